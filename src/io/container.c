/* The .prt container's framing (docs/FORMAT.md): a header, a chunk table, 8-byte aligned chunks
 * each with a CRC-32. Readers bound every offset and size by the bytes actually present. */
#include "io/container.h"

#include <stdarg.h>
#include <zlib.h>

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the .prt reader and writer assume a little-endian host"
#endif

#define FILE_VERSION 4   /* the newest this prt reads; files are written at the lowest they need */
#define HEADER_SIZE 24
#define ENTRY_SIZE 24
#define MAX_CHUNKS 4096
static const unsigned char MAGIC[8] = {'P', 'R', 'T', 'F', 0x0D, 0x0A, 0x1A, 0x0A};

bool prt__all_finite(const float *p, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(p[i])) return false;
    return true;
}

void prt__chunk_name(uint32_t id, char out[5])
{
    for (int i = 0; i < 4; ++i) {
        char c = (char)(id >> (8 * i) & 255);
        out[i] = c >= 32 && c < 127 ? c : '?';
    }
    out[4] = 0;
}

void prt__chunks_add(prt__chunk_list *l, uint32_t id, ...)
{
    if (l->failed) return;
    if (l->count == l->capacity) {
        int cap = l->capacity ? 2 * l->capacity : 16;
        prt__chunk_out *c = l->count < MAX_CHUNKS ? realloc(l->chunks, (size_t)cap * sizeof *c) : NULL;
        if (!c) { l->failed = true; return; }
        l->chunks = c;
        l->capacity = cap;
    }
    prt__chunk_out *c = &l->chunks[l->count++];
    memset(c, 0, sizeof *c);
    c->id = id;
    va_list ap;
    va_start(ap, id);
    for (int i = 0; i < PRT__CHUNK_PARTS; ++i) {
        const void *p = va_arg(ap, const void *);
        if (!p) break;
        c->parts[i] = p;
        c->sizes[i] = va_arg(ap, size_t);
    }
    va_end(ap);
}

void *prt__chunks_alloc(prt__chunk_list *l, size_t bytes)
{
    if (l->failed) return NULL;
    if (l->owned_count == l->owned_capacity) {
        int cap = l->owned_capacity ? 2 * l->owned_capacity : 16;
        void **o = realloc(l->owned, (size_t)cap * sizeof *o);
        if (!o) { l->failed = true; return NULL; }
        l->owned = o;
        l->owned_capacity = cap;
    }
    void *p = calloc(bytes ? bytes : 1, 1);
    if (!p) { l->failed = true; return NULL; }
    l->owned[l->owned_count++] = p;
    return p;
}

void prt__chunks_free(prt__chunk_list *l)
{
    for (int i = 0; i < l->owned_count; ++i) free(l->owned[i]);
    free(l->owned);
    free(l->chunks);
    memset(l, 0, sizeof *l);
}

static size_t chunk_size(const prt__chunk_out *c)
{
    size_t n = 0;
    for (int i = 0; i < PRT__CHUNK_PARTS && c->parts[i]; ++i) n += c->sizes[i];
    return n;
}

static uint32_t chunk_crc(const prt__chunk_out *c)
{
    /* One running CRC over the concatenated parts, without copying them together. */
    uLong crc = crc32(0L, Z_NULL, 0);
    for (int i = 0; i < PRT__CHUNK_PARTS && c->parts[i]; ++i) {
        const unsigned char *p = c->parts[i];
        size_t n = c->sizes[i];
        while (n) {
            unsigned int k = n > 0x40000000u ? 0x40000000u : (unsigned int)n;
            crc = crc32(crc, p, k);
            p += k;
            n -= k;
        }
    }
    return (uint32_t)crc;
}

