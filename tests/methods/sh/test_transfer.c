/* Diffuse SH transfer against analytic answers. */
#include "common.h"

static prt_transfer *bake(prt_context *ctx, prt_scene *s, int order, int samples, unsigned kinds)
{
    prt_bake_desc d = {0};
    d.order = order;
    d.samples = samples;
    d.kinds = kinds;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    return t;
}

/* An upward plane sees the whole upper hemisphere: its unshadowed transfer must be the
 * clamped cosine about +y, T_lm = (1/pi) sqrt(4pi/(2l+1)) c_l y_lm(+y), and shadowed must equal it. */
static void test_unoccluded_plane(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 4);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    const int order = 6, n = order * order;
    prt_transfer *t = bake(ctx, s, order, 4096, PRT_TRANSFER_UNSHADOWED | PRT_TRANSFER_SHADOWED);
    double zh[PRT_SH_MAX_ORDER], y[PRT_SH_MAX_COEFFS], up[3] = {0, 1, 0};
    prt_sh_clamped_cosine_zh(order, zh);
    prt_sh_eval(order, up, y);
    const float *un = prt_transfer_coeffs(t, PRT_TRANSFER_UNSHADOWED), *sh = prt_transfer_coeffs(t, PRT_TRANSFER_SHADOWED);
    double worst = 0;
    for (size_t v = 0; v < prt_transfer_vertex_count(t); ++v)
        for (int l = 0; l < order; ++l)
            for (int mm = -l; mm <= l; ++mm) {
                int i = l * (l + 1) + mm;
                double expect = sqrt(4 * M_PI / (2 * l + 1)) * zh[l] * y[i] / M_PI;
                worst = fmax(worst, fabs(un[v * n + i] - expect));
                assert_true(un[v * n + i] == sh[v * n + i]);
            }
    if (worst > 2e-3) fail_msg("unshadowed transfer differs from the clamped cosine by %g", worst);
    /* Under uniform unit light, exit radiance = albedo. */
    prt_sh_light L = uniform_light(order);
    float *rgb = malloc(prt_transfer_vertex_count(t) * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_UNSHADOWED, &L, rgb), PRT_OK);
    for (size_t v = 0; v < prt_transfer_vertex_count(t) * 3; ++v) assert_true(fabsf(rgb[v] - 0.5f) < 2e-3f);
    free(rgb);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* White furnace on a convex object: shadowed = unshadowed exactly (no ray is blocked), the
 * inter-reflected set adds nothing, and exit radiance under uniform unit light is the albedo. */
static void test_convex_white_furnace(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0.3f, -0.2f, 0.1f}, 0.8f, 24, 48);
    const float albedo = 0.8f;
    prt_scene *s = tm_scene(ctx, &m, albedo);
    prt_transfer *t = bake(ctx, s, 4, 2048, 0);
    size_t nv = prt_transfer_vertex_count(t);
    const float *un = prt_transfer_coeffs(t, PRT_TRANSFER_UNSHADOWED), *sh = prt_transfer_coeffs(t, PRT_TRANSFER_SHADOWED);
    assert_memory_equal(un, sh, nv * 16 * sizeof(float));
    prt_sh_light L = uniform_light(4);
    float *rgb = malloc(nv * 3 * sizeof(float));
    const prt_transfer_kind kinds[3] = {PRT_TRANSFER_UNSHADOWED, PRT_TRANSFER_SHADOWED, PRT_TRANSFER_INTERREFLECTED};
    for (int k = 0; k < 3; ++k) {
        assert_int_equal(prt_relight_sh(ctx, t, kinds[k], &L, rgb), PRT_OK);
        double worst = 0;
        for (size_t i = 0; i < nv * 3; ++i) worst = fmax(worst, fabs(rgb[i] - albedo));
        if (worst > 3e-3 * albedo) fail_msg("%s: exit radiance off the albedo by %g", prt_transfer_kind_name(kinds[k]), worst);
    }
    free(rgb);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static float floor_centre_radiance(prt_context *ctx, float albedo, prt_transfer_kind kind)
{
    test_mesh m = {0};
    tm_pit(&m, 8);
    prt_scene *s = tm_scene(ctx, &m, albedo);
    prt_transfer *t = bake(ctx, s, 4, 1024, 0);
    size_t nv = prt_transfer_vertex_count(t), v = nearest_vertex(prt_transfer_positions(t), nv, (float[3]){0, 0, 0});
    prt_sh_light L = uniform_light(4);
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh(ctx, t, kind, &L, rgb), PRT_OK);
    float r = rgb[v * 3];
    free(rgb);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    return r;
}

