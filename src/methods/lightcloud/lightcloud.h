/* The light-cloud method's state (Kristensen, Akenine-Moller & Jensen 2005: precomputed local
 * radiance transfer): the files of this folder look inside, and the spectral method's files do
 * not (the light cloud depends on the spectral method, not the other way round).
 *
 * A cloud of unit point lights (1 W/sr, white) was placed over a region; for each, the exit
 * radiance of every vertex was computed (the indirect part, or all of it with store_direct).
 * The mesh is cut into zones (boxes split along their longest axis); within a zone the lights
 * are clustered (each cloud light belongs to one merged light of the zone) and the zone's
 * per-vertex response vectors - per channel c and merged light l, [c][l] for the diffuse exit
 * radiance and [c][k][l] for the 16 SH coefficients k of a glossy vertex's glossy part - are
 * compressed with clustered PCA (or kept raw). With emission lobes (lobes.c: --emission-order 2
 * or 3) each cloud light was solved once per lobe of its emission, and every merged light has
 * `lobes` columns, [c][l * lobes + k]. */
#ifndef PRT_METHODS_LIGHTCLOUD_H
#define PRT_METHODS_LIGHTCLOUD_H

#include "compress/cpca.h"
#include "geom/kdtree.h"
#include "transfer/method.h"
#include "light/vertex_lights.h"

/* Cloud lights at most: nothing in the bake or the file holds every pair of them any more (pairs.c,
 * cluster.c); the limit keeps a zone's columns (48 SH values x 9 lobes x merged lights) within 32
 * bits with room, and is far beyond what a machine solves (each light is one spectral solve, and
 * each zone's thread holds every light's response in the zone: bake.c says how much up front). */
#define PRT__LIGHTCLOUD_MAX_LIGHTS (1u << 20)
#define PRT__LIGHTCLOUD_GLOSSY_N 16      /* SH order 4 exit radiance for glossy vertices, as the paper's n_b = 16 */
#define PRT__LIGHTCLOUD_EMISSION_ORDER 1 /* default --emission-order (lobes.c) */

/* One zone's responses in one form: raw [vertex][dim] or CPCA over the zone's vertices. */
typedef struct prt__lightcloud_block {
    uint32_t vertices, dim;
    float *raw;                  /* NULL when compressed */
    prt__cpca *cpca;
} prt__lightcloud_block;

typedef struct prt__lightcloud_zone {
    uint32_t lights;             /* merged lights */
    uint32_t *light_of;          /* [cloud light] the merged light it belongs to */
    float *positions;            /* [light][3] the merged lights' mean positions */
    prt__lightcloud_block diffuse;   /* over the zone's vertices in member order; dim 3 x lights */
    prt__lightcloud_block glossy;    /* over its glossy vertices in member order; dim 3 x 16 x lights */
} prt__lightcloud_zone;

typedef struct prt__lightcloud_cache {
    prt__vertex_lights lights;
    prt__kdtree tree;
    bool tree_ready;
    pthread_mutex_t lock;
    int warned;                  /* a light outside the cloud or seeing none of it was reported (atomic) */
    struct prt__gpu_sums *gpu;   /* the diffuse responses' description for the GPU (gpu.c), under lock */
} prt__lightcloud_cache;

