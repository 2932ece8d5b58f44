/* The wavelet method (Wang, Tran & Luebke 2005): Haar basis, separable BRDFs, sparse quantized
 * transport, interreflection passes, against analytic answers, the SH method and the reference
 * path tracer. */
#include "common.h"

#define DIM PRT_WAVELET_DIM

static uint32_t rng_state = 12345u;
static float frand(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return (float)(rng_state >> 8) / 16777216.0f;
}

/* Orthonormal: inner products survive the transform; exactly invertible; the basis functions of a
 * small size form an identity Gram matrix. */
static void test_haar(void **state)
{
    (void)state;
    for (int n = 1; n <= 128; n *= 2) {
        size_t nn = (size_t)n * n;
        float *a = malloc(nn * sizeof(float)), *b = malloc(nn * sizeof(float)), *a0 = malloc(nn * sizeof(float));
        double dot0 = 0, dot1 = 0, norm = 0;
        for (size_t i = 0; i < nn; ++i) {
            a[i] = a0[i] = frand() - 0.3f;
            b[i] = frand();
            dot0 += (double)a[i] * b[i];
            norm += (double)a[i] * a[i];
        }
        assert_int_equal(prt_haar2d(a, n, 0), PRT_OK);
        assert_int_equal(prt_haar2d(b, n, 0), PRT_OK);
        for (size_t i = 0; i < nn; ++i) dot1 += (double)a[i] * b[i];
        if (fabs(dot1 - dot0) > 1e-5 * (fabs(dot0) + norm)) fail_msg("n = %d: inner product %g became %g", n, dot0, dot1);
        assert_int_equal(prt_haar2d(a, n, 1), PRT_OK);
        for (size_t i = 0; i < nn; ++i)
            if (fabsf(a[i] - a0[i]) > 1e-5f) fail_msg("n = %d: inverse differs at %zu: %g vs %g", n, i, a[i], a0[i]);
        free(a); free(b); free(a0);
    }
    /* Gram matrix of the 64 basis functions of an 8 x 8 image. */
    float basis[64][64];
    for (int i = 0; i < 64; ++i) {
        memset(basis[i], 0, sizeof basis[i]);
        basis[i][i] = 1;
        assert_int_equal(prt_haar2d(basis[i], 8, 1), PRT_OK);
    }
    for (int i = 0; i < 64; ++i)
        for (int j = 0; j < 64; ++j) {
            double d = 0;
            for (int k = 0; k < 64; ++k) d += (double)basis[i][k] * basis[j][k];
            assert_true(fabs(d - (i == j)) < 1e-6);
        }
    float img[9] = {0};
    assert_int_equal(prt_haar2d(img, 3, 0), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_haar2d(img, 256, 0), PRT_ERR_INVALID_ARG);
}

/* Black with a bright disc of angular radius `radius_deg` around dir: a small area light. */
static prt_envmap *disc_env(const float dir[3], float radius_deg, float radiance, int width)
{
    prt_image img = {width, width / 2, calloc((size_t)width * width / 2 * 3, sizeof(float))};
    const double cr = cos(radius_deg * M_PI / 180.0);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < width; ++x) {
            double th = M_PI * (y + 0.5) / img.height, ph = 2 * M_PI * ((x + 0.5) / width - 0.5);
            double d[3] = {sin(th) * sin(ph), cos(th), -sin(th) * cos(ph)};
            if (d[0] * dir[0] + d[1] * dir[1] + d[2] * dir[2] >= cr)
                for (int c = 0; c < 3; ++c) img.rgb[((size_t)y * width + x) * 3 + c] = radiance;
        }
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    return env;
}

/* A random rotation (row-major), uniformly distributed: from a random unit quaternion. */
static void random_rotation(double R[9])
{
    double q[4], n = 0;
    for (int i = 0; i < 4; ++i) {
        double u1 = frand() + 1e-7, u2 = frand();
        q[i] = sqrt(-2 * log(u1)) * cos(2 * M_PI * u2);
        n += q[i] * q[i];
    }
    n = sqrt(n);
    double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                         2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
    memcpy(R, r, sizeof r);
}

/* The cube map's solid angles add up to the sphere; a constant environment has one scaling
 * coefficient per face and no details. */
static void test_light_cubemap(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    double total = 0;
    for (int i = 0; i < DIM; ++i) {
        float d[3], dw;
        prt_wavelet_texel(i, d, &dw);
        assert_true(fabsf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1) < 1e-5f);
        total += dw;
    }
    assert_true(fabs(total - 4 * M_PI) < 1e-4);
    prt_envmap *env = constant_env(2.0f);
    prt_wavelet_light *l = NULL;
    prt_wavelet_light_desc d = {0};
    d.coefficients = DIM;
    d.bits = 32;
    assert_int_equal(prt_wavelet_light_create(ctx, env, &d, &l), PRT_OK);
    const float *cube = prt_wavelet_light_cubemap(l), *c = prt_wavelet_light_coeffs(l);
    for (int i = 0; i < DIM * 3; ++i) assert_true(fabsf(cube[i] - 2.0f) < 1e-5f);
    for (int i = 0; i < DIM; ++i) {
        float expect = i % 4096 == 0 ? 2.0f * 64 : 0.0f;   /* orthonormal scaling function: 1/64 */
        if (fabsf(c[i * 4] - expect) > 1e-3f) fail_msg("coefficient %d: %g, expected %g", i, c[i * 4], expect);
    }
    prt_wavelet_light_release(l);
    /* Rotated, the texels stay within 1e-3 of the constant. */
    for (int r = 0; r < 3; ++r) {
        random_rotation(d.rotation);
        assert_int_equal(prt_wavelet_light_create(ctx, env, &d, &l), PRT_OK);
        cube = prt_wavelet_light_cubemap(l);
        float lo = INFINITY, hi = 0;
        for (int i = 0; i < DIM * 3; ++i) { lo = fminf(lo, cube[i]); hi = fmaxf(hi, cube[i]); }
        if (lo < 2.0f * (1 - 1e-3f) || hi > 2.0f * (1 + 1e-3f)) fail_msg("rotated constant map: texels %g .. %g", lo, hi);
        prt_wavelet_light_release(l);
    }
    memset(d.rotation, 0, sizeof d.rotation);
    /* Bad descriptions fail clearly. */
    d.bits = 12;
    assert_int_equal(prt_wavelet_light_create(ctx, env, &d, &l), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "bits"));
    d.bits = 0;
    d.coefficients = DIM + 1;
    assert_int_equal(prt_wavelet_light_create(ctx, env, &d, &l), PRT_ERR_INVALID_ARG);
    prt_envmap_release(env);
    prt_context_release(ctx);
}

/* A black 1024 x 512 map with one pixel of radiance `radiance` at (px, py); its exact energy
 * (radiance times the pixel's solid angle) and the direction through its centre. */
