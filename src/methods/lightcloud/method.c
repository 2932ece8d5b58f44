/* The light-cloud method's table entry (precomputed local radiance transfer, Kristensen,
 * Akenine-Moller & Jensen 2005): bake options, its chunks (LCPR, LCZN per zone, LCEM),
 * description, the neighbours control and relighting of point and sphere lights. The bake is
 * bake.c (+ cluster.c), the run time relight.c. */
#include "methods/lightcloud/lightcloud.h"

#define CHUNK_LCPR PRT__FOURCC('L', 'C', 'P', 'R')
#define CHUNK_LCZN PRT__FOURCC('L', 'C', 'Z', 'N')
#define CHUNK_LCEM PRT__FOURCC('L', 'C', 'E', 'M')
#define LCPR_HEADER 80
#define ZONE_HEADER 24
#define CPCA_HEADER 32

prt__lightcloud_cache *prt__lightcloud_cache_new(void)
{
    prt__lightcloud_cache *c = prt__calloc(1, sizeof *c);
    if (c) {
        pthread_mutex_init(&c->lock, NULL);
        prt__vertex_lights_init(&c->lights);
    }
    return c;
}

void prt__lightcloud_block_free(prt__lightcloud_block *b)
{
    free(b->raw);
    prt__cpca_free(b->cpca);
    memset(b, 0, sizeof *b);
}

void prt__lightcloud_set_free(void *state)
{
    prt__lightcloud_set *s = state;
    if (!s) return;
    for (uint32_t z = 0; s->zones && z < s->zone_count; ++z) {
        free(s->zones[z].light_of);
        free(s->zones[z].positions);
        prt__lightcloud_block_free(&s->zones[z].diffuse);
        prt__lightcloud_block_free(&s->zones[z].glossy);
    }
    free(s->zones);
    free(s->cloud);
    free(s->zone_of);
    free(s->glossy_of);
    free(s->members);
    free(s->member_start);
    free(s->glossy_start);
    free(s->emit);
    free(s->emit_sh);
    if (s->cache) {
        prt__vertex_lights_free(&s->cache->lights);
        prt__kdtree_free(&s->cache->tree);
        pthread_mutex_destroy(&s->cache->lock);
        free(s->cache);
    }
    free(s);
}

bool prt__lightcloud_index(const prt_transfer *t, prt__lightcloud_set *s)
{
    const size_t nv = t->mesh.vertex_count;
    const uint32_t nz = s->zone_count;
    free(s->glossy_of); free(s->members); free(s->member_start); free(s->glossy_start);
    s->glossy_of = malloc(nv * sizeof(uint32_t) + 4);
    s->members = malloc(nv * sizeof(uint32_t) + 4);
    s->member_start = prt__calloc((size_t)nz + 1, sizeof(uint32_t));
    s->glossy_start = prt__calloc((size_t)nz + 1, sizeof(uint32_t));
    if (!s->glossy_of || !s->members || !s->member_start || !s->glossy_start) return false;
    s->glossy_count = 0;
    for (size_t v = 0; v < nv; ++v) {
        const uint8_t k = t->mesh.material[v];
        const bool glossy = k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1]);
        s->glossy_of[v] = glossy ? s->glossy_count++ : UINT32_MAX;
        if (s->zone_of[v] >= nz) return false;
        s->member_start[s->zone_of[v] + 1]++;
        if (glossy) s->glossy_start[s->zone_of[v] + 1]++;
    }
    for (uint32_t z = 0; z < nz; ++z) {
        if (!s->member_start[z + 1]) return false;   /* an empty zone */
        s->member_start[z + 1] += s->member_start[z];
        s->glossy_start[z + 1] += s->glossy_start[z];
    }
    uint32_t *fill = prt__calloc((size_t)nz + 1, sizeof(uint32_t));
    if (!fill) return false;
    for (size_t v = 0; v < nv; ++v) {
        const uint32_t z = s->zone_of[v];
        s->members[s->member_start[z] + fill[z]++] = (uint32_t)v;
    }
    free(fill);
    return true;
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

float prt__lightcloud_spacing(const float *cloud, uint32_t count)
{
    if (count < 2) return 0.0f;
    prt__kdtree tree;
    float *nearest = malloc(count * sizeof(float));
    if (!nearest || !prt__kdtree_build(&tree, cloud, count)) { free(nearest); return 0.0f; }
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t idx[2];
        float d[2];
        nearest[i] = prt__kdtree_nearest(&tree, cloud + (size_t)i * 3, 2, idx, d) == 2 ? d[1] : 0.0f;
    }
    prt__kdtree_free(&tree);
    qsort(nearest, count, sizeof(float), cmp_float);
    const float median = nearest[count / 2];
    free(nearest);
    return median;
}

