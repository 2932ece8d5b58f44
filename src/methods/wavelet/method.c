/* The wavelet method's table entry (all-frequency glossy PRT, Wang, Tran & Luebke 2005): bake
 * options, its chunks (WAVP, WBRF, WAVT), description, controls, relighting and the CPU view
 * factor. The bake lives in bake.c, the kernels in relight.c, the lighting in lighting.c. */
#include "methods/wavelet/wavelet.h"

#include <strings.h>

#define CHUNK_WAVP PRT__FOURCC('W', 'A', 'V', 'P')
#define CHUNK_WBRF PRT__FOURCC('W', 'B', 'R', 'F')
#define CHUNK_WAVT PRT__FOURCC('W', 'A', 'V', 'T')
#define WAVP_HEADER 48
#define WBRF_HEADER (24 + 3 * PRT_BRDF_MAX_TERMS * 4)

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
    {"bounces", "N", PRT_OPTION_INT, 0, 8, NULL, "interreflection passes, 0..8 (default 0 = direct light only)"},
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

static prt_status wavelet_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    (void)scene;
    prt_wavelet_bake_desc d = {0};
    prt_brdf brdf;
    d.terms = prt__opt_int(o, "terms", 0);
    d.coefficients = prt__opt_int(o, "coefficients", 0);
    d.bits = prt__opt_int(o, "bits", 0);
    d.supersample = prt__opt_int(o, "supersample", 0);
    d.bounces = prt__opt_int(o, "bounces", 0);
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

/* ---- files ---- */
static prt_status wavelet_save(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__wavelet_set *ws = t->state;
    const prt__mesh *m = &t->mesh;
    const prt__sparse_store *ss = &ws->store;
    static const unsigned char zero8[8] = {0};
    /* Parameters, then one term count per vertex padded to 8 bytes. */
    unsigned char *head = prt__chunks_alloc(l, WAVP_HEADER);
    if (!head) return PRT_OK;   /* the list records the failure */
    const uint32_t p32[8] = {(uint32_t)ws->terms, (uint32_t)ss->n, (uint32_t)ss->bits, (uint32_t)ws->supersample,
                             (uint32_t)ws->bounces, (uint32_t)ws->gather_resolution, (uint32_t)ws->brdf_resolution, (uint32_t)ws->param};
    for (int i = 0; i < 8; ++i) prt__put32(head + 4 * i, p32[i]);
    prt__put64(head + 32, ss->vectors);
    prt__put64(head + 40, m->vertex_count);
    prt__chunks_add(l, CHUNK_WAVP, head, (size_t)WAVP_HEADER, ws->term_count, m->vertex_count, zero8,
                    ((m->vertex_count + 7) & ~(size_t)7) - m->vertex_count, NULL);
    for (int k = 0; k < PRT__MAX_BRDFS; ++k) {
        const prt_brdf_factors *f = ws->factors[k];
        if (!f) continue;
        unsigned char *h = prt__chunks_alloc(l, WBRF_HEADER);
        if (!h) return PRT_OK;
        prt__put32(h, (uint32_t)(k + 1));
        prt__put32(h + 4, (uint32_t)f->terms);
        prt__put32(h + 8, (uint32_t)f->computed);
        prt__put32(h + 12, (uint32_t)f->resolution);
        prt__put32(h + 16, (uint32_t)f->param);
        for (int c = 0; c < 3; ++c) memcpy(h + 24 + (size_t)c * PRT_BRDF_MAX_TERMS * 4, f->sigma[c], PRT_BRDF_MAX_TERMS * 4);
        const size_t maps = (size_t)3 * f->computed * f->resolution * f->resolution * sizeof(float);
        prt__chunks_add(l, CHUNK_WBRF, h, (size_t)WBRF_HEADER, f->light, maps, f->view, maps, NULL);
    }
    const size_t cells = ss->vectors * (size_t)ss->n, ib = cells * 2, vb = cells * 3 * (size_t)(ss->bits / 8);
    prt__chunks_add(l, CHUNK_WAVT, ss->index, ib, zero8, ((ib + 3) & ~(size_t)3) - ib, ss->values, vb, zero8, ((vb + 3) & ~(size_t)3) - vb,
                    ss->scale, ss->vectors * 12, NULL);
    return PRT_OK;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "%s", msg); }

