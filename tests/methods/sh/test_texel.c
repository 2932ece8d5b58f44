/* Per-texel transfer: an unoccluded plane against the closed-form clamped cosine, a normal map
 * tilting it, an occluder's shadow, the file round trip, and clear errors without a usable UV
 * layout. */
#include "common.h"

/* A unit plane at y = 0 facing +y, n x n cells, with uv = (x, -z) spanning [0, 1]. */
static prt_scene *uv_plane(prt_context *ctx, int n, bool with_uv, float uv_scale)
{
    test_mesh m = {0};
    tm_quad(&m, (float[3]){0, 0, 0}, (float[3]){1, 0, 0}, (float[3]){0, 0, -1}, n);
    size_t plane_vertices = m.nv;
    /* An occluder: a small quad above the plane's (0.25, 0.25) corner, facing down. */
    tm_quad(&m, (float[3]){0.1f, 0.15f, -0.1f}, (float[3]){0, 0, -0.3f}, (float[3]){0.3f, 0, 0}, 2);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    if (with_uv) {
        float *uv = malloc(m.nv * 2 * sizeof(float));
        for (size_t v = 0; v < m.nv; ++v) {
            /* The occluder gets a small chart in the top-right corner, away from the plane's. */
            bool plane = v < plane_vertices;
            uv[v * 2] = plane ? m.pos[v * 3] * uv_scale : 0.9f + 0.05f * (m.pos[v * 3] - 0.1f) / 0.3f;
            uv[v * 2 + 1] = plane ? -m.pos[v * 3 + 2] * uv_scale : 0.9f + 0.05f * (-m.pos[v * 3 + 2] - 0.1f) / 0.3f;
        }
        assert_int_equal(prt_scene_set_uv(s, 0, m.nv, uv), PRT_OK);
        free(uv);
    }
    tm_free(&m);
    return s;
}

/* (1/pi) clamped cosine about n, projected: the unshadowed transfer of a normal n. */
static void clamped_cosine(int order, const double n[3], double *T)
{
    double zh[10], y[100];
    prt_sh_clamped_cosine_zh(order, zh);
    prt_sh_eval(order, n, y);
    for (int l = 0; l < order; ++l)
        for (int m = -l; m <= l; ++m) T[l * (l + 1) + m] = sqrt(4 * M_PI / (2 * l + 1)) * zh[l] * y[l * (l + 1) + m] / M_PI;
}

static void test_plane_and_normal_map(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = uv_plane(ctx, 4, true, 0.8f);
    /* A constant normal map tilting the normal by 30 degrees towards +u (= +x here). */
    const double a = 30 * M_PI / 180;
    prt_image nm = {2, 2, malloc(12 * sizeof(float))};
    for (int i = 0; i < 4; ++i) { nm.rgb[i * 3] = (float)(0.5 + 0.5 * sin(a)); nm.rgb[i * 3 + 1] = 0.5f; nm.rgb[i * 3 + 2] = (float)(0.5 + 0.5 * cos(a)); }
    for (int pass = 0; pass < 2; ++pass) {
        prt_bake_desc d = {0};
        d.order = 3;
        d.samples = 4096;
        d.kinds = PRT_TRANSFER_UNSHADOWED | PRT_TRANSFER_SHADOWED;
        d.texels = 32;
        d.normal_map = pass ? &nm : NULL;
        prt_transfer *t = NULL;
        assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
        int w, h, ch;
        assert_true(prt_transfer_texel_size(t, &w, &h));
        assert_true(w == 32 && h == 32);
        const float *U = prt_transfer_texel_coeffs(t, PRT_TRANSFER_UNSHADOWED, &ch), *S = prt_transfer_texel_coeffs(t, PRT_TRANSFER_SHADOWED, NULL);
        assert_non_null(U);
        assert_int_equal(ch, 1);
        double n[3] = {pass ? sin(a) : 0, pass ? cos(a) : 1, 0}, want[9];
        clamped_cosine(3, n, want);
        /* Shadowed, tilted: light from below the real plane is blocked. T_00 by quadrature. */
        double want_sh00 = 0;
        for (int i = 0; i < 400; ++i)
            for (int j = 0; j < 800; ++j) {
                double z = -1 + 2 * (i + 0.5) / 400, ph = 2 * M_PI * (j + 0.5) / 800, r = sqrt(1 - z * z);
                double dir[3] = {r * cos(ph), r * sin(ph), z}, c = dir[0] * n[0] + dir[1] * n[1] + dir[2] * n[2];
                if (c > 0 && dir[1] > 0) want_sh00 += c * 0.28209479 / M_PI * 4 * M_PI / (400 * 800);
            }
        double worst = 0, worst_sh = 0;
        int checked = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                /* Plane texels away from the occluder (its shadow falls near uv (0.2, 0.2)). */
                if ((x + 0.5) / w > 0.78 || (y + 0.5) / h > 0.78 || ((x + 0.5) / w < 0.5 && (y + 0.5) / h < 0.5)) continue;
                size_t i = (size_t)y * w + x;
                for (int k = 0; k < 9; ++k) worst = fmax(worst, fabs(U[i * 9 + k] - want[k]));
                /* The far corner sees the occluder below 12 degrees elevation: nearly unshadowed. */
                if ((x + 0.5) / w > 0.6 && (y + 0.5) / h > 0.6) worst_sh = fmax(worst_sh, fabs(S[i * 9] - want_sh00));
                checked++;
            }
        print_message("%s: %d texels, worst |T - analytic| %.4f, shadowed T_00 %.4f\n", pass ? "normal-mapped" : "flat", checked, worst, worst_sh);
        assert_true(checked > 300);
        assert_true(worst < 0.01);      /* T_00 of an upright plane is 0.2821 */
        assert_true(worst_sh < 0.004);
        /* The occluder's shadow: texels under it get much less direct light. */
        size_t under = (size_t)(0.25 * 0.8 * h) * w + (size_t)(0.25 * 0.8 * w);
        assert_true(S[under * 9] < 0.8 * want_sh00);
        prt_transfer_release(t);
    }
    free(nm.rgb);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Self-shadowing bumps: a height map holding a ridge along v (a wall of height h across a plane,
 * repeating every unit of u). A texel of the floor at distance x from the wall's face sees the sky
 * above the wall's top, at elevation a = atan(h / x) towards it: its sky view factor is
 * (cos a1 + cos a2) / 2 with the next wall behind it, T_00 that times the open plane's 0.2821.
 * Light from the wall's side low down is blocked there, light from the other side is not. */
