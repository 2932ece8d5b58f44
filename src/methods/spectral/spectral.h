/* The spectral method's state (Wang, Zhu & Humphreys 2007: direct-to-indirect transfer in a
 * spectral mesh basis): the files of this folder look inside, and - a declared dependency,
 * docs/ARCHITECTURE.md - the light cloud's bake, which runs the spectral stages and run time.
 *
 * The mesh is cut into partitions; partition p carries count[p] basis functions, the lowest
 * frequencies of its own topological Laplacian, numbered first[p] .. first[p + 1] - 1. Vertex v
 * stores the values of its partition's functions at v. The transfer row of vertex v holds, for
 * basis function l, the irradiance at v when the surfaces emit radiance s_l (eq. 7), quantized to
 * 16 bits against a scale of its own (its largest entry is 32767); entries that round to zero or
 * lie below the bake's drop threshold times the row's largest are not stored. (Files written
 * before per-row scales hold one scale for the whole matrix, as the paper: loaded as that scale
 * on every row.) */
#ifndef PRT_METHODS_SPECTRAL_H
#define PRT_METHODS_SPECTRAL_H

#include "geom/raycast.h"
#include "light/light_sample.h"
#include "transfer/method.h"
#include "prt/spectral.h"
#include "light/vertex_lights.h"

#include <pthread.h>
#include <stdio.h>

#define PRT__SPECTRAL_MAX_FUNCTIONS 65535   /* indices are stored in 16 bits */
#define PRT__SPECTRAL_GLOSSY_ORDER 4        /* the glossy final bounce's SH: 16 BRDF bases, as the paper */
#define PRT__SPECTRAL_GLOSSY_N 16
#define PRT__SPECTRAL_MATRIX_FLOATS (3 * PRT__SPECTRAL_GLOSSY_N * PRT__SPECTRAL_GLOSSY_N)   /* one BRDF's SH matrix */
#define PRT__SPECTRAL_MAX_PARTITION 4096    /* vertices per partition: its eigen problem is dense */

typedef struct prt__spectral_basis {
    uint32_t partitions, functions;
    uint32_t *part_of;       /* [vertex] */
    uint32_t *count;         /* [partition] basis functions */
    /* derived by prt__spectral_basis_index: */
    uint32_t *first;         /* [partition + 1] first function of each partition */
    uint64_t *offset;        /* [vertex + 1] where vertex v's values start in `values` */
    uint32_t *members;       /* vertices grouped by partition, ascending within each */
    uint32_t *member_start;  /* [partition + 1] */
    float *values;           /* [offset[v] + j] = s_{first[part_of[v]] + j}(v) */
} prt__spectral_basis;

/* Run-time helpers built on first use (ray casting for shadow rays, the emitters' direct light),
 * guarded by `lock` so that relighting from several threads stays safe. */
typedef struct prt__spectral_cache {
    prt__vertex_lights lights;   /* shadow rays */
    pthread_mutex_t lock;        /* guards frames */
    void *frames;            /* prt__frame_rot[glossy_count]: the glossy vertices' frame rotations */
    struct prt__gpu_sums *gpu;   /* the bounces for the GPU (gpu.c), under lock, for this albedo: */
    float *gpu_albedo;
} prt__spectral_cache;