typedef struct prt__lightcloud_set {
    uint32_t cloud_count;
    float *cloud;                /* [light][3] */
    float spacing;               /* median distance from a cloud light to its nearest neighbour (one light: half the region's largest side) */
    float region[6];             /* min xyz, max xyz: where the cloud covers (the grid's box, the lights' bounds grown by half a spacing) */
    bool store_direct;           /* responses hold direct light too; else the run time adds it */
    int lobes;                   /* emission lobes per cloud light (lobes.c): 1, 4 or 9 (emission order squared) */
    int bounces, samples;
    float ray_offset;
    float merge_distance, merge_error;   /* as baked (informational) */
    uint32_t merge_response;     /* how merged lights' responses were formed (PRT__LIGHTCLOUD_MERGE_*; 0: before the choice existed, the mean) */
    uint32_t zone_count;
    uint32_t *zone_of;           /* [vertex] */
    uint32_t *glossy_of;         /* [vertex] glossy index or UINT32_MAX (derived from materials) */
    uint32_t glossy_count;
    uint32_t *members;           /* derived: vertices grouped by zone, ascending within each */
    uint32_t *member_start;      /* [zone + 1] */
    uint32_t *glossy_start;      /* [zone + 1] glossy members before each zone */
    prt__lightcloud_zone *zones;
    /* The scene's emissive surfaces at emission scale 1: the light they cause, per vertex (direct,
     * then indirect), and its glossy part; NULL when nothing emits. */
    float *emit;                 /* [vertex][3] direct, then [vertex][3] indirect */
    float *emit_sh;              /* [glossy vertex][3][16] */
    prt__lightcloud_cache *cache;
} prt__lightcloud_set;

extern const prt__method prt__method_lightcloud;

/* prt export --web (web.c, web.js). */
prt_status prt__lightcloud_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page);

static inline prt__lightcloud_set *prt__lightcloud(const prt_transfer *t) { return prt__state_of(t, &prt__method_lightcloud); }
void prt__lightcloud_set_free(void *state);
prt__lightcloud_cache *prt__lightcloud_cache_new(void);
/* The responses left to the GPU (gpu.c): r's products (the diffuse light, and the glossy vertices'
 * exit vectors with their emitted part) and the frame's vector from the cloud weights w
 * (prt__lightcloud_weights) and the lighting's emission. */
prt_status prt__lightcloud_gpu(prt_context *ctx, const prt_transfer *t, const float *w, float emission, prt_relit *r);
/* Numbers the glossy vertices (material with a glossy part) into s->glossy_of; derives members,
 * member_start and glossy_start from zone_of. False when out of memory or zone_of is out of range
 * or leaves a zone empty. */
bool prt__lightcloud_index(const prt_transfer *t, prt__lightcloud_set *s);
/* Median nearest-neighbour distance of the cloud (0 for a single light). */
float prt__lightcloud_spacing(const float *cloud, uint32_t count);
void prt__lightcloud_block_free(prt__lightcloud_block *b);

/* Bake (bake.c). */
/* A merged light's response at each vertex: the mean of its members' (1), their harmonic mean
 * (2, the paper's section 4.1 wording), or a solution computed at its position (3, the paper's
 * "higher quality" alternative). */
enum { PRT__LIGHTCLOUD_MERGE_MEAN = 1, PRT__LIGHTCLOUD_MERGE_HARMONIC = 2, PRT__LIGHTCLOUD_MERGE_SOLVE = 3 };
typedef struct prt__lightcloud_bake_desc {
    int grid[3];                 /* cloud grid cells; 0 = 6 x 6 x 6 */
    bool has_box;
    float box[6];                /* min xyz, max xyz; default the scene's bounds */
    const char *list_path;       /* JSON list of positions instead of (or besides) the grid */
    int surface_lights;          /* extra lights just off the surfaces */
    int zone_vertices;           /* 0 = 2000 */
    float merge_distance;        /* < 0: default (3 x spacing); 0: no merging */
    float merge_error;           /* < 0: default 0.1; 0: the response term is left out */
    int merge_response;          /* PRT__LIGHTCLOUD_MERGE_*; 0 = the default */
    const char *responses_path;  /* kept cloud-light solutions to take and to write (responses.h); NULL: none */
    bool store_direct;
    int bounces;                 /* 0 = 16 (closed rooms need many) */
    bool raw;                    /* no CPCA */
    int clusters, vectors;       /* per zone; 0 = 8, 8 */
    int emission_order;          /* 0 = PRT__LIGHTCLOUD_EMISSION_ORDER; 1..3 */
    /* The memory estimate's parts (method.c): what the bake holds besides the lights and zones in
     * flight, and one light's solve with one zone's clustering; under a memory limit
     * (prt__bake_job.memory_over) fewer are in flight than threads. 0: not known, no bound. */
    uint64_t memory_fixed, memory_per_flight;
} prt__lightcloud_bake_desc;
prt_status prt__lightcloud_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, const prt__lightcloud_bake_desc *d,
                                      prt_transfer *t, prt__bake_job **job);

