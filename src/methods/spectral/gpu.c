/* Spectral relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): the
 * direct light per vertex (shadow rays, the environment's SH transfer, emitters: method.c on the
 * CPU) is the frame's vector, and every bounce is two products on the GPU - the projection onto
 * the spectral basis (each function's sum over its partition's vertices) and the gather through
 * the sparse transfer rows, clamped at zero and scaled by albedo x row scale / pi, as relight.c.
 * Each gather's rows are shown: the bounces add up to the indirect light. The tail (a geometric
 * rest of the series from the power of the last two bounces, summed over the mesh) stays on the
 * CPU: files relit with it, or with a glossy final bounce, keep the CPU path. */
#include "methods/spectral/spectral.h"
#include "transfer/gpu_sums.h"

#include <string.h>

static prt__gpu_sums *build(const prt_transfer *t, const prt__spectral_set *s, const float *albedo, int bounces)
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
    g->key[0] = bounces;
    return g;
}

bool prt__spectral_gpu_can(const prt_transfer *t, int bounces, int tail)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    return bounces >= 1 && !tail && !s->glossy_count && 2 * bounces <= PRT__GPU_SUMS_MAX && b->offset[t->mesh.vertex_count] <= UINT32_MAX &&
           s->row_start[t->mesh.vertex_count] <= UINT32_MAX;
}

prt_status prt__spectral_gpu(prt_context *ctx, const prt_transfer *t, const float *albedo, const float *direct, int bounces, prt_relit *r)
{
    const prt__spectral_set *s = t->state;
    prt__spectral_cache *c = s->cache;
    const size_t nv = t->mesh.vertex_count;
    prt_status st = PRT_OK;
    pthread_mutex_lock(&c->lock);
    /* The scales hold albedo: a run-time albedo (--albedo-of) makes a new description. */
    if (!c->gpu || c->gpu->key[0] != bounces || !c->gpu_albedo || memcmp(c->gpu_albedo, albedo, nv * 3 * sizeof(float))) {
        if (!c->gpu_albedo) c->gpu_albedo = malloc(nv * 3 * sizeof(float));
        if (!c->gpu_albedo || !prt__gpu_sums_replace(&c->gpu, build(t, s, albedo, bounces))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
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
