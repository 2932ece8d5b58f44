/* prt/render.h - OpenGL 3.3 core drawing of relit meshes, headless through EGL.
 *
 * A prt_renderer owns a GL context (EGL surfaceless on Mesa when there is no display or GPU)
 * and an offscreen float framebuffer. It draws what relighting produced - per-vertex linear
 * radiance - and reads it back as a linear prt_image. Use from the creating thread only. */
#ifndef PRT_RENDER_H
#define PRT_RENDER_H

#include "prt/base.h"
#include "prt/image.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct prt_renderer prt_renderer;

#define PRT_MAX_PIXEL_LIGHTS 8   /* lights a renderer draws per pixel; the rest stay per vertex */
/* Which light a relit result (prt_relight_desc.component) or a GPU-finished light map holds. */
enum { PRT_COMPONENT_ALL = 0, PRT_COMPONENT_DIRECT, PRT_COMPONENT_INDIRECT };

typedef struct prt_renderer_desc {
    int width, height;       /* 0 = 800 x 600 */
    int samples;             /* MSAA samples; 0 = 4 */
} prt_renderer_desc;

typedef struct prt_camera {
    float eye[3], target[3], up[3];  /* up all zero = +y */
    float fov_y_deg;                 /* 0 = 40 */
} prt_camera;

/* ---- Light maps finished on the GPU ----
 * A light map of width x height texels, `covered` of them on the surface, and passes over it
 * described as data (as sokol or bgfx take buffers and images): the renderer knows no method. A
 * pass over a set of maps adds, for every map k and texel t, map_k(t) x light(source(t + dt_k)),
 * where source(u) is the covered texel u reads its light from (itself, or the one that fills its
 * gutter). The order is fixed:
 *   sub   = the scatter set's pass over the input (when it has maps),
 *   first = albedo x input, or sub on texels whose scatter_mask is set,
 *   b_1   = the bounce set's pass over first, b_k = its pass over b_(k-1), for gpu_bounces passes,
 *   final = first + emission scale x emission, less the light drawn per pixel
 *           (prt_render_mesh.gpu_pixel_direct) and clamped at zero (PRT_COMPONENT_DIRECT), sum
 *           of b_k (INDIRECT; smoothed over its chart with smooth_radius), or both (ALL).
 * The maps are uploaded packed into square texture-array atlases as the slices say (the method
 * packs them: rectangles of its maps, each placed in one atlas layer). */
typedef struct prt_render_slice {
    int map;                  /* which map of the set */
    int x, y, w, h;           /* the light-map texels it covers */
    int layer, ax, ay;        /* where they lie in the atlas array */
} prt_render_slice;

typedef struct prt_render_map_set {
    int map_count;            /* 0: the set is absent */
    const float *maps;        /* [map][covered][3]: map k at covered texel i */
    const int *offsets;       /* [map][2]: the shift dt_k, texels */
    int slice_count;
    const prt_render_slice *slices;
    int atlas_size, atlas_layers;   /* layers of atlas_size^2 texels (a power of two) */
    /* [map] the level (0..15) of the light's pyramid each map reads (NULL: every map reads
     * single texels): over the four blocks of 2^l x 2^l texels around the texel read, bilinearly
     * weighted, each block whose surface is all on that texel's chart by its area-weighted mean
     * light, any other by the level below's light (prt_render_passes.area, .chart;
     * methods/offset/prefilter.c). */
    const uint8_t *levels;
} prt_render_map_set;

typedef struct prt_render_passes {
    uint64_t id;              /* the renderer keeps one upload per id: equal ids describe equal data */
    int width, height;
    size_t covered;
    const uint32_t *texel;    /* [covered] y * width + x, increasing */
    const int32_t *source;    /* [width * height] the covered texel each texel reads, -1 none */
    const float *albedo;      /* [covered][3] */
    const uint8_t *scatter_mask;   /* [covered] non-zero: the scatter pass replaces albedo x input; NULL: nowhere */
    const float *emission;    /* [covered][3] radiance at emission scale 1; NULL: none */
    const float *area;        /* [covered] world area of each texel's surface; with levels */
    const int32_t *chart;     /* [covered] the UV chart of each texel (under 2^24; negative: the texel
                               * is no block's with others, it reads single texels); with levels */
    prt_render_map_set scatter, bounce;
    /* With levels: the bounced light (the sum of b_k) each texel shows is the mean over the
     * covered texels of its chart within smooth_radius texels in x and y, weighted by
     * (r + 1 - |dx|) (r + 1 - |dy|) x area x max(0, n . n')^32 (normal: [covered][3], unit; a
     * texel with a negative chart keeps its own); 0 (or normal NULL): none; at most 64
     * (methods/offset/smooth.c). */
    int smooth_radius;
    const float *normal;
} prt_render_passes;

