/* The reference path tracer against closed forms, and the PRT bake against the reference. */
#include "common.h"

/* White furnace: a convex object of albedo rho under unit radiance reflects exactly rho, all of
 * it direct. */
static void test_open_white_furnace(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 12, 24);
    prt_scene *s = tm_scene(ctx, &m, 0.8f);
    prt_envmap *env = constant_env(1.0f);
    prt_reference_desc d = {0};
    d.samples = 256;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r), PRT_OK);
    for (size_t v = 0; v < r.vertex_count * 3; ++v) {
        if (fabsf(r.radiance[v] - 0.8f) > 4 * r.std_error[v] + 1e-4f)
            fail_msg("vertex %zu: %g +- %g, expected 0.8", v / 3, r.radiance[v], r.std_error[v]);
        assert_true(r.indirect[v] == 0.0f);
        assert_true(r.std_error[v] < 0.05f);
    }
    prt_reference_vertices_free(&r);
    prt_envmap_release(env);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The same furnace inside a concave pit: albedo 1 reflects exactly 1 everywhere, however many
 * bounces it takes (Russian roulette must stay unbiased). */
static void test_concave_white_furnace(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_pit(&m, 4);
    prt_scene *s = tm_scene(ctx, &m, 1.0f);
    prt_envmap *env = constant_env(1.0f);
    prt_reference_desc d = {0};
    d.samples = 1024;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r), PRT_OK);
    double sum = 0, err2 = 0;
    for (size_t v = 0; v < r.vertex_count * 3; ++v) {
        if (fabsf(r.radiance[v] - 1.0f) > 5 * r.std_error[v]) fail_msg("vertex %zu: %g +- %g, expected 1", v / 3, r.radiance[v], r.std_error[v]);
        sum += r.radiance[v];
        err2 += (double)r.std_error[v] * r.std_error[v];
    }
    double n = (double)r.vertex_count * 3, mean = sum / n, mean_err = sqrt(err2) / n;
    if (fabs(mean - 1.0) > 4 * mean_err) fail_msg("mean %g +- %g, expected 1", mean, mean_err);
    prt_reference_vertices_free(&r);
    prt_envmap_release(env);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A convex diffuse sphere under a band-limited environment: exit radiance is rho/pi times the
 * irradiance, sum_l A_l sum_m L_lm y_lm(n) (Ramamoorthi & Hanrahan), exactly. */
static void test_sphere_analytic_irradiance(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 10, 20);
    const float rho = 0.6f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    prt_envmap *env = band_limited_env(512);
    prt_reference_desc d = {0};
    d.samples = 512;
    d.seed = 5;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r), PRT_OK);
    double zh[3];
    prt_sh_clamped_cosine_zh(3, zh);
    const float *n = prt_scene_normals(s);
    int outliers = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        double dn[3] = {n[v * 3], n[v * 3 + 1], n[v * 3 + 2]}, y[9], e = 0;
        prt_sh_eval(3, dn, y);
        for (int l = 0; l < 3; ++l)
            for (int mm = -l; mm <= l; ++mm) e += sqrt(4 * M_PI / (2 * l + 1)) * zh[l] * test_known_sh[l * (l + 1) + mm] * y[l * (l + 1) + mm];
        double expect = rho / M_PI * e;   /* red channel */
        double err = fabs(r.radiance[v * 3] - expect), bound = 4 * r.std_error[v * 3] + 0.005 * expect;
        if (err > bound) outliers++;
        if (err > 2 * bound) fail_msg("vertex %zu: %g +- %g, analytic %g", v, r.radiance[v * 3], r.std_error[v * 3], expect);
    }
    assert_true(outliers <= (int)(r.vertex_count / 100) + 1);
    prt_reference_vertices_free(&r);
    prt_envmap_release(env);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A sun: black sky but for a 3-degree disc 20000 times brighter than the unit sky. Importance
 * sampling must find it with few paths: each vertex of a convex sphere gets within a few
 * percent of the exact sum over the map's pixels, sum L_p max(n . w_p, 0) dw_p * rho / pi. */
