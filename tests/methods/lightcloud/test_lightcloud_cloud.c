/* Light clouds for lighting design (Kristensen et al. 2005): how merged lights' responses are
 * formed (mean, harmonic mean, a solution at the merged position), lights added to a cloud
 * without solving the old ones again (--responses: the same file as a bake of the whole cloud),
 * and glossy vertices' exit SH against the path tracer from a fixed eye. */
#include "common.h"
#include "methods/lightcloud/lightcloud.h"

/* Closed box of side 1 (inward normals), its floor at y = 0. */
static void closed_box(test_mesh *m, int n)
{
    tm_pit(m, n);
    tm_quad(m, (float[3]){-0.5f, 1, -0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, 1}, n);   /* ceiling, facing down */
}

static prt_status bake_opts(prt_context *ctx, const prt_scene *s, const char *const *opts, prt_transfer **t)
{
    const prt_method *lc = prt_method_find("lightcloud");
    assert_non_null(lc);
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(lc, &o), PRT_OK);
    for (int i = 0; opts && opts[i]; i += 2) assert_int_equal(prt_options_set(o, opts[i], opts[i + 1]), PRT_OK);
    *t = NULL;
    const prt_status st = prt_bake(ctx, s, lc, o, NULL, t);
    prt_options_release(o);
    return st;
}

static prt_transfer *bake_lc(prt_context *ctx, const prt_scene *s, const char *const *opts)
{
    prt_transfer *t = NULL;
    assert_int_equal(bake_opts(ctx, s, opts, &t), PRT_OK);
    return t;
}

static prt_lighting *one_light(const char *spec)
{
    prt_lighting *l = NULL;
    assert_int_equal(prt_lighting_create(&l), PRT_OK);
    prt_light li;
    assert_int_equal(prt_light_parse(spec, &li), PRT_OK);
    assert_int_equal(prt_lighting_add(l, &li, NULL), PRT_OK);
    return l;
}

/* ---- merged responses ---- */
static void test_merge_values(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    /* Five cloud lights in three merged lights: {0, 2, 3}, {1, 4}, and 5 alone (with 0 then 1's
     * light-of order). Width 17: a diffuse value and one SH group of 16 for the second call. */
    const uint32_t light_of[6] = {0, 1, 0, 0, 1, 2};
    float d[6] = {1, 2, 4, 4, 0, 0.1f};   /* light 4 reaches nothing at this vertex */
    float out[3];
    assert_int_equal(prt__lightcloud_merge(ctx, PRT__LIGHTCLOUD_MERGE_MEAN, 6, light_of, 3, d, 1, 1, out), PRT_OK);
    assert_float_equal(out[0], 3.0f, 1e-6f);
    assert_float_equal(out[1], 1.0f, 1e-6f);
    assert_true(out[2] == 0.1f);   /* one member: its own response, exactly */
    assert_int_equal(prt__lightcloud_merge(ctx, PRT__LIGHTCLOUD_MERGE_HARMONIC, 6, light_of, 3, d, 1, 1, out), PRT_OK);
    assert_float_equal(out[0], 3.0f / (1.0f + 0.25f + 0.25f), 1e-6f);   /* 2 */
    assert_true(out[1] == 0.0f);                                          /* a member of 0: the limit */
    assert_true(out[2] == 0.1f);
    /* An SH group keeps the mean's shape, scaled to the harmonic mean of its constant term. */
    float g[6 * 16] = {0};
    for (int j = 0; j < 6; ++j) {
        g[j * 16] = (float)(j + 1);
        for (int c = 1; c < 16; ++c) g[j * 16 + c] = (float)(c % 3 - 1) * (float)(j + 1) * 0.1f;
    }
    float sh[16 * 3];
    assert_int_equal(prt__lightcloud_merge(ctx, PRT__LIGHTCLOUD_MERGE_HARMONIC, 6, light_of, 3, g, 16, 16, sh), PRT_OK);
    const double h0 = 3.0 / (1.0 / 1 + 1.0 / 3 + 1.0 / 4), m0 = (1 + 3 + 4) / 3.0;
    for (int c = 0; c < 16; ++c) {
        const double mean = (g[c] + g[32 + c] + g[48 + c]) / 3.0;
        assert_float_equal(sh[c * 3 + 0], mean * h0 / m0, 1e-5);
        assert_true(sh[c * 3 + 2] == g[80 + c]);
    }
    prt_context_release(ctx);
}