/* ---- Per-vertex light finished on the GPU ----
 * Sparse products over RGB vectors, described as data (the renderer knows no method): product k
 * computes for each of its rows r
 *     y_k[r] = scale[r] * f(sum over entries e of row r of weight[e] * x_k[index[e]])
 * per channel, where x_k is the per-frame vector (prt_render_mesh.gpu_vector) when input is -1,
 * or product input's y (input < k); f clamps at zero when clamp is set; scale NULL is 1. Every
 * product with `shown` set is added row by row to the first vertices' prt_render_mesh.radiance
 * (the part the CPU computed; a mesh may have more vertices, a probe's sphere after them). A method builds the description once per file (lighting projected per
 * cluster, or a light vector, is all that changes per frame); the renderer uploads it once per id
 * into buffer textures and runs one transform-feedback pass per product. Where the GL limits or
 * memory do not allow, it evaluates the same products on the CPU and says so once. */
typedef struct prt_render_product {
    int input;                /* -1: gpu_vector; j < k: product j's rows */
    size_t rows;
    const uint32_t *start;    /* [rows + 1] row r's entries are start[r] .. start[r + 1] - 1 */
    const uint32_t *index;    /* [entries] the input row each entry reads */
    const float *weight;      /* [entries][3] */
    const float *scale;       /* [rows][3], or NULL */
    int clamp, shown;
    /* Non-zero: the rows are the glossy exit SH coefficients (vertex v's coefficient i at row
     * v * exit_order^2 + i; prt_render_mesh.exit_order), drawn in place of exit_sh (which may then
     * be NULL). At most one product. */
    int exit;
    /* Non-zero: the rows are the separable view factor's light-dependent terms (vertex v's term k
     * at row v * kvec_terms + k; prt_render_mesh.kvec_terms), drawn in place of kvec (which may
     * then be NULL). At most one product. */
    int kvec;
    /* Optional, for what sums cannot say (ratios, roots): a function applied to each row last,
     *     y[r] = map(y[r], a_0, .., a_{map_argc - 1}),
     * a_j read from map_args[j] (product j < k, or -1: gpu_vector) at row r, or at row 0 where
     * that has one row. Given twice by the description's builder, the same in float: map_glsl
     * the body of GLSL's `vec3 map(vec3 y, vec3 a0, vec3 a1, vec3 a2)` (unused arguments are
     * zero), map_cpu the C. NULL map_glsl: none. */
    const char *map_glsl;
    void (*map_cpu)(const float y[3], const float *const a[3], float out[3]);
    int map_argc;
    int map_args[3];
} prt_render_product;

typedef struct prt_render_sums {
    uint64_t id;              /* the renderer keeps one upload per id: equal ids describe equal data */
    size_t vector_length;     /* RGB entries of gpu_vector */
    int product_count;
    const prt_render_product *products;
} prt_render_sums;

/* Adds the shown products of s, evaluated on the CPU from vector, to rgb (vertex_count RGB): the
 * same sums as the GPU's passes, to float rounding. */
prt_status prt_render_sums_cpu(const prt_render_sums *s, const float *vector, size_t vertex_count, float *rgb);
/* The exit product's rows on the CPU as prt_relit.exit_sh lays them out ([vertex][channel][n],
 * n = order^2, vertex_count vertices); fails when s has none or its rows do not fit. */
prt_status prt_render_sums_exit_cpu(const prt_render_sums *s, const float *vector, size_t vertex_count, int order, float *exit_sh);
/* The exit product of s, or NULL. */
const prt_render_product *prt_render_sums_exit_product(const prt_render_sums *s);
/* The kvec product's rows on the CPU as prt_relit.kvec lays them out ([vertex][term][channel]);
 * fails when s has none or its rows do not fit. */
prt_status prt_render_sums_kvec_cpu(const prt_render_sums *s, const float *vector, size_t vertex_count, int terms, float *kvec);
/* The kvec product of s, or NULL. */
const prt_render_product *prt_render_sums_kvec_product(const prt_render_sums *s);

