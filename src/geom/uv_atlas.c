/* UV atlas generation. Charts grow from seed triangles across shared edges, best-aligned first,
 * while a triangle's normal stays within max_angle of the chart's mean normal. Each chart is
 * flattened by least-squares conformal maps (Levy, Petitjean, Ray & Maillot 2002) started from its
 * projection onto its mean plane, and checked: a map that folds a triangle, stretches one beyond
 * MAX_STRETCH or overlaps itself falls back to the projection; where neither is valid the faulty
 * triangles and those around their corners are cut out and charted apart (a chart with too many
 * faults is cut in two). Small charts then merge into neighbours while the union stays valid,
 * flat charts in one plane that touch (pieces meeting at T junctions) join, projected, and charts
 * of duplicate faces (back-to-back twins) lie on their faces' texels or, twins both alone, pair up.
 * Charts are scaled to one texel density, turned to their smallest
 * bounding box and packed by their bilinear supports, kept apart (four quarter turns each, into any hole they
 * fit; large charts also at angles between, when that packs a scale the upright charts do not);
 * the largest density that fits is found by bisection. Large charts with ragged outlines are also
 * cut in two along a straight line across their map where the pieces' boxes shrink most, and
 * packing keeps the better of the map with them cut and without, and of a few orders of the charts. */
#include "geom/uv_atlas.h"

#include "geom/texel_raster.h"

#include <limits.h>
#include <string.h>

#define MAX_STRETCH 4.0       /* singular-value ratio a chart's worst triangle may reach */
#define SPLIT_DEPTH 48
#define PACK_ANGLES 32
#define MERGE_AREA 3.0      /* how far a merged-in chart's texel density may stray from its host's */
#define MERGE_TRIES 6       /* neighbours a chart tries to merge into */
#define MERGE_SHARE 2e-3    /* charts with less of the surface than this merge into neighbours: at 5e-4 the
                             * dragon kept hundreds of charts of a few texels, each with its reach around it
                             * (res4 at 128: 54 -> 60%); at 4e-3 the bunny's larger charts pack worse */
#define PACK_STEPS 16      /* bisections of the scale from 0: to 2e-5 of the largest (8 from 40%: 2e-3) */
#define PACK_PROBES 8      /* scales 1%, 2%, .. above the bisection's also tried */
#define PACK_ORDERS 8      /* orders of the charts packing tries, each (pack_orders) */
#define SHUFFLE_RES 256    /* larger maps pack in the first order only: their charts are small beside them, and
                            * placing costs res^2 (the teapot at 512: 73.0% in any order, 16 s rather than 5) */
#define SHUFFLE_CHARTS 64  /* and so do maps of more charts: small ones fill what the order of the large leaves */
#define MIN_COVER 0.25     /* a map whose charts touch fewer of its texels is mostly gutter: a larger one is tried */
#define ATLAS_MAX_RES 4096 /* the largest map an error suggests */

typedef struct chart {
    uint32_t *tris;
    size_t nt;
    uint32_t *verts;    /* welded vertex ids */
    size_t nv;
    double *uv;         /* [nv][2], in scene units after flattening, texels after packing */
    double w, h;        /* bounding box after turning */
    uint32_t *corner;   /* [nt][3] the triangles' corners as indices into uv, for packing */
    bool valid;         /* its map passed chart_valid: a merge need only check what it adds */
    uint8_t cut;        /* CUT_WHOLE: cut into pieces (split_ragged); CUT_PIECE: one of those */
} chart;

#define CUT_WHOLE 1
#define CUT_PIECE 2

typedef struct atlas {
    const prt_context *ctx;
    const prt__mesh *m;
    size_t nt, nw;
    uint32_t *weld;      /* [vertex] welded id: vertices at one position share it */
    uint32_t *rep;       /* [welded] one vertex at that position */
    int64_t *across;     /* [tri * 3 + edge] the triangle across that edge, -1 on a seam */
    double *normal;      /* [tri][3] unit, zero when degenerate */
    double *smooth;      /* [tri][3] mean of its vertex normals: what charts grow by */
    double *area;        /* [tri] */
    uint8_t *twin;       /* [tri] 1 where a back-to-back duplicate face shares its corners */
    uint32_t *share;     /* [tri] the triangle on whose texels a duplicate face lies (share_duplicates), else itself */
    uint32_t *fan;       /* [tri * 3 + corner] the least corner of its fan: corners at one position
                          * joined through the triangles around it that meet across edges */
    int32_t *vlocal;     /* [corner] the chart vertex of a fan in the chart being worked on, else -1 */
    uint32_t *stamp;     /* [tri] last pass that touched it */
    uint32_t pass;
    chart *charts;
    size_t count, cap;
    size_t flattened, grown, unchecked, shared, glued;
    double total;
} atlas;

/* ---- welding and adjacency ---- */

/* Sorted as keys, not through a global pointer: contexts may bake on several threads at once. */
typedef struct pos_key { float p[3]; uint32_t i; } pos_key;
static int by_position(const void *a, const void *b)
{
    const pos_key *x = a, *y = b;
    for (int c = 0; c < 3; ++c)
        if (x->p[c] != y->p[c]) return x->p[c] < y->p[c] ? -1 : 1;
    return x->i < y->i ? -1 : x->i > y->i;
}

typedef struct edge_key { uint32_t a, b, id; } edge_key;
static int by_edge(const void *x, const void *y)
{
    const edge_key *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->id < q->id ? -1 : p->id > q->id;
}

static uint32_t uf_find(uint32_t *p, uint32_t i)
{
    while (p[i] != i) i = p[i] = p[p[i]];
    return i;
}

/* Joins two sets under their least member, so roots do not depend on the order of joining. */
static void uf_union(uint32_t *p, uint32_t x, uint32_t y)
{
    x = uf_find(p, x);
    y = uf_find(p, y);
    if (x != y) p[x > y ? x : y] = x < y ? x : y;
}

static bool build_adjacency(atlas *a)
{
    const prt__mesh *m = a->m;
    const size_t nv = m->vertex_count, nt = m->triangle_count;
    pos_key *order = malloc(nv * sizeof *order);
    edge_key *e = malloc(nt * 3 * sizeof *e);
    bool ok = order && e;
    if (ok) {
        for (size_t v = 0; v < nv; ++v) { memcpy(order[v].p, m->positions + v * 3, sizeof order[v].p); order[v].i = (uint32_t)v; }
        qsort(order, nv, sizeof *order, by_position);
        uint32_t id = 0;
        for (size_t k = 0; k < nv; ++k) {
            /* Compared as numbers, as sorted: -0 and +0 are one position. */
            if (k && (order[k].p[0] != order[k - 1].p[0] || order[k].p[1] != order[k - 1].p[1] || order[k].p[2] != order[k - 1].p[2])) id++;
            a->weld[order[k].i] = id;
            a->rep[id] = order[k].i;
        }
        a->nw = nv ? (size_t)id + 1 : 0;
        for (size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 3; ++k) {
                uint32_t p = a->weld[m->indices[t * 3 + k]], q = a->weld[m->indices[t * 3 + (k + 1) % 3]];
                e[t * 3 + k] = (edge_key){p < q ? p : q, p < q ? q : p, (uint32_t)(t * 3 + k)};
                a->across[t * 3 + k] = -1;
            }
        qsort(e, nt * 3, sizeof *e, by_edge);
        /* Two triangles running along an edge in opposite directions are one surface. Scans have
         * edges shared by 4-8 triangles (sheets touching, back-to-back duplicate faces): there
         * each triangle pairs with the opposite-running one it continues most smoothly (face
         * normals closest), never with its own back-to-back twin, so sheets stay sheets instead
         * of every such edge becoming a seam. */
        for (size_t i = 0; i < nt * 3;) {
            size_t j = i + 1;
            while (j < nt * 3 && e[j].a == e[i].a && e[j].b == e[i].b) j++;
            for (int round = 0; round < 8 * 8 && j - i >= 2; ++round) {
                double best = -INFINITY;
                size_t bs = 0, bu = 0;
                for (size_t x = i; x < j; ++x) {
                    const uint32_t s = e[x].id;
                    if (a->across[s] >= 0 || a->weld[m->indices[s]] != e[x].a) continue;   /* runs a -> b, unpaired */
                    for (size_t y = i; y < j; ++y) {
                        const uint32_t u = e[y].id;
                        if (a->across[u] >= 0 || a->weld[m->indices[u]] == e[y].a || s / 3 == u / 3) continue;
                        const uint32_t ts = s / 3, tu = u / 3;
                        /* Twins: the same three corners. */
                        const uint32_t cs = a->weld[m->indices[ts * 3 + (s % 3 + 2) % 3]], cu = a->weld[m->indices[tu * 3 + (u % 3 + 2) % 3]];
                        if (cs == cu) { a->twin[ts] = a->twin[tu] = 1; continue; }
                        const double *ns = a->normal + (size_t)ts * 3, *nu = a->normal + (size_t)tu * 3;
                        const double d = j - i == 2 ? 0 : ns[0] * nu[0] + ns[1] * nu[1] + ns[2] * nu[2];
                        if (d > best) { best = d; bs = s; bu = u; }
                    }
                }
                if (best == -INFINITY) break;
                a->across[bs] = bu / 3;
                a->across[bu] = bs / 3;
            }
            i = j;
        }
        /* Fans: the corners of triangles meeting across an edge, joined at both its ends. */
        uint32_t *f = a->fan;
        for (size_t i = 0; i < nt * 3; ++i) f[i] = (uint32_t)i;
        for (size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 3; ++k) {
                const int64_t o = a->across[t * 3 + k];
                if (o < 0) continue;
                const uint32_t p0 = a->weld[m->indices[t * 3 + k]], p1 = a->weld[m->indices[t * 3 + (k + 1) % 3]];
                for (int j = 0; j < 3; ++j) {
                    if (a->weld[m->indices[(size_t)o * 3 + j]] != p1 || a->weld[m->indices[(size_t)o * 3 + (j + 1) % 3]] != p0) continue;
                    uf_union(f, (uint32_t)(t * 3 + k), (uint32_t)(o * 3 + (j + 1) % 3));
                    uf_union(f, (uint32_t)(t * 3 + (k + 1) % 3), (uint32_t)(o * 3 + j));
                    break;
                }
            }
        for (size_t i = 0; i < nt * 3; ++i) f[i] = uf_find(f, (uint32_t)i);
    }
    free(order);
    free(e);
    return ok;
}

/* ---- flattening ---- */

static void plane_frame(const double n[3], double t1[3], double t2[3])
{
    const double ax = fabs(n[0]), ay = fabs(n[1]), az = fabs(n[2]);
    double h[3] = {0, 0, 0};
    h[ax <= ay && ax <= az ? 0 : ay <= az ? 1 : 2] = 1;
    t1[0] = n[1] * h[2] - n[2] * h[1]; t1[1] = n[2] * h[0] - n[0] * h[2]; t1[2] = n[0] * h[1] - n[1] * h[0];
    double l = sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
    for (int c = 0; c < 3; ++c) t1[c] /= l;
    t2[0] = n[1] * t1[2] - n[2] * t1[1]; t2[1] = n[2] * t1[0] - n[0] * t1[2]; t2[2] = n[0] * t1[1] - n[1] * t1[0];
}

/* A triangle's corners in its own plane: (0, 0), (x1, 0), (x2, y2) with y2 > 0. */
static bool tri_frame(const prt__mesh *m, const uint32_t *ix, double x[3], double y[3])
{
    const float *p0 = m->positions + ix[0] * 3, *p1 = m->positions + ix[1] * 3, *p2 = m->positions + ix[2] * 3;
    double e1[3], e2[3];
    for (int c = 0; c < 3; ++c) { e1[c] = (double)p1[c] - p0[c]; e2[c] = (double)p2[c] - p0[c]; }
    double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    if (!(l1 > 0)) return false;
    double d = (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / l1;
    double q = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2] - d * d;
    if (!(q > 0)) return false;
    x[0] = 0; y[0] = 0; x[1] = l1; y[1] = 0; x[2] = d; y[2] = sqrt(q);
    return y[2] > 1e-12 * l1;
}

double prt__uv_stretch(const prt__mesh *m, size_t t)
{
    const uint32_t *ix = m->indices + t * 3;
    double x[3], y[3];
    if (!tri_frame(m, ix, x, y)) return 1.0;
    const float *a = m->uv + ix[0] * 2, *b = m->uv + ix[1] * 2, *c = m->uv + ix[2] * 2;
    /* J maps (x, y) to (u, v): columns from the edges (x1, 0) and (x2, y2). */
    double ju0 = (b[0] - a[0]) / x[1], jv0 = (b[1] - a[1]) / x[1];
    double ju1 = ((c[0] - a[0]) - ju0 * x[2]) / y[2], jv1 = ((c[1] - a[1]) - jv0 * x[2]) / y[2];
    double f = ju0 * ju0 + ju1 * ju1 + jv0 * jv0 + jv1 * jv1, det = fabs(ju0 * jv1 - ju1 * jv0);
    double disc = sqrt(fmax(0.0, f * f / 4 - det * det));
    double s1 = sqrt(f / 2 + disc), s2 = sqrt(fmax(0.0, f / 2 - disc));
    return s2 > 0 ? s1 / s2 : INFINITY;
}

typedef struct lscm_tri { uint32_t v[3]; double a[3], b[3]; } lscm_tri;

/* Ax for the LSCM system: per triangle, the real and imaginary parts of sum W_j U_j / sqrt(2 area). */
static void lscm_apply(const lscm_tri *T, size_t nt, const double *uv, double *r)
{
    for (size_t t = 0; t < nt; ++t) {
        double re = 0, im = 0;
        for (int j = 0; j < 3; ++j) {
            const double u = uv[T[t].v[j] * 2], v = uv[T[t].v[j] * 2 + 1];
            re += T[t].a[j] * u - T[t].b[j] * v;
            im += T[t].b[j] * u + T[t].a[j] * v;
        }
        r[t * 2] = re;
        r[t * 2 + 1] = im;
    }
}

static void lscm_transpose(const lscm_tri *T, size_t nt, const double *r, double *g, size_t nv)
{
    memset(g, 0, nv * 2 * sizeof *g);
    for (size_t t = 0; t < nt; ++t)
        for (int j = 0; j < 3; ++j) {
            g[T[t].v[j] * 2] += T[t].a[j] * r[t * 2] + T[t].b[j] * r[t * 2 + 1];
            g[T[t].v[j] * 2 + 1] += -T[t].b[j] * r[t * 2] + T[t].a[j] * r[t * 2 + 1];
        }
}

/* Minimises the conformal energy with the fixed vertices (at least two) held where they are, by
 * conjugate gradients on the normal equations (Jacobi-preconditioned), starting from uv. False
 * when it fails to converge. */
