/* Transfer in participating media (src/methods/sh/volume.c, src/geom/volume.c,
 * src/io/grid_file.c, src/render/volumes.c): a non-absorbing medium under a uniform white sky
 * glows at exactly the sky's radiance (white furnace); a homogeneous slab's shadow on the ground is
 * the integral of its transmittance; density grid files round-trip and every damaged one is
 * refused by name; bakes do not depend on the thread count. */
#include <sys/stat.h>

#include "common.h"
#include "render/volumes.h"
#include "prt/reference.h"

/* A homogeneous box of density 1 in [lo, hi] with dims voxels. */
static prt_volume_desc box_volume(const int dims[3], const float lo[3], const float hi[3], float sigma_t, float albedo, float g, float **density)
{
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    *density = malloc(n * sizeof **density);
    for (size_t i = 0; i < n; ++i) (*density)[i] = 1.0f;
    prt_volume_desc d = {.sigma_t = sigma_t, .g = g, .density = *density};
    for (int c = 0; c < 3; ++c) { d.dims[c] = dims[c]; d.lo[c] = lo[c]; d.hi[c] = hi[c]; d.albedo[c] = albedo; }
    return d;
}

static prt_transfer *bake_sh(prt_context *ctx, prt_scene *s, int order, int samples, unsigned kinds)
{
    prt_sh_bake_desc d = {0};
    d.order = order;
    d.samples = samples;
    d.kinds = kinds;
    d.bounces = 1;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    return t;
}

static prt_lighting *uniform_lighting(float v)
{
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, constant_env(v), NULL, 1.0f), PRT_OK);
    return l;
}

/* A medium of albedo 1 in a uniform white environment: radiance 1 everywhere, whatever the
 * medium's thickness or phase function. The scene's one surface, a tiny square far below, sees
 * and blocks next to nothing. */
static void furnace(float sigma_t, float g, double tol)
{
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-0.01f, -50, -0.01f}, (float[3]){0, 0, 0.02f}, (float[3]){0.02f, 0, 0}, 1);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    float *density;
    const prt_volume_desc vd = box_volume((int[3]){10, 10, 10}, (float[3]){-1, -1, -1}, (float[3]){1, 1, 1}, sigma_t, 1.0f, g, &density);
    assert_int_equal(prt_scene_add_volume(s, &vd), PRT_OK);
    free(density);
    prt_transfer *t = bake_sh(ctx, s, 3, 256, PRT_TRANSFER_SHADOWED);
    prt_lighting *l = uniform_lighting(1.0f);
    prt_relit r;
    /* Relit for the GPU's sums (the viewer's default), the media come along all the same. */
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.gpu_finish = 1}, &r), PRT_OK);
    assert_non_null(r.gpu_sums);
    assert_int_equal(r.volume_count, 1);
    prt_relit_free(&r);
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    assert_int_equal(r.volume_count, 1);
    const prt_render_volume *v = &r.volumes[0];
    assert_int_equal(v->source_order, g != 0 ? 2 : 1);
    /* Each voxel's source towards any direction (band 0: y_0 = 1 / sqrt(4 pi)). */
    double worst = 0, mean = 0;
    const int rows = v->source_order * v->source_order;
    for (size_t k = 0; k < 1000; ++k) {
        const double S = v->source[k * 3 * rows] / sqrt(4 * M_PI);
        worst = fmax(worst, fabs(S - 1));
        mean += S / 1000;
    }
    /* What a camera sees through the medium: the march's light plus what lies behind it, 1 again. */
    double seen_worst = 0;
    for (int i = 0; i < 8; ++i) {
        const float o[3] = {-3, 0.1f * i - 0.4f, 0.05f * i}, d[3] = {1, 0, 0};
        float rgb[3];
        const float T = prt__march_volumes(r.volumes, r.volume_count, o, d, INFINITY, 0.5f, rgb);
        seen_worst = fmax(seen_worst, fabs(rgb[1] + T * 1.0f - 1));
    }
    print_message("furnace, optical thickness %g across, g %g: sources mean %.4f, worst |S - 1| %.4f; through the medium worst |L - 1| %.4f\n",
                  2 * sigma_t, g, mean, worst, seen_worst);
    assert_true(worst < tol);
    assert_true(seen_worst < tol);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static void test_furnace_thin(void **state) { (void)state; furnace(0.5f, 0.0f, 0.02); }
