/* prt/spectral.h - direct-to-indirect transfer in a spectral mesh basis (Wang, Zhu & Humphreys
 * 2007): what a file of method "spectral" holds, and its basis.
 *
 * The mesh is cut into partitions (METIS); partition p carries the lowest-frequency eigenvectors
 * of its topological Laplacian as basis functions s_l, orthonormal over the partition's vertices.
 * A vertex x stores T(x, l), the irradiance at x when every surface emits radiance s_l from its
 * front (sparse, 16-bit). Relighting computes direct light per vertex from any lighting, and per
 * bounce projects the reflected radiance B onto the basis (c_l = sum_v s_l(v) B(v)) and gathers
 * E(x) = sum_l T(x, l) c_l, B' = albedo / pi E: albedo can change without a rebake
 * (prt_relight_desc.albedo). Everything else goes through prt/method.h.
 * prt-method: spectral */
#ifndef PRT_SPECTRAL_H
#define PRT_SPECTRAL_H

#include "prt/base.h"
#include "prt/transfer.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct prt_spectral_info {
    int partitions, functions;
    int samples;              /* gathering rays per vertex of the bake */
    int partition_size;       /* vertices per partition the bake asked for */
    int env_order;            /* SH order of the environment's direct-light transfer */
    uint64_t coefficients;    /* non-zero transfer entries stored */
    size_t basis_bytes, transfer_bytes;
} prt_spectral_info;

/* 1 and info filled when t is a spectral file, else 0. */
int prt_transfer_spectral_info(const prt_transfer *t, prt_spectral_info *info);
/* Vertex v's partition, the index of its partition's first function, their count, and the
 * values of those functions at v (count floats, borrowed). 0 when t is not spectral or v is out
 * of range. */
int prt_transfer_spectral_vertex(const prt_transfer *t, size_t v, int *partition, int *first, int *count, const float **values);
/* Projects an RGB signal per vertex (3 floats each) onto the basis: 3 floats per function. */
prt_status prt_spectral_project(const prt_transfer *t, const float *signal, float *coefficients);
/* The per-vertex signal back from 3 coefficients per function. */
prt_status prt_spectral_reconstruct(const prt_transfer *t, const float *coefficients, float *signal);

#ifdef __cplusplus
}
#endif
#endif
