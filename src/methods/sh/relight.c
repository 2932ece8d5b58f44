/* Run-time SH relighting: per vertex, exit radiance = transfer . lighting per channel.
 *
 * The transfer is vertex-major with n = order^2 floats per channel, n rarely a multiple of the
 * vector width. Each vertex is done with full 8-wide multiply-adds plus a scalar tail; the
 * kernels are instantiated per order so the compiler unrolls them completely. Vertices are split
 * statically across threads. */
#include "methods/sh/sh.h"
#include "prt/sh.h"

#include <immintrin.h>
#include <math.h>
#include <omp.h>
#include <string.h>

typedef float v8 __attribute__((vector_size(32)));

static inline v8 load8(const float *p)
{
    v8 v;
    memcpy(&v, p, sizeof v);   /* unaligned load */
    return v;
}

typedef float v4 __attribute__((vector_size(16)));

static inline v4 fold8(v8 v)
{
    v4 lo, hi;
    memcpy(&lo, &v, 16);
    memcpy(&hi, (const char *)&v + 16, 16);
    return lo + hi;
}

/* Horizontal sums of three vectors at once: {sum r, sum g, sum b, 0}, sharing the shuffles
 * (SSE unpacks rather than a compiler's generic shuffle, so gcc and clang both build it). */
static inline v4 hsum8x3(v8 r, v8 g, v8 b)
{
    const __m128 r4 = (__m128)fold8(r), g4 = (__m128)fold8(g), b4 = (__m128)fold8(b), z = _mm_setzero_ps();
    const __m128 rg = _mm_add_ps(_mm_unpacklo_ps(r4, g4), _mm_unpackhi_ps(r4, g4));   /* r0+r2 g0+g2 r1+r3 g1+g3 */
    const __m128 bz = _mm_add_ps(_mm_unpacklo_ps(b4, z), _mm_unpackhi_ps(b4, z));
    return (v4)_mm_add_ps(_mm_movelh_ps(rg, bz), _mm_movehl_ps(bz, rg));
}

/* One-channel sets: the same n coefficients dot three lighting vectors, times albedo. */
static inline __attribute__((always_inline)) void relight1(const float *restrict coeffs, const float *restrict albedo,
                                                            const float (*restrict light)[PRT_SH_MAX_COEFFS + 8], int stride,
                                                            int n, long v0, long v1, float *restrict out)
{
    const int full = n & ~7;
    for (long v = v0; v < v1; ++v) {
        const float *t = coeffs + (size_t)v * stride;
        v8 r = {0}, g = {0}, b = {0};
        for (int i = 0; i < full; i += 8) {
            v8 x = load8(t + i);
            r += x * load8(light[0] + i);
            g += x * load8(light[1] + i);
            b += x * load8(light[2] + i);
        }
        v4 sum = hsum8x3(r, g, b);
        for (int i = full; i < n; ++i) sum += t[i] * (v4){light[0][i], light[1][i], light[2][i], 0};
        out[v * 3] = sum[0] * albedo[v * 3];
        out[v * 3 + 1] = sum[1] * albedo[v * 3 + 1];
        out[v * 3 + 2] = sum[2] * albedo[v * 3 + 2];
    }
}

/* Three-channel sets: channel c's n coefficients dot lighting channel c. */
static inline __attribute__((always_inline)) void relight3(const float *restrict coeffs,
                                                            const float (*restrict light)[PRT_SH_MAX_COEFFS + 8], int stride,
                                                            int n, long v0, long v1, float *restrict out)
{
    const int full = n & ~7;
    for (long v = v0; v < v1; ++v) {
        const float *t = coeffs + (size_t)v * 3 * stride;
        v8 acc[3] = {{0}, {0}, {0}};
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < full; i += 8) acc[c] += load8(t + c * stride + i) * load8(light[c] + i);
        v4 sum = hsum8x3(acc[0], acc[1], acc[2]);
        for (int i = full; i < n; ++i) sum += (v4){t[i], t[stride + i], t[2 * stride + i], 0} * (v4){light[0][i], light[1][i], light[2][i], 0};
        out[v * 3] = sum[0];
        out[v * 3 + 1] = sum[1];
        out[v * 3 + 2] = sum[2];
    }
}

