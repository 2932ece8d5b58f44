#include "cli.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

void cli_error(const cli *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "prt %s: ", c->cmd);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

int cli_fail(const cli *c, prt_status st)
{
    if (!c->reported) cli_error(c, "%s", prt_last_error()[0] ? prt_last_error() : prt_status_string(st));
    return cli_exit_code(st);
}

int cli_exit_code(prt_status st)
{
    switch (st) {
    case PRT_OK: return EXIT_OK;
    case PRT_ERR_INVALID_ARG: return EXIT_USAGE;
    case PRT_ERR_CANCELLED: return EXIT_INTERRUPTED;
    case PRT_ERR_BACKEND: return EXIT_BACKEND;
    case PRT_ERR_NO_MEMORY: return EXIT_NO_MEMORY;
    default: return EXIT_FAILURE_INPUT;
    }
}

/* Edit distance between a and the first n bytes of b, capped at 9, counting a swap of two
 * neighbouring letters as one edit (optimal string alignment): "--ligth" is one edit from
 * "--light", two from "--width". */
int cli_edit_distance(const char *a, const char *b, size_t n)
{
    const size_t la = strlen(a);
    if (la > 63 || n > 63) return 9;
    int rows[3][64], *prev2 = rows[0], *prev = rows[1], *row = rows[2];
    for (size_t j = 0; j <= n; ++j) prev[j] = (int)j;
    for (size_t i = 1; i <= la; ++i) {
        row[0] = (int)i;
        for (size_t j = 1; j <= n; ++j) {
            const int sub = prev[j - 1] + (a[i - 1] != b[j - 1]), del = prev[j] + 1, ins = row[j - 1] + 1;
            int d = sub < del ? (sub < ins ? sub : ins) : (del < ins ? del : ins);
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] && prev2[j - 2] + 1 < d) d = prev2[j - 2] + 1;
            row[j] = d;
        }
        int *t = prev2;
        prev2 = prev;
        prev = row;
        row = t;
    }
    return prev[n] < 9 ? prev[n] : 9;
}

int cli_bad_option(const cli *c, int opt, char **argv, const struct option *opts)
{
    extern int optind;
    const char *arg = optind > 0 ? argv[optind - 1] : "";
    if (opt == ':') return cli_usage(c, "option '%s' needs a value", arg);
    /* A misspelt long option: name the closest one (within a third of its length). */
    if (!strncmp(arg, "--", 2) && opts) {
        const char *name = arg + 2, *eq = strchr(name, '=');
        const size_t n = eq ? (size_t)(eq - name) : strlen(name);
        const char *best = NULL;
        int best_d = 9;
        for (const struct option *o = opts; o->name; ++o) {
            const int d = cli_edit_distance(o->name, name, n);
            if (d < best_d) { best_d = d; best = o->name; }
        }
        if (best && best_d <= 1 + (int)strlen(best) / 3) return cli_usage(c, "unknown option '%.*s': did you mean --%s?", (int)n + 2, arg, best);
    }
    return cli_usage(c, "unknown option '%s'", arg);
}

bool cli_run_gnuplot(const cli *c, const char *script)
{
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "gnuplot '%s' 2>&1", script);
    FILE *p = popen(cmd, "r");
    char line[512];
    bool said = false;
    while (p && fgets(line, sizeof line, p))
        if (!c->quiet || !said) { fprintf(stderr, "gnuplot: %s", line); said = true; }
    const int rc = p ? pclose(p) : -1;
    remove(script);
    return rc == 0;
}

int cli_usage(const cli *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "prt %s: ", c->cmd);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, " (prt %s --help lists the options)\n", c->cmd);   /* one line, for logs and scripts */
    va_end(ap);
    return EXIT_USAGE;
}


static void log_to_stderr(void *user, prt_log_level level, const char *msg)
{
    const cli *c = user;
    /* Errors are reported once, by the command, from prt_last_error(). */
    if (level == PRT_LOG_WARN && !c->quiet) fprintf(stderr, "prt %s: warning: %s\n", c->cmd, msg);
    if (level == PRT_LOG_INFO && !c->quiet) fprintf(stderr, "prt %s: %s\n", c->cmd, msg);
}

int cli_make_context(cli *c)
{
    /* Every command honours Ctrl-C: long work through its progress callback, and every command
     * checks before it writes (cli_check_interrupt), so an interrupted run writes nothing. */
    cli_catch_interrupt();
    prt_context_desc d = {0};
    d.threads = c->threads;
    d.log = log_to_stderr;
    d.log_user = c;
    d.cancel = cli_cancel_hook;
    prt_status st = prt_context_create(&d, &c->ctx);
    return st ? cli_fail(c, st) : EXIT_OK;
}

bool cli_parse_int(const char *s, int lo, int hi, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) return false;
    *out = (int)v;
    return true;
}

bool cli_parse_float(const char *s, float *out)
{
    char *end;
    errno = 0;
    float v = strtof(s, &end);
    if (errno || end == s || *end || !isfinite(v)) return false;
    *out = v;
    return true;
}

bool cli_parse_vec3(const char *s, bool allow_scalar, float out[3])
{
    char buf[256];
    snprintf(buf, sizeof buf, "%s", s);
    int n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (n == 3 || !cli_parse_float(tok, &out[n])) return false;
        n++;
    }
    if (n == 1 && allow_scalar) { out[1] = out[2] = out[0]; return true; }
    return n == 3;
}

/* ---- progress ---- */
static volatile sig_atomic_t interrupted;
static void on_sigint(int sig) { (void)sig; interrupted = 1; }
void cli_catch_interrupt(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}
bool cli_interrupted(void) { return interrupted != 0; }
int cli_cancel_hook(void *user) { (void)user; return interrupted != 0; }

