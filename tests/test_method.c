/* The method table and the lighting every layer shares: declarations and option checking, bakes
 * through the table equal the methods' own bakes and do not depend on the thread count, files
 * keep the scene's lights, relighting refuses lighting a method cannot handle, directional lights
 * project exactly, and glossy SH and wavelet transfer on a convex sphere match the reference path
 * tracer within their truncation. */
#include "common.h"

#include <cjson/cJSON.h>

static void test_table(void **state)
{
    (void)state;
    assert_true(prt_method_count() >= 2);
    assert_ptr_equal(prt_method_default(), prt_method_at(0));
    assert_string_equal(prt_method_name(prt_method_default()), "sh");
    assert_null(prt_method_at(prt_method_count()));
    assert_null(prt_method_find("fourier"));
    for (int i = 0; i < prt_method_count(); ++i) {
        const prt_method *m = prt_method_at(i);
        assert_ptr_equal(prt_method_find(prt_method_name(m)), m);
        assert_true(strlen(prt_method_summary(m)) > 10);
        assert_true(prt_method_lighting(m) != 0);
        const prt_option_desc *o;
        int n = prt_method_options(m, &o);
        assert_true(n > 0);
        for (int k = 0; k < n; ++k) {
            assert_non_null(o[k].name);
            assert_non_null(o[k].help);
            assert_ptr_equal(prt_method_option(m, o[k].name), &o[k]);
            if (o[k].type == PRT_OPTION_INT || o[k].type == PRT_OPTION_FLOAT) assert_true(o[k].min <= o[k].max);
            if (o[k].type == PRT_OPTION_CHOICE || o[k].type == PRT_OPTION_LIST) assert_non_null(o[k].choices);
        }
    }
}

static void test_options(void **state)
{
    (void)state;
    const prt_method *sh = prt_method_find("sh"), *wav = prt_method_find("wavelet");
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(sh, &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "order", "6"), PRT_OK);
    assert_string_equal(prt_options_get(o, "order"), "6");
    assert_int_equal(prt_options_set(o, "order", "7"), PRT_OK);   /* a later value wins */
    assert_string_equal(prt_options_get(o, "order"), "7");
    assert_int_equal(prt_options_set(o, "order", "11"), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "--order must be an integer in 1..10"));
    assert_int_equal(prt_options_set(o, "order", "5x"), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_options_set(o, "terms", "4"), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "option of method wavelet"));
    assert_int_equal(prt_options_set(o, "frobnicate", "1"), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "has no option --frobnicate"));
    assert_int_equal(prt_options_set(o, "kinds", "shadowed,glossy-shadowed"), PRT_OK);
    assert_int_equal(prt_options_set(o, "kinds", "shadowed,bogus"), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "'bogus'"));
    assert_int_equal(prt_options_set(o, "compress", "zip"), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "cpca, pca or vq"));
    assert_int_equal(prt_options_set(o, "bake-materials", "yes"), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_options_set(o, "bake-materials", NULL), PRT_OK);
    assert_null(prt_options_get(o, "samples"));
    prt_options_release(o);
    assert_int_equal(prt_options_create(wav, &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "bits", "12"), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "8 or 16"));
    prt_options_release(o);
}

static prt_scene *plate_and_box(prt_context *ctx)
{
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 12);
    tm_sphere(&m, (float[3]){0, 0.45f, 0}, 0.4f, 8, 16);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    tm_free(&m);
    return s;
}

static const float *coeffs_of(const prt_transfer *t, prt_transfer_kind k) { return prt_transfer_coeffs(t, k); }

