/* prt view: the interactive relighting viewer. The main thread owns the window, input and
 * drawing; a worker thread relights whenever the lighting or the method's state changes, so a
 * large mesh never stalls the window. Camera motion only redraws. */
#include "view.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PI_F 3.14159265358979f

static const char *HELP =
    "usage: prt view FILE.prt [options]\n"
    "Opens a window and relights the baked file in real time (OpenGL 3.3 through GLFW; needs a\n"
    "display - run under xvfb-run without one). The first frame equals prt render with the same\n"
    "size, camera and lighting.\n\n"
    "Mouse: left-drag orbits, right-drag (or shift+left) pans, wheel zooms,\n"
    "       ctrl+left-drag rotates the environment lighting.\n"
    "Keys:  h lists them all; k transfer kind, [ ] SH order, d full/direct/indirect,\n"
    "       + - exposure, t tone mapping, l reload probe, p screenshot, 0 reset, q quit.\n"
    "       Wavelet files (--method wavelet): [ ] halve or double the lighting's Haar\n"
    "       coefficients; lighting changes recompute the K-vectors, camera moves the view factor.\n\n"
    "      --width N --height N   window size (default 1024 x 768)\n"
    "      --exposure STOPS       initial exposure (default 0)\n"
    "      --script FILE          replay timed input and exit when it ends: lines\n"
    "                             'SECONDS VERB ARGS' with verbs orbit DYAW DPITCH, pan DX DY,\n"
    "                             zoom F, env-rotate YAW PITCH, key NAME, drag left|right DX DY\n"
    "                             [ctrl|shift], screenshot FILE (.png .exr), quit\n"
    "      --stats                print frame and relight times as JSON on exit\n"
    CLI_LIGHT_OPTIONS_HELP
    "  -j, --threads N            relighting threads\n"
    "  -q, --quiet                no messages\n"
    "  -h, --help                 this text\n\n" EXIT_CODES_HELP
    "A missing display exits with code 3 and says so.\n";

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* ---- camera ---- */
void view_camera(const viewer *v, prt_camera *cam)
{
    if (!v->moved) { *cam = v->start_cam; return; }
    float cp = cosf(v->pitch), sp = sinf(v->pitch), cy = cosf(v->yaw), sy = sinf(v->yaw);
    memset(cam, 0, sizeof *cam);
    memcpy(cam->target, v->target, sizeof v->target);
    cam->eye[0] = v->target[0] + v->dist * cp * sy;
    cam->eye[1] = v->target[1] + v->dist * sp;
    cam->eye[2] = v->target[2] + v->dist * cp * cy;
    cam->up[1] = 1;
    cam->fov_y_deg = v->fov;
}

static void begin_move(viewer *v)
{
    if (v->moved) return;
    /* Switch from the framed start camera to an orbit that reproduces it. */
    const prt_camera *c = &v->start_cam;
    float d[3] = {c->eye[0] - c->target[0], c->eye[1] - c->target[1], c->eye[2] - c->target[2]};
    v->dist = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    v->pitch = asinf(d[1] / v->dist);
    v->yaw = atan2f(d[0], d[2]);
    memcpy(v->target, c->target, sizeof v->target);
    v->fov = c->fov_y_deg;
    v->moved = true;
}

void view_orbit(viewer *v, float dyaw, float dpitch)
{
    begin_move(v);
    v->yaw += dyaw * PI_F / 180.0f;
    v->pitch = fminf(fmaxf(v->pitch + dpitch * PI_F / 180.0f, -1.55f), 1.55f);
    v->dirty = true;
}

void view_pan(viewer *v, float dx, float dy)
{
    begin_move(v);
    prt_camera cam;
    view_camera(v, &cam);
    float f[3] = {cam.target[0] - cam.eye[0], cam.target[1] - cam.eye[1], cam.target[2] - cam.eye[2]};
    float r[3] = {-f[2], 0, f[0]}, rl = sqrtf(r[0] * r[0] + r[2] * r[2]);
    if (rl > 0) { r[0] /= rl; r[2] /= rl; }
    for (int k = 0; k < 3; ++k) v->target[k] += (-dx * r[k] + (k == 1 ? dy : 0)) * v->dist;
    v->dirty = true;
}

