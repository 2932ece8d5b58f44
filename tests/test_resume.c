/* Resumable bakes: bakes killed with SIGKILL at random moments (any stage, any unit, inside a
 * checkpoint write) and resumed from their checkpoints write the same file, byte for byte outside
 * META, as an uninterrupted bake, for every method; a checkpoint of another bake is refused; torn
 * and damaged records are cut off and their units baked again. */
#include "small_bake.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

/* Progress events go down a pipe to the parent, which kills the child at the k-th. */
static int progress_to_pipe(void *user, const char *stage, uint64_t done, uint64_t total)
{
    (void)stage; (void)done; (void)total;
    char c = 1;
    return write(*(int *)user, &c, 1) == 1 ? 0 : 1;
}

/* Runs a resumed bake in a child process; returns after it finished (and saved its result to
 * save, when given) or after SIGKILL at the kill_at-th progress event (0: never). The child makes
 * its own context, and the parent runs nothing threaded before its last fork (OpenMP's thread
 * pool does not survive fork). Returns the number of progress events seen. */
static int child_bake(int method_index, const char *checkpoint, int kill_at, const char *save, bool *finished)
{
    int fds[2];
    assert_int_equal(pipe(fds), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(fds[0]);
        prt_context *ctx = NULL;
        if (prt_context_create(&(prt_context_desc){.threads = 2}, &ctx)) _exit(2);
        test_mesh m = {0};
        prt_scene *scene = small_bake_scene(ctx, &m);
        const prt_method *method = prt_method_at(method_index);
        prt_options *o = small_bake_options(method, "256");
        prt_bake_run_desc run = {.progress = progress_to_pipe, .progress_user = &fds[1], .checkpoint = checkpoint, .resume = 1};
        prt_transfer *t = NULL;
        int rc = prt_bake(ctx, scene, method, o, &run, &t) != PRT_OK || (save && prt_transfer_save(t, save) != PRT_OK);
        /* Freed before leaving: valgrind checks the child for leaks too. */
        prt_transfer_release(t);
        prt_options_release(o);
        prt_scene_release(scene);
        tm_free(&m);
        prt_context_release(ctx);
        _exit(rc);
    }
    close(fds[1]);
    int events = 0;
    char c;
    while (read(fds[0], &c, 1) == 1) {
        if (++events == kill_at) { kill(pid, SIGKILL); break; }
    }
    close(fds[0]);
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    *finished = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (!*finished) assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    return events;
}

static void test_killed_bakes_resume(void **state)
{
    (void)state;
    uint64_t rng = 0x2545f4914f6cdd1dULL;   /* fixed: the same kill points every run */
    const int methods = prt_method_count();
    char (*resumed_path)[512] = calloc((size_t)methods, sizeof *resumed_path);
    int *kills = calloc((size_t)methods, sizeof *kills);
    assert_non_null(resumed_path);
    assert_non_null(kills);
    for (int mi = 0; mi < methods; ++mi) {
        const prt_method *method = prt_method_at(mi);
        char cp[512];
        snprintf(cp, sizeof cp, "%s/%s.checkpoint", test_dir, prt_method_name(method));
        snprintf(resumed_path[mi], sizeof resumed_path[mi], "%s/%s_resumed.prt", test_dir, prt_method_name(method));
        /* A first run to the end counts the progress events; then kill at random events. */
        bool finished;
        int events = child_bake(mi, cp, 0, NULL, &finished);
        assert_true(finished);
        unlink(cp);
        for (int round = 0; round < 4; ++round) {
            rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
            int at = 1 + (int)(rng % (uint64_t)(events > 1 ? events : 1));
            child_bake(mi, cp, at, NULL, &finished);
            kills[mi] += !finished;
            if (finished) break;   /* resumed past the end: nothing left to kill */
        }
        struct stat sb;
        if (kills[mi]) assert_int_equal(stat(cp, &sb), 0);
        child_bake(mi, cp, 0, resumed_path[mi], &finished);   /* the resume that finishes */
        assert_true(finished);
        unlink(cp);
    }
    /* No more forks: bake each method once without a checkpoint here and compare. */
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    prt_scene *scene = small_bake_scene(ctx, &m);
    for (int mi = 0; mi < methods; ++mi) {
        const prt_method *method = prt_method_at(mi);
        prt_options *o = small_bake_options(method, "256");
        prt_transfer *plain = NULL;
        assert_int_equal(prt_bake(ctx, scene, method, o, NULL, &plain), PRT_OK);
        char pp[512];
        snprintf(pp, sizeof pp, "%s/%s_plain.prt", test_dir, prt_method_name(method));
        assert_int_equal(prt_transfer_save(plain, pp), PRT_OK);
        print_message("%s: killed %d times, resumed to the same bytes\n", prt_method_name(method), kills[mi]);
        assert_same_chunks(pp, resumed_path[mi]);
        prt_transfer_release(plain);
        prt_options_release(o);
    }
    free(resumed_path);
    free(kills);
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(ctx);
}

