/* Texel patches of a UV layout. */
#ifndef PRT_GEOM_TEXEL_RASTER_H
#define PRT_GEOM_TEXEL_RASTER_H

#include "geom/mesh.h"

/* Duplicate faces: triangles with the same three corners, in space and in UV, as another, either
 * way round (a back-to-back twin on its face's texels, uv_atlas.h). 1 for all of each such set but
 * one, the first not mirrored in UV (else the first): the one whose surface the texels hold. The
 * raster and the texel areas leave the others out. NULL when out of memory; free() it. */
uint8_t *prt__texel_duplicates(const prt__mesh *m);

/* Rasterizes the mesh's UVs (every vertex has them) into a W x H grid: texel (x, y) has its
 * centre at ((x + .5) / W, (y + .5) / H) and belongs to the first triangle covering it (owner:
 * triangle + 1, 0 = none; bary: 2 barycentrics per texel); triangles no centre falls in take the
 * texels they touch, and texels some triangle covers part of but not the centre go to the nearest
 * such triangle, sampled a quarter texel inside its point nearest the centre. Counts centres claimed twice inside triangles (overlap) and vertex uses
 * outside [0, 1] (outside). Duplicate faces (prt__texel_duplicates) take no texels. False when out
 * of memory. */
bool prt__texel_raster(const prt__mesh *m, int W, int H, uint32_t *owner, float *bary, size_t *overlap, size_t *outside);

/* The world-space surface area inside each texel of the W x H grid (each triangle clipped to
 * each texel square in UV space, scaled by its world-to-UV area ratio): the patch areas TA(t)
 * of texture-space transfer (Sunshine-Hill & Faloutsos 2006); their sum is the mesh's area when the layout covers it once
 * (duplicate faces, prt__texel_duplicates, left out). */
bool prt__texel_areas(const prt__mesh *m, int W, int H, float *area);

/* Each texel's UV chart (prt__uv_islands) when a bilinear read on the chart can weigh it (its
 * centre within one texel, on both axes, of a point of the chart), else -1: the chart of a texel's
 * owning triangle (prt__texel_raster) first, then the first triangle's that reaches it. Generated
 * atlases keep charts' reaches apart (uv_atlas.h). */
prt_status prt__texel_support_charts(const prt_context *ctx, const prt__mesh *m, int width, int height, int32_t *label);

/* Fills every texel without a value (covered[i] == 0; -> 2), ring by ring outwards from the valued
 * ones, with the mean of its neighbours in earlier rings, so that bilinear filtering and mip-maps
 * never pull in black across a chart's border. With label (prt__texel_support_charts; NULL: none)
 * a texel a chart's reads weigh takes only that chart's values, so no read on one chart weighs
 * another's; texels no chart reaches come after, from any. planes[k] holds floats[k] per texel
 * (NULL planes are skipped). False when out of memory. */
bool prt__texel_fill_gutters(int width, int height, const int32_t *label, uint8_t *covered, float **planes, const int *floats, int nplanes);
/* For every texel, the surface texel whose value it takes when read: itself on the surface
 * (index[t] >= 0, the covered index), else the source of its first neighbour (left, right, down,
 * up) in an earlier ring, rings growing outwards from the charts as prt__texel_fill_gutters's
 * (label as there); -1 when the map holds no surface. A fixed gather that a CPU loop and a GPU
 * shader both apply exactly. */
bool prt__texel_gutter_sources(int width, int height, const int32_t *index, const int32_t *label, int32_t *source);

#endif