prt_status cli_check_interrupt(cli *c)
{
    if (!interrupted) return PRT_OK;
    cli_error(c, "interrupted: nothing written");
    c->reported = true;
    return PRT_ERR_CANCELLED;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Stage times for the bake's report: one entry per stage name, in the order first seen. */
#define MAX_STAGES 256
static char stage_names[MAX_STAGES][64];
static const char *stage_name_ptrs[MAX_STAGES];
static double stage_seconds[MAX_STAGES];
static int stage_count;

int cli_stage_times(const char *const **names, const double **seconds)
{
    for (int i = 0; i < stage_count; ++i) stage_name_ptrs[i] = stage_names[i];
    *names = stage_name_ptrs;
    *seconds = stage_seconds;
    return stage_count;
}

int cli_progress(void *user, const char *stage, uint64_t done, uint64_t total)
{
    const cli *c = user;
    static char current[64];
    static double start;
    static int logged;   /* plain lines: the last tenth reported; json: the last percent */
    static int slot = -1;
    double t = now_seconds();
    const bool fresh = strcmp(current, stage) != 0;
    if (fresh) {
        snprintf(current, sizeof current, "%s", stage);
        start = t;
        logged = -1;
        slot = -1;
        for (int i = 0; i < stage_count && slot < 0; ++i)
            if (!strcmp(stage_names[i], current)) slot = i;
        if (slot < 0 && stage_count < MAX_STAGES) {
            slot = stage_count++;
            snprintf(stage_names[slot], sizeof stage_names[slot], "%s", current);
            stage_seconds[slot] = 0;
        }
    }
    double frac = total ? (double)done / (double)total : 1.0, elapsed = t - start;
    if (slot >= 0) stage_seconds[slot] = elapsed;   /* a stage's time: its first report to its last */
    if (c->quiet) return interrupted;
    char eta[32] = "--";
    if (frac > 0.01 && frac < 1.0) snprintf(eta, sizeof eta, "%.0f s", elapsed * (1.0 - frac) / frac);
    else if (frac >= 1.0) snprintf(eta, sizeof eta, "done");
    if (c->progress == CLI_PROGRESS_JSON) {
        /* Scripts: an object per whole percent, and at each stage's start and end. */
        const int percent = (int)(frac * 100.0);
        if (percent > logged) {
            logged = percent;
            const double eta_s = frac > 0.01 && frac < 1.0 ? elapsed * (1.0 - frac) / frac : frac >= 1.0 ? 0.0 : -1.0;
            char name[130];
            size_t k = 0;
            for (const char *p = stage; *p && k + 2 < sizeof name; ++p) {   /* stage names are plain text; keep JSON valid anyway */
                if (*p == '"' || *p == '\\') name[k++] = '\\';
                name[k++] = (unsigned char)*p < 0x20 ? ' ' : *p;
            }
            name[k] = 0;
            fprintf(stderr, "{\"stage\": \"%s\", \"done\": %llu, \"total\": %llu, \"percent\": %.1f, \"elapsed_s\": %.3f, \"eta_s\": %.3f}\n", name,
                    (unsigned long long)done, (unsigned long long)total, 100.0 * frac, elapsed, eta_s);
            fflush(stderr);
        }
        return interrupted;
    }
    if (c->progress == CLI_PROGRESS_LINES || !isatty(STDERR_FILENO)) {
        /* Logs, CI, nohup: a line when a stage starts and at every tenth, no control characters. */
        const int tenth = (int)(frac * 10.0);
        if (tenth > logged) {
            logged = tenth;
            fprintf(stderr, "prt %s: %s %3.0f%%  %.1f s  ETA %s\n", c->cmd, stage, 100.0 * frac, elapsed, eta);
            fflush(stderr);
        }
        return interrupted;
    }
    int width = 30, filled = (int)(frac * width);
    char bar[32];
    for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
    bar[width] = 0;
    fprintf(stderr, "\r%-14s [%s] %5.1f%%  %6.1f s  ETA %-8s", stage, bar, 100.0 * frac, elapsed, eta);
    if (frac >= 1.0) fputc('\n', stderr);
    fflush(stderr);
    return interrupted;
}

/* ---- camera ---- */
int cli_view_option(const cli *c, cli_view *v, int opt, const char *arg)
{
    switch (opt) {
    case OPT_WIDTH: if (!cli_parse_int(arg, 1, 8192, &v->width)) { cli_usage(c, "--width must be 1..8192"); return -1; } return 1;
    case OPT_HEIGHT: if (!cli_parse_int(arg, 1, 8192, &v->height)) { cli_usage(c, "--height must be 1..8192"); return -1; } return 1;
    case OPT_VIEW:
        if (!cli_parse_vec3(arg, false, v->view)) { cli_usage(c, "--view takes X,Y,Z"); return -1; }
        if (v->view[0] == 0 && v->view[1] == 0 && v->view[2] == 0) { cli_usage(c, "--view is a direction towards the camera: not 0,0,0"); return -1; }
        v->have_view = true;
        return 1;
    case OPT_EYE: if (!cli_parse_vec3(arg, false, v->eye)) { cli_usage(c, "--eye takes X,Y,Z"); return -1; } v->have_eye = true; return 1;
    case OPT_TARGET: if (!cli_parse_vec3(arg, false, v->target)) { cli_usage(c, "--target takes X,Y,Z"); return -1; } v->have_target = true; return 1;
    case OPT_FOV:
        if (!cli_parse_float(arg, &v->fov) || v->fov <= 1 || v->fov >= 179) { cli_usage(c, "--fov must be in (1, 179)"); return -1; }
        v->have_fov = true;
        return 1;
    case OPT_EXPOSURE: if (!cli_parse_float(arg, &v->save.exposure_stops)) { cli_usage(c, "--exposure takes a number of stops"); return -1; } return 1;
    case OPT_TONEMAP:
        if (!strcasecmp(arg, "reinhard")) v->save.tonemap = 1;
        else if (!strcasecmp(arg, "clamp")) v->save.tonemap = 2;
        else { cli_usage(c, "--tonemap must be reinhard or clamp"); return -1; }
        return 1;
    case OPT_BACKGROUND: if (!cli_parse_vec3(arg, true, v->background)) { cli_usage(c, "--background takes R,G,B"); return -1; } return 1;
    }
    return 0;
}

void cli_view_camera(const cli *c, const cli_view *v, const float *p, size_t nv, const uint32_t *indices, size_t nt, float aspect,
                     prt_camera *cam)
{
    cli_view_camera_boxes(c, v, p, nv, indices, nt, NULL, 0, aspect, cam);
}

void cli_view_camera_boxes(const cli *c, const cli_view *v, const float *p, size_t nv, const uint32_t *indices, size_t nt, const float *boxes,
                           int box_count, float aspect, prt_camera *cam)
{
    if (v->have_eye) {   /* no framing to find: the camera is given */
        memset(cam, 0, sizeof *cam);
        memcpy(cam->eye, v->eye, sizeof v->eye);
        memcpy(cam->target, v->target, sizeof v->target);
        cam->up[1] = 1;
        cam->fov_y_deg = v->fov;
        return;
    }
    /* The boxes' corners join the vertices as points no triangle uses: the framing's bounds
     * take them in, its rays still meet only the mesh. */
    float *all = box_count > 0 ? malloc((nv + 8 * (size_t)box_count) * 3 * sizeof(float)) : NULL;
    if (all) {
        memcpy(all, p, nv * 3 * sizeof(float));
        for (int b = 0; b < box_count; ++b)
            for (int k = 0; k < 8; ++k)
                for (int a = 0; a < 3; ++a) all[(nv + 8 * (size_t)b + (size_t)k) * 3 + (size_t)a] = boxes[b * 6 + ((k >> a) & 1) * 3 + a];
    }
    prt_camera_frame_mesh(c ? c->ctx : NULL, all ? all : p, all ? nv + 8 * (size_t)box_count : nv, indices, nt, v->have_view ? v->view : NULL,
                          v->have_fov ? v->fov : 0, aspect, cam);
    free(all);
}

int cli_scene_media_boxes(const prt_scene *s, float boxes[CLI_MAX_MEDIA * 6])
{
    int n = 0;
    prt_volume_desc vd;
    for (int i = 0; i < prt_scene_volume_count(s) && n < CLI_MAX_MEDIA; ++i)
        if (!prt_scene_volume(s, i, &vd)) {
            memcpy(boxes + n * 6, vd.lo, sizeof vd.lo);
            memcpy(boxes + n * 6 + 3, vd.hi, sizeof vd.hi);
            n++;
        }
    return n;
}

int cli_transfer_media_boxes(const prt_transfer *t, float boxes[CLI_MAX_MEDIA * 6])
{
    /* The file's description lists its media (any method that keeps them): "volumes", each with a
     * "min" and "max" corner. */
    char *text = NULL;
    if (prt_transfer_describe(t, NULL, 1, &text) || !text) return 0;
    cJSON *root = cJSON_Parse(text);
    free(text);
    int n = 0;
    const cJSON *vol;
    cJSON_ArrayForEach(vol, cJSON_GetObjectItemCaseSensitive(root, "volumes"))
    {
        const cJSON *lo = cJSON_GetObjectItemCaseSensitive(vol, "min"), *hi = cJSON_GetObjectItemCaseSensitive(vol, "max");
        if (n >= CLI_MAX_MEDIA || cJSON_GetArraySize(lo) != 3 || cJSON_GetArraySize(hi) != 3) continue;
        bool ok = true;
        for (int a = 0; a < 3; ++a) {
            const cJSON *x = cJSON_GetArrayItem(lo, a), *y = cJSON_GetArrayItem(hi, a);
            ok = ok && cJSON_IsNumber(x) && cJSON_IsNumber(y) && isfinite(x->valuedouble) && isfinite(y->valuedouble);
            if (ok) { boxes[n * 6 + a] = (float)x->valuedouble; boxes[n * 6 + 3 + a] = (float)y->valuedouble; }
        }
        n += ok;
    }
    cJSON_Delete(root);
    return n;
}

/* ---- scene ---- */
size_t cli_inside_points(const cli_light *l, const cli_view *v, float out[CLI_MAX_INSIDE_POINTS * 3])
{
    size_t n = 0;
    for (int i = 0; l && l->set_lights && i < l->light_count; ++i)
        if (l->lights[i].type != PRT_LIGHT_DIRECTIONAL) memcpy(out + n++ * 3, l->lights[i].position, 3 * sizeof(float));
    if (v && v->have_eye) memcpy(out + n++ * 3, v->eye, 3 * sizeof(float));
    return n;
}

int cli_scene_option(cli *c, prt_scene_desc *sd, int opt, const char *arg)
{
    switch (opt) {
    case OPT_PROGRESS:
        if (!strcmp(arg, "auto")) c->progress = CLI_PROGRESS_AUTO;
        else if (!strcmp(arg, "lines")) c->progress = CLI_PROGRESS_LINES;
        else if (!strcmp(arg, "json")) c->progress = CLI_PROGRESS_JSON;
        else { cli_usage(c, "--progress must be auto, lines or json"); return -1; }
        return 1;
    case OPT_MAX_EDGE:
        if (!cli_parse_float(arg, &sd->max_edge) || sd->max_edge <= 0) { cli_usage(c, "--max-edge must be > 0"); return -1; }
        return 1;
    case OPT_ALBEDO:
    case OPT_DEFAULT_ALBEDO:
        if (!cli_parse_vec3(arg, true, sd->default_albedo) || sd->default_albedo[0] < 0 || sd->default_albedo[0] > 1 ||
            sd->default_albedo[1] < 0 || sd->default_albedo[1] > 1 || sd->default_albedo[2] < 0 || sd->default_albedo[2] > 1) {
            cli_usage(c, "--%s takes R,G,B (or one value) in [0, 1]", opt == OPT_ALBEDO ? "albedo" : "default-albedo");
            return -1;
        }
        if (opt == OPT_ALBEDO) sd->override_albedo = 1;
        sd->default_albedo_given = 1;   /* --albedo 0 means black, not the 0.7 default */
        return 1;
    case OPT_CREASE:
        if (!cli_parse_float(arg, &sd->crease_angle_deg) || sd->crease_angle_deg <= 0 || sd->crease_angle_deg > 180) {
            cli_usage(c, "--crease-angle must be in (0, 180]");
            return -1;
        }
        return 1;
    case OPT_WINDING:
        if (!strcasecmp(arg, "auto")) sd->winding = PRT_WINDING_AUTO;
        else if (!strcasecmp(arg, "keep")) sd->winding = PRT_WINDING_KEEP;
        else if (!strcasecmp(arg, "flip")) sd->winding = PRT_WINDING_FLIP;
        else { cli_usage(c, "--winding must be auto, keep or flip"); return -1; }
        return 1;
    case OPT_IMPORT_TIMEOUT:
        if (!cli_parse_float(arg, &sd->import_seconds) || !(sd->import_seconds > 0) || sd->import_seconds > 1e6f) {
            cli_usage(c, "--import-timeout must be seconds in (0, 1e6]");
            return -1;
        }
        return 1;
    }
    return 0;
}

/* ---- lighting ---- */
int cli_light_option(const cli *c, cli_light *l, int opt, const char *arg)
{
    switch (opt) {
    case OPT_ENV:
        l->set_source = true;
        l->env_none = !strcasecmp(arg, "none");
        l->env_path = l->env_none ? NULL : arg;
        return 1;
    case OPT_LAYOUT:
        if (!strcasecmp(arg, "auto")) l->layout = PRT_ENV_AUTO;
        else if (!strcasecmp(arg, "latlong")) l->layout = PRT_ENV_LATLONG;
        else if (!strcasecmp(arg, "angular")) l->layout = PRT_ENV_ANGULAR;
        else if (!strcasecmp(arg, "cross")) l->layout = PRT_ENV_VCROSS;
        else { cli_usage(c, "--layout must be latlong, angular, cross or auto (got '%s')", arg); return -1; }
        return 1;
    case OPT_ROTATE: {
        float v[3] = {0, 0, 0};
        char buf[128];
        snprintf(buf, sizeof buf, "%s", arg);
        int n = 0;
        char *save = NULL;
        for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save))
            if (n == 3 || !cli_parse_float(tok, &v[n++])) { cli_usage(c, "--rotate takes YAW[,PITCH[,ROLL]] in degrees"); return -1; }
        if (n == 0) { cli_usage(c, "--rotate takes YAW[,PITCH[,ROLL]] in degrees"); return -1; }
        memcpy(l->rotate, v, sizeof v);
        l->set_rotate = true;
        return 1;
    }
    case OPT_INTENSITY:
        if (!cli_parse_float(arg, &l->intensity) || l->intensity < 0) { cli_usage(c, "--intensity must be a number >= 0"); return -1; }
        l->set_intensity = true;
        return 1;
    case OPT_ALBEDO_OF: {
        const char *eq = strrchr(arg, '=');
        if (!eq || eq == arg || eq - arg >= 64 || l->paint_count == CLI_MAX_LIGHTS ||
            !cli_parse_vec3(eq + 1, true, l->paint[l->paint_count].rgb)) {
            cli_usage(c, "--albedo-of takes NAME=R,G,B (or NAME=V for grey), at most %d times", CLI_MAX_LIGHTS);
            return -1;
        }
        const float *rgb = l->paint[l->paint_count].rgb;
        for (int k = 0; k < 3; ++k)
            if (!(rgb[k] >= 0.0f && rgb[k] <= 1.0f)) { cli_usage(c, "--albedo-of %s: albedo must lie in [0, 1]", arg); return -1; }
        memcpy(l->paint[l->paint_count].name, arg, (size_t)(eq - arg));
        l->paint[l->paint_count++].name[eq - arg] = 0;
        return 1;
    }
    case OPT_BRDF_OF: {
        const char *eq = strchr(arg, '=');
        prt_brdf b;
        if (!eq || eq == arg || eq - arg >= 64 || strlen(eq + 1) >= 128 || l->brdf_of_count == CLI_MAX_LIGHTS) {
            cli_usage(c, "--brdf-of takes NAME=SPEC (phong:32:0.5:0.3, ...), at most %d times", CLI_MAX_LIGHTS);
            return -1;
        }
        if (prt_brdf_parse(eq + 1, &b)) { cli_usage(c, "--brdf-of %s: %s", arg, prt_last_error()); return -1; }
        memcpy(l->brdf_of[l->brdf_of_count].name, arg, (size_t)(eq - arg));
        l->brdf_of[l->brdf_of_count].name[eq - arg] = 0;
        snprintf(l->brdf_of[l->brdf_of_count++].spec, 128, "%s", eq + 1);
        return 1;
    }
    case OPT_PAINT:
        l->paint_path = arg;
        return 1;
    case OPT_CONTROL: {
        const char *eq = strchr(arg, '=');
        char *end = NULL;
        errno = 0;
        const long v = eq ? strtol(eq + 1, &end, 10) : 0;
        if (!eq || eq == arg || eq - arg >= 64 || l->control_count == PRT_MAX_CONTROLS || end == eq + 1 || *end || errno || v < INT_MIN ||
            v > INT_MAX) {
            cli_usage(c, "--control takes NAME=INTEGER (for example bounces=8)");
            return -1;
        }
        memcpy(l->control[l->control_count].name, arg, (size_t)(eq - arg));
        l->control[l->control_count].name[eq - arg] = 0;
        l->control[l->control_count++].value = (int)v;
        return 1;
    }
    case OPT_BRDF:
    case OPT_BRDF_ALL:
        if (l->have_brdf && l->brdf_everywhere != (opt == OPT_BRDF_ALL)) { cli_usage(c, "give --brdf or --brdf-all, not both"); return -1; }
        if (prt_brdf_parse(arg, &l->brdf)) { cli_usage(c, "--%s: %s", opt == OPT_BRDF ? "brdf" : "brdf-all", prt_last_error()); return -1; }
        l->have_brdf = true;
        l->brdf_everywhere = opt == OPT_BRDF_ALL;
        return 1;
    case OPT_SUN:
        if (!cli_parse_vec3(arg, false, l->sun_dir)) { cli_usage(c, "--sun takes X,Y,Z"); return -1; }
        l->set_source = true;
        l->env_none = false;
        l->env_path = NULL;
        return 1;
    case OPT_LIGHT:
        l->set_lights = true;
        if (!strcasecmp(arg, "none")) { l->light_count = 0; return 1; }
        if (l->light_count == CLI_MAX_LIGHTS) { cli_usage(c, "at most %d --light options", CLI_MAX_LIGHTS); return -1; }
        if (cli_parse_light(arg, &l->lights[l->light_count])) { cli_usage(c, "--light: %s", prt_last_error()); return -1; }
        l->light_count++;
        return 1;
    case OPT_EMISSION:
        if (!cli_parse_float(arg, &l->emission) || l->emission < 0) { cli_usage(c, "--emission must be a number >= 0"); return -1; }
        l->set_emission = true;
        return 1;
    }
    return 0;
}

