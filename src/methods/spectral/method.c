/* The spectral method's table entry (direct-to-indirect transfer in a spectral mesh basis, Wang,
 * Zhu & Humphreys 2007): bake options, its chunks in file.c (SPCP, SPCB, SPCR, SPCE, SPCM, SPCH,
 * SPGE, SPCS; SPCT and SPCG in older files), description, the bounce control and relighting with
 * run-time albedo and BRDFs switched among the baked sets (the paper's Fig. 7). The basis is built
 * in basis.c, the transfer in bake.c, the run time in relight.c. */
#include "methods/spectral/spectral.h"
#include "transfer/gpu_sums.h"
#include "brdf/sh_matrix.h"


prt__spectral_cache *prt__spectral_cache_new(void)
{
    prt__spectral_cache *c = prt__calloc(1, sizeof *c);
    if (c) {
        pthread_mutex_init(&c->lock, NULL);
        prt__vertex_lights_init(&c->lights);
    }
    return c;
}

void prt__spectral_set_free(void *state)
{
    prt__spectral_set *s = state;
    if (!s) return;
    prt__spectral_basis_free(&s->basis);
    free(s->row_start);
    free(s->index);
    free(s->value);
    free(s->row_scale);
    free(s->raw_start);
    free(s->raw_index);
    free(s->raw_value);
    free(s->raw_gstart);
    free(s->raw_gindex);
    free(s->raw_gvalue);
    free(s->env);
    free(s->genv);
    free(s->emit);
    free(s->glossy_of);
    free(s->grow_start);
    free(s->gindex);
    free(s->gvalue);
    free(s->grow_scale);
    for (int k = 0; k < PRT__MAX_BRDFS; ++k) free(s->brdf_matrix[k]);
    for (int i = 0; s->set_matrix && i < s->set_count; ++i) free(s->set_matrix[i]);
    free(s->set_matrix);
    free(s->set);
    if (s->cache) {
        prt__vertex_lights_free(&s->cache->lights);
        prt__frame_rot *fr = s->cache->frames;
        for (uint32_t g = 0; fr && g < s->glossy_count; ++g) prt__frame_rot_release(&fr[g]);
        free(fr);
        pthread_mutex_destroy(&s->cache->lock);
        prt__gpu_sums_free(s->cache->gpu);
        free(s->cache->gpu_albedo);
        free(s->cache);
    }
    free(s);
}

bool prt__spectral_glossy_index(const prt_transfer *t, prt__spectral_set *s)
{
    const size_t nv = t->mesh.vertex_count;
    free(s->glossy_of);
    s->glossy_count = 0;
    if (!(s->glossy_of = malloc(nv * sizeof(uint32_t)))) return false;
    /* Surfaces with a glossy candidate keep glossy rows whatever they wear. */
    bool *set_glossy = s->set_count ? prt__calloc((size_t)t->mesh.surface_count + 1, 1) : NULL;
    if (s->set_count && !set_glossy) return false;
    for (int i = 0; i < s->set_count; ++i)
        if (prt_brdf_is_glossy(&s->set[i].brdf) && s->set[i].surface <= t->mesh.surface_count) set_glossy[s->set[i].surface] = true;
    for (size_t v = 0; v < nv; ++v) {
        const uint8_t k = t->mesh.material[v];
        const bool glossy = (k && k <= t->brdf_count && prt_brdf_is_glossy(&t->brdfs[k - 1])) ||
                            (set_glossy && t->mesh.surface && set_glossy[t->mesh.surface[v]]);
        s->glossy_of[v] = glossy ? s->glossy_count++ : UINT32_MAX;
    }
    free(set_glossy);
    return true;
}

static int spectral_brdf_set(const prt_transfer *t, int surface, int i, prt_brdf *out)
{
    const prt__spectral_set *s = t->state;
    int n = 0;
    for (int e = 0; e < s->set_count; ++e)
        if (s->set[e].surface == surface && n++ == i && out) *out = s->set[e].brdf;
    return n;
}

const float *prt__spectral_matrix_of(const prt_transfer *t, const int *brdf_of, size_t v)
{
    const prt__spectral_set *s = t->state;
    const uint16_t k = t->mesh.surface ? t->mesh.surface[v] : 0;
    if (brdf_of && k && brdf_of[k] >= 0)
        for (int e = 0, n = 0; e < s->set_count; ++e)
            if (s->set[e].surface == k && n++ == brdf_of[k]) return s->set_matrix[e];
    const uint8_t m = t->mesh.material[v];
    return m ? s->brdf_matrix[m - 1] : NULL;
}

