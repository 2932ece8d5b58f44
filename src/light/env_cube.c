/* An environment as radiance over a cube map of 6 x 64 x 64 texels (Ng et al. 2003; Wang et al.
 * 2005 section 4.3: the all-frequency lighting basis starts from it): each texel holds the map's
 * energy over the texels' exact areas, through a finer 6 x 256 x 256 cube made once per map
 * (kept in the map) and, per rotation, from that, so that small bright sources keep their energy
 * under any rotation. */
#include "light/env_cube.h"

#include "core/cubemap.h"

#include <math.h>
#include <string.h>

#define FACE PRT__ENV_CUBE_FACE
#define DIM PRT__ENV_CUBE_DIM

#define SRC 256   /* source cube resolution: 4 x 4 source texels under each lighting texel */
#define BLOCK (SRC / FACE)

/* Adds w x (r, g, b, 1) (rgbw = r w, g w, b w, w) around direction d (any length) in an n x n
 * cube of 4-float cells, or only the first 3 floats when `channels` is 3, with bilinear weights
 * over the 2 x 2 nearest texel centres. Within half a texel of a face edge the 2 x 2 reaches onto
 * the neighbouring faces (d projected onto their planes), and the weights are renormalized: the
 * kernel stays smooth across edges (clamping it there would make it a hard-edged box that takes
 * the wrong share of a constant map, by up to 15% on the edge texels), and the weights always add
 * up to 1, so the energy splatted is exactly the energy given. */
static inline void splat(float *acc, int n, int channels, const float d[3], const float *rgbw)
{
    float a, b;
    const int face = prt__cube_face(d, &a, &b);
    const float fx = (a + 1.0f) * 0.5f * n - 0.5f, fy = (b + 1.0f) * 0.5f * n - 0.5f;
    if (fx >= 0.0f && fx < n - 1.0f && fy >= 0.0f && fy < n - 1.0f) {
        const int x0 = (int)fx, y0 = (int)fy;
        const float tx = fx - x0, ty = fy - y0;
        float *p = acc + (((size_t)face * n + y0) * n + x0) * channels, *q = p + (size_t)n * channels;
        for (int c = 0; c < channels; ++c) {
            p[c] += (1 - tx) * (1 - ty) * rgbw[c];
            p[channels + c] += tx * (1 - ty) * rgbw[c];
            q[c] += (1 - tx) * ty * rgbw[c];
            q[channels + c] += tx * ty * rgbw[c];
        }
        return;
    }
    /* Near an edge: the taps that fall inside each face d is in front of (at most 3 faces). */
    size_t cell[12];
    float wt[12], sum = 0;
    int taps = 0;
    for (int g = 0; g < 6; ++g) {
        const float(*ax)[3] = prt__cube_axes[g];
        const float m = d[0] * ax[0][0] + d[1] * ax[0][1] + d[2] * ax[0][2];
        if (m <= 0.0f) continue;
        const float gx = ((d[0] * ax[1][0] + d[1] * ax[1][1] + d[2] * ax[1][2]) / m + 1.0f) * 0.5f * n - 0.5f;
        const float gy = ((d[0] * ax[2][0] + d[1] * ax[2][1] + d[2] * ax[2][2]) / m + 1.0f) * 0.5f * n - 0.5f;
        if (!(gx > -1.0f && gx < n && gy > -1.0f && gy < n)) continue;
        const int x0 = (int)floorf(gx), y0 = (int)floorf(gy);
        const float tx = gx - x0, ty = gy - y0;
        for (int k = 0; k < 4 && taps < 12; ++k) {
            const int x = x0 + (k & 1), y = y0 + (k >> 1);
            if (x < 0 || x >= n || y < 0 || y >= n) continue;
            wt[taps] = ((k & 1) ? tx : 1 - tx) * ((k >> 1) ? ty : 1 - ty);
            cell[taps] = ((size_t)g * n + y) * n + x;
            sum += wt[taps++];
        }
    }
    for (int i = 0; i < taps; ++i)
        for (int c = 0; c < channels; ++c) acc[cell[i] * channels + c] += wt[i] / sum * rgbw[c];
}

