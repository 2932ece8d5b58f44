/* Shadow-mapped local lights drawn per pixel (render/pixel_lights.h). The shading follows
 * light/lights.c to the letter (inverse square, the spot's smoothstep, the sphere's exact
 * horizon-clipped cap), and glossy materials follow brdf/brdf.c's prt_brdf_eval_glossy in the
 * frame of prt_brdf_frame, so a pixel at a vertex matches what prt_relit_shade computes there
 * with shadow rays, up to the shadow map's resolution at shadow edges. */
#include "render/draw.h"
#include "prt/brdf.h"

#include <string.h>

#define CUBE_RES 1024
#define PLANE_RES 4096
#define BRDF_TEXELS 12   /* RGBA texels per BRDF in the table the glossy shading reads */

static const char *VS_DEPTH =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "uniform mat4 vp;\n"
    "out vec3 w;\n"
    "void main() { w = pos; gl_Position = vp * vec4(pos, 1.0); }\n";
/* Distance from the light (cube maps) or along the light's travel (directional). Faces turned
 * towards the light are stored pushed back by two texels plus their slope over the filter's
 * reach (slope-scaled, from the face's own derivatives): a lit surface then never shadows itself
 * (no acne), while faces turned away - a room's ceiling seen from the sun outside - are stored
 * where they are, so a wall right under them needs no depth bias and no light leaks in along the
 * seam. Every face still casts: a one-sided shelf shadows what lies below it. */
static const char *FS_CUBE =
    "#version 330 core\n"
    "in vec3 w; uniform vec3 light; uniform float texel; out vec4 dist;\n"
    "void main() {\n"
    "  float d = length(w - light);\n"
    "  vec3 ng = normalize(cross(dFdx(w), dFdy(w)));\n"
    "  float c = abs(dot(ng, (w - light) / d)), t = sqrt(max(0.0, 1.0 - c * c)) / max(c, 0.1);\n"
    "  dist = vec4(d + (gl_FrontFacing ? (2.0 + 8.0 * t) * d * texel : 0.0));\n"
    "}\n";
static const char *FS_PLANE =
    "#version 330 core\n"
    "in vec3 w; uniform vec3 dir; uniform float texel; out vec4 dist;\n"
    "void main() {\n"
    "  vec3 ng = normalize(cross(dFdx(w), dFdy(w)));\n"
    "  float c = abs(dot(ng, dir)), t = sqrt(max(0.0, 1.0 - c * c)) / max(c, 0.1);\n"
    "  dist = vec4(dot(w, -dir) + (gl_FrontFacing ? (2.0 + 8.0 * t) * texel : 0.0));\n"
    "}\n";

static const char *VS_ADD =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "layout(location = 2) in vec3 normal;\n"
    "layout(location = 4) in vec3 albedo;\n"
    "layout(location = 5) in float visibility;\n"
    "layout(location = 6) in uint material;\n"
    "uniform mat4 mvp;\n"
    "// centroid: with multisampling an edge pixel's centre may lie off the triangle, and a point\n"
    "// extrapolated past a room's seam would be lit from outside.\n"
    "centroid out vec3 f_pos; centroid out vec3 f_nrm; centroid out vec3 f_alb; centroid out float f_vis; flat out uint f_mat;\n"
    "void main() {\n"
    "  f_pos = pos; f_nrm = normal; f_alb = albedo; f_vis = visibility; f_mat = material;\n"
    "  gl_Position = mvp * vec4(pos, 1.0);\n"
    "}\n";