/* ---- bake options ---- */
/* Help texts are reflowed by the printer (prt bake --help): line breaks here are for the source. */
static const prt_option_desc options[] = {
    {"basis", "N", PRT_OPTION_INT, 1, PRT__SPECTRAL_MAX_FUNCTIONS, NULL,
     "spectral basis functions in all, spread over the partitions by vertex count (default 1024)"},
    {"full-basis", NULL, PRT_OPTION_FLAG, 0, 0, NULL,
     "no truncation: every vertex its own basis function (the same space as all eigenvectors; "
     "at most 65535 vertices): the reference for the basis error"},
    {"partition", "V", PRT_OPTION_INT, 16, PRT__SPECTRAL_MAX_PARTITION / 2, NULL,
     "vertices per METIS partition, 16..2048 (default 1000)"},
    {"samples", "N", PRT_OPTION_INT, 16, 1 << 20, NULL,
     "gathering rays per vertex (default 4096; the paper uses 128x128)"},
    {"drop-below", "E", PRT_OPTION_FLOAT, 0, 0.1, NULL,
     "drop transfer entries below E x the largest of their row (each row is stored in 16 bits "
     "against its own largest; default 1e-3; 0: only what rounds to zero). In the README's window "
     "room 1e-3 keeps 83% of the bytes for 0.05% more error against the path tracer, 3e-3 60% for "
     "0.4% more, 1e-2 a third for 2.5% more (README, \"Spectral storage\")"},
    {"env-order", "N", PRT_OPTION_INT, 1, PRT_SH_MAX_ORDER, NULL,
     "SH order of the environment's shadowed direct light, 1..10 (default 4)"},
    {"ray-offset", "E", PRT_OPTION_FLOAT, 1e-30, 1e30, NULL, "ray origin offset (default 1e-4 x scene diagonal)"},
};

static const prt_control_desc controls[] = {
    {"bounces", "light bounces through the basis (0 = direct light only)", '[', ']', 0},
    {"tail", "the bounces past the last estimated as a geometric series (1) or left out (0)", 'U', 'O', 0},
};

static void spectral_memory_estimate(const prt_transfer *t, const prt_options *o, int threads, prt__memory_estimate *e)
{
    prt__spectral_bake_desc d = {0};
    d.functions = prt__opt_int(o, "basis", 0);
    d.full = prt__opt_flag(o, "full-basis");
    d.partition_size = prt__opt_int(o, "partition", 0);
    d.samples = prt__opt_int(o, "samples", 0);
    d.env_order = prt__opt_int(o, "env-order", 0);
    prt__spectral_memory(t, &d, threads, e);
}

static prt_status spectral_bake_begin(prt_context *ctx, const prt_scene *scene, const prt_options *o, prt_transfer *t, prt__bake_job **job)
{
    prt__spectral_bake_desc d = {0};
    d.functions = prt__opt_int(o, "basis", 0);
    d.full = prt__opt_flag(o, "full-basis");
    if (d.full && prt__opt(o, "basis")) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--basis and --full-basis exclude each other");
    d.partition_size = prt__opt_int(o, "partition", 0);
    d.samples = prt__opt_int(o, "samples", 0);
    d.env_order = prt__opt_int(o, "env-order", 0);
    d.drop_below = prt__opt_float(o, "drop-below", PRT__SPECTRAL_DROP_DEFAULT);
    d.ray_offset = prt__opt_float(o, "ray-offset", 0.0f);
    /* The BRDF sets are for switching at this method's run time; a bake that runs these stages
     * for another method (the light cloud's) does not need them. */
    d.scene = !o || prt_options_method(o) == &prt__method_spectral ? scene : NULL;
    prt_status st = prt__spectral_bake_begin(ctx, &d, t, job);
    if (!st && !(((prt__spectral_set *)t->state)->cache = prt__spectral_cache_new())) {
        (*job)->release(*job);   /* the driver releases only jobs that began */
        *job = NULL;
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    }
    return st;
}

