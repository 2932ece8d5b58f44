/* Conforming refinement to a maximum edge length. Each pass splits every edge longer than the
 * limit at its midpoint (one new vertex per edge, shared by both triangles through a hash map)
 * and re-triangulates each triangle by how many of its edges split (1 -> 2, 2 -> 3, 3 -> 4), so
 * no T-junction appears. Vertices duplicated at creases split independently but at bit-identical
 * positions, so creases keep their split normals and stay watertight. */
#include "geom/mesh.h"

#include <string.h>

#define MAX_TRIANGLES 50000000u

typedef struct edge_map {
    uint64_t *keys;     /* (min << 32 | max) + 1; 0 = empty */
    uint32_t *values;
    size_t cap;
} edge_map;

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 33; x *= 0xff51afd7ed558ccdULL; x ^= x >> 33; x *= 0xc4ceb9fe1a85ec53ULL; x ^= x >> 33;
    return x;
}

static uint32_t *edge_slot(edge_map *e, uint32_t a, uint32_t b, bool *found)
{
    uint64_t key = ((uint64_t)(a < b ? a : b) << 32 | (a < b ? b : a)) + 1;
    size_t i = mix64(key) & (e->cap - 1);
    while (e->keys[i] && e->keys[i] != key) i = (i + 1) & (e->cap - 1);
    *found = e->keys[i] == key;
    e->keys[i] = key;
    return &e->values[i];
}

static float edge_len2(const prt__mesh *m, uint32_t a, uint32_t b)
{
    float d[3];
    prt__v3_sub(m->positions + a * 3, m->positions + b * 3, d);
    return prt__v3_dot(d, d);
}

bool prt__mesh_reserve(prt__mesh *m, size_t max_v)
{
    if (max_v > UINT32_MAX) return false;
    float *pos = realloc(m->positions, max_v * 3 * sizeof(float));
    if (pos) m->positions = pos;
    float *nrm = pos ? realloc(m->normals, max_v * 3 * sizeof(float)) : NULL;
    if (nrm) m->normals = nrm;
    float *alb = nrm ? realloc(m->albedo, max_v * 3 * sizeof(float)) : NULL;
    if (alb) m->albedo = alb;
    uint8_t *mat = alb ? realloc(m->material, max_v) : NULL;
    if (mat) m->material = mat;
    uint16_t *surf = mat ? realloc(m->surface, max_v * sizeof(uint16_t)) : NULL;
    if (surf) m->surface = surf;
    float *uvs = surf ? realloc(m->uv, max_v * 2 * sizeof(float)) : NULL;
    if (uvs) m->uv = uvs;
    float *emi = uvs && m->emission ? realloc(m->emission, max_v * 3 * sizeof(float)) : NULL;
    if (emi) m->emission = emi;
    return uvs && (!m->emission || emi);
}

uint32_t prt__mesh_midpoint(prt__mesh *m, uint32_t a, uint32_t b)
{
    const uint32_t nv = (uint32_t)m->vertex_count++;
    for (int c = 0; c < 3; ++c) {
        m->positions[nv * 3 + c] = 0.5f * (m->positions[a * 3 + c] + m->positions[b * 3 + c]);
        m->normals[nv * 3 + c] = m->normals[a * 3 + c] + m->normals[b * 3 + c];
        m->albedo[nv * 3 + c] = 0.5f * (m->albedo[a * 3 + c] + m->albedo[b * 3 + c]);
        if (m->emission) m->emission[nv * 3 + c] = 0.5f * (m->emission[a * 3 + c] + m->emission[b * 3 + c]);
    }
    m->material[nv] = m->material[a];   /* edges never join two objects */
    m->surface[nv] = m->surface[a];
    for (int c = 0; c < 2; ++c) m->uv[nv * 2 + c] = 0.5f * (m->uv[a * 2 + c] + m->uv[b * 2 + c]);
    if (!prt__v3_normalize(m->normals + nv * 3)) memcpy(m->normals + nv * 3, m->normals + a * 3, 3 * sizeof(float));
    return nv;
}

