/* IEEE 754 binary16 ("half") conversions, round to nearest even: where 11 significant bits are
 * plenty (0.05% relative), files store halves. */
#include "core/internal.h"

#include <math.h>
#include <string.h>

uint16_t prt__half_from_float(float f)
{
    uint32_t x;
    memcpy(&x, &f, 4);
    const uint32_t sign = (x >> 16) & 0x8000u, a = x & 0x7fffffffu;
    if (a >= 0x7f800000u) return (uint16_t)(sign | 0x7c00u | (a > 0x7f800000u ? 0x200u : 0));   /* inf, nan */
    if (a >= 0x477ff000u) return (uint16_t)(sign | 0x7c00u);                                     /* rounds past 65504 */
    if (a < 0x38800000u) {   /* below 2^-14: a multiple of 2^-24 (subnormal, or the smallest normal) */
        float m;
        memcpy(&m, &a, 4);
        return (uint16_t)(sign | (uint32_t)lrintf(m * 16777216.0f));   /* exact scaling; nearest even */
    }
    uint32_t h = ((a - 0x38000000u) >> 13), rest = a & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) h++;
    return (uint16_t)(sign | h);
}

float prt__half_to_float(uint16_t h)
{
    const uint32_t sign = (uint32_t)(h & 0x8000u) << 16, e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    uint32_t x;
    if (e == 0x1f) x = sign | 0x7f800000u | (m << 13);
    else if (e) x = sign | ((e + 112) << 23) | (m << 13);
    else if (!m) x = sign;
    else {   /* subnormal: normalise */
        int k = 0;
        uint32_t mm = m;
        while (!(mm & 0x400u)) { mm <<= 1; ++k; }
        x = sign | ((uint32_t)(113 - k) << 23) | ((mm & 0x3ffu) << 13);
    }
    float f;
    memcpy(&f, &x, 4);
    return f;
}
