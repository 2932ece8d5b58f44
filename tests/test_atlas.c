/* Generated UV atlases: charts never overlap and keep a gutter between them, every triangle maps
 * with bounded stretch, the surface is unchanged, the layout is deterministic, and per-texel
 * transfer over it matches the closed form on a convex object with every gutter texel filled. */
#include "common.h"

#include "geom/texel_raster.h"
#include "geom/uv_atlas.h"

/* A sphere with radial noise, like a scan: normals swing from triangle to triangle. */
static void bumpy_sphere(test_mesh *m, int rings, int segs, float noise)
{
    tm_sphere(m, (float[3]){0, 0, 0}, 1.0f, rings, segs);
    uint32_t h = 12345;
    for (size_t v = 0; v < m->nv; ++v) {
        h = h * 1664525u + 1013904223u;
        float k = 1.0f + noise * ((float)(h >> 8) / 16777216.0f - 0.5f);
        for (int c = 0; c < 3; ++c) m->pos[v * 3 + c] *= k;
    }
}

/* Union-find over triangles sharing a corner: the same position with the same UV (inside a
 * chart, vertices the input split by normals still share both; seams give copies other UVs). */
static size_t find(size_t *p, size_t i)
{
    while (p[i] != i) i = p[i] = p[p[i]];
    return i;
}

static const prt__mesh *corner_mesh;
static int by_corner(const void *x, const void *y)
{
    const uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    int c = memcmp(corner_mesh->positions + a * 3, corner_mesh->positions + b * 3, 3 * sizeof(float));
    if (!c) c = memcmp(corner_mesh->uv + a * 2, corner_mesh->uv + b * 2, 2 * sizeof(float));
    return c ? c : (a > b) - (a < b);
}

static size_t *chart_of_triangles(const prt__mesh *m)
{
    size_t *parent = malloc(m->triangle_count * sizeof *parent), *by_vertex = malloc(m->vertex_count * sizeof *by_vertex);
    uint32_t *order = malloc(m->vertex_count * sizeof *order), *canon = malloc(m->vertex_count * sizeof *canon);
    for (size_t v = 0; v < m->vertex_count; ++v) order[v] = (uint32_t)v;
    corner_mesh = m;
    qsort(order, m->vertex_count, sizeof *order, by_corner);
    for (size_t k = 0; k < m->vertex_count; ++k) {
        const uint32_t v = order[k], u = k ? order[k - 1] : v;
        const bool same = k && !memcmp(m->positions + v * 3, m->positions + u * 3, 12) && !memcmp(m->uv + v * 2, m->uv + u * 2, 8);
        canon[v] = same ? canon[u] : v;
    }
    for (size_t t = 0; t < m->triangle_count; ++t) parent[t] = t;
    for (size_t v = 0; v < m->vertex_count; ++v) by_vertex[v] = SIZE_MAX;
    for (size_t t = 0; t < m->triangle_count; ++t)
        for (int k = 0; k < 3; ++k) {
            uint32_t v = canon[m->indices[t * 3 + k]];
            if (by_vertex[v] == SIZE_MAX) by_vertex[v] = t;
            else parent[find(parent, t)] = find(parent, by_vertex[v]);
        }
    for (size_t t = 0; t < m->triangle_count; ++t) parent[t] = find(parent, t);
    free(by_vertex);
    free(order);
    free(canon);
    return parent;
}

/* Does a bilinear read somewhere on triangle (u, v) (texel units) weigh the texel centred at
 * (px, py)? A point of the triangle within one texel of it on both axes (the triangle clipped to
 * that square keeps some area; a hair under one texel for the UVs' float rounding). */
static bool reaches(const float u[3], const float v[3], float px, float py)
{
    const float r = 1.0f - 1e-4f;
    float poly[12][2];
    int n = 3;
    for (int k = 0; k < 3; ++k) { poly[k][0] = u[k]; poly[k][1] = v[k]; }
    for (int side = 0; side < 4 && n; ++side) {
        const int axis = side / 2;
        const float sign = side % 2 ? 1.0f : -1.0f, at = (axis ? py : px) + sign * r;   /* keep sign (p - at) < 0 */
        float out[12][2];
        int m = 0;
        for (int i = 0; i < n && m < 11; ++i) {
            const float *p = poly[i], *q = poly[(i + 1) % n];
            const float dp = sign * (p[axis] - at), dq = sign * (q[axis] - at);
            if (dp < 0) { out[m][0] = p[0]; out[m][1] = p[1]; m++; }
            if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
                const float f = dp / (dp - dq);
                out[m][0] = p[0] + f * (q[0] - p[0]);
                out[m][1] = p[1] + f * (q[1] - p[1]);
                m++;
            }
        }
        memcpy(poly, out, sizeof out);
        n = m;
    }
    return n > 0;
}

