/* Bake checkpoints (see checkpoint.h). Layout, little-endian as the machine writes it:
 *   header  "PRTCKPT1", u32 version, u32 0, u64 fingerprint a, u64 fingerprint b, u32 crc of the 32 bytes before
 *   record  u32 stage, u32 0, u64 unit, u64 payload size, u32 payload crc, u32 crc of the 28 bytes before, payload */
#define _GNU_SOURCE
#include "transfer/checkpoint.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#define VERSION 1u
#define HEADER_BYTES 36
#define RECORD_BYTES 32

void prt__fingerprint_add(prt__fingerprint *f, const void *data, size_t size)
{
    /* Eight bytes at a time (scenes of tens of millions of vertices are hashed in well under a
     * second): two multiply-xorshift streams with different constants. */
    const unsigned char *p = data;
    uint64_t a = f->a ? f->a : 1469598103934665603ULL, b = f->b ? f->b : 0x9e3779b97f4a7c15ULL;
    size_t i = 0;
    for (; i + 8 <= size; i += 8) {
        uint64_t w;
        memcpy(&w, p + i, 8);
        a = (a ^ w) * 0xff51afd7ed558ccdULL;
        a ^= a >> 32;
        b = (b + w) * 0xc4ceb9fe1a85ec53ULL;
        b ^= b >> 29;
    }
    for (; i < size; ++i) {
        a = (a ^ p[i]) * 1099511628211ULL;
        b = (b + p[i] + 1) * 0xc4ceb9fe1a85ec53ULL;
        b ^= b >> 29;
    }
    a ^= size;   /* where one piece ends and the next begins */
    f->a = a;
    f->b = b;
}

typedef struct record {
    int stage;
    uint64_t unit, offset, size;
} record;

struct prt__checkpoint {
    const prt_context *ctx;
    char *path;
    int fd;
    bool broken;            /* a write failed: no more records */
    bool readonly;
    pthread_mutex_t lock;
    record *records;        /* sorted by (stage, unit) */
    size_t count;
    uint64_t appended;      /* records written by this process */
};

static int cmp_record(const void *x, const void *y)
{
    const record *a = x, *b = y;
    if (a->stage != b->stage) return a->stage < b->stage ? -1 : 1;
    return a->unit < b->unit ? -1 : a->unit > b->unit;
}

/* The same order, then by position in the file, so that of duplicates the first one sorts first. */
static int cmp_record_offset(const void *x, const void *y)
{
    int c = cmp_record(x, y);
    if (c) return c;
    const record *a = x, *b = y;
    return a->offset < b->offset ? -1 : a->offset > b->offset;
}

static bool read_at(int fd, void *buf, size_t n, uint64_t offset)
{
    unsigned char *p = buf;
    while (n) {
        ssize_t r = pread(fd, p, n, (off_t)offset);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return false;
        p += r; n -= (size_t)r; offset += (uint64_t)r;
    }
    return true;
}

static bool write_all(int fd, const void *buf, size_t n)
{
    const unsigned char *p = buf;
    while (n) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return false;
        p += w; n -= (size_t)w;
    }
    return true;
}

static void header_bytes(const prt__fingerprint *fp, unsigned char h[HEADER_BYTES])
{
    uint32_t version = VERSION, zero = 0;
    memcpy(h, "PRTCKPT1", 8);
    memcpy(h + 8, &version, 4);
    memcpy(h + 12, &zero, 4);
    memcpy(h + 16, &fp->a, 8);
    memcpy(h + 24, &fp->b, 8);
    uint32_t crc = prt__crc32(h, 32);
    memcpy(h + 32, &crc, 4);
}

