/* prt view: state shared by the viewer's main loop (cmd_view.c), its control table
 * (view_controls.c) and its script player (view_script.c). */
#ifndef PRT_VIEW_H
#define PRT_VIEW_H

#include "cli.h"

#include <pthread.h>

typedef struct viewer viewer;

/* A key binding. Methods add their own table with view_register; the viewer never switches on
 * the method. */
typedef struct view_control {
    int key;                   /* GLFW key code: upper-case ASCII for letters, '[', ']', '=', '-' ... */
    const char *name;          /* how scripts and the help overlay name the key */
    const char *help;
    void (*fn)(viewer *v);
} view_control;

#define VIEW_MAX_CONTROLS 64

/* What the relight worker computes: everything that changes the per-vertex radiance. */
typedef struct relight_job {
    prt_transfer_kind kind;
    int order;
    int component;             /* 0 full, 1 direct only, 2 indirect only */
    float env_yaw, env_pitch;  /* degrees */
    int light_coefficients;    /* wavelet: Haar coefficients of the lighting kept */
    unsigned version;
} relight_job;

struct viewer {
    cli *c;
    prt_window *win;
    prt_transfer *t;
    cli_light light;
    prt_sh_light sh;            /* the environment projected at the file's order, unrotated */
    /* camera: the auto-framed start until the user moves it, then an orbit */
    prt_camera start_cam;
    bool moved;
    float target[3], yaw, pitch, dist, fov;
    /* display */
    float exposure;
    int tonemap;
    float background[3];
    bool hud, help;
    /* lighting and method state */
    relight_job want;
    /* relight worker */
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t wake;
    bool quit_worker, job_posted, result_ready;
    relight_job job;
    float *result;              /* written by the worker under lock */
    float *result_exit;         /* glossy exit SH per vertex, when the file has glossy sets */
    size_t exit_floats;         /* per vertex: 3 x order^2, or 0 */
    /* wavelet files: the worker returns light-dependent K-vectors (result, kterms x 3 per
     * vertex); the GPU applies the view factor per pixel, so camera moves relight nothing. */
    prt_envmap *env;
    int kterms;
    float *kvec, *shaded;
    float *result_texels;       /* per-texel radiance map, when the file has texel sets */
    bool result_has_texels;     /* the latest result used them (its kind has a texel set) */
    int texel_width, texel_height;
    unsigned result_version, shown_version;
    double relight_ms;
    prt_context *worker_ctx;
    /* input */
    view_control controls[VIEW_MAX_CONTROLS];
    int ncontrols;
    int drag_button, drag_mods;
    double last_x, last_y;
    bool dirty, quit;
    int screenshots;
    /* statistics */
    double frame_ms_sum, draw_ms_sum, relight_ms_sum;
    long frames, draws, relights;
};

void view_register(viewer *v, const view_control *table, int count);
void view_register_core(viewer *v);
void view_register_sh(viewer *v);
void view_register_wavelet(viewer *v);
/* Looks a key up by its script name ("k", "[", "escape"); returns 0 if unknown. */
int view_key_code(const viewer *v, const char *name);
/* Runs the control bound to key, if any. */
void view_press(viewer *v, int key);

/* Camera and lighting changes, used by mouse handling and scripts. */
void view_orbit(viewer *v, float dyaw_deg, float dpitch_deg);
void view_pan(viewer *v, float dx, float dy);
void view_zoom(viewer *v, float factor);
void view_rotate_env(viewer *v, float dyaw_deg, float dpitch_deg);
void view_camera(const viewer *v, prt_camera *cam);
/* Posts the wanted relight to the worker. */
void view_request_relight(viewer *v);
/* Waits for the worker to finish the latest job and shows its result. */
void view_sync(viewer *v);
/* Draws a frame now; returns non-zero on a GL failure. */
int view_frame(viewer *v);
prt_status view_screenshot(viewer *v, const char *path);

/* Script replay: returns 0 on success, an exit code after reporting a bad script. */
typedef struct view_script view_script;
int view_script_load(const cli *c, const char *path, view_script **out);
/* Runs every event due at `elapsed` seconds; sets v->quit at the end of the script. */
int view_script_step(view_script *s, viewer *v, double elapsed);
void view_script_free(view_script *s);

#endif
