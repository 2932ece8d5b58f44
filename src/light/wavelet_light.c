/* Wavelet lighting (Ng et al. 2003; Wang et al. 2005 section 4.3): the environment box-filtered
 * into a 6 x 64 x 64 cube map, each face Haar-transformed, the largest coefficients kept and
 * quantized. Many more coefficients are kept than per transport vector, so that rotating the
 * lighting does not flicker. */
#include "core/cubemap.h"
#include "core/haar.h"
#include "light/envmap_internal.h"
#include "prt/wavelet.h"

#include <math.h>
#include <string.h>

#define FACE PRT_WAVELET_FACE
#define DIM PRT_WAVELET_DIM

struct prt_wavelet_light {
    float *cube;     /* [texel][3] radiance */
    float *coeffs;   /* [index][4] */
    int kept;
};

void prt_wavelet_texel(int index, float dir[3], float *solid_angle)
{
    int face = index / (FACE * FACE), y = index / FACE % FACE, x = index % FACE;
    prt__cube_texel(FACE, face, x, y, dir, solid_angle);
}

static int cmp_desc(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x < y) - (x > y);
}

prt_status prt_wavelet_light_create(prt_context *ctx, const prt_envmap *env, const prt_wavelet_light_desc *desc,
                                    prt_wavelet_light **out)
{
    if (!env || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_wavelet_light_create: env and out are required");
    *out = NULL;
    prt_wavelet_light_desc d = desc ? *desc : (prt_wavelet_light_desc){0};
    if (d.coefficients == 0) d.coefficients = 4096;
    if (d.bits == 0) d.bits = 16;
    if (d.intensity == 0) d.intensity = 1.0f;
    if (d.coefficients < 1 || d.coefficients > DIM)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting coefficients %d out of range 1..%d", d.coefficients, DIM);
    if (d.bits != 16 && d.bits != 32) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting bits must be 16 or 32, not %d", d.bits);
    if (!(d.intensity > 0) || !isfinite(d.intensity)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting intensity must be > 0");
    if (d.supersample < 0 || d.supersample > 16) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting supersampling %d out of range 0..16", d.supersample);
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    bool any = false;
    for (int i = 0; i < 9; ++i) any |= d.rotation[i] != 0;
    if (any) memcpy(R, d.rotation, sizeof R);
    int ss = d.supersample;
    if (!ss) {
        /* About one bilinear lookup per map pixel under the texel: every pixel contributes. */
        const prt_image *img = &env->img;
        double pixel = sqrt(4.0 * PRT_PI / ((double)img->width * img->height)), texel = 0.5 * PRT_PI / FACE;
        ss = (int)ceil(texel / pixel);
        ss = ss < 2 ? 2 : ss > 16 ? 16 : ss;
    }

    prt_wavelet_light *l = prt__calloc(1, sizeof *l);
    float *planes = prt__calloc((size_t)3 * DIM, sizeof(float)), *mag = prt__calloc(DIM, sizeof(float));
    if (l) {
        l->cube = prt__calloc((size_t)DIM * 3, sizeof(float));
        l->coeffs = prt__calloc((size_t)DIM * 4, sizeof(float));
    }
    if (!l || !planes || !mag || !l->cube || !l->coeffs) {
        prt_wavelet_light_release(l); free(planes); free(mag);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
    for (int t = 0; t < DIM; ++t) {
        int face = t / (FACE * FACE), y = t / FACE % FACE, x = t % FACE;
        double acc[3] = {0, 0, 0}, wsum = 0;
        for (int sy = 0; sy < ss; ++sy)
            for (int sx = 0; sx < ss; ++sx) {
                float a = (float)(2.0 * (x + (sx + 0.5) / ss) / FACE - 1.0), b = (float)(2.0 * (y + (sy + 0.5) / ss) / FACE - 1.0);
                float dir[3], src[3], rgb[3];
                prt__cube_dir(face, a, b, dir);
                /* Weight by the solid angle of the sample: the cube's Jacobian (1 + a^2 + b^2)^-3/2. */
                double r2 = 1.0 + (double)a * a + (double)b * b, w = 1.0 / (r2 * sqrt(r2));
                const float inv = (float)(1.0 / sqrt(r2));   /* |dir| = sqrt(r2); lookups want unit vectors */
                for (int i = 0; i < 3; ++i) dir[i] *= inv;
                for (int i = 0; i < 3; ++i) src[i] = (float)(R[i] * dir[0] + R[3 + i] * dir[1] + R[6 + i] * dir[2]);   /* R^T d */
                prt_envmap_lookup(env, src, rgb);
                for (int c = 0; c < 3; ++c) acc[c] += w * rgb[c];
                wsum += w;
            }
        for (int c = 0; c < 3; ++c) {
            float v = (float)(acc[c] / wsum) * d.intensity;
            l->cube[(size_t)t * 3 + c] = v;
            planes[(size_t)c * DIM + t] = v;
        }
    }
    for (int c = 0; c < 3; ++c)
        for (int f = 0; f < 6; ++f) prt__haar2d_forward(planes + (size_t)c * DIM + (size_t)f * FACE * FACE, FACE);
    for (int j = 0; j < DIM; ++j) {
        float r = planes[j], g = planes[DIM + j], b = planes[2 * DIM + j];
        mag[j] = r * r + g * g + b * b;
    }
    float thr = -1.0f;
    if (d.coefficients < DIM) {
        float *sorted = malloc((size_t)DIM * sizeof(float));
        if (!sorted) { prt_wavelet_light_release(l); free(planes); free(mag); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        memcpy(sorted, mag, (size_t)DIM * sizeof(float));
        qsort(sorted, DIM, sizeof(float), cmp_desc);
        thr = sorted[d.coefficients - 1];
        free(sorted);
    }
    float maxabs[3] = {0, 0, 0};
    /* Everything above the threshold, then ties in index order up to the count. */
    int above = 0, kept = 0;
    for (int j = 0; j < DIM; ++j) above += mag[j] > thr;
    int ties = d.coefficients - above;
    for (int j = 0; j < DIM; ++j) {
        if (!(mag[j] > thr || (mag[j] == thr && ties-- > 0))) { mag[j] = -1; continue; }
        kept++;
        for (int c = 0; c < 3; ++c) maxabs[c] = fmaxf(maxabs[c], fabsf(planes[(size_t)c * DIM + j]));
    }
    for (int j = 0; j < DIM; ++j) {
        if (mag[j] < 0) continue;
        for (int c = 0; c < 3; ++c) {
            float v = planes[(size_t)c * DIM + j];
            if (d.bits == 16 && maxabs[c] > 0) {   /* signed 16-bit, one scale per channel */
                float s = maxabs[c] / 32767.0f;
                v = (float)lrintf(v / s) * s;
            }
            l->coeffs[(size_t)j * 4 + c] = v;
        }
    }
    l->kept = kept;
    free(planes);
    free(mag);
    *out = l;
    return PRT_OK;
}

void prt_wavelet_light_release(prt_wavelet_light *l)
{
    if (!l) return;
    free(l->cube);
    free(l->coeffs);
    free(l);
}

const float *prt_wavelet_light_cubemap(const prt_wavelet_light *l) { return l ? l->cube : NULL; }
const float *prt_wavelet_light_coeffs(const prt_wavelet_light *l) { return l ? l->coeffs : NULL; }
int prt_wavelet_light_kept(const prt_wavelet_light *l) { return l ? l->kept : 0; }
