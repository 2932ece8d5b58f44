/* The transfer object shared by bake, file I/O and relighting. */
#ifndef PRT_CORE_TRANSFER_SET_H
#define PRT_CORE_TRANSFER_SET_H

#include "geom/mesh.h"
#include "prt/compress.h"
#include "prt/wavelet.h"
#include "brdf/separable.h"
#include "compress/sparse.h"

#define PRT__KIND_COUNT 5

/* A clustered-PCA compressed set (compress/cpca.c); VQ and PCA are special cases. */
typedef struct prt__cpca {
    prt_compress_method method;
    int clusters, dim;          /* dim = channels * order^2 */
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

struct prt__progress;
/* Compresses nv vectors of dim floats (X row-major) with desc's settings filled in. */
prt_status prt__cpca_build(prt_context *ctx, const float *X, size_t nv, int dim, const prt_compress_desc *desc,
                           struct prt__progress *prog, prt__cpca **out);

typedef struct prt__sh_set {
    int channels;       /* 0 = absent, 1 = albedo applied at relight, 3 = RGB with albedo */
    float *coeffs;      /* [vertex][channel][order^2]; NULL when compressed */
    prt__cpca *cpca;    /* non-NULL when compressed */
    int quant_bits;     /* 0, or 8 / 16: coeffs hold dequantized values and files store integers */
} prt__sh_set;

/* Quantization grid of one set: per coefficient index, value = bias + q * scale. */
void prt__quant_grid(const float *x, size_t nv, int dim, int bits, float *scale, float *bias);

/* Per-texel transfer over the UV layout: texel (x, y) has its centre at uv ((x + .5) / W,
 * (y + .5) / H); row 0 is v near 0. Diffuse kinds only (index 0..2 as for vertex sets). */
typedef struct prt__texel_sets {
    int width, height;
    float *albedo;        /* [texel][3] */
    uint8_t *covered;     /* [texel]: 1 baked, 2 filled from neighbours, 0 outside every chart */
    int channels[3];
    float *coeffs[3];     /* [texel][channel][order^2] */
} prt__texel_sets;
void prt__texel_sets_free(prt__texel_sets *s);
prt_status prt__texel_sets_copy(prt__texel_sets *dst, const prt__texel_sets *src, int order);

/* The wavelet method's transfer (prt/wavelet.h): per vertex term_count[v] sparse vectors,
 * vertex v's first at vec_start[v]. */
typedef struct prt__wavelet_set {
    int terms, supersample, bounces, gather_resolution, brdf_resolution;
    prt_brdf_param param;
    uint8_t *term_count;                          /* [vertex] */
    size_t *vec_start;                            /* [vertex + 1], derived */
    prt__sparse_store store;
    prt_brdf_factors *factors[PRT__MAX_BRDFS];    /* per material (k - 1); NULL = Lambertian */
    float *view_maps;                             /* prt_wavelet_view_maps' arrays, built on first use */
    uint8_t *vertex_set;
    int view_sets;
} prt__wavelet_set;
void prt__wavelet_set_free(prt__wavelet_set *w);
/* Fills vec_start from term_count; false if a count is 0 or above 16. */
bool prt__wavelet_index(prt__wavelet_set *w, size_t vertex_count, size_t *vectors);

struct prt_transfer {
    prt__mesh mesh;
    int order;
    prt__sh_set sets[PRT__KIND_COUNT];   /* indexed by prt__kind_index */
    int samples, bounces, threads;
    uint32_t seed;
    double bake_seconds;
    char source[512];
    bool has_env;
    prt_environment_desc env;
    bool glossy_exit;                 /* glossy sets hold exit radiance (BRDF baked in) */
    int brdf_count;
    prt_brdf brdfs[PRT__MAX_BRDFS];   /* materials named by mesh.material */
    prt__texel_sets texels;
    prt__wavelet_set *wavelet;        /* NULL unless baked with the wavelet method */
};

static inline bool prt__kind_glossy(int index) { return index >= 3; }
/* Floats per vertex of set k when uncompressed. */
static inline size_t prt__set_dim(const prt_transfer *t, int k)
{
    size_t n = (size_t)t->order * (size_t)t->order;
    return (size_t)t->sets[k].channels * n * (prt__kind_glossy(k) ? n : 1);
}
/* Copies a mesh including materials. */
prt_status prt__mesh_copy(prt__mesh *dst, const prt__mesh *src);

/* 0..4 for UNSHADOWED, SHADOWED, INTERREFLECTED, GLOSSY_SHADOWED, GLOSSY_INTERREFLECTED; -1 otherwise. */
int prt__kind_index(prt_transfer_kind kind);
prt_transfer_kind prt__kind_from_index(int index);

#endif
