/* Local lights (point, spot, directional, sphere): validation, the command-line form, their
 * unoccluded irradiance; and the prt_lighting object that carries an environment, the lights and
 * the emission scale through every layer. Units: include/prt/lighting.h. */
#include "light/envmap_internal.h"
#include "light/light_sample.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- one light ---- */

const char *prt_light_type_name(prt_light_type type)
{
    switch (type) {
    case PRT_LIGHT_POINT: return "point";
    case PRT_LIGHT_SPOT: return "spot";
    case PRT_LIGHT_DIRECTIONAL: return "directional";
    case PRT_LIGHT_SPHERE: return "sphere";
    case PRT_LIGHT_IES: return "ies";
    }
    return "unknown";
}

unsigned prt_light_type_bit(prt_light_type type)
{
    switch (type) {
    case PRT_LIGHT_POINT: return PRT_LIGHTS_POINT;
    case PRT_LIGHT_SPOT: return PRT_LIGHTS_SPOT;
    case PRT_LIGHT_DIRECTIONAL: return PRT_LIGHTS_DIRECTIONAL;
    case PRT_LIGHT_SPHERE: return PRT_LIGHTS_SPHERE;
    case PRT_LIGHT_IES: return PRT_LIGHTS_IES;
    }
    return 0;
}

const char *prt_lights_bit_name(unsigned bit)
{
    switch (bit) {
    case PRT_LIGHTS_ENVIRONMENT: return "environment";
    case PRT_LIGHTS_POINT: return "point lights";
    case PRT_LIGHTS_SPOT: return "spot lights";
    case PRT_LIGHTS_DIRECTIONAL: return "directional lights";
    case PRT_LIGHTS_SPHERE: return "sphere lights";
    case PRT_LIGHTS_EMISSIVE: return "emissive surfaces";
    case PRT_LIGHTS_IES: return "IES (profiled) lights";
    }
    return "unknown";
}

void prt_lights_names(unsigned bits, const char *sep, char *buf, size_t size)
{
    size_t at = 0;
    if (size) buf[0] = 0;
    for (unsigned bit = 1; bit <= PRT_LIGHTS_IES && at < size; bit <<= 1)
        if (bits & bit) at += (size_t)snprintf(buf + at, size - at, "%s%s", at ? sep : "", prt_lights_bit_name(bit));
}

static bool finite3(const float *v) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }
/* Finite, >= 0 and at most PRT__MAX_RADIANCE, so that sums over lights and samples cannot overflow. */
static bool colour_ok(const float *v)
{
    return finite3(v) && v[0] >= 0 && v[1] >= 0 && v[2] >= 0 && v[0] <= PRT__MAX_RADIANCE && v[1] <= PRT__MAX_RADIANCE && v[2] <= PRT__MAX_RADIANCE;
}

/* Normalises in double and leaves vectors that are unit to float precision alone, so that
 * validating twice (format, then parse) changes nothing. */
static bool unit(float *v)
{
    double len = sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
    if (!(len > 1e-30) || !isfinite(len)) return false;
    if (fabs(len - 1.0) > 1e-6)
        for (int k = 0; k < 3; ++k) v[k] = (float)(v[k] / len);
    return true;
}

