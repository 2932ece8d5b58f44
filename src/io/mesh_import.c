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

typedef struct corner_key { uint64_t hash; uint32_t face; } corner_key;
static int by_corner_hash(const void *a, const void *b)
{
    const corner_key *x = a, *y = b;
    if (x->hash != y->hash) return x->hash < y->hash ? -1 : 1;
    return x->face < y->face ? -1 : x->face > y->face;
}

static uint32_t find_root(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

/* Which triangles to flip. Per connected piece (triangles joined through shared positions): one
 * that is nearly closed (under 5% of its edges open) and wound inwards (negative signed volume
 * about its own centre) is an object whose winding is reversed - unless another piece has a
 * vertex inside its bounding box: then it is an enclosure (a room, whose walls face inwards on
 * purpose), and it is kept. Returns a flag per triangle (in file order over the meshes), or NULL
 * when nothing is to be flipped; counts what was decided. */
static uint8_t *inside_out_triangles(const struct aiScene *sc, const float *inside, size_t inside_count, size_t *flipped, size_t *kept)
{
    *flipped = *kept = 0;
    size_t nf = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; ++i) nf += sc->mMeshes[i]->mNumFaces;
    if (!nf || nf > UINT32_MAX / 3) return NULL;
    const struct aiVector3D **corner = malloc(nf * 3 * sizeof *corner);
    corner_key *keys = malloc(nf * 3 * sizeof *keys);
    uint32_t *parent = malloc(nf * sizeof *parent);
    uint64_t *edges = malloc(nf * 3 * 2 * sizeof *edges);
    uint8_t *tri = calloc(nf, 1), *flip = NULL;
    double (*piece)[12] = NULL;   /* signed volume, |volume|, edges, open edges, box lo[3], hi[3], centre sum... */
    double (*centre)[4] = NULL;
    bool ok = corner && keys && parent && edges && tri;
    size_t f = 0;
    for (unsigned i = 0; ok && i < sc->mNumMeshes; ++i) {
        const struct aiMesh *am = sc->mMeshes[i];
        for (unsigned k = 0; k < am->mNumFaces; ++k, ++f) {
            parent[f] = (uint32_t)f;
            const struct aiFace *face = &am->mFaces[k];
            tri[f] = face->mNumIndices == 3;
            for (int c = 0; c < 3; ++c) {
                corner[f * 3 + c] = tri[f] ? &am->mVertices[face->mIndices[c]] : NULL;
                keys[f * 3 + c] = (corner_key){tri[f] ? hash_pos(corner[f * 3 + c]) : 0, (uint32_t)f};
            }
        }
    }
    if (ok) {
        /* Triangles sharing a position are one piece. */
        qsort(keys, nf * 3, sizeof *keys, by_corner_hash);
        for (size_t k = 1; k < nf * 3; ++k)
            if (keys[k].hash == keys[k - 1].hash && tri[keys[k].face] && tri[keys[k - 1].face]) {
                uint32_t a = find_root(parent, keys[k].face), b = find_root(parent, keys[k - 1].face);
                if (a != b) parent[a < b ? b : a] = a < b ? a : b;
            }
        for (size_t t = 0; t < nf; ++t) parent[t] = find_root(parent, (uint32_t)t);
        piece = calloc(nf, sizeof *piece);
        centre = calloc(nf, sizeof *centre);
        ok = piece && centre;
    }
    if (ok) {
        for (size_t t = 0; t < nf; ++t) {
            if (!tri[t]) continue;
            double *c = centre[parent[t]], *q = piece[parent[t]];
            if (c[3] == 0) for (int a = 0; a < 3; ++a) { q[4 + a] = INFINITY; q[7 + a] = -INFINITY; }
            for (int k = 0; k < 3; ++k) {
                const struct aiVector3D *p = corner[t * 3 + k];
                const double v[3] = {p->x, p->y, p->z};
                for (int a = 0; a < 3; ++a) { c[a] += v[a]; q[4 + a] = fmin(q[4 + a], v[a]); q[7 + a] = fmax(q[7 + a], v[a]); }
                c[3] += 1;
            }
        }
        size_t e = 0;
        for (size_t t = 0; t < nf; ++t) {
            if (!tri[t]) continue;
            double *q = piece[parent[t]];
            const double *c = centre[parent[t]];
            double r[3][3];
            for (int k = 0; k < 3; ++k) {
                const struct aiVector3D *p = corner[t * 3 + k];
                r[k][0] = p->x - c[0] / c[3]; r[k][1] = p->y - c[1] / c[3]; r[k][2] = p->z - c[2] / c[3];
            }
            const double v = (r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0]) +
                              r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0])) / 6.0;
            q[0] += v;
            q[1] += fabs(v);
            for (int k = 0; k < 3; ++k) {
                uint64_t a = hash_pos(corner[t * 3 + k]), b = hash_pos(corner[t * 3 + (k + 1) % 3]);
                edges[e++] = a < b ? a * 31 + b : b * 31 + a;   /* the same for both directions */
                edges[e++] = parent[t];
            }
            q[2] += 3;
        }
        /* Open edges: those that occur once (pairs sorted by key; the piece rides along). */
        qsort(edges, e / 2, 2 * sizeof *edges, cmp_u64);
        for (size_t i = 0; i < e;) {
            size_t j = i;
            while (j < e && edges[j] == edges[i]) j += 2;
            if (j - i == 2) piece[edges[i + 1]][3] += 1;
            i = j;
        }
        /* Candidates: nearly closed, wound inwards. */
        for (size_t r = 0; r < nf; ++r) {
            double *q = piece[r];
            q[10] = centre[r][3] > 0 && q[2] > 0 && q[3] * 20 < q[2] && q[0] < -0.5 * q[1];
        }
        /* An enclosure holds another piece's vertex inside its box (candidates are few: a scene
         * of many closed props has them wound the same way, and a few enclosures at most). */
        uint32_t *cand = malloc(nf * sizeof *cand);
        size_t ncand = 0;
        for (size_t r = 0; cand && r < nf; ++r)
            if (piece[r][10] == 1) cand[ncand++] = (uint32_t)r;
        for (size_t t = 0; cand && t < nf && ncand; ++t) {
            if (!tri[t]) continue;
            for (int k = 0; k < 3; ++k) {
                const struct aiVector3D *p = corner[t * 3 + k];
                for (size_t i = 0; i < ncand; ++i) {
                    double *q = piece[cand[i]];
                    if (cand[i] == parent[t] || q[10] != 1) continue;
                    if (p->x > q[4] && p->x < q[7] && p->y > q[5] && p->y < q[8] && p->z > q[6] && p->z < q[9]) q[10] = 2;
                }
            }
        }
        /* So does one around a light (in the file's own frame, as `inside` is given). */
        for (size_t i = 0; cand && i < ncand; ++i)
            for (size_t k = 0; k < inside_count; ++k) {
                double *q = piece[cand[i]];
                const float *p = inside + k * 3;
                if (p[0] > q[4] && p[0] < q[7] && p[1] > q[5] && p[1] < q[8] && p[2] > q[6] && p[2] < q[9]) q[10] = 2;
            }
        free(cand);
        for (size_t r = 0; r < nf; ++r) {
            *flipped += piece[r][10] == 1;
            *kept += piece[r][10] == 2;
        }
        if (*flipped && (flip = calloc(nf, 1)))
            for (size_t t = 0; t < nf; ++t) flip[t] = tri[t] && piece[parent[t]][10] == 1;
    }
    free(corner); free(keys); free(parent); free(edges); free(tri); free(piece); free(centre);
    return flip;
}

