/* SH relighting finished on the GPU (prt_relight_desc.gpu_finish; prt_render_sums): each
 * vertex's transfer dotted with the light on the GPU. Uncompressed (and quantized: coeffs hold the
 * dequantized values) sets upload their rows and take the light's SH as the frame's vector;
 * clustered PCA sets upload each vertex's cluster and weights, and the frame's vector is every
 * cluster mean and PCA vector projected on the light on the CPU (a few thousand dot products), as
 * the course notes split it. One-channel sets are scaled by albedo per vertex, as relight.c.
 * Glossy sets add the exit vectors (build_glossy); the frame's vector is the diffuse part's
 * section, then the glossy set's. */
#include "methods/sh/sh.h"
#include "transfer/gpu_sums.h"

#include <string.h>

/* RGB entries of the frame's vector set k reads at n coefficients of light: the light itself, or
 * per cluster mean and PCA vector its projection (glossy sets: one per exit coefficient). */
static size_t section(const prt__sh_state *sh, int k, int n)
{
    const prt__cpca *c = sh->sets[k].cpca;
    const size_t per = prt__kind_glossy(k) ? (size_t)sh->order * sh->order : 1;
    return c ? ((size_t)c->clusters + c->vectors_total) * per : (size_t)n;
}

/* Set k's section of the frame's vector (section() entries) under the light's first n
 * coefficients, as relight.c and relight_glossy.c project it, in their order. */
static void fill(const prt__sh_state *sh, int k, const prt_sh_light *light, int n, float *x)
{
    const prt__sh_set *s = &sh->sets[k];
    const prt__cpca *c = s->cpca;
    if (!c) {
        for (int i = 0; i < n; ++i)
            for (int l = 0; l < 3; ++l) x[i * 3 + l] = light->coeffs[l][i];
        return;
    }
    const int stride = sh->order * sh->order, ch = s->channels;
    const size_t vectors = (size_t)c->clusters + c->vectors_total;
    if (!prt__kind_glossy(k)) {
        for (size_t row = 0; row < vectors; ++row) {
            const float *v = row < (size_t)c->clusters ? c->means + row * c->dim : c->basis + (row - (size_t)c->clusters) * c->dim;
            for (int l = 0; l < 3; ++l) {
                const float *seg = v + (ch == 3 ? l * stride : 0);
                float sum = 0;
                for (int i = 0; i < n; ++i) sum += seg[i] * light->coeffs[l][i];
                x[row * 3 + l] = sum;
            }
        }
        return;
    }
    /* Each mean and PCA vector is a transfer matrix X[c or 0][j][i]: its exit vector under the
     * light, sum_j X[j][i] L[j], at x[(vector * N + i) * 3 + c]. */
    const size_t N = (size_t)stride;
#pragma omp parallel for schedule(static)
    for (size_t q = 0; q < vectors; ++q) {
        const float *X = q < (size_t)c->clusters ? c->means + q * c->dim : c->basis + (q - (size_t)c->clusters) * c->dim;
        float *o = x + q * N * 3;
        for (int l = 0; l < 3; ++l) {
            const float *Xc = X + (ch == 3 ? (size_t)l * N * N : 0);
            for (size_t i = 0; i < N; ++i) {
                float sum = 0;
                for (int j = 0; j < n; ++j) sum += light->coeffs[l][j] * Xc[(size_t)j * N + i];
                o[i * 3 + l] = sum;
            }
        }
    }
}

/* The description of diffuse set k at n = order^2 coefficients of light, its section of the
 * frame's vector at entry base of length entries. */