static void test_sun_converges(void **state)
{
    (void)state;
    const int w = 512, h = 256;
    prt_image img = {w, h, calloc((size_t)w * h * 3, sizeof(float))};
    const double sun[3] = {0.48, 0.8, 0.36};   /* unit length */
    const double cos_r = cos(1.5 * M_PI / 180.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double th = M_PI * (y + 0.5) / h, ph = 2 * M_PI * ((x + 0.5) / w - 0.5);
            double d[3] = {sin(th) * sin(ph), cos(th), -sin(th) * cos(ph)};
            if (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2] > cos_r)
                for (int c = 0; c < 3; ++c) img.rgb[((size_t)y * w + x) * 3 + c] = 20000.0f;
        }
    /* The exact answer for the piecewise-constant map, per normal. */
    float *copy = malloc((size_t)w * h * 3 * sizeof(float));
    memcpy(copy, img.rgb, (size_t)w * h * 3 * sizeof(float));
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 8, 16);
    const float rho = 0.5f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    prt_reference_desc d = {0};
    d.samples = 64;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r), PRT_OK);
    const float *n = prt_scene_normals(s);
    int checked = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        double e = 0;
        for (int y = 0; y < h; ++y) {
            double th0 = M_PI * y / h, th1 = M_PI * (y + 1) / h, th = 0.5 * (th0 + th1), dw = 2 * M_PI / w * (cos(th0) - cos(th1));
            for (int x = 0; x < w; ++x) {
                float L = copy[((size_t)y * w + x) * 3];
                if (L == 0) continue;
                double ph = 2 * M_PI * ((x + 0.5) / w - 0.5);
                double dd[3] = {sin(th) * sin(ph), cos(th), -sin(th) * cos(ph)};
                double c = n[v * 3] * dd[0] + n[v * 3 + 1] * dd[1] + n[v * 3 + 2] * dd[2];
                if (c > 0) e += L * c * dw;
            }
        }
        double expect = rho / M_PI * e;
        if (expect < 1.0) continue;   /* the terminator, where a 3-degree disc is partly below the horizon */
        checked++;
        if (fabs(r.radiance[v * 3] - expect) > 0.03 * expect)
            fail_msg("vertex %zu: %g with 64 paths, exact %g", v, r.radiance[v * 3], expect);
    }
    assert_true(checked > 20);
    free(copy);
    prt_reference_vertices_free(&r);
    prt_envmap_release(env);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* PRT inter-reflected transfer under a lighting of its own band limit is exact up to the bake's
 * sampling and interpolation: it must agree with the reference within its error bars. */
static void test_prt_matches_reference(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_pit(&m, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    prt_envmap *env = band_limited_env(256);
    prt_bake_desc bd = {0};
    bd.order = 3;
    bd.samples = 4096;
    bd.bounces = 12;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &bd, &t), PRT_OK);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 3, &L), PRT_OK);
    size_t nv = prt_transfer_vertex_count(t);
    float *prt_rgb = malloc(nv * 3 * sizeof(float)), *prt_direct = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_INTERREFLECTED, &L, prt_rgb), PRT_OK);
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_SHADOWED, &L, prt_direct), PRT_OK);
    prt_reference_desc d = {0};
    d.samples = 1024;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r), PRT_OK);
    assert_int_equal(r.vertex_count, nv);
    double num = 0, den = 0, num_ind = 0, den_ind = 0, noise = 0, noise_ind = 0;
    int outside = 0;
    for (size_t i = 0; i < nv * 3; ++i) {
        double diff = prt_rgb[i] - r.radiance[i];
        num += diff * diff;
        den += (double)r.radiance[i] * r.radiance[i];
        double ind = prt_rgb[i] - prt_direct[i], di = ind - r.indirect[i];
        num_ind += di * di;
        den_ind += (double)r.indirect[i] * r.indirect[i];
        noise += (double)r.std_error[i] * r.std_error[i];
        noise_ind += (double)r.std_error_indirect[i] * r.std_error_indirect[i];
        if (fabs(diff) > 4 * r.std_error[i] + 0.02 * r.radiance[i]) outside++;
    }
    /* The reference's own noise, as a relative L2 over all vertices: what a perfect PRT would show. */
    double rel = sqrt(num / den), rel_ind = sqrt(num_ind / den_ind), rel_noise = sqrt(noise / den), rel_noise_ind = sqrt(noise_ind / den_ind);
    print_message("PRT (order 3, 12 bounces) vs reference on the pit: relative L2 %.4f (reference noise %.4f), indirect %.4f (noise %.4f), "
                  "%d of %zu outside 4 sigma + 2%%\n", rel, rel_noise, rel_ind, rel_noise_ind, outside, nv * 3);
    assert_true(rel < 1.5 * rel_noise + 0.01);
    assert_true(rel_ind < 1.5 * rel_noise_ind + 0.02);
    assert_true(outside < (int)(nv * 3 / 20));
    free(prt_rgb);
    free(prt_direct);
    prt_reference_vertices_free(&r);
    prt_transfer_release(t);
    prt_envmap_release(env);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The same agreement on the procedural demo scene (walls, a torus, a sphere on the floor).
 * Where the torus and the sphere rest on the floor, the bake's vertex spacing (6 cm on the floor)
 * cannot resolve the 3 mm gaps: light gathered there is interpolated from vertices outside the
 * contact shadow, so a few percent of vertices near contacts are too bright - the per-vertex
 * method's own discretization, which the reference makes visible. Everywhere else the two agree
 * within the reference's error bars; the bounds below allow for the contact band. */
