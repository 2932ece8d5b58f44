/* The spectral method's chunks in .prt files (docs/FORMAT.md): what it writes beside the
 * method-independent ones (transfer/file.c), and their loading, every count checked against the
 * chunk's size, the mesh and every other count before it sizes an allocation. */
#include "methods/spectral/spectral.h"

#include <float.h>

#define CHUNK_SPCP PRT__FOURCC('S', 'P', 'C', 'P')
#define CHUNK_SPCB PRT__FOURCC('S', 'P', 'C', 'B')
#define CHUNK_SPCT PRT__FOURCC('S', 'P', 'C', 'T')
#define CHUNK_SPCE PRT__FOURCC('S', 'P', 'C', 'E')
#define CHUNK_SPCM PRT__FOURCC('S', 'P', 'C', 'M')
#define CHUNK_SPCG PRT__FOURCC('S', 'P', 'C', 'G')
#define CHUNK_SPGE PRT__FOURCC('S', 'P', 'G', 'E')
/* Rows with a scale each (format version 3); files before them hold SPCT and SPCG, one scale for
 * the diffuse matrix and one for the glossy rows, still read. */
#define CHUNK_SPCR PRT__FOURCC('S', 'P', 'C', 'R')
#define CHUNK_SPCH PRT__FOURCC('S', 'P', 'C', 'H')
/* |T(v, l)| <= pi max |s_l| <= pi x 1.0001 (the gathering's weights sum to at most pi): a row's
 * scale is its largest over 32767. */
#define MAX_ROW_SCALE (3.1419f * 1.0001f / 32767.0f)
#define CHUNK_SPCS PRT__FOURCC('S', 'P', 'C', 'S')
#define SET_ENTRY (8 + PRT__BRDF_RECORD)   /* surface, glossy flag, the BRDF; then its matrix if glossy */
#define SPCP_HEADER 48
#define MATRIX_BYTES (3 * PRT__SPECTRAL_GLOSSY_N * PRT__SPECTRAL_GLOSSY_N * sizeof(float))

