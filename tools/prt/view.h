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
    void (*fn)(viewer *v, int arg);
    int arg;                   /* passed to fn: lets one function serve several keys */
} view_control;

#define VIEW_MAX_CONTROLS 64

/* What the relight worker computes from: everything that changes what relighting produces. */
typedef struct relight_job {
    int variant;
    int component;             /* PRT_COMPONENT_*: all, direct only, indirect only */
    int controls[PRT_MAX_CONTROLS];   /* the method's run-time controls */
    float env_yaw, env_pitch;  /* degrees, on top of the file's rotation */
    bool gpu;                  /* leave the method's last passes to the renderer (prt_relight_desc.gpu_finish) */
    prt_light lights[CLI_MAX_LIGHTS];
    int light_count;
    bool painted;              /* relight with the painting (viewer.paint, copied to job_paint) */
    bool probe;                /* a probe sphere lit by the file's neighbourhood transfer (j) */
    float probe_at[3];
    double time;               /* key-framed files: the pose, in frames (prt_transfer_at_time) */
    unsigned version;
} relight_job;

struct viewer {
    cli *c;
    prt_window *win;
    prt_transfer *t;
    cli_light light;
    float *albedo;              /* --albedo-of and surface edits applied to the file's albedo; NULL = as baked */
    int surface;                /* the named surface the surface controls act on, 0 = none */
    int *brdf_of;               /* per surface, its BRDF in the file's set (prt_relight_desc.brdf_of); NULL = as baked */
    /* camera: the auto-framed start until the user moves it, then an orbit */
    prt_camera start_cam;
    bool moved;
    float target[3], yaw, pitch, dist, fov;
    /* display */
    float exposure;
    int tonemap;
    float background[3];
    bool hud, help;
    bool side_by_side;          /* GPU-finished results: first-order light left, final right */
    char message[256];          /* one line shown under the status (a refused action) */
    /* lighting and method state */
    relight_job want;
    int selected;               /* the light the light controls act on, -1 = none */
    /* relight worker: owns `lighting` (the file's, with the command line's overrides) */
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t wake;
    bool quit_worker, job_posted, result_ready;
    relight_job job;
    prt_lighting *lighting;
    double base_rot[9];         /* the lighting's own rotation, under the viewer's */
    prt_relit result;           /* written by the worker under lock */
    prt_transfer *result_pose;  /* key-framed files: the pose `result` was relit on (owned) */
    prt_status result_status;
    char result_error[256];
    unsigned result_version, shown_version;
    double relight_ms;
    prt_context *worker_ctx;
    prt_relit shown;            /* what the window draws now */
    prt_sh_light result_probe;  /* the light arriving at the result's probe (with result, under lock) */
    float result_probe_at[3];   /* where the result's probe was lit: drawn there, not where a drag has moved it since */
    bool result_probe_on, shown_probe_on;
    prt_transfer *shown_pose;   /* and its pose (owned; NULL: the file's own mesh) */
    /* key frames (prt bake --frames): space plays and pauses, / and \ step */
    int key_frames;             /* the file's count; 1: one pose */
    bool playing;
    double play_clock;          /* when the time last moved while playing */
    /* input */
    view_control controls[VIEW_MAX_CONTROLS];
    int ncontrols;
    int drag_button, drag_mods;
    double last_x, last_y;
    bool dirty, quit;
    int screenshots;
    /* fly mode: W A S D move, E Z rise and sink, dragging turns the view about the eye */
    bool fly;
    float scene_size;           /* the bounding box's diagonal: a fly step is 2% of it */
    /* painting first-order light (files whose method takes it, prt/paint.h): o enters paint mode */
    prt_painter *painter;       /* made on the first dab */
    float *paint;               /* the painting: changed by the main thread under lock; NULL = none yet */
    float *job_paint;           /* the worker's copy for the job it runs (taken under lock) */
    int paint_w, paint_h;
    bool paint_mode;            /* dragging paints (right-drag erases), the wheel sizes the brush */
    float brush_radius;         /* world units; 0 = 3% of the scene until set */
    float brush_light;          /* intensity times brush_colour: irradiance / pi */
    int brush_colour;           /* in the palette */
    int paintings;              /* y saves prt-paint-N.exr */
    /* statistics */
    double frame_ms_sum, draw_ms_sum, relight_ms_sum;
    long frames, draws, relights;
};

