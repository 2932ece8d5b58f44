/* Every method relit on the GPU (prt_relight_desc.gpu_finish, prt_render_sums) gives what the CPU
 * gives, to float rounding: SH diffuse (raw, 8-bit quantized, clustered PCA) and glossy (exit
 * vectors, with a run-time lobe and with the BRDF baked in, raw and clustered PCA), wavelet,
 * spectral bounces (with and without the tail), the light cloud (clustered PCA and raw zones,
 * diffuse and glossy) and ambient occlusion, in a pit with a sphere in it. Each
 * description is summed on the CPU (prt_render_sums_cpu) and, where a GL 3.3 context can be made
 * (EGL surfaceless on llvmpipe without a GPU), on the GPU: the vertices' radiance read back and
 * the images drawn from both results. Without a context the GPU half skips, saying so. */
#include "common.h"

typedef struct gpu_case {
    const char *name, *method;
    const char *const *options;
    int env;              /* 1: band-limited environment; 0: a point light in the pit */
    int controls[2];      /* spectral: bounces, tail (-1: defaults) */
} gpu_case;

static prt_renderer *renderer;
static bool no_gl;

static prt_renderer *get_renderer(prt_context *ctx)
{
    if (!renderer && !no_gl && prt_renderer_create(ctx, &(prt_renderer_desc){96, 72, 1}, &renderer)) {
        print_message("skipping the GPU half: no OpenGL 3.3 context (%s)\n", prt_last_error());
        no_gl = true;
    }
    return renderer;
}

/* max |a - b| and the same over max |b|. */
static void diff(const float *a, const float *b, size_t n, double *abs_out, double *rel_out)
{
    double d = 0, m = 0;
    for (size_t i = 0; i < n; ++i) {
        d = fmax(d, fabs((double)a[i] - b[i]));
        m = fmax(m, fabs((double)b[i]));
    }
    *abs_out = d;
    *rel_out = m > 0 ? d / m : d;
}

