/* The spherical-harmonic method's table entry: bake options, its chunks in file.c (SHTR, CPCA, TXAL, TXLS),
 * its description, variants (the transfer kinds), controls and relighting. The bake itself lives
 * in bake*.c, relighting kernels in relight*.c, compression in compress.c, exports in
 * export.c. */
#include "methods/sh/sh.h"
#include "transfer/gpu_sums.h"
#include "methods/sh/bake.h"
#include "geom/texel_raster.h"
#include "light/envmap_internal.h"

#include <strings.h>


/* ---- state and kinds ---- */
prt__sh_state *prt__sh_state_new(void)
{
    prt__sh_state *s = prt__calloc(1, sizeof(prt__sh_state));
    pthread_mutex_t *lock = malloc(sizeof *lock);
    if (!s || !lock) { free(s); free(lock); return NULL; }
    pthread_mutex_init(lock, NULL);
    s->lock = lock;
    return s;
}

void prt__sh_state_free(void *state)
{
    prt__sh_state *s = state;
    if (!s) return;
    for (int i = 0; i < PRT__KIND_COUNT; ++i) {
        free(s->sets[i].coeffs);
        prt__cpca_free(s->sets[i].cpca);
    }
    prt__texel_sets_free(&s->texels);
    prt__sh_grid_free(&s->grid);
    for (int k = 0; k < s->volume_count; ++k) prt__sh_volume_free(&s->volumes[k]);
    free(s->volumes);
    prt__sh_frames_free(&s->frames);
    if (s->rays_ready) prt__raycaster_release(&s->rays);
    for (int i = 0; i < PRT__KIND_COUNT; ++i) prt__gpu_sums_free(s->gpu[i]);
    if (s->lock) { pthread_mutex_destroy(s->lock); free(s->lock); }
    free(s);
}

prt__sh_state *prt__sh_need(prt_context *ctx, const prt_transfer *t)
{
    prt__sh_state *s = prt__sh(t);
    if (!s) prt__fail(ctx, PRT_ERR_INVALID_ARG, "this is %s transfer, not spherical-harmonic transfer", t ? t->method->name : "no");
    return s;
}

int prt__kind_index(prt_transfer_kind kind)
{
    switch (kind) {
    case PRT_TRANSFER_UNSHADOWED: return 0;
    case PRT_TRANSFER_SHADOWED: return 1;
    case PRT_TRANSFER_INTERREFLECTED: return 2;
    case PRT_TRANSFER_GLOSSY_SHADOWED: return 3;
    case PRT_TRANSFER_GLOSSY_INTERREFLECTED: return 4;
    }
    return -1;
}

prt_transfer_kind prt__kind_from_index(int index) { return (prt_transfer_kind)(1u << index); }

const char *prt_transfer_kind_name(prt_transfer_kind kind)
{
    static const char *names[PRT__KIND_COUNT] = {"unshadowed", "shadowed", "interreflected", "glossy-shadowed", "glossy-interreflected"};
    int i = prt__kind_index(kind);
    return i < 0 ? "unknown" : names[i];
}

prt_status prt_transfer_kind_parse(const char *name, prt_transfer_kind *out)
{
    for (int i = 0; i < PRT__KIND_COUNT; ++i) {
        prt_transfer_kind k = prt__kind_from_index(i);
        const char *full = prt_transfer_kind_name(k);
        if (!strcasecmp(name, full) || (i < 3 && name[0] && !name[1] && name[0] == full[0])) { *out = k; return PRT_OK; }
    }
    return prt__fail(NULL, PRT_ERR_INVALID_ARG,
                     "unknown transfer kind '%s' (use unshadowed, shadowed, interreflected, glossy-shadowed or glossy-interreflected)", name);
}

int prt_transfer_kind_is_glossy(prt_transfer_kind kind) { return kind == PRT_TRANSFER_GLOSSY_SHADOWED || kind == PRT_TRANSFER_GLOSSY_INTERREFLECTED; }

prt_transfer_kind prt_transfer_kind_diffuse_part(prt_transfer_kind glossy)
{
    return glossy == PRT_TRANSFER_GLOSSY_INTERREFLECTED ? PRT_TRANSFER_INTERREFLECTED : PRT_TRANSFER_SHADOWED;
}

/* ---- the SH public accessors ---- */
static size_t texel_bytes(const prt__sh_state *s)
{
    const prt__texel_sets *tx = &s->texels;
    if (!tx->width) return 0;
    const size_t ntex = (size_t)tx->width * tx->height;
    size_t bytes = ntex * (3 * sizeof(float) + 1);
    for (int k = 0; k < 3; ++k) {
        const size_t dim = (size_t)tx->channels[k] * s->order * s->order;
        bytes += tx->bytes ? ntex * dim + 8 * dim : ntex * dim * (tx->halves ? 2 : sizeof(float));
    }
    return bytes;
}

void prt_transfer_get_info(const prt_transfer *t, prt_transfer_info *info)
{
    memset(info, 0, sizeof *info);
    info->vertex_count = t->mesh.vertex_count;
    info->triangle_count = t->mesh.triangle_count;
    info->bake_seconds = t->bake_seconds;
    info->threads = t->threads;
    info->transfer_bytes = t->method->transfer_bytes(t);
    snprintf(info->source, sizeof info->source, "%s", t->source);
    const prt__sh_state *s = prt__sh(t);
    if (!s) return;
    info->order = s->order;
    info->samples = s->samples;
    info->bounces = s->bounces;
    info->seed = s->seed;
    for (int i = 0; i < PRT__KIND_COUNT; ++i)
        if (s->sets[i].channels) info->kinds |= prt__kind_from_index(i);
    const prt__texel_sets *tx = &s->texels;
    info->texel_width = tx->width;
    info->texel_height = tx->height;
    info->texel_bytes = texel_bytes(s);
}

int prt_transfer_channels(const prt_transfer *t, prt_transfer_kind kind)
{
    const prt__sh_state *s = prt__sh(t);
    int i = prt__kind_index(kind);
    return !s || i < 0 ? 0 : s->sets[i].channels;
}

