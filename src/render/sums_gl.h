/* Per-vertex light finished on the GPU (prt_render_sums): the products' matrices in buffer
 * textures once per id, then per frame the vector uploaded and one transform-feedback pass per
 * product; the shown rows added to the vertices' radiance buffer. Where the GL limits or memory
 * do not allow, the same products run on the CPU (prt_render_sums_cpu) and a note says so once.
 * Requires a current OpenGL 3.3 core context. */
#ifndef PRT_RENDER_SUMS_GL_H
#define PRT_RENDER_SUMS_GL_H

#include "core/internal.h"
#include "prt/render.h"

#include <epoxy/gl.h>

typedef struct prt__sums_product_gl {
    GLuint start, index, weight, scale, out;      /* buffers */
    GLuint t_start, t_index, t_weight, t_scale, t_out;   /* their buffer textures */
    GLuint program;               /* its own pass where it has a map, else 0 (the shared one) */
} prt__sums_product_gl;

typedef struct prt__sums_gl {
    uint64_t id;                  /* the description uploaded, 0 = none */
    int count;
    prt__sums_product_gl *p;
    GLuint vector, t_vector, base_tex, program, combine, vao, fbo, rb;
    GLint c_base, c_y;
    float *pack;                  /* RGBA staging for the vector */
    size_t pack_length;
    bool cpu;                     /* the description is evaluated on the CPU (limits, memory) */
    bool noted;
    int on_gpu;                   /* prt_render_sums_on_gpu */
    size_t max_texels;            /* 0, or fewer buffer-texture texels than the GL allows */
} prt__sums_gl;

/* Radiance (vertex_count RGB, in buffer rad, which it replaces) plus the shown products of
 * mesh->gpu_sums from mesh->gpu_vector; rad2 is a scratch buffer of the same size. */
prt_status prt__sums_gl_run(prt__sums_gl *g, const prt_context *ctx, const prt_render_mesh *mesh, GLuint rad, GLuint rad2);
void prt__sums_gl_free(prt__sums_gl *g);
/* A description's counts and indices checked against each other (render/sums.c). */
prt_status prt__render_sums_check(const prt_render_sums *s, size_t vertex_count);

#endif
