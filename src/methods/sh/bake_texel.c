/* Per-texel SH transfer over the mesh's UV layout (Sloan et al. 2002, section 8; Kautz's course
 * notes on normal-mapped PRT). Every texel centre a triangle covers in UV space gets a surface
 * point, a shading normal perturbed by the tangent-space normal map, and the same transfer
 * integrals the vertices get. Inter-reflected texels gather the per-vertex inter-reflected
 * transfer at their ray hits (one final gather), so texels inherit the vertices' bounces. */
#include "methods/sh/bake.h"
#include "geom/texel_raster.h"
#include "geom/raycast.h"

#include <string.h>

#define PACKET 16

typedef struct texel_job {
    const prt__texel_input *in;
    const prt__mesh *m;
    int nc;
    uint32_t *owner;      /* [texel] triangle + 1, 0 = not covered */
    float *bary;          /* [texel][2] */
    prt__texel_sets *out;
} texel_job;

/* Bilinear lookup of the normal map at uv, wrapping like a repeating texture. */
static void normal_map_at(const prt_image *img, float u, float v, float out[3])
{
    float x = (u - floorf(u)) * img->width - 0.5f, y = (1.0f - (v - floorf(v))) * img->height - 0.5f;   /* image row 0 is the top */
    int x0 = (int)floorf(x), y0 = (int)floorf(y);
    float fx = x - x0, fy = y - y0;
    out[0] = out[1] = out[2] = 0;
    for (int k = 0; k < 4; ++k) {
        int xi = x0 + (k & 1), yi = y0 + (k >> 1);
        xi = ((xi % img->width) + img->width) % img->width;
        yi = ((yi % img->height) + img->height) % img->height;
        float w = ((k & 1) ? fx : 1 - fx) * ((k >> 1) ? fy : 1 - fy);
        for (int c = 0; c < 3; ++c) out[c] += w * img->rgb[((size_t)yi * img->width + xi) * 3 + c];
    }
    for (int c = 0; c < 3; ++c) out[c] = 2.0f * out[c] - 1.0f;
}

/* Point, geometric normal and shading normal of one covered texel, and the height field's frame
 * there (bump->len_u = 0 when there is none); false if degenerate. */
