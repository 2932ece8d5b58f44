/* Adaptive refinement: more vertices only where transfer changes faster than the vertices sample
 * it. Transfer lives at vertices and is interpolated across triangles, so a contact shadow under a
 * box, or a shadow edge crossing a big floor triangle, is drawn as a sawtooth or not at all; a
 * global --max-edge fixes that by multiplying every triangle. Here a cheap probe of what shapes
 * transfer - ambient occlusion within a tenth of the scene, and the shadow of each light the scene
 * names (its emitting surfaces included) - is taken at the vertices, at edge midpoints and inside
 * triangles. Edges whose ends differ, or whose midpoint differs from the mean of its ends, by more
 * than a threshold are split at the midpoint (which the probe has already measured), as are all
 * edges of a triangle whose inside differs from what its corners interpolate; levels repeat until
 * nothing differs, edges reach a minimum length or the vertex budget is spent.
 *
 * Splitting keeps triangles well shaped and the mesh conforming: a triangle with a marked edge
 * always has its longest edge marked too (longest-edge bisection, Rivara), which propagates along
 * longest-edge paths and ends, and is split by bisecting that edge first. Vertices duplicated at
 * creases (same position, two normals) are welded for the decisions, so both sides of a crease
 * split alike and no crack opens.
 *
 * Every probe is a function of the point alone (one fixed set of world directions), so the result
 * does not depend on the thread count, and neighbouring probes differ only where the geometry
 * around them does: noise does not mark edges. */
#include "core/progress.h"
#include "geom/raycast.h"

#define DIRECTIONS 128        /* world directions of the occlusion probe (about 64 per hemisphere) */
#define AO_RADIUS 0.1f        /* occlusion counts within this share of the scene's diagonal */
#define EMITTER_SAMPLES 32    /* points on emitting surfaces that stand for them */
#define SPHERE_SAMPLES 8      /* points on a sphere light's disc */
#define MAX_LEVELS_DEFAULT 10
#define DEFAULT_BUDGET 100000  /* new vertices when not told: a Cornell box needs thousands, a scan as many as it has */
#define MAX_CHANNELS 17       /* occlusion, emitters, and up to 15 lights */

typedef struct emitter_sample { float p[3], n[3]; } emitter_sample;

typedef struct probe_set {
    const prt__raycaster *rc;
    float dirs[DIRECTIONS * 3];
    float radius, offset;
    int channels;
    int light_count;               /* lights with a channel of their own */
    const prt_light *lights;
    int emitter_count;             /* 0 when nothing emits */
    emitter_sample emitters[EMITTER_SAMPLES];
} probe_set;

/* ---- the probe ---------------------------------------------------------------------------- */

/* Ambient occlusion over the fixed directions (cosine weighted): the share of the hemisphere free
 * within radius. NaN when most rays meet back faces: the point is inside geometry and says
 * nothing about the surface. */
static float probe_occlusion(const probe_set *ps, const float o[3], const float n[3])
{
    int idx[DIRECTIONS], count = 0;
    float w[DIRECTIONS];
    for (int k = 0; k < DIRECTIONS; ++k) {
        const float c = prt__v3_dot(n, ps->dirs + k * 3);
        if (c > 0.02f) { w[count] = c; idx[count++] = k; }
    }
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    double free_w = 0, all_w = 0;
    int back = 0;
    for (int at = 0; at < count; at += 16) {
        const int lanes = count - at < 16 ? count - at : 16;
        struct RTCRayHit16 rh __attribute__((aligned(64)));
        int valid[16] __attribute__((aligned(64)));
        prt__packet_rayhits(&rh, valid, o, ps->dirs, idx + at, lanes);
        for (int k = 0; k < 16; ++k) rh.ray.tfar[k] = ps->radius;
        rtcIntersect16(valid, ps->rc->scene, &ictx, &rh);
        for (int k = 0; k < lanes; ++k) {
            const float *d = ps->dirs + idx[at + k] * 3;
            all_w += w[at + k];
            if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) { free_w += w[at + k]; continue; }
            back += rh.hit.Ng_x[k] * d[0] + rh.hit.Ng_y[k] * d[1] + rh.hit.Ng_z[k] * d[2] > 0.0f;
        }
    }
    if (2 * back > count) return NAN;
    return all_w > 0 ? (float)(free_w / all_w) : 1.0f;
}

/* The share of the light from the points `q` (with normals qn, or NULL for points that shine every
 * way) that reaches o unshadowed, weighted by the cosines and distances; 1 where none of them
 * faces the surface (no light, so no shadow to resolve). */
static float probe_points(const probe_set *ps, const float o[3], const float n[3], const float *q, const float *qn, int count)
{
    double lit = 0, all = 0;
    for (int i = 0; i < count; ++i) {
        float d[3];
        prt__v3_sub(q + i * 3, o, d);
        const float r2 = prt__v3_dot(d, d), cos_o = prt__v3_dot(d, n);
        const float cos_q = qn ? -prt__v3_dot(d, qn + i * 3) : 1.0f;
        if (!(r2 > 0) || cos_o <= 0 || cos_q <= 0) continue;
        const double weight = (double)cos_o * cos_q / ((double)r2 * r2);
        all += weight;
        /* Stop short of the light's own surface: an emitter is part of the mesh. */
        float end[3];
        for (int c = 0; c < 3; ++c) end[c] = o[c] + d[c] * (1.0f - 1e-3f);
        if (prt__raycaster_segment_clear(ps->rc, o, end)) lit += weight;
    }
    return all > 0 ? (float)(lit / all) : 1.0f;
}

