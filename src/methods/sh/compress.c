/* prt_transfer_compress and friends: the public face of compress/cpca.c for SH transfer, and
 * the in-place steps the SH bake runs as its last stages. */
#include "methods/sh/sh.h"

prt_status prt__compress_desc_check(prt_context *ctx, prt_compress_desc *d)
{
    if (d->method > PRT_COMPRESS_VQ || d->clusters < 0 || d->vectors < 0 || d->iterations < 0)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "compression: unknown method or negative settings");
    if (d->method == PRT_COMPRESS_PCA) d->clusters = 1;
    if (d->clusters == 0) d->clusters = d->method == PRT_COMPRESS_VQ ? 256 : 64;
    if (d->method == PRT_COMPRESS_VQ) d->vectors = 0;
    else if (d->vectors == 0) d->vectors = 8;
    if (d->iterations == 0) d->iterations = 20;
    if (d->clusters > 65536 || d->vectors > 300 || d->iterations > 1000)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "compression: clusters <= 65536, vectors <= 300, iterations <= 1000");
    return PRT_OK;
}

prt_status prt__sh_compress_set(prt_context *ctx, prt__sh_state *s, size_t nv, int k, const prt_compress_desc *d, prt__progress *prog)
{
    prt__sh_set *set = &s->sets[k];
    if (set->cpca) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer is already compressed");
    if (set->quant_bits) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "compress before quantizing, not after");
    prt__cpca *c = NULL;
    prt_status st = prt__cpca_build(ctx, set->coeffs, nv, (int)prt__set_dim(s, k), d, prog, &c);
    if (st) return st;
    free(set->coeffs);
    set->coeffs = NULL;
    set->cpca = c;
    return PRT_OK;
}

prt_status prt__sh_quantize(prt_context *ctx, prt__sh_state *s, size_t nv, int bits)
{
    if (bits != 8 && bits != 16) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "quantization takes 8 or 16 bits (got %d)", bits);
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (s->sets[k].cpca) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "quantize before compressing: compressed sets keep float weights");
    for (int k = 0; k < PRT__KIND_COUNT; ++k) {
        prt__sh_set *set = &s->sets[k];
        if (!set->channels) continue;
        const int dim = (int)prt__set_dim(s, k);
        float *scale = malloc(2 * (size_t)dim * sizeof(float)), *bias = scale ? scale + dim : NULL;
        if (!scale) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        prt__quant_grid(set->coeffs, nv, dim, bits, scale, bias);
        const float levels = (float)((1u << bits) - 1);
        for (size_t v = 0; v < nv; ++v)
            for (int j = 0; j < dim; ++j) {
                float *x = &set->coeffs[v * dim + j];
                float l = scale[j] > 0 ? fminf(fmaxf(roundf((*x - bias[j]) / scale[j]), 0.0f), levels) : 0.0f;
                *x = bias[j] + l * scale[j];
            }
        free(scale);
        set->quant_bits = bits;
    }
    return PRT_OK;
}

bool prt__texel_quantize8(prt__texel_sets *tx, int order)
{
    const size_t ntex = (size_t)tx->width * tx->height;
    for (int k = 0; k < 3; ++k) {
        if (!tx->coeffs[k]) continue;
        const int dim = tx->channels[k] * order * order;
        float *scale = malloc(2 * (size_t)dim * sizeof(float)), *bias = scale ? scale + dim : NULL;
        if (!scale) return false;
        prt__quant_grid(tx->coeffs[k], ntex, dim, 8, scale, bias);
        for (size_t i = 0; i < ntex; ++i)
            for (int j = 0; j < dim; ++j) {
                float *x = &tx->coeffs[k][i * dim + j];
                const float l = scale[j] > 0 ? fminf(fmaxf(roundf((*x - bias[j]) / scale[j]), 0.0f), 255.0f) : 0.0f;
                *x = bias[j] + l * scale[j];
            }
        free(scale);
    }
    tx->bytes = true;
    tx->halves = false;
    return true;
}

