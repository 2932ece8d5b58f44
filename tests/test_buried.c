/* Ray origins inside geometry: a floor running under a closed box (a scan folded through itself,
 * a prop sunk into the ground). Vertices whose rays start inside the box are found, moved to a
 * free point of their fan where one exists and otherwise given their neighbours' transfer; none
 * stays black, and none is darker than the free vertices around the box. */
#include "common.h"

#include "geom/raycast.h"

static void test_floor_under_box(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh t = {0};
    tm_quad(&t, (float[3]){-1, 0, 1}, (float[3]){2, 0, 0}, (float[3]){0, 0, -2}, 40);   /* floor, 0.05 cells, up */
    const size_t floor_vertices = t.nv;
    tm_closed_box(&t, (float[3]){-0.31f, -0.1f, -0.31f}, (float[3]){0.31f, 0.4f, 0.31f}, 4);   /* sunk 0.1 into the floor */

    /* Which vertices the check finds, on the mesh as the bake sees it. */
    prt__mesh m = {0};
    assert_int_equal(prt__mesh_append(&m, t.pos, t.nrm, NULL, (float[3]){0.5f, 0.5f, 0.5f}, t.nv, t.idx, t.nt), PRT_OK);
    prt__raycaster rc;
    float *origins = NULL;
    uint8_t *status = malloc(m.vertex_count);
    const float offset = prt__ray_offset(&m);
    assert_int_equal(prt__raycaster_create(ctx, &m, &rc), PRT_OK);
    assert_int_equal(prt__vertex_origins(&m, offset, &origins), PRT_OK);
    assert_int_equal(prt__unbury_origins(ctx, &rc, &m, offset, origins, status, PRT_LOG_DEBUG), PRT_OK);
    size_t moved = 0, filled = 0;
    for (size_t v = 0; v < floor_vertices; ++v) {
        const float x = fabsf(t.pos[v * 3]), z = fabsf(t.pos[v * 3 + 2]), r = fmaxf(x, z);
        if (r < 0.25f) assert_int_equal(status[v], 2);      /* deep under the box: no free point */
        if (r > 0.36f) assert_int_equal(status[v], 0);      /* in the open */
        moved += status[v] == 1;
        filled += status[v] == 2;
    }
    for (size_t v = floor_vertices; v < t.nv; ++v) assert_int_equal(status[v], 0);   /* the box's own vertices are fine */
    print_message("floor under a box: %zu vertices moved to a free point, %zu filled from neighbours\n", moved, filled);
    assert_true(moved > 0 && filled > 0);

    /* The bake: nothing black, nothing darker than the free floor around the box. */
    prt_scene *s = tm_scene(ctx, &t, 0.5f);
    prt_bake_desc d = {0};
    d.order = 1;
    d.samples = 1024;
    d.kinds = PRT_TRANSFER_SHADOWED;
    prt_transfer *x = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &x), PRT_OK);
    assert_int_equal(prt_transfer_vertex_count(x), t.nv);
    const float *T = prt_transfer_coeffs(x, PRT_TRANSFER_SHADOWED);
    float ring_min = INFINITY, worst = INFINITY;
    for (size_t v = 0; v < floor_vertices; ++v) {
        const float r = fmaxf(fabsf(t.pos[v * 3]), fabsf(t.pos[v * 3 + 2]));
        if (status[v] == 0 && r > 0.31f && r < 0.41f) ring_min = fminf(ring_min, T[v]);
        if (status[v]) worst = fminf(worst, T[v]);
    }
    print_message("shadowed T_00: free floor beside the box >= %.4f, moved or filled >= %.4f\n", ring_min, worst);
    assert_true(ring_min > 0.05f);
    assert_true(worst >= ring_min - 0.02f);   /* 1024 samples: noise well below 0.02 */
    prt_transfer_release(x);
    /* Per texel (over a generated atlas): samples inside the box are left to the gutter fill, so
     * no texel of the map is black. */
    d.texels = 64;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &x), PRT_OK);
    const float *tx = prt_transfer_texel_coeffs(x, PRT_TRANSFER_SHADOWED, NULL);
    size_t black = 0;
    for (size_t i = 0; i < 64 * 64; ++i) black += !(tx[i] > 1e-4f);
    print_message("per texel: %zu of 4096 texels black\n", black);
    assert_int_equal(black, 0);
    prt_transfer_release(x);
    prt_scene_release(s);
    prt__raycaster_release(&rc);
    free(origins);
    free(status);
    prt__mesh_free(&m);
    tm_free(&t);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_floor_under_box),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