static float probe_light(const probe_set *ps, const prt_light *l, const float o[3], const float n[3])
{
    switch (l->type) {
    case PRT_LIGHT_DIRECTIONAL: {
        float d[3] = {l->direction[0], l->direction[1], l->direction[2]};
        if (!prt__v3_normalize(d) || prt__v3_dot(d, n) <= 0) return 1.0f;
        return prt__raycaster_occluded(ps->rc, o, d, INFINITY) ? 0.0f : 1.0f;
    }
    case PRT_LIGHT_SPHERE: {
        /* Points on the disc the sphere shows to o. */
        float axis[3], t1[3], t2[3], h[3] = {0, 0, 0}, q[SPHERE_SAMPLES * 3];
        prt__v3_sub(o, l->position, axis);
        if (!prt__v3_normalize(axis)) return 1.0f;
        h[fabsf(axis[0]) < 0.6f ? 0 : 1] = 1;
        prt__v3_cross(axis, h, t1);
        prt__v3_normalize(t1);
        prt__v3_cross(axis, t1, t2);
        for (int k = 0; k < SPHERE_SAMPLES; ++k) {
            const float r = l->radius * sqrtf((k + 0.5f) / SPHERE_SAMPLES), phi = 2.39996323f * k;
            for (int c = 0; c < 3; ++c) q[k * 3 + c] = l->position[c] + r * (cosf(phi) * t1[c] + sinf(phi) * t2[c]) + 0.9f * l->radius * axis[c];
        }
        return probe_points(ps, o, n, q, NULL, SPHERE_SAMPLES);
    }
    case PRT_LIGHT_SPOT: {   /* outside its cone no light falls: nothing to resolve */
        float d[3], axis[3] = {l->direction[0], l->direction[1], l->direction[2]};
        prt__v3_sub(o, l->position, d);
        const float angle = (l->angle_deg > 0 ? l->angle_deg : 30.0f) * (float)PRT_PI / 180.0f;
        if (!prt__v3_normalize(d) || !prt__v3_normalize(axis) || prt__v3_dot(d, axis) < cosf(angle)) return 1.0f;
        return probe_points(ps, o, n, l->position, NULL, 1);
    }
    default:   /* point: the shadow of one point */
        return probe_points(ps, o, n, l->position, NULL, 1);
    }
}

/* Every channel for rays leaving from o about the surface normal n. */
static void probe(const probe_set *ps, const float o[3], const float n[3], float *out)
{
    out[0] = probe_occlusion(ps, o, n);
    int ch = 1;
    if (ps->emitter_count) {
        float q[EMITTER_SAMPLES * 3], qn[EMITTER_SAMPLES * 3];
        for (int i = 0; i < ps->emitter_count; ++i)
            for (int c = 0; c < 3; ++c) { q[i * 3 + c] = ps->emitters[i].p[c]; qn[i * 3 + c] = ps->emitters[i].n[c]; }
        out[ch++] = probe_points(ps, o, n, q, qn, ps->emitter_count);
    }
    for (int i = 0; i < ps->light_count; ++i) out[ch++] = probe_light(ps, &ps->lights[i], o, n);
    if (isnan(out[0])) for (int c = 1; c < ps->channels; ++c) out[c] = NAN;   /* inside geometry: no information */
}

/* The probe's origin for a point p of a triangle with centroid cen: off the surface along n, and a
 * little towards the centroid, so that a point on a concave edge (a floor meeting a wall) does not
 * start in the other surface's plane. */
static void probe_origin(const probe_set *ps, const float p[3], const float n[3], const float cen[3], float o[3])
{
    float d[3];
    prt__v3_sub(cen, p, d);
    const float along = prt__v3_dot(d, n);
    for (int c = 0; c < 3; ++c) d[c] -= along * n[c];
    const float len = prt__v3_len(d), step = len > 1e-30f ? fminf(ps->offset, 0.25f * len) / len : 0.0f;
    for (int c = 0; c < 3; ++c) o[c] = p[c] + n[c] * ps->offset + d[c] * step;
}

/* The largest channel difference between a and b; 0 where either knows nothing. */
static float difference(const float *a, const float *b, int channels)
{
    float d = 0;
    for (int c = 0; c < channels; ++c) {
        const float x = fabsf(a[c] - b[c]);
        if (x > d) d = x;   /* NaN compares false */
    }
    return d;
}

/* An emitting triangle's share of the emitter samples: twice its area times its summed
 * emission (0 when it does not emit); cross gets its unnormalised normal when not NULL. */
static double emitter_weight(const prt__mesh *m, size_t t, float cross[3])
{
    const uint32_t *ix = m->indices + t * 3;
    float e1[3], e2[3], cr[3], e = 0;
    for (int k = 0; k < 3; ++k) e += m->emission[ix[k] * 3] + m->emission[ix[k] * 3 + 1] + m->emission[ix[k] * 3 + 2];
    if (!(e > 0)) return 0;
    prt__v3_sub(m->positions + ix[1] * 3, m->positions + ix[0] * 3, e1);
    prt__v3_sub(m->positions + ix[2] * 3, m->positions + ix[0] * 3, e2);
    prt__v3_cross(e1, e2, cr);
    if (cross) memcpy(cross, cr, sizeof cr);
    return (double)e * prt__v3_len(cr);
}

