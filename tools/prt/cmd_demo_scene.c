#include "cli.h"

#include <getopt.h>
#include <stdio.h>

static const char *HELP =
    "usage: prt demo-scene -o OUT.obj\n"
    "Writes the procedural demo scene (a torus and a sphere on a floor between a red and a green\n"
    "wall) as OUT.obj with materials in OUT.mtl beside it.\n\n"
    "  -o, --output FILE      the .obj to write (required)\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

int cmd_demo_scene(int argc, char **argv)
{
    cli c = {.cmd = "demo-scene"};
    const char *output = NULL;
    int opt;
    static const struct option opts[] = {{"output", required_argument, 0, 'o'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:h", opts, NULL)) != -1) {
        if (opt == 'o') output = optarg;
        else if (opt == 'h') { fputs(HELP, stdout); return EXIT_OK; }
        else return cli_bad_option(&c, opt, argv);
    }
    if (optind != argc || !output) return cli_usage(&c, "expected -o OUT.obj and no other arguments");
    prt_status st = prt_demo_scene_write(output);
    return st ? cli_fail(&c, st) : EXIT_OK;
}
