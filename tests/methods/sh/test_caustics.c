/* Caustics in SH transfer (src/methods/sh/bake.c, follow_specular): light that mirrors and glass
 * send onto diffuse receivers.
 *  - A tilted mirror standing over a floor under a smooth sky of the transfer's own band limit: the SH
 *    bake's inter-reflected transfer must agree per vertex with the reference path tracer, which
 *    renders the same perfect mirror - and the floor in front of it must be brighter than the
 *    same floor beside a black diffuse panel (the caustic), which the bake without the material
 *    gives.
 *  - A glass ball over a floor under a sun overhead: the spot under the ball is brighter than
 *    its shadow around it, and brighter than under an opaque ball by more than half of what the
 *    open floor gets.
 *  - Bad material specs are refused with one-line errors. */
#include "common.h"

#include "brdf/specular.h"

static void grid(FILE *f, int *base, const double o[3], const double u[3], const double v[3], int n)
{
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            fprintf(f, "v %.6f %.6f %.6f\n", o[0] + u[0] * i / n + v[0] * j / n, o[1] + u[1] * i / n + v[1] * j / n, o[2] + u[2] * i / n + v[2] * j / n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = *base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, d, a, d, c);   /* front: u x v */
        }
    *base += (n + 1) * (n + 1);
}

/* floor.obj: 4 x 4 m at y = 0 facing up; mirror.obj: a 1.2 x 1 m panel at x = 1,
 * its lower edge at y = 0.3, leaning 15 degrees over the floor (facing -x and a little down); ball.obj: a sphere of radius 0.5 at (0, 0.8, 0), normals outwards. */
static void write_meshes(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/floor.obj", test_dir);
    FILE *f = fopen(path, "w");
    int base = 1;
    grid(f, &base, (double[3]){-2, 0, -2}, (double[3]){0, 0, 4}, (double[3]){4, 0, 0}, 24);
    fclose(f);
    snprintf(path, sizeof path, "%s/mirror.obj", test_dir);
    f = fopen(path, "w");
    base = 1;
    grid(f, &base, (double[3]){1, 0.3, -0.6}, (double[3]){0, 0, 1.2}, (double[3]){-0.2588190451, 0.9659258263, 0}, 4);
    fclose(f);
    snprintf(path, sizeof path, "%s/ball.obj", test_dir);
    f = fopen(path, "w");
    const int nu = 48, nv = 24;
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {
            const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu, d[3] = {sin(th) * cos(ph), cos(th), sin(th) * sin(ph)};
            fprintf(f, "v %.6f %.6f %.6f\nvn %.6f %.6f %.6f\n", 0.5 * d[0], 0.8 + 0.5 * d[1], 0.5 * d[2], d[0], d[1], d[2]);
        }
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const int a = j * (nu + 1) + i + 1, b = a + 1, c = a + nu + 1, d = c + 1;
            if (j > 0) fprintf(f, "f %d//%d %d//%d %d//%d\n", a, a, d, d, c, c);
            if (j < nv - 1) fprintf(f, "f %d//%d %d//%d %d//%d\n", a, a, b, b, d, d);
        }
    fclose(f);
}

/* A grey sky (1 + d.s)^2 + 0.1 brightest towards s = (-1, 1, 0) / sqrt 2: quadratic in d, so
 * SH of order 3 holds it exactly. */
static prt_envmap *quadratic_sky(int width)
{
    prt_image img = {width, width / 2, malloc((size_t)width * width / 2 * 3 * sizeof(float))};
    const double s[3] = {-0.70710678118654752, 0.70710678118654752, 0};
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < width; ++x) {
            const double th = M_PI * (y + 0.5) / img.height, ph = 2 * M_PI * ((x + 0.5) / width - 0.5);
            const double d[3] = {sin(th) * sin(ph), cos(th), -sin(th) * cos(ph)}, t = 1 + d[0] * s[0] + d[1] * s[1] + d[2] * s[2];
            for (int c = 0; c < 3; ++c) img.rgb[((size_t)y * width + x) * 3 + c] = (float)(t * t + 0.1);
        }
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    return env;
}