/* Lays out m at res and checks everything an atlas promises; coverage at least min_coverage.
 * The number of charts. */
static size_t check_atlas(prt__mesh *m, int res, const char *what, double min_coverage)
{
    prt_context *ctx = test_context(1);
    const size_t nv0 = m->vertex_count, nt = m->triangle_count;
    float *tri_pos = malloc(nt * 9 * sizeof(float));
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) memcpy(tri_pos + t * 9 + k * 3, m->positions + m->indices[t * 3 + k] * 3, 3 * sizeof(float));
    prt__atlas_report r;
    assert_int_equal(prt__uv_atlas(ctx, m, &(prt__atlas_desc){.resolution = res}, &r), PRT_OK);
    assert_int_equal(m->triangle_count, nt);
    assert_int_equal(m->vertex_count, nv0 + r.added_vertices);
    assert_true(prt__mesh_has_uv(m));
    /* The same surface: every triangle's corners where they were. */
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) assert_memory_equal(tri_pos + t * 9 + k * 3, m->positions + m->indices[t * 3 + k] * 3, 3 * sizeof(float));
    free(tri_pos);
    for (size_t v = 0; v < m->vertex_count * 2; ++v) assert_true(m->uv[v] >= 0.0f && m->uv[v] <= 1.0f);
    /* Bounded stretch, and no triangle turned over but duplicate faces lying on their face's
     * texels (a back-to-back twin runs the other way round); those are the atlas's shared ones. */
    uint8_t *dup = prt__texel_duplicates(m);
    size_t dups = 0;
    double worst = 0, mean = 0;
    for (size_t t = 0; t < nt; ++t) {
        double s = prt__uv_stretch(m, t);
        worst = fmax(worst, s);
        mean += s / nt;
        dups += dup[t];
        const float *a = m->uv + m->indices[t * 3] * 2, *b = m->uv + m->indices[t * 3 + 1] * 2, *c = m->uv + m->indices[t * 3 + 2] * 2;
        if (!dup[t]) assert_true((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]) > 0);
    }
    assert_int_equal(dups, r.shared);
    /* Charts' bilinear reaches apart: no texel centre lies within one texel (on both axes) of two
     * charts, so a bilinear read on one chart never weighs a texel another chart's light is in. */
    size_t *chart = chart_of_triangles(m);
    size_t *owner = malloc((size_t)res * res * sizeof *owner);
    for (size_t i = 0; i < (size_t)res * res; ++i) owner[i] = SIZE_MAX;
    size_t clashes = 0, inside_twice = 0;
    const int fine = 4 * res;
    uint8_t *hit = calloc((size_t)fine * fine, 1);
    for (size_t t = 0; t < nt; ++t) {
        float u[3], v[3], uf[3], vf[3];
        for (int k = 0; k < 3; ++k) {
            u[k] = m->uv[m->indices[t * 3 + k] * 2] * res;
            v[k] = m->uv[m->indices[t * 3 + k] * 2 + 1] * res;
            uf[k] = u[k] * 4;
            vf[k] = v[k] * 4;
        }
        int x0 = (int)floorf(fminf(u[0], fminf(u[1], u[2]))) - 1, x1 = (int)ceilf(fmaxf(u[0], fmaxf(u[1], u[2]))) + 1;
        int y0 = (int)floorf(fminf(v[0], fminf(v[1], v[2]))) - 1, y1 = (int)ceilf(fmaxf(v[0], fmaxf(v[1], v[2]))) + 1;
        for (int y = y0 < 0 ? 0 : y0; y < y1 && y < res; ++y)
            for (int x = x0 < 0 ? 0 : x0; x < x1 && x < res; ++x) {
                if (!reaches(u, v, x + 0.5f, y + 0.5f)) continue;
                size_t *o = owner + (size_t)y * res + x;
                if (*o == SIZE_MAX) *o = chart[t];
                else if (*o != chart[t]) clashes++;
            }
        if (dup[t]) continue;
        /* Overlap at 4x the resolution: a sample strictly inside two triangles. */
        float d = (uf[1] - uf[0]) * (vf[2] - vf[0]) - (uf[2] - uf[0]) * (vf[1] - vf[0]);
        int fx0 = (int)floorf(fminf(uf[0], fminf(uf[1], uf[2]))), fx1 = (int)ceilf(fmaxf(uf[0], fmaxf(uf[1], uf[2])));
        int fy0 = (int)floorf(fminf(vf[0], fminf(vf[1], vf[2]))), fy1 = (int)ceilf(fmaxf(vf[0], fmaxf(vf[1], vf[2])));
        for (int y = fy0 < 0 ? 0 : fy0; y < fy1 && y < fine; ++y)
            for (int x = fx0 < 0 ? 0 : fx0; x < fx1 && x < fine; ++x) {
                float px = x + 0.5f, py = y + 0.5f;
                float b1 = ((px - uf[0]) * (vf[2] - vf[0]) - (uf[2] - uf[0]) * (py - vf[0])) / d;
                float b2 = ((uf[1] - uf[0]) * (py - vf[0]) - (px - uf[0]) * (vf[1] - vf[0])) / d;
                if (b1 <= 1e-4f || b2 <= 1e-4f || b1 + b2 >= 1 - 1e-4f) continue;
                inside_twice += hit[(size_t)y * fine + x]++ != 0;
            }
    }
    print_message("%s: %zu charts (%zu by LSCM), %zu vertices copied, %.0f%% coverage, stretch worst %.2f mean %.3f\n", what, r.charts,
                  r.flattened, r.added_vertices, 100 * r.coverage, worst, mean);
    assert_int_equal(inside_twice, 0);
    assert_int_equal(clashes, 0);
    assert_true(worst <= 4.0 + 1e-3);
    assert_true(mean < 1.2);
    assert_true(fabs(worst - r.worst_stretch) < 1e-9);
    assert_true(r.coverage >= min_coverage);
    /* One texel density: every chart's UV area over its surface area is the map's, to float
     * rounding of the UVs (1e-3 of a chart of a few texels). */
    double *uv_area = calloc(nt, sizeof *uv_area), *world = calloc(nt, sizeof *world);
    for (size_t t = 0; t < nt; ++t) {
        if (dup[t]) continue;   /* on its face's texels */
        const uint32_t *ix = m->indices + t * 3;
        const float *a = m->uv + ix[0] * 2, *b = m->uv + ix[1] * 2, *c = m->uv + ix[2] * 2;
        uv_area[chart[t]] += 0.5 * ((double)(b[0] - a[0]) * (c[1] - a[1]) - (double)(c[0] - a[0]) * (b[1] - a[1])) * res * res;
        float e1[3], e2[3], n[3];
        for (int k = 0; k < 3; ++k) { e1[k] = m->positions[ix[1] * 3 + k] - m->positions[ix[0] * 3 + k]; e2[k] = m->positions[ix[2] * 3 + k] - m->positions[ix[0] * 3 + k]; }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1]; n[1] = e1[2] * e2[0] - e1[0] * e2[2]; n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        world[chart[t]] += 0.5 * sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
    }
    double spread = 0;
    for (size_t t = 0; t < nt; ++t)
        if (world[t] > 0 && uv_area[t] > 4) spread = fmax(spread, fabs(uv_area[t] / world[t] / r.texel_density - 1));
    print_message("%s: texel density %.4g per unit area, charts within %.2g%% of it\n", what, r.texel_density, 100 * spread);
    assert_true(spread < 2e-3);
    /* Every texel a chart's reads reach takes its value from that chart's own texels. */
    {
        const size_t n = (size_t)res * res;
        int32_t *label = malloc(n * sizeof *label), *index = malloc(n * sizeof *index), *source = malloc(n * sizeof *source);
        uint32_t *tri = calloc(n, sizeof *tri);
        float *bary = malloc(n * 2 * sizeof *bary);
        size_t overlap, outside, wrong = 0, reached = 0;
        assert_true(prt__texel_raster(m, res, res, tri, bary, &overlap, &outside));
        /* Every texel the surface touches is sampled (what the per-texel bakes bake and prt info
         * counts), at a point of its own triangle, within a bilinear read's reach of its centre
         * (the chart's point nearest it, within 0.71 texels, moved at most 0.25 inwards; a
         * sliver's once lay a fifth of the way to its centroid, 8.8 texels off in the fan). */
        float *area = malloc(n * sizeof *area);
        assert_true(prt__texel_areas(m, res, res, area));
        size_t touched = 0, sampled = 0;
        double farthest = 0;
        for (size_t i = 0; i < n; ++i) {
            touched += area[i] > 0;
            if (!tri[i]) continue;
            sampled += area[i] > 0;
            const float b1 = bary[i * 2], b2 = bary[i * 2 + 1];
            assert_true(b1 >= -1e-5f && b2 >= -1e-5f && b1 + b2 <= 1 + 1e-5f);
            const uint32_t *ix = m->indices + (size_t)(tri[i] - 1) * 3;
            for (int axis = 0; axis < 2; ++axis) {
                const double q = ((1 - b1 - b2) * m->uv[ix[0] * 2 + axis] + b1 * m->uv[ix[1] * 2 + axis] + b2 * m->uv[ix[2] * 2 + axis]) * res;
                farthest = fmax(farthest, fabs(q - ((axis ? i / (size_t)res : i % (size_t)res) + 0.5)));
            }
        }
        free(area);
        print_message("%s: %zu texels touched, %zu sampled (%.1f%% of the map), samples within %.2f texels of their centres\n", what, touched, sampled,
                      100.0 * sampled / n, farthest);
        assert_int_equal(sampled, touched);
        assert_true(farthest < 1.0);
        for (size_t i = 0; i < n; ++i) index[i] = tri[i] ? (int32_t)i : -1;
        assert_int_equal(prt__texel_support_charts(ctx, m, res, res, label), PRT_OK);
        assert_true(prt__texel_gutter_sources(res, res, index, label, source));
        for (size_t i = 0; i < n; ++i) {
            if (label[i] < 0) continue;
            reached++;
            wrong += source[i] < 0 || label[source[i]] != label[i];
        }
        print_message("%s: %zu texels within the charts' reach, %zu reading another chart\n", what, reached, wrong);
        assert_int_equal(wrong, 0);
        free(label); free(index); free(source); free(tri); free(bary);
    }
    free(uv_area);
    free(world);
    free(hit);
    free(owner);
    free(chart);
    free(dup);
    prt_context_release(ctx);
    return r.charts;
}

