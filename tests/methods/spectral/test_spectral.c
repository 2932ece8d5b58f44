/* Direct-to-indirect transfer in a spectral mesh basis: the basis (partitions, orthonormality,
 * exact projection), direct light against closed forms, the white furnace, run-time albedo
 * against a rebake, the Cornell box against the path tracer, files. */
#include "common.h"

static prt_options *spectral_options(const char *functions, const char *partition, const char *samples)
{
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("spectral"), &o), PRT_OK);
    if (functions) assert_int_equal(prt_options_set(o, "basis", functions), PRT_OK);
    if (partition) assert_int_equal(prt_options_set(o, "partition", partition), PRT_OK);
    if (samples) assert_int_equal(prt_options_set(o, "samples", samples), PRT_OK);
    return o;
}

static prt_transfer *bake(prt_context *ctx, const prt_scene *s, const char *functions, const char *partition, const char *samples)
{
    prt_options *o = spectral_options(functions, partition, samples);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, s, prt_method_find("spectral"), o, NULL, &t), PRT_OK);
    prt_options_release(o);
    return t;
}

/* Closed box of side 1 (inward normals, n x n cells per face), floor at y = 0. */
static void closed_box(test_mesh *m, int n)
{
    tm_pit(m, n);
    tm_quad(m, (float[3]){-0.5f, 1, -0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, 1}, n);   /* ceiling, facing down */
}

/* Per partition: the functions are orthonormal over its vertices; with every function kept,
 * projecting and reconstructing gives the signal back. */
static void check_basis(const prt_transfer *t, bool full)
{
    prt_spectral_info info;
    assert_true(prt_transfer_spectral_info(t, &info));
    const size_t nv = prt_transfer_vertex_count(t);
    int *members = calloc((size_t)info.partitions, sizeof(int));
    int *firsts = malloc((size_t)info.partitions * sizeof(int)), *counts = malloc((size_t)info.partitions * sizeof(int));
    for (int p = 0; p < info.partitions; ++p) firsts[p] = -1;
    for (size_t v = 0; v < nv; ++v) {
        int p, first, count;
        const float *val;
        assert_true(prt_transfer_spectral_vertex(t, v, &p, &first, &count, &val));
        assert_in_range(p, 0, info.partitions - 1);
        if (firsts[p] < 0) { firsts[p] = first; counts[p] = count; }
        assert_int_equal(firsts[p], first);
        assert_int_equal(counts[p], count);
        members[p]++;
    }
    int total = 0;
    for (int p = 0; p < info.partitions; ++p) {
        assert_true(members[p] > 0);                 /* no empty partition */
        assert_true(counts[p] >= 1 && counts[p] <= members[p]);
        if (full) assert_int_equal(counts[p], members[p]);
        total += counts[p];
    }
    assert_int_equal(total, info.functions);
    /* Gram matrices, accumulated over each partition's vertices. */
    for (int p = 0; p < info.partitions; ++p) {
        const int k = counts[p];
        double *G = calloc((size_t)k * k, sizeof(double));
        for (size_t v = 0; v < nv; ++v) {
            int q;
            const float *val;
            prt_transfer_spectral_vertex(t, v, &q, NULL, NULL, &val);
            if (q != p) continue;
            for (int a = 0; a < k; ++a)
                for (int b = 0; b < k; ++b) G[a * k + b] += (double)val[a] * val[b];
        }
        for (int a = 0; a < k; ++a)
            for (int b = 0; b < k; ++b) assert_float_equal(G[a * k + b], a == b ? 1.0 : 0.0, 2e-4);
        free(G);
    }
    /* Projection and back. */
    float *signal = malloc(nv * 3 * sizeof(float)), *back = malloc(nv * 3 * sizeof(float));
    float *coeffs = malloc((size_t)info.functions * 3 * sizeof(float));
    srand(7);
    for (size_t i = 0; i < nv * 3; ++i) signal[i] = (float)rand() / (float)RAND_MAX;
    assert_int_equal(prt_spectral_project(t, signal, coeffs), PRT_OK);
    assert_int_equal(prt_spectral_reconstruct(t, coeffs, back), PRT_OK);
    if (full)
        for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(back[i], signal[i], 2e-3);
    /* Any basis keeps the constant of each connected piece: a constant signal comes back. */
    for (size_t i = 0; i < nv * 3; ++i) signal[i] = 0.25f;
    prt_spectral_project(t, signal, coeffs);
    prt_spectral_reconstruct(t, coeffs, back);
    for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(back[i], 0.25f, 1e-3);
    free(signal); free(back); free(coeffs);
    free(members); free(firsts); free(counts);
}

