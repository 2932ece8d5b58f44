/* The light-cloud method's table entry (precomputed local radiance transfer, Kristensen,
 * Akenine-Moller & Jensen 2005): bake options, its chunks in file.c (LCPR, LCZN per zone, LCEM),
 * description, the neighbours control and relighting of point and sphere lights (and of spot and
 * ies lights with emission lobes, lobes.c). The bake is bake.c (+ cluster.c), the run time
 * relight.c. */
#include "methods/lightcloud/lightcloud.h"
#include "transfer/gpu_sums.h"
#include "methods/spectral/spectral.h"


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
        prt__gpu_sums_free(s->cache->gpu);
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
    {"merge-response", "HOW", PRT_OPTION_CHOICE, 0, 0, "mean|harmonic|solve",
     "a merged light's response: mean (default) of its lights', their harmonic mean (the paper's "
     "wording), or solve: a solution at its position (one more solve per merged light and zone)"},
    {"responses", "FILE", PRT_OPTION_TEXT, 0, 0, NULL,
     "keep each cloud light's solution in FILE (all its emission lobes), and take those it already "
     "holds (same scene, settings and --emission-order): adding lights to a cloud (more --cloud "
     "positions) solves only the new ones"},
    {"store", "WHAT", PRT_OPTION_CHOICE, 0, 0, "indirect|all",
     "indirect (default): the run time adds direct light with shadows, per pixel when drawn; "
     "all: direct light baked too (soft, compresses worse)"},
    {"bounces", "N", PRT_OPTION_INT, 1, 64, NULL,
     "light bounces of each cloud light's solution (default 16: closed rooms need many), the rest of the series estimated "
     "after them (the spectral run time's tail)"},
    {"emission-order", "N", PRT_OPTION_INT, 1, 3, NULL,
     "SH order of each cloud light's emission: 1 (default) isotropic, point and sphere lights only; "
     "2 or 3: 4 or 9 solves and responses per cloud light, so that spot and ies lights relight "
     "through the cloud (narrowest cone held: README)"},
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

/* The spectral stages' memory (the bake runs them, on a second copy of the mesh), then per light or
 * zone in flight: one cloud light's solve (a few arrays over every vertex) and one zone's
 * responses to every light and lobe, merged and compressed (the responses themselves wait in a
 * scratch file). Lights counted from the grid or --cloud-surface (a --cloud FILE: as the default
 * grid). Over a limit, fewer lights and zones are in flight than threads (bake.c): at least one,
 * the least. fixed and per_flight: what the bake sizes that by (prt__lightcloud_bake_desc). */
static void lightcloud_memory_parts(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *e, uint64_t *fixed,
                                    uint64_t *per_flight)
{
    prt__spectral_bake_desc d = {0};
    d.functions = prt__opt_int(o, "basis", 0);
    d.full = prt__opt_flag(o, "full-basis");
    d.partition_size = prt__opt_int(o, "partition", 0);
    d.samples = prt__opt_int(o, "samples", 0);
    prt__spectral_memory(t, &d, threads, e);
    /* Under a limit the spectral stages stream too (bake.c passes it on): their least. */
    const uint64_t nv = t->mesh.vertex_count, spectral = e->bytes, spectral_least = e->least ? e->least : e->bytes;
    *fixed = *per_flight = 0;
    uint64_t lights = 216;
    const char *grid = prt__opt(o, "cloud-grid");
    int g[3];
    if (grid && sscanf(grid, "%d,%d,%d", &g[0], &g[1], &g[2]) == 3 && g[0] > 0 && g[1] > 0 && g[2] > 0) lights = (uint64_t)g[0] * g[1] * g[2];
    if (prt__opt(o, "cloud-surface")) lights = (uint64_t)prt__opt_int(o, "cloud-surface", 216);
    /* More is refused by the bake's own checks, which say so more plainly than a size would:
     * no estimate stands in their way. */
    if (lights > PRT__LIGHTCLOUD_MAX_LIGHTS) { e->bytes = e->least = 0; return; }
    const int order = prt__opt_int(o, "emission-order", 1);
    uint64_t zone = (uint64_t)prt__opt_int(o, "zone-vertices", 2000);
    if (zone > nv) zone = nv;
    const uint64_t lobes = (uint64_t)order * order;
    const uint64_t mesh = nv * (12 * sizeof(float) + 4) + t->mesh.triangle_count * 12;
    *per_flight = nv * 3 * sizeof(float) * 8 + zone * lights * lobes * 3 * sizeof(float) * 3;
    *fixed = spectral_least + mesh;
    const uint64_t flights = threads > 1 ? (uint64_t)threads : 1;
    e->bytes = spectral + mesh + flights * *per_flight;
    e->least = *fixed + *per_flight;
    snprintf(e->what, sizeof e->what, "%.0f MiB for the spectral stages, %.0f MiB a thread for the solves and zones of %llu lights%s",
             (double)spectral / 1048576.0, (double)*per_flight / 1048576.0, (unsigned long long)lights,
             flights > 1 ? ", fewer of them in flight under a limit" : "");
    snprintf(e->lower, sizeof e->lower, "a smaller --basis, --zone-vertices or fewer cloud lights");
}

