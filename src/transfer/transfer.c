/* prt_transfer: the method-independent parts (mesh, materials, lighting, bookkeeping) and the
 * dispatch of variants, controls and relighting to the method's table entry. */
#include "transfer/method.h"

#include <math.h>
#include <stdatomic.h>

prt_status prt__mesh_copy(prt__mesh *dst, const prt__mesh *src)
{
    prt_status st = prt__mesh_append(dst, src->positions, src->normals, src->albedo, (float[3]){0, 0, 0}, src->vertex_count,
                                     src->indices, src->triangle_count);
    if (!st && src->material) memcpy(dst->material, src->material, src->vertex_count);
    if (!st && src->uv) memcpy(dst->uv, src->uv, src->vertex_count * 2 * sizeof(float));
    if (!st && src->emission && !prt__mesh_emission(dst)) st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory copying a mesh");
    if (!st && src->emission) memcpy(dst->emission, src->emission, src->vertex_count * 3 * sizeof(float));
    /* Surface names: dst is empty here, so ids stay as they are. */
    if (!st && src->surface_count) {
        if (!(dst->surface_names = malloc((size_t)src->surface_count * PRT__SURFACE_NAME))) st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory copying a mesh");
        else {
            memcpy(dst->surface_names, src->surface_names, (size_t)src->surface_count * PRT__SURFACE_NAME);
            dst->surface_count = src->surface_count;
        }
    }
    if (!st && src->surface) memcpy(dst->surface, src->surface, src->vertex_count * sizeof(uint16_t));
    return st;
}

static prt_status copy_lights(prt_transfer *t, const prt_light *lights, int count)
{
    if (!count) return PRT_OK;
    t->lights = malloc((size_t)count * sizeof *lights);
    if (!t->lights) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    for (int i = 0; i < count; ++i) prt_light_copy(&t->lights[i], &lights[i]);   /* its own profile references */
    t->light_count = count;
    return PRT_OK;
}

uint64_t prt__transfer_serial(void)
{
    static _Atomic uint64_t next = 1;
    return atomic_fetch_add(&next, 1);
}

prt_status prt__transfer_from_scene(prt_context *ctx, const prt__method *m, const prt_scene *scene, prt_transfer **out)
{
    prt_transfer *t = prt__calloc(1, sizeof *t);
    if (!t) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->method = m;
    t->serial = prt__transfer_serial();
    prt_status st = prt__mesh_copy(&t->mesh, &scene->mesh);
    if (!st) st = copy_lights(t, scene->lights, scene->light_count);
    if (st) { prt_transfer_release(t); return prt__fail(ctx, st, "%s", prt_last_error()); }
    t->brdf_count = scene->brdf_count;
    memcpy(t->brdfs, scene->brdfs, sizeof t->brdfs);
    t->has_env = scene->has_env;
    t->env = scene->env;
    snprintf(t->source, sizeof t->source, "%s", scene->source);
    *out = t;
    return PRT_OK;
}

prt_status prt__transfer_copy_frame(prt_context *ctx, const prt_transfer *src, prt_transfer **out)
{
    prt_transfer *t = prt__calloc(1, sizeof *t);
    if (!t) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    *t = *src;
    t->serial = prt__transfer_serial();
    memset(&t->mesh, 0, sizeof t->mesh);
    t->lights = NULL;
    t->light_count = 0;
    t->state = NULL;
    prt_status st = prt__mesh_copy(&t->mesh, &src->mesh);
    if (!st) st = copy_lights(t, src->lights, src->light_count);
    if (st) { prt_transfer_release(t); return prt__fail(ctx, st, "%s", prt_last_error()); }
    *out = t;
    return PRT_OK;
}

void prt_transfer_release(prt_transfer *t)
{
    if (!t) return;
    if (t->state && t->method) t->method->free_state(t->state);
    prt__mesh_free(&t->mesh);
    for (int i = 0; i < t->light_count; ++i) prt_light_clear(&t->lights[i]);
    free(t->lights);
    free(t);
}

const prt_method *prt_transfer_method(const prt_transfer *t) { return t ? t->method : NULL; }