const float *prt_transfer_coeffs(const prt_transfer *t, prt_transfer_kind kind)
{
    const prt__sh_state *s = prt__sh(t);
    int i = prt__kind_index(kind);
    return !s || i < 0 || !s->sets[i].channels ? NULL : s->sets[i].coeffs;   /* NULL for compressed sets */
}

size_t prt_transfer_set_floats(const prt_transfer *t, prt_transfer_kind kind)
{
    const prt__sh_state *s = prt__sh(t);
    int i = prt__kind_index(kind);
    return !s || i < 0 ? 0 : prt__set_dim(s, i);
}

int prt_transfer_glossy_mirror(const prt_transfer *t)
{
    const prt__sh_state *s = prt__sh(t);
    return s && !s->glossy_exit;
}

int prt_transfer_texel_size(const prt_transfer *t, int *width, int *height)
{
    const prt__sh_state *s = prt__sh(t);
    if (width) *width = s ? s->texels.width : 0;
    if (height) *height = s ? s->texels.height : 0;
    return s && s->texels.width > 0;
}

const float *prt_transfer_texel_coeffs(const prt_transfer *t, prt_transfer_kind kind, int *channels)
{
    const prt__sh_state *s = prt__sh(t);
    int i = prt__kind_index(kind);
    if (!s || i < 0 || i > 2 || !s->texels.coeffs[i]) return NULL;
    if (channels) *channels = s->texels.channels[i];
    return s->texels.coeffs[i];
}

void prt__texel_sets_free(prt__texel_sets *s)
{
    for (int k = 0; k < 3; ++k) free(s->coeffs[k]);
    free(s->albedo);
    free(s->covered);
    memset(s, 0, sizeof *s);
}

prt_status prt__texel_sets_copy(prt__texel_sets *dst, const prt__texel_sets *src, int order)
{
    memset(dst, 0, sizeof *dst);
    if (!src->width) return PRT_OK;
    const size_t ntex = (size_t)src->width * src->height, nc = (size_t)order * order;
    dst->width = src->width;
    dst->height = src->height;
    dst->halves = src->halves;
    dst->bytes = src->bytes;
    dst->albedo = malloc(ntex * 3 * sizeof(float));
    dst->covered = malloc(ntex);
    bool ok = dst->albedo && dst->covered;
    if (ok) { memcpy(dst->albedo, src->albedo, ntex * 3 * sizeof(float)); memcpy(dst->covered, src->covered, ntex); }
    for (int k = 0; k < 3 && ok; ++k) {
        if (!src->coeffs[k]) continue;
        dst->channels[k] = src->channels[k];
        size_t bytes = ntex * (size_t)src->channels[k] * nc * sizeof(float);
        ok = (dst->coeffs[k] = malloc(bytes)) != NULL;
        if (ok) memcpy(dst->coeffs[k], src->coeffs[k], bytes);
    }
    if (!ok) { prt__texel_sets_free(dst); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory copying texel sets"); }
    return PRT_OK;
}

/* ---- bake options ---- */
static const prt_option_desc options[] = {
    {"order", "N", PRT_OPTION_INT, 1, PRT_SH_MAX_ORDER, NULL, "SH order, bands 1..10 (default 5 = 25 coefficients)"},
    {"samples", "N", PRT_OPTION_INT, 16, 1 << 20, NULL, "directions per vertex over the sphere (default 1024)"},
    {"kinds", "LIST", PRT_OPTION_LIST, 0, 0, "all|unshadowed|shadowed|interreflected|glossy-shadowed|glossy-interreflected|u|s|i",
     "comma list of unshadowed, shadowed, interreflected (u, s, i for short; or 'all': these\n"
     "three, the default) and glossy-shadowed, glossy-interreflected: per-vertex transfer matrices\n"
     "(order^4 floats each; use --order 4 or 5) for view-dependent surfaces"},
    {"bounces", "N", PRT_OPTION_INT, 1, 64, NULL, "interreflection bounces (default 3)"},
    {"seed", "N", PRT_OPTION_INT, 0, 2147483647, NULL, "rotates the low-discrepancy directions (default 0)"},
    {"brdf", "SPEC", PRT_OPTION_TEXT, 0, 0, NULL,
     "bake this BRDF into the glossy sets for every vertex (any isotropic model: lambert,\n"
     "phong, blinn, ashikhmin:N:N, lafortune:clay|skin)"},
    {"bake-materials", NULL, PRT_OPTION_FLAG, 0, 0, NULL,
     "bake each vertex's scene material BRDF into the glossy sets (without this or --brdf,\n"
     "glossy sets hold incident radiance and the lobe is chosen when rendering)"},
    {"texels", "N", PRT_OPTION_INT, 1, 8192, NULL,
     "also bake per-texel transfer (the diffuse kinds) into an N x N map, over the\n"
     "mesh's UVs or a generated atlas (see --uv)"},
    {"uv", "FROM", PRT_OPTION_CHOICE, 0, 0, "auto|mesh|atlas",
     "UV layout of --texels: the mesh's own when unique and inside [0, 1], else a generated\n"
     "atlas (auto, the default); only the mesh's (mesh); always an atlas (atlas)"},
    {"normal-map", "FILE", PRT_OPTION_TEXT, 0, 0, NULL,
     "tangent-space normal map perturbing the per-texel normals (.png/.jpg values as\n"
     "stored; .exr/.hdr/.pfm values in [0, 1])"},
    {"height-map", "FILE", PRT_OPTION_TEXT, 0, 0, NULL,
     "height map (its first channel, white highest) whose bumps shade the per-texel normals\n"
     "and shadow one another; follows the mesh's own texture coordinates"},
    {"bump-height", "H", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "world height of the height map's white (default 1% of the scene's diagonal)"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "shadow-ray origin offset (default 1e-4 x scene diagonal)"},
    {"neighbourhood", "N", PRT_OPTION_INT, 2, 64, NULL,
     "neighbourhood transfer: a grid of N^3 points around the scene holding how it shadows and lights\nwhat moves through it (prt render --probe, the viewer's probe)"},
    {"mm-per-unit", "S", PRT_OPTION_FLOAT, 1e-6, 1e9, NULL,
     "millimetres per scene unit, the scale the scene's translucent materials (\"subsurface\") scatter\nlight at (default 1000: the scene is in metres)"},
    {"compress", "M", PRT_OPTION_CHOICE, 0, 0, "cpca|pca|vq",
     "store the sets compressed: clustered PCA (cpca), one cluster (pca), or clusters only\n"
     "(vq); "
     "relighting reads them directly"},
    {"clusters", "K", PRT_OPTION_INT, 1, 65536, NULL, "clusters for cpca (default 64) and vq (default 256); alone: cpca"},
    {"vectors", "N", PRT_OPTION_INT, 1, 300, NULL, "average PCA vectors per cluster for cpca and pca (default 8); alone: cpca"},
    {"quantize", "B", PRT_OPTION_CHOICE, 0, 0, "8|16|32",
     "store uncompressed per-vertex sets as 8- or 16-bit integers (scale and bias per coefficient) or 32-bit floats (default 16: half the "
     "floats' size, its error some 1e-5 of each coefficient's range, far under a bake's own noise); per-texel sets as 8-bit levels "
     "(scale and bias per coefficient), halves (16) or floats"},
};

/* prt export's options for SH files (export.c). */
static const prt_option_desc export_options[] = {
    {"sh", NULL, PRT_OPTION_FLAG, 0, 0, NULL,
     "glTF only: add the per-vertex SH transfer of the diffuse kind exported as custom attributes _SH0, _SH1, ... (order 3: the "
     "first 9 coefficients of each channel, channel-major, VEC4 float, zero-padded) and, for one-channel kinds, the albedo as _ALBEDO; "
     "COLOR_0 is then relit at order 3 too, so both agree"},
    {"glsl", "FILE", PRT_OPTION_TEXT, 0, 0, NULL, "write the GLSL function prtRadiance() that relights those attributes, with the lighting "
     "exported under as its default (implies --sh)"},
};
static const prt_control_desc controls[] = {
    {"order", "SH order used for lighting (truncates the file's)", '[', ']', 0},
    {"light-window", "window on the SH of point, spot, sphere and directional lights: 0 none, 1 Hanning, 2 Lanczos", '1', '2', 0},
};

/* A map of numbers (normals, heights), not of colours. */
static prt_status load_data_map(prt_context *ctx, const char *what, const char *path, prt_image *out)
{
    prt_status st = prt_image_load(path, out);
    if (st) return prt__fail(ctx, st, "%s: %s", what, prt_last_error());
    /* 8-bit images come back sRGB-decoded; a data map stores plain numbers, so undo it. */
    const char *ext = strrchr(path, '.');
    if (ext && (!strcasecmp(ext, ".png") || !strcasecmp(ext, ".jpg") || !strcasecmp(ext, ".jpeg")))
        for (size_t i = 0; i < (size_t)out->width * out->height * 3; ++i) {
            float x = out->rgb[i];
            out->rgb[i] = x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
        }
    return PRT_OK;
}

/* The kinds --kinds names (0: the default). */
static unsigned option_kinds(const prt_options *o)
{
    unsigned kinds = 0;
    if (!prt__opt(o, "kinds")) return 0;
    char buf[256], *save = NULL;
    snprintf(buf, sizeof buf, "%s", prt__opt(o, "kinds"));
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        prt_transfer_kind k;
        if (!strcmp(tok, "all")) kinds |= 7u;
        else if (!prt_transfer_kind_parse(tok, &k)) kinds |= (unsigned)k;
    }
    return kinds;
}

