/* GL drawing shared by every target (headless EGL now, a window later): a program that draws
 * per-vertex linear radiance, and mesh upload. Requires a current OpenGL 3.3 core context. */
#ifndef PRT_RENDER_DRAW_H
#define PRT_RENDER_DRAW_H

#include "core/internal.h"
#include "prt/lighting.h"
#include "prt/render.h"
#include "render/light_map_gl.h"
#include "render/pixel_lights.h"
#include "render/volume_gl.h"
#include "render/sums_gl.h"

#include <epoxy/gl.h>

typedef struct prt__draw {
    GLuint program, vao, vbo_pos, vbo_rad, ibo;
    GLint u_mvp;
    size_t index_count;
    /* Glossy path: per-pixel evaluation of per-vertex exit SH held in a texture buffer. */
    GLuint program_g, vbo_nrm, tbo, tbo_tex;
    GLint ug_mvp, ug_order, ug_mirror, ug_eye, ug_knorm, ug_exit;
    int exit_order, exit_mirror;
    float *pack;            /* staging for the RGBA texel layout */
    size_t pack_vertices;
    /* Per-texel path: radiance map sampled at interpolated uv. */
    GLuint program_t, vbo_uv, tex;
    GLint ut_mvp, ut_map;
    int texel_width, texel_height;   /* 0: the per-texel path is off */
    bool has_uv;
    /* Separable view factor: K-vectors and view-map sets in a texture buffer, view maps in a
     * texture array. */
    GLuint program_s, tbo_k, tbo_k_tex, maps_tex, tbo_set, tbo_set_tex;
    GLint us_mvp, us_eye, us_terms, us_polar, us_kvec, us_maps, us_kset;
    int kvec_terms, view_polar;
    uint8_t *view_set;               /* a copy, for K-vector updates */
    float *kpack;
    size_t kpack_vertices;
    /* Local lights drawn per pixel with shadow maps, added after the main pass. */
    prt__pixel_lights lights;
    /* Light maps finished on the GPU: the final light map goes into tex, the first-order one
     * into tex_first, drawn beside it when side_by_side. */
    prt__light_map_gl light_map;
    GLuint tex_first;
    bool side_by_side;
    int gpu_width, gpu_height;   /* tex and tex_first allocated as render targets of this size (0: not) */
    /* Participating media as slices (the window's; prt_render ray-marches them on the CPU). */
    prt__volume_gl volumes;
    /* Per-vertex light finished on the GPU (prt_render_sums) into vbo_rad; vbo_rad2 its scratch. */
    prt__sums_gl sums;
    GLuint vbo_rad2;
    size_t rad2_vertices;
    const prt_context *ctx;      /* where notes go (the renderer's), may be NULL */
} prt__draw;

/* Compiles and links vs (+ gs, may be NULL) + fs; 0 after recording the compiler's message. */
GLuint prt__gl_program(const char *vs_src, const char *gs_src, const char *fs_src);
prt_status prt__draw_init(prt__draw *d);
void prt__draw_free(prt__draw *d);
/* Uploads geometry and radiance (re-uploads everything; the radiance changes per relight). Fails
 * only where the mesh asks for GPU accumulation the GPU cannot run. */
prt_status prt__draw_upload(prt__draw *d, const prt_render_mesh *mesh);
/* Runs the GPU passes of mesh's gpu_* fields into the per-texel map (the description's atlases
 * uploaded when new); nothing when mesh has no gpu_passes. */
prt_status prt__draw_upload_gpu(prt__draw *d, const prt_render_mesh *mesh);
/* Replaces the lights drawn per pixel, the albedo and glossy materials they shade (mesh's lights,
 * albedo, light_visibility, light_material; none when it has no lights, albedo or normals). */
void prt__draw_set_lights(prt__draw *d, const prt_render_mesh *mesh);
/* Replaces the vertices' radiance with mesh's radiance plus its gpu_sums from gpu_vector (when
 * it has them). */
prt_status prt__draw_upload_sums(prt__draw *d, const prt_render_mesh *mesh);
/* Replaces the per-texel radiance map; NULL turns the per-texel path off (vertex radiance). */
void prt__draw_upload_texels(prt__draw *d, const float *rgb, int width, int height);
/* Replaces the glossy exit coefficients (mesh layout: vertex, channel, coefficient). */
void prt__draw_upload_exit(prt__draw *d, const float *exit_sh, size_t vertex_count);
/* Replaces the K-vectors (prt_render_mesh.kvec layout). */
void prt__draw_upload_kvec(prt__draw *d, const float *kvec, size_t vertex_count);
/* Draws into the bound framebuffer of size w x h. */
void prt__draw_mesh(prt__draw *d, const prt_camera *cam, int w, int h, const float background[3]);
/* An offscreen multisampled float framebuffer, resolved into a float texture that can be read
 * back (screenshots, prt_render) or drawn to a window with tone mapping. */
typedef struct prt__target {
    int width, height, samples;
    GLuint fbo_ms, color_ms, depth_ms, fbo, color_tex;
} prt__target;

prt_status prt__target_init(prt__target *t, int width, int height, int samples);
void prt__target_free(prt__target *t);
/* Draws the mesh into the target and resolves it. */
void prt__target_draw(prt__target *t, prt__draw *d, const prt_camera *cam, const float background[3]);
/* The same, in bands of rows for big images, asking ctx's cancel hook between them; false when
 * it said stop (ctx NULL: one pass, never stopped). */
bool prt__target_draw_cancellable(prt__target *t, prt__draw *d, const prt_camera *cam, const float background[3], const prt_context *ctx);
/* Reads the resolved linear radiance, top row first. */
prt_status prt__target_read(const prt__target *t, prt_image *out);

/* Column-major view-projection matrix for a camera. */
void prt__camera_matrix(const prt_camera *cam, float aspect, float near_far[2], float out[16]);

#endif
