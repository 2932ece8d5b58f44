#include "render/draw.h"

#include <stdio.h>
#include <string.h>

static const char *VS =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "layout(location = 1) in vec3 radiance;\n"
    "uniform mat4 mvp;\n"
    "out vec3 v_radiance;\n"
    "void main() { v_radiance = radiance; gl_Position = mvp * vec4(pos, 1.0); }\n";
static const char *FS =
    "#version 330 core\n"
    "in vec3 v_radiance;\n"
    "out vec4 color;\n"
    "void main() { color = vec4(v_radiance, 1.0); }\n";

/* Per-texel: radiance comes from a map over the UV layout. */
static const char *VS_T =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "layout(location = 3) in vec2 uv;\n"
    "uniform mat4 mvp;\n"
    "out vec2 v_uv;\n"
    "void main() { v_uv = uv; gl_Position = mvp * vec4(pos, 1.0); }\n";
static const char *FS_T =
    "#version 330 core\n"
    "in vec2 v_uv;\n"
    "uniform sampler2D map;\n"
    "out vec4 color;\n"
    "void main() { color = vec4(texture(map, v_uv).rgb, 1.0); }\n";

/* Glossy: the geometry shader hands every fragment its triangle's vertex ids and barycentrics,
 * so the fragment shader interpolates the three vertices' exit SH (too many to pass as
 * varyings) and evaluates them at its own view direction by the recurrence of core/sh.c. */
static const char *VS_G =
    "#version 330 core\n"
    "layout(location = 0) in vec3 pos;\n"
    "layout(location = 1) in vec3 radiance;\n"
    "layout(location = 2) in vec3 normal;\n"
    "uniform mat4 mvp;\n"
    "out vec3 g_pos; out vec3 g_nrm; out vec3 g_rad; flat out int g_id;\n"
    "void main() { g_pos = pos; g_nrm = normal; g_rad = radiance; g_id = gl_VertexID; gl_Position = mvp * vec4(pos, 1.0); }\n";
static const char *GS_G =
    "#version 330 core\n"
    "layout(triangles) in;\n"
    "layout(triangle_strip, max_vertices = 3) out;\n"
    "in vec3 g_pos[]; in vec3 g_nrm[]; in vec3 g_rad[]; flat in int g_id[];\n"
    "out vec3 f_pos; out vec3 f_nrm; out vec3 f_rad; out vec3 f_bary; flat out ivec3 f_ids;\n"
    "void main() {\n"
    "  for (int k = 0; k < 3; ++k) {\n"
    "    f_pos = g_pos[k]; f_nrm = g_nrm[k]; f_rad = g_rad[k];\n"
    "    f_bary = vec3(k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0);\n"
    "    f_ids = ivec3(g_id[0], g_id[1], g_id[2]);\n"
    "    gl_Position = gl_in[k].gl_Position; EmitVertex();\n"
    "  }\n"
    "  EndPrimitive();\n"
    "}\n";
static const char *FS_G =
    "#version 330 core\n"
    "in vec3 f_pos; in vec3 f_nrm; in vec3 f_rad; in vec3 f_bary; flat in ivec3 f_ids;\n"
    "uniform samplerBuffer exit_sh; uniform int order; uniform int mirror; uniform vec3 eye;\n"
    "uniform float knorm[100];   // [l * 10 + m], PRT_SH_MAX_ORDER = 10\n"
    "out vec4 color;\n"
    "vec3 coeff(int i) {\n"
    "  int n2 = order * order;\n"
    "  return f_bary.x * texelFetch(exit_sh, f_ids.x * n2 + i).rgb + f_bary.y * texelFetch(exit_sh, f_ids.y * n2 + i).rgb\n"
    "       + f_bary.z * texelFetch(exit_sh, f_ids.z * n2 + i).rgb;\n"
    "}\n"
    "void main() {\n"
    "  vec3 n = normalize(f_nrm), v = normalize(eye - f_pos);\n"
    "  vec3 d = mirror != 0 ? normalize(2.0 * dot(n, v) * n - v) : v;\n"
    "  float re = 1.0, im = 0.0, qmm = 1.0;\n"
    "  vec3 acc = vec3(0.0);\n"
    "  for (int m = 0; m < order; ++m) {\n"
    "    if (m > 0) { float r2 = re * d.x - im * d.y; im = re * d.y + im * d.x; re = r2; qmm *= float(2 * m - 1); }\n"
    "    float qp = 0.0, q = qmm;\n"
    "    for (int l = m; l < order; ++l) {\n"
    "      if (l == m + 1) { qp = q; q = d.z * float(2 * m + 1) * qp; }\n"
    "      else if (l > m + 1) { float qn = (float(2 * l - 1) * d.z * q - float(l + m - 1) * qp) / float(l - m); qp = q; q = qn; }\n"
    "      float k = knorm[l * 10 + m] * q;\n"
    "      int c = l * (l + 1);\n"
    "      if (m == 0) acc += k * coeff(c);\n"
    "      else acc += k * re * coeff(c + m) + k * im * coeff(c - m);\n"
    "    }\n"
    "  }\n"
    "  // Run-time lobes leave out the BRDF's cosine: near the mirror direction it is n.v.\n"
    "  float cosine = mirror != 0 ? max(dot(n, v), 0.0) : 1.0;\n"
    "  color = vec4(f_rad + cosine * max(acc, vec3(0.0)), 1.0);\n"
    "}\n";

