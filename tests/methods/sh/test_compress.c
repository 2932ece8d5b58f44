/* PCA, VQ and clustered PCA of transfer sets. */
#include "common.h"

static prt_transfer *bake_pit(prt_context *ctx, int order)
{
    test_mesh m = {0};
    tm_pit(&m, 10);
    tm_sphere(&m, (float[3]){0.1f, 0.3f, -0.1f}, 0.2f, 10, 20);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    prt_bake_desc d = {0};
    d.order = order;
    d.samples = 256;
    d.bounces = 2;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    prt_scene_release(s);
    tm_free(&m);
    return t;
}

static prt_transfer *compress_set(prt_context *ctx, const prt_transfer *t, prt_compress_method method, int clusters, int vectors)
{
    prt_compress_desc d = {0};
    d.method = method;
    d.clusters = clusters;
    d.vectors = vectors;
    prt_transfer *z = NULL;
    assert_int_equal(prt_transfer_compress(ctx, t, &d, &z), PRT_OK);
    return z;
}

static double max_error(const prt_transfer *a, const prt_transfer *b, prt_transfer_kind kind)
{
    size_t n = prt_transfer_vertex_count(a) * (size_t)prt_transfer_channels(a, kind) * 9 * 9;
    float *x = malloc(n * sizeof(float)), *y = malloc(n * sizeof(float));
    prt_transfer_info info;
    prt_transfer_get_info(a, &info);
    n = prt_transfer_vertex_count(a) * (size_t)prt_transfer_channels(a, kind) * (size_t)(info.order * info.order);
    assert_int_equal(prt_transfer_reconstruct(a, kind, x), PRT_OK);
    assert_int_equal(prt_transfer_reconstruct(b, kind, y), PRT_OK);
    double e = 0;
    for (size_t i = 0; i < n; ++i) e = fmax(e, fabs(x[i] - y[i]));
    free(x);
    free(y);
    return e;
}

/* As many PCA vectors as the data's dimension reconstruct it exactly; so does CPCA with one
 * vector per dimension in every cluster. */
static void test_full_rank_is_exact(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = bake_pit(ctx, 3);
    prt_transfer *pca = compress_set(ctx, t, PRT_COMPRESS_PCA, 0, 27);   /* the 3-channel set has 27 dimensions */
    prt_transfer *cpca = compress_set(ctx, t, PRT_COMPRESS_CPCA, 8, 27);
    const prt_transfer_kind kinds[3] = {PRT_TRANSFER_UNSHADOWED, PRT_TRANSFER_SHADOWED, PRT_TRANSFER_INTERREFLECTED};
    for (int k = 0; k < 3; ++k) {
        assert_true(max_error(t, pca, kinds[k]) < 1e-5);
        assert_true(max_error(t, cpca, kinds[k]) < 1e-5);
    }
    prt_transfer_release(pca);
    prt_transfer_release(cpca);
    prt_transfer_release(t);
    prt_context_release(ctx);
}

/* Error falls as clusters or vectors grow. */
static void check_monotonic(prt_context *ctx, const prt_transfer *t, const char *what)
{
    const int vectors[4] = {1, 2, 4, 8}, clusters[4] = {1, 4, 16, 64};
    double last = INFINITY;
    for (int i = 0; i < 4; ++i) {
        prt_transfer *z = compress_set(ctx, t, PRT_COMPRESS_CPCA, 8, vectors[i]);
        prt_compress_info ci;
        assert_int_equal(prt_transfer_compress_info(z, PRT_TRANSFER_INTERREFLECTED, &ci), PRT_OK);
        print_message("%s: 8 clusters, %d vectors: relative error %.5f\n", what, vectors[i], ci.relative_error);
        assert_true(ci.compressed && ci.relative_error < last);
        last = ci.relative_error;
        prt_transfer_release(z);
    }
    last = INFINITY;
    for (int i = 0; i < 4; ++i) {
        prt_transfer *z = compress_set(ctx, t, PRT_COMPRESS_CPCA, clusters[i], 4);
        prt_compress_info ci;
        assert_int_equal(prt_transfer_compress_info(z, PRT_TRANSFER_INTERREFLECTED, &ci), PRT_OK);
        print_message("%s: %d clusters, 4 vectors: relative error %.5f\n", what, clusters[i], ci.relative_error);
        assert_true(ci.relative_error < last);
        last = ci.relative_error;
        prt_transfer_release(z);
    }
}

static void test_error_falls(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = bake_pit(ctx, 4);
    check_monotonic(ctx, t, "pit");
    prt_transfer_release(t);
    const char *data = shared_data_dir();
    char path[1024];
    if (data) snprintf(path, sizeof path, "%s/meshes/bunny/bunny_lowres.obj", data);
    if (!data || access(path, R_OK) != 0) {
        print_message("skipping the bunny part: ../shared/data is absent\n");
    } else {
        prt_scene *s = NULL;
        assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
        prt_bake_desc d = {0};
        d.order = 4;
        d.samples = 256;
        d.bounces = 2;
        assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
        check_monotonic(ctx, t, "bunny");
        prt_transfer_release(t);
        prt_scene_release(s);
    }
    prt_context_release(ctx);
}

