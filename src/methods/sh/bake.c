/* SH PRT for diffuse surfaces (Sloan, Kautz & Snyder 2002; Kautz course notes): per vertex
 *   unshadowed   T_i = 1/pi  integral max(n.s, 0) y_i(s) ds
 *   shadowed     T_i = 1/pi  integral V(s) max(n.s, 0) y_i(s) ds
 *   bounce b     T^b_i = rho/pi integral T^{b-1}_i(q(s)) (1 - V(s)) max(n.s, 0) ds
 * estimated with one shared low-discrepancy direction set of N directions (weight 4 pi / N).
 * The glossy shadowed matrix M_ji = integral V(s) H(n.s) y_j(s) y_i(s) ds shares the rays; glossy
 * bounces live in bake_glossy.c.
 * Every vertex's result depends only on its own inputs and the fixed direction set, so the
 * result is bit-identical for any thread count and schedule. */
#include "methods/sh/bake.h"
#include "geom/uv_atlas.h"
#include "geom/raycast.h"
#include "brdf/specular.h"

#include <string.h>

#define PACKET 16

typedef prt__hit hit_entry;

typedef struct bake_job {
    const prt__mesh *mesh;
    int order, ncoeff, samples;
    uint32_t seed;
    float offset;
    float *origins;       /* [vertex][3], see prt__vertex_origins */
    uint8_t *buried;      /* [vertex] prt__unbury_origins' status: 2 = filled from neighbours */
    size_t buried_count;
    float *dirs;          /* [samples][3] */
    float *basis;         /* [samples][ncoeff] */
    prt__raycaster rc;
    bool need_hits;
    prt__hit_store hits;  /* for interreflection (set up with the visibility stage) */
    prt_specular *spec;   /* per surface (prt__specular_table); NULL when nothing is specular */
    const prt__volume *volumes;   /* the scene's media: sample rays carry their transmittance */
    int volume_count;
} bake_job;

prt_sh_bake_desc prt_sh_bake_desc_defaults(void)
{
    prt_sh_bake_desc d = {0};
    d.order = 5;
    d.samples = 1024;
    d.kinds = PRT_TRANSFER_UNSHADOWED | PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED;
    d.bounces = 3;
    return d;
}

prt_sh_bake_desc prt_bake_desc_defaults(void) { return prt_sh_bake_desc_defaults(); }

/* A rotation of its own for each vertex, from (seed, vertex) alone: Shoemake's uniform random
 * quaternion from three hashed numbers. */
static void vertex_rotation(uint32_t seed, size_t v, double R[9])
{
    uint64_t h = (uint64_t)v * 0x9E3779B97F4A7C15ull ^ ((uint64_t)seed << 32 | 0x5bd1e995u);
    double u[3];
    for (int k = 0; k < 3; ++k) {
        h ^= h >> 33; h *= 0xff51afd7ed558ccdull; h ^= h >> 33; h *= 0xc4ceb9fe1a85ec53ull; h ^= h >> 33;
        u[k] = (double)(h >> 11) * (1.0 / 9007199254740992.0);
        h += 0x9E3779B97F4A7C15ull;
    }
    const double a = sqrt(1 - u[0]), b = sqrt(u[0]);
    const double x = a * sin(2 * PRT_PI * u[1]), y = a * cos(2 * PRT_PI * u[1]), z = b * sin(2 * PRT_PI * u[2]), w = b * cos(2 * PRT_PI * u[2]);
    R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - z * w);     R[2] = 2 * (x * z + y * w);
    R[3] = 2 * (x * y + z * w);     R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - x * w);
    R[6] = 2 * (x * z - y * w);     R[7] = 2 * (y * z + x * w);     R[8] = 1 - 2 * (x * x + y * y);
}

/* Caustics: a sample ray of vertex v that met a specular surface goes on, reflected or refracted,
 * for at most this many specular turns. */
#define MAX_SPECULAR 8

/* A number in [0, 1) from (seed, vertex, sample, turn) alone, so that glass chooses between
 * reflection and refraction the same way for any thread count. */
static double specular_choice(uint32_t seed, size_t v, uint32_t sample, int turn)
{
    uint64_t h = (uint64_t)v * 0x9E3779B97F4A7C15ull ^ ((uint64_t)sample << 20 | (uint64_t)turn) ^ ((uint64_t)seed << 40);
    h ^= h >> 33; h *= 0xff51afd7ed558ccdull; h ^= h >> 33; h *= 0xc4ceb9fe1a85ec53ull; h ^= h >> 33;
    return (double)(h >> 11) * (1.0 / 9007199254740992.0);
}

/* Follows sample ray `sample` of vertex v from its first hit (prim, barycentrics bu, bv at
 * distance t along d from o), a specular surface, through its specular turns. Where it escapes,
 * the SH basis of the escape direction times the throughput and c (the receiver's cosine and the
 * sample's weight) joins caustic[] (world frame): the light the mirror or glass focuses on v.
 * Where it ends on the front of a diffuse surface, *out is that hit, its weight carrying the
 * throughput, for the bounces to gather. Returns whether *out was filled. */
static bool follow_specular(const bake_job *job, size_t v, uint32_t sample, const float o[3], const float d_in[3], float t, uint32_t prim,
                            float bu, float bv, float c, float hit_weight, float *caustic, hit_entry *out)
{
    const prt__mesh *m = job->mesh;
    float p[3], d[3] = {d_in[0], d_in[1], d_in[2]}, throughput = 1.0f;
    for (int k = 0; k < 3; ++k) p[k] = o[k] + t * d[k];
    for (int turn = 0; turn < MAX_SPECULAR; ++turn) {
        const prt_specular *sp = prt__specular_of(job->spec, m, prim);
        const uint32_t *tri = m->indices + (size_t)prim * 3;
        const float *a = m->positions + tri[0] * 3, *b = m->positions + tri[1] * 3, *cc = m->positions + tri[2] * 3;
        float e1[3], e2[3], ng[3], ns[3];
        prt__v3_sub(b, a, e1);
        prt__v3_sub(cc, a, e2);
        prt__v3_cross(e1, e2, ng);
        if (!prt__v3_normalize(ng)) return false;
        if (!sp) {   /* a diffuse surface: its front carries light to the bounces */
            if (!out || prt__v3_dot(ng, d) >= 0.0f) return false;
            *out = (hit_entry){prim, sample, bu, bv, hit_weight * throughput};
            return true;
        }
        const float w0 = 1.0f - bu - bv;
        for (int k = 0; k < 3; ++k) ns[k] = w0 * m->normals[tri[0] * 3 + k] + bu * m->normals[tri[1] * 3 + k] + bv * m->normals[tri[2] * 3 + k];
        if (!prt__v3_normalize(ns) || prt__v3_dot(ns, ng) <= 0.0f) memcpy(ns, ng, sizeof ns);
        float nd[3], weight;
        const int side = prt__specular_scatter(sp, d, ng, ns, specular_choice(job->seed, v, sample, turn), nd, &weight);
        throughput *= weight;
        if (!side || !(throughput > 0.0f)) return false;
        float org[3];
        for (int k = 0; k < 3; ++k) org[k] = p[k] + (float)side * job->offset * ng[k];
        memcpy(d, nd, sizeof d);
        prt__ray_hit h;
        if (!prt__raycaster_hit(&job->rc, org, d, &h)) {
            double dd[3] = {d[0], d[1], d[2]}, y[PRT_SH_MAX_COEFFS];
            prt_sh_eval(job->order, dd, y);
            for (int i = 0; i < job->ncoeff; ++i) caustic[i] += c * throughput * (float)y[i];
            return false;
        }
        for (int k = 0; k < 3; ++k) p[k] = org[k] + h.t * d[k];
        prim = h.prim;
        bu = h.u;
        bv = h.v;
    }
    return false;
}

