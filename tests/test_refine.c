/* Adaptive refinement: vertices go where transfer changes faster than the vertices sample it
 * (the contact zone around a box on a floor, the outline of a point light's shadow) and nowhere
 * else (a lone convex object); the refined mesh covers the same surface, has no cracks at creases
 * and is the same for any thread count; the budget holds; bad arguments are refused. */
#include "common.h"

#include "geom/mesh.h"

static prt__mesh mesh_of(const test_mesh *t)
{
    prt__mesh m = {0};
    assert_int_equal(prt__mesh_append(&m, t->pos, t->nrm, NULL, (float[3]){0.5f, 0.5f, 0.5f}, t->nv, t->idx, t->nt), PRT_OK);
    return m;
}

/* A 10 x 10 floor of n x n cells, facing up, at y = 0. */
static void floor_quad(test_mesh *t, int n) { tm_quad(t, (float[3]){-5, 0, 5}, (float[3]){10, 0, 0}, (float[3]){0, 0, -10}, n); }

static bool on_floor(const prt__mesh *m, size_t v) { return m->positions[v * 3 + 1] == 0.0f; }

static void test_contact_zone(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh t = {0};
    floor_quad(&t, 1);   /* two triangles: no vertex anywhere near the box */
    tm_closed_box(&t, (float[3]){-0.5f, 0.02f, -0.5f}, (float[3]){0.5f, 1.02f, 0.5f}, 2);
    prt__mesh m = mesh_of(&t);
    const size_t before = m.vertex_count;
    prt_refine_stats s;
    assert_int_equal(prt__mesh_refine(ctx, &m, NULL, 0, &(prt_refine_desc){.max_new_vertices = 3000}, &s), PRT_OK);
    assert_int_equal(m.vertex_count, before + s.new_vertices);
    assert_true(s.new_vertices > 0 && s.new_vertices <= 3000);
    /* The occlusion the box casts reaches about a tenth of the scene (1.4) from its sides: new
     * floor vertices belong within 2 of its centre, a sixth of the floor. */
    size_t near = 0, far = 0;
    for (size_t v = before; v < m.vertex_count; ++v) {
        if (!on_floor(&m, v)) continue;
        const float r = fmaxf(fabsf(m.positions[v * 3]), fabsf(m.positions[v * 3 + 2]));
        if (r < 2.0f) near++;
        else far++;
    }
    print_message("box on a floor: %zu vertices added in %d levels; on the floor %zu within 2 of the box, %zu further\n", s.new_vertices, s.levels,
                  near, far);
    assert_true(near > 100);
    /* Density: the zone near the box is 16 of the floor's 100 square units. */
    assert_true((double)near / 16 > 10 * (double)far / 84);
    /* The box's top, far from everything, is left alone. */
    for (size_t v = before; v < m.vertex_count; ++v) assert_false(m.positions[v * 3 + 1] == 1.02f && fabsf(m.positions[v * 3]) < 0.4f && fabsf(m.positions[v * 3 + 2]) < 0.4f);
    prt__mesh_free(&m);

    /* The estimate a bake prints sees the same. */
    prt_scene *scene = tm_scene(ctx, &t, 0.5f);
    assert_int_equal(prt_scene_refine_estimate(ctx, scene, NULL, &s), PRT_OK);
    assert_true(s.marked_triangles > 0);
    prt_scene_release(scene);
    tm_free(&t);
    prt_context_release(ctx);
}

/* A lone convex object occludes nothing of itself: no probe differs, nothing is split. */
static void test_convex_untouched(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh t = {0};
    tm_sphere(&t, (float[3]){0, 0, 0}, 1, 12, 24);
    prt__mesh m = mesh_of(&t);
    prt_refine_stats s;
    assert_int_equal(prt__mesh_refine(ctx, &m, NULL, 0, NULL, &s), PRT_OK);
    assert_int_equal(s.new_vertices, 0);
    assert_int_equal(s.marked_edges, 0);
    assert_int_equal(m.vertex_count, t.nv);
    prt_scene *scene = tm_scene(ctx, &t, 0.5f);
    assert_int_equal(prt_scene_refine_estimate(ctx, scene, NULL, &s), PRT_OK);
    assert_int_equal(s.marked_triangles, 0);
    prt_scene_release(scene);
    prt__mesh_free(&m);
    tm_free(&t);
    prt_context_release(ctx);
}

