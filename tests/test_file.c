/* The .prt container: round trip and rejection of damaged files. */
#include "common.h"

#include <sys/stat.h>
#include <unistd.h>


static void path_in(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", test_dir, name); }

static prt_transfer *small_bake(prt_context *ctx)
{
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 4);
    tm_sphere(&m, (float[3]){0, 0.5f, 0}, 0.4f, 8, 12);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    prt_bake_desc d = {0};
    d.order = 3;
    d.samples = 64;
    d.seed = 42;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    prt_scene_release(s);
    tm_free(&m);
    return t;
}

static void test_round_trip(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = small_bake(ctx), *u = NULL;
    char path[512];
    path_in(path, sizeof path, "a.prt");
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    prt_transfer_info a, b;
    prt_transfer_get_info(t, &a);
    prt_transfer_get_info(u, &b);
    assert_int_equal(a.vertex_count, b.vertex_count);
    assert_int_equal(a.triangle_count, b.triangle_count);
    assert_int_equal(a.order, b.order);
    assert_int_equal(a.kinds, b.kinds);
    assert_int_equal(a.samples, b.samples);
    assert_int_equal(b.seed, 42);
    assert_string_equal(a.source, b.source);
    size_t nv = a.vertex_count;
    assert_memory_equal(prt_transfer_positions(t), prt_transfer_positions(u), nv * 12);
    assert_memory_equal(prt_transfer_normals(t), prt_transfer_normals(u), nv * 12);
    assert_memory_equal(prt_transfer_albedo(t), prt_transfer_albedo(u), nv * 12);
    assert_memory_equal(prt_transfer_indices(t), prt_transfer_indices(u), a.triangle_count * 12);
    const prt_transfer_kind kinds[3] = {PRT_TRANSFER_UNSHADOWED, PRT_TRANSFER_SHADOWED, PRT_TRANSFER_INTERREFLECTED};
    for (int k = 0; k < 3; ++k) {
        int ch = prt_transfer_channels(t, kinds[k]);
        assert_int_equal(ch, prt_transfer_channels(u, kinds[k]));
        assert_memory_equal(prt_transfer_coeffs(t, kinds[k]), prt_transfer_coeffs(u, kinds[k]), nv * (size_t)ch * 9 * 4);
    }
    /* No temporary file is left beside the result. */
    char cmd[600];
    snprintf(cmd, sizeof cmd, "ls %s | grep -q tmp", test_dir);
    assert_int_not_equal(system(cmd), 0);
    prt_transfer_release(u);
    prt_transfer_release(t);
    prt_context_release(ctx);
}

static void expect_rejected(prt_context *ctx, const void *data, size_t n, const char *needle)
{
    prt_transfer *u = (prt_transfer *)ctx;
    prt_status st = prt_transfer_load_memory(ctx, data, n, &u);
    assert_int_equal(st, PRT_ERR_FORMAT);
    assert_null(u);
    if (!strstr(prt_last_error(), needle)) fail_msg("error '%s' does not mention '%s'", prt_last_error(), needle);
}

static void test_damaged_files(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = small_bake(ctx);
    char path[512];
    path_in(path, sizeof path, "b.prt");
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    size_t n;
    unsigned char *orig = test_slurp(path, &n), *buf = malloc(n);

    /* A flipped byte anywhere is caught: in the header, the table, each chunk. */
    const size_t positions[] = {9, 30, n / 3, n / 2, n - 5};
    for (size_t i = 0; i < sizeof positions / sizeof positions[0]; ++i) {
        memcpy(buf, orig, n);
        buf[positions[i]] ^= 0x10;
        prt_transfer *u = NULL;
        prt_status st = prt_transfer_load_memory(ctx, buf, n, &u);
        if (st != PRT_ERR_FORMAT) fail_msg("flipped byte at %zu accepted (status %d)", positions[i], st);
        assert_null(u);
    }
    memcpy(buf, orig, n);
    buf[n / 2] ^= 1;
    expect_rejected(ctx, buf, n, "checksum");

    /* Truncated at several points. */
    expect_rejected(ctx, orig, 10, "truncated");   /* the magic is there: a cut file, not another format */
    expect_rejected(ctx, orig, 40, "truncated");
    expect_rejected(ctx, orig, n - 1, "truncated");
    expect_rejected(ctx, orig, n / 2, "truncated");

    /* A newer version is refused by name; a damaged version byte is damage. */
    memcpy(buf, orig, n);
    buf[8] = 99;
    expect_rejected(ctx, buf, n, "checksum");
    uint32_t count;
    memcpy(&count, buf + 12, 4);
    const size_t table_end = 24 + 24 * (size_t)count;
    memset(buf + 20, 0, 4);
    const uint32_t crc = (uint32_t)crc32(0L, buf, (uInt)table_end);
    memcpy(buf + 20, &crc, 4);
    expect_rejected(ctx, buf, n, "newer");

    /* Not a .prt at all. */
    expect_rejected(ctx, "hello world, this is not a prt file at all", 42, "not a .prt");

    /* The file variant names the file. */
    path_in(path, sizeof path, "c.prt");
    test_spit(path, orig, n - 7);
    prt_transfer *u = NULL;
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "c.prt"));
    path_in(path, sizeof path, "missing.prt");
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_ERR_IO);
    assert_non_null(strstr(prt_last_error(), "missing.prt"));

    free(orig);
    free(buf);
    prt_transfer_release(t);
    prt_context_release(ctx);
}


/* A file whose checksums are right but whose contents are not: each is refused by name. */
static void test_crafted_contents(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = small_bake(ctx), *u = NULL;
    char path[512];
    path_in(path, sizeof path, "c.prt");
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    const size_t nv = prt_transfer_vertex_count(t);
    size_t size;
    unsigned char *orig = test_slurp(path, &size), *f = malloc(size);
    const float zero3[3] = {0, 0, 0}, huge = 3e38f, too_bright = 1.5f;
    struct { const char *chunk; size_t offset; const void *bytes; size_t n; const char *says; } cases[] = {
        {"MESH", 16 + nv * 12, zero3, sizeof zero3, "normal"},          /* a zeroed normal */
        {"MESH", 16, &huge, sizeof huge, "position"},                   /* a coordinate near FLT_MAX */
        {"MESH", 16 + nv * 24 + 4, &too_bright, sizeof too_bright, "albedo"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memcpy(f, orig, size);
        test_patch_chunk(f, cases[i].chunk, cases[i].offset, cases[i].bytes, cases[i].n);
        assert_int_equal(prt_transfer_load_memory(ctx, f, size, &u), PRT_ERR_FORMAT);
        assert_non_null(strstr(prt_last_error(), cases[i].says));
        assert_null(u);
    }
    free(f);
    free(orig);
    prt_transfer_release(t);
    prt_context_release(ctx);
}

static void test_failed_save_leaves_nothing(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = small_bake(ctx);
    char path[512];
    path_in(path, sizeof path, "no/such/test_dir/x.prt");
    assert_int_equal(prt_transfer_save(t, path), PRT_ERR_IO);
    assert_non_null(strstr(prt_last_error(), "x.prt"));
    /* Overwriting keeps the old file intact until the new one is complete. */
    path_in(path, sizeof path, "d.prt");
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    prt_transfer *u = NULL;
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    prt_transfer_release(u);
    prt_transfer_release(t);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_damaged_files),
        cmocka_unit_test(test_failed_save_leaves_nothing),
        cmocka_unit_test(test_crafted_contents),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