static prt_status load_params(prt_context *ctx, prt_transfer *t, const prt__chunk_in *c)
{
    const unsigned char *p = c->data;
    const uint64_t nv = t->mesh.vertex_count, len = c->size;
    if (len < WAVP_HEADER || prt__get64(p + 40) != nv || WAVP_HEADER + ((nv + 7) & ~7ull) != len)
        return bad(ctx, "corrupt .prt file: invalid wavelet parameter chunk");
    uint32_t terms = prt__get32(p), n = prt__get32(p + 4), bits = prt__get32(p + 8), param = prt__get32(p + 28);
    uint64_t vectors = prt__get64(p + 32);
    if (terms < 1 || terms > PRT_BRDF_MAX_TERMS || n < 1 || n > PRT_WAVELET_DIM || (bits != 8 && bits != 16) || param > PRT_BRDF_PARAM_POLAR ||
        vectors < nv || vectors > nv * PRT_BRDF_MAX_TERMS)
        return bad(ctx, "corrupt .prt file: wavelet parameters out of range");
    prt__wavelet_set *w = t->state;
    w->terms = (int)terms;
    w->supersample = (int)prt__get32(p + 12);
    w->bounces = (int)prt__get32(p + 16);
    w->gather_resolution = (int)prt__get32(p + 20);
    w->brdf_resolution = (int)prt__get32(p + 24);
    w->param = (prt_brdf_param)param;
    w->term_count = malloc(nv);
    w->vec_start = malloc((nv + 1) * sizeof(size_t));
    if (!w->term_count || !w->vec_start) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(w->term_count, p + WAVP_HEADER, nv);
    size_t total = 0;
    if (!prt__wavelet_index(w, nv, &total) || total != vectors) return bad(ctx, "corrupt .prt file: wavelet term counts are inconsistent");
    /* K-vectors are `terms` long per vertex: no vertex may have more. */
    for (uint64_t v = 0; v < nv; ++v)
        if (w->term_count[v] > terms) return bad(ctx, "corrupt .prt file: a vertex has more wavelet terms than the file declares");
    w->store.n = (int)n;
    w->store.bits = (int)bits;
    w->store.dim = PRT_WAVELET_DIM;
    w->store.vectors = vectors;
    return PRT_OK;
}

static prt_status load_factors(prt_context *ctx, const prt_transfer *t, prt__wavelet_set *w, const prt__chunk_in *c)
{
    const unsigned char *p = c->data;
    const uint64_t len = c->size;
    if (len < WBRF_HEADER) return bad(ctx, "corrupt .prt file: short BRDF factorization chunk");
    uint32_t k = prt__get32(p), terms = prt__get32(p + 4), computed = prt__get32(p + 8), res = prt__get32(p + 12), param = prt__get32(p + 16);
    uint64_t maps = (uint64_t)3 * computed * res * res * 4;
    /* Every factorization has the file's resolution, parameterization and at most its terms: the
     * renderer packs all of them into one array of that shape. */
    if (k < 1 || k > (uint32_t)t->brdf_count || w->factors[k - 1] || terms < 1 || terms > computed || terms > (uint32_t)w->terms ||
        computed > PRT_BRDF_MAX_TERMS || (int)res != w->brdf_resolution || res < 4 || res > 96 || param != (uint32_t)w->param ||
        WBRF_HEADER + 2 * maps != len)
        return bad(ctx, "corrupt .prt file: invalid BRDF factorization chunk");
    prt_brdf_factors *f = prt__brdf_factors_alloc((int)terms, (int)computed, (int)res, (prt_brdf_param)param);
    if (!f) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int ch = 0; ch < 3; ++ch) memcpy(f->sigma[ch], p + 24 + (size_t)ch * PRT_BRDF_MAX_TERMS * 4, PRT_BRDF_MAX_TERMS * 4);
    memcpy(f->light, p + WBRF_HEADER, maps);
    memcpy(f->view, p + WBRF_HEADER + maps, maps);
    prt__brdf_factors_finish(f);
    w->factors[k - 1] = f;
    if (!prt__all_finite(f->light, maps / 4) || !prt__all_finite(f->view, maps / 4)) return bad(ctx, "corrupt .prt file: non-finite BRDF maps");
    return PRT_OK;
}