static void test_bake_through_table(void **state)
{
    (void)state;
    prt_context *one = test_context(1), *two = test_context(2);
    prt_scene *scene = plate_and_box(two);
    const prt_method *sh = prt_method_find("sh");
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(sh, &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "order", "4"), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "256"), PRT_OK);
    assert_int_equal(prt_options_set(o, "kinds", "all,glossy-shadowed"), PRT_OK);
    assert_int_equal(prt_options_set(o, "bounces", "2"), PRT_OK);
    prt_transfer *a = NULL, *b = NULL, *c = NULL, *q = NULL;
    /* By default the table stores 16-bit sets; within 1/65535 of each coefficient's range of
     * the floats that --quantize 32 keeps (and prt_bake_sh gives). */
    assert_int_equal(prt_bake(one, scene, sh, o, NULL, &q), PRT_OK);
    assert_int_equal(prt_options_set(o, "quantize", "32"), PRT_OK);
    assert_int_equal(prt_bake(one, scene, sh, o, NULL, &a), PRT_OK);
    assert_int_equal(prt_bake(two, scene, sh, o, NULL, &b), PRT_OK);
    prt_bake_desc d = {0};   /* the SH bake desc's prt 0.1 name (prt_sh_bake_desc now): old programs still build */
    d.order = 4;
    d.samples = 256;
    d.kinds = 7 | PRT_TRANSFER_GLOSSY_SHADOWED;
    d.bounces = 2;
    assert_int_equal(prt_bake_sh(two, scene, &d, &c), PRT_OK);
    const size_t nv = prt_transfer_vertex_count(a);
    const prt_transfer_kind kinds[4] = {PRT_TRANSFER_UNSHADOWED, PRT_TRANSFER_SHADOWED, PRT_TRANSFER_INTERREFLECTED, PRT_TRANSFER_GLOSSY_SHADOWED};
    for (int k = 0; k < 4; ++k) {
        const size_t bytes = nv * prt_transfer_set_floats(a, kinds[k]) * sizeof(float);
        assert_true(bytes > 0);
        /* The work units' results do not depend on the threads or on the way into the bake. */
        assert_memory_equal(coeffs_of(a, kinds[k]), coeffs_of(b, kinds[k]), bytes);
        assert_memory_equal(coeffs_of(a, kinds[k]), coeffs_of(c, kinds[k]), bytes);
        const size_t dim = prt_transfer_set_floats(a, kinds[k]);
        const float *x = coeffs_of(a, kinds[k]), *y = coeffs_of(q, kinds[k]);
        for (size_t j = 0; j < dim; ++j) {
            float lo = x[j], hi = x[j];
            for (size_t v = 0; v < nv; ++v) { lo = fminf(lo, x[v * dim + j]); hi = fmaxf(hi, x[v * dim + j]); }
            for (size_t v = 0; v < nv; ++v) assert_true(fabsf(x[v * dim + j] - y[v * dim + j]) <= (hi - lo) / 65535.0f * 0.51f + 1e-7f);
        }
    }
    prt_transfer_release(q);
    assert_ptr_equal(prt_transfer_method(a), sh);
    assert_int_equal(prt_transfer_variant_count(a), 4);
    assert_string_equal(prt_transfer_variant_name(a, prt_transfer_default_variant(a, 0)), "interreflected");
    assert_string_equal(prt_transfer_variant_name(a, prt_transfer_default_variant(a, 1)), "glossy-shadowed");
    assert_int_equal(prt_transfer_find_variant(a, "s"), 1);
    assert_int_equal(prt_transfer_find_variant(a, "glossy-interreflected"), -1);
    assert_non_null(strstr(prt_last_error(), "holds unshadowed, shadowed, interreflected, glossy-shadowed"));
    /* prt info in both forms. */
    char *text = NULL;
    assert_int_equal(prt_transfer_describe(a, "a.prt", 0, &text), PRT_OK);
    assert_non_null(strstr(text, "order:       4"));
    assert_non_null(strstr(text, "spherical-harmonic PRT (sh)"));
    free(text);
    assert_int_equal(prt_transfer_describe(a, "a.prt", 1, &text), PRT_OK);
    cJSON *j = cJSON_Parse(text);
    assert_non_null(j);
    assert_string_equal(cJSON_GetObjectItem(j, "method")->valuestring, "sh");
    assert_int_equal(cJSON_GetObjectItem(j, "order")->valueint, 4);
    assert_int_equal((int)cJSON_GetObjectItem(j, "vertices")->valuedouble, (int)nv);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(j, "kinds")), 4);
    cJSON_Delete(j);
    free(text);
    /* Relighting through the table equals the SH method's own functions. */
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    prt_envmap *env = band_limited_env(64);
    assert_int_equal(prt_lighting_set_envmap(l, env, NULL, 0.5f), PRT_OK);
    prt_sh_light L;
    assert_int_equal(prt_envmap_project_sh(prt_lighting_envmap(l), 4, &L), PRT_OK);
    prt_sh_light_scale(&L, 0.5f);
    float *own = malloc(nv * 3 * sizeof(float));
    for (int v = 0; v < 3; ++v) {
        prt_relight_desc rd = {.variant = v};
        prt_relit r;
        assert_int_equal(prt_relight(two, a, l, &rd, &r), PRT_OK);
        assert_int_equal(prt_relight_sh(two, a, kinds[v], &L, own), PRT_OK);
        for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(r.radiance[i], own[i], 1e-5f * (1.0f + fabsf(own[i])));
        assert_false(prt_relit_view_dependent(&r));
        prt_relit_free(&r);
    }
    free(own);
    prt_lighting_release(l);
    prt_options_release(o);
    prt_transfer_release(a);
    prt_transfer_release(b);
    prt_transfer_release(c);
    prt_scene_release(scene);
    prt_context_release(one);
    prt_context_release(two);
}