/* ---- description ---- */
static size_t spectral_bytes(const prt_transfer *t)
{
    const prt__spectral_set *s = t->state;
    const size_t nv = t->mesh.vertex_count, rows = (size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N;
    /* 2 + 2 bytes an entry, a count (and, unless one scale serves all, a scale) per row; the
     * environment's glossy transfer as halves */
    const size_t per_row = s->one_scale ? 4 : 8;
    const size_t genv = s->genv ? rows * (size_t)s->env_order * s->env_order * sizeof(uint16_t) : 0;
    return s->row_start[nv] * 4 + nv * per_row + (s->glossy_count ? s->grow_start[rows] * 4 + rows * per_row : 0) + genv;
}

static size_t basis_bytes(const prt_transfer *t)
{
    const prt__spectral_set *s = t->state;
    return s->basis.offset[t->mesh.vertex_count] * sizeof(float) + t->mesh.vertex_count * 4;
}

static void spectral_describe(const prt_transfer *t, prt__describe *d)
{
    const prt__spectral_set *s = t->state;
    const prt__spectral_basis *b = &s->basis;
    const size_t nv = t->mesh.vertex_count;
    uint32_t kmin = UINT32_MAX, kmax = 0, vmin = UINT32_MAX, vmax = 0;
    for (uint32_t p = 0; p < b->partitions; ++p) {
        const uint32_t k = b->count[p], n = b->member_start[p + 1] - b->member_start[p];
        if (k < kmin) kmin = k;
        if (k > kmax) kmax = k;
        if (n < vmin) vmin = n;
        if (n > vmax) vmax = n;
    }
    uint64_t nnz = s->row_start[nv], rmax = 0;
    for (size_t v = 0; v < nv; ++v)
        if (s->row_start[v + 1] - s->row_start[v] > rmax) rmax = s->row_start[v + 1] - s->row_start[v];
    const double per_vertex = nv ? (double)nnz / nv : 0.0;
    cJSON *j = prt__describe_json(d);
    if (j) {
        cJSON_AddNumberToObject(j, "partitions", b->partitions);
        cJSON_AddNumberToObject(j, "functions", b->functions);
        cJSON *per = cJSON_AddArrayToObject(j, "functions_per_partition");
        cJSON *sizes = cJSON_AddArrayToObject(j, "vertices_per_partition");
        for (uint32_t p = 0; p < b->partitions; ++p) {
            cJSON_AddItemToArray(per, cJSON_CreateNumber(b->count[p]));
            cJSON_AddItemToArray(sizes, cJSON_CreateNumber(b->member_start[p + 1] - b->member_start[p]));
        }
        cJSON_AddNumberToObject(j, "basis_bytes", (double)basis_bytes(t));
        cJSON_AddNumberToObject(j, "coefficients", (double)nnz);
        cJSON_AddNumberToObject(j, "coefficients_per_vertex", per_vertex);
        cJSON_AddNumberToObject(j, "coefficients_per_vertex_max", (double)rmax);
        cJSON_AddStringToObject(j, "scales", s->one_scale ? "one" : "row");
        cJSON_AddNumberToObject(j, "drop_below", s->drop);
        cJSON_AddNumberToObject(j, "samples", s->samples);
        cJSON_AddNumberToObject(j, "partition_size", s->partition_size);
        cJSON_AddNumberToObject(j, "env_order", s->env_order);
        cJSON_AddNumberToObject(j, "glossy_vertices", s->glossy_count);
        cJSON_AddNumberToObject(j, "glossy_coefficients", s->glossy_count ? (double)s->grow_start[(size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N] : 0.0);
        cJSON_AddBoolToObject(j, "glossy_environment", s->genv != NULL);
        return;
    }
    prt__describe_line(d, "basis:", "%u functions over %u partitions (%u..%u vertices, %u..%u functions each), %.2f MiB", b->functions, b->partitions,
                       vmin, vmax, kmin, kmax, basis_bytes(t) / 1048576.0);
    char storage[96];
    if (s->one_scale) snprintf(storage, sizeof storage, "16-bit, one scale");
    else if (s->drop > 0) snprintf(storage, sizeof storage, "16-bit, a scale per row, entries under %g of their row's largest dropped", s->drop);
    else snprintf(storage, sizeof storage, "16-bit, a scale per row");
    prt__describe_line(d, "transfer:", "%llu coefficients, %.1f per vertex (at most %llu), %s, %.2f MiB", (unsigned long long)nnz, per_vertex,
                       (unsigned long long)rmax, storage, spectral_bytes(t) / 1048576.0);
    prt__describe_line(d, "bake:", "%d rays per vertex; environment through SH order %d (%d coefficients per vertex)", s->samples, s->env_order,
                       s->env_order * s->env_order);
    if (s->glossy_count && s->genv)
        prt__describe_line(d, "glossy:", "%u vertices with a glossy final bounce (16 SH BRDF bases), %llu coefficients; the environment through a "
                           "16 x %d shadowed transfer per vertex", s->glossy_count,
                           (unsigned long long)s->grow_start[(size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N], s->env_order * s->env_order);
    else if (s->glossy_count)
        prt__describe_line(d, "glossy:", "%u vertices with a glossy final bounce (16 SH BRDF bases), %llu coefficients; the environment reflected "
                           "diffusely only (a file from before glossy environment transfer)", s->glossy_count,
                           (unsigned long long)s->grow_start[(size_t)s->glossy_count * PRT__SPECTRAL_GLOSSY_N]);
}

/* ---- variants and controls ---- */

/* Three bounces as the paper, and the tail on: a closed room of albedo 0.7 keeps only 1 - 0.7^3
 * of its indirect light in three bounces; the tail brings it within 3% of 64 bounces at no
 * measurable cost (docs/CLI.md). */
static void spectral_control_range(const prt_transfer *t, int i, int *lo, int *hi, int *def)
{
    (void)t;
    *lo = 0;
    *hi = i == 1 ? 1 : 64;
    *def = i == 1 ? 1 : 3;
}

/* ---- relighting ---- */

/* The pixel lights' materials: each surface's BRDF as brdf_of switched it (its highlight changes
 * with it, as its glossy final bounce does). */
static prt_status spectral_pixel_materials(prt_context *ctx, const prt_transfer *t, const int *brdf_of, prt_relit *r)
{
    const prt__spectral_set *s = t->state;
    if (!brdf_of || !s->set_count) return prt__relit_pixel_materials(ctx, t, NULL, r);
    const prt_brdf **chosen = prt__calloc((size_t)t->mesh.surface_count + 1, sizeof *chosen);
    if (!chosen) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int k = 1; k <= t->mesh.surface_count; ++k)
        for (int e = 0, n = 0; brdf_of[k] >= 0 && e < s->set_count; ++e)
            if (s->set[e].surface == k && n++ == brdf_of[k]) chosen[k] = &s->set[e].brdf;
    const prt_status st = prt__relit_pixel_materials(ctx, t, chosen, r);
    free(chosen);
    return st;
}
static prt_status spectral_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    if (d->brdf) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf does not apply to spectral transfer (it reflects diffusely; see --albedo-of)");
    const size_t nv = t->mesh.vertex_count;
    const int bounces = d->controls ? d->controls[0] : 3, tail = d->controls ? d->controls[1] : 1;
    if (bounces < 0 || bounces > 64) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range 0..64", bounces);
    if (tail < 0 || tail > 1) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "tail %d out of range 0..1", tail);
    prt_status st = prt__relit_alloc(ctx, t, r, d->with_indirect || d->component == PRT_COMPONENT_INDIRECT);
    if (st) return st;
    /* A switched BRDF brings its Lambertian part as the surface's albedo unless the caller
     * gives the albedo. */
    float *switched = NULL;
    bool any = false;
    for (int k = 1; d->brdf_of && !d->albedo && t->mesh.surface && k <= t->mesh.surface_count; ++k) any |= d->brdf_of[k] >= 0;
    if (any) {
        if (!(switched = malloc(nv * 3 * sizeof(float)))) { prt_relit_free(r); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        memcpy(switched, t->mesh.albedo, nv * 3 * sizeof(float));
        for (size_t v = 0; v < nv; ++v) {
            const uint16_t k = t->mesh.surface[v];
            prt_brdf b;
            if (k && d->brdf_of[k] >= 0 && spectral_brdf_set(t, k, d->brdf_of[k], &b) > d->brdf_of[k]) prt_brdf_lambert_albedo(&b, switched + v * 3);
        }
    }
    const float *albedo = d->albedo ? d->albedo : switched ? switched : t->mesh.albedo;
    /* Drawn, the local lights' direct light is the renderer's, per pixel with shadow maps (as the
     * paper draws it); its per-vertex value still feeds the bounces. */
    const int pixel = d->per_vertex || d->no_pixel_lights || d->component == PRT_COMPONENT_INDIRECT ? 0 : prt_lighting_count(l) < PRT_MAX_PIXEL_LIGHTS ? prt_lighting_count(l) : PRT_MAX_PIXEL_LIGHTS;
    float *E = prt__calloc(nv * 3, sizeof(float)), *direct = prt__calloc(nv * 3, sizeof(float));
    float *Ep = pixel ? prt__calloc(nv * 3, sizeof(float)) : NULL;
    float *indirect = r->indirect ? r->indirect : prt__calloc(nv * 3, sizeof(float));
    if (!E || !direct || !indirect || (pixel && !Ep)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__spectral_direct(ctx, t, l, E, Ep, pixel);
    if (!st) {
        for (size_t i = 0; i < nv * 3; ++i) direct[i] = albedo[i] / (float)PRT_PI * E[i];
        /* Drawn with all its light, the bounces run on the GPU (gpu.c) from this direct light. */
        const bool gpu = d->gpu_finish && d->component == PRT_COMPONENT_ALL && !r->indirect && prt__spectral_gpu_can(t, bounces, tail);
        st = prt__spectral_bounces(ctx, t, albedo, direct, d->component == PRT_COMPONENT_DIRECT || gpu ? 0 : bounces, tail, indirect);
        if (!st && gpu) st = prt__spectral_gpu(ctx, t, albedo, direct, bounces, tail, r);
    }
    if (!st && pixel) {
        r->pixel_lights = malloc((size_t)pixel * sizeof(prt_light));
        r->pixel_albedo = malloc(nv * 3 * sizeof(float));
        r->pixel_visibility = malloc((size_t)pixel * nv * sizeof(float));
        if (!r->pixel_lights || !r->pixel_albedo || !r->pixel_visibility) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            for (int i = 0; i < pixel; ++i) r->pixel_lights[i] = *prt_lighting_light(l, i);
            r->pixel_light_count = pixel;
            st = prt__spectral_visibility(ctx, t, r->pixel_lights, pixel, r->pixel_visibility);
            memcpy(r->pixel_albedo, albedo, nv * 3 * sizeof(float));
            if (!st) st = spectral_pixel_materials(ctx, t, d->brdf_of, r);
            for (size_t i = 0; i < nv * 3; ++i) direct[i] -= albedo[i] / (float)PRT_PI * Ep[i];
        }
    }
    const float emission = prt_lighting_emission(l);
    const float *le = t->mesh.emission;
    if (!st) {
        for (size_t i = 0; i < nv * 3; ++i) {
            const float own = le ? emission * le[i] : 0.0f;
            switch (d->component) {
            case PRT_COMPONENT_DIRECT: r->radiance[i] = own + direct[i]; break;
            case PRT_COMPONENT_INDIRECT: r->radiance[i] = indirect[i]; break;
            default: r->radiance[i] = own + direct[i] + indirect[i]; break;
            }
        }
    }
    /* The glossy final bounce (eq. 8): glossy surfaces reflect, view-dependently, everything the
     * other surfaces send out - emission, reflected direct light, the bounces - seen through the
     * basis; the renderer evaluates it per pixel. */
    const prt__spectral_set *s = t->state;
    if (!st && s->glossy_count) {
        float *out = malloc(nv * 3 * sizeof(float));
        r->exit_sh = malloc(nv * 3 * PRT__SPECTRAL_GLOSSY_N * sizeof(float));
        if (!out || !r->exit_sh) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            /* direct[] lacks the pixel lights' part: the surfaces' outgoing light needs all of it. */
            /* The emitters' glossy reflection is direct light, the rest of it indirect: the
             * components add up to the whole. */
            for (size_t i = 0; i < nv * 3; ++i) {
                const float own = le && d->component != PRT_COMPONENT_INDIRECT ? emission * le[i] : 0.0f;
                const float bounced = direct[i] + (Ep ? albedo[i] / (float)PRT_PI * Ep[i] : 0.0f) + indirect[i];
                out[i] = own + (d->component == PRT_COMPONENT_DIRECT ? 0.0f : bounced);
            }
            /* The environment's own glossy reflection is direct light. */
            prt_sh_light env;
            memset(&env, 0, sizeof env);
            if (d->component != PRT_COMPONENT_INDIRECT) st = prt__spectral_env_sh(ctx, t, l, &env);
            if (!st) st = prt__spectral_glossy(ctx, t, out, &env, d->brdf_of, r->exit_sh);
            r->exit_order = PRT__SPECTRAL_GLOSSY_ORDER;
            r->exit_mirror = 0;
        }
        free(out);
    }
    free(E);
    free(Ep);
    free(direct);
    free(switched);
    if (indirect != r->indirect) free(indirect);
    return st;
}