/* A plate at height 2 (beyond the occlusion probe's reach) under a point light at height 4 casts
 * a square shadow of side 2 on the floor: new floor vertices follow its outline. */
static void test_point_light_shadow(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh t = {0};
    floor_quad(&t, 4);
    tm_quad(&t, (float[3]){-0.5f, 2, 0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, -1}, 1);
    prt__mesh m = mesh_of(&t);
    const size_t before = m.vertex_count;
    prt_light light = {.type = PRT_LIGHT_POINT, .position = {0, 4, 0}, .intensity = {10, 10, 10}};
    prt_refine_stats s;
    /* Without the light nothing on the floor differs. */
    assert_int_equal(prt__mesh_refine(ctx, &m, NULL, 0, NULL, &s), PRT_OK);
    for (size_t v = before; v < m.vertex_count; ++v) assert_false(on_floor(&m, v));
    prt__mesh_free(&m);

    m = mesh_of(&t);
    assert_int_equal(prt__mesh_refine(ctx, &m, &light, 1, &(prt_refine_desc){.max_new_vertices = 4000}, &s), PRT_OK);
    size_t floor_new = 0, at_outline = 0;
    for (size_t v = before; v < m.vertex_count; ++v) {
        if (!on_floor(&m, v)) continue;
        floor_new++;
        const float r = fmaxf(fabsf(m.positions[v * 3]), fabsf(m.positions[v * 3 + 2]));
        at_outline += fabsf(r - 1.0f) < 0.5f;
    }
    print_message("point light shadow: %zu new floor vertices, %zu within 0.5 of the outline\n", floor_new, at_outline);
    assert_true(floor_new > 100);
    assert_true(at_outline >= 0.9 * floor_new);
    prt__mesh_free(&m);
    /* Lights the scene does not name (the sky's sun a file is relit under) are probed when given
     * as extra lights: the square's shadow on the floor then needs refining. */
    prt_scene *scene = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, t.pos, t.nrm, NULL, t.nv, t.idx, t.nt, NULL, &scene), PRT_OK);
    prt_refine_stats plain, lit;
    assert_int_equal(prt_scene_refine_estimate(ctx, scene, NULL, &plain), PRT_OK);
    prt_light sun = {.type = PRT_LIGHT_DIRECTIONAL, .direction = {0.1f, 1, 0.05f}, .irradiance = {1, 1, 1}};
    assert_int_equal(prt_scene_refine_estimate(ctx, scene, &(prt_refine_desc){.extra_lights = &sun, .extra_light_count = 1}, &lit), PRT_OK);
    print_message("extra light: %zu triangles marked, %zu without it\n", lit.marked_triangles, plain.marked_triangles);
    assert_true(lit.marked_triangles > plain.marked_triangles);
    prt_light bad = {.type = PRT_LIGHT_DIRECTIONAL};   /* no direction */
    assert_int_equal(prt_scene_refine_estimate(ctx, scene, &(prt_refine_desc){.extra_lights = &bad, .extra_light_count = 1}, &lit), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.extra_lights = &sun, .extra_light_count = -1}, &lit), PRT_ERR_INVALID_ARG);
    prt_scene_release(scene);
    tm_free(&t);
    prt_context_release(ctx);
}

static double signed_area(const prt__mesh *m, int axis)
{
    double sum = 0;
    for (size_t f = 0; f < m->triangle_count; ++f) {
        const float *a = m->positions + m->indices[f * 3] * 3, *b = m->positions + m->indices[f * 3 + 1] * 3, *c = m->positions + m->indices[f * 3 + 2] * 3;
        const int i = (axis + 1) % 3, j = (axis + 2) % 3;
        sum += 0.5 * ((double)(b[i] - a[i]) * (c[j] - a[j]) - (double)(b[j] - a[j]) * (c[i] - a[i]));
    }
    return sum;
}

