/* Glossy SH transfer (Sloan, Kautz & Snyder 2002, sections 6-7): the bounce loop that carries
 * light between diffuse and glossy surfaces, and the BRDF baked into glossy sets (incident into
 * exit radiance).
 *
 * Per vertex p and bounce b the state is a diffuse outgoing vector D_p (3 x n, n = order^2,
 * albedo applied) and an incident radiance matrix M_p (3 x n x n). A glossy vertex q sends
 * y(w)^T G_q toward w, with G_q = R^T B R M_q its exit matrix (R: SH rotation into q's frame,
 * B: the material's SH matrix). The light a receiver gets along an occluded direction s is the
 * barycentric mix of what the hit triangle's vertices send toward -s; y(-s) = (-1)^l y(s). The
 * BRDF matrices and frame rotations are brdf/sh_matrix.c's. */
#include "methods/sh/bake.h"

#include <string.h>

prt_status prt__bake_glossy_bounces(prt_context *ctx, const prt__bounce_input *in, float **diffuse_total, float **glossy_total)
{
    *diffuse_total = NULL;
    if (glossy_total) *glossy_total = NULL;
    const prt__mesh *m = in->mesh;
    const size_t nv = m->vertex_count;
    const int n = in->order * in->order, n3 = 3 * n;
    const size_t nn3 = (size_t)3 * n * n;
    const float w_dir = (float)(4.0 * PRT_PI / in->samples);
    prt_status st = PRT_OK;

    float *Bmat[PRT__MAX_BRDFS] = {0};
    bool *glossy_vertex = prt__calloc(nv, sizeof(bool));
    float *totD = prt__calloc(nv * n3, sizeof(float)), *prevD = prt__calloc(nv * n3, sizeof(float)),
          *nextD = prt__calloc(nv * n3, sizeof(float));
    float *totM = NULL, *prevM = prt__calloc(nv * nn3, sizeof(float)), *nextM = prt__calloc(nv * nn3, sizeof(float));
    float *G = NULL;
    if (!glossy_vertex || !totD || !prevD || !nextD || !prevM || !nextM) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for glossy inter-reflection"); goto done; }
    if (in->want_glossy && !(totM = prt__calloc(nv * nn3, sizeof(float)))) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for glossy inter-reflection"); goto done; }
    if ((st = prt__brdf_matrices(ctx, in->brdfs, in->brdf_count, in->order, Bmat))) goto done;
    size_t glossy_count = 0;
    for (size_t v = 0; v < nv; ++v) {
        uint8_t k = m->material ? m->material[v] : 0;
        glossy_vertex[v] = k && k <= in->brdf_count && Bmat[k - 1];
        glossy_count += glossy_vertex[v];
    }
    if (glossy_count && !(G = prt__calloc(nv * nn3, sizeof(float)))) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for glossy exit matrices"); goto done; }

    /* Bounce 0: direct light through the shadowed transfer. */
    for (size_t v = 0; v < nv; ++v)
        for (int c = 0; c < 3; ++c) {
            for (int j = 0; j < n; ++j) prevD[v * n3 + c * n + j] = m->albedo[v * 3 + c] * in->shadowed[v * n + j];
            memcpy(prevM + v * nn3 + (size_t)c * n * n, in->glossy_shadowed + v * (size_t)n * n, (size_t)n * n * sizeof(float));
        }
    memcpy(totD, prevD, nv * n3 * sizeof(float));
    if (totM) memcpy(totM, prevM, nv * nn3 * sizeof(float));

    float sign[PRT_SH_MAX_COEFFS];   /* y(-s) = (-1)^l y(s) */
    for (int l = 0; l < in->order; ++l)
        for (int mm = -l; mm <= l; ++mm) sign[l * (l + 1) + mm] = (l & 1) ? -1.0f : 1.0f;

    char stage[48];
    int alloc_failed = 0, read_failed = 0;
    for (int b = 1; b <= in->bounces && !st; ++b) {
        /* Exit matrices of the glossy vertices from this bounce's incident light. */
        if (glossy_count) {
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
            for (size_t v = 0; v < nv; ++v) {
                if (!glossy_vertex[v]) continue;
                prt__frame_rot fr;
                if (prt__frame_rot_create(in->order, m->normals + v * 3, &fr)) { __atomic_store_n(&alloc_failed, 1, __ATOMIC_RELAXED); continue; }
                const float *B = Bmat[m->material[v] - 1];
                for (int c = 0; c < 3; ++c)
                    prt__apply_brdf(&fr, B, c, in->order, prevM + v * nn3 + (size_t)c * n * n, G + v * nn3 + (size_t)c * n * n, n);
                prt__frame_rot_release(&fr);
            }
            if (alloc_failed) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory rotating glossy matrices"); break; }
        }
        snprintf(stage, sizeof stage, "glossy bounce %d/%d", b, in->bounces);
        prt__progress_begin(in->progress, stage, nv);
#pragma omp parallel num_threads(prt__threads(ctx))
        {
            float *accM = malloc(nn3 * sizeof(float));
            prt__hit *buf = malloc((size_t)in->samples * sizeof *buf);   /* a streamed vertex's hits */
            if (!accM || !buf) __atomic_store_n(&alloc_failed, 1, __ATOMIC_RELAXED);
#pragma omp for schedule(dynamic, 32)
            for (size_t p = 0; p < nv; ++p) {
                if (!accM || !buf || prt__progress_cancelled(in->progress)) continue;
                const uint32_t nh = in->hits->count[p];
                const prt__hit *hits = prt__hits_get(in->hits, p, buf);
                if (nh && !hits) { __atomic_store_n(&read_failed, 1, __ATOMIC_RELAXED); continue; }
                const bool needM = totM || glossy_vertex[p];
                float accD[3 * PRT_SH_MAX_COEFFS], I[3 * PRT_SH_MAX_COEFFS], yneg[PRT_SH_MAX_COEFFS];
                memset(accD, 0, (size_t)n3 * sizeof(float));
                if (needM) memset(accM, 0, nn3 * sizeof(float));
                for (uint32_t h = 0; h < nh; ++h) {
                    const prt__hit *hit = &hits[h];
                    const uint32_t *tri = m->indices + (size_t)hit->prim * 3;
                    const float bary[3] = {1.0f - hit->u - hit->v, hit->u, hit->v};
                    const float *ys = in->basis + (size_t)hit->sample * n;
                    memset(I, 0, (size_t)n3 * sizeof(float));
                    for (int k = 0; k < 3; ++k) {
                        const uint32_t q = tri[k];
                        const float bk = bary[k];
                        const float *Dq = prevD + (size_t)q * n3;
                        for (int i = 0; i < n3; ++i) I[i] += bk * Dq[i];
                        if (!glossy_vertex[q]) continue;
                        for (int i = 0; i < n; ++i) yneg[i] = sign[i] * ys[i] * bk;
                        const float *Gq = G + (size_t)q * nn3;
                        for (int row = 0; row < n3; ++row) {   /* row = channel x lighting coefficient */
                            const float *g = Gq + (size_t)row * n;
                            float s = 0.0f;
                            for (int i = 0; i < n; ++i) s += g[i] * yneg[i];
                            I[row] += s;
                        }
                    }
                    for (int i = 0; i < n3; ++i) accD[i] += hit->weight * I[i];
                    if (needM)
                        for (int row = 0; row < n3; ++row) {
                            float s = w_dir * I[row];
                            float *dst = accM + (size_t)row * n;
                            for (int i = 0; i < n; ++i) dst[i] += s * ys[i];
                        }
                }
                for (int c = 0; c < 3; ++c) {
                    float k = m->albedo[p * 3 + c] / (float)PRT_PI;
                    for (int j = 0; j < n; ++j) nextD[p * n3 + c * n + j] = k * accD[c * n + j];
                }
                if (needM) memcpy(nextM + p * nn3, accM, nn3 * sizeof(float));
                else memset(nextM + p * nn3, 0, nn3 * sizeof(float));
                if ((p & 63) == 0) prt__progress_add(in->progress, 64);
            }
            free(accM);
            free(buf);
        }
        prt__progress_end(in->progress);
        if (alloc_failed) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory in the glossy bounce"); break; }
        if (read_failed) { st = prt__fail(ctx, PRT_ERR_IO, "cannot read the ray hits' scratch file"); break; }
        if (prt__progress_cancelled(in->progress)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled"); break; }
        for (size_t i = 0; i < nv * n3; ++i) totD[i] += nextD[i];
        if (totM)
            for (size_t i = 0; i < nv * nn3; ++i) totM[i] += nextM[i];
        float *t;
        t = prevD; prevD = nextD; nextD = t;
        t = prevM; prevM = nextM; nextM = t;
    }
done:
    for (int k = 0; k < in->brdf_count; ++k) free(Bmat[k]);
    free(glossy_vertex); free(prevD); free(nextD); free(prevM); free(nextM); free(G);
    if (st) { free(totD); free(totM); return st; }
    *diffuse_total = totD;
    if (glossy_total) *glossy_total = totM;
    else free(totM);
    return PRT_OK;
}

prt_status prt__bake_brdf_in(prt_context *ctx, prt_transfer *t, const prt_brdf *override)
{
    prt__sh_state *sh = t->state;
    const int n = sh->order * sh->order;
    const size_t nn = (size_t)n * n, nv = t->mesh.vertex_count;
    float *Bmat[PRT__MAX_BRDFS] = {0};
    prt_status st = override ? prt__brdf_matrices(ctx, override, 1, sh->order, Bmat)
                             : prt__brdf_matrices(ctx, t->brdfs, t->brdf_count, sh->order, Bmat);
    for (int k = 3; k < PRT__KIND_COUNT && !st; ++k) {
        prt__sh_set *s = &sh->sets[k];
        if (!s->channels) continue;
        float *out = prt__calloc(nv * 3 * nn, sizeof(float));
        if (!out) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory baking the BRDF in"); break; }
        int failed = 0;
#pragma omp parallel for schedule(dynamic, 64) num_threads(prt__threads(ctx))
        for (size_t v = 0; v < nv; ++v) {
            uint8_t mat = t->mesh.material[v];
            const float *B = override ? Bmat[0] : (mat && mat <= t->brdf_count ? Bmat[mat - 1] : NULL);
            if (!B) continue;
            prt__frame_rot fr;
            if (prt__frame_rot_create(sh->order, t->mesh.normals + v * 3, &fr)) { __atomic_store_n(&failed, 1, __ATOMIC_RELAXED); continue; }
            for (int c = 0; c < 3; ++c) {
                const float *M = s->coeffs + v * s->channels * nn + (s->channels == 3 ? (size_t)c * nn : 0);
                prt__apply_brdf(&fr, B, c, sh->order, M, out + v * 3 * nn + (size_t)c * nn, n);
            }
            prt__frame_rot_release(&fr);
        }
        if (failed) { free(out); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory rotating glossy matrices"); break; }
        free(s->coeffs);
        s->coeffs = out;
        s->channels = 3;
    }
    if (!st) sh->glossy_exit = true;
    for (int k = 0; k < PRT__MAX_BRDFS; ++k) free(Bmat[k]);
    return st;
}
