/* Light maps finished by the GPU (offset radiance transfer mapping's run time, Sunshine-Hill &
 * Faloutsos 2006, sections 5.1-5.2). Light maps are RGBA32F render targets of the light map's size;
 * a pass draws, for every slice of every map, a quad over the slice's texels whose fragments add
 * map(t) x light(source(t + offset)) into the target with GL_ONE, GL_ONE blending. Reading the
 * light through the gutter-source map (a dependent read the paper's 2006 GPU avoided with dilated
 * gutters) gives exactly the sum a CPU takes over the same description. */
#include "render/light_map_gl.h"

#include "render/draw.h"

#include <string.h>

/* Quad corners in texel units; per slice: where its atlas texels are relative to the light map
 * (shift), the offset whose light it multiplies, and its atlas layer. */
static const char *VS_ACCUM =
    "#version 330 core\n"
    "layout(location = 0) in vec2 corner;\n"
    "layout(location = 1) in ivec4 shift_offset;\n"
    "layout(location = 2) in int layer;\n"
    "layout(location = 3) in int level;\n"
    "uniform vec2 size;\n"
    "flat out ivec4 f_so; flat out int f_layer; flat out int f_level;\n"
    "void main() { f_so = shift_offset; f_layer = layer; f_level = level; gl_Position = vec4(corner / size * 2.0 - 1.0, 0.0, 1.0); }\n";
static const char *FS_ACCUM =
    "#version 330 core\n"
    "flat in ivec4 f_so; flat in int f_layer; flat in int f_level;\n"
    "uniform sampler2DArray atlas; uniform sampler2D light, pyramid, charts; uniform isampler2D source;\n"
    "layout(location = 0) out vec4 bounce;\n"
    "layout(location = 1) out vec4 total;\n"
    "void main() {\n"
    "  ivec2 t = ivec2(gl_FragCoord.xy), p = t + f_so.zw, size = textureSize(source, 0);\n"
    "  if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, size))) discard;\n"
    "  ivec2 s = texelFetch(source, p, 0).xy;\n"
    "  if (s.x < 0) discard;\n"
    "  vec3 l = texelFetch(light, s, 0).rgb;\n"
    /* The light around s at the map's level, over blocks on s's chart alone (prefilter.c). */
    "  if (f_level > 0) {\n"
    "    float own = texelFetch(charts, s, 0).r;\n"
    "    for (int k = 1; k <= f_level; ++k) {\n"
    "      float inv = 1.0 / float(1 << k);\n"
    "      vec2 f = (vec2(s) + 0.5) * inv - 0.5;\n"
    "      ivec2 b0 = ivec2(floor(f)), size = textureSize(pyramid, k);\n"
    "      vec2 a = f - vec2(b0);\n"
    "      vec3 v = vec3(0.0);\n"
    "      for (int j = 0; j < 4; ++j) {\n"
    "        ivec2 b = b0 + ivec2(j & 1, j >> 1);\n"
    "        float w = ((j & 1) != 0 ? a.x : 1.0 - a.x) * ((j >> 1) != 0 ? a.y : 1.0 - a.y);\n"
    "        bool inside = b.x >= 0 && b.y >= 0 && b.x < size.x && b.y < size.y;\n"
    "        vec4 q = inside ? texelFetch(pyramid, b, k) : vec4(0.0);\n"
    "        bool pure = inside && q.a > 0.0 && texelFetch(charts, b, k).r == own;\n"
    "        v += w * (pure ? q.rgb / q.a : l);\n"
    "      }\n"
    "      l = v;\n"
    "    }\n"
    "  }\n"
    "  vec3 c = texelFetch(atlas, ivec3(t + f_so.xy, f_layer), 0).rgb * l;\n"
    "  bounce = vec4(c, 0.0);\n"
    "  total = vec4(c, 0.0);\n"
    "}\n";
/* Full-map passes: a triangle covering the map, each texel computed at its source. */
static const char *VS_FULL =
    "#version 330 core\n"
    "void main() { vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0); gl_Position = vec4(p, 0.0, 1.0); }\n";
