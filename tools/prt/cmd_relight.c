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
    "  -o, --output FILE      .glb, .gltf, .ply, .obj or .json; with --texels .exr, .hdr, .pfm or\n"
    "                         .png (required; written atomically)\n"
    "      --colors C         srgb or linear (default: linear for glTF, srgb for PLY and OBJ)\n"
    "      --exposure STOPS   scale radiance by 2^STOPS before clamping colours (default 0)\n"
    "  -k, --kind K           what to relight the file as (prt info lists what it holds);\n"
    "                         default: the richest view-independent one\n"
    "      --eye X,Y,Z        the viewpoint each vertex's colour is seen from; needed when the\n"
    "                         result depends on the view (glossy surfaces)\n"
    "      --texels           write the per-texel radiance map (top row = v 1) instead\n"
    CLI_TIME_HELP
    CLI_LIGHT_OPTIONS_HELP
    "Other:\n"
    "  -j, --threads N        worker threads\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

static const char *HELP_EXPORT_HEAD =
    "usage: prt export FILE.prt -o OUT.glb|.gltf|.ply|.obj [options]\n"
    "       prt export FILE.prt [the method's export options]\n"
    "Hands a baked .prt to other tools as a mesh with its exit radiance under a lighting as\n"
    "vertex colours: glTF 2.0 COLOR_0 (linear, as the format says; three.js, Godot, Unity,\n"
    "Blender read it), or sRGB-encoded colours in PLY and OBJ; otherwise the same as prt relight\n"
    "to a mesh. A method may export more of what its files hold - the transfer itself as glTF\n"
    "attributes, its maps as images - through its own options, listed below by method; they\n"
    "are written before the mesh, and a mesh that cannot be written takes them back.\n\n"
    "  -o, --output FILE      .glb, .gltf, .ply or .obj (written atomically; required unless\n"
    "                         only the method's own files are asked for)\n"
    "      --colors C         srgb or linear (default: linear for glTF, srgb for PLY and OBJ)\n"
    "      --exposure STOPS   scale radiance by 2^STOPS before clamping colours (default 0)\n"
    "  -k, --kind K           what to relight the file as (prt info lists what it holds);\n"
    "                         default: the richest view-independent one\n"
    "      --eye X,Y,Z        the viewpoint each vertex's colour is seen from (glossy surfaces)\n"
    "A web page instead of a mesh (prt export FILE.prt --web DIR): DIR/index.html with its\n"
    "scripts (WebGL2, nothing fetched: it opens from the file system with a double click) that\n"
    "opens at prt render's view of the same options, tone-maps as its PNGs do, and relights\n"
    "live: the environment's rotation and intensity, the method's controls, an orbit camera\n"
    "      --web DIR          write the page into DIR (made when missing)\n"
    "      --eye X,Y,Z --target X,Y,Z  the camera (default: prt render's auto framing)\n"
    "      --view X,Y,Z       direction from the scene centre towards the camera (auto framing)\n"
    "      --fov DEG          vertical field of view (default 40; 70 inside a closed scene)\n"
    "      --width N, --height N  the canvas in pixels (default 800 x 600)\n"
    "      --exposure STOPS, --tonemap reinhard|clamp, --background R,G,B  as prt render\n"
    CLI_LIGHT_OPTIONS_HELP;

static const char *HELP_EXPORT_TAIL =
    "Other:\n"
    "  -j, --threads N        worker threads\n"
    "  -q, --quiet            no messages\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

static void help_export(void)
{
    fputs(HELP_EXPORT_HEAD, stdout);
    for (int i = 0; i < prt_method_count(); ++i)
        cli_print_method_options(stdout, prt_method_at(i), prt_method_export_options, "Export options of %s files:", false);
    fputs(HELP_EXPORT_TAIL, stdout);
}

enum { OPT_EXPORT_OPTION = 3000, OPT_WEB = 2900 };

