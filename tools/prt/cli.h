/* Shared pieces of the prt command line: exit codes, option helpers, progress, lighting. */
#ifndef PRT_CLI_H
#define PRT_CLI_H

#include <getopt.h>
#include <prt/prt.h>
#include <stdbool.h>
#include <stdio.h>

/* Exit codes, documented in docs/CLI.md and every --help. */
enum {
    EXIT_OK = 0,
    EXIT_FAILURE_INPUT = 1,   /* a file is missing, unreadable, malformed or empty */
    EXIT_USAGE = 2,           /* bad command line */
    EXIT_BACKEND = 3,         /* Embree, OpenGL/EGL or the system failed */
    EXIT_NO_MEMORY = 4,
    EXIT_INTERRUPTED = 130    /* cancelled by SIGINT; nothing was written */
};

#define EXIT_CODES_HELP \
    "Exit codes: 0 success, 1 bad or missing input, 2 usage error, 3 backend failure,\n" \
    "            4 out of memory, 130 interrupted (no output written).\n"

typedef enum { CLI_PROGRESS_AUTO = 0, CLI_PROGRESS_LINES, CLI_PROGRESS_JSON } cli_progress_mode;

typedef struct cli {
    bool quiet;
    cli_progress_mode progress;   /* auto: a bar on a terminal, lines otherwise */
    int threads;
    prt_context *ctx;
    const char *cmd;
    bool reported;   /* the failure was already printed (cli_fail stays silent) */
} cli;

