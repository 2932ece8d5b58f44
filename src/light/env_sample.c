#include "light/env_sample.h"

#include <string.h>

static void to_map(const prt__env_sampler *s, const float d[3], float m[3])
{
    /* map = rot^T world */
    for (int i = 0; i < 3; ++i) m[i] = s->rot[i] * d[0] + s->rot[3 + i] * d[1] + s->rot[6 + i] * d[2];
}

prt_status prt__env_sampler_init(prt__env_sampler *s, const prt_envmap *env, const double rot[9], float scale)
{
    memset(s, 0, sizeof *s);
    s->env = env;
    s->scale = scale;
    for (int i = 0; i < 9; ++i) s->rot[i] = rot ? (float)rot[i] : (i % 4 == 0 ? 1.0f : 0.0f);
    const int w = env->img.width, h = env->img.height;
    s->n = (size_t)w * h;
    s->cdf = malloc(s->n * sizeof(double));
    if (!s->cdf) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory for the environment sampler");
    double acc = 0.0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double dir[3], jac;
            size_t i = (size_t)y * w + x;
            if (prt__env_dir_at(env, x + 0.5, y + 0.5, dir, &jac)) {
                const float *p = env->img.rgb + i * 3;
                acc += (p[0] + p[1] + p[2]) / 3.0 * jac;
            }
            s->cdf[i] = acc;
        }
    if (!(acc > 0)) {
        /* A black environment: sample uniformly over the covered pixels so pdfs stay finite. */
        acc = 0;
        for (size_t i = 0; i < s->n; ++i) s->cdf[i] = acc += 1.0;
    }
    for (size_t i = 0; i < s->n; ++i) s->cdf[i] /= acc;
    s->cdf[s->n - 1] = 1.0;
    return PRT_OK;
}

void prt__env_sampler_free(prt__env_sampler *s)
{
    free(s->cdf);
    memset(s, 0, sizeof *s);
}

void prt__env_radiance(const prt__env_sampler *s, const float d[3], float rgb[3])
{
    float m[3];
    to_map(s, d, m);
    const float *p = s->env->img.rgb + prt__env_pixel_index(s->env, m) * 3;
    for (int c = 0; c < 3; ++c) rgb[c] = p[c] * s->scale;
}

static double pixel_prob(const prt__env_sampler *s, size_t i) { return s->cdf[i] - (i ? s->cdf[i - 1] : 0.0); }

float prt__env_sample(const prt__env_sampler *s, double u1, double u2, double u3, float d[3], float rgb[3])
{
    size_t lo = 0, hi = s->n - 1;   /* first pixel whose cdf exceeds u1 */
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (s->cdf[mid] > u1) hi = mid; else lo = mid + 1;
    }
    const int w = s->env->img.width;
    double dir[3], jac;
    if (!prt__env_dir_at(s->env, (double)(lo % (size_t)w) + u2, (double)(lo / (size_t)w) + u3, dir, &jac) || !(jac > 0)) return 0.0f;
    float m[3] = {(float)dir[0], (float)dir[1], (float)dir[2]};
    for (int i = 0; i < 3; ++i) d[i] = s->rot[i * 3] * m[0] + s->rot[i * 3 + 1] * m[1] + s->rot[i * 3 + 2] * m[2];
    /* The direction may round into a neighbouring pixel: evaluate both from the direction. */
    prt__env_radiance(s, d, rgb);
    return prt__env_pdf(s, d);
}

float prt__env_pdf(const prt__env_sampler *s, const float d[3])
{
    float m[3], fx, fy;
    to_map(s, d, m);
    prt__env_pixel_of(s->env, m, &fx, &fy);
    size_t i = prt__env_pixel_index(s->env, m);
    double dir[3], jac;
    if (!prt__env_dir_at(s->env, fx, fy, dir, &jac) || !(jac > 0)) return 0.0f;
    return (float)(pixel_prob(s, i) / jac);
}
