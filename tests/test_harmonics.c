/* Spherical harmonics: orthonormality, rotation, zonal clamped cosine. Integrals use a product
 * Gauss-Legendre (in cos theta) x uniform (in phi) rule, exact for the band limits involved. */
#include "common.h"

#define GL_N 48
#define PHI_N 96

static double gl_x[GL_N], gl_w[GL_N];

static void gauss_legendre(void)
{
    for (int i = 0; i < GL_N; ++i) {
        double x = cos(M_PI * (i + 0.75) / (GL_N + 0.5)), dp = 0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1, p1 = x;
            for (int k = 2; k <= GL_N; ++k) { double p2 = ((2.0 * k - 1) * x * p1 - (k - 1.0) * p0) / k; p0 = p1; p1 = p2; }
            dp = GL_N * (x * p1 - p0) / (x * x - 1);
            double dx = p1 / dp;
            x -= dx;
            if (fabs(dx) < 1e-15) break;
        }
        gl_x[i] = x;
        gl_w[i] = 2.0 / ((1 - x * x) * dp * dp);
    }
}

/* Calls f for every quadrature direction with its weight. */
typedef void (*quad_fn)(void *user, const double dir[3], double w);
static void integrate(quad_fn f, void *user)
{
    for (int i = 0; i < GL_N; ++i)
        for (int j = 0; j < PHI_N; ++j) {
            double z = gl_x[i], r = sqrt(1 - z * z), ph = 2 * M_PI * (j + 0.5) / PHI_N;
            double d[3] = {r * cos(ph), r * sin(ph), z};
            f(user, d, gl_w[i] * 2 * M_PI / PHI_N);
        }
}

static double gram[PRT_SH_MAX_COEFFS][PRT_SH_MAX_COEFFS];
static void acc_gram(void *user, const double d[3], double w)
{
    (void)user;
    double y[PRT_SH_MAX_COEFFS];
    prt_sh_eval(PRT_SH_MAX_ORDER, d, y);
    for (int a = 0; a < PRT_SH_MAX_COEFFS; ++a)
        for (int b = 0; b < PRT_SH_MAX_COEFFS; ++b) gram[a][b] += w * y[a] * y[b];
}

static void test_orthonormal(void **state)
{
    (void)state;
    memset(gram, 0, sizeof gram);
    integrate(acc_gram, NULL);
    double worst = 0;
    for (int a = 0; a < PRT_SH_MAX_COEFFS; ++a)
        for (int b = 0; b < PRT_SH_MAX_COEFFS; ++b) worst = fmax(worst, fabs(gram[a][b] - (a == b)));
    assert_true(worst < 1e-10);
}

static void test_band1_is_yzx(void **state)
{
    (void)state;
    double d[3] = {0.3, -0.5, 0.2}, l = sqrt(0.09 + 0.25 + 0.04), y[4];
    for (int i = 0; i < 3; ++i) d[i] /= l;
    prt_sh_eval(2, d, y);
    double k = sqrt(3.0 / (4 * M_PI));
    assert_true(fabs(y[0] - 0.5 / sqrt(M_PI)) < 1e-12);
    assert_true(fabs(y[1] - k * d[1]) < 1e-12);
    assert_true(fabs(y[2] - k * d[2]) < 1e-12);
    assert_true(fabs(y[3] - k * d[0]) < 1e-12);
}

/* f is a band-limited function with random coefficients; g(R d) = f(d). */
typedef struct rot_case { const float *f; double rt[9]; double proj[PRT_SH_MAX_COEFFS]; } rot_case;
static void acc_rotated(void *user, const double d[3], double w)
{
    rot_case *rc = user;
    /* g(d) = f(R^T d) */
    double src[3] = {rc->rt[0] * d[0] + rc->rt[1] * d[1] + rc->rt[2] * d[2], rc->rt[3] * d[0] + rc->rt[4] * d[1] + rc->rt[5] * d[2],
                     rc->rt[6] * d[0] + rc->rt[7] * d[1] + rc->rt[8] * d[2]};
    double ys[PRT_SH_MAX_COEFFS], yd[PRT_SH_MAX_COEFFS];
    prt_sh_eval(PRT_SH_MAX_ORDER, src, ys);
    prt_sh_eval(PRT_SH_MAX_ORDER, d, yd);
    double g = 0;
    for (int i = 0; i < PRT_SH_MAX_COEFFS; ++i) g += rc->f[i] * ys[i];
    for (int i = 0; i < PRT_SH_MAX_COEFFS; ++i) rc->proj[i] += w * g * yd[i];
}