/* First-order light: albedo x irradiance / pi, or on masked texels what the scatter pass gathered. */
static const char *FS_FIRST =
    "#version 330 core\n"
    "uniform isampler2D source; uniform sampler2D input_map, albedo, mask, sub; uniform int has_sub;\n"
    "out vec4 color;\n"
    "void main() {\n"
    "  ivec2 s = texelFetch(source, ivec2(gl_FragCoord.xy), 0).xy;\n"
    "  if (s.x < 0) { color = vec4(0.0); return; }\n"
    "  vec3 f = texelFetch(albedo, s, 0).rgb * texelFetch(input_map, s, 0).rgb;\n"
    "  if (has_sub != 0 && texelFetch(mask, s, 0).r > 0.0) f = texelFetch(sub, s, 0).rgb;\n"
    "  color = vec4(f, 1.0);\n"
    "}\n";
/* The light's pyramid (prefilter.c's, to the float): level 0 area x light and area, and each
 * texel's chart (-2 off the surface); each level above the sums of its four children, in the same
 * order, and their chart, -1 where they differ. */
static const char *FS_PYRAMID0 =
    "#version 330 core\n"
    "uniform sampler2D light, area_chart;\n"
    "layout(location = 0) out vec4 sum;\n"
    "layout(location = 1) out vec4 chart;\n"
    "void main() {\n"
    "  ivec2 p = ivec2(gl_FragCoord.xy);\n"
    "  if (any(greaterThanEqual(p, textureSize(area_chart, 0)))) { sum = vec4(0.0); chart = vec4(-2.0); return; }\n"
    "  vec2 ac = texelFetch(area_chart, p, 0).rg;\n"
    "  sum = vec4(ac.r * texelFetch(light, p, 0).rgb, ac.r);\n"
    "  chart = vec4(ac.g);\n"
    "}\n";
static const char *FS_PYRAMID =
    "#version 330 core\n"
    "uniform sampler2D below, below_chart;\n"
    "layout(location = 0) out vec4 sum;\n"
    "layout(location = 1) out vec4 chart;\n"
    "void main() {\n"
    "  ivec2 p = ivec2(gl_FragCoord.xy) * 2, size = textureSize(below, 0);\n"
    "  vec4 q = vec4(0.0); float c = -2.0;\n"
    "  for (int j = 0; j < 4; ++j) {\n"
    "    ivec2 d = p + ivec2(j & 1, j >> 1);\n"
    "    if (d.x >= size.x || d.y >= size.y) continue;\n"
    "    q += texelFetch(below, d, 0);\n"
    "    float e = texelFetch(below_chart, d, 0).r;\n"
    "    if (e == -2.0) continue;\n"
    "    c = c == -2.0 ? e : c == e ? c : -1.0;\n"
    "  }\n"
    "  sum = q;\n"
    "  chart = vec4(c);\n"
    "}\n";
/* What is shown: first-order plus emission less the light drawn per pixel (pixel_direct: the
 * renderer's pixel lights on opaque texels, kept in first for the bounces), bounced light, or both
 * (component 0 all, 1 direct, 2 indirect); the first-order map alone as the second output. */
