/* JSON scene files: a list of meshes with transforms and materials (docs/SCENE.md). */
#include "geom/mesh.h"

#include <cjson/cJSON.h>
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
    if (!cJSON_IsObject(e)) return prt__fail(ctx, PRT_ERR_FORMAT, "scene: \"environment\" must be an object");
    const cJSON *v;
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
        const cJSON *a = NULL, *b = NULL;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "material"))) {
            const cJSON *mat = cJSON_IsString(v) ? cJSON_GetObjectItemCaseSensitive(materials, v->valuestring) : NULL;
            if (!mat) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': meshes[%d] names a material that \"materials\" does not define", path, index); break; }
            a = cJSON_GetObjectItemCaseSensitive(mat, "albedo");
            b = cJSON_GetObjectItemCaseSensitive(mat, "brdf");
            if (!a && !b) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': material '%s' needs an \"albedo\" or a \"brdf\"", path, v->valuestring); break; }
        }
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "albedo"))) a = v;
        if ((v = cJSON_GetObjectItemCaseSensitive(item, "brdf"))) b = v;
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
            prt_brdf_lambert_albedo(&brdf, rgb);
            albedo = rgb;
            has_brdf = true;
        }
        float xf[16];
        make_xform(s, r, t, xf);
        const size_t first_vertex = m->vertex_count;
        if ((st = prt__import_mesh(ctx, full, xf, albedo, desc, m))) break;
        if (has_brdf) {
            int id = prt__scene_brdf_id(scene, &brdf);
            if (!id) { st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': more than %d BRDF materials", path, PRT__MAX_BRDFS); break; }
            memset(m->material + first_vertex, id, m->vertex_count - first_vertex);
        }
        index++;
    }
    cJSON_Delete(root);
    return st;
}