/* Indexes the valid records of an open file and cuts off a torn tail. */
static prt_status scan(prt__checkpoint *c, const prt__fingerprint *fp, prt__fingerprint *got, uint64_t file_size)
{
    unsigned char h[HEADER_BYTES], want[HEADER_BYTES];
    if (file_size < HEADER_BYTES || !read_at(c->fd, h, HEADER_BYTES, 0) || memcmp(h, "PRTCKPT1", 8) != 0)
        return prt__fail(c->ctx, PRT_ERR_FORMAT, "'%s' is not a prt checkpoint (delete it, or bake without --resume)", c->path);
    prt__fingerprint own;
    memcpy(&own.a, h + 16, 8);
    memcpy(&own.b, h + 24, 8);
    header_bytes(fp ? fp : &own, want);
    if (got) *got = own;
    if (!fp && memcmp(h, want, HEADER_BYTES) != 0)
        return prt__fail(c->ctx, PRT_ERR_FORMAT, "'%s' is not a prt checkpoint (its header is damaged)", c->path);
    if (memcmp(h, want, HEADER_BYTES) != 0)
        return prt__fail(c->ctx, PRT_ERR_INVALID_ARG, "checkpoint '%s' belongs to another bake (other scene, method, options or prt "
                         "version); delete it, or bake without --resume", c->path);
    uint64_t at = HEADER_BYTES;
    size_t cap = 0;
    prt__bytes payload = {0};
    while (at + RECORD_BYTES <= file_size) {
        unsigned char r[RECORD_BYTES];
        if (!read_at(c->fd, r, RECORD_BYTES, at)) break;
        uint32_t stage, pad, pcrc, hcrc;
        uint64_t unit, size;
        memcpy(&stage, r, 4); memcpy(&pad, r + 4, 4); memcpy(&unit, r + 8, 8); memcpy(&size, r + 16, 8);
        memcpy(&pcrc, r + 24, 4); memcpy(&hcrc, r + 28, 4);
        if (hcrc != prt__crc32(r, 28) || pad != 0 || stage > PRT__CHECKPOINT_SHARD_STAGE || size > file_size - at - RECORD_BYTES) break;
        /* Read the payload to check it; bounded by the file's size, checked above. */
        if (payload.capacity < size) {
            unsigned char *q = realloc(payload.data, (size_t)size);
            if (!q) { prt__bytes_free(&payload); return prt__fail(c->ctx, PRT_ERR_NO_MEMORY, "out of memory reading a checkpoint"); }
            payload.data = q;
            payload.capacity = (size_t)size;
        }
        if (size && !read_at(c->fd, payload.data, (size_t)size, at + RECORD_BYTES)) break;
        if (prt__crc32(payload.data, (size_t)size) != pcrc) break;
        if (c->count == cap) {
            cap = cap ? cap * 2 : 1024;
            record *q = realloc(c->records, cap * sizeof *q);
            if (!q) { prt__bytes_free(&payload); return prt__fail(c->ctx, PRT_ERR_NO_MEMORY, "out of memory reading a checkpoint"); }
            c->records = q;
        }
        c->records[c->count++] = (record){(int)stage, unit, at + RECORD_BYTES, size};
        at += RECORD_BYTES + size;
    }
    prt__bytes_free(&payload);
    if (c->count) qsort(c->records, c->count, sizeof *c->records, cmp_record_offset);   /* records is NULL when there are none */
    /* A unit recorded twice (cannot happen from prt; a hand-made file) keeps its first record. */
    size_t out = 0;
    for (size_t i = 0; i < c->count; ++i)
        if (!out || cmp_record(&c->records[out - 1], &c->records[i]) != 0) c->records[out++] = c->records[i];
    c->count = out;
    if (c->readonly) return PRT_OK;
    if (at < file_size && ftruncate(c->fd, (off_t)at) != 0)
        return prt__fail(c->ctx, PRT_ERR_IO, "cannot cut the torn end off checkpoint '%s': %s", c->path, strerror(errno));
    if (lseek(c->fd, (off_t)at, SEEK_SET) < 0) return prt__fail(c->ctx, PRT_ERR_IO, "cannot seek in checkpoint '%s': %s", c->path, strerror(errno));
    return PRT_OK;
}

