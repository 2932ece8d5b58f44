/* Offset transfer maps at run time: the first-order light map (local lights with shadow rays from
 * each texel, the environment through each texel's shadowed SH transfer, emission), subsurface
 * scattering and inter-reflection as modulate-shift-accumulate passes over it (eq. 9), the
 * inter-reflection pass repeated once per bounce on what the last one gave. */
#include "method/offset.h"

#include "bake/texel_raster.h"

bool prt__offset_set_index(prt__offset_set *s)
{
    const size_t n = (size_t)s->width * s->height;
    free(s->index);
    free(s->source);
    s->source = NULL;
    if (!(s->index = malloc(n * sizeof *s->index))) return false;
    for (size_t i = 0; i < n; ++i) s->index[i] = -1;
    for (uint32_t k = 0; k < s->covered; ++k) {
        if (s->texel[k] >= n || (k && s->texel[k] <= s->texel[k - 1])) return false;
        s->index[s->texel[k]] = (int32_t)k;
    }
    if (!(s->source = malloc(n * sizeof *s->source))) return false;
    return prt__texel_gutter_sources(s->width, s->height, s->index, s->source);
}

/* out[i] = sum_k in(texel i + offset k) maps[k][i], over covered texels. An offset landing off
 * the surface reads its gutter's source (s->source): a cell that does hold surface takes the light
 * of the chart's edge rather than nothing - as the paper's lightmap with dilated gutters gives it,
 * and exactly what the GPU path (render/offset_gl.c) reads. */
static void apply(prt_context *ctx, const prt__offset_set *s, const float *maps, const float *in, float *out)
{
    const int W = s->width, H = s->height;
    const size_t nc = s->covered;
    const int32_t *src = s->source;
#pragma omp parallel for schedule(static, 256) num_threads(prt__threads(ctx))
    for (size_t i = 0; i < nc; ++i) {
        const int tx = (int)(s->texel[i] % (uint32_t)W), ty = (int)(s->texel[i] / (uint32_t)W);
        float sum[3] = {0, 0, 0};
        for (int k = 0; k < s->count; ++k) {
            const int sx = tx + s->offsets[k * 2], sy = ty + s->offsets[k * 2 + 1];
            if (sx < 0 || sx >= W || sy < 0 || sy >= H) continue;
            const float *m = maps + ((size_t)k * nc + i) * 3, *f = in + (size_t)src[(size_t)sy * W + sx] * 3;
            sum[0] += f[0] * m[0];
            sum[1] += f[1] * m[1];
            sum[2] += f[2] * m[2];
        }
        memcpy(out + i * 3, sum, sizeof sum);
    }
}

/* A full map from covered-texel values: every texel takes its source's (gutters included). */
static void spread(const prt__offset_set *s, const float *values, float *map)
{
    const size_t n = (size_t)s->width * s->height;
    for (size_t i = 0; i < n; ++i) {
        const int32_t c = s->source[i];
        if (c >= 0) memcpy(map + i * 3, values + (size_t)c * 3, 3 * sizeof *map);
        else map[i * 3] = map[i * 3 + 1] = map[i * 3 + 2] = 0;
    }
}

/* Shadow rays from the texels: the mesh in Embree and the texels' ray origins, once. */
static prt_status lights_ready(prt_context *ctx, const prt_transfer *t, prt__offset_set *s)
{
    pthread_mutex_lock(s->lock);
    prt__vertex_lights *c = s->lights;
    prt_status st = PRT_OK;
    if (!c->ready) {
        const size_t nc = s->covered;
        float *o = malloc(nc * 3 * sizeof *o + 1);
        st = o ? prt__raycaster_create(ctx, &t->mesh, &c->rc) : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st) {
            for (size_t i = 0; i < nc * 3; ++i) o[i] = s->pos[i] + s->nrm[i] * s->ray_offset;
            c->origins = o;
            c->ready = true;
        } else {
            free(o);
        }
    }
    pthread_mutex_unlock(s->lock);
    return st;
}

/* Bilinear lookup of a texel map at (u, v), clamped at the border. */
static void sample_map(const float *map, int W, int H, float u, float v, float out[3])
{
    const float x = fminf(fmaxf(u * W - 0.5f, 0.0f), (float)(W - 1)), y = fminf(fmaxf(v * H - 0.5f, 0.0f), (float)(H - 1));
    const int x0 = (int)x, y0 = (int)y, x1 = x0 + 1 < W ? x0 + 1 : x0, y1 = y0 + 1 < H ? y0 + 1 : y0;
    const float fx = x - x0, fy = y - y0;
    for (int c = 0; c < 3; ++c) {
        const float a = map[((size_t)y0 * W + x0) * 3 + c] * (1 - fx) + map[((size_t)y0 * W + x1) * 3 + c] * fx;
        const float b = map[((size_t)y1 * W + x0) * 3 + c] * (1 - fx) + map[((size_t)y1 * W + x1) * 3 + c] * fx;
        out[c] = a * (1 - fy) + b * fy;
    }
}