static void test_prt_matches_reference_demo(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_scene *s = load_demo_scene(ctx);
    prt_envmap *env = band_limited_env(256);
    prt_bake_desc bd = {0};
    bd.order = 3;
    bd.samples = 2048;
    bd.bounces = 8;
    bd.kinds = PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &bd, &t), PRT_OK);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 3, &L), PRT_OK);
    size_t nv = prt_transfer_vertex_count(t);
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh(ctx, t, PRT_TRANSFER_INTERREFLECTED, &L, rgb), PRT_OK);
    prt_reference_desc d = {0};
    d.samples = 256;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r), PRT_OK);
    double se = 0, sb = 0, noise = 0;
    int outside = 0;
    for (size_t i = 0; i < nv * 3; ++i) {
        double diff = rgb[i] - r.radiance[i];
        se += diff * diff;
        sb += (double)r.radiance[i] * r.radiance[i];
        noise += (double)r.std_error[i] * r.std_error[i];
        if (fabs(diff) > 4 * r.std_error[i] + 0.02 * r.radiance[i]) outside++;
    }
    double rel = sqrt(se / sb), rel_noise = sqrt(noise / sb);
    print_message("PRT (order 3) vs reference on the demo scene: relative L2 %.4f (reference noise %.4f), %d of %zu outside 4 sigma + 2%%\n",
                  rel, rel_noise, outside, nv * 3);
    assert_true(rel < 1.5 * rel_noise + 0.035);
    assert_true(outside < (int)(nv * 3 / 25));
    free(rgb);
    prt_reference_vertices_free(&r);
    prt_transfer_release(t);
    prt_envmap_release(env);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_deterministic_and_image(void **state)
{
    (void)state;
    test_mesh m = {0};
    tm_pit(&m, 4);
    prt_envmap *env = band_limited_env(64);
    prt_reference_vertices r[2];
    for (int i = 0; i < 2; ++i) {
        prt_context *ctx = test_context(i + 1);
        prt_scene *s = tm_scene(ctx, &m, 0.5f);
        prt_reference_desc d = {0};
        d.samples = 16;
        d.target_rel_error = 0.05f;
        d.max_samples = 256;
        assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r[i]), PRT_OK);
        prt_scene_release(s);
        prt_context_release(ctx);
    }
    assert_memory_equal(r[0].radiance, r[1].radiance, r[0].vertex_count * 3 * sizeof(float));
    assert_memory_equal(r[0].samples, r[1].samples, r[0].vertex_count * sizeof(int));
    bool grew = false;
    for (size_t v = 0; v < r[0].vertex_count; ++v) grew |= r[0].samples[v] > 16;
    assert_true(grew);   /* the target error asked for more samples somewhere */
    prt_reference_vertices_free(&r[0]);
    prt_reference_vertices_free(&r[1]);

    /* An image of a convex sphere in a white furnace: rho on the sphere, background elsewhere. */
    prt_context *ctx = test_context(0);
    test_mesh sm = {0};
    tm_sphere(&sm, (float[3]){0, 0, 0}, 1.0f, 16, 32);
    prt_scene *s = tm_scene(ctx, &sm, 0.5f);
    prt_envmap *white = constant_env(1.0f);
    prt_camera cam = {{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40};
    prt_reference_desc d = {0};
    d.samples = 64;
    prt_image img, err;
    float bg[3] = {0.25f, 0.25f, 0.25f};
    assert_int_equal(prt_reference_trace_image(ctx, s, white, &d, &cam, 32, 32, bg, &img, &err), PRT_OK);
    float centre = img.rgb[(16 * 32 + 16) * 3], corner = img.rgb[0];
    assert_true(fabsf(centre - 0.5f) < 4 * err.rgb[(16 * 32 + 16) * 3] + 1e-3f);
    assert_true(corner == 0.25f);
    prt_image_free(&img);
    prt_image_free(&err);
    d.samples = -1;
    assert_int_equal(prt_reference_trace_image(ctx, s, white, &d, &cam, 32, 32, bg, &img, NULL), PRT_ERR_INVALID_ARG);
    prt_envmap_release(white);
    prt_scene_release(s);
    tm_free(&sm);
    prt_context_release(ctx);
    prt_envmap_release(env);
    tm_free(&m);
}

/* ---- local lights, emitters and BRDFs ---- */

static prt_lighting *lighting_of(const char *const *specs, int n)
{
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    for (int i = 0; i < n; ++i) {
        prt_light light;
        if (prt_light_parse(specs[i], &light) != PRT_OK) fail_msg("%s", prt_last_error());
        assert_int_equal(prt_lighting_add(l, &light, NULL), PRT_OK);
    }
    return l;
}

/* A ground plane y = 0 facing up, side 2 * half, n x n cells, centred on the origin. */
static void ground(test_mesh *m, float half, int n)
{
    tm_quad(m, (float[3]){-half, 0, half}, (float[3]){2 * half, 0, 0}, (float[3]){0, 0, -2 * half}, n);
}

/* Point lights are deltas: with nothing else lighting an unoccluded plane, every vertex gets
 * exactly rho/pi I cos / r^2, with no noise; directly below the light it falls as 1/h^2. */