void view_zoom(viewer *v, float factor)
{
    begin_move(v);
    if (factor > 0) v->dist *= factor;
    v->dirty = true;
}

void view_rotate_env(viewer *v, float dyaw, float dpitch)
{
    v->want.env_yaw += dyaw;
    v->want.env_pitch = fminf(fmaxf(v->want.env_pitch + dpitch, -90.0f), 90.0f);
    view_request_relight(v);
}

/* ---- relight worker ---- */
static void relight_wavelet(viewer *v, const relight_job *job, float *out)
{
    /* The viewer's rotation on top of the file's (or command line's), as for SH lighting. */
    double rj[9], rf[9];
    prt_rotation_from_euler_deg(job->env_yaw, job->env_pitch, 0, rj);
    prt_rotation_from_euler_deg(v->light.rotate[0], v->light.rotate[1], v->light.rotate[2], rf);
    prt_wavelet_light_desc d = {0};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) d.rotation[i * 3 + j] = rj[i * 3] * rf[j] + rj[i * 3 + 1] * rf[3 + j] + rj[i * 3 + 2] * rf[6 + j];
    d.coefficients = job->light_coefficients;
    d.intensity = v->light.intensity;
    prt_wavelet_light *wl = NULL;
    if (prt_wavelet_light_create(v->worker_ctx, v->env, &d, &wl)) return;
    prt_relight_wavelet(v->worker_ctx, v->t, wl, out);
    prt_wavelet_light_release(wl);
}

static void relight(viewer *v, const relight_job *job, float *out, float *exit, float *texels, bool *used_texels)
{
    if (job->kind == PRT_TRANSFER_WAVELET) {
        *used_texels = false;
        relight_wavelet(v, job, out);
        return;
    }
    prt_sh_light sh = v->sh;
    sh.order = job->order;
    if (job->env_yaw != 0 || job->env_pitch != 0) {
        double rot[9];
        prt_rotation_from_euler_deg(job->env_yaw, job->env_pitch, 0, rot);
        prt_sh_light_rotate(&sh, rot);
    }
    size_t nv = prt_transfer_vertex_count(v->t);
    if (exit) memset(exit, 0, nv * v->exit_floats * sizeof(float));
    *used_texels = texels && !job->component && prt_transfer_texel_coeffs(v->t, job->kind, NULL) &&
                   !prt_relight_sh_texels(v->worker_ctx, v->t, job->kind, &sh, texels);
    if (prt_transfer_kind_is_glossy(job->kind)) {
        /* The diffuse kind of the same shadowing plus the view-dependent part; direct only is the
         * shadowed pair, indirect only the inter-reflected pair minus it. */
        const prt_brdf *lobe = v->light.have_brdf ? &v->light.brdf : NULL;
        prt_transfer_kind g = job->component == 1 ? PRT_TRANSFER_GLOSSY_SHADOWED : job->kind;
        prt_transfer_kind d = prt_transfer_kind_diffuse_part(g);
        if (prt_transfer_channels(v->t, d)) prt_relight_sh(v->worker_ctx, v->t, d, &sh, out);
        else memset(out, 0, nv * 3 * sizeof(float));
        if (prt_relight_sh_glossy(v->worker_ctx, v->t, g, &sh, lobe, exit)) return;
        if (job->component == 2) {
            float *direct = malloc(nv * v->exit_floats * sizeof(float)), *ddiff = malloc(nv * 3 * sizeof(float));
            if (direct && ddiff && !prt_relight_sh_glossy(v->worker_ctx, v->t, PRT_TRANSFER_GLOSSY_SHADOWED, &sh, lobe, direct)) {
                for (size_t i = 0; i < nv * v->exit_floats; ++i) exit[i] -= direct[i];
                if (!prt_relight_sh(v->worker_ctx, v->t, PRT_TRANSFER_SHADOWED, &sh, ddiff))
                    for (size_t i = 0; i < nv * 3; ++i) out[i] -= ddiff[i];
            }
            free(direct);
            free(ddiff);
        }
        return;
    }
    prt_transfer_kind kind = job->component ? PRT_TRANSFER_INTERREFLECTED : job->kind;
    if (prt_relight_sh(v->worker_ctx, v->t, kind, &sh, out)) return;
    if (job->component) {
        /* direct = shadowed; indirect = inter-reflected - shadowed */
        float *direct = malloc(nv * 3 * sizeof(float));
        if (!direct) return;
        prt_relight_sh(v->worker_ctx, v->t, PRT_TRANSFER_SHADOWED, &sh, direct);
        for (size_t i = 0; i < nv * 3; ++i) out[i] = job->component == 1 ? direct[i] : out[i] - direct[i];
        free(direct);
    }
}