static prt_scene *load(prt_context *ctx, const char *name, const char *json)
{
    char path[600];
    write_text(name, json, path, sizeof path);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, &(prt_scene_desc){.winding = PRT_WINDING_KEEP}, &s), PRT_OK);
    return s;
}

/* Red-channel radiance per vertex of the scene's SH bake relit by light L. */
static float *bake_relit(prt_context *ctx, const prt_scene *s, int order, int samples, unsigned kind, const prt_sh_light *L)
{
    prt_bake_desc bd = {0};
    bd.order = order;
    bd.samples = samples;
    bd.bounces = 2;
    bd.kinds = PRT_TRANSFER_SHADOWED | (kind == PRT_TRANSFER_INTERREFLECTED ? PRT_TRANSFER_INTERREFLECTED : 0);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &bd, &t), PRT_OK);
    const size_t nv = prt_transfer_vertex_count(t);
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh(ctx, t, (prt_transfer_kind)kind, L, rgb), PRT_OK);
    prt_transfer_release(t);
    return rgb;
}

static void test_mirror(void **state)
{
    (void)state;
    write_meshes();
    prt_context *ctx = test_context(0);
    prt_scene *with = load(ctx, "mirror.json",
                           "{\"materials\": {\"mirror\": {\"albedo\": 0, \"specular\": {\"type\": \"mirror\", \"reflectance\": 0.9}}, \"floor\": {\"albedo\": 0.5}},"
                           " \"meshes\": [{\"file\": \"floor.obj\", \"material\": \"floor\"}, {\"file\": \"mirror.obj\", \"material\": \"mirror\"}]}");
    prt_scene *without = load(ctx, "panel.json",
                              "{\"materials\": {\"mirror\": {\"albedo\": 0}, \"floor\": {\"albedo\": 0.5}},"
                              " \"meshes\": [{\"file\": \"floor.obj\", \"material\": \"floor\"}, {\"file\": \"mirror.obj\", \"material\": \"mirror\"}]}");
    prt_specular sp;
    assert_int_equal(prt_scene_specular(with, "mirror", &sp), 1);
    assert_int_equal(sp.type, PRT_SPECULAR_MIRROR);
    assert_int_equal(prt_scene_specular(without, "mirror", &sp), 0);
    prt_envmap *env = quadratic_sky(256);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 3, &L), PRT_OK);
    float *sh = bake_relit(ctx, with, 3, 4096, PRT_TRANSFER_INTERREFLECTED, &L);
    float *plain = bake_relit(ctx, without, 3, 4096, PRT_TRANSFER_INTERREFLECTED, &L);
    prt_reference_desc d = {0};
    d.samples = 1024;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, with, env, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(with);
    const size_t nv = prt_scene_vertex_count(with);
    assert_int_equal(r.vertex_count, nv);
    double num = 0, den = 0, noise = 0, caustic = 0, worst = 0;
    int floor = 0, patch = 0, outside = 0;
    for (size_t v = 0; v < nv; ++v) {
        if (fabsf(pos[v * 3 + 1]) > 1e-6f) continue;   /* the floor's vertices */
        floor++;
        const double got = sh[v * 3], ref = r.radiance[v * 3], err = r.std_error[v * 3];
        num += (got - ref) * (got - ref);
        den += ref * ref;
        noise += err * err;
        if (fabs(got - ref) > 4 * err + 0.03 * ref) outside++;
        /* The reflected patch: where the mirror adds more than a tenth. */
        if (got > 1.1 * plain[v * 3]) {
            patch++;
            caustic = fmax(caustic, got / plain[v * 3]);
            worst = fmax(worst, fabs(got - ref) / ref);
            if (fabs(got - ref) > 4 * err + 0.03 * ref) fail_msg("vertex %zu in the reflected patch: SH %g, reference %g +- %g", v, got, ref, err);
            /* Without the material the reference's light is not there: no caustic. */
            assert_true(plain[v * 3] < ref - 4 * err);
        }
    }
    const double rel = sqrt(num / den), rel_noise = sqrt(noise / den);
    print_message("mirror on a floor, order 3, 4096 directions vs the path tracer (1024 paths): relative L2 %.4f (reference noise %.4f) over %d floor vertices, "
                  "%d outside 4 sigma + 3%%; %d vertices in the reflected patch, up to %.2fx the light beside a black panel, worst %.1f%% off the reference\n",
                  rel, rel_noise, floor, outside, patch, caustic, 100 * worst);
    assert_true(patch >= 20);
    assert_true(caustic > 1.3);
    assert_true(rel < 1.5 * rel_noise + 0.01);
    assert_true(outside <= floor / 50);
    free(sh);
    free(plain);
    prt_reference_vertices_free(&r);
    prt_envmap_release(env);
    prt_scene_release(with);
    prt_scene_release(without);
    prt_context_release(ctx);
}

