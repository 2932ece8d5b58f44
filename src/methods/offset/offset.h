/* The offset method's state (offset radiance transfer mapping, Sunshine-Hill & Faloutsos 2006):
 * the texel patches of a light map over the mesh's UVs, the chosen offsets and, per transfer kind,
 * one map per offset of TR(t, t + dt) TVA(t, dt) over the covered texels. Shared by the files
 * of this folder only. */
#ifndef PRT_METHODS_OFFSET_H
#define PRT_METHODS_OFFSET_H

#include "transfer/method.h"
#include "prt/offset.h"
#include "light/vertex_lights.h"
#include "methods/offset/bins.h"

#include <pthread.h>

#define PRT__OFFSET_RADIOSITY_BIT 1
#define PRT__OFFSET_SUBSURFACE_BIT 2
#define PRT__OFFSET_ENV_COEFFS 9    /* first-order light from the environment: SH order 3 */
#define PRT__OFFSET_TEXEL_FLOATS (3 + 3 + 3 + 1 + PRT__OFFSET_ENV_COEFFS)   /* a texel patch in files: pos, nrm, albedo, area, env */
#define PRT__OFFSET_SHADOW_SAMPLES 4 /* shadow-ray points per texel: a rotated grid */
#define PRT__OFFSET_MAX_MAP_BOUNCES 64 /* --map-bounces: the default, the whole series (paths end earlier by weight) */
#define PRT__OFFSET_MAX_ENTRIES ((uint64_t)1 << 28)   /* texels x offsets, each 3 floats: 3 GiB */

/* The bake's per-texel energy cap on one kind of map (maps_step): how many texels gathered more
 * than they can reflect (or scatter) and were scaled down, the largest and mean factor over
 * them (gathered / bound, 1 when none). */
typedef struct prt__offset_cap {
    uint32_t texels;
    float max, mean;
} prt__offset_cap;

typedef struct prt__offset_set {
    int width, height, count;     /* the light map; offsets */
    unsigned kinds;               /* PRT__OFFSET_*_BIT */
    int iterations, importance;   /* how offsets were chosen: refinements, 0 = max, 1 = mean */
    int map_bounces;              /* bounces the radiosity maps hold: 1 (the run time repeats the
                                   * pass per bounce) or 2..PRT__OFFSET_MAX_MAP_BOUNCES (one pass gives them all) */
    float ray_offset;
    float sigma_a[3], sigma_s[3], eta, mm_per_unit;   /* the medium of subsurface transfer */
    int *offsets;                 /* count x (dx, dy) texels */
    uint32_t covered;             /* texels on the surface */
    uint32_t *texel;              /* [covered] y * width + x, increasing */
    float *pos, *nrm, *albedo;    /* [covered][3] */
    float *area;                  /* [covered] world area */
    float *emit;                  /* [covered][3] emitted radiance; NULL when nothing emits */
    float *emit_in;               /* [covered][3] irradiance from the emissive surfaces (scale 1),
                                   * shadowed; with emit */
    float *env;                   /* [covered][9] shadowed SH transfer (cosine / pi folded in) */
    float *radiosity, *subsurface;   /* [count][covered][3] or NULL */
    bool mapped[2];               /* radiosity, subsurface: in a mapped scratch file (maps.c), not malloc'd */
    /* Subsurface: the media (up to 255) and each covered texel's (0 = opaque: diffuse). */
    int medium_count;
    prt_medium *media;
    uint8_t *medium;
    /* The cap per kind (radiosity, subsurface), as the bake recorded it (files before it: unknown). */
    bool cap_known;
    prt__offset_cap cap[2];
    int32_t *index;               /* [width * height] covered index, -1 off the surface (derived) */
    int32_t *xy;                  /* [2][covered] texel columns, then rows (derived) */
    int32_t *source;              /* [width * height] the covered texel each texel reads: itself, or
                                   * its gutter's source (prt__texel_gutter_sources; derived) */
    /* Run-time: shadow rays for local lights, built on first use, from PRT__OFFSET_SHADOW_SAMPLES
     * points per texel on its own triangle (sample_pos, sample_nrm). */
    pthread_mutex_t *lock;
    prt__vertex_lights *lights;
    /* Run-time: shadow rays from the mesh's vertices, for the lights drawn per pixel (their
     * visibility per vertex, and their direct light where a result is shaded per vertex). */
    prt__vertex_lights *vertex_lights;
    float *sample_pos, *sample_nrm;
    /* Run-time: what the bounce maps read their light through (prefilter.c), built on first use
     * under lock: each covered texel's UV chart, and each offset's level of the light's pyramid
     * (levels = the pyramid's levels above the texels; 0: every offset reads single texels). */
    int32_t *chart;
    uint8_t *level;
    int levels;
    bool filter_ready;
    /* Run-time: pyramids (prt__offset_filter_scratch floats each) that radiosity relights have
     * finished with, under lock: relights run side by side, each taking one of its own, and the
     * next ones reuse them instead of allocating levels x covered x 12 bytes each time. */
    float **pyramids;
    int pyramid_count, pyramid_cap;
    /* Run-time: the passes the renderer runs (gpu.c), built on first use under lock and published
     * atomically; its slices are owned here. */
    prt_render_passes *passes;
    prt_render_slice *slices[2];
} prt__offset_set;

