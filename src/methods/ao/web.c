/* prt export --web of ao files: each vertex's accessibility times its albedo and its normal's SH
 * basis values (order 3), and the environment's SH, for the page (methods/ao/web.js), which relights
 * as relight.c does: the environment's SH rotated and scaled, convolved with the clamped cosine,
 * evaluated at each normal. */
#include "methods/ao/ao.h"

extern const char prt__js_ao_web[];   /* methods/ao/web.js, compiled in */

prt_status prt__ao_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page)
{
    const prt__ao_set *s = t->state;
    const prt__mesh *m = &t->mesh;
    const size_t nv = m->vertex_count;
    const int N = PRT__AO_ENV_ORDER, n = N * N;
    const prt_lighting *l = d->lighting;
    const prt_envmap *env = prt_lighting_envmap(l);
    const prt_environment_desc *ed = prt_lighting_environment_desc(l);
    prt_status st = prt__web_require_named_rotation(ctx, l);
    if (st) return st;
    float envflat[3 * 9];
    memset(envflat, 0, sizeof envflat);
    if (env) {
        prt_sh_light sh;
        if ((st = prt__web_unit_environment_sh(ctx, l, N, &sh))) return st;
        for (int c = 0; c < 3; ++c) memcpy(envflat + c * n, sh.coeffs[c], (size_t)n * sizeof(float));
    }
    double zh[PRT__AO_ENV_ORDER];
    prt_sh_clamped_cosine_zh(N, zh);
    for (int l = 0; l < N; ++l) zh[l] = (float)(sqrt(4.0 * PRT_PI / (2.0 * l + 1.0)) * (zh[l] / PRT_PI));   /* prt_sh_convolve_zh's factor per band */
    float *basis = malloc(nv * (size_t)n * sizeof *basis), *reflect = malloc(nv * 3 * sizeof *reflect);
    if (!basis || !reflect) { free(basis); free(reflect); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (size_t v = 0; v < nv; ++v) {
        prt_sh_eval_f(N, m->normals + v * 3, basis + v * (size_t)n);
        for (int c = 0; c < 3; ++c) reflect[v * 3 + c] = m->albedo[v * 3 + c] * s->access[v];
    }
    cJSON *meta = prt__web_meta(page);
    const double eu[3] = {ed->rotate_deg[0], ed->rotate_deg[1], ed->rotate_deg[2]};
    bool ok = cJSON_AddNumberToObject(meta, "order", N) && cJSON_AddBoolToObject(meta, "environment", env != NULL) &&
              cJSON_AddItemToObject(meta, "rotate", cJSON_CreateDoubleArray(eu, 3)) && cJSON_AddNumberToObject(meta, "intensity", prt_lighting_intensity(l)) &&
              cJSON_AddItemToObject(meta, "zh", cJSON_CreateDoubleArray(zh, N)) && prt__web_floats(page, "env", envflat, 3 * (size_t)n) &&
              prt__web_floats(page, "basis", basis, nv * (size_t)n) && prt__web_floats(page, "reflect", reflect, nv * 3);
    free(basis);
    free(reflect);
    if (!ok) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__web_script(page, prt__js_ao_web);
    return PRT_OK;
}