static const char *FS_FINAL =
    "#version 330 core\n"
    "uniform isampler2D source; uniform sampler2D first, total, emit, pixel_direct, area_chart, normals; uniform float emission;\n"
    "uniform int component, has_pixel, smooth_radius;\n"
    "layout(location = 0) out vec4 color;\n"
    "layout(location = 1) out vec4 first_order;\n"
    "void main() {\n"
    "  ivec2 s = texelFetch(source, ivec2(gl_FragCoord.xy), 0).xy;\n"
    "  if (s.x < 0) { color = first_order = vec4(0.0, 0.0, 0.0, 1.0); return; }\n"
    "  vec3 f = texelFetch(first, s, 0).rgb + emission * texelFetch(emit, s, 0).rgb, g = texelFetch(total, s, 0).rgb;\n"
    /* The bounced light over the texel's chart around it (methods/offset/smooth.c, in its order). */
    "  float own = smooth_radius > 0 ? texelFetch(area_chart, s, 0).g : -1.0;\n"
    "  if (own >= 0.0) {\n"
    "    ivec2 size = textureSize(area_chart, 0);\n"
    "    vec3 acc = vec3(0.0), n = texelFetch(normals, s, 0).rgb; float sum = 0.0;\n"
    "    for (int dy = -smooth_radius; dy <= smooth_radius; ++dy)\n"
    "      for (int dx = -smooth_radius; dx <= smooth_radius; ++dx) {\n"
    "        ivec2 q = s + ivec2(dx, dy);\n"
    "        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;\n"
    "        vec2 ac = texelFetch(area_chart, q, 0).rg;\n"
    "        if (ac.g != own) continue;\n"
    "        float f = max(dot(n, texelFetch(normals, q, 0).rgb), 0.0);\n"
    "        for (int k = 0; k < 5; ++k) f *= f;\n"
    "        float w = float((smooth_radius + 1 - abs(dx)) * (smooth_radius + 1 - abs(dy))) * ac.r * f;\n"
    "        if (!(w > 0.0)) continue;\n"
    "        acc += w * texelFetch(total, q, 0).rgb;\n"
    "        sum += w;\n"
    "      }\n"
    "    if (sum > 0.0) g = acc / sum;\n"
    "  }\n"
    "  if (has_pixel != 0) f = max(f - texelFetch(pixel_direct, s, 0).rgb, 0.0);\n"
    "  color = vec4(component == 1 ? f : component == 2 ? g : f + g, 1.0);\n"
    "  first_order = vec4(f, 1.0);\n"
    "}\n";

typedef struct quad_vertex {
    float x, y;
    int32_t shift_x, shift_y, offset_x, offset_y, layer, level;
} quad_vertex;

static GLuint new_map(int w, int h, GLenum internal, GLenum format, GLenum type, const void *data)
{
    GLuint tex;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, (GLint)internal, w, h, 0, format, type, data);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindTexture(GL_TEXTURE_2D, 0);
    return tex;
}

/* A per-texel map of a covered-texel array (floats per texel, 1 or 3; none: zeros), zero off the
 * surface. */
static GLuint texel_map(const prt_render_passes *lm, const float *values, const uint8_t *bytes, int floats, float *scratch)
{
    const size_t n = (size_t)lm->width * lm->height;
    memset(scratch, 0, n * 3 * sizeof *scratch);
    for (size_t i = 0; (values || bytes) && i < lm->covered; ++i)
        for (int c = 0; c < floats; ++c)
            scratch[(size_t)lm->texel[i] * floats + c] = values ? values[i * floats + c] : (float)bytes[i];
    return new_map(lm->width, lm->height, floats == 3 ? GL_RGB32F : GL_R32F, floats == 3 ? GL_RGB : GL_RED, GL_FLOAT, scratch);
}

void prt__light_map_gl_free(prt__light_map_gl *g)
{
    for (int k = 0; k < 2; ++k) {
        if (g->atlas[k]) glDeleteTextures(1, &g->atlas[k]);
        if (g->vbo[k]) glDeleteBuffers(1, &g->vbo[k]);
        if (g->vao[k]) glDeleteVertexArrays(1, &g->vao[k]);
    }
    GLuint tex[] = {g->source, g->albedo, g->mask, g->emit, g->input, g->sub, g->first, g->bounce[0], g->bounce[1], g->total, g->pixel_direct,
                    g->area_chart, g->normals, g->pyramid, g->charts};
    for (size_t i = 0; i < sizeof tex / sizeof *tex; ++i)
        if (tex[i]) glDeleteTextures(1, &tex[i]);
    if (g->fbo) glDeleteFramebuffers(1, &g->fbo);
    if (g->p_accum) glDeleteProgram(g->p_accum);
    if (g->p_first) glDeleteProgram(g->p_first);
    if (g->p_final) glDeleteProgram(g->p_final);
    if (g->p_pyramid0) glDeleteProgram(g->p_pyramid0);
    if (g->p_pyramid) glDeleteProgram(g->p_pyramid);
    memset(g, 0, sizeof *g);
}

