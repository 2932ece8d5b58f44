/* same_chunks A.prt B.prt: exit 0 when the two files hold the same bytes in every chunk but META
 * (the bake's time, threads and host), 1 when not, 2 when one cannot be read. For the shell tests
 * (cluster_test.sh); the C tests use assert_same_chunks of common.h, which this follows. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static unsigned char *chunks_but_meta(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    const long size = ftell(f);
    rewind(f);
    unsigned char *b = malloc((size_t)size + 1), *out = malloc((size_t)size + 1);
    int ok = b && out && size >= 24 && fread(b, 1, (size_t)size, f) == (size_t)size;
    fclose(f);
    uint32_t count = 0;
    if (ok) memcpy(&count, b + 12, 4);
    *n = 0;
    for (uint32_t i = 0; ok && i < count; ++i) {
        const size_t at = 24 + 24 * (size_t)i;
        uint64_t off, len;
        if (at + 24 > (size_t)size) { ok = 0; break; }
        memcpy(&off, b + at + 8, 8);
        memcpy(&len, b + at + 16, 8);
        if (off > (uint64_t)size || len > (uint64_t)size - off) { ok = 0; break; }
        if (!memcmp(b + at, "META", 4)) continue;
        memcpy(out + *n, b + at, 8);   /* id and CRC */
        memcpy(out + *n + 8, b + off, len);
        *n += 8 + len;
    }
    free(b);
    if (!ok) { free(out); return NULL; }
    return out;
}

int main(int argc, char **argv)
{
    if (argc != 3) { fprintf(stderr, "usage: same_chunks A.prt B.prt\n"); return 2; }
    size_t na, nb;
    unsigned char *a = chunks_but_meta(argv[1], &na), *b = chunks_but_meta(argv[2], &nb);
    const int rc = !a || !b ? 2 : na != nb || memcmp(a, b, na) != 0;
    if (rc == 2) fprintf(stderr, "same_chunks: cannot read %s\n", a ? argv[2] : argv[1]);
    free(a);
    free(b);
    return rc;
}
