/* Meshes with vertex colours out through assimp's exporters: prt builds the aiScene itself (one
 * mesh, one node, an empty material) and lets assimp write glTF 2.0, PLY or OBJ. Exporters write
 * their main file and its companions (.bin, .mtl) by name, so they write into a fresh directory
 * beside the target, and each file is renamed into place once all are complete. */
#include "core/internal.h"
#include "io/container.h"
#include "prt/image.h"

#include <assimp/cexport.h>
#include <cjson/cJSON.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

static float srgb_encode(float x)
{
    return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
}

/* Moves every file of dir into parent (their names are the export's), then removes dir. */
static bool move_out(const char *dir, const char *parent)
{
    DIR *d = opendir(dir);
    if (!d) return false;
    bool ok = true;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char from[8400], to[8400];
        snprintf(from, sizeof from, "%.4096s/%.255s", dir, e->d_name);
        snprintf(to, sizeof to, "%.4096s/%.255s", parent, e->d_name);
        ok &= rename(from, to) == 0;
    }
    closedir(d);
    return rmdir(dir) == 0 && ok;
}

static void remove_dir(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char f[8400];
        snprintf(f, sizeof f, "%.4096s/%.255s", dir, e->d_name);
        remove(f);
    }
    if (d) closedir(d);
    rmdir(dir);
}

static bool valid_attribute_name(const char *n)
{
    if (!n || n[0] != '_' || !n[1] || strlen(n) > 31) return false;
    for (const char *p = n + 1; *p; ++p)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '_')) return false;
    return true;
}

/* assimp writes colour sets 1..n as COLOR_1..COLOR_n: give them their own names. */
static bool rename_attributes(cJSON *gltf, int count, const char *const *names)
{
    cJSON *meshes = cJSON_GetObjectItemCaseSensitive(gltf, "meshes"), *mesh, *prim;
    int renamed = 0;
    cJSON_ArrayForEach(mesh, meshes) {
        cJSON_ArrayForEach(prim, cJSON_GetObjectItemCaseSensitive(mesh, "primitives")) {
            cJSON *attrs = cJSON_GetObjectItemCaseSensitive(prim, "attributes");
            for (int k = 0; k < count; ++k) {
                char from[24];
                snprintf(from, sizeof from, "COLOR_%d", k + 1);
                cJSON *a = cJSON_DetachItemFromObjectCaseSensitive(attrs, from);
                if (!a) return false;
                cJSON_AddItemToObject(attrs, names[k], a);
                renamed++;
            }
        }
    }
    return renamed == count;
}

/* Whether an "extensions" object anywhere under item names the extension. */
static bool extension_used(const cJSON *item, const char *name)
{
    const cJSON *c;
    cJSON_ArrayForEach(c, item) {
        if (c->string && !strcmp(c->string, "extensions") && cJSON_IsObject(c) && cJSON_GetObjectItemCaseSensitive(c, name)) return true;
        if ((cJSON_IsObject(c) || cJSON_IsArray(c)) && extension_used(c, name)) return true;
    }
    return false;
}

/* extensionsUsed as the file uses them: assimp 5.2 declares FB_ngon_encoding (its triangles
 * encoding polygons: prt's are triangles only) and KHR_materials_volume for a material with no
 * volume, which the glTF-Validator reports and loaders may refuse or warn about. */
static void prune_extensions(cJSON *gltf)
{
    cJSON *used = cJSON_GetObjectItemCaseSensitive(gltf, "extensionsUsed");
    for (int i = cJSON_GetArraySize(used) - 1; i >= 0; --i) {
        const cJSON *e = cJSON_GetArrayItem(used, i);
        if (!cJSON_IsString(e) || !extension_used(gltf, e->valuestring)) cJSON_DeleteItemFromArray(used, i);
    }
    if (used && !cJSON_GetArraySize(used)) cJSON_DeleteItemFromObjectCaseSensitive(gltf, "extensionsUsed");
}

/* The colours are light already (relit radiance, baked transfer): every material is marked
 * unlit (KHR_materials_unlit, meant for baked lighting), so that viewers show them as they are
 * instead of lighting them a second time. */
