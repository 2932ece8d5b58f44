/* The ambient-occlusion method: accessibility against closed forms (an open plane, a convex
 * sphere, a floor under a resting sphere, the floor of a pit), relighting under constant and
 * band-limited environments, the reference path tracer's direct light, files that round-trip and
 * damaged files refused. */
#include "common.h"
#include "methods/ao/ao.h"

static prt_transfer *bake_ao(prt_context *ctx, const prt_scene *s, const char *samples, const char *seed)
{
    const prt_method *m = prt_method_find("ao");
    assert_non_null(m);
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(m, &o), PRT_OK);
    if (samples) assert_int_equal(prt_options_set(o, "samples", samples), PRT_OK);
    if (seed) assert_int_equal(prt_options_set(o, "seed", seed), PRT_OK);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, s, m, o, NULL, &t), PRT_OK);
    prt_options_release(o);
    assert_ptr_equal(prt_transfer_method(t), m);
    return t;
}

static const float *access_of(const prt_transfer *t)
{
    const prt__ao_set *s = prt__ao(t);
    assert_non_null(s);
    return s->access;
}

static prt_lighting *lighting_of(prt_envmap *env)
{
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, env, NULL, 1.0f), PRT_OK);
    return l;
}

/* A 1 x 1 plane's vertices see the whole hemisphere; so does every vertex of a sphere alone
 * (convex: no ray above a vertex's tangent plane meets it again). */
static void test_unoccluded(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-0.5f, 0, 0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, -1}, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_transfer *t = bake_ao(ctx, s, NULL, NULL);
    const float *a = access_of(t);
    for (size_t v = 0; v < m.nv; ++v)
        if (a[v] != 1.0f) fail_msg("plane vertex %zu: A = %g, expected 1", v, a[v]);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);

    tm_sphere(&m, (float[3]){0.3f, 1.0f, -0.2f}, 0.7f, 16, 32);
    s = tm_scene(ctx, &m, 0.5f);
    t = bake_ao(ctx, s, "1024", "7");
    a = access_of(t);
    float lo = 1.0f;
    for (size_t v = 0; v < m.nv; ++v) lo = fminf(lo, a[v]);
    print_message("convex sphere: least A %.6f over %zu vertices\n", lo, m.nv);
    assert_true(lo >= 0.999f);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A sphere of radius R resting on a floor: a floor point at distance d from the contact sees the
 * whole sphere above its horizon, and the cosine-weighted solid angle it covers is the form factor
 * R^2 h / D^3 (D the distance to the centre, h = R its height), so A(d) = 1 - R^3 / (d^2 + R^2)^1.5:
 * 0 at the contact, 0.65 at d = R, 0.99 at d = 4R. */
static void test_sphere_on_floor(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    const float R = 0.5f;
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-2, 0, 2}, (float[3]){4, 0, 0}, (float[3]){0, 0, -4}, 64);
    const size_t floor_nv = m.nv;
    tm_sphere(&m, (float[3]){0, R, 0}, R, 32, 64);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_transfer *t = bake_ao(ctx, s, "1024", NULL);
    const float *a = access_of(t);
    double worst = 0, sum = 0;
    int n = 0;
    float near_max = 0.0f, far_min = 1.0f;
    for (size_t v = 0; v < floor_nv; ++v) {
        const float *p = m.pos + v * 3;
        const double d = sqrt((double)p[0] * p[0] + (double)p[2] * p[2]);
        if (d <= 0.25 * R) near_max = fmaxf(near_max, a[v]);
        if (d >= 3.5 * R) far_min = fminf(far_min, a[v]);
        if (d < 0.5 * R || d > 3 * R) continue;
        const double want = 1.0 - pow(R, 3) / pow(d * d + (double)R * R, 1.5), err = fabs(a[v] - want);
        if (err > 0.03) fail_msg("floor vertex at d = %.3f: A = %.4f, closed form %.4f", d, a[v], want);
        worst = fmax(worst, err);
        sum += err;
        n++;
    }
    print_message("sphere on a floor: |A - closed form| mean %.4f, worst %.4f over %d vertices; A <= %.3f near the contact, >= %.3f far "
                  "away\n", sum / n, worst, n, near_max, far_min);
    assert_true(sum / n < 0.01);
    assert_true(near_max < 0.3f);
    assert_true(far_min > 0.97f);
    /* The sphere's top sees only sky; its lowest ring (normals 6 degrees off straight down) almost
     * only the floor. */
    const size_t top = floor_nv, low_ring = floor_nv + 1 + 30 * 64;
    print_message("sphere: A = %.4f at the top, %.4f on the lowest ring\n", a[top], a[low_ring]);
    assert_true(a[top] == 1.0f);
    assert_true(a[low_ring] < 0.05f);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The floor centre of an open unit pit sees the sky only through its unit opening one unit up: the
 * form factor of a centred parallel square, 4 x (1/2pi) 2 X/sqrt(1+X^2) atan(X/sqrt(1+X^2)) with
 * X = 1/2, that is 0.2395. */
