/* The light clustering as it was before candidate pairs (issue 28), kept as the reference the
 * test (test_lightcloud_dense.c) and the bench (bench/bench_lightcloud_cluster.c) compare with:
 * every pair's distance in a table of n(n-1)/2 floats, complete linkage by Lance-Williams updates
 * over every cluster after each merge (O(n^2) memory, O(n^2 log n) time). Aborts when out of
 * memory: it is a reference, not library code. */
#ifndef PRT_TEST_LIGHTCLOUD_ALL_PAIRS_H
#define PRT_TEST_LIGHTCLOUD_ALL_PAIRS_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct ref_pair { float d; uint32_t a, b; uint32_t stamp_a, stamp_b; } ref_pair;
static inline bool ref_less(const ref_pair *x, const ref_pair *y)
{
    if (x->d != y->d) return x->d < y->d;
    if (x->a != y->a) return x->a < y->a;
    return x->b < y->b;
}
typedef struct ref_heap { ref_pair *p; size_t n, cap; } ref_heap;
static inline void ref_push(ref_heap *h, ref_pair e)
{
    if (h->n == h->cap) {
        h->cap = h->cap ? h->cap * 2 : 1024;
        h->p = realloc(h->p, h->cap * sizeof *h->p);
        if (!h->p) abort();
    }
    size_t i = h->n++;
    while (i > 0) {
        size_t parent = (i - 1) / 2;
        if (!ref_less(&e, &h->p[parent])) break;
        h->p[i] = h->p[parent];
        i = parent;
    }
    h->p[i] = e;
}
static inline ref_pair ref_pop(ref_heap *h)
{
    ref_pair top = h->p[0], last = h->p[--h->n];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= h->n) break;
        if (c + 1 < h->n && ref_less(&h->p[c + 1], &h->p[c])) c++;
        if (!ref_less(&h->p[c], &last)) break;
        h->p[i] = h->p[c];
        i = c;
    }
    if (h->n) h->p[i] = last;
    return top;
}
static inline size_t tri(size_t n, size_t i, size_t j) { return i * (2 * n - i - 1) / 2 + (j - i - 1); }
static inline uint32_t all_pairs(uint32_t n, float (*metric)(void *, uint32_t, uint32_t), void *user, uint32_t *cluster_of)
{
    float *d = malloc(((size_t)n * (n - 1) / 2 + 1) * sizeof(float));
    uint32_t *stamp = calloc(n, sizeof(uint32_t)), *parent = malloc(n * sizeof(uint32_t));
    if (!d || !stamp || !parent) abort();
    ref_heap h = {0};
    for (uint32_t i = 0; i < n; ++i) {
        parent[i] = i;
        for (uint32_t j = i + 1; j < n; ++j) {
            const float m = metric(user, i, j);
            d[tri(n, i, j)] = m < 1.0f ? m : INFINITY;
            if (m < 1.0f) ref_push(&h, (ref_pair){m, i, j, 0, 0});
        }
    }
    while (h.n) {
        const ref_pair e = ref_pop(&h);
        if (parent[e.a] != e.a || parent[e.b] != e.b || stamp[e.a] != e.stamp_a || stamp[e.b] != e.stamp_b) continue;
        parent[e.b] = e.a;
        stamp[e.a]++;
        for (uint32_t k = 0; k < n; ++k) {
            if (k == e.a || k == e.b || parent[k] != k) continue;
            float *dak = &d[k < e.a ? tri(n, k, e.a) : tri(n, e.a, k)];
            const float dbk = d[k < e.b ? tri(n, k, e.b) : tri(n, e.b, k)];
            if (dbk > *dak) *dak = dbk;
            if (*dak < 1.0f) {
                const uint32_t lo = k < e.a ? k : e.a, hi = k < e.a ? e.a : k;
                ref_push(&h, (ref_pair){*dak, lo, hi, stamp[lo], stamp[hi]});
            }
        }
    }
    uint32_t count = 0;
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t r = i;
        while (parent[r] != r) r = parent[r];
        cluster_of[i] = r == i ? count++ : cluster_of[r];
    }
    free(h.p);
    free(d);
    free(stamp);
    free(parent);
    return count;
}

#endif