extern const prt__method prt__method_offset;

/* prt export --web (web.c, web.js). */
prt_status prt__offset_web(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt__web *page);
/* Builds the texels' shadow-ray points (sample_pos, sample_nrm) and their ray caster, once. */
prt_status prt__offset_shadow_samples(prt_context *ctx, const prt_transfer *t);

void prt__offset_set_free(void *state);
/* The run-time cache (lock and shadow-ray state) of a new state; false when out of memory. */
bool prt__offset_cache_new(prt__offset_set *s);
/* Builds the covered-texel index (after load or bake) and the gutter sources, each chart's reads
 * from its own texels (label: prt__texel_support_charts of the mesh, NULL: by distance alone);
 * false when out of memory or the texel list is not increasing and inside the map. */
bool prt__offset_set_index(prt__offset_set *s, const int32_t *label);

/* The maps' storage (maps.c): values floats, malloc'd or (mapped: a bake over its memory limit) in
 * a shared mapping of an unlinked scratch file; drop hands a mapped state's map pages back to the
 * kernel (their bytes stay: the next touch reads them back), a no-op for malloc'd maps. */
prt_status prt__offset_maps_new(prt_context *ctx, size_t values, bool mapped, float **out);
void prt__offset_maps_free(float *maps, size_t values, bool mapped);
void prt__offset_maps_drop(const prt__offset_set *s);
/* Texels per block between drops: about 12 bytes x offsets each, per kind of map written. */
#define PRT__OFFSET_MAP_BLOCK 1024
/* Bounce units (64 texels, touching 1-2 pages per offset each) between drops. */
#define PRT__OFFSET_BOUNCE_DROP 8

#define PRT__OFFSET_MAX_MEDIA 255

typedef struct prt__offset_bake_desc {
    int texels, count, iterations, importance, seed;
    bool texels_default;          /* texels was not asked for: a generated atlas may take a larger map */
    int map_bounces, walks;       /* radiosity maps holding map_bounces bounces (1: one, bounced at
                                   * run time); paths per texel for those past the first */
    unsigned kinds;
    prt_uv_layout uv_layout;
    float sigma_a[3], sigma_s[3], eta, mm_per_unit, ray_offset;
    /* Translucent surfaces by surface id of the transfer's mesh (surface_count + 1 entries, 0 =
     * opaque, else media[k - 1]); NULL: with subsurface transfer, every surface is of the
     * medium sigma_a, sigma_s, eta. */
    const uint8_t *surface_medium;
    int medium_count;
    const prt_medium *media;
} prt__offset_bake_desc;

prt_status prt__offset_bake_begin(prt_context *ctx, const prt__offset_bake_desc *d, prt_transfer *t, prt__bake_job **out);
/* The light map's size for a scene when none was asked for: from least, doubled (up to 512, and
 * within the map entries count offsets allow) until m's surface, over uv_share of the map, has
 * texels at most a 64th of its diagonal wide; texel, diagonal, area: what it found. */
int prt__offset_scene_texels(const prt__mesh *m, double uv_share, int least, int count, double *texel, double *diagonal, double *area);

/* Run time: the light map after `bounces` (texels, width x height x 3, gutters filled) and its
 * first-order part; per vertex radiance and indirect light sampled from them. */
prt_status prt__offset_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r);
/* prt_relit_shade's part: the lights drawn per pixel, per vertex with shadow rays. */
prt_status prt__offset_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb);

/* Prefiltered light for the bounce maps (prefilter.c). A far offset's cell stands for a wide patch
 * of surface around its representative texel, but a map reads one texel's light: a shadow edge
 * under a sparse far offset then shows as bands. The bounce passes read instead the light of an
 * area-weighted pyramid at the offset's level (blocks up to half its cell's side), bilinear over
 * the four blocks around the texel read, a block straddling a chart's border standing in by the
 * level below. */
