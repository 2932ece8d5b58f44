/* The BRDF models, their parsing, and their SH projections (zonal lobes and isotropic matrices). */
#include "core/internal.h"
#include "prt/brdf.h"
#include "prt/sh.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Lafortune et al. 1997 three-lobe fits of measured clay and skin (as tabulated in pbrt v1's
 * material library); per lobe Cxy, Cz, n for R, G, B. */
static const prt_brdf LAFORTUNE_CLAY = {
    PRT_BRDF_LAFORTUNE, {0.383626f, 0.260749f, 0.274207f}, {0, 0, 0}, 0, 0, 3,
    {{-1.089701f, -1.102701f, -1.107603f}, {-0.733381f, -0.793320f, -0.848206f}, {-1.010548f, -1.012378f, -1.011263f}},
    {{-1.354682f, -2.714801f, -1.569866f}, {0.676108f, 0.679314f, 0.726031f}, {0.910783f, 0.885239f, 0.892451f}},
    {{17.968505f, 11.024489f, 21.270282f}, {8.219745f, 9.055139f, 11.261951f}, {152.912795f, 141.937171f, 201.046802f}}};
static const prt_brdf LAFORTUNE_SKIN = {
    PRT_BRDF_LAFORTUNE, {0.428425f, 0.301341f, 0.331054f}, {0, 0, 0}, 0, 0, 3,
    {{-1.131747f, -1.016939f, -0.966018f}, {-0.546570f, -0.643533f, -0.638934f}, {-0.998888f, -1.020153f, -1.027479f}},
    {{-1.209182f, -1.462488f, -1.222419f}, {0.380123f, 0.410559f, 0.437367f}, {0.857998f, 0.703913f, 0.573625f}},
    {{6.421658f, 3.699932f, 3.524889f}, {3.685044f, 4.266495f, 4.539742f}, {64.208486f, 63.919687f, 43.809866f}}};

const char *prt_brdf_model_name(prt_brdf_model m)
{
    switch (m) {
    case PRT_BRDF_LAMBERT: return "lambert";
    case PRT_BRDF_PHONG: return "phong";
    case PRT_BRDF_BLINN_PHONG: return "blinn";
    case PRT_BRDF_ASHIKHMIN_SHIRLEY: return "ashikhmin";
    case PRT_BRDF_LAFORTUNE: return "lafortune";
    }
    return "unknown";
}

static void grey(float *rgb, double v) { rgb[0] = rgb[1] = rgb[2] = (float)v; }

/* Reads up to max numbers separated by ':' after the model name; returns the count or -1. */
static int parse_numbers(const char *s, double *out, int max)
{
    int n = 0;
    while (*s == ':') {
        if (n == max) return -1;
        char *end;
        out[n] = strtod(s + 1, &end);
        if (end == s + 1) return -1;
        n++;
        s = end;
    }
    return *s ? -1 : n;
}

prt_status prt_brdf_parse(const char *spec, prt_brdf *out)
{
    static const char *usage = "lambert[:rho], phong:N[:ks[:kd]], blinn:N[:ks[:kd]], ashikhmin:NU:NV[:rs[:rd]], "
                               "lafortune:clay or lafortune:skin";
    if (!spec || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_brdf_parse: spec and out are required");
    prt_brdf b = {0};
    size_t name_len = strcspn(spec, ":");
    const char *rest = spec + name_len;
    double v[4];
    int n;
    if (name_len == 9 && !strncmp(spec, "lafortune", 9)) {
        if (!strcmp(rest, ":clay")) b = LAFORTUNE_CLAY;
        else if (!strcmp(rest, ":skin")) b = LAFORTUNE_SKIN;
        else return prt__fail(NULL, PRT_ERR_INVALID_ARG, "BRDF '%s': lafortune takes a preset, clay or skin", spec);
    } else if ((n = parse_numbers(rest, v, 4)) < 0) {
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "BRDF '%s': expected %s", spec, usage);
    } else if (name_len == 7 && !strncmp(spec, "lambert", 7)) {
        if (n > 1) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "BRDF '%s': lambert takes one reflectance", spec);
        b.model = PRT_BRDF_LAMBERT;
        grey(b.diffuse, n ? v[0] : 0.7);
    } else if ((name_len == 5 && !strncmp(spec, "phong", 5)) || (name_len == 5 && !strncmp(spec, "blinn", 5))) {
        if (n < 1 || n > 3) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "BRDF '%s': %.5s needs an exponent: %.5s:N[:ks[:kd]]", spec, spec, spec);
        b.model = spec[0] == 'p' ? PRT_BRDF_PHONG : PRT_BRDF_BLINN_PHONG;
        b.exponent = (float)v[0];
        grey(b.specular, n > 1 ? v[1] : 0.5);
        grey(b.diffuse, n > 2 ? v[2] : 0.0);
    } else if (name_len == 9 && !strncmp(spec, "ashikhmin", 9)) {
        if (n < 2) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "BRDF '%s': ashikhmin needs two exponents: ashikhmin:NU:NV[:rs[:rd]]", spec);
        b.model = PRT_BRDF_ASHIKHMIN_SHIRLEY;
        b.exponent = (float)v[0];
        b.exponent_v = (float)v[1];
        grey(b.specular, n > 2 ? v[2] : 0.75);   /* the all-frequency paper's k_s and k_d */
        grey(b.diffuse, n > 3 ? v[3] : 0.5);
    } else {
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "unknown BRDF '%s' (use %s)", spec, usage);
    }
    prt_status st = prt_brdf_validate(&b);
    if (st) return prt__fail(NULL, st, "BRDF '%s': %s", spec, prt_last_error());
    *out = b;
    return PRT_OK;
}