/* A directional light is a delta in direction: SH transfer relights it as the band-limited
 * clamped cosine, which at order 8 is within a few percent of rho/pi E cos(theta). */
static void test_directional_light(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 4);
    prt_scene *scene = tm_scene(ctx, &m, 0.5f);
    prt_bake_desc d = {0};
    d.order = 8;
    d.samples = 16384;
    d.kinds = PRT_TRANSFER_UNSHADOWED;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, scene, &d, &t), PRT_OK);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    for (int deg = 0; deg <= 60; deg += 20) {
        prt_lighting_clear_lights(l);
        const float th = (float)deg * (float)M_PI / 180.0f, E = 2.0f;
        prt_light sun = {.type = PRT_LIGHT_DIRECTIONAL, .direction = {sinf(th), cosf(th), 0}, .irradiance = {E, E, E}};
        assert_int_equal(prt_lighting_add(l, &sun, NULL), PRT_OK);
        prt_relit r;
        assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
        const float exact = 0.5f / (float)M_PI * E * cosf(th);
        for (size_t v = 0; v < prt_transfer_vertex_count(t); ++v) assert_float_equal(r.radiance[v * 3], exact, 0.03f * 0.5f / (float)M_PI * E);
        prt_relit_free(&r);
    }
    /* The wavelet method puts a directional light into the texel its direction falls in. */
    prt_wavelet_bake_desc wd = {0};
    wd.coefficients = PRT_WAVELET_DIM;
    wd.bits = 16;
    wd.supersample = 1;
    prt_transfer *w = NULL;
    assert_int_equal(prt_bake_wavelet(ctx, scene, &wd, &w), PRT_OK);
    for (int deg = 0; deg <= 60; deg += 30) {
        prt_lighting_clear_lights(l);
        const float th = (float)deg * (float)M_PI / 180.0f, E = 2.0f;
        prt_light sun = {.type = PRT_LIGHT_DIRECTIONAL, .direction = {sinf(th), cosf(th), 0.1f}, .irradiance = {E, E, E}};
        assert_int_equal(prt_lighting_add(l, &sun, NULL), PRT_OK);
        const float *dn = prt_lighting_light(l, 0)->direction;
        prt_relit r;
        assert_int_equal(prt_relight(ctx, w, l, NULL, &r), PRT_OK);
        const float exact = 0.5f / (float)M_PI * E * dn[1];
        for (size_t v = 0; v < prt_transfer_vertex_count(w); ++v) assert_float_equal(r.radiance[v * 3], exact, 0.02f * exact);
        prt_relit_free(&r);
    }
    /* Point lights are local: the wavelet method refuses them and says who can. */
    prt_light bulb = {.type = PRT_LIGHT_POINT, .position = {0, 1, 0}, .intensity = {1, 1, 1}};
    assert_int_equal(prt_lighting_add(l, &bulb, NULL), PRT_OK);
    prt_relit r;
    assert_int_equal(prt_relight(ctx, w, l, NULL, &r), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "cannot relight point lights"));
    assert_non_null(strstr(prt_last_error(), "methods sh, spectral, lightcloud, offset can"));
    assert_null(r.radiance);
    prt_transfer_release(w);
    assert_int_equal(prt_method_check_lighting(prt_method_find("wavelet"), PRT_LIGHTS_DIRECTIONAL), PRT_OK);
    assert_int_equal(prt_method_check_lighting(prt_method_find("wavelet"), PRT_LIGHTS_SPHERE), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "method 'wavelet' cannot relight sphere lights"));
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A scene's lights, its "no environment" and its emission survive the bake and the file. */
static void test_file_keeps_lighting(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    char obj[512], mtl[512], json[512], out[512];
    snprintf(obj, sizeof obj, "%s/lamp.obj", test_dir);
    snprintf(mtl, sizeof mtl, "%s/lamp.mtl", test_dir);
    snprintf(json, sizeof json, "%s/lamp.json", test_dir);
    snprintf(out, sizeof out, "%s/lamp.prt", test_dir);
    FILE *f = fopen(mtl, "w");
    fprintf(f, "newmtl glow\nKd 0.5 0.5 0.5\nKe 4 3 2\nnewmtl floor\nKd 0.7 0.7 0.7\n");
    fclose(f);
    f = fopen(obj, "w");
    fprintf(f, "mtllib lamp.mtl\nv -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nv -0.1 1 0.1\nv 0.1 1 0.1\nv 0.1 1 -0.1\nv -0.1 1 -0.1\n"
               "usemtl floor\nf 1 2 3\nf 1 3 4\nusemtl glow\nf 5 8 7\nf 5 7 6\n");
    fclose(f);
    f = fopen(json, "w");
    fprintf(f, "{\"meshes\": [{\"file\": \"lamp.obj\"}], \"environment\": \"none\",\n"
               " \"lights\": [{\"type\": \"spot\", \"position\": [0, 2, 0], \"direction\": [0, -1, 0], \"angle\": 40, \"falloff\": 20, \"intensity\": [5, 4, 3]},\n"
               "            {\"type\": \"directional\", \"direction\": [0, 1, 0], \"irradiance\": 1.5}]}\n");
    fclose(f);
    prt_scene *scene = NULL;
    assert_int_equal(prt_scene_load(ctx, json, NULL, &scene), PRT_OK);
    prt_transfer *t = NULL, *u = NULL;
    prt_bake_desc d = {0};
    d.order = 3;
    d.samples = 64;
    assert_int_equal(prt_bake_sh(ctx, scene, &d, &t), PRT_OK);
    assert_int_equal(prt_transfer_save(t, out), PRT_OK);
    assert_int_equal(prt_transfer_load(ctx, out, &u), PRT_OK);
    assert_int_equal(prt_transfer_light_count(u), 2);
    assert_memory_equal(prt_transfer_light(u, 0), prt_scene_light(scene, 0), sizeof(prt_light));
    assert_memory_equal(prt_transfer_light(u, 1), prt_scene_light(scene, 1), sizeof(prt_light));
    assert_non_null(prt_transfer_emission(u));
    assert_memory_equal(prt_transfer_emission(u), prt_transfer_emission(t), prt_transfer_vertex_count(t) * 3 * sizeof(float));
    prt_environment_desc env;
    assert_true(prt_transfer_environment(u, &env));
    assert_true(env.none);
    prt_lighting *l = NULL;
    assert_int_equal(prt_transfer_lighting(ctx, u, &l), PRT_OK);
    assert_null(prt_lighting_envmap(l));
    assert_int_equal(prt_lighting_count(l), 2);
    assert_int_equal(prt_lighting_content(l), PRT_LIGHTS_SPOT | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_EMISSIVE);
    /* SH cannot relight the emissive lamp (the spot it can); without it the lights work. */
    prt_relit r;
    assert_int_equal(prt_relight(ctx, u, l, NULL, &r), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "cannot relight emissive surfaces"));
    prt_lighting_set_emission(l, 0);
    assert_int_equal(prt_relight(ctx, u, l, NULL, &r), PRT_OK);
    prt_relit_free(&r);
    /* The reference path tracer traces the file's scene: materials, emission and lights. */
    prt_scene *back = NULL;
    assert_int_equal(prt_transfer_scene(ctx, u, &back), PRT_OK);
    assert_int_equal(prt_scene_light_count(back), 2);
    assert_memory_equal(prt_scene_emission(back), prt_transfer_emission(u), prt_transfer_vertex_count(u) * 3 * sizeof(float));
    prt_scene_release(back);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_transfer_release(u);
    prt_scene_release(scene);
    prt_context_release(ctx);
}