static void test_basis(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    /* Six separate faces, a sphere and a lone triangle: pieces that METIS must place somewhere. */
    test_mesh m = {0};
    closed_box(&m, 8);
    tm_sphere(&m, (float[3]){0, 0.4f, 0}, 0.2f, 10, 14);
    const uint32_t base = (uint32_t)m.nv;
    tm_vertex(&m, 0.1f, 0.05f, 0.1f, 0, 1, 0);
    tm_vertex(&m, 0.15f, 0.05f, 0.1f, 0, 1, 0);
    tm_vertex(&m, 0.1f, 0.05f, 0.05f, 0, 1, 0);
    tm_tri(&m, base, base + 2, base + 1);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    const size_t nv = prt_scene_vertex_count(s);
    char all[32];
    snprintf(all, sizeof all, "%zu", nv);
    prt_transfer *t = bake(ctx, s, all, "120", "16");
    prt_spectral_info info;
    assert_true(prt_transfer_spectral_info(t, &info));
    assert_true(info.partitions >= (int)(nv / 120) && info.partitions <= (int)(nv / 120) + 2);
    check_basis(t, true);
    prt_transfer_release(t);
    /* A truncated basis: about the functions asked for, at least one per partition. */
    t = bake(ctx, s, "64", "120", "16");
    assert_true(prt_transfer_spectral_info(t, &info));
    assert_true(info.functions >= 64 - info.partitions && info.functions <= 64 + info.partitions);
    check_basis(t, false);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    /* A mesh smaller than one partition is one partition with every function. */
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 4);
    s = tm_scene(ctx, &m, 0.5f);
    t = bake(ctx, s, NULL, NULL, "16");
    assert_true(prt_transfer_spectral_info(t, &info));
    assert_int_equal(info.partitions, 1);
    assert_int_equal(info.functions, 25);
    check_basis(t, true);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A lone plane sees nothing but the lights: direct light is the closed form, indirect is zero. */
static void test_direct_closed_forms(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 12);
    const float rho = 0.5f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    prt_transfer *t = bake(ctx, s, "32", NULL, "64");
    const size_t nv = prt_transfer_vertex_count(t);
    const float *P = prt_transfer_positions(t);
    const char *specs[3] = {"point:0.3,1,-0.2:2", "spot:0,1.5,0:0,-1,0:40,30:3", "directional:0.3,1,0.2:1.5"};
    for (int i = 0; i < 3; ++i) {
        prt_lighting *l = NULL;
        prt_light li;
        assert_int_equal(prt_lighting_create(&l), PRT_OK);
        assert_int_equal(prt_light_parse(specs[i], &li), PRT_OK);
        assert_int_equal(prt_lighting_add(l, &li, NULL), PRT_OK);
        prt_relit r;
        prt_relight_desc d = {.variant = -1, .with_indirect = 1, .per_vertex = 1};
        assert_int_equal(prt_relight(ctx, t, l, &d, &r), PRT_OK);
        assert_non_null(r.indirect);
        assert_null(r.pixel_lights);   /* per vertex: radiance holds all the light */
        for (size_t v = 0; v < nv; ++v) {
            float e[3];
            prt_light_irradiance(prt_lighting_light(l, 0), P + v * 3, (float[3]){0, 1, 0}, e);
            const float exact = rho / (float)M_PI * e[0];
            assert_float_equal(r.radiance[v * 3], exact, 2e-3f * exact + 1e-6f);
            assert_float_equal(r.indirect[v * 3], 0.0f, 1e-6f);
        }
        prt_relit_free(&r);
        prt_lighting_release(l);
    }
    /* A uniform environment of radiance 2: E = 2 pi, radiance 2 rho, through the baked SH transfer. */
    prt_image img = {16, 8, malloc(16 * 8 * 3 * sizeof(float))};
    for (int i = 0; i < 16 * 8 * 3; ++i) img.rgb[i] = 2.0f;
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, env, NULL, 1.0f), PRT_OK);
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r), PRT_OK);
    for (size_t v = 0; v < nv; ++v) assert_float_equal(r.radiance[v * 3 + 1], 2.0f * rho, 2e-3f);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* White furnace: every wall of a closed box emits L_e and reflects rho. Direct light is rho L_e
 * everywhere (a closed box's walls see emitters in every direction) and bounce k adds
 * rho^(k+1) L_e, so N bounces give L_e (1 + rho + ... + rho^(N+1)). */
static void test_white_furnace(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 10);
    const float rho = 0.6f, le = 1.5f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    assert_int_equal(prt_scene_set_emission(s, 0, prt_scene_vertex_count(s), (float[3]){le, le, le}), PRT_OK);
    prt_transfer *t = bake(ctx, s, "96", "150", "1024");
    const size_t nv = prt_transfer_vertex_count(t);
    prt_lighting *l = NULL;
    assert_int_equal(prt_transfer_lighting(ctx, t, &l), PRT_OK);
    prt_lighting_set_environment(l, &(prt_environment_desc){.none = 1});
    const int bounce_counts[4] = {0, 1, 3, 8};
    for (int i = 0; i < 4; ++i) {
        const int n = bounce_counts[i], controls[2] = {n, 0};   /* exactly n bounces: no tail */
        prt_relight_desc d = {.variant = -1, .controls = controls};
        prt_relit r;
        assert_int_equal(prt_relight(ctx, t, l, &d, &r), PRT_OK);
        double expect = 0, term = 1, mean = 0, worst = 0;
        for (int k = 0; k <= n + 1; ++k, term *= rho) expect += term;
        expect *= le;
        for (size_t v = 0; v < nv; ++v) {
            mean += r.radiance[v * 3 + 1] / nv;
            worst = fmax(worst, fabs(r.radiance[v * 3 + 1] - expect) / expect);
        }
        print_message("furnace, %d bounces: mean %.5f, expected %.5f, worst vertex %.2f%% off\n", n, mean, expect, 100 * worst);
        assert_float_equal(mean, expect, 0.003 * expect);
        assert_true(worst < 0.01);
        prt_relit_free(&r);
    }
    /* The defaults (3 bounces and the tail): every wall keeps rho of the power bounce after bounce,
     * so the tail's ratio is rho and the whole series L_e / (1 - rho) comes out. */
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1}, &r), PRT_OK);
    double mean = 0, worst = 0;
    const double expect = le / (1 - rho);
    for (size_t v = 0; v < nv; ++v) {
        mean += r.radiance[v * 3 + 1] / nv;
        worst = fmax(worst, fabs(r.radiance[v * 3 + 1] - expect) / expect);
    }
    print_message("furnace, defaults: mean %.5f, expected %.5f, worst vertex %.2f%% off\n", mean, expect, 100 * worst);
    assert_float_equal(mean, expect, 0.003 * expect);
    assert_true(worst < 0.01);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Relative L2 of a's indirect part against b's, and the ratio of their sums; worst: the largest
 * excess of a over b, relative, where b holds a fair share of light (over a tenth of its mean). */
