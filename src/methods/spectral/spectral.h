/* The spectral method's state (Wang, Zhu & Humphreys 2007: direct-to-indirect transfer in a
 * spectral mesh basis): the files of this folder look inside, and - a declared dependency,
 * docs/ARCHITECTURE.md - the light cloud's bake, which runs the spectral stages and run time.
 *
 * The mesh is cut into partitions; partition p carries count[p] basis functions, the lowest
 * frequencies of its own topological Laplacian, numbered first[p] .. first[p + 1] - 1. Vertex v
 * stores the values of its partition's functions at v. The transfer row of vertex v holds, for
 * basis function l, the irradiance at v when the surfaces emit radiance s_l (eq. 7), quantized to
 * 16 bits against one scale for the whole matrix; entries that round to zero are not stored. */
#ifndef PRT_METHODS_SPECTRAL_H
#define PRT_METHODS_SPECTRAL_H

#include "geom/raycast.h"
#include "light/light_sample.h"
#include "transfer/method.h"
#include "prt/spectral.h"
#include "light/vertex_lights.h"

#include <pthread.h>

#define PRT__SPECTRAL_MAX_FUNCTIONS 65535   /* indices are stored in 16 bits */
#define PRT__SPECTRAL_GLOSSY_ORDER 4        /* the glossy final bounce's SH: 16 BRDF bases, as the paper */
#define PRT__SPECTRAL_GLOSSY_N 16
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
} prt__spectral_cache;

typedef struct prt__spectral_set {
    prt__spectral_basis basis;
    int samples;             /* gathering rays per vertex at bake time */
    int partition_size;      /* what the bake asked for */
    float ray_offset;
    /* Sparse transfer rows: vertex v's entries are [row_start[v], row_start[v + 1]). */
    uint64_t *row_start;     /* [vertex + 1] */
    uint16_t *index;         /* basis function */
    int16_t *value;          /* times scale */
    float scale;
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
    int16_t *gvalue;
    float gscale;
    /* Per material (k - 1) with a glossy part: its local-frame SH matrix (3 x 16 x 16, the
     * glossy part only; prt_brdf_sh_matrix), computed at bake time and kept in the file. */
    float *brdf_matrix[PRT__MAX_BRDFS];
    prt__spectral_cache *cache;
} prt__spectral_set;

extern const prt__method prt__method_spectral;

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
    float drop_below;   /* entries below this times the largest are dropped too */
    float ray_offset;
} prt__spectral_bake_desc;
prt_status prt__spectral_bake_begin(prt_context *ctx, const prt__spectral_bake_desc *d, prt_transfer *t, prt__bake_job **job);

/* Numbers the glossy vertices of t (a material whose BRDF has a glossy part) into s->glossy_of;
 * false when out of memory. */
bool prt__spectral_glossy_index(const prt_transfer *t, prt__spectral_set *s);
/* Exit radiance SH (3 x 16 per vertex, world frame; zero where not glossy) of the glossy final
 * bounce from the outgoing radiance `out` (3 per vertex) of every surface. */
prt_status prt__spectral_glossy(prt_context *ctx, const prt_transfer *t, const float *out, float *exit_sh);

/* Run time (relight.c). Per-vertex irradiance from the lighting's direct light; when
 * pixel is not NULL it also gets the part from the lighting's first pixel_count local lights. */
prt_status prt__spectral_direct(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, float *irradiance, float *pixel, int pixel_count);
/* Per light and vertex ([light][vertex]): whether the vertex sees the light, 0..1. */
prt_status prt__spectral_visibility(prt_context *ctx, const prt_transfer *t, const prt_light *lights, int count, float *vis);
/* Per-vertex irradiance from count local lights, shadowed (adds to irradiance). */
prt_status prt__spectral_lights(prt_context *ctx, const prt_transfer *t, const prt_light *lights, int count, float *irradiance);
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