static void test_pit_floor(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_pit(&m, 16);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    prt_transfer *t = bake_ao(ctx, s, "4096", NULL);
    const size_t centre = nearest_vertex(m.pos, m.nv, (float[3]){0, 0, 0});
    const double X = 0.5, q = sqrt(1 + X * X), want = 4.0 / (2 * M_PI) * 2 * X / q * atan(X / q);
    const float got = access_of(t)[centre];
    print_message("pit floor centre: A = %.4f, closed form %.4f\n", got, want);
    assert_true(fabs(got - want) < 0.01);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Under a constant environment of radiance L a Lambertian vertex of albedo rho reflects exactly
 * rho L A (E = pi L whatever its normal); with colours given at run time, those colours. A
 * band-limited environment on an open plane gives rho / pi E(n) of its SH projection. */
static void test_relight(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 16);
    tm_sphere(&m, (float[3]){0, 0.45f, 0}, 0.4f, 12, 24);
    const float rho = 0.6f, L = 1.5f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    prt_transfer *t = bake_ao(ctx, s, "256", NULL);
    const size_t nv = prt_transfer_vertex_count(t);
    const float *a = access_of(t);
    prt_lighting *l = lighting_of(constant_env(L));
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    assert_null(r.exit_sh);
    assert_null(r.kvec);
    assert_null(r.texels);
    for (size_t v = 0; v < nv; ++v)
        for (int c = 0; c < 3; ++c)
            if (fabsf(r.radiance[v * 3 + c] - rho * L * a[v]) > 1e-4f * rho * L)
                fail_msg("vertex %zu: radiance %g, rho L A = %g", v, r.radiance[v * 3 + c], rho * L * a[v]);
    prt_relit_free(&r);
    /* Colours live: a different albedo per vertex. */
    float *albedo = malloc(nv * 3 * sizeof(float));
    for (size_t i = 0; i < nv * 3; ++i) albedo[i] = (float)(i % 7) / 6.0f;
    prt_relight_desc d = {.variant = -1, .albedo = albedo};
    assert_int_equal(prt_relight(ctx, t, l, &d, &r), PRT_OK);
    for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(r.radiance[i], albedo[i] * L * a[i / 3], 1e-4f);
    prt_relit_free(&r);
    free(albedo);
    /* What it cannot do is refused with a reason. */
    d = (prt_relight_desc){.variant = -1, .component = PRT_COMPONENT_INDIRECT};
    assert_int_equal(prt_relight(ctx, t, l, &d, &r), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "indirect"));
    prt_light sun;
    assert_int_equal(prt_light_parse("directional:0,1,0:3", &sun), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &sun, NULL), PRT_OK);
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "method 'ao' cannot relight directional lights"));
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);

    /* The open plane (A = 1) under a band-limited environment: rho / pi E(+y). */
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 4);
    s = tm_scene(ctx, &m, rho);
    t = bake_ao(ctx, s, NULL, NULL);
    l = lighting_of(band_limited_env(256));
    double zh[3], y[9];
    prt_sh_clamped_cosine_zh(3, zh);
    prt_sh_eval(3, (const double[3]){0, 1, 0}, y);
    double e = 0;
    for (int li = 0; li < 3; ++li)
        for (int mm = -li; mm <= li; ++mm) e += sqrt(4 * M_PI / (2 * li + 1)) * zh[li] * test_known_sh[li * (li + 1) + mm] * y[li * (li + 1) + mm];
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    const float tint[3] = {1.0f, 0.8f, 0.6f};
    for (size_t v = 0; v < m.nv; ++v)
        for (int c = 0; c < 3; ++c) {
            const double want = rho / M_PI * e * tint[c];
            if (fabs(r.radiance[v * 3 + c] - want) > 5e-3 * want) fail_msg("plane vertex %zu: %g, rho/pi E = %g", v, r.radiance[v * 3 + c], want);
        }
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Under a constant environment AO relighting is the exact direct light, which the path tracer's
 * direct part estimates independently: they must agree within its noise. */
