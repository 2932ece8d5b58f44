/* prt merge: puts the shards of one stage of a bake back together (docs/CLUSTER.md). */
#include "cli.h"

#include <cjson/cJSON.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *HELP =
    "usage: prt merge SHARD... -o OUT\n"
    "Puts the shards of one stage of a bake (prt bake --shard I/N) back together: they must be\n"
    "of one bake (scene, method, options, seed, prt version), one stage, and continue the same\n"
    "--from; every I of 1..N once. Then goes on with the bake where the shards' command ran it\n"
    "(its folder, scene and options, kept in the shards): when stages that can be spread remain,\n"
    "OUT holds every finished stage (the next shards' --from) and stdout says `next K`, the\n"
    "stage to shard next; after the last, OUT is the .prt file, byte for byte what one bake\n"
    "writes but for its time, threads and host, and stdout says `done`.\n\n"
    "  -o, --output FILE      what to write (required)\n"
    "  -j, --threads N        worker threads for the rest of the bake (default: all cores)\n"
    "  -q, --quiet            no progress or messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP
    "Shards that do not belong together (another bake, stage or --from, a shard twice or one\n"
    "missing) are refused with exit code 2, naming the file and what differs; a shard that is\n"
    "damaged or cut off, with exit code 1.\n";

int cmd_merge(int argc, char **argv)
{
    cli c = {.cmd = "merge"};
    const char *output = NULL;
    int opt;
    static const struct option opts[] = {{"output", required_argument, 0, 'o'}, {"threads", required_argument, 0, 'j'},
                                         {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:j:qh", opts, NULL)) != -1) {
        if (opt == 'o') output = optarg;
        else if (opt == 'j') { if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); }
        else if (opt == 'q') c.quiet = true;
        else if (opt == 'h') { fputs(HELP, stdout); return EXIT_OK; }
        else return cli_bad_option(&c, opt, argv, opts);
    }
    if (optind >= argc) return cli_usage(&c, "expected the SHARD files to merge");
    if (!output) return cli_usage(&c, "an output file is required (-o OUT)");
    char out_abs[4096], merging[4200];
    /* The bake goes on in the shards' folder: OUT as named here. */
    if (output[0] == '/') snprintf(out_abs, sizeof out_abs, "%s", output);
    else {
        char cwd[2048];
        if (!getcwd(cwd, sizeof cwd)) return cli_usage(&c, "cannot tell the current folder");
        snprintf(out_abs, sizeof out_abs, "%s/%s", cwd, output);
    }
    snprintf(merging, sizeof merging, "%s.merging", out_abs);
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_bake_shard info;
    prt_status st = prt_bake_merge_shards(c.ctx, (const char *const *)(argv + optind), argc - optind, merging, &info);
    if (st) {
        rc = cli_fail(&c, st);
        prt_context_release(c.ctx);
        return rc;
    }
    if (!c.quiet && info.stage >= 0)
        fprintf(stderr, "prt merge: %d shards of stage %d (%s), %llu units\n", info.count, info.stage, info.stage_name, (unsigned long long)info.units);
    /* The bake's command as the shards kept it: its folder and arguments. */
    cJSON *note = cJSON_Parse(info.note ? info.note : "");
    const cJSON *cwd = cJSON_GetObjectItemCaseSensitive(note, "cwd"), *args = cJSON_GetObjectItemCaseSensitive(note, "args");
    const int nargs = cJSON_IsArray(args) ? cJSON_GetArraySize(args) : -1;
    char **bake = nargs >= 0 ? calloc((size_t)nargs + 8, sizeof *bake) : NULL;
    char threads[16];
    if (!cJSON_IsString(cwd) || !bake) {
        cli_error(&c, "the shards do not say which bake they are of (made by another program?)");
        rc = EXIT_FAILURE_INPUT;
    } else if (chdir(cwd->valuestring) != 0) {
        cli_error(&c, "the shards were baked in %s, which is not here: merge where the scene is at the same path", cwd->valuestring);
        rc = EXIT_FAILURE_INPUT;
    } else {
        int n = 0;
        bake[n++] = "bake";
        for (int i = 0; i < nargs; ++i) {
            const cJSON *a = cJSON_GetArrayItem(args, i);
            if (cJSON_IsString(a)) bake[n++] = a->valuestring;
        }
        bake[n++] = "-o";
        bake[n++] = out_abs;
        if (c.quiet) bake[n++] = "-q";
        if (c.threads) {
            snprintf(threads, sizeof threads, "%d", c.threads);
            bake[n++] = "-j";
            bake[n++] = threads;
        }
        const cli_bake_extra extra = {.merged = merging};
        prt_context_release(c.ctx);
        c.ctx = NULL;
        rc = cli_bake_main(n, bake, &extra);
    }
    if (rc) remove(merging);
    free(bake);
    cJSON_Delete(note);
    free(info.note);
    prt_context_release(c.ctx);
    return rc;
}
