/* Wavelet lighting (Ng et al. 2003; Wang et al. 2005 section 4.3): the environment over a
 * 6 x 64 x 64 cube map (light/env_cube.c: exact areas, under any rotation), directional lights as
 * deltas in the texels their directions fall in, each face Haar-transformed, the largest
 * coefficients kept and quantized. Many more coefficients are kept than per transport vector, so
 * that rotating the lighting does not flicker. */
#include "core/cubemap.h"
#include "compress/sparse.h"
#include "core/haar.h"
#include "light/env_cube.h"
#include "prt/wavelet.h"

#include <math.h>
#include <string.h>

#define FACE PRT_WAVELET_FACE
#define DIM PRT_WAVELET_DIM
_Static_assert(PRT_WAVELET_FACE == PRT__ENV_CUBE_FACE, "the lighting cube is the shared environment cube");

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

prt_status prt_wavelet_light_create(prt_context *ctx, const prt_envmap *env, const prt_wavelet_light_desc *desc,
                                    prt_wavelet_light **out)
{
    if (!out || (!env && !(desc && desc->light_count > 0)))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_wavelet_light_create: an environment or directional lights, and out, are required");
    *out = NULL;
    prt_wavelet_light_desc d = desc ? *desc : (prt_wavelet_light_desc){0};
    if (d.coefficients == 0) d.coefficients = 4096;
    if (d.bits == 0) d.bits = 16;
    if (d.intensity == 0) d.intensity = 1.0f;
    if (d.coefficients < 1 || d.coefficients > DIM)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting coefficients %d out of range 1..%d", d.coefficients, DIM);
    if (d.bits != 16 && d.bits != 32) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting bits must be 16 or 32, not %d", d.bits);
    if (!(d.intensity > 0) || !isfinite(d.intensity)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting intensity must be > 0");
    /* supersample is still checked, but exact areas leave it nothing to set. */
    if (d.supersample < 0 || d.supersample > 16) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting supersampling %d out of range 0..16", d.supersample);
    for (int i = 0; i < d.light_count; ++i)
        if (!d.lights || d.lights[i].type != PRT_LIGHT_DIRECTIONAL)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "wavelet lighting takes directional lights only (light %d is not)", i + 1);
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
    prt_status st = env ? prt__env_cube(ctx, env, d.rotation, d.intensity, l->cube) : PRT_OK;
    if (st) { prt_wavelet_light_release(l); free(planes); free(mag); return st; }
    for (int t = 0; t < DIM; ++t)
        for (int c = 0; c < 3; ++c) planes[(size_t)c * DIM + t] = l->cube[(size_t)t * 3 + c];
    float omega[FACE * FACE];
    prt__env_cube_solid_angles(omega);
    /* A directional light is a delta: all of its irradiance E in the texel its direction falls
     * in, as radiance E over that texel's solid angle. */
    for (int i = 0; i < d.light_count; ++i) {
        float a, b, dir[3] = {d.lights[i].direction[0], d.lights[i].direction[1], d.lights[i].direction[2]};
        const int face = prt__cube_face(dir, &a, &b);
        int x = (int)((a + 1.0f) * 0.5f * FACE), y = (int)((b + 1.0f) * 0.5f * FACE);
        x = x < 0 ? 0 : x >= FACE ? FACE - 1 : x;
        y = y < 0 ? 0 : y >= FACE ? FACE - 1 : y;
        const int t = (face * FACE + y) * FACE + x;
        for (int c = 0; c < 3; ++c) {
            const float v = d.lights[i].irradiance[c] / omega[t % (FACE * FACE)];
            l->cube[(size_t)t * 3 + c] += v;
            planes[(size_t)c * DIM + t] += v;
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
        thr = prt__kth_largest(sorted, DIM, d.coefficients - 1);
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
