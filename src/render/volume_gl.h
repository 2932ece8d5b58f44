/* Participating media drawn by OpenGL as slices through 3D textures (volume_gl.c): what the
 * viewer draws (prt_render ray-marches on the CPU instead, render/volumes.c). */
#ifndef PRT_RENDER_VOLUME_GL_H
#define PRT_RENDER_VOLUME_GL_H

#include "core/internal.h"
#include "prt/render.h"

#include <epoxy/gl.h>

#define PRT__GL_VOLUMES 8

typedef struct prt__volume_gl {
    GLuint program, vao;
    GLint u_mvp, u_lo, u_hi, u_axis, u_count, u_reverse, u_eye, u_bands, u_tex[4];
    int count;
    struct { GLuint tex[4]; int dims[3], bands; float lo[3], hi[3]; } v[PRT__GL_VOLUMES];
} prt__volume_gl;

prt_status prt__volume_gl_init(prt__volume_gl *g);
void prt__volume_gl_free(prt__volume_gl *g);
/* Replaces the media drawn (the first PRT__GL_VOLUMES of mesh's; none when it has none). */
void prt__volume_gl_upload(prt__volume_gl *g, const prt_render_volume *v, int count);
/* Blends the media over what the bound framebuffer holds, tested against its depth: slices
 * across each box's axis nearest the view, back to front, each one a slab's emission and
 * absorption (premultiplied). */
void prt__volume_gl_draw(prt__volume_gl *g, const float mvp[16], const float eye[3]);

#endif