static void test_point_light_plane(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    ground(&m, 2, 8);
    const float rho = 0.6f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    const char *spec[] = {"point:0.3,1.5,-0.2:10,5,2"};
    prt_lighting *l = lighting_of(spec, 1);
    prt_reference_desc d = {0};
    d.samples = 16;
    d.lighting = l;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(s), up[3] = {0, 1, 0};
    double worst = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        float e[3];
        prt_light_irradiance(prt_lighting_light(l, 0), pos + v * 3, up, e);
        for (int c = 0; c < 3; ++c) {
            double want = rho / M_PI * e[c], rel = fabs(r.direct[v * 3 + c] - want) / want;
            worst = fmax(worst, rel);
            if (rel > 1e-5) fail_msg("vertex %zu: direct %g, closed form %g", v, r.direct[v * 3 + c], want);
            assert_true(fabs(r.radiance[v * 3 + c] - want) <= 4 * r.std_error[v * 3 + c] + 1e-5 * want);
            assert_true(r.indirect[v * 3 + c] == 0.0f);
        }
    }
    print_message("point light over a plane: worst relative error of the direct light vs rho/pi I cos/r^2: %.2e\n", worst);
    prt_reference_vertices_free(&r);
    /* Inverse square: the vertex at the origin under a light at heights 1 and 2. */
    size_t o = nearest_vertex(pos, prt_scene_vertex_count(s), (float[3]){0, 0, 0});
    float at[2];
    for (int k = 0; k < 2; ++k) {
        prt_light p;
        assert_int_equal(prt_light_parse(k ? "point:0,2,0:8" : "point:0,1,0:8", &p), PRT_OK);
        assert_int_equal(prt_lighting_set(l, 0, &p), PRT_OK);
        assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
        at[k] = r.radiance[o * 3];
        prt_reference_vertices_free(&r);
    }
    print_message("inverse square: radiance at h = 1: %g, h = 2: %g, ratio %.6f (exact 4)\n", at[0], at[1], at[0] / at[1]);
    assert_true(fabsf(at[0] - rho / (float)M_PI * 8.0f) < 1e-5f);
    assert_true(fabsf(at[0] / at[1] - 4.0f) < 1e-4f);
    prt_lighting_release(l);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A spot light's hard cone edge lands at radius h tan(angle) on the plane below it. */
static void test_spot_cone_edge(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    ground(&m, 1, 40);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    const char *spec[] = {"spot:0,1,0:0,-1,0:30:4"};
    prt_lighting *l = lighting_of(spec, 1);
    prt_reference_desc d = {0};
    d.samples = 4;
    d.lighting = l;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(s);
    const double edge = tan(30 * M_PI / 180);
    double lit_max = 0, dark_min = INFINITY;
    int inside = 0, outside = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        double rad = hypot(pos[v * 3], pos[v * 3 + 2]);
        if (r.radiance[v * 3] > 0) lit_max = fmax(lit_max, rad);
        else dark_min = fmin(dark_min, rad);
        if (fabs(rad - edge) < 0.02) {
            bool lit = r.radiance[v * 3] > 0;
            if (lit != (rad < edge)) fail_msg("vertex at radius %g is %s; the cone edge is at %g", rad, lit ? "lit" : "dark", edge);
            inside += rad < edge;
            outside += rad > edge;
        }
    }
    print_message("spot cone edge: predicted radius %.4f, outermost lit vertex %.4f, innermost dark vertex %.4f (%d/%d vertices within 0.02 of it)\n",
                  edge, lit_max, dark_min, inside, outside);
    assert_true(inside > 0 && outside > 0);
    assert_true(lit_max < edge && dark_min > edge);
    prt_reference_vertices_free(&r);
    prt_lighting_release(l);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A sphere light over an unoccluded plane: pi L R^2 / d^2 right below it, the exact cap
 * irradiance everywhere (prt_light_irradiance, checked against quadrature in test_lights). */
static void test_sphere_light_plane(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    ground(&m, 1.5f, 12);
    const float rho = 0.8f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    const char *spec[] = {"sphere:0,1,0:0.3:5,4,3"};
    prt_lighting *l = lighting_of(spec, 1);
    prt_reference_desc d = {0};
    d.samples = 256;
    d.lighting = l;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(s), up[3] = {0, 1, 0};
    double worst_sigma = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        float e[3];
        prt_light_irradiance(prt_lighting_light(l, 0), pos + v * 3, up, e);
        double want = rho / M_PI * e[0], diff = fabs(r.radiance[v * 3] - want);
        worst_sigma = fmax(worst_sigma, diff / (r.std_error[v * 3] + 1e-12));
        if (diff > 4 * r.std_error[v * 3] + 1e-3 * want) fail_msg("vertex %zu: %g +- %g, exact %g", v, r.radiance[v * 3], r.std_error[v * 3], want);
    }
    size_t o = nearest_vertex(pos, r.vertex_count, (float[3]){0, 0, 0});
    double centre = rho / M_PI * M_PI * 5 * 0.09;
    print_message("sphere light: centre vertex %g +- %g, rho/pi * pi L R^2/d^2 = %g; worst deviation %.2f sigma over %zu vertices\n",
                  r.radiance[o * 3], r.std_error[o * 3], centre, worst_sigma, r.vertex_count);
    assert_true(fabs(r.radiance[o * 3] - centre) < 4 * r.std_error[o * 3] + 1e-3 * centre);
    prt_reference_vertices_free(&r);
    prt_lighting_release(l);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A directional light on a convex sphere: rho/pi E max(n.d, 0), exactly (a delta). */
