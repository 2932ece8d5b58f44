/* Ambient-occlusion relighting: the environment's SH projection at order 3 convolved with the
 * clamped cosine gives the unshadowed irradiance E(n) at any normal (Ramamoorthi & Hanrahan
 * 2001); a vertex reflects albedo / pi * A * E(n). Exact under a constant environment (then
 * E = pi L whatever the normal and A carries all the shadowing); elsewhere it darkens all
 * directions alike, as ambient occlusion does. */
#include "methods/ao/ao.h"

prt_status prt__ao_irradiance_sh(prt_context *ctx, const prt_lighting *l, prt_sh_light *sh)
{
    prt_status st = prt_lighting_sh(l, PRT__AO_ENV_ORDER, sh);
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    /* E(n) / pi, so that a vertex's radiance is albedo * A * this. Channels lie PRT_SH_MAX_COEFFS
     * apart, not order^2: convolve each alone. */
    double zh[PRT__AO_ENV_ORDER];
    prt_sh_clamped_cosine_zh(sh->order, zh);
    for (int i = 0; i < sh->order; ++i) zh[i] /= PRT_PI;
    for (int c = 0; c < 3; ++c) prt_sh_convolve_zh(sh->order, zh, 1, sh->coeffs[c]);
    return PRT_OK;
}

prt_status prt__ao_radiance(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float *albedo, float *rgb)
{
    const prt__ao_set *s = prt__ao(t);
    if (!s || !l || !rgb) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ambient occlusion relighting: an ao transfer, lighting and output are required");
    const prt__mesh *m = &t->mesh;
    const size_t nv = m->vertex_count;
    if (!albedo) albedo = m->albedo;
    prt_sh_light sh;
    prt_status st = prt__ao_irradiance_sh(ctx, l, &sh);
    if (st) return st;
#pragma omp parallel for schedule(static, 1024) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v) {
        float e[3];
        prt_sh_light_eval(&sh, m->normals + v * 3, e);
        for (int c = 0; c < 3; ++c) {
            /* Order 3 rings below zero opposite a bright sun: no surface reflects less than nothing. */
            const float ec = e[c] > 0.0f ? e[c] : 0.0f;
            rgb[v * 3 + c] = albedo[v * 3 + c] * s->access[v] * ec;
        }
    }
    return PRT_OK;
}
