/* A method's entry in the method table (methods/table.c) and what the method-independent layer
 * (transfer/: bake.c, checkpoint.c, file.c, describe.c, export.c, transfer.c, options.c) offers
 * the entries. A method is its own folder, src/methods/NAME/ (its entry, state header NAME.h,
 * bake, run time, chunks, exports, GPU passes), plus one line in the table; see
 * docs/ARCHITECTURE.md. */
#ifndef PRT_TRANSFER_METHOD_H
#define PRT_TRANSFER_METHOD_H

#include "core/progress.h"
#include "io/container.h"
#include "transfer/checkpoint.h"
#include "transfer/transfer.h"
#include "transfer/web.h"

#include <cjson/cJSON.h>

typedef struct prt_method prt__method;

/* ---- Bakes as stages of independent work units ----
 * transfer/bake.c drives every method's bake: it asks for stage 0, runs its units on all threads
 * (in any order: a unit's result depends only on its inputs), reports progress and honours
 * cancellation between units, then asks for stage 1, and so on; a stage with no units and no
 * `whole` step ends the bake. Progress, cancellation and (later) checkpoints and sharding are
 * written once, here, for every method. */
typedef struct prt__bake_job prt__bake_job;

typedef struct prt__stage {
    char name[48];                 /* shown in progress ("visibility", "bounce 2/3") */
    uint64_t units;
    /* Runs one unit; thread in 0..job->threads-1 picks per-thread scratch. */
    prt_status (*run)(prt__bake_job *job, uint64_t unit, int thread);
    /* A step with parallel loops of its own (k-means, a BRDF fit), run once instead of units;
     * it reports through p and checks p for cancellation. */
    prt_status (*whole)(prt__bake_job *job, prt_context *ctx, prt__progress *p);
    /* Resumable bakes (transfer/checkpoint.h): writes everything unit `unit` produced into out, and
     * puts it back from those bytes (false when they do not fit the job: a corrupt checkpoint).
     * NULL: the stage's units run again on resume. */
    void (*save_unit)(prt__bake_job *job, uint64_t unit, prt__bytes *out);
    bool (*load_unit)(prt__bake_job *job, uint64_t unit, const unsigned char *data, size_t size);
} prt__stage;

struct prt__bake_job {
    /* Describes stage `index` (all earlier stages have finished); leave *out zeroed to end. */
    prt_status (*stage)(prt__bake_job *job, int index, prt__stage *out);
    /* Moves the results into t's state after the last stage. */
    prt_status (*finish)(prt__bake_job *job, prt_transfer *t);
    void (*release)(prt__bake_job *job);
    prt_context *ctx;
    int threads;                   /* set before the first stage */
    /* Set before the first stage (prt_bake_run_desc.memory_limit, transfer/bake.c): the bytes the
     * bake may hold (UINT64_MAX: no limit), and whether the method's estimate of an unbounded bake
     * (memory_estimate) is over it: then the method streams what it can. */
    uint64_t memory_limit;
    bool memory_over;
};

/* ---- Memory (prt_bake_run_desc.memory_limit) ----
 * A method's estimate of its bake's peak from the scene and options alone, before any work: the
 * driver adds what every bake holds (the transfer's mesh, the ray caster's tree) and refuses a
 * bake whose `least` is over the limit, naming `lower`. */
typedef struct prt__memory_estimate {
    uint64_t bytes;        /* the method's own data at its peak, baked as it would be without a limit */
    uint64_t least;        /* the same when streaming (== bytes: the method cannot stream) */
    char what[160];        /* what the bytes are ("ray hits of 1024 directions per vertex") */
    char lower[160];       /* the options that lower it ("--samples or --order") */
} prt__memory_estimate;
/* What the transfer's mesh and a ray caster over it hold (bytes). */
uint64_t prt__memory_scene_bytes(const prt_transfer *t);

/* Runs a job to the end (progress and cancellation through run, which may be NULL), then frees
 * it; t's bake_seconds and threads are filled in. Used by prt_bake and the methods' own bake
 * functions (a method's own public bake function with its desc struct). */
prt_status prt__bake_drive(prt_context *ctx, prt__bake_job *job, const prt_bake_run_desc *run, prt_transfer *t);
/* The same with a checkpoint (NULL = none); the driver takes units from it and adds to it. */
prt_status prt__bake_drive_checkpointed(prt_context *ctx, prt__bake_job *job, const prt_bake_run_desc *run, prt__checkpoint *cp,
                                        prt_transfer *t);

/* The frame every bake entry point shares: a transfer of method m made from the scene, the job
 * `begin` sets up from desc, the driver. */
