/* Offset transfer maps: what a texel receives from the texel `offset` away, for every texel, as
 * one map per offset. Light arriving at a texel is gathered from the first-order light map shifted
 * by each offset, modulated by that offset's map, and summed (eq. 9): a constant number of
 * texture operations per texel, whatever the lights. */
#include "methods/offset/transfer.h"

#include "methods/offset/sampling.h"
#include "geom/texel_raster.h"

/* ---- patches ------------------------------------------------------------------------------------ */

void prt__texel_patches_free(prt__texel_patches *p)
{
    free(p->pos); free(p->nrm); free(p->albedo); free(p->area); free(p->owner);
    memset(p, 0, sizeof *p);
}

prt_status prt__texel_patches_build(const prt_context *ctx, const prt__mesh *m, int width, int height, prt__texel_patches *out)
{
    memset(out, 0, sizeof *out);
    if (width < 1 || height < 1 || width > 8192 || height > 8192) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "texel map %d x %d is not 1..8192 a side", width, height);
    if (!prt__mesh_has_uv(m)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "texel patches need texture coordinates on every vertex");
    const size_t n = (size_t)width * height;
    out->width = width;
    out->height = height;
    out->pos = prt__calloc(n * 3, sizeof(float));
    out->nrm = prt__calloc(n * 3, sizeof(float));
    out->albedo = prt__calloc(n * 3, sizeof(float));
    out->area = prt__calloc(n, sizeof(float));
    out->owner = prt__calloc(n, sizeof(uint32_t));
    float *bary = prt__calloc(n * 2, sizeof(float));
    size_t overlap = 0, outside = 0;
    bool ok = out->pos && out->nrm && out->albedo && out->area && out->owner && bary && prt__texel_raster(m, width, height, out->owner, bary, &overlap, &outside) &&
              prt__texel_areas(m, width, height, out->area);
    if (!ok) { free(bary); prt__texel_patches_free(out); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %d x %d texel patches", width, height); }
    if (outside) {
        free(bary);
        prt__texel_patches_free(out);
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "texel patches need texture coordinates inside [0, 1]: %zu vertex uses lie outside", outside);
    }
    for (size_t i = 0; i < n; ++i) {
        if (!out->owner[i]) { out->area[i] = 0; continue; }   /* a sliver's texel it only touches: no centre of its own */
        const uint32_t *ix = m->indices + (size_t)(out->owner[i] - 1) * 3;
        const float w[3] = {1 - bary[i * 2] - bary[i * 2 + 1], bary[i * 2], bary[i * 2 + 1]};
        for (int c = 0; c < 3; ++c) {
            out->pos[i * 3 + c] = w[0] * m->positions[ix[0] * 3 + c] + w[1] * m->positions[ix[1] * 3 + c] + w[2] * m->positions[ix[2] * 3 + c];
            out->nrm[i * 3 + c] = w[0] * m->normals[ix[0] * 3 + c] + w[1] * m->normals[ix[1] * 3 + c] + w[2] * m->normals[ix[2] * 3 + c];
            out->albedo[i * 3 + c] = w[0] * m->albedo[ix[0] * 3 + c] + w[1] * m->albedo[ix[1] * 3 + c] + w[2] * m->albedo[ix[2] * 3 + c];
        }
        if (!prt__v3_normalize(out->nrm + i * 3)) memcpy(out->nrm + i * 3, m->normals + ix[0] * 3, 3 * sizeof(float));
    }
    free(bary);
    return PRT_OK;
}

/* ---- transfer between patches ------------------------------------------------------------------- */