/* The environment desc: the file's (or scene's), with the command line's overrides. */
static prt_environment_desc environment(const cli_light *l, bool has_env, const prt_environment_desc *file_env, bool has_lights)
{
    prt_environment_desc e;
    memset(&e, 0, sizeof e);
    if (has_env) e = *file_env;
    else e.none = has_lights;   /* a scene with lights of its own and no environment is lit by them alone */
    if (l->set_source) {
        e.none = l->env_none;
        memset(e.path, 0, sizeof e.path);
        e.layout = l->layout;
        memcpy(e.sun_dir, l->sun_dir, sizeof e.sun_dir);
        if (l->env_path) snprintf(e.path, sizeof e.path, "%s", l->env_path);
    }
    if (l->set_rotate) memcpy(e.rotate_deg, l->rotate, sizeof e.rotate_deg);
    if (l->set_intensity) e.intensity = l->intensity;
    return e;
}

/* The profiles of the ies lights parsed in this run: the command line's lights are plain values
 * copied between arrays, so the run owns their profiles. */
static prt_ies *kept_profiles[1024];
static int kept_count;

prt_status cli_parse_light(const char *spec, prt_light *out)
{
    prt_light l;
    prt_status st = prt_light_parse(spec, &l);
    if (st) return st;
    /* (Past 1024 ies lights in one command line the rest are left to the end of the process.) */
    if (l.type == PRT_LIGHT_IES && kept_count < (int)(sizeof kept_profiles / sizeof *kept_profiles)) kept_profiles[kept_count++] = l.profile;
    *out = l;
    return PRT_OK;
}

