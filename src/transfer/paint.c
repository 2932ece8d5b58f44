/* First-order light painted onto the surface (prt/paint.h): the checks every relight of a
 * painting passes, the painter (picking a surface point with a ray, brush dabs over the texels
 * whose surface points lie near it) and paintings as images. The method supplies its light map's
 * layout (prt_method.paint_layout); nothing here names a method. */
#include "transfer/method.h"

#include "geom/raycast.h"
#include "prt/paint.h"

int prt_method_paintable(const prt_method *m) { return m && m->paint_layout; }

/* The methods that take a painting, comma separated. */
static void paintable_methods(char *buf, size_t size)
{
    size_t at = 0;
    buf[0] = 0;
    for (int i = 0; i < prt_method_count(); ++i) {
        const prt_method *m = prt_method_at(i);
        if (m->paint_layout && at < size) at += (size_t)snprintf(buf + at, size - at, "%s%s", at ? ", " : "", m->name);
    }
}

static prt_status refuse(const prt_context *ctx, const prt_transfer *t)
{
    char those[128];
    paintable_methods(those, sizeof those);
    return prt__fail(ctx, PRT_ERR_INVALID_ARG,
                     "cannot paint light on a file of the %s method (%s): painted light enters a first-order light map over texels, "
                     "which it does not relight from; bake with --method %s",
                     t->method->name, t->method->title, those[0] ? those : "(none)");
}

prt_status prt_paint_size(const prt_transfer *t, int *width, int *height)
{
    if (!t || !width || !height) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_paint_size: transfer, width and height are required");
    if (!t->method->paint_layout) return refuse(NULL, t);
    prt__paint_layout lay;
    t->method->paint_layout(t, &lay);
    *width = lay.width;
    *height = lay.height;
    return PRT_OK;
}

prt_status prt__paint_check(const prt_context *ctx, const prt_transfer *t, const prt_relight_desc *d)
{
    if (!d->paint) return PRT_OK;
    if (!t->method->paint_layout) return refuse(ctx, t);
    prt__paint_layout lay;
    t->method->paint_layout(t, &lay);
    if (d->paint_width != lay.width || d->paint_height != lay.height)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the painting is %dx%d texels, the file's light map %dx%d", d->paint_width, d->paint_height, lay.width,
                         lay.height);
    for (uint32_t i = 0; i < lay.covered; ++i)
        for (int c = 0; c < 3; ++c) {
            const float v = d->paint[(size_t)lay.texel[i] * 3 + c];
            if (!(v >= 0.0f) || !isfinite(v))
                return prt__fail(ctx, PRT_ERR_INVALID_ARG, "painted light must be finite and >= 0 (texel %u, %u: %g)", lay.texel[i] % (uint32_t)lay.width,
                                 lay.texel[i] / (uint32_t)lay.width, (double)v);
        }
    return PRT_OK;
}

struct prt_painter {
    const prt_transfer *t;
    prt__paint_layout lay;
    prt__raycaster rc;
};

prt_status prt_painter_create(prt_context *ctx, const prt_transfer *t, prt_painter **out)
{
    if (!t || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_painter_create: transfer and out are required");
    *out = NULL;
    if (!t->method->paint_layout) return refuse(ctx, t);
    prt_painter *p = prt__calloc(1, sizeof *p);
    if (!p) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    p->t = t;
    t->method->paint_layout(t, &p->lay);
    prt_status st = prt__raycaster_create(ctx, &t->mesh, &p->rc);
    if (st) { free(p); return st; }
    *out = p;
    return PRT_OK;
}

void prt_painter_release(prt_painter *p)
{
    if (!p) return;
    prt__raycaster_release(&p->rc);
    free(p);
}

void prt_painter_size(const prt_painter *p, int *width, int *height)
{
    *width = p ? p->lay.width : 0;
    *height = p ? p->lay.height : 0;
}

int prt_painter_pick(const prt_painter *p, const float origin[3], const float dir[3], float position[3], float normal[3])
{
    if (!p || !origin || !dir) return 0;
    float d[3] = {dir[0], dir[1], dir[2]};
    const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0) || !isfinite(len)) return 0;
    for (int k = 0; k < 3; ++k) d[k] /= len;
    prt__ray_hit h;
    if (!prt__raycaster_hit(&p->rc, origin, d, &h) || h.prim >= p->t->mesh.triangle_count) return 0;
    const prt__mesh *m = &p->t->mesh;
    const uint32_t *ix = m->indices + (size_t)h.prim * 3;
    const float w[3] = {1 - h.u - h.v, h.u, h.v};
    float n[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) n[k] += w[j] * m->normals[ix[j] * 3 + k];
    float nl = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(nl > 0)) { memcpy(n, h.ng, sizeof n); nl = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]); }
    for (int k = 0; k < 3; ++k) {
        if (position) position[k] = origin[k] + d[k] * h.t;
        if (normal) normal[k] = nl > 0 ? n[k] / nl : 0.0f;
    }
    return 1;
}

