/* Low-discrepancy directions. The first two Sobol' dimensions form a (0,2)-sequence in base 2;
 * an XOR digital shift derived from the seed keeps that property while decorrelating seeds.
 * Sample i depends only on (i, seed), never on which thread asks. */
#include "core/internal.h"

static uint32_t hash32(uint32_t x)
{
    x ^= x >> 16; x *= 0x7feb352dU;
    x ^= x >> 15; x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

static uint32_t reverse_bits(uint32_t v)
{
    v = ((v >> 1) & 0x55555555U) | ((v & 0x55555555U) << 1);
    v = ((v >> 2) & 0x33333333U) | ((v & 0x33333333U) << 2);
    v = ((v >> 4) & 0x0F0F0F0FU) | ((v & 0x0F0F0F0FU) << 4);
    v = ((v >> 8) & 0x00FF00FFU) | ((v & 0x00FF00FFU) << 8);
    return (v >> 16) | (v << 16);
}

static uint32_t sobol_dim2(uint32_t i)
{
    uint32_t r = 0, v = 1U << 31;
    for (; i; i >>= 1, v ^= v >> 1)
        if (i & 1) r ^= v;
    return r;
}

void prt__sobol2(uint32_t i, uint32_t seed, double *u, double *v)
{
    uint32_t s0 = hash32(seed * 2U + 0x9e3779b9U), s1 = hash32(seed * 2U + 1U + 0x85ebca6bU);
    *u = (double)(reverse_bits(i) ^ s0) * (1.0 / 4294967296.0);
    *v = (double)(sobol_dim2(i) ^ s1) * (1.0 / 4294967296.0);
}

void prt__cosine_dir(double u1, double u2, const float n[3], const float tx[3], const float ty[3], float out[3])
{
    const double r = sqrt(u1), phi = 2.0 * PRT_PI * u2, z = sqrt(1.0 - u1 > 0.0 ? 1.0 - u1 : 0.0);
    const double lx = r * cos(phi), ly = r * sin(phi);
    for (int a = 0; a < 3; ++a) out[a] = (float)(lx * tx[a] + ly * ty[a] + z * n[a]);
}

void prt__sphere_dir(double u, double v, double dir[3])
{
    double z = 1.0 - 2.0 * u;
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * PRT_PI * v;
    dir[0] = r * cos(phi);
    dir[1] = r * sin(phi);
    dir[2] = z;
}
