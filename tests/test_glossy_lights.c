/* Glossy materials under local lights, for every method that draws local lights' direct light
 * per pixel (spectral, light cloud, offset maps): a Phong floor and a Blinn-Phong sphere seen from
 * a fixed eye against the path tracer - per vertex under point, spot, directional and small
 * sphere lights (prt_relit_shade's view-dependent direct light against the reference's), and in
 * the picture under a point light (the floor's highlight where the path tracer draws it, as
 * bright). */
#include "common.h"

#define W 160
#define H 120

static const float EYE[3] = {-1.5f, 0.8f, -1.5f};
static const float TARGET[3] = {0.0f, 0.2f, 0.0f};

/* A 2 x 2 floor (Phong 40) with a sphere (Blinn-Phong 80) on it; nothing else. */
static prt_scene *glossy_scene(prt_context *ctx)
{
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 48);
    const size_t nfloor = m.nv;
    tm_sphere(&m, (float[3]){0, 0.3f, 0}, 0.3f, 24, 48);
    prt_scene *s = tm_scene(ctx, &m, 0.4f);
    prt_brdf floor_brdf, ball;
    assert_int_equal(prt_brdf_parse("phong:40:0.5:0.4", &floor_brdf), PRT_OK);
    assert_int_equal(prt_brdf_parse("blinn:80:0.5:0.3", &ball), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, 0, nfloor, &floor_brdf), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, nfloor, m.nv - nfloor, &ball), PRT_OK);
    tm_free(&m);
    return s;
}

static prt_transfer *bake(prt_context *ctx, const prt_scene *s, const char *method)
{
    const prt_method *m = prt_method_find(method);
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(m, &o), PRT_OK);
    if (!strcmp(method, "spectral")) {
        assert_int_equal(prt_options_set(o, "basis", "64"), PRT_OK);
        assert_int_equal(prt_options_set(o, "samples", "64"), PRT_OK);
    } else if (!strcmp(method, "lightcloud")) {
        assert_int_equal(prt_options_set(o, "cloud-grid", "2,2,2"), PRT_OK);
        assert_int_equal(prt_options_set(o, "samples", "64"), PRT_OK);
        assert_int_equal(prt_options_set(o, "basis", "64"), PRT_OK);
    } else {
        assert_int_equal(prt_options_set(o, "texels", "64"), PRT_OK);
        assert_int_equal(prt_options_set(o, "offsets", "20"), PRT_OK);
    }
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, s, m, o, NULL, &t), PRT_OK);
    prt_options_release(o);
    return t;
}

/* Per vertex, one light: the direct light seen from the eye (prt_relit_shade) against the path
 * tracer's, over the vertices facing the eye. */
