/* Cancellation through the context's hook (prt_context_desc.cancel) and progress callbacks: each
 * long operation, stopped on the k-th look at the hook, returns PRT_ERR_CANCELLED, hands nothing
 * back, and stops asking soon after (a loop that keeps going after the hook said stop keeps
 * asking it). Deterministic: the hook counts its calls, no clock is read. */
#include "common.h"

typedef struct hook {
    long calls;     /* every call */
    long stop_at;   /* from this call on it says stop; 0 = never */
    long stopped;   /* calls that said stop */
} hook;

static int hook_fn(void *user)
{
    hook *h = user;
    const long n = __atomic_add_fetch(&h->calls, 1, __ATOMIC_RELAXED);
    if (!h->stop_at || n < h->stop_at) return 0;
    __atomic_add_fetch(&h->stopped, 1, __ATOMIC_RELAXED);
    return 1;
}

#define THREADS 2
/* Looks after the first "stop": each thread may be inside a look when another sets the flag,
 * and every stage between the loop and the return looks once more. */
#define MAX_LOOKS_AFTER 48

static prt_context *hooked_context(hook *h)
{
    prt_context *ctx = NULL;
    prt_context_desc d = {0};
    d.threads = THREADS;
    d.cancel = hook_fn;
    d.cancel_user = h;
    assert_int_equal(prt_context_create(&d, &ctx), PRT_OK);
    return ctx;
}

/* A floor with a sphere resting on it and a box sunk into it (buried origins, contact zones). */
static void make_scene_mesh(test_mesh *m, int floor_cells)
{
    tm_quad(m, (float[3]){-2, 0, 2}, (float[3]){4, 0, 0}, (float[3]){0, 0, -4}, floor_cells);
    tm_sphere(m, (float[3]){0.6f, 0.5f, 0}, 0.5f, 16, 32);
    tm_closed_box(m, (float[3]){-1.2f, -0.3f, -0.4f}, (float[3]){-0.4f, 0.4f, 0.4f}, 6);
}

static prt_scene *make_scene(prt_context *ctx, const test_mesh *m, float max_edge, prt_status *st)
{
    prt_scene_desc sd = {0};
    sd.max_edge = max_edge;
    sd.default_albedo[0] = sd.default_albedo[1] = sd.default_albedo[2] = 0.6f;
    prt_scene *s = (prt_scene *)(uintptr_t)1;   /* must come back NULL when it fails */
    *st = prt_scene_create_copy(ctx, m->pos, m->nrm, NULL, m->nv, m->idx, m->nt, &sd, &s);
    if (*st) assert_null(s);
    return *st ? NULL : s;
}

/* The calls a whole run makes, then runs stopped at a few points of it. */
static long stop_points(long total, long at[3])
{
    at[0] = 1;
    at[1] = total / 2 > 1 ? total / 2 : 1;
    at[2] = total > 2 ? total - 1 : 1;
    return 3;
}

static void assert_prompt(const hook *h)
{
    if (h->stopped > MAX_LOOKS_AFTER) fail_msg("the hook was asked %ld times after it said stop", h->stopped);
}

static void test_subdivision(void **state)
{
    (void)state;
    hook h = {0};
    prt_context *ctx = hooked_context(&h);
    test_mesh m = {0};
    make_scene_mesh(&m, 4);
    prt_status st;
    prt_scene *s = make_scene(ctx, &m, 0.02f, &st);
    assert_int_equal(st, PRT_OK);
    const long total = h.calls;
    assert_true(total >= 2);
    prt_scene_release(s);
    long at[3];
    for (long i = 0, n = stop_points(total, at); i < n; ++i) {
        h = (hook){.stop_at = at[i]};
        assert_null(make_scene(ctx, &m, 0.02f, &st));
        assert_int_equal(st, PRT_ERR_CANCELLED);
        assert_prompt(&h);
    }
    tm_free(&m);
    prt_context_release(ctx);
}

static void test_refine_estimate_and_refine(void **state)
{
    (void)state;
    hook h = {0};
    prt_context *ctx = hooked_context(&h);
    test_mesh m = {0};
    make_scene_mesh(&m, 24);
    prt_status st;
    prt_scene *s = make_scene(ctx, &m, 0, &st);
    assert_int_equal(st, PRT_OK);
    const size_t nv = prt_scene_vertex_count(s);
    prt_refine_stats rs;
    h = (hook){0};
    assert_int_equal(prt_scene_refine_estimate(ctx, s, NULL, &rs), PRT_OK);
    /* Its samples look at the hook each: stopped in the middle, the rest are skipped. */
    long total = h.calls, at[3];
    assert_true(total > 100);
    for (long i = 0, n = stop_points(total, at); i < n; ++i) {
        h = (hook){.stop_at = at[i]};
        assert_int_equal(prt_scene_refine_estimate(ctx, s, NULL, &rs), PRT_ERR_CANCELLED);
        assert_prompt(&h);
    }
    /* Refinement stopped before its first level splits nothing. */
    h = (hook){.stop_at = 1};
    assert_int_equal(prt_scene_refine(ctx, s, &(prt_refine_desc){.max_new_vertices = 2000}, &rs), PRT_ERR_CANCELLED);
    assert_int_equal(prt_scene_vertex_count(s), nv);
    assert_prompt(&h);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static prt_options *small_options(const prt_method *method)
{
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(method, &o), PRT_OK);
    /* Whatever of these the method has: a small, fast bake. */
    const char *settings[][2] = {{"order", "2"}, {"samples", "16"}, {"bounces", "1"}, {"texels", "32"}, {"resolution", "32"},
                                 {"offsets", "16"}, {"cloud-grid", "2,2,2"}, {"eigenvectors", "8"}};
    for (size_t i = 0; i < sizeof settings / sizeof *settings; ++i) (void)prt_options_set(o, settings[i][0], settings[i][1]);
    return o;
}