static void test_rotation_matches_projection(void **state)
{
    (void)state;
    float f[PRT_SH_MAX_COEFFS], g[PRT_SH_MAX_COEFFS];
    uint32_t seed = 12345;
    for (int i = 0; i < PRT_SH_MAX_COEFFS; ++i) {
        seed = seed * 1664525u + 1013904223u;
        f[i] = (float)((seed >> 8) / 16777216.0 - 0.5);
    }
    const double angles[3][3] = {{30, 20, 10}, {-125, 70, 200}, {90, 0, 0}};
    for (int a = 0; a < 3; ++a) {
        rot_case rc;
        memset(&rc, 0, sizeof rc);
        rc.f = f;
        double r[9];
        prt_rotation_from_euler_deg(angles[a][0], angles[a][1], angles[a][2], r);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) rc.rt[i * 3 + j] = r[j * 3 + i];
        integrate(acc_rotated, &rc);
        prt_sh_rotation *rot;
        assert_int_equal(prt_sh_rotation_create(PRT_SH_MAX_ORDER, r, &rot), PRT_OK);
        prt_sh_rotation_apply(rot, 1, f, g);
        prt_sh_rotation_release(rot);
        double worst = 0;
        for (int i = 0; i < PRT_SH_MAX_COEFFS; ++i) worst = fmax(worst, fabs(g[i] - rc.proj[i]));
        if (worst >= 1e-4) fail_msg("rotation %d: max coefficient error %g", a, worst);
    }
}

static void test_rotation_preserves_energy_and_inverts(void **state)
{
    (void)state;
    float f[PRT_SH_MAX_COEFFS], g[PRT_SH_MAX_COEFFS], h[PRT_SH_MAX_COEFFS];
    for (int i = 0; i < PRT_SH_MAX_COEFFS; ++i) f[i] = sinf(1.7f * i + 0.3f);
    double r[9], rt[9];
    prt_rotation_from_euler_deg(47, -33, 12, r);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) rt[i * 3 + j] = r[j * 3 + i];
    prt_sh_rotation *a, *b;
    assert_int_equal(prt_sh_rotation_create(PRT_SH_MAX_ORDER, r, &a), PRT_OK);
    assert_int_equal(prt_sh_rotation_create(PRT_SH_MAX_ORDER, rt, &b), PRT_OK);
    prt_sh_rotation_apply(a, 1, f, g);
    prt_sh_rotation_apply(b, 1, g, h);
    double ef = 0, eg = 0, worst = 0;
    for (int i = 0; i < PRT_SH_MAX_COEFFS; ++i) { ef += f[i] * f[i]; eg += g[i] * g[i]; worst = fmax(worst, fabs(h[i] - f[i])); }
    assert_true(fabs(ef - eg) < 1e-4 * ef);
    assert_true(worst < 1e-5);
    prt_sh_rotation_release(a);
    prt_sh_rotation_release(b);
}

typedef struct zh_case { double c[PRT_SH_MAX_ORDER]; } zh_case;
static void acc_zh(void *user, const double d[3], double w)
{
    zh_case *z = user;
    double y[PRT_SH_MAX_COEFFS];
    prt_sh_eval(PRT_SH_MAX_ORDER, d, y);
    double f = d[2] > 0 ? d[2] : 0;
    for (int l = 0; l < PRT_SH_MAX_ORDER; ++l) z->c[l] += w * f * y[l * (l + 1)];
}

static void test_clamped_cosine_closed_form(void **state)
{
    (void)state;
    /* The clamped cosine has a kink at the equator, so integrate it piecewise exactly: a
     * Gauss rule on the upper hemisphere alone (z in [0, 1]). */
    zh_case num;
    memset(&num, 0, sizeof num);
    for (int i = 0; i < GL_N; ++i) {
        double z = 0.5 * (gl_x[i] + 1), w = 0.5 * gl_w[i] * 2 * M_PI;
        double d[3] = {sqrt(1 - z * z), 0, z}, y[PRT_SH_MAX_COEFFS];
        prt_sh_eval(PRT_SH_MAX_ORDER, d, y);
        for (int l = 0; l < PRT_SH_MAX_ORDER; ++l) num.c[l] += w * z * y[l * (l + 1)];
    }
    double closed[PRT_SH_MAX_ORDER];
    prt_sh_clamped_cosine_zh(PRT_SH_MAX_ORDER, closed);
    for (int l = 0; l < PRT_SH_MAX_ORDER; ++l)
        if (fabs(num.c[l] - closed[l]) > 1e-10) fail_msg("band %d: numeric %.12f closed %.12f", l, num.c[l], closed[l]);
    /* Known values: sqrt(pi)/2, sqrt(pi/3), sqrt(5 pi)/8. */
    assert_true(fabs(closed[0] - sqrt(M_PI) / 2) < 1e-12);
    assert_true(fabs(closed[1] - sqrt(M_PI / 3)) < 1e-12);
    assert_true(fabs(closed[2] - sqrt(5 * M_PI) / 8) < 1e-12);
    (void)acc_zh;
}

static void test_bad_rotation_input(void **state)
{
    (void)state;
    prt_sh_rotation *r = NULL;
    double bad[9] = {NAN, 0, 0, 0, 1, 0, 0, 0, 1};
    assert_int_equal(prt_sh_rotation_create(3, bad, &r), PRT_ERR_INVALID_ARG);
    assert_null(r);
    double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    assert_int_equal(prt_sh_rotation_create(11, id, &r), PRT_ERR_INVALID_ARG);
    assert_true(strstr(prt_last_error(), "order") != NULL);
}

int main(void)
{
    gauss_legendre();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orthonormal),
        cmocka_unit_test(test_band1_is_yzx),
        cmocka_unit_test(test_rotation_matches_projection),
        cmocka_unit_test(test_rotation_preserves_energy_and_inverts),
        cmocka_unit_test(test_clamped_cosine_closed_form),
        cmocka_unit_test(test_bad_rotation_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