static void indirect_vs(const prt_relit *a, const prt_relit *b, double *l2, double *ratio, double *worst)
{
    const size_t n = a->vertex_count * 3;
    double se = 0, sb = 0, sa = 0, s = 0;
    for (size_t i = 0; i < n; ++i) s += b->indirect[i];
    *worst = -1;
    for (size_t i = 0; i < n; ++i) {
        const double x = a->indirect[i], y = b->indirect[i];
        se += (x - y) * (x - y);
        sb += y * y;
        sa += x;
        if (y > 0.1 * s / (double)n) *worst = fmax(*worst, (x - y) / y);
    }
    *l2 = sqrt(se / sb);
    *ratio = sa / s;
}

/* Defaults that converge: a closed room of albedo 0.7 under a point light keeps 1 - 0.7^3 of its
 * indirect light in three bounces; the default tail brings back the rest. Against 64 bounces
 * (tight: deterministic) and the path tracer (looser: its noise); in an open scene the tail adds no
 * light the bounces past the third would not. */
static void test_defaults_converge(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    for (int open = 0; open < 2; ++open) {
        test_mesh m = {0};
        if (open) {   /* a floor and one wall: most light leaves at every bounce */
            tm_quad(&m, (float[3]){-0.5f, 0, 0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, -1}, 12);
            tm_quad(&m, (float[3]){-0.5f, 0, -0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 1, 0}, 12);
        } else {
            closed_box(&m, 10);
        }
        tm_sphere(&m, (float[3]){0.1f, 0.25f, 0.05f}, 0.2f, 10, 14);
        prt_scene *s = tm_scene(ctx, &m, open ? 0.8f : 0.7f);
        prt_transfer *t = bake(ctx, s, NULL, NULL, NULL);   /* the bake's defaults too */
        prt_lighting *l = NULL;
        prt_light bulb;
        assert_int_equal(prt_lighting_create(&l), PRT_OK);
        assert_int_equal(prt_light_parse("point:-0.2,0.8,0.25:1", &bulb), PRT_OK);
        assert_int_equal(prt_lighting_add(l, &bulb, NULL), PRT_OK);
        const int all[2] = {64, 0}, three[2] = {3, 0};
        prt_relit def, full, cut;
        assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .with_indirect = 1}, &def), PRT_OK);
        assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .with_indirect = 1, .controls = all}, &full), PRT_OK);
        assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .with_indirect = 1, .controls = three}, &cut), PRT_OK);
        double l2, ratio, worst, l2_cut, ratio_cut, worst_cut;
        indirect_vs(&def, &full, &l2, &ratio, &worst);
        indirect_vs(&cut, &full, &l2_cut, &ratio_cut, &worst_cut);
        print_message("%s: defaults against 64 bounces: indirect %.4f, sum %.4f, worst excess %+.4f (3 bounces without the tail: %.4f, sum %.4f)\n",
                      open ? "floor and wall, albedo 0.8" : "closed room, albedo 0.7", l2, ratio, worst, l2_cut, ratio_cut);
        if (!open) {
            assert_true(ratio_cut < 0.8);   /* what the tail mends */
            assert_true(l2 < 0.035);
            assert_float_equal(ratio, 1.0, 0.01);
            assert_true(worst < 0.1);
            /* The same to the bit on one thread. */
            prt_context *one = test_context(1);
            prt_relit solo;
            assert_int_equal(prt_relight(one, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .with_indirect = 1}, &solo), PRT_OK);
            assert_memory_equal(solo.indirect, def.indirect, def.vertex_count * 3 * sizeof(float));
            prt_relit_free(&solo);
            prt_context_release(one);
            /* Direct light only stays direct light only. */
            prt_relit direct;
            assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_DIRECT}, &direct), PRT_OK);
            for (size_t i = 0; i < def.vertex_count * 3; ++i) assert_float_equal(direct.radiance[i], def.radiance[i] - def.indirect[i], 1e-6f + 1e-5f * def.radiance[i]);
            prt_relit_free(&direct);
            /* And the path tracer. */
            prt_scene *traced = NULL;
            assert_int_equal(prt_transfer_scene(ctx, t, &traced), PRT_OK);
            prt_reference_desc rd = {0};
            rd.samples = 256;
            rd.lighting = l;
            prt_reference_vertices ref;
            assert_int_equal(prt_reference_trace_vertices(ctx, traced, NULL, &rd, &ref), PRT_OK);
            double e[4], e_cut[4];
            vs_reference(def.radiance, def.indirect, &ref, def.vertex_count, NULL, e);
            vs_reference(cut.radiance, cut.indirect, &ref, def.vertex_count, NULL, e_cut);
            print_message("closed room against the path tracer: indirect %.4f (reference noise %.4f; 3 bounces without the tail %.4f)\n", e[2], e[3], e_cut[2]);
            assert_true(e[2] < e[3] + 0.03);
            prt_reference_vertices_free(&ref);
            prt_scene_release(traced);
        } else {
            assert_true(l2 < 0.6 * l2_cut);   /* half the error of stopping at three */
            assert_true(ratio < 1.005);
            assert_true(worst < 0.08);
        }
        prt_relit_free(&def);
        prt_relit_free(&full);
        prt_relit_free(&cut);
        prt_lighting_release(l);
        prt_transfer_release(t);
        prt_scene_release(s);
        tm_free(&m);
    }
    prt_context_release(ctx);
}

