/* Cube map direction <-> texel mapping and exact texel solid angles. */
#include "core/cubemap.h"

#include <math.h>

const float prt__cube_axes[6][3][3] = {
    {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},  {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
    {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},  {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},   {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
};

void prt__cube_dir(int face, float a, float b, float dir[3])
{
    const float(*ax)[3] = prt__cube_axes[face];
    for (int i = 0; i < 3; ++i) dir[i] = ax[0][i] + a * ax[1][i] + b * ax[2][i];
}

/* Solid angle of the face region [-1, a] x [-1, b] up to a constant: the integral of
 * (1 + a^2 + b^2)^(-3/2) has this closed form. */
static double area(double a, double b) { return atan2(a * b, sqrt(a * a + b * b + 1.0)); }

void prt__cube_texel(int n, int face, int x, int y, float dir[3], float *solid_angle)
{
    double a0 = 2.0 * x / n - 1.0, a1 = 2.0 * (x + 1) / n - 1.0, b0 = 2.0 * y / n - 1.0, b1 = 2.0 * (y + 1) / n - 1.0;
    prt__cube_dir(face, (float)(0.5 * (a0 + a1)), (float)(0.5 * (b0 + b1)), dir);
    float l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int i = 0; i < 3; ++i) dir[i] /= l;
    if (solid_angle) *solid_angle = (float)(area(a1, b1) - area(a0, b1) - area(a1, b0) + area(a0, b0));
}