static void setup_probe(probe_set *ps, const prt__raycaster *rc, const prt__mesh *m, const prt_light *lights, int light_count)
{
    memset(ps, 0, sizeof *ps);
    ps->rc = rc;
    ps->offset = prt__ray_offset(m);
    ps->radius = AO_RADIUS * 1e4f * ps->offset;   /* prt__ray_offset is 1e-4 of the diagonal */
    for (int k = 0; k < DIRECTIONS; ++k) {   /* a Fibonacci sphere */
        const float z = 1.0f - 2.0f * (k + 0.5f) / DIRECTIONS, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.39996323f * k;
        ps->dirs[k * 3] = r * cosf(phi); ps->dirs[k * 3 + 1] = z; ps->dirs[k * 3 + 2] = r * sinf(phi);
    }
    ps->lights = lights;
    ps->light_count = light_count < MAX_CHANNELS - 2 ? light_count : MAX_CHANNELS - 2;
    /* Emitting triangles, sampled by area times brightness at fixed stratified points. */
    double total = 0;
    for (size_t t = 0; m->emission && t < m->triangle_count; ++t) total += emitter_weight(m, t, NULL);
    if (total > 0) {
        double acc = 0;
        int next = 0;
        for (size_t t = 0; t < m->triangle_count && next < EMITTER_SAMPLES; ++t) {
            const uint32_t *ix = m->indices + t * 3;
            float e1[3], e2[3], cr[3];
            const double w = emitter_weight(m, t, cr);
            if (!(w > 0)) continue;
            prt__v3_sub(m->positions + ix[1] * 3, m->positions + ix[0] * 3, e1);
            prt__v3_sub(m->positions + ix[2] * 3, m->positions + ix[0] * 3, e2);
            acc += w;
            while (next < EMITTER_SAMPLES && (next + 0.5) / EMITTER_SAMPLES * total <= acc) {
                /* A point of the triangle from the R2 sequence, folded into it. */
                float u = fmodf(0.5f + 0.7548777f * next, 1.0f), v = fmodf(0.5f + 0.5698403f * next, 1.0f);
                if (u + v > 1) { u = 1 - u; v = 1 - v; }
                emitter_sample *s = &ps->emitters[next++];
                for (int c = 0; c < 3; ++c) s->p[c] = m->positions[ix[0] * 3 + c] + u * e1[c] + v * e2[c];
                memcpy(s->n, cr, sizeof cr);
                prt__v3_normalize(s->n);
                for (int c = 0; c < 3; ++c) s->p[c] += s->n[c] * ps->offset;   /* off its own surface */
            }
        }
        ps->emitter_count = next;
    }
    ps->channels = 1 + (ps->emitter_count > 0) + ps->light_count;
}

/* ---- edges ----------------------------------------------------------------------------------- */

typedef struct u64_map {
    uint64_t *keys;    /* key + 1; 0 = empty */
    uint32_t *values;
    size_t cap, count;
} u64_map;

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 33; x *= 0xff51afd7ed558ccdULL; x ^= x >> 33; x *= 0xc4ceb9fe1a85ec53ULL; x ^= x >> 33;
    return x;
}

static bool map_init(u64_map *m, size_t expected)
{
    m->cap = 16;
    while (m->cap < expected * 2) m->cap <<= 1;
    m->count = 0;
    m->keys = prt__calloc(m->cap, sizeof *m->keys);
    m->values = prt__calloc(m->cap, sizeof *m->values);
    return m->keys && m->values;
}

static void map_free(u64_map *m) { free(m->keys); free(m->values); memset(m, 0, sizeof *m); }

/* The slot of key (inserted with value `fresh` when absent). The map never fills: callers size it
 * for every key they insert. */
static uint32_t map_get(u64_map *m, uint64_t key, uint32_t fresh, bool *found)
{
    size_t i = mix64(key) & (m->cap - 1);
    while (m->keys[i] && m->keys[i] != key + 1) i = (i + 1) & (m->cap - 1);
    *found = m->keys[i] != 0;
    if (!*found) { m->keys[i] = key + 1; m->values[i] = fresh; m->count++; }
    return m->values[i];
}

/* The value of key, or `missing`. */
static uint32_t map_find(const u64_map *m, uint64_t key, uint32_t missing)
{
    size_t i = mix64(key) & (m->cap - 1);
    while (m->keys[i] && m->keys[i] != key + 1) i = (i + 1) & (m->cap - 1);
    return m->keys[i] ? m->values[i] : missing;
}

static uint64_t edge_key(uint32_t a, uint32_t b) { return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a; }

/* One edge of the current mesh. */
typedef struct edge {
    uint32_t a, b;        /* vertex ids, a < b */
    uint32_t weld;        /* index of its welded edge (crease duplicates share one) */
    uint32_t tri;         /* a triangle it belongs to (for the probe origin) */
    uint32_t mid;         /* row of its midpoint probe in `mid_values`, UINT32_MAX before it is taken */
    float length;
} edge;

typedef struct refiner {
    const prt_context *ctx;
    prt__mesh *m;
    probe_set ps;
    float threshold, min_edge;
    uint32_t *weld;                 /* per vertex: the first vertex at its exact position */
    float *values;                  /* per vertex probe, `channels` each */
    size_t values_cap;
    float *tri_worst;               /* per triangle: how far its inside is from its corners; < 0 = not probed */
    /* Midpoint probes survive across levels, keyed by the edge's vertex ids. */
    u64_map mid_index;
    float *mid_values;
    size_t mid_count, mid_cap;
    size_t probes;
    prt__progress progress;
    char stage[48];
} refiner;

static uint32_t weld_of(const refiner *r, uint32_t v) { return r->weld[v]; }

/* Canonical vertex per exact position, so crease duplicates decide together. */
static prt_status build_weld(refiner *r)
{
    const prt__mesh *m = r->m;
    free(r->weld);
    r->weld = malloc(m->vertex_count * sizeof *r->weld + 1);
    u64_map pos = {0};
    if (!r->weld || !map_init(&pos, m->vertex_count)) { map_free(&pos); return PRT_ERR_NO_MEMORY; }
    for (size_t v = 0; v < m->vertex_count; ++v) {
        uint32_t bits[3];
        memcpy(bits, m->positions + v * 3, sizeof bits);
        /* A hash of the position as the key, then an exact check against the found vertex; on a
         * rare collision the vertex stands alone (it decides for itself, as without welding). */
        const uint64_t key = mix64((uint64_t)bits[0] << 32 ^ bits[1]) ^ mix64(bits[2] + 0x9E3779B97F4A7C15ull);
        bool found;
        const uint32_t first = map_get(&pos, key & 0x7fffffffffffffffull, (uint32_t)v, &found);
        r->weld[v] = found && !memcmp(m->positions + (size_t)first * 3, m->positions + v * 3, 3 * sizeof(float)) ? first : (uint32_t)v;
    }
    map_free(&pos);
    return PRT_OK;
}