static void test_height_map_shadows(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){0, 0, 0}, (float[3]){1, 0, 0}, (float[3]){0, 0, -1}, 4);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    float *uv = malloc(m.nv * 2 * sizeof(float));
    for (size_t v = 0; v < m.nv; ++v) { uv[v * 2] = m.pos[v * 3]; uv[v * 2 + 1] = -m.pos[v * 3 + 2]; }
    assert_int_equal(prt_scene_set_uv(s, 0, m.nv, uv), PRT_OK);
    free(uv);
    tm_free(&m);
    /* 128 columns; columns 60..67 are the wall (centres u 0.473..0.527): its faces, halfway up
     * the bilinear ramp, at u = 0.4688 and 0.5312. */
    prt_image hm = {128, 4, calloc(128 * 4 * 3, sizeof(float))};
    for (int y = 0; y < 4; ++y)
        for (int x = 60; x <= 67; ++x) hm.rgb[(y * 128 + x) * 3] = 1.0f;
    const double wall = 0.2, face = 0.46875;
    prt_bake_desc d = {0};
    d.order = 6;
    d.samples = 8192;
    d.kinds = PRT_TRANSFER_UNSHADOWED | PRT_TRANSFER_SHADOWED;
    d.texels = 64;
    d.uv_layout = PRT_UV_MESH;
    d.height_map = &hm;
    d.height_scale = (float)wall;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    int w, h, ch;
    assert_true(prt_transfer_texel_size(t, &w, &h));
    const float *U = prt_transfer_texel_coeffs(t, PRT_TRANSFER_UNSHADOWED, &ch), *S = prt_transfer_texel_coeffs(t, PRT_TRANSFER_SHADOWED, NULL);
    const int nc = 36;
    const int columns[3] = {8, 16, 24};
    for (int k = 0; k < 3; ++k) {
        const double u = (columns[k] + 0.5) / w, x1 = face - u, x2 = u + face;   /* the next wall: at u - 1 */
        const double svf = (cos(atan(wall / x1)) + cos(atan(wall / x2))) / 2;
        const size_t i = (size_t)(h / 2) * w + columns[k];
        print_message("floor %.3f from the wall (elevation %.1f deg): sky view %.4f, baked %.4f\n", x1, atan(wall / x1) * 180 / M_PI, svf, S[i * nc] / 0.28209479);
        assert_float_equal(S[i * nc] / 0.28209479, svf, 0.02);
        assert_float_equal(U[i * nc], 0.28209479f, 0.003f);   /* the floor is flat here: no bump turns its normal */
        /* Low light (30 degrees up) from beyond the wall against the same light from behind. */
        double towards[3] = {cos(M_PI / 6), sin(M_PI / 6), 0}, away[3] = {-cos(M_PI / 6), sin(M_PI / 6), 0}, ya[36], yb[36];
        prt_sh_eval(6, towards, ya);
        prt_sh_eval(6, away, yb);
        double lit_towards = 0, lit_away = 0;
        for (int j = 0; j < nc; ++j) { lit_towards += S[i * nc + j] * ya[j]; lit_away += S[i * nc + j] * yb[j]; }
        if (atan(wall / x1) > M_PI / 5) assert_true(lit_towards < 0.5 * lit_away);
    }
    /* On the wall's top: open sky. */
    const size_t top = (size_t)(h / 2) * w + 32;
    print_message("wall top: sky view %.4f\n", S[top * nc] / 0.28209479);
    assert_float_equal(S[top * nc] / 0.28209479, 1.0, 0.02);
    prt_transfer_release(t);
    /* A ramp rising 20 degrees along +u: its normal leans towards -u, and without a normal map the
     * unshadowed transfer is that normal's clamped cosine. */
    prt_image ramp = {64, 2, calloc(64 * 2 * 3, sizeof(float))};
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 64; ++x) ramp.rgb[(y * 64 + x) * 3] = (x + 0.5f) / 64;
    const double a = 20 * M_PI / 180;
    prt_bake_desc dr = d;
    dr.order = 3;
    dr.samples = 1024;
    dr.kinds = PRT_TRANSFER_UNSHADOWED;
    dr.texels = 16;
    dr.height_map = &ramp;
    dr.height_scale = (float)tan(a);
    assert_int_equal(prt_bake_sh(ctx, s, &dr, &t), PRT_OK);
    U = prt_transfer_texel_coeffs(t, PRT_TRANSFER_UNSHADOWED, NULL);
    double n[3] = {-sin(a), cos(a), 0}, want[9], worst = 0;
    clamped_cosine(3, n, want);
    for (int x = 4; x < 12; ++x)
        for (int k = 0; k < 9; ++k) worst = fmax(worst, fabs(U[(size_t)(8 * 16 + x) * 9 + k] - want[k]));
    print_message("ramp of 20 degrees: worst |T - clamped cosine of its normal| %.4f\n", worst);
    assert_true(worst < 0.01);
    prt_transfer_release(t);
    free(ramp.rgb);
    /* Bad height maps are refused. */
    prt_image empty = {0};
    d.height_map = &empty;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "height map"));
    hm.rgb[5 * 3] = NAN;
    d.height_map = &hm;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    d.height_scale = -1;
    hm.rgb[5 * 3] = 0;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    d.height_scale = 0;
    d.texels = 0;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "per-texel"));
    free(hm.rgb);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_texel_errors(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_bake_desc d = {0};
    d.order = 2;
    d.samples = 64;
    d.kinds = PRT_TRANSFER_SHADOWED;
    d.texels = 16;
    d.uv_layout = PRT_UV_MESH;   /* without it, meshes like these get a generated atlas (test_atlas.c) */
    prt_transfer *t = NULL;
    prt_scene *s = uv_plane(ctx, 2, false, 1);
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "texture coordinates"));
    assert_null(t);
    prt_scene_release(s);
    s = uv_plane(ctx, 2, true, 1.5f);   /* a tiling layout, not a unique one */
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "inside [0, 1]"));
    prt_scene_release(s);
    s = uv_plane(ctx, 2, true, 1);
    prt_image empty = {0};
    d.normal_map = &empty;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    d.normal_map = NULL;
    d.texels = -1;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_ERR_INVALID_ARG);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Texel sets, their albedo and the UVs survive the file; relighting is the dot product times
 * the albedo; compression keeps them. */
