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
    "Bakes SCENE once per value of a parameter, relights every transfer kind under the lighting,\n"
    "and measures the per-vertex error against a reference computed on the same scene (prt\n"
    "reference SCENE -o REF.json with the same scene and lighting options). Writes one CSV row per\n"
    "value and kind, and with --plot a PNG of error and storage against the parameter (gnuplot).\n\n"
    "  -o, --output FILE      the CSV (param,value,kind,rmse,relative_l2,max_abs,bytes_per_vertex,bake_seconds)\n"
    "      --reference FILE   per-vertex reference JSON (required)\n"
    "      --plot FILE        PNG plot of relative L2 error and bytes per vertex\n"
    "      --param P          order | samples | bounces | clusters | vectors (default order);\n"
    "                         clusters and vectors bake once and compress with clustered PCA\n"
    "                         (vectors per cluster --vectors, default 8; clusters --clusters, 64)\n"
    "      --values LIST      comma list (default for order: 3,4,5,6,7,8,9,10)\n"
    "      --kinds LIST       unshadowed,shadowed,interreflected (default all)\n"
    "      --indirect         compare only the indirect light (inter-reflected minus shadowed)\n"
    "      --order N --samples N --bounces N --seed N   the settings not swept (bake defaults)\n"
    CLI_LIGHT_OPTIONS_HELP "Scene:\n" CLI_SCENE_OPTIONS_HELP
    "  -j, --threads N        worker threads\n"
    "  -q, --quiet            no progress\n"
    "  -h, --help             this text\n\n" EXIT_CODES_HELP;

enum { OPT_REFERENCE = 2400, OPT_PLOT, OPT_PARAM, OPT_VALUES, OPT_KINDS, OPT_INDIRECT_ONLY, OPT_ORDER, OPT_SAMPLES, OPT_BOUNCES, OPT_SEED,
       OPT_CLUSTERS, OPT_VECTORS };

static prt_status plot(const cli *c, const char *csv, const char *png, const char *param, unsigned kinds, bool indirect)
{
    char script[1100];
    snprintf(script, sizeof script, "%s.gp", png);
    FILE *f = fopen(script, "w");
    if (!f) return PRT_ERR_IO;
    fprintf(f, "set terminal pngcairo size 900,560 font ',11'\nset output '%s'\nset datafile separator ','\n", png);
    fprintf(f, "set title 'prt sweep: %s error against the reference'\nset xlabel '%s'\nset ylabel 'relative L2 error'\n", indirect ? "indirect" : "radiance", param);
    fprintf(f, "set logscale y\nset y2label 'bytes per vertex'\nset y2tics\nset ytics nomirror\nset grid\nset key outside right\n");
    fprintf(f, "plot ");
    const char *names[3] = {"unshadowed", "shadowed", "interreflected"};
    bool first = true;
    for (int k = 0; k < 3; ++k) {
        if (!(kinds & (1u << k))) continue;
        /* One series per kind: gnuplot joins points only within consecutive rows. */
        fprintf(f, "%s'< grep \",%s,\" \"%s\"' using 2:5 with linespoints lw 2 title '%s error', "
                   "'< grep \",%s,\" \"%s\"' using 2:7 axes x1y2 with lines dt 2 title '%s bytes'",
                first ? "" : ", ", names[k], csv, names[k], names[k], csv, names[k]);
        first = false;
    }
    fprintf(f, "\n");
    fclose(f);
    char cmd[2400];
    snprintf(cmd, sizeof cmd, "gnuplot '%s' 2>&1", script);
    FILE *p = popen(cmd, "r");
    char line[512];
    bool said = false;
    while (p && fgets(line, sizeof line, p))
        if (!c->quiet || !said) { fprintf(stderr, "gnuplot: %s", line); said = true; }
    int rc = p ? pclose(p) : -1;
    remove(script);
    if (rc != 0) {
        cli_error(c, "gnuplot failed (is gnuplot-nox installed? scripts/setup-deps.sh installs it); the CSV is written");
        return PRT_ERR_BACKEND;
    }
    return PRT_OK;
}