static prt__mesh to_mesh(const test_mesh *t)
{
    prt__mesh m = {0};
    assert_int_equal(prt__mesh_append(&m, t->pos, t->nrm, NULL, (float[3]){0.5f, 0.5f, 0.5f}, t->nv, t->idx, t->nt), PRT_OK);
    for (size_t v = 0; v < m.vertex_count * 2; ++v) m.uv[v] = NAN;
    return m;
}

/* A wall around a window built as four pieces meeting at T junctions (grids of different
 * spacing, sharing no edge), as scene files bring them: one chart, its hole kept, so texels
 * across the pieces' seams are neighbours in the map as on the wall. A second wall in another
 * plane, touching it, stays a chart of its own. */
static void test_flat_pieces(void **state)
{
    (void)state;
    test_mesh t = {0};
    tm_quad(&t, (float[3]){0, 0, 0}, (float[3]){3, 0, 0}, (float[3]){0, 1, 0}, 6);   /* below the window */
    tm_quad(&t, (float[3]){0, 2, 0}, (float[3]){3, 0, 0}, (float[3]){0, 1, 0}, 5);   /* above */
    tm_quad(&t, (float[3]){0, 1, 0}, (float[3]){1, 0, 0}, (float[3]){0, 1, 0}, 3);   /* left of it */
    tm_quad(&t, (float[3]){2, 1, 0}, (float[3]){1, 0, 0}, (float[3]){0, 1, 0}, 4);   /* right of it */
    prt__mesh m = to_mesh(&t);
    assert_int_equal(check_atlas(&m, 128, "wall of four pieces", 0.3), 1);
    prt__mesh_free(&m);
    tm_quad(&t, (float[3]){3, 0, 0}, (float[3]){0, 0, -2}, (float[3]){0, 3, 0}, 4);   /* a side wall at x = 3 */
    m = to_mesh(&t);
    assert_int_equal(check_atlas(&m, 128, "two walls", 0.3), 2);
    prt__mesh_free(&m);
    tm_free(&t);
}

