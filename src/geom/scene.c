/* prt_scene: loading, cleaning and subdividing input geometry. */
#include "geom/mesh.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <string.h>
#include <strings.h>

static prt_scene_desc fill_defaults(const prt_scene_desc *in)
{
    prt_scene_desc d = in ? *in : (prt_scene_desc){0};
    /* All zero is "unset" for descs that predate default_albedo_given; with it, black is black. */
    if (!d.default_albedo_given && d.default_albedo[0] == 0 && d.default_albedo[1] == 0 &&
        d.default_albedo[2] == 0)
        d.default_albedo[0] = d.default_albedo[1] = d.default_albedo[2] = 0.7f;
    if (d.crease_angle_deg <= 0) d.crease_angle_deg = 45.0f;
    return d;
}

static prt_status finish(prt_context *ctx, prt_scene *s, const prt_scene_desc *d, const char *what, prt_scene **out)
{
    prt_status st = prt__mesh_clean(ctx, &s->mesh, what);
    if (st == PRT_OK && d->max_edge != 0.0f) st = prt__mesh_subdivide(ctx, &s->mesh, d->max_edge);
    if (st != PRT_OK) { prt_scene_release(s); return st; }
    snprintf(s->source, sizeof s->source, "%s", what);
    *out = s;
    return PRT_OK;
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcasecmp(s + n - k, suffix) == 0;
}

prt_status prt_scene_load(prt_context *ctx, const char *path, const prt_scene_desc *desc, prt_scene **out)
{
    if (!out || !path) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_scene_load: path and out are required");
    *out = NULL;
    prt_scene_desc d = fill_defaults(desc);
    for (int c = 0; c < 3; ++c)
        if (!(d.default_albedo[c] >= 0 && d.default_albedo[c] <= 1))
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "albedo must lie in [0, 1]");
    struct stat sb;
    if (stat(path, &sb) != 0) return prt__fail(ctx, PRT_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    if (!S_ISREG(sb.st_mode)) return prt__fail(ctx, PRT_ERR_IO, "'%s' is %s, not a file", path, S_ISDIR(sb.st_mode) ? "a directory" : "not a regular file");
    prt_scene *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = ends_with(path, ".json") ? prt__import_scene_json(ctx, path, &d, s)
                                             : prt__import_mesh(ctx, path, NULL, NULL, d.inside_points, d.inside_points ? d.inside_point_count : 0, &d, &s->mesh);
    if (st != PRT_OK) { prt_scene_release(s); return st; }
    return finish(ctx, s, &d, path, out);
}

prt_status prt_scene_create_copy(prt_context *ctx, const float *positions, const float *normals,
                                 const float *albedo, size_t vertex_count,
                                 const uint32_t *indices, size_t triangle_count,
                                 const prt_scene_desc *desc, prt_scene **out)
{
    if (!out || !positions || !indices) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_scene_create_copy: positions, indices and out are required");
    *out = NULL;
    prt_scene_desc d = fill_defaults(desc);
    prt_scene *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = prt__mesh_append(&s->mesh, positions, normals, albedo, d.default_albedo, vertex_count, indices, triangle_count);
    if (st != PRT_OK) { prt__fail(ctx, st, "%s", prt_last_error()); prt_scene_release(s); return st; }
    return finish(ctx, s, &d, "(memory)", out);
}

int prt__scene_brdf_id(prt_scene *s, const prt_brdf *brdf)
{
    for (int k = 0; k < s->brdf_count; ++k)
        if (!memcmp(&s->brdfs[k], brdf, sizeof *brdf)) return k + 1;
    if (s->brdf_count == PRT__MAX_BRDFS) return 0;
    s->brdfs[s->brdf_count++] = *brdf;
    return s->brdf_count;
}

