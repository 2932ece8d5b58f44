/* prt/method.h - the method table: every PRT technique prt implements, behind one interface.
 *
 * A method is one entry of one table (docs/ARCHITECTURE.md). It declares its name, its bake
 * options (the command line's parser and --help both come from the declarations), the lighting
 * it relights (PRT_LIGHTS_* of prt/lighting.h), and the run-time controls a viewer can bind to
 * keys. Through it a program bakes a scene, describes a .prt file, and relights it under a
 * prt_lighting into a prt_relit - what the renderer draws - without naming the method:
 *
 *     const prt_method *m = prt_method_find("sh");
 *     prt_options *o; prt_options_create(m, &o); prt_options_set(o, "order", "6");
 *     prt_transfer *t; prt_bake(ctx, scene, m, o, &bake_desc, &t);
 *     prt_relit r; prt_relight(ctx, t, lighting, NULL, &r);
 *     prt_render_mesh mesh; prt_relit_render_mesh(t, &r, &mesh); prt_render(renderer, &mesh, ...);
 *
 * Method entries are static: the pointers stay valid for the life of the process. */
#ifndef PRT_METHOD_H
#define PRT_METHOD_H

#include "prt/base.h"
#include "prt/brdf.h"
#include "prt/lighting.h"
#include "prt/render.h"
#include "prt/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct prt_method prt_method;
typedef struct prt_transfer prt_transfer;

int prt_method_count(void);
const prt_method *prt_method_at(int index);                /* NULL out of range */
const prt_method *prt_method_find(const char *name);       /* NULL when no method has that name */
const prt_method *prt_method_default(void);                /* the first entry: "sh" */
const char *prt_method_name(const prt_method *m);          /* "sh", "wavelet", ... */
const char *prt_method_title(const prt_method *m);         /* "spherical-harmonic PRT" */
const char *prt_method_summary(const prt_method *m);       /* one line for --help texts */
/* PRT_LIGHTS_* bits of the lighting the method relights. */
unsigned prt_method_lighting(const prt_method *m);
/* 1 when m's files can be relit with other surface albedos than they were baked with
 * (prt_relight_desc.albedo). */
int prt_method_runtime_albedo(const prt_method *m);
/* Without runtime albedo: why the method's surface colours need a rebake (one clause), or NULL. */
const char *prt_method_baked_albedo_why(const prt_method *m);
/* 1 when the method always bakes into a light map over the UVs (its resolution is the map's, not
 * the mesh's: subdividing the mesh does not sharpen it). */
int prt_method_light_map(const prt_method *m);
/* The bake option of m that bakes a light map over the UVs instead of per-vertex transfer (its
 * value the map's size, 0 = off), or NULL when m has none (or always bakes one). */
const char *prt_method_light_map_option(const prt_method *m);
/* 1 when m's relighting can leave its last passes to the renderer (prt_relight_desc.gpu_finish),
 * as offset transfer maps do. */
int prt_method_gpu_passes(const prt_method *m);
/* 1 when m relights environments at all frequencies (the sharp shadow of a sky's sun), so that
 * refining a scene for it should probe the sun's shadow edges (prt_refine_desc.extra_lights). */
int prt_method_sharp_environment(const prt_method *m);
/* Checks that m relights everything `what` (PRT_LIGHTS_* bits) holds. On failure the error names
 * what is missing and the methods of the table that relight it, or says that none does. */
prt_status prt_method_check_lighting(const prt_method *m, unsigned what);
/* Names of the methods relighting every bit of `what`, comma separated, into buf ("" if none). */
void prt_methods_relighting(unsigned what, char *buf, size_t size);

/* ---- Bake options, declared once per method ---- */
typedef enum prt_option_type {
    PRT_OPTION_FLAG = 1,   /* no value */
    PRT_OPTION_INT,        /* min..max */
    PRT_OPTION_FLOAT,      /* min..max */
    PRT_OPTION_CHOICE,     /* one of `choices` ("cpca|pca|vq") */
    PRT_OPTION_LIST,       /* comma list of `choices` items */
    PRT_OPTION_TEXT        /* free text: a file name, a BRDF spec, ... */
} prt_option_type;

