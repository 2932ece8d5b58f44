/* Offsets for offset radiance transfer mapping: where transfer is strong, more offsets. The
 * importance of an offset is only known where it has been evaluated, so the density between
 * evaluated points is interpolated linearly over their Delaunay triangulation (qhull), sampled
 * exactly through three tetrahedra per triangle, refined with what each sample evaluates, and
 * finally sampled for the offsets the transfer maps are made for. Each offset then stands for the
 * integer offsets nearest to it (its Voronoi cell), and eq. 8 sums the texel areas over that cell
 * instead of multiplying one texel's area by the cell's size - the paper's fix for the bright and
 * dark polygons the product gives where texel areas vary. */
#include "methods/offset/sampling.h"

#include <libqhull_r/qhull_ra.h>

/* ---- Delaunay ---------------------------------------------------------------------------------- */

prt_status prt__delaunay2d(const prt_context *ctx, const double *xy, size_t n, uint32_t **tris, size_t *ntri)
{
    *tris = NULL;
    *ntri = 0;
    if (n < 3) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "a Delaunay triangulation needs 3 points or more (got %zu)", n);
    if (n > INT32_MAX / 2) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "too many points to triangulate (%zu)", n);
    coordT *pts = malloc(n * 2 * sizeof *pts);
    if (!pts) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory triangulating");
    memcpy(pts, xy, n * 2 * sizeof *pts);
    /* qhull reports through a FILE: keep its words for our own error message. */
    char *errtext = NULL;
    size_t errsize = 0;
    FILE *err = open_memstream(&errtext, &errsize);
    if (!err) { free(pts); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory triangulating"); }   /* qhull would print */
    qhT qh_qh;
    qhT *qh = &qh_qh;
    qh_zero(qh, err);
    /* d: Delaunay; Qbb: scale the lifted coordinate; Qc Qz: robust with cocircular input (a
     * regular grid is all cocircular quads); Qt: triangulated output. */
    char flags[] = "qhull d Qbb Qc Qz Qt";
    const int code = qh_new_qhull(qh, 2, (int)n, pts, False, flags, NULL, err);
    prt_status st = PRT_OK;
    if (code) {
        fflush(err);
        char first[200] = "";
        if (errtext) {
            snprintf(first, sizeof first, "%s", errtext);
            for (char *p = first; *p; ++p) if (*p == '\n') { *p = 0; break; }
        }
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "qhull could not triangulate %zu points (collinear or repeated?): %s", n, first);
    } else {
        size_t count = 0;
        facetT *facet;
        FORALLfacets
            if (!facet->upperdelaunay) count++;
        uint32_t *t = malloc(count * 3 * sizeof *t + 1);
        if (!t) {
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory triangulating");
        } else {
            size_t k = 0;
            FORALLfacets {
                if (facet->upperdelaunay) continue;
                vertexT *vertex, **vertexp;
                int c = 0;
                FOREACHvertex_(facet->vertices) if (c < 3) t[k * 3 + c++] = (uint32_t)qh_pointid(qh, vertex->point);
                /* Counter-clockwise. */
                const double *a = xy + t[k * 3] * 2, *b = xy + t[k * 3 + 1] * 2, *cc = xy + t[k * 3 + 2] * 2;
                if ((b[0] - a[0]) * (cc[1] - a[1]) - (b[1] - a[1]) * (cc[0] - a[0]) < 0) {
                    const uint32_t s = t[k * 3 + 1];
                    t[k * 3 + 1] = t[k * 3 + 2];
                    t[k * 3 + 2] = s;
                }
                k++;
            }
            *tris = t;
            *ntri = k;
        }
    }
    qh_freeqhull(qh, !qh_ALL);
    int curlong, totlong;
    qh_memfreeshort(qh, &curlong, &totlong);
    fclose(err);
    free(errtext);
    free(pts);
    return st;
}

