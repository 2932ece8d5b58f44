/* Ray casting over a mesh with Embree. */
#ifndef PRT_GEOM_RAYCAST_H
#define PRT_GEOM_RAYCAST_H

#include "geom/mesh.h"

typedef struct prt__raycaster {
    RTCScene scene;
} prt__raycaster;

prt_status prt__raycaster_create(const prt_context *ctx, const prt__mesh *m, prt__raycaster *out);
void prt__raycaster_release(prt__raycaster *rc);
/* Default origin offset for a mesh: small against its size, large against float precision. */
float prt__ray_offset(const prt__mesh *m);

#endif
