/* Translucency in SH transfer (Sloan et al. 2003, "Clustered principal components for
 * precomputed radiance transfer", section on subsurface scattering; Kautz's course notes,
 * "enhanced preprocess"): light that enters a translucent surface at vertex j leaves it at vertex i
 * as Jensen's dipole says, so the exit transfer of i is the incident transfer of its medium's
 * vertices weighted by R_d(|x_i - x_j|) times their area:
 *     T_out(i) = sum_j R_d(r_ij) A_j T_in(j),
 * with T_in(j) the inter-reflected transfer of j divided by the diffuse reflectance it was bounced
 * with (what arrives at j: direct and inter-reflected). Vertices near i, where R_d changes across
 * a vertex's area, take the kernel's mean over a disc of that area (its own: the closed form). */
#include "methods/sh/bake.h"
#include "brdf/dipole.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct cell_entry {
    uint64_t key;
    uint32_t vertex;
} cell_entry;

static int by_key(const void *a, const void *b)
{
    const cell_entry *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->vertex < y->vertex ? -1 : x->vertex > y->vertex;
}

/* Cells of side `cell` in a 21-bit range per axis around the origin (far beyond any mesh). */
static uint64_t cell_key(const float *p, double cell, const int offset[3])
{
    uint64_t key = 0;
    for (int c = 0; c < 3; ++c) {
        int64_t i = (int64_t)floor(p[c] / cell) + offset[c] + (1 << 20);
        if (i < 0) i = 0;
        if (i > (1 << 21) - 1) i = (1 << 21) - 1;
        key = key << 21 | (uint64_t)i;
    }
    return key;
}

typedef struct place {
    float p[3];
    uint8_t medium;
    uint32_t vertex;
} place;

static int by_place(const void *a, const void *b)
{
    const place *x = a, *y = b;
    for (int c = 0; c < 3; ++c)
        if (x->p[c] != y->p[c]) return x->p[c] < y->p[c] ? -1 : 1;
    if (x->medium != y->medium) return x->medium < y->medium ? -1 : 1;
    return x->vertex < y->vertex ? -1 : x->vertex > y->vertex;
}

/* Vertices at one place (copies along UV or normal seams) are one patch of surface: each gets the
 * area of them all, so that the patch scatters into itself once, not once per copy. */
static bool welded_areas(const prt__mesh *m, const uint8_t *medium, const double *area, double *welded)
{
    place *order = malloc(m->vertex_count * sizeof *order);
    if (!order) return false;
    size_t n = 0;
    for (size_t v = 0; v < m->vertex_count; ++v)
        if (medium[v]) {
            memcpy(order[n].p, m->positions + v * 3, sizeof order[n].p);
            order[n].medium = medium[v];
            order[n++].vertex = (uint32_t)v;
        }
    qsort(order, n, sizeof *order, by_place);
    for (size_t i = 0; i < n;) {
        size_t j = i;
        double sum = 0;
        while (j < n && order[j].p[0] == order[i].p[0] && order[j].p[1] == order[i].p[1] && order[j].p[2] == order[i].p[2] && order[j].medium == order[i].medium) sum += area[order[j++].vertex];
        for (size_t k = i; k < j; ++k) welded[order[k].vertex] = sum;
        i = j;
    }
    free(order);
    return true;
}

static void vertex_areas(const prt__mesh *m, double *area)
{
    memset(area, 0, m->vertex_count * sizeof *area);
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        const float *a = m->positions + ix[0] * 3, *b = m->positions + ix[1] * 3, *c = m->positions + ix[2] * 3;
        float e1[3], e2[3], n[3];
        prt__v3_sub(b, a, e1);
        prt__v3_sub(c, a, e2);
        prt__v3_cross(e1, e2, n);
        const double third = 0.5 * sqrt((double)prt__v3_dot(n, n)) / 3.0;
        for (int k = 0; k < 3; ++k) area[ix[k]] += third;
    }
}