static void test_directional_light(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 10, 20);
    const float rho = 0.5f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    const char *spec[] = {"directional:0.3,1,0.2:2,1,0.5"};
    prt_lighting *l = lighting_of(spec, 1);
    const float *dir = prt_lighting_light(l, 0)->direction, *n = prt_scene_normals(s);
    prt_reference_desc d = {0};
    d.samples = 8;
    d.lighting = l;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    int checked = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        double c = n[v * 3] * dir[0] + n[v * 3 + 1] * dir[1] + n[v * 3 + 2] * dir[2];
        if (c < 0.2 && c > -0.05) continue;   /* the terminator, where neighbouring facets may shadow a vertex */
        double want = rho / M_PI * 2 * fmax(c, 0.0);
        if (fabs(r.radiance[v * 3] - want) > 1e-5 * want + 1e-7) fail_msg("vertex %zu: %g, E cos = %g", v, r.radiance[v * 3], want);
        checked++;
    }
    assert_true(checked > 100);
    prt_reference_vertices_free(&r);
    prt_lighting_release(l);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Penumbra of a sphere light behind a straight edge. Light of radius R at height H, an opaque
 * plate at height h covering x < 0: on the ground, similar triangles put the penumbra at
 * |x| < R h / (H - h), and within it the visible part of the light's disc is a circular segment,
 * so the lit fraction is (acos(-t) + t sqrt(1 - t^2)) / pi at t = x (H - h) / (R h). */
static double segment_fraction(double t)
{
    t = fmax(-1.0, fmin(1.0, t));
    return (acos(-t) + t * sqrt(1 - t * t)) / M_PI;
}

static double crossing(const double *x, const double *f, int n, double level)
{
    for (int i = 1; i < n; ++i)
        if ((f[i - 1] - level) * (f[i] - level) <= 0 && f[i] != f[i - 1]) return x[i - 1] + (level - f[i - 1]) / (f[i] - f[i - 1]) * (x[i] - x[i - 1]);
    return NAN;
}

static void test_sphere_light_penumbra(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    const int nx = 120;
    /* A strip along x: 3 rows of nx + 1 vertices, 1 cm wide. */
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i <= nx; ++i) tm_vertex(&m, -0.6f + 1.2f * i / nx, 0, 0.01f * (1 - j), 0, 1, 0);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < nx; ++i) {
            uint32_t a = (uint32_t)(j * (nx + 1) + i), b = a + 1, c = a + (uint32_t)(nx + 1), dd = c + 1;
            tm_tri(&m, a, b, c);
            tm_tri(&m, b, dd, c);
        }
    tm_quad(&m, (float[3]){-3, 1, 3}, (float[3]){3, 0, 0}, (float[3]){0, 0, -6}, 2);   /* the plate, x in [-3, 0] at y = 1 */
    const size_t strip = (size_t)3 * (nx + 1);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    assert_int_equal(prt_scene_vertex_count(s), strip + 9);
    const char *spec[] = {"sphere:0,2,0:0.2:10"};
    prt_lighting *l = lighting_of(spec, 1);
    prt_reference_desc d = {0};
    d.samples = 2048;
    d.lighting = l;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(s), up[3] = {0, 1, 0};
    const double H = 2, h = 1, R = 0.2, half = R * h / (H - h);
    double x[200], f[200];
    int n = 0, bad = 0;
    for (size_t v = nx + 1; v < 2 * (size_t)(nx + 1); ++v) {   /* the middle row */
        float e[3];
        prt_light_irradiance(prt_lighting_light(l, 0), pos + v * 3, up, e);
        x[n] = pos[v * 3];
        f[n] = r.radiance[v * 3] / (0.5 / M_PI * e[0]);
        double want = segment_fraction(x[n] / half), sig = r.std_error[v * 3] / (0.5 / M_PI * e[0]);
        if (fabs(f[n] - want) > 4 * sig + 0.04) bad++;
        n++;
    }
    double x10 = crossing(x, f, n, 0.1), x90 = crossing(x, f, n, 0.9);
    /* The predicted 10-90 width: where the segment fraction is 0.1 and 0.9 (symmetric). */
    double lo = 0, hi = 1;
    for (int it = 0; it < 60; ++it) { double mid = 0.5 * (lo + hi); if (segment_fraction(mid) < 0.9) lo = mid; else hi = mid; }
    double pred = 2 * lo * half;
    print_message("sphere light penumbra: geometric full width %.4f, 10-90%% width predicted %.4f, measured %.4f (%+.1f%%); "
                  "%d of %d strip vertices off the segment curve by more than 4 sigma + 0.04\n",
                  2 * half, pred, x90 - x10, 100 * ((x90 - x10) / pred - 1), bad, n);
    assert_true(fabs((x90 - x10) / pred - 1) < 0.1);
    assert_true(fabs(0.5 * (x10 + x90)) < 0.02);   /* centred under the edge */
    assert_true(bad <= 3);
    prt_reference_vertices_free(&r);
    prt_lighting_release(l);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Directional albedo of a BRDF towards wo (local frame): the integral of f cos over the
 * hemisphere, by the midpoint rule in (sin^2 theta, phi), where dw cos = ds dphi / 2. */
