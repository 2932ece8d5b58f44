/* Glossy relighting: exit radiance SH vectors per vertex from the transfer matrices,
 *   e_p = A_p M_p L
 * where A_p is the reflection lobe's per-band factor rho_s a_l (run-time convolution, evaluated
 * at the mirrored view direction) or the identity when the BRDF was baked in. Compressed sets
 * are relit as Sloan et al. 2003 do: the cluster means and PCA vectors meet the lighting once,
 * then each vertex sums a few n-vectors. The view factor - evaluating e at a direction - is the
 * renderer's, per pixel (prt_glossy_eval on the CPU). */
#include "methods/sh/sh.h"

#include <omp.h>
#include <string.h>

/* out[c][i] = f[c][i] sum_j X[c or 0][j][i] L[c][j] for the first nl lighting coefficients (f:
 * the lobe factors per coefficient, NULL for none). One pass over the matrix rows feeds all three
 * channels; the fixed-size variants let the compiler keep the accumulators in vector registers,
 * and the factors meet them there before the one store. */
static inline __attribute__((always_inline)) void apply_light_n(const float *restrict X, int channels, int n, int nl,
                                                                const prt_sh_light *light, const float *restrict f, float *restrict out)
{
    float o0[PRT_SH_MAX_COEFFS], o1[PRT_SH_MAX_COEFFS], o2[PRT_SH_MAX_COEFFS];
    for (int i = 0; i < n; ++i) o0[i] = o1[i] = o2[i] = 0.0f;   /* only n: zeroing all 100 cost more than the sums */
    if (channels == 1) {
        for (int j = 0; j < nl; ++j) {
            const float l0 = light->coeffs[0][j], l1 = light->coeffs[1][j], l2 = light->coeffs[2][j];
            const float *row = X + (size_t)j * n;
#pragma omp simd
            for (int i = 0; i < n; ++i) { o0[i] += l0 * row[i]; o1[i] += l1 * row[i]; o2[i] += l2 * row[i]; }
        }
    } else {
        const size_t nn = (size_t)n * n;
        for (int j = 0; j < nl; ++j) {
            const float l0 = light->coeffs[0][j], l1 = light->coeffs[1][j], l2 = light->coeffs[2][j];
            const float *r0 = X + (size_t)j * n, *r1 = r0 + nn, *r2 = r1 + nn;
#pragma omp simd
            for (int i = 0; i < n; ++i) { o0[i] += l0 * r0[i]; o1[i] += l1 * r1[i]; o2[i] += l2 * r2[i]; }
        }
    }
    if (f)
        for (int i = 0; i < n; ++i) { o0[i] *= f[i]; o1[i] *= f[n + i]; o2[i] *= f[2 * n + i]; }
    memcpy(out, o0, (size_t)n * sizeof(float));
    memcpy(out + n, o1, (size_t)n * sizeof(float));
    memcpy(out + 2 * n, o2, (size_t)n * sizeof(float));
}

static void apply_light(const float *X, int channels, int n, int nl, const prt_sh_light *light, const float *f, float *out)
{
    switch (n) {   /* orders 3 to 6 cover glossy use; the generic path handles the rest */
    case 9: apply_light_n(X, channels, 9, nl, light, f, out); break;
    case 16: apply_light_n(X, channels, 16, nl, light, f, out); break;
    case 25: apply_light_n(X, channels, 25, nl, light, f, out); break;
    case 36: apply_light_n(X, channels, 36, nl, light, f, out); break;
    default: apply_light_n(X, channels, n, nl, light, f, out); break;
    }
}

/* Each material's lobe factors, expanded to every coefficient ([k][c][i] for coefficient i = l(l + 1) + m
 * of band l), and whether it has a glossy lobe (has[k]). */
