/* Run time of the light cloud (Kristensen et al. 2005, section 6).
 *
 * Weights: for each user light, the cloud lights nearest to it that it sees. The paper weights
 * the m nearest visible ones by (1 - d/r)^4 with r the distance to the farthest; that kernel
 * smooths but does not interpolate (a light placed on a cloud light still mixes in its
 * neighbours), so prt divides it by d^2 (a modified Shepard weight): a light exactly at a cloud
 * light gets that light's solution, and weights still fall to zero at r, so lights entering or
 * leaving the neighbourhood do so without a jump. r is the distance to the (m+1)-th nearest
 * cloud light whether seen or not, so that a light becoming hidden does not move r.
 *
 * Visibility fades: a cloud light counts by the fraction of 9 short paths (the user light to a
 * point on a small sphere around it, then on to the cloud light) that are unblocked, so a cloud
 * light disappearing behind a wall fades out over a short distance of the drag instead of
 * switching off (the paper fades over time; over distance the result does not depend on the frame
 * rate, and relighting stays a pure function of the lighting). Both legs are tested, so nothing
 * passes through a closed wall.
 *
 * Per zone, the cloud weights sum into the zone's merged lights; then per CPCA cluster the mean
 * and each basis vector are dotted with them once (eq. 13's x^m = X^m w and b_i = B_i w), and
 * each vertex adds its coefficients' share. */
#include "methods/lightcloud/lightcloud.h"

#include <omp.h>

#define FADE_PATHS 9