/* Glossy transfer on a convex sphere (no shadows, no bounces) against the path tracer seeing it
 * from the same eye, under a smooth environment, Phong 8. Measured: SH order 5 with the BRDF
 * baked in 2.3% (the band-limited exit vector), with the lobe convolved at run time 6.9% (it
 * takes the BRDF's cosine at the mirror direction only), wavelet with 4 separable terms 3.5%;
 * reference noise 1.1%. */
static double glossy_vs_reference(prt_context *ctx, const prt_transfer *t, const prt_scene *scene, prt_envmap *env_for_ref,
                                  const prt_lighting *l, const float eye[3], double *noise)
{
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    assert_true(prt_relit_view_dependent(&r));
    const size_t nv = prt_transfer_vertex_count(t);
    float *rgb = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relit_shade(ctx, t, &r, eye, rgb), PRT_OK);
    prt_reference_desc rd = {0};
    rd.samples = 2048;
    rd.eye = eye;
    prt_reference_vertices ref;
    assert_int_equal(prt_reference_trace_vertices(ctx, scene, env_for_ref, &rd, &ref), PRT_OK);
    /* Only vertices that face the eye: the others show no glossy part. */
    const float *P = prt_transfer_positions(t), *N = prt_transfer_normals(t);
    double se = 0, sb = 0, sn = 0;
    for (size_t v = 0; v < nv; ++v) {
        float to_eye[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]};
        if (to_eye[0] * N[v * 3] + to_eye[1] * N[v * 3 + 1] + to_eye[2] * N[v * 3 + 2] <= 0) continue;
        for (int c = 0; c < 3; ++c) {
            double a = rgb[v * 3 + c], b = ref.radiance[v * 3 + c];
            se += (a - b) * (a - b);
            sb += b * b;
            sn += (double)ref.std_error[v * 3 + c] * ref.std_error[v * 3 + c];
        }
    }
    *noise = sqrt(sn / sb);
    free(rgb);
    prt_relit_free(&r);
    prt_reference_vertices_free(&ref);
    return sqrt(se / sb);
}

