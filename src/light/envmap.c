/* Environment maps: direction <-> pixel for each layout, per-pixel solid angles, lookup and
 * projection onto SH. */
#include "light/envmap_internal.h"

#include <string.h>

prt_status prt_envmap_from_image(prt_image *img, prt_env_layout layout, prt_envmap **out)
{
    *out = NULL;
    if (!img || !img->rgb) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "environment: no image");
    int w = img->width, h = img->height;
    if (layout == PRT_ENV_AUTO) {
        if (w == 2 * h) layout = PRT_ENV_LATLONG;
        else if (w == h) layout = PRT_ENV_ANGULAR;
        else if (w * 4 == h * 3) layout = PRT_ENV_VCROSS;
        else return prt__fail(NULL, PRT_ERR_FORMAT,
                              "environment image is %dx%d: cannot tell its layout (2:1 lat-long, 1:1 angular, 3:4 vertical cross); name one", w, h);
    }
    if ((layout == PRT_ENV_LATLONG && w < 2) || (layout == PRT_ENV_VCROSS && (w % 3 || h != w / 3 * 4)) || layout > PRT_ENV_VCROSS)
        return prt__fail(NULL, PRT_ERR_FORMAT, "environment image %dx%d does not fit the requested layout", w, h);
    for (size_t i = 0; i < (size_t)w * h * 3; ++i) {
        if (!isfinite(img->rgb[i]) || img->rgb[i] < 0.0f)
            return prt__fail(NULL, PRT_ERR_FORMAT, "environment pixel %zu is negative or not finite", i / 3);
        /* Projections and relighting sum millions of these times solid angles and basis values:
         * beyond this they overflow to infinity instead of giving an answer. */
        if (img->rgb[i] > PRT__MAX_RADIANCE)
            return prt__fail(NULL, PRT_ERR_FORMAT, "environment pixel %zu is too bright (%g; at most %g, or sums overflow)", i / 3, (double)img->rgb[i],
                             (double)PRT__MAX_RADIANCE);
    }
    prt_envmap *e = prt__calloc(1, sizeof *e);
    if (!e) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    e->img = *img;
    e->layout = layout;
    memset(img, 0, sizeof *img);
    *out = e;
    return PRT_OK;
}

prt_status prt_envmap_load(const char *path, prt_env_layout layout, prt_envmap **out)
{
    prt_image img;
    *out = NULL;
    prt_status st = prt_image_load(path, &img);
    if (st) return st;
    st = prt_envmap_from_image(&img, layout, out);
    if (st) {
        char msg[900];
        snprintf(msg, sizeof msg, "%s", prt_last_error());
        prt_image_free(&img);
        return prt__fail(NULL, st, "'%s': %s", path, msg);
    }
    return PRT_OK;
}

void prt_envmap_release(prt_envmap *e)
{
    if (!e) return;
    prt_image_free(&e->img);
    free(e->cube_cache);
    for (int i = 0; i <= PRT_SH_MAX_ORDER; ++i) free(e->sh_cache[i]);
    free(e);
}

prt_env_layout prt_envmap_layout(const prt_envmap *e) { return e->layout; }
const prt_image *prt_envmap_image(const prt_envmap *e) { return &e->img; }

/* Vertical-cross faces: cell (column, row) and the map from face coordinates (fu right, fv down,
 * both in [-1, 1]) to a direction: dir = axis + fu * right + fv * down. */
typedef struct cross_face { int col, row; float axis[3], right[3], down[3]; } cross_face;
static const cross_face cross_faces[6] = {
    {1, 0, {0, 1, 0}, {1, 0, 0}, {0, 0, -1}},    /* +y */
    {0, 1, {-1, 0, 0}, {0, 0, -1}, {0, -1, 0}},  /* -x */
    {1, 1, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}},   /* -z, the view direction */
    {2, 1, {1, 0, 0}, {0, 0, 1}, {0, -1, 0}},    /* +x */
    {1, 2, {0, -1, 0}, {1, 0, 0}, {0, 0, 1}},    /* -y */
    {1, 3, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}},     /* +z, stored upside down */
};

