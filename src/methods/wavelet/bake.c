/* All-frequency glossy transfer (Wang, Tran & Luebke 2005): per vertex and BRDF term k the
 * transport T_k = g_k V cos dw over a 6 x 64 x 64 cube map, Haar-transformed per face and cut to
 * its N largest coefficients (direct pass, eq. 3), then interreflection passes gathering the
 * previous pass's vectors through a coarser cube map of hit points (eq. 8):
 *   T^{i+1}_k(x) = sum_w [sum_l h_l(x~, -w) T^i_l(x~)] g_k(w) (1 - V(x, w)) cos dw.
 * Every vertex depends only on its own rays and the previous pass, so results are identical for
 * any thread count. */
#include "methods/wavelet/wavelet.h"
#include "core/cubemap.h"
#include "core/haar.h"
#include "geom/raycast.h"

#include <string.h>

#define FACE PRT_WAVELET_FACE
#define DIM PRT_WAVELET_DIM
#define PACKET 16
#define PASS_BITS 16   /* intermediate passes keep 16 bits so truncation, not rounding, dominates */

/* A table of cube map directions, ordered in 4 x 4 tiles so a packet's rays stay coherent. */
typedef struct dir_table {
    int count;
    float *dir;      /* [entry][3] */
    float *dw;       /* [entry] solid angle */
    int *texel;      /* [entry] texel of the 64 x 64 (direct) or gather cube map */
} dir_table;

static void dir_table_free(dir_table *t) { free(t->dir); free(t->dw); free(t->texel); }

/* res x res per face, each texel split into ss x ss samples; texel indices at res (not res * ss). */
static bool dir_table_build(dir_table *t, int res, int ss)
{
    const int n = res * ss;
    t->count = 6 * n * n;
    t->dir = malloc((size_t)t->count * 3 * sizeof(float));
    t->dw = malloc((size_t)t->count * sizeof(float));
    t->texel = malloc((size_t)t->count * sizeof(int));
    if (!t->dir || !t->dw || !t->texel) { dir_table_free(t); return false; }
    const int tile = n >= 4 ? 4 : n;
    int e = 0;
    for (int f = 0; f < 6; ++f)
        for (int ty = 0; ty < n; ty += tile)
            for (int tx = 0; tx < n; tx += tile)
                for (int y = ty; y < ty + tile; ++y)
                    for (int x = tx; x < tx + tile; ++x, ++e) {
                        prt__cube_texel(n, f, x, y, t->dir + (size_t)e * 3, &t->dw[e]);
                        t->texel[e] = (f * res + y / ss) * res + x / ss;
                    }
    return true;
}

typedef struct wjob {
    const prt__mesh *mesh;
    prt__raycaster rc;
    float *origins;
    float *frames;                    /* [vertex][9]: s, t, n */
    prt_brdf_factors *const *factors; /* per material */
    const uint8_t *term_count;
    const size_t *vec_start;
    int kmax;
    dir_table direct, gather;
} wjob;

static const prt_brdf_factors *vertex_factors(const wjob *j, size_t v)
{
    uint8_t m = j->mesh->material[v];
    return m ? j->factors[m - 1] : NULL;
}

/* Light-map values g[c * K + k] of vertex v towards world direction d (1 for Lambertian vertices). */
static void light_maps(const wjob *j, size_t v, const float d[3], float *g, int K)
{
    const prt_brdf_factors *f = vertex_factors(j, v);
    if (!f) { g[0] = g[1] = g[2] = 1.0f; return; }
    const float *fr = j->frames + v * 9;
    float w[3] = {prt__v3_dot(d, fr), prt__v3_dot(d, fr + 3), prt__v3_dot(d, fr + 6)};
    prt_brdf_factors_lookup(f, 0, K, w, g);
}

/* View-map values of vertex v seen from world direction d (pointing away from v); false below its
 * horizon. Lambertian vertices: albedo / pi. */