/* ---- Exact area weights. A cube face's gnomonic projection maps great circles to straight
 * lines, so a spherical quad with great-circle edges (a cube texel; a lat-long pixel with its
 * parallels replaced by chords, which tile the sphere just as well) is a convex quad on the
 * face's plane, and its share of each texel is a polygon clip. */

typedef struct pt2 { float x, y; } pt2;

/* fminf and fmaxf are library calls here (NaN rules); these are not. */
static inline float minf(float a, float b) { return a < b ? a : b; }
static inline float maxf(float a, float b) { return a > b ? a : b; }

/* Sutherland-Hodgman: the part of polygon in[n] with sign * (coordinate axis - c) >= 0. */
static inline int clip_half(const pt2 *in, int n, pt2 *out, int axis, float c, float sign)
{
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const pt2 p = in[i], q = in[i + 1 < n ? i + 1 : 0];
        const float dp = sign * ((axis ? p.y : p.x) - c), dq = sign * ((axis ? q.y : q.x) - c);
        if (dp >= 0) out[m++] = p;
        if ((dp >= 0) != (dq >= 0)) {
            const float t = dp / (dp - dq);
            out[m++] = (pt2){p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
        }
    }
    return m;
}

/* The solid angle of polygon p on the plane of a face of n x n texels (texel units), up to a
 * constant factor: its area times the solid angle per area at its centroid, (1 + a^2 + b^2)^-3/2
 * (exact to second order; plane areas alone err by about 1% across a texel). */
/* Twice the signed area of polygon p (s) and its first moments relative to p[0] (times 6 s). */
static inline void poly_moments(const pt2 *p, int n, float *s, float *mx, float *my)
{
    /* Relative to the first vertex: products of coordinates up to 256 would cancel to 1e-2. */
    const float ox = p[0].x, oy = p[0].y;
    *s = *mx = *my = 0;
    for (int i = 1; i + 1 < n; ++i) {
        const float ax = p[i].x - ox, ay = p[i].y - oy, bx = p[i + 1].x - ox, by = p[i + 1].y - oy, c = ax * by - bx * ay;
        *s += c;
        *mx += (ax + bx) * c;
        *my += (ay + by) * c;
    }
}

static float poly_weight(const pt2 *p, int n, int size)
{
    const float ox = p[0].x, oy = p[0].y;
    float s, mx, my;
    poly_moments(p, n, &s, &mx, &my);
    if (s == 0) return 0;
    const float k = 2.0f / size, ca = (ox + mx / (3 * s)) * k - 1.0f, cb = (oy + my / (3 * s)) * k - 1.0f, r2 = 1.0f + ca * ca + cb * cb;
    return 0.5f * fabsf(s) / (r2 * sqrtf(r2));
}

/* poly_weight with the solid angle per area linearized about (xr, yr), where its logarithmic
 * gradient is (gx, gy): no division or root per piece, for the many small pieces of a rotation. */
static inline float poly_weight_lin(const pt2 *p, int n, float xr, float yr, float gx, float gy)
{
    const float ox = p[0].x, oy = p[0].y;
    float s, mx, my;
    poly_moments(p, n, &s, &mx, &my);
    const float w = 0.5f * s * (1.0f + gx * (ox - xr) + gy * (oy - yr)) + (gx * mx + gy * my) * (1.0f / 6.0f);
    return s < 0 ? -w : w;
}

