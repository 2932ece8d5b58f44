#include "cli.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *HELP =
    "usage: prt relight FILE.prt -o OUT.ply|OUT.json [options]\n"
    "       prt relight FILE.prt --texels -o MAP.exr|.hdr|.pfm|.png [options]\n"
    "Evaluates per-vertex exit radiance (linear RGB) of a baked .prt under a distant lighting.\n"
    "PLY output is binary with float red/green/blue vertex properties (opens in MeshLab,\n"
    "Blender, Open3D); JSON holds {\"kind\", \"vertex_count\", \"radiance\": [[r,g,b], ...]}.\n\n"
    "  -o, --output FILE      .ply or .json (required; written atomically)\n"
    "  -k, --kind K           unshadowed | shadowed | interreflected | glossy-shadowed |\n"
    "                         glossy-interreflected | wavelet (default: the richest diffuse kind\n"
    "                         held; wavelet for files baked with --method wavelet)\n"
    "      --eye X,Y,Z        glossy and wavelet kinds: the viewpoint each vertex's colour is\n"
    "                         seen from (wavelet files with only Lambertian materials need none)\n"
    "      --texels           write the per-texel radiance map (top row = v 1) instead\n"
    CLI_LIGHT_OPTIONS_HELP
    "  -j, --threads N        worker threads\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

int cmd_relight(int argc, char **argv)
{
    cli c = {.cmd = "relight"};
    cli_light light = {.intensity = 1.0f};
    const char *output = NULL, *kind_name = NULL;
    static const struct option opts[] = {{"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'},
                                         {"eye", required_argument, 0, 'e'}, {"texels", no_argument, 0, 'T'}, CLI_LIGHT_LONG_OPTIONS, {"threads", required_argument, 0, 'j'},
                                         {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    float eye[3] = {0, 0, 0};
    bool have_eye = false, texels = false;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'k': kind_name = optarg; break;
        case 'T': texels = true; break;
        case 'e': if (!cli_parse_vec3(optarg, false, eye)) return cli_usage(&c, "--eye takes X,Y,Z"); have_eye = true; break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_usage(&c, "unknown option");
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    if (!output) return cli_usage(&c, "an output file is required (-o OUT.ply or OUT.json)");
    const char *ext = strrchr(output, '.');
    bool json = ext && !strcasecmp(ext, ".json");
    if (!texels && !json && !(ext && !strcasecmp(ext, ".ply"))) return cli_usage(&c, "output must end in .ply or .json");
    if (texels && (json || (ext && !strcasecmp(ext, ".ply")))) return cli_usage(&c, "--texels writes an image: .exr, .hdr, .pfm or .png");
    prt_transfer_kind kind = 0;
    if (kind_name && prt_transfer_kind_parse(kind_name, &kind)) return cli_usage(&c, "%s", prt_last_error());
    if (kind && prt_transfer_kind_is_glossy(kind) && !have_eye) return cli_usage(&c, "glossy kinds are view-dependent: give --eye X,Y,Z");
    if (have_eye && kind && !prt_transfer_kind_is_glossy(kind) && kind != PRT_TRANSFER_WAVELET) return cli_usage(&c, "--eye applies to glossy and wavelet kinds only");
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_transfer *t = NULL;
    float *rgb = NULL;
    prt_sh_light sh;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st) {
        if (!kind) kind = cli_default_kind(t);
        if (kind == PRT_TRANSFER_WAVELET) {
            prt_wavelet_info wi;
            prt_transfer_wavelet_info(t, &wi);
            if (wi.glossy_materials && !have_eye) { cli_error(&c, "'%s' has glossy wavelet transfer, which is view-dependent: give --eye X,Y,Z", argv[optind]); st = PRT_ERR_INVALID_ARG; }
            else if (light.have_brdf) { cli_error(&c, "--brdf does not apply to wavelet transfer: its BRDFs are baked in"); st = PRT_ERR_INVALID_ARG; }
            if (st) { prt_transfer_release(t); prt_context_release(c.ctx); return EXIT_USAGE; }
        } else if (have_eye && !prt_transfer_kind_is_glossy(kind)) {
            cli_error(&c, "--eye applies to glossy and wavelet kinds only");
            prt_transfer_release(t); prt_context_release(c.ctx); return EXIT_USAGE;
        }
        cli_light_defaults_from(&light, t);
        prt_transfer_info info;
        prt_transfer_get_info(t, &info);
        st = cli_light_project(&c, &light, info.order, &sh, NULL);
    }
    if (!st && texels) {
        int w = 0, h = 0;
        if (!prt_transfer_texel_size(t, &w, &h)) {
            cli_error(&c, "'%s' has no per-texel transfer (bake with --texels N)", argv[optind]);
            rc = EXIT_FAILURE_INPUT;
        } else {
            prt_image img = {w, h, malloc((size_t)w * h * 3 * sizeof(float))};
            rgb = malloc((size_t)w * h * 3 * sizeof(float));
            st = img.rgb && rgb ? prt_relight_sh_texels(c.ctx, t, kind, &sh, rgb) : PRT_ERR_NO_MEMORY;
            if (!st) {
                for (int y = 0; y < h; ++y)   /* texel row 0 is v near 0: the image's bottom */
                    memcpy(img.rgb + (size_t)(h - 1 - y) * w * 3, rgb + (size_t)y * w * 3, (size_t)w * 3 * sizeof(float));
                st = prt_image_save(output, &img, NULL);
            }
            rc = st ? cli_fail(&c, st) : EXIT_OK;
            if (!st && !c.quiet) fprintf(stderr, "prt relight: wrote %s (%s, %d x %d texels)\n", output, prt_transfer_kind_name(kind), w, h);
            prt_image_free(&img);
        }
        free(rgb);
        prt_transfer_release(t);
        prt_context_release(c.ctx);
        return rc;
    }
    if (!st) {
        rgb = malloc(prt_transfer_vertex_count(t) * 3 * sizeof(float));
        float *exit = NULL;
        st = rgb ? cli_relight(&c, t, kind, &sh, &light, eye, rgb, &exit) : PRT_ERR_NO_MEMORY;
        if (!st && exit) {
            /* The view factor per vertex, as the renderer applies it per pixel. */
            const float *P = prt_transfer_positions(t), *N = prt_transfer_normals(t);
            const int order = sh.order;
            for (size_t v = 0; v < prt_transfer_vertex_count(t); ++v) {
                float to_eye[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]}, g[3];
                prt_glossy_eval(order, exit + v * 3 * (size_t)order * order, prt_transfer_glossy_mirror(t), N + v * 3, to_eye, g);
                for (int ch = 0; ch < 3; ++ch) rgb[v * 3 + ch] += g[ch];
            }
        }
        free(exit);
    }
    if (!st) {
        size_t nv = prt_transfer_vertex_count(t);
        if (json) {
            cli_vertex_field f = {"radiance", rgb};
            st = cli_write_vertex_json(output, prt_transfer_kind_name(kind), nv, &f, 1);
        } else {
            st = cli_write_vertex_ply(output, prt_transfer_positions(t), prt_transfer_normals(t), nv, prt_transfer_indices(t),
                                      prt_transfer_triangle_count(t), rgb);
        }
        if (st) cli_error(&c, "cannot write '%s'", output);
        else if (!c.quiet) fprintf(stderr, "prt relight: wrote %s (%s, %zu vertices)\n", output, prt_transfer_kind_name(kind), prt_transfer_vertex_count(t));
        rc = st ? EXIT_FAILURE_INPUT : EXIT_OK;
    } else {
        rc = cli_fail(&c, st);
    }
    free(rgb);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}
