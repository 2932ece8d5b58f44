/* JSON scene files: a list of meshes with transforms and materials, an environment and local
 * lights (docs/SCENE.md). */
#include "geom/mesh.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>

static prt_status read_vec3(const prt_context *ctx, const cJSON *item, const char *what, float out[3])
{
    if (cJSON_IsNumber(item)) { out[0] = out[1] = out[2] = (float)item->valuedouble; return PRT_OK; }
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
        return prt__fail(ctx, PRT_ERR_FORMAT, "scene: '%s' must be a number or an array of 3 numbers", what);
    for (int i = 0; i < 3; ++i) {
        const cJSON *e = cJSON_GetArrayItem(item, i);
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
            return prt__fail(ctx, PRT_ERR_FORMAT, "scene: '%s' element %d is not a finite number", what, i);
        out[i] = (float)e->valuedouble;
    }
    return PRT_OK;
}

/* Row-major 4x4 from scale, then rotation (yaw, pitch, roll in degrees), then translation. */
static void make_xform(const float s[3], const float r[3], const float t[3], float out[16])
{
    double rot[9];
    prt_rotation_from_euler_deg(r[0], r[1], r[2], rot);
    memset(out, 0, 16 * sizeof(float));
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) out[i * 4 + j] = (float)rot[i * 3 + j] * s[j];
        out[i * 4 + 3] = t[i];
    }
    out[15] = 1.0f;
}

static prt_status read_environment(const prt_context *ctx, const cJSON *e, const char *dir, prt_environment_desc *out)
{
    memset(out, 0, sizeof *out);
    /* "none" (or {"none": true}): a scene lit only by its lamps and emitters. */
    if (cJSON_IsString(e) && !strcmp(e->valuestring, "none")) { out->none = 1; return PRT_OK; }
    if (!cJSON_IsObject(e)) return prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"environment\" must be an object or \"none\"");
    const cJSON *v;
    if ((v = cJSON_GetObjectItemCaseSensitive(e, "none"))) {
        if (!cJSON_IsBool(v)) return prt__fail(ctx, PRT_ERR_FORMAT, "scene: environment \"none\" must be true or false");
        if (cJSON_IsTrue(v)) { out->none = 1; return PRT_OK; }
    }
    if ((v = cJSON_GetObjectItemCaseSensitive(e, "file"))) {
        if (!cJSON_IsString(v)) return prt__fail(ctx, PRT_ERR_FORMAT, "scene: environment \"file\" must be a string");
        snprintf(out->path, sizeof out->path, "%s%s", v->valuestring[0] == '/' ? "" : dir, v->valuestring);
    }
    if ((v = cJSON_GetObjectItemCaseSensitive(e, "layout"))) {
        const char *l = cJSON_IsString(v) ? v->valuestring : "";
        if (!strcmp(l, "latlong")) out->layout = PRT_ENV_LATLONG;
        else if (!strcmp(l, "angular")) out->layout = PRT_ENV_ANGULAR;
        else if (!strcmp(l, "cross")) out->layout = PRT_ENV_VCROSS;
        else if (strcmp(l, "auto")) return prt__fail(ctx, PRT_ERR_FORMAT, "scene: environment layout must be latlong, angular, cross or auto");
    }
    prt_status st;
    if ((v = cJSON_GetObjectItemCaseSensitive(e, "rotate")) && (st = read_vec3(ctx, v, "rotate", out->rotate_deg))) return st;
    if ((v = cJSON_GetObjectItemCaseSensitive(e, "sun")) && (st = read_vec3(ctx, v, "sun", out->sun_dir))) return st;
    if ((v = cJSON_GetObjectItemCaseSensitive(e, "intensity"))) {
        if (!cJSON_IsNumber(v) || !(v->valuedouble >= 0)) return prt__fail(ctx, PRT_ERR_FORMAT, "scene: environment intensity must be a number >= 0");
        out->intensity = (float)v->valuedouble;
    }
    return PRT_OK;
}

/* A colour: a number (grey) or [r, g, b], finite and >= 0. */
static prt_status read_colour(const prt_context *ctx, const cJSON *item, const char *what, float out[3])
{
    prt_status st = read_vec3(ctx, item, what, out);
    if (st) return st;
    for (int c = 0; c < 3; ++c)
        if (!(out[c] >= 0) || !isfinite(out[c])) return prt__fail(ctx, PRT_ERR_FORMAT, "scene: '%s' must be finite and >= 0", what);
    return PRT_OK;
}