static bool lscm_solve(const prt_context *ctx, const lscm_tri *T, size_t nt, size_t nv, const uint8_t *fixed, double *uv)
{
    const size_t n = nv * 2;
    double *r = malloc(nt * 2 * sizeof *r), *g = malloc(n * sizeof *g), *p = malloc(n * sizeof *p), *q = malloc(nt * 2 * sizeof *q),
           *z = malloc(n * sizeof *z), *dinv = calloc(n, sizeof *dinv);
    bool ok = r && g && p && q && z && dinv;
    if (ok) {
        for (size_t t = 0; t < nt; ++t)
            for (int j = 0; j < 3; ++j) {
                double s = T[t].a[j] * T[t].a[j] + T[t].b[j] * T[t].b[j];
                dinv[T[t].v[j] * 2] += s;
                dinv[T[t].v[j] * 2 + 1] += s;
            }
        for (size_t i = 0; i < n; ++i) dinv[i] = dinv[i] > 0 ? 1.0 / dinv[i] : 0.0;
        for (size_t v = 0; v < nv; ++v)
            if (fixed[v]) dinv[v * 2] = dinv[v * 2 + 1] = 0;   /* pinned: never moves */
        /* Residual r = -A uv; the gradient of the energy is A^T r. */
        lscm_apply(T, nt, uv, r);
        for (size_t i = 0; i < nt * 2; ++i) r[i] = -r[i];
        lscm_transpose(T, nt, r, g, nv);
        double rz = 0, g0 = 0;
        for (size_t i = 0; i < n; ++i) { z[i] = dinv[i] * g[i]; p[i] = z[i]; rz += g[i] * z[i]; g0 += dinv[i] ? g[i] * g[i] : 0; }
        const int max_iter = 200 + (int)fmin(2000.0, 10.0 * sqrt((double)nv));
        double gn = g0;
        /* Normal equations converge slowly; from the projection, 1e-7 of the first gradient's
         * squared norm leaves no visible difference in the map. */
        for (int it = 0; it < max_iter && gn > 1e-7 * g0 && rz > 0; ++it) {
            if ((it & 31) == 31 && prt__cancelled(ctx)) { ok = false; break; }   /* large charts take seconds */
            lscm_apply(T, nt, p, q);
            double qq = 0;
            for (size_t i = 0; i < nt * 2; ++i) qq += q[i] * q[i];
            if (!(qq > 0)) break;
            const double alpha = rz / qq;
            for (size_t i = 0; i < n; ++i) uv[i] += alpha * p[i];
            for (size_t i = 0; i < nt * 2; ++i) r[i] -= alpha * q[i];
            lscm_transpose(T, nt, r, g, nv);
            double rz2 = 0;
            gn = 0;
            for (size_t i = 0; i < n; ++i) { z[i] = dinv[i] * g[i]; rz2 += g[i] * z[i]; gn += dinv[i] ? g[i] * g[i] : 0; }
            const double beta = rz2 / rz;
            rz = rz2;
            for (size_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
        }
        for (size_t i = 0; i < n && ok; ++i) ok = isfinite(uv[i]);
    }
    free(r); free(g); free(p); free(q); free(z); free(dinv);
    return ok;
}

/* Do two triangles (corners p, q) cover a common area? Separating axes over their six edge
 * normals; projections that only touch (neighbours along an edge, at a corner) do not count. */
static bool triangles_overlap(const double p[3][2], const double q[3][2])
{
    for (int s = 0; s < 2; ++s) {
        const double (*t)[2] = s ? q : p;
        for (int e = 0; e < 3; ++e) {
            const double nx = t[(e + 1) % 3][1] - t[e][1], ny = t[e][0] - t[(e + 1) % 3][0];
            const double len = sqrt(nx * nx + ny * ny);
            if (!(len > 0)) continue;
            double plo = INFINITY, phi = -INFINITY, qlo = INFINITY, qhi = -INFINITY;
            for (int k = 0; k < 3; ++k) {
                double a = (p[k][0] * nx + p[k][1] * ny) / len, b = (q[k][0] * nx + q[k][1] * ny) / len;
                plo = fmin(plo, a); phi = fmax(phi, a); qlo = fmin(qlo, b); qhi = fmax(qhi, b);
            }
            const double eps = 1e-7 * (fmax(phi - plo, qhi - qlo) + 1e-300);
            if (phi <= qlo + eps || qhi <= plo + eps) return false;
        }
    }
    return true;
}

/* Overlap by rasterizing interiors on a grid of about 64 cells per triangle (at most 4M): a cell
 * centre strictly inside two triangles. For charts whose buckets would hold too many pairs (fans
 * of long slivers); 1 overlap, 0 none, -1 out of memory. */
static int raster_overlaps(const chart *c, uint8_t *bad, double umin, double vmin, double umax, double vmax, double area)
{
    double cell = sqrt(area / ((double)c->nt * 64));
    double gw = (umax - umin) / cell, gh = (vmax - vmin) / cell;
    if (gw * gh > 4e6) { double k = sqrt(gw * gh / 4e6); cell *= k; gw /= k; gh /= k; }
    if (gw > 4e6) gw = 4e6;
    if (gh > 4e6) gh = 4e6;
    const int W = (int)ceil(gw) + 1, H = (int)ceil(gh) + 1;
    uint8_t *grid = calloc((size_t)W * H, 1);
    if (!grid) return -1;
    int overlap = 0;
    for (size_t t = 0; t < c->nt && (!overlap || bad); ++t) {
        double u[3], v[3];
        for (int k = 0; k < 3; ++k) {
            const double *p = c->uv + (size_t)c->corner[t * 3 + k] * 2;
            u[k] = (p[0] - umin) / cell; v[k] = (p[1] - vmin) / cell;
        }
        double d = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
        if (!(d > 0)) continue;
        int x0 = (int)fmax(0, floor(fmin(u[0], fmin(u[1], u[2])))), x1 = (int)fmin(W, ceil(fmax(u[0], fmax(u[1], u[2]))));
        int y0 = (int)fmax(0, floor(fmin(v[0], fmin(v[1], v[2])))), y1 = (int)fmin(H, ceil(fmax(v[0], fmax(v[1], v[2]))));
        for (int y = y0; y < y1 && (!overlap || bad); ++y)
            for (int x = x0; x < x1; ++x) {
                double px = x + 0.5, py = y + 0.5;
                double b1 = ((px - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (py - v[0])) / d;
                double b2 = ((u[1] - u[0]) * (py - v[0]) - (px - u[0]) * (v[1] - v[0])) / d;
                if (b1 <= 1e-6 || b2 <= 1e-6 || b1 + b2 >= 1 - 1e-6) continue;
                if (grid[(size_t)y * W + x]++) { overlap = 1; if (bad) bad[t] = 1; break; }
            }
    }
    free(grid);
    return overlap;
}

/* Any two of the chart's triangles overlapping in UV: candidates from a grid of buckets about
 * one mean triangle wide, then the exact test; 1 overlap, 0 none, -1 out of memory. The first
 * `known` triangles are known not to overlap one another: their pairs are skipped. */
static int chart_overlaps(const chart *c, uint8_t *bad, double umin, double vmin, double umax, double vmax, double area, size_t known)
{
    double cell = sqrt(2 * area / (double)c->nt);
    double gw = (umax - umin) / cell + 1, gh = (vmax - vmin) / cell + 1;
    if (gw * gh > 4.0 * c->nt + 16) { double k = sqrt(gw * gh / (4.0 * c->nt + 16)); cell *= k; gw = (umax - umin) / cell + 1; gh = (vmax - vmin) / cell + 1; }
    if (gw > 4.0 * c->nt + 16 || gh > 4.0 * c->nt + 16) return raster_overlaps(c, bad, umin, vmin, umax, vmax, area);
    const size_t W = (size_t)gw, H = (size_t)gh, cells = W * H;
    int32_t (*box)[4] = malloc(c->nt * sizeof *box);
    size_t *count = calloc(cells + 1, sizeof *count), *fill = NULL;
    uint32_t *items = NULL;
    if (!count || !box) { free(count); free(box); return -1; }
    /* Pass 0 counts bucket entries; long slivers in a fan would put most triangles in most
     * buckets, so past a budget of entries or pairs the raster test takes over. */
    const double budget = 64.0 * c->nt + 4096;
    double entries = 0;
    for (size_t t = 0; t < c->nt; ++t) {
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        for (int k = 0; k < 3; ++k) {
            const double *q = c->uv + (size_t)c->corner[t * 3 + k] * 2;
            lo[0] = fmin(lo[0], q[0]); hi[0] = fmax(hi[0], q[0]); lo[1] = fmin(lo[1], q[1]); hi[1] = fmax(hi[1], q[1]);
        }
        box[t][0] = (int32_t)fmax(0, fmin((double)W - 1, (lo[0] - umin) / cell));
        box[t][1] = (int32_t)fmax(0, fmin((double)H - 1, (lo[1] - vmin) / cell));
        box[t][2] = (int32_t)fmax(0, fmin((double)W - 1, (hi[0] - umin) / cell));
        box[t][3] = (int32_t)fmax(0, fmin((double)H - 1, (hi[1] - vmin) / cell));
        entries += (double)(box[t][2] - box[t][0] + 1) * (box[t][3] - box[t][1] + 1);
        if (entries > budget) break;
    }
    double pairs = 0;
    if (entries <= budget) {
        for (size_t t = 0; t < c->nt; ++t)
            for (int32_t y = box[t][1]; y <= box[t][3]; ++y)
                for (int32_t x = box[t][0]; x <= box[t][2]; ++x) count[(size_t)y * W + x + 1]++;
        for (size_t b = 1; b <= cells; ++b) pairs += 0.5 * (double)count[b] * (double)count[b];
    }
    if (entries > budget || pairs > 4 * budget) { free(count); free(box); return raster_overlaps(c, bad, umin, vmin, umax, vmax, area); }
    for (size_t i = 1; i <= cells; ++i) count[i] += count[i - 1];
    fill = calloc(cells, sizeof *fill);
    items = malloc(count[cells] * sizeof *items + 1);
    if (!fill || !items) { free(count); free(box); free(fill); free(items); return -1; }
    for (size_t t = 0; t < c->nt; ++t)
        for (int32_t y = box[t][1]; y <= box[t][3]; ++y)
            for (int32_t x = box[t][0]; x <= box[t][2]; ++x) {
                const size_t b = (size_t)y * W + x;
                items[count[b] + fill[b]++] = (uint32_t)t;
            }
    int overlap = 0;
    for (size_t b = 0; b < cells && (!overlap || bad); ++b)
        for (size_t i = count[b]; i < count[b] + fill[b] && (!overlap || bad); ++i)
            for (size_t j = i + 1; j < count[b] + fill[b] && (!overlap || bad); ++j) {
                double p[3][2], q[3][2];
                for (int k = 0; k < 3; ++k) {
                    memcpy(p[k], c->uv + (size_t)c->corner[(size_t)items[i] * 3 + k] * 2, sizeof p[k]);
                    memcpy(q[k], c->uv + (size_t)c->corner[(size_t)items[j] * 3 + k] * 2, sizeof q[k]);
                }
                if (bad && bad[items[i]] && bad[items[j]]) continue;
                if (items[i] < known && items[j] < known) continue;
                if (triangles_overlap((const double (*)[2])p, (const double (*)[2])q)) {
                    overlap = 1;
                    if (bad) bad[items[i]] = bad[items[j]] = 1;
                }
            }
    free(count);
    free(fill);
    free(items);
    free(box);
    return overlap;
}

/* Does the chart's map keep every triangle the right way round and within MAX_STRETCH, and
 * cover no point of the plane twice? 1 yes, 0 no, -1 out of memory. With bad (one per triangle,
 * zeros), it goes on past the first fault and marks every triangle at fault. */
/* Does triangle t of chart c map the right way round and within MAX_STRETCH? Its UV area is
 * added to *area (none when degenerate in space: anything goes there). */
static bool triangle_valid(const atlas *a, const chart *c, size_t t, double *area)
{
    const prt__mesh *m = a->m;
    const uint32_t tri = c->tris[t], *ix = m->indices + (size_t)tri * 3;
    double x[3], y[3];
    if (!tri_frame(m, ix, x, y)) return true;
    const double *p[3];
    for (int k = 0; k < 3; ++k) p[k] = c->uv + (size_t)c->corner[t * 3 + k] * 2;
    double du1 = p[1][0] - p[0][0], dv1 = p[1][1] - p[0][1], du2 = p[2][0] - p[0][0], dv2 = p[2][1] - p[0][1];
    double sa = 0.5 * (du1 * dv2 - du2 * dv1);
    if (!(sa > 1e-9 * a->area[tri])) return false;
    double ju0 = du1 / x[1], jv0 = dv1 / x[1], ju1 = (du2 - ju0 * x[2]) / y[2], jv1 = (dv2 - jv0 * x[2]) / y[2];
    double f = ju0 * ju0 + ju1 * ju1 + jv0 * jv0 + jv1 * jv1, det = ju0 * jv1 - ju1 * jv0;
    double disc = sqrt(fmax(0.0, f * f / 4 - det * det));
    double s1 = sqrt(f / 2 + disc), s2 = sqrt(fmax(0.0, f / 2 - disc));
    *area += sa;
    return s2 > 0 && s1 <= MAX_STRETCH * s2;
}

static int chart_valid(const atlas *a, const chart *c, uint8_t *bad)
{
    int valid = 1;
    double umin = INFINITY, vmin = INFINITY, umax = -INFINITY, vmax = -INFINITY, area = 0;
    for (size_t t = 0; t < c->nt; ++t)
        if (!triangle_valid(a, c, t, &area)) { valid = 0; if (!bad) return 0; bad[t] = 1; }
    for (size_t v = 0; v < c->nv; ++v) {
        umin = fmin(umin, c->uv[v * 2]); umax = fmax(umax, c->uv[v * 2]);
        vmin = fmin(vmin, c->uv[v * 2 + 1]); vmax = fmax(vmax, c->uv[v * 2 + 1]);
    }
    if (c->nt < 2 || !(area > 0)) return valid;
    const int overlap = chart_overlaps(c, bad, umin, vmin, umax, vmax, area, 0);
    return overlap < 0 ? -1 : valid && !overlap;
}

/* chart_valid for the union M of a valid chart (M's first na triangles, their map unchanged) and
 * triangles added to it: only what the union adds is checked, the added triangles' orientation
 * and stretch, and overlap among them and with the host's triangles whose boxes meet theirs.
 * Re-checking the whole host made merging most of an atlas's time on scans. */
static int merge_valid(const atlas *a, const chart *M, size_t na)
{
    double area = 0, lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t t = na; t < M->nt; ++t) {
        if (!triangle_valid(a, M, t, &area)) return 0;
        for (int k = 0; k < 3; ++k) {
            const double *q = M->uv + (size_t)M->corner[t * 3 + k] * 2;
            lo[0] = q[0] < lo[0] ? q[0] : lo[0]; hi[0] = q[0] > hi[0] ? q[0] : hi[0];
            lo[1] = q[1] < lo[1] ? q[1] : lo[1]; hi[1] = q[1] > hi[1] ? q[1] : hi[1];
        }
    }
    /* The host's triangles near the added ones, first (their pairs are known apart), then the added. */
    chart sub = {.uv = M->uv};
    sub.corner = malloc(M->nt * 3 * sizeof *sub.corner);
    if (!sub.corner) return -1;
    double ulo = lo[0], vlo = lo[1], uhi = hi[0], vhi = hi[1];
    for (size_t t = 0; t < na; ++t) {
        const double *p0 = M->uv + (size_t)M->corner[t * 3] * 2, *p1 = M->uv + (size_t)M->corner[t * 3 + 1] * 2, *p2 = M->uv + (size_t)M->corner[t * 3 + 2] * 2;
        const double u0 = fmin(p0[0], fmin(p1[0], p2[0])), u1 = fmax(p0[0], fmax(p1[0], p2[0]));
        if (u0 > hi[0] || u1 < lo[0]) continue;
        const double v0 = fmin(p0[1], fmin(p1[1], p2[1])), v1 = fmax(p0[1], fmax(p1[1], p2[1]));
        if (v0 > hi[1] || v1 < lo[1]) continue;
        memcpy(sub.corner + sub.nt * 3, M->corner + t * 3, 3 * sizeof *sub.corner);
        sub.nt++;
        ulo = fmin(ulo, u0); uhi = fmax(uhi, u1); vlo = fmin(vlo, v0); vhi = fmax(vhi, v1);
        double x[3], y[3];
        if (tri_frame(a->m, a->m->indices + (size_t)M->tris[t] * 3, x, y))
            area += 0.5 * ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]));
    }
    const size_t known = sub.nt;
    memcpy(sub.corner + sub.nt * 3, M->corner + na * 3, (M->nt - na) * 3 * sizeof *sub.corner);
    sub.nt += M->nt - na;
    const int overlap = sub.nt < 2 || !(area > 0) ? 0 : chart_overlaps(&sub, NULL, ulo, vlo, uhi, vhi, area, known);
    free(sub.corner);
    return overlap < 0 ? -1 : !overlap;
}

/* Triangle t of chart c's terms in the conformal energy (none when degenerate in space). */
static void lscm_term(const prt__mesh *m, const chart *c, size_t t, lscm_tri *T)
{
    const uint32_t *ix = m->indices + (size_t)c->tris[t] * 3;
    double x[3], y[3];
    const bool ok = tri_frame(m, ix, x, y);
    const double s = ok ? 1.0 / sqrt(x[1] * y[2]) : 0;   /* 1 / sqrt(2 area) */
    for (int j = 0; j < 3; ++j) {
        const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
        T->v[j] = c->corner[t * 3 + j];
        T->a[j] = ok ? (x[j2] - x[j1]) * s : 0;
        T->b[j] = ok ? (y[j2] - y[j1]) * s : 0;
    }
}