/* Radiance 1 everywhere but for a 5-degree disc around the zenith, 2000 times brighter: a sun
 * overhead (order 5 SH blurs it; the ball's focusing still shows). */
static prt_envmap *sun_overhead(int width)
{
    prt_image img = {width, width / 2, malloc((size_t)width * width / 2 * 3 * sizeof(float))};
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < width; ++x) {
            const double th = M_PI * (y + 0.5) / img.height;
            for (int c = 0; c < 3; ++c) img.rgb[((size_t)y * width + x) * 3 + c] = th < 5 * M_PI / 180 ? 2000.0f : 1.0f;
        }
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    return env;
}

static void test_glass(void **state)
{
    (void)state;
    write_meshes();
    prt_context *ctx = test_context(0);
    const char *floor = "{\"file\": \"floor.obj\", \"material\": \"floor\"}, {\"file\": \"ball.obj\", \"material\": \"ball\"}]}";
    char json[2][600];
    snprintf(json[0], sizeof json[0], "{\"materials\": {\"ball\": {\"albedo\": 0, \"specular\": {\"type\": \"glass\", \"ior\": 1.5}}, \"floor\": {\"albedo\": 0.5}}, \"meshes\": [%s", floor);
    snprintf(json[1], sizeof json[1], "{\"materials\": {\"ball\": {\"albedo\": 0}, \"floor\": {\"albedo\": 0.5}}, \"meshes\": [%s", floor);
    prt_scene *glass = load(ctx, "glass.json", json[0]), *opaque = load(ctx, "opaque.json", json[1]);
    prt_envmap *env = sun_overhead(512);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 5, &L), PRT_OK);
    float *g = bake_relit(ctx, glass, 5, 4096, PRT_TRANSFER_SHADOWED, &L);
    float *o = bake_relit(ctx, opaque, 5, 4096, PRT_TRANSFER_SHADOWED, &L);
    /* Glass picks reflection or refraction from the vertex and sample alone: one thread gives
     * the same bits. */
    prt_context *one = test_context(1);
    float *g1 = bake_relit(one, glass, 5, 4096, PRT_TRANSFER_SHADOWED, &L);
    assert_memory_equal(g, g1, prt_scene_vertex_count(glass) * 3 * sizeof(float));
    free(g1);
    prt_context_release(one);
    const float *pos = prt_scene_positions(glass);
    const size_t nv = prt_scene_vertex_count(glass);
    /* Floor vertices by distance from the point under the centre: the spot (< 0.1), the ring of
     * shadow around it (0.3 .. 0.45, inside the ball's radius), and the open floor (> 1.2). */
    double spot = 0, ring = 0, open = 0, spot_opaque = 0;
    int ns = 0, nr = 0, no = 0;
    for (size_t v = 0; v < nv; ++v) {
        if (fabsf(pos[v * 3 + 1]) > 1e-6f) continue;
        const double rr = hypot(pos[v * 3], pos[v * 3 + 2]);
        if (rr < 0.1) { spot += g[v * 3]; spot_opaque += o[v * 3]; ns++; }
        else if (rr > 0.3 && rr < 0.45) { ring += g[v * 3]; nr++; }
        else if (rr > 1.2 && rr < 1.8) { open += g[v * 3]; no++; }
    }
    assert_true(ns > 0 && nr > 0 && no > 0);
    spot /= ns; ring /= nr; open /= no; spot_opaque /= ns;
    print_message("glass ball (ior 1.5) over a floor, a sun overhead, order 5: under its centre %.2f, its shadow around %.2f, under an opaque ball %.2f, "
                  "the open floor %.2f\n", spot, ring, spot_opaque, open);
    assert_true(spot > 1.5 * ring);
    assert_true(spot - spot_opaque > 0.5 * open);   /* the focused light: more than half the open floor's (order 5 rings below 0 under the opaque ball) */
    free(g);
    free(o);
    prt_envmap_release(env);
    prt_scene_release(glass);
    prt_scene_release(opaque);
    prt_context_release(ctx);
}