/* One entry of "lights": exactly the keys its type documents (docs/SCENE.md). */
static prt_status read_light(const prt_context *ctx, const char *path, int i, const cJSON *o, prt_light *out)
{
    memset(out, 0, sizeof *out);
    if (!cJSON_IsObject(o)) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d] must be an object", path, i);
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(o, "type");
    if (!cJSON_IsString(type))
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d] needs a \"type\": point, spot, directional or sphere", path, i);
    static const struct { const char *name; prt_light_type type; const char *keys[6]; } kinds[] = {
        {"point", PRT_LIGHT_POINT, {"position", "intensity"}},
        {"spot", PRT_LIGHT_SPOT, {"position", "direction", "angle", "falloff", "intensity"}},
        {"directional", PRT_LIGHT_DIRECTIONAL, {"direction", "irradiance"}},
        {"sphere", PRT_LIGHT_SPHERE, {"position", "radius", "radiance"}},
    };
    int k = -1;
    for (int j = 0; j < 4; ++j)
        if (!strcmp(type->valuestring, kinds[j].name)) k = j;
    if (k < 0)
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: unknown type '%s' (point, spot, directional or sphere)", path, i,
                         type->valuestring);
    out->type = kinds[k].type;
    const cJSON *v;
    cJSON_ArrayForEach(v, o) {
        bool known = !strcmp(v->string, "type");
        for (int j = 0; j < 6 && kinds[k].keys[j]; ++j) known |= !strcmp(v->string, kinds[k].keys[j]);
        if (!known) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: a %s light has no \"%s\"", path, i, kinds[k].name, v->string);
        if (!strcmp(v->string, "type")) continue;
        bool vector = !strcmp(v->string, "position") || !strcmp(v->string, "direction");
        bool scalar = !strcmp(v->string, "angle") || !strcmp(v->string, "falloff") || !strcmp(v->string, "radius");
        if (vector && !cJSON_IsArray(v))
            return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: \"%s\" must be [x, y, z]", path, i, v->string);
        if (scalar) {
            if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
                return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: \"%s\" must be a number", path, i, v->string);
            float x = (float)v->valuedouble;
            if (!strcmp(v->string, "angle")) out->angle_deg = x;
            else if (!strcmp(v->string, "falloff")) out->falloff_deg = x;
            else out->radius = x;
            continue;
        }
        float *dst = !strcmp(v->string, "position") ? out->position : !strcmp(v->string, "direction") ? out->direction
                   : !strcmp(v->string, "intensity") ? out->intensity : !strcmp(v->string, "irradiance") ? out->irradiance : out->radiance;
        prt_status st = vector ? read_vec3(ctx, v, v->string, dst) : read_colour(ctx, v, v->string, dst);
        if (st) {
            char msg[256];
            snprintf(msg, sizeof msg, "%s", prt_last_error());
            return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: %s", path, i, msg + (strncmp(msg, "scene: ", 7) ? 0 : 7));
        }
    }
    for (int j = 0; j < 6 && kinds[k].keys[j]; ++j)
        if (strcmp(kinds[k].keys[j], "angle") && strcmp(kinds[k].keys[j], "falloff") && !cJSON_GetObjectItemCaseSensitive(o, kinds[k].keys[j]))
            return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: a %s light needs \"%s\"", path, i, kinds[k].name, kinds[k].keys[j]);
    if (out->type == PRT_LIGHT_SPOT && cJSON_GetObjectItemCaseSensitive(o, "angle") && !(out->angle_deg > 0))
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: spot angle must be in (0, 90] degrees", path, i);
    prt_status st = prt_light_validate(out);
    if (st) {
        char msg[256];
        snprintf(msg, sizeof msg, "%s", prt_last_error());
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': lights[%d]: %s", path, i, msg);
    }
    return PRT_OK;
}