/* Visibility pass for one vertex: fills the unshadowed and shadowed sums and, when needed, the
 * list of occluded directions with what they hit (kept in job->hits). Returns false when keeping
 * them fails (memory, or the scratch file of a streamed bake). */
static bool visibility_vertex(bake_job *job, size_t v, float *unsh, float *sh, float *glossy, hit_entry *scratch,
                              float *rdirs, float *noise)
{
    double sq = 0;   /* sum of squared T_00 terms: the estimate's variance, for the noise report */
    const prt__mesh *m = job->mesh;
    const float *n = m->normals + v * 3;
    /* Each vertex sees the direction set turned by its own rotation (rdirs), so that neighbours'
     * errors do not line up into streaks; sums run over the unturned basis and are turned back
     * at the end (Y(R d) is the rotated basis). Glossy matrices keep the shared set. */
    prt_sh_rotation *rot = NULL;
    const float *dirs = job->dirs;
    if (rdirs && !glossy) {
        double R[9];
        vertex_rotation(job->seed, v, R);
        if (prt_sh_rotation_create(job->order, R, &rot) == PRT_OK) {
            for (int j = 0; j < job->samples; ++j) {
                const float *d = job->dirs + (size_t)j * 3;
                for (int r = 0; r < 3; ++r) rdirs[j * 3 + r] = (float)(R[r * 3] * d[0] + R[r * 3 + 1] * d[1] + R[r * 3 + 2] * d[2]);
            }
            dirs = rdirs;
        }
    }
    const float w = (float)(4.0 * PRT_PI / job->samples) / (float)PRT_PI;   /* 4pi/N and the 1/pi of the BRDF */
    const int nc = job->ncoeff;
    const float *org = job->origins + v * 3;
    uint32_t nhits = 0;   /* scratch holds one entry per sample, so it never overflows */
    float caustic[PRT_SH_MAX_COEFFS] = {0};   /* light specular surfaces send, world frame */
    int lane_sample[PACKET];
    float lane_cos[PACKET];
    int j = 0;
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    while (j < job->samples) {
        int lanes = 0;
        for (; j < job->samples && lanes < PACKET; ++j) {
            float c = prt__v3_dot(dirs + (size_t)j * 3, n);
            if (c <= 0.0f) continue;
            lane_sample[lanes] = j;
            lane_cos[lanes] = c;
            lanes++;
        }
        if (!lanes) break;
        _Alignas(64) int valid[PACKET];   /* Embree reads the mask with aligned 512-bit loads */
        bool blocked[PACKET];
        if (job->need_hits || job->spec) {
            _Alignas(64) struct RTCRayHit16 rh;
            prt__packet_rayhits(&rh, valid, org, dirs, lane_sample, lanes);
            rtcIntersect16(valid, job->rc.scene, &ictx, &rh);
            for (int k = 0; k < lanes; ++k) {
                blocked[k] = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                if (!blocked[k]) continue;
                const float *d = dirs + (size_t)lane_sample[k] * 3;
                if (prt__specular_of(job->spec, m, rh.hit.primID[k])) {
                    /* Not shadow but a turn: the light the surface reflects or refracts this way. */
                    hit_entry e;
                    if (sh && follow_specular(job, v, (uint32_t)lane_sample[k], org, d, rh.ray.tfar[k], rh.hit.primID[k], rh.hit.u[k], rh.hit.v[k],
                                              lane_cos[k] * w, lane_cos[k] * (float)(4.0 * PRT_PI / job->samples), caustic,
                                              job->need_hits ? &e : NULL))
                        scratch[nhits++] = e;
                    continue;
                }
                if (!job->need_hits) continue;
                /* Embree's unnormalized Ng points to the side from which the triangle winds
                 * counter-clockwise, like prt's normals (the pit and colour-bleeding tests pin
                 * this). The back of a surface emits nothing: only front-face hits carry light. */
                if (rh.hit.Ng_x[k] * d[0] + rh.hit.Ng_y[k] * d[1] + rh.hit.Ng_z[k] * d[2] >= 0.0f) continue;
                const float tr = job->volume_count ? expf(-prt__volumes_optical_depth(job->volumes, job->volume_count, org, d, rh.ray.tfar[k])) : 1.0f;
                scratch[nhits++] = (hit_entry){rh.hit.primID[k], (uint32_t)lane_sample[k], rh.hit.u[k], rh.hit.v[k],
                                               tr * lane_cos[k] * (float)(4.0 * PRT_PI / job->samples)};
            }
        } else {
            _Alignas(64) struct RTCRay16 r;
            prt__packet_rays(&r, valid, org, dirs, lane_sample, lanes);
            rtcOccluded16(valid, job->rc.scene, &ictx, &r);
            for (int k = 0; k < lanes; ++k) blocked[k] = r.tfar[k] < 0.0f;
        }
        for (int k = 0; k < lanes; ++k) {
            const float *y = job->basis + (size_t)lane_sample[k] * nc;
            float c = lane_cos[k] * w;
            if (unsh)
                for (int i = 0; i < nc; ++i) unsh[i] += c * y[i];
            /* Volumes dim what reaches the vertex: the shadowed sums carry their transmittance. */
            const float tr = job->volume_count && !blocked[k] ? expf(-prt__volumes_optical_depth(job->volumes, job->volume_count, org, dirs + (size_t)lane_sample[k] * 3, INFINITY)) : 1.0f;
            if (sh && !blocked[k]) {
                c *= tr;
                for (int i = 0; i < nc; ++i) sh[i] += c * y[i];
                sq += (double)(c * y[0]) * (c * y[0]);
            } else if (!sh && unsh) {
                sq += (double)(c * y[0]) * (c * y[0]);
            }
            if (glossy && !blocked[k]) {
                const float wg = tr * (float)(4.0 * PRT_PI / job->samples);
                for (int j = 0; j < nc; ++j) {
                    float s = wg * y[j];
                    for (int i = 0; i < nc; ++i) glossy[j * nc + i] += s * y[i];
                }
            }
        }
    }
    if (noise) {
        /* Standard error of T_00 over the N directions: sqrt(sum x^2 - T^2 / N), x each term. */
        const double t00 = sh ? sh[0] : unsh ? unsh[0] : 0;
        const double var = sq - t00 * t00 / job->samples;
        *noise = var > 0 ? (float)sqrt(var) : 0.0f;
    }
    if (rot) {
        float tmp[PRT_SH_MAX_COEFFS];
        if (unsh) { memcpy(tmp, unsh, (size_t)nc * sizeof *tmp); prt_sh_rotation_apply(rot, 1, tmp, unsh); }
        if (sh) { memcpy(tmp, sh, (size_t)nc * sizeof *tmp); prt_sh_rotation_apply(rot, 1, tmp, sh); }
        prt_sh_rotation_release(rot);
    }
    for (int i = 0; sh && job->spec && i < nc; ++i) sh[i] += caustic[i];
    return !job->need_hits || prt__hits_put(&job->hits, v, v + 1, scratch, &nhits);
}