int prt_transfer_frame_count(const prt_transfer *t)
{
    return t && t->method->frame_count ? t->method->frame_count(t) : 1;
}

prt_status prt_transfer_at_time(prt_context *ctx, const prt_transfer *t, double time, prt_transfer **out)
{
    if (!t || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_at_time: transfer and out are required");
    *out = NULL;
    const int count = prt_transfer_frame_count(t);
    if (count < 2 || !t->method->at_time) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the transfer holds one pose, no key frames to take a time between");
    /* Refused rather than clamped: a time past the last key frame is a script's mistake to see. */
    if (!(time >= 0 && time <= count - 1))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "time %g lies outside the key frames, 0 to %d (times are not clamped)", time, count - 1);
    int frame = (int)floor(time);
    if (frame > count - 2) frame = count - 2;
    prt_transfer *n = NULL;
    prt_status st = prt__transfer_copy_frame(ctx, t, &n);
    if (!st) st = t->method->at_time(ctx, t, frame, (float)(time - frame), n);
    if (st) { prt_transfer_release(n); return st; }
    *out = n;
    return PRT_OK;
}
double prt_transfer_bake_seconds(const prt_transfer *t) { return t ? t->bake_seconds : 0; }
uint64_t prt_transfer_peak_bytes(const prt_transfer *t) { return t ? t->peak_bytes : 0; }
uint64_t prt_transfer_memory_limit(const prt_transfer *t) { return t ? t->memory_limit : 0; }
int prt_transfer_bake_threads(const prt_transfer *t) { return t ? t->threads : 0; }
const char *prt_transfer_source(const prt_transfer *t) { return t ? t->source : ""; }
size_t prt_transfer_vertex_count(const prt_transfer *t) { return t->mesh.vertex_count; }
size_t prt_transfer_triangle_count(const prt_transfer *t) { return t->mesh.triangle_count; }
const float *prt_transfer_positions(const prt_transfer *t) { return t->mesh.positions; }
const float *prt_transfer_normals(const prt_transfer *t) { return t->mesh.normals; }
const float *prt_transfer_albedo(const prt_transfer *t) { return t->mesh.albedo; }
const uint32_t *prt_transfer_indices(const prt_transfer *t) { return t->mesh.indices; }
const float *prt_transfer_uvs(const prt_transfer *t) { return prt__mesh_has_uv(&t->mesh) ? t->mesh.uv : NULL; }
int prt_transfer_brdf_count(const prt_transfer *t) { return t->brdf_count; }
const prt_brdf *prt_transfer_brdf(const prt_transfer *t, int k) { return k >= 1 && k <= t->brdf_count ? &t->brdfs[k - 1] : NULL; }
const uint8_t *prt_transfer_materials(const prt_transfer *t) { return t->mesh.material; }
int prt_transfer_surface_count(const prt_transfer *t) { return t ? t->mesh.surface_count : 0; }
const char *prt_transfer_surface_name(const prt_transfer *t, int k) { return t && k >= 1 && k <= t->mesh.surface_count ? t->mesh.surface_names[k - 1] : NULL; }
const uint16_t *prt_transfer_surfaces(const prt_transfer *t) { return t && t->mesh.surface_count ? t->mesh.surface : NULL; }

prt_status prt_transfer_paint_albedo(const prt_transfer *t, const char *name, const float rgb[3], float *albedo)
{
    if (!t || !name || !rgb || !albedo) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_paint_albedo: transfer, name, colour and albedo are required");
    return prt__mesh_paint(&t->mesh, name, rgb, albedo);
}
const float *prt_transfer_emission(const prt_transfer *t) { return t->mesh.emission; }
int prt_transfer_light_count(const prt_transfer *t) { return t->light_count; }
const prt_light *prt_transfer_light(const prt_transfer *t, int i) { return i >= 0 && i < t->light_count ? &t->lights[i] : NULL; }

int prt_transfer_environment(const prt_transfer *t, prt_environment_desc *out)
{
    if (t->has_env) *out = t->env;
    return t->has_env;
}

