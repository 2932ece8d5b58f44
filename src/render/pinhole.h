/* The pinhole camera of prt_camera as rays: the CPU renderers (the path tracer, the media's ray
 * march) shoot through the same image plane the GL renderer projects onto. */
#ifndef PRT_RENDER_PINHOLE_H
#define PRT_RENDER_PINHOLE_H

#include "core/internal.h"
#include "prt/render.h"

#include <math.h>

typedef struct prt__pinhole {
    float f[3], s[3], u[3];   /* forward, right, up */
    float th, aspect;         /* tan of half the vertical field of view; width / height */
    int width, height;
} prt__pinhole;

static inline void prt__pinhole_init(const prt_camera *cam, int width, int height, prt__pinhole *p)
{
    float up[3] = {cam->up[0], cam->up[1], cam->up[2]};
    if (up[0] == 0 && up[1] == 0 && up[2] == 0) up[1] = 1;
    prt__v3_sub(cam->target, cam->eye, p->f);
    prt__v3_normalize(p->f);
    prt__v3_cross(p->f, up, p->s);
    prt__v3_normalize(p->s);
    prt__v3_cross(p->s, p->f, p->u);
    p->th = tanf(0.5f * (cam->fov_y_deg > 0 ? cam->fov_y_deg : 40.0f) * (float)PRT_PI / 180.0f);
    p->aspect = (float)width / (float)height;
    p->width = width;
    p->height = height;
}

/* The unit direction through image point (x, y) in pixels from the top left (x + 0.5 a centre). */
static inline void prt__pinhole_dir(const prt__pinhole *p, float x, float y, float dir[3])
{
    const float px = (2.0f * x / (float)p->width - 1.0f) * p->th * p->aspect, py = (1.0f - 2.0f * y / (float)p->height) * p->th;
    for (int k = 0; k < 3; ++k) dir[k] = p->f[k] + px * p->s[k] + py * p->u[k];
    prt__v3_normalize(dir);
}

#endif
