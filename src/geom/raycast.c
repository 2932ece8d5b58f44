/* Builds the Embree scene for a mesh. Embree copies the buffers (rtcSetNewGeometryBuffer), so
 * the mesh may be freed independently and Embree's padding rules are met. */
#include "geom/raycast.h"

#include <stdio.h>
#include <string.h>

static void embree_error(void *user, enum RTCError code, const char *str)
{
    prt__log((const prt_context *)user, PRT_LOG_ERROR, "embree error %d: %s", (int)code, str ? str : "");
}

static void release_device(void *device) { rtcReleaseDevice(device); }

/* The context's Embree device, made on first use: concurrent first calls may both make one; one
 * is published, the other released. NULL when Embree cannot make one. */
static RTCDevice device_of(const prt_context *ctx)
{
    prt_context *c = (prt_context *)ctx;   /* a memo: the device is the context's, made once */
    RTCDevice d = __atomic_load_n(&c->ray_device, __ATOMIC_ACQUIRE);
    if (d) return d;
    char cfg[64];
    snprintf(cfg, sizeof cfg, "threads=%d", prt__threads(ctx));
    RTCDevice made = rtcNewDevice(cfg);
    if (!made) return NULL;
    rtcSetDeviceErrorFunction(made, embree_error, c);
    __atomic_store_n(&c->ray_device_release, release_device, __ATOMIC_RELEASE);
    void *expected = NULL;
    if (!__atomic_compare_exchange_n(&c->ray_device, &expected, (void *)made, false, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
        rtcReleaseDevice(made);
        return expected;
    }
    return made;
}

static bool build_progress(void *ctx, double done)
{
    (void)done;
    return !prt__cancelled(ctx);
}

prt_status prt__raycaster_create(const prt_context *ctx, const prt__mesh *m, prt__raycaster *out)
{
    memset(out, 0, sizeof *out);
    RTCDevice device = device_of(ctx);
    if (!device) return prt__fail(ctx, PRT_ERR_BACKEND, "could not create the Embree device");
    RTCScene scene = rtcNewScene(device);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!scene || !geom) {
        if (scene) rtcReleaseScene(scene);
        if (geom) rtcReleaseGeometry(geom);
        return prt__fail(ctx, PRT_ERR_BACKEND, "Embree could not create a scene");
    }
    float *v = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), m->vertex_count);
    uint32_t *i = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), m->triangle_count);
    if (!v || !i) {
        rtcReleaseGeometry(geom);
        rtcReleaseScene(scene);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "Embree could not allocate geometry buffers");
    }
    memcpy(v, m->positions, m->vertex_count * 3 * sizeof(float));
    memcpy(i, m->indices, m->triangle_count * 3 * sizeof(uint32_t));
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    /* A build of tens of millions of triangles takes seconds: the cancel hook can stop it. */
    rtcSetSceneProgressMonitorFunction(scene, build_progress, (void *)ctx);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);   /* no rays slip through shared edges */
    if (prt__cancelled(ctx)) {
        rtcReleaseScene(scene);
        return prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled while building the ray-tracing structure");
    }
    rtcCommitScene(scene);
    enum RTCError err = rtcGetDeviceError(device);
    if (err != RTC_ERROR_NONE) {
        rtcReleaseScene(scene);
        if (err == RTC_ERROR_CANCELLED || prt__cancelled(ctx)) return prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled while building the ray-tracing structure");
        return prt__fail(ctx, PRT_ERR_BACKEND, "Embree failed to build the scene");
    }
    out->scene = scene;
    return PRT_OK;
}

void prt__raycaster_release(prt__raycaster *rc)
{
    if (rc->scene) rtcReleaseScene(rc->scene);
    rc->scene = NULL;
}

