/* Separable BRDF approximation by truncated SVD (Kautz & McCool 1999), sampled on the
 * parameterizations of Wang, Tran & Luebke 2005 (eq. 10 grid, eq. 11 polar). */
#include "brdf/separable.h"
#include "core/internal.h"

#include <lapacke.h>
#include <math.h>
#include <string.h>

#define MIN_COMPUTED 8

prt_brdf_factors *prt__brdf_factors_alloc(int terms, int computed, int resolution, prt_brdf_param param)
{
    prt_brdf_factors *f = prt__calloc(1, sizeof *f);
    if (!f) return NULL;
    size_t n = (size_t)3 * computed * resolution * resolution;
    f->light = prt__calloc(n, sizeof(float));
    f->view = prt__calloc(n, sizeof(float));
    if (!f->light || !f->view) { prt_brdf_factors_release(f); return NULL; }
    f->terms = terms;
    f->computed = computed;
    f->resolution = resolution;
    f->param = param;
    return f;
}

void prt_brdf_factors_release(prt_brdf_factors *f)
{
    if (!f) return;
    free(f->light);
    free(f->view);
    free(f);
}

int prt_brdf_factors_terms(const prt_brdf_factors *f) { return f ? f->terms : 0; }
int prt_brdf_factors_computed(const prt_brdf_factors *f) { return f ? f->computed : 0; }
int prt_brdf_factors_resolution(const prt_brdf_factors *f) { return f ? f->resolution : 0; }
prt_brdf_param prt_brdf_factors_param(const prt_brdf_factors *f) { return f ? f->param : PRT_BRDF_PARAM_GRID; }
float prt_brdf_factors_sigma(const prt_brdf_factors *f, int c, int k)
{
    return f && c >= 0 && c < 3 && k >= 0 && k < f->computed ? f->sigma[c][k] : 0.0f;
}

void prt__brdf_factors_finish(prt_brdf_factors *f)
{
    const size_t per = (size_t)f->computed * f->resolution * f->resolution * sizeof(float);
    f->grey = !memcmp(f->light, f->light + per / 4, per) && !memcmp(f->light, f->light + per / 2, per) && !memcmp(f->view, f->view + per / 4, per) &&
              !memcmp(f->view, f->view + per / 2, per);
}

bool prt__brdf_cell_dir(prt_brdf_param param, int res, int x, int y, float w[3])
{
    double u = (x + 0.5) / res, v = (y + 0.5) / res;
    if (param == PRT_BRDF_PARAM_GRID) {
        double a = 2 * u - 1, b = 2 * v - 1, r2 = a * a + b * b;
        if (r2 >= 1.0) return false;
        w[0] = (float)a; w[1] = (float)b; w[2] = (float)sqrt(1.0 - r2);
        return true;
    }
    double phi = 2 * PRT_PI * u, ct = 1.0 - v * v, st = sqrt(fmax(0.0, 1.0 - ct * ct));
    w[0] = (float)(st * cos(phi)); w[1] = (float)(st * sin(phi)); w[2] = (float)ct;
    return true;
}

