/* Light-cloud relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): per
 * zone, the cloud weights summed into its merged lights and every CPCA cluster mean and basis
 * vector dotted with them on the CPU (eq. 13's x^m = X^m w and b_i = B_i w: a few hundred dot
 * products a zone); each vertex's share - its cluster's mean plus its coefficients times the
 * basis projections - summed on the GPU. Raw zones upload their responses and take the merged
 * lights' weights as the frame's vector. Glossy vertices' exit vectors (16 SH coefficients a
 * channel) are a second product the same way, one row per coefficient, drawn per pixel; their
 * emitted part (emit_sh times the lighting's emission) reads the vector's last entry. The frame's
 * vector: every zone's diffuse section, then every zone's glossy section, then the emission. */
#include "methods/lightcloud/lightcloud.h"
#include "transfer/gpu_sums.h"

#include <string.h>

/* Zone z's section of the frame's vector for its diffuse (glossy 0) or glossy block: the merged
 * lights' weights (raw) or per mean and basis vector its projection (per exit coefficient). */
static size_t zone_length(const prt__lightcloud_set *s, uint32_t z, int K, int glossy)
{
    const prt__lightcloud_block *b = glossy ? &s->zones[z].glossy : &s->zones[z].diffuse;
    if (!b->vertices) return 0;
    return b->cpca ? ((size_t)b->cpca->clusters + b->cpca->vectors_total) * (glossy ? 16 : 1) : (size_t)s->zones[z].lights * (size_t)K;
}

static size_t total_length(const prt__lightcloud_set *s, int glossy)
{
    size_t n = 0;
    for (uint32_t z = 0; z < s->zone_count; ++z) n += zone_length(s, z, s->lobes, glossy);
    return n;
}

/* The glossy vertices' exit rows (vertex v's coefficient k at row v * 16 + k), reading the glossy
 * sections from gbase and the emission at entry emit. */
static bool build_exit(const prt_transfer *t, const prt__lightcloud_set *s, prt__gpu_sums *g, size_t gbase, size_t emit)
{
    const size_t nv = t->mesh.vertex_count;
    const int K = s->lobes;
    size_t entries = 0;
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_block *b = &s->zones[z].glossy;
        entries += 16 * (b->cpca ? b->vertices + b->cpca->weights_total : (size_t)b->vertices * s->zones[z].lights * (size_t)K);
    }
    if (s->emit_sh) entries += 16 * (size_t)s->glossy_count;
    prt_render_product *p = prt__gpu_sums_add(g, -1, nv * 16, entries, false, 0, 0);
    uint32_t *count = prt__calloc(nv * 16 + 1, sizeof(uint32_t));
    if (!p || !count) { free(count); return false; }
    p->exit = 1;
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight;
    /* Row lengths first, then entries in place (member order of each zone's glossy vertices). */
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_block *b = &s->zones[z].glossy;
        const uint32_t *members = s->members + s->member_start[z];
        for (uint32_t i = 0, r = 0; i < s->member_start[z + 1] - s->member_start[z] && r < b->vertices; ++i) {
            const uint32_t v = members[i];
            if (s->glossy_of[v] == UINT32_MAX) continue;
            const uint32_t n = (b->cpca ? 1 + b->cpca->counts[b->cpca->cluster_of[r]] : s->zones[z].lights * (uint32_t)K) + (s->emit_sh ? 1 : 0);
            for (int k = 0; k < 16; ++k) count[v * 16 + (size_t)k] = n;
            r++;
        }
    }
    for (size_t row = 0; row < nv * 16; ++row) start[row + 1] = start[row] + count[row];
    free(count);
    size_t base = gbase;
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_block *b = &s->zones[z].glossy;
        const uint32_t *members = s->members + s->member_start[z];
        const size_t L = (size_t)s->zones[z].lights * K;
        for (uint32_t i = 0, r = 0; i < s->member_start[z + 1] - s->member_start[z] && r < b->vertices; ++i) {
            const uint32_t v = members[i];
            if (s->glossy_of[v] == UINT32_MAX) continue;
            for (int k = 0; k < 16; ++k) {
                uint32_t e = start[v * 16 + (size_t)k];
                if (b->cpca) {
                    const prt__cpca *c = b->cpca;
                    const uint32_t cl = c->cluster_of[r];
                    index[e] = (uint32_t)(base + (size_t)cl * 16 + k);
                    w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = 1.0f;
                    e++;
                    for (uint32_t j = 0; j < c->counts[cl]; ++j, ++e) {
                        index[e] = (uint32_t)(base + ((size_t)c->clusters + c->basis_start[cl] + j) * 16 + k);
                        w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = c->weights[c->weight_start[r] + j];
                    }
                } else {
                    const float *x = b->raw + (size_t)r * b->dim;   /* [channel][coefficient][light] */
                    for (size_t l = 0; l < L; ++l, ++e) {
                        index[e] = (uint32_t)(base + l);
                        for (int c = 0; c < 3; ++c) w[e * 3 + c] = x[((size_t)c * 16 + k) * L + l];
                    }
                }
                if (s->emit_sh) {
                    index[e] = (uint32_t)emit;
                    for (int c = 0; c < 3; ++c) w[e * 3 + c] = s->emit_sh[(size_t)s->glossy_of[v] * 48 + c * 16 + k];
                }
            }
            r++;
        }
        base += zone_length(s, z, K, 1);
    }
    return true;
}

