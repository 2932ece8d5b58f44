/* SH PRT for diffuse surfaces (Sloan, Kautz & Snyder 2002; Kautz course notes): per vertex
 *   unshadowed   T_i = 1/pi  integral max(n.s, 0) y_i(s) ds
 *   shadowed     T_i = 1/pi  integral V(s) max(n.s, 0) y_i(s) ds
 *   bounce b     T^b_i = rho/pi integral T^{b-1}_i(q(s)) (1 - V(s)) max(n.s, 0) ds
 * estimated with one shared low-discrepancy direction set of N directions (weight 4 pi / N).
 * The glossy shadowed matrix M_ji = integral V(s) H(n.s) y_j(s) y_i(s) ds shares the rays; glossy
 * bounces live in sh_glossy.c.
 * Every vertex's result depends only on its own inputs and the fixed direction set, so the
 * result is bit-identical for any thread count and schedule. */
#include "bake/bake_internal.h"
#include "geom/raycast.h"

#include <string.h>

#define PACKET 16

typedef prt__hit hit_entry;

typedef struct bake_job {
    const prt__mesh *mesh;
    int order, ncoeff, samples;
    float offset;
    float *origins;       /* [vertex][3], see prt__vertex_origins */
    float *dirs;          /* [samples][3] */
    float *basis;         /* [samples][ncoeff] */
    prt__raycaster rc;
    bool need_hits;
    hit_entry **hits;     /* per vertex, for interreflection */
    uint32_t *hit_count;
    prt__progress progress;
} bake_job;

prt_bake_desc prt_bake_desc_defaults(void)
{
    prt_bake_desc d = {0};
    d.order = 5;
    d.samples = 1024;
    d.kinds = PRT_TRANSFER_UNSHADOWED | PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED;
    d.bounces = 3;
    return d;
}

/* Visibility pass for one vertex: fills the unshadowed and shadowed sums and, when needed, the
 * list of occluded directions with what they hit. Returns false on allocation failure. */
static bool visibility_vertex(bake_job *job, size_t v, float *unsh, float *sh, float *glossy, hit_entry *scratch,
                              hit_entry **hits_out, uint32_t *nhits_out)
{
    const prt__mesh *m = job->mesh;
    const float *n = m->normals + v * 3;
    const float w = (float)(4.0 * PRT_PI / job->samples) / (float)PRT_PI;   /* 4pi/N and the 1/pi of the BRDF */
    const int nc = job->ncoeff;
    const float *org = job->origins + v * 3;
    uint32_t nhits = 0;   /* scratch holds one entry per sample, so it never overflows */
    int lane_sample[PACKET];
    float lane_cos[PACKET];
    int j = 0;
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    while (j < job->samples) {
        int lanes = 0;
        for (; j < job->samples && lanes < PACKET; ++j) {
            float c = prt__v3_dot(job->dirs + (size_t)j * 3, n);
            if (c <= 0.0f) continue;
            lane_sample[lanes] = j;
            lane_cos[lanes] = c;
            lanes++;
        }
        if (!lanes) break;
        _Alignas(64) int valid[PACKET];   /* Embree reads the mask with aligned 512-bit loads */
        bool blocked[PACKET];
        if (job->need_hits) {
            _Alignas(64) struct RTCRayHit16 rh;
            prt__packet_rayhits(&rh, valid, org, job->dirs, lane_sample, lanes);
            rtcIntersect16(valid, job->rc.scene, &ictx, &rh);
            for (int k = 0; k < lanes; ++k) {
                blocked[k] = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                if (!blocked[k]) continue;
                /* Embree's unnormalized Ng points to the side from which the triangle winds
                 * counter-clockwise, like prt's normals (the pit and colour-bleeding tests pin
                 * this). The back of a surface emits nothing: only front-face hits carry light. */
                const float *d = job->dirs + (size_t)lane_sample[k] * 3;
                if (rh.hit.Ng_x[k] * d[0] + rh.hit.Ng_y[k] * d[1] + rh.hit.Ng_z[k] * d[2] >= 0.0f) continue;
                scratch[nhits++] = (hit_entry){rh.hit.primID[k], (uint32_t)lane_sample[k], rh.hit.u[k], rh.hit.v[k],
                                               lane_cos[k] * (float)(4.0 * PRT_PI / job->samples)};
            }
        } else {
            _Alignas(64) struct RTCRay16 r;
            prt__packet_rays(&r, valid, org, job->dirs, lane_sample, lanes);
            rtcOccluded16(valid, job->rc.scene, &ictx, &r);
            for (int k = 0; k < lanes; ++k) blocked[k] = r.tfar[k] < 0.0f;
        }
        for (int k = 0; k < lanes; ++k) {
            const float *y = job->basis + (size_t)lane_sample[k] * nc;
            float c = lane_cos[k] * w;
            if (unsh)
                for (int i = 0; i < nc; ++i) unsh[i] += c * y[i];
            if (sh && !blocked[k])
                for (int i = 0; i < nc; ++i) sh[i] += c * y[i];
            if (glossy && !blocked[k]) {
                const float wg = (float)(4.0 * PRT_PI / job->samples);
                for (int j = 0; j < nc; ++j) {
                    float s = wg * y[j];
                    for (int i = 0; i < nc; ++i) glossy[j * nc + i] += s * y[i];
                }
            }
        }
    }
    if (hits_out) {
        *nhits_out = nhits;
        *hits_out = NULL;
        if (nhits) {
            *hits_out = malloc(nhits * sizeof(hit_entry));
            if (!*hits_out) return false;
            memcpy(*hits_out, scratch, nhits * sizeof(hit_entry));
        }
    }
    return true;
}

