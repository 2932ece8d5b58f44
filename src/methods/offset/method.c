/* The offset method's table entry (offset radiance transfer mapping, Sunshine-Hill & Faloutsos
 * 2006): bake options, its chunks (OFSP parameters and offsets, OFST texel patches, OFSR and OFSS
 * maps), description, the bounce control and relighting. The offsets and maps are made in
 * bake.c (with sampling.c and transfer.c), the run time is
 * relight.c. */
#include "methods/offset/offset.h"

#define CHUNK_OFSP PRT__FOURCC('O', 'F', 'S', 'P')
#define CHUNK_OFST PRT__FOURCC('O', 'F', 'S', 'T')
#define CHUNK_OFSR PRT__FOURCC('O', 'F', 'S', 'R')
#define CHUNK_OFSS PRT__FOURCC('O', 'F', 'S', 'S')
#define CHUNK_OFSD PRT__FOURCC('O', 'F', 'S', 'D')
#define OFSP_HEADER 72
#define TEXEL_FLOATS (3 + 3 + 3 + 1 + PRT__OFFSET_ENV_COEFFS)   /* pos, nrm, albedo, area, env */

void prt__offset_set_free(void *state)
{
    prt__offset_set *s = state;
    if (!s) return;
    free(s->offsets); free(s->texel); free(s->pos); free(s->nrm); free(s->albedo); free(s->area); free(s->emit); free(s->emit_in); free(s->env);
    free(s->radiosity); free(s->subsurface); free(s->index); free(s->source); free(s->xy); free(s->media); free(s->medium);
    if (s->lights) { prt__vertex_lights_free(s->lights); free(s->lights); }
    free(s->sample_pos);
    free(s->sample_nrm);
    free(s->passes);
    free(s->slices[0]);
    free(s->slices[1]);
    if (s->lock) { pthread_mutex_destroy(s->lock); free(s->lock); }
    free(s);
}

bool prt__offset_cache_new(prt__offset_set *s)
{
    pthread_mutex_t *lock = malloc(sizeof *lock);
    prt__vertex_lights *lights = prt__calloc(1, sizeof *lights);
    if (!lock || !lights) { free(lock); free(lights); return false; }   /* free_state then finds neither */
    pthread_mutex_init(lock, NULL);
    prt__vertex_lights_init(lights);
    s->lock = lock;
    s->lights = lights;
    return true;
}

/* ---- bake options ---- */
static const prt_option_desc options[] = {
    {"texels", "N", PRT_OPTION_INT, 8, 4096, NULL,
     "light map of N x N texels over the mesh's UVs, or a generated atlas (see --uv) (default 128)"},
    {"offsets", "N", PRT_OPTION_INT, 1, 100000, NULL, "transfer maps, one per offset (default 200; the paper uses 50..400)"},
    {"iterations", "N", PRT_OPTION_INT, 0, 1000000, NULL,
     "refinements of the importance distribution the offsets are drawn from, rebuilt every 20 (default 1000)"},
    {"importance", "H", PRT_OPTION_CHOICE, 0, 0, "max|mean",
     "what weighs an offset: the largest transfer it carries to any texel (max, the default: distant objects keep their "
     "offsets) or the mean (fewer artefacts on one smooth chart)"},
    {"transfer", "K", PRT_OPTION_CHOICE, 0, 0, "auto|radiosity|subsurface|both",
     "radiosity: diffuse inter-reflection (see --map-bounces); subsurface: Jensen's dipole in place of diffuse reflection "
     "on the scene's translucent materials (a JSON material's \"subsurface\"), or on every surface of a scene that names "
     "none; both; auto (the default): radiosity, and subsurface where the scene names a medium"},
    {"medium", "M", PRT_OPTION_CHOICE, 0, 0, "skin|marble|ketchup",
     "measured coefficients of subsurface scattering for a scene that names no medium (Jensen et al. 2001; default skin)"},
    {"sigma-a", "R,G,B", PRT_OPTION_TEXT, 0, 0, NULL, "absorption per mm, instead of the medium's"},
    {"sigma-s", "R,G,B", PRT_OPTION_TEXT, 0, 0, NULL, "reduced scattering per mm, instead of the medium's"},
    {"eta", "N", PRT_OPTION_FLOAT, 1, 4, NULL, "relative index of refraction of the medium (default 1.3)"},
    {"mm-per-unit", "S", PRT_OPTION_FLOAT, 1e-6, 1e9, NULL,
     "millimetres per scene unit, the scale subsurface scattering needs (default 1000: the scene is in metres)"},
    {"uv", "FROM", PRT_OPTION_CHOICE, 0, 0, "auto|mesh|atlas",
     "UV layout: the mesh's own when unique and inside [0, 1], else a generated atlas (auto, the default); only the "
     "mesh's (mesh); always an atlas (atlas)"},
    {"map-bounces", "N", PRT_OPTION_INT, 1, 16, NULL,
     "bounces the radiosity maps hold: 2..16 (default 8) bake them all into the maps, as the paper, and one pass at "
     "run time gives them (the bounces past the first from paths traced from every texel: --walks); 1 bakes one "
     "and the run time repeats the pass per bounce (--control bounces)"},
    {"walks", "N", PRT_OPTION_INT, 16, 65536, NULL, "paths per texel for the bounces past the first of --map-bounces (default 256)"},
    {"seed", "N", PRT_OPTION_INT, 0, 2147483647, NULL, "seed of the offsets drawn and the paths traced (default 0)"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "shadow-ray origin offset (default 1e-4 x scene diagonal)"},
};