static void lightcloud_memory_estimate(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *e)
{
    uint64_t fixed, per_flight;
    lightcloud_memory_parts(t, o, threads, e, &fixed, &per_flight);
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
    d.merge_response = PRT__LIGHTCLOUD_MERGE_MEAN + prt__opt_choice(o, "merge-response", 0);
    d.responses_path = prt__opt(o, "responses");
    d.store_direct = prt__opt_choice(o, "store", 0) == 1;
    d.bounces = prt__opt_int(o, "bounces", 0);
    d.emission_order = prt__opt_int(o, "emission-order", 0);
    d.raw = prt__opt_choice(o, "compress", 0) == 1;
    if (d.raw && (prt__opt(o, "clusters") || prt__opt(o, "vectors"))) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--clusters and --vectors apply to --compress cpca, not none");
    d.clusters = prt__opt_int(o, "clusters", 0);
    d.vectors = prt__opt_int(o, "vectors", 0);
    prt__memory_estimate e;
    memset(&e, 0, sizeof e);
    lightcloud_memory_parts(t, o, prt__threads(ctx), &e, &d.memory_fixed, &d.memory_per_flight);
    d.memory_fixed += prt__memory_scene_bytes(t);
    return prt__lightcloud_bake_begin(ctx, scene, o, &d, t, job);
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

static const char *merge_name(uint32_t how)
{
    return how == PRT__LIGHTCLOUD_MERGE_HARMONIC ? "harmonic" : how == PRT__LIGHTCLOUD_MERGE_SOLVE ? "solve" : "mean";
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
            coeffs += (double)nz * zone->lights * s->lobes;
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
        cJSON_AddStringToObject(j, "merge_response", merge_name(s->merge_response));
        cJSON_AddStringToObject(j, "stored", s->store_direct ? "all" : "indirect");
        cJSON_AddStringToObject(j, "compression", compressed ? "cpca" : "none");
        cJSON_AddNumberToObject(j, "coefficients_per_vertex", per_vertex);
        cJSON_AddNumberToObject(j, "cpca_relative_error", rel);
        cJSON_AddNumberToObject(j, "bounces", s->bounces);
        cJSON_AddNumberToObject(j, "emission_order", s->lobes == 9 ? 3 : s->lobes == 4 ? 2 : 1);
        cJSON_AddNumberToObject(j, "glossy_vertices", s->glossy_count);
        return;
    }
    prt__describe_line(d, "cloud:", "%u point light%s, spacing %.4g, over (%.4g, %.4g, %.4g) .. (%.4g, %.4g, %.4g); %s baked (%d bounces)",
                       s->cloud_count, s->cloud_count == 1 ? "" : "s", s->spacing, s->region[0], s->region[1], s->region[2], s->region[3], s->region[4],
                       s->region[5], s->store_direct ? "direct and indirect light" : "indirect light", s->bounces);
    prt__describe_line(d, "bake:", "%d gathering rays per vertex for the bounces", s->samples);
    if (s->lobes > 1)
        prt__describe_line(d, "emission:", "SH order %d: %d lobes per cloud light (relights spot and ies lights)", s->lobes == 9 ? 3 : 2, s->lobes);
    prt__describe_line(d, "zones:", "%u (%u..%u vertices), merged lights per zone %u..%u (mean %.1f; merge distance %.4g, error %.3g; responses: %s)",
                       s->zone_count, vmin, vmax, lmin, lmax, lsum / s->zone_count, s->merge_distance, s->merge_error, merge_name(s->merge_response));
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
    /* The renderer draws no photometric profile: ies lights' direct light is per vertex, and the
     * other lights go first (below) so that they can still be drawn per pixel. */
    int plain = 0;
    for (int i = 0; i < count; ++i) plain += prt_lighting_light(l, i)->type != PRT_LIGHT_IES;
    const int pixel = s->store_direct || d->per_vertex || d->no_pixel_lights || d->component == PRT_COMPONENT_INDIRECT ? 0
                      : plain < PRT_MAX_PIXEL_LIGHTS ? plain : PRT_MAX_PIXEL_LIGHTS;
    float *w = malloc(((size_t)s->cloud_count * s->lobes * 3 + 3) * sizeof(float));
    float *cloud = prt__calloc(nv * 3, sizeof(float)), *E = prt__calloc(nv * 3, sizeof(float));
    float *exit_sh = s->glossy_count ? prt__calloc(nv * 48, sizeof(float)) : NULL;
    if (!w || !cloud || !E || (s->glossy_count && !exit_sh)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__lightcloud_weights(ctx, t, l, neighbours, w);
    /* Drawn with all its light, the responses are summed on the GPU (gpu.c), the glossy exit
     * vectors too: cloud stays zero and exit_sh unused here. */
    const bool gpu = d->gpu_finish && d->component == PRT_COMPONENT_ALL && !r->indirect;
    if (!st && gpu) st = prt__lightcloud_gpu(ctx, t, w, prt_lighting_emission(l), r);
    if (!st && d->component != PRT_COMPONENT_DIRECT && !gpu) st = prt__lightcloud_eval(ctx, t, w, cloud, exit_sh);
    /* Direct light of the user's lights, unless the cloud holds it. */
    if (!st && !s->store_direct && count) {
        prt_light *lights = malloc((size_t)count * sizeof(prt_light));
        if (!lights) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            int at = 0;
            for (int pass = 0; pass < 2; ++pass)
                for (int i = 0; i < count; ++i)
                    if ((prt_lighting_light(l, i)->type == PRT_LIGHT_IES) == (pass == 1)) lights[at++] = *prt_lighting_light(l, i);
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
                    st = prt__relit_pixel_materials(ctx, t, NULL, r);
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
        if (exit_sh && d->component != PRT_COMPONENT_DIRECT && !gpu) {
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
    if (!r->pixel_lights) return PRT_OK;
    const prt__lightcloud_set *s = t->state;
    prt_status st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, &s->cache->lights);
    const prt__vertex_materials mat = {r->pixel_albedo, r->pixel_material, r->pixel_brdfs, r->pixel_brdf_count};
    if (!st) prt__vertex_lights_shade(ctx, &s->cache->lights, &t->mesh, r->pixel_lights, r->pixel_light_count, &mat, eye, rgb);
    return st;
}

const prt__method prt__method_lightcloud = {
    .name = "lightcloud",
    .title = "precomputed local radiance transfer through a light cloud",
    .summary = "light cloud (Kristensen, Akenine-Moller & Jensen): drag point lights anywhere in a region, full global illumination",
    .lighting = PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_IES | PRT_LIGHTS_SPHERE | PRT_LIGHTS_EMISSIVE,
    /* The run time could recolour the direct light it adds, but not the bounced light it reads:
     * a half-recoloured scene would bleed the old colours, so colours are refused outright. */
    .baked_albedo_why = "every bounce of each stored cloud-light response was multiplied by the baked colours, so a new "
                        "colour changes every response (spectral relights the same lights with colours live)",
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .bake_begin = lightcloud_bake_begin,
    .memory_estimate = lightcloud_memory_estimate,
    .free_state = prt__lightcloud_set_free,
    .save = prt__lightcloud_save,
    .load = prt__lightcloud_load,
    .describe = lightcloud_describe,
    .transfer_bytes = lightcloud_bytes,
    .control_range = lc_control_range,
    .web = prt__lightcloud_web,
    .gpu_passes = true,
    .relight = lightcloud_relight,
    .shade = lightcloud_shade,
};
