/* Baking offset transfer maps: a light map over the mesh's UVs (or a generated atlas), offsets
 * chosen by the largest (or mean) transfer they carry, the maps (the transfer from each offset's
 * cell, eq. 8) for radiosity and/or subsurface scattering, and each texel's shadowed SH transfer for first-order light from the
 * environment. Stages: offsets, transfer maps, environment. */
#include "methods/offset/importance.h"
#include "geom/texel_raster.h"
#include "geom/uv_atlas.h"
#include "geom/uv_islands.h"
#include "light/light_sample.h"
#include "methods/offset/offset.h"

#define IMPORTANCE_TEXELS 4096   /* texels an offset's importance looks at (evenly spread) */
#define ENV_DIRECTIONS 256       /* rays per texel for its environment visibility */
#define EMITTER_SAMPLES 256      /* light samples per texel on the emissive surfaces */
#define NEAR_FIELD 8             /* radiosity: texels of a receiver's own chart this far summed exactly */
#define FAR_FIELD_RAYS 1024      /* radiosity: rays per texel estimating the rest (stratified) */

typedef struct obake {
    prt__bake_job base;
    prt__offset_bake_desc d;
    prt_transfer *t;
    prt__offset_set *s;
    prt__texel_patches patches;
    prt__raycaster rc;
    prt__offset_transfer x[2];   /* radiosity, subsurface */
    uint8_t *texel_medium;       /* [width * height] */
    int32_t *chart;              /* [width * height] each surface texel's UV chart, -1 off the surface */
    double *chart_area;          /* [charts] each chart's world area */
    prt__offset_charts charts;   /* what splits the offsets' cells (with s->source, s->texel) */
    prt__dipole (*dipoles)[3];   /* per medium */
    prt__progress *progress;
    struct bounce_scratch *bounce;   /* [bounce_threads] the bounces' per-thread scratch */
    int bounce_threads;
    /* Over the memory limit (base.memory_over): the maps live in mapped scratch files (maps.c),
     * written block by block, their pages handed back between blocks; block: texels per block. */
    bool streaming;
    size_t block;
    uint64_t units_touched;      /* bounce units since the pages were last handed back */
} obake;

/* Between blocks of a streamed bake: the maps' pages handed back (none otherwise). */
static void maps_block_done(const obake *ob)
{
    if (ob->streaming) prt__offset_maps_drop(ob->s);
}

/* ---- offsets ---- */

