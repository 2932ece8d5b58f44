/* The reference path tracer (prt/reference.h). Each path starts at a surface point: the vertex
 * itself for per-vertex results, or the first hit of a camera ray. At every surface it samples
 * each light explicitly (next-event estimation: the environment, every local light, one point on
 * the emissive triangles), then continues along a direction drawn from the material's BRDF with
 * Russian roulette; where that direction can also reach a light (the environment, a sphere, an
 * emissive triangle), the two estimates are combined by the power heuristic. Point, spot and
 * directional lights are deltas, reached only by next-event estimation.
 *
 * BRDF sampling is a mixture of cosine sampling and a lobe around where the BRDF peaks (Phong:
 * the mirror direction; Blinn-Phong and Ashikhmin-Shirley: their half-vector distributions;
 * Lafortune: its lobes' axes); the cosine part covers the whole hemisphere, so the estimate is
 * unbiased for any BRDF, and the mixture pdf enters the MIS weights. BRDFs are evaluated with
 * prt_brdf_eval in the frame of prt_brdf_frame, as the bakes do.
 *
 * Sphere lights are not part of the ray-cast scene: they are transparent emitters, adding their
 * radiance to every ray that crosses them and blocking nothing (no other light, no surface).
 *
 * Mirrors and glass (brdf/specular.c) are delta BSDFs: the path turns there without sampling a
 * light, and the light it then meets counts with weight 1. */
#include "core/progress.h"
#include "prt/reference.h"
#include "geom/raycast.h"
#include "light/env_sample.h"
#include "light/light_sample.h"
#include "brdf/specular.h"
#include "geom/volume.h"
#include "render/volumes.h"
#include "render/pinhole.h"

#include <string.h>

/* How one material is sampled: a cosine part with probability p_cos, else its lobe. */
enum { LOBE_NONE, LOBE_PHONG, LOBE_BLINN, LOBE_ASHIKHMIN, LOBE_LAFORTUNE };
typedef struct pt_material {
    const prt_brdf *brdf;    /* NULL = Lambert with the vertex albedo */
    int lobe;
    float p_cos;
    float nu, nv;            /* exponents (Blinn-Phong and Phong: nu) */
    int lobes;               /* Lafortune: per lobe the channel-mean coefficients and exponent */
    float cxy[PRT_BRDF_MAX_LOBES], cz[PRT_BRDF_MAX_LOBES], n[PRT_BRDF_MAX_LOBES];
} pt_material;

typedef struct pt_job {
    const prt__mesh *mesh;
    pt_material mats[PRT__MAX_BRDFS + 1];
    prt__raycaster rc;
    bool has_env;
    prt__env_sampler env;
    const prt_light *lights;
    int light_count;
    prt__emitters emit;
    float offset;
    int max_depth;
    uint32_t seed;
    const float *eye;
    float *origins;   /* per vertex, as the bakes use them */
    prt_specular *spec;   /* per surface (prt__specular_table); NULL when nothing is specular */
    const prt__volume *volumes;   /* participating media (the scene's "volumes") */
    int volume_count;
    float majorant;               /* of their summed extinction, for delta tracking */
} pt_job;

/* Transmittance of the media along o + t d, t < tfar (surface paths see media as absorbers:
 * what they scatter towards surfaces is left out, as the bakes leave it out). */
static float media_transmittance(const pt_job *j, const float o[3], const float d[3], float tfar)
{
    return j->volume_count ? expf(-prt__volumes_optical_depth(j->volumes, j->volume_count, o, d, tfar)) : 1.0f;
}

/* ---- counter-based random numbers: one stream per (item, sample), independent of threads */
typedef struct rng { uint64_t s; } rng;
static uint64_t splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
static rng rng_for(uint32_t seed, uint64_t item, uint32_t sample)
{
    rng r = {((uint64_t)seed << 32) ^ (item * 0x632be59bd9b4e019ULL) ^ ((uint64_t)sample * 0xd1b54a32d192ed03ULL)};
    splitmix(&r.s);
    return r;
}
static double uniform(rng *r) { return (double)(splitmix(&r->s) >> 11) * (1.0 / 9007199254740992.0); }

static void basis(const float n[3], float t[3], float b[3])
{
    /* Duff et al. 2017: an orthonormal basis without branches on the normal's direction. */
    float sign = copysignf(1.0f, n[2]), a = -1.0f / (sign + n[2]), c = n[0] * n[1] * a;
    t[0] = 1.0f + sign * n[0] * n[0] * a; t[1] = sign * c; t[2] = -sign * n[0];
    b[0] = c; b[1] = sign + n[1] * n[1] * a; b[2] = -n[1];
}

/* True when something blocks o + t d for t in (0, tfar). */
static bool occluded(const pt_job *j, const float o[3], const float d[3], float tfar)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r = {o[0], o[1], o[2], 0.0f, d[0], d[1], d[2], 0.0f, tfar, 0xFFFFFFFFu, 0, 0};
    rtcOccluded1(j->rc.scene, &ctx, &r);
    return r.tfar < 0.0f;
}

/* A surface point: position, shading and geometric normal, the shading frame (s, t, n) of
 * prt_brdf_frame, albedo, material, emitted radiance towards the viewer, and the origin for
 * rays leaving it (offset to its front side). */
typedef struct surface {
    float p[3], n[3], ng[3], s[3], t[3], rho[3], o[3], le[3];
    int mat;
    const prt_specular *sp;   /* a mirror or glass hit (n, ng its front's normals); NULL: diffuse */
    uint32_t tri;     /* the triangle hit (camera and path hits) */
    float dist;       /* of the hit along the ray that found it */
} surface;

