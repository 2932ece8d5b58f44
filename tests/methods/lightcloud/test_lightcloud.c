/* Precomputed local radiance transfer through a light cloud (Kristensen et al. 2005): a light at
 * a cloud light gives that light's solution (exactly, then within the compression error), the
 * clustering against a brute-force one, no light through a closed wall, no popping while a light
 * is dragged, the Cornell box against the path tracer, files and bad input. */
#include "common.h"
#include "methods/lightcloud/lightcloud.h"

/* Closed box of side 1 (inward normals), its floor at y = 0, centred at x = cx. */
static void closed_box(test_mesh *m, int n, float cx)
{
    const size_t first = m->nv;
    tm_pit(m, n);
    tm_quad(m, (float[3]){-0.5f, 1, -0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, 1}, n);   /* ceiling, facing down */
    for (size_t v = first; v < m->nv; ++v) m->pos[v * 3] += cx;
}

static prt_transfer *bake_lc(prt_context *ctx, const prt_scene *s, const char *const *opts)
{
    const prt_method *lc = prt_method_find("lightcloud");
    assert_non_null(lc);
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(lc, &o), PRT_OK);
    for (int i = 0; opts && opts[i]; i += 2) assert_int_equal(prt_options_set(o, opts[i], opts[i + 1]), PRT_OK);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, s, lc, o, NULL, &t), PRT_OK);
    prt_options_release(o);
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

static double rel_l2(const float *a, const float *b, size_t n)
{
    double se = 0, sb = 0;
    for (size_t i = 0; i < n; ++i) {
        se += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
        sb += (double)b[i] * b[i];
    }
    return sqrt(se / sb);
}

static const char cloud_json[] = "[[-0.25, 0.3, -0.25], [0.25, 0.3, -0.25], [-0.25, 0.7, -0.25], [0.25, 0.7, -0.25],"
                                 " [-0.25, 0.3, 0.25], [0.25, 0.3, 0.25], [-0.25, 0.7, 0.25], [0.25, 0.7, 0.25]]";

/* A light placed on a cloud light gets exactly that light's global illumination (the spectral
 * method's run time under the same light, with the same bounces), coloured and scaled; after
 * CPCA, within the compression's own error. */
static void test_light_at_cloud_light(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 8, 0);
    tm_sphere(&m, (float[3]){0, 0.2f, 0}, 0.15f, 8, 12);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    char path[512];
    write_text("cloud.json", cloud_json, path, sizeof path);
    const char *raw_opts[] = {"cloud", path, "compress", "none", "merge-distance", "0", "samples", "256", "basis", "64", "partition", "150", NULL};
    prt_transfer *raw = bake_lc(ctx, s, raw_opts);
    prt_options *so = NULL;
    assert_int_equal(prt_options_create(prt_method_find("spectral"), &so), PRT_OK);
    prt_options_set(so, "samples", "256");
    prt_options_set(so, "basis", "64");
    prt_options_set(so, "partition", "150");
    prt_transfer *sp = NULL;
    assert_int_equal(prt_bake(ctx, s, prt_method_find("spectral"), so, NULL, &sp), PRT_OK);
    prt_options_release(so);
    const size_t nv = prt_transfer_vertex_count(raw);
    prt_lighting *l = one_light("point:0.25,0.7,-0.25:2,1,0.5");
    const int sixteen[2] = {16, 1};   /* the bake's bounces and the spectral tail */
    prt_relit a, b;
    assert_int_equal(prt_relight(ctx, raw, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1}, &a), PRT_OK);
    assert_int_equal(prt_relight(ctx, sp, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .controls = sixteen}, &b), PRT_OK);
    for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(a.radiance[i], b.radiance[i], 1e-6f + 1e-5f * b.radiance[i]);
    /* The indirect part alone, and the direct part alone, add up. */
    prt_relit ind, dir;
    assert_int_equal(prt_relight(ctx, raw, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT}, &ind), PRT_OK);
    assert_int_equal(prt_relight(ctx, raw, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_DIRECT}, &dir), PRT_OK);
    double indirect_sum = 0;
    for (size_t i = 0; i < nv * 3; ++i) {
        assert_float_equal(ind.radiance[i] + dir.radiance[i], a.radiance[i], 1e-6f + 1e-5f * a.radiance[i]);
        indirect_sum += ind.radiance[i];
    }
    assert_true(indirect_sum > 0);
    prt_relit_free(&ind);
    prt_relit_free(&dir);
    /* Compressed: within a small multiple of the CPCA's relative error over the zone. */
    const char *cpca_opts[] = {"cloud", path, "merge-distance", "0", "samples", "256", "basis", "64", "partition", "150", "clusters", "2", "vectors", "3", NULL};
    prt_transfer *cp = bake_lc(ctx, s, cpca_opts);
    char *desc = NULL;
    assert_int_equal(prt_transfer_describe(cp, "cp", 1, &desc), PRT_OK);
    const char *at = strstr(desc, "\"cpca_relative_error\":");
    assert_non_null(at);
    const double cpca_err = atof(at + strlen("\"cpca_relative_error\":"));
    free(desc);
    prt_relit c, cind;
    assert_int_equal(prt_relight(ctx, cp, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1}, &c), PRT_OK);
    assert_int_equal(prt_relight(ctx, cp, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT}, &cind), PRT_OK);
    assert_int_equal(prt_relight(ctx, raw, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT}, &ind), PRT_OK);
    const double e_ind = rel_l2(cind.radiance, ind.radiance, nv * 3), e_all = rel_l2(c.radiance, a.radiance, nv * 3);
    print_message("CPCA (2 clusters, 3 vectors): relative error %.4f of the responses; this light's indirect %.4f, total %.4f\n", cpca_err, e_ind,
                  e_all);
    assert_true(cpca_err > 0 && cpca_err < 0.2);
    assert_true(e_ind < 3 * cpca_err);
    assert_true(e_all <= e_ind);
    prt_relit_free(&a);
    prt_relit_free(&b);
    prt_relit_free(&c);
    prt_relit_free(&cind);
    prt_relit_free(&ind);
    prt_lighting_release(l);
    prt_transfer_release(cp);
    prt_transfer_release(raw);
    prt_transfer_release(sp);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* ---- clustering ---- */