static bool view_maps(const wjob *j, size_t v, const float d[3], float *h, int K)
{
    const float *fr = j->frames + v * 9;
    float w[3] = {prt__v3_dot(d, fr), prt__v3_dot(d, fr + 3), prt__v3_dot(d, fr + 6)};
    if (w[2] <= 0.0f) return false;
    const prt_brdf_factors *f = vertex_factors(j, v);
    if (!f) {
        for (int c = 0; c < 3; ++c) h[c] = j->mesh->albedo[v * 3 + c] / (float)PRT_PI;
        return true;
    }
    prt_brdf_factors_lookup(f, 1, K, w, h);
    return true;
}

/* The next (up to) 16 table entries above the normal n from entry *e on, and their cosines. */
static int next_packet(const dir_table *t, const float n[3], int *e, int lane_entry[PACKET], float lane_cos[PACKET])
{
    int lanes = 0;
    for (; *e < t->count && lanes < PACKET; ++*e) {
        float c = prt__v3_dot(t->dir + (size_t)*e * 3, n);
        if (c <= 0.0f) continue;
        lane_entry[lanes] = *e;
        lane_cos[lanes++] = c;
    }
    return lanes;
}

static void haar_planes(float *planes, int count)
{
    for (int p = 0; p < count; ++p)
        for (int f = 0; f < 6; ++f) prt__haar2d_forward(planes + (size_t)p * DIM + (size_t)f * FACE * FACE, FACE);
}

/* Encodes K terms x 3 planes (or one grey plane for Lambertian vertices) into vectors from `first`. */
static void encode_terms(prt__sparse_store *s, size_t first, const float *planes, int K, bool grey, prt__sparse_scratch *w)
{
    for (int k = 0; k < K; ++k) {
        const float *r = planes + (size_t)k * 3 * DIM;
        if (grey) prt__sparse_encode(s, first + k, r, r, r, w);
        else prt__sparse_encode(s, first + k, r, r + DIM, r + 2 * DIM, w);
    }
}

static void direct_vertex(const wjob *j, size_t v, float *planes, prt__sparse_store *out, prt__sparse_scratch *w)
{
    const int K = j->term_count[v];
    const bool lambert = vertex_factors(j, v) == NULL;
    memset(planes, 0, (size_t)K * 3 * DIM * sizeof(float));
    const float *n = j->frames + v * 9 + 6, *org = j->origins + v * 3;
    const dir_table *t = &j->direct;
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    int lane_entry[PACKET], e = 0;
    float lane_cos[PACKET];
    float g[3 * PRT_BRDF_MAX_TERMS];
    int lanes;
    while ((lanes = next_packet(t, n, &e, lane_entry, lane_cos)) > 0) {
        _Alignas(64) int valid[PACKET];
        _Alignas(64) struct RTCRay16 r;
        prt__packet_rays(&r, valid, org, t->dir, lane_entry, lanes);
        rtcOccluded16(valid, j->rc.scene, &ictx, &r);
        for (int l = 0; l < lanes; ++l) {
            if (r.tfar[l] < 0.0f) continue;   /* blocked */
            const int en = lane_entry[l], texel = t->texel[en];
            const float wgt = lane_cos[l] * t->dw[en];
            if (lambert) { planes[texel] += wgt; continue; }
            light_maps(j, v, t->dir + (size_t)en * 3, g, K);
            for (int k = 0; k < K; ++k)
                for (int c = 0; c < 3; ++c) planes[((size_t)k * 3 + c) * DIM + texel] += g[c * K + k] * wgt;
        }
    }
    haar_planes(planes, lambert ? 1 : 3 * K);
    encode_terms(out, j->vec_start[v], planes, K, lambert, w);
}

/* Per-thread gathering state: weights per source vertex, [source term][receiver term][3]. */
typedef struct gather_state {
    int32_t *slot_of;        /* [vertex] -> entry, -1 when untouched */
    uint32_t *touched;       /* entries' vertices */
    float *weights;          /* [entry][kmax][kmax][3] */
    size_t count, capacity;
} gather_state;

