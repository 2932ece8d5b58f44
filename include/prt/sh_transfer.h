/* prt/sh_transfer.h - the SH method's own API: spherical-harmonic PRT (Sloan, Kautz & Snyder
 * 2002; Sloan et al. 2003), what a file of method "sh" holds beyond prt/method.h.
 * prt-method: sh
 *
 * An SH transfer set stores per vertex the vector T with exit radiance
 *     L_out(p) = sum_i L_i T_i(p)
 * for SH lighting L (prt_sh_light, prt/lighting.h). Sets with one channel exclude the albedo (it
 * is applied at relight time from the stored per-vertex albedo); three-channel sets include it,
 * because inter-reflection bleeds colour. Glossy sets hold a matrix per vertex and channel.
 * Every function here fails clearly (or returns 0) on other methods' files; the method table
 * (prt_bake, prt_relight, prt_transfer_describe) reaches every method, SH included. */
#ifndef PRT_SH_TRANSFER_H
#define PRT_SH_TRANSFER_H

#include "prt/base.h"
#include "prt/brdf.h"
#include "prt/compress.h"
#include "prt/image.h"
#include "prt/lighting.h"
#include "prt/scene.h"
#include "prt/transfer.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum prt_transfer_kind {
    PRT_TRANSFER_UNSHADOWED = 1,
    PRT_TRANSFER_SHADOWED = 2,
    PRT_TRANSFER_INTERREFLECTED = 4,
    /* Glossy transfer matrices (Sloan et al. 2002, section 6): per vertex and channel an
     * order^2 x order^2 matrix M from source lighting L to transferred incident radiance
     * M L (world frame, lower hemisphere cut off), or - with a BRDF baked in - to exit radiance.
     * Stored lighting-coefficient-major: M[j][i] is the response of incident coefficient i to
     * lighting coefficient j. */
    PRT_TRANSFER_GLOSSY_SHADOWED = 8,
    PRT_TRANSFER_GLOSSY_INTERREFLECTED = 16   /* diffuse-to-glossy and glossy-to-glossy bounces */
} prt_transfer_kind;

#define PRT_TRANSFER_ALL_KINDS 31u

typedef struct prt_sh_bake_desc {
    int order;            /* SH order (bands); 0 = 5 (25 coefficients); 1..10 */
    int samples;          /* directions per vertex over the sphere; 0 = 1024 */
    unsigned kinds;       /* OR of prt_transfer_kind; 0 = the three diffuse kinds */
    int bounces;          /* extra bounces for INTERREFLECTED; 0 = 3 */
    uint32_t seed;        /* rotates the low-discrepancy direction set; results are identical
                             for the same seed whatever the thread count */
    float ray_offset;     /* origin offset along the normal, scene units; 0 = 1e-4 x bbox diagonal */
    /* Glossy sets: 0 stores transferred incident radiance, convolved with a reflection lobe at
     * run time (prt_relight_sh_glossy); 1 bakes each vertex's scene material BRDF in (any
     * isotropic model, through its SH matrix), so the sets hold exit radiance. */
    int glossy_exit;
    const prt_brdf *glossy_brdf;   /* with glossy_exit: this BRDF for every vertex instead */
    /* Per-texel transfer (the diffuse kinds asked for) into a texels x texels map; 0 = none. Over
     * the layout uv_layout picks: a generated atlas copies the vertices on its seams, so the
     * transfer then has more vertices than the scene. */
    int texels;
    prt_uv_layout uv_layout;
    /* Tangent-space normal map for the per-texel transfer: RGB in [0, 1] as stored in the file
     * (0.5, 0.5, 1 = unperturbed; +y of the map along +v), or NULL. It follows the mesh's own
     * texture coordinates, so it cannot go with a generated atlas. */
    const prt_image *normal_map;
    /* Height map for the per-texel transfer (its first channel, [0, 1] as stored; white is
     * highest): its bumps shade the texels through the normals their slopes give (unless a
     * normal map does) and shadow one another (the course notes' self-shadowing bumps), so the
     * shadows move as the lighting turns. Follows the mesh's own texture coordinates, or NULL.
     * height_scale: world units of a stored 1; 0 = 1% of the scene's diagonal. */
    const prt_image *height_map;
    float height_scale;
    /* Millimetres per scene unit, the scale the scene's translucent materials (prt_scene_set_medium,
     * a JSON material's "subsurface") scatter light at in the inter-reflected transfer; 0 = 1000
     * (the scene is in metres). */
    float mm_per_unit;
    /* Neighbourhood transfer (Sloan et al. 2002): a grid of this many points along each axis of
     * the scene's bounding box grown on every side by a quarter of its largest extent (2..64; 0 = none), each holding
     * how the scene changes the distant lighting arriving there (prt_sh_light_at). */
    int neighbourhood;
    prt_progress_fn progress;
    void *progress_user;
} prt_sh_bake_desc;

/* Shows what a zero-initialised desc becomes. */
prt_sh_bake_desc prt_sh_bake_desc_defaults(void);

/* Deprecated names of prt 0.1 (the SH bake desc was the only one then): kept so that old
 * programs build and link; new code uses the names above. */
typedef prt_sh_bake_desc prt_bake_desc;
prt_sh_bake_desc prt_bake_desc_defaults(void);

prt_status prt_bake_sh(prt_context *ctx, const prt_scene *scene, const prt_sh_bake_desc *desc,
                       prt_transfer **out);

