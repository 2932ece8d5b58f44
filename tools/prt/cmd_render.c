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
    "  -k, --kind LIST        comma list of unshadowed, shadowed, interreflected, glossy-shadowed,\n"
    "                         glossy-interreflected, or 'all' (the three diffuse kinds); default:\n"
    "                         the richest kind in the file. Glossy kinds add the view-dependent\n"
    "                         part, evaluated per pixel, to the diffuse kind of the same shadowing;\n"
    "                         wavelet (files baked with --method wavelet) is shaded per vertex\n"
    "                         towards the camera\n"
    CLI_VIEW_OPTIONS_HELP
    CLI_LIGHT_OPTIONS_HELP
    "      --per-vertex       shade from the vertex sets even where the file has per-texel ones,\n"
    "                         and wavelet files' view factor per vertex rather than per pixel\n"
    "  -j, --threads N        worker threads for relighting\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

int cmd_render(int argc, char **argv)
{
    cli c = {.cmd = "render"};
    cli_light light = {.intensity = 1.0f};
    const char *output = NULL;
    prt_transfer_kind kinds[5];
    int nkinds = 0;
    bool per_vertex = false;
    cli_view view = CLI_VIEW_DEFAULTS;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'}, CLI_VIEW_LONG_OPTIONS, CLI_LIGHT_LONG_OPTIONS, {"threads", required_argument, 0, 'j'}, {"per-vertex", no_argument, 0, 'P'},
        {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (!r) r = cli_view_option(&c, &view, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'P': per_vertex = true; break;
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
                if (nkinds == 5) return cli_usage(&c, "--kind takes at most five kinds");
                if (prt_transfer_kind_parse(tok, &kinds[nkinds])) return cli_usage(&c, "%s", prt_last_error());
                nkinds++;
            }
            break;
        }
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_usage(&c, "unknown option");
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
    float *rgb = NULL;
    prt_image panel = {0}, sheet = {0};
    prt_sh_light sh;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st) {
        if (!nkinds) kinds[nkinds++] = cli_default_view_kind(t);
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
        cli_view_camera(&view, prt_transfer_positions(t), prt_transfer_vertex_count(t), (float)width / height, &cam);
    }
    for (int k = 0; k < nkinds && !st; ++k) {
        float *exit = NULL, *texels = NULL;
        if (kinds[k] == PRT_TRANSFER_WAVELET && light.have_brdf) { cli_error(&c, "--brdf does not apply to wavelet transfer: its BRDFs are baked in"); st = PRT_ERR_INVALID_ARG; break; }
        /* Wavelet files with glossy materials: the view factor per pixel from the K-vectors. */
        float *kvec = NULL;
        const float *view_maps = NULL;
        const uint8_t *view_set = NULL;
        int sets = 0, res = 0, polar = 0;
        prt_wavelet_info wi;
        if (kinds[k] == PRT_TRANSFER_WAVELET && !per_vertex && prt_transfer_wavelet_info(t, &wi) &&
            prt_wavelet_view_maps(t, &view_maps, &sets, &res, &polar, &view_set)) {
            st = cli_wavelet_kvec(&c, t, &light, &kvec);
            if (!st) st = prt_wavelet_shade(c.ctx, t, kvec, NULL, rgb);   /* Lambertian vertices; glossy ones per pixel */
        } else {
            st = cli_relight(&c, t, kinds[k], &sh, &light, cam.eye, rgb, &exit);
        }
        if (st) { free(kvec); break; }
        prt_transfer_info info;
        prt_transfer_get_info(t, &info);
        int tw = 0, th = 0;
        if (!per_vertex && prt_transfer_texel_coeffs(t, kinds[k], NULL)) {
            prt_transfer_texel_size(t, &tw, &th);
            texels = malloc((size_t)tw * th * 3 * sizeof(float));
            st = texels ? prt_relight_sh_texels(c.ctx, t, kinds[k], &sh, texels) : PRT_ERR_NO_MEMORY;
            if (st) { free(exit); free(texels); break; }
        }
        prt_render_mesh mesh = {.positions = prt_transfer_positions(t), .radiance = rgb, .vertex_count = prt_transfer_vertex_count(t),
                                .indices = prt_transfer_indices(t), .triangle_count = prt_transfer_triangle_count(t),
                                .normals = prt_transfer_normals(t), .exit_sh = exit, .exit_order = exit ? info.order : 0,
                                .exit_mirror = prt_transfer_glossy_mirror(t), .uv = prt_transfer_uvs(t), .texel_radiance = texels,
                                .texel_width = tw, .texel_height = th, .kvec = kvec, .kvec_terms = kvec ? wi.terms : 0,
                                .view_set = view_set, .view_maps = view_maps, .view_map_sets = sets, .view_map_resolution = res,
                                .view_map_polar = polar};
        st = prt_render(r, &mesh, &cam, view.background, &panel);
        free(exit);
        free(kvec);
        free(texels);
        if (st) break;
        for (int y = 0; y < height; ++y)
            memcpy(sheet.rgb + ((size_t)y * sheet.width + (size_t)k * width) * 3, panel.rgb + (size_t)y * width * 3,
                   (size_t)width * 3 * sizeof(float));
        prt_image_free(&panel);
    }
    if (!st) st = prt_image_save(output, &sheet, &view.save);
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