static void test_layouts(void **state)
{
    (void)state;
    test_mesh t = {0};
    tm_sphere(&t, (float[3]){0, 0, 0}, 1.0f, 24, 48);
    prt__mesh m = to_mesh(&t);
    check_atlas(&m, 256, "sphere", 0.6);
    prt__mesh_free(&m);
    tm_free(&t);

    bumpy_sphere(&t, 60, 120, 0.03f);
    m = to_mesh(&t);
    check_atlas(&m, 512, "bumpy sphere", 0.65);
    /* Deterministic: the same mesh gives the same layout. */
    prt__mesh m2 = to_mesh(&t);
    prt_context *ctx = test_context(1);
    assert_int_equal(prt__uv_atlas(ctx, &m2, &(prt__atlas_desc){.resolution = 512}, NULL), PRT_OK);
    assert_int_equal(m2.vertex_count, m.vertex_count);
    assert_memory_equal(m2.uv, m.uv, m.vertex_count * 2 * sizeof(float));
    assert_memory_equal(m2.indices, m.indices, m.triangle_count * 3 * sizeof(uint32_t));
    prt__mesh_free(&m2);
    prt__mesh_free(&m);
    tm_free(&t);

    /* A lumpy scan: bumps of several sizes on the noise. Folds in the flattening once cut it into
     * ~800 crumbs (31% at 128); cutting out only the faulty triangles and merging small charts
     * into neighbours leaves ~25 charts. */
    bumpy_sphere(&t, 80, 160, 0.02f);
    for (size_t v = 0; v < t.nv; ++v) {
        float *p = t.pos + v * 3;
        const float k = 1.0f + 0.25f * sinf(5 * p[0]) * sinf(4 * p[1] + 1) * sinf(6 * p[2] + 2) + 0.1f * sinf(13 * p[1]) * sinf(11 * p[0]);
        for (int c = 0; c < 3; ++c) p[c] *= k;
    }
    m = to_mesh(&t);
    check_atlas(&m, 128, "lumpy sphere at 128", 0.6);
    prt__mesh_free(&m);
    m = to_mesh(&t);
    check_atlas(&m, 512, "lumpy sphere", 0.66);   /* 69%: large charts also packed tilted between quarter turns */
    prt__mesh_free(&m);
    tm_free(&t);

    /* A disk as a fan of 3000 slivers: one flat chart whose triangles all meet at the centre
     * (every overlap bucket would hold most of them). */
    {
        test_mesh f = {0};
        tm_vertex(&f, 0, 0, 0, 0, 1, 0);
        for (int i = 0; i < 3000; ++i) {
            const float a = (float)(2 * M_PI * i / 3000);
            tm_vertex(&f, cosf(a), 0, -sinf(a), 0, 1, 0);
            tm_tri(&f, 0, 1 + i, 1 + (i + 1) % 3000);
        }
        m = to_mesh(&f);
        check_atlas(&m, 256, "fan", 0.7);
        prt__mesh_free(&m);
        tm_free(&f);
    }

    tm_pit(&t, 8);   /* a room without a ceiling: five planar charts meeting at right angles */
    m = to_mesh(&t);
    check_atlas(&m, 128, "open box", 0.45);
    prt__mesh_free(&m);
    tm_free(&t);

    /* Too many charts for the map: refused, naming the size that would hold them. */
    tm_sphere(&t, (float[3]){0, 0, 0}, 1.0f, 24, 48);
    m = to_mesh(&t);
    assert_int_equal(prt__uv_atlas(ctx, &m, &(prt__atlas_desc){.resolution = 4}, NULL), PRT_ERR_INVALID_ARG);
    print_message("sphere at 4 x 4: %s\n", prt_last_error());
    assert_non_null(strstr(prt_last_error(), "would hold them"));
    prt__mesh_free(&m);
    tm_free(&t);
    /* 3000 loose triangles: more charts than 64^2 holds whatever their scale (each reaches 2 x 2
     * texels at least); 128^2 holds them. Given a larger map to go to, it goes there. */
    for (uint32_t i = 0; i < 3000; ++i) {
        const float x = (float)(i % 60), z = (float)(i / 60);
        tm_vertex(&t, x, 0, z, 0, 1, 0);
        tm_vertex(&t, x, 0, z + 0.8f, 0, 1, 0);
        tm_vertex(&t, x + 0.8f, 0, z, 0, 1, 0);
        tm_tri(&t, i * 3, i * 3 + 1, i * 3 + 2);
    }
    m = to_mesh(&t);
    assert_int_equal(prt__uv_atlas(ctx, &m, &(prt__atlas_desc){.resolution = 64}, NULL), PRT_ERR_INVALID_ARG);
    print_message("3000 loose triangles at 64 x 64: %s\n", prt_last_error());
    assert_non_null(strstr(prt_last_error(), "3000 UV charts do not fit in 64 x 64 texels: --texels 128 would hold them"));
    prt__atlas_report r;
    assert_int_equal(prt__uv_atlas(ctx, &m, &(prt__atlas_desc){.resolution = 64, .max_resolution = 1024}, &r), PRT_OK);
    print_message("3000 loose triangles from 64 x 64: %d x %d, %.0f%% coverage (%d x %d: fit %d, %.0f%%)\n", r.resolution, r.resolution,
                  100 * r.coverage, r.smaller, r.smaller, r.smaller_fit, 100 * r.smaller_cover);
    assert_true(r.resolution >= 128 && r.resolution <= 1024);
    assert_true(r.coverage >= 0.25 || r.resolution == 1024);
    assert_int_equal(r.smaller, r.resolution / 2);
    prt__mesh_free(&m);
    tm_free(&t);
    prt_context_release(ctx);
}