static void set_frame(surface *s)
{
    prt_brdf_frame(s->n, s->s, s->t);
    /* Keep the frame orthonormal to the float precision the sampling relies on. */
    float d = prt__v3_dot(s->s, s->n);
    for (int c = 0; c < 3; ++c) s->s[c] -= d * s->n[c];
    if (!prt__v3_normalize(s->s)) basis(s->n, s->s, s->t);
    prt__v3_cross(s->n, s->s, s->t);
}

static void to_local(const surface *s, const float w[3], float l[3])
{
    l[0] = prt__v3_dot(w, s->s); l[1] = prt__v3_dot(w, s->t); l[2] = prt__v3_dot(w, s->n);
}

static void to_world(const surface *s, const float l[3], float w[3])
{
    for (int c = 0; c < 3; ++c) w[c] = l[0] * s->s[c] + l[1] * s->t[c] + l[2] * s->n[c];
}

/* Traces o + t d; fills the surface hit. Returns 0 on a miss, 1 on a front face, -1 on a back face. */
static int intersect(const pt_job *j, const float o[3], const float d[3], surface *s)
{
    prt__ray_hit h;
    if (!prt__raycaster_hit(&j->rc, o, d, &h)) return 0;
    s->dist = h.t;
    float ng[3] = {h.ng[0], h.ng[1], h.ng[2]};
    const prt__mesh *m = j->mesh;
    /* Glass is met from inside too; everything else only from the front. */
    s->sp = prt__specular_of(j->spec, m, h.prim);
    if (prt__v3_dot(ng, d) >= 0.0f && !(s->sp && s->sp->type == PRT_SPECULAR_GLASS)) return -1;   /* Ng faces where the triangle winds counter-clockwise */
    prt__v3_normalize(ng);
    const uint32_t *t = m->indices + (size_t)h.prim * 3;
    float w0 = 1.0f - h.u - h.v, w1 = h.u, w2 = h.v;
    for (int c = 0; c < 3; ++c) {
        s->p[c] = o[c] + h.t * d[c];
        s->n[c] = w0 * m->normals[t[0] * 3 + c] + w1 * m->normals[t[1] * 3 + c] + w2 * m->normals[t[2] * 3 + c];
        s->rho[c] = w0 * m->albedo[t[0] * 3 + c] + w1 * m->albedo[t[1] * 3 + c] + w2 * m->albedo[t[2] * 3 + c];
        s->ng[c] = ng[c];
        s->o[c] = s->p[c] + ng[c] * j->offset;
    }
    s->mat = m->material[t[0]];   /* a triangle never joins two objects */
    s->tri = h.prim;
    if (s->sp) {   /* the specular turn needs the front's normals as they are */
        if (!prt__v3_normalize(s->n) || prt__v3_dot(s->n, ng) <= 0.0f) memcpy(s->n, ng, sizeof ng);
        memset(s->le, 0, sizeof s->le);
        set_frame(s);
        return 1;
    }
    /* A shading normal turned away from the viewer would light the surface from behind. */
    if (!prt__v3_normalize(s->n) || prt__v3_dot(s->n, d) >= 0.0f) memcpy(s->n, ng, sizeof ng);
    set_frame(s);
    s->tri = h.prim;
    prt__emission_at(&j->emit, m, h.prim, w1, w2, s->le);
    return 1;
}

/* ---- BRDF evaluation and sampling in the local frame (z = n) ---- */

static void brdf_eval(const pt_job *j, const surface *s, const float wi[3], const float wo[3], float f[3])
{
    const pt_material *m = &j->mats[s->mat];
    if (m->brdf) { prt_brdf_eval(m->brdf, wi, wo, f); return; }
    bool up = wi[2] > 0.0f && wo[2] > 0.0f;
    for (int c = 0; c < 3; ++c) f[c] = up ? s->rho[c] / (float)PRT_PI : 0.0f;
}

/* Direction of a cos^n lobe about unit axis a, and its pdf (n+1)/(2 pi) cos^n. */
static void lobe_sample(const float a[3], float n, double u1, double u2, float w[3])
{
    float t[3], b[3];
    basis(a, t, b);
    double c = pow(u1, 1.0 / (n + 1.0)), sn = sqrt(fmax(0.0, 1.0 - c * c)), phi = 2.0 * PRT_PI * u2;
    for (int k = 0; k < 3; ++k) w[k] = (float)(sn * cos(phi) * t[k] + sn * sin(phi) * b[k] + c * a[k]);
}
static double lobe_pdf(const float a[3], float n, const float w[3])
{
    double c = prt__v3_dot(a, w);
    return c > 0 ? (n + 1.0) / (2.0 * PRT_PI) * pow(c, n) : 0.0;
}

/* Ashikhmin-Shirley's half-vector distribution: pdf_h = sqrt((nu+1)(nv+1))/(2 pi) (n.h)^(nu cos^2 phi + nv sin^2 phi). */
static double as_exponent(const pt_material *m, const float h[3])
{
    double s2 = (double)h[0] * h[0] + (double)h[1] * h[1];
    return s2 > 1e-12 ? (m->nu * h[0] * h[0] + m->nv * h[1] * h[1]) / s2 : 0.0;
}

/* Lafortune lobe k's axis for wo, normalised; false when it vanishes. */
static bool lafortune_axis(const pt_material *m, int k, const float wo[3], float a[3])
{
    a[0] = m->cxy[k] * wo[0]; a[1] = m->cxy[k] * wo[1]; a[2] = m->cz[k] * wo[2];
    return prt__v3_normalize(a);
}