static void run_case(prt_context *ctx, const prt_scene *scene, const gpu_case *c)
{
    prt_transfer *t = test_bake_with(ctx, scene, c->method, c->options);
    const size_t nv = prt_transfer_vertex_count(t);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    if (c->env) {
        assert_int_equal(prt_lighting_set_envmap(l, band_limited_env(64), NULL, 1.0f), PRT_OK);
    } else {
        prt_light p = {.type = PRT_LIGHT_POINT, .position = {0.1f, 0.55f, -0.15f}, .intensity = {0.8f, 0.7f, 0.5f}};
        assert_int_equal(prt_lighting_add(l, &p, NULL), PRT_OK);
    }
    const int *controls = c->controls[0] >= 0 ? c->controls : NULL;
    prt_relight_desc cpu_d = {.variant = -1, .per_vertex = 1, .controls = controls}, gpu_d = cpu_d;
    gpu_d.gpu_finish = 1;
    prt_relit cpu, gpu;
    assert_int_equal(prt_relight(ctx, t, l, &cpu_d, &cpu), PRT_OK);
    assert_int_equal(prt_relight(ctx, t, l, &gpu_d, &gpu), PRT_OK);
    assert_null(cpu.gpu_sums);
    assert_non_null(gpu.gpu_sums);   /* this case takes the GPU path */
    double peak = 0;
    for (size_t i = 0; i < nv * 3; ++i) peak = fmax(peak, cpu.radiance[i]);
    assert_true(peak > 1e-4);        /* something is lit */
    /* The description summed on the CPU. */
    float *sum = malloc(nv * 3 * sizeof(float)), *back = malloc(nv * 3 * sizeof(float));
    memcpy(sum, gpu.radiance, nv * 3 * sizeof(float));
    assert_int_equal(prt_render_sums_cpu(gpu.gpu_sums, gpu.gpu_vector, nv, sum), PRT_OK);
    double a, r, added = 0;
    for (size_t i = 0; i < nv * 3; ++i) added = fmax(added, sum[i] - gpu.radiance[i]);
    assert_true(added > 1e-3 * peak);   /* the sums carry light */
    diff(sum, cpu.radiance, nv * 3, &a, &r);
    print_message("%-22s %6zu vertices  sums on the CPU: max abs %.3g, rel %.3g (they add up to %.3g of %.3g)\n", c->name, nv, a, r, added, peak);
    assert_true(r < 2e-5);
    /* Glossy vertices' exit vectors, drawn per pixel from the exit product. */
    if (cpu.exit_sh) {
        assert_null(gpu.exit_sh);
        assert_int_equal(gpu.exit_order, cpu.exit_order);
        const size_t ne = nv * 3 * (size_t)cpu.exit_order * cpu.exit_order;
        float *e = malloc(ne * sizeof(float));
        assert_int_equal(prt_render_sums_exit_cpu(gpu.gpu_sums, gpu.gpu_vector, nv, cpu.exit_order, e), PRT_OK);
        double ep = 0;
        for (size_t i = 0; i < ne; ++i) ep = fmax(ep, fabs(cpu.exit_sh[i]));
        assert_true(ep > 1e-4);   /* they carry light */
        diff(e, cpu.exit_sh, ne, &a, &r);
        print_message("%-22s %6s           exit sums on the CPU: max abs %.3g, rel %.3g\n", c->name, "", a, r);
        assert_true(r < 2e-5);
        free(e);
    }
    /* Separable view factors' light-dependent terms (wavelet glossy vertices). */
    if (cpu.kvec) {
        assert_null(gpu.kvec);
        assert_int_equal(gpu.kvec_terms, cpu.kvec_terms);
        const size_t nk = nv * 3 * (size_t)cpu.kvec_terms;
        float *k = malloc(nk * sizeof(float));
        assert_int_equal(prt_render_sums_kvec_cpu(gpu.gpu_sums, gpu.gpu_vector, nv, cpu.kvec_terms, k), PRT_OK);
        diff(k, cpu.kvec, nk, &a, &r);
        print_message("%-22s %6s           K-vector sums on the CPU: max abs %.3g, rel %.3g\n", c->name, "", a, r);
        assert_true(r < 2e-5);
        free(k);
    }
    /* The CPU's view factor from the GPU's description (prt_relit_shade sums it there). */
    if (prt_relit_view_dependent(&cpu)) {
        assert_true(prt_relit_view_dependent(&gpu));
        float *sc = malloc(nv * 3 * sizeof(float)), *sg = malloc(nv * 3 * sizeof(float));
        const float eye[3] = {0.8f, 1.2f, 1.5f};
        assert_int_equal(prt_relit_shade(ctx, t, &cpu, eye, sc), PRT_OK);
        assert_int_equal(prt_relit_shade(ctx, t, &gpu, eye, sg), PRT_OK);
        diff(sg, sc, nv * 3, &a, &r);
        print_message("%-22s %6s           shaded from an eye: max abs %.3g, rel %.3g\n", c->name, "", a, r);
        assert_true(r < 2e-5);
        free(sc);
        free(sg);
    }
    /* On the GPU: the vertices' radiance read back, then both images. */
    prt_renderer *ren = get_renderer(ctx);
    if (ren) {
        prt_render_mesh gm, cm;
        prt_relit_render_mesh(t, &gpu, &gm);
        prt_relit_render_mesh(t, &cpu, &cm);
        assert_int_equal(prt_render_vertex_radiance(ren, &gm, back), PRT_OK);
        assert_int_equal(prt_render_sums_on_gpu(ren), 1);
        diff(back, cpu.radiance, nv * 3, &a, &r);
        print_message("%-22s %6s           on the GPU (%s): max abs %.3g, rel %.3g\n", c->name, "", prt_renderer_name(ren), a, r);
        assert_true(r < 2e-5);
        prt_camera cam;
        prt_camera_frame_mesh(ctx, prt_transfer_positions(t), nv, prt_transfer_indices(t), prt_transfer_triangle_count(t), NULL, 0, 96.0f / 72.0f, &cam);
        prt_image ig, ic;
        assert_int_equal(prt_render(ren, &gm, &cam, NULL, &ig), PRT_OK);
        assert_int_equal(prt_render(ren, &cm, &cam, NULL, &ic), PRT_OK);
        double ia, ir;
        diff(ig.rgb, ic.rgb, (size_t)ig.width * ig.height * 3, &ia, &ir);
        print_message("%-22s %6s           images: max abs %.3g, rel %.3g\n", c->name, "", ia, ir);
        assert_true(ir < 2e-3);   /* the float target holds halves */
        prt_image_free(&ig);
        prt_image_free(&ic);
    }
    free(sum);
    free(back);
    prt_relit_free(&cpu);
    prt_relit_free(&gpu);
    prt_lighting_release(l);
    prt_transfer_release(t);
}