static prt__gpu_sums *build(const prt_transfer *t, const prt__sh_state *sh, int k, int n, size_t base, size_t length)
{
    const prt__sh_set *s = &sh->sets[k];
    const size_t nv = t->mesh.vertex_count;
    const int stride = sh->order * sh->order, ch = s->channels;
    const prt__cpca *c = s->cpca;
    prt__gpu_sums *g = prt__gpu_sums_new(length);
    if (!g) return NULL;
    const size_t entries = c ? nv + c->weights_total : nv * (size_t)n;
    prt_render_product *p = prt__gpu_sums_add(g, -1, nv, entries, ch == 1, 0, 1);
    if (!p) { prt__gpu_sums_free(g); return NULL; }
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight, *scale = (float *)p->scale;
    uint32_t e = 0;
    for (size_t v = 0; v < nv; ++v) {
        start[v] = e;
        if (c) {
            const uint32_t cl = c->cluster_of[v];
            index[e] = (uint32_t)(base + cl);
            w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = 1.0f;
            e++;
            for (uint32_t j = 0; j < c->counts[cl]; ++j, ++e) {
                index[e] = (uint32_t)(base + c->clusters + c->basis_start[cl] + j);
                w[e * 3] = w[e * 3 + 1] = w[e * 3 + 2] = c->weights[c->weight_start[v] + j];
            }
        } else {
            const float *row = s->coeffs + v * (size_t)ch * stride;
            for (int i = 0; i < n; ++i, ++e) {
                index[e] = (uint32_t)(base + (size_t)i);
                for (int l = 0; l < 3; ++l) w[e * 3 + l] = row[(ch == 3 ? l * stride : 0) + i];
            }
        }
        if (scale) memcpy(scale + v * 3, t->mesh.albedo + v * 3, 3 * sizeof(float));
    }
    start[nv] = e;
    g->key[0] = k;
    g->key[1] = n;
    return g;
}

/* Glossy set k: its diffuse part (when the file holds one) as above, then the exit vectors
 * e = A M L (relight_glossy.c): row v * N + i holds sum_j M_c[j][i] L_c[j] for each channel c
 * (raw sets: the matrix row against the light; clustered PCA: the cluster mean's exit
 * coefficient i plus the vertex's weights times its PCA vectors', projected on the CPU), times
 * the material's lobe factor of band(i) (A: identity when the BRDF is baked in); vertices
 * without a glossy lobe get empty rows. */
static prt__gpu_sums *build_glossy(const prt_transfer *t, const prt__sh_state *sh, int k, int nl)
{
    const prt__sh_set *s = &sh->sets[k];
    const int d = prt__kind_index(prt_transfer_kind_diffuse_part(prt__kind_from_index(k)));
    const size_t nv = t->mesh.vertex_count, N = (size_t)sh->order * sh->order, dim = prt__set_dim(sh, k);
    /* The lobes' per-band factors, as relight_glossy.c's lobe_factors. */
    float table[PRT__MAX_BRDFS][3][PRT_SH_MAX_ORDER];
    bool has[PRT__MAX_BRDFS] = {false};
    for (int b = 0; !sh->glossy_exit && b < t->brdf_count && b < PRT__MAX_BRDFS; ++b) {
        const prt_brdf *br = &t->brdfs[b];
        double a[PRT_SH_MAX_ORDER];
        if (!(has[b] = prt_brdf_is_glossy(br)) || prt_brdf_lobe_bands(br, sh->order, a)) { has[b] = false; continue; }
        const double n = br->exponent, norm = br->model == PRT_BRDF_BLINN_PHONG ? (n + 8.0) / (n + 4.0) : (n + 2.0) / (n + 1.0);
        for (int c = 0; c < 3; ++c)
            for (int l = 0; l < sh->order; ++l) table[b][c][l] = (float)(br->specular[c] * a[l] * norm);
    }
    const prt__cpca *cp = s->cpca;
    const size_t dlen = d >= 0 && sh->sets[d].channels ? section(sh, d, nl) : 0, glen = section(sh, k, nl);
    prt__gpu_sums *g = prt__gpu_sums_new(dlen + glen);
    if (!g) return NULL;
    if (dlen) {
        prt__gpu_sums *diffuse = build(t, sh, d, nl, 0, dlen);
        if (!diffuse) { prt__gpu_sums_free(g); return NULL; }
        /* Moved over: the product's arrays change owner. */
        g->products[0] = diffuse->products[0];
        g->sums.product_count = 1;
        diffuse->sums.product_count = 0;
        prt__gpu_sums_free(diffuse);
    }
    size_t entries = 0;
    for (size_t v = 0; v < nv; ++v) {
        const int mat = t->mesh.material ? t->mesh.material[v] : 0;
        if (sh->glossy_exit || (mat && has[mat - 1])) entries += N * (cp ? 1 + (size_t)cp->counts[cp->cluster_of[v]] : (size_t)nl);
    }
    prt_render_product *p = prt__gpu_sums_add(g, -1, nv * N, entries, !sh->glossy_exit, 0, 0);
    if (!p) { prt__gpu_sums_free(g); return NULL; }
    p->exit = 1;
    uint32_t *start = (uint32_t *)p->start, *index = (uint32_t *)p->index;
    float *w = (float *)p->weight, *scale = (float *)p->scale;
    uint32_t e = 0;
    for (size_t v = 0; v < nv; ++v) {
        const int mat = t->mesh.material ? t->mesh.material[v] : 0;
        const bool lit = sh->glossy_exit || (mat && has[mat - 1]);
        const float *X = cp ? NULL : s->coeffs + v * dim;
        for (size_t i = 0; i < N; ++i) {
            const size_t row = v * N + i;
            start[row] = e;
            if (!lit) continue;
            if (cp) {
                const uint32_t cl = cp->cluster_of[v];
                index[e] = (uint32_t)(dlen + cl * N + i);
                w[(size_t)e * 3] = w[(size_t)e * 3 + 1] = w[(size_t)e * 3 + 2] = 1.0f;
                e++;
                for (uint32_t j = 0; j < cp->counts[cl]; ++j, ++e) {
                    index[e] = (uint32_t)(dlen + ((size_t)cp->clusters + cp->basis_start[cl] + j) * N + i);
                    w[(size_t)e * 3] = w[(size_t)e * 3 + 1] = w[(size_t)e * 3 + 2] = cp->weights[cp->weight_start[v] + j];
                }
            } else {
                for (int j = 0; j < nl; ++j, ++e) {
                    index[e] = (uint32_t)(dlen + (size_t)j);
                    for (int c = 0; c < 3; ++c) w[(size_t)e * 3 + c] = X[(s->channels == 3 ? (size_t)c * N * N : 0) + (size_t)j * N + i];
                }
            }
            if (scale) {
                int l = 0;
                while ((size_t)((l + 1) * (l + 1)) <= i) l++;
                for (int c = 0; c < 3; ++c) scale[row * 3 + c] = table[mat - 1][c][l];
            }
        }
    }
    start[nv * N] = e;
    g->key[0] = k;
    g->key[1] = nl;
    return g;
}