static const float *mid_row(const refiner *r, uint32_t row) { return r->mid_values + (size_t)row * r->ps.channels; }

/* ---- marking --------------------------------------------------------------------------------- */

/* Longest-edge order with a tie-break on welded ids, the same on both sides of a crease. */
static bool longer(const edge *e, const edge *f)
{
    if (e->length != f->length) return e->length > f->length;
    return e->weld > f->weld;
}

typedef struct candidate { float score; uint32_t weld; } candidate;

static int by_score(const void *pa, const void *pb)
{
    const candidate *a = pa, *b = pb;
    if (a->score != b->score) return a->score > b->score ? -1 : 1;
    return a->weld < b->weld ? -1 : a->weld > b->weld;
}

/* Marks the first `take` candidates, then closes the marking (a triangle with a marked edge gets
 * its longest marked); returns how many new vertices splitting would make. */
static size_t close_marks(const edge *edges, size_t ne, const uint32_t *tri_edges, size_t nt, const candidate *cand, size_t take,
                          uint8_t *welded_mark, size_t nw)
{
    memset(welded_mark, 0, nw);
    for (size_t i = 0; i < take; ++i) welded_mark[cand[i].weld] = 1;
    for (bool changed = true; changed;) {
        changed = false;
        for (size_t t = 0; t < nt; ++t) {
            const uint32_t *te = tri_edges + t * 3;
            if (!welded_mark[edges[te[0]].weld] && !welded_mark[edges[te[1]].weld] && !welded_mark[edges[te[2]].weld]) continue;
            const uint32_t l = longer(&edges[te[0]], &edges[te[1]]) ? (longer(&edges[te[0]], &edges[te[2]]) ? te[0] : te[2])
                                                                    : (longer(&edges[te[1]], &edges[te[2]]) ? te[1] : te[2]);
            if (!welded_mark[edges[l].weld]) { welded_mark[edges[l].weld] = 1; changed = true; }
        }
    }
    size_t n = 0;
    for (size_t e = 0; e < ne; ++e) n += welded_mark[edges[e].weld];
    return n;
}

/* ---- splitting ------------------------------------------------------------------------------- */

static bool reserve(refiner *r, size_t max_v)
{
    prt__mesh *m = r->m;
    if (!prt__mesh_reserve(m, max_v)) return false;
    if (max_v > r->values_cap) {
        float *v = realloc(r->values, max_v * r->ps.channels * sizeof(float));
        if (!v) return false;
        r->values = v;
        r->values_cap = max_v;
    }
    return true;
}


/* ---- one level ------------------------------------------------------------------------------- */

typedef struct level {
    edge *edges;
    size_t ne, nw;              /* edges, welded edges */
    uint32_t *tri_edges;        /* 3 per triangle: edge (v[k], v[k + 1]) */
    float *score;               /* per welded edge: how badly it needs splitting; 0 = not at all */
} level;

static void level_free(level *l) { free(l->edges); free(l->tri_edges); free(l->score); memset(l, 0, sizeof *l); }

static void centroid(const prt__mesh *m, size_t t, float out[3])
{
    const uint32_t *ix = m->indices + t * 3;
    for (int c = 0; c < 3; ++c) out[c] = (m->positions[ix[0] * 3 + c] + m->positions[ix[1] * 3 + c] + m->positions[ix[2] * 3 + c]) / 3.0f;
}

/* The edges of the current mesh, welded across creases. */
static prt_status build_edges(refiner *r, level *l)
{
    const prt__mesh *m = r->m;
    const size_t nt = m->triangle_count;
    u64_map em = {0}, wm = {0};
    l->edges = malloc(nt * 3 * sizeof *l->edges + 1);
    l->tri_edges = malloc(nt * 3 * sizeof *l->tri_edges + 1);
    /* Sized for every edge distinct (a triangle soup): the load stays at most one half. */
    if (!l->edges || !l->tri_edges || !map_init(&em, nt * 3 + 16) || !map_init(&wm, nt * 3 + 16)) {
        map_free(&em); map_free(&wm);
        return PRT_ERR_NO_MEMORY;
    }
    l->ne = l->nw = 0;
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m->indices[t * 3 + k], b = m->indices[t * 3 + (k + 1) % 3];
            bool found;
            const uint32_t e = map_get(&em, edge_key(a, b), (uint32_t)l->ne, &found);
            l->tri_edges[t * 3 + k] = e;
            if (found) continue;
            edge *ed = &l->edges[l->ne++];
            ed->a = a < b ? a : b;
            ed->b = a < b ? b : a;
            ed->tri = (uint32_t)t;
            float d[3];
            prt__v3_sub(m->positions + a * 3, m->positions + b * 3, d);
            ed->length = prt__v3_len(d);
            ed->weld = map_get(&wm, edge_key(weld_of(r, a), weld_of(r, b)), (uint32_t)l->nw, &found);
            if (!found) l->nw++;
            ed->mid = map_find(&r->mid_index, edge_key(a, b), UINT32_MAX);
        }
    map_free(&em);
    map_free(&wm);
    l->score = prt__calloc(l->nw + 1, sizeof *l->score);
    return l->score ? PRT_OK : PRT_ERR_NO_MEMORY;
}

static bool splittable(const refiner *r, const edge *e) { return e->length > 2.0f * r->min_edge; }

