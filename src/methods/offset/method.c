/* The offset method's table entry (offset radiance transfer mapping, Sunshine-Hill & Faloutsos
 * 2006): bake options, its chunks in file.c (OFSP parameters and offsets, OFST texel patches, OFSR and OFSS
 * maps), description, the bounce control and relighting. The offsets and maps are made in
 * bake.c (with sampling.c and transfer.c), the run time is
 * relight.c. */
#include "methods/offset/offset.h"


void prt__offset_set_free(void *state)
{
    prt__offset_set *s = state;
    if (!s) return;
    free(s->offsets); free(s->texel); free(s->pos); free(s->nrm); free(s->albedo); free(s->area); free(s->emit); free(s->emit_in); free(s->env);
    const size_t values = (size_t)s->count * s->covered * 3;
    prt__offset_maps_free(s->radiosity, values, s->mapped[0]);
    prt__offset_maps_free(s->subsurface, values, s->mapped[1]);
    free(s->index); free(s->source); free(s->xy); free(s->media); free(s->medium);
    if (s->lights) { prt__vertex_lights_free(s->lights); free(s->lights); }
    if (s->vertex_lights) { prt__vertex_lights_free(s->vertex_lights); free(s->vertex_lights); }
    free(s->sample_pos);
    free(s->sample_nrm);
    free(s->chart);
    free(s->level);
    free(s->passes);
    free(s->slices[0]);
    free(s->slices[1]);
    for (int i = 0; i < s->pyramid_count; ++i) free(s->pyramids[i]);
    free(s->pyramids);
    if (s->lock) { pthread_mutex_destroy(s->lock); free(s->lock); }
    free(s);
}

bool prt__offset_cache_new(prt__offset_set *s)
{
    pthread_mutex_t *lock = malloc(sizeof *lock);
    prt__vertex_lights *lights = prt__calloc(1, sizeof *lights), *vertex_lights = prt__calloc(1, sizeof *vertex_lights);
    if (!lock || !lights || !vertex_lights) { free(lock); free(lights); free(vertex_lights); return false; }   /* free_state then finds none */
    pthread_mutex_init(lock, NULL);
    prt__vertex_lights_init(lights);
    prt__vertex_lights_init(vertex_lights);
    s->lock = lock;
    s->lights = lights;
    s->vertex_lights = vertex_lights;
    return true;
}

/* ---- bake options ---- */
static const prt_option_desc options[] = {
    {"texels", "N", PRT_OPTION_INT, 8, 4096, NULL,
     "light map of N x N texels over the mesh's UVs, or a generated atlas (see --uv) (default: from the scene's size, texels of 1/64 of its diagonal or finer, 128 to 512)"},
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
    {"map-bounces", "N", PRT_OPTION_INT, 1, PRT__OFFSET_MAX_MAP_BOUNCES, NULL,
     "bounces the radiosity maps hold: 2..64 bake them all into the maps, as the paper, and one pass at run time "
     "gives them (the bounces past the first from paths traced from every texel, --walks, each ending when the "
     "albedos it met fall under 1e-4); the default, 64, is the whole series; 1 bakes one and the run time repeats "
     "the pass per bounce (--control bounces)"},
    {"walks", "N", PRT_OPTION_INT, 16, 65536, NULL, "paths per texel for the bounces past the first of --map-bounces (default 256)"},
    {"seed", "N", PRT_OPTION_INT, 0, 2147483647, NULL, "seed of the offsets drawn and the paths traced (default 0)"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "shadow-ray origin offset (default 1e-4 x scene diagonal)"},
};