/* Relighting a compressed set differs from the original by at most what Cauchy-Schwarz allows:
 * per vertex and channel |dL| <= |dT| |L| (times the albedo for one-channel sets). */
static void test_relight_bound(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = bake_pit(ctx, 4);
    prt_transfer *z = compress_set(ctx, t, PRT_COMPRESS_CPCA, 6, 3);
    prt_envmap *sky = NULL;
    prt_sh_light L;
    assert_int_equal(prt_sky_create(NULL, &sky), PRT_OK);
    assert_int_equal(prt_envmap_project_sh(sky, 4, &L), PRT_OK);
    size_t nv = prt_transfer_vertex_count(t);
    float *a = malloc(nv * 3 * sizeof(float)), *b = malloc(nv * 3 * sizeof(float));
    float *ta = malloc(nv * 48 * sizeof(float)), *tb = malloc(nv * 48 * sizeof(float));
    const prt_transfer_kind kinds[3] = {PRT_TRANSFER_UNSHADOWED, PRT_TRANSFER_SHADOWED, PRT_TRANSFER_INTERREFLECTED};
    double norm[3];
    for (int c = 0; c < 3; ++c) {
        norm[c] = 0;
        for (int i = 0; i < 16; ++i) norm[c] += (double)L.coeffs[c][i] * L.coeffs[c][i];
        norm[c] = sqrt(norm[c]);
    }
    for (int k = 0; k < 3; ++k) {
        int ch = prt_transfer_channels(t, kinds[k]);
        assert_int_equal(prt_relight_sh(ctx, t, kinds[k], &L, a), PRT_OK);
        assert_int_equal(prt_relight_sh(ctx, z, kinds[k], &L, b), PRT_OK);
        assert_int_equal(prt_transfer_reconstruct(t, kinds[k], ta), PRT_OK);
        assert_int_equal(prt_transfer_reconstruct(z, kinds[k], tb), PRT_OK);
        const float *albedo = prt_transfer_albedo(t);
        for (size_t v = 0; v < nv; ++v)
            for (int c = 0; c < 3; ++c) {
                const float *x = ta + (v * ch + (ch == 3 ? c : 0)) * 16, *y = tb + (v * ch + (ch == 3 ? c : 0)) * 16;
                double dt = 0;
                for (int i = 0; i < 16; ++i) dt += (double)(x[i] - y[i]) * (x[i] - y[i]);
                double bound = sqrt(dt) * norm[c] * (ch == 1 ? albedo[v * 3 + c] : 1.0) + 1e-4;
                if (fabs(a[v * 3 + c] - b[v * 3 + c]) > bound)
                    fail_msg("%s vertex %zu: |%g - %g| exceeds %g", prt_transfer_kind_name(kinds[k]), v, a[v * 3 + c], b[v * 3 + c], bound);
            }
    }
    free(a); free(b); free(ta); free(tb);
    prt_envmap_release(sky);
    prt_transfer_release(z);
    prt_transfer_release(t);
    prt_context_release(ctx);
}

/* VQ keeps only clusters: every vertex is its cluster's mean. The files round-trip, and the
 * result does not depend on the thread count. */
