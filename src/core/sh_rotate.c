/* Rotation of real SH coefficient vectors by the Ivanic-Ruedenberg recurrence (J. Phys. Chem.
 * 1996, with the 1998 erratum): band l's matrix is built from band l-1's and the 3x3 rotation,
 * exact for every order, with no re-projection. */
#include "core/internal.h"

#include <pthread.h>
#include <string.h>

struct prt_sh_rotation {
    int order;
    /* Band l block is (2l+1)^2 doubles, row-major, starting at offset[l]. */
    size_t offset[PRT_SH_MAX_ORDER];
    double *m;
};

/* Element (a, b) of band l's block, a and b in -l..l. */
#define BAND(r, l, a, b) ((r)->m[(r)->offset[l] + (size_t)((a) + (l)) * (2 * (l) + 1) + (size_t)((b) + (l))])

static double p_term(const prt_sh_rotation *r, int i, int l, int a, int b)
{
    double ri1 = BAND(r, 1, i, 1), rim1 = BAND(r, 1, i, -1), ri0 = BAND(r, 1, i, 0);
    if (b == l) return ri1 * BAND(r, l - 1, a, l - 1) - rim1 * BAND(r, l - 1, a, -l + 1);
    if (b == -l) return ri1 * BAND(r, l - 1, a, -l + 1) + rim1 * BAND(r, l - 1, a, l - 1);
    return ri0 * BAND(r, l - 1, a, b);
}

/* The recurrence's coefficients u, v, w at (l, m, n): the same for every rotation, so computed
 * once. Their square roots were most of a rotation's cost (perf), and the SH bake builds one
 * rotation per vertex. */
static double uvw[PRT_SH_MAX_ORDER][2 * PRT_SH_MAX_ORDER - 1][2 * PRT_SH_MAX_ORDER - 1][3];
static pthread_once_t uvw_once = PTHREAD_ONCE_INIT;

static void uvw_init(void)
{
    for (int l = 2; l < PRT_SH_MAX_ORDER; ++l)
        for (int m = -l; m <= l; ++m)
            for (int n = -l; n <= l; ++n) {
                int am = abs(m);
                double d = m == 0 ? 1.0 : 0.0;
                double denom = abs(n) < l ? (double)(l + n) * (l - n) : (double)(2 * l) * (2 * l - 1);
                double *c = uvw[l][m + l][n + l];
                c[0] = sqrt((double)(l + m) * (l - m) / denom);
                c[1] = 0.5 * sqrt((1.0 + d) * (l + am - 1.0) * (l + am) / denom) * (1.0 - 2.0 * d);
                c[2] = -0.5 * sqrt((l - am - 1.0) * (l - am) / denom) * (1.0 - d);
            }
}

prt_status prt_sh_rotation_create(int order, const double rot[9], prt_sh_rotation **out)
{
    *out = NULL;
    if (order < 1 || order > PRT_SH_MAX_ORDER)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "SH order %d out of range 1..%d", order, PRT_SH_MAX_ORDER);
    for (int i = 0; i < 9; ++i)
        if (!isfinite(rot[i])) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "rotation matrix is not finite");
    prt_sh_rotation *r = prt__calloc(1, sizeof *r);
    size_t total = 0;
    for (int l = 0; l < order; ++l) { r->offset[l] = total; total += (size_t)(2 * l + 1) * (2 * l + 1); }
    r->m = prt__calloc(total, sizeof(double));
    if (!r || !r->m) { if (r) free(r->m); free(r); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); }
    r->order = order;
    pthread_once(&uvw_once, uvw_init);
    BAND(r, 0, 0, 0) = 1.0;
    if (order > 1) {
        /* Band 1 basis order is (y, z, x) for m = -1, 0, 1. */
        static const int axis[3] = {1, 2, 0};
        for (int a = -1; a <= 1; ++a)
            for (int b = -1; b <= 1; ++b) BAND(r, 1, a, b) = rot[axis[a + 1] * 3 + axis[b + 1]];
    }
    for (int l = 2; l < order; ++l) {
        for (int m = -l; m <= l; ++m) {
            for (int n = -l; n <= l; ++n) {
                const double *c = uvw[l][m + l][n + l], u = c[0], v = c[1], w = c[2];
                double val = 0.0;
                if (u != 0.0) val += u * p_term(r, 0, l, m, n);
                if (v != 0.0) {
                    double vv;
                    if (m == 0) vv = p_term(r, 1, l, 1, n) + p_term(r, -1, l, -1, n);
                    else if (m > 0) vv = p_term(r, 1, l, m - 1, n) * sqrt(m == 1 ? 2.0 : 1.0)
                                       - (m == 1 ? 0.0 : p_term(r, -1, l, -m + 1, n));
                    else vv = (m == -1 ? 0.0 : p_term(r, 1, l, m + 1, n))
                            + p_term(r, -1, l, -m - 1, n) * sqrt(m == -1 ? 2.0 : 1.0);
                    val += v * vv;
                }
                if (w != 0.0) {
                    double ww = m > 0 ? p_term(r, 1, l, m + 1, n) + p_term(r, -1, l, -m - 1, n)
                                      : p_term(r, 1, l, m - 1, n) - p_term(r, -1, l, -m + 1, n);
                    val += w * ww;
                }
                BAND(r, l, m, n) = val;
            }
        }
    }
    *out = r;
    return PRT_OK;
}

void prt_sh_rotation_release(prt_sh_rotation *r)
{
    if (!r) return;
    free(r->m);
    free(r);
}

void prt_sh_rotation_apply(const prt_sh_rotation *r, int channels, const float *in, float *out)
{
    const int n = r->order * r->order;
    for (int c = 0; c < channels; ++c) {
        const float *src = in + (size_t)c * n;
        float *dst = out + (size_t)c * n;
        for (int l = 0; l < r->order; ++l) {
            int base = l * l;
            for (int a = -l; a <= l; ++a) {
                double s = 0.0;
                for (int b = -l; b <= l; ++b) s += BAND(r, l, a, b) * src[base + b + l];
                dst[base + a + l] = (float)s;
            }
        }
    }
}
