/* Photometric profiles from IESNA LM-63 files (1986, 1991, 1995 and 2002 forms): the keyword
 * header, TILT=NONE or INCLUDE, the numeric block and the candela table, read as hostile input -
 * every count bounded and checked against the bytes left before it sizes an allocation, every
 * number finite, angles strictly increasing over the ranges LM-63 allows. Only photometric type C
 * (every architectural luminaire's) is read; B and A (floodlights, automotive) are refused.
 *
 * Evaluation: vertical angle gamma from the photometric nadir, horizontal angle C about it from
 * the C0 plane; bilinear over the table, with the symmetries a horizontal range of 0 (one plane
 * for all), 90 (a quadrant mirrored), 180 (a half mirrored) or 360 degrees (wrapping) implies;
 * nothing outside the vertical range. The profile is immutable once read and shared by the lights
 * that use it (reference counted, atomically). */
#include "light/light_sample.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

/* Real files have at most a few hundred angles per axis (a 0.5-degree scan: 361 x 721). */
#define MAX_ANGLES 10000
#define MAX_VALUES (4u << 20)

struct prt_ies {
    int refs;                /* atomic */
    int nv, nh;
    float *v, *h;            /* angles, degrees */
    float *cd;               /* [h][v] candela, multipliers applied */
    float max_cd;
    char path[1024];         /* where it was read from ("" from memory) */
};

typedef struct reader {
    const char *p, *end;
    int line;
} reader;

static prt_status bad(int line, const char *fmt, const char *what)
{
    char msg[200];
    snprintf(msg, sizeof msg, fmt, what);
    return prt__fail(NULL, PRT_ERR_FORMAT, "IES: line %d: %s", line, msg);
}

/* The next line without its end (CR LF, LF or CR); false at the end of the data. */
static bool next_line(reader *r, const char **s, size_t *n)
{
    if (r->p >= r->end) return false;
    const char *a = r->p;
    while (r->p < r->end && *r->p != '\n' && *r->p != '\r') r->p++;
    *s = a;
    *n = (size_t)(r->p - a);
    if (r->p < r->end && *r->p == '\r') r->p++;
    if (r->p < r->end && *r->p == '\n' && (r->p == a || r->p[-1] != '\n')) r->p++;
    r->line++;
    return true;
}

