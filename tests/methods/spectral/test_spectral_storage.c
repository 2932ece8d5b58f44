/* The spectral transfer's storage (format version 3): every row, diffuse and glossy, quantized to
 * 16 bits against its own largest entry, entries below --drop-below x that largest dropped. Checked
 * against the bake's unquantized rows (kept for the test): the drop threshold honoured entry by
 * entry, every stored value within half a step of its row's scale, the relit result within the
 * bound that follows; files round trip bit for bit; files of one scale (SPCT, SPCG: the fuzz
 * seeds, written before per-row scales) still load as that scale on every row; bad sizes and
 * values in the new chunks are refused by name. */
#include "common.h"
#include "methods/spectral/spectral.h"

#ifndef PRT_SOURCE_DIR
#error "PRT_SOURCE_DIR must name the source tree (tests/methods/spectral/CMakeLists.txt)"
#endif

/* A pit with a glossy sphere in it: open (dim rows near the rim, bright ones on the floor). */
static prt_scene *pit_scene(prt_context *ctx, test_mesh *m, bool glossy)
{
    tm_pit(m, 6);
    const size_t pit = m->nv;
    tm_sphere(m, (float[3]){0, 0.3f, 0}, 0.2f, 6, 12);
    prt_scene *s = tm_scene(ctx, m, 0.6f);
    if (glossy) {
        prt_brdf phong;
        assert_int_equal(prt_brdf_parse("phong:20:0.5:0.4", &phong), PRT_OK);
        assert_int_equal(prt_scene_set_brdf(s, pit, m->nv - pit, &phong), PRT_OK);
    }
    return s;
}

static prt_status begin(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job)
{
    (void)scene;
    prt_status st = prt__spectral_bake_begin(ctx, desc, t, job);
    if (!st && !(((prt__spectral_set *)t->state)->cache = prt__spectral_cache_new())) st = PRT_ERR_NO_MEMORY;
    return st;
}

static prt_transfer *bake_kept(prt_context *ctx, const prt_scene *s, float drop)
{
    prt__spectral_bake_desc d = {.functions = 40, .partition_size = 32, .samples = 64, .drop_below = drop, .keep_rows = true};
    prt_transfer *t = NULL;
    if (prt__bake_with(ctx, s, &prt__method_spectral, begin, &d, NULL, &t)) fail_msg("%s", prt_last_error());
    return t;
}

/* Rows [start[r], start[r + 1]) of (index, q) against the raw rows: the scale is the row's
 * largest over 32767, kept are exactly the entries at or above drop x that largest that do not
 * round to zero, and each lies within half a step (and float rounding) of the raw value. */
static void check_rows(size_t rows, const uint64_t *start, const uint16_t *index, const int16_t *q, const float *scale, const uint64_t *raw_start,
                       const uint16_t *raw_index, const float *raw_value, float drop, uint64_t *dropped)
{
    for (size_t r = 0; r < rows; ++r) {
        float m = 0;
        for (uint64_t i = raw_start[r]; i < raw_start[r + 1]; ++i) m = fmaxf(m, fabsf(raw_value[i]));
        assert_float_equal(scale[r], m / 32767.0f, 1e-6f * scale[r] + 1e-30f);
        uint64_t k = start[r];
        int16_t big = 0;
        for (uint64_t i = raw_start[r]; i < raw_start[r + 1]; ++i) {
            const float x = raw_value[i];
            const bool keep = fabsf(x) >= drop * m && lroundf(x * (32767.0f / m)) != 0;   /* as the bake rounds */
            if (!keep) { ++*dropped; continue; }
            assert_true(k < start[r + 1]);
            assert_int_equal(index[k], raw_index[i]);
            assert_true(fabsf(q[k] * scale[r] - x) <= 0.5f * scale[r] + 1e-6f * fabsf(x));   /* half a step, and float rounding */
            if (abs(q[k]) > big) big = (int16_t)abs(q[k]);
            ++k;
        }
        assert_int_equal(k, start[r + 1]);
        if (start[r + 1] > start[r]) assert_int_equal(big, 32767);
    }
}