static bool mark_unlit(cJSON *gltf)
{
    cJSON *materials = cJSON_GetObjectItemCaseSensitive(gltf, "materials"), *m;
    if (!cJSON_GetArraySize(materials)) return true;
    cJSON_ArrayForEach(m, materials) {
        cJSON *ext = cJSON_GetObjectItemCaseSensitive(m, "extensions");
        if (!ext && !(ext = cJSON_AddObjectToObject(m, "extensions"))) return false;
        if (!cJSON_HasObjectItem(ext, "KHR_materials_unlit") && !cJSON_AddObjectToObject(ext, "KHR_materials_unlit")) return false;
    }
    cJSON *used = cJSON_GetObjectItemCaseSensitive(gltf, "extensionsUsed");
    if (!used && !(used = cJSON_AddArrayToObject(gltf, "extensionsUsed"))) return false;
    const cJSON *e;
    cJSON_ArrayForEach(e, used) if (cJSON_IsString(e) && !strcmp(e->valuestring, "KHR_materials_unlit")) return true;
    cJSON *name = cJSON_CreateString("KHR_materials_unlit");
    if (!name || !cJSON_AddItemToArray(used, name)) { cJSON_Delete(name); return false; }
    return true;
}

/* asset.generator names prt, then the exporter assimp named. */
static bool name_generator(cJSON *gltf)
{
    cJSON *asset = cJSON_GetObjectItemCaseSensitive(gltf, "asset");
    if (!cJSON_IsObject(asset)) return false;
    const cJSON *was = cJSON_GetObjectItemCaseSensitive(asset, "generator");
    char text[256];
    snprintf(text, sizeof text, "prt %s%s%.200s", prt_version_string(), cJSON_IsString(was) ? " through " : "", cJSON_IsString(was) ? was->valuestring : "");
    cJSON *g = cJSON_CreateString(text);
    const bool ok = g && (cJSON_HasObjectItem(asset, "generator") ? cJSON_ReplaceItemInObjectCaseSensitive(asset, "generator", g)
                                                                   : cJSON_AddItemToObject(asset, "generator", g));
    if (g && !ok) cJSON_Delete(g);
    return ok;
}

static unsigned char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    unsigned char *data = NULL;
    long n = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (n > 0 && fseek(f, 0, SEEK_SET) == 0 && (data = malloc((size_t)n)) && fread(data, 1, (size_t)n, f) != (size_t)n) { free(data); data = NULL; }
    fclose(f);
    *size = data ? (size_t)n : 0;
    return data;
}

static uint32_t get_u32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static void put_u32(unsigned char *p, uint32_t v) { p[0] = (unsigned char)v; p[1] = (unsigned char)(v >> 8); p[2] = (unsigned char)(v >> 16); p[3] = (unsigned char)(v >> 24); }

/* Finishes the JSON of the file assimp wrote - the custom attributes named, the material unlit,
 * extensionsUsed as used, the generator - so that the Khronos glTF-Validator finds nothing to report
 * (tests/gltf_test.sh): the JSON of a .gltf, or the JSON chunk of a .glb (its header and chunk
 * lengths rewritten, the binary chunk kept as it is). */
static bool finish_gltf(const char *file, bool binary, int count, const char *const *names)
{
    size_t size;
    unsigned char *data = read_all(file, &size);
    if (!data) return false;
    size_t json_at = 0, json_len = size, rest_at = size;
    if (binary) {
        /* Header: magic, version, length; then the JSON chunk (length, type), padded to 4. */
        if (size < 20 || memcmp(data, "glTF", 4) || get_u32(data + 12) > size - 20 || memcmp(data + 16, "JSON", 4)) { free(data); return false; }
        json_at = 20;
        json_len = get_u32(data + 12);
        rest_at = json_at + json_len;
    }
    cJSON *gltf = cJSON_ParseWithLength((const char *)data + json_at, json_len);
    bool named = gltf && rename_attributes(gltf, count, names) && name_generator(gltf) && mark_unlit(gltf);
    if (named) prune_extensions(gltf);
    char *text = named ? cJSON_PrintUnformatted(gltf) : NULL;
    cJSON_Delete(gltf);
    bool ok = text != NULL;
    FILE *f = ok ? fopen(file, "wb") : NULL;
    if (f) {
        const size_t n = strlen(text), padded = binary ? (n + 3) & ~(size_t)3 : n;
        if (binary) {
            unsigned char head[20];
            memcpy(head, "glTF", 4);
            put_u32(head + 4, 2);
            put_u32(head + 8, (uint32_t)(20 + padded + (size - rest_at)));
            put_u32(head + 12, (uint32_t)padded);
            memcpy(head + 16, "JSON", 4);
            ok = fwrite(head, 1, 20, f) == 20;
        }
        ok = ok && fwrite(text, 1, n, f) == n;
        for (size_t i = n; ok && i < padded; ++i) ok = fputc(' ', f) != EOF;
        if (binary) ok = ok && fwrite(data + rest_at, 1, size - rest_at, f) == size - rest_at;
        ok = (fclose(f) == 0) && ok;
    } else {
        ok = false;
    }
    cJSON_free(text);
    free(data);
    return ok;
}

