#include "cli.h"

#include <cjson/cJSON.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *HELP =
    "usage: prt compare A B [options]\n"
    "Measures how far result A is from B (the reference). Both are per-vertex results - a .prt\n"
    "(relit under the lighting options), the JSON of prt relight or prt reference - or both are\n"
    "images (.exr .hdr .pfm .png). Metrics over every channel of every vertex or pixel: RMSE,\n"
    "relative L2 (||A - B|| / ||B||), mean and max absolute error, PSNR for images (peak = max B),\n"
    "and for a reference with error bars the reference's own relative noise.\n\n"
    "  -k, --kind K           what to relight .prt inputs as (default: the richest\n"
    "                         view-independent one, as prt relight)\n"
    "      --indirect         compare only light that bounced at least once (a .prt's\n"
    "                         indirect part where its method separates it; a reference's\n"
    "                         \"indirect\")\n"
    "      --json FILE        also write the metrics as JSON ('-' for standard output)\n"
    "      --error-image FILE false-colour |A - B| (blue = 0 ... red = scale); for per-vertex\n"
    "                         results drawn on the mesh of the .prt input (needs one)\n"
    "      --error-scale S    error shown as red (default: the largest error)\n"
    "Error image camera (per-vertex results):\n"
    CLI_VIEW_WIDTH_HELP CLI_VIEW_CAMERA_HELP CLI_VIEW_BACKGROUND_HELP CLI_LIGHT_OPTIONS_HELP
    "Other:\n"
    "  -q, --quiet            print nothing but errors (and --json -)\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

enum { OPT_INDIRECT = 2300, OPT_JSON, OPT_ERROR_IMAGE, OPT_ERROR_SCALE };

typedef struct metrics { double rmse, rel_l2, mean_abs, max_abs, psnr, noise_rel; size_t count; } metrics;

static metrics measure(const float *a, const float *b, const float *b_err, size_t n)
{
    metrics m = {0};
    double se = 0, sb = 0, sa = 0, noise = 0, peak = 0;
    for (size_t i = 0; i < n; ++i) {
        double d = (double)a[i] - b[i];
        se += d * d;
        sb += (double)b[i] * b[i];
        sa += fabs(d);
        m.max_abs = fmax(m.max_abs, fabs(d));
        peak = fmax(peak, b[i]);
        if (b_err) noise += (double)b_err[i] * b_err[i];
    }
    m.count = n;
    m.rmse = sqrt(se / (double)n);
    m.rel_l2 = sb > 0 ? sqrt(se / sb) : INFINITY;
    m.mean_abs = sa / (double)n;
    m.psnr = se > 0 && peak > 0 ? 20.0 * log10(peak / m.rmse) : INFINITY;
    m.noise_rel = b_err && sb > 0 ? sqrt(noise / sb) : NAN;
    return m;
}

