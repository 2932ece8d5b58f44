/* prt/transfer.h - baked radiance transfer, its .prt file, and relighting.
 *
 * A prt_transfer holds the (possibly subdivided) mesh it was baked on and one or more transfer
 * sets. An SH transfer set stores per vertex the vector T with exit radiance
 *     L_out(p) = sum_i L_i T_i(p)
 * for SH lighting L (prt_sh_light). Sets with one channel exclude the albedo (it is applied at
 * relight time from the stored per-vertex albedo); three-channel sets include it, because
 * inter-reflection bleeds colour. See docs/FORMAT.md for the file layout. */
#ifndef PRT_TRANSFER_H
#define PRT_TRANSFER_H

#include "prt/base.h"
#include "prt/lighting.h"
#include "prt/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum prt_transfer_kind {
    PRT_TRANSFER_UNSHADOWED = 1,
    PRT_TRANSFER_SHADOWED = 2,
    PRT_TRANSFER_INTERREFLECTED = 4
} prt_transfer_kind;

typedef struct prt_bake_desc {
    int order;            /* SH order (bands); 0 = 5 (25 coefficients); 1..10 */
    int samples;          /* directions per vertex over the sphere; 0 = 1024 */
    unsigned kinds;       /* OR of prt_transfer_kind; 0 = all three */
    int bounces;          /* extra bounces for INTERREFLECTED; 0 = 3 */
    uint32_t seed;        /* rotates the low-discrepancy direction set; results are identical
                             for the same seed whatever the thread count */
    float ray_offset;     /* origin offset along the normal, scene units; 0 = 1e-4 x bbox diagonal */
    prt_progress_fn progress;
    void *progress_user;
} prt_bake_desc;

/* Shows what a zero-initialised desc becomes. */
prt_bake_desc prt_bake_desc_defaults(void);

typedef struct prt_transfer prt_transfer;

prt_status prt_bake_sh(prt_context *ctx, const prt_scene *scene, const prt_bake_desc *desc,
                       prt_transfer **out);
void prt_transfer_release(prt_transfer *t);

/* Files. Saving is atomic (temporary + rename); loading checks magic, version, sizes and CRCs. */
prt_status prt_transfer_save(const prt_transfer *t, const char *path);
prt_status prt_transfer_load(prt_context *ctx, const char *path, prt_transfer **out);
prt_status prt_transfer_load_memory(prt_context *ctx, const void *data, size_t size, prt_transfer **out);

typedef struct prt_transfer_info {
    size_t vertex_count, triangle_count;
    int order;                /* SH order of the sets */
    unsigned kinds;           /* which kinds the file holds */
    int samples, bounces;
    uint32_t seed;
    double bake_seconds;
    int threads;              /* threads the bake used (does not change the result) */
    size_t transfer_bytes;    /* bytes of all transfer sets */
    char source[512];         /* the scene the bake read */
} prt_transfer_info;

void prt_transfer_get_info(const prt_transfer *t, prt_transfer_info *info);
int prt_transfer_channels(const prt_transfer *t, prt_transfer_kind kind);  /* 0 if absent */
/* Borrowed pointer to a set's coefficients: vertex-major, channel, coefficient; NULL if absent. */
const float *prt_transfer_coeffs(const prt_transfer *t, prt_transfer_kind kind);

/* The lighting the baked scene named, if any (0 when none); see prt_scene_environment. */
int prt_transfer_environment(const prt_transfer *t, prt_environment_desc *out);

/* The mesh the transfer was baked on. */
size_t prt_transfer_vertex_count(const prt_transfer *t);
size_t prt_transfer_triangle_count(const prt_transfer *t);
const float *prt_transfer_positions(const prt_transfer *t);
const float *prt_transfer_normals(const prt_transfer *t);
const float *prt_transfer_albedo(const prt_transfer *t);
const uint32_t *prt_transfer_indices(const prt_transfer *t);

/* Exit radiance per vertex (RGB, 3 floats per vertex) under light. The light's order may differ
 * from the transfer's: the common bands are used. */
prt_status prt_relight_sh(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind,
                          const prt_sh_light *light, float *out_rgb);

const char *prt_transfer_kind_name(prt_transfer_kind kind);
/* Parses "unshadowed", "shadowed", "interreflected" (or their first letter). */
prt_status prt_transfer_kind_parse(const char *name, prt_transfer_kind *out);

#ifdef __cplusplus
}
#endif
#endif
