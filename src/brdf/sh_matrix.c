/* BRDFs as SH matrices applied in a vertex's own frame: what glossy transfer (the SH method's
 * glossy sets, the spectral method's glossy final bounce) uses to turn incident radiance in the
 * world frame into exit radiance. */
#include "brdf/sh_matrix.h"

#include <string.h>

prt_status prt__frame_rot_create(int order, const float normal[3], prt__frame_rot *out)
{
    memset(out, 0, sizeof *out);
    double n[3] = {normal[0], normal[1], normal[2]}, t[3], b[3];
    /* Any tangent serves: the BRDFs here are isotropic, so B commutes with turns about n. */
    double a[3] = {0, 0, 0};
    a[fabs(n[0]) < 0.6 ? 0 : (fabs(n[1]) < 0.6 ? 1 : 2)] = 1;
    t[0] = a[1] * n[2] - a[2] * n[1]; t[1] = a[2] * n[0] - a[0] * n[2]; t[2] = a[0] * n[1] - a[1] * n[0];
    double tl = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int k = 0; k < 3; ++k) t[k] /= tl;
    b[0] = n[1] * t[2] - n[2] * t[1]; b[1] = n[2] * t[0] - n[0] * t[2]; b[2] = n[0] * t[1] - n[1] * t[0];
    double R[9] = {t[0], t[1], t[2], b[0], b[1], b[2], n[0], n[1], n[2]}, RT[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) RT[i * 3 + j] = R[j * 3 + i];
    prt_status st = prt_sh_rotation_create(order, R, &out->to_local);
    if (!st) st = prt_sh_rotation_create(order, RT, &out->to_world);
    if (st) prt__frame_rot_release(out);
    return st;
}

void prt__frame_rot_release(prt__frame_rot *r)
{
    prt_sh_rotation_release(r->to_local);
    prt_sh_rotation_release(r->to_world);
    memset(r, 0, sizeof *r);
}

void prt__apply_brdf(const prt__frame_rot *r, const float *B, int c, int order, const float *in, float *out, int rows)
{
    const int n = order * order;
    const float *Bc = B + (size_t)c * n * n;
    float local[PRT_SH_MAX_COEFFS], exit_local[PRT_SH_MAX_COEFFS];
    for (int row = 0; row < rows; ++row) {
        prt_sh_rotation_apply(r->to_local, 1, in + (size_t)row * n, local);
        for (int i = 0; i < n; ++i) {
            float s = 0.0f;
            for (int j = 0; j < n; ++j) s += Bc[i * n + j] * local[j];
            exit_local[i] = s;
        }
        prt_sh_rotation_apply(r->to_world, 1, exit_local, out + (size_t)row * n);
    }
}

prt_status prt__brdf_matrices(prt_context *ctx, const prt_brdf *brdfs, int count, int order, float **out)
{
    const size_t n = (size_t)order * order;
    for (int k = 0; k < count; ++k) {
        out[k] = NULL;
        if (!prt_brdf_is_glossy(&brdfs[k])) continue;
        out[k] = malloc(3 * n * n * sizeof(float));
        if (!out[k]) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        prt_status st = prt_brdf_sh_matrix(&brdfs[k], order, out[k]);
        if (st) return prt__fail(ctx, st, "material %d: %s", k + 1, prt_last_error());
    }
    return PRT_OK;
}

