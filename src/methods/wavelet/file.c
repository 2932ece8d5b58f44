/* The wavelet method's chunks in .prt files (docs/FORMAT.md): what it writes beside the
 * method-independent ones (transfer/file.c), and their loading, every count checked against the
 * chunk's size, the mesh and every other count before it sizes an allocation. */
#include "methods/wavelet/wavelet.h"

#define CHUNK_WAVP PRT__FOURCC('W', 'A', 'V', 'P')
#define CHUNK_WBRF PRT__FOURCC('W', 'B', 'R', 'F')
#define CHUNK_WAVT PRT__FOURCC('W', 'A', 'V', 'T')
#define WAVP_HEADER 48
#define WBRF_HEADER (24 + 3 * PRT_BRDF_MAX_TERMS * 4)

prt_status prt__wavelet_save(const prt_transfer *t, prt__chunk_list *l)
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

prt_status prt__wavelet_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
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