/* Flattens chart c (its tris set, its verts found here): LSCM, else projection; false when neither
 * gives a valid map, with the triangles at fault in LSCM's map (else the projection's) marked in
 * bad (one per triangle, zeros). */
static bool flatten(atlas *a, chart *c, uint8_t *bad, bool *ok_memory)
{
    const prt__mesh *m = a->m;
    double n[3] = {0, 0, 0};
    for (size_t t = 0; t < c->nt; ++t)
        for (int k = 0; k < 3; ++k) n[k] += a->normal[c->tris[t] * 3 + k] * a->area[c->tris[t]];
    double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l > 0)) { n[0] = 0; n[1] = 0; n[2] = 1; l = 1; }
    for (int k = 0; k < 3; ++k) n[k] /= l;
    double t1[3], t2[3];
    plane_frame(n, t1, t2);
    double *proj = malloc(c->nv * 2 * sizeof *proj);
    lscm_tri *T = malloc(c->nt * sizeof *T);
    uint8_t *fixed = calloc(c->nv, 1);
    if (!proj || !T || !fixed) { free(proj); free(T); free(fixed); *ok_memory = false; return false; }
    /* The projection, and the two vertices furthest apart along its wider axis as pins. */
    uint32_t pin[2] = {0, 0};
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    uint32_t at_lo[2] = {0, 0}, at_hi[2] = {0, 0};
    for (size_t v = 0; v < c->nv; ++v) {
        const float *p = m->positions + (size_t)c->verts[v] * 3;
        double pv[2] = {0, 0};
        for (int k = 0; k < 3; ++k) { pv[0] += t1[k] * p[k]; pv[1] += t2[k] * p[k]; }
        proj[v * 2] = pv[0];
        proj[v * 2 + 1] = pv[1];
        for (int k = 0; k < 2; ++k) {
            if (pv[k] < lo[k]) { lo[k] = pv[k]; at_lo[k] = (uint32_t)v; }
            if (pv[k] > hi[k]) { hi[k] = pv[k]; at_hi[k] = (uint32_t)v; }
        }
    }
    const int axis = hi[0] - lo[0] >= hi[1] - lo[1] ? 0 : 1;
    pin[0] = at_lo[axis];
    pin[1] = at_hi[axis];
    bool lscm = c->nt > 1 && pin[0] != pin[1];
    fixed[pin[0]] = fixed[pin[1]] = 1;
    for (size_t t = 0; t < c->nt && lscm; ++t) lscm_term(m, c, t, &T[t]);
    int done = 0;
    bool marked = false;
    if (lscm) {
        memcpy(c->uv, proj, c->nv * 2 * sizeof *proj);
        if (lscm_solve(a->ctx, T, c->nt, c->nv, fixed, c->uv) && (done = chart_valid(a, c, NULL)) > 0) a->flattened++;
        if (done == 0) { done = chart_valid(a, c, bad); marked = true; }
    }
    if (done == 0) {
        memcpy(c->uv, proj, c->nv * 2 * sizeof *proj);
        done = chart_valid(a, c, NULL);
        if (done == 0 && !marked) done = chart_valid(a, c, bad);
    }
    if (done < 0) *ok_memory = false;
    free(proj);
    free(T);
    free(fixed);
    return done > 0;
}

/* ---- charts ---- */

typedef struct heap_item { double key; uint32_t tri; } heap_item;

static void heap_push(heap_item *h, size_t *n, heap_item it)
{
    size_t i = (*n)++;
    while (i) {
        size_t p = (i - 1) / 2;
        if (h[p].key > it.key || (h[p].key == it.key && h[p].tri < it.tri)) break;
        h[i] = h[p];
        i = p;
    }
    h[i] = it;
}

static heap_item heap_pop(heap_item *h, size_t *n)
{
    heap_item top = h[0], last = h[--(*n)];
    size_t i = 0;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= *n) break;
        if (c + 1 < *n && (h[c + 1].key > h[c].key || (h[c + 1].key == h[c].key && h[c + 1].tri < h[c].tri))) c++;
        if (last.key > h[c].key || (last.key == h[c].key && last.tri < h[c].tri)) break;
        h[i] = h[c];
        i = c;
    }
    h[i] = last;
    return top;
}

/* Numbers the chart's vertices (c->corner: [nt][3] corners to chart vertices; c->verts: a mesh
 * vertex at each) and sizes c->uv. Corners are one vertex where they share a fan (see fan), not
 * merely a position: scans pinch sheets together at single vertices, and one UV there would fold
 * the two fans onto each other. */
static bool chart_vertices(atlas *a, chart *c)
{
    const prt__mesh *m = a->m;
    const size_t n = c->nt * 3;
    c->verts = malloc(n * sizeof *c->verts);
    c->corner = malloc(n * sizeof *c->corner);
    if (!c->verts || !c->corner) return false;
    c->nv = 0;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t f = a->fan[(size_t)c->tris[i / 3] * 3 + i % 3];
        if (a->vlocal[f] < 0) { a->vlocal[f] = (int32_t)c->nv; c->verts[c->nv++] = m->indices[(size_t)c->tris[i / 3] * 3 + i % 3]; }
        c->corner[i] = (uint32_t)a->vlocal[f];
    }
    for (size_t i = 0; i < n; ++i) a->vlocal[a->fan[(size_t)c->tris[i / 3] * 3 + i % 3]] = -1;
    c->uv = malloc(c->nv * 2 * sizeof *c->uv);
    return c->uv != NULL;
}

static bool keep_chart(atlas *a, chart *c)
{
    if (a->count == a->cap) {
        size_t cap = a->cap ? a->cap * 2 : 64;
        chart *nc = realloc(a->charts, cap * sizeof *nc);
        if (!nc) return false;
        a->charts = nc;
        a->cap = cap;
    }
    a->charts[a->count++] = *c;
    return true;
}

static int by_double(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

/* Splits the triangle set into connected pieces, flattens each, and cuts a piece that cannot be
 * flattened in two at its median along its longest extent. */
static prt_status place_piece(const prt_context *ctx, atlas *a, uint32_t *tris, size_t nt, int depth)
{
    const prt__mesh *m = a->m;
    if (prt__cancelled(ctx)) return prt__fail(ctx, PRT_ERR_CANCELLED, "UV atlas cancelled");
    /* Connected pieces within this set (stamp marks membership, then visits). */
    a->pass += 2;
    const uint32_t member = a->pass - 1, seen = a->pass;
    for (size_t i = 0; i < nt; ++i) a->stamp[tris[i]] = member;
    uint32_t *order = malloc(nt * sizeof *order);
    if (!order) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    size_t pieces = 0, filled = 0;
    size_t *start = NULL;
    for (size_t i = 0; i < nt; ++i) {
        if (a->stamp[tris[i]] != member) continue;
        size_t *ns = realloc(start, (pieces + 2) * sizeof *ns);
        if (!ns) { free(order); free(start); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); }
        start = ns;
        start[pieces++] = filled;
        size_t head = filled;
        order[filled++] = tris[i];
        a->stamp[tris[i]] = seen;
        while (head < filled) {
            uint32_t t = order[head++];
            for (int k = 0; k < 3; ++k) {
                int64_t o = a->across[(size_t)t * 3 + k];
                if (o >= 0 && a->stamp[o] == member) { a->stamp[o] = seen; order[filled++] = (uint32_t)o; }
            }
        }
    }
    start = start ? start : malloc(sizeof *start);
    if (!start) { free(order); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); }
    start[pieces] = filled;
    prt_status st = PRT_OK;
    for (size_t p = 0; p < pieces && !st; ++p) {
        chart c = {0};
        c.nt = start[p + 1] - start[p];
        c.tris = malloc(c.nt * sizeof *c.tris);
        if (!c.tris) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); break; }
        memcpy(c.tris, order + start[p], c.nt * sizeof *c.tris);
        bool mem = true;
        uint8_t *bad = calloc(c.nt, 1);
        if (!bad || !chart_vertices(a, &c)) mem = false;
        bool flat = mem && flatten(a, &c, bad, &mem);
        size_t cut = 0;
        if (mem && !flat && c.nt > 1 && depth < SPLIT_DEPTH) {
            /* Only the faulty triangles and those around their corners come out, to be charted
             * on their own; the rest is flattened again. Scans fold around a few crumpled
             * vertices, and halving the whole chart for them grinds it down to crumbs. */
            uint8_t *hot = calloc(c.nv, 1);
            if (!hot) mem = false;
            for (size_t t = 0; hot && t < c.nt; ++t)
                if (bad[t]) for (int k = 0; k < 3; ++k) hot[c.corner[t * 3 + k]] = 1;
            for (size_t t = 0; hot && t < c.nt; ++t) {
                bad[t] = hot[c.corner[t * 3]] || hot[c.corner[t * 3 + 1]] || hot[c.corner[t * 3 + 2]];
                cut += bad[t];
            }
            free(hot);
        }
        if (mem && prt__cancelled(ctx)) { free(bad); free(c.tris); free(c.verts); free(c.uv); free(c.corner); st = prt__fail(ctx, PRT_ERR_CANCELLED, "UV atlas cancelled"); break; }
        if (!mem) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
        else if (flat || c.nt == 1 || depth >= SPLIT_DEPTH) {
            /* Not flat only past SPLIT_DEPTH (one triangle always is): it keeps its projection. */
            a->unchecked += !flat;
            c.valid = flat;
            free(bad);
            bad = NULL;
            if (!keep_chart(a, &c)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
            else continue;
        } else if (cut > 0 && cut * 2 <= c.nt) {
            uint32_t *sorted = malloc(c.nt * sizeof *sorted);
            if (!sorted) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
            else {
                size_t keep = 0, out = c.nt;
                for (size_t t = 0; t < c.nt; ++t) {
                    if (bad[t]) sorted[--out] = c.tris[t];
                    else sorted[keep++] = c.tris[t];
                }
                st = place_piece(ctx, a, sorted, keep, depth + 1);
                if (!st) st = place_piece(ctx, a, sorted + keep, c.nt - keep, depth + 1);
                free(sorted);
            }
        } else {
            /* Cut at the median centroid along the longest axis of the piece's box. */
            double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            double *key = malloc(c.nt * sizeof *key);
            uint32_t *sorted = malloc(c.nt * sizeof *sorted);
            if (!key || !sorted) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
            for (size_t t = 0; t < c.nt && !st; ++t)
                for (int k = 0; k < 3; ++k) {
                    const float *q = m->positions + m->indices[(size_t)c.tris[t] * 3 + k] * 3;
                    for (int x = 0; x < 3; ++x) { lo[x] = fmin(lo[x], q[x]); hi[x] = fmax(hi[x], q[x]); }
                }
            const int ax = hi[0] - lo[0] >= hi[1] - lo[1] && hi[0] - lo[0] >= hi[2] - lo[2] ? 0 : hi[1] - lo[1] >= hi[2] - lo[2] ? 1 : 2;
            if (!st) {
                for (size_t t = 0; t < c.nt; ++t) {
                    const uint32_t *ix = m->indices + (size_t)c.tris[t] * 3;
                    key[t] = (double)m->positions[ix[0] * 3 + ax] + m->positions[ix[1] * 3 + ax] + m->positions[ix[2] * 3 + ax];
                }
                double *ks = malloc(c.nt * sizeof *ks);
                if (!ks) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
                else {
                    memcpy(ks, key, c.nt * sizeof *ks);
                    qsort(ks, c.nt, sizeof *ks, by_double);
                    const size_t kth = c.nt / 2;
                    const double median = ks[kth];
                    free(ks);
                    size_t below = 0, above = c.nt;
                    for (size_t t = 0; t < c.nt; ++t) {
                        if (key[t] < median) sorted[below++] = c.tris[t];
                        else sorted[--above] = c.tris[t];
                    }
                    if (below == 0 || below == c.nt) {   /* all on one key: split the list in half */
                        memcpy(sorted, c.tris, c.nt * sizeof *sorted);
                        below = c.nt / 2;
                    }
                    st = place_piece(ctx, a, sorted, below, depth + 1);
                    if (!st) st = place_piece(ctx, a, sorted + below, c.nt - below, depth + 1);
                }
            }
            free(key);
            free(sorted);
        }
        free(bad);
        free(c.tris);
        free(c.verts);
        free(c.uv);
        free(c.corner);
    }
    free(order);
    free(start);
    return st;
}

/* Grows charts from seeds in triangle order: a neighbour joins while its normal stays within
 * max_angle of the chart's area-weighted mean. */
static prt_status grow_charts(const prt_context *ctx, atlas *a, double cos_max)
{
    const size_t nt = a->nt;
    uint8_t *taken = calloc(nt, 1);
    uint32_t *members = malloc(nt * sizeof *members);
    heap_item *heap = malloc(nt * 3 * sizeof *heap + sizeof *heap);
    prt_status st = taken && members && heap ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    for (size_t seed = 0; seed < nt && !st; ++seed) {
        if (taken[seed]) continue;
        size_t count = 0, hn = 0;
        double n[3];
        for (int k = 0; k < 3; ++k) n[k] = a->smooth[seed * 3 + k] * a->area[seed];
        taken[seed] = 1;
        members[count++] = (uint32_t)seed;
        a->pass++;
        a->stamp[seed] = a->pass;
        heap_push(heap, &hn, (heap_item){1.0, (uint32_t)seed});
        while (hn) {
            heap_item it = heap_pop(heap, &hn);
            if (it.tri != seed) {
                if (taken[it.tri]) continue;
                double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                const double *tn = a->smooth + (size_t)it.tri * 3;
                double d = l > 0 ? (tn[0] * n[0] + tn[1] * n[1] + tn[2] * n[2]) / l : 1.0;
                if (tn[0] == 0 && tn[1] == 0 && tn[2] == 0) d = 1.0;   /* degenerate: goes anywhere */
                if (d < cos_max) continue;
                taken[it.tri] = 1;
                members[count++] = it.tri;
                for (int k = 0; k < 3; ++k) n[k] += tn[k] * a->area[it.tri];
            }
            double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (int k = 0; k < 3; ++k) {
                int64_t o = a->across[(size_t)it.tri * 3 + k];
                if (o < 0 || taken[o] || hn >= nt * 3) continue;
                const double *tn = a->smooth + (size_t)o * 3;
                double d = l > 0 ? (tn[0] * n[0] + tn[1] * n[1] + tn[2] * n[2]) / l : 1.0;
                if (d < cos_max) continue;
                heap_push(heap, &hn, (heap_item){d, (uint32_t)o});
            }
        }
        a->grown++;
        st = place_piece(ctx, a, members, count, 0);
    }
    free(taken);
    free(members);
    free(heap);
    return st;
}

/* ---- merging ---- */

/* Tries to extend chart A by its neighbour B: A's map stays as it is, B's is moved onto it (the
 * similarity that best takes B's UVs of their shared vertices to A's) and relaxed by LSCM with
 * A's vertices held. The union must be valid, and B's triangles keep within MERGE_AREA of A's
 * UV area per surface area (the texel density stays near even inside the chart). 1 with A
 * replaced by the union, 0 not, -1 out of memory. */