typedef struct points { const float *p; float scale; } points;

static float distance_metric(void *user, uint32_t j, uint32_t k, uint64_t pair)
{
    (void)pair;
    const points *pts = user;
    float d[3];
    for (int i = 0; i < 3; ++i) d[i] = pts->p[j * 3 + i] - pts->p[k * 3 + i];
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * pts->scale;
}

/* The paper's rule done the slow way: repeatedly merge the two clusters whose farthest member
 * pair is closest, while that is below 1. */
static uint32_t brute_force(const points *pts, uint32_t n, uint32_t *cluster_of)
{
    uint32_t *head = malloc(n * sizeof(uint32_t));
    for (uint32_t i = 0; i < n; ++i) head[i] = i;
    for (;;) {
        float best = INFINITY;
        uint32_t ba = 0, bb = 0;
        for (uint32_t a = 0; a < n; ++a)
            for (uint32_t b = a + 1; b < n; ++b) {
                if (head[a] != a || head[b] != b) continue;
                float worst = 0;
                for (uint32_t i = 0; i < n; ++i)
                    for (uint32_t j = 0; j < n; ++j)
                        if (head[i] == a && head[j] == b) worst = fmaxf(worst, distance_metric((void *)pts, i, j, 0));
                if (worst < best) { best = worst; ba = a; bb = b; }
            }
        if (!(best < 1.0f)) break;
        for (uint32_t i = 0; i < n; ++i)
            if (head[i] == bb) head[i] = ba;
    }
    uint32_t count = 0;
    for (uint32_t i = 0; i < n; ++i) cluster_of[i] = head[i] == i ? count++ : cluster_of[head[i]];
    free(head);
    return count;
}

/* With the response and visibility terms out (w2 = 0, every pair visible), the clustering is
 * distance-only complete linkage: the same partition as the brute-force merge. */
