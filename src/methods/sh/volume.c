/* Transfer in participating media (Kautz's course notes, "diffuse volume"): per voxel of a
 * volume's grid, how distant lighting (SH) becomes the light its medium scatters.
 *
 * What is stored, and why: the radiance a voxel scatters towards a direction w is, per unit
 * extinction, S(w) = albedo integral p(w, s) L_in(s) ds. With the Henyey-Greenstein phase
 * function the integral is a convolution: S_lm = albedo g^l L_in,lm (Funk-Hecke), so a voxel
 * needs the SH of the radiance arriving there, band by band, as rows of a matrix from the
 * lighting's coefficients. We keep bands 0 and 1 (`bands` 2) when g != 0 and band 0 only for
 * isotropic media: g^2 of a cloud's g (0.3-0.6) is under a third, and every band kept costs
 * 3 order^2 floats a row per voxel. The rows hold all the light arriving, direct and scattered:
 *     incident[c][i][j] = integral y_i(s) T(p, s) [y_j(s) where s escapes to the distant light,
 *                         the surfaces' exit transfer E_c,j where s meets a front face] ds
 *                       + sum over orders b >= 1 of the rows of light scattered b times,
 * T(p, s) the transmittance of every volume towards s. Orders are iterated over the grid, each
 * scattered isotropically into the next (bands 1+ of a source are left out of the march: after
 * a scattering or two light has lost most of its direction):
 *     S^1_c = albedo_c incident_direct[c][0] / sqrt(4 pi),
 *     rows of order b at p: 4 pi / K sum_k y_i(s_k) integral T sigma_t S^b(p + t s_k) dt,
 *     S^(b+1)_c = albedo_c (its row 0) / sqrt(4 pi),
 * marched voxel by voxel (exact exp per step of the extinction at its middle: what the direct
 * rows' transmittance uses too), each voxel's orders scaled so that its K directions stop the
 * share of light its direct rows' many directions found stopped (light neither appears nor
 * vanishes between orders), until an order adds under 0.1% of the total or 24 orders, then a
 * geometric tail. Every voxel depends only on its own rays and the previous order, so results
 * do not depend on the thread count. */
#include "methods/sh/volume.h"

#include <stdlib.h>
#include <string.h>

#define VOLUME_DIRS_MAX 256   /* directions per voxel for the direct rows */
#define BOUNCE_DIRS 48        /* directions per voxel for the orders of scattering */
#define MAX_ORDERS 24

void prt__sh_volume_free(prt__sh_volume *v)
{
    prt__volume_free(&v->medium);
    free(v->incident);
    memset(v, 0, sizeof *v);
}

size_t prt__sh_volume_bytes(const prt__sh_volume *v, int order)
{
    const size_t n = (size_t)order * order;
    size_t active = 0;
    for (int z = 0; z < v->medium.dims[2]; ++z)
        for (int y = 0; y < v->medium.dims[1]; ++y)
            for (int x = 0; x < v->medium.dims[0]; ++x) active += prt__sh_volume_active(&v->medium, x, y, z);
    return prt__volume_voxels(&v->medium) * 4 + active * 3 * n * (size_t)v->bands * v->bands * 2;
}

/* A voxel whose neighbourhood holds no medium scatters nothing that trilinear reads reach: its
 * transfer is zero, and files leave it out. */
bool prt__sh_volume_active(const prt__volume *v, int x, int y, int z)
{
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int a = x + dx, b = y + dy, c = z + dz;
                if (a < 0 || b < 0 || c < 0 || a >= v->dims[0] || b >= v->dims[1] || c >= v->dims[2]) continue;
                if (v->density[((size_t)c * v->dims[1] + b) * v->dims[0] + a] > 0) return true;
            }
    return false;
}

/* Marches volume v from o along d up to tmax one voxel at a time (trilinear extinction at each
 * step's middle, exact attenuation per step; the source of the nearest voxel). With src ([voxel][stride]) adds T (1 - e) src[voxel] into acc (count
 * floats); returns the transmittance at the end. */
