/* Local lights' direct light at mesh vertices (or any points with normals) with shadow rays: what
 * every method that relights local lights per vertex or texel shares. The mesh goes into Embree on first use and
 * stays; `lock` keeps that safe when several threads relight at once. */
#ifndef PRT_LIGHT_VERTEX_LIGHTS_H
#define PRT_LIGHT_VERTEX_LIGHTS_H

#include "geom/raycast.h"

#include <pthread.h>

typedef struct prt__vertex_lights {
    pthread_mutex_t lock;
    bool ready;
    prt__raycaster rc;
    float *origins;          /* [vertex][3] shadow-ray origins */
} prt__vertex_lights;

void prt__vertex_lights_init(prt__vertex_lights *c);
void prt__vertex_lights_free(prt__vertex_lights *c);
/* Builds the ray caster and origins once (a failure is not kept: the next call tries again). */
prt_status prt__vertex_lights_ready(prt_context *ctx, const prt__mesh *m, float ray_offset, prt__vertex_lights *c);

/* Whether the segment o + d t, t in (0, tfar), hits anything. */
bool prt__vertex_lights_occluded(const prt__vertex_lights *c, const float o[3], const float d[3], float tfar);
/* Irradiance at vertex v from l, shadowed (point, spot, directional: one ray; sphere: exact
 * unoccluded times the visible fraction of 16 samples of its cone). */
void prt__vertex_light_at(const prt__vertex_lights *c, const prt__mesh *m, size_t v, const prt_light *l, float e[3]);
/* Whether vertex v sees l at all (cone and facing aside): 0 or 1, a sphere's visible fraction. */
float prt__vertex_light_visibility(const prt__vertex_lights *c, const prt__mesh *m, size_t v, const prt_light *l);

/* Adds count lights' shadowed irradiance at every vertex to E (3 per vertex); c must be ready. */
void prt__vertex_lights_add(prt_context *ctx, const prt__vertex_lights *c, const prt__mesh *m, const prt_light *lights, int count, float *E);
/* What a vertex reflects of local light: its albedo (3 per vertex) and, where material[v] = k > 0,
 * the glossy part of brdfs[k - 1] (material NULL: Lambertian everywhere). */
typedef struct prt__vertex_materials {
    const float *albedo;
    const uint8_t *material;
    const prt_brdf *brdfs;
    int brdf_count;
} prt__vertex_materials;
/* Adds count lights' shadowed direct light as the renderer's per-pixel pass draws it: albedo / pi
 * times irradiance, plus each glossy material's lobe seen from eye (NULL: Lambertian only);
 * c must be ready. */
void prt__vertex_lights_shade(prt_context *ctx, const prt__vertex_lights *c, const prt__mesh *m, const prt_light *lights, int count,
                              const prt__vertex_materials *mat, const float eye[3], float *rgb);
/* vis[light][vertex] = prt__vertex_light_visibility; c must be ready. */
void prt__vertex_lights_visibility(prt_context *ctx, const prt__vertex_lights *c, const prt__mesh *m, const prt_light *lights, int count,
                                   float *vis);

#endif
