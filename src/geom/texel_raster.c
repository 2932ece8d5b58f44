/* Texel patches of a UV layout: which triangle owns each texel centre, and how much surface each
 * texel covers. Shared by every method that bakes transfer per texel. */
#include "geom/texel_raster.h"

/* The point of triangle (u, v) nearest to (px, py), as barycentrics b1, b2; its squared distance. */
static float nearest_on_triangle(const float u[3], const float v[3], float px, float py, float *b1, float *b2)
{
    float best = INFINITY;
    for (int e = 0; e < 3; ++e) {
        const int a = e, b = (e + 1) % 3;
        float ex = u[b] - u[a], ey = v[b] - v[a], len2 = ex * ex + ey * ey;
        float t = len2 > 0 ? ((px - u[a]) * ex + (py - v[a]) * ey) / len2 : 0.0f;
        t = fminf(fmaxf(t, 0.0f), 1.0f);
        float qx = u[a] + t * ex - px, qy = v[a] + t * ey - py, d2 = qx * qx + qy * qy;
        if (d2 < best) {
            best = d2;
            float w[3] = {0, 0, 0};
            w[a] = 1 - t;
            w[b] = t;
            *b1 = w[1];
            *b2 = w[2];
        }
    }
    return best;
}

bool prt__texel_raster(const prt__mesh *m, int W, int H, uint32_t *owner, float *bary, size_t *overlap_out, size_t *outside_out)
{
    /* Rasterize the UV layout: texel (x, y) has its centre at ((x + .5) / W, (y + .5) / H); the
     * first triangle to cover a texel owns it, later ones count as overlap. */
    size_t overlap = 0, outside = 0;
    const size_t ntex = (size_t)W * H;
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        float u[3], v[3];
        for (int k = 0; k < 3; ++k) { u[k] = m->uv[ix[k] * 2] * W; v[k] = m->uv[ix[k] * 2 + 1] * H; }
        for (int k = 0; k < 3; ++k) outside += u[k] < -1e-3f * W || u[k] > W * 1.001f || v[k] < -1e-3f * H || v[k] > H * 1.001f;
        float area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
        if (area == 0.0f) continue;
        /* Clamped before converting: a file's UVs may lie far outside the map. */
        const int x0 = (int)fmaxf(floorf(fminf(u[0], fminf(u[1], u[2]))), 0.0f), x1 = (int)fminf(ceilf(fmaxf(u[0], fmaxf(u[1], u[2]))), (float)W);
        const int y0 = (int)fmaxf(floorf(fminf(v[0], fminf(v[1], v[2]))), 0.0f), y1 = (int)fminf(ceilf(fmaxf(v[0], fmaxf(v[1], v[2]))), (float)H);
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                float px = x + 0.5f, py = y + 0.5f;
                float b1 = ((px - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (py - v[0])) / area;
                float b2 = ((u[1] - u[0]) * (py - v[0]) - (px - u[0]) * (v[1] - v[0])) / area;
                if (b1 < -1e-6f || b2 < -1e-6f || b1 + b2 > 1.0f + 1e-6f) continue;
                size_t i = (size_t)y * W + x;
                if (owner[i]) {   /* centres on a shared edge are not overlap */
                    overlap += b1 > 1e-4f && b2 > 1e-4f && b1 + b2 < 1.0f - 1e-4f;
                    continue;
                }
                owner[i] = (uint32_t)t + 1;
                bary[i * 2] = b1;
                bary[i * 2 + 1] = b2;
            }
    }
    /* Triangles no texel centre falls in (slivers, charts smaller than a texel) take the texels
     * they touch, at their nearest point: otherwise the gutter fill would give them another
     * chart's light. Borders of larger triangles are left to the fill, which copies their own
     * chart's texels: a border sample sits where surfaces touch (a sphere resting on the floor)
     * and would see through the floor. */
    {
        float *near = malloc(ntex * sizeof *near);
        uint8_t *owns = prt__calloc(m->triangle_count, 1);
        if (!near || !owns) { free(near); free(owns); return false; }
        for (size_t i = 0; i < ntex; ++i) {
            near[i] = INFINITY;
            if (owner[i]) owns[owner[i] - 1] = 1;
        }
        for (size_t t = 0; t < m->triangle_count; ++t) {
            if (owns[t]) continue;
            const uint32_t *ix = m->indices + t * 3;
            float u[3], v[3];
            for (int k = 0; k < 3; ++k) { u[k] = m->uv[ix[k] * 2] * W; v[k] = m->uv[ix[k] * 2 + 1] * H; }
            if ((u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]) == 0.0f) continue;
            const int x0 = (int)fmaxf(floorf(fminf(u[0], fminf(u[1], u[2])) - 0.5f), 0.0f);
            const int x1 = (int)fminf(ceilf(fmaxf(u[0], fmaxf(u[1], u[2])) + 0.5f), (float)W);
            const int y0 = (int)fmaxf(floorf(fminf(v[0], fminf(v[1], v[2])) - 0.5f), 0.0f);
            const int y1 = (int)fminf(ceilf(fmaxf(v[0], fmaxf(v[1], v[2])) + 0.5f), (float)H);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    size_t i = (size_t)y * W + x;
                    if (owner[i] && near[i] == INFINITY) continue;   /* its centre is inside a triangle */
                    float b1 = 0, b2 = 0, d2 = nearest_on_triangle(u, v, x + 0.5f, y + 0.5f, &b1, &b2);
                    if (d2 > 0.5f || d2 >= near[i]) continue;   /* 0.5: the texel's corner is the farthest it reaches */
                    near[i] = d2;
                    owner[i] = (uint32_t)t + 1;
                    /* A fifth of the way to the centroid, away from where surfaces touch. */
                    bary[i * 2] = 0.8f * b1 + 0.2f / 3;
                    bary[i * 2 + 1] = 0.8f * b2 + 0.2f / 3;
                }
        }
        free(near);
        free(owns);
    }
    *overlap_out = overlap;
    *outside_out = outside;
    return true;
}

