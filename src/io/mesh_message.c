/* Imported meshes as bytes (see mesh_message.h). Layout, native byte order (both ends are the same
 * program on the same machine):
 *   "PRTMESH1", u32 status, u32 flags, u32 message length L, L bytes of message, then parts:
 *   f32 albedo[3], f32 emission[3], u64 nv, u64 nt, u32 has_uv, u32 name length N (< 64),
 *   N bytes of the part's name (its material), f32 positions[nv][3], f32 normals[nv][3], (has_uv) f32 uv[nv][2], u32 indices[nt][3]. */
#include "io/mesh_message.h"

#include <stdlib.h>
#include <string.h>

static const char MAGIC[8] = {'P', 'R', 'T', 'M', 'E', 'S', 'H', '2'};

void prt__mesh_message_begin(prt__bytes *b, prt_status status, uint32_t flags, const char *message)
{
    uint32_t head[3] = {(uint32_t)status, flags, message ? (uint32_t)strnlen(message, 1024) : 0};
    prt__bytes_put(b, MAGIC, sizeof MAGIC);
    prt__bytes_put(b, head, sizeof head);
    if (head[2]) prt__bytes_put(b, message, head[2]);
}

void prt__mesh_message_part(prt__bytes *b, const char *name, const float albedo[3], const float emission[3], size_t nv, const float *pos,
                            const float *nrm, const float *uv, size_t nt, const uint32_t *idx)
{
    float colours[6] = {albedo[0], albedo[1], albedo[2], emission[0], emission[1], emission[2]};
    uint64_t counts[2] = {nv, nt};
    uint32_t has_uv[2] = {uv != NULL, name ? (uint32_t)strnlen(name, PRT__SURFACE_NAME - 1) : 0};
    prt__bytes_put(b, colours, sizeof colours);
    prt__bytes_put(b, counts, sizeof counts);
    prt__bytes_put(b, has_uv, sizeof has_uv);
    if (has_uv[1]) prt__bytes_put(b, name, has_uv[1]);
    prt__bytes_put(b, pos, nv * 3 * sizeof(float));
    prt__bytes_put(b, nrm, nv * 3 * sizeof(float));
    if (uv) prt__bytes_put(b, uv, nv * 2 * sizeof(float));
    prt__bytes_put(b, idx, nt * 3 * sizeof(uint32_t));
}

typedef struct reader {
    const unsigned char *p;
    size_t left;
} reader;

static bool take(reader *r, void *out, size_t n)
{
    if (n > r->left) return false;
    memcpy(out, r->p, n);
    r->p += n;
    r->left -= n;
    return true;
}

/* A pointer to n elements of size bytes each, when the message holds them; copied into aligned
 * memory because the message's bytes carry no alignment. */
static void *take_array(reader *r, uint64_t n, size_t size, bool *short_message)
{
    size_t bytes;
    if (n > SIZE_MAX || !prt__mul_ok((size_t)n, size, &bytes) || bytes > r->left) { *short_message = true; return NULL; }
    void *a = malloc(bytes ? bytes : 1);
    if (a) take(r, a, bytes);
    return a;
}

prt_status prt__mesh_message_read(const prt_context *ctx, const unsigned char *data, size_t size, const char *path, uint32_t *flags,
                                  prt__mesh *m)
{
    reader r = {data, size};
    char magic[8];
    uint32_t head[3];
    *flags = 0;
    if (!take(&r, magic, sizeof magic) || memcmp(magic, MAGIC, sizeof magic) || !take(&r, head, sizeof head) || head[2] > 1024 ||
        head[2] > r.left)
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': the importer handed back no mesh", path);
    *flags = head[1];
    if (head[0] != PRT_OK) {
        char why[1025];
        memcpy(why, r.p, head[2]);
        why[head[2]] = 0;
        prt_status st = head[0] <= PRT_ERR_EMPTY ? (prt_status)head[0] : PRT_ERR_FORMAT;
        return prt__fail(ctx, st, "%s", head[2] ? why : "the importer failed");
    }
    r.p += head[2];
    r.left -= head[2];
    const size_t before = m->triangle_count;
    prt_status st = PRT_OK;
    for (size_t part = 0; r.left && !st; ++part) {
        float colours[6];
        uint64_t counts[2];
        uint32_t has_uv[2];
        char name[PRT__SURFACE_NAME] = "";
        if (!take(&r, colours, sizeof colours) || !take(&r, counts, sizeof counts) || !take(&r, has_uv, sizeof has_uv) || has_uv[0] > 1 ||
            has_uv[1] >= PRT__SURFACE_NAME || !take(&r, name, has_uv[1]) || counts[0] > UINT32_MAX || counts[1] > UINT32_MAX / 3) {
            st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': the importer's mesh part %zu is malformed", path, part);
            break;
        }
        const size_t nv = (size_t)counts[0], nt = (size_t)counts[1];
        bool short_message = false;
        float *pos = take_array(&r, nv, 3 * sizeof(float), &short_message);
        float *nrm = short_message ? NULL : take_array(&r, nv, 3 * sizeof(float), &short_message);
        float *uv = short_message || !has_uv[0] ? NULL : take_array(&r, nv, 2 * sizeof(float), &short_message);
        uint32_t *idx = short_message ? NULL : take_array(&r, nt, 3 * sizeof(uint32_t), &short_message);
        if (short_message) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': the importer's mesh part %zu is truncated", path, part);
        else if (!pos || !nrm || !idx || (has_uv[0] && !uv)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory importing '%s'", path);
        const size_t first = m->vertex_count;
        if (!st) st = prt__mesh_append(m, pos, nrm, NULL, colours, nv, idx, nt);
        if (!st && (colours[3] != 0 || colours[4] != 0 || colours[5] != 0)) {
            float *e = prt__mesh_emission(m);
            if (!e) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory importing '%s'", path);
            else
                for (size_t v = first; v < first + nv; ++v) memcpy(e + v * 3, colours + 3, 3 * sizeof(float));
        }
        if (!st && uv) prt__mesh_set_uv(m, first, nv, uv);
        if (!st) {
            name[has_uv[1]] = 0;
            const int id = prt__mesh_surface_id(m, name);
            if (id < 0) st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s': more than %d named surfaces", path, PRT__MAX_SURFACES);
            else prt__mesh_set_surface(m, first, nv, id);
        }
        if (st == PRT_ERR_FORMAT && !short_message) st = prt__fail(ctx, st, "'%s': %s", path, prt_last_error());
        free(pos); free(nrm); free(uv); free(idx);
    }
    if (!st && m->triangle_count == before) st = prt__fail(ctx, PRT_ERR_EMPTY, "'%s' holds no triangles", path);
    return st;
}