/* A scene for colour changes: a closed box with a sphere, lit by a point light. */
static prt_scene *room(prt_context *ctx, test_mesh *m, const float *albedo)
{
    closed_box(m, 8);
    tm_sphere(m, (float[3]){0.15f, 0.3f, 0.1f}, 0.2f, 10, 14);
    prt_scene_desc sd = {0};
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, m->pos, m->nrm, albedo, m->nv, m->idx, m->nt, &sd, &s), PRT_OK);
    return s;
}

/* Surface colours change at run time and give exactly what a bake with those colours gives. */
static void test_albedo_at_run_time(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 8);
    tm_sphere(&m, (float[3]){0.15f, 0.3f, 0.1f}, 0.2f, 10, 14);
    const size_t nv = m.nv;
    tm_free(&m);
    float *grey = malloc(nv * 3 * sizeof(float)), *painted = malloc(nv * 3 * sizeof(float));
    for (size_t i = 0; i < nv * 3; ++i) grey[i] = painted[i] = 0.6f;
    for (size_t v = 0; v < 81; ++v) { painted[v * 3] = 0.9f; painted[v * 3 + 1] = 0.2f; painted[v * 3 + 2] = 0.1f; }   /* the floor */
    prt_scene *a = room(ctx, &m, grey);
    tm_free(&m);
    prt_scene *b = room(ctx, &m, painted);
    tm_free(&m);
    prt_transfer *ta = bake(ctx, a, "128", "200", "256"), *tb = bake(ctx, b, "128", "200", "256");
    prt_lighting *l = NULL;
    prt_light bulb;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_light_parse("point:-0.2,0.8,0.1:1", &bulb), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &bulb, NULL), PRT_OK);
    prt_relight_desc d = {.variant = -1, .albedo = painted, .with_indirect = 1, .per_vertex = 1};
    prt_relit live, rebaked, plain;
    assert_int_equal(prt_relight(ctx, ta, l, &d, &live), PRT_OK);
    assert_int_equal(prt_relight(ctx, tb, l, &(prt_relight_desc){.variant = -1, .with_indirect = 1, .per_vertex = 1}, &rebaked), PRT_OK);
    assert_int_equal(prt_relight(ctx, ta, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1}, &plain), PRT_OK);
    double diff = 0, change = 0;
    for (size_t i = 0; i < nv * 3; ++i) {
        assert_float_equal(live.radiance[i], rebaked.radiance[i], 1e-5f + 1e-4f * rebaked.radiance[i]);
        assert_float_equal(live.indirect[i], rebaked.indirect[i], 1e-5f + 1e-4f * rebaked.indirect[i]);
        diff += fabs(live.radiance[i] - plain.radiance[i]);
        change += plain.radiance[i];
    }
    assert_true(diff > 0.05 * change);   /* the new colours did change the picture */
    /* The red floor bleeds onto the walls: their indirect light turns red. */
    double red = 0, blue = 0;
    for (size_t v = 81; v < 5 * 81; ++v) { red += live.indirect[v * 3]; blue += live.indirect[v * 3 + 2]; }
    print_message("walls, indirect: red %.4f, blue %.4f\n", red, blue);
    assert_true(red > 1.2 * blue);   /* grey everywhere: red = blue */
    prt_relit_free(&live);
    prt_relit_free(&rebaked);
    prt_relit_free(&plain);
    /* Colours outside [0, 1], and other methods, are refused. */
    painted[5] = 1.5f;
    assert_int_equal(prt_relight(ctx, ta, l, &d, &live), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "albedo"));
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("sh"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "64"), PRT_OK);
    prt_transfer *sh = NULL;
    assert_int_equal(prt_bake(ctx, a, prt_method_find("sh"), o, NULL, &sh), PRT_OK);
    prt_lighting *sky = NULL;
    assert_int_equal(prt_transfer_lighting(ctx, sh, &sky), PRT_OK);
    painted[5] = 0.5f;
    assert_int_equal(prt_relight(ctx, sh, sky, &d, &live), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "needs a rebake"));
    assert_false(prt_method_runtime_albedo(prt_method_find("sh")));
    assert_true(prt_method_runtime_albedo(prt_method_find("spectral")));
    prt_lighting_release(sky);
    prt_transfer_release(sh);
    prt_options_release(o);
    prt_lighting_release(l);
    prt_transfer_release(ta);
    prt_transfer_release(tb);
    prt_scene_release(a);
    prt_scene_release(b);
    free(grey);
    free(painted);
    prt_context_release(ctx);
}