void prt_brdf_frame(const float n[3], float s[3], float t[3])
{
    float ny1 = n[1] + 1.0f;
    s[0] = ny1 * ny1 + n[2] * n[2] - n[0] * n[0];
    s[1] = -2.0f * ny1 * n[0];
    s[2] = -2.0f * n[0] * n[2];
    float l = sqrtf(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    if (l < 1e-6f) {   /* the one singular normal, -y: any tangent will do */
        s[0] = 1; s[1] = 0; s[2] = 0;
    } else {
        for (int i = 0; i < 3; ++i) s[i] /= l;
    }
    prt__v3_cross(n, s, t);
    prt__v3_normalize(t);
}

prt_status prt_brdf_factor(const prt_brdf *b, const prt_brdf_factor_desc *desc, prt_brdf_factors **out)
{
    if (!b || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_brdf_factor: brdf and out are required");
    *out = NULL;
    prt_brdf_factor_desc d = desc ? *desc : (prt_brdf_factor_desc){0};
    if (d.terms == 0) d.terms = 4;
    if (d.resolution == 0) d.resolution = 48;
    if (d.terms < 1 || d.terms > PRT_BRDF_MAX_TERMS)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "BRDF terms %d out of range 1..%d", d.terms, PRT_BRDF_MAX_TERMS);
    if (d.resolution < 4 || d.resolution > 96)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "BRDF map resolution %d out of range 4..96", d.resolution);
    if (d.param != PRT_BRDF_PARAM_GRID && d.param != PRT_BRDF_PARAM_POLAR)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "unknown BRDF parameterization %d", (int)d.param);
    prt_status st = prt_brdf_validate(b);
    if (st) return st;

    const int res = d.resolution, cells = res * res;
    int *cell_of = prt__calloc((size_t)cells, sizeof(int));   /* matrix row of each cell, -1 outside */
    float *dirs = prt__calloc((size_t)cells * 3, sizeof(float));
    if (!cell_of || !dirs) { free(cell_of); free(dirs); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    int m = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x) {
            float w[3];
            cell_of[y * res + x] = prt__brdf_cell_dir(d.param, res, x, y, w) ? m : -1;
            if (cell_of[y * res + x] >= 0) memcpy(dirs + (size_t)m++ * 3, w, sizeof w);
        }
    const int computed = m < (d.terms > MIN_COMPUTED ? d.terms : MIN_COMPUTED) ? m : (d.terms > MIN_COMPUTED ? d.terms : MIN_COMPUTED);
    if (d.terms > m) { free(cell_of); free(dirs); return prt__fail(NULL, PRT_ERR_INVALID_ARG, "%d terms need a finer BRDF map than %d", d.terms, res); }

    size_t mm = (size_t)m * m;
    float *M = prt__calloc(3 * mm, sizeof(float));   /* per channel: row = light cell, column = view cell */
    float *A = prt__calloc(mm, sizeof(float));
    float *U = prt__calloc(mm, sizeof(float)), *VT = prt__calloc(mm, sizeof(float));
    float *S = prt__calloc((size_t)m, sizeof(float));
    float *sw = prt__calloc((size_t)m, sizeof(float));
    prt_brdf_factors *f = prt__brdf_factors_alloc(d.terms, computed, res, d.param);
    if (!M || !A || !U || !VT || !S || !sw || !f) { st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for a %d x %d BRDF matrix", m, m); goto done; }
    /* Each cell weighs by its projected solid angle (cos dw) on both sides, so that the SVD's
     * truncation is the best fit in the norm that matters when rendering: light arrives
     * cosine-weighted and grazing views cover little of the screen. Grid cells all have the same
     * projected solid angle (the disk is the projected hemisphere); polar cells have
     * cos(theta) dw = 2 (1 - v^2) v dv dphi. Without it, the huge grazing values of BRDFs such
     * as Ashikhmin-Shirley take every term. */
    for (int i = 0; i < m; ++i) {
        float z = dirs[(size_t)i * 3 + 2];
        sw[i] = d.param == PRT_BRDF_PARAM_GRID ? 1.0f : sqrtf(z * sqrtf(1.0f - z));   /* sqrt of (1 - v^2) v, v = sqrt(1 - cos) */
    }
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            float rgb[3];
            prt_brdf_eval(b, dirs + (size_t)i * 3, dirs + (size_t)j * 3, rgb);
            for (int c = 0; c < 3; ++c) M[c * mm + (size_t)i * m + j] = rgb[c] * sw[i] * sw[j];
        }
    for (int c = 0; c < 3 && !st; ++c) {
        int same = -1;   /* grey BRDFs: factor once */
        for (int p = 0; p < c && same < 0; ++p)
            if (!memcmp(M + c * mm, M + p * mm, mm * sizeof(float))) same = p;
        float *L = f->light + (size_t)c * computed * cells, *V = f->view + (size_t)c * computed * cells;
        if (same >= 0) {
            memcpy(L, f->light + (size_t)same * computed * cells, (size_t)computed * cells * sizeof(float));
            memcpy(V, f->view + (size_t)same * computed * cells, (size_t)computed * cells * sizeof(float));
            memcpy(f->sigma[c], f->sigma[same], sizeof f->sigma[c]);
            continue;
        }
        memcpy(A, M + c * mm, mm * sizeof(float));
        /* The row-major M read column-major is M^T (rows = view cells): its left vectors are the
         * view maps, its right vectors the light maps. Divide and conquer computes the full SVD
         * (about 1 s for the 1,810 cells of a 48 x 48 grid); sgesvdx's partial SVD proved
         * unreliable on rank-deficient matrices such as a Lambertian BRDF's. */
        lapack_int info = LAPACKE_sgesdd(LAPACK_COL_MAJOR, 'S', m, m, A, m, S, U, m, VT, m);
        if (info != 0) { st = prt__fail(NULL, PRT_ERR_BACKEND, "SVD of the BRDF matrix failed (LAPACK info %d)", (int)info); break; }
        for (int k = 0; k < computed; ++k) {
            float r = sqrtf(fmaxf(S[k], 0.0f));
            f->sigma[c][k] = S[k];
            /* Sign convention: the light map's largest entry positive (SVD leaves it free). */
            /* Column-major: U[i + k m] is view cell i, VT[k + i m] light cell i. */
            int big = 0;
            for (int i = 1; i < m; ++i)
                if (fabsf(VT[k + (size_t)i * m]) > fabsf(VT[k + (size_t)big * m])) big = i;
            float sign = VT[k + (size_t)big * m] < 0 ? -r : r;
            float *lk = L + (size_t)k * cells, *vk = V + (size_t)k * cells;
            for (int cell = 0; cell < cells; ++cell) {
                int i = cell_of[cell];
                if (i < 0) continue;
                lk[cell] = sign * VT[k + (size_t)i * m] / sw[i];
                vk[cell] = sign * U[i + (size_t)k * m] / sw[i];
            }
        }
    }
    if (st) goto done;
    /* Grid cells outside the disk copy the nearest cell inside along the radius, so bilinear
     * lookups near the rim do not blend towards zero. */
    if (d.param == PRT_BRDF_PARAM_GRID) {
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                if (cell_of[y * res + x] >= 0) continue;
                double a = 2.0 * (x + 0.5) / res - 1, bb = 2.0 * (y + 0.5) / res - 1, r = sqrt(a * a + bb * bb);
                int src = -1;
                for (double shrink = 1.0 - 0.5 / res; shrink > 0 && src < 0; shrink -= 0.5 / res) {
                    double aa = a / r * shrink, b2 = bb / r * shrink;
                    int sx = (int)floor((aa + 1) * 0.5 * res), sy = (int)floor((b2 + 1) * 0.5 * res);
                    if (sx >= 0 && sx < res && sy >= 0 && sy < res && cell_of[sy * res + sx] >= 0) src = sy * res + sx;
                }
                if (src < 0) continue;
                for (int c = 0; c < 3; ++c)
                    for (int k = 0; k < computed; ++k) {
                        size_t base = ((size_t)c * computed + k) * cells;
                        f->light[base + (size_t)y * res + x] = f->light[base + src];
                        f->view[base + (size_t)y * res + x] = f->view[base + src];
                    }
            }
    }
    prt__brdf_factors_finish(f);
