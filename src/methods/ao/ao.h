/* The ambient-occlusion method's state (the files of this folder look inside; nothing else
 * does): one number per vertex, its accessibility
 *   A = 1/pi * integral over the hemisphere of V(w) max(n.w, 0) dw,
 * the share of cosine-weighted directions that escape the scene (1 for an unoccluded vertex).
 * Relit, a vertex reflects albedo / pi * A * E(n): the environment's unshadowed irradiance at its
 * normal (SH order 3) darkened by how much of the sky it sees. */
#ifndef PRT_METHODS_AO_H
#define PRT_METHODS_AO_H

#include "transfer/method.h"

#define PRT__AO_MIN_SAMPLES 16
#define PRT__AO_MAX_SAMPLES (1 << 20)
#define PRT__AO_ENV_ORDER 3   /* irradiance needs no more (Ramamoorthi & Hanrahan 2001) */

typedef struct prt__ao_set {
    int samples;         /* cosine-weighted rays per vertex */
    uint32_t seed;       /* scrambles the low-discrepancy directions */
    float ray_offset;    /* the origin offset the bake used */
    uint32_t buried;     /* vertices with no free origin: given their neighbours' mean */
    float *access;       /* [vertex] A in [0, 1] */
    struct prt__gpu_sums *gpu;   /* the rows for the GPU (gpu.c), built on first use for this albedo: */
    float *gpu_albedo;
} prt__ao_set;

extern const prt__method prt__method_ao;

/* Relighting finished on the GPU (gpu.c): r's products and frame vector (albedo NULL: as baked). */
prt_status prt__ao_gpu(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float *albedo, prt_relit *r);

/* prt export --web (web.c, web.js). */
prt_status prt__ao_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page);

static inline prt__ao_set *prt__ao(const prt_transfer *t) { return prt__state_of(t, &prt__method_ao); }
void prt__ao_set_free(void *state);

/* The bake (bake.c) as stages of work units, for t holding the scene; samples 0 = 256. */
typedef struct prt__ao_bake_desc {
    int samples;
    uint32_t seed;
    float ray_offset;    /* 0 = prt__ray_offset of the mesh */
} prt__ao_bake_desc;
prt_status prt__ao_bake_begin(prt_context *ctx, const prt__ao_bake_desc *d, prt_transfer *t, prt__bake_job **job);

/* Its chunks (file.c). */
prt_status prt__ao_save(const prt_transfer *t, prt__chunk_list *out);
prt_status prt__ao_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count);

/* Exit radiance per vertex (relight.c): albedo / pi * A * E(n), E from the lighting's SH
 * projection at order 3; albedo NULL = as baked. */
/* The environment's irradiance over pi as order-3 SH (relight.c): E(n) / pi at any normal n. */
prt_status prt__ao_irradiance_sh(prt_context *ctx, const prt_lighting *l, prt_sh_light *sh);
prt_status prt__ao_radiance(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float *albedo, float *rgb);

#endif
