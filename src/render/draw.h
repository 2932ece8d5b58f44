/* GL drawing shared by every target (headless EGL now, a window later): a program that draws
 * per-vertex linear radiance, and mesh upload. Requires a current OpenGL 3.3 core context. */
#ifndef PRT_RENDER_DRAW_H
#define PRT_RENDER_DRAW_H

#include "core/internal.h"

#include <epoxy/gl.h>

typedef struct prt__draw {
    GLuint program, vao, vbo_pos, vbo_rad, ibo;
    GLint u_mvp;
    size_t index_count;
} prt__draw;

prt_status prt__draw_init(prt__draw *d);
void prt__draw_free(prt__draw *d);
/* Uploads geometry and radiance (re-uploads everything; the radiance changes per relight). */
void prt__draw_upload(prt__draw *d, const prt_render_mesh *mesh);
/* Draws into the bound framebuffer of size w x h. */
void prt__draw_mesh(const prt__draw *d, const prt_camera *cam, int w, int h, const float background[3]);
/* Column-major view-projection matrix for a camera. */
void prt__camera_matrix(const prt_camera *cam, float aspect, float near_far[2], float out[16]);

#endif
