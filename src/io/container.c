/* The .prt container (docs/FORMAT.md): a header, a chunk table, 8-byte aligned chunks each with
 * a CRC-32. Readers bound every count by the bytes actually present before allocating. */
#include "core/transfer_set.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <string.h>
#include <zlib.h>

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the .prt reader and writer assume a little-endian host"
#endif

#define FILE_VERSION 1
#define HEADER_SIZE 24
#define ENTRY_SIZE 24
#define MAX_CHUNKS 4096
static const unsigned char MAGIC[8] = {'P', 'R', 'T', 'F', 0x0D, 0x0A, 0x1A, 0x0A};

#define FOURCC(a, b, c, d) ((uint32_t)(a) | (uint32_t)(b) << 8 | (uint32_t)(c) << 16 | (uint32_t)(d) << 24)
#define CHUNK_META FOURCC('M', 'E', 'T', 'A')
#define CHUNK_MESH FOURCC('M', 'E', 'S', 'H')
#define CHUNK_SHTR FOURCC('S', 'H', 'T', 'R')
#define CHUNK_CPCA FOURCC('C', 'P', 'C', 'A')
#define CHUNK_MATL FOURCC('M', 'A', 'T', 'L')
#define CHUNK_UVS FOURCC('U', 'V', 'S', '0')
#define CHUNK_TXAL FOURCC('T', 'X', 'A', 'L')
#define CHUNK_TXLS FOURCC('T', 'X', 'L', 'S')
#define CHUNK_WAVP FOURCC('W', 'A', 'V', 'P')
#define CHUNK_WBRF FOURCC('W', 'B', 'R', 'F')
#define CHUNK_WAVT FOURCC('W', 'A', 'V', 'T')
#define WAVP_HEADER 48
#define WBRF_HEADER (24 + 3 * PRT_BRDF_MAX_TERMS * 4)
#define BRDF_RECORD 160   /* model, lobes, then 38 floats: see put_brdf */
#define CPCA_HEADER 64
#define PARTS 8

typedef struct chunk { uint32_t id; const void *parts[PARTS]; size_t sizes[PARTS]; size_t size; } chunk;

static void put32(unsigned char *p, uint32_t v) { memcpy(p, &v, 4); }
static void put64(unsigned char *p, uint64_t v) { memcpy(p, &v, 8); }
static uint32_t get32(const unsigned char *p) { uint32_t v; memcpy(&v, p, 4); return v; }
static uint64_t get64(const unsigned char *p) { uint64_t v; memcpy(&v, p, 8); return v; }

static void put_brdf(unsigned char *p, const prt_brdf *b)
{
    float f[38];
    memcpy(f, b->diffuse, 12);
    memcpy(f + 3, b->specular, 12);
    f[6] = b->exponent;
    f[7] = b->exponent_v;
    memcpy(f + 8, b->cxy, 36);
    memcpy(f + 17, b->cz, 36);
    memcpy(f + 26, b->n, 36);
    f[35] = f[36] = f[37] = 0;
    put32(p, (uint32_t)b->model);
    put32(p + 4, (uint32_t)b->lobes);
    memcpy(p + 8, f, sizeof f);
}

static void get_brdf(const unsigned char *p, prt_brdf *b)
{
    float f[38];
    memset(b, 0, sizeof *b);
    b->model = (prt_brdf_model)get32(p);
    b->lobes = (int)get32(p + 4);
    memcpy(f, p + 8, sizeof f);
    memcpy(b->diffuse, f, 12);
    memcpy(b->specular, f + 3, 12);
    b->exponent = f[6];
    b->exponent_v = f[7];
    memcpy(b->cxy, f + 8, 36);
    memcpy(b->cz, f + 17, 36);
    memcpy(b->n, f + 26, 36);
}

static uint32_t chunk_crc(const chunk *c)
{
    /* One running CRC over the concatenated parts, without copying them together. */
    uLong crc = crc32(0L, Z_NULL, 0);
    for (int i = 0; i < PARTS && c->parts[i]; ++i) {
        const unsigned char *p = c->parts[i];
        if (!c->sizes[i]) continue;
        size_t n = c->sizes[i];
        while (n) {
            unsigned int k = n > 0x40000000u ? 0x40000000u : (unsigned int)n;
            crc = crc32(crc, p, k);
            p += k;
            n -= k;
        }
    }
    return (uint32_t)crc;
}

