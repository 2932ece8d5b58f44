/* prt/lighting.h - lighting: environment maps, the procedural sky, SH projection, local lights
 * and the lighting object every layer shares.
 *
 * Units are radiometric, linear RGB, and hold everywhere in prt:
 *   environment  radiance L(w) arriving from direction w, W / (m^2 sr);
 *   point        radiant intensity I, W / sr: a surface at distance r whose normal makes angle
 *                theta with the direction to the light receives irradiance E = I cos(theta) / r^2;
 *   spot         a point light (same I) restricted to a cone around `direction`: full intensity
 *                within the inner half-angle `falloff`, none beyond the outer half-angle `angle`,
 *                smoothstep in cos between;
 *   ies          a point light whose intensity varies with direction as a photometric profile
 *                (an IES LM-63 file, candela) says: I(w) = scale x candela(w), W/sr, with the
 *                profile's nadir (vertical angle 0) along `direction` and its C0 plane towards
 *                `up`;
 *   directional  irradiance E, W / m^2, on a surface facing the light (direction = towards it);
 *   sphere       uniform radiance L, W / (m^2 sr), leaving a sphere of radius R (soft shadows): an
 *                unoccluded surface facing its centre at distance d > R receives E = pi L R^2 / d^2;
 *   emissive     radiance L_e, W / (m^2 sr), leaving the front of scene triangles whose material
 *                emits (Ke in MTL, emissiveFactor in glTF, "emission" in scene JSON).
 * A Lambertian surface of albedo rho under irradiance E leaves radiance rho / pi * E.
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
    int none;                 /* non-zero: no environment light at all (a room lit by its lamps) */
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

/* ---- Photometric profiles (IESNA LM-63) ----
 * A luminaire's candela distribution read from an IES file (LM-63-1986/1991/1995/2002; photometric
 * type C; TILT=NONE or INCLUDE, tilt data checked but not applied). Candela values carry the
 * file's multiplier and ballast factors. Immutable once read; shared by reference count (retain
 * and release from any thread). Bad files give PRT_ERR_FORMAT and a one-line reason. */
typedef struct prt_ies prt_ies;

prt_status prt_ies_load_memory(const void *data, size_t size, prt_ies **out);
prt_status prt_ies_load(const char *path, prt_ies **out);
prt_ies *prt_ies_retain(prt_ies *p);      /* returns p */
void prt_ies_release(prt_ies *p);
/* Candela at vertical angle (0 = nadir .. 180 = zenith) and horizontal angle (the C plane,
 * degrees, any value: the file's symmetry fills in what it leaves out); bilinear; 0 outside the
 * vertical range the file covers. */
float prt_ies_candela(const prt_ies *p, float vertical_deg, float horizontal_deg);
float prt_ies_max_candela(const prt_ies *p);
/* The path it was loaded from; "" when read from memory. */
const char *prt_ies_path(const prt_ies *p);

/* ---- Local lights ---- */
typedef enum prt_light_type {
    PRT_LIGHT_POINT = 1,
    PRT_LIGHT_SPOT,
    PRT_LIGHT_DIRECTIONAL,
    PRT_LIGHT_SPHERE,
    PRT_LIGHT_IES
} prt_light_type;

/* One light; units as stated at the top of this header. */
typedef struct prt_light {
    prt_light_type type;
    float position[3];    /* point, spot, sphere: world position */
    float direction[3];   /* spot: the axis it shines along; directional: towards the light (unit) */
    float intensity[3];   /* point, spot: W/sr */
    float irradiance[3];  /* directional: W/m^2 at normal incidence */
    float radiance[3];    /* sphere: W/(m^2 sr) */
    float angle_deg;      /* spot: outer half-angle, (0, 90]; 0 = 30 */
    float falloff_deg;    /* spot: inner half-angle, [0, angle]; 0 = angle (a hard edge) */
    float radius;         /* sphere: > 0 */
    float up[3];          /* ies: towards the C0 plane (made perpendicular to direction); zero = a fixed choice */
    float scale[3];       /* ies: W/sr per candela, per channel */
    prt_ies *profile;     /* ies: the profile; a light returned by prt_light_parse owns one
                           * reference (prt_light_clear), a lighting holds its own copies' */
} prt_light;

/* Checks type, finiteness and ranges (non-negative colours, unit-able directions, angles);
 * normalises directions and fills the spot defaults. */
prt_status prt_light_validate(prt_light *l);
/* Parses the command-line form:
 *   point:X,Y,Z:R,G,B                       intensity W/sr
 *   spot:X,Y,Z:DX,DY,DZ:ANGLE[,FALLOFF]:R,G,B
 *   directional:DX,DY,DZ:R,G,B              towards the light; irradiance W/m^2
 *   sphere:X,Y,Z:RADIUS:R,G,B               radiance
 *   ies:FILE:X,Y,Z[:DX,DY,DZ[,UX,UY,UZ][:R,G,B]]   profile FILE (read now); nadir along D
 *                                           (default 0,-1,0: down), C0 plane towards U;
 *                                           scale W/sr per candela (default 1)
 * (one number for R,G,B means grey). An ies light owns a reference to its profile: release it
 * with prt_light_clear. */
