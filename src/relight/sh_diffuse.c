/* Run-time SH relighting: per vertex, exit radiance = transfer . lighting per channel.
 * The lighting is laid out like a vertex's transfer block so the inner loop is one contiguous
 * multiply-add the compiler vectorizes; vertices are split statically across threads. */
#include "core/transfer_set.h"

#include <string.h>

prt_status prt_relight_sh(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light, float *out_rgb)
{
    if (!t || !light || !out_rgb) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_relight_sh: transfer, light and output are required");
    int k = prt__kind_index(kind);
    if (k < 0 || !t->sets[k].channels)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer holds no %s set", prt_transfer_kind_name(kind));
    if (light->order < 1 || light->order > PRT_SH_MAX_ORDER)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting SH order %d out of range", light->order);
    const int stride = t->order * t->order;
    const int order = light->order < t->order ? light->order : t->order;
    const int n = order * order;
    const int ch = t->sets[k].channels;
    const float *coeffs = t->sets[k].coeffs;
    const float *albedo = t->mesh.albedo;
    const long nv = (long)t->mesh.vertex_count;

    if (ch == 3) {
        /* Lighting laid out as [channel][stride], zero beyond the common order. */
        float lp[3 * PRT_SH_MAX_COEFFS];
        memset(lp, 0, sizeof lp);
        for (int c = 0; c < 3; ++c) memcpy(lp + c * stride, light->coeffs[c], (size_t)n * sizeof(float));
        const int m = 3 * stride;
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
        for (long v = 0; v < nv; ++v) {
            const float *tv = coeffs + (size_t)v * m;
            for (int c = 0; c < 3; ++c) {
                const float *a = tv + c * stride, *b = lp + c * stride;
                float s = 0.0f;
#pragma omp simd reduction(+ : s)
                for (int i = 0; i < n; ++i) s += a[i] * b[i];
                out_rgb[v * 3 + c] = s;
            }
        }
    } else {
        float lr[PRT_SH_MAX_COEFFS], lg[PRT_SH_MAX_COEFFS], lb[PRT_SH_MAX_COEFFS];
        memcpy(lr, light->coeffs[0], sizeof lr);
        memcpy(lg, light->coeffs[1], sizeof lg);
        memcpy(lb, light->coeffs[2], sizeof lb);
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
        for (long v = 0; v < nv; ++v) {
            const float *a = coeffs + (size_t)v * stride;
            float r = 0.0f, g = 0.0f, b = 0.0f;
#pragma omp simd reduction(+ : r, g, b)
            for (int i = 0; i < n; ++i) {
                r += a[i] * lr[i];
                g += a[i] * lg[i];
                b += a[i] * lb[i];
            }
            out_rgb[v * 3] = r * albedo[v * 3];
            out_rgb[v * 3 + 1] = g * albedo[v * 3 + 1];
            out_rgb[v * 3 + 2] = b * albedo[v * 3 + 2];
        }
    }
    return PRT_OK;
}
