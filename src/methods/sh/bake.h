/* What the diffuse visibility pass hands to the glossy bounce and BRDF steps. */
#ifndef PRT_METHODS_SH_BAKE_H
#define PRT_METHODS_SH_BAKE_H

#include "core/progress.h"
#include "brdf/sh_matrix.h"
#include "geom/raycast.h"
#include "methods/sh/height_field.h"
#include "brdf/dipole.h"
#include "methods/sh/sh.h"

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
    const prt__height_field *bumps;  /* a height field that shades and shadows the texels, or NULL */
    prt__progress *progress;
    const prt__volume *volumes;      /* participating media: sample rays carry their transmittance */
    int volume_count;
} prt__texel_input;

/* Translucency (subsurface.c): the inter-reflected transfer T ([vertex][3][nc]) of every vertex
 * of a medium (medium[v] = k > 0: kernels[k - 1]) becomes the light its medium carries to it
 * from every vertex of the medium nearby. The mesh's albedo there must be what the bounces
 * reflected with (the dipole's total diffuse reflectance, or the albedo an exponential falloff
 * spreads). */
prt_status prt__sh_subsurface(prt_context *ctx, const prt__mesh *m, const uint8_t *medium, const prt__dipole (*kernels)[3], int nc, float *T,
                              prt__progress *p);

/* Neighbourhood transfer (neighbourhood.c) over g's points (dims, lo, hi set): the sample
 * directions dirs/basis from each point; exit the surfaces' transfer ([vertex][channels][order^2],
 * channels 3 with albedo or 1 times the mesh's albedo) or NULL (only the shadow). */
prt_status prt__sh_neighbourhood_bake(prt_context *ctx, const prt__mesh *m, const prt__raycaster *rc, const float *dirs, const float *basis, int samples,
                                      int order, const float *exit, int exit_channels, prt__sh_grid *g, prt__progress *p);

/* Per-texel transfer of the diffuse kinds asked for; fails clearly without a unique UV layout. */
prt_status prt__bake_texels(prt_context *ctx, const prt__texel_input *in, prt__texel_sets *out);

/* Turns t's glossy sets from incident into exit radiance (3 channels) with each vertex's
 * material BRDF, or `override` for all; vertices without a glossy part get zero. */
prt_status prt__bake_brdf_in(prt_context *ctx, prt_transfer *t, const prt_brdf *override);

#endif
