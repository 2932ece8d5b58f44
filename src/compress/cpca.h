/* Clustered PCA of long vectors (compress/cpca.c); VQ and PCA are special cases. */
#ifndef PRT_COMPRESS_CPCA_H
#define PRT_COMPRESS_CPCA_H

#include "core/progress.h"
#include "prt/compress.h"

typedef struct prt__cpca {
    prt_compress_method method;
    int clusters, dim;          /* dim = floats per vector */
    uint32_t *counts;           /* PCA vectors per cluster */
    size_t *basis_start;        /* first vector of each cluster in `basis` (derived) */
    float *means;               /* [cluster][dim] */
    float *basis;               /* [vector][dim], clusters' vectors one after another */
    size_t vectors_total;
    uint32_t *cluster_of;       /* [vertex] */
    size_t *weight_start;       /* first weight of each vertex (derived) */
    float *weights;             /* per vertex, counts[cluster_of[v]] floats */
    size_t weights_total;
    double rms_error, relative_error;
} prt__cpca;

void prt__cpca_free(prt__cpca *c);
/* Fills basis_start and weight_start from counts and cluster_of; false if they are inconsistent. */
bool prt__cpca_index(prt__cpca *c, size_t vertex_count);
/* Compresses nv vectors of dim floats (X row-major) with desc's settings filled in. */
prt_status prt__cpca_build(prt_context *ctx, const float *X, size_t nv, int dim, const prt_compress_desc *desc,
                           prt__progress *prog, prt__cpca **out);
/* The same with vectors longer than full_max_dim (at most 512) decomposed only as far as the
 * vectors a cluster can be given (subspace iteration) instead of completely: much faster for
 * long vectors and small budgets. */
prt_status prt__cpca_build_ex(prt_context *ctx, const float *X, size_t nv, int dim, const prt_compress_desc *desc, int full_max_dim,
                              prt__progress *prog, prt__cpca **out);
/* Quantization grid of nv vectors of dim floats: per coefficient index, value = bias + q * scale. */
void prt__quant_grid(const float *x, size_t nv, int dim, int bits, float *scale, float *bias);

#endif
