/* prt export --web of offset files: the light map's texels (their shadow-ray points, shadowed SH
 * environment transfer, albedo, emission), the offsets and their transfer maps, and the prefilter's
 * charts and levels, for the page (methods/offset/web.js), which relights as relight.c does:
 * first-order light per texel (point lights through the framework's shadow cubes at the texels'
 * points, the environment's SH rotated in the browser), subsurface scattering and inter-reflection
 * as modulate-shift-accumulate passes, the map drawn per texel and the point lights' direct light
 * per pixel. The final light, point lights, for now. */
#include "methods/offset/offset.h"

extern const char prt__js_offset_web[];   /* methods/offset/web.js, compiled in */

prt_status prt__offset_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page)
{
    prt__offset_set *s = t->state;
    const size_t nc = s->covered, nv = t->mesh.vertex_count, S = PRT__OFFSET_SHADOW_SAMPLES;
    if (d->variant != 0)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web draws the final light of offset files: %s is not offered yet", prt_transfer_variant_name(t, d->variant));
    const prt_lighting *l = d->lighting;
    prt_status st = prt__web_point_lights_only(ctx, l, "the offset page lights with point lights (and the environment)", PRT_MAX_PIXEL_LIGHTS);
    if (st) return st;
    int lo, hi, def;
    t->method->control_range(t, 0, &lo, &hi, &def);
    const int bounces = d->controls ? d->controls[0] : def;
    if (bounces < lo || bounces > hi) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range %d..%d", bounces, lo, hi);
    st = prt__offset_shadow_samples(ctx, t);
    if (!st && s->radiosity) st = prt__offset_filter_ready(ctx, t, s);
    if (st) return st;

    /* The environment as the page rotates it: SH order 3, unrotated, intensity 1. */
    const prt_envmap *env = prt_lighting_envmap(l);
    const prt_environment_desc *ed = prt_lighting_environment_desc(l);
    if ((st = prt__web_require_named_rotation(ctx, l))) return st;
    float envflat[3 * PRT__OFFSET_ENV_COEFFS];
    memset(envflat, 0, sizeof envflat);
    if (env) {
        prt_sh_light sh;
        if ((st = prt__web_unit_environment_sh(ctx, l, 3, &sh))) return st;
        for (int c = 0; c < 3; ++c) memcpy(envflat + c * PRT__OFFSET_ENV_COEFFS, sh.coeffs[c], PRT__OFFSET_ENV_COEFFS * sizeof(float));
    }
    /* The albedo the per-pixel lights shade with (relight.c's pixel_lights): on translucent texels
     * the dipole's share that leaves within the texel the light entered. */
    float *pixel_albedo = malloc(nv * 3 * sizeof(float));
    uint32_t *source = malloc((size_t)s->width * s->height * sizeof(uint32_t));
    if (!pixel_albedo || !source) { free(pixel_albedo); free(source); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    memcpy(pixel_albedo, t->mesh.albedo, nv * 3 * sizeof(float));
    if (s->subsurface && s->medium)
        for (size_t v = 0; v < nv; ++v) {
            const int x = (int)fminf(fmaxf(t->mesh.uv[v * 2] * (float)s->width, 0.0f), (float)(s->width - 1));
            const int y = (int)fminf(fmaxf(t->mesh.uv[v * 2 + 1] * (float)s->height, 0.0f), (float)(s->height - 1));
            const int32_t c = s->source[(size_t)y * s->width + x];
            if (c >= 0 && s->medium[c]) memcpy(pixel_albedo + v * 3, s->subsurface + (size_t)c * 3, 3 * sizeof(float));
        }
    for (size_t i = 0; i < (size_t)s->width * s->height; ++i) source[i] = s->source[i] < 0 ? UINT32_MAX : (uint32_t)s->source[i];
    const float emission = prt_lighting_emission(l);

    cJSON *meta = prt__web_meta(page);
    bool ok = prt__web_point_lights_meta(meta, l);
    const double eu[3] = {ed->rotate_deg[0], ed->rotate_deg[1], ed->rotate_deg[2]};
    ok = ok && cJSON_AddNumberToObject(meta, "width", s->width) && cJSON_AddNumberToObject(meta, "height", s->height) &&
         cJSON_AddNumberToObject(meta, "covered", (double)nc) && cJSON_AddNumberToObject(meta, "count", s->count) &&
         cJSON_AddNumberToObject(meta, "samples", (double)S) && cJSON_AddNumberToObject(meta, "bounces", bounces) &&
         cJSON_AddNumberToObject(meta, "bounces_max", hi) && cJSON_AddNumberToObject(meta, "levels", s->radiosity ? s->levels : 0) &&
         cJSON_AddNumberToObject(meta, "smooth_radius", s->radiosity && s->levels ? prt__offset_smooth_radius(s) : 0) &&
         cJSON_AddBoolToObject(meta, "radiosity", s->radiosity != NULL) && cJSON_AddBoolToObject(meta, "subsurface", s->subsurface != NULL) &&
         cJSON_AddBoolToObject(meta, "emits", s->emit != NULL) && cJSON_AddNumberToObject(meta, "emission", emission) &&
         cJSON_AddBoolToObject(meta, "environment", env != NULL) && cJSON_AddItemToObject(meta, "rotate", cJSON_CreateDoubleArray(eu, 3)) &&
         cJSON_AddNumberToObject(meta, "intensity", prt_lighting_intensity(l)) &&
         cJSON_AddItemToObject(meta, "offsets", cJSON_CreateIntArray(s->offsets, s->count * 2));
    ok = ok && prt__web_floats(page, "uv", t->mesh.uv, nv * 2) && prt__web_uints(page, "texel", s->texel, nc) &&
         prt__web_uints(page, "source", source, (size_t)s->width * s->height) && prt__web_floats(page, "texel_albedo", s->albedo, nc * 3) &&
         prt__web_floats(page, "texel_env", s->env, nc * PRT__OFFSET_ENV_COEFFS) && prt__web_floats(page, "env", envflat, 3 * PRT__OFFSET_ENV_COEFFS) &&
         prt__web_floats(page, "sample_pos", s->sample_pos, nc * S * 3) && prt__web_floats(page, "sample_nrm", s->sample_nrm, nc * S * 3) &&
         prt__web_floats(page, "albedo", pixel_albedo, nv * 3) &&
         (!s->emit || (prt__web_floats(page, "emit", s->emit, nc * 3) && prt__web_floats(page, "emit_in", s->emit_in, nc * 3))) &&
         (!s->radiosity || (prt__web_floats(page, "radiosity", s->radiosity, (size_t)s->count * nc * 3) &&
                            prt__web_uints(page, "chart", (const uint32_t *)s->chart, nc) && prt__web_small(page, "level", "u8", s->level, (size_t)s->count) &&
                            prt__web_floats(page, "area", s->area, nc) && prt__web_floats(page, "texel_nrm", s->nrm, nc * 3))) &&
         (!s->subsurface || (prt__web_floats(page, "subsurface", s->subsurface, (size_t)s->count * nc * 3) &&
                             prt__web_small(page, "medium", "u8", s->medium, nc)));
    free(pixel_albedo);
    free(source);
    if (!ok) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__web_script(page, prt__js_offset_web);
    return PRT_OK;
}