/* A new SH transfer with in's mesh, settings and texel sets and no vertex sets yet. */
static prt_status copy_without_sets(prt_context *ctx, const prt_transfer *in, const prt__sh_state *s, prt_transfer **out, prt__sh_state **state)
{
    prt_transfer *t = NULL;
    prt_status st = prt__transfer_copy_frame(ctx, in, &t);
    if (st) return st;
    prt__sh_state *n = prt__sh_state_new();
    if (!n) { prt_transfer_release(t); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    t->state = n;
    n->order = s->order;
    n->samples = s->samples;
    n->bounces = s->bounces;
    n->seed = s->seed;
    n->glossy_exit = s->glossy_exit;
    if ((st = prt__texel_sets_copy(&n->texels, &s->texels, s->order))) { prt_transfer_release(t); return prt__fail(ctx, st, "%s", prt_last_error()); }
    if (s->grid.matrices) {
        const size_t bytes = (size_t)s->grid.dims[0] * s->grid.dims[1] * s->grid.dims[2] * 3 * (size_t)s->grid.order * s->grid.order * s->grid.order * s->grid.order * sizeof(float);
        const size_t points = (size_t)s->grid.dims[0] * s->grid.dims[1] * s->grid.dims[2];
        n->grid = s->grid;
        n->grid.matrices = malloc(bytes);
        n->grid.front = malloc(points * sizeof(float));
        if (!n->grid.matrices || !n->grid.front) { prt__sh_grid_free(&n->grid); prt_transfer_release(t); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        memcpy(n->grid.matrices, s->grid.matrices, bytes);
        memcpy(n->grid.front, s->grid.front, points * sizeof(float));
    }
    *out = t;
    *state = n;
    return PRT_OK;
}

prt_status prt_transfer_compress(prt_context *ctx, const prt_transfer *in, const prt_compress_desc *desc, prt_transfer **out)
{
    if (!in || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_compress: transfer and out are required");
    *out = NULL;
    const prt__sh_state *s = prt__sh(in);
    if (!s) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s transfer cannot be compressed: compression applies to SH sets", in->method->name);
    if (s->frames.count) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer's key frames are compressed across frames already");
    prt_compress_desc d = desc ? *desc : (prt_compress_desc){0};
    prt_status st = prt__compress_desc_check(ctx, &d);
    if (st) return st;
    /* Quantized sets (16-bit by default) hold their values on a grid: those values are what is
     * compressed, and the compressed sets keep float weights. */
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (s->sets[k].cpca) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer is already compressed");
    prt_transfer *t = NULL;
    prt__sh_state *n = NULL;
    if ((st = copy_without_sets(ctx, in, s, &t, &n))) return st;
    const size_t nv = in->mesh.vertex_count;
    prt__progress prog = {d.progress, d.progress_user, NULL, 0, 0, 0.0, 0, ctx};
    for (int k = 0; k < PRT__KIND_COUNT && !st; ++k) {
        if (!s->sets[k].channels) continue;
        char stage[48];
        snprintf(stage, sizeof stage, "compress %s", prt_transfer_kind_name(prt__kind_from_index(k)));
        prt__progress_begin(&prog, stage, (uint64_t)d.iterations);
        st = prt__cpca_build(ctx, s->sets[k].coeffs, nv, (int)prt__set_dim(s, k), &d, &prog, &n->sets[k].cpca);
        prt__progress_end(&prog);
        n->sets[k].channels = s->sets[k].channels;
    }
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}

prt_status prt_transfer_compress_info(const prt_transfer *t, prt_transfer_kind kind, prt_compress_info *out)
{
    memset(out, 0, sizeof *out);
    const prt__sh_state *s = prt__sh(t);
    int k = prt__kind_index(kind);
    if (!s || k < 0 || !s->sets[k].channels) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the transfer holds no %s set", prt_transfer_kind_name(kind));
    const prt__cpca *c = s->sets[k].cpca;
    size_t nv = t->mesh.vertex_count;
    if (!c) {
        size_t dim = prt__set_dim(s, k);
        int bits = s->sets[k].quant_bits;
        out->quantize_bits = bits;
        out->bytes = bits ? nv * dim * (size_t)(bits / 8) + 2 * dim * sizeof(float) : nv * dim * sizeof(float);
        return PRT_OK;
    }
    out->compressed = 1;
    out->method = c->method;
    out->clusters = c->clusters;
    out->vectors_total = (int)c->vectors_total;
    out->rms_error = c->rms_error;
    out->relative_error = c->relative_error;
    out->bytes = ((size_t)c->clusters * c->dim + c->vectors_total * c->dim + c->weights_total) * sizeof(float) + nv * sizeof(uint32_t) +
                 (size_t)c->clusters * sizeof(uint32_t);
    return PRT_OK;
}

prt_status prt_transfer_reconstruct(const prt_transfer *t, prt_transfer_kind kind, float *out)
{
    const prt__sh_state *sh = prt__sh(t);
    int k = prt__kind_index(kind);
    if (!sh || k < 0 || !sh->sets[k].channels) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the transfer holds no %s set", prt_transfer_kind_name(kind));
    const prt__sh_set *s = &sh->sets[k];
    size_t nv = t->mesh.vertex_count, dim = prt__set_dim(sh, k);
    if (!s->cpca) { memcpy(out, s->coeffs, nv * dim * sizeof(float)); return PRT_OK; }
    const prt__cpca *c = s->cpca;
    for (size_t v = 0; v < nv; ++v) {
        uint32_t cl = c->cluster_of[v];
        float *x = out + v * dim;
        memcpy(x, c->means + (size_t)cl * dim, dim * sizeof(float));
        for (uint32_t j = 0; j < c->counts[cl]; ++j) {
            float w = c->weights[c->weight_start[v] + j];
            const float *b = c->basis + (c->basis_start[cl] + j) * dim;
            for (size_t i = 0; i < dim; ++i) x[i] += w * b[i];
        }
    }
    return PRT_OK;
}

void prt__quant_grid(const float *x, size_t nv, int dim, int bits, float *scale, float *bias)
{
    const float levels = (float)((1u << bits) - 1);
    for (int j = 0; j < dim; ++j) {
        float lo = INFINITY, hi = -INFINITY;
        for (size_t v = 0; v < nv; ++v) {
            lo = fminf(lo, x[v * dim + j]);
            hi = fmaxf(hi, x[v * dim + j]);
        }
        bias[j] = lo;
        scale[j] = hi > lo ? (hi - lo) / levels : 0.0f;
    }
}

prt_status prt_transfer_quantize(prt_context *ctx, const prt_transfer *in, int bits, prt_transfer **out)
{
    if (!in || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_quantize: transfer and out are required");
    *out = NULL;
    const prt__sh_state *s = prt__sh(in);
    if (!s) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s transfer cannot be quantized this way: quantization applies to SH sets", in->method->name);
    if (bits != 8 && bits != 16) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "quantization takes 8 or 16 bits (got %d)", bits);
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (s->sets[k].cpca || s->frames.count) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "quantize before compressing: compressed sets keep float weights");
    prt_transfer *t = NULL;
    prt__sh_state *n = NULL;
    prt_status st = copy_without_sets(ctx, in, s, &t, &n);
    if (st) return st;
    const size_t nv = in->mesh.vertex_count;
    for (int k = 0; k < PRT__KIND_COUNT && !st; ++k) {
        if (!s->sets[k].channels) continue;
        const size_t bytes = nv * prt__set_dim(s, k) * sizeof(float);
        n->sets[k].channels = s->sets[k].channels;
        if (!(n->sets[k].coeffs = malloc(bytes))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else memcpy(n->sets[k].coeffs, s->sets[k].coeffs, bytes);
    }
    if (!st) st = prt__sh_quantize(ctx, n, nv, bits);
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}