static prt_status tree_ready(prt_context *ctx, const prt__lightcloud_set *s)
{
    prt__lightcloud_cache *c = s->cache;
    pthread_mutex_lock(&c->lock);
    prt_status st = PRT_OK;
    if (!c->tree_ready) {
        if (prt__kdtree_build(&c->tree, s->cloud, s->cloud_count)) c->tree_ready = true;
        else st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    pthread_mutex_unlock(&c->lock);
    return st;
}

/* Fraction of the short paths from p to cloud light q that are unblocked. */
static float seen(const prt__vertex_lights *vl, const float p[3], const float q[3], float radius)
{
    static const float dirs[FADE_PATHS][3] = {{0, 0, 0}, {.577f, .577f, .577f}, {-.577f, .577f, .577f}, {.577f, -.577f, .577f}, {.577f, .577f, -.577f},
                                              {-.577f, -.577f, .577f}, {-.577f, .577f, -.577f}, {.577f, -.577f, -.577f}, {-.577f, -.577f, -.577f}};
    int open = 0;
    for (int i = 0; i < FADE_PATHS; ++i) {
        const float a[3] = {p[0] + radius * dirs[i][0], p[1] + radius * dirs[i][1], p[2] + radius * dirs[i][2]};
        if ((i == 0 || prt__raycaster_segment_clear(&vl->rc, p, a)) && prt__raycaster_segment_clear(&vl->rc, a, q)) open++;
    }
    return (float)open / FADE_PATHS;
}

prt_status prt__lightcloud_weights(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, int neighbours, float *w)
{
    const prt__lightcloud_set *s = prt__lightcloud(t);
    const uint32_t n = s->cloud_count;
    const int K = s->lobes;
    memset(w, 0, (size_t)n * K * 3 * sizeof(float));
    const int count = prt_lighting_count(l);
    if (!count) return PRT_OK;
    prt_status st = tree_ready(ctx, s);
    if (!st) st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, &s->cache->lights);
    if (st) return st;
    if (neighbours < 1) neighbours = 1;
    if (neighbours > PRT__KDTREE_MAX_K - 1) neighbours = PRT__KDTREE_MAX_K - 1;
    const float radius = 0.25f * s->spacing;
    bool outside = false;
    for (int li = 0; li < count; ++li) {
        const prt_light *L = prt_lighting_light(l, li);
        /* The light's intensity over the lobes (lobes.c): lobe 0 alone for isotropic lights. */
        float power[9][3] = {{0}};
        if (L->type == PRT_LIGHT_POINT) memcpy(power[0], L->intensity, sizeof power[0]);
        else if (L->type == PRT_LIGHT_SPHERE)   /* a uniform sphere seen from outside: I = pi R^2 L in every direction */
            for (int k = 0; k < 3; ++k) power[0][k] = (float)PRT_PI * L->radius * L->radius * L->radiance[k];
        else if ((L->type == PRT_LIGHT_SPOT || L->type == PRT_LIGHT_IES) && K > 1) prt__lightcloud_project(L, K, power);
        else if (L->type == PRT_LIGHT_SPOT || L->type == PRT_LIGHT_IES)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "this light-cloud file has isotropic cloud lights (baked with --emission-order 1): %s lights need "
                             "--emission-order 2 or 3", prt_light_type_name(L->type));
        else return prt__fail(ctx, PRT_ERR_INVALID_ARG, "light-cloud transfer relights point, spot, ies and sphere lights, not %s lights", prt_light_type_name(L->type));
        /* m visible neighbours inside radius r; widen the search when all near ones are hidden. */
        uint32_t idx[PRT__KDTREE_MAX_K];
        float dist[PRT__KDTREE_MAX_K], weight[PRT__KDTREE_MAX_K];
        double sum = 0;
        int found = 0;
        for (int m = neighbours; sum <= 0 && m < PRT__KDTREE_MAX_K; m = m * 2 < PRT__KDTREE_MAX_K ? m * 2 : PRT__KDTREE_MAX_K) {
            found = prt__kdtree_nearest(&s->cache->tree, L->position, m + 1, idx, dist);
            if (found == 0) break;
            const float r = found > m ? dist[m] : dist[found - 1] * 1.5f + 1e-20f;
            const int use = found > m ? m : found;
            sum = 0;
            for (int i = 0; i < use; ++i) {
                const float *q = s->cloud + (size_t)idx[i] * 3;
                if (dist[i] <= 1e-6f * s->spacing) {   /* on a cloud light: its solution */
                    for (int j = 0; j < use; ++j) weight[j] = 0;
                    weight[i] = 1;
                    sum = 1;
                    break;
                }
                const float vis = dist[i] < r ? seen(&s->cache->lights, L->position, q, radius) : 0.0f;
                const float a = 1.0f - dist[i] / r, k = a * a * a * a / (dist[i] * dist[i]);
                weight[i] = vis * k;
                sum += weight[i];
            }
            found = use;
        }
        /* Said once while it lasts, not on every frame of a drag. */
        if (sum <= 0) {
            if (!__atomic_exchange_n(&s->cache->warned, 1, __ATOMIC_RELAXED))
                prt__log(ctx, PRT_LOG_WARN, "light at (%g, %g, %g) sees none of the light cloud near it: it adds no indirect light", L->position[0],
                         L->position[1], L->position[2]);
            outside = true;
            continue;
        }
        /* Beyond the region the cloud covers the nearest cloud lights stand in for the light, which
         * is wrong (light through a window does not fall off, for one): say so. */
        float beyond = 0;
        for (int k = 0; k < 3; ++k) beyond = fmaxf(beyond, fmaxf(s->region[k] - L->position[k], L->position[k] - s->region[3 + k]));
        if (beyond > 0) {
            if (!__atomic_exchange_n(&s->cache->warned, 1, __ATOMIC_RELAXED))
                prt__log(ctx, PRT_LOG_WARN, "light at (%g, %g, %g) lies %.3g outside the region the light cloud covers: its indirect light is the "
                         "nearest cloud lights' and will be wrong (bake with a --cloud-box that covers it)", L->position[0], L->position[1],
                         L->position[2], beyond);
            outside = true;
        }
        for (int i = 0; i < found; ++i)
            for (int j = 0; j < K; ++j)
                for (int k = 0; k < 3; ++k) w[((size_t)idx[i] * K + j) * 3 + k] += (float)(weight[i] / sum) * power[j][k];
    }
    if (!outside) __atomic_store_n(&s->cache->warned, 0, __ATOMIC_RELAXED);
    return PRT_OK;
}

