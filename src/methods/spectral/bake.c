/* Direct-to-indirect transfer in a spectral mesh basis (Wang, Zhu & Humphreys 2007, eq. 7):
 *   T^s(x, l) = integral over the hemisphere of x of s_l(y(x, w)) cos dw,
 * the irradiance at vertex x when every surface emits radiance s_l from its front side. One set of
 * cosine-weighted low-discrepancy rays per vertex serves every l at once: each closest front-face
 * hit adds pi/N times its barycentric weights to the three vertices it lands between, and those
 * weights times the vertices' basis values give the row. Rays that escape build the vertex's
 * shadowed SH irradiance transfer for the environment instead, and at glossy vertices the
 * shadowed transfer from the environment's SH to the incident radiance's (the BRDF then reflects
 * the environment view-dependently, as it does the surfaces' light).
 *
 * Stage 0 ("spectral basis", one step) partitions the mesh and solves the eigen problems; stage 1
 * gathers in blocks of vertices. Each vertex's rays depend only on its index, so every result is
 * the same for any thread count. Rows are kept as floats until the end, then each is quantized to
 * 16 bits against its own largest entry (the paper uses one scale for the matrix: a dim row then
 * keeps few bits), entries below --drop-below x that largest dropped. */
#include "methods/spectral/spectral.h"
#include "brdf/sh_matrix.h"
#include "core/progress.h"

#include <omp.h>

#define BLOCK 32
#define PACKET 16

/* Rows per vertex: the diffuse row, then the 16 glossy rows of a glossy vertex. */
#define ROWS (1 + PRT__SPECTRAL_GLOSSY_N)

typedef struct unit_rows {
    uint32_t count[BLOCK * ROWS];   /* entries of row r of the block's vertex i at [i * ROWS + r] (glossy rows: 0 if not glossy) */
    uint16_t *index;                /* every row's entries, in that order */
    float *value;
} unit_rows;

typedef struct thread_scratch {
    float *weight;           /* [vertex] hit weight, zero between uses */
    float *gweight;          /* [vertex][16] hit weight times y_k / cos for glossy receivers */
    uint32_t *touched;       /* vertices with a weight */
    float *row;              /* [ROWS][function] */
    uint32_t *keep;          /* [function] a row's quantization (streamed bakes count what it keeps) */
    int16_t *q;
    uint16_t *index;         /* a unit's rows before they are copied out, grown as needed */
    float *value;
    size_t cap;
} thread_scratch;

/* Room for `more` entries after `used` in the thread's unit buffers. */
static bool scratch_room(thread_scratch *sc, size_t used, size_t more)
{
    if (used + more <= sc->cap) return true;
    size_t cap = sc->cap ? sc->cap : 1024;
    while (cap < used + more) cap *= 2;
    uint16_t *index = realloc(sc->index, cap * sizeof(uint16_t));
    if (index) sc->index = index;
    float *value = index ? realloc(sc->value, cap * sizeof(float)) : NULL;
    if (value) sc->value = value;
    if (!index || !value) return false;
    sc->cap = cap;
    return true;
}

/* A streamed bake's block (memory_over): where its record - counts, indices, values, as the
 * checkpoint's - lies in the scratch file, its entries (diffuse, glossy) and how many of them
 * quantization keeps, so that the end allocates exactly the rows it writes. */
typedef struct spilled_unit {
    uint64_t at;
    uint32_t total[2], kept[2];
} spilled_unit;

typedef struct sbake {
    prt__bake_job base;
    prt_transfer *t;
    prt__spectral_set *s;
    prt__spectral_bake_desc d;
    prt__raycaster rc;
    float *origins;
    prt__emitters emitters;          /* the scene's emissive triangles at scale 1 (count 0: none) */
    unit_rows *units;                /* in memory; or, streamed: */
    spilled_unit *spilled;
    prt__spectral_spill spill;
    uint64_t unit_count;
    thread_scratch *scratch;
    int nscratch;
} sbake;

static uint32_t vertex_seed(size_t v)
{
    uint64_t z = (uint64_t)v * 0x9E3779B97F4A7C15ull + 0x5350454354524C31ull;   /* "SPECTRL1" */
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return (uint32_t)(z ^ (z >> 31));
}

#define EMITTER_RAYS 256

/* Light samples on the emitters for vertex v's direct light from emissive surfaces, combined with
 * the gathering rays that hit them by the balance heuristic: every sample adds
 * L_e cos / (N_b p_cos + N_l p_light), whichever strategy drew it. Large emitters (a glowing
 * wall) are found by the cosine rays, small ones (a ceiling lamp) by the light samples. */
static void emitter_samples(const sbake *sb, size_t v, int n_b, int n_l, double e[3])
{
    const prt__mesh *m = &sb->t->mesh;
    const float *n = m->normals + v * 3, *org = sb->origins + v * 3;
    const uint32_t seed = vertex_seed(v) ^ 0x45u;
    for (int i = 0; i < n_l; ++i) {
        double u1, u2;
        prt__sobol2((uint32_t)i, seed, &u1, &u2);
        prt__light_sample ls;
        if (!prt__emitters_sample(&sb->emitters, m, org, (i + 0.5) / n_l, u1, u2, &ls)) continue;
        const float cosine = prt__v3_dot(ls.wi, n);
        if (cosine <= 0.0f) continue;
        struct RTCIntersectContext ictx;
        rtcInitIntersectContext(&ictx);
        struct RTCRay r = {org[0], org[1], org[2], 0.0f, ls.wi[0], ls.wi[1], ls.wi[2], 0.0f, ls.dist * (1.0f - 1e-3f), 0xFFFFFFFFu, 0, 0};
        rtcOccluded1(sb->rc.scene, &ictx, &r);
        if (r.tfar < 0.0f) continue;
        /* ls.value = L_e / p_light */
        const double w = 1.0 / (n_b * cosine / PRT_PI + n_l * (double)ls.pdf);
        for (int k = 0; k < 3; ++k) e[k] += ls.value[k] * ls.pdf * cosine * w;
    }
}

