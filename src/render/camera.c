/* Auto framing that knows rooms. Seen from outside, a closed room is a box with its walls' backs
 * towards the camera: nothing of its inside shows. When rays from a point near the mesh's centre
 * meet surfaces facing that point in most directions, the mesh closes around it (a room, the
 * Cornell box, a courtyard open to the sky), and the camera goes inside: near the wall behind it
 * in the direction asked for, looking across. */
#include "geom/raycast.h"
#include "prt/render.h"

#include <string.h>

#define ENCLOSE_RAYS 64
#define ENCLOSED_SHARE 0.7   /* an open front (the Cornell box) or sky (a courtyard) still counts */

/* Distance along d from o to the first surface facing o, or INFINITY; *facing says whether the
 * first surface hit faces o. */
static float first_hit(const prt__raycaster *rc, const float o[3], const float d[3], bool *facing)
{
    prt__ray_hit h;
    *facing = false;
    if (!prt__raycaster_hit(rc, o, d, &h)) return INFINITY;
    *facing = h.ng[0] * d[0] + h.ng[1] * d[1] + h.ng[2] * d[2] < 0.0f;
    return h.t;
}

/* The share of directions from o whose first surface faces o. */
static double enclosure(const prt__raycaster *rc, const float o[3])
{
    int facing = 0;
    for (int k = 0; k < ENCLOSE_RAYS; ++k) {
        const float z = 1.0f - 2.0f * (k + 0.5f) / ENCLOSE_RAYS, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.39996323f * k;
        const float d[3] = {r * cosf(phi), z, r * sinf(phi)};
        bool f;
        first_hit(rc, o, d, &f);
        facing += f;
    }
    return (double)facing / ENCLOSE_RAYS;
}

int prt_camera_frame_mesh(prt_context *ctx, const float *positions, size_t nv, const uint32_t *indices, size_t nt, const float *from,
                          float fov_y_deg, float aspect, prt_camera *out)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nv * 3; ++i) {
        lo[i % 3] = fminf(lo[i % 3], positions[i]);
        hi[i % 3] = fmaxf(hi[i % 3], positions[i]);
    }
    if (!nv) { memset(lo, 0, sizeof lo); memset(hi, 0, sizeof hi); }
    prt_camera_frame(lo, hi, from, fov_y_deg > 0 ? fov_y_deg : 40.0f, aspect, out);
    if (!ctx || !indices || !nt || !nv) return 0;
    prt__mesh m = {0};
    m.vertex_count = nv;
    m.triangle_count = nt;
    m.positions = (float *)positions;   /* read only: the ray caster copies them */
    m.indices = (uint32_t *)indices;
    prt__raycaster rc;
    if (prt__raycaster_create(ctx, &m, &rc)) return 0;   /* framing from outside is still a view */
    /* The centre, or, where furniture fills it, a point a quarter of the way towards a side. */
    const float c[3] = {0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2])};
    const float shifts[7][3] = {{0, 0, 0}, {0, 0.25f, 0}, {0, -0.25f, 0}, {0.25f, 0, 0}, {-0.25f, 0, 0}, {0, 0, 0.25f}, {0, 0, -0.25f}};
    int inside = 0;
    float p[3];
    for (int s = 0; s < 7 && !inside; ++s) {
        for (int k = 0; k < 3; ++k) p[k] = c[k] + shifts[s][k] * (hi[k] - lo[k]);
        inside = enclosure(&rc, p) >= ENCLOSED_SHARE;
    }
    if (inside) {
        float dir[3] = {0.55f, 0.45f, 0.7f};
        if (from) memcpy(dir, from, sizeof dir);
        if (!prt__v3_normalize(dir)) { dir[0] = 0; dir[1] = 0; dir[2] = 1; }
        /* Back towards the wall behind the camera, short of it; looking through p. Where the
         * direction leaves through an opening, as far as the box allows. */
        bool facing;
        float reach = first_hit(&rc, p, dir, &facing);
        float box_reach = INFINITY;
        for (int k = 0; k < 3; ++k)
            if (dir[k] != 0) box_reach = fminf(box_reach, ((dir[k] > 0 ? hi[k] : lo[k]) - p[k]) / dir[k]);
        if (!(reach < box_reach)) reach = box_reach;
        const float back = 0.85f * reach;
        for (int k = 0; k < 3; ++k) {
            out->eye[k] = p[k] + dir[k] * back;
            out->target[k] = p[k] - dir[k] * 0.5f * back;
        }
        out->up[0] = 0; out->up[1] = 1; out->up[2] = 0;
        out->fov_y_deg = fov_y_deg > 0 ? fov_y_deg : 70.0f;   /* rooms are seen wide */
    }
    prt__raycaster_release(&rc);
    return inside;
}