static void test_glossy_sphere_vs_reference(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    tm_sphere(&m, (float[3]){0, 0, 0}, 1.0f, 16, 32);
    prt_scene *scene = tm_scene(ctx, &m, 0.3f);
    prt_brdf phong;
    assert_int_equal(prt_brdf_parse("phong:8:0.5:0.3", &phong), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(scene, 0, prt_scene_vertex_count(scene), &phong), PRT_OK);
    prt_envmap *env = band_limited_env(128);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, env, NULL, 1.0f), PRT_OK);
    prt_envmap *ref_env = band_limited_env(128);
    const float eye[3] = {1.5f, 2.0f, 3.0f};
    double noise;

    prt_bake_desc d = {0};
    d.order = 5;
    d.samples = 4096;
    d.kinds = PRT_TRANSFER_SHADOWED | PRT_TRANSFER_GLOSSY_SHADOWED;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, scene, &d, &t), PRT_OK);
    double e_sh = glossy_vs_reference(ctx, t, scene, ref_env, l, eye, &noise);
    print_message("glossy SH order 5, lobe at run time, vs reference: %.4f (reference noise %.4f)\n", e_sh, noise);
    /* The run-time lobe takes the BRDF's cosine at the mirror direction only. */
    assert_true(e_sh < 0.08 + 2 * noise);
    prt_transfer_release(t);
    d.glossy_exit = 1;
    assert_int_equal(prt_bake_sh(ctx, scene, &d, &t), PRT_OK);
    e_sh = glossy_vs_reference(ctx, t, scene, ref_env, l, eye, &noise);
    print_message("glossy SH order 5, BRDF baked in, vs reference: %.4f (reference noise %.4f)\n", e_sh, noise);
    assert_true(e_sh < 0.03 + 2 * noise);
    prt_transfer_release(t);

    prt_wavelet_bake_desc wd = {0};
    wd.terms = 4;
    wd.coefficients = 512;
    wd.bits = 16;
    wd.supersample = 1;
    assert_int_equal(prt_bake_wavelet(ctx, scene, &wd, &t), PRT_OK);
    double e_w = glossy_vs_reference(ctx, t, scene, ref_env, l, eye, &noise);
    print_message("glossy wavelet K=4 vs reference: %.4f (reference noise %.4f)\n", e_w, noise);
    assert_true(e_w < 0.05 + 2 * noise);
    prt_transfer_release(t);

    prt_envmap_release(ref_env);
    prt_lighting_release(l);
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(ctx);
}