/* Separable view factor (Wang, Tran & Luebke 2005): the same geometry shader; each corner's
 * K-vector (texel v * K + k: rgb = g_k, a = its view-map set) meets the view maps at this pixel's
 * direction in the frame of eq. 10 built on the interpolated normal, as the CPU does per vertex
 * (prt_relit_shade). */
static const char *FS_S =
    "#version 330 core\n"
    "in vec3 f_pos; in vec3 f_nrm; in vec3 f_rad; in vec3 f_bary; flat in ivec3 f_ids;\n"
    "uniform samplerBuffer kvec, kset; uniform sampler2DArray maps; uniform int terms; uniform int polar; uniform vec3 eye;\n"
    "out vec4 color;\n"
    "void main() {\n"
    "  vec3 n = normalize(f_nrm);\n"
    "  float ny1 = n.y + 1.0;\n"
    "  vec3 s = vec3(ny1 * ny1 + n.z * n.z - n.x * n.x, -2.0 * ny1 * n.x, -2.0 * n.x * n.z);\n"
    "  s = length(s) < 1e-6 ? vec3(1.0, 0.0, 0.0) : normalize(s);\n"
    "  vec3 t = normalize(cross(n, s));\n"
    "  vec3 wo = normalize(eye - f_pos);\n"
    "  vec3 l = vec3(dot(wo, s), dot(wo, t), dot(wo, n));\n"
    "  if (l.z < 0.02) { float r = length(l.xy); l.xy *= r > 0.0 ? sqrt(1.0 - 0.0004) / r : 0.0; l.z = 0.02; }\n"
    "  vec2 uv = polar != 0 ? vec2(fract(atan(l.y, l.x) / 6.28318530718), sqrt(max(0.0, 1.0 - l.z))) : 0.5 * (l.xy + 1.0);\n"
    "  vec3 acc = vec3(0.0);\n"
    "  for (int c = 0; c < 3; ++c) {\n"
    "    int id = f_ids[c];\n"
    "    int set = int(texelFetch(kset, id).r + 0.5);\n"
    "    if (set == 0) continue;\n"
    "    vec3 sum = vec3(0.0);\n"
    "    for (int k = 0; k < terms; ++k)\n"
    "      sum += texture(maps, vec3(uv, float((set - 1) * terms + k))).rgb * texelFetch(kvec, id * terms + k).rgb;\n"
    "    acc += f_bary[c] * sum;\n"
    "  }\n"
    "  color = vec4(max(f_rad + acc, vec3(0.0)), 1.0);\n"
    "}\n";

static GLuint compile(GLenum type, const char *src, char *log, size_t logsize)
{
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    GLint ok;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        glGetShaderInfoLog(s, (GLsizei)logsize, NULL, log);
        glDeleteShader(s);
        return 0;
    }
    return s;
}

/* Compiles and links vs (+ gs) + fs; 0 and a message on failure. */
GLuint prt__gl_program(const char *vs_src, const char *gs_src, const char *fs_src)
{
    char log[1024] = "";
    GLuint vs = compile(GL_VERTEX_SHADER, vs_src, log, sizeof log);
    GLuint gs = vs && gs_src ? compile(GL_GEOMETRY_SHADER, gs_src, log, sizeof log) : 0;
    GLuint fs = vs && (gs || !gs_src) ? compile(GL_FRAGMENT_SHADER, fs_src, log, sizeof log) : 0;
    if (!vs || (gs_src && !gs) || !fs) {
        if (vs) glDeleteShader(vs);
        if (gs) glDeleteShader(gs);
        prt__fail(NULL, PRT_ERR_BACKEND, "shader compilation failed: %s", log);
        return 0;
    }
    GLuint p = glCreateProgram();
    glAttachShader(p, vs);
    if (gs) glAttachShader(p, gs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    if (gs) glDeleteShader(gs);
    glDeleteShader(fs);
    GLint ok;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        glDeleteProgram(p);
        prt__fail(NULL, PRT_ERR_BACKEND, "shader link failed: %s", log);
        return 0;
    }
    return p;
}

