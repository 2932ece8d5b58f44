/* The reference path tracer (prt/reference.h). Each path starts at a surface point: the vertex
 * itself for per-vertex results, or the first hit of a camera ray. At every surface it samples
 * the environment (next-event estimation) and the cosine lobe, weighting both by the power
 * heuristic, then continues along the cosine sample with Russian roulette. */
#include "core/progress.h"
#include "geom/raycast.h"
#include "light/env_sample.h"

#include <string.h>

typedef struct pt_job {
    const prt__mesh *mesh;
    prt__raycaster rc;
    prt__env_sampler env;
    float offset;
    int max_depth;
    uint32_t seed;
    float *origins;   /* per vertex, as the bakes use them */
} pt_job;

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

static bool occluded(const pt_job *j, const float o[3], const float d[3])
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay r = {o[0], o[1], o[2], 0.0f, d[0], d[1], d[2], 0.0f, INFINITY, 0xFFFFFFFFu, 0, 0};
    rtcOccluded1(j->rc.scene, &ctx, &r);
    return r.tfar < 0.0f;
}

/* A surface point: position, shading and geometric normal, albedo, and the origin for rays
 * leaving it (offset to its front side). */
typedef struct surface { float p[3], n[3], ng[3], rho[3], o[3]; } surface;

/* Traces o + t d; fills the surface hit. Returns 0 on a miss, 1 on a front face, -1 on a back face. */
static int intersect(const pt_job *j, const float o[3], const float d[3], surface *s)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = o[0]; rh.ray.org_y = o[1]; rh.ray.org_z = o[2];
    rh.ray.dir_x = d[0]; rh.ray.dir_y = d[1]; rh.ray.dir_z = d[2];
    rh.ray.tfar = INFINITY;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(j->rc.scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return 0;
    float ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
    if (prt__v3_dot(ng, d) >= 0.0f) return -1;   /* Ng faces where the triangle winds counter-clockwise */
    prt__v3_normalize(ng);
    const prt__mesh *m = j->mesh;
    const uint32_t *t = m->indices + (size_t)rh.hit.primID * 3;
    float w0 = 1.0f - rh.hit.u - rh.hit.v, w1 = rh.hit.u, w2 = rh.hit.v;
    for (int c = 0; c < 3; ++c) {
        s->p[c] = o[c] + rh.ray.tfar * d[c];
        s->n[c] = w0 * m->normals[t[0] * 3 + c] + w1 * m->normals[t[1] * 3 + c] + w2 * m->normals[t[2] * 3 + c];
        s->rho[c] = w0 * m->albedo[t[0] * 3 + c] + w1 * m->albedo[t[1] * 3 + c] + w2 * m->albedo[t[2] * 3 + c];
        s->ng[c] = ng[c];
        s->o[c] = s->p[c] + ng[c] * j->offset;
    }
    /* A shading normal turned away from the viewer would light the surface from behind. */
    if (!prt__v3_normalize(s->n) || prt__v3_dot(s->n, d) >= 0.0f) memcpy(s->n, ng, sizeof ng);
    return 1;
}

/* One path's exit radiance at surface s, split into direct and indirect. */
static void path(const pt_job *j, const surface *start, rng *r, float direct[3], float indirect[3])
{
    surface s = *start;
    float beta[3] = {1, 1, 1};
    direct[0] = direct[1] = direct[2] = indirect[0] = indirect[1] = indirect[2] = 0.0f;
    for (int depth = 0;; ++depth) {
        float *acc = depth == 0 ? direct : indirect;
        const float *o = s.o;
        /* Next-event estimation towards the environment. */
        float wl[3], L[3];
        double u1 = uniform(r), u2 = uniform(r), u3 = uniform(r);
        float pdf_l = prt__env_sample(&j->env, u1, u2, u3, wl, L);
        float cl = prt__v3_dot(s.n, wl);
        if (pdf_l > 0.0f && cl > 0.0f && prt__v3_dot(s.ng, wl) > 0.0f && !occluded(j, o, wl)) {
            float pdf_b = cl / (float)PRT_PI, w = pdf_l * pdf_l / (pdf_l * pdf_l + pdf_b * pdf_b);
            for (int c = 0; c < 3; ++c) acc[c] += beta[c] * s.rho[c] / (float)PRT_PI * cl * L[c] / pdf_l * w;
        }
        /* Cosine-weighted continuation. */
        float t[3], b[3], wb[3];
        basis(s.n, t, b);
        double a = uniform(r), phi = 2.0 * PRT_PI * uniform(r), rad = sqrt(a);
        float x = (float)(rad * cos(phi)), y = (float)(rad * sin(phi)), z = (float)sqrt(fmax(0.0, 1.0 - a));
        for (int c = 0; c < 3; ++c) wb[c] = x * t[c] + y * b[c] + z * s.n[c];
        if (prt__v3_dot(s.ng, wb) <= 0.0f) break;   /* below the actual surface: no light from there */
        surface next;
        int hit = intersect(j, o, wb, &next);
        if (hit == 0) {
            float pdf_b = z / (float)PRT_PI, pl = prt__env_pdf(&j->env, wb), w = pdf_b * pdf_b / (pdf_b * pdf_b + pl * pl);
            prt__env_radiance(&j->env, wb, L);
            for (int c = 0; c < 3; ++c) acc[c] += beta[c] * s.rho[c] * L[c] * w;   /* rho/pi cos L / (cos/pi) */
            break;
        }
        if (hit < 0 || depth + 1 >= j->max_depth) break;
        for (int c = 0; c < 3; ++c) beta[c] *= s.rho[c];
        if (depth >= 2) {   /* Russian roulette: survive with the throughput's largest channel */
            float q = fminf(fmaxf(beta[0], fmaxf(beta[1], beta[2])), 0.95f);
            if (!(q > 0.0f) || uniform(r) >= q) break;
            for (int c = 0; c < 3; ++c) beta[c] /= q;
        }
        s = next;
    }
}