/* Files keep everything: relighting a loaded file gives the same light; the description names
 * partitions, functions and coefficients. */
static void test_file_round_trip(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    prt_scene *s = room(ctx, &m, NULL);
    prt_transfer *t = bake(ctx, s, "100", "200", "128");
    char path[1024];
    snprintf(path, sizeof path, "%s/room.prt", test_dir);
    if (prt_transfer_save(t, path)) fail_msg("%s", prt_last_error());
    prt_transfer *u = NULL;
    assert_int_equal(prt_transfer_load(ctx, path, &u), PRT_OK);
    prt_spectral_info a, b;
    assert_true(prt_transfer_spectral_info(t, &a));
    assert_true(prt_transfer_spectral_info(u, &b));
    assert_memory_equal(&a, &b, sizeof a);
    prt_lighting *l = NULL;
    prt_light lamp;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_light_parse("sphere:0,0.8,0:0.05:20", &lamp), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &lamp, NULL), PRT_OK);
    prt_relit r1, r2;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &r1), PRT_OK);
    assert_int_equal(prt_relight(ctx, u, l, NULL, &r2), PRT_OK);
    assert_memory_equal(r1.radiance, r2.radiance, prt_transfer_vertex_count(t) * 3 * sizeof(float));
    char *json = NULL;
    assert_int_equal(prt_transfer_describe(u, "room.prt", 1, &json), PRT_OK);
    assert_non_null(strstr(json, "\"partitions\""));
    assert_non_null(strstr(json, "\"coefficients_per_vertex\""));
    assert_non_null(strstr(json, "\"functions_per_partition\""));
    free(json);
    prt_relit_free(&r1);
    prt_relit_free(&r2);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_transfer_release(u);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Drawn, the local lights' direct light comes per pixel from the renderer with shadow maps: lit
 * floor pixels equal the closed form plus the per-vertex indirect light, pixels in an occluder's
 * shadow get only the indirect light. */
static void test_pixel_lights(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 16);
    tm_quad(&m, (float[3]){-0.2f, 0.5f, 0.2f}, (float[3]){0.4f, 0, 0}, (float[3]){0, 0, -0.4f}, 2);   /* occluder */
    const float rho = 0.5f;
    prt_scene *s = tm_scene(ctx, &m, rho);
    prt_transfer *t = bake(ctx, s, "64", NULL, "256");
    prt_lighting *l = NULL;
    prt_light bulb;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_light_parse("point:0,1,0:2", &bulb), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &bulb, NULL), PRT_OK);
    prt_relit r;
    prt_relight_desc d = {.variant = -1, .with_indirect = 1};
    assert_int_equal(prt_relight(ctx, t, l, &d, &r), PRT_OK);
    assert_int_equal(r.pixel_light_count, 1);
    /* Per vertex (prt_relit_shade) the light is back, with shadow rays. */
    const size_t nv = prt_transfer_vertex_count(t);
    float *shaded = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relit_shade(ctx, t, &r, NULL, shaded), PRT_OK);
    const float *P = prt_transfer_positions(t);
    prt_renderer *ren = NULL;
    assert_int_equal(prt_renderer_create(ctx, &(prt_renderer_desc){128, 128, 1}, &ren), PRT_OK);
    prt_render_mesh rm;
    prt_relit_render_mesh(t, &r, &rm);
    /* Looking straight down: x to the right, -z up the image. */
    const prt_camera cam = {{0, 3, 0}, {0, 0, 0}, {0, 0, -1}, 30};
    prt_image img;
    assert_int_equal(prt_render(ren, &rm, &cam, NULL, &img), PRT_OK);
    const float half = 3.0f * tanf(15.0f * (float)M_PI / 180.0f);
    const float spots[3][3] = {{0.6f, 0, 0.6f}, {-0.7f, 0, 0.3f}, {0.32f, 0, 0.0f}};   /* lit, lit, in the shadow */
    for (int i = 0; i < 3; ++i) {
        const int px = (int)((spots[i][0] / half + 1) * 64), py = (int)((spots[i][2] / half + 1) * 64);
        const float pixel = img.rgb[((size_t)py * 128 + px) * 3];
        /* The pixel's own world point (pixel centre) and the nearest vertex's indirect light. */
        const float wx = ((px + 0.5f) / 64 - 1) * half, wz = ((py + 0.5f) / 64 - 1) * half;
        const size_t v = nearest_vertex(P, nv, (float[3]){wx, 0, wz});
        float e[3];
        prt_light_irradiance(&bulb, (float[3]){wx, 0, wz}, (float[3]){0, 1, 0}, e);
        const float direct = i < 2 ? rho / (float)M_PI * e[0] : 0.0f;
        print_message("pixel at (%.2f, %.2f): %.5f, expected %.5f + indirect %.5f (vertex shaded %.5f)\n", wx, wz, pixel, direct, r.indirect[v * 3],
                      shaded[v * 3]);
        assert_float_equal(pixel, direct + r.indirect[v * 3], 0.03f * (direct + r.indirect[v * 3]) + 2e-3f);
    }
    prt_image_free(&img);
    prt_renderer_release(ren);
    free(shaded);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The glossy final bounce (eq. 8): a glossy floor in front of a glowing wall reflects the wall
 * view-dependently, as the path tracer sees it from the same eye (the floor's glossy part comes
 * only through the bounce: the wall is its only light). */
