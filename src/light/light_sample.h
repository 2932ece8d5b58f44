/* Sampling light from a surface point: the local lights of a prt_lighting and the scene's
 * emissive triangles. Shared by the reference path tracer and the methods that start from direct
 * light on surfaces, so that all of them see the same light. */
#ifndef PRT_LIGHT_LIGHT_SAMPLE_H
#define PRT_LIGHT_LIGHT_SAMPLE_H

#include "geom/mesh.h"

/* Irradiance from a uniform sphere of unit radiance: its centre at cos_t from the normal, its cap
 * of half-angle sigma with sin2_s = sin^2 sigma (>= 1 when the point is inside). Exact, horizon
 * clipped (lights.c says how). */
double prt__sphere_cap_irradiance(double cos_t, double sin2_s);
/* A spot light's angular factor towards a point that sees the light in unit direction wi. */
double prt__spot_factor(const prt_light *l, const float wi[3]);
/* An ies light's candela towards a point that sees the light in unit direction wi (times scale:
 * W/sr). */
double prt__ies_factor(const prt_light *l, const float wi[3]);
/* An ies light's frame: n its nadir, u towards its C0 plane, v = n x u towards C90. */
void prt__ies_frame(const prt_light *l, double n[3], double u[3], double v[3]);
/* A profile from a table made in memory (angles in degrees, candela [h][v]); takes ownership of
 * the three arrays, also on failure. The table is trusted to be valid (increasing type C angles). */
prt_status prt__ies_from_table(int nv, int nh, float *v, float *h, float *cd, prt_ies **out);

typedef struct prt__light_sample {
    float wi[3];      /* unit, from the surface point towards the light */
    float dist;       /* to the sampled point on the light; INFINITY for directional lights */
    float value[3];   /* incident radiance over pdf: the estimate is f(wi, wo) cos(wi) value */
    float pdf;        /* solid-angle pdf; 0 for delta lights (point, spot, directional): no MIS */
} prt__light_sample;

/* Samples light l as seen from p (two uniform numbers; sphere lights sample their visible cone
 * uniformly). False when l sends nothing to p (behind a spot, inside a sphere, black). */
bool prt__light_sample_from(const prt_light *l, const float p[3], double u1, double u2, prt__light_sample *s);
/* Distance along the ray o + t d (d unit) to where it enters sphere light l (from inside: where
 * it leaves), INFINITY when it misses. */
float prt__sphere_light_hit(const prt_light *l, const float o[3], const float d[3]);
/* The pdf per steradian with which prt__light_sample_from picks a direction of sphere l from p;
 * 0 inside the sphere (never sampled there). */
float prt__sphere_light_pdf(const prt_light *l, const float p[3]);

/* The emissive triangles of a mesh, sampled in proportion to area x luminance of their mean
 * emission, then uniformly over the triangle. */
typedef struct prt__emitters {
    size_t count;        /* emissive triangles; 0 = nothing emits (or scale 0) */
    uint32_t *tri;       /* their triangle indices */
    double *cdf;         /* count entries, last = 1 */
    float *pdf_area;     /* per mesh triangle: selection probability / area; 0 where it does not emit */
    float scale;         /* emission scale of the lighting */
} prt__emitters;

prt_status prt__emitters_init(prt__emitters *e, const prt__mesh *m, float scale);
void prt__emitters_free(prt__emitters *e);
/* Emitted radiance at barycentric (b1, b2) of triangle tri (front side), scaled. */
void prt__emission_at(const prt__emitters *e, const prt__mesh *m, uint32_t tri, float b1, float b2, float rgb[3]);
/* Samples a point on an emitter seen from p (three uniform numbers); false when the point faces
 * away from p or emits nothing. */
bool prt__emitters_sample(const prt__emitters *e, const prt__mesh *m, const float p[3], double u1, double u2, double u3,
                          prt__light_sample *s);
/* The pdf per steradian of prt__emitters_sample for a point of triangle tri at distance dist
 * whose front normal makes cosine cos_light with the direction back to p. */
float prt__emitters_pdf(const prt__emitters *e, uint32_t tri, float dist, float cos_light);

#endif
