/* Spectral relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): the
 * direct light per vertex (shadow rays, the environment's SH transfer, emitters: method.c on the
 * CPU) is the frame's vector, and every bounce is two products on the GPU - the projection onto
 * the spectral basis (each function's sum over its partition's vertices) and the gather through
 * the sparse transfer rows, clamped at zero and scaled by albedo x row scale / pi, as relight.c.
 * Each gather's rows are shown: the bounces add up to the indirect light. The tail (relight.c's
 * add_tail: a geometric rest of the series from the power of the last two bounces) is eight more:
 * each vertex's weight (the last bounce times the root of its ratio to the one before, a map), the
 * three area-weighted powers (per partition, then summed: one row each) and the weights times
 * the factor from those powers (a map reading the three rows). Files with a glossy final bounce
 * keep the CPU path. */
#include "methods/spectral/spectral.h"
#include "transfer/gpu_sums.h"

#include <math.h>
#include <string.h>

#define STR_(x) #x
#define STR(x) STR_(x)

/* The tail's weight per vertex: y (the last bounce) times the root of its ratio to a0 (the one
 * before), as add_tail. */
static const char *const TAIL_WEIGHT_GLSL =
    "vec3 r = mix(vec3(0.0), min(y / a0, vec3(" STR(PRT__SPECTRAL_TAIL_MAX_RATIO) ")), greaterThan(a0, vec3(0.0)));\n"
    "return y * sqrt(r);";

static void tail_weight(const float y[3], const float *const a[3], float out[3])
{
    for (int c = 0; c < 3; ++c) {
        const float r = a[0][c] > 0 ? fminf(y[c] / a[0][c], (float)PRT__SPECTRAL_TAIL_MAX_RATIO) : 0.0f;
        out[c] = y[c] * sqrtf(r);
    }
}

/* The weights y times add_tail's factor from the powers of the bounce before the last (a0), the
 * last (a1) and the weights (a2): q / (1 - q), q their ratio, rescaled to the last bounce's power. */
static const char *const TAIL_SCALE_GLSL =
    "vec3 q = mix(vec3(0.0), clamp(a1 / a0, vec3(0.0), vec3(" STR(PRT__SPECTRAL_TAIL_MAX_RATIO) ")), greaterThan(a0, vec3(0.0)));\n"
    "vec3 f = q / (vec3(1.0) - q);\n"
    "f = mix(vec3(0.0), min(f * a1 / a2, vec3(" STR(PRT__SPECTRAL_TAIL_MAX_RATIO) " / (1.0 - " STR(PRT__SPECTRAL_TAIL_MAX_RATIO) "))), greaterThan(a2, vec3(0.0)));\n"
    "return f * y;";

static void tail_scale(const float y[3], const float *const a[3], float out[3])
{
    const float R = (float)PRT__SPECTRAL_TAIL_MAX_RATIO, cap = R / (1.0f - R);
    for (int c = 0; c < 3; ++c) {
        float q = a[0][c] > 0 ? a[1][c] / a[0][c] : 0.0f;
        q = q > R ? R : q > 0 ? q : 0.0f;
        float f = q / (1.0f - q);
        f = a[2][c] > 0 ? fminf(f * a[1][c] / a[2][c], cap) : 0.0f;
        out[c] = f * y[c];
    }
}

/* The area-weighted sum of product `input`'s rows (one per vertex), as add_tail's bounce_power:
 * per partition, then the partitions in order. Returns the one-row product's index, or -1. */
static int add_power(prt__gpu_sums *g, const prt__spectral_basis *b, const float *area, int input, size_t nv)
{
    prt_render_product *p = prt__gpu_sums_add(g, input, b->partitions, b->member_start[b->partitions], false, 0, 0);
    if (!p) return -1;
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight;
    for (uint32_t q = 0; q <= b->partitions; ++q) start[q] = b->member_start[q];
    for (uint32_t i = 0; i < b->member_start[b->partitions]; ++i) {
        index[i] = b->members[i];
        w[(size_t)i * 3] = w[(size_t)i * 3 + 1] = w[(size_t)i * 3 + 2] = area[b->members[i]];
    }
    (void)nv;
    const int part = g->sums.product_count - 1;
    if (!(p = prt__gpu_sums_add(g, part, 1, b->partitions, false, 0, 0))) return -1;
    index = (uint32_t *)p->index;
    w = (float *)p->weight;
    ((uint32_t *)p->start)[1] = b->partitions;
    for (uint32_t q = 0; q < b->partitions; ++q) {
        index[q] = q;
        w[(size_t)q * 3] = w[(size_t)q * 3 + 1] = w[(size_t)q * 3 + 2] = 1.0f;
    }
    return g->sums.product_count - 1;
}

/* A product whose row v reads row v of `from` (weight 1): what a per-row map then rewrites. */
static prt_render_product *identity_product(prt__gpu_sums *g, int from, size_t nv, int shown)
{
    prt_render_product *p = prt__gpu_sums_add(g, from, nv, nv, false, 0, shown);
    if (!p) return NULL;
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight;
    for (size_t v = 0; v < nv; ++v) {
        start[v + 1] = (uint32_t)(v + 1);
        index[v] = (uint32_t)v;
        w[v * 3] = w[v * 3 + 1] = w[v * 3 + 2] = 1.0f;
    }
    return p;
}

/* The tail's products after the bounces' (last: the last bounce's product, before: the one before
 * it, -1 the frame's vector). */
