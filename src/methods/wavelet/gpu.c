/* Wavelet relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): the
 * lighting's Haar coefficients (lighting.c, on the CPU: rotation, transform, truncation) are the
 * frame's vector, and each Lambertian vertex's sparse row of quantized transport is dotted with it
 * on the GPU, scaled by its quantization scale and albedo / pi as relight.c and prt_wavelet_shade.
 * The notes call sparse products ill-suited to GPUs (gathers at random indices into a vector of
 * 24,576 entries): docs/GPU.md measures it. Files with glossy vertices sum every vertex's K
 * light-dependent terms g_k = T_k . L (relight.c's K-vectors) as a kvec product, which the
 * per-pixel view factor reads where the GPU wrote it; the Lambertian vertices' radiance is their
 * first term times albedo / pi, a second product. */
#include "methods/wavelet/wavelet.h"
#include "transfer/gpu_sums.h"

#include <pthread.h>
#include <string.h>

static pthread_mutex_t build_lock = PTHREAD_MUTEX_INITIALIZER;

bool prt__wavelet_glossy(const prt_transfer *t)
{
    const prt__wavelet_set *w = t->state;
    for (size_t v = 0; v < t->mesh.vertex_count; ++v) {
        const uint8_t mat = t->mesh.material[v];
        if (mat && w->factors[mat - 1]) return true;
    }
    return false;
}

/* Glossy files: every vertex's terms (row v * K + k: vector vec_start[v] + k's sparse row times
 * its scale, as prt_relight_wavelet), then the Lambertian vertices' radiance from their first. */
static prt__gpu_sums *build_glossy(const prt_transfer *t, const prt__wavelet_set *w)
{
    const size_t nv = t->mesh.vertex_count, K = (size_t)w->terms;
    const prt__sparse_store *s = &w->store;
    const int n = s->n;
    size_t entries = 0, lambertian = 0;
    for (size_t v = 0; v < nv; ++v) {
        entries += (size_t)w->term_count[v] * n;
        const uint8_t mat = t->mesh.material[v];
        lambertian += !(mat && w->factors[mat - 1]);
    }
    prt__gpu_sums *g = prt__gpu_sums_new(PRT_WAVELET_DIM);
    prt_render_product *p = g ? prt__gpu_sums_add(g, -1, nv * K, entries, true, 0, 0) : NULL;
    if (!p) { prt__gpu_sums_free(g); return NULL; }
    p->kvec = 1;
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *wt = (float *)p->weight, *scale = (float *)p->scale;
    uint32_t e = 0;
    for (size_t v = 0; v < nv; ++v)
        for (size_t k = 0; k < K; ++k) {
            const size_t row = v * K + k;
            start[row] = e;
            if (k >= (size_t)w->term_count[v]) continue;
            const size_t vec = w->vec_start[v] + k;
            for (int i = 0; i < n; ++i, ++e) {
                index[e] = s->index[vec * n + i];
                for (int c = 0; c < 3; ++c)
                    wt[(size_t)e * 3 + c] = s->bits == 8 ? (float)((const int8_t *)s->values)[(vec * n + i) * 3 + c]
                                                         : (float)((const int16_t *)s->values)[(vec * n + i) * 3 + c];
            }
            for (int c = 0; c < 3; ++c) scale[row * 3 + c] = s->scale[vec * 3 + c];
        }
    start[nv * K] = e;
    if (!(p = prt__gpu_sums_add(g, 0, nv, lambertian, true, 0, 1))) { prt__gpu_sums_free(g); return NULL; }
    start = (uint32_t *)p->start;
    index = (uint32_t *)p->index;
    wt = (float *)p->weight;
    scale = (float *)p->scale;
    e = 0;
    for (size_t v = 0; v < nv; ++v) {
        start[v] = e;
        const uint8_t mat = t->mesh.material[v];
        if (mat && w->factors[mat - 1]) continue;   /* drawn per pixel from its terms */
        index[e] = (uint32_t)(v * K);
        wt[(size_t)e * 3] = wt[(size_t)e * 3 + 1] = wt[(size_t)e * 3 + 2] = 1.0f;
        e++;
        for (int c = 0; c < 3; ++c) scale[v * 3 + c] = t->mesh.albedo[v * 3 + c] / (float)PRT_PI;
    }
    start[nv] = e;
    return g;
}

static prt__gpu_sums *build(const prt_transfer *t, const prt__wavelet_set *w)
{
    const size_t nv = t->mesh.vertex_count;
    const prt__sparse_store *s = &w->store;
    const int n = s->n;
    prt__gpu_sums *g = prt__gpu_sums_new(PRT_WAVELET_DIM);
    prt_render_product *p = g ? prt__gpu_sums_add(g, -1, nv, nv * (size_t)n, true, 0, 1) : NULL;
    if (!p) { prt__gpu_sums_free(g); return NULL; }
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *wt = (float *)p->weight, *scale = (float *)p->scale;
    for (size_t v = 0; v < nv; ++v) {
        const size_t vec = w->vec_start[v];
        const uint32_t e0 = (uint32_t)(v * (size_t)n);
        start[v] = e0;
        for (int i = 0; i < n; ++i) {
            index[e0 + i] = s->index[vec * n + i];
            for (int c = 0; c < 3; ++c)
                wt[(size_t)(e0 + i) * 3 + c] = s->bits == 8 ? (float)((const int8_t *)s->values)[(vec * n + i) * 3 + c]
                                                            : (float)((const int16_t *)s->values)[(vec * n + i) * 3 + c];
        }
        for (int c = 0; c < 3; ++c) scale[v * 3 + c] = s->scale[vec * 3 + c] * (t->mesh.albedo[v * 3 + c] / (float)PRT_PI);
    }
    start[nv] = (uint32_t)(nv * (size_t)n);
    return g;
}

prt_status prt__wavelet_gpu(prt_context *ctx, const prt_transfer *t, const prt_wavelet_light *light, prt_relit *r)
{
    prt__wavelet_set *w = t->state;
    pthread_mutex_lock(&build_lock);
    if (!w->gpu) w->gpu = prt__wavelet_glossy(t) ? build_glossy(t, w) : build(t, w);
    prt__gpu_sums *g = w->gpu;
    pthread_mutex_unlock(&build_lock);
    if (!g) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    float *x = r->gpu_vector = prt__calloc((size_t)PRT_WAVELET_DIM * 3, sizeof(float));
    if (!x) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const float *L = light ? prt_wavelet_light_coeffs(light) : NULL;
    for (size_t i = 0; L && i < PRT_WAVELET_DIM; ++i) memcpy(x + i * 3, L + i * 4, 3 * sizeof(float));
    r->gpu_sums = &g->sums;
    return PRT_OK;
}