static prt_status read_lights(const prt_context *ctx, const char *path, const cJSON *arr, prt_scene *scene)
{
    if (!cJSON_IsArray(arr)) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': \"lights\" must be an array", path);
    int n = cJSON_GetArraySize(arr);
    if (n > 65536) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': %d lights; at most 65536", path, n);
    if (n == 0) return PRT_OK;
    scene->lights = prt__calloc((size_t)n, sizeof *scene->lights);
    if (!scene->lights) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %d lights", n);
    const cJSON *o;
    int i = 0;
    cJSON_ArrayForEach(o, arr) {
        prt_status st = read_light(ctx, path, i, o, &scene->lights[i]);
        if (st) return st;
        scene->light_count = ++i;
    }
    return PRT_OK;
}

/* The BRDF a material wears: its "brdf", else the first of its "brdfs" (the set it can switch
 * among at run time); NULL when it names none. */
static const cJSON *material_brdf(const cJSON *mat)
{
    const cJSON *b = cJSON_GetObjectItemCaseSensitive(mat, "brdf");
    if (b) return b;
    const cJSON *set = cJSON_GetObjectItemCaseSensitive(mat, "brdfs");
    return cJSON_IsArray(set) ? cJSON_GetArrayItem(set, 0) : NULL;
}

/* A material's "brdfs": the BRDFs its surface can switch among at run time, the one it wears
 * (its "brdf", else the first) among them, each once. A material no surface wears has none. */
static prt_status read_brdf_set(const prt_context *ctx, const char *path, const cJSON *mat, const prt_scene_desc *desc, prt_scene *scene)
{
    const cJSON *set = cJSON_GetObjectItemCaseSensitive(mat, "brdfs"), *e;
    if (!set) return PRT_OK;
    if (!cJSON_IsArray(set) || cJSON_GetArraySize(set) == 0)
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"brdfs\" must be a non-empty array of BRDF strings", path, mat->string);
    int surface = 0;
    for (int k = 1; k <= scene->mesh.surface_count && !surface; ++k)
        if (!strcmp(scene->mesh.surface_names[k - 1], mat->string)) surface = k;
    const cJSON *worn = cJSON_GetObjectItemCaseSensitive(mat, "brdf");
    for (int i = -1; i < cJSON_GetArraySize(set); ++i) {
        e = i < 0 ? worn : cJSON_GetArrayItem(set, i);
        if (!e) continue;
        prt_brdf b;
        if (!cJSON_IsString(e) || prt_brdf_parse(e->valuestring, &b))
            return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"brdfs\"[%d]: %s", path, mat->string, i < 0 ? 0 : i,
                             cJSON_IsString(e) ? prt_last_error() : "not a string such as \"phong:32:0.5:0.3\"");
        if (!surface) continue;
        if (desc->override_albedo) memcpy(b.diffuse, desc->default_albedo, sizeof b.diffuse);   /* --albedo: its kd too */
        prt_status st = prt__scene_brdf_choice(scene, surface, &b);
        if (st == PRT_ERR_INVALID_ARG) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': more than %d BRDFs in the materials' \"brdfs\"", path, PRT__MAX_BRDF_SET);
        if (st) return st;
    }
    return PRT_OK;
}

/* "camera": {"eye": [x, y, z], "target": [x, y, z], "fov": degrees}; eye and target required. */
static prt_status read_camera(const prt_context *ctx, const char *path, const cJSON *o, prt_scene *scene)
{
    const cJSON *eye = cJSON_GetObjectItemCaseSensitive(o, "eye"), *target = cJSON_GetObjectItemCaseSensitive(o, "target"),
                *fov = cJSON_GetObjectItemCaseSensitive(o, "fov"), *v;
    if (!cJSON_IsObject(o) || !cJSON_IsArray(eye) || !cJSON_IsArray(target))
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': \"camera\" must be an object with \"eye\" and \"target\" ([x, y, z]) and an optional \"fov\"", path);
    cJSON_ArrayForEach(v, o)
        if (strcmp(v->string, "eye") && strcmp(v->string, "target") && strcmp(v->string, "fov"))
            return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': \"camera\" has no \"%s\" (eye, target, fov)", path, v->string);
    prt_status st;
    if ((st = read_vec3(ctx, eye, "camera eye", scene->camera_eye)) || (st = read_vec3(ctx, target, "camera target", scene->camera_target))) return st;
    scene->camera_fov = 0;
    if (fov) {
        if (!cJSON_IsNumber(fov) || !(fov->valuedouble > 0 && fov->valuedouble < 180))
            return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': camera \"fov\" must be a vertical angle in (0, 180) degrees", path);
        scene->camera_fov = (float)fov->valuedouble;
    }
    const float *e = scene->camera_eye, *t = scene->camera_target;
    if (e[0] == t[0] && e[1] == t[1] && e[2] == t[2]) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': camera \"eye\" and \"target\" are the same point", path);
    scene->has_camera = true;
    return PRT_OK;
}

