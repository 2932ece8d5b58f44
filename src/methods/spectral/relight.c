/* Run time of the spectral method: direct light per vertex from every kind of light, then
 * bounces through the spectral basis (Wang, Zhu & Humphreys 2007, eq. 4 and the multi-bounce
 * gathering after it): project the outgoing radiance onto the basis, multiply by the sparse
 * T^s (each row's 16-bit entries times its scale), apply each vertex's albedo / pi, repeat.
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

prt_status prt__spectral_bounces(prt_context *ctx, const prt_transfer *t, const float *albedo, const float *direct_out, int bounces,
                                 float *indirect_out)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    const size_t nv = t->mesh.vertex_count;
    memset(indirect_out, 0, nv * 3 * sizeof(float));
    if (bounces <= 0) return PRT_OK;
    float *coeffs = prt__calloc((size_t)b->functions * 3, sizeof(float));
    float *cur = prt__calloc(nv * 3, sizeof(float));
    if (!coeffs || !cur) { free(coeffs); free(cur); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    const float *from = direct_out;
    for (int bounce = 0; bounce < bounces; ++bounce) {
        prt__spectral_project(b, from, coeffs, prt__threads(ctx));
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
    free(coeffs);
    free(cur);
    return prt__cancelled(ctx) ? prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled") : PRT_OK;
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