/* The glass ball under the smooth sky: the floor beneath and around it agrees with the path
 * tracer per vertex (two refractions, Fresnel's reflections and internal reflections on the way). */
static void test_glass_matches_reference(void **state)
{
    (void)state;
    write_meshes();
    prt_context *ctx = test_context(0);
    prt_scene *s = load(ctx, "glass3.json", "{\"materials\": {\"ball\": {\"albedo\": 0, \"specular\": \"glass\"}, \"floor\": {\"albedo\": 0.5}}, "
                                            "\"meshes\": [{\"file\": \"floor.obj\", \"material\": \"floor\"}, {\"file\": \"ball.obj\", \"material\": \"ball\"}]}");
    prt_envmap *env = quadratic_sky(256);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 3, &L), PRT_OK);
    float *sh = bake_relit(ctx, s, 3, 4096, PRT_TRANSFER_INTERREFLECTED, &L);
    prt_reference_desc d = {0};
    d.samples = 1024;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(s);
    double num = 0, den = 0, noise = 0;
    int n = 0, outside = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        if (fabsf(pos[v * 3 + 1]) > 1e-6f || hypot(pos[v * 3], pos[v * 3 + 2]) > 1.0) continue;   /* the floor near the ball */
        const double got = sh[v * 3], ref = r.radiance[v * 3], err = r.std_error[v * 3];
        num += (got - ref) * (got - ref);
        den += ref * ref;
        noise += err * err;
        n++;
        if (fabs(got - ref) > 4 * err + 0.03 * ref) outside++;
    }
    const double rel = sqrt(num / den), rel_noise = sqrt(noise / den);
    print_message("glass ball (ior 1.5) under the smooth sky, order 3: relative L2 %.4f against the path tracer (its noise %.4f) over the %d floor vertices "
                  "within 1 m, %d outside 4 sigma + 3%%\n", rel, rel_noise, n, outside);
    assert_true(n > 100);
    assert_true(rel < 1.5 * rel_noise + 0.01);
    assert_true(outside <= n / 20);
    free(sh);
    prt_reference_vertices_free(&r);
    prt_envmap_release(env);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Fresnel's equations at normal incidence ((n - 1) / (n + 1))^2, the same from either side,
 * total internal reflection past the critical angle; a ray through a glass slab's faces. */