/* The bake's peak (bake.c's arrays): the sets of every kind, the bounce buffers and the ray hits -
 * by far the most, up to one 20-byte hit per direction over the hemisphere (a closed room has
 * about that many; an open scene fewer), which a streamed bake keeps in a scratch file instead. */
static void sh_memory_estimate(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *e)
{
    const prt_sh_bake_desc def = prt_sh_bake_desc_defaults();
    const uint64_t nv = t->mesh.vertex_count, order = (uint64_t)prt__opt_int(o, "order", def.order), nc = order * order, nn = nc * nc;
    const uint64_t samples = (uint64_t)prt__opt_int(o, "samples", def.samples), texels = (uint64_t)prt__opt_int(o, "texels", 0);
    unsigned kinds = option_kinds(o);
    if (!kinds) kinds = def.kinds;
    bool scene_glossy = false;
    for (size_t v = 0; v < nv && !scene_glossy; ++v) {
        const uint8_t k = t->mesh.material[v];
        scene_glossy = k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1]);
    }
    const bool ir = kinds & (PRT_TRANSFER_INTERREFLECTED | PRT_TRANSFER_GLOSSY_INTERREFLECTED);
    const bool coupled = ir && ((kinds & PRT_TRANSFER_GLOSSY_INTERREFLECTED) || scene_glossy);
    const uint64_t f = sizeof(float);
    uint64_t per_vertex = f;   /* the noise report */
    if (kinds & PRT_TRANSFER_UNSHADOWED) per_vertex += nc * f;
    if ((kinds & PRT_TRANSFER_SHADOWED) || ir) per_vertex += nc * f;
    if ((kinds & PRT_TRANSFER_GLOSSY_SHADOWED) || coupled) per_vertex += nn * f;
    if (coupled) per_vertex += 3 * 3 * nc * f + ((kinds & PRT_TRANSFER_GLOSSY_INTERREFLECTED) ? 4 : 3) * 3 * nn * f;
    else if (kinds & PRT_TRANSFER_INTERREFLECTED) per_vertex += 3 * 3 * nc * f;
    if (prt__opt(o, "compress") || prt__opt(o, "clusters") || prt__opt(o, "vectors")) per_vertex += 2 * 3 * nc * f;   /* the set and its projection */
    const uint64_t fixed = nv * per_vertex + texels * texels * 3 * 3 * nc * f + (uint64_t)threads * samples * (3 * f + sizeof(prt__hit));
    /* Hits: a list per vertex in memory (its allocation's header and pointer beside it), or a
     * place and count per vertex when streamed. */
    const uint64_t hits = ir ? nv * ((samples / 2 + 1) * sizeof(prt__hit) + 16 + 8 + 4) : 0;
    e->bytes = fixed + hits;
    e->least = ir ? fixed + nv * 12 : e->bytes;
    if (ir)
        snprintf(e->what, sizeof e->what, "%.0f MiB of transfer beside up to %.0f MiB of ray hits at %llu directions a vertex, which can stream",
                 (double)fixed / 1048576.0, (double)hits / 1048576.0, (unsigned long long)samples);
    else
        snprintf(e->what, sizeof e->what, "%.0f MiB of transfer", (double)fixed / 1048576.0);
    snprintf(e->lower, sizeof e->lower, "%s", ir ? "--order, fewer --kinds or no --compress" : "--order or fewer --kinds");
}