static prt_envmap *one_pixel_env(int px, int py, float radiance, double *energy, double dir[3])
{
    const int w = 1024, h = 512;
    prt_image img = {w, h, calloc((size_t)w * h * 3, sizeof(float))};
    for (int c = 0; c < 3; ++c) img.rgb[((size_t)py * w + px) * 3 + c] = radiance;
    *energy = radiance * (2 * M_PI / w) * (cos(M_PI * py / h) - cos(M_PI * (py + 1) / h));
    double th = M_PI * (py + 0.5) / h, ph = 2 * M_PI * ((px + 0.5) / w - 0.5);
    dir[0] = sin(th) * sin(ph); dir[1] = cos(th); dir[2] = -sin(th) * cos(ph);
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    return env;
}

/* The lighting cube conserves a one-pixel sun's energy wherever it sits in the map (poles, seam,
 * anywhere) and under any rotation, to 0.5%, and keeps it sharp: all of it within 2.5 degrees
 * of where the sun now is. */
static void test_light_conserves_small_sources(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    const int spots[][2] = {{0, 0}, {1023, 0}, {517, 0}, {300, 1}, {77, 2}, {512, 5}, {900, 20}, {0, 100}, {1023, 200}, {896, 155}, {896, 256}, {768, 128},
                            {512, 255}, {511, 256}, {128, 311}, {640, 400}, {3, 491}, {999, 509}, {256, 510}, {1023, 511}, {600, 511}};
    const int nspots = (int)(sizeof spots / sizeof spots[0]), rotations = 3;
    double lo = INFINITY, hi = 0, worst_spread = 0;
    int bad = 0;
    for (int s = 0; s < nspots; ++s) {
        double energy, sun[3];
        prt_envmap *env = one_pixel_env(spots[s][0], spots[s][1], 1000.0f, &energy, sun);
        for (int r = 0; r <= rotations; ++r) {
            prt_wavelet_light_desc ld = {.coefficients = DIM, .bits = 32};
            double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            if (r) { random_rotation(R); memcpy(ld.rotation, R, sizeof R); }
            const double at[3] = {R[0] * sun[0] + R[1] * sun[1] + R[2] * sun[2], R[3] * sun[0] + R[4] * sun[1] + R[5] * sun[2],
                                  R[6] * sun[0] + R[7] * sun[1] + R[8] * sun[2]};
            prt_wavelet_light *l = NULL;
            assert_int_equal(prt_wavelet_light_create(ctx, env, &ld, &l), PRT_OK);
            const float *cube = prt_wavelet_light_cubemap(l);
            double e = 0, far = 0;
            for (int i = 0; i < DIM; ++i) {
                float d[3], dw;
                prt_wavelet_texel(i, d, &dw);
                e += (double)cube[i * 3 + 1] * dw;
                double cosang = d[0] * at[0] + d[1] * at[1] + d[2] * at[2];
                if (cosang < cos(2.5 * M_PI / 180)) far += (double)cube[i * 3 + 1] * dw;
                else worst_spread = fmax(worst_spread, cube[i * 3 + 1] > 0 ? acos(fmin(cosang, 1.0)) * 180 / M_PI : 0);
            }
            lo = fmin(lo, e / energy);
            hi = fmax(hi, e / energy);
            if (fabs(e / energy - 1) > 0.005 || far > 1e-4 * energy) {
                print_message("sun at pixel (%d, %d), rotation %d: %.2f%% of its energy, %.3f%% beyond 2.5 degrees\n", spots[s][0], spots[s][1], r,
                              100 * e / energy, 100 * far / energy);
                bad++;
            }
            prt_wavelet_light_release(l);
        }
        prt_envmap_release(env);
    }
    print_message("one-pixel sun: %.2f%% to %.2f%% of its energy, lit texels within %.2f degrees\n", 100 * lo, 100 * hi, worst_spread);
    assert_int_equal(bad, 0);
    prt_context_release(ctx);
}

/* Mean exit radiance over a convex Lambertian sphere, each vertex weighted by a third of the area
 * of its triangles: proportional to the light's energy, so rotating the light must not change it. */
static double sphere_mean(const test_mesh *m, const float *rgb)
{
    double sum = 0, area = 0;
    for (size_t t = 0; t < m->nt; ++t) {
        const uint32_t *tri = m->idx + t * 3;
        const float *a = m->pos + tri[0] * 3, *b = m->pos + tri[1] * 3, *c = m->pos + tri[2] * 3;
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2], z = u[0] * v[1] - u[1] * v[0];
        double ar = 0.5 * sqrt(x * x + y * y + z * z);
        for (int k = 0; k < 3; ++k) sum += ar / 3 * rgb[tri[k] * 3 + 1];
        area += ar;
    }
    return sum / area;
}

/* Dragging a sunny probe around a convex sphere keeps its mean brightness (SH does to 0.1%): a
 * one-pixel-wide synthetic sun with every transport coefficient kept (128 coefficients alone vary
 * the mean by about 25% for a sun this small: the truncated transport, not the light), and
 * venice_sunset_1k.hdr with the default transport when present. */
static void test_rotation_keeps_mean(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 12, 24);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    prt_transfer *t[2] = {NULL, NULL};
    assert_int_equal(prt_bake_wavelet(ctx, s, &(prt_wavelet_bake_desc){.supersample = 1, .coefficients = DIM, .bits = 16}, &t[0]), PRT_OK);
    assert_int_equal(prt_bake_wavelet(ctx, s, &(prt_wavelet_bake_desc){.supersample = 1}, &t[1]), PRT_OK);
    const size_t nv = prt_transfer_vertex_count(t[0]);
    assert_int_equal(nv, m.nv);
    float *k = malloc(nv * 3 * sizeof(float)), *rgb = malloc(nv * 3 * sizeof(float));
    prt_envmap *envs[2] = {disc_env((float[3]){0.48f, 0.6f, -0.64f}, 0.25f, 20000.0f, 1024), NULL};
    char path[600];
    const char *data = shared_data_dir();
    if (data) {
        snprintf(path, sizeof path, "%s/envmaps/polyhaven_1k/venice_sunset_1k.hdr", data);
        if (prt_envmap_load(path, PRT_ENV_AUTO, &envs[1])) envs[1] = NULL;
    }
    if (!envs[1]) print_message("venice_sunset_1k.hdr not found: synthetic sun only\n");
    double worst = 0;
    for (int e = 0; e < 2; ++e) {
        if (!envs[e]) continue;
        double lo = INFINITY, hi = 0;
        for (int r = 0; r < 6; ++r) {
            prt_wavelet_light_desc ld = {0};
            if (r) random_rotation(ld.rotation);
            prt_wavelet_light *l = NULL;
            assert_int_equal(prt_wavelet_light_create(ctx, envs[e], &ld, &l), PRT_OK);
            assert_int_equal(prt_relight_wavelet(ctx, t[e], l, k), PRT_OK);
            assert_int_equal(prt_wavelet_shade(ctx, t[e], k, NULL, rgb), PRT_OK);
            double mean = sphere_mean(&m, rgb);
            lo = fmin(lo, mean);
            hi = fmax(hi, mean);
            prt_wavelet_light_release(l);
        }
        print_message("%s: sphere mean %.4f .. %.4f under rotations (%.2f%%)\n", e ? "venice sunset" : "synthetic sun", lo, hi, 100 * (hi / lo - 1));
        worst = fmax(worst, hi / lo - 1);
        prt_envmap_release(envs[e]);
    }
    if (worst > 0.01) fail_msg("the mean radiance varies by %.2f%% under rotation", 100 * worst);
    free(k); free(rgb);
    prt_transfer_release(t[0]);
    prt_transfer_release(t[1]);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The lit pixels of a lat-long map: direction through the centre and radiance (green) x exact
 * solid angle, [count][4]. Exact irradiance is then a sum over them (cosine at the pixel centre:
 * fine for sources a few pixels wide). */
