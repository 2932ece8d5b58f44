#include "cli.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

static const char *HELP =
    "usage: prt sweep SCENE --reference REF.json -o OUT.csv [--plot OUT.png] [options]\n"
    "       prt sweep --method all SCENE [--json FILE] [--plot PREFIX] [options]   (every method:\n"
    "       see below; prt pick SCENE is the same)\n"
    "Bakes SCENE once per value of one bake option of a method, relights every kind each file\n"
    "holds under the lighting, and measures the per-vertex error against a reference computed\n"
    "on the same scene (prt reference SCENE -o REF.json with the same scene and lighting\n"
    "options). Writes one CSV row per value and kind, and with --plot a PNG of error and storage\n"
    "against the parameter (gnuplot).\n\n"
    "  -o, --output FILE      the CSV (required): param,value,kind,rmse,relative_l2,max_abs,\n"
    "                         bytes_per_vertex,bake_seconds,relative_l2_above_noise (the error\n"
    "                         with the reference's own noise taken out, when it has error bars)\n"
    "      --reference FILE   per-vertex reference JSON (required)\n"
    "      --plot FILE        PNG plot of relative L2 error and bytes per vertex\n"
    "      --method M         the method to bake with (default: the first prt bake --help lists)\n"
    "      --param P          an integer bake option of the method (or a choice one, with\n"
    "                         --values) to sweep (default: its first integer one); e.g. order,\n"
    "                         samples, bounces, clusters, vectors\n"
    "      --values LIST      comma list (default: every value of small ranges, else powers of two)\n"
    "      --indirect         compare only the indirect light (where the method separates it)\n"
    "      any bake option of the method (prt bake --method M --help) fixes what is not swept\n"
    "      (except --brdf, which is the run-time lobe here, as in prt relight), for example\n"
    "      --samples 512\n"
    CLI_LIGHT_HEADER_HELP CLI_LIGHT_SOURCES_HELP
    "  --brdf SPEC           run-time reflection lobe for glossy sets, as in prt relight:\n"
    "                        phong:N[:KS] or blinn:N[:KS] (default: the scene's materials)\n"
    CLI_LIGHT_PAINT_HELP CLI_LIGHT_CONTROL_HELP
    "Scene:\n" CLI_SCENE_FILE_HELP
    "Other:\n"
    "  -j, --threads N        worker threads\n"
    CLI_PROGRESS_HELP
    "  -q, --quiet            no progress or messages\n"
    "  -h, --help             this text\n\n";

enum { OPT_REFERENCE = 2400, OPT_PLOT, OPT_PARAM, OPT_VALUES, OPT_INDIRECT_ONLY, OPT_METHOD, OPT_METHOD_OPTION = 3000 };

#define MAX_VARIANTS 16

static prt_status plot(const cli *c, const char *csv, const char *png, const char *param, char names[][64], int nnames, bool indirect)
{
    char script[1100];
    snprintf(script, sizeof script, "%s.gp", png);
    FILE *f = fopen(script, "w");
    if (!f) return PRT_ERR_IO;
    fprintf(f, "set terminal pngcairo size 900,560 font ',11'\nset output '%s'\nset datafile separator ','\n", png);
    fprintf(f, "set title 'prt sweep: %s error against the reference'\nset xlabel '%s'\nset ylabel 'relative L2 error'\n", indirect ? "indirect" : "radiance", param);
    fprintf(f, "set logscale y\nset y2label 'bytes per vertex'\nset y2tics\nset ytics nomirror\nset grid\nset key outside right\n");
    fprintf(f, "plot ");
    for (int k = 0; k < nnames; ++k) {
        /* One series per kind: gnuplot joins points only within consecutive rows. */
        fprintf(f, "%s'< grep \",%s,\" \"%s\"' using 2:5 with linespoints lw 2 title '%s error', "
                   "'< grep \",%s,\" \"%s\"' using 2:7 axes x1y2 with lines dt 2 title '%s bytes'",
                k ? ", " : "", names[k], csv, names[k], names[k], csv, names[k]);
    }
    fprintf(f, "\n");
    fclose(f);
    if (!cli_run_gnuplot(c, script)) {
        cli_error(c, "gnuplot failed (is gnuplot-nox installed? scripts/setup-deps.sh installs it); the CSV is written");
        return PRT_ERR_BACKEND;
    }
    return PRT_OK;
}