static prt_scene *pit_scene(prt_context *ctx)
{
    test_mesh m = {0};
    tm_pit(&m, 10);
    tm_sphere(&m, (float[3]){0, 0.25f, 0}, 0.18f, 10, 16);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    tm_free(&m);
    return s;
}

static void test_sh(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = pit_scene(ctx);
    static const char *const raw[] = {"order", "4", "samples", "128", "bounces", "1", NULL};
    static const char *const quant[] = {"order", "4", "samples", "128", "bounces", "1", "quantize", "8", NULL};
    static const char *const cpca[] = {"order", "4", "samples", "128", "bounces", "1", "clusters", "4", "vectors", "3", NULL};
    const gpu_case cases[] = {{"sh raw", "sh", raw, 1, {-1, -1}}, {"sh quantized 8-bit", "sh", quant, 1, {-1, -1}}, {"sh cpca", "sh", cpca, 1, {-1, -1}}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) run_case(ctx, s, &cases[i]);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Glossy SH: exit vectors summed on the GPU and drawn per pixel, against the CPU's exit_sh. */
static void glossy_case(prt_context *ctx, int glossy_exit, int compressed)
{
    test_mesh m = {0};
    tm_pit(&m, 8);
    tm_sphere(&m, (float[3]){0, 0.25f, 0}, 0.18f, 10, 16);
    prt_scene *scene = tm_scene(ctx, &m, 0.4f);
    tm_free(&m);
    prt_brdf phong;
    assert_int_equal(prt_brdf_parse("phong:8:0.5:0.3", &phong), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(scene, 0, prt_scene_vertex_count(scene), &phong), PRT_OK);
    prt_bake_desc bd = {0};
    bd.order = 4;
    bd.samples = 128;
    bd.kinds = PRT_TRANSFER_SHADOWED | PRT_TRANSFER_GLOSSY_SHADOWED;
    bd.glossy_exit = glossy_exit;
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake_sh(ctx, scene, &bd, &t), PRT_OK);
    if (compressed) {   /* clustered PCA: the projections on the CPU, each vertex's sums on the GPU */
        prt_transfer *c = NULL;
        assert_int_equal(prt_transfer_compress(ctx, t, &(prt_compress_desc){.clusters = 4, .vectors = 3}, &c), PRT_OK);
        prt_transfer_release(t);
        t = c;
    }
    const char *name = compressed ? (glossy_exit ? " (baked, cpca)" : " (lobe, cpca)") : glossy_exit ? " (baked)" : " (lobe)";
    const size_t nv = prt_transfer_vertex_count(t);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, band_limited_env(64), NULL, 1.0f), PRT_OK);
    prt_relight_desc cd = {.variant = prt_transfer_find_variant(t, "glossy-shadowed")}, gd = cd;
    gd.gpu_finish = 1;
    prt_relit cpu, gpu;
    assert_int_equal(prt_relight(ctx, t, l, &cd, &cpu), PRT_OK);
    assert_int_equal(prt_relight(ctx, t, l, &gd, &gpu), PRT_OK);
    assert_non_null(cpu.exit_sh);
    assert_null(gpu.exit_sh);
    assert_non_null(gpu.gpu_sums);
    const size_t ne = nv * 3 * 16;
    float *e = malloc(ne * sizeof(float));
    assert_int_equal(prt_render_sums_exit_cpu(gpu.gpu_sums, gpu.gpu_vector, nv, 4, e), PRT_OK);
    double a, r, peak = 0;
    for (size_t i = 0; i < ne; ++i) peak = fmax(peak, fabs(cpu.exit_sh[i]));
    assert_true(peak > 1e-3);   /* the exit vectors carry light */
    diff(e, cpu.exit_sh, ne, &a, &r);
    print_message("sh glossy%-13s %6zu vertices  exit sums on the CPU: max abs %.3g, rel %.3g\n", name, nv, a, r);
    assert_true(r < 2e-5);
    /* The diffuse part beside them (clustered PCA too when compressed). */
    float *rad = malloc(nv * 3 * sizeof(float));
    memcpy(rad, gpu.radiance, nv * 3 * sizeof(float));
    assert_int_equal(prt_render_sums_cpu(gpu.gpu_sums, gpu.gpu_vector, nv, rad), PRT_OK);
    diff(rad, cpu.radiance, nv * 3, &a, &r);
    assert_true(r < 2e-5);
    free(rad);
    prt_renderer *ren = get_renderer(ctx);
    if (ren) {
        prt_render_mesh gm, cm;
        prt_relit_render_mesh(t, &gpu, &gm);
        prt_relit_render_mesh(t, &cpu, &cm);
        assert_int_equal(gm.exit_order, 4);
        prt_camera cam;
        prt_camera_frame_mesh(ctx, prt_transfer_positions(t), nv, prt_transfer_indices(t), prt_transfer_triangle_count(t), NULL, 0, 96.0f / 72.0f, &cam);
        prt_image ig, ic;
        assert_int_equal(prt_render(ren, &gm, &cam, NULL, &ig), PRT_OK);
        assert_int_equal(prt_render_sums_on_gpu(ren), 1);
        assert_int_equal(prt_render(ren, &cm, &cam, NULL, &ic), PRT_OK);
        double ia, ir;
        diff(ig.rgb, ic.rgb, (size_t)ig.width * ig.height * 3, &ia, &ir);
        print_message("sh glossy%-13s %6s           images: max abs %.3g, rel %.3g\n", name, "", ia, ir);
        assert_true(ir < 2e-3);
        prt_image_free(&ig);
        prt_image_free(&ic);
    }
    /* The CPU's view factor from the GPU's description: prt_relit_shade sums it there. */
    float *sc = malloc(nv * 3 * sizeof(float)), *sg = malloc(nv * 3 * sizeof(float));
    const float eye[3] = {0.8f, 1.2f, 1.5f};
    assert_int_equal(prt_relit_shade(ctx, t, &cpu, eye, sc), PRT_OK);
    assert_int_equal(prt_relit_shade(ctx, t, &gpu, eye, sg), PRT_OK);
    diff(sg, sc, nv * 3, &a, &r);
    assert_true(r < 2e-5);
    free(sc);
    free(sg);
    free(e);
    prt_relit_free(&cpu);
    prt_relit_free(&gpu);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(scene);
}

