/* Mesh import through assimp's C API, in a child process (io/isolate.h): assimp can loop or
 * abort on malformed files. Assimp triangulates, flattens the node hierarchy and generates
 * smooth normals split at the crease angle where the file has none; the child takes per-material
 * diffuse albedo and emission and hands everything back as a mesh message (io/mesh_message.h),
 * which the caller validates and later cleans (prt__mesh_clean). */
#include "geom/mesh.h"
#include "io/isolate.h"
#include "io/mesh_message.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <dirent.h>
#include <sys/stat.h>

/* PLY and STL have no materials; assimp's readers invent a white one, which would make a
 * scanned mesh a perfect reflector. Such files get the default albedo. */
static bool format_has_materials(const char *path)
{
    const char *ext = strrchr(path, '.');
    return !(ext && (!strcasecmp(ext, ".ply") || !strcasecmp(ext, ".stl")));
}

static void material_albedo(const struct aiMaterial *mat, const prt_scene_desc *desc, bool has_materials, float out[3])
{
    memcpy(out, desc->default_albedo, 3 * sizeof(float));
    if (!mat || desc->override_albedo || !has_materials) return;
    struct aiString name;
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) == 0)
        return;  /* assimp's stand-in for "no material": keep prt's default */
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS ||
        aiGetMaterialColor(mat, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS) {
        out[0] = c.r; out[1] = c.g; out[2] = c.b;
    }
}

/* What a part is called: its material's name (assimp's stand-in for "no material" is none),
 * else the mesh's own name; NULL for formats without materials (PLY, STL). */
static const char *surface_name(const struct aiMaterial *mat, const struct aiMesh *am, bool has_materials)
{
    static struct aiString name;
    if (!has_materials) return NULL;
    if (mat && aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && name.length && strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) != 0)
        return name.data;
    return am->mName.length ? am->mName.data : NULL;
}

/* Emitted radiance of a material: Ke in MTL, emissiveFactor in glTF (assimp maps both to the
 * emissive colour), times the emissive strength where the file gives one. */
static void material_emission(const struct aiMaterial *mat, bool has_materials, float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    if (!mat || !has_materials) return;
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, AI_MATKEY_COLOR_EMISSIVE, &c) != aiReturn_SUCCESS) return;
    ai_real strength = 1;
    unsigned one = 1;
    if (aiGetMaterialFloatArray(mat, AI_MATKEY_EMISSIVE_INTENSITY, &strength, &one) != aiReturn_SUCCESS || one != 1) strength = 1;
    out[0] = c.r * strength; out[1] = c.g * strength; out[2] = c.b * strength;
}

typedef struct edge_key { uint64_t key; } edge_key;

static uint64_t hash_pos(const struct aiVector3D *p)
{
    uint32_t b[3];
    memcpy(&b[0], &p->x, 4); memcpy(&b[1], &p->y, 4); memcpy(&b[2], &p->z, 4);
    uint64_t h = 1469598103934665603ULL;
    for (int i = 0; i < 3; ++i) { h ^= b[i]; h *= 1099511628211ULL; h ^= h >> 29; }
    return h;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* True when the file's triangles, taken together, form a nearly closed surface (under 5% of
 * edges, matched by position, are open) whose counter-clockwise normals point inwards. */
static bool looks_inside_out(const struct aiScene *sc)
{
    double c[3] = {0, 0, 0};
    size_t nv = 0, ne = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; ++i) {
        const struct aiMesh *am = sc->mMeshes[i];
        for (unsigned v = 0; v < am->mNumVertices; ++v, ++nv) { c[0] += am->mVertices[v].x; c[1] += am->mVertices[v].y; c[2] += am->mVertices[v].z; }
        ne += (size_t)am->mNumFaces * 3;
    }
    if (!nv || !ne) return false;
    for (int k = 0; k < 3; ++k) c[k] /= (double)nv;
    uint64_t *edges = malloc(ne * sizeof *edges);
    if (!edges) return false;
    double vol = 0, absvol = 0;
    size_t e = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; ++i) {
        const struct aiMesh *am = sc->mMeshes[i];
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const struct aiFace *face = &am->mFaces[f];
            if (face->mNumIndices != 3) continue;
            const struct aiVector3D *p[3];
            double q[3][3];
            for (int k = 0; k < 3; ++k) {
                p[k] = &am->mVertices[face->mIndices[k]];
                q[k][0] = p[k]->x - c[0]; q[k][1] = p[k]->y - c[1]; q[k][2] = p[k]->z - c[2];
            }
            double t = (q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
                        q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0])) / 6.0;
            vol += t;
            absvol += fabs(t);
            for (int k = 0; k < 3; ++k) {
                uint64_t a = hash_pos(p[k]), b = hash_pos(p[(k + 1) % 3]);
                edges[e++] = a < b ? a * 31 + b : b * 31 + a;   /* the same for both directions */
            }
        }
    }
    qsort(edges, e, sizeof *edges, cmp_u64);
    size_t open = 0;
    for (size_t i = 0; i < e;) {
        size_t j = i;
        while (j < e && edges[j] == edges[i]) ++j;
        open += j - i == 1;
        i = j;
    }
    free(edges);
    return e > 0 && open * 20 < e && vol < -0.5 * absvol;
}

