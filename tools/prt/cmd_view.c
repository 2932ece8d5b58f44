/* prt view: the interactive relighting viewer. The main thread owns the window, input and
 * drawing; a worker thread relights whenever the lighting or the method's state changes, so a
 * large mesh never stalls the window. Camera motion only redraws. */
#include "view.h"
#include "probe.h"

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
    "size, camera and lighting (with render's default kind, tone mapping and background).\n\n"
    "Mouse: left-drag orbits (in fly mode: looks around), right-drag (or shift+left) pans,\n"
    "       wheel zooms,\n"
    "       ctrl+left-drag rotates the environment lighting,\n"
    "       alt+left-drag moves the selected light in the view plane (turns a directional one),\n"
    "       alt+right-drag or alt+wheel moves it in depth.\n"
    "       Paint mode (o; files whose method takes painted light, prt info says): left-drag\n"
    "       paints first-order light onto the surface under the cursor, right-drag erases,\n"
    "       wheel sizes the brush, , . dim/brighten it, u its colour, v clears, y saves\n"
    "       prt-paint-N.exr (prt render --paint); the light's bounces and subsurface\n"
    "       scattering follow at once.\n"
    "Keys:  h lists them all; k what the file is relit as, d full/direct/indirect, the method's\n"
    "       own controls (h lists them), n add a light, g b the method's GPU passes on the\n"
    "       GPU or CPU and first-order and final light side by side (where it has them),\n"
    "       tab select the next, x remove it, , . dim/brighten, c recolour,\n"
    "       + - exposure, t tone mapping, l reload probe, p screenshot, 0 reset, q quit;\n"
    "       f fly mode: w a s d move, e z rise and sink (walk into a room or Sponza).\n"
    "       Surfaces (files whose colours change live): m select the next, a recolour,\n"
    "       ; ' darken/lighten, r its next BRDF of the set baked for it (a scene material's\n"
    "       \"brdfs\"; prt info lists the sets; its diffuse part becomes the colour).\n"
    "       Lighting changes relight; camera moves only redraw (view-dependent parts are\n"
    "       evaluated per pixel).\n\n"
    "      --width N --height N   window size (default 1024 x 768)\n"
    "      --exposure STOPS       initial exposure (default 0)\n"
    "      --view X,Y,Z --eye X,Y,Z --target X,Y,Z --fov DEG   the starting camera, as prt render\n"
    "                             takes it (auto framing from inside rooms and the Cornell box)\n"
    "      --script FILE          replay timed input and exit when it ends: lines\n"
    "                             'SECONDS VERB ARGS' with verbs orbit DYAW DPITCH, pan DX DY,\n"
    "                             zoom F, env-rotate YAW PITCH, key NAME, drag left|right DX DY\n"
    "                             [ctrl|shift|alt], light-add TYPE [X Y Z], light-select N,\n"
    "                             light-move DX DY DZ, light-scale F, light-colour R G B,\n"
    "                             light-remove, paint X Y RADIUS R,G,B (window pixels from\n"
    "                             the top left, world radius; 0,0,0 erases), paint-clear,\n"
    "                             paint-save FILE, screenshot FILE (.png .exr), quit\n"
    "      --stats                print frame and relight times as JSON on exit\n"
    "      --time T               key-framed files (prt bake --frames): start at the pose T\n"
    "                             frames in (0..F-1); space plays and pauses (a key frame a\n"
    "                             second, looping), / and \\ step a tenth of a frame\n"
    "      --play                 start playing\n"
    "      --accumulate W         files whose method has GPU passes (prt info says): where the\n"
    "                             last sums run - gpu (the default: offset maps in binned atlases,\n"
    "                             additive blending, b shows first-order and final side by side;\n"
    "                             the other methods' per-vertex sums as transform-feedback passes)\n"
    "                             or cpu; g switches\n"
    CLI_LIGHT_OPTIONS_HELP
    "Other:\n"
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
    prt_camera before;
    view_camera(v, &before);
    v->yaw += dyaw * PI_F / 180.0f;
    v->pitch = fminf(fmaxf(v->pitch + dpitch * PI_F / 180.0f, -1.55f), 1.55f);
    if (v->fly) {
        /* Looking around: the eye stays, the target swings round it (the opposite way, so that
         * dragging right looks right). */
        v->yaw -= 2 * dyaw * PI_F / 180.0f;
        v->pitch = fminf(fmaxf(v->pitch - 2 * dpitch * PI_F / 180.0f, -1.55f), 1.55f);
        const float cp = cosf(v->pitch), sp = sinf(v->pitch), cy = cosf(v->yaw), sy = sinf(v->yaw);
        v->target[0] = before.eye[0] - v->dist * cp * sy;
        v->target[1] = before.eye[1] - v->dist * sp;
        v->target[2] = before.eye[2] - v->dist * cp * cy;
    }
    v->dirty = true;
}

