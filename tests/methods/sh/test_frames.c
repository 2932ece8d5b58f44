/* Key-framed SH transfer (prt_bake_frames, prt_transfer_at_time): a floor under a blocker that
 * moves across it, in three OBJ key frames. At the key frames the file relights as the frames'
 * own bakes do (within the compression across frames); between them it blends them; topology
 * that differs and a damaged key frames chunk are refused. */
#include "common.h"

#define GRID 24
static const float BLOCKER_X[3] = {-0.3f, 0.0f, 0.3f};

/* Floor [-1, 1]^2 at y = 0 facing up, a 0.6 x 0.6 blocker at height 0.4 centred on x; extra
 * adds a triangle (other topology). */
static void write_frame(const char *name, float x, bool extra, char *path, size_t n)
{
    snprintf(path, n, "%s/%s", test_dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("o floor\n", f);
    for (int j = 0; j <= GRID; ++j)
        for (int i = 0; i <= GRID; ++i) fprintf(f, "v %g 0 %g\n", -1 + 2.0 * i / GRID, -1 + 2.0 * j / GRID);
    for (int j = 0; j < GRID; ++j)
        for (int i = 0; i < GRID; ++i) {
            const int a = j * (GRID + 1) + i + 1;
            fprintf(f, "f %d %d %d\nf %d %d %d\n", a, a + GRID + 1, a + 1, a + 1, a + GRID + 1, a + GRID + 2);
        }
    const int b = (GRID + 1) * (GRID + 1);
    fputs("o blocker\n", f);
    fprintf(f, "v %g 0.4 -0.3\nv %g 0.4 -0.3\nv %g 0.4 0.3\nv %g 0.4 0.3\n", x - 0.3, x + 0.3, x + 0.3, x - 0.3);
    fprintf(f, "f %d %d %d\nf %d %d %d\n", b + 1, b + 2, b + 3, b + 1, b + 3, b + 4);
    if (extra) fprintf(f, "f %d %d %d\n", b + 1, b + 2, b + 4);
    fclose(f);
}

static prt_scene *load(prt_context *ctx, const char *path)
{
    prt_scene_desc sd = {0};
    sd.default_albedo[0] = sd.default_albedo[1] = sd.default_albedo[2] = 0.6f;
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, &sd, &s), PRT_OK);
    return s;
}

static const char *const OPTIONS[] = {"order", "4", "samples", "256", "bounces", "1", "kinds", "shadowed", NULL};

/* The key frames' bake: OPTIONS, and a compression across frames that loses something (16
 * coefficients a row, 4 PCA vectors in each of 8 clusters). */
static prt_options *options(void)
{
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("sh"), &o), PRT_OK);
    for (int i = 0; OPTIONS[i]; i += 2) assert_int_equal(prt_options_set(o, OPTIONS[i], OPTIONS[i + 1]), PRT_OK);
    assert_int_equal(prt_options_set(o, "clusters", "8"), PRT_OK);
    assert_int_equal(prt_options_set(o, "vectors", "4"), PRT_OK);
    return o;
}

/* A sky: uniform light plus more from above. */
static prt_sh_light sky(void)
{
    prt_sh_light l = uniform_light(4);
    for (int c = 0; c < 3; ++c) l.coeffs[c][2] = 2.0f;   /* Y_1^0: the z... whichever axis, the same for every bake */
    for (int c = 0; c < 3; ++c) l.coeffs[c][1] = 1.5f;
    return l;
}

static float *relight(prt_context *ctx, const prt_transfer *t)
{
    const size_t nv = prt_transfer_vertex_count(t);
    float *rgb = malloc(nv * 3 * sizeof(float));
    const prt_sh_light l = sky();
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_SHADOWED, &l, rgb), PRT_OK);
    return rgb;
}

static double rel_l2(const float *a, const float *b, size_t n)
{
    double d = 0, s = 0;
    for (size_t i = 0; i < n; ++i) {
        d += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
        s += (double)b[i] * b[i];
    }
    return sqrt(d / s);
}