typedef struct prt_option_desc {
    const char *name;      /* the long option without dashes: "order" */
    const char *arg;       /* placeholder in help texts ("N", "SPEC"); NULL for flags */
    prt_option_type type;
    double min, max;       /* INT and FLOAT ranges, inclusive */
    const char *choices;   /* CHOICE and LIST: items separated by '|' */
    const char *help;      /* what it does and its default; lines separated by '\n' */
} prt_option_desc;

/* The method's bake options: *out points at count entries. */
int prt_method_options(const prt_method *m, const prt_option_desc **out);
/* The option of m called name, or NULL. */
const prt_option_desc *prt_method_option(const prt_method *m, const char *name);

/* A set of option values for one method, as a user gave them. */
typedef struct prt_options prt_options;
prt_status prt_options_create(const prt_method *m, prt_options **out);
void prt_options_release(prt_options *o);
/* Checks value against the declaration and stores it (a later value replaces an earlier one).
 * value is NULL for flags. Errors name the option: "--order must be an integer in 1..10". An
 * option m does not declare is an error that names the methods declaring it. */
prt_status prt_options_set(prt_options *o, const char *name, const char *value);
/* The value given for name, NULL when not given ("" for a given flag). */
const char *prt_options_get(const prt_options *o, const char *name);
const prt_method *prt_options_method(const prt_options *o);
/* 1 when a bake with these options writes a light map (prt_method_light_map, or the method's
 * light-map option given and not 0): its resolution is the map's, not the mesh's. */
int prt_options_light_map(const prt_options *o);

/* ---- Baking ---- */
/* A spreadable stage handed to prt_bake_run_desc.spread; valid during that call. */
typedef struct prt_bake_work prt_bake_work;

typedef struct prt_bake_run_desc {
    prt_progress_fn progress;   /* stage names and done/total units; return non-zero to cancel */
    void *progress_user;
    /* Resumable bakes: the results of every finished work unit are appended to this file as the
     * unit completes (each record checksummed, so a process killed at any moment leaves a usable
     * file). prt_bake leaves it in place when it succeeds (delete it once the result is saved) or
     * stops in a way a later run can continue (cancelled, out of memory, I/O, backend), and
     * deletes it when it fails on its input or options. Without resume an
     * existing file is started afresh. Two bakes cannot share one (the second fails). NULL = none.
     * A checkpoint names its bake by the prt version, method, options as given and the scene;
     * resuming it with a build of other code of the same version is not detected. */
    const char *checkpoint;
    /* Non-zero: take every unit the checkpoint already holds instead of computing it (a checkpoint
     * of another bake - other scene, method, options or prt version - is an error; a missing one
     * is an empty one). The result is byte-identical to an uninterrupted bake. */
    int resume;
    /* Filled in when not NULL: work units taken from the checkpoint, and units of every stage run. */
    uint64_t *recovered_units, *total_units;

    /* ---- Bakes over many machines (docs/CLUSTER.md) ----
     * A stage whose units keep records (what checkpoints hold) can be spread; `whole` steps and
     * stages without records run wherever the bake goes on. The fields below read the checkpoint
     * without writing to it (any number of processes may read one file at once). */
    /* Shards: shard_count > 0 computes only the units u with u % shard_count == shard_index - 1
     * (shard_index in 1..shard_count) of the first spreadable stage the checkpoint does not hold
     * whole, writes their records to `shard` (a checkpoint-format file that also names the bake,
     * the stage, I/N, the checkpoint it continued and shard_note), and stops there: prt_bake
     * returns PRT_OK with *out NULL. stage_given: that stage must be `stage` (an error otherwise).
     * prt_bake_merge_shards puts the shards back together. */
    int shard_index, shard_count, stage_given, stage;
    const char *shard;
    const char *shard_note;     /* free text kept in the shard (prt merge keeps the bake's command) */
    /* Non-zero: stop (PRT_OK, *out NULL) at the first spreadable stage the checkpoint does not
     * hold whole instead of computing it; with stage_seen, a list of the stages so far. */
    int stop_at_missing;
    /* Filled in when not NULL: the stage the bake stopped at (a shard's stage, or where
     * stop_at_missing stopped), or -1 when it ran to the end. */
    int *stopped_stage;
    /* Called as each stage begins: its index, name, units (0 for a `whole` step), whether it can be
     * spread, and how many of its units the checkpoint holds. */
    void (*stage_seen)(void *user, int index, const char *name, uint64_t units, int spreadable, uint64_t recorded);
    void *stage_user;
    /* Spreads every spreadable stage over processes (prt bake under mpirun): called on every
     * process for each such stage, it must leave every unit done, through prt_bake_work_run
     * (computed here) or prt_bake_work_put (a record computed elsewhere). NULL: the units run here. */
    prt_status (*spread)(void *user, prt_bake_work *work);
    void *spread_user;

    /* ---- Memory ----
     * The bytes the bake may hold (0: prt_memory_default_limit(), half the physical memory;
     * UINT64_MAX: no limit). Before any work the method estimates its peak from the scene and
     * options: over the limit, a method that can streams (SH keeps its ray hits in a scratch file
     * instead of memory: the same bytes result), and one that cannot is refused at once with a
     * line saying what it would need and which option lowers it. Only prt_bake (options) is held
     * to it. The process's peak resident memory is kept in the transfer (prt_transfer_peak_bytes). */
    uint64_t memory_limit;
} prt_bake_run_desc;