/* Probes the midpoints of splittable edges that have none yet. */
static prt_status probe_midpoints(refiner *r, level *l)
{
    prt__mesh *m = r->m;
    const int ch = r->ps.channels;
    size_t need = 0;
    for (size_t e = 0; e < l->ne; ++e) need += l->edges[e].mid == UINT32_MAX && splittable(r, &l->edges[e]);
    if (r->mid_count + need > r->mid_cap) {
        const size_t cap = (r->mid_count + need) * 3 / 2 + 64;
        float *v = realloc(r->mid_values, cap * ch * sizeof(float));
        if (!v) return PRT_ERR_NO_MEMORY;
        r->mid_values = v;
        r->mid_cap = cap;
    }
    /* The map of rows must hold every edge that will ever be probed: grow it by rebuilding. */
    if ((r->mid_index.count + need) * 2 > r->mid_index.cap) {
        u64_map bigger;
        if (!map_init(&bigger, (r->mid_index.count + need) * 2)) { map_free(&bigger); return PRT_ERR_NO_MEMORY; }
        for (size_t i = 0; i < r->mid_index.cap; ++i)
            if (r->mid_index.keys[i]) {
                bool found;
                map_get(&bigger, r->mid_index.keys[i] - 1, r->mid_index.values[i], &found);
            }
        map_free(&r->mid_index);
        r->mid_index = bigger;
    }
    uint32_t *pending = malloc(need * sizeof *pending + 1);
    if (!pending) return PRT_ERR_NO_MEMORY;
    size_t n = 0;
    for (size_t e = 0; e < l->ne; ++e) {
        edge *ed = &l->edges[e];
        if (ed->mid != UINT32_MAX || !splittable(r, ed)) continue;
        ed->mid = (uint32_t)(r->mid_count + n);
        bool found;
        map_get(&r->mid_index, edge_key(ed->a, ed->b), ed->mid, &found);
        pending[n++] = (uint32_t)e;
    }
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(r->ctx))
    for (size_t i = 0; i < n; ++i) {
        if (prt__progress_add(&r->progress, 1)) continue;
        const edge *ed = &l->edges[pending[i]];
        float p[3], nrm[3], cen[3], o[3];
        for (int c = 0; c < 3; ++c) {
            p[c] = 0.5f * (m->positions[ed->a * 3 + c] + m->positions[ed->b * 3 + c]);
            nrm[c] = m->normals[ed->a * 3 + c] + m->normals[ed->b * 3 + c];
        }
        if (!prt__v3_normalize(nrm)) memcpy(nrm, m->normals + ed->a * 3, sizeof nrm);
        centroid(m, ed->tri, cen);
        probe_origin(&r->ps, p, nrm, cen, o);
        probe(&r->ps, o, nrm, r->mid_values + (size_t)ed->mid * ch);
    }
    free(pending);
    r->mid_count += n;
    r->probes += n;
    return PRT_OK;
}

/* Scores edges whose ends, or whose midpoint and ends, disagree. */
static void score_edges(const refiner *r, level *l)
{
    const int ch = r->ps.channels;
    for (size_t e = 0; e < l->ne; ++e) {
        const edge *ed = &l->edges[e];
        if (!splittable(r, ed)) continue;
        const float *va = r->values + (size_t)ed->a * ch, *vb = r->values + (size_t)ed->b * ch, *vm = mid_row(r, ed->mid);
        float mean[MAX_CHANNELS];
        for (int c = 0; c < ch; ++c) mean[c] = 0.5f * (va[c] + vb[c]);
        /* A gradient is what interpolation draws well: ends that differ count at half weight, a
         * midpoint off the line between them in full. */
        const float d = fmaxf(0.5f * difference(va, vb, ch), difference(vm, mean, ch));
        if (d > r->threshold && d * ed->length * ed->length > l->score[ed->weld]) l->score[ed->weld] = d * ed->length * ed->length;
    }
}

/* Probes the inside of triangles not yet known to agree with their corners: more points in
 * bigger triangles, so that a shadow falling wholly inside a big floor triangle is found. */
static void score_triangles(refiner *r, level *l, float spacing)
{
    prt__mesh *m = r->m;
    const int ch = r->ps.channels;
    const size_t nt = m->triangle_count;
    float *worst = prt__calloc(nt + 1, sizeof *worst);
    if (!worst) return;   /* the edges alone still refine */
    size_t probes = 0;
#pragma omp parallel for schedule(dynamic, 32) reduction(+ : probes) num_threads(prt__threads(r->ctx))
    for (size_t t = 0; t < nt; ++t) {
        if (r->tri_worst[t] >= 0) { worst[t] = r->tri_worst[t]; continue; }   /* unchanged since it was probed */
        if (prt__progress_add(&r->progress, 1)) continue;
        const uint32_t *te = l->tri_edges + t * 3, *ix = m->indices + t * 3;
        if (!splittable(r, &l->edges[te[0]]) && !splittable(r, &l->edges[te[1]]) && !splittable(r, &l->edges[te[2]])) {
            r->tri_worst[t] = 0;   /* too small to split, whatever it holds */
            continue;
        }
        float e1[3], e2[3], cr[3], cen[3];
        prt__v3_sub(m->positions + ix[1] * 3, m->positions + ix[0] * 3, e1);
        prt__v3_sub(m->positions + ix[2] * 3, m->positions + ix[0] * 3, e2);
        prt__v3_cross(e1, e2, cr);
        const float area = 0.5f * prt__v3_len(cr);
        int k = (int)ceilf(area / (spacing * spacing));
        k = k < 1 ? 1 : k > 16 ? 16 : k;
        centroid(m, t, cen);
        float d = 0;
        for (int s = 0; s < k; ++s) {
            float u = 1.0f / 3, v = 1.0f / 3;
            if (s) {   /* the R2 sequence folded into the triangle */
                u = fmodf(0.5f + 0.7548777f * s, 1.0f); v = fmodf(0.5f + 0.5698403f * s, 1.0f);
                if (u + v > 1) { u = 1 - u; v = 1 - v; }
            }
            const float w[3] = {1 - u - v, u, v};
            float p[3] = {0, 0, 0}, nrm[3] = {0, 0, 0}, expect[MAX_CHANNELS], got[MAX_CHANNELS], o[3];
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < 3; ++j) { p[c] += w[j] * m->positions[ix[j] * 3 + c]; nrm[c] += w[j] * m->normals[ix[j] * 3 + c]; }
            if (!prt__v3_normalize(nrm)) continue;
            for (int c = 0; c < ch; ++c)
                expect[c] = w[0] * r->values[(size_t)ix[0] * ch + c] + w[1] * r->values[(size_t)ix[1] * ch + c] + w[2] * r->values[(size_t)ix[2] * ch + c];
            probe_origin(&r->ps, p, nrm, cen, o);
            probe(&r->ps, o, nrm, got);
            probes++;
            d = fmaxf(d, difference(got, expect, ch));
        }
        worst[t] = d;
        r->tri_worst[t] = d;
    }
    r->probes += probes;
    for (size_t t = 0; t < nt; ++t) {
        if (!(worst[t] > r->threshold)) continue;
        const uint32_t *te = l->tri_edges + t * 3;
        for (int k = 0; k < 3; ++k) {
            const edge *ed = &l->edges[te[k]];
            if (splittable(r, ed) && worst[t] * ed->length * ed->length > l->score[ed->weld]) l->score[ed->weld] = worst[t] * ed->length * ed->length;
        }
    }
    free(worst);
}