/* The per-vertex value of what the renderer draws per pixel: the pixel lights' direct light. */
static prt_status spectral_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb)
{
    if (!r->pixel_lights) return PRT_OK;
    const prt__spectral_set *s = t->state;
    prt_status st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, &s->cache->lights);
    const prt__vertex_materials mat = {r->pixel_albedo, r->pixel_material, r->pixel_brdfs, r->pixel_brdf_count};
    if (!st) prt__vertex_lights_shade(ctx, &s->cache->lights, &t->mesh, r->pixel_lights, r->pixel_light_count, &mat, eye, rgb);
    return st;
}

const prt__method prt__method_spectral = {
    .name = "spectral",
    .title = "direct-to-indirect transfer in a spectral mesh basis",
    .summary = "spectral mesh basis (Wang, Zhu & Humphreys): multi-bounce indirect light from any local light, albedo live",
    .lighting = PRT_LIGHTS_ENVIRONMENT | PRT_LIGHTS_POINT | PRT_LIGHTS_SPOT | PRT_LIGHTS_DIRECTIONAL | PRT_LIGHTS_SPHERE | PRT_LIGHTS_EMISSIVE,
    .runtime_albedo = true,
    .options = options,
    .option_count = (int)(sizeof options / sizeof options[0]),
    .controls = controls,
    .control_count = (int)(sizeof controls / sizeof controls[0]),
    .bake_begin = spectral_bake_begin,
    .memory_estimate = spectral_memory_estimate,
    .free_state = prt__spectral_set_free,
    .save = prt__spectral_save,
    .load = prt__spectral_load,
    .describe = spectral_describe,
    .transfer_bytes = spectral_bytes,
    .control_range = spectral_control_range,
    .web = prt__spectral_web,
    .brdf_set = spectral_brdf_set,
    .gpu_passes = true,
    .relight = spectral_relight,
    .shade = spectral_shade,
};