/* ---- bake options ---- */
/* Help texts are reflowed by the printer (prt bake --help): line breaks here are for the source. */
static const prt_option_desc options[] = {
    {"cloud-grid", "NX,NY,NZ", PRT_OPTION_TEXT, 0, 0, NULL,
     "cloud lights at the centres of an NX x NY x NZ grid over the box (default 6,6,6)"},
    {"cloud-box", "X0,Y0,Z0,X1,Y1,Z1", PRT_OPTION_TEXT, 0, 0, NULL,
     "the region lights will move in (default the scene's bounds)"},
    {"cloud", "FILE", PRT_OPTION_TEXT, 0, 0, NULL,
     "cloud light positions from JSON: [[x,y,z], ...] or {\"lights\": [...]} (replaces the grid "
     "unless --cloud-grid is given too)"},
    {"cloud-surface", "N", PRT_OPTION_INT, 1, PRT__LIGHTCLOUD_MAX_LIGHTS, NULL,
     "N more lights just off the surfaces (denser where lamps go)"},
    {"zone-vertices", "N", PRT_OPTION_INT, 16, 1e7, NULL,
     "split the scene box until a zone holds at most N vertices (default 2000)"},
    {"merge-distance", "D", PRT_OPTION_FLOAT, 0, 1e30, NULL,
     "lights farther apart never merge: w1 = 1/D (default 3 x the cloud spacing; 0: no merging)"},
    {"merge-error", "E", PRT_OPTION_FLOAT, 0, 1e30, NULL,
     "responses differing by E x the zone's largest never merge: w2 = 1/(E max) (default 0.1; "
     "0: distance and visibility only)"},
    {"store", "WHAT", PRT_OPTION_CHOICE, 0, 0, "indirect|all",
     "indirect (default): the run time adds direct light with shadows, per pixel when drawn; "
     "all: direct light baked too (soft, compresses worse)"},
    {"bounces", "N", PRT_OPTION_INT, 1, 64, NULL,
     "light bounces of each cloud light's solution (default 16: closed rooms need many)"},
    {"compress", "M", PRT_OPTION_CHOICE, 0, 0, "cpca|none",
     "cpca (default): clustered PCA per zone; none: keep every response"},
    {"clusters", "K", PRT_OPTION_INT, 1, 4096, NULL, "CPCA clusters per zone (default 8)"},
    {"vectors", "N", PRT_OPTION_INT, 1, 256, NULL, "average PCA vectors per cluster (default 8)"},
    {"samples", "N", PRT_OPTION_INT, 16, 1 << 20, NULL,
     "gathering rays per vertex for the bounces (default 4096)"},
    {"basis", "N", PRT_OPTION_INT, 1, 65535, NULL, "spectral basis functions the bounces use (default 1024)"},
    {"full-basis", NULL, PRT_OPTION_FLAG, 0, 0, NULL,
     "bounces without basis truncation (at most 65535 vertices)"},
    {"partition", "V", PRT_OPTION_INT, 16, 2048, NULL,
     "vertices per METIS partition of the basis (default 1000)"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "ray origin offset (default 1e-4 x scene diagonal)"},
};

static const prt_control_desc controls[] = {
    {"neighbours", "cloud lights each user light is interpolated from", '[', ']', 0},
};

static prt_status parse_floats(prt_context *ctx, const char *name, const char *text, int n, float *out)
{
    const char *p = text;
    for (int i = 0; i < n; ++i) {
        char *end;
        const double v = strtod(p, &end);
        if (end == p || !isfinite(v) || fabs(v) > 1e30) break;
        out[i] = (float)v;
        p = end;
        if (i + 1 < n) {
            if (*p != ',') break;
            p++;
        } else if (*p == '\0') {
            return PRT_OK;
        }
    }
    return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--%s expects %d comma-separated numbers, got \"%s\"", name, n, text);
}