static double mean3(const float *c) { return (c[0] + c[1] + c[2]) / 3.0; }

void prt_brdf_format(const prt_brdf *b, char *buf, size_t size)
{
    switch (b->model) {
    case PRT_BRDF_LAMBERT: snprintf(buf, size, "lambert:%g", mean3(b->diffuse)); break;
    case PRT_BRDF_PHONG:
    case PRT_BRDF_BLINN_PHONG:
        snprintf(buf, size, "%s:%g:%g:%g", prt_brdf_model_name(b->model), b->exponent, mean3(b->specular), mean3(b->diffuse));
        break;
    case PRT_BRDF_ASHIKHMIN_SHIRLEY:
        snprintf(buf, size, "ashikhmin:%g:%g:%g:%g", b->exponent, b->exponent_v, mean3(b->specular), mean3(b->diffuse));
        break;
    case PRT_BRDF_LAFORTUNE:
        snprintf(buf, size, "lafortune:%s", b->diffuse[0] == LAFORTUNE_SKIN.diffuse[0] ? "skin" : "clay");
        break;
    }
}

prt_status prt_brdf_validate(const prt_brdf *b)
{
    if ((unsigned)b->model > PRT_BRDF_LAFORTUNE) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "unknown BRDF model %d", (int)b->model);
    for (int c = 0; c < 3; ++c) {
        if (!(b->diffuse[c] >= 0 && b->diffuse[c] <= 1) || !(b->specular[c] >= 0 && b->specular[c] <= 1))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "reflectances must lie in [0, 1]");
    }
    bool uses_exp = b->model == PRT_BRDF_PHONG || b->model == PRT_BRDF_BLINN_PHONG || b->model == PRT_BRDF_ASHIKHMIN_SHIRLEY;
    if (uses_exp && !(b->exponent >= 0 && b->exponent <= 1e5f))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "exponent %g out of range 0..1e5", b->exponent);
    if (b->model == PRT_BRDF_ASHIKHMIN_SHIRLEY && !(b->exponent_v >= 0 && b->exponent_v <= 1e5f))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "exponent n_v %g out of range 0..1e5", b->exponent_v);
    if (b->model == PRT_BRDF_LAFORTUNE) {
        if (b->lobes < 1 || b->lobes > PRT_BRDF_MAX_LOBES)
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "Lafortune lobes %d out of range 1..%d", b->lobes, PRT_BRDF_MAX_LOBES);
        for (int k = 0; k < b->lobes; ++k)
            for (int c = 0; c < 3; ++c)
                if (!isfinite(b->cxy[k][c]) || !isfinite(b->cz[k][c]) || !(b->n[k][c] >= 0 && b->n[k][c] <= 1e5f))
                    return prt__fail(NULL, PRT_ERR_INVALID_ARG, "Lafortune lobe %d is not finite or its exponent is out of range", k);
    }
    return PRT_OK;
}

int prt_brdf_is_isotropic(const prt_brdf *b)
{
    return b->model != PRT_BRDF_ASHIKHMIN_SHIRLEY || b->exponent == b->exponent_v;
}

int prt_brdf_is_glossy(const prt_brdf *b)
{
    if (b->model == PRT_BRDF_LAMBERT) return 0;
    if (b->model == PRT_BRDF_LAFORTUNE || b->model == PRT_BRDF_ASHIKHMIN_SHIRLEY) return 1;
    return b->specular[0] > 0 || b->specular[1] > 0 || b->specular[2] > 0;
}

void prt_brdf_lambert_albedo(const prt_brdf *b, float rgb[3])
{
    for (int c = 0; c < 3; ++c) rgb[c] = b->model == PRT_BRDF_ASHIKHMIN_SHIRLEY ? 0.0f : b->diffuse[c];
}