static void test_drop_threshold(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    prt_scene *s = pit_scene(ctx, &m, true);
    uint64_t dropped_before = 0;
    for (int i = 0; i < 3; ++i) {
        const float drop = i == 0 ? 0.0f : i == 1 ? 1e-3f : 0.05f;
        prt_transfer *t = bake_kept(ctx, s, drop);
        const prt__spectral_set *st = t->state;
        const size_t nv = t->mesh.vertex_count, ng = (size_t)st->glossy_count * PRT__SPECTRAL_GLOSSY_N;
        assert_true(st->glossy_count > 0);
        uint64_t dropped = 0;
        check_rows(nv, st->row_start, st->index, st->value, st->row_scale, st->raw_start, st->raw_index, st->raw_value, drop, &dropped);
        check_rows(ng, st->grow_start, st->gindex, st->gvalue, st->grow_scale, st->raw_gstart, st->raw_gindex, st->raw_gvalue, drop, &dropped);
        if (i) assert_true(dropped > dropped_before);   /* a higher threshold drops more */
        dropped_before = dropped;
        prt_transfer_release(t);
    }
    /* The option reaches the bake, and prt info says what it was. */
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("spectral"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "basis", "40"), PRT_OK);
    assert_int_equal(prt_options_set(o, "partition", "32"), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "64"), PRT_OK);
    assert_int_equal(prt_options_set(o, "drop-below", "0.02"), PRT_OK);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, s, prt_method_find("spectral"), o, NULL, &t), PRT_OK);
    assert_float_equal(((prt__spectral_set *)t->state)->drop, 0.02f, 0);
    char *text = NULL;
    assert_int_equal(prt_transfer_describe(t, "pit.prt", 0, &text), PRT_OK);
    assert_non_null(strstr(text, "16-bit, a scale per row, entries under 0.02 of their row's largest dropped"));
    free(text);
    assert_int_equal(prt_options_set(o, "drop-below", "0.2"), PRT_ERR_INVALID_ARG);   /* 0..0.1 */
    prt_transfer_release(t);
    prt_options_release(o);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Saved and loaded, the storage is the same to the bit and relights the same; relit, it stays
 * within what the quantization and the dropped entries can change: one bounce of irradiance at
 * v differs from the raw rows' by at most sum over v's raw entries of |error of the entry| |c_l|. */
