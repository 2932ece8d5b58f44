/* prt/sh.h - real orthonormal spherical harmonics.
 *
 * Order n means bands l = 0..n-1, i.e. n*n coefficients; index i = l*(l+1) + m for m = -l..l.
 * The basis is the real orthonormal one (integral of y_i*y_j over the sphere = delta_ij), with
 * the Condon-Shortley phase folded out so that y_{1,-1}, y_{1,0}, y_{1,1} are proportional to
 * y, z, x of the direction. Directions are unit vectors in prt's world frame (+y up).
 * All functions are pure and thread-safe. */
#ifndef PRT_SH_H
#define PRT_SH_H

#include "prt/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PRT_SH_MAX_ORDER 10
#define PRT_SH_MAX_COEFFS (PRT_SH_MAX_ORDER * PRT_SH_MAX_ORDER)

/* Evaluates all order*order basis functions at the unit direction dir into out. */
void prt_sh_eval(int order, const double dir[3], double *out);
void prt_sh_eval_f(int order, const float dir[3], float *out);

/* Rotation of SH coefficient vectors. rot is a row-major 3x3 rotation matrix R; the rotated
 * function g satisfies g(R d) = f(d). */
typedef struct prt_sh_rotation prt_sh_rotation;
prt_status prt_sh_rotation_create(int order, const double rot[9], prt_sh_rotation **out);
void prt_sh_rotation_release(prt_sh_rotation *r);
/* in and out hold `channels` vectors of order*order coefficients each, channel-major; they may
 * not alias. */
void prt_sh_rotation_apply(const prt_sh_rotation *r, int channels, const float *in, float *out);

/* Zonal coefficients of the clamped cosine max(cos theta, 0) about +z, for l = 0..order-1:
 * out[l] = projection onto y_{l,0}. Closed form. */
void prt_sh_clamped_cosine_zh(int order, double *out);
/* Convolves coefficient vector(s) with zonal kernel zh (as returned above): c_lm *= sqrt(4pi/(2l+1)) zh_l. */
void prt_sh_convolve_zh(int order, const double *zh, int channels, float *coeffs);

/* Builds a rotation matrix from Z-Y-X-free yaw about +y then pitch about +x, in degrees. */
void prt_rotation_from_euler_deg(double yaw, double pitch, double roll, double rot[9]);

#ifdef __cplusplus
}
#endif
#endif
