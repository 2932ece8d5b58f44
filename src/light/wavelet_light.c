/* Wavelet lighting (Ng et al. 2003; Wang et al. 2005 section 4.3): the environment box-filtered
 * (once, into a finer cube; then per rotation from that) into a 6 x 64 x 64 cube map, each face Haar-transformed, the largest coefficients kept and
 * quantized. Many more coefficients are kept than per transport vector, so that rotating the
 * lighting does not flicker. */
#include "core/cubemap.h"
#include "compress/sparse.h"
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

#define SRC 256   /* source cube resolution: 4 x 4 source texels under each lighting texel */

/* Bilinear lookup in the source cube (clamped at face edges) along any non-zero direction. */
static void cube_lookup(const float *src, const float d[3], float rgb[3])
{
    float a, b;
    const int face = prt__cube_face(d, &a, &b);
    float fx = (a + 1.0f) * 0.5f * SRC - 0.5f, fy = (b + 1.0f) * 0.5f * SRC - 0.5f;
    fx = fminf(fmaxf(fx, 0.0f), SRC - 1.0f);
    fy = fminf(fmaxf(fy, 0.0f), SRC - 1.0f);
    int x0 = (int)fx, y0 = (int)fy, x1 = x0 + 1 < SRC ? x0 + 1 : x0, y1 = y0 + 1 < SRC ? y0 + 1 : y0;
    float tx = fx - x0, ty = fy - y0;
    const float *p = src + (size_t)face * SRC * SRC * 3;
    const float *p00 = p + ((size_t)y0 * SRC + x0) * 3, *p10 = p + ((size_t)y0 * SRC + x1) * 3, *p01 = p + ((size_t)y1 * SRC + x0) * 3,
                *p11 = p + ((size_t)y1 * SRC + x1) * 3;
    for (int c = 0; c < 3; ++c)
        rgb[c] = (1 - ty) * ((1 - tx) * p00[c] + tx * p10[c]) + ty * ((1 - tx) * p01[c] + tx * p11[c]);
}

/* The environment box-filtered into the source cube, once per map: about one lookup per map
 * pixel under each source texel. Concurrent first calls may both build it; one copy wins. */
static const float *source_cube(prt_context *ctx, const prt_envmap *env)
{
    float *cached = __atomic_load_n(&env->cube_cache, __ATOMIC_ACQUIRE);
    if (cached) return cached;
    float *c = malloc((size_t)6 * SRC * SRC * 3 * sizeof(float));
    if (!c) return NULL;
    const prt_image *img = &env->img;
    const double pixel = sqrt(4.0 * PRT_PI / ((double)img->width * img->height)), texel = 0.5 * PRT_PI / SRC;
    int ss = (int)ceil(texel / pixel);
    ss = ss < 1 ? 1 : ss > 16 ? 16 : ss;
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
    for (int t = 0; t < 6 * SRC * SRC; ++t) {
        int face = t / (SRC * SRC), y = t / SRC % SRC, x = t % SRC;
        double acc[3] = {0, 0, 0}, wsum = 0;
        for (int sy = 0; sy < ss; ++sy)
            for (int sx = 0; sx < ss; ++sx) {
                float a = (float)(2.0 * (x + (sx + 0.5) / ss) / SRC - 1.0), b = (float)(2.0 * (y + (sy + 0.5) / ss) / SRC - 1.0);
                float dir[3], rgb[3];
                prt__cube_dir(face, a, b, dir);
                double r2 = 1.0 + (double)a * a + (double)b * b, w = 1.0 / (r2 * sqrt(r2));
                const float inv = (float)(1.0 / sqrt(r2));   /* lookups want unit vectors */
                for (int i = 0; i < 3; ++i) dir[i] *= inv;
                prt_envmap_lookup(env, dir, rgb);
                for (int k = 0; k < 3; ++k) acc[k] += w * rgb[k];
                wsum += w;
            }
        for (int k = 0; k < 3; ++k) c[(size_t)t * 3 + k] = (float)(acc[k] / wsum);
    }
    float *expected = NULL;
    /* The cache is a memo of a pure function of the map, so filling it through a const map is safe. */
    if (!__atomic_compare_exchange_n(&((prt_envmap *)env)->cube_cache, &expected, c, false, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
        free(c);
        return expected;
    }
    return c;
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
    const float *src = source_cube(ctx, env);
    /* Bilinear samples at the corners shared by 2 x 2 source texels average them exactly: 2 x 2
     * samples cover the 4 x 4 source texels under a lighting texel. */
    const int ss = d.supersample ? d.supersample : SRC / FACE / 2;

    prt_wavelet_light *l = prt__calloc(1, sizeof *l);
    float *planes = prt__calloc((size_t)3 * DIM, sizeof(float)), *mag = prt__calloc(DIM, sizeof(float));
    if (l) {
        l->cube = prt__calloc((size_t)DIM * 3, sizeof(float));
        l->coeffs = prt__calloc((size_t)DIM * 4, sizeof(float));
    }
    if (!src || !l || !planes || !mag || !l->cube || !l->coeffs) {
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
                float dir[3], rot[3], rgb[3];
                prt__cube_dir(face, a, b, dir);
                /* Weight by the solid angle of the sample: the cube's Jacobian (1 + a^2 + b^2)^-3/2. */
                double r2 = 1.0 + (double)a * a + (double)b * b, w = 1.0 / (r2 * sqrt(r2));
                for (int i = 0; i < 3; ++i) rot[i] = (float)(R[i] * dir[0] + R[3 + i] * dir[1] + R[6 + i] * dir[2]);   /* R^T d */
                cube_lookup(src, rot, rgb);
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