/* The mixture's pdf per steradian of wi (local) given wo (local). */
static double brdf_pdf(const pt_material *m, const float wo[3], const float wi[3])
{
    double p = m->p_cos * fmax(wi[2], 0.0f) / PRT_PI;
    if (m->p_cos >= 1.0f || wi[2] <= 0.0f) return p;
    double q = 0.0, hv[3] = {(double)wi[0] + wo[0], (double)wi[1] + wo[1], (double)wi[2] + wo[2]};
    double hl = sqrt(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]);
    float h[3] = {(float)(hv[0] / hl), (float)(hv[1] / hl), (float)(hv[2] / hl)};
    double oh = prt__v3_dot(wo, h);
    switch (m->lobe) {
    case LOBE_PHONG: {
        float r[3] = {-wo[0], -wo[1], wo[2]};
        q = lobe_pdf(r, m->nu, wi);
        break;
    }
    case LOBE_BLINN:
        if (hl > 0 && oh > 0 && h[2] > 0) q = (m->nu + 1.0) / (2.0 * PRT_PI) * pow(h[2], m->nu) / (4.0 * oh);
        break;
    case LOBE_ASHIKHMIN:
        if (hl > 0 && oh > 0 && h[2] > 0)
            q = sqrt((m->nu + 1.0) * (m->nv + 1.0)) / (2.0 * PRT_PI) * pow(h[2], as_exponent(m, h)) / (4.0 * oh);
        break;
    case LOBE_LAFORTUNE:
        for (int k = 0; k < m->lobes; ++k) {
            float a[3];
            if (lafortune_axis(m, k, wo, a)) q += lobe_pdf(a, m->n[k], wi) / m->lobes;
        }
        break;
    }
    return p + (1.0 - m->p_cos) * q;
}

/* Draws wi (local) from the mixture; false when the draw is not a direction above the surface. */
static bool brdf_sample(const pt_material *m, const float wo[3], rng *r, float wi[3])
{
    double pick = uniform(r), u1 = uniform(r), u2 = uniform(r);
    if (pick < m->p_cos) {
        double rad = sqrt(u1), phi = 2.0 * PRT_PI * u2;
        wi[0] = (float)(rad * cos(phi)); wi[1] = (float)(rad * sin(phi)); wi[2] = (float)sqrt(fmax(0.0, 1.0 - u1));
        return wi[2] > 0.0f;
    }
    float h[3];
    switch (m->lobe) {
    case LOBE_PHONG: {
        float rr[3] = {-wo[0], -wo[1], wo[2]};
        lobe_sample(rr, m->nu, u1, u2, wi);
        return wi[2] > 0.0f;
    }
    case LOBE_BLINN: {
        float z[3] = {0, 0, 1};
        lobe_sample(z, m->nu, u1, u2, h);
        break;
    }
    case LOBE_ASHIKHMIN: {
        /* Their eq. 9 in the first quadrant, mirrored into the other three. */
        double u = 4.0 * u1;
        int quad = (int)u < 4 ? (int)u : 3;
        double f = u - quad;
        double phi = atan(sqrt((m->nu + 1.0) / (m->nv + 1.0)) * tan(0.5 * PRT_PI * f));
        if (quad == 1) phi = PRT_PI - phi; else if (quad == 2) phi = PRT_PI + phi; else if (quad == 3) phi = 2.0 * PRT_PI - phi;
        double cp = cos(phi), sp = sin(phi), e = m->nu * cp * cp + m->nv * sp * sp;
        double ch = pow(1.0 - u2, 1.0 / (e + 1.0)), sh = sqrt(fmax(0.0, 1.0 - ch * ch));
        h[0] = (float)(sh * cp); h[1] = (float)(sh * sp); h[2] = (float)ch;
        break;
    }
    case LOBE_LAFORTUNE: {
        int k = (int)(u1 * m->lobes);
        if (k >= m->lobes) k = m->lobes - 1;
        double v = u1 * m->lobes - k;   /* the rest of u1 drives the lobe */
        float a[3];
        if (!lafortune_axis(m, k, wo, a)) return false;
        lobe_sample(a, m->n[k], v, u2, wi);
        return wi[2] > 0.0f;
    }
    default:
        return false;
    }
    float oh = prt__v3_dot(wo, h);
    if (oh <= 0.0f) return false;
    for (int c = 0; c < 3; ++c) wi[c] = 2.0f * oh * h[c] - wo[c];
    return wi[2] > 0.0f;
}

static void material_init(pt_material *m, const prt_brdf *b)
{
    memset(m, 0, sizeof *m);
    m->brdf = b;
    m->p_cos = 1.0f;
    if (!b || !prt_brdf_is_glossy(b)) return;
    double kd = (b->diffuse[0] + b->diffuse[1] + b->diffuse[2]) / 3.0, ks = (b->specular[0] + b->specular[1] + b->specular[2]) / 3.0;
    double pc = 0.5;
    switch (b->model) {
    case PRT_BRDF_PHONG: m->lobe = LOBE_PHONG; m->nu = b->exponent; pc = kd / (kd + ks); break;
    case PRT_BRDF_BLINN_PHONG: m->lobe = LOBE_BLINN; m->nu = b->exponent; pc = kd / (kd + ks); break;
    case PRT_BRDF_ASHIKHMIN_SHIRLEY:
        m->lobe = LOBE_ASHIKHMIN; m->nu = b->exponent; m->nv = b->exponent_v;
        pc = kd * (1.0 - ks) / (kd * (1.0 - ks) + ks + 1e-9);
        break;
    case PRT_BRDF_LAFORTUNE:
        m->lobe = LOBE_LAFORTUNE;
        m->lobes = b->lobes;
        for (int k = 0; k < b->lobes; ++k) {
            m->cxy[k] = (b->cxy[k][0] + b->cxy[k][1] + b->cxy[k][2]) / 3.0f;
            m->cz[k] = (b->cz[k][0] + b->cz[k][1] + b->cz[k][2]) / 3.0f;
            m->n[k] = (b->n[k][0] + b->n[k][1] + b->n[k][2]) / 3.0f;
        }
        break;
    default: break;
    }
    /* The cosine part must keep a share: it is what makes the mixture cover every direction. */
    m->p_cos = (float)fmin(0.9, fmax(0.1, pc));
}