static prt__gpu_sums *build(const prt_transfer *t, const prt__lightcloud_set *s)
{
    const size_t nv = t->mesh.vertex_count;
    const int K = s->lobes;
    const size_t dlen = total_length(s, 0), glen = s->glossy_count ? total_length(s, 1) : 0;
    size_t entries = 0;
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_block *b = &s->zones[z].diffuse;
        entries += b->cpca ? b->vertices + b->cpca->weights_total : (size_t)b->vertices * s->zones[z].lights * (size_t)K;
    }
    prt__gpu_sums *g = prt__gpu_sums_new(dlen + glen + (s->glossy_count ? 1 : 0));
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
        base += zone_length(s, z, K, 0);
    }
    if (s->glossy_count && !build_exit(t, s, g, dlen, dlen + glen)) { prt__gpu_sums_free(g); return NULL; }
    return g;
}

/* Zone z's block (diffuse: per 1, glossy: per 16) under its merged lights' weights W ([light][c])
 * into out, as the zone's section of the frame's vector. */
static void fill(const prt__lightcloud_block *b, size_t L, int per, const float *W, float *out)
{
    if (!b->cpca) {
        memcpy(out, W, L * 3 * sizeof(float));
        return;
    }
    const prt__cpca *cp = b->cpca;
    for (size_t vec = 0; vec < (size_t)cp->clusters + cp->vectors_total; ++vec) {
        const float *v = vec < (size_t)cp->clusters ? cp->means + vec * cp->dim : cp->basis + (vec - cp->clusters) * cp->dim;
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < per; ++k) {
                const float *xr = v + ((size_t)c * per + k) * L;
                float sum = 0;
                for (size_t l = 0; l < L; ++l) sum += xr[l] * W[l * 3 + c];
                out[(vec * per + k) * 3 + c] = sum;
            }
    }
}

prt_status prt__lightcloud_gpu(prt_context *ctx, const prt_transfer *t, const float *w, float emission, prt_relit *r)
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
    size_t base = 0, gbase = total_length(s, 0);
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_zone *zone = &s->zones[z];
        const size_t len = zone_length(s, z, K, 0), glen = s->glossy_count ? zone_length(s, z, K, 1) : 0;
        if (!len && !glen) continue;
        /* relight.c's merged-light weights, in its order. */
        const size_t L = (size_t)zone->lights * K;
        memset(W, 0, L * 3 * sizeof(float));
        for (uint32_t j = 0; j < s->cloud_count; ++j)
            for (int k = 0; k < K; ++k)
                for (int c = 0; c < 3; ++c) W[((size_t)zone->light_of[j] * K + k) * 3 + c] += w[((size_t)j * K + k) * 3 + c];
        if (len) fill(&zone->diffuse, L, 1, W, x + base * 3);
        if (glen) fill(&zone->glossy, L, 16, W, x + gbase * 3);
        base += len;
        gbase += glen;
    }
    /* method.c's emitted exit radiance: emission times emit_sh. */
    if (s->glossy_count && s->emit_sh && emission > 0)
        for (int c = 0; c < 3; ++c) x[gbase * 3 + (size_t)c] = emission;
    free(W);
    if (s->glossy_count) {
        r->exit_order = 4;
        r->exit_mirror = 0;
    }
    r->gpu_sums = &g->sums;
    return PRT_OK;
}
