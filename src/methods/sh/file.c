/* The spherical-harmonic method's chunks in .prt files (docs/FORMAT.md): what it writes beside the
 * method-independent ones (transfer/file.c), and their loading, every count checked against the
 * chunk's size, the mesh and every other count before it sizes an allocation. */
#include "methods/sh/sh.h"

#define CHUNK_SHTR PRT__FOURCC('S', 'H', 'T', 'R')
#define CHUNK_CPCA PRT__FOURCC('C', 'P', 'C', 'A')
#define CHUNK_TXAL PRT__FOURCC('T', 'X', 'A', 'L')
#define CHUNK_TXLS PRT__FOURCC('T', 'X', 'L', 'S')
#define CHUNK_TXLH PRT__FOURCC('T', 'X', 'L', 'H')   /* the same as halves */
#define CHUNK_TXLQ PRT__FOURCC('T', 'X', 'L', 'Q')   /* the same as bytes, a scale and bias per coefficient */
#define CHUNK_NBHD PRT__FOURCC('N', 'B', 'H', 'D')   /* neighbourhood transfer */
#define NBHD_HEADER 40
#define CHUNK_VOLU PRT__FOURCC('V', 'O', 'L', 'U')   /* transfer in a participating medium, one per volume */
#define VOLU_HEADER 68
#define CHUNK_FRMS PRT__FOURCC('F', 'R', 'M', 'S')   /* key frames' poses */
#define CHUNK_FRCP PRT__FOURCC('F', 'R', 'C', 'P')   /* a set's rows of every key frame, one CPCA */
#define CPCA_HEADER 64
#define FRMS_HEADER 16

void prt__sh_save_meta(const prt_transfer *t, cJSON *meta)
{
    const prt__sh_state *s = t->state;
    cJSON_AddNumberToObject(meta, "order", s->order);
    cJSON_AddNumberToObject(meta, "samples", s->samples);
    cJSON_AddNumberToObject(meta, "bounces", s->bounces);
    cJSON_AddNumberToObject(meta, "seed", s->seed);
    if (s->glossy_exit) cJSON_AddBoolToObject(meta, "glossy_exit", 1);
}

/* A CPCA chunk of `rows` rows; h: its header, kind, channels and order filled in. */
static void save_cpca(prt__chunk_list *l, uint32_t id, unsigned char *h, const prt__cpca *c, size_t rows)
{
    prt__put32(h + 12, (uint32_t)c->method);
    prt__put32(h + 16, (uint32_t)c->clusters);
    prt__put32(h + 20, (uint32_t)c->dim);
    prt__put64(h + 24, rows);
    prt__put64(h + 32, c->vectors_total);
    prt__put64(h + 40, c->weights_total);
    memcpy(h + 48, &c->rms_error, 8);
    memcpy(h + 56, &c->relative_error, 8);
    const size_t dim = (size_t)c->dim;
    prt__chunks_add(l, id, h, (size_t)CPCA_HEADER, c->counts, (size_t)c->clusters * 4, c->means, (size_t)c->clusters * dim * 4, c->basis,
                    c->vectors_total * dim * 4, c->cluster_of, rows * 4, c->weights, c->weights_total * 4, NULL);
}

/* Key frames: FRMS (count, flags: 1 = normals, vertex count; then every frame's positions and
 * normals), then one FRCP per set (a CPCA chunk over count x vertex-count rows). The sets of
 * key frame 0 are not written again: they are the FRCP's first rows. */
static void save_frames(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__sh_state *sh = t->state;
    const prt__sh_frames *fr = &sh->frames;
    const size_t nv = t->mesh.vertex_count, rows = (size_t)fr->count * nv;
    unsigned char *h = prt__chunks_alloc(l, FRMS_HEADER);
    if (!h) return;
    prt__put32(h, (uint32_t)fr->count);
    prt__put32(h + 4, fr->normals ? 1u : 0u);
    prt__put64(h + 8, nv);
    if (fr->normals) prt__chunks_add(l, CHUNK_FRMS, h, (size_t)FRMS_HEADER, fr->positions, rows * 12, fr->normals, rows * 12, NULL);
    else prt__chunks_add(l, CHUNK_FRMS, h, (size_t)FRMS_HEADER, fr->positions, rows * 12, NULL);
    for (int k = 0; k < PRT__KIND_COUNT; ++k) {
        if (!fr->sets[k]) continue;
        unsigned char *c = prt__chunks_alloc(l, CPCA_HEADER);
        if (!c) return;
        prt__put32(c, (uint32_t)prt__kind_from_index(k));
        prt__put32(c + 4, (uint32_t)sh->sets[k].channels);
        prt__put32(c + 8, (uint32_t)sh->order);
        save_cpca(l, CHUNK_FRCP, c, fr->sets[k], rows);
    }
}