prt_status prt__draw_init(prt__draw *d)
{
    memset(d, 0, sizeof *d);
    if (!(d->program = prt__gl_program(VS, NULL, FS))) return PRT_ERR_BACKEND;
    if (!(d->program_g = prt__gl_program(VS_G, GS_G, FS_G)) || !(d->program_t = prt__gl_program(VS_T, NULL, FS_T)) ||
        !(d->program_s = prt__gl_program(VS_G, GS_G, FS_S))) {
        glDeleteProgram(d->program);
        if (d->program_g) glDeleteProgram(d->program_g);
        if (d->program_t) glDeleteProgram(d->program_t);
        d->program = d->program_g = d->program_t = 0;
        return PRT_ERR_BACKEND;
    }
    if (prt__pixel_lights_init(&d->lights)) {
        glDeleteProgram(d->program);
        glDeleteProgram(d->program_g);
        glDeleteProgram(d->program_t);
        glDeleteProgram(d->program_s);
        d->program = d->program_g = d->program_t = d->program_s = 0;
        return PRT_ERR_BACKEND;
    }
    d->us_mvp = glGetUniformLocation(d->program_s, "mvp");
    d->us_eye = glGetUniformLocation(d->program_s, "eye");
    d->us_terms = glGetUniformLocation(d->program_s, "terms");
    d->us_polar = glGetUniformLocation(d->program_s, "polar");
    d->us_kvec = glGetUniformLocation(d->program_s, "kvec");
    d->us_maps = glGetUniformLocation(d->program_s, "maps");
    d->us_kset = glGetUniformLocation(d->program_s, "kset");
    glGenBuffers(1, &d->tbo_k);
    glGenTextures(1, &d->tbo_k_tex);
    glGenTextures(1, &d->maps_tex);
    d->ut_mvp = glGetUniformLocation(d->program_t, "mvp");
    d->ut_map = glGetUniformLocation(d->program_t, "map");
    glGenBuffers(1, &d->vbo_uv);
    glGenTextures(1, &d->tex);
    d->u_mvp = glGetUniformLocation(d->program, "mvp");
    d->ug_mvp = glGetUniformLocation(d->program_g, "mvp");
    d->ug_order = glGetUniformLocation(d->program_g, "order");
    d->ug_mirror = glGetUniformLocation(d->program_g, "mirror");
    d->ug_eye = glGetUniformLocation(d->program_g, "eye");
    d->ug_knorm = glGetUniformLocation(d->program_g, "knorm");
    d->ug_exit = glGetUniformLocation(d->program_g, "exit_sh");
    glGenBuffers(1, &d->vbo_nrm);
    glGenBuffers(1, &d->tbo);
    glGenTextures(1, &d->tbo_tex);
    glGenVertexArrays(1, &d->vao);
    glGenBuffers(1, &d->vbo_pos);
    glGenBuffers(1, &d->vbo_rad);
    glGenBuffers(1, &d->ibo);
    if (prt__volume_gl_init(&d->volumes)) memset(&d->volumes, 0, sizeof d->volumes);   /* media stay undrawn, the rest works */
    return PRT_OK;
}

void prt__draw_free(prt__draw *d)
{
    prt__volume_gl_free(&d->volumes);
    prt__pixel_lights_free(&d->lights);
    if (d->program) glDeleteProgram(d->program);
    if (d->program_g) glDeleteProgram(d->program_g);
    if (d->program_t) glDeleteProgram(d->program_t);
    if (d->program_s) glDeleteProgram(d->program_s);
    if (d->tbo_k) glDeleteBuffers(1, &d->tbo_k);
    if (d->tbo_k_tex) glDeleteTextures(1, &d->tbo_k_tex);
    if (d->tbo_set) glDeleteBuffers(1, &d->tbo_set);
    if (d->tbo_set_tex) glDeleteTextures(1, &d->tbo_set_tex);
    if (d->maps_tex) glDeleteTextures(1, &d->maps_tex);
    free(d->kpack);
    free(d->view_set);
    if (d->vbo_uv) glDeleteBuffers(1, &d->vbo_uv);
    if (d->tex) glDeleteTextures(1, &d->tex);
    if (d->tex_first) glDeleteTextures(1, &d->tex_first);
    prt__light_map_gl_free(&d->light_map);
    if (d->vbo_nrm) { GLuint b[2] = {d->vbo_nrm, d->tbo}; glDeleteBuffers(2, b); }
    if (d->tbo_tex) glDeleteTextures(1, &d->tbo_tex);
    free(d->pack);
    if (d->vao) glDeleteVertexArrays(1, &d->vao);
    GLuint bufs[3] = {d->vbo_pos, d->vbo_rad, d->ibo};
    if (d->vbo_pos) glDeleteBuffers(3, bufs);
    prt__sums_gl_free(&d->sums);
    if (d->vbo_rad2) glDeleteBuffers(1, &d->vbo_rad2);
    memset(d, 0, sizeof *d);
}