static void check_direct(prt_context *ctx, const prt_transfer *t, const prt_scene *ts, const char *method, const char *spec, double tolerance)
{
    const size_t nv = prt_transfer_vertex_count(t);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    prt_light light;
    assert_int_equal(prt_light_parse(spec, &light), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &light, NULL), PRT_OK);
    prt_relit lit;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .component = PRT_COMPONENT_DIRECT}, &lit), PRT_OK);
    assert_int_equal(lit.pixel_light_count, 1);
    assert_non_null(lit.pixel_material);
    assert_true(prt_relit_view_dependent(&lit));
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relit_shade(ctx, t, &lit, NULL, rgb), PRT_ERR_INVALID_ARG);   /* view-dependent: needs the eye */
    assert_int_equal(prt_relit_shade(ctx, t, &lit, EYE, rgb), PRT_OK);
    const float *P = prt_scene_positions(ts), *N = prt_scene_normals(ts);
    prt_reference_vertices ref;
    assert_int_equal(prt_reference_trace_vertices(ctx, ts, NULL, &(prt_reference_desc){.samples = 64, .lighting = l, .eye = EYE}, &ref), PRT_OK);
    assert_int_equal(ref.vertex_count, nv);
    double num = 0, den = 0, noise = 0, peak = 0, peak_ref = 0;
    for (size_t v = 0; v < nv; ++v) {
        /* The path tracer sees nothing of a vertex turned away from the eye. */
        const float to_eye[3] = {EYE[0] - P[v * 3], EYE[1] - P[v * 3 + 1], EYE[2] - P[v * 3 + 2]};
        if (to_eye[0] * N[v * 3] + to_eye[1] * N[v * 3 + 1] + to_eye[2] * N[v * 3 + 2] <= 0) continue;
        for (int c = 0; c < 3; ++c) {
            const double a = rgb[v * 3 + c], b = ref.direct[v * 3 + c];
            num += (a - b) * (a - b);
            den += b * b;
            noise += (double)ref.std_error[v * 3 + c] * ref.std_error[v * 3 + c];
            if (P[v * 3 + 1] < 1e-4f) {   /* the floor */
                peak = fmax(peak, a);
                peak_ref = fmax(peak_ref, b);
            }
        }
    }
    const double rel = sqrt(num / den), rel_noise = sqrt(noise / den);
    print_message("%s, %s: glossy direct light per vertex %.4f relative L2 from the path tracer (its noise %.4f); floor's brightest %.3f "
                  "(path tracer %.3f)\n", method, spec, rel, rel_noise, peak, peak_ref);
    assert_true(rel < tolerance + 2 * rel_noise);
    assert_true(fabs(peak - peak_ref) < tolerance * peak_ref);
    prt_reference_vertices_free(&ref);
    free(rgb);
    prt_relit_free(&lit);
    prt_lighting_release(l);
}

static void check_method(const char *method)
{
    prt_context *ctx = test_context(0);
    prt_scene *s = glossy_scene(ctx);
    prt_transfer *t = bake(ctx, s, method);
    /* The transfer's own mesh: a bake may add vertices (refinement) or split them (atlas seams). */
    prt_scene *ts = NULL;
    assert_int_equal(prt_transfer_scene(ctx, t, &ts), PRT_OK);
    /* Point, spot and directional light: the same formulas on both sides, up to the path
     * tracer's shadow-ray origins. A small sphere light: the lobe taken at its centre, where the
     * path tracer integrates over the sphere. */
    check_direct(ctx, t, ts, method, "point:0.3,1,0.2:3", 0.02);
    check_direct(ctx, t, ts, method, "sphere:0.3,1,0.2:0.05:120", 0.05);
    if (strcmp(method, "lightcloud") != 0) {   /* light clouds of the default emission order take point and sphere lights */
        check_direct(ctx, t, ts, method, "spot:0.3,1,0.2:-0.3,-1,-0.2:60,40:3", 0.02);
        check_direct(ctx, t, ts, method, "directional:0.3,1,0.5:2", 0.02);
    }
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    prt_light bulb;
    assert_int_equal(prt_light_parse("point:0.3,1,0.2:3", &bulb), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &bulb, NULL), PRT_OK);

    /* Drawn: the floor's highlight where the path tracer draws it, and as bright. The whole
     * light (direct and indirect), so the picture is what prt render shows. */
    prt_relit full;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1}, &full), PRT_OK);
    prt_renderer *ren = NULL;
    assert_int_equal(prt_renderer_create(ctx, &(prt_renderer_desc){W, H, 0}, &ren), PRT_OK);
    prt_render_mesh rm;
    prt_relit_render_mesh(t, &full, &rm);
    prt_camera cam = {{EYE[0], EYE[1], EYE[2]}, {TARGET[0], TARGET[1], TARGET[2]}, {0, 1, 0}, 50};
    prt_image img, pt;
    assert_int_equal(prt_render(ren, &rm, &cam, NULL, &img), PRT_OK);
    assert_int_equal(prt_reference_trace_image(ctx, s, NULL, &(prt_reference_desc){.samples = 32, .lighting = l}, &cam, W, H, NULL, &pt, NULL),
                     PRT_OK);
    /* The brightest 5 x 5 window of each (luminance), in the lower half: the floor. */
    int bx[2] = {0}, by[2] = {0};
    double best[2] = {0};
    const prt_image *im[2] = {&img, &pt};
    for (int k = 0; k < 2; ++k)
        for (int y = H / 2; y < H - 2; ++y)
            for (int x = 2; x < W - 2; ++x) {
                double sum = 0;
                for (int dy = -2; dy <= 2; ++dy)
                    for (int dx = -2; dx <= 2; ++dx) {
                        const float *p = im[k]->rgb + ((size_t)(y + dy) * W + (x + dx)) * 3;
                        sum += p[0] + p[1] + p[2];
                    }
                if (sum > best[k]) { best[k] = sum; bx[k] = x; by[k] = y; }
            }
    print_message("%s: the floor's highlight drawn at (%d, %d), %.2f; the path tracer's at (%d, %d), %.2f\n", method, bx[0], by[0], best[0] / 75,
                  bx[1], by[1], best[1] / 75);
    assert_true(abs(bx[0] - bx[1]) <= 4 && abs(by[0] - by[1]) <= 4);
    assert_true(fabs(best[0] - best[1]) < 0.25 * best[1]);
    prt_image_free(&img);
    prt_image_free(&pt);
    prt_renderer_release(ren);
    prt_scene_release(ts);
    prt_relit_free(&full);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* The environment's direct light on glossy surfaces goes through the glossy path too (spectral:
 * the shadowed transfer from the environment to the incident SH at glossy vertices): under a
 * sky without a sun (smooth enough for SH order 4), each glossy vertex's direct light seen from
 * the eye against the path tracer's. */