static bool add_tail(prt__gpu_sums *g, const prt_transfer *t, const prt__spectral_basis *b, int before, int last)
{
    const prt__mesh *m = &t->mesh;
    const size_t nv = m->vertex_count;
    float *area = prt__calloc(nv ? nv : 1, sizeof(float));   /* as add_tail: a third of each triangle to each corner */
    if (!area) return false;
    prt__spectral_vertex_areas(m, area);
    /* Each vertex's weight: the last bounce's row (one entry of weight 1) through the map. */
    prt_render_product *p = identity_product(g, last, nv, 0);
    bool ok = p != NULL;
    if (ok) {
        p->map_glsl = TAIL_WEIGHT_GLSL;
        p->map_cpu = tail_weight;
        p->map_argc = 1;
        p->map_args[0] = before;
    }
    const int weight = g->sums.product_count - 1;
    const int p_before = ok ? add_power(g, b, area, before, nv) : -1, p_last = p_before >= 0 ? add_power(g, b, area, last, nv) : -1;
    const int p_w = p_last >= 0 ? add_power(g, b, area, weight, nv) : -1;
    free(area);
    if (p_w < 0 || !(p = identity_product(g, weight, nv, 1))) return false;
    p->map_glsl = TAIL_SCALE_GLSL;
    p->map_cpu = tail_scale;
    p->map_argc = 3;
    p->map_args[0] = p_before;
    p->map_args[1] = p_last;
    p->map_args[2] = p_w;
    return true;
}

static prt__gpu_sums *build(const prt_transfer *t, const prt__spectral_set *s, const float *albedo, int bounces, int tail)
{
    const size_t nv = t->mesh.vertex_count;
    const prt__spectral_basis *b = &s->basis;
    prt__gpu_sums *g = prt__gpu_sums_new(nv);
    if (!g) return NULL;
    for (int k = 0; k < bounces; ++k) {
        prt_render_product *p = prt__gpu_sums_add(g, k ? 2 * k - 1 : -1, b->functions, b->offset[nv], false, 0, 0);
        if (!p) { prt__gpu_sums_free(g); return NULL; }
        uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
        float *w = (float *)p->weight;
        /* Function first[q] + j of partition q: its value at each member, in member order. */
        uint32_t e = 0;
        for (uint32_t q = 0; q < b->partitions; ++q)
            for (uint32_t j = 0; j < b->count[q]; ++j) {
                start[b->first[q] + j] = e;
                for (uint32_t i = b->member_start[q]; i < b->member_start[q + 1]; ++i, ++e) {
                    const uint32_t v = b->members[i];
                    index[e] = v;
                    w[(size_t)e * 3] = w[(size_t)e * 3 + 1] = w[(size_t)e * 3 + 2] = b->values[b->offset[v] + j];
                }
            }
        start[b->functions] = e;
        p = prt__gpu_sums_add(g, 2 * k, nv, s->row_start[nv], true, 1, 1);
        if (!p) { prt__gpu_sums_free(g); return NULL; }
        start = (uint32_t *)p->start;
        index = (uint32_t *)p->index;
        w = (float *)p->weight;
        float *scale = (float *)p->scale;
        for (size_t v = 0; v <= nv; ++v) start[v] = (uint32_t)s->row_start[v];
        for (uint64_t i = 0; i < s->row_start[nv]; ++i) {
            index[i] = s->index[i];
            w[i * 3] = w[i * 3 + 1] = w[i * 3 + 2] = (float)s->value[i];
        }
        for (size_t v = 0; v < nv; ++v) {
            const float kk = s->row_scale[v] / (float)PRT_PI;
            for (int c = 0; c < 3; ++c) scale[v * 3 + c] = albedo[v * 3 + c] * kk;
        }
    }
    if (tail && !add_tail(g, t, b, bounces > 1 ? 2 * bounces - 3 : -1, 2 * bounces - 1)) { prt__gpu_sums_free(g); return NULL; }
    g->key[0] = bounces;
    g->key[1] = tail;
    return g;
}

bool prt__spectral_gpu_can(const prt_transfer *t, int bounces, int tail)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    return bounces >= 1 && !s->glossy_count && 2 * bounces + (tail ? 8 : 0) <= PRT__GPU_SUMS_MAX && b->offset[t->mesh.vertex_count] <= UINT32_MAX &&
           s->row_start[t->mesh.vertex_count] <= UINT32_MAX;
}

prt_status prt__spectral_gpu(prt_context *ctx, const prt_transfer *t, const float *albedo, const float *direct, int bounces, int tail, prt_relit *r)
{
    const prt__spectral_set *s = t->state;
    prt__spectral_cache *c = s->cache;
    const size_t nv = t->mesh.vertex_count;
    prt_status st = PRT_OK;
    pthread_mutex_lock(&c->lock);
    /* The scales hold albedo: a run-time albedo (--albedo-of) makes a new description. */
    if (!c->gpu || c->gpu->key[0] != bounces || c->gpu->key[1] != tail || !c->gpu_albedo || memcmp(c->gpu_albedo, albedo, nv * 3 * sizeof(float))) {
        if (!c->gpu_albedo) c->gpu_albedo = malloc(nv * 3 * sizeof(float));
        if (!c->gpu_albedo || !prt__gpu_sums_replace(&c->gpu, build(t, s, albedo, bounces, tail))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else memcpy(c->gpu_albedo, albedo, nv * 3 * sizeof(float));
    }
    const prt__gpu_sums *g = c->gpu;
    pthread_mutex_unlock(&c->lock);
    if (st) return st;
    if (!(r->gpu_vector = malloc(nv * 3 * sizeof(float)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(r->gpu_vector, direct, nv * 3 * sizeof(float));
    r->gpu_sums = &g->sums;
    return PRT_OK;
}
