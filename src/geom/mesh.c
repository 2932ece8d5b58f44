/* Mesh building and cleaning: the one place input geometry is validated. */
#include "geom/mesh.h"

#include <string.h>

void prt__mesh_free(prt__mesh *m)
{
    free(m->positions); free(m->normals); free(m->albedo); free(m->material); free(m->uv); free(m->emission); free(m->indices);
    free(m->surface); free(m->surface_names);
    memset(m, 0, sizeof *m);
}

static bool grow(void **p, size_t count, size_t elem)
{
    size_t bytes;
    if (!prt__mul_ok(count, elem, &bytes)) return false;
    void *q = realloc(*p, bytes ? bytes : 1);
    if (!q) return false;
    *p = q;
    return true;
}

prt_status prt__mesh_append(prt__mesh *m, const float *pos, const float *nrm, const float *albedo,
                            const float rgb_default[3], size_t nv, const uint32_t *idx, size_t nt)
{
    size_t v0 = m->vertex_count, t0 = m->triangle_count, nv2 = v0 + nv, nt2 = t0 + nt;
    if (nv2 > UINT32_MAX || nt2 > UINT32_MAX / 3)
        return prt__fail(NULL, PRT_ERR_NO_MEMORY, "mesh too large (%zu vertices)", nv2);
    if (!grow((void **)&m->positions, nv2 * 3, sizeof(float)) || !grow((void **)&m->normals, nv2 * 3, sizeof(float)) ||
        !grow((void **)&m->albedo, nv2 * 3, sizeof(float)) || !grow((void **)&m->material, nv2, 1) || !grow((void **)&m->uv, nv2 * 2, sizeof(float)) || !grow((void **)&m->indices, nt2 * 3, sizeof(uint32_t)) || !grow((void **)&m->surface, nv2, sizeof(uint16_t)) ||
        (m->emission && !grow((void **)&m->emission, nv2 * 3, sizeof(float))))
        return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory growing mesh");
    memcpy(m->positions + v0 * 3, pos, nv * 3 * sizeof(float));
    if (nrm) memcpy(m->normals + v0 * 3, nrm, nv * 3 * sizeof(float));
    else memset(m->normals + v0 * 3, 0, nv * 3 * sizeof(float));
    memset(m->material + v0, 0, nv);
    memset(m->surface + v0, 0, nv * sizeof(uint16_t));
    if (m->emission) memset(m->emission + v0 * 3, 0, nv * 3 * sizeof(float));
    for (size_t i = 0; i < nv * 2; ++i) m->uv[v0 * 2 + i] = NAN;
    for (size_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) m->albedo[(v0 + i) * 3 + c] = albedo ? albedo[i * 3 + c] : rgb_default[c];
    for (size_t i = 0; i < nt * 3; ++i) {
        if (idx[i] >= nv)
            return prt__fail(NULL, PRT_ERR_FORMAT, "triangle %zu references vertex %u of %zu", i / 3, idx[i], nv);
        m->indices[t0 * 3 + i] = (uint32_t)(idx[i] + v0);
    }
    m->vertex_count = nv2;
    m->triangle_count = nt2;
    return PRT_OK;
}

/* A triangle by its corners' positions, turned so that the smallest corner comes first (the
 * winding kept): two faces with equal keys lie on each other, facing the same way. */
typedef struct tri_key { float p[9]; uint32_t t; } tri_key;
static int by_tri_key(const void *x, const void *y)
{
    const tri_key *a = x, *b = y;
    for (int k = 0; k < 9; ++k)
        if (a->p[k] != b->p[k]) return a->p[k] < b->p[k] ? -1 : 1;
    return a->t < b->t ? -1 : a->t > b->t;
}

static int corner_before(const float *a, const float *b)
{
    for (int c = 0; c < 3; ++c)
        if (a[c] != b[c]) return a[c] < b[c];
    return 0;
}

