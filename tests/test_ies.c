/* IES (LM-63) photometric profiles and ies lights: values and symmetries read back, every kind
 * of damaged file refused with a one-line reason (never a crash), the command-line form, and a
 * uniform profile shading exactly like a point light of the same intensity - in closed form, at
 * vertices through the reference path tracer's light sampling, and in the path tracer itself. */
#include "common.h"

/* Quadrant symmetric (horizontal 0..90), 2002 form, CRLF line ends. */
static const char downlight[] =
    "IESNA:LM-63-2002\r\n[TEST] quadrant\r\nTILT=NONE\r\n"
    "1 -1 1.0 7 3 1 2 0.1 0.1 0.0\r\n1.0 1.0 20\r\n"
    "0 15 30 45 60 75 90\r\n0 45 90\r\n"
    "1000 950 800 500 200 50 0\r\n1000 940 780 480 180 40 0\r\n1000 930 760 450 160 30 0\r\n";
/* Axially symmetric, 100 cd everywhere (0..180), 1995 form, numbers split over lines by commas. */
static const char uniform[] = "IESNA:LM-63-1995\n[TEST] uniform\nTILT=NONE\n1 1000 1\n5 1 1 1 0 0 0\n1 1 10\n0 45 90\n135 180\n0\n100,100,100\n100,100\n";
/* TILT=INCLUDE, a full circle (0..360), multiplier 2 and ballast 0.9, no IESNA line (1986). */
static const char full[] =
    "[TEST] full\nTILT=INCLUDE\n1\n3\n0 45 90\n1.0 0.9 0.8\n1 500 2 3 5 1 1 0.2 0.2 0.05\n0.9 1 15\n0 90 180\n0 90 180 270 360\n"
    "10 5 0\n20 8 1\n30 10 2\n20 8 1\n10 5 0\n";
/* Bilateral (0..180) downlight that only lights one side more: for the frame test. */
static const char half[] = "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 2 3 1 2 0 0 0\n1 1 0\n0 90\n0 90 180\n10 10\n20 20\n40 40\n";

static prt_ies *load(const char *text)
{
    prt_ies *p = NULL;
    if (prt_ies_load_memory(text, strlen(text), &p) != PRT_OK) fail_msg("%s", prt_last_error());
    return p;
}

static void near(double got, double want)
{
    if (fabs(got - want) > 1e-4 * (1 + fabs(want))) fail_msg("got %.9g, want %.9g", got, want);
}

static void test_values_and_symmetry(void **state)
{
    (void)state;
    prt_ies *p = load(downlight);
    near(prt_ies_candela(p, 0, 0), 1000);
    near(prt_ies_candela(p, 15, 45), 940);
    near(prt_ies_candela(p, 22.5f, 0), 875);                /* bilinear in the vertical angle */
    near(prt_ies_candela(p, 15, 67.5f), 935);               /* and in the horizontal */
    near(prt_ies_candela(p, 15, 135), 940);                 /* mirrored about C90 */
    near(prt_ies_candela(p, 15, 315), 940);                 /* and about C0 */
    near(prt_ies_candela(p, 15, -45), 940);
    near(prt_ies_candela(p, 15, 270), 930);
    near(prt_ies_candela(p, 120, 0), 0);                    /* above the range it covers */
    near(prt_ies_max_candela(p), 1000);
    prt_ies_release(p);
    p = load(uniform);
    for (int v = 0; v <= 180; v += 10)
        for (int h = 0; h < 360; h += 25) near(prt_ies_candela(p, (float)v, (float)h), 100);
    prt_ies_release(p);
    p = load(full);   /* x multiplier 2 x ballast 0.9 */
    near(prt_ies_candela(p, 0, 0), 18);
    near(prt_ies_candela(p, 90, 90), 14.4);
    near(prt_ies_candela(p, 0, 315), 27);                   /* between C270 and C360 */
    near(prt_ies_candela(p, 45, 180), 36);                 /* (30 + 10) / 2 x 1.8 */
    prt_ies_release(p);
    p = load(half);
    near(prt_ies_candela(p, 45, 90), 20);
    near(prt_ies_candela(p, 45, 270), 20);                  /* mirrored about the C0-C180 plane */
    near(prt_ies_candela(p, 45, 225), 30);
    prt_ies_release(p);
}

