/* The light-cloud bake (Kristensen, Akenine-Moller & Jensen 2005, sections 4-5):
 *   1. the spectral method's transfer for the scene (its stages, run as this bake's first ones):
 *      with it, the global illumination of any light is direct light plus a few sparse bounces;
 *   2. "light cloud": lights on a grid / from a list / just off the surfaces, minus those inside
 *      geometry; their mutual visibility; the zones; the emitters' own response;
 *   3. "cloud lights": one unit per cloud light: its exit radiance at every vertex (the indirect
 *      part, or all of it; taken from --responses FILE where it holds the light), written to a
 *      scratch file in zone order (and kept in FILE when the stage ends) so that
 *   4. "zones": one unit per zone, each thread holding one zone's responses at a time: lights
 *      clustered by the paper's metric (eq. 9), merged responses formed (--merge-response: the
 *      mean, the harmonic mean or a solution at the merged position), then clustered PCA.
 * Per-light solves use the path of the spectral run time rather than photon mapping: for equal
 * error it costs a few sparse products per light instead of a photon map per light. Every result
 * depends only on its unit's inputs: the file is the same for any thread count. */
#include "methods/lightcloud/lightcloud.h"
#include "methods/lightcloud/responses.h"
#include "methods/spectral/spectral.h"

#include <cjson/cJSON.h>
#include <omp.h>
#include <stdio.h>
#include <unistd.h>

/* Candidate pairs at most: beyond, the merge distance takes in a large part of the cloud (26 GiB of
 * bookkeeping at the limit). */
#define PAIRS_MAX (1ull << 29)

void openblas_set_num_threads(int);
int openblas_get_num_threads(void);

typedef struct lcbake {
    prt__bake_job base;
    prt_transfer *t;
    prt__lightcloud_set *s;
    prt__lightcloud_bake_desc d;
    /* The spectral transfer the per-light solves run on, and its bake while it runs. */
    prt_transfer *inner;
    prt__bake_job *inner_job;
    prt__stage inner_stage;
    int first_own;                   /* index of the "light cloud" stage; -1 until the inner bake ends */
    FILE *spill;                     /* responses [light][zone-ordered diffuse | glossy] */
    size_t stride;                   /* floats per light: its lobes' responses one after another */
    size_t one;                      /* floats per lobe's response */
    uint32_t *pos_of;                /* [vertex] position in member order */
    prt__lightcloud_pairs pairs;     /* the pairs within the merge distance and their mutual visibility */
    uint8_t *dark;                   /* [light] 1 when the light reaches no vertex at all */
    float merge_distance, merge_error;
    int merge_response;              /* PRT__LIGHTCLOUD_MERGE_* */
    prt__raycaster rc;               /* while the zones solve merged lights: is a mean position in open space */
    float near;                      /* closer to a surface than this is "on" it (place_cloud's rule) */
    prt__lightcloud_responses *kept; /* --responses: solutions kept by earlier bakes */
    prt__fingerprint kept_fp;
    char *responses_path;            /* its path (owned) */
    float *list;                     /* --cloud positions, read when the bake begins */
    uint32_t list_count;
    int blas_threads;                /* OpenBLAS's own thread count while the zones run (0: untouched) */
    /* Under a memory limit: at most `flights` cloud lights or zones in flight at once (0: as many
     * as threads); the others' threads wait at the gate holding nothing. */
    int flights, in_flight;
    bool gate_ready;
    pthread_mutex_t gate;
    pthread_cond_t gate_freed;
} lcbake;

/* The gate: which thread goes first changes nothing in the results, only when they come. */
static void flight_enter(lcbake *b)
{
    if (!b->flights) return;
    pthread_mutex_lock(&b->gate);
    while (b->in_flight >= b->flights) pthread_cond_wait(&b->gate_freed, &b->gate);
    b->in_flight++;
    pthread_mutex_unlock(&b->gate);
}

static void flight_leave(lcbake *b)
{
    if (!b->flights) return;
    pthread_mutex_lock(&b->gate);
    b->in_flight--;
    pthread_cond_signal(&b->gate_freed);
    pthread_mutex_unlock(&b->gate);
}

/* ---- the spectral stages, passed through ---- */
static prt_status inner_run(prt__bake_job *job, uint64_t unit, int thread)
{
    lcbake *b = (lcbake *)job;
    b->inner_job->threads = job->threads;
    return b->inner_stage.run(b->inner_job, unit, thread);
}
static prt_status inner_whole(prt__bake_job *job, prt_context *ctx, prt__progress *p)
{
    lcbake *b = (lcbake *)job;
    b->inner_job->threads = job->threads;
    return b->inner_stage.whole(b->inner_job, ctx, p);
}
static void inner_save(prt__bake_job *job, uint64_t unit, prt__bytes *out)
{
    lcbake *b = (lcbake *)job;
    b->inner_stage.save_unit(b->inner_job, unit, out);
}
static bool inner_load(prt__bake_job *job, uint64_t unit, const unsigned char *data, size_t size)
{
    lcbake *b = (lcbake *)job;
    return b->inner_stage.load_unit(b->inner_job, unit, data, size);
}

/* ---- placing the cloud ---- */
static void mesh_bounds(const prt__mesh *m, float box[6])
{
    for (int k = 0; k < 3; ++k) { box[k] = INFINITY; box[3 + k] = -INFINITY; }
    for (size_t v = 0; v < m->vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            const float x = m->positions[v * 3 + k];
            if (x < box[k]) box[k] = x;
            if (x > box[3 + k]) box[3 + k] = x;
        }
}

static prt_status read_list(prt_context *ctx, const char *path, float **pts, uint32_t *count)
{
    void *text = NULL;
    size_t size = 0;
    prt_status st = prt__read_file(path, &text, &size);
    if (st) return prt__fail(ctx, st, "%s: %s", path, prt_last_error());
    cJSON *root = cJSON_ParseWithLength(text, size);
    free(text);
    if (!root) return prt__fail(ctx, PRT_ERR_FORMAT, "%s: not valid JSON", path);
    const cJSON *list = cJSON_IsArray(root) ? root : cJSON_GetObjectItemCaseSensitive(root, "lights");
    const int n = cJSON_IsArray(list) ? cJSON_GetArraySize(list) : -1;
    if (n < 0) st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: expected a list of [x, y, z] positions (or {\"lights\": [...]})", path);
    else if (n == 0) st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: the list holds no lights", path);
    else if ((unsigned)n > PRT__LIGHTCLOUD_MAX_LIGHTS) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s: %d lights, at most %u", path, n, PRT__LIGHTCLOUD_MAX_LIGHTS);
    float *p = st ? NULL : malloc((size_t)(n > 0 ? n : 1) * 3 * sizeof(float));
    if (!st && !p) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int i = 0; i < n && !st; ++i) {
        const cJSON *e = cJSON_GetArrayItem(list, i);
        if (cJSON_IsObject(e)) e = cJSON_GetObjectItemCaseSensitive(e, "position");
        bool ok = cJSON_IsArray(e) && cJSON_GetArraySize(e) == 3;
        for (int k = 0; ok && k < 3; ++k) {
            const cJSON *x = cJSON_GetArrayItem(e, k);
            ok = cJSON_IsNumber(x) && isfinite(x->valuedouble) && fabs(x->valuedouble) < 1e30;
            if (ok) p[i * 3 + k] = (float)x->valuedouble;
        }
        if (!ok) st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: light %d is not a position [x, y, z] of finite numbers", path, i);
    }
    cJSON_Delete(root);
    if (st) { free(p); return st; }
    *pts = p;
    *count = (uint32_t)n;
    return PRT_OK;
}