/* prt export's options for offset files (export.c). */
static const prt_option_desc export_options[] = {
    {"maps", "DIR", PRT_OPTION_TEXT, 0, 0, NULL,
     "each transfer map as an OpenEXR file cropped to its non-zero box, the surface and medium masks, and DIR/index.json naming "
     "kind, offset and box (with or without -o); replaces what an earlier export left in DIR"},
};
static const prt_control_desc controls[] = {
    {"bounces", "inter-reflection passes over the light map (radiosity; 0 = first-order and subsurface only)", '[', ']', 0},
};

static bool parse_rgb(const char *text, float out[3])
{
    char *end;
    for (int c = 0; c < 3; ++c) {
        out[c] = strtof(text, &end);
        if (end == text || !(out[c] >= 0) || !isfinite(out[c])) return false;
        text = end;
        if (c < 2) {
            if (*text != ',') { out[1] = out[2] = out[0]; return *text == 0 && c == 0; }
            text++;
        }
    }
    return *text == 0;
}

static prt_status offset_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    prt__offset_bake_desc d = {0};
    d.texels = prt__opt_int(o, "texels", 128);
    d.count = prt__opt_int(o, "offsets", 200);
    d.iterations = prt__opt_int(o, "iterations", 1000);
    d.importance = prt__opt_choice(o, "importance", 0);
    const int kind = prt__opt_choice(o, "transfer", 0);
    if (prt__opt(o, "sigma-a") && (!parse_rgb(prt__opt(o, "sigma-a"), d.sigma_a) || !(d.sigma_a[0] > 0 && d.sigma_a[1] > 0 && d.sigma_a[2] > 0)))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--sigma-a takes R,G,B (or one value), each > 0 per mm");
    if (prt__opt(o, "sigma-s") && !parse_rgb(prt__opt(o, "sigma-s"), d.sigma_s))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--sigma-s takes R,G,B (or one value), each >= 0 per mm");

    static const char *const medium_names[3] = {"skin", "marble", "ketchup"};
    prt_medium preset;
    if (prt_medium_preset(medium_names[prt__opt_choice(o, "medium", 0)], &preset)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s", prt_last_error());
    for (int c = 0; c < 3; ++c) { d.sigma_s[c] = preset.sigma_s[c]; d.sigma_a[c] = preset.sigma_a[c]; }
    /* The scene's translucent materials, by the transfer mesh's surface ids. */
    const prt__mesh *tm = &t->mesh;
    uint8_t *surface_medium = prt__calloc((size_t)tm->surface_count + 1, 1);
    prt_medium named[PRT__OFFSET_MAX_MEDIA];
    int nnamed = 0;
    if (!surface_medium) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int k = 0; k < tm->surface_count; ++k) {
        prt_medium m;
        if (!prt_scene_medium(scene, tm->surface_names[k], &m)) continue;
        if (nnamed == PRT__OFFSET_MAX_MEDIA) { free(surface_medium); return prt__fail(ctx, PRT_ERR_INVALID_ARG, "more than %d translucent materials", PRT__OFFSET_MAX_MEDIA); }
        named[nnamed++] = m;
        surface_medium[k + 1] = (uint8_t)nnamed;
    }
    d.kinds = kind == 1 ? PRT__OFFSET_RADIOSITY_BIT : kind == 2 ? PRT__OFFSET_SUBSURFACE_BIT : kind == 3 ? PRT__OFFSET_RADIOSITY_BIT | PRT__OFFSET_SUBSURFACE_BIT
            : PRT__OFFSET_RADIOSITY_BIT | (nnamed ? PRT__OFFSET_SUBSURFACE_BIT : 0u);
    if (nnamed) { d.surface_medium = surface_medium; d.medium_count = nnamed; d.media = named; }
    /* The medium options describe the one medium of a scene that names none: refused, not
     * ignored, where they would not apply. */
    const char *medium_opts[4] = {"medium", "sigma-a", "sigma-s", "eta"};
    for (int i = 0; i < 4; ++i) {
        if (!prt__opt(o, medium_opts[i])) continue;
        const char *why = !(d.kinds & PRT__OFFSET_SUBSURFACE_BIT) ? "without subsurface transfer (--transfer subsurface or both)"
                          : nnamed ? "when the scene names its translucent materials (their \"subsurface\" sets the medium)" : NULL;
        if (why) { free(surface_medium); return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--%s does not apply %s", medium_opts[i], why); }
    }
    d.eta = prt__opt_float(o, "eta", 1.3f);
    d.mm_per_unit = prt__opt_float(o, "mm-per-unit", 1000.0f);
    d.uv_layout = (prt_uv_layout)prt__opt_choice(o, "uv", 0);
    d.seed = prt__opt_int(o, "seed", 0);
    d.map_bounces = prt__opt_int(o, "map-bounces", (kind == 2) ? 1 : 8);
    d.walks = prt__opt_int(o, "walks", 256);
    if ((prt__opt(o, "map-bounces") || prt__opt(o, "walks")) && !(d.kinds & PRT__OFFSET_RADIOSITY_BIT)) {
        free(surface_medium);
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--%s does not apply without radiosity transfer", prt__opt(o, "map-bounces") ? "map-bounces" : "walks");
    }
    if (prt__opt(o, "walks") && d.map_bounces < 2) { free(surface_medium); return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--walks applies to --map-bounces 2 and more"); }
    d.ray_offset = prt__opt_float(o, "ray-offset", 0.0f);
    const prt_status st = prt__offset_bake_begin(ctx, &d, t, job);
    free(surface_medium);
    return st;
}

/* ---- files ---- */
static prt_status offset_save(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__offset_set *s = t->state;
    const size_t nc = s->covered;
    unsigned char *head = prt__chunks_alloc(l, OFSP_HEADER);
    float *texels = prt__chunks_alloc(l, nc * TEXEL_FLOATS * sizeof(float));
    if (!head || !texels) return PRT_OK;   /* the list records the failure */
    const uint32_t p32[8] = {(uint32_t)s->width, (uint32_t)s->height, (uint32_t)s->count, s->kinds, (uint32_t)s->iterations,
                             (uint32_t)s->importance, s->covered, s->emit != NULL};
    for (int i = 0; i < 8; ++i) prt__put32(head + 4 * i, p32[i]);
    const float f[10] = {s->ray_offset, s->eta, s->mm_per_unit, s->sigma_a[0], s->sigma_a[1], s->sigma_a[2], s->sigma_s[0], s->sigma_s[1], s->sigma_s[2],
                         s->map_bounces > 1 ? (float)s->map_bounces : 0.0f};
    memcpy(head + 32, f, sizeof f);
    prt__chunks_add(l, CHUNK_OFSP, head, (size_t)OFSP_HEADER, s->offsets, (size_t)s->count * 2 * sizeof(int32_t), NULL);
    for (size_t i = 0; i < nc; ++i) {
        float *e = texels + i * TEXEL_FLOATS;
        memcpy(e, s->pos + i * 3, 12);
        memcpy(e + 3, s->nrm + i * 3, 12);
        memcpy(e + 6, s->albedo + i * 3, 12);
        e[9] = s->area[i];
        memcpy(e + 10, s->env + i * PRT__OFFSET_ENV_COEFFS, PRT__OFFSET_ENV_COEFFS * sizeof(float));
    }
    prt__chunks_add(l, CHUNK_OFST, s->texel, nc * sizeof(uint32_t), texels, nc * TEXEL_FLOATS * sizeof(float), s->emit, s->emit ? nc * 3 * sizeof(float) : 0,
                    s->emit_in, s->emit ? nc * 3 * sizeof(float) : 0, NULL);
    const size_t maps = (size_t)s->count * nc * 3 * sizeof(float);
    if (s->radiosity) prt__chunks_add(l, CHUNK_OFSR, s->radiosity, maps, NULL);
    if (s->subsurface) {
        /* The media: count, 7 floats each, then each texel's (padded to 4 bytes). */
        static const unsigned char zero4[4] = {0};
        unsigned char *head = prt__chunks_alloc(l, 4);
        if (!head) return PRT_OK;
        prt__put32(head, (uint32_t)s->medium_count);
        prt__chunks_add(l, CHUNK_OFSS, s->subsurface, maps, NULL);
        prt__chunks_add(l, CHUNK_OFSD, head, (size_t)4, s->media, (size_t)s->medium_count * sizeof(prt_medium), s->medium, nc, zero4,
                        ((nc + 3) & ~(size_t)3) - nc, NULL);
    }
    return PRT_OK;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %s", msg); }

/* A texel gathers at most all it sees (radiosity: its albedo) or all it scatters (subsurface:
 * under 1), as the bake caps them; a file with more would make light grow bounce by bounce. */
static prt_status load_maps(prt_context *ctx, const prt__offset_set *s, const prt__chunk_in *c, bool radiosity, float **out)
{
    const uint64_t n = (uint64_t)s->count * s->covered * 3;
    if (c->size != n * sizeof(float)) return bad(ctx, "offset transfer map chunk size mismatch");
    if (!(*out = malloc(n * sizeof(float) + 1))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(*out, c->data, n * sizeof(float));
    for (uint64_t i = 0; i < n; ++i)
        if (!((*out)[i] >= 0 && (*out)[i] <= 1e30f)) return bad(ctx, "offset transfer map values out of range");
    /* Multi-bounce maps: bounce k adds at most the texel's albedo times the brightest albedo to the
     * power k - 1. */
    double series[3] = {1, 1, 1};
    if (radiosity && s->map_bounces > 1) {
        double top[3] = {0, 0, 0};
        for (size_t i = 0; i < s->covered; ++i)
            for (int ch = 0; ch < 3; ++ch) top[ch] = fmax(top[ch], s->albedo[i * 3 + ch]);
        for (int ch = 0; ch < 3; ++ch) {
            double power = 1;
            for (int k = 1; k < s->map_bounces; ++k) { power *= top[ch]; series[ch] += power; }
        }
    }
    for (size_t i = 0; i < s->covered; ++i)
        for (int ch = 0; ch < 3; ++ch) {
            double sum = 0;
            for (int k = 0; k < s->count; ++k) sum += (*out)[((size_t)k * s->covered + i) * 3 + ch];
            const double bound = radiosity ? s->albedo[i * 3 + ch] * series[ch] : 1.0;
            if (!(sum <= bound * 1.001 + 1e-6)) return bad(ctx, "an offset texel gathers more light than it can");
        }
    return PRT_OK;
}

static prt_status offset_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    (void)meta;
    prt__offset_set *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = s;
    if (!prt__offset_cache_new(s)) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!prt__mesh_has_uv(&t->mesh)) return bad(ctx, "an offset file's mesh has no texture coordinates for its light map");
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_OFSP);
    if (!c || c->size < OFSP_HEADER) return bad(ctx, "offset parameter chunk missing or short");
    const unsigned char *p = c->data;
    s->width = (int)prt__get32(p);
    s->height = (int)prt__get32(p + 4);
    s->count = (int)prt__get32(p + 8);
    s->kinds = prt__get32(p + 12);
    s->iterations = (int)prt__get32(p + 16);
    s->importance = (int)prt__get32(p + 20);
    s->covered = prt__get32(p + 24);
    const uint32_t emits = prt__get32(p + 28);
    float f[10];
    memcpy(f, p + 32, sizeof f);
    s->ray_offset = f[0]; s->eta = f[1]; s->mm_per_unit = f[2];
    for (int k = 0; k < 3; ++k) { s->sigma_a[k] = f[3 + k]; s->sigma_s[k] = f[6 + k]; }
    /* Files of maps holding one bounce wrote 0 here. */
    if (!(f[9] == 0 || (f[9] >= 2 && f[9] <= 16 && f[9] == floorf(f[9])))) return bad(ctx, "offset map bounces out of range");
    s->map_bounces = f[9] >= 2 ? (int)f[9] : 1;
    if (s->map_bounces > 1 && !(s->kinds & PRT__OFFSET_RADIOSITY_BIT)) return bad(ctx, "offset map bounces without radiosity maps");
    const uint64_t n = (uint64_t)(uint32_t)s->width * (uint32_t)s->height;
    if (s->width < 8 || s->width > 4096 || s->height < 8 || s->height > 4096 || s->count < 1 || !s->kinds || s->kinds > 3 || s->iterations < 0 ||
        (s->importance != 0 && s->importance != 1) || !s->covered || s->covered > n || emits > 1 ||
        (uint64_t)s->count > (uint64_t)(2 * s->width - 1) * (uint64_t)(2 * s->height - 1) || n * (uint64_t)s->count > PRT__OFFSET_MAX_ENTRIES ||
        !(s->ray_offset > 0) || !(s->ray_offset <= fmaxf(1e4f * prt__ray_offset(&t->mesh), 1e-6f)) || !(s->eta >= 1 && s->eta <= 4) ||
        !(s->mm_per_unit > 0 && s->mm_per_unit <= 1e9f))
        return bad(ctx, "offset parameters out of range");
    if (c->size != OFSP_HEADER + (uint64_t)s->count * 8) return bad(ctx, "offset parameter chunk size mismatch");
    if (!(s->offsets = malloc((size_t)s->count * 2 * sizeof(int)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int k = 0; k < s->count * 2; ++k) {
        s->offsets[k] = (int32_t)prt__get32(p + OFSP_HEADER + 4 * k);
        const int lim = k % 2 ? s->height : s->width;
        if (s->offsets[k] <= -lim || s->offsets[k] >= lim) return bad(ctx, "an offset lies beyond the light map");
    }
    if (!(c = prt__chunk_take(chunks, count, CHUNK_OFST))) return bad(ctx, "offset texel chunk missing");
    const size_t nc = s->covered;
    if (c->size != (uint64_t)nc * (4 + TEXEL_FLOATS * 4 + (emits ? 24 : 0))) return bad(ctx, "offset texel chunk size mismatch");
    s->texel = malloc(nc * sizeof *s->texel);
    s->pos = malloc(nc * 12); s->nrm = malloc(nc * 12); s->albedo = malloc(nc * 12); s->area = malloc(nc * 4);
    s->env = malloc(nc * PRT__OFFSET_ENV_COEFFS * sizeof(float));
    if (emits) { s->emit = malloc(nc * 12); s->emit_in = malloc(nc * 12); }
    if (!s->texel || !s->pos || !s->nrm || !s->albedo || !s->area || !s->env || (emits && (!s->emit || !s->emit_in)))
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(s->texel, c->data, nc * 4);
    const float *e = (const float *)(const void *)(c->data + nc * 4);
    float row[TEXEL_FLOATS];
    /* Texel points lie on the mesh (rays start there): inside its bounds, with unit normals and
     * no more area than the whole surface. */
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < t->mesh.vertex_count; ++v)
        for (int k = 0; k < 3; ++k) { lo[k] = fminf(lo[k], t->mesh.positions[v * 3 + k]); hi[k] = fmaxf(hi[k], t->mesh.positions[v * 3 + k]); }
    double surface = 0;
    for (size_t f = 0; f < t->mesh.triangle_count; ++f) {
        const uint32_t *ix = t->mesh.indices + f * 3;
        float e1[3], e2[3], cr[3];
        prt__v3_sub(t->mesh.positions + ix[1] * 3, t->mesh.positions + ix[0] * 3, e1);
        prt__v3_sub(t->mesh.positions + ix[2] * 3, t->mesh.positions + ix[0] * 3, e2);
        prt__v3_cross(e1, e2, cr);
        surface += 0.5 * prt__v3_len(cr);
    }
    const float margin = 1e-3f * (hi[0] - lo[0] + hi[1] - lo[1] + hi[2] - lo[2]) + 1e-6f;
    for (size_t i = 0; i < nc; ++i) {
        memcpy(row, (const unsigned char *)e + i * sizeof row, sizeof row);
        if (!prt__all_finite(row, TEXEL_FLOATS) || !(row[9] > 0) || !(row[9] <= surface * 1.01 + 1e-12)) return bad(ctx, "offset texel values out of range");
        for (int k = 0; k < 3; ++k)
            if (!(row[k] >= lo[k] - margin && row[k] <= hi[k] + margin)) return bad(ctx, "an offset texel lies outside the mesh");
        if (!(fabsf(prt__v3_len(row + 3) - 1.0f) < 1e-3f)) return bad(ctx, "an offset texel normal is not of unit length");
        for (int k = 10; k < TEXEL_FLOATS; ++k)
            if (!(fabsf(row[k]) <= 10.0f)) return bad(ctx, "offset texel environment transfer out of range");
        for (int k = 6; k < 9; ++k)
            if (!(row[k] >= 0 && row[k] <= 1)) return bad(ctx, "offset texel albedo out of range");
        memcpy(s->pos + i * 3, row, 12);
        memcpy(s->nrm + i * 3, row + 3, 12);
        memcpy(s->albedo + i * 3, row + 6, 12);
        s->area[i] = row[9];
        memcpy(s->env + i * PRT__OFFSET_ENV_COEFFS, row + 10, PRT__OFFSET_ENV_COEFFS * sizeof(float));
    }
    if (emits) {
        memcpy(s->emit, c->data + nc * (4 + TEXEL_FLOATS * 4), nc * 12);
        memcpy(s->emit_in, c->data + nc * (4 + TEXEL_FLOATS * 4 + 12), nc * 12);
        for (size_t i = 0; i < nc * 3; ++i)
            if (!(s->emit[i] >= 0 && s->emit[i] <= PRT__MAX_RADIANCE) || !(s->emit_in[i] >= 0 && s->emit_in[i] <= 1e30f))
                return bad(ctx, "offset texel emission out of range");
    }
    if (!prt__offset_set_index(s)) return bad(ctx, "offset texels out of order or beyond the light map");
    prt_status st = PRT_OK;
    c = prt__chunk_take(chunks, count, CHUNK_OFSR);
    if (!c != !(s->kinds & PRT__OFFSET_RADIOSITY_BIT)) return bad(ctx, "the radiosity map chunk does not match the transfer kinds");
    if (c && (st = load_maps(ctx, s, c, true, &s->radiosity))) return st;
    c = prt__chunk_take(chunks, count, CHUNK_OFSS);
    if (!c != !(s->kinds & PRT__OFFSET_SUBSURFACE_BIT)) return bad(ctx, "the subsurface map chunk does not match the transfer kinds");
    if (c && (st = load_maps(ctx, s, c, false, &s->subsurface))) return st;
    c = prt__chunk_take(chunks, count, CHUNK_OFSD);
    if (!c != !s->subsurface) return bad(ctx, "the subsurface media chunk does not match the transfer kinds");
    if (c) {
        if (c->size < 4) return bad(ctx, "offset media chunk short");
        s->medium_count = (int)prt__get32(c->data);
        if (s->medium_count < 1 || s->medium_count > PRT__OFFSET_MAX_MEDIA ||
            c->size != 4 + (uint64_t)s->medium_count * sizeof(prt_medium) + (((uint64_t)nc + 3) & ~3ull))
            return bad(ctx, "offset media chunk size mismatch");
        s->media = malloc((size_t)s->medium_count * sizeof(prt_medium));
        s->medium = malloc(nc + 1);
        if (!s->media || !s->medium) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(s->media, c->data + 4, (size_t)s->medium_count * sizeof(prt_medium));
        memcpy(s->medium, c->data + 4 + (size_t)s->medium_count * sizeof(prt_medium), nc);
        for (int k = 0; k < s->medium_count; ++k)
            if (prt_medium_check(&s->media[k])) return bad(ctx, "an offset medium is out of range");
        for (size_t i = 0; i < nc; ++i)
            if (s->medium[i] > s->medium_count) return bad(ctx, "a texel's medium is out of range");
    }
    static const uint32_t ids[5] = {CHUNK_OFSP, CHUNK_OFST, CHUNK_OFSR, CHUNK_OFSS, CHUNK_OFSD};
    for (int i = 0; i < 5; ++i)
        if (prt__chunk_take(chunks, count, ids[i])) return bad(ctx, "an offset chunk appears twice");
    return PRT_OK;
}

/* ---- description ---- */
static size_t offset_bytes(const prt_transfer *t)
{
    const prt__offset_set *s = t->state;
    const size_t maps = (size_t)s->count * s->covered * 3 * sizeof(float);
    return (s->radiosity ? maps : 0) + (s->subsurface ? maps : 0) + (size_t)s->covered * (4 + TEXEL_FLOATS * 4);
}

static void offset_describe(const prt_transfer *t, prt__describe *d)
{
    const prt__offset_set *s = t->state;
    const char *kinds = s->kinds == 3 ? "radiosity and subsurface" : s->kinds == 1 ? "radiosity" : "subsurface";
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "texel_width", s->width);
        cJSON_AddNumberToObject(j, "texel_height", s->height);
        cJSON_AddNumberToObject(j, "covered_texels", s->covered);
        cJSON_AddNumberToObject(j, "offsets", s->count);
        cJSON_AddStringToObject(j, "transfer", kinds);
        cJSON_AddNumberToObject(j, "iterations", s->iterations);
        cJSON_AddStringToObject(j, "importance", s->importance ? "mean" : "max");
        cJSON_AddNumberToObject(j, "map_bounces", s->map_bounces);
        cJSON *media = s->medium_count ? cJSON_AddArrayToObject(j, "media") : NULL;
        for (int k = 0; k < s->medium_count; ++k) {
            cJSON *m = cJSON_CreateObject();
            cJSON *sa = cJSON_AddArrayToObject(m, "sigma_a"), *ss = cJSON_AddArrayToObject(m, "sigma_s");
            for (int c = 0; c < 3; ++c) { cJSON_AddItemToArray(sa, cJSON_CreateNumber(s->media[k].sigma_a[c])); cJSON_AddItemToArray(ss, cJSON_CreateNumber(s->media[k].sigma_s[c])); }
            cJSON_AddNumberToObject(m, "eta", s->media[k].eta);
            cJSON_AddNumberToObject(m, "falloff_mm", s->media[k].falloff_mm);
            cJSON_AddItemToArray(media, m);
        }
        if (s->medium_count) cJSON_AddNumberToObject(j, "mm_per_unit", s->mm_per_unit);
        return;
    }
    prt__describe_line(d, "light map:", "%d x %d texels, %u on the surface (%.0f%%)", s->width, s->height, s->covered,
                       100.0 * s->covered / ((double)s->width * s->height));
    prt__describe_line(d, "transfer:", "%s: %d offset maps (drawn by %s transference, %d refinements), %.2f MiB", kinds, s->count,
                       s->importance ? "mean" : "max", s->iterations, offset_bytes(t) / 1048576.0);
    if (s->kinds & PRT__OFFSET_RADIOSITY_BIT)
        prt__describe_line(d, "bounces:", s->map_bounces > 1 ? "the radiosity maps hold %d bounces (one pass at run time)" : "the radiosity maps hold one; the run time repeats the pass",
                           s->map_bounces);
    for (int k = 0; k < s->medium_count; ++k) {
        size_t texels = 0;
        for (size_t i = 0; i < s->covered; ++i) texels += s->medium[i] == k + 1;
        const prt_medium *m = &s->media[k];
        if (m->falloff_mm > 0)
            prt__describe_line(d, k ? "" : "media:", "exponential falloff over %g mm (%zu texels), %g mm per unit", m->falloff_mm, texels, s->mm_per_unit);
        else
            prt__describe_line(d, k ? "" : "media:", "dipole, sigma_a %g %g %g, sigma_s' %g %g %g per mm, eta %g (%zu texels), %g mm per unit", m->sigma_a[0],
                               m->sigma_a[1], m->sigma_a[2], m->sigma_s[0], m->sigma_s[1], m->sigma_s[2], m->eta, texels, s->mm_per_unit);
    }
}

