/* Light clouds beyond the old 4,096-light cap (issue 28): the candidate pairs found through the
 * grid are every pair within the distance; the clustering over them gives the clusters of the
 * all-pairs code it replaced (kept here, slow, as the reference) on random and gridded clouds with
 * the response and visibility terms in; a cloud of 21,952 lights bakes, relights a light on a
 * cloud light with that light's own solution, agrees with a 6 x 6 x 6 cloud where both are
 * accurate, and bakes the same file on 1 and 2 threads. */
#include "common.h"
#include "methods/lightcloud/lightcloud.h"

#include "methods/lightcloud/all_pairs.h"

/* ---- a synthetic eq. 9 ---- */
#define PROBES 24
typedef struct cloud {
    const float *p;
    float distance;        /* merge distance */
    float w2;              /* response term's weight (0: left out) */
    float resp[0x4000][PROBES];   /* each light's "response" at a few probe points */
    int hide;              /* pairs whose hash is 0 mod hide are not visible (0: all visible) */
} cloud;

static float synthetic_metric(void *user, uint32_t j, uint32_t k)
{
    const cloud *c = user;
    float d[3];
    prt__v3_sub(c->p + (size_t)j * 3, c->p + (size_t)k * 3, d);
    float m = prt__v3_len(d) / c->distance;
    if (m >= 1.0f) return m;
    if (c->hide && ((j * 2654435761u) ^ (k * 40503u)) % (uint32_t)c->hide == 0) return m + 1.0f;
    float worst = 0;
    for (int i = 0; i < PROBES; ++i) worst = fmaxf(worst, fabsf(c->resp[j][i] - c->resp[k][i]));
    return m + c->w2 * worst;
}
static float pair_metric(void *user, uint32_t j, uint32_t k, uint64_t pair)
{
    (void)pair;
    return synthetic_metric(user, j, k);
}

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static float uniform(void)
{
    rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
    return (float)((rng >> 11) / 9007199254740992.0);
}

/* The grid finds exactly the pairs closer than r, each once, ascending. */
static void test_pairs(void **state)
{
    (void)state;
    const uint32_t n = 1500;
    float *p = malloc(n * 3 * sizeof(float));
    for (uint32_t i = 0; i < n * 3; ++i) p[i] = uniform() * (i % 3 == 1 ? 0.3f : 1.0f);
    const float radii[] = {0.0005f, 0.03f, 0.1f, 0.4f, 5.0f};   /* far below the spacing (wide cells), typical, every pair */
    for (size_t ri = 0; ri < sizeof radii / sizeof radii[0]; ++ri) {
        prt__lightcloud_pairs pairs;
        assert_int_equal(prt__lightcloud_pairs_find(NULL, p, n, radii[ri], 2, &pairs), PRT_OK);
        uint64_t at = 0;
        for (uint32_t j = 0; j < n; ++j) {
            assert_int_equal(pairs.start[j], at);
            for (uint32_t k = j + 1; k < n; ++k) {
                float d[3];
                prt__v3_sub(p + j * 3, p + k * 3, d);
                if (!(prt__v3_len(d) < radii[ri])) continue;
                assert_true(at < pairs.count);
                assert_int_equal(pairs.other[at], k);
                at++;
            }
        }
        assert_int_equal(pairs.count, at);
        if (ri == 4) assert_int_equal(at, (uint64_t)n * (n - 1) / 2);
        prt__lightcloud_pairs_free(&pairs);
    }
    free(p);
}

static void check_same(cloud *c, uint32_t n, const char *what)
{
    prt__lightcloud_pairs pairs;
    assert_int_equal(prt__lightcloud_pairs_find(NULL, c->p, n, c->distance, 1, &pairs), PRT_OK);
    uint32_t *fast = malloc(n * sizeof(uint32_t)), *slow = malloc(n * sizeof(uint32_t)), count = 0;
    assert_int_equal(prt__lightcloud_cluster(NULL, &pairs, pair_metric, c, fast, &count), PRT_OK);
    const uint32_t expect = all_pairs(n, synthetic_metric, c, slow);
    print_message("%s: %u lights, %llu candidate pairs, %u clusters (all pairs: %u)\n", what, n, (unsigned long long)pairs.count, count, expect);
    assert_int_equal(count, expect);
    assert_true(count < n && count > 1);
    assert_memory_equal(fast, slow, n * sizeof(uint32_t));
    prt__lightcloud_pairs_free(&pairs);
    free(fast);
    free(slow);
}

