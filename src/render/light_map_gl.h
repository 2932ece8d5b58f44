/* Light maps finished on the GPU (prt_render_passes): the description's maps cropped into
 * texture-array atlases once per id, then per upload the light map accumulated by additive
 * blending - one quad per slice, its map times the input light shifted by the map's offset - the
 * scatter set first, then each bounce. Requires a current OpenGL 3.3 core context. */
#ifndef PRT_RENDER_LIGHT_MAP_GL_H
#define PRT_RENDER_LIGHT_MAP_GL_H

#include "core/internal.h"
#include "prt/render.h"

#include <epoxy/gl.h>

typedef struct prt__light_map_gl {
    uint64_t id;                  /* the description uploaded (prt_render_passes.id), 0 = none */
    int width, height;
    GLuint atlas[2];              /* per set (bounce, scatter): RGB32F texture array, 0 = none */
    GLuint vao[2], vbo[2];
    GLsizei vertices[2];          /* 6 per slice */
    GLuint source;                /* RG32I: the surface texel each texel reads (-1: none) */
    GLuint albedo, mask, emit;    /* per texel, off the surface as their sources */
    GLuint input, sub, first, bounce[2], total, pixel_direct;   /* RGBA32F work maps */
    GLuint fbo;
    GLuint p_accum, p_first, p_final, p_pyramid0, p_pyramid;
    /* Prefiltered light for the bounce maps (prt_render_map_set.levels): texel area and chart,
     * and the light's pyramid of pyramid_size^2 texels (the map's size up to a power of two). */
    int levels, pyramid_size;
    GLuint area_chart, pyramid, charts;
    int smooth_radius;            /* prt_render_passes.smooth_radius, with levels (it reads area_chart) */
    GLuint normals;               /* RGB32F: each surface texel's normal, with smooth_radius */
    bool has_emit, has_mask;
} prt__light_map_gl;

/* Uploads the description's maps unless its id is already there; fails (and says why) when the
 * description is inconsistent or the GPU cannot hold its atlases. */
prt_status prt__light_map_gl_load(prt__light_map_gl *g, const prt_render_passes *lm);
/* Runs the passes from input (width x height RGB irradiance / pi) and writes the result into
 * final_tex and, when first_tex is not 0, the first-order light into first_tex (both RGBA32F,
 * width x height, every texel filled: gutters take their source's value), both less
 * pixel_direct (width x height RGB, the light drawn per pixel; NULL: none) and clamped at zero.
 * component: the PRT_COMPONENT_* of the light in final_tex. */
void prt__light_map_gl_run(prt__light_map_gl *g, const float *input, const float *pixel_direct, float emission, int bounces, int component,
                           GLuint final_tex, GLuint first_tex);
void prt__light_map_gl_free(prt__light_map_gl *g);

#endif