static float march(const prt__volume *v, const float o[3], const float d[3], float tmax, const float *src, size_t stride, int count, float *acc)
{
    float t0, t1;
    if (!prt__volume_clip(v, o, d, tmax, &t0, &t1)) return 1.0f;
    const float h = 2.0f * prt__volume_step(v);
    float T = 1.0f;
    for (float t = t0; t < t1 && T > 1e-4f; t += h) {
        const float dt = fminf(h, t1 - t), tm = t + 0.5f * dt;
        size_t idx = 0, mul = 1;
        for (int c = 0; c < 3; ++c) {
            int i = (int)((o[c] + tm * d[c] - v->lo[c]) / (v->hi[c] - v->lo[c]) * (float)v->dims[c]);
            i = i < 0 ? 0 : i >= v->dims[c] ? v->dims[c] - 1 : i;
            idx += (size_t)i * mul;
            mul *= (size_t)v->dims[c];
        }
        const float pm[3] = {o[0] + tm * d[0], o[1] + tm * d[1], o[2] + tm * d[2]};
        const float sigma = prt__volume_extinction(v, pm);   /* the medium the renderer and the path tracer see */
        if (!(sigma > 0)) continue;
        const float e = expf(-sigma * dt);
        if (src) {
            const float w = T * (1.0f - e);
            const float *s = src + idx * stride;
            for (int k = 0; k < count; ++k) acc[k] += w * s[k];
        }
        T *= e;
    }
    return T;
}