/* Everything prt__import_mesh needs, as the child process sees it. */
typedef struct import_job {
    const char *path;
    const float *xform, *albedo_override;
    const prt_scene_desc *desc;
} import_job;

static void fail_message(prt__bytes *out, prt_status st, const char *fmt, const char *path, const char *why)
{
    char msg[1024];
    snprintf(msg, sizeof msg, fmt, path, why ? why : "");
    for (char *p = msg; *p; ++p)   /* assimp's messages may hold newlines: errors are one line */
        if ((unsigned char)*p < 0x20 || *p == 0x7f) *p = ' ';
    prt__mesh_message_begin(out, st, 0, msg);
}

/* The assimp side of an import: the file's triangles as a mesh message (io/mesh_message.h).
 * Runs in a child process unless the caller asked otherwise. */
static void import_with_assimp(void *arg, prt__bytes *out)
{
    const import_job *job = arg;
    const char *path = job->path;
    const float *xform = job->xform;
    const prt_scene_desc *desc = job->desc;
    struct aiPropertyStore *props = aiCreatePropertyStore();
    aiSetImportPropertyFloat(props, AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, desc->crease_angle_deg);
    /* Points and lines are dropped; only triangles take part in transport. */
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    unsigned flags = aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType | aiProcess_ValidateDataStructure;
    const struct aiScene *sc = aiImportFileExWithProperties(path, flags, NULL, props);
    aiReleasePropertyStore(props);
    if (!sc) { fail_message(out, PRT_ERR_FORMAT, "'%s' is not a mesh prt can read: %s", path, aiGetErrorString()); return; }
    if (sc->mNumMeshes == 0) {
        aiReleaseImport(sc);
        fail_message(out, PRT_ERR_EMPTY, "'%s' holds no triangle meshes%s", path, NULL);
        return;
    }
    /* Orientation is settled before normals are generated from the winding. */
    bool file_normals = false;
    for (unsigned i = 0; i < sc->mNumMeshes; ++i) file_normals |= sc->mMeshes[i]->mNormals != NULL;
    bool flip = desc->winding == PRT_WINDING_FLIP, flipped_auto = false;
    if (desc->winding == PRT_WINDING_AUTO && !file_normals && looks_inside_out(sc)) flip = flipped_auto = true;
    if (flip) {
        /* The scene belongs to us until aiReleaseImport; assimp's C API only hands it out const. */
        struct aiScene *msc = (struct aiScene *)sc;
        for (unsigned i = 0; i < msc->mNumMeshes; ++i) {
            struct aiMesh *am = msc->mMeshes[i];
            for (unsigned f = 0; f < am->mNumFaces; ++f)
                if (am->mFaces[f].mNumIndices == 3) {
                    unsigned t = am->mFaces[f].mIndices[1];
                    am->mFaces[f].mIndices[1] = am->mFaces[f].mIndices[2];
                    am->mFaces[f].mIndices[2] = t;
                }
            if (am->mNormals)
                for (unsigned v = 0; v < am->mNumVertices; ++v) {
                    am->mNormals[v].x = -am->mNormals[v].x; am->mNormals[v].y = -am->mNormals[v].y; am->mNormals[v].z = -am->mNormals[v].z;
                }
        }
    }
    sc = aiApplyPostProcessing(sc, aiProcess_GenSmoothNormals | aiProcess_JoinIdenticalVertices);
    if (!sc) { fail_message(out, PRT_ERR_FORMAT, "'%s': assimp post-processing failed: %s", path, aiGetErrorString()); return; }

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

    prt__mesh_message_begin(out, PRT_OK, flipped_auto ? PRT__IMPORT_FLIPPED : 0, NULL);
    for (unsigned i = 0; i < sc->mNumMeshes; ++i) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) || am->mNumFaces == 0) continue;
        const struct aiMaterial *mat = am->mMaterialIndex < sc->mNumMaterials ? sc->mMaterials[am->mMaterialIndex] : NULL;
        float rgb[3], le[3];
        if (job->albedo_override) memcpy(rgb, job->albedo_override, sizeof rgb);
        else material_albedo(mat, desc, format_has_materials(path), rgb);
        material_emission(mat, format_has_materials(path), le);
        size_t nv = am->mNumVertices, nt = 0;
        float *pos = prt__calloc(nv * 3, sizeof(float)), *nrm = prt__calloc(nv * 3, sizeof(float));
        float *uv = am->mTextureCoords[0] ? prt__calloc(nv * 2, sizeof(float)) : NULL;
        uint32_t *idx = prt__calloc((size_t)am->mNumFaces * 3, sizeof(uint32_t));
        if (!pos || !nrm || !idx || (am->mTextureCoords[0] && !uv)) {
            free(pos); free(nrm); free(uv); free(idx);
            out->failed = true;
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
            if (uv) { uv[v * 2] = am->mTextureCoords[0][v].x; uv[v * 2 + 1] = am->mTextureCoords[0][v].y; }
        }
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const struct aiFace *face = &am->mFaces[f];
            if (face->mNumIndices != 3) continue;
            memcpy(idx + nt * 3, face->mIndices, 3 * sizeof(uint32_t));
            nt++;
        }
        prt__mesh_message_part(out, surface_name(mat, am, format_has_materials(path)), rgb, le, nv, pos, nrm, uv, nt, idx);
        free(pos); free(nrm); free(uv); free(idx);
    }
    aiReleaseImport(sc);
}

