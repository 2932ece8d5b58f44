/* The bounced light averaged over each receiver's neighbours on its chart (offset.h,
 * prt__offset_smooth): a tent of prt__offset_smooth_radius texels, weighted by texel area and by
 * how alike the texels face. */
#include "methods/offset/offset.h"

int prt__offset_smooth_radius(const prt__offset_set *s)
{
    const int side = s->width < s->height ? s->width : s->height, r = side / 64;
    return r < 1 ? 1 : r > PRT__OFFSET_SMOOTH_MAX ? PRT__OFFSET_SMOOTH_MAX : r;
}

void prt__offset_smooth(prt_context *ctx, const prt__offset_set *s, const float *in, float *out)
{
    const int W = s->width, H = s->height, R = prt__offset_smooth_radius(s);
    const ptrdiff_t nc = (ptrdiff_t)s->covered;
#pragma omp parallel for schedule(static, 256) num_threads(prt__threads(ctx))
    for (ptrdiff_t i = 0; i < nc; ++i) {
        const int x = s->xy[i], y = s->xy[nc + i];
        const int32_t own = s->chart[i];
        if (own < 0) {   /* no chart of its own (none in practice): its own light, as the pyramid reads it */
            memcpy(out + i * 3, in + i * 3, 3 * sizeof *out);
            continue;
        }
        /* In float and in this order: the GPU's final pass (render/light_map_gl.c) sums the same way. */
        float acc[3] = {0, 0, 0}, sum = 0;
        for (int dy = -R; dy <= R; ++dy)
            for (int dx = -R; dx <= R; ++dx) {
                const int X = x + dx, Y = y + dy;
                if (X < 0 || Y < 0 || X >= W || Y >= H) continue;
                const int32_t j = s->index[(size_t)Y * W + X];
                if (j < 0 || s->chart[j] != own) continue;
                const float *n = s->nrm + i * 3, *m = s->nrm + (size_t)j * 3;
                const float w = (float)((R + 1 - abs(dx)) * (R + 1 - abs(dy))) * s->area[j] * prt__offset_smooth_facing(n[0] * m[0] + n[1] * m[1] + n[2] * m[2]);
                if (!(w > 0)) continue;   /* a texel facing away (or of no area) adds nothing, not even its NaN */
                for (int c = 0; c < 3; ++c) acc[c] += w * in[(size_t)j * 3 + c];
                sum += w;
            }
        for (int c = 0; c < 3; ++c) out[i * 3 + c] = sum > 0 ? acc[c] / sum : in[i * 3 + c];
    }
}