prt_status prt_transfer_lighting(prt_context *ctx, const prt_transfer *t, prt_lighting **out)
{
    if (!t || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_lighting: transfer and out are required");
    prt_lighting *l = NULL;
    prt_status st = prt_lighting_create(&l);
    /* A scene that names no environment is lit by the procedural sky, unless it brings lights of
     * its own (a room lit by its lamps). */
    prt_environment_desc env = {0};
    if (t->has_env) env = t->env;
    else env.none = t->light_count > 0 || t->mesh.emission != NULL;
    if (!st) st = prt_lighting_set_environment(l, &env);
    for (int i = 0; i < t->light_count && !st; ++i) st = prt_lighting_add(l, &t->lights[i], NULL);
    if (st) { prt_lighting_release(l); return prt__fail(ctx, st, "%s", prt_last_error()); }
    *out = l;
    return PRT_OK;
}

prt_status prt_transfer_scene(prt_context *ctx, const prt_transfer *t, prt_scene **out)
{
    if (!t || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_scene: transfer and out are required");
    *out = NULL;
    prt_scene *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = prt__mesh_copy(&s->mesh, &t->mesh);
    if (!st && t->light_count) {
        if (!(s->lights = malloc((size_t)t->light_count * sizeof *s->lights))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            for (int i = 0; i < t->light_count; ++i) prt_light_copy(&s->lights[i], &t->lights[i]);
            s->light_count = t->light_count;
        }
    }
    if (st) { prt_scene_release(s); return st; }
    s->brdf_count = t->brdf_count;
    memcpy(s->brdfs, t->brdfs, sizeof s->brdfs);
    s->has_env = t->has_env;
    s->env = t->env;
    snprintf(s->source, sizeof s->source, "%s", t->source);
    *out = s;
    return PRT_OK;
}

/* ---- variants and controls ---- */
/* A method without variant hooks has one variant, named after it. */
static int variants(const prt_transfer *t) { return t->method->variant_count ? t->method->variant_count(t) : 1; }
static const char *variant(const prt_transfer *t, int i) { return t->method->variant_name ? t->method->variant_name(t, i) : t->method->name; }

int prt_transfer_variant_count(const prt_transfer *t) { return variants(t); }

const char *prt_transfer_variant_name(const prt_transfer *t, int i)
{
    return i >= 0 && i < variants(t) ? variant(t, i) : "";
}

int prt_transfer_default_variant(const prt_transfer *t, int drawing) { return t->method->default_variant ? t->method->default_variant(t, drawing) : 0; }

int prt_transfer_find_variant(const prt_transfer *t, const char *name)
{
    const int n = variants(t);
    int found = t->method->find_variant ? t->method->find_variant(t, name) : -1;
    for (int i = 0; i < n && found < 0; ++i)
        if (!strcmp(variant(t, i), name)) found = i;
    if (found >= 0) return found;
    char list[512] = "";
    size_t at = 0;
    for (int i = 0; i < n && at < sizeof list; ++i) at += (size_t)snprintf(list + at, sizeof list - at, "%s%s", i ? ", " : "", variant(t, i));
    prt__fail(NULL, PRT_ERR_INVALID_ARG, "this %s file holds no '%s' (it holds %s)", t->method->name, name, list);
    return -1;
}

int prt_transfer_controls(const prt_transfer *t, const prt_control_desc **out)
{
    if (out) *out = t->method->controls;
    return t->method->control_count;
}

void prt_transfer_control_range(const prt_transfer *t, int i, int *lo, int *hi, int *def)
{
    int a = 0, b = 0, c = 0;
    if (i >= 0 && i < t->method->control_count) t->method->control_range(t, i, &a, &b, &c);
    if (lo) *lo = a;
    if (hi) *hi = b;
    if (def) *def = c;
}

/* ---- relighting ---- */
prt_status prt__relit_pixel_materials(prt_context *ctx, const prt_transfer *t, const prt_brdf *const *surface_brdf, prt_relit *r)
{
    const size_t nv = t->mesh.vertex_count;
    uint8_t *material = prt__calloc(nv ? nv : 1, 1);
    prt_brdf *table = prt__calloc(PRT__MAX_BRDFS, sizeof(prt_brdf));
    if (!material || !table) { free(material); free(table); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    int count = t->brdf_count;
    memcpy(table, t->brdfs, (size_t)count * sizeof(prt_brdf));
    if (t->mesh.material) memcpy(material, t->mesh.material, nv);
    /* Switched surfaces: their BRDF's row of the table, appended once. */
    for (size_t v = 0; surface_brdf && t->mesh.surface && v < nv; ++v) {
        const prt_brdf *b = surface_brdf[t->mesh.surface[v]];
        if (!b) continue;
        int id = 0;
        for (int k = 0; k < count && !id; ++k)
            if (!memcmp(&table[k], b, sizeof *b)) id = k + 1;
        if (!id && count < PRT__MAX_BRDFS) { table[count++] = *b; id = count; }
        material[v] = (uint8_t)id;
    }
    bool glossy = false;
    for (size_t v = 0; v < nv && !glossy; ++v) glossy = material[v] && prt_brdf_is_glossy(&table[material[v] - 1]);
    if (!glossy) { free(material); free(table); return PRT_OK; }
    r->pixel_material = material;
    r->pixel_brdfs = table;
    r->pixel_brdf_count = count;
    return PRT_OK;
}

prt_status prt__relit_alloc(prt_context *ctx, const prt_transfer *t, prt_relit *r, bool indirect)
{
    const size_t nv = t->mesh.vertex_count;
    r->vertex_count = nv;
    r->radiance = prt__calloc(nv * 3, sizeof(float));
    if (indirect) r->indirect = prt__calloc(nv * 3, sizeof(float));
    if (!r->radiance || (indirect && !r->indirect)) { prt_relit_free(r); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    return PRT_OK;
}

void prt_relit_free(prt_relit *r)
{
    if (!r) return;
    free(r->radiance);
    free(r->indirect);
    free(r->exit_sh);
    free(r->texels);
    free(r->kvec);
    free(r->pixel_lights);
    free(r->pixel_albedo);
    free(r->pixel_visibility);
    free(r->pixel_material);
    free(r->pixel_brdfs);
    free(r->gpu_input);
    free(r->gpu_pixel_direct);
    for (int k = 0; k < r->volume_count; ++k) {
        free((void *)r->volumes[k].extinction);
        free((void *)r->volumes[k].source);
    }
    free(r->volumes);
    free(r->gpu_vector);
    memset(r, 0, sizeof *r);
}

prt_status prt_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *desc, prt_relit *out)
{
    if (!t || !l || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_relight: transfer, lighting and out are required");
    memset(out, 0, sizeof *out);
    prt_relight_desc d = desc ? *desc : (prt_relight_desc){.variant = -1};
    if (!desc) d.variant = -1;
    if (d.variant < 0) d.variant = prt_transfer_default_variant(t, 1);
    if (d.variant >= variants(t)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "variant %d out of range (the file has %d)", d.variant, variants(t));
    if (d.component < PRT_COMPONENT_ALL || d.component > PRT_COMPONENT_INDIRECT) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "unknown light component %d", d.component);
    if (d.albedo && !t->method->runtime_albedo)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the %s method bakes surface colours in%s%s: changing them needs a rebake", t->method->name,
                         t->method->baked_albedo_why ? " - " : "", t->method->baked_albedo_why ? t->method->baked_albedo_why : "");
    for (int k = 1; d.brdf_of && k <= t->mesh.surface_count; ++k) {
        if (d.brdf_of[k] < 0) continue;
        const int n = prt_transfer_brdf_set(t, k, -1, NULL);
        if (!n) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "surface '%s' has no BRDF set to switch among%s", t->mesh.surface_names[k - 1],
                                 t->method->brdf_set ? " (a material's \"brdfs\" in the scene)" : " (spectral bakes keep one: a material's \"brdfs\")");
        if (d.brdf_of[k] >= n) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "surface '%s': BRDF %d out of range (its set has %d)", t->mesh.surface_names[k - 1], d.brdf_of[k], n);
    }
    if (d.albedo)
        for (size_t i = 0; i < t->mesh.vertex_count * 3; ++i)
            if (!(d.albedo[i] >= 0.0f && d.albedo[i] <= 1.0f)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "albedo must lie in [0, 1]");
    prt_status st = prt__paint_check(ctx, t, &d);
    if (st) return st;
    st = prt_method_check_lighting(t->method, prt_relight_needs(t, l));
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    st = t->method->relight(ctx, t, l, &d, out);
    /* Overflow anywhere (lights of 1e38) is an error, never infinities handed on. */
    const size_t nv = t->mesh.vertex_count;
    if (!st && (!prt__all_finite(out->radiance, nv * 3) || (out->indirect && !prt__all_finite(out->indirect, nv * 3)) ||
                (out->exit_sh && !prt__all_finite(out->exit_sh, nv * 3 * (size_t)out->exit_order * out->exit_order)) ||
                (out->texels && !prt__all_finite(out->texels, (size_t)out->texel_width * out->texel_height * 3)) ||
                (out->kvec && !prt__all_finite(out->kvec, nv * 3 * (size_t)out->kvec_terms))))
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "relighting overflowed (the result is not finite): the lighting is too bright");
    if (st) prt_relit_free(out);
    return st;
}

