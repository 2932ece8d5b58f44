/* The SH bounces' ray hits, kept in memory or streamed through a scratch file (bake.h). */
#include "methods/sh/bake.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

prt_status prt__hits_init(prt_context *ctx, prt__hit_store *s, size_t vertex_count, uint32_t samples, bool streaming)
{
    memset(s, 0, sizeof *s);
    s->vertex_count = vertex_count;
    s->samples = samples;
    const size_t n = vertex_count ? vertex_count : 1;
    s->count = prt__calloc(n, sizeof *s->count);
    if (streaming) {
        s->at = prt__calloc(n, sizeof *s->at);
        /* tmpfile(): unlinked at once, so that nothing is left behind however the process ends. */
        if (s->count && s->at && !(s->spill = tmpfile())) {
            prt__hits_free(s);
            return prt__fail(ctx, PRT_ERR_IO, "cannot create a scratch file for the ray hits (TMPDIR)");
        }
    } else {
        s->list = prt__calloc(n, sizeof *s->list);
    }
    if (!s->count || (streaming ? !s->at : !s->list)) {
        prt__hits_free(s);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the ray hits of %zu vertices", vertex_count);
    }
    return PRT_OK;
}

void prt__hits_free(prt__hit_store *s)
{
    if (s->list)
        for (size_t v = 0; v < s->vertex_count; ++v) free(s->list[v]);
    free(s->list);
    free(s->count);
    free(s->at);
    if (s->spill) fclose(s->spill);
    memset(s, 0, sizeof *s);
}

bool prt__hits_put(prt__hit_store *s, size_t v0, size_t v1, const void *hits_in, const uint32_t *count)
{
    const unsigned char *hits = hits_in;   /* a checkpoint's record: not aligned */
    if (s->spill) {
        size_t total = 0;
        for (size_t v = v0; v < v1; ++v) total += count[v - v0];
        const size_t bytes = total * sizeof(prt__hit);
        /* A block's place in the file is taken as it finishes: any order, any thread. */
        const uint64_t base = __atomic_fetch_add(&s->end, (uint64_t)bytes, __ATOMIC_RELAXED);
        size_t done = 0;
        while (done < bytes) {
            const ssize_t w = pwrite(fileno(s->spill), (const char *)hits + done, bytes - done, (off_t)(base + done));
            if (w <= 0) return false;
            done += (size_t)w;
        }
        uint64_t at = base;
        for (size_t v = v0; v < v1; ++v) {
            s->at[v] = at;
            s->count[v] = count[v - v0];
            at += (uint64_t)count[v - v0] * sizeof(prt__hit);
        }
        return true;
    }
    for (size_t v = v0; v < v1; ++v) {
        const uint32_t n = count[v - v0];
        free(s->list[v]);
        s->list[v] = NULL;
        s->count[v] = 0;
        if (n) {
            if (!(s->list[v] = malloc(n * sizeof(prt__hit)))) return false;
            memcpy(s->list[v], hits, n * sizeof(prt__hit));
        }
        s->count[v] = n;
        hits += n * sizeof(prt__hit);
    }
    return true;
}

const prt__hit *prt__hits_get(const prt__hit_store *s, size_t v, prt__hit *buf)
{
    if (!s->spill) return s->list[v];
    const size_t bytes = (size_t)s->count[v] * sizeof *buf;
    size_t done = 0;
    while (done < bytes) {
        const ssize_t r = pread(fileno(s->spill), (char *)buf + done, bytes - done, (off_t)(s->at[v] + done));
        if (r <= 0) return NULL;
        done += (size_t)r;
    }
    return buf;
}