/* Calls out(cell, area) for each texel of face g (n x n, texel units) that quad q overlaps. */
#define MAX_POLY 12
static void quad_cells(const pt2 q[4], int n, void (*out)(void *, size_t, float), void *user, int g)
{
    float x0 = q[0].x, x1 = x0, y0 = q[0].y, y1 = y0;
    for (int k = 1; k < 4; ++k) {
        x0 = minf(x0, q[k].x); x1 = maxf(x1, q[k].x);
        y0 = minf(y0, q[k].y); y1 = maxf(y1, q[k].y);
    }
    const int cx0 = (int)maxf(floorf(x0), 0.0f), cx1 = (int)minf(floorf(x1), n - 1.0f);
    const int cy0 = (int)maxf(floorf(y0), 0.0f), cy1 = (int)minf(floorf(y1), n - 1.0f);
    const size_t base = (size_t)g * n * n;
    if (cx0 == cx1 && cy0 == cy1 && x0 >= cx0 && x1 <= cx0 + 1 && y0 >= cy0 && y1 <= cy0 + 1) {
        out(user, base + (size_t)cy0 * n + cx0, poly_weight(q, 4, n));
        return;
    }
    pt2 a[MAX_POLY], b[MAX_POLY], c[MAX_POLY], col[MAX_POLY];
    for (int cx = cx0; cx <= cx1; ++cx) {
        int m = clip_half(q, 4, a, 0, (float)cx, 1.0f);
        m = clip_half(a, m, col, 0, (float)(cx + 1), -1.0f);
        if (m < 3) continue;
        for (int cy = cy0; cy <= cy1; ++cy) {
            int k = clip_half(col, m, b, 1, (float)cy, 1.0f);
            k = clip_half(b, k, c, 1, (float)(cy + 1), -1.0f);
            if (k >= 3) out(user, base + (size_t)cy * n + cx, poly_weight(c, k, n));
        }
    }
}

/* The quad with corners d[4] (unit directions, in order around it) on face g's plane, in texel
 * units of an n x n face; false when a corner is not in front of that face. */
static bool quad_on_face(const float d[4][3], int g, int n, pt2 q[4])
{
    const float(*ax)[3] = prt__cube_axes[g];
    for (int k = 0; k < 4; ++k) {
        const float m = d[k][0] * ax[0][0] + d[k][1] * ax[0][1] + d[k][2] * ax[0][2];
        if (m <= 1e-3f) return false;
        q[k].x = ((d[k][0] * ax[1][0] + d[k][1] * ax[1][1] + d[k][2] * ax[1][2]) / m + 1.0f) * 0.5f * n;
        q[k].y = ((d[k][0] * ax[2][0] + d[k][1] * ax[2][1] + d[k][2] * ax[2][2]) / m + 1.0f) * 0.5f * n;
    }
    return true;
}

/* Solid angle of the spherical triangle a b c (unit vectors; Van Oosterom and Strackee). */
static float tri_solid_angle(const float a[3], const float b[3], const float c[3])
{
    const double det = a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) - a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
                       a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0]);
    const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2], bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2], ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
    return (float)(2.0 * atan2(fabs(det), 1.0 + ab + bc + ca));
}

typedef struct deposit_job {
    float *acc;
    int channels;
    const float *val;
    float scale;
} deposit_job;

static void add_area(void *user, size_t cell, float area)
{
    (void)cell;
    *(float *)user += area;
}

static void add_value(void *user, size_t cell, float area)
{
    const deposit_job *j = user;
    const float w = area * j->scale;
    for (int c = 0; c < j->channels; ++c) j->acc[cell * j->channels + c] += w * j->val[c];
}

/* Adds val (`channels` floats: energies, and for the source cube the solid angle) to the n x n
 * cube acc, shared among the texels in proportion to the area of the quad d[4] over each (on the
 * faces' planes: the solid angle per plane area changes by about 1% across a texel, a
 * first-order error that cancels between the two sides of each texel edge). The shares add up
 * to 1, so val lands whole. Quads wider than 0.2 rad, or reaching behind a face they touch, are
 * split in four along great circles. */
