/* Packing offset transfer maps into square atlases (Sunshine-Hill & Faloutsos 2006, section 5.2):
 * fewer textures to switch between while accumulating. Each map is cut into vertical slices of
 * power-of-two widths, which turns two-dimensional packing into one-dimensional packing per
 * width: a free area takes the best-fitting slice of its width, or the top of the tallest when
 * none fits (the rest stays to place), or is halved when no slice has its width. */
#ifndef PRT_METHODS_OFFSET_BINS_H
#define PRT_METHODS_OFFSET_BINS_H

#include "core/internal.h"

/* A rectangle of map `map` (from column sx, row sy, w x h) placed in atlas `bin` at (dx, dy). */
typedef struct prt__bin_piece {
    int map, sx, sy, w, h;
    int bin, dx, dy;
} prt__bin_piece;

/* Places count maps of widths w[i] and heights h[i] (0 x 0 = empty, nothing placed) into atlases
 * of bin_size x bin_size (a power of two, 1..16384): every texel of every map lands in exactly
 * one atlas texel, and no two land in the same. */
prt_status prt__bin_maps(const prt_context *ctx, const int *w, const int *h, int count, int bin_size, prt__bin_piece **pieces, int *piece_count,
                         int *bin_count);

/* The bounding box of a map's non-zero texels (3 floats each), for cropping before binning;
 * false when every texel is zero. */
bool prt__map_crop(const float *map, int width, int height, int *x0, int *y0, int *w, int *h);

#endif
