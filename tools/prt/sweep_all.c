/* prt sweep --method all (and its short name, prt pick): which method suits a scene. Bakes the
 * scene with every method of the table that relights the lighting given, measures each against
 * the reference path tracer at the vertices, and reports error, bake time, file size, relight
 * and frame time side by side. Bakes and the reference are cached by what made them. */
#include "cli.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define DEFAULT_REFERENCE_SAMPLES 512
#define FRAME_WIDTH 800
#define FRAME_HEIGHT 600
#define TIMED_RUNS 3   /* relight and frame times: the least of this many runs */

const char *const cli_sweep_all_help =
    "Which method for a scene: prt sweep --method all SCENE (or prt pick SCENE)\n"
    "Bakes SCENE with every method of the table (prt bake --help lists them) that relights the\n"
    "lighting given - a method that cannot is listed as skipped, with the reason - each with its\n"
    "default options on the mesh as the scene gives it (prt bake's default refinement is left\n"
    "out, so that all are measured at the reference's vertices), and measures each against the\n"
    "reference path tracer at the vertices.\n"
    "Prints a table on stdout: relative L2 error of the radiance (and of the indirect light, where\n"
    "the method separates it), bake time, file size (bytes of the .prt), relight time (the whole\n"
    "scene relit once, per vertex, as the error is measured) and frame time (relit for drawing plus\n"
    "one 800x600 frame through the headless renderer, as prt render draws it: llvmpipe on the CPU\n"
    "where there is no GPU; without OpenGL, relight plus the per-vertex shading on the CPU, and the\n"
    "output says so); both times are the least of 3 runs. Then one line saying which method to\n"
    "pick for what. Each method is relit as its richest view-independent kind (prt info lists\n"
    "them); per-texel methods (offset) are compared at the vertices, as the one-method sweep does.\n\n"
    "      --json FILE        the same as JSON: {\"methods\": [{\"method\", \"variant\", \"relative_l2\",\n"
    "                         \"relative_l2_indirect\" (null where not separated),\n"
    "                         \"relative_l2_above_noise\", \"bake_seconds\", \"file_bytes\",\n"
    "                         \"relight_seconds\", \"frame_seconds\", \"reused\", \"skipped\" (null, or\n"
    "                         why)}, ...], \"pick\", ...}\n"
    "      --plot PREFIX      PREFIX-error-vs-bake.png and PREFIX-error-vs-size.png: relative L2\n"
    "                         error against bake time and against file size (gnuplot; a .png\n"
    "                         ending of PREFIX is dropped)\n"
    "      --reference FILE   per-vertex reference (prt reference SCENE -o REF.json with the same\n"
    "                         scene and lighting options); default: traced here with\n"
    "                         --reference-samples paths per vertex and kept in the cache\n"
    "      --reference-samples N  paths per vertex of that reference (default 512: about 20 s on\n"
    "                         two cores for the 10,000-vertex demo scene; its noise is printed)\n"
    "      --cache DIR        where bakes and the reference are kept (default: SCENE without its\n"
    "                         extension + .sweep/). Each file is named by a hash of the scene\n"
    "                         file's bytes, the scene loaded, the scene and bake options given, the\n"
    "                         method and the prt version (the reference: of the lighting and\n"
    "                         samples instead of the method); a rerun with the same inputs loads\n"
    "                         them instead of baking, and says so; written atomically\n"
    "      --rebake           bake (and trace the reference) again even when the cache has them\n"
    "      bake options that every method declares (today --ray-offset) apply to every bake;\n"
    "      other bake options, --param, --values, --indirect and -o belong to the one-method\n"
    "      sweep (--method M) and are refused here, as are --brdf, --brdf-all, --albedo-of and\n"
    "      --control\n"
    "Lighting (default: what the scene named, else the procedural sky; the reference traces all\n"
    "of it, so a method that cannot relight a part is skipped):\n" CLI_LIGHT_SOURCES_HELP
    "Scene:\n" CLI_SCENE_FILE_HELP
    "Other:\n"
    "  -j, --threads N        worker threads\n"
    CLI_PROGRESS_HELP
    "  -q, --quiet            no progress or messages (the table still goes to stdout)\n"
    "  -h, --help             this text\n"
    "Interrupted (Ctrl-C): exit 130 and no table, JSON or plot; finished bakes stay in the cache.\n";

enum { OPT_A_JSON = 2600, OPT_A_PLOT, OPT_A_REFERENCE, OPT_A_REF_SAMPLES, OPT_A_CACHE, OPT_A_REBAKE, OPT_A_METHOD, OPT_A_PARAM,
       OPT_A_VALUES, OPT_A_INDIRECT, OPT_A_METHOD_OPTION = 3000 };

bool cli_sweep_all_asked(int argc, char **argv)
{
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--")) break;
        if (!strcmp(argv[i], "--method") && i + 1 < argc && !strcmp(argv[i + 1], "all")) return true;
        if (!strcmp(argv[i], "--method=all")) return true;
    }
    return false;
}

/* ---- keys: FNV-1a, 64 bits ---- */
typedef struct { uint64_t h; } hasher;
static void hash_bytes(hasher *k, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; ++i) k->h = (k->h ^ p[i]) * 1099511628211ull;
}
static void hash_text(hasher *k, const char *s) { hash_bytes(k, s, strlen(s) + 1); }
static prt_status hash_file(hasher *k, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return PRT_ERR_IO;
    unsigned char buf[1 << 16];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) hash_bytes(k, buf, n);
    const bool ok = !ferror(f);
    fclose(f);
    return ok ? PRT_OK : PRT_ERR_IO;
}