static const char *FS_ADD =
    "#version 330 core\n"
    "centroid in vec3 f_pos; centroid in vec3 f_nrm; centroid in vec3 f_alb; centroid in float f_vis; flat in uint f_mat;\n"
    "uniform int gate;          // 1: f_vis (the vertices' shadow rays) is meaningful\n"
    "uniform int type;          // 1 point, 2 spot, 3 directional, 4 sphere (prt_light_type)\n"
    "uniform vec3 lpos, ldir, colour; uniform vec2 cosang; uniform float radius;\n"
    "uniform samplerCube cube; uniform sampler2D plane; uniform mat4 light_vp;\n"
    "uniform float texel;       // shadow-map texel: radians (cube) or world units (plane)\n"
    "uniform float bias;        // world units, on top of the texel-sized part\n"
    "uniform int brdf_count;    // materials 1..brdf_count have a glossy part in the table\n"
    "uniform samplerBuffer brdfs; uniform vec3 eye;\n"
    "out vec4 color;\n"
    "const float PI = 3.14159265358979;\n"
    "// The glossy part of BRDF `id` (brdf/brdf.c, prt_brdf_eval_glossy) for world directions wi\n"
    "// (to the light) and wo (to the eye), in the frame of prt_brdf_frame about n.\n"
    "vec3 glossy(int id, vec3 n, vec3 wi_w, vec3 wo_w) {\n"
    "  float ny1 = n.y + 1.0;\n"
    "  vec3 s = vec3(ny1 * ny1 + n.z * n.z - n.x * n.x, -2.0 * ny1 * n.x, -2.0 * n.x * n.z);\n"
    "  s = length(s) < 1e-6 ? vec3(1.0, 0.0, 0.0) : normalize(s);\n"
    "  vec3 t = normalize(cross(n, s));\n"
    "  vec3 wi = vec3(dot(wi_w, s), dot(wi_w, t), dot(wi_w, n)), wo = vec3(dot(wo_w, s), dot(wo_w, t), dot(wo_w, n));\n"
    "  if (wi.z <= 0.0 || wo.z <= 0.0) return vec3(0.0);\n"
    "  int b = (id - 1) * 12;\n"
    "  vec4 head = texelFetch(brdfs, b);   // model, exponent, exponent_v, lobes\n"
    "  vec3 ks = texelFetch(brdfs, b + 1).rgb;\n"
    "  int model = int(head.x + 0.5);\n"
    "  if (model == 1) {\n"
    "    float r = -wi.x * wo.x - wi.y * wo.y + wi.z * wo.z;\n"
    "    return r > 0.0 ? ks * ((head.y + 2.0) / (2.0 * PI) * pow(r, head.y)) : vec3(0.0);\n"
    "  }\n"
    "  if (model == 2) {\n"
    "    vec3 h = wi + wo;\n"
    "    return ks * ((head.y + 8.0) / (8.0 * PI) * pow(h.z / length(h), head.y));\n"
    "  }\n"
    "  if (model == 3) {\n"
    "    vec3 h = normalize(wi + wo);\n"
    "    float hk = dot(h, wi), sin2 = 1.0 - h.z * h.z;\n"
    "    float e = sin2 > 1e-12 ? (head.y * h.x * h.x + head.z * h.y * h.y) / sin2 : 0.0;\n"
    "    float spec = sqrt((head.y + 1.0) * (head.z + 1.0)) / (8.0 * PI) * pow(h.z, e) / (hk * max(wi.z, wo.z));\n"
    "    float di = 1.0 - pow(1.0 - wi.z / 2.0, 5.0), dd = 1.0 - pow(1.0 - wo.z / 2.0, 5.0);\n"
    "    vec3 kd = texelFetch(brdfs, b + 2).rgb;\n"
    "    vec3 fresnel = ks + (vec3(1.0) - ks) * pow(1.0 - hk, 5.0);\n"
    "    return spec * fresnel + 28.0 * kd / (23.0 * PI) * (vec3(1.0) - ks) * di * dd;\n"
    "  }\n"
    "  vec3 sum = vec3(0.0);\n"
    "  for (int k = 0; k < int(head.w + 0.5); ++k) {\n"
    "    vec3 cxy = texelFetch(brdfs, b + 3 + 3 * k).rgb, cz = texelFetch(brdfs, b + 4 + 3 * k).rgb, e = texelFetch(brdfs, b + 5 + 3 * k).rgb;\n"
    "    vec3 base = cxy * (wi.x * wo.x + wi.y * wo.y) + cz * (wi.z * wo.z);\n"
    "    sum += mix(vec3(0.0), pow(max(base, vec3(1e-30)), e), greaterThan(base, vec3(0.0)));\n"
    "  }\n"
    "  return sum;\n"
    "}\n"
    "float cap(float cos_t, float sin2_s) {\n"
    "  if (sin2_s >= 1.0) return PI;\n"
    "  if (cos_t * cos_t >= sin2_s) return cos_t > 0.0 ? PI * sin2_s * cos_t : 0.0;\n"
    "  float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));\n"
    "  float x = sqrt(1.0 / sin2_s - 1.0);\n"
    "  float y = clamp(-x * cos_t / sin_t, -1.0, 1.0);\n"
    "  float s = sin_t * sqrt(max(0.0, 1.0 - y * y));\n"
    "  return max(0.0, (cos_t * acos(y) - x * s) * sin2_s + atan(s, x));\n"
    "}\n"
    "// Fraction of a kernel x kernel grid of cube-map samples around the direction to p that see\n"
    "// the light: samples step `step` world units across, at p's distance.\n"
    "float cube_lit(vec3 d, float dist, float step, int n) {\n"
    "  vec3 w = normalize(d);\n"
    "  vec3 t = normalize(abs(w.x) < 0.6 ? cross(w, vec3(1.0, 0.0, 0.0)) : cross(w, vec3(0.0, 1.0, 0.0)));\n"
    "  vec3 b = cross(w, t);\n"
    "  float lit = 0.0, h = 0.5 * float(n - 1), eps = 0.25 * dist * texel + bias;\n"
    "  for (int i = 0; i < n; ++i) for (int j = 0; j < n; ++j) {\n"
    "    vec3 q = d + ((float(i) - h) * t + (float(j) - h) * b) * step;\n"
    "    lit += dist - eps <= texture(cube, q).r ? 1.0 : 0.0;\n"
    "  }\n"
    "  return lit / float(n * n);\n"
    "}\n"
    "void main() {\n"
    "  // A triangle none of whose vertices sees the light stays dark: shadow-map texels cannot\n"
    "  // leak light in along the seams of closed rooms. A sphere light's vertex visibility is a\n"
    "  // fraction of 16 rays, which misses a penumbra's faint tail: there the gate fades the light\n"
    "  // out across the triangles instead of cutting it off at their edges (a staircase).\n"
    "  if (gate != 0 && f_vis <= 0.0 && type != 4) discard;\n"
    "  vec3 n = normalize(f_nrm), E = vec3(0.0), wi = ldir;\n"
    "  float lit = 1.0;\n"
    "  if (type == 3) {\n"
    "    float c = dot(n, ldir);\n"
    "    if (c <= 0.0) discard;\n"
    "    E = colour * c;\n"
    "    // The map is read a few texels off the surface along its normal (so that taps near a seam\n"
    "    // stay on the occluder's side), but compared with the surface point's own depth: moving\n"
    "    // towards the light would let an occluder right at a seam (a ceiling over a wall) through.\n"
    "    vec4 q = light_vp * vec4(f_pos + n * 4.0 * texel, 1.0);\n"
    "    vec2 uv = q.xy * 0.5 + 0.5;\n"
    "    float depth = dot(f_pos, -ldir), sum = 0.0;\n"
    "    vec2 px = vec2(1.0) / vec2(textureSize(plane, 0));\n"
    "    // 3 x 3 taps a texel apart: smooth edges; the normal offset keeps them on an occluder's side\n"
    "    // of a seam.\n"
    "    for (int i = -1; i <= 1; ++i) for (int j = -1; j <= 1; ++j)\n"
    "      sum += depth - (0.25 * texel + bias) <= texture(plane, uv + vec2(i, j) * px).r ? 1.0 : 0.0;\n"
    "    lit = sum / 9.0;\n"
    "  } else {\n"
    "    vec3 d0 = lpos - f_pos;\n"
    "    float r2 = dot(d0, d0), r = sqrt(r2);\n"
    "    if (r <= 0.0) discard;\n"
    "    wi = d0 / r;\n"
    "    float c = dot(n, wi);\n"
    "    if (type == 4) {\n"
    "      E = colour * cap(c, r > radius ? radius * radius / r2 : 1.0);\n"
    "    } else {\n"
    "      if (c <= 0.0) discard;\n"
    "      float s = 1.0;\n"
    "      if (type == 2) { float k = dot(ldir, -wi); s = k >= cosang.y ? 1.0 : k <= cosang.x ? 0.0 : smoothstep(0.0, 1.0, (k - cosang.x) / (cosang.y - cosang.x)); }\n"
    "      E = colour * c / r2 * s;\n"
    "    }\n"
    "    if (E.r + E.g + E.b <= 0.0) discard;\n"
    "    // Looked up off the surface along its normal, compared at the surface point (as above).\n"
    "    vec3 d = f_pos + n * 4.0 * r * texel - lpos;\n"
    "    float dist = r;\n"
    "    float step = dist * texel;\n"
    "    if (type == 4 && radius > 0.0) {\n"
    "      // Penumbra from the average blocker distance (percentage-closer soft shadows).\n"
    "      vec3 w = normalize(d);\n"
    "      vec3 t = normalize(abs(w.x) < 0.6 ? cross(w, vec3(1.0, 0.0, 0.0)) : cross(w, vec3(0.0, 1.0, 0.0)));\n"
    "      vec3 b = cross(w, t);\n"
    "      float blockers = 0.0, count = 0.0, eps = 0.25 * dist * texel + bias;\n"
    "      for (int i = -2; i <= 2; ++i) for (int j = -2; j <= 2; ++j) {\n"
    "        float s = texture(cube, d + (float(i) * t + float(j) * b) * radius * 0.5).r;\n"
    "        if (s < dist - eps) { blockers += s; count += 1.0; }\n"
    "      }\n"
    "      if (count > 0.0) {\n"
    "        float db = blockers / count;\n"
    "        step = max(step, radius * (dist - db) / max(db, 1e-6) / 3.0);\n"
    "      }\n"
    "      lit = cube_lit(d, dist, step, 7);\n"
    "    } else {\n"
    "      lit = cube_lit(d, dist, step, 3);\n"
    "    }\n"
    "  }\n"
    "  if (gate != 0 && type == 4) lit *= clamp(f_vis * 8.0, 0.0, 1.0);\n"
    "  vec3 f = f_alb / PI;\n"
    "  int id = int(f_mat);\n"
    "  if (id > 0 && id <= brdf_count) f += glossy(id, n, wi, normalize(eye - f_pos));\n"
    "  color = vec4(f * E * lit, 1.0);\n"
    "}\n";