static void test_pit_and_interreflection(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    float un = floor_centre_radiance(ctx, 0.5f, PRT_TRANSFER_UNSHADOWED);
    float sh = floor_centre_radiance(ctx, 0.5f, PRT_TRANSFER_SHADOWED);
    /* The floor centre of a unit cube pit sees the sky only through the 1x1 opening at height 1:
     * the view factor to it is four corner rectangles of 0.5 x 0.5, each
     * (1/pi) A/sqrt(1+A^2) atan(A/sqrt(1+A^2)) with A = 0.5, i.e. 0.2394 in all. Under uniform
     * light only T_00 matters, so the SH order truncates nothing here. */
    double a = 0.5, s2 = sqrt(1 + a * a);
    double view_factor = 4.0 * (a / s2 * atan(a / s2)) / M_PI;
    assert_true(un > 0.49f && un < 0.51f);
    if (fabs(sh - 0.5 * view_factor) > 0.01) fail_msg("pit floor shadowed %g, expected %g", sh, 0.5 * view_factor);
    assert_true(sh < 0.6f * un);
    float ir_lo = floor_centre_radiance(ctx, 0.3f, PRT_TRANSFER_INTERREFLECTED);
    float sh_lo = floor_centre_radiance(ctx, 0.3f, PRT_TRANSFER_SHADOWED);
    float ir_hi = floor_centre_radiance(ctx, 0.8f, PRT_TRANSFER_INTERREFLECTED);
    float sh_hi = floor_centre_radiance(ctx, 0.8f, PRT_TRANSFER_SHADOWED);
    assert_true(ir_lo > sh_lo);
    assert_true(ir_hi > sh_hi);
    /* The inter-reflected gain over shadowed grows with albedo (more bounces survive). */
    assert_true(ir_hi / sh_hi > ir_lo / sh_lo + 0.05f);
    prt_context_release(ctx);
}

/* White furnace inside a concave shape: with albedo 1 and unit radiance from everywhere, every
 * point of the pit reflects exactly 1 once enough bounces are gathered, including the vertices
 * on the concave edges where floor and walls meet (whose rays must not start inside the other
 * surface's plane). */
static void test_concave_white_furnace(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_pit(&m, 8);
    prt_scene *s = tm_scene(ctx, &m, 1.0f);
    prt_bake_desc d = {0};
    d.order = 2;
    d.samples = 2048;
    d.bounces = 64;
    d.kinds = PRT_TRANSFER_INTERREFLECTED;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    size_t nv = prt_transfer_vertex_count(t);
    prt_sh_light L = uniform_light(2);
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_INTERREFLECTED, &L, rgb), PRT_OK);
    double worst = 0;
    for (size_t i = 0; i < nv * 3; ++i) worst = fmax(worst, fabs(rgb[i] - 1.0));
    if (worst > 0.01) fail_msg("furnace in a pit: worst vertex off by %g", worst);
    free(rgb);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Colour bleeding: a white floor next to a red wall receives more red than green. */
static void test_colour_bleeding(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 8);   /* floor */
    size_t floor_nv = m.nv;
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){0, 0, -2}, (float[3]){0, 2, 0}, 8);   /* wall x = -1 facing +x */
    float *albedo = malloc(m.nv * 3 * sizeof(float));
    for (size_t v = 0; v < m.nv; ++v) {
        bool wall = v >= floor_nv;
        albedo[v * 3] = 0.8f;
        albedo[v * 3 + 1] = wall ? 0.1f : 0.8f;
        albedo[v * 3 + 2] = wall ? 0.1f : 0.8f;
    }
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, m.pos, m.nrm, albedo, m.nv, m.idx, m.nt, NULL, &s), PRT_OK);
    prt_transfer *t = bake(ctx, s, 3, 1024, PRT_TRANSFER_INTERREFLECTED);
    assert_int_equal(prt_transfer_channels(t, PRT_TRANSFER_INTERREFLECTED), 3);
    size_t nv = prt_transfer_vertex_count(t), v = nearest_vertex(prt_transfer_positions(t), nv, (float[3]){-0.75f, 0, 0});
    prt_sh_light L = uniform_light(3);
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_INTERREFLECTED, &L, rgb), PRT_OK);
    assert_true(rgb[v * 3] > rgb[v * 3 + 1] * 1.05f);
    assert_true(fabsf(rgb[v * 3 + 1] - rgb[v * 3 + 2]) < 1e-5f);
    free(rgb);
    free(albedo);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Same seed, different thread counts: bit-identical transfer. Different seed: different. */