prt_status prt_painter_dab(const prt_painter *p, const prt_paint_brush *b, float *map, int *changed)
{
    if (changed) *changed = 0;
    if (!p || !b || !map) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_painter_dab: painter, brush and map are required");
    bool ok = b->radius > 0 && isfinite(b->radius) && b->opacity >= 0 && b->opacity <= 1;
    for (int k = 0; k < 3; ++k) ok = ok && isfinite(b->centre[k]) && isfinite(b->normal[k]) && b->rgb[k] >= 0 && isfinite(b->rgb[k]);
    if (!ok) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a brush needs a finite centre and normal, a radius > 0, light >= 0 and an opacity in [0, 1]");
    const float r2 = b->radius * b->radius, inner = 0.75f * b->radius, opacity = b->opacity > 0 ? b->opacity : 1.0f;
    const bool facing = b->normal[0] != 0 || b->normal[1] != 0 || b->normal[2] != 0;
    int n = 0;
    /* Every covered texel, brute force: a 512^2 map is a quarter of a millisecond a dab, well
     * under the relight each dab asks for. */
    for (uint32_t i = 0; i < p->lay.covered; ++i) {
        const float *x = p->lay.pos + (size_t)i * 3, *nr = p->lay.nrm + (size_t)i * 3;
        const float dx = x[0] - b->centre[0], dy = x[1] - b->centre[1], dz = x[2] - b->centre[2], d2 = dx * dx + dy * dy + dz * dz;
        if (!(d2 <= r2)) continue;
        /* Corners (a floor meeting a wall, 90 degrees) take paint; backs of thin walls do not. */
        if (facing && nr[0] * b->normal[0] + nr[1] * b->normal[1] + nr[2] * b->normal[2] < -0.05f) continue;
        const float dist = sqrtf(d2), edge = dist <= inner ? 1.0f : (b->radius - dist) / (b->radius - inner);
        const float w = opacity * (edge > 0 ? edge : 0);
        float *c = map + (size_t)p->lay.texel[i] * 3;
        for (int k = 0; k < 3; ++k) c[k] += (b->rgb[k] - c[k]) * w;
        n++;
    }
    if (changed) *changed = n;
    return PRT_OK;
}

prt_status prt_paint_save(const char *path, const float *map, int width, int height)
{
    if (!path || !map || width < 1 || height < 1) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_paint_save: a path and a map are required");
    prt_image img = {width, height, malloc((size_t)width * height * 3 * sizeof(float))};
    if (!img.rgb) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    for (int y = 0; y < height; ++y)   /* texel row 0 is v near 0: the image's bottom */
        memcpy(img.rgb + (size_t)(height - 1 - y) * width * 3, map + (size_t)y * width * 3, (size_t)width * 3 * sizeof(float));
    prt_status st = prt_image_save(path, &img, NULL);
    free(img.rgb);
    return st;
}

prt_status prt_paint_load(const prt_transfer *t, const char *path, float **out)
{
    if (!t || !path || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_paint_load: transfer, path and out are required");
    *out = NULL;
    int w, h;
    prt_status st = prt_paint_size(t, &w, &h);
    if (st) return st;
    prt_image img;
    if ((st = prt_image_load(path, &img))) return prt__fail(NULL, st, "painting '%s': %s", path, prt_last_error());
    if (img.width != w || img.height != h) {
        prt_image_free(&img);
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "painting '%s' is %dx%d, the file's light map %dx%d", path, img.width, img.height, w, h);
    }
    float *map = malloc((size_t)w * h * 3 * sizeof(float));
    if (!map) { prt_image_free(&img); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (int y = 0; y < h; ++y) memcpy(map + (size_t)y * w * 3, img.rgb + (size_t)(h - 1 - y) * w * 3, (size_t)w * 3 * sizeof(float));
    prt_image_free(&img);
    for (size_t i = 0; i < (size_t)w * h * 3; ++i)
        if (!(map[i] >= 0.0f) || !isfinite(map[i])) { free(map); return prt__fail(NULL, PRT_ERR_FORMAT, "painting '%s' holds negative or non-finite light", path); }
    *out = map;
    return PRT_OK;
}
