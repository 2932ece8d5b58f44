/* prt/paint.h - first-order light painted onto the surface (Sunshine-Hill & Faloutsos 2006,
 * section 5.3: "the first-order lightmap may be simulated by painting"). Methods that relight from
 * a first-order light map over texels (prt_method_paintable: offset transfer maps) take light
 * painted onto that map (prt_relight_desc.paint) on top of what the lights deliver, and gather
 * its inter-reflection and subsurface scattering as they gather a lamp's: painting costs what
 * moving a light costs.
 *
 * A painting is width x height RGB values over the file's light map (prt_paint_size; row 0 at v
 * near 0), each the first-order light arriving at that texel, as irradiance / pi - the units of
 * the light map the GPU passes start from (prt_relit.gpu_input). An opaque texel then shows
 * albedo x paint and sends that on to the others; a translucent one takes it under its surface.
 * Values off the surface are ignored. Zero everywhere is no painting.
 *
 *     prt_painter *p; prt_painter_create(ctx, t, &p);
 *     float hit[3], n[3];
 *     if (prt_painter_pick(p, eye, dir, hit, n)) prt_painter_dab(p, &(prt_paint_brush){...}, map);
 *     prt_relight(ctx, t, lighting, &(prt_relight_desc){.variant = -1, .paint = map,
 *                 .paint_width = w, .paint_height = h}, &relit);
 *
 * A painter borrows its transfer (release it first) and may be used from several threads at once
 * for picks; dabs write only the map they are given. */
#ifndef PRT_PAINT_H
#define PRT_PAINT_H

#include "prt/base.h"
#include "prt/method.h"

#ifdef __cplusplus
extern "C" {
#endif

/* 1 when m's files take painted first-order light. */
int prt_method_paintable(const prt_method *m);
/* The size of the map a painting of t covers; fails with one line saying why when t's method
 * relights from no first-order light map. */
prt_status prt_paint_size(const prt_transfer *t, int *width, int *height);

typedef struct prt_painter prt_painter;

/* A painter for t: its texels' surface points and a ray caster over its mesh. Refuses methods
 * that take no painting (as prt_paint_size). */
prt_status prt_painter_create(prt_context *ctx, const prt_transfer *t, prt_painter **out);
void prt_painter_release(prt_painter *p);
void prt_painter_size(const prt_painter *p, int *width, int *height);

/* The first surface point on the ray origin + s dir (s > 0; dir need not be unit): 1 and its
 * position and the surface's own normal there (as the mesh winds it, not turned to the ray), or
 * 0 when the ray meets nothing. */
int prt_painter_pick(const prt_painter *p, const float origin[3], const float dir[3], float position[3], float normal[3]);

typedef struct prt_paint_brush {
    float centre[3];   /* world position, on the surface */
    /* The surface's normal at centre (prt_painter_pick's): texels whose normals turn more than
     * 90 degrees from it - the far side of a thin wall, the inside of a tube - are left alone.
     * All zero: any texel. */
    float normal[3];
    float radius;      /* world units, > 0: texels whose surface points lie within it */
    float rgb[3];      /* the light to paint (irradiance / pi, >= 0); zero erases */
    /* How far each dab moves a texel's light towards rgb: 0 = 1 (all the way). The outer quarter
     * of the radius fades out, so strokes have soft edges. */
    float opacity;
} prt_paint_brush;

/* One dab of the brush onto map (prt_painter_size's width x height RGB). *changed (may be NULL)
 * gets how many texels it touched. */
prt_status prt_painter_dab(const prt_painter *p, const prt_paint_brush *b, float *map, int *changed);

/* A painting as an image (.exr, .pfm, .hdr; .exr keeps half floats): texel row 0 (v near 0) at
 * the image's bottom, as prt export --maps writes maps. Loading checks the size against t's light
 * map and that every value is finite and >= 0; *out is malloc'd (free it). */
prt_status prt_paint_save(const char *path, const float *map, int width, int height);
prt_status prt_paint_load(const prt_transfer *t, const char *path, float **out);

#ifdef __cplusplus
}
#endif
#endif
