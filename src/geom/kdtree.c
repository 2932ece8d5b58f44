/* Static kd-tree: the points are ordered so that every index range [lo, hi) is a node whose
 * middle element splits the rest along the range's longest axis. No pointers, two arrays. */
#include "geom/kdtree.h"

/* Insertion into a small sorted index range by coordinate, then index: deterministic. */
static void sort_range(uint32_t *idx, uint32_t n, const float *pts, int axis)
{
    /* Shell sort: no qsort context pointer in C11. */
    static const uint32_t gaps[] = {701, 301, 132, 57, 23, 10, 4, 1};
    for (size_t g = 0; g < sizeof gaps / sizeof gaps[0]; ++g) {
        const uint32_t gap = gaps[g];
        for (uint32_t i = gap; i < n; ++i) {
            const uint32_t x = idx[i];
            const float key = pts[(size_t)x * 3 + axis];
            uint32_t j = i;
            while (j >= gap) {
                const uint32_t y = idx[j - gap];
                const float ky = pts[(size_t)y * 3 + axis];
                if (ky < key || (ky == key && y < x)) break;
                idx[j] = y;
                j -= gap;
            }
            idx[j] = x;
        }
    }
}

static void build(prt__kdtree *t, uint32_t lo, uint32_t hi)
{
    while (hi - lo > 1) {
        float mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t i = lo; i < hi; ++i)
            for (int k = 0; k < 3; ++k) {
                const float v = t->points[(size_t)t->order[i] * 3 + k];
                mn[k] = v < mn[k] ? v : mn[k];
                mx[k] = v > mx[k] ? v : mx[k];
            }
        int axis = 0;
        for (int k = 1; k < 3; ++k)
            if (mx[k] - mn[k] > mx[axis] - mn[axis]) axis = k;
        sort_range(t->order + lo, hi - lo, t->points, axis);
        const uint32_t mid = lo + (hi - lo) / 2;
        t->axis[mid] = (uint8_t)axis;
        build(t, lo, mid);
        lo = mid + 1;
    }
}

bool prt__kdtree_build(prt__kdtree *t, const float *points, uint32_t count)
{
    memset(t, 0, sizeof *t);
    t->points = points;
    t->count = count;
    t->order = malloc((size_t)(count ? count : 1) * sizeof(uint32_t));
    t->axis = prt__calloc(count ? count : 1, 1);
    if (!t->order || !t->axis) { prt__kdtree_free(t); return false; }
    for (uint32_t i = 0; i < count; ++i) t->order[i] = i;
    build(t, 0, count);
    return true;
}

void prt__kdtree_free(prt__kdtree *t)
{
    free(t->order);
    free(t->axis);
    t->order = NULL;
    t->axis = NULL;
    t->count = 0;
}

typedef struct best { int k, n; uint32_t *index; float *d2; } best;

static void offer(best *b, uint32_t i, float d2)
{
    if (b->n == b->k && (d2 > b->d2[b->n - 1] || (d2 == b->d2[b->n - 1] && i > b->index[b->n - 1]))) return;
    int j = b->n < b->k ? b->n++ : b->n - 1;
    while (j > 0 && (b->d2[j - 1] > d2 || (b->d2[j - 1] == d2 && b->index[j - 1] > i))) {
        b->d2[j] = b->d2[j - 1];
        b->index[j] = b->index[j - 1];
        --j;
    }
    b->d2[j] = d2;
    b->index[j] = i;
}

static void search(const prt__kdtree *t, uint32_t lo, uint32_t hi, const float q[3], best *b)
{
    if (lo >= hi) return;
    const uint32_t mid = lo + (hi - lo) / 2, i = t->order[mid];
    const float *p = t->points + (size_t)i * 3;
    const float dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
    offer(b, i, dx * dx + dy * dy + dz * dz);
    if (hi - lo == 1) return;
    const int axis = t->axis[mid];
    const float diff = q[axis] - p[axis];
    const bool left_first = diff < 0;
    search(t, left_first ? lo : mid + 1, left_first ? mid : hi, q, b);
    if (b->n < b->k || diff * diff <= b->d2[b->n - 1]) search(t, left_first ? mid + 1 : lo, left_first ? hi : mid, q, b);
}

int prt__kdtree_nearest(const prt__kdtree *t, const float q[3], int k, uint32_t *index, float *dist)
{
    if (k > PRT__KDTREE_MAX_K) k = PRT__KDTREE_MAX_K;
    if ((uint32_t)k > t->count) k = (int)t->count;
    if (k <= 0) return 0;
    float d2[PRT__KDTREE_MAX_K];
    best b = {k, 0, index, d2};
    search(t, 0, t->count, q, &b);
    if (dist)
        for (int i = 0; i < b.n; ++i) dist[i] = sqrtf(d2[i]);
    return b.n;
}