/* The three ways on one bake: uncompressed responses of the same clusters; the harmonic mean is
 * at most the mean; merged lights of one member are that member's response whatever the way,
 * those of several solved at their position differ from the mean; the choice survives a file. */
static void test_merge_modes(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 6);
    tm_sphere(&m, (float[3]){0.1f, 0.25f, 0}, 0.15f, 6, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    const char *base[] = {"cloud-grid", "3,3,3", "samples", "128", "basis", "48", "partition", "100", "compress", "none", "merge-distance", "0.7",
                          "merge-error", "0"};
    const char *opts[3][18];
    const char *how[3] = {"mean", "harmonic", "solve"};
    prt_transfer *t[3];
    for (int k = 0; k < 3; ++k) {
        memcpy(opts[k], base, sizeof base);
        opts[k][14] = "merge-response";
        opts[k][15] = how[k];
        opts[k][16] = NULL;
        t[k] = bake_lc(ctx, s, opts[k]);
    }
    const prt__lightcloud_set *a = t[0]->state, *h = t[1]->state, *x = t[2]->state;
    assert_int_equal(a->merge_response, PRT__LIGHTCLOUD_MERGE_MEAN);
    assert_int_equal(x->merge_response, PRT__LIGHTCLOUD_MERGE_SOLVE);
    int merged = 0, differ = 0;
    for (uint32_t z = 0; z < a->zone_count; ++z) {
        const prt__lightcloud_zone *za = &a->zones[z], *zh = &h->zones[z], *zx = &x->zones[z];
        assert_int_equal(za->lights, zh->lights);
        assert_int_equal(za->lights, zx->lights);
        assert_memory_equal(za->light_of, zx->light_of, a->cloud_count * sizeof(uint32_t));
        const uint32_t L = za->lights, rows = za->diffuse.vertices;
        uint32_t *count = calloc(L, sizeof(uint32_t));
        for (uint32_t j = 0; j < a->cloud_count; ++j) count[za->light_of[j]]++;
        for (uint32_t l = 0; l < L; ++l) {
            merged += count[l] > 1;
            double se = 0, sa = 0;
            for (uint32_t i = 0; i < rows * 3; ++i) {
                const float ma = za->diffuse.raw[(size_t)i * L + l], mh = zh->diffuse.raw[(size_t)i * L + l], mx = zx->diffuse.raw[(size_t)i * L + l];
                assert_true(mh <= ma * (1 + 1e-5f) + 1e-12f);
                if (count[l] == 1) assert_true(mx == ma && mh == ma);
                se += ((double)mx - ma) * ((double)mx - ma);
                sa += (double)ma * ma;
            }
            if (count[l] > 1 && sa > 0 && sqrt(se / sa) > 1e-3) differ++;
        }
        free(count);
    }
    print_message("%d merged lights of several cloud lights; %d solved at their position differ from the mean by > 0.1%%\n", merged, differ);
    assert_true(merged > 0);
    assert_true(differ > 0);
    /* File round trip of the choice. */
    char path[512];
    snprintf(path, sizeof path, "%s/solve.prt", test_dir);
    assert_int_equal(prt_transfer_save(t[2], path), PRT_OK);
    prt_transfer *back = NULL;
    assert_int_equal(prt_transfer_load(ctx, path, &back), PRT_OK);
    assert_int_equal(((const prt__lightcloud_set *)back->state)->merge_response, PRT__LIGHTCLOUD_MERGE_SOLVE);
    char *desc = NULL;
    assert_int_equal(prt_transfer_describe(back, "solve", 1, &desc), PRT_OK);
    assert_non_null(strstr(desc, "\"merge_response\":\t\"solve\""));
    free(desc);
    prt_transfer_release(back);
    for (int k = 0; k < 3; ++k) prt_transfer_release(t[k]);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* ---- adding lights ---- */
#define KEPT_HEADER 56   /* the kept solutions file's header (responses.c) */

static void test_add_lights(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 6);
    const size_t box_nv = m.nv;
    tm_sphere(&m, (float[3]){0.1f, 0.25f, 0}, 0.15f, 6, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    prt_brdf shiny = {0};
    assert_int_equal(prt_brdf_parse("phong:12:0.4:0.4", &shiny), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, box_nv, m.nv - box_nv, &shiny), PRT_OK);   /* the sphere glossy */
    char kept[512], fresh[512], more[512];
    snprintf(kept, sizeof kept, "%s/kept.lcr", test_dir);
    snprintf(fresh, sizeof fresh, "%s/fresh.lcr", test_dir);
    write_text("more.json", "[[-0.3, 0.8, 0.3], [0.3, 0.45, -0.3], [-0.2, 0.4, -0.2]]", more, sizeof more);
    /* A grid with its solutions kept; then the grid and three more lights, taking them. */
    const char *first[] = {"cloud-grid", "3,3,3", "samples", "128", "basis", "48", "partition", "100", "responses", kept, NULL};
    prt_transfer *a = bake_lc(ctx, s, first);
    const size_t nv = prt_transfer_vertex_count(a);
    const uint32_t glossy = ((const prt__lightcloud_set *)a->state)->glossy_count, n = ((const prt__lightcloud_set *)a->state)->cloud_count;
    assert_true(glossy > 0);
    size_t size = 0;
    free(test_slurp(kept, &size));
    const size_t record = (4 + nv * 3 + (size_t)glossy * 48) * sizeof(float);
    assert_int_equal(size, KEPT_HEADER + n * record);
    const char *added[] = {"cloud-grid", "3,3,3", "cloud", more, "samples", "128", "basis", "48", "partition", "100", "responses", kept, NULL};
    prt_transfer *b = bake_lc(ctx, s, added);
    free(test_slurp(kept, &size));
    assert_int_equal(size, KEPT_HEADER + (n + 3) * record);
    /* The whole cloud solved anew: the same file (but the bake's time). */
    const char *whole[] = {"cloud-grid", "3,3,3", "cloud", more, "samples", "128", "basis", "48", "partition", "100", "responses", fresh, NULL};
    prt_transfer *c = bake_lc(ctx, s, whole);
    assert_int_equal(((const prt__lightcloud_set *)c->state)->cloud_count, n + 3);
    assert_same_file(b, c, "added");
    /* A file of other settings is refused, so is a damaged one; fewer lights than it holds lose none. */
    const char *other[] = {"cloud-grid", "3,3,3", "samples", "64", "basis", "48", "partition", "100", "responses", kept, NULL};
    prt_transfer *bad = NULL;
    assert_int_equal(bake_opts(ctx, s, other, &bad), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "other settings"));
    const char *fewer[] = {"cloud-grid", "2,2,2", "samples", "128", "basis", "48", "partition", "100", "responses", kept, NULL};
    prt_transfer_release(bake_lc(ctx, s, fewer));
    free(test_slurp(kept, &size));
    assert_int_equal(size, KEPT_HEADER + (n + 3 + 8) * record);
    unsigned char *bytes = test_slurp(kept, &size);
    test_spit(kept, bytes, size - 4);
    assert_int_equal(bake_opts(ctx, s, first, &bad), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "size"));
    float nan = NAN;
    memcpy(bytes + KEPT_HEADER + 4 * sizeof(float) + 8, &nan, sizeof nan);
    test_spit(kept, bytes, size);
    assert_int_equal(bake_opts(ctx, s, fewer, &bad), PRT_ERR_FORMAT);   /* its first record is the 2 x 2 x 2 grid's first light */
    assert_non_null(strstr(prt_last_error(), "non-finite"));
    free(bytes);
    prt_transfer_release(a);
    prt_transfer_release(b);
    prt_transfer_release(c);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Emission lobes kept too: at order 2 a light's record holds its 4 lobes' solutions, a bake that
 * takes them writes the same file as one without --responses, and a file kept at another order is
 * refused by name. Merging works lobe by lobe: a merged light's lobe k is the mean of its members'
 * lobe k (against a bake without merging), or with --merge-response solve a solution of each lobe
 * at the merged position. */