static int lit_pixels(const prt_envmap *env, double **out)
{
    const prt_image *img = prt_envmap_image(env);
    const int w = img->width, h = img->height;
    int count = 0;
    double *p = NULL;
    for (int pass = 0; pass < 2; ++pass) {
        count = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float L = img->rgb[((size_t)y * w + x) * 3 + 1];
                if (L == 0) continue;
                if (pass) {
                    const double th = M_PI * (y + 0.5) / h, ph = 2 * M_PI * ((x + 0.5) / w - 0.5);
                    double *o = p + (size_t)count * 4;
                    o[0] = sin(th) * sin(ph); o[1] = cos(th); o[2] = -sin(th) * cos(ph);
                    o[3] = L * 2 * M_PI / w * (cos(M_PI * y / h) - cos(M_PI * (y + 1) / h));
                }
                count++;
            }
        if (!pass) p = malloc((size_t)(count ? count : 1) * 4 * sizeof(double));
    }
    *out = p;
    return count;
}

static double irradiance(const double *lit, int count, const double n[3])
{
    double e = 0;
    for (int i = 0; i < count; ++i) {
        const double *q = lit + (size_t)i * 4, c = q[0] * n[0] + q[1] * n[1] + q[2] * n[2];
        if (c > 0) e += q[3] * c;
    }
    return e;
}

/* Sun-lit vertices of a convex Lambertian sphere under a small sun (1 degree across), every
 * transport coefficient kept: as bright as the exact integral of the map at each vertex normal,
 * on average to 0.25% and each to 1% rms. (The lighting cube used to give suns near the poles up
 * to 1.5% too much energy; the transport adds no bias of its own.) */
static void test_sunlit_brightness(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 12, 24);
    const float rho = 0.5f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_wavelet(ctx, s, &(prt_wavelet_bake_desc){.coefficients = DIM, .bits = 16, .supersample = 2}, &t), PRT_OK);
    assert_int_equal(prt_transfer_vertex_count(t), m.nv);
    float *k = malloc(m.nv * 3 * sizeof(float)), *rgb = malloc(m.nv * 3 * sizeof(float));
    double bias = 0, rms = 0;
    int count = 0;
    for (int i = 0; i < 5; ++i) {
        const double el = (20 + 17 * i) * M_PI / 180, az = 0.3 + 0.7 * i;
        const float dir[3] = {(float)(cos(el) * sin(az)), (float)sin(el), (float)(-cos(el) * cos(az))};
        prt_envmap *env = disc_env(dir, 0.5f, 1000.0f, 1024);
        double *lit = NULL;
        const int nlit = lit_pixels(env, &lit);
        prt_wavelet_light *l = NULL;
        assert_int_equal(prt_wavelet_light_create(ctx, env, &(prt_wavelet_light_desc){.coefficients = DIM, .bits = 32}, &l), PRT_OK);
        assert_int_equal(prt_relight_wavelet(ctx, t, l, k), PRT_OK);
        assert_int_equal(prt_wavelet_shade(ctx, t, k, NULL, rgb), PRT_OK);
        for (size_t v = 0; v < m.nv; ++v) {
            const double n[3] = {m.nrm[v * 3], m.nrm[v * 3 + 1], m.nrm[v * 3 + 2]};
            if (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2] < 0.5) continue;
            const double e = rgb[v * 3 + 1] / (rho / M_PI * irradiance(lit, nlit, n)) - 1;
            bias += e;
            rms += e * e;
            count++;
        }
        free(lit);
        prt_wavelet_light_release(l);
        prt_envmap_release(env);
    }
    bias /= count;
    rms = sqrt(rms / count);
    print_message("sun-lit vertices, every coefficient kept: %+.3f%% on average, %.2f%% rms\n", 100 * bias, 100 * rms);
    assert_true(fabs(bias) < 0.0025);
    assert_true(rms < 0.01);
    free(k); free(rgb);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* With every coefficient kept, relighting equals the cube map quadrature of the rendering
 * equation, sum_j L_j rho/pi max(n.w_j, 0) dw_j, for an unoccluded plane; with a constant sky it
 * is rho L (the white furnace), to the quadrature's accuracy. */
