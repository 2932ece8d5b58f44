/* The separable BRDF approximation's data, shared with the transfer object and the file reader. */
#ifndef PRT_BRDF_SEPARABLE_H
#define PRT_BRDF_SEPARABLE_H

#include "prt/brdf.h"

#include <stdbool.h>

struct prt_brdf_factors {
    int terms, computed, resolution;
    bool grey;             /* all channels equal: lookups read channel 0 once */
    prt_brdf_param param;
    float sigma[3][PRT_BRDF_MAX_TERMS];
    float *light, *view;   /* [channel][computed][resolution^2], row y, column x */
};

/* Allocates maps for `computed` terms; returns NULL without memory. */
prt_brdf_factors *prt__brdf_factors_alloc(int terms, int computed, int resolution, prt_brdf_param param);
/* Sets grey from the maps. */
void prt__brdf_factors_finish(prt_brdf_factors *f);
/* Local direction of map cell (x, y); false for grid cells outside the disk. */
bool prt__brdf_cell_dir(prt_brdf_param param, int res, int x, int y, float w[3]);

#endif