static prt_status sh_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **out)
{
    prt_sh_bake_desc d = {0};
    prt__sh_extra extra;
    memset(&extra, 0, sizeof extra);
    prt_brdf brdf;
    d.order = prt__opt_int(o, "order", 0);
    d.samples = prt__opt_int(o, "samples", 0);
    d.bounces = prt__opt_int(o, "bounces", 0);
    d.seed = (uint32_t)prt__opt_int(o, "seed", 0);
    d.texels = prt__opt_int(o, "texels", 0);
    d.uv_layout = (prt_uv_layout)prt__opt_choice(o, "uv", PRT_UV_AUTO);
    d.ray_offset = prt__opt_float(o, "ray-offset", 0.0f);
    d.mm_per_unit = prt__opt_float(o, "mm-per-unit", 0.0f);
    d.neighbourhood = prt__opt_int(o, "neighbourhood", 0);
    extra.scene = scene;
    prt_status st = PRT_OK;
    d.kinds = option_kinds(o);
    if (prt__opt(o, "brdf")) {
        if ((st = prt_brdf_parse(prt__opt(o, "brdf"), &brdf))) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf: %s", prt_last_error());
        d.glossy_brdf = &brdf;
        d.glossy_exit = 1;
    }
    if (prt__opt_flag(o, "bake-materials")) d.glossy_exit = 1;
    if (!st && prt__opt(o, "uv") && !d.texels) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "--uv needs --texels N");
    if (!st && prt__opt(o, "normal-map")) {
        if (!d.texels) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "--normal-map needs --texels N");
        else st = load_data_map(ctx, "normal map", prt__opt(o, "normal-map"), &extra.normal_map);
    }
    if (!st && prt__opt(o, "height-map")) {
        if (!d.texels) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "--height-map needs --texels N");
        else st = load_data_map(ctx, "height map", prt__opt(o, "height-map"), &extra.height_map);
    }
    if (!st && prt__opt(o, "bump-height") && !prt__opt(o, "height-map")) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "--bump-height needs --height-map FILE");
    d.height_scale = prt__opt_float(o, "bump-height", 0.0f);
    /* --clusters or --vectors alone ask for clustered PCA. */
    extra.compressing = prt__opt(o, "compress") || prt__opt(o, "clusters") || prt__opt(o, "vectors");
    extra.compress.method = (prt_compress_method)prt__opt_choice(o, "compress", 0);
    extra.compress.clusters = prt__opt_int(o, "clusters", 0);
    extra.compress.vectors = prt__opt_int(o, "vectors", 0);
    extra.compress.seed = d.seed;
    /* 16-bit by default where nothing compresses the sets; 32 keeps the floats. */
    const int bits = prt__opt_int(o, "quantize", extra.compressing ? 32 : 16);
    extra.quantize = bits == 32 ? 0 : bits;
    if (!st && extra.compressing && prt__opt(o, "quantize") && bits != 32)
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "--quantize applies to uncompressed sets; drop --compress or --quantize");
    if (!st && extra.compressing) st = prt__compress_desc_check(ctx, &extra.compress);
    /* A key frame's sets stay floats: the join compresses every frame's rows as one. */
    if (prt__options_keyframe(o)) {
        extra.compressing = false;
        extra.quantize = 0;
        if (!st && d.texels) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frames hold per-vertex transfer: drop --texels");
        if (!st && prt__opt(o, "quantize") && bits != 32)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frames are stored compressed across frames: drop --quantize");
    }
    if (!st) st = prt__sh_bake_begin(ctx, &d, &extra, t, out);
    prt_image_free(&extra.normal_map);   /* empty when the job took them */
    prt_image_free(&extra.height_map);
    return st;
}

/* ---- description ---- */
static size_t grid_bytes(const prt__sh_state *s)
{
    const prt__sh_grid *g = &s->grid;
    return g->matrices ? (size_t)g->dims[0] * g->dims[1] * g->dims[2] * (3 * (size_t)g->order * g->order * g->order * g->order + 1) * sizeof(float) : 0;
}

static size_t sh_bytes(const prt_transfer *t)
{
    const prt__sh_state *s = t->state;
    if (s->frames.count) return prt__sh_frames_bytes(s, t->mesh.vertex_count);
    size_t bytes = 0;
    for (int i = 0; i < PRT__KIND_COUNT; ++i)
        if (s->sets[i].channels) {
            prt_compress_info ci;
            prt_transfer_compress_info(t, prt__kind_from_index(i), &ci);
            bytes += ci.bytes;
        }
    for (int q = 0; q < s->volume_count; ++q) bytes += prt__sh_volume_bytes(&s->volumes[q], s->order);
    return bytes + texel_bytes(s) + grid_bytes(s);
}

/* Share of the texel map's texels holding some of the surface, from the stored mesh's UVs (as
 * the texel bake counts them); negative when it cannot be found. */
static double texel_coverage(const prt_transfer *t, int w, int h)
{
    if (!prt__mesh_has_uv(&t->mesh) || w < 1 || h < 1) return -1;
    float *area = malloc((size_t)w * h * sizeof *area);
    if (!area || !prt__texel_areas(&t->mesh, w, h, area)) { free(area); return -1; }
    size_t on = 0;
    for (size_t i = 0; i < (size_t)w * h; ++i) on += area[i] > 0;
    free(area);
    return (double)on / ((double)w * h);
}

/* What the key frames would take as separate files: each frame's sets at 16 bits (the default)
 * and its mesh positions and normals. */
static size_t separate_frames_bytes(const prt__sh_state *s, size_t nv)
{
    size_t bytes = 0;
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (s->sets[k].channels) bytes += nv * prt__set_dim(s, k) * 2 + 2 * prt__set_dim(s, k) * sizeof(float);
    return (size_t)s->frames.count * (bytes + nv * 3 * sizeof(float) * (s->frames.normals ? 2 : 1));
}

