/* Specular surfaces (perfect mirrors, smooth dielectrics): how a ray turns at one, shared by the
 * bakes that follow specular paths (caustics) and the reference path tracer, so that both see the
 * same optics. */
#ifndef PRT_BRDF_SPECULAR_H
#define PRT_BRDF_SPECULAR_H

#include "core/internal.h"
#include "geom/mesh.h"

/* Fresnel's reflectance of unpolarised light meeting a smooth boundary at cos_i (> 0) from the
 * side of index n1, eta = n1 / n2; 1 under total internal reflection. */
double prt__fresnel_dielectric(double cos_i, double eta);

/* A ray travelling along d (unit) meets specular surface s at a point whose geometric normal ng
 * and shading normal ns (unit) face its front. u in [0, 1) picks reflection with Fresnel's
 * probability at glass. Writes the new direction and the factor the ray's throughput takes (a
 * mirror's reflectance; 1 at glass, the choice carrying Fresnel's weight). Returns the side of
 * the surface the new ray leaves on (+1 front, -1 back: its origin moves that way along ng), or
 * 0 when the light ends there (the back of a mirror is dark). */
int prt__specular_scatter(const prt_specular *s, const float d[3], const float ng[3], const float ns[3], double u, float out[3], float *weight);

/* The scene's specular materials per surface of mesh m (whose surface names are the scene's):
 * an array of m->surface_count + 1 (index 0, unnamed surfaces, is diffuse), or NULL when no
 * surface is specular (*out NULL, PRT_OK). */
prt_status prt__specular_table(const prt_context *ctx, const prt_scene *scene, const prt__mesh *m, prt_specular **out);

/* The specular material of triangle tri under table (NULL: none), or NULL when it is diffuse. */
static inline const prt_specular *prt__specular_of(const prt_specular *table, const prt__mesh *m, uint32_t tri)
{
    if (!table || !m->surface) return NULL;
    const uint16_t sid = m->surface[m->indices[(size_t)tri * 3]];   /* a triangle never joins two surfaces */
    return sid <= m->surface_count && table[sid].type != PRT_SPECULAR_NONE ? &table[sid] : NULL;
}

#endif