/* Gathers vertex v into sc->row (functions entries), env (order^2 entries), at glossy vertices
 * genv (16 x order^2) and, when the scene emits, emit (3 entries). */
static void gather_vertex(const sbake *sb, size_t v, thread_scratch *sc, float *env, float *genv, float *emit)
{
    const prt__mesh *m = &sb->t->mesh;
    const prt__spectral_basis *b = &sb->s->basis;
    const int N = sb->d.samples, order = sb->d.env_order, nc = order * order;
    const float *n = m->normals + v * 3, *org = sb->origins + v * 3;
    float tx[3], ty[3];
    prt_brdf_frame(n, tx, ty);
    const float c = (float)(PRT_PI / N);
    const uint32_t seed = vertex_seed(v);
    uint32_t touched = 0;
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    float dirs[PACKET * 3];
    int idx[PACKET];
    for (int k = 0; k < PACKET; ++k) idx[k] = k;
    memset(env, 0, (size_t)nc * sizeof(float));
    if (genv) memset(genv, 0, (size_t)PRT__SPECTRAL_GLOSSY_N * nc * sizeof(float));
    const int n_l = sb->emitters.count ? EMITTER_RAYS : 0;
    const bool glossy = sb->s->glossy_of && sb->s->glossy_of[v] != UINT32_MAX;
    double e[3] = {0, 0, 0};
    for (int i0 = 0; i0 < N; i0 += PACKET) {
        const int lanes = N - i0 < PACKET ? N - i0 : PACKET;
        for (int k = 0; k < lanes; ++k) {
            double u1, u2;
            prt__sobol2((uint32_t)(i0 + k), seed, &u1, &u2);
            prt__cosine_dir(u1, u2, n, tx, ty, dirs + k * 3);
        }
        struct RTCRayHit16 rh;
        int valid[16] __attribute__((aligned(64)));
        prt__packet_rayhits(&rh, valid, org, dirs, idx, lanes);
        rtcIntersect16(valid, sb->rc.scene, &ictx, &rh);
        for (int k = 0; k < lanes; ++k) {
            const float *d = dirs + k * 3;
            if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
                float y[PRT_SH_MAX_COEFFS];
                prt_sh_eval_f(order, d, y);
                for (int i = 0; i < nc; ++i) env[i] += c * y[i];
                if (genv) {   /* y_k(d) y_i(d) over the cosine-weighted pdf, as the glossy rows */
                    float yk[PRT__SPECTRAL_GLOSSY_N];
                    prt_sh_eval_f(PRT__SPECTRAL_GLOSSY_ORDER, d, yk);
                    const float f = c / fmaxf(prt__v3_dot(d, n), 1e-3f);
                    for (int k = 0; k < PRT__SPECTRAL_GLOSSY_N; ++k)
                        for (int i = 0; i < nc; ++i) genv[k * nc + i] += f * yk[k] * y[i];
                }
                continue;
            }
            const float ng[3] = {rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]};
            if (prt__v3_dot(ng, d) >= 0.0f) continue;   /* the back of a surface emits nothing */
            const uint32_t *tri = m->indices + (size_t)rh.hit.primID[k] * 3;
            const float w[3] = {1.0f - rh.hit.u[k] - rh.hit.v[k], rh.hit.u[k], rh.hit.v[k]};
            if (n_l) {
                float le[3];
                prt__emission_at(&sb->emitters, m, rh.hit.primID[k], rh.hit.u[k], rh.hit.v[k], le);
                if (le[0] > 0 || le[1] > 0 || le[2] > 0) {
                    const float cosine = prt__v3_dot(d, n), len = prt__v3_len(ng);
                    const double pl = prt__emitters_pdf(&sb->emitters, rh.hit.primID[k], rh.ray.tfar[k], -prt__v3_dot(ng, d) / len);
                    const double wgt = cosine / (N * cosine / PRT_PI + n_l * pl);
                    for (int a = 0; a < 3; ++a) e[a] += le[a] * wgt;
                }
            }
            for (int a = 0; a < 3; ++a) {
                const uint32_t u = tri[a];
                if (sc->weight[u] == 0.0f) sc->touched[touched++] = u;
                sc->weight[u] += c * w[a];
                if (sc->weight[u] == 0.0f) sc->weight[u] = 1e-38f;   /* stays listed exactly once */
            }
            if (glossy) {
                /* Radiance from the hit projected on y_k: the cosine-weighted pdf is divided out. */
                float y[PRT__SPECTRAL_GLOSSY_N];
                prt_sh_eval_f(PRT__SPECTRAL_GLOSSY_ORDER, d, y);
                const float cosine = fmaxf(prt__v3_dot(d, n), 1e-3f);
                for (int a = 0; a < 3; ++a) {
                    float *gw = sc->gweight + (size_t)tri[a] * PRT__SPECTRAL_GLOSSY_N;
                    const float f = c * w[a] / cosine;
                    for (int j = 0; j < PRT__SPECTRAL_GLOSSY_N; ++j) gw[j] += f * y[j];
                }
            }
        }
    }
    if (n_l) {
        emitter_samples(sb, v, N, n_l, e);
        for (int a = 0; a < 3; ++a) emit[a] = (float)e[a];
    }
    const size_t F = b->functions;
    memset(sc->row, 0, (glossy ? ROWS : 1) * F * sizeof(float));
    for (uint32_t i = 0; i < touched; ++i) {
        const uint32_t u = sc->touched[i], q = b->part_of[u], k = b->count[q];
        const float w = sc->weight[u], *s = b->values + b->offset[u];
        float *row = sc->row + b->first[q];
        for (uint32_t j = 0; j < k; ++j) row[j] += w * s[j];
        sc->weight[u] = 0.0f;
        if (!glossy) continue;
        float *gw = sc->gweight + (size_t)u * PRT__SPECTRAL_GLOSSY_N;
        for (int r = 0; r < PRT__SPECTRAL_GLOSSY_N; ++r) {
            float *grow = sc->row + (size_t)(1 + r) * F + b->first[q];
            for (uint32_t j = 0; j < k; ++j) grow[j] += gw[r] * s[j];
            gw[r] = 0.0f;
        }
    }
}