/* A material's "specular": "mirror" (reflectance 1), "glass" (ior 1.5), {"type": "mirror",
 * "reflectance": R} or {"type": "glass", "ior": N}. */
static prt_status read_specular(const prt_context *ctx, const char *path, const char *name, const cJSON *sp, prt_specular *out)
{
    static const char usage[] = "\"specular\" must be \"mirror\", \"glass\", {\"type\": \"mirror\", \"reflectance\": R} or {\"type\": \"glass\", \"ior\": N}";
    memset(out, 0, sizeof *out);
    const cJSON *type = cJSON_IsObject(sp) ? cJSON_GetObjectItemCaseSensitive(sp, "type") : sp;
    if (!cJSON_IsString(type)) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': %s", path, name, usage);
    if (!strcmp(type->valuestring, "mirror")) *out = (prt_specular){PRT_SPECULAR_MIRROR, 1.0f, 0.0f};
    else if (!strcmp(type->valuestring, "glass")) *out = (prt_specular){PRT_SPECULAR_GLASS, 0.0f, 1.5f};
    else return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': unknown specular type '%s' (mirror or glass)", path, name, type->valuestring);
    const cJSON *v, *keys = cJSON_IsObject(sp) ? sp : NULL;
    cJSON_ArrayForEach(v, keys) {
        if (!strcmp(v->string, "type")) continue;
        const char *key = out->type == PRT_SPECULAR_MIRROR ? "reflectance" : "ior";
        if (strcmp(v->string, key))
            return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': a %s has no \"%s\" (only \"%s\")", path, name, type->valuestring, v->string, key);
        if (!cJSON_IsNumber(v)) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"%s\" must be a number", path, name, key);
        if (out->type == PRT_SPECULAR_MIRROR) out->reflectance = (float)v->valuedouble;
        else out->ior = (float)v->valuedouble;
    }
    if (prt_specular_check(out)) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': %s", path, name, prt_last_error());
    return PRT_OK;
}

/* One entry of "volumes" (docs/SCENE.md): a grid ("file" or "procedural" with "resolution" and
 * "seed") in the box "min".."max", with "extinction", "albedo" and "g". */
