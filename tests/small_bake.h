/* A small scene every method bakes in about a second, with options that give each method several
 * stages and units: the bake the resume, shard and cluster-style tests cut up and compare. */
#ifndef PRT_TESTS_SMALL_BAKE_H
#define PRT_TESTS_SMALL_BAKE_H

#include "common.h"

static inline prt_scene *small_bake_scene(prt_context *ctx, test_mesh *m)
{
    tm_quad(m, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 24);
    tm_sphere(m, (float[3]){0, 0.45f, 0}, 0.4f, 16, 24);
    return tm_scene(ctx, m, 0.6f);
}

static inline prt_options *small_bake_options(const prt_method *method, const char *samples)
{
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(method, &o), PRT_OK);
    if (!strcmp(prt_method_name(method), "sh")) {
        assert_int_equal(prt_options_set(o, "samples", samples), PRT_OK);
        assert_int_equal(prt_options_set(o, "bounces", "2"), PRT_OK);      /* three spread stages */
        assert_int_equal(prt_options_set(o, "compress", "cpca"), PRT_OK);  /* a `whole` stage after them */
        assert_int_equal(prt_options_set(o, "clusters", "4"), PRT_OK);
    } else {
        if (prt_method_option(method, "bounces")) assert_int_equal(prt_options_set(o, "bounces", "1"), PRT_OK);
        if (prt_method_option(method, "gather-res")) assert_int_equal(prt_options_set(o, "gather-res", "8"), PRT_OK);
        if (prt_method_option(method, "brdf-res")) assert_int_equal(prt_options_set(o, "brdf-res", "8"), PRT_OK);
        if (prt_method_option(method, "cloud-grid")) {   /* light clouds: 18 lights, each a unit of its own */
            assert_int_equal(prt_options_set(o, "cloud-grid", "3,2,3"), PRT_OK);
            assert_int_equal(prt_options_set(o, "samples", samples), PRT_OK);
        }
    }
    return o;
}

#endif