int prt_bake_work_stage(const prt_bake_work *w);
const char *prt_bake_work_name(const prt_bake_work *w);
uint64_t prt_bake_work_units(const prt_bake_work *w);
int prt_bake_work_threads(const prt_bake_work *w);     /* thread may be 0..this-1 below */
int prt_bake_work_done(const prt_bake_work *w, uint64_t unit);
int prt_bake_work_cancelled(const prt_bake_work *w);
/* Computes unit on this process (thread: the calling thread's slot, each slot used by one thread at
 * a time) and returns its record in *data, *size (valid until the slot's next call). */
prt_status prt_bake_work_run(prt_bake_work *w, uint64_t unit, int thread, const void **data, size_t *size);
/* Takes a record computed elsewhere (thread-safe for distinct units); PRT_ERR_FORMAT when it does
 * not fit the bake. */
prt_status prt_bake_work_put(prt_bake_work *w, uint64_t unit, const void *data, size_t size);
/* The record of a done unit (as prt_bake_work_run gives it). */
prt_status prt_bake_work_record(prt_bake_work *w, uint64_t unit, int thread, const void **data, size_t *size);

/* What a shard file holds (prt_bake_shard_info). */
typedef struct prt_bake_shard {
    int index, count;           /* I/N */
    int stage;                  /* -1: the bake had no stage left to spread */
    char stage_name[48];
    uint64_t units, records;    /* the stage's units; records the shard holds */
    char from[4096];            /* the checkpoint it continued ("" for none) */
    char *note;                 /* shard_note (malloc'd; free it) */
} prt_bake_shard;
/* Reads a shard's description; PRT_ERR_FORMAT for a file that is not a whole shard. */
prt_status prt_bake_shard_info(prt_context *ctx, const char *path, prt_bake_shard *out);
/* Checks that the shards belong together (one bake, one stage, one checkpoint continued, I/N with
 * every I from 1 to N once) and writes `out`: a checkpoint holding the records of the checkpoint
 * they continued and of all the shards, from which prt_bake resumes (stop_at_missing then tells
 * whether stages remain). Each refusal names the file and what differs. info (may be NULL) gets
 * the first shard's description. */
prt_status prt_bake_merge_shards(prt_context *ctx, const char *const *paths, int count, const char *out, prt_bake_shard *info);

/* Bakes scene with method m (o may be NULL for its defaults). The method runs as stages of
 * independent work units; results do not depend on the thread count. Restored units are
 * announced through the log hook (PRT_LOG_INFO) and counted as done in the progress. */
prt_status prt_bake(prt_context *ctx, const prt_scene *scene, const prt_method *m, const prt_options *o,
                    const prt_bake_run_desc *run, prt_transfer **out);
/* Key-framed PRT (animated objects): bakes count (2..1024) key frames of one object - scenes of
 * the same topology: vertex and triangle counts and indices; else an error naming the first key
 * frame (1-based) that differs - each with o, and joins them into one transfer that holds every
 * frame, compressed across frames where the method compresses (prt_transfer_at_time reads a pose
 * between them). Methods without key frames refuse. run's checkpoint is not used. */
