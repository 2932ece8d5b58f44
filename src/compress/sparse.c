/* Non-linear approximation: keep the largest coefficients, then uniform quantization. Keeping the
 * largest coefficients of an orthonormal expansion is the best N-term approximation in L2. */
#include "compress/sparse.h"

#include <math.h>
#include <string.h>

prt_status prt__sparse_alloc(prt__sparse_store *s, size_t vectors, int n, int bits, int dim)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    s->bits = bits;
    s->dim = dim;
    s->vectors = vectors;
    size_t cells = vectors * (size_t)n;
    s->index = prt__calloc(cells ? cells : 1, sizeof(uint16_t));
    s->values = prt__calloc(cells * 3 * ((size_t)bits / 8) + 8, 1);   /* padded: SIMD readers load 4 or 8 bytes at the last value */
    s->scale = prt__calloc(vectors ? vectors * 3 : 1, sizeof(float));
    if (!s->index || !s->values || !s->scale) {
        prt__sparse_free(s);
        return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for %zu sparse vectors", vectors);
    }
    return PRT_OK;
}

void prt__sparse_save(const prt__sparse_store *s, size_t first, size_t count, prt__bytes *out)
{
    const size_t n = (size_t)s->n, vb = (size_t)s->bits / 8;
    prt__bytes_put(out, s->index + first * n, count * n * sizeof(uint16_t));
    prt__bytes_put(out, (const unsigned char *)s->values + first * n * 3 * vb, count * n * 3 * vb);
    prt__bytes_put(out, s->scale + first * 3, count * 3 * sizeof(float));
}

bool prt__sparse_load(prt__sparse_store *s, size_t first, size_t count, const unsigned char *data, size_t size)
{
    const size_t n = (size_t)s->n, vb = (size_t)s->bits / 8;
    const size_t ib = count * n * sizeof(uint16_t), valb = count * n * 3 * vb, sb = count * 3 * sizeof(float);
    if (first > s->vectors || count > s->vectors - first || size != ib + valb + sb) return false;
    for (size_t i = 0; i < count * n; ++i) {   /* readers index dense vectors of dim with them */
        uint16_t k;
        memcpy(&k, data + i * sizeof k, sizeof k);
        if (k >= s->dim) return false;
    }
    memcpy(s->index + first * n, data, ib);
    memcpy((unsigned char *)s->values + first * n * 3 * vb, data + ib, valb);
    memcpy(s->scale + first * 3, data + ib + valb, sb);
    return true;
}

void prt__sparse_free(prt__sparse_store *s)
{
    free(s->index);
    free(s->values);
    free(s->scale);
    memset(s, 0, sizeof *s);
}

size_t prt__sparse_bytes(const prt__sparse_store *s)
{
    return s->vectors * ((size_t)s->n * (2 + 3 * (size_t)s->bits / 8) + 12);
}

bool prt__sparse_scratch_init(prt__sparse_scratch *w, int dim)
{
    w->mag = malloc((size_t)dim * sizeof(float));
    w->sel = malloc((size_t)dim * sizeof(float));
    if (!w->mag || !w->sel) { prt__sparse_scratch_free(w); return false; }
    return true;
}

void prt__sparse_scratch_free(prt__sparse_scratch *w)
{
    free(w->mag);
    free(w->sel);
    w->mag = w->sel = NULL;
}

float prt__kth_largest(float *x, int n, int k)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        float pivot = x[lo + (hi - lo) / 2];
        int i = lo, j = hi;
        while (i <= j) {
            while (x[i] > pivot) i++;
            while (x[j] < pivot) j--;
            if (i <= j) { float t = x[i]; x[i] = x[j]; x[j] = t; i++; j--; }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else return x[k];
    }
    return x[k];
}