bool prt__env_dir_at(const prt_envmap *e, double fx, double fy, double dir[3], double *jac)
{
    const int w = e->img.width, h = e->img.height;
    if (e->layout == PRT_ENV_LATLONG) {
        double th = PRT_PI * fy / h, phi = 2.0 * PRT_PI * (fx / w - 0.5);
        dir[0] = sin(th) * sin(phi); dir[1] = cos(th); dir[2] = -sin(th) * cos(phi);
        *jac = (2.0 * PRT_PI / w) * (PRT_PI / h) * sin(th);
        return true;
    }
    if (e->layout == PRT_ENV_ANGULAR) {
        double a = 2.0 * fx / w - 1.0, b = 1.0 - 2.0 * fy / h, r = sqrt(a * a + b * b);
        if (r >= 1.0) return false;
        double th = PRT_PI * r, s = r > 1e-12 ? sin(th) / r : PRT_PI;
        dir[0] = a * s; dir[1] = b * s; dir[2] = -cos(th);
        *jac = PRT_PI * s * 4.0 / ((double)w * h);   /* dw = pi sin(pi r) / r dA */
        return true;
    }
    int size = w / 3, col = (int)floor(fx / size), row = (int)floor(fy / size);
    for (int f = 0; f < 6; ++f) {
        const cross_face *cf = &cross_faces[f];
        if (cf->col != col || cf->row != row) continue;
        double fu = 2.0 * (fx - col * size) / size - 1.0, fv = 2.0 * (fy - row * size) / size - 1.0;
        double len2 = 1.0 + fu * fu + fv * fv, len = sqrt(len2);
        for (int c = 0; c < 3; ++c) dir[c] = (cf->axis[c] + fu * cf->right[c] + fv * cf->down[c]) / len;
        *jac = 4.0 / ((double)size * size) / (len2 * len);
        return true;
    }
    return false;
}

/* Direction and solid angle of the pixel centre at (x, y); returns false outside the map. */
static bool pixel_dir(const prt_envmap *e, int x, int y, double dir[3], double *solid_angle)
{
    if (!prt__env_dir_at(e, x + 0.5, y + 0.5, dir, solid_angle)) return false;
    if (e->layout == PRT_ENV_LATLONG) {   /* exact: the pixel's band of the sphere */
        const int w = e->img.width, h = e->img.height;
        *solid_angle = 2.0 * PRT_PI / w * (cos(PRT_PI * y / h) - cos(PRT_PI * (y + 1) / h));
    }
    return true;
}

/* Continuous image coordinates (pixels) for a direction. */
void prt__env_pixel_of(const prt_envmap *e, const float d[3], float *px, float *py)
{
    const int w = e->img.width, h = e->img.height;
    if (e->layout == PRT_ENV_LATLONG) {
        float th = acosf(fminf(fmaxf(d[1], -1.0f), 1.0f)), phi = atan2f(d[0], -d[2]);
        *px = (phi / (float)(2 * PRT_PI) + 0.5f) * w;
        *py = th / (float)PRT_PI * h;
    } else if (e->layout == PRT_ENV_ANGULAR) {
        float r = acosf(fminf(fmaxf(-d[2], -1.0f), 1.0f)) / (float)PRT_PI, s = sqrtf(d[0] * d[0] + d[1] * d[1]);
        float a = s > 1e-12f ? d[0] / s * r : 0.0f, b = s > 1e-12f ? d[1] / s * r : 0.0f;
        *px = (a + 1.0f) * 0.5f * w;
        *py = (1.0f - b) * 0.5f * h;
    } else {
        int size = w / 3, best = 0;
        float bestdot = -2.0f;
        for (int f = 0; f < 6; ++f) {
            float dd = prt__v3_dot(d, cross_faces[f].axis);
            if (dd > bestdot) { bestdot = dd; best = f; }
        }
        const cross_face *cf = &cross_faces[best];
        float fu = prt__v3_dot(d, cf->right) / bestdot, fv = prt__v3_dot(d, cf->down) / bestdot;
        *px = cf->col * size + (fu + 1.0f) * 0.5f * size;
        *py = cf->row * size + (fv + 1.0f) * 0.5f * size;
        *px = fminf(fmaxf(*px, cf->col * size + 0.5f), (cf->col + 1) * size - 0.5f);
        *py = fminf(fmaxf(*py, cf->row * size + 0.5f), (cf->row + 1) * size - 0.5f);
    }
}

size_t prt__env_pixel_index(const prt_envmap *e, const float d[3])
{
    float fx, fy;
    prt__env_pixel_of(e, d, &fx, &fy);
    int x = (int)floorf(fx), y = (int)floorf(fy);
    x = x < 0 ? 0 : x >= e->img.width ? e->img.width - 1 : x;
    y = y < 0 ? 0 : y >= e->img.height ? e->img.height - 1 : y;
    return (size_t)y * e->img.width + x;
}

void prt_envmap_lookup(const prt_envmap *e, const float dir[3], float rgb[3])
{
    const int w = e->img.width, h = e->img.height;
    float px, py;
    prt__env_pixel_of(e, dir, &px, &py);
    float fx = px - 0.5f, fy = py - 0.5f;
    int x0 = (int)floorf(fx), y0 = (int)floorf(fy);
    float tx = fx - x0, ty = fy - y0;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
            int x = x0 + i, y = y0 + j;
            if (e->layout == PRT_ENV_LATLONG) x = ((x % w) + w) % w;   /* wraps in azimuth */
            else x = x < 0 ? 0 : x >= w ? w - 1 : x;
            y = y < 0 ? 0 : y >= h ? h - 1 : y;
            float wgt = (i ? tx : 1 - tx) * (j ? ty : 1 - ty);
            const float *p = e->img.rgb + ((size_t)y * w + x) * 3;
            for (int c = 0; c < 3; ++c) rgb[c] += wgt * p[c];
        }
}

