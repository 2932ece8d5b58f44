/* Neighbourhood transfer (src/methods/sh/neighbourhood.c): the radiance arriving at points around a
 * baked scene. Under a black square the sky is missing exactly the square's solid angle; a probe
 * sphere moved through a scene (under a slab, beside it, above it) is lit as the path tracer lights
 * the same sphere placed there. */
#include "common.h"
#include "prt/reference.h"

static prt_transfer *bake(prt_context *ctx, prt_scene *s, int order, int samples, int grid)
{
    prt_sh_bake_desc d = {0};
    d.order = order;
    d.samples = samples;
    d.kinds = PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED;
    d.bounces = 3;
    d.neighbourhood = grid;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    return t;
}

/* The grid's point (i, j, k). */
static void point(const prt_transfer *t, int i, int j, int k, float p[3])
{
    int dims[3];
    float lo[3], hi[3];
    assert_int_equal(prt_transfer_neighbourhood(t, dims, lo, hi), 1);
    const int ix[3] = {i, j, k};
    for (int c = 0; c < 3; ++c) p[c] = lo[c] + (hi[c] - lo[c]) * ix[c] / (dims[c] - 1);
}

static void test_black_square(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    /* A black square of side 2 at y = 1, facing down. */
    tm_quad(&m, (float[3]){-1, 1, -1}, (float[3]){0, 0, 2}, (float[3]){2, 0, 0}, 2);
    prt_scene *s = tm_scene(ctx, &m, 0.0f);
    prt_transfer *t = bake(ctx, s, 3, 16384, 9);
    int dims[3];
    float lo[3], hi[3];
    assert_int_equal(prt_transfer_neighbourhood(t, dims, lo, hi), 1);
    assert_true(dims[0] == 9 && dims[1] == 9 && dims[2] == 9);
    prt_sh_light sky = uniform_light(3), in;
    for (int j = 0; j < 4; ++j) {   /* the grid's points under the square's centre */
        float p[3];
        point(t, 4, j, 4, p);
        assert_int_equal(prt_sh_light_at(ctx, t, p, &sky, &in), PRT_OK);
        const double h = 1 - p[1], omega = 4 * asin(1 / (1 + h * h));   /* a square of half-side 1 at distance h */
        const double want = 1 - omega / (4 * M_PI);
        print_message("%.2f under a black square: sky seen %.4f, by the grid %.4f\n", h, want, in.coeffs[0][0] / sky.coeffs[0][0]);
        assert_float_equal(in.coeffs[0][0] / sky.coeffs[0][0], want, 0.01);
    }
    /* Bad calls and files without a grid: clear errors. */
    float p[3] = {0, 0, 0};
    assert_int_equal(prt_sh_light_at(ctx, t, p, NULL, &in), PRT_ERR_INVALID_ARG);
    p[0] = NAN;
    assert_int_equal(prt_sh_light_at(ctx, t, p, &sky, &in), PRT_ERR_INVALID_ARG);
    prt_transfer_release(t);
    t = bake(ctx, s, 3, 64, 0);
    p[0] = 0;
    assert_int_equal(prt_transfer_neighbourhood(t, NULL, NULL, NULL), 0);
    assert_int_equal(prt_sh_light_at(ctx, t, p, &sky, &in), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "--neighbourhood"));
    prt_transfer_release(t);
    prt_sh_bake_desc d = {.neighbourhood = 65};
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Between a grid point above a floor and one beneath it (many of its rays meet the floor's back),
 * the light is nearly the upper point's: the one beneath counts for little (its weight falls with
 * the share of its rays meeting back faces, to nothing at a quarter). Halfway between two open points
 * it is their mean. */
