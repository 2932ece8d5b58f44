/* Offset transfer maps on the GPU (Sunshine-Hill & Faloutsos 2006, sections 5.1-5.2): the maps
 * cropped, sliced and binned into texture-array atlases once per transfer, then per relight the
 * light map accumulated by additive blending - one quad per slice, its map times the input light
 * shifted by the slice's offset - subsurface scattering first, then each inter-reflection bounce.
 * Requires a current OpenGL 3.3 core context. */
#ifndef PRT_RENDER_OFFSET_GL_H
#define PRT_RENDER_OFFSET_GL_H

#include "core/internal.h"

#include <epoxy/gl.h>

struct prt_transfer;

typedef struct prt__offset_gl {
    uint64_t serial;              /* the transfer uploaded (prt_transfer serial), 0 = none */
    int width, height, bin_size, layers;
    GLuint atlas[2];              /* per kind (radiosity, subsurface): RGB32F texture array, 0 = none */
    GLuint vao[2], vbo[2];
    GLsizei vertices[2];          /* 6 per slice */
    GLuint source;                /* RG32I: the surface texel each texel reads (-1: none) */
    GLuint albedo, medium, emit;  /* per texel, off the surface as their sources */
    GLuint input, sub, first, bounce[2], total;   /* RGBA32F work maps */
    GLuint fbo;
    GLuint p_accum, p_first, p_final;
    bool has_emit, has_medium;
} prt__offset_gl;

/* Uploads transfer t's maps unless they are already there; fails (and says why) when t is not an
 * offset file or the GPU cannot hold its atlases. */
prt_status prt__offset_gl_load(prt__offset_gl *g, const struct prt_transfer *t);
/* Runs the passes from input (width x height RGB irradiance / pi) and writes the result into
 * final_tex and, when first_tex is not 0, the first-order light into first_tex (both RGBA32F,
 * width x height, every texel filled: gutters take their source's value). component: the
 * PRT_COMPONENT_* of the light in final_tex. */
void prt__offset_gl_run(prt__offset_gl *g, const float *input, float emission, int bounces, int component, GLuint final_tex, GLuint first_tex);
void prt__offset_gl_free(prt__offset_gl *g);

#endif