static void test_keep_all_reproduces_integral(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 2);   /* facing +y */
    const float rho = 0.6f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    prt_wavelet_bake_desc bd = {0};
    bd.coefficients = DIM;
    bd.bits = 16;
    bd.supersample = 1;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_wavelet(ctx, s, &bd, &t), PRT_OK);
    prt_sky_desc sky = {0};
    prt_envmap *envs[2] = {NULL, constant_env(1.5f)};
    assert_int_equal(prt_sky_create(&sky, &envs[0]), PRT_OK);
    for (int e = 0; e < 2; ++e) {
        prt_wavelet_light *l = NULL;
        prt_wavelet_light_desc ld = {0};
        ld.coefficients = DIM;
        ld.bits = 32;
        assert_int_equal(prt_wavelet_light_create(ctx, envs[e], &ld, &l), PRT_OK);
        const float *cube = prt_wavelet_light_cubemap(l);
        double expect[3] = {0, 0, 0};
        for (int i = 0; i < DIM; ++i) {
            float d[3], dw;
            prt_wavelet_texel(i, d, &dw);
            if (d[1] > 0)
                for (int c = 0; c < 3; ++c) expect[c] += rho / M_PI * cube[i * 3 + c] * d[1] * dw;
        }
        if (e == 1)
            for (int c = 0; c < 3; ++c) assert_true(fabs(expect[c] - rho * 1.5) < 2e-3 * rho * 1.5);
        float kvec[9 * 3], rgb[9 * 3];
        assert_int_equal(prt_relight_wavelet(ctx, t, l, kvec), PRT_OK);
        assert_int_equal(prt_wavelet_shade(ctx, t, kvec, (float[3]){0, 5, 0}, rgb), PRT_OK);
        /* The only difference left is the 16-bit rounding of the transport: at most half a step
         * per coefficient, times the light's coefficient there. */
        const float *L = prt_wavelet_light_coeffs(l);
        int *idx = malloc(DIM * sizeof(int));
        float *val = malloc(DIM * 3 * sizeof(float));
        for (int v = 0; v < 9; ++v) {
            assert_int_equal(prt_transfer_wavelet_vector(t, (size_t)v, 0, idx, val), DIM);
            for (int c = 0; c < 3; ++c) {
                float mx = 0;
                double bound = 0;
                for (int i = 0; i < DIM; ++i) mx = fmaxf(mx, fabsf(val[i * 3 + c]));
                for (int i = 0; i < DIM; ++i) bound += 0.5 * mx / 32767.0 * fabs(L[(size_t)idx[i] * 4 + c]);
                bound *= rho / M_PI;
                if (fabs(rgb[v * 3 + c] - expect[c]) > bound + 1e-5 * expect[c])
                    fail_msg("env %d vertex %d channel %d: %g, expected %g (16-bit bound %g)", e, v, c, rgb[v * 3 + c], expect[c], bound);
                assert_true(bound < 2e-3 * expect[c]);
            }
        }
        free(idx);
        free(val);
        prt_wavelet_light_release(l);
        prt_envmap_release(envs[e]);
    }
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* With K = the full rank the factorization reproduces the sampled BRDF at the sample points,
 * for every model and both parameterizations; a Lambertian BRDF is rank one. */
static void test_svd_full_rank(void **state)
{
    (void)state;
    const char *specs[] = {"phong:20:0.5:0.3", "blinn:40:0.6:0.2", "lafortune:clay", "ashikhmin:10:100:0.75:0.5"};
    for (int p = 0; p < 2; ++p)
        for (int i = 0; i < 4; ++i) {
            prt_brdf b;
            assert_int_equal(prt_brdf_parse(specs[i], &b), PRT_OK);
            const int res = 4, full = p == 0 ? 12 : 16;   /* grid: 12 cells lie inside the disk */
            prt_brdf_factor_desc d = {full, res, p == 0 ? PRT_BRDF_PARAM_GRID : PRT_BRDF_PARAM_POLAR};
            prt_brdf_factors *f = NULL;
            assert_int_equal(prt_brdf_factor(&b, &d, &f), PRT_OK);
            double maxerr = 0, maxf = 0;
            for (int a = 0; a < res * res; ++a)
                for (int c = 0; c < res * res; ++c) {
                    float wi[3], wo[3], ref[3], got[3];
                    double ua = (a % res + 0.5) / res, va = (a / res + 0.5) / res, uc = (c % res + 0.5) / res, vc = (c / res + 0.5) / res;
                    if (p == 0) {
                        wi[0] = (float)(2 * ua - 1); wi[1] = (float)(2 * va - 1);
                        wo[0] = (float)(2 * uc - 1); wo[1] = (float)(2 * vc - 1);
                        if (wi[0] * wi[0] + wi[1] * wi[1] >= 1 || wo[0] * wo[0] + wo[1] * wo[1] >= 1) continue;
                        wi[2] = sqrtf(1 - wi[0] * wi[0] - wi[1] * wi[1]);
                        wo[2] = sqrtf(1 - wo[0] * wo[0] - wo[1] * wo[1]);
                    } else {
                        double ca = 1 - va * va, cc = 1 - vc * vc, sa = sqrt(1 - ca * ca), sc = sqrt(1 - cc * cc);
                        wi[0] = (float)(sa * cos(2 * M_PI * ua)); wi[1] = (float)(sa * sin(2 * M_PI * ua)); wi[2] = (float)ca;
                        wo[0] = (float)(sc * cos(2 * M_PI * uc)); wo[1] = (float)(sc * sin(2 * M_PI * uc)); wo[2] = (float)cc;
                    }
                    prt_brdf_eval(&b, wi, wo, ref);
                    prt_brdf_factors_eval(f, full, wi, wo, got);
                    for (int ch = 0; ch < 3; ++ch) {
                        maxerr = fmax(maxerr, fabs(ref[ch] - got[ch]));
                        maxf = fmax(maxf, fabs(ref[ch]));
                    }
                }
            if (maxerr > 1e-4 * maxf) fail_msg("%s (%s): full rank misses the samples by %g of %g", specs[i], p ? "polar" : "grid", maxerr, maxf);
            /* The singular values decrease. */
            for (int k = 1; k < full; ++k) assert_true(prt_brdf_factors_sigma(f, 0, k) <= prt_brdf_factors_sigma(f, 0, k - 1) * (1 + 1e-5f));
            prt_brdf_factors_release(f);
            /* At a useful resolution more terms fit better between the samples too, in the
             * weighted norm the SVD minimizes (Ashikhmin-Shirley's grazing spikes need maps finer
             * than this test affords). */
            if (i == 3) continue;
            d = (prt_brdf_factor_desc){8, 24, p == 0 ? PRT_BRDF_PARAM_GRID : PRT_BRDF_PARAM_POLAR};
            assert_int_equal(prt_brdf_factor(&b, &d, &f), PRT_OK);
            double rms[16], rel[16];
            assert_int_equal(prt_brdf_factors_error(f, &b, 20000, rms, rel), PRT_OK);
            for (int k = 1; k < 8; ++k)
                if (rel[k] > rel[k - 1] * 1.02) fail_msg("%s (%s): error %g with %d terms, %g with %d", specs[i], p ? "polar" : "grid", rel[k], k + 1, rel[k - 1], k);
            assert_true(rel[7] < rel[0]);
            prt_brdf_factors_release(f);
        }
    prt_brdf lam;
    assert_int_equal(prt_brdf_parse("lambert:0.7", &lam), PRT_OK);
    prt_brdf_factors *f = NULL;
    assert_int_equal(prt_brdf_factor(&lam, &(prt_brdf_factor_desc){1, 0, 0}, &f), PRT_OK);
    double rms[16], rel[16];
    assert_int_equal(prt_brdf_factors_error(f, &lam, 20000, rms, rel), PRT_OK);
    assert_true(rel[0] < 1e-5);
    assert_true(prt_brdf_factors_sigma(f, 0, 1) < 1e-4f * prt_brdf_factors_sigma(f, 0, 0));
    prt_brdf_factors_release(f);
    /* Bad requests. */
    assert_int_equal(prt_brdf_factor(&lam, &(prt_brdf_factor_desc){17, 0, 0}, &f), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_brdf_factor(&lam, &(prt_brdf_factor_desc){4, 200, 0}, &f), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_brdf_factor(&lam, &(prt_brdf_factor_desc){13, 4, 0}, &f), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "finer"));
}