/* ---- light transport ---- */

static float mis(float a, float b) { return a * a / (a * a + b * b); }

static bool nonzero(const float *v) { return v[0] > 0 || v[1] > 0 || v[2] > 0; }

/* Adds beta f cos value w for light arriving along world wi from distance dist (INFINITY for
 * distant light) at surface s seen from wo (local), when nothing blocks it; pdf_l = 0 for delta
 * lights. */
static void add_light(const pt_job *j, const surface *s, const float wo[3], const float beta[3], const float wi[3], float dist,
                      const float value[3], float pdf_l, float *acc)
{
    float cl = prt__v3_dot(s->n, wi);
    if (!(cl > 0.0f) || prt__v3_dot(s->ng, wi) <= 0.0f) return;
    float wil[3], f[3];
    to_local(s, wi, wil);
    brdf_eval(j, s, wil, wo, f);
    if (!nonzero(f)) return;
    if (isfinite(dist)) {
        /* The shadow ray leaves from the offset origin and stops just short of the light's point,
         * so that an emitting triangle does not shadow itself. */
        float d[3];
        for (int c = 0; c < 3; ++c) d[c] = s->p[c] + wi[c] * dist - s->o[c];
        float len = prt__v3_len(d);
        if (len > 0.0f && prt__v3_normalize(d) && occluded(j, s->o, d, len * (1.0f - 1e-4f))) return;
    } else if (occluded(j, s->o, wi, INFINITY)) {
        return;
    }
    const float tr = media_transmittance(j, s->o, wi, dist);
    float w = pdf_l > 0.0f ? mis(pdf_l, (float)brdf_pdf(&j->mats[s->mat], wo, wil)) : 1.0f;
    for (int c = 0; c < 3; ++c) acc[c] += beta[c] * f[c] * cl * value[c] * w * tr;
}

/* Radiance that sphere lights add along o + t d for t < tmax, MIS-weighted against pdf_b (0 = no MIS). */
static void spheres_along(const pt_job *j, const float p[3], const float o[3], const float d[3], float tmax, float pdf_b, float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    for (int i = 0; i < j->light_count; ++i) {
        const prt_light *l = &j->lights[i];
        if (l->type != PRT_LIGHT_SPHERE || !(prt__sphere_light_hit(l, o, d) < tmax)) continue;
        float pl = prt__sphere_light_pdf(l, p), w = pdf_b > 0.0f && pl > 0.0f ? mis(pdf_b, pl) : 1.0f;
        for (int c = 0; c < 3; ++c) out[c] += l->radiance[c] * w;
    }
}

/* One path's exit radiance at surface s towards world direction wo_world, split into direct
 * (emission of s, and light that reaches s without bouncing) and indirect. */