static void test_round_trip_within_bound(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    prt_scene *s = pit_scene(ctx, &m, true);
    prt_transfer *t = bake_kept(ctx, s, 2e-3f);
    char path[1024];
    snprintf(path, sizeof path, "%s/pit.prt", test_dir);
    if (prt_transfer_save(t, path)) fail_msg("%s", prt_last_error());
    prt_transfer *u = NULL;
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    const prt__spectral_set *a = t->state, *b = u->state;
    const size_t nv = t->mesh.vertex_count, ng = (size_t)a->glossy_count * PRT__SPECTRAL_GLOSSY_N;
    assert_false(b->one_scale);
    assert_float_equal(b->drop, 2e-3f, 0);
    assert_memory_equal(a->row_start, b->row_start, (nv + 1) * sizeof(uint64_t));
    assert_memory_equal(a->row_scale, b->row_scale, nv * sizeof(float));
    assert_memory_equal(a->index, b->index, a->row_start[nv] * sizeof(uint16_t));
    assert_memory_equal(a->value, b->value, a->row_start[nv] * sizeof(int16_t));
    assert_memory_equal(a->grow_start, b->grow_start, (ng + 1) * sizeof(uint64_t));
    assert_memory_equal(a->grow_scale, b->grow_scale, ng * sizeof(float));
    assert_memory_equal(a->gvalue, b->gvalue, a->grow_start[ng] * sizeof(int16_t));
    /* The container says it needs version 3: older readers refuse it as newer. */
    size_t n = 0;
    unsigned char *file = test_slurp(path, &n);
    uint32_t version;
    memcpy(&version, file + 8, 4);
    assert_int_equal(version, 3);
    free(file);

    prt_lighting *l = NULL;
    prt_light lamp;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_light_parse("point:0.1,0.8,0.1:3", &lamp), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &lamp, NULL), PRT_OK);
    prt_relit r1, r2;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r1), PRT_OK);
    assert_int_equal(prt_relight(ctx, u, l, NULL, &r2), PRT_OK);
    assert_memory_equal(r1.radiance, r2.radiance, nv * 3 * sizeof(float));
    assert_memory_equal(r1.exit_sh, r2.exit_sh, nv * 3 * PRT__SPECTRAL_GLOSSY_N * sizeof(float));

    /* One bounce through the stored rows against the raw ones, from the same direct light. */
    float *E = calloc(nv * 3, sizeof(float)), *direct = malloc(nv * 3 * sizeof(float)), *stored = malloc(nv * 3 * sizeof(float));
    float *coeffs = calloc((size_t)a->basis.functions * 3, sizeof(float));
    assert_int_equal(prt__spectral_direct(ctx, t, l, E, NULL, 0), PRT_OK);
    for (size_t i = 0; i < nv * 3; ++i) direct[i] = t->mesh.albedo[i] / (float)PRT_PI * E[i];
    assert_int_equal(prt__spectral_bounces(ctx, u, t->mesh.albedo, direct, 1, 0, stored), PRT_OK);   /* one bounce, no tail */
    prt__spectral_project(&a->basis, direct, coeffs, 1);
    int tight = 0;
    for (size_t v = 0; v < nv; ++v) {
        uint64_t k = b->row_start[v];
        for (int c = 0; c < 3; ++c) {
            double raw = 0, bound = 0;
            k = b->row_start[v];
            for (uint64_t i = a->raw_start[v]; i < a->raw_start[v + 1]; ++i) {
                const double x = a->raw_value[i], cl = coeffs[(size_t)a->raw_index[i] * 3 + c];
                raw += x * cl;
                if (k < b->row_start[v + 1] && b->index[k] == a->raw_index[i]) {
                    bound += fabs(b->value[k] * (double)b->row_scale[v] - x) * fabs(cl);
                    ++k;
                } else {
                    bound += fabs(x) * fabs(cl);   /* dropped */
                }
            }
            const double rho = t->mesh.albedo[v * 3 + c] / PRT_PI, want = rho * (raw > 0 ? raw : 0), got = stored[v * 3 + c];
            /* float sums: a relative 1e-5 of the row's magnitude on top */
            double mag = 0;
            for (uint64_t i = a->raw_start[v]; i < a->raw_start[v + 1]; ++i) mag += fabs(a->raw_value[i] * coeffs[(size_t)a->raw_index[i] * 3 + c]);
            assert_true(fabs(got - want) <= rho * (bound + 1e-5 * mag) + 1e-12);
            tight += fabs(got - want) > 0.1 * rho * bound;
        }
    }
    assert_true(tight > 0);   /* the bound is not vacuous: some vertices come near it */
    free(E); free(direct); free(stored); free(coeffs);
    prt_relit_free(&r1);
    prt_relit_free(&r2);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_transfer_release(u);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The bytes and length of chunk id in a file image. */
static unsigned char *chunk_in(unsigned char *file, const char *id, uint64_t *len)
{
    uint32_t count;
    const unsigned char *e = test_chunk_entry(file, id, &count);
    if (!e) return NULL;
    uint64_t off;
    memcpy(&off, e + 8, 8);
    memcpy(len, e + 16, 8);
    return file + off;
}

/* Files of one scale (the fuzz seeds, written by prt before format version 3) load with that
 * scale on every row and their entries as stored; they say so in prt info. */
