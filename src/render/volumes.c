/* Participating media over surfaces: a CPU ray march per pixel, composited depth-correctly over
 * what the GL renderer drew (each march ends at the first surface Embree finds on the pixel's
 * ray). The media's light comes relit (prt_render_volume: extinction and scattered-light SH per
 * voxel), so this is only emission-absorption along the ray. */
#include "render/volumes.h"
#include "geom/raycast.h"
#include "render/pinhole.h"

#include <stdlib.h>
#include <string.h>

/* Trilinear corners of p in v (voxel centres at (i + 0.5) / dims); false outside the box. */
static bool corners(const prt_render_volume *v, const float p[3], size_t at[8], float w[8])
{
    int i0[3], step[3];
    float f[3];
    for (int c = 0; c < 3; ++c) {
        if (!(p[c] >= v->lo[c] && p[c] <= v->hi[c])) return false;
        float u = (p[c] - v->lo[c]) / (v->hi[c] - v->lo[c]) * (float)v->dims[c] - 0.5f;
        u = fminf(fmaxf(u, 0.0f), (float)(v->dims[c] - 1));
        i0[c] = (int)u;
        if (i0[c] > v->dims[c] - 2) i0[c] = v->dims[c] > 1 ? v->dims[c] - 2 : 0;
        f[c] = v->dims[c] > 1 ? u - (float)i0[c] : 0.0f;
        step[c] = v->dims[c] > 1;
    }
    for (int k = 0; k < 8; ++k) {
        const int b[3] = {k & 1, k >> 1 & 1, k >> 2 & 1};
        w[k] = 1;
        for (int c = 0; c < 3; ++c) w[k] *= b[c] ? f[c] : 1.0f - f[c];
        at[k] = ((size_t)(i0[2] + b[2] * step[2]) * v->dims[1] + (size_t)(i0[1] + b[1] * step[1])) * v->dims[0] + (size_t)(i0[0] + b[0] * step[0]);
    }
    return true;
}

float prt__march_volumes(const prt_render_volume *vols, int count, const float o[3], const float d[3], float tmax, float jitter, float rgb[3])
{
    float T = 1.0f;
    rgb[0] = rgb[1] = rgb[2] = 0;
    /* The source's SH at the ray's direction (bands 0 and 1). */
    const double dd[3] = {d[0], d[1], d[2]};
    double y[4];
    prt_sh_eval(2, dd, y);
    for (int q = 0; q < count; ++q) {
        const prt_render_volume *v = &vols[q];
        float a = 0.0f, b = tmax, h = INFINITY;
        bool miss = false;
        for (int c = 0; c < 3 && !miss; ++c) {
            h = fminf(h, 0.5f * (v->hi[c] - v->lo[c]) / (float)v->dims[c]);
            if (fabsf(d[c]) < 1e-12f) { miss = o[c] < v->lo[c] || o[c] > v->hi[c]; continue; }
            float ta = (v->lo[c] - o[c]) / d[c], tb = (v->hi[c] - o[c]) / d[c];
            if (ta > tb) { const float s = ta; ta = tb; tb = s; }
            a = fmaxf(a, ta);
            b = fminf(b, tb);
        }
        if (miss || !(b > a)) continue;
        const int rows = v->source_order * v->source_order;
        for (float t = a + (jitter - 1.0f) * h; t < b && T > 1e-4f; t += h) {
            const float t0 = fmaxf(t, a), t1 = fminf(t + h, b), dt = t1 - t0;
            if (!(dt > 0)) continue;
            const float tm = 0.5f * (t0 + t1), p[3] = {o[0] + tm * d[0], o[1] + tm * d[1], o[2] + tm * d[2]};
            size_t at[8];
            float w[8];
            if (!corners(v, p, at, w)) continue;
            float sigma = 0, S[3] = {0, 0, 0};
            for (int k = 0; k < 8; ++k) {
                if (w[k] == 0) continue;
                sigma += w[k] * v->extinction[at[k]];
                const float *s = v->source + at[k] * 3 * (size_t)rows;
                for (int c = 0; c < 3; ++c)
                    for (int i = 0; i < rows; ++i) S[c] += w[k] * s[c * rows + i] * (float)y[i];
            }
            if (!(sigma > 0)) continue;
            const float e = expf(-sigma * dt);
            for (int c = 0; c < 3; ++c) rgb[c] += T * (1.0f - e) * fmaxf(S[c], 0.0f);
            T *= e;
        }
    }
    return T;
}

static float pixel_jitter(int x, int y)
{
    uint32_t h = (uint32_t)x * 0x9E3779B1u ^ (uint32_t)y * 0x85EBCA77u;
    h ^= h >> 15; h *= 0x2C1B3C6Du; h ^= h >> 12; h *= 0x297A2D39u; h ^= h >> 15;
    return (float)(h >> 8) * (1.0f / 16777216.0f);
}

prt_status prt__render_volumes(const prt_context *ctx, const prt_render_mesh *mesh, const prt_camera *cam, prt_image *img)
{
    if (!mesh->volume_count || !img->rgb) return PRT_OK;
    prt__mesh m;
    memset(&m, 0, sizeof m);
    m.positions = (float *)mesh->positions;
    m.indices = (uint32_t *)mesh->indices;
    m.vertex_count = mesh->vertex_count;
    m.triangle_count = mesh->triangle_count;
    prt__raycaster rc;
    prt_status st = prt__raycaster_create(ctx, &m, &rc);
    if (st) return st;
    const int width = img->width, height = img->height;
    prt__pinhole pin;
    prt__pinhole_init(cam, width, height, &pin);
#pragma omp parallel for schedule(dynamic, 4) num_threads(prt__threads(ctx))
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float dir[3];
            prt__pinhole_dir(&pin, (float)x + 0.5f, (float)y + 0.5f, dir);
            prt__ray_hit h;
            const float tmax = prt__raycaster_hit(&rc, cam->eye, dir, &h) ? h.t : INFINITY;
            float add[3];
            const float T = prt__march_volumes(mesh->volumes, mesh->volume_count, cam->eye, dir, tmax, pixel_jitter(x, y), add);
            float *px_rgb = img->rgb + ((size_t)y * width + x) * 3;
            for (int c = 0; c < 3; ++c) px_rgb[c] = T * px_rgb[c] + add[c];
        }
    prt__raycaster_release(&rc);
    return PRT_OK;
}