static bool texel_surface(const texel_job *job, size_t texel, float p[3], float ng[3], float ns[3], float *albedo, prt__bump_frame *bump)
{
    const prt__mesh *m = job->m;
    const uint32_t tri = job->owner[texel] - 1, *ix = m->indices + (size_t)tri * 3;
    const float b1 = job->bary[texel * 2], b2 = job->bary[texel * 2 + 1], b0 = 1.0f - b1 - b2;
    const float *p0 = m->positions + ix[0] * 3, *p1 = m->positions + ix[1] * 3, *p2 = m->positions + ix[2] * 3;
    float e1[3], e2[3];
    prt__v3_sub(p1, p0, e1);
    prt__v3_sub(p2, p0, e2);
    prt__v3_cross(e1, e2, ng);
    if (!prt__v3_normalize(ng)) return false;
    for (int c = 0; c < 3; ++c) {
        p[c] = b0 * p0[c] + b1 * p1[c] + b2 * p2[c];
        ns[c] = b0 * m->normals[ix[0] * 3 + c] + b1 * m->normals[ix[1] * 3 + c] + b2 * m->normals[ix[2] * 3 + c];
        albedo[c] = b0 * m->albedo[ix[0] * 3 + c] + b1 * m->albedo[ix[1] * 3 + c] + b2 * m->albedo[ix[2] * 3 + c];
    }
    if (!prt__v3_normalize(ns)) memcpy(ns, ng, 3 * sizeof(float));
    if (prt__v3_dot(ng, ns) < 0) for (int c = 0; c < 3; ++c) ng[c] = -ng[c];   /* the side the shading normal faces */
    const prt_image *nm = job->in->normal_map;
    const prt__height_field *hf = job->in->bumps;
    bump->len_u = 0;
    if (nm || hf) {
        /* Tangent frame from the triangle's UV gradients (dP/du, dP/dv, and the sign of the UV map). */
        const float *t0 = m->uv + ix[0] * 2, *t1 = m->uv + ix[1] * 2, *t2 = m->uv + ix[2] * 2;
        float du1 = t1[0] - t0[0], dv1 = t1[1] - t0[1], du2 = t2[0] - t0[0], dv2 = t2[1] - t0[1];
        float det = du1 * dv2 - du2 * dv1;
        if (det != 0.0f) {
            float tan[3], bit[3], pv[3];
            for (int c = 0; c < 3; ++c) { tan[c] = (e1[c] * dv2 - e2[c] * dv1) / det; pv[c] = (e2[c] * du1 - e1[c] * du2) / det; }
            const float len_u = sqrtf(prt__v3_dot(tan, tan)), len_v = sqrtf(prt__v3_dot(pv, pv));
            float d = prt__v3_dot(tan, ns);
            for (int c = 0; c < 3; ++c) tan[c] -= d * ns[c];
            if (prt__v3_normalize(tan)) {
                prt__v3_cross(ns, tan, bit);
                if (det < 0) for (int c = 0; c < 3; ++c) bit[c] = -bit[c];
                const float u = b0 * t0[0] + b1 * t1[0] + b2 * t2[0], v = b0 * t0[1] + b1 * t1[1] + b2 * t2[1];
                if (hf && len_u > 0 && len_v > 0) {
                    memcpy(bump->t, tan, sizeof tan);
                    memcpy(bump->b, bit, sizeof bit);
                    memcpy(bump->n, ns, sizeof bump->n);
                    bump->u = u;
                    bump->v = v;
                    bump->len_u = len_u;
                    bump->len_v = len_v;
                }
                float n2[3];
                if (nm) {
                    float t[3];
                    normal_map_at(nm, u, v, t);
                    for (int c = 0; c < 3; ++c) n2[c] = t[0] * tan[c] + t[1] * bit[c] + t[2] * ns[c];
                    if (prt__v3_normalize(n2)) memcpy(ns, n2, sizeof n2);
                } else if (bump->len_u > 0) {
                    prt__height_normal(hf, bump, n2);   /* without a normal map, the bumps' own slopes shade */
                    memcpy(ns, n2, sizeof n2);
                }
            }
        }
    }
    return true;
}

