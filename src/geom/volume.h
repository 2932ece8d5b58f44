/* Participating media as the bakes, the renderer and the path tracer see them: a density grid in
 * a world box, trilinear between voxel centres, zero outside the box (volume.c). */
#ifndef PRT_GEOM_VOLUME_H
#define PRT_GEOM_VOLUME_H

#include "core/internal.h"
#include "prt/volume.h"

typedef struct prt__volume {
    int dims[3];
    float lo[3], hi[3];
    float sigma_t, albedo[3], g;
    float *density;   /* [z][y][x], owned */
    float max_density;
} prt__volume;

/* Copies d (checked) into v. */
prt_status prt__volume_init(prt_context *ctx, const prt_volume_desc *d, prt__volume *v);
void prt__volume_free(prt__volume *v);
static inline size_t prt__volume_voxels(const prt__volume *v) { return (size_t)v->dims[0] * v->dims[1] * v->dims[2]; }
/* The centre of voxel (x, y, z). */
void prt__volume_voxel_centre(const prt__volume *v, int x, int y, int z, float p[3]);
/* Extinction (sigma_t times the trilinear density) at p; 0 outside the box. */
float prt__volume_extinction(const prt__volume *v, const float p[3]);
/* The stretch [t0, t1] of o + t d (t in [0, tmax]) inside the box; false when none. */
bool prt__volume_clip(const prt__volume *v, const float o[3], const float d[3], float tmax, float *t0, float *t1);
/* The march step: half the smallest voxel. */
float prt__volume_step(const prt__volume *v);
/* Optical depth of the volumes along o + t d, t in [0, tmax] (INFINITY: to the end of the
 * boxes), by the midpoint rule at prt__volume_step (deterministic). */
float prt__volumes_optical_depth(const prt__volume *v, int count, const float o[3], const float d[3], float tmax);
/* Henyey-Greenstein phase function of cos(angle between the incident flow and the scattered
 * direction) per steradian, and sampling of it around direction w from (u1, u2). */
float prt__hg_phase(float g, float cos_theta);
void prt__hg_sample(float g, const float w[3], double u1, double u2, float out[3]);

#endif
