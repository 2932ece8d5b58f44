/* libFuzzer harness: the light cloud's kept solutions (`--responses FILE`,
 * src/methods/lightcloud/responses.c), read as a bake reads them: opened for the fingerprint and
 * counts its own header names (so that the fuzzer gets past them), its first records' positions
 * looked up as cloud lights, and every light it holds read back. The reader takes a path, so the
 * bytes go through a temporary file. */
#include "methods/lightcloud/responses.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint64_t get64(const uint8_t *p)
{
    uint64_t x = 0;
    for (int i = 7; i >= 0; --i) x = x << 8 | p[i];
    return x;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 56) return 0;
    const uint64_t nv = get64(data + 24), glossy = get64(data + 32), lobes = get64(data + 48);
    if (nv > 4096 || glossy > nv) return 0;   /* a bake's own counts: what the file must match */
    const int K = lobes == 4 || lobes == 9 ? (int)lobes : 1;   /* other counts: refused as a bake's would be */
    char path[] = "/tmp/prt_fuzz_lcr_XXXXXX";
    const int fd = mkstemp(path);
    if (fd < 0) return 0;
    const bool written = write(fd, data, size) == (ssize_t)size;
    close(fd);
    if (written) {
        const prt__fingerprint fp = {get64(data + 8), get64(data + 16)};
        /* Up to four cloud lights at the first records' positions (where the bytes reach). */
        const size_t record = (4 + (nv * 3 + glossy * 48) * (size_t)K) * sizeof(float);
        float cloud[12] = {0};
        uint32_t n = 0;
        for (size_t i = 0; i < 4 && 56 + i * record + 12 <= size; ++i) memcpy(cloud + 3 * n++, data + 56 + i * record, 12);
        prt__lightcloud_responses *r = NULL;
        if (prt__lightcloud_responses_open(NULL, path, &fp, nv, glossy, K, cloud, n, &r) == PRT_OK) {
            float *diffuse = malloc((nv * 3 + 1) * sizeof(float)), *sh = malloc((glossy * 48 + 1) * sizeof(float));
            for (uint32_t j = 0; j < n && diffuse && sh; ++j) {
                bool lit;
                for (int k = 0; k < K && prt__lightcloud_responses_has(r, j); ++k) prt__lightcloud_responses_read(NULL, r, j, k, diffuse, sh, &lit);
            }
            free(diffuse);
            free(sh);
            prt__lightcloud_responses_close(r);
        }
    }
    unlink(path);
    return 0;
}