static void *worker(void *arg)
{
    viewer *v = arg;
    const size_t floats = prt_transfer_vertex_count(v->t) * 3 * (size_t)(v->kterms ? v->kterms : 1);
    float *buf = malloc(floats * sizeof(float));
    float *ebuf = v->exit_floats ? malloc(prt_transfer_vertex_count(v->t) * v->exit_floats * sizeof(float)) : NULL;
    if (v->exit_floats && !ebuf) { free(buf); buf = NULL; }
    float *tbuf = v->result_texels ? malloc((size_t)v->texel_width * v->texel_height * 3 * sizeof(float)) : NULL;
    bool used_texels = false;
    pthread_mutex_lock(&v->lock);
    while (!v->quit_worker) {
        if (!v->job_posted) { pthread_cond_wait(&v->wake, &v->lock); continue; }
        relight_job job = v->job;
        v->job_posted = false;
        pthread_mutex_unlock(&v->lock);
        double t0 = now();
        if (buf) relight(v, &job, buf, ebuf, tbuf, &used_texels);
        double ms = (now() - t0) * 1e3;
        pthread_mutex_lock(&v->lock);
        if (buf) {
            memcpy(v->result, buf, floats * sizeof(float));
            if (ebuf) memcpy(v->result_exit, ebuf, prt_transfer_vertex_count(v->t) * v->exit_floats * sizeof(float));
            v->result_has_texels = used_texels;
            if (used_texels) memcpy(v->result_texels, tbuf, (size_t)v->texel_width * v->texel_height * 3 * sizeof(float));
            v->result_version = job.version;
            v->result_ready = true;
            v->relight_ms = ms;
        }
        pthread_cond_broadcast(&v->wake);
    }
    pthread_mutex_unlock(&v->lock);
    free(buf);
    free(ebuf);
    free(tbuf);
    return NULL;
}

void view_request_relight(viewer *v)
{
    pthread_mutex_lock(&v->lock);
    v->want.version++;
    v->job = v->want;
    v->job_posted = true;
    pthread_cond_broadcast(&v->wake);
    pthread_mutex_unlock(&v->lock);
}

/* Wavelet files: the new K-vectors go to the GPU, which evaluates the view factor per pixel;
 * Lambertian vertices' radiance (view-independent) is uploaded as vertex radiance. */
static void shade(viewer *v)
{
    if (prt_wavelet_shade(v->c->ctx, v->t, v->kvec, NULL, v->shaded)) return;
    prt_window_set_radiance(v->win, v->shaded, prt_transfer_vertex_count(v->t));
    prt_window_set_kvec(v->win, v->kvec, prt_transfer_vertex_count(v->t));
}

/* Takes a finished result, if any; returns true when new radiance was uploaded. */
static bool take_result(viewer *v)
{
    bool got = false;
    pthread_mutex_lock(&v->lock);
    if (v->result_ready && v->kvec) {
        memcpy(v->kvec, v->result, prt_transfer_vertex_count(v->t) * 3 * (size_t)v->kterms * sizeof(float));
        shade(v);
    } else if (v->result_ready) {
        prt_window_set_radiance(v->win, v->result, prt_transfer_vertex_count(v->t));
        if (v->exit_floats) prt_window_set_exit(v->win, v->result_exit, prt_transfer_vertex_count(v->t));
        if (v->result_texels)
            prt_window_set_texels(v->win, v->result_has_texels ? v->result_texels : NULL, v->texel_width, v->texel_height);
    }
    if (v->result_ready) {
        v->shown_version = v->result_version;
        v->result_ready = false;
        v->relight_ms_sum += v->relight_ms;
        v->relights++;
        got = true;
    }
    pthread_mutex_unlock(&v->lock);
    return got;
}

