/* UV atlases for meshes without a usable texture layout: charts grown by normal deviation, each
 * flattened by least-squares conformal maps (Levy et al. 2002), packed into a square by the texels
 * whose centres lie within a texel of them (a bilinear read's reach), those of two charts never the
 * same texel: each holds its own chart's value (texel_raster.h's gutter sources and fill), and no
 * read on one chart weighs another's. What per-texel transfer bakes over. */
#ifndef PRT_GEOM_UV_ATLAS_H
#define PRT_GEOM_UV_ATLAS_H

#include "geom/mesh.h"

typedef struct prt__atlas_desc {
    int resolution;       /* texels per side of the map the atlas is laid out for */
    int max_resolution;   /* above resolution: while the charts do not fit, or touch under a quarter of
                           * the map's texels (mostly gutter), a map twice as wide is tried, up to
                           * this; the report says which was taken */
    int padding;       /* empty texels between any two charts' bilinear supports; 0 = none */
    float max_angle;   /* degrees a triangle's normal may turn from its chart's mean; 0 = 60 */
} prt__atlas_desc;

typedef struct prt__atlas_report {
    size_t grown;            /* charts grown by normal deviation */
    size_t charts;           /* after cutting charts that would fold or overlap, and merging small ones */
    size_t cut;              /* of those, the charts added by cutting large ragged ones in two for packing */
    size_t added_vertices;   /* copies made where a vertex lies on a seam between charts */
    size_t shared;           /* duplicate faces laid on their duplicate's texels (back-to-back twins) */
    size_t glued;            /* twins both on their own (a fin's two sides) glued into one chart */
    size_t flattened;        /* charts flattened by LSCM before merging (the rest by projection onto their plane) */
    double coverage;         /* share of the map's texels that hold some of the surface */
    double texel_density;    /* texels per unit of surface area, the same in every chart */
    double worst_stretch;    /* largest ratio of a triangle map's singular values */
    int resolution;          /* texels per side of the map laid out for */
    int smaller;             /* the last smaller map tried and passed over (0: none), */
    bool smaller_fit;        /* whether the charts fitted it (then they touched too few of its texels: */
    double smaller_cover;    /* this share) */
} prt__atlas_report;

/* Replaces m's texture coordinates by a generated atlas inside [0, 1], copying vertices that lie
 * on seams between charts (their other attributes are copied as they are). Deterministic. */
prt_status prt__uv_atlas(const prt_context *ctx, prt__mesh *m, const prt__atlas_desc *d, prt__atlas_report *report);

/* Why m's own texture coordinates cannot carry a resolution x resolution map (missing, outside
 * [0, 1], or overlapping on more than 1% of the texels they cover), written to why; false when
 * they can. */
bool prt__uv_layout_unusable(const prt__mesh *m, int resolution, char *why, size_t why_size);

/* The ratio of the singular values of the map from triangle t's surface to its UVs (1 = no
 * shear or anisotropic stretch); 1 for a triangle degenerate in space. */
double prt__uv_stretch(const prt__mesh *m, size_t t);

#endif