static prt_status lightcloud_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    prt__lightcloud_bake_desc d = {0};
    prt_status st = PRT_OK;
    const char *grid = prt__opt(o, "cloud-grid"), *box = prt__opt(o, "cloud-box");
    if (grid) {
        float g[3];
        if ((st = parse_floats(ctx, "cloud-grid", grid, 3, g))) return st;
        for (int k = 0; k < 3; ++k) {
            if (!(g[k] >= 1 && g[k] <= 4096 && g[k] == floorf(g[k])))
                return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--cloud-grid expects three whole numbers in 1..4096, got \"%s\"", grid);
            d.grid[k] = (int)g[k];
        }
    }
    if (box) {
        if ((st = parse_floats(ctx, "cloud-box", box, 6, d.box))) return st;
        d.has_box = true;
    }
    d.list_path = prt__opt(o, "cloud");
    d.surface_lights = prt__opt_int(o, "cloud-surface", 0);
    d.zone_vertices = prt__opt_int(o, "zone-vertices", 0);
    d.merge_distance = prt__opt(o, "merge-distance") ? prt__opt_float(o, "merge-distance", 0) : -1.0f;
    d.merge_error = prt__opt(o, "merge-error") ? prt__opt_float(o, "merge-error", 0) : -1.0f;
    d.store_direct = prt__opt_choice(o, "store", 0) == 1;
    d.bounces = prt__opt_int(o, "bounces", 0);
    d.raw = prt__opt_choice(o, "compress", 0) == 1;
    if (d.raw && (prt__opt(o, "clusters") || prt__opt(o, "vectors"))) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--clusters and --vectors apply to --compress cpca, not none");
    d.clusters = prt__opt_int(o, "clusters", 0);
    d.vectors = prt__opt_int(o, "vectors", 0);
    return prt__lightcloud_bake_begin(ctx, scene, o, &d, t, job);
}

/* ---- files ---- */
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

static prt_status lightcloud_save(const prt_transfer *t, prt__chunk_list *l)
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
    prt_status st = load_block(ctx, &c, nz, 3 * lights, dform == 1, &zone->diffuse);
    if (!st) st = load_block(ctx, &c, gz, 48 * lights, gform == 1, &zone->glossy);
    if (!st && c.left) st = bad(ctx, "light-cloud zone chunk has trailing bytes");
    return st;
}

static prt_status lightcloud_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
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
    const uint32_t store = prt__get32(h + 8), bounces = prt__get32(h + 12), samples = prt__get32(h + 16), glossy = prt__get32(h + 20);
    memcpy(&s->spacing, h + 24, 4);
    memcpy(&s->ray_offset, h + 28, 4);
    memcpy(&s->merge_distance, h + 32, 4);
    memcpy(&s->merge_error, h + 36, 4);
    memcpy(s->region, h + 48, sizeof s->region);
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

/* ---- description ---- */
static size_t block_bytes(const prt__lightcloud_block *b)
{
    if (!b->vertices) return 0;
    if (b->raw) return (size_t)b->vertices * b->dim * 4;
    const prt__cpca *c = b->cpca;
    return ((size_t)c->clusters * (1 + b->dim) + c->vectors_total * b->dim + b->vertices + c->weights_total) * 4;
}

static size_t lightcloud_bytes(const prt_transfer *t)
{
    const prt__lightcloud_set *s = t->state;
    size_t n = (size_t)s->cloud_count * 12 + t->mesh.vertex_count * 4;
    for (uint32_t z = 0; z < s->zone_count; ++z)
        n += (size_t)s->cloud_count * 4 + block_bytes(&s->zones[z].diffuse) + block_bytes(&s->zones[z].glossy);
    return n;
}