static double pow5(double x) { double x2 = x * x; return x2 * x2 * x; }

void prt_brdf_eval_glossy(const prt_brdf *b, const float wi[3], const float wo[3], float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (wi[2] <= 0.0f || wo[2] <= 0.0f) return;
    switch (b->model) {
    case PRT_BRDF_LAMBERT: return;
    case PRT_BRDF_PHONG: {
        double rdot = -wi[0] * wo[0] - wi[1] * wo[1] + wi[2] * wo[2];
        if (rdot <= 0) return;
        double s = (b->exponent + 2.0) / (2.0 * PRT_PI) * pow(rdot, b->exponent);
        for (int c = 0; c < 3; ++c) rgb[c] = (float)(b->specular[c] * s);
        return;
    }
    case PRT_BRDF_BLINN_PHONG: {
        double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
        double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        if (len <= 0) return;
        double s = (b->exponent + 8.0) / (8.0 * PRT_PI) * pow(h[2] / len, b->exponent);
        for (int c = 0; c < 3; ++c) rgb[c] = (float)(b->specular[c] * s);
        return;
    }
    case PRT_BRDF_ASHIKHMIN_SHIRLEY: {
        double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
        double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        if (len <= 0) return;
        for (int k = 0; k < 3; ++k) h[k] /= len;
        double hk = h[0] * wi[0] + h[1] * wi[1] + h[2] * wi[2];
        double sin2 = 1.0 - h[2] * h[2];
        double e = sin2 > 1e-12 ? (b->exponent * h[0] * h[0] + b->exponent_v * h[1] * h[1]) / sin2 : 0.0;
        double spec = sqrt((b->exponent + 1.0) * (b->exponent_v + 1.0)) / (8.0 * PRT_PI) * pow(h[2], e) /
                      (hk * fmax(wi[2], wo[2]));
        double di = 1.0 - pow5(1.0 - wi[2] / 2.0), dd = 1.0 - pow5(1.0 - wo[2] / 2.0);
        for (int c = 0; c < 3; ++c) {
            double rs = b->specular[c];
            double fresnel = rs + (1.0 - rs) * pow5(1.0 - hk);
            double diffuse = 28.0 * b->diffuse[c] / (23.0 * PRT_PI) * (1.0 - rs) * di * dd;
            rgb[c] = (float)(spec * fresnel + diffuse);
        }
        return;
    }
    case PRT_BRDF_LAFORTUNE:
        for (int k = 0; k < b->lobes; ++k)
            for (int c = 0; c < 3; ++c) {
                double base = b->cxy[k][c] * (wi[0] * wo[0] + wi[1] * wo[1]) + b->cz[k][c] * wi[2] * wo[2];
                if (base > 0) rgb[c] += (float)pow(base, b->n[k][c]);
            }
        return;
    }
}

void prt_brdf_eval(const prt_brdf *b, const float wi[3], const float wo[3], float rgb[3])
{
    prt_brdf_eval_glossy(b, wi, wo, rgb);
    if (wi[2] <= 0.0f || wo[2] <= 0.0f) return;
    float kd[3];
    prt_brdf_lambert_albedo(b, kd);
    for (int c = 0; c < 3; ++c) rgb[c] += kd[c] / (float)PRT_PI;
}

prt_status prt_brdf_lobe_bands(const prt_brdf *b, int order, double *a)
{
    if (order < 1 || order > PRT_SH_MAX_ORDER) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "SH order %d out of range 1..%d", order, PRT_SH_MAX_ORDER);
    if (b->model != PRT_BRDF_PHONG && b->model != PRT_BRDF_BLINN_PHONG)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a %s BRDF has no reflection lobe to convolve at run time; bake it in (--brdf at bake time)",
                         prt_brdf_model_name(b->model));
    double s = b->model == PRT_BRDF_BLINN_PHONG ? b->exponent / 4.0 : b->exponent;
    /* Legendre polynomials as coefficient arrays (exact for these small degrees); then
     * a_l = (s+1) sum_k c_lk / (s+k+1), the exact integral of (s+1) t^s P_l(t) over [0, 1]. */
    double p[PRT_SH_MAX_ORDER][PRT_SH_MAX_ORDER] = {{0}};
    p[0][0] = 1.0;
    if (order > 1) p[1][1] = 1.0;
    for (int l = 2; l < order; ++l)
        for (int k = 0; k <= l; ++k)
            p[l][k] = ((2.0 * l - 1.0) * (k ? p[l - 1][k - 1] : 0.0) - (l - 1.0) * p[l - 2][k]) / l;
    for (int l = 0; l < order; ++l) {
        double sum = 0.0;
        for (int k = 0; k <= l; ++k) sum += p[l][k] / (s + k + 1.0);
        a[l] = (s + 1.0) * sum;
    }
    return PRT_OK;
}