static void test_clustering_distance_only(void **state)
{
    (void)state;
    uint64_t rng = 0x9E3779B97F4A7C15ull;
    for (int round = 0; round < 6; ++round) {
        const uint32_t n = 30 + 7 * (uint32_t)round;
        float *p = malloc(n * 3 * sizeof(float));
        for (uint32_t i = 0; i < n * 3; ++i) {
            rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
            p[i] = (float)(rng >> 11) / 9007199254740992.0f;
        }
        points pts = {p, 1.0f / (0.15f + 0.05f * round)};
        uint32_t *fast = malloc(n * sizeof(uint32_t)), *slow = malloc(n * sizeof(uint32_t)), count = 0;
        /* Candidates a little beyond the distance: the clustering leaves pairs at 1 or more apart. */
        prt__lightcloud_pairs pairs;
        assert_int_equal(prt__lightcloud_pairs_find(NULL, p, n, 1.001f / pts.scale, 1, &pairs), PRT_OK);
        assert_int_equal(prt__lightcloud_cluster(NULL, &pairs, distance_metric, &pts, fast, &count), PRT_OK);
        prt__lightcloud_pairs_free(&pairs);
        const uint32_t expect = brute_force(&pts, n, slow);
        assert_int_equal(count, expect);
        assert_true(count < n && count > 1);
        for (uint32_t i = 0; i < n; ++i) assert_int_equal(fast[i], slow[i]);
        /* Every pair inside a cluster is close (the all-pairs rule). */
        for (uint32_t i = 0; i < n; ++i)
            for (uint32_t j = i + 1; j < n; ++j)
                if (fast[i] == fast[j]) assert_true(distance_metric(&pts, i, j, 0) < 1.0f);
        free(p);
        free(fast);
        free(slow);
    }
}

/* Two closed rooms side by side: a light in one puts nothing in the other, direct or indirect,
 * through the cloud lights of the other room, the clustering or the compression. */
static void test_no_light_through_walls(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 8, -0.55f);
    closed_box(&m, 8, 0.55f);
    prt_scene *s = tm_scene(ctx, &m, 0.7f);
    const char *opts[] = {"cloud-grid", "6,3,3", "samples", "256", "basis", "128", "partition", "150", "zone-vertices", "200", NULL};
    prt_transfer *t = bake_lc(ctx, s, opts);
    const size_t nv = prt_transfer_vertex_count(t);
    const float *pos = prt_transfer_positions(t);
    /* Close to the dividing wall, among cloud lights of both rooms. */
    const char *specs[2] = {"point:-0.1,0.5,0.05:3", "point:-0.5,0.5,0.1:3"};
    for (int k = 0; k < 2; ++k) {
        prt_lighting *l = one_light(specs[k]);
        prt_relit r;
        assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1}, &r), PRT_OK);
        double lit = 0, dark = 0;
        size_t nlit = 0;
        for (size_t v = 0; v < nv; ++v) {
            if (pos[v * 3] < 0) { lit += r.radiance[v * 3]; nlit++; }
            else dark = fmax(dark, fabs(r.radiance[v * 3]) + fabs(r.radiance[v * 3 + 1]) + fabs(r.radiance[v * 3 + 2]));
        }
        print_message("%s: lit room mean %.4g, other room at most %.3g\n", specs[k], lit / nlit, dark);
        assert_true(lit > 0);
        assert_true(dark <= 1e-6 * lit / nlit);
        prt_relit_free(&r);
        prt_lighting_release(l);
    }
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Largest change of any vertex's indirect light in one step of a drag along a path in `steps`
 * steps, relative to the largest indirect value seen. */
static double drag(prt_context *ctx, const prt_transfer *t, int steps)
{
    const size_t nv = prt_transfer_vertex_count(t);
    float *prev = malloc(nv * 3 * sizeof(float));
    double worst = 0, largest = 0;
    for (int i = 0; i <= steps; ++i) {
        const double u = (double)i / steps;
        char spec[128];   /* over the sphere, which hides the cloud lights below it one after another */
        snprintf(spec, sizeof spec, "point:%.9g,%.9g,%.9g:1", -0.42 + 0.84 * u, 0.7, -0.3 + 0.3 * u);
        prt_lighting *l = one_light(spec);
        prt_relit r;
        assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT}, &r), PRT_OK);
        for (size_t k = 0; k < nv * 3; ++k) {
            largest = fmax(largest, r.radiance[k]);
            if (i) worst = fmax(worst, fabs(r.radiance[k] - prev[k]));
        }
        memcpy(prev, r.radiance, nv * 3 * sizeof(float));
        prt_relit_free(&r);
        prt_lighting_release(l);
    }
    free(prev);
    return worst / largest;
}