/* Every slice inside the light map and its atlas, of a map of the set; false otherwise. */
static bool set_valid(const prt_render_passes *lm, const prt_render_map_set *set)
{
    if (!set->map_count) return true;
    if (set->map_count < 0 || !set->maps || !set->offsets || set->slice_count < 0 || (set->slice_count && !set->slices) || set->atlas_size < 1 ||
        (set->atlas_size & (set->atlas_size - 1)) || set->atlas_layers < 0)
        return false;
    for (int i = 0; i < set->slice_count; ++i) {
        const prt_render_slice *p = &set->slices[i];
        if (p->map < 0 || p->map >= set->map_count || p->w < 1 || p->h < 1 || p->x < 0 || p->y < 0 || p->x > lm->width - p->w ||
            p->y > lm->height - p->h || p->layer < 0 || p->layer >= set->atlas_layers || p->ax < 0 || p->ay < 0 || p->ax > set->atlas_size - p->w ||
            p->ay > set->atlas_size - p->h)
            return false;
    }
    return true;
}

/* Uploads set k's atlases (layer by layer, each slice's texels from the covered-texel maps through
 * index) and the slices' quads. */
static prt_status upload_set(prt__light_map_gl *g, const prt_render_passes *lm, const prt_render_map_set *set, const int32_t *index, int k,
                             int max_size, int max_layers)
{
    if (!set->map_count || !set->slice_count) return PRT_OK;
    const int W = lm->width, size = set->atlas_size, layers = set->atlas_layers;
    const size_t nc = lm->covered;
    if (size > max_size) return prt__fail(NULL, PRT_ERR_BACKEND, "atlases of %d^2 texels are beyond this GPU's %d-texel textures", size, max_size);
    if (layers > max_layers)
        return prt__fail(NULL, PRT_ERR_BACKEND, "the light map's passes need %d atlases of %d^2 texels; this GPU holds %d in one texture array", layers, size,
                         max_layers);
    const size_t layer_texels = (size_t)size * size;
    float *layer = malloc(layer_texels * 3 * sizeof *layer);
    quad_vertex *quads = malloc((size_t)set->slice_count * 6 * sizeof *quads);
    if (!layer || !quads) { free(layer); free(quads); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for the light map's atlases"); }
    glGenTextures(1, &g->atlas[k]);
    glBindTexture(GL_TEXTURE_2D_ARRAY, g->atlas[k]);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGB32F, size, size, layers, 0, GL_RGB, GL_FLOAT, NULL);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    /* One atlas at a time: its slices' texels straight from the covered-texel maps. */
    for (int b = 0; b < layers; ++b) {
        memset(layer, 0, layer_texels * 3 * sizeof *layer);
        for (int p = 0; p < set->slice_count; ++p) {
            const prt_render_slice *pc = &set->slices[p];
            if (pc->layer != b) continue;
            const float *map = set->maps + (size_t)pc->map * nc * 3;
            for (int y = 0; y < pc->h; ++y)
                for (int x = 0; x < pc->w; ++x) {
                    const int32_t i = index[(size_t)(pc->y + y) * W + pc->x + x];
                    if (i >= 0) memcpy(layer + ((size_t)(pc->ay + y) * size + pc->ax + x) * 3, map + (size_t)i * 3, 3 * sizeof *layer);
                }
        }
        glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, b, size, size, 1, GL_RGB, GL_FLOAT, layer);
    }
    for (int p = 0; p < set->slice_count; ++p) {
        const prt_render_slice *pc = &set->slices[p];
        const quad_vertex v = {0, 0, pc->ax - pc->x, pc->ay - pc->y, set->offsets[pc->map * 2], set->offsets[pc->map * 2 + 1], pc->layer,
                               set->levels ? set->levels[pc->map] : 0};
        const float xs[6] = {0, 1, 1, 0, 1, 0}, ys[6] = {0, 0, 1, 0, 1, 1};
        for (int c = 0; c < 6; ++c) {
            quads[p * 6 + c] = v;
            quads[p * 6 + c].x = (float)(pc->x + xs[c] * pc->w);
            quads[p * 6 + c].y = (float)(pc->y + ys[c] * pc->h);
        }
    }
    glGenVertexArrays(1, &g->vao[k]);
    glGenBuffers(1, &g->vbo[k]);
    glBindVertexArray(g->vao[k]);
    glBindBuffer(GL_ARRAY_BUFFER, g->vbo[k]);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)set->slice_count * 6 * sizeof *quads), quads, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof *quads, (void *)offsetof(quad_vertex, x));
    glEnableVertexAttribArray(1);
    glVertexAttribIPointer(1, 4, GL_INT, sizeof *quads, (void *)offsetof(quad_vertex, shift_x));
    glEnableVertexAttribArray(2);
    glVertexAttribIPointer(2, 1, GL_INT, sizeof *quads, (void *)offsetof(quad_vertex, layer));
    glEnableVertexAttribArray(3);
    glVertexAttribIPointer(3, 1, GL_INT, sizeof *quads, (void *)offsetof(quad_vertex, level));
    glBindVertexArray(0);
    g->vertices[k] = set->slice_count * 6;
    free(layer);
    free(quads);
    return PRT_OK;
}