static void deposit(float *acc, int n, int channels, const float d[4][3], const float *val, int depth)
{
    int faces = 0;
    bool split = false;
    for (int k = 0; k < 4; ++k) {
        float a, b;
        faces |= 1 << prt__cube_face(d[k], &a, &b);
        const float *e = d[(k + 2) & 3];
        split |= d[k][0] * e[0] + d[k][1] * e[1] + d[k][2] * e[2] < 0.98f;   /* diagonal over 0.2 rad */
    }
    pt2 q[6][4];
    /* A quad over a cube corner can reach a third face with none of its corners: every face
     * that all corners are in front of takes part (its clip is empty when the quad misses it). */
    int use = 0;
    for (int g = 0; g < 6 && !split; ++g) {
        const bool on = quad_on_face(d, g, n, q[g]);
        if (on) use |= 1 << g;
        else split = faces >> g & 1;
    }
    if (split && depth < 8) {
        float mid[9][3];   /* 3 x 3 grid: corners, edge midpoints, centre */
        const int at[4] = {0, 2, 8, 6};
        for (int k = 0; k < 4; ++k) memcpy(mid[at[k]], d[k], sizeof mid[0]);
        for (int i = 0; i < 3; ++i) {
            mid[1][i] = d[0][i] + d[1][i]; mid[5][i] = d[1][i] + d[2][i];
            mid[7][i] = d[2][i] + d[3][i]; mid[3][i] = d[3][i] + d[0][i];
            mid[4][i] = d[0][i] + d[1][i] + d[2][i] + d[3][i];
        }
        for (int k = 1; k < 8; k += 2) {
            const float l = sqrtf(mid[k][0] * mid[k][0] + mid[k][1] * mid[k][1] + mid[k][2] * mid[k][2]);
            for (int i = 0; i < 3; ++i) mid[k][i] /= l;
        }
        const float l = sqrtf(mid[4][0] * mid[4][0] + mid[4][1] * mid[4][1] + mid[4][2] * mid[4][2]);
        for (int i = 0; i < 3; ++i) mid[4][i] /= l;
        const int sub[4][4] = {{0, 1, 4, 3}, {1, 2, 5, 4}, {4, 5, 8, 7}, {3, 4, 7, 6}};
        /* Each quarter takes its share of val by its solid angle. */
        float parts[4], total = 0, sd[4][4][3];
        for (int s = 0; s < 4; ++s) {
            for (int k = 0; k < 4; ++k) memcpy(sd[s][k], mid[sub[s][k]], sizeof sd[0][0]);
            parts[s] = tri_solid_angle(sd[s][0], sd[s][1], sd[s][2]) + tri_solid_angle(sd[s][0], sd[s][2], sd[s][3]);
            total += parts[s];
        }
        for (int s = 0; s < 4; ++s) {
            float v[4];
            for (int c = 0; c < channels; ++c) v[c] = total > 0 ? val[c] * parts[s] / total : 0.25f * val[c];
            deposit(acc, n, channels, (const float(*)[3])sd[s], v, depth + 1);
        }
        return;
    }
    float area = 0;
    for (int g = 0; g < 6; ++g)
        if (use >> g & 1) quad_cells(q[g], n, add_area, &area, g);
    if (!(area > 0)) return;
    deposit_job j = {acc, channels, val, 1.0f / area};
    for (int g = 0; g < 6; ++g)
        if (use >> g & 1) quad_cells(q[g], n, add_value, &j, g);
}

/* A quad corner: the face it lies on and its coordinates there in texel units (n x n). */
typedef struct corner { float u, v; int face; } corner;

static inline corner corner_of(const float d[3], int n)
{
    float a, b;
    const int f = prt__cube_face(d, &a, &b);
    return (corner){(a + 1.0f) * 0.5f * n, (b + 1.0f) * 0.5f * n, f};
}

/* deposit() for quads whose corners c[4] (of d[4]) lie on one face and span at most 3 x 3
 * texels, the usual case, without the callbacks: whole into one texel, or clipped. */
