/* Texel patches of a UV layout: which triangle each texel samples, and how much surface each
 * texel covers. Shared by every method that bakes transfer per texel. */
#include "geom/texel_raster.h"

#include "geom/uv_islands.h"

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

/* A triangle's corners (position, then UV) sorted, so that one face either way round gives one key. */
typedef struct face_key { float c[3][5]; uint32_t t; } face_key;
static int corner_cmp(const float *a, const float *b)
{
    for (int k = 0; k < 5; ++k)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}
static int face_cmp(const void *x, const void *y)
{
    const face_key *p = x, *q = y;
    for (int k = 0; k < 3; ++k) {
        const int c = corner_cmp(p->c[k], q->c[k]);
        if (c) return c;
    }
    return p->t < q->t ? -1 : p->t > q->t;
}

uint8_t *prt__texel_duplicates(const prt__mesh *m)
{
    const size_t nt = m->triangle_count;
    face_key *key = malloc(nt * sizeof *key + 1);
    uint8_t *skip = prt__calloc(nt + 1, 1);
    if (!key || !skip) { free(key); free(skip); return NULL; }
    for (size_t t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m->indices[t * 3 + k];
            memcpy(key[t].c[k], m->positions + v * 3, 3 * sizeof(float));
            memcpy(key[t].c[k] + 3, m->uv + v * 2, 2 * sizeof(float));
        }
        for (int i = 1; i < 3; ++i)   /* three corners: insertion sort */
            for (int j = i; j > 0 && corner_cmp(key[t].c[j - 1], key[t].c[j]) > 0; --j) {
                float tmp[5];
                memcpy(tmp, key[t].c[j], sizeof tmp);
                memcpy(key[t].c[j], key[t].c[j - 1], sizeof tmp);
                memcpy(key[t].c[j - 1], tmp, sizeof tmp);
            }
        key[t].t = (uint32_t)t;
    }
    qsort(key, nt, sizeof *key, face_cmp);
    for (size_t i = 0; i < nt;) {
        size_t j = i + 1;
        while (j < nt && !corner_cmp(key[j].c[0], key[i].c[0]) && !corner_cmp(key[j].c[1], key[i].c[1]) && !corner_cmp(key[j].c[2], key[i].c[2])) j++;
        if (j - i > 1) {
            size_t keep = i;   /* the first not mirrored in UV, else the first */
            for (size_t k = i; k < j; ++k) {
                const uint32_t *ix = m->indices + (size_t)key[k].t * 3;
                const float *a = m->uv + ix[0] * 2, *b = m->uv + ix[1] * 2, *c = m->uv + ix[2] * 2;
                if ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]) > 0) { keep = k; break; }
            }
            for (size_t k = i; k < j; ++k) skip[key[k].t] = k != keep;
        }
        i = j;
    }
    free(key);
    return skip;
}

/* How far inside a chart a border texel's sample lies, in texels (prt__texel_raster). */
#define BORDER_INSET 0.25f

/* The point (b1, b2) of triangle (u, v) (texel units) moved towards its centroid, away from where
 * surfaces touch: BORDER_INSET of a texel, at most a fifth of the way (a sliver's centroid may lie
 * texels away, and the sample must stay in its texel's reach). Barycentrics into out. */
static void inset(const float u[3], const float v[3], float b1, float b2, float out[2])
{
    const float gu = (u[0] + u[1] + u[2]) / 3, gv = (v[0] + v[1] + v[2]) / 3;
    const float qu = u[0] + b1 * (u[1] - u[0]) + b2 * (u[2] - u[0]), qv = v[0] + b1 * (v[1] - v[0]) + b2 * (v[2] - v[0]);
    const float to_g = sqrtf((gu - qu) * (gu - qu) + (gv - qv) * (gv - qv));
    const float f = to_g > 0 ? fminf(0.2f, BORDER_INSET / to_g) : 0.0f;
    out[0] = (1 - f) * b1 + f / 3;
    out[1] = (1 - f) * b2 + f / 3;
}

