/* The importance of offsets while they are chosen (offsets stage of the bake): how much transfer
 * each offset carries over a spread of sample texels, evaluated batch by batch for
 * prt__choose_offsets by a team of threads that never makes the choosing thread wait. */
#ifndef PRT_METHODS_OFFSET_IMPORTANCE_H
#define PRT_METHODS_OFFSET_IMPORTANCE_H

#include "methods/offset/sampling.h"
#include "methods/offset/transfer.h"
#include "core/progress.h"

typedef struct prt__offset_importance_desc {
    const prt__texel_patches *patches;
    const prt__offset_transfer *x;   /* [2]: radiosity, subsurface */
    unsigned kinds;                  /* which of x count (PRT__OFFSET_*_BIT) */
    int mean;                        /* 0: the largest over the sample texels, 1: their mean */
    const uint32_t *sample;          /* texels looked at (y * width + x) */
    size_t count;
} prt__offset_importance_desc;

/* prt__choose_offsets with this importance, on prt__threads(ctx) threads; the same offsets for any
 * thread count. Progress: one step per offset evaluated. */
prt_status prt__offset_choose(prt_context *ctx, const prt__offset_importance_desc *d, const prt__offset_desc *od, prt__progress *p, int **offsets,
                              int *count);

#endif