static inline void deposit_fast(float *acc, int n, int channels, const float *d0, const float *d1, const float *d2, const float *d3,
                                const corner c[4], const float *val)
{
    const int f = c[0].face;
    if (c[1].face == f && c[2].face == f && c[3].face == f) {
        const float x0 = minf(minf(c[0].u, c[1].u), minf(c[2].u, c[3].u)), x1 = maxf(maxf(c[0].u, c[1].u), maxf(c[2].u, c[3].u));
        const float y0 = minf(minf(c[0].v, c[1].v), minf(c[2].v, c[3].v)), y1 = maxf(maxf(c[0].v, c[1].v), maxf(c[2].v, c[3].v));
        const int cx0 = (int)maxf(floorf(x0), 0.0f), cx1 = (int)minf(floorf(x1), n - 1.0f);
        const int cy0 = (int)maxf(floorf(y0), 0.0f), cy1 = (int)minf(floorf(y1), n - 1.0f);
        float *face = acc + (size_t)f * n * n * channels;
        if (cx0 == cx1 && cy0 == cy1) {   /* inside one texel (corners on face f: inside the face) */
            float *o = face + ((size_t)cy0 * n + cx0) * channels;
            for (int ch = 0; ch < channels; ++ch) o[ch] += val[ch];
            return;
        }
        if (cx1 - cx0 <= 2 && cy1 - cy0 <= 2) {
            pt2 q[4] = {{c[0].u, c[0].v}, {c[1].u, c[1].v}, {c[2].u, c[2].v}, {c[3].u, c[3].v}};
            /* d ln((1 + a^2 + b^2)^-3/2) per texel, at the corner c[0]. */
            const float kt = 2.0f / n, ra = c[0].u * kt - 1.0f, rb = c[0].v * kt - 1.0f, f = -3.0f * kt / (1.0f + ra * ra + rb * rb);
            const float gx = f * ra, gy = f * rb;
            pt2 b0[MAX_POLY], b1[MAX_POLY], b2[MAX_POLY], b3[MAX_POLY];
            float area[9], total = 0;
            int cell[9], k = 0;
            for (int cx = cx0; cx <= cx1; ++cx) {
                const pt2 *col = q;
                int m = 4;
                if (cx > cx0) { m = clip_half(col, m, b0, 0, (float)cx, 1.0f); col = b0; }
                if (cx < cx1) { m = clip_half(col, m, b1, 0, (float)(cx + 1), -1.0f); col = b1; }
                for (int cy = cy0; cy <= cy1 && m >= 3; ++cy) {
                    const pt2 *p = col;
                    int j = m;
                    if (cy > cy0) { j = clip_half(p, j, b2, 1, (float)cy, 1.0f); p = b2; }
                    if (cy < cy1) { j = clip_half(p, j, b3, 1, (float)(cy + 1), -1.0f); p = b3; }
                    if (j < 3) continue;
                    area[k] = poly_weight_lin(p, j, c[0].u, c[0].v, gx, gy);
                    total += area[k];
                    cell[k++] = cy * n + cx;
                }
            }
            if (total > 0)
                for (int i = 0; i < k; ++i) {
                    float *o = face + (size_t)cell[i] * channels;
                    const float w = area[i] / total;
                    for (int ch = 0; ch < channels; ++ch) o[ch] += w * val[ch];
                }
            return;
        }
    }
    float d[4][3];
    const float *src[4] = {d0, d1, d2, d3};
    for (int k = 0; k < 4; ++k) {   /* deposit() wants unit vectors */
        const float l = 1.0f / sqrtf(src[k][0] * src[k][0] + src[k][1] * src[k][1] + src[k][2] * src[k][2]);
        for (int i = 0; i < 3; ++i) d[k][i] = src[k][i] * l;
    }
    deposit(acc, n, channels, (const float(*)[3])d, val, 0);
}

/* Sub-sample spacing (radians) for the splat into the source cube: half the smallest source
 * texel (at the face corners, sqrt(2)/3 of the face-centre size). */
#define SPLAT_STEP (2.0 / SRC * (1.4142135623730951 / 3.0) / 2.0)

/* Lat-long rows [y0, y1): each pixel's energy (radiance times its exact solid angle) and solid
 * angle, shared among the source texels by exact area (`deposit`). cphi, sphi: cos and sin of
 * the W + 1 column edges' azimuths. */
static void deposit_latlong_rows(float *acc, const prt_image *img, const double *cphi, const double *sphi, int y0, int y1)
{
    const int w = img->width, h = img->height;
    float(*edge)[3] = malloc((size_t)2 * (w + 1) * sizeof *edge);
    corner *cn = malloc((size_t)2 * (w + 1) * sizeof *cn);
    if (!edge || !cn) { free(edge); free(cn); return; }
    for (int y = y0; y < y1; ++y) {
        const double th[2] = {PRT_PI * y / h, PRT_PI * (y + 1) / h};
        for (int r = 0; r < 2; ++r) {
            const double st = sin(th[r]), ct = cos(th[r]);
            for (int x = 0; x <= w; ++x) {
                float *e = edge[(size_t)r * (w + 1) + x];
                e[0] = (float)(st * sphi[x]); e[1] = (float)ct; e[2] = (float)(-st * cphi[x]);
            }
        }
        for (int x = 0; x <= w; ++x) {
            cn[x] = corner_of(edge[x], SRC);
            cn[w + 1 + x] = corner_of(edge[w + 1 + x], SRC);
        }
        const float dw = (float)(2.0 * PRT_PI / w * (cos(th[0]) - cos(th[1])));
        for (int x = 0; x < w; ++x) {
            const corner c[4] = {cn[x], cn[x + 1], cn[w + 1 + x + 1], cn[w + 1 + x]};
            const float *px = img->rgb + ((size_t)y * w + x) * 3, val[4] = {px[0] * dw, px[1] * dw, px[2] * dw, dw};
            deposit_fast(acc, SRC, 4, edge[x], edge[x + 1], edge[(w + 1) + x + 1], edge[(w + 1) + x], c, val);
        }
    }
    free(edge);
    free(cn);
}

