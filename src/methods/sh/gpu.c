/* Diffuse SH relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): each
 * vertex's transfer dotted with the light on the GPU. Uncompressed (and quantized: coeffs hold the
 * dequantized values) sets upload their rows and take the light's SH as the frame's vector;
 * clustered PCA sets upload each vertex's cluster and weights, and the frame's vector is every
 * cluster mean and PCA vector projected on the light on the CPU (a few thousand dot products), as
 * the course notes split it. One-channel sets are scaled by albedo per vertex, as relight.c. */
#include "methods/sh/sh.h"
#include "transfer/gpu_sums.h"

#include <string.h>

/* The description of set k at n = order^2 coefficients of light. */
static prt__gpu_sums *build(const prt_transfer *t, const prt__sh_state *sh, int k, int n)
{
    const prt__sh_set *s = &sh->sets[k];
    const size_t nv = t->mesh.vertex_count;
    const int stride = sh->order * sh->order, ch = s->channels;
    const prt__cpca *c = s->cpca;
    const size_t length = c ? (size_t)c->clusters + c->vectors_total : (size_t)n;
    prt__gpu_sums *g = prt__gpu_sums_new(length);
    if (!g) return NULL;
    const size_t entries = c ? nv + c->weights_total : nv * (size_t)n;
    prt_render_product *p = prt__gpu_sums_add(g, -1, nv, entries, ch == 1, 0, 1);
    if (!p) { prt__gpu_sums_free(g); return NULL; }
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight, *scale = (float *)p->scale;
    uint32_t e = 0;
    for (size_t v = 0; v < nv; ++v) {
        start[v] = e;
        if (c) {
            const uint32_t cl = c->cluster_of[v];
            index[e] = cl;
            w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = 1.0f;
            e++;
            for (uint32_t j = 0; j < c->counts[cl]; ++j, ++e) {
                index[e] = (uint32_t)(c->clusters + c->basis_start[cl] + j);
                w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = c->weights[c->weight_start[v] + j];
            }
        } else {
            const float *row = s->coeffs + v * (size_t)ch * stride;
            for (int i = 0; i < n; ++i, ++e) {
                index[e] = (uint32_t)i;
                for (int l = 0; l < 3; ++l) w[e * 3 + l] = row[(ch == 3 ? l * stride : 0) + i];
            }
        }
        if (scale) memcpy(scale + v * 3, t->mesh.albedo + v * 3, 3 * sizeof(float));
    }
    start[nv] = e;
    g->key[0] = k;
    g->key[1] = n;
    return g;
}

bool prt__sh_gpu_can(const prt__sh_state *s, int k) { return k >= 0 && k <= 2 && s->sets[k].channels; }

prt_status prt__sh_gpu_relight(prt_context *ctx, const prt_transfer *t, int k, const prt_sh_light *light, prt_relit *r)
{
    prt__sh_state *sh = t->state;
    const int order = light->order < sh->order ? light->order : sh->order, n = order * order;
    pthread_mutex_lock(sh->lock);
    if (!sh->gpu[k] || sh->gpu[k]->key[1] != n) prt__gpu_sums_replace(&sh->gpu[k], build(t, sh, k, n));
    const prt__gpu_sums *g = sh->gpu[k];
    pthread_mutex_unlock(sh->lock);
    if (!g || g->key[1] != n) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = prt__relit_alloc(ctx, t, r, false);
    if (st) return st;
    const size_t length = g->sums.vector_length;
    float *x = r->gpu_vector = prt__calloc(length * 3, sizeof(float));
    if (!x) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const prt__sh_set *s = &sh->sets[k];
    const prt__cpca *c = s->cpca;
    if (!c) {
        for (int i = 0; i < n; ++i)
            for (int l = 0; l < 3; ++l) x[i * 3 + l] = light->coeffs[l][i];
    } else {
        /* relight.c's projections, in its order. */
        const int stride = sh->order * sh->order, ch = s->channels;
        for (size_t row = 0; row < length; ++row) {
            const float *v = row < (size_t)c->clusters ? c->means + row * c->dim : c->basis + (row - (size_t)c->clusters) * c->dim;
            for (int l = 0; l < 3; ++l) {
                const float *seg = v + (ch == 3 ? l * stride : 0);
                float sum = 0;
                for (int i = 0; i < n; ++i) sum += seg[i] * light->coeffs[l][i];
                x[row * 3 + l] = sum;
            }
        }
    }
    r->gpu_sums = &g->sums;
    return PRT_OK;
}
