/* Translucent media for subsurface scattering: Jensen et al. 2001's measured coefficients. */
#include "core/internal.h"
#include "prt/scene.h"

#include <string.h>

static const struct { const char *name; prt_medium m; } presets[] = {
    /* Table 2 of Jensen et al. 2001, per mm: absorption, reduced scattering; eta 1.3. */
    {"skin", {{0.032f, 0.17f, 0.48f}, {0.74f, 0.88f, 1.01f}, 1.3f, 0}},
    {"marble", {{0.0021f, 0.0041f, 0.0071f}, {2.19f, 2.62f, 3.00f}, 1.3f, 0}},
    {"ketchup", {{0.061f, 0.97f, 1.45f}, {0.18f, 0.07f, 0.03f}, 1.3f, 0}},
};

prt_status prt_medium_preset(const char *name, prt_medium *out)
{
    for (size_t i = 0; name && i < sizeof presets / sizeof presets[0]; ++i)
        if (!strcmp(presets[i].name, name)) { *out = presets[i].m; return PRT_OK; }
    return prt__fail(NULL, PRT_ERR_INVALID_ARG, "unknown medium '%s' (skin, marble or ketchup; or give sigma_a, sigma_s and eta)", name ? name : "");
}

prt_status prt_medium_check(const prt_medium *m)
{
    if (m->falloff_mm != 0) {
        if (!(m->falloff_mm > 0 && m->falloff_mm <= 1e6f)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a falloff distance must lie in (0, 1e6] mm (got %g)", m->falloff_mm);
        return PRT_OK;
    }
    for (int c = 0; c < 3; ++c)
        if (!(m->sigma_a[c] > 0 && m->sigma_a[c] <= 1e6f) || !(m->sigma_s[c] >= 0 && m->sigma_s[c] <= 1e6f))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a medium needs absorption in (0, 1e6] and reduced scattering in [0, 1e6] per mm");
    if (!(m->eta >= 1 && m->eta <= 4)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a medium's index of refraction must lie in [1, 4] (got %g)", m->eta);
    return PRT_OK;
}
