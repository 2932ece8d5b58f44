/* prt export --web of spectral files: the basis, the sparse direct-to-indirect rows, the baked
 * environment and emitter transfer, for the page (methods/spectral/web.js), which relights as
 * spectral_relight does: direct light at the vertices (point lights through the framework's
 * shadow cubes, the environment's SH rotated in the browser, emitters), then the bounces through
 * the basis and the geometric tail; the point lights' direct light is drawn per pixel, as
 * prt render draws it. Diffuse files with point lights only, for now. */
#include "methods/spectral/spectral.h"

extern const char prt__js_spectral_web[];   /* methods/spectral/web.js, compiled in */

prt_status prt__spectral_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    const size_t nv = t->mesh.vertex_count;
    if (s->glossy_count)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web relights diffuse spectral files for now: this one has %u glossy vertices, whose final "
                         "bounce the page does not evaluate yet", s->glossy_count);
    const prt_lighting *l = d->lighting;
    prt_status st = prt__web_point_lights_only(ctx, l, "the spectral page lights with point lights (and the environment)", 0);
    if (st) return st;
    if (s->row_start[nv] > UINT32_MAX || b->offset[nv] > UINT32_MAX)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web: this file's transfer is too large for a page");
    int lo, hi, bounces_def, tail_def;
    t->method->control_range(t, 0, &lo, &hi, &bounces_def);
    t->method->control_range(t, 1, &lo, &hi, &tail_def);
    const int bounces = d->controls ? d->controls[0] : bounces_def, tail = d->controls ? d->controls[1] : tail_def;

    /* The environment as the page rotates it: its SH unrotated, at intensity 1. */
    const prt_envmap *env = prt_lighting_envmap(l);
    const prt_environment_desc *ed = prt_lighting_environment_desc(l);
    if ((st = prt__web_require_named_rotation(ctx, l))) return st;
    prt_sh_light sh;
    memset(&sh, 0, sizeof sh);
    if (env && s->env && s->env_order > 0) {
        prt_lighting *unit = NULL;
        static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        st = prt_lighting_copy(l, &unit);
        if (st) return prt__fail(ctx, st, "%s", prt_last_error());
        prt_lighting_set_rotation(unit, identity);
        prt_lighting_set_intensity(unit, 1.0f);
        st = prt__spectral_env_sh(ctx, t, unit, &sh);
        prt_lighting_release(unit);
        if (st) return st;
    }
    const int nc = s->env_order * s->env_order;
    float envflat[3 * PRT_SH_MAX_COEFFS];
    memset(envflat, 0, sizeof envflat);
    for (int c = 0; c < 3 && sh.order; ++c) memcpy(envflat + c * nc, sh.coeffs[c], (size_t)nc * sizeof(float));

    /* Emitters: their direct light on the vertices and their own radiance, at the lighting's scale. */
    const float emission = prt_lighting_emission(l);
    float *emit = NULL, *own = NULL;
    if ((s->emit || t->mesh.emission) && emission > 0) {
        emit = prt__calloc(nv * 3, sizeof(float));
        own = prt__calloc(nv * 3, sizeof(float));
        if (!emit || !own) { free(emit); free(own); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        for (size_t i = 0; i < nv * 3; ++i) {
            emit[i] = s->emit ? emission * s->emit[i] : 0.0f;
            own[i] = t->mesh.emission ? emission * t->mesh.emission[i] : 0.0f;
        }
    }
    uint32_t *row32 = malloc((nv + 1) * sizeof *row32), *offset32 = malloc((nv + 1) * sizeof *offset32);
    if (!row32 || !offset32) { free(row32); free(offset32); free(emit); free(own); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (size_t v = 0; v <= nv; ++v) { row32[v] = (uint32_t)s->row_start[v]; offset32[v] = (uint32_t)b->offset[v]; }

    cJSON *meta = prt__web_meta(page);
    bool ok = prt__web_point_lights_meta(meta, l);
    const double eu[3] = {ed->rotate_deg[0], ed->rotate_deg[1], ed->rotate_deg[2]};
    ok = ok && cJSON_AddNumberToObject(meta, "bounces", bounces) && cJSON_AddNumberToObject(meta, "bounces_max", hi > 64 ? hi : 64) &&
         cJSON_AddNumberToObject(meta, "tail", tail) && cJSON_AddNumberToObject(meta, "tail_max_ratio", PRT__SPECTRAL_TAIL_MAX_RATIO) &&
         cJSON_AddNumberToObject(meta, "partitions", b->partitions) && cJSON_AddNumberToObject(meta, "functions", b->functions) &&
         cJSON_AddNumberToObject(meta, "env_order", sh.order ? s->env_order : 0) && cJSON_AddBoolToObject(meta, "environment", env != NULL) &&
         cJSON_AddItemToObject(meta, "rotate", cJSON_CreateDoubleArray(eu, 3)) && cJSON_AddNumberToObject(meta, "intensity", prt_lighting_intensity(l)) &&
         cJSON_AddBoolToObject(meta, "emission", emit != NULL);
    ok = ok && prt__web_uints(page, "part_of", b->part_of, nv) && prt__web_uints(page, "first", b->first, (size_t)b->partitions + 1) &&
         prt__web_uints(page, "basis_start", offset32, nv + 1) && prt__web_floats(page, "basis", b->values, offset32[nv]) &&
         prt__web_uints(page, "row_start", row32, nv + 1) && prt__web_small(page, "index", "u16", s->index, row32[nv]) &&
         prt__web_small(page, "value", "i16", s->value, row32[nv]) && prt__web_floats(page, "row_scale", s->row_scale, nv) &&
         prt__web_floats(page, "albedo", t->mesh.albedo, nv * 3) &&
         (!sh.order || (prt__web_floats(page, "env", envflat, 3 * (size_t)nc) && prt__web_floats(page, "env_transfer", s->env, nv * (size_t)nc))) &&
         (!emit || (prt__web_floats(page, "emit", emit, nv * 3) && prt__web_floats(page, "own", own, nv * 3)));
    free(row32);
    free(offset32);
    free(emit);
    free(own);
    if (!ok) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__web_script(page, prt__js_spectral_web);
    return PRT_OK;
}
