/* The spectral method's table entry (direct-to-indirect transfer in a spectral mesh basis, Wang,
 * Zhu & Humphreys 2007): bake options, its chunks (SPCP, SPCB, SPCT, SPCE), description, the
 * bounce control and relighting with run-time albedo. The basis is built in
 * basis.c, the transfer in bake.c, the run time in relight.c. */
#include "methods/spectral/spectral.h"
#include "brdf/sh_matrix.h"

#define CHUNK_SPCP PRT__FOURCC('S', 'P', 'C', 'P')
#define CHUNK_SPCB PRT__FOURCC('S', 'P', 'C', 'B')
#define CHUNK_SPCT PRT__FOURCC('S', 'P', 'C', 'T')
#define CHUNK_SPCE PRT__FOURCC('S', 'P', 'C', 'E')
#define CHUNK_SPCM PRT__FOURCC('S', 'P', 'C', 'M')
#define CHUNK_SPCG PRT__FOURCC('S', 'P', 'C', 'G')
#define SPCP_HEADER 48
#define MATRIX_BYTES (3 * PRT__SPECTRAL_GLOSSY_N * PRT__SPECTRAL_GLOSSY_N * sizeof(float))

static prt__spectral_cache *cache_new(void)
{
    prt__spectral_cache *c = prt__calloc(1, sizeof *c);
    if (c) {
        pthread_mutex_init(&c->lock, NULL);
        prt__vertex_lights_init(&c->lights);
    }
    return c;
}

void prt__spectral_set_free(void *state)
{
    prt__spectral_set *s = state;
    if (!s) return;
    prt__spectral_basis_free(&s->basis);
    free(s->row_start);
    free(s->index);
    free(s->value);
    free(s->env);
    free(s->emit);
    free(s->glossy_of);
    free(s->grow_start);
    free(s->gindex);
    free(s->gvalue);
    for (int k = 0; k < PRT__MAX_BRDFS; ++k) free(s->brdf_matrix[k]);
    if (s->cache) {
        prt__vertex_lights_free(&s->cache->lights);
        prt__frame_rot *fr = s->cache->frames;
        for (uint32_t g = 0; fr && g < s->glossy_count; ++g) prt__frame_rot_release(&fr[g]);
        free(fr);
        pthread_mutex_destroy(&s->cache->lock);
        free(s->cache);
    }
    free(s);
}

bool prt__spectral_glossy_index(const prt_transfer *t, prt__spectral_set *s)
{
    const size_t nv = t->mesh.vertex_count;
    free(s->glossy_of);
    s->glossy_count = 0;
    if (!(s->glossy_of = malloc(nv * sizeof(uint32_t)))) return false;
    for (size_t v = 0; v < nv; ++v) {
        const uint8_t k = t->mesh.material[v];
        const bool glossy = k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1]);
        s->glossy_of[v] = glossy ? s->glossy_count++ : UINT32_MAX;
    }
    return true;
}

/* ---- bake options ---- */
/* Help texts are reflowed by the printer (prt bake --help): line breaks here are for the source. */
static const prt_option_desc options[] = {
    {"basis", "N", PRT_OPTION_INT, 1, PRT__SPECTRAL_MAX_FUNCTIONS, NULL,
     "spectral basis functions in all, spread over the partitions by vertex count (default 1024)"},
    {"full-basis", NULL, PRT_OPTION_FLAG, 0, 0, NULL,
     "no truncation: every vertex its own basis function (the same space as all eigenvectors; "
     "at most 65535 vertices): the reference for the basis error"},
    {"partition", "V", PRT_OPTION_INT, 16, PRT__SPECTRAL_MAX_PARTITION / 2, NULL,
     "vertices per METIS partition, 16..2048 (default 1000)"},
    {"samples", "N", PRT_OPTION_INT, 16, 1 << 20, NULL,
     "gathering rays per vertex (default 4096; the paper uses 128x128)"},
    {"drop-below", "E", PRT_OPTION_FLOAT, 0, 0.1, NULL,
     "also drop transfer entries below E x the largest (default 0: only what rounds to zero at "
     "16 bits, as the paper); in the demo room 5e-4 keeps a third of the entries for a 2% "
     "change, 1e-3 a fifth for 5%"},
    {"env-order", "N", PRT_OPTION_INT, 1, PRT_SH_MAX_ORDER, NULL,
     "SH order of the environment's shadowed direct light, 1..10 (default 4)"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "ray origin offset (default 1e-4 x scene diagonal)"},
};

