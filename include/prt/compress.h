/* prt/compress.h - compression of transfer data: PCA, VQ (k-means) and clustered PCA, the
 * settings and the error report; the SH method compresses its sets with them
 * (prt_transfer_compress, prt/sh_transfer.h), the light cloud its zones.
 *
 * Clustered PCA (Sloan et al. 2003, as used by Kristensen et al. 2005, section 5) approximates
 * each vertex's transfer vector x in its cluster c as x ~ mean_c + sum_i z_i B_ci. Vertices
 * start in k-means clusters; each iteration recomputes every cluster's local PCA, gives the next
 * PCA vector to the cluster whose next eigenvalue per member vertex is largest (the largest drop in
 * error per vertex), and moves each vertex to the cluster that reconstructs it best, until the
 * budget of vectors is spent and no vertex moves. VQ is clustered PCA with no vectors; PCA is one
 * cluster. Relighting works on compressed sets directly: per lighting change one dot product per
 * cluster mean and vector, then per vertex a short weighted sum. Results are deterministic for a
 * seed whatever the thread count. */
#ifndef PRT_COMPRESS_H
#define PRT_COMPRESS_H

#include "prt/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum prt_compress_method {
    PRT_COMPRESS_CPCA = 0,   /* clustered PCA */
    PRT_COMPRESS_PCA,        /* one cluster */
    PRT_COMPRESS_VQ          /* clusters, no vectors: each vertex stores its cluster only */
} prt_compress_method;

typedef struct prt_compress_desc {
    prt_compress_method method;
    int clusters;            /* 0 = 64 for CPCA, 256 for VQ (PCA: always 1) */
    int vectors;             /* average PCA vectors per cluster; 0 = 8 (VQ: always 0) */
    int iterations;          /* reclustering iterations; 0 = 20 */
    uint32_t seed;           /* picks the initial cluster centres */
    prt_progress_fn progress;
    void *progress_user;
} prt_compress_desc;

typedef struct prt_compress_info {
    int compressed;          /* 0 if the set is stored uncompressed */
    int quantize_bits;       /* 8 or 16 when quantized, 0 for 32-bit floats */
    prt_compress_method method;
    int clusters, vectors_total;
    double rms_error;        /* RMS over vertices of |x - reconstruction| (transfer units) */
    double relative_error;   /* rms_error / RMS |x| */
    size_t bytes;            /* storage of the set */
} prt_compress_info;

#ifdef __cplusplus
}
#endif

/* prt 0.1 declared the compression of SH sets (prt_transfer_compress, prt_transfer_quantize, ...)
 * in this header: programs that include it alone still find it, in the SH method's own header. */
#include "prt/sh_transfer.h"

#endif