static void expect_bad(const char *text, const char *words)
{
    prt_ies *p = (prt_ies *)1;
    prt_status st = prt_ies_load_memory(text, strlen(text), &p);
    if (st != PRT_ERR_FORMAT) fail_msg("accepted (%d): %s", (int)st, text);
    assert_null(p);
    const char *msg = prt_last_error();
    if (!strstr(msg, words)) fail_msg("message '%s' does not say '%s'", msg, words);
    assert_null(strchr(msg, '\n'));
}

static void test_bad_files(void **state)
{
    (void)state;
    const char *head = "IESNA:LM-63-2002\nTILT=NONE\n";
    char buf[512];
#define BAD(body, words) do { snprintf(buf, sizeof buf, "%s%s", head, body); expect_bad(buf, words); } while (0)
    expect_bad("", "no TILT= line");
    expect_bad("IESNA:LM-63-2002\n[TEST] x\n", "no TILT= line");
    expect_bad("IESNA:LM-63-2002\nTILT=lamp.tlt\n1 -1 1 2 1 1 2 0 0 0\n1 1 1\n0 90\n0\n1 1\n", "line 2: TILT must be NONE or INCLUDE");
    BAD("1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 45 90\n0\n100 90\n", "file ends before a candela value");
    BAD("1 -1 1 3 4 1 2 0 0 0\n1 1 10\n0 45 90\n0\n100 90\n", "longer than the file");
    BAD("1 -1 1 10000 10000 1 2 0 0 0\n1 1 10\n0 90\n0\n1 2\n", "too large");
    BAD("1 -1 1 20000 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1 2\n", "vertical angles must be a whole number");
    BAD("1 -1 1 -3 1 1 2 0 0 0\n1 1 10\n", "vertical angles must be a whole number");
    BAD("1 -1 1 2.5 1 1 2 0 0 0\n1 1 10\n", "whole number");
    BAD("1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\nnan 1\n", "candela value is not");
    BAD("1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\ninf 1\n", "not finite");
    BAD("1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n-5 1\n", "negative");
    BAD("1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 60 45\n0\n1 2 3\n", "line 5: a vertical angle must increase strictly");
    BAD("1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 45 45\n0\n1 2 3\n", "increase strictly");
    BAD("1 -1 1 2 2 1 2 0 0 0\n1 1 10\n0 90\n0 400\n1 2 3 4\n", "out of range");
    BAD("1 -1 1 2 2 1 2 0 0 0\n1 1 10\n0 90\n0 120\n1 2 3 4\n", "must end at 0, 90, 180 or 360");
    BAD("1 -1 1 2 2 1 2 0 0 0\n1 1 10\n0 90\n10 90\n1 2 3 4\n", "must start at 0");
    BAD("1 -1 1 2 1 1 2 0 0 0\n1 1 10\n10 90\n0\n1 2\n", "must start at 0 or 90");
    BAD("1 -1 1 2 1 2 2 0 0 0\n1 1 10\n0 90\n0\n1 2\n", "type B is not read");
    BAD("1 -1 0 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1 2\n", "multiplier must be > 0");
    BAD("1 -1 1 2 1 1 2 0 0 0\n0 1 10\n0 90\n0\n1 2\n", "ballast factors");
    BAD("1 -1 1e38 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1e30 2\n", "above 1e30");
    BAD("1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 ninety\n0\n1 2\n", "not a number");
    BAD("1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1 0000000000000000000000000000000000000000000000000000000000000000001\n", "too long");
#undef BAD
    /* Every prefix of a valid file: refused or read, never a crash; those missing numbers refused. */
    const size_t n = strlen(downlight);
    char *cut = malloc(n + 1);
    int refused = 0;
    for (size_t k = 0; k < n; ++k) {
        memcpy(cut, downlight, k);
        cut[k] = 0;
        prt_ies *p = NULL;
        if (prt_ies_load_memory(cut, k, &p) == PRT_OK) prt_ies_release(p);
        else refused++;
    }
    assert_true(refused > (int)n - 12);   /* at most the last value's digits and line end can go */
    free(cut);
}