/* Instantiates both kernels for a compile-time n. */
#define DISPATCH(N)                                                               \
    case N:                                                                       \
        if (ch == 1) relight1(coeffs, albedo, (const float (*)[PRT_SH_MAX_COEFFS + 8])lt, stride, N, v0, v1, out_rgb); \
        else relight3(coeffs, (const float (*)[PRT_SH_MAX_COEFFS + 8])lt, stride, N, v0, v1, out_rgb);                 \
        break;

/* Compressed sets: project every cluster mean and PCA vector on the lighting once (a few
 * thousand dot products), then each vertex is its mean's value plus a short weighted sum. */
static prt_status relight_cpca(prt_context *ctx, const prt_transfer *t, const prt__sh_set *set, const float (*light)[PRT_SH_MAX_COEFFS + 8],
                               int n, float *out)
{
    const prt__cpca *c = set->cpca;
    const prt__sh_state *sh = t->state;
    const int stride = sh->order * sh->order, ch = set->channels;
    const size_t rows = (size_t)c->clusters + c->vectors_total;
    v4 *proj = malloc(rows * sizeof(v4));   /* [cluster means..., vectors...] x {r, g, b, 0} */
    if (!proj) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (size_t r = 0; r < rows; ++r) {
        const float *x = r < (size_t)c->clusters ? c->means + r * c->dim : c->basis + (r - (size_t)c->clusters) * c->dim;
        v4 p = {0, 0, 0, 0};
        for (int l = 0; l < 3; ++l) {
            const float *seg = x + (ch == 3 ? l * stride : 0);
            float s = 0;
            for (int i = 0; i < n; ++i) s += seg[i] * light[l][i];
            p[l] = s;
        }
        proj[r] = p;
    }
    const float *albedo = t->mesh.albedo;
    const long nv = (long)t->mesh.vertex_count;
#pragma omp parallel for schedule(static) num_threads(nv < 4096 ? 1 : prt__threads(ctx))
    for (long v = 0; v < nv; ++v) {
        uint32_t k = c->cluster_of[v];
        const float *w = c->weights + c->weight_start[v];
        const v4 *b = proj + (size_t)c->clusters + c->basis_start[k];
        /* Two running sums halve the dependency chain of the multiply-adds. */
        v4 acc = proj[k], acc2 = {0, 0, 0, 0};
        const uint32_t cnt = c->counts[k];
        uint32_t j = 0;
        for (; j + 1 < cnt; j += 2) {
            acc += w[j] * b[j];
            acc2 += w[j + 1] * b[j + 1];
        }
        if (j < cnt) acc += w[j] * b[j];
        acc += acc2;
        if (ch == 1) { acc[0] *= albedo[v * 3]; acc[1] *= albedo[v * 3 + 1]; acc[2] *= albedo[v * 3 + 2]; }
        out[v * 3] = acc[0];
        out[v * 3 + 1] = acc[1];
        out[v * 3 + 2] = acc[2];
    }
    free(proj);
    return PRT_OK;
}

prt_status prt_relight_sh(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light, float *out_rgb)
{
    if (!t || !light || !out_rgb) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_relight_sh: transfer, light and output are required");
    const prt__sh_state *sh = prt__sh_need(ctx, t);
    if (!sh) return PRT_ERR_INVALID_ARG;
    int k = prt__kind_index(kind);
    if (k < 0 || !sh->sets[k].channels)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer holds no %s set", prt_transfer_kind_name(kind));
    if (prt__kind_glossy(k))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s is view-dependent: relight it with prt_relight_sh_glossy", prt_transfer_kind_name(kind));
    if (light->order < 1 || light->order > PRT_SH_MAX_ORDER)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "lighting SH order %d out of range", light->order);
    const int stride = sh->order * sh->order;
    const int order = light->order < sh->order ? light->order : sh->order;
    const int n = order * order, ch = sh->sets[k].channels;
    const float *coeffs = sh->sets[k].coeffs, *albedo = t->mesh.albedo;
    const long nv = (long)t->mesh.vertex_count;
    /* Zero-padded so vector loads of the lighting may run past n. */
    float lt[3][PRT_SH_MAX_COEFFS + 8];
    memset(lt, 0, sizeof lt);
    for (int c = 0; c < 3; ++c) memcpy(lt[c], light->coeffs[c], (size_t)n * sizeof(float));
    if (sh->sets[k].cpca) return relight_cpca(ctx, t, &sh->sets[k], lt, n, out_rgb);
    const int threads = prt__threads(ctx);
    /* Below a few thousand vertices a thread team costs more than it saves. */
    const int team = nv < 4096 ? 1 : threads;