static prt_status lobe_factors(const prt_transfer *t, int order, const prt_brdf *brdf, float *table, bool *has)
{
    const int count = brdf ? 1 : t->brdf_count;
    for (int k = 0; k < count; ++k) {
        const prt_brdf *b = brdf ? brdf : &t->brdfs[k];
        has[k] = prt_brdf_is_glossy(b);
        if (!has[k]) continue;
        double a[PRT_SH_MAX_ORDER];
        prt_status st = prt_brdf_lobe_bands(b, order, a);
        if (st) return st;
        /* The lobe integrates to one; the BRDF's own normalisation and its cosine (n.v at the mirror
         * direction, applied where the exit vector is evaluated) make it the library's Phong or
         * Blinn-Phong: (n+2)/(n+1) and, for Blinn-Phong's mirror lobe of exponent n/4, (n+8)/(n+4). */
        const double n = b->exponent, norm = b->model == PRT_BRDF_BLINN_PHONG ? (n + 8.0) / (n + 4.0) : (n + 2.0) / (n + 1.0);
        const int nc = order * order;
        for (int c = 0; c < 3; ++c)
            for (int l = 0; l < order; ++l)
                for (int m = -l; m <= l; ++m) table[((size_t)k * 3 + c) * nc + l * (l + 1) + m] = (float)(b->specular[c] * a[l] * norm);
    }
    return PRT_OK;
}

prt_status prt_relight_sh_glossy(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light,
                                 const prt_brdf *brdf, float *out_exit)
{
    return prt__relight_sh_glossy(ctx, t, kind, light, brdf, true, NULL, 0, out_exit);
}