bool prt__raycaster_occluded(const prt__raycaster *rc, const float o[3], const float d[3], float tfar)
{
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    struct RTCRay r;
    memset(&r, 0, sizeof r);
    r.org_x = o[0]; r.org_y = o[1]; r.org_z = o[2];
    r.dir_x = d[0]; r.dir_y = d[1]; r.dir_z = d[2];
    r.tnear = 0.0f;
    r.tfar = tfar;
    r.mask = 0xFFFFFFFFu;
    rtcOccluded1(rc->scene, &ictx, &r);
    return r.tfar < 0.0f;
}

bool prt__raycaster_hit(const prt__raycaster *rc, const float o[3], const float d[3], prt__ray_hit *out)
{
    struct RTCIntersectContext ictx;
    rtcInitIntersectContext(&ictx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = o[0]; rh.ray.org_y = o[1]; rh.ray.org_z = o[2];
    rh.ray.dir_x = d[0]; rh.ray.dir_y = d[1]; rh.ray.dir_z = d[2];
    rh.ray.tfar = INFINITY;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rc->scene, &ictx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    *out = (prt__ray_hit){rh.ray.tfar, rh.hit.u, rh.hit.v, {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}, rh.hit.primID};
    return true;
}

bool prt__raycaster_segment_clear(const prt__raycaster *rc, const float a[3], const float b[3])
{
    float d[3];
    prt__v3_sub(b, a, d);
    const float len = prt__v3_len(d);
    if (!(len > 0)) return true;
    for (int k = 0; k < 3; ++k) d[k] /= len;
    return !prt__raycaster_occluded(rc, a, d, len);
}

prt_status prt__vertex_origins(const prt__mesh *m, float offset, float **out)
{
    /* An offset beyond the scene's size (a corrupt file, a typo) would move origins out of the
     * range Embree accepts (it asserts on such rays). */
    const float diagonal = 1e4f * prt__ray_offset(m);
    if (!(offset >= 0.0f) || !(offset <= fmaxf(diagonal, 1e-6f)))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "ray offset %g is not between 0 and the scene's size (diagonal %g)", offset, diagonal);
    float *o = prt__calloc(m->vertex_count * 3, sizeof(float));
    float *cen = prt__calloc(m->vertex_count * 3, sizeof(float));
    if (!o || !cen) { free(o); free(cen); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for ray origins"); }
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *tri = m->indices + t * 3;
        for (int c = 0; c < 3; ++c) {
            float centroid = (m->positions[tri[0] * 3 + c] + m->positions[tri[1] * 3 + c] + m->positions[tri[2] * 3 + c]) / 3.0f;
            for (int k = 0; k < 3; ++k) cen[tri[k] * 3 + c] += centroid - m->positions[tri[k] * 3 + c];
        }
    }
    for (size_t v = 0; v < m->vertex_count; ++v) {
        const float *p = m->positions + v * 3, *n = m->normals + v * 3;
        float *d = cen + v * 3;
        float along = prt__v3_dot(d, n);   /* keep only the tangential part */
        for (int c = 0; c < 3; ++c) d[c] -= along * n[c];
        /* d sums the offsets to the fan's centroids: near zero inside a flat or evenly curved
         * fan, large at a boundary or crease; its length also bounds how far is safe to move. */
        float len = prt__v3_len(d), step = 0.0f;
        if (len > 1e-30f) {
            for (int c = 0; c < 3; ++c) d[c] /= len;
            step = fminf(offset, 0.25f * len);
        }
        for (int c = 0; c < 3; ++c) o[v * 3 + c] = p[c] + n[c] * offset + d[c] * step;
    }
    free(cen);
    *out = o;
    return PRT_OK;
}

float prt__ray_offset(const prt__mesh *m)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < m->vertex_count * 3; ++i) {
        lo[i % 3] = fminf(lo[i % 3], m->positions[i]);
        hi[i % 3] = fmaxf(hi[i % 3], m->positions[i]);
    }
    float d[3];
    prt__v3_sub(hi, lo, d);
    return 1e-4f * prt__v3_len(d);
}
