/* UV islands by union-find over corners welded on exact (position, uv): a triangle soup whose
 * vertices were never shared still forms the charts its texture layout draws. */
#include "geom/uv_islands.h"

typedef struct corner { float key[5]; uint32_t vertex; } corner;

static int key_cmp(const corner *a, const corner *b)
{
    for (int c = 0; c < 5; ++c)
        if (a->key[c] != b->key[c]) return a->key[c] < b->key[c] ? -1 : 1;
    return 0;
}

static int corner_cmp(const void *a, const void *b)
{
    const int k = key_cmp(a, b);
    if (k) return k;
    const uint32_t i = ((const corner *)a)->vertex, j = ((const corner *)b)->vertex;
    return i < j ? -1 : i > j;
}

static uint32_t find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
}

prt_status prt__uv_islands(const prt_context *ctx, const prt__mesh *m, uint32_t *island, uint32_t *count)
{
    const size_t nv = m->vertex_count, nt = m->triangle_count;
    if (!prt__mesh_has_uv(m)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "UV islands need texture coordinates on every vertex");
    corner *c = malloc(nv * sizeof *c + 1);
    uint32_t *order = malloc(nv * sizeof *order + 1), *parent = malloc(nv * sizeof *parent + 1);
    if (!c || !order || !parent) { free(c); free(order); free(parent); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory finding UV islands"); }
    for (size_t v = 0; v < nv; ++v) {
        c[v] = (corner){{m->uv[v * 2], m->uv[v * 2 + 1], m->positions[v * 3], m->positions[v * 3 + 1], m->positions[v * 3 + 2]}, (uint32_t)v};
        parent[v] = (uint32_t)v;
    }
    qsort(c, nv, sizeof *c, corner_cmp);
    /* Equal keys sort together: each run's vertices are one corner. */
    for (size_t i = 1; i < nv; ++i)
        if (!key_cmp(&c[i - 1], &c[i])) parent[find(parent, c[i].vertex)] = find(parent, c[i - 1].vertex);
    free(c);
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        const uint32_t r = find(parent, ix[0]);
        for (int k = 1; k < 3; ++k) {
            const uint32_t q = find(parent, ix[k]);
            if (q != r) parent[q] = r;
        }
    }
    /* Numbered by first triangle, reusing order[] as root -> island. */
    for (size_t v = 0; v < nv; ++v) order[v] = UINT32_MAX;
    uint32_t n = 0;
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t r = find(parent, m->indices[t * 3]);
        if (order[r] == UINT32_MAX) order[r] = n++;
        island[t] = order[r];
    }
    free(order);
    free(parent);
    *count = n;
    return PRT_OK;
}