/* Bytes the import reads: the file, and for a .gltf the files beside it (its external buffers). */
static double input_bytes(const char *path)
{
    struct stat sb;
    double bytes = stat(path, &sb) == 0 ? (double)sb.st_size : 0.0;
    const char *ext = strrchr(path, '.');
    if (!ext || strcasecmp(ext, ".gltf") != 0) return bytes;
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash) *slash = 0;
    else snprintf(dir, sizeof dir, ".");
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        char full[8192];
        snprintf(full, sizeof full, "%s/%s", dir, e->d_name);
        if (e->d_name[0] != '.' && stat(full, &sb) == 0 && S_ISREG(sb.st_mode) && strcmp(full, path) != 0) bytes += (double)sb.st_size;
    }
    if (d) closedir(d);
    return bytes;
}

/* Default time limit: generous for assimp's slowest readers on real files (tens of MB/s). */
static double import_seconds(double bytes, const prt_scene_desc *desc)
{
    return desc->import_seconds > 0 ? desc->import_seconds : 60.0 + 10.0 * bytes / 1e6;
}

/* What the child may hand back: a mesh message holds at most ~40 bytes a vertex and 12 a
 * triangle, and no format spends less than a few bytes of file on either; 256 MB for small files. */
static size_t import_max_bytes(double bytes)
{
    double cap = 256e6 + 100.0 * bytes;
    return cap >= (double)SIZE_MAX ? SIZE_MAX : (size_t)cap;
}

prt_status prt__import_mesh(const prt_context *ctx, const char *path, const float *xform,
                            const float *albedo_override, const prt_scene_desc *desc, prt__mesh *m)
{
    FILE *probe = fopen(path, "rb");
    if (!probe) return prt__fail(ctx, PRT_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    fclose(probe);
    import_job job = {path, xform, albedo_override, desc};
    prt__bytes msg = {0};
    prt_status st = PRT_OK;
    if (desc->import_in_process) {
        import_with_assimp(&job, &msg);
        if (msg.failed) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory importing '%s'", path);
    } else {
        char what[600];
        snprintf(what, sizeof what, "assimp reading '%s'", path);
        const double bytes = input_bytes(path);
        st = prt__run_isolated(ctx, import_with_assimp, &job, import_seconds(bytes, desc), import_max_bytes(bytes), what, &msg);
    }
    uint32_t flags = 0;
    if (!st) st = prt__mesh_message_read(ctx, msg.data, msg.size, path, &flags, m);
    prt__bytes_free(&msg);
    if (!st && (flags & PRT__IMPORT_FLIPPED))
        prt__log(ctx, PRT_LOG_WARN, "%s: closed mesh wound clockwise (normals would point inwards); flipped it (--winding keep to prevent)", path);
    return st;
}
