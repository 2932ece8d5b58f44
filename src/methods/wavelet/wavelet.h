/* The wavelet method's state (the files of this folder look inside; nothing else does): per
 * vertex term_count[v] sparse transport vectors, vertex v's first at vec_start[v]. */
#ifndef PRT_METHODS_WAVELET_H
#define PRT_METHODS_WAVELET_H

#include "brdf/separable.h"
#include "compress/sparse.h"
#include "transfer/method.h"
#include "prt/wavelet.h"

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
    struct prt__gpu_sums *gpu;                    /* the rows for the GPU (gpu.c), built on first use */
} prt__wavelet_set;

extern const prt__method prt__method_wavelet;

/* prt export --web (web.c, web.js). */
prt_status prt__wavelet_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page);

static inline prt__wavelet_set *prt__wavelet(const prt_transfer *t) { return prt__state_of(t, &prt__method_wavelet); }
void prt__wavelet_set_free(void *w);
/* Relighting finished on the GPU (gpu.c): whether t has glossy vertices (their K-vectors then
 * come as a kvec product), and r's products and frame vector for light (NULL: no light). */
bool prt__wavelet_glossy(const prt_transfer *t);   /* any vertex with a separable BRDF */
prt_status prt__wavelet_gpu(prt_context *ctx, const prt_transfer *t, const prt_wavelet_light *light, prt_relit *r);
/* Fills vec_start from term_count; false if a count is 0 or above 16. */
bool prt__wavelet_index(prt__wavelet_set *w, size_t vertex_count, size_t *vectors);
/* Packs the factored materials' view maps for the renderer (prt_wavelet_view_maps). */
prt_status prt__wavelet_build_view_maps(const prt_transfer *t, prt__wavelet_set *w);
/* The wavelet bake (bake.c) as stages of work units, for t holding the scene. */
prt_status prt__wavelet_bake_begin(prt_context *ctx, const prt_wavelet_bake_desc *d, prt_transfer *t, prt__bake_job **job);

/* Its chunks (file.c). */
prt_status prt__wavelet_save(const prt_transfer *t, prt__chunk_list *out);
prt_status prt__wavelet_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count);

#endif
