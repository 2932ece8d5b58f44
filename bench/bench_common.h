/* Limits the benchmarks measure in the same run as the code they judge: raw Embree ray
 * throughput on the bake's own rays, and plain memory read bandwidth. */
#ifndef PRT_BENCH_COMMON_H
#define PRT_BENCH_COMMON_H

#include "prt/prt.h"
#include "core/internal.h"
#include "core/progress.h"
#include "geom/raycast.h"

#include <unistd.h>

/* Traces, from origins[v] of every stride-th vertex, each of the `count` directions above its
 * normal in packets of 16 (rtcIntersect16 or rtcOccluded16) with nothing else around them;
 * returns the time taken and the rays traced in *rays. */
static inline double bench_raw_rays(const prt__mesh *m, const prt__raycaster *rc, const float *origins, const float *dirs, int count,
                                    size_t stride, bool intersect, int threads, uint64_t *rays)
{
    uint64_t total = 0;
    double t0 = prt__now();
#pragma omp parallel for schedule(dynamic, 8) num_threads(threads) reduction(+ : total)
    for (size_t v = 0; v < m->vertex_count; v += stride) {
        const float *n = m->normals + v * 3;
        struct RTCIntersectContext ictx;
        rtcInitIntersectContext(&ictx);
        int j = 0;
        while (j < count) {
            int lanes = 0, idx[16];
            for (; j < count && lanes < 16; ++j)
                if (prt__v3_dot(dirs + (size_t)j * 3, n) > 0) idx[lanes++] = j;
            if (!lanes) break;
            _Alignas(64) int valid[16];
            if (intersect) {
                _Alignas(64) struct RTCRayHit16 rh;
                prt__packet_rayhits(&rh, valid, origins + v * 3, dirs, idx, lanes);
                rtcIntersect16(valid, rc->scene, &ictx, &rh);
            } else {
                _Alignas(64) struct RTCRay16 ray;
                prt__packet_rays(&ray, valid, origins + v * 3, dirs, idx, lanes);
                rtcOccluded16(valid, rc->scene, &ictx, &ray);
            }
            total += (uint64_t)lanes;
        }
    }
    *rays = total;
    return prt__now() - t0;
}

/* Read bandwidth of a plain streaming sum over `bytes` of floats, best of many passes: for a
 * buffer the size of the relight's data this is the limit the relight loop can reach (cache-
 * resident when it fits, like the relight's own data); 512 MiB gives the DRAM figure. */
static inline double bench_read_bandwidth(size_t bytes, int threads)
{
    const size_t n = bytes / sizeof(float);
    float *buf = malloc(n * sizeof(float));
    if (!buf) return 0;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (size_t i = 0; i < n; ++i) buf[i] = (float)(i & 1023);
    const int passes = bytes > ((size_t)64 << 20) ? 5 : 200;
    double best = 1e30, sink = 0;
    for (int pass = 0; pass < passes; ++pass) {
        double t0 = prt__now();
        float s = 0;
        /* Sixteen running sums per thread: vectorizes with gcc and clang alike, no pragma needed. */
#pragma omp parallel num_threads(threads) reduction(+ : s)
        {
            float acc[16] = {0};
#pragma omp for schedule(static)
            for (size_t b = 0; b < n / 16; ++b)
                for (int k = 0; k < 16; ++k) acc[k] += buf[b * 16 + k];
            for (int k = 0; k < 16; ++k) s += acc[k];
        }
        double dt = prt__now() - t0;
        sink += s;
        if (dt < best) best = dt;
    }
    free(buf);
    if (sink == 42.0) fputs("", stderr);   /* keep the sums alive */
    return (double)n * sizeof(float) / best;
}

/* The mesh a benchmark runs on: the one given, else ../shared/data's bunny when present, else the
 * procedural demo scene; loaded with a context of `threads` threads (0 = all). Returns false
 * after saying why. */
/* Best wall time of a relight of t under l with the method's controls (all of them,
 * prt_transfer_controls) over five runs. */