prt_status prt_scene_set_brdf(prt_scene *s, size_t first, size_t count, const prt_brdf *brdf)
{
    if (!s || !brdf) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_set_brdf: scene and brdf are required");
    if (first > s->mesh.vertex_count || count > s->mesh.vertex_count - first)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "vertex range %zu+%zu exceeds the scene's %zu vertices", first, count, s->mesh.vertex_count);
    prt_status st = prt_brdf_validate(brdf);
    if (st) return st;
    int id = prt__scene_brdf_id(s, brdf);
    if (!id) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "more than %d BRDF materials", PRT__MAX_BRDFS);
    float rho[3];
    prt_brdf_lambert_albedo(brdf, rho);
    for (size_t v = first; v < first + count; ++v) {
        s->mesh.material[v] = (uint8_t)id;
        memcpy(s->mesh.albedo + v * 3, rho, sizeof rho);
    }
    return PRT_OK;
}

int prt_scene_brdf_count(const prt_scene *s) { return s->brdf_count; }

prt_status prt_scene_paint_albedo(prt_scene *s, const char *name, const float rgb[3])
{
    if (!s || !name || !rgb) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_paint_albedo: scene, name and colour are required");
    return prt__mesh_paint(&s->mesh, name, rgb, s->mesh.albedo);
}

prt_status prt__scene_brdf_choice(prt_scene *s, int surface, const prt_brdf *b)
{
    for (int k = 0; k < s->brdf_set_count; ++k)
        if (s->brdf_set[k].surface == surface && !memcmp(&s->brdf_set[k].brdf, b, sizeof *b)) return PRT_OK;
    if (s->brdf_set_count == PRT__MAX_BRDF_SET) return PRT_ERR_INVALID_ARG;
    prt__brdf_choice *grown = realloc(s->brdf_set, (size_t)(s->brdf_set_count + 1) * sizeof *grown);
    if (!grown) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    s->brdf_set = grown;
    s->brdf_set[s->brdf_set_count++] = (prt__brdf_choice){(uint16_t)surface, *b};
    return PRT_OK;
}

prt_status prt_scene_add_brdf_choice(prt_scene *s, const char *name, const prt_brdf *brdf)
{
    if (!s || !name || !brdf) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_add_brdf_choice: scene, name and BRDF are required");
    int k = 1;
    while (k <= s->mesh.surface_count && strcmp(s->mesh.surface_names[k - 1], name)) ++k;
    if (k > s->mesh.surface_count) {
        char names[512] = "";
        for (int j = 1, at = 0; j <= s->mesh.surface_count && at < (int)sizeof names; ++j)
            at += snprintf(names + at, sizeof names - (size_t)at, "%s%s", j > 1 ? ", " : "", s->mesh.surface_names[j - 1]);
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "no surface '%s' (%s%s)", name, s->mesh.surface_count ? "the scene has " : "the scene names none",
                         names);
    }
    prt_brdf b = *brdf;
    if (prt_brdf_validate(&b)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "%s", prt_last_error());
    /* The surface's own BRDF comes first (what "as baked" is): its first vertex's material, or
     * a Lambertian one of its colour. */
    bool listed = false;
    for (int e = 0; e < s->brdf_set_count && !listed; ++e) listed = s->brdf_set[e].surface == k;
    for (size_t v = 0; !listed && s->mesh.surface && v < s->mesh.vertex_count; ++v) {
        if (s->mesh.surface[v] != k) continue;
        prt_brdf worn = {.model = PRT_BRDF_LAMBERT};
        if (s->mesh.material[v]) worn = s->brdfs[s->mesh.material[v] - 1];
        else memcpy(worn.diffuse, s->mesh.albedo + v * 3, sizeof worn.diffuse);
        prt_status st = prt__scene_brdf_choice(s, k, &worn);
        if (st) return st == PRT_ERR_INVALID_ARG ? prt__fail(NULL, st, "more than %d BRDFs in the sets", PRT__MAX_BRDF_SET) : st;
        break;
    }
    prt_status st = prt__scene_brdf_choice(s, k, &b);
    return st == PRT_ERR_INVALID_ARG ? prt__fail(NULL, st, "more than %d BRDFs in the sets", PRT__MAX_BRDF_SET) : st;
}