void view_register(viewer *v, const view_control *table, int count);
void view_register_core(viewer *v);
/* The method's run-time controls (prt_transfer_controls), bound to the keys it suggests. */
void view_register_method(viewer *v);
/* Light editing, for the light types the file's method relights. */
void view_register_lights(viewer *v);
/* Looks a key up by its script name ("k", "[", "escape"); returns 0 if unknown. */
int view_key_code(const viewer *v, const char *name);
/* Runs the control bound to key, if any. */
void view_press(viewer *v, int key);

/* Camera and lighting changes, used by mouse handling and scripts. */
/* Turns the camera about its target, or in fly mode about the eye (looking around). */
void view_orbit(viewer *v, float dyaw_deg, float dpitch_deg);
/* Fly mode: moves eye and target together along the view (forward > 0), sideways and up, in
 * steps of 2% of the scene. */
void view_fly(viewer *v, float forward, float right, float up);
void view_pan(viewer *v, float dx, float dy);
void view_zoom(viewer *v, float factor);
void view_rotate_env(viewer *v, float dyaw_deg, float dpitch_deg);
/* Light editing, shared by keys, mouse and scripts; each returns false (with v->message set)
 * when the action does not apply. */
bool view_light_add(viewer *v, prt_light_type type, const float *position);
bool view_light_select(viewer *v, int index);
bool view_light_remove(viewer *v);
/* Moves the selected light: point, spot and sphere lights by (dx, dy) of the view plane and dz
 * along the view direction (world units); directional lights turn by dx, dy degrees. */
bool view_light_move(viewer *v, float dx, float dy, float dz);
bool view_light_scale(viewer *v, float factor);
bool view_light_colour(viewer *v, const float rgb[3]);
/* Surface colours (methods that change them at run time): select the next named surface; set
 * its albedo (each channel in [0, 1]); scale it (clamped to 1). */
bool view_surface_next(viewer *v);
bool view_surface_albedo(viewer *v, const float rgb[3]);
bool view_surface_scale(viewer *v, float factor);
/* The selected surface reflects with the next BRDF of the set baked for it (its diffuse part
 * becomes the surface's colour). */
bool view_surface_next_brdf(viewer *v);
void view_register_surfaces(viewer *v);
/* The probe (files with neighbourhood transfer): j shows or hides it, alt+drag then moves it. */
void view_register_probe(viewer *v);
/* Key frames (files that hold them): play / pause, step; view_play advances a playing time to
 * now (call once a main-loop iteration). */
void view_register_frames(viewer *v);
void view_play(viewer *v, double now_s);
/* Takes the lighting's rotation and lights as the viewer's starting point. */
void view_take_lights(viewer *v);
/* The light types the file's method relights (PRT_LIGHTS_* bits). */
unsigned view_light_types(const viewer *v);
void view_camera(const viewer *v, prt_camera *cam);
/* Posts the wanted relight to the worker. */
void view_request_relight(viewer *v);
/* Waits for the worker to finish the latest job and shows its result. */
void view_sync(viewer *v);
/* Draws a frame now; returns non-zero on a GL failure. */
int view_frame(viewer *v);
prt_status view_screenshot(viewer *v, const char *path);

/* Painting first-order light (view_paint.c). Each returns false with v->message set when it does
 * not apply (a file whose method takes no painting says why). */
void view_register_paint(viewer *v);
/* One dab at window pixel (x, y) (from the top left): the surface under it, a brush of `radius`
 * world units painting rgb (irradiance / pi; zero erases). */
bool view_paint_at(viewer *v, double x, double y, float radius, const float rgb[3]);
/* The same with the current brush (erase: paints nothing), for mouse strokes. */
bool view_paint_stroke(viewer *v, double x, double y, bool erase);
bool view_paint_clear(viewer *v);
bool view_paint_save(viewer *v, const char *path);
bool view_paint_load(viewer *v, const char *path);
/* Paint mode's own keys (, . brighten and dim the brush): true when key was taken. */
bool view_paint_key(viewer *v, int key);
/* The wheel in paint mode: the brush grows or shrinks by 10% a step. */
void view_paint_resize(viewer *v, float steps);
/* A status line for paint mode into buf ("" outside it). */
void view_paint_status(const viewer *v, char *buf, size_t n);
void view_paint_free(viewer *v);

/* Script replay: returns 0 on success, an exit code after reporting a bad script. */
typedef struct view_script view_script;
int view_script_load(const cli *c, const char *path, view_script **out);
/* Runs every event due at `elapsed` seconds; sets v->quit at the end of the script. */
int view_script_step(view_script *s, viewer *v, double elapsed);
void view_script_free(view_script *s);

#endif
