/* Light arriving at points around a baked scene (prt/method.h: prt_transfer_light_at), for the
 * methods whose table entry holds it. */
#include "transfer/method.h"

#include <math.h>

int prt_transfer_light_at_box(const prt_transfer *t, float lo[3], float hi[3])
{
    float a[3], b[3];
    if (!t || !t->method->light_at_box || !t->method->light_at_box(t, a, b)) return 0;
    for (int c = 0; c < 3; ++c) {
        if (lo) lo[c] = a[c];
        if (hi) hi[c] = b[c];
    }
    return 1;
}

prt_status prt_transfer_light_at(prt_context *ctx, const prt_transfer *t, const prt_lighting *l, const float p[3], prt_sh_light *out)
{
    if (!t || !l || !p || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_light_at: transfer, lighting, point and out are required");
    if (!(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_light_at: the point is not finite");
    if (!prt_transfer_light_at_box(t, NULL, NULL))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' holds no light for points around its scene (%s)", t->source,
                         t->method->light_at ? "bake it with --neighbourhood N" : "its method bakes none");
    return t->method->light_at(ctx, t, l, p, out);
}