/* "name=value;" for each option given, in order: what a key says of the command line. */
typedef struct { char text[8192]; size_t at; } keytext;
static void key_add(keytext *k, const char *name, const char *value)
{
    if (k->at < sizeof k->text)
        k->at += (size_t)snprintf(k->text + k->at, sizeof k->text - k->at, "%s=%s;", name, value ? value : "");
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

typedef struct row {
    const prt_method *m;
    char skipped[512];   /* "" when measured */
    char variant[64];
    char path[1200];
    bool reused;
    double rel_l2, rel_l2_indirect, above_noise, bake_s, relight_s, frame_s;
    long long file_bytes;
} row;

static void human_bytes(double b, char *out, size_t n)
{
    if (b >= 1e9) snprintf(out, n, "%.2f GB", b / 1e9);
    else if (b >= 1e6) snprintf(out, n, "%.1f MB", b / 1e6);
    else if (b >= 1e3) snprintf(out, n, "%.0f KB", b / 1e3);
    else snprintf(out, n, "%.0f B", b);
}

static void human_seconds(double s, char *out, size_t n)
{
    if (s < 1e-3) snprintf(out, n, "%.3f ms", s * 1e3);
    else if (s < 1) snprintf(out, n, "%.1f ms", s * 1e3);
    else snprintf(out, n, "%.1f s", s);
}

/* Relative L2 of a against b over n floats. */
static double rel_l2(const float *a, const float *b, size_t n)
{
    double se = 0, sb = 0;
    for (size_t i = 0; i < n; ++i) {
        const double d = (double)a[i] - b[i];
        se += d * d;
        sb += (double)b[i] * b[i];
    }
    return sb > 0 ? sqrt(se / sb) : INFINITY;
}

/* One line: which method for what. Empty when nothing was measured. */
static void pick_line(const row *rows, int n, char *out, size_t size)
{
    int best = -1, bake = -1, small = -1, frame = -1;
    for (int i = 0; i < n; ++i) {
        if (rows[i].skipped[0]) continue;
        if (best < 0 || rows[i].rel_l2 < rows[best].rel_l2) best = i;
        if (bake < 0 || rows[i].bake_s < rows[bake].bake_s) bake = i;
        if (small < 0 || rows[i].file_bytes < rows[small].file_bytes) small = i;
        if (frame < 0 || rows[i].frame_s < rows[frame].frame_s) frame = i;
    }
    out[0] = 0;
    if (best < 0) { snprintf(out, size, "nothing to pick: no method of the table relights this lighting"); return; }
    /* Each method once, with every criterion it wins. */
    const int winners[4] = {best, bake, small, frame};
    size_t at = (size_t)snprintf(out, size, "pick ");
    bool done[4] = {false, false, false, false};
    int groups = 0;
    for (int w = 0; w < 4; ++w) {
        if (done[w]) continue;
        const row *r = &rows[winners[w]];
        at += (size_t)snprintf(out + at, at < size ? size - at : 0, "%s%s for ", groups++ ? "; " : "", prt_method_name(r->m));
        int parts = 0;
        for (int v = w; v < 4; ++v) {
            if (done[v] || winners[v] != winners[w]) continue;
            done[v] = true;
            char q[32];
            int more = 0;   /* are there later criteria of this method? */
            for (int u = v + 1; u < 4; ++u) more += !done[u] && winners[u] == winners[w];
            const char *sep = parts == 0 ? "" : more ? ", " : " and ";
            if (v == 0) at += (size_t)snprintf(out + at, at < size ? size - at : 0, "%sthe lowest error (%.3g)", sep, r->rel_l2);
            if (v == 1) { snprintf(q, sizeof q, r->bake_s < 10 ? "%.2f s" : "%.1f s", r->bake_s); at += (size_t)snprintf(out + at, at < size ? size - at : 0, "%sthe fastest bake (%s)", sep, q); }
            if (v == 2) { human_bytes((double)r->file_bytes, q, sizeof q); at += (size_t)snprintf(out + at, at < size ? size - at : 0, "%sthe smallest file (%s)", sep, q); }
            if (v == 3) { human_seconds(r->frame_s, q, sizeof q); at += (size_t)snprintf(out + at, at < size ? size - at : 0, "%sthe cheapest frame (%s)", sep, q); }
            parts++;
        }
        if (winners[w] != best) at += (size_t)snprintf(out + at, at < size ? size - at : 0, " at error %.3g", r->rel_l2);
    }
    /* A middle way: the smallest file within 1.5x of the lowest error, when that is another method. */
    int mid = -1;
    for (int i = 0; i < n; ++i)
        if (!rows[i].skipped[0] && i != best && rows[i].rel_l2 <= 1.5 * rows[best].rel_l2 && (mid < 0 || rows[i].file_bytes < rows[mid].file_bytes)) mid = i;
    if (mid >= 0 && rows[mid].file_bytes < rows[best].file_bytes) {
        char b[32], s[32];
        human_bytes((double)rows[mid].file_bytes, b, sizeof b);
        snprintf(s, sizeof s, rows[mid].bake_s < 10 ? "%.2f s" : "%.1f s", rows[mid].bake_s);
        snprintf(out + at, at < size ? size - at : 0, "; %s comes within 1.5x of the lowest error (%.3g) in %s, baked in %s", prt_method_name(rows[mid].m),
                 rows[mid].rel_l2, b, s);
    }
}

/* Error against bake time and against file size, one PNG each, points named by method. */
static prt_status plots(cli *c, const char *prefix, const row *rows, int n, double noise)
{
    char stem[1100];
    snprintf(stem, sizeof stem, "%s", prefix);
    const size_t len = strlen(stem);
    if (len > 4 && !strcasecmp(stem + len - 4, ".png")) stem[len - 4] = 0;
    static const struct { const char *suffix, *xlabel; int column; } kinds[2] = {{"-error-vs-bake.png", "bake time (s)", 2},
                                                                                  {"-error-vs-size.png", "file size (MB)", 3}};
    for (int k = 0; k < 2; ++k) {
        char png[1200], tmp[1300], script[1300];
        snprintf(png, sizeof png, "%s%s", stem, kinds[k].suffix);
        snprintf(tmp, sizeof tmp, "%s.tmp.%ld.png", png, (long)getpid());
        snprintf(script, sizeof script, "%s.tmp.%ld.gp", png, (long)getpid());
        FILE *f = fopen(script, "w");
        if (!f) { cli_error(c, "cannot write '%s'", script); c->reported = true; return PRT_ERR_IO; }
        /* Inline data: method, bake seconds, MB, error, indirect error (NaN = none). */
        fprintf(f, "$d << EOD\n");
        int points = 0;
        for (int i = 0; i < n; ++i)
            if (!rows[i].skipped[0] && isfinite(rows[i].rel_l2) && rows[i].rel_l2 > 0) {
                fprintf(f, "%s %.6g %.6g %.6g %.6g\n", prt_method_name(rows[i].m), fmax(rows[i].bake_s, 1e-3), fmax((double)rows[i].file_bytes / 1e6, 1e-6),
                        rows[i].rel_l2, isfinite(rows[i].rel_l2_indirect) && rows[i].rel_l2_indirect > 0 ? rows[i].rel_l2_indirect : NAN);
                points++;
            }
        fprintf(f, "EOD\n");
        fprintf(f, "set terminal pngcairo size 900,560 font ',11'\nset output '%s'\n", tmp);
        fprintf(f, "set title 'prt sweep --method all: error against the reference and %s'\n", k ? "storage" : "bake time");
        fprintf(f, "set xlabel '%s'\nset ylabel 'relative L2 error'\nset logscale xy\nset grid\nset key top right\nset offsets graph 0.1, graph 0.2, graph 0.1, graph 0.1\n",
                kinds[k].xlabel);
        if (points && isfinite(noise) && noise > 0)   /* errors near it are the reference's noise */
            fprintf(f, "set arrow from graph 0, first %.6g to graph 1, first %.6g nohead dt 2 lc rgb '#777777'\n"
                       "set label \"reference noise\" at graph 0.02, first %.6g offset 0,-0.7 tc rgb '#777777'\n", noise, noise, noise);
        if (points)
            fprintf(f, "plot $d using %d:4 with points pt 7 ps 2 lc rgb '#1f77b4' title 'radiance', "
                       "$d using %d:5 with points pt 6 ps 2 lc rgb '#d62728' title 'indirect light', "
                       "$d using %d:4:1 with labels left offset char 1.2,0.5 notitle\n",
                    kinds[k].column, kinds[k].column, kinds[k].column);
        else
            fprintf(f, "unset logscale\nset label 'no method measured' at graph 0.4, graph 0.5\nplot [0:1][0:1] NaN notitle\n");
        fclose(f);
        if (!cli_run_gnuplot(c, script) || rename(tmp, png) != 0) {
            remove(tmp);
            cli_error(c, "gnuplot failed (is gnuplot-nox installed? scripts/setup-deps.sh installs it); the table is written");
            c->reported = true;
            return PRT_ERR_BACKEND;
        }
        if (!c->quiet) fprintf(stderr, "prt %s: wrote %s\n", c->cmd, png);
    }
    return PRT_OK;
}

static prt_status write_json(cli *c, const char *path, const char *scene_path, const char *ref_what, double ref_noise, const char *frame_what,
                             const row *rows, int n, const char *pick)
{
    cJSON *j = cJSON_CreateObject(), *arr = j ? cJSON_AddArrayToObject(j, "methods") : NULL;
    if (!arr) { cJSON_Delete(j); return PRT_ERR_NO_MEMORY; }
    cJSON_AddStringToObject(j, "scene", scene_path);
    cJSON_AddStringToObject(j, "reference", ref_what);
    if (isfinite(ref_noise)) cJSON_AddNumberToObject(j, "reference_relative_std_error", ref_noise);
    else cJSON_AddNullToObject(j, "reference_relative_std_error");
    cJSON_AddStringToObject(j, "frame", frame_what);
    cJSON_AddStringToObject(j, "prt_version", prt_version_string());
    for (int i = 0; i < n; ++i) {
        const row *r = &rows[i];
        cJSON *o = cJSON_CreateObject();
        if (!o) { cJSON_Delete(j); return PRT_ERR_NO_MEMORY; }
        cJSON_AddItemToArray(arr, o);
        cJSON_AddStringToObject(o, "method", prt_method_name(r->m));
        if (r->skipped[0]) {
            cJSON_AddStringToObject(o, "skipped", r->skipped);
            static const char *const nulls[] = {"variant", "relative_l2", "relative_l2_indirect", "relative_l2_above_noise", "bake_seconds",
                                                "file_bytes", "relight_seconds", "frame_seconds", "file"};
            for (size_t k = 0; k < sizeof nulls / sizeof nulls[0]; ++k) cJSON_AddNullToObject(o, nulls[k]);
            cJSON_AddBoolToObject(o, "reused", 0);
            continue;
        }
        cJSON_AddNullToObject(o, "skipped");
        cJSON_AddStringToObject(o, "variant", r->variant);
        const struct { const char *name; double v; } nums[] = {{"relative_l2", r->rel_l2}, {"relative_l2_indirect", r->rel_l2_indirect},
                                                              {"relative_l2_above_noise", r->above_noise}, {"bake_seconds", r->bake_s},
                                                              {"file_bytes", (double)r->file_bytes}, {"relight_seconds", r->relight_s},
                                                              {"frame_seconds", r->frame_s}};
        for (size_t k = 0; k < sizeof nums / sizeof nums[0]; ++k) {
            if (isfinite(nums[k].v)) cJSON_AddNumberToObject(o, nums[k].name, nums[k].v);
            else cJSON_AddNullToObject(o, nums[k].name);
        }
        cJSON_AddStringToObject(o, "file", r->path);
        cJSON_AddBoolToObject(o, "reused", r->reused);
    }
    cJSON_AddStringToObject(j, "pick", pick);
    char *text = cJSON_Print(j);
    cJSON_Delete(j);
    if (!text) return PRT_ERR_NO_MEMORY;
    const prt_status st = cli_write_text(path, text);
    cJSON_free(text);
    if (st) { cli_error(c, "cannot write '%s'", path); c->reported = true; }
    return st;
}

/* mkdir -p for the cache. */
static bool make_dirs(const char *path)
{
    char buf[1100];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + 1; *p; ++p) {
        if (*p != '/') continue;
        *p = 0;
        if (mkdir(buf, 0777) != 0 && errno != EEXIST) return false;
        *p = '/';
    }
    if (mkdir(buf, 0777) != 0 && errno != EEXIST) return false;
    struct stat s;
    return stat(buf, &s) == 0 && S_ISDIR(s.st_mode);
}