static void sh_describe(const prt_transfer *t, prt__describe *d)
{
    const prt__sh_state *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    bool glossy = s->sets[3].channels || s->sets[4].channels;
    prt_transfer_info info;
    prt_transfer_get_info(t, &info);
    static const char *cnames[3] = {"cpca", "pca", "vq"}, *long_names[3] = {"clustered PCA", "PCA", "VQ"};
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "order", s->order);
        cJSON_AddNumberToObject(j, "coefficients", s->order * s->order);
        cJSON *kinds = cJSON_AddArrayToObject(j, "kinds");
        for (int k = 0; k < PRT__KIND_COUNT; ++k) {
            if (!s->sets[k].channels) continue;
            const prt_transfer_kind kind = prt__kind_from_index(k);
            cJSON *o = cJSON_CreateObject();
            cJSON_AddStringToObject(o, "kind", prt_transfer_kind_name(kind));
            cJSON_AddNumberToObject(o, "channels", s->sets[k].channels);
            cJSON_AddNumberToObject(o, "floats_per_vertex", (double)prt__set_dim(s, k));
            prt_compress_info ci;
            prt_transfer_compress_info(t, kind, &ci);
            cJSON_AddNumberToObject(o, "bytes", (double)ci.bytes);
            if (ci.quantize_bits) cJSON_AddNumberToObject(o, "quantize_bits", ci.quantize_bits);
            if (ci.compressed) {
                cJSON_AddStringToObject(o, "compression", cnames[ci.method]);
                cJSON_AddNumberToObject(o, "clusters", ci.clusters);
                cJSON_AddNumberToObject(o, "pca_vectors", ci.vectors_total);
                cJSON_AddNumberToObject(o, "relative_error", ci.relative_error);
                cJSON_AddNumberToObject(o, "compression_ratio", (double)nv * (double)prt__set_dim(s, k) * 4.0 / (double)ci.bytes);
            }
            cJSON_AddItemToArray(kinds, o);
        }
        if (s->texels.width) {
            cJSON *tx = cJSON_AddObjectToObject(j, "texels");
            cJSON_AddNumberToObject(tx, "width", s->texels.width);
            cJSON_AddNumberToObject(tx, "height", s->texels.height);
            cJSON_AddNumberToObject(tx, "bytes", (double)info.texel_bytes);
            const double cov = texel_coverage(t, s->texels.width, s->texels.height);
            if (cov >= 0) cJSON_AddNumberToObject(j, "atlas_coverage", cov);
            cJSON *tk = cJSON_AddArrayToObject(tx, "kinds");
            for (int k = 0; k < 3; ++k)
                if (s->texels.coeffs[k]) cJSON_AddItemToArray(tk, cJSON_CreateString(prt_transfer_kind_name(prt__kind_from_index(k))));
        }
        if (s->grid.matrices) {
            cJSON *g = cJSON_AddObjectToObject(j, "neighbourhood");
            cJSON *dims = cJSON_AddArrayToObject(g, "points"), *lo = cJSON_AddArrayToObject(g, "from"), *hi = cJSON_AddArrayToObject(g, "to");
            for (int c = 0; c < 3; ++c) {
                cJSON_AddItemToArray(dims, cJSON_CreateNumber(s->grid.dims[c]));
                cJSON_AddItemToArray(lo, cJSON_CreateNumber(s->grid.lo[c]));
                cJSON_AddItemToArray(hi, cJSON_CreateNumber(s->grid.hi[c]));
            }
            cJSON_AddNumberToObject(g, "bytes", (double)grid_bytes(s));
        }
        if (s->volume_count) {
            cJSON *vs = cJSON_AddArrayToObject(j, "volumes");
            for (int q = 0; q < s->volume_count; ++q) {
                const prt__sh_volume *v = &s->volumes[q];
                cJSON *o = cJSON_CreateObject(), *dims = cJSON_AddArrayToObject(o, "voxels"), *lo = cJSON_AddArrayToObject(o, "min"),
                      *hi = cJSON_AddArrayToObject(o, "max"), *al = cJSON_AddArrayToObject(o, "albedo");
                for (int c = 0; c < 3; ++c) {
                    cJSON_AddItemToArray(dims, cJSON_CreateNumber(v->medium.dims[c]));
                    cJSON_AddItemToArray(lo, cJSON_CreateNumber(v->medium.lo[c]));
                    cJSON_AddItemToArray(hi, cJSON_CreateNumber(v->medium.hi[c]));
                    cJSON_AddItemToArray(al, cJSON_CreateNumber(v->medium.albedo[c]));
                }
                cJSON_AddNumberToObject(o, "extinction", v->medium.sigma_t);
                cJSON_AddNumberToObject(o, "g", v->medium.g);
                cJSON_AddNumberToObject(o, "max_density", v->medium.max_density);
                cJSON_AddNumberToObject(o, "bands", v->bands);
                cJSON_AddNumberToObject(o, "orders_of_scattering", v->orders);
                cJSON_AddNumberToObject(o, "bytes", (double)prt__sh_volume_bytes(v, s->order));
                cJSON_AddItemToArray(vs, o);
            }
        }
        if (s->frames.count) {
            cJSON *fr = cJSON_AddObjectToObject(j, "key_frames");
            cJSON_AddNumberToObject(fr, "count", s->frames.count);
            cJSON_AddNumberToObject(fr, "bytes", (double)prt__sh_frames_bytes(s, nv));
            cJSON_AddNumberToObject(fr, "separate_bytes", (double)separate_frames_bytes(s, nv));
            for (int k = 0; k < PRT__KIND_COUNT; ++k)
                if (s->frames.sets[k]) {
                    cJSON *o = cJSON_AddObjectToObject(fr, prt_transfer_kind_name(prt__kind_from_index(k)));
                    cJSON_AddStringToObject(o, "compression", cnames[s->frames.sets[k]->method]);
                    cJSON_AddNumberToObject(o, "clusters", s->frames.sets[k]->clusters);
                    cJSON_AddNumberToObject(o, "pca_vectors", (double)s->frames.sets[k]->vectors_total);
                    cJSON_AddNumberToObject(o, "relative_error", s->frames.sets[k]->relative_error);
                }
        }
        cJSON_AddNumberToObject(j, "samples", s->samples);
        cJSON_AddNumberToObject(j, "bounces", s->bounces);
        cJSON_AddNumberToObject(j, "seed", s->seed);
        if (glossy) cJSON_AddStringToObject(j, "glossy", s->glossy_exit ? "exit radiance (BRDF baked in)" : "incident radiance (lobe at render time)");
        return;
    }
    prt__describe_line(d, "order:", "%d (%d coefficients)", s->order, s->order * s->order);
    char kinds[512] = "";
    size_t at = 0;
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (s->sets[k].channels && at < sizeof kinds)
            at += (size_t)snprintf(kinds + at, sizeof kinds - at, "%s%s (%d ch)", at ? " " : "", prt_transfer_kind_name(prt__kind_from_index(k)),
                                   s->sets[k].channels);
    prt__describe_line(d, "kinds:", "%s", kinds);
    if (glossy)
        prt__describe_line(d, "glossy:", "%s", s->glossy_exit ? "transfer matrices to exit radiance (BRDF baked in)"
                                                              : "transfer matrices to incident radiance; the lobe is applied when rendering");
    for (int k = 1; k <= t->brdf_count; ++k) {
        char spec[128], label[32];
        prt_brdf_format(&t->brdfs[k - 1], spec, sizeof spec);
        snprintf(label, sizeof label, "material %d:", k);
        prt__describe_line(d, label, "%s", spec);
    }
    for (int k = 0; k < PRT__KIND_COUNT; ++k) {
        prt_compress_info ci;
        const prt_transfer_kind kind = prt__kind_from_index(k);
        if (!s->sets[k].channels || prt_transfer_compress_info(t, kind, &ci)) continue;
        if (ci.quantize_bits) prt__describe_line(d, "quantized:", "%s %d-bit", prt_transfer_kind_name(kind), ci.quantize_bits);
        if (!ci.compressed) continue;
        double raw = (double)nv * (double)prt__set_dim(s, k) * 4.0;
        prt__describe_line(d, "compressed:", "%s %s, %d clusters, %d PCA vectors, %.1f bytes/vertex (%.1fx smaller), relative error %.4f",
                           prt_transfer_kind_name(kind), long_names[ci.method], ci.clusters, ci.vectors_total, (double)ci.bytes / (double)nv,
                           raw / (double)ci.bytes, ci.relative_error);
    }
    if (s->texels.width) {
        char tk[128] = "";
        size_t n = 0;
        for (int k = 0; k < 3; ++k)
            if (s->texels.coeffs[k]) n += (size_t)snprintf(tk + n, sizeof tk - n, "%s%s", n ? ", " : "", prt_transfer_kind_name(prt__kind_from_index(k)));
        const double cov = texel_coverage(t, s->texels.width, s->texels.height);
        char on[64] = "";
        if (cov >= 0) snprintf(on, sizeof on, ", atlas coverage %.0f%%", 100 * cov);
        prt__describe_line(d, "texels:", "%d x %d (%s%s), %.2f MiB%s", s->texels.width, s->texels.height, tk, on, info.texel_bytes / 1048576.0,
                           s->texels.bytes ? " (8-bit)" : s->texels.halves ? " (halves)" : "");
    }
    if (s->grid.matrices)
        prt__describe_line(d, "neighbourhood:", "%d x %d x %d points from (%g, %g, %g) to (%g, %g, %g), %.2f MiB (prt render --probe)", s->grid.dims[0],
                           s->grid.dims[1], s->grid.dims[2], s->grid.lo[0], s->grid.lo[1], s->grid.lo[2], s->grid.hi[0], s->grid.hi[1], s->grid.hi[2],
                           grid_bytes(s) / 1048576.0);
    for (int q = 0; q < s->volume_count; ++q) {
        const prt__sh_volume *v = &s->volumes[q];
        prt__describe_line(d, q ? "" : "volumes:", "%d x %d x %d voxels from (%g, %g, %g) to (%g, %g, %g): extinction %g x density (up to %g), albedo (%g, %g, %g), "
                           "g %g; arriving light kept in %s, %d orders of scattering; %.2f MiB", v->medium.dims[0], v->medium.dims[1], v->medium.dims[2],
                           v->medium.lo[0], v->medium.lo[1], v->medium.lo[2], v->medium.hi[0], v->medium.hi[1], v->medium.hi[2], v->medium.sigma_t,
                           v->medium.max_density, v->medium.albedo[0], v->medium.albedo[1], v->medium.albedo[2], v->medium.g,
                           v->bands == 2 ? "SH bands 0-1 (HG)" : "band 0 (isotropic)", v->orders,
                           prt__sh_volume_bytes(v, s->order) / 1048576.0);
    }
    if (s->frames.count) {
        const double held = (double)prt__sh_frames_bytes(s, nv), apart = (double)separate_frames_bytes(s, nv);
        const bool mib = apart >= 1048576.0;
        prt__describe_line(d, "key frames:", "%d (times 0 to %d), %.2f %s with their poses, against %.2f %s as %d separate files' 16-bit sets",
                           s->frames.count, s->frames.count - 1, held / (mib ? 1048576.0 : 1024.0), mib ? "MiB" : "KiB",
                           apart / (mib ? 1048576.0 : 1024.0), mib ? "MiB" : "KiB", s->frames.count);
        for (int k = 0; k < PRT__KIND_COUNT; ++k) {
            const prt__cpca *c = s->frames.sets[k];
            if (c)
                prt__describe_line(d, "", "%s: one %s over every frame's rows, %d clusters, %zu PCA vectors, relative error %.4f",
                                   prt_transfer_kind_name(prt__kind_from_index(k)), long_names[c->method], c->clusters, c->vectors_total, c->relative_error);
        }
    }
    prt__describe_line(d, "bake:", "%d samples, %d bounces, seed %u", s->samples, s->bounces, s->seed);
}