static inline double bench_relight_time_controls(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const int *controls)
{
    double best = 1e30;
    for (int run = 0; run < 5; ++run) {
        prt_relight_desc d = {.variant = -1, .controls = controls};
        prt_relit r;
        const double t0 = prt__now();
        if (prt_relight(ctx, t, l, &d, &r)) { fprintf(stderr, "bench: %s\n", prt_last_error()); exit(1); }
        const double dt = prt__now() - t0;
        prt_relit_free(&r);
        if (dt < best) best = dt;
    }
    return best;
}

/* The same with `bounces` as the method's first control and the others at their defaults. */
static inline double bench_relight_time(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, int bounces)
{
    int controls[PRT_MAX_CONTROLS];
    const int n = prt_transfer_controls(t, NULL);
    for (int i = 1; i < n && i < PRT_MAX_CONTROLS; ++i) prt_transfer_control_range(t, i, NULL, NULL, &controls[i]);
    controls[0] = bounces;
    return bench_relight_time_controls(ctx, t, l, controls);
}

/* Adds a diffuse ground plane (albedo 0.7) of cells x cells squares under the mesh's first
 * object_nv vertices, three times their width (the setting of the papers' objects on a plane). */
static inline bool bench_ground_plane(prt__mesh *m, size_t object_nv, int cells)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < object_nv; ++v)
        for (int c = 0; c < 3; ++c) { lo[c] = fminf(lo[c], m->positions[v * 3 + c]); hi[c] = fmaxf(hi[c], m->positions[v * 3 + c]); }
    const float size = 3.0f * fmaxf(hi[0] - lo[0], hi[2] - lo[2]), cx = 0.5f * (lo[0] + hi[0]), cz = 0.5f * (lo[2] + hi[2]);
    float *pos = malloc((size_t)(cells + 1) * (cells + 1) * 3 * sizeof(float)), *nrm = malloc((size_t)(cells + 1) * (cells + 1) * 3 * sizeof(float));
    uint32_t *idx = malloc((size_t)cells * cells * 6 * sizeof(uint32_t));
    if (!pos || !nrm || !idx) { free(pos); free(nrm); free(idx); return false; }
    for (int j = 0; j <= cells; ++j)
        for (int i = 0; i <= cells; ++i) {
            float *p = pos + ((size_t)j * (cells + 1) + i) * 3, *n = nrm + ((size_t)j * (cells + 1) + i) * 3;
            p[0] = cx + size * ((float)i / cells - 0.5f); p[1] = lo[1]; p[2] = cz + size * ((float)j / cells - 0.5f);
            n[0] = 0; n[1] = 1; n[2] = 0;
        }
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            uint32_t a = (uint32_t)(j * (cells + 1) + i), b = a + 1, c = a + (uint32_t)(cells + 1), d = c + 1;
            uint32_t *t = idx + ((size_t)j * cells + i) * 6;
            t[0] = a; t[1] = c; t[2] = b; t[3] = b; t[4] = c; t[5] = d;   /* counter-clockwise seen from +y */
        }
    const bool ok = !prt__mesh_append(m, pos, nrm, NULL, (float[3]){0.7f, 0.7f, 0.7f}, (size_t)(cells + 1) * (cells + 1), idx, (size_t)cells * cells * 2);
    free(pos); free(nrm); free(idx);
    return ok;
}

static inline bool bench_load(const char *mesh, int threads, prt_context **ctx, prt_scene **scene, const char **used)
{
    static const char *bunny = "../shared/data/meshes/bunny/bun_zipper.ply";
    static char demo[] = "/tmp/prt_bench_demo.obj";
    if (!mesh) {
        if (access(bunny, R_OK) == 0) mesh = bunny;
        else {
            fprintf(stderr, "bench: %s not found; using the procedural demo scene\n", bunny);
            if (prt_demo_scene_write(demo)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return false; }
            mesh = demo;
        }
    }
    *used = mesh;
    if (prt_context_create(&(prt_context_desc){.threads = threads}, ctx)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return false; }
    if (prt_scene_load(*ctx, mesh, NULL, scene)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return false; }
    return true;
}

#endif