/* The same clusters as the all-pairs code: a random cloud and a grid (many equal distances: the
 * ties break the same way), distance only, with the response term, with hidden pairs. */
static void test_same_clusters_as_all_pairs(void **state)
{
    (void)state;
    const uint32_t side = 14, n = side * side * side;   /* 2,744 */
    float *grid = malloc(n * 3 * sizeof(float)), *random = malloc(n * 3 * sizeof(float));
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t x = i % side, y = i / side % side, z = i / (side * side);
        grid[i * 3] = (x + 0.5f) / side; grid[i * 3 + 1] = (y + 0.5f) / side; grid[i * 3 + 2] = (z + 0.5f) / side;
        for (int k = 0; k < 3; ++k) random[i * 3 + k] = uniform();
    }
    cloud *c = calloc(1, sizeof *c);
    float probe[PROBES][3];
    for (int i = 0; i < PROBES; ++i)
        for (int k = 0; k < 3; ++k) probe[i][k] = uniform();
    const float *clouds[2] = {grid, random};
    for (int which = 0; which < 2; ++which) {
        c->p = clouds[which];
        /* Responses falling off as 1 / (d^2 + 0.05): near lights differ little, near probes much. */
        float largest = 0;
        for (uint32_t j = 0; j < n; ++j)
            for (int i = 0; i < PROBES; ++i) {
                float d[3];
                prt__v3_sub(c->p + j * 3, probe[i], d);
                c->resp[j][i] = 1.0f / (prt__v3_dot(d, d) + 0.05f);
                largest = fmaxf(largest, c->resp[j][i]);
            }
        c->distance = 3.0f / side;
        char what[64];
        c->w2 = 0; c->hide = 0;
        snprintf(what, sizeof what, "%s, distance only", which ? "random" : "grid");
        check_same(c, n, what);
        c->w2 = 1.0f / (0.1f * largest); c->hide = 0;
        snprintf(what, sizeof what, "%s, with responses", which ? "random" : "grid");
        check_same(c, n, what);
        c->w2 = 1.0f / (0.3f * largest); c->hide = 5;
        snprintf(what, sizeof what, "%s, responses and hidden pairs", which ? "random" : "grid");
        check_same(c, n, what);
    }
    free(c);
    free(grid);
    free(random);
}

/* ---- a dense cloud baked ---- */
/* Closed box of side 1 (inward normals), floor at y = 0, with a sphere casting shadows. */
static prt_scene *box_scene(prt_context *ctx, test_mesh *m)
{
    tm_pit(m, 6);
    tm_quad(m, (float[3]){-0.5f, 1, -0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, 1}, 6);   /* ceiling, facing down */
    tm_sphere(m, (float[3]){0.2f, 0.3f, 0.1f}, 0.15f, 6, 8);
    return tm_scene(ctx, m, 0.6f);
}

static prt_transfer *bake(prt_context *ctx, const prt_scene *s, const char *method, const char *grid, const char *const *more)
{
    const char *opts[32] = {"samples", "128", "basis", "48", "partition", "100"};
    int n = 6;
    if (grid) { opts[n++] = "cloud-grid"; opts[n++] = grid; }
    for (int i = 0; more && more[i]; ++i) opts[n++] = more[i];
    opts[n] = NULL;
    return test_bake_with(ctx, s, method, opts);
}

static double rel_l2(const float *a, const float *b, size_t n)
{
    double se = 0, sb = 0;
    for (size_t i = 0; i < n; ++i) {
        se += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
        sb += (double)b[i] * b[i];
    }
    return sqrt(se / sb);
}

static size_t cloud_lights(const prt_transfer *t) { return prt__lightcloud(t)->cloud_count; }

/* 21,952 cloud lights (28^3) bake and relight. Unmerged and uncompressed, a light's indirect light
 * is closer to the spectral method's solution at the light itself (what the cloud interpolates)
 * than a 6 x 6 x 6 cloud's; merged and compressed (the defaults), within the merging's error. */