/* Borrowed arrays describing what to draw. */
/* A participating medium the renderer ray-marches over the surfaces (depth-correct: each pixel's
 * march ends at the first surface it meets): dims voxels spanning lo..hi (x fastest; values at
 * voxel centres, trilinear between them), the extinction per world unit, and the radiance the
 * medium scatters per unit extinction as SH (source_order 1 or 2) of the direction the light
 * travels, that is the view ray's: L = integral T(t) sigma_t(t) S(t, d) dt + T(end) L(end). */
typedef struct prt_render_volume {
    int dims[3];
    float lo[3], hi[3];
    const float *extinction;     /* [voxel] */
    const float *source;         /* [voxel][3][source_order^2] */
    int source_order;
} prt_render_volume;

typedef struct prt_render_mesh {
    const float *positions;      /* 3 per vertex */
    const float *radiance;       /* 3 per vertex, linear (view-independent part) */
    size_t vertex_count;
    const uint32_t *indices;     /* 3 per triangle */
    size_t triangle_count;
    /* Optional view-dependent part (glossy PRT): per vertex 3 x exit_order^2 SH coefficients
     * (prt_relit.exit_sh), interpolated and evaluated per pixel at the view
     * direction, or at its mirror about the interpolated normal when exit_mirror is set; the
     * result (clamped at zero) is added to radiance. normals are required with it. */
    const float *normals;
    const float *exit_sh;
    int exit_order;              /* 0 = none; 1..10 */
    int exit_mirror;
    /* Optional per-texel radiance (prt_relit.texels): a texel_width x
     * texel_height RGB map, row 0 at v near 0, sampled bilinearly per pixel at the vertices'
     * interpolated uv (2 per vertex) in place of `radiance`. */
    const float *uv;
    const float *texel_radiance;
    int texel_width, texel_height;
    /* Optional separable view factor (Wang, Tran & Luebke 2005): per vertex kvec_terms RGB
     * light-dependent terms g_k (prt_relit.kvec) and its view-map set (0: none), the view maps
     * ([set][term][channel][res][res], prt_relit.view_maps). Per pixel each corner's
     * sum_k h_k(wo) g_k is evaluated at the pixel's view direction in the frame of the
     * interpolated normal, blended by barycentrics and added to radiance. Needs normals. */
    const float *kvec;
    int kvec_terms;
    const uint8_t *view_set;
    const float *view_maps;
    int view_map_sets, view_map_resolution, view_map_polar;
    /* Optional local lights drawn per pixel (methods that relight local lights leave their
     * direct light out of radiance): each pixel is shaded as a Lambertian surface of the
     * interpolated albedo (3 per vertex) under these lights (at most 8; units of prt/lighting.h),
     * with shadows from shadow maps (cube maps for point, spot and sphere lights, soft edges for
     * spheres; an orthographic map for directional ones), added to radiance. Needs normals. */
    const struct prt_light *lights;
    int light_count;
    const float *albedo;
    /* Optional, per light and vertex ([light][vertex]): 0 where the vertex cannot see the light
     * (shadow rays); a triangle none of whose vertices sees a light gets none of it, whatever its
     * shadow map says. NULL = the shadow maps alone. */
    const float *light_visibility;
    /* Optional, with lights: per vertex 0 = Lambertian, k = light_brdfs[k - 1], whose glossy part
     * (prt_brdf_eval_glossy) is added per pixel at the view direction, in the frame of the
     * interpolated normal (prt_brdf_frame; a sphere light's at the direction of its centre); a
     * triangle takes one of its vertices' material (they differ only where surfaces meet). */
    const uint8_t *light_material;
    const struct prt_brdf *light_brdfs;
    int light_brdf_count;
    /* Optional: a light map the GPU finishes (prt_render_passes: the modulate-shift-accumulate
     * passes of offset radiance transfer maps). The renderer uploads the description's maps once
     * per id, then on each upload runs its passes from gpu_input (width x height RGB irradiance /
     * pi, zero off the surface) - the scatter set, the first-order light, gpu_bounces passes of
     * the bounce set, the final combination for gpu_component (PRT_COMPONENT_* above)
     * with gpu_emission times the emission - and draws the result per texel (needs uv;
     * texel_width x texel_height as the description's). prt_relit_render_mesh fills these from
     * what relighting with prt_relight_desc.gpu_finish gave. */
    const struct prt_render_passes *gpu_passes;
    const float *gpu_input;
    float gpu_emission;
    int gpu_bounces, gpu_component;
    /* Optional with gpu_passes: width x height RGB (as gpu_input), light drawn per pixel
     * (`lights`) that the shown maps leave out: first-order and final light are
     * max(first + emission - gpu_pixel_direct, 0) (plus the bounces), as the CPU's map.
     * NULL = none. */
    const float *gpu_pixel_direct;
    /* Optional: per-vertex light the GPU adds to radiance (prt_render_sums above) from the
     * per-frame vector gpu_vector (vector_length RGB). prt_relit_render_mesh fills these from
     * what relighting with prt_relight_desc.gpu_finish gave. */
    const struct prt_render_sums *gpu_sums;
    const float *gpu_vector;
    /* With gpu_passes: the first-order light map on the left half of the image, the final one
     * on the right (the paper's side-by-side viewer). */
    int side_by_side;
    /* Optional participating media drawn over the surfaces (prt_relit.volumes). */
    const prt_render_volume *volumes;
    int volume_count;
} prt_render_mesh;

