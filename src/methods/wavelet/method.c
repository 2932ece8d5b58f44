/* The wavelet method's table entry (all-frequency glossy PRT, Wang, Tran & Luebke 2005): bake
 * options, its chunks in file.c (WAVP, WBRF, WAVT), description, controls, relighting and the CPU view
 * factor. The bake lives in bake.c, the kernels in relight.c, the lighting in lighting.c. */
#include "methods/wavelet/wavelet.h"
#include "transfer/gpu_sums.h"

#include <strings.h>


void prt__wavelet_set_free(void *state)
{
    prt__wavelet_set *w = state;
    if (!w) return;
    free(w->term_count);
    free(w->vec_start);
    free(w->view_maps);
    free(w->vertex_set);
    prt__sparse_free(&w->store);
    for (int k = 0; k < PRT__MAX_BRDFS; ++k) prt_brdf_factors_release(w->factors[k]);
    prt__gpu_sums_free(w->gpu);
    free(w);
}

bool prt__wavelet_index(prt__wavelet_set *w, size_t vertex_count, size_t *vectors)
{
    size_t at = 0;
    for (size_t v = 0; v < vertex_count; ++v) {
        if (w->term_count[v] < 1 || w->term_count[v] > PRT_BRDF_MAX_TERMS) return false;
        w->vec_start[v] = at;
        at += w->term_count[v];
    }
    w->vec_start[vertex_count] = at;
    *vectors = at;
    return true;
}

/* ---- the wavelet public accessors ---- */
int prt_transfer_wavelet_info(const prt_transfer *t, prt_wavelet_info *info)
{
    if (info) memset(info, 0, sizeof *info);
    const prt__wavelet_set *w = prt__wavelet(t);
    if (!w) return 0;
    if (info) {
        info->terms = w->terms;
        info->coefficients = w->store.n;
        info->bits = w->store.bits;
        info->supersample = w->supersample;
        info->bounces = w->bounces;
        info->gather_resolution = w->gather_resolution;
        info->brdf_resolution = w->brdf_resolution;
        info->param = w->param;
        info->vectors = w->store.vectors;
        info->bytes = prt__sparse_bytes(&w->store);
        for (int k = 0; k < PRT__MAX_BRDFS; ++k) info->glossy_materials += w->factors[k] != NULL;
    }
    return 1;
}

int prt_transfer_wavelet_vertex_terms(const prt_transfer *t, size_t v)
{
    const prt__wavelet_set *w = prt__wavelet(t);
    return w && v < t->mesh.vertex_count ? w->term_count[v] : 0;
}

const prt_brdf_factors *prt_transfer_wavelet_factors(const prt_transfer *t, int k)
{
    const prt__wavelet_set *w = prt__wavelet(t);
    return w && k >= 1 && k <= PRT__MAX_BRDFS ? w->factors[k - 1] : NULL;
}

int prt_transfer_wavelet_vector(const prt_transfer *t, size_t v, int k, int *index, float *rgb)
{
    const prt__wavelet_set *w = prt__wavelet(t);
    if (!w || v >= t->mesh.vertex_count || k < 0 || k >= w->term_count[v]) return 0;
    const size_t vec = w->vec_start[v] + (size_t)k;
    for (int i = 0; i < w->store.n; ++i) prt__sparse_get(&w->store, vec, i, &index[i], rgb + 3 * i);
    return w->store.n;
}