static void test_furnace_thick(void **state) { (void)state; furnace(4.0f, 0.0f, 0.05); }
static void test_furnace_hg(void **state) { (void)state; furnace(1.0f, 0.6f, 0.05); }

/* Transmittance of the slab [-w, w] x [y0, y1] x [-w, w] of extinction sigma seen from the
 * origin, cosine-weighted over the upper hemisphere / pi: what the ground's shadowed transfer
 * gives under a uniform unit sky. */
static double slab_shadow(double w, double y0, double y1, double sigma)
{
    const int nt = 800, np = 400;
    double sum = 0;
    for (int i = 0; i < nt; ++i) {
        const double ct = (i + 0.5) / nt;   /* cos theta, uniform: cos-weighted measure d(cos^2)/2 */
        const double st = sqrt(1 - ct * ct);
        for (int j = 0; j < np; ++j) {
            const double ph = 2 * M_PI * (j + 0.5) / np, d[3] = {st * cos(ph), ct, st * sin(ph)};
            /* The ray's stretch inside the box. */
            double a = y0 / d[1], b = y1 / d[1];
            for (int c = 0; c < 3; c += 2) {
                if (fabs(d[c]) < 1e-12) continue;
                const double ta = fmin(-w / d[c], w / d[c]), tb = fmax(-w / d[c], w / d[c]);
                a = fmax(a, ta);
                b = fmin(b, tb);
            }
            const double len = b > a ? b - a : 0;
            sum += exp(-sigma * len) * 2 * ct / nt / np;   /* d(cos^2 theta) = 2 cos dcos; dphi / 2pi */
        }
    }
    return sum;
}

