/* The ambient-occlusion bake: per vertex, `samples` cosine-distributed low-discrepancy rays from
 * its ray origin (geom/raycast.h), A = the share that escape. With cosine-distributed directions
 * the estimator of 1/pi * integral V cos dw is the plain mean of V, so A is an integer count over
 * the sample count and needs no weights.
 *
 * One stage, "ambient occlusion", over blocks of vertices. A vertex's directions depend only on
 * its index and the seed, so every result is the same for any thread count; vertices whose origin
 * stays buried inside geometry take their neighbours' mean in finish (deterministic from the
 * restored units, so resumed bakes agree byte for byte). */
#include "methods/ao/ao.h"
#include "geom/raycast.h"

#define BLOCK 64
#define PACKET 16

typedef struct ao_bake {
    prt__bake_job base;
    prt_transfer *t;
    prt__ao_set *s;          /* owned by t */
    prt__raycaster rc;
    float *origins;          /* [vertex][3] */
    uint8_t *status;         /* [vertex] prt__unbury_origins' verdict: 2 = buried */
} ao_bake;

/* A vertex's own scramble of the sequence, from (seed, vertex) alone (splitmix64). */
static uint32_t vertex_seed(uint32_t seed, size_t v)
{
    uint64_t z = (uint64_t)v * 0x9E3779B97F4A7C15ull + ((uint64_t)seed << 32 | 0x414F4F43u);   /* "AOOC" */
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return (uint32_t)(z ^ (z >> 31));
}

static float vertex_access(const ao_bake *b, size_t v)
{
    const prt__mesh *m = &b->t->mesh;
    const int N = b->s->samples;
    const float *n = m->normals + v * 3, *org = b->origins + v * 3;
    float tx[3], ty[3];
    prt_brdf_frame(n, tx, ty);
    const uint32_t seed = vertex_seed(b->s->seed, v);
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    float dirs[PACKET * 3];
    int idx[PACKET];
    for (int k = 0; k < PACKET; ++k) idx[k] = k;
    int free_rays = 0;
    for (int i0 = 0; i0 < N; i0 += PACKET) {
        const int lanes = N - i0 < PACKET ? N - i0 : PACKET;
        for (int k = 0; k < lanes; ++k) {
            double u1, u2;
            prt__sobol2((uint32_t)(i0 + k), seed, &u1, &u2);
            prt__cosine_dir(u1, u2, n, tx, ty, dirs + k * 3);
        }
        _Alignas(64) int valid[PACKET];
        _Alignas(64) struct RTCRay16 r;
        prt__packet_rays(&r, valid, org, dirs, idx, lanes);
        rtcOccluded16(valid, b->rc.scene, &ictx, &r);
        for (int k = 0; k < lanes; ++k) free_rays += r.tfar[k] >= 0.0f;   /* Embree sets tfar to -inf when blocked */
    }
    return (float)((double)free_rays / N);
}

static prt_status run_unit(prt__bake_job *base, uint64_t unit, int thread)
{
    (void)thread;
    ao_bake *b = (ao_bake *)base;
    const size_t nv = b->t->mesh.vertex_count;
    for (size_t v = unit * BLOCK; v < nv && v < (unit + 1) * BLOCK; ++v) b->s->access[v] = vertex_access(b, v);
    return PRT_OK;
}

/* Checkpoint records: the unit's accessibilities, 4 bytes a vertex. */
static size_t unit_vertices(const ao_bake *b, uint64_t unit, size_t *first)
{
    const size_t nv = b->t->mesh.vertex_count, v0 = unit * BLOCK;
    *first = v0;
    return v0 < nv ? (nv - v0 < BLOCK ? nv - v0 : BLOCK) : 0;
}

static void save_unit(prt__bake_job *base, uint64_t unit, prt__bytes *out)
{
    ao_bake *b = (ao_bake *)base;
    size_t first;
    const size_t n = unit_vertices(b, unit, &first);
    prt__bytes_put(out, b->s->access + first, n * sizeof(float));
}

static bool load_unit(prt__bake_job *base, uint64_t unit, const unsigned char *data, size_t size)
{
    ao_bake *b = (ao_bake *)base;
    size_t first;
    const size_t n = unit_vertices(b, unit, &first);
    if (!n || size != n * sizeof(float)) return false;
    float a[BLOCK];
    memcpy(a, data, size);
    for (size_t i = 0; i < n; ++i)
        if (!(a[i] >= 0.0f && a[i] <= 1.0f)) return false;
    memcpy(b->s->access + first, a, size);
    return true;
}

static prt_status ao_stage(prt__bake_job *base, int index, prt__stage *out)
{
    ao_bake *b = (ao_bake *)base;
    if (index > 0) return PRT_OK;   /* done */
    snprintf(out->name, sizeof out->name, "ambient occlusion");
    out->units = (b->t->mesh.vertex_count + BLOCK - 1) / BLOCK;
    out->run = run_unit;
    out->save_unit = save_unit;
    out->load_unit = load_unit;
    return PRT_OK;
}

static prt_status ao_finish(prt__bake_job *base, prt_transfer *t)
{
    ao_bake *b = (ao_bake *)base;
    return b->s->buried ? prt__fill_buried(&t->mesh, b->status, b->s->access, 1, NULL) : PRT_OK;
}

static void ao_release(prt__bake_job *base)
{
    ao_bake *b = (ao_bake *)base;
    prt__raycaster_release(&b->rc);
    free(b->origins);
    free(b->status);
    free(b);
}

prt_status prt__ao_bake_begin(prt_context *ctx, const prt__ao_bake_desc *desc, prt_transfer *t, prt__bake_job **out)
{
    prt__ao_bake_desc d = desc ? *desc : (prt__ao_bake_desc){0};
    if (!d.samples) d.samples = 256;
    if (d.samples < PRT__AO_MIN_SAMPLES || d.samples > PRT__AO_MAX_SAMPLES)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ambient occlusion samples %d out of range %d..%d", d.samples, PRT__AO_MIN_SAMPLES,
                         PRT__AO_MAX_SAMPLES);
    if (!(d.ray_offset >= 0.0f) || !isfinite(d.ray_offset)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ray offset must be >= 0");
    ao_bake *b = prt__calloc(1, sizeof *b);
    prt__ao_set *s = prt__calloc(1, sizeof *s);
    if (!b || !s) { free(b); free(s); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    b->base.stage = ao_stage;
    b->base.finish = ao_finish;
    b->base.release = ao_release;
    b->base.ctx = ctx;
    b->t = t;
    b->s = s;
    t->state = s;   /* owned by t from here on */
    const size_t nv = t->mesh.vertex_count;
    s->samples = d.samples;
    s->seed = d.seed;
    s->ray_offset = d.ray_offset > 0 ? d.ray_offset : prt__ray_offset(&t->mesh);
    s->access = prt__calloc(nv, sizeof(float));
    b->status = prt__calloc(nv, 1);
    prt_status st = !s->access || !b->status ? prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory") : PRT_OK;
    if (!st) st = prt__raycaster_create(ctx, &t->mesh, &b->rc);
    if (!st) st = prt__vertex_origins(&t->mesh, s->ray_offset, &b->origins);
    if (!st) st = prt__unbury_origins(ctx, &b->rc, &t->mesh, s->ray_offset, b->origins, b->status, PRT_LOG_INFO);
    for (size_t v = 0; !st && v < nv; ++v) s->buried += b->status[v] == 2;
    if (st) { ao_release(&b->base); return st; }
    *out = &b->base;
    return PRT_OK;
}
