/* prt: one command line over libprt. Each subcommand lives in its own cmd_*.c. */
#include "cli.h"

#include <stdio.h>
#include <string.h>

static const struct { const char *name; int (*fn)(int, char **); const char *summary; } commands[] = {
    {"bake", cmd_bake, "precompute radiance transfer for a scene into a .prt file"},
    {"merge", cmd_merge, "put the shards of a bake spread over machines back together (docs/CLUSTER.md)"},
    {"relight", cmd_relight, "per-vertex exit radiance of a .prt under a lighting: glTF, PLY, OBJ, JSON or a texel map"},
    {"export", cmd_export, "a .prt as a mesh for other tools: radiance as vertex colours, and what its method exports"},
    {"render", cmd_render, "draw a relit .prt to an image: PNG, EXR, HDR or PFM (headless OpenGL)"},
    {"view", cmd_view, "interactive real-time relighting window (GLFW); --script replays input"},
    {"env", cmd_env, "project an environment probe to SH; optional band-limited / irradiance image"},
    {"info", cmd_info, "describe what a .prt file holds"},
    {"reference", cmd_reference, "ground truth by path tracing: per-vertex (direct/indirect) or an image"},
    {"compare", cmd_compare, "error between two results (vertices or images): RMSE, relative L2, PSNR"},
    {"sweep", cmd_sweep, "bake and relight over a parameter range against a reference: CSV and plot"},
    {"pick", cmd_pick, "which method for a scene: each baked and measured side by side (sweep --method all)"},
    {"demo-scene", cmd_demo_scene, "write the procedural demo scene as OBJ+MTL"},
};

static void usage(FILE *f)
{
    fprintf(f, "usage: prt COMMAND [OPTIONS]   (prt COMMAND --help for each)\n       prt --version\n\nCommands:\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i) fprintf(f, "  %-11s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\n" EXIT_CODES_HELP);
}

int main(int argc, char **argv)
{
    if (argc < 2) { usage(stderr); return EXIT_USAGE; }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) { usage(stdout); return EXIT_OK; }
    if (!strcmp(argv[1], "--version")) { printf("prt %s\n", prt_version_string()); return EXIT_OK; }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i)
        if (!strcmp(argv[1], commands[i].name)) {
            const int rc = commands[i].fn(argc - 1, argv + 1);
            cli_release_lights();
            return rc;
        }
    /* A misspelt command: name the closest one (within a third of its length), on one line. */
    const char *best = NULL;
    int best_d = 9;
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; ++i) {
        const int d = cli_edit_distance(commands[i].name, argv[1], strlen(argv[1]));
        if (d < best_d) { best_d = d; best = commands[i].name; }
    }
    if (best && best_d <= 1 + (int)strlen(best) / 3) {
        fprintf(stderr, "prt: unknown command '%s': did you mean 'prt %s'? (prt --help lists the commands)\n", argv[1], best);
        return EXIT_USAGE;
    }
    fprintf(stderr, "prt: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return EXIT_USAGE;
}