/* Interpolates a 3-channel transfer at a hit point. */
static inline __attribute__((always_inline)) void gather_hit(const prt__mesh *m, const float *prev, int nc3, const hit_entry *h, float *acc)
{
    const uint32_t *t = m->indices + (size_t)h->prim * 3;
    float b0 = (1.0f - h->u - h->v) * h->weight, b1 = h->u * h->weight, b2 = h->v * h->weight;
    const float *t0 = prev + (size_t)t[0] * nc3, *t1 = prev + (size_t)t[1] * nc3, *t2 = prev + (size_t)t[2] * nc3;
    for (int i = 0; i < nc3; ++i) acc[i] += b0 * t0[i] + b1 * t1[i] + b2 * t2[i];
}

/* The bake as stages (transfer/method.h): visibility per block of vertices, then either the
 * coupled glossy bounce loop or one stage per diffuse bounce, then texels and the BRDF. */
#define BLOCK 64

typedef enum { ST_VISIBILITY, ST_GLOSSY_BOUNCES, ST_BOUNCE, ST_SUBSURFACE, ST_NEIGHBOURHOOD, ST_TEXELS, ST_BRDF_IN, ST_COMPRESS, ST_QUANTIZE, ST_VOLUME } stage_kind;

typedef struct sh_bake {
    prt__bake_job base;
    prt_sh_bake_desc d;
    prt_transfer *t;
    prt__sh_state *s;
    bake_job job;
    float *unsh, *shad, *gshad;
    float *noise;                  /* [vertex] T_00's standard error; NaN where restored from a checkpoint */
    bool want_gsh, want_gir, coupled;
    float *total, *prev, *next;    /* diffuse bounce buffers, [vertex][3][order^2] */
    hit_entry **scratch;           /* per thread, one entry per sample */
    int nscratch;
    float **rdirs;                 /* per thread, the direction set turned for one vertex */
    int nrdirs;
    stage_kind plan[80];
    int bounce_of[80];            /* ST_BOUNCE: its number; ST_COMPRESS: the set it compresses */
    int stages;
    prt__sh_extra extra;          /* compression, quantization, the normal and height maps (owned) */
    prt__height_field height;     /* over d.height_map */
    uint8_t *medium;              /* [vertex] 0 opaque, k: translucent with kernels[k - 1]; NULL when none is */
    prt__dipole (*kernels)[3];
    prt_brdf brdf;                /* d.glossy_brdf points here */
    int compressing_set;
} sh_bake;

static uint64_t blocks(size_t nv) { return (nv + BLOCK - 1) / BLOCK; }

static prt_status run_visibility(prt__bake_job *b, uint64_t unit, int thread)
{
    sh_bake *sb = (sh_bake *)b;
    bake_job *job = &sb->job;
    const size_t nv = sb->t->mesh.vertex_count, nc = (size_t)job->ncoeff, nn = nc * nc;
    for (size_t v = unit * BLOCK; v < nv && v < (unit + 1) * BLOCK; ++v)
        if (!visibility_vertex(job, v, sb->unsh ? sb->unsh + v * nc : NULL, sb->shad ? sb->shad + v * nc : NULL, sb->gshad ? sb->gshad + v * nn : NULL,
                               job->need_hits ? sb->scratch[thread] : NULL, thread < sb->nrdirs ? sb->rdirs[thread] : NULL,
                               sb->noise ? sb->noise + v : NULL))
            return job->hits.spill ? prt__fail(b->ctx, PRT_ERR_IO, "cannot write the ray hits' scratch file (disk full?)")
                                   : prt__fail(b->ctx, PRT_ERR_NO_MEMORY, "out of memory recording ray hits");
    return PRT_OK;
}

/* One vertex's gather over its hits; nc3 known at compile time for the usual orders, so that the
 * sums stay in registers across the hits instead of going through memory at each one. */
static inline __attribute__((always_inline)) void gather_vertex(const prt__mesh *m, const float *prev, int nc3, const hit_entry *hits, uint32_t count,
                                                                float *restrict acc)
{
    float a[3 * PRT_SH_MAX_COEFFS];
    for (int i = 0; i < nc3; ++i) a[i] = 0;
    for (uint32_t h = 0; h < count; ++h) gather_hit(m, prev, nc3, &hits[h], a);
    memcpy(acc, a, (size_t)nc3 * sizeof(float));
}

static prt_status run_bounce(prt__bake_job *b, uint64_t unit, int thread)
{
    sh_bake *sb = (sh_bake *)b;
    const prt__mesh *m = &sb->t->mesh;
    const int nc = sb->job.ncoeff, nc3 = 3 * nc;
    for (size_t v = unit * BLOCK; v < m->vertex_count && v < (unit + 1) * BLOCK; ++v) {
        float acc[3 * PRT_SH_MAX_COEFFS];
        const uint32_t count = sb->job.hits.count[v];
        const hit_entry *hits = prt__hits_get(&sb->job.hits, v, sb->scratch[thread]);
        if (count && !hits) return prt__fail(b->ctx, PRT_ERR_IO, "cannot read the ray hits' scratch file");
        switch (nc3) {
        case 27: gather_vertex(m, sb->prev, 27, hits, count, acc); break;
        case 48: gather_vertex(m, sb->prev, 48, hits, count, acc); break;
        case 75: gather_vertex(m, sb->prev, 75, hits, count, acc); break;
        default: gather_vertex(m, sb->prev, nc3, hits, count, acc); break;
        }
        for (int c = 0; c < 3; ++c) {
            float k = m->albedo[v * 3 + c] / (float)PRT_PI;
            for (int i = 0; i < nc; ++i) {
                float x = k * acc[c * nc + i];
                sb->next[v * nc3 + c * nc + i] = x;
                sb->total[v * nc3 + c * nc + i] += x;
            }
        }
    }
    return PRT_OK;
}

/* Checkpoint records (transfer/checkpoint.h): a unit's rows of every array it wrote, and for
 * visibility the hit lists the bounces gather over. */
typedef struct rows { float *base; size_t per_vertex; } rows;

static int visibility_rows(const sh_bake *sb, rows r[3])
{
    const size_t nc = (size_t)sb->job.ncoeff;
    int n = 0;
    if (sb->unsh) r[n++] = (rows){sb->unsh, nc};
    if (sb->shad) r[n++] = (rows){sb->shad, nc};
    if (sb->gshad) r[n++] = (rows){sb->gshad, nc * nc};
    return n;
}

static int bounce_rows(const sh_bake *sb, rows r[3])
{
    const size_t nc3 = 3 * (size_t)sb->job.ncoeff;
    r[0] = (rows){sb->next, nc3};
    r[1] = (rows){sb->total, nc3};
    return 2;
}

static void unit_range(const sh_bake *sb, uint64_t unit, size_t *v0, size_t *v1)
{
    const size_t nv = sb->t->mesh.vertex_count;
    *v0 = unit * BLOCK;
    *v1 = *v0 + BLOCK < nv ? *v0 + BLOCK : nv;
}

static void save_rows(const rows *r, int n, size_t v0, size_t v1, prt__bytes *out)
{
    for (int i = 0; i < n; ++i) prt__bytes_put(out, r[i].base + v0 * r[i].per_vertex, (v1 - v0) * r[i].per_vertex * sizeof(float));
}