static void test_deterministic_across_threads(void **state)
{
    (void)state;
    test_mesh m = {0};
    tm_pit(&m, 8);
    prt_transfer *t[3];
    for (int i = 0; i < 3; ++i) {
        prt_context *ctx = test_context(i == 0 ? 1 : 2);
        prt_scene *s = tm_scene(ctx, &m, 0.6f);
        prt_bake_desc d = {0};
        d.order = 4;
        d.samples = 256;
        d.seed = i == 2 ? 7 : 3;
        assert_int_equal(prt_bake_sh(ctx, s, &d, &t[i]), PRT_OK);
        prt_scene_release(s);
        prt_context_release(ctx);
    }
    size_t nv = prt_transfer_vertex_count(t[0]);
    assert_memory_equal(prt_transfer_coeffs(t[0], PRT_TRANSFER_INTERREFLECTED), prt_transfer_coeffs(t[1], PRT_TRANSFER_INTERREFLECTED),
                        nv * 3 * 16 * sizeof(float));
    assert_memory_equal(prt_transfer_coeffs(t[0], PRT_TRANSFER_SHADOWED), prt_transfer_coeffs(t[1], PRT_TRANSFER_SHADOWED), nv * 16 * sizeof(float));
    assert_memory_not_equal(prt_transfer_coeffs(t[0], PRT_TRANSFER_SHADOWED), prt_transfer_coeffs(t[2], PRT_TRANSFER_SHADOWED), nv * 16 * sizeof(float));
    for (int i = 0; i < 3; ++i) prt_transfer_release(t[i]);
    tm_free(&m);
}

/* Relighting with a rotated light equals the light's rotation applied to the band-limited
 * lighting: for the unoccluded plane, rotating a light 180 degrees about x turns "from above"
 * into "from below", which the plane cannot see. */
static void test_relight_rotation(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 2);
    prt_scene *s = tm_scene(ctx, &m, 1.0f);
    prt_transfer *t = bake(ctx, s, 3, 1024, PRT_TRANSFER_UNSHADOWED);
    /* Radiance L(d) = max(d.y, 0) projected exactly: coefficients of the clamped cosine about +y. */
    prt_sh_light L;
    memset(&L, 0, sizeof L);
    L.order = 3;
    double zh[3], y[9], up[3] = {0, 1, 0};
    prt_sh_clamped_cosine_zh(3, zh);
    prt_sh_eval(3, up, y);
    for (int l = 0; l < 3; ++l)
        for (int mm = -l; mm <= l; ++mm)
            for (int c = 0; c < 3; ++c) L.coeffs[c][l * (l + 1) + mm] = (float)(sqrt(4 * M_PI / (2 * l + 1)) * zh[l] * y[l * (l + 1) + mm]);
    float rgb[3 * 64];
    assert_true(prt_transfer_vertex_count(t) <= 64);
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_UNSHADOWED, &L, rgb), PRT_OK);
    float before = rgb[0];
    double flip[9];
    prt_rotation_from_euler_deg(0, 180, 0, flip);
    assert_int_equal(prt_sh_light_rotate(&L, flip), PRT_OK);
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_UNSHADOWED, &L, rgb), PRT_OK);
    /* From above, order-3 cosine lobe: (1/pi) sum A_l^2 ... > 0.6; from below the plane
     * receives only the ringing of the truncation, a few percent. */
    assert_true(before > 0.6f);
    assert_true(fabsf(rgb[0]) < 0.1f * before);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static int cancel_after_first(void *user, const char *stage, uint64_t done, uint64_t total)
{
    (void)stage; (void)done; (void)total;
    int *calls = user;
    return ++*calls > 1;
}

