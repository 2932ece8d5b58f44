/* Light sampling from surface points (light/light_sample.h). */
#include "light/light_sample.h"

#include <string.h>

double prt__spot_factor(const prt_light *l, const float wi[3])
{
    /* The spot shines along its direction; the point sees the light along wi, so the light sees
     * the point along -wi. */
    double c = -((double)l->direction[0] * wi[0] + (double)l->direction[1] * wi[1] + (double)l->direction[2] * wi[2]);
    double outer = cos(l->angle_deg * PRT_PI / 180.0), inner = cos(l->falloff_deg * PRT_PI / 180.0);
    if (c >= inner) return 1.0;
    if (c <= outer) return 0.0;
    double t = (c - outer) / (inner - outer);
    return t * t * (3.0 - 2.0 * t);
}

/* Orthonormal t, b around unit w. */
static void frame(const double w[3], double t[3], double b[3])
{
    double a[3] = {0, 0, 0};
    a[fabs(w[0]) < 0.6 ? 0 : 1] = 1;
    t[0] = a[1] * w[2] - a[2] * w[1]; t[1] = a[2] * w[0] - a[0] * w[2]; t[2] = a[0] * w[1] - a[1] * w[0];
    double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int k = 0; k < 3; ++k) t[k] /= len;
    b[0] = w[1] * t[2] - w[2] * t[1]; b[1] = w[2] * t[0] - w[0] * t[2]; b[2] = w[0] * t[1] - w[1] * t[0];
}

/* 1 - cos of the half-angle of the cone a sphere subtends at distance^2 d2 (> R^2), without
 * cancellation for small spheres. */
static double cone_one_minus_cos(double R2, double d2)
{
    double s2 = R2 / d2;
    return s2 / (1.0 + sqrt(fmax(0.0, 1.0 - s2)));
}

bool prt__light_sample_from(const prt_light *l, const float p[3], double u1, double u2, prt__light_sample *s)
{
    memset(s, 0, sizeof *s);
    if (l->type == PRT_LIGHT_DIRECTIONAL) {
        memcpy(s->wi, l->direction, sizeof s->wi);
        s->dist = INFINITY;
        memcpy(s->value, l->irradiance, sizeof s->value);
        return s->value[0] > 0 || s->value[1] > 0 || s->value[2] > 0;
    }
    double d[3] = {(double)l->position[0] - p[0], (double)l->position[1] - p[1], (double)l->position[2] - p[2]};
    double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(d2);
    if (!(r > 0)) return false;
    double w[3] = {d[0] / r, d[1] / r, d[2] / r};
    if (l->type != PRT_LIGHT_SPHERE) {
        for (int k = 0; k < 3; ++k) s->wi[k] = (float)w[k];
        const bool ies = l->type == PRT_LIGHT_IES;
        double f = l->type == PRT_LIGHT_SPOT ? prt__spot_factor(l, s->wi) : ies ? prt__ies_factor(l, s->wi) : 1.0;
        if (f <= 0) return false;
        s->dist = (float)r;
        const float *I = ies ? l->scale : l->intensity;
        for (int k = 0; k < 3; ++k) s->value[k] = (float)(I[k] * f / d2);
        return s->value[0] > 0 || s->value[1] > 0 || s->value[2] > 0;
    }
    const double R = l->radius;
    if (r <= R) return false;   /* inside: every direction reaches the sphere; BRDF sampling finds it */
    /* Uniform over the cone the sphere subtends. */
    double omc = cone_one_minus_cos(R * R, d2), v = u1 * omc;
    double cos_t = 1.0 - v, sin_t = sqrt(fmax(0.0, v * (2.0 - v))), phi = 2.0 * PRT_PI * u2;
    double t[3], b[3];
    frame(w, t, b);
    double dir[3];
    for (int k = 0; k < 3; ++k) dir[k] = sin_t * cos(phi) * t[k] + sin_t * sin(phi) * b[k] + cos_t * w[k];
    /* Distance to the near side of the sphere along dir (the cone grazes it at the rim). */
    double disc = R * R - d2 * sin_t * sin_t;
    double dist = r * cos_t - sqrt(fmax(0.0, disc));
    for (int k = 0; k < 3; ++k) s->wi[k] = (float)dir[k];
    s->dist = (float)fmax(dist, 0.0);
    s->pdf = (float)(1.0 / (2.0 * PRT_PI * omc));
    for (int k = 0; k < 3; ++k) s->value[k] = (float)(l->radiance[k] * 2.0 * PRT_PI * omc);
    return s->value[0] > 0 || s->value[1] > 0 || s->value[2] > 0;
}

float prt__sphere_light_hit(const prt_light *l, const float o[3], const float d[3])
{
    double oc[3] = {(double)o[0] - l->position[0], (double)o[1] - l->position[1], (double)o[2] - l->position[2]};
    double b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
    double c = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - (double)l->radius * l->radius;
    double disc = b * b - c;
    if (disc < 0) return INFINITY;
    double q = sqrt(disc), t = c > 0 ? -b - q : -b + q;
    return t > 0 ? (float)t : INFINITY;
}

float prt__sphere_light_pdf(const prt_light *l, const float p[3])
{
    double d[3] = {(double)l->position[0] - p[0], (double)l->position[1] - p[1], (double)l->position[2] - p[2]};
    double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], R2 = (double)l->radius * l->radius;
    if (d2 <= R2) return 0.0f;
    return (float)(1.0 / (2.0 * PRT_PI * cone_one_minus_cos(R2, d2)));
}