/* Splits every edge whose welded edge is marked; returns the new vertex count. */
static prt_status split(refiner *r, level *l, const uint8_t *marked, size_t new_vertices)
{
    prt__mesh *m = r->m;
    const int ch = r->ps.channels;
    const size_t nt = m->triangle_count;
    uint32_t *mid = malloc(l->ne * sizeof *mid + 1), *out = malloc(nt * 4 * 3 * sizeof *out + 1);
    float *worst = malloc(nt * 4 * sizeof *worst + 1);
    if (!mid || !out || !worst || !reserve(r, m->vertex_count + new_vertices)) { free(mid); free(out); free(worst); return PRT_ERR_NO_MEMORY; }
    for (size_t e = 0; e < l->ne; ++e) {
        const edge *ed = &l->edges[e];
        mid[e] = UINT32_MAX;
        if (!marked[ed->weld]) continue;
        mid[e] = prt__mesh_midpoint(m, ed->a, ed->b);
        float *out_v = r->values + (size_t)mid[e] * ch;
        if (ed->mid != UINT32_MAX) memcpy(out_v, mid_row(r, ed->mid), ch * sizeof(float));
        else for (int c = 0; c < ch; ++c) out_v[c] = 0.5f * (r->values[(size_t)ed->a * ch + c] + r->values[(size_t)ed->b * ch + c]);
    }
    size_t n = 0;
#define EMIT(x, y, z, keep) (out[n * 3] = (x), out[n * 3 + 1] = (y), out[n * 3 + 2] = (z), worst[n] = (keep), n++)
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t *v = m->indices + t * 3, *te = l->tri_edges + t * 3;
        int longest = 0;
        for (int k = 1; k < 3; ++k)
            if (longer(&l->edges[te[k]], &l->edges[te[longest]])) longest = k;
        if (mid[te[longest]] == UINT32_MAX) {   /* closure: no marked edge at all */
            EMIT(v[0], v[1], v[2], r->tri_worst[t]);
            continue;
        }
        /* Bisect the longest edge (a, b) towards c, then each half along its other marked edge. */
        const uint32_t a = v[longest], b = v[(longest + 1) % 3], c = v[(longest + 2) % 3];
        const uint32_t mab = mid[te[longest]], mbc = mid[te[(longest + 1) % 3]], mca = mid[te[(longest + 2) % 3]];
        if (mca == UINT32_MAX) {
            EMIT(a, mab, c, -1);
        } else {
            EMIT(a, mab, mca, -1);
            EMIT(mab, c, mca, -1);
        }
        if (mbc == UINT32_MAX) {
            EMIT(mab, b, c, -1);
        } else {
            EMIT(mab, b, mbc, -1);
            EMIT(mab, mbc, c, -1);
        }
    }
#undef EMIT
    free(mid);
    free(m->indices);
    m->indices = out;
    m->triangle_count = n;
    free(r->tri_worst);
    r->tri_worst = worst;
    return PRT_OK;
}

/* ---- the driver ------------------------------------------------------------------------------ */

static void probe_vertices(refiner *r, size_t first)
{
    prt__mesh *m = r->m;
    const int ch = r->ps.channels;
    /* One triangle per vertex, for the origin's nudge towards its centroid. */
    uint32_t *tri = malloc((m->vertex_count - first) * sizeof *tri + 1);
    if (tri)
        for (size_t t = 0; t < m->triangle_count; ++t)
            for (int k = 0; k < 3; ++k)
                if (m->indices[t * 3 + k] >= first) tri[m->indices[t * 3 + k] - first] = (uint32_t)t;
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(r->ctx))
    for (size_t v = first; v < m->vertex_count; ++v) {
        if (prt__progress_add(&r->progress, 1)) continue;
        float cen[3], o[3];
        if (tri) centroid(m, tri[v - first], cen);
        else memcpy(cen, m->positions + v * 3, sizeof cen);
        probe_origin(&r->ps, m->positions + v * 3, m->normals + v * 3, cen, o);
        probe(&r->ps, o, m->normals + v * 3, r->values + v * ch);
    }
    r->probes += m->vertex_count - first;
    free(tri);
}

static void refiner_free(refiner *r)
{
    free(r->weld);
    free(r->values);
    free(r->tri_worst);
    map_free(&r->mid_index);
    free(r->mid_values);
}