int prt_transfer_brdf_set(const prt_transfer *t, int k, int i, prt_brdf *out)
{
    if (!t || !t->method->brdf_set || k < 1 || k > t->mesh.surface_count) return 0;
    return t->method->brdf_set(t, k, i, out);
}

unsigned prt_relight_needs(const prt_transfer *t, const prt_lighting *l)
{
    unsigned what = prt_lighting_content(l) & ~(unsigned)PRT_LIGHTS_EMISSIVE;
    if (t && t->mesh.emission && prt_lighting_emission(l) > 0) what |= PRT_LIGHTS_EMISSIVE;
    return what;
}

int prt_relit_view_dependent(const prt_relit *r)
{
    return r && (r->exit_sh || (r->gpu_sums && (prt_render_sums_exit_product(r->gpu_sums) || prt_render_sums_kvec_product(r->gpu_sums))) || r->kvec ||
                 (r->pixel_lights && r->pixel_material));
}

void prt_relit_render_mesh(const prt_transfer *t, const prt_relit *r, prt_render_mesh *m)
{
    memset(m, 0, sizeof *m);
    m->positions = t->mesh.positions;
    m->normals = t->mesh.normals;
    m->indices = t->mesh.indices;
    m->vertex_count = t->mesh.vertex_count;
    m->triangle_count = t->mesh.triangle_count;
    m->uv = prt__mesh_has_uv(&t->mesh) ? t->mesh.uv : NULL;
    m->radiance = r->radiance;
    m->exit_sh = r->exit_sh;
    m->exit_order = r->exit_sh || (r->gpu_sums && prt_render_sums_exit_product(r->gpu_sums)) ? r->exit_order : 0;
    m->exit_mirror = r->exit_mirror;
    m->texel_radiance = r->texels;
    m->texel_width = r->texel_width;
    m->texel_height = r->texel_height;
    m->kvec = r->kvec;
    m->kvec_terms = r->kvec || (r->gpu_sums && prt_render_sums_kvec_product(r->gpu_sums)) ? r->kvec_terms : 0;
    m->view_set = r->view_set;
    m->view_maps = r->view_maps;
    m->view_map_sets = r->view_map_sets;
    m->view_map_resolution = r->view_map_resolution;
    m->view_map_polar = r->view_map_polar;
    m->lights = r->pixel_lights;
    m->light_count = r->pixel_lights ? r->pixel_light_count : 0;
    m->albedo = r->pixel_albedo;
    m->light_visibility = r->pixel_lights ? r->pixel_visibility : NULL;
    m->light_material = r->pixel_lights ? r->pixel_material : NULL;
    m->light_brdfs = r->pixel_lights ? r->pixel_brdfs : NULL;
    m->light_brdf_count = r->pixel_lights && r->pixel_material ? r->pixel_brdf_count : 0;
    m->volumes = r->volumes;
    m->volume_count = r->volume_count;
    if (r->gpu_input) {
        m->gpu_passes = r->gpu_passes;
        m->gpu_input = r->gpu_input;
        m->gpu_emission = r->gpu_emission;
        m->gpu_bounces = r->gpu_bounces;
        m->gpu_component = r->gpu_component;
        m->gpu_pixel_direct = r->gpu_pixel_direct;
    }
    if (r->gpu_sums && r->gpu_vector) {
        m->gpu_sums = r->gpu_sums;
        m->gpu_vector = r->gpu_vector;
    }
}