prt_status prt__sh_subsurface(prt_context *ctx, const prt__mesh *m, const uint8_t *medium, const prt__dipole (*kernels)[3], int nc, float *T,
                              prt__progress *p)
{
    const size_t nv = m->vertex_count, nc3 = 3 * (size_t)nc;
    size_t count = 0;
    int media = 0;
    for (size_t v = 0; v < nv; ++v)
        if (medium[v]) { count++; media = medium[v] > media ? medium[v] : media; }
    if (!count) return PRT_OK;
    double reach = 0;
    for (int k = 0; k < media; ++k) reach = fmax(reach, prt__dipole_reach(kernels[k]));
    if (!(reach > 0) || !isfinite(reach)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a translucent medium scatters nowhere (its reach is %g)", reach);
    double *area = malloc(2 * nv * sizeof *area), *welded = area ? area + nv : NULL;
    cell_entry *cells = malloc(count * sizeof *cells);
    float *in = malloc(count * nc3 * sizeof *in), *out = malloc(count * nc3 * sizeof *out);
    uint32_t *slot = malloc(nv * sizeof *slot);
    if (!area || !cells || !in || !out || !slot) {
        free(area); free(cells); free(in); free(out); free(slot);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for subsurface scattering over %zu vertices", count);
    }
    vertex_areas(m, area);
    if (!welded_areas(m, medium, area, welded)) {
        free(area); free(cells); free(in); free(out); free(slot);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for subsurface scattering over %zu vertices", count);
    }
    const int here[3] = {0, 0, 0};
    size_t n = 0;
    for (size_t v = 0; v < nv; ++v) {
        if (!medium[v]) continue;
        slot[v] = (uint32_t)n;
        /* What arrives at v: its inter-reflected exit over the reflectance it was bounced with. */
        for (int c = 0; c < 3; ++c) {
            const float r = m->albedo[v * 3 + c];
            for (int i = 0; i < nc; ++i) in[n * nc3 + c * nc + i] = r > 0 ? T[v * nc3 + c * nc + i] / r : 0.0f;
        }
        cells[n++] = (cell_entry){cell_key(m->positions + v * 3, reach, here), (uint32_t)v};
    }
    qsort(cells, count, sizeof *cells, by_key);
    prt__progress_begin(p, p->stage, count);
    int cancelled = 0;
#pragma omp parallel for schedule(dynamic, 64) num_threads(count < 2048 ? 1 : prt__threads(ctx))
    for (size_t e = 0; e < count; ++e) {
        if (__atomic_load_n(&cancelled, __ATOMIC_RELAXED)) continue;
        const uint32_t vi = cells[e].vertex;
        const int mi = medium[vi];
        const prt__dipole *kd = kernels[mi - 1];
        const float *pi = m->positions + (size_t)vi * 3;
        double acc[3 * PRT_SH_MAX_COEFFS];
        memset(acc, 0, nc3 * sizeof *acc);
        /* The 27 cells around vi's, each a run of the sorted entries, in a fixed order. */
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int off[3] = {dx, dy, dz};
                    const uint64_t key = cell_key(pi, reach, off);
                    size_t lo = 0, hi = count;
                    while (lo < hi) {
                        const size_t mid = (lo + hi) / 2;
                        if (cells[mid].key < key) lo = mid + 1; else hi = mid;
                    }
                    for (size_t f = lo; f < count && cells[f].key == key; ++f) {
                        const uint32_t vj = cells[f].vertex;
                        if (medium[vj] != mi) continue;   /* light scatters within one medium */
                        const double aj = area[vj], rad = sqrt(aj / PRT_PI);
                        const float *pj = m->positions + (size_t)vj * 3;
                        const double dxv = pi[0] - pj[0], dyv = pi[1] - pj[1], dzv = pi[2] - pj[2], r = sqrt(dxv * dxv + dyv * dyv + dzv * dzv);
                        if (r > reach || !(aj > 0) || !(welded[vi] > 0)) continue;
                        const float *x = in + (size_t)slot[vj] * nc3;
                        const bool same = pj[0] == pi[0] && pj[1] == pi[1] && pj[2] == pi[2];   /* vi itself or a copy */
                        const double wrad = sqrt(welded[vi] / PRT_PI);
                        for (int c = 0; c < 3; ++c) {
                            const double w = same ? prt__dipole_disc(&kd[c], wrad) * aj / welded[vi]
                                           : r < 3 * rad ? prt__dipole_disc_mean(&kd[c], r, rad) * aj
                                                         : prt__dipole_rd(&kd[c], r) * aj;
                            for (int i = 0; i < nc; ++i) acc[c * nc + i] += w * x[c * nc + i];
                        }
                    }
                }
        float *o = out + (size_t)slot[vi] * nc3;
        for (int c = 0; c < 3; ++c) {
            /* An exponential falloff spreads what the surface's albedo reflects; the dipole is its own. */
            const double scale = kd[c].falloff > 0 ? m->albedo[(size_t)vi * 3 + c] : 1.0;
            for (int i = 0; i < nc; ++i) o[c * nc + i] = (float)(acc[c * nc + i] * scale);
        }
        if ((e & 63) == 63 && prt__progress_add(p, 64)) __atomic_store_n(&cancelled, 1, __ATOMIC_RELAXED);
    }
    prt__progress_end(p);
    if (!cancelled)
        for (size_t v = 0; v < nv; ++v)
            if (medium[v]) memcpy(T + v * nc3, out + (size_t)slot[v] * nc3, nc3 * sizeof *T);
    free(area); free(cells); free(in); free(out); free(slot);
    return cancelled ? prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled") : PRT_OK;
}