prt_status prt__wavelet_build_view_maps(const prt_transfer *t, prt__wavelet_set *w)
{
    /* Gather the factored materials' first `terms` view maps into one array; vertices point at
     * their material's slot. Built when the set is made (bake or load), so reading it later from
     * any number of threads needs no locking. */
    int slot[PRT__MAX_BRDFS] = {0}, n = 0, res = 0;
    for (int k = 0; k < PRT__MAX_BRDFS; ++k)
        if (w->factors[k]) { slot[k] = ++n; res = w->factors[k]->resolution; }
    if (!n) return PRT_OK;
    const size_t cells = (size_t)res * res, per_set = (size_t)w->terms * 3 * cells;
    float *m = prt__calloc((size_t)n * per_set, sizeof(float));
    uint8_t *vs = prt__calloc(t->mesh.vertex_count, 1);
    if (!m || !vs) { free(m); free(vs); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (int k = 0; k < PRT__MAX_BRDFS; ++k) {
        const prt_brdf_factors *f = w->factors[k];
        if (!f) continue;
        for (int term = 0; term < f->terms && term < w->terms; ++term)
            for (int c = 0; c < 3; ++c)
                memcpy(m + (size_t)(slot[k] - 1) * per_set + ((size_t)term * 3 + c) * cells, f->view + ((size_t)c * f->computed + term) * cells,
                       cells * sizeof(float));
    }
    for (size_t v = 0; v < t->mesh.vertex_count; ++v) {
        uint8_t mat = t->mesh.material[v];
        vs[v] = mat ? (uint8_t)slot[mat - 1] : 0;
    }
    free(w->view_maps);
    free(w->vertex_set);
    w->view_maps = m;
    w->vertex_set = vs;
    w->view_sets = n;
    return PRT_OK;
}

int prt_wavelet_view_maps(const prt_transfer *t, const float **maps, int *sets, int *resolution, int *polar, const uint8_t **vertex_set)
{
    const prt__wavelet_set *w = prt__wavelet(t);
    if (!w || !w->view_maps) return 0;
    int res = 0;
    for (int k = 0; k < PRT__MAX_BRDFS && !res; ++k)
        if (w->factors[k]) res = w->factors[k]->resolution;
    if (maps) *maps = w->view_maps;
    if (sets) *sets = w->view_sets;
    if (resolution) *resolution = res;
    if (polar) *polar = w->param == PRT_BRDF_PARAM_POLAR;
    if (vertex_set) *vertex_set = w->vertex_set;
    return 1;
}

/* ---- bake options ---- */
/* Help texts are reflowed by the printer (prt bake --help): line breaks here are for the source. */
static const prt_option_desc options[] = {
    {"terms", "K", PRT_OPTION_INT, 1, PRT_BRDF_MAX_TERMS, NULL,
     "separable BRDF terms per glossy material, 1..16 (default 4); the cosine-weighted RMS "
     "error per K is reported"},
    {"coefficients", "N", PRT_OPTION_INT, 1, PRT_WAVELET_DIM, NULL,
     "Haar coefficients kept per transport vector (default 128)"},
    {"bits", "B", PRT_OPTION_CHOICE, 0, 0, "8|16", "quantization per colour channel: 8 (default) or 16"},
    {"supersample", "S", PRT_OPTION_INT, 1, 4, NULL,
     "visibility rays per cube texel side, 1..4 (default 2: 6x128x128)"},
    {"bounces", "N", PRT_OPTION_INT, 0, 8, NULL,
     "interreflection passes, 0..8 (default 2: direct light alone, 0, is 34% below the path tracer on the demo scene, 2 passes 10%)"},
    {"gather-res", "R", PRT_OPTION_INT, 4, 64, NULL,
     "hit-point cube map per side for bounces, 4..64 (default 32)"},
    {"brdf-res", "R", PRT_OPTION_INT, 4, 96, NULL, "BRDF light/view map size, 4..96 (default 48)"},
    {"param", "P", PRT_OPTION_CHOICE, 0, 0, "grid|polar",
     "BRDF parameterization: grid (default, eq. 10) or polar (eq. 11)"},
    {"brdf", "SPEC", PRT_OPTION_TEXT, 0, 0, NULL,
     "this BRDF for every vertex instead of the scene's materials: lambert[:RHO], "
     "phong:N[:KS[:KD]], blinn:N[:KS[:KD]], ashikhmin:NU:NV[:RS[:RD]] (anisotropic) or "
     "lafortune:clay|skin"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL,
     "shadow-ray origin offset (default 1e-4 x scene diagonal)"},
};

static const prt_control_desc controls[] = {
    {"light-coefficients", "Haar coefficients of the lighting kept", '[', ']', 1},
};

/* Sparse stores of --coefficients per transport vector (a uint16 index and three channels), one
 * vector a vertex and --terms at glossy vertices: with bounces the direct pass, the previous and
 * next passes and their sum at 16 bits, then the file's store; each thread's cube-map planes. */
static void wavelet_memory_estimate(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *e)
{
    const uint64_t nv = t->mesh.vertex_count, n = (uint64_t)prt__opt_int(o, "coefficients", 128), terms = (uint64_t)prt__opt_int(o, "terms", 4);
    const uint64_t bounces = (uint64_t)prt__opt_int(o, "bounces", 2), bits = (uint64_t)prt__opt_int(o, "bits", 8);
    uint64_t vectors = 0;
    for (size_t v = 0; v < nv; ++v) {
        const uint8_t k = t->mesh.material[v];
        vectors += k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1]) ? terms : 1;
    }
    const uint64_t store = vectors * n * (2 + 3 * 2), final = vectors * n * (2 + 3 * bits / 8);
    const uint64_t stores = (bounces ? 4 * store : 0) + final;
    const uint64_t per_thread = terms * 3 * PRT_WAVELET_DIM * sizeof(float) + nv * sizeof(int32_t);
    e->bytes = e->least = stores + nv * (9 * sizeof(float) + 8 + 1) + (uint64_t)threads * per_thread;
    snprintf(e->what, sizeof e->what, "%.0f MiB of sparse transport, %llu coefficients a vector for %llu vectors", (double)stores / 1048576.0,
             (unsigned long long)n, (unsigned long long)vectors);
    snprintf(e->lower, sizeof e->lower, "fewer --coefficients, --bounces 0 or fewer --terms");
}