/* ---- variants and controls ---- */
static int sh_variant_count(const prt_transfer *t)
{
    const prt__sh_state *s = t->state;
    int n = 0;
    for (int k = 0; k < PRT__KIND_COUNT; ++k) n += s->sets[k].channels != 0;
    return n;
}

/* The set index of variant i. */
static int set_of_variant(const prt__sh_state *s, int i)
{
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (s->sets[k].channels && i-- == 0) return k;
    return -1;
}

static int variant_of_set(const prt__sh_state *s, int k)
{
    if (k < 0 || !s->sets[k].channels) return -1;
    int i = 0;
    for (int j = 0; j < k; ++j) i += s->sets[j].channels != 0;
    return i;
}

static const char *sh_variant_name(const prt_transfer *t, int i) { return prt_transfer_kind_name(prt__kind_from_index(set_of_variant(t->state, i))); }

static int sh_default_variant(const prt_transfer *t, int drawing)
{
    const prt__sh_state *s = t->state;
    static const int draw_order[] = {4, 3, 2, 1, 0}, plain_order[] = {2, 1, 0, 4, 3};
    const int *order = drawing ? draw_order : plain_order;
    for (int i = 0; i < PRT__KIND_COUNT; ++i)
        if (s->sets[order[i]].channels) return variant_of_set(s, order[i]);
    return 0;
}

