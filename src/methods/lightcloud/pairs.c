/* The pairs of cloud lights that may merge (Kristensen et al. 2005, eq. 9: w1 |p_j - p_k| reaches
 * 1 at the merge distance, so lights farther apart never merge), found through a uniform grid of
 * cells one merge distance wide: each light looks at its own cell and the 26 around it. Memory
 * and time grow with the lights and their neighbours within the distance, not with every pair:
 * the all-pairs table it replaces held n^2 / 2 values (8 GiB at 64k lights). */
#include "methods/lightcloud/lightcloud.h"

#include <omp.h>

void prt__lightcloud_pairs_free(prt__lightcloud_pairs *p)
{
    free(p->start);
    free(p->other);
    free(p->visible);
    memset(p, 0, sizeof *p);
}

/* A cell's coordinate along one axis. Cells are a little wider than the distance (and computed in
 * double) so that rounding cannot put two lights closer than it two cells apart. */
static int64_t cell_of(float x, double lo, double inv) { return (int64_t)floor(((double)x - lo) * inv); }

/* Lights closer than r to light j, above j, ascending, into out (NULL: counted only). */
static uint32_t near_above(const float *pos, uint32_t j, float r, const int64_t dims[3], const double lo[3], double inv, const uint64_t *cell_start,
                           const uint32_t *cell_light, uint32_t *out)
{
    const float *p = pos + (size_t)j * 3;
    int64_t c[3];
    for (int k = 0; k < 3; ++k) c[k] = cell_of(p[k], lo[k], inv);
    uint32_t count = 0;
    for (int64_t z = c[2] - 1; z <= c[2] + 1; ++z)
        for (int64_t y = c[1] - 1; y <= c[1] + 1; ++y)
            for (int64_t x = c[0] - 1; x <= c[0] + 1; ++x) {
                if (x < 0 || y < 0 || z < 0 || x >= dims[0] || y >= dims[1] || z >= dims[2]) continue;
                const uint64_t cell = ((uint64_t)z * dims[1] + y) * dims[0] + x;
                for (uint64_t i = cell_start[cell]; i < cell_start[cell + 1]; ++i) {
                    const uint32_t k = cell_light[i];
                    if (k <= j) continue;
                    float d[3];
                    /* The metric's own distance, computed the same way. */
                    prt__v3_sub(p, pos + (size_t)k * 3, d);
                    if (!(prt__v3_len(d) < r)) continue;
                    if (out) out[count] = k;
                    count++;
                }
            }
    if (out)   /* cells are visited out of index order: ascending, for a result independent of the grid */
        for (uint32_t a = 1; a < count; ++a) {
            const uint32_t v = out[a];
            uint32_t b = a;
            for (; b > 0 && out[b - 1] > v; --b) out[b] = out[b - 1];
            out[b] = v;
        }
    return count;
}

prt_status prt__lightcloud_pairs_find(prt_context *ctx, const float *pos, uint32_t n, float r, int threads, prt__lightcloud_pairs *out)
{
    memset(out, 0, sizeof *out);
    out->n = n;
    out->start = prt__calloc((size_t)n + 1, sizeof(uint64_t));
    if (!out->start) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (n < 2 || !(r > 0) || !isfinite(r)) return PRT_OK;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < (size_t)n * 3; ++i) {
        lo[i % 3] = fmin(lo[i % 3], pos[i]);
        hi[i % 3] = fmax(hi[i % 3], pos[i]);
    }
    /* No more cells than lights (a distance far below the spacing would make most cells empty). */
    double width = (double)r * 1.0001;
    int64_t dims[3];
    for (;;) {
        double cells = 1, d[3];
        for (int k = 0; k < 3; ++k) cells *= d[k] = floor((hi[k] - lo[k]) / width) + 1;
        if (cells <= (double)n + 1) {
            for (int k = 0; k < 3; ++k) dims[k] = (int64_t)d[k];
            break;
        }
        width *= 1.5;
    }
    const double inv = 1.0 / width;
    const uint64_t ncells = (uint64_t)dims[0] * dims[1] * dims[2];
    uint64_t *cell_start = prt__calloc(ncells + 1, sizeof(uint64_t));
    uint32_t *cell_light = malloc((size_t)n * sizeof(uint32_t));
    uint64_t *fill = prt__calloc(ncells + 1, sizeof(uint64_t));
    prt_status st = cell_start && cell_light && fill ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) {
        /* Counting sort of the lights by cell, ascending within each. */
        for (uint32_t j = 0; j < n; ++j) {
            const uint64_t cell = ((uint64_t)cell_of(pos[j * 3 + 2], lo[2], inv) * dims[1] + cell_of(pos[j * 3 + 1], lo[1], inv)) * dims[0] +
                                  cell_of(pos[j * 3], lo[0], inv);
            cell_start[cell + 1]++;
        }
        for (uint64_t c = 0; c < ncells; ++c) cell_start[c + 1] += cell_start[c];
        for (uint32_t j = 0; j < n; ++j) {
            const uint64_t cell = ((uint64_t)cell_of(pos[j * 3 + 2], lo[2], inv) * dims[1] + cell_of(pos[j * 3 + 1], lo[1], inv)) * dims[0] +
                                  cell_of(pos[j * 3], lo[0], inv);
            cell_light[cell_start[cell] + fill[cell]++] = j;
        }
        /* Two passes: count each light's pairs, then write them where the counts say. */
#pragma omp parallel for schedule(dynamic, 256) num_threads(threads) if (n >= 4096)
        for (uint32_t j = 0; j < n; ++j) out->start[j + 1] = near_above(pos, j, r, dims, lo, inv, cell_start, cell_light, NULL);
        for (uint32_t j = 0; j < n; ++j) out->start[j + 1] += out->start[j];
        out->count = out->start[n];
        out->other = malloc((size_t)(out->count ? out->count : 1) * sizeof(uint32_t));
        if (!out->other) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    if (!st) {
#pragma omp parallel for schedule(dynamic, 256) num_threads(threads) if (n >= 4096)
        for (uint32_t j = 0; j < n; ++j) near_above(pos, j, r, dims, lo, inv, cell_start, cell_light, out->other + out->start[j]);
    }
    free(cell_start);
    free(cell_light);
    free(fill);
    if (st) prt__lightcloud_pairs_free(out);
    return st;
}