prt_status prt__sh_save(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__sh_state *sh = t->state;
    const prt__mesh *m = &t->mesh;
    if (sh->frames.count) {
        save_frames(t, l);
        return PRT_OK;   /* key frames hold no texel sets */
    }
    for (int k = 0; k < PRT__KIND_COUNT; ++k) {
        const prt__sh_set *s = &sh->sets[k];
        if (!s->channels) continue;
        unsigned char *h = prt__chunks_alloc(l, CPCA_HEADER);
        if (!h) break;
        prt__put32(h, (uint32_t)prt__kind_from_index(k));
        prt__put32(h + 4, (uint32_t)s->channels);
        prt__put32(h + 8, (uint32_t)sh->order);
        if (!s->cpca) {
            const size_t dim = prt__set_dim(sh, k), n = m->vertex_count * dim;
            prt__put64(h + 16, m->vertex_count);
            if (!s->quant_bits) {
                prt__chunks_add(l, CHUNK_SHTR, h, (size_t)24, s->coeffs, n * sizeof(float), NULL);
                continue;
            }
            /* Quantized: scale[dim], bias[dim], then the integers, padded to 4 bytes. */
            prt__put32(h + 12, (uint32_t)s->quant_bits);
            const size_t qbytes = n * (size_t)(s->quant_bits / 8), padded = (qbytes + 3) & ~(size_t)3;
            float *grid = prt__chunks_alloc(l, 2 * dim * sizeof(float));
            unsigned char *q = prt__chunks_alloc(l, padded);
            if (!grid || !q) break;
            prt__quant_grid(s->coeffs, m->vertex_count, (int)dim, s->quant_bits, grid, grid + dim);
            for (size_t i = 0; i < n; ++i) {
                size_t j = i % dim;
                float lv = grid[j] > 0 ? roundf((s->coeffs[i] - grid[dim + j]) / grid[j]) : 0.0f;
                uint32_t u = (uint32_t)fminf(fmaxf(lv, 0.0f), (float)((1u << s->quant_bits) - 1));
                if (s->quant_bits == 8) q[i] = (unsigned char)u;
                else { uint16_t w = (uint16_t)u; memcpy(q + 2 * i, &w, 2); }
            }
            prt__chunks_add(l, CHUNK_SHTR, h, (size_t)24, grid, 2 * dim * sizeof(float), q, padded, NULL);
            continue;
        }
        save_cpca(l, CHUNK_CPCA, h, s->cpca, m->vertex_count);
    }
    const prt__texel_sets *tx = &sh->texels;
    if (tx->width) {
        static const unsigned char pad4[4] = {0};
        const size_t ntex = (size_t)tx->width * tx->height;
        unsigned char *head = prt__chunks_alloc(l, 8);
        if (head) {
            prt__put32(head, (uint32_t)tx->width);
            prt__put32(head + 4, (uint32_t)tx->height);
        }
        const size_t pad = ((ntex + 3) & ~(size_t)3) - ntex;
        if (pad) prt__chunks_add(l, CHUNK_TXAL, head, (size_t)8, tx->albedo, ntex * 12, tx->covered, ntex, pad4, pad, NULL);
        else prt__chunks_add(l, CHUNK_TXAL, head, (size_t)8, tx->albedo, ntex * 12, tx->covered, ntex, NULL);
        for (int k = 0; k < 3; ++k) {
            if (!tx->coeffs[k]) continue;
            unsigned char *h = prt__chunks_alloc(l, 24);
            if (!h) break;
            prt__put32(h, (uint32_t)prt__kind_from_index(k));
            prt__put32(h + 4, (uint32_t)tx->channels[k]);
            prt__put32(h + 8, (uint32_t)sh->order);
            prt__put32(h + 12, (uint32_t)tx->width);
            prt__put32(h + 16, (uint32_t)tx->height);
            const size_t dim = (size_t)tx->channels[k] * sh->order * sh->order, n = ntex * dim;
            if (tx->bytes) {
                /* scale[dim], bias[dim], then the levels, padded to 4 bytes. */
                const size_t padded = (n + 3) & ~(size_t)3;
                float *grid = prt__chunks_alloc(l, 2 * dim * sizeof(float));
                unsigned char *q = prt__chunks_alloc(l, padded);
                if (!grid || !q) break;
                prt__quant_grid(tx->coeffs[k], ntex, (int)dim, 8, grid, grid + dim);
                for (size_t i = 0; i < n; ++i) {
                    const size_t j = i % dim;
                    const float lv = grid[j] > 0 ? roundf((tx->coeffs[k][i] - grid[dim + j]) / grid[j]) : 0.0f;
                    q[i] = (unsigned char)fminf(fmaxf(lv, 0.0f), 255.0f);
                }
                memset(q + n, 0, padded - n);
                if (l->version < 4) l->version = 4;   /* readers of version 3 would skip the texel sets */
                prt__chunks_add(l, CHUNK_TXLQ, h, (size_t)24, grid, 2 * dim * sizeof(float), q, padded, NULL);
                continue;
            }
            if (!tx->halves) {
                prt__chunks_add(l, CHUNK_TXLS, h, (size_t)24, tx->coeffs[k], n * 4, NULL);
                continue;
            }
            uint16_t *v = prt__chunks_alloc(l, n * 2 + 2);   /* + 2: 4-byte chunks */
            if (!v) break;
            for (size_t i = 0; i < n; ++i) v[i] = prt__half_from_float(tx->coeffs[k][i]);
            if (l->version < 2) l->version = 2;   /* readers of version 1 would skip the texel sets */
            v[n] = 0;
            prt__chunks_add(l, CHUNK_TXLH, h, (size_t)24, v, n * 2 + (n & 1 ? 2 : 0), NULL);
        }
    }
    const prt__sh_grid *g = &sh->grid;
    if (g->matrices) {
        unsigned char *h = prt__chunks_alloc(l, NBHD_HEADER);
        if (h) {
            for (int c = 0; c < 3; ++c) {
                prt__put32(h + 4 * c, (uint32_t)g->dims[c]);
                memcpy(h + 16 + 4 * c, &g->lo[c], 4);
                memcpy(h + 28 + 4 * c, &g->hi[c], 4);
            }
            prt__put32(h + 12, (uint32_t)g->order);
            const size_t n = (size_t)g->order * g->order;
            const size_t points = (size_t)g->dims[0] * g->dims[1] * g->dims[2];
            prt__chunks_add(l, CHUNK_NBHD, h, (size_t)NBHD_HEADER, g->matrices, points * 3 * n * n * sizeof(float), g->front, points * sizeof(float), NULL);
        }
    }
    for (int k = 0; k < sh->volume_count; ++k) {
        const prt__sh_volume *v = &sh->volumes[k];
        unsigned char *h = prt__chunks_alloc(l, VOLU_HEADER);
        if (!h) break;
        for (int c = 0; c < 3; ++c) {
            prt__put32(h + 4 * c, (uint32_t)v->medium.dims[c]);
            memcpy(h + 24 + 4 * c, &v->medium.lo[c], 4);
            memcpy(h + 36 + 4 * c, &v->medium.hi[c], 4);
            memcpy(h + 52 + 4 * c, &v->medium.albedo[c], 4);
        }
        prt__put32(h + 12, (uint32_t)sh->order);
        prt__put32(h + 16, (uint32_t)v->bands);
        prt__put32(h + 20, (uint32_t)v->orders);
        memcpy(h + 48, &v->medium.sigma_t, 4);
        memcpy(h + 64, &v->medium.g, 4);
        /* Transfer of the voxels with medium around them only, as halves. */
        const size_t voxels = prt__volume_voxels(&v->medium), n = (size_t)sh->order * sh->order;
        const size_t pd = 3 * (size_t)v->bands * v->bands * n;
        size_t active = 0;
        for (int z = 0; z < v->medium.dims[2]; ++z)
            for (int y = 0; y < v->medium.dims[1]; ++y)
                for (int x = 0; x < v->medium.dims[0]; ++x) active += prt__sh_volume_active(&v->medium, x, y, z);
        const size_t halves = active * pd;
        uint16_t *q = prt__chunks_alloc(l, halves * 2 + 2);
        if (!q) break;
        size_t at = 0, k2 = 0;
        for (int z = 0; z < v->medium.dims[2]; ++z)
            for (int y = 0; y < v->medium.dims[1]; ++y)
                for (int x = 0; x < v->medium.dims[0]; ++x, ++k2) {
                    if (!prt__sh_volume_active(&v->medium, x, y, z)) continue;
                    for (size_t i = 0; i < pd; ++i) q[at++] = prt__half_from_float(v->incident[k2 * pd + i]);
                }
        q[halves] = 0;
        if (l->version < 2) l->version = 2;   /* half-float chunk */
        prt__chunks_add(l, CHUNK_VOLU, h, (size_t)VOLU_HEADER, v->medium.density, voxels * 4, q, halves * 2 + (halves & 1 ? 2 : 0), NULL);
    }
    return PRT_OK;   /* allocation failures are recorded in the list and reported when writing */
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "%s", msg); }