static float *gather_entry(gather_state *gs, uint32_t v, int kmax)
{
    const size_t stride = (size_t)kmax * kmax * 3;
    if (gs->slot_of[v] < 0) {
        if (gs->count == gs->capacity) {
            size_t cap = gs->capacity ? 2 * gs->capacity : 256;
            float *w = realloc(gs->weights, cap * stride * sizeof(float));
            uint32_t *t = realloc(gs->touched, cap * sizeof(uint32_t));
            if (w) gs->weights = w;
            if (t) gs->touched = t;
            if (!w || !t) return NULL;
            gs->capacity = cap;
        }
        gs->slot_of[v] = (int32_t)gs->count;
        gs->touched[gs->count] = v;
        memset(gs->weights + gs->count * stride, 0, stride * sizeof(float));
        gs->count++;
    }
    return gs->weights + (size_t)gs->slot_of[v] * stride;
}

static bool bounce_vertex(const wjob *j, size_t x, const prt__sparse_store *prev, float *planes, gather_state *gs,
                          prt__sparse_store *out, prt__sparse_scratch *w)
{
    const prt__mesh *m = j->mesh;
    const int K = j->term_count[x], kmax = j->kmax;
    const bool lambert = vertex_factors(j, x) == NULL;
    const float *n = j->frames + x * 9 + 6, *org = j->origins + x * 3;
    const dir_table *t = &j->gather;
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    int lane_entry[PACKET], e = 0;
    float lane_cos[PACKET], g[3 * PRT_BRDF_MAX_TERMS], h[3 * PRT_BRDF_MAX_TERMS];
    gs->count = 0;
    int lanes;
    while ((lanes = next_packet(t, n, &e, lane_entry, lane_cos)) > 0) {
        _Alignas(64) int valid[PACKET];
        _Alignas(64) struct RTCRayHit16 rh;
        prt__packet_rayhits(&rh, valid, org, t->dir, lane_entry, lanes);
        rtcIntersect16(valid, j->rc.scene, &ictx, &rh);
        for (int l = 0; l < lanes; ++l) {
            if (rh.hit.geomID[l] == RTC_INVALID_GEOMETRY_ID) continue;
            const float *d = t->dir + (size_t)lane_entry[l] * 3;
            /* Only front faces emit (as in the SH bake, methods/sh/bake.c). */
            if (rh.hit.Ng_x[l] * d[0] + rh.hit.Ng_y[l] * d[1] + rh.hit.Ng_z[l] * d[2] >= 0.0f) continue;
            const float wgt = lane_cos[l] * t->dw[lane_entry[l]];
            float rw[3 * PRT_BRDF_MAX_TERMS];   /* receiver: g_k(w) cos dw, [k][c] */
            if (lambert) rw[0] = rw[1] = rw[2] = wgt;
            else {
                light_maps(j, x, d, g, K);
                for (int k = 0; k < K; ++k)
                    for (int c = 0; c < 3; ++c) rw[k * 3 + c] = g[c * K + k] * wgt;
            }
            /* The hit's nearest vertex stands for the point seen, as the paper's false-colour
             * cube map does: a third of the gathering that interpolating three vertices costs. */
            const uint32_t *tri = m->indices + (size_t)rh.hit.primID[l] * 3;
            const float bu = rh.hit.u[l], bv = rh.hit.v[l], bw = 1.0f - bu - bv;
            const uint32_t src = bw >= bu && bw >= bv ? tri[0] : bu >= bv ? tri[1] : tri[2];
            const float back[3] = {-d[0], -d[1], -d[2]};
            const int Ks = j->term_count[src];
            if (!view_maps(j, src, back, h, Ks)) continue;
            float *ew = gather_entry(gs, src, kmax);
            if (!ew) return false;
            for (int s = 0; s < Ks; ++s)
                for (int k = 0; k < K; ++k)
                    for (int c = 0; c < 3; ++c) ew[((size_t)s * kmax + k) * 3 + c] += h[c * Ks + s] * rw[k * 3 + c];
        }
    }
    memset(planes, 0, (size_t)K * 3 * DIM * sizeof(float));
    for (size_t i = 0; i < gs->count; ++i) {
        const uint32_t src = gs->touched[i];
        const float *ew = gs->weights + i * (size_t)kmax * kmax * 3;
        for (int s = 0; s < j->term_count[src]; ++s)
            for (int k = 0; k < K; ++k)
                prt__sparse_accumulate(prev, j->vec_start[src] + s, ew + ((size_t)s * kmax + k) * 3, planes + (size_t)k * 3 * DIM);
        gs->slot_of[src] = -1;
    }
    encode_terms(out, j->vec_start[x], planes, K, false, w);
    return true;
}

