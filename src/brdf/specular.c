/* Specular surfaces: perfect mirror reflection and Fresnel-weighted dielectric reflection and
 * refraction. */
#include "brdf/specular.h"

#include <string.h>

prt_status prt_specular_check(const prt_specular *s)
{
    if (!s) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "no specular material");
    switch (s->type) {
    case PRT_SPECULAR_NONE: return PRT_OK;
    case PRT_SPECULAR_MIRROR:
        if (!(s->reflectance >= 0 && s->reflectance <= 1)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a mirror's reflectance must lie in [0, 1] (got %g)", s->reflectance);
        return PRT_OK;
    case PRT_SPECULAR_GLASS:
        if (!(s->ior >= 1 && s->ior <= 4)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a glass's index of refraction must lie in [1, 4] (got %g)", s->ior);
        return PRT_OK;
    }
    return prt__fail(NULL, PRT_ERR_INVALID_ARG, "unknown specular type %d (mirror or glass)", (int)s->type);
}

double prt__fresnel_dielectric(double cos_i, double eta)
{
    const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return 1.0;
    const double cos_t = sqrt(1.0 - sin2_t);
    const double rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t), rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

static void reflect(const float d[3], const float n[3], float cos_i, float out[3])
{
    for (int c = 0; c < 3; ++c) out[c] = d[c] + 2.0f * cos_i * n[c];
}

/* Refraction of d through the boundary with normal n (facing d's side), eta = n1 / n2, when no
 * total internal reflection. */
static bool refract(const float d[3], const float n[3], float cos_i, float eta, float out[3])
{
    const float sin2_t = eta * eta * (1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f) return false;
    const float cos_t = sqrtf(1.0f - sin2_t);
    for (int c = 0; c < 3; ++c) out[c] = eta * d[c] + (eta * cos_i - cos_t) * n[c];
    return prt__v3_normalize(out);
}

int prt__specular_scatter(const prt_specular *s, const float d[3], const float ng[3], const float ns[3], double u, float out[3], float *weight)
{
    const bool front = prt__v3_dot(d, ng) < 0.0f;
    if (s->type == PRT_SPECULAR_MIRROR && !front) return 0;
    /* Normals on the side the ray comes from; the shading normal bends the turn (a tessellated
     * sphere focuses like a smooth one) unless it would send the ray through the wrong side. */
    float g[3], n[3];
    for (int c = 0; c < 3; ++c) { g[c] = front ? ng[c] : -ng[c]; n[c] = front ? ns[c] : -ns[c]; }
    for (int attempt = 0; attempt < 2; ++attempt) {
        if (attempt) memcpy(n, g, sizeof n);
        const float cos_i = -prt__v3_dot(d, n);
        if (!(cos_i > 0.0f)) continue;
        bool reflected = true;
        if (s->type == PRT_SPECULAR_MIRROR) {
            reflect(d, n, cos_i, out);
            *weight = s->reflectance;
        } else {
            const float eta = front ? 1.0f / s->ior : s->ior;
            *weight = 1.0f;
            reflected = u < prt__fresnel_dielectric(cos_i, eta) || !refract(d, n, cos_i, eta, out);
            if (reflected) reflect(d, n, cos_i, out);
        }
        if (!prt__v3_normalize(out)) continue;
        const float side = prt__v3_dot(out, g);
        if (reflected && side > 0.0f) return front ? 1 : -1;
        if (!reflected && side < 0.0f) return front ? -1 : 1;
    }
    return 0;
}

prt_status prt__specular_table(const prt_context *ctx, const prt_scene *scene, const prt__mesh *m, prt_specular **out)
{
    *out = NULL;
    if (!scene || !scene->specular_count || !m->surface || !m->surface_count) return PRT_OK;
    prt_specular *t = prt__calloc((size_t)m->surface_count + 1, sizeof *t);
    if (!t) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    int n = 0;
    for (int k = 0; k < m->surface_count; ++k) n += prt_scene_specular(scene, m->surface_names[k], &t[k + 1]);
    if (!n) { free(t); return PRT_OK; }
    *out = t;
    return PRT_OK;
}