/* Interpolates a 3-channel transfer at a hit point. */
static inline void gather_hit(const prt__mesh *m, const float *prev, int nc3, const hit_entry *h, float *acc)
{
    const uint32_t *t = m->indices + (size_t)h->prim * 3;
    float b0 = (1.0f - h->u - h->v) * h->weight, b1 = h->u * h->weight, b2 = h->v * h->weight;
    const float *t0 = prev + (size_t)t[0] * nc3, *t1 = prev + (size_t)t[1] * nc3, *t2 = prev + (size_t)t[2] * nc3;
    for (int i = 0; i < nc3; ++i) acc[i] += b0 * t0[i] + b1 * t1[i] + b2 * t2[i];
}

prt_status prt_bake_sh(prt_context *ctx, const prt_scene *scene, const prt_bake_desc *desc_in, prt_transfer **out)
{
    if (!ctx || !scene || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake_sh: ctx, scene and out are required");
    *out = NULL;
    prt_bake_desc d = desc_in ? *desc_in : (prt_bake_desc){0};
    prt_bake_desc def = prt_bake_desc_defaults();
    if (d.order == 0) d.order = def.order;
    if (d.samples == 0) d.samples = def.samples;
    if (d.kinds == 0) d.kinds = def.kinds;
    if (d.bounces == 0) d.bounces = def.bounces;
    if (d.order < 1 || d.order > PRT_SH_MAX_ORDER)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "SH order %d out of range 1..%d", d.order, PRT_SH_MAX_ORDER);
    if (d.samples < 16 || d.samples > (1 << 20))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "samples %d out of range 16..%d", d.samples, 1 << 20);
    if (d.bounces < 1 || d.bounces > 64) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range 1..64", d.bounces);
    if (d.kinds & ~PRT_TRANSFER_ALL_KINDS) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "unknown transfer kind bits 0x%x", d.kinds);
    if (d.glossy_brdf) {
        prt_status bst = prt_brdf_validate(d.glossy_brdf);
        if (bst) return prt__fail(ctx, bst, "glossy BRDF: %s", prt_last_error());
        if (!d.glossy_exit) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a glossy BRDF at bake time needs glossy_exit (it is baked in)");
    }
    if (d.texels < 0 || d.texels > 8192) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "texels %d out of range 0..8192", d.texels);
    if (d.normal_map && !d.texels) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a normal map needs per-texel transfer (texels > 0)");
    if (d.normal_map && (d.normal_map->width < 1 || d.normal_map->height < 1 || !d.normal_map->rgb))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the normal map is empty");
    if (d.glossy_exit && !(d.kinds & (PRT_TRANSFER_GLOSSY_SHADOWED | PRT_TRANSFER_GLOSSY_INTERREFLECTED)))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "baking a BRDF in needs a glossy kind (glossy-shadowed or glossy-interreflected)");

    if (d.ray_offset < 0 || !isfinite(d.ray_offset)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ray offset must be >= 0");

    double t_start = prt__now();
    prt_transfer *t = prt__calloc(1, sizeof *t);
    if (!t) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const prt__mesh *sm = &scene->mesh;
    prt_status st = prt__mesh_copy(&t->mesh, sm);
    if (st) { prt_transfer_release(t); return st; }
    t->order = d.order;
    t->samples = d.samples;
    t->bounces = (d.kinds & (PRT_TRANSFER_INTERREFLECTED | PRT_TRANSFER_GLOSSY_INTERREFLECTED)) ? d.bounces : 0;
    t->seed = d.seed;
    t->threads = prt__threads(ctx);
    snprintf(t->source, sizeof t->source, "%s", scene->source);
    t->has_env = scene->has_env;
    t->env = scene->env;
    t->brdf_count = scene->brdf_count;
    memcpy(t->brdfs, scene->brdfs, sizeof t->brdfs);
    bool scene_glossy = false;   /* some vertex has a material with a glossy part */
    for (size_t v = 0; v < t->mesh.vertex_count && !scene_glossy; ++v) {
        uint8_t k = t->mesh.material[v];
        scene_glossy = k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1]);
    }
    const bool want_gsh = d.kinds & PRT_TRANSFER_GLOSSY_SHADOWED, want_gir = d.kinds & PRT_TRANSFER_GLOSSY_INTERREFLECTED;
    const bool want_ir = d.kinds & (PRT_TRANSFER_INTERREFLECTED | PRT_TRANSFER_GLOSSY_INTERREFLECTED);
    /* Glossy surfaces in the scene or glossy receivers put the glossy matrices into the bounce loop. */
    const bool coupled = want_ir && (want_gir || scene_glossy);
    const bool need_glossy_sh = want_gsh || coupled;

    const size_t nv = t->mesh.vertex_count;
    bake_job job = {0};
    job.mesh = &t->mesh;
    job.order = d.order;
    job.ncoeff = d.order * d.order;
    job.samples = d.samples;
    job.offset = d.ray_offset > 0 ? d.ray_offset : prt__ray_offset(&t->mesh);
    job.need_hits = want_ir;
    job.progress.fn = d.progress;
    job.progress.user = d.progress_user;
    const int nc = job.ncoeff;
    bool want_unsh = d.kinds & PRT_TRANSFER_UNSHADOWED;
    bool want_sh = d.kinds & (PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED | PRT_TRANSFER_GLOSSY_INTERREFLECTED);
    const size_t nn = (size_t)nc * nc;

    job.dirs = prt__calloc((size_t)d.samples * 3, sizeof(float));
    job.basis = prt__calloc((size_t)d.samples * nc, sizeof(float));
    float *unsh = want_unsh ? prt__calloc(nv * nc, sizeof(float)) : NULL;
    float *shad = want_sh ? prt__calloc(nv * nc, sizeof(float)) : NULL;
    float *gshad = need_glossy_sh ? prt__calloc(nv * nn, sizeof(float)) : NULL;
    if (job.need_hits) {
        job.hits = prt__calloc(nv, sizeof *job.hits);
        job.hit_count = prt__calloc(nv, sizeof *job.hit_count);
    }
    if (!job.dirs || !job.basis || (want_unsh && !unsh) || (want_sh && !shad) || (need_glossy_sh && !gshad) || (job.need_hits && (!job.hits || !job.hit_count))) {
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for a bake of %zu vertices", nv);
        goto done;
    }
    for (int j = 0; j < d.samples; ++j) {
        double u, v, dir[3], y[PRT_SH_MAX_COEFFS];
        prt__sobol2((uint32_t)j, d.seed, &u, &v);
        prt__sphere_dir(u, v, dir);
        prt_sh_eval(d.order, dir, y);
        for (int c = 0; c < 3; ++c) job.dirs[(size_t)j * 3 + c] = (float)dir[c];
        for (int i = 0; i < nc; ++i) job.basis[(size_t)j * nc + i] = (float)y[i];
    }
    if ((st = prt__raycaster_create(ctx, &t->mesh, &job.rc))) goto done;
    if ((st = prt__vertex_origins(&t->mesh, job.offset, &job.origins))) goto done;

    int alloc_failed = 0;
    prt__progress_begin(&job.progress, "visibility", nv);
