/* prt/reference.h - ground truth: an unbiased Monte Carlo path tracer over the same scene and
 * lighting that the PRT methods bake, for measuring their error.
 *
 * Surfaces are one-sided (the back of a triangle is black, as in the bakes) and reflect with
 * their material's BRDF from prt's library (Lambert with the per-vertex albedo where a vertex has
 * no BRDF material). Light comes from a prt_lighting: a distant environment map, piecewise
 * constant over its pixels (as the SH projection sees it), local lights (point, spot,
 * directional, sphere) and the scene's emissive surfaces, all sampled explicitly (next-event
 * estimation) and combined by multiple importance sampling with BRDF sampling where paths can
 * also hit them (environment, spheres, emissive triangles). Sphere lights are not scene geometry:
 * they are transparent emitters that add their radiance to the rays crossing them and occlude
 * nothing (neither other light nor surfaces behind them). Specular surfaces (prt_scene_set_specular)
 * turn paths as a perfect mirror or Fresnel glass (met from inside too) and sample no light; what
 * a path meets after them counts whole (caustics; no light sample could have found it), so a
 * caustic of a small source converges slowly. A path that starts at a vertex of a specular
 * surface sees it as the bakes do: diffuse, of its albedo. Paths end by Russian roulette. Results are
 * deterministic for a seed whatever the thread count: each (vertex or pixel, sample) pair has its
 * own random stream. */
#ifndef PRT_REFERENCE_H
#define PRT_REFERENCE_H

#include "prt/base.h"
#include "prt/lighting.h"
#include "prt/render.h"
#include "prt/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct prt_reference_desc {
    int samples;               /* paths per vertex or pixel; 0 = 256. With target_rel_error, the first batch */
    float target_rel_error;    /* > 0: add batches until each vertex's standard error / mean is below this */
    int max_samples;           /* cap for target_rel_error; 0 = 65536 */
    int max_depth;             /* hard bounce limit; 0 = 256 (Russian roulette ends paths long before) */
    uint32_t seed;
    float ray_offset;          /* 0 = 1e-4 x scene diagonal, as in the bakes */
    const double *rotation;    /* row-major 3x3 applied to the environment; NULL = identity */
    float intensity;           /* environment scale; 0 = 1 */
    /* The lighting to trace under. When set, the env argument of the trace functions must be
     * NULL and rotation/intensity are ignored (the lighting carries its own). NULL: the env
     * argument with rotation/intensity, and the scene's emissive surfaces at scale 1. */
    const prt_lighting *lighting;
    /* Per-vertex results: exit radiance of glossy vertices towards this world position (zero when
     * it lies behind them); NULL = along the vertex normal. Lambertian vertices are seen along
     * their normal whatever the eye. */
    const float *eye;
    prt_progress_fn progress;
    void *progress_user;
} prt_reference_desc;

/* Per-vertex exit radiance; all arrays 3 floats per vertex, owned by the result. */
typedef struct prt_reference_vertices {
    size_t vertex_count;
    float *radiance;           /* direct + indirect */
    float *direct;             /* light that reached the vertex straight from the environment */
    float *indirect;           /* light that bounced off at least one surface first */
    float *std_error;          /* standard error of the radiance estimate */
    float *std_error_indirect;
    int *samples;              /* paths traced per vertex */
} prt_reference_vertices;

prt_status prt_reference_trace_vertices(prt_context *ctx, const prt_scene *scene, const prt_envmap *env,
                                        const prt_reference_desc *desc, prt_reference_vertices *out);
void prt_reference_vertices_free(prt_reference_vertices *r);

/* An image from a camera: each pixel's radiance (background where no surface is hit, NULL =
 * black); std_error may be NULL. */
prt_status prt_reference_trace_image(prt_context *ctx, const prt_scene *scene, const prt_envmap *env,
                                     const prt_reference_desc *desc, const prt_camera *cam, int width, int height,
                                     const float background[3], prt_image *out, prt_image *std_error);

#ifdef __cplusplus
}
#endif
#endif