/* ---- the piecewise-linear density ---------------------------------------------------------------- */

static double tri_area(const double *a, const double *b, const double *c)
{
    return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
}

void prt__plpdf_free(prt__plpdf *p)
{
    free(p->xy);
    free(p->w);
    free(p->tris);
    free(p->cdf);
    memset(p, 0, sizeof *p);
}

prt_status prt__plpdf_build(const prt_context *ctx, const double *xy, const double *w, size_t n, prt__plpdf *out)
{
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < n; ++i)
        if (!(w[i] >= 0) || !isfinite(w[i])) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "importance %g at point %zu is not finite and >= 0", w[i], i);
    prt_status st = prt__delaunay2d(ctx, xy, n, &out->tris, &out->ntri);
    if (st) return st;
    out->n = n;
    out->xy = malloc(n * 2 * sizeof *out->xy);
    out->w = malloc(n * sizeof *out->w);
    out->cdf = malloc(out->ntri * 3 * sizeof *out->cdf + 1);
    if (!out->xy || !out->w || !out->cdf) { prt__plpdf_free(out); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory building a density"); }
    memcpy(out->xy, xy, n * 2 * sizeof *xy);
    memcpy(out->w, w, n * sizeof *w);
    /* The prism under a triangle, its top the plane through the three weights, is three
     * tetrahedra: (a0 a1 a2 b0), (a1 a2 b0 b1), (a2 b0 b1 b2) with volumes area * w_k / 3. */
    double sum = 0;
    for (size_t t = 0; t < out->ntri; ++t) {
        const uint32_t *ix = out->tris + t * 3;
        const double area = tri_area(xy + ix[0] * 2, xy + ix[1] * 2, xy + ix[2] * 2);
        for (int k = 0; k < 3; ++k) {
            sum += area * w[ix[k]] / 3;
            out->cdf[t * 3 + k] = sum;
        }
    }
    if (!(sum > 0)) { prt__plpdf_free(out); return prt__fail(ctx, PRT_ERR_INVALID_ARG, "every importance is 0: nothing to sample"); }
    for (size_t i = 0; i < out->ntri * 3; ++i) out->cdf[i] /= sum;
    out->cdf[out->ntri * 3 - 1] = 1.0;
    out->total = sum;
    return PRT_OK;
}

double prt__plpdf_eval(const prt__plpdf *p, double x, double y)
{
    const double q[2] = {x, y};
    for (size_t t = 0; t < p->ntri; ++t) {
        const uint32_t *ix = p->tris + t * 3;
        const double *a = p->xy + ix[0] * 2, *b = p->xy + ix[1] * 2, *c = p->xy + ix[2] * 2;
        const double area = tri_area(a, b, c);
        if (!(area > 0)) continue;
        const double l0 = tri_area(q, b, c) / area, l1 = tri_area(a, q, c) / area, l2 = 1 - l0 - l1;
        const double eps = -1e-12;
        if (l0 >= eps && l1 >= eps && l2 >= eps) return (l0 * p->w[ix[0]] + l1 * p->w[ix[1]] + l2 * p->w[ix[2]]) / p->total;
    }
    return 0;
}