static double total_area(const prt__mesh *m)
{
    double sum = 0;
    for (size_t f = 0; f < m->triangle_count; ++f) {
        float e1[3], e2[3], cr[3];
        const uint32_t *ix = m->indices + f * 3;
        for (int c = 0; c < 3; ++c) { e1[c] = m->positions[ix[1] * 3 + c] - m->positions[ix[0] * 3 + c]; e2[c] = m->positions[ix[2] * 3 + c] - m->positions[ix[0] * 3 + c]; }
        cr[0] = e1[1] * e2[2] - e1[2] * e2[1]; cr[1] = e1[2] * e2[0] - e1[0] * e2[2]; cr[2] = e1[0] * e2[1] - e1[1] * e2[0];
        sum += 0.5 * sqrt((double)cr[0] * cr[0] + (double)cr[1] * cr[1] + (double)cr[2] * cr[2]);
    }
    return sum;
}

typedef struct pos_edge { float a[3], b[3]; } pos_edge;

static int cmp_pos_edge(const void *x, const void *y) { return memcmp(x, y, sizeof(pos_edge)); }

/* Every edge, by the positions of its ends, and how many triangles share it: a crack or a
 * T-junction leaves an edge used once away from the mesh's border. */
static void assert_no_cracks(const prt__mesh *m)
{
    pos_edge *e = malloc(m->triangle_count * 3 * sizeof *e);
    for (size_t f = 0; f < m->triangle_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const float *p = m->positions + m->indices[f * 3 + k] * 3, *q = m->positions + m->indices[f * 3 + (k + 1) % 3] * 3;
            const bool swap = memcmp(p, q, 3 * sizeof(float)) > 0;
            memcpy(e[f * 3 + k].a, swap ? q : p, 3 * sizeof(float));
            memcpy(e[f * 3 + k].b, swap ? p : q, 3 * sizeof(float));
        }
    const size_t n = m->triangle_count * 3;
    qsort(e, n, sizeof *e, cmp_pos_edge);
    size_t single = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && !cmp_pos_edge(&e[i], &e[j])) j++;
        if (j - i == 1) {
            /* Only the floor's outer border may be used once. */
            const bool border = (fabsf(e[i].a[0]) == 5 && e[i].a[0] == e[i].b[0]) || (fabsf(e[i].a[2]) == 5 && e[i].a[2] == e[i].b[2]);
            if (!border) single++;
        }
        assert_true(j - i <= 2);
        i = j;
    }
    assert_int_equal(single, 0);
    free(e);
}

/* Refinement splits triangles without moving the surface: the same area, the same oriented area,
 * no crack along the box's creases (its faces have vertices of their own), the same mesh for any
 * thread count. */
static void test_conforming_and_deterministic(void **state)
{
    (void)state;
    test_mesh t = {0};
    floor_quad(&t, 2);
    /* Corners exact in binary, so that every face computes them to the same bits. */
    tm_closed_box(&t, (float[3]){-1.25f, 0.0078125f, -0.75f}, (float[3]){0.75f, 1.25f, 0.875f}, 1);
    prt__mesh one = mesh_of(&t), two = mesh_of(&t);
    assert_no_cracks(&one);
    const double area = total_area(&one), oriented[3] = {signed_area(&one, 0), signed_area(&one, 1), signed_area(&one, 2)};
    prt_context *c1 = test_context(1), *c2 = test_context(2);
    prt_refine_stats s1, s2;
    const prt_refine_desc d = {.max_new_vertices = 2500};
    assert_int_equal(prt__mesh_refine(c1, &one, NULL, 0, &d, &s1), PRT_OK);
    assert_int_equal(prt__mesh_refine(c2, &two, NULL, 0, &d, &s2), PRT_OK);
    print_message("box by a floor: %zu vertices added in %d levels, %zu triangles\n", s1.new_vertices, s1.levels, s1.triangles);
    assert_true(s1.new_vertices > 500);
    assert_int_equal(one.vertex_count, two.vertex_count);
    assert_int_equal(one.triangle_count, two.triangle_count);
    assert_memory_equal(one.positions, two.positions, one.vertex_count * 3 * sizeof(float));
    assert_memory_equal(one.normals, two.normals, one.vertex_count * 3 * sizeof(float));
    assert_memory_equal(one.indices, two.indices, one.triangle_count * 3 * sizeof(uint32_t));
    assert_float_equal(total_area(&one), area, 1e-4 * area);
    for (int a = 0; a < 3; ++a) assert_float_equal(signed_area(&one, a), oriented[a], 1e-4 * area);
    assert_no_cracks(&one);
    /* Unit normals, and attributes carried to every new vertex. */
    for (size_t v = 0; v < one.vertex_count; ++v) {
        const float *n = one.normals + v * 3;
        assert_float_equal(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-4f);
        assert_float_equal(one.albedo[v * 3], 0.5f, 1e-6f);
    }
    /* No triangle got needle-thin: longest-edge bisection bounds the smallest angle. */
    double worst = 1;
    for (size_t f = 0; f < one.triangle_count; ++f) {
        const uint32_t *ix = one.indices + f * 3;
        for (int k = 0; k < 3; ++k) {
            const float *p = one.positions + ix[k] * 3, *q = one.positions + ix[(k + 1) % 3] * 3, *r = one.positions + ix[(k + 2) % 3] * 3;
            float u[3], w[3];
            for (int c = 0; c < 3; ++c) { u[c] = q[c] - p[c]; w[c] = r[c] - p[c]; }
            const double cosang = (u[0] * w[0] + u[1] * w[1] + u[2] * w[2]) / sqrt((u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) * (double)(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]));
            worst = fmin(worst, sin(acos(fmin(1.0, cosang))));
        }
    }
    print_message("smallest angle after refinement: %.1f degrees\n", asin(worst) * 180 / M_PI);
    assert_true(worst > sin(10 * M_PI / 180));
    prt__mesh_free(&one);
    prt__mesh_free(&two);

    /* The budget holds. */
    prt__mesh small = mesh_of(&t);
    assert_int_equal(prt__mesh_refine(c2, &small, NULL, 0, &(prt_refine_desc){.max_new_vertices = 40}, &s1), PRT_OK);
    assert_true(s1.new_vertices <= 40 && s1.new_vertices > 0);
    assert_true(s1.budget_spent);
    prt__mesh_free(&small);
    tm_free(&t);
    prt_context_release(c1);
    prt_context_release(c2);
}

