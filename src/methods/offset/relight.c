/* Offset transfer maps at run time: the first-order light map (local lights with shadow rays from
 * each texel, the environment through each texel's shadowed SH transfer, emission), subsurface
 * scattering and inter-reflection as modulate-shift-accumulate passes over it (eq. 9), the
 * inter-reflection pass repeated once per bounce on what the last one gave. */
#include "methods/offset/offset.h"

#include "geom/texel_raster.h"


bool prt__offset_set_index(prt__offset_set *s, const int32_t *label)
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
    free(s->xy);
    if (!(s->xy = malloc((size_t)s->covered * 2 * sizeof *s->xy + 1))) return false;
    for (uint32_t k = 0; k < s->covered; ++k) {
        s->xy[k] = (int32_t)(s->texel[k] % (uint32_t)s->width);
        s->xy[s->covered + k] = (int32_t)(s->texel[k] / (uint32_t)s->width);
    }
    return prt__texel_gutter_sources(s->width, s->height, s->index, label, s->source);
}

/* out[i] = sum_k in(texel i + offset k) maps[k][i], over covered texels. An offset landing off
 * the surface reads its gutter's source (s->source): a cell that does hold surface takes the light
 * of the chart's edge rather than nothing - as the paper's lightmap with dilated gutters gives it,
 * and exactly what the GPU path (render/light_map_gl.c) reads. Blocks of texels take the maps one
 * after the other, so that each map streams through memory once and the block's sums stay in
 * cache (texel by texel, every offset would touch a new cache line); each texel still sums its
 * offsets in order, so the result does not depend on the block or thread count. */
#define APPLY_BLOCK 2048

/* One map over texels [0, n) of a block: o (n x 3, the block's sums) += in(source(t + offset)) x
 * m. x, y: the texels' columns and rows; at: their indices into the map (y W + x). Scalar on
 * purpose: eight-wide AVX2 gathers of the sources and their light measured three times slower
 * here (prt_bench_offset, 256^2 and 512^2 with 400 maps) - the loop is bound by those loads. */
static void apply_map(int n, const int32_t *restrict x, const int32_t *restrict y, const uint32_t *restrict at, int ox, int oy, int W, int H,
                      const int32_t *restrict src, const float *restrict in, const float *restrict m, float *restrict o)
{
    const int32_t shift = oy * W + ox;
    for (int i = 0; i < n; ++i) {
        if ((unsigned)(x[i] + ox) >= (unsigned)W || (unsigned)(y[i] + oy) >= (unsigned)H) continue;
        const float *restrict f = in + (size_t)src[(int32_t)at[i] + shift] * 3;
        o[i * 3] += f[0] * m[i * 3];
        o[i * 3 + 1] += f[1] * m[i * 3 + 1];
        o[i * 3 + 2] += f[2] * m[i * 3 + 2];
    }
}