prt_status prt_mesh_export(const char *path, const prt_mesh_export_desc *d)
{
    if (!path || !d || !d->positions || !d->indices || !d->rgb || !d->vertex_count || !d->triangle_count)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: path, positions, indices, colours and counts are required");
    if (d->vertex_count > UINT32_MAX || d->triangle_count > UINT32_MAX / 3) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: too large");
    for (size_t i = 0; i < d->triangle_count * 3; ++i)
        if (d->indices[i] >= d->vertex_count) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: index %u out of range", d->indices[i]);
    /* glTF allows no NaN or infinity in an accessor, and NORMAL only unit vectors. */
    if (!prt__all_finite(d->positions, d->vertex_count * 3)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: a position is not finite");
    for (size_t v = 0; d->normals && v < d->vertex_count; ++v) {
        float n[3] = {d->normals[v * 3], d->normals[v * 3 + 1], d->normals[v * 3 + 2]};
        if (!prt__v3_normalize(n)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: the normal of vertex %zu is not a direction", v);
    }
    const char *ext = strrchr(path, '.'), *format = NULL;
    bool gltf = false;
    if (ext && !strcasecmp(ext, ".glb")) { format = "glb2"; gltf = true; }
    else if (ext && !strcasecmp(ext, ".gltf")) { format = "gltf2"; gltf = true; }
    else if (ext && !strcasecmp(ext, ".ply")) format = "plyb";
    else if (ext && !strcasecmp(ext, ".obj")) format = "obj";
    else return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: '%s' is not .glb, .gltf, .ply or .obj", path);
    if (d->attribute_count < 0 || d->attribute_count > 7 || (d->attribute_count && (!d->attributes || !d->attribute_names)))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: 0 to 7 custom attributes, with their data and names");
    if (d->attribute_count && !gltf) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: custom attributes need glTF (.glb or .gltf)");
    for (int k = 0; k < d->attribute_count; ++k) {
        if (!valid_attribute_name(d->attribute_names[k]))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: attribute name '%s' is not '_' followed by A-Z, 0-9 or '_' (31 bytes at most)",
                             d->attribute_names[k] ? d->attribute_names[k] : "(null)");
        for (int j = 0; j < k; ++j)
            if (!strcmp(d->attribute_names[j], d->attribute_names[k])) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: attribute '%s' named twice", d->attribute_names[k]);
    }
    if (d->attribute_count && !prt__all_finite(d->attributes, d->vertex_count * 4 * (size_t)d->attribute_count))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: a custom attribute's value is not finite");
    const bool srgb = d->encoding == PRT_COLOURS_SRGB || (d->encoding == PRT_COLOURS_DEFAULT && !gltf);
    const float scale = exp2f(d->exposure_stops);
    if (!isfinite(scale)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: exposure %g is out of range", d->exposure_stops);

    const size_t nv = d->vertex_count, nt = d->triangle_count;
    struct aiVector3D *pos = prt__calloc(nv, sizeof *pos), *nrm = d->normals ? prt__calloc(nv, sizeof *nrm) : NULL;
    struct aiColor4D *col = prt__calloc(nv * (size_t)(1 + d->attribute_count), sizeof *col);
    struct aiFace *faces = prt__calloc(nt, sizeof *faces);
    unsigned *idx = prt__calloc(nt * 3, sizeof *idx);
    if (!pos || (d->normals && !nrm) || !col || !faces || !idx) {
        free(pos); free(nrm); free(col); free(faces); free(idx);
        return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory exporting '%s'", path);
    }
    for (size_t v = 0; v < nv; ++v) {
        pos[v] = (struct aiVector3D){d->positions[v * 3], d->positions[v * 3 + 1], d->positions[v * 3 + 2]};
        if (nrm) {   /* unit length, as glTF's NORMAL must be (checked above) */
            float n[3] = {d->normals[v * 3], d->normals[v * 3 + 1], d->normals[v * 3 + 2]};
            prt__v3_normalize(n);
            nrm[v] = (struct aiVector3D){n[0], n[1], n[2]};
        }
        float c[3];
        for (int k = 0; k < 3; ++k) {
            float x = d->rgb[v * 3 + k] * scale;
            x = isfinite(x) ? fminf(fmaxf(x, 0.0f), 1.0f) : 0.0f;
            c[k] = srgb ? srgb_encode(x) : x;
        }
        col[v] = (struct aiColor4D){c[0], c[1], c[2], 1.0f};
        for (int k = 0; k < d->attribute_count; ++k) {
            const float *a = d->attributes + (v * (size_t)d->attribute_count + (size_t)k) * 4;
            col[(size_t)(k + 1) * nv + v] = (struct aiColor4D){a[0], a[1], a[2], a[3]};
        }
    }
    for (size_t t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k) idx[t * 3 + k] = d->indices[t * 3 + k];
        faces[t].mNumIndices = 3;
        faces[t].mIndices = idx + t * 3;
    }
    struct aiMesh mesh;
    memset(&mesh, 0, sizeof mesh);
    mesh.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    mesh.mNumVertices = (unsigned)nv;
    mesh.mNumFaces = (unsigned)nt;
    mesh.mVertices = pos;
    mesh.mNormals = nrm;
    for (int k = 0; k <= d->attribute_count; ++k) mesh.mColors[k] = col + (size_t)k * nv;
    mesh.mFaces = faces;
    memcpy(mesh.mName.data, "prt", 4);
    mesh.mName.length = 3;
    struct aiMesh *meshes[1] = {&mesh};
    struct aiMaterial material;   /* no properties: the colours are the vertices' */
    memset(&material, 0, sizeof material);
    struct aiMaterial *materials[1] = {&material};
    unsigned mesh_index = 0;
    struct aiNode root;
    memset(&root, 0, sizeof root);
    memcpy(root.mName.data, "prt", 4);
    root.mName.length = 3;
    root.mTransformation.a1 = root.mTransformation.b2 = root.mTransformation.c3 = root.mTransformation.d4 = 1;
    root.mNumMeshes = 1;
    root.mMeshes = &mesh_index;
    struct aiScene scene;
    memset(&scene, 0, sizeof scene);
    scene.mRootNode = &root;
    scene.mNumMeshes = 1;
    scene.mMeshes = meshes;
    scene.mNumMaterials = 1;
    scene.mMaterials = materials;

    /* A fresh directory beside the target, so that companions keep the target's base name. */
    char parent[4096], dir[4200], tmp_path[8400];
    snprintf(parent, sizeof parent, "%s", path);
    char *slash = strrchr(parent, '/');
    const char *base = slash ? slash + 1 : path;
    if (slash) *slash = 0;
    else snprintf(parent, sizeof parent, ".");
    snprintf(dir, sizeof dir, "%s/.%s.tmp.%ld", parent, base, (long)getpid());
    prt_status st = PRT_OK;
    if (mkdir(dir, 0777) != 0) st = prt__fail(NULL, PRT_ERR_IO, "cannot write beside '%s': %s", path, strerror(errno));
    if (!st) {
        snprintf(tmp_path, sizeof tmp_path, "%s/%s", dir, base);
        if (aiExportScene(&scene, format, tmp_path, 0) != aiReturn_SUCCESS)
            st = prt__fail(NULL, PRT_ERR_IO, "assimp could not write '%s': %s", path, aiGetErrorString());
        else if (gltf && !finish_gltf(tmp_path, !strcmp(format, "glb2"), d->attribute_count, d->attribute_names))
            st = prt__fail(NULL, PRT_ERR_IO, "cannot rewrite the JSON of '%s' that assimp wrote (unreadable, or without its asset%s)", path,
                           d->attribute_count ? " or the colour sets of the custom attributes" : "");
        else if (!move_out(dir, parent))
            st = prt__fail(NULL, PRT_ERR_IO, "cannot move '%s' into place: %s", path, strerror(errno));
        if (st) remove_dir(dir);
    }
    free(pos); free(nrm); free(col); free(faces); free(idx);
    return st;
}
