/* prt_transfer_describe: what a .prt holds, as text lines or JSON, from one code path. The
 * method-independent fields come first and last; the method adds its own in between. */
#include "transfer/method.h"

#include <stdarg.h>

void prt__describe_line(prt__describe *d, const char *label, const char *fmt, ...)
{
    if (d->json || d->failed) return;
    char value[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(value, sizeof value, fmt, ap);
    va_end(ap);
    char line[2200];
    int n = snprintf(line, sizeof line, "%-12s %s\n", label, value);
    if (n < 0) return;
    if (d->length + (size_t)n + 1 > d->capacity) {
        size_t cap = (d->capacity + (size_t)n + 1) * 2;
        char *p = realloc(d->text, cap);
        if (!p) { d->failed = true; return; }
        d->text = p;
        d->capacity = cap;
    }
    memcpy(d->text + d->length, line, (size_t)n + 1);
    d->length += (size_t)n;
}

static size_t mesh_bytes(const prt_transfer *t)
{
    return t->mesh.vertex_count * 36 + t->mesh.triangle_count * 12;
}

/* Vertices per named surface (count + 1 entries, [0] = unnamed); NULL when none are named. */
static size_t *surface_sizes(const prt_transfer *t)
{
    const prt__mesh *m = &t->mesh;
    if (!m->surface_count || !m->surface) return NULL;
    size_t *n = prt__calloc((size_t)m->surface_count + 1, sizeof(size_t));
    for (size_t v = 0; n && v < m->vertex_count; ++v) n[m->surface[v]]++;
    return n;
}

prt_status prt_transfer_describe(const prt_transfer *t, const char *name, int json, char **out)
{
    if (!t || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_describe: transfer and out are required");
    *out = NULL;
    prt__describe d = {0};
    d.json = json != 0;
    if (d.json) d.root = cJSON_CreateObject();
    const size_t bytes = t->method->transfer_bytes(t), nv = t->mesh.vertex_count;
    cJSON *j = prt__describe_json(&d);
    if (j) {
        cJSON_AddStringToObject(j, "file", name ? name : "");
        cJSON_AddStringToObject(j, "method", t->method->name);
    }
    prt__describe_line(&d, "file:", "%s", name ? name : "");
    prt__describe_line(&d, "method:", "%s (%s)", t->method->title, t->method->name);
    t->method->describe(t, &d);
    char spec[128];
    /* The box, so that cameras (--eye, --target) and lights can be placed without opening the mesh. */
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (size_t v = 0; v < nv; ++v)
        for (int c = 0; c < 3; ++c) {
            const float x = t->mesh.positions[v * 3 + c];
            if (!v || x < lo[c]) lo[c] = x;
            if (!v || x > hi[c]) hi[c] = x;
        }
    if (j) {
        cJSON_AddNumberToObject(j, "vertices", (double)nv);
        cJSON_AddNumberToObject(j, "triangles", (double)t->mesh.triangle_count);
        cJSON *box = cJSON_AddObjectToObject(j, "bounds");
        cJSON_AddItemToObject(box, "min", cJSON_CreateFloatArray(lo, 3));
        cJSON_AddItemToObject(box, "max", cJSON_CreateFloatArray(hi, 3));
        cJSON_AddNumberToObject(j, "transfer_bytes", (double)bytes);
        cJSON_AddNumberToObject(j, "mesh_bytes", (double)mesh_bytes(t));
        cJSON_AddNumberToObject(j, "bytes_per_vertex", (double)bytes / (double)nv);
        cJSON_AddNumberToObject(j, "bake_seconds", t->bake_seconds);
        cJSON_AddNumberToObject(j, "bake_threads", t->threads);
        if (t->peak_bytes) cJSON_AddNumberToObject(j, "bake_peak_resident_bytes", (double)t->peak_bytes);
        if (t->memory_limit) cJSON_AddNumberToObject(j, "bake_memory_limit_bytes", t->memory_limit == UINT64_MAX ? -1.0 : (double)t->memory_limit);
        cJSON_AddStringToObject(j, "source", t->source);
        cJSON *mats = cJSON_GetObjectItemCaseSensitive(j, "materials");
        if (!mats) {
            mats = cJSON_AddArrayToObject(j, "materials");
            for (int k = 1; k <= t->brdf_count; ++k) {
                prt_brdf_format(&t->brdfs[k - 1], spec, sizeof spec);
                cJSON_AddItemToArray(mats, cJSON_CreateString(spec));
            }
        }
        cJSON *lights = cJSON_AddArrayToObject(j, "lights");
        for (int i = 0; i < t->light_count; ++i) {
            char l[512];
            prt_light_format(&t->lights[i], l, sizeof l);
            cJSON_AddItemToArray(lights, cJSON_CreateString(l));
        }
        size_t emitting = 0;
        for (size_t v = 0; t->mesh.emission && v < nv; ++v)
            emitting += t->mesh.emission[v * 3] > 0 || t->mesh.emission[v * 3 + 1] > 0 || t->mesh.emission[v * 3 + 2] > 0;
        cJSON_AddNumberToObject(j, "emissive_vertices", (double)emitting);
        if (t->has_env) cJSON_AddStringToObject(j, "environment", t->env.none ? "none" : t->env.path[0] ? t->env.path : "procedural sky");
        cJSON *surfaces = cJSON_AddArrayToObject(j, "surfaces");
        size_t *sizes = surface_sizes(t);
        for (int k = 0; sizes && k < t->mesh.surface_count; ++k) {
            cJSON *o = cJSON_CreateObject();
            cJSON_AddStringToObject(o, "name", t->mesh.surface_names[k]);
            cJSON_AddNumberToObject(o, "vertices", (double)sizes[k + 1]);
            const int nb = prt_transfer_brdf_set(t, k + 1, -1, NULL);
            cJSON *set = nb ? cJSON_AddArrayToObject(o, "brdfs") : NULL;   /* what --brdf-of switches among */
            for (int i = 0; i < nb; ++i) {
                prt_brdf b;
                prt_transfer_brdf_set(t, k + 1, i, &b);
                prt_brdf_format(&b, spec, sizeof spec);
                cJSON_AddItemToArray(set, cJSON_CreateString(spec));
            }
            cJSON_AddItemToArray(surfaces, o);
        }
        free(sizes);
        cJSON *relights = cJSON_AddArrayToObject(j, "relights");
        for (unsigned bit = 1; bit <= PRT_LIGHTS_IES; bit <<= 1)
            if (t->method->lighting & bit) cJSON_AddItemToArray(relights, cJSON_CreateString(prt_lights_bit_name(bit)));   /* as listed below */
        cJSON_AddBoolToObject(j, "runtime_albedo", t->method->runtime_albedo);
        cJSON_AddBoolToObject(j, "gpu_passes", t->method->gpu_passes);
        cJSON *exports = cJSON_AddArrayToObject(j, "export_options");
        for (int i = 0; i < t->method->export_option_count; ++i) cJSON_AddItemToArray(exports, cJSON_CreateString(t->method->export_options[i].name));
        cJSON *controls = cJSON_AddArrayToObject(j, "controls");
        for (int i = 0; i < t->method->control_count; ++i) {
            int lo, hi, def;
            prt_transfer_control_range(t, i, &lo, &hi, &def);
            cJSON *o = cJSON_CreateObject();
            cJSON_AddStringToObject(o, "name", t->method->controls[i].name);
            cJSON_AddNumberToObject(o, "min", lo);
            cJSON_AddNumberToObject(o, "max", hi);
            cJSON_AddNumberToObject(o, "default", def);
            cJSON_AddItemToArray(controls, o);
        }
        char *text = cJSON_Print(j);
        cJSON_Delete(j);
        if (!text) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
        *out = strdup(text);
        cJSON_free(text);
        return *out ? PRT_OK : prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    }
    size_t emissive = 0;
    for (size_t v = 0; t->mesh.emission && v < nv; ++v)
        emissive += t->mesh.emission[v * 3] > 0 || t->mesh.emission[v * 3 + 1] > 0 || t->mesh.emission[v * 3 + 2] > 0;
    prt__describe_line(&d, "mesh:", "%zu vertices, %zu triangles%s", nv, t->mesh.triangle_count, prt__mesh_has_uv(&t->mesh) ? ", with UVs" : "");
    prt__describe_line(&d, "bounds:", "%.4g, %.4g, %.4g to %.4g, %.4g, %.4g (size %.4g x %.4g x %.4g)", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
                       hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    if (emissive) prt__describe_line(&d, "emissive:", "%zu vertices emit light", emissive);
    for (int i = 0; i < t->light_count; ++i) {
        char l[512];
        prt_light_format(&t->lights[i], l, sizeof l);
        prt__describe_line(&d, i ? "" : "lights:", "%s", l);
    }
    if (t->has_env)
        prt__describe_line(&d, "environment:", "%s", t->env.none ? "none" : t->env.path[0] ? t->env.path : "procedural sky");
    size_t *sizes = surface_sizes(t);
    for (int k = 0; sizes && k < t->mesh.surface_count; ++k)
        prt__describe_line(&d, k ? "" : "surfaces:", "%s (%zu vertices)", t->mesh.surface_names[k], sizes[k + 1]);
    free(sizes);
    /* The BRDF sets, each surface's on one line: what --brdf-of and the viewer's m switch among. */
    for (int k = 1, first = 1; k <= t->mesh.surface_count; ++k) {
        const int nb = prt_transfer_brdf_set(t, k, -1, NULL);
        if (!nb) continue;
        char line[1024];
        size_t at = (size_t)snprintf(line, sizeof line, "%s:", t->mesh.surface_names[k - 1]);
        for (int i = 0; i < nb && at < sizeof line; ++i) {
            prt_brdf b;
            prt_transfer_brdf_set(t, k, i, &b);
            prt_brdf_format(&b, spec, sizeof spec);
            at += (size_t)snprintf(line + at, sizeof line - at, "%s %s", i ? "," : "", spec);
        }
        prt__describe_line(&d, first ? "brdf sets:" : "", "%s", line);
        first = 0;
    }
    /* What the file can be relit under and with, so that help texts can point here. */
    char relights[256] = "";
    prt_lights_names(t->method->lighting, ", ", relights, sizeof relights);
    bool sets = false;
    for (int k = 1; k <= t->mesh.surface_count && !sets; ++k) sets = prt_transfer_brdf_set(t, k, -1, NULL) > 0;
    prt__describe_line(&d, "relights:", "%s%s%s%s%s", relights, t->method->runtime_albedo ? "; surface colours live (--albedo-of)" : "",
                       sets ? "; BRDFs of the baked sets (--brdf-of)" : "",
                       t->method->gpu_passes ? "; GPU passes (--accumulate gpu)" : "",
                       t->method->paint_layout ? "; painted first-order light (--paint, prt view's o)" : "");
    for (int i = 0; i < t->method->export_option_count; ++i)
        prt__describe_line(&d, i ? "" : "exports:", "--%s%s%s", t->method->export_options[i].name, t->method->export_options[i].arg ? " " : "",
                           t->method->export_options[i].arg ? t->method->export_options[i].arg : "");
    for (int i = 0; i < t->method->control_count; ++i) {
        int lo, hi, def;
        prt_transfer_control_range(t, i, &lo, &hi, &def);
        prt__describe_line(&d, i ? "" : "controls:", "%s %d..%d (default %d): %s", t->method->controls[i].name, lo, hi, def, t->method->controls[i].help);
    }
    prt__describe_line(&d, "storage:", "%.2f MiB transfer, %.0f bytes per vertex", bytes / 1048576.0, (double)bytes / (double)nv);
    prt__describe_line(&d, "bake time:", "%.2f s on %d threads", t->bake_seconds, t->threads);
    if (t->peak_bytes) {
        char peak[32], limit[32];
        prt__describe_line(&d, "bake memory:", "peak %s resident (limit %s)", prt_memory_size_format(t->peak_bytes, peak, sizeof peak),
                           t->memory_limit ? prt_memory_size_format(t->memory_limit, limit, sizeof limit) : "not recorded");
    }
    prt__describe_line(&d, "source:", "%s", t->source);
    if (d.failed) { free(d.text); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    *out = d.text;
    return PRT_OK;
}

size_t prt_transfer_bytes(const prt_transfer *t) { return t ? t->method->transfer_bytes(t) : 0; }

prt_status prt_transfer_bake_report(const prt_transfer *t, char **out)
{
    if (!t || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_bake_report: transfer and out are required");
    prt__describe d = {0};
    if (t->method->report) t->method->report(t, &d);
    if (d.failed) { free(d.text); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    *out = d.text ? d.text : strdup("");
    return *out ? PRT_OK : prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
}
