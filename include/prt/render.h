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

typedef struct prt_renderer_desc {
    int width, height;       /* 0 = 800 x 600 */
    int samples;             /* MSAA samples; 0 = 4 */
} prt_renderer_desc;

typedef struct prt_camera {
    float eye[3], target[3], up[3];  /* up all zero = +y */
    float fov_y_deg;                 /* 0 = 40 */
} prt_camera;

/* Borrowed arrays describing what to draw. */
typedef struct prt_render_mesh {
    const float *positions;      /* 3 per vertex */
    const float *radiance;       /* 3 per vertex, linear */
    size_t vertex_count;
    const uint32_t *indices;     /* 3 per triangle */
    size_t triangle_count;
} prt_render_mesh;

prt_status prt_renderer_create(prt_context *ctx, const prt_renderer_desc *desc, prt_renderer **out);
void prt_renderer_release(prt_renderer *r);
/* background: linear RGB behind the mesh (NULL = black). */
prt_status prt_render(prt_renderer *r, const prt_render_mesh *mesh, const prt_camera *cam,
                      const float background[3], prt_image *out);
/* A camera that frames the box [lo, hi] from direction `from` (towards the eye; NULL = a
 * default three-quarter view). */
void prt_camera_frame(const float lo[3], const float hi[3], const float *from, float fov_y_deg,
                      float aspect, prt_camera *out);
/* The GL renderer string, for reports ("llvmpipe ..."). */
const char *prt_renderer_name(const prt_renderer *r);

#ifdef __cplusplus
}
#endif
#endif
