/* prt export --web of light-cloud files: the cloud, the zones' responses (raw or clustered PCA)
 * and the emitters' light, for the page (methods/lightcloud/web.js), which relights as relight.c
 * does: each point light's weights over the cloud lights near it that it sees (the framework's
 * JavaScript ray caster for the short fading paths), summed into each zone's merged lights and
 * dotted with the responses; the lights' direct light drawn per pixel by the framework unless the
 * file stores it. Diffuse files and point lights, for now. */
#include "methods/lightcloud/lightcloud.h"

extern const char prt__js_lightcloud_web[];   /* methods/lightcloud/web.js, compiled in */

static bool block(prt__web *page, cJSON *zone, int z, const prt__lightcloud_block *b)
{
    char name[64];
    if (!cJSON_AddNumberToObject(zone, "vertices", b->vertices) || !cJSON_AddNumberToObject(zone, "dim", b->dim) ||
        !cJSON_AddBoolToObject(zone, "raw", b->raw != NULL))
        return false;
    if (!b->vertices) return true;
    if (b->raw) {
        snprintf(name, sizeof name, "z%d_raw", z);
        return prt__web_floats(page, name, b->raw, (size_t)b->vertices * b->dim);
    }
    const prt__cpca *c = b->cpca;
    bool ok = cJSON_AddNumberToObject(zone, "clusters", c->clusters) && cJSON_AddNumberToObject(zone, "vectors", (double)c->vectors_total);
    snprintf(name, sizeof name, "z%d_means", z);
    ok = ok && prt__web_floats(page, name, c->means, (size_t)c->clusters * c->dim);
    snprintf(name, sizeof name, "z%d_basis", z);
    ok = ok && prt__web_floats(page, name, c->basis, c->vectors_total * c->dim);
    snprintf(name, sizeof name, "z%d_counts", z);
    ok = ok && prt__web_uints(page, name, c->counts, (size_t)c->clusters);
    snprintf(name, sizeof name, "z%d_cluster_of", z);
    ok = ok && prt__web_uints(page, name, c->cluster_of, b->vertices);
    snprintf(name, sizeof name, "z%d_weights", z);
    return ok && prt__web_floats(page, name, c->weights, c->weights_total);
}

prt_status prt__lightcloud_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page)
{
    const prt__lightcloud_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    if (s->glossy_count)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web relights diffuse light-cloud files for now: this one has %u glossy vertices, whose exit "
                         "radiance the page does not evaluate yet", s->glossy_count);
    const prt_lighting *l = d->lighting;
    prt_status st = prt__web_point_lights_only(ctx, l, "the light-cloud page lights with point lights", PRT_MAX_PIXEL_LIGHTS);
    if (st) return st;
    int lo, hi, def;
    t->method->control_range(t, 0, &lo, &hi, &def);
    const int neighbours = d->controls ? d->controls[0] : def;

    const float emission = prt_lighting_emission(l);
    float *fixed = NULL;   /* the emitters' light: their own radiance, their direct and indirect light */
    if ((s->emit || t->mesh.emission) && emission > 0) {
        if (!(fixed = prt__calloc(nv * 3, sizeof(float)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        for (size_t i = 0; i < nv * 3; ++i)
            fixed[i] = emission * ((t->mesh.emission ? t->mesh.emission[i] : 0.0f) + (s->emit ? s->emit[i] + s->emit[nv * 3 + i] : 0.0f));
    }
    cJSON *meta = prt__web_meta(page), *zones = cJSON_CreateArray();
    bool ok = zones && cJSON_AddItemToObject(meta, "zones", zones) && prt__web_point_lights_meta(meta, l);
    const double region[6] = {s->region[0], s->region[1], s->region[2], s->region[3], s->region[4], s->region[5]};
    ok = ok && cJSON_AddNumberToObject(meta, "cloud_count", s->cloud_count) && cJSON_AddNumberToObject(meta, "spacing", s->spacing) &&
         cJSON_AddItemToObject(meta, "region", cJSON_CreateDoubleArray(region, 6)) && cJSON_AddNumberToObject(meta, "lobes", s->lobes) &&
         cJSON_AddBoolToObject(meta, "store_direct", s->store_direct) && cJSON_AddNumberToObject(meta, "neighbours", neighbours) &&
         cJSON_AddNumberToObject(meta, "neighbours_max", PRT__KDTREE_MAX_K - 1) && cJSON_AddBoolToObject(meta, "emission", fixed != NULL);
    ok = ok && prt__web_floats(page, "cloud", s->cloud, (size_t)s->cloud_count * 3) && prt__web_uints(page, "members", s->members, nv) &&
         prt__web_uints(page, "member_start", s->member_start, (size_t)s->zone_count + 1) && prt__web_floats(page, "albedo", t->mesh.albedo, nv * 3) &&
         (!fixed || prt__web_floats(page, "fixed", fixed, nv * 3));
    free(fixed);
    for (uint32_t z = 0; ok && z < s->zone_count; ++z) {
        const prt__lightcloud_zone *zone = &s->zones[z];
        cJSON *o = cJSON_CreateObject();
        char name[64];
        snprintf(name, sizeof name, "z%u_light_of", z);
        ok = o && cJSON_AddItemToArray(zones, o) && cJSON_AddNumberToObject(o, "lights", zone->lights) &&
             prt__web_uints(page, name, zone->light_of, s->cloud_count) && block(page, o, (int)z, &zone->diffuse);
    }
    if (!ok) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__web_script(page, prt__js_lightcloud_web);
    return PRT_OK;
}