static prt_status load_transport(prt_context *ctx, prt__wavelet_set *w, const prt__chunk_in *c)
{
    const unsigned char *p = c->data;
    const uint64_t len = c->size;
    prt__sparse_store *s = &w->store;
    const uint64_t cells = (uint64_t)s->vectors * s->n, ib = cells * 2, vb = cells * 3 * (uint64_t)(s->bits / 8);
    if (((ib + 3) & ~3ull) + ((vb + 3) & ~3ull) + s->vectors * 12 != len) return bad(ctx, "corrupt .prt file: wavelet transfer chunk size mismatch");
    const int n = s->n, bits = s->bits;
    const size_t vectors = s->vectors;
    prt_status st = prt__sparse_alloc(s, vectors, n, bits, PRT_WAVELET_DIM);
    if (st) return prt__fail(ctx, st, "out of memory");
    memcpy(s->index, p, ib);
    memcpy(s->values, p + ((ib + 3) & ~3ull), vb);
    memcpy(s->scale, p + ((ib + 3) & ~3ull) + ((vb + 3) & ~3ull), vectors * 12);
    for (uint64_t i = 0; i < cells; ++i)
        if (s->index[i] >= PRT_WAVELET_DIM) return bad(ctx, "corrupt .prt file: a wavelet index is out of range");
    if (!prt__all_finite(s->scale, vectors * 3)) return bad(ctx, "corrupt .prt file: non-finite wavelet scales");
    return PRT_OK;
}

static prt_status wavelet_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    (void)meta;
    prt__wavelet_set *w = prt__calloc(1, sizeof *w);
    if (!w) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = w;
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_WAVP);
    if (!c) return bad(ctx, "corrupt .prt file: wavelet parameter chunk missing");
    prt_status st = load_params(ctx, t, c);
    while (!st && (c = prt__chunk_take(chunks, count, CHUNK_WBRF))) st = load_factors(ctx, t, w, c);
    if (!st && !(c = prt__chunk_take(chunks, count, CHUNK_WAVT))) st = bad(ctx, "corrupt .prt file: wavelet transfer chunk missing");
    if (!st) st = load_transport(ctx, w, c);
    if (!st && prt__chunk_take(chunks, count, CHUNK_WAVP)) st = bad(ctx, "corrupt .prt file: two wavelet parameter chunks");
    if (!st && prt__chunk_take(chunks, count, CHUNK_WAVT)) st = bad(ctx, "corrupt .prt file: two wavelet transfer chunks");
    /* Every vertex's term count must match its material's factorization. */
    for (size_t v = 0; v < t->mesh.vertex_count && !st; ++v) {
        uint8_t mat = t->mesh.material[v];
        const prt_brdf_factors *f = mat ? w->factors[mat - 1] : NULL;
        if (w->term_count[v] != (f ? f->terms : 1)) st = bad(ctx, "corrupt .prt file: wavelet term counts do not match the materials");
    }
    if (!st) st = prt__wavelet_build_view_maps(t, w);
    return st;
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
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .bake_begin = wavelet_bake_begin,
    .free_state = prt__wavelet_set_free,
    .save = wavelet_save,
    .load = wavelet_load,
    .describe = wavelet_describe,
    .report = wavelet_report,
    .transfer_bytes = wavelet_bytes,
    .variant_count = wavelet_variant_count,
    .variant_name = wavelet_variant_name,
    .default_variant = wavelet_default_variant,
    .control_range = wavelet_control_range,
    .relight = wavelet_relight,
    .shade = wavelet_shade,
};