#pragma omp parallel num_threads(prt__threads(ctx))
    {
        hit_entry *scratch = job.need_hits ? malloc((size_t)d.samples * sizeof(hit_entry)) : NULL;
        if (job.need_hits && !scratch) __atomic_store_n(&alloc_failed, 1, __ATOMIC_RELAXED);
#pragma omp for schedule(dynamic, 32)
        for (size_t v = 0; v < nv; ++v) {
            if (prt__progress_cancelled(&job.progress) || __atomic_load_n(&alloc_failed, __ATOMIC_RELAXED)) continue;
            bool ok = visibility_vertex(&job, v, unsh ? unsh + v * nc : NULL, shad ? shad + v * nc : NULL,
                                        gshad ? gshad + v * nn : NULL, scratch,
                                        job.need_hits ? &job.hits[v] : NULL, job.need_hits ? &job.hit_count[v] : NULL);
            if (!ok) __atomic_store_n(&alloc_failed, 1, __ATOMIC_RELAXED);
            prt__progress_add(&job.progress, 1);
        }
        free(scratch);
    }
    prt__progress_end(&job.progress);
    if (alloc_failed) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory recording ray hits"); goto done; }
    if (prt__progress_cancelled(&job.progress)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled"); goto done; }

    if (want_unsh) { t->sets[0].channels = 1; t->sets[0].coeffs = unsh; unsh = NULL; }
    if (coupled) {
        prt__bounce_input bi = {&t->mesh, d.order, d.samples, job.basis, job.hits, job.hit_count, shad, gshad,
                                t->brdfs, t->brdf_count, d.bounces, want_gir, &job.progress};
        float *dtot = NULL, *gtot = NULL;
        if ((st = prt__bake_glossy_bounces(ctx, &bi, &dtot, want_gir ? &gtot : NULL))) goto done;
        if (d.kinds & PRT_TRANSFER_INTERREFLECTED) { t->sets[2].channels = 3; t->sets[2].coeffs = dtot; }
        else free(dtot);
        if (want_gir) { t->sets[4].channels = 3; t->sets[4].coeffs = gtot; }
    } else if (d.kinds & PRT_TRANSFER_INTERREFLECTED) {
        const int nc3 = 3 * nc;
        float *total = prt__calloc(nv * nc3, sizeof(float)), *prev = prt__calloc(nv * nc3, sizeof(float)),
              *next = prt__calloc(nv * nc3, sizeof(float));
        if (!total || !prev || !next) {
            free(total); free(prev); free(next);
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for interreflection");
            goto done;
        }
        /* Bounce 0 is the shadowed transfer times the (coloured) albedo. */
        for (size_t v = 0; v < nv; ++v)
            for (int c = 0; c < 3; ++c)
                for (int i = 0; i < nc; ++i)
                    prev[v * nc3 + c * nc + i] = total[v * nc3 + c * nc + i] = t->mesh.albedo[v * 3 + c] * shad[v * nc + i];
        char stage[32];
        for (int b = 1; b <= d.bounces; ++b) {
            snprintf(stage, sizeof stage, "bounce %d/%d", b, d.bounces);
            prt__progress_begin(&job.progress, stage, nv);
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
            for (size_t v = 0; v < nv; ++v) {
                if (prt__progress_cancelled(&job.progress)) continue;
                float acc[3 * PRT_SH_MAX_COEFFS];
                memset(acc, 0, (size_t)nc3 * sizeof(float));
                for (uint32_t h = 0; h < job.hit_count[v]; ++h) gather_hit(&t->mesh, prev, nc3, &job.hits[v][h], acc);
                for (int c = 0; c < 3; ++c) {
                    float k = t->mesh.albedo[v * 3 + c] / (float)PRT_PI;
                    for (int i = 0; i < nc; ++i) {
                        float x = k * acc[c * nc + i];
                        next[v * nc3 + c * nc + i] = x;
                        total[v * nc3 + c * nc + i] += x;
                    }
                }
                if ((v & 255) == 0) prt__progress_add(&job.progress, 256);
            }
            prt__progress_end(&job.progress);
            float *tmp = prev; prev = next; next = tmp;
            if (prt__progress_cancelled(&job.progress)) break;
        }
        free(prev); free(next);
        if (prt__progress_cancelled(&job.progress)) { free(total); st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled"); goto done; }
        t->sets[2].channels = 3;
        t->sets[2].coeffs = total;
    }
    if (d.kinds & PRT_TRANSFER_SHADOWED) { t->sets[1].channels = 1; t->sets[1].coeffs = shad; shad = NULL; }
    if (want_gsh) { t->sets[3].channels = 1; t->sets[3].coeffs = gshad; gshad = NULL; }
    if (d.texels) {
        prt__texel_input ti = {&t->mesh, t->source, d.order, d.samples, job.dirs, job.basis, job.rc.scene, job.offset,
                               t->sets[2].coeffs, d.kinds & 7u, d.texels, d.texels, d.normal_map, &job.progress};
        if ((st = prt__bake_texels(ctx, &ti, &t->texels))) goto done;
    }
    if (d.glossy_exit && (st = prt__bake_brdf_in(ctx, t, d.glossy_brdf))) goto done;
    t->bake_seconds = prt__now() - t_start;

done:
    prt__raycaster_release(&job.rc);
    if (job.hits)
        for (size_t v = 0; v < nv; ++v) free(job.hits[v]);
    free(job.hits); free(job.hit_count); free(job.origins); free(job.dirs); free(job.basis); free(unsh); free(shad); free(gshad);
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}