/* Prints "prt CMD: message" on stderr. */
void cli_error(const cli *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Reports the library's last error and maps the status to an exit code. */
int cli_fail(const cli *c, prt_status st);
int cli_usage(const cli *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
int cli_make_context(cli *c);
/* Edit distance between a and the first n bytes of b (a swap of neighbours is one edit), capped at 9. */
int cli_edit_distance(const char *a, const char *b, size_t n);
/* Parses a --light style spec; an ies light's profile is kept for the whole run (released by
 * cli_release_lights when the command returns), so lights can be copied freely. */
prt_status cli_parse_light(const char *spec, prt_light *out);
void cli_release_lights(void);
/* Runs gnuplot on the script at path (then removes it), passing its messages on (the first one
 * only when quiet); false when it fails. */
bool cli_run_gnuplot(const cli *c, const char *script);
/* The usage error for what getopt_long returned as opt ('?' unknown, ':' missing value; opterr 0
 * and an optstring starting with ':'), naming the argument. */
int cli_bad_option(const cli *c, int opt, char **argv, const struct option *opts);
/* The exit code for a status, when the message was already printed. */
int cli_exit_code(prt_status st);

bool cli_parse_int(const char *s, int lo, int hi, int *out);
bool cli_parse_float(const char *s, float *out);
/* "a,b,c" (or one number, repeated, when allow_scalar). */
bool cli_parse_vec3(const char *s, bool allow_scalar, float out[3]);

/* A progress callback drawing a bar with ETA on stderr when it is a terminal. */
int cli_progress(void *user, const char *stage, uint64_t done, uint64_t total);
/* Installs a SIGINT handler that makes cli_progress cancel the running operation. */
void cli_catch_interrupt(void);
bool cli_interrupted(void);
/* The context's cancel hook (prt_context_desc.cancel): true once Ctrl-C or SIGTERM arrived. */
int cli_cancel_hook(void *user);
/* PRT_ERR_CANCELLED after saying so when SIGINT or SIGTERM arrived: call it before writing. */
prt_status cli_check_interrupt(cli *c);

/* Lighting options shared by relight, render, view, compare, reference, sweep and env. The
 * command line overrides what the file or scene names: --env replaces its environment (keeping
 * its rotation and intensity unless --rotate/--intensity are given), --light replaces its lights. */
#define CLI_MAX_LIGHTS 64
typedef struct cli_light {
    const prt_method *method; /* the method the lighting is for when no .prt says (sweep); NULL: any */
    const char *env_path;     /* NULL: the procedural sky */
    bool env_none;            /* --env none: no environment light */
    prt_env_layout layout;
    float rotate[3];          /* yaw, pitch, roll in degrees */
    float intensity;          /* multiplier; commands start it at 1 */
    float sun_dir[3];         /* sky only; zero = default */
    bool set_source, set_rotate, set_intensity;   /* what the command line gave explicitly */
    prt_light lights[CLI_MAX_LIGHTS];
    int light_count;
    bool set_lights;          /* --light given: replaces the scene's lights (--light none: no lights) */
    float emission;           /* scale of emissive surfaces */
    bool set_emission;
    bool have_brdf;           /* --brdf or --brdf-all: the reflection lobe for glossy sets */
    bool brdf_everywhere;     /* --brdf-all: on every surface, not only the glossy materials */
    prt_brdf brdf;
    /* --albedo-of NAME=R,G,B: surface colours at run time (methods that allow it). */
    struct { char name[64]; float rgb[3]; } paint[CLI_MAX_LIGHTS];
    int paint_count;
    /* --brdf-of NAME=SPEC: a BRDF of the surface's baked set at run time (methods that keep sets). */
    struct { char name[64]; char spec[128]; } brdf_of[CLI_MAX_LIGHTS];
    int brdf_of_count;
    /* --control NAME=V: the method's run-time settings (prt_transfer_controls). */
    struct { char name[64]; int value; } control[PRT_MAX_CONTROLS];
    int control_count;
    const char *paint_path;   /* --paint FILE: first-order light painted onto the light map (prt/paint.h) */
    bool gpu_finish;          /* --accumulate gpu: the method's last passes in the renderer */
    bool whole_texels;        /* a light map for a file: every light in it, none left to draw per pixel */
    char path_buf[1024];
} cli_light;

/* The lighting help comes in parts so that each command lists only what it takes: the header
 * and light sources (every lighting command), and the relight settings (commands that relight a
 * .prt: relight, render, view, compare, sweep). */
#define CLI_LIGHT_HEADER_HELP \
    "Lighting (default: what the scene named, else the procedural sky where the method " \
    "relights it):\n"
#define CLI_LIGHT_SOURCES_HELP \
    "  --env FILE|none       environment probe (.hdr .pfm .exr .png), or no environment light\n" \
    "  --layout L            latlong | angular | cross | auto (default: the scene's, else auto\n" \
    "                        from the aspect ratio)\n" \
    "  --rotate Y[,P[,R]]    rotate the environment: yaw about +y, pitch, roll in degrees\n" \
    "  --intensity S         scale the environment (default: the scene's, else 1)\n" \
    "  --sun X,Y,Z           sun direction of the procedural sky\n" \
    "  --light SPEC          a light, repeatable; replaces the scene's lights ('none': no lights):\n" \
    "                        point:X,Y,Z:R,G,B (W/sr)  spot:X,Y,Z:DX,DY,DZ:ANGLE[,FALLOFF]:R,G,B\n" \
    "                        directional:DX,DY,DZ:R,G,B (towards the light, W/m^2)\n" \
    "                        sphere:X,Y,Z:RADIUS:R,G,B (radiance)\n" \
    "                        ies:FILE:X,Y,Z[:DX,DY,DZ[,UX,UY,UZ][:R,G,B]] (IES profile, nadir\n" \
    "                        along D (default 0,-1,0), C0 towards U; W/sr per candela)\n" \
    "  --emission S          scale the scene's emissive surfaces (0 turns them off; default 1)\n"
#define CLI_LIGHT_BRDF_HELP \
    "  --brdf SPEC           reflection lobe of the glossy materials, for glossy sets baked\n" \
    "                        without a BRDF: phong:N[:KS] or blinn:N[:KS] (default: the\n" \
    "                        scene's own lobes); diffuse surfaces stay diffuse\n" \
    "  --brdf-all SPEC       the same lobe on every surface, diffuse ones included\n"
#define CLI_LIGHT_PAINT_HELP \
    "  --albedo-of NAME=R,G,B  recolour the surface NAME (prt info lists them), repeatable;\n" \
    "                        for methods that change colours without a rebake (prt info says)\n" \
    "  --brdf-of NAME=SPEC   reflect with BRDF SPEC on surface NAME, repeatable: one of the set\n" \
    "                        baked for it (prt info lists the sets; a scene material's \"brdfs\",\n" \
    "                        spectral files); its diffuse part becomes the colour (--albedo-of wins)\n" \
    "  --paint FILE          first-order light painted onto the light map (.exr .pfm .hdr of the\n" \
    "                        map's size, as prt view's y saves it), for files whose method\n" \
    "                        takes it (prt info says): reflected, scattered under the skin\n" \
    "                        and bounced like a lamp's light\n"
#define CLI_LIGHT_CONTROL_HELP \
    "  --control NAME=V      a run-time setting of the file's method (prt info lists them)\n"
#define CLI_LIGHT_RELIGHT_HELP CLI_LIGHT_BRDF_HELP CLI_LIGHT_PAINT_HELP CLI_LIGHT_CONTROL_HELP
/* Everything, for the commands that take every lighting option. */
#define CLI_LIGHT_OPTIONS_HELP CLI_LIGHT_HEADER_HELP CLI_LIGHT_SOURCES_HELP CLI_LIGHT_RELIGHT_HELP

/* Returns 1 if the option was a lighting option (consumed), 0 if not, -1 on a bad value. */
int cli_light_option(const cli *c, cli_light *l, int opt, const char *arg);
enum { OPT_ENV = 1000, OPT_LAYOUT, OPT_ROTATE, OPT_INTENSITY, OPT_SUN, OPT_BRDF, OPT_LIGHT, OPT_EMISSION, OPT_ALBEDO_OF, OPT_CONTROL, OPT_BRDF_ALL,
       OPT_BRDF_OF, OPT_PAINT };
#define CLI_LIGHT_LONG_OPTIONS \
    {"env", required_argument, 0, OPT_ENV}, {"layout", required_argument, 0, OPT_LAYOUT}, \
    {"rotate", required_argument, 0, OPT_ROTATE}, {"intensity", required_argument, 0, OPT_INTENSITY}, \
    {"sun", required_argument, 0, OPT_SUN}, {"brdf", required_argument, 0, OPT_BRDF}, \
    {"light", required_argument, 0, OPT_LIGHT}, {"emission", required_argument, 0, OPT_EMISSION}, \
    {"albedo-of", required_argument, 0, OPT_ALBEDO_OF}, {"control", required_argument, 0, OPT_CONTROL}, \
    {"brdf-all", required_argument, 0, OPT_BRDF_ALL}, {"brdf-of", required_argument, 0, OPT_BRDF_OF}, \
    {"paint", required_argument, 0, OPT_PAINT}
/* The lighting to use: what t (or, without t, the scene s; with neither, nothing) names, with the
 * command line's overrides. */
prt_status cli_lighting(const cli *c, const cli_light *l, const prt_transfer *t, const prt_scene *s, prt_lighting **out);
/* The environment as the command line and file name it, projected to SH (prt env). */
prt_status cli_light_project(const cli *c, const cli_light *l, int order, prt_sh_light *out, prt_env_layout *layout);

/* Relight options shared by relight, render, compare and view: which variant, and the method's
 * run-time settings. */
typedef struct cli_kinds {
    const char *variants[16];   /* names given with --kind, in order; none = the file's default */
    int count;
} cli_kinds;
/* Parses a comma list of variant names into r ('all' = every variant of the file, resolved later). */
bool cli_relight_kinds(cli_kinds *r, char *list);
/* Resolves r's names against t into indices (all variants for 'all', the default when empty);
 * returns the count or -1 after reporting. */
int cli_relight_resolve(const cli *c, const cli_kinds *r, const prt_transfer *t, int drawing, int *indices, int max);
/* The albedo array --albedo-of and --brdf-of ask for (malloc'd; NULL and PRT_OK when they ask
 * nothing). */
prt_status cli_painted_albedo(const cli *c, const cli_light *l, const prt_transfer *t, float **out);
/* The same for a choice of BRDFs made elsewhere (the viewer's): each chosen BRDF's diffuse part,
 * then --albedo-of. brdf_of as prt_relight_desc.brdf_of, or NULL. */
prt_status cli_painted_albedo_for(const cli *c, const cli_light *l, const prt_transfer *t, const int *brdf_of, float **out);
/* --paint FILE for t into d (paint, paint_width, paint_height); *owned is the map to free after
 * relighting (NULL when none was given). Reports a file that does not fit or a method that
 * takes no painting. */
prt_status cli_painting(const cli *c, const cli_light *l, const prt_transfer *t, prt_relight_desc *d, float **owned);
/* prt_relight_desc.brdf_of for --brdf-of (malloc'd, surface count + 1 entries; NULL and PRT_OK
 * when it asks nothing); reports an unknown surface or a BRDF not baked for it, listing them. */
prt_status cli_brdf_choice(const cli *c, const cli_light *l, const prt_transfer *t, int **out);
/* The method's control values with --control applied (defaults elsewhere); count is returned. */
int cli_controls(const cli *c, const cli_light *l, const prt_transfer *t, int values[PRT_MAX_CONTROLS]);
/* --accumulate cpu|gpu; false when it is neither. */
bool cli_parse_accumulate(const char *arg, bool *gpu);
/* Whether --accumulate gpu applies to t (its method has GPU passes, drawn per texel); reports when not. */
bool cli_check_accumulate(const cli *c, const prt_transfer *t, bool per_vertex);
/* --time T of relight, render and view: the pose of a key-framed file (prt bake --frames). */
#define CLI_TIME_HELP \
    "      --time T           key-framed files (prt bake --frames): the pose T frames in (0 the\n" \
    "                         first key frame, 0.5 halfway to the second; times outside 0..F-1\n" \
    "                         are refused, not clamped)\n"
enum { OPT_TIME = 1090 };
/* Parses --time's value; false (after reporting) when it is no number. */
bool cli_parse_time(const cli *c, const char *arg, double *time);
/* Replaces *t by its pose at time (prt_transfer_at_time); reports a time the file does not hold. */
prt_status cli_at_time(cli *c, const char *path, double time, prt_transfer **t);

/* Relights t into out with l (variant index, per-vertex only when asked). */
prt_status cli_relight(const cli *c, const prt_transfer *t, const prt_lighting *lighting, const cli_light *l, int variant, bool per_vertex,
                       bool with_indirect, prt_relit *out);

/* Scene options shared by bake, reference and sweep. */
#define CLI_SCENE_FILE_HELP \
    "      --max-edge L       subdivide until no edge is longer than L scene units\n" \
    "      --albedo R,G,B     albedo of every surface, a JSON scene's own colours included\n" \
    "                         (or one value for grey)\n" \
    "      --default-albedo R,G,B  albedo where the file has no material (default 0.7)\n" \
    "      --crease-angle D   split computed normals above D degrees (default 45)\n" \
    "      --winding W        auto | keep | flip: which side of imported triangles faces out\n" \
    "                         (auto flips closed pieces without normals wound inside out, but\n" \
    "                         keeps those enclosing other geometry or a light: rooms face in)\n" \
    "      --import-timeout S  give up on a mesh file that the importer has not read in S seconds\n" \
    "                         (default 60 + 10 per MB; a malformed file can make it loop)\n"
/* --progress is no scene option: the long commands (bake, reference, sweep) list it beside -q. */
#define CLI_PROGRESS_HELP \
    "      --progress P       auto (a bar on a terminal, else a line per tenth with ETA), lines,\n" \
    "                         or json (one object per line: stage, done, total, percent,\n" \
    "                         elapsed_s, eta_s - for scripts)\n"
enum { OPT_MAX_EDGE = 1100, OPT_ALBEDO, OPT_DEFAULT_ALBEDO, OPT_CREASE, OPT_WINDING, OPT_IMPORT_TIMEOUT, OPT_PROGRESS };
#define CLI_SCENE_LONG_OPTIONS \
    {"max-edge", required_argument, 0, OPT_MAX_EDGE}, {"albedo", required_argument, 0, OPT_ALBEDO}, \
    {"default-albedo", required_argument, 0, OPT_DEFAULT_ALBEDO}, {"crease-angle", required_argument, 0, OPT_CREASE}, \
    {"winding", required_argument, 0, OPT_WINDING}, {"import-timeout", required_argument, 0, OPT_IMPORT_TIMEOUT}, \
    {"progress", required_argument, 0, OPT_PROGRESS}
/* Returns 1 if consumed, 0 if not a scene option, -1 after reporting a bad value. Also takes
 * --progress (the commands that load scenes are the long ones). */
int cli_scene_option(cli *c, prt_scene_desc *sd, int opt, const char *arg);
/* The stages cli_progress has seen and how long each took, in order. */
int cli_stage_times(const char *const **names, const double **seconds);

/* ---- per-vertex and image results (results.c) ---- */
/* Writes text and a newline to path atomically (a temporary beside it, then renamed). */
prt_status cli_write_text(const char *path, const char *text);
typedef struct cli_vertex_field { const char *name; const float *rgb; } cli_vertex_field;
/* {"kind": kind, "vertex_count": n, NAME: [[r, g, b], ...], ...}, written atomically. */
prt_status cli_write_vertex_json(const char *path, const char *kind, size_t nv, const cli_vertex_field *fields, int nfields);
/* Binary PLY with positions, normals and float red/green/blue, written atomically. */
prt_status cli_write_vertex_ply(const char *path, const float *pos, const float *nrm, size_t nv, const uint32_t *idx, size_t nt,
                                const float *rgb);

/* Something to compare: per-vertex radiance (from a .prt relit, a relight or reference JSON) or
 * an image. */
typedef struct cli_result {
    bool image;
    prt_image img;
    size_t nv;
    float *radiance;          /* 3 per vertex */
    float *indirect;          /* 3 per vertex, NULL when the source does not separate it */
    float *std_error;         /* reference JSON only */
    float *std_error_indirect;
    prt_transfer *transfer;   /* when loaded from a .prt: its mesh draws error images */
    char what[256];
} cli_result;
/* Loads path; a .prt is relit with `light` and the variant called `kind` (NULL = its richest
 * view-independent one; view-dependent results are seen from the auto-framed camera). */
prt_status cli_result_load(cli *c, const char *path, const cli_light *light, const char *kind, cli_result *out);
/* Relative L2 of a against b with b's own noise taken out: sqrt(max(0, sum (a-b)^2 - sum err^2)
 * / sum b^2), the error a would show against a noiseless b (err = b's standard errors). */
double cli_rel_l2_above_noise(const float *a, const float *b, const float *err, size_t n);
void cli_result_free(cli_result *r);

/* Camera and image options shared by render and reference. */
typedef struct cli_view {
    int width, height;
    bool have_view, have_eye, have_target;
    float view[3], eye[3], target[3], fov, background[3];
    prt_image_save_desc save;
    bool have_fov;   /* else 40 degrees outside, 70 inside a room (auto framing) */
} cli_view;
#define CLI_VIEW_DEFAULTS {800, 600, false, false, false, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 40.0f, {0.02f, 0.02f, 0.02f}, {0, 0}, false}
/* In parts: render's --width is per panel, and compare draws exact colours (no tone mapping). */
#define CLI_VIEW_WIDTH_HELP \
    "      --width N          image width in pixels (default 800)\n"
#define CLI_VIEW_CAMERA_HELP \
    "      --height N         image height in pixels (default 600)\n" \
    "      --view X,Y,Z       direction from the scene centre towards the camera (auto framing:\n" \
    "                         from inside when the scene closes around its centre, as rooms do)\n" \
    "      --eye X,Y,Z        camera position (with --target: overrides auto framing)\n" \
    "      --target X,Y,Z     point the camera looks at\n" \
    "      --fov DEG          vertical field of view (default 40; 70 inside a closed scene)\n"
#define CLI_VIEW_TONE_HELP \
    "      --exposure STOPS   PNG: scale radiance by 2^STOPS before tone mapping (default 0)\n" \
    "      --tonemap T        PNG: reinhard (default) or clamp\n"
#define CLI_VIEW_BACKGROUND_HELP \
    "      --background R,G,B linear radiance where no surface is hit (default 0.02)\n"
#define CLI_VIEW_OPTIONS_HELP \
    CLI_VIEW_WIDTH_HELP CLI_VIEW_CAMERA_HELP CLI_VIEW_TONE_HELP CLI_VIEW_BACKGROUND_HELP
enum { OPT_WIDTH = 1200, OPT_HEIGHT, OPT_VIEW, OPT_EYE, OPT_TARGET, OPT_FOV, OPT_EXPOSURE, OPT_TONEMAP, OPT_BACKGROUND };
#define CLI_VIEW_LONG_OPTIONS \
    {"width", required_argument, 0, OPT_WIDTH}, {"height", required_argument, 0, OPT_HEIGHT}, {"view", required_argument, 0, OPT_VIEW}, \
    {"eye", required_argument, 0, OPT_EYE}, {"target", required_argument, 0, OPT_TARGET}, {"fov", required_argument, 0, OPT_FOV}, \
    {"exposure", required_argument, 0, OPT_EXPOSURE}, {"tonemap", required_argument, 0, OPT_TONEMAP}, \
    {"background", required_argument, 0, OPT_BACKGROUND}
int cli_view_option(const cli *c, cli_view *v, int opt, const char *arg);
/* The camera for a mesh: auto framing (from inside when the mesh closes around its centre)
 * unless --eye/--target were given. */
void cli_view_camera(const cli *c, const cli_view *v, const float *positions, size_t nv, const uint32_t *indices, size_t nt, float aspect,
                     prt_camera *cam);
/* The same, framing the boxes too (lo xyz, hi xyz each): participating media above a scene. */
void cli_view_camera_boxes(const cli *c, const cli_view *v, const float *positions, size_t nv, const uint32_t *indices, size_t nt, const float *boxes,
                           int box_count, float aspect, prt_camera *cam);
#define CLI_MAX_MEDIA 64
/* The boxes of a scene's or a file's participating media (at most CLI_MAX_MEDIA). */
int cli_scene_media_boxes(const prt_scene *s, float boxes[CLI_MAX_MEDIA * 6]);
int cli_transfer_media_boxes(const prt_transfer *t, float boxes[CLI_MAX_MEDIA * 6]);
/* The points a room must keep facing as the scene is loaded (prt_scene_desc.inside_points): the
 * positions of l's --light lights (directional ones have none) and v's --eye; either may be NULL.
 * out holds 3 floats per point; returns the count. */
#define CLI_MAX_INSIDE_POINTS (CLI_MAX_LIGHTS + 1)
size_t cli_inside_points(const cli_light *l, const cli_view *v, float out[CLI_MAX_INSIDE_POINTS * 3]);

/* The method a command line names with --method NAME (or --method=NAME) before parsing it,
 * the default method when it names none; NULL after reporting an unknown name. */
const prt_method *cli_method_from_argv(const cli *c, int argc, char **argv);
/* Help texts are at most this wide. */
#define CLI_HELP_COLUMNS 100
/* Prints text (its line breaks taken as spaces) from column col, wrapped at CLI_HELP_COLUMNS
 * with continuation lines indented by indent spaces, and ends the line. */
void cli_print_wrapped(FILE *f, int col, int indent, const char *text);
/* A method's list of option declarations: its bake options (prt_method_options) or its export
 * options (prt_method_export_options). */
typedef int (*cli_option_list_fn)(const prt_method *m, const prt_option_desc **out);
/* Prints a method's options of that list as help text under heading (printf format with the
 * method's name, "Method %s:") and, with summary, the method's summary, wrapped at
 * CLI_HELP_COLUMNS; nothing when it has none. */
void cli_print_method_options(FILE *f, const prt_method *m, cli_option_list_fn list, const char *heading, bool summary);
/* Appends to opts (n entries so far, room for max with the terminator) every method's options of
 * that list, so that one of another method gets an error naming the method it belongs to rather
 * than "unknown option"; `chosen`'s come first, so a name two methods share is parsed as the
 * chosen one declares it (NULL: in table order). Option i of names[] gets code first_code + i.
 * Terminates opts and returns the new count. */
int cli_collect_method_options(const prt_method *chosen, cli_option_list_fn list, struct option *opts, int n, int max, const char **names,
                               int max_names, int first_code);
/* Prints a library-made text (describe, bake report) to f, each line prefixed. */
void cli_print_lines(FILE *f, const char *prefix, const char *text);

int cmd_bake(int argc, char **argv);
/* The bake command's body (cmd_bake.c), also finishing prt merge: merged is the checkpoint the
 * shards were put together into (NULL for a bake), note what a shard keeps of the command. */
typedef struct cli_bake_extra {
    const char *merged;
    char *note;
    int rank, ranks;   /* under mpirun: this process's rank and how many there are */
} cli_bake_extra;
int cli_bake_main(int argc, char **argv, const cli_bake_extra *extra);
int cmd_merge(int argc, char **argv);
/* prt bake under mpirun (cluster.c; without MPI in the build, one process and nothing spread).
 * start: MPI is started when mpirun (or another launcher) started this process; true then. */
bool cli_cluster_start(int *argc, char ***argv);
int cli_cluster_rank(void);
int cli_cluster_size(void);
/* Ends MPI; a non-zero rc aborts every process of the job. */
void cli_cluster_end(int rc);
/* prt_bake_run_desc.spread over the job's processes. */
prt_status cli_cluster_spread(void *user, prt_bake_work *w);
/* "MPI" when the build can spread bakes over processes, else NULL. */
const char *cli_cluster_build(void);
int cmd_relight(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_env(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_demo_scene(int argc, char **argv);
int cmd_reference(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_sweep(int argc, char **argv);
int cmd_view(int argc, char **argv);
/* prt sweep --method all, and prt pick (its short name): every method of the table on one scene
 * (sweep_all.c). cmd is the name errors carry ("sweep" or "pick"). */
int cmd_sweep_all(const char *cmd, int argc, char **argv);
int cmd_pick(int argc, char **argv);
/* Whether a sweep command line asks for --method all. */
bool cli_sweep_all_asked(int argc, char **argv);
/* The help of --method all, without the exit codes. */
extern const char *const cli_sweep_all_help;

#endif
