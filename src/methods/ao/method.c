/* The ambient-occlusion method's table entry: one cosine-weighted visibility per vertex, relit as
 * the environment's unshadowed irradiance (SH order 3) times that visibility. Bake options, its
 * chunks in file.c (AOCP, AOCA), description and relighting; the bake lives in bake.c, the kernel
 * in relight.c. */
#include "methods/ao/ao.h"
#include "transfer/gpu_sums.h"

void prt__ao_set_free(void *state)
{
    prt__ao_set *s = state;
    if (!s) return;
    free(s->access);
    prt__gpu_sums_free(s->gpu);
    free(s->gpu_albedo);
    free(s);
}

/* ---- bake options ---- */
/* Help texts are reflowed by the printer (prt bake --help): line breaks here are for the source. */
static const prt_option_desc options[] = {
    {"samples", "N", PRT_OPTION_INT, PRT__AO_MIN_SAMPLES, PRT__AO_MAX_SAMPLES, NULL,
     "cosine-weighted visibility rays per vertex (default 256; the noise in A is about "
     "0.5 / sqrt(N) at most)"},
    {"seed", "N", PRT_OPTION_INT, 0, 2147483647, NULL, "scrambles the low-discrepancy directions (default 0)"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "ray origin offset (default 1e-4 x scene diagonal)"},
};

/* One float a vertex. */
static void ao_memory_estimate(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *e)
{
    (void)o;
    (void)threads;
    e->bytes = e->least = (uint64_t)t->mesh.vertex_count * sizeof(float);
    snprintf(e->what, sizeof e->what, "one float a vertex");
    snprintf(e->lower, sizeof e->lower, "a mesh of fewer vertices");
}

static prt_status ao_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    (void)scene;
    prt__ao_bake_desc d = {0};
    d.samples = prt__opt_int(o, "samples", 0);
    d.seed = (uint32_t)prt__opt_int(o, "seed", 0);
    d.ray_offset = prt__opt_float(o, "ray-offset", 0.0f);
    return prt__ao_bake_begin(ctx, &d, t, job);
}

/* ---- description ---- */
static size_t ao_bytes(const prt_transfer *t) { return t->mesh.vertex_count * sizeof(float); }

static void ao_describe(const prt_transfer *t, prt__describe *d)
{
    const prt__ao_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    double sum = 0.0;
    float lo = 1.0f;
    size_t open = 0;
    for (size_t v = 0; v < nv; ++v) {
        sum += s->access[v];
        lo = fminf(lo, s->access[v]);
        open += s->access[v] == 1.0f;
    }
    const double mean = nv ? sum / (double)nv : 0.0;
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "samples", s->samples);
        cJSON_AddNumberToObject(j, "seed", s->seed);
        cJSON_AddNumberToObject(j, "ray_offset", s->ray_offset);
        cJSON_AddNumberToObject(j, "env_order", PRT__AO_ENV_ORDER);
        cJSON_AddNumberToObject(j, "accessibility_mean", mean);
        cJSON_AddNumberToObject(j, "accessibility_min", nv ? lo : 0.0);
        cJSON_AddNumberToObject(j, "unoccluded_vertices", (double)open);
        cJSON_AddNumberToObject(j, "buried_vertices", s->buried);
        return;
    }
    prt__describe_line(d, "occlusion:", "1 float per vertex, %d cosine-weighted rays each (seed %u)", s->samples, s->seed);
    prt__describe_line(d, "visibility:", "mean %.3f, least %.3f, %zu of %zu vertices unoccluded", mean, nv ? lo : 0.0f, open, nv);
    if (s->buried) prt__describe_line(d, "buried:", "%u vertices with no free ray origin took their neighbours' mean", s->buried);
    prt__describe_line(d, "relighting:", "environment through SH order %d, unshadowed irradiance x visibility, diffuse (albedo live)",
                       PRT__AO_ENV_ORDER);
}

/* ---- relighting ---- */
static prt_status ao_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    if (d->brdf) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf does not apply to ambient occlusion (it reflects diffusely; see --albedo-of)");
    if (d->component == PRT_COMPONENT_INDIRECT)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "ambient occlusion holds direct light only: it has no indirect component");
    prt_status st = prt__relit_alloc(ctx, t, r, false);
    if (st) return st;
    if (d->gpu_finish) return prt__ao_gpu(ctx, t, l, d->albedo, r);   /* summed on the GPU (gpu.c) */
    return prt__ao_radiance(ctx, t, l, d->albedo, r->radiance);
}

const prt__method prt__method_ao = {
    .name = "ao",
    .title = "ambient occlusion",
    .summary = "ambient occlusion: one cosine-weighted visibility per vertex times the environment's irradiance, albedo live",
    .web = prt__ao_web,
    .lighting = PRT_LIGHTS_ENVIRONMENT,
    .runtime_albedo = true,
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .bake_begin = ao_bake_begin,
    .memory_estimate = ao_memory_estimate,
    .free_state = prt__ao_set_free,
    .save = prt__ao_save,
    .load = prt__ao_load,
    .describe = ao_describe,
    .transfer_bytes = ao_bytes,
    .gpu_passes = true,
    .relight = ao_relight,
};
