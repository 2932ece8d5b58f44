/* Choosing the offsets of offset radiance transfer mapping (Sunshine-Hill & Faloutsos 2006): a
 * continuous importance distribution built from scattered data points (Delaunay triangulation,
 * a C0 piecewise-linear density sampled through three tetrahedra per triangle, appendix A), the
 * Voronoi areas of the chosen offsets clipped to [-1, 1]^2, and the per-texel Voronoi area sums
 * TVA of eq. 8. */
#ifndef PRT_METHODS_OFFSET_SAMPLING_H
#define PRT_METHODS_OFFSET_SAMPLING_H

#include "core/internal.h"

/* The Delaunay triangles (3 point indices each, counter-clockwise) of n 2-D points (xy, 2 each),
 * by qhull; fails on fewer than 3 points or when all are collinear. */
prt_status prt__delaunay2d(const prt_context *ctx, const double *xy, size_t n, uint32_t **tris, size_t *ntri);

/* A density over the convex hull of data points, linear over each Delaunay triangle between the
 * points' weights (>= 0, not all 0), normalised to integrate to 1. */
typedef struct prt__plpdf {
    size_t n, ntri;
    double *xy, *w;          /* the data points and their weights (copies) */
    uint32_t *tris;
    double *cdf;             /* 3 tetrahedra per triangle: running sums of their volumes, last = 1 */
    double total;            /* volume under the unnormalised surface */
} prt__plpdf;

prt_status prt__plpdf_build(const prt_context *ctx, const double *xy, const double *w, size_t n, prt__plpdf *out);
void prt__plpdf_free(prt__plpdf *p);
/* The normalised density at (x, y); 0 outside the hull. */
double prt__plpdf_eval(const prt__plpdf *p, double x, double y);
/* A sample from four uniform numbers in [0, 1): one picks a tetrahedron by binary search over the
 * summed volumes, three place a point uniformly inside it (Rocchini & Cignoni's folding of the
 * unit cube); the point's (x, y) follows the density. */
void prt__plpdf_sample(const prt__plpdf *p, const double u[4], double out[2]);

/* Areas of the Voronoi cells of n distinct points, each clipped to the square [-1, 1]^2 (the
 * cells then tile it: the areas sum to 4). Points must lie in the square. */
prt_status prt__voronoi_areas(const prt_context *ctx, const double *xy, size_t n, double *areas);

/* What an importance callback says for each of n offsets (offsets: dx, dy in texels, 2 each) into
 * out[n]: the largest (or mean) transference of any texel to the texel that far away. Called with
 * a batch at a time - the seed grid, then the samples drawn from one build of the distribution -
 * so that a callback can spread a whole batch over its threads at once (one parallel region per
 * batch, not per offset: tiny regions stall when cores are shared). Its values must not depend on
 * how it splits the work. */
typedef void (*prt__offset_importance_fn)(void *user, const int *offsets, size_t n, double *out);

typedef struct prt__offset_desc {
    int width, height;       /* the map, texels */
    int count;               /* offsets wanted (a regular grid of about 100 seeds the search) */
    int iterations;          /* refinement samples (default 1000), the distribution rebuilt every 20 */
    uint64_t seed;
} prt__offset_desc;

/* Chooses desc->count distinct integer offsets (dx, dy in texels, |dx| < width, |dy| < height;
 * (0, 0) always among them) by importance: the grid seed, then `iterations` samples from the
 * distribution of what the callback said so far (each 20 drawn from one build, then evaluated as
 * one batch: the paper's "batch of offsets with the same iteration of the distribution"), then the
 * final offsets from the converged distribution. offsets gets 2 ints per offset. Deterministic
 * for a seed. */
prt_status prt__choose_offsets(const prt_context *ctx, const prt__offset_desc *desc, prt__offset_importance_fn importance, void *user,
                               int **offsets, int *count);

/* The nearest chosen offset (normalised coordinates, as the Voronoi cells; ties to the lower
 * index) of every integer offset (dx, dy) with |dx| < width, |dy| < height:
 * out[(dy + height - 1) * (2 width - 1) + dx + width - 1] (malloc'd). */
prt_status prt__offset_labels(const prt_context *ctx, int width, int height, const int *offsets, int count, int32_t **out);

/* The charts of a light map, which split offset cells: a cell around t + offset k stands for its
 * surface by the light of one texel, its representative (the texel itself on the surface, else its
 * gutter's source). Where the cell also covers other charts - other surfaces, far away in space,
 * lit differently - their texels are counted with the offset whose representative lies on their
 * own chart and is nearest to them there (the nearest in space when no offset's does), so that
 * every texel's transfer goes with light from its own surface (no blotches across seams). */
typedef struct prt__offset_charts {
    const int32_t *chart;    /* [width * height] each surface texel's chart, -1 off the surface */
    const int32_t *source;   /* [width * height] covered index of the texel whose light each reads, -1 none */
    const uint32_t *texel;   /* [covered] the texel of each covered index */
    const float *pos;        /* [width * height][3] each surface texel's point */
} prt__offset_charts;

/* For receiver (tx, ty): each offset's representative texel (-1 none: off the map or no surface
 * near) and its chart (-1 none). */
void prt__offset_reps(const prt__offset_charts *c, int width, int height, const int *offsets, int count, int tx, int ty, int32_t *rep,
                      int32_t *rep_chart);
/* The offset that counts surface texel (sx, sy) of chart `chart` for receiver (tx, ty), whose
 * nearest offset is k. */
int prt__offset_recell(const prt__offset_charts *c, int width, const int *offsets, int count, int tx, int ty, const int32_t *rep,
                       const int32_t *rep_chart, int k, int sx, int sy, int chart);

/* TVA of eq. 8: for texel t and offset k, the sum of texel areas A(t + v) over the integer offsets
 * v whose nearest chosen offset is k (v within |vx| < width, |vy| < height; ties to the lower
 * index). area: width * height texel areas (0 outside the charts). out: width * height * count,
 * texel-major. With every integer offset chosen, TVA(t, k) = A(t + offset k). The bake no longer
 * uses it (its cells are chart-aware, bake.c); the offset form of transfer.c does. */
prt_status prt__offset_tva(const prt_context *ctx, const float *area, int width, int height, const int *offsets, int count, float *out);

#endif