bool prt__sh_gpu_can(const prt__sh_state *s, int k, const prt_relight_desc *d)
{
    if (k >= 0 && k <= 2) return s->sets[k].channels;
    return k >= 3 && k <= 4 && s->sets[k].channels && !d->brdf;
}

prt_status prt__sh_gpu_relight(prt_context *ctx, const prt_transfer *t, int k, const prt_sh_light *light, prt_relit *r)
{
    prt__sh_state *sh = t->state;
    const int order = light->order < sh->order ? light->order : sh->order, n = order * order;
    const bool glossy = prt__kind_glossy(k);
    pthread_mutex_lock(sh->lock);
    if (!sh->gpu[k] || sh->gpu[k]->key[1] != n)
        prt__gpu_sums_replace(&sh->gpu[k], glossy ? build_glossy(t, sh, k, n) : build(t, sh, k, n, 0, section(sh, k, n)));
    const prt__gpu_sums *g = sh->gpu[k];
    pthread_mutex_unlock(sh->lock);
    if (!g || g->key[1] != n) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (glossy) {
        r->exit_order = sh->order;
        r->exit_mirror = !sh->glossy_exit;
    }
    prt_status st = prt__relit_alloc(ctx, t, r, false);
    if (st) return st;
    const size_t length = g->sums.vector_length;
    float *x = r->gpu_vector = prt__calloc(length * 3, sizeof(float));
    if (!x) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (glossy) {
        const int dk = prt__kind_index(prt_transfer_kind_diffuse_part(prt__kind_from_index(k)));
        const size_t dlen = dk >= 0 && sh->sets[dk].channels ? section(sh, dk, n) : 0;
        if (dlen) fill(sh, dk, light, n, x);
        fill(sh, k, light, n, x + dlen * 3);
    } else {
        fill(sh, k, light, n, x);
    }
    r->gpu_sums = &g->sums;
    return PRT_OK;
}