/* A light dragged in small steps through the room, past an obstacle that hides cloud lights
 * from it: per step of 1/20 of the cloud spacing no vertex's indirect light changes by more than
 * 8% of the largest, and halving the step halves the change (no jumps: weights fall to zero at
 * the edge of the neighbourhood, and hidden cloud lights fade out over a short distance). */
static void test_no_popping(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 8, 0);
    tm_sphere(&m, (float[3]){0, 0.45f, 0}, 0.18f, 8, 12);
    prt_scene *s = tm_scene(ctx, &m, 0.6f);
    const char *opts[] = {"cloud-grid", "4,4,4", "samples", "256", "basis", "96", "partition", "150", "compress", "none", "merge-distance", "0", NULL};
    prt_transfer *t = bake_lc(ctx, s, opts);
    /* Spacing 0.25; the path is 0.89 long: 71 steps of 1/20 spacing. */
    const double coarse = drag(ctx, t, 71), fine = drag(ctx, t, 142), finer = drag(ctx, t, 284);
    print_message("dragging: largest change of a vertex's indirect light per step, relative to the largest: %.4f, halved steps %.4f, "
                  "quartered %.4f\n", coarse, fine, finer);
    assert_true(coarse < 0.08);
    assert_true(fine < 0.6 * coarse);
    assert_true(finer < 0.6 * fine);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* Files keep everything; damaged ones are refused; bad input fails clearly. */
static void test_files_and_bad_input(void **state)
{
    (void)state;
    prt_context *ctx = test_context(0);
    test_mesh m = {0};
    closed_box(&m, 6, 0);
    tm_sphere(&m, (float[3]){0.2f, 0.5f, 0}, 0.1f, 6, 8);
    prt_scene *s = tm_scene(ctx, &m, 0.5f);
    assert_int_equal(prt_scene_set_emission(s, 0, 49, (float[3]){0.5f, 0.5f, 0.5f}), PRT_OK);   /* the floor glows */
    const char *opts[] = {"cloud-grid", "3,3,3", "samples", "128", "basis", "48", "partition", "100", NULL};
    prt_transfer *t = bake_lc(ctx, s, opts);
    char path[512];
    snprintf(path, sizeof path, "%s/lc.prt", test_dir);
    assert_int_equal(prt_transfer_save(t, path), PRT_OK);
    prt_transfer *back = NULL;
    assert_int_equal(prt_transfer_load(ctx, path, &back), PRT_OK);
    prt_lighting *l = one_light("point:0.1,0.6,0.1:2");
    prt_lighting_set_emission(l, 1.0f);
    prt_relit a, b;
    assert_int_equal(prt_relight(ctx, t, l, NULL, &a), PRT_OK);
    assert_int_equal(prt_relight(ctx, back, l, NULL, &b), PRT_OK);
    const size_t nv = prt_transfer_vertex_count(t);
    for (size_t i = 0; i < nv * 3; ++i) assert_float_equal(a.radiance[i], b.radiance[i], 0.0f);
    assert_non_null(a.pixel_lights);   /* drawn: the point light's direct light is per pixel */
    prt_relit_free(&a);
    prt_relit_free(&b);
    /* Lights it cannot relight are refused with the reason. */
    prt_lighting *spot = one_light("spot:0,0.9,0:0,-1,0:30:1");
    assert_int_equal(prt_relight(ctx, t, spot, NULL, &a), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "spot"));
    prt_lighting_release(spot);
    /* Every byte of a chunk damaged: the CRC catches it; the truncated file is refused. */
    size_t size = 0;
    unsigned char *data = NULL;
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    data = malloc(size);
    assert_int_equal(fread(data, 1, size, f), size);
    fclose(f);
    prt_transfer *broken = NULL;
    assert_int_not_equal(prt_transfer_load_memory(ctx, data, size / 2, &broken), PRT_OK);
    free(data);
    /* Options and cloud files. */
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("lightcloud"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "cloud-grid", "3,x,3"), PRT_OK);   /* text: checked when baking */
    prt_transfer *bad = NULL;
    assert_int_equal(prt_bake(ctx, s, prt_method_find("lightcloud"), o, NULL, &bad), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "--cloud-grid"));
    char list[512];
    write_text("bad.json", "[[0, 0.5, 0], [1, \"two\", 3]]", list, sizeof list);
    prt_options_set(o, "cloud-grid", "2,2,2");
    prt_options_set(o, "cloud", list);
    assert_int_equal(prt_bake(ctx, s, prt_method_find("lightcloud"), o, NULL, &bad), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "light 1"));
    write_text("inside.json", "[[0.2, 0.5, 0.01], [0.21, 0.52, 0]]", list, sizeof list);
    prt_options_release(o);
    assert_int_equal(prt_options_create(prt_method_find("lightcloud"), &o), PRT_OK);
    prt_options_set(o, "cloud", list);
    prt_options_set(o, "samples", "64");
    /* Every cloud light inside the sphere: nothing left to bake. */
    assert_int_equal(prt_bake(ctx, s, prt_method_find("lightcloud"), o, NULL, &bad), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "no cloud light"));
    prt_options_release(o);
    prt_lighting_release(l);
    prt_transfer_release(back);
    prt_transfer_release(t);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

