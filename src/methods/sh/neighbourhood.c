/* Neighbourhood transfer (Sloan, Kautz & Snyder 2002, section 7): a grid of points around the
 * baked scene, each holding the matrix that turns distant lighting (SH) into the radiance arriving
 * at that point - the scene's shadow and the light its surfaces reflect included:
 *     M_c,ij(p) = integral y_i(s) [V(p, s) y_j(s) + (1 - V(p, s)) T_c,j(hit(p, s))] ds,
 * T the exit transfer of the surface a ray from p meets (inter-reflected, else shadowed times
 * albedo, else nothing: only the shadow). Another object moved through that space is lit by
 * M(p) L instead of L: shadowed and lit by what the baked scene blocks and reflects. */
#include "methods/sh/bake.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void prt__sh_grid_free(prt__sh_grid *g)
{
    free(g->matrices);
    free(g->front);
    memset(g, 0, sizeof *g);
}

static void grid_point(const prt__sh_grid *g, int x, int y, int z, float p[3])
{
    const int ix[3] = {x, y, z};
    for (int c = 0; c < 3; ++c) p[c] = g->dims[c] > 1 ? g->lo[c] + (g->hi[c] - g->lo[c]) * (float)ix[c] / (float)(g->dims[c] - 1) : g->lo[c];
}

prt_status prt__sh_neighbourhood_bake(prt_context *ctx, const prt__mesh *m, const prt__raycaster *rc, const float *dirs, const float *basis, int samples,
                                      int order, const float *exit, int exit_channels, prt__sh_grid *g, prt__progress *p)
{
    const int n = order * order;
    const size_t points = (size_t)g->dims[0] * g->dims[1] * g->dims[2], per = 3 * (size_t)n * n;
    g->order = order;
    g->matrices = prt__calloc(points * per, sizeof(float));
    g->front = prt__calloc(points, sizeof(float));
    if (!g->matrices || !g->front)
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for a neighbourhood grid of %zu points", points);
    prt__progress_begin(p, p->stage, points);
    const double w = 4.0 * PRT_PI / samples;
    int cancelled = 0;
#pragma omp parallel num_threads(prt__threads(ctx))
    {
        double *acc = malloc(per * sizeof *acc);
#pragma omp for schedule(dynamic, 4)
        for (size_t k = 0; k < points; ++k) {
            if (!acc || __atomic_load_n(&cancelled, __ATOMIC_RELAXED)) continue;
            const int x = (int)(k % (size_t)g->dims[0]), y = (int)(k / (size_t)g->dims[0] % (size_t)g->dims[1]), z = (int)(k / ((size_t)g->dims[0] * g->dims[1]));
            float o[3];
            grid_point(g, x, y, z, o);
            memset(acc, 0, per * sizeof *acc);
            int back = 0;
            for (int s = 0; s < samples; ++s) {
                const float *d = dirs + (size_t)s * 3, *ys = basis + (size_t)s * n;
                prt__ray_hit h;
                if (!prt__raycaster_hit(rc, o, d, &h)) {   /* open: the distant light itself */
                    for (int i = 0; i < n; ++i)
                        for (int j = 0; j < n; ++j) {
                            const double v = w * ys[i] * ys[j];
                            for (int c = 0; c < 3; ++c) acc[((size_t)c * n + i) * n + j] += v;
                        }
                    continue;
                }
                if (h.ng[0] * d[0] + h.ng[1] * d[1] + h.ng[2] * d[2] >= 0) { back++; continue; }   /* a back face: inside, dark */
                if (!exit) continue;
                const uint32_t *t = m->indices + (size_t)h.prim * 3;
                const float bw[3] = {1.0f - h.u - h.v, h.u, h.v};
                float T[3][PRT_SH_MAX_COEFFS];
                for (int c = 0; c < 3; ++c)
                    for (int j = 0; j < n; ++j) {
                        float sum = 0;
                        for (int q = 0; q < 3; ++q) {
                            const size_t v = t[q];
                            sum += bw[q] * (exit_channels == 3 ? exit[(v * 3 + (size_t)c) * n + j] : exit[v * n + j] * m->albedo[v * 3 + c]);
                        }
                        T[c][j] = sum;
                    }
                for (int c = 0; c < 3; ++c)
                    for (int i = 0; i < n; ++i)
                        for (int j = 0; j < n; ++j) acc[((size_t)c * n + i) * n + j] += w * ys[i] * T[c][j];
            }
            g->front[k] = 1.0f - (float)back / (float)samples;
            float *out = g->matrices + k * per;
            for (size_t i = 0; i < per; ++i) out[i] = (float)acc[i];
            if (prt__progress_add(p, 1)) __atomic_store_n(&cancelled, 1, __ATOMIC_RELAXED);
        }
        if (!acc) __atomic_store_n(&cancelled, 2, __ATOMIC_RELAXED);
        free(acc);
    }
    prt__progress_end(p);
    if (cancelled == 2) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the neighbourhood grid");
    if (cancelled) return prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    return PRT_OK;
}