/* Any layout: n x n sub-samples per pixel, each weighted by its own solid angle. */
static void splat_generic(float *acc, const prt_envmap *env)
{
    const prt_image *img = &env->img;
    for (int y = 0; y < img->height; ++y)
        for (int x = 0; x < img->width; ++x) {
            double dir[3], jac;
            if (!prt__env_dir_at(env, x + 0.5, y + 0.5, dir, &jac)) continue;
            /* Pixels of angular maps stretch up to about pi / 2 times more one way: margin 2. */
            const int n = (int)fmin(64.0, fmax(1.0, ceil(2.0 * sqrt(jac) / SPLAT_STEP)));
            const float *px = img->rgb + ((size_t)y * img->width + x) * 3;
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    if (!prt__env_dir_at(env, x + (i + 0.5) / n, y + (j + 0.5) / n, dir, &jac)) continue;
                    const float wsub = (float)(jac / ((double)n * n)), d[3] = {(float)dir[0], (float)dir[1], (float)dir[2]};
                    const float rgbw[4] = {px[0] * wsub, px[1] * wsub, px[2] * wsub, wsub};
                    splat(acc, SRC, 4, d, rgbw);
                }
        }
}

/* The map integrated into the source cube, once per map: each source texel holds its energy,
 * RGB. Every pixel lands whole, shared over the texels its solid angle covers, so small bright
 * sources keep their energy wherever they sit. Concurrent first calls may both build it; one
 * copy wins. */
static const float *source_cube(prt_context *ctx, const prt_envmap *env)
{
    float *cached = __atomic_load_n(&env->cube_cache, __ATOMIC_ACQUIRE);
    if (cached) return cached;
    const size_t cells = (size_t)6 * SRC * SRC;
    float *acc = prt__calloc(cells * 4, sizeof(float)), *c = malloc(cells * 3 * sizeof(float));
    if (!acc || !c) { free(acc); free(c); return NULL; }
    const prt_image *img = &env->img;
    if (env->layout == PRT_ENV_LATLONG) {
        /* Bands of rows at least 0.04 rad tall: pixels from bands two apart never share a source
         * texel, so the even bands, then the odd ones, run in parallel and every texel sums in
         * the same order on any number of threads. */
        const int w = img->width, band = (int)ceil(0.04 / (PRT_PI / img->height)), bands = (img->height + band - 1) / band;
        double *cs = malloc((size_t)2 * (w + 1) * sizeof(double));
        if (!cs) { free(acc); free(c); return NULL; }
        for (int x = 0; x <= w; ++x) {
            const double ph = 2.0 * PRT_PI * ((double)x / w - 0.5);
            cs[x] = cos(ph);
            cs[w + 1 + x] = sin(ph);
        }
        for (int parity = 0; parity < 2; ++parity) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(prt__threads(ctx))
            for (int k = parity; k < bands; k += 2) {
                const int y1 = (k + 1) * band < img->height ? (k + 1) * band : img->height;
                deposit_latlong_rows(acc, img, cs, cs + w + 1, k * band, y1);
            }
        }
        free(cs);
    } else {
        splat_generic(acc, env);
    }
    /* Each texel's energy scaled so that the solid angle it took becomes its own: a constant map
     * gives exactly that constant. Exact areas match to about 1e-4 per texel; the sub-sample
     * splats of other layouts only under a block of 4 x 4 texels (a lighting texel), so those are
     * scaled per block, and a sun's energy does not depend on where it falls in a block. */
    const int block = env->layout == PRT_ENV_LATLONG ? 1 : BLOCK, nb = SRC / block;
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
    for (int t = 0; t < 6 * nb * nb; ++t) {
        const int face = t / (nb * nb), by = t / nb % nb, bx = t % nb;
        float dir[3], dw;
        prt__cube_texel(nb, face, bx, by, dir, &dw);
        double area = 0;
        for (int y = by * block; y < (by + 1) * block; ++y)
            for (int x = bx * block; x < (bx + 1) * block; ++x) area += acc[(((size_t)face * SRC + y) * SRC + x) * 4 + 3];
        const float k = area > 0 ? (float)(dw / area) : 0.0f;
        for (int y = by * block; y < (by + 1) * block; ++y)
            for (int x = bx * block; x < (bx + 1) * block; ++x) {
                const size_t i = ((size_t)face * SRC + y) * SRC + x;
                for (int ch = 0; ch < 3; ++ch) c[i * 3 + ch] = acc[i * 4 + ch] * k;
            }
    }
    free(acc);
    float *expected = NULL;
    /* The cache is a memo of a pure function of the map, so filling it through a const map is safe. */
    if (!__atomic_compare_exchange_n(&((prt_envmap *)env)->cube_cache, &expected, c, false, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
        free(c);
        return expected;
    }
    return c;
}