prt_status prt__pixel_lights_init(prt__pixel_lights *p)
{
    memset(p, 0, sizeof *p);
    p->program_cube = prt__gl_program(VS_DEPTH, NULL, FS_CUBE);
    p->program_plane = p->program_cube ? prt__gl_program(VS_DEPTH, NULL, FS_PLANE) : 0;
    p->program_add = p->program_plane ? prt__gl_program(VS_ADD, NULL, FS_ADD) : 0;
    if (!p->program_add) { prt__pixel_lights_free(p); return PRT_ERR_BACKEND; }
    p->uc_vp = glGetUniformLocation(p->program_cube, "vp");
    p->uc_light = glGetUniformLocation(p->program_cube, "light");
    p->uc_texel = glGetUniformLocation(p->program_cube, "texel");
    p->up_texel = glGetUniformLocation(p->program_plane, "texel");
    p->up_vp = glGetUniformLocation(p->program_plane, "vp");
    p->up_dir = glGetUniformLocation(p->program_plane, "dir");
    const GLuint a = p->program_add;
    p->ua_mvp = glGetUniformLocation(a, "mvp");
    p->ua_type = glGetUniformLocation(a, "type");
    p->ua_pos = glGetUniformLocation(a, "lpos");
    p->ua_dir = glGetUniformLocation(a, "ldir");
    p->ua_colour = glGetUniformLocation(a, "colour");
    p->ua_cos = glGetUniformLocation(a, "cosang");
    p->ua_radius = glGetUniformLocation(a, "radius");
    p->ua_cube = glGetUniformLocation(a, "cube");
    p->ua_plane = glGetUniformLocation(a, "plane");
    p->ua_light_vp = glGetUniformLocation(a, "light_vp");
    p->ua_texel = glGetUniformLocation(a, "texel");
    p->ua_bias = glGetUniformLocation(a, "bias");
    p->ua_gate = glGetUniformLocation(a, "gate");
    p->ua_brdf_count = glGetUniformLocation(a, "brdf_count");
    p->ua_brdfs = glGetUniformLocation(a, "brdfs");
    p->ua_eye = glGetUniformLocation(a, "eye");
    glGenFramebuffers(1, &p->fbo);
    glGenRenderbuffers(1, &p->depth_rb);
    glBindRenderbuffer(GL_RENDERBUFFER, p->depth_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, CUBE_RES, CUBE_RES);
    glGenRenderbuffers(1, &p->plane_depth_rb);
    glBindRenderbuffer(GL_RENDERBUFFER, p->plane_depth_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, PLANE_RES, PLANE_RES);
    glBindRenderbuffer(GL_RENDERBUFFER, 0);
    glGenBuffers(1, &p->vbo_albedo);
    glGenBuffers(1, &p->vbo_visibility);
    glGenBuffers(1, &p->vbo_material);
    glGenBuffers(1, &p->tbo_brdf);
    glGenTextures(1, &p->tex_brdf);
    return PRT_OK;
}