void prt__sh_neighbourhood_eval(const prt__sh_grid *g, const float p[3], const prt_sh_light *in, int order, prt_sh_light *out)
{
    const int n = order * order, gn = g->order * g->order;
    memset(out, 0, sizeof *out);
    out->order = order;
    /* Trilinear weights; outside the grid the nearest face's points (clamped). */
    int i0[3];
    float f[3];
    for (int c = 0; c < 3; ++c) {
        const float span = g->hi[c] - g->lo[c];
        float u = g->dims[c] > 1 && span > 0 ? (p[c] - g->lo[c]) / span * (float)(g->dims[c] - 1) : 0.0f;
        u = fminf(fmaxf(u, 0.0f), (float)(g->dims[c] - 1));
        i0[c] = (int)floorf(u);
        if (i0[c] >= g->dims[c] - 1) i0[c] = g->dims[c] > 1 ? g->dims[c] - 2 : 0;
        f[c] = g->dims[c] > 1 ? u - (float)i0[c] : 0.0f;
    }
    /* A point inside or behind geometry (under a floor, behind a wall) stands in for the space
     * around it less: its weight falls from 1 with none of its rays meeting back faces to 0 with
     * a quarter of them (points in the open meet front faces only). */
    float w8[8], total = 0;
    int at8[3 * 8];
    for (int corner = 0; corner < 8; ++corner) {
        float wgt = 1;
        for (int c = 0; c < 3; ++c) {
            const int b = corner >> c & 1;
            if (b && g->dims[c] == 1) { wgt = 0; break; }
            at8[corner * 3 + c] = i0[c] + b;
            wgt *= b ? f[c] : 1.0f - f[c];
        }
        w8[corner] = wgt;
        if (wgt == 0) continue;
        const float front = g->front[((size_t)at8[corner * 3 + 2] * g->dims[1] + at8[corner * 3 + 1]) * g->dims[0] + at8[corner * 3]];
        const float trust = fminf(fmaxf(4.0f * front - 3.0f, 0.0f), 1.0f);
        total += wgt * trust;
    }
    if (total > 1e-6f)
        for (int corner = 0; corner < 8; ++corner) {
            if (w8[corner] == 0) continue;
            const float front = g->front[((size_t)at8[corner * 3 + 2] * g->dims[1] + at8[corner * 3 + 1]) * g->dims[0] + at8[corner * 3]];
            w8[corner] *= fminf(fmaxf(4.0f * front - 3.0f, 0.0f), 1.0f) / total;
        }
    float L[3][PRT_SH_MAX_COEFFS];
    memset(L, 0, sizeof L);
    for (int c = 0; c < 3; ++c)
        for (int j = 0; j < n && j < in->order * in->order; ++j) L[c][j] = in->coeffs[c][j];
    for (int corner = 0; corner < 8; ++corner) {
        const float wgt = w8[corner];
        const int *ix = at8 + corner * 3;
        if (wgt == 0) continue;
        const float *M = g->matrices + (((size_t)ix[2] * g->dims[1] + ix[1]) * g->dims[0] + ix[0]) * 3 * (size_t)gn * gn;
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < n; ++i) {
                float sum = 0;
                for (int j = 0; j < n; ++j) sum += M[((size_t)c * gn + i) * gn + j] * L[c][j];
                out->coeffs[c][i] += wgt * sum;
            }
    }
}

int prt_transfer_neighbourhood(const prt_transfer *t, int dims[3], float lo[3], float hi[3])
{
    const prt__sh_state *s = prt__sh(t);
    if (!s || !s->grid.matrices) return 0;
    if (dims) memcpy(dims, s->grid.dims, sizeof s->grid.dims);
    if (lo) memcpy(lo, s->grid.lo, sizeof s->grid.lo);
    if (hi) memcpy(hi, s->grid.hi, sizeof s->grid.hi);
    return 1;
}

prt_status prt_sh_light_at(prt_context *ctx, const prt_transfer *t, const float p[3], const prt_sh_light *light, prt_sh_light *out)
{
    if (!t || !p || !light || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_sh_light_at: transfer, point, light and out are required");
    const prt__sh_state *s = prt__sh_need(ctx, t);
    if (!s) return PRT_ERR_INVALID_ARG;
    if (!s->grid.matrices)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' holds no neighbourhood transfer: bake it with --neighbourhood N", t->source);
    if (light->order < 1 || light->order > PRT_SH_MAX_ORDER) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting SH order %d out of range", light->order);
    if (!(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_sh_light_at: the point is not finite");
    prt__sh_neighbourhood_eval(&s->grid, p, light, light->order < s->grid.order ? light->order : s->grid.order, out);
    return PRT_OK;
}

bool prt__sh_light_at_box(const prt_transfer *t, float lo[3], float hi[3]) { return prt_transfer_neighbourhood(t, NULL, lo, hi) != 0; }

prt_status prt__sh_light_at_lighting(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float p[3], prt_sh_light *out)
{
    const prt__sh_state *s = prt__sh(t);
    prt_sh_light distant;
    prt_status st = prt_lighting_sh(l, s->grid.order, &distant);
    return st ? prt__fail(ctx, st, "%s", prt_last_error()) : prt_sh_light_at(ctx, t, p, &distant, out);
}