/* The rotated lighting: the source cube's energy, 2 x 2 texels at a time (half a lighting texel:
 * as sharp as resampling the source cube was, at a quarter of the quads), shared by exact area
 * among the lighting texels that the rotated quad covers (`deposit`). The light keeps exactly the
 * map's energy under any rotation, and a constant map stays constant to about 1e-3. Each source
 * face adds into its own cube, summed in face order after: the same result on any number of
 * threads. */
static void deposit_rotated(prt_context *ctx, const float *src, const double R[9], float *per_face, float *dst)
{
    enum { HALF = SRC / 2 };
#pragma omp parallel for schedule(dynamic, 1) num_threads(prt__threads(ctx))
    for (int face = 0; face < 6; ++face) {
        const float *axis = prt__cube_axes[face][0], *right = prt__cube_axes[face][1], *up = prt__cube_axes[face][2];
        float ra[3], rr[3], ru[3];
        for (int i = 0; i < 3; ++i) {   /* R e is linear in the face coordinates */
            ra[i] = (float)(R[3 * i] * axis[0] + R[3 * i + 1] * axis[1] + R[3 * i + 2] * axis[2]);
            rr[i] = (float)(R[3 * i] * right[0] + R[3 * i + 1] * right[1] + R[3 * i + 2] * right[2]);
            ru[i] = (float)(R[3 * i] * up[0] + R[3 * i + 1] * up[1] + R[3 * i + 2] * up[2]);
        }
        const float *fsrc = src + (size_t)face * SRC * SRC * 3;
        float *acc = per_face + (size_t)face * DIM * 3;
        float edge[2][HALF + 1][3];   /* rotated quad corners (not unit) along two row edges */
        corner cn[2][HALF + 1];
        for (int y = 0; y < HALF; ++y) {
            const int lo = y & 1, hi = lo ^ 1;   /* the row edge below was the one above last row */
            for (int r = y ? 1 : 0; r < 2; ++r) {
                const int slot = r ? hi : lo;
                const float b = 2.0f * (y + r) / HALF - 1.0f;
                for (int x = 0; x <= HALF; ++x) {
                    const float a = 2.0f * x / HALF - 1.0f;
                    for (int i = 0; i < 3; ++i) edge[slot][x][i] = ra[i] + a * rr[i] + b * ru[i];
                    cn[slot][x] = corner_of(edge[slot][x], FACE);
                }
            }
            for (int x = 0; x < HALF; ++x) {
                const float *e0 = fsrc + ((size_t)(2 * y) * SRC + 2 * x) * 3, *e1 = e0 + (size_t)SRC * 3;
                const float val[3] = {e0[0] + e0[3] + e1[0] + e1[3], e0[1] + e0[4] + e1[1] + e1[4], e0[2] + e0[5] + e1[2] + e1[5]};
                const corner c[4] = {cn[lo][x], cn[lo][x + 1], cn[hi][x + 1], cn[hi][x]};
                deposit_fast(acc, FACE, 3, edge[lo][x], edge[lo][x + 1], edge[hi][x + 1], edge[hi][x], c, val);
            }
        }
    }
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
    for (int i = 0; i < DIM * 3; ++i) {
        float v = 0;
        for (int f = 0; f < 6; ++f) v += per_face[(size_t)f * DIM * 3 + i];
        dst[i] = v;
    }
}