static int try_merge(atlas *a, chart *A, const chart *B)
{
    const prt__mesh *m = a->m;
    chart M = {0};
    M.nt = A->nt + B->nt;
    M.tris = malloc(M.nt * sizeof *M.tris);
    if (!M.tris) return -1;
    memcpy(M.tris, A->tris, A->nt * sizeof *M.tris);
    memcpy(M.tris + A->nt, B->tris, B->nt * sizeof *M.tris);
    uint8_t *fixed = NULL;
    int32_t *sub = NULL;
    uint32_t *subv = NULL;
    double *x = NULL;
    lscm_tri *T = NULL;
    int result = -1;
    if (!chart_vertices(a, &M)) goto done;
    fixed = calloc(M.nv, 1);
    sub = malloc(M.nv * sizeof *sub);
    if (!fixed || !sub) goto done;
    for (size_t i = 0; i < A->nt * 3; ++i) {
        const uint32_t v = M.corner[i];
        fixed[v] = 1;
        memcpy(M.uv + (size_t)v * 2, A->uv + (size_t)A->corner[i] * 2, 2 * sizeof *M.uv);
    }
    /* The similarity z -> alpha z + beta (complex) from B's UVs to A's at shared corners. */
    double zc[2] = {0, 0}, wc[2] = {0, 0}, n = 0;
    for (size_t i = 0; i < B->nt * 3; ++i) {
        const uint32_t v = M.corner[A->nt * 3 + i];
        if (!fixed[v]) continue;
        const double *z = B->uv + (size_t)B->corner[i] * 2, *w = M.uv + (size_t)v * 2;
        zc[0] += z[0]; zc[1] += z[1]; wc[0] += w[0]; wc[1] += w[1]; n++;
    }
    result = 0;
    if (n < 2) goto done;
    zc[0] /= n; zc[1] /= n; wc[0] /= n; wc[1] /= n;
    double num[2] = {0, 0}, den = 0;
    for (size_t i = 0; i < B->nt * 3; ++i) {
        const uint32_t v = M.corner[A->nt * 3 + i];
        if (!fixed[v]) continue;
        const double *z = B->uv + (size_t)B->corner[i] * 2, *w = M.uv + (size_t)v * 2;
        const double zr = z[0] - zc[0], zi = z[1] - zc[1], wr = w[0] - wc[0], wi = w[1] - wc[1];
        num[0] += zr * wr + zi * wi;   /* conj(z) w */
        num[1] += zr * wi - zi * wr;
        den += zr * zr + zi * zi;
    }
    if (!(den > 0)) goto done;
    const double ar = num[0] / den, ai = num[1] / den;
    const double br = wc[0] - (ar * zc[0] - ai * zc[1]), bi = wc[1] - (ar * zc[1] + ai * zc[0]);
    /* B's vertices, numbered on their own: the solve touches only them. */
    size_t ns = 0;
    subv = malloc(B->nt * 3 * sizeof *subv);
    T = malloc(B->nt * sizeof *T);
    if (!subv || !T) { result = -1; goto done; }
    for (size_t v = 0; v < M.nv; ++v) sub[v] = -1;
    for (size_t i = 0; i < B->nt * 3; ++i) {
        const uint32_t v = M.corner[A->nt * 3 + i];
        if (sub[v] < 0) { sub[v] = (int32_t)ns; subv[ns++] = v; }
        if (!fixed[v]) {
            const double *z = B->uv + (size_t)B->corner[i] * 2;
            M.uv[(size_t)v * 2] = ar * z[0] - ai * z[1] + br;
            M.uv[(size_t)v * 2 + 1] = ar * z[1] + ai * z[0] + bi;
        }
    }
    x = malloc(ns * 2 * sizeof *x);
    uint8_t *sfix = malloc(ns);
    if (!x || !sfix) { free(sfix); result = -1; goto done; }
    bool any_free = false;
    for (size_t k = 0; k < ns; ++k) {
        memcpy(x + k * 2, M.uv + (size_t)subv[k] * 2, 2 * sizeof *x);
        sfix[k] = fixed[subv[k]];
        any_free |= !sfix[k];
    }
    for (size_t t = 0; t < B->nt; ++t) {
        lscm_term(m, &M, A->nt + t, &T[t]);
        for (int j = 0; j < 3; ++j) T[t].v[j] = (uint32_t)sub[T[t].v[j]];
    }
    bool solved = !any_free || lscm_solve(a->ctx, T, B->nt, ns, sfix, x);
    free(sfix);
    if (!solved) goto done;
    for (size_t k = 0; k < ns; ++k) memcpy(M.uv + (size_t)subv[k] * 2, x + k * 2, 2 * sizeof *x);
    /* B's density against A's. */
    double ua = 0, sa = 0;
    for (size_t t = 0; t < A->nt; ++t) {
        const double *p0 = M.uv + (size_t)M.corner[t * 3] * 2, *p1 = M.uv + (size_t)M.corner[t * 3 + 1] * 2, *p2 = M.uv + (size_t)M.corner[t * 3 + 2] * 2;
        ua += 0.5 * ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]));
        sa += a->area[M.tris[t]];
    }
    const double density = sa > 0 ? ua / sa : 0;
    for (size_t t = A->nt; t < M.nt; ++t) {
        const double *p0 = M.uv + (size_t)M.corner[t * 3] * 2, *p1 = M.uv + (size_t)M.corner[t * 3 + 1] * 2, *p2 = M.uv + (size_t)M.corner[t * 3 + 2] * 2;
        const double u = 0.5 * ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]));
        const double s = a->area[M.tris[t]] * density;
        if (s > 0 && (u > MERGE_AREA * s || u * MERGE_AREA < s)) goto done;
    }
    result = A->valid ? merge_valid(a, &M, A->nt) : chart_valid(a, &M, NULL);
    if (result > 0) {
        M.valid = true;
        free(A->tris); free(A->verts); free(A->uv); free(A->corner);
        *A = M;
        M = (chart){0};
    }
done:
    free(M.tris); free(M.verts); free(M.uv); free(M.corner);
    free(fixed); free(sub); free(subv); free(x); free(T);
    return result;
}

typedef struct merge_key { double area; uint32_t i; } merge_key;
static int by_area(const void *x, const void *y)
{
    const merge_key *p = x, *q = y;
    if (p->area != q->area) return p->area < q->area ? -1 : 1;
    return p->i < q->i ? -1 : p->i > q->i;
}

/* Merges charts into neighbours, smallest first, each into the neighbour it shares the longest
 * boundary with (else the next longest) while the union stays valid: fewer, larger charts waste
 * fewer texels on gutters. */
static prt_status merge_charts(const prt_context *ctx, atlas *a)
{
    const prt__mesh *m = a->m;
    const size_t count = a->count;
    uint32_t *owner = malloc(a->nt * sizeof *owner);
    merge_key *keys = malloc(count * sizeof *keys);
    double *shared = calloc(count, sizeof *shared);
    uint32_t *near = malloc(count * sizeof *near);
    uint8_t *dead = calloc(count, 1);
    prt_status st = owner && keys && shared && near && dead ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    for (size_t ci = 0; ci < count && !st; ++ci) {
        double area = 0;
        for (size_t t = 0; t < a->charts[ci].nt; ++t) { owner[a->charts[ci].tris[t]] = (uint32_t)ci; area += a->area[a->charts[ci].tris[t]]; }
        keys[ci] = (merge_key){area, (uint32_t)ci};
    }
    if (!st) qsort(keys, count, sizeof *keys, by_area);
    for (size_t k = 0; k < count && !st; ++k) {
        const uint32_t bi = keys[k].i;
        chart *B = &a->charts[bi];
        if (keys[k].area > MERGE_SHARE * a->total) break;
        if (prt__cancelled(ctx)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "UV atlas cancelled"); break; }
        /* Neighbours by shared boundary length. */
        size_t nn = 0;
        for (size_t t = 0; t < B->nt; ++t) {
            const uint32_t tri = B->tris[t];
            for (int e = 0; e < 3; ++e) {
                const int64_t o = a->across[(size_t)tri * 3 + e];
                if (o < 0 || owner[o] == bi) continue;
                const uint32_t ci = owner[o];
                const float *p = m->positions + m->indices[(size_t)tri * 3 + e] * 3, *q = m->positions + m->indices[(size_t)tri * 3 + (e + 1) % 3] * 3;
                const double d = sqrt(((double)p[0] - q[0]) * ((double)p[0] - q[0]) + ((double)p[1] - q[1]) * ((double)p[1] - q[1]) + ((double)p[2] - q[2]) * ((double)p[2] - q[2]));
                if (shared[ci] == 0) near[nn++] = ci;
                shared[ci] += d + 1e-300;
            }
        }
        for (int tries = 0; tries < MERGE_TRIES && nn && !st; ++tries) {
            size_t best = 0;
            for (size_t j = 1; j < nn; ++j)
                if (shared[near[j]] > shared[near[best]] || (shared[near[j]] == shared[near[best]] && near[j] < near[best])) best = j;
            const uint32_t ai = near[best];
            if (shared[ai] <= 0) break;
            shared[ai] = -1;   /* tried */
            const int r = try_merge(a, &a->charts[ai], B);
            if (r < 0) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
            else if (r > 0) {
                for (size_t t = 0; t < B->nt; ++t) owner[B->tris[t]] = ai;
                free(B->tris); free(B->verts); free(B->uv); free(B->corner);
                *B = (chart){0};
                dead[bi] = 1;
                break;
            }
        }
        for (size_t j = 0; j < nn; ++j) shared[near[j]] = 0;
    }
    if (!st) {
        size_t kept = 0;
        for (size_t ci = 0; ci < count; ++ci)
            if (!dead[ci]) a->charts[kept++] = a->charts[ci];
        a->count = kept;
    }
    free(owner); free(keys); free(shared); free(near); free(dead);
    return st;
}

/* ---- flat pieces ---- */

static double diagonal_of(const prt__mesh *m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, d2 = 0;
    for (size_t v = 0; v < m->vertex_count; ++v)
        for (int k = 0; k < 3; ++k) { lo[k] = fmin(lo[k], m->positions[v * 3 + k]); hi[k] = fmax(hi[k], m->positions[v * 3 + k]); }
    for (int k = 0; k < 3 && m->vertex_count; ++k) d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    return sqrt(d2);
}

/* A flat chart's plane (unit normal n, offset d = n.p) and box, or false when it is not flat. */
typedef struct flat { double n[3], d, lo[3], hi[3]; bool ok; } flat;

static flat chart_flat(const atlas *a, const chart *c, double eps)
{
    flat f = {.ok = false};
    double n[3] = {0, 0, 0};
    for (size_t t = 0; t < c->nt; ++t)
        for (int k = 0; k < 3; ++k) n[k] += a->normal[(size_t)c->tris[t] * 3 + k] * a->area[c->tris[t]];
    const double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l > 0)) return f;
    for (int k = 0; k < 3; ++k) f.n[k] = n[k] / l;
    for (size_t t = 0; t < c->nt; ++t) {
        const double *q = a->normal + (size_t)c->tris[t] * 3;
        if (a->area[c->tris[t]] > 0 && q[0] * f.n[0] + q[1] * f.n[1] + q[2] * f.n[2] < 1 - 1e-6) return f;
    }
    const float *p0 = a->m->positions + (size_t)c->verts[0] * 3;
    f.d = f.n[0] * p0[0] + f.n[1] * p0[1] + f.n[2] * p0[2];
    for (int k = 0; k < 3; ++k) { f.lo[k] = INFINITY; f.hi[k] = -INFINITY; }
    for (size_t v = 0; v < c->nv; ++v) {
        const float *p = a->m->positions + (size_t)c->verts[v] * 3;
        if (fabs(f.n[0] * p[0] + f.n[1] * p[1] + f.n[2] * p[2] - f.d) > eps) return f;
        for (int k = 0; k < 3; ++k) { f.lo[k] = fmin(f.lo[k], p[k]); f.hi[k] = fmax(f.hi[k], p[k]); }
    }
    f.ok = true;
    return f;
}

/* Does a vertex of B lie on an edge of A's (within eps)? Pieces of one wall that meet at T
 * junctions (a wall built around a window, as scene files bring them) share no edge. */
static bool pieces_touch(const atlas *a, const chart *A, const chart *B, double eps)
{
    const prt__mesh *m = a->m;
    for (size_t t = 0; t < A->nt; ++t)
        for (int e = 0; e < 3; ++e) {
            if (a->across[(size_t)A->tris[t] * 3 + e] >= 0) continue;   /* inside A */
            const float *p = m->positions + m->indices[(size_t)A->tris[t] * 3 + e] * 3, *q = m->positions + m->indices[(size_t)A->tris[t] * 3 + (e + 1) % 3] * 3;
            const double ex = q[0] - p[0], ey = q[1] - p[1], ez = q[2] - p[2], l2 = ex * ex + ey * ey + ez * ez;
            for (size_t v = 0; v < B->nv; ++v) {
                const float *x = m->positions + (size_t)B->verts[v] * 3;
                const double f = l2 > 0 ? fmin(fmax(((x[0] - p[0]) * ex + (x[1] - p[1]) * ey + (x[2] - p[2]) * ez) / l2, 0), 1) : 0;
                const double dx = p[0] + f * ex - x[0], dy = p[1] + f * ey - x[1], dz = p[2] + f * ez - x[2];
                if (dx * dx + dy * dy + dz * dz <= eps * eps) return true;
            }
        }
    return false;
}

/* Joins flat charts lying in one plane that touch (pieces of a wall meeting at T junctions, which
 * share no edge and so grew apart) into one chart mapped by projection onto the plane - exact for
 * flat pieces - where the union maps without overlap. Texels on either side of such a seam are
 * then neighbours in the map as on the surface: no chart border (and, in the offset method, no
 * band where its cells change) where the surface runs on. */
static prt_status join_flat_pieces(const prt_context *ctx, atlas *a, double diagonal)
{
    const size_t count = a->count;
    if (count < 2 || count > 4096) return PRT_OK;   /* pairs: beyond that, the time is not worth it */
    const double eps = 1e-6 * diagonal + 1e-12;
    flat *f = malloc(count * sizeof *f);
    uint32_t *group = malloc(count * sizeof *group);
    uint8_t *dead = calloc(count, 1);
    prt_status st = f && group && dead ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    for (size_t i = 0; !st && i < count; ++i) { f[i] = chart_flat(a, &a->charts[i], eps); group[i] = (uint32_t)i; }
    for (size_t i = 0; !st && i < count; ++i) {
        if (!f[i].ok) continue;
        if (prt__cancelled(ctx)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "UV atlas cancelled"); break; }
        for (size_t j = i + 1; j < count; ++j) {
            if (!f[j].ok || f[i].n[0] * f[j].n[0] + f[i].n[1] * f[j].n[1] + f[i].n[2] * f[j].n[2] < 1 - 1e-6 || fabs(f[i].d - f[j].d) > eps) continue;
            bool apart = false;
            for (int k = 0; k < 3; ++k) apart |= f[i].lo[k] > f[j].hi[k] + eps || f[j].lo[k] > f[i].hi[k] + eps;
            if (apart || uf_find(group, (uint32_t)i) == uf_find(group, (uint32_t)j)) continue;
            if (pieces_touch(a, &a->charts[i], &a->charts[j], eps) || pieces_touch(a, &a->charts[j], &a->charts[i], eps))
                uf_union(group, (uint32_t)i, (uint32_t)j);
        }
    }
    /* Each group of two or more: the union, projected; kept where it is valid. */
    for (size_t r = 0; !st && r < count; ++r) {
        if (uf_find(group, (uint32_t)r) != r) continue;
        chart M = {0};
        size_t members = 0;
        for (size_t i = r; i < count; ++i)
            if (uf_find(group, (uint32_t)i) == r) { M.nt += a->charts[i].nt; members++; }
        if (members < 2) continue;
        if (!(M.tris = malloc(M.nt * sizeof *M.tris))) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); break; }
        M.nt = 0;
        for (size_t i = r; i < count; ++i)
            if (uf_find(group, (uint32_t)i) == r) { memcpy(M.tris + M.nt, a->charts[i].tris, a->charts[i].nt * sizeof *M.tris); M.nt += a->charts[i].nt; }
        int valid = -1;
        if (chart_vertices(a, &M)) {
            double t1[3], t2[3];
            plane_frame(f[r].n, t1, t2);
            valid = 0;
            for (int mirror = 0; mirror < 2 && valid == 0; ++mirror) {   /* whichever way round keeps the triangles' orientation */
                for (size_t v = 0; v < M.nv; ++v) {
                    const float *p = a->m->positions + (size_t)M.verts[v] * 3;
                    M.uv[v * 2] = t1[0] * p[0] + t1[1] * p[1] + t1[2] * p[2];
                    M.uv[v * 2 + 1] = (mirror ? -1 : 1) * (t2[0] * p[0] + t2[1] * p[1] + t2[2] * p[2]);
                }
                valid = chart_valid(a, &M, NULL);
            }
        }
        if (valid < 0) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); }
        if (valid > 0) {
            M.valid = true;
            for (size_t i = r + 1; i < count; ++i)
                if (uf_find(group, (uint32_t)i) == r) {
                    chart *c = &a->charts[i];
                    free(c->tris); free(c->verts); free(c->uv); free(c->corner);
                    *c = (chart){0};
                    dead[i] = 1;
                }
            chart *c = &a->charts[r];
            free(c->tris); free(c->verts); free(c->uv); free(c->corner);
            *c = M;
        } else {
            free(M.tris); free(M.verts); free(M.uv); free(M.corner);
        }
    }
    if (!st) {
        size_t kept = 0;
        for (size_t ci = 0; ci < count; ++ci)
            if (!dead[ci]) a->charts[kept++] = a->charts[ci];
        a->count = kept;
    }
    free(f); free(group); free(dead);
    return st;
}

