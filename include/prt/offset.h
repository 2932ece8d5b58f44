/* prt/offset.h - offset radiance transfer maps (Sunshine-Hill & Faloutsos 2006): what a file of
 * method "offset" holds. A light map of width x height texels over the mesh's UVs; for each of
 * `count` offsets dt and each transfer kind, a map whose texel t holds the transfer to t from the
 * surface the offset's cell stands for (the paper's TR(t, t + dt) TVA(t, dt), eq. 10): at run time
 * the first-order light map, shifted by dt, is multiplied by it and summed over the offsets (eq. 9)
 * - for the radiosity maps of far offsets, the light prefiltered to their cell's size
 * (prt_render_map_set.levels). The maps are what relighting for the GPU hands the renderer, sliced into atlases
 * (prt_relit.gpu_passes), and what prt export --maps writes as OpenEXR files with an index.
 * Everything else goes through prt/method.h.
 * prt-method: offset */
#ifndef PRT_OFFSET_H
#define PRT_OFFSET_H

#include "prt/base.h"
#include "prt/transfer.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum prt_offset_kind { PRT_OFFSET_RADIOSITY = 0, PRT_OFFSET_SUBSURFACE = 1 } prt_offset_kind;

typedef struct prt_offset_info {
    int width, height;        /* the light map, texels */
    int count;                /* offsets, one map per offset and kind */
    int covered;              /* texels on the surface */
    int has[2];               /* which kinds the file holds (prt_offset_kind) */
    int map_bounces;          /* bounces the radiosity maps hold: 1 (a pass per bounce) or 2..64 (one pass; 64: the whole series, the default) */
} prt_offset_info;

/* 1 and info filled when t is an offset file, else 0. */
int prt_transfer_offset_info(const prt_transfer *t, prt_offset_info *info);
/* Offset k's map of a kind as width x height RGB (row 0 at v near 0, zero off the surface) and
 * its offset in texels (dx, dy); rgb may be NULL to ask for the offset only. */
prt_status prt_transfer_offset_map(const prt_transfer *t, prt_offset_kind kind, int k, int offset[2], float *rgb);

/* Where each texel's light is read (width x height values, y * width + x): itself on the
 * surface, else the surface texel that fills its gutter (rings grown outwards from the charts,
 * each texel taking the source of its first neighbour - left, right, down, up - in the ring
 * before), -1 when the map holds no surface. The maps multiply the light at source(t + dt)
 * (prefiltered for far radiosity maps: prt_render_map_set.levels). */
prt_status prt_transfer_offset_sources(const prt_transfer *t, int32_t *source);

/* Which texels scatter under their surface: width x height values, 0 opaque, k the k-th medium
 * (as prt info lists them); fails when the file has no subsurface maps. */
prt_status prt_transfer_offset_medium(const prt_transfer *t, float *medium);

#ifdef __cplusplus
}
#endif
#endif
