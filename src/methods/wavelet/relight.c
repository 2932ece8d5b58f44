/* Wavelet relighting: the light-dependent K-vector g_k = T_k . L per lighting change (sparse
 * transport against the dense, truncated light), and the view factor sum_k h_k(wo) g_k per view
 * change. */
#include "methods/wavelet/wavelet.h"

#include <string.h>

#if defined(__SSE4_1__)
#include <immintrin.h>
#if defined(__AVX2__)
/* Two coefficients per step: their six bytes spread to two RGB0 lane groups, converted once and
 * multiplied with the two light texels loaded side by side. The store pads its values, so the
 * 8-byte reads past the last coefficient stay inside. */
static inline void dot_8(const uint16_t *idx, const int8_t *q, int n, const float *L, float acc[3])
{
    const __m128i spread = _mm_setr_epi8(0, 1, 2, -1, 3, 4, 5, -1, -1, -1, -1, -1, -1, -1, -1, -1);
    __m256 a = _mm256_setzero_ps(), b = _mm256_setzero_ps();
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        int64_t w0, w1;
        memcpy(&w0, q + 3 * i, 8);
        memcpy(&w1, q + 3 * i + 6, 8);
        __m256 q0 = _mm256_cvtepi32_ps(_mm256_cvtepi8_epi32(_mm_shuffle_epi8(_mm_cvtsi64_si128(w0), spread)));
        __m256 q1 = _mm256_cvtepi32_ps(_mm256_cvtepi8_epi32(_mm_shuffle_epi8(_mm_cvtsi64_si128(w1), spread)));
        __m256 l0 = _mm256_loadu2_m128(L + (size_t)idx[i + 1] * 4, L + (size_t)idx[i] * 4);
        __m256 l1 = _mm256_loadu2_m128(L + (size_t)idx[i + 3] * 4, L + (size_t)idx[i + 2] * 4);
        a = _mm256_fmadd_ps(q0, l0, a);
        b = _mm256_fmadd_ps(q1, l1, b);
    }
    a = _mm256_add_ps(a, b);
    __m128 s = _mm_add_ps(_mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1));
    for (; i < n; ++i) {
        int32_t w;
        memcpy(&w, q + 3 * i, 4);
        __m128 qv = _mm_cvtepi32_ps(_mm_cvtepi8_epi32(_mm_shuffle_epi8(_mm_cvtsi32_si128(w), spread)));
        s = _mm_add_ps(s, _mm_mul_ps(qv, _mm_loadu_ps(L + (size_t)idx[i] * 4)));
    }
    float out[4];
    _mm_storeu_ps(out, s);
    acc[0] = out[0]; acc[1] = out[1]; acc[2] = out[2];
}

#else
/* One coefficient per step, all three channels at once: the light's RGB(0) at the index times
 * the coefficient's three integers (the fourth lane reads the next byte and meets the zero pad).
 * The store pads its values by 4 bytes, so the last read stays inside. */
static inline void dot_8(const uint16_t *idx, const int8_t *q, int n, const float *L, float acc[3])
{
    __m128 a = _mm_setzero_ps(), b = _mm_setzero_ps();
    int i = 0;
    for (; i + 2 <= n; i += 2) {
        int32_t w0, w1;
        memcpy(&w0, q + 3 * i, 4);
        memcpy(&w1, q + 3 * i + 3, 4);
        __m128 q0 = _mm_cvtepi32_ps(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(w0)));
        __m128 q1 = _mm_cvtepi32_ps(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(w1)));
        a = _mm_add_ps(a, _mm_mul_ps(q0, _mm_loadu_ps(L + (size_t)idx[i] * 4)));
        b = _mm_add_ps(b, _mm_mul_ps(q1, _mm_loadu_ps(L + (size_t)idx[i + 1] * 4)));
    }
    for (; i < n; ++i) {
        int32_t w0;
        memcpy(&w0, q + 3 * i, 4);
        a = _mm_add_ps(a, _mm_mul_ps(_mm_cvtepi32_ps(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(w0))), _mm_loadu_ps(L + (size_t)idx[i] * 4)));
    }
    float out[4];
    _mm_storeu_ps(out, _mm_add_ps(a, b));
    acc[0] = out[0]; acc[1] = out[1]; acc[2] = out[2];
}

