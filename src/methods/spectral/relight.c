/* Run time of the spectral method: direct light per vertex from every kind of light, then
 * bounces through the spectral basis (Wang, Zhu & Humphreys 2007, eq. 4 and the multi-bounce
 * gathering after it): project the outgoing radiance onto the basis, multiply by the sparse
 * T^s (each row's 16-bit entries times its scale), apply each vertex's albedo / pi, repeat; then, by default, the rest of the series as a
 * geometric tail (add_tail).
 *
 * Direct light: point, spot and directional lights with one shadow ray per vertex; sphere lights
 * exactly unoccluded times the visible fraction of their cone (16 rays); emissive surfaces and the
 * environment through what the bake stored per vertex (emitters' irradiance at scale 1, shadowed
 * SH transfer). Shadow rays need the mesh in Embree: built on first use and kept. */
#include "methods/spectral/spectral.h"
#include "brdf/sh_matrix.h"
#include "light/envmap_internal.h"

#include <omp.h>

prt_status prt__spectral_visibility(prt_context *ctx, const prt_transfer *t, const prt_light *lights, int count, float *vis)
{
    const prt__spectral_set *s = t->state;
    prt_status st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, &s->cache->lights);
    if (!st) prt__vertex_lights_visibility(ctx, &s->cache->lights, &t->mesh, lights, count, vis);
    return st;
}

prt_status prt__spectral_env_sh(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, prt_sh_light *sh)
{
    const prt__spectral_set *s = t->state;
    memset(sh, 0, sizeof *sh);
    const prt_envmap *env = prt_lighting_envmap(l);
    if (!env || !(prt_lighting_intensity(l) > 0)) return PRT_OK;
    prt_status st = prt__envmap_project_sh_cached(env, s->env_order, sh);
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    double rot[9];
    prt_lighting_rotation(l, rot);
    if (!(rot[0] == 1 && rot[4] == 1 && rot[8] == 1) && (st = prt_sh_light_rotate(sh, rot))) return st;
    prt_sh_light_scale(sh, prt_lighting_intensity(l));
    return PRT_OK;
}

prt_status prt__spectral_direct(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, float *E, float *pixel, int pixel_count)
{
    const prt__spectral_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    prt_status st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, &s->cache->lights);
    if (st) return st;
    const prt__vertex_lights *c = &s->cache->lights;
    memset(E, 0, nv * 3 * sizeof(float));
    /* The environment through the baked visibility. */
    prt_sh_light sh;
    if ((st = prt__spectral_env_sh(ctx, t, l, &sh))) return st;
    if (sh.order) {
        const int nc = s->env_order * s->env_order;
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
        for (size_t v = 0; v < nv; ++v) {
            const float *tv = s->env + v * (size_t)nc;
            for (int k = 0; k < 3; ++k) {
                float sum = 0.0f;
                for (int i = 0; i < nc; ++i) sum += sh.coeffs[k][i] * tv[i];
                E[v * 3 + k] = sum > 0.0f ? sum : 0.0f;   /* ringing of the truncated SH can dip below zero */
            }
        }
    }
    const int count = prt_lighting_count(l);
    if (count) {
#pragma omp parallel for schedule(dynamic, 256) num_threads(prt__threads(ctx))
        for (size_t v = 0; v < nv; ++v)
            for (int i = 0; i < count; ++i) {
                float e[3];
                prt__vertex_light_at(c, &t->mesh, v, prt_lighting_light(l, i), e);
                for (int k = 0; k < 3; ++k) E[v * 3 + k] += e[k];
                if (pixel && i < pixel_count)
                    for (int k = 0; k < 3; ++k) pixel[v * 3 + k] += e[k];
            }
    }
    const float emission = prt_lighting_emission(l);
    if (s->emit && emission > 0)
        for (size_t i = 0; i < nv * 3; ++i) E[i] += emission * s->emit[i];
    return prt__cancelled(ctx) ? prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled") : PRT_OK;
}

/* Area-weighted sums of one bounce's radiance per channel: per partition in parallel, each
 * partition in a fixed order, then the partitions in order - the same for any thread count. */
static void bounce_power(const prt__spectral_basis *b, const float *area, const float *x, double *part, double out[3], int threads)
{
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
    for (uint32_t q = 0; q < b->partitions; ++q) {
        double a[3] = {0, 0, 0};
        for (uint32_t i = b->member_start[q]; i < b->member_start[q + 1]; ++i) {
            const uint32_t v = b->members[i];
            for (int c = 0; c < 3; ++c) a[c] += (double)area[v] * x[(size_t)v * 3 + c];
        }
        for (int c = 0; c < 3; ++c) part[(size_t)q * 3 + c] = a[c];
    }
    out[0] = out[1] = out[2] = 0;
    for (uint32_t q = 0; q < b->partitions; ++q)
        for (int c = 0; c < 3; ++c) out[c] += part[(size_t)q * 3 + c];
}