/* prt export's options for offset files (export.c). */
static const prt_option_desc export_options[] = {
    {"maps", "DIR", PRT_OPTION_TEXT, 0, 0, NULL,
     "each transfer map as OpenEXR files of the boxes its axial slicing crops it to, the surface and medium masks, and "
     "DIR/index.json naming each map's kind, offset and pieces (with or without -o); replaces what an earlier export left in DIR"},
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

/* One float RGB map per offset over the light map's covered texels (bounded here by the whole map:
 * --texels, or the largest size a scene gets without it), for radiosity and for subsurface
 * transfer, and their halves as the file is written; the texels' points, normals, areas and
 * environment transfer. Sized by the light map, not the vertices. Streamed (bake.c, maps.c), the
 * float maps live in a mapped scratch file and only the pages of the block in hand are resident:
 * a block of texels' rows of every offset, or the bounce units between drops on every thread. */
static void offset_memory_estimate(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *e)
{
    const uint64_t w = (uint64_t)prt__opt_int(o, "texels", 512), texels = w * w, K = (uint64_t)prt__opt_int(o, "offsets", 200);
    const int kind = prt__opt_choice(o, "transfer", 0);   /* auto, radiosity, subsurface, both */
    const uint64_t kinds = kind == 3 ? 2 : 1;   /* auto: radiosity, and subsurface maps only where a medium is named (not known here) */
    const uint64_t maps = texels * K * 3 * sizeof(float) * kinds, halves = maps / 2;
    const bool bounces = kind != 2 && prt__opt_int(o, "map-bounces", PRT__OFFSET_MAX_MAP_BOUNCES) > 1;
    const uint64_t page = 4096, block = K * (PRT__OFFSET_MAP_BLOCK * 3 * sizeof(float) + 2 * page);
    const uint64_t bounce = bounces ? K * 2 * page * (PRT__OFFSET_BOUNCE_DROP + (uint64_t)(threads > 1 ? threads : 1)) : 0;
    /* The UV atlas (vertices copied along seams), the charts and texel patches over every
     * triangle: about 256 bytes a vertex, measured on Sponza at 126k vertices. */
    const uint64_t other = texels * (4 + 4 * 3 * sizeof(float) + 9 * sizeof(float) + 16) + (uint64_t)t->mesh.vertex_count * 256;
    e->bytes = maps + halves + other;
    e->least = halves + (block > bounce ? block : bounce) + other;
    if (e->least > e->bytes) e->least = e->bytes;
    snprintf(e->what, sizeof e->what, "up to %.0f MiB of %llu maps over %llux%llu texels and %.0f MiB of their halves as the file is written; the maps can stream",
             (double)maps / 1048576.0, (unsigned long long)(K * kinds), (unsigned long long)w, (unsigned long long)w, (double)halves / 1048576.0);
    snprintf(e->lower, sizeof e->lower, "fewer --offsets or a smaller --texels");
}

static prt_status offset_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    prt__offset_bake_desc d = {0};
    d.texels = prt__opt_int(o, "texels", 128);
    d.texels_default = !prt__opt(o, "texels");
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
    /* Every bounce by default: the paths end on their own (weight under 1e-4) long before 64 in
     * rooms of any albedo below 0.86, so the maps hold the converged series. */
    d.map_bounces = prt__opt_int(o, "map-bounces", (kind == 2) ? 1 : PRT__OFFSET_MAX_MAP_BOUNCES);
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

/* ---- description ---- */
static size_t offset_bytes(const prt_transfer *t)
{
    const prt__offset_set *s = t->state;
    const size_t maps = (size_t)s->count * s->covered * 3 * sizeof(uint16_t);   /* stored as halves */
    return (s->radiosity ? maps : 0) + (s->subsurface ? maps : 0) + (size_t)s->covered * (4 + PRT__OFFSET_TEXEL_FLOATS * 4);
}

/* How tightly each kind's maps are cropped (gpu.c): the boxes of their axial slicing, and the
 * share of the boxes' texels that hold data, sliced and as one box per map; false when out of
 * memory. */
static bool describe_crops(const prt__offset_set *s, prt__offset_crops c[2])
{
    const float *maps[2] = {s->radiosity, s->subsurface};
    memset(c, 0, 2 * sizeof *c);
    for (int k = 0; k < 2; ++k)
        if (maps[k] && prt__offset_crop_maps(NULL, s, maps[k], &c[k])) { prt__offset_maps_drop(s); prt__offset_crops_free(&c[0]); return false; }
    prt__offset_maps_drop(s);   /* a streamed bake's maps: read, not kept */
    return true;
}

static double share(int64_t part, int64_t whole) { return whole ? 100.0 * (double)part / (double)whole : 0.0; }

static void offset_describe(const prt_transfer *t, prt__describe *d)
{
    static const char *const crop_kinds[2] = {"radiosity", "subsurface"};
    const prt__offset_set *s = t->state;
    const char *kinds = s->kinds == 3 ? "radiosity and subsurface" : s->kinds == 1 ? "radiosity" : "subsurface";
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "texel_width", s->width);
        cJSON_AddNumberToObject(j, "texel_height", s->height);
        cJSON_AddNumberToObject(j, "covered_texels", s->covered);
        cJSON_AddNumberToObject(j, "atlas_coverage", (double)s->covered / ((double)s->width * s->height));
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
        prt__offset_crops c[2];
        const bool cropped = describe_crops(s, c);
        cJSON *crops = cropped ? cJSON_AddObjectToObject(j, "crops") : NULL;
        for (int k = 0; crops && k < 2; ++k) {
            if (!c[k].count && !c[k].data) continue;
            cJSON *o = cJSON_AddObjectToObject(crops, crop_kinds[k]);
            cJSON_AddNumberToObject(o, "boxes", c[k].count);
            cJSON_AddNumberToObject(o, "data_texels", (double)c[k].data);
            cJSON_AddNumberToObject(o, "box_texels", (double)c[k].area);
            cJSON_AddNumberToObject(o, "unsliced_box_texels", (double)c[k].whole);
            cJSON_AddNumberToObject(o, "data_share", c[k].area ? (double)c[k].data / (double)c[k].area : 0.0);
            cJSON_AddNumberToObject(o, "unsliced_data_share", c[k].whole ? (double)c[k].data / (double)c[k].whole : 0.0);
        }
        if (cropped) { prt__offset_crops_free(&c[0]); prt__offset_crops_free(&c[1]); }
        if (s->cap_known) {
            cJSON *cap = cJSON_AddObjectToObject(j, "energy_cap");
            for (int k = 0; k < 2; ++k) {
                if (!(s->kinds & (1u << k))) continue;
                cJSON *e = cJSON_AddObjectToObject(cap, k ? "subsurface" : "radiosity");
                cJSON_AddNumberToObject(e, "texels", s->cap[k].texels);
                cJSON_AddNumberToObject(e, "fraction", (double)s->cap[k].texels / s->covered);
                cJSON_AddNumberToObject(e, "max_factor", s->cap[k].max);
                cJSON_AddNumberToObject(e, "mean_factor", s->cap[k].mean);
            }
        }
        return;
    }
    prt__describe_line(d, "light map:", "%d x %d texels, %u on the surface (atlas coverage %.0f%%)", s->width, s->height, s->covered,
                       100.0 * s->covered / ((double)s->width * s->height));
    prt__describe_line(d, "transfer:", "%s: %d offset maps (drawn by %s transference, %d refinements), %.2f MiB", kinds, s->count,
                       s->importance ? "mean" : "max", s->iterations, offset_bytes(t) / 1048576.0);
    prt__offset_crops c[2];
    if (describe_crops(s, c)) {
        for (int k = 0, line = 0; k < 2; ++k) {
            if (!(s->kinds & (1u << k))) continue;
            prt__describe_line(d, line++ ? "" : "crops:", "%s maps in %d boxes: %.1f%% of their texels hold data (%.1f%% in one box per map)",
                               crop_kinds[k], c[k].count, share(c[k].data, c[k].area), share(c[k].data, c[k].whole));
        }
        prt__offset_crops_free(&c[0]);
        prt__offset_crops_free(&c[1]);
    }
    if (s->kinds & PRT__OFFSET_RADIOSITY_BIT)
        prt__describe_line(d, "bounces:", s->map_bounces >= PRT__OFFSET_MAX_MAP_BOUNCES ? "the radiosity maps hold every bounce (paths of up to %d; one pass at run time)"
                                          : s->map_bounces > 1 ? "the radiosity maps hold %d bounces (one pass at run time)"
                                                               : "the radiosity maps hold one; the run time repeats the pass",
                           s->map_bounces);
    for (int k = 0; s->cap_known && k < 2; ++k) {
        if (!(s->kinds & (1u << k))) continue;
        const prt__offset_cap *c = &s->cap[k];
        if (!c->texels)
            prt__describe_line(d, "energy cap:", "%s maps: no texel gathered more than it can", k ? "subsurface" : "radiosity");
        else   /* as the share they were over: factors near 1 would all read "1" */
            prt__describe_line(d, "energy cap:", "%s maps: %u texels (%.1f%%) gathered more than they can, by up to %.3g%% (mean %.3g%%); scaled down to it",
                               k ? "subsurface" : "radiosity", c->texels, 100.0 * c->texels / s->covered, 100.0 * (c->max - 1), 100.0 * (c->mean - 1));
    }
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

/* A painting covers the first-order light map (prt/paint.h); relight.c adds it to what the lights
 * deliver. */
static void offset_paint_layout(const prt_transfer *t, prt__paint_layout *out)
{
    const prt__offset_set *s = t->state;
    *out = (prt__paint_layout){s->width, s->height, s->covered, s->texel, s->pos, s->nrm};
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
    .memory_estimate = offset_memory_estimate,
    .free_state = prt__offset_set_free,
    .save = prt__offset_save,
    .load = prt__offset_load,
    .describe = offset_describe,
    .transfer_bytes = offset_bytes,
    .variant_count = offset_variant_count,
    .variant_name = offset_variant_name,
    .default_variant = offset_default_variant,
    .control_range = offset_control_range,
    .web = prt__offset_web,
    .relight = offset_relight,
    .shade = prt__offset_shade,
    .paint_layout = offset_paint_layout,
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
