/* Height maps for per-texel SH transfer: see height_field.h. */
#include "methods/sh/height_field.h"

#include <math.h>

bool prt__height_field_init(prt__height_field *h, const prt_image *map, float scale)
{
    h->map = map;
    h->scale = scale;
    h->top = 0;
    if (!map || map->width < 1 || map->height < 1 || !map->rgb || !(scale > 0) || !isfinite(scale)) return false;
    for (size_t i = 0; i < (size_t)map->width * map->height; ++i) {
        const float x = map->rgb[i * 3];
        if (!isfinite(x)) return false;
        if (x * scale > h->top) h->top = x * scale;
    }
    return true;
}

float prt__height_at(const prt__height_field *h, float u, float v)
{
    const prt_image *img = h->map;
    const float x = (u - floorf(u)) * img->width - 0.5f, y = (1.0f - (v - floorf(v))) * img->height - 0.5f;   /* row 0 is the top */
    const int x0 = (int)floorf(x), y0 = (int)floorf(y);
    const float fx = x - x0, fy = y - y0;
    float sum = 0;
    for (int k = 0; k < 4; ++k) {
        int xi = x0 + (k & 1), yi = y0 + (k >> 1);
        xi = ((xi % img->width) + img->width) % img->width;
        yi = ((yi % img->height) + img->height) % img->height;
        sum += ((k & 1) ? fx : 1 - fx) * ((k >> 1) ? fy : 1 - fy) * img->rgb[((size_t)yi * img->width + xi) * 3];
    }
    return sum * h->scale;
}

void prt__height_normal(const prt__height_field *h, const prt__bump_frame *f, float out[3])
{
    const float du = 1.0f / (float)h->map->width, dv = 1.0f / (float)h->map->height;
    /* Slopes in world units per world unit along t and b. */
    const float su = (prt__height_at(h, f->u + du, f->v) - prt__height_at(h, f->u - du, f->v)) / (2 * du * f->len_u);
    const float sv = (prt__height_at(h, f->u, f->v + dv) - prt__height_at(h, f->u, f->v - dv)) / (2 * dv * f->len_v);
    float len = 0;
    for (int c = 0; c < 3; ++c) { out[c] = f->n[c] - su * f->t[c] - sv * f->b[c]; len += out[c] * out[c]; }
    len = sqrtf(len);
    for (int c = 0; c < 3; ++c) out[c] /= len;
}

bool prt__height_blocks(const prt__height_field *h, const prt__bump_frame *f, const float d[3])
{
    const float dt = d[0] * f->t[0] + d[1] * f->t[1] + d[2] * f->t[2];
    const float db = d[0] * f->b[0] + d[1] * f->b[1] + d[2] * f->b[2];
    const float dn = d[0] * f->n[0] + d[1] * f->n[1] + d[2] * f->n[2];
    if (dn <= 0) return true;   /* into the surface the bumps stand on */
    const float h0 = prt__height_at(h, f->u, f->v), end = (h->top - h0) / dn;   /* beyond it the ray is above every bump */
    const float across = sqrtf(dt * dt + db * db);
    if (!(end > 0) || !(across > 0)) return false;
    const float pixel = fminf(f->len_u / (float)h->map->width, f->len_v / (float)h->map->height);
    const int most = 4 * (h->map->width > h->map->height ? h->map->width : h->map->height);
    float step = 0.5f * pixel / across;
    if (end / step > (float)most) step = end / (float)most;
    const float eps = 1e-4f * h->top, gu = dt / f->len_u, gv = db / f->len_v;
    for (float s = step; s < end; s += step)
        if (prt__height_at(h, f->u + s * gu, f->v + s * gv) > h0 + s * dn + eps) return true;
    return false;
}