static double directional_albedo(const prt_brdf *b, const float wo[3], int c)
{
    const int ns = 400, np = 800;
    double sum = 0;
    for (int i = 0; i < ns; ++i) {
        double s2 = (i + 0.5) / ns, st = sqrt(s2), ct = sqrt(1 - s2);
        for (int k = 0; k < np; ++k) {
            double ph = 2 * M_PI * (k + 0.5) / np;
            float wi[3] = {(float)(st * cos(ph)), (float)(st * sin(ph)), (float)ct}, f[3];
            prt_brdf_eval(b, wi, wo, f);
            sum += f[c];
        }
    }
    return sum * 0.5 / ns * 2 * M_PI / np;
}

/* A convex glossy sphere under a uniform white environment, seen from an eye: each vertex's exit
 * radiance towards the eye is its BRDF's directional albedo for that view, whatever the BRDF. */
static void test_glossy_albedo(void **state)
{
    (void)state;
    static const char *brdfs[] = {"phong:20:0.6:0.3", "blinn:40:0.5:0.4", "ashikhmin:10:200:0.3:0.5", "lafortune:clay"};
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 10, 20);
    prt_envmap *white = constant_env(1.0f);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, white, NULL, 1.0f), PRT_OK);
    const float eye[3] = {1.5f, 2.0f, 6.0f};
    for (int k = 0; k < 4; ++k) {
        prt_brdf b;
        assert_int_equal(prt_brdf_parse(brdfs[k], &b), PRT_OK);
        prt_scene *s = tm_scene(ctx, &m, 0.5f);
        assert_int_equal(prt_scene_set_brdf(s, 0, prt_scene_vertex_count(s), &b), PRT_OK);
        prt_reference_desc d = {0};
        d.samples = 1024;
        d.seed = 3;
        d.lighting = l;
        d.eye = eye;
        prt_reference_vertices r;
        assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
        const float *pos = prt_scene_positions(s), *nrm = prt_scene_normals(s);
        double worst = 0, worst_sigma = 0;
        int checked = 0;
        for (size_t v = 0; v < r.vertex_count; v += 2) {
            float wo[3] = {eye[0] - pos[v * 3], eye[1] - pos[v * 3 + 1], eye[2] - pos[v * 3 + 2]}, sv[3], tv[3], wl[3];
            float len = sqrtf(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
            for (int c = 0; c < 3; ++c) wo[c] /= len;
            prt_brdf_frame(nrm + v * 3, sv, tv);
            wl[0] = wo[0] * sv[0] + wo[1] * sv[1] + wo[2] * sv[2];
            wl[1] = wo[0] * tv[0] + wo[1] * tv[1] + wo[2] * tv[2];
            wl[2] = wo[0] * nrm[v * 3] + wo[1] * nrm[v * 3 + 1] + wo[2] * nrm[v * 3 + 2];
            if (wl[2] < 0.25f) continue;
            int c = (int)(v % 3);
            double want = directional_albedo(&b, wl, c), got = r.radiance[v * 3 + c], se = r.std_error[v * 3 + c];
            worst = fmax(worst, fabs(got - want) / want);
            worst_sigma = fmax(worst_sigma, fabs(got - want) / se);
            if (fabs(got - want) > 4 * se + 0.01 * want) fail_msg("%s, vertex %zu: %g +- %g, albedo %g", brdfs[k], v, got, se, want);
            assert_true(r.indirect[v * 3 + c] < 1e-3f * want);
            checked++;
        }
        print_message("%-26s directional albedo towards the eye: %d vertices, worst relative error %.4f (%.2f sigma)\n", brdfs[k], checked,
                      worst, worst_sigma);
        assert_true(checked >= 10);
        prt_reference_vertices_free(&r);
        prt_scene_release(s);
    }
    prt_lighting_release(l);
    tm_free(&m);
    prt_context_release(ctx);
}