prt_status prt_bake_frames(prt_context *ctx, const prt_scene *const *frames, int count, const prt_method *m, const prt_options *o,
                           const prt_bake_run_desc *run, prt_transfer **out);

/* ---- What a file holds ---- */
const prt_method *prt_transfer_method(const prt_transfer *t);
/* A description of t: human-readable lines ("label:  value") or, with json != 0, a JSON object
 * (method-independent fields - file, method, vertices, triangles, transfer_bytes,
 * bytes_per_vertex, bake_seconds, bake_threads, source, materials, lights - plus the method's
 * own). The string is malloc'd: free() it. `name` is shown as the file name. */
prt_status prt_transfer_describe(const prt_transfer *t, const char *name, int json, char **out);

/* Bytes of the method's data in t (what files store beyond the mesh): the storage every method's
 * description and bake summary report. */
size_t prt_transfer_bytes(const prt_transfer *t);
/* How long the bake took and on how many threads (informational: the result is the same for any
 * thread count), and the scene it read. */
double prt_transfer_bake_seconds(const prt_transfer *t);
/* The process's peak resident memory when the bake ended, and the limit it was held to (bytes;
 * 0: not known, as in files of older versions). Bookkeeping like the bake time. */
uint64_t prt_transfer_peak_bytes(const prt_transfer *t);
uint64_t prt_transfer_memory_limit(const prt_transfer *t);
int prt_transfer_bake_threads(const prt_transfer *t);
const char *prt_transfer_source(const prt_transfer *t);
/* Light arriving at points around a baked scene (a method's neighbourhood transfer: SH bakes it
 * with --neighbourhood N): 1 and the box it covers (lo, hi may be NULL) when t holds it, else 0. */
int prt_transfer_light_at_box(const prt_transfer *t, float lo[3], float hi[3]);
/* The radiance arriving at p under l's distant part (environment, directional lights), as SH of
 * the method's order: what an object moved to p is lit by, the scene's shadow and the light its
 * surfaces reflect included. An error naming how to bake it when t holds none. */
prt_status prt_transfer_light_at(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float p[3], prt_sh_light *out);

/* Text lines the method shows once after a bake (for example the separable BRDF fit error per
 * number of terms); *out is malloc'd (free it) and "" when there is nothing to say. */
prt_status prt_transfer_bake_report(const prt_transfer *t, char **out);

/* Variants: what a file can be relit as (for SH: its transfer kinds; one for single-variant
 * methods). Index 0..count-1. */
int prt_transfer_variant_count(const prt_transfer *t);
const char *prt_transfer_variant_name(const prt_transfer *t, int index);
/* The variant a command uses when none is asked for: the richest view-independent one
 * (drawing = 0) or the richest to draw (drawing != 0: glossy where present). */
int prt_transfer_default_variant(const prt_transfer *t, int drawing);
/* Index of the variant called name (a method may accept abbreviations), or -1 after recording an
 * error that lists the file's variants. */
int prt_transfer_find_variant(const prt_transfer *t, const char *name);

/* Run-time controls the method offers (a viewer binds them to keys; scripts name them). */
typedef struct prt_control_desc {
    const char *name;      /* "order", "light-coefficients" */
    const char *help;
    int key_down, key_up;  /* suggested keys (GLFW codes: upper-case ASCII, '[', ']') */
    int multiplicative;    /* non-zero: keys halve and double the value; else -1 and +1 */
} prt_control_desc;
#define PRT_MAX_CONTROLS 8
int prt_transfer_controls(const prt_transfer *t, const prt_control_desc **out);
/* Range and default of control i for this file. */
void prt_transfer_control_range(const prt_transfer *t, int index, int *lo, int *hi, int *def);

/* ---- Export: what a method hands other tools beyond relit meshes ----
 * A method may declare export options (prt export --help lists them under the method): the SH
 * method's transfer as glTF attributes and a shader, offset transfer maps as images. A program
 * makes the options for the file's method, sets what the user gave, and calls prt_transfer_export
 * before it writes the relit mesh (if any): the method writes its own files and hands back
 * attributes for a glTF mesh. */
int prt_method_export_options(const prt_method *m, const prt_option_desc **out);
const prt_option_desc *prt_method_export_option(const prt_method *m, const char *name);
/* Options checked against m's export declarations (prt_options_set, prt_options_get and
 * prt_options_release as for bake options; an option of another method's exports is an error
 * naming that method). */