/* prt export --web DIR: the page, opened at prt render's camera for the same options. */
static int export_web(cli *c, cli_light *light, cli_view *view, const char *dir, const char *path, const char *kind)
{
    int rc = cli_make_context(c);
    if (rc) return rc;
    prt_transfer *t = NULL;
    prt_lighting *lighting = NULL;
    prt_export_result er = {0};
    prt_status st = prt_transfer_load(c->ctx, path, &t);
    int variant = -1, controls[PRT_MAX_CONTROLS], nc = 0;
    if (!st) {
        variant = kind ? prt_transfer_find_variant(t, kind) : prt_transfer_default_variant(t, 0);
        if (variant < 0) rc = cli_usage(c, "%s", prt_last_error());
    }
    if (!st && !rc) st = cli_lighting(c, light, t, NULL, &lighting);
    if (!st && !rc && (nc = cli_controls(c, light, t, controls)) < 0) rc = EXIT_USAGE;
    if (!st && !rc) {
        prt_camera cam;
        cli_view_camera(c, view, prt_transfer_positions(t), prt_transfer_vertex_count(t), prt_transfer_indices(t), prt_transfer_triangle_count(t),
                        (float)view->width / (float)view->height, &cam);
        prt_web_desc w = {.dir = dir, .fov_y_deg = cam.fov_y_deg, .width = view->width, .height = view->height,
                          .exposure_stops = view->save.exposure_stops, .tonemap = view->save.tonemap};
        memcpy(w.eye, cam.eye, sizeof w.eye);
        memcpy(w.target, cam.target, sizeof w.target);
        memcpy(w.up, cam.up, sizeof w.up);
        memcpy(w.background, view->background, sizeof w.background);
        const prt_export_desc d = {.lighting = lighting, .variant = variant, .controls = nc > 0 ? controls : NULL, .source = path};
        st = prt_transfer_export_web(c->ctx, t, &d, &w, &er);
        if (st == PRT_ERR_INVALID_ARG) { rc = cli_usage(c, "%s", prt_last_error()); st = PRT_OK; }
        if (!st && !rc && !c->quiet) cli_print_lines(stderr, "prt export: ", er.report);
    }
    if (st && !rc) rc = cli_fail(c, st);
    prt_export_result_free(&er);
    prt_lighting_release(lighting);
    prt_transfer_release(t);
    prt_context_release(c->ctx);
    return rc;
}

/* The method's export options as given, checked against the file's method; PRT_ERR_INVALID_ARG
 * after saying why when one is not its method's. */
static prt_status export_options(cli *c, const prt_transfer *t, int count, const char *const *names, char *const *values, prt_options **out)
{
    *out = NULL;
    if (!count) return PRT_OK;
    prt_status st = prt_export_options_create(prt_transfer_method(t), out);
    for (int i = 0; i < count && !st; ++i)
        if ((st = prt_options_set(*out, names[i], values[i]))) cli_usage(c, "%s", prt_last_error());
    if (st) { prt_options_release(*out); *out = NULL; c->reported = true; }
    return st;
}

/* Runs the method's export; the error is printed (one line) and mapped to an exit code. What it
 * wrote is said once the mesh (if any) is written too. */
static int run_export(cli *c, const prt_transfer *t, const prt_export_desc *d, prt_export_result *r)
{
    prt_status st = prt_transfer_export(c->ctx, t, d, r);
    if (st == PRT_ERR_INVALID_ARG) return cli_usage(c, "%s", prt_last_error());
    return st ? cli_fail(c, st) : EXIT_OK;
}

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

