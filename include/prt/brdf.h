/* prt/brdf.h - the BRDF library every method shares.
 *
 * Directions live in the local shading frame (z = normal), both pointing away from the surface;
 * f(wi, wo) is in 1/sr, RGB. A BRDF is split into a Lambertian part (rho_d / pi, handled by the
 * diffuse transfer sets) and the rest ("glossy part", which the glossy transfer matrices carry). */
#ifndef PRT_BRDF_H
#define PRT_BRDF_H

#include "prt/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum prt_brdf_model {
    PRT_BRDF_LAMBERT = 0,
    PRT_BRDF_PHONG,               /* rho_d/pi + rho_s (n+2)/(2pi) max(r.wo, 0)^n, r = mirror of wi */
    PRT_BRDF_BLINN_PHONG,         /* rho_d/pi + rho_s (n+8)/(8pi) (n.h)^n */
    PRT_BRDF_ASHIKHMIN_SHIRLEY,   /* Ashikhmin & Shirley 2000, anisotropic (n_u along the tangent x) */
    PRT_BRDF_LAFORTUNE            /* rho_d/pi + sum of lobes [Cxy (x.x' + y.y') + Cz z.z']^n */
} prt_brdf_model;

#define PRT_BRDF_MAX_LOBES 3

/* Zero-initialised = black Lambert; prt_brdf_parse fills sensible values. */
typedef struct prt_brdf {
    prt_brdf_model model;
    float diffuse[3];     /* rho_d; Ashikhmin-Shirley: R_d */
    float specular[3];    /* rho_s; Ashikhmin-Shirley: R_s (Fresnel at normal incidence) */
    float exponent;       /* Phong / Blinn-Phong shininess; Ashikhmin-Shirley n_u */
    float exponent_v;     /* Ashikhmin-Shirley n_v (anisotropic when != n_u) */
    int lobes;            /* Lafortune: 1..PRT_BRDF_MAX_LOBES */
    float cxy[PRT_BRDF_MAX_LOBES][3], cz[PRT_BRDF_MAX_LOBES][3], n[PRT_BRDF_MAX_LOBES][3];
} prt_brdf;

/* Parses "lambert[:rho]", "phong:N[:ks[:kd]]", "blinn:N[:ks[:kd]]",
 * "ashikhmin:NU:NV[:rs[:rd]]", "lafortune:clay" or "lafortune:skin" (Lafortune et al. 1997
 * measured fits, three lobes). ks, kd, rs, rd are grey reflectances. */
prt_status prt_brdf_parse(const char *spec, prt_brdf *out);
/* Writes a spec that prt_brdf_parse reads back to the same model (colours as their mean). */
void prt_brdf_format(const prt_brdf *b, char *buf, size_t size);
/* Checks ranges: finite, reflectances in [0, 1], exponents in [0, 1e5]. */
prt_status prt_brdf_validate(const prt_brdf *b);
int prt_brdf_is_isotropic(const prt_brdf *b);
/* True when the model has a glossy part at all (not a plain Lambert). */
int prt_brdf_is_glossy(const prt_brdf *b);
const char *prt_brdf_model_name(prt_brdf_model m);

/* Full BRDF and its glossy part (f minus rho_d/pi for Lambert, Phong, Blinn-Phong, Lafortune;
 * all of it for Ashikhmin-Shirley, whose diffuse term is not Lambertian). Zero below the horizon. */
void prt_brdf_eval(const prt_brdf *b, const float wi[3], const float wo[3], float rgb[3]);
void prt_brdf_eval_glossy(const prt_brdf *b, const float wi[3], const float wo[3], float rgb[3]);
/* Lambertian albedo rho_d the diffuse transfer uses (0 for Ashikhmin-Shirley). */
void prt_brdf_lambert_albedo(const prt_brdf *b, float rgb[3]);

/* Reflection-lobe zonal kernel for run-time convolution (Phong and Blinn-Phong only): the
 * normalised lobe K(t) = (s+1)/(2pi) max(t, 0)^s about the mirror direction (Blinn-Phong uses
 * s = n/4), without the cosine factor, as Sloan et al. 2002 convolve. Writes per band l the
 * Funk-Hecke factor a_l = 2pi integral K(t) P_l(t) dt, so that the convolved lighting is
 * sum a_l L_lm y_lm(r). Multiply by rho_s for radiance. */
prt_status prt_brdf_lobe_bands(const prt_brdf *b, int order, double *a);

/* SH projection of the glossy part for isotropic BRDFs, in the local frame, per channel c:
 *   B[c][i][j] = integral over wo of y_i(wo) integral over wi in H+ of f(wi, wo) cos(wi) y_j(wi)
 * so that the exit radiance coefficients are e = B L_local. The outer integral projects the exit
 * function extended mirror-symmetrically below the horizon (no step to ring), so B_ij is twice
 * the upper-hemisphere integral for l_i + m_i even and zero otherwise. B holds 3 * order^4 floats. The
 * double integral is numerical (about 1 degree resolution for wi; lobes sharper than n ~ 2000
 * are under-resolved). */
prt_status prt_brdf_sh_matrix(const prt_brdf *b, int order, float *B);

#ifdef __cplusplus
}
#endif
#endif