void cli_release_lights(void)
{
    while (kept_count > 0) prt_ies_release(kept_profiles[--kept_count]);
}

prt_status cli_lighting(const cli *c, const cli_light *l, const prt_transfer *t, const prt_scene *s, prt_lighting **out)
{
    *out = NULL;
    prt_environment_desc file_env;
    memset(&file_env, 0, sizeof file_env);
    bool has_env = t ? prt_transfer_environment(t, &file_env) : s ? prt_scene_environment(s, &file_env) : false;
    const int nfile = t ? prt_transfer_light_count(t) : s ? prt_scene_light_count(s) : 0;
    /* What the scene names that the file's method cannot relight is left out, with a warning;
     * what the command line asks for explicitly is refused later by the method, by name. */
    const prt_method *method = t ? prt_transfer_method(t) : l->method;
    const unsigned can = method ? prt_method_lighting(method) : ~0u;
    bool emits = (t ? prt_transfer_emission(t) != NULL : s ? prt_scene_emission(s) != NULL : false) && !(l->set_emission && l->emission == 0);
    unsigned dropped = 0;
    if (emits && !l->set_emission && !(can & PRT_LIGHTS_EMISSIVE)) { emits = false; dropped |= PRT_LIGHTS_EMISSIVE; }
    int kept = 0;
    for (int i = 0; i < nfile; ++i) {
        const prt_light *li = t ? prt_transfer_light(t, i) : prt_scene_light(s, i);
        if (can & prt_light_type_bit(li->type)) kept++;
        else if (!l->set_lights) dropped |= prt_light_type_bit(li->type);
    }
    /* A scene that names no environment is lit by its own lights and emitters when it has any
     * the method relights (lights the command line puts in their place count as its own), else
     * by the procedural sky: --light added to a plain scene adds to the sky. */
    const bool own = (l->set_lights ? kept > 0 && l->light_count > 0 : kept > 0) || emits;
    prt_environment_desc e = environment(l, has_env, &file_env, own);
    /* A method that relights no distant light is not given the fallback sky; an environment
     * the scene names is left out with the warning below. */
    if (!(can & PRT_LIGHTS_ENVIRONMENT) && !l->set_source && !e.none) {
        if (has_env) dropped |= PRT_LIGHTS_ENVIRONMENT;
        e.none = 1;
    }
    prt_lighting *lighting = NULL;
    prt_status st = prt_lighting_create(&lighting);
    if (!st) st = prt_lighting_set_environment(lighting, &e);
    if (!st && l->set_intensity) prt_lighting_set_intensity(lighting, l->intensity);
    if (l->set_lights)
        for (int i = 0; i < l->light_count && !st; ++i) st = prt_lighting_add(lighting, &l->lights[i], NULL);
    else
        for (int i = 0; i < nfile && !st; ++i) {
            const prt_light *li = t ? prt_transfer_light(t, i) : prt_scene_light(s, i);
            if (can & prt_light_type_bit(li->type)) st = prt_lighting_add(lighting, li, NULL);
        }
    if (l->set_emission) prt_lighting_set_emission(lighting, l->emission);
    else if (dropped & PRT_LIGHTS_EMISSIVE) prt_lighting_set_emission(lighting, 0);
    if (st) { prt_lighting_release(lighting); return st; }
    if (dropped && !c->quiet) {
        char names[256] = "", others[128];
        size_t at = 0;
        for (unsigned bit = 1; bit <= PRT_LIGHTS_IES; bit <<= 1)
            if ((dropped & bit) && at < sizeof names) at += (size_t)snprintf(names + at, sizeof names - at, "%s%s", at ? " and " : "", prt_lights_bit_name(bit));
        prt_methods_relighting(dropped, others, sizeof others);
        fprintf(stderr, "prt %s: warning: method %s cannot relight the scene's %s: left out (%s%sprt reference path-traces them)\n", c->cmd,
                prt_method_name(method), names, others[0] ? others : "", others[0] ? " can; " : "");
    }
    if (!prt_lighting_content(lighting) || (prt_lighting_content(lighting) == PRT_LIGHTS_EMISSIVE && !emits))
        if (!c->quiet) fprintf(stderr, "prt %s: warning: nothing lights the scene (no environment, no lights, no emitters): the result is black\n", c->cmd);
    *out = lighting;
    return PRT_OK;
}