prt_status prt_scene_set_emission(prt_scene *s, size_t first, size_t count, const float rgb[3])
{
    if (!s || !rgb) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_set_emission: scene and rgb are required");
    if (first > s->mesh.vertex_count || count > s->mesh.vertex_count - first)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "vertex range %zu+%zu exceeds the scene's %zu vertices", first, count, s->mesh.vertex_count);
    for (int c = 0; c < 3; ++c)
        if (!(rgb[c] >= 0.0f && rgb[c] <= PRT__MAX_RADIANCE)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "emission must be finite and >= 0");
    float *e = prt__mesh_emission(&s->mesh);
    if (!e) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    for (size_t v = first; v < first + count; ++v) memcpy(e + v * 3, rgb, 3 * sizeof(float));
    return PRT_OK;
}

prt_status prt_scene_set_uv(prt_scene *s, size_t first, size_t count, const float *uv)
{
    if (!s || !uv) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_set_uv: scene and uv are required");
    if (first > s->mesh.vertex_count || count > s->mesh.vertex_count - first)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "vertex range %zu+%zu exceeds the scene's %zu vertices", first, count, s->mesh.vertex_count);
    for (size_t i = 0; i < count * 2; ++i)
        if (!isfinite(uv[i])) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "texture coordinate %zu is not finite", i / 2);
    prt__mesh_set_uv(&s->mesh, first, count, uv);
    return PRT_OK;
}

void prt_scene_release(prt_scene *s)
{
    if (!s) return;
    prt__mesh_free(&s->mesh);
    for (int i = 0; i < s->light_count; ++i) prt_light_clear(&s->lights[i]);
    free(s->lights);
    free(s->brdf_set);
    free(s->media);
    free(s->speculars);
    for (int k = 0; k < s->volume_count; ++k) prt__volume_free(&s->volumes[k]);
    free(s->volumes);
    free(s);
}

/* PRT_OK when the scene has a surface of that name; else the error naming the surfaces there are. */
static prt_status require_surface(prt_scene *s, const char *surface)
{
    for (int k = 0; k < s->mesh.surface_count; ++k)
        if (!strcmp(s->mesh.surface_names[k], surface)) return PRT_OK;
    const float keep[3] = {0, 0, 0};
    return prt__mesh_paint(&s->mesh, surface, keep, NULL);   /* fails naming the surfaces there are */
}