prt_status prt__offset_filter_ready(prt_context *ctx, const prt_transfer *t, prt__offset_set *s);
/* The light each covered texel stands for at levels 0..s->levels: out[l] ([covered][3]; out[0] =
 * in) as the comment above says, level by level from out[l - 1]. scratch:
 * prt__offset_filter_scratch floats. */
size_t prt__offset_filter_scratch(const prt__offset_set *s);
/* A pyramid's scratch for a relight (one the set keeps, or a new one; NULL when out of memory),
 * given back when the relight ends; the set frees them with itself. After
 * prt__offset_filter_ready. */
float *prt__offset_filter_take(prt__offset_set *s);
void prt__offset_filter_give(prt__offset_set *s, float *scratch);
void prt__offset_filter(const prt__offset_set *s, const float *in, float *scratch, const float **out);

/* The bounced light shown (smooth.c): each receiver's gathered light averaged with its chart's
 * texels within prt__offset_smooth_radius texels (a tent, weighted by texel area), when the maps
 * read prefiltered light (s->levels > 0; after prt__offset_filter_ready). A far cell's light is
 * read at one representative, and which surface the representatives land on changes from one
 * receiver to the next: a receiver with one on a small hot spot (the Cornell box's lamp panel,
 * 10-100 times its surroundings) gathers it over the whole cell, its neighbour without one
 * gathers none. Right on average (the cells reach around small charts for that, bake.c), each
 * receiver's gather is one draw of that lottery, and shows as blotches of a few texels;
 * averaging the neighbours' draws keeps the mean (about: it is normalised per receiver, so
 * not exactly at chart borders or where texel areas vary; 0.3-1% in the tests) and takes out much of the spread (issue 30). It
 * also softens the bounced light's own detail over that radius. in, out: [covered][3], not the
 * same. */
void prt__offset_smooth(prt_context *ctx, const prt__offset_set *s, const float *in, float *out);
/* A neighbour's weight by the cosine between the two texels' normals: cos^32 (0 from 90
 * degrees): on a curved chart - a torus's side and its underside - texels facing other ways
 * gather other light (the demo scene's torus: the smoothing's worst block 1-3 points less off).
 * By squaring, as the GPU's and the page's (render/light_map_gl.c, web.js). */
static inline float prt__offset_smooth_facing(float cosine)
{
    float f = cosine > 0 ? cosine : 0;
    for (int k = 0; k < 5; ++k) f *= f;
    return f;
}
/* The radius: a texel per 64 of the map's smaller side, at most PRT__OFFSET_SMOOTH_MAX. The
 * blotches are a share of an offset's cell, and with a given number of offsets the cells cover
 * the same share of any map; the cap bounds the cost at (2 x 4 + 1)^2 reads per texel (at
 * 1024^2 uncapped it was 5 s a relight), so maps above 256^2 are smoothed over less of their
 * cells. R = 4 at 64^2 maps failed the tests' bounds: too wide on a small map. */
#define PRT__OFFSET_SMOOTH_MAX 4
int prt__offset_smooth_radius(const prt__offset_set *s);

/* The GPU passes for t (gpu.c): the maps cropped to the boxes of their axial slicing and sliced into atlases
 * (bins.c, section 5.2), described for the renderer; built once, then borrowed from t. */
prt_status prt__offset_gpu_passes(prt_context *ctx, const prt_transfer *t, const prt_render_passes **out);

/* A kind's maps ([count][covered][3]) cropped to the boxes of their axial slicing (bins.c), for
 * the GPU's atlases and prt info (gpu.c): count boxes, box[b] of map map[b], in map order. */
typedef struct prt__offset_crops {
    prt__map_box *box;
    int *map;
    int count;
    int64_t data, area, whole;   /* non-zero texels; texels of the boxes; of one box per map */
} prt__offset_crops;
prt_status prt__offset_crop_maps(prt_context *ctx, const prt__offset_set *s, const float *maps, prt__offset_crops *out);
void prt__offset_crops_free(prt__offset_crops *c);

/* prt export (export.c): --maps DIR. */
prt_status prt__offset_export(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt_export_result *out);

/* Its chunks (file.c). */
prt_status prt__offset_save(const prt_transfer *t, prt__chunk_list *out);
prt_status prt__offset_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count);

#endif