static int sh_find_variant(const prt_transfer *t, const char *name)
{
    prt_transfer_kind k;
    if (prt_transfer_kind_parse(name, &k)) return -1;
    return variant_of_set(t->state, prt__kind_index(k));
}

static void sh_control_range(const prt_transfer *t, int i, int *lo, int *hi, int *def)
{
    const prt__sh_state *s = t->state;
    if (i == 1) {
        *lo = 0;
        *hi = PRT__SH_WINDOW_COUNT - 1;
        *def = PRT__SH_LIGHT_WINDOW_DEFAULT;
        return;
    }
    *lo = 1;
    *hi = s->order;
    *def = s->order;
}

/* ---- relighting ---- */
static prt_status project(prt_context *ctx, const prt_lighting *l, int order, prt_sh_light *out)
{
    const prt_status st = prt_lighting_sh(l, order, out);
    return st ? prt__fail(ctx, st, "%s", prt_last_error()) : PRT_OK;
}

/* local: the positioned lights' SH per vertex at sh's order, or NULL. */
static prt_status relight_kind(prt_context *ctx, const prt_transfer *t, int k, const prt_sh_light *sh, const float *local, const prt_relight_desc *d,
                               float *rgb, float *exit)
{
    const prt_transfer_kind kind = prt__kind_from_index(k);
    prt_status st = PRT_OK;
    if (!prt__kind_glossy(k)) {
        st = prt_relight_sh(ctx, t, kind, sh, rgb);
        return st || !local ? st : prt__relight_sh_local(ctx, t, k, local, sh->order, rgb);
    }
    const prt_transfer_kind diffuse = prt_transfer_kind_diffuse_part(kind);
    if (prt_transfer_channels(t, diffuse)) {
        st = prt_relight_sh(ctx, t, diffuse, sh, rgb);
        if (!st && local) st = prt__relight_sh_local(ctx, t, prt__kind_index(diffuse), local, sh->order, rgb);
    } else {
        memset(rgb, 0, t->mesh.vertex_count * 3 * sizeof(float));
    }
    if (!st) st = prt__relight_sh_glossy(ctx, t, kind, sh, d->brdf, d->brdf_everywhere, local, sh->order, exit);
    return st;
}

static prt_status relight_with(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, const prt__sh_state *s, int k,
                               const prt_sh_light *shl, const float *local, int window, prt_relit *r);

