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

/* A box of a map: columns x0 .. x0 + w - 1, rows y0 .. y0 + h - 1. */
typedef struct prt__map_box {
    int x0, y0, w, h;
} prt__map_box;

/* What a piece costs beyond its texels, in texels: in an export its file's header (about 380
 * bytes of OpenEXR, as much as 64 texels of RGB halves), on the GPU its quads and the ragged ends
 * of its power-of-two slices. */
#define PRT__SLICE_OVERHEAD 64

/* Axial slicing (the paper's section 5.1: maps cropped "to minimal bounding boxes, including
 * axial slicing"): disjoint minimal boxes that hold every non-zero texel of a map (3 floats
 * each) between them, appended to *boxes (grown with realloc; *count boxes of *cap). The map's
 * box is cut in two along its widest band of empty rows or columns (the one that leaves out the
 * most texels), each side cropped to its own box and cut again, down to boxes without an empty
 * band; then, bottom up, a cut is kept only where its pieces cost less than the box they came
 * from, a piece costing its area plus `overhead` texels (ties keep the box whole). An empty map
 * gives no box, a map without an empty band its one box. */
prt_status prt__map_slice(const prt_context *ctx, const float *map, int width, int height, int overhead, prt__map_box **boxes, int *count,
                          int *cap);

#endif