prt_status prt_renderer_create(prt_context *ctx, const prt_renderer_desc *desc, prt_renderer **out);
void prt_renderer_release(prt_renderer *r);
/* How prt_render draws media (prt_render_mesh.volumes): 0 (the default) ray-marched per pixel
 * on the CPU; 1 as the viewer draws them, slices through 3D textures blended by OpenGL (faster,
 * coarser). */
void prt_renderer_set_volume_slices(prt_renderer *r, int on);
/* background: linear RGB behind the mesh (NULL = black). */
prt_status prt_render(prt_renderer *r, const prt_render_mesh *mesh, const prt_camera *cam,
                      const float background[3], prt_image *out);
/* The per-texel light map the renderer draws for mesh (texel_width x texel_height RGB, row 0 at v
 * near 0) read back: for light maps finished on the GPU (gpu_passes) the passes' result, and in
 * first_rgb (may be NULL) the first-order map; else texel_radiance as uploaded.
 * Fails when the mesh draws no per-texel map, or first_rgb is asked of one not GPU-finished. */
prt_status prt_render_light_map(prt_renderer *r, const prt_render_mesh *mesh, float *rgb, float *first_rgb);
/* The per-vertex radiance the renderer draws for mesh (vertex_count RGB) read back: radiance
 * plus what gpu_sums added on the GPU (or on the CPU where the GPU could not). */
prt_status prt_render_vertex_radiance(prt_renderer *r, const prt_render_mesh *mesh, float *rgb);
/* Where mesh's gpu_sums were last evaluated: 1 on the GPU, 0 on the CPU (the GL limits or memory
 * did not allow), -1 when the mesh has none. */
int prt_render_sums_on_gpu(const prt_renderer *r);
/* Buffer-texture texels the GPU sums may use: 0 = what the GL allows (the default); fewer make
 * bigger descriptions fall back to the CPU, as a smaller GPU would. */
void prt_renderer_limit_buffer_texels(prt_renderer *r, size_t texels);
/* A camera that frames the box [lo, hi] from direction `from` (towards the eye; NULL = a
 * default three-quarter view). */
void prt_camera_frame(const float lo[3], const float hi[3], const float *from, float fov_y_deg,
                      float aspect, prt_camera *out);
/* Auto framing for a mesh (positions, triangles): prt_camera_frame's view of its box, unless the
 * mesh closes around a point near its centre (a room, the Cornell box, a courtyard: from there
 * most directions meet surfaces facing it). Then the camera is inside, backed towards the wall in
 * direction `from`, looking across, with a 70 degree field of view unless fov_y_deg > 0 asks
 * otherwise. Returns 1 for a view from inside, 0 otherwise. ctx may be NULL (outside only). */
int prt_camera_frame_mesh(prt_context *ctx, const float *positions, size_t vertex_count, const uint32_t *indices, size_t triangle_count,
                          const float *from, float fov_y_deg, float aspect, prt_camera *out);
/* The GL renderer string, for reports ("llvmpipe ..."). */
const char *prt_renderer_name(const prt_renderer *r);

