/* Importance sampling of an environment map in proportion to radiance x solid angle, with an
 * optional rotation and scale, for the reference path tracer. The map is piecewise constant
 * over pixels (as in the SH projection), so sampling and evaluation agree exactly. */
#ifndef PRT_LIGHT_ENV_SAMPLE_H
#define PRT_LIGHT_ENV_SAMPLE_H

#include "light/envmap_internal.h"

typedef struct prt__env_sampler {
    const prt_envmap *env;
    double *cdf;            /* one entry per pixel, cdf[n-1] = 1 */
    size_t n;
    float rot[9];           /* world = rot * map frame */
    float scale;
} prt__env_sampler;

prt_status prt__env_sampler_init(prt__env_sampler *s, const prt_envmap *env, const double rot[9], float scale);
void prt__env_sampler_free(prt__env_sampler *s);
/* Radiance arriving from world direction d. */
void prt__env_radiance(const prt__env_sampler *s, const float d[3], float rgb[3]);
/* Samples a world direction from three uniform numbers; returns its pdf per steradian
 * (0 when the sample fell outside the map) and its radiance. */
float prt__env_sample(const prt__env_sampler *s, double u1, double u2, double u3, float d[3], float rgb[3]);
/* The pdf per steradian with which prt__env_sample returns world direction d. */
float prt__env_pdf(const prt__env_sampler *s, const float d[3]);

#endif