prt_status prt_brdf_sh_matrix(const prt_brdf *b, int order, float *B)
{
    if (order < 1 || order > PRT_SH_MAX_ORDER) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "SH order %d out of range 1..%d", order, PRT_SH_MAX_ORDER);
    prt_status st = prt_brdf_validate(b);
    if (st) return st;
    if (!prt_brdf_is_isotropic(b))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the SH matrix needs an isotropic BRDF (ashikhmin with n_u = n_v); "
                                                    "anisotropic ones need a method with separable BRDFs (prt bake --help)");
    const int nc = order * order;
    /* Equal-area cells in (cos theta, phi) on the upper hemisphere, midpoints. */
    enum { OZ = 24, OP = 48, IZ = 96, IP = 192 };
    const int ni = IZ * IP;
    float *ydir = malloc((size_t)ni * 3 * sizeof(float)), *yi = malloc((size_t)ni * nc * sizeof(float));
    float *rows = calloc((size_t)OZ * OP * 3 * nc, sizeof(float));   /* per wo: sum f cos y_j dwi */
    if (!ydir || !yi || !rows) { free(ydir); free(yi); free(rows); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (int k = 0; k < ni; ++k) {
        double z = ((k / IP) + 0.5) / IZ, phi = 2.0 * PRT_PI * ((k % IP) + 0.5) / IP, r = sqrt(fmax(0.0, 1.0 - z * z));
        double d[3] = {r * cos(phi), r * sin(phi), z}, y[PRT_SH_MAX_COEFFS];
        prt_sh_eval(order, d, y);
        for (int c = 0; c < 3; ++c) ydir[k * 3 + c] = (float)d[c];
        for (int j = 0; j < nc; ++j) yi[(size_t)k * nc + j] = (float)y[j];
    }
    const float wi_weight = (float)(2.0 * PRT_PI / ni);
#pragma omp parallel for schedule(static)
    for (int o = 0; o < OZ * OP; ++o) {
        double z = ((o / OP) + 0.5) / OZ, phi = 2.0 * PRT_PI * ((o % OP) + 0.5) / OP, r = sqrt(fmax(0.0, 1.0 - z * z));
        float wo[3] = {(float)(r * cos(phi)), (float)(r * sin(phi)), (float)z};
        float *row = rows + (size_t)o * 3 * nc;
        for (int k = 0; k < ni; ++k) {
            float f[3];
            prt_brdf_eval_glossy(b, ydir + k * 3, wo, f);
            if (f[0] == 0.0f && f[1] == 0.0f && f[2] == 0.0f) continue;
            const float *y = yi + (size_t)k * nc;
            float cw = ydir[k * 3 + 2] * wi_weight;
            for (int c = 0; c < 3; ++c) {
                float fc = f[c] * cw;
                for (int j = 0; j < nc; ++j) row[c * nc + j] += fc * y[j];
            }
        }
    }
    /* Outer integral in a fixed order, so the result does not depend on the thread count. */
    double *acc = calloc((size_t)3 * nc * nc, sizeof(double));
    if (!acc) { free(ydir); free(yi); free(rows); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    const double wo_weight = 2.0 * PRT_PI / (OZ * OP);
    for (int o = 0; o < OZ * OP; ++o) {
        double z = ((o / OP) + 0.5) / OZ, phi = 2.0 * PRT_PI * ((o % OP) + 0.5) / OP, r = sqrt(fmax(0.0, 1.0 - z * z));
        double d[3] = {r * cos(phi), r * sin(phi), z}, y[PRT_SH_MAX_COEFFS];
        prt_sh_eval(order, d, y);
        const float *row = rows + (size_t)o * 3 * nc;
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < nc; ++i)
                for (int j = 0; j < nc; ++j) acc[((size_t)c * nc + i) * nc + j] += wo_weight * y[i] * row[c * nc + j];
    }
    /* The exit function only matters above the horizon. Projecting its mirror-symmetric extension
     * (g(x, y, -z) = g(x, y, z)) rather than a function that drops to zero below avoids the ringing
     * of that step (a constant exit radiance would read 19% low towards the normal at order 5):
     * y_lm(x, y, -z) = (-1)^(l+m) y_lm(x, y, z), so rows with l + m odd vanish and the others double. */
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) {
            const int i = l * (l + 1) + m;
            const double f = ((l + m) & 1) ? 0.0 : 2.0;
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < nc; ++j) B[((size_t)c * nc + i) * nc + j] = (float)(f * acc[((size_t)c * nc + i) * nc + j]);
        }
    free(acc); free(ydir); free(yi); free(rows);
    return PRT_OK;
}