static prt_status read_volume(const prt_context *ctx, const char *path, const char *dir, int i, const cJSON *o, prt_scene *scene)
{
    static const char *const keys[] = {"file", "procedural", "resolution", "seed", "min", "max", "extinction", "albedo", "g"};
    if (!cJSON_IsObject(o)) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': volumes[%d] must be an object", path, i);
    const cJSON *v;
    cJSON_ArrayForEach(v, o) {
        bool known = false;
        for (size_t k = 0; k < sizeof keys / sizeof *keys; ++k) known |= !strcmp(v->string, keys[k]);
        if (!known) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': volumes[%d] has no \"%s\" (file, procedural, resolution, seed, min, max, extinction, albedo, g)", path, i, v->string);
    }
    const cJSON *file = cJSON_GetObjectItemCaseSensitive(o, "file"), *proc = cJSON_GetObjectItemCaseSensitive(o, "procedural");
    if (!!file == !!proc) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': volumes[%d] needs a grid \"file\" or a \"procedural\" one (cloud or smoke), not both", path, i);
    prt_volume_desc d = {.sigma_t = 1.0f, .albedo = {1, 1, 1}};
    float *density = NULL;
    prt_status st = PRT_OK;
    char msg[600];
    if ((v = cJSON_GetObjectItemCaseSensitive(o, "min")) && (st = read_vec3(ctx, v, "min", d.lo))) goto fail;
    if ((v = cJSON_GetObjectItemCaseSensitive(o, "max")) && (st = read_vec3(ctx, v, "max", d.hi))) goto fail;
    if (!cJSON_GetObjectItemCaseSensitive(o, "min") || !cJSON_GetObjectItemCaseSensitive(o, "max")) {
        st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: a volume needs its box, \"min\" and \"max\"");
        goto fail;
    }
    if ((v = cJSON_GetObjectItemCaseSensitive(o, "albedo")) && (st = read_colour(ctx, v, "albedo", d.albedo))) goto fail;
    if ((v = cJSON_GetObjectItemCaseSensitive(o, "extinction"))) {
        if (!cJSON_IsNumber(v)) { st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"extinction\" must be a number (per unit length at density 1)"); goto fail; }
        d.sigma_t = (float)v->valuedouble;
    }
    if ((v = cJSON_GetObjectItemCaseSensitive(o, "g"))) {
        if (!cJSON_IsNumber(v)) { st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"g\" must be a number in (-1, 1)"); goto fail; }
        d.g = (float)v->valuedouble;
    }
    if (file) {
        if (!cJSON_IsString(file)) { st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: a volume's \"file\" must be a string"); goto fail; }
        if (cJSON_GetObjectItemCaseSensitive(o, "resolution") || cJSON_GetObjectItemCaseSensitive(o, "seed")) {
            st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"resolution\" and \"seed\" belong to procedural volumes (a file says its own size)");
            goto fail;
        }
        char full[1024];
        snprintf(full, sizeof full, "%s%s", file->valuestring[0] == '/' ? "" : dir, file->valuestring);
        if ((st = prt_volume_grid_load((prt_context *)ctx, full, d.dims, &density))) goto fail;
    } else {
        if (!cJSON_IsString(proc)) { st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"procedural\" must be \"cloud\" or \"smoke\""); goto fail; }
        float res[3] = {32, 32, 32};
        uint32_t seed = 1;
        if ((v = cJSON_GetObjectItemCaseSensitive(o, "resolution")) && (st = read_vec3(ctx, v, "resolution", res))) goto fail;
        for (int c = 0; c < 3; ++c) {
            if (!(res[c] >= 1 && res[c] <= PRT_VOLUME_MAX_DIM) || res[c] != floorf(res[c])) {
                st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"resolution\" must be whole numbers of voxels in 1..%d", PRT_VOLUME_MAX_DIM);
                goto fail;
            }
            d.dims[c] = (int)res[c];
        }
        if ((v = cJSON_GetObjectItemCaseSensitive(o, "seed"))) {
            if (!cJSON_IsNumber(v) || !(v->valuedouble >= 0 && v->valuedouble <= 4294967295.0) || v->valuedouble != floor(v->valuedouble)) {
                st = prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"seed\" must be a whole number in 0..4294967295");
                goto fail;
            }
            seed = (uint32_t)v->valuedouble;
        }
        if ((st = prt_volume_generate((prt_context *)ctx, proc->valuestring, d.dims, seed, &density))) goto fail;
    }
    d.density = density;
    st = prt_scene_add_volume(scene, &d);
fail:
    free(density);
    if (!st) return PRT_OK;
    snprintf(msg, sizeof msg, "%s", prt_last_error());
    return prt__fail(ctx, st == PRT_ERR_NO_MEMORY ? st : PRT_ERR_FORMAT, "'%s': volumes[%d]: %s", path, i, msg + (strncmp(msg, "scene: ", 7) ? 0 : 7));
}