void view_sync(viewer *v)
{
    pthread_mutex_lock(&v->lock);
    while (v->result_version != v->want.version || v->job_posted) pthread_cond_wait(&v->wake, &v->lock);
    pthread_mutex_unlock(&v->lock);
    take_result(v);
}

/* ---- drawing ---- */
static void status_line(const viewer *v, char *buf, size_t n)
{
    static const char *component[3] = {"", " (direct only)", " (indirect only)"};
    double frames = v->frames ? (double)v->frames : 1.0, draws = v->draws ? (double)v->draws : 1.0;
    double relights = v->relights ? (double)v->relights : 1.0;
    int len = v->kvec ? snprintf(buf, n, "wavelet, up to %d terms, %d light coefficients, %zu vertices, exposure %+.1f, light at %.0f, %.0f deg\nframe %.2f ms  draw %.2f ms  relight %.2f ms  (h: help)",
                                 v->kterms, v->want.light_coefficients, prt_transfer_vertex_count(v->t), v->exposure, v->want.env_yaw, v->want.env_pitch,
                                 v->frame_ms_sum / frames, v->draw_ms_sum / draws, v->relight_ms_sum / relights)
                      : snprintf(buf, n, "SH %s%s, order %d, %zu vertices, exposure %+.1f, light at %.0f, %.0f deg\nframe %.2f ms  draw %.2f ms  relight %.2f ms  (h: help)",
                       prt_transfer_kind_name(v->want.component ? PRT_TRANSFER_INTERREFLECTED : v->want.kind), component[v->want.component],
                       v->want.order, prt_transfer_vertex_count(v->t), v->exposure, v->want.env_yaw, v->want.env_pitch,
                       v->frame_ms_sum / frames, v->draw_ms_sum / draws, v->relight_ms_sum / relights);
    if (v->help)
        for (int i = 0; i < v->ncontrols && len > 0 && (size_t)len < n; ++i)
            len += snprintf(buf + len, n - (size_t)len, "\n  %-7s %s", v->controls[i].name, v->controls[i].help);
}

int view_frame(viewer *v)
{
    double t0 = now();
    prt_camera cam;
    view_camera(v, &cam);
    char overlay[4096] = "";
    if (v->hud) status_line(v, overlay, sizeof overlay);
    prt_status st = prt_window_draw(v->win, &cam, v->background, v->exposure, v->tonemap, overlay);
    v->draw_ms_sum += (now() - t0) * 1e3;
    v->draws++;
    v->dirty = false;
    return st ? cli_fail(v->c, st) : 0;
}

prt_status view_screenshot(viewer *v, const char *path)
{
    /* A screenshot shows the current lighting: wait for its relight, draw, read the linear image. */
    view_sync(v);
    if (view_frame(v)) return PRT_ERR_BACKEND;
    prt_image img;
    prt_status st = prt_window_read(v->win, &img);
    if (st) return st;
    prt_image_save_desc sd = {v->exposure, v->tonemap};
    st = prt_image_save(path, &img, &sd);
    prt_image_free(&img);
    return st;
}

/* ---- input ---- */
static void handle(viewer *v, const prt_event *e)
{
    switch (e->type) {
    case PRT_EVENT_CLOSE: v->quit = true; break;
    case PRT_EVENT_KEY:
        if (e->action != PRT_ACTION_RELEASE) view_press(v, e->key == '=' && (e->mods & PRT_MOD_SHIFT) ? '=' : e->key);
        break;
    case PRT_EVENT_BUTTON:
        v->drag_button = e->action == PRT_ACTION_PRESS ? e->button + 1 : 0;
        v->drag_mods = e->mods;
        v->last_x = e->x;
        v->last_y = e->y;
        break;
    case PRT_EVENT_MOVE: {
        double dx = e->x - v->last_x, dy = e->y - v->last_y;
        v->last_x = e->x;
        v->last_y = e->y;
        if (!v->drag_button) break;
        if (v->drag_mods & PRT_MOD_CTRL) view_rotate_env(v, (float)dx * 0.25f, (float)dy * 0.25f);
        else if (v->drag_button == 2 || (v->drag_mods & PRT_MOD_SHIFT)) view_pan(v, (float)dx / 400.0f, (float)dy / 400.0f);
        else view_orbit(v, (float)-dx * 0.3f, (float)dy * 0.3f);
        break;
    }
    case PRT_EVENT_SCROLL: view_zoom(v, powf(0.9f, (float)e->y)); break;
    case PRT_EVENT_NONE: break;
    }
}

