/* What the diffuse visibility pass hands to the glossy bounce and BRDF steps. */
#ifndef PRT_METHODS_SH_BAKE_H
#define PRT_METHODS_SH_BAKE_H

#include "core/progress.h"
#include "methods/sh/sh.h"

#include <embree3/rtcore.h>

/* One occluded direction of a vertex and the front face it hit. */
typedef struct prt__hit {
    uint32_t prim, sample;
    float u, v, weight;   /* barycentrics of the hit; cos * 4pi/N */
} prt__hit;

typedef struct prt__bounce_input {
    const prt__mesh *mesh;
    int order, samples;
    const float *basis;              /* [sample][order^2] */
    prt__hit *const *hits;           /* per vertex */
    const uint32_t *hit_count;
    const float *shadowed;           /* [vertex][order^2], includes 1/pi */
    const float *glossy_shadowed;    /* [vertex][order^2 (lighting j)][order^2 (incident i)] */
    const prt_brdf *brdfs;           /* materials: mesh.material k -> brdfs[k - 1] */
    int brdf_count;
    int bounces;
    bool want_glossy;                /* keep the glossy inter-reflected matrices for every vertex */
    prt__progress *progress;
} prt__bounce_input;

/* Inter-reflection with glossy surfaces in the loop: diffuse-to-diffuse, glossy-to-diffuse,
 * diffuse-to-glossy and glossy-to-glossy transport, bounce by bounce. Fills diffuse_total
 * ([vertex][3][order^2], albedo applied) and, when want_glossy, glossy_total
 * ([vertex][3][order^2][order^2]). */
prt_status prt__bake_glossy_bounces(prt_context *ctx, const prt__bounce_input *in, float **diffuse_total, float **glossy_total);

/* Per material, the local-frame SH matrix of its glossy part (NULL for materials without one):
 * out[k] holds 3 x order^4 floats for material k + 1. */
prt_status prt__brdf_matrices(prt_context *ctx, const prt_brdf *brdfs, int count, int order, float **out);

typedef struct prt__texel_input {
    const prt__mesh *mesh;
    const char *source;
    int order, samples;
    const float *dirs, *basis;       /* [sample][3], [sample][order^2] */
    RTCScene scene;
    float offset;
    const float *vertex_ir;          /* [vertex][3][order^2] inter-reflected transfer, or NULL */
    unsigned kinds;
    int width, height;
    const prt_image *normal_map;     /* tangent-space, values in [0, 1] (0.5 = flat), or NULL */
    prt__progress *progress;
} prt__texel_input;

/* Per-texel transfer of the diffuse kinds asked for; fails clearly without a unique UV layout. */
prt_status prt__bake_texels(prt_context *ctx, const prt__texel_input *in, prt__texel_sets *out);

/* Turns t's glossy sets from incident into exit radiance (3 channels) with each vertex's
 * material BRDF, or `override` for all; vertices without a glossy part get zero. */
prt_status prt__bake_brdf_in(prt_context *ctx, prt_transfer *t, const prt_brdf *override);

/* Rotations between the world frame and a vertex's local frame (z = normal). */
typedef struct prt__frame_rot {
    prt_sh_rotation *to_local, *to_world;
} prt__frame_rot;
prt_status prt__frame_rot_create(int order, const float normal[3], prt__frame_rot *out);
void prt__frame_rot_release(prt__frame_rot *r);
/* rows x order^2 world-frame incident vectors (row stride order^2) through B (3 x order^4, channel
 * c) into world-frame exit vectors; in and out may not alias. */
void prt__apply_brdf(const prt__frame_rot *r, const float *B, int c, int order, const float *in, float *out, int rows);

#endif
