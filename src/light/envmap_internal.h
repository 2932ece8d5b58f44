/* Environment-map internals shared by projection (envmap.c) and sampling (env_sample.c). */
#ifndef PRT_LIGHT_ENVMAP_INTERNAL_H
#define PRT_LIGHT_ENVMAP_INTERNAL_H

#include "core/internal.h"
#include "prt/lighting.h"

struct prt_envmap {
    prt_image img;
    prt_env_layout layout;
    /* The map integrated into a 6 x 256 x 256 cube of RGB energies (radiance times solid
     * angle per texel), built on first use by light/env_cube.c and
     * published atomically: rotations resample it, not the map. */
    float *cube_cache;
    /* The map's SH projection per order, built on first use and published atomically: every
     * lighting change of an SH relight rotates it instead of projecting the map again. */
    prt_sh_light *sh_cache[PRT_SH_MAX_ORDER + 1];
};

/* prt_envmap_project_sh through the map's cache (thread-safe). */
prt_status prt__envmap_project_sh_cached(const prt_envmap *e, int order, prt_sh_light *out);

/* Direction at continuous image coordinates (pixels, (0,0) = top-left corner) and the solid
 * angle per unit pixel area there; false outside the map (angular rim, empty cross cells). */
bool prt__env_dir_at(const prt_envmap *e, double fx, double fy, double dir[3], double *jac);
/* Continuous image coordinates of a direction. */
void prt__env_pixel_of(const prt_envmap *e, const float d[3], float *fx, float *fy);
/* The pixel a direction falls in (the map is piecewise constant over pixels, as the SH
 * projection and the path tracer both treat it). */
size_t prt__env_pixel_index(const prt_envmap *e, const float d[3]);

#endif
