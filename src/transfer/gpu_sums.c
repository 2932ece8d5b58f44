/* Building prt_render_sums descriptions (transfer/gpu_sums.h). */
#include "transfer/gpu_sums.h"
#include "transfer/transfer.h"

#include <stdlib.h>

prt__gpu_sums *prt__gpu_sums_new(size_t vector_length)
{
    prt__gpu_sums *g = prt__calloc(1, sizeof *g);
    if (!g) return NULL;
    g->sums.id = prt__transfer_serial();   /* unique in the process, never reused */
    g->sums.vector_length = vector_length;
    g->sums.products = g->products;
    return g;
}

prt_render_product *prt__gpu_sums_add(prt__gpu_sums *g, int input, size_t rows, size_t entries, bool with_scale, int clamp, int shown)
{
    if (g->sums.product_count >= PRT__GPU_SUMS_MAX || entries > UINT32_MAX || rows >= UINT32_MAX) return NULL;
    prt_render_product *p = &g->products[g->sums.product_count];
    uint32_t *start = prt__calloc(rows + 1, sizeof(uint32_t));
    uint32_t *index = prt__calloc(entries ? entries : 1, sizeof(uint32_t));
    float *weight = prt__calloc(entries ? entries * 3 : 1, sizeof(float));
    float *scale = with_scale ? prt__calloc(rows ? rows * 3 : 1, sizeof(float)) : NULL;
    if (!start || !index || !weight || (with_scale && !scale)) { free(start); free(index); free(weight); free(scale); return NULL; }
    *p = (prt_render_product){.input = input, .rows = rows, .start = start, .index = index, .weight = weight, .scale = scale, .clamp = clamp, .shown = shown};
    g->sums.product_count++;
    return p;
}

bool prt__gpu_sums_replace(prt__gpu_sums **slot, prt__gpu_sums *next)
{
    if (!next) return false;
    next->replaced = *slot;
    *slot = next;
    return true;
}

void prt__gpu_sums_free(prt__gpu_sums *g)
{
    if (!g) return;
    prt__gpu_sums_free(g->replaced);
    for (int k = 0; k < g->sums.product_count; ++k) {
        free((void *)g->products[k].start);
        free((void *)g->products[k].index);
        free((void *)g->products[k].weight);
        free((void *)g->products[k].scale);
    }
    free(g);
}