/* A CPCA chunk of vertex_count rows into sh->sets, or with frames, of frames x vertex count rows
 * into sh->frames.sets. */
static prt_status load_cpca(prt_context *ctx, prt__sh_state *sh, const prt__chunk_in *in, uint64_t vertex_count, bool frames)
{
    const unsigned char *p = in->data;
    const uint64_t len = in->size;
    if (len < CPCA_HEADER) return bad(ctx, "corrupt .prt file: bad compressed transfer chunk");
    uint32_t kind = prt__get32(p), channels = prt__get32(p + 4), order = prt__get32(p + 8), method = prt__get32(p + 12);
    uint32_t clusters = prt__get32(p + 16), dim = prt__get32(p + 20);
    uint64_t nv = prt__get64(p + 24), nvec = prt__get64(p + 32), nw = prt__get64(p + 40);
    int k = prt__kind_index((prt_transfer_kind)kind);
    /* Every count is bounded by the chunk's own length before it sizes anything. */
    if (k < 0 || (channels != 1 && channels != 3) || order < 1 || order > PRT_SH_MAX_ORDER || method > PRT_COMPRESS_VQ ||
        dim != channels * order * order * (prt__kind_glossy(k) ? order * order : 1) || nv != vertex_count || (sh->order && (int)order != sh->order) ||
        sh->sets[k].channels || (frames && sh->frames.sets[k]) || clusters == 0 || clusters > len / 4 || nvec > len / 4 || nw > len / 4 || (uint64_t)clusters * dim > len / 4 ||
        nvec * dim > len / 4 || CPCA_HEADER + 4 * ((uint64_t)clusters + (uint64_t)clusters * dim + nvec * dim + nv + nw) != len)
        return bad(ctx, "corrupt .prt file: invalid compressed transfer chunk");
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
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    const unsigned char *q = p + CPCA_HEADER;
    memcpy(c->counts, q, clusters * 4ull); q += clusters * 4ull;
    memcpy(c->means, q, (size_t)clusters * dim * 4); q += (size_t)clusters * dim * 4;
    memcpy(c->basis, q, nvec * dim * 4); q += nvec * dim * 4;
    memcpy(c->cluster_of, q, nv * 4); q += nv * 4;
    memcpy(c->weights, q, nw * 4);
    if (!prt__cpca_index(c, nv)) {
        prt__cpca_free(c);
        return bad(ctx, "corrupt .prt file: compressed transfer indices are inconsistent");
    }
    if (!prt__all_finite(c->means, (size_t)clusters * dim) || !prt__all_finite(c->basis, nvec * dim) || !prt__all_finite(c->weights, nw)) {
        prt__cpca_free(c);
        return bad(ctx, "corrupt .prt file: non-finite compressed transfer");
    }
    sh->order = (int)order;
    if (frames) {
        sh->frames.sets[k] = c;
        return PRT_OK;   /* the set's channels are given once every chunk is in (load_frames) */
    }
    sh->sets[k].channels = (int)channels;
    sh->sets[k].cpca = c;
    return PRT_OK;
}