static void test_glossy_final_bounce(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    tm_quad(&m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 16);   /* floor, up */
    const size_t floor_nv = m.nv;
    tm_quad(&m, (float[3]){-1, 0, -1}, (float[3]){2, 0, 0}, (float[3]){0, 1, 0}, 8);    /* wall at z = -1, facing +z */
    float *albedo = malloc(m.nv * 3 * sizeof(float));
    for (size_t i = 0; i < m.nv * 3; ++i) albedo[i] = i < floor_nv * 3 ? 0.3f : 0.0f;
    prt_scene_desc sd = {0};
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, m.pos, m.nrm, albedo, m.nv, m.idx, m.nt, &sd, &s), PRT_OK);
    prt_brdf phong;
    assert_int_equal(prt_brdf_parse("phong:8:0.3:0.5", &phong), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, 0, floor_nv, &phong), PRT_OK);
    assert_int_equal(prt_scene_set_emission(s, floor_nv, prt_scene_vertex_count(s) - floor_nv, (float[3]){1, 1, 1}), PRT_OK);
    prt_transfer *t = bake(ctx, s, "256", NULL, "2048");
    char *text = NULL;
    assert_int_equal(prt_transfer_describe(t, "glossy", 0, &text), PRT_OK);
    assert_non_null(strstr(text, "glossy final bounce"));
    free(text);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);   /* the wall alone */
    const float eye[3] = {0, 0.6f, 2.5f};
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1}, &r), PRT_OK);
    assert_true(prt_relit_view_dependent(&r));
    const size_t nv = prt_transfer_vertex_count(t);
    float *ours = malloc(nv * 3 * sizeof(float)), *flat = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relit_shade(ctx, t, &r, eye, ours), PRT_OK);
    memcpy(flat, r.radiance, nv * 3 * sizeof(float));
    prt_scene *traced = NULL;
    assert_int_equal(prt_transfer_scene(ctx, t, &traced), PRT_OK);
    prt_reference_desc rd = {0};
    rd.samples = 1024;
    rd.lighting = l;
    rd.eye = eye;
    prt_reference_vertices ref;
    assert_int_equal(prt_reference_trace_vertices(ctx, traced, NULL, &rd, &ref), PRT_OK);
    double se = 0, sf = 0, sb = 0, sn = 0;
    for (size_t i = 0; i < floor_nv * 3; ++i) {
        se += ((double)ours[i] - ref.radiance[i]) * ((double)ours[i] - ref.radiance[i]);
        sf += ((double)flat[i] - ref.radiance[i]) * ((double)flat[i] - ref.radiance[i]);
        sb += (double)ref.radiance[i] * ref.radiance[i];
        sn += (double)ref.std_error[i] * ref.std_error[i];
    }
    print_message("glossy floor vs path tracer: %.4f with the glossy bounce, %.4f without (reference noise %.4f)\n", sqrt(se / sb), sqrt(sf / sb),
                  sqrt(sn / sb));
    assert_true(sqrt(se / sb) < 0.5 * sqrt(sf / sb));   /* the glossy bounce is what the floor shows */
    assert_true(sqrt(se / sb) < sqrt(sn / sb) + 0.08);
    prt_reference_vertices_free(&ref);
    prt_scene_release(traced);
    free(ours);
    free(flat);
    free(albedo);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Point lights are drawn per pixel over surfaces that other programs drew first (glossy ones
 * through a geometry shader): every pixel of a lit, smooth region takes the light - none is left
 * dark among lit neighbours, as when the light's pass met the glossy pass's depths a bit short
 * (the demo scene with a glossy sphere and torus showed dark speckles all over its walls). */