/* Reads the rows back; false (having written nothing) when the record is too short. */
static bool load_rows(const rows *r, int n, size_t v0, size_t v1, const unsigned char **data, size_t *size)
{
    size_t need = 0;
    for (int i = 0; i < n; ++i) need += (v1 - v0) * r[i].per_vertex * sizeof(float);
    if (need > *size) return false;
    for (int i = 0; i < n; ++i) {
        size_t bytes = (v1 - v0) * r[i].per_vertex * sizeof(float);
        memcpy(r[i].base + v0 * r[i].per_vertex, *data, bytes);
        *data += bytes;
        *size -= bytes;
    }
    return true;
}

static void save_visibility(prt__bake_job *b, uint64_t unit, prt__bytes *out)
{
    sh_bake *sb = (sh_bake *)b;
    rows r[3];
    size_t v0, v1;
    unit_range(sb, unit, &v0, &v1);
    save_rows(r, visibility_rows(sb, r), v0, v1, out);
    if (!sb->job.need_hits) return;
    /* A streamed bake reads them back from its scratch file: the same record either way. */
    hit_entry *buf = sb->job.hits.spill ? malloc((size_t)sb->d.samples * sizeof *buf) : NULL;
    if (sb->job.hits.spill && !buf) { out->failed = true; return; }
    for (size_t v = v0; v < v1; ++v) {
        const uint32_t n = sb->job.hits.count[v];
        const hit_entry *h = prt__hits_get(&sb->job.hits, v, buf);
        if (n && !h) { out->failed = true; break; }
        prt__bytes_put(out, &n, sizeof n);
        prt__bytes_put(out, h, n * sizeof(hit_entry));
    }
    free(buf);
}

static bool load_visibility(prt__bake_job *b, uint64_t unit, const unsigned char *data, size_t size)
{
    sh_bake *sb = (sh_bake *)b;
    const prt__mesh *m = &sb->t->mesh;
    rows r[3];
    size_t v0, v1;
    unit_range(sb, unit, &v0, &v1);
    /* Check the hit lists before anything is written: a unit is restored whole or not at all. */
    const unsigned char *p = data;
    size_t left = size, fixed = 0;
    const int n = visibility_rows(sb, r);
    for (int i = 0; i < n; ++i) fixed += (v1 - v0) * r[i].per_vertex * sizeof(float);
    if (fixed > left) return false;
    if (sb->job.need_hits) {
        const unsigned char *q = p + fixed;
        size_t rest = left - fixed;
        for (size_t v = v0; v < v1; ++v) {
            uint32_t count;
            if (rest < sizeof count) return false;
            memcpy(&count, q, sizeof count);
            q += sizeof count; rest -= sizeof count;
            if (count > (uint32_t)sb->d.samples || (size_t)count * sizeof(hit_entry) > rest) return false;
            for (uint32_t h = 0; h < count; ++h) {
                hit_entry e;
                memcpy(&e, q + (size_t)h * sizeof e, sizeof e);
                if (e.prim >= m->triangle_count || e.sample >= (uint32_t)sb->d.samples) return false;   /* the bounces index with them */
            }
            q += (size_t)count * sizeof(hit_entry); rest -= (size_t)count * sizeof(hit_entry);
        }
        if (rest) return false;
    } else if (fixed != left) {
        return false;
    }
    load_rows(r, n, v0, v1, &p, &left);
    for (size_t v = v0; sb->job.need_hits && v < v1; ++v) {
        uint32_t count;
        memcpy(&count, p, sizeof count);
        p += sizeof count;
        if (!prt__hits_put(&sb->job.hits, v, v + 1, p, &count)) return false;
        p += (size_t)count * sizeof(hit_entry);
    }
    return true;
}

static void save_bounce(prt__bake_job *b, uint64_t unit, prt__bytes *out)
{
    sh_bake *sb = (sh_bake *)b;
    rows r[3];
    size_t v0, v1;
    unit_range(sb, unit, &v0, &v1);
    save_rows(r, bounce_rows(sb, r), v0, v1, out);
}

static bool load_bounce(prt__bake_job *b, uint64_t unit, const unsigned char *data, size_t size)
{
    sh_bake *sb = (sh_bake *)b;
    rows r[3];
    size_t v0, v1;
    unit_range(sb, unit, &v0, &v1);
    const int n = bounce_rows(sb, r);
    return size == 2 * (v1 - v0) * r[0].per_vertex * sizeof(float) && load_rows(r, n, v0, v1, &data, &size);
}

static prt_status run_glossy_bounces(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    sh_bake *sb = (sh_bake *)b;
    prt_transfer *t = sb->t;
    prt__bounce_input bi = {&t->mesh, sb->d.order, sb->d.samples, sb->job.basis, &sb->job.hits, sb->shad, sb->gshad,
                            t->brdfs, t->brdf_count, sb->d.bounces, sb->want_gir, p};
    float *dtot = NULL, *gtot = NULL;
    prt_status st = prt__bake_glossy_bounces(ctx, &bi, &dtot, sb->want_gir ? &gtot : NULL);
    if (st) return st;
    if (sb->job.buried_count) {
        const size_t nc = (size_t)sb->d.order * sb->d.order;
        st = prt__fill_buried(&t->mesh, sb->job.buried, dtot, 3 * nc, NULL);
        if (!st && gtot) st = prt__fill_buried(&t->mesh, sb->job.buried, gtot, 3 * nc * nc, NULL);
        if (st) { free(dtot); free(gtot); return st; }
    }
    if (sb->d.kinds & PRT_TRANSFER_INTERREFLECTED) { sb->s->sets[2].channels = 3; sb->s->sets[2].coeffs = dtot; }
    else free(dtot);
    if (sb->want_gir) { sb->s->sets[4].channels = 3; sb->s->sets[4].coeffs = gtot; }
    return PRT_OK;
}

static prt_status run_texels(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    sh_bake *sb = (sh_bake *)b;
    prt_transfer *t = sb->t;
    prt__texel_input ti = {&t->mesh, t->source, sb->d.order, sb->d.samples, sb->job.dirs, sb->job.basis, sb->job.rc.scene, sb->job.offset,
                           sb->s->sets[2].coeffs, sb->d.kinds & 7u, sb->d.texels, sb->d.texels, sb->d.normal_map,
                           sb->d.height_map ? &sb->height : NULL, p, sb->job.volumes, sb->job.volume_count};
    return prt__bake_texels(ctx, &ti, &sb->s->texels);
}

static prt_status run_subsurface(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    sh_bake *sb = (sh_bake *)b;
    return prt__sh_subsurface(ctx, &sb->t->mesh, sb->medium, (const prt__dipole(*)[3])sb->kernels, sb->job.ncoeff, sb->s->sets[2].coeffs, p);
}

static prt_status run_neighbourhood(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    sh_bake *sb = (sh_bake *)b;
    const prt__mesh *m = &sb->t->mesh;
    prt__sh_grid *g = &sb->s->grid;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < m->vertex_count; ++v)
        for (int c = 0; c < 3; ++c) { lo[c] = fminf(lo[c], m->positions[v * 3 + c]); hi[c] = fmaxf(hi[c], m->positions[v * 3 + c]); }
    float size = 0;   /* the largest extent: a flat scene still gets room above and below */
    for (int c = 0; c < 3; ++c) size = fmaxf(size, hi[c] - lo[c]);
    if (!(size > 0)) size = 1;
    for (int c = 0; c < 3; ++c) {
        const float grow = 0.25f * size;
        g->lo[c] = lo[c] - grow;
        g->hi[c] = hi[c] + grow;
        g->dims[c] = sb->d.neighbourhood;
    }
    const float *exit = sb->s->sets[2].coeffs ? sb->s->sets[2].coeffs : sb->shad;
    return prt__sh_neighbourhood_bake(ctx, m, &sb->job.rc, sb->job.dirs, sb->job.basis, sb->d.samples, sb->d.order, exit, sb->s->sets[2].coeffs ? 3 : 1, g, p);
}

