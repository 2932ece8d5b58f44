/* prt/lighting.h - distant lighting: environment maps, the procedural sky, SH projection.
 *
 * Lighting for SH PRT is prt_sh_light: order*order coefficients per RGB channel of the incident
 * radiance L(w), with L_i = integral L(w) y_i(w) dw over the sphere. */
#ifndef PRT_LIGHTING_H
#define PRT_LIGHTING_H

#include "prt/base.h"
#include "prt/image.h"
#include "prt/sh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum prt_env_layout {
    PRT_ENV_AUTO = 0,     /* from the aspect ratio: 2:1 lat-long, 1:1 angular, 3:4 vertical cross */
    PRT_ENV_LATLONG,      /* row 0 = +y (up); the image centre looks along -z; u grows towards +x */
    PRT_ENV_ANGULAR,      /* Debevec angular map: centre = -z, radius 1 = +z */
    PRT_ENV_VCROSS        /* vertical cross 3w x 4w: +y top, -x left, -z centre, +x right, -y, +z (upside down) bottom */
} prt_env_layout;

typedef struct prt_sh_light {
    int order;
    float coeffs[3][PRT_SH_MAX_COEFFS];  /* per channel R, G, B */
} prt_sh_light;

typedef struct prt_envmap prt_envmap;

/* A distant lighting named by a scene file and carried into the .prt it bakes, so that
 * relighting and rendering can default to it. */
typedef struct prt_environment_desc {
    char path[1024];          /* probe file; empty = the procedural sky */
    prt_env_layout layout;
    float rotate_deg[3];      /* yaw (about +y), pitch, roll */
    float intensity;          /* radiance scale; 0 = 1 */
    float sun_dir[3];         /* procedural sky only; zero = its default */
} prt_environment_desc;

/* Takes ownership of img's pixels (img is zeroed). */
prt_status prt_envmap_from_image(prt_image *img, prt_env_layout layout, prt_envmap **out);
prt_status prt_envmap_load(const char *path, prt_env_layout layout, prt_envmap **out);
void prt_envmap_release(prt_envmap *env);
prt_env_layout prt_envmap_layout(const prt_envmap *env);
const prt_image *prt_envmap_image(const prt_envmap *env);
/* Radiance arriving from world direction dir (bilinear). */
void prt_envmap_lookup(const prt_envmap *env, const float dir[3], float rgb[3]);

/* Projects with exact per-pixel solid angles. */
prt_status prt_envmap_project_sh(const prt_envmap *env, int order, prt_sh_light *out);

/* Procedural sky: a Lambertian-friendly gradient dome plus a sun disc. Zero fields = defaults. */
typedef struct prt_sky_desc {
    float sun_dir[3];        /* towards the sun; default normalize(0.4, 0.8, 0.3) */
    float sun_radiance[3];   /* radiance inside the disc; default (1000, 950, 850): about twice the sky's irradiance */
    float sun_angle_deg;     /* angular diameter; default 4 degrees (wider than the real sun so SH order 5..10 resolves it fairly) */
    float zenith[3];         /* sky radiance straight up; default (0.35, 0.5, 0.9) */
    float horizon[3];        /* sky radiance at the horizon; default (0.9, 0.95, 1.0) */
    float ground[3];         /* radiance from below the horizon; default (0.25, 0.22, 0.2) */
    int width;               /* lat-long image width; default 512 */
} prt_sky_desc;

prt_status prt_sky_create(const prt_sky_desc *desc, prt_envmap **out);

/* Rotates an SH light in place: the lighting that arrived from d now arrives from R d. */
prt_status prt_sh_light_rotate(prt_sh_light *light, const double rot[9]);
/* Scales all coefficients. */
void prt_sh_light_scale(prt_sh_light *light, float scale);
/* Evaluates the band-limited radiance in direction dir. */
void prt_sh_light_eval(const prt_sh_light *light, const float dir[3], float rgb[3]);
/* Renders the band-limited lighting (or, with irradiance != 0, the irradiance / pi, i.e. the
 * exit radiance of a white Lambertian surface facing each direction) as a lat-long image. */
prt_status prt_sh_light_to_image(const prt_sh_light *light, int width, int irradiance, prt_image *out);

#ifdef __cplusplus
}
#endif
#endif