static void test_pixel_lights_over_glossy(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    char obj[512], json[512];
    snprintf(obj, sizeof obj, "%s/speckles.obj", test_dir);
    assert_int_equal(prt_demo_scene_write(obj), PRT_OK);
    write_text("speckles.json", "{ \"materials\": { \"sphere\": { \"brdf\": \"phong:30:0.5:0.4\" }, \"torus\": { \"brdf\": \"blinn:60:0.4:0.5\" } },\n"
               "  \"meshes\": [ { \"file\": \"speckles.obj\" } ] }\n", json, sizeof json);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, json, NULL, &s), PRT_OK);
    prt_transfer *t = bake(ctx, s, "64", NULL, "64");
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    prt_light bulb;
    assert_int_equal(prt_light_parse("point:0.05,0.9,0.05:3", &bulb), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &bulb, NULL), PRT_OK);
    prt_relit lit;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1}, &lit), PRT_OK);
    assert_true(prt_relit_view_dependent(&lit) && lit.pixel_light_count == 1);
    prt_renderer *ren = NULL;
    assert_int_equal(prt_renderer_create(ctx, &(prt_renderer_desc){320, 240, 0}, &ren), PRT_OK);   /* multisampled, as prt render */
    prt_render_mesh rm;
    prt_relit_render_mesh(t, &lit, &rm);
    prt_image img;
    prt_camera cam;
    prt_camera_frame((float[3]){-1.5f, 0, -1.5f}, (float[3]){1.5f, 1.5f, 1.5f}, NULL, 40, 320.0f / 240, &cam);
    assert_int_equal(prt_render(ren, &rm, &cam, NULL, &img), PRT_OK);
    int lit_pixels = 0, dark = 0;
    for (int y = 1; y < img.height - 1; ++y)
        for (int x = 1; x < img.width - 1; ++x) {
            /* A speckle: darker than half its darkest neighbour, all of them lit (at an edge or
             * a shadow's rim some neighbour is dark too). */
            float lo = INFINITY;
            for (int k = 0; k < 9; ++k)
                if (k != 4) lo = fminf(lo, img.rgb[((size_t)(y + k / 3 - 1) * img.width + (x + k % 3 - 1)) * 3 + 1]);
            if (lo < 0.03f) continue;
            lit_pixels++;
            dark += img.rgb[((size_t)y * img.width + x) * 3 + 1] < 0.5f * lo;
        }
    print_message("a point light over the glossy demo scene: %d of %d lit pixels dark among lit neighbours\n", dark, lit_pixels);
    assert_true(lit_pixels > 5000);
    assert_true(dark <= lit_pixels / 1000);
    prt_image_free(&img);
    prt_renderer_release(ren);
    /* A big image is drawn in bands (a cancel is heard between them): the same picture as one
     * pass draws (a renderer without a context draws in one). */
    prt_renderer *banded = NULL, *whole = NULL;
    assert_int_equal(prt_renderer_create(ctx, &(prt_renderer_desc){1600, 1400, 0}, &banded), PRT_OK);
    assert_int_equal(prt_renderer_create(NULL, &(prt_renderer_desc){1600, 1400, 0}, &whole), PRT_OK);
    prt_image a, b;
    prt_camera_frame((float[3]){-1.5f, 0, -1.5f}, (float[3]){1.5f, 1.5f, 1.5f}, NULL, 40, 1600.0f / 1400, &cam);
    assert_int_equal(prt_render(banded, &rm, &cam, NULL, &a), PRT_OK);
    assert_int_equal(prt_render(whole, &rm, &cam, NULL, &b), PRT_OK);
    double worst = 0;
    for (size_t i = 0; i < (size_t)1600 * 1400 * 3; ++i) worst = fmax(worst, fabs((double)a.rgb[i] - b.rgb[i]));
    print_message("1600 x 1400 in bands: %.3g from one pass at most\n", worst);
    assert_true(worst < 1e-6);
    prt_image_free(&a);
    prt_image_free(&b);
    prt_renderer_release(banded);
    prt_renderer_release(whole);
    prt_relit_free(&lit);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Sunlight through a window into a closed room, drawn per pixel: no pixel is lit where the
 * per-vertex drawing (shadow rays from the vertices) has no light anywhere near it - the shadow
 * maps leak nothing along the room's seams. Returns the number of leaking pixels. */
static int seam_leaks(prt_context *ctx, prt_renderer *ren, const prt_transfer *t, const prt_lighting *l, bool gate)
{
    const int zero[2] = {0, 0}, W = 320, H = 240;
    prt_relit drawn, flat;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .controls = zero}, &drawn), PRT_OK);
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .controls = zero, .per_vertex = 1}, &flat), PRT_OK);
    const prt_camera cam = {{2.5f, 1.5f, -1.8f}, {-1, 1.2f, 2}, {0, 1, 0}, 70};
    prt_render_mesh rm;
    prt_image a, b;
    prt_relit_render_mesh(t, &drawn, &rm);
    if (!gate) rm.light_visibility = NULL;
    assert_int_equal(prt_render(ren, &rm, &cam, NULL, &a), PRT_OK);
    prt_relit_render_mesh(t, &flat, &rm);
    assert_int_equal(prt_render(ren, &rm, &cam, NULL, &b), PRT_OK);
    int leaks = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            if (a.rgb[((size_t)y * W + x) * 3] < 0.05f) continue;
            bool near = false;
            for (int dy = -6; dy <= 6 && !near; ++dy)
                for (int dx = -6; dx <= 6 && !near; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    near = xx >= 0 && yy >= 0 && xx < W && yy < H && b.rgb[((size_t)yy * W + xx) * 3] > 0.01f;
                }
            leaks += !near;
        }
    prt_image_free(&a);
    prt_image_free(&b);
    prt_relit_free(&drawn);
    prt_relit_free(&flat);
    return leaks;
}

static void test_no_seam_leaks(void **state)
{
    (void)state;
    char path[32];
    const int n = snprintf(path, sizeof path, "/tmp/prt_test_room_%06d", 0);
    memset(path + n - 6, 'X', 6);   /* mkstemp's template */
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    prt_context *ctx = test_context(0);
    assert_int_equal(prt_demo_room_write(path, 0.125f), PRT_OK);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    prt_transfer *t = bake(ctx, s, "256", NULL, "64");
    prt_lighting *l = NULL;
    prt_light sun;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_light_parse("directional:0.3,0.6,1:30", &sun), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &sun, NULL), PRT_OK);
    prt_renderer *ren = NULL;
    assert_int_equal(prt_renderer_create(ctx, &(prt_renderer_desc){320, 240, 4}, &ren), PRT_OK);
    const int leaks = seam_leaks(ctx, ren, t, l, true), ungated = seam_leaks(ctx, ren, t, l, false);
    print_message("sunlit room: %d leaking pixels (%d with the shadow maps alone)\n", leaks, ungated);
    assert_int_equal(leaks, 0);
    prt_renderer_release(ren);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    remove(path);
    char mtl[sizeof path + 8];
    snprintf(mtl, sizeof mtl, "%s.mtl", path);
    remove(mtl);
    prt_context_release(ctx);
}