#pragma omp parallel num_threads(team)
    {
        int tid = omp_get_thread_num(), nt = omp_get_num_threads();
        long v0 = nv * tid / nt, v1 = nv * (tid + 1) / nt;
        switch (n) {
            DISPATCH(1) DISPATCH(4) DISPATCH(9) DISPATCH(16) DISPATCH(25)
            DISPATCH(36) DISPATCH(49) DISPATCH(64) DISPATCH(81) DISPATCH(100)
        }
    }
    return PRT_OK;
}

/* Vertex v's transfer vector of set s (dim floats), reconstructed when compressed. */
static const float *set_row(const prt__sh_set *s, size_t v, size_t dim, float *buf)
{
    if (!s->cpca) return s->coeffs + v * dim;
    const prt__cpca *c = s->cpca;
    const uint32_t cl = c->cluster_of[v];
    memcpy(buf, c->means + (size_t)cl * dim, dim * sizeof(float));
    for (uint32_t j = 0; j < c->counts[cl]; ++j) {
        const float w = c->weights[c->weight_start[v] + j], *b = c->basis + (c->basis_start[cl] + j) * dim;
        for (size_t i = 0; i < dim; ++i) buf[i] += w * b[i];
    }
    return buf;
}

/* SH transfer holds visibility to infinity, so a light inside the scene (a lamp in a room, a bulb
 * under a roof) lies in directions the transfer finds blocked beyond the light, and would light
 * nothing. Over up to REACH_VERTICES vertices that face a light and see it (a shadow ray), the
 * transfer's response to a delta towards it (pi T(w) / albedo: 1 unoccluded, as cos) is compared
 * with the cosine; a light that gets under a quarter of it on average is refused, naming it,
 * rather than drawn dark. Files holding only glossy matrices (no diffuse response to read) ask
 * the geometry the same question: is the way on from the light, beyond it, open? */
#define REACH_VERTICES 512
#define REACH_LEAST 0.25