prt_status prt__draw_upload(prt__draw *d, const prt_render_mesh *m)
{
    glBindVertexArray(d->vao);
    glBindBuffer(GL_ARRAY_BUFFER, d->vbo_pos);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(m->vertex_count * 3 * sizeof(float)), m->positions, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindBuffer(GL_ARRAY_BUFFER, d->vbo_rad);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(m->vertex_count * 3 * sizeof(float)), m->radiance, GL_DYNAMIC_DRAW);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, d->ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(m->triangle_count * 3 * sizeof(uint32_t)), m->indices, GL_STATIC_DRAW);
    const bool exit_given = m->exit_sh || (m->gpu_sums && prt_render_sums_exit_product(m->gpu_sums));   /* or summed on the GPU */
    d->exit_order = exit_given && m->normals && m->exit_order >= 1 && m->exit_order <= PRT_SH_MAX_ORDER ? m->exit_order : 0;
    d->exit_mirror = m->exit_mirror;
    const bool kvec_given = m->kvec || (m->gpu_sums && prt_render_sums_kvec_product(m->gpu_sums));   /* or summed on the GPU */
    d->kvec_terms = kvec_given && m->normals && m->view_set && m->view_maps && m->kvec_terms >= 1 && m->view_map_sets >= 1 &&
                            m->view_map_resolution >= 1 ? m->kvec_terms : 0;
    if (m->normals) {   /* also for lights set later (prt_window_set_lights) */
        glBindBuffer(GL_ARRAY_BUFFER, d->vbo_nrm);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(m->vertex_count * 3 * sizeof(float)), m->normals, GL_STATIC_DRAW);
        glEnableVertexAttribArray(2);
        glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    } else {
        glDisableVertexAttribArray(2);
    }
    d->has_uv = m->uv != NULL;
    d->texel_width = d->texel_height = 0;
    if (d->has_uv) {
        glBindBuffer(GL_ARRAY_BUFFER, d->vbo_uv);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(m->vertex_count * 2 * sizeof(float)), m->uv, GL_STATIC_DRAW);
        glEnableVertexAttribArray(3);
        glVertexAttribPointer(3, 2, GL_FLOAT, GL_FALSE, 0, NULL);
    } else {
        glDisableVertexAttribArray(3);
    }
    glBindVertexArray(0);
    d->index_count = m->triangle_count * 3;
    prt__draw_set_lights(d, m);
    prt__volume_gl_upload(&d->volumes, m->volumes, m->volumes ? m->volume_count : 0);
    d->lights.dirty = true;   /* new geometry casts new shadows */
    if (d->exit_order && m->exit_sh) prt__draw_upload_exit(d, m->exit_sh, m->vertex_count);
    if (d->kvec_terms) {
        free(d->view_set);
        d->view_set = malloc(m->vertex_count);
        if (!d->view_set) { d->kvec_terms = 0; return PRT_OK; }
        memcpy(d->view_set, m->view_set, m->vertex_count);
        /* Each vertex's view-map set (0: none) beside its terms, which the GPU may write. */
        float *set = malloc(m->vertex_count * sizeof(float) + 1);
        if (!set) { d->kvec_terms = 0; return PRT_OK; }
        for (size_t v = 0; v < m->vertex_count; ++v) set[v] = (float)m->view_set[v];
        if (!d->tbo_set) glGenBuffers(1, &d->tbo_set);
        if (!d->tbo_set_tex) glGenTextures(1, &d->tbo_set_tex);
        glBindBuffer(GL_TEXTURE_BUFFER, d->tbo_set);
        glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)(m->vertex_count * sizeof(float)), set, GL_STATIC_DRAW);
        glBindTexture(GL_TEXTURE_BUFFER, d->tbo_set_tex);
        glTexBuffer(GL_TEXTURE_BUFFER, GL_R32F, d->tbo_set);
        glBindTexture(GL_TEXTURE_BUFFER, 0);
        glBindBuffer(GL_TEXTURE_BUFFER, 0);
        free(set);
        d->kpack_vertices = 0;   /* the packing must be rebuilt with the new sets */
        d->view_polar = m->view_map_polar;
        const int res = m->view_map_resolution, layers = m->view_map_sets * m->kvec_terms;
        /* [set][term][channel][res][res] -> one RGB layer per (set, term). */
        float *rgb = malloc((size_t)layers * res * res * 3 * sizeof(float));
        if (!rgb) { d->kvec_terms = 0; return PRT_OK; }
        for (int layer = 0; layer < layers; ++layer)
            for (int i = 0; i < res * res; ++i)
                for (int c = 0; c < 3; ++c)
                    rgb[((size_t)layer * res * res + i) * 3 + c] = m->view_maps[((size_t)layer * 3 + c) * res * res + i];
        glBindTexture(GL_TEXTURE_2D_ARRAY, d->maps_tex);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGB32F, res, res, layers, 0, GL_RGB, GL_FLOAT, rgb);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        /* As the CPU lookup: the polar angle wraps, everything else clamps at the edge texels. */
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, d->view_polar ? GL_REPEAT : GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
        free(rgb);
        prt__draw_upload_kvec(d, m->kvec, m->vertex_count);
    }
    if (m->texel_radiance && m->texel_width > 0 && m->texel_height > 0) prt__draw_upload_texels(d, m->texel_radiance, m->texel_width, m->texel_height);
    prt_status st = prt__draw_upload_sums(d, m);
    return st ? st : prt__draw_upload_gpu(d, m);
}

