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

void prt__vertex_lights_shade(prt_context *ctx, const prt__vertex_lights *c, const prt__mesh *m, const prt_light *lights, int count,
                              const prt__vertex_materials *mat, const float eye[3], float *rgb)
{
    const size_t nv = m->vertex_count;
#pragma omp parallel for schedule(dynamic, 256) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v) {
        const float *p = m->positions + v * 3, *n = m->normals + v * 3, *a = mat->albedo + v * 3;
        const int id = mat->material && eye ? mat->material[v] : 0;
        const prt_brdf *b = id > 0 && id <= mat->brdf_count ? &mat->brdfs[id - 1] : NULL;
        float s[3], t[3], wo[3] = {0, 0, 1};
        if (b) {   /* the view direction in the BRDF's frame, as the renderer's per-pixel pass */
            float to_eye[3] = {eye[0] - p[0], eye[1] - p[1], eye[2] - p[2]};
            prt__v3_normalize(to_eye);
            prt_brdf_frame(n, s, t);
            wo[0] = prt__v3_dot(to_eye, s);
            wo[1] = prt__v3_dot(to_eye, t);
            wo[2] = prt__v3_dot(to_eye, n);
        }
        for (int i = 0; i < count; ++i) {
            const prt_light *l = &lights[i];
            float e[3], f[3] = {a[0] / (float)PRT_PI, a[1] / (float)PRT_PI, a[2] / (float)PRT_PI};
            prt__vertex_light_at(c, m, v, l, e);
            if (e[0] <= 0.0f && e[1] <= 0.0f && e[2] <= 0.0f) continue;
            if (b) {
                float w[3], wi[3], g[3];
                if (l->type == PRT_LIGHT_DIRECTIONAL) memcpy(w, l->direction, sizeof w);
                else prt__v3_sub(l->position, p, w);
                prt__v3_normalize(w);
                wi[0] = prt__v3_dot(w, s);
                wi[1] = prt__v3_dot(w, t);
                wi[2] = prt__v3_dot(w, n);
                prt_brdf_eval_glossy(b, wi, wo, g);
                for (int k = 0; k < 3; ++k) f[k] += g[k];
            }
            for (int k = 0; k < 3; ++k) rgb[v * 3 + k] += f[k] * e[k];
        }
    }
}
