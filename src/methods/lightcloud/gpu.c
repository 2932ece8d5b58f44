/* Light-cloud relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): per
 * zone, the cloud weights summed into its merged lights and every CPCA cluster mean and basis
 * vector dotted with them on the CPU (eq. 13's x^m = X^m w and b_i = B_i w: a few hundred dot
 * products a zone); each vertex's share - its cluster's mean plus its coefficients times the
 * basis projections - summed on the GPU. Raw zones upload their responses and take the merged
 * lights' weights as the frame's vector. The diffuse part only: glossy exit vectors stay
 * relight.c's. */
#include "methods/lightcloud/lightcloud.h"
#include "transfer/gpu_sums.h"

#include <string.h>

/* Where each zone's part of the frame's vector starts ([zone + 1]). */
static size_t zone_length(const prt__lightcloud_set *s, uint32_t z, int K)
{
    const prt__lightcloud_block *b = &s->zones[z].diffuse;
    if (!b->vertices) return 0;
    return b->cpca ? (size_t)b->cpca->clusters + b->cpca->vectors_total : (size_t)s->zones[z].lights * (size_t)K;
}

static prt__gpu_sums *build(const prt_transfer *t, const prt__lightcloud_set *s)
{
    const size_t nv = t->mesh.vertex_count;
    const int K = s->lobes;
    size_t length = 0, entries = 0;
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_block *b = &s->zones[z].diffuse;
        length += zone_length(s, z, K);
        entries += b->cpca ? b->vertices + b->cpca->weights_total : (size_t)b->vertices * s->zones[z].lights * (size_t)K;
    }
    prt__gpu_sums *g = prt__gpu_sums_new(length);
    prt_render_product *p = g ? prt__gpu_sums_add(g, -1, nv, entries, false, 0, 1) : NULL;
    uint32_t *count = prt__calloc(nv + 1, sizeof(uint32_t));
    if (!p || !count) { free(count); prt__gpu_sums_free(g); return NULL; }
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight;
    /* Rows per vertex first (each vertex lies in one zone), then entries in place. */
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_block *b = &s->zones[z].diffuse;
        const uint32_t *members = s->members + s->member_start[z];
        for (uint32_t r = 0; r < b->vertices; ++r)
            count[members[r]] = b->cpca ? 1 + b->cpca->counts[b->cpca->cluster_of[r]] : s->zones[z].lights * (uint32_t)K;
    }
    for (size_t v = 0; v < nv; ++v) start[v + 1] = start[v] + count[v];
    free(count);
    size_t base = 0;
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_block *b = &s->zones[z].diffuse;
        const uint32_t *members = s->members + s->member_start[z];
        const size_t L = (size_t)s->zones[z].lights * K;
        for (uint32_t r = 0; r < b->vertices; ++r) {
            uint32_t e = start[members[r]];
            if (b->cpca) {
                const prt__cpca *c = b->cpca;
                const uint32_t cl = c->cluster_of[r];
                index[e] = (uint32_t)(base + cl);
                w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = 1.0f;
                e++;
                for (uint32_t j = 0; j < c->counts[cl]; ++j, ++e) {
                    index[e] = (uint32_t)(base + (size_t)c->clusters + c->basis_start[cl] + j);
                    w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = c->weights[c->weight_start[r] + j];
                }
            } else {
                const float *x = b->raw + (size_t)r * b->dim;   /* [channel][light] */
                for (size_t l = 0; l < L; ++l, ++e) {
                    index[e] = (uint32_t)(base + l);
                    for (int c = 0; c < 3; ++c) w[e * 3 + c] = x[(size_t)c * L + l];
                }
            }
        }
        base += zone_length(s, z, K);
    }
    return g;
}

prt_status prt__lightcloud_gpu(prt_context *ctx, const prt_transfer *t, const float *w, prt_relit *r)
{
    const prt__lightcloud_set *s = t->state;
    prt__lightcloud_cache *cache = s->cache;
    pthread_mutex_lock(&cache->lock);
    if (!cache->gpu) cache->gpu = build(t, s);
    prt__gpu_sums *g = cache->gpu;
    pthread_mutex_unlock(&cache->lock);
    if (!g) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const int K = s->lobes;
    float *x = r->gpu_vector = prt__calloc(g->sums.vector_length * 3 + 3, sizeof(float));
    float *W = malloc(((size_t)s->cloud_count * K * 3 + 3) * sizeof(float));
    if (!x || !W) { free(W); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    size_t base = 0;
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_zone *zone = &s->zones[z];
        const prt__lightcloud_block *b = &zone->diffuse;
        const size_t len = zone_length(s, z, K);
        if (!len) continue;
        /* relight.c's merged-light weights, in its order. */
        const size_t L = (size_t)zone->lights * K;
        memset(W, 0, L * 3 * sizeof(float));
        for (uint32_t j = 0; j < s->cloud_count; ++j)
            for (int k = 0; k < K; ++k)
                for (int c = 0; c < 3; ++c) W[((size_t)zone->light_of[j] * K + k) * 3 + c] += w[((size_t)j * K + k) * 3 + c];
        float *out = x + base * 3;
        if (!b->cpca) {
            memcpy(out, W, L * 3 * sizeof(float));
        } else {
            const prt__cpca *cp = b->cpca;
            for (size_t vec = 0; vec < len; ++vec) {
                const float *v = vec < (size_t)cp->clusters ? cp->means + vec * cp->dim : cp->basis + (vec - cp->clusters) * cp->dim;
                for (int c = 0; c < 3; ++c) {
                    const float *xr = v + (size_t)c * L;
                    float sum = 0;
                    for (size_t l = 0; l < L; ++l) sum += xr[l] * W[l * 3 + c];
                    out[vec * 3 + c] = sum;
                }
            }
        }
        base += len;
    }
    free(W);
    r->gpu_sums = &g->sums;
    return PRT_OK;
}