prt_status prt__draw_upload_sums(prt__draw *d, const prt_render_mesh *m)
{
    if (!m->gpu_sums) { d->sums.on_gpu = -1; return PRT_OK; }
    glBindBuffer(GL_ARRAY_BUFFER, d->vbo_rad);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(m->vertex_count * 3 * sizeof(float)), m->radiance, GL_DYNAMIC_DRAW);
    if (!d->vbo_rad2) glGenBuffers(1, &d->vbo_rad2);
    if (d->rad2_vertices != m->vertex_count) {
        glBindBuffer(GL_ARRAY_BUFFER, d->vbo_rad2);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(m->vertex_count * 3 * sizeof(float)), NULL, GL_DYNAMIC_COPY);
        d->rad2_vertices = m->vertex_count;
    }
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    prt_status st = prt__sums_gl_run(&d->sums, d->ctx, m, d->vbo_rad, d->vbo_rad2);
    const prt_render_product *kv = prt_render_sums_kvec_product(m->gpu_sums);
    if (!st && kv && d->kvec_terms) {
        const size_t K = (size_t)d->kvec_terms;
        if (kv->rows != m->vertex_count * K) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: %zu kvec rows for %zu vertices of %zu terms", kv->rows, m->vertex_count, K);
        if (d->sums.on_gpu == 1) {   /* the rows are the terms' buffer texture texels already */
            glBindBuffer(GL_COPY_READ_BUFFER, d->sums.p[kv - m->gpu_sums->products].out);
            glBindBuffer(GL_COPY_WRITE_BUFFER, d->tbo_k);
            glBufferData(GL_COPY_WRITE_BUFFER, (GLsizeiptr)(kv->rows * 4 * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
            glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, 0, (GLsizeiptr)(kv->rows * 4 * sizeof(float)));
            glBindTexture(GL_TEXTURE_BUFFER, d->tbo_k_tex);
            glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, d->tbo_k);
            glBindTexture(GL_TEXTURE_BUFFER, 0);
        } else {
            float *kvec = malloc(kv->rows * 3 * sizeof(float) + 1);
            if (!kvec) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
            st = prt_render_sums_kvec_cpu(m->gpu_sums, m->gpu_vector, m->vertex_count, d->kvec_terms, kvec);
            if (!st) prt__draw_upload_kvec(d, kvec, m->vertex_count);
            free(kvec);
            if (st) return st;
        }
    }
    const prt_render_product *e = prt_render_sums_exit_product(m->gpu_sums);
    if (st || !e || !d->exit_order) return st;
    const size_t n = (size_t)d->exit_order * d->exit_order;
    if (e->rows != m->vertex_count * n) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: %zu exit rows for %zu vertices of order %d", e->rows, m->vertex_count, d->exit_order);
    if (d->sums.on_gpu == 1) {   /* the rows are the exit buffer texture's texels already */
        glBindBuffer(GL_COPY_READ_BUFFER, d->sums.p[e - m->gpu_sums->products].out);
        glBindBuffer(GL_COPY_WRITE_BUFFER, d->tbo);
        glBufferData(GL_COPY_WRITE_BUFFER, (GLsizeiptr)(e->rows * 4 * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
        glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, 0, 0, (GLsizeiptr)(e->rows * 4 * sizeof(float)));
        glBindTexture(GL_TEXTURE_BUFFER, d->tbo_tex);
        glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, d->tbo);
        glBindTexture(GL_TEXTURE_BUFFER, 0);
        return PRT_OK;
    }
    float *exit_sh = malloc(m->vertex_count * 3 * n * sizeof(float));
    if (!exit_sh) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    st = prt_render_sums_exit_cpu(m->gpu_sums, m->gpu_vector, m->vertex_count, d->exit_order, exit_sh);
    if (!st) prt__draw_upload_exit(d, exit_sh, m->vertex_count);
    free(exit_sh);
    return st;
}

/* A display map: RGBA32F, filtered as the per-texel path samples it. */
static void display_map(GLuint tex, int width, int height)
{
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, width, height, 0, GL_RGBA, GL_FLOAT, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindTexture(GL_TEXTURE_2D, 0);
}

prt_status prt__draw_upload_gpu(prt__draw *d, const prt_render_mesh *m)
{
    d->side_by_side = false;
    if (!m->gpu_passes) return PRT_OK;
    if (!m->gpu_input || !d->has_uv) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU accumulation needs the first-order input and texture coordinates");
    prt_status st = prt__light_map_gl_load(&d->light_map, m->gpu_passes);
    if (st) return st;
    if (m->texel_width != d->light_map.width || m->texel_height != d->light_map.height)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU accumulation: a %dx%d input for a %dx%d light map", m->texel_width, m->texel_height, d->light_map.width,
                         d->light_map.height);
    if (!d->tex_first) glGenTextures(1, &d->tex_first);
    if (d->gpu_width != d->light_map.width || d->gpu_height != d->light_map.height) {   /* not on every light drag */
        display_map(d->tex, d->light_map.width, d->light_map.height);
        display_map(d->tex_first, d->light_map.width, d->light_map.height);
        d->gpu_width = d->light_map.width;
        d->gpu_height = d->light_map.height;
    }
    prt__light_map_gl_run(&d->light_map, m->gpu_input, m->gpu_pixel_direct, m->gpu_emission, m->gpu_bounces, m->gpu_component, d->tex, d->tex_first);
    d->texel_width = d->light_map.width;
    d->texel_height = d->light_map.height;
    d->side_by_side = m->side_by_side != 0;
    return PRT_OK;
}