static void test_vs_reference(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 16);
    tm_sphere(&m, (float[3]){0, 0.4f, 0}, 0.4f, 12, 24);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    prt_transfer *t = bake_ao(ctx, s, "2048", NULL);
    prt_envmap *env = constant_env(1.0f);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, constant_env(1.0f), NULL, 1.0f), PRT_OK);
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    prt_scene *ts = NULL;
    assert_int_equal(prt_transfer_scene(ctx, t, &ts), PRT_OK);
    prt_reference_desc d = {0};
    d.samples = 512;
    d.seed = 3;
    prt_reference_vertices ref;
    assert_int_equal(prt_reference_trace_vertices(ctx, ts, env, &d, &ref), PRT_OK);
    const size_t nv = prt_transfer_vertex_count(t);
    assert_int_equal(ref.vertex_count, nv);
    double num = 0, den = 0, noise = 0;
    for (size_t i = 0; i < nv * 3; ++i) {
        num += ((double)r.radiance[i] - ref.direct[i]) * ((double)r.radiance[i] - ref.direct[i]);
        den += (double)ref.direct[i] * ref.direct[i];
        noise += (double)ref.std_error[i] * ref.std_error[i];   /* of all light: a bound for the direct part's */
    }
    const double rel = sqrt(num / den), rel_noise = sqrt(noise / den);
    print_message("ao vs the reference's direct light under a constant sky: relative L2 %.4f (reference noise at most %.4f)\n", rel, rel_noise);
    assert_true(rel < 1.5 * rel_noise + 0.01);
    prt_reference_vertices_free(&ref);
    prt_scene_release(ts);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_envmap_release(env);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static prt_scene *small_scene(prt_context *ctx, test_mesh *m)
{
    tm_quad(m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 8);
    tm_sphere(m, (float[3]){0, 0.45f, 0}, 0.4f, 8, 12);
    return tm_scene(ctx, m, 0.6f);
}

/* Saved and loaded, a file saves to the same bytes outside META and relights the same; prt info
 * describes it in both forms; the seed changes the directions, not the estimate. */
static void test_file_round_trip(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    prt_scene *s = small_scene(ctx, &m);
    prt_transfer *t = bake_ao(ctx, s, "128", "5");
    char pa[512], pb[512];
    snprintf(pa, sizeof pa, "%s/ao_a.prt", test_dir);
    snprintf(pb, sizeof pb, "%s/ao_b.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, pa), PRT_OK);
    prt_transfer *u = NULL;
    assert_int_equal(prt_transfer_load(ctx, pa, &u), PRT_OK);
    assert_ptr_equal(prt_transfer_method(u), prt_method_find("ao"));
    assert_int_equal(prt_transfer_save(u, pb), PRT_OK);
    assert_same_chunks(pa, pb);
    assert_int_equal(prt__ao(u)->samples, 128);
    assert_int_equal(prt__ao(u)->seed, 5);
    assert_int_equal(prt_transfer_bytes(u), m.nv * sizeof(float));
    prt_lighting *l = lighting_of(constant_env(2.0f));
    prt_relit ra, rb;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &ra), PRT_OK);
    assert_int_equal(prt_relight(ctx, u, l, NULL, &rb), PRT_OK);
    assert_memory_equal(ra.radiance, rb.radiance, m.nv * 3 * sizeof(float));
    prt_relit_free(&ra);
    prt_relit_free(&rb);
    prt_lighting_release(l);
    char *text = NULL;
    assert_int_equal(prt_transfer_describe(u, "ao_a.prt", 0, &text), PRT_OK);
    assert_non_null(strstr(text, "ambient occlusion (ao)"));
    assert_non_null(strstr(text, "128 cosine-weighted rays"));
    free(text);
    assert_int_equal(prt_transfer_describe(u, "ao_a.prt", 1, &text), PRT_OK);
    assert_non_null(strstr(text, "\"accessibility_mean\""));
    free(text);
    /* Another seed: other directions, the same answer within the noise. */
    prt_transfer *w = bake_ao(ctx, s, "128", "6");
    const float *a = access_of(t), *b = access_of(w);
    double diff = 0;
    int differ = 0;
    for (size_t v = 0; v < m.nv; ++v) { diff += fabs(a[v] - b[v]); differ += a[v] != b[v]; }
    assert_true(differ > 0);
    assert_true(diff / m.nv < 0.03);
    prt_transfer_release(w);
    prt_transfer_release(u);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* One field of a saved file changed (checksums fixed): the loader's own checks refuse it. */