static prt_status wavelet_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    (void)scene;
    prt_wavelet_bake_desc d = {0};
    prt_brdf brdf;
    d.terms = prt__opt_int(o, "terms", 0);
    d.coefficients = prt__opt_int(o, "coefficients", 0);
    d.bits = prt__opt_int(o, "bits", 0);
    d.supersample = prt__opt_int(o, "supersample", 0);
    d.bounces = prt__opt_int(o, "bounces", 2);   /* prt_wavelet_bake_desc's zero stays direct light only, as prt 0.1 */
    d.gather_resolution = prt__opt_int(o, "gather-res", 0);
    d.brdf_resolution = prt__opt_int(o, "brdf-res", 0);
    d.param = (prt_brdf_param)prt__opt_choice(o, "param", 0);
    d.ray_offset = prt__opt_float(o, "ray-offset", 0.0f);
    if (prt__opt(o, "brdf")) {
        if (prt_brdf_parse(prt__opt(o, "brdf"), &brdf)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf: %s", prt_last_error());
        d.brdf = &brdf;
    }
    return prt__wavelet_bake_begin(ctx, &d, t, job);
}

/* ---- description ---- */
static size_t wavelet_bytes(const prt_transfer *t) { return prt__sparse_bytes(&((const prt__wavelet_set *)t->state)->store); }

