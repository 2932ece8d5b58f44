/* Cube maps of directions: 6 faces (+x, -x, +y, -y, +z, -z) of n x n texels, texel (face, x, y)
 * at index (face * n + y) * n + x. Face coordinates a, b in [-1, 1] map to the direction
 * normalize(face_axis + a * right + b * up) with OpenGL's cube map orientation. */
#ifndef PRT_CORE_CUBEMAP_H
#define PRT_CORE_CUBEMAP_H

#include <math.h>

/* Per face: the major axis, then the directions a and b grow along (OpenGL cube map layout,
 * with b pointing up the face rather than down the texture). */
extern const float prt__cube_axes[6][3][3];

/* Direction (not normalized) for face coordinates a, b in [-1, 1]. */
void prt__cube_dir(int face, float a, float b, float dir[3]);
/* Unit direction through the centre of texel (x, y) of face, and that texel's solid angle. */
void prt__cube_texel(int n, int face, int x, int y, float dir[3], float *solid_angle);
/* Face and face coordinates (a, b in [-1, 1]) that direction d (any length > 0) passes through:
 * the major axis (x before y before z on ties), then the other two over it, per face as
 * prt__cube_dir lays them out. Inline, as splatting a map into a cube calls it per sample. */
static inline int prt__cube_face(const float d[3], float *a, float *b)
{
    const float x = d[0], y = d[1], z = d[2], ax = fabsf(x), ay = fabsf(y), az = fabsf(z);
    if (ax >= ay && ax >= az) {
        const float r = 1.0f / x;
        *a = -z * r; *b = y * fabsf(r);
        return x >= 0 ? 0 : 1;
    }
    if (ay >= az) {
        const float r = 1.0f / y;
        *a = x * fabsf(r); *b = -z * r;
        return y >= 0 ? 2 : 3;
    }
    const float r = 1.0f / z;
    *a = x * r; *b = y * fabsf(r);
    return z >= 0 ? 4 : 5;
}

#endif
