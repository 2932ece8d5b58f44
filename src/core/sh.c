/* Real orthonormal spherical harmonics: evaluation by a stable recurrence and zonal
 * convolution.
 *
 * y_lm(d) = K_lm Q_lm(z) Re/Im((x + i y)^|m|) * sqrt(2) for m != 0, with Q_lm the associated
 * Legendre function divided by sin^m(theta). Working with the polynomial Q and the complex
 * power avoids atan2/acos and the division by sin(theta) at the poles. */
#include "core/internal.h"

#include <string.h>

/* K_lm = sqrt((2l+1)/(4 pi) (l-m)!/(l+m)!), times sqrt(2) for m > 0. */
static double norm_table[PRT_SH_MAX_ORDER][PRT_SH_MAX_ORDER];
static int norm_ready;

static void init_norms(void)
{
    for (int l = 0; l < PRT_SH_MAX_ORDER; ++l) {
        for (int m = 0; m <= l; ++m) {
            double ratio = 1.0;  /* (l-m)!/(l+m)! */
            for (int k = l - m + 1; k <= l + m; ++k) ratio /= k;
            double k_lm = sqrt((2.0 * l + 1.0) / (4.0 * PRT_PI) * ratio);
            norm_table[l][m] = m == 0 ? k_lm : sqrt(2.0) * k_lm;
        }
    }
    __atomic_store_n(&norm_ready, 1, __ATOMIC_RELEASE);
}

void prt__sh_norms(float out[PRT_SH_MAX_ORDER * PRT_SH_MAX_ORDER])
{
    if (!__atomic_load_n(&norm_ready, __ATOMIC_ACQUIRE)) init_norms();
    for (int l = 0; l < PRT_SH_MAX_ORDER; ++l)
        for (int m = 0; m < PRT_SH_MAX_ORDER; ++m) out[l * PRT_SH_MAX_ORDER + m] = m <= l ? (float)norm_table[l][m] : 0.0f;
}

void prt_sh_eval(int order, const double dir[3], double *out)
{
    if (!__atomic_load_n(&norm_ready, __ATOMIC_ACQUIRE)) init_norms();  /* idempotent: a race writes equal values */
    if (order < 1) return;
    if (order > PRT_SH_MAX_ORDER) order = PRT_SH_MAX_ORDER;
    const double x = dir[0], y = dir[1], z = dir[2];
    double re = 1.0, im = 0.0;      /* (x + i y)^m */
    double q_mm = 1.0;              /* Q_mm = (2m-1)!! */
    for (int m = 0; m < order; ++m) {
        if (m > 0) {
            double r2 = re * x - im * y;
            im = re * y + im * x;
            re = r2;
            q_mm *= (2.0 * m - 1.0);
        }
        double q_prev = 0.0, q = q_mm;   /* Q_{l-1,m}, Q_{l,m} for l = m */
        for (int l = m; l < order; ++l) {
            if (l == m + 1) {
                q_prev = q;
                q = z * (2.0 * m + 1.0) * q_prev;
            } else if (l > m + 1) {
                double q_next = ((2.0 * l - 1.0) * z * q - (l + m - 1.0) * q_prev) / (double)(l - m);
                q_prev = q;
                q = q_next;
            }
            double k = norm_table[l][m] * q;
            int centre = l * (l + 1);
            if (m == 0) {
                out[centre] = k;
            } else {
                out[centre + m] = k * re;
                out[centre - m] = k * im;
            }
        }
    }
}

void prt_sh_eval_f(int order, const float dir[3], float *out)
{
    double d[3] = {dir[0], dir[1], dir[2]}, tmp[PRT_SH_MAX_COEFFS];
    if (order > PRT_SH_MAX_ORDER) order = PRT_SH_MAX_ORDER;
    prt_sh_eval(order, d, tmp);
    for (int i = 0; i < order * order; ++i) out[i] = (float)tmp[i];
}

void prt_sh_clamped_cosine_zh(int order, double *out)
{
    for (int l = 0; l < order; ++l) {
        double a;   /* irradiance-convention coefficient A_l (Ramamoorthi & Hanrahan 2001) */
        if (l == 0) a = PRT_PI;
        else if (l == 1) a = 2.0 * PRT_PI / 3.0;
        else if (l & 1) a = 0.0;
        else {
            double f = 1.0;   /* l! / (2^l ((l/2)!)^2) */
            for (int k = 1; k <= l; ++k) f *= k;
            for (int k = 1; k <= l / 2; ++k) f /= (double)k * k;
            f /= ldexp(1.0, l);
            double sign = ((l / 2 - 1) & 1) ? -1.0 : 1.0;
            a = 2.0 * PRT_PI * sign / ((l + 2.0) * (l - 1.0)) * f;
        }
        out[l] = a * sqrt((2.0 * l + 1.0) / (4.0 * PRT_PI));
    }
}

void prt_sh_convolve_zh(int order, const double *zh, int channels, float *coeffs)
{
    for (int c = 0; c < channels; ++c)
        for (int l = 0; l < order; ++l) {
            double s = sqrt(4.0 * PRT_PI / (2.0 * l + 1.0)) * zh[l];
            for (int m = -l; m <= l; ++m) coeffs[c * order * order + l * (l + 1) + m] *= (float)s;
        }
}

void prt_rotation_from_euler_deg(double yaw, double pitch, double roll, double rot[9])
{
    /* R = Ry(yaw) * Rx(pitch) * Rz(roll): yaw turns the horizon about +y (up). */
    double a = yaw * PRT_PI / 180.0, b = pitch * PRT_PI / 180.0, c = roll * PRT_PI / 180.0;
    double ry[9] = {cos(a), 0, sin(a), 0, 1, 0, -sin(a), 0, cos(a)};
    double rx[9] = {1, 0, 0, 0, cos(b), -sin(b), 0, sin(b), cos(b)};
    double rz[9] = {cos(c), -sin(c), 0, sin(c), cos(c), 0, 0, 0, 1};
    double t[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            t[i * 3 + j] = rx[i * 3] * rz[j] + rx[i * 3 + 1] * rz[3 + j] + rx[i * 3 + 2] * rz[6 + j];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            rot[i * 3 + j] = ry[i * 3] * t[j] + ry[i * 3 + 1] * t[3 + j] + ry[i * 3 + 2] * t[6 + j];
}