int cmd_sweep(int argc, char **argv)
{
    cli c = {.cmd = "sweep"};
    cli_light light = {.intensity = 1.0f};
    prt_scene_desc sd = {0};
    prt_bake_desc base = {0};
    const char *output = NULL, *reference = NULL, *plot_path = NULL, *param = "order", *values = NULL;
    unsigned kinds = 7;
    bool indirect = false;
    int seed, clusters = 64, vectors = 8;
    static const struct option opts[] = {
        {"output", required_argument, 0, 'o'}, {"reference", required_argument, 0, OPT_REFERENCE}, {"plot", required_argument, 0, OPT_PLOT},
        {"param", required_argument, 0, OPT_PARAM}, {"values", required_argument, 0, OPT_VALUES}, {"kinds", required_argument, 0, OPT_KINDS},
        {"indirect", no_argument, 0, OPT_INDIRECT_ONLY}, {"order", required_argument, 0, OPT_ORDER},
        {"samples", required_argument, 0, OPT_SAMPLES}, {"bounces", required_argument, 0, OPT_BOUNCES}, {"seed", required_argument, 0, OPT_SEED},
        {"clusters", required_argument, 0, OPT_CLUSTERS}, {"vectors", required_argument, 0, OPT_VECTORS}, CLI_LIGHT_LONG_OPTIONS, CLI_SCENE_LONG_OPTIONS, {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'},
        {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &light, opt, optarg);
        if (!r) r = cli_scene_option(&c, &sd, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case 'o': output = optarg; break;
        case OPT_REFERENCE: reference = optarg; break;
        case OPT_PLOT: plot_path = optarg; break;
        case OPT_PARAM:
            if (strcmp(optarg, "order") && strcmp(optarg, "samples") && strcmp(optarg, "bounces") && strcmp(optarg, "clusters") &&
                strcmp(optarg, "vectors"))
                return cli_usage(&c, "--param must be order, samples, bounces, clusters or vectors");
            param = optarg;
            break;
        case OPT_VALUES: values = optarg; break;
        case OPT_KINDS: {
            char buf[256], *save = NULL;
            snprintf(buf, sizeof buf, "%s", optarg);
            kinds = 0;
            for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
                prt_transfer_kind k;
                if (!strcasecmp(tok, "all")) { kinds = 7; continue; }
                if (prt_transfer_kind_parse(tok, &k)) return cli_usage(&c, "%s", prt_last_error());
                kinds |= (unsigned)k;
            }
            if (!kinds) return cli_usage(&c, "--kinds is empty");
            break;
        }
        case OPT_INDIRECT_ONLY: indirect = true; break;
        case OPT_ORDER: if (!cli_parse_int(optarg, 1, PRT_SH_MAX_ORDER, &base.order)) return cli_usage(&c, "--order must be 1..%d", PRT_SH_MAX_ORDER); break;
        case OPT_SAMPLES: if (!cli_parse_int(optarg, 16, 1 << 20, &base.samples)) return cli_usage(&c, "--samples must be 16..1048576"); break;
        case OPT_BOUNCES: if (!cli_parse_int(optarg, 1, 64, &base.bounces)) return cli_usage(&c, "--bounces must be 1..64"); break;
        case OPT_SEED: if (!cli_parse_int(optarg, 0, 2147483647, &seed)) return cli_usage(&c, "--seed must be a non-negative integer"); base.seed = (uint32_t)seed; break;
        case OPT_CLUSTERS: if (!cli_parse_int(optarg, 1, 65536, &clusters)) return cli_usage(&c, "--clusters must be 1..65536"); break;
        case OPT_VECTORS: if (!cli_parse_int(optarg, 1, 300, &vectors)) return cli_usage(&c, "--vectors must be 1..300"); break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_usage(&c, "unknown option");
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one SCENE argument");
    if (!output || !reference) return cli_usage(&c, "-o OUT.csv and --reference REF.json are required");
    if (indirect) kinds &= PRT_TRANSFER_INTERREFLECTED;
    if (!kinds) return cli_usage(&c, "--indirect compares the inter-reflected kind only");
    int list[64], nvalues = 0;
    {
        char buf[512], *save = NULL;
        bool cl = !strcmp(param, "clusters"), ve = !strcmp(param, "vectors");
        snprintf(buf, sizeof buf, "%s", values ? values : !strcmp(param, "order") ? "3,4,5,6,7,8,9,10" : !strcmp(param, "samples") ? "64,128,256,512,1024,2048,4096"
                                                 : cl ? "1,4,16,64,256" : ve ? "1,2,4,8,16" : "1,2,3,4,6,8");
        int hi = !strcmp(param, "order") ? PRT_SH_MAX_ORDER : !strcmp(param, "samples") ? 1 << 20 : cl ? 65536 : ve ? 300 : 64;
        int lo = !strcmp(param, "samples") ? 16 : 1;
        for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
            if (nvalues == 64 || !cli_parse_int(tok, lo, hi, &list[nvalues])) return cli_usage(&c, "--values: '%s' is not a valid %s", tok, param);
            nvalues++;
        }
    }
    int rc = cli_make_context(&c);
    if (rc) return rc;
    cli_catch_interrupt();
    cli_result ref;
    prt_status st = cli_result_load(&c, reference, &light, 0, &ref);
    if (st) { prt_context_release(c.ctx); return cli_exit_code(st); }
    if (ref.image || (indirect && !ref.indirect)) {
        cli_error(&c, "'%s' must be a per-vertex reference%s", reference, indirect ? " with an \"indirect\" field" : "");
        cli_result_free(&ref);
        prt_context_release(c.ctx);
        return EXIT_USAGE;
    }
    prt_scene *scene = NULL;
    st = prt_scene_load(c.ctx, argv[optind], &sd, &scene);
    if (!st && prt_scene_vertex_count(scene) != ref.nv) {
        cli_error(&c, "the scene has %zu vertices, the reference %zu: compute it from the same scene with the same options", prt_scene_vertex_count(scene), ref.nv);
        rc = EXIT_FAILURE_INPUT;
    }
    if (!st) cli_light_defaults_from_scene(&light, scene);
    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld", output, (long)getpid());
    FILE *csv = !st && !rc ? fopen(tmp, "w") : NULL;
    if (!st && !rc && !csv) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; }
    if (csv) fprintf(csv, "param,value,kind,rmse,relative_l2,max_abs,bytes_per_vertex,bake_seconds\n");
    float *rgb = !st && !rc ? malloc(ref.nv * 3 * sizeof(float)) : NULL, *direct = rgb ? malloc(ref.nv * 3 * sizeof(float)) : NULL;
    const bool compressing = !strcmp(param, "clusters") || !strcmp(param, "vectors");
    prt_transfer *baked = NULL;   /* compression sweeps bake once */
    for (int i = 0; i < nvalues && !st && !rc && direct; ++i) {
        prt_bake_desc d = base;
        if (!strcmp(param, "order")) d.order = list[i];
        else if (!strcmp(param, "samples")) d.samples = list[i];
        else if (!strcmp(param, "bounces")) d.bounces = list[i];
        d.kinds = kinds | (indirect ? PRT_TRANSFER_SHADOWED : 0);
        d.progress = cli_progress;
        d.progress_user = &c;
        prt_transfer *t = NULL;
        if (!compressing || !baked) {
            if ((st = prt_bake_sh(c.ctx, scene, &d, compressing ? &baked : &t))) break;
        }
        if (compressing) {
            prt_compress_desc cd = {0};
            cd.clusters = !strcmp(param, "clusters") ? list[i] : clusters;
            cd.vectors = !strcmp(param, "vectors") ? list[i] : vectors;
            if ((st = prt_transfer_compress(c.ctx, baked, &cd, &t))) break;
        }
        prt_transfer_info info;
        prt_transfer_get_info(t, &info);
        prt_sh_light sh;
        if ((st = cli_light_project(&c, &light, info.order, &sh, NULL))) { prt_transfer_release(t); break; }
        for (int k = 0; k < 3 && !st; ++k) {
            prt_transfer_kind kind = (prt_transfer_kind)(1u << k);
            if (!(kinds & kind)) continue;
            if ((st = prt_relight_sh(c.ctx, t, kind, &sh, rgb))) break;
            const float *b = ref.radiance;
            if (indirect) {
                if ((st = prt_relight_sh(c.ctx, t, PRT_TRANSFER_SHADOWED, &sh, direct))) break;
                for (size_t v = 0; v < ref.nv * 3; ++v) rgb[v] -= direct[v];
                b = ref.indirect;
            }
            double se = 0, sb = 0, mx = 0;
            for (size_t v = 0; v < ref.nv * 3; ++v) {
                double diff = (double)rgb[v] - b[v];
                se += diff * diff;
                sb += (double)b[v] * b[v];
                mx = fmax(mx, fabs(diff));
            }
            prt_compress_info ci;
            prt_transfer_compress_info(t, kind, &ci);
            double bytes = (double)ci.bytes / (double)ref.nv;
            fprintf(csv, "%s,%d,%s,%.6g,%.6g,%.6g,%.0f,%.3f\n", param, list[i], prt_transfer_kind_name(kind), sqrt(se / (3.0 * ref.nv)),
                    sb > 0 ? sqrt(se / sb) : INFINITY, mx, bytes, info.bake_seconds);
            if (!c.quiet)
                fprintf(stderr, "prt sweep: %s %d %-14s relative L2 %.5f\n", param, list[i], prt_transfer_kind_name(kind), sb > 0 ? sqrt(se / sb) : INFINITY);
        }
        prt_transfer_release(t);
    }
    prt_transfer_release(baked);
    if (!direct && !st && !rc) st = PRT_ERR_NO_MEMORY;
    if (csv) {
        bool ok = !ferror(csv);
        ok &= fclose(csv) == 0;
        if (st || rc || !ok || rename(tmp, output) != 0) {
            remove(tmp);
            if (!st && !rc) { cli_error(&c, "cannot write '%s'", output); rc = EXIT_FAILURE_INPUT; }
        }
    }
    if (!st && !rc && plot_path) {
        st = plot(&c, output, plot_path, param, kinds, indirect);
        if (st) rc = EXIT_BACKEND;
        else if (!c.quiet) fprintf(stderr, "prt sweep: wrote %s and %s\n", output, plot_path);
    } else if (!st && !rc && !c.quiet) {
        fprintf(stderr, "prt sweep: wrote %s\n", output);
    }
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    free(direct);
    prt_scene_release(scene);
    cli_result_free(&ref);
    prt_context_release(c.ctx);
    return rc;
}