static bool is_sep(char c) { return c == ' ' || c == '\t' || c == ',' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

/* The next number of the numeric block (separated by white space or commas). */
static prt_status number(reader *r, double *out, const char *what)
{
    while (r->p < r->end && is_sep(*r->p)) {
        if (*r->p == '\n' || (*r->p == '\r' && (r->p + 1 >= r->end || r->p[1] != '\n'))) r->line++;
        r->p++;
    }
    if (r->p >= r->end) return bad(r->line, "file ends before %s", what);
    char buf[64];
    size_t n = 0;
    while (r->p + n < r->end && !is_sep(r->p[n]) && n < sizeof buf - 1) {
        buf[n] = r->p[n];
        n++;
    }
    if (r->p + n < r->end && !is_sep(r->p[n])) return bad(r->line, "%s: number too long", what);
    buf[n] = 0;
    char *e;
    errno = 0;
    double v = strtod(buf, &e);
    if (e != buf + n || n == 0) return bad(r->line, "%s is not a number", what);
    if (!isfinite(v)) return bad(r->line, "%s is not finite", what);
    r->p += n;
    *out = v;
    return PRT_OK;
}

static prt_status integer(reader *r, int lo, int hi, int *out, const char *what)
{
    double v;
    prt_status st = number(r, &v, what);
    if (st) return st;
    if (v != floor(v) || v < lo || v > hi) {
        char msg[160];
        snprintf(msg, sizeof msg, "%s must be a whole number in %d..%d (got %.6g)", what, lo, hi, v);
        return prt__fail(NULL, PRT_ERR_FORMAT, "IES: line %d: %s", r->line, msg);
    }
    *out = (int)v;
    return PRT_OK;
}

/* n angles, strictly increasing, each in [lo, hi]. */
static prt_status angles(reader *r, int n, float *a, double lo, double hi, const char *what)
{
    for (int i = 0; i < n; ++i) {
        double v;
        prt_status st = number(r, &v, what);
        if (st) return st;
        if (v < lo || v > hi) return bad(r->line, "%s out of range", what);
        if (i && !(v > a[i - 1])) return bad(r->line, "%s must increase strictly", what);
        a[i] = (float)v;
    }
    return PRT_OK;
}

void prt_ies_release(prt_ies *p)
{
    if (!p || __atomic_sub_fetch(&p->refs, 1, __ATOMIC_ACQ_REL) > 0) return;
    free(p->v);
    free(p->h);
    free(p->cd);
    free(p);
}

prt_ies *prt_ies_retain(prt_ies *p)
{
    if (p) __atomic_add_fetch(&p->refs, 1, __ATOMIC_RELAXED);
    return p;
}

static prt_status parse(const char *data, size_t size, prt_ies *p)
{
    reader r = {data, data + size, 0};
    const char *s;
    size_t n;
    /* The header: an optional IESNA line, keyword lines, then TILT=. */
    bool tilt = false;
    while (next_line(&r, &s, &n)) {
        if (n >= 5 && !strncmp(s, "TILT=", 5)) { tilt = true; break; }
        if (r.line > 10000) return bad(r.line, "%s", "no TILT= line in the first 10000 lines");
    }
    if (!tilt) return bad(r.line, "%s", "no TILT= line (not an IES LM-63 file?)");
    const char *t = s + 5;
    size_t tn = n - 5;
    while (tn && (t[tn - 1] == ' ' || t[tn - 1] == '\t')) tn--;
    prt_status st;
    r.line++;   /* from here r.line is the line r.p is on */
    if (tn == 7 && !strncmp(t, "INCLUDE", 7)) {
        /* Tilt data describe how output changes as the lamp tilts: read and checked, not applied
         * (prt's luminaires hang at their photometered attitude). */
        int geometry = 0, count = 0;
        if ((st = integer(&r, 1, 3, &geometry, "the lamp-to-luminaire geometry"))) return st;
        if ((st = integer(&r, 0, MAX_ANGLES, &count, "the number of tilt angles"))) return st;
        if ((size_t)count * 4 > (size_t)(r.end - r.p)) return bad(r.line, "%s", "tilt table longer than the file");
        for (int i = 0; i < 2 * count; ++i) {
            double v;
            if ((st = number(&r, &v, i < count ? "a tilt angle" : "a tilt factor"))) return st;
            if (i >= count && v < 0) return bad(r.line, "%s", "a tilt factor is negative");
        }
    } else if (!(tn == 4 && !strncmp(t, "NONE", 4))) {
        return bad(r.line - 1, "%s", "TILT must be NONE or INCLUDE (tilt data in another file are not read)");
    }
    int lamps = 0, nv = 0, nh = 0, type = 0, units = 0;
    double lumens = 0, mult = 0, dims[3] = {0, 0, 0}, ballast = 0, blp = 0, watts = 0;
    if ((st = integer(&r, 1, 1000000, &lamps, "the number of lamps"))) return st;
    if ((st = number(&r, &lumens, "the lumens per lamp"))) return st;
    if ((st = number(&r, &mult, "the candela multiplier"))) return st;
    if (!(mult > 0)) return bad(r.line, "%s", "the candela multiplier must be > 0");
    if ((st = integer(&r, 1, MAX_ANGLES, &nv, "the number of vertical angles"))) return st;
    if ((st = integer(&r, 1, MAX_ANGLES, &nh, "the number of horizontal angles"))) return st;
    if ((st = integer(&r, 1, 3, &type, "the photometric type"))) return st;
    if (type != 1) return bad(r.line, "photometric type %s is not read (only type C, 1)", type == 2 ? "B" : "A");
    if ((st = integer(&r, 1, 2, &units, "the units type (1 feet, 2 metres)"))) return st;
    for (int k = 0; k < 3; ++k)
        if ((st = number(&r, &dims[k], "the luminous opening's dimensions"))) return st;
    if ((st = number(&r, &ballast, "the ballast factor"))) return st;
    if ((st = number(&r, &blp, "the ballast-lamp photometric factor"))) return st;
    if ((st = number(&r, &watts, "the input watts"))) return st;
    if (!(ballast > 0) || !(blp > 0)) return bad(r.line, "%s", "ballast factors must be > 0");
    const size_t values = (size_t)nv * (size_t)nh;
    /* Every number takes at least two bytes (a digit and a separator): a table the rest of the
     * file cannot hold is refused before anything is allocated. */
    if (values > MAX_VALUES) return bad(r.line, "%s", "candela table too large (over 4M values)");
    if ((values + (size_t)nv + (size_t)nh) * 2 > (size_t)(r.end - r.p) + 1)
        return bad(r.line, "%s", "candela table longer than the file (truncated?)");
    p->nv = nv;
    p->nh = nh;
    p->v = malloc((size_t)nv * sizeof *p->v);
    p->h = malloc((size_t)nh * sizeof *p->h);
    p->cd = malloc(values * sizeof *p->cd);
    if (!p->v || !p->h || !p->cd) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "IES: out of memory for the candela table");
    if ((st = angles(&r, nv, p->v, 0, 180, "a vertical angle"))) return st;
    if (p->v[0] != 0 && p->v[0] != 90) return bad(r.line, "%s", "vertical angles must start at 0 or 90 degrees (type C)");
    if (nv > 1 && p->v[nv - 1] != 90 && p->v[nv - 1] != 180) return bad(r.line, "%s", "vertical angles must end at 90 or 180 degrees (type C)");
    if ((st = angles(&r, nh, p->h, 0, 360, "a horizontal angle"))) return st;
    if (p->h[0] != 0) return bad(r.line, "%s", "horizontal angles must start at 0 degrees (type C)");
    const float last = p->h[nh - 1];
    if (nh > 1 && last != 90 && last != 180 && !(last > 180)) return bad(r.line, "%s", "horizontal angles must end at 0, 90, 180 or 360 degrees");
    const double scale = mult * ballast * blp;
    p->max_cd = 0;
    for (size_t i = 0; i < values; ++i) {
        double v;
        if ((st = number(&r, &v, "a candela value"))) return st;
        if (v < 0) return bad(r.line, "%s", "a candela value is negative");
        v *= scale;
        if (!(v <= PRT__MAX_RADIANCE)) return bad(r.line, "%s", "a candela value times the multipliers is above 1e30");
        p->cd[i] = (float)v;
        if (p->cd[i] > p->max_cd) p->max_cd = p->cd[i];
    }
    (void)lamps; (void)lumens; (void)dims; (void)watts;   /* photometry is absolute once multiplied */
    return PRT_OK;
}