static const prt_control_desc controls[] = {
    {"bounces", "light bounces through the basis (0 = direct light only)", '[', ']', 0},
};

static prt_status spectral_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    (void)scene;
    prt__spectral_bake_desc d = {0};
    d.functions = prt__opt_int(o, "basis", 0);
    d.full = prt__opt_flag(o, "full-basis");
    if (d.full && prt__opt(o, "basis")) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--basis and --full-basis exclude each other");
    d.partition_size = prt__opt_int(o, "partition", 0);
    d.samples = prt__opt_int(o, "samples", 0);
    d.env_order = prt__opt_int(o, "env-order", 0);
    d.drop_below = prt__opt_float(o, "drop-below", 0.0f);
    d.ray_offset = prt__opt_float(o, "ray-offset", 0.0f);
    prt_status st = prt__spectral_bake_begin(ctx, &d, t, job);
    if (!st && !(((prt__spectral_set *)t->state)->cache = cache_new())) {
        (*job)->release(*job);   /* the driver releases only jobs that began */
        *job = NULL;
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    return st;
}

/* ---- files ---- */
static prt_status spectral_save(const prt_transfer *t, prt__chunk_list *l)
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
    memcpy(head + 24, &s->scale, 4);
    memcpy(head + 28, &s->ray_offset, 4);
    prt__put64(head + 32, nnz);
    prt__put64(head + 40, nv);
    prt__chunks_add(l, CHUNK_SPCP, head, (size_t)SPCP_HEADER, b->part_of, nv * sizeof(uint32_t), b->count, (size_t)b->partitions * sizeof(uint32_t), NULL);
    prt__chunks_add(l, CHUNK_SPCB, b->values, b->offset[nv] * sizeof(float), NULL);
    for (size_t v = 0; v < nv; ++v) counts[v] = (uint32_t)(s->row_start[v + 1] - s->row_start[v]);
    const size_t bytes = nnz * 2, pad = ((bytes + 3) & ~(size_t)3) - bytes;
    prt__chunks_add(l, CHUNK_SPCT, counts, nv * sizeof(uint32_t), s->index, bytes, zero4, pad, s->value, bytes, zero4, pad, NULL);
    prt__chunks_add(l, CHUNK_SPCE, s->env, nv * (size_t)s->env_order * s->env_order * sizeof(float), NULL);
    if (s->emit) prt__chunks_add(l, CHUNK_SPCM, s->emit, nv * 3 * sizeof(float), NULL);
    if (s->glossy_count) {
        /* glossy vertex count, SH order, scale, 0, entries per row, indices, values */
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
        memcpy(gh + 8, &s->gscale, 4);
        prt__put32(gh + 12, (uint32_t)nmat);
        unsigned char *at = gh + 16;
        for (int k = 0; k < PRT__MAX_BRDFS; ++k)
            if (s->brdf_matrix[k]) {
                prt__put32(at, (uint32_t)(k + 1));
                memcpy(at + 4, s->brdf_matrix[k], MATRIX_BYTES);
                at += 4 + MATRIX_BYTES;
            }
        for (size_t r = 0; r < rows; ++r) gcounts[r] = (uint32_t)(s->grow_start[r + 1] - s->grow_start[r]);
        prt__chunks_add(l, CHUNK_SPCG, gh, 16 + mbytes, gcounts, rows * sizeof(uint32_t), s->gindex, gb, zero4, gpad, s->gvalue, gb, zero4, gpad, NULL);
    }
    return PRT_OK;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %s", msg); }

