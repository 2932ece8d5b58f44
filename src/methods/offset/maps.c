/* The transfer maps' storage (offset.h): malloc'd, or - a bake over its memory limit - a shared
 * mapping of an unlinked scratch file, written and read through the same pointer, whose pages
 * the bake hands back to the kernel block by block (prt__offset_maps_drop). Handed back, a page
 * of a shared file mapping keeps its bytes in the page cache (written back to the file under
 * pressure) and comes back on the next touch: every pass over the maps stays as it is, only the
 * resident memory is bounded by the blocks between drops. */
#define _DEFAULT_SOURCE   /* madvise: posix_madvise's POSIX_MADV_DONTNEED does nothing on Linux */
#include "methods/offset/offset.h"

#include <stdio.h>
#include <sys/mman.h>
#include <unistd.h>

static size_t mapped_bytes(size_t values)
{
    const size_t page = (size_t)sysconf(_SC_PAGESIZE);
    return (values * sizeof(float) + page) / page * page;   /* at least a page */
}

prt_status prt__offset_maps_new(prt_context *ctx, size_t values, bool mapped, float **out)
{
    *out = NULL;
    if (!mapped) {
        if (!(*out = malloc(values * sizeof(float) + 1))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the transfer maps");
        return PRT_OK;
    }
    /* tmpfile(): unlinked at once, so that nothing is left behind however the process ends; the
     * mapping keeps the file once its stream is closed. */
    FILE *f = tmpfile();
    if (!f) return prt__fail(ctx, PRT_ERR_IO, "cannot create a scratch file for the transfer maps (TMPDIR)");
    const size_t bytes = mapped_bytes(values);
    void *p = MAP_FAILED;
    if (ftruncate(fileno(f), (off_t)bytes) == 0) p = mmap(NULL, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fileno(f), 0);
    fclose(f);
    if (p == MAP_FAILED) return prt__fail(ctx, PRT_ERR_IO, "cannot map a scratch file of %zu MiB for the transfer maps (TMPDIR full?)", bytes >> 20);
    *out = p;
    return PRT_OK;
}

void prt__offset_maps_free(float *maps, size_t values, bool mapped)
{
    if (!maps) return;
    if (mapped) munmap(maps, mapped_bytes(values));
    else free(maps);
}

void prt__offset_maps_drop(const prt__offset_set *s)
{
    const size_t values = (size_t)s->count * s->covered * 3;
    const float *maps[2] = {s->radiosity, s->subsurface};
    for (int k = 0; k < 2; ++k)
        if (maps[k] && s->mapped[k]) madvise((void *)maps[k], mapped_bytes(values), MADV_DONTNEED);
}