prt_status prt__mesh_refine(const prt_context *ctx, prt__mesh *m, const prt_light *lights, int light_count,
                            const prt_refine_desc *desc, prt_refine_stats *stats)
{
    prt_refine_desc d = desc ? *desc : (prt_refine_desc){0};
    if (!(d.threshold >= 0 && d.threshold < 1)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "refinement threshold must lie in [0, 1) (got %g)", d.threshold);
    if (!(d.min_edge >= 0) || !isfinite(d.min_edge)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "minimum edge length must be finite and >= 0 (got %g)", d.min_edge);
    if (d.max_levels < 0 || d.max_levels > 20) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "refinement levels must be 0..20 (got %d)", d.max_levels);
    size_t budget = d.max_new_vertices;
    if (!budget) {   /* as many as the mesh has, at least DEFAULT_BUDGET, within the limits */
        budget = m->vertex_count > DEFAULT_BUDGET ? m->vertex_count : DEFAULT_BUDGET;
        if (budget > PRT__MAX_REFINE_VERTICES) budget = PRT__MAX_REFINE_VERTICES;
        if (m->vertex_count + budget > UINT32_MAX) budget = UINT32_MAX - m->vertex_count;
    }
    if (budget > PRT__MAX_REFINE_VERTICES || m->vertex_count + budget > UINT32_MAX)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a refinement budget of %zu vertices is over the limit of %u", budget, PRT__MAX_REFINE_VERTICES);
    const float diag = 1e4f * prt__ray_offset(m);
    refiner r = {.ctx = ctx, .m = m, .threshold = d.threshold > 0 ? d.threshold : 0.1f, .min_edge = d.min_edge};
    if (!(r.min_edge > 0)) {
        /* The budget sets the finest scale worth splitting: a quarter of the edge length the
         * surface would have with every vertex (those there and those allowed) spread evenly.
         * Below it, a scene's fine carvings would spend the budget that its floors need. */
        double area = 0;
        for (size_t t = 0; t < m->triangle_count; ++t) {
            const uint32_t *ix = m->indices + t * 3;
            float e1[3], e2[3], cr[3];
            prt__v3_sub(m->positions + ix[1] * 3, m->positions + ix[0] * 3, e1);
            prt__v3_sub(m->positions + ix[2] * 3, m->positions + ix[0] * 3, e2);
            prt__v3_cross(e1, e2, cr);
            area += 0.5 * prt__v3_len(cr);
        }
        const double even = sqrt(4.0 / sqrt(3.0) * area / (double)(m->vertex_count + budget) * 0.5);
        r.min_edge = fmaxf(diag / 2000, (float)(even / 8));
    }
    const int levels = d.max_levels ? d.max_levels : MAX_LEVELS_DEFAULT;
    prt_refine_stats s = {0};
    prt__raycaster rc = {0};
    prt_status st = prt__raycaster_create(ctx, m, &rc);
    if (st) return st;
    /* Midpoints lie on the triangles they split: the surface, and so the ray caster, never change. */
    setup_probe(&r.ps, &rc, m, lights, light_count);
    r.tri_worst = malloc(m->triangle_count * sizeof *r.tri_worst + 1);
    if (r.tri_worst)
        for (size_t t = 0; t < m->triangle_count; ++t) r.tri_worst[t] = -1;
    if (!r.tri_worst || !reserve(&r, m->vertex_count) || !map_init(&r.mid_index, m->triangle_count * 2 + 16)) st = PRT_ERR_NO_MEMORY;
    r.progress = (prt__progress){.fn = d.progress, .user = d.progress_user, .ctx = ctx};
    if (!st) {
        prt__progress_begin(&r.progress, "refine: vertices", m->vertex_count);
        probe_vertices(&r, 0);
        prt__progress_end(&r.progress);
    }
    const size_t start_vertices = m->vertex_count;
    for (int lv = 0; !st && lv < levels; ++lv) {
        if (prt__progress_cancelled(&r.progress)) break;
        level l = {0};
        st = build_weld(&r);
        if (!st) st = build_edges(&r, &l);
        if (st) { level_free(&l); break; }
        size_t work = 0;
        for (size_t e = 0; e < l.ne; ++e) work += l.edges[e].mid == UINT32_MAX && splittable(&r, &l.edges[e]);
        for (size_t t = 0; t < m->triangle_count; ++t) work += r.tri_worst[t] < 0;
        snprintf(r.stage, sizeof r.stage, "refine: level %d", lv + 1);
        prt__progress_begin(&r.progress, r.stage, work);
        st = probe_midpoints(&r, &l);
        if (!st) score_edges(&r, &l);
        if (!st) score_triangles(&r, &l, diag / 50);
        prt__progress_end(&r.progress);
        if (!st && prt__progress_cancelled(&r.progress)) st = PRT_ERR_CANCELLED;
        if (st) { level_free(&l); break; }
        size_t nc = 0;
        for (size_t w = 0; w < l.nw; ++w) nc += l.score[w] > 0;
        candidate *cand = malloc(nc * sizeof *cand + 1);
        uint8_t *marked = malloc(l.nw + 1);
        if (!cand || !marked) { free(cand); free(marked); level_free(&l); st = PRT_ERR_NO_MEMORY; break; }
        nc = 0;
        for (size_t w = 0; w < l.nw; ++w)
            if (l.score[w] > 0) cand[nc++] = (candidate){l.score[w], (uint32_t)w};
        qsort(cand, nc, sizeof *cand, by_score);
        if (lv == 0) s.marked_edges = nc;
        /* As many of the worst edges (the difference times the edge's length squared: how much
         * surface shows it) as the budget allows after closure; a level spends at most half of
         * what is left, so that big triangles split again at later levels get their share. */
        const size_t remaining = budget - (m->vertex_count - start_vertices);
        const size_t left = remaining / 2 >= 1000 ? remaining / 2 : remaining;
        bool limited = false;
        size_t take = nc, added = close_marks(l.edges, l.ne, l.tri_edges, m->triangle_count, cand, take, marked, l.nw);
        if (added > left) {
            size_t lo = 0, hi = nc;   /* lo fits, hi does not */
            while (hi - lo > 1) {
                const size_t midp = lo + (hi - lo) / 2;
                if (close_marks(l.edges, l.ne, l.tri_edges, m->triangle_count, cand, midp, marked, l.nw) <= left) lo = midp;
                else hi = midp;
            }
            take = lo;
            added = close_marks(l.edges, l.ne, l.tri_edges, m->triangle_count, cand, take, marked, l.nw);
            limited = true;
        }
        if (take > 0 && added > 0) {
            const size_t before = m->vertex_count;
            st = split(&r, &l, marked, added);
            if (!st) {   /* new vertices carry their midpoint probes */
                s.levels = lv + 1;
                prt__log(ctx, PRT_LOG_INFO, "refinement level %d: %zu edges differ, %zu split, %zu vertices added", lv + 1, nc,
                         added, m->vertex_count - before);
            }
        }
        free(cand);
        free(marked);
        level_free(&l);
        s.budget_spent = limited;
        if (take == 0 || added == 0 || (limited && left == remaining)) break;
    }
    if (!st && prt__progress_cancelled(&r.progress)) st = PRT_ERR_CANCELLED;
    if (st == PRT_ERR_NO_MEMORY) prt__fail(ctx, st, "out of memory refining the mesh");
    else if (st == PRT_ERR_CANCELLED) prt__fail(ctx, st, "refinement cancelled");
    s.new_vertices = m->vertex_count - start_vertices;
    s.triangles = m->triangle_count;
    s.probes = r.probes;
    refiner_free(&r);
    prt__raycaster_release(&rc);
    if (stats) *stats = s;
    return st;
}