typedef struct prt__spectral_set {
    prt__spectral_basis basis;
    int samples;             /* gathering rays per vertex at bake time */
    int partition_size;      /* what the bake asked for */
    float ray_offset;
    /* Sparse transfer rows: vertex v's entries are [row_start[v], row_start[v + 1]). */
    uint64_t *row_start;     /* [vertex + 1] */
    uint16_t *index;         /* basis function */
    int16_t *value;          /* times row_scale[v] */
    float *row_scale;        /* [vertex] 0 for an empty row */
    float drop;              /* entries below drop x their row's largest were dropped */
    bool one_scale;          /* loaded from a file with one scale for the matrix (SPCT, SPCG) */
    /* Direct light from the environment: shadowed irradiance transfer per vertex in SH of
     * env_order (the gathering rays that escaped), E = sum_i L_i env[v][i]. */
    int env_order;
    float *env;              /* [vertex][env_order^2] */
    /* Direct irradiance from the scene's emissive surfaces at emission scale 1 (their geometry
     * is static, so it is baked); NULL when nothing emits. */
    float *emit;             /* [vertex][3] */
    /* Glossy final bounce (eq. 8): vertices whose material has a glossy part also store, per SH
     * basis function k of the incident direction (order 4, world frame), the sparse row
     * Tg(x, l, k) = integral over x's hemisphere of s_l(y(x, w)) y_k(w) dw, so that the radiance
     * arriving at x from the surfaces is sum_l Tg(x, l, k) c_l in SH; the material's BRDF matrix
     * turns it into exit radiance seen from any view. Rows of glossy vertex g, function k:
     * [grow_start[g * 16 + k], grow_start[g * 16 + k + 1]). */
    uint32_t glossy_count;
    uint32_t *glossy_of;     /* [vertex] g, or UINT32_MAX for vertices without a glossy material */
    uint64_t *grow_start;    /* [glossy_count * 16 + 1] */
    uint16_t *gindex;
    int16_t *gvalue;         /* times grow_scale[row] */
    float *grow_scale;       /* [glossy_count * 16] */
    /* The environment's direct light on glossy vertices: per glossy vertex g, the shadowed
     * transfer from the environment's SH (env_order) to the incident radiance's SH (order 4,
     * world frame) over the rays that escaped, in = genv[g] L ([16][env_order^2], row-major);
     * the BRDF matrix turns it into exit radiance as for the surfaces' light. Stored as halves
     * (the bake rounds its own copy). NULL in files written before it (the environment then
     * reflects diffusely only). */
    float *genv;
    /* Per material (k - 1) with a glossy part: its local-frame SH matrix (3 x 16 x 16, the
     * glossy part only; prt_brdf_sh_matrix), computed at bake time and kept in the file. */
    float *brdf_matrix[PRT__MAX_BRDFS];
    /* BRDF sets (the paper's Fig. 7: "we precompute and store the projections of several glossy
     * BRDFs, and switch between them on the fly"): candidate BRDFs of named surfaces and the SH
     * matrix of each glossy one (NULL for diffuse ones). The glossy rows hold incident radiance,
     * whatever the BRDF, so a surface with a glossy candidate has them and switching is a matrix
     * swap; projecting a BRDF takes seconds, so it is done at bake time. */
    int set_count;
    prt__brdf_choice *set;   /* [set_count] */
    float **set_matrix;      /* [set_count] */
    prt__spectral_cache *cache;
    /* Only when the bake desc asks (keep_rows: measurements and tests): the rows before
     * quantization, every entry that is not zero, as floats; diffuse and glossy. */
    uint64_t *raw_start;     /* [vertex + 1] */
    uint16_t *raw_index;
    float *raw_value;
    uint64_t *raw_gstart;    /* [glossy_count * 16 + 1] */
    uint16_t *raw_gindex;
    float *raw_gvalue;
} prt__spectral_set;

extern const prt__method prt__method_spectral;

/* Relighting finished on the GPU (gpu.c): whether these controls allow it (no glossy final
 * bounce), and r's products and frame vector (the direct light reflected, per vertex). */
bool prt__spectral_gpu_can(const prt_transfer *t, int bounces, int tail);
/* A third of each triangle's area to each of its corners (relight.c; area zeroed by the caller). */
void prt__spectral_vertex_areas(const prt__mesh *m, float *area);
prt_status prt__spectral_gpu(prt_context *ctx, const prt_transfer *t, const float *albedo, const float *direct, int bounces, int tail, prt_relit *r);

/* prt export --web (web.c, web.js). */
prt_status prt__spectral_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page);

static inline prt__spectral_set *prt__spectral(const prt_transfer *t) { return prt__state_of(t, &prt__method_spectral); }
void prt__spectral_set_free(void *state);
/* The run-time cache of a new state (shadow rays and glossy frames, built on first use); NULL
 * when out of memory. */
prt__spectral_cache *prt__spectral_cache_new(void);
void prt__spectral_basis_free(prt__spectral_basis *b);
/* Derives first, offset, members and member_start from part_of and count; false (nothing
 * allocated that b does not own) when they are inconsistent: a partition id out of range, a
 * partition without vertices, more functions than vertices or none, a total that does not
 * match `functions`. */
bool prt__spectral_basis_index(prt__spectral_basis *b, size_t vertex_count);

/* Partitions m with METIS into pieces of about partition_size vertices and gives each the
 * lowest-frequency eigenvectors of its Laplacian, about `functions` in all (basis.c). */
prt_status prt__spectral_basis_build(prt_context *ctx, const prt__mesh *m, int partition_size, int functions, prt__progress *p,
                                     prt__spectral_basis *out);
/* The untruncated basis: vertex v alone is partition v with the one function 1 (it spans what all
 * eigenvectors span); at most PRT__SPECTRAL_MAX_FUNCTIONS vertices. */
prt_status prt__spectral_basis_full(prt_context *ctx, size_t vertex_count, prt__spectral_basis *out);
/* Coefficients of a per-vertex RGB signal (3 floats per vertex) on the basis: 3 per function. */
void prt__spectral_project(const prt__spectral_basis *b, const float *signal, float *coeffs, int threads);
/* The signal back from its coefficients (3 floats per vertex). */
void prt__spectral_reconstruct(const prt__spectral_basis *b, size_t vertex_count, const float *coeffs, float *signal, int threads);

