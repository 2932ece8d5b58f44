/* Meshes with vertex colours out through assimp's exporters: prt builds the aiScene itself (one
 * mesh, one node, an empty material) and lets assimp write glTF 2.0, PLY or OBJ. Exporters write
 * their main file and its companions (.bin, .mtl) by name, so they write into a fresh directory
 * beside the target, and each file is renamed into place once all are complete. */
#include "core/internal.h"
#include "prt/image.h"

#include <assimp/cexport.h>
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

prt_status prt_mesh_export(const char *path, const prt_mesh_export_desc *d)
{
    if (!path || !d || !d->positions || !d->indices || !d->rgb || !d->vertex_count || !d->triangle_count)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: path, positions, indices, colours and counts are required");
    if (d->vertex_count > UINT32_MAX || d->triangle_count > UINT32_MAX / 3) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: too large");
    for (size_t i = 0; i < d->triangle_count * 3; ++i)
        if (d->indices[i] >= d->vertex_count) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: index %u out of range", d->indices[i]);
    const char *ext = strrchr(path, '.'), *format = NULL;
    bool gltf = false;
    if (ext && !strcasecmp(ext, ".glb")) { format = "glb2"; gltf = true; }
    else if (ext && !strcasecmp(ext, ".gltf")) { format = "gltf2"; gltf = true; }
    else if (ext && !strcasecmp(ext, ".ply")) format = "plyb";
    else if (ext && !strcasecmp(ext, ".obj")) format = "obj";
    else return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: '%s' is not .glb, .gltf, .ply or .obj", path);
    const bool srgb = d->encoding == PRT_COLOURS_SRGB || (d->encoding == PRT_COLOURS_DEFAULT && !gltf);
    const float scale = exp2f(d->exposure_stops);
    if (!isfinite(scale)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "mesh export: exposure %g is out of range", d->exposure_stops);

    const size_t nv = d->vertex_count, nt = d->triangle_count;
    struct aiVector3D *pos = prt__calloc(nv, sizeof *pos), *nrm = d->normals ? prt__calloc(nv, sizeof *nrm) : NULL;
    struct aiColor4D *col = prt__calloc(nv, sizeof *col);
    struct aiFace *faces = prt__calloc(nt, sizeof *faces);
    unsigned *idx = prt__calloc(nt * 3, sizeof *idx);
    if (!pos || (d->normals && !nrm) || !col || !faces || !idx) {
        free(pos); free(nrm); free(col); free(faces); free(idx);
        return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory exporting '%s'", path);
    }
    for (size_t v = 0; v < nv; ++v) {
        pos[v] = (struct aiVector3D){d->positions[v * 3], d->positions[v * 3 + 1], d->positions[v * 3 + 2]};
        if (nrm) nrm[v] = (struct aiVector3D){d->normals[v * 3], d->normals[v * 3 + 1], d->normals[v * 3 + 2]};
        float c[3];
        for (int k = 0; k < 3; ++k) {
            float x = d->rgb[v * 3 + k] * scale;
            x = isfinite(x) ? fminf(fmaxf(x, 0.0f), 1.0f) : 0.0f;
            c[k] = srgb ? srgb_encode(x) : x;
        }
        col[v] = (struct aiColor4D){c[0], c[1], c[2], 1.0f};
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
    mesh.mColors[0] = col;
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
        else if (!move_out(dir, parent))
            st = prt__fail(NULL, PRT_ERR_IO, "cannot move '%s' into place: %s", path, strerror(errno));
        if (st) remove_dir(dir);
    }
    free(pos); free(nrm); free(col); free(faces); free(idx);
    return st;
}