prt_status prt_transfer_save(const prt_transfer *t, const char *path)
{
    if (!t || !path) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_save: transfer and path are required");
    const prt__mesh *m = &t->mesh;
    cJSON *meta = cJSON_CreateObject();
    cJSON_AddStringToObject(meta, "method", t->wavelet ? "wavelet" : "sh");
    cJSON_AddStringToObject(meta, "prt_version", prt_version_string());
    cJSON_AddNumberToObject(meta, "order", t->order);
    cJSON_AddNumberToObject(meta, "samples", t->samples);
    cJSON_AddNumberToObject(meta, "bounces", t->bounces);
    cJSON_AddNumberToObject(meta, "seed", t->seed);
    cJSON_AddNumberToObject(meta, "threads", t->threads);
    cJSON_AddNumberToObject(meta, "bake_seconds", t->bake_seconds);
    cJSON_AddStringToObject(meta, "source", t->source);
    if (t->glossy_exit) cJSON_AddBoolToObject(meta, "glossy_exit", 1);
    if (t->has_env) {
        cJSON *e = cJSON_AddObjectToObject(meta, "environment");
        cJSON_AddStringToObject(e, "file", t->env.path);
        cJSON_AddNumberToObject(e, "layout", t->env.layout);
        cJSON_AddItemToObject(e, "rotate", cJSON_CreateFloatArray(t->env.rotate_deg, 3));
        cJSON_AddItemToObject(e, "sun", cJSON_CreateFloatArray(t->env.sun_dir, 3));
        cJSON_AddNumberToObject(e, "intensity", t->env.intensity);
    }
    char *meta_text = cJSON_PrintUnformatted(meta);
    cJSON_Delete(meta);
    if (!meta_text) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");

    chunk chunks[11 + PRT__KIND_COUNT + PRT__MAX_BRDFS];
    void *qbuf[2 * PRT__KIND_COUNT + 1];   /* quantized copies, freed after writing */
    int nqbuf = 0;
    memset(chunks, 0, sizeof chunks);
    int count = 0;
    chunks[count++] = (chunk){CHUNK_META, {meta_text}, {strlen(meta_text)}, 0};
    unsigned char mesh_head[16], set_head[PRT__KIND_COUNT][CPCA_HEADER];
    put64(mesh_head, m->vertex_count);
    put64(mesh_head + 8, m->triangle_count);
    size_t v3 = m->vertex_count * 3 * sizeof(float);
    chunks[count++] = (chunk){CHUNK_MESH, {mesh_head, m->positions, m->normals, m->albedo, m->indices},
                              {16, v3, v3, v3, m->triangle_count * 3 * sizeof(uint32_t)}, 0};
    for (int k = 0; k < PRT__KIND_COUNT; ++k) {
        const prt__sh_set *s = &t->sets[k];
        if (!s->channels) continue;
        unsigned char *h = set_head[k];
        memset(h, 0, CPCA_HEADER);
        put32(h, (uint32_t)prt__kind_from_index(k));
        put32(h + 4, (uint32_t)s->channels);
        put32(h + 8, (uint32_t)t->order);
        if (!s->cpca) {
            const size_t dim = prt__set_dim(t, k), n = m->vertex_count * dim;
            put64(h + 16, m->vertex_count);
            if (!s->quant_bits) {
                chunks[count++] = (chunk){CHUNK_SHTR, {h, s->coeffs}, {24, n * sizeof(float)}, 0};
                continue;
            }
            /* Quantized: scale[dim], bias[dim], then the integers, padded to 4 bytes. */
            put32(h + 12, (uint32_t)s->quant_bits);
            const size_t qbytes = n * (size_t)(s->quant_bits / 8), padded = (qbytes + 3) & ~(size_t)3;
            float *grid = malloc(2 * dim * sizeof(float));
            unsigned char *q = calloc(padded ? padded : 1, 1);
            if (!grid || !q) { free(grid); free(q); cJSON_free(meta_text); for (int i = 0; i < nqbuf; ++i) free(qbuf[i]); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
            prt__quant_grid(s->coeffs, m->vertex_count, (int)dim, s->quant_bits, grid, grid + dim);
            for (size_t i = 0; i < n; ++i) {
                size_t j = i % dim;
                float l = grid[j] > 0 ? roundf((s->coeffs[i] - grid[dim + j]) / grid[j]) : 0.0f;
                uint32_t u = (uint32_t)fminf(fmaxf(l, 0.0f), (float)((1u << s->quant_bits) - 1));
                if (s->quant_bits == 8) q[i] = (unsigned char)u;
                else { uint16_t w = (uint16_t)u; memcpy(q + 2 * i, &w, 2); }
            }
            qbuf[nqbuf++] = grid;
            qbuf[nqbuf++] = q;
            chunks[count++] = (chunk){CHUNK_SHTR, {h, grid, q}, {24, 2 * dim * sizeof(float), padded}, 0};
            continue;
        }
        const prt__cpca *c = s->cpca;
        put32(h + 12, (uint32_t)c->method);
        put32(h + 16, (uint32_t)c->clusters);
        put32(h + 20, (uint32_t)c->dim);
        put64(h + 24, m->vertex_count);
        put64(h + 32, c->vectors_total);
        put64(h + 40, c->weights_total);
        memcpy(h + 48, &c->rms_error, 8);
        memcpy(h + 56, &c->relative_error, 8);
        size_t dim = (size_t)c->dim;
        chunks[count++] = (chunk){CHUNK_CPCA, {h, c->counts, c->means, c->basis, c->cluster_of, c->weights},
                                  {CPCA_HEADER, (size_t)c->clusters * 4, (size_t)c->clusters * dim * 4, c->vectors_total * dim * 4,
                                   m->vertex_count * 4, c->weights_total * 4}, 0};
    }
    unsigned char *matl = NULL;
    if (t->brdf_count) {
        /* count, pad, the BRDF records, then one material id per vertex padded to 8 bytes. */
        size_t bytes = 8 + (size_t)t->brdf_count * BRDF_RECORD + ((m->vertex_count + 7) & ~(size_t)7);
        matl = calloc(bytes, 1);
        if (!matl) { cJSON_free(meta_text); for (int i = 0; i < nqbuf; ++i) free(qbuf[i]); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
        put32(matl, (uint32_t)t->brdf_count);
        for (int k = 0; k < t->brdf_count; ++k) put_brdf(matl + 8 + (size_t)k * BRDF_RECORD, &t->brdfs[k]);
        if (m->material) memcpy(matl + 8 + (size_t)t->brdf_count * BRDF_RECORD, m->material, m->vertex_count);
        qbuf[nqbuf++] = matl;
        chunks[count++] = (chunk){CHUNK_MATL, {matl}, {bytes}, 0};
    }
    if (prt__mesh_has_uv(m)) chunks[count++] = (chunk){CHUNK_UVS, {m->uv}, {m->vertex_count * 2 * sizeof(float)}, 0};
    const prt__texel_sets *tx = &t->texels;
    unsigned char txal_head[8], txls_head[3][24];
    static const unsigned char pad4[4] = {0};
    if (tx->width) {
        const size_t ntex = (size_t)tx->width * tx->height;
        put32(txal_head, (uint32_t)tx->width);
        put32(txal_head + 4, (uint32_t)tx->height);
        chunks[count++] = (chunk){CHUNK_TXAL, {txal_head, tx->albedo, tx->covered, pad4}, {8, ntex * 12, ntex, ((ntex + 3) & ~(size_t)3) - ntex}, 0};
        for (int k = 0; k < 3; ++k) {
            if (!tx->coeffs[k]) continue;
            unsigned char *h = txls_head[k];
            memset(h, 0, 24);
            put32(h, (uint32_t)prt__kind_from_index(k));
            put32(h + 4, (uint32_t)tx->channels[k]);
            put32(h + 8, (uint32_t)t->order);
            put32(h + 12, (uint32_t)tx->width);
            put32(h + 16, (uint32_t)tx->height);
            chunks[count++] = (chunk){CHUNK_TXLS, {h, tx->coeffs[k]}, {24, ntex * (size_t)tx->channels[k] * t->order * t->order * 4}, 0};
        }
    }
    unsigned char wavp_head[WAVP_HEADER], wbrf_head[PRT__MAX_BRDFS][WBRF_HEADER];
    const prt__wavelet_set *ws = t->wavelet;
    if (ws) {
        /* Parameters, then one term count per vertex padded to 8 bytes. */
        const prt__sparse_store *ss = &ws->store;
        memset(wavp_head, 0, sizeof wavp_head);
        const uint32_t p32[8] = {(uint32_t)ws->terms, (uint32_t)ss->n, (uint32_t)ss->bits, (uint32_t)ws->supersample,
                                 (uint32_t)ws->bounces, (uint32_t)ws->gather_resolution, (uint32_t)ws->brdf_resolution, (uint32_t)ws->param};
        for (int i = 0; i < 8; ++i) put32(wavp_head + 4 * i, p32[i]);
        put64(wavp_head + 32, ss->vectors);
        put64(wavp_head + 40, m->vertex_count);
        static const unsigned char zero8[8] = {0};
        chunks[count++] = (chunk){CHUNK_WAVP, {wavp_head, ws->term_count, zero8}, {WAVP_HEADER, m->vertex_count, ((m->vertex_count + 7) & ~(size_t)7) - m->vertex_count}, 0};
        for (int k = 0; k < PRT__MAX_BRDFS; ++k) {
            const prt_brdf_factors *f = ws->factors[k];
            if (!f) continue;
            unsigned char *h = wbrf_head[k];
            memset(h, 0, WBRF_HEADER);
            put32(h, (uint32_t)(k + 1));
            put32(h + 4, (uint32_t)f->terms);
            put32(h + 8, (uint32_t)f->computed);
            put32(h + 12, (uint32_t)f->resolution);
            put32(h + 16, (uint32_t)f->param);
            for (int c = 0; c < 3; ++c) memcpy(h + 24 + (size_t)c * PRT_BRDF_MAX_TERMS * 4, f->sigma[c], PRT_BRDF_MAX_TERMS * 4);
            size_t maps = (size_t)3 * f->computed * f->resolution * f->resolution * sizeof(float);
            chunks[count++] = (chunk){CHUNK_WBRF, {h, f->light, f->view}, {WBRF_HEADER, maps, maps}, 0};
        }
        const size_t cells = ss->vectors * (size_t)ss->n, ib = cells * 2, vb = cells * 3 * (size_t)(ss->bits / 8);
        static const unsigned char zero4[4] = {0};
        chunks[count++] = (chunk){CHUNK_WAVT, {ss->index, zero4, ss->values, zero4, ss->scale},
                                  {ib, ((ib + 3) & ~(size_t)3) - ib, vb, ((vb + 3) & ~(size_t)3) - vb, ss->vectors * 12}, 0};
    }
    unsigned char head[HEADER_SIZE + ENTRY_SIZE * (11 + PRT__KIND_COUNT + PRT__MAX_BRDFS)];
    memset(head, 0, sizeof head);
    memcpy(head, MAGIC, 8);
    put32(head + 8, FILE_VERSION);
    put32(head + 12, (uint32_t)count);
    size_t table_end = HEADER_SIZE + (size_t)ENTRY_SIZE * count, offset = (table_end + 7) & ~(size_t)7;
    for (int i = 0; i < count; ++i) {
        chunk *c = &chunks[i];
        for (int p = 0; p < PARTS; ++p) c->size += c->sizes[p];
        unsigned char *e = head + HEADER_SIZE + ENTRY_SIZE * i;
        put32(e, c->id);
        put32(e + 4, chunk_crc(c));
        put64(e + 8, offset);
        put64(e + 16, c->size);
        offset = (offset + c->size + 7) & ~(size_t)7;
    }
    put32(head + 20, 0);
    put32(head + 20, prt__crc32(head, table_end));   /* over the header (crc field zero) and the table */

    prt__atomic_file f;
    prt_status st = prt__atomic_open(&f, path);
    if (st) { cJSON_free(meta_text); for (int i = 0; i < nqbuf; ++i) free(qbuf[i]); return st; }
    static const unsigned char zeros[8] = {0};
    st = prt__atomic_write(&f, head, table_end);
    size_t pos = table_end;
    for (int i = 0; i < count && !st; ++i) {
        size_t pad = ((pos + 7) & ~(size_t)7) - pos;
        st = prt__atomic_write(&f, zeros, pad);
        pos += pad;
        for (int p = 0; p < PARTS && !st; ++p)
            if (chunks[i].parts[p]) st = prt__atomic_write(&f, chunks[i].parts[p], chunks[i].sizes[p]);
        pos += chunks[i].size;
    }
    cJSON_free(meta_text);
    for (int i = 0; i < nqbuf; ++i) free(qbuf[i]);
    if (st) { prt__atomic_abort(&f); return st; }
    return prt__atomic_commit(&f);
}

static prt_status bad(prt_context *ctx, const char *msg)
{
    return prt__fail(ctx, PRT_ERR_FORMAT, "%s", msg);
}

static bool all_finite(const float *p, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(p[i])) return false;
    return true;
}

/* Wavelet chunks: WAVP (parameters, per-vertex term counts) comes in pass 1, WBRF (one
 * factorization per glossy material) and WAVT (the sparse vectors) in pass 2. */
static prt_status read_wavelet_chunk(prt_context *ctx, prt_transfer *t, uint32_t id, const unsigned char *p, uint64_t len)
{
    const uint64_t nv = t->mesh.vertex_count;
    prt__wavelet_set *w = t->wavelet;
    if (id == CHUNK_WAVP) {
        if (w || len < WAVP_HEADER || get64(p + 40) != nv || WAVP_HEADER + ((nv + 7) & ~7ull) != len)
            return bad(ctx, "corrupt .prt file: invalid wavelet parameter chunk");
        uint32_t terms = get32(p), n = get32(p + 4), bits = get32(p + 8), param = get32(p + 28);
        uint64_t vectors = get64(p + 32);
        if (terms < 1 || terms > PRT_BRDF_MAX_TERMS || n < 1 || n > PRT_WAVELET_DIM || (bits != 8 && bits != 16) || param > PRT_BRDF_PARAM_POLAR ||
            vectors < nv || vectors > nv * PRT_BRDF_MAX_TERMS)
            return bad(ctx, "corrupt .prt file: wavelet parameters out of range");
        w = t->wavelet = prt__calloc(1, sizeof *w);
        if (!w) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        w->terms = (int)terms;
        w->supersample = (int)get32(p + 12);
        w->bounces = (int)get32(p + 16);
        w->gather_resolution = (int)get32(p + 20);
        w->brdf_resolution = (int)get32(p + 24);
        w->param = (prt_brdf_param)param;
        w->term_count = malloc(nv);
        w->vec_start = malloc((nv + 1) * sizeof(size_t));
        if (!w->term_count || !w->vec_start) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(w->term_count, p + WAVP_HEADER, nv);
        size_t total = 0;
        if (!prt__wavelet_index(w, nv, &total) || total != vectors) return bad(ctx, "corrupt .prt file: wavelet term counts are inconsistent");
        w->store.n = (int)n;
        w->store.bits = (int)bits;
        w->store.dim = PRT_WAVELET_DIM;
        w->store.vectors = vectors;
        return PRT_OK;
    }
    if (!w) return bad(ctx, "corrupt .prt file: wavelet data without its parameter chunk");
    if (id == CHUNK_WBRF) {
        if (len < WBRF_HEADER) return bad(ctx, "corrupt .prt file: short BRDF factorization chunk");
        uint32_t k = get32(p), terms = get32(p + 4), computed = get32(p + 8), res = get32(p + 12), param = get32(p + 16);
        uint64_t maps = (uint64_t)3 * computed * res * res * 4;
        if (k < 1 || k > PRT__MAX_BRDFS || w->factors[k - 1] || terms < 1 || terms > computed || computed > PRT_BRDF_MAX_TERMS || res < 4 ||
            res > 96 || param > PRT_BRDF_PARAM_POLAR || WBRF_HEADER + 2 * maps != len)
            return bad(ctx, "corrupt .prt file: invalid BRDF factorization chunk");
        prt_brdf_factors *f = prt__brdf_factors_alloc((int)terms, (int)computed, (int)res, (prt_brdf_param)param);
        if (!f) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        for (int c = 0; c < 3; ++c) memcpy(f->sigma[c], p + 24 + (size_t)c * PRT_BRDF_MAX_TERMS * 4, PRT_BRDF_MAX_TERMS * 4);
        memcpy(f->light, p + WBRF_HEADER, maps);
        memcpy(f->view, p + WBRF_HEADER + maps, maps);
        prt__brdf_factors_finish(f);
        w->factors[k - 1] = f;
        if (!all_finite(f->light, maps / 4) || !all_finite(f->view, maps / 4)) return bad(ctx, "corrupt .prt file: non-finite BRDF maps");
        return PRT_OK;
    }
    prt__sparse_store *s = &w->store;
    if (s->index) return bad(ctx, "corrupt .prt file: two wavelet transfer chunks");
    const uint64_t cells = (uint64_t)s->vectors * s->n, ib = cells * 2, vb = cells * 3 * (uint64_t)(s->bits / 8);
    if (((ib + 3) & ~3ull) + ((vb + 3) & ~3ull) + s->vectors * 12 != len) return bad(ctx, "corrupt .prt file: wavelet transfer chunk size mismatch");
    int n = s->n, bits = s->bits;
    size_t vectors = s->vectors;
    prt_status st = prt__sparse_alloc(s, vectors, n, bits, PRT_WAVELET_DIM);
    if (st) return prt__fail(ctx, st, "out of memory");
    memcpy(s->index, p, ib);
    memcpy(s->values, p + ((ib + 3) & ~3ull), vb);
    memcpy(s->scale, p + ((ib + 3) & ~3ull) + ((vb + 3) & ~3ull), vectors * 12);
    for (uint64_t i = 0; i < cells; ++i)
        if (s->index[i] >= PRT_WAVELET_DIM) return bad(ctx, "corrupt .prt file: a wavelet index is out of range");
    if (!all_finite(s->scale, vectors * 3)) return bad(ctx, "corrupt .prt file: non-finite wavelet scales");
    return PRT_OK;
}

/* Every vertex's term count must match its material's factorization. */
static prt_status check_wavelet(prt_context *ctx, const prt_transfer *t)
{
    const prt__wavelet_set *w = t->wavelet;
    if (!w->store.index) return bad(ctx, "corrupt .prt file: wavelet transfer chunk missing");
    for (size_t v = 0; v < t->mesh.vertex_count; ++v) {
        uint8_t mat = t->mesh.material[v];
        const prt_brdf_factors *f = mat ? w->factors[mat - 1] : NULL;
        if (w->term_count[v] != (f ? f->terms : 1)) return bad(ctx, "corrupt .prt file: wavelet term counts do not match the materials");
    }
    return PRT_OK;
}

prt_status prt_transfer_load_memory(prt_context *ctx, const void *data, size_t size, prt_transfer **out)
{
    if (!out || (!data && size)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_load_memory: data and out are required");
    *out = NULL;
    const unsigned char *b = data;
    if (size < HEADER_SIZE || memcmp(b, MAGIC, 8) != 0) return bad(ctx, "not a .prt file (bad magic number)");
    uint32_t version = get32(b + 8), count = get32(b + 12);
    if (version > FILE_VERSION) {
        return prt__fail(ctx, PRT_ERR_FORMAT, "file format version %u is newer than this prt supports (%d): upgrade prt", version, FILE_VERSION);
    }
    if (version < 1) return prt__fail(ctx, PRT_ERR_FORMAT, "file format version %u is not a valid .prt version", version);
    if (count == 0 || count > MAX_CHUNKS) return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %u chunks", count);
    size_t table_end = HEADER_SIZE + (size_t)ENTRY_SIZE * count;
    if (table_end > size) return bad(ctx, "truncated .prt file (chunk table cut off)");
    unsigned char *head = malloc(table_end);
    if (!head) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(head, b, table_end);
    uint32_t stored = get32(head + 20);
    put32(head + 20, 0);
    uint32_t actual = prt__crc32(head, table_end);
    free(head);
    if (stored != actual) return bad(ctx, "corrupt .prt file: header checksum mismatch");

    prt_transfer *t = prt__calloc(1, sizeof *t);
    if (!t) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = PRT_OK;
    bool have_meta = false, have_mesh = false;
    /* Two passes: the mesh fixes the vertex count that transfer chunks must match. */
    for (int pass = 0; pass < 3 && !st; ++pass) {
        for (uint32_t i = 0; i < count && !st; ++i) {
            const unsigned char *e = b + HEADER_SIZE + (size_t)ENTRY_SIZE * i;
            uint32_t id = get32(e), crc = get32(e + 4);
            uint64_t off = get64(e + 8), len = get64(e + 16);
            if (off > size || len > size - off) { st = bad(ctx, "truncated .prt file: a chunk extends past the end"); break; }
            const unsigned char *p = b + off;
            bool mine = pass == 0   ? (id == CHUNK_META || id == CHUNK_MESH)
                        : pass == 1 ? (id == CHUNK_SHTR || id == CHUNK_CPCA || id == CHUNK_MATL || id == CHUNK_UVS || id == CHUNK_TXAL ||
                                       id == CHUNK_WAVP)
                                    : (id == CHUNK_TXLS || id == CHUNK_WBRF || id == CHUNK_WAVT);
            if (!mine) continue;
            if (prt__crc32(p, (size_t)len) != crc) {
                char what[5] = {(char)(id & 255), (char)(id >> 8 & 255), (char)(id >> 16 & 255), (char)(id >> 24), 0};
                st = prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: checksum mismatch in chunk %s", what);
                break;
            }
            if (id == CHUNK_META) {
                cJSON *meta = cJSON_ParseWithLength((const char *)p, (size_t)len);
                const cJSON *method = cJSON_GetObjectItemCaseSensitive(meta, "method");
                if (!meta || !cJSON_IsString(method)) { cJSON_Delete(meta); st = bad(ctx, "corrupt .prt file: unreadable metadata"); break; }
                if (strcmp(method->valuestring, "sh") != 0 && strcmp(method->valuestring, "wavelet") != 0) {
                    st = prt__fail(ctx, PRT_ERR_FORMAT, "this prt cannot read method '%.64s'", method->valuestring);
                    cJSON_Delete(meta);
                    break;
                }
                const cJSON *x;
                if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "samples"))) t->samples = x->valueint;
                if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "bounces"))) t->bounces = x->valueint;
                if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "seed"))) t->seed = (uint32_t)x->valuedouble;
                if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "threads"))) t->threads = x->valueint;
                if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "bake_seconds"))) t->bake_seconds = x->valuedouble;
                if (cJSON_IsString(x = cJSON_GetObjectItemCaseSensitive(meta, "source"))) snprintf(t->source, sizeof t->source, "%s", x->valuestring);
                t->glossy_exit = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(meta, "glossy_exit"));
                if (cJSON_IsObject(x = cJSON_GetObjectItemCaseSensitive(meta, "environment"))) {
                    const cJSON *f = cJSON_GetObjectItemCaseSensitive(x, "file"), *l = cJSON_GetObjectItemCaseSensitive(x, "layout"),
                                *r = cJSON_GetObjectItemCaseSensitive(x, "rotate"), *s = cJSON_GetObjectItemCaseSensitive(x, "sun"),
                                *in = cJSON_GetObjectItemCaseSensitive(x, "intensity");
                    t->has_env = true;
                    if (cJSON_IsString(f)) snprintf(t->env.path, sizeof t->env.path, "%s", f->valuestring);
                    if (cJSON_IsNumber(l) && l->valueint >= 0 && l->valueint <= PRT_ENV_VCROSS) t->env.layout = (prt_env_layout)l->valueint;
                    for (int k = 0; k < 3; ++k) {
                        const cJSON *a = cJSON_GetArrayItem(r, k), *b = cJSON_GetArrayItem(s, k);
                        if (cJSON_IsNumber(a)) t->env.rotate_deg[k] = (float)a->valuedouble;
                        if (cJSON_IsNumber(b)) t->env.sun_dir[k] = (float)b->valuedouble;
                    }
                    if (cJSON_IsNumber(in) && in->valuedouble >= 0) t->env.intensity = (float)in->valuedouble;
                }
                cJSON_Delete(meta);
                have_meta = true;
            } else if (id == CHUNK_MESH) {
                if (have_mesh || len < 16) { st = bad(ctx, "corrupt .prt file: bad mesh chunk"); break; }
                uint64_t nv = get64(p), nt = get64(p + 8);
                /* Bound the counts by the chunk's length before any arithmetic can overflow. */
                if (nv == 0 || nt == 0 || nv > len / 36 || nt > len / 12 || 16 + nv * 36 + nt * 12 != len) {
                    st = bad(ctx, "corrupt .prt file: mesh chunk sizes are inconsistent");
                    break;
                }
                prt__mesh *m = &t->mesh;
                m->positions = malloc(nv * 12); m->normals = malloc(nv * 12); m->albedo = malloc(nv * 12);
                m->indices = malloc(nt * 12);
                m->material = calloc(nv, 1);
                m->uv = malloc(nv * 8);
                if (m->uv) for (uint64_t k = 0; k < nv * 2; ++k) m->uv[k] = NAN;
                if (!m->positions || !m->normals || !m->albedo || !m->indices || !m->material || !m->uv) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
                memcpy(m->positions, p + 16, nv * 12);
                memcpy(m->normals, p + 16 + nv * 12, nv * 12);
                memcpy(m->albedo, p + 16 + nv * 24, nv * 12);
                memcpy(m->indices, p + 16 + nv * 36, nt * 12);
                m->vertex_count = nv;
                m->triangle_count = nt;
                for (uint64_t k = 0; k < nt * 3; ++k)
                    if (m->indices[k] >= nv) { st = bad(ctx, "corrupt .prt file: a triangle index is out of range"); break; }
                if (!st && !(all_finite(m->positions, nv * 3) && all_finite(m->normals, nv * 3) && all_finite(m->albedo, nv * 3)))
                    st = bad(ctx, "corrupt .prt file: non-finite vertex data");
                have_mesh = true;
            } else if (id == CHUNK_UVS) {
                uint64_t nv = t->mesh.vertex_count;
                if (len != nv * 8) { st = bad(ctx, "corrupt .prt file: texture coordinate chunk size mismatch"); break; }
                memcpy(t->mesh.uv, p, nv * 8);
                if (!prt__mesh_has_uv(&t->mesh)) { st = bad(ctx, "corrupt .prt file: non-finite texture coordinates"); break; }
            } else if (id == CHUNK_TXAL) {
                uint32_t w = len >= 8 ? get32(p) : 0, h = len >= 8 ? get32(p + 4) : 0;
                uint64_t ntex = (uint64_t)w * h;
                if (t->texels.width || w == 0 || h == 0 || w > 8192 || h > 8192 || 8 + ntex * 12 + ((ntex + 3) & ~3ull) != len) {
                    st = bad(ctx, "corrupt .prt file: invalid texel albedo chunk");
                    break;
                }
                t->texels.albedo = malloc(ntex * 12);
                t->texels.covered = malloc(ntex);
                if (!t->texels.albedo || !t->texels.covered) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
                memcpy(t->texels.albedo, p + 8, ntex * 12);
                memcpy(t->texels.covered, p + 8 + ntex * 12, ntex);
                t->texels.width = (int)w;
                t->texels.height = (int)h;
                if (!all_finite(t->texels.albedo, ntex * 3)) { st = bad(ctx, "corrupt .prt file: non-finite texel albedo"); break; }
            } else if (id == CHUNK_TXLS) {
                uint32_t kind = len >= 24 ? get32(p) : 0, channels = len >= 24 ? get32(p + 4) : 0, order = len >= 24 ? get32(p + 8) : 0;
                uint32_t w = len >= 24 ? get32(p + 12) : 0, h = len >= 24 ? get32(p + 16) : 0;
                int k = prt__kind_index((prt_transfer_kind)kind);
                uint64_t n = (uint64_t)w * h * channels * order * order;
                if (k < 0 || k > 2 || (channels != 1 && channels != 3) || (int)order != t->order || (int)w != t->texels.width ||
                    (int)h != t->texels.height || !w || t->texels.coeffs[k] || 24 + n * 4 != len) {
                    st = bad(ctx, "corrupt .prt file: invalid texel transfer chunk");
                    break;
                }
                if (!(t->texels.coeffs[k] = malloc(n * 4))) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
                memcpy(t->texels.coeffs[k], p + 24, n * 4);
                t->texels.channels[k] = (int)channels;
            } else if (id == CHUNK_WAVP || id == CHUNK_WBRF || id == CHUNK_WAVT) {
                st = read_wavelet_chunk(ctx, t, id, p, len);
            } else if (id == CHUNK_MATL) {
                uint64_t nv = t->mesh.vertex_count;
                uint32_t nb = len >= 8 ? get32(p) : 0;
                if (!have_mesh || t->brdf_count || nb == 0 || nb > PRT__MAX_BRDFS ||
                    8 + (uint64_t)nb * BRDF_RECORD + ((nv + 7) & ~7ull) != len) {
                    st = bad(ctx, "corrupt .prt file: invalid material chunk");
                    break;
                }
                for (uint32_t k = 0; k < nb && !st; ++k) {
                    get_brdf(p + 8 + (size_t)k * BRDF_RECORD, &t->brdfs[k]);
                    if (prt_brdf_validate(&t->brdfs[k])) st = bad(ctx, "corrupt .prt file: invalid BRDF in the material chunk");
                }
                if (st) break;
                t->brdf_count = (int)nb;
                memcpy(t->mesh.material, p + 8 + (size_t)nb * BRDF_RECORD, nv);
                for (uint64_t v = 0; v < nv; ++v)
                    if (t->mesh.material[v] > nb) { st = bad(ctx, "corrupt .prt file: a material id is out of range"); break; }
            } else if (id == CHUNK_CPCA) {
                if (!have_mesh || len < CPCA_HEADER) { st = bad(ctx, "corrupt .prt file: bad compressed transfer chunk"); break; }
                uint32_t kind = get32(p), channels = get32(p + 4), order = get32(p + 8), method = get32(p + 12);
                uint32_t clusters = get32(p + 16), dim = get32(p + 20);
                uint64_t nv = get64(p + 24), nvec = get64(p + 32), nw = get64(p + 40);
                int k = prt__kind_index((prt_transfer_kind)kind);
                /* Every count is bounded by the chunk's own length before it sizes anything. */
                if (k < 0 || (channels != 1 && channels != 3) || order < 1 || order > PRT_SH_MAX_ORDER || method > PRT_COMPRESS_VQ ||
                    dim != channels * order * order * (prt__kind_glossy(k) ? order * order : 1) || nv != t->mesh.vertex_count || (t->order && (int)order != t->order) ||
                    t->sets[k].channels || clusters == 0 || clusters > len / 4 || nvec > len / 4 || nw > len / 4 ||
                    (uint64_t)clusters * dim > len / 4 || nvec * dim > len / 4 ||
                    CPCA_HEADER + 4 * ((uint64_t)clusters + (uint64_t)clusters * dim + nvec * dim + nv + nw) != len) {
                    st = bad(ctx, "corrupt .prt file: invalid compressed transfer chunk");
                    break;
                }
                prt__cpca *c = prt__calloc(1, sizeof *c);
                if (c) {
                    c->method = (prt_compress_method)method;
                    c->clusters = (int)clusters;
                    c->dim = (int)dim;
                    c->vectors_total = nvec;
                    c->weights_total = nw;
                    memcpy(&c->rms_error, p + 48, 8);
                    memcpy(&c->relative_error, p + 56, 8);
                    c->counts = malloc(clusters * 4ull);
                    c->means = malloc((size_t)clusters * dim * 4);
                    c->basis = malloc(nvec * dim * 4 + 4);
                    c->cluster_of = malloc(nv * 4);
                    c->weights = malloc(nw * 4 + 4);
                }
                if (!c || !c->counts || !c->means || !c->basis || !c->cluster_of || !c->weights) {
                    prt__cpca_free(c);
                    st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
                    break;
                }
                const unsigned char *q = p + CPCA_HEADER;
                memcpy(c->counts, q, clusters * 4ull); q += clusters * 4ull;
                memcpy(c->means, q, (size_t)clusters * dim * 4); q += (size_t)clusters * dim * 4;
                memcpy(c->basis, q, nvec * dim * 4); q += nvec * dim * 4;
                memcpy(c->cluster_of, q, nv * 4); q += nv * 4;
                memcpy(c->weights, q, nw * 4);
                if (!prt__cpca_index(c, nv)) {
                    prt__cpca_free(c);
                    st = bad(ctx, "corrupt .prt file: compressed transfer indices are inconsistent");
                    break;
                }
                t->order = (int)order;
                t->sets[k].channels = (int)channels;
                t->sets[k].cpca = c;
            } else {
                if (!have_mesh) { st = bad(ctx, "corrupt .prt file: transfer without a mesh"); break; }
                if (len < 24) { st = bad(ctx, "corrupt .prt file: short transfer chunk"); break; }
                uint32_t kind = get32(p), channels = get32(p + 4), order = get32(p + 8);
                uint64_t nv = get64(p + 16);
                int k = prt__kind_index((prt_transfer_kind)kind);
                if (k < 0 || (channels != 1 && channels != 3) || order < 1 || order > PRT_SH_MAX_ORDER || nv != t->mesh.vertex_count ||
                    (t->order && (int)order != t->order) || t->sets[k].channels) {
                    st = bad(ctx, "corrupt .prt file: invalid transfer chunk header");
                    break;
                }
                uint32_t bits = get32(p + 12);
                uint64_t dim = (uint64_t)channels * order * order * (prt__kind_glossy(k) ? order * order : 1), n = nv * dim;
                uint64_t need = bits == 0 ? 24 + n * 4 : 24 + 8 * dim + ((n * (bits / 8) + 3) & ~3ull);
                if ((bits != 0 && bits != 8 && bits != 16) || n > len || need != len) { st = bad(ctx, "corrupt .prt file: transfer chunk size mismatch"); break; }
                float *c = malloc(n * 4);
                if (!c) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
                if (bits == 0) {
                    memcpy(c, p + 24, n * 4);
                } else {
                    const unsigned char *grid = p + 24, *q = p + 24 + 8 * dim;
                    for (uint64_t i = 0; i < n; ++i) {
                        uint64_t j = i % dim;
                        float scale, bias;
                        memcpy(&scale, grid + 4 * j, 4);
                        memcpy(&bias, grid + 4 * (dim + j), 4);
                        uint32_t u = q[i];
                        if (bits == 16) { uint16_t w; memcpy(&w, q + 2 * i, 2); u = w; }
                        c[i] = bias + (float)u * scale;
                    }
                }
                t->sets[k].quant_bits = (int)bits;
                t->order = (int)order;
                t->sets[k].channels = (int)channels;
                t->sets[k].coeffs = c;
            }
        }
    }
    if (!st && (!have_meta || !have_mesh)) st = bad(ctx, "corrupt .prt file: metadata or mesh chunk missing");
    if (!st && t->wavelet) st = check_wavelet(ctx, t);
    if (!st && !t->order && !t->wavelet) st = bad(ctx, ".prt file holds no transfer");
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}

prt_status prt_transfer_load(prt_context *ctx, const char *path, prt_transfer **out)
{
    void *data;
    size_t size;
    if (out) *out = NULL;
    prt_status st = prt__read_file(path, &data, &size);
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    st = prt_transfer_load_memory(ctx, data, size, out);
    free(data);
    if (st) {
        char msg[900];
        snprintf(msg, sizeof msg, "%s", prt_last_error());
        return prt__fail(ctx, st, "'%s': %s", path, msg);
    }
    return PRT_OK;
}