static void test_light_spec(void **state)
{
    (void)state;
    char path[512], spec[700], back[900];
    write_text("downlight.ies", downlight, path, sizeof path);
    prt_light l, m;
    snprintf(spec, sizeof spec, "ies:%s:0,3,0", path);
    assert_int_equal(prt_light_parse(spec, &l), PRT_OK);
    assert_int_equal(l.type, PRT_LIGHT_IES);
    assert_true(l.direction[1] == -1 && l.scale[0] == 1);
    assert_string_equal(prt_ies_path(l.profile), path);
    prt_light_clear(&l);
    snprintf(spec, sizeof spec, "ies:%s:1,2,3:0,0,-2,1,0,0:0.5,0.25,1", path);
    assert_int_equal(prt_light_parse(spec, &l), PRT_OK);
    assert_true(l.direction[2] == -1 && l.up[0] == 1 && l.scale[1] == 0.25f);
    prt_light_format(&l, back, sizeof back);
    assert_int_equal(prt_light_parse(back, &m), PRT_OK);
    assert_memory_equal(l.position, m.position, sizeof l.position);
    assert_memory_equal(l.direction, m.direction, sizeof l.direction);
    assert_memory_equal(l.scale, m.scale, sizeof l.scale);
    prt_light_clear(&m);
    /* A lighting keeps its own reference: the parsed light can go first. */
    prt_lighting *lg = NULL;
    assert_int_equal(prt_lighting_create(&lg), PRT_OK);
    assert_int_equal(prt_lighting_add(lg, &l, NULL), PRT_OK);
    prt_light_clear(&l);
    prt_lighting *copy = NULL;
    assert_int_equal(prt_lighting_copy(lg, &copy), PRT_OK);
    prt_lighting_release(lg);
    assert_true(prt_lighting_content(copy) & PRT_LIGHTS_IES);
    near(prt_ies_candela(prt_lighting_light(copy, 0)->profile, 0, 0), 1000);
    prt_lighting_release(copy);
    /* Methods that cannot take it refuse it by name, pointing at the one that can. */
    assert_int_equal(prt_method_check_lighting(prt_method_find("spectral"), PRT_LIGHTS_IES), PRT_ERR_INVALID_ARG);
    print_message("spectral and an ies light: %s\n", prt_last_error());
    assert_non_null(strstr(prt_last_error(), "IES"));
    assert_non_null(strstr(prt_last_error(), "lightcloud"));
    assert_int_equal(prt_method_check_lighting(prt_method_find("lightcloud"), PRT_LIGHTS_IES | PRT_LIGHTS_SPOT), PRT_OK);
    /* One-line errors. */
    static const char *bad[] = {"ies:", "ies:x.ies", "ies::0,1,0", "ies:/nonexistent/x.ies:0,1,0", "ies:%s:0,1", "ies:%s:0,1,0:0,0,0",
                                "ies:%s:0,1,0:0,-1,0:-1", "ies:%s:0,1,0:0,-1,0,1:1", "ies:%s:nan,1,0"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; ++i) {
        snprintf(spec, sizeof spec, bad[i], path);
        if (prt_light_parse(spec, &l) == PRT_OK) fail_msg("accepted '%s'", spec);
        assert_null(strchr(prt_last_error(), '\n'));
    }
    write_text("broken.ies", "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n", path, sizeof path);
    snprintf(spec, sizeof spec, "ies:%s:0,1,0", path);
    assert_int_not_equal(prt_light_parse(spec, &l), PRT_OK);
    print_message("a broken file: %s\n", prt_last_error());
    assert_non_null(strstr(prt_last_error(), "IES: line"));
}