/* sum_l x[l] w[l] over n values in sixteen running sums, added pairwise at the end: gcc and clang
 * keep them in two vector registers. One running sum (as before) chained every add through the
 * last and ran at a quarter of a plain read of the same bytes (prt_bench_lightcloud). */
static inline float dot(const float *restrict x, const float *restrict w, size_t n)
{
    float acc[16] = {0};
    size_t l = 0;
    for (; l + 16 <= n; l += 16)
        for (int k = 0; k < 16; ++k) acc[k] += x[l + k] * w[l + k];
    for (int k = 0; l < n; ++l, ++k) acc[k] += x[l] * w[l];
    for (int h = 8; h; h >>= 1)
        for (int k = 0; k < h; ++k) acc[k] += acc[k + h];
    return acc[0];
}

/* A vector's exit values (channels x `per` rows of L columns, layout [c][k][light]) under the
 * zone's weights Wc ([c][light]). */
static void project(const float *x, size_t L, int per, const float *Wc, float *out)
{
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < per; ++k) out[c * per + k] = dot(x + ((size_t)c * per + k) * L, Wc + (size_t)c * L, L);
}

/* Each vertex: its cluster's projected mean plus its weights times the cluster's projected
 * vectors, summed in registers and added to its row once. */
static inline __attribute__((always_inline)) void reconstruct(const prt__cpca *cp, uint32_t rows, const float *proj, int out_n, float *out, const uint32_t *row_vertex,
                                                              size_t out_stride)
{
    for (uint32_t r = 0; r < rows; ++r) {
        const uint32_t cl = cp->cluster_of[r], cnt = cp->counts[cl];
        const float *restrict z = cp->weights + cp->weight_start[r];
        const float *restrict mean = proj + (size_t)cl * out_n, *restrict B = proj + ((size_t)cp->clusters + cp->basis_start[cl]) * out_n;
        float *o = out + (size_t)row_vertex[r] * out_stride;
        if (out_n == 3) {
            /* Diffuse rows are three values: two running sums each, so that the adds of a vertex's
             * eight or so vectors are two chains, not one. */
            float a0 = mean[0], a1 = mean[1], a2 = mean[2], b0 = 0, b1 = 0, b2 = 0;
            uint32_t j = 0;
            for (; j + 2 <= cnt; j += 2) {
                const float *p = B + (size_t)j * 3;
                a0 += z[j] * p[0]; a1 += z[j] * p[1]; a2 += z[j] * p[2];
                b0 += z[j + 1] * p[3]; b1 += z[j + 1] * p[4]; b2 += z[j + 1] * p[5];
            }
            if (j < cnt) { const float *p = B + (size_t)j * 3; a0 += z[j] * p[0]; a1 += z[j] * p[1]; a2 += z[j] * p[2]; }
            o[0] += a0 + b0; o[1] += a1 + b1; o[2] += a2 + b2;
            continue;
        }
        float e[48];
        for (int i = 0; i < out_n; ++i) e[i] = mean[i];
        for (uint32_t j = 0; j < cnt; ++j) {
            const float zj = z[j], *restrict bv = B + (size_t)j * out_n;
            for (int i = 0; i < out_n; ++i) e[i] += zj * bv[i];
        }
        for (int i = 0; i < out_n; ++i) o[i] += e[i];
    }
}

/* Adds block b's exit values under zone weights Wc ([c][light]) to out rows (stride per vertex
 * `per * 3`) listed by row_vertex. */