/* Gutter texels between two charts: a texel within the reach of chart 0's reads takes chart 0's
 * value though chart 1's texel is nearer; texels no chart reaches take the nearest. A row of
 * seven: chart 0 at 0, its reach 1..2, chart 1 at 3, its reach 4, nothing's 5..6. */
static void test_gutters_by_chart(void **state)
{
    (void)state;
    const int32_t index[7] = {0, -1, -1, 1, -1, -1, -1}, label[7] = {0, 0, 0, 1, 1, -1, -1};
    int32_t source[7], blind[7];
    assert_true(prt__texel_gutter_sources(7, 1, index, label, source));
    assert_true(prt__texel_gutter_sources(7, 1, index, NULL, blind));
    const int32_t want[7] = {0, 0, 0, 1, 1, 1, 1};
    assert_memory_equal(source, want, sizeof want);
    assert_int_equal(blind[2], 1);   /* by distance alone, chart 1's texel is the nearer */
    float value[7] = {1, 0, 0, 5, 0, 0, 0};
    uint8_t covered[7] = {1, 0, 0, 1, 0, 0, 0};
    float *planes[1] = {value};
    const int floats[1] = {1};
    assert_true(prt__texel_fill_gutters(7, 1, label, covered, planes, floats, 1));
    const float filled[7] = {1, 1, 1, 5, 5, 5, 5};
    for (int i = 0; i < 7; ++i) assert_float_equal(value[i], filled[i], 0);
    for (int i = 0; i < 7; ++i) assert_int_equal(covered[i], i == 0 || i == 3 ? 1 : 2);
}