void prt__draw_set_lights(prt__draw *d, const prt_render_mesh *m)
{
    prt__pixel_lights_set(&d->lights, d->vao, m);
}

void prt__draw_upload_texels(prt__draw *d, const float *rgb, int width, int height)
{
    if (!rgb || !d->has_uv || width <= 0 || height <= 0) { d->texel_width = d->texel_height = 0; return; }
    glBindTexture(GL_TEXTURE_2D, d->tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, width, height, 0, GL_RGB, GL_FLOAT, rgb);   /* row 0 = v near 0, as GL wants */
    d->gpu_width = d->gpu_height = 0;   /* no longer a render target */
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindTexture(GL_TEXTURE_2D, 0);
    d->texel_width = width;
    d->texel_height = height;
}

void prt__draw_upload_exit(prt__draw *d, const float *exit_sh, size_t nv)
{
    if (!d->exit_order) return;
    const size_t n = (size_t)d->exit_order * d->exit_order;
    if (d->pack_vertices != nv) {
        free(d->pack);
        d->pack = malloc(nv * n * 4 * sizeof(float));
        d->pack_vertices = d->pack ? nv : 0;
        if (!d->pack) { d->exit_order = 0; return; }   /* draws without the glossy part rather than crash */
    }
    /* One RGBA texel per coefficient: GL 3.3 buffer textures have no RGB32F. */
    for (size_t v = 0; v < nv; ++v)
        for (size_t i = 0; i < n; ++i) {
            float *t = d->pack + (v * n + i) * 4;
            for (int c = 0; c < 3; ++c) t[c] = exit_sh[(v * 3 + (size_t)c) * n + i];
            t[3] = 0.0f;
        }
    glBindBuffer(GL_TEXTURE_BUFFER, d->tbo);
    glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)(nv * n * 4 * sizeof(float)), d->pack, GL_DYNAMIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, d->tbo_tex);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, d->tbo);
    glBindTexture(GL_TEXTURE_BUFFER, 0);
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

void prt__draw_upload_kvec(prt__draw *d, const float *kvec, size_t nv)
{
    if (!d->kvec_terms || !kvec) return;
    const size_t K = (size_t)d->kvec_terms;
    if (d->kpack_vertices != nv) {
        free(d->kpack);
        d->kpack = malloc(nv * K * 4 * sizeof(float));
        d->kpack_vertices = d->kpack ? nv : 0;
        if (!d->kpack) { d->kvec_terms = 0; return; }
    }
    for (size_t v = 0; v < nv; ++v)
        for (size_t k = 0; k < K; ++k) {
            float *t = d->kpack + (v * K + k) * 4;
            for (int c = 0; c < 3; ++c) t[c] = kvec[(v * K + k) * 3 + (size_t)c];
            t[3] = (float)d->view_set[v];
        }
    glBindBuffer(GL_TEXTURE_BUFFER, d->tbo_k);
    glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)(nv * K * 4 * sizeof(float)), d->kpack, GL_DYNAMIC_DRAW);
    glBindTexture(GL_TEXTURE_BUFFER, d->tbo_k_tex);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, d->tbo_k);
    glBindTexture(GL_TEXTURE_BUFFER, 0);
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

void prt__camera_matrix(const prt_camera *cam, float aspect, float near_far[2], float out[16])
{
    float up[3] = {cam->up[0], cam->up[1], cam->up[2]};
    if (up[0] == 0 && up[1] == 0 && up[2] == 0) up[1] = 1;
    float f[3], s[3], u[3];
    prt__v3_sub(cam->target, cam->eye, f);
    float dist = prt__v3_len(f);
    prt__v3_normalize(f);
    prt__v3_cross(f, up, s);
    if (!prt__v3_normalize(s)) { float alt[3] = {0, 0, 1}; prt__v3_cross(f, alt, s); prt__v3_normalize(s); }
    prt__v3_cross(s, f, u);
    float view[16] = {s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
                      -prt__v3_dot(s, cam->eye), -prt__v3_dot(u, cam->eye), prt__v3_dot(f, cam->eye), 1};
    float fov = (cam->fov_y_deg > 0 ? cam->fov_y_deg : 40.0f) * (float)PRT_PI / 180.0f;
    float n = near_far ? near_far[0] : dist * 0.01f, fa = near_far ? near_far[1] : dist * 100.0f;
    float t = 1.0f / tanf(fov * 0.5f);
    float proj[16] = {t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (fa + n) / (n - fa), -1, 0, 0, 2 * fa * n / (n - fa), 0};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) {
            float acc = 0;
            for (int k = 0; k < 4; ++k) acc += proj[k * 4 + r] * view[c * 4 + k];
            out[c * 4 + r] = acc;
        }
}