static void test_add_lights_lobes(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 5);
    const size_t box_nv = m.nv;
    tm_sphere(&m, (float[3]){0.1f, 0.25f, 0}, 0.15f, 5, 6);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    prt_brdf shiny = {0};
    assert_int_equal(prt_brdf_parse("phong:12:0.4:0.4", &shiny), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, box_nv, m.nv - box_nv, &shiny), PRT_OK);
    char kept[512], more[512];
    snprintf(kept, sizeof kept, "%s/lobes.lcr", test_dir);
    write_text("more.json", "[[-0.3, 0.8, 0.3], [0.3, 0.45, -0.3]]", more, sizeof more);
    const char *first[] = {"cloud-grid", "2,2,2", "emission-order", "2", "samples", "64", "basis", "32", "partition", "100", "merge-distance", "0.7",
                           "merge-error", "0", "compress", "none", "responses", kept, NULL};
    prt_transfer *a = bake_lc(ctx, s, first);
    const prt__lightcloud_set *sa = a->state;
    assert_int_equal(sa->lobes, 4);
    const size_t nv = prt_transfer_vertex_count(a), record = (4 + 4 * (nv * 3 + (size_t)sa->glossy_count * 48)) * sizeof(float);
    const uint32_t n = sa->cloud_count;
    assert_true(sa->glossy_count > 0);
    size_t size = 0;
    free(test_slurp(kept, &size));
    assert_int_equal(size, KEPT_HEADER + n * record);
    /* The grid's lights taken, the two new ones solved: the same file as a bake without the kept file. */
    const char *added[] = {"cloud-grid", "2,2,2", "cloud", more, "emission-order", "2", "samples", "64", "basis", "32", "partition", "100",
                           "merge-distance", "0.7", "merge-error", "0", "compress", "none", "responses", kept, NULL};
    const char *plain[] = {"cloud-grid", "2,2,2", "cloud", more, "emission-order", "2", "samples", "64", "basis", "32", "partition", "100",
                           "merge-distance", "0.7", "merge-error", "0", "compress", "none", NULL};
    prt_transfer *b = bake_lc(ctx, s, added), *c = bake_lc(ctx, s, plain);
    assert_int_equal(((const prt__lightcloud_set *)c->state)->cloud_count, n + 2);
    assert_same_file(b, c, "lobes");
    free(test_slurp(kept, &size));
    assert_int_equal(size, KEPT_HEADER + (n + 2) * record);
    /* Kept at order 2, asked at order 1 (the default): refused, naming the order. */
    const char *order1[] = {"cloud-grid", "2,2,2", "samples", "64", "basis", "32", "partition", "100", "merge-distance", "0.7", "responses", kept, NULL};
    prt_transfer *bad = NULL;
    assert_int_equal(bake_opts(ctx, s, order1, &bad), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "emission order 2"));
    /* The merged lights' lobes against the same cloud unmerged (the same zones), and solved. */
    const char *apart[] = {"cloud-grid", "2,2,2", "cloud", more, "emission-order", "2", "samples", "64", "basis", "32", "partition", "100",
                           "merge-distance", "0", "compress", "none", "responses", kept, NULL};
    const char *solved[] = {"cloud-grid", "2,2,2", "cloud", more, "emission-order", "2", "samples", "64", "basis", "32", "partition", "100",
                            "merge-distance", "0.7", "merge-error", "0", "compress", "none", "merge-response", "solve", "responses", kept, NULL};
    prt_transfer *u = bake_lc(ctx, s, apart), *x = bake_lc(ctx, s, solved);
    const prt__lightcloud_set *sc = c->state, *su = u->state, *sx = x->state;
    assert_int_equal(sc->zone_count, su->zone_count);
    int merged = 0, differ = 0;
    for (uint32_t z = 0; z < sc->zone_count; ++z) {
        const prt__lightcloud_zone *zc = &sc->zones[z], *zu = &su->zones[z], *zx = &sx->zones[z];
        const uint32_t Lc = zc->lights * 4, Lu = zu->lights * 4, rows = zc->diffuse.vertices * 3;
        assert_int_equal(zu->lights, sc->cloud_count);
        for (uint32_t l = 0; l < zc->lights; ++l) {
            uint32_t count = 0;
            for (uint32_t j = 0; j < sc->cloud_count; ++j) count += zc->light_of[j] == l;
            merged += count > 1;
            for (int k = 0; k < 4; ++k) {
                double se = 0, sa = 0;
                for (uint32_t i = 0; i < rows; ++i) {
                    double mean = 0;
                    for (uint32_t j = 0; j < sc->cloud_count; ++j)
                        if (zc->light_of[j] == l) mean += zu->diffuse.raw[(size_t)i * Lu + zu->light_of[j] * 4 + k];
                    mean /= count;
                    const float got = zc->diffuse.raw[(size_t)i * Lc + l * 4 + k], sol = zx->diffuse.raw[(size_t)i * Lc + l * 4 + k];
                    assert_float_equal(got, mean, 1e-5 * fabs(mean) + 1e-9);
                    if (count == 1) assert_true(sol == got);
                    se += ((double)sol - got) * ((double)sol - got);
                    sa += (double)got * got;
                }
                if (count > 1 && sa > 0 && sqrt(se / sa) > 1e-3) differ++;
            }
        }
    }
    print_message("order 2: %d merged lights of several cloud lights; %d of their lobes solved at the position differ from the mean by > 0.1%%\n", merged,
                  differ);
    assert_true(merged > 0);
    assert_true(differ > 0);
    prt_transfer_release(u);
    prt_transfer_release(x);
    prt_transfer_release(a);
    prt_transfer_release(b);
    prt_transfer_release(c);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* ---- glossy vertices ---- */