static void lightcloud_describe(const prt_transfer *t, prt__describe *d)
{
    const prt__lightcloud_set *s = t->state;
    uint32_t lmin = UINT32_MAX, lmax = 0, vmin = UINT32_MAX, vmax = 0;
    double lsum = 0, coeffs = 0, err2 = 0, errw = 0;
    bool compressed = false;
    for (uint32_t z = 0; z < s->zone_count; ++z) {
        const prt__lightcloud_zone *zone = &s->zones[z];
        const uint32_t nz = s->member_start[z + 1] - s->member_start[z];
        lmin = zone->lights < lmin ? zone->lights : lmin;
        lmax = zone->lights > lmax ? zone->lights : lmax;
        vmin = nz < vmin ? nz : vmin;
        vmax = nz > vmax ? nz : vmax;
        lsum += zone->lights;
        if (zone->diffuse.cpca) {
            compressed = true;
            coeffs += (double)zone->diffuse.cpca->weights_total;
            err2 += zone->diffuse.cpca->relative_error * zone->diffuse.cpca->relative_error * nz;
            errw += nz;
        } else {
            coeffs += (double)nz * zone->lights;
        }
    }
    const double per_vertex = t->mesh.vertex_count ? coeffs / t->mesh.vertex_count : 0;
    const double rel = errw > 0 ? sqrt(err2 / errw) : 0;
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "cloud_lights", s->cloud_count);
        cJSON_AddNumberToObject(j, "cloud_spacing", s->spacing);
        cJSON *region = cJSON_AddArrayToObject(j, "cloud_region");
        for (int k = 0; k < 6; ++k) cJSON_AddItemToArray(region, cJSON_CreateNumber(s->region[k]));
        cJSON_AddNumberToObject(j, "samples", s->samples);
        cJSON_AddNumberToObject(j, "zones", s->zone_count);
        cJSON *per = cJSON_AddArrayToObject(j, "merged_lights_per_zone");
        for (uint32_t z = 0; z < s->zone_count; ++z) cJSON_AddItemToArray(per, cJSON_CreateNumber(s->zones[z].lights));
        cJSON_AddNumberToObject(j, "merge_distance", s->merge_distance);
        cJSON_AddNumberToObject(j, "merge_error", s->merge_error);
        cJSON_AddStringToObject(j, "stored", s->store_direct ? "all" : "indirect");
        cJSON_AddStringToObject(j, "compression", compressed ? "cpca" : "none");
        cJSON_AddNumberToObject(j, "coefficients_per_vertex", per_vertex);
        cJSON_AddNumberToObject(j, "cpca_relative_error", rel);
        cJSON_AddNumberToObject(j, "bounces", s->bounces);
        cJSON_AddNumberToObject(j, "glossy_vertices", s->glossy_count);
        return;
    }
    prt__describe_line(d, "cloud:", "%u point light%s, spacing %.4g, over (%.4g, %.4g, %.4g) .. (%.4g, %.4g, %.4g); %s baked (%d bounces)",
                       s->cloud_count, s->cloud_count == 1 ? "" : "s", s->spacing, s->region[0], s->region[1], s->region[2], s->region[3], s->region[4],
                       s->region[5], s->store_direct ? "direct and indirect light" : "indirect light", s->bounces);
    prt__describe_line(d, "bake:", "%d gathering rays per vertex for the bounces", s->samples);
    prt__describe_line(d, "zones:", "%u (%u..%u vertices), merged lights per zone %u..%u (mean %.1f; merge distance %.4g, error %.3g)", s->zone_count,
                       vmin, vmax, lmin, lmax, lsum / s->zone_count, s->merge_distance, s->merge_error);
    if (compressed)
        prt__describe_line(d, "compression:", "clustered PCA per zone, %.1f coefficients per vertex and channel, relative error %.3g", per_vertex, rel);
    else
        prt__describe_line(d, "compression:", "none: %.1f responses per vertex and channel", per_vertex);
    if (s->glossy_count) prt__describe_line(d, "glossy:", "%u vertices with SH order 4 exit radiance", s->glossy_count);
}

static void lc_control_range(const prt_transfer *t, int i, int *lo, int *hi, int *def)
{
    (void)t;
    (void)i;
    *lo = 1;
    *hi = PRT__KDTREE_MAX_K - 1;
    *def = 8;
}