static void write_obj(const char *name, const test_mesh *m, char *path, size_t size)
{
    snprintf(path, size, "%s/%s", test_dir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (size_t v = 0; v < m->nv; ++v) fprintf(f, "v %.9g %.9g %.9g\nvn %.9g %.9g %.9g\n", m->pos[v * 3], m->pos[v * 3 + 1], m->pos[v * 3 + 2],
                                               m->nrm[v * 3], m->nrm[v * 3 + 1], m->nrm[v * 3 + 2]);
    for (size_t t = 0; t < m->nt; ++t)
        fprintf(f, "f %u//%u %u//%u %u//%u\n", m->idx[t * 3] + 1, m->idx[t * 3] + 1, m->idx[t * 3 + 1] + 1, m->idx[t * 3 + 1] + 1,
                m->idx[t * 3 + 2] + 1, m->idx[t * 3 + 2] + 1);
    fclose(f);
}

/* A small emissive square (side a, radiance Le, facing down) at height 1 over a plane: far from
 * it, it is a point light of intensity Le a^2 cos(theta_l); its vertices return Le; a camera
 * looking at it sees Le. */
static void test_emissive_quad(void **state)
{
    (void)state;
    char path[512];
    test_mesh plane = {0}, lamp = {0};
    ground(&plane, 1.5f, 10);
    const float a = 0.1f, Le = 100.0f, rho = 0.5f;
    tm_quad(&lamp, (float[3]){-a / 2, 1, -a / 2}, (float[3]){a, 0, 0}, (float[3]){0, 0, a}, 1);   /* a x (0,0,a) = -y */
    write_obj("plane.obj", &plane, path, sizeof path);
    write_obj("lamp.obj", &lamp, path, sizeof path);
    snprintf(path, sizeof path, "%s/emissive.json", test_dir);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "{\"environment\": \"none\", \"meshes\": [{\"file\": \"plane.obj\", \"albedo\": %g}, {\"file\": \"lamp.obj\", \"emission\": %g}]}\n",
            rho, Le);
    fclose(f);
    prt_context *ctx = test_context(0);
    prt_scene *s = NULL;
    if (prt_scene_load(ctx, path, NULL, &s) != PRT_OK) fail_msg("%s", prt_last_error());
    prt_lighting *l = NULL;
    assert_int_equal(prt_scene_lighting(ctx, s, &l), PRT_OK);
    assert_null(prt_lighting_envmap(l));
    prt_reference_desc d = {0};
    d.samples = 256;
    d.lighting = l;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(s);
    double worst = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        const float *p = pos + v * 3;
        if (p[1] > 0.5f) {   /* the lamp: its own radiance (and a little reflected light) */
            assert_true(r.direct[v * 3] >= Le && r.radiance[v * 3] < Le * 1.001f);
            continue;
        }
        double dx = -p[0], dy = 1 - p[1], dz = -p[2], r2 = dx * dx + dy * dy + dz * dz, c = dy / sqrt(r2);
        double want = rho / M_PI * Le * a * a * c * c / r2;   /* cos at the lamp = cos at the plane here */
        double rel = fabs(r.radiance[v * 3] - want) / want;
        worst = fmax(worst, rel);
        if (fabs(r.radiance[v * 3] - want) > 4 * r.std_error[v * 3] + 0.02 * want)
            fail_msg("vertex %zu: %g +- %g, point-light limit %g", v, r.radiance[v * 3], r.std_error[v * 3], want);
    }
    print_message("emissive 10 cm square at 1 m: worst relative deviation from its point-light limit %.4f\n", worst);
    prt_reference_vertices_free(&r);
    /* Seen by a camera below it, the lamp is Le. */
    prt_camera cam = {{0, 0.5f, 0}, {0, 1, 0}, {0, 0, 1}, 4};
    prt_image img;
    d.samples = 4;
    assert_int_equal(prt_reference_trace_image(ctx, s, NULL, &d, &cam, 5, 5, NULL, &img, NULL), PRT_OK);
    assert_true(img.rgb[(2 * 5 + 2) * 3] >= Le && img.rgb[(2 * 5 + 2) * 3] < Le * 1.001f);
    prt_image_free(&img);
    /* Emission scale 0 switches it off. */
    prt_lighting_set_emission(l, 0);
    d.samples = 4;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    for (size_t v = 0; v < r.vertex_count * 3; ++v) assert_true(r.radiance[v] == 0.0f);
    prt_reference_vertices_free(&r);
    prt_lighting_release(l);
    prt_scene_release(s);
    tm_free(&plane);
    tm_free(&lamp);
    prt_context_release(ctx);
}

/* Form factor of the rectangle [0, x] x [0, y] in a parallel plane at distance 1 to a point below
 * its corner, signed (odd in x and in y) so that rectangles add up by inclusion-exclusion. */
static double rect_ff(double x, double y)
{
    double sx = sqrt(1 + x * x), sy = sqrt(1 + y * y);
    return (x / sx * atan(y / sx) + y / sy * atan(x / sy)) / (2 * M_PI);
}

/* The Cornell box lit only by its ceiling light (Ke 17 12 4): a floor vertex in the light's full
 * view gets rho/pi times the exact irradiance of the rectangle (form factor) as direct light,
 * the light's vertices return Ke, nothing is NaN. */