void prt_glossy_eval(int order, const float *exit_coeffs, int mirror, const float normal[3], const float to_eye[3], float rgb[3])
{
    float d[3] = {to_eye[0], to_eye[1], to_eye[2]}, y[PRT_SH_MAX_COEFFS];
    if (mirror) {
        float k = 2.0f * prt__v3_dot(normal, to_eye);
        for (int c = 0; c < 3; ++c) d[c] = k * normal[c] - to_eye[c];
    }
    /* Run-time lobes leave out the BRDF's cosine: near the mirror direction it is n.v. */
    float v[3] = {to_eye[0], to_eye[1], to_eye[2]};
    prt__v3_normalize(v);
    const float cosine = mirror ? fmaxf(prt__v3_dot(normal, v), 0.0f) : 1.0f;
    prt__v3_normalize(d);
    prt_sh_eval_f(order, d, y);
    const int n = order * order;
    for (int c = 0; c < 3; ++c) {
        float s = 0.0f;
        for (int i = 0; i < n; ++i) s += exit_coeffs[c * n + i] * y[i];
        rgb[c] = s > 0.0f ? cosine * s : 0.0f;   /* truncated SH rings below zero near sharp features */
    }
}

prt_status prt_relit_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb)
{
    if (!t || !r || !rgb || r->vertex_count != t->mesh.vertex_count) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_relit_shade: a result of this transfer is required");
    if (prt_relit_view_dependent(r) && !eye) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "this result is view-dependent: an eye position is required");
    const size_t nv = t->mesh.vertex_count;
    memcpy(rgb, r->radiance, nv * 3 * sizeof(float));
    /* The light a renderer would have summed on the GPU, summed here. */
    if (r->gpu_sums && r->gpu_vector) {
        const prt_status st = prt_render_sums_cpu(r->gpu_sums, r->gpu_vector, nv, rgb);
        if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    }
    /* Exit coefficients the GPU would have summed, summed here. */
    float *gpu_exit = NULL;
    if (!r->exit_sh && r->gpu_sums && prt_render_sums_exit_product(r->gpu_sums)) {
        if (!(gpu_exit = malloc(nv * 3 * (size_t)r->exit_order * r->exit_order * sizeof(float)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        const prt_status st = prt_render_sums_exit_cpu(r->gpu_sums, r->gpu_vector, nv, r->exit_order, gpu_exit);
        if (st) { free(gpu_exit); return prt__fail(ctx, st, "%s", prt_last_error()); }
    }
    const float *exit_sh = r->exit_sh ? r->exit_sh : gpu_exit;
    if (exit_sh) {
        const size_t stride = 3 * (size_t)r->exit_order * r->exit_order;
        const float *P = t->mesh.positions, *N = t->mesh.normals;
        for (size_t v = 0; v < nv; ++v) {
            float to_eye[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]}, g[3];
            prt_glossy_eval(r->exit_order, exit_sh + v * stride, r->exit_mirror, N + v * 3, to_eye, g);
            for (int c = 0; c < 3; ++c) rgb[v * 3 + c] += g[c];
        }
    }
    free(gpu_exit);
    /* View-factor terms the GPU would have summed: the method's shade reads them from a copy. */
    if (!r->kvec && r->gpu_sums && prt_render_sums_kvec_product(r->gpu_sums) && t->method->shade) {
        prt_relit with = *r;
        if (!(with.kvec = malloc(nv * (size_t)r->kvec_terms * 3 * sizeof(float)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        prt_status st = prt_render_sums_kvec_cpu(r->gpu_sums, r->gpu_vector, nv, r->kvec_terms, with.kvec);
        if (st) st = prt__fail(ctx, st, "%s", prt_last_error());
        else st = t->method->shade(ctx, t, &with, eye, rgb);
        free(with.kvec);
        return st;
    }
    if ((r->kvec || r->pixel_lights) && t->method->shade) return t->method->shade(ctx, t, r, eye, rgb);
    return PRT_OK;
}