prt_status prt__import_scene_json(const prt_context *ctx, const char *path, const prt_scene_desc *desc, prt_scene *scene)
{
    prt__mesh *m = &scene->mesh;
    void *text;
    size_t size;
    prt_status st = prt__read_file(path, &text, &size);
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    cJSON *root = cJSON_ParseWithLength(text, size);
    free(text);
    if (!root) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s' is not valid JSON", path);
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
    const cJSON *materials = cJSON_GetObjectItemCaseSensitive(root, "materials");
    if (!cJSON_IsArray(meshes) || cJSON_GetArraySize(meshes) == 0) {
        cJSON_Delete(root);
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': a scene needs a non-empty \"meshes\" array", path);
    }
    /* Mesh paths are relative to the scene file's folder. */
    char dir[512] = "";
    const char *slash = strrchr(path, '/');
    if (slash && (size_t)(slash - path) < sizeof dir - 1) { memcpy(dir, path, (size_t)(slash - path) + 1); dir[slash - path + 1] = 0; }

    const cJSON *env = cJSON_GetObjectItemCaseSensitive(root, "environment");
    if (env) {
        if ((st = read_environment(ctx, env, dir, &scene->env))) { cJSON_Delete(root); return st; }
        scene->has_env = true;
    }
    const cJSON *lights = cJSON_GetObjectItemCaseSensitive(root, "lights");
    if (lights && (st = read_lights(ctx, path, lights, scene))) { cJSON_Delete(root); return st; }
    const cJSON *camera = cJSON_GetObjectItemCaseSensitive(root, "camera");
    if (camera && (st = read_camera(ctx, path, camera, scene))) { cJSON_Delete(root); return st; }
    const cJSON *volumes = cJSON_GetObjectItemCaseSensitive(root, "volumes"), *vol;
    if (volumes && !cJSON_IsArray(volumes)) { cJSON_Delete(root); return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': \"volumes\" must be an array", path); }
    int vi = 0;
    cJSON_ArrayForEach(vol, volumes)
        if ((st = read_volume(ctx, path, dir, vi++, vol, scene))) { cJSON_Delete(root); return st; }
    /* Lights with a position sit inside whatever room they light, and the camera inside the room
     * it looks around: its walls face them. So do the points the caller names (its own lights). */
    const size_t extra = desc->inside_points ? desc->inside_point_count : 0;
    float *light_points = malloc(((size_t)scene->light_count + 1 + extra) * 3 * sizeof *light_points);
    if (!light_points) { cJSON_Delete(root); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    size_t light_point_count = 0;
    for (int i = 0; i < scene->light_count; ++i)
        if (scene->lights[i].type != PRT_LIGHT_DIRECTIONAL) memcpy(light_points + light_point_count++ * 3, scene->lights[i].position, 3 * sizeof(float));
    if (scene->has_camera) memcpy(light_points + light_point_count++ * 3, scene->camera_eye, 3 * sizeof(float));
    if (extra) memcpy(light_points + light_point_count * 3, desc->inside_points, extra * 3 * sizeof(float));
    light_point_count += extra;
    const cJSON *item;
    int index = 0;
    cJSON_ArrayForEach(item, meshes) {
        const cJSON *file = cJSON_GetObjectItemCaseSensitive(item, "file");
        if (!cJSON_IsString(file)) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': meshes[%d] needs a \"file\" string", path, index); break; }
        char full[1024];
        snprintf(full, sizeof full, "%s%s", file->valuestring[0] == '/' ? "" : dir, file->valuestring);
        float s[3] = {1, 1, 1}, r[3] = {0, 0, 0}, t[3] = {0, 0, 0}, rgb[3];
        const float *albedo = NULL;
        const cJSON *v;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "scale")) && (st = read_vec3(ctx, v, "scale", s))) break;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "rotate")) && (st = read_vec3(ctx, v, "rotate", r))) break;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "translate")) && (st = read_vec3(ctx, v, "translate", t))) break;
        prt_brdf brdf;
        bool has_brdf = false;
        const cJSON *a = NULL, *b = NULL, *e = NULL;
        const char *material_name = NULL;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "material"))) {
            material_name = cJSON_IsString(v) ? v->valuestring : NULL;
            const cJSON *mat = cJSON_IsString(v) ? cJSON_GetObjectItemCaseSensitive(materials, v->valuestring) : NULL;
            if (!mat) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': meshes[%d] names a material that \"materials\" does not define", path, index); break; }
            a = cJSON_GetObjectItemCaseSensitive(mat, "albedo");
            b = material_brdf(mat);
            e = cJSON_GetObjectItemCaseSensitive(mat, "emission");
            if (!a && !b && !e && !cJSON_GetObjectItemCaseSensitive(mat, "subsurface") && !cJSON_GetObjectItemCaseSensitive(mat, "specular")) {
                st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s' needs an \"albedo\", a \"brdf\", an \"emission\", a \"subsurface\" or a \"specular\"", path,
                               v->valuestring);
                break;
            }
        }
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "albedo"))) a = v;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "brdf"))) b = v;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "emission"))) e = v;
        float le[3];
        if (e && (st = read_colour(ctx, e, "emission", le))) {
            st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': meshes[%d]: \"emission\" must be a number or [r, g, b], finite and >= 0", path, index);
            break;
        }
        if (a && b) {
            st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': meshes[%d]: give an albedo or a brdf, not both (the BRDF's kd is its albedo)", path, index);
            break;
        }
        if (a) {
            if ((st = read_vec3(ctx, a, "albedo", rgb))) break;
            albedo = rgb;
        }
        if (b) {
            if (!cJSON_IsString(b)) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': meshes[%d]: \"brdf\" must be a string such as \"phong:32:0.5:0.3\"", path, index); break; }
            if ((st = prt_brdf_parse(b->valuestring, &brdf))) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': meshes[%d]: %s", path, index, prt_last_error()); break; }
            if (desc->override_albedo) memcpy(brdf.diffuse, desc->default_albedo, sizeof brdf.diffuse);   /* --albedo: its kd too */
            prt_brdf_lambert_albedo(&brdf, rgb);
            albedo = rgb;
            has_brdf = true;
        }
        float xf[16];
        make_xform(s, r, t, xf);
        const size_t first_vertex = m->vertex_count;
        if ((st = prt__import_mesh(ctx, full, xf, albedo, light_points, light_point_count, desc, m))) break;
        if (has_brdf) {
            int id = prt__scene_brdf_id(scene, &brdf);
            if (!id) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': more than %d BRDF materials", path, PRT__MAX_BRDFS); break; }
            memset(m->material + first_vertex, id, m->vertex_count - first_vertex);
        }
        /* Without a material of its own, the file's materials are looked up by name: a JSON
         * material called like one of them replaces it on that surface. */
        if (!a && !b && !e && materials && m->surface)
            for (int sid = 1; sid <= m->surface_count && !st; ++sid) {
                const cJSON *mat = cJSON_GetObjectItemCaseSensitive(materials, m->surface_names[sid - 1]);
                if (!mat) continue;
                const cJSON *ma = cJSON_GetObjectItemCaseSensitive(mat, "albedo"), *mb = material_brdf(mat),
                            *me = cJSON_GetObjectItemCaseSensitive(mat, "emission");
                float mrgb[3] = {0, 0, 0}, mle[3] = {0, 0, 0};
                int brdf_id = 0;
                if (ma && mb) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': give an albedo or a brdf, not both", path, m->surface_names[sid - 1]);
                else if (ma && read_vec3(ctx, ma, "albedo", mrgb)) st = PRT_ERR_FORMAT;
                else if (me && read_colour(ctx, me, "emission", mle))
                    st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"emission\" must be a number or [r, g, b], finite and >= 0", path, m->surface_names[sid - 1]);
                else if (mb) {
                    prt_brdf mbrdf;
                    if (!cJSON_IsString(mb) || prt_brdf_parse(mb->valuestring, &mbrdf))
                        st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"brdf\" must be a BRDF such as \"phong:32:0.5:0.3\"", path, m->surface_names[sid - 1]);
                    else if (desc->override_albedo && (memcpy(mbrdf.diffuse, desc->default_albedo, sizeof mbrdf.diffuse), false))
                        ;
                    else if (!(brdf_id = prt__scene_brdf_id(scene, &mbrdf))) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': more than %d BRDF materials", path, PRT__MAX_BRDFS);
                    else prt_brdf_lambert_albedo(&mbrdf, mrgb);
                }
                float *em = !st && me && (m->emission || mle[0] > 0 || mle[1] > 0 || mle[2] > 0) ? prt__mesh_emission(m) : NULL;
                if (!st && me && !em && (m->emission || mle[0] > 0 || mle[1] > 0 || mle[2] > 0)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
                for (size_t k = first_vertex; k < m->vertex_count && !st; ++k) {
                    if (m->surface[k] != sid) continue;
                    if (ma || mb) memcpy(m->albedo + k * 3, mrgb, sizeof mrgb);
                    if (mb) m->material[k] = (uint8_t)brdf_id;
                    if (em) memcpy(em + k * 3, mle, sizeof mle);
                }
            }
        if (st) break;
        /* prt_scene_desc.override_albedo (--albedo) sets every surface's diffuse albedo, a
         * JSON albedo or a BRDF's kd included (the BRDF keeps its glossy lobe). */
        if (desc->override_albedo)
            for (size_t k = first_vertex; k < m->vertex_count; ++k) memcpy(m->albedo + k * 3, desc->default_albedo, 3 * sizeof(float));
        /* The JSON material names the surface (what --albedo-of recolours), else the file's own. */
        if (material_name) {
            const int id = prt__mesh_surface_id(m, material_name);
            if (id < 0) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': more than %d named surfaces", path, PRT__MAX_SURFACES); break; }
            prt__mesh_set_surface(m, first_vertex, m->vertex_count - first_vertex, id);
        }
        /* A JSON emission replaces whatever the mesh file's materials emit. */
        if (e && (m->emission || le[0] > 0 || le[1] > 0 || le[2] > 0)) {
            float *em = prt__mesh_emission(m);
            if (!em) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
            for (size_t k = first_vertex; k < m->vertex_count; ++k) memcpy(em + k * 3, le, sizeof le);
        }
        index++;
    }
    if (!st) prt__mesh_compact_surfaces(m);   /* the files' names a JSON material replaced */
    const cJSON *setmat, *sets = st ? NULL : materials;
    cJSON_ArrayForEach(setmat, sets)
        if ((st = read_brdf_set(ctx, path, setmat, desc, scene))) break;
    /* Translucent materials: "subsurface" is a measured medium's name or its coefficients. A
     * material no surface wears has nothing to make translucent. */
    const cJSON *mat, *translucent = st ? NULL : materials;
    cJSON_ArrayForEach(mat, translucent) {
        const cJSON *sub = cJSON_GetObjectItemCaseSensitive(mat, "subsurface");
        if (!sub) continue;
        prt_medium med = {.eta = 1.3f};
        if (cJSON_IsString(sub)) {
            if (prt_medium_preset(sub->valuestring, &med)) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': %s", path, mat->string, prt_last_error());
        } else if (cJSON_IsObject(sub) && cJSON_GetObjectItemCaseSensitive(sub, "falloff")) {
            const cJSON *f = cJSON_GetObjectItemCaseSensitive(sub, "falloff");
            if (!cJSON_IsNumber(f)) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"falloff\" must be a distance in mm", path, mat->string);
            else med.falloff_mm = (float)f->valuedouble;
        } else if (cJSON_IsObject(sub)) {
            const cJSON *sa = cJSON_GetObjectItemCaseSensitive(sub, "sigma_a"), *ss = cJSON_GetObjectItemCaseSensitive(sub, "sigma_s"),
                        *eta = cJSON_GetObjectItemCaseSensitive(sub, "eta");
            if (!sa || !ss || read_colour(ctx, sa, "sigma_a", med.sigma_a) || read_colour(ctx, ss, "sigma_s", med.sigma_s) || (eta && !cJSON_IsNumber(eta)))
                st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"subsurface\" needs \"sigma_a\" and \"sigma_s\" (per mm: a number or [r, g, b]) "
                               "and an optional \"eta\", or a \"falloff\" distance", path, mat->string);
            if (!st && eta) med.eta = (float)eta->valuedouble;
        } else {
            st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': \"subsurface\" must be \"skin\", \"marble\", \"ketchup\" or an object", path,
                           mat->string);
        }
        if (!st && prt_medium_check(&med)) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s': %s", path, mat->string, prt_last_error());
        bool worn = false;
        for (int k = 0; !st && k < m->surface_count && !worn; ++k) worn = !strcmp(m->surface_names[k], mat->string);
        if (!st && worn && prt_scene_set_medium(scene, mat->string, &med)) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': %s", path, prt_last_error());
        if (st) break;
    }
    /* Specular materials: "specular" is "mirror", "glass" or an object saying which and how. */
    const cJSON *specular = st ? NULL : materials;
    cJSON_ArrayForEach(mat, specular) {
        const cJSON *sp = cJSON_GetObjectItemCaseSensitive(mat, "specular");
        if (!sp) continue;
        prt_specular spec;
        if ((st = read_specular(ctx, path, mat->string, sp, &spec))) break;
        bool worn = false;
        for (int k = 0; k < m->surface_count && !worn; ++k) worn = !strcmp(m->surface_names[k], mat->string);
        if (worn && prt_scene_set_specular(scene, mat->string, &spec)) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': %s", path, prt_last_error()); break; }
    }
    free(light_points);
    cJSON_Delete(root);
    return st;
}