static void test_cornell_box(void **state)
{
    (void)state;
    const char *path = cornell_box_path();
    if (!path) skip();
    prt_context *ctx = test_context(0);
    prt_scene_desc sd = {0};
    sd.max_edge = 0.25f;
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, &sd, &s), PRT_OK);
    assert_non_null(prt_scene_emission(s));
    prt_lighting *l = NULL;
    assert_int_equal(prt_scene_lighting(ctx, s, &l), PRT_OK);
    assert_null(prt_lighting_envmap(l));   /* lit by its emitter alone */
    prt_reference_desc d = {0};
    d.samples = 128;
    d.lighting = l;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r), PRT_OK);
    const float *pos = prt_scene_positions(s), *em = prt_scene_emission(s), *alb = prt_scene_albedo(s);
    int lamp = 0;
    for (size_t v = 0; v < r.vertex_count; ++v) {
        for (int c = 0; c < 3; ++c) assert_true(isfinite(r.radiance[v * 3 + c]) && r.radiance[v * 3 + c] >= 0);
        if (em[v * 3] > 0) {
            lamp++;
            assert_true(em[v * 3] == 17 && em[v * 3 + 1] == 12 && em[v * 3 + 2] == 4);
            for (int c = 0; c < 3; ++c) assert_true(r.direct[v * 3 + c] >= em[v * 3 + c] && r.radiance[v * 3 + c] < 1.02f * em[v * 3 + c]);
        }
    }
    assert_true(lamp >= 4);
    /* A floor vertex that sees the whole light (x in [-0.24, 0.23], z in [-0.22, 0.16], y = 1.98). */
    size_t v = nearest_vertex(pos, r.vertex_count, (float[3]){0.45f, 0, -0.35f});
    const float *p = pos + v * 3;
    double h = 1.98 - p[1], x0 = (-0.24 - p[0]) / h, x1 = (0.23 - p[0]) / h, z0 = (-0.22 - p[2]) / h, z1 = (0.16 - p[2]) / h;
    double F = rect_ff(x1, z1) - rect_ff(x0, z1) - rect_ff(x1, z0) + rect_ff(x0, z0);
    print_message("Cornell box floor vertex (%.3f, %.3f, %.3f): direct %.4f %.4f %.4f, form factor %.4f -> exact %.4f %.4f %.4f; "
                  "indirect %.4f %.4f %.4f\n",
                  p[0], p[1], p[2], r.direct[v * 3], r.direct[v * 3 + 1], r.direct[v * 3 + 2], F, alb[v * 3] / M_PI * M_PI * 17 * F,
                  alb[v * 3 + 1] * 12 * F, alb[v * 3 + 2] * 4 * F, r.indirect[v * 3], r.indirect[v * 3 + 1], r.indirect[v * 3 + 2]);
    const float ke[3] = {17, 12, 4};
    for (int c = 0; c < 3; ++c) {
        double want = alb[v * 3 + c] / M_PI * M_PI * ke[c] * F;   /* rho/pi E, E = pi Le F */
        assert_true(fabs(r.direct[v * 3 + c] - want) < 4 * r.std_error[v * 3 + c] + 0.02 * want);
        assert_true(r.indirect[v * 3 + c] > 0);
    }
    prt_reference_vertices_free(&r);
    prt_lighting_release(l);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Every light type together, one and two threads: the same bits. Bad combinations are refused. */
static void test_lights_thread_independent(void **state)
{
    (void)state;
    test_mesh m = {0};
    tm_pit(&m, 4);
    const char *spec[] = {"point:0,0.8,0:2", "spot:0.2,1.5,0:0,-1,0:25,10:3", "directional:0.3,1,0.2:1", "sphere:-0.2,1.2,0.1:0.1:20"};
    prt_lighting *l = lighting_of(spec, 4);
    prt_envmap *env = band_limited_env(64);
    assert_int_equal(prt_lighting_set_envmap(l, env, NULL, 0.5f), PRT_OK);
    prt_brdf b;
    assert_int_equal(prt_brdf_parse("phong:30:0.4:0.4", &b), PRT_OK);
    const float eye[3] = {0.3f, 2, 1};
    prt_reference_vertices r[2];
    for (int i = 0; i < 2; ++i) {
        prt_context *ctx = test_context(i + 1);
        prt_scene *s = tm_scene(ctx, &m, 0.5f);
        assert_int_equal(prt_scene_set_brdf(s, 0, 25, &b), PRT_OK);   /* the floor is glossy */
        prt_reference_desc d = {0};
        d.samples = 16;
        d.lighting = l;
        d.eye = eye;
        assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r[i]), PRT_OK);
        if (i == 0) {
            assert_int_equal(prt_reference_trace_vertices(ctx, s, env, &d, &r[1]), PRT_ERR_INVALID_ARG);
            d.lighting = NULL;
            assert_int_equal(prt_reference_trace_vertices(ctx, s, NULL, &d, &r[1]), PRT_ERR_INVALID_ARG);
        }
        prt_scene_release(s);
        prt_context_release(ctx);
    }
    assert_memory_equal(r[0].radiance, r[1].radiance, r[0].vertex_count * 3 * sizeof(float));
    for (size_t v = 0; v < r[0].vertex_count * 3; ++v) assert_true(isfinite(r[0].radiance[v]));
    prt_reference_vertices_free(&r[0]);
    prt_reference_vertices_free(&r[1]);
    prt_lighting_release(l);
    tm_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_open_white_furnace),
        cmocka_unit_test(test_concave_white_furnace),
        cmocka_unit_test(test_sphere_analytic_irradiance),
        cmocka_unit_test(test_sun_converges),
        cmocka_unit_test(test_prt_matches_reference),
        cmocka_unit_test(test_prt_matches_reference_demo),
        cmocka_unit_test(test_deterministic_and_image),
        cmocka_unit_test(test_point_light_plane),
        cmocka_unit_test(test_spot_cone_edge),
        cmocka_unit_test(test_sphere_light_plane),
        cmocka_unit_test(test_directional_light),
        cmocka_unit_test(test_sphere_light_penumbra),
        cmocka_unit_test(test_glossy_albedo),
        cmocka_unit_test(test_emissive_quad),
        cmocka_unit_test(test_cornell_box),
        cmocka_unit_test(test_lights_thread_independent),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