prt_status prt_ies_load_memory(const void *data, size_t size, prt_ies **out)
{
    if (!out || (!data && size)) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_ies_load_memory: data and out are required");
    *out = NULL;
    prt_ies *p = prt__calloc(1, sizeof *p);
    if (!p) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "IES: out of memory");
    p->refs = 1;
    prt_status st = parse(data ? data : "", size, p);
    if (st) { prt_ies_release(p); return st; }
    *out = p;
    return PRT_OK;
}

prt_status prt__ies_from_table(int nv, int nh, float *v, float *h, float *cd, prt_ies **out)
{
    *out = NULL;
    prt_ies *p = prt__calloc(1, sizeof *p);
    if (!p) { free(v); free(h); free(cd); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    p->refs = 1;
    p->nv = nv;
    p->nh = nh;
    p->v = v;
    p->h = h;
    p->cd = cd;
    for (size_t i = 0; i < (size_t)nv * nh; ++i) p->max_cd = cd[i] > p->max_cd ? cd[i] : p->max_cd;
    *out = p;
    return PRT_OK;
}

typedef struct load_ctx { prt_ies *p; } load_ctx;
static prt_status load_bytes(void *user, const void *data, size_t size)
{
    return prt_ies_load_memory(data, size, &((load_ctx *)user)->p);
}

prt_status prt_ies_load(const char *path, prt_ies **out)
{
    if (!path || !out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_ies_load: path and out are required");
    *out = NULL;
    if (strlen(path) >= sizeof ((prt_ies *)0)->path) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "IES path longer than 1023 bytes");
    load_ctx c = {NULL};
    prt_status st = prt__load_path(NULL, path, load_bytes, &c);
    if (st) return st;
    snprintf(c.p->path, sizeof c.p->path, "%s", path);
    *out = c.p;
    return PRT_OK;
}

const char *prt_ies_path(const prt_ies *p) { return p ? p->path : ""; }
float prt_ies_max_candela(const prt_ies *p) { return p ? p->max_cd : 0.0f; }

/* Index i and fraction f with a[i] <= x <= a[i + 1] (a increasing, n >= 2, x inside). */
static void bracket(const float *a, int n, double x, int *i, double *f)
{
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (a[mid] <= x) lo = mid; else hi = mid;
    }
    *i = lo;
    *f = a[hi] > a[lo] ? fmin(1.0, fmax(0.0, (x - a[lo]) / (a[hi] - a[lo]))) : 0.0;
}

