#include "cli.h"

#include <errno.h>
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
    cli_error(c, "%s", prt_last_error()[0] ? prt_last_error() : prt_status_string(st));
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

int cli_usage(const cli *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "prt %s: ", c->cmd);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\nTry 'prt %s --help'.\n", c->cmd);
    va_end(ap);
    return EXIT_USAGE;
}

static void log_to_stderr(void *user, prt_log_level level, const char *msg)
{
    const cli *c = user;
    /* Errors are reported once, by the command, from prt_last_error(). */
    if (level == PRT_LOG_WARN && !c->quiet) fprintf(stderr, "prt %s: warning: %s\n", c->cmd, msg);
}

int cli_make_context(cli *c)
{
    prt_context_desc d = {0};
    d.threads = c->threads;
    d.log = log_to_stderr;
    d.log_user = c;
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

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int cli_progress(void *user, const char *stage, uint64_t done, uint64_t total)
{
    const cli *c = user;
    static char current[64];
    static double start;
    if (c->quiet || !isatty(STDERR_FILENO)) return interrupted;
    double t = now_seconds();
    if (strcmp(current, stage) != 0) {
        snprintf(current, sizeof current, "%s", stage);
        start = t;
    }
    double frac = total ? (double)done / (double)total : 1.0, elapsed = t - start;
    char eta[32] = "--";
    if (frac > 0.01 && frac < 1.0) snprintf(eta, sizeof eta, "%.0f s", elapsed * (1.0 - frac) / frac);
    else if (frac >= 1.0) snprintf(eta, sizeof eta, "done");
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
    case OPT_VIEW: if (!cli_parse_vec3(arg, false, v->view)) { cli_usage(c, "--view takes X,Y,Z"); return -1; } v->have_view = true; return 1;
    case OPT_EYE: if (!cli_parse_vec3(arg, false, v->eye)) { cli_usage(c, "--eye takes X,Y,Z"); return -1; } v->have_eye = true; return 1;
    case OPT_TARGET: if (!cli_parse_vec3(arg, false, v->target)) { cli_usage(c, "--target takes X,Y,Z"); return -1; } v->have_target = true; return 1;
    case OPT_FOV: if (!cli_parse_float(arg, &v->fov) || v->fov <= 1 || v->fov >= 179) { cli_usage(c, "--fov must be in (1, 179)"); return -1; } return 1;
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

void cli_view_camera(const cli_view *v, const float *p, size_t nv, float aspect, prt_camera *cam)
{
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (size_t i = 0; i < nv * 3; ++i) {
        if (p[i] < lo[i % 3]) lo[i % 3] = p[i];
        if (p[i] > hi[i % 3]) hi[i % 3] = p[i];
    }
    prt_camera_frame(lo, hi, v->have_view ? v->view : NULL, v->fov, aspect, cam);
    if (v->have_eye) { memcpy(cam->eye, v->eye, sizeof v->eye); memcpy(cam->target, v->target, sizeof v->target); }
}

/* ---- scene ---- */
int cli_scene_option(const cli *c, prt_scene_desc *sd, int opt, const char *arg)
{
    switch (opt) {
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
    }
    return 0;
}

/* ---- lighting ---- */
int cli_light_option(const cli *c, cli_light *l, int opt, const char *arg)
{
    switch (opt) {
    case OPT_ENV: l->env_path = arg; l->set_source = true; return 1;
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
    case OPT_BRDF:
        if (prt_brdf_parse(arg, &l->brdf)) { cli_usage(c, "--brdf: %s", prt_last_error()); return -1; }
        l->have_brdf = true;
        return 1;
    case OPT_SUN:
        if (!cli_parse_vec3(arg, false, l->sun_dir)) { cli_usage(c, "--sun takes X,Y,Z"); return -1; }
        l->set_source = true;
        return 1;
    }
    return 0;
}

void cli_light_defaults_from(cli_light *l, const prt_transfer *t)
{
    prt_environment_desc e;
    if (prt_transfer_environment(t, &e)) cli_light_defaults_from_env(l, &e);
}

void cli_light_defaults_from_scene(cli_light *l, const prt_scene *s)
{
    prt_environment_desc e;
    if (prt_scene_environment(s, &e)) cli_light_defaults_from_env(l, &e);
}

void cli_light_defaults_from_env(cli_light *l, const prt_environment_desc *e)
{
    if (!l->set_source) {
        if (e->path[0]) {
            snprintf(l->path_buf, sizeof l->path_buf, "%s", e->path);
            l->env_path = l->path_buf;
            l->layout = e->layout;
        }
        memcpy(l->sun_dir, e->sun_dir, sizeof l->sun_dir);
    }
    if (!l->set_rotate) memcpy(l->rotate, e->rotate_deg, sizeof l->rotate);
    if (!l->set_intensity && e->intensity > 0) l->intensity = e->intensity;
}

prt_status cli_light_project(const cli *c, const cli_light *l, int order, prt_sh_light *out, prt_envmap **env_out)
{
    (void)c;
    prt_envmap *env = NULL;
    prt_status st;
    if (l->env_path) {
        st = prt_envmap_load(l->env_path, l->layout, &env);
    } else {
        prt_sky_desc sky = {0};
        memcpy(sky.sun_dir, l->sun_dir, sizeof sky.sun_dir);
        st = prt_sky_create(&sky, &env);
    }
    if (st) return st;
    st = prt_envmap_project_sh(env, order < 1 ? 1 : order, out);   /* wavelet-only files have no SH order */
    if (!st && (l->rotate[0] != 0 || l->rotate[1] != 0 || l->rotate[2] != 0)) {
        double rot[9];
        prt_rotation_from_euler_deg(l->rotate[0], l->rotate[1], l->rotate[2], rot);
        st = prt_sh_light_rotate(out, rot);
    }
    if (!st) prt_sh_light_scale(out, l->intensity);
    if (env_out && !st) *env_out = env;
    else prt_envmap_release(env);
    return st;
}

prt_transfer_kind cli_default_kind(const prt_transfer *t)
{
    prt_transfer_info info;
    prt_transfer_get_info(t, &info);
    if (info.kinds == PRT_TRANSFER_WAVELET) return PRT_TRANSFER_WAVELET;
    if (prt_transfer_channels(t, PRT_TRANSFER_INTERREFLECTED)) return PRT_TRANSFER_INTERREFLECTED;
    if (prt_transfer_channels(t, PRT_TRANSFER_SHADOWED)) return PRT_TRANSFER_SHADOWED;
    return PRT_TRANSFER_UNSHADOWED;
}

prt_transfer_kind cli_default_view_kind(const prt_transfer *t)
{
    if (prt_transfer_channels(t, PRT_TRANSFER_WAVELET)) return PRT_TRANSFER_WAVELET;
    if (prt_transfer_channels(t, PRT_TRANSFER_GLOSSY_INTERREFLECTED)) return PRT_TRANSFER_GLOSSY_INTERREFLECTED;
    if (prt_transfer_channels(t, PRT_TRANSFER_GLOSSY_SHADOWED)) return PRT_TRANSFER_GLOSSY_SHADOWED;
    return cli_default_kind(t);
}

prt_status cli_relight(const cli *c, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *sh, const cli_light *l,
                       const float eye[3], float *rgb, float **exit)
{
    *exit = NULL;
    if (kind == PRT_TRANSFER_WAVELET) return cli_relight_wavelet(c, t, l, eye, rgb);
    if (!prt_transfer_kind_is_glossy(kind)) return prt_relight_sh(c->ctx, t, kind, sh, rgb);
    const size_t nv = prt_transfer_vertex_count(t);
    prt_transfer_info info;
    prt_transfer_get_info(t, &info);
    prt_transfer_kind diffuse = prt_transfer_kind_diffuse_part(kind);
    prt_status st = PRT_OK;
    if (prt_transfer_channels(t, diffuse)) st = prt_relight_sh(c->ctx, t, diffuse, sh, rgb);
    else memset(rgb, 0, nv * 3 * sizeof(float));
    if (st) return st;
    float *e = malloc(nv * 3 * (size_t)info.order * info.order * sizeof(float));
    if (!e) return PRT_ERR_NO_MEMORY;
    st = prt_relight_sh_glossy(c->ctx, t, kind, sh, l && l->have_brdf ? &l->brdf : NULL, e);
    if (st) { free(e); return st; }
    *exit = e;
    return PRT_OK;
}

void cli_report_factors(const prt_transfer *t)
{
    for (int k = 1; k <= prt_transfer_brdf_count(t); ++k) {
        const prt_brdf_factors *f = prt_transfer_wavelet_factors(t, k);
        if (!f) continue;
        double rms[PRT_BRDF_MAX_TERMS], rel[PRT_BRDF_MAX_TERMS];
        char spec[128];
        prt_brdf_format(prt_transfer_brdf(t, k), spec, sizeof spec);
        if (prt_brdf_factors_error(f, prt_transfer_brdf(t, k), 0, rms, rel)) continue;
        fprintf(stderr, "prt bake: material %d (%s), %d terms used; cosine-weighted RMS error by terms:\n", k, spec, prt_brdf_factors_terms(f));
        for (int K = 1; K <= prt_brdf_factors_computed(f); ++K)
            fprintf(stderr, "  K=%-2d %.4g (%.1f%%)%s\n", K, rms[K - 1], 100.0 * rel[K - 1], K == prt_brdf_factors_terms(f) ? "  <- used" : "");
    }
}

prt_status cli_light_wavelet(const cli *c, const cli_light *l, prt_wavelet_light **out)
{
    prt_envmap *env = NULL;
    prt_status st;
    if (l->env_path) {
        st = prt_envmap_load(l->env_path, l->layout, &env);
    } else {
        prt_sky_desc sky = {0};
        memcpy(sky.sun_dir, l->sun_dir, sizeof sky.sun_dir);
        st = prt_sky_create(&sky, &env);
    }
    if (st) return st;
    prt_wavelet_light_desc d = {0};
    d.intensity = l->intensity;
    if (l->rotate[0] != 0 || l->rotate[1] != 0 || l->rotate[2] != 0) prt_rotation_from_euler_deg(l->rotate[0], l->rotate[1], l->rotate[2], d.rotation);
    st = prt_wavelet_light_create(c->ctx, env, &d, out);
    prt_envmap_release(env);
    return st;
}

prt_status cli_wavelet_kvec(const cli *c, const prt_transfer *t, const cli_light *l, float **kvec)
{
    *kvec = NULL;
    prt_wavelet_info wi;
    if (!prt_transfer_wavelet_info(t, &wi)) return prt_relight_wavelet(c->ctx, t, NULL, NULL);   /* reports the missing set */
    prt_wavelet_light *wl = NULL;
    prt_status st = cli_light_wavelet(c, l, &wl);
    if (st) return st;
    float *k = malloc(prt_transfer_vertex_count(t) * (size_t)wi.terms * 3 * sizeof(float));
    if (!k) st = PRT_ERR_NO_MEMORY;
    if (!st) st = prt_relight_wavelet(c->ctx, t, wl, k);
    prt_wavelet_light_release(wl);
    if (st) { free(k); return st; }
    *kvec = k;
    return PRT_OK;
}

prt_status cli_relight_wavelet(const cli *c, const prt_transfer *t, const cli_light *l, const float eye[3], float *rgb)
{
    float *kvec = NULL;
    prt_status st = cli_wavelet_kvec(c, t, l, &kvec);
    if (!st) st = prt_wavelet_shade(c->ctx, t, kvec, eye, rgb);
    free(kvec);
    return st;
}
