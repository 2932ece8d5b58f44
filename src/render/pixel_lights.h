/* Local lights drawn per pixel with shadow maps: what methods that relight local lights leave out
 * of their per-vertex radiance (direct light per pixel, indirect light per vertex, as Wang, Zhu &
 * Humphreys 2007 draw it). Point, spot and sphere lights get a cube map of distances from the
 * light, directional lights an orthographic map; an additive pass shades each pixel as a
 * Lambertian surface of the interpolated albedo plus its material's glossy lobe at the view
 * direction, with percentage-closer filtering (and a blocker
 * search that widens the penumbra for sphere lights). Requires a current OpenGL 3.3 context. */
#ifndef PRT_RENDER_PIXEL_LIGHTS_H
#define PRT_RENDER_PIXEL_LIGHTS_H

#include "core/internal.h"
#include "prt/lighting.h"
#include "prt/render.h"

#include <epoxy/gl.h>

#define PRT__PIXEL_LIGHTS PRT_MAX_PIXEL_LIGHTS

typedef struct prt__pixel_lights {
    GLuint program_cube, program_plane, program_add;
    GLint uc_vp, uc_light, uc_texel, up_vp, up_dir, up_texel;
    GLint ua_mvp, ua_type, ua_pos, ua_dir, ua_colour, ua_cos, ua_radius, ua_cube, ua_plane, ua_light_vp, ua_texel, ua_bias;
    GLuint fbo, depth_rb, plane_depth_rb, vbo_albedo, vbo_visibility;
    bool has_visibility;
    size_t vertex_count;
    GLint ua_gate, ua_brdf_count, ua_brdfs, ua_eye;
    GLuint vbo_material, tbo_brdf, tex_brdf;
    int brdf_count;            /* glossy materials uploaded (0: Lambertian everywhere) */
    GLuint cube[PRT__PIXEL_LIGHTS], plane[PRT__PIXEL_LIGHTS];
    int count;
    prt_light lights[PRT__PIXEL_LIGHTS];
    float light_vp[PRT__PIXEL_LIGHTS][16];
    float lo[3], hi[3];        /* the mesh's bounds: shadow map ranges */
    bool dirty;                /* shadow maps need drawing */
} prt__pixel_lights;

prt_status prt__pixel_lights_init(prt__pixel_lights *p);
void prt__pixel_lights_free(prt__pixel_lights *p);
/* Takes mesh's lights (the first PRT__PIXEL_LIGHTS), per-vertex albedo (vao's attribute 4),
 * visibility (5) and glossy materials (6, and a table of their BRDFs); no lights, albedo or
 * normals turn the pass off. The positions give the bounds. */
void prt__pixel_lights_set(prt__pixel_lights *p, GLuint vao, const prt_render_mesh *mesh);
/* Draws the shadow maps if the lights or geometry changed (binds its own framebuffer and restores
 * the caller's framebuffer and viewport). */
void prt__pixel_lights_shadows(prt__pixel_lights *p, GLuint vao, size_t index_count);
/* Adds every light's shaded, shadowed direct light to what is drawn (depth test LEQUAL against
 * the main pass, additive blending). mvp as the main pass. */
void prt__pixel_lights_draw(const prt__pixel_lights *p, GLuint vao, size_t index_count, const float mvp[16], const float eye[3]);

#endif
