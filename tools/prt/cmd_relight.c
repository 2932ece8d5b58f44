#include "cli.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *HELP =
    "usage: prt relight FILE.prt -o OUT.glb|.gltf|.ply|.obj|.json [options]\n"
    "       prt relight FILE.prt --texels -o MAP.exr|.hdr|.pfm|.png [options]\n"
    "Evaluates per-vertex exit radiance of a baked .prt under a lighting and hands the mesh\n"
    "with it to other tools: glTF 2.0 (.glb, .gltf) with the radiance as COLOR_0 (linear, as\n"
    "the format says; three.js, Godot, Unity, Blender read it), PLY and OBJ with sRGB-encoded\n"
    "vertex colours (what MeshLab and Blender show as is; --colors linear for PLY writes float\n"
    "linear red/green/blue instead). Colours are clamped to [0, 1] after --exposure. JSON holds\n"
    "{\"kind\", \"vertex_count\", \"radiance\": [[r,g,b], ...]} unclamped and, where the method\n"
    "separates them, \"indirect\" (the light that bounced at least once) and \"direct\".\n\n"
    "  -o, --output FILE      .glb, .gltf, .ply, .obj or .json (required; written atomically)\n"
    "      --colors C         srgb or linear (default: linear for glTF, srgb for PLY and OBJ)\n"
    "      --exposure STOPS   scale radiance by 2^STOPS before clamping colours (default 0)\n"
    "  -k, --kind K           what to relight the file as (prt info lists what it holds: for SH\n"
    "                         files unshadowed | shadowed | interreflected | glossy-shadowed |\n"
    "                         glossy-interreflected); default: the richest view-independent one\n"
    "      --eye X,Y,Z        the viewpoint each vertex's colour is seen from; needed when the\n"
    "                         result depends on the view (glossy surfaces)\n"
    "      --texels           write the per-texel radiance map (top row = v 1) instead\n"
    CLI_LIGHT_OPTIONS_HELP
    "  -j, --threads N        worker threads\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

static prt_status write_texels(const cli *c, const prt_relit *r, const char *output)
{
    const int w = r->texel_width, h = r->texel_height;
    prt_image img = {w, h, malloc((size_t)w * h * 3 * sizeof(float))};
    if (!img.rgb) return PRT_ERR_NO_MEMORY;
    for (int y = 0; y < h; ++y)   /* texel row 0 is v near 0: the image's bottom */
        memcpy(img.rgb + (size_t)(h - 1 - y) * w * 3, r->texels + (size_t)y * w * 3, (size_t)w * 3 * sizeof(float));
    prt_status st = prt_image_save(output, &img, NULL);
    if (!st && !c->quiet) fprintf(stderr, "prt relight: wrote %s (%d x %d texels)\n", output, w, h);
    prt_image_free(&img);
    return st;
}