void prt__plpdf_sample(const prt__plpdf *p, const double u[4], double out[2])
{
    /* The first tetrahedron whose running volume passes u[0]. */
    size_t lo = 0, hi = p->ntri * 3 - 1;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (p->cdf[mid] <= u[0]) lo = mid + 1;
        else hi = mid;
    }
    const size_t t = lo / 3;
    const int k = (int)(lo % 3);
    const uint32_t *ix = p->tris + t * 3;
    /* Its corners as (x, y, z): a = base corners at z = 0, b = top corners at z = w. */
    double a[3][3], b[3][3], v[4][3];
    for (int j = 0; j < 3; ++j) {
        a[j][0] = b[j][0] = p->xy[ix[j] * 2];
        a[j][1] = b[j][1] = p->xy[ix[j] * 2 + 1];
        a[j][2] = 0;
        b[j][2] = p->w[ix[j]];
    }
    const double (*corner[3][4])[3] = {{&a[0], &a[1], &a[2], &b[0]}, {&a[1], &a[2], &b[0], &b[1]}, {&a[2], &b[0], &b[1], &b[2]}};
    for (int j = 0; j < 4; ++j) memcpy(v[j], *corner[k][j], sizeof v[j]);
    /* A point uniform in the unit cube folded into the corner tetrahedron s + t + r <= 1. */
    double s = u[1], tt = u[2], r = u[3];
    if (s + tt > 1) { s = 1 - s; tt = 1 - tt; }
    if (tt + r > 1) {
        const double tmp = r;
        r = 1 - s - tt;
        tt = 1 - tmp;
    } else if (s + tt + r > 1) {
        const double tmp = r;
        r = s + tt + r - 1;
        s = 1 - tt - tmp;
    }
    for (int c = 0; c < 2; ++c) out[c] = v[0][c] + s * (v[1][c] - v[0][c]) + tt * (v[2][c] - v[0][c]) + r * (v[3][c] - v[0][c]);
}

/* ---- Voronoi areas ------------------------------------------------------------------------------- */

/* Clips the convex polygon poly (n points) to the half-plane nrm . x <= d into out (room for
 * n + 1 points: a convex polygon gains at most one); returns its point count. */
static int clip(const double (*poly)[2], int n, const double nrm[2], double d, double (*out)[2])
{
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const double *p = poly[i], *q = poly[(i + 1) % n];
        const double dp = nrm[0] * p[0] + nrm[1] * p[1] - d, dq = nrm[0] * q[0] + nrm[1] * q[1] - d;
        if (dp <= 0) { out[m][0] = p[0]; out[m][1] = p[1]; m++; }
        if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
            const double f = dp / (dp - dq);
            out[m][0] = p[0] + f * (q[0] - p[0]);
            out[m][1] = p[1] + f * (q[1] - p[1]);
            m++;
        }
    }
    return m;
}

