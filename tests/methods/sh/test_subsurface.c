/* Translucency in SH transfer (src/methods/sh/subsurface.c): a slab of skin, lit from every
 * direction. Every face of a convex slab receives the same incident transfer (its DC part y00,
 * the cosine over a hemisphere), so at the bottom face's centre the inter-reflected transfer's DC
 * part is y00 times the dipole integrated over the slab's faces: its own face reflecting, the top
 * face transmitting through the slab's thickness. Checked against that integral of the dipole's
 * closed form, for two thicknesses. */
#include "common.h"

#include "brdf/dipole.h"

static void face(FILE *f, int *base, const double o[3], const double u[3], const double v[3], int nu, int nv)
{
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i)
            fprintf(f, "v %.6f %.6f %.6f\n", o[0] + u[0] * i / nu + v[0] * j / nv, o[1] + u[1] * i / nu + v[1] * j / nv, o[2] + u[2] * i / nu + v[2] * j / nv);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const int a = *base + j * (nu + 1) + i, b = a + 1, c = a + nu + 1, d = c + 1;
            fprintf(f, "f %d %d %d\nf %d %d %d\n", a, b, d, a, d, c);
        }
    *base += (nu + 1) * (nv + 1);
}

/* A slab of side 2h (mm), thickness d, its bottom at y = 0, n cells along a side. */
static void write_slab(const char *path, double h, double d, int n)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "o slab\n");
    int base = 1;
    face(f, &base, (double[3]){-h, d, h}, (double[3]){2 * h, 0, 0}, (double[3]){0, 0, -2 * h}, n, n);    /* top, up */
    face(f, &base, (double[3]){-h, 0, -h}, (double[3]){2 * h, 0, 0}, (double[3]){0, 0, 2 * h}, n, n);    /* bottom, down */
    face(f, &base, (double[3]){h, 0, h}, (double[3]){0, 0, -2 * h}, (double[3]){0, d, 0}, n, 2);         /* +x */
    face(f, &base, (double[3]){-h, 0, -h}, (double[3]){0, 0, 2 * h}, (double[3]){0, d, 0}, n, 2);        /* -x */
    face(f, &base, (double[3]){-h, 0, h}, (double[3]){2 * h, 0, 0}, (double[3]){0, d, 0}, n, 2);         /* +z */
    face(f, &base, (double[3]){h, 0, -h}, (double[3]){-2 * h, 0, 0}, (double[3]){0, d, 0}, n, 2);        /* -z */
    fclose(f);
}

/* The dipole integrated over a face of side 2h at height y above the point (0, 0, 0): midpoints of
 * a fine grid (R_d changes over about its zr, a millimetre or so). */
static double face_integral(const prt__dipole *k, double h, double y)
{
    const int n = 800;
    const double step = 2 * h / n;
    double sum = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double x = -h + (i + 0.5) * step, z = -h + (j + 0.5) * step;
            sum += prt__dipole_rd(k, sqrt(x * x + y * y + z * z));
        }
    return sum * step * step;
}

static void test_slab(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_medium skin;
    assert_int_equal(prt_medium_preset("skin", &skin), PRT_OK);
    prt__dipole k[3];
    assert_int_equal(prt__dipole_from_medium(&skin, 1.0, k), PRT_OK);
    const double h = 10, thickness[2] = {1, 3}, y00 = 0.28209479177387814;
    double baked_thin[3] = {0};
    for (int s = 0; s < 2; ++s) {
        char obj[600], json[600];
        snprintf(obj, sizeof obj, "%s/slab.obj", test_dir);
        write_slab(obj, h, thickness[s], 40);
        write_text("slab.json", "{\"materials\": {\"slab\": {\"subsurface\": \"skin\"}}, \"meshes\": [{\"file\": \"slab.obj\"}]}", json, sizeof json);
        prt_scene *scene = NULL;
        assert_int_equal(prt_scene_load(ctx, json, NULL, &scene), PRT_OK);
        prt_options *o = NULL;
        assert_int_equal(prt_options_create(prt_method_find("sh"), &o), PRT_OK);
        const char *set[][2] = {{"order", "2"}, {"samples", "1024"}, {"kinds", "interreflected"}, {"bounces", "1"}, {"mm-per-unit", "1"}, {"quantize", "32"}};
        for (size_t i = 0; i < sizeof set / sizeof set[0]; ++i) assert_int_equal(prt_options_set(o, set[i][0], set[i][1]), PRT_OK);
        prt_transfer *t = NULL;
        assert_int_equal(prt_bake(ctx, scene, prt_method_find("sh"), o, NULL, &t), PRT_OK);
        const float *pos = prt_transfer_positions(t), centre[3] = {0, 0, 0};
        const size_t nv = prt_transfer_vertex_count(t);
        /* The bottom face's vertex at the centre (the top face's is thickness away). */
        size_t v = nearest_vertex(pos, nv, centre);
        assert_true(fabsf(pos[v * 3 + 1]) < 1e-6f);
        const float *T = prt_transfer_coeffs(t, PRT_TRANSFER_INTERREFLECTED);
        assert_non_null(T);
        assert_int_equal(prt_transfer_channels(t, PRT_TRANSFER_INTERREFLECTED), 3);
        for (int c = 0; c < 3; ++c) {
            const double own = face_integral(&k[c], h, 0), through = face_integral(&k[c], h, thickness[s]);
            const double got = T[v * 12 + c * 4] / y00;
            print_message("skin slab %.0f mm thick, channel %d: dipole over the faces %.4f (own face %.4f + through the slab %.4f), baked %.4f\n",
                          thickness[s], c, own + through, own, through, got);
            assert_true(fabs(got - (own + through)) < 0.03 * (own + through));
            /* The thicker slab lets less through: the bake's own numbers say so. */
            if (s == 0) baked_thin[c] = got;
            else assert_true(got < baked_thin[c]);
        }
        prt_transfer_release(t);
        prt_options_release(o);
        prt_scene_release(scene);
    }
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_slab, test_dir_setup, test_dir_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