static void test_slab_shadow(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-4, 0, -4}, (float[3]){0, 0, 8}, (float[3]){8, 0, 0}, 8);
    prt_scene *s = tm_scene(ctx, &m, 1.0f);
    const float sigmas[2] = {0.5f, 2.0f};
    for (int q = 0; q < 2; ++q) {
        float *density;
        prt_scene *sq = tm_scene(ctx, &m, 1.0f);
        const prt_volume_desc vd = box_volume((int[3]){12, 3, 12}, (float[3]){-6, 1, -6}, (float[3]){6, 2, 6}, sigmas[q], 0.8f, 0.0f, &density);
        assert_int_equal(prt_scene_add_volume(sq, &vd), PRT_OK);
        free(density);
        prt_transfer *t = bake_sh(ctx, sq, 3, 16384, PRT_TRANSFER_SHADOWED);
        prt_lighting *l = uniform_lighting(1.0f);
        prt_relit r;
        assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
        const size_t v = nearest_vertex(prt_scene_positions(sq), prt_scene_vertex_count(sq), (float[3]){0, 0, 0});
        const double want = slab_shadow(6, 1, 2, sigmas[q]), got = r.radiance[v * 3 + 1];
        print_message("slab of optical depth %.1f: ground under it %.4f, analytic %.4f (2 E3(tau) of an infinite slab %s)\n", sigmas[q], got, want,
                      q ? "0.0375" : "0.4432");
        assert_float_equal(got, want, 0.01);
        prt_relit_free(&r);
        prt_lighting_release(l);
        prt_transfer_release(t);
        prt_scene_release(sq);
    }
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static void test_grid_files(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    char path[512];
    snprintf(path, sizeof path, "%s/g.grid", test_dir);
    const int dims[3] = {5, 4, 3};
    float *d = NULL;
    assert_int_equal(prt_volume_generate(ctx, "smoke", dims, 3, &d), PRT_OK);
    float *again = NULL;
    assert_int_equal(prt_volume_generate(ctx, "smoke", dims, 3, &again), PRT_OK);
    assert_memory_equal(d, again, 60 * sizeof(float));   /* deterministic for a seed */
    free(again);
    assert_int_equal(prt_volume_grid_save(ctx, path, dims, d), PRT_OK);
    int got[3];
    float *back = NULL;
    assert_int_equal(prt_volume_grid_load(ctx, path, got, &back), PRT_OK);
    assert_memory_equal(got, dims, sizeof dims);
    assert_memory_equal(back, d, 60 * sizeof(float));
    free(back);
    size_t size;
    unsigned char *file = test_slurp(path, &size);
    assert_int_equal(size, 28 + 60 * 4 + 4);
    /* Every damage refused, by what is wrong. */
    struct { const char *what; size_t at; uint32_t value; int fix_crc; size_t size; } bad[] = {
        {"magic", 0, 0x21212121, 0, 0},
        {"version 2", 8, 2, 1, 0},
        {"axis 0", 12, 0, 1, 0},
        {"axis 1", 16, 100000, 1, 0},
        {"flags", 24, 1, 1, 0},
        {"needs", 12, 6, 1, 0},                    /* more voxels than the file holds */
        {"CRC", 40, 0x3f800000, 0, 0},             /* a value changed, the CRC not */
        {"holds", 40, 0x7fc00000, 1, 0},           /* NaN */
        {"holds", 44, 0xbf800000, 1, 0},           /* -1 */
        {"shorter", 0, 0, 0, 20},                  /* truncated */
        {"needs", 0, 0, 0, 28 + 59 * 4 + 4},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        unsigned char *b = malloc(size);
        memcpy(b, file, size);
        size_t n = bad[i].size ? bad[i].size : size;
        if (!bad[i].size) memcpy(b + bad[i].at, &bad[i].value, 4);
        if (bad[i].fix_crc) {
            /* prt's CRC-32 (IEEE) of everything before the last 4 bytes. */
            uint32_t crc = 0xFFFFFFFFu;
            for (size_t k = 0; k < n - 4; ++k) {
                crc ^= b[k];
                for (int j = 0; j < 8; ++j) crc = crc >> 1 ^ (0xEDB88320u & (0u - (crc & 1)));
            }
            crc ^= 0xFFFFFFFFu;
            memcpy(b + n - 4, &crc, 4);
        }
        float *out = (float *)1;
        int od[3];
        assert_int_equal(prt_volume_grid_parse(ctx, b, n, od, &out), PRT_ERR_FORMAT);
        assert_null(out);
        print_message("%s: %s\n", bad[i].what, prt_last_error());
        assert_non_null(strstr(prt_last_error(), bad[i].what));
        free(b);
    }
    free(file);
    /* A scene names grid files and procedural grids; mistakes are named. */
    char scene_path[512], obj[512];
    write_text("plane.obj", "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 3 2\nf 1 4 3\n", obj, sizeof obj);
    write_text("v.json", "{\"meshes\": [{\"file\": \"plane.obj\"}], \"volumes\": [{\"file\": \"g.grid\", \"min\": [0, 1, 0], \"max\": [1, 2, 1], "
                         "\"extinction\": 3, \"albedo\": [0.9, 0.8, 0.7], \"g\": 0.4}, {\"procedural\": \"cloud\", \"resolution\": [8, 6, 4], \"seed\": 2, "
                         "\"min\": [0, 1, 0], \"max\": [1, 2, 1]}]}", scene_path, sizeof scene_path);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, scene_path, NULL, &s), PRT_OK);
    assert_int_equal(prt_scene_volume_count(s), 2);
    prt_volume_desc vd;
    assert_int_equal(prt_scene_volume(s, 0, &vd), PRT_OK);
    assert_true(vd.dims[0] == 5 && vd.dims[2] == 3 && vd.sigma_t == 3 && fabsf(vd.g - 0.4f) < 1e-6f && fabsf(vd.albedo[2] - 0.7f) < 1e-6f);
    assert_memory_equal(vd.density, d, 60 * sizeof(float));
    assert_int_equal(prt_scene_volume(s, 1, &vd), PRT_OK);
    assert_true(vd.dims[0] == 8 && vd.dims[1] == 6 && vd.dims[2] == 4);
    prt_scene_release(s);
    const char *wrong[][2] = {
        {"{\"procedural\": \"fog\", \"min\": [0, 0, 0], \"max\": [1, 1, 1]}", "fog"},
        {"{\"procedural\": \"cloud\", \"min\": [0, 0, 0]}", "\"max\""},
        {"{\"procedural\": \"cloud\", \"file\": \"g.grid\", \"min\": [0, 0, 0], \"max\": [1, 1, 1]}", "not both"},
        {"{\"procedural\": \"cloud\", \"min\": [0, 0, 0], \"max\": [1, 1, 1], \"g\": 1}", "g must"},
        {"{\"procedural\": \"cloud\", \"min\": [0, 0, 0], \"max\": [1, 1, 1], \"colour\": 1}", "colour"},
        {"{\"file\": \"missing.grid\", \"min\": [0, 0, 0], \"max\": [1, 1, 1]}", "missing.grid"},
        {"{\"procedural\": \"smoke\", \"resolution\": 0, \"min\": [0, 0, 0], \"max\": [1, 1, 1]}", "resolution"},
    };
    for (size_t i = 0; i < sizeof wrong / sizeof *wrong; ++i) {
        char text[1024];
        snprintf(text, sizeof text, "{\"meshes\": [{\"file\": \"plane.obj\"}], \"volumes\": [%s]}", wrong[i][0]);
        write_text("w.json", text, scene_path, sizeof scene_path);
        assert_int_equal(prt_scene_load(ctx, scene_path, NULL, &s), PRT_ERR_FORMAT);
        print_message("%s\n", prt_last_error());
        assert_non_null(strstr(prt_last_error(), wrong[i][1]));
        assert_non_null(strstr(prt_last_error(), "volumes[0]"));
    }
    free(d);
    /* examples/cloud.json loads: the demo scene it names (../out/scene.obj, as the README's tour
       writes it) and a 32^3 procedural cloud. Copied beside a fresh demo scene in the test folder. */
    char example[1024], text[4096], dir[1024], copy[1024];
    snprintf(example, sizeof example, "%s", __FILE__);
    char *cut = strstr(example, "tests/methods/sh/test_volume.c");
    if (cut) {
        strcpy(cut, "examples/cloud.json");
        FILE *f = fopen(example, "rb");
        assert_non_null(f);
        size_t n = fread(text, 1, sizeof text - 1, f);
        fclose(f);
        text[n] = 0;
        snprintf(dir, sizeof dir, "%s/out", test_dir);
        assert_int_equal(mkdir(dir, 0700), 0);
        snprintf(copy, sizeof copy, "%s/out/scene.obj", test_dir);
        assert_int_equal(prt_demo_scene_write(copy), PRT_OK);
        snprintf(dir, sizeof dir, "%s/examples", test_dir);
        assert_int_equal(mkdir(dir, 0700), 0);
        snprintf(copy, sizeof copy, "%s/examples/cloud.json", test_dir);
        f = fopen(copy, "wb");
        assert_non_null(f);
        assert_int_equal(fwrite(text, 1, n, f), n);
        fclose(f);
        assert_int_equal(prt_scene_load(ctx, copy, NULL, &s), PRT_OK);
        assert_int_equal(prt_scene_volume_count(s), 1);
        assert_int_equal(prt_scene_volume(s, 0, &vd), PRT_OK);
        assert_true(vd.dims[0] == 32 && vd.dims[1] == 32 && vd.dims[2] == 32 && vd.g > 0);
        prt_scene_release(s);
    }
    prt_context_release(ctx);
}