done:
    free(sw);
    free(cell_of); free(dirs); free(M); free(A); free(U); free(VT); free(S);
    if (st) { prt_brdf_factors_release(f); return st; }
    *out = f;
    return PRT_OK;
}

void prt_brdf_factors_lookup(const prt_brdf_factors *f, int view, int terms, const float w[3], float *out)
{
    if (terms > f->computed) terms = f->computed;
    if (w[2] <= 0.0f) {
        memset(out, 0, (size_t)3 * terms * sizeof(float));
        return;
    }
    const int res = f->resolution;
    float fx, fy;
    if (f->param == PRT_BRDF_PARAM_GRID) {
        fx = (w[0] + 1.0f) * 0.5f * res - 0.5f;
        fy = (w[1] + 1.0f) * 0.5f * res - 0.5f;
    } else {
        float phi = atan2f(w[1], w[0]);
        if (phi < 0) phi += 2.0f * (float)PRT_PI;
        fx = phi / (2.0f * (float)PRT_PI) * res - 0.5f;
        fy = sqrtf(fmaxf(0.0f, 1.0f - w[2])) * res - 0.5f;
    }
    int x0 = (int)floorf(fx), y0 = (int)floorf(fy);
    float tx = fx - x0, ty = fy - y0;
    int x1 = x0 + 1, y1 = y0 + 1;
    if (f->param == PRT_BRDF_PARAM_POLAR) {   /* the angle wraps around */
        x0 = (x0 % res + res) % res;
        x1 = (x1 % res + res) % res;
    } else {
        x0 = x0 < 0 ? 0 : x0 >= res ? res - 1 : x0;
        x1 = x1 < 0 ? 0 : x1 >= res ? res - 1 : x1;
    }
    y0 = y0 < 0 ? 0 : y0 >= res ? res - 1 : y0;
    y1 = y1 < 0 ? 0 : y1 >= res ? res - 1 : y1;
    const float w00 = (1 - tx) * (1 - ty), w10 = tx * (1 - ty), w01 = (1 - tx) * ty, w11 = tx * ty;
    const size_t cells = (size_t)res * res;
    const float *maps = view ? f->view : f->light;
    const int i00 = y0 * res + x0, i10 = y0 * res + x1, i01 = y1 * res + x0, i11 = y1 * res + x1;
    for (int c = 0; c < (f->grey ? 1 : 3); ++c)
        for (int k = 0; k < terms; ++k) {
            const float *p = maps + ((size_t)c * f->computed + k) * cells;
            out[c * terms + k] = w00 * p[i00] + w10 * p[i10] + w01 * p[i01] + w11 * p[i11];
        }
    if (f->grey) {
        memcpy(out + terms, out, (size_t)terms * sizeof(float));
        memcpy(out + 2 * terms, out, (size_t)terms * sizeof(float));
    }
}

