/* Orthonormal 2D Haar transform, non-standard decomposition: one level replaces every 2 x 2 block
 * (a b / c d) of the current s x s average image by its average and three details, each scaled
 * by 1/2 so that the step is orthonormal. */
#include "core/haar.h"
#include "core/internal.h"
#include "prt/haar.h"

#include <string.h>

void prt__haar2d_forward(float *img, int n)
{
    float out[PRT__HAAR_MAX * PRT__HAAR_MAX];
    for (int s = n; s >= 2; s >>= 1) {
        const int h = s / 2;
        for (int y = 0; y < h; ++y) {
            const float *r0 = img + (size_t)(2 * y) * n, *r1 = r0 + n;
            float *top = out + (size_t)y * s, *bottom = out + (size_t)(h + y) * s;
            for (int x = 0; x < h; ++x) {
                float a = r0[2 * x], b = r0[2 * x + 1], c = r1[2 * x], d = r1[2 * x + 1];
                top[x] = 0.5f * (a + b + c + d);
                top[h + x] = 0.5f * (a - b + c - d);
                bottom[x] = 0.5f * (a + b - c - d);
                bottom[h + x] = 0.5f * (a - b - c + d);
            }
        }
        for (int y = 0; y < s; ++y) memcpy(img + (size_t)y * n, out + (size_t)y * s, (size_t)s * sizeof(float));
    }
}

void prt__haar2d_inverse(float *img, int n)
{
    float out[PRT__HAAR_MAX * PRT__HAAR_MAX];
    for (int s = 2; s <= n; s <<= 1) {
        const int h = s / 2;
        for (int y = 0; y < h; ++y) {
            const float *top = img + (size_t)y * n, *bottom = img + (size_t)(h + y) * n;
            float *r0 = out + (size_t)(2 * y) * s, *r1 = r0 + s;
            for (int x = 0; x < h; ++x) {
                float m = top[x], dh = top[h + x], dv = bottom[x], dd = bottom[h + x];
                r0[2 * x] = 0.5f * (m + dh + dv + dd);
                r0[2 * x + 1] = 0.5f * (m - dh + dv - dd);
                r1[2 * x] = 0.5f * (m + dh - dv - dd);
                r1[2 * x + 1] = 0.5f * (m - dh - dv + dd);
            }
        }
        for (int y = 0; y < s; ++y) memcpy(img + (size_t)y * n, out + (size_t)y * s, (size_t)s * sizeof(float));
    }
}

prt_status prt_haar2d(float *img, int n, int inverse)
{
    if (!img || n < 1 || n > PRT__HAAR_MAX || (n & (n - 1)))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "Haar transform size %d must be a power of two from 1 to %d", n, PRT__HAAR_MAX);
    if (inverse) prt__haar2d_inverse(img, n);
    else prt__haar2d_forward(img, n);
    return PRT_OK;
}