prt_status prt__container_write(const char *path, const prt__chunk_list *l)
{
    if (l->version > FILE_VERSION) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "format version %u is newer than this prt writes", l->version);
    if (l->failed) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory preparing '%s'", path);
    if (l->count < 1 || l->count > MAX_CHUNKS) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "a .prt file holds 1..%d chunks", MAX_CHUNKS);
    const size_t table_end = HEADER_SIZE + (size_t)ENTRY_SIZE * l->count;
    unsigned char *head = calloc(table_end, 1);
    if (!head) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(head, MAGIC, 8);
    prt__put32(head + 8, l->version > 1 ? l->version : 1);
    prt__put32(head + 12, (uint32_t)l->count);
    size_t offset = (table_end + 7) & ~(size_t)7;
    for (int i = 0; i < l->count; ++i) {
        const prt__chunk_out *c = &l->chunks[i];
        const size_t size = chunk_size(c);
        unsigned char *e = head + HEADER_SIZE + ENTRY_SIZE * i;
        prt__put32(e, c->id);
        prt__put32(e + 4, chunk_crc(c));
        prt__put64(e + 8, offset);
        prt__put64(e + 16, size);
        offset = (offset + size + 7) & ~(size_t)7;
    }
    prt__put32(head + 20, prt__crc32(head, table_end));   /* over the header (crc field zero) and the table */

    prt__atomic_file f;
    prt_status st = prt__atomic_open(&f, path);
    if (st) { free(head); return st; }
    static const unsigned char zeros[8] = {0};
    st = prt__atomic_write(&f, head, table_end);
    free(head);
    size_t pos = table_end;
    for (int i = 0; i < l->count && !st; ++i) {
        const prt__chunk_out *c = &l->chunks[i];
        size_t pad = ((pos + 7) & ~(size_t)7) - pos;
        st = prt__atomic_write(&f, zeros, pad);
        pos += pad;
        for (int p = 0; p < PRT__CHUNK_PARTS && c->parts[p] && !st; ++p) st = prt__atomic_write(&f, c->parts[p], c->sizes[p]);
        pos += chunk_size(c);
    }
    if (st) { prt__atomic_abort(&f); return st; }
    return prt__atomic_commit(&f);
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "%s", msg); }

prt_status prt__container_read(prt_context *ctx, const void *data, size_t size, prt__chunk_in **chunks, int *count)
{
    *chunks = NULL;
    *count = 0;
    const unsigned char *b = data;
    if (b && size > 0 && size < HEADER_SIZE && !memcmp(b, MAGIC, size < 8 ? size : 8)) return bad(ctx, "truncated .prt file (header cut off)");
    if (!b || size < HEADER_SIZE || memcmp(b, MAGIC, 8) != 0) return bad(ctx, "not a .prt file (bad magic number)");
    uint32_t version = prt__get32(b + 8), n = prt__get32(b + 12);
    /* The checksum covers the version: a damaged version byte is damage, not a newer file. */
    const bool table_ok = n > 0 && n <= MAX_CHUNKS;
    const size_t table_end = HEADER_SIZE + (size_t)ENTRY_SIZE * (table_ok ? n : 0);
    if (table_ok && table_end <= size) {
        unsigned char *head = malloc(table_end);
        if (!head) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(head, b, table_end);
        uint32_t stored = prt__get32(head + 20);
        prt__put32(head + 20, 0);
        uint32_t actual = prt__crc32(head, table_end);
        free(head);
        if (stored != actual) return bad(ctx, "corrupt .prt file: header checksum mismatch");
    }
    if (version > FILE_VERSION)
        return prt__fail(ctx, PRT_ERR_FORMAT, "file format version %u is newer than this prt supports (%d): upgrade prt", version, FILE_VERSION);
    if (version < 1) return prt__fail(ctx, PRT_ERR_FORMAT, "file format version %u is not a valid .prt version", version);
    if (!table_ok) return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %u chunks", n);
    if (table_end > size) return bad(ctx, "truncated .prt file (chunk table cut off)");
    prt__chunk_in *c = prt__calloc(n, sizeof *c);
    if (!c) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (uint32_t i = 0; i < n; ++i) {
        const unsigned char *e = b + HEADER_SIZE + (size_t)ENTRY_SIZE * i;
        uint64_t off = prt__get64(e + 8), len = prt__get64(e + 16);
        if (off > size || len > size - off) { free(c); return bad(ctx, "truncated .prt file: a chunk extends past the end"); }
        c[i].id = prt__get32(e);
        c[i].data = b + off;
        c[i].size = len;
        if (prt__crc32(c[i].data, (size_t)len) != prt__get32(e + 4)) {
            char what[5];
            prt__chunk_name(c[i].id, what);
            free(c);
            return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: checksum mismatch in chunk %s", what);
        }
    }
    *chunks = c;
    *count = (int)n;
    return PRT_OK;
}

prt__chunk_in *prt__chunk_take(prt__chunk_in *chunks, int count, uint32_t id)
{
    for (int i = 0; i < count; ++i)
        if (chunks[i].id == id && !chunks[i].used) {
            chunks[i].used = true;
            return &chunks[i];
        }
    return NULL;
}