enum { OPT_W = 2500, OPT_H, OPT_EXP, OPT_SCRIPT, OPT_STATS };

int cmd_view(int argc, char **argv)
{
    cli c = {.cmd = "view"};
    viewer v;
    memset(&v, 0, sizeof v);
    v.c = &c;
    v.light.intensity = 1.0f;
    v.hud = true;
    v.tonemap = 1;
    v.background[0] = v.background[1] = v.background[2] = 0.02f;
    int width = 1024, height = 768;
    const char *script_path = NULL;
    bool stats = false;
    static const struct option opts[] = {
        {"width", required_argument, 0, OPT_W}, {"height", required_argument, 0, OPT_H}, {"exposure", required_argument, 0, OPT_EXP},
        {"script", required_argument, 0, OPT_SCRIPT}, {"stats", no_argument, 0, OPT_STATS}, CLI_LIGHT_LONG_OPTIONS,
        {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &v.light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        switch (opt) {
        case OPT_W: if (!cli_parse_int(optarg, 16, 8192, &width)) return cli_usage(&c, "--width must be 16..8192"); break;
        case OPT_H: if (!cli_parse_int(optarg, 16, 8192, &height)) return cli_usage(&c, "--height must be 16..8192"); break;
        case OPT_EXP: if (!cli_parse_float(optarg, &v.exposure)) return cli_usage(&c, "--exposure takes a number of stops"); break;
        case OPT_SCRIPT: script_path = optarg; break;
        case OPT_STATS: stats = true; break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_usage(&c, "unknown option");
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    view_script *script = NULL;
    int rc = script_path ? view_script_load(&c, script_path, &script) : EXIT_OK;
    if (rc) return rc;
    if ((rc = cli_make_context(&c))) { view_script_free(script); return rc; }
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &v.t);
    prt_transfer_info info;
    if (!st) {
        prt_transfer_get_info(v.t, &info);
        cli_light_defaults_from(&v.light, v.t);
        st = cli_light_project(&c, &v.light, info.order, &v.sh, prt_transfer_channels(v.t, PRT_TRANSFER_WAVELET) ? &v.env : NULL);
    }
    if (!st) st = prt_context_create(&(prt_context_desc){c.threads, NULL, NULL}, &v.worker_ctx);
    char title[600];
    snprintf(title, sizeof title, "prt view - %s", argv[optind]);
    if (!st) st = prt_window_create(c.ctx, &(prt_window_desc){width, height, 0, title}, &v.win);
    if (st) {
        rc = cli_fail(&c, st);
        prt_transfer_release(v.t);
        prt_context_release(v.worker_ctx);
        prt_context_release(c.ctx);
        view_script_free(script);
        return rc;
    }
    view_register_core(&v);
    size_t nv = prt_transfer_vertex_count(v.t);
    if (v.env) {
        prt_wavelet_info wi;
        prt_transfer_wavelet_info(v.t, &wi);
        v.kterms = wi.terms;
        v.kvec = calloc(nv * 3 * (size_t)v.kterms, sizeof(float));
        v.shaded = calloc(nv * 3, sizeof(float));
        v.want.light_coefficients = 4096;
        view_register_wavelet(&v);
    } else {
        view_register_sh(&v);
    }
    v.result = calloc(nv * 3 * (size_t)(v.kterms ? v.kterms : 1), sizeof(float));
    if (v.env && (!v.kvec || !v.shaded)) { free(v.result); v.result = NULL; }
    if (prt_transfer_channels(v.t, PRT_TRANSFER_GLOSSY_SHADOWED) || prt_transfer_channels(v.t, PRT_TRANSFER_GLOSSY_INTERREFLECTED)) {
        v.exit_floats = 3 * (size_t)info.order * info.order;
        v.result_exit = calloc(nv * v.exit_floats, sizeof(float));
    }
    if (prt_transfer_texel_size(v.t, &v.texel_width, &v.texel_height))
        v.result_texels = calloc((size_t)v.texel_width * v.texel_height * 3, sizeof(float));
    if (!v.result || (v.exit_floats && !v.result_exit) || (v.texel_width && !v.result_texels)) {
        cli_error(&c, "out of memory");
        free(v.result);
        free(v.result_exit);
        free(v.result_texels);
        prt_window_release(v.win);
        prt_transfer_release(v.t);
        prt_context_release(v.worker_ctx);
        prt_context_release(c.ctx);
        view_script_free(script);
        return EXIT_NO_MEMORY;
    }
    prt_render_mesh mesh = {.positions = prt_transfer_positions(v.t), .radiance = v.result, .vertex_count = nv,
                            .indices = prt_transfer_indices(v.t), .triangle_count = prt_transfer_triangle_count(v.t),
                            .normals = prt_transfer_normals(v.t), .exit_sh = v.result_exit, .exit_order = v.exit_floats ? info.order : 0,
                            .exit_mirror = prt_transfer_glossy_mirror(v.t), .uv = prt_transfer_uvs(v.t)};
    if (v.kvec) {
        mesh.radiance = v.shaded;
        if (prt_wavelet_view_maps(v.t, &mesh.view_maps, &mesh.view_map_sets, &mesh.view_map_resolution, &mesh.view_map_polar, &mesh.view_set)) {
            mesh.kvec = v.kvec;
            mesh.kvec_terms = v.kterms;
        }
    }
    prt_window_set_mesh(v.win, &mesh);
    int fw, fh;
    prt_window_size(v.win, &fw, &fh);
    prt_camera_frame((float[3]){0, 0, 0}, (float[3]){0, 0, 0}, NULL, 40, 1, &v.start_cam);
    {
        cli_view view = CLI_VIEW_DEFAULTS;   /* the same framing as prt render */
        cli_view_camera(&view, prt_transfer_positions(v.t), nv, (float)fw / fh, &v.start_cam);
    }
    v.want.kind = cli_default_view_kind(v.t);
    v.want.order = info.order;
    pthread_mutex_init(&v.lock, NULL);
    pthread_cond_init(&v.wake, NULL);
    pthread_create(&v.thread, NULL, worker, &v);
    view_request_relight(&v);
    view_sync(&v);   /* the first frame is lit */

    double start = now();
    v.dirty = true;
    while (!v.quit && !rc) {
        double iteration = now();   /* a frame's time covers input, uploads and drawing */
        prt_event e;
        while (prt_window_next_event(v.win, &e)) handle(&v, &e);
        if (script) rc = view_script_step(script, &v, now() - start);
        if (take_result(&v)) v.dirty = true;
        if (v.quit || rc) break;
        if (v.dirty) {
            if ((rc = view_frame(&v))) break;
            v.frame_ms_sum += (now() - iteration) * 1e3;
            v.frames++;
        } else {
            prt_window_wait(v.win, 0.02);   /* idle: wake for input or a finished relight */
        }
    }
    pthread_mutex_lock(&v.lock);
    v.quit_worker = true;
    pthread_cond_broadcast(&v.wake);
    pthread_mutex_unlock(&v.lock);
    pthread_join(v.thread, NULL);
    if (stats) {
        double frames = v.frames ? (double)v.frames : 1.0, draws = v.draws ? (double)v.draws : 1.0;
        double relights = v.relights ? (double)v.relights : 1.0;
        printf("{\"vertices\": %zu, \"frames\": %ld, \"frame_ms\": %.3f, \"draw_ms\": %.3f, \"fps\": %.1f, \"relights\": %ld, \"relight_ms\": %.3f}\n",
               nv, v.frames, v.frame_ms_sum / frames, v.draw_ms_sum / draws, 1000.0 / (v.frame_ms_sum / frames), v.relights,
               v.relight_ms_sum / relights);
    }
    prt_window_release(v.win);
    pthread_mutex_destroy(&v.lock);
    pthread_cond_destroy(&v.wake);
    free(v.result);
    free(v.result_exit);
    free(v.result_texels);
    free(v.kvec);
    free(v.shaded);
    prt_envmap_release(v.env);
    prt_transfer_release(v.t);
    prt_context_release(v.worker_ctx);
    prt_context_release(c.ctx);
    view_script_free(script);
    return rc;
}