prt_status prt__light_map_gl_load(prt__light_map_gl *g, const prt_render_passes *lm)
{
    if (!lm) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU accumulation needs a light-map description");
    if (lm->id && g->id == lm->id) return PRT_OK;
    prt__light_map_gl_free(g);
    const int W = lm->width, H = lm->height;
    const size_t n = (size_t)(W > 0 ? W : 0) * (size_t)(H > 0 ? H : 0);
    bool ok = W > 0 && H > 0 && lm->covered <= n && (lm->texel || !lm->covered) && lm->source && lm->albedo && set_valid(lm, &lm->scatter) &&
              set_valid(lm, &lm->bounce);
    for (size_t i = 0; ok && i < lm->covered; ++i) ok = lm->texel[i] < n && (i == 0 || lm->texel[i] > lm->texel[i - 1]);
    for (size_t i = 0; ok && i < n; ++i) ok = lm->source[i] >= -1 && lm->source[i] < (int64_t)lm->covered;
    if (!ok) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the light map's description is inconsistent (sizes, texels, sources or slices)");
    GLint max_size = 0, max_layers = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    if (W > max_size || H > max_size) return prt__fail(NULL, PRT_ERR_BACKEND, "a %dx%d light map is beyond this GPU's %d-texel textures", W, H, max_size);
    g->width = W;
    g->height = H;
    g->p_accum = prt__gl_program(VS_ACCUM, NULL, FS_ACCUM);
    g->p_first = g->p_accum ? prt__gl_program(VS_FULL, NULL, FS_FIRST) : 0;
    g->p_final = g->p_first ? prt__gl_program(VS_FULL, NULL, FS_FINAL) : 0;
    g->p_pyramid0 = g->p_final ? prt__gl_program(VS_FULL, NULL, FS_PYRAMID0) : 0;
    g->p_pyramid = g->p_pyramid0 ? prt__gl_program(VS_FULL, NULL, FS_PYRAMID) : 0;
    if (!g->p_pyramid) { prt__light_map_gl_free(g); return PRT_ERR_BACKEND; }   /* prt__gl_program said why */
    g->levels = 0;
    for (int k = 0; lm->bounce.levels && k < lm->bounce.map_count; ++k) g->levels = lm->bounce.levels[k] > g->levels ? lm->bounce.levels[k] : g->levels;
    if (lm->smooth_radius < 0 || lm->smooth_radius > 64) {
        prt__light_map_gl_free(g);
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the light map's smoothing radius %d is outside 0..64 texels", lm->smooth_radius);
    }
    g->smooth_radius = g->levels && lm->normal ? lm->smooth_radius : 0;
    g->pyramid_size = 1;
    while (g->pyramid_size < W || g->pyramid_size < H) g->pyramid_size *= 2;
    if (g->levels && (g->levels > 15 || !lm->area || !lm->chart || (1 << g->levels) > g->pyramid_size)) {
        prt__light_map_gl_free(g);
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the light map's description has pyramid levels without texel areas and charts, or past its size");
    }
    while (glGetError() != GL_NO_ERROR) {}
    float *scratch = malloc(n * 3 * sizeof *scratch);
    int32_t *index = malloc(n * sizeof *index), *src = malloc(n * 2 * sizeof *src);
    prt_status st = scratch && index && src ? PRT_OK : prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for the light map");
    if (!st) {
        for (size_t i = 0; i < n; ++i) index[i] = -1;
        for (size_t i = 0; i < lm->covered; ++i) index[lm->texel[i]] = (int32_t)i;
        st = upload_set(g, lm, &lm->bounce, index, 0, max_size, max_layers);
    }
    if (!st) st = upload_set(g, lm, &lm->scatter, index, 1, max_size, max_layers);
    if (!st) {
        for (size_t i = 0; i < n; ++i) {
            const int32_t c = lm->source[i];
            src[i * 2] = c < 0 ? -1 : (int32_t)(lm->texel[c] % (uint32_t)W);
            src[i * 2 + 1] = c < 0 ? -1 : (int32_t)(lm->texel[c] / (uint32_t)W);
        }
        g->source = new_map(W, H, GL_RG32I, GL_RG_INTEGER, GL_INT, src);
        g->albedo = texel_map(lm, lm->albedo, NULL, 3, scratch);
        g->has_mask = lm->scatter_mask != NULL;
        g->mask = texel_map(lm, NULL, lm->scatter_mask, 1, scratch);
        g->has_emit = lm->emission != NULL;
        g->emit = texel_map(lm, lm->emission, NULL, 3, scratch);
        GLuint *work[] = {&g->input, &g->sub, &g->first, &g->bounce[0], &g->bounce[1], &g->total, &g->pixel_direct};
        for (size_t i = 0; i < sizeof work / sizeof *work; ++i) *work[i] = new_map(W, H, GL_RGBA32F, GL_RGBA, GL_FLOAT, NULL);
        if (g->levels) {   /* the prefilter's inputs and pyramid: every level allocated, so texelFetch may read any */
            for (size_t i = 0; i < n * 3; ++i) scratch[i] = 0;
            for (size_t i = 0; i < n; ++i) scratch[i * 2 + 1] = -2.0f;
            for (size_t i = 0; i < lm->covered; ++i) {
                scratch[(size_t)lm->texel[i] * 2] = lm->area[i];
                scratch[(size_t)lm->texel[i] * 2 + 1] = lm->chart[i] < 0 ? -1.0f : (float)lm->chart[i];   /* no chart: never pure (prefilter.c) */
            }
            g->area_chart = new_map(W, H, GL_RG32F, GL_RG, GL_FLOAT, scratch);
            if (g->smooth_radius) {
                for (size_t i = 0; i < n * 3; ++i) scratch[i] = 0;
                for (size_t i = 0; i < lm->covered; ++i) memcpy(scratch + (size_t)lm->texel[i] * 3, lm->normal + i * 3, 3 * sizeof *scratch);
                g->normals = new_map(W, H, GL_RGB32F, GL_RGB, GL_FLOAT, scratch);
            }
            GLuint *pyr[2] = {&g->pyramid, &g->charts};
            const GLenum internal[2] = {GL_RGBA32F, GL_R32F}, format[2] = {GL_RGBA, GL_RED};
            for (int k = 0; k < 2; ++k) {
                glGenTextures(1, pyr[k]);
                glBindTexture(GL_TEXTURE_2D, *pyr[k]);
                for (int l = 0; l <= g->levels; ++l)
                    glTexImage2D(GL_TEXTURE_2D, l, (GLint)internal[k], g->pyramid_size >> l, g->pyramid_size >> l, 0, format[k], GL_FLOAT, NULL);
                glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
                glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
                glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
                glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, g->levels);
            }
            glBindTexture(GL_TEXTURE_2D, 0);
        }
        glGenFramebuffers(1, &g->fbo);
    }
    free(scratch);
    free(index);
    free(src);
    if (!st) {
        const GLenum e = glGetError();
        if (e == GL_OUT_OF_MEMORY) st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "the GPU has no room for the light map's atlases");
        else if (e != GL_NO_ERROR) st = prt__fail(NULL, PRT_ERR_BACKEND, "uploading the light map's atlases failed (GL error 0x%x)", e);
    }
    if (st) { prt__light_map_gl_free(g); return st; }
    g->id = lm->id;
    return PRT_OK;
}

