/* Ambient occlusion finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): the
 * environment's SH at order 3 convolved with the clamped cosine / pi on the CPU (nine colours) is
 * the frame's vector; each vertex's row holds its normal's SH basis values, clamped at zero and
 * scaled by albedo x accessibility on the GPU, as relight.c. The scales hold albedo: a run-time
 * albedo makes a new description. */
#include "methods/ao/ao.h"
#include "transfer/gpu_sums.h"

#include <pthread.h>
#include <string.h>

static pthread_mutex_t build_lock = PTHREAD_MUTEX_INITIALIZER;

static prt__gpu_sums *build(const prt_transfer *t, const prt__ao_set *s, const float *albedo)
{
    const prt__mesh *m = &t->mesh;
    const size_t nv = m->vertex_count;
    const int n = PRT__AO_ENV_ORDER * PRT__AO_ENV_ORDER;
    prt__gpu_sums *g = prt__gpu_sums_new((size_t)n);
    prt_render_product *p = g ? prt__gpu_sums_add(g, -1, nv, nv * (size_t)n, true, 1, 1) : NULL;
    if (!p) { prt__gpu_sums_free(g); return NULL; }
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight, *scale = (float *)p->scale;
    for (size_t v = 0; v < nv; ++v) {
        float y[PRT_SH_MAX_COEFFS];
        prt_sh_eval_f(PRT__AO_ENV_ORDER, m->normals + v * 3, y);
        start[v] = (uint32_t)(v * (size_t)n);
        for (int i = 0; i < n; ++i) {
            const size_t e = v * (size_t)n + (size_t)i;
            index[e] = (uint32_t)i;
            w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = y[i];
        }
        for (int c = 0; c < 3; ++c) scale[v * 3 + c] = albedo[v * 3 + c] * s->access[v];
    }
    start[nv] = (uint32_t)(nv * (size_t)n);
    return g;
}

prt_status prt__ao_gpu(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float *albedo, prt_relit *r)
{
    prt__ao_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    if (!albedo) albedo = t->mesh.albedo;
    prt_sh_light sh;
    prt_status st = prt__ao_irradiance_sh(ctx, l, &sh);
    if (st) return st;
    pthread_mutex_lock(&build_lock);
    if (!s->gpu || !s->gpu_albedo || memcmp(s->gpu_albedo, albedo, nv * 3 * sizeof(float))) {
        if (!s->gpu_albedo) s->gpu_albedo = malloc(nv * 3 * sizeof(float));
        if (!s->gpu_albedo || !prt__gpu_sums_replace(&s->gpu, build(t, s, albedo))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else memcpy(s->gpu_albedo, albedo, nv * 3 * sizeof(float));
    }
    const prt__gpu_sums *g = s->gpu;
    pthread_mutex_unlock(&build_lock);
    if (st) return st;
    const int n = sh.order * sh.order;
    float *x = r->gpu_vector = prt__calloc((size_t)PRT__AO_ENV_ORDER * PRT__AO_ENV_ORDER * 3, sizeof(float));
    if (!x) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) x[i * 3 + c] = sh.coeffs[c][i];
    r->gpu_sums = &g->sums;
    return PRT_OK;
}