/* One octant of the face, mirrored. */
void prt__env_cube_solid_angles(float *table)
{
    const int h = FACE / 2;
    for (int y = 0; y < h; ++y)
        for (int x = y; x < h; ++x) {
            float dir[3], dw;
            prt__cube_texel(FACE, 0, x, y, dir, &dw);
            const int xs[2] = {x, FACE - 1 - x}, ys[2] = {y, FACE - 1 - y};
            for (int i = 0; i < 2; ++i)
                for (int j = 0; j < 2; ++j) {
                    table[ys[j] * FACE + xs[i]] = dw;
                    table[xs[i] * FACE + ys[j]] = dw;
                }
        }
}

prt_status prt__env_cube(prt_context *ctx, const prt_envmap *env, const double rotation[9], float intensity, float *radiance)
{
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    bool any = false;
    for (int i = 0; rotation && i < 9; ++i) any |= rotation[i] != 0;
    if (any) memcpy(R, rotation, sizeof R);
    const bool identity = !any || (R[0] == 1 && R[4] == 1 && R[8] == 1 && R[1] == 0 && R[2] == 0 && R[3] == 0 && R[5] == 0 && R[6] == 0 && R[7] == 0);
    const float *src = source_cube(ctx, env);
    float *rot = identity ? NULL : prt__calloc((size_t)7 * DIM * 3, sizeof(float));   /* 6 per-face cubes, then their sum */
    if (!src || (!identity && !rot)) { free(rot); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    /* Each texel: its energy (of the 4 x 4 source texels under it, or deposited by the rotation)
     * over its solid angle. */
    const float *from = identity ? src : rot + (size_t)6 * DIM * 3;
    float omega[FACE * FACE];
    prt__env_cube_solid_angles(omega);
    const int n = identity ? SRC : FACE, fine = n / FACE;
    if (!identity) deposit_rotated(ctx, src, R, rot, rot + (size_t)6 * DIM * 3);
#pragma omp parallel for schedule(static) num_threads(prt__threads(ctx))
    for (int t = 0; t < DIM; ++t) {
        int face = t / (FACE * FACE), y = t / FACE % FACE, x = t % FACE;
        double acc[3] = {0, 0, 0};
        for (int sy = 0; sy < fine; ++sy)
            for (int sx = 0; sx < fine; ++sx) {
                const float *e = from + (((size_t)face * n + (size_t)y * fine + sy) * n + (size_t)x * fine + sx) * 3;
                for (int c = 0; c < 3; ++c) acc[c] += e[c];
            }
        for (int c = 0; c < 3; ++c) radiance[(size_t)t * 3 + c] = (float)(acc[c] / omega[t % (FACE * FACE)]) * intensity;
    }
    free(rot);
    return PRT_OK;
}

static void quads_of(const float *src, float *energy)
{
    for (int face = 0; face < 6; ++face)
        for (int y = 0; y < PRT__ENV_CUBE_QUADS; ++y)
            for (int x = 0; x < PRT__ENV_CUBE_QUADS; ++x) {
                /* As deposit_rotated adds them. */
                const float *e0 = src + (((size_t)face * SRC + 2 * y) * SRC + 2 * x) * 3, *e1 = e0 + (size_t)SRC * 3;
                float *o = energy + (((size_t)face * PRT__ENV_CUBE_QUADS + y) * PRT__ENV_CUBE_QUADS + x) * 3;
                for (int c = 0; c < 3; ++c) o[c] = e0[c] + e0[3 + c] + e1[c] + e1[3 + c];
            }
}

prt_status prt__env_cube_quads(prt_context *ctx, const prt_envmap *env, float *energy)
{
    const float *src = source_cube(ctx, env);
    if (!src) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    quads_of(src, energy);
    return PRT_OK;
}