static void offset_control_range(const prt_transfer *t, int i, int *lo, int *hi, int *def)
{
    (void)i;
    const prt__offset_set *s = t ? t->state : NULL;
    *lo = 0;
    if (s && s->map_bounces > 1) { *hi = 1; *def = 1; return; }   /* the maps hold the bounces: one pass or none */
    *hi = 64;
    *def = 3;   /* as spectral; a closed room keeps a fifth of its indirect light past the third */
}

/* The final light, and the first-order light map it starts from (the paper's viewer shows both
 * side by side: prt render -k final,first-order). */
static int offset_variant_count(const prt_transfer *t) { (void)t; return 2; }
static const char *offset_variant_name(const prt_transfer *t, int i) { (void)t; return i == 1 ? "first-order" : "final"; }
static int offset_default_variant(const prt_transfer *t, int drawing) { (void)t; (void)drawing; return 0; }

static prt_status offset_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    prt_relight_desc dd = *d;
    if (d->variant == 1 && dd.component == PRT_COMPONENT_ALL) dd.component = PRT_COMPONENT_DIRECT;
    return prt__offset_relight(ctx, t, l, &dd, r);
}

const prt__method prt__method_offset = {
    .name = "offset",
    .title = "offset radiance transfer maps",
    .summary = "offset transfer maps (Sunshine-Hill & Faloutsos): radiosity and subsurface scattering in texture space, any first-order light",
    .lighting = PRT_LIGHTS_ENVIRONMENT | PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_SPHERE | PRT_LIGHTS_EMISSIVE,
    .runtime_albedo = false,
    .light_map = true,
    .gpu_passes = true,
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .export_options = export_options,
    .export_option_count = (int)(sizeof export_options / sizeof export_options[0]),
    .export_files = prt__offset_export,
    .bake_begin = offset_bake_begin,
    .free_state = prt__offset_set_free,
    .save = offset_save,
    .load = offset_load,
    .describe = offset_describe,
    .transfer_bytes = offset_bytes,
    .variant_count = offset_variant_count,
    .variant_name = offset_variant_name,
    .default_variant = offset_default_variant,
    .control_range = offset_control_range,
    .relight = offset_relight,
};

