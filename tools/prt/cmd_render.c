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
    "  -o, --output FILE      .png (tone-mapped sRGB), .exr (linear half), .hdr or .pfm\n"
    "  -k, --kind LIST        comma list of unshadowed,shadowed,interreflected or 'all'\n"
    "                         (default: the richest kind in the file)\n"
    "      --width N          width of one panel in pixels (default 800)\n"
    "      --height N         height in pixels (default 600)\n"
    "      --view X,Y,Z       direction from the scene centre towards the camera (auto framing)\n"
    "      --eye X,Y,Z        camera position (with --target: overrides auto framing)\n"
    "      --target X,Y,Z     point the camera looks at\n"
    "      --fov DEG          vertical field of view (default 40)\n"
    "      --exposure STOPS   PNG: scale radiance by 2^STOPS before tone mapping (default 0)\n"
    "      --tonemap T        PNG: reinhard (default) or clamp\n"
    "      --background R,G,B linear background radiance (default 0.02)\n"
    CLI_LIGHT_OPTIONS_HELP
    "  -j, --threads N        worker threads for relighting\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

enum { OPT_WIDTH = 2000, OPT_HEIGHT, OPT_VIEW, OPT_EYE, OPT_TARGET, OPT_FOV, OPT_EXPOSURE, OPT_TONEMAP, OPT_BACKGROUND };