static prt_transfer *at(prt_context *ctx, const prt_transfer *t, double time)
{
    prt_transfer *p = NULL;
    assert_int_equal(prt_transfer_at_time(ctx, t, time, &p), PRT_OK);
    return p;
}

static void test_frames(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    char path[3][512], mid_path[512];
    prt_scene *scenes[3];
    for (int f = 0; f < 3; ++f) {
        char name[32];
        snprintf(name, sizeof name, "frame%d.obj", f);
        write_frame(name, BLOCKER_X[f], false, path[f], sizeof path[f]);
        scenes[f] = load(ctx, path[f]);
    }
    prt_options *o = options();
    prt_transfer *anim = NULL;
    assert_int_equal(prt_bake_frames(ctx, (const prt_scene *const *)scenes, 3, prt_method_find("sh"), o, NULL, &anim), PRT_OK);
    assert_int_equal(prt_transfer_frame_count(anim), 3);
    const size_t nv = prt_transfer_vertex_count(anim), n = nv * 3;

    /* At the key frames: the frames' own bakes, within the compression across frames. */
    float *own[3], *keyed[3];
    for (int f = 0; f < 3; ++f) {
        prt_transfer *single = test_bake_with(ctx, scenes[f], "sh", OPTIONS);
        assert_int_equal(prt_transfer_frame_count(single), 1);
        own[f] = relight(ctx, single);
        prt_transfer *p = at(ctx, anim, f);
        assert_memory_equal(prt_transfer_positions(p), prt_transfer_positions(single), nv * 3 * sizeof(float));
        keyed[f] = relight(ctx, p);
        const double e = rel_l2(keyed[f], own[f], n);
        print_message("key frame %d against its own bake: relative L2 %.5f\n", f, e);
        assert_true(e > 0 && e < 0.02);
        prt_transfer_release(p);
        prt_transfer_release(single);
    }
    /* Without a time the file is its first key frame. */
    float *plain = relight(ctx, anim);
    assert_memory_equal(plain, keyed[0], n * sizeof(float));
    free(plain);

    /* Between key frames: the blend of the two (relighting is linear in the coefficients), the
     * pose halfway. */
    prt_transfer *half = at(ctx, anim, 0.5);
    float *mid = relight(ctx, half);
    double blend = 0;
    for (size_t i = 0; i < n; ++i) blend = fmax(blend, fabs(mid[i] - 0.5 * (keyed[0][i] + keyed[1][i])));
    assert_true(blend < 1e-4);
    const float *p0 = prt_transfer_positions(anim), *ph = prt_transfer_positions(half);
    const size_t corner = nv - 4;   /* the blocker's first vertex: x - 0.3 */
    assert_float_equal(ph[corner * 3], 0.5f * (BLOCKER_X[0] + BLOCKER_X[1]) - 0.3f, 1e-5);
    assert_float_equal(p0[corner * 3], BLOCKER_X[0] - 0.3f, 1e-5);

    /* Against a bake of the in-between pose itself: the blend of two shadows is not the shadow
     * halfway, but it is nearer to it than either key frame. */
    write_frame("mid.obj", 0.5f * (BLOCKER_X[0] + BLOCKER_X[1]), false, mid_path, sizeof mid_path);
    prt_scene *ms = load(ctx, mid_path);
    prt_transfer *mt = test_bake_with(ctx, ms, "sh", OPTIONS);
    float *truth = relight(ctx, mt);
    const double e_mid = rel_l2(mid, truth, n), e0 = rel_l2(keyed[0], truth, n), e1 = rel_l2(keyed[1], truth, n);
    print_message("T = 0.5 against a bake of the in-between frame: relative L2 %.4f (key frame 0 %.4f, key frame 1 %.4f)\n", e_mid, e0, e1);
    assert_true(e_mid < e0 && e_mid < e1);
    free(truth);
    prt_transfer_release(mt);
    prt_scene_release(ms);

    /* Times outside the key frames, and times on a transfer of one pose, are refused. */
    prt_transfer *bad = NULL;
    assert_int_equal(prt_transfer_at_time(ctx, anim, 2.01, &bad), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "outside the key frames"));
    assert_int_equal(prt_transfer_at_time(ctx, anim, -0.5, &bad), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_transfer_at_time(ctx, half, 0, &bad), PRT_ERR_INVALID_ARG);
    assert_null(bad);

    /* The file round-trips: the same poses and light at every time. */
    char file[512];
    snprintf(file, sizeof file, "%s/anim.prt", test_dir);
    assert_int_equal(prt_transfer_save(anim, file), PRT_OK);
    prt_transfer *back = NULL;
    assert_int_equal(prt_transfer_load(ctx, file, &back), PRT_OK);
    assert_int_equal(prt_transfer_frame_count(back), 3);
    assert_int_equal(prt_transfer_bytes(back), prt_transfer_bytes(anim));
    prt_transfer *hb = at(ctx, back, 0.5);
    float *mid_back = relight(ctx, hb);
    assert_memory_equal(mid_back, mid, n * sizeof(float));
    free(mid_back);
    prt_transfer_release(hb);
    prt_transfer_release(back);

    /* A damaged key frames chunk is refused, however it is damaged (checksums fixed: only the
     * loader's own checks can catch it). */
    size_t size;
    unsigned char *bytes = test_slurp(file, &size);
    const struct { const char *chunk; size_t offset; uint32_t value; } damage[] = {
        {"FRMS", 0, 4},            /* a frame count the chunk has no room for */
        {"FRMS", 0, 1},            /* one key frame */
        {"FRMS", 8, 7},            /* another vertex count */
        {"FRMS", 16, 0x7fc00000},  /* a NaN position */
        {"FRMS", 16, 0x3f000000},  /* key frame 0 is not the mesh */
        {"FRCP", 24, 7},           /* rows */
        {"FRCP", 16, 100000},      /* clusters */
    };
    for (size_t i = 0; i < sizeof damage / sizeof damage[0]; ++i) {
        unsigned char *copy = malloc(size);
        memcpy(copy, bytes, size);
        test_patch_chunk(copy, damage[i].chunk, damage[i].offset, &damage[i].value, 4);
        prt_transfer *t = NULL;
        assert_int_equal(prt_transfer_load_memory(ctx, copy, size, &t), PRT_ERR_FORMAT);
        assert_null(t);
        print_message("%s +%zu: %s\n", damage[i].chunk, damage[i].offset, prt_last_error());
        free(copy);
    }
    free(bytes);

    /* Topology that differs is refused, naming the key frame. */
    char odd[512];
    write_frame("odd.obj", 0.3f, true, odd, sizeof odd);
    prt_scene_release(scenes[2]);
    scenes[2] = load(ctx, odd);
    prt_transfer *none = NULL;
    assert_int_equal(prt_bake_frames(ctx, (const prt_scene *const *)scenes, 3, prt_method_find("sh"), o, NULL, &none), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "key frame 3"));
    assert_null(none);
    /* So are methods without key frames. */
    prt_options *wo = NULL;
    assert_int_equal(prt_options_create(prt_method_find("wavelet"), &wo), PRT_OK);
    assert_int_equal(prt_bake_frames(ctx, (const prt_scene *const *)scenes, 2, prt_method_find("wavelet"), wo, NULL, &none), PRT_ERR_INVALID_ARG);
    prt_options_release(wo);

    free(mid);
    prt_transfer_release(half);
    for (int f = 0; f < 3; ++f) {
        free(own[f]);
        free(keyed[f]);
        prt_scene_release(scenes[f]);
    }
    prt_transfer_release(anim);
    prt_options_release(o);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_frames)};
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