static prt_status offsets_step(prt__bake_job *base, prt_context *ctx, prt__progress *p)
{
    obake *ob = (obake *)base;
    prt__offset_set *s = ob->s;
    const size_t n = (size_t)s->width * s->height;
    uint32_t *sample = malloc(((size_t)s->covered + 1) * sizeof *sample);
    if (!sample) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    size_t count = 0;
    const size_t stride = s->covered > IMPORTANCE_TEXELS ? (s->covered + IMPORTANCE_TEXELS - 1) / IMPORTANCE_TEXELS : 1;
    for (size_t i = 0, seen = 0; i < n; ++i)
        if (ob->patches.area[i] > 0 && seen++ % stride == 0) sample[count++] = (uint32_t)i;
    prt__progress_begin(p, p->stage, (uint64_t)(121 + ob->d.iterations));
    const prt__offset_importance_desc id = {&ob->patches, ob->x, ob->d.kinds, ob->d.importance, sample, count};
    const prt__offset_desc od = {s->width, s->height, ob->d.count, ob->d.iterations, (uint64_t)ob->d.seed};
    int got = 0;
    prt_status st = prt__offset_choose(ctx, &id, &od, p, &s->offsets, &got);
    free(sample);
    if (!st && prt__progress_cancelled(p)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    if (!st) s->count = got;
    return st;
}

/* ---- maps ---- */

static uint64_t walk_random(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static double walk_uniform(uint64_t *s) { return (double)(walk_random(s) >> 11) * (1.0 / 9007199254740992.0); }

static void cosine_direction(const float n[3], double u1, double u2, float d[3])
{
    float t1[3], t2[3], h[3] = {0, 0, 0};
    h[fabsf(n[0]) < 0.6f ? 0 : fabsf(n[1]) < 0.6f ? 1 : 2] = 1;
    prt__v3_cross(n, h, t1);
    prt__v3_normalize(t1);
    prt__v3_cross(n, t1, t2);
    prt__cosine_dir(u1, u2, n, t1, t2, d);
}


/* The landing texel of a ray from a texel's surface point: the covered texel whose light stands
 * for the hit (its gutter's source where the hit's texel centre is off the chart), -1 none. */
static int32_t landing(const obake *ob, const float o[3], const float d[3], prt__ray_hit *h)
{
    const prt__mesh *m = &ob->t->mesh;
    const prt__offset_set *s = ob->s;
    if (!prt__raycaster_hit(&ob->rc, o, d, h) || h->prim >= m->triangle_count) return -1;
    if (prt__v3_dot(h->ng, d) > 0) return -1;   /* a back face: surfaces reflect on their front only */
    const uint32_t *ix = m->indices + (size_t)h->prim * 3;
    const float b0 = 1 - h->u - h->v;
    const float hu = b0 * m->uv[ix[0] * 2] + h->u * m->uv[ix[1] * 2] + h->v * m->uv[ix[2] * 2];
    const float hv = b0 * m->uv[ix[0] * 2 + 1] + h->u * m->uv[ix[1] * 2 + 1] + h->v * m->uv[ix[2] * 2 + 1];
    const int hx = (int)fminf(fmaxf(floorf(hu * s->width), 0.0f), (float)(s->width - 1));   /* clamped before the cast: */
    const int hy = (int)fminf(fmaxf(floorf(hv * s->height), 0.0f), (float)(s->height - 1));   /* UVs may lie far out */
    return s->source[(size_t)hy * s->width + hx];
}

/* A receiver's representatives sorted along x, for nearest_rep's pruned search. */
typedef struct rep_point { float p[3]; int o, chart; double area; } rep_point;   /* chart and its area */
typedef struct rep_index { rep_point *pt; int n; } rep_index;

static int rep_point_cmp(const void *a, const void *b)
{
    const rep_point *x = a, *y = b;
    if (x->p[0] != y->p[0]) return x->p[0] < y->p[0] ? -1 : 1;
    return (x->o > y->o) - (x->o < y->o);
}

static void rep_index_build(const obake *ob, const int32_t *rep, int K, rep_index *ix)
{
    ix->n = 0;
    for (int o = 0; o < K; ++o) {
        if (rep[o] < 0) continue;
        rep_point *q = &ix->pt[ix->n++];
        memcpy(q->p, ob->patches.pos + (size_t)rep[o] * 3, sizeof q->p);
        q->o = o;
        q->chart = ob->chart[rep[o]];
        q->area = q->chart >= 0 ? ob->chart_area[q->chart] : 0;
    }
    qsort(ix->pt, (size_t)ix->n, sizeof *ix->pt, rep_point_cmp);
}

/* The representative nearest q among those `fits` takes (chart: the landing's, area: its chart's
 * area): pruned along x; ties to the lower offset, -1 none. */
static int nearest_where(const rep_index *ix, const float *q, int32_t chart, double area, bool (*fits)(const rep_point *, int32_t, double, double))
{
    int lo = 0, hi = ix->n;   /* the first point at or past q's x */
    while (lo < hi) { const int mid = (lo + hi) / 2; if (ix->pt[mid].p[0] < q[0]) lo = mid + 1; else hi = mid; }
    int best = -1;
    double near = INFINITY;
    /* Outwards both ways; once |dx|^2 passes the nearest distance, none further can be nearer. */
    for (int i = lo, j = lo - 1; i < ix->n || j >= 0;) {
        const double di = i < ix->n ? (double)ix->pt[i].p[0] - q[0] : INFINITY, dj = j >= 0 ? (double)q[0] - ix->pt[j].p[0] : INFINITY;
        const rep_point *r = di <= dj ? &ix->pt[i++] : &ix->pt[j--];
        const double dx = r->p[0] - q[0];
        if (dx * dx > near) break;
        const double dy = r->p[1] - q[1], dz = r->p[2] - q[2], d2 = dx * dx + dy * dy + dz * dz;
        if (fits && !fits(r, chart, area, d2)) continue;
        if (d2 < near || (d2 == near && r->o < best)) { near = d2; best = r->o; }
    }
    return best;
}

/* The landing's own chart, one of a quarter its area or more, or a smaller chart's representative
 * within SMALL_REACH of that chart's side (the square root of its area): a small chart's cell
 * takes in only the larger chart's surface close around it. (The Cornell box at 200 offsets:
 * the nearest alone 0.216 relative L2 to the path tracer, worst 16-pixel block 538% off; 0.5 of
 * the side 0.069 and 50%, 0.7 0.074 and 75%, own charts only 0.070 and 44% - but then the receivers
 * without a representative on a small lit chart see none of its light, which a cell reaching
 * around it makes up for on average.) The reach balances two flows, on average only: the small
 * chart's hits that nearer representatives on the larger chart take (its light lost) against the
 * larger chart's surface its own representatives take in (its light counted there too). A painted
 * 0.2 m tile on a floor (test_paint.c) has about five representatives for every wall texel, most
 * through its gutter onto its border texels: at 0.7 of its side its representatives kept 0.55 of
 * its hits and took in floor worth 0.83 of them, a bounce 1.38 times the exact one (0.97 before
 * border texels were sampled); at 0.45 1.05 (0.94 over all bounces). Where fewer receivers have a
 * representative on the small chart less is made up: test_offset.c's lamp panel keeps 0.92 of the
 * exact bounce's energy (0.98 at 0.7), the Cornell box's image 0.94 of the path tracer's mean
 * (0.97), with less error per block. A reach per chart measured to balance the flows (a3be35c,
 * reverted) gave the tile 1.02, the lamp panel 0.92 still, and the demo's worst blocks 4-6 points
 * worse: what the images miss is not made of these flows alone (issue 30). */
#define SMALL_REACH 0.45
static bool near_enough(const rep_point *r, int32_t chart, double area, double d2)
{
    return r->chart == chart || r->area >= area / 4 || d2 <= SMALL_REACH * SMALL_REACH * r->area;
}

/* The offset whose representative stands for surface texel `land` - the cell it counts in: the
 * nearest in space. A cell is the surface around its representative in 3-D, not the texels around
 * it in the map, which far from the receiver span other charts. With `own_chart` (inter-reflection),
 * the nearest that near_enough allows, else any: the run time reads a cell's light at its
 * representative, and across charts light jumps - the Cornell box's
 * ceiling light, a chart of 0.18 m^2 1 cm under the ceiling and lit 10-20 times brighter, took the
 * ceiling around it into its cell, and the boxes' sides gathered 5 times the path tracer's light
 * (issue 30). (Only representatives facing the same way measured worse: the floor in a torus's
 * contact shadow then takes the lit floor's light, 1.18 of the exact bounce's energy against
 * 0.97.) Ties to the lower offset; -1 when the receiver has no representative. */
static int nearest_rep(const obake *ob, const rep_index *ix, uint32_t land, bool own_chart)
{
    const float *q = ob->patches.pos + (size_t)land * 3;
    const int32_t chart = ob->chart[land];
    int best = -1;
    if (own_chart && chart >= 0) best = nearest_where(ix, q, chart, ob->chart_area[chart], near_enough);
    return best >= 0 ? best : nearest_where(ix, q, -1, 0, NULL);
}

/* A receiver's representatives, one set per thread: per offset the texel and chart
 * (prt__offset_reps) and, sorted in space, nearest_rep's index. */
typedef struct receiver { int32_t *rep, *rep_chart; rep_index ix; } receiver;

/* One thread's scratch in the bounces: acc NULL until first used. */
typedef struct bounce_scratch { double *acc; receiver rc; } bounce_scratch;

static bool receiver_init(receiver *r, int K)
{
    r->rep = malloc((size_t)K * 2 * sizeof *r->rep);
    r->rep_chart = r->rep ? r->rep + K : NULL;
    r->ix = (rep_index){malloc((size_t)K * sizeof *r->ix.pt), 0};
    return r->rep && r->ix.pt;
}

static void receiver_free(receiver *r) { free(r->rep); free(r->ix.pt); }

static void receiver_at(const obake *ob, receiver *r, int tx, int ty)
{
    const prt__offset_set *s = ob->s;
    prt__offset_reps(&ob->charts, s->width, s->height, s->offsets, s->count, tx, ty, r->rep, r->rep_chart);
    rep_index_build(ob, r->rep, s->count, &r->ix);
}

/* First-bounce radiosity maps, entry (o, t) the transfer to t from the surface its cell o holds
 * (eq. 8's integral, not one texel's transfer times the cell's area: far from t, a cell spans
 * surfaces whose transfer to t differs wholly - the floor under a torus and the floor beyond).
 * The texels of t's own chart within NEAR_FIELD texels, where transfer changes fastest, are summed
 * exactly (TR times area, visibility by a ray each); the rest of the hemisphere by FAR_FIELD_RAYS
 * cosine-distributed rays, stratified, each hit landing in its (chart-split) cell with the weight
 * albedo / rays: what TR times area integrates to. Seeded per texel: the same for any thread count. */
static bool radiosity_maps(obake *ob, const int32_t *label, float *maps, prt__progress *p)
{
    prt__offset_set *s = ob->s;
    const int W = s->width, H = s->height, K = s->count, gw = 2 * W - 1, strata = (int)sqrt((double)FAR_FIELD_RAYS);
    const size_t nc = s->covered;
    int short_of_memory = 0;
#pragma omp parallel num_threads(prt__threads(ob->base.ctx))
    {
        receiver rc;
        const bool ready = receiver_init(&rc, K);
        if (!ready) __atomic_store_n(&short_of_memory, 1, __ATOMIC_RELAXED);
        for (size_t first = 0; first < nc; first += ob->block) {   /* one block unless streaming */
        const size_t end = first + ob->block < nc ? first + ob->block : nc;
#pragma omp for schedule(dynamic, 16)
        for (size_t i = first; i < end; ++i) {
            for (int o = 0; o < K; ++o) memset(maps + ((size_t)o * nc + i) * 3, 0, 3 * sizeof *maps);   /* also when cancelled: the cap reads them */
            if (!ready || prt__progress_cancelled(p)) continue;
            const size_t t = s->texel[i];
            const int tx = (int)(t % (size_t)W), ty = (int)(t / (size_t)W);
            const int32_t own = ob->chart[t];
            receiver_at(ob, &rc, tx, ty);
            for (int dy = -NEAR_FIELD; dy <= NEAR_FIELD; ++dy)
                for (int dx = -NEAR_FIELD; dx <= NEAR_FIELD; ++dx) {
                    const int sx = tx + dx, sy = ty + dy;
                    if (sx < 0 || sx >= W || sy < 0 || sy >= H) continue;
                    const size_t src = (size_t)sy * W + sx;
                    if (ob->chart[src] != own) continue;
                    float tr[3];
                    prt__offset_tr(&ob->x[0], t, src, tr);
                    if (!(tr[0] > 0 || tr[1] > 0 || tr[2] > 0)) continue;
                    const int o = prt__offset_recell(&ob->charts, W, s->offsets, K, tx, ty, rc.rep, rc.rep_chart,
                                                     label[(size_t)(dy + H - 1) * gw + dx + W - 1], sx, sy, own);
                    for (int c = 0; c < 3; ++c) maps[((size_t)o * nc + i) * 3 + c] += tr[c] * ob->patches.area[src];
                }
            uint64_t rng = ((uint64_t)ob->d.seed << 32) ^ (i * 0x9E6C63D0676A9A99ull) ^ 0x5851F42D4C957F2Dull;
            float org[3];
            for (int c = 0; c < 3; ++c) org[c] = s->pos[i * 3 + c] + s->nrm[i * 3 + c] * s->ray_offset;
            const float w = 1.0f / (strata * strata);
            for (int r = 0; r < strata * strata; ++r) {
                float d[3];
                cosine_direction(s->nrm + i * 3, (r / strata + walk_uniform(&rng)) / strata, (r % strata + walk_uniform(&rng)) / strata, d);
                prt__ray_hit h;
                const int32_t at = landing(ob, org, d, &h);
                if (at < 0) continue;
                const uint32_t land = s->texel[at];
                const int lx = (int)(land % (uint32_t)W), ly = (int)(land / (uint32_t)W);
                if (ob->chart[land] == own && abs(lx - tx) <= NEAR_FIELD && abs(ly - ty) <= NEAR_FIELD) continue;   /* summed exactly */
                const int o = nearest_rep(ob, &rc.ix, land, true);
                if (o < 0) continue;
                for (int c = 0; c < 3; ++c) maps[((size_t)o * nc + i) * 3 + c] += s->albedo[i * 3 + c] * w;
            }
            prt__progress_add(p, 1);
        }
#pragma omp single
        maps_block_done(ob);
        }
        receiver_free(&rc);
    }
    return !short_of_memory;
}

/* Subsurface maps, entry (o, t) the dipole from every texel of t's medium within its reach,
 * summed exactly into the cell that counts it (the label of its offset from t, split by chart as
 * the radiosity maps' near field is): eq. 8's integral over the cell, not the transfer at its
 * representative times its area - near t, where the cells are a texel or two, the dipole changes
 * within a cell by orders of magnitude, and a cell's representative nearer t than most of its
 * texels took the peak for the whole cell (the energy cap then fired on a quarter of the skin
 * demo's texels, scaling some by 90). The texels within reach come from a grid over space, so
 * other charts of the medium nearby count too. Summed in a fixed order: the same for any thread
 * count. */
static bool subsurface_maps(obake *ob, const int32_t *label, float *maps, prt__progress *p)
{
    prt__offset_set *s = ob->s;
    const int W = s->width, H = s->height, K = s->count, gw = 2 * W - 1;
    const size_t nc = s->covered;
    double *reach = malloc(((size_t)s->medium_count + 1) * sizeof *reach), most = 0;
    if (!reach) return false;
    for (int m = 0; m < s->medium_count; ++m) most = fmax(most, reach[m] = prt__dipole_reach(ob->dipoles[m]));
    /* A grid of cells at least `most` wide over the translucent texels (at most 2^21 cells). */
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nc; ++i)
        for (int c = 0; c < 3 && s->medium[i]; ++c) { lo[c] = fminf(lo[c], s->pos[i * 3 + c]); hi[c] = fmaxf(hi[c], s->pos[i * 3 + c]); }
    double h = most > 0 ? most : 1;
    int dim[3] = {1, 1, 1};
    for (;;) {
        for (int c = 0; c < 3; ++c) dim[c] = hi[c] >= lo[c] ? (int)fmin((hi[c] - lo[c]) / h, 1 << 20) + 1 : 1;
        if ((uint64_t)dim[0] * dim[1] * dim[2] <= (1u << 21)) break;
        h *= 2;
    }
    const size_t cells = (size_t)dim[0] * dim[1] * dim[2];
    uint32_t *start = prt__calloc(cells + 1, sizeof *start), *order = malloc(nc * sizeof *order + 1), *at = malloc(nc * sizeof *at + 1);
    if (!start || !order || !at) { free(reach); free(start); free(order); free(at); return false; }
    for (size_t i = 0; i < nc; ++i) {
        if (!s->medium[i]) continue;
        int g[3];
        for (int c = 0; c < 3; ++c) g[c] = (int)fmin((s->pos[i * 3 + c] - lo[c]) / h, dim[c] - 1);
        at[i] = (uint32_t)(((size_t)g[2] * dim[1] + g[1]) * dim[0] + g[0]);
        start[at[i] + 1]++;
    }
    for (size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
    {   /* counting sort: within a cell in covered order */
        uint32_t *fill = malloc(cells * sizeof *fill + 1);
        if (!fill) { free(reach); free(start); free(order); free(at); return false; }
        memcpy(fill, start, cells * sizeof *fill);
        for (size_t i = 0; i < nc; ++i)
            if (s->medium[i]) order[fill[at[i]]++] = (uint32_t)i;
        free(fill);
    }
    int short_of_memory = 0;
#pragma omp parallel num_threads(prt__threads(ob->base.ctx))
    {
        receiver rc;
        const bool ready = receiver_init(&rc, K);
        if (!ready) __atomic_store_n(&short_of_memory, 1, __ATOMIC_RELAXED);
        for (size_t first = 0; first < nc; first += ob->block) {   /* one block unless streaming */
        const size_t end = first + ob->block < nc ? first + ob->block : nc;
#pragma omp for schedule(dynamic, 16)
        for (size_t i = first; i < end; ++i) {
            for (int o = 0; o < K; ++o) memset(maps + ((size_t)o * nc + i) * 3, 0, 3 * sizeof *maps);
            if (!ready || prt__progress_cancelled(p)) continue;
            if (s->medium[i]) {
                const size_t t = s->texel[i];
                const int tx = (int)(t % (size_t)W), ty = (int)(t / (size_t)W);
                const double r2 = reach[s->medium[i] - 1] * reach[s->medium[i] - 1];
                receiver_at(ob, &rc, tx, ty);
                int g[3];
                for (int c = 0; c < 3; ++c) g[c] = (int)fmin((s->pos[i * 3 + c] - lo[c]) / h, dim[c] - 1);
                for (int z = g[2] - 1; z <= g[2] + 1; ++z)
                    for (int y = g[1] - 1; y <= g[1] + 1; ++y)
                        for (int x = g[0] - 1; x <= g[0] + 1; ++x) {
                            if (x < 0 || y < 0 || z < 0 || x >= dim[0] || y >= dim[1] || z >= dim[2]) continue;
                            const size_t cell = ((size_t)z * dim[1] + y) * dim[0] + x;
                            for (uint32_t q = start[cell]; q < start[cell + 1]; ++q) {
                                const uint32_t j = order[q];
                                if (s->medium[j] != s->medium[i]) continue;
                                float d[3];
                                prt__v3_sub(s->pos + j * 3, s->pos + i * 3, d);
                                if (prt__v3_dot(d, d) > r2) continue;
                                const size_t src = s->texel[j];
                                const int sx = (int)(src % (size_t)W), sy = (int)(src / (size_t)W);
                                float tr[3];
                                if (j == i) prt__offset_tr(&ob->x[1], t, src, tr);   /* its own disc, in closed form */
                                else {
                                    const prt__dipole *dm = ob->dipoles[s->medium[i] - 1];
                                    const double r = sqrt((double)prt__v3_dot(d, d)), a = fmin(sqrt(s->area[j] / PRT_PI), r / 2);   /* the half nearer t is t's own texel's */
                                    for (int c = 0; c < 3; ++c)
                                        tr[c] = (float)prt__dipole_disc_mean(&dm[c], r, a) * (dm[c].falloff > 0 ? ob->patches.albedo[t * 3 + c] : 1.0f);
                                }
                                /* Near in the map on t's chart: its cell there; else (across a seam, another
                                 * chart) the surface around the representative nearest in space, as radiosity. */
                                const bool near = ob->chart[src] == ob->chart[t] && abs(sx - tx) <= NEAR_FIELD && abs(sy - ty) <= NEAR_FIELD;
                                const int o = src == t ? 0
                                              : near ? prt__offset_recell(&ob->charts, W, s->offsets, K, tx, ty, rc.rep, rc.rep_chart,
                                                                          label[(size_t)(sy - ty + H - 1) * gw + sx - tx + W - 1], sx, sy, ob->chart[src])
                                                     : nearest_rep(ob, &rc.ix, (uint32_t)src, false);
                                if (o < 0) continue;
                                for (int c = 0; c < 3; ++c) maps[((size_t)o * nc + i) * 3 + c] += tr[c] * s->area[j];
                            }
                        }
            }
            prt__progress_add(p, 1);
        }
#pragma omp single
        maps_block_done(ob);
        }
        receiver_free(&rc);
    }
    free(reach); free(start); free(order); free(at);
    return !short_of_memory;
}

static prt_status maps_step(prt__bake_job *base, prt_context *ctx, prt__progress *p)
{
    obake *ob = (obake *)base;
    prt__offset_set *s = ob->s;
    const int W = s->width, H = s->height, K = s->count;
    const size_t nc = s->covered;
    ob->charts = (prt__offset_charts){ob->chart, s->source, s->texel, ob->patches.pos};
    int32_t *label = NULL;
    prt_status st = prt__offset_labels(ctx, W, H, s->offsets, K, &label);
    if (!st && (s->offsets[0] != 0 || s->offsets[1] != 0)) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "the first offset must be (0, 0)");
    prt__progress_begin(p, p->stage, (uint64_t)nc * (uint64_t)((ob->d.kinds & 1) + ((ob->d.kinds >> 1) & 1)));
    for (int k = 0; k < 2 && !st; ++k) {
        if (!(ob->d.kinds & (1u << k))) continue;
        float *maps = NULL;
        if ((st = prt__offset_maps_new(ctx, nc * (size_t)K * 3, ob->streaming, &maps))) break;
        /* The state's at once: the blocks hand its pages back as they finish. */
        s->mapped[k] = ob->streaming;
        if (k == 0) s->radiosity = maps;
        else s->subsurface = maps;
        if (!(k == 0 ? radiosity_maps(ob, label, maps, p) : subsurface_maps(ob, label, maps, p))) {
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the transfer maps");
            break;
        }
        /* What a texel gathers is bounded: its form factors add up to at most 1 (all it sees),
         * the dipole to its total diffuse reflectance. Where the offsets' cells overestimate it
         * (a chart's texels crowding into a point, as at a sphere's pole), scale the texel's maps
         * down to the bound: the bounces then converge, and no texel shines. */
        size_t capped = 0;
        double top = 1, total = 0;   /* the cap's factors (gathered / bound), over the texels capped */
        for (size_t i = 0; i < nc; ++i) {
            double factor = 1;
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (int o = 0; o < K; ++o) sum += maps[((size_t)o * nc + i) * 3 + c];
                const prt__dipole *dm = k && s->medium[i] ? &ob->dipoles[s->medium[i] - 1][c] : NULL;
                const double limit = k == 0 ? s->albedo[i * 3 + c] : dm ? prt__dipole_total(dm) * (dm->falloff > 0 ? s->albedo[i * 3 + c] : 1.0) : 0.0;
                if (!(sum > limit) || !(sum > 0)) continue;
                factor = fmax(factor, limit > 0 ? sum / limit : INFINITY);
                for (int o = 0; o < K; ++o) maps[((size_t)o * nc + i) * 3 + c] *= (float)(limit / sum);
            }
            if (i + 1 == nc || (i + 1) % ob->block == 0) maps_block_done(ob);
            if (!(factor > 1)) continue;
            capped++;
            top = fmax(top, factor);
            total += factor;
        }
        s->cap_known = true;
        s->cap[k] = (prt__offset_cap){(uint32_t)capped, (float)fmin(top, 1e30), capped ? (float)fmin(total / (double)capped, 1e30) : 1.0f};
        if (capped)
            prt__log(ctx, PRT_LOG_INFO, "%s maps: %zu of %zu texels would gather more than they %s (their offsets' cells overlap; %s); scaled down to that",
                     k ? "subsurface" : "radiosity", capped, nc, k ? "scatter" : "reflect",
                     k ? "scattering wider than the light map's reach or texels, see --mm-per-unit" : "more offsets make it rarer");
        if (prt__progress_cancelled(p)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    }
    free(label);
    return st;
}

/* ---- first-order light from the environment ---- */

/* Per texel, the SH projection of V(w) max(0, n . w) / pi over a Fibonacci sphere: the radiance a
 * texel of albedo 1 reflects is this dotted with the lighting's SH. And, when the scene emits, the
 * shadowed irradiance from its emissive surfaces by light samples on them (stratified, the same
 * for every texel): their direct light is first-order light like any lamp's. */
static prt_status env_step(prt__bake_job *base, prt_context *ctx, prt__progress *p)
{
    obake *ob = (obake *)base;
    prt__offset_set *s = ob->s;
    float *dirs = malloc(ENV_DIRECTIONS * 3 * sizeof *dirs), *y = malloc(ENV_DIRECTIONS * PRT__OFFSET_ENV_COEFFS * sizeof *y);
    if (!dirs || !y) { free(dirs); free(y); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (int k = 0; k < ENV_DIRECTIONS; ++k) {
        const float z = 1.0f - 2.0f * (k + 0.5f) / ENV_DIRECTIONS, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.39996323f * k;
        dirs[k * 3] = r * cosf(phi); dirs[k * 3 + 1] = z; dirs[k * 3 + 2] = r * sinf(phi);
        prt_sh_eval_f(3, dirs + k * 3, y + k * PRT__OFFSET_ENV_COEFFS);
    }
    prt__emitters em = {0};
    if (s->emit && prt__emitters_init(&em, &ob->t->mesh, 1.0f)) { free(dirs); free(y); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    prt__progress_begin(p, p->stage, s->covered);
    const float weight = (float)(4 * PRT_PI / ENV_DIRECTIONS / PRT_PI);
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
    for (size_t i = 0; i < s->covered; ++i) {
        if (prt__progress_cancelled(p)) continue;
        const float *n = s->nrm + i * 3, *q = s->pos + i * 3;
        float o[3], *out = s->env + i * PRT__OFFSET_ENV_COEFFS;
        for (int c = 0; c < 3; ++c) o[c] = q[c] + n[c] * s->ray_offset;
        memset(out, 0, PRT__OFFSET_ENV_COEFFS * sizeof *out);
        for (int k = 0; k < ENV_DIRECTIONS; ++k) {
            const float cosine = prt__v3_dot(n, dirs + k * 3);
            if (cosine <= 0 || prt__raycaster_occluded(&ob->rc, o, dirs + k * 3, INFINITY)) continue;
            for (int c = 0; c < PRT__OFFSET_ENV_COEFFS; ++c) out[c] += weight * cosine * y[k * PRT__OFFSET_ENV_COEFFS + c];
        }
        double e[3] = {0, 0, 0};
        for (int k = 0; em.count && k < EMITTER_SAMPLES; ++k) {
            prt__light_sample ls;
            const double u1 = fmod(0.5 + 0.7548776662466927 * k, 1.0), u2 = fmod(0.5 + 0.5698402909980532 * k, 1.0);
            if (!prt__emitters_sample(&em, &ob->t->mesh, o, (k + 0.5) / EMITTER_SAMPLES, u1, u2, &ls)) continue;
            const float cosine = prt__v3_dot(ls.wi, n);
            if (cosine <= 0 || prt__raycaster_occluded(&ob->rc, o, ls.wi, ls.dist * (1.0f - 1e-3f))) continue;
            for (int c = 0; c < 3; ++c) e[c] += ls.value[c] * cosine;   /* value = L_e / pdf */
        }
        for (int c = 0; s->emit_in && c < 3; ++c) s->emit_in[i * 3 + c] = (float)(e[c] / EMITTER_SAMPLES);
        prt__progress_add(p, 1);
    }
    prt__emitters_free(&em);
    free(dirs);
    free(y);
    return prt__progress_cancelled(p) ? prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled") : PRT_OK;
}

/* ---- multi-bounce radiosity maps ---- */

/* Bounces past the first, added to the single-bounce radiosity maps (the paper's maps hold every
 * bounce: TR(t, t') is the radiosity solution with unit emission at t'). From each texel, paths
 * of cosine-distributed rays: where the k-th ray (k >= 2) lands, the path's weight - the albedos
 * met so far, the texel's own first - goes to the offset cell that holds the landing point (the
 * surface around its representative, nearest_rep), as a unit emitter there would send it back.
 * Summed over a cell this is the integral of eq. 8, so no cell's surface goes missing; the first
 * bounce is radiosity_maps'. Seeded per texel: the same maps for any thread count. */
/* Bounces are a stage of units (blocks of texels), so that they resume, shard and spread like any
 * other: a unit's record is its texels' radiosity maps after the bounces. */
#define BOUNCE_BLOCK 64

/* A bounce unit's rows written or read: in a streamed bake, every PRT__OFFSET_BOUNCE_DROP of them the pages
 * go back (units in flight on other threads touch theirs again, read back from the file). */
static void bounce_touched(obake *ob)
{
    if (ob->streaming && __atomic_add_fetch(&ob->units_touched, 1, __ATOMIC_RELAXED) % PRT__OFFSET_BOUNCE_DROP == 0) prt__offset_maps_drop(ob->s);
}

static void bounce_texel(obake *ob, receiver *rc, double *acc, size_t i)
{
    prt__offset_set *s = ob->s;
    const int W = s->width, K = s->count, B = s->map_bounces, N = ob->d.walks > 0 ? ob->d.walks : 256;
    const size_t nc = s->covered;
    const prt__mesh *m = &ob->t->mesh;
    const int strata = (int)sqrt((double)N);
    memset(acc, 0, (size_t)K * 3 * sizeof *acc);
    const int tx = (int)(s->texel[i] % (uint32_t)W), ty = (int)(s->texel[i] / (uint32_t)W);
    receiver_at(ob, rc, tx, ty);
    uint64_t rng = ((uint64_t)ob->d.seed << 32) ^ (i * 0xD1B54A32D192ED03ull);
    for (int w = 0; w < N; ++w) {
        float o[3], n[3], d[3];
        double weight[3];
        for (int c = 0; c < 3; ++c) {
            n[c] = s->nrm[i * 3 + c];
            o[c] = s->pos[i * 3 + c] + n[c] * s->ray_offset;
            weight[c] = s->albedo[i * 3 + c];
        }
        /* The first direction stratified: the paths spread evenly over the hemisphere. */
        double u1 = walk_uniform(&rng), u2 = walk_uniform(&rng);
        if (w < strata * strata) { u1 = (w / strata + u1) / strata; u2 = (w % strata + u2) / strata; }
        for (int k = 1; k <= B; ++k) {
            if (k > 1) { u1 = walk_uniform(&rng); u2 = walk_uniform(&rng); }
            cosine_direction(n, u1, u2, d);
            prt__ray_hit h;
            const int32_t at = landing(ob, o, d, &h);
            if (at < 0) break;
            if (k > 1) {   /* the cell of the surface around the landing point (nearest_rep) */
                const int cell = nearest_rep(ob, &rc->ix, s->texel[at], true);
                for (int c = 0; c < 3 && cell >= 0; ++c) acc[cell * 3 + c] += weight[c];
            }
            double most = 0;
            for (int c = 0; c < 3; ++c) { weight[c] *= s->albedo[(size_t)at * 3 + c]; most = fmax(most, weight[c]); }
            if (!(most > 1e-4)) break;
            /* On from the hit, off its surface along its (front-facing) shading normal. */
            const uint32_t *ix = m->indices + (size_t)h.prim * 3;
            const float b0 = 1 - h.u - h.v;
            float len = 0;
            for (int c = 0; c < 3; ++c) {
                n[c] = b0 * m->normals[ix[0] * 3 + c] + h.u * m->normals[ix[1] * 3 + c] + h.v * m->normals[ix[2] * 3 + c];
                len += n[c] * n[c];
            }
            if (!(len > 0) || prt__v3_dot(n, d) >= 0)   /* the front's geometric normal (it faces the ray) */
                for (int c = 0; c < 3; ++c) n[c] = h.ng[c];
            prt__v3_normalize(n);
            for (int c = 0; c < 3; ++c) o[c] = o[c] + d[c] * h.t + n[c] * s->ray_offset;
        }
    }
    for (int k = 0; k < K; ++k)
        for (int c = 0; c < 3; ++c) s->radiosity[((size_t)k * nc + i) * 3 + c] += (float)(acc[k * 3 + c] / N);
}

static prt_status bounce_unit(prt__bake_job *base, uint64_t unit, int thread)
{
    obake *ob = (obake *)base;
    const int K = ob->s->count;
    bounce_scratch *b = &ob->bounce[thread];
    if (!b->acc) {
        if (!(b->acc = malloc((size_t)K * 3 * sizeof *b->acc)) || !receiver_init(&b->rc, K)) {
            receiver_free(&b->rc);
            free(b->acc);
            memset(b, 0, sizeof *b);
            return prt__fail(base->ctx, PRT_ERR_NO_MEMORY, "out of memory tracing the maps' bounces");
        }
    }
    const size_t nc = ob->s->covered, end = (size_t)(unit + 1) * BOUNCE_BLOCK < nc ? (size_t)(unit + 1) * BOUNCE_BLOCK : nc;
    for (size_t i = (size_t)unit * BOUNCE_BLOCK; i < end; ++i) bounce_texel(ob, &b->rc, b->acc, i);
    bounce_touched(ob);
    return PRT_OK;
}

/* A unit's record: for each of its texels, for each offset, the map's RGB. */
static void bounce_save(prt__bake_job *base, uint64_t unit, prt__bytes *out)
{
    const prt__offset_set *s = ((obake *)base)->s;
    const size_t nc = s->covered, first = (size_t)unit * BOUNCE_BLOCK, end = first + BOUNCE_BLOCK < nc ? first + BOUNCE_BLOCK : nc;
    for (int k = 0; k < s->count; ++k) prt__bytes_put(out, s->radiosity + ((size_t)k * nc + first) * 3, (end - first) * 3 * sizeof(float));
    bounce_touched((obake *)base);
}

static bool bounce_load(prt__bake_job *base, uint64_t unit, const unsigned char *data, size_t size)
{
    const prt__offset_set *s = ((obake *)base)->s;
    const size_t nc = s->covered, first = (size_t)unit * BOUNCE_BLOCK, end = first + BOUNCE_BLOCK < nc ? first + BOUNCE_BLOCK : nc;
    const size_t row = (end - first) * 3 * sizeof(float);
    if (first >= nc || size != row * (size_t)s->count) return false;
    for (int k = 0; k < s->count; ++k) {
        const float *v = (const float *)(data + row * (size_t)k);
        for (size_t j = 0; j < (end - first) * 3; ++j) {
            float x;
            memcpy(&x, v + j, sizeof x);
            if (!isfinite(x) || x < 0) return false;
        }
        memcpy(s->radiosity + ((size_t)k * nc + first) * 3, data + row * (size_t)k, row);
    }
    bounce_touched((obake *)base);
    return true;
}

static prt_status offset_stage(prt__bake_job *base, int index, prt__stage *out)
{
    static const char *const names[3] = {"offsets", "transfer maps", "first-order light"};
    static prt_status (*const steps[3])(prt__bake_job *, prt_context *, prt__progress *) = {offsets_step, maps_step, env_step};
    obake *ob = (obake *)base;
    /* The memory limit is known once the bake has begun: before the first stage. */
    ob->streaming = base->memory_over;
    ob->block = ob->streaming ? PRT__OFFSET_MAP_BLOCK : ob->s->covered ? ob->s->covered : 1;
    if (index == 1 && ob->streaming)
        prt__log(base->ctx, PRT_LOG_INFO, "memory: the transfer maps stream through a scratch file, %d texels at a time", PRT__OFFSET_MAP_BLOCK);
    if (index < 0 || index > 3 || (index == 3 && (ob->s->map_bounces < 2 || !ob->s->radiosity))) return PRT_OK;
    if (index == 3) {
        free(ob->bounce);
        if (!(ob->bounce = prt__calloc((size_t)base->threads, sizeof *ob->bounce))) return prt__fail(base->ctx, PRT_ERR_NO_MEMORY, "out of memory");
        ob->bounce_threads = base->threads;
        ob->charts = (prt__offset_charts){ob->chart, ob->s->source, ob->s->texel, ob->patches.pos};
        snprintf(out->name, sizeof out->name, "bounces");
        out->units = (ob->s->covered + BOUNCE_BLOCK - 1) / BOUNCE_BLOCK;
        out->run = bounce_unit;
        out->save_unit = bounce_save;
        out->load_unit = bounce_load;
        return PRT_OK;
    }
    snprintf(out->name, sizeof out->name, "%s", names[index]);
    out->whole = steps[index];
    return PRT_OK;
}

static prt_status offset_finish(prt__bake_job *base, prt_transfer *t)
{
    const obake *ob = (const obake *)base;
    /* The steps wrote into the state. The maps are stored as halves (11 significant bits, 0.05%
     * relative: far under the paths' noise), so the transfer holds what its file will. */
    prt__offset_set *s = t->state;
    const size_t n = (size_t)s->count * s->covered * 3, step = ob->block * (size_t)s->count * 3;
    for (int k = 0; k < 2; ++k) {
        float *maps = k ? s->subsurface : s->radiosity;
        for (size_t first = 0; maps && first < n; first += step) {
            const size_t end = n - first > step ? first + step : n;
            for (size_t i = first; i < end; ++i) maps[i] = prt__half_to_float(prt__half_from_float(maps[i]));
            maps_block_done(ob);
        }
    }
    maps_block_done(ob);
    return PRT_OK;
}

static void offset_release(prt__bake_job *base)
{
    obake *ob = (obake *)base;
    prt__raycaster_release(&ob->rc);
    prt__texel_patches_free(&ob->patches);
    for (int i = 0; ob->bounce && i < ob->bounce_threads; ++i) {
        if (ob->bounce[i].acc) receiver_free(&ob->bounce[i].rc);
        free(ob->bounce[i].acc);
    }
    free(ob->bounce);
    free(ob->texel_medium);
    free(ob->chart);
    free(ob->chart_area);
    free(ob->dipoles);
    free(ob);
}

/* ---- set-up ---- */

/* Each surface texel's UV chart (the island of the triangle that owns it), -1 off the surface. */
static prt_status texel_charts(prt_context *ctx, const prt__mesh *m, const prt__texel_patches *p, int32_t **out, double **area)
{
    const size_t n = (size_t)p->width * p->height;
    uint32_t *island = malloc(m->triangle_count * sizeof *island + 1), count = 0;
    int32_t *chart = malloc(n * sizeof *chart);
    if (!island || !chart) { free(island); free(chart); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    prt_status st = prt__uv_islands(ctx, m, island, &count);
    for (size_t i = 0; !st && i < n; ++i) chart[i] = p->area[i] > 0 && p->owner[i] ? (int32_t)island[p->owner[i] - 1] : -1;
    free(island);
    double *sum = st ? NULL : prt__calloc(count + 1, sizeof *sum);
    if (!st && !sum) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (st) { free(chart); return st; }
    for (size_t i = 0; i < n; ++i)
        if (chart[i] >= 0) sum[chart[i]] += p->area[i];
    *out = chart;
    *area = sum;
    return PRT_OK;
}

/* The largest light map a generated atlas may grow to when no size was asked for: the map and
 * its offsets within PRT__OFFSET_MAX_ENTRIES, and bakes of minutes rather than hours. */
#define AUTO_MAX_TEXELS 1024
#define ATLAS_SHARE 0.65   /* about what a generated atlas covers (bunny, dragon) */

/* Without --texels, the light map's size follows the scene: its texels on the surface at most a
 * 64th of the scene's diagonal wide (a scale for indirect light, the environment's shadows and
 * painted light that holds in any units: a 3 m room and a 15 cm bunny get the same texels per
 * diagonal), the map 128 at least and SCENE_MAX_TEXELS at most (a bake of minutes; --texels asks
 * for more). Finer did not pay: the closed room at 256^2 (1/151) was as far from the path tracer
 * as at 128^2 (1/75), 0.092 against 0.089 relative L2, for four times the bake; a scene with far
 * more surface than its extent (Sponza: 1/50 at 128^2) takes 256^2. uv_share: the share of the
 * map's area the layout covers. */
#define SCENE_TEXELS_PER_DIAGONAL 64
#define SCENE_MAX_TEXELS 512

int prt__offset_scene_texels(const prt__mesh *m, double uv_share, int least, int count, double *texel, double *diagonal, double *area)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, a = 0, d2 = 0;
    for (size_t v = 0; v < m->vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], m->positions[v * 3 + k]);
            hi[k] = fmax(hi[k], m->positions[v * 3 + k]);
        }
    for (size_t f = 0; f < m->triangle_count; ++f) {
        const float *p0 = m->positions + m->indices[f * 3] * 3, *p1 = m->positions + m->indices[f * 3 + 1] * 3, *p2 = m->positions + m->indices[f * 3 + 2] * 3;
        const double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        const double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        a += 0.5 * sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    }
    for (int k = 0; k < 3; ++k) d2 += m->vertex_count ? (hi[k] - lo[k]) * (hi[k] - lo[k]) : 0;
    *diagonal = sqrt(d2);
    *area = a;
    const double want = *diagonal / SCENE_TEXELS_PER_DIAGONAL, share = fmin(fmax(uv_share, 0.05), 1.0);
    int r = least;
    while (r < SCENE_MAX_TEXELS && (uint64_t)r * r * 4 * (uint64_t)count <= PRT__OFFSET_MAX_ENTRIES && sqrt(a / (share * r * r)) > want) r *= 2;
    *texel = sqrt(a / (share * r * r));
    return r;
}

/* The share of [0, 1]^2 that m's own texture coordinates cover (overlaps counted twice). */
static double uv_share(const prt__mesh *m)
{
    double a = 0;
    for (size_t f = 0; f < m->triangle_count; ++f) {
        const float *a0 = m->uv + m->indices[f * 3] * 2, *a1 = m->uv + m->indices[f * 3 + 1] * 2, *a2 = m->uv + m->indices[f * 3 + 2] * 2;
        a += 0.5 * fabs((double)(a1[0] - a0[0]) * (a2[1] - a0[1]) - (double)(a2[0] - a0[0]) * (a1[1] - a0[1]));
    }
    return a;
}

/* Sizes the light map from the scene when no size was asked for, and says so. */
static void size_for_scene(prt_context *ctx, prt__offset_bake_desc *d, const prt_transfer *t, double share)
{
    if (!d->texels_default) return;
    double texel, diagonal, area;
    const int r = prt__offset_scene_texels(&t->mesh, share, d->texels, d->count, &texel, &diagonal, &area);
    if (r != d->texels)
        prt__log(ctx, PRT_LOG_INFO, "light map %d x %d for the scene's size: its %.3g square units of surface in texels about %.3g wide, 1/%.0f of its "
                 "diagonal %.3g (texels of 1/%d of it or finer, maps up to %d; --texels sets the size)", r, r, area, texel, diagonal / texel, diagonal,
                 SCENE_TEXELS_PER_DIAGONAL, SCENE_MAX_TEXELS);
    d->texels = r;
}

/* The mesh's own UVs when they are a unique layout inside [0, 1], else a generated atlas (which
 * copies the vertices on chart seams: before anything is sized by the vertex count). Without
 * --texels, the atlas's map doubles (up to AUTO_MAX_TEXELS) while its charts do not fit or are
 * mostly gutter (see prt__atlas_desc), and d->texels becomes the size taken. */
static prt_status layout(prt_context *ctx, prt__offset_bake_desc *d, prt_transfer *t)
{
    char why[160] = "asked for";
    if (d->uv_layout == PRT_UV_MESH) {
        /* The mesh's own layout, as asked: it must be one (the input's fault when it is not). */
        if (prt__uv_layout_unusable(&t->mesh, d->texels, why, sizeof why))
            return prt__fail(ctx, PRT_ERR_FORMAT, "--uv mesh: '%s' has no usable UV layout (%s); --uv auto generates an atlas", t->source, why);
        size_for_scene(ctx, d, t, uv_share(&t->mesh));
        return PRT_OK;
    }
    if (d->uv_layout == PRT_UV_AUTO && !prt__uv_layout_unusable(&t->mesh, d->texels, why, sizeof why)) {
        size_for_scene(ctx, d, t, uv_share(&t->mesh));
        return PRT_OK;
    }
    size_for_scene(ctx, d, t, ATLAS_SHARE);
    int max = d->texels;
    while (d->texels_default && max <= AUTO_MAX_TEXELS / 2 && (uint64_t)max * max * 4 * (uint64_t)d->count <= PRT__OFFSET_MAX_ENTRIES) max *= 2;
    prt__atlas_report r;
    prt_status st = prt__uv_atlas(ctx, &t->mesh, &(prt__atlas_desc){.resolution = d->texels, .max_resolution = max}, &r);
    if (st) return st;
    if (r.resolution != d->texels) {
        char was[96];
        if (r.smaller_fit) snprintf(was, sizeof was, "touch only %.0f%% of the texels of %d x %d (mostly gutter)", 100 * r.smaller_cover, r.smaller, r.smaller);
        else snprintf(was, sizeof was, "do not fit %d x %d", r.smaller, r.smaller);
        prt__log(ctx, PRT_LOG_INFO, "light map %d x %d: the %zu UV charts of '%s' %s (--texels sets the size)", r.resolution, r.resolution, r.charts,
                 t->source, was);
        d->texels = r.resolution;
    }
    prt__log(ctx, PRT_LOG_INFO, "UV atlas for '%s' (%s): %zu charts touch %.0f%% of the %dx%d light map's texels (each one baked: "
             "the coverage prt info reports), worst stretch %.2f", t->source, why,
             r.charts, 100 * r.coverage, d->texels, d->texels, r.worst_stretch);
    return PRT_OK;
}

prt_status prt__offset_bake_begin(prt_context *ctx, const prt__offset_bake_desc *desc, prt_transfer *t, prt__bake_job **out)
{
    prt__offset_bake_desc d = *desc;
    if (d.texels < 8 || d.texels > 4096) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "light map size %d out of range 8..4096", d.texels);
    if (d.count < 1) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "offsets must be at least 1");
    if ((uint64_t)d.texels * d.texels * (uint64_t)d.count > PRT__OFFSET_MAX_ENTRIES)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%d offsets over a %dx%d light map is more than %llu map entries; use fewer offsets or texels", d.count,
                         d.texels, d.texels, (unsigned long long)PRT__OFFSET_MAX_ENTRIES);
    if (!d.kinds) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "no transfer kind to bake");
    prt_status st = layout(ctx, &d, t);
    if (st) return st;
    obake *ob = prt__calloc(1, sizeof *ob);
    prt__offset_set *s = prt__calloc(1, sizeof *s);
    if (!ob || !s) { free(ob); free(s); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    ob->base.stage = offset_stage;
    ob->base.finish = offset_finish;
    ob->base.release = offset_release;
    ob->base.ctx = ctx;
    ob->d = d;
    ob->t = t;
    ob->s = s;
    t->state = s;   /* owned by t from here on */
    if (!prt__offset_cache_new(s)) { offset_release(&ob->base); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    s->width = s->height = d.texels;
    s->kinds = d.kinds;
    s->iterations = d.iterations;
    s->map_bounces = d.map_bounces > 1 ? d.map_bounces : 1;
    s->cap[0] = s->cap[1] = (prt__offset_cap){0, 1, 1};   /* none capped until maps_step says */
    s->importance = d.importance;
    s->eta = d.eta;
    s->mm_per_unit = d.mm_per_unit;
    for (int c = 0; c < 3; ++c) { s->sigma_a[c] = d.sigma_a[c]; s->sigma_s[c] = d.sigma_s[c]; }
    /* The media: the scene's translucent materials, or one for every surface. */
    if (d.kinds & PRT__OFFSET_SUBSURFACE_BIT) {
        s->medium_count = d.surface_medium ? d.medium_count : 1;
        s->media = malloc((size_t)(s->medium_count + 1) * sizeof *s->media);
        ob->dipoles = malloc((size_t)(s->medium_count + 1) * sizeof *ob->dipoles);
        if (!s->media || !ob->dipoles) { offset_release(&ob->base); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        for (int k = 0; k < s->medium_count; ++k) {
            s->media[k] = d.surface_medium ? d.media[k] : (prt_medium){{d.sigma_a[0], d.sigma_a[1], d.sigma_a[2]}, {d.sigma_s[0], d.sigma_s[1], d.sigma_s[2]}, d.eta, 0};
            /* Per mm in the medium; the scene's lengths become mm through mm_per_unit. */
            if (!st) st = prt__dipole_from_medium(&s->media[k], d.mm_per_unit, ob->dipoles[k]);
        }
        if (st) { offset_release(&ob->base); return st; }
    }
    s->ray_offset = d.ray_offset > 0 ? d.ray_offset : prt__ray_offset(&t->mesh);
    st = prt__texel_patches_build(ctx, &t->mesh, d.texels, d.texels, &ob->patches);
    if (!st) st = prt__raycaster_create(ctx, &t->mesh, &ob->rc);
    const size_t n = (size_t)d.texels * d.texels;
    for (size_t i = 0; !st && i < n; ++i) s->covered += ob->patches.area[i] > 0;
    if (!st && !s->covered) st = prt__fail(ctx, PRT_ERR_EMPTY, "no texel of the %dx%d light map lies on the surface", d.texels, d.texels);
    if (!st) {
        const size_t nc = s->covered;
        s->texel = malloc(nc * sizeof *s->texel);
        s->pos = malloc(nc * 3 * sizeof(float));
        s->nrm = malloc(nc * 3 * sizeof(float));
        s->albedo = malloc(nc * 3 * sizeof(float));
        s->area = malloc(nc * sizeof(float));
        s->env = prt__calloc(nc * PRT__OFFSET_ENV_COEFFS, sizeof(float));
        bool emits = false;
        for (size_t v = 0; t->mesh.emission && v < t->mesh.vertex_count * 3 && !emits; ++v) emits = t->mesh.emission[v] > 0;
        if (emits) { s->emit = prt__calloc(nc * 3, sizeof(float)); s->emit_in = prt__calloc(nc * 3, sizeof(float)); }
        if (s->medium_count) {
            s->medium = prt__calloc(nc + 1, 1);
            ob->texel_medium = prt__calloc(n + 1, 1);
            if (!s->medium || !ob->texel_medium) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        }
        if (!s->texel || !s->pos || !s->nrm || !s->albedo || !s->area || !s->env || (emits && (!s->emit || !s->emit_in)))
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    for (size_t i = 0, k = 0; !st && i < n; ++i) {
        if (!(ob->patches.area[i] > 0)) continue;
        s->texel[k] = (uint32_t)i;
        memcpy(s->pos + k * 3, ob->patches.pos + i * 3, 3 * sizeof(float));
        memcpy(s->nrm + k * 3, ob->patches.nrm + i * 3, 3 * sizeof(float));
        memcpy(s->albedo + k * 3, ob->patches.albedo + i * 3, 3 * sizeof(float));
        s->area[k] = ob->patches.area[i];
        if (s->medium) {   /* the owning triangle's surface */
            const uint32_t v0 = t->mesh.indices[(size_t)(ob->patches.owner[i] - 1) * 3];
            const uint16_t sid = t->mesh.surface ? t->mesh.surface[v0] : 0;
            s->medium[k] = ob->texel_medium[i] = d.surface_medium ? d.surface_medium[sid] : 1;
        }
        if (s->emit) {   /* the owning triangle's emission at the texel centre */
            const uint32_t *ix = t->mesh.indices + (size_t)(ob->patches.owner[i] - 1) * 3;
            for (int c = 0; c < 3; ++c)
                s->emit[k * 3 + c] = (t->mesh.emission[ix[0] * 3 + c] + t->mesh.emission[ix[1] * 3 + c] + t->mesh.emission[ix[2] * 3 + c]) / 3.0f;
        }
        k++;
    }
    /* A translucent texel reflects light that bounced onto it through its medium, as it does first-
     * order light: the dipole's total diffuse reflectance, not the mesh's colour, is the albedo its
     * radiosity maps gather with (an exponential falloff keeps the albedo: it integrates to 1). */
    for (size_t k = 0; !st && s->medium && k < s->covered; ++k) {
        if (!s->medium[k]) continue;
        for (int c = 0; c < 3; ++c) {
            const prt__dipole *dm = &ob->dipoles[s->medium[k] - 1][c];
            if (dm->falloff > 0) continue;
            s->albedo[k * 3 + c] = ob->patches.albedo[(size_t)s->texel[k] * 3 + c] = (float)fmin(1.0, prt__dipole_total(dm));
        }
    }
    if (!st) {
        int32_t *label = malloc(n * sizeof *label);
        if (!label) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st) st = prt__texel_support_charts(ctx, &t->mesh, d.texels, d.texels, label);
        if (!st && !prt__offset_set_index(s, label)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        free(label);
    }
    if (!st) st = texel_charts(ctx, &t->mesh, &ob->patches, &ob->chart, &ob->chart_area);
    if (!st) {
        ob->x[0] = (prt__offset_transfer){.kind = PRT__OFFSET_RADIOSITY, .patches = &ob->patches, .rc = &ob->rc, .ray_offset = s->ray_offset};
        ob->x[1] = (prt__offset_transfer){.kind = PRT__OFFSET_DIPOLE, .patches = &ob->patches, .medium = ob->texel_medium,
                                          .media = (const prt__dipole (*)[3])ob->dipoles};
    }
    if (st) { offset_release(&ob->base); return st; }
    *out = &ob->base;
    return PRT_OK;
}