/* The transfer of one texel: unshadowed and shadowed sums, and the inter-reflected one (3 ch). */
static bool texel_bake(const texel_job *job, size_t texel, float *unsh, float *shad, float *ir)
{
    const prt__texel_input *in = job->in;
    const prt__mesh *m = job->m;
    const int nc = job->nc;
    float p[3], ng[3], ns[3], rho[3];
    prt__bump_frame bump;
    if (!texel_surface(job, texel, p, ng, ns, rho, &bump)) return true;
    const prt__height_field *hf = bump.len_u > 0 ? in->bumps : NULL;
    /* A direction the bumps block meets the surface around the texel, lit as the surface is:
     * the texel's own triangle's inter-reflected transfer stands for what the bump sends back. */
    const uint32_t *own = m->indices + (size_t)(job->owner[texel] - 1) * 3;
    const float ob1 = job->bary[texel * 2], ob2 = job->bary[texel * 2 + 1], own_w[3] = {1.0f - ob1 - ob2, ob1, ob2};
    float org[3];
    for (int c = 0; c < 3; ++c) org[c] = p[c] + ng[c] * in->offset;
    /* A sample inside geometry (a scan folded through itself, a prop sunk into the floor) is left
     * unbaked: the gutter fill gives it its neighbours' transfer, as vertices get theirs. */
    const prt__raycaster rc = {in->scene};
    if (prt__origin_back_share(&rc, org, ng) > 0.5) return false;
    memcpy(job->out->albedo + texel * 3, rho, sizeof rho);
    const float w = (float)(4.0 * PRT_PI / in->samples) / (float)PRT_PI;
    float direct[PRT_SH_MAX_COEFFS] = {0}, gather[3 * PRT_SH_MAX_COEFFS] = {0};
    int lane_sample[PACKET];
    float lane_cos[PACKET];
    int j = 0;
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    while (j < in->samples) {
        int lanes = 0;
        for (; j < in->samples && lanes < PACKET; ++j) {
            const float *d = in->dirs + (size_t)j * 3;
            float c = prt__v3_dot(d, ns);
            if (c <= 0.0f) continue;
            if (unsh) { const float *y = in->basis + (size_t)j * nc; for (int i = 0; i < nc; ++i) unsh[i] += c * w * y[i]; }
            if (prt__v3_dot(d, ng) <= 0.0f) continue;   /* a bumped normal leaning past the real surface: blocked by it */
            if (hf && prt__height_blocks(hf, &bump, d)) {
                if (ir) {
                    const float cw = c * (float)(4.0 * PRT_PI / in->samples);
                    for (int q = 0; q < 3; ++q) {
                        const float *T = in->vertex_ir + (size_t)own[q] * 3 * nc;
                        for (int i = 0; i < 3 * nc; ++i) gather[i] += cw * own_w[q] * T[i];
                    }
                }
                continue;
            }
            lane_sample[lanes] = j;
            lane_cos[lanes] = c;
            lanes++;
        }
        if (!lanes) break;
        _Alignas(64) int valid[PACKET];
        bool blocked[PACKET];
        if (ir) {
            _Alignas(64) struct RTCRayHit16 rh;
            prt__packet_rayhits(&rh, valid, org, in->dirs, lane_sample, lanes);
            rtcIntersect16(valid, in->scene, &ictx, &rh);
            for (int k = 0; k < lanes; ++k) {
                blocked[k] = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
                if (!blocked[k]) continue;
                const float *d = in->dirs + (size_t)lane_sample[k] * 3;
                if (rh.hit.Ng_x[k] * d[0] + rh.hit.Ng_y[k] * d[1] + rh.hit.Ng_z[k] * d[2] >= 0.0f) continue;   /* back faces emit nothing */
                const uint32_t *t = m->indices + (size_t)rh.hit.primID[k] * 3;
                const float u = rh.hit.u[k], v = rh.hit.v[k], bw[3] = {1.0f - u - v, u, v};
                const float tr = in->volume_count ? expf(-prt__volumes_optical_depth(in->volumes, in->volume_count, org, d, rh.ray.tfar[k])) : 1.0f;
                const float cw = tr * lane_cos[k] * (float)(4.0 * PRT_PI / in->samples);
                for (int q = 0; q < 3; ++q) {
                    const float *T = in->vertex_ir + (size_t)t[q] * 3 * nc;
                    for (int i = 0; i < 3 * nc; ++i) gather[i] += cw * bw[q] * T[i];
                }
            }
        } else {
            _Alignas(64) struct RTCRay16 r;
            prt__packet_rays(&r, valid, org, in->dirs, lane_sample, lanes);
            rtcOccluded16(valid, in->scene, &ictx, &r);
            for (int k = 0; k < lanes; ++k) blocked[k] = r.tfar[k] < 0.0f;
        }
        for (int k = 0; k < lanes; ++k) {
            if (blocked[k]) continue;
            const float *y = in->basis + (size_t)lane_sample[k] * nc;
            const float tr = in->volume_count ? expf(-prt__volumes_optical_depth(in->volumes, in->volume_count, org, in->dirs + (size_t)lane_sample[k] * 3, INFINITY)) : 1.0f;
            for (int i = 0; i < nc; ++i) direct[i] += tr * lane_cos[k] * w * y[i];
        }
    }
    if (shad) memcpy(shad, direct, (size_t)nc * sizeof(float));
    if (ir)
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < nc; ++i) ir[c * nc + i] = rho[c] * direct[i] + rho[c] / (float)PRT_PI * gather[c * nc + i];
    return true;
}