/* Whether triangle t spans an edge its corners cannot resolve, probing everything afresh. */
static bool triangle_needs_refinement(const refiner *r, size_t t, float spacing)
{
    const prt__mesh *m = r->m;
    const int ch = r->ps.channels;
    const uint32_t *ix = m->indices + t * 3;
    float cen[3], vals[3][MAX_CHANNELS];
    centroid(m, t, cen);
    for (int k = 0; k < 3; ++k) {
        float o[3];
        probe_origin(&r->ps, m->positions + ix[k] * 3, m->normals + ix[k] * 3, cen, o);
        probe(&r->ps, o, m->normals + ix[k] * 3, vals[k]);
    }
    float e1[3], e2[3], cr[3];
    prt__v3_sub(m->positions + ix[1] * 3, m->positions + ix[0] * 3, e1);
    prt__v3_sub(m->positions + ix[2] * 3, m->positions + ix[0] * 3, e2);
    prt__v3_cross(e1, e2, cr);
    int k = (int)ceilf(0.5f * prt__v3_len(cr) / (spacing * spacing));
    k = k < 1 ? 1 : k > 16 ? 16 : k;
    for (int s = -3; s < k; ++s) {   /* the three edge midpoints, then points inside */
        float w[3];
        if (s < 0) {
            w[0] = w[1] = w[2] = 0.5f;
            w[s + 3] = 0;
        } else {
            float u = 1.0f / 3, v = 1.0f / 3;
            if (s) {
                u = fmodf(0.5f + 0.7548777f * s, 1.0f); v = fmodf(0.5f + 0.5698403f * s, 1.0f);
                if (u + v > 1) { u = 1 - u; v = 1 - v; }
            }
            w[0] = 1 - u - v; w[1] = u; w[2] = v;
        }
        float p[3] = {0, 0, 0}, nrm[3] = {0, 0, 0}, expect[MAX_CHANNELS], got[MAX_CHANNELS], o[3];
        for (int c = 0; c < 3; ++c)
            for (int j = 0; j < 3; ++j) { p[c] += w[j] * m->positions[ix[j] * 3 + c]; nrm[c] += w[j] * m->normals[ix[j] * 3 + c]; }
        if (!prt__v3_normalize(nrm)) continue;
        for (int c = 0; c < ch; ++c) expect[c] = w[0] * vals[0][c] + w[1] * vals[1][c] + w[2] * vals[2][c];
        probe_origin(&r->ps, p, nrm, cen, o);
        probe(&r->ps, o, nrm, got);
        if (difference(got, expect, ch) > r->threshold) return true;
    }
    return difference(vals[0], vals[1], ch) > 2 * r->threshold || difference(vals[1], vals[2], ch) > 2 * r->threshold ||
           difference(vals[2], vals[0], ch) > 2 * r->threshold;
}

#define ESTIMATE_SAMPLES 2000

prt_status prt__mesh_refine_estimate(const prt_context *ctx, const prt__mesh *m, const prt_light *lights, int light_count,
                                     const prt_refine_desc *desc, prt_refine_stats *stats)
{
    prt_refine_desc d = desc ? *desc : (prt_refine_desc){0};
    if (!(d.threshold >= 0 && d.threshold < 1)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "refinement threshold must lie in [0, 1) (got %g)", d.threshold);
    const float diag = 1e4f * prt__ray_offset(m);
    refiner r = {.ctx = ctx, .m = (prt__mesh *)m, .threshold = d.threshold > 0 ? d.threshold : 0.1f};
    prt__raycaster rc = {0};
    prt_status st = prt__raycaster_create(ctx, m, &rc);
    if (st) return st;
    setup_probe(&r.ps, &rc, m, lights, light_count);
    /* Evenly spread triangles (a fixed stride, so the answer is the same every run). */
    const size_t nt = m->triangle_count, samples = nt < ESTIMATE_SAMPLES ? nt : ESTIMATE_SAMPLES;
    size_t needs = 0;
    int stop = 0;   /* a sample sends up to 19 probes of many rays each (more with many lights) */
#pragma omp parallel for schedule(dynamic, 8) reduction(+ : needs) num_threads(prt__threads(ctx))
    for (size_t i = 0; i < samples; ++i) {
        if (prt__cancel_poll(ctx, &stop, i, 0)) continue;
        needs += triangle_needs_refinement(&r, (size_t)((double)i * nt / samples), diag / 50);
    }
    prt__raycaster_release(&rc);
    prt_refine_stats s = {0};
    s.marked_triangles = samples ? (size_t)llround((double)needs * nt / samples) : 0;
    s.triangles = nt;
    s.probes = samples;
    if (stats) *stats = s;
    return stop || prt__cancelled(ctx) ? prt__fail(ctx, PRT_ERR_CANCELLED, "refinement estimate cancelled") : PRT_OK;
}
