/* prt/wavelet.h - all-frequency relighting of glossy objects (Wang, Tran & Luebke 2005).
 *
 * Lighting is a 6 x 64 x 64 cube map of radiance in the orthonormal 2D Haar basis (per face).
 * Each BRDF is approximated as f(wi, wo) ~ sum_k g_k(wi) h_k(wo) (prt_brdf_factor); a vertex
 * stores one sparse transport vector per term,
 *     T_k[j] = g_k(w_j) V(w_j) max(n.w_j, 0) dw_j        (direct; eq. 3)
 * plus the bounced vectors gathered over a cube map of hit points (eq. 8), as the N largest Haar
 * coefficients quantized to 8 or 16 bits per colour channel. Relighting is
 *     g_k = T_k . L  (the light-dependent K-vector, per lighting change)
 *     L_out(wo) = sum_k h_k(wo) g_k   (per view change).
 * Lambertian vertices (no glossy material) have one term with g = 1 and h = albedo / pi: this is
 * Ng et al. 2003's diffuse all-frequency PRT. The set lives in a prt_transfer with the mesh and
 * is saved in the same .prt container.
 * prt-method: wavelet */
#ifndef PRT_WAVELET_H
#define PRT_WAVELET_H

#include "prt/base.h"
#include "prt/brdf.h"
#include "prt/haar.h"
#include "prt/lighting.h"
#include "prt/scene.h"
#include "prt/transfer.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PRT_WAVELET_FACE 64
#define PRT_WAVELET_DIM (6 * PRT_WAVELET_FACE * PRT_WAVELET_FACE)   /* 24,576 */

typedef struct prt_wavelet_bake_desc {
    int terms;             /* K, separable terms per glossy BRDF, 1..16; 0 = 4 */
    int coefficients;      /* N, Haar coefficients kept per transport vector, 1..24576; 0 = 128 */
    int bits;              /* quantization per colour channel: 8 or 16; 0 = 8 */
    int supersample;       /* visibility rays per cube texel side (1 = one ray per texel), 1..4; 0 = 2 */
    int bounces;           /* interreflection passes, 0..8 (0 = direct light only) */
    int gather_resolution; /* hit-point cube map per side for the passes, 4..64; 0 = 32 */
    int brdf_resolution;   /* light and view map size, 4..96; 0 = 48 */
    prt_brdf_param param;  /* BRDF parameterization; 0 = grid (eq. 10) */
    const prt_brdf *brdf;  /* a BRDF for every vertex instead of the scene's materials, or NULL */
    float ray_offset;      /* origin offset along the normal; 0 = 1e-4 x bbox diagonal */
    prt_progress_fn progress;
    void *progress_user;
} prt_wavelet_bake_desc;

prt_status prt_bake_wavelet(prt_context *ctx, const prt_scene *scene, const prt_wavelet_bake_desc *desc, prt_transfer **out);

typedef struct prt_wavelet_info {
    int terms, coefficients, bits, supersample, bounces, gather_resolution, brdf_resolution;
    prt_brdf_param param;
    size_t vectors;         /* transport vectors in all */
    size_t bytes;           /* their storage (indices, values, scales) */
    int glossy_materials;   /* materials with a factored BRDF */
} prt_wavelet_info;

/* 0 when t holds no wavelet transfer. */
int prt_transfer_wavelet_info(const prt_transfer *t, prt_wavelet_info *info);
/* Terms of vertex v (1 for Lambertian vertices). */
int prt_transfer_wavelet_vertex_terms(const prt_transfer *t, size_t v);
/* The factorization of material k (1-based), NULL for Lambertian materials. */
const prt_brdf_factors *prt_transfer_wavelet_factors(const prt_transfer *t, int k);

/* ---- Lighting ---- */
typedef struct prt_wavelet_light_desc {
    int coefficients;      /* largest Haar coefficients kept, 1..24576; 0 = 4096 */
    int bits;              /* 16, or 32 for unquantized floats; 0 = 16 */
    double rotation[9];    /* lighting from d now arrives from R d; all zero = none */
    float intensity;       /* radiance scale of the environment; 0 = 1 */
    int supersample;       /* no longer used (areas are exact); 0..16 accepted */
    /* Directional lights (world frame, not rotated, not scaled): each adds its irradiance as a
     * delta, E over the solid angle of the texel its direction falls in. */
    const prt_light *lights;
    int light_count;
} prt_wavelet_light_desc;

typedef struct prt_wavelet_light prt_wavelet_light;

/* Integrates env into the cube map, each map pixel's energy split among the texels it covers by
 * exact area (through a finer 6 x 256 x 256 cube the map keeps after the first call, whose texels
 * a rotation splits the same way), so small bright sources keep their energy under any rotation;
 * adds the directional lights; transforms each face, keeps the largest coefficients and
 * quantizes them. env may be NULL when desc names directional lights. */
prt_status prt_wavelet_light_create(prt_context *ctx, const prt_envmap *env, const prt_wavelet_light_desc *desc,
                                    prt_wavelet_light **out);
void prt_wavelet_light_release(prt_wavelet_light *l);
/* The radiance cube map before the transform: [texel][3], texel index (face * 64 + y) * 64 + x. */
const float *prt_wavelet_light_cubemap(const prt_wavelet_light *l);
/* Kept coefficients after quantization, [index][4] (RGB and a zero pad), zero where dropped. */
const float *prt_wavelet_light_coeffs(const prt_wavelet_light *l);
int prt_wavelet_light_kept(const prt_wavelet_light *l);

/* Light-dependent K-vectors: out[(v * terms + k) * 3 + c] with terms = info.terms (unused
 * terms of a vertex are zero). Recompute when the lighting changes. */
prt_status prt_relight_wavelet(prt_context *ctx, const prt_transfer *t, const prt_wavelet_light *light, float *out_kvec);
/* Exit radiance per vertex towards eye (a world position): the view maps at each vertex's view
 * direction dotted with its K-vector, clamped at zero (a few separable terms can undershoot).
 * Recompute when the view changes. With eye NULL only the
 * Lambertian vertices are shaded (their radiance does not depend on the view) and the glossy
 * ones get zero: the renderer adds their view factor per pixel (prt_render_mesh.kvec). */
prt_status prt_wavelet_shade(prt_context *ctx, const prt_transfer *t, const float *kvec, const float eye[3], float *out_rgb);

/* What the renderer needs to evaluate the view factor per pixel: the view maps of the file's
 * factored materials as one array [set][term][channel][resolution][resolution] (terms = info.terms;
 * map row y, column x; borrowed until t is released), and per vertex its set (0: Lambertian,
 * s: the s-th factored material). Returns 0 when the file has no factored material. The first
 * call builds the arrays inside t: make it before sharing t between threads. */
int prt_wavelet_view_maps(const prt_transfer *t, const float **maps, int *sets, int *resolution, int *polar, const uint8_t **vertex_set);

/* Vertex v's term k decoded: its kept coefficients' indices and RGB values (dequantized), at
 * most info.coefficients of each; returns how many (0 when v or k is out of range). */
int prt_transfer_wavelet_vector(const prt_transfer *t, size_t v, int k, int *index, float *rgb);

/* Cube map geometry, for tests and tools: the unit direction through the centre of texel i and
 * its solid angle. */
void prt_wavelet_texel(int index, float dir[3], float *solid_angle);

#ifdef __cplusplus
}
#endif
#endif