static void test_bad_arguments(void **state)
{
    (void)state;
    prt_context *ctx = test_context(1);
    test_mesh t = {0};
    floor_quad(&t, 1);
    prt_scene *scene = tm_scene(ctx, &t, 0.5f);
    prt_refine_stats s;
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.threshold = 1.5f}, &s), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "threshold"));
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.threshold = NAN}, &s), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.min_edge = INFINITY}, &s), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.max_levels = 99}, &s), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.max_new_vertices = (size_t)1 << 40}, &s), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_refine(ctx, NULL, NULL, &s), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_refine_estimate(ctx, NULL, NULL, &s), PRT_ERR_INVALID_ARG);
    assert_int_equal(prt_scene_vertex_count(scene), 4);   /* refused calls change nothing */
    prt_scene_release(scene);
    tm_free(&t);
    prt_context_release(ctx);
}

static int progress_stop(void *user, const char *stage, uint64_t done, uint64_t total)
{
    (void)done; (void)total;
    int *until = user;
    return strstr(stage, "level 2") != NULL || --*until < 0;   /* in level 2, or after `until` reports */
}

static void test_cancel(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh t = {0};
    floor_quad(&t, 1);
    tm_closed_box(&t, (float[3]){-0.5f, 0.015625f, -0.5f}, (float[3]){0.5f, 1.015625f, 0.5f}, 2);   /* exact in binary: no crack to begin with */
    prt_scene *scene = tm_scene(ctx, &t, 0.5f);
    prt_refine_stats s;
    int until = 0;
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.progress = progress_stop, .progress_user = &until}, &s), PRT_ERR_CANCELLED);
    assert_int_equal(prt_scene_vertex_count(scene), t.nv);   /* stopped at once: nothing split */
    /* Stopped in its second level: the first level's split stays, and the mesh is whole. */
    until = 1 << 30;
    assert_int_equal(prt_scene_refine(ctx, scene, &(prt_refine_desc){.progress = progress_stop, .progress_user = &until}, &s), PRT_ERR_CANCELLED);
    assert_true(prt_scene_vertex_count(scene) > t.nv);
    assert_no_cracks(&scene->mesh);
    prt_scene_release(scene);
    tm_free(&t);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_contact_zone),
        cmocka_unit_test(test_convex_untouched),
        cmocka_unit_test(test_point_light_shadow),
        cmocka_unit_test(test_conforming_and_deterministic),
        cmocka_unit_test(test_bad_arguments),
        cmocka_unit_test(test_cancel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