#endif
static inline void dot_16(const uint16_t *idx, const int16_t *q, int n, const float *L, float acc[3])
{
    __m128 a = _mm_setzero_ps();
    for (int i = 0; i < n; ++i) {
        int64_t w;
        memcpy(&w, q + 3 * i, 8);
        a = _mm_add_ps(a, _mm_mul_ps(_mm_cvtepi32_ps(_mm_cvtepi16_epi32(_mm_cvtsi64_si128(w))), _mm_loadu_ps(L + (size_t)idx[i] * 4)));
    }
    float out[4];
    _mm_storeu_ps(out, a);
    acc[0] = out[0]; acc[1] = out[1]; acc[2] = out[2];
}
#else
/* Portable builds: one scalar loop for either width. */
#define SCALAR_DOT(name, type)                                                                    \
    static inline void name(const uint16_t *idx, const type *q, int n, const float *L, float acc[3]) \
    {                                                                                             \
        float a0 = 0, a1 = 0, a2 = 0;                                                             \
        for (int i = 0; i < n; ++i) {                                                             \
            const float *l = L + (size_t)idx[i] * 4;                                              \
            a0 += (float)q[3 * i] * l[0];                                                         \
            a1 += (float)q[3 * i + 1] * l[1];                                                     \
            a2 += (float)q[3 * i + 2] * l[2];                                                     \
        }                                                                                         \
        acc[0] = a0; acc[1] = a1; acc[2] = a2;                                                    \
    }
SCALAR_DOT(dot_8, int8_t)
SCALAR_DOT(dot_16, int16_t)
#endif

prt_status prt_relight_wavelet(prt_context *ctx, const prt_transfer *t, const prt_wavelet_light *light, float *out_kvec)
{
    if (t && !prt__wavelet(t)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "this .prt holds no wavelet transfer (bake with --method wavelet)");
    if (!t || !light || !out_kvec) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_relight_wavelet: transfer, light and output are required");
    const prt__wavelet_set *w = prt__wavelet(t);
    const size_t nv = t->mesh.vertex_count;
    const int K = w->terms, n = w->store.n;
    const float *L = prt_wavelet_light_coeffs(light);
    const prt__sparse_store *s = &w->store;
#pragma omp parallel for schedule(static, 256) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v) {
        float *o = out_kvec + v * (size_t)K * 3;
        memset(o, 0, (size_t)K * 3 * sizeof(float));
        for (int k = 0; k < w->term_count[v]; ++k) {
            const size_t vec = w->vec_start[v] + k;
            float acc[3];
            if (s->bits == 8) dot_8(s->index + vec * n, (const int8_t *)s->values + vec * n * 3, n, L, acc);
            else dot_16(s->index + vec * n, (const int16_t *)s->values + vec * n * 3, n, L, acc);
            for (int c = 0; c < 3; ++c) o[k * 3 + c] = acc[c] * s->scale[vec * 3 + c];
        }
    }
    return PRT_OK;
}

prt_status prt_wavelet_shade(prt_context *ctx, const prt_transfer *t, const float *kvec, const float eye[3], float *out_rgb)
{
    if (!t || !kvec || !out_rgb) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_wavelet_shade: transfer, K-vectors and output are required");
    const prt__wavelet_set *w = prt__wavelet(t);
    if (!w) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "this .prt holds no wavelet transfer (bake with --method wavelet)");
    const prt__mesh *m = &t->mesh;
    const size_t nv = m->vertex_count;
    const int K = w->terms;
#pragma omp parallel for schedule(static, 256) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v) {
        const float *g = kvec + v * (size_t)K * 3;
        float *o = out_rgb + v * 3;
        const uint8_t mat = m->material[v];
        const prt_brdf_factors *f = mat ? w->factors[mat - 1] : NULL;
        if (!f) {
            for (int c = 0; c < 3; ++c) o[c] = m->albedo[v * 3 + c] / (float)PRT_PI * g[c];
            continue;
        }
        if (!eye) {   /* drawn per pixel */
            o[0] = o[1] = o[2] = 0.0f;
            continue;
        }
        const float *n = m->normals + v * 3;
        float s[3], tt[3], wo[3], loc[3], h[3 * PRT_BRDF_MAX_TERMS];
        prt_brdf_frame(n, s, tt);
        prt__v3_sub(eye, m->positions + v * 3, wo);
        prt__v3_normalize(wo);
        loc[0] = prt__v3_dot(wo, s);
        loc[1] = prt__v3_dot(wo, tt);
        loc[2] = prt__v3_dot(wo, n);
        /* Interpolated normals turn slightly away from the eye along silhouettes: read the view
         * maps just above the horizon there instead of going black. */
        if (loc[2] < 0.02f) {
            float r = sqrtf(loc[0] * loc[0] + loc[1] * loc[1]);
            float sc = r > 0 ? sqrtf(1.0f - 0.02f * 0.02f) / r : 0.0f;
            loc[0] *= sc; loc[1] *= sc; loc[2] = 0.02f;
        }
        const int Kv = w->term_count[v];
        prt_brdf_factors_lookup(f, 1, Kv, loc, h);
        for (int c = 0; c < 3; ++c) {
            float acc = 0;
            for (int k = 0; k < Kv; ++k) acc += h[c * Kv + k] * g[k * 3 + c];
            o[c] = acc > 0.0f ? acc : 0.0f;   /* a few terms can undershoot; radiance cannot (the shader clamps too) */
        }
    }
    return PRT_OK;
}
