/* Direct light of local lights at mesh vertices: one shadow ray per point, spot and directional
 * light; sphere lights exactly unoccluded times the visible fraction of their cone. Rays start
 * from each vertex moved off its surface (prt__vertex_origins). */
#include "light/vertex_lights.h"
#include "light/light_sample.h"

#include <omp.h>

#define SPHERE_RAYS 16

void prt__vertex_lights_init(prt__vertex_lights *c)
{
    memset(c, 0, sizeof *c);
    pthread_mutex_init(&c->lock, NULL);
}

void prt__vertex_lights_free(prt__vertex_lights *c)
{
    prt__raycaster_release(&c->rc);
    free(c->origins);
    c->origins = NULL;
    c->ready = false;
    pthread_mutex_destroy(&c->lock);
}

prt_status prt__vertex_lights_ready(prt_context *ctx, const prt__mesh *m, float ray_offset, prt__vertex_lights *c)
{
    pthread_mutex_lock(&c->lock);
    prt_status st = PRT_OK;
    if (!c->ready) {
        st = prt__raycaster_create(ctx, m, &c->rc);
        if (!st) st = prt__vertex_origins(m, ray_offset, &c->origins);
        if (!st) st = prt__unbury_origins(ctx, &c->rc, m, ray_offset, c->origins, NULL, PRT_LOG_DEBUG);   /* the bake said */
        if (st) {
            prt__raycaster_release(&c->rc);
            free(c->origins);
            c->origins = NULL;
        } else {
            c->ready = true;
        }
    }
    pthread_mutex_unlock(&c->lock);
    return st;
}

bool prt__vertex_lights_occluded(const prt__vertex_lights *c, const float o[3], const float d[3], float tfar)
{
    return prt__raycaster_occluded(&c->rc, o, d, tfar);
}

/* Whether the light point p + wi dist is hidden from the ray origin o (the vertex moved off its
 * surface); dist INFINITY for distant light. */
static bool shadowed(const prt__vertex_lights *c, const float p[3], const float o[3], const float wi[3], float dist)
{
    if (!isfinite(dist)) return prt__vertex_lights_occluded(c, o, wi, INFINITY);
    float d[3];
    for (int k = 0; k < 3; ++k) d[k] = p[k] + wi[k] * dist - o[k];
    const float len = prt__v3_len(d);
    return len > 0.0f && prt__v3_normalize(d) && prt__vertex_lights_occluded(c, o, d, len * (1.0f - 1e-4f));
}

void prt__vertex_light_at(const prt__vertex_lights *c, const prt__mesh *m, size_t v, const prt_light *l, float e[3])
{
    const float *p = m->positions + v * 3, *o = c->origins + v * 3, *n = m->normals + v * 3;
    e[0] = e[1] = e[2] = 0.0f;
    if (l->type != PRT_LIGHT_SPHERE) {
        prt__light_sample s;
        if (!prt__light_sample_from(l, p, 0.5, 0.5, &s)) return;
        const float cosine = prt__v3_dot(s.wi, n);
        if (cosine <= 0.0f || shadowed(c, p, o, s.wi, s.dist)) return;
        for (int k = 0; k < 3; ++k) e[k] = cosine * s.value[k];
        return;
    }
    float exact[3];
    prt_light_irradiance(l, p, n, exact);
    if (exact[0] <= 0 && exact[1] <= 0 && exact[2] <= 0) return;
    double seen = 0.0, all = 0.0;
    for (int i = 0; i < SPHERE_RAYS; ++i) {
        double u1, u2;
        prt__sobol2((uint32_t)i, (uint32_t)v * 2654435761u, &u1, &u2);
        prt__light_sample s;
        if (!prt__light_sample_from(l, p, u1, u2, &s)) continue;
        const float cosine = prt__v3_dot(s.wi, n);
        if (cosine <= 0.0f) continue;
        all += cosine;
        if (!shadowed(c, p, o, s.wi, s.dist)) seen += cosine;
    }
    const float f = all > 0 ? (float)(seen / all) : 0.0f;
    for (int k = 0; k < 3; ++k) e[k] = exact[k] * f;
}

float prt__vertex_light_visibility(const prt__vertex_lights *c, const prt__mesh *m, size_t v, const prt_light *l)
{
    const float *p = m->positions + v * 3, *o = c->origins + v * 3;
    if (l->type == PRT_LIGHT_DIRECTIONAL) return prt__vertex_lights_occluded(c, o, l->direction, INFINITY) ? 0.0f : 1.0f;
    prt_light bare = *l;
    if (l->type == PRT_LIGHT_SPOT) bare.type = PRT_LIGHT_POINT;
    if (l->type == PRT_LIGHT_IES) {   /* visibility only: any colour that is not black */
        bare.type = PRT_LIGHT_POINT;
        bare.intensity[0] = bare.intensity[1] = bare.intensity[2] = 1.0f;
    }
    const int samples = l->type == PRT_LIGHT_SPHERE ? SPHERE_RAYS : 1;
    int seen = 0, tried = 0;
    for (int i = 0; i < samples; ++i) {
        double u1 = 0.5, u2 = 0.5;
        if (samples > 1) prt__sobol2((uint32_t)i, (uint32_t)v * 2654435761u, &u1, &u2);
        prt__light_sample s;
        if (!prt__light_sample_from(&bare, p, u1, u2, &s)) continue;
        tried++;
        seen += !shadowed(c, p, o, s.wi, s.dist);
    }
    return tried ? (float)seen / (float)tried : 0.0f;
}

void prt__vertex_lights_add(prt_context *ctx, const prt__vertex_lights *c, const prt__mesh *m, const prt_light *lights, int count, float *E)
{
    const size_t nv = m->vertex_count;
#pragma omp parallel for schedule(dynamic, 256) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v)
        for (int i = 0; i < count; ++i) {
            float e[3];
            prt__vertex_light_at(c, m, v, &lights[i], e);
            for (int k = 0; k < 3; ++k) E[v * 3 + k] += e[k];
        }
}

void prt__vertex_lights_visibility(prt_context *ctx, const prt__vertex_lights *c, const prt__mesh *m, const prt_light *lights, int count,
                                   float *vis)
{
    const size_t nv = m->vertex_count;
#pragma omp parallel for schedule(dynamic, 256) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v)
        for (int i = 0; i < count; ++i) vis[(size_t)i * nv + v] = prt__vertex_light_visibility(c, m, v, &lights[i]);
}