/* The rest of the series past the last bounce b_k, as a geometric one: power q / (1 - q) times
 * b_k's, with q the ratio of the last two bounces' power (area-weighted sums, per channel). In a
 * closed room of uniform albedo every bounce keeps that albedo of the power, so q is exact there;
 * ratios per vertex or per partition mislead where light is still spreading (a closed room of
 * albedo 0.7: 18% and 4% off 64 bounces, against 2.6% for one ratio for the whole mesh). q is
 * capped at 0.95 (a tail of 19 times the last bounce); a dark last-but-one bounce gives none. */
void prt__spectral_vertex_areas(const prt__mesh *m, float *area)
{
    for (size_t i = 0; i < m->triangle_count; ++i) {
        const uint32_t *ix = m->indices + i * 3;
        const float *p0 = m->positions + (size_t)ix[0] * 3, *p1 = m->positions + (size_t)ix[1] * 3, *p2 = m->positions + (size_t)ix[2] * 3;
        const float u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, w[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        const float cx = u[1] * w[2] - u[2] * w[1], cy = u[2] * w[0] - u[0] * w[2], cz = u[0] * w[1] - u[1] * w[0];
        const float third = sqrtf(cx * cx + cy * cy + cz * cz) / 6.0f;
        for (int k = 0; k < 3; ++k) area[ix[k]] += third;
    }
}

static prt_status add_tail(prt_context *ctx, const prt_transfer *t, const float *before, const float *last, float *indirect_out)
{
    const prt__spectral_basis *b = &((const prt__spectral_set *)t->state)->basis;
    const prt__mesh *m = &t->mesh;
    const size_t nv = m->vertex_count;
    float *area = prt__calloc(nv, sizeof(float));   /* a third of each triangle's area to each corner */
    double *part = prt__calloc((size_t)b->partitions * 3, sizeof(double));
    if (!area || !part) { free(area); free(part); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    prt__spectral_vertex_areas(m, area);
    double p_before[3], p_last[3];
    bounce_power(b, area, before, part, p_before, prt__threads(ctx));
    bounce_power(b, area, last, part, p_last, prt__threads(ctx));
    float f[3];
    for (int c = 0; c < 3; ++c) {
        double q = p_before[c] > 0 ? p_last[c] / p_before[c] : 0.0;
        q = q > PRT__SPECTRAL_TAIL_MAX_RATIO ? PRT__SPECTRAL_TAIL_MAX_RATIO : q > 0 ? q : 0.0;
        f[c] = (float)(q / (1.0 - q));
    }
    /* Shaped per vertex by the square root of its own ratio of the last two bounces, then scaled
     * to the power above: where light still arrives (its ratio above q) the tail grows, where it
     * drains (near the lights) it shrinks - half a step towards the next bounce's shape. Against
     * 64 bounces in closed rooms of albedo 0.5 / 0.7 / 0.8: 0.3% / 1.2% / 2.1% instead of 0.8% /
     * 2.6% / 4.2% with the last bounce's own shape. The weights are at most the last bounce. */
    float *w = prt__calloc(nv * 3, sizeof(float));
    if (!w) { free(area); free(part); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (size_t i = 0; i < nv * 3; ++i) {
        const float r = before[i] > 0 ? fminf(last[i] / before[i], (float)PRT__SPECTRAL_TAIL_MAX_RATIO) : 0.0f;
        w[i] = last[i] * sqrtf(r);
    }
    double p_w[3];
    bounce_power(b, area, w, part, p_w, prt__threads(ctx));
    const float cap = (float)(PRT__SPECTRAL_TAIL_MAX_RATIO / (1.0 - PRT__SPECTRAL_TAIL_MAX_RATIO));
    for (int c = 0; c < 3; ++c) f[c] = p_w[c] > 0 ? fminf((float)(f[c] * p_last[c] / p_w[c]), cap) : 0.0f;
    for (size_t v = 0; v < nv; ++v)
        for (int c = 0; c < 3; ++c) indirect_out[v * 3 + c] += f[c] * w[v * 3 + c];
    free(w);
    free(area);
    free(part);
    return PRT_OK;
}

prt_status prt__spectral_bounces(prt_context *ctx, const prt_transfer *t, const float *albedo, const float *direct_out, int bounces, int tail,
                                 float *indirect_out)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    const size_t nv = t->mesh.vertex_count;
    memset(indirect_out, 0, nv * 3 * sizeof(float));
    if (bounces <= 0) return PRT_OK;
    float *coeffs = prt__calloc((size_t)b->functions * 3, sizeof(float));
    float *cur = prt__calloc(nv * 3, sizeof(float)), *prev = tail ? prt__calloc(nv * 3, sizeof(float)) : NULL;
    if (!coeffs || !cur || (tail && !prev)) { free(coeffs); free(cur); free(prev); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    const float *from = direct_out;
    for (int bounce = 0; bounce < bounces; ++bounce) {
        prt__spectral_project(b, from, coeffs, prt__threads(ctx));
        /* The tail compares the last two bounces: keep the one this bounce starts from. */
        if (tail && bounce == bounces - 1) memcpy(prev, from, nv * 3 * sizeof(float));
        /* Each vertex gathers its row of T^s; the next bounce starts from what it reflects. */
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
        for (size_t v = 0; v < nv; ++v) {
            float e0 = 0, e1 = 0, e2 = 0;
            for (uint64_t i = s->row_start[v]; i < s->row_start[v + 1]; ++i) {
                const float q = s->value[i];
                const float *c = coeffs + (size_t)s->index[i] * 3;
                e0 += q * c[0];
                e1 += q * c[1];
                e2 += q * c[2];
            }
            const float *rho = albedo + v * 3, k = s->row_scale[v] / (float)PRT_PI;
            cur[v * 3 + 0] = rho[0] * k * (e0 > 0 ? e0 : 0);
            cur[v * 3 + 1] = rho[1] * k * (e1 > 0 ? e1 : 0);
            cur[v * 3 + 2] = rho[2] * k * (e2 > 0 ? e2 : 0);
        }
        for (size_t i = 0; i < nv * 3; ++i) indirect_out[i] += cur[i];
        from = cur;
        if (prt__cancelled(ctx)) break;
    }
    prt_status st = prt__cancelled(ctx) ? prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled") : PRT_OK;
    if (!st && tail) st = add_tail(ctx, t, prev, cur, indirect_out);
    free(coeffs);
    free(cur);
    free(prev);
    return st;
}

/* The glossy vertices' frame rotations, built once. */
static prt_status glossy_ready(prt_context *ctx, const prt_transfer *t, prt__spectral_cache *c)
{
    const prt__spectral_set *s = t->state;
    pthread_mutex_lock(&c->lock);
    prt_status st = PRT_OK;
    if (!c->frames) {
        prt__frame_rot *fr = prt__calloc(s->glossy_count, sizeof *fr);
        if (!fr) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        for (size_t v = 0; v < t->mesh.vertex_count && !st; ++v)
            if (s->glossy_of[v] != UINT32_MAX && prt__frame_rot_create(PRT__SPECTRAL_GLOSSY_ORDER, t->mesh.normals + v * 3, &fr[s->glossy_of[v]]))
                st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (st) {
            for (uint32_t g = 0; fr && g < s->glossy_count; ++g) prt__frame_rot_release(&fr[g]);
            free(fr);
        } else {
            c->frames = fr;
        }
    }
    pthread_mutex_unlock(&c->lock);
    return st;
}

prt_status prt__spectral_glossy(prt_context *ctx, const prt_transfer *t, const float *out, const prt_sh_light *env, const int *brdf_of,
                                 float *exit_sh)
{
    const prt__spectral_set *s = t->state;
    const size_t nv = t->mesh.vertex_count, n = PRT__SPECTRAL_GLOSSY_N;
    memset(exit_sh, 0, nv * 3 * n * sizeof(float));
    if (!s->glossy_count) return PRT_OK;
    prt_status st = glossy_ready(ctx, t, s->cache);
    if (st) return st;
    float *coeffs = prt__calloc((size_t)s->basis.functions * 3, sizeof(float));
    if (!coeffs) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__spectral_project(&s->basis, out, coeffs, prt__threads(ctx));
    const prt__frame_rot *frames = s->cache->frames;
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v) {
        const uint32_t g = s->glossy_of[v];
        const float *B = g == UINT32_MAX ? NULL : prt__spectral_matrix_of(t, brdf_of, v);
        if (!B) continue;   /* diffuse, or a surface switched to a diffuse candidate */
        /* Incident radiance in SH (world frame), per channel, then the BRDF's exit radiance. */
        float in[3][PRT__SPECTRAL_GLOSSY_N];
        for (size_t k = 0; k < n; ++k) {
            const size_t row = (size_t)g * n + k;
            float a = 0, b = 0, d = 0;
            for (uint64_t i = s->grow_start[row]; i < s->grow_start[row + 1]; ++i) {
                const float q = s->gvalue[i], *x = coeffs + (size_t)s->gindex[i] * 3;
                a += q * x[0]; b += q * x[1]; d += q * x[2];
            }
            const float scale = s->grow_scale[row];
            in[0][k] = a * scale;
            in[1][k] = b * scale;
            in[2][k] = d * scale;
        }
        if (env && env->order == s->env_order && s->genv) {   /* the environment, shadowed */
            const int nc = s->env_order * s->env_order;
            const float *G = s->genv + (size_t)g * n * nc;
            for (size_t k = 0; k < n; ++k)
                for (int c = 0; c < 3; ++c) {
                    float sum = 0.0f;
                    for (int i = 0; i < nc; ++i) sum += G[k * nc + i] * env->coeffs[c][i];
                    in[c][k] += sum;
                }
        }
        for (int c = 0; c < 3; ++c) prt__apply_brdf(&frames[g], B, c, PRT__SPECTRAL_GLOSSY_ORDER, in[c], exit_sh + (v * 3 + (size_t)c) * n, 1);
    }
    free(coeffs);
    return PRT_OK;
}
