#include "cli.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *HELP =
    "usage: prt reference INPUT [-o OUT.json|OUT.ply] [--image OUT.exr|OUT.png] [options]\n"
    "Ground truth by unbiased Monte Carlo path tracing (Embree): per-vertex exit radiance split\n"
    "into direct and indirect light with standard errors, and/or an image from a camera.\n"
    "INPUT is a .prt (its baked mesh, so results match the file vertex for vertex, and all the\n"
    "lighting its scene named, whatever the method relights) or a scene, read with the same\n"
    "options as prt bake.\n"
    "Surfaces are one-sided and reflect with their material's BRDF (Lambert where none); light\n"
    "comes from the environment, local lights and emissive surfaces, each sampled explicitly and\n"
    "combined with BRDF sampling (MIS); paths end by Russian roulette. Glossy vertices are seen\n"
    "from the camera (--eye, or the auto-framed view prt render uses).\n\n"
    "  -o, --output FILE      per-vertex result: .json (radiance, direct, indirect, std_error,\n"
    "                         std_error_indirect) or .ply (radiance as float vertex colours)\n"
    "      --image FILE       image from the camera (.exr .png .hdr .pfm)\n"
    "      --samples N        paths per vertex or pixel (default 256)\n"
    "      --target-error E   add paths until every vertex's standard error is below E times its\n"
    "                         radiance (doubling, up to --max-samples)\n"
    "      --max-samples N    cap for --target-error (default 65536)\n"
    "      --seed N           random seed (default 0; results do not depend on the thread count)\n"
    CLI_VIEW_OPTIONS_HELP
    "Lighting (default: what the scene named, all of it, else the procedural sky):\n"
    CLI_LIGHT_SOURCES_HELP
    "  --albedo-of NAME=R,G,B  recolour the surface NAME (a material of the scene; prt info lists\n"
    "                        a .prt's), repeatable\n"
    "Scene (when INPUT is not a .prt):\n" CLI_SCENE_FILE_HELP
    "Other:\n"
    "  -j, --threads N        worker threads\n"
    CLI_PROGRESS_HELP
    "  -q, --quiet            no progress or messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

enum { OPT_IMAGE_OUT = 2200, OPT_SAMPLES, OPT_TARGET_ERROR, OPT_MAX_SAMPLES, OPT_SEED };