void prt__pixel_lights_free(prt__pixel_lights *p)
{
    if (p->program_cube) glDeleteProgram(p->program_cube);
    if (p->program_plane) glDeleteProgram(p->program_plane);
    if (p->program_add) glDeleteProgram(p->program_add);
    if (p->fbo) glDeleteFramebuffers(1, &p->fbo);
    if (p->depth_rb) glDeleteRenderbuffers(1, &p->depth_rb);
    if (p->plane_depth_rb) glDeleteRenderbuffers(1, &p->plane_depth_rb);
    if (p->vbo_albedo) glDeleteBuffers(1, &p->vbo_albedo);
    if (p->vbo_visibility) glDeleteBuffers(1, &p->vbo_visibility);
    if (p->vbo_material) glDeleteBuffers(1, &p->vbo_material);
    if (p->tbo_brdf) glDeleteBuffers(1, &p->tbo_brdf);
    if (p->tex_brdf) glDeleteTextures(1, &p->tex_brdf);
    for (int i = 0; i < PRT__PIXEL_LIGHTS; ++i) {
        if (p->cube[i]) glDeleteTextures(1, &p->cube[i]);
        if (p->plane[i]) glDeleteTextures(1, &p->plane[i]);
    }
    memset(p, 0, sizeof *p);
}

