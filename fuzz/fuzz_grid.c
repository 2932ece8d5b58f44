/* libFuzzer harness: raw density grid files (docs/FORMAT.md) from memory; a grid that parses is
 * placed in a scene as a volume and its extinction read along a ray through it. */
#include <prt/prt.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    int dims[3];
    float *d = NULL;
    if (prt_volume_grid_parse(NULL, data, size, dims, &d) != PRT_OK) {
        if (d) abort();   /* a refusal leaves nothing behind */
        return 0;
    }
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    for (size_t i = 0; i < n; ++i)
        if (!(d[i] >= 0) || !isfinite(d[i])) abort();   /* every value checked */
    const prt_volume_desc v = {.dims = {dims[0], dims[1], dims[2]}, .density = d, .lo = {0, 0, 0}, .hi = {1, 1, 1}, .sigma_t = 1, .albedo = {1, 1, 1}};
    if (prt_volume_check(&v) != PRT_OK) abort();
    free(d);
    return 0;
}