/* ---- emissive triangles ---- */

static double luminance(const float *rgb) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

static void tri_normal(const prt__mesh *m, uint32_t tri, float n[3], float *area)
{
    const uint32_t *v = m->indices + (size_t)tri * 3;
    float e1[3], e2[3];
    prt__v3_sub(m->positions + v[1] * 3, m->positions + v[0] * 3, e1);
    prt__v3_sub(m->positions + v[2] * 3, m->positions + v[0] * 3, e2);
    prt__v3_cross(e1, e2, n);   /* counter-clockwise is the front, as the ray caster reads it */
    *area = 0.5f * prt__v3_len(n);
    prt__v3_normalize(n);
}

prt_status prt__emitters_init(prt__emitters *e, const prt__mesh *m, float scale)
{
    memset(e, 0, sizeof *e);
    e->scale = scale;
    if (!m->emission || !(scale > 0)) return PRT_OK;
    size_t n = 0;
    double *w = prt__calloc(m->triangle_count, sizeof *w);
    if (!w) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for the emitter table");
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *v = m->indices + t * 3;
        double lum = (luminance(m->emission + v[0] * 3) + luminance(m->emission + v[1] * 3) + luminance(m->emission + v[2] * 3)) / 3.0;
        float nrm[3], area;
        tri_normal(m, (uint32_t)t, nrm, &area);
        w[t] = lum > 0 ? lum * area : 0.0;
        n += w[t] > 0;
    }
    if (n == 0) { free(w); return PRT_OK; }
    e->tri = malloc(n * sizeof *e->tri);
    e->cdf = malloc(n * sizeof *e->cdf);
    e->pdf_area = prt__calloc(m->triangle_count, sizeof *e->pdf_area);
    if (!e->tri || !e->cdf || !e->pdf_area) {
        free(w);
        prt__emitters_free(e);
        return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for the emitter table");
    }
    double acc = 0;
    for (size_t t = 0; t < m->triangle_count; ++t)
        if (w[t] > 0) { e->tri[e->count] = (uint32_t)t; e->cdf[e->count++] = acc += w[t]; }
    for (size_t i = 0; i < e->count; ++i) {
        uint32_t t = e->tri[i];
        float nrm[3], area;
        tri_normal(m, t, nrm, &area);
        e->pdf_area[t] = (float)(w[t] / acc / area);
        e->cdf[i] /= acc;
    }
    e->cdf[e->count - 1] = 1.0;
    free(w);
    e->scale = scale;
    return PRT_OK;
}

void prt__emitters_free(prt__emitters *e)
{
    free(e->tri); free(e->cdf); free(e->pdf_area);
    memset(e, 0, sizeof *e);
}

void prt__emission_at(const prt__emitters *e, const prt__mesh *m, uint32_t tri, float b1, float b2, float rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!e->count || !(e->pdf_area[tri] > 0)) return;
    const uint32_t *v = m->indices + (size_t)tri * 3;
    float b0 = 1.0f - b1 - b2;
    for (int c = 0; c < 3; ++c)
        rgb[c] = e->scale * (b0 * m->emission[v[0] * 3 + c] + b1 * m->emission[v[1] * 3 + c] + b2 * m->emission[v[2] * 3 + c]);
}

bool prt__emitters_sample(const prt__emitters *e, const prt__mesh *m, const float p[3], double u1, double u2, double u3,
                          prt__light_sample *s)
{
    memset(s, 0, sizeof *s);
    if (!e->count) return false;
    size_t lo = 0, hi = e->count - 1;   /* first emitter whose cdf exceeds u1 */
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (e->cdf[mid] > u1) hi = mid; else lo = mid + 1;
    }
    uint32_t tri = e->tri[lo];
    const uint32_t *v = m->indices + (size_t)tri * 3;
    double su = sqrt(u2);
    float b1 = (float)(u3 * su), b2 = (float)(1.0 - su), b0 = 1.0f - b1 - b2;
    double q[3], d[3];
    for (int c = 0; c < 3; ++c) {
        q[c] = (double)b0 * m->positions[v[0] * 3 + c] + (double)b1 * m->positions[v[1] * 3 + c] + (double)b2 * m->positions[v[2] * 3 + c];
        d[c] = q[c] - p[c];
    }
    double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(d2);
    if (!(r > 0)) return false;
    float nrm[3], area;
    tri_normal(m, tri, nrm, &area);
    for (int c = 0; c < 3; ++c) s->wi[c] = (float)(d[c] / r);
    float cos_l = -prt__v3_dot(nrm, s->wi);
    if (!(cos_l > 0)) return false;   /* the back of an emitter is dark */
    float le[3];
    prt__emission_at(e, m, tri, b1, b2, le);
    s->dist = (float)r;
    s->pdf = prt__emitters_pdf(e, tri, (float)r, cos_l);
    if (!(s->pdf > 0) || !isfinite(s->pdf)) return false;
    for (int c = 0; c < 3; ++c) s->value[c] = le[c] / s->pdf;
    return le[0] > 0 || le[1] > 0 || le[2] > 0;
}

float prt__emitters_pdf(const prt__emitters *e, uint32_t tri, float dist, float cos_light)
{
    if (!e->count || !(cos_light > 0)) return 0.0f;
    return e->pdf_area[tri] * dist * dist / cos_light;
}
