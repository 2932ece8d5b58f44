/* Light clustering (Kristensen et al. 2005, section 4.1): bottom-up merging of the lights of a
 * cloud while every pair of lights across the two clusters is "close" (metric below 1), closest
 * cluster pair first. The distance between clusters is the largest metric over their member pairs
 * (complete linkage: the paper's all-pairs rule), kept up to date with the Lance-Williams update
 * max(d(g, k), d(h, k)); a heap with stale entries skipped picks the next pair, so n lights cost
 * O(n^2 log n), not the O(n^3) of scanning every pair after each merge. */
#include "methods/lightcloud/lightcloud.h"

typedef struct pair { float d; uint32_t a, b; uint32_t stamp_a, stamp_b; } pair;

static bool pair_less(const pair *x, const pair *y)
{
    if (x->d != y->d) return x->d < y->d;
    if (x->a != y->a) return x->a < y->a;
    return x->b < y->b;
}

typedef struct heap { pair *p; size_t n, cap; } heap;

static bool heap_push(heap *h, pair e)
{
    if (h->n == h->cap) {
        size_t cap = h->cap ? h->cap * 2 : 1024;
        pair *p = realloc(h->p, cap * sizeof *p);
        if (!p) return false;
        h->p = p;
        h->cap = cap;
    }
    size_t i = h->n++;
    while (i > 0) {
        size_t parent = (i - 1) / 2;
        if (!pair_less(&e, &h->p[parent])) break;
        h->p[i] = h->p[parent];
        i = parent;
    }
    h->p[i] = e;
    return true;
}

static pair heap_pop(heap *h)
{
    pair top = h->p[0], last = h->p[--h->n];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= h->n) break;
        if (c + 1 < h->n && pair_less(&h->p[c + 1], &h->p[c])) c++;
        if (!pair_less(&h->p[c], &last)) break;
        h->p[i] = h->p[c];
        i = c;
    }
    if (h->n) h->p[i] = last;
    return top;
}

/* Index of (i, j), i < j, in a strict upper triangle of n. */
static size_t tri(size_t n, size_t i, size_t j) { return i * (2 * n - i - 1) / 2 + (j - i - 1); }

prt_status prt__lightcloud_cluster(prt_context *ctx, uint32_t n, prt__light_metric_fn metric, void *user, uint32_t *cluster_of, uint32_t *clusters)
{
    *clusters = 0;
    if (n == 0) return PRT_OK;
    const size_t pairs = (size_t)n * (n - 1) / 2;
    float *d = malloc((pairs ? pairs : 1) * sizeof(float));
    uint32_t *stamp = prt__calloc(n, sizeof(uint32_t));
    uint32_t *parent = malloc((size_t)n * sizeof(uint32_t));
    heap h = {0};
    prt_status st = d && stamp && parent ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (uint32_t i = 0; i < n && !st; ++i) {
        parent[i] = i;
        for (uint32_t j = i + 1; j < n; ++j) {
            const float m = metric(user, i, j);
            d[tri(n, i, j)] = m < 1.0f ? m : INFINITY;
            if (m < 1.0f && !heap_push(&h, (pair){m, i, j, 0, 0})) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
        }
        if (prt__cancelled(ctx)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled");
    }
    /* Cluster ids are their smallest member; parent[i] = i while i heads a live cluster. */
    while (!st && h.n) {
        const pair e = heap_pop(&h);
        if (parent[e.a] != e.a || parent[e.b] != e.b || stamp[e.a] != e.stamp_a || stamp[e.b] != e.stamp_b) continue;   /* stale */
        /* Merge b into a (a < b): a's distances become the larger of the two. */
        parent[e.b] = e.a;
        stamp[e.a]++;
        for (uint32_t k = 0; k < n; ++k) {
            if (k == e.a || k == e.b || parent[k] != k) continue;
            float *dak = &d[k < e.a ? tri(n, k, e.a) : tri(n, e.a, k)];
            const float dbk = d[k < e.b ? tri(n, k, e.b) : tri(n, e.b, k)];
            if (dbk > *dak) *dak = dbk;
            if (*dak < 1.0f) {
                const uint32_t lo = k < e.a ? k : e.a, hi = k < e.a ? e.a : k;
                if (!heap_push(&h, (pair){*dak, lo, hi, stamp[lo], stamp[hi]})) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
            }
        }
    }
    if (!st) {
        /* Number the clusters in order of their smallest member. */
        uint32_t count = 0;
        for (uint32_t i = 0; i < n; ++i) {
            uint32_t r = i;
            while (parent[r] != r) r = parent[r];
            if (r == i) cluster_of[i] = count++;
            else cluster_of[i] = cluster_of[r];
        }
        *clusters = count;
    }
    free(h.p);
    free(d);
    free(stamp);
    free(parent);
    return st;
}

/* Merged lights' responses (section 4.1's last step). The mean is the least-squares stand-in for
 * the members under equal weights; the harmonic mean is what the paper names: per value, n /
 * sum(1 / x), 0 when a member's is 0 or below (the limit; a light that does not reach a vertex).
 * SH groups (group > 1: a glossy vertex's 16 coefficients of one channel, which change sign) keep
 * the mean's shape, scaled to the harmonic mean of the constant coefficient. A merged light of
 * one member is that member's response exactly. */
prt_status prt__lightcloud_merge(prt_context *ctx, int how, uint32_t n, const uint32_t *light_of, uint32_t lights, const float *src, size_t width,
                                 int group, float *dst)
{
    uint32_t *start = prt__calloc((size_t)lights + 1, sizeof(uint32_t)), *member = malloc(((size_t)n + 1) * sizeof(uint32_t));
    uint32_t *fill = prt__calloc((size_t)lights + 1, sizeof(uint32_t));
    if (!start || !member || !fill) { free(start); free(member); free(fill); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (uint32_t j = 0; j < n; ++j) start[light_of[j] + 1]++;
    for (uint32_t l = 0; l < lights; ++l) start[l + 1] += start[l];
    for (uint32_t j = 0; j < n; ++j) member[start[light_of[j]] + fill[light_of[j]]++] = j;   /* ascending within each light */
    free(fill);
    for (uint32_t l = 0; l < lights; ++l) {
        const uint32_t *mj = member + start[l], count = start[l + 1] - start[l];
        for (size_t i = 0; i < width; i += (size_t)group) {
            float mean[16];
            for (int c = 0; c < group; ++c) {
                /* Summed in member order in float, as before the choice existed: means are unchanged. */
                float sum = 0;
                for (uint32_t m = 0; m < count; ++m) sum += src[(size_t)mj[m] * width + i + c];
                mean[c] = count == 1 ? sum : sum / (float)count;
            }
            if (how == PRT__LIGHTCLOUD_MERGE_HARMONIC && count > 1) {
                double inv = 0;
                for (uint32_t m = 0; m < count && isfinite(inv); ++m) {
                    const float x = src[(size_t)mj[m] * width + i];
                    inv = x > 0 ? inv + 1.0 / x : INFINITY;
                }
                const double h = isfinite(inv) && inv > 0 ? count / inv : 0.0;
                if (group == 1) mean[0] = (float)h;
                else {
                    const double scale = mean[0] > 0 ? h / mean[0] : 0.0;
                    for (int c = 0; c < group; ++c) mean[c] = (float)(mean[c] * scale);
                }
            }
            for (int c = 0; c < group; ++c) dst[(i + c) * lights + l] = mean[c];
        }
    }
    free(start);
    free(member);
    return PRT_OK;
}