/* total = truncate(total + pass), vector by vector. */
static void add_pass(const wjob *j, size_t v, const prt__sparse_store *a, const prt__sparse_store *b, float *planes, prt__sparse_store *out,
                     prt__sparse_scratch *w)
{
    const int K = j->term_count[v];
    const float one[3] = {1, 1, 1};
    memset(planes, 0, (size_t)K * 3 * DIM * sizeof(float));
    for (int k = 0; k < K; ++k) {
        prt__sparse_accumulate(a, j->vec_start[v] + k, one, planes + (size_t)k * 3 * DIM);
        if (b) prt__sparse_accumulate(b, j->vec_start[v] + k, one, planes + (size_t)k * 3 * DIM);
    }
    encode_terms(out, j->vec_start[v], planes, K, false, w);
}

/* The bake as stages (transfer/method.h): the direct pass, then per bounce a gathering pass and
 * a truncated running sum, each over blocks of vertices. */
#define BLOCK 16

typedef enum { ST_DIRECT, ST_BOUNCE, ST_SUM } stage_kind;

typedef struct thread_scratch {
    float *planes;
    prt__sparse_scratch w;
    gather_state gs;
} thread_scratch;

typedef struct wbake {
    prt__bake_job base;
    prt_wavelet_bake_desc d;
    prt_transfer *t;
    prt__wavelet_set *ws;
    wjob j;
    size_t vectors;
    prt__sparse_store direct, prev, next, total, sum;
    thread_scratch *scratch;
    int nscratch;
    stage_kind current;
    int bounce;               /* the pass the current stage belongs to */
    const prt__sparse_store *from, *a, *b;
    prt__sparse_store *out;
} wbake;

static prt_status run_unit(prt__bake_job *base, uint64_t unit, int thread)
{
    wbake *wb = (wbake *)base;
    thread_scratch *sc = &wb->scratch[thread];
    const size_t nv = wb->t->mesh.vertex_count;
    for (size_t v = unit * BLOCK; v < nv && v < (unit + 1) * BLOCK; ++v) {
        if (wb->current == ST_DIRECT) direct_vertex(&wb->j, v, sc->planes, wb->out, &sc->w);
        else if (wb->current == ST_SUM) add_pass(&wb->j, v, wb->a, wb->b, sc->planes, wb->out, &sc->w);
        else if (!bounce_vertex(&wb->j, v, wb->a, sc->planes, &sc->gs, wb->out, &sc->w))
            return prt__fail(base->ctx, PRT_ERR_NO_MEMORY, "out of memory in the wavelet bake (bounce %d)", wb->bounce);
    }
    return PRT_OK;
}

/* Checkpoint records: the unit's vectors of the pass it wrote. */
static void unit_vectors(const wbake *wb, uint64_t unit, size_t *first, size_t *count)
{
    const size_t nv = wb->t->mesh.vertex_count, v0 = unit * BLOCK, v1 = v0 + BLOCK < nv ? v0 + BLOCK : nv;
    *first = wb->j.vec_start[v0];
    *count = wb->j.vec_start[v1 - 1] + (size_t)wb->j.term_count[v1 - 1] - *first;
}

