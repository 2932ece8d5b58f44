#include "cli.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *HELP =
    "usage: prt render FILE.prt -o OUT.png|OUT.exr [options]\n"
    "Relights a baked .prt and draws it with OpenGL 3.3 (headless EGL; Mesa llvmpipe without a\n"
    "GPU). Several kinds are drawn side by side, left to right, in the order given.\n\n"
    "  -o, --output FILE      the image (required): .png (tone-mapped sRGB), .exr (linear half),\n"
    "                         .hdr or .pfm\n"
    "  -k, --kind LIST        comma list of what to draw the file as (prt info lists what it\n"
    "                         holds), or 'all'; default: the richest. View-dependent parts\n"
    "                         (glossy surfaces) are evaluated per pixel\n"
    "      --width N          image width in pixels, per panel (default 800)\n"
    CLI_VIEW_CAMERA_HELP CLI_VIEW_TONE_HELP CLI_VIEW_BACKGROUND_HELP
    CLI_LIGHT_OPTIONS_HELP
    "Other:\n"
    "      --per-vertex       shade from the vertex sets even where the file has per-texel ones,\n"
    "                         and evaluate view-dependent parts per vertex rather than per pixel\n"
    "      --accumulate W     files whose method has GPU passes (prt info says): where the passes\n"
    "                         run - cpu (default: threads) or gpu (the maps binned into atlases,\n"
    "                         accumulated by additive blending); the same light map either way\n"
    "  -j, --threads N        worker threads for relighting\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

#define MAX_PANELS 16

int cmd_render(int argc, char **argv)
{
    cli c = {.cmd = "render"};
    cli_light light = {.intensity = 1.0f};
    cli_kinds kinds = {0};
    char kind_buf[512];
    const char *output = NULL;
    bool per_vertex = false;
    cli_view view = CLI_VIEW_DEFAULTS;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'}, CLI_VIEW_LONG_OPTIONS, CLI_LIGHT_LONG_OPTIONS,
        {"threads", required_argument, 0, 'j'}, {"per-vertex", no_argument, 0, 'P'}, {"accumulate", required_argument, 0, 'A'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0}};
    int opt;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (!r) r = cli_view_option(&c, &view, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'P': per_vertex = true; break;
        case 'A':
            if (!cli_parse_accumulate(optarg, &light.gpu_finish)) return cli_usage(&c, "--accumulate takes cpu or gpu");
            break;
        case 'k':
            snprintf(kind_buf, sizeof kind_buf, "%s", optarg);
            if (!cli_relight_kinds(&kinds, kind_buf)) return cli_usage(&c, "--kind takes a comma list of at most 16 names");
            break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    if (!output) return cli_usage(&c, "an output image is required (-o OUT.png)");
    if (view.have_eye != view.have_target) return cli_usage(&c, "--eye and --target go together");
    const int width = view.width, height = view.height;
    int rc = cli_make_context(&c);
    if (rc) return rc;

    prt_transfer *t = NULL;
    prt_renderer *r = NULL;
    prt_lighting *lighting = NULL;
    float *rgb = NULL;
    prt_image panel = {0}, sheet = {0};
    int variants[MAX_PANELS], count = 0;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st && (count = cli_relight_resolve(&c, &kinds, t, 1, variants, MAX_PANELS)) < 0) rc = EXIT_USAGE;
    if (!st && !rc && light.gpu_finish && !cli_check_accumulate(&c, t, per_vertex)) rc = EXIT_USAGE;
    if (!st && !rc) st = cli_lighting(&c, &light, t, NULL, &lighting);
    if (!st && !rc) st = prt_renderer_create(c.ctx, &(prt_renderer_desc){width, height, 0}, &r);
    if (!st && !rc) {
        size_t nv = prt_transfer_vertex_count(t);
        rgb = malloc(nv * 3 * sizeof(float));
        sheet.width = width * count;
        sheet.height = height;
        sheet.rgb = calloc((size_t)sheet.width * height * 3, sizeof(float));
        if (!rgb || !sheet.rgb) st = PRT_ERR_NO_MEMORY;
    }
    prt_camera cam;
    if (!st && !rc) cli_view_camera(&c, &view, prt_transfer_positions(t), prt_transfer_vertex_count(t), prt_transfer_indices(t), prt_transfer_triangle_count(t),
                                   (float)width / height, &cam);
    for (int k = 0; k < count && !st && !rc; ++k) {
        prt_relit relit;
        if ((st = cli_relight(&c, t, lighting, &light, variants[k], per_vertex, false, &relit))) break;
        prt_render_mesh mesh;
        prt_relit_render_mesh(t, &relit, &mesh);
        if (per_vertex && prt_relit_view_dependent(&relit)) {
            /* The view factor on the CPU, per vertex, towards the camera. */
            st = prt_relit_shade(c.ctx, t, &relit, cam.eye, rgb);
            prt_render_mesh plain = {.positions = mesh.positions, .radiance = rgb, .vertex_count = mesh.vertex_count, .indices = mesh.indices,
                                     .triangle_count = mesh.triangle_count, .normals = mesh.normals};
            mesh = plain;
        }
        if (!st) st = prt_render(r, &mesh, &cam, view.background, &panel);
        prt_relit_free(&relit);
        if (st) break;
        for (int y = 0; y < height; ++y)
            memcpy(sheet.rgb + ((size_t)y * sheet.width + (size_t)k * width) * 3, panel.rgb + (size_t)y * width * 3,
                   (size_t)width * 3 * sizeof(float));
        prt_image_free(&panel);
    }
    if (!st && !rc) st = cli_check_interrupt(&c);
    if (!st && !rc) st = prt_image_save(output, &sheet, &view.save);
    if (!st && !rc && !c.quiet) {
        fprintf(stderr, "prt render: wrote %s (", output);
        for (int k = 0; k < count; ++k) fprintf(stderr, "%s%s", k ? ", " : "", prt_transfer_variant_name(t, variants[k]));
        fprintf(stderr, "; %s)\n", prt_renderer_name(r));
    }
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    prt_image_free(&sheet);
    prt_renderer_release(r);
    prt_lighting_release(lighting);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}