static prt_status run_volumes(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    sh_bake *sb = (sh_bake *)b;
    prt__sh_state *s = sb->s;
    const prt_scene *scene = sb->extra.scene;
    const float *exit = s->sets[2].coeffs ? s->sets[2].coeffs : sb->shad ? sb->shad : s->sets[1].coeffs;
    const prt__volume_scene in = {scene->volumes, scene->volume_count, &sb->job.rc, &sb->t->mesh, exit, s->sets[2].coeffs ? 3 : 1,
                                  sb->d.order, sb->d.samples, sb->d.seed};
    if (!(s->volumes = prt__calloc((size_t)scene->volume_count, sizeof *s->volumes))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int k = 0; k < scene->volume_count; ++k) {
        const prt_status st = prt__sh_volume_bake(ctx, &in, k, &s->volumes[k], p);
        if (st) return st;
        s->volume_count = k + 1;
    }
    return PRT_OK;
}

static prt_status run_brdf_in(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    (void)p;
    sh_bake *sb = (sh_bake *)b;
    return prt__bake_brdf_in(ctx, sb->t, sb->d.glossy_brdf);
}

static prt_status run_compress(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    sh_bake *sb = (sh_bake *)b;
    p->total = (uint64_t)sb->extra.compress.iterations;
    return prt__sh_compress_set(ctx, sb->s, sb->t->mesh.vertex_count, sb->compressing_set, &sb->extra.compress, p);
}

static prt_status run_quantize(prt__bake_job *b, prt_context *ctx, prt__progress *p)
{
    (void)p;
    sh_bake *sb = (sh_bake *)b;
    return prt__sh_quantize(ctx, sb->s, sb->t->mesh.vertex_count, sb->extra.quantize);
}

static int by_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

/* How noisy the Monte Carlo transfer is: each vertex's standard error of T_00 relative to its
 * value, summarised as the median and 95th percentile (vertices that see almost nothing are
 * left out: relative error means little there). */
static void report_noise(prt_context *ctx, const sh_bake *sb)
{
    const size_t nv = sb->t->mesh.vertex_count, nc = (size_t)sb->job.ncoeff;
    const float *T = sb->shad ? sb->shad : sb->unsh;
    if (!T || !nv) return;
    float *rel = malloc(nv * sizeof *rel);
    if (!rel) return;
    size_t n = 0;
    for (size_t v = 0; v < nv; ++v)
        if (isfinite(sb->noise[v]) && T[v * nc] > 0.01f) rel[n++] = sb->noise[v] / T[v * nc];
    if (n) {
        qsort(rel, n, sizeof *rel, by_float);
        prt__log(ctx, PRT_LOG_INFO, "estimated Monte Carlo noise of %s T_00 with %d directions: median %.2f%%, 95th percentile %.2f%% of each vertex's value "
                                    "(over %zu vertices, as if the directions were independent: the low-discrepancy set does better; 4x the samples halves it)",
                 sb->shad ? "shadowed" : "unshadowed", sb->d.samples, 100.0 * rel[n / 2], 100.0 * rel[(size_t)(0.95 * (double)(n - 1))], n);
    }
    free(rel);
}

static prt_status sh_stage(prt__bake_job *b, int index, prt__stage *out)
{
    sh_bake *sb = (sh_bake *)b;
    const size_t nv = sb->t->mesh.vertex_count;
    const int nc = sb->job.ncoeff, nc3 = 3 * nc;
    if (index > 0 && sb->plan[index - 1] == ST_VISIBILITY && sb->noise) {
        report_noise(b->ctx, sb);
        free(sb->noise);
        sb->noise = NULL;
    }
    if (index > 0 && sb->plan[index - 1] == ST_VISIBILITY) {
        /* Visibility is done: vertices whose whole fan is buried take their neighbours' transfer
         * (their own rays all start inside geometry); hand the sets over, and start the diffuse
         * bounces from them. */
        prt__sh_state *s = sb->s;
        if (sb->job.buried_count) {
            prt_status st = PRT_OK;
            if (sb->unsh) st = prt__fill_buried(&sb->t->mesh, sb->job.buried, sb->unsh, (size_t)nc, NULL);
            if (!st && sb->shad) st = prt__fill_buried(&sb->t->mesh, sb->job.buried, sb->shad, (size_t)nc, NULL);
            if (!st && sb->gshad) st = prt__fill_buried(&sb->t->mesh, sb->job.buried, sb->gshad, (size_t)nc * nc, NULL);
            if (st) return st;
        }
        if (sb->d.kinds & PRT_TRANSFER_UNSHADOWED) { s->sets[0].channels = 1; s->sets[0].coeffs = sb->unsh; sb->unsh = NULL; }
        if (!sb->coupled && (sb->d.kinds & PRT_TRANSFER_INTERREFLECTED)) {
            sb->total = prt__calloc(nv * nc3, sizeof(float));
            sb->prev = prt__calloc(nv * nc3, sizeof(float));
            sb->next = prt__calloc(nv * nc3, sizeof(float));
            if (!sb->total || !sb->prev || !sb->next) return prt__fail(b->ctx, PRT_ERR_NO_MEMORY, "out of memory for interreflection");
            /* Bounce 0 is the shadowed transfer times the (coloured) albedo. */
            for (size_t v = 0; v < nv; ++v)
                for (int c = 0; c < 3; ++c)
                    for (int i = 0; i < nc; ++i)
                        sb->prev[v * nc3 + c * nc + i] = sb->total[v * nc3 + c * nc + i] = sb->t->mesh.albedo[v * 3 + c] * sb->shad[v * nc + i];
        }
    }
    if (index > 0 && sb->plan[index - 1] == ST_BOUNCE) {
        float *tmp = sb->prev; sb->prev = sb->next; sb->next = tmp;
    }
    if (index > 0 && (index == sb->stages || sb->plan[index] != ST_BOUNCE) && sb->plan[index - 1] == ST_BOUNCE) {
        if (sb->job.buried_count) {
            const prt_status st = prt__fill_buried(&sb->t->mesh, sb->job.buried, sb->total, (size_t)nc3, NULL);
            if (st) return st;
        }
        sb->s->sets[2].channels = 3;
        sb->s->sets[2].coeffs = sb->total;
        sb->total = NULL;
    }
    if (index > 0 && (index == sb->stages || sb->plan[index] >= ST_TEXELS)) {
        /* Every stage that reads the shadowed and glossy-shadowed sets has run. */
        if (sb->shad && (sb->d.kinds & PRT_TRANSFER_SHADOWED)) { sb->s->sets[1].channels = 1; sb->s->sets[1].coeffs = sb->shad; sb->shad = NULL; }
        if (sb->gshad && sb->want_gsh) { sb->s->sets[3].channels = 1; sb->s->sets[3].coeffs = sb->gshad; sb->gshad = NULL; }
    }
    if (index >= sb->stages) return PRT_OK;
    switch (sb->plan[index]) {
    case ST_VISIBILITY: {
        snprintf(out->name, sizeof out->name, "visibility");
        if (sb->job.need_hits && !sb->job.hits.count) {
            /* Over the memory limit the hits, the bake's largest part, go to a scratch file. */
            prt_status st = prt__hits_init(b->ctx, &sb->job.hits, nv, (uint32_t)sb->d.samples, b->memory_over);
            if (st) return st;
            if (b->memory_over)
                prt__log(b->ctx, PRT_LOG_INFO, "the ray hits of the bounces stream through a scratch file in TMPDIR (the bake's estimate is over its memory limit)");
        }
        if (sb->job.need_hits && !sb->scratch) {
            sb->scratch = prt__calloc((size_t)b->threads, sizeof *sb->scratch);
            if (!sb->scratch) return prt__fail(b->ctx, PRT_ERR_NO_MEMORY, "out of memory");
            sb->nscratch = b->threads;
            for (int i = 0; i < b->threads; ++i)
                if (!(sb->scratch[i] = malloc((size_t)sb->d.samples * sizeof(hit_entry)))) return prt__fail(b->ctx, PRT_ERR_NO_MEMORY, "out of memory");
        }
        if (!sb->rdirs) {
            sb->rdirs = prt__calloc((size_t)b->threads, sizeof *sb->rdirs);
            if (!sb->rdirs) return prt__fail(b->ctx, PRT_ERR_NO_MEMORY, "out of memory");
            sb->nrdirs = b->threads;
            for (int i = 0; i < b->threads; ++i)
                if (!(sb->rdirs[i] = malloc((size_t)sb->d.samples * 3 * sizeof(float)))) return prt__fail(b->ctx, PRT_ERR_NO_MEMORY, "out of memory");
        }
        out->units = blocks(nv);
        out->run = run_visibility;
        out->save_unit = save_visibility;
        out->load_unit = load_visibility;
        break;
    }
    case ST_GLOSSY_BOUNCES: snprintf(out->name, sizeof out->name, "glossy bounces"); out->whole = run_glossy_bounces; break;
    case ST_BOUNCE:
        snprintf(out->name, sizeof out->name, "bounce %d/%d", sb->bounce_of[index], sb->d.bounces);
        out->units = blocks(nv);
        out->run = run_bounce;
        out->save_unit = save_bounce;
        out->load_unit = load_bounce;
        break;
    case ST_SUBSURFACE: snprintf(out->name, sizeof out->name, "subsurface"); out->whole = run_subsurface; break;
    case ST_NEIGHBOURHOOD: snprintf(out->name, sizeof out->name, "neighbourhood"); out->whole = run_neighbourhood; break;
    case ST_TEXELS: snprintf(out->name, sizeof out->name, "texels"); out->whole = run_texels; break;
    case ST_VOLUME: snprintf(out->name, sizeof out->name, "volumes"); out->whole = run_volumes; break;
    case ST_BRDF_IN: snprintf(out->name, sizeof out->name, "bake BRDF in"); out->whole = run_brdf_in; break;
    case ST_COMPRESS:
        sb->compressing_set = sb->bounce_of[index];
        snprintf(out->name, sizeof out->name, "compress %s", prt_transfer_kind_name(prt__kind_from_index(sb->compressing_set)));
        out->whole = run_compress;
        break;
    case ST_QUANTIZE: snprintf(out->name, sizeof out->name, "quantize"); out->whole = run_quantize; break;
    }
    return PRT_OK;
}