/* The reference: traced under the full lighting with the camera prt reference uses by default,
 * kept in the cache as prt reference -o writes it. */
static prt_status trace_reference(cli *c, const prt_scene *scene, const prt_lighting *lighting, const float eye[3], int samples, const char *path,
                                  cli_result *ref)
{
    prt_reference_desc rd = {0};
    rd.samples = samples;
    rd.lighting = lighting;
    rd.eye = eye;
    rd.progress = cli_progress;
    rd.progress_user = c;
    prt_reference_vertices res = {0};
    prt_status st = prt_reference_trace_vertices(c->ctx, scene, NULL, &rd, &res);
    if (!st) st = cli_check_interrupt(c);
    const size_t nv = res.vertex_count;
    if (!st) {
        cli_vertex_field f[5] = {{"radiance", res.radiance}, {"direct", res.direct}, {"indirect", res.indirect},
                                 {"std_error", res.std_error}, {"std_error_indirect", res.std_error_indirect}};
        if ((st = cli_write_vertex_json(path, "reference", nv, f, 5))) { cli_error(c, "cannot write the reference '%s'", path); c->reported = true; }
    }
    if (!st) {
        memset(ref, 0, sizeof *ref);
        ref->nv = nv;
        const float *src[4] = {res.radiance, res.indirect, res.std_error, res.std_error_indirect};
        float **dst[4] = {&ref->radiance, &ref->indirect, &ref->std_error, &ref->std_error_indirect};
        for (int k = 0; k < 4 && !st; ++k) {
            if (!(*dst[k] = malloc(nv * 3 * sizeof(float)))) st = PRT_ERR_NO_MEMORY;
            else memcpy(*dst[k], src[k], nv * 3 * sizeof(float));
        }
        snprintf(ref->what, sizeof ref->what, "%s", path);
        if (st) cli_result_free(ref);
    }
    prt_reference_vertices_free(&res);
    return st;
}