/* Clips the convex polygon to x >= lo (axis 0) or x <= hi etc.: keep where sign * (p[axis] - at) <= 0. */
static int clip_axis(float (*poly)[2], int n, int axis, float at, float sign)
{
    float out[16][2];
    int m = 0;
    for (int i = 0; i < n && m < 15; ++i) {
        const float *p = poly[i], *q = poly[(i + 1) % n];
        const float dp = sign * (p[axis] - at), dq = sign * (q[axis] - at);
        if (dp <= 0) { out[m][0] = p[0]; out[m][1] = p[1]; m++; }
        if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
            const float f = dp / (dp - dq);
            out[m][0] = p[0] + f * (q[0] - p[0]);
            out[m][1] = p[1] + f * (q[1] - p[1]);
            m++;
        }
    }
    memcpy(poly, out, (size_t)m * sizeof *out);
    return m;
}

bool prt__texel_areas(const prt__mesh *m, int W, int H, float *area)
{
    const size_t ntex = (size_t)W * H;
    double *acc = prt__calloc(ntex, sizeof *acc);
    if (!acc) return false;
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        float u[3], v[3], e1[3], e2[3], cr[3];
        for (int k = 0; k < 3; ++k) { u[k] = m->uv[ix[k] * 2] * W; v[k] = m->uv[ix[k] * 2 + 1] * H; }
        const float uv_area = 0.5f * fabsf((u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]));
        prt__v3_sub(m->positions + ix[1] * 3, m->positions + ix[0] * 3, e1);
        prt__v3_sub(m->positions + ix[2] * 3, m->positions + ix[0] * 3, e2);
        prt__v3_cross(e1, e2, cr);
        const double world = 0.5 * prt__v3_len(cr);
        if (!(uv_area > 0)) continue;   /* no texels to give it to */
        /* World area per texel-space area: the triangle's footprint in each texel scaled by it. */
        const double scale = world / uv_area;
        const int x0 = (int)fmaxf(floorf(fminf(u[0], fminf(u[1], u[2]))), 0.0f), x1 = (int)fminf(ceilf(fmaxf(u[0], fmaxf(u[1], u[2]))), (float)W);
        const int y0 = (int)fmaxf(floorf(fminf(v[0], fminf(v[1], v[2]))), 0.0f), y1 = (int)fminf(ceilf(fmaxf(v[0], fmaxf(v[1], v[2]))), (float)H);
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                float poly[16][2] = {{u[0], v[0]}, {u[1], v[1]}, {u[2], v[2]}};
                int n = 3;
                n = clip_axis(poly, n, 0, (float)x, -1.0f);
                n = clip_axis(poly, n, 0, (float)(x + 1), 1.0f);
                n = clip_axis(poly, n, 1, (float)y, -1.0f);
                n = clip_axis(poly, n, 1, (float)(y + 1), 1.0f);
                double a = 0;
                for (int k = 0; k < n; ++k) a += (double)poly[k][0] * poly[(k + 1) % n][1] - (double)poly[(k + 1) % n][0] * poly[k][1];
                acc[(size_t)y * W + x] += 0.5 * fabs(a) * scale;
            }
    }
    for (size_t i = 0; i < ntex; ++i) area[i] = (float)acc[i];
    free(acc);
    return true;
}

/* Fills every uncovered texel, ring by ring outwards from the baked ones, with the mean of its
 * neighbours in earlier rings: bilinear filtering and mip-maps then never pull in black across a
 * chart's border. covered: 0 outside every chart -> 2 filled. */
