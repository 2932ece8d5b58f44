/* prt export --web of wavelet files: the sparse Haar transport, the environment's energy over the
 * fine cube (2 x 2 blocks, what a rotation deposits) and the directional lights, for the page
 * (methods/wavelet/web.js), which builds the lighting as lighting.c does - the cube rotated with
 * exact areas as light/env_cube.c, each face Haar-transformed, the largest coefficients kept and
 * quantized - and dots it with each vertex's transport as relight.c; glossy vertices' view factor
 * per pixel from the separable BRDFs' view maps, as render/draw.c's FS_S. */
#include "methods/wavelet/wavelet.h"

#include "core/cubemap.h"
#include "light/env_cube.h"

extern const char prt__js_wavelet_web[];   /* methods/wavelet/web.js, compiled in */

prt_status prt__wavelet_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page)
{
    const prt__wavelet_set *w = t->state;
    /* Glossy materials: their view maps and each vertex's set, for the view factor per pixel. */
    const float *view_maps = NULL;
    const uint8_t *vertex_set = NULL;
    int view_sets = 0, view_res = 0, polar = 0;
    const bool glossy = prt_wavelet_view_maps(t, &view_maps, &view_sets, &view_res, &polar, &vertex_set) && view_sets > 0;
    const prt_lighting *l = d->lighting;
    const prt_envmap *env = prt_lighting_envmap(l);
    const size_t nv = t->mesh.vertex_count, vectors = w->store.vectors;
    const int n = w->store.n;
    int lo, hi, def;
    t->method->control_range(t, 0, &lo, &hi, &def);
    const int coefficients = d->controls && d->controls[0] ? d->controls[0] : def;
    if (coefficients < lo || coefficients > hi)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "light-coefficients %d out of range %d..%d", coefficients, lo, hi);

    /* The rotation the page starts at: the yaw, pitch and roll the environment was named with. */
    const prt_environment_desc *ed = prt_lighting_environment_desc(l);
    prt_status st = prt__web_require_named_rotation(ctx, l);
    if (st) return st;

    cJSON *meta = prt__web_meta(page), *lights = cJSON_CreateArray();
    bool ok = lights && cJSON_AddItemToObject(meta, "lights", lights);
    for (int i = 0; ok && i < prt_lighting_count(l); ++i) {
        const prt_light *li = prt_lighting_light(l, i);
        if (li->type != PRT_LIGHT_DIRECTIONAL) continue;   /* the table lets no other kind through */
        cJSON *o = cJSON_CreateObject();
        const double dir[3] = {li->direction[0], li->direction[1], li->direction[2]}, e[3] = {li->irradiance[0], li->irradiance[1], li->irradiance[2]};
        ok = o && cJSON_AddItemToArray(lights, o) && cJSON_AddItemToObject(o, "direction", cJSON_CreateDoubleArray(dir, 3)) &&
             cJSON_AddItemToObject(o, "irradiance", cJSON_CreateDoubleArray(e, 3));
    }
    double axes[54];
    for (int i = 0; i < 54; ++i) axes[i] = prt__cube_axes[i / 9][i / 3 % 3][i % 3];
    const double eu[3] = {ed->rotate_deg[0], ed->rotate_deg[1], ed->rotate_deg[2]};
    ok = ok && cJSON_AddNumberToObject(meta, "coefficients", n) && cJSON_AddNumberToObject(meta, "bits", w->store.bits) &&
         cJSON_AddNumberToObject(meta, "terms", w->terms) && cJSON_AddNumberToObject(meta, "light_coefficients", coefficients) &&
         cJSON_AddNumberToObject(meta, "light_coefficients_min", lo) && cJSON_AddNumberToObject(meta, "light_coefficients_max", hi) &&
         cJSON_AddBoolToObject(meta, "environment", env != NULL) && cJSON_AddItemToObject(meta, "rotate", cJSON_CreateDoubleArray(eu, 3)) &&
         cJSON_AddNumberToObject(meta, "intensity", prt_lighting_intensity(l)) && cJSON_AddItemToObject(meta, "axes", cJSON_CreateDoubleArray(axes, 54));
    if (!ok) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");

    float omega[PRT__ENV_CUBE_FACE * PRT__ENV_CUBE_FACE];
    prt__env_cube_solid_angles(omega);
    ok = prt__web_floats(page, "omega", omega, PRT__ENV_CUBE_FACE * PRT__ENV_CUBE_FACE);
    if (ok && env) {
        const size_t count = (size_t)6 * PRT__ENV_CUBE_QUADS * PRT__ENV_CUBE_QUADS * 3;
        float *quads = malloc(count * sizeof *quads);
        if (!quads) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        st = prt__env_cube_quads(ctx, env, quads);
        if (st) { free(quads); return st; }
        ok = prt__web_floats(page, "quads", quads, count);
        free(quads);
    }
    ok = ok && cJSON_AddBoolToObject(meta, "glossy", glossy) &&
         (!glossy || (cJSON_AddNumberToObject(meta, "view_sets", view_sets) && cJSON_AddNumberToObject(meta, "view_resolution", view_res) &&
                      cJSON_AddBoolToObject(meta, "polar", polar) &&
                      prt__web_floats(page, "view_maps", view_maps, (size_t)view_sets * w->terms * 3 * view_res * view_res) &&
                      prt__web_small(page, "vertex_set", "u8", vertex_set, nv)));
    ok = ok && prt__web_small(page, "term_count", "u8", w->term_count, nv) && prt__web_small(page, "index", "u16", w->store.index, vectors * (size_t)n) &&
         prt__web_small(page, "values", w->store.bits == 8 ? "i8" : "i16", w->store.values, vectors * (size_t)n * 3) &&
         prt__web_floats(page, "scale", w->store.scale, vectors * 3) && prt__web_floats(page, "albedo", t->mesh.albedo, nv * 3);
    if (!ok) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__web_script(page, prt__js_wavelet_web);
    return PRT_OK;
}
