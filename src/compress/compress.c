/* prt_transfer_compress and friends: the public face of compress/cpca.c. */
#include "core/progress.h"
#include "core/transfer_set.h"

#include <string.h>

/* A new transfer with in's mesh and settings and no sets yet. */
static prt_status copy_without_sets(prt_context *ctx, const prt_transfer *in, prt_transfer **out)
{
    prt_transfer *t = prt__calloc(1, sizeof *t);
    if (!t) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    *t = *in;
    memset(&t->mesh, 0, sizeof t->mesh);
    memset(t->sets, 0, sizeof t->sets);
    memset(&t->texels, 0, sizeof t->texels);
    const prt__mesh *m = &in->mesh;
    prt_status st = prt__mesh_copy(&t->mesh, m);
    if (!st) st = prt__texel_sets_copy(&t->texels, &in->texels, in->order);   /* texel sets stay as they are */
    if (st) { prt_transfer_release(t); return prt__fail(ctx, st, "%s", prt_last_error()); }
    *out = t;
    return PRT_OK;
}

prt_status prt_transfer_compress(prt_context *ctx, const prt_transfer *in, const prt_compress_desc *desc, prt_transfer **out)
{
    if (!in || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_compress: transfer and out are required");
    *out = NULL;
    if (in->wavelet) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "wavelet transfer is already sparse and quantized: compression applies to SH sets");
    prt_compress_desc d = desc ? *desc : (prt_compress_desc){0};
    if (d.method > PRT_COMPRESS_VQ || d.clusters < 0 || d.vectors < 0 || d.iterations < 0)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "compression: unknown method or negative settings");
    if (d.method == PRT_COMPRESS_PCA) d.clusters = 1;
    if (d.clusters == 0) d.clusters = d.method == PRT_COMPRESS_VQ ? 256 : 64;
    if (d.method == PRT_COMPRESS_VQ) d.vectors = 0;
    else if (d.vectors == 0) d.vectors = 8;
    if (d.iterations == 0) d.iterations = 20;
    if (d.clusters > 65536 || d.vectors > 300 || d.iterations > 1000)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "compression: clusters <= 65536, vectors <= 300, iterations <= 1000");
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (in->sets[k].cpca) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer is already compressed");
        else if (in->sets[k].quant_bits) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "compress before quantizing, not after");

    prt_transfer *t = NULL;
    prt_status st = copy_without_sets(ctx, in, &t);
    if (st) return st;
    const prt__mesh *m = &in->mesh;
    prt__progress prog = {d.progress, d.progress_user, NULL, 0, 0, 0.0, 0};
    for (int k = 0; k < PRT__KIND_COUNT && !st; ++k) {
        const prt__sh_set *s = &in->sets[k];
        if (!s->channels) continue;
        char stage[48];
        snprintf(stage, sizeof stage, "compress %s", prt_transfer_kind_name(prt__kind_from_index(k)));
        prt__progress_begin(&prog, stage, (uint64_t)d.iterations);
        st = prt__cpca_build(ctx, s->coeffs, m->vertex_count, (int)prt__set_dim(in, k), &d, &prog, &t->sets[k].cpca);
        prt__progress_end(&prog);
        t->sets[k].channels = s->channels;
    }
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}

prt_status prt_transfer_compress_info(const prt_transfer *t, prt_transfer_kind kind, prt_compress_info *out)
{
    memset(out, 0, sizeof *out);
    int k = prt__kind_index(kind);
    if (k < 0 || !t->sets[k].channels) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the transfer holds no %s set", prt_transfer_kind_name(kind));
    const prt__cpca *c = t->sets[k].cpca;
    size_t nv = t->mesh.vertex_count;
    if (!c) {
        size_t dim = prt__set_dim(t, k);
        int bits = t->sets[k].quant_bits;
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
    int k = prt__kind_index(kind);
    if (k < 0 || !t->sets[k].channels) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "the transfer holds no %s set", prt_transfer_kind_name(kind));
    const prt__sh_set *s = &t->sets[k];
    size_t nv = t->mesh.vertex_count, dim = prt__set_dim(t, k);
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
    if (in->wavelet) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "wavelet transfer is quantized when baked (--bits): quantization applies to SH sets");
    if (bits != 8 && bits != 16) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "quantization takes 8 or 16 bits (got %d)", bits);
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (in->sets[k].cpca) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "quantize before compressing: compressed sets keep float weights");
    prt_transfer *t = NULL;
    prt_status st = copy_without_sets(ctx, in, &t);
    if (st) return st;
    const prt__mesh *m = &in->mesh;
    for (int k = 0; k < PRT__KIND_COUNT && !st; ++k) {
        const prt__sh_set *s = &in->sets[k];
        if (!s->channels) continue;
        const int dim = (int)prt__set_dim(in, k);
        const size_t nv = m->vertex_count;
        float *scale = malloc(2 * (size_t)dim * sizeof(float)), *bias = scale ? scale + dim : NULL;
        float *q = malloc(nv * (size_t)dim * sizeof(float));
        if (!q || !scale) { free(q); free(scale); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
        prt__quant_grid(s->coeffs, nv, dim, bits, scale, bias);
        const float levels = (float)((1u << bits) - 1);
        for (size_t v = 0; v < nv; ++v)
            for (int j = 0; j < dim; ++j) {
                float x = s->coeffs[v * dim + j];
                float l = scale[j] > 0 ? fminf(fmaxf(roundf((x - bias[j]) / scale[j]), 0.0f), levels) : 0.0f;
                q[v * dim + j] = bias[j] + l * scale[j];
            }
        free(scale);
        t->sets[k].channels = s->channels;
        t->sets[k].coeffs = q;
        t->sets[k].quant_bits = bits;
    }
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}