static double rel_rms(const float *a, const float *b, size_t n)
{
    double e = 0, r = 0;
    for (size_t i = 0; i < n; ++i) {
        e += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
        r += (double)b[i] * b[i];
    }
    return sqrt(e / r);
}

static float *wavelet_vertices(prt_context *ctx, const prt_transfer *t, const prt_envmap *env, const float eye[3])
{
    prt_wavelet_info wi;
    assert_true(prt_transfer_wavelet_info(t, &wi));
    size_t nv = prt_transfer_vertex_count(t);
    prt_wavelet_light *l = NULL;
    assert_int_equal(prt_wavelet_light_create(ctx, env, NULL, &l), PRT_OK);
    float *k = malloc(nv * (size_t)wi.terms * 3 * sizeof(float)), *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relight_wavelet(ctx, t, l, k), PRT_OK);
    assert_int_equal(prt_wavelet_shade(ctx, t, k, eye, rgb), PRT_OK);
    free(k);
    prt_wavelet_light_release(l);
    return rgb;
}

/* A convex diffuse sphere: under a smooth environment the wavelet result (128 coefficients,
 * 8 bits) matches SH PRT; under a sharp one (sky with sun) both match the path tracer. */
static void test_convex_diffuse(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 10, 20);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    prt_transfer *tw = NULL, *ts = NULL;
    assert_int_equal(prt_bake_wavelet(ctx, s, &(prt_wavelet_bake_desc){.supersample = 1}, &tw), PRT_OK);
    prt_bake_desc sd = {0};
    sd.order = 6;
    sd.samples = 4096;
    sd.kinds = PRT_TRANSFER_SHADOWED;
    assert_int_equal(prt_bake_sh(ctx, s, &sd, &ts), PRT_OK);
    const size_t nv = m.nv;
    const float eye[3] = {0, 0, 10};
    prt_envmap *smooth = band_limited_env(256);
    float *w = wavelet_vertices(ctx, tw, smooth, eye), *sh = malloc(nv * 3 * sizeof(float));
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(smooth, 6, &L), PRT_OK);
    assert_int_equal(prt_relight_sh(ctx, ts, PRT_TRANSFER_SHADOWED, &L, sh), PRT_OK);
    double e = rel_rms(w, sh, nv * 3);
    print_message("convex sphere, smooth light: wavelet vs SH order 6: %.2f%% relative RMS\n", 100 * e);
    assert_true(e < 0.02);
    free(w);

    prt_sky_desc sky = {0};
    prt_envmap *sharp = NULL;
    assert_int_equal(prt_sky_create(&sky, &sharp), PRT_OK);
    w = wavelet_vertices(ctx, tw, sharp, eye);
    prt_reference_desc rd = {0};
    rd.samples = 2048;
    prt_reference_vertices r;
    assert_int_equal(prt_reference_trace_vertices(ctx, s, sharp, &rd, &r), PRT_OK);
    double err = rel_rms(w, r.radiance, nv * 3), noise = 0, ref2 = 0;
    for (size_t i = 0; i < nv * 3; ++i) { noise += (double)r.std_error[i] * r.std_error[i]; ref2 += (double)r.radiance[i] * r.radiance[i]; }
    noise = sqrt(noise / ref2);
    assert_int_equal(prt_envmap_project_sh(sharp, 6, &L), PRT_OK);
    assert_int_equal(prt_relight_sh(ctx, ts, PRT_TRANSFER_SHADOWED, &L, sh), PRT_OK);
    double esh = rel_rms(sh, r.radiance, nv * 3);
    print_message("convex sphere, sky with sun: wavelet %.2f%%, SH order 6 %.2f%% vs path tracer (noise %.2f%%)\n", 100 * err, 100 * esh, 100 * noise);
    /* Diffuse transfer is band-limited by the cosine, so on a convex object SH is as good: both
     * must agree with the path tracer to 3% beyond its noise. */
    assert_true(err < 0.03 + 2 * noise);
    assert_true(esh < 0.03 + 2 * noise);
    free(w);
    free(sh);
    prt_reference_vertices_free(&r);
    prt_envmap_release(smooth);
    prt_envmap_release(sharp);
    prt_transfer_release(tw);
    prt_transfer_release(ts);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A glossy convex sphere under constant unit radiance: each vertex reflects its directional
 * albedo towards the eye, integral f(wi, wo) cos dwi, which the test integrates from the analytic
 * BRDF. The separable approximation with K terms is what limits the match. */
static void test_glossy_furnace(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 8, 16);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_brdf b;
    assert_int_equal(prt_brdf_parse("phong:6:0.4:0.4", &b), PRT_OK);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_wavelet(ctx, s, &(prt_wavelet_bake_desc){.supersample = 1, .brdf = &b, .terms = 8, .bits = 16}, &t), PRT_OK);
    prt_envmap *env = constant_env(1.0f);
    const float eye[3] = {0.3f, 0.5f, 20.0f};
    float *got = wavelet_vertices(ctx, t, env, eye);
    const float *N = prt_transfer_normals(t), *P = prt_transfer_positions(t);
    double e2 = 0, r2 = 0;
    for (size_t v = 0; v < prt_transfer_vertex_count(t); ++v) {
        const float *n = N + v * 3;
        float wo[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]};
        float l = sqrtf(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
        for (int i = 0; i < 3; ++i) wo[i] /= l;
        float cwo = wo[0] * n[0] + wo[1] * n[1] + wo[2] * n[2];
        if (cwo < 0.2f) continue;   /* silhouettes: the view maps' rim */
        /* Local frame with z = n; the BRDF is isotropic, so any tangent works. */
        float tx[3];
        tangent_of(n, tx);
        float ty[3] = {n[1] * tx[2] - n[2] * tx[1], n[2] * tx[0] - n[0] * tx[2], n[0] * tx[1] - n[1] * tx[0]};
        float lo[3] = {wo[0] * tx[0] + wo[1] * tx[1] + wo[2] * tx[2], wo[0] * ty[0] + wo[1] * ty[1] + wo[2] * ty[2], cwo};
        double expect = 0;
        for (int i = 0; i < DIM; ++i) {
            float dir[3], dw, f[3];
            prt_wavelet_texel(i, dir, &dw);
            float li[3] = {dir[0] * tx[0] + dir[1] * tx[1] + dir[2] * tx[2], dir[0] * ty[0] + dir[1] * ty[1] + dir[2] * ty[2],
                           dir[0] * n[0] + dir[1] * n[1] + dir[2] * n[2]};
            if (li[2] <= 0) continue;
            prt_brdf_eval(&b, li, lo, f);
            expect += f[0] * li[2] * dw;
        }
        e2 += (got[v * 3] - expect) * (got[v * 3] - expect);
        r2 += expect * expect;
    }
    double rel = sqrt(e2 / r2);
    print_message("glossy furnace, phong 6, K = 8: %.2f%% relative RMS against the BRDF's directional albedo\n", 100 * rel);
    assert_true(rel < 0.05);
    free(got);
    prt_envmap_release(env);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Width (in scene units, along x) over which radiance along a row of floor vertices rises from
 * 10% to 90% of its lit level. */