/* Back-to-back twins, as decimated scans have them: a triangle of a closed sphere doubled the
 * other way round (facing in, no neighbour of its own) lies on its face's texels, sharing its UVs:
 * drawn where it fights its face for the pixels, it shows the same light, and the per-texel bakes
 * give the texels its face's surface and area. A loose double-sided triangle (a fin, both sides
 * seen) keeps texels for each side, one chart of two glued along the longest edge. */
static void test_twins(void **state)
{
    (void)state;
    test_mesh t = {0};
    tm_sphere(&t, (float[3]){0, 0, 0}, 1.0f, 12, 24);
    const size_t nt0 = t.nt;
    const uint32_t face = 40;
    tm_tri(&t, t.idx[face * 3], t.idx[face * 3 + 2], t.idx[face * 3 + 1]);
    const uint32_t fin = (uint32_t)t.nv;
    tm_vertex(&t, 2, 0, 0, 0, 0, 1);
    tm_vertex(&t, 2.4f, 0, 0, 0, 0, 1);
    tm_vertex(&t, 2.1f, 0.3f, 0, 0, 0, 1);
    tm_tri(&t, fin, fin + 1, fin + 2);
    tm_tri(&t, fin, fin + 2, fin + 1);
    prt__mesh m = to_mesh(&t), twin = to_mesh(&t);
    tm_free(&t);
    prt__mesh plain = {0};
    test_mesh s = {0};
    tm_sphere(&s, (float[3]){0, 0, 0}, 1.0f, 12, 24);
    plain = to_mesh(&s);
    tm_free(&s);
    prt_context *ctx = test_context(1);
    prt__atlas_report rp;
    assert_int_equal(prt__uv_atlas(ctx, &plain, &(prt__atlas_desc){.resolution = 128}, &rp), PRT_OK);
    const size_t charts = check_atlas(&m, 128, "sphere with a twin and a fin", 0.5);
    /* The fin's chart; the twin none. Large charts may be cut for packing, in one map and not the
     * other: counted before. */
    prt__atlas_report rt;
    assert_int_equal(prt__uv_atlas(ctx, &twin, &(prt__atlas_desc){.resolution = 128}, &rt), PRT_OK);
    assert_int_equal(charts, rt.charts);
    assert_int_equal(rt.charts - rt.cut, rp.charts - rp.cut + 1);
    prt__mesh_free(&twin);
    /* The twin on its face's UVs, corner by corner at the same position. */
    const uint32_t tw = (uint32_t)nt0;
    for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.indices[tw * 3 + k];
        bool found = false;
        for (int j = 0; j < 3; ++j) {
            const uint32_t w = m.indices[face * 3 + j];
            if (!memcmp(m.positions + v * 3, m.positions + w * 3, 12)) { found = true; assert_memory_equal(m.uv + v * 2, m.uv + w * 2, 8); }
        }
        assert_true(found);
    }
    /* No texel is the twin's; the texels' areas sum to the surface less the twin. */
    const int res = 128;
    uint32_t *owner = calloc((size_t)res * res, sizeof *owner);
    float *bary = calloc((size_t)res * res * 2, sizeof *bary), *area = calloc((size_t)res * res, sizeof *area);
    size_t overlap, outside, faces = 0;
    assert_true(prt__texel_raster(&m, res, res, owner, bary, &overlap, &outside));
    assert_true(prt__texel_areas(&m, res, res, area));
    double sum = 0, surface = 0;
    for (size_t i = 0; i < (size_t)res * res; ++i) {
        assert_true(owner[i] != tw + 1);
        faces += owner[i] == face + 1;
        sum += area[i];
    }
    for (size_t f = 0; f < m.triangle_count; ++f) {
        if (f == tw) continue;
        const uint32_t *ix = m.indices + f * 3;
        float e1[3], e2[3], n[3];
        for (int k = 0; k < 3; ++k) { e1[k] = m.positions[ix[1] * 3 + k] - m.positions[ix[0] * 3 + k]; e2[k] = m.positions[ix[2] * 3 + k] - m.positions[ix[0] * 3 + k]; }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1]; n[1] = e1[2] * e2[0] - e1[0] * e2[2]; n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        surface += 0.5 * sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
    }
    print_message("twin's face owns %zu texels, the twin none; texel areas %.5f of a surface of %.5f without the twin\n", faces, sum, surface);
    assert_true(faces > 0);
    assert_int_equal(overlap, 0);
    assert_true(fabs(sum - surface) < 1e-4 * surface);
    /* The fin: both sides' texels, the back side the front's mirrored over the longest edge. */
    const uint32_t f0 = (uint32_t)nt0 + 1, f1 = (uint32_t)nt0 + 2;
    size_t own0 = 0, own1 = 0;
    for (size_t i = 0; i < (size_t)res * res; ++i) { own0 += owner[i] == f0 + 1; own1 += owner[i] == f1 + 1; }
    print_message("fin: %zu and %zu texels\n", own0, own1);
    assert_true(own0 > 0 && own1 > 0);
    free(owner); free(bary); free(area);
    prt__mesh_free(&m);
    prt__mesh_free(&plain);
    prt_context_release(ctx);
}