bool prt__texel_fill_gutters(int width, int height, uint8_t *covered, float **planes, const int *floats, int nplanes)
{
    const size_t n = (size_t)width * height;
    uint32_t *ring = malloc(n * sizeof *ring), *next = malloc(n * sizeof *next);
    if (!ring || !next) { free(ring); free(next); return false; }
    size_t count = 0;
    const int dx[4] = {-1, 1, 0, 0}, dy[4] = {0, 0, -1, 1};
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            size_t i = (size_t)y * width + x;
            if (covered[i]) continue;
            for (int k = 0; k < 4; ++k) {
                int u = x + dx[k], v = y + dy[k];
                if (u >= 0 && u < width && v >= 0 && v < height && covered[(size_t)v * width + u] == 1) { covered[i] = 3; ring[count++] = (uint32_t)i; break; }
            }
        }
    while (count) {
        for (size_t r = 0; r < count; ++r) {
            const size_t i = ring[r];
            const int x = (int)(i % width), y = (int)(i / width);
            size_t nb[4];
            int m = 0;
            for (int k = 0; k < 4; ++k) {
                int u = x + dx[k], v = y + dy[k];
                if (u < 0 || u >= width || v < 0 || v >= height) continue;
                size_t j = (size_t)v * width + u;
                if (covered[j] == 1 || covered[j] == 2) nb[m++] = j;
            }
            for (int pl = 0; pl < nplanes; ++pl) {
                if (!planes[pl]) continue;
                float *dst = planes[pl] + i * floats[pl];
                for (int f = 0; f < floats[pl]; ++f) {
                    float sum = 0;
                    for (int k = 0; k < m; ++k) sum += planes[pl][nb[k] * floats[pl] + f];
                    dst[f] = sum / m;
                }
            }
        }
        size_t next_count = 0;
        for (size_t r = 0; r < count; ++r) covered[ring[r]] = 2;
        for (size_t r = 0; r < count; ++r) {
            const size_t i = ring[r];
            const int x = (int)(i % width), y = (int)(i / width);
            for (int k = 0; k < 4; ++k) {
                int u = x + dx[k], v = y + dy[k];
                if (u < 0 || u >= width || v < 0 || v >= height) continue;
                size_t j = (size_t)v * width + u;
                if (!covered[j]) { covered[j] = 3; next[next_count++] = (uint32_t)j; }
            }
        }
        uint32_t *tmp = ring; ring = next; next = tmp;
        count = next_count;
    }
    free(ring);
    free(next);
    return true;
}

/* Neighbour k (left, right, down, up) of texel i inside a width x height map, or false. */
static bool neighbour(int width, int height, size_t i, int k, size_t *j)
{
    static const int dx[4] = {-1, 1, 0, 0}, dy[4] = {0, 0, -1, 1};
    const int u = (int)(i % (size_t)width) + dx[k], v = (int)(i / (size_t)width) + dy[k];
    if (u < 0 || u >= width || v < 0 || v >= height) return false;
    *j = (size_t)v * width + u;
    return true;
}

bool prt__texel_gutter_sources(int width, int height, const int32_t *index, int32_t *source)
{
    const size_t n = (size_t)width * height;
    uint32_t *ring = malloc(n * sizeof *ring + 1), *next = malloc(n * sizeof *next + 1);
    uint8_t *state = malloc(n + 1);   /* 0 unreached, 1 in an earlier ring, 2 queued for the next */
    if (!ring || !next || !state) { free(ring); free(next); free(state); return false; }
    size_t count = 0, j;
    for (size_t i = 0; i < n; ++i) {
        source[i] = index[i] >= 0 ? index[i] : -1;
        state[i] = index[i] >= 0;
    }
    /* The first ring: uncovered texels beside the surface. */
    for (size_t i = 0; i < n; ++i) {
        if (state[i]) continue;
        for (int k = 0; k < 4; ++k)
            if (neighbour(width, height, i, k, &j) && state[j] == 1) { ring[count++] = (uint32_t)i; state[i] = 2; break; }
    }
    while (count) {
        /* Sources come only from earlier rings: read them all before marking this one. */
        for (size_t r = 0; r < count; ++r)
            for (int k = 0; k < 4; ++k)
                if (neighbour(width, height, ring[r], k, &j) && state[j] == 1) { source[ring[r]] = source[j]; break; }
        for (size_t r = 0; r < count; ++r) state[ring[r]] = 1;
        size_t next_count = 0;
        for (size_t r = 0; r < count; ++r)
            for (int k = 0; k < 4; ++k)
                if (neighbour(width, height, ring[r], k, &j) && state[j] == 0) { state[j] = 2; next[next_count++] = (uint32_t)j; }
        uint32_t *tmp = ring; ring = next; next = tmp;
        count = next_count;
    }
    free(ring);
    free(next);
    free(state);
    return true;
}