static size_t file_size(const char *path)
{
    struct stat sb;
    assert_int_equal(stat(path, &sb), 0);
    return (size_t)sb.st_size;
}

/* Damaged checkpoints: a torn tail, garbage after the last record and a flipped byte inside a
 * record all lose at most the records from there on; the result stays the same. */
static void test_damaged_checkpoints(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    prt_scene *scene = small_bake_scene(ctx, &m);
    const prt_method *sh = prt_method_find("sh");
    prt_options *o = small_bake_options(sh, "64");
    char cp[512];
    snprintf(cp, sizeof cp, "%s/damaged.checkpoint", test_dir);
    prt_transfer *plain = NULL;
    assert_int_equal(prt_bake(ctx, scene, sh, o, NULL, &plain), PRT_OK);
    for (int damage = 0; damage < 3; ++damage) {
        prt_transfer *t = NULL;
        prt_bake_run_desc write = {.checkpoint = cp};
        assert_int_equal(prt_bake(ctx, scene, sh, o, &write, &t), PRT_OK);
        prt_transfer_release(t);
        const size_t size = file_size(cp);
        assert_true(size > 4096);
        if (damage == 0) assert_int_equal(truncate(cp, (off_t)(size - 7)), 0);
        FILE *f = fopen(cp, damage == 1 ? "ab" : "r+b");
        assert_non_null(f);
        if (damage == 1) fputs("garbage after the last record", f);
        if (damage == 2) { fseek(f, (long)(size / 2), SEEK_SET); fputc(0x5a ^ fgetc(f), f); }
        fclose(f);
        uint64_t recovered = 0, total = 0;
        prt_bake_run_desc run = {.checkpoint = cp, .resume = 1, .recovered_units = &recovered, .total_units = &total};
        assert_int_equal(prt_bake(ctx, scene, sh, o, &run, &t), PRT_OK);
        if (damage == 1) assert_true(recovered == total);   /* every record before the garbage is whole */
        else assert_true(recovered > 0 && recovered < total);
        assert_same_file(t, plain, "damaged");
        prt_transfer_release(t);
    }
    prt_transfer_release(plain);
    unlink(cp);
    prt_options_release(o);
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(ctx);
}

/* A checkpoint of another bake (other options, another scene) or not a checkpoint at all is
 * refused with a message saying so, and a missing one is an empty one. */
static void test_foreign_checkpoints(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh m = {0};
    prt_scene *scene = small_bake_scene(ctx, &m);
    const prt_method *sh = prt_method_find("sh");
    prt_options *o64 = small_bake_options(sh, "64"), *o128 = small_bake_options(sh, "128");
    char cp[512];
    snprintf(cp, sizeof cp, "%s/foreign.checkpoint", test_dir);
    prt_transfer *t = NULL;
    uint64_t recovered = 1;
    prt_bake_run_desc fresh = {.checkpoint = cp, .resume = 1, .recovered_units = &recovered};
    assert_int_equal(prt_bake(ctx, scene, sh, o64, &fresh, &t), PRT_OK);   /* none there yet */
    assert_int_equal(recovered, 0);
    prt_transfer_release(t);
    prt_bake_run_desc run = {.checkpoint = cp, .resume = 1};
    assert_int_equal(prt_bake(ctx, scene, sh, o128, &run, &t), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "another bake"));
    char other[512];
    write_text("not_a_checkpoint", "hello", other, sizeof other);
    run.checkpoint = other;
    assert_int_equal(prt_bake(ctx, scene, sh, o64, &run, &t), PRT_ERR_FORMAT);
    assert_non_null(strstr(prt_last_error(), "not a prt checkpoint"));
    unlink(cp);
    prt_options_release(o64);
    prt_options_release(o128);
    prt_scene_release(scene);
    tm_free(&m);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_killed_bakes_resume),
        cmocka_unit_test(test_damaged_checkpoints),
        cmocka_unit_test(test_foreign_checkpoints),
    };
    return cmocka_run_group_tests(tests, test_dir_setup, test_dir_teardown);
}