static int relight_main(int argc, char **argv, bool exporting)
{
    cli c = {.cmd = exporting ? "export" : "relight"};
    cli_light light = {.intensity = 1.0f};
    const char *output = NULL, *kind = NULL;
    static const struct option fixed[] = {{"output", required_argument, 0, 'o'}, {"kind", required_argument, 0, 'k'},
                                          {"eye", required_argument, 0, 'e'}, {"texels", no_argument, 0, 'T'}, CLI_LIGHT_LONG_OPTIONS,
                                          {"time", required_argument, 0, OPT_TIME},
                                          {"colors", required_argument, 0, 'C'}, {"exposure", required_argument, 0, 'E'},
                                          {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'},
                                          {"web", required_argument, 0, OPT_WEB}, {"target", required_argument, 0, OPT_TARGET},
                                          {"view", required_argument, 0, OPT_VIEW}, {"fov", required_argument, 0, OPT_FOV},
                                          {"width", required_argument, 0, OPT_WIDTH}, {"height", required_argument, 0, OPT_HEIGHT},
                                          {"tonemap", required_argument, 0, OPT_TONEMAP}, {"background", required_argument, 0, OPT_BACKGROUND}};
    /* Every method's export options are parsed, here and in relight (where each is refused by
     * name), and checked against the file's method once it is loaded. */
    struct option opts[128];
    const char *names[64];
    int n = 0;
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; ++i) opts[n++] = fixed[i];
    cli_collect_method_options(NULL, prt_method_export_options, opts, n, 128, names, 64, OPT_EXPORT_OPTION);
    const char *given_names[64];
    char *given_values[64];
    int given = 0;
    int opt;
    float eye[3] = {0, 0, 0};
    bool have_eye = false, texels = false, timed = false;
    double time = 0;
    prt_colour_encoding encoding = PRT_COLOURS_DEFAULT;
    float exposure = 0;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    const char *web = NULL;
    cli_view view = CLI_VIEW_DEFAULTS;
    bool have_view_option = false;
    while ((opt = getopt_long(argc, argv, ":o:k:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        if (opt == OPT_WEB) { web = optarg; continue; }
        if ((r = cli_view_option(&c, &view, opt, optarg)) < 0) return EXIT_USAGE;
        if (r) { have_view_option = true; continue; }
        if (opt >= OPT_EXPORT_OPTION) {
            const char *name = names[opt - OPT_EXPORT_OPTION];
            if (!exporting) return cli_usage(&c, "--%s belongs to prt export", name);
            if (given == 64) return cli_usage(&c, "too many export options");
            given_names[given] = name;
            given_values[given++] = optarg;
            continue;
        }
        switch (opt) {
        case 'o': output = optarg; break;
        case 'k': kind = optarg; break;
        case 'T': texels = true; break;
        case OPT_TIME:
            if (!cli_parse_time(&c, optarg, &time)) return EXIT_USAGE;
            timed = true;
            break;
        case 'C':
            if (!strcasecmp(optarg, "srgb")) encoding = PRT_COLOURS_SRGB;
            else if (!strcasecmp(optarg, "linear")) encoding = PRT_COLOURS_LINEAR;
            else return cli_usage(&c, "--colors must be srgb or linear");
            break;
        case 'E': if (!cli_parse_float(optarg, &exposure) || fabsf(exposure) > 64) return cli_usage(&c, "--exposure takes stops in [-64, 64]"); break;
        case 'e': if (!cli_parse_vec3(optarg, false, eye)) return cli_usage(&c, "--eye takes X,Y,Z"); have_eye = true; break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h':
            if (exporting) help_export();
            else fputs(HELP, stdout);
            return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    if (web) {
        if (!exporting) return cli_usage(&c, "--web belongs to prt export");
        if (output || given || texels || encoding) return cli_usage(&c, "--web writes a page: leave out -o, --texels, --colors and the method's export options");
        if (have_eye != view.have_target) return cli_usage(&c, "with --web, --eye and --target go together (the camera)");
        if (have_eye) { memcpy(view.eye, eye, sizeof eye); view.have_eye = true; }
        view.save.exposure_stops = exposure;
        return export_web(&c, &light, &view, web, argv[optind], kind);
    }
    if (have_view_option) return cli_usage(&c, "--target, --view, --fov, --width, --height, --tonemap and --background go with --web");
    if (given && !output) {   /* only the method's own files */
        int rc = cli_make_context(&c);
        if (rc) return rc;
        prt_transfer *t = NULL;
        prt_options *eo = NULL;
        prt_export_result er = {0};
        prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
        if (st) rc = cli_fail(&c, st);
        else if (export_options(&c, t, given, given_names, given_values, &eo)) rc = EXIT_USAGE;
        else {
            const prt_export_desc d = {.options = eo, .variant = -1, .mesh = PRT_EXPORT_NO_MESH, .source = argv[optind]};
            rc = run_export(&c, t, &d, &er);
            if (!rc && !c.quiet) cli_print_lines(stderr, "prt export: ", er.report);
        }
        prt_export_result_free(&er);
        prt_options_release(eo);
        prt_transfer_release(t);
        prt_context_release(c.ctx);
        return rc;
    }
    if (!output) return cli_usage(&c, "an output file is required (-o OUT.glb, .gltf, .ply, .obj or .json)");
    const char *ext = strrchr(output, '.');
    bool json = ext && !strcasecmp(ext, ".json");
    const bool ply = ext && !strcasecmp(ext, ".ply"),
               mesh = ext && (ply || !strcasecmp(ext, ".glb") || !strcasecmp(ext, ".gltf") || !strcasecmp(ext, ".obj"));
    if (exporting && (texels || json)) return cli_usage(&c, "prt export writes meshes (.glb .gltf .ply .obj): prt relight writes %s", texels ? "texel maps" : "JSON");
    const bool gltf_out = ext && (!strcasecmp(ext, ".glb") || !strcasecmp(ext, ".gltf"));
    if (!texels && !json && !mesh) return cli_usage(&c, "output must end in .glb, .gltf, .ply, .obj or .json");
    if (texels && (json || mesh)) return cli_usage(&c, "--texels writes an image: .exr, .hdr, .pfm or .png");
    if (texels && have_eye) return cli_usage(&c, "--eye applies to per-vertex results seen from a viewpoint, not to --texels maps");
    if ((encoding || exposure != 0) && !mesh) return cli_usage(&c, "--colors and --exposure apply to mesh outputs (.glb .gltf .ply .obj)");
    int rc = cli_make_context(&c);
    if (rc) return rc;
    prt_transfer *t = NULL;
    prt_lighting *lighting = NULL;
    prt_options *eo = NULL;
    prt_export_result er = {0};
    prt_relit r;
    memset(&r, 0, sizeof r);
    float *rgb = NULL;
    int variant = -1;
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &t);
    if (!st && timed) st = cli_at_time(&c, argv[optind], time, &t);
    /* Export options are checked before anything is written. */
    if (!st && export_options(&c, t, given, given_names, given_values, &eo)) rc = EXIT_USAGE;
    if (!st && !rc) {
        variant = kind ? prt_transfer_find_variant(t, kind) : prt_transfer_default_variant(t, 0);
        if (variant < 0) rc = cli_usage(&c, "%s", prt_last_error());
    }
    if (!st && !rc) st = cli_lighting(&c, &light, t, NULL, &lighting);
    light.whole_texels = texels;   /* the map is the picture: no renderer adds lights to it */
    if (!st && !rc) st = cli_relight(&c, t, lighting, &light, variant, !texels, json && !texels, &r);
    if (!st && !rc) st = cli_check_interrupt(&c);
    if (!st && !rc && texels) {
        if (!r.texels) {
            const char *map = prt_method_light_map_option(prt_transfer_method(t));
            cli_error(&c, "'%s' has no per-texel %s transfer%s%s%s", argv[optind], prt_transfer_variant_name(t, variant), map ? " (bake with --" : "",
                      map ? map : "", map ? " N)" : "");
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
        if (!rc && !st && exporting) {
            /* The method's own files first: a mesh whose companions could not be written is not
             * left behind, and one that cannot be written takes them back. */
            int controls[PRT_MAX_CONTROLS];
            const int nc = light.control_count ? cli_controls(&c, &light, t, controls) : 0;
            if (nc < 0) rc = EXIT_USAGE;
            const prt_export_desc d = {.options = eo, .lighting = lighting, .variant = variant, .controls = nc > 0 ? controls : NULL,
                                       .mesh = gltf_out ? PRT_EXPORT_MESH_GLTF : PRT_EXPORT_MESH_OTHER, .source = argv[optind]};
            if (!rc) rc = run_export(&c, t, &d, &er);
            if (!rc && er.radiance) memcpy(rgb, er.radiance, nv * 3 * sizeof(float));
        }
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
                    dd.brdf_everywhere = light.brdf_everywhere;
                    dd.leave_out_unreachable = !light.set_lights;
                    float *albedo = NULL, *painting = NULL;
                    int *brdf_of = NULL;
                    prt_relit rd;
                    if (nc >= 0 && !cli_brdf_choice(&c, &light, t, &brdf_of) && !cli_painted_albedo_for(&c, &light, t, brdf_of, &albedo) &&
                        !cli_painting(&c, &light, t, &dd, &painting) &&
                        (dd.albedo = albedo, dd.brdf_of = brdf_of, !prt_relight(c.ctx, t, lighting, &dd, &rd))) {
                        if ((direct = malloc(nv * 3 * sizeof(float))) && prt_relit_shade(c.ctx, t, &rd, eye, direct)) { free(direct); direct = NULL; }
                        prt_relit_free(&rd);
                    }
                    free(albedo);
                    free(painting);
                    free(brdf_of);
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
                                                 prt_transfer_triangle_count(t), rgb, encoding, exposure, er.attribute_count, er.attributes,
                                                 er.attribute_names};
                if ((st = prt_mesh_export(output, &ed))) {
                    cli_error(&c, "%s", prt_last_error());
                    rc = EXIT_FAILURE_INPUT;
                    st = PRT_OK;
                }
            }
            if (st) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; st = PRT_OK; }
            else if (!rc && !c.quiet) {
                fprintf(stderr, "prt %s: wrote %s (%s, %zu vertices%s)\n", c.cmd, output, prt_transfer_variant_name(t, variant), nv,
                        er.attribute_count ? ", with the method's attributes" : "");
                cli_print_lines(stderr, "prt export: ", er.report);
            }
            if (rc)
                for (int i = 0; i < er.file_count; ++i) remove(er.files[i]);
        }
    }
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    prt_export_result_free(&er);
    prt_options_release(eo);
    prt_relit_free(&r);
    prt_lighting_release(lighting);
    prt_transfer_release(t);
    prt_context_release(c.ctx);
    return rc;
}

int cmd_relight(int argc, char **argv) { return relight_main(argc, argv, false); }
int cmd_export(int argc, char **argv) { return relight_main(argc, argv, true); }