static prt_status load_params(prt_context *ctx, prt_transfer *t, prt__spectral_set *s, const prt__chunk_in *c, uint64_t *nnz)
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
    memcpy(&s->scale, p + 24, 4);
    memcpy(&s->ray_offset, p + 28, 4);
    *nnz = prt__get64(p + 32);
    if (b->functions < 1 || b->functions > PRT__SPECTRAL_MAX_FUNCTIONS || b->partitions < 1 || b->partitions > nv || s->env_order < 1 ||
        s->env_order > PRT_SH_MAX_ORDER || !(s->scale > 0) || !isfinite(s->scale) || !(s->ray_offset > 0) || !isfinite(s->ray_offset) ||
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

static prt_status load_transfer(prt_context *ctx, size_t nv, prt__spectral_set *s, uint64_t nnz, const prt__chunk_in *c)
{
    const uint64_t bytes = nnz * 2, padded = (bytes + 3) & ~3ull;
    if (c->size != nv * 4 + 2 * padded) return bad(ctx, "spectral transfer chunk size mismatch");
    s->row_start = malloc((nv + 1) * sizeof(uint64_t));
    s->index = malloc(bytes ? bytes : 1);
    s->value = malloc(bytes ? bytes : 1);
    if (!s->row_start || !s->index || !s->value) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    s->row_start[0] = 0;
    for (size_t v = 0; v < nv; ++v) {
        const uint32_t n = prt__get32(c->data + v * 4);
        if (n > s->basis.functions || s->row_start[v] + n > nnz) return bad(ctx, "spectral transfer counts are inconsistent");
        s->row_start[v + 1] = s->row_start[v] + n;
    }
    if (s->row_start[nv] != nnz) return bad(ctx, "spectral transfer counts are inconsistent");
    memcpy(s->index, c->data + nv * 4, bytes);
    memcpy(s->value, c->data + nv * 4 + padded, bytes);
    for (size_t v = 0; v < nv; ++v)
        for (uint64_t i = s->row_start[v]; i < s->row_start[v + 1]; ++i)
            if (s->index[i] >= s->basis.functions || (i > s->row_start[v] && s->index[i] <= s->index[i - 1]))
                return bad(ctx, "a spectral transfer index is out of range or out of order");
    return PRT_OK;
}

static prt_status load_glossy(prt_context *ctx, const prt_transfer *t, prt__spectral_set *s, const prt__chunk_in *c)
{
    const unsigned char *head = c->data;
    const uint64_t rows = (uint64_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N;
    uint64_t len = c->size;
    if (len < 16 || prt__get32(head) != s->glossy_count || prt__get32(head + 4) != PRT__SPECTRAL_GLOSSY_ORDER)
        return bad(ctx, "invalid spectral glossy chunk");
    memcpy(&s->gscale, head + 8, 4);
    if (!(s->gscale > 0) || !isfinite(s->gscale)) return bad(ctx, "spectral glossy scale out of range");
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
    for (size_t v = 0; v < t->mesh.vertex_count; ++v)
        if (s->glossy_of[v] != UINT32_MAX && !s->brdf_matrix[t->mesh.material[v] - 1]) return bad(ctx, "a glossy material's BRDF matrix is missing");
    const unsigned char *p = head + (size_t)nmat * (4 + MATRIX_BYTES);   /* the rest as if the matrices were not there */
    len -= (uint64_t)nmat * (4 + MATRIX_BYTES);
    if (len < 16 + rows * 4) return bad(ctx, "invalid spectral glossy chunk");
    if (!(s->grow_start = malloc((rows + 1) * sizeof(uint64_t)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    s->grow_start[0] = 0;
    for (uint64_t r = 0; r < rows; ++r) {
        const uint32_t n = prt__get32(p + 16 + r * 4);
        if (n > s->basis.functions) return bad(ctx, "spectral glossy counts are inconsistent");
        s->grow_start[r + 1] = s->grow_start[r] + n;
    }
    const uint64_t gnnz = s->grow_start[rows], gb = gnnz * 2, padded = (gb + 3) & ~3ull;
    if (len != 16 + rows * 4 + 2 * padded) return bad(ctx, "spectral glossy chunk size mismatch");
    s->gindex = malloc(gb ? gb : 1);
    s->gvalue = malloc(gb ? gb : 1);
    if (!s->gindex || !s->gvalue) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(s->gindex, p + 16 + rows * 4, gb);
    memcpy(s->gvalue, p + 16 + rows * 4 + padded, gb);
    for (uint64_t r = 0; r < rows; ++r)
        for (uint64_t i = s->grow_start[r]; i < s->grow_start[r + 1]; ++i)
            if (s->gindex[i] >= s->basis.functions || (i > s->grow_start[r] && s->gindex[i] <= s->gindex[i - 1]))
                return bad(ctx, "a spectral glossy index is out of range or out of order");
    return PRT_OK;
}

static prt_status spectral_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    (void)meta;
    prt__spectral_set *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = s;
    if (!(s->cache = cache_new())) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const size_t nv = t->mesh.vertex_count;
    uint64_t nnz = 0;
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_SPCP);
    prt_status st = c ? load_params(ctx, t, s, c, &nnz) : bad(ctx, "spectral parameter chunk missing");
    if (!st) st = (c = prt__chunk_take(chunks, count, CHUNK_SPCB)) ? load_basis(ctx, nv, &s->basis, c) : bad(ctx, "spectral basis chunk missing");
    if (!st) st = (c = prt__chunk_take(chunks, count, CHUNK_SPCT)) ? load_transfer(ctx, nv, s, nnz, c) : bad(ctx, "spectral transfer chunk missing");
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
    /* The glossy final bounce: there exactly when some vertex's material has a glossy part. */
    if (!st && !prt__spectral_glossy_index(t, s)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    c = st ? NULL : prt__chunk_take(chunks, count, CHUNK_SPCG);
    if (!st && !c != !s->glossy_count) st = bad(ctx, "the spectral glossy chunk does not match the glossy materials");
    if (!st && c) st = load_glossy(ctx, t, s, c);
    static const uint32_t ids[6] = {CHUNK_SPCP, CHUNK_SPCB, CHUNK_SPCT, CHUNK_SPCE, CHUNK_SPCM, CHUNK_SPCG};
    for (int i = 0; i < 6 && !st; ++i)
        if (prt__chunk_take(chunks, count, ids[i])) st = bad(ctx, "a spectral chunk appears twice");
    return st;
}

/* ---- description ---- */
static size_t spectral_bytes(const prt_transfer *t)
{
    const prt__spectral_set *s = t->state;
    const size_t nv = t->mesh.vertex_count, rows = (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N;
    return s->row_start[nv] * 4 + nv * 4 + (s->glossy_count ? s->grow_start[rows] * 4 + rows * 4 : 0);
}

static size_t basis_bytes(const prt_transfer *t)
{
    const prt__spectral_set *s = t->state;
    return s->basis.offset[t->mesh.vertex_count] * sizeof(float) + t->mesh.vertex_count * 4;
}

static void spectral_describe(const prt_transfer *t, prt__describe *d)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    const size_t nv = t->mesh.vertex_count;
    uint32_t kmin = UINT32_MAX, kmax = 0, vmin = UINT32_MAX, vmax = 0;
    for (uint32_t p = 0; p < b->partitions; ++p) {
        const uint32_t k = b->count[p], n = b->member_start[p + 1] - b->member_start[p];
        if (k < kmin) kmin = k;
        if (k > kmax) kmax = k;
        if (n < vmin) vmin = n;
        if (n > vmax) vmax = n;
    }
    uint64_t nnz = s->row_start[nv], rmax = 0;
    for (size_t v = 0; v < nv; ++v)
        if (s->row_start[v + 1] - s->row_start[v] > rmax) rmax = s->row_start[v + 1] - s->row_start[v];
    const double per_vertex = nv ? (double)nnz / nv : 0.0;
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "partitions", b->partitions);
        cJSON_AddNumberToObject(j, "functions", b->functions);
        cJSON *per = cJSON_AddArrayToObject(j, "functions_per_partition");
        cJSON *sizes = cJSON_AddArrayToObject(j, "vertices_per_partition");
        for (uint32_t p = 0; p < b->partitions; ++p) {
            cJSON_AddItemToArray(per, cJSON_CreateNumber(b->count[p]));
            cJSON_AddItemToArray(sizes, cJSON_CreateNumber(b->member_start[p + 1] - b->member_start[p]));
        }
        cJSON_AddNumberToObject(j, "basis_bytes", (double)basis_bytes(t));
        cJSON_AddNumberToObject(j, "coefficients", (double)nnz);
        cJSON_AddNumberToObject(j, "coefficients_per_vertex", per_vertex);
        cJSON_AddNumberToObject(j, "coefficients_per_vertex_max", (double)rmax);
        cJSON_AddNumberToObject(j, "samples", s->samples);
        cJSON_AddNumberToObject(j, "partition_size", s->partition_size);
        cJSON_AddNumberToObject(j, "env_order", s->env_order);
        cJSON_AddNumberToObject(j, "glossy_vertices", s->glossy_count);
        cJSON_AddNumberToObject(j, "glossy_coefficients", s->glossy_count ? (double)s->grow_start[(size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N] : 0.0);
        return;
    }
    prt__describe_line(d, "basis:", "%u functions over %u partitions (%u..%u vertices, %u..%u functions each), %.2f MiB", b->functions, b->partitions,
                       vmin, vmax, kmin, kmax, basis_bytes(t) / 1048576.0);
    prt__describe_line(d, "transfer:", "%llu coefficients, %.1f per vertex (at most %llu), 16-bit, %.2f MiB", (unsigned long long)nnz, per_vertex,
                       (unsigned long long)rmax, spectral_bytes(t) / 1048576.0);
    prt__describe_line(d, "bake:", "%d rays per vertex; environment through SH order %d (%d coefficients per vertex)", s->samples, s->env_order,
                       s->env_order * s->env_order);
    if (s->glossy_count)
        prt__describe_line(d, "glossy:", "%u vertices with a glossy final bounce (16 SH BRDF bases), %llu coefficients", s->glossy_count,
                           (unsigned long long)s->grow_start[(size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N]);
}

/* ---- variants and controls ---- */

static void spectral_control_range(const prt_transfer *t, int i, int *lo, int *hi, int *def)
{
    (void)t;
    (void)i;
    *lo = 0;
    *hi = 64;
    *def = 3;
}

/* ---- relighting ---- */
static prt_status spectral_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    if (d->brdf) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf does not apply to spectral transfer (it reflects diffusely; see --albedo-of)");
    const size_t nv = t->mesh.vertex_count;
    const int bounces = d->controls ? d->controls[0] : 3;
    if (bounces < 0 || bounces > 64) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range 0..64", bounces);
    prt_status st = prt__relit_alloc(ctx, t, r, d->with_indirect || d->component == PRT_COMPONENT_INDIRECT);
    if (st) return st;
    const float *albedo = d->albedo ? d->albedo : t->mesh.albedo;
    /* Drawn, the local lights' direct light is the renderer's, per pixel with shadow maps (as the
     * paper draws it); its per-vertex value still feeds the bounces. */
    const int pixel = d->per_vertex || d->component == PRT_COMPONENT_INDIRECT ? 0 : prt_lighting_count(l) < PRT_MAX_PIXEL_LIGHTS ? prt_lighting_count(l) : PRT_MAX_PIXEL_LIGHTS;
    float *E = prt__calloc(nv * 3, sizeof(float)), *direct = prt__calloc(nv * 3, sizeof(float));
    float *Ep = pixel ? prt__calloc(nv * 3, sizeof(float)) : NULL;
    float *indirect = r->indirect ? r->indirect : prt__calloc(nv * 3, sizeof(float));
    if (!E || !direct || !indirect || (pixel && !Ep)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__spectral_direct(ctx, t, l, E, Ep, pixel);
    if (!st) {
        for (size_t i = 0; i < nv * 3; ++i) direct[i] = albedo[i] / (float)PRT_PI * E[i];
        st = prt__spectral_bounces(ctx, t, albedo, direct, d->component == PRT_COMPONENT_DIRECT ? 0 : bounces, indirect);
    }
    if (!st && pixel) {
        r->pixel_lights = malloc((size_t)pixel * sizeof(prt_light));
        r->pixel_albedo = malloc(nv * 3 * sizeof(float));
        r->pixel_visibility = malloc((size_t)pixel * nv * sizeof(float));
        if (!r->pixel_lights || !r->pixel_albedo || !r->pixel_visibility) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            for (int i = 0; i < pixel; ++i) r->pixel_lights[i] = *prt_lighting_light(l, i);
            r->pixel_light_count = pixel;
            st = prt__spectral_visibility(ctx, t, r->pixel_lights, pixel, r->pixel_visibility);
            memcpy(r->pixel_albedo, albedo, nv * 3 * sizeof(float));
            for (size_t i = 0; i < nv * 3; ++i) direct[i] -= albedo[i] / (float)PRT_PI * Ep[i];
        }
    }
    const float emission = prt_lighting_emission(l);
    const float *le = t->mesh.emission;
    if (!st) {
        for (size_t i = 0; i < nv * 3; ++i) {
            const float own = le ? emission * le[i] : 0.0f;
            switch (d->component) {
            case PRT_COMPONENT_DIRECT: r->radiance[i] = own + direct[i]; break;
            case PRT_COMPONENT_INDIRECT: r->radiance[i] = indirect[i]; break;
            default: r->radiance[i] = own + direct[i] + indirect[i]; break;
            }
        }
    }
    /* The glossy final bounce (eq. 8): glossy surfaces reflect, view-dependently, everything the
     * other surfaces send out - emission, reflected direct light, the bounces - seen through the
     * basis; the renderer evaluates it per pixel. */
    const prt__spectral_set *s = t->state;
    if (!st && s->glossy_count) {
        float *out = malloc(nv * 3 * sizeof(float));
        r->exit_sh = malloc(nv * 3 * PRT__SPECTRAL_GLOSSY_N * sizeof(float));
        if (!out || !r->exit_sh) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            /* direct[] lacks the pixel lights' part: the surfaces' outgoing light needs all of it. */
            /* The emitters' glossy reflection is direct light, the rest of it indirect: the
             * components add up to the whole. */
            for (size_t i = 0; i < nv * 3; ++i) {
                const float own = le && d->component != PRT_COMPONENT_INDIRECT ? emission * le[i] : 0.0f;
                const float bounced = direct[i] + (Ep ? albedo[i] / (float)PRT_PI * Ep[i] : 0.0f) + indirect[i];
                out[i] = own + (d->component == PRT_COMPONENT_DIRECT ? 0.0f : bounced);
            }
            st = prt__spectral_glossy(ctx, t, out, r->exit_sh);
            r->exit_order = PRT__SPECTRAL_GLOSSY_ORDER;
            r->exit_mirror = 0;
        }
        free(out);
    }
    free(E);
    free(Ep);
    free(direct);
    if (indirect != r->indirect) free(indirect);
    return st;
}

/* The per-vertex value of what the renderer draws per pixel: the pixel lights' direct light. */
static prt_status spectral_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb)
{
    (void)eye;
    if (!r->pixel_lights) return PRT_OK;
    const size_t nv = t->mesh.vertex_count;
    float *E = prt__calloc(nv * 3, sizeof(float));
    if (!E) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = prt__spectral_lights(ctx, t, r->pixel_lights, r->pixel_light_count, E);
    for (size_t i = 0; i < nv * 3 && !st; ++i) rgb[i] += r->pixel_albedo[i] / (float)PRT_PI * E[i];
    free(E);
    return st;
}

const prt__method prt__method_spectral = {
    .name = "spectral",
    .title = "direct-to-indirect transfer in a spectral mesh basis",
    .summary = "spectral mesh basis (Wang, Zhu & Humphreys): multi-bounce indirect light from any local light, albedo live",
    .lighting = PRT_LIGHTS_ENVIRONMENT | PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_SPHERE | PRT_LIGHTS_EMISSIVE,
    .runtime_albedo = true,
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .bake_begin = spectral_bake_begin,
    .free_state = prt__spectral_set_free,
    .save = spectral_save,
    .load = spectral_load,
    .describe = spectral_describe,
    .transfer_bytes = spectral_bytes,
    .control_range = spectral_control_range,
    .relight = spectral_relight,
    .shade = spectral_shade,
};

/* ---- the spectral public accessors ---- */
int prt_transfer_spectral_info(const prt_transfer *t, prt_spectral_info *info)
{
    if (info) memset(info, 0, sizeof *info);
    const prt__spectral_set *s = prt__spectral(t);
    if (!s) return 0;
    if (info) {
        info->partitions = (int)s->basis.partitions;
        info->functions = (int)s->basis.functions;
        info->samples = s->samples;
        info->partition_size = s->partition_size;
        info->env_order = s->env_order;
        info->coefficients = s->row_start[t->mesh.vertex_count];
        info->basis_bytes = basis_bytes(t);
        info->transfer_bytes = spectral_bytes(t);
    }
    return 1;
}

int prt_transfer_spectral_vertex(const prt_transfer *t, size_t v, int *partition, int *first, int *count, const float **values)
{
    const prt__spectral_set *s = prt__spectral(t);
    if (!s || v >= t->mesh.vertex_count) return 0;
    const prt__spectral_basis *b = &s->basis;
    const uint32_t p = b->part_of[v];
    if (partition) *partition = (int)p;
    if (first) *first = (int)b->first[p];
    if (count) *count = (int)b->count[p];
    if (values) *values = b->values + b->offset[v];
    return 1;
}

prt_status prt_spectral_project(const prt_transfer *t, const float *signal, float *coefficients)
{
    const prt__spectral_set *s = prt__spectral(t);
    if (!s || !signal || !coefficients) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_spectral_project: a spectral transfer and arrays are required");
    prt__spectral_project(&s->basis, signal, coefficients, prt__threads(NULL));
    return PRT_OK;
}

prt_status prt_spectral_reconstruct(const prt_transfer *t, const float *coefficients, float *signal)
{
    const prt__spectral_set *s = prt__spectral(t);
    if (!s || !signal || !coefficients) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_spectral_reconstruct: a spectral transfer and arrays are required");
    prt__spectral_reconstruct(&s->basis, t->mesh.vertex_count, coefficients, signal, prt__threads(NULL));
    return PRT_OK;
}
