/* Participating media drawn over a rendered image (volumes.c). */
#ifndef PRT_RENDER_VOLUMES_H
#define PRT_RENDER_VOLUMES_H

#include "core/internal.h"
#include "prt/render.h"
#include "prt/reference.h"

/* Ray-marches mesh->volumes along every pixel's camera ray (the projection prt_render draws
 * with: row 0 at the top) up to the first surface of the mesh, and composites what they scatter
 * over img: L = sum T (1 - e) S + T img. Deterministic: a fixed step, shifted per pixel by a
 * hash of the pixel so that the steps do not band. */
prt_status prt__render_volumes(const prt_context *ctx, const prt_render_mesh *mesh, const prt_camera *cam, prt_image *img);
/* The same for one ray from o along unit d ending at tmax (INFINITY: none): the radiance the
 * media add in rgb and their transmittance; jitter in [0, 1) shifts the steps. */
float prt__march_volumes(const prt_render_volume *v, int count, const float o[3], const float d[3], float tmax, float jitter, float rgb[3]);

/* The reference path tracer's radiance arriving at o from -d (d unit) through the scene's media
 * and to its surfaces, desc->lighting's environment only (pathtrace.c): the mean of `samples`
 * paths in out, and the standard error of its green channel. For tests against the bakes. */
prt_status prt__reference_media_radiance(prt_context *ctx, const prt_scene *scene, const prt_reference_desc *desc, const float o[3], const float d[3],
                                         int samples, float out[3], float *std_error);

#endif