/* ---- relighting ---- */
static prt_status lightcloud_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    if (d->brdf) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf does not apply to light-cloud transfer (its materials are baked)");
    const prt__lightcloud_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    const int neighbours = d->controls ? d->controls[0] : 8;
    if (neighbours < 1 || neighbours >= PRT__KDTREE_MAX_K) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "neighbours %d out of range 1..%d", neighbours, PRT__KDTREE_MAX_K - 1);
    if (s->store_direct && d->component != PRT_COMPONENT_ALL)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "this file stores direct and indirect light together (baked with --store all): it cannot show one of them");
    /* With --store all the indirect part is not separable: no `indirect` array. */
    prt_status st = prt__relit_alloc(ctx, t, r, !s->store_direct && (d->with_indirect || d->component == PRT_COMPONENT_INDIRECT));
    if (st) return st;
    const int count = prt_lighting_count(l);
    const int pixel = s->store_direct || d->per_vertex || d->component == PRT_COMPONENT_INDIRECT ? 0 : count < PRT_MAX_PIXEL_LIGHTS ? count : PRT_MAX_PIXEL_LIGHTS;
    float *w = malloc(((size_t)s->cloud_count * 3 + 3) * sizeof(float));
    float *cloud = prt__calloc(nv * 3, sizeof(float)), *E = prt__calloc(nv * 3, sizeof(float));
    float *exit_sh = s->glossy_count ? prt__calloc(nv * 48, sizeof(float)) : NULL;
    if (!w || !cloud || !E || (s->glossy_count && !exit_sh)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__lightcloud_weights(ctx, t, l, neighbours, w);
    if (!st && d->component != PRT_COMPONENT_DIRECT) st = prt__lightcloud_eval(ctx, t, w, cloud, exit_sh);
    /* Direct light of the user's lights, unless the cloud holds it. */
    if (!st && !s->store_direct && count) {
        prt_light *lights = malloc((size_t)count * sizeof(prt_light));
        if (!lights) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            for (int i = 0; i < count; ++i) lights[i] = *prt_lighting_light(l, i);
            st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, &s->cache->lights);
            /* Drawn, the first lights' direct light is the renderer's, per pixel with shadow maps. */
            if (!st) prt__vertex_lights_add(ctx, &s->cache->lights, &t->mesh, lights + pixel, count - pixel, E);
            if (!st && pixel) {
                r->pixel_lights = malloc((size_t)pixel * sizeof(prt_light));
                r->pixel_albedo = malloc(nv * 3 * sizeof(float));
                r->pixel_visibility = malloc((size_t)pixel * nv * sizeof(float));
                if (!r->pixel_lights || !r->pixel_albedo || !r->pixel_visibility) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
                else {
                    memcpy(r->pixel_lights, lights, (size_t)pixel * sizeof(prt_light));
                    r->pixel_light_count = pixel;
                    memcpy(r->pixel_albedo, t->mesh.albedo, nv * 3 * sizeof(float));
                    prt__vertex_lights_visibility(ctx, &s->cache->lights, &t->mesh, lights, pixel, r->pixel_visibility);
                }
            }
            free(lights);
        }
    }
    const float emission = prt_lighting_emission(l), *le = t->mesh.emission;
    if (!st) {
        for (size_t i = 0; i < nv * 3; ++i) {
            const float own = le ? emission * le[i] : 0.0f;
            const float em_direct = s->emit ? emission * s->emit[i] : 0.0f, em_indirect = s->emit ? emission * s->emit[nv * 3 + i] : 0.0f;
            const float direct = t->mesh.albedo[i] / (float)PRT_PI * E[i] + em_direct;
            /* With --store all the cloud's response is direct and indirect together. */
            const float indirect = cloud[i] + em_indirect;
            if (r->indirect) r->indirect[i] = indirect;
            switch (d->component) {
            case PRT_COMPONENT_DIRECT: r->radiance[i] = own + direct; break;
            case PRT_COMPONENT_INDIRECT: r->radiance[i] = indirect; break;
            default: r->radiance[i] = own + direct + indirect; break;
            }
        }
        if (exit_sh && d->component != PRT_COMPONENT_DIRECT) {
            if (s->emit_sh && emission > 0)
                for (size_t v = 0; v < nv; ++v)
                    if (s->glossy_of[v] != UINT32_MAX)
                        for (int k = 0; k < 48; ++k) exit_sh[v * 48 + k] += emission * s->emit_sh[(size_t)s->glossy_of[v] * 48 + k];
            r->exit_sh = exit_sh;
            r->exit_order = 4;
            r->exit_mirror = 0;
            exit_sh = NULL;
        }
    }
    free(exit_sh);
    free(w);
    free(cloud);
    free(E);
    return st;
}

static prt_status lightcloud_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb)
{
    (void)eye;
    if (!r->pixel_lights) return PRT_OK;
    const prt__lightcloud_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    float *E = prt__calloc(nv * 3, sizeof(float));
    if (!E) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, &s->cache->lights);
    if (!st) prt__vertex_lights_add(ctx, &s->cache->lights, &t->mesh, r->pixel_lights, r->pixel_light_count, E);
    for (size_t i = 0; i < nv * 3 && !st; ++i) rgb[i] += r->pixel_albedo[i] / (float)PRT_PI * E[i];
    free(E);
    return st;
}

const prt__method prt__method_lightcloud = {
    .name = "lightcloud",
    .title = "precomputed local radiance transfer through a light cloud",
    .summary = "light cloud (Kristensen, Akenine-Moller & Jensen): drag point lights anywhere in a region, full global illumination",
    .lighting = PRT_LIGHTS_POINT | PRT_LIGHTS_SPHERE | PRT_LIGHTS_EMISSIVE,
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .bake_begin = lightcloud_bake_begin,
    .free_state = prt__lightcloud_set_free,
    .save = lightcloud_save,
    .load = lightcloud_load,
    .describe = lightcloud_describe,
    .transfer_bytes = lightcloud_bytes,
    .control_range = lc_control_range,
    .relight = lightcloud_relight,
    .shade = lightcloud_shade,
};