/* Relative L2 over the glossy vertices that face the eye, of a against b (3 per vertex). */
static double glossy_error(const prt_transfer *t, const float *a, const float *b, const float eye[3])
{
    const prt__lightcloud_set *s = t->state;
    const float *P = prt_transfer_positions(t), *N = prt_transfer_normals(t);
    double se = 0, sb = 0;
    for (size_t v = 0; v < prt_transfer_vertex_count(t); ++v) {
        const float d[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]};
        if (s->glossy_of[v] == UINT32_MAX || d[0] * N[v * 3] + d[1] * N[v * 3 + 1] + d[2] * N[v * 3 + 2] <= 0) continue;
        for (int c = 0; c < 3; ++c) {
            se += ((double)a[v * 3 + c] - b[v * 3 + c]) * ((double)a[v * 3 + c] - b[v * 3 + c]);
            sb += (double)b[v * 3 + c] * b[v * 3 + c];
        }
    }
    return sqrt(se / sb);
}

/* A glossy sphere (Phong exponent 12, the paper's Fig. 9 lobe) in a closed box with a red and a
 * blue wall, lit by a point light placed on a cloud light (so that neither interpolation nor
 * merging nor compression stands between the cloud light's solution and what is measured): the
 * glossy vertices' exit SH (order 4), evaluated towards a fixed eye by prt_relit_shade, against the
 * path tracer's radiance towards the same eye. The light that bounced at least once is what the
 * exit SH carries; without it the glossy vertices would show only their diffuse part. All light
 * as drawn adds the point light's direct light with the sphere's BRDF (its glossy highlight too,
 * per vertex as the renderer does it per pixel). */
