/* Per-vertex light finished on the GPU (prt_render_sums, include/prt/render.h), as methods build
 * it: a description owning its products' arrays, made once per transfer (and per variant) and
 * kept in the method's state until the transfer goes. */
#ifndef PRT_TRANSFER_GPU_SUMS_H
#define PRT_TRANSFER_GPU_SUMS_H

#include "core/internal.h"
#include "prt/render.h"

#define PRT__GPU_SUMS_MAX 136   /* the spectral bounces: two products each, up to 64, and the tail's eight */

typedef struct prt__gpu_sums {
    prt_render_sums sums;          /* sums.products points at products */
    prt_render_product products[PRT__GPU_SUMS_MAX];
    int key[4];                    /* what the method built it for (set, order, ...) */
    /* Descriptions this one replaced: results relit earlier may still be drawn from them (the
     * viewer draws one result while its worker relights the next), so they live as long as the
     * transfer; freed with this one. */
    struct prt__gpu_sums *replaced;
} prt__gpu_sums;

/* A new empty description with a fresh id, for vector_length RGB entries; NULL when out of memory. */
prt__gpu_sums *prt__gpu_sums_new(size_t vector_length);
/* Adds a product of `rows` rows and `entries` entries (arrays allocated, zeroed; scale when
 * with_scale) and returns it, or NULL (out of memory, too many products, entries past 32 bits). */
prt_render_product *prt__gpu_sums_add(prt__gpu_sums *g, int input, size_t rows, size_t entries, bool with_scale, int clamp, int shown);
/* Makes next the current description in *slot, keeping the one it replaces (above); next NULL
 * (out of memory) leaves *slot as it was and returns false. */
bool prt__gpu_sums_replace(prt__gpu_sums **slot, prt__gpu_sums *next);
void prt__gpu_sums_free(prt__gpu_sums *g);

#endif