/* BRDF_TEXELS RGBA texels per BRDF: (model, exponent, exponent_v, lobes), specular, diffuse, then
 * each Lafortune lobe's cxy, cz and n. */
static void upload_brdfs(prt__pixel_lights *p, const prt_brdf *brdfs, int count)
{
    float *t = calloc((size_t)count * BRDF_TEXELS * 4, sizeof(float));
    if (!t) { p->brdf_count = 0; return; }
    for (int i = 0; i < count; ++i) {
        const prt_brdf *b = &brdfs[i];
        float *q = t + (size_t)i * BRDF_TEXELS * 4;
        q[0] = (float)b->model;
        q[1] = b->exponent;
        q[2] = b->exponent_v;
        q[3] = (float)(b->lobes < PRT_BRDF_MAX_LOBES ? b->lobes : PRT_BRDF_MAX_LOBES);
        for (int c = 0; c < 3; ++c) {
            q[4 + c] = b->specular[c];
            q[8 + c] = b->diffuse[c];
            for (int k = 0; k < PRT_BRDF_MAX_LOBES; ++k) {
                q[(3 + 3 * k) * 4 + c] = b->cxy[k][c];
                q[(4 + 3 * k) * 4 + c] = b->cz[k][c];
                q[(5 + 3 * k) * 4 + c] = b->n[k][c];
            }
        }
    }
    glBindBuffer(GL_TEXTURE_BUFFER, p->tbo_brdf);
    glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)((size_t)count * BRDF_TEXELS * 4 * sizeof(float)), t, GL_DYNAMIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, p->tex_brdf);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, p->tbo_brdf);
    glBindTexture(GL_TEXTURE_BUFFER, 0);
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
    free(t);
    p->brdf_count = count;
}