static void test_optics(void **state)
{
    (void)state;
    assert_true(fabs(prt__fresnel_dielectric(1.0, 1 / 1.5) - 0.04) < 1e-9);
    assert_true(fabs(prt__fresnel_dielectric(1.0, 1.5) - 0.04) < 1e-9);
    assert_true(prt__fresnel_dielectric(cos(42.5 * M_PI / 180), 1.5) == 1.0);   /* critical angle 41.8 degrees */
    assert_true(prt__fresnel_dielectric(cos(41.0 * M_PI / 180), 1.5) < 1.0);
    assert_true(fabs(prt__fresnel_dielectric(1e-6, 1 / 1.5) - 1.0) < 1e-4);   /* grazing */
    const prt_specular glass = {PRT_SPECULAR_GLASS, 0, 1.5f}, mirror = {PRT_SPECULAR_MIRROR, 0.8f, 0};
    const float up[3] = {0, 1, 0}, s30 = 0.5f, c30 = 0.8660254f, d[3] = {s30, -c30, 0};
    float out[3], w;
    /* u above F refracts into the back: Snell, sin t = sin 30 / 1.5 */
    assert_int_equal(prt__specular_scatter(&glass, d, up, up, 0.99, out, &w), -1);
    assert_true(fabsf(out[0] - s30 / 1.5f) < 1e-5f && out[1] < 0 && w == 1.0f);
    /* out of the glass again through the slab's bottom face (its front faces down): the
     * direction it came in with, on that face's front */
    const float down[3] = {0, -1, 0};
    float back[3];
    assert_int_equal(prt__specular_scatter(&glass, out, down, down, 0.99, back, &w), 1);
    assert_true(fabsf(back[0] - d[0]) < 1e-5f && fabsf(back[1] - d[1]) < 1e-5f);
    /* u below F reflects */
    assert_int_equal(prt__specular_scatter(&glass, d, up, up, 0.0, out, &w), 1);
    assert_true(fabsf(out[0] - s30) < 1e-6f && fabsf(out[1] - c30) < 1e-6f);
    /* a mirror reflects its reflectance; its back is dark */
    assert_int_equal(prt__specular_scatter(&mirror, d, up, up, 0.5, out, &w), 1);
    assert_true(fabsf(out[1] - c30) < 1e-6f && w == 0.8f);
    const float from_below[3] = {0, 1, 0};
    assert_int_equal(prt__specular_scatter(&mirror, from_below, up, up, 0.5, out, &w), 0);
}

static void refused(prt_context *ctx, const char *spec, const char *says)
{
    char json[600], path[600];
    snprintf(json, sizeof json, "{\"materials\": {\"m\": {\"specular\": %s}}, \"meshes\": [{\"file\": \"mirror.obj\", \"material\": \"m\"}]}", spec);
    write_text("bad.json", json, path, sizeof path);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_ERR_FORMAT);
    assert_null(s);
    const char *e = prt_last_error();
    print_message("\"specular\": %s -> %s\n", spec, e);
    assert_non_null(strstr(e, says));
    assert_null(strchr(e, '\n'));
}

static void test_bad_specs(void **state)
{
    (void)state;
    write_meshes();
    prt_context *ctx = test_context(0);
    refused(ctx, "\"chrome\"", "unknown specular type 'chrome'");
    refused(ctx, "3", "\"specular\" must be");
    refused(ctx, "{\"ior\": 1.5}", "\"specular\" must be");
    refused(ctx, "{\"type\": \"glass\", \"ior\": 0.5}", "index of refraction must lie in [1, 4]");
    refused(ctx, "{\"type\": \"glass\", \"ior\": \"high\"}", "\"ior\" must be a number");
    refused(ctx, "{\"type\": \"mirror\", \"reflectance\": 1.5}", "reflectance must lie in [0, 1]");
    refused(ctx, "{\"type\": \"mirror\", \"ior\": 1.5}", "a mirror has no \"ior\"");
    /* The API: an unknown surface names the ones there are; a bad material is refused. */
    prt_scene *s = load(ctx, "ok.json", "{\"materials\": {\"m\": {\"specular\": \"glass\"}}, \"meshes\": [{\"file\": \"mirror.obj\", \"material\": \"m\"}]}");
    prt_specular sp;
    assert_int_equal(prt_scene_specular(s, "m", &sp), 1);
    assert_true(sp.type == PRT_SPECULAR_GLASS && sp.ior == 1.5f);
    assert_int_not_equal(prt_scene_set_specular(s, "nope", &sp), PRT_OK);
    assert_non_null(strstr(prt_last_error(), "m"));
    assert_int_equal(prt_scene_set_specular(s, "m", &(prt_specular){PRT_SPECULAR_GLASS, 0, 5.0f}), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_set_specular(s, "m", &(prt_specular){PRT_SPECULAR_NONE, 0, 0}), PRT_OK);
    assert_int_equal(prt_scene_specular(s, "m", NULL), 0);
    prt_scene_release(s);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_optics),
        cmocka_unit_test(test_bad_specs),
        cmocka_unit_test(test_mirror),
        cmocka_unit_test(test_glass),
        cmocka_unit_test(test_glass_matches_reference),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
