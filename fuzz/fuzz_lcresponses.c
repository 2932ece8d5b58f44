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
    if (size < 48) return 0;
    const uint64_t nv = get64(data + 24), glossy = get64(data + 32);
    if (nv > 4096 || glossy > nv) return 0;   /* a bake's own counts: what the file must match */
    char path[] = "/tmp/prt_fuzz_lcr_XXXXXX";
    const int fd = mkstemp(path);
    if (fd < 0) return 0;
    const bool written = write(fd, data, size) == (ssize_t)size;
    close(fd);
    if (written) {
        const prt__fingerprint fp = {get64(data + 8), get64(data + 16)};
        /* Up to four cloud lights at the first records' positions (where the bytes reach). */
        const size_t record = (4 + nv * 3 + glossy * 48) * sizeof(float);
        float cloud[12] = {0};
        uint32_t n = 0;
        for (size_t i = 0; i < 4 && 48 + i * record + 12 <= size; ++i) memcpy(cloud + 3 * n++, data + 48 + i * record, 12);
        prt__lightcloud_responses *r = NULL;
        if (prt__lightcloud_responses_open(NULL, path, &fp, nv, glossy, cloud, n, &r) == PRT_OK) {
            float *diffuse = malloc((nv * 3 + 1) * sizeof(float)), *sh = malloc((glossy * 48 + 1) * sizeof(float));
            for (uint32_t j = 0; j < n && diffuse && sh; ++j) {
                bool lit;
                if (prt__lightcloud_responses_has(r, j)) prt__lightcloud_responses_read(NULL, r, j, diffuse, sh, &lit);
            }
            free(diffuse);
            free(sh);
            prt__lightcloud_responses_close(r);
        }
    }
    unlink(path);
    return 0;
}