prt_status prt__mesh_subdivide(const prt_context *ctx, prt__mesh *m, float max_edge)
{
    if (!(max_edge > 0.0f) || !isfinite(max_edge))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "max edge length must be positive and finite (got %g)", max_edge);
    const float max2 = max_edge * max_edge;
    /* Refuse at once what would take minutes and gigabytes to refuse later: a triangle whose
     * longest edge is L ends with at least (L / max_edge)^2 / 4 triangles. */
    double estimate = 0;
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *v = m->indices + t * 3;
        double l2 = fmax(edge_len2(m, v[0], v[1]), fmax(edge_len2(m, v[1], v[2]), edge_len2(m, v[2], v[0])));
        estimate += fmax(1.0, l2 / ((double)max_edge * max_edge) / 4.0);
    }
    if (estimate > MAX_TRIANGLES)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "subdividing to max edge %g would make at least %.3g triangles (the limit is %u); choose a larger --max-edge",
                         max_edge, estimate, MAX_TRIANGLES);
    for (int pass = 0; pass < 64; ++pass) {
        if (prt__cancelled(ctx)) return prt__fail(ctx, PRT_ERR_CANCELLED, "subdivision cancelled");
        size_t split_edges = 0, new_tris = 0;
        for (size_t t = 0; t < m->triangle_count; ++t) {
            const uint32_t *v = m->indices + t * 3;
            int n = 0;
            for (int k = 0; k < 3; ++k) n += edge_len2(m, v[k], v[(k + 1) % 3]) > max2;
            split_edges += n;
            new_tris += (size_t)n + 1;
        }
        if (split_edges == 0) return PRT_OK;
        if (new_tris > MAX_TRIANGLES)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "subdividing to max edge %g would exceed %u triangles; choose a larger --max-edge",
                             max_edge, MAX_TRIANGLES);
        edge_map em = {0};
        em.cap = 16;
        while (em.cap < split_edges * 2) em.cap <<= 1;
        em.keys = prt__calloc(em.cap, sizeof *em.keys);
        em.values = prt__calloc(em.cap, sizeof *em.values);
        size_t max_v = m->vertex_count + split_edges;   /* an upper bound: shared edges count twice */
        uint32_t *out = prt__calloc(new_tris * 3, sizeof(uint32_t));
        if (!em.keys || !em.values || !out || !prt__mesh_reserve(m, max_v)) {
            free(em.keys); free(em.values); free(out);
            return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory subdividing the mesh");
        }
        size_t nt = 0;
        for (size_t t = 0; t < m->triangle_count; ++t) {
            if ((t & 0xffff) == 0 && prt__cancelled(ctx)) {   /* a few ms between looks */
                free(em.keys); free(em.values); free(out);
                return prt__fail(ctx, PRT_ERR_CANCELLED, "subdivision cancelled");
            }
            uint32_t v[3], mid[3];
            memcpy(v, m->indices + t * 3, sizeof v);
            int count = 0;
            for (int k = 0; k < 3; ++k) {
                uint32_t a = v[k], b = v[(k + 1) % 3];
                mid[k] = UINT32_MAX;
                if (edge_len2(m, a, b) <= max2) continue;
                count++;
                bool found;
                uint32_t *slot = edge_slot(&em, a, b, &found);
                if (!found) *slot = prt__mesh_midpoint(m, a, b);
                mid[k] = *slot;
            }
#define EMIT(x, y, z) (out[nt * 3] = (x), out[nt * 3 + 1] = (y), out[nt * 3 + 2] = (z), nt++)
            if (count == 0) {
                EMIT(v[0], v[1], v[2]);
            } else if (count == 1) {
                int k = mid[0] != UINT32_MAX ? 0 : mid[1] != UINT32_MAX ? 1 : 2;
                uint32_t a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3], mm = mid[k];
                EMIT(a, mm, c);
                EMIT(mm, b, c);
            } else if (count == 2) {
                int k = mid[0] == UINT32_MAX ? 0 : mid[1] == UINT32_MAX ? 1 : 2;   /* the unsplit edge (c, a) */
                uint32_t c = v[k], a = v[(k + 1) % 3], b = v[(k + 2) % 3];
                uint32_t mab = mid[(k + 1) % 3], mbc = mid[(k + 2) % 3];
                EMIT(mab, b, mbc);
                /* Cut the remaining quad (a, mab, mbc, c) along its shorter diagonal. */
                if (edge_len2(m, a, mbc) <= edge_len2(m, mab, c)) {
                    EMIT(a, mab, mbc);
                    EMIT(a, mbc, c);
                } else {
                    EMIT(a, mab, c);
                    EMIT(mab, mbc, c);
                }
            } else {
                EMIT(v[0], mid[0], mid[2]);
                EMIT(mid[0], v[1], mid[1]);
                EMIT(mid[2], mid[1], v[2]);
                EMIT(mid[0], mid[1], mid[2]);
            }
#undef EMIT
        }
        free(em.keys); free(em.values);
        free(m->indices);
        m->indices = out;
        m->triangle_count = nt;
    }
    return prt__fail(ctx, PRT_ERR_INVALID_ARG, "subdivision did not converge for max edge %g", max_edge);
}