static prt_status sh_finish(prt__bake_job *b, prt_transfer *t)
{
    /* Every stage wrote into the state already. Quantized bakes (16-bit, the table's default)
     * store their texel sets as halves (0.05% relative), 8-bit ones as bytes with a scale and
     * bias per coefficient (the course notes' quantized maps): the transfer holds what the file will. */
    const sh_bake *sb = (const sh_bake *)b;
    prt__sh_state *s = t->state;
    prt__texel_sets *tx = &s->texels;
    if (!sb->extra.quantize || !tx->width) return PRT_OK;
    if (sb->extra.quantize == 8)
        return prt__texel_quantize8(tx, s->order) ? PRT_OK : prt__fail(b->ctx, PRT_ERR_NO_MEMORY, "out of memory quantizing the texel sets");
    const size_t ntex = (size_t)tx->width * tx->height;
    for (int k = 0; k < 3; ++k)
        for (size_t i = 0; tx->coeffs[k] && i < ntex * (size_t)tx->channels[k] * s->order * s->order; ++i)
            tx->coeffs[k][i] = prt__half_to_float(prt__half_from_float(tx->coeffs[k][i]));
    tx->halves = true;
    return PRT_OK;
}

static void sh_release(prt__bake_job *b)
{
    sh_bake *sb = (sh_bake *)b;
    bake_job *job = &sb->job;
    prt__raycaster_release(&job->rc);
    prt__hits_free(&job->hits);
    for (int i = 0; i < sb->nscratch; ++i) free(sb->scratch[i]);
    for (int i = 0; i < sb->nrdirs; ++i) free(sb->rdirs[i]);
    free(sb->rdirs);
    free(sb->noise);
    free(sb->scratch);
    free(job->spec); free(job->origins); free(job->buried); free(job->dirs); free(job->basis);
    free(sb->medium); free(sb->kernels);
    free(sb->unsh); free(sb->shad); free(sb->gshad); free(sb->total); free(sb->prev); free(sb->next);
    prt_image_free(&sb->extra.normal_map);
    prt_image_free(&sb->extra.height_map);
    free(sb);
}

/* Per-texel transfer needs a unique layout inside [0, 1]: the mesh's own, or one generated here
 * (which copies the vertices on chart seams, before anything is sized by the vertex count). */
static prt_status texel_layout(prt_context *ctx, const prt_sh_bake_desc *d, prt_transfer *t)
{
    char why[160] = "asked for";
    if (d->uv_layout == PRT_UV_MESH) return PRT_OK;   /* the texel bake says what is wrong with them */
    if (d->uv_layout == PRT_UV_AUTO && !prt__uv_layout_unusable(&t->mesh, d->texels, why, sizeof why)) return PRT_OK;
    if (d->normal_map || d->height_map)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a %s map follows the mesh's own texture coordinates, and '%s' cannot use them for texels (%s)",
                         d->normal_map ? "normal" : "height", t->source, why);
    prt__atlas_report r;
    const size_t nv = t->mesh.vertex_count;
    prt_status st = prt__uv_atlas(ctx, &t->mesh, &(prt__atlas_desc){.resolution = d->texels}, &r);
    if (st) return st;
    prt__log(ctx, PRT_LOG_INFO, "UV atlas for '%s' (%s): %zu charts touch %.0f%% of the %dx%d map's texels, worst stretch %.2f; %zu of %zu vertices copied along seams",
             t->source, why, r.charts, 100 * r.coverage, d->texels, d->texels, r.worst_stretch, r.added_vertices, nv);
    return PRT_OK;
}

/* The scene's translucent materials: which vertices scatter light under their surface, with
 * which kernel, and the albedo their bounces reflect with (the dipole's total diffuse
 * reflectance; an exponential falloff spreads the albedo the surface has). */