prt_status cli_light_project(const cli *c, const cli_light *l, int order, prt_sh_light *out, prt_env_layout *layout)
{
    (void)c;
    prt_environment_desc e = environment(l, false, NULL, false);
    if (e.none) { cli_error(c, "--env none leaves nothing to project"); return PRT_ERR_INVALID_ARG; }
    prt_lighting *lighting = NULL;
    prt_status st = prt_lighting_create(&lighting);
    if (!st) st = prt_lighting_set_environment(lighting, &e);
    if (!st) st = prt_envmap_project_sh(prt_lighting_envmap(lighting), order, out);
    if (!st && layout) *layout = prt_envmap_layout(prt_lighting_envmap(lighting));
    if (!st && (l->rotate[0] != 0 || l->rotate[1] != 0 || l->rotate[2] != 0)) {
        double rot[9];
        prt_rotation_from_euler_deg(l->rotate[0], l->rotate[1], l->rotate[2], rot);
        st = prt_sh_light_rotate(out, rot);
    }
    if (!st) prt_sh_light_scale(out, l->intensity);
    prt_lighting_release(lighting);
    return st;
}

/* ---- variants and relighting ---- */
bool cli_relight_kinds(cli_kinds *r, char *list)
{
    r->count = 0;
    char *save = NULL;
    for (char *tok = strtok_r(list, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (r->count == (int)(sizeof r->variants / sizeof r->variants[0])) return false;
        r->variants[r->count++] = tok;
    }
    return r->count > 0;
}

int cli_relight_resolve(const cli *c, const cli_kinds *r, const prt_transfer *t, int drawing, int *indices, int max)
{
    int n = 0;
    if (!r->count) {
        indices[n++] = prt_transfer_default_variant(t, drawing);
        return n;
    }
    for (int i = 0; i < r->count; ++i) {
        if (!strcasecmp(r->variants[i], "all")) {
            for (int v = 0; v < prt_transfer_variant_count(t) && n < max; ++v) indices[n++] = v;
            continue;
        }
        int v = prt_transfer_find_variant(t, r->variants[i]);
        if (v < 0) { cli_error(c, "%s", prt_last_error()); return -1; }
        if (n == max) { cli_error(c, "--kind takes at most %d names", max); return -1; }
        indices[n++] = v;
    }
    return n;
}

prt_status cli_brdf_choice(const cli *c, const cli_light *l, const prt_transfer *t, int **out)
{
    *out = NULL;
    if (!l || !l->brdf_of_count) return PRT_OK;
    const int ns = prt_transfer_surface_count(t);
    int *choice = malloc(((size_t)ns + 1) * sizeof *choice);
    if (!choice) { cli_error(c, "out of memory"); return PRT_ERR_NO_MEMORY; }
    for (int k = 0; k <= ns; ++k) choice[k] = -1;
    bool ok = false;   /* until every --brdf-of is resolved */
    for (int i = 0; i < l->brdf_of_count; ++i) {
        ok = false;
        int k = 1;
        while (k <= ns && strcmp(prt_transfer_surface_name(t, k), l->brdf_of[i].name)) ++k;
        char list[1024] = "";
        size_t at = 0;
        if (k > ns) {
            for (int j = 1; j <= ns && at < sizeof list; ++j) at += (size_t)snprintf(list + at, sizeof list - at, "%s%s", j > 1 ? ", " : "", prt_transfer_surface_name(t, j));
            cli_error(c, "--brdf-of: the file has no surface '%s' (%s%s)", l->brdf_of[i].name, ns ? "it has " : "it names none", list);
            break;
        }
        const int n = prt_transfer_brdf_set(t, k, -1, NULL);
        if (!n) {
            cli_error(c, "--brdf-of: surface '%s' has no BRDF set in this file (bake it with the spectral method from a scene whose material '%s' "
                         "lists \"brdfs\")", l->brdf_of[i].name, l->brdf_of[i].name);
            break;
        }
        /* Compared as prt_brdf_format writes them: the spelling on the command line need not match. */
        prt_brdf want, b;
        char w[128], e[128];
        prt_brdf_parse(l->brdf_of[i].spec, &want);
        prt_brdf_format(&want, w, sizeof w);
        for (int j = 0; j < n; ++j) {
            prt_transfer_brdf_set(t, k, j, &b);
            prt_brdf_format(&b, e, sizeof e);
            if (!strcmp(e, w)) choice[k] = j;
            if (at < sizeof list) at += (size_t)snprintf(list + at, sizeof list - at, "%s%s", j ? ", " : "", e);
        }
        if (choice[k] < 0) {
            cli_error(c, "--brdf-of %s=%s: not in the set baked for '%s' (%s); switching needs a BRDF's SH projection, made at bake time",
                      l->brdf_of[i].name, l->brdf_of[i].spec, l->brdf_of[i].name, list);
            break;
        }
        ok = true;
    }
    if (!ok) { free(choice); ((cli *)c)->reported = true; return PRT_ERR_INVALID_ARG; }
    *out = choice;
    return PRT_OK;
}

prt_status cli_painted_albedo_for(const cli *c, const cli_light *l, const prt_transfer *t, const int *brdf_of, float **out)
{
    *out = NULL;
    const int ns = prt_transfer_surface_count(t);
    bool any = false;
    for (int k = 1; brdf_of && k <= ns; ++k) any |= brdf_of[k] >= 0;
    if (!any && (!l || !l->paint_count)) return PRT_OK;
    const size_t nv = prt_transfer_vertex_count(t);
    float *a = malloc(nv * 3 * sizeof(float));
    if (!a) { cli_error(c, "out of memory"); return PRT_ERR_NO_MEMORY; }
    memcpy(a, prt_transfer_albedo(t), nv * 3 * sizeof(float));
    /* A chosen BRDF's diffuse part first, so that --albedo-of recolours over it. */
    for (int k = 1; any && k <= ns; ++k) {
        prt_brdf b;
        if (brdf_of[k] < 0 || prt_transfer_brdf_set(t, k, brdf_of[k], &b) <= brdf_of[k]) continue;
        float rgb[3];
        prt_brdf_lambert_albedo(&b, rgb);
        prt_transfer_paint_albedo(t, prt_transfer_surface_name(t, k), rgb, a);
    }
    for (int i = 0; l && i < l->paint_count; ++i) {
        prt_status st = prt_transfer_paint_albedo(t, l->paint[i].name, l->paint[i].rgb, a);
        if (st) { cli_error(c, "--albedo-of: %s", prt_last_error()); ((cli *)c)->reported = true; free(a); return st; }
    }
    *out = a;
    return PRT_OK;
}

prt_status cli_painted_albedo(const cli *c, const cli_light *l, const prt_transfer *t, float **out)
{
    *out = NULL;
    int *choice = NULL;
    prt_status st = cli_brdf_choice(c, l, t, &choice);
    if (!st) st = cli_painted_albedo_for(c, l, t, choice, out);
    free(choice);
    return st;
}

int cli_controls(const cli *c, const cli_light *l, const prt_transfer *t, int values[PRT_MAX_CONTROLS])
{
    const prt_control_desc *cd;
    const int n = prt_transfer_controls(t, &cd);
    for (int i = 0; i < n; ++i) prt_transfer_control_range(t, i, NULL, NULL, &values[i]);
    for (int k = 0; l && k < l->control_count; ++k) {
        int i = 0;
        while (i < n && strcmp(cd[i].name, l->control[k].name)) ++i;
        char names[256] = "";
        for (int j = 0; j < n; ++j) snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", j ? ", " : "", cd[j].name);
        if (i == n) { cli_error(c, "--control: the file's method has no setting '%s' (it has %s)", l->control[k].name, n ? names : "none"); return -1; }
        int lo, hi, def;
        prt_transfer_control_range(t, i, &lo, &hi, &def);
        if (l->control[k].value < lo || l->control[k].value > hi) {
            cli_error(c, "--control %s=%d: out of range %d..%d for this file", cd[i].name, l->control[k].value, lo, hi);
            return -1;
        }
        values[i] = l->control[k].value;
    }
    return n;
}

bool cli_parse_accumulate(const char *arg, bool *gpu)
{
    if (!strcasecmp(arg, "cpu")) *gpu = false;
    else if (!strcasecmp(arg, "gpu")) *gpu = true;
    else return false;
    return true;
}

bool cli_check_accumulate(const cli *c, const prt_transfer *t, bool per_vertex)
{
    if (!prt_method_gpu_passes(prt_transfer_method(t))) {
        char names[256] = "";
        for (int i = 0, at = 0; i < prt_method_count() && at < (int)sizeof names; ++i)
            if (prt_method_gpu_passes(prt_method_at(i)))
                at += snprintf(names + at, sizeof names - (size_t)at, "%s%s", at ? ", " : "", prt_method_name(prt_method_at(i)));
        cli_error(c, "--accumulate gpu applies to files of methods with GPU passes (%s), and this is a %s file", names,
                  prt_method_name(prt_transfer_method(t)));
        return false;
    }
    if (per_vertex && prt_method_light_map(prt_transfer_method(t))) {
        cli_error(c, "--accumulate gpu draws the light map per texel; --per-vertex asks for vertex colours");
        return false;
    }
    return true;
}

prt_status cli_painting(const cli *c, const cli_light *l, const prt_transfer *t, prt_relight_desc *d, float **owned)
{
    (void)c;   /* prt_last_error says what failed; the caller reports it */
    *owned = NULL;
    if (!l || !l->paint_path) return PRT_OK;
    prt_status st = prt_paint_load(t, l->paint_path, owned);
    if (!st) st = prt_paint_size(t, &d->paint_width, &d->paint_height);
    if (st) { free(*owned); *owned = NULL; return st; }
    d->paint = *owned;
    return PRT_OK;
}

bool cli_parse_time(const cli *c, const char *arg, double *time)
{
    float f;
    if (cli_parse_float(arg, &f) && isfinite(f)) { *time = f; return true; }
    cli_usage(c, "--time takes a number of frames (0 = the first key frame)");
    return false;
}

prt_status cli_at_time(cli *c, const char *path, double time, prt_transfer **t)
{
    prt_transfer *posed = NULL;
    const prt_status st = prt_transfer_at_time(c->ctx, *t, time, &posed);
    if (st) {
        cli_error(c, "--time %g: '%s': %s", time, path, prt_last_error());
        c->reported = true;
        return st;
    }
    prt_transfer_release(*t);
    *t = posed;
    return PRT_OK;
}

prt_status cli_relight(const cli *c, const prt_transfer *t, const prt_lighting *lighting, const cli_light *l, int variant, bool per_vertex,
                       bool with_indirect, prt_relit *out)
{
    prt_relight_desc d;
    memset(&d, 0, sizeof d);
    d.variant = variant;
    d.per_vertex = per_vertex;
    d.with_indirect = with_indirect;
    d.brdf = l && l->have_brdf ? &l->brdf : NULL;
    d.brdf_everywhere = l && l->brdf_everywhere;
    d.no_pixel_lights = l && l->whole_texels;
    d.gpu_finish = l && l->gpu_finish;
    d.leave_out_unreachable = !(l && l->set_lights);   /* the scene's own lamps: left out with a warning; lights asked for: refused */
    int controls[PRT_MAX_CONTROLS];
    const int nc = cli_controls(c, l, t, controls);
    if (nc < 0) { ((cli *)c)->reported = true; return PRT_ERR_INVALID_ARG; }
    d.controls = nc ? controls : NULL;
    float *albedo = NULL;
    int *brdf_of = NULL;
    prt_status st = cli_brdf_choice(c, l, t, &brdf_of);
    if (!st) st = cli_painted_albedo_for(c, l, t, brdf_of, &albedo);
    if (st) { free(brdf_of); return st; }
    d.albedo = albedo;
    d.brdf_of = brdf_of;
    float *painting = NULL;
    st = cli_painting(c, l, t, &d, &painting);
    if (!st) st = prt_relight(c->ctx, t, lighting, &d, out);
    free(painting);
    free(albedo);
    free(brdf_of);
    if (st == PRT_ERR_INVALID_ARG) {
        /* Lighting the method refuses: say how to leave it out. */
        const unsigned refused = prt_relight_needs(t, lighting) & ~prt_method_lighting(prt_transfer_method(t));
        if (refused) {
            const bool lights = refused & (PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_SPHERE | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_IES), emit = refused & PRT_LIGHTS_EMISSIVE,
                       env = refused & PRT_LIGHTS_ENVIRONMENT;
            char how[96] = "";
            snprintf(how, sizeof how, "%s%s%s%s%s", lights ? "--light none" : "", lights && (emit || env) ? ", " : "", emit ? "--emission 0" : "",
                     emit && env ? ", " : "", env ? "--env none" : "");
            cli_error(c, "%s (to leave %s out: %s)", prt_last_error(), lights + emit + env > 1 ? "them" : "it", how);
            ((cli *)c)->reported = true;
        }
    }
    return st;
}

/* ---- methods ---- */
const prt_method *cli_method_from_argv(const cli *c, int argc, char **argv)
{
    const char *name = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--")) break;
        if (!strcmp(argv[i], "--method") && i + 1 < argc) name = argv[++i];
        else if (!strncmp(argv[i], "--method=", 9)) name = argv[i] + 9;
    }
    if (!name) return prt_method_default();
    const prt_method *m = prt_method_find(name);
    if (!m) {
        char list[256] = "";
        const int n = prt_method_count();
        for (int i = 0; i < n; ++i)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i == 0 ? "" : i == n - 1 ? " or " : ", ", prt_method_name(prt_method_at(i)));
        cli_usage(c, "--method must be %s (got '%s')", list, name);
    }
    return m;
}