static void wavelet_describe(const prt_transfer *t, prt__describe *d)
{
    prt_wavelet_info wi;
    prt_transfer_wavelet_info(t, &wi);
    static const char *params[2] = {"grid", "polar"};
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "terms", wi.terms);
        cJSON_AddNumberToObject(j, "coefficients", wi.coefficients);
        cJSON_AddNumberToObject(j, "bits", wi.bits);
        cJSON_AddNumberToObject(j, "supersample", wi.supersample);
        cJSON_AddNumberToObject(j, "bounces", wi.bounces);
        cJSON_AddNumberToObject(j, "gather_resolution", wi.gather_resolution);
        cJSON_AddNumberToObject(j, "brdf_resolution", wi.brdf_resolution);
        cJSON_AddStringToObject(j, "brdf_parameterization", params[wi.param]);
        cJSON_AddNumberToObject(j, "vectors", (double)wi.vectors);
        cJSON *mats = cJSON_AddArrayToObject(j, "materials");
        for (int k = 1; k <= t->brdf_count; ++k) {
            char spec[128];
            prt_brdf_format(&t->brdfs[k - 1], spec, sizeof spec);
            cJSON *o = cJSON_CreateObject();
            cJSON_AddStringToObject(o, "brdf", spec);
            cJSON_AddNumberToObject(o, "terms", prt_brdf_factors_terms(prt_transfer_wavelet_factors(t, k)));
            cJSON_AddItemToArray(mats, o);
        }
        return;
    }
    prt__describe_line(d, "transport:", "6x64x64 Haar, %d coefficients per vector, %d-bit, up to %d terms per vertex", wi.coefficients, wi.bits, wi.terms);
    prt__describe_line(d, "bake:", "%d x %d rays per texel, %d interreflection pass%s (%dx%d gather)", wi.supersample, wi.supersample, wi.bounces,
                       wi.bounces == 1 ? "" : "es", wi.gather_resolution, wi.gather_resolution);
    for (int k = 1; k <= t->brdf_count; ++k) {
        char spec[128], label[32];
        prt_brdf_format(&t->brdfs[k - 1], spec, sizeof spec);
        snprintf(label, sizeof label, "material %d:", k);
        const prt_brdf_factors *f = prt_transfer_wavelet_factors(t, k);
        if (f) prt__describe_line(d, label, "%s: %d separable terms, %dx%d %s maps", spec, prt_brdf_factors_terms(f), wi.brdf_resolution, wi.brdf_resolution,
                                  params[wi.param]);
        else prt__describe_line(d, label, "%s: Lambertian (one term)", spec);
    }
    prt__describe_line(d, "vectors:", "%zu", wi.vectors);
}

/* The fit of each factored material: cosine-weighted RMS error per number of terms. */
static void wavelet_report(const prt_transfer *t, prt__describe *d)
{
    for (int k = 1; k <= t->brdf_count; ++k) {
        const prt_brdf_factors *f = prt_transfer_wavelet_factors(t, k);
        double rms[PRT_BRDF_MAX_TERMS], rel[PRT_BRDF_MAX_TERMS];
        char spec[128], label[48];
        if (!f || prt_brdf_factors_error(f, &t->brdfs[k - 1], 0, rms, rel)) continue;
        prt_brdf_format(&t->brdfs[k - 1], spec, sizeof spec);
        snprintf(label, sizeof label, "material %d:", k);
        prt__describe_line(d, label, "%s, %d terms used; cosine-weighted RMS error by terms:", spec, prt_brdf_factors_terms(f));
        for (int K = 1; K <= prt_brdf_factors_computed(f); ++K)
            prt__describe_line(d, "", "K=%-2d %.4g (%.1f%%)%s", K, rms[K - 1], 100.0 * rel[K - 1], K == prt_brdf_factors_terms(f) ? "  <- used" : "");
    }
}

/* ---- variants and controls ---- */
static int wavelet_variant_count(const prt_transfer *t) { (void)t; return 1; }
static const char *wavelet_variant_name(const prt_transfer *t, int i) { (void)t; (void)i; return "wavelet"; }
static int wavelet_default_variant(const prt_transfer *t, int drawing) { (void)t; (void)drawing; return 0; }

static void wavelet_control_range(const prt_transfer *t, int i, int *lo, int *hi, int *def)
{
    (void)t;
    (void)i;
    *lo = 64;
    *hi = PRT_WAVELET_DIM;
    *def = 4096;
}