/* ---- the offset public accessors ---- */
int prt_transfer_offset_info(const prt_transfer *t, prt_offset_info *info)
{
    if (info) memset(info, 0, sizeof *info);
    const prt__offset_set *s = prt__state_of(t, &prt__method_offset);
    if (!s) return 0;
    if (info) {
        info->width = s->width;
        info->height = s->height;
        info->count = s->count;
        info->covered = (int)s->covered;
        info->has[PRT_OFFSET_RADIOSITY] = s->radiosity != NULL;
        info->has[PRT_OFFSET_SUBSURFACE] = s->subsurface != NULL;
        info->map_bounces = s->map_bounces;
    }
    return 1;
}

prt_status prt_transfer_offset_map(const prt_transfer *t, prt_offset_kind kind, int k, int offset[2], float *rgb)
{
    const prt__offset_set *s = prt__state_of(t, &prt__method_offset);
    if (!s || !offset) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_offset_map: an offset transfer and offset[2] are required");
    const float *maps = kind == PRT_OFFSET_RADIOSITY ? s->radiosity : kind == PRT_OFFSET_SUBSURFACE ? s->subsurface : NULL;
    if (!maps) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the file holds no %s maps", kind == PRT_OFFSET_SUBSURFACE ? "subsurface" : "such");
    if (k < 0 || k >= s->count) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "offset %d out of range (the file has %d)", k, s->count);
    offset[0] = s->offsets[k * 2];
    offset[1] = s->offsets[k * 2 + 1];
    if (!rgb) return PRT_OK;
    memset(rgb, 0, (size_t)s->width * s->height * 3 * sizeof *rgb);
    for (size_t i = 0; i < s->covered; ++i) memcpy(rgb + (size_t)s->texel[i] * 3, maps + ((size_t)k * s->covered + i) * 3, 3 * sizeof *rgb);
    return PRT_OK;
}

prt_status prt_transfer_offset_sources(const prt_transfer *t, int32_t *source)
{
    const prt__offset_set *s = prt__state_of(t, &prt__method_offset);
    if (!s || !source) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_offset_sources: an offset transfer and an array are required");
    for (size_t i = 0, n = (size_t)s->width * s->height; i < n; ++i) source[i] = s->source[i] < 0 ? -1 : (int32_t)s->texel[s->source[i]];
    return PRT_OK;
}

prt_status prt_transfer_offset_medium(const prt_transfer *t, float *medium)
{
    const prt__offset_set *s = prt__state_of(t, &prt__method_offset);
    if (!s || !medium) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_offset_medium: an offset transfer and an array are required");
    if (!s->medium) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the file holds no subsurface maps");
    memset(medium, 0, (size_t)s->width * s->height * sizeof *medium);
    for (size_t i = 0; i < s->covered; ++i) medium[s->texel[i]] = s->medium[i];
    return PRT_OK;
}