/* prt export through the table: a method's export options are checked against the file's method,
 * bake options are not export options, a refused export writes nothing, and one that succeeds
 * lists its files and hands back the attributes and colours the mesh must carry. */
static void test_export_through_table(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    prt_scene *scene = plate_and_box(ctx);
    const prt_method *sh = prt_method_find("sh");
    prt_options *o = NULL, *eo = NULL;
    assert_int_equal(prt_options_create(sh, &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "order", "4"), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "64"), PRT_OK);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, scene, sh, o, NULL, &t), PRT_OK);
    prt_lighting *l = NULL;
    assert_int_equal(prt_transfer_lighting(ctx, t, &l), PRT_OK);
    assert_int_equal(prt_export_options_create(sh, &eo), PRT_OK);
    assert_int_equal(prt_options_set(eo, "maps", "x"), PRT_ERR_INVALID_ARG);   /* another method's */
    assert_non_null(strstr(prt_last_error(), "export option of method offset"));
    assert_int_equal(prt_options_set(eo, "order", "3"), PRT_ERR_INVALID_ARG);   /* a bake option */
    prt_export_result r;
    prt_export_desc d = {.options = o, .lighting = l, .variant = -1, .mesh = PRT_EXPORT_MESH_GLTF};
    assert_int_equal(prt_transfer_export(ctx, t, &d, &r), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "export options"));
    char glsl[512];
    snprintf(glsl, sizeof glsl, "%s/x.glsl", test_dir);
    assert_int_equal(prt_options_set(eo, "glsl", glsl), PRT_OK);
    d.options = eo;
    d.mesh = PRT_EXPORT_MESH_OTHER;   /* PLY and OBJ have no custom attributes */
    assert_int_equal(prt_transfer_export(ctx, t, &d, &r), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "glTF"));
    assert_int_equal(access(glsl, F_OK), -1);
    d.mesh = PRT_EXPORT_MESH_GLTF;
    assert_int_equal(prt_transfer_export(ctx, t, &d, &r), PRT_OK);
    assert_int_equal(r.attribute_count, 7);   /* interreflected: 3 channels x 9 coefficients, in VEC4s */
    assert_non_null(r.attributes);
    assert_non_null(r.radiance);
    assert_int_equal(r.file_count, 1);
    assert_string_equal(r.files[0], glsl);
    assert_int_equal(access(glsl, F_OK), 0);
    assert_non_null(strstr(r.report, glsl));
    /* The colours are relit at the attributes' order 3: what the shader gives under the lighting. */
    const int three[2] = {3, 0};   /* order 3, no window */
    prt_relight_desc rd = {.variant = prt_transfer_default_variant(t, 0), .per_vertex = 1, .controls = three};
    prt_relit rl;
    assert_int_equal(prt_relight(ctx, t, l, &rd, &rl), PRT_OK);
    assert_memory_equal(rl.radiance, r.radiance, prt_transfer_vertex_count(t) * 3 * sizeof(float));
    prt_relit_free(&rl);
    prt_export_result_free(&r);
    /* Unwritable: nothing is left, and the error says where. */
    snprintf(glsl, sizeof glsl, "%s/no/such/dir/x.glsl", test_dir);
    assert_int_equal(prt_options_set(eo, "glsl", glsl), PRT_OK);
    assert_int_equal(prt_transfer_export(ctx, t, &d, &r), PRT_ERR_IO);
    assert_non_null(strstr(prt_last_error(), "x.glsl"));
    assert_null(r.files);
    /* A file whose method exports nothing of its own takes no options, and exports nothing. */
    prt_options_release(o);
    assert_int_equal(prt_options_create(prt_method_find("spectral"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "64"), PRT_OK);
    assert_int_equal(prt_options_set(o, "basis", "16"), PRT_OK);
    prt_transfer *u = NULL;
    assert_int_equal(prt_bake(ctx, scene, prt_method_find("spectral"), o, NULL, &u), PRT_OK);
    assert_int_equal(prt_method_export_options(prt_transfer_method(u), NULL), 0);
    d.options = NULL;
    assert_int_equal(prt_transfer_export(ctx, u, &d, &r), PRT_OK);
    assert_int_equal(r.attribute_count + r.file_count, 0);
    assert_null(r.radiance);
    prt_export_result_free(&r);
    prt_transfer_release(u);
    prt_options_release(eo);
    prt_options_release(o);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(scene);
    prt_context_release(ctx);
}