static void test_texel_file(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = uv_plane(ctx, 4, true, 0.8f);
    prt_bake_desc d = {0};
    d.order = 3;
    d.samples = 256;
    d.bounces = 1;
    d.kinds = PRT_TRANSFER_SHADOWED | PRT_TRANSFER_INTERREFLECTED;
    d.texels = 16;
    prt_transfer *t = NULL, *u = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &t), PRT_OK);
    char path[600];
    snprintf(path, sizeof path, "%s/texels.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    int ch = 0;
    const float *a = prt_transfer_texel_coeffs(t, PRT_TRANSFER_INTERREFLECTED, &ch), *b = prt_transfer_texel_coeffs(u, PRT_TRANSFER_INTERREFLECTED, NULL);
    assert_int_equal(ch, 3);
    assert_memory_equal(a, b, 16 * 16 * 27 * sizeof(float));
    assert_memory_equal(prt_transfer_uvs(t), prt_transfer_uvs(u), prt_transfer_vertex_count(t) * 2 * sizeof(float));
    prt_sh_light L = uniform_light(3);
    float *r1 = malloc(16 * 16 * 3 * sizeof(float)), *r2 = malloc(16 * 16 * 3 * sizeof(float));
    assert_int_equal(prt_relight_sh_texels(ctx, u, PRT_TRANSFER_SHADOWED, &L, r1), PRT_OK);
    const float *S = prt_transfer_texel_coeffs(u, PRT_TRANSFER_SHADOWED, NULL);
    for (int i = 0; i < 256; i += 17) assert_float_equal(r1[i * 3], S[i * 9] * L.coeffs[0][0] * 0.5f, 1e-5f);   /* albedo 0.5 */
    /* Inter-reflected >= shadowed times albedo everywhere: the occluder's underside bounces light down. */
    assert_int_equal(prt_relight_sh_texels(ctx, u, PRT_TRANSFER_INTERREFLECTED, &L, r2), PRT_OK);
    for (int i = 0; i < 256 * 3; ++i) assert_true(r2[i] >= r1[i] - 1e-4f);
    assert_int_equal(prt_relight_sh_texels(ctx, u, PRT_TRANSFER_UNSHADOWED, &L, r2), PRT_ERR_INVALID_ARG);
    prt_transfer *z = NULL;
    prt_compress_desc cd = {0};
    cd.clusters = 4;
    assert_int_equal(prt_transfer_compress(ctx, t, &cd, &z), PRT_OK);
    assert_memory_equal(prt_transfer_texel_coeffs(z, PRT_TRANSFER_INTERREFLECTED, NULL), a, 16 * 16 * 27 * sizeof(float));
    prt_transfer_release(z);
    free(r1);
    free(r2);
    prt_transfer_release(u);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* 8-bit texel sets (--quantize 8): 256 levels per coefficient between its least and greatest
 * value, the transfer holding what the file stores (a load gives the same numbers), within half
 * a level of the floats, and a quarter of the halves' bytes. */
static void test_texel_bytes(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = uv_plane(ctx, 4, true, 0.8f);
    prt_transfer *t[2] = {NULL, NULL}, *u = NULL;
    const char *bits[2] = {"32", "8"};
    for (int q = 0; q < 2; ++q) {
        prt_options *o = NULL;
        assert_int_equal(prt_options_create(prt_method_find("sh"), &o), PRT_OK);
        assert_int_equal(prt_options_set(o, "order", "4"), PRT_OK);
        assert_int_equal(prt_options_set(o, "samples", "256"), PRT_OK);
        assert_int_equal(prt_options_set(o, "kinds", "shadowed"), PRT_OK);
        assert_int_equal(prt_options_set(o, "texels", "32"), PRT_OK);
        assert_int_equal(prt_options_set(o, "quantize", bits[q]), PRT_OK);
        assert_int_equal(prt_bake(ctx, s, prt_method_find("sh"), o, NULL, &t[q]), PRT_OK);
        prt_options_release(o);
    }
    const size_t n = 32 * 32 * 16;
    const float *f = prt_transfer_texel_coeffs(t[0], PRT_TRANSFER_SHADOWED, NULL), *b = prt_transfer_texel_coeffs(t[1], PRT_TRANSFER_SHADOWED, NULL);
    for (int j = 0; j < 16; ++j) {
        float lo = INFINITY, hi = -INFINITY;
        for (size_t i = j; i < n; i += 16) { lo = fminf(lo, f[i]); hi = fmaxf(hi, f[i]); }
        for (size_t i = j; i < n; i += 16) assert_true(fabsf(b[i] - f[i]) <= 0.5f * (hi - lo) / 255 * 1.001f + 1e-7f);
    }
    char path[600];
    snprintf(path, sizeof path, "%s/bytes.prt", test_dir);
    assert_int_equal(prt_transfer_save(t[1], path), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    const float *c = prt_transfer_texel_coeffs(u, PRT_TRANSFER_SHADOWED, NULL);
    for (size_t i = 0; i < n; ++i) assert_float_equal(c[i], b[i], 1e-6f * (fabsf(b[i]) + 1e-3f));
    prt_transfer_info a, z;
    prt_transfer_get_info(t[0], &a);
    prt_transfer_get_info(u, &z);
    print_message("texel sets: %zu bytes as floats, %zu as 8-bit levels\n", (size_t)a.texel_bytes, (size_t)z.texel_bytes);
    assert_true(z.texel_bytes < a.texel_bytes / 2);
    prt_transfer_release(u);
    prt_transfer_release(t[0]);
    prt_transfer_release(t[1]);
    prt_scene_release(s);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane_and_normal_map),
        cmocka_unit_test(test_height_map_shadows),
        cmocka_unit_test(test_texel_errors),
        cmocka_unit_test_setup_teardown(test_texel_file, test_dir_setup, test_dir_teardown),
        cmocka_unit_test_setup_teardown(test_texel_bytes, test_dir_setup, test_dir_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