static void test_vq_files_and_determinism(void **state)
{
    (void)state;
    prt_context *one = test_context(1), *two = test_context(2);
    prt_transfer *t = bake_pit(two, 3);
    prt_transfer *v1 = compress_set(one, t, PRT_COMPRESS_VQ, 16, 0), *v2 = compress_set(two, t, PRT_COMPRESS_VQ, 16, 0);
    prt_compress_info ci;
    assert_int_equal(prt_transfer_compress_info(v1, PRT_TRANSFER_SHADOWED, &ci), PRT_OK);
    assert_int_equal(ci.vectors_total, 0);
    assert_true(ci.clusters <= 16 && ci.clusters > 1);
    assert_true(max_error(v1, v2, PRT_TRANSFER_INTERREFLECTED) == 0.0);
    prt_transfer *c1 = compress_set(one, t, PRT_COMPRESS_CPCA, 5, 3), *c2 = compress_set(two, t, PRT_COMPRESS_CPCA, 5, 3);
    assert_true(max_error(c1, c2, PRT_TRANSFER_INTERREFLECTED) == 0.0);
    /* Every byte of the files, the reported errors included, except META's timing fields. */
    for (int k = 0; k < 3; ++k) {
        prt_compress_info i1, i2;
        assert_int_equal(prt_transfer_compress_info(c1, (prt_transfer_kind)(1 << k), &i1), PRT_OK);
        assert_int_equal(prt_transfer_compress_info(c2, (prt_transfer_kind)(1 << k), &i2), PRT_OK);
        assert_memory_equal(&i1.rms_error, &i2.rms_error, sizeof i1.rms_error);
        assert_memory_equal(&i1.relative_error, &i2.relative_error, sizeof i1.relative_error);
    }
    char path[512];
    snprintf(path, sizeof path, "%s/c.prt", test_dir);
    assert_int_equal(prt_transfer_save(c1, path), PRT_OK);
    prt_transfer *back = NULL;
    assert_int_equal(prt_transfer_load(two, path, &back), PRT_OK);
    assert_true(max_error(c1, back, PRT_TRANSFER_INTERREFLECTED) == 0.0);
    assert_null(prt_transfer_coeffs(back, PRT_TRANSFER_SHADOWED));
    prt_transfer_info a, b;
    prt_transfer_get_info(c1, &a);
    prt_transfer_get_info(t, &b);
    assert_true(a.transfer_bytes < b.transfer_bytes);
    prt_transfer_release(back);
    /* A damaged compressed chunk is rejected. */
    FILE *f = fopen(path, "r+b");
    fseek(f, -8, SEEK_END);
    int byte = fgetc(f);
    fseek(f, -8, SEEK_END);
    fputc(byte ^ 0xff, f);
    fclose(f);
    assert_int_equal(prt_transfer_load(two, path, &back), PRT_ERR_FORMAT);
    assert_null(back);
    /* Bad settings. */
    prt_compress_desc d = {0};
    d.vectors = 1000;
    prt_transfer *z = NULL;
    assert_int_equal(prt_transfer_compress(one, t, &d, &z), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_transfer_compress(one, c1, NULL, &z), PRT_ERR_INVALID_ARG);
    assert_null(z);
    prt_transfer_release(v1); prt_transfer_release(v2); prt_transfer_release(c1); prt_transfer_release(c2);
    prt_transfer_release(t);
    prt_context_release(one);
    prt_context_release(two);
}

/* 8- and 16-bit quantization: every coefficient within half a step of the original, and the
 * file stores exactly the quantized values in about a quarter / half of the bytes. */
static void test_quantization(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = bake_pit(ctx, 3);
    size_t nv = prt_transfer_vertex_count(t);
    const int bits[2] = {8, 16};
    for (int b = 0; b < 2; ++b) {
        prt_transfer *q = NULL;
        assert_int_equal(prt_transfer_quantize(ctx, t, bits[b], &q), PRT_OK);
        const prt_transfer_kind kind = PRT_TRANSFER_INTERREFLECTED;
        const float *x = prt_transfer_coeffs(t, kind), *y = prt_transfer_coeffs(q, kind);
        const int dim = 27;
        for (int j = 0; j < dim; ++j) {
            float lo = INFINITY, hi = -INFINITY;
            for (size_t v = 0; v < nv; ++v) { lo = fminf(lo, x[v * dim + j]); hi = fmaxf(hi, x[v * dim + j]); }
            float half_step = (hi - lo) / (float)((1u << bits[b]) - 1) * 0.5f;
            for (size_t v = 0; v < nv; ++v)
                if (fabsf(x[v * dim + j] - y[v * dim + j]) > half_step * 1.001f + 1e-7f)
                    fail_msg("%d-bit: coefficient %d of vertex %zu moved %g > %g", bits[b], j, v, fabsf(x[v * dim + j] - y[v * dim + j]), half_step);
        }
        char path[512];
        snprintf(path, sizeof path, "%s/q%d.prt", test_dir, bits[b]);
        assert_int_equal(prt_transfer_save(q, path), PRT_OK);
        prt_transfer *back = NULL;
        assert_int_equal(prt_transfer_load(ctx, path, &back), PRT_OK);
        const float *z = prt_transfer_coeffs(back, kind);
        for (size_t i = 0; i < nv * dim; ++i) assert_true(fabsf(z[i] - y[i]) <= 1e-6f * fmaxf(1.0f, fabsf(y[i])));
        prt_compress_info ci;
        assert_int_equal(prt_transfer_compress_info(back, kind, &ci), PRT_OK);
        assert_int_equal(ci.quantize_bits, bits[b]);
        assert_true(ci.bytes < nv * dim * 4 * (size_t)bits[b] / 32 + 1024);
        prt_transfer_release(back);
        /* A quantized transfer compresses (what a default bake of the table gives); the
         * compressed sets keep float weights. */
        prt_transfer *z2 = NULL;
        assert_int_equal(prt_transfer_compress(ctx, q, NULL, &z2), PRT_OK);
        assert_int_equal(prt_transfer_compress_info(z2, kind, &ci), PRT_OK);
        assert_true(ci.compressed && !ci.quantize_bits);
        prt_transfer_release(z2);
        prt_transfer_release(q);
    }
    prt_transfer *q = NULL;
    assert_int_equal(prt_transfer_quantize(ctx, t, 12, &q), PRT_ERR_INVALID_ARG);
    prt_transfer_release(t);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_rank_is_exact),
        cmocka_unit_test(test_error_falls),
        cmocka_unit_test(test_relight_bound),
        cmocka_unit_test(test_vq_files_and_determinism),
        cmocka_unit_test(test_quantization),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