static double edge_width(const float *pos, const float *rgb, const size_t *row, int count)
{
    float lo = INFINITY, hi = 0;
    for (int i = 0; i < count; ++i) { lo = fminf(lo, rgb[row[i] * 3 + 1]); hi = fmaxf(hi, rgb[row[i] * 3 + 1]); }
    double x10 = NAN, x90 = NAN;
    for (int i = 0; i < count; ++i) {
        float f = (rgb[row[i] * 3 + 1] - lo) / (hi - lo);
        if (isnan(x10) && f >= 0.1f) x10 = pos[row[i] * 3];
        if (isnan(x90) && f >= 0.9f) x90 = pos[row[i] * 3];
    }
    return x90 - x10;
}

/* A small light and an occluder with a straight edge: the wavelet shadow edge is as sharp as the
 * geometry allows (penumbra plus vertex spacing); order-5 SH smears it far wider. */
static void test_sharp_shadow(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    const int cells = 100;
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, cells);   /* floor, +y */
    /* Occluder: a double-sided card over x < 0 at height h (two quads back to back). */
    const float h = 0.3f;
    tm_quad(&m, (float[3]){-3, h, -3}, (float[3]){3, 0, 0}, (float[3]){0, 0, 6}, 1);
    tm_quad(&m, (float[3]){-3, h, 3}, (float[3]){3, 0, 0}, (float[3]){0, 0, -6}, 1);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    const float radius = 1.0f;   /* degrees: the light subtends 2 degrees, straight above */
    prt_envmap *env = disc_env((float[3]){0, 1, 0}, radius, 2000.0f, 1024);
    prt_transfer *tw = NULL, *ts = NULL;
    assert_int_equal(prt_bake_wavelet(ctx, s, &(prt_wavelet_bake_desc){.supersample = 2}, &tw), PRT_OK);
    prt_bake_desc sd = {0};
    sd.order = 5;
    sd.samples = 4096;
    sd.kinds = PRT_TRANSFER_SHADOWED;
    assert_int_equal(prt_bake_sh(ctx, s, &sd, &ts), PRT_OK);
    float *w = wavelet_vertices(ctx, tw, env, (float[3]){0, 5, 0}), *sh = malloc(prt_transfer_vertex_count(ts) * 3 * sizeof(float));
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 5, &L), PRT_OK);
    assert_int_equal(prt_relight_sh(ctx, ts, PRT_TRANSFER_SHADOWED, &L, sh), PRT_OK);
    /* The floor row through z = 0, x from -0.5 to 0.5. */
    size_t row[cells + 1];
    int count = 0;
    for (int i = 0; i <= cells; ++i) {
        float x = -1 + 2.0f * i / cells;
        if (x < -0.5f || x > 0.5f) continue;
        row[count++] = nearest_vertex(m.pos, (size_t)(cells + 1) * (cells + 1), (float[3]){x, 0, 0});
    }
    const double spacing = 2.0 / cells, penumbra = 2 * h * tan(radius * M_PI / 180), bound = penumbra + 2 * spacing;
    double ww = edge_width(m.pos, w, row, count), ws = edge_width(m.pos, sh, row, count);
    print_message("shadow edge 10-90%%: wavelet %.3f, SH order 5 %.3f (penumbra %.3f + 2 vertex spacings = %.3f)\n", ww, ws, penumbra, bound);
    assert_true(ww <= bound + 1e-6);
    assert_true(ws > 3 * bound);
    free(w);
    free(sh);
    prt_envmap_release(env);
    prt_transfer_release(tw);
    prt_transfer_release(ts);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* 8-bit coefficients stay within half a quantization step of the 16-bit ones (the same
 * coefficients are kept), and relit K-vectors within the bound that implies. */
static void test_quantization_bound(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 1.2f, 0}, 0.5f, 8, 16);
    tm_quad(&m, (float[3]){-2, 0, 2}, (float[3]){4, 0, 0}, (float[3]){0, 0, -4}, 6);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    prt_brdf b;
    assert_int_equal(prt_brdf_parse("phong:10:0.4:0.4", &b), PRT_OK);
    prt_transfer *t8 = NULL, *t16 = NULL;
    prt_wavelet_bake_desc d = {.supersample = 1, .brdf = &b, .terms = 2, .brdf_resolution = 16};
    assert_int_equal(prt_bake_wavelet(ctx, s, &d, &t8), PRT_OK);
    d.bits = 16;
    assert_int_equal(prt_bake_wavelet(ctx, s, &d, &t16), PRT_OK);
    prt_wavelet_info wi;
    prt_transfer_wavelet_info(t8, &wi);
    assert_int_equal(wi.bits, 8);
    const int n = wi.coefficients;
    int *i8 = malloc(n * sizeof(int)), *i16 = malloc(n * sizeof(int));
    float *v8 = malloc(n * 3 * sizeof(float)), *v16 = malloc(n * 3 * sizeof(float));
    prt_sky_desc sky = {0};
    prt_envmap *env = NULL;
    assert_int_equal(prt_sky_create(&sky, &env), PRT_OK);
    prt_wavelet_light *l = NULL;
    assert_int_equal(prt_wavelet_light_create(ctx, env, NULL, &l), PRT_OK);
    const float *L = prt_wavelet_light_coeffs(l);
    const size_t nv = prt_transfer_vertex_count(t8);
    float *k8 = malloc(nv * 2 * 3 * sizeof(float)), *k16 = malloc(nv * 2 * 3 * sizeof(float));
    assert_int_equal(prt_relight_wavelet(ctx, t8, l, k8), PRT_OK);
    assert_int_equal(prt_relight_wavelet(ctx, t16, l, k16), PRT_OK);
    for (size_t v = 0; v < nv; ++v)
        for (int k = 0; k < 2; ++k) {
            assert_int_equal(prt_transfer_wavelet_vector(t8, v, k, i8, v8), n);
            assert_int_equal(prt_transfer_wavelet_vector(t16, v, k, i16, v16), n);
            for (int c = 0; c < 3; ++c) {
                float mx = 0;
                for (int i = 0; i < n; ++i) mx = fmaxf(mx, fabsf(v16[i * 3 + c]));
                const float step8 = mx / 127.0f, step16 = mx / 32767.0f;
                double bound = 0;
                for (int i = 0; i < n; ++i) {
                    assert_int_equal(i8[i], i16[i]);
                    if (fabsf(v8[i * 3 + c] - v16[i * 3 + c]) > 0.5f * (step8 + 2 * step16) * 1.001f + 1e-12f)
                        fail_msg("vertex %zu term %d coefficient %d: 8-bit %g vs %g (step %g)", v, k, i, v8[i * 3 + c], v16[i * 3 + c], step8);
                    bound += 0.5 * (step8 + 2 * step16) * fabs(L[(size_t)i8[i] * 4 + c]);
                }
                double diff = fabs(k8[(v * 2 + k) * 3 + c] - k16[(v * 2 + k) * 3 + c]);
                if (diff > bound * 1.001 + 1e-6) fail_msg("vertex %zu term %d: K-vectors differ by %g, bound %g", v, k, diff, bound);
            }
        }
    free(i8); free(i16); free(v8); free(v16); free(k8); free(k16);
    prt_wavelet_light_release(l);
    prt_envmap_release(env);
    prt_transfer_release(t8);
    prt_transfer_release(t16);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Interreflection in a pit: one wavelet bounce pass agrees with one SH bounce (diffuse, the
 * light that bounced is low-frequency) and adds light; bakes are identical for any thread count. */