void prt__pixel_lights_set(prt__pixel_lights *p, GLuint vao, const prt_render_mesh *m)
{
    const bool ok = m->lights && m->light_count > 0 && m->albedo && m->normals;
    const prt_light *lights = ok ? m->lights : NULL;
    const float *positions = m->positions, *albedo = m->albedo, *visibility = m->light_visibility;
    const size_t nv = m->vertex_count;
    const int count = ok ? m->light_count : 0;
    const int n = lights && albedo && count > 0 ? (count < PRT__PIXEL_LIGHTS ? count : PRT__PIXEL_LIGHTS) : 0;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; n && v < nv; ++v)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fminf(lo[k], positions[v * 3 + k]);
            hi[k] = fmaxf(hi[k], positions[v * 3 + k]);
        }
    /* The same lights over the same bounds keep their shadow maps (a viewer relights often). */
    const bool same = n == p->count && (n == 0 || !memcmp(p->lights, lights, (size_t)n * sizeof *lights)) && !memcmp(lo, p->lo, sizeof lo) &&
                      !memcmp(hi, p->hi, sizeof hi);
    p->count = n;
    if (!n) return;
    memcpy(p->lights, lights, (size_t)n * sizeof *lights);
    memcpy(p->lo, lo, sizeof lo);
    memcpy(p->hi, hi, sizeof hi);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, p->vbo_albedo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(nv * 3 * sizeof(float)), albedo, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(4);
    glVertexAttribPointer(4, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    p->has_visibility = visibility != NULL;
    p->vertex_count = nv;
    if (visibility) {
        glBindBuffer(GL_ARRAY_BUFFER, p->vbo_visibility);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)n * nv * sizeof(float)), visibility, GL_DYNAMIC_DRAW);
        glEnableVertexAttribArray(5);
    } else {
        glDisableVertexAttribArray(5);
        glVertexAttrib1f(5, 1.0f);
    }
    const int brdf_count = m->light_material && m->light_brdfs ? m->light_brdf_count : 0;
    if (brdf_count > 0) {
        glBindBuffer(GL_ARRAY_BUFFER, p->vbo_material);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)nv, m->light_material, GL_DYNAMIC_DRAW);
        glEnableVertexAttribArray(6);
        glVertexAttribIPointer(6, 1, GL_UNSIGNED_BYTE, 0, NULL);
        upload_brdfs(p, m->light_brdfs, brdf_count);
    } else {
        glDisableVertexAttribArray(6);
        glVertexAttribI4ui(6, 0, 0, 0, 0);
        p->brdf_count = 0;
    }
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    glBindVertexArray(0);
    if (!same) p->dirty = true;
}

