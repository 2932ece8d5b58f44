/* Transfer in participating media (volume.c): what the SH bake keeps per voxel of each of the
 * scene's volumes, and how relighting turns it into the light the medium scatters. */
#ifndef PRT_METHODS_SH_VOLUME_H
#define PRT_METHODS_SH_VOLUME_H

#include "core/progress.h"
#include "geom/mesh.h"
#include "geom/raycast.h"
#include "geom/volume.h"

typedef struct prt__sh_volume {
    prt__volume medium;   /* grid, box, extinction, albedo, g (its own copy) */
    int bands;            /* bands of the arriving light kept: 1 (isotropic) or 2 (HG) */
    int orders;           /* orders of scattering the bake iterated */
    float *incident;      /* [voxel][3][bands^2][order^2]: SH of the radiance arriving, direct and scattered (channel, band row, lighting coefficient) */
} prt__sh_volume;

/* What the bake of a scene's volumes reads: every volume (their shadows on each other), the
 * surfaces (rays end at them; front faces send back their exit transfer) and the directions. */
typedef struct prt__volume_scene {
    const prt__volume *volumes;
    int count;
    const prt__raycaster *rc;     /* NULL: no surfaces */
    const prt__mesh *mesh;
    const float *exit;            /* the surfaces' transfer, [vertex][exit_channels][order^2] (3: albedo in; 1: times the mesh's), or NULL */
    int exit_channels;
    int order, samples;
    uint32_t seed;
} prt__volume_scene;

prt_status prt__sh_volume_bake(prt_context *ctx, const prt__volume_scene *in, int which, prt__sh_volume *out, prt__progress *p);
void prt__sh_volume_free(prt__sh_volume *v);
/* Whether voxel (x, y, z) or one of its 26 neighbours holds medium: only those carry transfer. */
bool prt__sh_volume_active(const prt__volume *v, int x, int y, int z);
/* Bytes its file chunk holds (densities as floats, rows of voxels with medium around them as
 * halves), the header left out. */
size_t prt__sh_volume_bytes(const prt__sh_volume *v, int order);
/* The light each voxel scatters per unit extinction under light (truncated at the bake's order,
 * `order`), as SH of the direction the light travels (the view ray's), bands^2 coefficients per
 * channel: out[voxel][3][bands^2]. */
void prt__sh_volume_source(const prt__sh_volume *v, int order, const prt_sh_light *light, float *out);

#endif
