/* Emission lobes of the light cloud: each cloud light is solved not once (isotropic) but once per
 * lobe of a low-order SH basis of its emission direction, so that lights whose intensity varies
 * with direction (spot lights, IES profiles) relight through the cloud (the paper's section 8:
 * "spotlights with emission described by spherical harmonics").
 *
 * The spectral solver takes only lights of non-negative intensity, so the lobes are not the SH
 * themselves but f_0 = 1 and f_k = 1 + P_k / m_k (k >= 1), where P_k are the real SH polynomials
 * up to a scale (x, y, z; xy, yz, 3z^2 - 1, xz, x^2 - y^2 in world axes) and m_k the largest |P_k|
 * on the sphere: every f_k >= 0 and they span the same space. A light of intensity I(w) projects
 * onto P_k (a_k = integral I P_k / integral P_k^2) and then onto the f_k:
 *   I ~ sum a_k P_k = (a_0 - sum_k>0 a_k m_k) f_0 + sum_k>0 a_k m_k f_k.
 * Its response is that combination of the cloud light's responses to the lobes. A lobe is handed
 * to the solver as an ies light whose profile tabulates f_k at 1-degree steps (bilinear error
 * below 1e-4 for these quadratics). Order 1 is the isotropic cloud of before. */
#include "methods/lightcloud/lightcloud.h"
#include "light/light_sample.h"

/* P_k at unit w (world axes). */
static double poly(int k, const double w[3])
{
    const double x = w[0], y = w[1], z = w[2];
    switch (k) {
    case 0: return 1;
    case 1: return x;
    case 2: return y;
    case 3: return z;
    case 4: return x * y;
    case 5: return y * z;
    case 6: return 3 * z * z - 1;
    case 7: return x * z;
    default: return x * x - y * y;
    }
}
/* Largest |P_k| on the sphere, and the integral of P_k^2 over it. */
static const double poly_max[9] = {1, 1, 1, 1, 0.5, 0.5, 2, 0.5, 1};
static const double poly_norm[9] = {4 * PRT_PI, 4 * PRT_PI / 3, 4 * PRT_PI / 3, 4 * PRT_PI / 3, 4 * PRT_PI / 15, 4 * PRT_PI / 15,
                                    16 * PRT_PI / 5, 4 * PRT_PI / 15, 16 * PRT_PI / 15};

double prt__lightcloud_lobe(int k, const double w[3]) { return k == 0 ? 1.0 : 1.0 + poly(k, w) / poly_max[k]; }

/* The lobes' frame as ies lights: nadir -y, C0 towards +x (so C90 = (-y) x (+x) = +z). */
static const float LOBE_DIR[3] = {0, -1, 0}, LOBE_UP[3] = {1, 0, 0};

prt_status prt__lightcloud_lobe_light(int k, const float pos[3], prt_light *out)
{
    memset(out, 0, sizeof *out);
    if (k == 0) {   /* isotropic: the plain unit point light of an order-1 cloud */
        *out = (prt_light){.type = PRT_LIGHT_POINT, .position = {pos[0], pos[1], pos[2]}, .intensity = {1, 1, 1}};
        return PRT_OK;
    }
    enum { NV = 181, NH = 361 };
    float *v = malloc(NV * sizeof(float)), *h = malloc(NH * sizeof(float)), *cd = malloc((size_t)NV * NH * sizeof(float));
    prt_status st = v && h && cd ? PRT_OK : prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    prt_light l = {.type = PRT_LIGHT_IES, .position = {pos[0], pos[1], pos[2]}, .scale = {1, 1, 1}};
    memcpy(l.direction, LOBE_DIR, sizeof l.direction);
    memcpy(l.up, LOBE_UP, sizeof l.up);
    if (!st) {
        for (int i = 0; i < NV; ++i) v[i] = (float)i;
        for (int j = 0; j < NH; ++j) h[j] = (float)j;
        double n[3], u[3], b[3];
        prt__ies_frame(&l, n, u, b);
        for (int j = 0; j < NH; ++j)
            for (int i = 0; i < NV; ++i) {
                const double g = i * PRT_PI / 180, c = j * PRT_PI / 180;
                double w[3];
                for (int a = 0; a < 3; ++a) w[a] = cos(g) * n[a] + sin(g) * (cos(c) * u[a] + sin(c) * b[a]);
                cd[(size_t)j * NV + i] = (float)prt__lightcloud_lobe(k, w);
            }
        st = prt__ies_from_table(NV, NH, v, h, cd, &l.profile);
        v = h = NULL;
        cd = NULL;
    }
    free(v);
    free(h);
    free(cd);
    if (!st) *out = l;
    return st;
}

/* Equal-area strata: z uniform in [-1, 1], phi uniform. Fine enough for a 10-degree cone's edge
 * to be integrated to a fraction of a percent. */
#define QZ 256
#define QP 512

void prt__lightcloud_project(const prt_light *l, int lobes, float c[][3])
{
    double a[9][3] = {{0}};
    const double dw = 4 * PRT_PI / ((double)QZ * QP);
    for (int iz = 0; iz < QZ; ++iz) {
        const double z = -1 + (iz + 0.5) * 2.0 / QZ, r = sqrt(fmax(0.0, 1 - z * z));
        for (int ip = 0; ip < QP; ++ip) {
            const double phi = (ip + 0.5) * 2 * PRT_PI / QP;
            const double w[3] = {r * cos(phi), r * sin(phi), z};
            const float wf[3] = {(float)w[0], (float)w[1], (float)w[2]};
            float I[3];
            prt_light_intensity_towards(l, wf, I);
            if (I[0] == 0 && I[1] == 0 && I[2] == 0) continue;
            for (int k = 0; k < lobes; ++k) {
                const double p = poly(k, w) * dw;
                for (int ch = 0; ch < 3; ++ch) a[k][ch] += I[ch] * p;
            }
        }
    }
    for (int ch = 0; ch < 3; ++ch) {
        double rest = 0;
        for (int k = 1; k < lobes; ++k) {
            const double ck = a[k][ch] / poly_norm[k] * poly_max[k];
            c[k][ch] = (float)ck;
            rest += ck;
        }
        c[0][ch] = (float)(a[0][ch] / poly_norm[0] - rest);
    }
}