/* Method-independent facts plus, for SH files, the SH settings (order, kinds, samples, bounces,
 * seed, texels; zero for other methods). prt_transfer_describe covers every method, and
 * prt_transfer_bytes gives any file's transfer storage. */
typedef struct prt_transfer_info {
    size_t vertex_count, triangle_count;
    int order;                /* SH order of the sets */
    unsigned kinds;           /* which kinds the file holds */
    int samples, bounces;
    uint32_t seed;
    double bake_seconds;
    int threads;              /* threads the bake used (does not change the result) */
    size_t transfer_bytes;    /* bytes of all transfer sets (vertex and texel) */
    int texel_width, texel_height;   /* per-texel sets' size, 0 without */
    size_t texel_bytes;       /* bytes of the per-texel sets and their albedo */
    char source[512];         /* the scene the bake read */
} prt_transfer_info;

void prt_transfer_get_info(const prt_transfer *t, prt_transfer_info *info);
int prt_transfer_channels(const prt_transfer *t, prt_transfer_kind kind);  /* 0 if absent */
/* Borrowed pointer to a set's coefficients: vertex-major, channel, coefficient; NULL if absent. */
const float *prt_transfer_coeffs(const prt_transfer *t, prt_transfer_kind kind);

/* Neighbourhood transfer (prt_sh_bake_desc.neighbourhood): 1 and the grid (points per axis, its
 * corners; any may be NULL) when the transfer holds one, else 0. */
int prt_transfer_neighbourhood(const prt_transfer *t, int dims[3], float lo[3], float hi[3]);
/* The radiance arriving at point p under the distant light `light`, as SH (of the light's order,
 * at most the transfer's): the scene's shadow and the light its surfaces reflect included, so an
 * object at p - a probe, a character - is shadowed and lit by the baked scene. Trilinear between
 * the grid's points; outside the grid, its nearest face's. An error when there is no grid. */
prt_status prt_sh_light_at(prt_context *ctx, const prt_transfer *t, const float p[3], const prt_sh_light *light, prt_sh_light *out);

/* Exit radiance per vertex (RGB, 3 floats per vertex) under light. The light's order may differ
 * from the transfer's: the common bands are used. */
prt_status prt_relight_sh(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind,
                          const prt_sh_light *light, float *out_rgb);

/* Glossy relighting: per vertex 3 x order^2 SH coefficients (world frame) of view-dependent exit
 * radiance, for the renderer to evaluate per pixel (prt_render_mesh.exit_sh). For sets that hold
 * incident radiance, the reflection lobe comes from `brdf` (NULL: each vertex's material; Lambert
 * vertices get zero) and the result is to be evaluated at the mirror of the view direction; for
 * sets with the BRDF baked in, `brdf` must be NULL and the result is evaluated at the view
 * direction itself (see prt_transfer_glossy_mirror). */
prt_status prt_relight_sh_glossy(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light,
                                 const prt_brdf *brdf, float *out_exit);
/* 1 when glossy exit coefficients are evaluated at the mirror direction (run-time lobes), 0
 * when at the view direction (BRDF baked in). */
int prt_transfer_glossy_mirror(const prt_transfer *t);
/* Floats per vertex a set holds uncompressed: channels x order^2 (x order^2 for glossy sets). */
size_t prt_transfer_set_floats(const prt_transfer *t, prt_transfer_kind kind);
/* The diffuse kind that supplies the view-independent part beside a glossy kind. */
prt_transfer_kind prt_transfer_kind_diffuse_part(prt_transfer_kind glossy);
int prt_transfer_kind_is_glossy(prt_transfer_kind kind);
/* Per-texel transfer: its size (returns 0 when the file has none), a set's coefficients
 * ([texel][channel][order^2], row 0 at v near 0; channels as for vertex sets), and relighting into a width x height RGB radiance map (albedo
 * applied; row 0 at v near 0). */
int prt_transfer_texel_size(const prt_transfer *t, int *width, int *height);
const float *prt_transfer_texel_coeffs(const prt_transfer *t, prt_transfer_kind kind, int *channels);
prt_status prt_relight_sh_texels(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light,
                                 float *out_rgb);

const char *prt_transfer_kind_name(prt_transfer_kind kind);
/* Parses "unshadowed", "shadowed", "interreflected" (or their first letter), "glossy-shadowed",
 * "glossy-interreflected". */
prt_status prt_transfer_kind_parse(const char *name, prt_transfer_kind *out);

/* ---- Compression of SH sets (the algorithms' settings are prt/compress.h's) ---- */
/* Compresses every set of `in` into a new transfer (the mesh is copied). */
prt_status prt_transfer_compress(prt_context *ctx, const prt_transfer *in, const prt_compress_desc *desc, prt_transfer **out);
/* Rounds every uncompressed set to `bits` (8 or 16) per coefficient with a scale and bias per
 * coefficient index (each SH coefficient of each channel gets the range it uses over the mesh);
 * the file then stores the integers. Every value moves by at most half its scale. */
prt_status prt_transfer_quantize(prt_context *ctx, const prt_transfer *in, int bits, prt_transfer **out);
prt_status prt_transfer_compress_info(const prt_transfer *t, prt_transfer_kind kind, prt_compress_info *out);
/* Writes a set's coefficients (reconstructed when compressed), laid out as prt_transfer_coeffs. */
prt_status prt_transfer_reconstruct(const prt_transfer *t, prt_transfer_kind kind, float *out);

#ifdef __cplusplus
}
#endif
#endif