static prt_status translucent_media(prt_context *ctx, sh_bake *sb, const prt_scene *scene, float mm_per_unit)
{
    prt__mesh *m = &sb->t->mesh;
    if (!m->surface || !m->surface_count) return PRT_OK;
    uint8_t *of_surface = prt__calloc((size_t)m->surface_count + 1, 1);
    prt__dipole (*kernels)[3] = malloc(255 * sizeof *kernels);
    if (!of_surface || !kernels) { free(of_surface); free(kernels); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    int count = 0;
    prt_status st = PRT_OK;
    for (int k = 0; k < m->surface_count && !st; ++k) {
        prt_medium md;
        if (!prt_scene_medium(scene, m->surface_names[k], &md)) continue;
        if (count == 255) { st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "more than 255 translucent materials"); break; }
        st = prt__dipole_from_medium(&md, mm_per_unit, kernels[count]);
        of_surface[k + 1] = (uint8_t)++count;
    }
    if (!st && count) {
        if (!(sb->medium = prt__calloc(m->vertex_count ? m->vertex_count : 1, 1))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        for (size_t v = 0; !st && v < m->vertex_count; ++v) {
            const int k = m->surface[v] <= m->surface_count ? of_surface[m->surface[v]] : 0;
            sb->medium[v] = (uint8_t)k;
            for (int c = 0; k && c < 3; ++c)
                if (!(kernels[k - 1][c].falloff > 0)) m->albedo[v * 3 + c] = (float)prt__dipole_total(&kernels[k - 1][c]);
        }
        if (!st && !(sb->d.kinds & PRT_TRANSFER_INTERREFLECTED))
            prt__log(ctx, PRT_LOG_WARN, "%d translucent material%s scatter%s light under the surface in inter-reflected transfer only, which this bake leaves out: "
                     "elsewhere %s reflect%s it as a diffuse surface of the medium's total reflectance", count, count > 1 ? "s" : "", count > 1 ? "" : "s",
                     count > 1 ? "they" : "it", count > 1 ? "" : "s");
    }
    free(of_surface);
    if (st || !count) { free(kernels); free(sb->medium); sb->medium = NULL; return st; }
    sb->kernels = kernels;
    return PRT_OK;
}

prt_status prt__sh_bake_begin(prt_context *ctx, const prt_sh_bake_desc *desc_in, prt__sh_extra *extra, prt_transfer *t, prt__bake_job **out)
{
    prt_sh_bake_desc d = desc_in ? *desc_in : (prt_sh_bake_desc){0};
    if (extra && extra->normal_map.rgb) d.normal_map = &extra->normal_map;
    if (extra && extra->height_map.rgb) d.height_map = &extra->height_map;
    prt_sh_bake_desc def = prt_sh_bake_desc_defaults();
    if (d.order == 0) d.order = def.order;
    if (d.samples == 0) d.samples = def.samples;
    if (d.kinds == 0) d.kinds = def.kinds;
    if (d.bounces == 0) d.bounces = def.bounces;
    if (d.order < 1 || d.order > PRT_SH_MAX_ORDER)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "SH order %d out of range 1..%d", d.order, PRT_SH_MAX_ORDER);
    if (d.samples < 16 || d.samples > (1 << 20))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "samples %d out of range 16..%d", d.samples, 1 << 20);
    if (d.bounces < 1 || d.bounces > 64) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range 1..64", d.bounces);
    if (d.kinds & ~PRT_TRANSFER_ALL_KINDS) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "unknown transfer kind bits 0x%x", d.kinds);
    if (d.glossy_brdf) {
        prt_status bst = prt_brdf_validate(d.glossy_brdf);
        if (bst) return prt__fail(ctx, bst, "glossy BRDF: %s", prt_last_error());
        if (!d.glossy_exit) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a glossy BRDF at bake time needs glossy_exit (it is baked in)");
    }
    if (d.texels < 0 || d.texels > 8192) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "texels %d out of range 0..8192", d.texels);
    if (d.normal_map && !d.texels) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a normal map needs per-texel transfer (texels > 0)");
    if (d.normal_map && (d.normal_map->width < 1 || d.normal_map->height < 1 || !d.normal_map->rgb))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the normal map is empty");
    if (d.height_map && !d.texels) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a height map needs per-texel transfer (texels > 0)");
    if (d.height_scale < 0 || !isfinite(d.height_scale)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the height scale must be >= 0 (0: 1%% of the scene's diagonal)");
    if (d.height_map) {
        prt__height_field probe;
        if (!prt__height_field_init(&probe, d.height_map, 1.0f)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the height map is empty or holds a value that is not a number");
    }
    if (d.glossy_exit && !(d.kinds & (PRT_TRANSFER_GLOSSY_SHADOWED | PRT_TRANSFER_GLOSSY_INTERREFLECTED)))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "baking a BRDF in needs a glossy kind (glossy-shadowed or glossy-interreflected)");
    if (d.ray_offset < 0 || !isfinite(d.ray_offset)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ray offset must be >= 0");
    if (d.neighbourhood && (d.neighbourhood < 2 || d.neighbourhood > 64))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a neighbourhood grid has 2..64 points along each axis (got %d)", d.neighbourhood);
    if (d.neighbourhood) {
        /* N^3 points x 3 x order^4 floats: said up front rather than found out of memory. */
        const double n2 = (double)d.order * d.order, bytes = pow(d.neighbourhood, 3) * (3 * n2 * n2 + 1) * sizeof(float);
        if (bytes > 2.0 * 1073741824.0)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a neighbourhood grid of %d^3 points at order %d would hold %.1f GiB (at most 2): fewer points or a "
                             "lower --order", d.neighbourhood, d.order, bytes / 1073741824.0);
        prt__log(ctx, PRT_LOG_INFO, "neighbourhood grid: %d^3 points, %.1f MiB", d.neighbourhood, bytes / 1048576.0);
    }
    if (d.mm_per_unit < 0 || !isfinite(d.mm_per_unit)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "millimetres per unit must be > 0 (0: 1000)");

    if ((unsigned)d.uv_layout > PRT_UV_GENERATE) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "unknown UV layout %d", (int)d.uv_layout);
    if (d.texels) {
        prt_status lst = texel_layout(ctx, &d, t);
        if (lst) return lst;
    }

    sh_bake *sb = prt__calloc(1, sizeof *sb);
    prt__sh_state *s = prt__sh_state_new();
    if (!sb || !s) { free(sb); free(s); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    sb->base.stage = sh_stage;
    sb->base.finish = sh_finish;
    sb->base.release = sh_release;
    if (extra) {   /* the job owns the normal map from here on */
        sb->extra = *extra;
        memset(&extra->normal_map, 0, sizeof extra->normal_map);
        memset(&extra->height_map, 0, sizeof extra->height_map);
        if (d.normal_map == &extra->normal_map) d.normal_map = &sb->extra.normal_map;
        if (d.height_map == &extra->height_map) d.height_map = &sb->extra.height_map;
    }
    if (d.glossy_brdf) { sb->brdf = *d.glossy_brdf; d.glossy_brdf = &sb->brdf; }
    sb->d = d;
    sb->t = t;
    sb->s = s;
    t->state = s;   /* owned by t from here on, so a failed bake frees it with t */
    s->order = d.order;
    s->samples = d.samples;
    if (sb->d.height_map) {
        float scale = sb->d.height_scale;
        if (scale == 0) {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (size_t v = 0; v < t->mesh.vertex_count; ++v)
                for (int c = 0; c < 3; ++c) { lo[c] = fminf(lo[c], t->mesh.positions[v * 3 + c]); hi[c] = fmaxf(hi[c], t->mesh.positions[v * 3 + c]); }
            scale = 0.01f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
            prt__log(ctx, PRT_LOG_INFO, "height map: %dx%d, a stored 1 is %g (1%% of the scene's diagonal; --bump-height sets it)", sb->d.height_map->width,
                     sb->d.height_map->height, scale);
        }
        prt__height_field_init(&sb->height, sb->d.height_map, scale > 0 ? scale : 1.0f);
    }
    s->bounces = (d.kinds & (PRT_TRANSFER_INTERREFLECTED | PRT_TRANSFER_GLOSSY_INTERREFLECTED)) ? d.bounces : 0;
    s->seed = d.seed;
    bool scene_glossy = false;   /* some vertex has a material with a glossy part */
    for (size_t v = 0; v < t->mesh.vertex_count && !scene_glossy; ++v) {
        uint8_t k = t->mesh.material[v];
        scene_glossy = k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1]);
    }
    sb->want_gsh = d.kinds & PRT_TRANSFER_GLOSSY_SHADOWED;
    sb->want_gir = d.kinds & PRT_TRANSFER_GLOSSY_INTERREFLECTED;
    const bool want_ir = d.kinds & (PRT_TRANSFER_INTERREFLECTED | PRT_TRANSFER_GLOSSY_INTERREFLECTED);
    /* Glossy surfaces in the scene or glossy receivers put the glossy matrices into the bounce loop. */
    sb->coupled = want_ir && (sb->want_gir || scene_glossy);
    const bool need_glossy_sh = sb->want_gsh || sb->coupled;

    const size_t nv = t->mesh.vertex_count;
    bake_job *job = &sb->job;
    job->mesh = &t->mesh;
    job->order = d.order;
    job->ncoeff = d.order * d.order;
    job->samples = d.samples;
    job->seed = d.seed;
    job->offset = d.ray_offset > 0 ? d.ray_offset : prt__ray_offset(&t->mesh);
    job->need_hits = want_ir;
    const int nc = job->ncoeff;
    const bool want_unsh = d.kinds & PRT_TRANSFER_UNSHADOWED;
    const bool want_sh = d.kinds & (PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED | PRT_TRANSFER_GLOSSY_INTERREFLECTED);
    const size_t nn = (size_t)nc * nc;
    job->dirs = prt__calloc((size_t)d.samples * 3, sizeof(float));
    job->basis = prt__calloc((size_t)d.samples * nc, sizeof(float));
    sb->unsh = want_unsh ? prt__calloc(nv * nc, sizeof(float)) : NULL;
    sb->shad = want_sh ? prt__calloc(nv * nc, sizeof(float)) : NULL;
    if ((sb->noise = malloc((nv ? nv : 1) * sizeof(float))))
        for (size_t v = 0; v < nv; ++v) sb->noise[v] = NAN;   /* a report only: no memory, no report */
    sb->gshad = need_glossy_sh ? prt__calloc(nv * nn, sizeof(float)) : NULL;
    prt_status st = PRT_OK;
    if (!job->dirs || !job->basis || (want_unsh && !sb->unsh) || (want_sh && !sb->shad) || (need_glossy_sh && !sb->gshad))
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for a bake of %zu vertices", nv);
    for (int j = 0; j < d.samples && !st; ++j) {
        double u, v, dir[3], y[PRT_SH_MAX_COEFFS];
        prt__sobol2((uint32_t)j, d.seed, &u, &v);
        prt__sphere_dir(u, v, dir);
        prt_sh_eval(d.order, dir, y);
        for (int c = 0; c < 3; ++c) job->dirs[(size_t)j * 3 + c] = (float)dir[c];
        for (int i = 0; i < nc; ++i) job->basis[(size_t)j * nc + i] = (float)y[i];
    }
    if (!st) st = prt__raycaster_create(ctx, &t->mesh, &job->rc);
    if (!st && sb->extra.scene) st = prt__specular_table(ctx, sb->extra.scene, &t->mesh, &job->spec);
    if (!st && job->spec) {
        int n = 0;
        for (int k = 1; k <= t->mesh.surface_count; ++k) n += job->spec[k].type != PRT_SPECULAR_NONE;
        prt__log(ctx, PRT_LOG_INFO, "%d specular surface%s: sample rays turn at %s (up to %d times) and carry the light %s focus%s into the shadowed and "
                 "inter-reflected transfer (caustics)", n, n > 1 ? "s" : "", n > 1 ? "them" : "it", MAX_SPECULAR, n > 1 ? "they" : "it", n > 1 ? "" : "es");
    }
    if (!st && sb->extra.scene && sb->extra.scene->volume_count) {
        job->volumes = sb->extra.scene->volumes;
        job->volume_count = sb->extra.scene->volume_count;
        for (int k = 0; k < job->volume_count; ++k)
            if (prt__volume_voxels(&job->volumes[k]) > 128u * 128u * 128u)
                st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "volume %d has %zu voxels; the SH bake takes at most 128^3 per volume", k, prt__volume_voxels(&job->volumes[k]));
    }
    if (!st) st = prt__vertex_origins(&t->mesh, job->offset, &job->origins);
    if (!st && !(job->buried = malloc(nv ? nv : 1))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__unbury_origins(ctx, &job->rc, &t->mesh, job->offset, job->origins, job->buried, PRT_LOG_INFO);
    for (size_t v = 0; !st && v < nv; ++v) job->buried_count += job->buried[v] == 2;
    if (!st && sb->extra.scene) st = translucent_media(ctx, sb, sb->extra.scene, d.mm_per_unit > 0 ? d.mm_per_unit : 1000.0f);
    if (st) { sh_release(&sb->base); return st; }
    sb->plan[sb->stages++] = ST_VISIBILITY;
    if (sb->coupled) sb->plan[sb->stages++] = ST_GLOSSY_BOUNCES;
    else if (d.kinds & PRT_TRANSFER_INTERREFLECTED)
        for (int bnc = 1; bnc <= d.bounces; ++bnc) { sb->bounce_of[sb->stages] = bnc; sb->plan[sb->stages++] = ST_BOUNCE; }
    if (sb->medium && (d.kinds & PRT_TRANSFER_INTERREFLECTED)) sb->plan[sb->stages++] = ST_SUBSURFACE;
    if (d.neighbourhood) sb->plan[sb->stages++] = ST_NEIGHBOURHOOD;
    if (sb->extra.scene && sb->extra.scene->volume_count) sb->plan[sb->stages++] = ST_VOLUME;
    if (d.texels) sb->plan[sb->stages++] = ST_TEXELS;
    if (d.glossy_exit) sb->plan[sb->stages++] = ST_BRDF_IN;
    if (sb->extra.compressing)
        for (int k = 0; k < PRT__KIND_COUNT; ++k)
            if (d.kinds & prt__kind_from_index(k)) { sb->bounce_of[sb->stages] = k; sb->plan[sb->stages++] = ST_COMPRESS; }
    if (sb->extra.quantize) sb->plan[sb->stages++] = ST_QUANTIZE;
    *out = &sb->base;
    return PRT_OK;
}

static prt_status begin_from_desc(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job)
{
    prt__sh_extra extra;
    memset(&extra, 0, sizeof extra);
    extra.scene = scene;
    return prt__sh_bake_begin(ctx, desc, &extra, t, job);
}

prt_status prt_bake_sh(prt_context *ctx, const prt_scene *scene, const prt_sh_bake_desc *desc, prt_transfer **out)
{
    prt_bake_run_desc run = {.progress = desc ? desc->progress : NULL, .progress_user = desc ? desc->progress_user : NULL};
    return prt__bake_with(ctx, scene, &prt__method_sh, begin_from_desc, desc, &run, out);
}
