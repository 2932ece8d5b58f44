/* Operations on SH lighting vectors: rotation, evaluation, band-limited images. */
#include "core/internal.h"
#include "prt/lighting.h"
#include "light/envmap_internal.h"

#include <string.h>

prt_status prt_sh_light_rotate(prt_sh_light *light, const double rot[9])
{
    prt_sh_rotation *r;
    prt_status st = prt_sh_rotation_create(light->order, rot, &r);
    if (st) return st;
    float in[3 * PRT_SH_MAX_COEFFS], out[3 * PRT_SH_MAX_COEFFS];
    const int n = light->order * light->order;
    for (int c = 0; c < 3; ++c) memcpy(in + c * n, light->coeffs[c], n * sizeof(float));
    prt_sh_rotation_apply(r, 3, in, out);
    for (int c = 0; c < 3; ++c) memcpy(light->coeffs[c], out + c * n, n * sizeof(float));
    prt_sh_rotation_release(r);
    return PRT_OK;
}

void prt_sh_light_scale(prt_sh_light *light, float s)
{
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < light->order * light->order; ++i) light->coeffs[c][i] *= s;
}

void prt_sh_light_eval(const prt_sh_light *light, const float dir[3], float rgb[3])
{
    float y[PRT_SH_MAX_COEFFS];
    prt_sh_eval_f(light->order, dir, y);
    for (int c = 0; c < 3; ++c) {
        float s = 0;
        for (int i = 0; i < light->order * light->order; ++i) s += light->coeffs[c][i] * y[i];
        rgb[c] = s;
    }
}

prt_status prt_sh_light_to_image(const prt_sh_light *light, int width, int irradiance, prt_image *out)
{
    memset(out, 0, sizeof *out);
    if (width < 2 || width > 16384 || width % 2)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "image width must be even and in 2..16384 (got %d)", width);
    if (light->order < 1 || light->order > PRT_SH_MAX_ORDER)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "SH order %d out of range", light->order);
    prt_sh_light l = *light;
    if (irradiance) {
        /* E(n) / pi = exit radiance of a white Lambertian surface facing n. */
        double zh[PRT_SH_MAX_ORDER];
        prt_sh_clamped_cosine_zh(l.order, zh);
        for (int i = 0; i < l.order; ++i) zh[i] /= PRT_PI;
        /* Channels are PRT_SH_MAX_COEFFS apart, not order^2: convolve each alone. */
        for (int c = 0; c < 3; ++c) prt_sh_convolve_zh(l.order, zh, 1, l.coeffs[c]);
    }
    out->width = width;
    out->height = width / 2;
    out->rgb = prt__calloc((size_t)width * out->height * 3, sizeof(float));
    if (!out->rgb) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    for (int y = 0; y < out->height; ++y)
        for (int x = 0; x < width; ++x) {
            float th = (float)PRT_PI * (y + 0.5f) / out->height, phi = (float)(2 * PRT_PI) * ((x + 0.5f) / width - 0.5f);
            float dir[3] = {sinf(th) * sinf(phi), cosf(th), -sinf(th) * cosf(phi)};
            prt_sh_light_eval(&l, dir, out->rgb + ((size_t)y * width + x) * 3);
        }
    return PRT_OK;
}

/* The environment's projection (cached with the map), rotated and scaled, plus each directional
 * light as a delta, E y_i(d). */
prt_status prt_lighting_sh(const prt_lighting *l, int order, prt_sh_light *out)
{
    if (!l || !out || order < 1 || order > PRT_SH_MAX_ORDER) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_lighting_sh: lighting, out and order 1..%d are required", PRT_SH_MAX_ORDER);
    memset(out, 0, sizeof *out);
    out->order = order;
    const prt_envmap *env = prt_lighting_envmap(l);
    prt_status st = PRT_OK;
    if (env) {
        if ((st = prt__envmap_project_sh_cached(env, order, out))) return st;
        double rot[9];
        prt_lighting_rotation(l, rot);
        if (!(rot[0] == 1 && rot[4] == 1 && rot[8] == 1) && (st = prt_sh_light_rotate(out, rot))) return st;
        prt_sh_light_scale(out, prt_lighting_intensity(l));
    }
    for (int i = 0; i < prt_lighting_count(l); ++i) {
        const prt_light *li = prt_lighting_light(l, i);
        if (li->type != PRT_LIGHT_DIRECTIONAL) continue;
        float y[PRT_SH_MAX_COEFFS];
        prt_sh_eval_f(order, li->direction, y);
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < order * order; ++k) out->coeffs[c][k] += li->irradiance[c] * y[k];
    }
    return PRT_OK;
}