static void test_real_meshes(void **state)
{
    (void)state;
    const char *dir = shared_data_dir();
    const char *names[] = {"meshes/bunny/bun_zipper.ply", "meshes/teapot/teapot.obj"};
    for (int i = 0; i < 2; ++i) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir ? dir : "", names[i]);
        if (!dir || access(path, R_OK)) { print_message("skipped %s: %s not found (../shared/data)\n", names[i], path); continue; }
        prt_context *ctx = test_context(1);
        prt_scene *s = NULL;
        assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
        /* The bunny at 512: 73% (65% before large charts were also tried tilted between quarter
         * turns). At 128, issue 30's 70% (66.9% while two-texel gutters kept charts apart rather
         * than their bilinear reaches). */
        check_atlas(&s->mesh, 512, names[i], i == 0 ? 0.70 : 0.64);
        if (i == 0) {   /* the bunny at the offset method's default light map */
            prt_scene *s2 = NULL;
            assert_int_equal(prt_scene_load(ctx, path, NULL, &s2), PRT_OK);
            check_atlas(&s2->mesh, 128, "bunny at 128", 0.70);
            prt_scene_release(s2);
        }
        prt_scene_release(s);
        prt_context_release(ctx);
    }
}

/* Issue 30: at the offset method's default light map (128^2) the atlas of a scan covers at least
 * 70% of the texels with surface it bakes (prt info's atlas_coverage). Texels a chart's border
 * only crosses count since they are sampled at the chart's surface nearest their centre: coarse
 * scans, their triangles a texel or larger, gained most (the dragon's res4 66 -> 74%, the teapot
 * 63 -> 71%). The bunny at 128 is checked in test_real_meshes. */
static void test_scan_coverage(void **state)
{
    (void)state;
    /* Procedural, no data needed: a coarse bumpy sphere, its triangles several texels wide. */
    test_mesh t = {0};
    bumpy_sphere(&t, 16, 32, 0.03f);
    prt__mesh pm = to_mesh(&t);
    check_atlas(&pm, 128, "coarse bumpy sphere at 128", 0.71);   /* 72.6% (68.6% in one order of its six charts) */
    prt__mesh_free(&pm);
    tm_free(&t);
    const char *dir = shared_data_dir();
    /* The low-resolution bunny (18 charts, four of 15-29% of the surface, ragged) packed to 65%
     * until the atlas cut large ragged charts in two for packing: 73.8% (21 charts). */
    const struct { const char *name; double min; } scans[] = {
        {"meshes/dragon/dragon_vrip_res3.ply", 0.70}, {"meshes/dragon/dragon_vrip_res4.ply", 0.70},
        {"meshes/teapot/teapot.obj", 0.70}, {"meshes/bunny/bunny_lowres.obj", 0.70},
    };
    for (size_t i = 0; i < sizeof scans / sizeof *scans; ++i) {
        char path[1024], what[128];
        snprintf(path, sizeof path, "%s/%s", dir ? dir : "", scans[i].name);
        if (!dir || access(path, R_OK)) { print_message("skipped %s: %s not found (../shared/data)\n", scans[i].name, path); continue; }
        prt_context *ctx = test_context(1);
        prt_scene *s = NULL;
        assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
        snprintf(what, sizeof what, "%s at 128", scans[i].name);
        check_atlas(&s->mesh, 128, what, scans[i].min);
        prt_scene_release(s);
        prt_context_release(ctx);
    }
}