static void test_cancel(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_pit(&m, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    int calls = 0;
    prt_bake_desc d = {0};
    d.samples = 256;
    d.progress = cancel_after_first;
    d.progress_user = &calls;
    prt_transfer *t = (prt_transfer *)&calls;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_CANCELLED);
    assert_null(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static void test_bad_bake_args(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    test_mesh m = {0};
    tm_pit(&m, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_transfer *t = NULL;
    prt_bake_desc d = {0};
    d.order = 11;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "order"));
    d.order = 3;
    d.samples = 3;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    d.samples = 0;
    d.kinds = 32;   /* no such kind */
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_null(t);
    d.kinds = PRT_TRANSFER_SHADOWED;   /* a BRDF to bake in, but no glossy kind to bake it into */
    d.glossy_exit = 1;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "glossy kind"));
    d.glossy_exit = 0;
    prt_brdf bad_brdf = {0};
    bad_brdf.model = PRT_BRDF_PHONG;
    bad_brdf.exponent = -3;
    d.glossy_brdf = &bad_brdf;
    d.kinds = PRT_TRANSFER_GLOSSY_SHADOWED;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_null(t);
    d.glossy_brdf = NULL;
    d.kinds = 0;
    prt_bake_desc def = prt_bake_desc_defaults();
    assert_int_equal(def.order, 5);
    assert_int_equal(def.samples, 1024);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Every vertex sees the direction set turned its own way: on a plane, where one shared set would
 * give every vertex the same quadrature error (streaks and blotches along the mesh), neighbours'
 * errors differ and are not correlated; the same seed still gives the same bake. */
static void test_decorrelated_noise(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 20);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_transfer *t = bake(ctx, s, 2, 64, PRT_TRANSFER_UNSHADOWED), *u = bake(ctx, s, 2, 64, PRT_TRANSFER_UNSHADOWED);
    const size_t nv = prt_transfer_vertex_count(t);
    const float *T = prt_transfer_coeffs(t, PRT_TRANSFER_UNSHADOWED);
    assert_memory_equal(T, prt_transfer_coeffs(u, PRT_TRANSFER_UNSHADOWED), nv * 4 * sizeof(float));
    /* Errors of T_1,0 (the normal's band-1 term; 0 for T_1,-1 and T_1,1 exactly) against the closed
     * form, along each row of the grid: the mean product of neighbours against the mean square. */
    double zh[2], y[4], up[3] = {0, 1, 0};
    prt_sh_clamped_cosine_zh(2, zh);
    prt_sh_eval(2, up, y);
    const double expect = sqrt(4 * M_PI / 3) * zh[1] * y[2] / M_PI;
    double sq = 0, prod = 0, lo = INFINITY, hi = -INFINITY;
    size_t pairs = 0;
    for (int r = 0; r <= 20; ++r)
        for (int c = 0; c < 20; ++c) {
            const size_t a = (size_t)r * 21 + c, b = a + 1;
            const double ea = T[a * 4 + 2] - expect, eb = T[b * 4 + 2] - expect;
            sq += ea * ea;
            prod += ea * eb;
            lo = fmin(lo, ea);
            hi = fmax(hi, ea);
            pairs++;
        }
    const double corr = prod / sq;
    print_message("64 directions on a plane: T_1,0 error %.4f .. %.4f, neighbour correlation %.2f\n", lo, hi, corr);
    assert_true(hi - lo > 1e-3);       /* one shared set: every vertex the same error */
    assert_true(fabs(corr) < 0.3);     /* shared: 1 */
    prt_transfer_release(t);
    prt_transfer_release(u);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unoccluded_plane),
        cmocka_unit_test(test_decorrelated_noise),
        cmocka_unit_test(test_convex_white_furnace),
        cmocka_unit_test(test_pit_and_interreflection),
        cmocka_unit_test(test_concave_white_furnace),
        cmocka_unit_test(test_colour_bleeding),
        cmocka_unit_test(test_deterministic_across_threads),
        cmocka_unit_test(test_relight_rotation),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_bad_bake_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