prt_status prt_light_validate(prt_light *l)
{
    if (!l) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_light_validate: light is required");
    const prt_light_type t = l->type;
    if (t != PRT_LIGHT_POINT && t != PRT_LIGHT_SPOT && t != PRT_LIGHT_DIRECTIONAL && t != PRT_LIGHT_SPHERE && t != PRT_LIGHT_IES)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "unknown light type %d (point, spot, directional, sphere or ies)", (int)t);
    const char *name = prt_light_type_name(t);
    if (t != PRT_LIGHT_DIRECTIONAL && !finite3(l->position))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "%s light: position must be finite", name);
    if (t == PRT_LIGHT_SPOT || t == PRT_LIGHT_DIRECTIONAL || t == PRT_LIGHT_IES) {
        if (!finite3(l->direction) || !unit(l->direction))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "%s light: direction must be finite and non-zero", name);
    }
    if ((t == PRT_LIGHT_POINT || t == PRT_LIGHT_SPOT) && !colour_ok(l->intensity))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "%s light: intensity must be finite, >= 0 and at most 1e30", name);
    if (t == PRT_LIGHT_DIRECTIONAL && !colour_ok(l->irradiance))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "directional light: irradiance must be finite, >= 0 and at most 1e30");
    if (t == PRT_LIGHT_SPHERE) {
        if (!colour_ok(l->radiance)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "sphere light: radiance must be finite, >= 0 and at most 1e30");
        if (!(l->radius > 0) || !isfinite(l->radius))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "sphere light: radius must be finite and > 0 (got %g)", l->radius);
    }
    if (t == PRT_LIGHT_IES) {
        if (!l->profile) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "ies light: no profile");
        if (!colour_ok(l->scale)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "ies light: scale must be finite, >= 0 and at most 1e30");
        if (!finite3(l->up)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "ies light: up must be finite");
        /* The brightest direction's W/sr stays within the bound every other light keeps. */
        for (int k = 0; k < 3; ++k)
            if (!((double)l->scale[k] * prt_ies_max_candela(l->profile) <= PRT__MAX_RADIANCE))
                return prt__fail(NULL, PRT_ERR_INVALID_ARG, "ies light: scale x peak candela is above 1e30 W/sr");
    }
    if (t == PRT_LIGHT_SPOT) {
        if (l->angle_deg == 0) l->angle_deg = 30.0f;
        if (!(l->angle_deg > 0 && l->angle_deg <= 90))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "spot light: angle %g outside (0, 90] degrees", l->angle_deg);
        if (l->falloff_deg == 0) l->falloff_deg = l->angle_deg;
        if (!(l->falloff_deg > 0 && l->falloff_deg <= l->angle_deg))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "spot light: falloff %g outside [0, angle %g] degrees", l->falloff_deg, l->angle_deg);
    }
    return PRT_OK;
}

/* Reads a comma-separated list of finite numbers filling exactly [min, max] of out; returns
 * the count, or -1. */
static int parse_list(const char *s, size_t len, double *out, int min, int max)
{
    char buf[256];
    if (len == 0 || len >= sizeof buf) return -1;
    memcpy(buf, s, len);
    buf[len] = 0;
    int n = 0;
    const char *p = buf;
    for (;;) {
        if (n == max) return -1;
        char *end;
        errno = 0;
        out[n] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(out[n]) || (*end && *end != ',')) return -1;
        /* strtod skips leading blanks; a field is a number and nothing else. */
        if (*p == ' ' || *p == '\t') return -1;
        n++;
        if (!*end) break;
        p = end + 1;
    }
    return n >= min ? n : -1;
}

/* ies:FILE:X,Y,Z[:DX,DY,DZ[,UX,UY,UZ][:R,G,B]]: FILE runs to the colon before the position (the
 * fields after it hold no colon), so paths with colons work. */