static prt_status sh_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    const prt__sh_state *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    int k = set_of_variant(s, d->variant);
    const int order = d->controls && d->controls[0] >= 1 && d->controls[0] < s->order ? d->controls[0] : s->order;
    /* A run-time lobe shapes glossy kinds only; the diffuse kinds drawn beside them ignore it, and
     * a file with none has nothing it could shape. */
    if (d->brdf && !s->sets[3].channels && !s->sets[4].channels)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a run-time BRDF (--brdf) shapes glossy SH sets baked without a BRDF, and this file holds none "
                         "(prt info lists what it holds)");
    if (d->brdf && prt__kind_glossy(k) && s->glossy_exit)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "this transfer has its BRDF baked in; a run-time BRDF cannot replace it (re-bake without --brdf)");
    const int window = d->controls ? d->controls[1] : PRT__SH_LIGHT_WINDOW_DEFAULT;
    if (window < 0 || window >= PRT__SH_WINDOW_COUNT)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "light-window %d: use 0 (none), 1 (Hanning) or 2 (Lanczos)", window);
    prt_sh_light sh;
    prt_status st = project(ctx, l, s->order, &sh);
    if (st) return st;
    sh.order = order;
    prt__sh_window_directional(l, window, &sh);
    /* Point, spot, ies and sphere lights: their SH at every vertex (local.c). */
    float *local = NULL;
    if (prt__sh_local_count(l)) {
        uint8_t *unreachable = malloc((size_t)prt_lighting_count(l) + 1);
        prt_lighting *reach = NULL;
        if (!unreachable) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        st = prt__sh_local_reach(ctx, t, l, d->leave_out_unreachable, unreachable);
        if (!st) st = prt_lighting_copy(l, &reach);
        for (int i = prt_lighting_count(l) - 1; !st && i >= 0; --i)
            if (unreachable[i]) st = prt_lighting_remove(reach, i);
        free(unreachable);
        if (!st && !(local = malloc(nv * 3 * (size_t)order * order * sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st) prt__sh_local_project(ctx, reach, order, window, t->mesh.positions, nv, local);
        if (!st) st = relight_with(ctx, t, reach, d, s, k, &sh, local, window, r);   /* per texel too, without what was left out */
        prt_lighting_release(reach);
        free(local);
        return st;
    }
    return relight_with(ctx, t, l, d, s, k, &sh, NULL, window, r);
}

/* Volumes: the light their media scatter, for the renderer's ray march and the viewer's slices
 * (distant light only), whichever path summed the surfaces. */
static prt_status relight_volumes(prt_context *ctx, const prt__sh_state *s, const prt_sh_light *shl, prt_relit *r)
{
    if (s->volume_count && !(r->volumes = prt__calloc((size_t)s->volume_count, sizeof *r->volumes))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int q = 0; q < s->volume_count; ++q) {
        const prt__sh_volume *v = &s->volumes[q];
        const size_t voxels = prt__volume_voxels(&v->medium);
        prt_render_volume *rv = &r->volumes[q];
        float *ext = malloc(voxels * sizeof *ext), *src = malloc(voxels * 3 * (size_t)v->bands * v->bands * sizeof *src);
        rv->extinction = ext;
        rv->source = src;
        r->volume_count = q + 1;
        if (!ext || !src) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(rv->dims, v->medium.dims, sizeof rv->dims);
        memcpy(rv->lo, v->medium.lo, sizeof rv->lo);
        memcpy(rv->hi, v->medium.hi, sizeof rv->hi);
        rv->source_order = v->bands;
        for (size_t i = 0; i < voxels; ++i) ext[i] = v->medium.sigma_t * v->medium.density[i];
        prt__sh_volume_source(v, s->order, shl, src);
    }
    return PRT_OK;
}

static prt_status relight_with(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, const prt__sh_state *s, int k,
                               const prt_sh_light *shl, const float *local, int window, prt_relit *r)
{
    const size_t nv = t->mesh.vertex_count;
    const int order = shl->order;
    prt_status st;
    /* Direct light is the shadowed pair; indirect the inter-reflected pair minus it. */
    const bool split_ok = s->sets[1].channels && s->sets[2].channels && (!prt__kind_glossy(k) || (s->sets[3].channels && s->sets[4].channels));
    if (d->component && !split_ok)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "separating direct and indirect light needs shadowed and inter-reflected sets%s",
                         prt__kind_glossy(k) ? " (diffuse and glossy)" : "");
    if (d->component == PRT_COMPONENT_DIRECT) k = prt__kind_glossy(k) ? 3 : 1;
    else if (d->component == PRT_COMPONENT_INDIRECT) k = prt__kind_glossy(k) ? 4 : 2;
    /* Light from distant lighting, drawn per vertex: the GPU sums it (gpu.c). Local lights
     * (lighting per vertex), compressed glossy sets, per-texel maps and the indirect part (a
     * difference of two sets) stay here. */
    if (d->gpu_finish && !local && !d->with_indirect && d->component != PRT_COMPONENT_INDIRECT && prt__sh_gpu_can(s, k, d) &&
        !(!d->per_vertex && d->component == PRT_COMPONENT_ALL && k <= 2 && s->texels.coeffs[k]))
        return (st = prt__sh_gpu_relight(ctx, t, k, shl, r)) ? st : relight_volumes(ctx, s, shl, r);
    const bool want_indirect = (d->with_indirect || d->component == PRT_COMPONENT_INDIRECT) && split_ok && (k == 2 || k == 4);
    if ((st = prt__relit_alloc(ctx, t, r, want_indirect))) return st;
    const size_t exit_floats = 3 * (size_t)s->order * s->order;
    if (prt__kind_glossy(k)) {
        r->exit_sh = prt__calloc(nv * exit_floats, sizeof(float));
        if (!r->exit_sh) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        r->exit_order = s->order;
        r->exit_mirror = !s->glossy_exit;
    }
    if ((st = relight_kind(ctx, t, k, shl, local, d, r->radiance, r->exit_sh))) return st;
    if (want_indirect) {
        /* The part that bounced: this kind minus its shadowed counterpart. */
        const int direct = k == 4 ? 3 : 1;
        float *dexit = direct == 3 ? prt__calloc(nv * exit_floats, sizeof(float)) : NULL;
        if (direct == 3 && !dexit) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        st = relight_kind(ctx, t, direct, shl, local, d, r->indirect, dexit);
        for (size_t i = 0; !st && i < nv * 3; ++i) r->indirect[i] = r->radiance[i] - r->indirect[i];
        if (!st && d->component == PRT_COMPONENT_INDIRECT) {
            memcpy(r->radiance, r->indirect, nv * 3 * sizeof(float));
            for (size_t i = 0; dexit && i < nv * exit_floats; ++i) r->exit_sh[i] -= dexit[i];
        }
        free(dexit);
        if (st) return st;
        if (!d->with_indirect) { free(r->indirect); r->indirect = NULL; }
    }
    if (!d->per_vertex && d->component == PRT_COMPONENT_ALL && k <= 2 && s->texels.coeffs[k]) {
        r->texel_width = s->texels.width;
        r->texel_height = s->texels.height;
        r->texels = prt__calloc((size_t)r->texel_width * r->texel_height * 3, sizeof(float));
        if (!r->texels) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if ((st = prt_relight_sh_texels(ctx, t, prt__kind_from_index(k), shl, r->texels))) return st;
        if (local && (st = prt__relight_sh_texels_local(ctx, t, k, l, order, window, r->texels))) return st;
    }
    return relight_volumes(ctx, s, shl, r);
}

const prt__method prt__method_sh = {
    .name = "sh",
    .title = "spherical-harmonic PRT",
    .summary = "spherical-harmonic PRT (Sloan et al.): diffuse and glossy, per vertex or texel, compressible",
    .lighting = PRT_LIGHTS_ENVIRONMENT | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_SPHERE | PRT_LIGHTS_IES,
    .light_map_option = "texels",
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .export_options = export_options,
    .export_option_count = (int)(sizeof export_options / sizeof export_options[0]),
    .export_files = prt__sh_export,
    .web = prt__sh_web,
    .bake_begin = sh_bake_begin,
    .memory_estimate = sh_memory_estimate,
    .free_state = prt__sh_state_free,
    .save_meta = prt__sh_save_meta,
    .save = prt__sh_save,
    .load = prt__sh_load,
    .describe = sh_describe,
    .transfer_bytes = sh_bytes,
    .variant_count = sh_variant_count,
    .variant_name = sh_variant_name,
    .default_variant = sh_default_variant,
    .find_variant = sh_find_variant,
    .control_range = sh_control_range,
    .gpu_passes = true,
    .relight = sh_relight,
    .light_at_box = prt__sh_light_at_box,
    .light_at = prt__sh_light_at_lighting,
    .join_frames = prt__sh_join_frames,
    .frame_count = prt__sh_frame_count,
    .at_time = prt__sh_at_time,
};
