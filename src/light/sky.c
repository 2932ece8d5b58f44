/* A procedural sky for the demo and for tests: a gradient dome, a darker ground and a sun disc,
 * rendered into a lat-long map so that it goes through the same projection as any probe. */
#include "core/internal.h"
#include "prt/lighting.h"

#include <string.h>

static bool all_zero(const float *v) { return v[0] == 0 && v[1] == 0 && v[2] == 0; }

prt_status prt_sky_create(const prt_sky_desc *desc, prt_envmap **out)
{
    prt_sky_desc d = desc ? *desc : (prt_sky_desc){0};
    *out = NULL;
    if (all_zero(d.sun_dir)) { d.sun_dir[0] = 0.4f; d.sun_dir[1] = 0.8f; d.sun_dir[2] = 0.3f; }
    if (all_zero(d.sun_radiance)) { d.sun_radiance[0] = 1000; d.sun_radiance[1] = 950; d.sun_radiance[2] = 850; }
    if (d.sun_angle_deg == 0) d.sun_angle_deg = 4.0f;
    if (all_zero(d.zenith)) { d.zenith[0] = 0.35f; d.zenith[1] = 0.5f; d.zenith[2] = 0.9f; }
    if (all_zero(d.horizon)) { d.horizon[0] = 0.9f; d.horizon[1] = 0.95f; d.horizon[2] = 1.0f; }
    if (all_zero(d.ground)) { d.ground[0] = 0.25f; d.ground[1] = 0.22f; d.ground[2] = 0.2f; }
    if (d.width == 0) d.width = 512;
    if (d.width < 8 || d.width > 16384 || d.width % 2)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "sky width must be even and in 8..16384 (got %d)", d.width);
    if (!prt__v3_normalize(d.sun_dir)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "sun direction must be non-zero");
    if (!(d.sun_angle_deg > 0 && d.sun_angle_deg < 90))
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "sun angle must be in (0, 90) degrees");

    prt_image img = {d.width, d.width / 2, NULL};
    img.rgb = prt__calloc((size_t)img.width * img.height * 3, sizeof(float));
    if (!img.rgb) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    const float cos_sun = cosf(0.5f * d.sun_angle_deg * (float)PRT_PI / 180.0f);
    const int ss = 4;   /* supersampling keeps the sun disc's energy independent of pixel size */
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            float acc[3] = {0, 0, 0};
            for (int sy = 0; sy < ss; ++sy)
                for (int sx = 0; sx < ss; ++sx) {
                    float th = (float)PRT_PI * (y + (sy + 0.5f) / ss) / img.height;
                    float phi = (float)(2 * PRT_PI) * ((x + (sx + 0.5f) / ss) / img.width - 0.5f);
                    float dir[3] = {sinf(th) * sinf(phi), cosf(th), -sinf(th) * cosf(phi)};
                    float c[3];
                    if (dir[1] >= 0) {
                        float t = sqrtf(dir[1]);
                        for (int k = 0; k < 3; ++k) c[k] = d.horizon[k] + (d.zenith[k] - d.horizon[k]) * t;
                    } else {
                        memcpy(c, d.ground, sizeof c);
                    }
                    if (prt__v3_dot(dir, d.sun_dir) >= cos_sun) memcpy(c, d.sun_radiance, sizeof c);
                    for (int k = 0; k < 3; ++k) acc[k] += c[k];
                }
            for (int k = 0; k < 3; ++k) img.rgb[((size_t)y * img.width + x) * 3 + k] = acc[k] / (ss * ss);
        }
    prt_status st = prt_envmap_from_image(&img, PRT_ENV_LATLONG, out);
    prt_image_free(&img);
    return st;
}