static void test_interreflection(void **state)
{
    (void)state;
    prt_context *ctx1 = test_context(1), *ctx = test_context(2);
    test_mesh m = {0};
    tm_pit(&m, 6);
    prt_scene *s = tm_scene(ctx, &m, 0.8f);
    prt_transfer *t0 = NULL, *t1 = NULL, *t1b = NULL, *ts = NULL;
    prt_wavelet_bake_desc d = {.supersample = 1, .gather_resolution = 16};
    assert_int_equal(prt_bake_wavelet(ctx, s, &d, &t0), PRT_OK);
    d.bounces = 1;
    assert_int_equal(prt_bake_wavelet(ctx, s, &d, &t1), PRT_OK);
    assert_int_equal(prt_bake_wavelet(ctx1, s, &d, &t1b), PRT_OK);
    prt_bake_desc sd = {0};
    sd.order = 6;
    sd.samples = 4096;
    sd.bounces = 1;
    sd.kinds = PRT_TRANSFER_INTERREFLECTED;
    assert_int_equal(prt_bake_sh(ctx, s, &sd, &ts), PRT_OK);
    prt_envmap *env = band_limited_env(256);
    const float eye[3] = {0, 3, 0};
    const size_t nv = m.nv;
    float *w0 = wavelet_vertices(ctx, t0, env, eye), *w1 = wavelet_vertices(ctx, t1, env, eye), *w1b = wavelet_vertices(ctx, t1b, env, eye);
    float *sh = malloc(nv * 3 * sizeof(float));
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(env, 6, &L), PRT_OK);
    assert_int_equal(prt_relight_sh(ctx, ts, PRT_TRANSFER_INTERREFLECTED, &L, sh), PRT_OK);
    assert_memory_equal(w1, w1b, nv * 3 * sizeof(float));
    double sum0 = 0, sum1 = 0;
    for (size_t i = 0; i < nv * 3; ++i) { sum0 += w0[i]; sum1 += w1[i]; }
    double e = rel_rms(w1, sh, nv * 3);
    print_message("pit, one bounce: wavelet vs SH %.2f%% relative RMS; the bounce adds %.1f%%\n", 100 * e, 100 * (sum1 / sum0 - 1));
    assert_true(sum1 > 1.1 * sum0);
    assert_true(e < 0.05);
    free(w0); free(w1); free(w1b); free(sh);
    prt_envmap_release(env);
    prt_transfer_release(t0); prt_transfer_release(t1); prt_transfer_release(t1b); prt_transfer_release(ts);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
    prt_context_release(ctx1);
}

/* Both bounce paths of eq. 8 at work between a floor and a wall: a glossy wall lights a diffuse
 * floor (glossy-to-diffuse), a diffuse wall lights a glossy floor (diffuse-to-glossy); a black wall
 * adds nothing. */
static void test_glossy_bounce_paths(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 6);    /* floor, +y */
    const size_t floor_nv = m.nv;
    tm_quad(&m, (float[3]){-1, 0, -1}, (float[3]){2, 0, 0}, (float[3]){0, 2, 0}, 6);    /* wall at z = -1, facing +z */
    prt_brdf glossy, lambert, black;
    assert_int_equal(prt_brdf_parse("phong:8:0.7:0.1", &glossy), PRT_OK);
    assert_int_equal(prt_brdf_parse("lambert:0.8", &lambert), PRT_OK);
    assert_int_equal(prt_brdf_parse("lambert:0", &black), PRT_OK);
    prt_envmap *env = band_limited_env(128);
    const float eye[3] = {0, 1.5f, 3};
    const prt_wavelet_bake_desc d = {.supersample = 1, .terms = 3, .brdf_resolution = 16, .bounces = 1, .gather_resolution = 16};
    /* [case]: 0 black wall, 1 Lambertian wall, 2 glossy wall (floor Lambertian); 3 black wall,
     * 4 Lambertian wall (floor glossy). Mean floor radiance. */
    double mean[5];
    for (int cse = 0; cse < 5; ++cse) {
        prt_scene *s = tm_scene(ctx, &m, 0.6f);
        const prt_brdf *wall = cse == 0 || cse == 3 ? &black : cse == 2 ? &glossy : &lambert;
        assert_int_equal(prt_scene_set_brdf(s, floor_nv, m.nv - floor_nv, wall), PRT_OK);
        if (cse >= 3) assert_int_equal(prt_scene_set_brdf(s, 0, floor_nv, &glossy), PRT_OK);
        prt_transfer *t = NULL;
        assert_int_equal(prt_bake_wavelet(ctx, s, &d, &t), PRT_OK);
        float *rgb = wavelet_vertices(ctx, t, env, eye);
        mean[cse] = 0;
        for (size_t v = 0; v < floor_nv; ++v) mean[cse] += rgb[v * 3 + 1] / (double)floor_nv;
        free(rgb);
        prt_transfer_release(t);
        prt_scene_release(s);
    }
    print_message("floor: black wall %.4f, Lambertian wall %.4f, glossy wall %.4f; glossy floor: black wall %.4f, Lambertian wall %.4f\n", mean[0],
                  mean[1], mean[2], mean[3], mean[4]);
    assert_true(mean[1] > 1.05 * mean[0]);
    assert_true(mean[2] > 1.02 * mean[0]);   /* glossy-to-diffuse */
    assert_true(fabs(mean[2] - mean[1]) > 0.005 * mean[1]);
    assert_true(mean[4] > 1.02 * mean[3]);   /* diffuse-to-glossy */
    prt_envmap_release(env);
    tm_free(&m);
    prt_context_release(ctx);
}

static int cancel_at_first(void *user, const char *stage, uint64_t done, uint64_t total)
{
    (void)stage; (void)done; (void)total;
    ++*(int *)user;
    return 1;
}

