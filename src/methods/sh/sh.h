/* The spherical-harmonic method's state (the files of this folder look inside; nothing else
 * does). */
#ifndef PRT_METHODS_SH_H
#define PRT_METHODS_SH_H

#include "compress/cpca.h"
#include "geom/raycast.h"
#include "transfer/method.h"
#include "prt/sh_transfer.h"
#include "methods/sh/volume.h"

#include <pthread.h>

#define PRT__KIND_COUNT 5

typedef struct prt__sh_set {
    int channels;       /* 0 = absent, 1 = albedo applied at relight, 3 = RGB with albedo */
    float *coeffs;      /* [vertex][channel][order^2]; NULL when compressed */
    prt__cpca *cpca;    /* non-NULL when compressed */
    int quant_bits;     /* 0, or 8 / 16: coeffs hold dequantized values and files store integers */
} prt__sh_set;

/* Per-texel transfer over the UV layout: texel (x, y) has its centre at uv ((x + .5) / W,
 * (y + .5) / H); row 0 is v near 0. Diffuse kinds only (index 0..2 as for vertex sets). */
typedef struct prt__texel_sets {
    int width, height;
    float *albedo;        /* [texel][3] */
    uint8_t *covered;     /* [texel]: 1 baked, 2 filled from neighbours, 0 outside every chart */
    int channels[3];
    float *coeffs[3];     /* [texel][channel][order^2] */
    bool halves;          /* coeffs hold IEEE halves' values, as the file stores them */
    bool bytes;           /* coeffs hold 8-bit levels' values (a scale and bias per coefficient), likewise */
} prt__texel_sets;

/* Rounds every texel set to 256 levels per coefficient between its least and greatest value
 * (8-bit quantization, as the file will store it); false when out of memory. */
bool prt__texel_quantize8(prt__texel_sets *tx, int order);

/* Neighbourhood transfer (neighbourhood.c): dims[0] x dims[1] x dims[2] points spanning lo..hi
 * (x fastest), each 3 matrices [channel][order^2][order^2] from distant lighting to the radiance
 * arriving there, and the share of its rays that met no back face (under 1: the point lies inside
 * or behind geometry, and stands in for the space around it less); dims 0 when absent. */
typedef struct prt__sh_grid {
    int dims[3], order;
    float lo[3], hi[3];
    float *matrices;
    float *front;
} prt__sh_grid;

void prt__sh_grid_free(prt__sh_grid *g);
/* The radiance arriving at p as SH of `order` (at most the grid's) under the distant light in. */
/* The table entry's light_at_box and light_at (neighbourhood.c). */
bool prt__sh_light_at_box(const prt_transfer *t, float lo[3], float hi[3]);
prt_status prt__sh_light_at_lighting(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float p[3], prt_sh_light *out);
void prt__sh_neighbourhood_eval(const prt__sh_grid *g, const float p[3], const prt_sh_light *in, int order, prt_sh_light *out);
/* Key frames of an animated object (frames.c; the course notes' "animated objects"): every
 * frame's pose, and each set's rows of every frame [frame][vertex] compressed as one, so that
 * the frames share clusters and basis. */
typedef struct prt__sh_frames {
    int count;                          /* 0: one pose; else >= 2 */
    float *positions;                   /* [frame][vertex][3] */
    float *normals;                     /* likewise, or NULL when the mesh has none */
    prt__cpca *sets[PRT__KIND_COUNT];   /* where sets[k].channels */
} prt__sh_frames;

typedef struct prt__sh_state {
    int order;
    prt__sh_set sets[PRT__KIND_COUNT];   /* indexed by prt__kind_index */
    int samples, bounces;
    uint32_t seed;
    bool glossy_exit;                    /* glossy sets hold exit radiance (BRDF baked in) */
    prt__texel_sets texels;
    prt__sh_grid grid;
    int volume_count;                    /* the scene's participating media (volume.c) */
    prt__sh_volume *volumes;
    /* Key frames; sets[] then hold key frame 0 reconstructed (what relighting without a time uses). */
    prt__sh_frames frames;
    /* Shadow rays for the local-light reach check, built on first use under lock. */
    pthread_mutex_t *lock;
    prt__raycaster rays;
    bool rays_ready;
    /* Diffuse sets' descriptions for the GPU (gpu.c), built on first use under lock. */
    struct prt__gpu_sums *gpu[PRT__KIND_COUNT];
} prt__sh_state;

extern const prt__method prt__method_sh;

/* prt export --web (web.c, web.js). */
prt_status prt__sh_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page);

/* t's SH state, or NULL after recording an error naming t's method when t is not SH transfer. */
prt__sh_state *prt__sh_need(prt_context *ctx, const prt_transfer *t);
static inline prt__sh_state *prt__sh(const prt_transfer *t) { return prt__state_of(t, &prt__method_sh); }
prt__sh_state *prt__sh_state_new(void);
void prt__sh_state_free(void *state);

void prt__texel_sets_free(prt__texel_sets *s);
prt_status prt__texel_sets_copy(prt__texel_sets *dst, const prt__texel_sets *src, int order);

static inline bool prt__kind_glossy(int index) { return index >= 3; }
/* Floats per vertex of set k when uncompressed. */
static inline size_t prt__set_dim(const prt__sh_state *s, int k)
{
    size_t n = (size_t)s->order * (size_t)s->order;
    return (size_t)s->sets[k].channels * n * (prt__kind_glossy(k) ? n : 1);
}
/* 0..4 for UNSHADOWED, SHADOWED, INTERREFLECTED, GLOSSY_SHADOWED, GLOSSY_INTERREFLECTED; -1 otherwise. */
int prt__kind_index(prt_transfer_kind kind);
prt_transfer_kind prt__kind_from_index(int index);

