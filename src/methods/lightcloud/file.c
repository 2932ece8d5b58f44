/* The light-cloud method's chunks in .prt files (docs/FORMAT.md): what it writes beside the
 * method-independent ones (transfer/file.c), and their loading, every count checked against the
 * chunk's size, the mesh and every other count before it sizes an allocation. */
#include "methods/lightcloud/lightcloud.h"

#define CHUNK_LCPR PRT__FOURCC('L', 'C', 'P', 'R')
#define CHUNK_LCZN PRT__FOURCC('L', 'C', 'Z', 'N')
#define CHUNK_LCEM PRT__FOURCC('L', 'C', 'E', 'M')
#define LCPR_HEADER 80
#define ZONE_HEADER 24
#define CPCA_HEADER 32

static void put_block(prt__bytes *out, const prt__lightcloud_block *b)
{
    if (!b->vertices) return;
    if (b->raw) {
        prt__bytes_put(out, b->raw, (size_t)b->vertices * b->dim * sizeof(float));
        return;
    }
    const prt__cpca *c = b->cpca;
    unsigned char h[CPCA_HEADER] = {0};
    prt__put32(h, (uint32_t)c->clusters);
    prt__put64(h + 8, c->vectors_total);
    prt__put64(h + 16, c->weights_total);
    memcpy(h + 24, &c->relative_error, 8);
    prt__bytes_put(out, h, sizeof h);
    prt__bytes_put(out, c->counts, (size_t)c->clusters * 4);
    prt__bytes_put(out, c->means, (size_t)c->clusters * b->dim * 4);
    prt__bytes_put(out, c->basis, c->vectors_total * b->dim * 4);
    prt__bytes_put(out, c->cluster_of, (size_t)b->vertices * 4);
    prt__bytes_put(out, c->weights, c->weights_total * 4);
}

prt_status prt__lightcloud_save(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__lightcloud_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    unsigned char *h = prt__chunks_alloc(l, LCPR_HEADER);
    if (!h) return PRT_OK;
    prt__put32(h, s->cloud_count);
    prt__put32(h + 4, s->zone_count);
    prt__put32(h + 8, s->store_direct);
    prt__put32(h + 12, (uint32_t)s->bounces);
    prt__put32(h + 16, (uint32_t)s->samples);
    prt__put32(h + 20, s->glossy_count);
    memcpy(h + 24, &s->spacing, 4);
    memcpy(h + 28, &s->ray_offset, 4);
    memcpy(h + 32, &s->merge_distance, 4);
    memcpy(h + 36, &s->merge_error, 4);
    prt__put64(h + 40, nv);
    memcpy(h + 48, s->region, sizeof s->region);
    prt__put32(h + 72, s->lobes > 1 ? (uint32_t)s->lobes : 0);   /* 0 in files from before lobes: one */
    prt__put32(h + 76, s->merge_response);   /* 0 in files from before the choice: the mean */
    prt__chunks_add(l, CHUNK_LCPR, h, (size_t)LCPR_HEADER, s->cloud, (size_t)s->cloud_count * 12, s->zone_of, nv * 4, NULL);
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_zone *zone = &s->zones[z];
        prt__bytes bytes = {0};
        unsigned char zh[ZONE_HEADER] = {0};
        prt__put32(zh, z);
        prt__put32(zh + 4, zone->lights);
        prt__put32(zh + 8, zone->diffuse.vertices);
        prt__put32(zh + 12, zone->glossy.vertices);
        prt__put32(zh + 16, zone->diffuse.raw || !zone->diffuse.vertices ? 0 : 1);
        prt__put32(zh + 20, zone->glossy.raw || !zone->glossy.vertices ? 0 : 1);
        prt__bytes_put(&bytes, zh, sizeof zh);
        prt__bytes_put(&bytes, zone->light_of, (size_t)s->cloud_count * 4);
        prt__bytes_put(&bytes, zone->positions, (size_t)zone->lights * 12);
        put_block(&bytes, &zone->diffuse);
        put_block(&bytes, &zone->glossy);
        void *copy = bytes.failed ? NULL : prt__chunks_alloc(l, bytes.size);
        if (copy) {
            memcpy(copy, bytes.data, bytes.size);
            prt__chunks_add(l, CHUNK_LCZN, copy, bytes.size, NULL);
        } else {
            l->failed = true;
        }
        prt__bytes_free(&bytes);
    }
    if (s->emit) prt__chunks_add(l, CHUNK_LCEM, s->emit, nv * 6 * sizeof(float), s->emit_sh, (size_t)s->glossy_count * 48 * sizeof(float), NULL);
    return PRT_OK;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %s", msg); }