static prt_status parse_ies(const char *spec, prt_light *out)
{
    const char *field[4];
    size_t len[4];
    int nf = 0;
    const char *end = spec + strlen(spec), *p = end;
    /* Up to three numeric fields from the end, as long as they look numeric. */
    while (nf < 3) {
        const char *colon = p;
        while (colon > spec + 4 && colon[-1] != ':') colon--;
        if (colon <= spec + 4) break;
        size_t n = (size_t)(p - colon);
        bool numeric = n > 0;
        for (size_t i = 0; i < n && numeric; ++i) numeric = strchr("0123456789+-.,eE", colon[i]) != NULL;
        if (!numeric) break;
        field[nf] = colon;
        len[nf] = n;
        nf++;
        p = colon - 1;
    }
    if (nf == 0 || p <= spec + 4) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': expected ies:FILE:X,Y,Z[:DX,DY,DZ[,UX,UY,UZ][:R,G,B]]", spec);
    char path[1024];
    const size_t plen = (size_t)(p - (spec + 4));
    if (plen >= sizeof path) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': file name too long", spec);
    memcpy(path, spec + 4, plen);
    path[plen] = 0;
    prt_light l;
    memset(&l, 0, sizeof l);
    l.type = PRT_LIGHT_IES;
    l.direction[1] = -1.0f;
    l.scale[0] = l.scale[1] = l.scale[2] = 1.0f;
    double v[6];
    /* field[nf - 1] is the position, then the direction, then the scale. */
    if (parse_list(field[nf - 1], len[nf - 1], v, 3, 3) < 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': position needs X,Y,Z", spec);
    for (int c = 0; c < 3; ++c) l.position[c] = (float)v[c];
    if (nf >= 2) {
        int n = parse_list(field[nf - 2], len[nf - 2], v, 3, 6);
        if (n != 3 && n != 6) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': direction needs DX,DY,DZ or DX,DY,DZ,UX,UY,UZ", spec);
        for (int c = 0; c < 3; ++c) l.direction[c] = (float)v[c];
        for (int c = 0; c < 3 && n == 6; ++c) l.up[c] = (float)v[3 + c];
    }
    if (nf == 3) {
        int n = parse_list(field[0], len[0], v, 1, 3);
        if (n != 1 && n != 3) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': scale needs R,G,B or one number", spec);
        for (int c = 0; c < 3; ++c) l.scale[c] = (float)v[n == 3 ? c : 0];
    }
    prt_status st = prt_ies_load(path, &l.profile);
    if (!st) st = prt_light_validate(&l);
    if (st) {
        char msg[256];
        snprintf(msg, sizeof msg, "%s", prt_last_error());
        prt_ies_release(l.profile);
        return prt__fail(NULL, st, "light '%s': %s", spec, msg);
    }
    *out = l;
    return PRT_OK;
}

void prt_light_clear(prt_light *l)
{
    if (!l) return;
    if (l->type == PRT_LIGHT_IES) prt_ies_release(l->profile);
    memset(l, 0, sizeof *l);
}

void prt_light_copy(prt_light *dst, const prt_light *src)
{
    if (!dst || !src) return;
    *dst = *src;
    if (dst->type == PRT_LIGHT_IES) prt_ies_retain(dst->profile);
}

void prt_light_intensity_towards(const prt_light *l, const float w[3], float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!l || (l->type != PRT_LIGHT_POINT && l->type != PRT_LIGHT_SPOT && l->type != PRT_LIGHT_IES)) return;
    const float wi[3] = {-w[0], -w[1], -w[2]};
    if (l->type == PRT_LIGHT_IES) {
        double f = prt__ies_factor(l, wi);
        for (int k = 0; k < 3; ++k) rgb[k] = (float)(l->scale[k] * f);
        return;
    }
    double f = l->type == PRT_LIGHT_SPOT ? prt__spot_factor(l, wi) : 1.0;
    for (int k = 0; k < 3; ++k) rgb[k] = (float)(l->intensity[k] * f);
}