prt_status prt_light_parse(const char *spec, prt_light *out);
/* Releases what a light owns (an ies light's profile reference) and zeroes it. */
void prt_light_clear(prt_light *l);
/* dst = src, taking a reference of its own to src's profile (dst is overwritten, not released). */
void prt_light_copy(prt_light *dst, const prt_light *src);
/* The intensity light l (point, spot or ies) sends along unit direction w (from the light), W/sr;
 * zero for directional and sphere lights. */
void prt_light_intensity_towards(const prt_light *l, const float w[3], float rgb[3]);
/* The command-line form of l (prt_light_parse reads it back). */
void prt_light_format(const prt_light *l, char *buf, size_t size);
const char *prt_light_type_name(prt_light_type type);
/* Irradiance at point p with unit normal n from l, ignoring occlusion (sphere: its unoccluded
 * visible cap, exact). */
void prt_light_irradiance(const prt_light *l, const float p[3], const float n[3], float rgb[3]);

/* What a lighting holds, and what a method relights (prt_method_lighting). */
enum {
    PRT_LIGHTS_ENVIRONMENT = 1,
    PRT_LIGHTS_POINT = 2,
    PRT_LIGHTS_SPOT = 4,
    PRT_LIGHTS_DIRECTIONAL = 8,
    PRT_LIGHTS_SPHERE = 16,
    PRT_LIGHTS_EMISSIVE = 32,
    PRT_LIGHTS_IES = 64
};
/* The PRT_LIGHTS_* bit of a light type. */
unsigned prt_light_type_bit(prt_light_type type);
/* "environment", "point lights", ... for one bit. */
const char *prt_lights_bit_name(unsigned bit);
/* The names of every bit of `bits`, separated by sep (", "), into buf ("" for none). */
void prt_lights_names(unsigned bits, const char *sep, char *buf, size_t size);

/* ---- The lighting object ----
 * An environment (probe or procedural sky, rotated and scaled; or none), any number of local
 * lights, and a scale for the scene's emissive surfaces (their geometry and radiance belong to
 * the scene). Not thread-safe while being changed; read-only use from many threads is fine. */
typedef struct prt_lighting prt_lighting;

/* An empty lighting: no environment, no lights, emissive surfaces at scale 1. */
prt_status prt_lighting_create(prt_lighting **out);
prt_status prt_lighting_copy(const prt_lighting *src, prt_lighting **out);
void prt_lighting_release(prt_lighting *l);

/* Loads the environment a desc names (probe file, or the procedural sky when path is empty;
 * none when desc->none) with its rotation and intensity. */
prt_status prt_lighting_set_environment(prt_lighting *l, const prt_environment_desc *desc);
/* Takes ownership of env (NULL removes the environment); rot row-major (NULL = identity);
 * intensity 0 = 1. */
prt_status prt_lighting_set_envmap(prt_lighting *l, prt_envmap *env, const double rot[9], float intensity);
void prt_lighting_set_rotation(prt_lighting *l, const double rot[9]);
/* The environment's radiance scale, >= 0 (0 turns it off; other values are ignored). */
void prt_lighting_set_intensity(prt_lighting *l, float intensity);
/* NULL when the lighting has no environment. */
const prt_envmap *prt_lighting_envmap(const prt_lighting *l);
void prt_lighting_rotation(const prt_lighting *l, double rot[9]);
float prt_lighting_intensity(const prt_lighting *l);
/* The desc the environment came from (all zero when set by prt_lighting_set_envmap). */
const prt_environment_desc *prt_lighting_environment_desc(const prt_lighting *l);

/* The distant part of a lighting as SH of `order` (what SH transfer dots): the environment
 * projected, rotated and scaled, plus each directional light as a delta (E y_i(d)). Local
 * lights with a position are not distant and are left out. */
prt_status prt_lighting_sh(const prt_lighting *l, int order, prt_sh_light *out);

/* Validates and appends a copy; *index (may be NULL) gets its position. */
prt_status prt_lighting_add(prt_lighting *l, const prt_light *light, int *index);
prt_status prt_lighting_set(prt_lighting *l, int index, const prt_light *light);
prt_status prt_lighting_remove(prt_lighting *l, int index);
void prt_lighting_clear_lights(prt_lighting *l);
int prt_lighting_count(const prt_lighting *l);
const prt_light *prt_lighting_light(const prt_lighting *l, int index);   /* NULL out of range */

/* Scale of the scene's emissive surfaces (default 1; 0 turns them off). */
void prt_lighting_set_emission(prt_lighting *l, float scale);
float prt_lighting_emission(const prt_lighting *l);

/* PRT_LIGHTS_* bits of what l holds: the environment, each light type present, and
 * PRT_LIGHTS_EMISSIVE when the emission scale is above zero (whether the scene emits is the
 * scene's business). */
unsigned prt_lighting_content(const prt_lighting *l);

#ifdef __cplusplus
}
#endif
#endif
