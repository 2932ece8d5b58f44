/* What the diffuse visibility pass hands to the glossy bounce and BRDF steps. */
#ifndef PRT_METHODS_SH_BAKE_H
#define PRT_METHODS_SH_BAKE_H

#include "core/progress.h"
#include "brdf/sh_matrix.h"
#include "geom/raycast.h"
#include "methods/sh/height_field.h"
#include "brdf/dipole.h"
#include "methods/sh/sh.h"

#include <stdio.h>

/* One occluded direction of a vertex and the front face it hit. */
typedef struct prt__hit {
    uint32_t prim, sample;
    float u, v, weight;   /* barycentrics of the hit; cos * 4pi/N */
} prt__hit;

/* The bounces' ray hits (hits.c): each vertex's list in memory, or, when the bake streams
 * (prt__bake_job.memory_over), in an unlinked scratch file written block by block as visibility
 * finishes and read back vertex by vertex by every bounce (through the page cache, not the
 * process's memory). Either way the bounces gather the same hits in the same order. */
typedef struct prt__hit_store {
    size_t vertex_count;
    uint32_t samples;           /* a vertex has at most this many hits */
    uint32_t *count;            /* [vertex] */
    prt__hit **list;            /* [vertex] in memory; NULL when streaming */
    FILE *spill;                /* streaming: the scratch file */
    uint64_t *at;               /* streaming: [vertex] where its hits start in spill */
    uint64_t end;               /* streaming: bytes written (taken atomically) */
} prt__hit_store;

/* Sets up an empty store; streaming with a scratch file in TMPDIR. */
prt_status prt__hits_init(prt_context *ctx, prt__hit_store *s, size_t vertex_count, uint32_t samples, bool streaming);
void prt__hits_free(prt__hit_store *s);
/* Keeps vertices [v0, v1)'s hits, given one after another (count[v - v0] each); thread-safe for
 * disjoint ranges. False when memory or the scratch file fails. */
bool prt__hits_put(prt__hit_store *s, size_t v0, size_t v1, const void *hits, const uint32_t *count);
/* Vertex v's hits: in memory, or read into buf (room for `samples`); NULL when reading fails
 * (or, in memory, when it has none). */
const prt__hit *prt__hits_get(const prt__hit_store *s, size_t v, prt__hit *buf);

typedef struct prt__bounce_input {
    const prt__mesh *mesh;
    int order, samples;
    const float *basis;              /* [sample][order^2] */
    const prt__hit_store *hits;
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