/* What the SH bake does after transfer: compression or quantization (the bake's last stages),
 * and a normal map the job takes over. */
typedef struct prt__sh_extra {
    bool compressing;
    prt_compress_desc compress;   /* defaults filled in (prt__compress_desc_check) */
    int quantize;                 /* 0, 8 or 16 */
    prt_image normal_map;         /* moved into the job when it holds pixels */
    prt_image height_map;         /* likewise */
    const prt_scene *scene;       /* its translucent materials (prt_scene_medium), or NULL */
} prt__sh_extra;

/* The SH bake (bake.c) as stages of work units: validates d (defaults filled in),
 * and sets up the job for t (which holds the scene's mesh and materials). extra may be NULL. */
prt_status prt__sh_bake_begin(prt_context *ctx, const prt_sh_bake_desc *d, prt__sh_extra *extra, prt_transfer *t, prt__bake_job **job);

/* Compression steps (compress.c): defaults filled in and checked; one set compressed in
 * place; every set quantized in place. */
prt_status prt__compress_desc_check(prt_context *ctx, prt_compress_desc *d);
prt_status prt__sh_compress_set(prt_context *ctx, prt__sh_state *s, size_t vertex_count, int k, const prt_compress_desc *d, prt__progress *prog);
prt_status prt__sh_quantize(prt_context *ctx, prt__sh_state *s, size_t vertex_count, int bits);
/* prt_relight_sh_glossy with a choice of where a run-time lobe applies: every vertex, or only
 * the vertices whose scene material is glossy (what prt_relight_desc.brdf_everywhere chooses). */
/* local (NULL = none): per-vertex lighting added to light, [vertex][3][local_order^2]. */
prt_status prt__relight_sh_glossy(prt_context *ctx, const prt_transfer *t, prt_transfer_kind kind, const prt_sh_light *light,
                                  const prt_brdf *brdf, bool brdf_everywhere, const float *local, int local_order, float *out_exit);

/* Local lights (local.c): point, spot, ies and sphere lights as SH of incident radiance at points.
 * Windows on the bands of their projection (and of directional lights'): none, Hanning, Lanczos. */
enum { PRT__SH_WINDOW_NONE, PRT__SH_WINDOW_HANNING, PRT__SH_WINDOW_LANCZOS, PRT__SH_WINDOW_COUNT };
#define PRT__SH_LIGHT_WINDOW_DEFAULT PRT__SH_WINDOW_NONE
/* Is l a light at a point (point, spot, sphere, ies), whose light differs per vertex? */
bool prt__sh_light_positioned(const prt_light *l);
/* Refuses, naming it, a positioned light of l that the file's shadowed transfer finds blocked
 * beyond it from the vertices that see it (a light inside a room): it would light nothing. With
 * leave_out, such lights are marked in out[light] (count of l's lights) with a warning instead. */
prt_status prt__sh_local_reach(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, bool leave_out, uint8_t *out);
/* How many of l's lights have a position. */
int prt__sh_local_count(const prt_lighting *l);
/* sigma[l] for l < order. */
void prt__sh_window(int window, int order, double *sigma);
/* Applies the window to the directional lights that prt_lighting_sh put into sh unwindowed. */
void prt__sh_window_directional(const prt_lighting *l, int window, prt_sh_light *sh);
/* out[point][channel][order^2]: l's positioned lights' incident radiance at each of count points. */
void prt__sh_local_project(prt_context *ctx, const prt_lighting *l, int order, int window, const float *points, size_t count, float *out);
/* Adds to out_rgb what diffuse set k makes of per-vertex lighting local ([vertex][3][order^2],
 * order at most the file's), times albedo for one-channel sets. */
prt_status prt__relight_sh_local(prt_context *ctx, const prt_transfer *t, int k, const float *local, int order, float *out_rgb);
/* The same per texel (points from the file's UV layout), into a texel map. */
prt_status prt__relight_sh_texels_local(prt_context *ctx, const prt_transfer *t, int k, const prt_lighting *l, int order, int window, float *out_rgb);

/* Set k relit for the GPU to finish (gpu.c): r gets zero radiance, the products and the frame's
 * vector (glossy sets: exit order and mirror too, exit_sh left NULL). prt__sh_gpu_can says
 * whether set k can be (diffuse sets; glossy sets, raw or clustered PCA, relit with the
 * materials' own lobes or the BRDF baked in, not a run-time --brdf). */
bool prt__sh_gpu_can(const prt__sh_state *s, int k, const prt_relight_desc *d);
prt_status prt__sh_gpu_relight(prt_context *ctx, const prt_transfer *t, int k, const prt_sh_light *light, prt_relit *r);

/* prt export (export.c): --sh and --glsl. */
prt_status prt__sh_export(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt_export_result *out);

/* Key frames (frames.c): the method entry's join_frames, frame_count and at_time; rows [vertex]
 * of key frame f of a frames' set into out; the frames' storage in bytes. */
prt_status prt__sh_join_frames(prt_context *ctx, prt_transfer *const *frames, int count, const prt_options *o, prt_transfer **out);
int prt__sh_frame_count(const prt_transfer *t);
prt_status prt__sh_at_time(prt_context *ctx, const prt_transfer *t, int frame, float w, prt_transfer *out);
void prt__sh_frame_rows(const prt__cpca *c, size_t vertex_count, int f, float *out);
size_t prt__sh_frames_bytes(const prt__sh_state *s, size_t vertex_count);
void prt__sh_frames_free(prt__sh_frames *f);

/* Its chunks (file.c). */
void prt__sh_save_meta(const prt_transfer *t, cJSON *meta);
prt_status prt__sh_save(const prt_transfer *t, prt__chunk_list *out);
prt_status prt__sh_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count);

#endif