prt_status prt__spectral_save(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    const size_t nv = t->mesh.vertex_count;
    const uint64_t nnz = s->row_start[nv];
    static const unsigned char zero4[4] = {0};
    unsigned char *head = prt__chunks_alloc(l, SPCP_HEADER);
    uint32_t *counts = prt__chunks_alloc(l, nv * sizeof(uint32_t));
    if (!head || !counts) return PRT_OK;   /* the list records the failure */
    const uint32_t p32[6] = {b->functions, b->partitions, (uint32_t)s->samples, (uint32_t)s->partition_size, (uint32_t)s->env_order, 0};
    for (int i = 0; i < 6; ++i) prt__put32(head + 4 * i, p32[i]);
    /* head + 24: the one scale of files before per-row scales, 0 now */
    memcpy(head + 28, &s->ray_offset, 4);
    prt__put64(head + 32, nnz);
    prt__put64(head + 40, nv);
    prt__chunks_add(l, CHUNK_SPCP, head, (size_t)SPCP_HEADER, b->part_of, nv * sizeof(uint32_t), b->count, (size_t)b->partitions * sizeof(uint32_t), NULL);
    prt__chunks_add(l, CHUNK_SPCB, b->values, b->offset[nv] * sizeof(float), NULL);
    for (size_t v = 0; v < nv; ++v) counts[v] = (uint32_t)(s->row_start[v + 1] - s->row_start[v]);
    const size_t bytes = nnz * 2, pad = ((bytes + 3) & ~(size_t)3) - bytes;
    unsigned char *rh = prt__chunks_alloc(l, 8);
    if (!rh) return PRT_OK;
    memcpy(rh, &s->drop, 4);
    prt__put32(rh + 4, 0);
    if (l->version < 3) l->version = 3;   /* readers of version 2 would find no transfer */
    prt__chunks_add(l, CHUNK_SPCR, rh, (size_t)8, counts, nv * sizeof(uint32_t), s->row_scale, nv * sizeof(float), s->index, bytes, zero4, pad, s->value,
                    bytes, zero4, pad, NULL);
    prt__chunks_add(l, CHUNK_SPCE, s->env, nv * (size_t)s->env_order * s->env_order * sizeof(float), NULL);
    if (s->emit) prt__chunks_add(l, CHUNK_SPCM, s->emit, nv * 3 * sizeof(float), NULL);
    if (s->set_count) {
        /* count, 0, then per entry: surface, glossy (1: its SH matrix follows), the BRDF. */
        size_t bytes = 8;
        for (int i = 0; i < s->set_count; ++i) bytes += SET_ENTRY + (s->set_matrix[i] ? MATRIX_BYTES : 0);
        unsigned char *p = prt__chunks_alloc(l, bytes);
        if (!p) return PRT_OK;
        prt__put32(p, (uint32_t)s->set_count);
        prt__put32(p + 4, 0);
        unsigned char *at = p + 8;
        for (int i = 0; i < s->set_count; ++i) {
            prt__put32(at, s->set[i].surface);
            prt__put32(at + 4, s->set_matrix[i] != NULL);
            prt__brdf_put(at + 8, &s->set[i].brdf);
            at += SET_ENTRY;
            if (s->set_matrix[i]) { memcpy(at, s->set_matrix[i], MATRIX_BYTES); at += MATRIX_BYTES; }
        }
        prt__chunks_add(l, CHUNK_SPCS, p, bytes, NULL);
    }
    if (s->glossy_count) {
        /* glossy vertex count, SH order, drop, material count, matrices, entries per row, scales,
         * indices, values */
        const size_t rows = (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N, gnnz = s->grow_start[rows], gb = gnnz * 2,
                     gpad = ((gb + 3) & ~(size_t)3) - gb;
        int nmat = 0;
        for (int k = 0; k < PRT__MAX_BRDFS; ++k) nmat += s->brdf_matrix[k] != NULL;
        const size_t mbytes = (size_t)nmat * (4 + MATRIX_BYTES);
        unsigned char *gh = prt__chunks_alloc(l, 16 + mbytes);
        uint32_t *gcounts = prt__chunks_alloc(l, rows * sizeof(uint32_t));
        if (!gh || !gcounts) return PRT_OK;
        prt__put32(gh, s->glossy_count);
        prt__put32(gh + 4, PRT__SPECTRAL_GLOSSY_ORDER);
        memcpy(gh + 8, &s->drop, 4);
        prt__put32(gh + 12, (uint32_t)nmat);
        unsigned char *at = gh + 16;
        for (int k = 0; k < PRT__MAX_BRDFS; ++k)
            if (s->brdf_matrix[k]) {
                prt__put32(at, (uint32_t)(k + 1));
                memcpy(at + 4, s->brdf_matrix[k], MATRIX_BYTES);
                at += 4 + MATRIX_BYTES;
            }
        for (size_t r = 0; r < rows; ++r) gcounts[r] = (uint32_t)(s->grow_start[r + 1] - s->grow_start[r]);
        prt__chunks_add(l, CHUNK_SPCH, gh, 16 + mbytes, gcounts, rows * sizeof(uint32_t), s->grow_scale, rows * sizeof(float), s->gindex, gb, zero4,
                        gpad, s->gvalue, gb, zero4, gpad, NULL);
        if (s->genv) {   /* glossy vertex count, environment coefficients, then the matrices as halves */
            const size_t n = (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N * s->env_order * s->env_order;
            unsigned char *eh = prt__chunks_alloc(l, 8 + n * 2 + 2);
            if (!eh) return PRT_OK;
            prt__put32(eh, s->glossy_count);
            prt__put32(eh + 4, (uint32_t)(s->env_order * s->env_order));
            uint16_t *h = (uint16_t *)(eh + 8);
            for (size_t i = 0; i < n; ++i) h[i] = prt__half_from_float(s->genv[i]);
            h[n] = 0;
            prt__chunks_add(l, CHUNK_SPGE, eh, 8 + n * 2 + (n & 1 ? 2 : 0), NULL);
        }
    }
    return PRT_OK;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %s", msg); }

static prt_status load_params(prt_context *ctx, prt_transfer *t, prt__spectral_set *s, const prt__chunk_in *c, uint64_t *nnz, float *one_scale)
{
    const unsigned char *p = c->data;
    const uint64_t nv = t->mesh.vertex_count, len = c->size;
    if (len < SPCP_HEADER || prt__get64(p + 40) != nv) return bad(ctx, "invalid spectral parameter chunk");
    prt__spectral_basis *b = &s->basis;
    b->functions = prt__get32(p);
    b->partitions = prt__get32(p + 4);
    s->samples = (int)prt__get32(p + 8);
    s->partition_size = (int)prt__get32(p + 12);
    s->env_order = (int)prt__get32(p + 16);
    memcpy(one_scale, p + 24, 4);
    memcpy(&s->ray_offset, p + 28, 4);
    *nnz = prt__get64(p + 32);
    if (b->functions < 1 || b->functions > PRT__SPECTRAL_MAX_FUNCTIONS || b->partitions < 1 || b->partitions > nv || s->env_order < 1 ||
        s->env_order > PRT_SH_MAX_ORDER || !(*one_scale >= 0) || !isfinite(*one_scale) || !(s->ray_offset > 0) || !isfinite(s->ray_offset) ||
        *nnz > nv * (uint64_t)b->functions)
        return bad(ctx, "spectral parameters out of range");
    if (len != SPCP_HEADER + nv * 4 + (uint64_t)b->partitions * 4) return bad(ctx, "spectral parameter chunk size mismatch");
    if (!(s->ray_offset <= fmaxf(1e4f * prt__ray_offset(&t->mesh), 1e-6f))) return bad(ctx, "spectral ray offset larger than the scene");
    b->part_of = malloc(nv * sizeof(uint32_t));
    b->count = malloc((size_t)b->partitions * sizeof(uint32_t));
    if (!b->part_of || !b->count) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(b->part_of, p + SPCP_HEADER, nv * 4);
    memcpy(b->count, p + SPCP_HEADER + nv * 4, (size_t)b->partitions * 4);
    if (!prt__spectral_basis_index(b, nv)) return bad(ctx, "spectral partitions are inconsistent");
    return PRT_OK;
}

static prt_status load_basis(prt_context *ctx, size_t nv, prt__spectral_basis *b, const prt__chunk_in *c)
{
    const uint64_t n = b->offset[nv];
    if (c->size != n * sizeof(float)) return bad(ctx, "spectral basis chunk size mismatch");
    if (!(b->values = malloc(n ? n * sizeof(float) : 1))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(b->values, c->data, n * sizeof(float));
    /* Orthonormal vectors have no component beyond 1. */
    for (uint64_t i = 0; i < n; ++i)
        if (!(fabsf(b->values[i]) <= 1.0001f)) return bad(ctx, "spectral basis values out of range");
    return PRT_OK;
}

/* Per-row scales: finite, zero exactly for the rows without entries, at most `most`. */
static bool row_scales_ok(const float *scale, const uint64_t *start, uint64_t rows, float most)
{
    for (uint64_t r = 0; r < rows; ++r)
        if (!(scale[r] >= 0 && scale[r] <= most) || (scale[r] > 0) != (start[r + 1] > start[r])) return false;
    return true;
}

/* SPCT (one_scale > 0: the scale of every row) or SPCR (one_scale 0: a drop threshold, then a
 * scale per row after the counts). */
static prt_status load_transfer(prt_context *ctx, size_t nv, prt__spectral_set *s, uint64_t nnz, const prt__chunk_in *c, float one_scale)
{
    const bool per_row = one_scale == 0;
    const uint64_t bytes = nnz * 2, padded = (bytes + 3) & ~3ull, head = per_row ? 8 : 0, counts = head + nv * (per_row ? 8 : 4);
    if (c->size != counts + 2 * padded) return bad(ctx, "spectral transfer chunk size mismatch");
    if (per_row) {
        memcpy(&s->drop, c->data, 4);
        if (!(s->drop >= 0 && s->drop <= 0.1f) || prt__get32(c->data + 4)) return bad(ctx, "spectral drop threshold out of range");
    }
    s->row_start = malloc((nv + 1) * sizeof(uint64_t));
    s->row_scale = malloc(nv ? nv * sizeof(float) : 1);
    s->index = malloc(bytes ? bytes : 1);
    s->value = malloc(bytes ? bytes : 1);
    if (!s->row_start || !s->row_scale || !s->index || !s->value) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    s->row_start[0] = 0;
    for (size_t v = 0; v < nv; ++v) {
        const uint32_t n = prt__get32(c->data + head + v * 4);
        if (n > s->basis.functions || s->row_start[v] + n > nnz) return bad(ctx, "spectral transfer counts are inconsistent");
        s->row_start[v + 1] = s->row_start[v] + n;
    }
    if (s->row_start[nv] != nnz) return bad(ctx, "spectral transfer counts are inconsistent");
    if (per_row) {
        memcpy(s->row_scale, c->data + head + nv * 4, nv * sizeof(float));
        if (!row_scales_ok(s->row_scale, s->row_start, nv, MAX_ROW_SCALE)) return bad(ctx, "a spectral transfer row scale is out of range");
    } else {
        for (size_t v = 0; v < nv; ++v) s->row_scale[v] = s->row_start[v + 1] > s->row_start[v] ? one_scale : 0.0f;   /* as SPCR has them */
        s->one_scale = true;
    }
    memcpy(s->index, c->data + counts, bytes);
    memcpy(s->value, c->data + counts + padded, bytes);
    for (size_t v = 0; v < nv; ++v)
        for (uint64_t i = s->row_start[v]; i < s->row_start[v + 1]; ++i)
            if (s->index[i] >= s->basis.functions || (i > s->row_start[v] && s->index[i] <= s->index[i - 1]))
                return bad(ctx, "a spectral transfer index is out of range or out of order");
    return PRT_OK;
}

/* SPCG (one scale for the glossy rows) or SPCH (per_row: the drop threshold in its place, a scale
 * per row after the counts). */
static prt_status load_glossy(prt_context *ctx, const prt_transfer *t, prt__spectral_set *s, const prt__chunk_in *c, bool per_row)
{
    const unsigned char *head = c->data;
    const uint64_t rows = (uint64_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N;
    uint64_t len = c->size;
    if (len < 16 || prt__get32(head) != s->glossy_count || prt__get32(head + 4) != PRT__SPECTRAL_GLOSSY_ORDER)
        return bad(ctx, "invalid spectral glossy chunk");
    float gscale;
    memcpy(&gscale, head + 8, 4);
    if (per_row ? gscale != s->drop : !(gscale > 0) || !isfinite(gscale)) return bad(ctx, "spectral glossy scale out of range");
    /* The glossy materials' SH matrices: one for each material a glossy vertex uses, no other. */
    const uint32_t nmat = prt__get32(head + 12);
    if (nmat > (uint32_t)t->brdf_count || len < 16 + (uint64_t)nmat * (4 + MATRIX_BYTES)) return bad(ctx, "invalid spectral glossy chunk");
    for (uint32_t i = 0; i < nmat; ++i) {
        const unsigned char *e = head + 16 + (size_t)i * (4 + MATRIX_BYTES);
        const uint32_t k = prt__get32(e);
        if (k < 1 || k > (uint32_t)t->brdf_count || !prt_brdf_is_glossy(&t->brdfs[k - 1]) || s->brdf_matrix[k - 1])
            return bad(ctx, "a spectral glossy material is out of range or repeated");
        if (!(s->brdf_matrix[k - 1] = malloc(MATRIX_BYTES))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(s->brdf_matrix[k - 1], e + 4, MATRIX_BYTES);
        if (!prt__all_finite(s->brdf_matrix[k - 1], MATRIX_BYTES / sizeof(float))) return bad(ctx, "non-finite spectral glossy BRDF matrix");
    }
    for (size_t v = 0; v < t->mesh.vertex_count; ++v) {
        const uint8_t k = t->mesh.material[v];
        if (s->glossy_of[v] != UINT32_MAX && k && prt_brdf_is_glossy(&t->brdfs[k - 1]) && !s->brdf_matrix[k - 1])
            return bad(ctx, "a glossy material's BRDF matrix is missing");
    }
    const unsigned char *p = head + (size_t)nmat * (4 + MATRIX_BYTES);   /* the rest as if the matrices were not there */
    len -= (uint64_t)nmat * (4 + MATRIX_BYTES);
    const uint64_t counts = 16 + rows * (per_row ? 8 : 4);   /* where the indices start */
    if (len < counts) return bad(ctx, "invalid spectral glossy chunk");
    s->grow_start = malloc((rows + 1) * sizeof(uint64_t));
    s->grow_scale = malloc(rows ? rows * sizeof(float) : 1);
    if (!s->grow_start || !s->grow_scale) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    s->grow_start[0] = 0;
    for (uint64_t r = 0; r < rows; ++r) {
        const uint32_t n = prt__get32(p + 16 + r * 4);
        if (n > s->basis.functions) return bad(ctx, "spectral glossy counts are inconsistent");
        s->grow_start[r + 1] = s->grow_start[r] + n;
    }
    const uint64_t gnnz = s->grow_start[rows], gb = gnnz * 2, padded = (gb + 3) & ~3ull;
    if (len != counts + 2 * padded) return bad(ctx, "spectral glossy chunk size mismatch");
    if (per_row) {
        memcpy(s->grow_scale, p + 16 + rows * 4, rows * sizeof(float));
        if (!row_scales_ok(s->grow_scale, s->grow_start, rows, FLT_MAX)) return bad(ctx, "a spectral glossy row scale is out of range");
    } else {
        for (uint64_t r = 0; r < rows; ++r) s->grow_scale[r] = s->grow_start[r + 1] > s->grow_start[r] ? gscale : 0.0f;
    }
    s->gindex = malloc(gb ? gb : 1);
    s->gvalue = malloc(gb ? gb : 1);
    if (!s->gindex || !s->gvalue) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(s->gindex, p + counts, gb);
    memcpy(s->gvalue, p + counts + padded, gb);
    for (uint64_t r = 0; r < rows; ++r)
        for (uint64_t i = s->grow_start[r]; i < s->grow_start[r + 1]; ++i)
            if (s->gindex[i] >= s->basis.functions || (i > s->grow_start[r] && s->gindex[i] <= s->gindex[i - 1]))
                return bad(ctx, "a spectral glossy index is out of range or out of order");
    return PRT_OK;
}

/* The BRDF sets (SPCS; files before them have none): every count checked against the chunk. */
static prt_status load_sets(prt_context *ctx, const prt_transfer *t, prt__spectral_set *s, const prt__chunk_in *c)
{
    const unsigned char *p = c->data;
    const uint64_t len = c->size;
    if (len < 8) return bad(ctx, "invalid spectral BRDF set chunk");
    const uint32_t n = prt__get32(p);
    if (n < 1 || n > PRT__MAX_BRDF_SET || len < 8 + (uint64_t)n * SET_ENTRY) return bad(ctx, "spectral BRDF set count out of range");
    s->set = prt__calloc(n, sizeof *s->set);
    s->set_matrix = prt__calloc(n, sizeof *s->set_matrix);
    if (!s->set || !s->set_matrix) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    s->set_count = (int)n;
    uint64_t at = 8;
    for (uint32_t i = 0; i < n; ++i) {
        if (len - at < SET_ENTRY) return bad(ctx, "spectral BRDF set chunk size mismatch");
        const uint32_t surface = prt__get32(p + at), glossy = prt__get32(p + at + 4);
        prt__brdf_choice *e = &s->set[i];
        prt__brdf_get(p + at + 8, &e->brdf);
        at += SET_ENTRY;
        if (surface < 1 || surface > (uint32_t)t->mesh.surface_count || glossy > 1) return bad(ctx, "a spectral BRDF set names no surface of the mesh");
        e->surface = (uint16_t)surface;
        if (prt_brdf_validate(&e->brdf) || (int)glossy != prt_brdf_is_glossy(&e->brdf)) return bad(ctx, "invalid BRDF in a spectral BRDF set");
        for (uint32_t j = 0; j < i; ++j)
            if (s->set[j].surface == e->surface && !memcmp(&s->set[j].brdf, &e->brdf, sizeof e->brdf)) return bad(ctx, "a spectral BRDF set repeats a BRDF");
        if (!glossy) continue;
        if (len - at < MATRIX_BYTES) return bad(ctx, "spectral BRDF set chunk size mismatch");
        if (!(s->set_matrix[i] = malloc(MATRIX_BYTES))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(s->set_matrix[i], p + at, MATRIX_BYTES);
        at += MATRIX_BYTES;
        if (!prt__all_finite(s->set_matrix[i], PRT__SPECTRAL_MATRIX_FLOATS)) return bad(ctx, "non-finite spectral BRDF set matrix");
    }
    return at == len ? PRT_OK : bad(ctx, "spectral BRDF set chunk size mismatch");
}

prt_status prt__spectral_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    (void)meta;
    prt__spectral_set *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = s;
    if (!(s->cache = prt__spectral_cache_new())) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const size_t nv = t->mesh.vertex_count;
    uint64_t nnz = 0;
    float one_scale = 0;
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_SPCP);
    prt_status st = c ? load_params(ctx, t, s, c, &nnz, &one_scale) : bad(ctx, "spectral parameter chunk missing");
    if (!st) st = (c = prt__chunk_take(chunks, count, CHUNK_SPCB)) ? load_basis(ctx, nv, &s->basis, c) : bad(ctx, "spectral basis chunk missing");
    /* Rows with a scale each (SPCR: SPCP's one scale is 0), or one scale for all (SPCT, older). */
    if (!st) {
        prt__chunk_in *one = prt__chunk_take(chunks, count, CHUNK_SPCT), *rows = prt__chunk_take(chunks, count, CHUNK_SPCR);
        if (one && rows) st = bad(ctx, "spectral transfer appears with one scale and with per-row scales");
        else if (!one && !rows) st = bad(ctx, "spectral transfer chunk missing");
        else if (!rows != (one_scale > 0)) st = bad(ctx, "the spectral scale does not match the transfer chunk");
        else st = load_transfer(ctx, nv, s, nnz, one ? one : rows, one_scale);
    }
    if (!st) {
        const uint64_t n = nv * (uint64_t)s->env_order * s->env_order;
        if (!(c = prt__chunk_take(chunks, count, CHUNK_SPCE))) st = bad(ctx, "spectral environment chunk missing");
        else if (c->size != n * sizeof(float)) st = bad(ctx, "spectral environment chunk size mismatch");
        else if (!(s->env = malloc(n * sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            memcpy(s->env, c->data, n * sizeof(float));
            if (!prt__all_finite(s->env, n)) st = bad(ctx, "non-finite spectral environment transfer");
        }
    }
    /* Direct light from the emissive surfaces: there exactly when something emits. */
    bool emits = false;
    for (size_t i = 0; t->mesh.emission && i < nv * 3 && !emits; ++i) emits = t->mesh.emission[i] > 0;
    c = st ? NULL : prt__chunk_take(chunks, count, CHUNK_SPCM);
    if (!st && !c && emits) st = bad(ctx, "the spectral emitters chunk is missing although the scene emits");
    if (!st && c) {
        if (c->size != nv * 3 * sizeof(float)) st = bad(ctx, "spectral emitters chunk size mismatch");
        else if (!(s->emit = malloc(nv * 3 * sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            memcpy(s->emit, c->data, nv * 3 * sizeof(float));
            for (size_t i = 0; i < nv * 3 && !st; ++i)
                if (!(s->emit[i] >= 0.0f && s->emit[i] <= PRT__MAX_RADIANCE)) st = bad(ctx, "spectral emitter irradiance out of range");
        }
    }
    /* The BRDF sets come first: their glossy candidates decide which vertices have glossy rows. */
    c = st ? NULL : prt__chunk_take(chunks, count, CHUNK_SPCS);
    if (c) st = load_sets(ctx, t, s, c);
    /* The glossy final bounce: there exactly when some vertex's material (or candidate) has a glossy part. */
    if (!st && !prt__spectral_glossy_index(t, s)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    /* Its rows scaled as the diffuse ones: SPCG beside SPCT, SPCH beside SPCR. */
    c = st ? NULL : prt__chunk_take(chunks, count, s->one_scale ? CHUNK_SPCG : CHUNK_SPCH);
    if (!st && !c != !s->glossy_count) st = bad(ctx, "the spectral glossy chunk does not match the glossy materials");
    if (!st && c) st = load_glossy(ctx, t, s, c, !s->one_scale);
    /* The environment on glossy vertices: optional (files written before it reflect the
     * environment diffusely), and only beside the glossy rows. */
    c = st ? NULL : prt__chunk_take(chunks, count, CHUNK_SPGE);
    if (!st && c) {
        const uint64_t nc = (uint64_t)s->env_order * s->env_order, n = (uint64_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N * nc;
        if (!s->glossy_count || c->size < 8 || prt__get32(c->data) != s->glossy_count || prt__get32(c->data + 4) != nc ||
            c->size != 8 + (n + (n & 1)) * 2)
            st = bad(ctx, "the spectral glossy environment chunk does not match the glossy vertices");
        else if (!(s->genv = malloc(n * sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else
            for (uint64_t i = 0; i < n && !st; ++i) {
                uint16_t h;
                memcpy(&h, c->data + 8 + i * 2, 2);
                s->genv[i] = prt__half_to_float(h);
                if (!isfinite(s->genv[i])) st = bad(ctx, "non-finite spectral glossy environment transfer");
            }
    }
    static const uint32_t ids[10] = {CHUNK_SPCP, CHUNK_SPCB, CHUNK_SPCT, CHUNK_SPCR, CHUNK_SPCE, CHUNK_SPCM, CHUNK_SPCG, CHUNK_SPCH, CHUNK_SPGE, CHUNK_SPCS};
    for (int i = 0; i < 10 && !st; ++i)
        if (prt__chunk_take(chunks, count, ids[i])) st = bad(ctx, "a spectral chunk appears twice or beside the other storage");
    return st;
}