static void test_spectral_environment(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_scene *s = glossy_scene(ctx);
    prt_transfer *t = bake(ctx, s, "spectral");
    const size_t nv = prt_transfer_vertex_count(t);
    prt_envmap *sky = NULL;
    assert_int_equal(prt_sky_create(&(prt_sky_desc){.sun_radiance = {1e-6f, 1e-6f, 1e-6f}, .width = 128}, &sky), PRT_OK);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, sky, NULL, 1), PRT_OK);
    prt_relit lit;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .component = PRT_COMPONENT_DIRECT}, &lit), PRT_OK);
    assert_non_null(lit.exit_sh);
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relit_shade(ctx, t, &lit, EYE, rgb), PRT_OK);
    prt_reference_vertices ref;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &(prt_reference_desc){.samples = 256, .lighting = l, .eye = EYE}, &ref), PRT_OK);
    const float *P = prt_scene_positions(s), *N = prt_scene_normals(s);
    double num = 0, den = 0, diffuse = 0;
    for (size_t v = 0; v < nv; ++v) {
        const float to_eye[3] = {EYE[0] - P[v * 3], EYE[1] - P[v * 3 + 1], EYE[2] - P[v * 3 + 2]};
        if (to_eye[0] * N[v * 3] + to_eye[1] * N[v * 3 + 1] + to_eye[2] * N[v * 3 + 2] <= 0) continue;
        for (int c = 0; c < 3; ++c) {
            const double a = rgb[v * 3 + c], b = ref.direct[v * 3 + c], d = lit.radiance[v * 3 + c];
            num += (a - b) * (a - b);
            den += b * b;
            diffuse += (d - b) * (d - b);
        }
    }
    print_message("spectral, a sky on glossy surfaces: direct light per vertex %.4f relative L2 from the path tracer (%.4f reflecting "
                  "diffusely only)\n", sqrt(num / den), sqrt(diffuse / den));
    assert_true(sqrt(num / den) < 0.15);   /* SH order 4 blurs the Phong 40 and Blinn 80 lobes */
    assert_true(sqrt(num / den) < 0.5 * sqrt(diffuse / den));
    prt_reference_vertices_free(&ref);
    free(rgb);
    prt_relit_free(&lit);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_spectral(void **state) { (void)state; check_method("spectral"); }
static void test_lightcloud(void **state) { (void)state; check_method("lightcloud"); }
static void test_offset(void **state) { (void)state; check_method("offset"); }

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spectral),
        cmocka_unit_test(test_spectral_environment),
        cmocka_unit_test(test_lightcloud),
        cmocka_unit_test(test_offset),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
