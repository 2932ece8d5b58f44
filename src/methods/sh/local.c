/* Local lights through SH (Sloan, Kautz & Snyder 2002, section 7: the light's radiance sampled as
 * SH at points over the object, here at every vertex or texel). At a point p a light is a function
 * on p's sphere of directions, projected at the file's order:
 *   point, spot, ies  a delta towards the light of weight I(w) / r^2, I(w) the intensity it sends
 *                     towards p as src/light defines it (prt_light_intensity_towards: the spot's
 *                     cone, the profile), so c_lm = I / r^2 y_lm(w);
 *   sphere            the uniform cap of half-angle s (sin s = R / r) it subtends, of radiance L:
 *                     a zonal function whose coefficients are closed-form, turned to w:
 *                     c_lm = 2 pi L int_{cos s}^1 P_l(x) dx y_lm(w);
 *   directional       already in prt_lighting_sh (a delta E y_lm(d), the same at every point).
 * Cut off at the order, a delta rings (negative lobes opposite the light); a window's sigma factors
 * per band (Hanning, Lanczos) trade the ringing for blur. Shadowed transfer holds visibility per
 * direction, which is as right for a light at a point as for a distant one (but for occluders
 * behind the light); inter-reflected transfer assumed the light distant, so local lights' bounces
 * are approximate. */
#include "methods/sh/sh.h"

#include <math.h>
#include <string.h>

bool prt__sh_light_positioned(const prt_light *l)
{
    return l->type == PRT_LIGHT_POINT || l->type == PRT_LIGHT_SPOT || l->type == PRT_LIGHT_SPHERE || l->type == PRT_LIGHT_IES;
}

int prt__sh_local_count(const prt_lighting *l)
{
    int n = 0;
    for (int i = 0; l && i < prt_lighting_count(l); ++i) n += prt__sh_light_positioned(prt_lighting_light(l, i));
    return n;
}

void prt__sh_window(int window, int order, double *sigma)
{
    for (int l = 0; l < order; ++l) {
        const double x = PRT_PI * l / order;
        sigma[l] = window == PRT__SH_WINDOW_HANNING ? 0.5 * (1.0 + cos(x)) : window == PRT__SH_WINDOW_LANCZOS && l ? sin(x) / x : 1.0;
    }
}

void prt__sh_window_directional(const prt_lighting *l, int window, prt_sh_light *sh)
{
    if (window == PRT__SH_WINDOW_NONE) return;
    double sigma[PRT_SH_MAX_ORDER];
    prt__sh_window(window, sh->order, sigma);
    for (int i = 0; i < prt_lighting_count(l); ++i) {
        const prt_light *li = prt_lighting_light(l, i);
        if (li->type != PRT_LIGHT_DIRECTIONAL) continue;
        float y[PRT_SH_MAX_COEFFS];
        prt_sh_eval_f(sh->order, li->direction, y);
        for (int b = 0; b < sh->order; ++b)
            for (int k = b * b; k < (b + 1) * (b + 1); ++k)
                for (int c = 0; c < 3; ++c) sh->coeffs[c][k] += (float)((sigma[b] - 1.0) * li->irradiance[c] * y[k]);
    }
}

/* 2 pi int_a^1 P_l(x) dx for l < order: the cap's zonal weights per band, given t = 1 - a (a = cos of
 * its half-angle; t = 2 is the whole sphere, only l = 0 left). int_a^1 P_l = (P_{l-1}(a) - P_{l+1}(a))
 * / (2l + 1), but for small caps that difference cancels (a sphere light far away next to its size
 * would add nothing), so there the series int_0^t P_l(1 - u) du = t - l(l+1) t^2 / 4
 * + (l-1) l (l+1) (l+2) t^3 / 48 is used, accurate to 1e-5 of t up to order 15 for t < 1e-3. */
static void cap_bands(double t, int order, double *w)
{
    w[0] = 2.0 * PRT_PI * t;
    if (t < 1e-3) {
        for (int l = 1; l < order; ++l) {
            const double L = (double)l * (l + 1);
            w[l] = 2.0 * PRT_PI * t * (1.0 - L * t / 4.0 + (L - 2.0) * L * t * t / 48.0);
        }
        return;
    }
    const double a = 1.0 - t;
    double P[PRT_SH_MAX_ORDER + 2];
    P[0] = 1.0;
    P[1] = a;
    for (int k = 1; k <= order; ++k) P[k + 1] = ((2 * k + 1) * a * P[k] - k * P[k - 1]) / (k + 1);
    for (int l = 1; l < order; ++l) w[l] = 2.0 * PRT_PI * (P[l - 1] - P[l + 1]) / (2 * l + 1);
}

/* Adds light li's incident radiance at p, as SH, to out (3 channels of n = order^2). */
static void add_light(const prt_light *li, const float p[3], int order, const double *sigma, float *out)
{
    const int n = order * order;
    double d[3] = {(double)li->position[0] - p[0], (double)li->position[1] - p[1], (double)li->position[2] - p[2]};
    const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(r2);
    float w[3] = {0, 1, 0};   /* any direction will do at the centre of a sphere light */
    if (r > 0) for (int k = 0; k < 3; ++k) w[k] = (float)(d[k] / r);
    double band[PRT_SH_MAX_ORDER];
    float colour[3];
    if (li->type == PRT_LIGHT_SPHERE) {
        const double R = li->radius;
        const double q = R * R / r2;   /* sin^2 of the half-angle; 1 - cos without cancelling */
        cap_bands(r > R ? q / (1.0 + sqrt(1.0 - q)) : 2.0, order, band);
        memcpy(colour, li->radiance, sizeof colour);
    } else {
        if (!(r > 0)) return;   /* a point light at the point itself lights nothing that faces anywhere */
        const float from[3] = {-w[0], -w[1], -w[2]};
        prt_light_intensity_towards(li, from, colour);
        if (colour[0] == 0 && colour[1] == 0 && colour[2] == 0) return;
        for (int c = 0; c < 3; ++c) colour[c] = (float)(colour[c] / r2);
        for (int l = 0; l < order; ++l) band[l] = 1.0;
    }
    float y[PRT_SH_MAX_COEFFS];
    prt_sh_eval_f(order, w, y);
    for (int l = 0; l < order; ++l) {
        const float s = (float)(band[l] * sigma[l]);
        for (int k = l * l; k < (l + 1) * (l + 1); ++k)
            for (int c = 0; c < 3; ++c) out[c * n + k] += colour[c] * s * y[k];
    }
}

void prt__sh_local_project(prt_context *ctx, const prt_lighting *l, int order, int window, const float *points, size_t count, float *out)
{
    const int n = order * order;
    double sigma[PRT_SH_MAX_ORDER];
    prt__sh_window(window, order, sigma);
    const int lights = prt_lighting_count(l);
#pragma omp parallel for schedule(static) num_threads(count < 4096 ? 1 : prt__threads(ctx))
    for (size_t v = 0; v < count; ++v) {
        float *o = out + v * 3 * (size_t)n;
        memset(o, 0, 3 * (size_t)n * sizeof(float));
        for (int i = 0; i < lights; ++i) {
            const prt_light *li = prt_lighting_light(l, i);
            if (prt__sh_light_positioned(li)) add_light(li, points + v * 3, order, sigma, o);
        }
    }
}