prt_status prt_light_parse(const char *spec, prt_light *out)
{
    if (!spec || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_light_parse: spec and out are required");
    if (!strncmp(spec, "ies:", 4)) return parse_ies(spec, out);
    const char *field[6];
    size_t len[6];
    int nf = 0;
    for (const char *p = spec;;) {
        const char *colon = strchr(p, ':');
        if (nf == 6) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': too many ':' fields", spec);
        field[nf] = p;
        len[nf] = colon ? (size_t)(colon - p) : strlen(p);
        nf++;
        if (!colon) break;
        p = colon + 1;
    }
    static const struct { const char *name; prt_light_type type; int fields; const char *form; } kinds[] = {
        {"point", PRT_LIGHT_POINT, 3, "point:X,Y,Z:R,G,B"},
        {"spot", PRT_LIGHT_SPOT, 5, "spot:X,Y,Z:DX,DY,DZ:ANGLE[,FALLOFF]:R,G,B"},
        {"directional", PRT_LIGHT_DIRECTIONAL, 3, "directional:DX,DY,DZ:R,G,B"},
        {"sphere", PRT_LIGHT_SPHERE, 4, "sphere:X,Y,Z:RADIUS:R,G,B"},
    };
    int k = -1;
    for (int i = 0; i < 4; ++i)
        if (len[0] == strlen(kinds[i].name) && !strncmp(field[0], kinds[i].name, len[0])) k = i;
    if (k < 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': unknown type (point, spot, directional or sphere)", spec);
    if (nf != kinds[k].fields) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': expected %s", spec, kinds[k].form);
    prt_light l;
    memset(&l, 0, sizeof l);
    l.type = kinds[k].type;
    double v[3];
    int f = 1;
    if (l.type != PRT_LIGHT_DIRECTIONAL) {
        if (parse_list(field[f], len[f], v, 3, 3) < 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': position needs X,Y,Z", spec);
        for (int c = 0; c < 3; ++c) l.position[c] = (float)v[c];
        f++;
    }
    if (l.type == PRT_LIGHT_SPOT || l.type == PRT_LIGHT_DIRECTIONAL) {
        if (parse_list(field[f], len[f], v, 3, 3) < 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': direction needs DX,DY,DZ", spec);
        for (int c = 0; c < 3; ++c) l.direction[c] = (float)v[c];
        f++;
    }
    if (l.type == PRT_LIGHT_SPOT) {
        int n = parse_list(field[f], len[f], v, 1, 2);
        if (n < 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': angle needs ANGLE or ANGLE,FALLOFF (degrees)", spec);
        if (!(v[0] > 0) || (n == 2 && !(v[1] >= 0)))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': angle must be > 0 and falloff >= 0", spec);
        l.angle_deg = (float)v[0];
        l.falloff_deg = n == 2 ? (float)v[1] : 0.0f;
        f++;
    }
    if (l.type == PRT_LIGHT_SPHERE) {
        if (parse_list(field[f], len[f], v, 1, 1) < 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': radius needs one number", spec);
        l.radius = (float)v[0];
        f++;
    }
    const char *what = l.type == PRT_LIGHT_DIRECTIONAL ? "irradiance" : l.type == PRT_LIGHT_SPHERE ? "radiance" : "intensity";
    int n = parse_list(field[f], len[f], v, 1, 3);
    if (n != 1 && n != 3) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light '%s': %s needs R,G,B or one number", spec, what);
    float *rgb = l.type == PRT_LIGHT_DIRECTIONAL ? l.irradiance : l.type == PRT_LIGHT_SPHERE ? l.radiance : l.intensity;
    for (int c = 0; c < 3; ++c) rgb[c] = (float)v[n == 3 ? c : 0];
    prt_status st = prt_light_validate(&l);
    if (st) {
        char msg[256];
        snprintf(msg, sizeof msg, "%s", prt_last_error());
        return prt__fail(NULL, st, "light '%s': %s", spec, msg);
    }
    *out = l;
    return PRT_OK;
}

/* %.9g reads back to the same float. */
static int put3(char *buf, size_t size, const float *v, bool grey_ok)
{
    if (grey_ok && v[0] == v[1] && v[1] == v[2]) return snprintf(buf, size, "%.9g", v[0]);
    return snprintf(buf, size, "%.9g,%.9g,%.9g", v[0], v[1], v[2]);
}

void prt_light_format(const prt_light *l, char *buf, size_t size)
{
    if (!buf || size == 0) return;
    buf[0] = 0;
    if (!l) return;
    char a[96], b[96], c[96];
    switch (l->type) {
    case PRT_LIGHT_POINT:
        put3(a, sizeof a, l->position, false); put3(b, sizeof b, l->intensity, true);
        snprintf(buf, size, "point:%s:%s", a, b);
        return;
    case PRT_LIGHT_SPOT:
        put3(a, sizeof a, l->position, false); put3(b, sizeof b, l->direction, false); put3(c, sizeof c, l->intensity, true);
        snprintf(buf, size, "spot:%s:%s:%.9g,%.9g:%s", a, b, l->angle_deg, l->falloff_deg, c);
        return;
    case PRT_LIGHT_DIRECTIONAL:
        put3(a, sizeof a, l->direction, false); put3(b, sizeof b, l->irradiance, true);
        snprintf(buf, size, "directional:%s:%s", a, b);
        return;
    case PRT_LIGHT_SPHERE:
        put3(a, sizeof a, l->position, false); put3(b, sizeof b, l->radiance, true);
        snprintf(buf, size, "sphere:%s:%.9g:%s", a, l->radius, b);
        return;
    case PRT_LIGHT_IES:
        put3(a, sizeof a, l->position, false); put3(b, sizeof b, l->scale, true);
        snprintf(buf, size, "ies:%s:%s:%.9g,%.9g,%.9g,%.9g,%.9g,%.9g:%s", prt_ies_path(l->profile), a, l->direction[0], l->direction[1], l->direction[2],
                 l->up[0], l->up[1], l->up[2], b);
        return;
    }
}

/* Irradiance from a uniform sphere of unit radiance whose centre lies at angle theta from the
 * normal (cos_t) and whose cap has half-angle sigma (sin2_s = sin^2 sigma). Fully above the
 * horizon the cap gives pi sin^2 sigma cos theta. Where it straddles the horizon, the exact
 * horizon-clipped integral (Snyder 1996, "Area light sources for real-time graphics"; as written
 * in Lagarde & de Rousiers 2014, eq. 19): a sphere cap's irradiance depends only on its circular
 * outline, so the disc formula is exact for the sphere too. */
double prt__sphere_cap_irradiance(double cos_t, double sin2_s)
{
    if (sin2_s >= 1.0) return PRT_PI;   /* inside the sphere: radiance L from the whole hemisphere */
    if (cos_t * cos_t >= sin2_s) return cos_t > 0 ? PRT_PI * sin2_s * cos_t : 0.0;
    double sin_t = sqrt(fmax(0.0, 1.0 - cos_t * cos_t));
    double x = sqrt(1.0 / sin2_s - 1.0);   /* cot sigma */
    double y = fmin(1.0, fmax(-1.0, -x * cos_t / sin_t));
    double s = sin_t * sqrt(fmax(0.0, 1.0 - y * y));
    return fmax(0.0, (cos_t * acos(y) - x * s) * sin2_s + atan2(s, x));
}

void prt_light_irradiance(const prt_light *l, const float p[3], const float n[3], float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!l) return;
    if (l->type == PRT_LIGHT_DIRECTIONAL) {
        float c = prt__v3_dot(n, l->direction);
        for (int k = 0; k < 3; ++k) rgb[k] = c > 0 ? l->irradiance[k] * c : 0.0f;
        return;
    }
    double d[3] = {(double)l->position[0] - p[0], (double)l->position[1] - p[1], (double)l->position[2] - p[2]};
    double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(r2);
    if (l->type == PRT_LIGHT_SPHERE) {
        double R = l->radius, cos_t = r > 0 ? (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / r : 1.0;
        double e = prt__sphere_cap_irradiance(cos_t, r > R ? R * R / r2 : 1.0);
        for (int k = 0; k < 3; ++k) rgb[k] = (float)(l->radiance[k] * e);
        return;
    }
    if (!(r > 0)) return;
    double c = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / r;
    if (c <= 0) return;
    float wi[3] = {(float)(d[0] / r), (float)(d[1] / r), (float)(d[2] / r)};
    if (l->type == PRT_LIGHT_IES) {
        double f = prt__ies_factor(l, wi);
        for (int k = 0; k < 3; ++k) rgb[k] = (float)(l->scale[k] * f * c / r2);
        return;
    }
    double s = l->type == PRT_LIGHT_SPOT ? prt__spot_factor(l, wi) : 1.0;
    for (int k = 0; k < 3; ++k) rgb[k] = (float)(l->intensity[k] * c / r2 * s);
}

/* ---- the lighting object ---- */

struct prt_lighting {
    prt_envmap *env;
    double rot[9];
    float intensity;
    prt_environment_desc desc;
    prt_light *lights;
    int count, cap;
    float emission;
};

static const double IDENTITY[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

prt_status prt_lighting_create(prt_lighting **out)
{
    if (!out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_create: out is required");
    prt_lighting *l = prt__calloc(1, sizeof *l);
    if (!l) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for a lighting");
    memcpy(l->rot, IDENTITY, sizeof l->rot);
    l->intensity = 1.0f;
    l->emission = 1.0f;
    *out = l;
    return PRT_OK;
}

void prt_lighting_release(prt_lighting *l)
{
    if (!l) return;
    prt_envmap_release(l->env);
    for (int i = 0; i < l->count; ++i) prt_light_clear(&l->lights[i]);
    free(l->lights);
    free(l);
}

static prt_status copy_envmap(const prt_envmap *src, prt_envmap **out)
{
    prt_image img = src->img;
    size_t n = (size_t)img.width * img.height * 3;
    img.rgb = malloc(n * sizeof(float));
    if (!img.rgb) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory copying an environment");
    memcpy(img.rgb, src->img.rgb, n * sizeof(float));
    prt_status st = prt_envmap_from_image(&img, src->layout, out);
    if (st) prt_image_free(&img);
    return st;
}

prt_status prt_lighting_copy(const prt_lighting *src, prt_lighting **out)
{
    if (!src || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_copy: src and out are required");
    *out = NULL;
    prt_lighting *l = prt__calloc(1, sizeof *l);
    if (!l) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for a lighting");
    *l = *src;
    l->env = NULL;
    l->lights = NULL;
    l->cap = 0;
    prt_status st = src->env ? copy_envmap(src->env, &l->env) : PRT_OK;
    if (!st && src->count) {
        l->lights = malloc((size_t)src->count * sizeof *l->lights);
        if (!l->lights) st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory copying lights");
        else {
            for (int i = 0; i < src->count; ++i) prt_light_copy(&l->lights[i], &src->lights[i]);
            l->cap = src->count;
        }
    }
    if (st) { l->count = 0; prt_lighting_release(l); return st; }
    *out = l;
    return PRT_OK;
}

prt_status prt_lighting_set_environment(prt_lighting *l, const prt_environment_desc *desc)
{
    if (!l || !desc) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_set_environment: lighting and desc are required");
    if (!desc->none && (!finite3(desc->rotate_deg) || !(desc->intensity >= 0) || !isfinite(desc->intensity)))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "environment: rotation must be finite and intensity a finite number >= 0");
    prt_envmap *env = NULL;
    if (!desc->none) {
        prt_status st;
        if (desc->path[0]) {
            st = prt_envmap_load(desc->path, desc->layout, &env);
        } else {
            prt_sky_desc sky;
            memset(&sky, 0, sizeof sky);
            memcpy(sky.sun_dir, desc->sun_dir, sizeof sky.sun_dir);
            st = prt_sky_create(&sky, &env);
        }
        if (st) return st;
    }
    prt_envmap_release(l->env);
    l->env = env;
    l->desc = *desc;
    if (desc->none) memcpy(l->rot, IDENTITY, sizeof l->rot);
    else prt_rotation_from_euler_deg(desc->rotate_deg[0], desc->rotate_deg[1], desc->rotate_deg[2], l->rot);
    l->intensity = desc->intensity > 0 ? desc->intensity : 1.0f;
    return PRT_OK;
}

prt_status prt_lighting_set_envmap(prt_lighting *l, prt_envmap *env, const double rot[9], float intensity)
{
    if (!l) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_set_envmap: lighting is required");
    if (!(intensity >= 0) || !isfinite(intensity))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "environment intensity must be a finite number >= 0 (got %g)", intensity);
    for (int i = 0; rot && i < 9; ++i)
        if (!isfinite(rot[i])) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "environment rotation must be finite");
    if (l->env != env) prt_envmap_release(l->env);
    l->env = env;
    memset(&l->desc, 0, sizeof l->desc);
    memcpy(l->rot, rot ? rot : IDENTITY, sizeof l->rot);
    l->intensity = intensity > 0 ? intensity : 1.0f;
    return PRT_OK;
}

void prt_lighting_set_rotation(prt_lighting *l, const double rot[9])
{
    if (l) memcpy(l->rot, rot ? rot : IDENTITY, sizeof l->rot);
}

void prt_lighting_set_intensity(prt_lighting *l, float intensity)
{
    /* An explicit 0 turns the environment off; a void setter cannot refuse bad values, so
     * negative or non-finite ones leave the intensity as it was. */
    if (l && intensity >= 0 && isfinite(intensity)) l->intensity = intensity;
}

const prt_envmap *prt_lighting_envmap(const prt_lighting *l) { return l ? l->env : NULL; }

void prt_lighting_rotation(const prt_lighting *l, double rot[9]) { memcpy(rot, l ? l->rot : IDENTITY, 9 * sizeof(double)); }

float prt_lighting_intensity(const prt_lighting *l) { return l ? l->intensity : 1.0f; }

const prt_environment_desc *prt_lighting_environment_desc(const prt_lighting *l) { return l ? &l->desc : NULL; }

prt_status prt_lighting_add(prt_lighting *l, const prt_light *light, int *index)
{
    if (!l || !light) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_add: lighting and light are required");
    prt_light copy = *light;
    prt_status st = prt_light_validate(&copy);
    if (st) return st;
    if (l->count == l->cap) {
        if (l->cap >= 1 << 20) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a lighting holds at most %d lights", 1 << 20);
        int cap = l->cap ? l->cap * 2 : 8;
        prt_light *p = realloc(l->lights, (size_t)cap * sizeof *p);
        if (!p) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory adding a light");
        l->lights = p;
        l->cap = cap;
    }
    if (index) *index = l->count;
    prt_light_copy(&l->lights[l->count++], &copy);
    return PRT_OK;
}

prt_status prt_lighting_set(prt_lighting *l, int index, const prt_light *light)
{
    if (!l || !light) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_set: lighting and light are required");
    if (index < 0 || index >= l->count) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light index %d out of range 0..%d", index, l->count - 1);
    prt_light copy = *light;
    prt_status st = prt_light_validate(&copy);
    if (st) return st;
    prt_light old = l->lights[index];
    prt_light_copy(&l->lights[index], &copy);
    prt_light_clear(&old);
    return PRT_OK;
}

prt_status prt_lighting_remove(prt_lighting *l, int index)
{
    if (!l) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_remove: lighting is required");
    if (index < 0 || index >= l->count) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "light index %d out of range 0..%d", index, l->count - 1);
    prt_light_clear(&l->lights[index]);
    memmove(l->lights + index, l->lights + index + 1, (size_t)(l->count - index - 1) * sizeof *l->lights);
    l->count--;
    return PRT_OK;
}

void prt_lighting_clear_lights(prt_lighting *l)
{
    if (!l) return;
    for (int i = 0; i < l->count; ++i) prt_light_clear(&l->lights[i]);
    l->count = 0;
}

int prt_lighting_count(const prt_lighting *l) { return l ? l->count : 0; }

const prt_light *prt_lighting_light(const prt_lighting *l, int index)
{
    return l && index >= 0 && index < l->count ? &l->lights[index] : NULL;
}

void prt_lighting_set_emission(prt_lighting *l, float scale)
{
    /* Negative or NaN scales would make surfaces absorb light: they switch emission off. */
    if (l) l->emission = scale > 0 && isfinite(scale) ? scale : 0.0f;
}

float prt_lighting_emission(const prt_lighting *l) { return l ? l->emission : 0.0f; }

unsigned prt_lighting_content(const prt_lighting *l)
{
    if (!l) return 0;
    unsigned bits = l->env ? PRT_LIGHTS_ENVIRONMENT : 0;
    for (int i = 0; i < l->count; ++i) bits |= prt_light_type_bit(l->lights[i].type);
    if (l->emission > 0) bits |= PRT_LIGHTS_EMISSIVE;
    return bits;
}