/* Candidate pairs (pairs.c): for each light j, the lights k > j closer than the merge distance
 * (the only ones eq. 9 can put below 1), ascending, found through a uniform grid. */
typedef struct prt__lightcloud_pairs {
    uint32_t n;                  /* lights */
    uint64_t count;              /* pairs */
    uint64_t *start;             /* [light + 1]: light j's pairs are other[start[j] .. start[j + 1]) */
    uint32_t *other;             /* [pair] */
    uint8_t *visible;            /* [pair] V_jk of eq. 9 (1 = the segment is clear); the bake's to fill */
} prt__lightcloud_pairs;
/* Pairs of the n lights at pos closer than r (none when r <= 0), on up to `threads` threads; the
 * result does not depend on them. */
prt_status prt__lightcloud_pairs_find(prt_context *ctx, const float *pos, uint32_t n, float r, int threads, prt__lightcloud_pairs *out);
void prt__lightcloud_pairs_free(prt__lightcloud_pairs *p);

/* Clustering (cluster.c): merges the lights bottom-up while every pair across two clusters has
 * metric(j, k) < 1, smallest first; only candidate pairs can be below 1 (the metric of any other
 * pair must be 1 or more). pair: the pair's index in `pairs`. cluster_of[i] numbers the clusters
 * in order of their first member. */
typedef float (*prt__light_metric_fn)(void *user, uint32_t j, uint32_t k, uint64_t pair);
prt_status prt__lightcloud_cluster(prt_context *ctx, const prt__lightcloud_pairs *pairs, prt__light_metric_fn metric, void *user, uint32_t *cluster_of,
                                   uint32_t *clusters);
/* Merged responses (how: PRT__LIGHTCLOUD_MERGE_MEAN or _HARMONIC): src [cloud light][width],
 * dst [width][merged light]; groups of `group` values (1, or 16 SH coefficients) merge together. */
prt_status prt__lightcloud_merge(prt_context *ctx, int how, uint32_t n, const uint32_t *light_of, uint32_t lights, const float *src, size_t width,
                                 int group, float *dst);

/* Run time (relight.c): weights over the cloud (3 per light and lobe: [light][lobe][colour]) for
 * the lights of l, by interpolation among the `neighbours` nearest cloud lights visible from
 * each light. */
prt_status prt__lightcloud_weights(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, int neighbours, float *w);
/* Exit radiance from cloud weights: rgb (3 per vertex, added to) and, for glossy vertices, the
 * glossy part's SH (3 x 16 per vertex, added to; may be NULL). */
prt_status prt__lightcloud_eval(prt_context *ctx, const prt_transfer *t, const float *w, float *rgb, float *exit_sh);

/* Emission lobes (lobes.c). Lobe k (< 9) of the emission direction w, >= 0. */
double prt__lightcloud_lobe(int k, const double w[3]);
/* The light a cloud light at pos is solved with for lobe k: the unit point light for k = 0, an
 * ies light with the lobe as its profile otherwise (release with prt_light_clear). */
prt_status prt__lightcloud_lobe_light(int k, const float pos[3], prt_light *out);
/* Coefficients c[k][channel] of light l's intensity (point, spot, ies) over the first `lobes`
 * lobes: I(w) ~ sum_k c_k f_k(w). */
void prt__lightcloud_project(const prt_light *l, int lobes, float c[][3]);

/* Its chunks (file.c). */
prt_status prt__lightcloud_save(const prt_transfer *t, prt__chunk_list *out);
prt_status prt__lightcloud_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count);

#endif