/* A streamed block's rows into the scratch file: counts, indices and values (the checkpoint
 * record's first parts), and what quantizing each row keeps. */
static bool spill_unit(sbake *sb, uint64_t unit, const uint32_t *count, const uint16_t *index, const float *value, uint32_t *keep, int16_t *q)
{
    const size_t nv = sb->t->mesh.vertex_count, v0 = unit * BLOCK, n = (v0 + BLOCK < nv ? v0 + BLOCK : nv) - v0;
    spilled_unit *su = &sb->spilled[unit];
    uint32_t total[2] = {0, 0}, kept[2] = {0, 0};
    size_t e = 0;
    for (size_t i = 0; i < n * ROWS; ++i) {
        float scale;
        kept[i % ROWS != 0] += prt__spectral_quantize_row(value + e, count[i], sb->d.drop_below, keep, q, &scale);
        total[i % ROWS != 0] += count[i];
        e += count[i];
    }
    const void *parts[3] = {count, index, value};
    const size_t bytes[3] = {n * ROWS * sizeof(uint32_t), e * sizeof(uint16_t), e * sizeof(float)};
    uint64_t at;
    if (!prt__spectral_spill_put(&sb->spill, parts, bytes, 3, &at)) return false;
    su->at = at;
    memcpy(su->total, total, sizeof total);
    memcpy(su->kept, kept, sizeof kept);
    return true;
}