/* The light's frame: nadir along direction, C0 towards up, C90 = nadir x up. */
static void test_frame(void **state)
{
    (void)state;
    prt_light l = {0};
    l.type = PRT_LIGHT_IES;
    l.profile = load(half);
    l.position[1] = 1;
    l.direction[1] = -1;
    l.up[0] = 1;
    l.scale[0] = l.scale[1] = l.scale[2] = 1;
    assert_int_equal(prt_light_validate(&l), PRT_OK);
    /* nadir (0,-1,0), C0 +x, C90 = n x u = (0,-1,0) x (1,0,0) = (0,0,1). */
    const float toward_c0[3] = {0.70710678f, -0.70710678f, 0}, toward_c90[3] = {0, -0.70710678f, 0.70710678f},
                toward_c180[3] = {-0.70710678f, -0.70710678f, 0};
    float I[3];
    prt_light_intensity_towards(&l, toward_c0, I);
    near(I[0], 10);
    prt_light_intensity_towards(&l, toward_c90, I);
    near(I[0], 20);
    prt_light_intensity_towards(&l, toward_c180, I);
    near(I[0], 40);
    prt_ies_release(l.profile);
}

/* A uniform profile of 100 cd with scale s is a point light of intensity 100 s. */
static void test_uniform_is_point(void **state)
{
    (void)state;
    char path[512], spec[700];
    write_text("uniform.ies", uniform, path, sizeof path);
    prt_light ies, point;
    snprintf(spec, sizeof spec, "ies:%s:0.2,0.6,0.1:0.3,-1,0.2:0.02,0.03,0.05", path);
    assert_int_equal(prt_light_parse(spec, &ies), PRT_OK);
    assert_int_equal(prt_light_parse("point:0.2,0.6,0.1:2,3,5", &point), PRT_OK);
    for (int i = 0; i < 50; ++i) {
        const float p[3] = {(float)(i % 7) * 0.3f - 1, (float)(i % 3) * 0.2f - 0.5f, (float)(i % 5) * 0.25f - 0.5f};
        const float n[3] = {0, 1, 0};
        float a[3], b[3];
        prt_light_irradiance(&ies, p, n, a);
        prt_light_irradiance(&point, p, n, b);
        for (int k = 0; k < 3; ++k)
            if (fabsf(a[k] - b[k]) > 1e-6f * b[k]) fail_msg("at %d: %g vs %g", i, a[k], b[k]);
    }
    /* The path tracer: the pit lit by each, same seed, same samples. */
    prt_context *ctx = test_context(1);
    test_mesh m = {0};
    tm_pit(&m, 6);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    prt_lighting *la = NULL, *lb = NULL;
    assert_int_equal(prt_lighting_create(&la), PRT_OK);
    assert_int_equal(prt_lighting_create(&lb), PRT_OK);
    assert_int_equal(prt_lighting_add(la, &ies, NULL), PRT_OK);
    assert_int_equal(prt_lighting_add(lb, &point, NULL), PRT_OK);
    prt_reference_desc d = {0};
    d.samples = 32;
    d.lighting = la;
    prt_reference_vertices ra, rb;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &ra), PRT_OK);
    d.lighting = lb;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &rb), PRT_OK);
    double sum = 0, worst = 0;
    for (size_t i = 0; i < ra.vertex_count * 3; ++i) {
        sum += rb.radiance[i];
        worst = fmax(worst, fabs((double)ra.radiance[i] - rb.radiance[i]) / (1e-6 + fabs(rb.radiance[i])));
    }
    print_message("uniform ies vs point light, path traced: worst relative difference %.2e (mean radiance %.4g)\n", worst,
                  sum / (double)(ra.vertex_count * 3));
    assert_true(sum > 0);
    assert_true(worst < 1e-5);
    prt_reference_vertices_free(&ra);
    prt_reference_vertices_free(&rb);
    prt_lighting_release(la);
    prt_lighting_release(lb);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
    prt_light_clear(&ies);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_values_and_symmetry),
        cmocka_unit_test(test_bad_files),
        cmocka_unit_test(test_light_spec),
        cmocka_unit_test(test_frame),
        cmocka_unit_test(test_uniform_is_point),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
