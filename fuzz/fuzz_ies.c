/* libFuzzer harness: IES (LM-63) photometric profiles from memory, then the profile evaluated
 * over directions that cross every symmetry fold and run outside the ranges it covers. */
#include <prt/prt.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    prt_ies *p = NULL;
    if (prt_ies_load_memory(data, size, &p) != PRT_OK) return 0;
    float sum = 0;
    for (int v = -1; v <= 19; ++v)
        for (int h = -2; h <= 26; ++h) {
            const float c = prt_ies_candela(p, v * 10.0f, h * 15.0f);
            if (!(c >= 0) || !isfinite(c)) abort();   /* every value is a finite candela */
            sum += c;
        }
    (void)prt_ies_candela(p, NAN, 0);
    (void)prt_ies_candela(p, 45, INFINITY);
    (void)sum;
    (void)prt_ies_max_candela(p);
    prt_ies_release(p);
    return 0;
}