static void new_texture(GLuint *tex, GLenum target, int res)
{
    if (*tex) return;
    glGenTextures(1, tex);
    glBindTexture(target, *tex);
    if (target == GL_TEXTURE_CUBE_MAP)
        for (int f = 0; f < 6; ++f) glTexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + f, 0, GL_R32F, res, res, 0, GL_RED, GL_FLOAT, NULL);
    else
        glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, res, res, 0, GL_RED, GL_FLOAT, NULL);
    glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(target, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(target, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    if (target == GL_TEXTURE_CUBE_MAP) glTexParameteri(target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    glBindTexture(target, 0);
}

/* Column-major orthographic view-projection looking along -dir at the bounds. */
static void ortho_towards(const float dir[3], const float lo[3], const float hi[3], float out[16])
{
    float c[3], ext[3];
    for (int k = 0; k < 3; ++k) c[k] = 0.5f * (lo[k] + hi[k]);
    prt__v3_sub(hi, lo, ext);
    const float R = fmaxf(0.5f * prt__v3_len(ext), 1e-6f);
    float f[3] = {-dir[0], -dir[1], -dir[2]}, up[3] = {0, 1, 0}, s[3], u[3];
    if (fabsf(f[1]) > 0.99f) { up[1] = 0; up[2] = 1; }
    prt__v3_cross(f, up, s);
    prt__v3_normalize(s);
    prt__v3_cross(s, f, u);
    const float eye[3] = {c[0] - f[0] * 2 * R, c[1] - f[1] * 2 * R, c[2] - f[2] * 2 * R};
    /* x = s.(p - eye) / R, y = u.(p - eye) / R, z from depth f.(p - eye) in [R, 3R] to [-1, 1]. */
    const float n = R * 0.5f, fa = 3.5f * R;
    const float zs = 2.0f / (fa - n), zo = -(fa + n) / (fa - n);
    const float ez[3] = {prt__v3_dot(s, eye), prt__v3_dot(u, eye), prt__v3_dot(f, eye)};
    float m[16] = {s[0] / R, u[0] / R, f[0] * zs, 0, s[1] / R, u[1] / R, f[1] * zs, 0, s[2] / R, u[2] / R, f[2] * zs, 0,
                   -ez[0] / R, -ez[1] / R, -ez[2] * zs + zo, 1};
    memcpy(out, m, sizeof m);
}

void prt__pixel_lights_shadows(prt__pixel_lights *p, GLuint vao, size_t index_count)
{
    if (!p->count || !p->dirty) return;
    GLint prev_fbo = 0, prev_vp[4];
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &prev_fbo);
    glGetIntegerv(GL_VIEWPORT, prev_vp);
    glBindFramebuffer(GL_FRAMEBUFFER, p->fbo);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glBindVertexArray(vao);
    float ext[3];
    prt__v3_sub(p->hi, p->lo, ext);
    const float diag = fmaxf(prt__v3_len(ext), 1e-6f);
    /* +x, -x, +y, -y, +z, -z with GL's cube-map orientation. */
    static const float look[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    static const float ups[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
    for (int i = 0; i < p->count; ++i) {
        const prt_light *l = &p->lights[i];
        if (l->type == PRT_LIGHT_DIRECTIONAL) {
            new_texture(&p->plane[i], GL_TEXTURE_2D, PLANE_RES);
            ortho_towards(l->direction, p->lo, p->hi, p->light_vp[i]);
            glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, p->plane_depth_rb);
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, p->plane[i], 0);
            glViewport(0, 0, PLANE_RES, PLANE_RES);
            glClearColor(1e30f, 1e30f, 1e30f, 1e30f);
            glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
            glUseProgram(p->program_plane);
            glUniformMatrix4fv(p->up_vp, 1, GL_FALSE, p->light_vp[i]);
            glUniform3fv(p->up_dir, 1, l->direction);
            glUniform1f(p->up_texel, diag / PLANE_RES);
            glDrawElements(GL_TRIANGLES, (GLsizei)index_count, GL_UNSIGNED_INT, NULL);
            continue;
        }
        new_texture(&p->cube[i], GL_TEXTURE_CUBE_MAP, CUBE_RES);
        float far = 0;
        for (int corner = 0; corner < 8; ++corner) {
            float q[3] = {corner & 1 ? p->hi[0] : p->lo[0], corner & 2 ? p->hi[1] : p->lo[1], corner & 4 ? p->hi[2] : p->lo[2]}, d[3];
            prt__v3_sub(q, l->position, d);
            far = fmaxf(far, prt__v3_len(d));
        }
        float nf[2] = {diag * 1e-4f, far * 1.01f + diag * 1e-3f};
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, p->depth_rb);
        glViewport(0, 0, CUBE_RES, CUBE_RES);
        glUseProgram(p->program_cube);
        glUniform3fv(p->uc_light, 1, l->position);
        glUniform1f(p->uc_texel, 2.0f / CUBE_RES);
        for (int f = 0; f < 6; ++f) {
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_CUBE_MAP_POSITIVE_X + f, p->cube[i], 0);
            glClearColor(1e30f, 1e30f, 1e30f, 1e30f);
            glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
            prt_camera cam = {{l->position[0], l->position[1], l->position[2]},
                              {l->position[0] + look[f][0], l->position[1] + look[f][1], l->position[2] + look[f][2]},
                              {ups[f][0], ups[f][1], ups[f][2]}, 90.0f};
            float vp[16];
            prt__camera_matrix(&cam, 1.0f, nf, vp);
            glUniformMatrix4fv(p->uc_vp, 1, GL_FALSE, vp);
            glDrawElements(GL_TRIANGLES, (GLsizei)index_count, GL_UNSIGNED_INT, NULL);
        }
    }
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, (GLuint)prev_fbo);
    glViewport(prev_vp[0], prev_vp[1], prev_vp[2], prev_vp[3]);
    p->dirty = false;
}