void cli_print_wrapped(FILE *f, int col, int indent, const char *text)
{
    if (col < indent) { fprintf(f, "%*s", indent - col, ""); col = indent; }
    bool words = false;   /* a word of text is on the current line */
    for (const char *p = text; p && *p;) {
        while (*p == ' ' || *p == '\n' || *p == '\t') ++p;
        const int len = (int)strcspn(p, " \n\t");
        if (!len) break;
        /* A word wider than the whole column still goes out, alone on its line. */
        if (col > indent && col + (words ? 1 : 0) + len > CLI_HELP_COLUMNS) {
            fprintf(f, "\n%*s", indent, "");
            col = indent;
            words = false;
        }
        if (words) { fputc(' ', f); ++col; }
        fprintf(f, "%.*s", len, p);
        col += len;
        words = true;
        p += len;
    }
    fputc('\n', f);
}

void cli_print_method_options(FILE *f, const prt_method *m, cli_option_list_fn list, const char *heading, bool summary)
{
    const prt_option_desc *o;
    int n = list(m, &o);
    if (!n) return;
    char title[128];
    snprintf(title, sizeof title, heading, prt_method_name(m));
    /* Option texts are reflowed: their authors' line breaks cannot know where they start. */
    if (summary) cli_print_wrapped(f, fprintf(f, "%s ", title), 6, prt_method_summary(m));
    else fprintf(f, "%s\n", title);
    for (int i = 0; i < n; ++i) {
        char head[64];
        snprintf(head, sizeof head, "--%s%s%s", o[i].name, o[i].arg ? " " : "", o[i].arg ? o[i].arg : "");
        int col = 0;
        if (strlen(head) <= 18) col = fprintf(f, "      %-18s ", head);
        else fprintf(f, "      %s\n", head);
        cli_print_wrapped(f, col, 25, o[i].help);
    }
}