prt_status prt_envmap_project_sh(const prt_envmap *e, int order, prt_sh_light *out)
{
    if (order < 1 || order > PRT_SH_MAX_ORDER)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "SH order %d out of range 1..%d", order, PRT_SH_MAX_ORDER);
    const int w = e->img.width, h = e->img.height, n = order * order;
    double *rows = prt__calloc((size_t)h * 3 * n + (size_t)h, sizeof(double));
    if (!rows) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    double *row_area = rows + (size_t)h * 3 * n;
    /* Rows are summed separately, then in order, so the result never depends on the thread count. */
#pragma omp parallel for schedule(static)
    for (int y = 0; y < h; ++y) {
        double basis[PRT_SH_MAX_COEFFS], basis2[PRT_SH_MAX_COEFFS], dir[3], dw;
        double *acc = rows + (size_t)y * 3 * n;
        for (int x = 0; x < w; ++x) {
            if (!pixel_dir(e, x, y, dir, &dw)) continue;
            if (e->layout == PRT_ENV_LATLONG) {
                /* The image is constant over a pixel: integrate the basis over the pixel's band
                 * of cos(theta) with 2-point Gauss-Legendre; azimuth is handled exactly below. */
                double z0 = cos(PRT_PI * y / h), z1 = cos(PRT_PI * (y + 1) / h), zc = 0.5 * (z0 + z1), dz = 0.5 * (z0 - z1) / sqrt(3.0);
                double s = sqrt(fmax(0.0, 1.0 - dir[1] * dir[1])), cx = s > 0 ? dir[0] / s : 0, cz = s > 0 ? dir[2] / s : -1;
                for (int k = 0; k < 2; ++k) {
                    double z = k ? zc - dz : zc + dz, r = sqrt(fmax(0.0, 1.0 - z * z));
                    double d2[3] = {r * cx, z, r * cz};
                    prt_sh_eval(order, d2, k ? basis2 : basis);
                }
                for (int i = 0; i < n; ++i) basis[i] = 0.5 * (basis[i] + basis2[i]);
            } else {
                prt_sh_eval(order, dir, basis);
            }
            const float *p = e->img.rgb + ((size_t)y * w + x) * 3;
            for (int c = 0; c < 3; ++c) {
                double v = p[c] * dw;
                for (int i = 0; i < n; ++i) acc[c * n + i] += v * basis[i];
            }
            row_area[y] += dw;
        }
    }
    double total[3 * PRT_SH_MAX_COEFFS] = {0}, area = 0.0;
    for (int y = 0; y < h; ++y) {
        for (int i = 0; i < 3 * n; ++i) total[i] += rows[(size_t)y * 3 * n + i];
        area += row_area[y];
    }
    free(rows);
    /* Angular and cross maps use pixel-centre solid angles; rescale so they cover exactly 4 pi. */
    double norm = e->layout == PRT_ENV_LATLONG ? 1.0 : 4.0 * PRT_PI / area;
    memset(out, 0, sizeof *out);
    out->order = order;
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < n; ++i) out->coeffs[c][i] = (float)(total[c * n + i] * norm);
    if (e->layout == PRT_ENV_LATLONG) {
        /* The mean of cos(m phi) or sin(m phi) over a pixel's azimuth width is its centre value
         * times sinc(m dphi / 2): apply it to make the sums exact pixel integrals. */
        const double half = PRT_PI / w;
        for (int l = 0; l < order; ++l)
            for (int m = -l; m <= l; ++m) {
                if (m == 0) continue;
                double a = abs(m) * half, sinc = sin(a) / a;
                for (int c = 0; c < 3; ++c) out->coeffs[c][l * (l + 1) + m] = (float)(out->coeffs[c][l * (l + 1) + m] * sinc);
            }
    }
    return PRT_OK;
}

prt_status prt__envmap_project_sh_cached(const prt_envmap *e, int order, prt_sh_light *out)
{
    if (order < 1 || order > PRT_SH_MAX_ORDER)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "SH order %d out of range 1..%d", order, PRT_SH_MAX_ORDER);
    prt_sh_light *cached = __atomic_load_n(&e->sh_cache[order], __ATOMIC_ACQUIRE);
    if (cached) { *out = *cached; return PRT_OK; }
    prt_status st = prt_envmap_project_sh(e, order, out);
    if (st) return st;
    prt_sh_light *c = malloc(sizeof *c), *expected = NULL;
    if (!c) return PRT_OK;   /* no cache this time; the result stands */
    *c = *out;
    /* Concurrent first calls may both project; one copy wins and the other is dropped. */
    if (!__atomic_compare_exchange_n(&((prt_envmap *)e)->sh_cache[order], &expected, c, false, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) free(c);
    return PRT_OK;
}