prt_status prt__sh_volume_bake(prt_context *ctx, const prt__volume_scene *in, int which, prt__sh_volume *out, prt__progress *p)
{
    const prt__volume *v = &in->volumes[which];
    const int order = in->order, n = order * order, bands = fabsf(v->g) > 1e-6f && order > 1 ? 2 : 1, rows = bands * bands;
    const size_t voxels = prt__volume_voxels(v), per_direct = 3 * (size_t)rows * n, per_multi = 3 * (size_t)n;
    const double w_bounce = 4.0 * PRT_PI / BOUNCE_DIRS;
    memset(out, 0, sizeof *out);
    prt_volume_desc d = {.density = v->density, .sigma_t = v->sigma_t, .g = v->g};
    memcpy(d.dims, v->dims, sizeof d.dims);
    memcpy(d.lo, v->lo, sizeof d.lo);
    memcpy(d.hi, v->hi, sizeof d.hi);
    memcpy(d.albedo, v->albedo, sizeof d.albedo);
    prt_status st = prt__volume_init(ctx, &d, &out->medium);
    if (st) return st;
    out->bands = bands;
    const int ndir = in->samples < VOLUME_DIRS_MAX ? in->samples : VOLUME_DIRS_MAX;
    float *dirs = malloc((size_t)(ndir + BOUNCE_DIRS) * 3 * sizeof *dirs), *ys = malloc((size_t)(ndir + BOUNCE_DIRS) * n * sizeof *ys);
    float *last_rows = prt__calloc(voxels * per_direct, sizeof(float));   /* the last order's rows, for the tail */
    float *tmax = malloc(voxels * BOUNCE_DIRS * sizeof *tmax);
    float *prev = prt__calloc(voxels * per_multi, sizeof(float)), *next = prt__calloc(voxels * per_multi, sizeof(float));
    uint8_t *act = malloc(voxels);
    float *absorbed = prt__calloc(voxels, sizeof(float));   /* share of the direct rows' rays the medium stops */
    out->incident = prt__calloc(voxels * per_direct, sizeof(float));
    if (!dirs || !ys || !last_rows || !tmax || !prev || !next || !act || !absorbed || !out->incident) {
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the transfer of a volume of %zu voxels", voxels);
        goto done;
    }
    for (int j = 0; j < ndir + BOUNCE_DIRS; ++j) {
        double a, b, dir[3], y[PRT_SH_MAX_COEFFS];
        if (j < ndir) prt__sobol2((uint32_t)j, in->seed, &a, &b);
        else prt__sobol2((uint32_t)(j - ndir), in->seed ^ 0x5eed5eedu, &a, &b);
        prt__sphere_dir(a, b, dir);
        for (int c = 0; c < 3; ++c) dirs[j * 3 + c] = (float)dir[c];
        prt_sh_eval(order, dir, y);
        for (int i = 0; i < n; ++i) ys[(size_t)j * n + i] = (float)y[i];
    }
    for (int z = 0; z < v->dims[2]; ++z)
        for (int y = 0; y < v->dims[1]; ++y)
            for (int x = 0; x < v->dims[0]; ++x) act[((size_t)z * v->dims[1] + y) * v->dims[0] + x] = prt__sh_volume_active(v, x, y, z);
    /* Progress: the direct rows, then one step per order of scattering. */
    prt__progress_begin(p, p->stage, (uint64_t)v->dims[2] * (1 + MAX_ORDERS));
    int cancelled = 0;
    const double w = 4.0 * PRT_PI / ndir, k0 = 1.0 / sqrt(4.0 * PRT_PI);
#pragma omp parallel for num_threads(prt__threads(ctx)) schedule(dynamic, 1)
    for (int z = 0; z < v->dims[2]; ++z) {
        if (__atomic_load_n(&cancelled, __ATOMIC_RELAXED)) continue;
        double acc[3 * 4 * PRT_SH_MAX_COEFFS];
        for (int y = 0; y < v->dims[1]; ++y)
            for (int x = 0; x < v->dims[0]; ++x) {
                const size_t k = ((size_t)z * v->dims[1] + y) * v->dims[0] + x;
                float o[3];
                prt__volume_voxel_centre(v, x, y, z, o);
                for (int s = 0; s < BOUNCE_DIRS; ++s) {
                    prt__ray_hit h;
                    tmax[k * BOUNCE_DIRS + s] = in->rc && prt__raycaster_hit(in->rc, o, dirs + (size_t)(ndir + s) * 3, &h) ? h.t : INFINITY;
                }
                if (!act[k]) continue;
                memset(acc, 0, per_direct * sizeof *acc);
                double stopped = 0;
                for (int s = 0; s < ndir; ++s) {
                    const float *dir = dirs + (size_t)s * 3, *ysb = ys + (size_t)s * n;
                    prt__ray_hit h;
                    const bool hit = in->rc && prt__raycaster_hit(in->rc, o, dir, &h);
                    const float t_end = hit ? h.t : INFINITY;
                    float T = march(v, o, dir, t_end, NULL, 0, 0, NULL);
                    stopped += 1.0 - T;
                    for (int q = 0; q < in->count; ++q)
                        if (q != which) T *= expf(-prt__volumes_optical_depth(&in->volumes[q], 1, o, dir, t_end));
                    if (!(T > 0)) continue;
                    float E[3][PRT_SH_MAX_COEFFS];
                    if (hit) {   /* a surface: what it sends back (front faces only), else nothing */
                        if (!in->exit || h.ng[0] * dir[0] + h.ng[1] * dir[1] + h.ng[2] * dir[2] >= 0) continue;
                        const uint32_t *tri = in->mesh->indices + (size_t)h.prim * 3;
                        const float bw[3] = {1.0f - h.u - h.v, h.u, h.v};
                        for (int c = 0; c < 3; ++c)
                            for (int j = 0; j < n; ++j) {
                                float sum = 0;
                                for (int q = 0; q < 3; ++q) {
                                    const size_t vx = tri[q];
                                    sum += bw[q] * (in->exit_channels == 3 ? in->exit[(vx * 3 + (size_t)c) * n + j] : in->exit[vx * n + j] * in->mesh->albedo[vx * 3 + c]);
                                }
                                E[c][j] = sum;
                            }
                    }
                    for (int c = 0; c < 3; ++c) {
                        const float *src = hit ? E[c] : ysb;
                        for (int i = 0; i < rows; ++i) {
                            const double a = w * T * ysb[i];
                            double *row = acc + ((size_t)c * rows + i) * n;
                            for (int j = 0; j < n; ++j) row[j] += a * src[j];
                        }
                    }
                }
                absorbed[k] = (float)(stopped / ndir);
                float *dst = out->incident + k * per_direct;
                for (size_t i = 0; i < per_direct; ++i) dst[i] = (float)acc[i];
                for (int c = 0; c < 3; ++c)
                    for (int j = 0; j < n; ++j) prev[k * per_multi + (size_t)c * n + j] = (float)(v->albedo[c] * k0 * acc[(size_t)c * rows * n + j]);
            }
        if (prt__progress_add(p, 1)) __atomic_store_n(&cancelled, 1, __ATOMIC_RELAXED);
    }
    double last[3] = {0, 0, 0}, before[3] = {0, 0, 0}, total[3] = {0, 0, 0};
    for (size_t k = 0; k < voxels; ++k)
        for (int c = 0; c < 3; ++c) total[c] += prev[k * per_multi + (size_t)c * n];
    int orders = 1;
    for (int b = 2; b <= MAX_ORDERS && !cancelled; ++b) {
#pragma omp parallel for num_threads(prt__threads(ctx)) schedule(dynamic, 1)
        for (int z = 0; z < v->dims[2]; ++z) {
            if (__atomic_load_n(&cancelled, __ATOMIC_RELAXED)) continue;
            float acc[3 * PRT_SH_MAX_COEFFS];
            double lam[3 * 4 * PRT_SH_MAX_COEFFS];
            for (int y = 0; y < v->dims[1]; ++y)
                for (int x = 0; x < v->dims[0]; ++x) {
                    const size_t k = ((size_t)z * v->dims[1] + y) * v->dims[0] + x;
                    float *dst = next + k * per_multi, *lr = last_rows + k * per_direct;
                    if (!act[k]) { memset(dst, 0, per_multi * sizeof *dst); continue; }
                    float o[3];
                    prt__volume_voxel_centre(v, x, y, z, o);
                    memset(lam, 0, per_direct * sizeof *lam);
                    double stopped = 0;
                    for (int s = 0; s < BOUNCE_DIRS; ++s) {
                        memset(acc, 0, per_multi * sizeof *acc);
                        stopped += 1.0 - march(v, o, dirs + (size_t)(ndir + s) * 3, tmax[k * BOUNCE_DIRS + s], prev, per_multi, (int)per_multi, acc);
                        const float *yk = ys + (size_t)(ndir + s) * n;
                        for (int c = 0; c < 3; ++c)
                            for (int i = 0; i < rows; ++i)
                                for (int j = 0; j < n; ++j) lam[((size_t)c * rows + i) * n + j] += yk[i] * acc[(size_t)c * n + j];
                    }
                    /* The few scattering directions stop another share of the light than the
                     * direct rows' many found: scaled to theirs, light neither appears nor
                     * vanishes between orders (a non-absorbing medium in a white furnace stays
                     * at 1 voxel by voxel). */
                    const double scale = w_bounce * (stopped > 1e-6 * BOUNCE_DIRS ? absorbed[k] * BOUNCE_DIRS / stopped : 1.0);
                    for (size_t i = 0; i < per_direct; ++i) lr[i] = (float)(scale * lam[i]);
                    for (int c = 0; c < 3; ++c)
                        for (int j = 0; j < n; ++j) dst[(size_t)c * n + j] = (float)(v->albedo[c] * k0 * lr[(size_t)c * rows * n + j]);
                }
            if (prt__progress_add(p, 1)) __atomic_store_n(&cancelled, 1, __ATOMIC_RELAXED);
        }
        if (cancelled) break;
        memcpy(before, last, sizeof before);
        memset(last, 0, sizeof last);
        for (size_t k = 0; k < voxels; ++k) {
            for (size_t i = 0; i < per_direct; ++i) out->incident[k * per_direct + i] += last_rows[k * per_direct + i];
            for (int c = 0; c < 3; ++c) last[c] += next[k * per_multi + (size_t)c * n];
        }
        float *tmp = prev; prev = next; next = tmp;
        orders = b;
        bool small = true;
        for (int c = 0; c < 3; ++c) { total[c] += last[c]; small &= !(fabs(last[c]) > 1e-3 * fabs(total[c])); }
        if (small) break;
    }
    /* The orders left out shrink about geometrically: their sum from the last one's ratio. */
    if (!cancelled && orders == MAX_ORDERS)
        for (int c = 0; c < 3; ++c) {
            const double r = before[c] > 0 ? fmin(fmax(last[c] / before[c], 0.0), 0.95) : 0.0, tail = r / (1.0 - r);
            for (size_t k = 0; k < voxels; ++k)
                for (size_t i = 0; i < (size_t)rows * n; ++i) out->incident[k * per_direct + (size_t)c * rows * n + i] += (float)tail * last_rows[k * per_direct + (size_t)c * rows * n + i];
        }
    out->orders = orders;
    prt__progress_end(p);
    if (cancelled) st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    else prt__log(ctx, PRT_LOG_INFO, "volume %d: %d x %d x %d voxels, %d directions (%d for scattering), %d orders of scattering%s", which, v->dims[0], v->dims[1],
                  v->dims[2], ndir, BOUNCE_DIRS, orders, orders == MAX_ORDERS ? " and a geometric tail" : "");
done:
    free(dirs); free(ys); free(last_rows); free(tmax); free(prev); free(next); free(act); free(absorbed);
    if (st) prt__sh_volume_free(out);
    return st;
}

void prt__sh_volume_source(const prt__sh_volume *v, int order, const prt_sh_light *light, float *out)
{
    const int n = order * order, rows = v->bands * v->bands;
    const size_t voxels = prt__volume_voxels(&v->medium), per = 3 * (size_t)rows * n;
    const int ln = light->order < order ? light->order * light->order : n;
    for (size_t k = 0; k < voxels; ++k) {
        const float *I = v->incident + k * per;
        float *o = out + k * 3 * (size_t)rows;
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < rows; ++i) {
                float sum = 0;
                for (int j = 0; j < ln; ++j) sum += I[((size_t)c * rows + i) * n + j] * light->coeffs[c][j];
                /* band l of the arriving light scatters with g^l (Funk-Hecke of the HG lobe). */
                o[c * rows + i] = v->medium.albedo[c] * (i == 0 ? 1.0f : v->medium.g) * sum;
            }
    }
}
