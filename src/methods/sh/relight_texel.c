/* Per-texel relighting: one dot product per texel and channel into a radiance map the renderer
 * samples per pixel. Cheap next to drawing (a 512 x 512 map of 25 coefficients is 6.5 M
 * multiply-adds), so it runs on every lighting change. */
#include "methods/sh/sh.h"

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