/* Blue, cyan, green, yellow, red. */
static void false_colour(float t, float rgb[3])
{
    static const float stops[5][3] = {{0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
    t = fminf(fmaxf(t, 0.0f), 1.0f) * 4.0f;
    int i = (int)fminf(t, 3.0f);
    float f = t - (float)i;
    for (int c = 0; c < 3; ++c) rgb[c] = stops[i][c] + (stops[i + 1][c] - stops[i][c]) * f;
}

int cmd_compare(int argc, char **argv)
{
    cli c = {.cmd = "compare"};
    cli_light light = {.intensity = 1.0f};
    cli_view view = CLI_VIEW_DEFAULTS;
    const char *kind_name = NULL, *json = NULL, *error_image = NULL;
    bool indirect = false;
    float scale = 0;
    static const struct option opts[] = {
        {"kind", required_argument, 0, 'k'}, {"indirect", no_argument, 0, OPT_INDIRECT}, {"json", required_argument, 0, OPT_JSON},
        {"error-image", required_argument, 0, OPT_ERROR_IMAGE}, {"error-scale", required_argument, 0, OPT_ERROR_SCALE},
        CLI_VIEW_LONG_OPTIONS, CLI_LIGHT_LONG_OPTIONS, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":k:qh", opts, NULL)) != -1) {
        /* The error image's colours are exact: nothing to expose or tone map. */
        if (opt == OPT_EXPOSURE || opt == OPT_TONEMAP)
            return cli_usage(&c, "--%s does not apply: the error image's colours are exact",
                             opt == OPT_EXPOSURE ? "exposure" : "tonemap");
        int r = cli_light_option(&c, &light, opt, optarg);
        if (!r) r = cli_view_option(&c, &view, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'k': kind_name = optarg; break;
        case OPT_INDIRECT: indirect = true; break;
        case OPT_JSON: json = optarg; break;
        case OPT_ERROR_IMAGE: error_image = optarg; break;
        case OPT_ERROR_SCALE: if (!cli_parse_float(optarg, &scale) || scale <= 0) return cli_usage(&c, "--error-scale must be > 0"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind != argc - 2) return cli_usage(&c, "expected two results, A and B (the reference)");
    if (view.have_eye != view.have_target) return cli_usage(&c, "--eye and --target go together");
    int rc = cli_make_context(&c);
    if (rc) return rc;
    cli_result a, b;
    memset(&b, 0, sizeof b);
    prt_status st = cli_result_load(&c, argv[optind], &light, kind_name, &a);
    if (!st) st = cli_result_load(&c, argv[optind + 1], &light, kind_name, &b);
    if (st) { cli_result_free(&a); prt_context_release(c.ctx); return cli_exit_code(st); }

    const float *va = NULL, *vb = NULL, *eb = NULL;
    size_t n = 0;
    if (a.image != b.image) {
        cli_error(&c, "cannot compare an image with a per-vertex result");
        rc = EXIT_USAGE;
    } else if (a.image) {
        if (a.img.width != b.img.width || a.img.height != b.img.height) {
            cli_error(&c, "image sizes differ: %dx%d and %dx%d", a.img.width, a.img.height, b.img.width, b.img.height);
            rc = EXIT_FAILURE_INPUT;
        } else if (indirect) {
            cli_error(&c, "images hold no separate indirect component");
            rc = EXIT_USAGE;
        }
        va = a.img.rgb; vb = b.img.rgb;
        n = (size_t)a.img.width * a.img.height * 3;
    } else {
        if (a.nv != b.nv) {
            cli_error(&c, "vertex counts differ: %zu and %zu (compare results on the same baked mesh: prt reference FILE.prt)", a.nv, b.nv);
            rc = EXIT_FAILURE_INPUT;
        } else if (indirect && (!a.indirect || !b.indirect)) {
            cli_error(&c, "--indirect needs both results to separate it ('%s' does not)", !a.indirect ? a.what : b.what);
            rc = EXIT_USAGE;
        }
        va = indirect ? a.indirect : a.radiance;
        vb = indirect ? b.indirect : b.radiance;
        eb = indirect ? b.std_error_indirect : b.std_error;
        n = a.nv * 3;
    }
    metrics m = {0};
    if (!rc && cli_check_interrupt(&c)) rc = EXIT_INTERRUPTED;
    if (!rc) {
        m = measure(va, vb, eb, n);
        if (!c.quiet) {
            printf("A: %s\nB: %s%s\n", a.what, b.what, indirect ? "  (indirect only)" : "");
            printf("%s: %zu values\n", a.image ? "pixels" : "vertices", n / 3);
            printf("RMSE         %.6g\nrelative L2  %.6g\nmean |A-B|   %.6g\nmax |A-B|    %.6g\n", m.rmse, m.rel_l2, m.mean_abs, m.max_abs);
            if (a.image) printf("PSNR         %.2f dB\n", m.psnr);
            if (!isnan(m.noise_rel)) printf("B's own relative noise %.6g\nrelative L2 above B's noise %.6g\n", m.noise_rel, cli_rel_l2_above_noise(va, vb, eb, n));
        }
        if (json) {
            cJSON *root = cJSON_CreateObject();
            cJSON_AddStringToObject(root, "a", a.what);
            cJSON_AddStringToObject(root, "b", b.what);
            cJSON_AddStringToObject(root, "domain", a.image ? "pixels" : "vertices");
            cJSON_AddBoolToObject(root, "indirect_only", indirect);
            cJSON_AddNumberToObject(root, "count", (double)(n / 3));
            cJSON_AddNumberToObject(root, "rmse", m.rmse);
            cJSON_AddNumberToObject(root, "relative_l2", m.rel_l2);
            cJSON_AddNumberToObject(root, "mean_abs", m.mean_abs);
            cJSON_AddNumberToObject(root, "max_abs", m.max_abs);
            if (a.image && isfinite(m.psnr)) cJSON_AddNumberToObject(root, "psnr_db", m.psnr);
            if (!isnan(m.noise_rel)) {
                cJSON_AddNumberToObject(root, "reference_relative_noise", m.noise_rel);
                cJSON_AddNumberToObject(root, "relative_l2_above_noise", cli_rel_l2_above_noise(va, vb, eb, n));
            }
            char *text = cJSON_Print(root);
            cJSON_Delete(root);
            FILE *f = strcmp(json, "-") ? fopen(json, "w") : stdout;
            if (!f || fprintf(f, "%s\n", text) < 0 || (f != stdout && fclose(f) != 0)) {
                cli_error(&c, "cannot write '%s'", json);
                rc = EXIT_FAILURE_INPUT;
            }
            cJSON_free(text);
        }
    }
    if (!rc && error_image) {
        float top = scale > 0 ? (float)scale : (float)m.max_abs;
        if (!(top > 0)) top = 1;
        size_t count = n / 3;
        float *err = malloc(count * 3 * sizeof(float));
        for (size_t i = 0; i < count && err; ++i) {
            float e = fmaxf(fabsf(va[i * 3] - vb[i * 3]), fmaxf(fabsf(va[i * 3 + 1] - vb[i * 3 + 1]), fabsf(va[i * 3 + 2] - vb[i * 3 + 2])));
            false_colour(e / top, err + i * 3);
        }
        prt_image out = {0};
        prt_image_save_desc sd = {0, 2};   /* the colours are exact: clamp, no tone curve */
        if (!err) st = PRT_ERR_NO_MEMORY;
        else if (a.image) {
            out.width = a.img.width; out.height = a.img.height; out.rgb = err; err = NULL;
        } else {
            const prt_transfer *t = a.transfer ? a.transfer : b.transfer;
            if (!t) {
                cli_error(&c, "--error-image for per-vertex results needs a .prt input to draw on");
                rc = EXIT_USAGE;
            } else {
                prt_renderer *r = NULL;
                prt_camera cam;
                cli_view_camera(&c, &view, prt_transfer_positions(t), prt_transfer_vertex_count(t), prt_transfer_indices(t), prt_transfer_triangle_count(t),
                                (float)view.width / view.height, &cam);
                st = prt_renderer_create(c.ctx, &(prt_renderer_desc){view.width, view.height, 0}, &r);
                prt_render_mesh mesh = {.positions = prt_transfer_positions(t), .radiance = err, .vertex_count = prt_transfer_vertex_count(t),
                                        .indices = prt_transfer_indices(t), .triangle_count = prt_transfer_triangle_count(t)};
                if (!st) st = prt_render(r, &mesh, &cam, view.background, &out);
                prt_renderer_release(r);
            }
        }
        if (!st && !rc) st = prt_image_save(error_image, &out, &sd);
        if (st) rc = cli_fail(&c, st);
        else if (!rc && !c.quiet) printf("error image  %s (red = %.4g)\n", error_image, top);
        free(err);
        prt_image_free(&out);
    }
    cli_result_free(&a);
    cli_result_free(&b);
    prt_context_release(c.ctx);
    return rc;
}
