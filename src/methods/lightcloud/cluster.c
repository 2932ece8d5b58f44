/* Light clustering (Kristensen et al. 2005, section 4.1): bottom-up merging of the lights of a
 * cloud while every pair of lights across the two clusters is "close" (metric below 1), closest
 * cluster pair first. The distance between clusters is the largest metric over their member pairs
 * (complete linkage: the paper's all-pairs rule), kept up to date with the Lance-Williams update
 * max(d(g, k), d(h, k)); a heap with stale entries skipped picks the next pair.
 *
 * Only the candidate pairs (pairs.c: lights within the merge distance) are looked at, and only
 * cluster pairs whose every cross pair is close are kept: a cluster's neighbours are a sorted list
 * of (cluster, distance), and a merge keeps the neighbours both sides had (the largest of a close
 * and a far pair is far). Memory and time follow the close pairs, not n^2; the merges, and so the
 * clusters, are those of the all-pairs table it replaced, which held every distance (the heap's
 * order is by distance then index, and the same entries are live in both). */
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

typedef struct edge { uint32_t k; float d; } edge;   /* a neighbouring cluster and the distance to it (>= 1: far) */

/* The entry for cluster k in a sorted neighbour list; every close pair is listed on both sides. */
static edge *find(edge *list, uint32_t len, uint32_t k)
{
    uint32_t lo = 0, hi = len;
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (list[mid].k < k) lo = mid + 1;
        else hi = mid;
    }
    return lo < len && list[lo].k == k ? &list[lo] : NULL;
}

prt_status prt__lightcloud_cluster(prt_context *ctx, const prt__lightcloud_pairs *pairs, prt__light_metric_fn metric, void *user, uint32_t *cluster_of,
                                   uint32_t *clusters)
{
    *clusters = 0;
    const uint32_t n = pairs->n;
    if (n == 0) return PRT_OK;
    float *m = malloc((size_t)(pairs->count ? pairs->count : 1) * sizeof(float));
    uint64_t *start = prt__calloc((size_t)n + 1, sizeof(uint64_t));
    uint32_t *len = prt__calloc(n, sizeof(uint32_t)), *stamp = prt__calloc(n, sizeof(uint32_t)), *parent = malloc((size_t)n * sizeof(uint32_t));
    edge *adj = NULL;
    heap h = {0};
    prt_status st = m && start && len && stamp && parent ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    /* Every candidate pair's distance, once; the close ones counted on both sides. */
    for (uint32_t j = 0; j < n && !st; ++j) {
        parent[j] = j;
        for (uint64_t p = pairs->start[j]; p < pairs->start[j + 1]; ++p) {
            m[p] = metric(user, j, pairs->other[p], p);
            if (m[p] < 1.0f) { start[j + 1]++; start[pairs->other[p] + 1]++; }
        }
        if (prt__cancelled(ctx)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled");
    }
    if (!st) {
        for (uint32_t j = 0; j < n; ++j) start[j + 1] += start[j];
        if (!(adj = malloc((size_t)(start[n] ? start[n] : 1) * sizeof(edge)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    /* Lists ascending: j's lower neighbours arrive while they are visited, then its upper ones
     * (pairs lists each light's in ascending order). */
    for (uint32_t j = 0; j < n && !st; ++j)
        for (uint64_t p = pairs->start[j]; p < pairs->start[j + 1]; ++p) {
            if (!(m[p] < 1.0f)) continue;
            const uint32_t k = pairs->other[p];
            adj[start[j] + len[j]++] = (edge){k, m[p]};
            adj[start[k] + len[k]++] = (edge){j, m[p]};
            if (!heap_push(&h, (pair){m[p], j, k, 0, 0})) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
        }
    free(m);
    /* Cluster ids are their smallest member; parent[i] = i while i heads a live cluster. */
    while (!st && h.n) {
        const pair e = heap_pop(&h);
        if (parent[e.a] != e.a || parent[e.b] != e.b || stamp[e.a] != e.stamp_a || stamp[e.b] != e.stamp_b) continue;   /* stale */
        /* Merge b into a (a < b): a keeps the neighbours both had, each at the larger distance. */
        parent[e.b] = e.a;
        stamp[e.a]++;
        edge *A = adj + start[e.a];
        const edge *B = adj + start[e.b];
        const uint32_t na = len[e.a], nb = len[e.b];
        uint32_t kept = 0;
        for (uint32_t i = 0, j = 0; i < na; ++i) {
            const edge ea = A[i];
            if (ea.k == e.b || parent[ea.k] != ea.k || !(ea.d < 1.0f)) continue;   /* absorbed, or already far */
            while (j < nb && B[j].k < ea.k) j++;
            const float db = j < nb && B[j].k == ea.k ? B[j].d : INFINITY, d = ea.d > db ? ea.d : db;
            edge *back = find(adj + start[ea.k], len[ea.k], e.a);
            if (back) back->d = d;
            if (!(d < 1.0f)) continue;
            A[kept++] = (edge){ea.k, d};
            const uint32_t lo = ea.k < e.a ? ea.k : e.a, hi = ea.k < e.a ? e.a : ea.k;
            if (!heap_push(&h, (pair){d, lo, hi, stamp[lo], stamp[hi]})) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
        }
        len[e.a] = kept;
        len[e.b] = 0;
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
    free(adj);
    free(start);
    free(len);
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