/* The bake (bake.c) as stages of work units. */
typedef struct prt__spectral_bake_desc {
    int partition_size, functions, samples, env_order;
    bool full;   /* every vertex its own function: no truncation */
    float drop_below;   /* entries below this times their row's largest are dropped too (the option's default: PRT__SPECTRAL_DROP_DEFAULT) */
    float ray_offset;
    bool keep_rows;     /* also keep the unquantized rows in the state (raw_*) */
    const prt_scene *scene;   /* its BRDF sets are kept (NULL: none) */
} prt__spectral_bake_desc;
/* The default relative drop threshold: the largest that keeps the storage's error under 1% in L2
 * and 5% at the 99th-percentile vertex on the README's scenes (bench/bench_spectral_storage.c;
 * README, "Spectral storage"). */
#define PRT__SPECTRAL_DROP_DEFAULT 1e-3f

/* Quantizes a row of n values to 16 bits against its largest magnitude m: keeps the entries with
 * |x| >= drop * m whose quantized value is not zero, writing their positions in x to keep and
 * their values to q; returns how many. *scale = m / 32767 (0 for a row of zeros). */
/* Transfer rows streamed through an unlinked scratch file (spill.c): a bake whose estimate is
 * over its memory limit keeps each block's unquantized rows there instead of in memory. */
typedef struct prt__spectral_spill {
    FILE *file;
    uint64_t end;            /* where the next record goes (taken atomically) */
} prt__spectral_spill;
prt_status prt__spectral_spill_open(prt_context *ctx, prt__spectral_spill *s);
void prt__spectral_spill_close(prt__spectral_spill *s);
/* Writes the n parts one after another as one record, from any thread; *at: where it starts.
 * False on a write error. */
bool prt__spectral_spill_put(prt__spectral_spill *s, const void *const *parts, const size_t *bytes, int n, uint64_t *at);
/* Reads `bytes` at `at`; false on a read error. */
bool prt__spectral_spill_get(const prt__spectral_spill *s, uint64_t at, void *data, size_t bytes);

uint32_t prt__spectral_quantize_row(const float *x, uint32_t n, float drop, uint32_t *keep, int16_t *q, float *scale);
prt_status prt__spectral_bake_begin(prt_context *ctx, const prt__spectral_bake_desc *d, prt_transfer *t, prt__bake_job **job);
/* The spectral bake's memory (transfer/method.h's prt__memory_estimate) for d's settings (zeros:
 * the defaults) on t's scene, with `threads` gathering: the rows, dense in a closed scene (every
 * basis function reached), held as floats and then quantized, the environment transfer and each
 * thread's weights over every vertex; streaming (least), the quantized rows only, the floats in
 * a scratch file. */
void prt__spectral_memory(const prt_transfer *t, const prt__spectral_bake_desc *d, int threads, prt__memory_estimate *e);

/* Numbers the glossy vertices of t (a material whose BRDF has a glossy part, or a surface with a
 * glossy candidate in s->set) into s->glossy_of; false when out of memory. */
bool prt__spectral_glossy_index(const prt_transfer *t, prt__spectral_set *s);
/* Exit radiance SH (3 x 16 per vertex, world frame; zero where not glossy) of the glossy final
 * bounce from the outgoing radiance `out` (3 per vertex) of every surface, plus the environment's
 * direct light (env in SH of env_order, NULL or order 0: none) where the file has genv. brdf_of:
 * as prt_relight_desc.brdf_of (NULL = the baked materials). */
prt_status prt__spectral_glossy(prt_context *ctx, const prt_transfer *t, const float *out, const prt_sh_light *env, const int *brdf_of,
                                float *exit_sh);
/* The SH matrix vertex v reflects with (NULL: diffuse), given brdf_of as above. */
const float *prt__spectral_matrix_of(const prt_transfer *t, const int *brdf_of, size_t v);
/* The lighting's environment in SH of the transfer's env_order, rotated and scaled; order 0 when
 * there is none. */
prt_status prt__spectral_env_sh(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, prt_sh_light *sh);

/* Run time (relight.c). Per-vertex irradiance from the lighting's direct light; when
 * pixel is not NULL it also gets the part from the lighting's first pixel_count local lights. */
prt_status prt__spectral_direct(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, float *irradiance, float *pixel, int pixel_count);
/* Per light and vertex ([light][vertex]): whether the vertex sees the light, 0..1. */
prt_status prt__spectral_visibility(prt_context *ctx, const prt_transfer *t, const prt_light *lights, int count, float *vis);
/* N bounces from outgoing radiance `direct_out` (3 per vertex) with per-vertex albedo: fills
 * indirect_out (3 per vertex) with the radiance that bounced at least once. With `tail`, the
 * bounces past the N-th are added as a geometric series from the ratio of the last two bounces'
 * power (relight.c); N = 0 stays direct light only. */
#define PRT__SPECTRAL_TAIL_MAX_RATIO 0.95
prt_status prt__spectral_bounces(prt_context *ctx, const prt_transfer *t, const float *albedo, const float *direct_out, int bounces, int tail,
                                 float *indirect_out);

/* Its chunks (file.c). */
prt_status prt__spectral_save(const prt_transfer *t, prt__chunk_list *out);
prt_status prt__spectral_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count);

#endif
