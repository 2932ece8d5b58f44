/* Minimal use of libprt's public API: build a scene (a plane under a sphere), bake diffuse
 * transfer, light it with the procedural sky, and print the exit radiance under the sphere and
 * far from it. Build: cc minimal.c $(pkg-config --cflags --libs prt) */
#include <prt/prt.h>
#include <stdio.h>
#include <stdlib.h>

static int fail(const char *what)
{
    fprintf(stderr, "minimal: %s: %s\n", what, prt_last_error());
    return 1;
}

int main(void)
{
    /* A 3x3 grid plane at y = 0 facing up, and an octahedron hovering over its centre. */
    float pos[16 * 3 + 6 * 3], nrm[16 * 3 + 6 * 3];
    uint32_t idx[18 * 3 + 8 * 3];
    size_t nv = 0, nt = 0;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i, ++nv) {
            pos[nv * 3] = -1.5f + i; pos[nv * 3 + 1] = 0; pos[nv * 3 + 2] = 1.5f - j;
            nrm[nv * 3] = 0; nrm[nv * 3 + 1] = 1; nrm[nv * 3 + 2] = 0;
        }
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            uint32_t a = (uint32_t)(j * 4 + i), b = a + 1, c = a + 4, d = c + 1;
            uint32_t t[6] = {a, b, c, b, d, c};
            for (int k = 0; k < 6; ++k) idx[nt * 3 + (size_t)k] = t[k];
            nt += 2;
        }
    const float oct[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (int k = 0; k < 6; ++k, ++nv)
        for (int c = 0; c < 3; ++c) { pos[nv * 3 + c] = 0.4f * oct[k][c] + (c == 1 ? 0.6f : 0.0f); nrm[nv * 3 + c] = oct[k][c]; }
    const uint32_t faces[8][3] = {{0, 2, 4}, {4, 2, 1}, {1, 2, 5}, {5, 2, 0}, {4, 3, 0}, {1, 3, 4}, {5, 3, 1}, {0, 3, 5}};
    for (int f = 0; f < 8; ++f, ++nt)
        for (int k = 0; k < 3; ++k) idx[nt * 3 + (size_t)k] = 16 + faces[f][k];

    prt_context *ctx;
    if (prt_context_create(NULL, &ctx)) return fail("context");
    prt_scene *scene;
    if (prt_scene_create_copy(ctx, pos, nrm, NULL, nv, idx, nt, NULL, &scene)) return fail("scene");
    prt_sh_bake_desc bake = {0};    /* zero = defaults: order 5, 1024 samples, all kinds */
    bake.samples = 256;
    prt_transfer *t;
    if (prt_bake_sh(ctx, scene, &bake, &t)) return fail("bake");

    prt_envmap *sky;
    prt_sh_light light;
    if (prt_sky_create(NULL, &sky) || prt_envmap_project_sh(sky, 5, &light)) return fail("lighting");
    float *rgb = malloc(prt_transfer_vertex_count(t) * 3 * sizeof(float));
    if (!rgb || prt_relight_sh(ctx, t, PRT_TRANSFER_SHADOWED, &light, rgb)) return fail("relight");
    /* Vertex 9 (-0.5, 0, -0.5) lies in the shadow the sun casts; vertex 0 is in the open. */
    printf("in its shadow: %.3f %.3f %.3f\n", rgb[9 * 3], rgb[9 * 3 + 1], rgb[9 * 3 + 2]);
    printf("in the open:   %.3f %.3f %.3f\n", rgb[0], rgb[1], rgb[2]);
    int ok = rgb[9 * 3 + 1] < 0.9f * rgb[1];   /* the shadowed vertex must be clearly darker */
    free(rgb);
    prt_envmap_release(sky);
    prt_transfer_release(t);
    prt_scene_release(scene);
    prt_context_release(ctx);
    return ok ? 0 : 1;
}