prt_status prt__checkpoint_open(const prt_context *ctx, const char *path, const prt__fingerprint *fp, bool resume, prt__checkpoint **out)
{
    *out = NULL;
    prt__checkpoint *c = prt__calloc(1, sizeof *c);
    if (!c || !(c->path = strdup(path))) { free(c); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    c->ctx = ctx;
    c->fd = -1;
    pthread_mutex_init(&c->lock, NULL);
    struct stat sb;
    bool exists = stat(path, &sb) == 0;
    if (exists && !S_ISREG(sb.st_mode)) {
        prt__checkpoint_close(c, false);
        return prt__fail(ctx, PRT_ERR_IO, "checkpoint '%s' is not a regular file", path);
    }
    prt_status st = PRT_OK;
    /* A checkpoint shorter than its header was cut off before its first record: nothing to
     * resume. A short file that is not the start of one is someone else's: refused, not emptied. */
    const bool usable = resume && exists && sb.st_size >= HEADER_BYTES;
    c->fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    unsigned char head[8];
    const size_t have = exists && sb.st_size < 8 ? (size_t)sb.st_size : 8;
    if (c->fd < 0) st = prt__fail(ctx, PRT_ERR_IO, "cannot open checkpoint '%s': %s", path, strerror(errno));
    else if (resume && exists && !usable && (!read_at(c->fd, head, have, 0) || memcmp(head, "PRTCKPT1", have) != 0))
        st = prt__fail(ctx, PRT_ERR_FORMAT, "'%s' is not a prt checkpoint (delete it, or bake without --resume)", path);
    else if (flock(c->fd, LOCK_EX | LOCK_NB) != 0)
        st = prt__fail(ctx, PRT_ERR_IO, "checkpoint '%s' is in use by another bake of the same output", path);
    else if (usable) {
        st = scan(c, fp, NULL, (uint64_t)sb.st_size);
    } else {
        unsigned char h[HEADER_BYTES];
        header_bytes(fp, h);
        if (ftruncate(c->fd, 0) != 0 || !write_all(c->fd, h, sizeof h))
            st = prt__fail(ctx, PRT_ERR_IO, "cannot write checkpoint '%s': %s", path, strerror(errno));
    }
    if (st) {
        prt__checkpoint_close(c, false);
        return st;
    }
    *out = c;
    return PRT_OK;
}

prt_status prt__checkpoint_open_read(const prt_context *ctx, const char *path, const prt__fingerprint *fp, prt__fingerprint *got,
                                     prt__checkpoint **out)
{
    *out = NULL;
    prt__checkpoint *c = prt__calloc(1, sizeof *c);
    if (!c || !(c->path = strdup(path))) { free(c); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    c->ctx = ctx;
    c->readonly = c->broken = true;
    pthread_mutex_init(&c->lock, NULL);
    struct stat sb;
    prt_status st = PRT_OK;
    if ((c->fd = open(path, O_RDONLY | O_CLOEXEC)) < 0) st = prt__fail(ctx, PRT_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    else if (fstat(c->fd, &sb) != 0 || !S_ISREG(sb.st_mode)) st = prt__fail(ctx, PRT_ERR_IO, "'%s' is not a regular file", path);
    else st = scan(c, fp, got, (uint64_t)sb.st_size);
    if (st) {
        prt__checkpoint_close(c, false);
        return st;
    }
    *out = c;
    return PRT_OK;
}

size_t prt__checkpoint_size(const prt__checkpoint *c) { return c ? c->count : 0; }

void prt__checkpoint_key(const prt__checkpoint *c, size_t i, int *stage, uint64_t *unit)
{
    *stage = c->records[i].stage;
    *unit = c->records[i].unit;
}

bool prt__checkpoint_writable(const prt__checkpoint *c) { return c && !c->readonly; }

static const record *lookup(const prt__checkpoint *c, int stage, uint64_t unit)
{
    record key = {stage, unit, 0, 0};
    return c->count ? bsearch(&key, c->records, c->count, sizeof key, cmp_record) : NULL;   /* records is NULL when there are none */
}

uint64_t prt__checkpoint_count(const prt__checkpoint *c, int stage)
{
    uint64_t n = 0;
    for (size_t i = 0; i < c->count; ++i) n += c->records[i].stage == stage;
    return n;
}

bool prt__checkpoint_find(prt__checkpoint *c, int stage, uint64_t unit, prt__bytes *out)
{
    const record *r = lookup(c, stage, unit);
    if (!r) return false;
    out->size = 0;
    out->failed = false;
    if (r->size > out->capacity) {
        unsigned char *q = realloc(out->data, (size_t)r->size);
        if (!q) return false;
        out->data = q;
        out->capacity = (size_t)r->size;
    }
    if (r->size && !read_at(c->fd, out->data, (size_t)r->size, r->offset)) return false;
    out->size = (size_t)r->size;
    return true;
}

void prt__checkpoint_append(prt__checkpoint *c, int stage, uint64_t unit, const void *data, size_t size)
{
    unsigned char r[RECORD_BYTES];
    uint32_t s = (uint32_t)stage, pad = 0, pcrc = prt__crc32(data, size);
    uint64_t u = unit, n = size;
    memcpy(r, &s, 4); memcpy(r + 4, &pad, 4); memcpy(r + 8, &u, 8); memcpy(r + 16, &n, 8); memcpy(r + 24, &pcrc, 4);
    uint32_t hcrc = prt__crc32(r, 28);
    memcpy(r + 28, &hcrc, 4);
    pthread_mutex_lock(&c->lock);
    if (!c->broken && write_all(c->fd, r, sizeof r) && write_all(c->fd, data, size)) {
        c->appended++;
    } else if (!c->broken) {
        c->broken = true;
        prt__log(c->ctx, PRT_LOG_WARN, "cannot write checkpoint '%s' (%s): the bake goes on without one", c->path, strerror(errno));
    }
    pthread_mutex_unlock(&c->lock);
}

uint64_t prt__checkpoint_records(const prt__checkpoint *c) { return c ? c->count + c->appended : 0; }

void prt__checkpoint_close(prt__checkpoint *c, bool remove)
{
    if (!c) return;
    if (c->fd >= 0) close(c->fd);
    if (remove && c->path && !c->readonly) unlink(c->path);
    pthread_mutex_destroy(&c->lock);
    free(c->records);
    free(c->path);
    free(c);
}
