#include "cli.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>

static const char *HELP =
    "usage: prt info FILE.prt [--json]\n"
    "Describes a .prt file: its method and that method's settings, what it can be relit as,\n"
    "the mesh, materials, the lights its scene named, storage and bake settings. The file is\n"
    "fully validated (sizes and checksums) on the way.\n\n"
    "      --json             machine-readable output\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

int cmd_info(int argc, char **argv)
{
    cli c = {.cmd = "info", .quiet = true};
    int json = 0, opt;
    static const struct option opts[] = {{"json", no_argument, 0, 'J'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":h", opts, NULL)) != -1) {
        if (opt == 'J') json = 1;
        else if (opt == 'h') { fputs(HELP, stdout); return EXIT_OK; }
        else return cli_bad_option(&c, opt, argv, opts);
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    c.threads = 1;
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_transfer *t = NULL;
    char *text = NULL;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st) st = prt_transfer_describe(t, argv[optind], json, &text);
    if (st) rc = cli_fail(&c, st);
    else printf("%s%s", text, json ? "\n" : "");
    free(text);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}