void prt__sparse_encode(prt__sparse_store *s, size_t vec, const float *r, const float *g, const float *b, prt__sparse_scratch *w)
{
    const int dim = s->dim, n = s->n;
    /* Non-negative floats order like their bit patterns: a histogram of the top 12 bits finds the
     * bin holding the n-th largest, and only that bin's members need a selection. */
    enum { BINS = 4096, SHIFT = 19 };
    uint32_t hist[BINS];
    memset(hist, 0, sizeof hist);
    for (int j = 0; j < dim; ++j) {
        float m = r[j] * r[j] + g[j] * g[j] + b[j] * b[j];
        uint32_t u;
        memcpy(&u, &m, 4);
        w->mag[j] = m;
        if (u) hist[u >> SHIFT]++;   /* zeros (most of a cube below the horizon) would serialize on one counter */
    }
    uint32_t nonzero = 0;
    for (int i = 1; i < BINS; ++i) nonzero += hist[i];
    hist[0] += (uint32_t)dim - nonzero - hist[0];
    float thr = -1.0f;   /* keeps everything when n == dim */
    if (n < dim) {
        int bin = BINS - 1;
        uint32_t above_bin = 0;
        while (bin > 0 && above_bin + hist[bin] < (uint32_t)n) above_bin += hist[bin--];
        int members = 0;
        for (int j = 0; j < dim; ++j) {
            uint32_t u;
            memcpy(&u, &w->mag[j], 4);
            if ((int)(u >> SHIFT) == bin) w->sel[members++] = w->mag[j];
        }
        thr = prt__kth_largest(w->sel, members, n - 1 - (int)above_bin);
    }
    /* Strictly above the threshold first, then ties in index order, so the choice is unique. */
    int above = 0;
    for (int j = 0; j < dim; ++j) above += w->mag[j] > thr;
    int ties = n - above, count = 0;
    uint16_t *idx = s->index + vec * (size_t)n;
    for (int j = 0; j < dim && count < n; ++j) {
        if (w->mag[j] > thr || (w->mag[j] == thr && ties-- > 0)) idx[count++] = (uint16_t)j;
    }
    while (count < n) idx[count++] = 0;   /* cannot happen (dim >= n), kept for safety */
    const float *ch[3] = {r, g, b};
    const float qmax = s->bits == 8 ? 127.0f : 32767.0f;
    float *scale = s->scale + vec * 3;
    for (int c = 0; c < 3; ++c) {
        float m = 0;
        for (int i = 0; i < n; ++i) m = fmaxf(m, fabsf(ch[c][idx[i]]));
        scale[c] = m > 0 ? m / qmax : 0.0f;
        const float inv = m > 0 ? qmax / m : 0.0f;
        if (s->bits == 8) {
            int8_t *q = (int8_t *)s->values + vec * (size_t)n * 3;
            for (int i = 0; i < n; ++i) q[i * 3 + c] = (int8_t)lrintf(fmaxf(-qmax, fminf(qmax, ch[c][idx[i]] * inv)));
        } else {
            int16_t *q = (int16_t *)s->values + vec * (size_t)n * 3;
            for (int i = 0; i < n; ++i) q[i * 3 + c] = (int16_t)lrintf(fmaxf(-qmax, fminf(qmax, ch[c][idx[i]] * inv)));
        }
    }
}

void prt__sparse_accumulate(const prt__sparse_store *s, size_t vec, const float weight[3], float *dense)
{
    const int n = s->n, dim = s->dim;
    const uint16_t *idx = s->index + vec * (size_t)n;
    const float *scale = s->scale + vec * 3;
    const float w0 = weight[0] * scale[0], w1 = weight[1] * scale[1], w2 = weight[2] * scale[2];
    float *d0 = dense, *d1 = dense + dim, *d2 = dense + 2 * (size_t)dim;
    if (s->bits == 8) {
        const int8_t *q = (const int8_t *)s->values + vec * (size_t)n * 3;
        for (int i = 0; i < n; ++i) {
            int j = idx[i];
            d0[j] += w0 * q[3 * i];
            d1[j] += w1 * q[3 * i + 1];
            d2[j] += w2 * q[3 * i + 2];
        }
    } else {
        const int16_t *q = (const int16_t *)s->values + vec * (size_t)n * 3;
        for (int i = 0; i < n; ++i) {
            int j = idx[i];
            d0[j] += w0 * q[3 * i];
            d1[j] += w1 * q[3 * i + 1];
            d2[j] += w2 * q[3 * i + 2];
        }
    }
}

void prt__sparse_get(const prt__sparse_store *s, size_t vec, int i, int *index, float rgb[3])
{
    const size_t at = vec * (size_t)s->n + (size_t)i;
    *index = s->index[at];
    for (int c = 0; c < 3; ++c) {
        int q = s->bits == 8 ? ((const int8_t *)s->values)[at * 3 + c] : ((const int16_t *)s->values)[at * 3 + c];
        rgb[c] = (float)q * s->scale[vec * 3 + c];
    }
}