void view_fly(viewer *v, float forward, float right, float up)
{
    begin_move(v);
    prt_camera cam;
    view_camera(v, &cam);
    float f[3] = {cam.target[0] - cam.eye[0], cam.target[1] - cam.eye[1], cam.target[2] - cam.eye[2]};
    const float fl = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    if (!(fl > 0)) return;
    for (int k = 0; k < 3; ++k) f[k] /= fl;
    float r[3] = {-f[2], 0, f[0]};
    const float rl = sqrtf(r[0] * r[0] + r[2] * r[2]);
    if (rl > 0) { r[0] /= rl; r[2] /= rl; }
    const float step = 0.02f * (v->scene_size > 0 ? v->scene_size : 1.0f);
    for (int k = 0; k < 3; ++k) v->target[k] += step * (forward * f[k] + right * r[k] + (k == 1 ? up : 0));
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
void view_take_lights(viewer *v)
{
    prt_lighting_rotation(v->lighting, v->base_rot);
    int n = prt_lighting_count(v->lighting);
    if (n > CLI_MAX_LIGHTS) {
        snprintf(v->message, sizeof v->message, "the viewer edits at most %d lights: the first %d of %d are shown", CLI_MAX_LIGHTS, CLI_MAX_LIGHTS, n);
        if (!v->c->quiet) fprintf(stderr, "prt view: warning: %s\n", v->message);
        n = CLI_MAX_LIGHTS;
    }
    v->want.light_count = n;
    for (int i = 0; i < n; ++i) v->want.lights[i] = *prt_lighting_light(v->lighting, i);
    v->selected = n ? 0 : -1;
}

/* The job's lighting: the viewer's rotation on top of the lighting's own, and the job's lights;
 * a key-framed file's pose at the job's time into *pose (NULL for files of one pose); with the
 * probe shown, the light arriving at it into *probe. */
static prt_status relight(viewer *v, const relight_job *job, prt_relit *out, prt_transfer **pose, prt_sh_light *probe)
{
    *pose = NULL;
    double rj[9], r[9];
    prt_rotation_from_euler_deg(job->env_yaw, job->env_pitch, 0, rj);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r[i * 3 + j] = rj[i * 3] * v->base_rot[j] + rj[i * 3 + 1] * v->base_rot[3 + j] + rj[i * 3 + 2] * v->base_rot[6 + j];
    prt_lighting_set_rotation(v->lighting, r);
    prt_lighting_clear_lights(v->lighting);
    prt_status st = PRT_OK;
    for (int i = 0; i < job->light_count && !st; ++i) st = prt_lighting_add(v->lighting, &job->lights[i], NULL);
    prt_relight_desc d;
    memset(&d, 0, sizeof d);
    d.variant = job->variant;
    d.component = job->component;
    d.controls = job->controls;
    d.brdf = v->light.have_brdf ? &v->light.brdf : NULL;
    d.brdf_everywhere = v->light.brdf_everywhere;
    d.albedo = v->albedo;
    d.brdf_of = v->brdf_of;
    d.gpu_finish = job->gpu;
    d.leave_out_unreachable = 1;   /* live: a lamp dragged where the method cannot carry it is left out, with a warning, not the frame */
    if (job->painted && v->job_paint) {   /* the worker's copy, taken with the job */
        d.paint = v->job_paint;
        d.paint_width = v->paint_w;
        d.paint_height = v->paint_h;
    }
    if (!st && v->key_frames > 1) st = prt_transfer_at_time(v->worker_ctx, v->t, job->time, pose);
    if (!st) st = prt_relight(v->worker_ctx, *pose ? *pose : v->t, v->lighting, &d, out);
    if (!st && job->probe && (st = cli_probe_arriving(v->worker_ctx, v->t, v->lighting, job->probe_at, probe))) prt_relit_free(out);
    if (st) {
        prt_transfer_release(*pose);
        *pose = NULL;
    }
    return st;
}

static void *worker(void *arg)
{
    viewer *v = arg;
    pthread_mutex_lock(&v->lock);
    while (!v->quit_worker) {
        if (!v->job_posted) { pthread_cond_wait(&v->wake, &v->lock); continue; }
        relight_job job = v->job;
        v->job_posted = false;
        if (job.painted && v->paint) memcpy(v->job_paint, v->paint, (size_t)v->paint_w * v->paint_h * 3 * sizeof *v->paint);
        pthread_mutex_unlock(&v->lock);
        double t0 = now();
        prt_relit r;
        prt_transfer *pose = NULL;
        prt_sh_light probe;
        memset(&probe, 0, sizeof probe);
        prt_status st = relight(v, &job, &r, &pose, &probe);
        double ms = (now() - t0) * 1e3;
        pthread_mutex_lock(&v->lock);
        prt_relit_free(&v->result);
        prt_transfer_release(v->result_pose);
        v->result = r;
        v->result_pose = pose;
        v->result_probe = probe;
        v->result_probe_on = job.probe;
        memcpy(v->result_probe_at, job.probe_at, sizeof v->result_probe_at);
        v->result_status = st;
        if (st) snprintf(v->result_error, sizeof v->result_error, "%s", prt_last_error());
        v->result_version = job.version;
        v->result_ready = true;
        v->relight_ms = ms;
        pthread_cond_broadcast(&v->wake);
    }
    pthread_mutex_unlock(&v->lock);
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

/* Uploads a relit result: the whole mesh when what it holds or its pose changed, else only the
 * arrays. Takes r and pose (NULL: the file's own mesh). */
static void show(viewer *v, prt_relit *r, prt_transfer *pose)
{
    const size_t nv = prt_transfer_vertex_count(v->t);
    const prt_relit *o = &v->shown;
    const prt_transfer *t = pose ? pose : v->t;
    const bool same = !pose && o->radiance && (o->exit_sh != NULL) == (r->exit_sh != NULL) && o->exit_order == r->exit_order &&
                      (o->texels != NULL) == (r->texels != NULL) && o->texel_width == r->texel_width && o->texel_height == r->texel_height &&
                      (o->kvec != NULL) == (r->kvec != NULL) && o->kvec_terms == r->kvec_terms && o->exit_mirror == r->exit_mirror &&
                      (o->gpu_input != NULL) == (r->gpu_input != NULL) && (o->gpu_sums != NULL) == (r->gpu_sums != NULL);
    /* A probe sphere joins the mesh: the whole mesh goes up while one is shown, and once more
     * when it goes. */
    const bool probe = v->result_probe_on;
    if (probe || v->shown_probe_on) {
        prt_render_mesh mesh, joined;
        prt_relit_render_mesh(t, r, &mesh);
        mesh.side_by_side = v->side_by_side;
        cli_probe_mesh keep = {0};
        const float at[1][4] = {{v->result_probe_at[0], v->result_probe_at[1], v->result_probe_at[2], 0}};
        if (probe && !cli_probe_drawable(&mesh)) snprintf(v->message, sizeof v->message, "the probe draws over per-vertex radiance: this kind has per-pixel parts");
        if (probe && cli_probe_drawable(&mesh) && cli_probe_spheres(&mesh, at, &v->result_probe, 1, cli_probe_radius(v->t), &keep, &joined))
            prt_window_set_mesh(v->win, &joined);
        else
            prt_window_set_mesh(v->win, &mesh);
        cli_probe_mesh_free(&keep);
        v->shown_probe_on = probe;
    } else if (same) {
        prt_window_set_radiance(v->win, r->radiance, nv);
        if (r->gpu_sums) {   /* the per-vertex sums again on the GPU from this frame's vector */
            prt_render_mesh mesh;
            prt_relit_render_mesh(t, r, &mesh);
            prt_window_set_gpu_sums(v->win, &mesh);
        }
        if (r->gpu_input) {
            prt_render_mesh mesh;
            prt_relit_render_mesh(t, r, &mesh);
            mesh.side_by_side = v->side_by_side;
            prt_window_set_gpu_input(v->win, &mesh);
        }
        if (r->exit_sh) prt_window_set_exit(v->win, r->exit_sh, nv);
        if (r->texels) prt_window_set_texels(v->win, r->texels, r->texel_width, r->texel_height);
        if (r->kvec) prt_window_set_kvec(v->win, r->kvec, nv);
        prt_render_mesh mesh;
        prt_relit_render_mesh(t, r, &mesh);
        prt_window_set_lights(v->win, &mesh);   /* shadow maps are redrawn only when the lights moved */
        if (r->volume_count) prt_window_set_volumes(v->win, &mesh);
    } else {
        prt_render_mesh mesh;
        prt_relit_render_mesh(t, r, &mesh);
        mesh.side_by_side = v->side_by_side;
        prt_window_set_mesh(v->win, &mesh);
    }
    prt_relit_free(&v->shown);
    prt_transfer_release(v->shown_pose);
    v->shown = *r;
    v->shown_pose = pose;
    memset(r, 0, sizeof *r);
}

/* Takes a finished result, if any; returns true when something new is shown. */
static bool take_result(viewer *v)
{
    bool got = false;
    pthread_mutex_lock(&v->lock);
    if (v->result_ready) {
        if (v->result_status) {
            /* Refused (a component the method cannot separate, say): say why and go back. */
            snprintf(v->message, sizeof v->message, "%s", v->result_error);
            if (v->want.component) { v->want.component = 0; v->job = v->want; v->want.version++; v->job.version = v->want.version; v->job_posted = true; pthread_cond_broadcast(&v->wake); }
        } else {
            show(v, &v->result, v->result_pose);
            v->result_pose = NULL;
        }
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
    char settings[256] = "";
    const prt_control_desc *cd;
    int nc = prt_transfer_controls(v->t, &cd);
    for (int i = 0, at = 0; i < nc && at < (int)sizeof settings; ++i)
        at += snprintf(settings + at, sizeof settings - (size_t)at, ", %s %d", cd[i].name, v->want.controls[i]);
    if (v->shown.gpu_input) snprintf(settings + strlen(settings), sizeof settings - strlen(settings), ", GPU passes%s", v->side_by_side ? ", first-order | final" : "");
    if (v->shown.gpu_sums) snprintf(settings + strlen(settings), sizeof settings - strlen(settings), ", GPU sums");
    int len = snprintf(buf, n, "%s %s%s%s, %zu vertices, exposure %+.1f, light at %.0f, %.0f deg\nframe %.2f ms  draw %.2f ms  relight %.2f ms  (h: help)",
                       prt_method_name(prt_transfer_method(v->t)), prt_transfer_variant_name(v->t, v->want.variant), component[v->want.component], settings,
                       prt_transfer_vertex_count(v->t), v->exposure, v->want.env_yaw, v->want.env_pitch, v->frame_ms_sum / frames, v->draw_ms_sum / draws,
                       v->relight_ms_sum / relights);
    for (int i = 0; i < v->want.light_count && len > 0 && (size_t)len < n; ++i) {
        char spec[256];
        prt_light_format(&v->want.lights[i], spec, sizeof spec);
        len += snprintf(buf + len, n - (size_t)len, "\n%s light %d: %s", i == v->selected ? ">" : " ", i + 1, spec);
    }
    if (v->key_frames > 1 && len > 0 && (size_t)len < n)
        len += snprintf(buf + len, n - (size_t)len, "\ntime %.2f of 0..%d (%s; space %s, / \\ step)", v->want.time, v->key_frames - 1,
                        v->playing ? "playing" : "paused", v->playing ? "pauses" : "plays");
    if (v->surface && len > 0 && (size_t)len < n) len += snprintf(buf + len, n - (size_t)len, "\nsurface: %s", prt_transfer_surface_name(v->t, v->surface));
    char paint[256];
    view_paint_status(v, paint, sizeof paint);
    if (paint[0] && len > 0 && (size_t)len < n) len += snprintf(buf + len, n - (size_t)len, "\n%s", paint);
    if (v->message[0] && len > 0 && (size_t)len < n) len += snprintf(buf + len, n - (size_t)len, "\n%s", v->message);
    static const char *const mouse[] = {
        "  drag    orbit (fly mode: look around)", "  right-drag, shift+drag   pan", "  wheel   zoom",
        "  ctrl+drag   rotate the environment lighting",
        "  alt+drag    move the selected light across the view (alt+right-drag, alt+wheel: in depth)"};
    if (v->help)
        for (size_t i = 0; i < sizeof mouse / sizeof mouse[0] && len > 0 && (size_t)len < n; ++i)
            len += snprintf(buf + len, n - (size_t)len, "\n%s", mouse[i]);
    if (v->help && prt_method_paintable(prt_transfer_method(v->t)) && len > 0 && (size_t)len < n)
        len += snprintf(buf + len, n - (size_t)len, "\n  o, then drag   paint first-order light (right-drag erases, wheel: brush size)");
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
    if (st && (v->shown.gpu_input || v->shown.gpu_sums)) {
        /* The GPU could not take the maps (too many atlases, too little memory): the same passes
         * on the CPU, and say so. */
        snprintf(v->message, sizeof v->message, "GPU passes failed (%.160s): on the CPU now", prt_last_error());
        if (!v->c->quiet) fprintf(stderr, "prt view: %s\n", v->message);
        v->want.gpu = false;
        v->side_by_side = false;
        view_sync(v);   /* the CPU's result replaces the GPU input */
        view_request_relight(v);
        view_sync(v);
        st = prt_window_draw(v->win, &cam, v->background, v->exposure, v->tonemap, overlay);
    }
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
        /* Paint mode: a click is a dab (left paints, right erases). */
        if (v->paint_mode && !v->drag_mods && (v->drag_button == 1 || v->drag_button == 2)) view_paint_stroke(v, e->x, e->y, v->drag_button == 2);
        break;
    case PRT_EVENT_MOVE: {
        double dx = e->x - v->last_x, dy = e->y - v->last_y;
        v->last_x = e->x;
        v->last_y = e->y;
        if (!v->drag_button) break;
        if (v->paint_mode && !v->drag_mods && (v->drag_button == 1 || v->drag_button == 2)) view_paint_stroke(v, e->x, e->y, v->drag_button == 2);
        else if (v->drag_mods & PRT_MOD_ALT) {
            /* Lights follow the cursor: a pixel moves them by the view's extent at the target. */
            const float px = v->dist > 0 ? v->dist * 0.0015f : 0.01f;
            if (v->drag_button == 2) view_light_move(v, 0, 0, (float)dy * px);
            else view_light_move(v, (float)dx * px, (float)-dy * px, 0);
        } else if (v->drag_mods & PRT_MOD_CTRL) view_rotate_env(v, (float)dx * 0.25f, (float)dy * 0.25f);
        else if (v->drag_button == 2 || (v->drag_mods & PRT_MOD_SHIFT)) view_pan(v, (float)dx / 400.0f, (float)dy / 400.0f);
        else view_orbit(v, (float)-dx * 0.3f, (float)dy * 0.3f);
        break;
    }
    case PRT_EVENT_SCROLL:
        if (v->paint_mode) view_paint_resize(v, (float)e->y);
        else if (v->drag_mods & PRT_MOD_ALT) view_light_move(v, 0, 0, (float)e->y * (v->dist > 0 ? v->dist : 1.0f) * 0.05f);
        else view_zoom(v, powf(0.9f, (float)e->y));
        break;
    case PRT_EVENT_NONE: break;
    }
}

enum { OPT_W = 2500, OPT_H, OPT_EXP, OPT_SCRIPT, OPT_STATS, OPT_ACCUMULATE, OPT_PLAY };

int cmd_view(int argc, char **argv)
{
    cli c = {.cmd = "view"};
    viewer v;
    memset(&v, 0, sizeof v);
    v.c = &c;
    pthread_mutex_init(&v.lock, NULL);   /* a painting given with --paint is loaded under it */
    pthread_cond_init(&v.wake, NULL);
    v.light.intensity = 1.0f;
    v.hud = true;
    v.tonemap = 1;
    v.background[0] = v.background[1] = v.background[2] = 0.02f;
    int width = 1024, height = 768;
    const char *script_path = NULL;
    bool stats = false, accumulate_given = false;
    cli_view view = CLI_VIEW_DEFAULTS;
    static const struct option opts[] = {
        {"width", required_argument, 0, OPT_W}, {"height", required_argument, 0, OPT_H}, {"exposure", required_argument, 0, OPT_EXP},
        {"script", required_argument, 0, OPT_SCRIPT}, {"stats", no_argument, 0, OPT_STATS}, CLI_LIGHT_LONG_OPTIONS,
        {"accumulate", required_argument, 0, OPT_ACCUMULATE},
        {"view", required_argument, 0, OPT_VIEW}, {"eye", required_argument, 0, OPT_EYE}, {"target", required_argument, 0, OPT_TARGET},
        {"fov", required_argument, 0, OPT_FOV}, {"time", required_argument, 0, OPT_TIME}, {"play", no_argument, 0, OPT_PLAY},
        {"threads", required_argument, 0, 'j'}, {"quiet", no_argument, 0, 'q'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    bool timed = false, play = false;
    int opt;
    optind = 1;
    opterr = 0;   /* one line of our own instead of getopt's */
    while ((opt = getopt_long(argc, argv, ":j:qh", opts, NULL)) != -1) {
        int r = cli_light_option(&c, &v.light, opt, optarg);
        if (r < 0) return EXIT_USAGE;
        if (r) continue;
        if (opt == OPT_VIEW || opt == OPT_EYE || opt == OPT_TARGET || opt == OPT_FOV) {   /* the camera, as prt render takes it */
            if (cli_view_option(&c, &view, opt, optarg) < 0) return EXIT_USAGE;
            continue;
        }
        switch (opt) {
        case OPT_W: if (!cli_parse_int(optarg, 16, 8192, &width)) return cli_usage(&c, "--width must be 16..8192"); break;
        case OPT_H: if (!cli_parse_int(optarg, 16, 8192, &height)) return cli_usage(&c, "--height must be 16..8192"); break;
        case OPT_EXP: if (!cli_parse_float(optarg, &v.exposure)) return cli_usage(&c, "--exposure takes a number of stops"); break;
        case OPT_SCRIPT: script_path = optarg; break;
        case OPT_STATS: stats = true; break;
        case OPT_TIME:
            if (!cli_parse_time(&c, optarg, &v.want.time)) return EXIT_USAGE;
            timed = true;
            break;
        case OPT_PLAY: play = true; break;
        case OPT_ACCUMULATE:
            if (!cli_parse_accumulate(optarg, &v.light.gpu_finish)) return cli_usage(&c, "--accumulate takes cpu or gpu");
            accumulate_given = true;
            break;
        case 'j': if (!cli_parse_int(optarg, 1, 1024, &c.threads)) return cli_usage(&c, "--threads must be 1..1024"); break;
        case 'q': c.quiet = true; break;
        case 'h': fputs(HELP, stdout); return EXIT_OK;
        default: return cli_bad_option(&c, opt, argv, opts);
        }
    }
    if (optind != argc - 1) return cli_usage(&c, "expected exactly one FILE.prt argument");
    if (view.have_eye != view.have_target) return cli_usage(&c, "--eye and --target go together");
    view_script *script = NULL;
    int rc = script_path ? view_script_load(&c, script_path, &script) : EXIT_OK;
    if (rc) return rc;
    if ((rc = cli_make_context(&c))) { view_script_free(script); return rc; }
    prt_status st = prt_transfer_load(c.ctx, argv[optind], &v.t);
    if (!st) v.key_frames = prt_transfer_frame_count(v.t);
    if (!st && (timed || play) && v.key_frames < 2) {
        cli_error(&c, "--%s: '%s' holds one pose, no key frames (prt bake --frames)", timed ? "time" : "play", argv[optind]);
        c.reported = true;
        st = PRT_ERR_INVALID_ARG;
    }
    if (!st && !(v.want.time >= 0 && v.want.time <= v.key_frames - 1)) {
        cli_error(&c, "--time %g lies outside the key frames of '%s', 0 to %d (times are not clamped)", v.want.time, argv[optind], v.key_frames - 1);
        c.reported = true;
        st = PRT_ERR_INVALID_ARG;
    }
    v.playing = play;
    v.play_clock = -1;
    if (!st) st = cli_lighting(&c, &v.light, v.t, NULL, &v.lighting);
    if (!st) st = prt_context_create(&(prt_context_desc){.threads = c.threads}, &v.worker_ctx);
    if (!st) {
        /* The file's lights become the viewer's to edit; the worker relights with a copy per job. */
        view_take_lights(&v);
        v.want.variant = prt_transfer_default_variant(v.t, 1);
        /* Methods with GPU passes run them on the GPU unless asked otherwise (the papers they come
         * from run them there). */
        if (!accumulate_given) v.light.gpu_finish = prt_method_gpu_passes(prt_transfer_method(v.t));
        else if (v.light.gpu_finish && !cli_check_accumulate(&c, v.t, false)) { c.reported = true; st = PRT_ERR_INVALID_ARG; }
        v.want.gpu = v.light.gpu_finish;
        if (cli_controls(&c, &v.light, v.t, v.want.controls) < 0) { c.reported = true; st = PRT_ERR_INVALID_ARG; }
        if (!st) st = cli_brdf_choice(&c, &v.light, v.t, &v.brdf_of);
        if (!st) st = cli_painted_albedo_for(&c, &v.light, v.t, v.brdf_of, &v.albedo);
        if (!st && v.light.paint_path && !view_paint_load(&v, v.light.paint_path)) {
            cli_error(&c, "--paint: %s", v.message);
            c.reported = true;
            st = PRT_ERR_INVALID_ARG;
        }
    }
    if (!st) {
        /* The first frame is lit before the window opens, so a bad lighting fails at once. */
        prt_relit first;
        prt_sh_light none;
        v.job = v.want;
        st = relight(&v, &v.want, &first, &v.shown_pose, &none);
        if (!st) v.shown = first;
    }
    char title[600];
    snprintf(title, sizeof title, "prt view - %s", argv[optind]);
    if (!st) st = prt_window_create(c.ctx, &(prt_window_desc){width, height, 0, title}, &v.win);
    if (st) {
        rc = cli_fail(&c, st);
        prt_relit_free(&v.shown);
        prt_transfer_release(v.shown_pose);
        prt_lighting_release(v.lighting);
        free(v.albedo);
        free(v.brdf_of);
        view_paint_free(&v);
        pthread_mutex_destroy(&v.lock);
        pthread_cond_destroy(&v.wake);
        prt_transfer_release(v.t);
        prt_context_release(v.worker_ctx);
        prt_context_release(c.ctx);
        view_script_free(script);
        return rc;
    }
    view_register_core(&v);
    view_register_method(&v);
    view_register_lights(&v);
    view_register_surfaces(&v);
    view_register_paint(&v);
    view_register_probe(&v);
    view_register_frames(&v);
    const size_t nv = prt_transfer_vertex_count(v.t);
    {
        prt_render_mesh mesh;
        prt_relit_render_mesh(v.shown_pose ? v.shown_pose : v.t, &v.shown, &mesh);
        prt_window_set_mesh(v.win, &mesh);
    }
    int fw, fh;
    prt_window_size(v.win, &fw, &fh);
    {
        const float *p = prt_transfer_positions(v.t);
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < nv * 3; ++i) { lo[i % 3] = fminf(lo[i % 3], p[i]); hi[i % 3] = fmaxf(hi[i % 3], p[i]); }
        v.scene_size = nv ? sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2])) : 1.0f;
    }
    prt_camera_frame((float[3]){0, 0, 0}, (float[3]){0, 0, 0}, NULL, 40, 1, &v.start_cam);
    {   /* the same framing as prt render */
        float media[CLI_MAX_MEDIA * 6];
        const int nmedia = view.have_eye ? 0 : cli_transfer_media_boxes(v.t, media);
        cli_view_camera_boxes(&c, &view, prt_transfer_positions(v.t), nv, prt_transfer_indices(v.t), prt_transfer_triangle_count(v.t), media, nmedia,
                              (float)fw / fh, &v.start_cam);
    }
    v.result_version = v.shown_version = v.want.version;
    pthread_create(&v.thread, NULL, worker, &v);

    double start = now();
    v.dirty = true;
    while (!v.quit && !rc) {
        if (cli_interrupted()) break;   /* Ctrl-C in the terminal closes the window */
        double iteration = now();   /* a frame's time covers input, uploads and drawing */
        prt_event e;
        while (prt_window_next_event(v.win, &e)) handle(&v, &e);
        if (script) rc = view_script_step(script, &v, now() - start);
        view_play(&v, now());
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
    prt_relit_free(&v.result);
    prt_relit_free(&v.shown);
    prt_transfer_release(v.result_pose);
    prt_transfer_release(v.shown_pose);
    prt_lighting_release(v.lighting);
    free(v.albedo);
    free(v.brdf_of);
    view_paint_free(&v);
    prt_transfer_release(v.t);
    prt_context_release(v.worker_ctx);
    prt_context_release(c.ctx);
    view_script_free(script);
    return rc;
}