/* Drops triangles lying exactly on an earlier one with the same winding (models exported twice,
 * a box's face pasted over another, as in the Cornell box's OBJ): they double the light a
 * surface gathers and leave edges with four triangles, which no chart or welding can use. Faces
 * back to back (opposite windings) are a two-sided sheet and stay. */
static prt_status drop_duplicates(const prt_context *ctx, prt__mesh *m, float *face_n, const char *what)
{
    const size_t nt = m->triangle_count;
    tri_key *keys = malloc(nt * sizeof *keys + 1);
    uint8_t *drop = prt__calloc(nt + 1, 1);
    if (!keys || !drop) { free(keys); free(drop); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (size_t t = 0; t < nt; ++t) {
        const float *q[3];
        for (int k = 0; k < 3; ++k) q[k] = m->positions + (size_t)m->indices[t * 3 + k] * 3;
        const int first = corner_before(q[1], q[0]) ? (corner_before(q[2], q[1]) ? 2 : 1) : (corner_before(q[2], q[0]) ? 2 : 0);
        for (int k = 0; k < 3; ++k) memcpy(keys[t].p + k * 3, q[(first + k) % 3], 3 * sizeof(float));
        keys[t].t = (uint32_t)t;
    }
    qsort(keys, nt, sizeof *keys, by_tri_key);
    size_t dropped = 0;
    for (size_t i = 1; i < nt; ++i) {
        bool same = true;   /* compared as numbers, as sorted: -0 and +0 are one position */
        for (int k = 0; k < 9 && same; ++k) same = keys[i].p[k] == keys[i - 1].p[k];
        if (same) { drop[keys[i].t] = 1; dropped++; }
    }
    if (dropped) {
        size_t kept = 0;
        for (size_t t = 0; t < nt; ++t) {
            if (drop[t]) continue;
            memmove(m->indices + kept * 3, m->indices + t * 3, 3 * sizeof(uint32_t));
            memmove(face_n + kept * 3, face_n + t * 3, 3 * sizeof(float));
            kept++;
        }
        m->triangle_count = kept;
        prt__log(ctx, PRT_LOG_WARN, "%s: dropped %zu triangles lying on others with the same winding", what, dropped);
    }
    free(keys);
    free(drop);
    return PRT_OK;
}

prt_status prt__mesh_clean(const prt_context *ctx, prt__mesh *m, const char *what)
{
    if (m->vertex_count == 0 || m->triangle_count == 0)
        return prt__fail(ctx, PRT_ERR_EMPTY, "%s: the mesh has no triangles", what);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < m->vertex_count * 3; ++i) {
        if (!isfinite(m->positions[i]))
            return prt__fail(ctx, PRT_ERR_FORMAT, "%s: vertex %zu has a non-finite coordinate", what, i / 3);
        if (!isfinite(m->albedo[i]) || m->albedo[i] < 0.0f || m->albedo[i] > 1.0f)
            return prt__fail(ctx, PRT_ERR_FORMAT, "%s: vertex %zu has albedo %g outside [0, 1]", what, i / 3, m->albedo[i]);
        if (m->emission && !(isfinite(m->emission[i]) && m->emission[i] >= 0.0f))
            return prt__fail(ctx, PRT_ERR_FORMAT, "%s: vertex %zu has emission %g (must be finite and >= 0)", what, i / 3, m->emission[i]);
        lo[i % 3] = fminf(lo[i % 3], m->positions[i]);
        hi[i % 3] = fmaxf(hi[i % 3], m->positions[i]);
    }
    float ext[3];
    prt__v3_sub(hi, lo, ext);
    double diag = prt__v3_len(ext);
    /* Triangles whose area is below this are numerically degenerate: their normal is noise. */
    double min_area = 1e-14 * diag * diag;

    size_t kept = 0;
    float *face_n = prt__calloc(m->triangle_count * 3, sizeof(float));
    if (!face_n) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *tri = m->indices + t * 3;
        if (tri[0] >= m->vertex_count || tri[1] >= m->vertex_count || tri[2] >= m->vertex_count) {
            free(face_n);
            return prt__fail(ctx, PRT_ERR_FORMAT, "%s: triangle %zu references a vertex out of range", what, t);
        }
        float e1[3], e2[3], n[3];
        prt__v3_sub(m->positions + tri[1] * 3, m->positions + tri[0] * 3, e1);
        prt__v3_sub(m->positions + tri[2] * 3, m->positions + tri[0] * 3, e2);
        prt__v3_cross(e1, e2, n);   /* length = 2 * area, so this weights normals by area */
        if (!(0.5 * prt__v3_len(n) > min_area) || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
        memmove(m->indices + kept * 3, tri, 3 * sizeof(uint32_t));
        memcpy(face_n + kept * 3, n, sizeof n);
        kept++;
    }
    if (kept == 0) {
        free(face_n);
        return prt__fail(ctx, PRT_ERR_EMPTY, "%s: all %zu triangles have zero area", what, m->triangle_count);
    }
    if (kept < m->triangle_count)
        prt__log(ctx, PRT_LOG_WARN, "%s: dropped %zu zero-area triangles of %zu", what, m->triangle_count - kept, m->triangle_count);
    m->triangle_count = kept;
    prt_status st = drop_duplicates(ctx, m, face_n, what);
    if (st) { free(face_n); return st; }
    kept = m->triangle_count;

    /* Repair normals that are missing (zero), non-finite or not unit: area-weighted average of
     * the faces around the vertex, or the first face's normal if those cancel out. */
    float *acc = prt__calloc(m->vertex_count * 3, sizeof(float));
    uint32_t *remap = prt__calloc(m->vertex_count, sizeof(uint32_t));
    if (!acc || !remap) { free(face_n); free(acc); free(remap); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (size_t t = 0; t < kept; ++t)
        for (int k = 0; k < 3; ++k) {
            uint32_t v = m->indices[t * 3 + k];
            for (int c = 0; c < 3; ++c) acc[v * 3 + c] += face_n[t * 3 + c];
            remap[v] = 1;
        }
    size_t repaired = 0;
    for (size_t v = 0; v < m->vertex_count; ++v) {
        float *n = m->normals + v * 3;
        float len = prt__v3_len(n);
        if (isfinite(len) && fabsf(len - 1.0f) < 1e-3f) { prt__v3_normalize(n); continue; }
        if (!(isfinite(len) && len > 1e-6f && prt__v3_normalize(n))) {
            memcpy(n, acc + v * 3, 3 * sizeof(float));
            if (!prt__v3_normalize(n)) { n[0] = 0; n[1] = 1; n[2] = 0; }
            if (len != 0.0f) repaired++;
        }
    }
    if (repaired) prt__log(ctx, PRT_LOG_WARN, "%s: recomputed %zu invalid vertex normals", what, repaired);

    /* Drop unreferenced vertices (scanned PLYs carry many). */
    size_t nv = 0;
    for (size_t v = 0; v < m->vertex_count; ++v) {
        if (!remap[v]) continue;
        remap[v] = (uint32_t)nv;
        if (nv != v) {
            memcpy(m->positions + nv * 3, m->positions + v * 3, 3 * sizeof(float));
            memcpy(m->normals + nv * 3, m->normals + v * 3, 3 * sizeof(float));
            memcpy(m->albedo + nv * 3, m->albedo + v * 3, 3 * sizeof(float));
            m->material[nv] = m->material[v];
            if (m->surface) m->surface[nv] = m->surface[v];
            memcpy(m->uv + nv * 2, m->uv + v * 2, 2 * sizeof(float));
            if (m->emission) memcpy(m->emission + nv * 3, m->emission + v * 3, 3 * sizeof(float));
        }
        nv++;
    }
    for (size_t i = 0; i < kept * 3; ++i) m->indices[i] = remap[m->indices[i]];
    m->vertex_count = nv;
    free(face_n); free(acc); free(remap);
    return PRT_OK;
}

int prt__mesh_surface_id(prt__mesh *m, const char *name)
{
    char clean[PRT__SURFACE_NAME];
    size_t n = 0;
    for (; name && name[n] && n < PRT__SURFACE_NAME - 1; ++n) clean[n] = (unsigned char)name[n] < 32 || name[n] == 127 ? '_' : name[n];
    clean[n] = 0;
    if (!n) return 0;
    for (int k = 0; k < m->surface_count; ++k)
        if (!strcmp(m->surface_names[k], clean)) return k + 1;
    if (m->surface_count >= PRT__MAX_SURFACES) return -1;
    char (*names)[PRT__SURFACE_NAME] = realloc(m->surface_names, (size_t)(m->surface_count + 1) * PRT__SURFACE_NAME);
    if (!names) return -1;
    m->surface_names = names;
    memset(names[m->surface_count], 0, PRT__SURFACE_NAME);   /* files hold all 64 bytes: no heap garbage */
    memcpy(names[m->surface_count], clean, n + 1);
    return ++m->surface_count;
}

prt_status prt__mesh_paint(const prt__mesh *m, const char *name, const float rgb[3], float *albedo)
{
    for (int c = 0; c < 3; ++c)
        if (!(rgb[c] >= 0.0f && rgb[c] <= 1.0f)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "albedo of '%s' must lie in [0, 1]", name);
    bool found = false;
    for (int k = 0; k < m->surface_count; ++k) {
        if (strcmp(m->surface_names[k], name)) continue;
        found = true;
        for (size_t v = 0; v < m->vertex_count; ++v)
            if (m->surface[v] == k + 1) memcpy(albedo + v * 3, rgb, 3 * sizeof(float));
    }
    if (found) return PRT_OK;
    if (!m->surface_count) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "no surface is called '%s': none is named (the meshes had no materials)", name);
    char list[512] = "";
    for (int k = 0; k < m->surface_count && strlen(list) < sizeof list - 80; ++k)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", k ? ", " : "", m->surface_names[k]);
    return prt__fail(NULL, PRT_ERR_INVALID_ARG, "no surface is called '%s' (there are %s%s)", name, list, strlen(list) >= sizeof list - 80 ? ", ..." : "");
}

