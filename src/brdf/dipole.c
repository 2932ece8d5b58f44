/* Jensen et al. 2001's dipole: see dipole.h. */
#include "brdf/dipole.h"

#include <math.h>

prt_status prt__dipole_init(double sigma_a, double sigma_s_reduced, double eta, prt__dipole *out)
{
    if (!(sigma_a > 0) || !(sigma_s_reduced >= 0) || !(eta >= 1 && eta <= 4) || !isfinite(sigma_a) || !isfinite(sigma_s_reduced))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "dipole: sigma_a > 0, sigma_s' >= 0 (finite) and eta in [1, 4] (got %g, %g, %g)", sigma_a,
                         sigma_s_reduced, eta);
    const double sigma_t = sigma_a + sigma_s_reduced;
    /* Diffuse Fresnel reflectance (Egan and Hilgeman's fit) and the boundary term A. */
    const double fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta, a = (1 + fdr) / (1 - fdr);
    out->falloff = 0;
    out->alpha = sigma_s_reduced / sigma_t;
    out->sigma_tr = sqrt(3 * sigma_a * sigma_t);
    out->zr = 1 / sigma_t;
    out->zv = out->zr * (1 + 4 * a / 3);
    return PRT_OK;
}

double prt__dipole_rd(const prt__dipole *d, double r)
{
    if (d->falloff > 0) return exp(-r / d->falloff) / (2 * PRT_PI * d->falloff * d->falloff);
    const double dr = sqrt(r * r + d->zr * d->zr), dv = sqrt(r * r + d->zv * d->zv);
    return d->alpha / (4 * PRT_PI) *
           (d->zr * (d->sigma_tr * dr + 1) * exp(-d->sigma_tr * dr) / (dr * dr * dr) + d->zv * (d->sigma_tr * dv + 1) * exp(-d->sigma_tr * dv) / (dv * dv * dv));
}

double prt__dipole_disc(const prt__dipole *d, double a)
{
    if (d->falloff > 0) return 1 - exp(-a / d->falloff) * (1 + a / d->falloff);
    /* Each pole: alpha / 2 (exp(-sigma_tr z) - z exp(-sigma_tr d(a)) / d(a)), d(a) = sqrt(a^2 + z^2). */
    const double dr = sqrt(a * a + d->zr * d->zr), dv = sqrt(a * a + d->zv * d->zv);
    return 0.5 * d->alpha * (exp(-d->sigma_tr * d->zr) - d->zr * exp(-d->sigma_tr * dr) / dr + exp(-d->sigma_tr * d->zv) - d->zv * exp(-d->sigma_tr * dv) / dv);
}

double prt__dipole_total(const prt__dipole *d)
{
    if (d->falloff > 0) return 1;
    /* Each pole integrates to alpha / 2 exp(-sigma_tr z). */
    return 0.5 * d->alpha * (exp(-d->sigma_tr * d->zr) + exp(-d->sigma_tr * d->zv));
}

prt_status prt__dipole_from_medium(const prt_medium *m, double mm_per_unit, prt__dipole out[3])
{
    for (int c = 0; c < 3; ++c) {
        if (m->falloff_mm > 0) {   /* the mean distance in scene units */
            out[c] = (prt__dipole){.falloff = m->falloff_mm / mm_per_unit};
            continue;
        }
        prt_status st = prt__dipole_init(m->sigma_a[c] * mm_per_unit, m->sigma_s[c] * mm_per_unit, m->eta, &out[c]);
        if (st) return st;
    }
    return PRT_OK;
}

/* How far a medium scatters: the distance (scene units) within which its kernel gives back all
 * but 1e-3 of its total, the farthest of its channels. */
double prt__dipole_reach(const prt__dipole d[3])
{
    double reach = 0;
    for (int c = 0; c < 3; ++c) {
        const double total = prt__dipole_total(&d[c]);
        double r = d[c].falloff > 0 ? d[c].falloff : 1 / d[c].sigma_tr;
        if (!(total > 0) || !(r > 0) || !isfinite(r)) continue;
        for (int k = 0; k < 200 && prt__dipole_disc(&d[c], r) < (1 - 1e-3) * total; ++k) r *= 1.25;
        reach = fmax(reach, r);
    }
    return reach;
}

/* The mean of a medium's kernel over a disc of radius a whose centre lies r from the entry point
 * (a source patch, flat): Gauss-Legendre over the disc's area in the radius squared, the midpoint
 * rule over the angle (the kernel depends on the angle only through the distance, so half a
 * turn). At a patch's own distance, where the kernel changes most across it, its value at the
 * centre is far from its mean (12% under for an exponential falloff of 20 mm over patches of
 * about 15 mm), and its value at the rim's distance further under. */
double prt__dipole_disc_mean(const prt__dipole *d, double r, double a)
{
    static const double node[3] = {0.1127016653792583, 0.5, 0.8872983346207417}, weight[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
    double sum = 0;
    for (int i = 0; i < 3; ++i) {
        const double rho = a * sqrt(node[i]);
        for (int k = 0; k < 4; ++k) {
            const double phi = PRT_PI * (k + 0.5) / 4, x = r + rho * cos(phi), y = rho * sin(phi);
            sum += weight[i] / 4 * prt__dipole_rd(d, sqrt(x * x + y * y));
        }
    }
    return sum;
}