int cmd_relight(int argc, char **argv)
{
    cli c = {.cmd = "relight"};
    cli_light light = {.intensity = 1.0f};
    const char *output = NULL, *kind = NULL;
    static const struct option opts[] = {{"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'},
                                         {"eye", required_argument, 0, 'e'}, {"texels", no_argument, 0, 'T'}, CLI_LIGHT_LONG_OPTIONS,
                                         {"colors", required_argument, 0, 'C'}, {"exposure", required_argument, 0, 'E'},
                                         {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'},
                                         {0, 0, 0, 0}};
    int opt;
    float eye[3] = {0, 0, 0};
    bool have_eye = false, texels = false;
    prt_colour_encoding encoding = PRT_COLOURS_DEFAULT;
    float exposure = 0;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case 'k': kind = optarg; break;
        case 'T': texels = true; break;
        case 'C':
            if (!strcasecmp(optarg, "srgb")) encoding = PRT_COLOURS_SRGB;
            else if (!strcasecmp(optarg, "linear")) encoding = PRT_COLOURS_LINEAR;
            else return cli_usage(&c, "--colors must be srgb or linear");
            break;
        case 'E': if (!cli_parse_float(optarg, &exposure) || fabsf(exposure) > 64) return cli_usage(&c, "--exposure takes stops in [-64, 64]"); break;
        case 'e': if (!cli_parse_vec3(optarg, false, eye)) return cli_usage(&c, "--eye takes X,Y,Z"); have_eye = true; break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    if (!output) return cli_usage(&c, "an output file is required (-o OUT.glb, .gltf, .ply, .obj or .json)");
    const char *ext = strrchr(output, '.');
    bool json = ext && !strcasecmp(ext, ".json");
    const bool ply = ext && !strcasecmp(ext, ".ply"),
               mesh = ext && (ply || !strcasecmp(ext, ".glb") || !strcasecmp(ext, ".gltf") || !strcasecmp(ext, ".obj"));
    if (!texels && !json && !mesh) return cli_usage(&c, "output must end in .glb, .gltf, .ply, .obj or .json");
    if (texels && (json || mesh)) return cli_usage(&c, "--texels writes an image: .exr, .hdr, .pfm or .png");
    if ((encoding || exposure != 0) && !mesh) return cli_usage(&c, "--colors and --exposure apply to mesh outputs (.glb .gltf .ply .obj)");
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_transfer *t = NULL;
    prt_lighting *lighting = NULL;
    prt_relit r;
    memset(&r, 0, sizeof r);
    float *rgb = NULL;
    int variant = -1;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st) {
        variant = kind ? prt_transfer_find_variant(t, kind) : prt_transfer_default_variant(t, 0);
        if (variant < 0) rc = cli_usage(&c, "%s", prt_last_error());
    }
    if (!st && !rc) st = cli_lighting(&c, &light, t, NULL, &lighting);
    if (!st && !rc) st = cli_relight(&c, t, lighting, &light, variant, !texels, json && !texels, &r);
    if (!st && !rc) st = cli_check_interrupt(&c);
    if (!st && !rc && texels) {
        if (!r.texels) {
            cli_error(&c, "'%s' has no per-texel %s transfer (bake with --texels N)", argv[optind], prt_transfer_variant_name(t, variant));
            rc = EXIT_FAILURE_INPUT;
        } else {
            st = write_texels(&c, &r, output);
        }
    } else if (!st && !rc) {
        const bool view_dependent = prt_relit_view_dependent(&r);
        if (view_dependent && !have_eye) {
            cli_error(&c, "'%s' relit as %s is view-dependent: give --eye X,Y,Z", argv[optind], prt_transfer_variant_name(t, variant));
            rc = EXIT_USAGE;
        } else if (!view_dependent && have_eye) {
            cli_error(&c, "--eye applies to view-dependent results only ('%s' relit as %s does not depend on the view)", argv[optind],
                      prt_transfer_variant_name(t, variant));
            rc = EXIT_USAGE;
        }
        const size_t nv = prt_transfer_vertex_count(t);
        if (!rc && !(rgb = malloc(nv * 3 * sizeof(float)))) st = PRT_ERR_NO_MEMORY;
        if (!rc && !st) st = prt_relit_shade(c.ctx, t, &r, eye, rgb);
        if (!rc && !st) st = cli_check_interrupt(&c);
        if (!rc && !st) {
            if (json) {
                /* Where the method separates bounced light, the direct part too: what relighting
                 * with direct light only gives (seen from the same eye). */
                float *direct = NULL;
                if (r.indirect) {
                    prt_relight_desc dd = {.variant = variant, .component = PRT_COMPONENT_DIRECT, .per_vertex = 1};
                    int controls[PRT_MAX_CONTROLS];
                    const int nc = cli_controls(&c, &light, t, controls);
                    dd.controls = nc > 0 ? controls : NULL;
                    dd.brdf = light.have_brdf ? &light.brdf : NULL;
                    float *albedo = NULL;
                    prt_relit rd;
                    if (nc >= 0 && !cli_painted_albedo(&c, &light, t, &albedo) && (dd.albedo = albedo, !prt_relight(c.ctx, t, lighting, &dd, &rd))) {
                        if ((direct = malloc(nv * 3 * sizeof(float))) && prt_relit_shade(c.ctx, t, &rd, eye, direct)) { free(direct); direct = NULL; }
                        prt_relit_free(&rd);
                    }
                    free(albedo);
                }
                cli_vertex_field f[3] = {{"radiance", rgb}, {"indirect", r.indirect}, {"direct", direct}};
                st = cli_write_vertex_json(output, prt_transfer_variant_name(t, variant), nv, f, r.indirect ? (direct ? 3 : 2) : 1);
                free(direct);
            } else if (ply && encoding == PRT_COLOURS_LINEAR) {
                /* Float colours keep what 8 bits would lose; assimp's PLY writer has 8 bits only. */
                const float k = exp2f(exposure);
                for (size_t i = 0; i < nv * 3; ++i) rgb[i] = fminf(fmaxf(rgb[i] * k, 0.0f), 1.0f);
                st = cli_write_vertex_ply(output, prt_transfer_positions(t), prt_transfer_normals(t), nv, prt_transfer_indices(t),
                                          prt_transfer_triangle_count(t), rgb);
            } else {
                const prt_mesh_export_desc ed = {prt_transfer_positions(t), prt_transfer_normals(t), nv, prt_transfer_indices(t),
                                                 prt_transfer_triangle_count(t), rgb, encoding, exposure};
                st = prt_mesh_export(output, &ed);
                if (st) { cli_error(&c, "%s", prt_last_error()); rc = EXIT_FAILURE_INPUT; st = PRT_OK; }
            }
            if (st) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; st = PRT_OK; }
            else if (!rc && !c.quiet) fprintf(stderr, "prt relight: wrote %s (%s, %zu vertices)\n", output, prt_transfer_variant_name(t, variant), nv);
        }
    }
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    prt_relit_free(&r);
    prt_lighting_release(lighting);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}