static void bind(GLuint program, const char *name, int unit, GLenum target, GLuint tex)
{
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(target, tex);
    glUniform1i(glGetUniformLocation(program, name), unit);
}

static void target(GLuint fbo, GLuint color0, GLuint color1)
{
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, color0, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, color1, 0);
    const GLenum both[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(color1 ? 2 : 1, both);
}

/* Adds every slice of kind k's maps times `light` into the bound targets. */
static void accumulate(prt__light_map_gl *g, int k, GLuint light)
{
    glUseProgram(g->p_accum);
    glUniform2f(glGetUniformLocation(g->p_accum, "size"), (float)g->width, (float)g->height);
    bind(g->p_accum, "atlas", 0, GL_TEXTURE_2D_ARRAY, g->atlas[k]);
    bind(g->p_accum, "light", 1, GL_TEXTURE_2D, light);
    bind(g->p_accum, "source", 2, GL_TEXTURE_2D, g->source);
    bind(g->p_accum, "pyramid", 3, GL_TEXTURE_2D, g->pyramid);
    bind(g->p_accum, "charts", 4, GL_TEXTURE_2D, g->charts);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    glBlendEquation(GL_FUNC_ADD);
    glBindVertexArray(g->vao[k]);
    glDrawArrays(GL_TRIANGLES, 0, g->vertices[k]);
    glBindVertexArray(0);
    glDisable(GL_BLEND);
}