static void path(const pt_job *j, const surface *start, const float wo_world[3], rng *r, float direct[3], float indirect[3])
{
    surface s = *start;
    float beta[3] = {1, 1, 1}, wo[3], dir[3] = {-wo_world[0], -wo_world[1], -wo_world[2]};   /* dir: the ray arriving at s */
    to_local(&s, wo_world, wo);
    direct[0] = direct[1] = direct[2] = indirect[0] = indirect[1] = indirect[2] = 0.0f;
    if (wo[2] <= 0.0f) return;   /* seen from behind: one-sided surfaces send nothing that way */
    for (int c = 0; c < 3; ++c) direct[c] += s.le[c];
    for (int depth = 0;; ++depth) {
        float *acc = depth == 0 ? direct : indirect;
        if (s.sp) {
            /* A mirror or glass: no light to sample (a delta BSDF), the path turns and whatever it
             * meets counts whole - next-event estimation could not have found it. */
            float nd[3], wgt, org[3], sph[3];
            const int side = prt__specular_scatter(s.sp, dir, s.ng, s.n, uniform(r), nd, &wgt);
            if (!side) break;
            for (int c = 0; c < 3; ++c) { beta[c] *= wgt; org[c] = s.p[c] + (float)side * j->offset * s.ng[c]; }
            surface next;
            const int hit = intersect(j, org, nd, &next);
            const float tr = media_transmittance(j, org, nd, hit ? next.dist : INFINITY);
            for (int c = 0; c < 3; ++c) beta[c] *= tr;
            spheres_along(j, s.p, org, nd, hit ? next.dist : INFINITY, 0.0f, sph);
            for (int c = 0; c < 3; ++c) acc[c] += beta[c] * sph[c];
            if (hit == 0) {
                if (j->has_env) {
                    float L[3];
                    prt__env_radiance(&j->env, nd, L);
                    for (int c = 0; c < 3; ++c) acc[c] += beta[c] * L[c];
                }
                break;
            }
            if (hit < 0) break;
            for (int c = 0; c < 3; ++c) acc[c] += beta[c] * next.le[c];
            if (depth + 1 >= j->max_depth) break;
            if (depth >= 2) {
                float q = fminf(fmaxf(beta[0], fmaxf(beta[1], beta[2])), 0.95f);
                if (!(q > 0.0f) || uniform(r) >= q) break;
                for (int c = 0; c < 3; ++c) beta[c] /= q;
            }
            wo[0] = -prt__v3_dot(nd, next.s); wo[1] = -prt__v3_dot(nd, next.t); wo[2] = -prt__v3_dot(nd, next.n);
            memcpy(dir, nd, sizeof dir);
            s = next;
            continue;
        }
        prt__light_sample ls;
        /* Next-event estimation: the environment, each local light, one emitter point. */
        if (j->has_env) {
            double u1 = uniform(r), u2 = uniform(r), u3 = uniform(r);
            float L[3];
            float pdf = prt__env_sample(&j->env, u1, u2, u3, ls.wi, L);
            if (pdf > 0.0f) {
                for (int c = 0; c < 3; ++c) ls.value[c] = L[c] / pdf;
                add_light(j, &s, wo, beta, ls.wi, INFINITY, ls.value, pdf, acc);
            }
        }
        for (int i = 0; i < j->light_count; ++i) {
            double u1 = uniform(r), u2 = uniform(r);
            if (prt__light_sample_from(&j->lights[i], s.p, u1, u2, &ls))
                add_light(j, &s, wo, beta, ls.wi, ls.dist, ls.value, ls.pdf, acc);
        }
        if (j->emit.count) {
            double u1 = uniform(r), u2 = uniform(r), u3 = uniform(r);
            if (prt__emitters_sample(&j->emit, j->mesh, s.p, u1, u2, u3, &ls))
                add_light(j, &s, wo, beta, ls.wi, ls.dist, ls.value, ls.pdf, acc);
        }
        /* Continue along a BRDF sample. */
        const pt_material *m = &j->mats[s.mat];
        float wil[3], wi[3], f[3];
        if (!brdf_sample(m, wo, r, wil)) break;
        to_world(&s, wil, wi);
        if (prt__v3_dot(s.ng, wi) <= 0.0f) break;   /* below the actual surface: no light from there */
        float pdf_b = (float)brdf_pdf(m, wo, wil);
        brdf_eval(j, &s, wil, wo, f);
        if (!(pdf_b > 0.0f) || !nonzero(f)) break;
        float weight[3];
        for (int c = 0; c < 3; ++c) weight[c] = beta[c] * f[c] * wil[2] / pdf_b;
        surface next;
        int hit = intersect(j, s.o, wi, &next);
        const float tr = media_transmittance(j, s.o, wi, hit ? next.dist : INFINITY);
        for (int c = 0; c < 3; ++c) weight[c] *= tr;
        float sph[3];
        spheres_along(j, s.p, s.o, wi, hit ? next.dist : INFINITY, pdf_b, sph);
        for (int c = 0; c < 3; ++c) acc[c] += weight[c] * sph[c];
        if (hit == 0) {
            if (j->has_env) {
                float L[3], pl = prt__env_pdf(&j->env, wi), w = mis(pdf_b, pl);
                prt__env_radiance(&j->env, wi, L);
                for (int c = 0; c < 3; ++c) acc[c] += weight[c] * L[c] * w;
            }
            break;
        }
        if (hit < 0) break;
        if (nonzero(next.le)) {
            /* The pdf with which next-event estimation would have picked this point. */
            float pl = prt__emitters_pdf(&j->emit, next.tri, next.dist, -prt__v3_dot(next.ng, wi)), w = mis(pdf_b, pl);
            for (int c = 0; c < 3; ++c) acc[c] += weight[c] * next.le[c] * w;
        }
        if (depth + 1 >= j->max_depth) break;
        for (int c = 0; c < 3; ++c) beta[c] = weight[c];
        if (depth >= 2) {   /* Russian roulette: survive with the throughput's largest channel */
            float q = fminf(fmaxf(beta[0], fmaxf(beta[1], beta[2])), 0.95f);
            if (!(q > 0.0f) || uniform(r) >= q) break;
            for (int c = 0; c < 3; ++c) beta[c] /= q;
        }
        wo[0] = -prt__v3_dot(wi, next.s); wo[1] = -prt__v3_dot(wi, next.t); wo[2] = -prt__v3_dot(wi, next.n);
        memcpy(dir, wi, sizeof dir);
        s = next;
    }
}

static void job_free(pt_job *j)
{
    prt__raycaster_release(&j->rc);
    if (j->has_env) prt__env_sampler_free(&j->env);
    prt__emitters_free(&j->emit);
    free(j->origins);
    free(j->spec);
}

static prt_status job_init(prt_context *ctx, const prt_scene *scene, const prt_envmap *env, const prt_reference_desc *d, pt_job *j)
{
    memset(j, 0, sizeof *j);
    if (!ctx || !scene) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: context and scene are required");
    if (d->lighting && env)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: with desc->lighting set, the env argument must be NULL (the lighting carries its environment)");
    if (!d->lighting && !env) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: an environment or desc->lighting is required");
    if (d->samples < 0 || d->max_samples < 0 || d->max_depth < 0 || !(d->target_rel_error >= 0) || !(d->intensity >= 0) ||
        !(d->ray_offset >= 0))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: negative or non-finite settings");
    if (d->eye && !(isfinite(d->eye[0]) && isfinite(d->eye[1]) && isfinite(d->eye[2])))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: the eye position must be finite");
    j->mesh = &scene->mesh;
    j->offset = d->ray_offset > 0 ? d->ray_offset : prt__ray_offset(j->mesh);
    j->max_depth = d->max_depth ? d->max_depth : 256;
    j->seed = d->seed;
    j->eye = d->eye;
    j->volumes = scene->volumes;
    j->volume_count = scene->volume_count;
    for (int k = 0; k < scene->volume_count; ++k) j->majorant += scene->volumes[k].sigma_t * scene->volumes[k].max_density;
    material_init(&j->mats[0], NULL);
    for (int k = 0; k < scene->brdf_count; ++k) material_init(&j->mats[k + 1], &scene->brdfs[k]);
    /* Without a lighting: the env argument, rotated and scaled, with the scene's emitters at scale 1. */
    const prt_envmap *e = env;
    double rot[9];
    const double *rp = d->rotation;
    float scale = d->intensity > 0 ? d->intensity : 1.0f, emission = 1.0f;
    if (d->lighting) {
        e = prt_lighting_envmap(d->lighting);
        prt_lighting_rotation(d->lighting, rot);
        rp = rot;
        scale = prt_lighting_intensity(d->lighting);
        j->light_count = prt_lighting_count(d->lighting);
        j->lights = prt_lighting_light(d->lighting, 0);
        emission = prt_lighting_emission(d->lighting);
    }
    prt_status st = PRT_OK;
    if (e) { st = prt__env_sampler_init(&j->env, e, rp, scale); j->has_env = !st; }
    if (!st) st = prt__emitters_init(&j->emit, j->mesh, emission);
    if (!st) st = prt__raycaster_create(ctx, j->mesh, &j->rc);
    if (!st) st = prt__specular_table(ctx, scene, j->mesh, &j->spec);
    if (!st) st = prt__vertex_origins(j->mesh, j->offset, &j->origins);
    /* The same origins as the bakes, so that comparisons are of the same points. */
    if (!st) st = prt__unbury_origins(ctx, &j->rc, j->mesh, j->offset, j->origins, NULL, PRT_LOG_DEBUG);
    if (st) job_free(j);
    return st;
}