static void test_one_scale_files_load(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    static const char *seeds[2] = {PRT_SOURCE_DIR "/fuzz/regress/prt/spectral/seed.prt", PRT_SOURCE_DIR "/fuzz/regress/prt/spectral/seed_glossy.prt"};
    for (int i = 0; i < 2; ++i) {
        size_t n = 0;
        unsigned char *file = test_slurp(seeds[i], &n);
        uint64_t len = 0, tlen = 0;
        const unsigned char *spcp = chunk_in(file, "SPCP", &len), *spct = chunk_in(file, "SPCT", &tlen);
        assert_non_null(spcp);
        assert_non_null(spct);
        assert_null(chunk_in(file, "SPCR", &len));
        float scale;
        memcpy(&scale, spcp + 24, 4);
        assert_true(scale > 0);
        prt_transfer *t = NULL;
        if (prt_transfer_load(ctx, seeds[i], &t)) fail_msg("%s: %s", seeds[i], prt_last_error());
        const prt__spectral_set *s = t->state;
        const size_t nv = t->mesh.vertex_count;
        assert_true(s->one_scale);
        for (size_t v = 0; v < nv; ++v) assert_true(s->row_scale[v] == (s->row_start[v + 1] > s->row_start[v] ? scale : 0.0f));
        const uint64_t nnz = s->row_start[nv], padded = (nnz * 2 + 3) & ~3ull;
        assert_int_equal(tlen, nv * 4 + 2 * padded);
        assert_memory_equal(s->index, spct + nv * 4, nnz * 2);
        assert_memory_equal(s->value, spct + nv * 4 + padded, nnz * 2);
        if (s->glossy_count) {
            const unsigned char *spcg = chunk_in(file, "SPCG", &len);
            assert_non_null(spcg);
            float gscale;
            memcpy(&gscale, spcg + 8, 4);
            for (size_t r = 0; r < (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N; ++r)
                assert_true(s->grow_scale[r] == (s->grow_start[r + 1] > s->grow_start[r] ? gscale : 0.0f));
        }
        char *text = NULL;
        assert_int_equal(prt_transfer_describe(t, "seed.prt", 0, &text), PRT_OK);
        assert_non_null(strstr(text, "16-bit, one scale"));
        free(text);
        /* Saved again, it is written in today's storage and relights the same. */
        char path[1024];
        snprintf(path, sizeof path, "%s/again.prt", test_dir);
        if (prt_transfer_save(t, path)) fail_msg("%s", prt_last_error());
        prt_transfer *u = NULL;
        assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
        assert_false(((prt__spectral_set *)u->state)->one_scale);
        prt_lighting *l = NULL;
        prt_light lamp;
        assert_int_equal(prt_lighting_create(&l), PRT_OK);
        assert_int_equal(prt_light_parse("point:0.2,0.7,0.1:3", &lamp), PRT_OK);
        assert_int_equal(prt_lighting_add(l, &lamp, NULL), PRT_OK);
        prt_relit r1, r2;
        assert_int_equal(prt_relight(ctx, t, l, NULL, &r1), PRT_OK);
        assert_int_equal(prt_relight(ctx, u, l, NULL, &r2), PRT_OK);
        assert_memory_equal(r1.radiance, r2.radiance, nv * 3 * sizeof(float));
        prt_relit_free(&r1);
        prt_relit_free(&r2);
        prt_lighting_release(l);
        prt_transfer_release(u);
        prt_transfer_release(t);
        free(file);
    }
    prt_context_release(ctx);
}

static void expect_refused(prt_context *ctx, const unsigned char *orig, size_t n, const char *chunk, size_t offset, const void *bytes, size_t len,
                           const char *words)
{
    unsigned char *buf = malloc(n);
    memcpy(buf, orig, n);
    test_patch_chunk(buf, chunk, offset, bytes, len);
    char path[1024];
    snprintf(path, sizeof path, "%s/bad.prt", test_dir);
    test_spit(path, buf, n);
    prt_transfer *t = NULL;
    assert_int_equal(prt_transfer_load(ctx, path, &t), PRT_ERR_FORMAT);
    if (!strstr(prt_last_error(), words)) fail_msg("%s at %zu: '%s' does not say '%s'", chunk, offset, prt_last_error(), words);
    assert_null(t);
    free(buf);
}

/* Counts and sizes that do not match the chunk, scales out of range, thresholds out of range. */
static void test_bad_sizes_refused(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    prt_scene *s = pit_scene(ctx, &m, true);
    prt_transfer *t = bake_kept(ctx, s, 1e-3f);
    const size_t nv = t->mesh.vertex_count;
    const uint64_t nnz = ((prt__spectral_set *)t->state)->row_start[nv];
    const prt__spectral_set *st = t->state;
    uint32_t empty = UINT32_MAX, full = UINT32_MAX;   /* a vertex whose row kept nothing (if any), one whose row kept something */
    for (size_t v = 0; v < nv; ++v) {
        if (st->row_start[v + 1] == st->row_start[v] && empty == UINT32_MAX) empty = (uint32_t)v;
        if (st->row_start[v + 1] > st->row_start[v] && full == UINT32_MAX) full = (uint32_t)v;
    }
    assert_true(full != UINT32_MAX);
    char path[1024];
    snprintf(path, sizeof path, "%s/good.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    size_t n = 0;
    unsigned char *orig = test_slurp(path, &n);
    const uint32_t huge = 0xFFFFFFFFu, one = 1;
    const uint64_t big = 1ull << 40, more = nnz + 2;
    const float neg = -1.0f, nan_ = NAN, over = 1.0f, half = 0.5f;
    expect_refused(ctx, orig, n, "SPCR", 8, &huge, 4, "counts are inconsistent");
    expect_refused(ctx, orig, n, "SPCR", 8 + (size_t)full * 4, &(uint32_t){0}, 4, "counts are inconsistent");   /* a row short: the sum no longer matches */
    expect_refused(ctx, orig, n, "SPCP", 32, &big, 8, "parameters out of range");
    expect_refused(ctx, orig, n, "SPCP", 32, &more, 8, "transfer chunk size mismatch");
    expect_refused(ctx, orig, n, "SPCP", 24, &over, 4, "scale does not match");   /* one scale beside per-row scales */
    expect_refused(ctx, orig, n, "SPCR", 0, &half, 4, "drop threshold out of range");
    expect_refused(ctx, orig, n, "SPCR", 4, &one, 4, "drop threshold out of range");   /* the reserved word */
    const size_t scales = 8 + nv * 4;
    expect_refused(ctx, orig, n, "SPCR", scales + (size_t)full * 4, &neg, 4, "row scale is out of range");
    expect_refused(ctx, orig, n, "SPCR", scales + (size_t)full * 4, &nan_, 4, "row scale is out of range");
    expect_refused(ctx, orig, n, "SPCR", scales + (size_t)full * 4, &over, 4, "row scale is out of range");   /* beyond pi / 32767 */
    expect_refused(ctx, orig, n, "SPCR", scales + (size_t)full * 4, &(float){0}, 4, "row scale is out of range");   /* zero on a row with entries */
    if (empty != UINT32_MAX) expect_refused(ctx, orig, n, "SPCR", scales + (size_t)empty * 4, &(float){1e-6f}, 4, "row scale is out of range");
    /* The glossy rows: counts, scales. */
    const size_t gh = 16 + 4 + 3 * 16 * 16 * sizeof(float), grows = (size_t)st->glossy_count * PRT__SPECTRAL_GLOSSY_N;   /* one matrix */
    expect_refused(ctx, orig, n, "SPCH", gh, &huge, 4, "glossy counts are inconsistent");
    expect_refused(ctx, orig, n, "SPCH", gh + grows * 4, &nan_, 4, "glossy row scale is out of range");
    expect_refused(ctx, orig, n, "SPCH", 8, &half, 4, "glossy scale out of range");   /* its drop threshold differs from SPCR's */
    free(orig);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_drop_threshold),
        cmocka_unit_test(test_round_trip_within_bound),
        cmocka_unit_test(test_one_scale_files_load),
        cmocka_unit_test(test_bad_sizes_refused),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
