/* BRDFs as SH matrices applied in a vertex's own frame (z = its normal): incident radiance in
 * SH of the world frame -> rotated into the frame -> the material's SH matrix (prt_brdf_sh_matrix)
 * -> rotated back: exit radiance in SH of the world frame. Shared by every method with glossy
 * SH transfer. */
#ifndef PRT_BRDF_SH_MATRIX_H
#define PRT_BRDF_SH_MATRIX_H

#include "core/internal.h"
#include "prt/brdf.h"

/* Rotations between the world frame and a vertex's local frame (z = normal). */
typedef struct prt__frame_rot {
    prt_sh_rotation *to_local, *to_world;
} prt__frame_rot;
prt_status prt__frame_rot_create(int order, const float normal[3], prt__frame_rot *out);
void prt__frame_rot_release(prt__frame_rot *r);
/* rows x order^2 world-frame incident vectors (row stride order^2) through B (3 x order^4, channel
 * c) into world-frame exit vectors; in and out may not alias. */
void prt__apply_brdf(const prt__frame_rot *r, const float *B, int c, int order, const float *in, float *out, int rows);

/* Per material, the local-frame SH matrix of its glossy part (NULL for materials without one):
 * out[k] holds 3 x order^4 floats for material k + 1. */
prt_status prt__brdf_matrices(prt_context *ctx, const prt_brdf *brdfs, int count, int order, float **out);

#endif