/* The Cornell box against the path tracer: four point lights at random positions that are not
 * cloud lights, total and indirect light (emitters left out of the comparison). The 6 x 6 x 6
 * cloud's interpolation dominates the error (measured against 1024 paths: the spectral solve at
 * the light itself 2% beyond the reference's noise, interpolated 10%, merged and compressed 13%,
 * for indirect light; README: error against cloud density). */
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
    const char *opts[] = {"cloud-grid", "6,6,6", "samples", "1024", NULL};
    prt_transfer *t = bake_lc(ctx, s, opts);
    const size_t nv = prt_transfer_vertex_count(t);
    prt_scene *traced = NULL;
    assert_int_equal(prt_transfer_scene(ctx, t, &traced), PRT_OK);
    const float *emit = prt_transfer_emission(t);
    uint64_t rng = 0x853c49e6748fea9bull;
    for (int i = 0; i < 4; ++i) {
        float p[3];
        for (int k = 0; k < 3; ++k) {
            rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
            p[k] = (float)(rng >> 11) / 9007199254740992.0f;
        }
        char spec[128];   /* inside the box, above the blocks */
        snprintf(spec, sizeof spec, "point:%g,%g,%g:0.6", -0.7 + 1.4 * p[0], 1.25 + 0.6 * p[1], -0.6 + 1.2 * p[2]);
        prt_lighting *l = one_light(spec);
        prt_lighting_set_emission(l, 0.0f);
        prt_relit r;
        assert_int_equal(prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .with_indirect = 1}, &r), PRT_OK);
        prt_reference_desc rd = {0};
        rd.samples = 256;
        rd.lighting = l;
        prt_reference_vertices ref;
        assert_int_equal(prt_reference_trace_vertices(ctx, traced, NULL, &rd, &ref), PRT_OK);
        double e[4];
        vs_reference(r.radiance, r.indirect, &ref, nv, emit, e);
        const double total = e[0], rn = e[1], indirect = e[2], rni = e[3];
        /* Errors add in quadrature: what the reference's own noise does not explain. */
        const double total_own = sqrt(fmax(0, total * total - rn * rn)), indirect_own = sqrt(fmax(0, indirect * indirect - rni * rni));
        print_message("Cornell box, %s: total %.4f (reference noise %.4f: %.4f beyond it), indirect %.4f (noise %.4f: %.4f beyond)\n", spec, total,
                      rn, total_own, indirect, rni, indirect_own);
        assert_true(total_own < 0.08);
        assert_true(indirect_own < 0.22);
        prt_relit_free(&r);
        prt_reference_vertices_free(&ref);
        prt_lighting_release(l);
    }
    prt_scene_release(traced);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
}

int main(int argc, char **argv)
{
    /* The Cornell box against the path tracer runs on its own (ctest: lightcloud-cornell): a
     * minute normally, too long to repeat under the sanitizers in every `make test`. */
    if (argc > 1 && !strcmp(argv[1], "cornell")) {
        const struct CMUnitTest cornell[] = {cmocka_unit_test(test_cornell_vs_reference)};
        return cmocka_run_group_tests(cornell, NULL, NULL);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_light_at_cloud_light, test_dir_setup, test_dir_teardown),
        cmocka_unit_test(test_clustering_distance_only),
        cmocka_unit_test(test_no_light_through_walls),
        cmocka_unit_test(test_no_popping),
        cmocka_unit_test_setup_teardown(test_files_and_bad_input, test_dir_setup, test_dir_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