void prt__mesh_compact_surfaces(prt__mesh *m)
{
    if (!m->surface_count) return;
    int *map = prt__calloc((size_t)m->surface_count + 1, sizeof(int));
    if (!map) return;   /* unused names cost nothing but a line in prt info */
    for (size_t v = 0; v < m->vertex_count; ++v) map[m->surface[v]] = 1;
    int n = 0;
    for (int k = 1; k <= m->surface_count; ++k) {
        if (!map[k]) continue;
        map[k] = ++n;
        if (n != k) memcpy(m->surface_names[n - 1], m->surface_names[k - 1], PRT__SURFACE_NAME);
    }
    for (size_t v = 0; v < m->vertex_count; ++v) m->surface[v] = (uint16_t)(m->surface[v] ? map[m->surface[v]] : 0);
    m->surface_count = n;
    free(map);
}

void prt__mesh_set_surface(prt__mesh *m, size_t first, size_t count, int id)
{
    for (size_t v = first; v < first + count; ++v) m->surface[v] = (uint16_t)id;
}

float *prt__mesh_emission(prt__mesh *m)
{
    if (!m->emission) m->emission = prt__calloc(m->vertex_count ? m->vertex_count * 3 : 1, sizeof(float));
    return m->emission;
}

void prt__mesh_set_uv(prt__mesh *m, size_t first, size_t count, const float *uv)
{
    memcpy(m->uv + first * 2, uv, count * 2 * sizeof(float));
}

bool prt__mesh_has_uv(const prt__mesh *m)
{
    if (!m->uv || !m->vertex_count) return false;
    for (size_t i = 0; i < m->vertex_count * 2; ++i)
        if (!isfinite(m->uv[i])) return false;
    return true;
}