void prt_reference_vertices_free(prt_reference_vertices *r)
{
    if (!r) return;
    free(r->radiance); free(r->direct); free(r->indirect); free(r->std_error); free(r->std_error_indirect); free(r->samples);
    memset(r, 0, sizeof *r);
}

/* Running sums for one vertex; double so that long runs stay exact enough. */
typedef struct moments { double sum[3], sq[3], ind[3], ind_sq[3], dir[3]; int n; } moments;

static void add_samples(const pt_job *j, const surface *s, const float wo[3], uint64_t item, int from, int to, moments *m)
{
    for (int k = from; k < to; ++k) {
        rng r = rng_for(j->seed, item, (uint32_t)k);
        float dl[3], il[3];
        path(j, s, wo, &r, dl, il);
        for (int c = 0; c < 3; ++c) {
            double v = (double)dl[c] + il[c];
            m->sum[c] += v; m->sq[c] += v * v;
            m->ind[c] += il[c]; m->ind_sq[c] += (double)il[c] * il[c];
            m->dir[c] += dl[c];
        }
    }
    m->n = to;
}

static double std_err(double sum, double sq, int n)
{
    if (n < 2) return INFINITY;
    double mean = sum / n, var = (sq / n - mean * mean) * n / (n - 1.0);
    return sqrt(fmax(var, 0.0) / n);
}

static bool converged(const moments *m, float target)
{
    double mean = (m->sum[0] + m->sum[1] + m->sum[2]) / (3.0 * m->n);
    double err = (std_err(m->sum[0], m->sq[0], m->n) + std_err(m->sum[1], m->sq[1], m->n) + std_err(m->sum[2], m->sq[2], m->n)) / 3.0;
    return mean <= 0.0 ? err < 1e-6 : err <= target * mean;
}

/* Vertex v as a path's first surface, and the direction its result is seen from. */
static void vertex_surface(const pt_job *j, size_t v, surface *s, float wo[3])
{
    const prt__mesh *m = j->mesh;
    memset(s, 0, sizeof *s);
    memcpy(s->p, m->positions + v * 3, sizeof s->p);
    memcpy(s->n, m->normals + v * 3, sizeof s->n);
    memcpy(s->ng, s->n, sizeof s->n);
    memcpy(s->rho, m->albedo + v * 3, sizeof s->rho);
    memcpy(s->o, j->origins + v * 3, sizeof s->o);
    s->mat = m->material[v];
    set_frame(s);
    if (j->emit.count && m->emission)
        for (int c = 0; c < 3; ++c) s->le[c] = j->emit.scale * m->emission[v * 3 + c];
    /* Only glossy vertices depend on the eye. A Lambertian one leaves the same radiance every way
     * its front faces, so it is seen along its normal: an eye behind it (a room's ceiling seen
     * from a camera above) must not turn it black. */
    const bool glossy = j->mats[s->mat].brdf && prt_brdf_is_glossy(j->mats[s->mat].brdf);
    if (j->eye && glossy) prt__v3_sub(j->eye, s->p, wo);
    if (!j->eye || !glossy || !prt__v3_normalize(wo)) memcpy(wo, s->n, 3 * sizeof(float));
}