prt_status prt__bake_texels(prt_context *ctx, const prt__texel_input *in, prt__texel_sets *out)
{
    memset(out, 0, sizeof *out);
    const prt__mesh *m = in->mesh;
    if (!prt__mesh_has_uv(m))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "per-texel transfer needs texture coordinates on every mesh, and '%s' has %s",
                         in->source, m->uv && m->vertex_count && isfinite(m->uv[0]) ? "some without" : "none");
    const int W = in->width, H = in->height, nc = in->order * in->order;
    const size_t ntex = (size_t)W * H;
    texel_job job = {in, m, nc, prt__calloc(ntex, sizeof(uint32_t)), prt__calloc(ntex * 2, sizeof(float)), out};
    out->width = W;
    out->height = H;
    out->albedo = prt__calloc(ntex * 3, sizeof(float));
    out->covered = prt__calloc(ntex, 1);
    const bool want[3] = {(in->kinds & PRT_TRANSFER_UNSHADOWED) != 0, (in->kinds & PRT_TRANSFER_SHADOWED) != 0,
                          (in->kinds & PRT_TRANSFER_INTERREFLECTED) != 0 && in->vertex_ir};
    prt_status st = PRT_OK;
    for (int k = 0; k < 3; ++k) {
        if (!want[k]) continue;
        out->channels[k] = k == 2 ? 3 : 1;
        if (!(out->coeffs[k] = prt__calloc(ntex * (size_t)out->channels[k] * nc, sizeof(float)))) st = PRT_ERR_NO_MEMORY;
    }
    if (st || !job.owner || !job.bary || !out->albedo || !out->covered) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %dx%d texels", W, H); goto fail; }

    size_t overlap = 0, outside = 0;
    if (!prt__texel_raster(m, W, H, job.owner, job.bary, &overlap, &outside)) {
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %dx%d texels", W, H);
        goto fail;
    }
    if (outside) {
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "per-texel transfer needs texture coordinates inside [0, 1] (a unique layout); "
                                                 "%zu vertex uses lie outside", outside);
        goto fail;
    }
    size_t covered = 0;
    for (size_t i = 0; i < ntex; ++i) covered += job.owner[i] != 0;
    if (!covered) { st = prt__fail(ctx, PRT_ERR_EMPTY, "no texel centre of the %dx%d grid falls inside any UV triangle", W, H); goto fail; }
    if (overlap * 100 > covered)
        prt__log(ctx, PRT_LOG_WARN, "UV layout overlaps itself: %zu texels claimed twice (each keeps its first triangle)", overlap);

    prt__progress_begin(in->progress, "texels", ntex);
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
    for (size_t i = 0; i < ntex; ++i) {
        if (job.owner[i] && !prt__progress_cancelled(in->progress)) {
            out->covered[i] = texel_bake(&job, i, out->coeffs[0] ? out->coeffs[0] + i * nc : NULL, out->coeffs[1] ? out->coeffs[1] + i * nc : NULL,
                                         out->coeffs[2] ? out->coeffs[2] + i * 3 * nc : NULL);
        }
        if ((i & 255) == 0) prt__progress_add(in->progress, 256);
    }
    prt__progress_end(in->progress);
    if (prt__progress_cancelled(in->progress)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled"); goto fail; }
    {
        float *planes[4] = {out->coeffs[0], out->coeffs[1], out->coeffs[2], out->albedo};
        const int floats[4] = {nc, nc, 3 * nc, 3};
        int32_t *label = malloc(ntex * sizeof *label);
        if (!label) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %dx%d texels", W, H); goto fail; }
        /* Each chart's reads take only its own transfer: gutters between charts may be one texel. */
        if (!(st = prt__texel_support_charts(ctx, m, W, H, label)) && !prt__texel_fill_gutters(W, H, label, out->covered, planes, floats, 4))
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %dx%d texels", W, H);
        free(label);
        if (st) goto fail;
    }
    free(job.owner);
    free(job.bary);
    return PRT_OK;
fail:
    free(job.owner);
    free(job.bary);
    prt__texel_sets_free(out);
    return st;
}
