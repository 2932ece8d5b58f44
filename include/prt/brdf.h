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


/* ---- Separable approximation (Kautz & McCool 1999; Wang, Tran & Luebke 2005) ----
 * f(wi, wo) ~ sum_k g_k(wi) h_k(wo) per channel, from the SVD of the BRDF sampled on a
 * resolution x resolution parameterization of the hemisphere for both directions. g_k are the
 * light maps, h_k the view maps (sqrt(sigma_k) u_k and sqrt(sigma_k) v_k). Directions are in the
 * local frame (z = normal, x = the tangent s, y = t; see prt_brdf_frame). */
typedef enum prt_brdf_param {
    PRT_BRDF_PARAM_GRID = 0,   /* x = (w.s + 1) / 2, y = (w.t + 1) / 2: the disk inside the square (eq. 10) */
    PRT_BRDF_PARAM_POLAR       /* x = atan2(w.t, w.s) / 2pi, y = sqrt(1 - w.n) (eq. 11): better for anisotropy */
} prt_brdf_param;

#define PRT_BRDF_MAX_TERMS 16

typedef struct prt_brdf_factor_desc {
    int terms;              /* K, 1..PRT_BRDF_MAX_TERMS; 0 = 4 */
    int resolution;         /* texels per side of the light and view maps, 4..96; 0 = 48 */
    prt_brdf_param param;
} prt_brdf_factor_desc;

typedef struct prt_brdf_factors prt_brdf_factors;

/* Samples f on the parameterization (cell centres; cells of the grid outside the disk are not
 * directions and take their rim neighbour's values for filtering), weights each cell by the
 * square root of its projected solid angle on both sides (so the truncation is the best fit in
 * the cos(wi) cos(wo)-weighted norm; uniform for the grid, whose cells all project to equal
 * areas), factors each channel by an SVD (LAPACKE sgesdd; channels with equal samples share one)
 * and keeps the leading max(K, 8) terms, of which the first K are used. */
prt_status prt_brdf_factor(const prt_brdf *b, const prt_brdf_factor_desc *desc, prt_brdf_factors **out);
void prt_brdf_factors_release(prt_brdf_factors *f);
int prt_brdf_factors_terms(const prt_brdf_factors *f);
/* Terms computed (>= terms): the error report covers them all. */
int prt_brdf_factors_computed(const prt_brdf_factors *f);
int prt_brdf_factors_resolution(const prt_brdf_factors *f);
prt_brdf_param prt_brdf_factors_param(const prt_brdf_factors *f);
/* Singular value k (0-based) of channel c. */
float prt_brdf_factors_sigma(const prt_brdf_factors *f, int c, int k);
/* Bilinearly filtered light (view = 0) or view (view = 1) maps at local direction w: out[c * terms + k]
 * for the first `terms` terms (<= computed). Zero below the horizon. */
void prt_brdf_factors_lookup(const prt_brdf_factors *f, int view, int terms, const float w[3], float *out);
/* The approximation with the first `terms` terms at (wi, wo). */
void prt_brdf_factors_eval(const prt_brdf_factors *f, int terms, const float wi[3], const float wo[3], float rgb[3]);
/* Cosine-weighted RMS error against the analytic BRDF over `samples` independent direction pairs
 * (uniform on the hemisphere, weight cos(wi) cos(wo): light arrives cosine-weighted and grazing
 * views cover little of an image; 0 = 100000), for K = 1 .. computed: rms[K - 1] and
 * relative[K - 1] (RMS over the weighted RMS of f itself). Channels averaged. */
prt_status prt_brdf_factors_error(const prt_brdf_factors *f, const prt_brdf *b, int samples, double *rms, double *relative);
/* The frame of eq. 10 for a normal: s from the stereographic parameterization of normals (one
 * discontinuity, at n = -y), t = n x s. */
void prt_brdf_frame(const float n[3], float s[3], float t[3]);

#ifdef __cplusplus
}
#endif
#endif
