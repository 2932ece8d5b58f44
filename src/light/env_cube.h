/* Environments as radiance over a 6 x 64 x 64 cube map, energy-exact under any rotation: the
 * lighting the all-frequency (Haar) basis projects. */
#ifndef PRT_LIGHT_ENV_CUBE_H
#define PRT_LIGHT_ENV_CUBE_H

#include "light/envmap_internal.h"

#define PRT__ENV_CUBE_FACE 64
#define PRT__ENV_CUBE_DIM (6 * PRT__ENV_CUBE_FACE * PRT__ENV_CUBE_FACE)

/* env's radiance (times intensity) over the cube, rotated by the row-major rotation (lighting from
 * d arrives from R d; NULL or all zero = none): radiance[texel][3], texel (face * 64 + y) * 64 + x
 * (core/cubemap.h's faces). Thread-safe; the first call per map builds its fine cube. */
prt_status prt__env_cube(prt_context *ctx, const prt_envmap *env, const double rotation[9], float intensity, float *radiance);
/* The map's energy over the fine cube in blocks of 2 x 2 texels (half a lighting texel each),
 * energy[face][y][x][3] with 128 x 128 blocks a face: what prt__env_cube shares among the texels
 * a rotated block covers, for code that rotates the lighting elsewhere (prt export --web). */
#define PRT__ENV_CUBE_QUADS 128
prt_status prt__env_cube_quads(prt_context *ctx, const prt_envmap *env, float *energy);
/* The solid angle of each texel of a face (all faces alike): table[y * 64 + x]. */
void prt__env_cube_solid_angles(float *table);

#endif