int cmd_sweep_all(const char *cmd, int argc, char **argv)
{
    cli c = {.cmd = cmd};
    cli_light light = {.intensity = 1.0f};
    prt_scene_desc sd = {0};
    const char *json = NULL, *plot_prefix = NULL, *reference = NULL, *cache = NULL;
    int ref_samples = DEFAULT_REFERENCE_SAMPLES;
    bool rebake = false;
    keytext scene_key = {.at = 0}, light_key = {.at = 0}, bake_key = {.at = 0};
    /* Bake options every method declares apply to every bake. */
    const char *shared_names[32], *shared_values[32];
    int nshared = 0;

    static const struct option fixed[] = {
        {"json", required_argument, 0, OPT_A_JSON}, {"plot", required_argument, 0, OPT_A_PLOT}, {"reference", required_argument, 0, OPT_A_REFERENCE},
        {"reference-samples", required_argument, 0, OPT_A_REF_SAMPLES}, {"cache", required_argument, 0, OPT_A_CACHE},
        {"rebake", no_argument, 0, OPT_A_REBAKE}, {"method", required_argument, 0, OPT_A_METHOD}, {"param", required_argument, 0, OPT_A_PARAM},
        {"values", required_argument, 0, OPT_A_VALUES}, {"indirect", no_argument, 0, OPT_A_INDIRECT}, {"output", required_argument, 0, 'o'},
        CLI_LIGHT_LONG_OPTIONS, CLI_SCENE_LONG_OPTIONS, {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'},
        {"help", no_argument, 0, 'h'}};
    struct option opts[256];
    const char *names[200];
    int n = 0;
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; ++i) opts[n++] = fixed[i];
    cli_collect_method_options(NULL, prt_method_options, opts, n, 256, names, 200, OPT_A_METHOD_OPTION);

    int opt, idx = -1, rc = EXIT_OK;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while (!rc && (idx = -1, opt = getopt_long(argc, argv, ":o:j:qh", opts, &idx)) != -1) {
        const char *oname = idx >= 0 ? opts[idx].name : "";
        if (opt == OPT_BRDF || opt == OPT_BRDF_ALL || opt == OPT_ALBEDO_OF || opt == OPT_BRDF_OF || opt == OPT_CONTROL || opt == OPT_PAINT) {
            rc = cli_usage(&c, "--%s sets how one method's file is relit: it does not apply with --method all (give --method M)", oname);
            break;
        }
        int r = cli_light_option(&c, &light, opt, optarg);
        if (r > 0) { key_add(&light_key, oname, optarg); continue; }
        if (!r) r = cli_scene_option(&c, &sd, opt, optarg);
        if (r < 0) { rc = EXIT_USAGE; break; }
        if (r) { if (opt != OPT_PROGRESS) key_add(&scene_key, oname, optarg); continue; }
        if (opt >= OPT_A_METHOD_OPTION) {
            const char *name = names[opt - OPT_A_METHOD_OPTION];
            char owners[256] = "";
            size_t at = 0;
            bool all = true;
            for (int m = 0; m < prt_method_count(); ++m) {
                if (prt_method_option(prt_method_at(m), name)) {
                    if (at < sizeof owners) at += (size_t)snprintf(owners + at, sizeof owners - at, "%s%s", at ? ", " : "", prt_method_name(prt_method_at(m)));
                } else {
                    all = false;
                }
            }
            if (!all) {
                rc = cli_usage(&c, "--%s is a bake option of %s only: with --method all every method bakes with its defaults "
                                   "(sweep it with --method M --param %s)", name, owners, name);
                break;
            }
            for (int m = 0; m < prt_method_count() && !rc; ++m) {   /* checked against each declaration */
                prt_options *probe = NULL;
                if (prt_options_create(prt_method_at(m), &probe)) { rc = cli_fail(&c, PRT_ERR_NO_MEMORY); break; }
                if (prt_options_set(probe, name, optarg)) rc = cli_usage(&c, "%s", prt_last_error());
                prt_options_release(probe);
            }
            if (!rc && nshared < 32) {
                shared_names[nshared] = name;
                shared_values[nshared++] = optarg;
                key_add(&bake_key, name, optarg);
            }
            continue;
        }
        switch (opt) {
        case OPT_A_JSON: json = optarg; break;
        case OPT_A_PLOT: plot_prefix = optarg; break;
        case OPT_A_REFERENCE: reference = optarg; break;
        case OPT_A_REF_SAMPLES:
            if (!cli_parse_int(optarg, 1, 1 << 24, &ref_samples)) rc = cli_usage(&c, "--reference-samples must be 1..16777216");
            break;
        case OPT_A_CACHE: cache = optarg; break;
        case OPT_A_REBAKE: rebake = true; break;
        case OPT_A_METHOD:
            if (strcmp(optarg, "all")) rc = cli_usage(&c, "--method %s and --method all: give one", optarg);
            break;
        case OPT_A_PARAM:
        case OPT_A_VALUES:
        case OPT_A_INDIRECT:
        case 'o':
            rc = cli_usage(&c, "%s%s belongs to the one-method sweep (--method M): --method all reports every method at its defaults "
                               "(--json FILE for machine-readable results)", opt == 'o' ? "-o" : "--", opt == 'o' ? "" : oname);
            break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) rc = cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h':
            printf("usage: prt %s%s SCENE [--json FILE] [--plot PREFIX] [--reference REF.json] [options]\n", c.cmd,
                   strcmp(c.cmd, "sweep") ? "" : " --method all");
            fputs(cli_sweep_all_help, stdout);
            fputs("\n" EXIT_CODES_HELP, stdout);
            return EXIT_OK;
        default: rc = cli_bad_option(&c, opt, argv, opts); break;
        }
    }
    if (!rc && optind != argc - 1) rc = cli_usage(&c, "expected exactly one SCENE argument");
    if (!rc && light.set_intensity && light.intensity == 0) rc = cli_usage(&c, "--intensity 0 leaves nothing to light the scene");
    if (rc) return rc;
    const char *scene_path = argv[optind];
    char cache_dir[1100];
    if (cache) {
        snprintf(cache_dir, sizeof cache_dir, "%s", cache);
    } else {
        /* Beside the scene: SCENE without its extension + ".sweep". */
        snprintf(cache_dir, sizeof cache_dir, "%s", scene_path);
        char *dot = strrchr(cache_dir, '.'), *slash = strrchr(cache_dir, '/');
        if (dot && (!slash || dot > slash + 1)) *dot = 0;
        const size_t l = strlen(cache_dir);
        snprintf(cache_dir + l, sizeof cache_dir - l, ".sweep");
    }
    if (strlen(cache_dir) > 900) return cli_usage(&c, "the cache directory's path is too long");
    if ((rc = cli_make_context(&c))) return rc;

    /* What every key starts from: the scene file's bytes, the options that load it, the prt version. */
    hasher base = {1469598103934665603ull};
    hash_text(&base, prt_version_string());
    prt_status st = hash_file(&base, scene_path);
    if (st) { cli_error(&c, "cannot read '%s'", scene_path); prt_context_release(c.ctx); return EXIT_FAILURE_INPUT; }
    hash_text(&base, scene_key.text);

    prt_scene *scene = NULL;
    prt_lighting *lighting = NULL;
    prt_renderer *renderer = NULL;
    cli_result ref = {0};
    bool have_ref = false;
    float *rgb = NULL;
    row rows[32];
    int nrows = 0;
    char ref_what[1200] = "", frame_what[256] = "", pick[1024] = "";
    double ref_noise = NAN;

    float inside[CLI_MAX_INSIDE_POINTS * 3];   /* a room around a --light keeps facing in, as prt reference sees it */
    sd.inside_point_count = cli_inside_points(&light, NULL, inside);
    sd.inside_points = inside;
    st = prt_scene_load(c.ctx, scene_path, &sd, &scene);
    if (!st && !c.quiet)
        fprintf(stderr, "prt %s: %s: %zu vertices, %zu triangles; cache %s/\n", c.cmd, scene_path, prt_scene_vertex_count(scene),
                prt_scene_triangle_count(scene), cache_dir);
    const size_t nv = st ? 0 : prt_scene_vertex_count(scene);
    if (!st) {
        /* The scene as loaded, too: files it names (materials, meshes of a JSON scene) change it. */
        hash_bytes(&base, prt_scene_positions(scene), nv * 3 * sizeof(float));
        hash_bytes(&base, prt_scene_normals(scene), nv * 3 * sizeof(float));
        hash_bytes(&base, prt_scene_albedo(scene), nv * 3 * sizeof(float));
        hash_bytes(&base, prt_scene_indices(scene), prt_scene_triangle_count(scene) * 3 * sizeof(uint32_t));
        if (prt_scene_emission(scene)) hash_bytes(&base, prt_scene_emission(scene), nv * 3 * sizeof(float));
        const int nb = prt_scene_brdf_count(scene);
        hash_bytes(&base, &nb, sizeof nb);
    }
    if (!st && !make_dirs(cache_dir)) {
        cli_error(&c, "cannot create the cache directory '%s' (--cache DIR)", cache_dir);
        c.reported = true;
        st = PRT_ERR_IO;
    }
    /* The reference traces every light the scene names (no method filters it), as prt reference does. */
    light.method = NULL;
    if (!st) st = cli_lighting(&c, &light, NULL, scene, &lighting);
    unsigned needs = 0;
    if (!st) {
        needs = prt_lighting_content(lighting);
        if (!prt_scene_emission(scene)) needs &= ~(unsigned)PRT_LIGHTS_EMISSIVE;
    }
    cli_view view = CLI_VIEW_DEFAULTS;
    prt_camera cam;
    memset(&cam, 0, sizeof cam);
    if (!st) cli_view_camera(&c, &view, prt_scene_positions(scene), nv, prt_scene_indices(scene), prt_scene_triangle_count(scene),
                             (float)view.width / view.height, &cam);

    /* ---- the reference ---- */
    if (!st && reference) {
        st = cli_result_load(&c, reference, &light, NULL, &ref);
        if (!st) {
            have_ref = true;
            if (ref.image) {
                cli_error(&c, "'%s' must be a per-vertex reference (prt reference SCENE -o REF.json)", reference);
                c.reported = true;
                rc = EXIT_USAGE;
            } else if (ref.nv != nv) {
                cli_error(&c, "the scene has %zu vertices, the reference %zu: compute it from the same scene with the same options", nv, ref.nv);
                rc = EXIT_FAILURE_INPUT;
            }
            snprintf(ref_what, sizeof ref_what, "%s", reference);
        } else {
            c.reported = true;
        }
    } else if (!st) {
        hasher k = base;
        hash_text(&k, "reference");
        hash_text(&k, light_key.text);
        if (light.env_path) hash_file(&k, light.env_path);   /* a missing probe fails below, with its own message */
        hash_bytes(&k, &ref_samples, sizeof ref_samples);
        hash_bytes(&k, cam.eye, sizeof cam.eye);
        snprintf(ref_what, sizeof ref_what, "%s/reference-%016llx.json", cache_dir, (unsigned long long)k.h);
        if (!rebake && access(ref_what, R_OK) == 0) {
            if (!cli_result_load(&c, ref_what, &light, NULL, &ref) && !ref.image && ref.nv == nv) {
                have_ref = true;
                if (!c.quiet) fprintf(stderr, "prt %s: reference: reusing %s (same scene, lighting, samples and prt version)\n", c.cmd, ref_what);
            } else {
                cli_result_free(&ref);
                if (!c.quiet) fprintf(stderr, "prt %s: reference: %s is unreadable: tracing it again\n", c.cmd, ref_what);
            }
        }
        if (!have_ref) {
            if (!c.quiet) fprintf(stderr, "prt %s: reference: tracing %d paths per vertex (--reference-samples N for more)\n", c.cmd, ref_samples);
            st = trace_reference(&c, scene, lighting, cam.eye, ref_samples, ref_what, &ref);
            have_ref = !st;
        }
    }
    if (!st && !rc) {
        double e = 0, s = 0;
        if (ref.std_error) {
            for (size_t i = 0; i < nv * 3; ++i) { e += (double)ref.std_error[i] * ref.std_error[i]; s += (double)ref.radiance[i] * ref.radiance[i]; }
            ref_noise = s > 0 ? sqrt(e / s) : NAN;
        }
        if (!c.quiet && isfinite(ref_noise))
            fprintf(stderr, "prt %s: reference: relative standard error %.4f (errors near it are the reference's noise)\n", c.cmd, ref_noise);
    }

    /* ---- a frame: relight for drawing and one headless frame, or the CPU shading without OpenGL ---- */
    if (!st && !rc) {
        if (prt_renderer_create(c.ctx, &(prt_renderer_desc){FRAME_WIDTH, FRAME_HEIGHT, 0}, &renderer) == PRT_OK) {
            snprintf(frame_what, sizeof frame_what, "relight for drawing + one %dx%d frame (%s)", FRAME_WIDTH, FRAME_HEIGHT, prt_renderer_name(renderer));
        } else {
            renderer = NULL;
            snprintf(frame_what, sizeof frame_what, "relight + per-vertex shading on the CPU (no OpenGL: %s)", prt_last_error());
            if (!c.quiet) fprintf(stderr, "prt %s: no headless renderer: frame time is relight + CPU shading (%s)\n", c.cmd, prt_last_error());
        }
    }

    /* ---- every method ---- */
    for (int mi = 0; mi < prt_method_count() && mi < 32 && !st && !rc; ++mi) {
        row *r = &rows[nrows++];
        memset(r, 0, sizeof *r);
        r->m = prt_method_at(mi);
        r->rel_l2 = r->rel_l2_indirect = r->above_noise = NAN;
        const char *mname = prt_method_name(r->m);
        if (prt_method_check_lighting(r->m, needs) != PRT_OK) {
            snprintf(r->skipped, sizeof r->skipped, "%s", prt_last_error());
            if (!c.quiet) fprintf(stderr, "prt %s: %s: skipped: %s\n", c.cmd, mname, r->skipped);
            continue;
        }
        hasher k = base;
        hash_text(&k, mname);
        hash_text(&k, bake_key.text);
        snprintf(r->path, sizeof r->path, "%s/%s-%016llx.prt", cache_dir, mname, (unsigned long long)k.h);
        prt_transfer *t = NULL;
        if (!rebake && access(r->path, R_OK) == 0) {
            if (prt_transfer_load(c.ctx, r->path, &t) == PRT_OK) {
                r->reused = true;
                if (!c.quiet) fprintf(stderr, "prt %s: %s: reusing %s (same scene, options and prt version)\n", c.cmd, mname, r->path);
            } else if (!c.quiet) {
                fprintf(stderr, "prt %s: %s: %s is unreadable (%s): baking again\n", c.cmd, mname, r->path, prt_last_error());
            }
        }
        if (!t) {
            prt_options *o = NULL;
            if ((st = prt_options_create(r->m, &o))) break;
            for (int s = 0; s < nshared && !st; ++s) st = prt_options_set(o, shared_names[s], shared_values[s]);
            if (!c.quiet) fprintf(stderr, "prt %s: %s: baking with its defaults\n", c.cmd, mname);
            prt_bake_run_desc run = {.progress = cli_progress, .progress_user = &c};
            if (!st) st = prt_bake(c.ctx, scene, r->m, o, &run, &t);
            prt_options_release(o);
            if (st == PRT_ERR_INVALID_ARG || st == PRT_ERR_EMPTY) {   /* the method refuses this scene: say why, go on */
                snprintf(r->skipped, sizeof r->skipped, "the bake refused the scene: %s", prt_last_error());
                if (!c.quiet) fprintf(stderr, "prt %s: %s: skipped: %s\n", c.cmd, mname, r->skipped);
                st = PRT_OK;
                continue;
            }
            if (!st) st = cli_check_interrupt(&c);
            if (!st && (st = prt_transfer_save(t, r->path))) { cli_error(&c, "cannot write '%s': %s", r->path, prt_last_error()); c.reported = true; }
            if (st) { prt_transfer_release(t); break; }
        }
        struct stat fs;
        r->file_bytes = stat(r->path, &fs) == 0 ? (long long)fs.st_size : -1;
        r->bake_s = prt_transfer_bake_seconds(t);
        /* A generated UV atlas appends copies of seam vertices after the scene's own, which keep
         * their order: compare those, from a buffer sized for all. */
        const size_t tnv = prt_transfer_vertex_count(t);
        if (tnv < nv) {
            snprintf(r->skipped, sizeof r->skipped, "its bake has %zu vertices, the scene %zu: not comparable at the vertices", tnv, nv);
            prt_transfer_release(t);
            continue;
        }
        free(rgb);
        if (!(rgb = malloc(tnv * 3 * sizeof(float)))) { st = PRT_ERR_NO_MEMORY; prt_transfer_release(t); break; }
        const int variant = prt_transfer_default_variant(t, 0);
        snprintf(r->variant, sizeof r->variant, "%s", prt_transfer_variant_name(t, variant));
        /* The comparison path of the one-method sweep: per vertex, shaded towards the camera. */
        prt_relit rl;
        double t0 = now_seconds();
        st = cli_relight(&c, t, lighting, &light, variant, true, true, &rl);
        r->relight_s = now_seconds() - t0;
        if (st == PRT_ERR_INVALID_ARG && !c.reported) {   /* the method refused this lighting for this scene (an SH file, a lamp inside a room) */
            snprintf(r->skipped, sizeof r->skipped, "%s", prt_last_error());
            if (!c.quiet) fprintf(stderr, "prt %s: %s: skipped: %s\n", c.cmd, mname, r->skipped);
            st = PRT_OK;
            prt_transfer_release(t);
            continue;
        }
        if (st) { prt_transfer_release(t); break; }
        /* Times are the least of a few runs: one run on a busy machine says little. */
        for (int again = 0; again < TIMED_RUNS - 1 && !st; ++again) {
            prt_relit more;
            t0 = now_seconds();
            st = cli_relight(&c, t, lighting, &light, variant, true, true, &more);
            r->relight_s = fmin(r->relight_s, now_seconds() - t0);
            if (!st) prt_relit_free(&more);
        }
        if (st) { prt_relit_free(&rl); prt_transfer_release(t); break; }
        t0 = now_seconds();
        st = prt_relit_shade(c.ctx, t, &rl, cam.eye, rgb);
        const double shade_s = now_seconds() - t0;
        if (!st) {
            r->rel_l2 = rel_l2(rgb, ref.radiance, nv * 3);
            if (ref.std_error) r->above_noise = cli_rel_l2_above_noise(rgb, ref.radiance, ref.std_error, nv * 3);
            if (rl.indirect && ref.indirect) r->rel_l2_indirect = rel_l2(rl.indirect, ref.indirect, nv * 3);
        }
        prt_relit_free(&rl);
        /* The frame: what prt render does for one image (a first, untimed one warms up the GL
         * state: shaders, buffers). */
        r->frame_s = r->relight_s + shade_s;
        for (int pass = 0; !st && renderer && pass <= TIMED_RUNS; ++pass) {
            prt_relit fr;
            prt_image img = {0};
            t0 = now_seconds();
            st = cli_relight(&c, t, lighting, &light, prt_transfer_default_variant(t, 1), false, false, &fr);
            if (st) break;
            prt_render_mesh mesh;
            prt_relit_render_mesh(t, &fr, &mesh);
            st = prt_render(renderer, &mesh, &cam, view.background, &img);
            if (pass == 1) r->frame_s = now_seconds() - t0;
            else if (pass > 1) r->frame_s = fmin(r->frame_s, now_seconds() - t0);
            prt_image_free(&img);
            prt_relit_free(&fr);
        }
        prt_transfer_release(t);
        if (!st) st = cli_check_interrupt(&c);
        if (st) break;
        if (!c.quiet) {
            char b[32], f[32];
            human_bytes((double)r->file_bytes, b, sizeof b);
            human_seconds(r->frame_s, f, sizeof f);
            fprintf(stderr, "prt %s: %s (%s): relative L2 %.4f, %s, frame %s\n", c.cmd, mname, r->variant, r->rel_l2, b, f);
        }
    }
    if (!st && !rc) st = cli_check_interrupt(&c);

    /* ---- the table, the JSON, the plots ---- */
    if (!st && !rc) {
        pick_line(rows, nrows, pick, sizeof pick);
        printf("%-11s %-22s %9s %9s %10s %10s %10s %10s  %s\n", "method", "kind", "rel. L2", "indirect", "bake", "file", "relight", "frame", "");
        for (int i = 0; i < nrows; ++i) {
            const row *r = &rows[i];
            if (r->skipped[0]) { printf("%-11s skipped: %s\n", prt_method_name(r->m), r->skipped); continue; }
            char ind[16], bake[32], file[32], rel[32], frame[32];
            if (isfinite(r->rel_l2_indirect)) snprintf(ind, sizeof ind, "%.4f", r->rel_l2_indirect);
            else snprintf(ind, sizeof ind, "-");
            snprintf(bake, sizeof bake, r->bake_s < 10 ? "%.2f s" : "%.1f s", r->bake_s);
            human_bytes((double)r->file_bytes, file, sizeof file);
            human_seconds(r->relight_s, rel, sizeof rel);
            human_seconds(r->frame_s, frame, sizeof frame);
            printf("%-11s %-22s %9.4f %9s %10s %10s %10s %10s  %s\n", prt_method_name(r->m), r->variant, r->rel_l2, ind, bake, file, rel, frame,
                   r->reused ? "(bake reused)" : "");
        }
        char noise[64] = "";
        if (isfinite(ref_noise)) snprintf(noise, sizeof noise, " (its relative standard error %.4f)", ref_noise);
        printf("reference: %s%s; frame: %s\n", ref_what, noise, frame_what);
        printf("%s\n", pick);
        fflush(stdout);
        if (json && (st = write_json(&c, json, scene_path, ref_what, ref_noise, frame_what, rows, nrows, pick)) == PRT_OK && !c.quiet)
            fprintf(stderr, "prt %s: wrote %s\n", c.cmd, json);
        if (!st && plot_prefix && (st = plots(&c, plot_prefix, rows, nrows, ref_noise))) rc = st == PRT_ERR_BACKEND ? EXIT_BACKEND : cli_exit_code(st);
    }
    if (st == PRT_ERR_CANCELLED && !rc && !c.reported) {
        cli_error(&c, "interrupted: nothing written (finished bakes stay in %s/ for the next run)", cache_dir);
        rc = EXIT_INTERRUPTED;
    }
    if (st && !rc) rc = cli_fail(&c, st);
    free(rgb);
    if (have_ref) cli_result_free(&ref);
    prt_renderer_release(renderer);
    prt_lighting_release(lighting);
    prt_scene_release(scene);
    prt_context_release(c.ctx);
    return rc;
}

int cmd_pick(int argc, char **argv) { return cmd_sweep_all("pick", argc, argv); }
