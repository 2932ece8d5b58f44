/* Sparse top-N vectors of RGB coefficients (of Haar wavelets, for all-frequency transport: Ng et
 * al. 2003, Wang et al. 2005), quantized per vector and channel: a vector keeps the N coefficients of largest RGB magnitude, their indices
 * ascending, each channel as a signed integer times the vector's scale for that channel. */
#ifndef PRT_COMPRESS_SPARSE_H
#define PRT_COMPRESS_SPARSE_H

#include "core/internal.h"

typedef struct prt__sparse_store {
    int n, bits, dim;        /* coefficients per vector, 8 or 16, length of the dense vectors */
    size_t vectors;
    uint16_t *index;         /* [vector][n] */
    void *values;            /* int8_t or int16_t [vector][n][3] */
    float *scale;            /* [vector][3]: value = q * scale */
} prt__sparse_store;

prt_status prt__sparse_alloc(prt__sparse_store *s, size_t vectors, int n, int bits, int dim);
void prt__sparse_free(prt__sparse_store *s);
/* Vectors [first, first + count) as bytes (indices, values, scales) for checkpoints, and back;
 * load writes nothing and returns false when the bytes do not fit. */
void prt__sparse_save(const prt__sparse_store *s, size_t first, size_t count, prt__bytes *out);
bool prt__sparse_load(prt__sparse_store *s, size_t first, size_t count, const unsigned char *data, size_t size);
size_t prt__sparse_bytes(const prt__sparse_store *s);

/* The k-th largest (0-based) of x[0..n), reordering x (Hoare's selection, expected linear time). */
float prt__kth_largest(float *x, int n, int k);

/* Scratch for encoding one vector. */
typedef struct prt__sparse_scratch {
    float *mag, *sel;
} prt__sparse_scratch;
bool prt__sparse_scratch_init(prt__sparse_scratch *w, int dim);
void prt__sparse_scratch_free(prt__sparse_scratch *w);

/* Encodes dense channels r, g, b (dim floats each; g and b may equal r for grey vectors) into
 * vector `vec`. */
void prt__sparse_encode(prt__sparse_store *s, size_t vec, const float *r, const float *g, const float *b, prt__sparse_scratch *w);
/* dense[c][index] += weight[c] * value, c = 0..2 (dense holds 3 planes of dim floats). */
void prt__sparse_accumulate(const prt__sparse_store *s, size_t vec, const float weight[3], float *dense);
/* Decoded coefficient i of vector vec: its index and RGB value. */
void prt__sparse_get(const prt__sparse_store *s, size_t vec, int i, int *index, float rgb[3]);

#endif