/* Every method, through the table: the file is the same, byte for byte outside META, whatever
 * the thread count (compression included). */
static void test_files_independent_of_threads(void **state)
{
    (void)state;
    prt_context *one = test_context(1), *two = test_context(2);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 8);
    tm_sphere(&m, (float[3]){0, 0.45f, 0}, 0.4f, 6, 10);
    prt_scene *scene = tm_scene(two, &m, 0.6f);
    prt_brdf phong;
    assert_int_equal(prt_brdf_parse("phong:12:0.4:0.3", &phong), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(scene, 81, prt_scene_vertex_count(scene) - 81, &phong), PRT_OK);
    for (int mi = 0; mi < prt_method_count(); ++mi) {
        const prt_method *method = prt_method_at(mi);
        prt_options *o = NULL;
        assert_int_equal(prt_options_create(method, &o), PRT_OK);
        if (prt_method_option(method, "samples")) assert_int_equal(prt_options_set(o, "samples", "128"), PRT_OK);
        if (prt_method_option(method, "compress")) assert_int_equal(prt_options_set(o, "compress", "cpca"), PRT_OK);
        if (prt_method_option(method, "clusters")) assert_int_equal(prt_options_set(o, "clusters", "4"), PRT_OK);
        if (prt_method_option(method, "supersample")) assert_int_equal(prt_options_set(o, "supersample", "1"), PRT_OK);
        if (prt_method_option(method, "brdf-res")) assert_int_equal(prt_options_set(o, "brdf-res", "8"), PRT_OK);
        if (prt_method_option(method, "cloud-grid")) assert_int_equal(prt_options_set(o, "cloud-grid", "3,2,3"), PRT_OK);
        if (prt_method_option(method, "bounces") && prt_method_option(method, "gather-res")) {
            assert_int_equal(prt_options_set(o, "bounces", "1"), PRT_OK);
            assert_int_equal(prt_options_set(o, "gather-res", "8"), PRT_OK);
        }
        prt_transfer *a = NULL, *b = NULL;
        assert_int_equal(prt_bake(one, scene, method, o, NULL, &a), PRT_OK);
        assert_int_equal(prt_bake(two, scene, method, o, NULL, &b), PRT_OK);
        assert_same_file(a, b, prt_method_name(method));
        prt_transfer_release(a);
        prt_transfer_release(b);
        prt_options_release(o);
    }
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(one);
    prt_context_release(two);
}