/* 1 inside geometry (most of 14 rays in fixed directions reach the back of a surface first), 2 on
 * a surface (one of them hits within `near`: such a light would see both sides of a thin shelf or
 * wall), else 0. */
static int inside(const prt__raycaster *rc, const float p[3], float near)
{
    static const float dirs[14][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1},
                                      {.577f, .577f, .577f}, {-.577f, .577f, .577f}, {.577f, -.577f, .577f}, {.577f, .577f, -.577f},
                                      {-.577f, -.577f, .577f}, {-.577f, .577f, -.577f}, {.577f, -.577f, -.577f}, {-.577f, -.577f, -.577f}};
    int back = 0;
    bool touching = false;
    for (int i = 0; i < 14; ++i) {
        struct RTCIntersectContext ictx;
        rtcInitIntersectContext(&ictx);
        struct RTCRayHit rh;
        memset(&rh, 0, sizeof rh);
        rh.ray.org_x = p[0]; rh.ray.org_y = p[1]; rh.ray.org_z = p[2];
        rh.ray.dir_x = dirs[i][0]; rh.ray.dir_y = dirs[i][1]; rh.ray.dir_z = dirs[i][2];
        rh.ray.tfar = INFINITY;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(rc->scene, &ictx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        if (rh.ray.tfar < near) touching = true;
        if (rh.hit.Ng_x * dirs[i][0] + rh.hit.Ng_y * dirs[i][1] + rh.hit.Ng_z * dirs[i][2] > 0) back++;
    }
    return back > 7 ? 1 : touching ? 2 : 0;
}

/* The grid's cells (into g), or 0 when a list replaces the grid. */
static uint64_t grid_size(const prt__lightcloud_bake_desc *d, int g[3])
{
    g[0] = g[1] = g[2] = 6;
    if (d->grid[0]) memcpy(g, d->grid, 3 * sizeof(int));
    else if (d->list_path) return 0;
    return (uint64_t)g[0] * g[1] * g[2];
}