/* The pyramid of `light` (FS_PYRAMID0, FS_PYRAMID): level l rendered while level l - 1 is the
 * only one its textures show (base = max = l - 1), so no pass reads what it writes. */
static void build_pyramid(prt__light_map_gl *g, GLuint light, GLuint vao)
{
    glBindVertexArray(vao);
    for (int l = 0; l <= g->levels; ++l) {
        glBindFramebuffer(GL_FRAMEBUFFER, g->fbo);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, g->pyramid, l);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, g->charts, l);
        const GLenum both[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
        glDrawBuffers(2, both);
        glViewport(0, 0, g->pyramid_size >> l, g->pyramid_size >> l);
        if (l == 0) {
            glUseProgram(g->p_pyramid0);
            bind(g->p_pyramid0, "light", 0, GL_TEXTURE_2D, light);
            bind(g->p_pyramid0, "area_chart", 1, GL_TEXTURE_2D, g->area_chart);
        } else {
            GLuint tex[2] = {g->pyramid, g->charts};
            for (int k = 0; k < 2; ++k) {
                glBindTexture(GL_TEXTURE_2D, tex[k]);
                glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, l - 1);
                glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, l - 1);
            }
            glUseProgram(g->p_pyramid);
            bind(g->p_pyramid, "below", 0, GL_TEXTURE_2D, g->pyramid);
            bind(g->p_pyramid, "below_chart", 1, GL_TEXTURE_2D, g->charts);
        }
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    GLuint tex[2] = {g->pyramid, g->charts};
    for (int k = 0; k < 2; ++k) {
        glBindTexture(GL_TEXTURE_2D, tex[k]);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, g->levels);
    }
    glBindTexture(GL_TEXTURE_2D, 0);
    glViewport(0, 0, g->width, g->height);
}