prt_status prt_reference_trace_vertices(prt_context *ctx, const prt_scene *scene, const prt_envmap *env, const prt_reference_desc *desc,
                                        prt_reference_vertices *out)
{
    prt_reference_desc d = desc ? *desc : (prt_reference_desc){0};
    if (!out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: out is required");
    memset(out, 0, sizeof *out);
    pt_job j;
    prt_status st = job_init(ctx, scene, env, &d, &j);
    if (st) return st;
    const int first = d.samples ? d.samples : 256, cap = d.max_samples ? d.max_samples : 65536;
    const size_t nv = scene->mesh.vertex_count;
    moments *m = prt__calloc(nv, sizeof *m);
    out->vertex_count = nv;
    out->radiance = prt__calloc(nv * 3, sizeof(float)); out->direct = prt__calloc(nv * 3, sizeof(float));
    out->indirect = prt__calloc(nv * 3, sizeof(float)); out->std_error = prt__calloc(nv * 3, sizeof(float));
    out->std_error_indirect = prt__calloc(nv * 3, sizeof(float)); out->samples = prt__calloc(nv, sizeof(int));
    if (!m || !out->radiance || !out->direct || !out->indirect || !out->std_error || !out->std_error_indirect || !out->samples) {
        free(m); prt_reference_vertices_free(out); job_free(&j);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %zu reference vertices", nv);
    }
    prt__progress prog = {d.progress, d.progress_user, NULL, 0, 0, 0.0, 0, ctx};
    /* Batches double the sample count of the vertices that have not converged yet. A vertex's
     * k-th sample always uses stream (vertex, k), so batching never changes the result. */
    for (int target = first, pass = 0;; target *= 2, ++pass) {
        char stage[48];
        snprintf(stage, sizeof stage, pass ? "reference +%d" : "reference", target);
        prt__progress_begin(&prog, stage, nv);
        size_t pending = 0;
#pragma omp parallel for schedule(dynamic, 16) num_threads(prt__threads(ctx)) reduction(+ : pending)
        for (size_t v = 0; v < nv; ++v) {
            if (prt__progress_cancelled(&prog)) continue;
            if (pass == 0 || (!converged(&m[v], d.target_rel_error) && m[v].n < cap)) {
                surface s;
                float wo[3];
                vertex_surface(&j, v, &s, wo);
                add_samples(&j, &s, wo, v, m[v].n, target < cap ? target : cap, &m[v]);
                pending += !converged(&m[v], d.target_rel_error) && m[v].n < cap;
            }
            prt__progress_add(&prog, 1);
        }
        prt__progress_end(&prog);
        if (prt__progress_cancelled(&prog)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "reference cancelled"); break; }
        if (!(d.target_rel_error > 0) || pending == 0 || target >= cap) break;
    }
    for (size_t v = 0; v < nv && !st; ++v) {
        out->samples[v] = m[v].n;
        for (int c = 0; c < 3; ++c) {
            out->radiance[v * 3 + c] = (float)(m[v].sum[c] / m[v].n);
            out->direct[v * 3 + c] = (float)(m[v].dir[c] / m[v].n);
            out->indirect[v * 3 + c] = (float)(m[v].ind[c] / m[v].n);
            out->std_error[v * 3 + c] = (float)std_err(m[v].sum[c], m[v].sq[c], m[v].n);
            out->std_error_indirect[v * 3 + c] = (float)std_err(m[v].ind[c], m[v].ind_sq[c], m[v].n);
        }
    }
    free(m);
    job_free(&j);
    if (st) prt_reference_vertices_free(out);
    return st;
}

/* Radiance arriving at o from direction -d through the media (delta tracking against the
 * summed extinction's majorant; at each scattering the environment by next-event estimation
 * with its transmittance, then a Henyey-Greenstein turn, Russian roulette after 3). Where a
 * ray leaves the media at a surface, the surface's path (media as absorbers) takes over; a
 * camera ray that meets nothing shows the background, a scattered one nothing (the
 * environment came by next-event estimation). */
static void media_path(const pt_job *j, const float o_in[3], const float d_in[3], const float *background, rng *r, float out[3])
{
    float o[3] = {o_in[0], o_in[1], o_in[2]}, d[3] = {d_in[0], d_in[1], d_in[2]}, beta[3] = {1, 1, 1};
    out[0] = out[1] = out[2] = 0;
    for (int depth = 0; depth < j->max_depth; ++depth) {
        surface hit;
        const int h = intersect(j, o, d, &hit);
        const float ts = h ? hit.dist : INFINITY;
        /* The stretch of the ray inside any volume's box. */
        float a = INFINITY, b = -INFINITY;
        for (int q = 0; q < j->volume_count; ++q) {
            float t0, t1;
            if (prt__volume_clip(&j->volumes[q], o, d, ts, &t0, &t1)) { a = fminf(a, t0); b = fmaxf(b, t1); }
        }
        int scatter = -1;
        float x[3];
        if (j->majorant > 0 && b > a)
            for (float t = a;;) {
                t -= logf(1.0f - (float)uniform(r)) / j->majorant;
                if (t >= b) break;
                for (int c = 0; c < 3; ++c) x[c] = o[c] + t * d[c];
                float sig[64], total = 0;
                for (int q = 0; q < j->volume_count && q < 64; ++q) total += sig[q] = prt__volume_extinction(&j->volumes[q], x);
                float u = (float)uniform(r) * j->majorant;
                if (u >= total) continue;   /* a null collision */
                for (int q = 0; q < j->volume_count && q < 64 && scatter < 0; ++q) {
                    if (u < sig[q]) scatter = q;
                    u -= sig[q];
                }
                if (scatter < 0) scatter = j->volume_count - 1;
                break;
            }
        if (scatter < 0) {
            if (h > 0) {
                float dl[3], il[3], back[3] = {-d[0], -d[1], -d[2]};
                path(j, &hit, back, r, dl, il);
                for (int c = 0; c < 3; ++c) out[c] += beta[c] * (dl[c] + il[c]);
            } else if (h == 0 && depth == 0 && background) {
                for (int c = 0; c < 3; ++c) out[c] += background[c];
            }
            return;
        }
        const prt__volume *v = &j->volumes[scatter];
        for (int c = 0; c < 3; ++c) beta[c] *= v->albedo[c];
        if (j->has_env) {
            double u1 = uniform(r), u2 = uniform(r), u3 = uniform(r);
            float L[3], wi[3];
            const float pdf = prt__env_sample(&j->env, u1, u2, u3, wi, L);
            if (pdf > 0.0f && !occluded(j, x, wi, INFINITY)) {
                const float f = prt__hg_phase(v->g, prt__v3_dot(wi, d)) * media_transmittance(j, x, wi, INFINITY) / pdf;
                for (int c = 0; c < 3; ++c) out[c] += beta[c] * f * L[c];
            }
        }
        if (depth >= 3) {
            const float q = fminf(fmaxf(beta[0], fmaxf(beta[1], beta[2])), 0.95f);
            if (!(q > 0.0f) || uniform(r) >= q) return;
            for (int c = 0; c < 3; ++c) beta[c] /= q;
        }
        float nd[3];
        const double u1 = uniform(r), u2 = uniform(r);
        prt__hg_sample(v->g, d, u1, u2, nd);
        if (!prt__v3_normalize(nd)) return;
        memcpy(o, x, sizeof o);
        memcpy(d, nd, sizeof d);
    }
}

