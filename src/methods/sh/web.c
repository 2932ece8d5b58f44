/* prt export --web of SH files: the per-vertex diffuse transfer and the distant lighting's SH
 * for the page (methods/sh/web.js relights: colour = T . L, L the environment's SH rotated and
 * scaled in the browser plus the directional lights'), as sh_relight does on the CPU. */
#include "methods/sh/sh.h"

extern const char prt__js_sh_web[];   /* methods/sh/web.js, compiled in */

prt_status prt__sh_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page)
{
    const prt__sh_state *s = t->state;
    const char *vname = prt_transfer_variant_name(t, d->variant);
    prt_transfer_kind kind = 0;
    if (prt_transfer_kind_parse(vname, &kind) || prt_transfer_kind_is_glossy(kind) || !prt_transfer_channels(t, kind))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web relights per-vertex diffuse SH transfer (unshadowed, shadowed, interreflected): "
                         "this file relit as %s has none (choose one with -k)", vname);
    const int N = s->order, n = N * N, ch = prt_transfer_channels(t, kind);
    const int order = d->controls && d->controls[0] >= 1 && d->controls[0] < N ? d->controls[0] : N;
    const int window = d->controls ? d->controls[1] : PRT__SH_LIGHT_WINDOW_DEFAULT;
    if (window < 0 || window >= PRT__SH_WINDOW_COUNT)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "light-window %d: use 0 (none), 1 (Hanning) or 2 (Lanczos)", window);
    const prt_lighting *l = d->lighting;
    const size_t nv = t->mesh.vertex_count;
    if (s->volume_count)
        prt__log(ctx, PRT_LOG_WARN, "the page draws the surfaces only: the file's participating media shadow them there but are not drawn (prt render and "
                                    "prt view draw them)");

    /* The environment as the page rotates it: unrotated and at intensity 1 when its rotation is
     * the yaw, pitch and roll it was named with (the page starts there); else as it is. */
    prt_lighting *env = NULL, *dir = NULL;
    prt_status st = prt_lighting_copy(l, &env);
    if (!st) st = prt_lighting_copy(l, &dir);
    if (st) { prt_lighting_release(env); return prt__fail(ctx, st, "%s", prt_last_error()); }
    prt_lighting_clear_lights(env);
    const prt_environment_desc *ed = prt_lighting_environment_desc(l);
    float euler[3] = {0, 0, 0};
    if (prt__web_rotation_named(l)) {
        static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        memcpy(euler, ed->rotate_deg, sizeof euler);
        prt_lighting_set_rotation(env, identity);
    }
    const float intensity = prt_lighting_intensity(l);
    prt_lighting_set_intensity(env, 1.0f);
    prt_sh_light esh;
    memset(&esh, 0, sizeof esh);
    const bool has_env = prt_lighting_envmap(l) != NULL;
    if (has_env) st = prt_lighting_sh(env, N, &esh);

    /* The directional lights' SH at every order the page offers, windowed as sh_relight does. */
    int local = 0;
    if (!st) st = prt_lighting_set_envmap(dir, NULL, NULL, 0);
    for (int i = prt_lighting_count(dir) - 1; !st && i >= 0; --i)
        if (prt__sh_light_positioned(prt_lighting_light(dir, i))) { st = prt_lighting_remove(dir, i); local++; }
    float *directional = prt__calloc((size_t)N * 3 * n, sizeof *directional);
    if (!st && !directional) st = PRT_ERR_NO_MEMORY;
    for (int o = 1; !st && o <= N; ++o) {
        prt_sh_light dsh;
        if ((st = prt_lighting_sh(dir, N, &dsh))) break;
        dsh.order = o;
        prt__sh_window_directional(dir, window, &dsh);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < o * o; ++k) directional[((size_t)(o - 1) * 3 + c) * n + k] = dsh.coeffs[c][k];
    }
    const int directional_count = prt_lighting_count(dir);
    prt_lighting_release(env);
    prt_lighting_release(dir);
    if (st) { free(directional); return prt__fail(ctx, st, "%s", st == PRT_ERR_NO_MEMORY ? "out of memory" : prt_last_error()); }
    if (local)
        prt__web_report(page, "left out %d point, spot, sphere or IES light%s: the SH page relights distant lighting (the environment, directional "
                        "lights)", local, local == 1 ? "" : "s");
    if (s->texels.width)
        prt__web_report(page, "the page relights the per-vertex transfer (prt render --per-vertex draws the same), not the per-texel maps");

    float *all = malloc(nv * (size_t)ch * n * sizeof *all);
    if (!all) { free(directional); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    if ((st = prt_transfer_reconstruct(t, kind, all))) { free(all); free(directional); return prt__fail(ctx, st, "%s", prt_last_error()); }
    float envflat[3 * PRT_SH_MAX_COEFFS];
    for (int c = 0; c < 3; ++c) memcpy(envflat + c * n, esh.coeffs[c], (size_t)n * sizeof(float));
    cJSON *meta = prt__web_meta(page);
    const double eu[3] = {euler[0], euler[1], euler[2]};
    bool ok = prt__web_floats(page, "transfer", all, nv * (size_t)ch * n) && (ch == 3 || prt__web_floats(page, "albedo", t->mesh.albedo, nv * 3)) &&
              prt__web_floats(page, "environment", envflat, 3 * (size_t)n) && prt__web_floats(page, "directional", directional, (size_t)N * 3 * n) &&
              cJSON_AddNumberToObject(meta, "order", N) && cJSON_AddNumberToObject(meta, "order_default", order) &&
              cJSON_AddNumberToObject(meta, "channels", ch) && cJSON_AddBoolToObject(meta, "environment", has_env) &&
              cJSON_AddNumberToObject(meta, "directional_lights", directional_count) &&
              cJSON_AddItemToObject(meta, "rotate", cJSON_CreateDoubleArray(eu, 3)) && cJSON_AddNumberToObject(meta, "intensity", intensity);
    free(all);
    free(directional);
    if (!ok) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__web_script(page, prt__js_sh_web);
    return PRT_OK;
}
