/* Mesh import through assimp's C API. Assimp triangulates, flattens the node hierarchy and
 * generates smooth normals split at the crease angle where the file has none; prt then takes
 * per-material diffuse albedo and hands everything to prt__mesh_clean. */
#include "geom/mesh.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>

static void material_albedo(const struct aiMaterial *mat, const prt_scene_desc *desc, float out[3])
{
    memcpy(out, desc->default_albedo, 3 * sizeof(float));
    if (!mat || desc->override_albedo) return;
    struct aiString name;
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) == 0)
        return;  /* assimp's stand-in for "no material": keep prt's default */
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS ||
        aiGetMaterialColor(mat, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS) {
        out[0] = c.r; out[1] = c.g; out[2] = c.b;
    }
}

prt_status prt__import_mesh(const prt_context *ctx, const char *path, const float *xform,
                            const float *albedo_override, const prt_scene_desc *desc, prt__mesh *m)
{
    FILE *probe = fopen(path, "rb");
    if (!probe) return prt__fail(ctx, PRT_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    fclose(probe);

    struct aiPropertyStore *props = aiCreatePropertyStore();
    aiSetImportPropertyFloat(props, AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, desc->crease_angle_deg);
    /* Points and lines are dropped; only triangles take part in transport. */
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    unsigned flags = aiProcess_Triangulate | aiProcess_GenSmoothNormals | aiProcess_JoinIdenticalVertices |
                     aiProcess_PreTransformVertices | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
    const struct aiScene *sc = aiImportFileExWithProperties(path, flags, NULL, props);
    aiReleasePropertyStore(props);
    if (!sc) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s' is not a mesh prt can read: %s", path, aiGetErrorString());
    if (sc->mNumMeshes == 0) {
        aiReleaseImport(sc);
        return prt__fail(ctx, PRT_ERR_EMPTY, "'%s' holds no triangle meshes", path);
    }

    /* Normals transform by the inverse transpose of the linear part. */
    float nmat[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    if (xform) {
        const float *a = xform;  /* row-major 4x4 */
        float c00 = a[5] * a[10] - a[6] * a[9], c01 = a[6] * a[8] - a[4] * a[10], c02 = a[4] * a[9] - a[5] * a[8];
        float c10 = a[2] * a[9] - a[1] * a[10], c11 = a[0] * a[10] - a[2] * a[8], c12 = a[1] * a[8] - a[0] * a[9];
        float c20 = a[1] * a[6] - a[2] * a[5], c21 = a[2] * a[4] - a[0] * a[6], c22 = a[0] * a[5] - a[1] * a[4];
        float cof[9] = {c00, c01, c02, c10, c11, c12, c20, c21, c22};  /* cofactor matrix = det * inverse^T */
        memcpy(nmat, cof, sizeof cof);
    }

    prt_status st = PRT_OK;
    size_t before = m->triangle_count;
    for (unsigned i = 0; i < sc->mNumMeshes && st == PRT_OK; ++i) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || am->mNumFaces == 0) continue;
        float rgb[3];
        if (albedo_override) memcpy(rgb, albedo_override, sizeof rgb);
        else material_albedo(am->mMaterialIndex < sc->mNumMaterials ? sc->mMaterials[am->mMaterialIndex] : NULL, desc, rgb);
        size_t nv = am->mNumVertices, nt = 0;
        float *pos = prt__calloc(nv * 3, sizeof(float)), *nrm = prt__calloc(nv * 3, sizeof(float));
        uint32_t *idx = prt__calloc((size_t)am->mNumFaces * 3, sizeof(uint32_t));
        if (!pos || !nrm || !idx) {
            free(pos); free(nrm); free(idx);
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory importing '%s'", path);
            break;
        }
        for (size_t v = 0; v < nv; ++v) {
            float p[3] = {am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z};
            float n[3] = {0, 0, 0};
            if (am->mNormals) { n[0] = am->mNormals[v].x; n[1] = am->mNormals[v].y; n[2] = am->mNormals[v].z; }
            for (int r = 0; r < 3; ++r) {
                pos[v * 3 + r] = xform ? xform[r * 4] * p[0] + xform[r * 4 + 1] * p[1] + xform[r * 4 + 2] * p[2] + xform[r * 4 + 3] : p[r];
                nrm[v * 3 + r] = nmat[r * 3] * n[0] + nmat[r * 3 + 1] * n[1] + nmat[r * 3 + 2] * n[2];
            }
            if (xform) prt__v3_normalize(nrm + v * 3);  /* a zero normal stays zero: "recompute" */
        }
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const struct aiFace *face = &am->mFaces[f];
            if (face->mNumIndices != 3) continue;
            memcpy(idx + nt * 3, face->mIndices, 3 * sizeof(uint32_t));
            nt++;
        }
        st = prt__mesh_append(m, pos, nrm, NULL, rgb, nv, idx, nt);
        free(pos); free(nrm); free(idx);
    }
    aiReleaseImport(sc);
    if (st == PRT_OK && m->triangle_count == before)
        return prt__fail(ctx, PRT_ERR_EMPTY, "'%s' holds no triangles", path);
    return st;
}