int cli_collect_method_options(const prt_method *chosen, cli_option_list_fn list, struct option *opts, int n, int max, const char **names,
                               int max_names, int first_code)
{
    int extra = 0;
    for (int m = -1; m < prt_method_count(); ++m) {
        const prt_method *method = m < 0 ? chosen : prt_method_at(m);
        if (!method || (m >= 0 && method == chosen)) continue;
        const prt_option_desc *o;
        const int count = list(method, &o);
        for (int i = 0; i < count && n < max - 1 && extra < max_names; ++i) {
            bool seen = false;   /* a command's own flag, or another method's option of that name */
            for (int k = 0; k < n && !seen; ++k) seen = !strcmp(opts[k].name, o[i].name);
            if (seen) continue;
            names[extra] = o[i].name;
            opts[n++] = (struct option){o[i].name, o[i].type == PRT_OPTION_FLAG ? no_argument : required_argument, 0, first_code + extra};
            extra++;
        }
    }
    opts[n] = (struct option){0, 0, 0, 0};
    return n;
}

void cli_print_lines(FILE *f, const char *prefix, const char *text)
{
    for (const char *p = text; p && *p;) {
        const char *nl = strchr(p, '\n');
        int len = nl ? (int)(nl - p) : (int)strlen(p);
        fprintf(f, "%s%.*s\n", prefix, len, p);
        p = nl ? nl + 1 : NULL;
    }
}