void prt__pixel_lights_draw(const prt__pixel_lights *p, GLuint vao, size_t index_count, const float mvp[16], const float eye[3])
{
    if (!p->count) return;
    float ext[3];
    prt__v3_sub(p->hi, p->lo, ext);
    const float diag = fmaxf(prt__v3_len(ext), 1e-6f);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    /* The surfaces were drawn by other programs (glossy ones through a geometry shader), whose
     * depths may differ from this pass's in the last bit: without a nudge towards the eye, the
     * light would miss pixels at random (dark speckles over glossy scenes). */
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(-1.0f, -4.0f);
    glEnable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
    glUseProgram(p->program_add);
    glUniformMatrix4fv(p->ua_mvp, 1, GL_FALSE, mvp);
    glUniform1i(p->ua_cube, 0);
    glUniform1i(p->ua_plane, 1);
    glUniform1f(p->ua_bias, diag * 2e-5f);
    glUniform1i(p->ua_brdf_count, p->brdf_count);
    glUniform3fv(p->ua_eye, 1, eye);
    glUniform1i(p->ua_brdfs, 2);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_BUFFER, p->brdf_count ? p->tex_brdf : 0);
    glBindVertexArray(vao);
    /* Each sample takes a light once: coincident duplicate faces pass the depth test together. */
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_EQUAL, 0, 0xFF);
    glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
    for (int i = 0; i < p->count; ++i) {
        glClear(GL_STENCIL_BUFFER_BIT);
        const prt_light *l = &p->lights[i];
        const float *colour = l->type == PRT_LIGHT_DIRECTIONAL ? l->irradiance : l->type == PRT_LIGHT_SPHERE ? l->radiance : l->intensity;
        glUniform1i(p->ua_type, (int)l->type);
        glUniform1i(p->ua_gate, p->has_visibility);
        if (p->has_visibility) {   /* this light's row of the visibility */
            glBindBuffer(GL_ARRAY_BUFFER, p->vbo_visibility);
            glVertexAttribPointer(5, 1, GL_FLOAT, GL_FALSE, 0, (const void *)((size_t)i * p->vertex_count * sizeof(float)));
            glBindBuffer(GL_ARRAY_BUFFER, 0);
        }
        glUniform3fv(p->ua_pos, 1, l->position);
        glUniform3fv(p->ua_dir, 1, l->direction);
        glUniform3fv(p->ua_colour, 1, colour);
        glUniform2f(p->ua_cos, cosf(l->angle_deg * (float)PRT_PI / 180.0f), cosf(l->falloff_deg * (float)PRT_PI / 180.0f));
        glUniform1f(p->ua_radius, l->type == PRT_LIGHT_SPHERE ? l->radius : 0.0f);
        if (l->type == PRT_LIGHT_DIRECTIONAL) {
            glUniformMatrix4fv(p->ua_light_vp, 1, GL_FALSE, p->light_vp[i]);
            glUniform1f(p->ua_texel, diag / PLANE_RES);
            glActiveTexture(GL_TEXTURE1);
            glBindTexture(GL_TEXTURE_2D, p->plane[i]);
        } else {
            glUniform1f(p->ua_texel, 2.0f / CUBE_RES);
            glActiveTexture(GL_TEXTURE0);
            glBindTexture(GL_TEXTURE_CUBE_MAP, p->cube[i]);
        }
        glDrawElements(GL_TRIANGLES, (GLsizei)index_count, GL_UNSIGNED_INT, NULL);
    }
    glBindVertexArray(0);
    glDisable(GL_STENCIL_TEST);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glActiveTexture(GL_TEXTURE0);
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
    glDepthFunc(GL_LESS);
}
