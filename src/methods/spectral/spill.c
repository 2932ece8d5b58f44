/* The transfer rows of a bake over its memory limit, streamed through an unlinked scratch file
 * (spectral.h): each block of vertices writes its record where the file ends as it finishes, and
 * the bake's end reads the records back one block at a time. */
#include "methods/spectral/spectral.h"

#include <unistd.h>

prt_status prt__spectral_spill_open(prt_context *ctx, prt__spectral_spill *s)
{
    s->end = 0;
    /* tmpfile(): unlinked at once, so that nothing is left behind however the process ends. */
    if (!(s->file = tmpfile())) return prt__fail(ctx, PRT_ERR_IO, "cannot create a scratch file for the spectral transfer rows (TMPDIR)");
    return PRT_OK;
}

void prt__spectral_spill_close(prt__spectral_spill *s)
{
    if (s->file) fclose(s->file);
    s->file = NULL;
    s->end = 0;
}

static bool write_at(int fd, const void *data, size_t bytes, uint64_t at)
{
    size_t done = 0;
    while (done < bytes) {
        const ssize_t w = pwrite(fd, (const char *)data + done, bytes - done, (off_t)(at + done));
        if (w <= 0) return false;
        done += (size_t)w;
    }
    return true;
}

bool prt__spectral_spill_put(prt__spectral_spill *s, const void *const *parts, const size_t *bytes, int n, uint64_t *at)
{
    size_t total = 0;
    for (int i = 0; i < n; ++i) total += bytes[i];
    /* A record's place in the file is taken as it finishes: any order, any thread. */
    uint64_t p = __atomic_fetch_add(&s->end, (uint64_t)total, __ATOMIC_RELAXED);
    *at = p;
    for (int i = 0; i < n; ++i) {
        if (!write_at(fileno(s->file), parts[i], bytes[i], p)) return false;
        p += bytes[i];
    }
    return true;
}

bool prt__spectral_spill_get(const prt__spectral_spill *s, uint64_t at, void *data, size_t bytes)
{
    size_t done = 0;
    while (done < bytes) {
        const ssize_t r = pread(fileno(s->file), (char *)data + done, bytes - done, (off_t)(at + done));
        if (r <= 0) return false;
        done += (size_t)r;
    }
    return true;
}
