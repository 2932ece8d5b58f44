/* Wavelet relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): the
 * lighting's Haar coefficients (lighting.c, on the CPU: rotation, transform, truncation) are the
 * frame's vector, and each Lambertian vertex's sparse row of quantized transport is dotted with it
 * on the GPU, scaled by its quantization scale and albedo / pi as relight.c and prt_wavelet_shade.
 * The notes call sparse products ill-suited to GPUs (gathers at random indices into a vector of
 * 24,576 entries): docs/GPU.md measures it. Files with glossy vertices keep the CPU path (their
 * K-vectors feed the per-pixel view factor). */
#include "methods/wavelet/wavelet.h"
#include "transfer/gpu_sums.h"

#include <pthread.h>
#include <string.h>

static pthread_mutex_t build_lock = PTHREAD_MUTEX_INITIALIZER;

bool prt__wavelet_gpu_can(const prt_transfer *t)
{
    const prt__wavelet_set *w = t->state;
    for (size_t v = 0; v < t->mesh.vertex_count; ++v) {
        const uint8_t mat = t->mesh.material[v];
        if (mat && w->factors[mat - 1]) return false;
    }
    return true;
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
    if (!w->gpu) w->gpu = build(t, w);
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