prt_status prt_export_options_create(const prt_method *m, prt_options **out);

typedef enum prt_export_mesh {
    PRT_EXPORT_NO_MESH = 0,   /* only the method's own files */
    PRT_EXPORT_MESH_GLTF,     /* a glTF mesh is written beside them: custom attributes possible */
    PRT_EXPORT_MESH_OTHER     /* a PLY or OBJ mesh: colours only */
} prt_export_mesh;

typedef struct prt_export_desc {
    const prt_options *options;     /* made by prt_export_options_create for t's method; NULL = none given */
    const prt_lighting *lighting;   /* what the mesh is relit under (required with a mesh) */
    int variant;                    /* what it is relit as; -1 = prt_transfer_default_variant(t, 0) */
    /* Run-time controls the user chose (laid out as prt_relight_desc.controls); NULL = none. A
     * method's export may refuse values its files cannot carry (SH attributes hold order 3). */
    const int *controls;
    prt_export_mesh mesh;
    const char *source;             /* the file's name, for what exported files say of their origin */
} prt_export_desc;

typedef struct prt_export_result {
    /* Per-vertex attributes for a glTF mesh, as prt_mesh_export_desc takes them. */
    int attribute_count;
    float *attributes;
    const char *const *attribute_names;   /* static strings */
    /* When not NULL, the per-vertex colours (3 per vertex, linear) the mesh must carry so that
     * they agree with what the attributes give under the lighting (for example relit at the
     * attributes' SH order); NULL = the relit radiance as usual. */
    float *radiance;
    /* Files written; a program removes them when it then cannot write the mesh. */
    int file_count;
    char **files;
    char *report;                   /* lines saying what was written ("" when nothing) */
} prt_export_result;

/* Runs t's method's export with the options given: writes its files (atomically) and fills out.
 * A method without export options accepts only none. PRT_ERR_INVALID_ARG when the options do not
 * fit the file or the mesh (an SH attribute export to PLY, say), with nothing written. */
prt_status prt_transfer_export(prt_context *ctx, const prt_transfer *t, const prt_export_desc *desc, prt_export_result *out);

/* ---- A web page (prt export --web DIR) ----
 * DIR/index.html and its scripts: WebGL2, no network, no build step, opened from the file system
 * with a double click (classic <script src> tags: data as base64 in data.js). It opens at the
 * camera given, tone-maps as prt render's PNGs do, and relights live with the method's run-time
 * controls (environment rotation and intensity, lights). Methods without a page are refused
 * (prt_method_web says which have one). */
typedef struct prt_web_desc {
    const char *dir;                    /* made when missing; its files are replaced */
    float eye[3], target[3], up[3];     /* prt render's camera (up all zero = +y) */
    float fov_y_deg;                    /* vertical; 0 = 40 */
    int width, height;                  /* the canvas in CSS pixels; 0 = 800 x 600 */
    float exposure_stops;               /* as prt_image_save_desc */
    int tonemap;                        /* 0 or 1 Reinhard on luminance, 2 clamp */
    float background[3];                /* linear radiance where no surface is hit */
} prt_web_desc;
/* Writes the page for t relit as desc says (lighting, variant, controls; options and mesh are
 * ignored); out gets the files written and report lines. Nothing is left on failure. */
prt_status prt_transfer_export_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *desc, const prt_web_desc *web,
                                   prt_export_result *out);
/* Non-zero when m's files can be exported as a web page. */
int prt_method_web(const prt_method *m);
void prt_export_result_free(prt_export_result *r);

/* ---- Relighting ---- */

