/* A height map over the mesh's texture coordinates (the course notes' self-shadowing bumps):
 * heights in world units along the surface normal, the shading normals they imply, and whether
 * a direction leaving a texel is blocked by the bumps around it. */
#ifndef PRT_METHODS_SH_HEIGHT_FIELD_H
#define PRT_METHODS_SH_HEIGHT_FIELD_H

#include "prt/image.h"

#include <stdbool.h>

typedef struct prt__height_field {
    const prt_image *map;   /* first channel, [0, 1] as stored; wraps like a repeating texture */
    float scale;            /* world units of a stored 1 */
    float top;              /* the highest height, world units */
} prt__height_field;

/* The surface around one texel as the height field sees it: the unit tangent frame (t along +u,
 * b along +v, n the surface's normal) and the world length of one unit of u and of v. */
typedef struct prt__bump_frame {
    float t[3], b[3], n[3];
    float u, v;
    float len_u, len_v;
} prt__bump_frame;

/* Fills h->top; false when the map holds no pixels or a value that is not finite. */
bool prt__height_field_init(prt__height_field *h, const prt_image *map, float scale);

/* The height at (u, v), world units (bilinear). */
float prt__height_at(const prt__height_field *h, float u, float v);

/* The shading normal the bumps give at the frame's point (central differences over one pixel). */
void prt__height_normal(const prt__height_field *h, const prt__bump_frame *f, float out[3]);

/* Whether the world direction d, leaving the frame's point on the height field, meets a bump
 * before it rises above the highest one (marched in steps of half a map pixel). */
bool prt__height_blocks(const prt__height_field *h, const prt__bump_frame *f, const float d[3]);

#endif