prt_status prt_scene_add_volume(prt_scene *s, const prt_volume_desc *d)
{
    if (!s || !d) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_add_volume: scene and volume are required");
    if (s->volume_count >= 64) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a scene holds at most 64 volumes");
    prt__volume v;
    prt_status st = prt__volume_init(NULL, d, &v);
    if (st) return st;
    prt__volume *grown = realloc(s->volumes, (size_t)(s->volume_count + 1) * sizeof *grown);
    if (!grown) { prt__volume_free(&v); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    s->volumes = grown;
    s->volumes[s->volume_count++] = v;
    return PRT_OK;
}

int prt_scene_volume_count(const prt_scene *s) { return s ? s->volume_count : 0; }

prt_status prt_scene_volume(const prt_scene *s, int index, prt_volume_desc *out)
{
    if (!s || !out || index < 0 || index >= s->volume_count) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_volume: no volume %d", index);
    const prt__volume *v = &s->volumes[index];
    memset(out, 0, sizeof *out);
    memcpy(out->dims, v->dims, sizeof out->dims);
    memcpy(out->lo, v->lo, sizeof out->lo);
    memcpy(out->hi, v->hi, sizeof out->hi);
    memcpy(out->albedo, v->albedo, sizeof out->albedo);
    out->density = v->density;
    out->sigma_t = v->sigma_t;
    out->g = v->g;
    return PRT_OK;
}

prt_status prt_scene_set_medium(prt_scene *s, const char *surface, const prt_medium *m)
{
    if (!s || !surface || !m) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_set_medium: scene, surface and medium are required");
    prt_status st = prt_medium_check(m);
    if (st) return st;
    if ((st = require_surface(s, surface))) return st;
    for (int k = 0; k < s->medium_count; ++k)
        if (!strcmp(s->media[k].name, surface)) { s->media[k].m = *m; return PRT_OK; }
    struct prt__named_medium *grown = realloc(s->media, (size_t)(s->medium_count + 1) * sizeof *grown);
    if (!grown) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    s->media = grown;
    memset(&s->media[s->medium_count], 0, sizeof *s->media);
    snprintf(s->media[s->medium_count].name, sizeof s->media[0].name, "%s", surface);
    s->media[s->medium_count++].m = *m;
    return PRT_OK;
}

int prt_scene_medium(const prt_scene *s, const char *surface, prt_medium *out)
{
    for (int k = 0; s && surface && k < s->medium_count; ++k)
        if (!strcmp(s->media[k].name, surface)) { if (out) *out = s->media[k].m; return 1; }
    return 0;
}

prt_status prt_scene_set_specular(prt_scene *s, const char *surface, const prt_specular *sp)
{
    if (!s || !surface || !sp) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_set_specular: scene, surface and material are required");
    prt_status st = sp->type == PRT_SPECULAR_NONE ? PRT_OK : prt_specular_check(sp);
    if (st) return st;
    if ((st = require_surface(s, surface))) return st;
    for (int k = 0; k < s->specular_count; ++k)
        if (!strcmp(s->speculars[k].name, surface)) { s->speculars[k].s = *sp; return PRT_OK; }
    if (sp->type == PRT_SPECULAR_NONE) return PRT_OK;
    struct prt__named_specular *grown = realloc(s->speculars, (size_t)(s->specular_count + 1) * sizeof *grown);
    if (!grown) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    s->speculars = grown;
    memset(&s->speculars[s->specular_count], 0, sizeof *s->speculars);
    snprintf(s->speculars[s->specular_count].name, sizeof s->speculars[0].name, "%s", surface);
    s->speculars[s->specular_count++].s = *sp;
    return PRT_OK;
}

int prt_scene_specular(const prt_scene *s, const char *surface, prt_specular *out)
{
    for (int k = 0; s && surface && k < s->specular_count; ++k)
        if (!strcmp(s->speculars[k].name, surface) && s->speculars[k].s.type != PRT_SPECULAR_NONE) {
            if (out) *out = s->speculars[k].s;
            return 1;
        }
    return 0;
}

size_t prt_scene_vertex_count(const prt_scene *s) { return s->mesh.vertex_count; }
size_t prt_scene_triangle_count(const prt_scene *s) { return s->mesh.triangle_count; }
const float *prt_scene_positions(const prt_scene *s) { return s->mesh.positions; }
const float *prt_scene_normals(const prt_scene *s) { return s->mesh.normals; }
const float *prt_scene_albedo(const prt_scene *s) { return s->mesh.albedo; }
const uint32_t *prt_scene_indices(const prt_scene *s) { return s->mesh.indices; }

int prt_scene_environment(const prt_scene *s, prt_environment_desc *out)
{
    if (s->has_env) *out = s->env;
    return s->has_env;
}

int prt_scene_light_count(const prt_scene *s) { return s ? s->light_count : 0; }

const prt_light *prt_scene_light(const prt_scene *s, int index)
{
    return s && index >= 0 && index < s->light_count ? &s->lights[index] : NULL;
}

prt_status prt_scene_set_lights(prt_scene *s, const prt_light *lights, int count)
{
    if (!s || count < 0 || (count && !lights)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_scene_set_lights: scene and lights (count >= 0) are required");
    prt_light *copy = count ? malloc((size_t)count * sizeof *copy) : NULL;
    if (count && !copy) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    if (count) memcpy(copy, lights, (size_t)count * sizeof *copy);
    for (int i = 0; i < count; ++i)
        if (prt_light_validate(&copy[i])) {
            free(copy);
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light %d: %s", i + 1, prt_last_error());
        }
    free(s->lights);
    s->lights = copy;
    s->light_count = count;
    return PRT_OK;
}

int prt_scene_camera(const prt_scene *s, float eye[3], float target[3], float *fov_deg)
{
    if (!s || !s->has_camera) return 0;
    if (eye) memcpy(eye, s->camera_eye, sizeof s->camera_eye);
    if (target) memcpy(target, s->camera_target, sizeof s->camera_target);
    if (fov_deg) *fov_deg = s->camera_fov;
    return 1;
}

const float *prt_scene_emission(const prt_scene *s) { return s ? s->mesh.emission : NULL; }

prt_status prt_scene_lighting(prt_context *ctx, const prt_scene *s, prt_lighting **out)
{
    if (!s || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_scene_lighting: scene and out are required");
    *out = NULL;
    prt_lighting *l = NULL;
    prt_status st = prt_lighting_create(&l);
    if (st) return st;
    /* A scene lit by its own lamps or emitters gets no sky unless it asks for one. */
    prt_environment_desc env;
    memset(&env, 0, sizeof env);
    if (s->has_env) env = s->env;
    else env.none = s->light_count > 0 || s->mesh.emission != NULL;
    st = prt_lighting_set_environment(l, &env);
    for (int i = 0; i < s->light_count && !st; ++i) st = prt_lighting_add(l, &s->lights[i], NULL);
    if (st) {
        char msg[900];
        snprintf(msg, sizeof msg, "%s", prt_last_error());
        prt_lighting_release(l);
        return prt__fail(ctx, st, "%s: %s", s->source, msg);
    }
    *out = l;
    return PRT_OK;
}

void prt_scene_bounds(const prt_scene *s, float lo[3], float hi[3])
{
    for (int c = 0; c < 3; ++c) { lo[c] = INFINITY; hi[c] = -INFINITY; }
    for (size_t i = 0; i < s->mesh.vertex_count * 3; ++i) {
        lo[i % 3] = fminf(lo[i % 3], s->mesh.positions[i]);
        hi[i % 3] = fmaxf(hi[i % 3], s->mesh.positions[i]);
    }
}

/* The scene's lights and desc's extra ones in one array (the caller frees it). */
static prt_status refine_lights(prt_context *ctx, const prt_scene *s, const prt_refine_desc *desc, prt_light **out, int *count)
{
    *out = NULL;
    const int extra = desc && desc->extra_lights ? desc->extra_light_count : 0;
    if (extra < 0 || extra > 64) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "refinement: extra_light_count must be 0..64 (got %d)", extra);
    prt_light *all = malloc(((size_t)s->light_count + (size_t)extra + 1) * sizeof *all);
    if (!all) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (s->light_count) memcpy(all, s->lights, (size_t)s->light_count * sizeof *all);
    for (int i = 0; i < extra; ++i) {
        all[s->light_count + i] = desc->extra_lights[i];
        if (prt_light_validate(&all[s->light_count + i])) {
            free(all);
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "refinement: extra light %d: %s", i, prt_last_error());
        }
    }
    *out = all;
    *count = s->light_count + extra;
    return PRT_OK;
}

prt_status prt_scene_refine(prt_context *ctx, prt_scene *s, const prt_refine_desc *desc, prt_refine_stats *stats)
{
    if (!s) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_scene_refine: scene is required");
    int count = 0;
    prt_light *lights = NULL;
    prt_status st = refine_lights(ctx, s, desc, &lights, &count);
    if (!st) st = prt__mesh_refine(ctx, &s->mesh, lights, count, desc, stats);
    free(lights);
    return st;
}

prt_status prt_scene_refine_estimate(prt_context *ctx, const prt_scene *s, const prt_refine_desc *desc, prt_refine_stats *stats)
{
    if (!s) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_scene_refine_estimate: scene is required");
    int count = 0;
    prt_light *lights = NULL;
    prt_status st = refine_lights(ctx, s, desc, &lights, &count);
    if (!st) st = prt__mesh_refine_estimate(ctx, &s->mesh, lights, count, desc, stats);
    free(lights);
    return st;
}