prt_status prt__offset_relight(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const prt_relight_desc *d, prt_relit *r)
{
    prt__offset_set *s = t->state;
    const int bounces = d->controls ? d->controls[0] : 3;
    if (bounces < 0 || bounces > 64) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range 0..64", bounces);
    if (d->brdf) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf does not apply to offset transfer maps (they reflect diffusely)");
    const size_t nc = s->covered, n = (size_t)s->width * s->height, nv = t->mesh.vertex_count;
    prt_status st = prt__relit_alloc(ctx, t, r, !d->gpu_finish && (d->with_indirect || d->component == PRT_COMPONENT_INDIRECT));
    if (st) return st;
    float *E = prt__calloc(nc * 3, sizeof(float)), *first = malloc(nc * 3 * sizeof(float)), *indirect = prt__calloc(nc * 3, sizeof(float));
    float *a = malloc(nc * 3 * sizeof(float)), *b = malloc(nc * 3 * sizeof(float));
    float *map = prt__calloc(n * 3, sizeof(float)), *imap = r->indirect ? prt__calloc(n * 3, sizeof(float)) : NULL;
    if (!E || !first || !indirect || !a || !b || !map || (r->indirect && !imap) ) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    /* Local lights (directional ones too: sharp shadows), by shadow rays from each texel. */
    prt_light *local = NULL;
    int nlocal = 0;
    if (!st && prt_lighting_count(l)) {
        if ((st = lights_ready(ctx, t, s))) goto done;
        if (!(local = malloc((size_t)prt_lighting_count(l) * sizeof *local))) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
        for (int i = 0; i < prt_lighting_count(l); ++i) local[nlocal++] = *prt_lighting_light(l, i);
        const prt__mesh texels = {.vertex_count = nc, .positions = s->pos, .normals = s->nrm};
        prt__vertex_lights_add(ctx, s->lights, &texels, local, nlocal, E);
    }
    /* The environment alone (the directional lights are in E already) through the texels' SH. */
    prt_sh_light env;
    memset(&env, 0, sizeof env);
    if (!st && prt_lighting_envmap(l)) {
        prt_lighting *only = NULL;
        st = prt_lighting_copy(l, &only);
        while (!st && prt_lighting_count(only)) st = prt_lighting_remove(only, 0);
        if (!st) st = prt_lighting_sh(only, 3, &env);
        prt_lighting_release(only);
    }
    if (st) goto done;
    const float emission = prt_lighting_emission(l);
    /* first: first-order radiance; a: irradiance / pi, what subsurface scattering takes in. The
     * emissive surfaces light the others directly (their baked irradiance); their own emission
     * is added to what is shown, not bounced again. */
    for (size_t i = 0; i < nc; ++i)
        for (int c = 0; c < 3; ++c) {
            float e = (E[i * 3 + c] + (s->emit_in ? emission * s->emit_in[i * 3 + c] : 0.0f)) / (float)PRT_PI;
            for (int k = 0; k < PRT__OFFSET_ENV_COEFFS; ++k) e += s->env[i * PRT__OFFSET_ENV_COEFFS + k] * env.coeffs[c][k];
            a[i * 3 + c] = e > 0 ? e : 0;
            first[i * 3 + c] = s->albedo[i * 3 + c] * a[i * 3 + c];
        }
    if (d->gpu_finish) {   /* the renderer runs the passes below (render/offset_gl.c) */
        r->gpu_input = prt__calloc(n * 3, sizeof(float));
        if (!r->gpu_input) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
        for (size_t i = 0; i < nc; ++i) {
            memcpy(r->gpu_input + (size_t)s->texel[i] * 3, a + i * 3, 3 * sizeof(float));
            for (int c = 0; c < 3; ++c) b[i * 3 + c] = first[i * 3 + c] + (s->emit ? emission * s->emit[i * 3 + c] : 0.0f);
        }
        spread(s, b, map);
        for (size_t v = 0; v < nv; ++v) sample_map(map, s->width, s->height, t->mesh.uv[v * 2], t->mesh.uv[v * 2 + 1], r->radiance + v * 3);
        r->gpu_emission = emission;
        r->gpu_bounces = bounces;
        r->gpu_component = d->component;
        r->texel_width = s->width;
        r->texel_height = s->height;
        goto done;
    }
    if (s->subsurface) {   /* on translucent texels the dipole replaces albedo x irradiance */
        apply(ctx, s, s->subsurface, a, b);
        for (size_t i = 0; i < nc; ++i)
            if (s->medium[i]) memcpy(first + i * 3, b + i * 3, 3 * sizeof(float));
    }
    /* Inter-reflection: each bounce gathers what the last one sent out. */
    if (s->radiosity && d->component != PRT_COMPONENT_DIRECT) {
        memcpy(a, first, nc * 3 * sizeof(float));
        for (int k = 0; k < bounces; ++k) {
            apply(ctx, s, s->radiosity, a, b);
            for (size_t i = 0; i < nc * 3; ++i) indirect[i] += b[i];
            float *tmp = a; a = b; b = tmp;
        }
    }
    if (s->emit)
        for (size_t i = 0; i < nc * 3; ++i) first[i] += emission * s->emit[i];
    /* The shown map (b): gutters as the GPU path fills them, each texel its source's value. */
    for (size_t i = 0; i < nc; ++i)
        for (int c = 0; c < 3; ++c) {
            const float f = first[i * 3 + c], g = indirect[i * 3 + c];
            b[i * 3 + c] = d->component == PRT_COMPONENT_DIRECT ? f : d->component == PRT_COMPONENT_INDIRECT ? g : f + g;
        }
    spread(s, b, map);
    if (imap) spread(s, indirect, imap);
    /* Per vertex: the light map at the vertex's texture coordinates. */
    for (size_t v = 0; v < nv; ++v) {
        const float u = t->mesh.uv[v * 2], w = t->mesh.uv[v * 2 + 1];
        sample_map(map, s->width, s->height, u, w, r->radiance + v * 3);
        if (r->indirect) sample_map(imap, s->width, s->height, u, w, r->indirect + v * 3);
    }
    r->texels = map;
    r->texel_width = s->width;
    r->texel_height = s->height;
    map = NULL;
done:
    free(local);
    free(E); free(first); free(indirect); free(a); free(b); free(map); free(imap);
    return st;
}