static void expect_refused(const unsigned char *file, size_t size, const char *chunk, size_t offset, const void *bytes, size_t n,
                           const char *why)
{
    unsigned char *b = malloc(size);
    memcpy(b, file, size);
    test_patch_chunk(b, chunk, offset, bytes, n);
    prt_transfer *t = NULL;
    prt_status st = prt_transfer_load_memory(NULL, b, size, &t);
    if (st != PRT_ERR_FORMAT) fail_msg("%s at %zu: loaded with status %d", chunk, offset, (int)st);
    assert_null(t);
    if (!strstr(prt_last_error(), why)) fail_msg("%s at %zu: '%s' does not say '%s'", chunk, offset, prt_last_error(), why);
    free(b);
}

/* Chunk `from` renamed `to` in the table (its checksum fixed): the loader must refuse the file. */
static void expect_renamed_refused(const unsigned char *file, size_t size, const char *from, const char *to, const char *why)
{
    unsigned char *b = malloc(size);
    memcpy(b, file, size);
    uint32_t count, zero = 0;
    memcpy(&count, b + 12, 4);
    bool found = false;
    for (uint32_t i = 0; i < count && !found; ++i)
        if (!memcmp(b + 24 + 24 * (size_t)i, from, 4)) { memcpy(b + 24 + 24 * (size_t)i, to, 4); found = true; }
    assert_true(found);
    memcpy(b + 20, &zero, 4);
    const uint32_t crc = (uint32_t)crc32(0L, b, (uInt)(24 + 24 * (size_t)count));
    memcpy(b + 20, &crc, 4);
    prt_transfer *t = NULL;
    assert_int_equal(prt_transfer_load_memory(NULL, b, size, &t), PRT_ERR_FORMAT);
    assert_null(t);
    if (!strstr(prt_last_error(), why)) fail_msg("%s renamed %s: '%s' does not say '%s'", from, to, prt_last_error(), why);
    free(b);
}

static void test_bad_input(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    prt_scene *s = small_scene(ctx, &m);
    prt_transfer *t = bake_ao(ctx, s, "64", NULL);
    char path[512];
    snprintf(path, sizeof path, "%s/ao_bad.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    size_t size;
    unsigned char *file = test_slurp(path, &size);
    prt_transfer *u = NULL;
    assert_int_equal(prt_transfer_load_memory(ctx, file, size, &u), PRT_OK);   /* untouched, it loads */
    prt_transfer_release(u);
    const uint32_t zero = 0, huge = 1u << 30, too_many = (uint32_t)m.nv + 1;
    const uint64_t nv1 = m.nv + 1;
    const float big = 1e30f, nan = NAN, above = 1.5f, below = -0.25f;
    expect_refused(file, size, "AOCP", 0, &zero, 4, "parameters out of range");        /* no samples */
    expect_refused(file, size, "AOCP", 0, &huge, 4, "parameters out of range");        /* too many */
    expect_refused(file, size, "AOCP", 8, &big, 4, "ray offset");                      /* beyond the scene */
    expect_refused(file, size, "AOCP", 8, &nan, 4, "ray offset");
    expect_refused(file, size, "AOCP", 12, &too_many, 4, "parameters out of range");   /* buried > vertices */
    expect_refused(file, size, "AOCP", 16, &nv1, 8, "parameter chunk");                /* another mesh's */
    expect_refused(file, size, "AOCA", 0, &above, 4, "outside [0, 1]");
    expect_refused(file, size, "AOCA", 4 * (m.nv - 1), &below, 4, "outside [0, 1]");
    expect_refused(file, size, "AOCA", 8, &nan, 4, "outside [0, 1]");
    /* A chunk renamed away is a chunk missing. */
    expect_renamed_refused(file, size, "AOCP", "AOCX", "parameter chunk missing");
    expect_renamed_refused(file, size, "AOCA", "AOCX", "ambient occlusion chunk missing");
    free(file);
    /* Options outside their declarations never reach the bake. */
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("ao"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "8"), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_options_set(o, "seed", "-1"), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_options_set(o, "order", "3"), PRT_ERR_INVALID_ARG);
    prt_options_release(o);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unoccluded),
        cmocka_unit_test(test_sphere_on_floor),
        cmocka_unit_test(test_pit_floor),
        cmocka_unit_test(test_relight),
        cmocka_unit_test(test_vs_reference),
        cmocka_unit_test(test_file_round_trip),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