/* ---- the spectral public accessors ---- */
int prt_transfer_spectral_info(const prt_transfer *t, prt_spectral_info *info)
{
    if (info) memset(info, 0, sizeof *info);
    const prt__spectral_set *s = prt__spectral(t);
    if (!s) return 0;
    if (info) {
        info->partitions = (int)s->basis.partitions;
        info->functions = (int)s->basis.functions;
        info->samples = s->samples;
        info->partition_size = s->partition_size;
        info->env_order = s->env_order;
        info->coefficients = s->row_start[t->mesh.vertex_count];
        info->basis_bytes = basis_bytes(t);
        info->transfer_bytes = spectral_bytes(t);
    }
    return 1;
}

int prt_transfer_spectral_vertex(const prt_transfer *t, size_t v, int *partition, int *first, int *count, const float **values)
{
    const prt__spectral_set *s = prt__spectral(t);
    if (!s || v >= t->mesh.vertex_count) return 0;
    const prt__spectral_basis *b = &s->basis;
    const uint32_t p = b->part_of[v];
    if (partition) *partition = (int)p;
    if (first) *first = (int)b->first[p];
    if (count) *count = (int)b->count[p];
    if (values) *values = b->values + b->offset[v];
    return 1;
}

prt_status prt_spectral_project(const prt_transfer *t, const float *signal, float *coefficients)
{
    const prt__spectral_set *s = prt__spectral(t);
    if (!s || !signal || !coefficients) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_spectral_project: a spectral transfer and arrays are required");
    prt__spectral_project(&s->basis, signal, coefficients, prt__threads(NULL));
    return PRT_OK;
}

prt_status prt_spectral_reconstruct(const prt_transfer *t, const float *coefficients, float *signal)
{
    const prt__spectral_set *s = prt__spectral(t);
    if (!s || !signal || !coefficients) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_spectral_reconstruct: a spectral transfer and arrays are required");
    prt__spectral_reconstruct(&s->basis, t->mesh.vertex_count, coefficients, signal, prt__threads(NULL));
    return PRT_OK;
}