void prt__draw_mesh(prt__draw *d, const prt_camera *cam, int w, int h, const float background[3])
{
    prt__pixel_lights_shadows(&d->lights, d->vao, d->index_count);
    float mvp[16];
    prt__camera_matrix(cam, (float)w / (float)h, NULL, mvp);
    glViewport(0, 0, w, h);
    glClearColor(background ? background[0] : 0, background ? background[1] : 0, background ? background[2] : 0, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);   /* one-sided walls must show from both sides */
    if (d->texel_width && d->side_by_side && d->tex_first) {
        /* First-order light on the left, the final light on the right, each with half the width;
         * the lights drawn per pixel on both, as both maps leave their direct light out. */
        const int half = w / 2;
        float side[16];
        prt__camera_matrix(cam, (float)half / (float)h, NULL, side);
        for (int k = 0; k < 2; ++k) {
            glViewport(k ? half : 0, 0, k ? w - half : half, h);
            glUseProgram(d->program_t);
            glUniformMatrix4fv(d->ut_mvp, 1, GL_FALSE, side);
            glActiveTexture(GL_TEXTURE0);
            glUniform1i(d->ut_map, 0);
            glBindTexture(GL_TEXTURE_2D, k ? d->tex : d->tex_first);
            glBindVertexArray(d->vao);
            glDrawElements(GL_TRIANGLES, (GLsizei)d->index_count, GL_UNSIGNED_INT, NULL);
            glBindVertexArray(0);
            prt__pixel_lights_draw(&d->lights, d->vao, d->index_count, side, cam->eye);
        }
        glViewport(0, 0, w, h);
        return;
    }
    if (d->texel_width) {
        glUseProgram(d->program_t);
        glUniformMatrix4fv(d->ut_mvp, 1, GL_FALSE, mvp);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, d->tex);
        glUniform1i(d->ut_map, 0);
    } else if (d->kvec_terms) {
        glUseProgram(d->program_s);
        glUniformMatrix4fv(d->us_mvp, 1, GL_FALSE, mvp);
        glUniform3fv(d->us_eye, 1, cam->eye);
        glUniform1i(d->us_terms, d->kvec_terms);
        glUniform1i(d->us_polar, d->view_polar);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_BUFFER, d->tbo_k_tex);
        glUniform1i(d->us_kvec, 0);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D_ARRAY, d->maps_tex);
        glUniform1i(d->us_maps, 1);
        glActiveTexture(GL_TEXTURE2);
        glBindTexture(GL_TEXTURE_BUFFER, d->tbo_set_tex);
        glUniform1i(d->us_kset, 2);
    } else if (d->exit_order) {
        float knorm[PRT_SH_MAX_ORDER * PRT_SH_MAX_ORDER];   /* the same K_lm as the CPU's evaluation */
        prt__sh_norms(knorm);
        glUseProgram(d->program_g);
        glUniformMatrix4fv(d->ug_mvp, 1, GL_FALSE, mvp);
        glUniform1i(d->ug_order, d->exit_order);
        glUniform1i(d->ug_mirror, d->exit_mirror);
        glUniform3fv(d->ug_eye, 1, cam->eye);
        glUniform1fv(d->ug_knorm, 100, knorm);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_BUFFER, d->tbo_tex);
        glUniform1i(d->ug_exit, 0);
    } else {
        glUseProgram(d->program);
        glUniformMatrix4fv(d->u_mvp, 1, GL_FALSE, mvp);
    }
    glBindVertexArray(d->vao);
    glDrawElements(GL_TRIANGLES, (GLsizei)d->index_count, GL_UNSIGNED_INT, NULL);
    glBindVertexArray(0);
    prt__pixel_lights_draw(&d->lights, d->vao, d->index_count, mvp, cam->eye);
    prt__volume_gl_draw(&d->volumes, mvp, cam->eye);   /* over the surfaces, tested against their depth */
}

void prt_camera_frame(const float lo[3], const float hi[3], const float *from, float fov_y_deg, float aspect, prt_camera *out)
{
    memset(out, 0, sizeof *out);
    float dir[3] = {0.55f, 0.45f, 0.7f};
    if (from) memcpy(dir, from, sizeof dir);
    if (!prt__v3_normalize(dir)) { dir[0] = 0; dir[1] = 0; dir[2] = 1; }
    float c[3], ext[3];
    for (int k = 0; k < 3; ++k) c[k] = 0.5f * (lo[k] + hi[k]);
    prt__v3_sub(hi, lo, ext);
    float radius = 0.5f * prt__v3_len(ext);
    if (!(radius > 0)) radius = 1;
    float fov = (fov_y_deg > 0 ? fov_y_deg : 40.0f) * (float)PRT_PI / 180.0f;
    float half = aspect < 1 ? atanf(tanf(fov * 0.5f) * aspect) : fov * 0.5f;
    float dist = radius / sinf(half) * 0.85f;   /* the bounding sphere overstates most scenes' silhouettes */
    for (int k = 0; k < 3; ++k) { out->target[k] = c[k]; out->eye[k] = c[k] + dir[k] * dist; }
    out->up[1] = 1;
    out->fov_y_deg = fov_y_deg > 0 ? fov_y_deg : 40.0f;
}