/* Everything prt__import_mesh needs, as the child process sees it. */
typedef struct import_job {
    const char *path;
    const float *xform, *albedo_override;
    const prt_scene_desc *desc;
    const float *inside;     /* points inside the scene's rooms (its lights), world space */
    size_t inside_count;
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
    /* Into world space without joining meshes that share a material: objects without materials
     * (OBJ's "o plane", "o blocker") would otherwise become one surface under the last name. */
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_PTV_KEEP_HIERARCHY, 1);
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
    bool flip = desc->winding == PRT_WINDING_FLIP;
    size_t pieces_flipped = 0, pieces_kept = 0;
    uint8_t *flip_tri = NULL;
    if (desc->winding == PRT_WINDING_AUTO && !file_normals) {
        /* The lights into the file's frame: p = A^-1 (w - t) for the row-major affine xform. */
        float *local = job->inside_count ? malloc(job->inside_count * 3 * sizeof *local) : NULL;
        size_t nlocal = 0;
        for (size_t k = 0; local && k < job->inside_count; ++k) {
            const float *w = job->inside + k * 3, *a = xform;
            float d[3] = {w[0], w[1], w[2]};
            if (!a) { memcpy(local + nlocal++ * 3, d, sizeof d); continue; }
            for (int c = 0; c < 3; ++c) d[c] -= a[c * 4 + 3];
            /* Cramer's rule: the columns of A are the images of the file's axes. */
            const double det = (double)a[0] * (a[5] * a[10] - a[6] * a[9]) - (double)a[1] * (a[4] * a[10] - a[6] * a[8]) + (double)a[2] * (a[4] * a[9] - a[5] * a[8]);
            if (!(fabs(det) > 1e-30)) continue;
            for (int c = 0; c < 3; ++c) {
                double m[9];
                for (int r = 0; r < 3; ++r)
                    for (int q = 0; q < 3; ++q) m[r * 3 + q] = q == c ? d[r] : a[r * 4 + q];
                local[nlocal * 3 + c] = (float)((m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6])) / det);
            }
            nlocal++;
        }
        flip_tri = inside_out_triangles(sc, local, nlocal, &pieces_flipped, &pieces_kept);
        free(local);
        flip = flip_tri != NULL;
    }
    if (flip) {
        /* The scene belongs to us until aiReleaseImport; assimp's C API only hands it out const. */
        struct aiScene *msc = (struct aiScene *)sc;
        size_t face = 0;
        for (unsigned i = 0; i < msc->mNumMeshes; ++i) {
            struct aiMesh *am = msc->mMeshes[i];
            for (unsigned f = 0; f < am->mNumFaces; ++f, ++face)
                if (am->mFaces[f].mNumIndices == 3 && (!flip_tri || flip_tri[face])) {
                    unsigned t = am->mFaces[f].mIndices[1];
                    am->mFaces[f].mIndices[1] = am->mFaces[f].mIndices[2];
                    am->mFaces[f].mIndices[2] = t;
                }
            if (am->mNormals && !flip_tri)   /* an automatic flip only happens without file normals */
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

    free(flip_tri);
    /* What the winding check decided travels in the flags: counts of pieces flipped and kept. */
    const uint32_t nflip = pieces_flipped < 0xFFF ? (uint32_t)pieces_flipped : 0xFFF, nkept = pieces_kept < 0xFFF ? (uint32_t)pieces_kept : 0xFFF;
    prt__mesh_message_begin(out, PRT_OK, (nflip ? PRT__IMPORT_FLIPPED : 0) | (nkept ? PRT__IMPORT_KEPT_ENCLOSURE : 0) | nflip << 8 | nkept << 20, NULL);
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

prt_status prt__import_mesh(const prt_context *ctx, const char *path, const float *xform, const float *albedo_override,
                            const float *inside, size_t inside_count, const prt_scene_desc *desc, prt__mesh *m)
{
    FILE *probe = fopen(path, "rb");
    if (!probe) return prt__fail(ctx, PRT_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    fclose(probe);
    import_job job = {path, xform, albedo_override, desc, inside, inside_count};
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
    const unsigned nflip = (flags >> 8) & 0xFFF, nkept = (flags >> 20) & 0xFFF;
    if (!st && (flags & PRT__IMPORT_FLIPPED))
        prt__log(ctx, PRT_LOG_WARN, "%s: %u closed piece%s wound clockwise with nothing inside (an object seen from outside, normals pointing in): "
                 "flipped (--winding keep to prevent)", path, nflip, nflip == 1 ? "" : "s");
    if (!st && (flags & PRT__IMPORT_KEPT_ENCLOSURE))
        prt__log(ctx, PRT_LOG_INFO, "%s: %u closed piece%s wound clockwise around other geometry, a light or the camera (a room seen from inside): kept as %s "
                 "(--winding flip to flip)", path, nkept, nkept == 1 ? "" : "s", nkept == 1 ? "it is" : "they are");
    return st;
}