static prt_status job_init(prt_context *ctx, const prt_scene *scene, const prt_envmap *env, const prt_reference_desc *d, pt_job *j)
{
    memset(j, 0, sizeof *j);
    if (!ctx || !scene || !env) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: context, scene and environment are required");
    if (d->samples < 0 || d->max_samples < 0 || d->max_depth < 0 || !(d->target_rel_error >= 0) || !(d->intensity >= 0) ||
        !(d->ray_offset >= 0))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "reference: negative or non-finite settings");
    j->mesh = &scene->mesh;
    j->offset = d->ray_offset > 0 ? d->ray_offset : prt__ray_offset(j->mesh);
    j->max_depth = d->max_depth ? d->max_depth : 256;
    j->seed = d->seed;
    prt_status st = prt__env_sampler_init(&j->env, env, d->rotation, d->intensity > 0 ? d->intensity : 1.0f);
    if (!st) st = prt__raycaster_create(ctx, j->mesh, &j->rc);
    if (!st) st = prt__vertex_origins(j->mesh, j->offset, &j->origins);
    if (st) { prt__raycaster_release(&j->rc); prt__env_sampler_free(&j->env); }
    return st;
}

static void job_free(pt_job *j)
{
    prt__raycaster_release(&j->rc);
    prt__env_sampler_free(&j->env);
    free(j->origins);
}

void prt_reference_vertices_free(prt_reference_vertices *r)
{
    if (!r) return;
    free(r->radiance); free(r->direct); free(r->indirect); free(r->std_error); free(r->std_error_indirect); free(r->samples);
    memset(r, 0, sizeof *r);
}

/* Running sums for one vertex; double so that long runs stay exact enough. */
typedef struct moments { double sum[3], sq[3], ind[3], ind_sq[3], dir[3]; int n; } moments;

static void add_samples(const pt_job *j, const surface *s, uint64_t item, int from, int to, moments *m)
{
    for (int k = from; k < to; ++k) {
        rng r = rng_for(j->seed, item, (uint32_t)k);
        float dl[3], il[3];
        path(j, s, &r, dl, il);
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
    prt__progress prog = {d.progress, d.progress_user, NULL, 0, 0, 0.0, 0};
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
                memcpy(s.p, scene->mesh.positions + v * 3, sizeof s.p);
                memcpy(s.n, scene->mesh.normals + v * 3, sizeof s.n);
                memcpy(s.ng, s.n, sizeof s.n);
                memcpy(s.rho, scene->mesh.albedo + v * 3, sizeof s.rho);
                memcpy(s.o, j.origins + v * 3, sizeof s.o);
                add_samples(&j, &s, v, m[v].n, target < cap ? target : cap, &m[v]);
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
    float f[3], s[3], u[3], up[3] = {cam->up[0], cam->up[1], cam->up[2]};
    if (up[0] == 0 && up[1] == 0 && up[2] == 0) up[1] = 1;
    prt__v3_sub(cam->target, cam->eye, f);
    prt__v3_normalize(f);
    prt__v3_cross(f, up, s);
    prt__v3_normalize(s);
    prt__v3_cross(s, f, u);
    const float th = tanf(0.5f * (cam->fov_y_deg > 0 ? cam->fov_y_deg : 40.0f) * (float)PRT_PI / 180.0f), aspect = (float)width / height;
    prt__progress prog = {d.progress, d.progress_user, NULL, 0, 0, 0.0, 0};
    prt__progress_begin(&prog, "reference image", (uint64_t)height);
#pragma omp parallel for schedule(dynamic, 1) num_threads(prt__threads(ctx))
    for (int y = 0; y < height; ++y) {
        if (prt__progress_cancelled(&prog)) continue;
        for (int x = 0; x < width; ++x) {
            double sum[3] = {0, 0, 0}, sq[3] = {0, 0, 0};
            for (int k = 0; k < spp; ++k) {
                rng r = rng_for(j.seed, (uint64_t)y * width + x, (uint32_t)k);
                float px = (2.0f * (x + (float)uniform(&r)) / width - 1.0f) * th * aspect;
                float py = (1.0f - 2.0f * (y + (float)uniform(&r)) / height) * th;
                float dir[3] = {f[0] + px * s[0] + py * u[0], f[1] + px * s[1] + py * u[1], f[2] + px * s[2] + py * u[2]};
                prt__v3_normalize(dir);
                surface hit;
                float v[3] = {0, 0, 0};
                int h = intersect(&j, cam->eye, dir, &hit);
                if (h == 0) {
                    if (background) memcpy(v, background, sizeof v);
                } else if (h > 0) {
                    float dl[3], il[3];
                    path(&j, &hit, &r, dl, il);
                    for (int c = 0; c < 3; ++c) v[c] = dl[c] + il[c];
                }
                for (int c = 0; c < 3; ++c) { sum[c] += v[c]; sq[c] += (double)v[c] * v[c]; }
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