/* ---- relighting ---- */
static prt_status wavelet_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    const prt__wavelet_set *w = t->state;
    if (d->component) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the wavelet method does not separate direct and indirect light");
    if (d->brdf) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf does not apply to wavelet transfer: its BRDFs are baked in");
    prt_status st = prt__relit_alloc(ctx, t, r, false);
    if (st) return st;
    const size_t nv = t->mesh.vertex_count;
    const bool gpu = d->gpu_finish;   /* the sparse rows summed on the GPU (gpu.c) */
    if (gpu) {
        const prt_envmap *env = prt_lighting_envmap(l);
        prt_wavelet_light *wl = NULL;
        if (env || prt_lighting_count(l)) {
            prt_wavelet_light_desc ld = {0};
            prt_lighting_rotation(l, ld.rotation);
            ld.intensity = prt_lighting_intensity(l);
            ld.coefficients = d->controls ? d->controls[0] : 0;
            ld.lights = prt_lighting_count(l) ? prt_lighting_light(l, 0) : NULL;
            ld.light_count = prt_lighting_count(l);
            if ((st = prt_wavelet_light_create(ctx, env, &ld, &wl))) return st;
        }
        st = prt__wavelet_gpu(ctx, t, wl, r);
        prt_wavelet_light_release(wl);
        /* Glossy vertices: their terms (a kvec product) meet the view maps per pixel. */
        if (!st && prt__wavelet_glossy(t) &&
            prt_wavelet_view_maps(t, &r->view_maps, &r->view_map_sets, &r->view_map_resolution, &r->view_map_polar, &r->view_set))
            r->kvec_terms = w->terms;
        return st;
    }
    r->kvec = prt__calloc(nv * (size_t)w->terms * 3, sizeof(float));
    if (!r->kvec) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    r->kvec_terms = w->terms;
    const prt_envmap *env = prt_lighting_envmap(l);
    if (env || prt_lighting_count(l)) {
        prt_wavelet_light_desc ld = {0};
        prt_lighting_rotation(l, ld.rotation);
        ld.intensity = prt_lighting_intensity(l);
        ld.coefficients = d->controls ? d->controls[0] : 0;
        ld.lights = prt_lighting_count(l) ? prt_lighting_light(l, 0) : NULL;   /* directional only: checked by the table */
        ld.light_count = prt_lighting_count(l);
        prt_wavelet_light *wl = NULL;
        if ((st = prt_wavelet_light_create(ctx, env, &ld, &wl))) return st;
        st = prt_relight_wavelet(ctx, t, wl, r->kvec);
        prt_wavelet_light_release(wl);
        if (st) return st;
    }
    /* Lambertian vertices do not depend on the view: their radiance is final here. Glossy ones
     * get their view factor per pixel in the renderer, or from prt_relit_shade. */
    if ((st = prt_wavelet_shade(ctx, t, r->kvec, NULL, r->radiance))) return st;
    if (!prt_wavelet_view_maps(t, &r->view_maps, &r->view_map_sets, &r->view_map_resolution, &r->view_map_polar, &r->view_set)) {
        free(r->kvec);   /* all Lambertian: nothing depends on the view */
        r->kvec = NULL;
        r->kvec_terms = 0;
    }
    return PRT_OK;
}

static prt_status wavelet_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb)
{
    /* prt_wavelet_shade evaluates every vertex, the Lambertian ones included. */
    return prt_wavelet_shade(ctx, t, r->kvec, eye, rgb);
}

const prt__method prt__method_wavelet = {
    .name = "wavelet",
    .title = "all-frequency wavelet PRT",
    .summary = "all-frequency glossy PRT (Wang, Tran & Luebke): Haar cube maps, separable BRDFs, sharp shadows",
    .lighting = PRT_LIGHTS_ENVIRONMENT | PRT_LIGHTS_DIRECTIONAL,
    .sharp_environment = true,
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .bake_begin = wavelet_bake_begin,
    .gpu_passes = true,
    .memory_estimate = wavelet_memory_estimate,
    .free_state = prt__wavelet_set_free,
    .save = prt__wavelet_save,
    .load = prt__wavelet_load,
    .describe = wavelet_describe,
    .report = wavelet_report,
    .transfer_bytes = wavelet_bytes,
    .variant_count = wavelet_variant_count,
    .variant_name = wavelet_variant_name,
    .default_variant = wavelet_default_variant,
    .control_range = wavelet_control_range,
    .web = prt__wavelet_web,
    .relight = wavelet_relight,
    .shade = wavelet_shade,
};