typedef prt_status (*prt__bake_begin_fn)(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job);
prt_status prt__bake_with(prt_context *ctx, const prt_scene *scene, const prt__method *m, prt__bake_begin_fn begin, const void *desc,
                          const prt_bake_run_desc *run, prt_transfer **out);

/* ---- Options (transfer/options.c) ---- */
const char *prt__opt(const prt_options *o, const char *name);   /* NULL when not given */
int prt__opt_int(const prt_options *o, const char *name, int fallback);
float prt__opt_float(const prt_options *o, const char *name, float fallback);
bool prt__opt_flag(const prt_options *o, const char *name);
/* Index of the given item of a CHOICE option's choices, or fallback. */
int prt__opt_choice(const prt_options *o, const char *name, int fallback);
/* True for options made by prt_export_options_create. */
bool prt__options_exporting(const prt_options *o);
/* True for the options prt_bake_frames bakes each key frame with: the method leaves out what its
 * join_frames does across all frames instead (compression, quantization). */
bool prt__options_keyframe(const prt_options *o);
/* A copy of o (NULL: defaults) for method m with that mark set. */
prt_status prt__options_keyframe_copy(const prt_method *m, const prt_options *o, prt_options **out);
/* Adds the options as given (sorted by name, so the order on a command line does not matter). */
void prt__options_fingerprint(const prt_options *o, prt__fingerprint *fp);
/* Adds the scene as t holds it - mesh (positions, normals, albedo, materials, UVs, emission,
 * triangles) and BRDFs at full precision - to fp: what any baked result depends on. */
void prt__transfer_fingerprint_scene(const prt_transfer *t, prt__fingerprint *fp);

/* ---- Descriptions (transfer/describe.c) ----
 * One code path writes both forms: text lines for people, fields for JSON. */