/* in[l]: the light at the pyramid's level l (prt__offset_filter); level: each map's, NULL: 0. */
static void apply(prt_context *ctx, const prt__offset_set *s, const float *maps, const float *const *in, const uint8_t *level, float *restrict out)
{
    const int W = s->width, H = s->height;
    const size_t nc = s->covered, blocks = (nc + APPLY_BLOCK - 1) / APPLY_BLOCK;
#pragma omp parallel for schedule(dynamic, 1) num_threads(prt__threads(ctx))
    for (size_t b = 0; b < blocks; ++b) {
        const size_t i0 = b * APPLY_BLOCK;
        const int n = (int)(i0 + APPLY_BLOCK < nc ? APPLY_BLOCK : nc - i0);
        float *o = out + i0 * 3;
        memset(o, 0, (size_t)n * 3 * sizeof *o);
        for (int k = 0; k < s->count; ++k)
            apply_map(n, s->xy + i0, s->xy + nc + i0, s->texel + i0, s->offsets[k * 2], s->offsets[k * 2 + 1], W, H, s->source, in[level ? level[k] : 0],
                      maps + ((size_t)k * nc + i0) * 3, o);
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

/* Where a texel's shadow rays start: PRT__OFFSET_SHADOW_SAMPLES points of a rotated grid over the
 * texel's square in UV space, each mapped onto the texel's own triangle (barycentrics clamped to
 * it, so no point leaves the surface it lights), with the interpolated normal. A shadow edge then
 * crosses a texel as a fraction of its area instead of a step from lit to dark, and a texel half
 * under an object resting on it is half lit. Texels without a triangle keep their centre. */
static bool shadow_samples(const prt_transfer *t, prt__offset_set *s)
{
    static const float grid[PRT__OFFSET_SHADOW_SAMPLES][2] = {{0.125f, 0.375f}, {0.375f, -0.125f}, {-0.125f, -0.375f}, {-0.375f, 0.125f}};
    const int W = s->width, H = s->height, S = PRT__OFFSET_SHADOW_SAMPLES;
    const size_t n = (size_t)W * H, nc = s->covered;
    const prt__mesh *m = &t->mesh;
    uint32_t *owner = prt__calloc(n, sizeof *owner);
    float *bary = malloc(n * 2 * sizeof *bary);
    free(s->sample_pos);   /* an earlier attempt that failed */
    free(s->sample_nrm);
    s->sample_pos = malloc(nc * S * 3 * sizeof(float));
    s->sample_nrm = malloc(nc * S * 3 * sizeof(float));
    size_t overlap, outside;
    bool ok = owner && bary && s->sample_pos && s->sample_nrm && prt__texel_raster(m, W, H, owner, bary, &overlap, &outside);
    for (size_t i = 0; ok && i < nc; ++i) {
        const uint32_t tri = owner[s->texel[i]];
        const int tx = (int)(s->texel[i] % (uint32_t)W), ty = (int)(s->texel[i] / (uint32_t)W);
        for (int k = 0; k < S; ++k) {
            float *p = s->sample_pos + (i * S + k) * 3, *nr = s->sample_nrm + (i * S + k) * 3;
            memcpy(p, s->pos + i * 3, 3 * sizeof *p);
            memcpy(nr, s->nrm + i * 3, 3 * sizeof *nr);
            if (!tri || tri > m->triangle_count) continue;
            const uint32_t *ix = m->indices + (size_t)(tri - 1) * 3;
            const float *a = m->uv + ix[0] * 2, *b = m->uv + ix[1] * 2, *c = m->uv + ix[2] * 2;
            const double qu = (tx + 0.5 + grid[k][0]) / W, qv = (ty + 0.5 + grid[k][1]) / H;
            const double e1u = b[0] - a[0], e1v = b[1] - a[1], e2u = c[0] - a[0], e2v = c[1] - a[1], det = e1u * e2v - e2u * e1v;
            if (!(fabs(det) > 1e-20)) continue;
            double w1 = ((qu - a[0]) * e2v - e2u * (qv - a[1])) / det, w2 = (e1u * (qv - a[1]) - (qu - a[0]) * e1v) / det, w0 = 1 - w1 - w2;
            w0 = fmax(w0, 0.0); w1 = fmax(w1, 0.0); w2 = fmax(w2, 0.0);
            const double sum = w0 + w1 + w2;
            if (!(sum > 0)) continue;
            w0 /= sum; w1 /= sum; w2 /= sum;
            double len = 0;
            for (int d = 0; d < 3; ++d) {
                p[d] = (float)(w0 * m->positions[ix[0] * 3 + d] + w1 * m->positions[ix[1] * 3 + d] + w2 * m->positions[ix[2] * 3 + d]);
                const double v = w0 * m->normals[ix[0] * 3 + d] + w1 * m->normals[ix[1] * 3 + d] + w2 * m->normals[ix[2] * 3 + d];
                len += v * v;
            }
            len = sqrt(len);
            if (len > 0)
                for (int d = 0; d < 3; ++d) nr[d] = (float)((w0 * m->normals[ix[0] * 3 + d] + w1 * m->normals[ix[1] * 3 + d] + w2 * m->normals[ix[2] * 3 + d]) / len);
        }
    }
    free(owner);
    free(bary);
    return ok;
}

/* Shadow rays from the texels: the mesh in Embree and the texels' ray origins, once. */
static prt_status lights_ready(prt_context *ctx, const prt_transfer *t, prt__offset_set *s)
{
    pthread_mutex_lock(s->lock);
    prt__vertex_lights *c = s->lights;
    prt_status st = PRT_OK;
    if (!c->ready) {
        const size_t np = (size_t)s->covered * PRT__OFFSET_SHADOW_SAMPLES;
        float *o = malloc(np * 3 * sizeof *o + 1);
        st = o && shadow_samples(t, s) ? prt__raycaster_create(ctx, &t->mesh, &c->rc) : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st) {
            for (size_t i = 0; i < np * 3; ++i) o[i] = s->sample_pos[i] + s->sample_nrm[i] * s->ray_offset;
            c->origins = o;
            c->ready = true;
        } else {
            free(o);
        }
    }
    pthread_mutex_unlock(s->lock);
    return st;
}

prt_status prt__offset_shadow_samples(prt_context *ctx, const prt_transfer *t) { return lights_ready(ctx, t, t->state); }

/* The lights the renderer draws per pixel: copies of the first count local lights, the albedo
 * they shade per vertex and each vertex's visibility of each (shadow rays from the vertices). On
 * translucent surfaces the albedo is the dipole's share that leaves within the texel the light
 * entered (its subsurface map at offset (0, 0)): what the map would show as a staircase at a
 * shadow edge is drawn per pixel, and only the light carried between texels stays in the map. */
static prt_status pixel_lights(prt_context *ctx, const prt_transfer *t, const prt__offset_set *s, const prt_light *local, int count, prt_relit *r)
{
    const size_t nv = t->mesh.vertex_count;
    prt_status st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, s->vertex_lights);
    if (st) return st;
    r->pixel_lights = malloc((size_t)count * sizeof(prt_light));
    r->pixel_albedo = malloc(nv * 3 * sizeof(float));
    r->pixel_visibility = malloc((size_t)count * nv * sizeof(float));
    if (!r->pixel_lights || !r->pixel_albedo || !r->pixel_visibility) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(r->pixel_lights, local, (size_t)count * sizeof(prt_light));
    r->pixel_light_count = count;
    memcpy(r->pixel_albedo, t->mesh.albedo, nv * 3 * sizeof(float));
    if (s->subsurface && s->medium)
        for (size_t v = 0; v < nv; ++v) {
            const int x = (int)fminf(fmaxf(t->mesh.uv[v * 2] * (float)s->width, 0.0f), (float)(s->width - 1));
            const int y = (int)fminf(fmaxf(t->mesh.uv[v * 2 + 1] * (float)s->height, 0.0f), (float)(s->height - 1));
            const int32_t c = s->source[(size_t)y * s->width + x];
            if (c >= 0 && s->medium[c]) memcpy(r->pixel_albedo + v * 3, s->subsurface + (size_t)c * 3, 3 * sizeof(float));
        }
    prt__vertex_lights_visibility(ctx, s->vertex_lights, &t->mesh, r->pixel_lights, count, r->pixel_visibility);
    return prt__relit_pixel_materials(ctx, t, NULL, r);
}