static void save_unit(prt__bake_job *base, uint64_t unit, prt__bytes *out)
{
    wbake *wb = (wbake *)base;
    size_t first, count;
    unit_vectors(wb, unit, &first, &count);
    prt__sparse_save(wb->out, first, count, out);
}

static bool load_unit(prt__bake_job *base, uint64_t unit, const unsigned char *data, size_t size)
{
    wbake *wb = (wbake *)base;
    size_t first, count;
    unit_vectors(wb, unit, &first, &count);
    return prt__sparse_load(wb->out, first, count, data, size);
}

static prt_status scratch_init(wbake *wb, int threads)
{
    const size_t nv = wb->t->mesh.vertex_count;
    wb->scratch = prt__calloc((size_t)threads, sizeof *wb->scratch);
    if (!wb->scratch) return prt__fail(wb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
    wb->nscratch = threads;
    for (int i = 0; i < threads; ++i) {
        thread_scratch *sc = &wb->scratch[i];
        sc->planes = malloc((size_t)wb->j.kmax * 3 * DIM * sizeof(float));
        bool ok = sc->planes && prt__sparse_scratch_init(&sc->w, DIM);
        if (ok && wb->d.bounces) {
            sc->gs.slot_of = malloc(nv * sizeof(int32_t));
            if (sc->gs.slot_of) memset(sc->gs.slot_of, 0xff, nv * sizeof(int32_t));
            else ok = false;
        }
        if (!ok) return prt__fail(wb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    return PRT_OK;
}

static prt_status wavelet_stage(prt__bake_job *base, int index, prt__stage *out)
{
    wbake *wb = (wbake *)base;
    const prt_wavelet_bake_desc *d = &wb->d;
    prt_status st;
    if (index == 0 && (st = scratch_init(wb, base->threads))) return st;
    /* Finish the previous stage's bookkeeping. */
    if (index > 0 && wb->current == ST_SUM) {
        /* Running total, truncated after each pass (as the paper does); next becomes the source
         * of the following pass. */
        if (wb->bounce > 1) prt__sparse_free(&wb->total);
        wb->total = wb->sum;
        memset(&wb->sum, 0, sizeof wb->sum);
        prt__sparse_store tmp = wb->prev;
        wb->prev = wb->next;
        wb->next = tmp;
        wb->from = &wb->prev;
    }
    if (index > 0 && wb->current == ST_DIRECT) wb->from = &wb->direct;
    if (index == 0) {
        wb->current = ST_DIRECT;
        wb->out = d->bounces ? &wb->direct : &wb->ws->store;
        if ((st = prt__sparse_alloc(wb->out, wb->vectors, d->coefficients, d->bounces ? PASS_BITS : d->bits, DIM))) return st;
        snprintf(out->name, sizeof out->name, "wavelet direct");
    } else if (wb->current == ST_DIRECT || wb->current == ST_SUM) {
        if (wb->bounce == d->bounces) return PRT_OK;   /* done */
        wb->bounce++;
        wb->current = ST_BOUNCE;
        wb->a = wb->from;
        wb->out = &wb->next;
        if (!wb->next.index && (st = prt__sparse_alloc(&wb->next, wb->vectors, d->coefficients, PASS_BITS, DIM))) return st;
        snprintf(out->name, sizeof out->name, "wavelet bounce %d/%d", wb->bounce, d->bounces);
    } else {
        const bool last = wb->bounce == d->bounces;
        wb->current = ST_SUM;
        wb->a = wb->bounce == 1 ? &wb->direct : &wb->total;
        wb->b = &wb->next;
        wb->out = &wb->sum;
        if ((st = prt__sparse_alloc(&wb->sum, wb->vectors, d->coefficients, last ? d->bits : PASS_BITS, DIM))) return st;
        snprintf(out->name, sizeof out->name, "wavelet sum");
    }
    out->units = (wb->t->mesh.vertex_count + BLOCK - 1) / BLOCK;
    out->run = run_unit;
    out->save_unit = save_unit;
    out->load_unit = load_unit;
    return PRT_OK;
}

static prt_status wavelet_finish(prt__bake_job *base, prt_transfer *t)
{
    wbake *wb = (wbake *)base;
    if (wb->d.bounces) {
        wb->ws->store = wb->total;
        memset(&wb->total, 0, sizeof wb->total);
    }
    return prt__wavelet_build_view_maps(t, wb->ws);
}

static void wavelet_release(prt__bake_job *base)
{
    wbake *wb = (wbake *)base;
    prt__raycaster_release(&wb->j.rc);
    free(wb->j.origins);
    free(wb->j.frames);
    dir_table_free(&wb->j.direct);
    dir_table_free(&wb->j.gather);
    for (int i = 0; i < wb->nscratch; ++i) {
        thread_scratch *sc = &wb->scratch[i];
        free(sc->planes);
        prt__sparse_scratch_free(&sc->w);
        free(sc->gs.slot_of); free(sc->gs.touched); free(sc->gs.weights);
    }
    free(wb->scratch);
    prt__sparse_free(&wb->direct);
    prt__sparse_free(&wb->prev);
    prt__sparse_free(&wb->next);
    prt__sparse_free(&wb->total);
    prt__sparse_free(&wb->sum);
    free(wb);
}

prt_status prt__wavelet_bake_begin(prt_context *ctx, const prt_wavelet_bake_desc *desc_in, prt_transfer *t, prt__bake_job **out)
{
    prt_wavelet_bake_desc d = desc_in ? *desc_in : (prt_wavelet_bake_desc){0};
    if (!d.terms) d.terms = 4;
    if (!d.coefficients) d.coefficients = 128;
    if (!d.bits) d.bits = 8;
    if (!d.supersample) d.supersample = 2;
    if (!d.gather_resolution) d.gather_resolution = 32;
    if (!d.brdf_resolution) d.brdf_resolution = 48;
    if (d.terms < 1 || d.terms > PRT_BRDF_MAX_TERMS) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "BRDF terms %d out of range 1..%d", d.terms, PRT_BRDF_MAX_TERMS);
    if (d.coefficients < 1 || d.coefficients > DIM) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "wavelet coefficients %d out of range 1..%d", d.coefficients, DIM);
    if (d.bits != 8 && d.bits != 16) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "quantization bits must be 8 or 16, not %d", d.bits);
    if (d.supersample < 1 || d.supersample > 4) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "supersampling %d out of range 1..4", d.supersample);
    if (d.bounces < 0 || d.bounces > 8) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range 0..8", d.bounces);
    if (d.gather_resolution < 4 || d.gather_resolution > 64) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "gather resolution %d out of range 4..64", d.gather_resolution);
    if (d.brdf_resolution < 4 || d.brdf_resolution > 96) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "BRDF resolution %d out of range 4..96", d.brdf_resolution);
    if (d.param > PRT_BRDF_PARAM_POLAR) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "unknown BRDF parameterization %d", (int)d.param);
    if (d.ray_offset < 0 || !isfinite(d.ray_offset)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ray offset must be >= 0");
    if (d.brdf) {
        prt_status bst = prt_brdf_validate(d.brdf);
        if (bst) return prt__fail(ctx, bst, "BRDF: %s", prt_last_error());
    }
    wbake *wb = prt__calloc(1, sizeof *wb);
    prt__wavelet_set *ws = prt__calloc(1, sizeof *ws);
    if (!wb || !ws) { free(wb); free(ws); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    wb->base.stage = wavelet_stage;
    wb->base.finish = wavelet_finish;
    wb->base.release = wavelet_release;
    wb->base.ctx = ctx;
    wb->d = d;
    wb->t = t;
    wb->ws = ws;
    t->state = ws;   /* owned by t from here on */
    const size_t nv = t->mesh.vertex_count;
    if (d.brdf) {   /* one BRDF everywhere: it becomes the only material, its kd the albedo */
        t->brdf_count = 1;
        t->brdfs[0] = *d.brdf;
        float kd[3];
        prt_brdf_lambert_albedo(d.brdf, kd);
        for (size_t v = 0; v < nv; ++v) {
            t->mesh.material[v] = 1;
            memcpy(t->mesh.albedo + v * 3, kd, sizeof kd);
        }
    }
    ws->terms = d.terms;
    ws->supersample = d.supersample;
    ws->bounces = d.bounces;
    ws->gather_resolution = d.gather_resolution;
    ws->brdf_resolution = d.brdf_resolution;
    ws->param = d.param;
    wjob *j = &wb->j;
    j->mesh = &t->mesh;
    prt_status st = PRT_OK;
    /* Factor every material with a glossy part that some vertex uses. */
    bool used[PRT__MAX_BRDFS + 1] = {false};
    for (size_t v = 0; v < nv; ++v) used[t->mesh.material[v]] = true;
    for (int k = 1; k <= t->brdf_count && !st; ++k) {
        if (!used[k] || !prt_brdf_is_glossy(&t->brdfs[k - 1])) continue;
        prt_brdf_factor_desc fd = {d.terms, d.brdf_resolution, d.param};
        if ((st = prt_brdf_factor(&t->brdfs[k - 1], &fd, &ws->factors[k - 1]))) st = prt__fail(ctx, st, "material %d: %s", k, prt_last_error());
    }
    ws->term_count = prt__calloc(nv, 1);
    ws->vec_start = prt__calloc(nv + 1, sizeof(size_t));
    j->frames = prt__calloc(nv * 9, sizeof(float));
    if (!st && (!ws->term_count || !ws->vec_start || !j->frames)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) {
        j->factors = ws->factors;
        j->kmax = 1;
        for (size_t v = 0; v < nv; ++v) {
            uint8_t mat = t->mesh.material[v];
            ws->term_count[v] = (uint8_t)(mat && ws->factors[mat - 1] ? d.terms : 1);
            if (ws->term_count[v] > j->kmax) j->kmax = ws->term_count[v];
            float *fr = j->frames + v * 9;
            memcpy(fr + 6, t->mesh.normals + v * 3, 3 * sizeof(float));
            prt_brdf_frame(fr + 6, fr, fr + 3);
        }
        ws->terms = j->kmax;   /* K-vectors are this long: 1 when every vertex is Lambertian */
        prt__wavelet_index(ws, nv, &wb->vectors);
        j->term_count = ws->term_count;
        j->vec_start = ws->vec_start;
        if (!dir_table_build(&j->direct, FACE, d.supersample) || (d.bounces && !dir_table_build(&j->gather, d.gather_resolution, 1)))
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    if (!st) st = prt__raycaster_create(ctx, &t->mesh, &j->rc);
    const float offset = d.ray_offset > 0 ? d.ray_offset : prt__ray_offset(&t->mesh);
    if (!st) st = prt__vertex_origins(&t->mesh, offset, &j->origins);
    if (!st) st = prt__unbury_origins(ctx, &j->rc, &t->mesh, offset, j->origins, NULL, PRT_LOG_INFO);
    if (st) { wavelet_release(&wb->base); return st; }
    *out = &wb->base;
    return PRT_OK;
}

static prt_status begin_from_desc(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job)
{
    (void)scene;
    return prt__wavelet_bake_begin(ctx, desc, t, job);
}

prt_status prt_bake_wavelet(prt_context *ctx, const prt_scene *scene, const prt_wavelet_bake_desc *desc, prt_transfer **out)
{
    prt_bake_run_desc run = {.progress = desc ? desc->progress : NULL, .progress_user = desc ? desc->progress_user : NULL};
    return prt__bake_with(ctx, scene, &prt__method_wavelet, begin_from_desc, desc, &run, out);
}