typedef struct prt__describe {
    bool json;
    cJSON *root;        /* JSON mode: the object fields go into */
    char *text;         /* text mode: the lines so far */
    size_t length, capacity;
    bool failed;
} prt__describe;
/* A "label:   value" text line (nothing in JSON mode). */
void prt__describe_line(prt__describe *d, const char *label, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* The JSON object to add fields to, or NULL in text mode. */
static inline cJSON *prt__describe_json(prt__describe *d) { return d->json ? d->root : NULL; }

/* ---- Painted first-order light (prt/paint.h) ----
 * The light map a painting covers and its texels on the surface, borrowed from the transfer. */
typedef struct prt__paint_layout {
    int width, height;
    uint32_t covered;
    const uint32_t *texel;       /* [covered] y * width + x */
    const float *pos, *nrm;      /* [covered][3] the texels' surface points and normals */
} prt__paint_layout;
/* prt_relight's checks of desc->paint (transfer/paint.c): a method with a layout, the map's size,
 * values finite and >= 0 on the surface. */
prt_status prt__paint_check(const prt_context *ctx, const prt_transfer *t, const prt_relight_desc *d);

/* ---- The entry ---- */
struct prt_method {
    const char *name;       /* what --method and the file's META call it */
    const char *title;      /* "spherical-harmonic PRT" */
    const char *summary;    /* one line */
    unsigned lighting;      /* PRT_LIGHTS_* it relights */
    bool runtime_albedo;    /* relight honours prt_relight_desc.albedo */
    const char *baked_albedo_why;   /* without runtime_albedo: why colours need a rebake (one clause), or NULL */
    bool light_map;         /* always bakes a light map (prt_method_light_map) */
    const char *light_map_option;   /* its INT option that bakes a light map of that size instead of
                                     * per-vertex transfer (0 = off), or NULL (prt_method_light_map_option) */
    bool gpu_passes;        /* relight honours prt_relight_desc.gpu_finish (prt_method_gpu_passes) */
    bool sharp_environment; /* relights environments at all frequencies: sharp shadows of a sky's
                             * sun, which refinement probes (prt_method_sharp_environment) */
    const prt_option_desc *options;
    int option_count;
    const prt_control_desc *controls;
    int control_count;
    /* prt export: options of its own and what they write (prt_transfer_export: d has its
     * defaults filled and its options checked against export_options; out is zeroed). */
    const prt_option_desc *export_options;
    int export_option_count;
    prt_status (*export_files)(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt_export_result *out);
    /* prt export --web (transfer/web.h): the arrays, parameters and relighting script the page
     * needs beyond the mesh and the view, for t relit as d says (lighting, variant, controls).
     * NULL: no page; prt_transfer_export_web refuses the file. */
    prt_status (*web)(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page);

    /* Bake: set up a job for t (which holds the scene's mesh, materials and lighting). */
    prt_status (*bake_begin)(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job);
    /* Its bake's memory from t's scene and the options (threads: the bake's), filled into out
     * (zeroed); NULL: the method's data is small beside the scene's. */
    void (*memory_estimate)(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *out);
    void (*free_state)(void *state);

    /* Files: the method's META fields and chunks; load consumes its chunks (marking them used),
     * checks every count against the file and the mesh, and builds t->state. */
    void (*save_meta)(const prt_transfer *t, cJSON *meta);
    prt_status (*save)(const prt_transfer *t, prt__chunk_list *out);
    prt_status (*load)(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count);

    /* What the file holds: description lines/fields and the bytes of the method's data. */
    void (*describe)(const prt_transfer *t, prt__describe *d);
    /* Lines worth showing once after a bake (fit errors, warnings); may be NULL. */
    void (*report)(const prt_transfer *t, prt__describe *d);
    size_t (*transfer_bytes)(const prt_transfer *t);

    /* Variants and controls. find_variant may be NULL (exact names only); without variant_count,
     * variant_name and default_variant the file has one variant, named after the method. */
    int (*variant_count)(const prt_transfer *t);
    const char *(*variant_name)(const prt_transfer *t, int index);
    int (*default_variant)(const prt_transfer *t, int drawing);
    int (*find_variant)(const prt_transfer *t, const char *name);
    void (*control_range)(const prt_transfer *t, int index, int *lo, int *hi, int *def);
    /* The candidate BRDFs the bake kept for named surface `surface` (1-based), which relighting
     * switches among (prt_relight_desc.brdf_of): returns their count, *out = entry i when in range.
     * NULL: the method keeps none. */
    int (*brdf_set)(const prt_transfer *t, int surface, int i, prt_brdf *out);

    /* Relight: lighting (already checked against `lighting`) + desc (defaults filled) -> out.
     * shade (may be NULL) adds the view-dependent part of r that only the method can evaluate on
     * the CPU (beyond exit_sh, which is generic), and the direct light of r's pixel_lights, to
     * rgb. */
    prt_status (*relight)(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *out);
    prt_status (*shade)(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb);
    /* Painted first-order light (prt_relight_desc.paint, prt/paint.h): t's light map and texels.
     * NULL: the method relights from no first-order light map, and prt_relight refuses paint. */
    void (*paint_layout)(const prt_transfer *t, prt__paint_layout *out);
    /* Light arriving at points around the scene (prt_transfer_light_at): the box it covers
     * (false: t holds none), and the radiance arriving at p under l's distant part, as SH of the
     * method's order. NULL: the method never holds it. */
    bool (*light_at_box)(const prt_transfer *t, float lo[3], float hi[3]);
    prt_status (*light_at)(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float p[3], prt_sh_light *out);

    /* Key frames (prt_bake_frames, prt_transfer_at_time); NULL: the method bakes one pose.
     * join_frames makes one animated transfer of count (>= 2) transfers baked from key frames of
     * one topology with options marked prt__options_keyframe (o: the bake's options as given).
     * frame_count: the key frames t holds (1: one pose). at_time fills out's state (out: a copy
     * of t's frame, mesh of key frame 0, state NULL) with the pose and transfer between key frames
     * `frame` and frame + 1 at weight w in [0, 1], one pose. */
    prt_status (*join_frames)(prt_context *ctx, prt_transfer *const *frames, int count, const prt_options *o, prt_transfer **out);
    int (*frame_count)(const prt_transfer *t);
    prt_status (*at_time)(prt_context *ctx, const prt_transfer *t, int frame, float w, prt_transfer *out);
};

/* A BRDF as PRT__BRDF_RECORD bytes of a .prt (model, lobes, 38 floats), and back (unchecked:
 * validate what is read). */
#define PRT__BRDF_RECORD 160
void prt__brdf_put(unsigned char *p, const prt_brdf *b);
void prt__brdf_get(const unsigned char *p, prt_brdf *b);

/* Adds a line to an export's report. */
void prt__export_report(prt_export_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Records a file an export wrote (for removal should the mesh fail); false when out of memory. */
bool prt__export_file(prt_export_result *r, const char *path);

/* Allocates the relit arrays of a result for t (radiance always; the rest as flags say). */
prt_status prt__relit_alloc(prt_context *ctx, const prt_transfer *t, prt_relit *r, bool indirect);
/* Fills r's pixel_material and pixel_brdfs with t's materials, where surface_brdf[k] (NULL, or
 * NULL entries: as baked) replaces named surface k's, when any vertex then is glossy (the
 * renderer draws the pixel lights' highlights); leaves them NULL otherwise. */
prt_status prt__relit_pixel_materials(prt_context *ctx, const prt_transfer *t, const prt_brdf *const *surface_brdf, prt_relit *r);

#endif
