/* Participating media: density grids placed in world boxes (docs/SCENE.md "volumes"), their raw
 * grid files (docs/FORMAT.md "Density grid files") and procedural generators. */
#ifndef PRT_VOLUME_H
#define PRT_VOLUME_H

#include "prt/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct prt_scene prt_scene;

/* A density grid: dims[0] x dims[1] x dims[2] voxels (x fastest), each a density >= 0 at its
 * centre; the medium's extinction there is sigma_t times the density (per world unit). */
typedef struct prt_volume_desc {
    int dims[3];
    const float *density;   /* borrowed for the call */
    float lo[3], hi[3];     /* the world box the grid fills */
    float sigma_t;          /* extinction per world unit at density 1 */
    float albedo[3];        /* single-scattering albedo per channel, in [0, 1] */
    float g;                /* Henyey-Greenstein asymmetry in (-1, 1); 0 = isotropic */
} prt_volume_desc;

#define PRT_VOLUME_MAX_DIM 512

/* Checks d: dims in 1..PRT_VOLUME_MAX_DIM, densities finite and >= 0, a box of positive size,
 * sigma_t finite and >= 0, albedo in [0, 1], |g| < 1. */
prt_status prt_volume_check(const prt_volume_desc *d);
/* Adds a copy of the volume to the scene (a JSON scene's "volumes" do the same). */
prt_status prt_scene_add_volume(prt_scene *scene, const prt_volume_desc *d);
int prt_scene_volume_count(const prt_scene *scene);
/* The scene's volume `index`; its density stays the scene's. */
prt_status prt_scene_volume(const prt_scene *scene, int index, prt_volume_desc *out);

/* Procedural grids, the same for the same (kind, dims, seed) on every machine: "cloud" (a
 * billowing heap of puffs with a flat-ish base, densities up to about 1) or "smoke" (a rising,
 * widening, turbulent plume). *out is malloc'd, dims[0] * dims[1] * dims[2] floats. */
prt_status prt_volume_generate(prt_context *ctx, const char *kind, const int dims[3], uint32_t seed, float **out);

/* Raw density grid files (docs/FORMAT.md): written atomically; read with every count checked
 * against the file's size before anything is allocated, and the CRC and every value checked.
 * *density is malloc'd. */
prt_status prt_volume_grid_save(prt_context *ctx, const char *path, const int dims[3], const float *density);
prt_status prt_volume_grid_load(prt_context *ctx, const char *path, int dims[3], float **density);
/* The same from bytes in memory (what the fuzz harness feeds). */
prt_status prt_volume_grid_parse(prt_context *ctx, const void *data, size_t size, int dims[3], float **density);

#ifdef __cplusplus
}
#endif

#endif
