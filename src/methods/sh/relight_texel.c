/* Per-texel relighting: one dot product per texel and channel into a radiance map the renderer
 * samples per pixel. Cheap next to drawing (a 512 x 512 map of 25 coefficients is 6.5 M
 * multiply-adds), so it runs on every lighting change. */
#include "methods/sh/sh.h"
#include "geom/texel_raster.h"

#include <string.h>

prt_status prt_relight_sh_texels(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light, float *out_rgb)
{
    if (!t || !light || !out_rgb) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_relight_sh_texels: transfer, light and output are required");
    const prt__sh_state *sh = prt__sh_need(ctx, t);
    if (!sh) return PRT_ERR_INVALID_ARG;
    int k = prt__kind_index(kind);
    const prt__texel_sets *s = &sh->texels;
    if (k < 0 || k > 2 || !s->coeffs[k])
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer holds no per-texel %s set (bake with --texels N --kinds %s)",
                         prt_transfer_kind_name(kind), prt_transfer_kind_name(kind));
    if (light->order < 1 || light->order > PRT_SH_MAX_ORDER) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "light order %d out of range", light->order);
    const int n = sh->order * sh->order, nl = light->order < sh->order ? light->order * light->order : n, ch = s->channels[k];
    const size_t ntex = (size_t)s->width * s->height;
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
    for (size_t i = 0; i < ntex; ++i) {
        const float *T = s->coeffs[k] + i * (size_t)ch * n;
        for (int c = 0; c < 3; ++c) {
            const float *Tc = T + (ch == 3 ? (size_t)c * n : 0);
            float sum = 0.0f;
            for (int j = 0; j < nl; ++j) sum += Tc[j] * light->coeffs[c][j];
            out_rgb[i * 3 + c] = ch == 1 ? sum * s->albedo[i * 3 + c] : sum;
        }
    }
    return PRT_OK;
}

/* Local lights per texel: each baked texel's surface point from the file's UV layout (the texel
 * bake's raster), its lights projected there and dotted with its transfer. The texels around the
 * charts take their neighbours' local light ring by ring, as the bake filled their transfer, so
 * that filtering pulls in no dark seams. */
prt_status prt__relight_sh_texels_local(prt_context *ctx, const prt_transfer *t, int k, const prt_lighting *l, int order, int window, float *out_rgb)
{
    const prt__sh_state *sh = prt__sh_need(ctx, t);
    if (!sh) return PRT_ERR_INVALID_ARG;
    const prt__texel_sets *s = &sh->texels;
    if (k < 0 || k > 2 || !s->coeffs[k] || order < 1 || order > sh->order)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "local lights: no per-texel set %d at order %d", k, order);
    if (!prt__mesh_has_uv(&t->mesh)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "local lights per texel need the file's UVs, and it has none");
    const int W = s->width, H = s->height, n = sh->order * sh->order, nl = order * order, ch = s->channels[k];
    const size_t ntex = (size_t)W * H;
    uint32_t *owner = calloc(ntex, sizeof *owner);   /* the raster claims texels whose owner is 0 */
    float *bary = malloc(ntex * 2 * sizeof *bary), *points = malloc(ntex * 3 * sizeof *points);
    size_t overlap, outside, count = 0;
    size_t *index = malloc(ntex * sizeof *index);
    prt_status st = PRT_OK;
    if (!owner || !bary || !points || !index || !prt__texel_raster(&t->mesh, W, H, owner, bary, &overlap, &outside)) {
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %dx%d texels", W, H);
        goto done;
    }
    const prt__mesh *m = &t->mesh;
    for (size_t i = 0; i < ntex; ++i) {
        if (!owner[i] || s->covered[i] != 1) continue;
        const uint32_t *ix = m->indices + (size_t)(owner[i] - 1) * 3;
        const float b1 = bary[i * 2], b2 = bary[i * 2 + 1], b0 = 1.0f - b1 - b2;
        for (int c = 0; c < 3; ++c)
            points[count * 3 + c] = b0 * m->positions[ix[0] * 3 + c] + b1 * m->positions[ix[1] * 3 + c] + b2 * m->positions[ix[2] * 3 + c];
        index[count++] = i;
    }
    /* The lights' SH for a block of texels at a time: a whole 1024^2 map at order 6 would hold
     * 430 MB of it. */
    enum { BLOCK = 16384 };
    float *local = malloc((size_t)BLOCK * 3 * (size_t)nl * sizeof(float)), *map = calloc(ntex * 3, sizeof(float));
    uint8_t *mask = calloc(ntex, 1);
    if (!local || !map || !mask) { free(local); free(map); free(mask); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
    for (size_t q0 = 0; q0 < count; q0 += BLOCK) {
        const size_t nb = count - q0 < BLOCK ? count - q0 : BLOCK;
        prt__sh_local_project(ctx, l, order, window, points + q0 * 3, nb, local);
#pragma omp parallel for schedule(static) num_threads(nb < 4096 ? 1 : prt__threads(ctx))
        for (size_t q = 0; q < nb; ++q) {
            const size_t i = index[q0 + q];
            const float *T = s->coeffs[k] + i * (size_t)ch * n, *L = local + q * 3 * (size_t)nl;
            for (int c = 0; c < 3; ++c) {
                const float *Tc = T + (ch == 3 ? (size_t)c * n : 0), *Lc = L + c * nl;
                float sum = 0.0f;
                for (int j = 0; j < nl; ++j) sum += Tc[j] * Lc[j];
                map[i * 3 + c] = ch == 1 ? sum * s->albedo[i * 3 + c] : sum;
            }
            mask[i] = 1;
        }
    }
    const int three = 3;
    int32_t *label = malloc(ntex * sizeof *label);
    if (!label) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    else if (!(st = prt__texel_support_charts(ctx, m, W, H, label)) && !prt__texel_fill_gutters(W, H, label, mask, &map, &three, 1))
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    free(label);
    for (size_t i = 0; !st && i < ntex; ++i)
        if (s->covered[i])
            for (int c = 0; c < 3; ++c) out_rgb[i * 3 + c] += map[i * 3 + c];
    free(local);
    free(map);
    free(mask);
done:
    free(owner);
    free(bary);
    free(points);
    free(index);
    return st;
}