/* ---- duplicate faces ---- */

typedef struct tri_key { uint32_t c[3], t; } tri_key;
static int by_corners(const void *x, const void *y)
{
    const tri_key *p = x, *q = y;
    for (int k = 0; k < 3; ++k)
        if (p->c[k] != q->c[k]) return p->c[k] < q->c[k] ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

/* Do triangles t and u (the same three corners) run the same way round? */
static bool same_winding(const atlas *a, uint32_t t, uint32_t u)
{
    const uint32_t *x = a->m->indices + (size_t)t * 3, *y = a->m->indices + (size_t)u * 3;
    for (int k = 0; k < 3; ++k)
        if (a->weld[y[k]] == a->weld[x[0]]) return a->weld[y[(k + 1) % 3]] == a->weld[x[1]];
    return false;
}

/* Glues chart D, one triangle, the back-to-back twin of C's one, onto C across C's longest edge:
 * D's third corner is C's mirrored over that edge (D runs the other way round, so it keeps its
 * orientation). 1 with C the pair, 0 when the pair is not valid, -1 out of memory. */
static int glue_twins(atlas *a, chart *C, const chart *D)
{
    const prt__mesh *m = a->m;
    const uint32_t t = C->tris[0], u = D->tris[0], *x = m->indices + (size_t)t * 3, *y = m->indices + (size_t)u * 3;
    int e = 0;
    double best = -1;
    for (int k = 0; k < 3; ++k) {
        const float *p = m->positions + x[k] * 3, *q = m->positions + x[(k + 1) % 3] * 3;
        const double l = ((double)p[0] - q[0]) * ((double)p[0] - q[0]) + ((double)p[1] - q[1]) * ((double)p[1] - q[1]) + ((double)p[2] - q[2]) * ((double)p[2] - q[2]);
        if (l > best) { best = l; e = k; }
    }
    chart M = {0};
    M.nt = 2;
    M.nv = 4;
    M.tris = malloc(2 * sizeof *M.tris);
    M.verts = malloc(4 * sizeof *M.verts);
    M.uv = malloc(8 * sizeof *M.uv);
    M.corner = malloc(6 * sizeof *M.corner);
    if (!M.tris || !M.verts || !M.uv || !M.corner) { free(M.tris); free(M.verts); free(M.uv); free(M.corner); return -1; }
    M.tris[0] = t;
    M.tris[1] = u;
    /* C's corners in order as chart vertices 0..2; D's apex (opposite the edge) is vertex 3. */
    for (int k = 0; k < 3; ++k) {
        M.verts[k] = C->verts[C->corner[k]];
        M.corner[k] = (uint32_t)k;
        memcpy(M.uv + k * 2, C->uv + (size_t)C->corner[k] * 2, 2 * sizeof *M.uv);
    }
    const int ea = e, eb = (e + 1) % 3, apex = (e + 2) % 3;
    for (int k = 0; k < 3; ++k) {
        const uint32_t w = a->weld[y[k]];
        M.corner[3 + k] = w == a->weld[x[ea]] ? (uint32_t)ea : w == a->weld[x[eb]] ? (uint32_t)eb : 3;
        if (M.corner[3 + k] == 3) M.verts[3] = y[k];
    }
    const double *A = M.uv + ea * 2, *B = M.uv + eb * 2, *P = M.uv + apex * 2;
    const double dx = B[0] - A[0], dy = B[1] - A[1], l2 = dx * dx + dy * dy;
    const double f = l2 > 0 ? ((P[0] - A[0]) * dx + (P[1] - A[1]) * dy) / l2 : 0;
    M.uv[6] = 2 * (A[0] + f * dx) - P[0];
    M.uv[7] = 2 * (A[1] + f * dy) - P[1];
    const int valid = chart_valid(a, &M, NULL);
    if (valid > 0) {
        M.valid = true;
        free(C->tris); free(C->verts); free(C->uv); free(C->corner);
        *C = M;
        return 1;
    }
    free(M.tris); free(M.verts); free(M.uv); free(M.corner);
    return valid;
}

/* Charts made only of duplicate faces (the same three corners as a triangle of a chart kept, either
 * way round) are not packed: each of their triangles lies on its duplicate's texels, sharing its
 * UVs. Scans are full of them: the dragon's decimation leaves a thousand back-to-back twins, the
 * inward one of each a chart of one triangle on its own (inside the closed surface, facing into
 * it: nothing there to light or see). Coplanar with its twin and drawn without culling, it then
 * shows its twin's light rather than fighting it for the pixels; the per-texel bakes take such
 * texels from the face that is not mirrored in UV (texel_raster.c). Larger charts are kept first. */
static prt_status share_duplicates(const prt_context *ctx, atlas *a)
{
    const size_t nt = a->nt, count = a->count;
    tri_key *key = malloc(nt * sizeof *key);
    uint32_t *chart_of = malloc(nt * sizeof *chart_of), *first = malloc(nt * sizeof *first);
    merge_key *order = malloc(count * sizeof *order + 1);
    uint8_t *kept = calloc(count + 1, 1), *dropped = calloc(count + 1, 1);
    prt_status st = key && chart_of && first && order && kept && dropped ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    for (size_t t = 0; !st && t < nt; ++t) {
        uint32_t c[3] = {a->weld[a->m->indices[t * 3]], a->weld[a->m->indices[t * 3 + 1]], a->weld[a->m->indices[t * 3 + 2]]}, x;
        if (c[0] > c[1]) { x = c[0]; c[0] = c[1]; c[1] = x; }
        if (c[1] > c[2]) { x = c[1]; c[1] = c[2]; c[2] = x; }
        if (c[0] > c[1]) { x = c[0]; c[0] = c[1]; c[1] = x; }
        key[t] = (tri_key){{c[0], c[1], c[2]}, (uint32_t)t};
        a->share[t] = (uint32_t)t;
    }
    if (!st) qsort(key, nt, sizeof *key, by_corners);
    /* first[t]: where t's run of equal corners starts in key. */
    for (size_t i = 0; !st && i < nt; ++i)
        first[key[i].t] = i && !memcmp(key[i].c, key[i - 1].c, sizeof key[i].c) ? first[key[i - 1].t] : (uint32_t)i;
    for (size_t ci = 0; !st && ci < count; ++ci) {
        for (size_t t = 0; t < a->charts[ci].nt; ++t) chart_of[a->charts[ci].tris[t]] = (uint32_t)ci;
        order[ci] = (merge_key){-(double)a->charts[ci].nt, (uint32_t)ci};
    }
    if (!st) qsort(order, count, sizeof *order, by_area);
    for (size_t k = 0; !st && k < count; ++k) {
        const uint32_t ci = order[k].i;
        const chart *c = &a->charts[ci];
        bool all = true;
        for (size_t t = 0; t < c->nt && all; ++t) {
            const uint32_t tri = c->tris[t];
            bool found = false;
            for (size_t i = first[tri]; i < nt && !memcmp(key[i].c, key[first[tri]].c, sizeof key[i].c) && !found; ++i)
                found = key[i].t != tri && kept[chart_of[key[i].t]] && !(c->nt == 1 && a->charts[chart_of[key[i].t]].nt == 1 && !same_winding(a, tri, key[i].t));
            all = found;
        }
        if (!all || c->nt == 0) { kept[ci] = 1; continue; }
        dropped[ci] = 1;
        for (size_t t = 0; t < c->nt; ++t) {
            const uint32_t tri = c->tris[t];
            for (size_t i = first[tri]; i < nt; ++i)
                if (key[i].t != tri && kept[chart_of[key[i].t]]) { a->share[tri] = key[i].t; break; }
        }
    }
    /* Twins both on their own: a fin of no thickness, or a sheet's two sides, each side seen. They
     * keep their own texels, glued along their longest edge - where the two sides meet - into one
     * chart of two: half the reach (the texels around charts) of two charts of one. */
    for (size_t ci = 0; !st && ci < count; ++ci) {
        chart *c = &a->charts[ci];
        if (dropped[ci] || c->nt != 1) continue;
        const uint32_t tri = c->tris[0];
        for (size_t i = first[tri]; i < nt && !memcmp(key[i].c, key[first[tri]].c, sizeof key[i].c); ++i) {
            const uint32_t u = key[i].t, di = chart_of[u];
            if (u == tri || di == ci || dropped[di] || a->charts[di].nt != 1 || same_winding(a, tri, u)) continue;
            const int r = glue_twins(a, c, &a->charts[di]);
            if (r < 0) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
            else if (r > 0) { dropped[di] = 2; a->glued++; }
            break;
        }
    }
    if (!st) {
        size_t live = 0;
        for (size_t ci = 0; ci < count; ++ci) {
            chart *c = &a->charts[ci];
            if (dropped[ci] == 2) { free(c->tris); free(c->verts); free(c->uv); free(c->corner); }
            else if (dropped[ci]) { a->shared += c->nt; free(c->tris); free(c->verts); free(c->uv); free(c->corner); }
            else a->charts[live++] = *c;
        }
        a->count = live;
    }
    free(key); free(chart_of); free(first); free(order); free(kept); free(dropped);
    return st;
}

/* ---- packing ---- */

/* Turns a chart to the smallest-area bounding box of PACK_ANGLES tried, lying wide, corner at 0. */
static void chart_orient(chart *c)
{
    double best = INFINITY, best_angle = 0;
    for (int i = 0; i < PACK_ANGLES; ++i) {
        const double th = (PRT_PI / 2) * i / PACK_ANGLES, cs = cos(th), sn = sin(th);
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        for (size_t v = 0; v < c->nv; ++v) {
            double u = cs * c->uv[v * 2] - sn * c->uv[v * 2 + 1], w = sn * c->uv[v * 2] + cs * c->uv[v * 2 + 1];
            lo[0] = fmin(lo[0], u); hi[0] = fmax(hi[0], u); lo[1] = fmin(lo[1], w); hi[1] = fmax(hi[1], w);
        }
        double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        if (area < best * (1 - 1e-9)) { best = area; best_angle = th; }
    }
    const double cs = cos(best_angle), sn = sin(best_angle);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t v = 0; v < c->nv; ++v) {
        double u = cs * c->uv[v * 2] - sn * c->uv[v * 2 + 1], w = sn * c->uv[v * 2] + cs * c->uv[v * 2 + 1];
        c->uv[v * 2] = u;
        c->uv[v * 2 + 1] = w;
        lo[0] = fmin(lo[0], u); hi[0] = fmax(hi[0], u); lo[1] = fmin(lo[1], w); hi[1] = fmax(hi[1], w);
    }
    const bool turn = hi[1] - lo[1] > hi[0] - lo[0];
    for (size_t v = 0; v < c->nv; ++v) {
        double u = c->uv[v * 2] - lo[0], w = c->uv[v * 2 + 1] - lo[1];
        c->uv[v * 2] = turn ? w : u;
        c->uv[v * 2 + 1] = turn ? (hi[0] - lo[0]) - u : w;
    }
    c->w = turn ? hi[1] - lo[1] : hi[0] - lo[0];
    c->h = turn ? hi[0] - lo[0] : hi[1] - lo[1];
}

/* One density for every chart: scales it so its UV area equals its area in space, then turns it. */
static void chart_scale(const atlas *a, chart *c)
{
    double uv_area = 0, area = 0;
    for (size_t t = 0; t < c->nt; ++t) {
        const double *p[3];
        for (int k = 0; k < 3; ++k) p[k] = c->uv + (size_t)c->corner[t * 3 + k] * 2;
        uv_area += 0.5 * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]));
        area += a->area[c->tris[t]];
    }
    const double k = uv_area > 0 && area > 0 ? sqrt(area / uv_area) : 1.0;
    for (size_t v = 0; v < c->nv * 2; ++v) c->uv[v] *= k;
    chart_orient(c);
}

typedef struct chart_key { double size, h; uint32_t i; } chart_key;
static int by_size(const void *x, const void *y)
{
    const chart_key *a = x, *b = y;
    if (a->size != b->size) return a->size > b->size ? -1 : 1;
    if (a->h != b->h) return a->h > b->h ? -1 : 1;
    return a->i < b->i ? -1 : a->i > b->i;
}

/* A chart's footprint is its bilinear support: the texels whose centres lie within one texel
 * (on both axes) of some point of the chart, every texel a bilinear read on the chart can weigh
 * (texel_raster.c samples those whose square the chart meets, reaching less far). Packing keeps footprints disjoint, so each such
 * texel can hold its own chart's light and no read on a chart takes another's (the gutter
 * sources are chosen by chart, texel_raster.c). REACH_SLACK covers float UVs written after.
 * The grid a chart is rasterised into has its box's corner on a texel's edge, one texel above
 * and right of the grid's (a rectangle's texels then hold all of it), except along an axis where
 * the chart is w texels wide with w's fraction half or more: there its corner lies on a texel's
 * centre (ORIGIN), and it reaches floor(w + 2) columns rather than round(w + 2) (a chart of 0.5
 * to 1 texel, as scans' loose triangles are: 2 texels rather than 3). */
#define REACH 1.0
#define REACH_SLACK 1e-3
#define ORIGIN (0.5 + 2 * REACH_SLACK)
/* Charts whose grid has at least this many texels are also tried at PACK_TILTS angles between
 * quarter turns (11.25 degrees apart): large ragged charts nest into each other's bays (the low
 * resolution bunny at 128: 55 -> 59% from 4 angles to 8). Small ones fill holes as they are. */
#define PACK_TILTS 8
#define TILT_TEXELS 256
#define TILT_CHARTS 256 /* atlases of more charts pack upright only: a second packing per scale would cost most of their time */

typedef struct placement { int32_t x, y, turn, tilt; } placement;

/* Scratch for packing at one scale: the chart's footprint, turned, and what is packed. */
typedef struct packer {
    const atlas *a;
    int res, pad;
    const uint32_t *order;  /* the charts to pack, in turn */
    size_t n;
    int words;              /* 64-bit words per row of the map */
    uint8_t *bits;          /* the chart's footprint, unturned */
    uint64_t *mask;         /* the footprint turned, as rows of bits */
    uint64_t *occupied;     /* texels packed charts touch, grown by pad: res rows of words */
    int32_t *bottom;        /* [column] of the turned footprint */
    int32_t *floor;         /* [column] lowest texel not occupied */
    double cache_s;         /* the scale the cached supports are at */
    uint8_t **cache;        /* [chart * PACK_TILTS + tilt] its support at cache_s, else NULL: orders tried at one
                             * scale share them, and rasterising a scan's charts costs more than placing them */
} packer;

/* A chart tilted by tilt / PACK_TILTS of a quarter turn: the rotation and the corner of its box. */
typedef struct tilt_frame { double cs, sn, lo[2], w, h; } tilt_frame;

static tilt_frame chart_tilt(const chart *c, int tilt)
{
    tilt_frame f = {1, 0, {0, 0}, c->w, c->h};
    if (!tilt) return f;
    const double th = (PRT_PI / 2) * tilt / PACK_TILTS;
    f.cs = cos(th);
    f.sn = sin(th);
    double hi[2] = {-INFINITY, -INFINITY};
    f.lo[0] = f.lo[1] = INFINITY;
    for (size_t v = 0; v < c->nv; ++v) {
        const double u = f.cs * c->uv[v * 2] - f.sn * c->uv[v * 2 + 1], w = f.sn * c->uv[v * 2] + f.cs * c->uv[v * 2 + 1];
        f.lo[0] = fmin(f.lo[0], u); hi[0] = fmax(hi[0], u); f.lo[1] = fmin(f.lo[1], w); hi[1] = fmax(hi[1], w);
    }
    f.w = hi[0] - f.lo[0];
    f.h = hi[1] - f.lo[1];
    return f;
}

