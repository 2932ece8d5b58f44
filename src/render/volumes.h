/* Participating media drawn over a rendered image (volumes.c). */
#ifndef PRT_RENDER_VOLUMES_H
#define PRT_RENDER_VOLUMES_H

#include "core/internal.h"
#include "prt/render.h"

/* Ray-marches mesh->volumes along every pixel's camera ray (the projection prt_render draws
 * with: row 0 at the top) up to the first surface of the mesh, and composites what they scatter
 * over img: L = sum T (1 - e) S + T img. Deterministic: a fixed step, shifted per pixel by a
 * hash of the pixel so that the steps do not band. */
prt_status prt__render_volumes(const prt_context *ctx, const prt_render_mesh *mesh, const prt_camera *cam, prt_image *img);
/* The same for one ray from o along unit d ending at tmax (INFINITY: none): the radiance the
 * media add in rgb and their transmittance; jitter in [0, 1) shifts the steps. */
float prt__march_volumes(const prt_render_volume *v, int count, const float o[3], const float d[3], float tmax, float jitter, float rgb[3]);

#endif