typedef struct prt_relight_desc {
    int variant;            /* 0..count-1; -1 = prt_transfer_default_variant(t, 1) */
    int component;          /* PRT_COMPONENT_*: all light, only direct, only the bounced part */
    int per_vertex;         /* no per-texel maps: shade from the vertex sets */
    int with_indirect;      /* also fill prt_relit.indirect when the method can separate it */
    /* Values of the method's controls (prt_transfer_controls), one for each of them - a method
     * may gain controls (spectral: bounces, then tail), so fill them from
     * prt_transfer_control_range's defaults and set those you mean; NULL = their defaults. */
    const int *controls;
    /* A BRDF for view-dependent evaluation where the method lets the renderer choose it (SH sets
     * holding incident radiance); NULL = each vertex's material. It replaces the lobe of the
     * vertices whose material is glossy, and diffuse surfaces stay diffuse (a scene without
     * glossy materials refuses it) unless brdf_everywhere is set, which gives every vertex the
     * lobe. Files with nothing it could shape refuse it (other methods, SH files without glossy
     * sets or with a BRDF baked in). */
    const prt_brdf *brdf;
    int brdf_everywhere;
    /* Keep every light in radiance and texels even when relit for drawing: nothing will draw
     * lights per pixel (a light map written to a file). */
    int no_pixel_lights;
    /* Diffuse albedo per vertex (3 floats each, linear RGB in [0, 1]) replacing the baked one, for
     * methods that let surface colours change without a rebake (prt_method_runtime_albedo); NULL
     * = as baked. Other methods refuse it. */
    const float *albedo;
    /* Leave the last step to the GPU where the method has one (prt_method_gpu_passes; offset
     * maps: the modulate-shift-accumulate passes): prt_relit.gpu_passes and gpu_input are filled
     * instead of texels, and a renderer given the result (prt_relit_render_mesh) finishes it.
     * Other methods ignore it. */
    int gpu_finish;
    /* BRDF switching (the spectral paper's Fig. 7): per named surface k (1..
     * prt_transfer_surface_count; entry 0 unused), the index of the BRDF of its baked set
     * (prt_transfer_brdf_set) to reflect with, or -1 for the one it was baked wearing. Only the
     * glossy reflection changes here; the BRDF's Lambertian part is the surface's albedo, which
     * `albedo` (NULL: each chosen BRDF's Lambertian part, elsewhere as baked) says. NULL = every
     * surface as baked. Methods that keep no sets refuse a choice. */
    const int *brdf_of;
    /* First-order light painted onto the surface (prt/paint.h): paint_width x paint_height RGB
     * over the file's light map (prt_paint_size), irradiance / pi added to what the lights
     * deliver, then reflected, scattered and bounced with it. NULL = none. Methods without a
     * first-order light map (prt_method_paintable) refuse it, saying why. */
    const float *paint;
    int paint_width, paint_height;
    /* Non-zero: a light the method finds it cannot carry in this scene (an SH file's lamp inside a
     * closed room, which its transfer sees blocked beyond the lamp) is left out with a warning
     * through the log hook instead of refused - for lights the file's scene named rather than
     * lights asked for. */
    int leave_out_unreachable;
} prt_relight_desc;

/* What relighting produced: everything the renderer draws. Arrays are owned by the result
 * (prt_relit_free) except view_maps/view_set, which are borrowed from the transfer. */