/* The same bake on 1 and 2 threads writes the same file; the file reads back with its volume. */
static void test_threads_and_file(void **state)
{
    (void)state;
    prt_transfer *t[2];
    prt_context *ctxs[2];
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-2, 0, -2}, (float[3]){0, 0, 4}, (float[3]){4, 0, 0}, 6);
    tm_closed_box(&m, (float[3]){0.2f, 0, 0.2f}, (float[3]){0.6f, 1.4f, 0.6f}, 2);   /* reaching into the cloud */
    for (int i = 0; i < 2; ++i) {
        ctxs[i] = test_context(i + 1);
        prt_scene *s = tm_scene(ctxs[i], &m, 0.6f);
        const int dims[3] = {10, 8, 10};
        float *d;
        assert_int_equal(prt_volume_generate(ctxs[i], "cloud", dims, 5, &d), PRT_OK);
        prt_volume_desc vd = {.dims = {10, 8, 10}, .density = d, .lo = {-1, 0.5f, -1}, .hi = {1, 2, 1}, .sigma_t = 5, .albedo = {0.9f, 0.9f, 0.8f}, .g = 0.3f};
        assert_int_equal(prt_scene_add_volume(s, &vd), PRT_OK);
        free(d);
        t[i] = bake_sh(ctxs[i], s, 3, 64, PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED);
        prt_scene_release(s);
    }
    assert_same_file(t[0], t[1], "volume_threads");
    char path[512];
    snprintf(path, sizeof path, "%s/volume_threads_a.prt", test_dir);
    prt_transfer *back = NULL;
    assert_int_equal(prt_transfer_load(ctxs[0], path, &back), PRT_OK);
    prt_lighting *l = uniform_lighting(1.0f);
    prt_relit a, b;
    assert_int_equal(prt_relight(ctxs[0], t[0], l, NULL, &a), PRT_OK);
    assert_int_equal(prt_relight(ctxs[0], back, l, NULL, &b), PRT_OK);
    assert_int_equal(b.volume_count, 1);
    assert_int_equal(b.volumes[0].source_order, 2);
    double worst = 0;
    for (size_t k = 0; k < 800 * 3 * 4; ++k) worst = fmax(worst, fabs(a.volumes[0].source[k] - b.volumes[0].source[k]) / (fabs(a.volumes[0].source[k]) + 1e-2));
    print_message("volume transfer read back: worst relative difference %.2g (halves)\n", worst);
    assert_true(worst < 2e-3);
    /* prt info reports it. */
    char *text = NULL;
    assert_int_equal(prt_transfer_describe(back, NULL, 0, &text), PRT_OK);
    assert_non_null(strstr(text, "volume"));
    free(text);
    prt_relit_free(&a);
    prt_relit_free(&b);
    prt_lighting_release(l);
    prt_transfer_release(back);
    for (int i = 0; i < 2; ++i) { prt_transfer_release(t[i]); prt_context_release(ctxs[i]); }
    tm_free(&m);
}