/* Does triangle (u, v) (texel units) meet the open square of half-side r about (px, py)?
 * Separating axes: the square's two, the triangle's edge normals. */
static bool meets_square(const float u[3], const float v[3], float px, float py, float r)
{
    if (fminf(u[0], fminf(u[1], u[2])) >= px + r || fmaxf(u[0], fmaxf(u[1], u[2])) <= px - r) return false;
    if (fminf(v[0], fminf(v[1], v[2])) >= py + r || fmaxf(v[0], fmaxf(v[1], v[2])) <= py - r) return false;
    for (int e = 0; e < 3; ++e) {
        const int j = (e + 1) % 3, k = (e + 2) % 3;
        const float nx = v[j] - v[e], ny = u[e] - u[j], half = r * (fabsf(nx) + fabsf(ny));
        if (!(half > 0)) continue;
        const float a = nx * u[e] + ny * v[e], b = nx * u[k] + ny * v[k], c = nx * px + ny * py;
        if (fmaxf(a, b) <= c - half || fminf(a, b) >= c + half) return false;
    }
    return true;
}

bool prt__texel_raster(const prt__mesh *m, int W, int H, uint32_t *owner, float *bary, size_t *overlap_out, size_t *outside_out)
{
    /* Rasterize the UV layout: texel (x, y) has its centre at ((x + .5) / W, (y + .5) / H); the
     * first triangle to cover a texel owns it, later ones count as overlap. */
    size_t overlap = 0, outside = 0;
    const size_t ntex = (size_t)W * H;
    uint8_t *dup = prt__texel_duplicates(m);
    if (!dup) return false;
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        if (dup[t]) continue;
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
     * chart's light. */
    {
        float *near = malloc(ntex * sizeof *near);
        uint8_t *owns = prt__calloc(m->triangle_count, 1);
        if (!near || !owns) { free(near); free(owns); free(dup); return false; }
        for (size_t i = 0; i < ntex; ++i) {
            near[i] = INFINITY;
            if (owner[i]) owns[owner[i] - 1] = 1;
        }
        for (size_t t = 0; t < m->triangle_count; ++t) {
            if (owns[t] || dup[t]) continue;
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
                    inset(u, v, b1, b2, bary + i * 2);
                }
        }
        /* Border texels: those a chart's triangles cover part of but not the centre. Bilinear
         * reads on the chart weigh them, so they hold the chart's own surface, sampled at the
         * point nearest the centre (the light there is what the centre would extrapolate), inset
         * as a sliver's, away from where surfaces touch (a sphere resting on the floor). Their
         * surface counts then, not only the gutter fill's copy of the next texel in. */
        for (size_t i = 0; i < ntex; ++i) near[i] = owner[i] ? -1.0f : INFINITY;
        for (size_t t = 0; t < m->triangle_count; ++t) {
            if (dup[t]) continue;
            const uint32_t *ix = m->indices + t * 3;
            float u[3], v[3];
            for (int k = 0; k < 3; ++k) { u[k] = m->uv[ix[k] * 2] * W; v[k] = m->uv[ix[k] * 2 + 1] * H; }
            if ((u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]) == 0.0f) continue;
            const int x0 = (int)fmaxf(floorf(fminf(u[0], fminf(u[1], u[2]))), 0.0f), x1 = (int)fminf(ceilf(fmaxf(u[0], fmaxf(u[1], u[2]))), (float)W);
            const int y0 = (int)fmaxf(floorf(fminf(v[0], fminf(v[1], v[2]))), 0.0f), y1 = (int)fminf(ceilf(fmaxf(v[0], fmaxf(v[1], v[2]))), (float)H);
            for (int y = y0; y < y1; ++y)
                for (int x = x0; x < x1; ++x) {
                    const size_t i = (size_t)y * W + x;
                    if (near[i] < 0 || !meets_square(u, v, x + 0.5f, y + 0.5f, 0.5f)) continue;
                    float b1 = 0, b2 = 0, d2 = nearest_on_triangle(u, v, x + 0.5f, y + 0.5f, &b1, &b2);
                    if (d2 >= near[i]) continue;
                    near[i] = d2;
                    owner[i] = (uint32_t)t + 1;
                    inset(u, v, b1, b2, bary + i * 2);
                }
        }
        free(near);
        free(owns);
    }
    free(dup);
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
    uint8_t *dup = acc ? prt__texel_duplicates(m) : NULL;
    if (!acc || !dup) { free(acc); return false; }
    for (size_t t = 0; t < m->triangle_count; ++t) {
        if (dup[t]) continue;
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
                /* Where the triangle only runs along the texel's edge or through its corner, the
                 * clipping below leaves rounding (1e-9 of a texel) that the raster, asking the
                 * same question as here, does not sample: such a texel holds none of it. */
                if (!meets_square(u, v, x + 0.5f, y + 0.5f, 0.5f)) continue;
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
    free(dup);
    return true;
}