prt_status prt__sh_local_reach(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, bool leave_out, uint8_t *out)
{
    const prt__sh_state *sh = t->state;
    int k = sh->sets[1].channels ? 1 : sh->sets[2].channels ? 2 : -1;   /* shadowed, else inter-reflected */
    const bool geometric = k < 0 && (sh->sets[3].channels || sh->sets[4].channels);   /* glossy only */
    const prt__mesh *m = &t->mesh;
    if (out) memset(out, 0, (size_t)prt_lighting_count(l));
    /* At order 1 an open light's response is a quarter of its cosine overhead: nothing to tell.
     * Unshadowed transfer holds no visibility: every light reaches. */
    if ((k < 0 && !geometric) || sh->order < 2 || !m->normals || !m->vertex_count) return PRT_OK;
    if (geometric) k = sh->sets[3].channels ? 3 : 4;
    const prt__sh_set *s = &sh->sets[k];
    const int stride = sh->order * sh->order, ch = s->channels;
    const size_t dim = prt__set_dim(sh, k), nv = m->vertex_count, step = nv > REACH_VERTICES ? nv / REACH_VERTICES : 1;
    /* The mesh in Embree once per transfer: a viewer relights on every drag of a lamp. */
    prt__sh_state *state = t->state;
    prt_status st = PRT_OK;
    pthread_mutex_lock(state->lock);
    if (!state->rays_ready && !(st = prt__raycaster_create(ctx, m, &state->rays))) state->rays_ready = true;
    pthread_mutex_unlock(state->lock);
    if (st) return st;
    const prt__raycaster *rc = &state->rays;
    const float off = prt__ray_offset(m);
    for (int i = 0; !st && i < prt_lighting_count(l); ++i) {
        const prt_light *li = prt_lighting_light(l, i);
        if (!prt__sh_light_positioned(li)) continue;
        double sum = 0;
        size_t n = 0;
        for (size_t v = 0; v < nv; v += step) {
            const float *p = m->positions + v * 3, *nr = m->normals + v * 3;
            float d[3] = {li->position[0] - p[0], li->position[1] - p[1], li->position[2] - p[2]};
            const float r = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(r > 2 * off)) continue;
            for (int c = 0; c < 3; ++c) d[c] /= r;
            const float cosine = d[0] * nr[0] + d[1] * nr[1] + d[2] * nr[2];
            if (cosine < 0.3f) continue;
            const float o[3] = {p[0] + nr[0] * off, p[1] + nr[1] * off, p[2] + nr[2] * off};
            const float radius = li->type == PRT_LIGHT_SPHERE ? li->radius : 0.0f;
            if (prt__raycaster_occluded(rc, o, d, r - 2 * off - radius)) continue;
            if (geometric) {
                const float beyond[3] = {li->position[0] + d[0] * (radius + off), li->position[1] + d[1] * (radius + off), li->position[2] + d[2] * (radius + off)};
                sum += prt__raycaster_occluded(rc, beyond, d, INFINITY) ? 0.0 : 1.0;
                n++;
                continue;
            }
            float buf[3 * PRT_SH_MAX_COEFFS], y[PRT_SH_MAX_COEFFS];
            const float *T = set_row(s, v, dim, buf);
            prt_sh_eval_f(sh->order, d, y);
            double resp = 0, albedo = 0;
            for (int c = 0; c < (ch == 3 ? 3 : 1); ++c) {
                for (int j = 0; j < stride; ++j) resp += (double)T[c * stride + j] * y[j];
                albedo += ch == 3 ? m->albedo[v * 3 + c] : 1.0;
            }
            if (albedo > 0) { sum += PRT_PI * resp / albedo / cosine; n++; }
        }
        if (!(n >= 8 && sum / (double)n < REACH_LEAST)) continue;
        char why[400];
        snprintf(why, sizeof why, "light %d (%s at %g, %g, %g) is inside the scene where SH transfer cannot carry it: from most vertices that see it, "
                 "the transfer finds the way towards it blocked beyond it (%.0f%% of its light gets through on average; a room, a roof, a wall behind "
                 "it), for SH transfer holds visibility to infinity", i + 1, prt_light_type_name(li->type), li->position[0], li->position[1],
                 li->position[2], 100 * sum / (double)n);
        if (leave_out) {
            prt__log(ctx, PRT_LOG_WARN, "%s: left out (bake with --method spectral, lightcloud or offset for lights inside a scene)", why);
            if (out) out[i] = 1;
        } else {
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s: bake with --method spectral, lightcloud or offset for lights inside a scene (--light none "
                           "leaves the lights out)", why);
        }
    }
    return st;
}

/* Local lights differ per vertex, so each vertex dots its own lighting: n multiply-adds per
 * channel, as cheap as the distant lighting's kernel without its vector tricks. */
prt_status prt__relight_sh_local(prt_context *ctx, const prt_transfer *t, int k, const float *local, int order, float *out_rgb)
{
    const prt__sh_state *sh = prt__sh_need(ctx, t);
    if (!sh) return PRT_ERR_INVALID_ARG;
    const prt__sh_set *s = &sh->sets[k];
    if (k < 0 || k > 2 || !s->channels || order < 1 || order > sh->order)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "local lights: no diffuse set %d at order %d", k, order);
    const int stride = sh->order * sh->order, n = order * order, ch = s->channels;
    const size_t dim = prt__set_dim(sh, k);
    const float *albedo = t->mesh.albedo;
    const long nv = (long)t->mesh.vertex_count;
#pragma omp parallel for schedule(static) num_threads(nv < 4096 ? 1 : prt__threads(ctx))
    for (long v = 0; v < nv; ++v) {
        float buf[3 * PRT_SH_MAX_COEFFS];
        const float *T = set_row(s, (size_t)v, dim, buf), *L = local + (size_t)v * 3 * n;
        for (int c = 0; c < 3; ++c) {
            const float *Tc = T + (ch == 3 ? c * stride : 0), *Lc = L + c * n;
            float sum = 0.0f;
            for (int i = 0; i < n; ++i) sum += Tc[i] * Lc[i];
            out_rgb[v * 3 + c] += ch == 1 ? sum * albedo[v * 3 + c] : sum;
        }
    }
    return PRT_OK;
}