typedef struct cursor { const unsigned char *p; uint64_t left; } cursor;

/* The next n x size bytes, or NULL when the chunk holds fewer (no overflow: n and size are
 * bounded by the chunk length first). */
static const unsigned char *take(cursor *c, uint64_t n, uint64_t size)
{
    if (size && n > c->left / size) return NULL;
    const unsigned char *p = c->p;
    c->p += n * size;
    c->left -= n * size;
    return p;
}

static prt_status load_block(prt_context *ctx, cursor *c, uint32_t rows, uint32_t dim, bool compressed, prt__lightcloud_block *b)
{
    b->vertices = rows;
    b->dim = dim;
    if (!rows) return PRT_OK;
    if (!compressed) {
        const unsigned char *p = take(c, (uint64_t)rows * dim, 4);
        if (!p) return bad(ctx, "light-cloud zone chunk too short");
        if (!(b->raw = malloc((size_t)rows * dim * 4))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(b->raw, p, (size_t)rows * dim * 4);
        return prt__all_finite(b->raw, (size_t)rows * dim) ? PRT_OK : bad(ctx, "non-finite light responses");
    }
    const unsigned char *h = take(c, CPCA_HEADER, 1);
    if (!h) return bad(ctx, "light-cloud zone chunk too short");
    const uint32_t clusters = prt__get32(h);
    const uint64_t nvec = prt__get64(h + 8), nw = prt__get64(h + 16);
    if (clusters == 0 || clusters > rows || nvec > (uint64_t)clusters * dim || nw > nvec * rows) return bad(ctx, "light-cloud CPCA counts out of range");
    const unsigned char *counts = take(c, clusters, 4), *means = take(c, (uint64_t)clusters * dim, 4), *basis = take(c, nvec * dim, 4),
                        *cluster_of = take(c, rows, 4), *weights = take(c, nw, 4);
    if (!counts || !means || !basis || !cluster_of || !weights) return bad(ctx, "light-cloud zone chunk too short");
    prt__cpca *cp = prt__calloc(1, sizeof *cp);
    if (!cp) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    b->cpca = cp;
    cp->method = PRT_COMPRESS_CPCA;
    cp->clusters = (int)clusters;
    cp->dim = (int)dim;
    cp->vectors_total = nvec;
    cp->weights_total = nw;
    memcpy(&cp->relative_error, h + 24, 8);
    cp->counts = malloc(clusters * 4ull);
    cp->means = malloc((size_t)clusters * dim * 4);
    cp->basis = malloc(nvec * dim * 4 + 4);
    cp->cluster_of = malloc(rows * 4ull);
    cp->weights = malloc(nw * 4 + 4);
    if (!cp->counts || !cp->means || !cp->basis || !cp->cluster_of || !cp->weights) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(cp->counts, counts, clusters * 4ull);
    memcpy(cp->means, means, (size_t)clusters * dim * 4);
    memcpy(cp->basis, basis, nvec * dim * 4);
    memcpy(cp->cluster_of, cluster_of, rows * 4ull);
    memcpy(cp->weights, weights, nw * 4);
    if (!prt__cpca_index(cp, rows)) return bad(ctx, "light-cloud CPCA indices are inconsistent");
    if (!prt__all_finite(cp->means, (size_t)clusters * dim) || !prt__all_finite(cp->basis, nvec * dim) || !prt__all_finite(cp->weights, nw))
        return bad(ctx, "non-finite light-cloud CPCA data");
    return PRT_OK;
}

static prt_status load_zone(prt_context *ctx, const prt_transfer *t, prt__lightcloud_set *s, uint32_t z, const prt__chunk_in *in)
{
    cursor c = {in->data, in->size};
    const unsigned char *h = take(&c, ZONE_HEADER, 1);
    if (!h) return bad(ctx, "light-cloud zone chunk too short");
    prt__lightcloud_zone *zone = &s->zones[z];
    const uint32_t lights = prt__get32(h + 4), nz = prt__get32(h + 8), gz = prt__get32(h + 12), dform = prt__get32(h + 16), gform = prt__get32(h + 20);
    if (prt__get32(h) != z || lights == 0 || lights > s->cloud_count || nz != s->member_start[z + 1] - s->member_start[z] ||
        gz != s->glossy_start[z + 1] - s->glossy_start[z] || dform > 1 || gform > 1)
        return bad(ctx, "light-cloud zone header does not match the mesh");
    (void)t;
    const unsigned char *light_of = take(&c, s->cloud_count, 4), *pos = take(&c, lights, 12);
    if (!light_of || !pos) return bad(ctx, "light-cloud zone chunk too short");
    zone->lights = lights;
    zone->light_of = malloc((size_t)s->cloud_count * 4);
    zone->positions = malloc((size_t)lights * 12);
    if (!zone->light_of || !zone->positions) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(zone->light_of, light_of, (size_t)s->cloud_count * 4);
    memcpy(zone->positions, pos, (size_t)lights * 12);
    for (uint32_t j = 0; j < s->cloud_count; ++j)
        if (zone->light_of[j] >= lights) return bad(ctx, "light-cloud merged light index out of range");
    if (!prt__all_finite(zone->positions, (size_t)lights * 3)) return bad(ctx, "non-finite light-cloud positions");
    const uint32_t cols = lights * (uint32_t)s->lobes;   /* lights <= cloud_count <= 2^20: 48 x 9 x lights fits 32 bits */
    prt_status st = load_block(ctx, &c, nz, 3 * cols, dform == 1, &zone->diffuse);
    if (!st) st = load_block(ctx, &c, gz, 48 * cols, gform == 1, &zone->glossy);
    if (!st && c.left) st = bad(ctx, "light-cloud zone chunk has trailing bytes");
    return st;
}

prt_status prt__lightcloud_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    (void)meta;
    const size_t nv = t->mesh.vertex_count;
    prt__lightcloud_set *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = s;
    if (!(s->cache = prt__lightcloud_cache_new())) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_LCPR);
    if (!c) return bad(ctx, "the light-cloud parameter chunk is missing");
    const unsigned char *h = c->data;
    if (c->size < LCPR_HEADER || prt__get64(h + 40) != nv) return bad(ctx, "invalid light-cloud parameter chunk");
    s->cloud_count = prt__get32(h);
    s->zone_count = prt__get32(h + 4);
    const uint32_t lobes = prt__get32(h + 72);
    if (lobes != 0 && lobes != 4 && lobes != 9) return bad(ctx, "light-cloud emission lobes out of range");
    s->lobes = lobes ? (int)lobes : 1;
    const uint32_t store = prt__get32(h + 8), bounces = prt__get32(h + 12), samples = prt__get32(h + 16), glossy = prt__get32(h + 20);
    memcpy(&s->spacing, h + 24, 4);
    memcpy(&s->ray_offset, h + 28, 4);
    memcpy(&s->merge_distance, h + 32, 4);
    memcpy(&s->merge_error, h + 36, 4);
    memcpy(s->region, h + 48, sizeof s->region);
    s->merge_response = prt__get32(h + 76);
    if (s->merge_response > PRT__LIGHTCLOUD_MERGE_SOLVE) return bad(ctx, "light-cloud merge response out of range");
    for (int k = 0; k < 3; ++k)
        if (!isfinite(s->region[k]) || !isfinite(s->region[3 + k]) || !(s->region[k] <= s->region[3 + k]) || fabsf(s->region[k]) > 1e30f ||
            fabsf(s->region[3 + k]) > 1e30f)
            return bad(ctx, "light-cloud region out of range");
    if (s->cloud_count == 0 || s->cloud_count > PRT__LIGHTCLOUD_MAX_LIGHTS || s->zone_count == 0 || s->zone_count > nv || store > 1 || bounces < 1 ||
        bounces > 64 || samples > (1u << 20) || !(s->spacing >= 0) || !isfinite(s->spacing) || !(s->ray_offset > 0) || !isfinite(s->ray_offset) ||
        !isfinite(s->merge_distance) || !isfinite(s->merge_error))
        return bad(ctx, "light-cloud parameters out of range");
    if (c->size != LCPR_HEADER + (uint64_t)s->cloud_count * 12 + nv * 4) return bad(ctx, "light-cloud parameter chunk size mismatch");
    if (!(s->ray_offset <= fmaxf(1e4f * prt__ray_offset(&t->mesh), 1e-6f))) return bad(ctx, "light-cloud ray offset larger than the scene");
    s->store_direct = store;
    s->bounces = (int)bounces;
    s->samples = (int)samples;
    s->cloud = malloc((size_t)s->cloud_count * 12);
    s->zone_of = malloc(nv * 4 + 4);
    s->zones = prt__calloc(s->zone_count, sizeof *s->zones);
    if (!s->cloud || !s->zone_of || !s->zones) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(s->cloud, h + LCPR_HEADER, (size_t)s->cloud_count * 12);
    memcpy(s->zone_of, h + LCPR_HEADER + (size_t)s->cloud_count * 12, nv * 4);
    if (!prt__all_finite(s->cloud, (size_t)s->cloud_count * 3)) return bad(ctx, "non-finite light-cloud positions");
    for (uint32_t i = 0; i < s->cloud_count * 3; ++i)
        if (fabsf(s->cloud[i]) > 1e30f) return bad(ctx, "light-cloud positions out of range");
    if (!prt__lightcloud_index(t, s)) return bad(ctx, "light-cloud zones are inconsistent (a vertex's zone out of range or an empty zone)");
    if (s->glossy_count != glossy) return bad(ctx, "the light-cloud glossy vertices do not match the glossy materials");
    prt_status st = PRT_OK;
    for (uint32_t z = 0; z < s->zone_count && !st; ++z) {
        prt__chunk_in *zc = prt__chunk_take(chunks, count, CHUNK_LCZN);
        st = zc ? load_zone(ctx, t, s, z, zc) : bad(ctx, "a light-cloud zone chunk is missing");
    }
    if (!st && prt__chunk_take(chunks, count, CHUNK_LCZN)) st = bad(ctx, "more light-cloud zone chunks than zones");
    c = st ? NULL : prt__chunk_take(chunks, count, CHUNK_LCEM);
    if (!st && !c != !t->mesh.emission) st = bad(ctx, "the light-cloud emitter chunk does not match the mesh's emission");
    if (!st && c) {
        const uint64_t n = nv * 6 + (uint64_t)s->glossy_count * 48;
        if (c->size != n * 4) st = bad(ctx, "light-cloud emitter chunk size mismatch");
        else if (!(s->emit = malloc(nv * 6 * 4)) || !(s->emit_sh = malloc((size_t)s->glossy_count * 48 * 4 + 4))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            memcpy(s->emit, c->data, nv * 6 * 4);
            memcpy(s->emit_sh, c->data + nv * 6 * 4, (size_t)s->glossy_count * 48 * 4);
            if (!prt__all_finite(s->emit, nv * 6) || !prt__all_finite(s->emit_sh, (size_t)s->glossy_count * 48)) st = bad(ctx, "non-finite light-cloud emitter light");
        }
        if (!st && prt__chunk_take(chunks, count, CHUNK_LCEM)) st = bad(ctx, "a light-cloud chunk appears twice");
    }
    if (!st && prt__chunk_take(chunks, count, CHUNK_LCPR)) st = bad(ctx, "a light-cloud chunk appears twice");
    return st;
}
