#include "cli.h"

#include <getopt.h>
#include <stdio.h>

static const char *HELP =
    "usage: prt demo-scene -o OUT.obj [--room [--cell D]]\n"
    "Writes the procedural demo scene (a torus and a sphere on a floor between a red and a green\n"
    "wall) as OUT.obj with materials in OUT.mtl beside it.\n\n"
    "  -o, --output FILE      the .obj to write (required)\n"
    "      --room             instead a closed 6 x 3 x 4 m room with a 1.2 x 1 m window in its front\n"
    "                         wall (z = 2), a box and a shelf: light it through the window, e.g.\n"
    "                         --env none --light directional:0.3,0.6,1:30\n"
    "      --cell D           the room's grid spacing in metres (default 0.0625: about 30,000\n"
    "                         vertices)\n"
    "  -q, --quiet            accepted for scripts, as every command takes it (this one prints\n"
    "                         nothing but errors)\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

int cmd_demo_scene(int argc, char **argv)
{
    cli c = {.cmd = "demo-scene"};
    const char *output = NULL;
    bool room = false, have_cell = false;
    float cell = 0.0625f;
    int opt;
    static const struct option opts[] = {{"output", required_argument, 0, 'o'}, {"room", no_argument, 0, 'r'}, {"cell", required_argument, 0, 'c'},
                                         {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:qh", opts, NULL)) != -1) {
        if (opt == 'o') output = optarg;
        else if (opt == 'r') room = true;
        else if (opt == 'c') {
            if (!cli_parse_float(optarg, &cell) || !(cell >= 0.005f && cell <= 1.0f)) return cli_usage(&c, "--cell takes a spacing in 0.005..1 metres");
            have_cell = true;
        }
        else if (opt == 'q') c.quiet = true;
        else if (opt == 'h') { fputs(HELP, stdout); return EXIT_OK; }
        else return cli_bad_option(&c, opt, argv, opts);
    }
    if (optind != argc || !output) return cli_usage(&c, "expected -o OUT.obj and no other arguments");
    if (have_cell && !room)
        return cli_usage(&c, "--cell is the room's grid spacing: give --room too");
    prt_status st = room ? prt_demo_room_write(output, cell) : prt_demo_scene_write(output);
    return st ? cli_fail(&c, st) : EXIT_OK;
}
