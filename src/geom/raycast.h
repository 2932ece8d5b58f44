/* Ray casting over a mesh with Embree: the one header through which the rest of prt reaches
 * Embree (its device is the context's, made on first use). */
#ifndef PRT_GEOM_RAYCAST_H
#define PRT_GEOM_RAYCAST_H

#include "geom/mesh.h"

#include <embree3/rtcore.h>

typedef struct prt__raycaster {
    RTCScene scene;
} prt__raycaster;

prt_status prt__raycaster_create(const prt_context *ctx, const prt__mesh *m, prt__raycaster *out);
void prt__raycaster_release(prt__raycaster *rc);
/* Whether anything lies on the ray o + d t, t in (0, tfar) (d unit). */
bool prt__raycaster_occluded(const prt__raycaster *rc, const float o[3], const float d[3], float tfar);
/* The first surface on the ray o + d t (d unit): distance t, triangle, barycentrics and Embree's
 * unnormalized geometric normal (pointing to where the triangle winds counter-clockwise). */
typedef struct prt__ray_hit {
    float t, u, v, ng[3];
    uint32_t prim;
} prt__ray_hit;
/* False on a miss. */
bool prt__raycaster_hit(const prt__raycaster *rc, const float o[3], const float d[3], prt__ray_hit *out);
/* Whether the segment from a to b is free of geometry. */
bool prt__raycaster_segment_clear(const prt__raycaster *rc, const float a[3], const float b[3]);
/* Fills a 16-wide packet of rays from one origin along dirs[idx[k]] for the first `lanes`
 * lanes; the rest are masked off in `valid` (which Embree reads with aligned loads). */
static inline void prt__packet_rays(struct RTCRay16 *r, int *valid, const float org[3], const float *dirs, const int *idx, int lanes)
{
    for (int k = 0; k < 16; ++k) {
        const float *d = dirs + (size_t)idx[k < lanes ? k : 0] * 3;
        valid[k] = k < lanes ? -1 : 0;
        r->org_x[k] = org[0]; r->org_y[k] = org[1]; r->org_z[k] = org[2];
        r->dir_x[k] = d[0]; r->dir_y[k] = d[1]; r->dir_z[k] = d[2];
        r->tnear[k] = 0.0f; r->tfar[k] = INFINITY; r->time[k] = 0.0f;
        r->mask[k] = 0xFFFFFFFFu; r->id[k] = 0; r->flags[k] = 0;
    }
}

static inline void prt__packet_rayhits(struct RTCRayHit16 *rh, int *valid, const float org[3], const float *dirs, const int *idx, int lanes)
{
    prt__packet_rays(&rh->ray, valid, org, dirs, idx, lanes);
    for (int k = 0; k < 16; ++k) { rh->hit.geomID[k] = RTC_INVALID_GEOMETRY_ID; rh->hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID; }
}

/* Ray origins for rays leaving each vertex: the vertex moved along its normal by `offset`, and
 * towards the centroid of its triangle fan by as much (at most a quarter of the way). The second
 * move keeps a vertex on a concave edge (a floor meeting a wall) from starting its rays inside the
 * other surface's plane, where they would be blocked or leak depending on rounding. Offsets
 * beyond the mesh's bounding-box diagonal are refused. */
prt_status prt__vertex_origins(const prt__mesh *m, float offset, float **out);

/* Finds origins that start inside geometry (more than half of a hemisphere of probe rays meets
 * back faces first) and moves each to the freest point of its triangle fan. status (optional,
 * per vertex): 0 fine, 1 moved, 2 buried with no free point found. Says how many at `level`. */
prt_status prt__unbury_origins(const prt_context *ctx, const prt__raycaster *rc, const prt__mesh *m, float offset, float *origins,
                               uint8_t *status, prt_log_level level);

/* The share of a hemisphere of probe rays about n from o that meet a back face first: above one
 * half, o is inside geometry. */
double prt__origin_back_share(const prt__raycaster *rc, const float o[3], const float n[3]);

/* Gives every vertex of status 2 (see above) the mean of its neighbours that have values, ring by
 * ring outwards; data holds stride floats per vertex. unfilled (may be NULL): how many found no
 * such neighbour. Fails only out of memory. */
prt_status prt__fill_buried(const prt__mesh *m, const uint8_t *status, float *data, size_t stride, size_t *unfilled);

/* Default origin offset for a mesh: small against its size, large against float precision. */
float prt__ray_offset(const prt__mesh *m);

#endif
