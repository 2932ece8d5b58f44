/* prt export --web DIR: a page that relights in the browser. The framework part: the mesh, the
 * view and tone mapping as prt render's, the files (index.html, data.js, prt.js, method.js) and
 * the dispatch to the method's part (methods/NAME/web.c), which adds its arrays, parameters and
 * relighting script. Browsers refuse fetch() and modules over file://, so everything is a classic
 * script: the data as base64 strings in data.js, assigned to a global. */
#include "transfer/method.h"
#include "prt/render.h"

#include <errno.h>
#include <stdarg.h>
#include <sys/stat.h>

extern const char prt__js_transfer_web[];   /* transfer/web.js, compiled in (cmake/embed.cmake) */

struct prt__web {
    cJSON *meta;          /* the method's parameters */
    const char *script;
    prt__bytes arrays;    /* "name": ["f32", "base64"], ... */
    int array_count;
    prt_export_result *out;
    bool failed;
};

static bool put_text(prt__bytes *b, const char *s) { return prt__bytes_put(b, s, strlen(s)); }

static bool put_base64(prt__bytes *b, const unsigned char *p, size_t n)
{
    static const char abc[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char chunk[4096];
    size_t at = 0;
    for (size_t i = 0; i < n; i += 3) {
        const unsigned v = (unsigned)p[i] << 16 | (i + 1 < n ? (unsigned)p[i + 1] << 8 : 0) | (i + 2 < n ? p[i + 2] : 0);
        chunk[at++] = abc[v >> 18 & 63];
        chunk[at++] = abc[v >> 12 & 63];
        chunk[at++] = i + 1 < n ? abc[v >> 6 & 63] : '=';
        chunk[at++] = i + 2 < n ? abc[v & 63] : '=';
        if (at == sizeof chunk) { prt__bytes_put(b, chunk, at); at = 0; }
    }
    return prt__bytes_put(b, chunk, at) && !b->failed;
}

/* Elements of `size` bytes as little-endian bytes (typed arrays in every browser are). */
static bool add_array(prt__web *w, const char *name, const char *type, const void *v, size_t count, int size)
{
    unsigned char *le = malloc(count * (size_t)size + 1);
    if (!le) return !(w->failed = true);
    const unsigned char *p = v;
    for (size_t i = 0; i < count; ++i) {
        uint32_t x = 0;
        if (size == 4) { uint32_t u; memcpy(&u, p + i * 4, 4); x = u; }
        else if (size == 2) { uint16_t u; memcpy(&u, p + i * 2, 2); x = u; }
        else x = p[i];
        for (int b = 0; b < size; ++b) le[i * (size_t)size + (size_t)b] = (unsigned char)(x >> (8 * b));
    }
    prt__bytes *b = &w->arrays;
    bool ok = put_text(b, w->array_count++ ? ",\n\"" : "\"") && put_text(b, name) && put_text(b, "\": [\"") && put_text(b, type) &&
              put_text(b, "\", \"") && put_base64(b, le, count * (size_t)size) && put_text(b, "\"]");
    free(le);
    if (!ok) w->failed = true;
    return ok;
}

bool prt__web_floats(prt__web *w, const char *name, const float *v, size_t count) { return add_array(w, name, "f32", v, count, 4); }
bool prt__web_uints(prt__web *w, const char *name, const uint32_t *v, size_t count) { return add_array(w, name, "u32", v, count, 4); }
bool prt__web_small(prt__web *w, const char *name, const char *type, const void *v, size_t count)
{
    const int size = !strcmp(type, "u16") || !strcmp(type, "i16") ? 2 : !strcmp(type, "u8") || !strcmp(type, "i8") ? 1 : 0;
    if (!size) return !(w->failed = true);
    return add_array(w, name, type, v, count, size);
}
cJSON *prt__web_meta(prt__web *w) { return w->meta; }
void prt__web_script(prt__web *w, const char *js) { w->script = js; }

void prt__web_report(prt__web *w, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    prt__export_report(w->out, "%s", line);
}

/* Writes dir/name from text, atomically, and records it. */
bool prt__web_rotation_named(const prt_lighting *l)
{
    const prt_environment_desc *ed = prt_lighting_environment_desc(l);
    double named[9], rot[9];
    prt_rotation_from_euler_deg(ed->rotate_deg[0], ed->rotate_deg[1], ed->rotate_deg[2], named);
    prt_lighting_rotation(l, rot);
    for (int i = 0; i < 9; ++i)
        if (fabs(named[i] - rot[i]) > 1e-6) return false;
    return true;
}

prt_status prt__web_require_named_rotation(prt_context *ctx, const prt_lighting *l)
{
    if (prt_lighting_envmap(l) && !prt__web_rotation_named(l))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web: the environment's rotation is not one of yaw, pitch and roll (give it with --rotate)");
    return PRT_OK;
}

prt_status prt__web_point_lights_only(prt_context *ctx, const prt_lighting *l, const char *what, int max)
{
    for (int i = 0; i < prt_lighting_count(l); ++i)
        if (prt_lighting_light(l, i)->type != PRT_LIGHT_POINT)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web: %s; light %d is not one (give --light point:X,Y,Z:R,G,B)", what, i + 1);
    if (max > 0 && prt_lighting_count(l) > max)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web: the page draws at most %d point lights", max);
    return PRT_OK;
}

bool prt__web_point_lights_meta(cJSON *meta, const prt_lighting *l)
{
    cJSON *lights = cJSON_CreateArray();
    bool ok = lights && cJSON_AddItemToObject(meta, "lights", lights);
    for (int i = 0; ok && i < prt_lighting_count(l); ++i) {
        const prt_light *li = prt_lighting_light(l, i);
        cJSON *o = cJSON_CreateObject();
        const double p[3] = {li->position[0], li->position[1], li->position[2]}, k[3] = {li->intensity[0], li->intensity[1], li->intensity[2]};
        ok = o && cJSON_AddItemToArray(lights, o) && cJSON_AddItemToObject(o, "position", cJSON_CreateDoubleArray(p, 3)) &&
             cJSON_AddItemToObject(o, "intensity", cJSON_CreateDoubleArray(k, 3));
    }
    return ok;
}

prt_status prt__web_unit_environment_sh(prt_context *ctx, const prt_lighting *l, int order, prt_sh_light *sh)
{
    static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    prt_lighting *unit = NULL;
    prt_status st = prt_lighting_copy(l, &unit);
    if (!st) {
        prt_lighting_clear_lights(unit);
        prt_lighting_set_rotation(unit, identity);
        prt_lighting_set_intensity(unit, 1.0f);
        st = prt_lighting_sh(unit, order, sh);
    }
    prt_lighting_release(unit);
    return st ? prt__fail(ctx, st, "%s", prt_last_error()) : PRT_OK;
}

static prt_status write_file(prt_context *ctx, prt_export_result *out, const char *dir, const char *name, const char *text)
{
    char path[4200];
    if (snprintf(path, sizeof path, "%s/%s", dir, name) >= (int)sizeof path) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "path too long: '%s'", dir);
    prt_status st = prt__atomic_write_text(path, text);
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    if (!prt__export_file(out, path)) { remove(path); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    return PRT_OK;
}

static cJSON *vec3(const float v[3])
{
    const double d[3] = {v[0], v[1], v[2]};
    return cJSON_CreateDoubleArray(d, 3);
}

/* Text with <, > and & escaped, for the page's title. */
static void put_html(prt__bytes *b, const char *s)
{
    for (; *s; ++s) put_text(b, *s == '<' ? "&lt;" : *s == '>' ? "&gt;" : *s == '&' ? "&amp;" : (char[2]){*s, 0});
}

static char *html(const prt_transfer *t, const char *source, int width, int height)
{
    prt__bytes b = {0};
    char line[512];
    put_text(&b, "<!doctype html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>prt: ");
    put_html(&b, source);
    put_text(&b, " (");
    put_html(&b, t->method->name);
    put_text(&b, ")</title>\n<style>\n"
                 "html, body { margin: 0; height: 100%; background: #1c1c1c; color: #ddd; font: 13px sans-serif; overflow: hidden; }\n"
                 "#view { position: absolute; left: 0; top: 0; display: block; cursor: grab; touch-action: none; }\n");
    snprintf(line, sizeof line,
             "#view { width: %dpx; height: %dpx; }\n#panel { position: absolute; left: %dpx; top: 0; width: 260px; bottom: 0; "
             "padding: 8px 12px; box-sizing: border-box; overflow-y: auto; }\n",
             width, height, width);
    put_text(&b, line);
    put_text(&b, "#panel h1 { font-size: 14px; margin: 0 0 6px; }\n#panel label { display: block; margin: 8px 0 2px; }\n"
                 "#panel input[type=range] { width: 100%; }\n#panel .note { color: #999; margin: 6px 0; }\n#panel button { margin: 4px 4px 0 0; }\n"
                 "#message, .noscript { position: absolute; left: 24px; top: 24px; right: 24px; padding: 16px; background: #422; color: #fff; font-size: 16px; }\n"
                 "</style>\n</head>\n<body>\n");
    snprintf(line, sizeof line, "<canvas id=\"view\" width=\"%d\" height=\"%d\"></canvas>\n", width, height);
    put_text(&b, line);
    put_text(&b, "<div id=\"panel\"></div>\n<div id=\"message\" hidden></div>\n"
                 "<noscript><div class=\"noscript\">This page relights with JavaScript and WebGL2: allow JavaScript to see it.</div></noscript>\n"
                 "<script src=\"data.js\"></script>\n<script src=\"prt.js\"></script>\n<script src=\"method.js\"></script>\n"
                 "<script>PRT.start();</script>\n</body>\n</html>\n");
    if (!prt__bytes_put(&b, "", 1)) { prt__bytes_free(&b); return NULL; }
    return (char *)b.data;
}

static bool framework_meta(cJSON *root, const prt_transfer *t, const prt_export_desc *d, const prt_web_desc *web, const char *source)
{
    cJSON *view = cJSON_AddObjectToObject(root, "view");
    float up[3] = {web->up[0], web->up[1], web->up[2]};
    if (!up[0] && !up[1] && !up[2]) up[1] = 1;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < t->mesh.vertex_count * 3; ++i) {
        lo[i % 3] = fminf(lo[i % 3], t->mesh.positions[i]);
        hi[i % 3] = fmaxf(hi[i % 3], t->mesh.positions[i]);
    }
    if (!t->mesh.vertex_count) memset(lo, 0, sizeof lo), memset(hi, 0, sizeof hi);
    return cJSON_AddStringToObject(root, "source", source) && cJSON_AddStringToObject(root, "method", t->method->name) &&
           cJSON_AddStringToObject(root, "title", t->method->title) &&
           cJSON_AddStringToObject(root, "kind", prt_transfer_variant_name(t, d->variant)) &&
           cJSON_AddNumberToObject(root, "vertices", (double)t->mesh.vertex_count) &&
           cJSON_AddNumberToObject(root, "triangles", (double)t->mesh.triangle_count) && cJSON_AddItemToObject(root, "lo", vec3(lo)) &&
           cJSON_AddItemToObject(root, "hi", vec3(hi)) && view && cJSON_AddItemToObject(view, "eye", vec3(web->eye)) &&
           cJSON_AddItemToObject(view, "target", vec3(web->target)) && cJSON_AddItemToObject(view, "up", vec3(up)) &&
           cJSON_AddNumberToObject(view, "fov", web->fov_y_deg > 0 ? web->fov_y_deg : 40.0) && cJSON_AddNumberToObject(view, "width", web->width) &&
           cJSON_AddNumberToObject(view, "height", web->height) && cJSON_AddNumberToObject(view, "exposure", web->exposure_stops) &&
           cJSON_AddBoolToObject(view, "clamp", web->tonemap == 2) && cJSON_AddNumberToObject(view, "max_pixel_lights", PRT_MAX_PIXEL_LIGHTS) && cJSON_AddItemToObject(view, "background", vec3(web->background));
}

