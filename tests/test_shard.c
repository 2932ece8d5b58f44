/* Bakes over many machines (docs/CLUSTER.md): every method's bake cut into 3 shards per stage that
 * can be spread, merged stage by stage, writes the same file, byte for byte outside META, as one
 * bake; shards that do not belong together, a missing shard and one cut off are refused, naming
 * the file and what differs. */
#include "small_bake.h"

#include <sys/stat.h>

/* Shard I/N of the next stage from `from` (NULL: none) into path. */
static void bake_shard(prt_context *ctx, const prt_scene *scene, const prt_method *m, const prt_options *o, const char *from, int i, int n,
                       const char *path)
{
    prt_transfer *t = (prt_transfer *)1;
    prt_bake_run_desc run = {.checkpoint = from, .shard_index = i, .shard_count = n, .shard = path};
    assert_int_equal(prt_bake(ctx, scene, m, o, &run, &t), PRT_OK);
    assert_null(t);
}

static void shard_path(char *out, size_t size, const char *method, int stage, int i)
{
    snprintf(out, size, "%s/%s_%d_%d.shard", test_dir, method, stage, i);
}

static void test_shards_merge_to_the_same_bytes(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    prt_scene *scene = small_bake_scene(ctx, &m);
    for (int mi = 0; mi < prt_method_count(); ++mi) {
        const prt_method *method = prt_method_at(mi);
        const char *name = prt_method_name(method);
        prt_options *o = small_bake_options(method, "128");
        char merged[2][512], plain[512], sharded[512];
        snprintf(merged[0], sizeof merged[0], "%s/%s_a.merged", test_dir, name);
        snprintf(merged[1], sizeof merged[1], "%s/%s_b.merged", test_dir, name);
        snprintf(plain, sizeof plain, "%s/%s_plain.prt", test_dir, name);
        snprintf(sharded, sizeof sharded, "%s/%s_sharded.prt", test_dir, name);
        const char *from = NULL;
        prt_transfer *t = NULL;
        int rounds = 0, spread = 0;
        for (; !t; ++rounds) {
            assert_true(rounds < 16);
            char paths[3][512];
            for (int i = 0; i < 3; ++i) {
                shard_path(paths[i], sizeof paths[i], name, rounds, i + 1);
                bake_shard(ctx, scene, method, o, from, i + 1, 3, paths[i]);
            }
            /* Given in another order than made: merge sorts nothing out by position. */
            const char *list[3] = {paths[2], paths[0], paths[1]};
            prt_bake_shard info;
            const char *out = merged[rounds % 2];
            assert_int_equal(prt_bake_merge_shards(ctx, list, 3, out, &info), PRT_OK);
            spread += info.stage >= 0;
            if (info.stage >= 0) assert_true(info.records > 0 && info.records <= info.units);
            free(info.note);
            int stopped = -2;
            prt_bake_run_desc run = {.checkpoint = out, .stop_at_missing = 1, .stopped_stage = &stopped};
            assert_int_equal(prt_bake(ctx, scene, method, o, &run, &t), PRT_OK);
            assert_true(t ? stopped == -1 : stopped >= 0);
            from = out;
        }
        assert_int_equal(prt_transfer_save(t, sharded), PRT_OK);
        prt_transfer_release(t);
        assert_int_equal(prt_bake(ctx, scene, method, o, NULL, &t), PRT_OK);
        assert_int_equal(prt_transfer_save(t, plain), PRT_OK);
        prt_transfer_release(t);
        print_message("%s: %d stage(s) spread over 3 shards, merged to the same bytes\n", name, spread);
        assert_same_chunks(plain, sharded);
        prt_options_release(o);
    }
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(ctx);
}

