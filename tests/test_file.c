/* The .prt container: round trip and rejection of damaged files. */
#include "common.h"

#include <sys/stat.h>
#include <zlib.h>
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

static void *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    rewind(f);
    void *p = malloc(*size);
    assert_int_equal(fread(p, 1, *size, f), *size);
    fclose(f);
    return p;
}

static void spit(const char *path, const void *p, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(p, 1, n, f), n);
    fclose(f);
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
    unsigned char *orig = slurp(path, &n), *buf = malloc(n);

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
    spit(path, orig, n - 7);
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


/* Overwrites bytes of chunk `id` at `offset` and fixes every checksum, so that only the loader's
 * own checks can catch the change. */
static void patch_chunk(unsigned char *file, const char *id, size_t offset, const void *bytes, size_t n)
{
    uint32_t count;
    memcpy(&count, file + 12, 4);
    for (uint32_t i = 0; i < count; ++i) {
        unsigned char *e = file + 24 + 24 * (size_t)i;
        if (memcmp(e, id, 4)) continue;
        uint64_t off, len;
        memcpy(&off, e + 8, 8);
        memcpy(&len, e + 16, 8);
        assert_true(offset + n <= len);
        memcpy(file + off + offset, bytes, n);
        uint32_t crc = (uint32_t)crc32(0L, file + off, (uInt)len);
        memcpy(e + 4, &crc, 4);
        uint32_t zero = 0;
        memcpy(file + 20, &zero, 4);
        crc = (uint32_t)crc32(0L, file, (uInt)(24 + 24 * (size_t)count));
        memcpy(file + 20, &crc, 4);
        return;
    }
    fail_msg("no chunk %s", id);
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
    unsigned char *orig = slurp(path, &size), *f = malloc(size);
    const float zero3[3] = {0, 0, 0}, huge = 3e38f, too_bright = 1.5f;
    struct { const char *chunk; size_t offset; const void *bytes; size_t n; const char *says; } cases[] = {
        {"MESH", 16 + nv * 12, zero3, sizeof zero3, "normal"},          /* a zeroed normal */
        {"MESH", 16, &huge, sizeof huge, "position"},                   /* a coordinate near FLT_MAX */
        {"MESH", 16 + nv * 24 + 4, &too_bright, sizeof too_bright, "albedo"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memcpy(f, orig, size);
        patch_chunk(f, cases[i].chunk, cases[i].offset, cases[i].bytes, cases[i].n);
        assert_int_equal(prt_transfer_load_memory(ctx, f, size, &u), PRT_ERR_FORMAT);
        assert_non_null(strstr(prt_last_error(), cases[i].says));
        assert_null(u);
    }
    free(f);
    free(orig);
    prt_transfer_release(t);
    /* A wavelet file whose declared terms disagree with its vertices' term counts (the K-vector
     * buffers are sized from the former). */
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 6, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_brdf phong;
    assert_int_equal(prt_brdf_parse("phong:10:0.5:0.3", &phong), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, 0, prt_scene_vertex_count(s), &phong), PRT_OK);
    prt_wavelet_bake_desc wd = {0};
    wd.terms = 2;
    wd.coefficients = 16;
    wd.supersample = 1;
    wd.brdf_resolution = 8;
    assert_int_equal(prt_bake_wavelet(ctx, s, &wd, &t), PRT_OK);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    orig = slurp(path, &size);
    const uint32_t one = 1, tiny = 4;
    patch_chunk(orig, "WAVP", 0, &one, sizeof one);
    assert_int_equal(prt_transfer_load_memory(ctx, orig, size, &u), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "terms"));
    free(orig);
    orig = slurp(path, &size);
    patch_chunk(orig, "WBRF", 12, &tiny, sizeof tiny);   /* a factorization of another resolution */
    assert_int_equal(prt_transfer_load_memory(ctx, orig, size, &u), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "factorization"));
    free(orig);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Offset files (texel patches, maps, media) whose checksums are right but whose contents are
 * not: each is refused with a message that says what. */
static void test_crafted_offset_contents(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){0, 0, 1}, (float[3]){1, 0, 0}, (float[3]){0, 0, -1}, 4);   /* a floor, up */
    tm_quad(&m, (float[3]){0, 0, 0}, (float[3]){1, 0, 0}, (float[3]){0, 1, 0}, 4);    /* a wall, facing +z */
    prt_scene *scene = tm_scene(ctx, &m, 0.6f);
    float *uv = malloc(m.nv * 2 * sizeof *uv);
    for (size_t v = 0; v < m.nv; ++v) {   /* the floor left, the wall right */
        const bool wall = v >= 25;
        uv[v * 2] = 0.5f * m.pos[v * 3] + (wall ? 0.5f : 0.0f);
        uv[v * 2 + 1] = wall ? m.pos[v * 3 + 1] : 1.0f - m.pos[v * 3 + 2];
    }
    assert_int_equal(prt_scene_set_uv(scene, 0, m.nv, uv), PRT_OK);
    free(uv);
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("offset"), &o), PRT_OK);
    const char *kv[] = {"texels", "8", "offsets", "5", "iterations", "10", "transfer", "both", "uv", "mesh"};
    for (int i = 0; i < 10; i += 2) assert_int_equal(prt_options_set(o, kv[i], kv[i + 1]), PRT_OK);
    prt_transfer *t = NULL, *u = NULL;
    assert_int_equal(prt_bake(ctx, scene, prt_method_find("offset"), o, NULL, &t), PRT_OK);
    prt_offset_info info;
    assert_int_equal(prt_transfer_offset_info(t, &info), 1);
    char path[512];
    path_in(path, sizeof path, "o.prt");
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);   /* as saved, it loads */
    prt_transfer_release(u);
    size_t size;
    unsigned char *orig = slurp(path, &size), *f = malloc(size);
    const uint32_t five = 5, big_offset = 8, zero = 0, medium_9 = 0x09090909u;
    const float far = 1e6f, bright = 100.0f, long_normal[3] = {0, 2, 0};
    struct { const char *chunk; size_t offset; const void *bytes; size_t n; const char *says; } cases[] = {
        {"OFSP", 0, &five, 4, "parameters out of range"},                     /* a map of 5 texels a side */
        {"OFSP", 72, &big_offset, 4, "beyond the light map"},                 /* an offset as wide as the map */
        {"OFST", 0, &medium_9, 4, "out of order or beyond"},                  /* a texel index past the map */
        {"OFST", (size_t)info.covered * 4, &far, 4, "outside the mesh"},        /* a texel point far away */
        {"OFST", (size_t)info.covered * 4 + 12, long_normal, 12, "unit length"},
        {"OFSR", 0, &bright, 4, "more light than it can"},                    /* a map entry of 100 */
        {"OFSD", 0, &zero, 4, "media chunk"},                                 /* no media */
        {"OFSD", 4 + 32, &medium_9, 4, "medium is out of range"},             /* texels of medium 9 of 1 */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        memcpy(f, orig, size);
        patch_chunk(f, cases[i].chunk, cases[i].offset, cases[i].bytes, cases[i].n);
        assert_int_equal(prt_transfer_load_memory(ctx, f, size, &u), PRT_ERR_FORMAT);
        if (!strstr(prt_last_error(), cases[i].says)) fail_msg("case %zu: '%s' does not say '%s'", i, prt_last_error(), cases[i].says);
        assert_null(u);
    }
    free(orig);
    free(f);
    prt_transfer_release(t);
    prt_options_release(o);
    prt_scene_release(scene);
    tm_free(&m);
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
        cmocka_unit_test(test_crafted_offset_contents),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