/* A small homogeneous medium under a smooth sky (exactly SH order 3): what the bake's ray march
 * sees through it against the path tracer (delta tracking, HG sampling, the sky by next-event
 * estimation) at a few rays, isotropic and forward-scattering. */
static void vs_path_tracer(float g, float albedo, double tol)
{
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-0.01f, -50, -0.01f}, (float[3]){0, 0, 0.02f}, (float[3]){0.02f, 0, 0}, 1);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    float *density;
    const prt_volume_desc vd = box_volume((int[3]){4, 4, 4}, (float[3]){-1, -1, -1}, (float[3]){1, 1, 1}, 1.5f, albedo, g, &density);
    assert_int_equal(prt_scene_add_volume(s, &vd), PRT_OK);
    free(density);
    prt_transfer *t = bake_sh(ctx, s, 3, 256, PRT_TRANSFER_SHADOWED);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, band_limited_env(128), NULL, 1.0f), PRT_OK);
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    const float rays[4][6] = {{-3, 0.2f, 0.1f, 1, 0, 0}, {0.1f, 3, -0.3f, 0, -1, 0}, {0.3f, -3, 0, 0, 1, 0}, {0, 0.4f, 3, 0, 0, -1}};
    double worst = 0;
    for (int i = 0; i < 4; ++i) {
        float baked[3], ref[3], err;
        prt__march_volumes(r.volumes, r.volume_count, rays[i], rays[i] + 3, INFINITY, 0.5f, baked);
        prt_reference_desc rd = {.lighting = l, .seed = 3};
        assert_int_equal(prt__reference_media_radiance(ctx, s, &rd, rays[i], rays[i] + 3, 40000, ref, &err), PRT_OK);
        const double rel = fabs(baked[1] - ref[1]) / ref[1];
        print_message("g %.1f, ray %d: baked %.4f %.4f %.4f, path tracer %.4f %.4f %.4f (+- %.4f): %.1f%%\n", g, i, baked[0], baked[1], baked[2], ref[0], ref[1],
                      ref[2], err, 100 * rel);
        worst = fmax(worst, rel);
    }
    assert_true(worst < tol);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static void test_vs_path_tracer_isotropic(void **state) { (void)state; vs_path_tracer(0.0f, 0.8f, 0.05); }