prt_status prt__texel_support_charts(const prt_context *ctx, const prt__mesh *m, int W, int H, int32_t *label)
{
    const size_t n = (size_t)W * H, nt = m->triangle_count;
    uint32_t *island = malloc(nt * sizeof *island + 1), count = 0, *owner = prt__calloc(n, sizeof *owner);
    float *bary = malloc(n * 2 * sizeof *bary + 1);
    size_t overlap, outside;
    if (!island || !owner || !bary) { free(island); free(owner); free(bary); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %dx%d texels", W, H); }
    prt_status st = prt__uv_islands(ctx, m, island, &count);
    if (!st && !prt__texel_raster(m, W, H, owner, bary, &overlap, &outside)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for %dx%d texels", W, H);
    for (size_t i = 0; !st && i < n; ++i) label[i] = owner[i] ? (int32_t)island[owner[i] - 1] : -1;
    /* A texel a bilinear read reaches has its centre within a texel of the read: within 1 on
     * both axes of some point of the chart. The first triangle's chart, where layouts not made
     * for it (a mesh's own UVs) let several reach one texel. */
    for (size_t t = 0; !st && t < nt; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        float u[3], v[3];
        for (int k = 0; k < 3; ++k) { u[k] = m->uv[ix[k] * 2] * W; v[k] = m->uv[ix[k] * 2 + 1] * H; }
        const int x0 = (int)fmaxf(floorf(fminf(u[0], fminf(u[1], u[2])) - 1.0f), 0.0f), x1 = (int)fminf(ceilf(fmaxf(u[0], fmaxf(u[1], u[2])) + 1.0f), (float)W);
        const int y0 = (int)fmaxf(floorf(fminf(v[0], fminf(v[1], v[2])) - 1.0f), 0.0f), y1 = (int)fminf(ceilf(fmaxf(v[0], fmaxf(v[1], v[2])) + 1.0f), (float)H);
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                int32_t *l = label + (size_t)y * W + x;
                if (*l < 0 && meets_square(u, v, x + 0.5f, y + 0.5f, 1.0f)) *l = (int32_t)island[t];
            }
    }
    free(island);
    free(owner);
    free(bary);
    return st;
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

/* The rings of a gutter fill, outwards from the texels that have values (ring 0). First the texels
 * of charts' supports (label >= 0), each reached only from its own chart's texels (rings 1 .. the
 * returned split); then every texel left, from any (rings above split). order: every texel
 * reached, ring by ring, *count of them; ring: each texel's, -1 unreached. A texel then takes its
 * value from its neighbours in earlier rings that may_take allows. */
static int32_t rings(int width, int height, const uint8_t *have, const int32_t *label, int32_t *ring, uint32_t *order, size_t *count)
{
    const size_t n = (size_t)width * height;
    size_t done = 0, j;
    for (size_t i = 0; i < n; ++i) {
        ring[i] = have[i] ? 0 : -1;
        if (have[i]) order[done++] = (uint32_t)i;
    }
    int32_t r = 0, split = 0;
    for (int phase = label ? 0 : 1; phase < 2; ++phase) {
        size_t head = 0, first = done;   /* the front: phase one's the valued texels, phase two's all reached */
        while (head < first) {
            bool grew = false;
            for (size_t q = head; q < first; ++q)
                for (int k = 0; k < 4; ++k) {
                    if (!neighbour(width, height, order[q], k, &j) || ring[j] >= 0) continue;
                    if (phase == 0 && (label[j] < 0 || label[j] != label[order[q]])) continue;
                    ring[j] = r + 1;
                    order[done++] = (uint32_t)j;
                    grew = true;
                }
            r += grew;
            head = first;
            first = done;
        }
        if (phase == 0) split = r;
    }
    *count = done;
    return split;
}

/* May texel i (ring ri) take its value from neighbour j? From an earlier ring, and inside a
 * chart's support (ri <= split) only from the same chart. */
static bool may_take(const int32_t *ring, const int32_t *label, int32_t split, size_t i, size_t j)
{
    return ring[j] >= 0 && ring[j] < ring[i] && (ring[i] > split || label[j] == label[i]);
}

/* Fills every uncovered texel, ring by ring (see rings), with the mean of its neighbours in earlier
 * rings: bilinear filtering and mip-maps then never pull in black across a chart's border, nor,
 * with labels, another chart's values. covered: 0 outside every chart -> 2 filled. */
bool prt__texel_fill_gutters(int width, int height, const int32_t *label, uint8_t *covered, float **planes, const int *floats, int nplanes)
{
    const size_t n = (size_t)width * height;
    uint32_t *order = malloc(n * sizeof *order + 1);
    int32_t *ring = malloc(n * sizeof *ring + 1);
    if (!order || !ring) { free(order); free(ring); return false; }
    size_t count = 0, j;
    const int32_t split = rings(width, height, covered, label, ring, order, &count);
    for (size_t q = 0; q < count; ++q) {
        const size_t i = order[q];
        if (!ring[i]) continue;
        size_t nb[4];
        int m = 0;
        for (int k = 0; k < 4; ++k)
            if (neighbour(width, height, i, k, &j) && may_take(ring, label, split, i, j)) nb[m++] = j;
        for (int pl = 0; pl < nplanes; ++pl) {
            if (!planes[pl]) continue;
            float *dst = planes[pl] + i * floats[pl];
            for (int f = 0; f < floats[pl]; ++f) {
                float sum = 0;
                for (int k = 0; k < m; ++k) sum += planes[pl][nb[k] * floats[pl] + f];
                dst[f] = m ? sum / m : 0.0f;
            }
        }
        covered[i] = 2;
    }
    free(order);
    free(ring);
    return true;
}

bool prt__texel_gutter_sources(int width, int height, const int32_t *index, const int32_t *label, int32_t *source)
{
    const size_t n = (size_t)width * height;
    uint32_t *order = malloc(n * sizeof *order + 1);
    int32_t *ring = malloc(n * sizeof *ring + 1);
    uint8_t *have = malloc(n + 1);
    if (!order || !ring || !have) { free(order); free(ring); free(have); return false; }
    for (size_t i = 0; i < n; ++i) {
        source[i] = index[i] >= 0 ? index[i] : -1;
        have[i] = index[i] >= 0;
    }
    size_t count = 0, j;
    const int32_t split = rings(width, height, have, label, ring, order, &count);
    for (size_t q = 0; q < count; ++q) {
        const size_t i = order[q];
        if (!ring[i]) continue;
        for (int k = 0; k < 4; ++k)
            if (neighbour(width, height, i, k, &j) && may_take(ring, label, split, i, j)) { source[i] = source[j]; break; }
    }
    free(order);
    free(ring);
    free(have);
    return true;
}