/* Where chart UV q lies in its grid at scale s, tilted by f: what packing rasterises and what the
 * layout writes, one expression for both. */
/* Where the box's corner lies in the grid along an axis where the chart is `extent` texels wide. */
static double grid_origin(double extent)
{
    const double frac = extent - floor(extent);
    return frac >= 0.5 && frac < 1 - 3 * REACH_SLACK ? ORIGIN : REACH;
}

static void grid_point(const tilt_frame *f, const double *q, double s, double out[2])
{
    out[0] = (f->cs * q[0] - f->sn * q[1] - f->lo[0]) * s + grid_origin(f->w * s);
    out[1] = (f->sn * q[0] + f->cs * q[1] - f->lo[1]) * s + grid_origin(f->h * s);
}

/* The chart's grid at scale s, tilted by f (turn 0): a w x h box holding every texel it reaches. */
static void chart_grid(const tilt_frame *f, double s, int *w, int *h)
{
    *w = (int)ceil(f->w * s + grid_origin(f->w * s) + REACH + REACH_SLACK);
    *h = (int)ceil(f->h * s + grid_origin(f->h * s) + REACH + REACH_SLACK);
}

/* Marks the texels of the chart's grid whose open square of half-side r about the centre the chart
 * meets (separating axes: the square's two, the triangles' edge normals): r = REACH + REACH_SLACK,
 * its bilinear support; r = 0.5, the texels holding some of its surface. */
static void footprint(packer *p, const chart *c, const tilt_frame *f, double s, int W, int H, double r)
{
    memset(p->bits, 0, (size_t)W * H);
    for (size_t t = 0; t < c->nt; ++t) {
        double u[3], v[3];
        for (int k = 0; k < 3; ++k) {
            double g[2];
            grid_point(f, c->uv + (size_t)c->corner[t * 3 + k] * 2, s, g);
            u[k] = g[0];
            v[k] = g[1];
        }
        const double ulo = fmin(u[0], fmin(u[1], u[2])), uhi = fmax(u[0], fmax(u[1], u[2]));
        const double vlo = fmin(v[0], fmin(v[1], v[2])), vhi = fmax(v[0], fmax(v[1], v[2]));
        double nx[3], ny[3], lo[3], hi[3];
        for (int e = 0; e < 3; ++e) {
            const int j = (e + 1) % 3, k = (e + 2) % 3;
            nx[e] = v[j] - v[e];
            ny[e] = u[e] - u[j];
            const double a = nx[e] * u[e] + ny[e] * v[e], b = nx[e] * u[k] + ny[e] * v[k];
            lo[e] = fmin(a, b);
            hi[e] = fmax(a, b);
        }
        const int x0 = (int)fmax(0, floor(ulo - r)), x1 = (int)fmin(W, ceil(uhi + r));
        const int y0 = (int)fmax(0, floor(vlo - r)), y1 = (int)fmin(H, ceil(vhi + r));
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const double px = x + 0.5, py = y + 0.5;
                if (ulo >= px + r || uhi <= px - r || vlo >= py + r || vhi <= py - r) continue;
                bool apart = false;
                for (int e = 0; e < 3 && !apart; ++e) {
                    const double cproj = nx[e] * px + ny[e] * py, half = r * (fabs(nx[e]) + fabs(ny[e]));
                    apart = half > 0 && (hi[e] <= cproj - half || lo[e] >= cproj + half);
                }
                if (!apart) p->bits[(size_t)y * W + x] = 1;
            }
    }
}

/* The footprint turned by turn quarters counter-clockwise about its grid (texel (x, y) of the
 * W x H grid goes to (H - 1 - y, x) at one turn), as rows of bits, and the lowest touched row of
 * each column (INT32_MAX where none); its width and height. */
static void turned(packer *p, const uint8_t *bits, int W, int H, int turn, int *w_out, int *h_out)
{
    const int w = turn & 1 ? H : W, h = turn & 1 ? W : H, words = (w + 63) / 64;
    memset(p->mask, 0, (size_t)h * words * sizeof *p->mask);
    for (int x = 0; x < w; ++x) p->bottom[x] = INT32_MAX;
    int height = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            if (!bits[(size_t)y * W + x]) continue;
            const int tx = turn == 0 ? x : turn == 1 ? H - 1 - y : turn == 2 ? W - 1 - x : y;
            const int ty = turn == 0 ? y : turn == 1 ? x : turn == 2 ? H - 1 - y : W - 1 - x;
            p->mask[(size_t)ty * words + tx / 64] |= (uint64_t)1 << (tx % 64);
            if (ty < p->bottom[tx]) p->bottom[tx] = ty;
            if (ty + 1 > height) height = ty + 1;
        }
    *w_out = w;
    *h_out = height;
}

/* Chart ci's support (footprint at REACH + REACH_SLACK) tilted by f (tilt) at scale s, W x H:
 * from the cache where it holds it, else rasterised (into p->bits) and kept there. */
static const uint8_t *support(packer *p, uint32_t ci, int tilt, const tilt_frame *f, double s, int W, int H)
{
    uint8_t **slot = NULL;
    if (p->cache) {
        if (p->cache_s != s) {
            for (size_t i = 0; i < p->a->count * PACK_TILTS; ++i) { free(p->cache[i]); p->cache[i] = NULL; }
            p->cache_s = s;
        }
        slot = &p->cache[(size_t)ci * PACK_TILTS + tilt];
        if (*slot) return *slot;
    }
    footprint(p, &p->a->charts[ci], f, s, W, H, REACH + REACH_SLACK);
    if (slot && (*slot = malloc((size_t)W * H))) memcpy(*slot, p->bits, (size_t)W * H);   /* else uncached */
    return p->bits;
}

/* Does row r of the turned footprint (w wide) touch an occupied texel when its corner is at (x, y)? */
static bool row_hits(const packer *p, int w, int r, int x, int y)
{
    const int words = (w + 63) / 64, sh = x % 64, base = x / 64;
    const uint64_t *m = p->mask + (size_t)r * words, *o = p->occupied + (size_t)(y + r) * p->words + base;
    uint64_t carry = 0;
    for (int k = 0; k <= words; ++k) {
        const uint64_t cur = k < words ? m[k] : 0;
        const uint64_t v = sh ? (cur << sh) | carry : cur;
        carry = sh ? cur >> (64 - sh) : 0;
        if (v && (base + k >= p->words || (o[k] & v))) return true;
    }
    return false;
}

/* Does the turned footprint (w wide, h rows) touch no occupied texel when its corner is at (x, y)?
 * The row that last hit (*hint) is asked first: climbing past an obstacle, it mostly hits again. */
static bool fits(const packer *p, int w, int h, int x, int y, int *hint)
{
    if (*hint >= 0 && *hint < h && row_hits(p, w, *hint, x, y)) return false;
    for (int r = 0; r < h; ++r)
        if (r != *hint && row_hits(p, w, r, x, y)) { *hint = r; return false; }
    return true;
}

/* Marks the turned footprint at (x, y), grown by pad texels every way, as occupied. */
static void occupy(packer *p, int w, int h, int x, int y)
{
    const int words = (w + 63) / 64, res = p->res, pad = p->pad;
    for (int r = 0; r < h; ++r)
        for (int k = 0; k < w; ++k) {
            if (!(p->mask[(size_t)r * words + k / 64] >> (k % 64) & 1)) continue;
            for (int yy = y + r - pad; yy <= y + r + pad; ++yy) {
                if (yy < 0 || yy >= res) continue;
                for (int xx = x + k - pad; xx <= x + k + pad; ++xx)
                    if (xx >= 0 && xx < res) p->occupied[(size_t)yy * p->words + xx / 64] |= (uint64_t)1 << (xx % 64);
            }
        }
    for (int c = x - pad < 0 ? 0 : x - pad; c < x + w + pad && c < res; ++c) {
        while (p->floor[c] < res && p->occupied[(size_t)p->floor[c] * p->words + c / 64] >> (c % 64) & 1) p->floor[c]++;
    }
}

/* Packs the charts' footprints at scale s (texels per scene unit) into the map, largest first:
 * each, at each quarter turn, goes where its top lies lowest, down into any hole it fits (not
 * only onto the others' tops), its bilinear support apart from every other chart's (and pad more
 * empty texels between them). Corners in at, or false when some chart does not fit. */
static bool pack(packer *p, double s, bool tilt, placement *at, size_t *touched)
{
    const atlas *a = p->a;
    const int res = p->res;
    if (touched) *touched = 0;
    memset(p->occupied, 0, (size_t)res * p->words * sizeof *p->occupied);
    for (int x = 0; x < res; ++x) p->floor[x] = 0;
    for (size_t i = 0; i < p->n; ++i) {
        const uint32_t ci = p->order[i];
        const chart *c = &a->charts[ci];
        int W, H;
        tilt_frame f = chart_tilt(c, 0);
        chart_grid(&f, s, &W, &H);
        const int tilts = tilt && (int64_t)W * H >= TILT_TEXELS ? PACK_TILTS : 1;
        int64_t best_top = INT64_MAX;
        placement best = {0, 0, -1, 0};
        for (int k = 0; k < tilts; ++k) {
            f = chart_tilt(c, k);
            chart_grid(&f, s, &W, &H);
            if (W > res || H > res) continue;   /* turned or not, it needs both within the map (and bits holds no more) */
            const uint8_t *bits = support(p, ci, k, &f, s, W, H);
            for (int turn = 0; turn < 4; ++turn) {
                int w, h;
                if ((turn & 1 ? H : W) > res) continue;
                turned(p, bits, W, H, turn, &w, &h);
                int hint = -1;
                for (int x = 0; x + w <= res; ++x) {
                    /* From the lowest free texel under every column up; above all that is packed it fits. */
                    int64_t y = 0;
                    for (int j = 0; j < w; ++j)
                        if (p->bottom[j] != INT32_MAX && (int64_t)p->floor[x + j] - p->bottom[j] > y) y = (int64_t)p->floor[x + j] - p->bottom[j];
                    while (y + h < best_top && y + h <= res && !fits(p, w, h, x, (int)y, &hint)) y++;
                    if (y + h < best_top && y + h <= res) { best_top = y + h; best = (placement){x, (int32_t)y, turn, k}; }
                }
            }
        }
        if (best.turn < 0) return false;
        f = chart_tilt(c, best.tilt);
        chart_grid(&f, s, &W, &H);
        if (touched) {
            footprint(p, c, &f, s, W, H, 0.5);
            for (size_t i = 0; i < (size_t)W * H; ++i) *touched += p->bits[i];
        }
        const uint8_t *bits = support(p, ci, best.tilt, &f, s, W, H);
        int w, h;
        turned(p, bits, W, H, best.turn, &w, &h);
        occupy(p, w, h, best.x, best.y);
        if (at) at[ci] = best;
    }
    return true;
}

/* Can n charts fit at all? Each's support holds a texel at least, and texels of two charts' lie
 * more than pad apart on both axes, so the (pad + 1)-wide squares at their corners are disjoint
 * inside a map pad wider: n (pad + 1)^2 <= (res + pad)^2. */
static bool count_fits(size_t n, int res, int pad)
{
    return (double)n * (pad + 1) * (pad + 1) <= ((double)res + pad) * ((double)res + pad);
}

/* An order to pack charts in: n chart ids, largest mostly first. */
typedef struct pack_order { uint32_t *ids; size_t n; bool shuffled; } pack_order;

/* Does the order pack at scale s? Upright first, then (with few enough charts) tilted; which in *tilt. */
static bool packs(packer *pk, const pack_order *o, double s, bool *tilt)
{
    pk->order = o->ids;
    pk->n = o->n;
    if (pack(pk, s, false, NULL, NULL)) { *tilt = false; return true; }
    if (o->n <= TILT_CHARTS && pack(pk, s, true, NULL, NULL)) { *tilt = true; return true; }
    return false;
}

/* Packs the charts into res x res in the best of the orders: the largest scale (texels per scene
 * unit) that some order packed, by bisection, in *scale (0 when none fit at any), the order in
 * *which, the corners in at and the texels the charts touch in *touched (either may be NULL).
 * With total < 0 only whether they fit at all. */
static prt_status pack_map(const prt_context *ctx, const atlas *a, const pack_order *orders, int norders, int res, int pad, double total,
                           double *scale, int *which, placement *at, size_t *touched)
{
    *scale = 0;
    *which = 0;
    if (!a->count) return PRT_OK;
    const int side = res + 1;
    packer pk = {.a = a, .res = res, .pad = pad};
    pk.words = (res + 63) / 64;
    pk.bits = malloc((size_t)side * side);
    pk.mask = malloc((size_t)side * pk.words * sizeof *pk.mask);
    pk.occupied = malloc((size_t)side * pk.words * sizeof *pk.occupied);
    pk.bottom = malloc(side * sizeof *pk.bottom);
    pk.floor = malloc(side * sizeof *pk.floor);
    pk.cache = calloc(a->count * PACK_TILTS, sizeof *pk.cache);   /* none: all rasterised anew */
    pk.cache_s = -1;
    prt_status st = PRT_OK;
    if (!pk.bits || !pk.mask || !pk.occupied || !pk.bottom || !pk.floor) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    double best = 0;
    bool best_tilt = false, tilt = false;
    for (int v = 0; v < norders && !st; ++v) {
        const pack_order *o = &orders[v];
        if (!count_fits(o->n, res, pad) || (o->shuffled && total >= 0)) continue;
        if (total < 0) {
            if (packs(&pk, o, 0, &tilt)) { best = 1; *which = v; break; }
            continue;
        }
        /* The surface itself bounds the scale; packing at a scale is not monotone in it, so the
         * bisection keeps the largest scale that packed. Tilting large charts packs most maps
         * tighter but some looser (each chart takes what is best for it alone): a scale packs when
         * either way does, the upright one tried first. The cut charts need only search above
         * the uncut ones' scale. */
        double lo = 0, hi = res / sqrt(total);
        int steps = PACK_STEPS;
        bool packed = false, lo_tilt = false;
        if (best > 0) { lo = best; steps = PACK_STEPS / 2 - 2; }
        /* Most scans pack to well over 40% of the map: starting there saves most of the steps. */
        else if (packs(&pk, o, hi * sqrt(0.4), &tilt)) { lo = hi * sqrt(0.4); steps = PACK_STEPS / 2; packed = true; lo_tilt = tilt; }
        else if (!packs(&pk, o, 0, &tilt)) steps = 0;
        for (int it = 0; it < steps; ++it) {
            if (prt__cancelled(ctx)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "UV atlas cancelled"); break; }
            double mid = 0.5 * (lo + hi);
            if (packs(&pk, o, mid, &tilt)) { lo = mid; lo_tilt = tilt; packed = true; }
            else hi = mid;
        }
        /* Not monotone: a few scales just above the bisection's may pack too (the bunny at 128:
         * 70.6 -> 71.7%). */
        const double found = lo;
        for (int k = 1; k <= PACK_PROBES && found > 0 && !st; ++k)
            if (packs(&pk, o, found * (1 + 0.01 * k), &tilt)) { lo = found * (1 + 0.01 * k); lo_tilt = tilt; packed = true; }
        if (packed && lo > best) { best = lo; best_tilt = lo_tilt; *which = v; }
    }
    /* The shuffled orders at those scales above the best, each scale packing when one of them
     * does (the supports rasterised once per scale). */
    const double base = best;
    for (int k = 1; k <= PACK_PROBES && base > 0 && total >= 0 && !st; ++k) {
        if (prt__cancelled(ctx)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "UV atlas cancelled"); break; }
        const double sc = base * (1 + 0.01 * k);
        for (int v = 0; v < norders; ++v)
            if (orders[v].shuffled && count_fits(orders[v].n, res, pad) && packs(&pk, &orders[v], sc, &tilt)) {
                best = sc; best_tilt = tilt; *which = v;
                break;
            }
    }
    if (!st && best > 0) {
        *scale = best;
        if (total >= 0) {
            pk.order = orders[*which].ids;
            pk.n = orders[*which].n;
            pack(&pk, best, best_tilt, at, touched);
        }
    }
    for (size_t i = 0; pk.cache && i < a->count * PACK_TILTS; ++i) free(pk.cache[i]);
    free(pk.cache);
    free(pk.bits); free(pk.mask); free(pk.occupied); free(pk.bottom); free(pk.floor);
    return st;
}