static void expect_refusal(prt_context *ctx, const char *const *paths, int n, prt_status st, const char *says, const char *names)
{
    char out[512];
    snprintf(out, sizeof out, "%s/refused.merged", test_dir);
    assert_int_equal(prt_bake_merge_shards(ctx, paths, n, out, NULL), st);
    if (!strstr(prt_last_error(), says) || (names && !strstr(prt_last_error(), names)))
        fail_msg("refusal '%s' does not say '%s' and name '%s'", prt_last_error(), says, names ? names : "");
    struct stat sb;
    assert_int_not_equal(stat(out, &sb), 0);   /* nothing written */
}

static void test_mismatched_shards_are_refused(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    prt_scene *scene = small_bake_scene(ctx, &m);
    const prt_method *sh = prt_method_find("sh");
    prt_options *o = small_bake_options(sh, "64"), *other = small_bake_options(sh, "128");
    char p[3][512], q[512], two[512], cut[512], merged[512], later[512];
    for (int i = 0; i < 3; ++i) {
        shard_path(p[i], sizeof p[i], "mm", 0, i + 1);
        bake_shard(ctx, scene, sh, o, NULL, i + 1, 3, p[i]);
    }
    shard_path(q, sizeof q, "other", 0, 2);
    bake_shard(ctx, scene, sh, other, NULL, 2, 3, q);
    shard_path(two, sizeof two, "halves", 0, 2);
    bake_shard(ctx, scene, sh, o, NULL, 2, 2, two);
    /* Another bake's shard, one of another N, a shard twice, one missing. */
    expect_refusal(ctx, (const char *[]){p[0], q, p[2]}, 3, PRT_ERR_INVALID_ARG, "another bake", q);
    expect_refusal(ctx, (const char *[]){p[0], two, p[2]}, 3, PRT_ERR_INVALID_ARG, "one of 3 shards", two);
    expect_refusal(ctx, (const char *[]){p[0], p[1], p[1]}, 3, PRT_ERR_INVALID_ARG, "both shard 2/3", p[1]);
    expect_refusal(ctx, (const char *[]){p[0], p[2]}, 2, PRT_ERR_INVALID_ARG, "missing 2/3", NULL);
    /* A shard of a later stage beside those of the first. */
    snprintf(merged, sizeof merged, "%s/mm.merged", test_dir);
    assert_int_equal(prt_bake_merge_shards(ctx, (const char *[]){p[0], p[1], p[2]}, 3, merged, NULL), PRT_OK);
    shard_path(later, sizeof later, "mm", 1, 2);
    bake_shard(ctx, scene, sh, o, merged, 2, 3, later);
    expect_refusal(ctx, (const char *[]){p[0], later, p[2]}, 3, PRT_ERR_INVALID_ARG, "holds stage 1", later);
    /* Cut off before its description (killed while writing): not a whole shard. */
    snprintf(cut, sizeof cut, "%s/cut.shard", test_dir);
    struct stat sb;
    assert_int_equal(stat(p[1], &sb), 0);
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "head -c %lld '%s' > '%s'", (long long)sb.st_size - 40, p[1], cut);
    assert_int_equal(system(cmd), 0);
    expect_refusal(ctx, (const char *[]){p[0], cut, p[2]}, 3, PRT_ERR_FORMAT, "not a whole shard", cut);
    /* --stage that is not the next one to spread. */
    prt_transfer *t = NULL;
    char path[512];
    shard_path(path, sizeof path, "mm", 9, 1);
    prt_bake_run_desc run = {.checkpoint = merged, .shard_index = 1, .shard_count = 3, .shard = path, .stage_given = 1, .stage = 0};
    assert_int_equal(prt_bake(ctx, scene, sh, o, &run, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "not the next"));
    /* The merged file of other options is refused as a --from. */
    run.stage_given = 0;
    assert_int_equal(prt_bake(ctx, scene, sh, other, &run, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "another bake"));
    prt_options_release(o);
    prt_options_release(other);
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shards_merge_to_the_same_bytes),
        cmocka_unit_test(test_mismatched_shards_are_refused),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