/* Every method's bake, stopped at its first look, half-way and at its last: nothing comes back. */
static void test_bakes(void **state)
{
    (void)state;
    hook h = {0};
    prt_context *ctx = hooked_context(&h);
    test_mesh m = {0};
    make_scene_mesh(&m, 12);
    prt_status st;
    prt_scene *s = make_scene(ctx, &m, 0, &st);
    assert_int_equal(st, PRT_OK);
    int baked = 0;
    for (int k = 0; k < prt_method_count(); ++k) {
        const prt_method *method = prt_method_at(k);
        prt_options *o = small_options(method);
        prt_transfer *t = NULL;
        h = (hook){0};
        st = prt_bake(ctx, s, method, o, NULL, &t);
        if (st) {   /* a method this scene does not suit: say so, test the others */
            print_message("%s: not baked here (%s)\n", prt_method_name(method), prt_last_error());
            prt_options_release(o);
            continue;
        }
        prt_transfer_release(t);
        baked++;
        long total = h.calls, at[3];
        for (long i = 0, n = stop_points(total, at); i < n; ++i) {
            h = (hook){.stop_at = at[i]};
            t = (prt_transfer *)(uintptr_t)1;
            st = prt_bake(ctx, s, method, o, NULL, &t);
            if (st != PRT_ERR_CANCELLED) fail_msg("%s stopped at look %ld of %ld: %s", prt_method_name(method), at[i], total, prt_status_string(st));
            assert_null(t);
            if (h.stopped > MAX_LOOKS_AFTER)
                fail_msg("%s stopped at look %ld of %ld: asked %ld times more", prt_method_name(method), at[i], total, h.stopped);
        }
        prt_options_release(o);
    }
    assert_true(baked >= 1);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

static int stop_on_second(void *user, const char *stage, uint64_t done, uint64_t total)
{
    (void)stage; (void)done; (void)total;
    return ++*(int *)user >= 2;
}

/* Clustered PCA of a set: stopped by the hook in any of its passes, or by the progress callback. */
static void test_compress(void **state)
{
    (void)state;
    hook h = {0};
    prt_context *ctx = hooked_context(&h);
    test_mesh m = {0};
    make_scene_mesh(&m, 12);
    prt_status st;
    prt_scene *s = make_scene(ctx, &m, 0, &st);
    assert_int_equal(st, PRT_OK);
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find("sh"), &o), PRT_OK);
    assert_int_equal(prt_options_set(o, "order", "4"), PRT_OK);
    assert_int_equal(prt_options_set(o, "samples", "16"), PRT_OK);
    (void)prt_options_set(o, "quantize", "32");   /* floats, where 16-bit sets are the default */
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, s, prt_method_find("sh"), o, NULL, &t), PRT_OK);
    prt_compress_desc cd = {.method = PRT_COMPRESS_CPCA, .clusters = 8, .vectors = 4, .iterations = 6};
    prt_transfer *c = NULL;
    h = (hook){0};
    st = prt_transfer_compress(ctx, t, &cd, &c);
    if (st) fail_msg("compress: %s", prt_last_error());
    prt_transfer_release(c);
    long total = h.calls, at[3];
    assert_true(total > 100);   /* it looks inside its passes, not only between iterations */
    for (long i = 0, n = stop_points(total, at); i < n; ++i) {
        h = (hook){.stop_at = at[i]};
        c = (prt_transfer *)(uintptr_t)1;
        assert_int_equal(prt_transfer_compress(ctx, t, &cd, &c), PRT_ERR_CANCELLED);
        assert_null(c);
        assert_prompt(&h);
    }
    h = (hook){0};
    int reports = 0;
    cd.progress = stop_on_second;
    cd.progress_user = &reports;
    c = (prt_transfer *)(uintptr_t)1;
    assert_int_equal(prt_transfer_compress(ctx, t, &cd, &c), PRT_ERR_CANCELLED);
    assert_null(c);
    prt_transfer_release(t);
    prt_options_release(o);
    prt_scene_release(s);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_subdivision),
        cmocka_unit_test(test_refine_estimate_and_refine),
        cmocka_unit_test(test_bakes),
        cmocka_unit_test(test_compress),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