prt_status prt__offset_shade(prt_context *ctx, const prt_transfer *t, const prt_relit *r, const float eye[3], float *rgb)
{
    if (!r->pixel_lights) return PRT_OK;
    const prt__offset_set *s = t->state;
    prt_status st = prt__vertex_lights_ready(ctx, &t->mesh, s->ray_offset, s->vertex_lights);
    const prt__vertex_materials mat = {r->pixel_albedo, r->pixel_material, r->pixel_brdfs, r->pixel_brdf_count};
    if (!st) prt__vertex_lights_shade(ctx, s->vertex_lights, &t->mesh, r->pixel_lights, r->pixel_light_count, &mat, eye, rgb);
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
    int lo, hi, def;
    prt_transfer_control_range(t, 0, &lo, &hi, &def);
    const int bounces = d->controls ? d->controls[0] : def;
    if ((bounces < lo || bounces > hi) && s->map_bounces > 1)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range %d..%d: this file's maps hold %d bounces, given by one pass (bake with --map-bounces 1 to bounce at run time)", bounces, lo, hi,
                         s->map_bounces);
    if (bounces < lo || bounces > hi) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bounces %d out of range %d..%d", bounces, lo, hi);
    if (d->brdf) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--brdf does not apply to offset transfer maps (they reflect diffusely)");
    if (d->gpu_finish && (d->per_vertex || d->with_indirect))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "gpu_finish leaves the light map to the renderer: per-vertex light and a separate indirect part need the CPU's");
    const size_t nc = s->covered, n = (size_t)s->width * s->height, nv = t->mesh.vertex_count;
    prt_status st = prt__relit_alloc(ctx, t, r, !d->gpu_finish && (d->with_indirect || d->component == PRT_COMPONENT_INDIRECT));
    if (st) return st;
    float *E = prt__calloc(nc * 3, sizeof(float)), *first = malloc(nc * 3 * sizeof(float)), *indirect = prt__calloc(nc * 3, sizeof(float));
    float *a = malloc(nc * 3 * sizeof(float)), *b = malloc(nc * 3 * sizeof(float));
    float *map = prt__calloc(n * 3, sizeof(float)), *imap = r->indirect ? prt__calloc(n * 3, sizeof(float)) : NULL, *hide = NULL;
    if (!E || !first || !indirect || !a || !b || !map || (r->indirect && !imap) ) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    /* Local lights (directional ones too: sharp shadows), by shadow rays from each texel. */
    prt_light *local = NULL;
    int nlocal = 0;
    if (!st && prt_lighting_count(l)) {
        if ((st = lights_ready(ctx, t, s))) goto done;
        if (!(local = malloc((size_t)prt_lighting_count(l) * sizeof *local))) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
        for (int i = 0; i < prt_lighting_count(l); ++i) local[nlocal++] = *prt_lighting_light(l, i);
        const size_t S = PRT__OFFSET_SHADOW_SAMPLES;
        const prt__mesh points = {.vertex_count = nc * S, .positions = s->sample_pos, .normals = s->sample_nrm};
        float *Es = prt__calloc(nc * S * 3, sizeof *Es);
        if (!Es) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
        prt__vertex_lights_add(ctx, s->lights, &points, local, nlocal, Es);
        for (size_t i = 0; i < nc; ++i)
            for (size_t k = 0; k < S; ++k)
                for (int c = 0; c < 3; ++c) E[i * 3 + c] += Es[(i * S + k) * 3 + c] / (float)S;
        free(Es);
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
     * is added to what is shown, not bounced again. Painted light (prt/paint.h) arrives as the
     * lights' does: reflected, scattered and bounced with it (checked >= 0 by prt_relight). */
    for (size_t i = 0; i < nc; ++i)
        for (int c = 0; c < 3; ++c) {
            float e = (E[i * 3 + c] + (s->emit_in ? emission * s->emit_in[i * 3 + c] : 0.0f)) / (float)PRT_PI;
            for (int k = 0; k < PRT__OFFSET_ENV_COEFFS; ++k) e += s->env[i * PRT__OFFSET_ENV_COEFFS + k] * env.coeffs[c][k];
            a[i * 3 + c] = (e > 0 ? e : 0) + (d->paint ? d->paint[(size_t)s->texel[i] * 3 + c] : 0.0f);
            first[i * 3 + c] = s->albedo[i * 3 + c] * a[i * 3 + c];
        }
    /* Drawn for the screen, the local lights' direct light on opaque surfaces is the renderer's,
     * per pixel with shadow maps: a shadow edge is then as sharp as the screen, not a staircase
     * of texels. The light map keeps it for the bounces and the subsurface scattering, and shows
     * the rest (hide: what it leaves out) - on the CPU here, on the GPU in its final pass. */
    const int pixel = !d->per_vertex && !d->no_pixel_lights && d->component != PRT_COMPONENT_INDIRECT && nlocal <= PRT_MAX_PIXEL_LIGHTS ? nlocal : 0;
    hide = pixel ? prt__calloc(nc * 3, sizeof(float)) : NULL;
    if (pixel && !hide) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
    for (size_t i = 0; pixel && i < nc; ++i) {
        const float *own = s->subsurface && s->medium && s->medium[i] ? s->subsurface + i * 3 : s->albedo + i * 3;   /* see pixel_lights */
        for (int c = 0; c < 3; ++c) hide[i * 3 + c] = own[c] * E[i * 3 + c] / (float)PRT_PI;
    }
    if (pixel && (st = pixel_lights(ctx, t, s, local, pixel, r))) { goto done; }
    if (d->gpu_finish) {   /* the renderer runs the passes below (gpu.c describes them) */
        if ((st = prt__offset_gpu_passes(ctx, t, &r->gpu_passes))) { goto done; }
        r->gpu_input = prt__calloc(n * 3, sizeof(float));
        if (!r->gpu_input) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
        r->gpu_pixel_direct = hide ? prt__calloc(n * 3, sizeof(float)) : NULL;
        if (hide && !r->gpu_pixel_direct) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
        for (size_t i = 0; i < nc; ++i) {
            memcpy(r->gpu_input + (size_t)s->texel[i] * 3, a + i * 3, 3 * sizeof(float));
            if (hide) memcpy(r->gpu_pixel_direct + (size_t)s->texel[i] * 3, hide + i * 3, 3 * sizeof(float));
            for (int c = 0; c < 3; ++c)
                b[i * 3 + c] = fmaxf(first[i * 3 + c] + (s->emit ? emission * s->emit[i * 3 + c] : 0.0f) - (hide ? hide[i * 3 + c] : 0.0f), 0.0f);
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
        const float *in[1] = {a};
        apply(ctx, s, s->subsurface, in, NULL, b);
        for (size_t i = 0; i < nc; ++i)
            if (s->medium[i]) memcpy(first + i * 3, b + i * 3, 3 * sizeof(float));
    }
    /* Inter-reflection: each bounce gathers what the last one sent out. */
    if (s->radiosity && d->component != PRT_COMPONENT_DIRECT) {
        if ((st = prt__offset_filter_ready(ctx, t, s))) goto done;
        const float *in[16];
        float *pyramid = prt__offset_filter_take(s);
        if (!pyramid) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
        memcpy(a, first, nc * 3 * sizeof(float));
        for (int k = 0; k < bounces; ++k) {
            prt__offset_filter(s, a, pyramid, in);
            apply(ctx, s, s->radiosity, in, s->level, b);
            for (size_t i = 0; i < nc * 3; ++i) indirect[i] += b[i];
            float *tmp = a; a = b; b = tmp;
        }
        prt__offset_filter_give(s, pyramid);
        if (s->levels && bounces > 0) {   /* see prt__offset_smooth */
            prt__offset_smooth(ctx, s, indirect, b);
            memcpy(indirect, b, nc * 3 * sizeof(float));
        }
    }
    if (s->emit)
        for (size_t i = 0; i < nc * 3; ++i) first[i] += emission * s->emit[i];
    /* The shown map (b): gutters as the GPU path fills them, each texel its source's value. */
    for (size_t i = 0; i < nc; ++i)
        for (int c = 0; c < 3; ++c) {
            const float f = fmaxf(first[i * 3 + c] - (hide ? hide[i * 3 + c] : 0.0f), 0.0f), g = indirect[i * 3 + c];
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
    free(E); free(first); free(indirect); free(a); free(b); free(map); free(imap); free(hide);
    return st;
}