static prt_status place_cloud(lcbake *b, const prt__raycaster *rc)
{
    prt_context *ctx = b->base.ctx;
    const prt__mesh *m = &b->t->mesh;
    float box[6];
    if (b->d.has_box) memcpy(box, b->d.box, sizeof box);
    else mesh_bounds(m, box);
    const float diag = sqrtf((box[3] - box[0]) * (box[3] - box[0]) + (box[4] - box[1]) * (box[4] - box[1]) + (box[5] - box[2]) * (box[5] - box[2]));
    const float *list = b->list;
    const uint32_t nlist = b->list_count;
    prt_status st = PRT_OK;
    int g[3];
    const uint64_t ngrid = grid_size(&b->d, g);
    const uint64_t total = ngrid + nlist + (uint64_t)b->d.surface_lights;   /* checked when the bake began */
    float *p = malloc((size_t)(total ? total : 1) * 3 * sizeof(float));
    if (!p) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    uint64_t n = 0;
    for (int z = 0; z < (ngrid ? g[2] : 0); ++z)
        for (int y = 0; y < g[1]; ++y)
            for (int x = 0; x < g[0]; ++x, ++n) {
                p[n * 3 + 0] = box[0] + (box[3] - box[0]) * (x + 0.5f) / g[0];
                p[n * 3 + 1] = box[1] + (box[4] - box[1]) * (y + 0.5f) / g[1];
                p[n * 3 + 2] = box[2] + (box[5] - box[2]) * (z + 0.5f) / g[2];
            }
    if (nlist) memcpy(p + n * 3, list, (size_t)nlist * 3 * sizeof(float));
    n += nlist;
    if (b->d.surface_lights) {
        /* Area-weighted points on the triangles, moved off the front face by half a grid cell
         * (or 5% of the box): dense lighting where a designer puts lamps, against the walls. */
        const float lift = ngrid ? 0.5f * diag / cbrtf((float)ngrid) : 0.05f * diag;
        double *cdf = malloc((m->triangle_count + 1) * sizeof(double));
        if (!cdf) { free(p); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        cdf[0] = 0;
        for (size_t i = 0; i < m->triangle_count; ++i) {
            const uint32_t *tri = m->indices + i * 3;
            float e1[3], e2[3], c[3];
            prt__v3_sub(m->positions + tri[1] * 3, m->positions + tri[0] * 3, e1);
            prt__v3_sub(m->positions + tri[2] * 3, m->positions + tri[0] * 3, e2);
            prt__v3_cross(e1, e2, c);
            cdf[i + 1] = cdf[i] + 0.5 * prt__v3_len(c);
        }
        for (int i = 0; i < b->d.surface_lights && cdf[m->triangle_count] > 0; ++i) {
            double u, v;
            prt__sobol2((uint32_t)i, 0x4C434C44u, &u, &v);
            const double target = (i + 0.5) / b->d.surface_lights * cdf[m->triangle_count];
            size_t lo = 0, hi = m->triangle_count;
            while (hi - lo > 1) { size_t mid = (lo + hi) / 2; if (cdf[mid] <= target) lo = mid; else hi = mid; }
            const uint32_t *tri = m->indices + lo * 3;
            if (u + v > 1) { u = 1 - u; v = 1 - v; }
            float e1[3], e2[3], nrm[3];
            prt__v3_sub(m->positions + tri[1] * 3, m->positions + tri[0] * 3, e1);
            prt__v3_sub(m->positions + tri[2] * 3, m->positions + tri[0] * 3, e2);
            prt__v3_cross(e1, e2, nrm);
            if (!prt__v3_normalize(nrm)) continue;
            for (int k = 0; k < 3; ++k)
                p[n * 3 + k] = m->positions[tri[0] * 3 + k] + (float)u * e1[k] + (float)v * e2[k] + lift * nrm[k];
            n++;
        }
        free(cdf);
    }
    /* The region the cloud covers: the grid's box, and the other lights' bounds grown below. */
    float region[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    if (ngrid) memcpy(region, box, sizeof region);
    /* Drop lights inside geometry or on a surface (closer than a tenth of a grid cell, or than 1%
     * of the box's diagonal). */
    float near = 0.01f * diag;
    if (ngrid)
        for (int k = 0; k < 3; ++k) near = fminf(near, 0.1f * (box[3 + k] - box[k]) / g[k]);
    b->near = near;
    uint64_t kept = 0, in = 0, on = 0;
    for (uint64_t i = 0; i < n; ++i) {
        const int where = inside(rc, p + i * 3, near);
        in += where == 1;
        on += where == 2;
        if (where) continue;
        memmove(p + kept * 3, p + i * 3, 3 * sizeof(float));
        kept++;
    }
    if (in || on)
        prt__log(ctx, PRT_LOG_INFO, "light cloud: of %llu lights, %llu lie inside geometry and %llu on a surface: dropped", (unsigned long long)n,
                 (unsigned long long)in, (unsigned long long)on);
    if (!kept) { free(p); return prt__fail(ctx, PRT_ERR_INVALID_ARG, "no cloud light lies in open space: give a box (--cloud-box) or a list inside the open space"); }
    b->s->cloud = p;
    b->s->cloud_count = (uint32_t)kept;
    float spacing = prt__lightcloud_spacing(p, (uint32_t)kept);
    if (kept == 1) {   /* no neighbour to measure: half the region's largest side (the scene's when the cloud is one listed light) */
        float mesh_box[6];
        mesh_bounds(m, mesh_box);
        const float *r = ngrid ? box : mesh_box;
        spacing = 0.5f * fmaxf(r[3] - r[0], fmaxf(r[4] - r[1], r[5] - r[2]));
    }
    if (nlist || b->d.surface_lights)   /* lights not on the grid: the bounds of all of them, grown by half a spacing */
        for (uint64_t i = 0; i < kept; ++i)
            for (int k = 0; k < 3; ++k) {
                region[k] = fminf(region[k], p[i * 3 + k] - 0.5f * spacing);
                region[3 + k] = fmaxf(region[3 + k], p[i * 3 + k] + 0.5f * spacing);
            }
    b->s->spacing = spacing;
    memcpy(b->s->region, region, sizeof region);
    return st;
}

/* ---- zones: boxes split at the middle of their longest axis ---- */
static prt_status split_zones(lcbake *b, uint32_t *idx, uint32_t n, uint32_t *zone_count)
{
    const prt__mesh *m = &b->t->mesh;
    float mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const float x = m->positions[(size_t)idx[i] * 3 + k];
            mn[k] = x < mn[k] ? x : mn[k];
            mx[k] = x > mx[k] ? x : mx[k];
        }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (mx[k] - mn[k] > mx[axis] - mn[axis]) axis = k;
    const float mid = 0.5f * (mn[axis] + mx[axis]);
    uint32_t left = 0;
    if (n > (uint32_t)b->d.zone_vertices && mx[axis] > mn[axis]) {
        for (uint32_t i = 0; i < n; ++i)
            if (m->positions[(size_t)idx[i] * 3 + axis] < mid) { uint32_t tmp = idx[left]; idx[left++] = idx[i]; idx[i] = tmp; }
    }
    if (left == 0 || left == n) {
        for (uint32_t i = 0; i < n; ++i) b->s->zone_of[idx[i]] = *zone_count;
        (*zone_count)++;
        return PRT_OK;
    }
    prt_status st = split_zones(b, idx, left, zone_count);
    return st ? st : split_zones(b, idx + left, n - left, zone_count);
}

/* One solve: the spectral run time under one unit point light (pos) or the scene's emitters
 * (pos NULL). direct and indirect get the exit radiance per vertex (3 each; direct may be NULL),
 * glossy the glossy vertices' SH exit radiance (48 each). */
static prt_status solve(lcbake *b, prt_context *ctx, const float *pos, int lobe, float *direct, float *indirect, float *glossy)
{
    prt__lightcloud_set *s = b->s;
    const size_t nv = b->t->mesh.vertex_count;
    prt_lighting *l = NULL;
    prt_status st = prt_lighting_create(&l);
    if (st) return prt__fail(ctx, st, "out of memory");
    if (pos) {   /* lobe 0: the unit point light; the others its emission lobes (lobes.c) */
        prt_light pl;
        st = prt__lightcloud_lobe_light(lobe, pos, &pl);
        if (!st) st = prt_lighting_add(l, &pl, NULL);
        prt_light_clear(&pl);
        prt_lighting_set_emission(l, 0.0f);
    }
    const int controls[2] = {s->bounces, 1};   /* and the spectral tail: the rest of the series */
    prt_relight_desc d = {.variant = 0, .per_vertex = 1, .with_indirect = 1, .controls = controls};
    prt_relit r = {0};
    if (!st) st = prt__method_spectral.relight(ctx, b->inner, l, &d, &r);
    if (!st) {
        const float *le = b->t->mesh.emission;
        for (size_t i = 0; i < nv * 3; ++i) {
            /* The emitters' own radiance is the run time's to add: keep what they light. */
            const float own = !pos && le ? le[i] : 0.0f;
            indirect[i] = r.indirect[i];
            if (direct) direct[i] = r.radiance[i] - own - r.indirect[i];
        }
        if (s->glossy_count && r.exit_sh)
            for (size_t v = 0; v < nv; ++v)
                if (s->glossy_of[v] != UINT32_MAX)
                    memcpy(glossy + (size_t)s->glossy_of[v] * 48, r.exit_sh + v * 48, 48 * sizeof(float));
    }
    prt_relit_free(&r);
    prt_lighting_release(l);
    return st;
}

static prt_status cloud_step(prt__bake_job *job, prt_context *ctx, prt__progress *p)
{
    (void)p;
    lcbake *b = (lcbake *)job;
    prt__lightcloud_set *s = b->s;
    const prt__mesh *m = &b->t->mesh;
    const size_t nv = m->vertex_count;
    prt__raycaster rc = {0};
    prt_status st = prt__raycaster_create(ctx, m, &rc);
    if (!st) st = place_cloud(b, &rc);
    const uint32_t n = s->cloud_count;
    b->merge_distance = b->d.merge_distance >= 0 ? b->d.merge_distance : 3.0f * s->spacing;
    b->merge_error = b->d.merge_error >= 0 ? b->d.merge_error : 0.1f;
    b->merge_response = b->d.merge_response ? b->d.merge_response : PRT__LIGHTCLOUD_MERGE_MEAN;
    s->merge_response = (uint32_t)b->merge_response;
    s->merge_distance = b->merge_distance;
    s->merge_error = b->merge_error;
    /* The pairs that could merge and their mutual visibility (V_jk of eq. 9): lights farther
     * apart than the merge distance never merge, so no table holds every pair. */
    if (!st) st = prt__lightcloud_pairs_find(ctx, s->cloud, n, b->merge_distance, job->threads, &b->pairs);
    if (!st && b->pairs.count > PAIRS_MAX)
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%llu pairs of cloud lights lie within the merge distance %g (%.1f per light): at most %llu; lower "
                       "--merge-distance", (unsigned long long)b->pairs.count, b->merge_distance, (double)b->pairs.count / n, (unsigned long long)PAIRS_MAX);
    if (!st && (!(b->pairs.visible = prt__calloc(b->pairs.count + 1, 1)) || !(b->dark = prt__calloc(n, 1))))
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) {
        /* A pair is one ray, a microsecond: below 256 lights the loop takes less than waking a
         * team costs on a loaded machine (a scheduler's time slice). */
        const prt__lightcloud_pairs *pp = &b->pairs;
#pragma omp parallel for schedule(dynamic, 16) num_threads(job->threads) if (n >= 256)
        for (uint32_t j = 0; j < n; ++j)
            for (uint64_t q = pp->start[j]; q < pp->start[j + 1]; ++q)
                pp->visible[q] = prt__raycaster_segment_clear(&rc, s->cloud + (size_t)j * 3, s->cloud + (size_t)pp->other[q] * 3);
    }
    prt__raycaster_release(&rc);
    /* Zones. */
    uint32_t *idx = st ? NULL : malloc(nv * sizeof(uint32_t));
    if (!st && (!idx || !(s->zone_of = malloc(nv * sizeof(uint32_t))))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) {
        for (size_t v = 0; v < nv; ++v) idx[v] = (uint32_t)v;
        s->zone_count = 0;
        st = split_zones(b, idx, (uint32_t)nv, &s->zone_count);
    }
    free(idx);
    /* One chunk per zone, and a file holds at most 4096 chunks. */
    if (!st && s->zone_count > 4000)
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%u zones of at most %d vertices: at most 4000 fit a file (raise --zone-vertices)", s->zone_count,
                       b->d.zone_vertices);
    if (!st && !prt__lightcloud_index(b->t, s)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st && !(s->zones = prt__calloc(s->zone_count, sizeof *s->zones))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st && !(b->pos_of = malloc(nv * sizeof(uint32_t)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st)
        for (size_t i = 0; i < nv; ++i) b->pos_of[s->members[i]] = (uint32_t)i;
    /* The scratch file of responses. */
    b->one = nv * 3 + (size_t)s->glossy_count * 48;
    b->stride = b->one * (size_t)s->lobes;
    if (!st && !(b->spill = tmpfile())) st = prt__fail(ctx, PRT_ERR_IO, "cannot create a scratch file for the light responses (TMPDIR)");
    if (!st && b->d.responses_path)
        st = prt__lightcloud_responses_open(ctx, b->d.responses_path, &b->kept_fp, nv, s->glossy_count, s->lobes, s->cloud, n, &b->kept);
    /* What the scene's emitters light, baked whole (direct and indirect): the renderer cannot
     * draw emitters' direct light. */
    if (!st && m->emission) {
        s->emit = prt__calloc(nv * 6, sizeof(float));
        s->emit_sh = prt__calloc((size_t)s->glossy_count * 48 + 1, sizeof(float));
        if (!s->emit || !s->emit_sh) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else st = solve(b, ctx, NULL, 0, s->emit, s->emit + nv * 3, s->emit_sh);
    }
    if (!st) {
        /* What the cloud will take, said before the lights are solved: each zone's thread holds
         * every light's response at the zone's vertices, and as much again merged. */
        uint64_t zone_floats = 0;
        for (uint32_t z = 0; z < s->zone_count; ++z) {
            const uint64_t f = (uint64_t)(s->member_start[z + 1] - s->member_start[z]) * 3 + (uint64_t)(s->glossy_start[z + 1] - s->glossy_start[z]) * 48;
            if (f > zone_floats) zone_floats = f;
        }
        const double mib = 1048576.0, zone = 2.0 * (double)zone_floats * s->lobes * n * 4 / mib;
        const double pairs = ((double)b->pairs.count * (4 + 1 + 2 * 8 + 20) + (double)n * 40) / mib;
        prt__log(ctx, PRT_LOG_INFO, "light cloud: %u light%s (spacing %.3g), %llu pairs within the merge distance (%.1f MiB with the clustering's), "
                 "%u zones (up to %.1f MiB per thread while one clusters and compresses), responses %.1f MiB on disk", n, n == 1 ? "" : "s", s->spacing,
                 (unsigned long long)b->pairs.count, pairs, s->zone_count, zone, (double)b->stride * n * 4 / mib);
        /* Over the limit: as many lights and zones in flight as fit beside the rest, sized as the
         * estimate sized them (at least one: the estimate's least, checked before the bake). The
         * zones are the cloud's now, no longer the options' guess: the larger of the two counts. */
        const uint64_t actual = (uint64_t)nv * 3 * sizeof(float) * 8 + 3 * zone_floats * (uint64_t)s->lobes * n * sizeof(float);
        const uint64_t per = actual > b->d.memory_per_flight ? actual : b->d.memory_per_flight;
        if (job->memory_over && per && job->threads > 1) {
            const uint64_t room = job->memory_limit > b->d.memory_fixed ? (job->memory_limit - b->d.memory_fixed) / per : 0;
            b->flights = room < 1 ? 1 : room < (uint64_t)job->threads ? (int)room : 0;
            if (b->flights)
                prt__log(ctx, PRT_LOG_INFO, "memory: %d cloud light%s or zone%s in flight at a time of %d threads (%.1f MiB each), to stay within the limit",
                         b->flights, b->flights == 1 ? "" : "s", b->flights == 1 ? "" : "s", job->threads, (double)per / mib);
        }
    }
    return st;
}

/* ---- one cloud light ---- */
static prt_status write_response(lcbake *b, uint64_t unit, const float *resp)
{
    const size_t bytes = b->stride * sizeof(float);
    const off_t at = (off_t)(unit * bytes);
    if (pwrite(fileno(b->spill), resp, bytes, at) != (ssize_t)bytes) return prt__fail(b->base.ctx, PRT_ERR_IO, "cannot write the light responses' scratch file (disk full?)");
    return PRT_OK;
}

/* One cloud light's response to one emission lobe as stored: exit radiance per vertex (indirect,
 * or all of it with store_direct) into diffuse (3 per vertex, vertex order), the glossy vertices'
 * SH into glossy (48 each), whether it reaches any vertex into *lit. */
static prt_status light_response(lcbake *b, prt_context *ctx, const float *pos, int lobe, float *diffuse, float *glossy, bool *lit)
{
    const size_t nv = b->t->mesh.vertex_count;
    float *direct = malloc(nv * 3 * sizeof(float));
    prt_status st = direct ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = solve(b, ctx, pos, lobe, direct, diffuse, glossy);
    if (!st) {
        *lit = false;
        for (size_t i = 0; i < nv * 3 && !*lit; ++i) *lit = direct[i] != 0 || diffuse[i] != 0;
    }
    if (!st && b->s->store_direct)
        for (size_t i = 0; i < nv * 3; ++i) diffuse[i] += direct[i];
    free(direct);
    return st;
}

static prt_status light_solve_unit(lcbake *b, uint64_t unit);
static prt_status light_run(prt__bake_job *job, uint64_t unit, int thread)
{
    (void)thread;
    lcbake *b = (lcbake *)job;
    flight_enter(b);
    const prt_status st = light_solve_unit(b, unit);
    flight_leave(b);
    return st;
}

static prt_status light_solve_unit(lcbake *b, uint64_t unit)
{
    prt__bake_job *job = &b->base;
    prt__lightcloud_set *s = b->s;
    const size_t nv = b->t->mesh.vertex_count;
    float *diffuse = malloc(nv * 3 * sizeof(float));
    float *glossy = malloc(((size_t)s->glossy_count * 48 + 1) * sizeof(float)), *resp = malloc(b->stride * sizeof(float) + 4);
    prt_status st = diffuse && glossy && resp ? PRT_OK : prt__fail(job->ctx, PRT_ERR_NO_MEMORY, "out of memory");
    /* Each lobe solved, or taken from the kept solutions (which hold every lobe); lobe 0, the
     * isotropic light, says whether the light reaches anything. */
    const bool kept = prt__lightcloud_responses_has(b->kept, (uint32_t)unit);
    for (int k = 0; k < s->lobes && !st; ++k) {
        float *out = resp + b->one * (size_t)k;
        bool lit = false;
        if (kept) st = prt__lightcloud_responses_read(job->ctx, b->kept, (uint32_t)unit, k, diffuse, glossy, &lit);
        else st = light_response(b, job->ctx, s->cloud + unit * 3, k, diffuse, glossy, &lit);
        if (!st && k == 0) b->dark[unit] = !lit;
        if (!st) {
            for (size_t v = 0; v < nv; ++v) memcpy(out + (size_t)b->pos_of[v] * 3, diffuse + v * 3, 3 * sizeof(float));
            /* Glossy vertices in member order too. */
            for (size_t i = 0, g = 0; i < nv; ++i) {
                const uint32_t gv = s->glossy_of[s->members[i]];
                if (gv != UINT32_MAX) memcpy(out + nv * 3 + 48 * g++, glossy + (size_t)gv * 48, 48 * sizeof(float));
            }
        }
    }
    if (!st) st = write_response(b, unit, resp);
    free(diffuse);
    free(glossy);
    free(resp);
    return st;
}

/* A unit's record: its response, then whether it reaches no vertex (1.0f) or does (0.0f). */
static void light_save(prt__bake_job *job, uint64_t unit, prt__bytes *out)
{
    lcbake *b = (lcbake *)job;
    const size_t bytes = b->stride * sizeof(float);
    float *resp = malloc(bytes + sizeof(float));
    if (!resp || pread(fileno(b->spill), resp, bytes, (off_t)(unit * bytes)) != (ssize_t)bytes) out->failed = true;
    else {
        resp[b->stride] = b->dark[unit] ? 1.0f : 0.0f;
        prt__bytes_put(out, resp, bytes + sizeof(float));
    }
    free(resp);
}

static bool light_load(prt__bake_job *job, uint64_t unit, const unsigned char *data, size_t size)
{
    lcbake *b = (lcbake *)job;
    if (size != (b->stride + 1) * sizeof(float)) return false;
    float *resp = malloc(size);
    if (!resp) return false;
    memcpy(resp, data, size);
    const float dark = resp[b->stride];
    const bool ok = prt__all_finite(resp, b->stride) && (dark == 0.0f || dark == 1.0f) && !write_response(b, unit, resp);
    b->dark[unit] = dark == 1.0f;
    free(resp);
    return ok;
}

/* ---- one zone: clustering and compression ---- */
typedef struct zone_data {
    const lcbake *b;
    uint32_t n, nz, gz;
    const float *R;          /* [light][nz * 3] */
    const float *G;          /* [light][gz * 48] */
    float w2;
} zone_data;

/* Eq. 9: w1 |p_j - p_k| + w2 max over vertices of the response difference + V_jk, with w1 = 1 /
 * merge distance and w2 = 1 / (merge error x the zone's largest response). Returns early once
 * it reaches 1: only whether it stays below 1 and its order below 1 matter. Only pairs within the
 * merge distance come here (pair: their index in b->pairs). */
static float metric(void *user, uint32_t j, uint32_t k, uint64_t pair)
{
    const zone_data *z = user;
    const lcbake *b = z->b;
    if (b->merge_distance <= 0) return INFINITY;
    float d[3];
    prt__v3_sub(b->s->cloud + (size_t)j * 3, b->s->cloud + (size_t)k * 3, d);
    float m = prt__v3_len(d) / b->merge_distance;
    if (m >= 1.0f) return m;
    if (!b->pairs.visible[pair]) return m + 1.0f;
    if (z->w2 <= 0) return m;
    const float *rj = z->R + (size_t)j * z->nz * 3, *rk = z->R + (size_t)k * z->nz * 3;
    float worst = 0;
    for (size_t i = 0; i < (size_t)z->nz * 3; ++i) {
        const float e = fabsf(rj[i] - rk[i]);
        if (e > worst) { worst = e; if (m + z->w2 * worst >= 1.0f) return m + z->w2 * worst; }
    }
    const float *gj = z->G + (size_t)j * z->gz * 48, *gk = z->G + (size_t)k * z->gz * 48;
    for (size_t i = 0; i < (size_t)z->gz * 3; ++i) {
        float s = 0;
        for (int c = 0; c < 16; ++c) { const float e = gj[i * 16 + c] - gk[i * 16 + c]; s += e * e; }
        if (sqrtf(s) > worst) { worst = sqrtf(s); if (m + z->w2 * worst >= 1.0f) return m + z->w2 * worst; }
    }
    return m + z->w2 * worst;
}

static prt_status compress_block(prt_context *ctx, const lcbake *b, uint32_t zone, float *X, uint32_t rows, uint32_t dim, prt__lightcloud_block *out)
{
    out->vertices = rows;
    out->dim = dim;
    if (b->d.raw || !rows) { out->raw = X; return PRT_OK; }
    prt_compress_desc cd = {.method = PRT_COMPRESS_CPCA, .clusters = b->d.clusters, .vectors = b->d.vectors, .iterations = 20, .seed = zone};
    if (cd.vectors > (int)dim) cd.vectors = (int)dim;
    prt__progress quiet = {0};
    quiet.ctx = ctx;
    prt_status st = prt__cpca_build_ex(ctx, X, rows, (int)dim, &cd, 64, &quiet, &out->cpca);
    free(X);
    return st;
}

/* The paper's alternative: each merged light of several members solved at its mean position (every
 * emission lobe), its response in zone z written over the mean in X and Y ([row][merged light l's
 * lobe k at l * lobes + k]). A mean position inside geometry or on a surface (the members surround
 * an obstacle) keeps the mean. */
static prt_status solve_merged(lcbake *b, prt_context *ctx, uint32_t z, const uint32_t *members, float *X, float *Y)
{
    prt__lightcloud_set *s = b->s;
    const prt__lightcloud_zone *zone = &s->zones[z];
    const size_t nv = b->t->mesh.vertex_count;
    const int K = s->lobes;
    const uint32_t L = zone->lights * (uint32_t)K, first = s->member_start[z], nz = s->member_start[z + 1] - first;
    float *diffuse = malloc(nv * 3 * sizeof(float)), *glossy = malloc(((size_t)s->glossy_count * 48 + 1) * sizeof(float));
    prt_status st = diffuse && glossy ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (uint32_t l = 0; l < zone->lights && !st; ++l) {
        if (members[l] < 2 || inside(&b->rc, zone->positions + (size_t)l * 3, b->near)) continue;
        for (int k = 0; k < K && !st; ++k) {
            const size_t col = (size_t)l * K + k;
            bool lit = false;
            st = light_response(b, ctx, zone->positions + (size_t)l * 3, k, diffuse, glossy, &lit);
            /* The zone's rows: its vertices in member order, its glossy ones counted in the same order. */
            for (uint32_t i = 0, g = 0; i < nz && !st; ++i) {
                const uint32_t v = s->members[first + i], gv = s->glossy_of[v];
                for (int c = 0; c < 3; ++c) X[((size_t)i * 3 + c) * L + col] = diffuse[(size_t)v * 3 + c];
                if (gv != UINT32_MAX) {
                    for (int c = 0; c < 48; ++c) Y[((size_t)g * 48 + c) * L + col] = glossy[(size_t)gv * 48 + c];
                    g++;
                }
            }
        }
        if (!st && prt__cancelled(ctx)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    }
    free(diffuse);
    free(glossy);
    return st;
}

/* prt__lightcloud_merge lobe by lobe: src holds every cloud light's responses lobe after lobe
 * ([lobe][cloud light][width]), dst takes merged light l's lobe k in column l * lobes + k of its
 * rows; each lobe merged as a single response would be. */
static prt_status merge_lobes(prt_context *ctx, int how, uint32_t n, const uint32_t *light_of, uint32_t lights, int lobes, const float *src,
                              size_t width, int group, float *dst)
{
    if (lobes == 1) return prt__lightcloud_merge(ctx, how, n, light_of, lights, src, width, group, dst);
    const size_t L = (size_t)lights * lobes;
    float *one = malloc((width * lights + 1) * sizeof(float));
    prt_status st = one ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int k = 0; k < lobes && !st; ++k) {
        st = prt__lightcloud_merge(ctx, how, n, light_of, lights, src + (size_t)k * n * width, width, group, one);
        for (size_t i = 0; i < width && !st; ++i)
            for (uint32_t l = 0; l < lights; ++l) dst[i * L + (size_t)l * lobes + k] = one[i * lights + l];
    }
    free(one);
    return st;
}

static prt_status zone_run(lcbake *b, prt_context *ctx, uint32_t z)
{
    prt__lightcloud_set *s = b->s;
    prt__lightcloud_zone *zone = &s->zones[z];
    const size_t nv = b->t->mesh.vertex_count;
    const uint32_t n = s->cloud_count, first = s->member_start[z], nz = s->member_start[z + 1] - first;
    const uint32_t gfirst = s->glossy_start[z], gz = s->glossy_start[z + 1] - gfirst;
    /* R and G: every light's responses, lobe by lobe ([lobe][light][...]); clustering looks at
     * lobe 0, the isotropic light's. */
    const int K = s->lobes;
    float *R = malloc((size_t)K * n * nz * 3 * sizeof(float) + 4), *G = malloc(((size_t)K * n * gz * 48 + 1) * sizeof(float));
    zone->light_of = malloc((size_t)n * sizeof(uint32_t));
    prt_status st = R && G && zone->light_of ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const int fd = b->spill ? fileno(b->spill) : -1;
    float largest = 0;
    for (uint32_t j = 0; j < n && !st; ++j)
        for (int k = 0; k < K && !st; ++k) {
            const off_t base = (off_t)(((uint64_t)j * b->stride + (uint64_t)k * b->one) * sizeof(float));
            const size_t rb = (size_t)nz * 3 * sizeof(float), gb = (size_t)gz * 48 * sizeof(float);
            if (pread(fd, R + ((size_t)k * n + j) * nz * 3, rb, base + (off_t)((size_t)first * 3 * sizeof(float))) != (ssize_t)rb ||
                (gb && pread(fd, G + ((size_t)k * n + j) * gz * 48, gb, base + (off_t)((nv * 3 + (size_t)gfirst * 48) * sizeof(float))) != (ssize_t)gb))
                st = prt__fail(ctx, PRT_ERR_IO, "cannot read the light responses' scratch file");
        }
    for (size_t i = 0; !st && i < (size_t)n * nz * 3; ++i) largest = fabsf(R[i]) > largest ? fabsf(R[i]) : largest;
    for (size_t i = 0; !st && i < (size_t)n * gz * 48; ++i) largest = fabsf(G[i]) > largest ? fabsf(G[i]) : largest;
    zone_data zd = {b, n, nz, gz, R, G, b->merge_error > 0 && largest > 0 ? 1.0f / (b->merge_error * largest) : 0.0f};
    if (!st) st = prt__lightcloud_cluster(ctx, &b->pairs, metric, &zd, zone->light_of, &zone->lights);
    /* Columns: merged light l's lobe k at l * K + k. */
    const uint32_t L = zone->lights * (uint32_t)K;
    float *X = NULL, *Y = NULL;
    uint32_t *members = NULL;
    if (!st) {
        X = prt__calloc((size_t)nz * 3 * L + 1, sizeof(float));
        Y = prt__calloc((size_t)gz * 48 * L + 1, sizeof(float));
        zone->positions = prt__calloc((size_t)zone->lights * 3, sizeof(float));
        members = prt__calloc(zone->lights, sizeof(uint32_t));
        if (!X || !Y || !zone->positions || !members) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    if (!st) {
        /* Merged lights: mean position; responses as the bake asks (the solution at the mean
         * position starts from the mean, for lights where it cannot solve). */
        for (uint32_t j = 0; j < n; ++j) {
            const uint32_t l = zone->light_of[j];
            members[l]++;
            for (int k = 0; k < 3; ++k) zone->positions[l * 3 + k] += s->cloud[(size_t)j * 3 + k];
        }
        for (uint32_t l = 0; l < zone->lights; ++l)
            for (int k = 0; k < 3; ++k) zone->positions[l * 3 + k] /= (float)members[l];
        const int how = b->merge_response == PRT__LIGHTCLOUD_MERGE_HARMONIC ? PRT__LIGHTCLOUD_MERGE_HARMONIC : PRT__LIGHTCLOUD_MERGE_MEAN;
        st = merge_lobes(ctx, how, n, zone->light_of, zone->lights, K, R, (size_t)nz * 3, 1, X);
        if (!st) st = merge_lobes(ctx, how, n, zone->light_of, zone->lights, K, G, (size_t)gz * 48, 16, Y);
        if (!st && b->merge_response == PRT__LIGHTCLOUD_MERGE_SOLVE) st = solve_merged(b, ctx, z, members, X, Y);
    }
    free(R);
    free(G);
    free(members);
    if (!st) { st = compress_block(ctx, b, z, X, nz, 3 * L, &zone->diffuse); X = NULL; }
    if (!st) { st = compress_block(ctx, b, z, Y, gz, 48 * L, &zone->glossy); Y = NULL; }
    free(X);
    free(Y);
    return st;
}

/* A cloud light's response to one lobe from the scratch file, back in vertex order (to keep it). */
static prt_status kept_response(void *user, uint32_t light, int lobe, float *diffuse, float *glossy, bool *lit)
{
    lcbake *b = user;
    const prt__lightcloud_set *s = b->s;
    const size_t nv = b->t->mesh.vertex_count, bytes = b->one * sizeof(float);
    float *resp = malloc(bytes + 4);
    if (!resp) return prt__fail(b->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const off_t at = (off_t)(((uint64_t)light * b->stride + (uint64_t)lobe * b->one) * sizeof(float));
    const bool ok = pread(fileno(b->spill), resp, bytes, at) == (ssize_t)bytes;
    if (ok) {
        for (size_t v = 0; v < nv; ++v) memcpy(diffuse + v * 3, resp + (size_t)b->pos_of[v] * 3, 3 * sizeof(float));
        for (size_t i = 0, g = 0; i < nv; ++i) {
            const uint32_t gv = s->glossy_of[s->members[i]];
            if (gv != UINT32_MAX) memcpy(glossy + (size_t)gv * 48, resp + nv * 3 + 48 * g++, 48 * sizeof(float));
        }
        *lit = !b->dark[light];
    }
    free(resp);
    return ok ? PRT_OK : prt__fail(b->base.ctx, PRT_ERR_IO, "cannot read the light responses' scratch file");
}

/* What the zones need before any of them runs, once the cloud lights are solved: the kept
 * solutions written (--responses), every light dark refused, the ray caster for solved merges. */
static prt_status zones_begin(lcbake *b, prt_context *ctx)
{
    if (b->kept) {
        const uint32_t reused = prt__lightcloud_responses_reused(b->kept);
        prt__log(ctx, PRT_LOG_INFO, "light cloud: %u of %u cloud lights' solutions taken from %s, %u solved", reused, b->s->cloud_count,
                 b->d.responses_path, b->s->cloud_count - reused);
        const prt_status st = prt__lightcloud_responses_write(ctx, b->kept, b->d.responses_path, &b->kept_fp, b->s->cloud, b->s->cloud_count,
                                                               kept_response, b);
        if (st) return st;
    }
    uint32_t dark = 0;
    for (uint32_t j = 0; j < b->s->cloud_count; ++j) dark += b->dark[j];
    if (dark == b->s->cloud_count)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "none of the %u cloud lights reaches a surface (is the cloud outside a closed scene?): give a "
                         "--cloud-box or --cloud list where the lights will be", dark);
    if (dark)
        prt__log(ctx, PRT_LOG_WARN, "%u of %u cloud lights reach no surface (outside a closed scene, or shut in): they add nothing", dark,
                 b->s->cloud_count);
    /* Zones compress side by side, each entering LAPACK: OpenBLAS's pool would only fight prt's
     * threads, so it is single-threaded until the stage ends (as the spectral basis does it). */
    b->blas_threads = openblas_get_num_threads();
    openblas_set_num_threads(1);
    return b->merge_response == PRT__LIGHTCLOUD_MERGE_SOLVE ? prt__raycaster_create(ctx, &b->t->mesh, &b->rc) : PRT_OK;
}

static void zones_end(lcbake *b)
{
    if (b->blas_threads > 0) openblas_set_num_threads(b->blas_threads);
    b->blas_threads = 0;
}

/* One zone per unit, its clustered PCA on the thread that runs it (nested regions get one thread):
 * the stage is one parallel region. Parallel passes inside each zone's compression ended in a
 * barrier each, hundreds per zone, and where cores are shared every barrier waited for a thread
 * the scheduler had set aside (2.2 times as long on 2 threads as on 1 beside two busy loops). */
static prt_status zone_unit(prt__bake_job *job, uint64_t unit, int thread)
{
    (void)thread;
    lcbake *b = (lcbake *)job;
    flight_enter(b);
    const prt_status st = zone_run(b, job->ctx, (uint32_t)unit);
    flight_leave(b);
    return st;
}

static prt_status lc_stage(prt__bake_job *job, int index, prt__stage *out)
{
    lcbake *b = (lcbake *)job;
    if (b->first_own < 0) {
        b->inner_job->threads = job->threads;
        /* Over the memory limit the spectral stages stream their rows (methods/spectral/spill.c). */
        b->inner_job->memory_limit = job->memory_limit;
        b->inner_job->memory_over = job->memory_over;
        memset(&b->inner_stage, 0, sizeof b->inner_stage);
        prt_status st = b->inner_job->stage(b->inner_job, index, &b->inner_stage);
        if (st) return st;
        if (b->inner_stage.units || b->inner_stage.whole) {
            *out = b->inner_stage;
            out->run = b->inner_stage.run ? inner_run : NULL;
            out->whole = b->inner_stage.whole ? inner_whole : NULL;
            out->save_unit = b->inner_stage.save_unit ? inner_save : NULL;
            out->load_unit = b->inner_stage.load_unit ? inner_load : NULL;
            return PRT_OK;
        }
        /* The spectral transfer is complete: finish it and free its bake. */
        st = b->inner_job->finish(b->inner_job, b->inner);
        b->inner_job->release(b->inner_job);
        b->inner_job = NULL;
        if (st) return st;
        b->first_own = index;
    }
    const int own = index - b->first_own;
    if (own == 3) zones_end(b);   /* asked for the stage after the zones: they have all run */
    if (own == 0) {
        snprintf(out->name, sizeof out->name, "light cloud");
        out->whole = cloud_step;
    } else if (own == 1) {
        snprintf(out->name, sizeof out->name, "cloud lights");
        out->units = b->s->cloud_count;
        out->run = light_run;
        out->save_unit = light_save;
        out->load_unit = light_load;
    } else if (own == 2) {
        const prt_status st = zones_begin(b, job->ctx);
        if (st) return st;
        snprintf(out->name, sizeof out->name, "zones");
        out->units = b->s->zone_count;
        out->run = zone_unit;
    }
    return PRT_OK;
}

static prt_status lc_finish(prt__bake_job *job, prt_transfer *t)
{
    (void)job;
    (void)t;   /* the state has been t's since the bake began */
    return PRT_OK;
}

static void lc_release(prt__bake_job *job)
{
    lcbake *b = (lcbake *)job;
    if (b->inner_job) b->inner_job->release(b->inner_job);
    prt_transfer_release(b->inner);
    if (b->spill) fclose(b->spill);
    zones_end(b);   /* a bake that failed or was cancelled in the zones */
    prt__raycaster_release(&b->rc);
    prt__lightcloud_responses_close(b->kept);
    free(b->responses_path);
    free(b->pos_of);
    prt__lightcloud_pairs_free(&b->pairs);
    free(b->dark);
    free(b->list);
    if (b->gate_ready) { pthread_mutex_destroy(&b->gate); pthread_cond_destroy(&b->gate_freed); }
    free(b);
}

prt_status prt__lightcloud_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, const prt__lightcloud_bake_desc *desc,
                                      prt_transfer *t, prt__bake_job **job)
{
    prt__lightcloud_bake_desc d = *desc;
    if (!d.zone_vertices) d.zone_vertices = 2000;
    if (!d.bounces) d.bounces = 16;
    if (!d.clusters) d.clusters = 8;
    if (!d.vectors) d.vectors = 8;
    if (!d.emission_order) d.emission_order = PRT__LIGHTCLOUD_EMISSION_ORDER;
    if (d.emission_order < 1 || d.emission_order > 3) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--emission-order must be 1, 2 or 3");
    if (d.has_box) {
        for (int k = 0; k < 3; ++k)
            if (!(d.box[k] < d.box[3 + k])) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--cloud-box: each minimum must be below its maximum");
    }
    /* The cloud's size and list are checked before any work: a bad --cloud file or an absurd
     * grid must not wait for the spectral stages. */
    float *list = NULL;
    uint32_t nlist = 0;
    if (d.list_path) {
        const prt_status st = read_list(ctx, d.list_path, &list, &nlist);
        if (st) return st;
    }
    int g[3];
    const uint64_t total = grid_size(&d, g) + nlist + (uint64_t)d.surface_lights;
    if (total > PRT__LIGHTCLOUD_MAX_LIGHTS) {
        free(list);
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%llu cloud lights asked for, at most %u", (unsigned long long)total, PRT__LIGHTCLOUD_MAX_LIGHTS);
    }
    {   /* What it will take, before any work (cloud_step says it again exactly, before the lights are solved). */
        const uint64_t nv = t->mesh.vertex_count, zv = nv < (uint64_t)d.zone_vertices ? nv : (uint64_t)d.zone_vertices;
        const double mib = 1048576.0, K = (double)d.emission_order * d.emission_order;
        prt__log(ctx, PRT_LOG_INFO, "light cloud: up to %llu lights: about %.1f MiB per thread while a zone clusters and compresses (more with glossy "
                 "surfaces), %.1f MiB of responses on disk", (unsigned long long)total, 2.0 * K * (double)total * (double)zv * 12 / mib,
                 K * (double)total * (double)nv * 12 / mib);
    }
    lcbake *b = prt__calloc(1, sizeof *b);
    prt__lightcloud_set *s = prt__calloc(1, sizeof *s);
    if (!b || !s) { free(b); free(s); free(list); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    b->list = list;
    b->list_count = nlist;
    b->base.stage = lc_stage;
    b->base.finish = lc_finish;
    b->base.release = lc_release;
    b->base.ctx = ctx;
    b->t = t;
    b->s = s;
    b->d = d;
    if (d.responses_path && !(b->d.responses_path = b->responses_path = strdup(d.responses_path))) {
        free(b); free(s); free(list);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    b->first_own = -1;
    b->gate_ready = !pthread_mutex_init(&b->gate, NULL);
    if (b->gate_ready && pthread_cond_init(&b->gate_freed, NULL)) { pthread_mutex_destroy(&b->gate); b->gate_ready = false; }
    t->state = s;
    s->store_direct = d.store_direct;
    s->lobes = d.emission_order * d.emission_order;
    s->bounces = d.bounces;
    s->samples = prt__opt_int(o, "samples", 4096);
    prt_status st = b->gate_ready && (s->cache = prt__lightcloud_cache_new()) ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__transfer_copy_frame(ctx, t, &b->inner);
    if (!st) {
        b->inner->method = &prt__method_spectral;
        st = prt__method_spectral.bake_begin(ctx, scene, o, b->inner, &b->inner_job);
    }
    if (!st) s->ray_offset = prt__spectral(b->inner)->ray_offset;
    if (!st && d.responses_path) prt__lightcloud_responses_fingerprint(t, o, s, &b->kept_fp);
    if (st) { lc_release(&b->base); return st; }
    *job = &b->base;
    return PRT_OK;
}
