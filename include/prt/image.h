/* prt/image.h - linear float RGB images: .hdr, .pfm, .exr, .png in and out.
 * An image is a plain struct the caller owns after a load; release it with prt_image_free. */
#ifndef PRT_IMAGE_H
#define PRT_IMAGE_H

#include "prt/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct prt_image {
    int width, height;
    float *rgb;          /* width*height*3 floats, row 0 at the top, linear radiance */
} prt_image;

/* Loads .hdr (Radiance RGBE), .pfm, .exr or .png/.jpg (sRGB decoded to linear), chosen by the
 * file's contents. Rejects NaN or infinite pixels with PRT_ERR_FORMAT. */
prt_status prt_image_load(const char *path, prt_image *out);
prt_status prt_image_load_memory(const void *data, size_t size, prt_image *out);

typedef struct prt_image_save_desc {
    float exposure_stops;  /* PNG only: radiance is scaled by 2^exposure_stops; default 0 */
    int tonemap;           /* PNG only: 0 = default (Reinhard on luminance), 1 = Reinhard, 2 = clamp */
} prt_image_save_desc;

/* Saves by extension: .png (tone-mapped, sRGB 8-bit), .exr (linear half), .hdr, .pfm.
 * Written atomically: a temporary file is renamed over the target only when complete. */
prt_status prt_image_save(const char *path, const prt_image *img, const prt_image_save_desc *desc);
/* Saves count frames of one size as an animated PNG (APNG, .png only), looping, fps frames per
 * second (1..100), each tone-mapped as prt_image_save does; viewers without APNG show the first
 * frame. Written atomically. */
prt_status prt_image_save_animation(const char *path, const prt_image *frames, int count, int fps, const prt_image_save_desc *desc);
void prt_image_free(prt_image *img);

/* A mesh with per-vertex colours for other tools: glTF 2.0 (.glb, .gltf + .bin), PLY (.ply,
 * binary) or OBJ (.obj + .mtl, colours after each v). Written through assimp's exporter; every
 * file lands under its final name only when complete. The glTF passes the Khronos glTF-Validator:
 * positions and attributes must be finite and normals directions (written at unit length),
 * else PRT_ERR_INVALID_ARG. */
typedef enum prt_colour_encoding {
    PRT_COLOURS_DEFAULT = 0,   /* linear for glTF (its COLOR_0 is linear), sRGB for PLY and OBJ */
    PRT_COLOURS_SRGB,          /* sRGB-encoded, clamped to [0, 1]: what mesh viewers show as is */
    PRT_COLOURS_LINEAR         /* linear, clamped to [0, 1] (PLY keeps 8 bits: prefer glTF) */
} prt_colour_encoding;

typedef struct prt_mesh_export_desc {
    const float *positions, *normals;   /* 3 per vertex; normals may be NULL */
    size_t vertex_count;
    const uint32_t *indices;            /* 3 per triangle */
    size_t triangle_count;
    const float *rgb;                   /* 3 per vertex, linear radiance */
    prt_colour_encoding encoding;
    float exposure_stops;               /* radiance is scaled by 2^exposure_stops first */
    /* glTF only: more per-vertex data as custom attributes (VEC4 float each), written as colour
     * sets by assimp's exporter and then renamed; glTF wants such names to start with '_'. */
    int attribute_count;                /* 0..7 */
    const float *attributes;            /* 4 * attribute_count floats per vertex */
    const char *const *attribute_names; /* attribute_count names, each "_" then [A-Z0-9_], <= 31 bytes */
} prt_mesh_export_desc;

prt_status prt_mesh_export(const char *path, const prt_mesh_export_desc *desc);

#ifdef __cplusplus
}
#endif
#endif