/* A progress callback that asks to stop cancels the bake cleanly. */
static void test_cancel(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 24, 48);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    int calls = 0;
    prt_transfer *t = NULL;
    prt_wavelet_bake_desc d = {.supersample = 1, .bounces = 1, .progress = cancel_at_first, .progress_user = &calls};
    assert_int_equal(prt_bake_wavelet(ctx, s, &d, &t), PRT_ERR_CANCELLED);
    assert_null(t);
    assert_true(calls >= 1);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Save and load give the same relighting; damage is caught; bad descriptions fail clearly. */
static void test_wavelet_file(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0.6f, 0}, 0.5f, 6, 12);
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 3);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    prt_brdf b;
    assert_int_equal(prt_brdf_parse("ashikhmin:10:100:0.6:0.3", &b), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, 0, 6 * 12 - 10, &b), PRT_OK);
    prt_transfer *t = NULL, *u = NULL;
    assert_int_equal(prt_bake_wavelet(ctx, s, &(prt_wavelet_bake_desc){.supersample = 1, .terms = 3, .brdf_resolution = 16, .param = PRT_BRDF_PARAM_POLAR}, &t), PRT_OK);
    prt_wavelet_info wi;
    assert_true(prt_transfer_wavelet_info(t, &wi));
    assert_int_equal(wi.glossy_materials, 1);
    assert_int_equal(prt_transfer_wavelet_vertex_terms(t, 0), 3);
    assert_int_equal(prt_transfer_wavelet_vertex_terms(t, m.nv - 1), 1);
    char path[512];
    snprintf(path, sizeof path, "%s/w.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    prt_sky_desc sky = {0};
    prt_envmap *env = NULL;
    assert_int_equal(prt_sky_create(&sky, &env), PRT_OK);
    float *a = wavelet_vertices(ctx, t, env, (float[3]){1, 2, 3}), *c = wavelet_vertices(ctx, u, env, (float[3]){1, 2, 3});
    assert_memory_equal(a, c, m.nv * 3 * sizeof(float));
    assert_string_equal(prt_method_name(prt_transfer_method(u)), "wavelet");
    assert_int_equal(prt_transfer_variant_count(u), 1);
    assert_int_equal(prt_transfer_channels(u, PRT_TRANSFER_SHADOWED), 0);
    /* SH relighting of a wavelet file and wavelet relighting of an SH file fail with a message. */
    prt_sh_light L = uniform_light(3);
    assert_int_not_equal(prt_relight_sh(ctx, u, PRT_TRANSFER_SHADOWED, &L, a), PRT_OK);
    prt_transfer *z = NULL;
    assert_int_equal(prt_transfer_compress(ctx, u, NULL, &z), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "SH sets"));
    assert_int_equal(prt_transfer_quantize(ctx, u, 8, &z), PRT_ERR_INVALID_ARG);
    assert_null(z);
    prt_transfer *ts = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &(prt_bake_desc){.order = 2, .samples = 64, .kinds = PRT_TRANSFER_SHADOWED}, &ts), PRT_OK);
    prt_wavelet_light *l = NULL;
    assert_int_equal(prt_wavelet_light_create(ctx, env, NULL, &l), PRT_OK);
    assert_int_equal(prt_relight_wavelet(ctx, ts, l, a), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "wavelet"));
    /* A flipped byte in the transport is caught by its checksum. */
    FILE *f = fopen(path, "rb");
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *bytes = malloc((size_t)size);
    assert_int_equal(fread(bytes, 1, (size_t)size, f), (size_t)size);
    fclose(f);
    bytes[size - 40] ^= 0x5a;
    prt_transfer *bad = NULL;
    assert_int_equal(prt_transfer_load_memory(ctx, bytes, (size_t)size, &bad), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "checksum"));
    free(bytes);
    /* Out-of-range bake settings. */
    const prt_wavelet_bake_desc bads[] = {{.terms = 17}, {.coefficients = DIM + 1}, {.bits = 12}, {.supersample = 5}, {.bounces = 9}, {.gather_resolution = 2}, {.brdf_resolution = 100}};
    const char *words[] = {"terms", "coefficients", "bits", "supersampling", "bounces", "gather", "resolution"};
    for (int i = 0; i < 7; ++i) {
        prt_transfer *x = NULL;
        assert_int_equal(prt_bake_wavelet(ctx, s, &bads[i], &x), PRT_ERR_INVALID_ARG);
        if (!strstr(prt_last_error(), words[i])) fail_msg("message '%s' does not name %s", prt_last_error(), words[i]);
        assert_null(x);
    }
    free(a); free(c);
    prt_wavelet_light_release(l);
    prt_envmap_release(env);
    prt_transfer_release(t); prt_transfer_release(u); prt_transfer_release(ts);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Wavelet files whose checksums are right but whose contents are not: each is refused by name. */
static void test_crafted_files(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_transfer *t = NULL, *u = NULL;
    char path[512];
    snprintf(path, sizeof path, "%s/w.prt", test_dir);
    size_t size;
    unsigned char *orig;
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
    orig = test_slurp(path, &size);
    const uint32_t one = 1, tiny = 4;
    test_patch_chunk(orig, "WAVP", 0, &one, sizeof one);
    assert_int_equal(prt_transfer_load_memory(ctx, orig, size, &u), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "terms"));
    free(orig);
    orig = test_slurp(path, &size);
    test_patch_chunk(orig, "WBRF", 12, &tiny, sizeof tiny);   /* a factorization of another resolution */
    assert_int_equal(prt_transfer_load_memory(ctx, orig, size, &u), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "factorization"));
    free(orig);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(int argc, char **argv)
{
    /* Damaged files on their own (ctest: wavelet-files), quick enough for valgrind in every run. */
    if (argc > 1 && !strcmp(argv[1], "files")) {
        const struct CMUnitTest files[] = {cmocka_unit_test_setup_teardown(test_crafted_files, test_dir_setup, test_dir_teardown)};
        return cmocka_run_group_tests(files, NULL, NULL);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_haar),
        cmocka_unit_test(test_light_cubemap),
        cmocka_unit_test(test_light_conserves_small_sources),
        cmocka_unit_test(test_rotation_keeps_mean),
        cmocka_unit_test(test_sunlit_brightness),
        cmocka_unit_test(test_keep_all_reproduces_integral),
        cmocka_unit_test(test_svd_full_rank),
        cmocka_unit_test(test_convex_diffuse),
        cmocka_unit_test(test_glossy_furnace),
        cmocka_unit_test(test_sharp_shadow),
        cmocka_unit_test(test_quantization_bound),
        cmocka_unit_test(test_interreflection),
        cmocka_unit_test(test_glossy_bounce_paths),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test_setup_teardown(test_wavelet_file, test_dir_setup, test_dir_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
