/* Participating media: density grids in world boxes, their extinction, optical depth along rays,
 * the Henyey-Greenstein phase function, and procedural grids ("cloud", "smoke"). */
#include "geom/volume.h"

#include <stdlib.h>
#include <string.h>

prt_status prt_volume_check(const prt_volume_desc *d)
{
    if (!d) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: no description");
    size_t n = 1;
    for (int c = 0; c < 3; ++c) {
        if (d->dims[c] < 1 || d->dims[c] > PRT_VOLUME_MAX_DIM)
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: grid size %d along axis %d out of range 1..%d", d->dims[c], c, PRT_VOLUME_MAX_DIM);
        n *= (size_t)d->dims[c];
        if (!isfinite(d->lo[c]) || !isfinite(d->hi[c]) || !(d->hi[c] > d->lo[c]))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: its box must have finite corners with max > min on every axis");
        if (!(d->albedo[c] >= 0 && d->albedo[c] <= 1)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: albedo must lie in [0, 1]");
    }
    if (!d->density) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: no densities");
    if (!(d->sigma_t >= 0) || !isfinite(d->sigma_t)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: extinction must be finite and >= 0");
    if (!(fabsf(d->g) < 1)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: Henyey-Greenstein g must lie in (-1, 1)");
    for (size_t i = 0; i < n; ++i)
        if (!(d->density[i] >= 0) || !isfinite(d->density[i]))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "volume: density %zu is %g (densities are finite and >= 0)", i, (double)d->density[i]);
    return PRT_OK;
}

prt_status prt__volume_init(prt_context *ctx, const prt_volume_desc *d, prt__volume *v)
{
    memset(v, 0, sizeof *v);
    prt_status st = prt_volume_check(d);
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    const size_t n = (size_t)d->dims[0] * d->dims[1] * d->dims[2];
    if (!(v->density = malloc(n * sizeof(float)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for a volume of %zu voxels", n);
    memcpy(v->density, d->density, n * sizeof(float));
    memcpy(v->dims, d->dims, sizeof v->dims);
    memcpy(v->lo, d->lo, sizeof v->lo);
    memcpy(v->hi, d->hi, sizeof v->hi);
    memcpy(v->albedo, d->albedo, sizeof v->albedo);
    v->sigma_t = d->sigma_t;
    v->g = d->g;
    for (size_t i = 0; i < n; ++i) v->max_density = fmaxf(v->max_density, v->density[i]);
    return PRT_OK;
}

void prt__volume_free(prt__volume *v)
{
    free(v->density);
    memset(v, 0, sizeof *v);
}

void prt__volume_voxel_centre(const prt__volume *v, int x, int y, int z, float p[3])
{
    const int ix[3] = {x, y, z};
    for (int c = 0; c < 3; ++c) p[c] = v->lo[c] + (v->hi[c] - v->lo[c]) * ((float)ix[c] + 0.5f) / (float)v->dims[c];
}

float prt__volume_extinction(const prt__volume *v, const float p[3])
{
    int i0[3];
    float f[3];
    for (int c = 0; c < 3; ++c) {
        if (!(p[c] >= v->lo[c] && p[c] <= v->hi[c])) return 0.0f;
        /* Voxel centres at (i + 0.5) / dims: clamped to the outer centres near the faces. */
        float u = (p[c] - v->lo[c]) / (v->hi[c] - v->lo[c]) * (float)v->dims[c] - 0.5f;
        u = fminf(fmaxf(u, 0.0f), (float)(v->dims[c] - 1));
        i0[c] = (int)u;
        if (i0[c] > v->dims[c] - 2) i0[c] = v->dims[c] > 1 ? v->dims[c] - 2 : 0;
        f[c] = v->dims[c] > 1 ? u - (float)i0[c] : 0.0f;
    }
    const size_t sx = 1, sy = (size_t)v->dims[0], sz = (size_t)v->dims[0] * v->dims[1];
    const size_t dx = v->dims[0] > 1 ? sx : 0, dy = v->dims[1] > 1 ? sy : 0, dz = v->dims[2] > 1 ? sz : 0;
    const float *a = v->density + (size_t)i0[2] * sz + (size_t)i0[1] * sy + (size_t)i0[0];
    const float c00 = a[0] + f[0] * (a[dx] - a[0]), c10 = a[dy] + f[0] * (a[dy + dx] - a[dy]);
    const float c01 = a[dz] + f[0] * (a[dz + dx] - a[dz]), c11 = a[dz + dy] + f[0] * (a[dz + dy + dx] - a[dz + dy]);
    const float c0 = c00 + f[1] * (c10 - c00), c1 = c01 + f[1] * (c11 - c01);
    return v->sigma_t * (c0 + f[2] * (c1 - c0));
}

bool prt__volume_clip(const prt__volume *v, const float o[3], const float d[3], float tmax, float *t0, float *t1)
{
    float a = 0.0f, b = tmax;
    for (int c = 0; c < 3; ++c) {
        if (fabsf(d[c]) < 1e-12f) {
            if (o[c] < v->lo[c] || o[c] > v->hi[c]) return false;
            continue;
        }
        float ta = (v->lo[c] - o[c]) / d[c], tb = (v->hi[c] - o[c]) / d[c];
        if (ta > tb) { const float s = ta; ta = tb; tb = s; }
        a = fmaxf(a, ta);
        b = fminf(b, tb);
    }
    if (!(b > a)) return false;
    *t0 = a;
    *t1 = b;
    return true;
}

float prt__volume_step(const prt__volume *v)
{
    float s = INFINITY;
    for (int c = 0; c < 3; ++c) s = fminf(s, (v->hi[c] - v->lo[c]) / (float)v->dims[c]);
    return 0.5f * s;
}

float prt__volumes_optical_depth(const prt__volume *v, int count, const float o[3], const float d[3], float tmax)
{
    float tau = 0.0f;
    for (int k = 0; k < count; ++k) {
        float t0, t1;
        if (!(v[k].max_density > 0 && v[k].sigma_t > 0) || !prt__volume_clip(&v[k], o, d, tmax, &t0, &t1)) continue;
        const float h = prt__volume_step(&v[k]);
        const int steps = (int)ceilf((t1 - t0) / h);
        const float dt = (t1 - t0) / (float)(steps > 0 ? steps : 1);
        for (int i = 0; i < steps; ++i) {
            const float t = t0 + ((float)i + 0.5f) * dt, p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
            tau += prt__volume_extinction(&v[k], p) * dt;
        }
    }
    return tau;
}

float prt__hg_phase(float g, float cos_theta)
{
    const float den = 1.0f + g * g - 2.0f * g * cos_theta;
    return (float)(1.0 / (4.0 * PRT_PI)) * (1.0f - g * g) / (den * sqrtf(den));
}

void prt__hg_sample(float g, const float w[3], double u1, double u2, float out[3])
{
    double c;   /* cos of the angle to w (pbrt's inversion, with g's sign kept) */
    if (fabsf(g) < 1e-3f) c = 1.0 - 2.0 * u1;
    else {
        const double s = (1.0 - (double)g * g) / (1.0 - g + 2.0 * g * u1);
        c = (1.0 + (double)g * g - s * s) / (2.0 * g);
    }
    c = fmin(fmax(c, -1.0), 1.0);
    const double sn = sqrt(fmax(0.0, 1.0 - c * c)), phi = 2.0 * PRT_PI * u2;
    float t[3], b[3];
    const float a[3] = {fabsf(w[0]) > 0.9f ? 0.0f : 1.0f, fabsf(w[0]) > 0.9f ? 1.0f : 0.0f, 0.0f};
    prt__v3_cross(w, a, t);
    prt__v3_normalize(t);
    prt__v3_cross(w, t, b);
    for (int k = 0; k < 3; ++k) out[k] = (float)(sn * cos(phi) * t[k] + sn * sin(phi) * b[k] + c * w[k]);
}

/* Value noise from an integer hash of the lattice point and the seed: the same numbers on every
 * machine (integer maths, then doubles). */
static double lattice(int x, int y, int z, uint32_t seed)
{
    uint64_t h = (uint64_t)(uint32_t)x * 0x9E3779B97F4A7C15ull ^ (uint64_t)(uint32_t)y * 0xC2B2AE3D27D4EB4Full ^
                 (uint64_t)(uint32_t)z * 0x165667B19E3779F9ull ^ (uint64_t)seed * 0x27D4EB2F165667C5ull;
    h ^= h >> 33; h *= 0xff51afd7ed558ccdull; h ^= h >> 33; h *= 0xc4ceb9fe1a85ec53ull; h ^= h >> 33;
    return (double)(h >> 11) * (1.0 / 9007199254740992.0);
}

static double noise3(double x, double y, double z, uint32_t seed)
{
    const int ix = (int)floor(x), iy = (int)floor(y), iz = (int)floor(z);
    double fx = x - ix, fy = y - iy, fz = z - iz;
    fx = fx * fx * (3 - 2 * fx); fy = fy * fy * (3 - 2 * fy); fz = fz * fz * (3 - 2 * fz);
    double r = 0;
    for (int c = 0; c < 8; ++c) {
        const int a = c & 1, b = c >> 1 & 1, e = c >> 2 & 1;
        r += (a ? fx : 1 - fx) * (b ? fy : 1 - fy) * (e ? fz : 1 - fz) * lattice(ix + a, iy + b, iz + e, seed);
    }
    return r;
}

static double fbm(double x, double y, double z, uint32_t seed)
{
    double sum = 0, amp = 0.5;
    for (int o = 0; o < 4; ++o, amp *= 0.5, x *= 2.03, y *= 2.03, z *= 2.03) sum += amp * noise3(x, y, z, seed + (uint32_t)o * 7919u);
    return sum / 0.9375;   /* in [0, 1] */
}

static double smooth01(double e0, double e1, double x)
{
    double t = fmin(fmax((x - e0) / (e1 - e0), 0.0), 1.0);
    return t * t * (3 - 2 * t);
}

prt_status prt_volume_generate(prt_context *ctx, const char *kind, const int dims[3], uint32_t seed, float **out)
{
    if (!kind || !dims || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_volume_generate: kind, dims and out are required");
    const bool cloud = !strcmp(kind, "cloud"), smoke = !strcmp(kind, "smoke");
    if (!cloud && !smoke) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "unknown procedural volume '%s' (cloud or smoke)", kind);
    for (int c = 0; c < 3; ++c)
        if (dims[c] < 1 || dims[c] > PRT_VOLUME_MAX_DIM) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "volume grid size %d out of range 1..%d", dims[c], PRT_VOLUME_MAX_DIM);
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    float *d = malloc(n * sizeof *d);
    if (!d) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for a volume of %zu voxels", n);
    /* A cloud: puffs placed from the seed on a low heap, their union softened and eroded by
     * noise; its base flattened. */
    double puff[14][4];
    for (int k = 0; k < 14; ++k) {
        const double a = 2 * PRT_PI * lattice(k, 1, 0, seed), r = 0.26 * sqrt(lattice(k, 2, 0, seed));
        puff[k][3] = 0.09 + 0.14 * lattice(k, 3, 0, seed) * (1 - r / 0.26 * 0.5);   /* bigger in the middle */
        puff[k][0] = 0.5 + r * cos(a);
        puff[k][2] = 0.5 + r * sin(a);
        puff[k][1] = 0.3 + 0.9 * puff[k][3] + 0.1 * lattice(k, 4, 0, seed);
    }
    for (int z = 0; z < dims[2]; ++z)
        for (int y = 0; y < dims[1]; ++y)
            for (int x = 0; x < dims[0]; ++x) {
                const double u = (x + 0.5) / dims[0], v = (y + 0.5) / dims[1], w = (z + 0.5) / dims[2];
                double rho;
                if (cloud) {
                    double f = -1;
                    for (int k = 0; k < 14; ++k) {
                        const double dx = u - puff[k][0], dy = v - puff[k][1], dz = w - puff[k][2];
                        f = fmax(f, 1.0 - sqrt(dx * dx + dy * dy + dz * dz) / puff[k][3]);
                    }
                    const double nse = fbm(u * 6, v * 6, w * 6, seed);
                    rho = smooth01(0.0, 0.25, f + 0.4 * (nse - 0.5)) * smooth01(0.24, 0.32, v + 0.05 * (nse - 0.5));
                } else {
                    const double cx = 0.5 + 0.12 * (fbm(v * 2, 0.3, 0.7, seed) - 0.5) * 2 * v, cz = 0.5 + 0.12 * (fbm(0.9, v * 2, 0.1, seed) - 0.5) * 2 * v;
                    const double radius = 0.06 + 0.3 * v, r = sqrt((u - cx) * (u - cx) + (w - cz) * (w - cz));
                    const double nse = fbm(u * 6, v * 6 - 0.0, w * 6, seed);
                    rho = smooth01(0.0, 0.4, 1.0 - r / radius) * (0.4 + 0.9 * nse) * (1.0 - smooth01(0.7, 1.0, v)) * smooth01(0.0, 0.05, v);
                }
                d[((size_t)z * dims[1] + y) * dims[0] + x] = (float)fmax(rho, 0.0);
            }
    *out = d;
    return PRT_OK;
}