void prt_brdf_factors_eval(const prt_brdf_factors *f, int terms, const float wi[3], const float wo[3], float rgb[3])
{
    float g[3 * PRT_BRDF_MAX_TERMS], h[3 * PRT_BRDF_MAX_TERMS];
    if (terms > f->computed) terms = f->computed;
    prt_brdf_factors_lookup(f, 0, terms, wi, g);
    prt_brdf_factors_lookup(f, 1, terms, wo, h);
    for (int c = 0; c < 3; ++c) {
        float s = 0;
        for (int k = 0; k < terms; ++k) s += g[c * terms + k] * h[c * terms + k];
        rgb[c] = s;
    }
}

/* splitmix64: a fixed, well-mixed stream, so the error report is the same on every run. */
static double next_uniform(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

/* Uniform hemisphere direction from two numbers in [0, 1). */
static void hemi(double u, double v, float w[3])
{
    double ct = u, st = sqrt(fmax(0.0, 1.0 - ct * ct)), phi = 2 * PRT_PI * v;
    w[0] = (float)(st * cos(phi)); w[1] = (float)(st * sin(phi)); w[2] = (float)ct;
}

prt_status prt_brdf_factors_error(const prt_brdf_factors *f, const prt_brdf *b, int samples, double *rms, double *relative)
{
    if (!f || !b || !rms) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_brdf_factors_error: factors, brdf and rms are required");
    if (samples <= 0) samples = 100000;
    const int K = f->computed;
    double err[PRT_BRDF_MAX_TERMS] = {0}, norm = 0, wsum = 0;
    uint64_t rng = 0x9e3779b97f4a7c15ull;
    for (int s = 0; s < samples; ++s) {
        /* Independent pairs: two scrambles of one 2D sequence would tie wo to wi. */
        double u0 = next_uniform(&rng), v0 = next_uniform(&rng), u1 = next_uniform(&rng), v1 = next_uniform(&rng);
        float wi[3], wo[3], g[3 * PRT_BRDF_MAX_TERMS], h[3 * PRT_BRDF_MAX_TERMS], ref[3];
        hemi(u0, v0, wi);
        hemi(u1, v1, wo);
        prt_brdf_eval(b, wi, wo, ref);
        prt_brdf_factors_lookup(f, 0, K, wi, g);
        prt_brdf_factors_lookup(f, 1, K, wo, h);
        const double cw = (double)wi[2] * wo[2];
        wsum += cw * 3;
        for (int c = 0; c < 3; ++c) {
            double acc = 0;
            norm += cw * (double)ref[c] * ref[c];
            for (int k = 0; k < K; ++k) {
                acc += (double)g[c * K + k] * h[c * K + k];
                double e = acc - ref[c];
                err[k] += cw * e * e;
            }
        }
    }
    for (int k = 0; k < K; ++k) {
        rms[k] = sqrt(err[k] / wsum);
        if (relative) relative[k] = norm > 0 ? sqrt(err[k] / norm) : 0.0;
    }
    return PRT_OK;
}