static void test_sh_glossy(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    glossy_case(ctx, 0, 0);
    glossy_case(ctx, 1, 0);
    glossy_case(ctx, 0, 1);
    glossy_case(ctx, 1, 1);
    prt_context_release(ctx);
}

static void test_wavelet(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = pit_scene(ctx);
    static const char *const opts[] = {"supersample", "1", "bounces", "0", NULL};
    const gpu_case c = {"wavelet", "wavelet", opts, 1, {-1, -1}};
    run_case(ctx, s, &c);
    /* Glossy vertices (the sphere's last 150 with a Phong lobe): their K-vectors summed on the GPU
     * and read by the per-pixel view factor, the Lambertian ones' radiance from their first term. */
    prt_brdf phong;
    assert_int_equal(prt_brdf_parse("phong:8:0.5:0.3", &phong), PRT_OK);
    const size_t nv = prt_scene_vertex_count(s);
    assert_int_equal(prt_scene_set_brdf(s, nv - 150, 150, &phong), PRT_OK);
    const gpu_case g = {"wavelet glossy", "wavelet", opts, 1, {-1, -1}};
    run_case(ctx, s, &g);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_spectral(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = pit_scene(ctx);
    static const char *const opts[] = {"samples", "128", "basis", "64", "partition", "150", NULL};
    /* Without the tail, with it (the default: a geometric rest of the series from the last two
     * bounces' power), and one bounce with it (the tail compares with the direct light). */
    const gpu_case cases[] = {{"spectral 3 bounces", "spectral", opts, 0, {3, 0}},
                              {"spectral 3 + tail", "spectral", opts, 0, {3, 1}},
                              {"spectral 1 + tail", "spectral", opts, 0, {1, 1}}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) run_case(ctx, s, &cases[i]);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_lightcloud(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = pit_scene(ctx);
    static const char *const cpca[] = {"cloud-grid", "3,3,3", "samples", "128", "basis", "48", "partition", "100", "zone-vertices", "200", NULL};
    static const char *const raw[] = {"cloud-grid", "3,3,3", "samples", "128", "basis", "48", "partition", "100", "compress", "none", NULL};
    const gpu_case cases[] = {{"lightcloud cpca", "lightcloud", cpca, 0, {-1, -1}}, {"lightcloud raw", "lightcloud", raw, 0, {-1, -1}}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) run_case(ctx, s, &cases[i]);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Glossy vertices (a Phong lobe on every surface): their exit vectors summed on the GPU too. */
static void test_lightcloud_glossy(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = pit_scene(ctx);
    prt_brdf phong;
    assert_int_equal(prt_brdf_parse("phong:8:0.5:0.3", &phong), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, 0, prt_scene_vertex_count(s), &phong), PRT_OK);
    static const char *const cpca[] = {"cloud-grid", "3,3,3", "samples", "128", "basis", "48", "partition", "100", "zone-vertices", "200", NULL};
    static const char *const raw[] = {"cloud-grid", "3,3,3", "samples", "128", "basis", "48", "partition", "100", "compress", "none", NULL};
    const gpu_case cases[] = {{"lightcloud glossy cpca", "lightcloud", cpca, 0, {-1, -1}}, {"lightcloud glossy raw", "lightcloud", raw, 0, {-1, -1}}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) run_case(ctx, s, &cases[i]);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void test_ao(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    prt_scene *s = pit_scene(ctx);
    static const char *const opts[] = {"samples", "128", NULL};
    const gpu_case c = {"ao", "ao", opts, 1, {-1, -1}};
    run_case(ctx, s, &c);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static void on_log(void *user, prt_log_level level, const char *msg)
{
    (void)level;
    if (strstr(msg, "summed on the CPU instead of the GPU")) snprintf(user, 256, "%s", msg);
}

/* Where the GPU cannot hold a description (here a renderer told it has 1000 buffer texels), the
 * renderer sums on the CPU, says so once, and draws the same; bad descriptions are refused. */
static void square_times(const float y[3], const float *const a[3], float out[3])
{
    for (int c = 0; c < 3; ++c) out[c] = y[c] * y[c] * a[0][c];
}

/* A product's map (GLSL on the GPU, C on the CPU) gives the same rows both ways; GLSL that does
 * not compile sends the description to the CPU, saying why; a map reading a later product is
 * refused. */
static void map_case(prt_context *ctx, const prt_transfer *t, const prt_relit *r, char *note)
{
    const size_t nv = prt_transfer_vertex_count(t);
    float *x = malloc(nv * 3 * sizeof(float)), *cpu = calloc(nv * 3, sizeof(float)), *back = malloc(nv * 3 * sizeof(float));
    float *w = malloc(nv * 3 * sizeof(float)), *zero = calloc(nv * 3, sizeof(float));
    uint32_t *start = malloc((nv + 1) * sizeof(uint32_t)), *index = malloc(nv * sizeof(uint32_t));
    for (size_t v = 0; v < nv; ++v) {
        start[v] = (uint32_t)v;
        index[v] = (uint32_t)(nv - 1 - v);
        for (int c = 0; c < 3; ++c) {
            x[v * 3 + c] = 0.25f + (float)((v * 7 + (size_t)c * 3) % 17) / 17.0f;
            w[v * 3 + c] = 0.5f + (float)c;
        }
    }
    start[nv] = (uint32_t)nv;
    prt_render_product p = {.input = -1, .rows = nv, .start = start, .index = index, .weight = w, .shown = 1,
                            .map_glsl = "return y * y * a0;", .map_cpu = square_times, .map_argc = 1, .map_args = {-1}};
    prt_render_sums sums = {.id = UINT64_MAX - 7, .vector_length = nv, .product_count = 1, .products = &p};
    assert_int_equal(prt_render_sums_cpu(&sums, x, nv, cpu), PRT_OK);
    for (size_t v = 0; v < nv; ++v)
        for (int c = 0; c < 3; ++c) {
            const float y = w[v * 3 + c] * x[(nv - 1 - v) * 3 + c];
            assert_float_equal(cpu[v * 3 + c], y * y * x[v * 3 + c], 1e-6);
        }
    prt_renderer *ren = NULL;
    if (!no_gl && !prt_renderer_create(ctx, &(prt_renderer_desc){32, 32, 1}, &ren)) {
        prt_render_mesh m;
        prt_relit_render_mesh(t, r, &m);
        m.radiance = zero;
        m.exit_sh = NULL;
        m.exit_order = 0;
        m.gpu_sums = &sums;
        m.gpu_vector = x;
        assert_int_equal(prt_render_vertex_radiance(ren, &m, back), PRT_OK);
        assert_int_equal(prt_render_sums_on_gpu(ren), 1);
        double a, rel;
        diff(back, cpu, nv * 3, &a, &rel);
        print_message("map on the GPU: max abs %.3g, rel %.3g\n", a, rel);
        assert_true(rel < 2e-6);
        /* GLSL that does not compile: the CPU sums it, and the note says why. */
        p.map_glsl = "return y * undeclared;";
        sums.id = UINT64_MAX - 8;
        note[0] = 0;
        assert_int_equal(prt_render_vertex_radiance(ren, &m, back), PRT_OK);
        assert_int_equal(prt_render_sums_on_gpu(ren), 0);
        print_message("note: %.80s...\n", note);
        assert_non_null(strstr(note, "GPU sums shader"));
        for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(back[i], cpu[i], 1e-6);
        p.map_glsl = "return y * y * a0;";
        prt_renderer_release(ren);
    }
    /* A map reading itself or a later product is refused. */
    p.map_args[0] = 0;
    assert_int_equal(prt_render_sums_cpu(&sums, x, nv, cpu), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "map reads 0"));
    free(x);
    free(cpu);
    free(back);
    free(w);
    free(zero);
    free(start);
    free(index);
}

static void test_fallback(void **state)
{
    (void)state;
    char note[256] = "";
    prt_context *ctx = NULL;
    assert_int_equal(prt_context_create(&(prt_context_desc){.threads = 2, .log = on_log, .log_user = note}, &ctx), PRT_OK);
    prt_scene *s = pit_scene(ctx);
    static const char *const raw[] = {"order", "4", "samples", "64", "bounces", "1", NULL};
    prt_transfer *t = test_bake_with(ctx, s, "sh", raw);
    const size_t nv = prt_transfer_vertex_count(t);
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    assert_int_equal(prt_lighting_set_envmap(l, band_limited_env(64), NULL, 1.0f), PRT_OK);
    prt_relight_desc d = {.variant = -1, .gpu_finish = 1};
    prt_relit r;
    assert_int_equal(prt_relight(ctx, t, l, &d, &r), PRT_OK);
    float *cpu = calloc(nv * 3, sizeof(float)), *back = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_render_sums_cpu(r.gpu_sums, r.gpu_vector, nv, cpu), PRT_OK);
    prt_renderer *small = NULL;
    get_renderer(ctx);   /* held across small's life and release */
    if (prt_renderer_create(ctx, &(prt_renderer_desc){32, 32, 1}, &small)) {
        print_message("skipping the GPU half: no OpenGL 3.3 context (%s)\n", prt_last_error());
    } else {
        prt_renderer_limit_buffer_texels(small, 1000);
        prt_render_mesh m;
        prt_relit_render_mesh(t, &r, &m);
        assert_int_equal(prt_render_vertex_radiance(small, &m, back), PRT_OK);
        assert_int_equal(prt_render_sums_on_gpu(small), 0);
        assert_non_null(strstr(note, "texels exceed"));
        print_message("note: %s\n", note);
        for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(back[i], cpu[i], 1e-6);
        prt_renderer_release(small);
        /* Another renderer (the shared one, made before small) still draws after small's release:
         * the EGL display they share stays up while either holds it. */
        prt_renderer *other = get_renderer(ctx);
        assert_non_null(other);
        memset(back, 0, nv * 3 * sizeof(float));
        assert_int_equal(prt_render_vertex_radiance(other, &m, back), PRT_OK);
        for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(back[i], cpu[i], 1e-5);
    }
    /* A product reading past its input is refused, naming it. */
    prt_render_product bad = r.gpu_sums->products[0];
    uint32_t *index = malloc(bad.start[bad.rows] * sizeof(uint32_t));
    memcpy(index, bad.index, bad.start[bad.rows] * sizeof(uint32_t));
    index[5] = 1000000;
    bad.index = index;
    prt_render_sums sums = *r.gpu_sums;
    sums.products = &bad;
    sums.product_count = 1;
    assert_int_equal(prt_render_sums_cpu(&sums, r.gpu_vector, nv, cpu), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "product 0 reads row 1000000"));
    free(index);
    map_case(ctx, t, &r, note);
    free(cpu);
    free(back);
    prt_relit_free(&r);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

static int teardown(void **state)
{
    (void)state;
    prt_renderer_release(renderer);
    renderer = NULL;
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sh),
        cmocka_unit_test(test_sh_glossy),
        cmocka_unit_test(test_wavelet),
        cmocka_unit_test(test_spectral),
        cmocka_unit_test(test_lightcloud),
        cmocka_unit_test(test_lightcloud_glossy),
        cmocka_unit_test(test_ao),
        cmocka_unit_test(test_fallback),
    };
    return cmocka_run_group_tests(tests, NULL, teardown);
}