/* Key frames (save_frames): the poses, then every set's rows; key frame 0's sets are then
 * reconstructed into sh->sets, and its pose must be the mesh's. */
static prt_status load_frames(prt_context *ctx, prt_transfer *t, prt__sh_state *sh, const prt__chunk_in *in, prt__chunk_in *chunks, int count)
{
    const unsigned char *p = in->data;
    const uint64_t len = in->size, nv = t->mesh.vertex_count;
    const uint32_t frames = len >= FRMS_HEADER ? prt__get32(p) : 0, flags = len >= FRMS_HEADER ? prt__get32(p + 4) : 0;
    const uint64_t fnv = len >= FRMS_HEADER ? prt__get64(p + 8) : 0;
    const bool normals = flags & 1;
    if (sh->order) return bad(ctx, "corrupt .prt file: key frames beside transfer of one pose");
    if (frames < 2 || frames > 1024 || flags > 1 || fnv != nv || normals != (t->mesh.normals != NULL) ||
        FRMS_HEADER + (uint64_t)frames * nv * 12 * (normals ? 2 : 1) != len)
        return bad(ctx, "corrupt .prt file: invalid key frames chunk");
    const size_t rows = (size_t)frames * nv;
    prt__sh_frames *fr = &sh->frames;
    fr->positions = malloc(rows * 12 + 4);
    fr->normals = normals ? malloc(rows * 12 + 4) : NULL;
    if (!fr->positions || (normals && !fr->normals)) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(fr->positions, p + FRMS_HEADER, rows * 12);
    if (normals) memcpy(fr->normals, p + FRMS_HEADER + rows * 12, rows * 12);
    if (!prt__all_finite(fr->positions, rows * 3) || (normals && !prt__all_finite(fr->normals, rows * 3)))
        return bad(ctx, "corrupt .prt file: non-finite key frame poses");
    if (memcmp(fr->positions, t->mesh.positions, nv * 12) || (normals && memcmp(fr->normals, t->mesh.normals, nv * 12)))
        return bad(ctx, "corrupt .prt file: key frame 0 is not the file's mesh");
    fr->count = (int)frames;
    const prt__chunk_in *c;
    prt_status st = PRT_OK;
    int channels[PRT__KIND_COUNT] = {0};
    while (!st && (c = prt__chunk_take(chunks, count, CHUNK_FRCP))) {
        st = load_cpca(ctx, sh, c, rows, true);
        if (!st) channels[prt__kind_index((prt_transfer_kind)prt__get32(c->data))] = (int)prt__get32(c->data + 4);
    }
    if (st) return st;
    if (!sh->order) return bad(ctx, "corrupt .prt file: key frames without transfer");
    for (int k = 0; k < PRT__KIND_COUNT; ++k) {
        if (!fr->sets[k]) continue;
        sh->sets[k].channels = channels[k];
        if (!(sh->sets[k].coeffs = malloc(nv * prt__set_dim(sh, k) * sizeof(float) + 4))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        prt__sh_frame_rows(fr->sets[k], nv, 0, sh->sets[k].coeffs);
    }
    return PRT_OK;
}

static prt_status load_set(prt_context *ctx, prt__sh_state *sh, const prt__chunk_in *in, uint64_t vertex_count)
{
    const unsigned char *p = in->data;
    const uint64_t len = in->size;
    if (len < 24) return bad(ctx, "corrupt .prt file: short transfer chunk");
    uint32_t kind = prt__get32(p), channels = prt__get32(p + 4), order = prt__get32(p + 8), bits = prt__get32(p + 12);
    uint64_t nv = prt__get64(p + 16);
    int k = prt__kind_index((prt_transfer_kind)kind);
    if (k < 0 || (channels != 1 && channels != 3) || order < 1 || order > PRT_SH_MAX_ORDER || nv != vertex_count ||
        (sh->order && (int)order != sh->order) || sh->sets[k].channels)
        return bad(ctx, "corrupt .prt file: invalid transfer chunk header");
    uint64_t dim = (uint64_t)channels * order * order * (prt__kind_glossy(k) ? order * order : 1), n = nv * dim;
    uint64_t need = bits == 0 ? 24 + n * 4 : 24 + 8 * dim + ((n * (bits / 8) + 3) & ~3ull);
    if ((bits != 0 && bits != 8 && bits != 16) || n > len || need != len) return bad(ctx, "corrupt .prt file: transfer chunk size mismatch");
    float *c = malloc(n * 4);
    if (!c) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
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
    if (!prt__all_finite(c, n)) { free(c); return bad(ctx, "corrupt .prt file: non-finite transfer coefficients"); }
    sh->sets[k].quant_bits = (int)bits;
    sh->order = (int)order;
    sh->sets[k].channels = (int)channels;
    sh->sets[k].coeffs = c;
    return PRT_OK;
}

static prt_status load_texels(prt_context *ctx, prt__sh_state *sh, prt__chunk_in *chunks, int count)
{
    prt__chunk_in *in = prt__chunk_take(chunks, count, CHUNK_TXAL);
    prt__texel_sets *tx = &sh->texels;
    if (!in) {
        if (prt__chunk_take(chunks, count, CHUNK_TXLS) || prt__chunk_take(chunks, count, CHUNK_TXLH) || prt__chunk_take(chunks, count, CHUNK_TXLQ))
            return bad(ctx, "corrupt .prt file: texel transfer without its albedo chunk");
        return PRT_OK;
    }
    const unsigned char *p = in->data;
    uint64_t len = in->size;
    uint32_t w = len >= 8 ? prt__get32(p) : 0, h = len >= 8 ? prt__get32(p + 4) : 0;
    uint64_t ntex = (uint64_t)w * h;
    if (w == 0 || h == 0 || w > 8192 || h > 8192 || 8 + ntex * 12 + ((ntex + 3) & ~3ull) != len) return bad(ctx, "corrupt .prt file: invalid texel albedo chunk");
    tx->albedo = malloc(ntex * 12);
    tx->covered = malloc(ntex);
    if (!tx->albedo || !tx->covered) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(tx->albedo, p + 8, ntex * 12);
    memcpy(tx->covered, p + 8 + ntex * 12, ntex);
    tx->width = (int)w;
    tx->height = (int)h;
    if (!prt__all_finite(tx->albedo, ntex * 3)) return bad(ctx, "corrupt .prt file: non-finite texel albedo");
    int form = 0;   /* the sets' one representation: 1 floats, 2 halves, 3 bytes */
    while ((in = prt__chunk_take(chunks, count, CHUNK_TXLS)) || (in = prt__chunk_take(chunks, count, CHUNK_TXLH)) ||
           (in = prt__chunk_take(chunks, count, CHUNK_TXLQ))) {
        const int this_form = in->id == CHUNK_TXLS ? 1 : in->id == CHUNK_TXLH ? 2 : 3;
        if (form && form != this_form) return bad(ctx, "corrupt .prt file: texel transfer sets stored in different forms");
        form = this_form;
        tx->halves = form == 2;
        tx->bytes = form == 3;
        p = in->data;
        len = in->size;
        uint32_t kind = len >= 24 ? prt__get32(p) : 0, channels = len >= 24 ? prt__get32(p + 4) : 0, order = len >= 24 ? prt__get32(p + 8) : 0;
        uint32_t tw = len >= 24 ? prt__get32(p + 12) : 0, th = len >= 24 ? prt__get32(p + 16) : 0;
        int k = prt__kind_index((prt_transfer_kind)kind);
        const uint64_t dim = (uint64_t)channels * order * order, n = (uint64_t)tw * th * dim;
        const uint64_t need = form == 1 ? 24 + n * 4 : form == 2 ? 24 + ((n * 2 + 3) & ~3ull) : 24 + 8 * dim + ((n + 3) & ~3ull);
        if (k < 0 || k > 2 || (channels != 1 && channels != 3) || (int)order != sh->order || (int)tw != tx->width || (int)th != tx->height ||
            tx->coeffs[k] || need != len)
            return bad(ctx, "corrupt .prt file: invalid texel transfer chunk");
        if (!(tx->coeffs[k] = malloc(n * 4))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (form == 2)
            for (uint64_t i = 0; i < n; ++i) {
                uint16_t hv;
                memcpy(&hv, p + 24 + i * 2, 2);
                tx->coeffs[k][i] = prt__half_to_float(hv);
            }
        else if (form == 3) {
            const unsigned char *grid = p + 24, *q = p + 24 + 8 * dim;
            for (uint64_t i = 0; i < n; ++i) {
                const uint64_t jj = i % dim;
                float scale, bias;
                memcpy(&scale, grid + 4 * jj, 4);
                memcpy(&bias, grid + 4 * (dim + jj), 4);
                tx->coeffs[k][i] = bias + (float)q[i] * scale;
            }
        } else
            memcpy(tx->coeffs[k], p + 24, n * 4);
        tx->channels[k] = (int)channels;
        if (!prt__all_finite(tx->coeffs[k], n)) return bad(ctx, "corrupt .prt file: non-finite texel transfer");
    }
    return PRT_OK;
}

/* u32 dims[3], u32 order, f32 lo[3], f32 hi[3], then f32 [point][3][n][n], f32 front[point]. */
static prt_status load_grid(prt_context *ctx, prt__sh_state *sh, const prt__chunk_in *in)
{
    const unsigned char *p = in->data;
    if (in->size < NBHD_HEADER) return bad(ctx, "corrupt .prt file: short neighbourhood chunk");
    prt__sh_grid g = {0};
    uint64_t points = 1;
    for (int c = 0; c < 3; ++c) {
        const uint32_t d = prt__get32(p + 4 * c);
        if (d < 2 || d > 64) return bad(ctx, "corrupt .prt file: neighbourhood grid size out of range");
        g.dims[c] = (int)d;
        points *= d;
        memcpy(&g.lo[c], p + 16 + 4 * c, 4);
        memcpy(&g.hi[c], p + 28 + 4 * c, 4);
        if (!isfinite(g.lo[c]) || !isfinite(g.hi[c]) || !(g.hi[c] > g.lo[c])) return bad(ctx, "corrupt .prt file: neighbourhood grid bounds invalid");
    }
    g.order = (int)prt__get32(p + 12);
    if (g.order != sh->order) return bad(ctx, "corrupt .prt file: neighbourhood grid of another SH order than the transfer");
    const uint64_t n = (uint64_t)g.order * g.order, floats = points * 3 * n * n;
    if (NBHD_HEADER + (floats + points) * 4 != in->size) return bad(ctx, "corrupt .prt file: neighbourhood chunk size mismatch");
    g.matrices = malloc(floats * 4);
    g.front = malloc(points * 4);
    if (!g.matrices || !g.front) { free(g.matrices); free(g.front); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    memcpy(g.matrices, p + NBHD_HEADER, floats * 4);
    memcpy(g.front, p + NBHD_HEADER + floats * 4, points * 4);
    bool ok = prt__all_finite(g.matrices, floats);
    for (uint64_t i = 0; ok && i < points; ++i) ok = g.front[i] >= 0 && g.front[i] <= 1;
    if (!ok) { free(g.matrices); free(g.front); return bad(ctx, "corrupt .prt file: non-finite neighbourhood transfer or a share of rays outside [0, 1]"); }
    sh->grid = g;
    return PRT_OK;
}

/* u32 dims[3], order, bands, orders; f32 lo[3], hi[3], sigma_t, albedo[3], g; then f32
 * density[voxel], then as halves incident[voxel][3][bands^2][n] of the voxels with medium in
 * their 3 x 3 x 3 neighbourhood (docs/FORMAT.md). */
static prt_status load_volume(prt_context *ctx, prt__sh_state *sh, const prt__chunk_in *in)
{
    const unsigned char *p = in->data;
    if (in->size < VOLU_HEADER) return bad(ctx, "corrupt .prt file: short volume chunk");
    if (sh->volume_count >= 64) return bad(ctx, "corrupt .prt file: more than 64 volume chunks");
    prt__sh_volume v;
    memset(&v, 0, sizeof v);
    uint64_t voxels = 1;
    for (int c = 0; c < 3; ++c) {
        const uint32_t d = prt__get32(p + 4 * c);
        if (d < 1 || d > PRT_VOLUME_MAX_DIM) return bad(ctx, "corrupt .prt file: volume grid size out of range");
        v.medium.dims[c] = (int)d;
        voxels *= d;
        memcpy(&v.medium.lo[c], p + 24 + 4 * c, 4);
        memcpy(&v.medium.hi[c], p + 36 + 4 * c, 4);
        memcpy(&v.medium.albedo[c], p + 52 + 4 * c, 4);
        if (!isfinite(v.medium.lo[c]) || !isfinite(v.medium.hi[c]) || !(v.medium.hi[c] > v.medium.lo[c])) return bad(ctx, "corrupt .prt file: volume box invalid");
        if (!(v.medium.albedo[c] >= 0 && v.medium.albedo[c] <= 1)) return bad(ctx, "corrupt .prt file: volume albedo outside [0, 1]");
    }
    if (voxels > 128u * 128u * 128u) return bad(ctx, "corrupt .prt file: volume of more than 128^3 voxels");
    if (prt__get32(p + 12) != (uint32_t)sh->order) return bad(ctx, "corrupt .prt file: volume transfer of another SH order than the transfer");
    v.bands = (int)prt__get32(p + 16);
    v.orders = (int)prt__get32(p + 20);
    if (v.bands < 1 || v.bands > 2 || v.bands > sh->order) return bad(ctx, "corrupt .prt file: volume bands out of range");
    if (v.orders < 1 || v.orders > 1000) return bad(ctx, "corrupt .prt file: volume orders of scattering out of range");
    memcpy(&v.medium.sigma_t, p + 48, 4);
    memcpy(&v.medium.g, p + 64, 4);
    if (!(v.medium.sigma_t >= 0) || !isfinite(v.medium.sigma_t) || !(fabsf(v.medium.g) < 1)) return bad(ctx, "corrupt .prt file: volume extinction or g out of range");
    const uint64_t n = (uint64_t)sh->order * sh->order, pd = 3 * (uint64_t)v.bands * v.bands * n;
    if (in->size < VOLU_HEADER + voxels * 4) return bad(ctx, "corrupt .prt file: volume chunk size mismatch");
    /* The densities say which voxels carry transfer; only then is the rest's size known. */
    v.medium.density = malloc(voxels * 4);
    if (!v.medium.density) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(v.medium.density, p + VOLU_HEADER, voxels * 4);
    bool ok = true;
    for (uint64_t i = 0; ok && i < voxels; ++i) {
        ok = v.medium.density[i] >= 0 && isfinite(v.medium.density[i]);
        v.medium.max_density = fmaxf(v.medium.max_density, v.medium.density[i]);
    }
    if (!ok) { prt__sh_volume_free(&v); return bad(ctx, "corrupt .prt file: a volume density below zero or not a number"); }
    uint64_t active = 0;
    for (int z = 0; z < v.medium.dims[2]; ++z)
        for (int y = 0; y < v.medium.dims[1]; ++y)
            for (int x = 0; x < v.medium.dims[0]; ++x) active += prt__sh_volume_active(&v.medium, x, y, z);
    const uint64_t halves = active * pd;
    if (VOLU_HEADER + voxels * 4 + halves * 2 + (halves & 1) * 2 != in->size) { prt__sh_volume_free(&v); return bad(ctx, "corrupt .prt file: volume chunk size mismatch"); }
    v.incident = prt__calloc(voxels * pd, 4);
    if (!v.incident) { prt__sh_volume_free(&v); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    const unsigned char *q = p + VOLU_HEADER + voxels * 4;
    uint64_t k2 = 0;
    for (int z = 0; z < v.medium.dims[2]; ++z)
        for (int y = 0; y < v.medium.dims[1]; ++y)
            for (int x = 0; x < v.medium.dims[0]; ++x, ++k2) {
                if (!prt__sh_volume_active(&v.medium, x, y, z)) continue;
                for (uint64_t i = 0; i < pd; ++i, q += 2) v.incident[k2 * pd + i] = prt__half_to_float((uint16_t)(q[0] | q[1] << 8));
            }
    if (!prt__all_finite(v.incident, voxels * pd)) { prt__sh_volume_free(&v); return bad(ctx, "corrupt .prt file: non-finite volume transfer"); }
    prt__sh_volume *grown = realloc(sh->volumes, (size_t)(sh->volume_count + 1) * sizeof *grown);
    if (!grown) { prt__sh_volume_free(&v); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    sh->volumes = grown;
    sh->volumes[sh->volume_count++] = v;
    return PRT_OK;
}

prt_status prt__sh_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    prt__sh_state *sh = prt__sh_state_new();
    if (!sh) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = sh;
    const cJSON *x;
    if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "samples"))) sh->samples = x->valueint;
    if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "bounces"))) sh->bounces = x->valueint;
    if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "seed"))) sh->seed = (uint32_t)x->valuedouble;
    sh->glossy_exit = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(meta, "glossy_exit"));
    prt_status st = PRT_OK;
    const prt__chunk_in *in;
    while (!st && (in = prt__chunk_take(chunks, count, CHUNK_SHTR))) st = load_set(ctx, sh, in, t->mesh.vertex_count);
    while (!st && (in = prt__chunk_take(chunks, count, CHUNK_CPCA))) st = load_cpca(ctx, sh, in, t->mesh.vertex_count, false);
    if (!st && (in = prt__chunk_take(chunks, count, CHUNK_FRMS))) st = load_frames(ctx, t, sh, in, chunks, count);
    else if (!st && prt__chunk_take(chunks, count, CHUNK_FRCP)) st = bad(ctx, "corrupt .prt file: key-frame transfer without its key frames chunk");
    if (!st && sh->frames.count && prt__chunk_take(chunks, count, CHUNK_FRMS)) st = bad(ctx, "corrupt .prt file: two key frames chunks");
    if (!st && !sh->order) st = bad(ctx, ".prt file holds no transfer");
    if (!st) st = load_texels(ctx, sh, chunks, count);
    if (!st && prt__chunk_take(chunks, count, CHUNK_TXAL)) st = bad(ctx, "corrupt .prt file: two texel albedo chunks");
    if (!st && (in = prt__chunk_take(chunks, count, CHUNK_NBHD))) st = load_grid(ctx, sh, in);
    if (!st && prt__chunk_take(chunks, count, CHUNK_NBHD)) st = bad(ctx, "corrupt .prt file: two neighbourhood chunks");
    while (!st && (in = prt__chunk_take(chunks, count, CHUNK_VOLU))) st = load_volume(ctx, sh, in);
    return st;
}