/* The Stanford dragon's crude decimation: edges shared by 4-8 triangles, back-to-back duplicate
 * faces, pinched vertices. It once gave ~3400 charts and did not fit 128 or 256 texels. */
static void test_dragon(void **state)
{
    (void)state;
    const char *dir = shared_data_dir();
    char path[1024];
    snprintf(path, sizeof path, "%s/meshes/dragon/dragon_vrip_res3.ply", dir ? dir : "");
    if (!dir || access(path, R_OK)) { print_message("skipped the dragon: %s not found (../shared/data)\n", path); return; }
    prt_context *ctx = test_context(1);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    /* Of its 1555 charts, 1104 were single triangles, most the inward twin of a face of the closed
     * surface (on its face's texels now), the rest loose double-sided triangles (a chart of two). */
    assert_true(check_atlas(&s->mesh, 256, "dragon res3 at 256", 0.65) < 1000);
    prt_scene_release(s);
    prt_context_release(ctx);
}

/* Per-texel transfer of a convex object without UVs: every texel of the generated atlas, baked or
 * filled in a gutter, holds the unoccluded clamped cosine's DC term. */
static void test_texels_on_atlas(void **state)
{
    (void)state;
    prt_context *ctx = test_context(2);
    test_mesh t = {0};
    tm_sphere(&t, (float[3]){0, 0, 0}, 1.0f, 16, 32);
    prt_scene *s = tm_scene(ctx, &t, 0.5f);
    prt_bake_desc d = {0};
    d.order = 1;
    d.samples = 4096;
    d.kinds = PRT_TRANSFER_UNSHADOWED | PRT_TRANSFER_SHADOWED;
    d.texels = 64;
    prt_transfer *x = NULL;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &x), PRT_OK);
    assert_non_null(prt_transfer_uvs(x));
    assert_true(prt_transfer_vertex_count(x) > t.nv);   /* seams copy vertices */
    int w, h;
    assert_true(prt_transfer_texel_size(x, &w, &h) && w == 64 && h == 64);
    const float *U = prt_transfer_texel_coeffs(x, PRT_TRANSFER_UNSHADOWED, NULL), *S = prt_transfer_texel_coeffs(x, PRT_TRANSFER_SHADOWED, NULL);
    double worst = 0;
    for (int i = 0; i < w * h; ++i) {
        worst = fmax(worst, fabs(U[i] - 0.28209479));
        worst = fmax(worst, fabs(S[i] - 0.28209479));
    }
    print_message("sphere without UVs, 64x64 texels: worst |T_00 - 0.2821| %.4f over every texel\n", worst);
    assert_true(worst < 0.01);
    prt_transfer_release(x);
    /* Only the mesh's own UVs: refused, saying why. */
    d.uv_layout = PRT_UV_MESH;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &x), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "texture coordinates"));
    /* A normal map follows the mesh's own UVs, which the atlas replaces. */
    d.uv_layout = PRT_UV_AUTO;
    prt_image nm = {1, 1, (float[3]){0.5f, 0.5f, 1.0f}};
    d.normal_map = &nm;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &x), PRT_ERR_INVALID_ARG);
    assert_non_null(strstr(prt_last_error(), "normal map"));
    d.normal_map = NULL;
    d.uv_layout = (prt_uv_layout)7;
    assert_int_equal(prt_bake_sh(ctx, s, &d, &x), PRT_ERR_INVALID_ARG);
    prt_scene_release(s);
    tm_free(&t);
    prt_context_release(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gutters_by_chart),
        cmocka_unit_test(test_twins),
        cmocka_unit_test(test_flat_pieces),
        cmocka_unit_test(test_layouts),
        cmocka_unit_test(test_real_meshes),
        cmocka_unit_test(test_scan_coverage),
        cmocka_unit_test(test_dragon),
        cmocka_unit_test(test_texels_on_atlas),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