static void test_dense_cloud(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    prt_scene *s = box_scene(ctx, &m);
    char kept[512];
    snprintf(kept, sizeof kept, "%s/kept.lcr", test_dir);
    const char *raw[] = {"merge-distance", "0", "compress", "none", "responses", kept, NULL}, *raw_small[] = {"merge-distance", "0", "compress", "none", NULL};
    const char *merged[] = {"responses", kept, NULL};   /* the same solutions, taken from the file */
    prt_transfer *sp = bake(ctx, s, "spectral", NULL, NULL), *dense = bake(ctx, s, "lightcloud", "28,28,28", raw),
                 *small = bake(ctx, s, "lightcloud", "6,6,6", raw_small), *dense_merged = bake(ctx, s, "lightcloud", "28,28,28", merged);
    assert_true(cloud_lights(dense) > 20000);
    assert_int_equal(cloud_lights(dense_merged), cloud_lights(dense));
    const size_t nv = prt_transfer_vertex_count(sp);
    const int sixteen[2] = {16, 1};   /* the bake's bounces and the spectral tail */
    double sum_dense = 0, sum_small = 0, worst_dense = 0, worst_merged = 0;
    for (int i = 0; i < 6; ++i) {
        char spec[128];   /* in the open, away from the sphere */
        snprintf(spec, sizeof spec, "point:%g,%g,%g:1", -0.4 + 0.35 * uniform(), 0.2 + 0.7 * uniform(), -0.4 + 0.8 * uniform());
        prt_lighting *l = NULL;
        assert_int_equal(prt_lighting_create(&l), PRT_OK);
        prt_light li;
        assert_int_equal(prt_light_parse(spec, &li), PRT_OK);
        assert_int_equal(prt_lighting_add(l, &li, NULL), PRT_OK);
        prt_relit want, a, b, c;
        const prt_relight_desc ind = {.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT};
        prt_relight_desc ind16 = ind;
        ind16.controls = sixteen;
        assert_int_equal(prt_relight(ctx, sp, l, &ind16, &want), PRT_OK);
        assert_int_equal(prt_relight(ctx, dense, l, &ind, &a), PRT_OK);
        assert_int_equal(prt_relight(ctx, small, l, &ind, &b), PRT_OK);
        assert_int_equal(prt_relight(ctx, dense_merged, l, &ind, &c), PRT_OK);
        const double ed = rel_l2(a.radiance, want.radiance, nv * 3), es = rel_l2(b.radiance, want.radiance, nv * 3),
                     em = rel_l2(c.radiance, want.radiance, nv * 3);
        print_message("%s: indirect light against the spectral solution at the light: %.4f (21,952 lights), %.4f (216), merged and compressed "
                      "%.4f (21,952)\n", spec, ed, es, em);
        sum_dense += ed;
        sum_small += es;
        worst_dense = fmax(worst_dense, ed);
        worst_merged = fmax(worst_merged, em);
        prt_relit_free(&want);
        prt_relit_free(&a);
        prt_relit_free(&b);
        prt_relit_free(&c);
        prt_lighting_release(l);
    }
    print_message("mean: %.4f (21,952 lights), %.4f (216); worst %.4f, merged and compressed %.4f\n", sum_dense / 6, sum_small / 6, worst_dense,
                  worst_merged);
    assert_true(sum_dense < sum_small);
    assert_true(worst_dense < 0.05);
    assert_true(worst_merged < 0.15);
    prt_transfer_release(dense_merged);
    prt_transfer_release(small);
    prt_transfer_release(dense);
    prt_transfer_release(sp);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Beyond 4,096 lights the file is the same on 1 and 2 threads; past the limit the bake is refused
 * before any work. */
static void test_dense_threads_and_limit(void **state)
{
    (void)state;
    test_mesh m = {0};
    prt_context *one = test_context(1), *two = test_context(2);
    prt_scene *s = box_scene(one, &m);
    prt_transfer *a = bake(one, s, "lightcloud", "17,17,17", NULL), *b = bake(two, s, "lightcloud", "17,17,17", NULL);   /* 4,913 */
    assert_true(cloud_lights(a) > 4096);
    assert_same_file(a, b, "dense");
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("lightcloud"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "cloud-grid", "102,102,102"), PRT_OK);   /* 1,061,208 */
    prt_transfer *bad = NULL;
    assert_int_equal(prt_bake(one, s, prt_method_find("lightcloud"), o, NULL, &bad), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "at most 1048576"));
    prt_options_release(o);
    prt_transfer_release(a);
    prt_transfer_release(b);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(one);
    prt_context_release(two);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pairs),
        cmocka_unit_test(test_same_clusters_as_all_pairs),
        cmocka_unit_test_setup_teardown(test_dense_cloud, test_dir_setup, test_dir_teardown),
        cmocka_unit_test_setup_teardown(test_dense_threads_and_limit, test_dir_setup, test_dir_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