prt_status prt_transfer_export_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *desc, const prt_web_desc *web, prt_export_result *out)
{
    if (!t || !desc || !web || !out || !web->dir || !*web->dir)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_export_web: transfer, desc, web (with a folder) and out are required");
    memset(out, 0, sizeof *out);
    if (!desc->lighting) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_export_web: the page needs the lighting it opens under");
    if (!t->method->web) {
        char names[256] = "";
        size_t at = 0;
        for (int i = 0; i < prt_method_count(); ++i)
            if (prt_method_web(prt_method_at(i)) && at < sizeof names)
                at += (size_t)snprintf(names + at, sizeof names - at, "%s%s", at ? ", " : "", prt_method_name(prt_method_at(i)));
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web: %s files have no web page yet (%s files do)", t->method->name, names);
    }
    prt_web_desc w = *web;
    if (w.width <= 0) w.width = 800;
    if (w.height <= 0) w.height = 600;
    if (w.width > 8192 || w.height > 8192) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web: a canvas of %dx%d is too big", w.width, w.height);
    prt_export_desc d = *desc;
    if (d.variant < 0) d.variant = prt_transfer_default_variant(t, 0);
    if (d.variant >= prt_transfer_variant_count(t)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "variant %d out of range", d.variant);
    const char *source = d.source ? d.source : t->source;
    const char *base = strrchr(source, '/');
    base = base ? base + 1 : source;

    prt__web page = {.meta = cJSON_CreateObject(), .out = out};
    cJSON *root = cJSON_CreateObject();
    prt_status st = page.meta && root ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = t->method->web(ctx, t, &d, &page);
    if (!st && !page.script) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "--web: the %s method gave the page no script", t->method->name);
    if (!st) {
        const size_t nv = t->mesh.vertex_count, nt = t->mesh.triangle_count;
        prt__web_floats(&page, "positions", t->mesh.positions, nv * 3);
        prt__web_floats(&page, "normals", t->mesh.normals, nv * 3);
        prt__web_uints(&page, "indices", t->mesh.indices, nt * 3);
        if (!framework_meta(root, t, &d, &w, base) || !cJSON_AddItemToObject(root, "params", page.meta)) page.failed = true;
        else page.meta = NULL;   /* root owns it */
        if (page.failed) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    if (!st && mkdir(w.dir, 0777) != 0 && errno != EEXIST) st = prt__fail(ctx, PRT_ERR_IO, "cannot create '%s': %s", w.dir, strerror(errno));
    if (!st) {
        char *meta = cJSON_PrintUnformatted(root);
        prt__bytes data = {0};
        put_text(&data, "// prt export --web: the data of ");
        put_text(&data, base);
        put_text(&data, " (generated; the page's scripts read it as the global PRT_DATA).\nvar PRT_DATA = {\"meta\": ");
        if (meta) put_text(&data, meta);
        put_text(&data, ",\n\"arrays\": {\n");
        prt__bytes_put(&data, page.arrays.data, page.arrays.size);
        if (!meta || !put_text(&data, "}};") || !prt__bytes_put(&data, "", 1) || page.arrays.failed)
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        free(meta);
        prt__bytes_free(&page.arrays);   /* copied into data: half the memory for the writing */
        char *page_html = st ? NULL : html(t, base, w.width, w.height);
        if (!st && !page_html) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st) st = write_file(ctx, out, w.dir, "data.js", (const char *)data.data);
        if (!st) st = write_file(ctx, out, w.dir, "prt.js", prt__js_transfer_web);
        if (!st) st = write_file(ctx, out, w.dir, "method.js", page.script);
        if (!st) st = write_file(ctx, out, w.dir, "index.html", page_html);
        if (!st) {
            double bytes = 0;
            struct stat sb;
            for (int i = 0; i < out->file_count; ++i)
                if (!stat(out->files[i], &sb)) bytes += (double)sb.st_size;
            prt__export_report(out, "wrote %s/index.html (%s, %s; %.1f MB with its scripts): open it in a browser with WebGL2", w.dir, t->method->name,
                               prt_transfer_variant_name(t, d.variant), bytes / 1e6);
        }
        free(page_html);
        prt__bytes_free(&data);
    }
    prt__bytes_free(&page.arrays);
    cJSON_Delete(page.meta);
    cJSON_Delete(root);
    if (st) {
        for (int i = 0; i < out->file_count; ++i) remove(out->files[i]);
        prt_export_result_free(out);
    }
    return st;
}