/* ---- cutting ragged charts ---- */

/* A chart holding more than SPLIT_SHARE of the surface is a large piece of the map, and when its
 * outline is ragged no packing closes the bays around it (the low resolution bunny at 128: four
 * charts of 15-29%, filling half their boxes, 65% of the map). Such a chart is cut in two along a
 * straight line across its map (SPLIT_DIRS directions, SPLIT_CUTS places each) where the pieces'
 * boxes, each grown by the texels a chart's border costs, shrink the most, by SPLIT_GAIN at
 * least, or nearly as much along sharper creases; each piece keeps its part of the map, so it
 * stays as valid as the whole (and its density, rescaled as every chart is, the same). */
#define SPLIT_SHARE 0.0625
#define SPLIT_GAIN 0.10
#define SPLIT_DIRS 8
#define SPLIT_CUTS 15
#define SPLIT_MAX 64   /* cuts in one atlas */
#define SPLIT_SLACK 0.03

typedef struct cut_key { double key, area; uint32_t t; } cut_key;
static int by_cut(const void *x, const void *y)
{
    const cut_key *a = x, *b = y;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    return a->t < b->t ? -1 : a->t > b->t;
}

/* The smallest box (of PACK_ANGLES / 2 turns), each side grown by g, around the chart's vertices v[0..n). */
static double piece_box(const chart *c, const uint32_t *v, size_t n, double g)
{
    double best = INFINITY;
    for (int i = 0; i < PACK_ANGLES / 2; ++i) {
        const double th = PRT_PI * i / PACK_ANGLES, cs = cos(th), sn = sin(th);
        double lo0 = INFINITY, hi0 = -INFINITY, lo1 = INFINITY, hi1 = -INFINITY;
        for (size_t k = 0; k < n; ++k) {
            const double *q = c->uv + (size_t)v[k] * 2;
            const double u = cs * q[0] - sn * q[1], w = sn * q[0] + cs * q[1];
            lo0 = u < lo0 ? u : lo0; hi0 = u > hi0 ? u : hi0; lo1 = w < lo1 ? w : lo1; hi1 = w > hi1 ? w : hi1;
        }
        const double area = (hi0 - lo0 + g) * (hi1 - lo1 + g);
        best = area < best ? area : best;
    }
    return best;
}

typedef struct rim_edge { uint32_t a, b; } rim_edge;
static int by_rim_edge(const void *x, const void *y)
{
    const rim_edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    return p->b < q->b ? -1 : p->b > q->b;
}

/* rim[t]: triangle t of the chart has an edge on its border (no other triangle of the chart along
 * it); the longest edge of its map in *longest. False without memory. */
static bool chart_rim(const chart *c, uint8_t *rim, double *longest)
{
    rim_edge *e = malloc(c->nt * 3 * sizeof *e);
    if (!e) return false;
    *longest = 0;
    for (size_t t = 0; t < c->nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const uint32_t p = c->corner[t * 3 + k], q = c->corner[t * 3 + (k + 1) % 3];
            e[t * 3 + k] = (rim_edge){p < q ? p : q, p < q ? q : p};
            *longest = fmax(*longest, hypot(c->uv[p * 2] - c->uv[q * 2], c->uv[p * 2 + 1] - c->uv[q * 2 + 1]));
        }
    qsort(e, c->nt * 3, sizeof *e, by_rim_edge);
    memset(rim, 0, c->nt);
    for (size_t t = 0; t < c->nt; ++t)
        for (int k = 0; k < 3 && !rim[t]; ++k) {
            const uint32_t p = c->corner[t * 3 + k], q = c->corner[t * 3 + (k + 1) % 3];
            const rim_edge key = {p < q ? p : q, p < q ? q : p};
            const rim_edge *f = bsearch(&key, e, c->nt * 3, sizeof *e, by_rim_edge);
            /* bsearch finds one of the run: the edge is shared when a neighbour in the run matches. */
            rim[t] = !((f > e && !by_rim_edge(f - 1, &key)) || (f + 1 < e + c->nt * 3 && !by_rim_edge(f + 1, &key)));
        }
    free(e);
    return true;
}

/* Is the piece of triangles with side[t] == which joined through its vertices? */
static bool piece_joined(const chart *c, const uint8_t *side, uint8_t which, uint32_t *parent)
{
    for (size_t v = 0; v < c->nv; ++v) parent[v] = (uint32_t)v;
    uint32_t first = UINT32_MAX;
    for (size_t t = 0; t < c->nt; ++t) {
        if (side[t] != which) continue;
        const uint32_t *k = c->corner + t * 3;
        uf_union(parent, k[0], k[1]);
        uf_union(parent, k[0], k[2]);
        first = k[0];
    }
    if (first == UINT32_MAX) return false;
    const uint32_t root = uf_find(parent, first);
    for (size_t t = 0; t < c->nt; ++t)
        if (side[t] == which && uf_find(parent, c->corner[t * 3]) != root) return false;
    return true;
}

/* The triangles of c with side[t] == which as a chart of their own, their map as in c. */
static bool cut_piece(const chart *c, const uint8_t *side, uint8_t which, int32_t *local, chart *out)
{
    *out = (chart){0};
    out->valid = c->valid;
    for (size_t t = 0; t < c->nt; ++t) out->nt += side[t] == which;
    out->tris = malloc(out->nt * sizeof *out->tris);
    out->corner = malloc(out->nt * 3 * sizeof *out->corner);
    out->verts = malloc(out->nt * 3 * sizeof *out->verts);
    out->uv = malloc(out->nt * 3 * 2 * sizeof *out->uv);
    if (!out->tris || !out->corner || !out->verts || !out->uv) return false;
    for (size_t v = 0; v < c->nv; ++v) local[v] = -1;
    size_t n = 0;
    for (size_t t = 0; t < c->nt; ++t) {
        if (side[t] != which) continue;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = c->corner[t * 3 + k];
            if (local[v] < 0) {
                local[v] = (int32_t)out->nv;
                out->verts[out->nv] = c->verts[v];
                out->uv[out->nv * 2] = c->uv[v * 2];
                out->uv[out->nv * 2 + 1] = c->uv[v * 2 + 1];
                out->nv++;
            }
            out->corner[n * 3 + k] = (uint32_t)local[v];
        }
        out->tris[n++] = c->tris[t];
    }
    return true;
}

static void chart_free(chart *c)
{
    free(c->tris); free(c->verts); free(c->uv); free(c->corner);
}

static prt_status split_ragged(const prt_context *ctx, atlas *a, int res, int pad)
{
    /* A chart's border costs its reach and the padding beyond, on each side: in scene units at
     * about the density charts pack to (70% of the map). */
    const double g = (2 * REACH + pad + 1) * sqrt(a->total / 0.7) / res;
    int32_t *where = malloc(a->nt * sizeof *where);   /* [mesh triangle] its index in the chart being cut, else -1 */
    prt_status st = where ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    for (size_t t = 0; t < a->nt && !st; ++t) where[t] = -1;
    int cuts = 0;
    for (size_t ci = 0; ci < a->count && !st && cuts < SPLIT_MAX;) {
        chart *c = &a->charts[ci];
        double area = 0;
        for (size_t t = 0; t < c->nt; ++t) area += a->area[c->tris[t]];
        bool twins = false;
        for (size_t t = 0; t < c->nt && !twins; ++t) twins = a->twin[c->tris[t]];
        if (area <= SPLIT_SHARE * a->total || twins || c->nt < 8) { ci++; continue; }
        cut_key *keys = malloc(c->nt * sizeof *keys);
        uint8_t *side = malloc(c->nt), *best_side = malloc(c->nt);
        uint8_t *rim = malloc(c->nt);
        uint32_t *parent = malloc((c->nv + 1) * sizeof *parent), *outline[2] = {malloc(c->nt * 3 * sizeof **outline), malloc(c->nt * 3 * sizeof **outline)};
        int32_t *local = malloc((c->nv + 1) * sizeof *local);
        double longest = 0;
        if (!keys || !side || !best_side || !rim || !parent || !outline[0] || !outline[1] || !local || !chart_rim(c, rim, &longest))
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
        /* A piece's box is its outline's: triangles on the chart's border, or beside the cut - whose
         * keys (three corners' projections) lie within two edges of it. */
        const double band = 2 * longest * (1 + 1e-6) + 1e-12;
        const double whole = (c->w + g) * (c->h + g);
        double best = whole * (1 - SPLIT_GAIN), limit = 0, best_crease = -1;
        bool found = false;
        for (size_t t = 0; t < c->nt && !st; ++t) where[c->tris[t]] = (int32_t)t;
        /* Two rounds: the smallest boxes, then of the cuts within SPLIT_SLACK of them the one
         * running most along creases (the mean of 1 - cos of the normals across its edges), where
         * a seam shows least and the map bends most. */
        for (int round = 0; round < 2 && !st; ++round) {
            if (round) { if (!found) break; limit = fmin(best * (1 + SPLIT_SLACK), whole * (1 - SPLIT_GAIN)); }
            for (int dir = 0; dir < SPLIT_DIRS && !st; ++dir) {
                const double th = PRT_PI * dir / SPLIT_DIRS, cs = cos(th), sn = sin(th);
                for (size_t t = 0; t < c->nt; ++t) {
                    double k = 0;
                    for (int j = 0; j < 3; ++j) {
                        const double *q = c->uv + (size_t)c->corner[t * 3 + j] * 2;
                        k += cs * q[0] + sn * q[1];
                    }
                    keys[t] = (cut_key){k, a->area[c->tris[t]], (uint32_t)t};
                }
                qsort(keys, c->nt, sizeof *keys, by_cut);
                double run = 0;
                size_t i = 0;
                for (int q = 1; q <= SPLIT_CUTS; ++q) {
                    const double at = area * q / (SPLIT_CUTS + 1);
                    while (i < c->nt && run + keys[i].area <= at) run += keys[i++].area;
                    if (i == 0 || i == c->nt) continue;
                    for (size_t j = 0; j < c->nt; ++j) side[keys[j].t] = j >= i;
                    if (!piece_joined(c, side, 0, parent) || !piece_joined(c, side, 1, parent)) continue;
                    size_t n[2] = {0, 0};
                    for (size_t j = 0; j < c->nt; ++j) {
                        const uint32_t t = keys[j].t;
                        if (!rim[t] && fabs(keys[j].key - keys[i].key) > band) continue;
                        for (int k = 0; k < 3; ++k) outline[side[t]][n[side[t]]++] = c->corner[t * 3 + k];
                    }
                    const double cost = piece_box(c, outline[0], n[0], g) + piece_box(c, outline[1], n[1], g);
                    if (!round) {
                        if (cost < best) { best = cost; found = true; }
                        continue;
                    }
                    if (cost > limit) continue;
                    double crease = 0;
                    size_t edges = 0;
                    for (size_t t = 0; t < c->nt; ++t) {
                        if (side[t]) continue;
                        for (int k = 0; k < 3; ++k) {
                            const int64_t o = a->across[(size_t)c->tris[t] * 3 + k];
                            if (o < 0 || where[o] < 0 || !side[where[o]]) continue;
                            const double *n0 = a->smooth + (size_t)c->tris[t] * 3, *n1 = a->smooth + (size_t)o * 3;
                            crease += 1 - (n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2]);
                            edges++;
                        }
                    }
                    crease = edges ? crease / edges : 0;
                    if (crease > best_crease) { best_crease = crease; memcpy(best_side, side, c->nt); }
                }
            }
        }
        for (size_t t = 0; t < c->nt; ++t) where[c->tris[t]] = -1;
        /* The whole stays beside its pieces: packing tries the map either way (pack_map). */
        if (!st && found) {
            chart p[2];
            const bool ok0 = cut_piece(c, best_side, 0, local, &p[0]), ok1 = cut_piece(c, best_side, 1, local, &p[1]);
            for (int k = 0; k < 2 && ok0 && ok1 && !st; ++k) {
                p[k].cut = CUT_PIECE;
                chart_scale(a, &p[k]);
                if (!keep_chart(a, &p[k])) { chart_free(&p[k]); if (!k) chart_free(&p[1]); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); }
            }
            if (!ok0 || !ok1) { chart_free(&p[0]); chart_free(&p[1]); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); }
            a->charts[ci].cut |= CUT_WHOLE;   /* keep_chart may have moved the charts */
            cuts++;
        }
        ci++;
        free(keys); free(side); free(best_side); free(rim); free(parent); free(outline[0]); free(outline[1]); free(local);
    }
    free(where);
    return st;
}

/* The orders packing tries: the charts uncut (those split_ragged cut kept whole), largest box
 * first (the small ones fill the room left around them), then PACK_ORDERS - 1 shuffles of that
 * (neighbours among the ten largest swapped at random, deterministically): which packs tightest
 * differs from map to map (the coarse bumpy sphere at 128: 68.6% in the first, 71% in a shuffle).
 * Then the same with the cut pieces in place of their wholes, where some were cut. */
static prt_status pack_orders(const prt_context *ctx, const atlas *a, int res, pack_order *orders, int *norders)
{
    bool any_cut = false;
    for (size_t i = 0; i < a->count; ++i) any_cut |= a->charts[i].cut != 0;
    chart_key *keys = malloc(a->count * sizeof *keys);
    if (!keys) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    prt_status st = PRT_OK;
    *norders = 0;
    for (int set = 0; set < (any_cut ? 2 : 1) && !st; ++set) {
        const uint8_t skip = set ? CUT_WHOLE : CUT_PIECE;
        size_t n = 0;
        for (size_t i = 0; i < a->count; ++i)
            if (!(a->charts[i].cut & skip)) keys[n++] = (chart_key){a->charts[i].w * a->charts[i].h, a->charts[i].h, (uint32_t)i};
        qsort(keys, n, sizeof *keys, by_size);
        uint32_t h = 12345;
        for (int k = 0; k < (res <= SHUFFLE_RES && n <= SHUFFLE_CHARTS ? PACK_ORDERS : 1) && !st; ++k) {
            pack_order *o = &orders[(*norders)++];
            o->n = n;
            o->shuffled = k > 0;
            o->ids = malloc(n * sizeof *o->ids + 1);
            if (!o->ids) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); break; }
            for (size_t i = 0; i < n; ++i) o->ids[i] = keys[i].i;
            for (size_t i = 0; k && i + 1 < n && i + 1 < 10; ++i) {
                h = h * 1664525u + 1013904223u;
                if ((h >> 16) % 3 == 0) { const uint32_t t = o->ids[i]; o->ids[i] = o->ids[i + 1]; o->ids[i + 1] = t; }
            }
        }
    }
    free(keys);
    return st;
}

/* Keeps the charts of the order that packed (at, indexed by chart, follows them); frees the rest. */
static prt_status keep_packed(const prt_context *ctx, atlas *a, const pack_order *o, placement *at)
{
    uint8_t *in = calloc(a->count + 1, 1);
    if (!in) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    for (size_t i = 0; i < o->n; ++i) in[o->ids[i]] = 1;
    size_t live = 0;
    for (size_t ci = 0; ci < a->count; ++ci) {
        if (!in[ci]) { chart_free(&a->charts[ci]); continue; }
        at[live] = at[ci];
        a->charts[live++] = a->charts[ci];
    }
    a->count = live;
    free(in);
    return PRT_OK;
}

/* ---- the mesh with its new vertices ---- */