/* Per-texel SH sets of a table bake (16-bit by default) are stored as halves: the file is half
 * the floats' size, loads to exactly what the bake holds, and stays within 2^-11 of the floats
 * that --quantize 32 keeps. */
static void test_texel_halves(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *scene = plate_and_box(ctx);
    const prt_method *sh = prt_method_find("sh");
    prt_transfer *t[2] = {NULL, NULL};
    for (int k = 0; k < 2; ++k) {
        prt_options *o = NULL;
        assert_int_equal(prt_options_create(sh, &o), PRT_OK);
        assert_int_equal(prt_options_set(o, "order", "3"), PRT_OK);
        assert_int_equal(prt_options_set(o, "samples", "64"), PRT_OK);
        assert_int_equal(prt_options_set(o, "texels", "32"), PRT_OK);
        assert_int_equal(prt_options_set(o, "kinds", "shadowed"), PRT_OK);
        if (k) assert_int_equal(prt_options_set(o, "quantize", "32"), PRT_OK);
        assert_int_equal(prt_bake(ctx, scene, sh, o, NULL, &t[k]), PRT_OK);
        prt_options_release(o);
    }
    int w, h, ch, ch32;
    assert_int_equal(prt_transfer_texel_size(t[0], &w, &h), 1);
    const float *half = prt_transfer_texel_coeffs(t[0], PRT_TRANSFER_SHADOWED, &ch), *full = prt_transfer_texel_coeffs(t[1], PRT_TRANSFER_SHADOWED, &ch32);
    assert_non_null(half);
    assert_non_null(full);
    const size_t n = (size_t)w * h * ch * 9;
    for (size_t i = 0; i < n; ++i) assert_true(fabsf(half[i] - full[i]) <= fabsf(full[i]) * (1.0f / 2048) + 6e-8f);
    char path[2][600];
    size_t bytes[2];
    for (int k = 0; k < 2; ++k) {
        snprintf(path[k], sizeof path[k], "%s/texels%d.prt", test_dir, k);
        assert_int_equal(prt_transfer_save(t[k], path[k]), PRT_OK);
        unsigned char *d = test_slurp(path[k], &bytes[k]);
        /* Halves need format version 2 (a reader of version 1 would skip them); floats stay 1. */
        assert_int_equal(d[8], k ? 1 : 2);
        free(d);
    }
    print_message("32 x 32 texels, order 3: %zu bytes with halves, %zu with floats\n", bytes[0], bytes[1]);
    assert_true(bytes[0] + (size_t)w * h * ch * 9 * 2 <= bytes[1] + 64);
    prt_transfer *back = NULL;
    assert_int_equal(prt_transfer_load(ctx, path[0], &back), PRT_OK);
    assert_memory_equal(prt_transfer_texel_coeffs(back, PRT_TRANSFER_SHADOWED, &ch), half, n * sizeof(float));
    prt_transfer_release(back);
    prt_transfer_release(t[0]);
    prt_transfer_release(t[1]);
    prt_scene_release(scene);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_options),
        cmocka_unit_test(test_bake_through_table),
        cmocka_unit_test(test_directional_light),
        cmocka_unit_test(test_file_keeps_lighting),
        cmocka_unit_test(test_glossy_sphere_vs_reference),
        cmocka_unit_test(test_files_independent_of_threads),
        cmocka_unit_test(test_export_through_table),
        cmocka_unit_test(test_texel_halves),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
