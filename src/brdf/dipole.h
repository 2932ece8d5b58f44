/* Jensen et al. 2001's dipole diffusion kernel for subsurface scattering, shared by the methods
 * that scatter light under translucent surfaces. */
#ifndef PRT_BRDF_DIPOLE_H
#define PRT_BRDF_DIPOLE_H

#include "core/internal.h"
#include "prt/scene.h"

/* Jensen et al. 2001's dipole for one colour channel: sigma_a and reduced scattering sigma_s'
 * per unit length, relative index of refraction eta. */
typedef struct prt__dipole {
    double sigma_tr, alpha, zr, zv;
    double falloff;   /* > 0: an exponential falloff of this mean distance instead, integrating to 1 */
} prt__dipole;

prt_status prt__dipole_init(double sigma_a, double sigma_s_reduced, double eta, prt__dipole *out);
/* Diffuse reflectance R_d(r): exitance at distance r per unit flux entering at a point (1/area). */
double prt__dipole_rd(const prt__dipole *d, double r);
/* Its integral over the plane, in closed form: the total diffuse reflectance. */
double prt__dipole_total(const prt__dipole *d);
/* Its integral over a disc of radius a about the entry point, in closed form. With `falloff`
 * set, the three are those of exp(-r / d) / (2 pi d^2), whose total is 1. */
double prt__dipole_disc(const prt__dipole *d, double a);

/* A medium's kernel per colour channel in scene units: its coefficients per mm times
 * mm_per_unit (or its exponential falloff's mean distance over it). */
prt_status prt__dipole_from_medium(const prt_medium *m, double mm_per_unit, prt__dipole out[3]);
/* How far a medium scatters: the distance within which its kernel gives back all but 1e-3 of its
 * total, the farthest of its channels. */
double prt__dipole_reach(const prt__dipole d[3]);
/* The mean of the kernel over a disc of radius a whose centre lies r from the entry point. */
double prt__dipole_disc_mean(const prt__dipole *d, double r, double a);

#endif