void prt__offset_tr(const prt__offset_transfer *x, size_t t, size_t s, float out[3])
{
    const prt__texel_patches *p = x->patches;
    out[0] = out[1] = out[2] = 0;
    if (!(p->area[t] > 0) || !(p->area[s] > 0)) return;
    const prt__dipole *dip = x->dipole;
    if (x->kind == PRT__OFFSET_DIPOLE && x->medium) {   /* light scatters within one medium */
        if (!x->medium[t] || x->medium[t] != x->medium[s]) return;
        dip = x->media[x->medium[t] - 1];
    }
    if (t == s) {
        /* Light scattered back out within the texel itself: the dipole over a disc of its area
         * (per unit area, as every entry); a surface does not light itself by inter-reflection. */
        if (x->kind == PRT__OFFSET_DIPOLE) {
            const double a = sqrt(p->area[t] / PRT_PI);
            for (int c = 0; c < 3; ++c) out[c] = (float)(prt__dipole_disc(&dip[c], a) / p->area[t] * (dip[c].falloff > 0 ? p->albedo[t * 3 + c] : 1.0f));
        }
        return;
    }
    const float *pt = p->pos + t * 3, *ps = p->pos + s * 3;
    float d[3];
    prt__v3_sub(ps, pt, d);
    const float r2 = prt__v3_dot(d, d);
    if (!(r2 > 0)) return;
    if (x->kind == PRT__OFFSET_DIPOLE) {
        /* At the distance of the source patch's rim when its centre is nearer than that: a texel
         * whose centre nearly touches another's (slivers, a sphere's pole) would otherwise take
         * the dipole's peak for its whole area. */
        const double r = sqrt((double)r2 + p->area[s] / PRT_PI);
        for (int c = 0; c < 3; ++c) out[c] = (float)prt__dipole_rd(&dip[c], r) * (dip[c].falloff > 0 ? p->albedo[t * 3 + c] : 1.0f);
        return;
    }
    const float r = sqrtf(r2);
    const float ct = prt__v3_dot(p->nrm + t * 3, d) / r, cs = -prt__v3_dot(p->nrm + s * 3, d) / r;
    if (ct <= 0 || cs <= 0) return;
    float a[3], b[3];
    for (int c = 0; c < 3; ++c) {
        a[c] = pt[c] + p->nrm[t * 3 + c] * x->ray_offset;
        b[c] = ps[c] + p->nrm[s * 3 + c] * x->ray_offset;
    }
    if (!prt__raycaster_segment_clear(x->rc, a, b)) return;
    /* Per unit area of a disc of the source's area seen from t (Wallace et al. 1989): bounded by
     * 1 / area where the points' own form factor would blow up (texels meeting at a corner). */
    const float f = ct * cs / ((float)PRT_PI * r2 + p->area[s]);
    for (int c = 0; c < 3; ++c) out[c] = p->albedo[t * 3 + c] * f;
}

prt_status prt__offset_maps(const prt_context *ctx, const prt__offset_transfer *x, const int *offsets, int count, float **maps)
{
    const prt__texel_patches *p = x->patches;
    const int W = p->width, H = p->height;
    const size_t n = (size_t)W * H;
    float *tva = malloc(n * (size_t)count * sizeof *tva), *out = prt__calloc(n * (size_t)count * 3, sizeof *out);
    if (!tva || !out) { free(tva); free(out); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %d transfer maps of %d x %d", count, W, H); }
    prt_status st = prt__offset_tva(ctx, p->area, W, H, offsets, count, tva);
    if (st) { free(tva); free(out); return st; }
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
    for (size_t t = 0; t < n; ++t) {
        if (!(p->area[t] > 0)) continue;
        const int tx = (int)(t % (size_t)W), ty = (int)(t / (size_t)W);
        for (int k = 0; k < count; ++k) {
            const int sx = tx + offsets[k * 2], sy = ty + offsets[k * 2 + 1];
            if (sx < 0 || sx >= W || sy < 0 || sy >= H) continue;
            float tr[3];
            prt__offset_tr(x, t, (size_t)sy * W + sx, tr);
            for (int c = 0; c < 3; ++c) out[((size_t)k * n + t) * 3 + c] = tr[c] * tva[t * (size_t)count + k];
        }
    }
    free(tva);
    *maps = out;
    return PRT_OK;
}

void prt__offset_apply(const prt_context *ctx, int width, int height, const int *offsets, int count, const float *maps, const float *first,
                       float *out)
{
    const size_t n = (size_t)width * height;
    /* Row by row: each offset's map and the shifted first-order row stream through together. */
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
    for (int y = 0; y < height; ++y) {
        float *o = out + (size_t)y * width * 3;
        memset(o, 0, (size_t)width * 3 * sizeof *o);
        for (int k = 0; k < count; ++k) {
            const int dx = offsets[k * 2], sy = y + offsets[k * 2 + 1];
            if (sy < 0 || sy >= height) continue;
            const int x0 = dx < 0 ? -dx : 0, x1 = dx > 0 ? width - dx : width;
            const float *m = maps + ((size_t)k * n + (size_t)y * width) * 3, *f = first + (size_t)sy * width * 3;
            for (int x = x0; x < x1; ++x)
                for (int c = 0; c < 3; ++c) o[x * 3 + c] += f[(x + dx) * 3 + c] * m[x * 3 + c];
        }
    }
}

void prt__offset_gather(const prt_context *ctx, const prt__offset_transfer *x, const float *first, float *out)
{
    const prt__texel_patches *p = x->patches;
    const size_t n = (size_t)p->width * p->height;
#pragma omp parallel for schedule(dynamic, 16) num_threads(prt__threads(ctx))
    for (size_t t = 0; t < n; ++t) {
        double sum[3] = {0, 0, 0};
        for (size_t s = 0; s < n && p->area[t] > 0; ++s) {
            if (!(p->area[s] > 0)) continue;
            float tr[3];
            prt__offset_tr(x, t, s, tr);
            for (int c = 0; c < 3; ++c) sum[c] += (double)first[s * 3 + c] * tr[c] * p->area[s];
        }
        for (int c = 0; c < 3; ++c) out[t * 3 + c] = (float)sum[c];
    }
}