prt_status prt__voronoi_areas(const prt_context *ctx, const double *xy, size_t n, double *areas)
{
    for (size_t i = 0; i < n; ++i)
        if (!(fabs(xy[i * 2]) <= 1 && fabs(xy[i * 2 + 1]) <= 1)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "point %zu lies outside [-1, 1]^2", i);
    if (n == 1) { areas[0] = 4; return PRT_OK; }
    /* A cell is bounded by its Delaunay neighbours' bisectors; with two points (no triangle) each
     * is the other's neighbour. */
    uint32_t *tris = NULL;
    size_t nt = 0;
    if (n >= 3) {
        prt_status st = prt__delaunay2d(ctx, xy, n, &tris, &nt);
        if (st) return st;
    }
    uint32_t *start = prt__calloc(n + 1, sizeof *start), *nb = malloc((nt * 6 + 2) * sizeof *nb), *fill = prt__calloc(n, sizeof *fill);
    if (!start || !nb || !fill) { free(tris); free(start); free(nb); free(fill); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for Voronoi cells"); }
    if (n == 2) {
        start[1] = 1; start[2] = 2; nb[0] = 1; nb[1] = 0;
    } else {
        for (size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 3; ++k) start[tris[t * 3 + k] + 1] += 2;
        for (size_t i = 0; i < n; ++i) start[i + 1] += start[i];
        for (size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = tris[t * 3 + k];
                nb[start[v] + fill[v]++] = tris[t * 3 + (k + 1) % 3];
                nb[start[v] + fill[v]++] = tris[t * 3 + (k + 2) % 3];
            }
    }
    /* A point qhull left out (a repeated point) has no neighbours and would claim the square. */
    for (size_t i = 0; n > 2 && i < n; ++i)
        if (start[i + 1] == start[i]) {
            free(tris); free(start); free(nb); free(fill);
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "point %zu (%g, %g) repeats another or was left out of the triangulation", i, xy[i * 2], xy[i * 2 + 1]);
        }
    uint32_t most = 0;
    for (size_t i = 0; i < n; ++i) most = start[i + 1] - start[i] > most ? start[i + 1] - start[i] : most;
    /* A cell has at most 4 + (its bisectors) corners. */
    double (*a)[2] = malloc((most + 6) * sizeof *a), (*b)[2] = malloc((most + 6) * sizeof *b);
    if (!a || !b) { free(a); free(b); free(tris); free(start); free(nb); free(fill); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for Voronoi cells"); }
    for (size_t i = 0; i < n; ++i) {
        static const double square[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        memcpy(a, square, sizeof square);
        int m = 4;
        const double *p = xy + i * 2;
        for (uint32_t j = start[i]; j < start[i + 1] && m > 0; ++j) {
            const double *q = xy + nb[j] * 2;
            /* Nearer p than q: (q - p) . x <= (|q|^2 - |p|^2) / 2. */
            const double nrm[2] = {q[0] - p[0], q[1] - p[1]};
            m = clip((const double (*)[2])a, m, nrm, 0.5 * (q[0] * q[0] + q[1] * q[1] - p[0] * p[0] - p[1] * p[1]), b);
            double (*tmp)[2] = a; a = b; b = tmp;
        }
        double area = 0;
        for (int k = 0; k < m; ++k) area += a[k][0] * a[(k + 1) % m][1] - a[(k + 1) % m][0] * a[k][1];
        areas[i] = 0.5 * area;
    }
    free(a); free(b);
    free(tris); free(start); free(nb); free(fill);
    return PRT_OK;
}

/* ---- choosing offsets ------------------------------------------------------------------------------ */

static uint64_t next_random(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);   /* splitmix64 */
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *s) { return (double)(next_random(s) >> 11) * (1.0 / 9007199254740992.0); }

typedef struct offset_set {
    int *xy;                 /* integer offsets, 2 each */
    double *pos, *w;         /* normalised positions, importances */
    size_t n, cap;
    uint8_t *taken;          /* per integer offset of the (2W-1) x (2H-1) grid */
    int width, height;
} offset_set;

static bool offset_add(offset_set *o, int dx, int dy, double w)
{
    const size_t cell = (size_t)(dy + o->height - 1) * (size_t)(2 * o->width - 1) + (size_t)(dx + o->width - 1);
    if (o->taken[cell]) return false;
    if (o->n == o->cap) {
        const size_t cap = o->cap ? o->cap * 2 : 256;
        int *xy = realloc(o->xy, cap * 2 * sizeof *xy);
        if (xy) o->xy = xy;
        double *pos = xy ? realloc(o->pos, cap * 2 * sizeof *pos) : NULL;
        if (pos) o->pos = pos;
        double *ww = pos ? realloc(o->w, cap * sizeof *ww) : NULL;
        if (!ww) return false;
        o->w = ww;
        o->cap = cap;
    }
    o->taken[cell] = 1;
    o->xy[o->n * 2] = dx;
    o->xy[o->n * 2 + 1] = dy;
    o->pos[o->n * 2] = o->width > 1 ? (double)dx / (o->width - 1) : 0;
    o->pos[o->n * 2 + 1] = o->height > 1 ? (double)dy / (o->height - 1) : 0;
    o->w[o->n] = w;
    o->n++;
    return true;
}

/* The integer offset nearest to a normalised sample. */
static void snap(const offset_set *o, const double p[2], int *dx, int *dy)
{
    *dx = (int)lround(fmax(-1, fmin(1, p[0])) * (o->width - 1));
    *dy = (int)lround(fmax(-1, fmin(1, p[1])) * (o->height - 1));
}

/* The density from the data so far, with a floor of a thousandth of the largest importance, so
 * that no region of offsets is ruled out for good by the few points that first sampled it. */
static prt_status build_density(const prt_context *ctx, const offset_set *o, prt__plpdf *pdf)
{
    double top = 0;
    for (size_t i = 0; i < o->n; ++i) top = fmax(top, o->w[i]);
    double *w = malloc(o->n * sizeof *w);
    if (!w) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    for (size_t i = 0; i < o->n; ++i) w[i] = o->w[i] + (top > 0 ? 1e-3 * top : 1.0);
    const prt_status st = prt__plpdf_build(ctx, o->pos, w, o->n, pdf);
    free(w);
    return st;
}

prt_status prt__choose_offsets(const prt_context *ctx, const prt__offset_desc *d, prt__offset_importance_fn importance, void *user,
                               int **offsets, int *count)
{
    *offsets = NULL;
    *count = 0;
    if (!d || !importance || d->width < 2 || d->height < 2 || d->width > 16384 || d->height > 16384)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "choosing offsets needs a map of 2..16384 texels a side and an importance");
    const size_t all = (size_t)(2 * d->width - 1) * (size_t)(2 * d->height - 1);
    if (d->count < 1 || (size_t)d->count > all)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "offset count %d is not between 1 and the %zu integer offsets of the map", d->count, all);
    const int iterations = d->iterations > 0 ? d->iterations : 1000;
    offset_set data = {.width = d->width, .height = d->height, .taken = prt__calloc(all, 1)};
    offset_set chosen = {.width = d->width, .height = d->height, .taken = prt__calloc(all, 1)};
    prt_status st = data.taken && chosen.taken ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    /* The seed: an 11 x 11 grid over the whole range of offsets, (0, 0) at its centre. */
    for (int j = 0; !st && j <= 10; ++j)
        for (int i = 0; !st && i <= 10; ++i) {
            const double p[2] = {i / 5.0 - 1, j / 5.0 - 1};
            int dx, dy;
            snap(&data, p, &dx, &dy);
            if (!data.taken[(size_t)(dy + d->height - 1) * (size_t)(2 * d->width - 1) + (size_t)(dx + d->width - 1)]) offset_add(&data, dx, dy, 0);
        }
    if (!st && data.n) importance(user, data.xy, data.n, data.w);
    uint64_t rng = d->seed * 0x2545F4914F6CDD1Dull + 1;
    prt__plpdf pdf = {0};
    /* Refinement: samples from the current density add data points; rebuilt every 20. A sample's
     * importance only counts from the next build on, so the 20 drawn from one build are evaluated
     * together when the batch is complete: the same offsets as one at a time. */
    size_t pending = data.n;   /* the first data point not yet evaluated */
    for (int it = 0; !st && it < iterations && data.n < all; ++it) {
        if (it % 20 == 0) {
            if (pending < data.n) importance(user, data.xy + pending * 2, data.n - pending, data.w + pending);
            pending = data.n;
            prt__plpdf_free(&pdf);
            if ((st = build_density(ctx, &data, &pdf))) break;
            if (prt__cancelled(ctx)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled choosing offsets"); break; }
        }
        for (int tries = 0; tries < 64; ++tries) {   /* a sample at an offset already known adds nothing */
            const double u[4] = {uniform(&rng), uniform(&rng), uniform(&rng), uniform(&rng)};
            double p[2];
            int dx, dy;
            prt__plpdf_sample(&pdf, u, p);
            snap(&data, p, &dx, &dy);
            if (data.taken[(size_t)(dy + d->height - 1) * (size_t)(2 * d->width - 1) + (size_t)(dx + d->width - 1)]) continue;
            offset_add(&data, dx, dy, 0);
            break;
        }
    }
    if (!st && pending < data.n) importance(user, data.xy + pending * 2, data.n - pending, data.w + pending);
    /* The final offsets from the converged density: (0, 0) first (a texel's own light), then
     * distinct samples. */
    if (!st) {
        prt__plpdf_free(&pdf);
        st = build_density(ctx, &data, &pdf);
    }
    if (!st && !offset_add(&chosen, 0, 0, 0)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    for (size_t tries = 0; !st && chosen.n < (size_t)d->count && tries < 64 * (size_t)d->count; ++tries) {
        const double u[4] = {uniform(&rng), uniform(&rng), uniform(&rng), uniform(&rng)};
        double p[2];
        int dx, dy;
        prt__plpdf_sample(&pdf, u, p);
        snap(&chosen, p, &dx, &dy);
        const size_t before = chosen.n;
        if (!offset_add(&chosen, dx, dy, 0) && chosen.n == before &&
            !chosen.taken[(size_t)(dy + d->height - 1) * (size_t)(2 * d->width - 1) + (size_t)(dx + d->width - 1)])
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    }
    /* A density too peaked to give enough distinct offsets: the rest in a fixed scan. */
    for (size_t cell = 0; !st && cell < all && chosen.n < (size_t)d->count; ++cell)
        if (!chosen.taken[cell] &&
            !offset_add(&chosen, (int)(cell % (size_t)(2 * d->width - 1)) - (d->width - 1), (int)(cell / (size_t)(2 * d->width - 1)) - (d->height - 1), 0))
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    prt__plpdf_free(&pdf);
    if (!st && chosen.n == (size_t)d->count) {
        *offsets = chosen.xy;
        chosen.xy = NULL;
        *count = d->count;
    } else if (!st) {
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    }
    free(data.xy); free(data.pos); free(data.w); free(data.taken);
    free(chosen.xy); free(chosen.pos); free(chosen.w); free(chosen.taken);
    return st;
}

/* ---- eq. 8: Voronoi-summed texel areas ----------------------------------------------------------- */

typedef struct run { int k, dy, dx0, dx1; } run;

prt_status prt__offset_labels(const prt_context *ctx, int width, int height, const int *offsets, int count, int32_t **out)
{
    const int gw = 2 * width - 1, gh = 2 * height - 1;
    int32_t *label = malloc((size_t)gw * gh * sizeof *label);
    if (!label) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory labelling offsets");
    const double sx = width > 1 ? 1.0 / (width - 1) : 1, sy = height > 1 ? 1.0 / (height - 1) : 1;
#pragma omp parallel for schedule(dynamic, 4) num_threads(prt__threads(ctx))
    for (int y = 0; y < gh; ++y)
        for (int x = 0; x < gw; ++x) {
            const double px = (x - (width - 1)) * sx, py = (y - (height - 1)) * sy;
            double best = INFINITY;
            int32_t arg = 0;
            for (int k = 0; k < count; ++k) {
                const double ddx = px - offsets[k * 2] * sx, ddy = py - offsets[k * 2 + 1] * sy, d2 = ddx * ddx + ddy * ddy;
                if (d2 < best) { best = d2; arg = k; }
            }
            label[(size_t)y * gw + x] = arg;
        }
    *out = label;
    return PRT_OK;
}

void prt__offset_reps(const prt__offset_charts *c, int width, int height, const int *offsets, int count, int tx, int ty, int32_t *rep,
                      int32_t *rep_chart)
{
    for (int k = 0; k < count; ++k) {
        const int x = tx + offsets[k * 2], y = ty + offsets[k * 2 + 1];
        const int32_t src = x < 0 || x >= width || y < 0 || y >= height ? -1 : c->source[(size_t)y * width + x];
        rep[k] = src < 0 ? -1 : (int32_t)c->texel[src];
        rep_chart[k] = src < 0 ? -1 : c->chart[rep[k]];
    }
}

int prt__offset_recell(const prt__offset_charts *c, int width, const int *offsets, int count, int tx, int ty, const int32_t *rep,
                       const int32_t *rep_chart, int k, int sx, int sy, int chart)
{
    if (rep_chart[k] == chart) return k;
    int best = -1;
    double nearest = INFINITY;
    for (int o = 0; o < count; ++o) {   /* on its own chart, nearest in the map (ties to the lower index) */
        if (rep_chart[o] != chart) continue;
        const double dx = tx + offsets[o * 2] - sx, dy = ty + offsets[o * 2 + 1] - sy, d2 = dx * dx + dy * dy;
        if (d2 < nearest) { nearest = d2; best = o; }
    }
    if (best >= 0) return best;
    const float *q = c->pos + ((size_t)sy * width + sx) * 3;
    for (int o = 0; o < count; ++o) {   /* no offset lands on its chart: the nearest in space */
        if (rep[o] < 0) continue;
        const float *r = c->pos + (size_t)rep[o] * 3;
        const double dx = r[0] - q[0], dy = r[1] - q[1], dz = r[2] - q[2], d2 = dx * dx + dy * dy + dz * dz;
        if (d2 < nearest) { nearest = d2; best = o; }
    }
    return best >= 0 ? best : k;
}

prt_status prt__offset_tva(const prt_context *ctx, const float *area, int width, int height, const int *offsets, int count, float *out)
{
    if (width < 1 || height < 1 || width > 16384 || height > 16384 || count < 1 || !area || !offsets || !out)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "TVA needs a map, offsets and an output");
    const int gw = 2 * width - 1, gh = 2 * height - 1;
    /* Every integer offset labelled with its nearest chosen offset, row by row into runs. */
    int32_t *label = NULL;
    prt_status lst = prt__offset_labels(ctx, width, height, offsets, count, &label);
    if (lst) return lst;
    size_t nruns = 0, cap = (size_t)gh * 4 + 16;
    run *runs = malloc(cap * sizeof *runs);
    for (int y = 0; runs && y < gh; ++y)
        for (int x = 0; x < gw;) {
            int e = x;
            while (e + 1 < gw && label[(size_t)y * gw + e + 1] == label[(size_t)y * gw + x]) e++;
            if (nruns == cap) {
                run *r = realloc(runs, cap * 2 * sizeof *r);
                if (!r) { free(runs); runs = NULL; break; }
                runs = r;
                cap *= 2;
            }
            runs[nruns++] = (run){label[(size_t)y * gw + x], y - (height - 1), x - (width - 1), e - (width - 1)};
            x = e + 1;
        }
    free(label);
    /* Row prefix sums of the areas: a run is one subtraction. */
    double *prefix = runs ? malloc((size_t)height * (width + 1) * sizeof *prefix) : NULL;
    if (!prefix) { free(runs); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for TVA"); }
    for (int y = 0; y < height; ++y) {
        double *p = prefix + (size_t)y * (width + 1);
        p[0] = 0;
        for (int x = 0; x < width; ++x) p[x + 1] = p[x] + area[(size_t)y * width + x];
    }
    memset(out, 0, (size_t)width * height * count * sizeof *out);
#pragma omp parallel for schedule(dynamic, 16) num_threads(prt__threads(ctx))
    for (size_t t = 0; t < (size_t)width * height; ++t) {
        if (!(area[t] > 0)) continue;   /* only texels on the charts gather */
        const int tx = (int)(t % (size_t)width), ty = (int)(t / (size_t)width);
        float *o = out + t * count;
        for (size_t r = 0; r < nruns; ++r) {
            const run *u = &runs[r];
            const int y = ty + u->dy;
            if (y < 0 || y >= height) continue;
            const int x0 = tx + u->dx0 < 0 ? 0 : tx + u->dx0, x1 = tx + u->dx1 >= width ? width - 1 : tx + u->dx1;
            if (x0 > x1) continue;
            const double *p = prefix + (size_t)y * (width + 1);
            o[u->k] += (float)(p[x1 + 1] - p[x0]);
        }
    }
    free(prefix);
    free(runs);
    return PRT_OK;
}
