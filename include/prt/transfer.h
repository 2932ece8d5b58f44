/* prt/transfer.h - baked radiance transfer and its .prt file, whatever the method.
 *
 * A prt_transfer holds the (possibly subdivided) mesh it was baked on, its materials and the
 * lighting its scene named, and the transfer of one method (prt/method.h: every method is
 * reached through the method table, which bakes, describes and relights any file; a method's own
 * API, for programs that want more, is in its header: prt/sh_transfer.h, prt/wavelet.h,
 * prt/spectral.h, prt/offset.h). Files are written atomically and validated on read; see
 * docs/FORMAT.md for the layout. */
#ifndef PRT_TRANSFER_H
#define PRT_TRANSFER_H

#include "prt/base.h"
#include "prt/brdf.h"
#include "prt/image.h"
#include "prt/lighting.h"
#include "prt/method.h"
#include "prt/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where per-texel transfer's UV layout comes from. */
typedef enum prt_uv_layout {
    PRT_UV_AUTO = 0,       /* the mesh's own when unique and inside [0, 1], else a generated atlas */
    PRT_UV_MESH = 1,       /* the mesh's own, or fail saying why it cannot be used */
    PRT_UV_GENERATE = 2    /* always a generated atlas (charts, least-squares conformal maps, gutters) */
} prt_uv_layout;

typedef struct prt_transfer prt_transfer;

void prt_transfer_release(prt_transfer *t);

/* Files. Saving is atomic (temporary + rename); loading checks magic, version, sizes and CRCs. */
prt_status prt_transfer_save(const prt_transfer *t, const char *path);
prt_status prt_transfer_load(prt_context *ctx, const char *path, prt_transfer **out);
prt_status prt_transfer_load_memory(prt_context *ctx, const void *data, size_t size, prt_transfer **out);

/* Key frames (prt_bake_frames): how many t holds (1: one pose), and the pose at time `time` in
 * frames (0: the first key frame, 0.5 halfway to the second, count - 1 the last) as a transfer of
 * one pose: positions, normals and transfer interpolated linearly between the two key frames
 * around it. Times outside [0, count - 1] are refused, not clamped; so is any time for a
 * transfer of one pose. */
int prt_transfer_frame_count(const prt_transfer *t);
prt_status prt_transfer_at_time(prt_context *ctx, const prt_transfer *t, double time, prt_transfer **out);

/* The lighting the baked scene named, if any (0 when none); see prt_scene_environment. */
int prt_transfer_environment(const prt_transfer *t, prt_environment_desc *out);

/* The mesh the transfer was baked on, and its UVs (2 per vertex, NULL without). */
size_t prt_transfer_vertex_count(const prt_transfer *t);
size_t prt_transfer_triangle_count(const prt_transfer *t);
const float *prt_transfer_positions(const prt_transfer *t);
const float *prt_transfer_normals(const prt_transfer *t);
const float *prt_transfer_albedo(const prt_transfer *t);
const uint32_t *prt_transfer_indices(const prt_transfer *t);
const float *prt_transfer_uvs(const prt_transfer *t);

/* Scene materials with a BRDF: count, and the model of material k (1-based, as per-vertex ids). */
int prt_transfer_brdf_count(const prt_transfer *t);
const prt_brdf *prt_transfer_brdf(const prt_transfer *t, int k);
const uint8_t *prt_transfer_materials(const prt_transfer *t);   /* per vertex; 0 = plain diffuse */
/* Named surfaces: the materials of the mesh files (usemtl in OBJ, glTF materials) or of a JSON
 * scene, in order of first appearance. Count, the name of surface k (1..count; NULL out of
 * range), and per vertex its surface (0 = unnamed; NULL when nothing is named). */
int prt_transfer_surface_count(const prt_transfer *t);
const char *prt_transfer_surface_name(const prt_transfer *t, int k);
const uint16_t *prt_transfer_surfaces(const prt_transfer *t);
/* Sets the albedo (3 floats per vertex, for example a copy of prt_transfer_albedo) of every
 * vertex of the surface called name to rgb, in [0, 1]: what prt_relight_desc.albedo takes for
 * methods that change colours at run time. An unknown name is an error that lists the names. */
prt_status prt_transfer_paint_albedo(const prt_transfer *t, const char *name, const float rgb[3], float *albedo);
/* BRDF sets: the candidate BRDFs the bake kept for named surface k (1..surface count), that
 * relighting switches among at run time (prt_relight_desc.brdf_of; a scene material's "brdfs",
 * docs/SCENE.md). Returns their count (0: none, or a method that keeps none); when i is in range,
 * *out gets entry i. The surface's baked BRDF is among them. */
int prt_transfer_brdf_set(const prt_transfer *t, int k, int i, prt_brdf *out);
/* CPU evaluation of glossy exit coefficients (prt_relit.exit_sh) for one vertex:
 * to_eye points from the surface to the viewer; normal is the shading normal. */
void prt_glossy_eval(int order, const float *exit_coeffs, int mirror, const float normal[3], const float to_eye[3], float rgb[3]);

#ifdef __cplusplus
}
#endif

/* prt 0.1 declared the SH method's API (prt_bake_desc, prt_bake_sh, prt_transfer_kind,
 * prt_relight_sh, ...) in this header: programs that include it alone still find it, in the SH
 * method's own header. */
#include "prt/sh_transfer.h"

#endif