int cmd_reference(int argc, char **argv)
{
    cli c = {.cmd = "reference"};
    cli_light light = {.intensity = 1.0f};
    cli_view view = CLI_VIEW_DEFAULTS;
    prt_scene_desc sd = {0};
    prt_reference_desc rd = {0};
    const char *output = NULL, *image = NULL;
    int seed;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"image", required_argument, 0, OPT_IMAGE_OUT},
        {"samples", required_argument, 0, OPT_SAMPLES}, {"target-error", required_argument, 0, OPT_TARGET_ERROR},
        {"max-samples", required_argument, 0, OPT_MAX_SAMPLES}, {"seed", required_argument, 0, OPT_SEED},
        CLI_VIEW_LONG_OPTIONS, CLI_LIGHT_LONG_OPTIONS, CLI_SCENE_LONG_OPTIONS, {"threads", required_argument, 0, 'j'},
        {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":o:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (!r) r = cli_view_option(&c, &view, opt, optarg);
        if (!r) r = cli_scene_option(&c, &sd, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case OPT_IMAGE_OUT: image = optarg; break;
        case OPT_SAMPLES: if (!cli_parse_int(optarg, 1, 1 << 24, &rd.samples)) return cli_usage(&c, "--samples must be 1..16777216"); break;
        case OPT_TARGET_ERROR:
            if (!cli_parse_float(optarg, &rd.target_rel_error) || rd.target_rel_error <= 0 || rd.target_rel_error >= 1)
                return cli_usage(&c, "--target-error must be in (0, 1)");
            break;
        case OPT_MAX_SAMPLES: if (!cli_parse_int(optarg, 1, 1 << 24, &rd.max_samples)) return cli_usage(&c, "--max-samples must be 1..16777216"); break;
        case OPT_SEED: if (!cli_parse_int(optarg, 0, 2147483647, &seed)) return cli_usage(&c, "--seed must be a non-negative integer"); rd.seed = (uint32_t)seed; break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one INPUT (.prt or scene)");
    if (!output && !image) return cli_usage(&c, "nothing to do: give -o OUT.json|.ply and/or --image OUT");
    const char *ext = output ? strrchr(output, '.') : NULL;
    bool json = ext && !strcasecmp(ext, ".json");
    if (output && !json && !(ext && !strcasecmp(ext, ".ply"))) return cli_usage(&c, "-o must end in .json or .ply");
    if (view.have_eye != view.have_target) return cli_usage(&c, "--eye and --target go together");
    if (light.set_intensity && light.intensity == 0) return cli_usage(&c, "--intensity 0 leaves nothing to trace");
    /* Both set how a .prt is relit; the path tracer reflects with the materials' own BRDFs and
     * follows every bounce. */
    if (light.brdf_of_count)
        return cli_usage(&c, "--brdf-of does not apply: prt reference traces the BRDFs the scene's materials wear "
                             "(trace a scene whose material wears it: its \"brdf\")");
    if (light.have_brdf || light.control_count)
        return cli_usage(&c, "--%s does not apply: prt reference traces the scene's materials, "
                             "it relights no .prt", light.have_brdf ? (light.brdf_everywhere ? "brdf-all" : "brdf") : "control");
    int rc = cli_make_context(&c);
    if (rc) return rc;

    const char *input = argv[optind];
    const char *in_ext = strrchr(input, '.');
    prt_scene *scene = NULL;
    prt_transfer *t = NULL;
    prt_lighting *lighting = NULL;
    prt_reference_vertices res = {0};
    prt_image img = {0};
    prt_status st;
    if (in_ext && !strcasecmp(in_ext, ".prt")) {
        /* The baked mesh as it is: no cleaning or subdivision can change the vertex order. */
        st = prt_transfer_load(c.ctx, input, &t);
        if (!st) st = prt_transfer_scene(c.ctx, t, &scene);
    } else {
        /* A room around a --light or the --eye keeps facing inwards. */
        float inside[CLI_MAX_INSIDE_POINTS * 3];
        sd.inside_point_count = cli_inside_points(&light, &view, inside);
        sd.inside_points = inside;
        st = prt_scene_load(c.ctx, input, &sd, &scene);
        /* The scene's camera, unless the command line frames its own. */
        float fov;
        if (!st && !view.have_eye && !view.have_view && prt_scene_camera(scene, view.eye, view.target, &fov)) {
            view.have_eye = view.have_target = true;
            if (!view.have_fov && fov > 0) view.fov = fov, view.have_fov = true;
        }
    }
    for (int i = 0; !st && i < light.paint_count; ++i)
        if ((st = prt_scene_paint_albedo(scene, light.paint[i].name, light.paint[i].rgb))) {
            cli_error(&c, "--albedo-of: %s", prt_last_error());
            c.reported = true;
        }
    /* The scene's lighting, not the baked method's share of it: every light the scene named is
     * traced, whatever the method could relight (cli_lighting with no transfer and no method). */
    if (!st) st = cli_lighting(&c, &light, NULL, scene, &lighting);
    rd.lighting = lighting;
    rd.progress = cli_progress;
    rd.progress_user = &c;
    /* View-dependent surfaces are seen from the camera, as prt relight and compare see them. */
    prt_camera cam;
    float media[CLI_MAX_MEDIA * 6];
    if (!st)
        cli_view_camera_boxes(&c, &view, prt_scene_positions(scene), prt_scene_vertex_count(scene), prt_scene_indices(scene), prt_scene_triangle_count(scene),
                              media, cli_scene_media_boxes(scene, media), (float)view.width / view.height, &cam);
    rd.eye = cam.eye;
    if (!st && output) st = prt_reference_trace_vertices(c.ctx, scene, NULL, &rd, &res);
    if (!st && output) st = cli_check_interrupt(&c);
    if (!st && output) {
        size_t nv = res.vertex_count;
        if (json) {
            cli_vertex_field f[5] = {{"radiance", res.radiance}, {"direct", res.direct}, {"indirect", res.indirect},
                                     {"std_error", res.std_error}, {"std_error_indirect", res.std_error_indirect}};
            st = cli_write_vertex_json(output, "reference", nv, f, 5);
        } else {
            st = cli_write_vertex_ply(output, prt_scene_positions(scene), prt_scene_normals(scene), nv, prt_scene_indices(scene),
                                      prt_scene_triangle_count(scene), res.radiance);
        }
        if (st) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; }
        else if (!c.quiet) {
            long total = 0;
            int lo = res.samples[0], hi = res.samples[0];
            for (size_t v = 0; v < nv; ++v) { total += res.samples[v]; lo = res.samples[v] < lo ? res.samples[v] : lo; hi = res.samples[v] > hi ? res.samples[v] : hi; }
            double err = 0, sum = 0;
            for (size_t i = 0; i < nv * 3; ++i) { err += (double)res.std_error[i] * res.std_error[i]; sum += (double)res.radiance[i] * res.radiance[i]; }
            fprintf(stderr, "prt reference: wrote %s (%zu vertices, %d..%d paths each, %ld in all; relative standard error %.4f)\n", output, nv,
                    lo, hi, total, sum > 0 ? sqrt(err / sum) : 0.0);
        }
    }
    if (!st && !rc && image) {
        st = prt_reference_trace_image(c.ctx, scene, NULL, &rd, &cam, view.width, view.height, view.background, &img, NULL);
        if (!st) st = cli_check_interrupt(&c);
        if (!st) st = prt_image_save(image, &img, &view.save);
        if (!st && !c.quiet) fprintf(stderr, "prt reference: wrote %s\n", image);
    }
    if (st && !rc) rc = cli_fail(&c, st);
    prt_image_free(&img);
    prt_reference_vertices_free(&res);
    prt_lighting_release(lighting);
    prt_scene_release(scene);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}