/* A window (GLFW, OpenGL 3.3 core) drawing exactly what prt_render draws - the same shaders
 * into the same float framebuffer - then tone-mapped for the screen as prt_image_save tone-maps
 * PNGs, with an optional text overlay. Needs a display: without one, prt_window_create fails
 * with PRT_ERR_BACKEND and says so. Use from the creating thread only. */
typedef struct prt_window prt_window;

typedef struct prt_window_desc {
    int width, height;       /* 0 = 1024 x 768 */
    int samples;             /* MSAA samples; 0 = 4 */
    const char *title;       /* NULL = "prt" */
} prt_window_desc;

typedef enum prt_event_type {
    PRT_EVENT_NONE = 0,
    PRT_EVENT_KEY,           /* key, action, mods */
    PRT_EVENT_BUTTON,        /* button (0 left, 1 right, 2 middle), action, mods, x, y */
    PRT_EVENT_MOVE,          /* x, y: cursor position in framebuffer pixels from the top left */
    PRT_EVENT_SCROLL,        /* y: wheel steps */
    PRT_EVENT_CLOSE          /* the window was asked to close */
} prt_event_type;

enum { PRT_MOD_SHIFT = 1, PRT_MOD_CTRL = 2, PRT_MOD_ALT = 4 };
enum { PRT_ACTION_RELEASE = 0, PRT_ACTION_PRESS = 1, PRT_ACTION_REPEAT = 2 };
/* Key codes are GLFW's: printable keys are their upper-case ASCII code, PRT_KEY_ESCAPE etc. */
enum { PRT_KEY_ESCAPE = 256, PRT_KEY_TAB = 258, PRT_KEY_F12 = 301 };

typedef struct prt_event {
    prt_event_type type;
    int key, button, action, mods;
    double x, y;
} prt_event;

prt_status prt_window_create(prt_context *ctx, const prt_window_desc *desc, prt_window **out);
void prt_window_release(prt_window *w);
/* Next pending input event; returns 0 when there is none (it polls the system first). */
int prt_window_next_event(prt_window *w, prt_event *ev);
/* Blocks until an event arrives or timeout seconds pass. */
void prt_window_wait(prt_window *w, double timeout);
/* Geometry and radiance to draw (copied to the GPU); set_radiance replaces the colours only. */
void prt_window_set_mesh(prt_window *w, const prt_render_mesh *mesh);
void prt_window_set_radiance(prt_window *w, const float *rgb, size_t vertex_count);
/* Replaces the lights drawn per pixel and their albedo (mesh's lights, light_count, albedo and
 * positions; the geometry must be the one given to set_mesh). */
void prt_window_set_lights(prt_window *w, const prt_render_mesh *mesh);
/* Replaces the media drawn (mesh's volumes, relit: their source changes with the lighting). */
void prt_window_set_volumes(prt_window *w, const prt_render_mesh *mesh);
/* Replaces the per-texel radiance map (needs the mesh's uv); NULL switches back to vertex radiance. */
void prt_window_set_texels(prt_window *w, const float *rgb, int width, int height);
/* Replaces the GPU-finished input (mesh's gpu_* fields, the transfer given to set_mesh) and runs
 * the accumulation passes again; side_by_side as in prt_render_mesh. */
void prt_window_set_gpu_input(prt_window *w, const prt_render_mesh *mesh);
/* Replaces the per-vertex radiance and runs the mesh's gpu_sums again from its gpu_vector (the
 * description given to set_mesh, or a new one). */
void prt_window_set_gpu_sums(prt_window *w, const prt_render_mesh *mesh);
/* Replaces the glossy exit coefficients (same layout and order as given to set_mesh). */
void prt_window_set_exit(prt_window *w, const float *exit_sh, size_t vertex_count);
/* Replaces the wavelet K-vectors (same layout as prt_render_mesh.kvec). */
void prt_window_set_kvec(prt_window *w, const float *kvec, size_t vertex_count);
/* Draws and presents. tonemap: 0/1 Reinhard, 2 clamp (as prt_image_save_desc). overlay: text
 * drawn at the top left, NULL for none. */
prt_status prt_window_draw(prt_window *w, const prt_camera *cam, const float background[3], float exposure_stops, int tonemap,
                           const char *overlay);
/* The linear radiance of the last draw, without the overlay: what prt_render would return. */
prt_status prt_window_read(prt_window *w, prt_image *out);
void prt_window_size(const prt_window *w, int *width, int *height);

#ifdef __cplusplus
}
#endif
#endif