static bool eval_block(const prt__lightcloud_block *b, uint32_t lights, int per, const float *Wc, float *out, const uint32_t *row_vertex,
                       size_t out_stride)
{
    if (!b->vertices) return true;
    const size_t L = lights;
    const int out_n = 3 * per;
    float e[48];   /* per <= 16 */
    if (b->raw) {
        for (uint32_t r = 0; r < b->vertices; ++r) {
            float *o = out + (size_t)row_vertex[r] * out_stride;
            project(b->raw + (size_t)r * b->dim, L, per, Wc, e);
            for (int i = 0; i < out_n; ++i) o[i] += e[i];
        }
        return true;
    }
    const prt__cpca *cp = b->cpca;
    float *proj = malloc((size_t)(cp->vectors_total + (size_t)cp->clusters) * out_n * sizeof(float));
    if (!proj) return false;
    /* Project every cluster mean and basis vector once (eq. 13). */
    for (size_t vec = 0; vec < (size_t)cp->clusters + cp->vectors_total; ++vec)
        project(vec < (size_t)cp->clusters ? cp->means + vec * cp->dim : cp->basis + (vec - cp->clusters) * cp->dim, L, per, Wc, proj + vec * out_n);
    if (per == 1) reconstruct(cp, b->vertices, proj, 3, out, row_vertex, out_stride);   /* sized at compile time: e stays in registers */
    else if (per == 16) reconstruct(cp, b->vertices, proj, 48, out, row_vertex, out_stride);
    else reconstruct(cp, b->vertices, proj, out_n, out, row_vertex, out_stride);
    free(proj);
    return true;
}

prt_status prt__lightcloud_eval(prt_context *ctx, const prt_transfer *t, const float *w, float *rgb, float *exit_sh)
{
    const prt__lightcloud_set *s = prt__lightcloud(t);
    int failed = 0;
/* Small scenes evaluate in well under a millisecond: threads would only add their start-up. */
#pragma omp parallel num_threads(prt__threads(ctx)) reduction(| : failed) if (s->zone_count > 1 && t->mesh.vertex_count > 20000)
    {
        const int K = s->lobes;
        float *W = malloc(((size_t)s->cloud_count * K * 3 + 3) * sizeof(float)), *Wc = malloc(((size_t)s->cloud_count * K * 3 + 3) * sizeof(float));
        uint32_t *rows = malloc(((size_t)s->glossy_count + 1) * sizeof(uint32_t));
#pragma omp for schedule(dynamic, 1)
        for (uint32_t z = 0; z < s->zone_count; ++z) {
            if (!W || !Wc || !rows) { failed = 1; continue; }
            const prt__lightcloud_zone *zone = &s->zones[z];
            /* Columns: merged light l's lobe k at l * K + k, as the bake stored them. */
            const uint32_t cols = zone->lights * (uint32_t)K;
            memset(W, 0, (size_t)cols * 3 * sizeof(float));
            bool any = false;
            for (uint32_t j = 0; j < s->cloud_count; ++j)
                for (int k = 0; k < K; ++k)
                    for (int c = 0; c < 3; ++c) {
                        const float x = w[((size_t)j * K + k) * 3 + c];
                        W[((size_t)zone->light_of[j] * K + k) * 3 + c] += x;
                        any |= x != 0;
                    }
            if (!any) continue;
            /* By channel, so that each row's sum reads its weights contiguously. */
            for (uint32_t l = 0; l < cols; ++l)
                for (int c = 0; c < 3; ++c) Wc[(size_t)c * cols + l] = W[(size_t)l * 3 + c];
            const uint32_t *members = s->members + s->member_start[z];
            if (!eval_block(&zone->diffuse, cols, 1, Wc, rgb, members, 3)) failed = 1;
            if (exit_sh && zone->glossy.vertices) {
                uint32_t g = 0;
                for (uint32_t i = 0; i < s->member_start[z + 1] - s->member_start[z]; ++i)
                    if (s->glossy_of[members[i]] != UINT32_MAX) rows[g++] = members[i];
                if (!eval_block(&zone->glossy, cols, 16, Wc, exit_sh, rows, 48)) failed = 1;
            }
        }
        free(W);
        free(Wc);
        free(rows);
    }
    return failed ? prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory") : PRT_OK;
}