static void test_points_beneath(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 2);   /* a floor, facing up */
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_transfer *t = bake(ctx, s, 3, 4096, 4);   /* y points at -0.5, -1/6, 1/6, 0.5 */
    prt_sh_light sky = uniform_light(3), mid, above, below, top;
    float p[3], q[3], r[3];
    point(t, 1, 1, 1, q);   /* beneath the floor */
    point(t, 1, 2, 1, p);   /* above it */
    point(t, 1, 3, 1, r);
    assert_true(q[1] < 0 && p[1] > 0);
    assert_int_equal(prt_sh_light_at(ctx, t, p, &sky, &above), PRT_OK);
    assert_int_equal(prt_sh_light_at(ctx, t, q, &sky, &below), PRT_OK);
    const float between[3] = {p[0], 0.5f * (p[1] + q[1]), p[2]};
    assert_int_equal(prt_sh_light_at(ctx, t, between, &sky, &mid), PRT_OK);
    print_message("above the floor %.4f, beneath it %.4f, halfway %.4f\n", above.coeffs[0][0], below.coeffs[0][0], mid.coeffs[0][0]);
    assert_true(fabsf(above.coeffs[0][0] - below.coeffs[0][0]) > 0.1f * above.coeffs[0][0]);
    const float plain = 0.5f * (above.coeffs[0][0] + below.coeffs[0][0]);   /* trilinear alone */
    assert_true(fabsf(mid.coeffs[0][0] - above.coeffs[0][0]) < 0.25f * fabsf(plain - above.coeffs[0][0]));
    const float open_mid[3] = {p[0], 0.5f * (p[1] + r[1]), p[2]};
    assert_int_equal(prt_sh_light_at(ctx, t, r, &sky, &top), PRT_OK);
    assert_int_equal(prt_sh_light_at(ctx, t, open_mid, &sky, &mid), PRT_OK);
    for (int k = 0; k < 9; ++k) assert_float_equal(mid.coeffs[0][k], 0.5f * (above.coeffs[0][k] + top.coeffs[0][k]), 1e-5f);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The sky of the path-tracer comparison: bright above the horizon, dim below. */
static prt_envmap *sky_map(void)
{
    prt_image img = {16, 8, malloc(16 * 8 * 3 * sizeof(float))};
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) img.rgb[(y * 16 + x) * 3 + c] = y < 4 ? 2.0f : 0.2f;
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    return env;
}