/* The default values of an option: every value of a small range, else powers of two. */
static int default_values(const prt_option_desc *d, int *list, int max)
{
    int n = 0;
    const double lo = d->min, hi = d->max;
    if (hi - lo <= 15) {
        for (double v = lo; v <= hi && n < max; v += 1) list[n++] = (int)v;
        return n;
    }
    double v = 1;
    while (v < lo) v *= 2;
    for (; v <= hi && n < 7 && n < max; v *= 2) list[n++] = (int)v;
    return n;
}

int cmd_sweep(int argc, char **argv)
{
    cli c = {.cmd = "sweep"};
    cli_light light = {.intensity = 1.0f};
    prt_scene_desc sd = {0};
    const char *output = NULL, *reference = NULL, *plot_path = NULL, *param = NULL, *values = NULL;
    bool indirect = false;
    if (cli_sweep_all_asked(argc, argv)) return cmd_sweep_all("sweep", argc, argv);
    const prt_method *method = cli_method_from_argv(&c, argc, argv);
    if (!method) return EXIT_USAGE;
    const prt_option_desc *mo;
    const int nmo = prt_method_options(method, &mo);
    struct option opts[128];
    int n = 0;
    static const struct option fixed[] = {
        {"output", required_argument, 0, 'o'}, {"reference", required_argument, 0, OPT_REFERENCE}, {"plot", required_argument, 0, OPT_PLOT},
        {"param", required_argument, 0, OPT_PARAM}, {"values", required_argument, 0, OPT_VALUES}, {"indirect", no_argument, 0, OPT_INDIRECT_ONLY},
        {"method", required_argument, 0, OPT_METHOD}, CLI_LIGHT_LONG_OPTIONS, CLI_SCENE_LONG_OPTIONS, {"threads", required_argument, 0, 'j'},
        {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; ++i) opts[n++] = fixed[i];
    for (int i = 0; i < nmo && n < 127; ++i)
        if (strcmp(mo[i].name, "brdf"))   /* --brdf is the lighting's (run-time lobe) here, as in relight */
            opts[n++] = (struct option){mo[i].name, mo[i].type == PRT_OPTION_FLAG ? no_argument : required_argument, 0, OPT_METHOD_OPTION + i};
    opts[n] = (struct option){0, 0, 0, 0};
    prt_options *fixed_opts = NULL;
    if (prt_options_create(method, &fixed_opts)) return cli_fail(&c, PRT_ERR_NO_MEMORY);
    int opt, rc = EXIT_OK;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while (!rc && (opt = getopt_long(argc, argv, ":o:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (!r) r = cli_scene_option(&c, &sd, opt, optarg);
        if (r < 0) { rc = EXIT_USAGE; break; }
        if (r) continue;
        if (opt >= OPT_METHOD_OPTION) {
            if (prt_options_set(fixed_opts, mo[opt - OPT_METHOD_OPTION].name, optarg)) rc = cli_usage(&c, "%s", prt_last_error());
            continue;
        }
        switch (opt) {
        case 'o': output = optarg; break;
        case OPT_REFERENCE: reference = optarg; break;
        case OPT_PLOT: plot_path = optarg; break;
        case OPT_PARAM: param = optarg; break;
        case OPT_VALUES: values = optarg; break;
        case OPT_INDIRECT_ONLY: indirect = true; break;
        case OPT_METHOD:
            if (prt_method_find(optarg) != method) rc = cli_usage(&c, "give the method as --method %s (or --method=%s)", optarg, optarg);
            break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) rc = cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h':
            fputs(HELP, stdout);
            fputs(cli_sweep_all_help, stdout);
            fputs("\n" EXIT_CODES_HELP, stdout);
            prt_options_release(fixed_opts);
            return EXIT_OK;
        default: rc = cli_bad_option(&c, opt, argv, opts); break;
        }
    }
    const prt_option_desc *pd = NULL;
    if (!rc && param) {
        pd = prt_method_option(method, param);
        if (!pd || (pd->type != PRT_OPTION_INT && pd->type != PRT_OPTION_CHOICE))
            rc = cli_usage(&c, "--param must name an integer (or, with --values, a choice) bake "
                               "option of method %s (prt bake --method %s --help)",
                           prt_method_name(method), prt_method_name(method));
    } else if (!rc) {
        for (int i = 0; i < nmo && !pd; ++i)
            if (mo[i].type == PRT_OPTION_INT) pd = &mo[i];
        if (!pd) rc = cli_usage(&c, "method %s has no integer option to sweep", prt_method_name(method));
    }
    if (!rc && optind != argc - 1) rc = cli_usage(&c, "expected exactly one SCENE argument");
    if (!rc && (!output || !reference)) rc = cli_usage(&c, "-o OUT.csv and --reference REF.json are required");
    char list_text[64][32];
    int nvalues = 0;
    if (!rc && values) {
        char buf[512], *save = NULL;
        snprintf(buf, sizeof buf, "%s", values);
        for (char *tok = strtok_r(buf, ",", &save); tok && !rc; tok = strtok_r(NULL, ",", &save)) {
            if (nvalues == 64) { rc = cli_usage(&c, "--values takes at most 64 values"); break; }
            prt_options *probe = NULL;
            prt_options_create(method, &probe);
            if (prt_options_set(probe, pd->name, tok)) rc = cli_usage(&c, "--values: %s", prt_last_error());
            prt_options_release(probe);
            snprintf(list_text[nvalues++], sizeof list_text[0], "%s", tok);
        }
    } else if (!rc) {
        int list[64];
        int count = pd->type == PRT_OPTION_INT ? default_values(pd, list, 64) : 0;
        for (int i = 0; i < count; ++i) snprintf(list_text[nvalues++], sizeof list_text[0], "%d", list[i]);
        if (!nvalues) rc = cli_usage(&c, "give --values for --param %s", pd->name);
    }
    if (!rc) rc = cli_make_context(&c);
    if (rc) { prt_options_release(fixed_opts); return rc; }
    cli_result ref;
    prt_status st = cli_result_load(&c, reference, &light, NULL, &ref);
    if (st) { prt_options_release(fixed_opts); prt_context_release(c.ctx); return cli_exit_code(st); }
    if (ref.image || (indirect && !ref.indirect)) {
        cli_error(&c, "'%s' must be a per-vertex reference%s", reference, indirect ? " with an \"indirect\" field" : "");
        cli_result_free(&ref);
        prt_options_release(fixed_opts);
        prt_context_release(c.ctx);
        return EXIT_USAGE;
    }
    prt_scene *scene = NULL;
    prt_lighting *lighting = NULL;
    float inside[CLI_MAX_INSIDE_POINTS * 3];   /* a room around a --light keeps facing in, as prt reference sees it */
    sd.inside_point_count = cli_inside_points(&light, NULL, inside);
    sd.inside_points = inside;
    st = prt_scene_load(c.ctx, argv[optind], &sd, &scene);
    if (!st && prt_scene_vertex_count(scene) != ref.nv) {
        cli_error(&c, "the scene has %zu vertices, the reference %zu: compute it from the same scene with the same options", prt_scene_vertex_count(scene), ref.nv);
        rc = EXIT_FAILURE_INPUT;
    }
    light.method = method;
    if (!st && !rc) st = cli_lighting(&c, &light, NULL, scene, &lighting);
    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld", output, (long)getpid());
    FILE *csv = !st && !rc ? fopen(tmp, "w") : NULL;
    if (!st && !rc && !csv) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; }
    if (csv) fprintf(csv, "param,value,kind,rmse,relative_l2,max_abs,bytes_per_vertex,bake_seconds,relative_l2_above_noise\n");
    const float *ref_err = indirect ? ref.std_error_indirect : ref.std_error;
    float *rgb = !st && !rc ? malloc(ref.nv * 3 * sizeof(float)) : NULL;
    size_t rgb_vertices = ref.nv;
    if (!st && !rc && !rgb) st = PRT_ERR_NO_MEMORY;
    char names[MAX_VARIANTS][64];
    int nnames = 0;
    for (int i = 0; i < nvalues && !st && !rc; ++i) {
        prt_options *o = NULL;
        if ((st = prt_options_create(method, &o))) break;
        for (int k = 0; k < nmo && !st; ++k)
            if (prt_options_get(fixed_opts, mo[k].name) && strcmp(mo[k].name, pd->name))
                st = prt_options_set(o, mo[k].name, mo[k].type == PRT_OPTION_FLAG ? NULL : prt_options_get(fixed_opts, mo[k].name));
        if (!st) st = prt_options_set(o, pd->name, list_text[i]);
        prt_transfer *t = NULL;
        prt_bake_run_desc run = {.progress = cli_progress, .progress_user = &c};
        if (!st) st = prt_bake(c.ctx, scene, method, o, &run, &t);
        prt_options_release(o);
        if (st) break;
        /* A generated UV atlas appends copies of seam vertices after the scene's own, which
         * keep their order: compare those, from a buffer sized for all. */
        const size_t tnv = prt_transfer_vertex_count(t);
        if (tnv < ref.nv) {
            cli_error(&c, "the bake has %zu vertices, the reference %zu", tnv, ref.nv);
            rc = EXIT_FAILURE_INPUT;
            prt_transfer_release(t);
            break;
        }
        if (tnv > rgb_vertices) {
            float *grown = realloc(rgb, tnv * 3 * sizeof(float));
            if (!grown) { st = PRT_ERR_NO_MEMORY; prt_transfer_release(t); break; }
            rgb = grown;
            rgb_vertices = tnv;
        }
        const double bytes = (double)prt_transfer_bytes(t) / (double)ref.nv;
        for (int v = 0; v < prt_transfer_variant_count(t) && !st; ++v) {
            prt_relit r;
            if ((st = cli_relight(&c, t, lighting, &light, v, true, indirect, &r))) break;
            if (indirect && !r.indirect) { prt_relit_free(&r); continue; }   /* this kind holds no bounced light of its own */
            cli_view view = CLI_VIEW_DEFAULTS;
            prt_camera cam;
            cli_view_camera(&c, &view, prt_scene_positions(scene), ref.nv, prt_scene_indices(scene), prt_scene_triangle_count(scene), (float)view.width / view.height, &cam);
            st = prt_relit_shade(c.ctx, t, &r, cam.eye, rgb);
            const float *a = indirect ? r.indirect : rgb, *b = indirect ? ref.indirect : ref.radiance;
            double se = 0, sb = 0, mx = 0;
            for (size_t k = 0; !st && k < ref.nv * 3; ++k) {
                double diff = (double)a[k] - b[k];
                se += diff * diff;
                sb += (double)b[k] * b[k];
                mx = fmax(mx, fabs(diff));
            }
            const double above = ref_err && !st ? cli_rel_l2_above_noise(a, b, ref_err, ref.nv * 3) : NAN;
            prt_relit_free(&r);
            if (st) break;
            const char *name = prt_transfer_variant_name(t, v);
            bool known = false;
            for (int k = 0; k < nnames && !known; ++k) known = !strcmp(names[k], name);
            if (!known && nnames < MAX_VARIANTS) snprintf(names[nnames++], sizeof names[0], "%s", name);
            fprintf(csv, "%s,%s,%s,%.6g,%.6g,%.6g,%.0f,%.3f,%.6g\n", pd->name, list_text[i], name, sqrt(se / (3.0 * ref.nv)), sb > 0 ? sqrt(se / sb) : INFINITY,
                    mx, bytes, prt_transfer_bake_seconds(t), above);
            if (!c.quiet)
                fprintf(stderr, "prt sweep: %s %s %-21s relative L2 %.5f (%.5f above the reference's noise)\n", pd->name, list_text[i], name,
                        sb > 0 ? sqrt(se / sb) : INFINITY, above);
        }
        prt_transfer_release(t);
    }
    if (csv) {
        bool ok = !ferror(csv);
        ok &= fclose(csv) == 0;
        if (st || rc || !ok || rename(tmp, output) != 0) {
            remove(tmp);
            if (!st && !rc) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; }
        }
    }
    if (!st && !rc && plot_path) {
        st = plot(&c, output, plot_path, pd->name, names, nnames, indirect);
        if (st) rc = EXIT_BACKEND;
        else if (!c.quiet) fprintf(stderr, "prt sweep: wrote %s and %s\n", output, plot_path);
    } else if (!st && !rc && !c.quiet) {
        fprintf(stderr, "prt sweep: wrote %s\n", output);
    }
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    prt_lighting_release(lighting);
    prt_scene_release(scene);
    prt_options_release(fixed_opts);
    cli_result_free(&ref);
    prt_context_release(c.ctx);
    return rc;
}
