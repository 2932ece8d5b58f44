/* Cube maps of directions: 6 faces (+x, -x, +y, -y, +z, -z) of n x n texels, texel (face, x, y)
 * at index (face * n + y) * n + x. Face coordinates a, b in [-1, 1] map to the direction
 * normalize(face_axis + a * right + b * up) with OpenGL's cube map orientation. */
#ifndef PRT_CORE_CUBEMAP_H
#define PRT_CORE_CUBEMAP_H

/* Direction (not normalized) for face coordinates a, b in [-1, 1]. */
void prt__cube_dir(int face, float a, float b, float dir[3]);
/* Unit direction through the centre of texel (x, y) of face, and that texel's solid angle. */
void prt__cube_texel(int n, int face, int x, int y, float dir[3], float *solid_angle);
/* Face and face coordinates (a, b in [-1, 1]) that direction d (any length > 0) passes through. */
int prt__cube_face(const float d[3], float *a, float *b);

#endif