static void test_vs_path_tracer_hg(void **state) { (void)state; vs_path_tracer(0.5f, 0.8f, 0.10); }

/* The viewer's slices (OpenGL, 3D textures) and prt_render's ray march draw the same cloud over
 * the same ground: the images agree. Skips without an OpenGL context. */
static void test_slices_vs_march(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-3, 0, -3}, (float[3]){0, 0, 6}, (float[3]){6, 0, 0}, 12);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    const int dims[3] = {16, 12, 16};
    float *d;
    assert_int_equal(prt_volume_generate(ctx, "cloud", dims, 4, &d), PRT_OK);
    prt_volume_desc vd = {.dims = {16, 12, 16}, .density = d, .lo = {-1.5f, 0.5f, -1.5f}, .hi = {1.5f, 2.5f, 1.5f}, .sigma_t = 6, .albedo = {0.9f, 0.9f, 0.9f}, .g = 0.4f};
    assert_int_equal(prt_scene_add_volume(s, &vd), PRT_OK);
    free(d);
    prt_transfer *t = bake_sh(ctx, s, 3, 64, PRT_TRANSFER_SHADOWED);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, band_limited_env(64), NULL, 1.0f), PRT_OK);
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    prt_render_mesh mesh;
    prt_relit_render_mesh(t, &r, &mesh);
    prt_renderer *ren = NULL;
    if (prt_renderer_create(ctx, &(prt_renderer_desc){160, 120, 1}, &ren) != PRT_OK) {
        print_message("no OpenGL context (%s): skipped\n", prt_last_error());
    } else {
        const prt_camera cam = {{4, 2.5f, 5}, {0, 1.2f, 0}, {0, 0, 0}, 45};
        prt_image march, slices, bare;
        const float bg[3] = {0.1f, 0.1f, 0.1f};
        assert_int_equal(prt_render(ren, &mesh, &cam, bg, &march), PRT_OK);
        prt_renderer_set_volume_slices(ren, 1);
        assert_int_equal(prt_render(ren, &mesh, &cam, bg, &slices), PRT_OK);
        prt_render_mesh none = mesh;
        none.volume_count = 0;
        assert_int_equal(prt_render(ren, &none, &cam, bg, &bare), PRT_OK);
        double diff = 0, mean = 0, cloud = 0;
        for (size_t i = 0; i < (size_t)160 * 120 * 3; ++i) {
            diff += fabs(march.rgb[i] - slices.rgb[i]);
            mean += march.rgb[i];
            cloud += fabs(march.rgb[i] - bare.rgb[i]);
        }
        print_message("slices against the ray march: mean |difference| %.2f%% of the mean radiance; the cloud changes the image by %.1f%%\n", 100 * diff / mean,
                      100 * cloud / mean);
        if (getenv("PRT_VOLUME_IMAGES")) {
            prt_image_save("/tmp/volume_march.png", &march, NULL);
            prt_image_save("/tmp/volume_slices.png", &slices, NULL);
        }
        assert_true(cloud / mean > 0.05);   /* the cloud is there */
        assert_true(diff / mean < 0.05);
        prt_image_free(&march);
        prt_image_free(&slices);
        prt_image_free(&bare);
        prt_renderer_release(ren);
    }
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_furnace_thin),
        cmocka_unit_test(test_furnace_thick),
        cmocka_unit_test(test_furnace_hg),
        cmocka_unit_test(test_slab_shadow),
        cmocka_unit_test(test_vs_path_tracer_isotropic),
        cmocka_unit_test(test_vs_path_tracer_hg),
        cmocka_unit_test(test_slices_vs_march),
        cmocka_unit_test(test_grid_files),
        cmocka_unit_test(test_threads_and_file),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