/* Candela along one horizontal plane index at vertical angle index/fraction. */
static double along(const prt_ies *p, int h, int vi, double vf)
{
    const float *row = p->cd + (size_t)h * p->nv;
    return p->nv == 1 ? row[0] : row[vi] * (1.0 - vf) + row[vi + 1] * vf;
}

float prt_ies_candela(const prt_ies *p, float vertical_deg, float horizontal_deg)
{
    if (!p || !isfinite(vertical_deg) || !isfinite(horizontal_deg)) return 0.0f;
    double g = vertical_deg;
    if (g < p->v[0] - 1e-4 || g > p->v[p->nv - 1] + 1e-4) return 0.0f;
    if (p->nv == 1 && fabs(g - p->v[0]) > 1e-4) return 0.0f;
    int vi = 0;
    double vf = 0;
    if (p->nv > 1) bracket(p->v, p->nv, fmin(fmax(g, p->v[0]), p->v[p->nv - 1]), &vi, &vf);
    if (p->nh == 1) return (float)along(p, 0, vi, vf);
    double c = fmod(horizontal_deg, 360.0);
    if (c < 0) c += 360.0;
    const double last = p->h[p->nh - 1];
    if (last == 90) {          /* a quadrant, mirrored about the C0-C180 and C90-C270 planes */
        if (c > 180) c = 360 - c;
        if (c > 90) c = 180 - c;
    } else if (last == 180) {  /* a half, mirrored about the C0-C180 plane */
        if (c > 180) c = 360 - c;
    }
    if (c > last) {            /* between the last plane and C360 = C0 */
        double f = (c - last) / (360.0 - last);
        return (float)(along(p, p->nh - 1, vi, vf) * (1.0 - f) + along(p, 0, vi, vf) * f);
    }
    int hi;
    double hf;
    bracket(p->h, p->nh, c, &hi, &hf);
    return (float)(along(p, hi, vi, vf) * (1.0 - hf) + along(p, hi + 1, vi, vf) * hf);
}

/* ---- the light's frame ---- */

void prt__ies_frame(const prt_light *l, double n[3], double u[3], double v[3])
{
    for (int k = 0; k < 3; ++k) n[k] = l->direction[k];
    double a[3] = {l->up[0], l->up[1], l->up[2]};
    double an = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
    for (int k = 0; k < 3; ++k) a[k] -= an * n[k];
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(len > 1e-6)) {       /* no C0 direction given (or along the nadir): one fixed by the nadir */
        double b[3] = {0, 0, 0};
        b[fabs(n[0]) < 0.9 ? 0 : 2] = 1;
        double bn = b[0] * n[0] + b[1] * n[1] + b[2] * n[2];
        for (int k = 0; k < 3; ++k) a[k] = b[k] - bn * n[k];
        len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    }
    for (int k = 0; k < 3; ++k) u[k] = a[k] / len;
    v[0] = n[1] * u[2] - n[2] * u[1];
    v[1] = n[2] * u[0] - n[0] * u[2];
    v[2] = n[0] * u[1] - n[1] * u[0];
}

double prt__ies_factor(const prt_light *l, const float wi[3])
{
    if (!l->profile) return 0.0;
    double n[3], u[3], v[3];
    prt__ies_frame(l, n, u, v);
    /* The light sees the point along -wi. */
    double w[3] = {-(double)wi[0], -(double)wi[1], -(double)wi[2]};
    double cn = w[0] * n[0] + w[1] * n[1] + w[2] * n[2];
    double cu = w[0] * u[0] + w[1] * u[1] + w[2] * u[2];
    double cv = w[0] * v[0] + w[1] * v[1] + w[2] * v[2];
    double gamma = acos(fmin(1.0, fmax(-1.0, cn))) * 180.0 / PRT_PI;
    double c = (cu == 0 && cv == 0) ? 0.0 : atan2(cv, cu) * 180.0 / PRT_PI;
    return prt_ies_candela(l->profile, (float)gamma, (float)c);
}