static prt_status write_layout(const prt_context *ctx, atlas *a, prt__mesh *m, const placement *at, double s, int res, size_t *added)
{
    const size_t nv = m->vertex_count, nt = m->triangle_count;
    /* A mesh vertex keeps its id in the first chart vertex that uses it; every other chart vertex
     * at it (across a seam, or the other fan of a pinch) gets a copy. */
    uint32_t *own_c = malloc(nv * sizeof *own_c), *own_v = malloc(nv * sizeof *own_v);
    uint32_t *dup = malloc(nv * sizeof *dup), *dup_c = malloc(nv * sizeof *dup_c), *dup_v = malloc(nv * sizeof *dup_v);
    uint32_t *ids = malloc(nt * 3 * sizeof *ids), *src = NULL;
    size_t extra = 0, cap = 0;
    bool ok = own_c && own_v && dup && dup_c && dup_v && ids;
    for (size_t v = 0; ok && v < nv; ++v) { own_c[v] = UINT32_MAX; dup_c[v] = UINT32_MAX; }
    for (size_t ci = 0; ok && ci < a->count; ++ci) {
        const chart *c = &a->charts[ci];
        for (size_t i = 0; ok && i < c->nt * 3; ++i) {
            const size_t slot = (size_t)c->tris[i / 3] * 3 + i % 3;
            const uint32_t o = m->indices[slot], v = c->corner[i];
            if (own_c[o] == UINT32_MAX) { own_c[o] = (uint32_t)ci; own_v[o] = v; }
            if (own_c[o] == ci && own_v[o] == v) { ids[slot] = o; continue; }
            if (dup_c[o] != ci || dup_v[o] != v) {
                if (nv + extra >= UINT32_MAX) { free(own_c); free(own_v); free(dup); free(dup_c); free(dup_v); free(ids); free(src);
                    return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the UV atlas would need more than 2^32 vertices"); }
                if (extra == cap) {
                    cap = cap ? cap * 2 : 1024;
                    uint32_t *ns = realloc(src, cap * sizeof *ns);
                    if (!ns) { ok = false; break; }
                    src = ns;
                }
                dup_c[o] = (uint32_t)ci; dup_v[o] = v;
                dup[o] = (uint32_t)(nv + extra);
                src[extra++] = o;
            }
            ids[slot] = dup[o];
        }
    }
    free(own_c); free(own_v); free(dup); free(dup_c); free(dup_v);
    /* A duplicate face takes the vertices of its duplicate's corners at its own (share_duplicates). */
    for (size_t t = 0; ok && t < nt; ++t) {
        const uint32_t d = a->share[t];
        if (d == t) continue;
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j)
                if (a->weld[m->indices[t * 3 + k]] == a->weld[m->indices[(size_t)d * 3 + j]]) { ids[t * 3 + k] = ids[(size_t)d * 3 + j]; break; }
    }
    const size_t nv2 = nv + extra;
#define GROW(p, n) do { if (ok) { void *q_ = realloc((p), (n)); if (q_) (p) = q_; else ok = false; } } while (0)
    GROW(m->positions, nv2 * 3 * sizeof(float));
    GROW(m->normals, nv2 * 3 * sizeof(float));
    GROW(m->albedo, nv2 * 3 * sizeof(float));
    GROW(m->material, nv2);
    GROW(m->uv, nv2 * 2 * sizeof(float));
    if (m->surface) GROW(m->surface, nv2 * sizeof(uint16_t));
    if (m->emission) GROW(m->emission, nv2 * 3 * sizeof(float));
#undef GROW
    if (!ok) { free(ids); free(src); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas"); }
    for (size_t k = 0; k < extra; ++k) {
        const size_t o = src[k], next = nv + k;
        memcpy(m->positions + next * 3, m->positions + o * 3, 3 * sizeof(float));
        memcpy(m->normals + next * 3, m->normals + o * 3, 3 * sizeof(float));
        memcpy(m->albedo + next * 3, m->albedo + o * 3, 3 * sizeof(float));
        m->material[next] = m->material[o];
        if (m->surface) m->surface[next] = m->surface[o];
        if (m->emission) memcpy(m->emission + next * 3, m->emission + o * 3, 3 * sizeof(float));
    }
    for (size_t ci = 0; ci < a->count; ++ci) {
        const chart *c = &a->charts[ci];
        int W, H;
        const tilt_frame f = chart_tilt(c, at[ci].tilt);
        chart_grid(&f, s, &W, &H);
        for (size_t i = 0; i < c->nt * 3; ++i) {
            const size_t slot = (size_t)c->tris[i / 3] * 3 + i % 3;
            const uint32_t id = ids[slot];
            m->indices[slot] = id;
            /* Where packing put it: its grid turned about the grid's corner (texels onto texels). */
            double g[2];
            grid_point(&f, c->uv + (size_t)c->corner[i] * 2, s, g);
            const double gx = g[0], gy = g[1];
            const int turn = at[ci].turn;
            const double tx = turn == 0 ? gx : turn == 1 ? H - gy : turn == 2 ? W - gx : gy;
            const double ty = turn == 0 ? gy : turn == 1 ? gx : turn == 2 ? H - gy : W - gx;
            m->uv[(size_t)id * 2] = (float)((at[ci].x + tx) / res);
            m->uv[(size_t)id * 2 + 1] = (float)((at[ci].y + ty) / res);
        }
    }
    for (size_t t = 0; t < nt; ++t)
        if (a->share[t] != t) memcpy(m->indices + t * 3, ids + t * 3, 3 * sizeof *ids);
    m->vertex_count = nv2;
    *added = extra;
    free(ids);
    free(src);
    return PRT_OK;
}

prt_status prt__uv_atlas(const prt_context *ctx, prt__mesh *m, const prt__atlas_desc *d, prt__atlas_report *report)
{
    prt__atlas_report rep = {0};
    const int pad = d->padding > 0 ? d->padding : 0;
    const double max_angle = d->max_angle > 0 ? d->max_angle : 60.0;
    if (d->resolution < 1) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "UV atlas resolution %d must be positive", d->resolution);
    if (!(max_angle < 90.0)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "UV atlas chart angle must be below 90 degrees");
    if (!m->triangle_count) return prt__fail(ctx, PRT_ERR_EMPTY, "no triangles to lay out in UV space");
    atlas a = {0};
    a.ctx = ctx;
    a.m = m;
    a.nt = m->triangle_count;
    a.weld = malloc(m->vertex_count * sizeof *a.weld);
    a.rep = malloc(m->vertex_count * sizeof *a.rep);
    a.across = malloc(a.nt * 3 * sizeof *a.across);
    a.normal = malloc(a.nt * 3 * sizeof *a.normal);
    a.area = malloc(a.nt * sizeof *a.area);
    a.smooth = malloc(a.nt * 3 * sizeof *a.smooth);
    a.stamp = calloc(a.nt, sizeof *a.stamp);
    a.twin = calloc(a.nt, 1);
    a.share = malloc(a.nt * sizeof *a.share);
    a.fan = malloc(a.nt * 3 * sizeof *a.fan);
    prt_status st = PRT_OK;
    double total = 0;
    if (!a.weld || !a.rep || !a.across || !a.normal || !a.smooth || !a.area || !a.stamp || !a.twin || !a.share || !a.fan) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    for (size_t t = 0; t < a.nt && !st; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        const float *p0 = m->positions + ix[0] * 3, *p1 = m->positions + ix[1] * 3, *p2 = m->positions + ix[2] * 3;
        double e1[3], e2[3], n[3];
        for (int c = 0; c < 3; ++c) { e1[c] = (double)p1[c] - p0[c]; e2[c] = (double)p2[c] - p0[c]; }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1]; n[1] = e1[2] * e2[0] - e1[0] * e2[2]; n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        a.area[t] = 0.5 * l;
        total += a.area[t];
        for (int c = 0; c < 3; ++c) a.normal[t * 3 + c] = l > 0 ? n[c] / l : 0.0;
        /* Scans are noisy: face normals swing from triangle to triangle and would cut charts
         * into crumbs; the vertex normals' mean follows the surface's shape. */
        double sn[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) sn[c] += m->normals[ix[k] * 3 + c];
        double sl = sqrt(sn[0] * sn[0] + sn[1] * sn[1] + sn[2] * sn[2]);
        for (int c = 0; c < 3; ++c) a.smooth[t * 3 + c] = sl != 0 ? sn[c] / sl : a.normal[t * 3 + c];
    }
    if (!st && !(total > 0)) st = prt__fail(ctx, PRT_ERR_EMPTY, "the mesh has no area to lay out in UV space");
    if (!st && !build_adjacency(&a)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    /* Back-to-back twins share their vertex normals: the one facing the other way grows by their
     * opposite, so it never joins its twin's chart (both would map to one place). */
    for (size_t t = 0; t < a.nt && !st; ++t) {
        double *sm = a.smooth + t * 3;
        const double *n = a.normal + t * 3;
        if (a.twin[t] && sm[0] * n[0] + sm[1] * n[1] + sm[2] * n[2] < 0)
            for (int c = 0; c < 3; ++c) sm[c] = -sm[c];
    }
    if (!st) {
        a.vlocal = malloc(a.nt * 3 * sizeof *a.vlocal);
        if (!a.vlocal) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
        else for (size_t i = 0; i < a.nt * 3; ++i) a.vlocal[i] = -1;
    }
    if (!st) st = grow_charts(ctx, &a, cos(max_angle * PRT_PI / 180.0));
    a.total = total;
    if (!st) st = merge_charts(ctx, &a);
    if (!st) st = join_flat_pieces(ctx, &a, diagonal_of(m));
    if (!st) st = share_duplicates(ctx, &a);
    placement *at = NULL;
    pack_order orders[2 * PACK_ORDERS] = {{0}};
    int norders = 0, which = 0;
    double s = 0;
    int res = d->resolution;
    if (!st) {
        for (size_t ci = 0; ci < a.count; ++ci) chart_scale(&a, &a.charts[ci]);
        st = split_ragged(ctx, &a, res, pad);
        if (!st) st = pack_orders(ctx, &a, res, orders, &norders);
        at = malloc(a.count * sizeof *at);
        if (!st && !at) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
    }
    /* The map: the size asked for, else (up to max_resolution) twice as wide while the charts do
     * not fit or touch under MIN_COVER of its texels. Packing is cheap next to the charting. */
    const int max_res = d->max_resolution > res ? d->max_resolution : res;
    while (!st) {
        size_t touched = 0;
        st = pack_map(ctx, &a, orders, norders, res, pad, total, &s, &which, at, &touched);
        if (st) break;
        const double cover = (double)touched / ((double)res * res);
        if (s > 0 && (cover >= MIN_COVER || res == max_res)) break;
        if (res * 2 > max_res || res > INT_MAX / 2) break;
        rep.smaller = res;
        rep.smaller_fit = s > 0;
        rep.smaller_cover = cover;
        res *= 2;
    }
    if (!st && !(s > 0)) {
        /* It fits nowhere it may go: say which map would hold the charts at all. */
        int need = res;
        double s0 = 0;
        while (!st && !(s0 > 0) && need <= ATLAS_MAX_RES / 2) {
            need *= 2;
            st = pack_map(ctx, &a, orders, norders, need, pad, -1, &s0, &which, NULL, NULL);
        }
        if (!st && s0 > 0)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%zu UV charts do not fit in %d x %d texels: --texels %d would hold them",
                           orders[0].n, res, res, need);
        else if (!st && need > res)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%zu UV charts do not fit in %d x %d texels, nor in %d x %d",
                           orders[0].n, res, res, need, need);
        else if (!st)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%zu UV charts do not fit in %d x %d texels", orders[0].n, res, res);
    }
    if (!st) st = keep_packed(ctx, &a, &orders[which], at);
    if (!st) rep.cut = a.count - orders[0].n;   /* the uncut charts are the first order's */
    if (!st) {
        rep.resolution = res;
        st = write_layout(ctx, &a, m, at, s, res, &rep.added_vertices);
    }
    if (!st) {
        rep.charts = a.count;
        rep.shared = a.shared;
        rep.glued = a.glued;
        rep.flattened = a.flattened;
        rep.grown = a.grown;
        if (a.unchecked)
            prt__log(ctx, PRT_LOG_WARN, "UV atlas: %zu charts could not be flattened without folds or overlap after %d cuts; their texels may be shared",
                     a.unchecked, SPLIT_DEPTH);
        /* Texels holding some of the surface, as the per-texel bakes count them. */
        float *texel_area = malloc((size_t)res * res * sizeof *texel_area);
        if (!texel_area || !prt__texel_areas(m, res, res, texel_area)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the UV atlas");
        size_t on = 0;
        for (size_t i = 0; !st && i < (size_t)res * res; ++i) on += texel_area[i] > 0;
        free(texel_area);
        rep.coverage = (double)on / ((double)res * res);
        rep.texel_density = s * s;
        for (size_t t = 0; t < m->triangle_count; ++t) {
            double r = prt__uv_stretch(m, t);
            if (r > rep.worst_stretch) rep.worst_stretch = r;
        }
        if (report && !st) *report = rep;
    }
    for (size_t i = 0; i < a.count; ++i) { free(a.charts[i].tris); free(a.charts[i].verts); free(a.charts[i].uv); free(a.charts[i].corner); }
    free(a.charts);
    free(a.weld); free(a.rep); free(a.across); free(a.normal); free(a.smooth); free(a.area); free(a.stamp); free(a.twin); free(a.share); free(a.vlocal); free(a.fan);
    for (int k = 0; k < norders; ++k) free(orders[k].ids);
    free(at);
    return st;
}

bool prt__uv_layout_unusable(const prt__mesh *m, int resolution, char *why, size_t why_size)
{
    if (!prt__mesh_has_uv(m)) {
        snprintf(why, why_size, "%s", m->uv && m->vertex_count && isfinite(m->uv[0]) ? "some vertices have no texture coordinates" : "it has no texture coordinates");
        return true;
    }
    size_t outside = 0;
    for (size_t v = 0; v < m->vertex_count; ++v)
        outside += !(m->uv[v * 2] >= -1e-3f && m->uv[v * 2] <= 1.001f && m->uv[v * 2 + 1] >= -1e-3f && m->uv[v * 2 + 1] <= 1.001f);
    if (outside) { snprintf(why, why_size, "%zu of its texture coordinates lie outside [0, 1]", outside); return true; }
    const int W = resolution, H = resolution;
    uint8_t *hit = calloc((size_t)W * H, 1), *dup = hit ? prt__texel_duplicates(m) : NULL;
    if (!dup) { free(hit); snprintf(why, why_size, "its UV layout could not be checked (out of memory)"); return true; }
    size_t overlap = 0, covered = 0;
    for (size_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t *ix = m->indices + t * 3;
        if (dup[t]) continue;   /* a duplicate face on its face's texels: one surface */
        float u[3], v[3];
        for (int k = 0; k < 3; ++k) { u[k] = m->uv[ix[k] * 2] * W; v[k] = m->uv[ix[k] * 2 + 1] * H; }
        float area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
        if (area == 0.0f) continue;
        int x0 = (int)floorf(fminf(u[0], fminf(u[1], u[2]))), x1 = (int)ceilf(fmaxf(u[0], fmaxf(u[1], u[2])));
        int y0 = (int)floorf(fminf(v[0], fminf(v[1], v[2]))), y1 = (int)ceilf(fmaxf(v[0], fmaxf(v[1], v[2])));
        for (int y = y0 < 0 ? 0 : y0; y < y1 && y < H; ++y)
            for (int x = x0 < 0 ? 0 : x0; x < x1 && x < W; ++x) {
                float px = x + 0.5f, py = y + 0.5f;
                float b1 = ((px - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (py - v[0])) / area;
                float b2 = ((u[1] - u[0]) * (py - v[0]) - (px - u[0]) * (v[1] - v[0])) / area;
                if (b1 < -1e-6f || b2 < -1e-6f || b1 + b2 > 1.0f + 1e-6f) continue;
                /* Centres on a shared edge belong to both triangles: only one strictly inside
                 * two is an overlap. */
                const bool strict = b1 > 1e-4f && b2 > 1e-4f && b1 + b2 < 1.0f - 1e-4f;
                uint8_t *h = hit + (size_t)y * W + x;
                if (!*h) covered++;
                if (strict && (*h & 2) && !(*h & 4)) { overlap++; *h |= 4; }   /* each texel once, however many claim it */
                *h |= strict ? 3 : 1;
            }
    }
    free(hit);
    free(dup);
    if (!covered) { snprintf(why, why_size, "its texture coordinates cover no texel centre of a %dx%d map", W, H); return true; }
    if (overlap * 100 > covered) {
        snprintf(why, why_size, "its UV layout overlaps itself on %.1f%% of the texels it covers", 100.0 * overlap / covered);
        return true;
    }
    return false;
}