static void test_glossy_vs_reference(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 8);
    const size_t box_nv = m.nv;
    tm_sphere(&m, (float[3]){0, 0.3f, 0}, 0.22f, 16, 24);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    /* The walls at x = -0.5 (red) and x = +0.5 (blue): the second and third faces of the pit. */
    prt_brdf red = {0}, blue = {0}, shiny = {0};
    assert_int_equal(prt_brdf_parse("lambert:0.7", &red), PRT_OK);
    blue = red;
    red.diffuse[1] = red.diffuse[2] = 0.1f;
    blue.diffuse[0] = blue.diffuse[1] = 0.1f;
    const size_t face = (size_t)9 * 9;
    assert_int_equal(prt_scene_set_brdf(s, face, face, &red), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, 2 * face, face, &blue), PRT_OK);
    assert_int_equal(prt_brdf_parse("phong:12:0.5:0.3", &shiny), PRT_OK);
    assert_int_equal(prt_scene_set_brdf(s, box_nv, m.nv - box_nv, &shiny), PRT_OK);
    const char *opts[] = {"cloud-grid", "3,3,3", "samples", "512", "basis", "128", "partition", "200", "compress", "none", "merge-distance", "0", NULL};
    prt_transfer *t = bake_lc(ctx, s, opts);
    const prt__lightcloud_set *set = t->state;
    assert_true(set->glossy_count > 0);
    const size_t nv = prt_transfer_vertex_count(t);
    /* A cloud light up and to the side (the grid's (0, 2, 2) cell: x = -1/3, y = 5/6, z = 1/3). */
    char spec[128];
    snprintf(spec, sizeof spec, "point:%.9g,%.9g,%.9g:1", -1.0 / 3, 5.0 / 6, 1.0 / 3);
    prt_lighting *l = one_light(spec);
    prt_lighting_set_emission(l, 0.0f);
    const float eye[3] = {0.35f, 0.45f, 0.45f};
    prt_relit ind, all;
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT}, &ind), PRT_OK);
    assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1}, &all), PRT_OK);   /* as drawn: the light per pixel */
    assert_non_null(ind.exit_sh);
    float *shade_ind = malloc(nv * 3 * sizeof(float)), *shade_all = malloc(nv * 3 * sizeof(float));
    assert_int_equal(prt_relit_shade(ctx, t, &ind, eye, shade_ind), PRT_OK);
    assert_int_equal(prt_relit_shade(ctx, t, &all, eye, shade_all), PRT_OK);
    prt_scene *traced = NULL;
    assert_int_equal(prt_transfer_scene(ctx, t, &traced), PRT_OK);
    prt_reference_desc rd = {0};
    rd.samples = 1024;
    rd.lighting = l;
    rd.eye = eye;
    prt_reference_vertices ref;
    assert_int_equal(prt_reference_trace_vertices(ctx, traced, NULL, &rd, &ref), PRT_OK);
    const double e_ind = glossy_error(t, shade_ind, ref.indirect, eye);
    double sn = 0, sb = 0;
    const float *P = prt_transfer_positions(t), *N = prt_transfer_normals(t);
    for (size_t v = 0; v < nv; ++v) {
        const float d[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]};
        if (set->glossy_of[v] == UINT32_MAX || d[0] * N[v * 3] + d[1] * N[v * 3 + 1] + d[2] * N[v * 3 + 2] <= 0) continue;
        for (int c = 0; c < 3; ++c) {
            sn += (double)ref.std_error_indirect[v * 3 + c] * ref.std_error_indirect[v * 3 + c];
            sb += (double)ref.indirect[v * 3 + c] * ref.indirect[v * 3 + c];
        }
    }
    const double noise = sqrt(sn / sb), beyond = sqrt(fmax(0, e_ind * e_ind - noise * noise));
    const double e_flat = glossy_error(t, ind.radiance, ref.indirect, eye);   /* the diffuse part alone */
    const double e_all = glossy_error(t, shade_all, ref.radiance, eye);
    print_message("glossy vertices towards the eye, indirect light: exit SH %.4f (reference noise %.4f: %.4f beyond it); without the exit SH %.4f; "
                  "all light %.4f\n", e_ind, noise, beyond, e_flat, e_all);
    /* Measured: exit SH 0.213 (0.203 beyond the noise; 0.163 with a basis of 512 functions: the
     * rest is the order-4 SH of a Phong-12 lobe seen at grazing angles), 0.600 without it; all
     * light 0.142 (0.411 with the direct light Lambertian, per_vertex = 1, the point light's own
     * highlight missing). */
    assert_true(beyond < 0.25);
    assert_true(e_flat > 2.5 * e_ind);
    assert_true(e_all < 0.25);
    free(shade_ind);
    free(shade_all);
    prt_relit_free(&ind);
    prt_relit_free(&all);
    prt_reference_vertices_free(&ref);
    prt_scene_release(traced);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_merge_values),
        cmocka_unit_test_setup_teardown(test_merge_modes, test_dir_setup, test_dir_teardown),
        cmocka_unit_test_setup_teardown(test_add_lights, test_dir_setup, test_dir_teardown),
        cmocka_unit_test_setup_teardown(test_add_lights_lobes, test_dir_setup, test_dir_teardown),
        cmocka_unit_test(test_glossy_vs_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