prt_status prt__target_init(prt__target *t, int width, int height, int samples)
{
    memset(t, 0, sizeof *t);
    t->width = width; t->height = height; t->samples = samples;
    glGenFramebuffers(1, &t->fbo_ms);
    glGenRenderbuffers(1, &t->color_ms);
    glGenRenderbuffers(1, &t->depth_ms);
    glBindRenderbuffer(GL_RENDERBUFFER, t->color_ms);
    /* Half floats: radiance to 3 significant digits, half the memory traffic of RGBA32F. */
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA16F, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, t->depth_ms);
    /* Stencil: the per-pixel lights pass lights each sample once, even where a mesh has two
     * coincident copies of a face (the Cornell box's boxes do). */
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH24_STENCIL8, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo_ms);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, t->color_ms);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, t->depth_ms);
    GLenum ms_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glGenFramebuffers(1, &t->fbo);
    glGenTextures(1, &t->color_tex);
    glBindTexture(GL_TEXTURE_2D, t->color_tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, width, height, 0, GL_RGBA, GL_FLOAT, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t->color_tex, 0);
    GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (ms_status != GL_FRAMEBUFFER_COMPLETE || status != GL_FRAMEBUFFER_COMPLETE) {
        prt__target_free(t);
        return prt__fail(NULL, PRT_ERR_BACKEND, "float framebuffer is not supported by this OpenGL driver");
    }
    return PRT_OK;
}

void prt__target_free(prt__target *t)
{
    GLuint fbos[2] = {t->fbo_ms, t->fbo}, rbs[2] = {t->color_ms, t->depth_ms};
    if (t->fbo_ms || t->fbo) glDeleteFramebuffers(2, fbos);
    if (t->color_ms || t->depth_ms) glDeleteRenderbuffers(2, rbs);
    if (t->color_tex) glDeleteTextures(1, &t->color_tex);
    memset(t, 0, sizeof *t);
}

void prt__target_draw(prt__target *t, prt__draw *d, const prt_camera *cam, const float background[3])
{
    prt__target_draw_cancellable(t, d, cam, background, NULL);
}

bool prt__target_draw_cancellable(prt__target *t, prt__draw *d, const prt_camera *cam, const float background[3], const prt_context *ctx)
{
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo_ms);
    /* A big image is drawn in bands of rows, finished one by one, so that a cancel is heard
     * between them (one draw of 12 million pixels takes seconds on a CPU rasterizer). The
     * shadow maps come first: the bands' scissor would clip them. */
    const int band = ctx && (size_t)t->width * t->height > ((size_t)2 << 20) ? (int)(((size_t)1 << 20) / (size_t)t->width) + 1 : t->height;
    if (band < t->height) {
        prt__pixel_lights_shadows(&d->lights, d->vao, d->index_count);
        glBindFramebuffer(GL_FRAMEBUFFER, t->fbo_ms);
        glEnable(GL_SCISSOR_TEST);
        for (int y = 0; y < t->height; y += band) {
            glScissor(0, y, t->width, band);
            prt__draw_mesh(d, cam, t->width, t->height, background);
            glFinish();
            if (prt__cancelled(ctx)) { glDisable(GL_SCISSOR_TEST); glBindFramebuffer(GL_FRAMEBUFFER, 0); return false; }
        }
        glDisable(GL_SCISSOR_TEST);
    } else {
        prt__draw_mesh(d, cam, t->width, t->height, background);
    }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t->fbo_ms);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, t->fbo);
    glBlitFramebuffer(0, 0, t->width, t->height, 0, 0, t->width, t->height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return true;
}

prt_status prt__target_read(const prt__target *t, prt_image *out)
{
    memset(out, 0, sizeof *out);
    size_t n = (size_t)t->width * t->height;
    float *rgba = malloc(n * 4 * sizeof(float));
    out->rgb = malloc(n * 3 * sizeof(float));
    if (!rgba || !out->rgb) { free(rgba); free(out->rgb); out->rgb = NULL; return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t->fbo);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, t->width, t->height, GL_RGBA, GL_FLOAT, rgba);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    GLenum err = glGetError();
    out->width = t->width;
    out->height = t->height;
    for (int y = 0; y < t->height; ++y)   /* GL's rows run bottom-up; prt images top-down */
        for (int x = 0; x < t->width; ++x)
            for (int c = 0; c < 3; ++c)
                out->rgb[((size_t)y * t->width + x) * 3 + c] = rgba[((size_t)(t->height - 1 - y) * t->width + x) * 4 + c];
    free(rgba);
    if (err != GL_NO_ERROR) { prt_image_free(out); return prt__fail(NULL, PRT_ERR_BACKEND, "OpenGL error 0x%x while drawing", err); }
    return PRT_OK;
}