int cmd_render(int argc, char **argv)
{
    cli c = {.cmd = "render"};
    cli_light light = {.intensity = 1.0f};
    const char *output = NULL;
    prt_transfer_kind kinds[3];
    int nkinds = 0, width = 800, height = 600;
    bool have_view = false, have_eye = false, have_target = false;
    float view[3], eye[3], target[3], fov = 40.0f, background[3] = {0.02f, 0.02f, 0.02f};
    prt_image_save_desc save = {0};
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'}, {"width", required_argument, 0, OPT_WIDTH},
        {"height", required_argument, 0, OPT_HEIGHT}, {"view", required_argument, 0, OPT_VIEW}, {"eye", required_argument, 0, OPT_EYE},
        {"target", required_argument, 0, OPT_TARGET}, {"fov", required_argument, 0, OPT_FOV},
        {"exposure", required_argument, 0, OPT_EXPOSURE}, {"tonemap", required_argument, 0, OPT_TONEMAP},
        {"background", required_argument, 0, OPT_BACKGROUND}, CLI_LIGHT_LONG_OPTIONS, {"threads", required_argument, 0, 'j'},
        {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'k': {
            char buf[256], *save_ptr = NULL;
            snprintf(buf, sizeof buf, "%s", optarg);
            nkinds = 0;
            for (char *tok = strtok_r(buf, ",", &save_ptr); tok; tok = strtok_r(NULL, ",", &save_ptr)) {
                if (!strcasecmp(tok, "all")) {
                    kinds[0] = PRT_TRANSFER_UNSHADOWED; kinds[1] = PRT_TRANSFER_SHADOWED; kinds[2] = PRT_TRANSFER_INTERREFLECTED;
                    nkinds = 3;
                    continue;
                }
                if (nkinds == 3) return cli_usage(&c, "--kind takes at most three kinds");
                if (prt_transfer_kind_parse(tok, &kinds[nkinds])) return cli_usage(&c, "%s", prt_last_error());
                nkinds++;
            }
            break;
        }
        case OPT_WIDTH: if (!cli_parse_int(optarg, 1, 8192, &width)) return cli_usage(&c, "--width must be 1..8192"); break;
        case OPT_HEIGHT: if (!cli_parse_int(optarg, 1, 8192, &height)) return cli_usage(&c, "--height must be 1..8192"); break;
        case OPT_VIEW: if (!cli_parse_vec3(optarg, false, view)) return cli_usage(&c, "--view takes X,Y,Z"); have_view = true; break;
        case OPT_EYE: if (!cli_parse_vec3(optarg, false, eye)) return cli_usage(&c, "--eye takes X,Y,Z"); have_eye = true; break;
        case OPT_TARGET: if (!cli_parse_vec3(optarg, false, target)) return cli_usage(&c, "--target takes X,Y,Z"); have_target = true; break;
        case OPT_FOV: if (!cli_parse_float(optarg, &fov) || fov <= 1 || fov >= 179) return cli_usage(&c, "--fov must be in (1, 179)"); break;
        case OPT_EXPOSURE: if (!cli_parse_float(optarg, &save.exposure_stops)) return cli_usage(&c, "--exposure takes a number of stops"); break;
        case OPT_TONEMAP:
            if (!strcasecmp(optarg, "reinhard")) save.tonemap = 1;
            else if (!strcasecmp(optarg, "clamp")) save.tonemap = 2;
            else return cli_usage(&c, "--tonemap must be reinhard or clamp");
            break;
        case OPT_BACKGROUND: if (!cli_parse_vec3(optarg, true, background)) return cli_usage(&c, "--background takes R,G,B"); break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_usage(&c, "unknown option");
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    if (!output) return cli_usage(&c, "an output image is required (-o OUT.png)");
    if (have_eye != have_target) return cli_usage(&c, "--eye and --target go together");
    int rc = cli_make_context(&c);
    if (rc) return rc;

    prt_transfer *t = NULL;
    prt_renderer *r = NULL;
    float *rgb = NULL;
    prt_image panel = {0}, sheet = {0};
    prt_sh_light sh;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st) {
        if (!nkinds) kinds[nkinds++] = cli_default_kind(t);
        cli_light_defaults_from(&light, t);
        prt_transfer_info info;
        prt_transfer_get_info(t, &info);
        st = cli_light_project(&c, &light, info.order, &sh, NULL);
    }
    if (!st) st = prt_renderer_create(c.ctx, &(prt_renderer_desc){width, height, 0}, &r);
    if (!st) {
        size_t nv = prt_transfer_vertex_count(t);
        rgb = malloc(nv * 3 * sizeof(float));
        sheet.width = width * nkinds;
        sheet.height = height;
        sheet.rgb = calloc((size_t)sheet.width * height * 3, sizeof(float));
        if (!rgb || !sheet.rgb) st = PRT_ERR_NO_MEMORY;
    }
    prt_camera cam;
    if (!st) {
        float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
        const float *p = prt_transfer_positions(t);
        for (size_t i = 0; i < prt_transfer_vertex_count(t) * 3; ++i) {
            if (p[i] < lo[i % 3]) lo[i % 3] = p[i];
            if (p[i] > hi[i % 3]) hi[i % 3] = p[i];
        }
        prt_camera_frame(lo, hi, have_view ? view : NULL, fov, (float)width / height, &cam);
        if (have_eye) { memcpy(cam.eye, eye, sizeof eye); memcpy(cam.target, target, sizeof target); }
    }
    for (int k = 0; k < nkinds && !st; ++k) {
        st = prt_relight_sh(c.ctx, t, kinds[k], &sh, rgb);
        if (st) break;
        prt_render_mesh mesh = {prt_transfer_positions(t), rgb, prt_transfer_vertex_count(t), prt_transfer_indices(t),
                                prt_transfer_triangle_count(t)};
        st = prt_render(r, &mesh, &cam, background, &panel);
        if (st) break;
        for (int y = 0; y < height; ++y)
            memcpy(sheet.rgb + ((size_t)y * sheet.width + (size_t)k * width) * 3, panel.rgb + (size_t)y * width * 3,
                   (size_t)width * 3 * sizeof(float));
        prt_image_free(&panel);
    }
    if (!st) st = prt_image_save(output, &sheet, &save);
    if (!st && !c.quiet) {
        fprintf(stderr, "prt render: wrote %s (", output);
        for (int k = 0; k < nkinds; ++k) fprintf(stderr, "%s%s", k ? ", " : "", prt_transfer_kind_name(kinds[k]));
        fprintf(stderr, "; %s)\n", prt_renderer_name(r));
    }
    rc = st ? cli_fail(&c, st) : EXIT_OK;
    free(rgb);
    prt_image_free(&sheet);
    prt_renderer_release(r);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}