typedef struct prt_relit {
    size_t vertex_count;
    float *radiance;          /* 3 per vertex, linear: the view-independent part */
    float *indirect;          /* 3 per vertex: light that bounced at least once; NULL when not asked or not separable */
    /* View-dependent part as SH exit vectors (3 x exit_order^2 per vertex), evaluated at the view
     * direction or at its mirror (exit_mirror). */
    float *exit_sh;
    int exit_order, exit_mirror;
    /* Per-texel radiance over the mesh's UVs (width x height RGB, row 0 at v near 0), drawn in
     * place of `radiance`. */
    float *texels;
    int texel_width, texel_height;
    /* View-dependent part as separable view factors: per vertex kvec_terms RGB light-dependent
     * terms and the view maps of its material (see prt_render_mesh). */
    float *kvec;
    int kvec_terms;
    const uint8_t *view_set;
    const float *view_maps;
    int view_map_sets, view_map_resolution, view_map_polar;
    /* Local lights whose direct light the renderer draws per pixel with shadow maps, left out
     * of `radiance` (methods that relight local lights do this when relit for drawing, that is
     * per_vertex = 0), and the albedo they shade, 3 per vertex. prt_relit_shade adds them per
     * vertex with shadow rays. NULL / 0 when radiance holds all the light. */
    prt_light *pixel_lights;
    int pixel_light_count;
    float *pixel_albedo;
    /* Per pixel light and vertex ([light][vertex]): whether the vertex sees the light (shadow
     * rays from the vertex; a fraction for sphere lights). The renderer keeps the light off
     * triangles none of whose vertices see it, so that a shadow map's texels cannot leak light
     * along a room's seams. */
    float *pixel_visibility;
    /* The glossy part of each vertex's material under the pixel lights (as baked, or as
     * relighting switched it: prt_relight_desc.brdf_of): per vertex 0 = Lambert (pixel_albedo
     * alone), k = pixel_brdfs[k - 1], whose glossy lobe the renderer evaluates per pixel at the
     * view direction. NULL when no vertex under the pixel lights is glossy; then the result stays
     * view-independent. */
    uint8_t *pixel_material;
    prt_brdf *pixel_brdfs;
    int pixel_brdf_count;
    /* With desc.gpu_finish, for methods with GPU passes: the passes (borrowed from the transfer),
     * the first-order input they start from, per texel over the texel map (texel_width x
     * texel_height RGB: irradiance / pi, zero off the surface), the emission scale, and the
     * bounces and component asked for; texels is NULL and radiance holds albedo x irradiance /
     * pi plus emission (the light before scattering and bounces). NULL otherwise. */
    const prt_render_passes *gpu_passes;
    float *gpu_input;
    float gpu_emission;
    int gpu_bounces, gpu_component;
    /* With gpu_input and pixel_lights: per texel (as gpu_input), the pixel lights' first-order
     * light (albedo x their irradiance / pi on opaque texels), which the passes keep for the
     * bounces but the shown maps leave out, as the CPU's texels do; radiance leaves it out too.
     * NULL otherwise. */
    float *gpu_pixel_direct;
    /* Participating media relit (the SH method's volumes): extinction and source arrays owned
     * by the result. NULL / 0 when the file holds none. */
    prt_render_volume *volumes;
    int volume_count;
    /* With desc.gpu_finish, for methods whose per-vertex light the GPU finishes: the products
     * (borrowed from the transfer) and the per-frame vector they start from (vector_length RGB);
     * radiance then holds only what the CPU computed, and the products' shown rows add the rest
     * (prt_render_sums). NULL otherwise. */
    const prt_render_sums *gpu_sums;
    float *gpu_vector;
} prt_relit;

/* The PRT_LIGHTS_* bits relighting t under lighting needs: what the lighting holds, with
 * PRT_LIGHTS_EMISSIVE only when t's scene emits and the emission scale is above zero. */
unsigned prt_relight_needs(const prt_transfer *t, const prt_lighting *lighting);

/* Relights t under lighting. The method refuses lighting it cannot relight (the error names the
 * methods that can). desc NULL = defaults. */
prt_status prt_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *lighting, const prt_relight_desc *desc,
                       prt_relit *out);
void prt_relit_free(prt_relit *r);
/* The mesh of t with what r holds, for prt_render or a prt_window (borrowed pointers). */
void prt_relit_render_mesh(const prt_transfer *t, const prt_relit *r, prt_render_mesh *out);
/* Exit radiance per vertex towards the world position eye (3 floats per vertex): the
 * view-independent part plus the view-dependent part evaluated on the CPU, as the renderer does
 * per pixel. eye may be NULL when r has no view-dependent part. Per-texel maps are not used. */
prt_status prt_relit_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *out_rgb);
/* 1 when r's radiance depends on the view. */
int prt_relit_view_dependent(const prt_relit *r);

/* The lighting the baked scene named (environment, lights, emissive surfaces), loaded: what
 * commands relight with when the user gives no lighting. */
prt_status prt_transfer_lighting(prt_context *ctx, const prt_transfer *t, prt_lighting **out);
/* The baked mesh as a scene (materials, UVs, emission, lights, environment; no cleaning or
 * subdivision, so vertices match t's one for one): what the reference path tracer traces. */
prt_status prt_transfer_scene(prt_context *ctx, const prt_transfer *t, prt_scene **out);
/* The scene's local lights and emission, as baked. */
int prt_transfer_light_count(const prt_transfer *t);
const prt_light *prt_transfer_light(const prt_transfer *t, int index);
const float *prt_transfer_emission(const prt_transfer *t);   /* 3 per vertex; NULL when nothing emits */

#ifdef __cplusplus
}
#endif
#endif