static prt_status run_unit(prt__bake_job *base, uint64_t unit, int thread)
{
    sbake *sb = (sbake *)base;
    const size_t nv = sb->t->mesh.vertex_count, v0 = unit * BLOCK, v1 = v0 + BLOCK < nv ? v0 + BLOCK : nv;
    const uint32_t F = sb->s->basis.functions;
    const int nc = sb->d.env_order * sb->d.env_order;
    thread_scratch *sc = &sb->scratch[thread];
    uint32_t streamed[BLOCK * ROWS];
    uint32_t *count = sb->spilled ? streamed : sb->units[unit].count;
    size_t at = 0;
    memset(count, 0, sizeof streamed);
    for (size_t v = v0; v < v1; ++v) {
        const uint32_t g = sb->s->glossy_of ? sb->s->glossy_of[v] : UINT32_MAX;
        float *genv = g != UINT32_MAX ? sb->s->genv + (size_t)g * PRT__SPECTRAL_GLOSSY_N * nc : NULL;
        gather_vertex(sb, v, sc, sb->s->env + v * (size_t)nc, genv, sb->s->emit ? sb->s->emit + v * 3 : NULL);
        const int rows = sb->s->glossy_of && sb->s->glossy_of[v] != UINT32_MAX ? ROWS : 1;
        for (int r = 0; r < rows; ++r) {
            const float *row = sc->row + (size_t)r * F;
            if (!scratch_room(sc, at, F)) return prt__fail(base->ctx, PRT_ERR_NO_MEMORY, "out of memory");
            uint16_t *index = sc->index;
            float *value = sc->value;
            uint32_t n = 0;
            for (uint32_t l = 0; l < F; ++l)
                if (row[l] != 0.0f) { index[at] = (uint16_t)l; value[at++] = row[l]; ++n; }
            count[(v - v0) * ROWS + (size_t)r] = n;
        }
    }
    if (sb->spilled) {
        if (!spill_unit(sb, unit, count, sc->index, sc->value, sc->keep, sc->q))
            return prt__fail(base->ctx, PRT_ERR_IO, "cannot write the spectral transfer rows' scratch file (disk full?)");
        return PRT_OK;
    }
    unit_rows *u = &sb->units[unit];
    free(u->index);
    free(u->value);
    u->index = malloc(at ? at * sizeof(uint16_t) : 1);
    u->value = malloc(at ? at * sizeof(float) : 1);
    if (!u->index || !u->value) return prt__fail(base->ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(u->index, sc->index, at * sizeof(uint16_t));
    memcpy(u->value, sc->value, at * sizeof(float));
    return PRT_OK;
}

/* The block's glossy vertices: the first one's number and how many (they are numbered in order). */
static size_t block_glossy(const prt__spectral_set *s, size_t v0, size_t v1, uint32_t *first)
{
    size_t n = 0;
    *first = 0;
    for (size_t v = v0; s->glossy_of && v < v1; ++v)
        if (s->glossy_of[v] != UINT32_MAX && !n++) *first = s->glossy_of[v];
    return n;
}

/* Checkpoint record of a unit: counts, indices, values, then the block's environment rows,
 * emitters' light and glossy vertices' environment transfer. */
static void save_unit(prt__bake_job *base, uint64_t unit, prt__bytes *out)
{
    sbake *sb = (sbake *)base;
    const size_t nv = sb->t->mesh.vertex_count, v0 = unit * BLOCK, v1 = v0 + BLOCK < nv ? v0 + BLOCK : nv;
    const int nc = sb->d.env_order * sb->d.env_order;
    if (sb->spilled) {   /* the record's rows as the scratch file holds them */
        const spilled_unit *su = &sb->spilled[unit];
        const size_t bytes = (v1 - v0) * ROWS * sizeof(uint32_t) + ((size_t)su->total[0] + su->total[1]) * (sizeof(uint16_t) + sizeof(float));
        void *rec = malloc(bytes);
        if (!rec || !prt__spectral_spill_get(&sb->spill, su->at, rec, bytes)) out->failed = true;
        else prt__bytes_put(out, rec, bytes);
        free(rec);
    } else {
        const unit_rows *u = &sb->units[unit];
        size_t total = 0;
        for (size_t i = 0; i < (v1 - v0) * ROWS; ++i) total += u->count[i];
        prt__bytes_put(out, u->count, (v1 - v0) * ROWS * sizeof(uint32_t));
        prt__bytes_put(out, u->index, total * sizeof(uint16_t));
        prt__bytes_put(out, u->value, total * sizeof(float));
    }
    prt__bytes_put(out, sb->s->env + v0 * nc, (v1 - v0) * nc * sizeof(float));
    if (sb->s->emit) prt__bytes_put(out, sb->s->emit + v0 * 3, (v1 - v0) * 3 * sizeof(float));
    uint32_t g0;
    const size_t ng = block_glossy(sb->s, v0, v1, &g0), gn = (size_t)PRT__SPECTRAL_GLOSSY_N * nc;
    if (ng) prt__bytes_put(out, sb->s->genv + g0 * gn, ng * gn * sizeof(float));
}

static bool load_unit(prt__bake_job *base, uint64_t unit, const unsigned char *data, size_t size)
{
    sbake *sb = (sbake *)base;
    const size_t nv = sb->t->mesh.vertex_count, v0 = unit * BLOCK, v1 = v0 + BLOCK < nv ? v0 + BLOCK : nv, n = v1 - v0;
    const uint32_t F = sb->s->basis.functions;
    const size_t nc = (size_t)sb->d.env_order * sb->d.env_order;
    uint32_t count[BLOCK * ROWS];
    if (size < n * ROWS * sizeof(uint32_t)) return false;
    memcpy(count, data, n * ROWS * sizeof(uint32_t));
    size_t total = 0;
    for (size_t i = 0; i < n * ROWS; ++i) {
        const bool glossy = sb->s->glossy_of && sb->s->glossy_of[v0 + i / ROWS] != UINT32_MAX;
        if (count[i] > F || (i % ROWS && !glossy && count[i])) return false;
        total += count[i];
    }
    const size_t ne = sb->s->emit ? n * 3 : 0;
    uint32_t g0;
    const size_t gn = block_glossy(sb->s, v0, v1, &g0) * PRT__SPECTRAL_GLOSSY_N * nc;
    if (size != n * ROWS * sizeof(uint32_t) + total * (sizeof(uint16_t) + sizeof(float)) + (n * nc + ne + gn) * sizeof(float)) return false;
    const unsigned char *pi = data + n * ROWS * sizeof(uint32_t), *pv = pi + total * sizeof(uint16_t), *pe = pv + total * sizeof(float);
    uint16_t *index = malloc(total ? total * sizeof(uint16_t) : 1);
    float *value = malloc(total ? total * sizeof(float) : 1);
    if (!index || !value) { free(index); free(value); return false; }
    memcpy(index, pi, total * sizeof(uint16_t));
    memcpy(value, pv, total * sizeof(float));
    /* Indices ascend within each vertex and stay below the function count; values are finite. */
    size_t at = 0;
    bool ok = prt__all_finite(value, total);
    for (size_t i = 0; i < n * ROWS && ok; ++i)
        for (uint32_t e = 0; e < count[i]; ++e, ++at)
            if (index[at] >= F || (e && index[at] <= index[at - 1])) ok = false;
    float env[BLOCK * PRT_SH_MAX_COEFFS], emit[BLOCK * 3];
    memcpy(env, pe, n * nc * sizeof(float));
    memcpy(emit, pe + n * nc * sizeof(float), ne * sizeof(float));
    if (ok) ok = prt__all_finite(env, n * nc) && prt__all_finite(emit, ne);
    for (size_t i = 0; i < ne && ok; ++i) ok = emit[i] >= 0.0f;
    const unsigned char *pg = pe + (n * nc + ne) * sizeof(float);
    float *genv = gn ? sb->s->genv + (size_t)g0 * PRT__SPECTRAL_GLOSSY_N * nc : NULL;
    if (ok && gn) {
        memcpy(genv, pg, gn * sizeof(float));
        ok = prt__all_finite(genv, gn);
    }
    if (ok && sb->spilled) {
        uint32_t *keep = malloc((F ? F : 1) * sizeof(uint32_t));
        int16_t *q = malloc((F ? F : 1) * sizeof(int16_t));
        ok = keep && q && spill_unit(sb, unit, count, index, value, keep, q);
        if (!ok) prt__log(base->ctx, PRT_LOG_ERROR, "cannot write the spectral transfer rows' scratch file (disk full?)");
        free(keep);
        free(q);
        free(index);
        free(value);
        index = NULL;
        value = NULL;
    }
    if (!ok) { free(index); free(value); return false; }
    if (!sb->spilled) {
        unit_rows *u = &sb->units[unit];
        free(u->index);
        free(u->value);
        u->index = index;
        u->value = value;
        memset(u->count, 0, sizeof u->count);
        memcpy(u->count, count, n * ROWS * sizeof(uint32_t));
    }
    memcpy(sb->s->env + v0 * nc, env, n * nc * sizeof(float));
    if (ne) memcpy(sb->s->emit + v0 * 3, emit, ne * sizeof(float));
    return true;
}

static prt_status basis_step(prt__bake_job *base, prt_context *ctx, prt__progress *p)
{
    sbake *sb = (sbake *)base;
    if (sb->d.full) return prt__spectral_basis_full(ctx, sb->t->mesh.vertex_count, &sb->s->basis);
    return prt__spectral_basis_build(ctx, &sb->t->mesh, sb->d.partition_size, sb->d.functions, p, &sb->s->basis);
}

static prt_status scratch_init(sbake *sb)
{
    const size_t nv = sb->t->mesh.vertex_count;
    const int threads = sb->base.threads;
    sb->scratch = prt__calloc((size_t)threads, sizeof *sb->scratch);
    if (!sb->scratch) return prt__fail(sb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
    sb->nscratch = threads;
    /* Over the memory limit the rows, the bake's largest part, go to a scratch file. */
    if (sb->base.memory_over) {
        prt_status st = prt__spectral_spill_open(sb->base.ctx, &sb->spill);
        if (st) return st;
        if (!(sb->spilled = prt__calloc(sb->unit_count, sizeof *sb->spilled))) return prt__fail(sb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
        prt__log(sb->base.ctx, PRT_LOG_INFO, "the spectral transfer rows stream through a scratch file in TMPDIR (the bake's estimate is over its memory limit)");
    } else if (!(sb->units = prt__calloc(sb->unit_count, sizeof *sb->units))) {
        return prt__fail(sb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    for (int i = 0; i < threads; ++i) {
        thread_scratch *sc = &sb->scratch[i];
        sc->weight = prt__calloc(nv, sizeof(float));
        sc->touched = prt__calloc(nv, sizeof(uint32_t));
        const size_t rows = sb->s->glossy_count ? ROWS : 1;
        sc->row = prt__calloc(rows * sb->s->basis.functions, sizeof(float));
        if (sb->s->glossy_count && !(sc->gweight = prt__calloc(nv * PRT__SPECTRAL_GLOSSY_N, sizeof(float))))
            return prt__fail(sb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (sb->spilled && (!(sc->keep = malloc(sb->s->basis.functions * sizeof(uint32_t))) || !(sc->q = malloc(sb->s->basis.functions * sizeof(int16_t)))))
            return prt__fail(sb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!sc->weight || !sc->touched || !sc->row) return prt__fail(sb->base.ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    return PRT_OK;
}

static prt_status spectral_stage(prt__bake_job *base, int index, prt__stage *out)
{
    sbake *sb = (sbake *)base;
    if (index == 0) {
        snprintf(out->name, sizeof out->name, "spectral basis");
        out->whole = basis_step;
        return PRT_OK;
    }
    if (index > 1) return PRT_OK;
    prt_status st = scratch_init(sb);
    if (st) return st;
    snprintf(out->name, sizeof out->name, "spectral transfer");
    out->units = sb->unit_count;
    out->run = run_unit;
    out->save_unit = save_unit;
    out->load_unit = load_unit;
    return PRT_OK;
}

uint32_t prt__spectral_quantize_row(const float *x, uint32_t n, float drop, uint32_t *keep, int16_t *q, float *scale)
{
    float m = 0.0f;
    for (uint32_t i = 0; i < n; ++i) m = fmaxf(m, fabsf(x[i]));
    *scale = m > 0.0f ? m / 32767.0f : 0.0f;
    if (!(m > 0.0f)) return 0;
    const float inv = 32767.0f / m, floor_ = drop * m;
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (fabsf(x[i]) < floor_) continue;
        const long v = lroundf(x[i] * inv);
        if (!v) continue;
        keep[k] = i;
        q[k++] = (int16_t)(v > 32767 ? 32767 : v < -32767 ? -32767 : v);
    }
    return k;
}

/* Every row (the diffuse one and each glossy one) quantized against its own largest entry, so
 * that a dim row (a vertex far out on a ground plane) keeps the relative precision of a bright
 * one; entries that round to zero or fall below --drop-below x the row's largest are dropped. */
static prt_status spectral_finish(prt__bake_job *base, prt_transfer *t)
{
    sbake *sb = (sbake *)base;
    prt__spectral_set *s = sb->s;
    const size_t nv = t->mesh.vertex_count;
    size_t total[2] = {0, 0};   /* diffuse, glossy: at most what the units hold */
    size_t kept[2] = {0, 0};    /* streamed: exactly what quantization keeps */
    for (uint64_t u = 0; u < sb->unit_count; ++u) {
        if (sb->spilled) {
            for (int g = 0; g < 2; ++g) { total[g] += sb->spilled[u].total[g]; kept[g] += sb->spilled[u].kept[g]; }
            continue;
        }
        for (size_t i = 0; i < BLOCK * ROWS; ++i) total[i % ROWS != 0] += sb->units[u].count[i];
    }
    if (!sb->spilled) { kept[0] = total[0]; kept[1] = total[1]; }
    s->drop = sb->d.drop_below;
    const size_t ng = (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N, F = s->basis.functions;
    s->row_start = prt__calloc(nv + 1, sizeof(uint64_t));
    s->row_scale = prt__calloc(nv ? nv : 1, sizeof(float));
    s->index = malloc(kept[0] ? kept[0] * sizeof(uint16_t) : 1);
    s->value = malloc(kept[0] ? kept[0] * sizeof(int16_t) : 1);
    s->grow_start = prt__calloc(ng + 1, sizeof(uint64_t));
    s->grow_scale = prt__calloc(ng ? ng : 1, sizeof(float));
    s->gindex = malloc(kept[1] ? kept[1] * sizeof(uint16_t) : 1);
    s->gvalue = malloc(kept[1] ? kept[1] * sizeof(int16_t) : 1);
    uint32_t *keep = malloc((F ? F : 1) * sizeof(uint32_t));
    int16_t *q = malloc((F ? F : 1) * sizeof(int16_t));
    /* A streamed block read back: its counts, indices and values. */
    uint32_t rcount[BLOCK * ROWS];
    uint16_t *rindex = NULL;
    float *rvalue = NULL;
    size_t rcap = 0;
    if (sb->d.keep_rows) {
        s->raw_start = prt__calloc(nv + 1, sizeof(uint64_t));
        s->raw_index = malloc(total[0] ? total[0] * sizeof(uint16_t) : 1);
        s->raw_value = malloc(total[0] ? total[0] * sizeof(float) : 1);
        s->raw_gstart = prt__calloc(ng + 1, sizeof(uint64_t));
        s->raw_gindex = malloc(total[1] ? total[1] * sizeof(uint16_t) : 1);
        s->raw_gvalue = malloc(total[1] ? total[1] * sizeof(float) : 1);
    }
    if (!s->row_start || !s->row_scale || !s->index || !s->value || !s->grow_start || !s->grow_scale || !s->gindex || !s->gvalue || !keep || !q ||
        (sb->d.keep_rows && (!s->raw_start || !s->raw_index || !s->raw_value || !s->raw_gstart || !s->raw_gindex || !s->raw_gvalue))) {
        free(keep);
        free(q);
        return prt__fail(base->ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    /* The glossy materials' SH matrices, once per bake (a numerical double integral). */
    if (s->glossy_count) {
        bool used[PRT__MAX_BRDFS] = {false};
        for (size_t v = 0; v < nv; ++v)
            if (s->glossy_of[v] != UINT32_MAX && t->mesh.material[v]) used[t->mesh.material[v] - 1] = true;
        prt_brdf only[PRT__MAX_BRDFS];
        for (int k = 0; k < t->brdf_count; ++k) {
            if (!used[k]) continue;
            only[0] = t->brdfs[k];
            float *B[1] = {NULL};
            prt_status st = prt__brdf_matrices(base->ctx, only, 1, PRT__SPECTRAL_GLOSSY_ORDER, B);
            if (st) { free(B[0]); free(keep); free(q); return st; }
            s->brdf_matrix[k] = B[0];
        }
        /* The glossy candidates of the BRDF sets: the same projection, each once. */
        for (int i = 0; i < s->set_count; ++i) {
            if (!prt_brdf_is_glossy(&s->set[i].brdf)) continue;
            for (int k = 0; k < t->brdf_count && !s->set_matrix[i]; ++k)
                if (s->brdf_matrix[k] && !memcmp(&t->brdfs[k], &s->set[i].brdf, sizeof(prt_brdf)) && (s->set_matrix[i] = malloc(PRT__SPECTRAL_MATRIX_FLOATS * sizeof(float))))
                    memcpy(s->set_matrix[i], s->brdf_matrix[k], PRT__SPECTRAL_MATRIX_FLOATS * sizeof(float));
            if (s->set_matrix[i]) continue;
            float *B[1] = {NULL};
            prt_status st = prt__brdf_matrices(base->ctx, &s->set[i].brdf, 1, PRT__SPECTRAL_GLOSSY_ORDER, B);
            if (st) { free(B[0]); return st; }
            s->set_matrix[i] = B[0];
        }
    }
    /* The environment's glossy transfer is kept as halves: the bake relights as its file will. */
    const size_t genv_n = (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N * s->env_order * s->env_order;
    for (size_t i = 0; s->genv && i < genv_n; ++i) s->genv[i] = prt__half_to_float(prt__half_from_float(s->genv[i]));
    size_t at[2] = {0, 0};
    prt_status st = PRT_OK;
    for (uint64_t u = 0; u < sb->unit_count && !st; ++u) {
        const uint32_t *count;
        const uint16_t *rows_index;
        const float *rows_value;
        if (sb->spilled) {
            const spilled_unit *su = &sb->spilled[u];
            const size_t n = (u + 1) * BLOCK < nv ? BLOCK : nv - u * BLOCK, entries = (size_t)su->total[0] + su->total[1];
            if (entries > rcap) {
                free(rindex);
                free(rvalue);
                rindex = malloc(entries * sizeof(uint16_t));
                rvalue = malloc(entries * sizeof(float));
                rcap = rindex && rvalue ? entries : 0;
                if (!rcap) { st = prt__fail(base->ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
            }
            const uint64_t ai = su->at + n * ROWS * sizeof(uint32_t), av = ai + entries * sizeof(uint16_t);
            if (!prt__spectral_spill_get(&sb->spill, su->at, rcount, n * ROWS * sizeof(uint32_t)) ||
                !prt__spectral_spill_get(&sb->spill, ai, rindex, entries * sizeof(uint16_t)) ||
                !prt__spectral_spill_get(&sb->spill, av, rvalue, entries * sizeof(float))) {
                st = prt__fail(base->ctx, PRT_ERR_IO, "cannot read the spectral transfer rows' scratch file");
                break;
            }
            count = rcount;
            rows_index = rindex;
            rows_value = rvalue;
        } else {
            count = sb->units[u].count;
            rows_index = sb->units[u].index;
            rows_value = sb->units[u].value;
        }
        size_t e = 0;
        for (size_t v = u * BLOCK; v < nv && v < (u + 1) * BLOCK && !st; ++v) {
            const uint32_t gv = s->glossy_of ? s->glossy_of[v] : UINT32_MAX;
            for (int row = 0; row < ROWS && !st; ++row) {
                const int g = row != 0;
                const uint32_t n = count[(v - u * BLOCK) * ROWS + (size_t)row];
                if (g && gv == UINT32_MAX) continue;   /* no glossy rows: n is 0 */
                const size_t gr = g ? (size_t)gv * PRT__SPECTRAL_GLOSSY_N + (size_t)(row - 1) : 0;
                if (sb->d.keep_rows) {
                    uint64_t *start = g ? s->raw_gstart + gr : s->raw_start + v;
                    memcpy((g ? s->raw_gindex : s->raw_index) + start[0], rows_index + e, n * sizeof(uint16_t));
                    memcpy((g ? s->raw_gvalue : s->raw_value) + start[0], rows_value + e, n * sizeof(float));
                    start[1] = start[0] + n;
                }
                float scale;
                const uint32_t k = prt__spectral_quantize_row(rows_value + e, n, sb->d.drop_below, keep, q, &scale);
                if (at[g] + k > kept[g]) { st = prt__fail(base->ctx, PRT_ERR_IO, "the spectral transfer rows' scratch file changed under the bake"); break; }
                uint16_t *index = (g ? s->gindex : s->index) + at[g];
                int16_t *value = (g ? s->gvalue : s->value) + at[g];
                for (uint32_t i = 0; i < k; ++i) {
                    index[i] = rows_index[e + keep[i]];
                    value[i] = q[i];
                }
                at[g] += k;
                e += n;
                if (!g) {
                    s->row_start[v + 1] = at[0];
                    s->row_scale[v] = scale;
                } else {
                    s->grow_start[gr + 1] = at[1];
                    s->grow_scale[gr] = scale;
                }
            }
        }
    }
    free(keep);
    free(q);
    free(rindex);
    free(rvalue);
    if (st) return st;
    /* Room was made for every entry: give back what the drop threshold left over. */
    uint16_t *i16;
    int16_t *v16;
    if (at[0] && (i16 = realloc(s->index, at[0] * sizeof(uint16_t)))) s->index = i16;
    if (at[0] && (v16 = realloc(s->value, at[0] * sizeof(int16_t)))) s->value = v16;
    if (at[1] && (i16 = realloc(s->gindex, at[1] * sizeof(uint16_t)))) s->gindex = i16;
    if (at[1] && (v16 = realloc(s->gvalue, at[1] * sizeof(int16_t)))) s->gvalue = v16;
    return PRT_OK;
}

static void spectral_release(prt__bake_job *base)
{
    sbake *sb = (sbake *)base;
    prt__raycaster_release(&sb->rc);
    free(sb->origins);
    prt__emitters_free(&sb->emitters);
    if (sb->units)
        for (uint64_t u = 0; u < sb->unit_count; ++u) { free(sb->units[u].index); free(sb->units[u].value); }
    free(sb->units);
    free(sb->spilled);
    prt__spectral_spill_close(&sb->spill);
    for (int i = 0; i < sb->nscratch; ++i) {
        thread_scratch *sc = &sb->scratch[i];
        free(sc->weight); free(sc->gweight); free(sc->touched); free(sc->row); free(sc->index); free(sc->value); free(sc->keep); free(sc->q);
    }
    free(sb->scratch);
    free(sb);
}

void prt__spectral_memory(const prt_transfer *t, const prt__spectral_bake_desc *d, int threads, prt__memory_estimate *e)
{
    const uint64_t nv = t->mesh.vertex_count, T = threads > 0 ? (uint64_t)threads : 1;
    const uint64_t ps = d->full ? 1 : d->partition_size ? (uint64_t)d->partition_size : 1000;
    const uint64_t asked = d->full ? nv : d->functions ? (uint64_t)d->functions : 1024;
    /* The basis as basis.c cuts it: ceil(nv / ps) partitions, each its share of the functions by
     * vertex count, at least one (256 functions over 208 partitions are 208). */
    const uint64_t parts = nv ? (nv + ps - 1) / ps : 1;
    uint64_t per_part = d->full ? 1 : (asked + parts / 2) / parts;
    if (per_part < 1) per_part = 1;
    if (per_part > ps) per_part = ps;
    uint64_t F = parts * per_part;
    if (F > nv) F = nv;
    const uint64_t samples = d->samples ? (uint64_t)d->samples : 4096, order = d->env_order ? (uint64_t)d->env_order : 4;
    uint64_t glossy = 0;
    for (size_t v = 0; v < nv; ++v) {
        const uint8_t k = t->mesh.material[v];
        glossy += k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1]);
    }
    /* A row holds at most F entries, and at most what its rays reach: three vertices a hit, each
     * with the functions of its partition. Dense in a closed scene; open ones hold fewer (rays
     * that escape reach nothing), which the scene's size alone does not tell. */
    uint64_t entries = samples * 3 * per_part;
    if (entries > F) entries = F;
    const uint64_t rows = nv + glossy * PRT__SPECTRAL_GLOSSY_N, units = (nv + BLOCK - 1) / BLOCK, rows_per_vertex = glossy ? ROWS : 1;
    /* Every bake ends holding the quantized rows (4 bytes an entry, at most every entry), their
     * starts and scales; resident, the float rows (6) beside them and each block's counts; streamed,
     * a block read back at a time and a place in the scratch file per block. Raw rows (6) when kept. */
    const uint64_t quantized = rows * entries * 4 + rows * (8 + 4) + (d->keep_rows ? rows * entries * 6 + rows * 8 : 0);
    const uint64_t resident = rows * entries * 6 + units * sizeof(unit_rows);
    const uint64_t streamed = (uint64_t)BLOCK * rows_per_vertex * entries * 6 + units * sizeof(spilled_unit) + T * F * 6;
    /* The basis (each vertex's values, offsets, grouping) and each thread's dense eigen problem;
     * the environment transfer, the emitters' light; each thread's weights over every vertex, its
     * row of every function and a block's rows before they are copied out. */
    const uint64_t basis = nv * per_part * sizeof(float) + nv * (8 + 4 + 4) + T * ps * ps * sizeof(double);
    const uint64_t other = nv * order * order * sizeof(float) + glossy * PRT__SPECTRAL_GLOSSY_N * order * order * sizeof(float) +
                           (t->mesh.emission ? nv * 3 * sizeof(float) : 0) +
                           T * (nv * 8 + (glossy ? nv * PRT__SPECTRAL_GLOSSY_N * sizeof(float) : 0) + rows_per_vertex * F * sizeof(float) +
                                (uint64_t)BLOCK * rows_per_vertex * entries * 6);
    e->bytes = quantized + resident + basis + other;
    e->least = quantized + streamed + basis + other;
    snprintf(e->what, sizeof e->what, "rows of up to %llu of %llu basis functions for %llu vertices: %.0f MiB as floats, %.0f MiB quantized; %.0f MiB besides",
             (unsigned long long)entries, (unsigned long long)F, (unsigned long long)nv, (double)resident / 1048576.0, (double)quantized / 1048576.0,
             (double)(basis + other) / 1048576.0);
    snprintf(e->lower, sizeof e->lower, "a smaller --basis or fewer -j threads");
}

prt_status prt__spectral_bake_begin(prt_context *ctx, const prt__spectral_bake_desc *desc, prt_transfer *t, prt__bake_job **out)
{
    prt__spectral_bake_desc d = desc ? *desc : (prt__spectral_bake_desc){0};
    if (!d.partition_size) d.partition_size = 1000;
    if (!d.functions) d.functions = 1024;
    if (!d.samples) d.samples = 4096;
    if (!d.env_order) d.env_order = 4;
    if (d.partition_size < 16 || d.partition_size > PRT__SPECTRAL_MAX_PARTITION / 2)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "partition size %d out of range 16..%d", d.partition_size, PRT__SPECTRAL_MAX_PARTITION / 2);
    if (d.functions < 1 || d.functions > PRT__SPECTRAL_MAX_FUNCTIONS)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "basis functions %d out of range 1..%d", d.functions, PRT__SPECTRAL_MAX_FUNCTIONS);
    if (d.samples < 16 || d.samples > 1 << 20) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "samples %d out of range 16..1048576", d.samples);
    if (d.env_order < 1 || d.env_order > PRT_SH_MAX_ORDER) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "environment SH order %d out of range 1..%d", d.env_order, PRT_SH_MAX_ORDER);
    if (d.ray_offset < 0 || !isfinite(d.ray_offset)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ray offset must be >= 0");
    if (!(d.drop_below >= 0 && d.drop_below <= 0.1f)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--drop-below must lie in 0..0.1");
    const size_t nv = t->mesh.vertex_count;
    sbake *sb = prt__calloc(1, sizeof *sb);
    prt__spectral_set *s = prt__calloc(1, sizeof *s);
    if (!sb || !s) { free(sb); free(s); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    sb->base.stage = spectral_stage;
    sb->base.finish = spectral_finish;
    sb->base.release = spectral_release;
    sb->base.ctx = ctx;
    sb->d = d;
    sb->t = t;
    sb->s = s;
    t->state = s;   /* owned by t from here on */
    s->samples = d.samples;
    s->partition_size = d.full ? 1 : d.partition_size;
    s->env_order = d.env_order;
    s->ray_offset = d.ray_offset > 0 ? d.ray_offset : prt__ray_offset(&t->mesh);
    sb->unit_count = (nv + BLOCK - 1) / BLOCK;
    s->env = prt__calloc(nv * (size_t)d.env_order * d.env_order, sizeof(float));
    prt_status st = !s->env ? prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory") : PRT_OK;
    if (!st && t->mesh.emission) st = prt__emitters_init(&sb->emitters, &t->mesh, 1.0f);
    /* The scene's BRDF sets; glossy candidates need an SH projection, which only isotropic
     * BRDFs have. */
    const prt_scene *scene = d.scene;
    if (!st && scene && scene->brdf_set_count) {
        s->set = malloc((size_t)scene->brdf_set_count * sizeof *s->set);
        s->set_matrix = prt__calloc((size_t)scene->brdf_set_count, sizeof *s->set_matrix);
        if (!s->set || !s->set_matrix) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            memcpy(s->set, scene->brdf_set, (size_t)scene->brdf_set_count * sizeof *s->set);
            s->set_count = scene->brdf_set_count;
        }
        for (int i = 0; !st && i < s->set_count; ++i)
            if (prt_brdf_is_glossy(&s->set[i].brdf) && !prt_brdf_is_isotropic(&s->set[i].brdf)) {
                char spec[128];
                prt_brdf_format(&s->set[i].brdf, spec, sizeof spec);
                st = prt__fail(ctx, PRT_ERR_FORMAT, "surface '%s': the BRDF set's %s is anisotropic: the spectral glossy bounce projects "
                               "isotropic BRDFs only (the wavelet method factors anisotropic ones)", t->mesh.surface_names[s->set[i].surface - 1], spec);
            }
    }
    if (!st && !prt__spectral_glossy_index(t, s)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const size_t genv_n = (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N * d.env_order * d.env_order;
    if (!st && genv_n && !(s->genv = prt__calloc(genv_n, sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st && sb->emitters.count && !(s->emit = prt__calloc(nv * 3, sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__raycaster_create(ctx, &t->mesh, &sb->rc);
    if (!st) st = prt__vertex_origins(&t->mesh, s->ray_offset, &sb->origins);
    if (!st) st = prt__unbury_origins(ctx, &sb->rc, &t->mesh, s->ray_offset, sb->origins, NULL, PRT_LOG_INFO);
    if (st) { spectral_release(&sb->base); return st; }
    *out = &sb->base;
    return PRT_OK;
}