static void test_probe_against_reference(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-2, 0, 2}, (float[3]){4, 0, 0}, (float[3]){0, 0, -4}, 8);   /* floor, up */
    tm_closed_box(&m, (float[3]){-0.6f, 1.0f, -0.6f}, (float[3]){0.6f, 1.2f, 0.6f}, 2);   /* a slab over it */
    const size_t scene_vertices = m.nv;
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_transfer *t = bake(ctx, s, 5, 4096, 9);
    prt_envmap *env = sky_map();
    prt_sh_light sky;
    assert_int_equal(prt_envmap_project_sh(env, 5, &sky), PRT_OK);
    double zh[5];
    prt_sh_clamped_cosine_zh(5, zh);
    /* Grid points (x 0.75, y 0.4 apart): under the slab, beside it, above it. */
    const int where[3][3] = {{4, 4, 4}, {6, 4, 4}, {4, 7, 4}};
    const char *names[3] = {"under the slab", "beside it", "above it"};
    for (int k = 0; k < 3; ++k) {
        float p[3];
        point(t, where[k][0], where[k][1], where[k][2], p);
        prt_sh_light in;
        assert_int_equal(prt_sh_light_at(ctx, t, p, &sky, &in), PRT_OK);
        /* The same probe, a sphere of radius 0.08 and albedo 0.5, in the scene for the path tracer. */
        test_mesh probe = m;
        probe.pos = memcpy(malloc(m.nv * 3 * sizeof(float)), m.pos, m.nv * 3 * sizeof(float));
        probe.nrm = memcpy(malloc(m.nv * 3 * sizeof(float)), m.nrm, m.nv * 3 * sizeof(float));
        probe.idx = memcpy(malloc(m.nt * 3 * sizeof(uint32_t)), m.idx, m.nt * 3 * sizeof(uint32_t));
        probe.cap_v = m.nv;
        probe.cap_t = m.nt;
        tm_sphere(&probe, p, 0.08f, 8, 12);
        prt_scene *ps = tm_scene(ctx, &probe, 0.5f);
        prt_reference_vertices ref;
        assert_int_equal(prt_reference_trace_vertices(ctx, ps, env, &(prt_reference_desc){.samples = 2048}, &ref), PRT_OK);
        double e2 = 0, n2 = 0, d2 = 0;
        for (size_t v = scene_vertices; v < probe.nv; ++v) {
            double y[25], E = 0, E0 = 0;
            const double nrm[3] = {probe.nrm[v * 3], probe.nrm[v * 3 + 1], probe.nrm[v * 3 + 2]};
            prt_sh_eval(5, nrm, y);
            for (int l = 0; l < 5; ++l)
                for (int q = l * l; q < (l + 1) * (l + 1); ++q) {
                    E += sqrt(4 * M_PI / (2 * l + 1)) * zh[l] * in.coeffs[0][q] * y[q];
                    E0 += sqrt(4 * M_PI / (2 * l + 1)) * zh[l] * sky.coeffs[0][q] * y[q];
                }
            const double got = 0.5 / M_PI * E, distant = 0.5 / M_PI * E0, want = ref.radiance[v * 3];
            e2 += (got - want) * (got - want);
            d2 += (distant - want) * (distant - want);
            n2 += want * want;
        }
        print_message("probe %s (%.2f, %.2f, %.2f): relative L2 against the path tracer %.4f (the distant sky alone: %.4f)\n", names[k], p[0], p[1],
                      p[2], sqrt(e2 / n2), sqrt(d2 / n2));
        assert_true(sqrt(e2 / n2) < 0.08);
        if (k == 0) assert_true(sqrt(d2 / n2) > 3 * sqrt(e2 / n2));   /* the shadow matters there */
        prt_reference_vertices_free(&ref);
        prt_scene_release(ps);
        tm_free(&probe);
    }
    prt_envmap_release(env);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Saved and loaded, the grid answers the same; a damaged grid chunk is refused. */
static void test_grid_file(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_pit(&m, 4);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_transfer *t = bake(ctx, s, 3, 256, 4), *u = NULL;
    char path[600];
    snprintf(path, sizeof path, "%s/grid.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    prt_sh_light sky = uniform_light(3), a, b;
    const float p[3] = {0.1f, 0.3f, -0.2f};
    assert_int_equal(prt_sh_light_at(ctx, t, p, &sky, &a), PRT_OK);
    assert_int_equal(prt_sh_light_at(ctx, u, p, &sky, &b), PRT_OK);
    assert_memory_equal(&a, &b, sizeof a);
    prt_transfer_release(u);
    /* A grid of 3 points along x where the chunk holds 4; then one of 65; then NaN bounds. */
    const uint32_t patches[3] = {3, 65, 0x7fc00000u};
    const size_t at[3] = {0, 4, 16};
    for (int k = 0; k < 3; ++k) {
        size_t size;
        unsigned char *bytes = test_slurp(path, &size);
        test_patch_chunk(bytes, "NBHD", at[k], &patches[k], 4);
        char bad[640];
        snprintf(bad, sizeof bad, "%s/bad.prt", test_dir);
        test_spit(bad, bytes, size);
        free(bytes);
        assert_int_equal(prt_transfer_load(ctx, bad, &u), PRT_ERR_FORMAT);
        print_message("damaged grid: %s\n", prt_last_error());
        assert_non_null(strstr(prt_last_error(), "neighbourhood"));
    }
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_black_square),
        cmocka_unit_test(test_points_beneath),
        cmocka_unit_test(test_probe_against_reference),
        cmocka_unit_test_setup_teardown(test_grid_file, test_dir_setup, test_dir_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