prt_status prt__reference_media_radiance(prt_context *ctx, const prt_scene *scene, const prt_reference_desc *desc, const float o[3], const float d[3],
                                         int samples, float out[3], float *std_error)
{
    prt_reference_desc dd = desc ? *desc : (prt_reference_desc){0};
    pt_job j;
    prt_status st = job_init(ctx, scene, NULL, &dd, &j);
    if (st) return st;
    float *v = malloc((size_t)(samples > 0 ? samples : 1) * 3 * sizeof *v);
    if (!v) { job_free(&j); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
    for (int k = 0; k < samples; ++k) {
        rng r = rng_for(j.seed, 0x5ca77e5ull, (uint32_t)k);
        media_path(&j, o, d, NULL, &r, v + (size_t)k * 3);
    }
    double sum[3] = {0, 0, 0}, sq = 0;   /* summed in sample order: the same for any thread count */
    for (int k = 0; k < samples; ++k) {
        for (int c = 0; c < 3; ++c) sum[c] += v[(size_t)k * 3 + c];
        sq += (double)v[(size_t)k * 3 + 1] * v[(size_t)k * 3 + 1];
    }
    free(v);
    for (int c = 0; c < 3; ++c) out[c] = (float)(sum[c] / samples);
    if (std_error) *std_error = (float)std_err(sum[1], sq, samples);
    job_free(&j);
    return PRT_OK;
}

prt_status prt_reference_trace_image(prt_context *ctx, const prt_scene *scene, const prt_envmap *env, const prt_reference_desc *desc,
                                     const prt_camera *cam, int width, int height, const float background[3], prt_image *out,
                                     prt_image *std_error)
{
    prt_reference_desc d = desc ? *desc : (prt_reference_desc){0};
    if (!out || !cam || width < 1 || height < 1 || width > 16384 || height > 16384)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: a camera and an image size in 1..16384 are required");
    memset(out, 0, sizeof *out);
    if (std_error) memset(std_error, 0, sizeof *std_error);
    pt_job j;
    prt_status st = job_init(ctx, scene, env, &d, &j);
    if (st) return st;
    const int spp = d.samples ? d.samples : 256;
    out->width = width; out->height = height;
    out->rgb = prt__calloc((size_t)width * height * 3, sizeof(float));
    float *err = prt__calloc((size_t)width * height * 3, sizeof(float));
    if (!out->rgb || !err) { free(err); prt_image_free(out); job_free(&j); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    prt__pinhole pin;
    prt__pinhole_init(cam, width, height, &pin);
    prt__progress prog = {d.progress, d.progress_user, NULL, 0, 0, 0.0, 0, ctx};
    prt__progress_begin(&prog, "reference image", (uint64_t)height);
#pragma omp parallel for schedule(dynamic, 1) num_threads(prt__threads(ctx))
    for (int y = 0; y < height; ++y) {
        if (prt__progress_cancelled(&prog)) continue;
        for (int x = 0; x < width; ++x) {
            double sum[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
            for (int k = 0; k < spp; ++k) {
                rng r = rng_for(j.seed, (uint64_t)y * width + x, (uint32_t)k);
                const float jx = (float)uniform(&r), jy = (float)uniform(&r);
                float dir[3];
                prt__pinhole_dir(&pin, (float)x + jx, (float)y + jy, dir);
                surface hit;
                float v[3] = {0, 0, 0}, back[3] = {-dir[0], -dir[1], -dir[2]};
                int h = j.volume_count ? 2 : intersect(&j, cam->eye, dir, &hit);
                if (h == 2) {
                    media_path(&j, cam->eye, dir, background, &r, v);
                    h = intersect(&j, cam->eye, dir, &hit);   /* for the sphere lights below */
                } else if (h == 0) {
                    if (background) memcpy(v, background, sizeof v);
                } else if (h > 0) {
                    float dl[3], il[3];
                    path(&j, &hit, back, &r, dl, il);
                    for (int c = 0; c < 3; ++c) v[c] = dl[c] + il[c];
                }
                float sph[3];   /* sphere lights in front of whatever the ray hit */
                spheres_along(&j, cam->eye, cam->eye, dir, h ? hit.dist : INFINITY, 0.0f, sph);
                for (int c = 0; c < 3; ++c) { v[c] += sph[c]; sum[c] += v[c]; sq[c] += (double)v[c] * v[c]; }
            }
            for (int c = 0; c < 3; ++c) {
                out->rgb[((size_t)y * width + x) * 3 + c] = (float)(sum[c] / spp);
                err[((size_t)y * width + x) * 3 + c] = (float)std_err(sum[c], sq[c], spp);
            }
        }
        prt__progress_add(&prog, 1);
    }
    prt__progress_end(&prog);
    job_free(&j);
    if (prt__progress_cancelled(&prog)) {
        free(err);
        prt_image_free(out);
        return prt__fail(ctx, PRT_ERR_CANCELLED, "reference cancelled");
    }
    if (std_error) { std_error->width = width; std_error->height = height; std_error->rgb = err; }
    else free(err);
    return PRT_OK;
}