void prt__light_map_gl_run(prt__light_map_gl *g, const float *input, const float *pixel_direct, float emission, int bounces, int component,
                           GLuint final_tex, GLuint first_tex)
{
    const float zero[4] = {0, 0, 0, 0};
    GLint viewport[4];
    glGetIntegerv(GL_VIEWPORT, viewport);
    const GLboolean multisample = glIsEnabled(GL_MULTISAMPLE), depth = glIsEnabled(GL_DEPTH_TEST), cull = glIsEnabled(GL_CULL_FACE),
                    blend = glIsEnabled(GL_BLEND);
    GLint program = 0;
    glGetIntegerv(GL_CURRENT_PROGRAM, &program);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glDisable(GL_MULTISAMPLE);
    glViewport(0, 0, g->width, g->height);
    glBindTexture(GL_TEXTURE_2D, g->input);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, g->width, g->height, GL_RGB, GL_FLOAT, input);
    if (pixel_direct) {
        glBindTexture(GL_TEXTURE_2D, g->pixel_direct);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, g->width, g->height, GL_RGB, GL_FLOAT, pixel_direct);
    }
    GLuint empty_vao;
    glGenVertexArrays(1, &empty_vao);
    /* The scatter pass over the irradiance (subsurface scattering), then the first-order light map. */
    if (g->vertices[1]) {
        target(g->fbo, g->sub, 0);
        glClearBufferfv(GL_COLOR, 0, zero);
        accumulate(g, 1, g->input);
    }
    target(g->fbo, g->first, 0);
    glUseProgram(g->p_first);
    bind(g->p_first, "source", 0, GL_TEXTURE_2D, g->source);
    bind(g->p_first, "input_map", 1, GL_TEXTURE_2D, g->input);
    bind(g->p_first, "albedo", 2, GL_TEXTURE_2D, g->albedo);
    bind(g->p_first, "mask", 3, GL_TEXTURE_2D, g->mask);
    bind(g->p_first, "sub", 4, GL_TEXTURE_2D, g->sub);
    glUniform1i(glGetUniformLocation(g->p_first, "has_sub"), g->vertices[1] && g->has_mask);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    /* Inter-reflection: each bounce gathers the last one's light; all of them add into total. */
    target(g->fbo, g->total, 0);
    glClearBufferfv(GL_COLOR, 0, zero);
    GLuint from = g->first;
    for (int b = 0; b < bounces && g->vertices[0] && component != PRT_COMPONENT_DIRECT; ++b) {
        const GLuint to = g->bounce[b & 1];
        if (g->levels) build_pyramid(g, from, empty_vao);
        target(g->fbo, to, g->total);
        glClearBufferfv(GL_COLOR, 0, zero);
        accumulate(g, 0, from);
        from = to;
    }
    target(g->fbo, final_tex, first_tex);
    glUseProgram(g->p_final);
    bind(g->p_final, "source", 0, GL_TEXTURE_2D, g->source);
    bind(g->p_final, "first", 1, GL_TEXTURE_2D, g->first);
    bind(g->p_final, "total", 2, GL_TEXTURE_2D, g->total);
    bind(g->p_final, "emit", 3, GL_TEXTURE_2D, g->emit);
    bind(g->p_final, "pixel_direct", 4, GL_TEXTURE_2D, g->pixel_direct);
    bind(g->p_final, "area_chart", 5, GL_TEXTURE_2D, g->area_chart);   /* 0 without smooth_radius: then never read */
    bind(g->p_final, "normals", 6, GL_TEXTURE_2D, g->normals);
    /* Nothing bounced (no bounces, or the direct light alone): nothing to smooth. */
    const int smooth = bounces > 0 && component != PRT_COMPONENT_DIRECT ? g->smooth_radius : 0;
    glUniform1i(glGetUniformLocation(g->p_final, "smooth_radius"), smooth);
    glUniform1f(glGetUniformLocation(g->p_final, "emission"), g->has_emit ? emission : 0.0f);
    glUniform1i(glGetUniformLocation(g->p_final, "component"), component);
    glUniform1i(glGetUniformLocation(g->p_final, "has_pixel"), pixel_direct != NULL);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glDeleteVertexArrays(1, &empty_vao);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glActiveTexture(GL_TEXTURE0);
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    /* As found: the mesh is drawn next (antialiased, depth-tested). */
    if (multisample) glEnable(GL_MULTISAMPLE);
    if (depth) glEnable(GL_DEPTH_TEST);
    if (cull) glEnable(GL_CULL_FACE);
    if (blend) glEnable(GL_BLEND);
    for (int unit = 6; unit >= 0; --unit) {
        glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
        glBindTexture(GL_TEXTURE_2D, 0);
        glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
    }
    glUseProgram((GLuint)program);
}