/* The Cornell box lit by its ceiling light and by a point light, against the path tracer: all
 * bounces (16), total and indirect light, emitters left out. Measured (1024 rays, 1024 functions,
 * max edge 0.1, 512 paths): total 3.2% / 2.8% against reference noise 2.9% / 2.4%, indirect
 * 7.5% / 6.8% against 6.8% / 5.8%: the method's own error hides in the reference's noise. */
static void test_cornell_vs_reference(void **state)
{
    (void)state;
    const char *path = cornell_box_path();
    if (!path) skip();
    prt_context *ctx = test_context(0);
    prt_scene_desc sd = {0};
    sd.max_edge = 0.1f;
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, &sd, &s), PRT_OK);
    prt_transfer *t = bake(ctx, s, NULL, NULL, "1024");
    const size_t nv = prt_transfer_vertex_count(t);
    prt_scene *traced = NULL;
    assert_int_equal(prt_transfer_scene(ctx, t, &traced), PRT_OK);
    const char *lights[2] = {NULL, "point:0.2,1.2,0.3:1.5"};
    for (int i = 0; i < 2; ++i) {
        prt_lighting *l = NULL;
        assert_int_equal(prt_lighting_create(&l), PRT_OK);   /* no environment: the box's own light */
        if (lights[i]) {
            prt_light li;
            assert_int_equal(prt_light_parse(lights[i], &li), PRT_OK);
            assert_int_equal(prt_lighting_add(l, &li, NULL), PRT_OK);
        }
        const int bounces[2] = {16, 0};
        prt_relight_desc d = {.variant = -1, .controls = bounces, .with_indirect = 1, .per_vertex = 1};
        prt_relit r;
        assert_int_equal(prt_relight(ctx, t, l, &d, &r), PRT_OK);
        prt_reference_desc rd = {0};
        rd.samples = 512;
        rd.lighting = l;
        prt_reference_vertices ref;
        assert_int_equal(prt_reference_trace_vertices(ctx, traced, NULL, &rd, &ref), PRT_OK);
        const float *emit = prt_transfer_emission(t);
        double e[4];
        vs_reference(r.radiance, r.indirect, &ref, nv, emit, e);
        const double total = e[0], rn = e[1], indirect = e[2], rni = e[3];
        print_message("Cornell box, %s: total %.4f (reference noise %.4f), indirect %.4f (noise %.4f)\n", lights[i] ? lights[i] : "ceiling light",
                      total, rn, indirect, rni);
        assert_true(total < rn + 0.015);
        assert_true(indirect < rni + 0.03);
        prt_relit_free(&r);
        prt_reference_vertices_free(&ref);
        prt_lighting_release(l);
    }
    /* The back wall repainted at run time equals a bake of the box with that colour. */
    const float blue[3] = {0.2f, 0.3f, 0.9f};
    float *painted = malloc(nv * 3 * sizeof(float));
    memcpy(painted, prt_transfer_albedo(t), nv * 3 * sizeof(float));
    assert_int_equal(prt_transfer_paint_albedo(t, "backWall", blue, painted), PRT_OK);
    assert_int_equal(prt_transfer_paint_albedo(t, "frontWall", blue, painted), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "backWall"));   /* the error lists the names */
    assert_int_equal(prt_scene_paint_albedo(s, "backWall", blue), PRT_OK);
    prt_transfer *rebaked = bake(ctx, s, NULL, NULL, "1024");
    prt_lighting *l = NULL;
    prt_light bulb;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_light_parse("point:0.2,1.2,0.3:1.5", &bulb), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &bulb, NULL), PRT_OK);
    prt_relit live, again;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .albedo = painted}, &live), PRT_OK);
    assert_int_equal(prt_relight(ctx, rebaked, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1}, &again), PRT_OK);
    for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(live.radiance[i], again.radiance[i], 1e-5f + 1e-4f * again.radiance[i]);
    prt_relit_free(&live);
    prt_relit_free(&again);
    prt_lighting_release(l);
    prt_transfer_release(rebaked);
    free(painted);
    prt_scene_release(traced);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

int main(int argc, char **argv)
{
    /* The renderer's test runs on its own (ctest: spectral-render), without leak checking:
     * Mesa's driver leaks where LeakSanitizer cannot name it (see tests/cli_test.sh). */
    if (argc > 1 && !strcmp(argv[1], "render")) {
        const struct CMUnitTest render[] = {cmocka_unit_test(test_pixel_lights), cmocka_unit_test(test_no_seam_leaks),
                                            cmocka_unit_test(test_pixel_lights_over_glossy)};
        return cmocka_run_group_tests(render, test_dir_setup, test_dir_teardown);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_basis),
        cmocka_unit_test(test_direct_closed_forms),
        cmocka_unit_test(test_white_furnace),
        cmocka_unit_test(test_defaults_converge),
        cmocka_unit_test(test_albedo_at_run_time),
        cmocka_unit_test(test_glossy_final_bounce),
        cmocka_unit_test_setup_teardown(test_file_round_trip, test_dir_setup, test_dir_teardown),
        cmocka_unit_test(test_cornell_vs_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