prt_status prt__relight_sh_glossy(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light,
                                  const prt_brdf *brdf, bool brdf_everywhere, const float *local, int local_order, float *out_exit)
{
    if (!t || !light || !out_exit) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_relight_sh_glossy: transfer, light and output are required");
    const prt__sh_state *sh = prt__sh_need(ctx, t);
    if (!sh) return PRT_ERR_INVALID_ARG;
    int k = prt__kind_index(kind);
    if (k < 0 || !prt__kind_glossy(k)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s is not a glossy kind", prt_transfer_kind_name(kind));
    const prt__sh_set *s = &sh->sets[k];
    if (!s->channels) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer holds no %s set (bake it with --kinds %s)",
                                       prt_transfer_kind_name(kind), prt_transfer_kind_name(kind));
    if (light->order < 1 || light->order > PRT_SH_MAX_ORDER) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "light order %d out of range", light->order);
    if (sh->glossy_exit && brdf)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "this transfer has its BRDF baked in; a run-time BRDF cannot replace it (re-bake without --brdf)");
    bool has[PRT__MAX_BRDFS] = {false};
    /* A run-time lobe given for the glossy materials only replaces their lobes: the diffuse
     * surfaces beside them stay diffuse. */
    bool scene_glossy[PRT__MAX_BRDFS] = {false};
    if (brdf && !brdf_everywhere && !sh->glossy_exit) {
        bool any = false;
        for (int i = 0; i < t->brdf_count && i < PRT__MAX_BRDFS; ++i) any |= scene_glossy[i] = prt_brdf_is_glossy(&t->brdfs[i]);
        if (!any)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf shapes the glossy materials and this scene has none (they are named in a "
                             "JSON scene, docs/SCENE.md): --brdf-all gives every surface the lobe");
    }
    if (local && (local_order < 1 || local_order > light->order || local_order > sh->order))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "local lights at order %d for a lighting of order %d", local_order, light->order);
    float *table = NULL;   /* lobe_factors'; shared by the worker threads */
    if (!sh->glossy_exit) {
        if (brdf && prt_brdf_validate(brdf)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "BRDF: %s", prt_last_error());
        if (!(table = malloc((size_t)(brdf ? 1 : t->brdf_count) * 3 * sh->order * sh->order * sizeof(float) + 1)))
            return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        prt_status st = lobe_factors(t, sh->order, brdf, table, has);
        if (st) { free(table); return prt__fail(ctx, st, "%s", prt_last_error()); }
        bool any = false;
        for (int i = 0; i < (brdf ? 1 : t->brdf_count); ++i) any |= has[i];
        if (!any) {
            free(table);
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "no glossy material to convolve with: name a BRDF (--brdf phong:N) or give the scene glossy materials");
        }
    }
    const int n = sh->order * sh->order, nl = light->order < sh->order ? light->order * light->order : n;
    const size_t nv = t->mesh.vertex_count, dim = prt__set_dim(sh, k);
    const prt__cpca *cp = s->cpca;
    const int nloc = local ? local_order * local_order : 0;
    /* Compressed sets meet per-vertex lighting one vertex at a time: its matrix rebuilt in a
     * buffer of the thread's own. */
    const int threads = prt__threads(ctx);
    float *rows = cp && local ? malloc((size_t)threads * dim * sizeof(float)) : NULL;
    if (cp && local && !rows) { free(table); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    /* Compressed: every mean and PCA vector meets the lighting once. */
    float *proj_mean = NULL, *proj_basis = NULL;
    if (cp) {
        proj_mean = malloc((size_t)cp->clusters * 3 * n * sizeof(float));
        proj_basis = malloc((cp->vectors_total ? cp->vectors_total : 1) * 3 * (size_t)n * sizeof(float));
        if (!proj_mean || !proj_basis) { free(proj_mean); free(proj_basis); free(rows); free(table); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
        for (size_t q = 0; q < (size_t)cp->clusters + cp->vectors_total; ++q) {
            if (q < (size_t)cp->clusters) apply_light(cp->means + q * dim, s->channels, n, nl, light, NULL, proj_mean + q * 3 * n);
            else apply_light(cp->basis + (q - cp->clusters) * dim, s->channels, n, nl, light, NULL, proj_basis + (q - cp->clusters) * 3 * n);
        }
    }
#pragma omp parallel for schedule(static) num_threads(threads)
    for (size_t v = 0; v < nv; ++v) {
        float *e = out_exit + v * 3 * n;
        prt_sh_light here;   /* the distant lighting plus this vertex's local lights */
        const prt_sh_light *lv = light;
        if (local && !cp) {
            here = *light;
            const float *L = local + v * 3 * (size_t)nloc;
            for (int c = 0; c < 3; ++c)
                for (int i = 0; i < nloc; ++i) here.coeffs[c][i] += L[c * nloc + i];
            lv = &here;
        }
        const int own = t->mesh.material ? t->mesh.material[v] : 0;
        const int mat = !brdf ? own : brdf_everywhere || (own && scene_glossy[own - 1]) ? 1 : 0;
        if (!sh->glossy_exit && (!mat || !has[mat - 1])) { memset(e, 0, (size_t)3 * n * sizeof(float)); continue; }
        const float *restrict f = sh->glossy_exit ? NULL : table + (size_t)(mat - 1) * 3 * n;
        if (cp) {
            const uint32_t cl = cp->cluster_of[v], cnt = cp->counts[cl];
            const float *restrict mean = proj_mean + (size_t)cl * 3 * n, *restrict B = proj_basis + cp->basis_start[cl] * 3 * n;
            const float *restrict w = cp->weights + cp->weight_start[v];
            /* Four vectors per pass: adding them one by one into e chained every add through a
             * store and a load of the same bytes. */
            const int m3 = 3 * n;
            memcpy(e, mean, (size_t)m3 * sizeof(float));
            uint32_t j = 0;
            for (; j + 4 <= cnt; j += 4) {
                const float w0 = w[j], w1 = w[j + 1], w2 = w[j + 2], w3 = w[j + 3];
                const float *restrict b0 = B + (size_t)j * m3, *restrict b1 = b0 + m3, *restrict b2 = b1 + m3, *restrict b3 = b2 + m3;
#pragma omp simd
                for (int i = 0; i < m3; ++i) e[i] += w0 * b0[i] + w1 * b1[i] + w2 * b2[i] + w3 * b3[i];
            }
            for (; j < cnt; ++j) {
                const float wj = w[j], *restrict bj = B + (size_t)j * m3;
#pragma omp simd
                for (int i = 0; i < m3; ++i) e[i] += wj * bj[i];
            }
            if (local) {
                float *M = rows + (size_t)omp_get_thread_num() * dim, add[3 * PRT_SH_MAX_COEFFS];
                memcpy(M, cp->means + (size_t)cl * dim, dim * sizeof(float));
                for (j = 0; j < cnt; ++j) {
                    const float wj = w[j], *restrict bj = cp->basis + (cp->basis_start[cl] + j) * dim;
#pragma omp simd
                    for (size_t i = 0; i < dim; ++i) M[i] += wj * bj[i];
                }
                memset(&here, 0, sizeof here);
                here.order = local_order;
                const float *L = local + v * 3 * (size_t)nloc;
                for (int c = 0; c < 3; ++c) memcpy(here.coeffs[c], L + c * nloc, (size_t)nloc * sizeof(float));
                apply_light(M, s->channels, n, nloc, &here, NULL, add);
                for (int i = 0; i < m3; ++i) e[i] += add[i];
            }
            if (f)
                for (int i = 0; i < m3; ++i) e[i] *= f[i];
        } else {
            apply_light(s->coeffs + v * dim, s->channels, n, nl, lv, f, e);
        }
    }
    free(table);
    free(proj_mean);
    free(proj_basis);
    free(rows);
    return PRT_OK;
}
