/* The wavelet method through libprt's public API: a glossy sphere over a diffuse floor, baked
 * with a separable Phong BRDF and one interreflection pass, relit under the procedural sky at two
 * rotations (a lighting change recomputes the K-vectors) and seen from two eyes (a view change
 * re-evaluates only the view maps). Build: cc wavelet.c $(pkg-config --cflags --libs prt) -lm */
#include <math.h>
#include <prt/prt.h>
#include <stdio.h>
#include <stdlib.h>

static int fail(const char *what)
{
    fprintf(stderr, "wavelet: %s: %s\n", what, prt_last_error());
    return 1;
}

int main(void)
{
    /* Floor: 9 x 9 vertices over [-2, 2]^2 at y = 0; sphere: radius 0.5 at height 0.7. */
    enum { FN = 9, RINGS = 12, SEGS = 24 };
    const size_t floor_nv = FN * FN, nv = floor_nv + (RINGS + 1) * SEGS;
    float *pos = malloc(nv * 3 * sizeof(float)), *nrm = malloc(nv * 3 * sizeof(float));
    uint32_t *idx = malloc(((FN - 1) * (FN - 1) * 2 + RINGS * SEGS * 2) * 3 * sizeof(uint32_t));
    size_t v = 0, t = 0;
    for (int j = 0; j < FN; ++j)
        for (int i = 0; i < FN; ++i, ++v) {
            pos[v * 3] = -2.0f + 4.0f * i / (FN - 1); pos[v * 3 + 1] = 0; pos[v * 3 + 2] = 2.0f - 4.0f * j / (FN - 1);
            nrm[v * 3] = 0; nrm[v * 3 + 1] = 1; nrm[v * 3 + 2] = 0;
        }
    for (int j = 0; j + 1 < FN; ++j)
        for (int i = 0; i + 1 < FN; ++i) {
            uint32_t a = (uint32_t)(j * FN + i), b = a + 1, c = a + FN, d = c + 1, q[6] = {a, b, c, b, d, c};
            for (int k = 0; k < 6; ++k) idx[t * 3 + (size_t)k] = q[k];
            t += 2;
        }
    for (int r = 0; r <= RINGS; ++r)   /* poles repeated per segment: simple, and harmless here */
        for (int s = 0; s < SEGS; ++s, ++v) {
            float th = 3.14159265f * r / RINGS, ph = 6.2831853f * s / SEGS;
            float n[3] = {sinf(th) * cosf(ph), cosf(th), sinf(th) * sinf(ph)};
            for (int c = 0; c < 3; ++c) { nrm[v * 3 + c] = n[c]; pos[v * 3 + c] = 0.5f * n[c] + (c == 1 ? 0.7f : 0.0f); }
        }
    for (int r = 0; r < RINGS; ++r)
        for (int s = 0; s < SEGS; ++s) {
            uint32_t a = (uint32_t)(floor_nv + r * SEGS + s), b = (uint32_t)(floor_nv + r * SEGS + (s + 1) % SEGS), c = a + SEGS, d = b + SEGS;
            uint32_t q[6] = {a, b, c, b, d, c};
            for (int k = 0; k < 6; ++k) idx[t * 3 + (size_t)k] = q[k];
            t += 2;
        }

    prt_context *ctx;
    prt_scene *scene;
    prt_brdf phong;
    if (prt_context_create(NULL, &ctx)) return fail("context");
    if (prt_scene_create_copy(ctx, pos, nrm, NULL, nv, idx, t, NULL, &scene)) return fail("scene");
    /* Cleaning may drop the repeated pole vertices: the sphere is whatever follows the floor. */
    if (prt_brdf_parse("phong:20:0.5:0.3", &phong) || prt_scene_set_brdf(scene, floor_nv, prt_scene_vertex_count(scene) - floor_nv, &phong))
        return fail("material");
    prt_wavelet_bake_desc bake = {0};   /* zero = defaults: K = 4, 128 coefficients, 8 bits */
    bake.supersample = 1;
    bake.bounces = 1;
    prt_transfer *tr;
    if (prt_bake_wavelet(ctx, scene, &bake, &tr)) return fail("bake");
    prt_wavelet_info info;
    prt_transfer_wavelet_info(tr, &info);
    printf("%zu vertices, %zu transport vectors, %.0f bytes per vertex\n", prt_transfer_vertex_count(tr), info.vectors,
           (double)info.bytes / (double)prt_transfer_vertex_count(tr));

    prt_envmap *sky;
    if (prt_sky_create(NULL, &sky)) return fail("sky");
    const size_t n = prt_transfer_vertex_count(tr);
    float *kvec = malloc(n * (size_t)info.terms * 3 * sizeof(float)), *rgb = malloc(n * 3 * sizeof(float));
    const size_t top = floor_nv + 5;   /* a sphere vertex near the top, facing the sun's side */
    float seen[2][2];
    for (int rot = 0; rot < 2; ++rot) {
        prt_wavelet_light_desc ld = {0};
        prt_rotation_from_euler_deg(rot * 120.0, 0, 0, ld.rotation);
        prt_wavelet_light *light;
        if (prt_wavelet_light_create(ctx, sky, &ld, &light) || prt_relight_wavelet(ctx, tr, light, kvec)) return fail("relight");
        for (int e = 0; e < 2; ++e) {
            const float eye[3] = {e ? -4.0f : 4.0f, 3.0f, 2.0f};
            if (prt_wavelet_shade(ctx, tr, kvec, eye, rgb)) return fail("shade");
            seen[rot][e] = rgb[top * 3 + 1];
            printf("sky rotated %3d degrees, eye %+.0f: sphere %.3f, floor centre %.3f\n", rot * 120, eye[0], rgb[top * 3 + 1], rgb[40 * 3 + 1]);
        }
        prt_wavelet_light_release(light);
    }
    /* Glossy: the colour depends on the eye; relighting changes it too. */
    int ok = fabsf(seen[0][0] - seen[0][1]) > 1e-3f && fabsf(seen[0][0] - seen[1][0]) > 1e-3f;
    free(kvec); free(rgb); free(pos); free(nrm); free(idx);
    prt_envmap_release(sky);
    prt_transfer_release(tr);
    prt_scene_release(scene);
    prt_context_release(ctx);
    return ok ? 0 : 1;
}
