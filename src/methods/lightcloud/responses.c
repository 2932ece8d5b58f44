/* Kept cloud-light solutions (`--responses FILE`): each cloud light's exit radiance at every
 * vertex, as the bake solved it, so that a later bake of the same scene and settings with more
 * lights (a region refined, lights added by a list) solves only the lights it has not seen. A
 * light's solution depends on nothing but the scene, the settings of the solve and its position,
 * and is the same for any thread count, so a kept one is the one the bake would compute: a bake
 * that reuses them writes the same file as one that solves every light.
 *
 * File (native floats and little-endian counts, written whole to a temporary and renamed):
 *   "PRTLCRS2", fingerprint (2 x u64), vertices (u64), glossy vertices (u64), records (u64),
 *   emission lobes per light (u64: 1, 4 or 9, --emission-order squared), then per record:
 *   position (3 floats), 1.0 when it reaches some vertex (its isotropic lobe does) else 0.0, and
 *   per lobe: exit radiance [vertex][3] (indirect, or all of it as the bake stores), the glossy
 *   vertices' SH [glossy][48].
 * The reader checks the size against the counts before it trusts any of them, and every value it
 * hands out for finiteness. */
#include "methods/lightcloud/lightcloud.h"
#include "methods/lightcloud/responses.h"

#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#define HEADER 56
static const char magic[8] = {'P', 'R', 'T', 'L', 'C', 'R', 'S', '2'};

struct prt__lightcloud_responses {
    int fd;                      /* -1: no file yet */
    uint64_t nv, glossy, records, lobes;
    uint64_t one, floats;        /* floats per lobe, per record after its position and flag */
    float *pos;                  /* [record][4]: position, flag */
    uint32_t *record_of;         /* [cloud light] its record or UINT32_MAX */
    uint32_t reused;
};

void prt__lightcloud_responses_fingerprint(const prt_transfer *t, const prt_options *o, const prt__lightcloud_set *s, prt__fingerprint *fp)
{
    memset(fp, 0, sizeof *fp);
    const char *v = prt_version_string();
    prt__fingerprint_add(fp, v, strlen(v) + 1);
    prt__transfer_fingerprint_scene(t, fp);
    /* The settings a solve depends on (the spectral transfer's and the solve's own), not the
     * cloud, the zones, merging or compression. */
    static const char *const names[] = {"samples", "basis", "full-basis", "partition", "ray-offset", "bounces", "store"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        const char *x = prt__opt(o, names[i]);
        prt__fingerprint_add(fp, names[i], strlen(names[i]) + 1);
        prt__fingerprint_add(fp, x ? x : "", x ? strlen(x) + 1 : 1);
    }
    prt__fingerprint_add(fp, &s->bounces, sizeof s->bounces);
    prt__fingerprint_add(fp, &s->store_direct, sizeof s->store_direct);
    prt__fingerprint_add(fp, &s->lobes, sizeof s->lobes);
}

void prt__lightcloud_responses_close(prt__lightcloud_responses *r)
{
    if (!r) return;
    if (r->fd >= 0) close(r->fd);
    free(r->pos);
    free(r->record_of);
    free(r);
}

static uint64_t get64(const unsigned char *p)
{
    uint64_t x = 0;
    for (int i = 7; i >= 0; --i) x = x << 8 | p[i];
    return x;
}

static void put64(unsigned char *p, uint64_t x)
{
    for (int i = 0; i < 8; ++i) p[i] = (unsigned char)(x >> (8 * i));
}

/* A record's position as bytes, and its index: sorted by both. */
typedef struct keyed { float p[3]; uint32_t record; } keyed;
static int key_cmp(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    const int c = memcmp(x->p, y->p, sizeof x->p);
    return c ? c : (x->record > y->record) - (x->record < y->record);
}

prt_status prt__lightcloud_responses_open(prt_context *ctx, const char *path, const prt__fingerprint *fp, uint64_t nv, uint64_t glossy, int lobes,
                                          const float *cloud, uint32_t n, prt__lightcloud_responses **out)
{
    *out = NULL;
    prt__lightcloud_responses *r = prt__calloc(1, sizeof *r);
    if (!r) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    r->fd = -1;
    r->nv = nv;
    r->glossy = glossy;
    r->lobes = (uint64_t)lobes;
    r->one = nv * 3 + glossy * 48;
    r->floats = r->one * r->lobes;
    r->record_of = malloc(((size_t)n + 1) * sizeof(uint32_t));
    if (!r->record_of) { prt__lightcloud_responses_close(r); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (uint32_t j = 0; j < n; ++j) r->record_of[j] = UINT32_MAX;
    r->fd = open(path, O_RDONLY);
    if (r->fd < 0) {
        *out = r;   /* none kept yet: every light is solved, and kept when the bake writes the file */
        return PRT_OK;
    }
    struct stat sb;
    unsigned char h[HEADER];
    prt_status st = PRT_OK;
    if (fstat(r->fd, &sb) || pread(r->fd, h, HEADER, 0) != HEADER || memcmp(h, magic, 8))
        st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: not a file of kept light-cloud solutions", path);
    else if (get64(h + 48) != 1 && get64(h + 48) != 4 && get64(h + 48) != 9)
        st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: its emission lobes per light are out of range (damaged)", path);
    else if (get64(h + 48) != r->lobes)   /* named: the one setting a grown cloud is likely to change */
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s holds solutions at emission order %d, this bake's is %d (--emission-order): name another file or delete it",
                       path, get64(h + 48) == 9 ? 3 : get64(h + 48) == 4 ? 2 : 1, lobes == 9 ? 3 : lobes == 4 ? 2 : 1);
    else if (get64(h + 8) != fp->a || get64(h + 16) != fp->b || get64(h + 24) != nv || get64(h + 32) != glossy)
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG,
                       "%s holds the solutions of another scene or other settings (samples, basis, bounces, store, ...): name another file or delete it", path);
    const uint64_t records = st ? 0 : get64(h + 40), record_bytes = (r->floats + 4) * sizeof(float);
    if (!st && (records > (uint64_t)(sb.st_size - HEADER) / record_bytes || (uint64_t)sb.st_size != HEADER + records * record_bytes || records > UINT32_MAX - 1))
        st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: its size does not match its counts (truncated or damaged)", path);
    if (!st && !(r->pos = malloc((records + 1) * 4 * sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (uint64_t i = 0; i < records && !st; ++i) {
        float *p = r->pos + i * 4;
        if (pread(r->fd, p, 4 * sizeof(float), (off_t)(HEADER + i * record_bytes)) != (ssize_t)(4 * sizeof(float)) || !prt__all_finite(p, 4) ||
            (p[3] != 0.0f && p[3] != 1.0f))
            st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: record %llu is damaged", path, (unsigned long long)i);
    }
    r->records = records;
    /* Positions match bit for bit: the grid and the lists give the same floats every bake. The
     * last record of a position wins (a file never holds two; a damaged one is no worse). Records
     * sorted by position, each light found by bisection: clouds of 10^5 lights and more. */
    keyed *key = st ? NULL : malloc((records + 1) * sizeof *key);
    if (!st && !key) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (uint64_t i = 0; i < records && !st; ++i) {
        memcpy(key[i].p, r->pos + i * 4, sizeof key[i].p);
        key[i].record = (uint32_t)i;
    }
    if (!st) qsort(key, records, sizeof *key, key_cmp);
    for (uint32_t j = 0; j < n && !st; ++j) {
        keyed want;
        memcpy(want.p, cloud + (size_t)j * 3, sizeof want.p);
        want.record = UINT32_MAX;   /* after every record of its position: the last one is just before */
        uint64_t lo = 0, hi = records;
        while (lo < hi) {
            const uint64_t mid = lo + (hi - lo) / 2;
            if (key_cmp(&key[mid], &want) < 0) lo = mid + 1;
            else hi = mid;
        }
        if (lo > 0 && !memcmp(key[lo - 1].p, want.p, sizeof want.p)) r->record_of[j] = key[lo - 1].record;
    }
    free(key);
    if (st) { prt__lightcloud_responses_close(r); return st; }
    *out = r;
    return PRT_OK;
}

bool prt__lightcloud_responses_has(const prt__lightcloud_responses *r, uint32_t light) { return r && r->record_of[light] != UINT32_MAX; }

prt_status prt__lightcloud_responses_read(prt_context *ctx, prt__lightcloud_responses *r, uint32_t light, int lobe, float *diffuse, float *glossy,
                                          bool *lit)
{
    const uint64_t i = r->record_of[light], record_bytes = (r->floats + 4) * sizeof(float);
    const off_t at = (off_t)(HEADER + i * record_bytes + (4 + (uint64_t)lobe * r->one) * sizeof(float));
    const size_t db = r->nv * 3 * sizeof(float), gb = r->glossy * 48 * sizeof(float);
    if (pread(r->fd, diffuse, db, at) != (ssize_t)db || (gb && pread(r->fd, glossy, gb, at + (off_t)db) != (ssize_t)gb))
        return prt__fail(ctx, PRT_ERR_IO, "cannot read the kept light-cloud solutions");
    if (!prt__all_finite(diffuse, r->nv * 3) || !prt__all_finite(glossy, r->glossy * 48))
        return prt__fail(ctx, PRT_ERR_FORMAT, "the kept light-cloud solutions hold non-finite values (damaged)");
    *lit = r->pos[i * 4 + 3] == 1.0f;
    if (lobe == 0) __atomic_fetch_add(&r->reused, 1, __ATOMIC_RELAXED);
    return PRT_OK;
}

uint32_t prt__lightcloud_responses_reused(const prt__lightcloud_responses *r) { return r ? r->reused : 0; }

prt_status prt__lightcloud_responses_write(prt_context *ctx, prt__lightcloud_responses *r, const char *path, const prt__fingerprint *fp,
                                           const float *cloud, uint32_t n,
                                           prt_status (*get)(void *user, uint32_t light, int lobe, float *diffuse, float *glossy, bool *lit),
                                           void *user)
{
    /* The cloud's lights, then the kept ones it does not hold (a bake with fewer lights loses none). */
    uint8_t *used = prt__calloc(r->records + 1, 1);
    float *rec = malloc((r->floats + 4) * sizeof(float));
    prt_status st = used && rec ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (uint32_t j = 0; j < n && !st; ++j)
        if (r->record_of[j] != UINT32_MAX) used[r->record_of[j]] = 1;
    uint64_t total = n;
    for (uint64_t i = 0; i < r->records; ++i) total += !used[i];
    unsigned char h[HEADER];
    memcpy(h, magic, 8);
    put64(h + 8, fp->a);
    put64(h + 16, fp->b);
    put64(h + 24, r->nv);
    put64(h + 32, r->glossy);
    put64(h + 40, total);
    put64(h + 48, r->lobes);
    prt__atomic_file f = {0};
    if (!st) st = prt__atomic_open(&f, path);
    if (!st) st = prt__atomic_write(&f, h, HEADER);
    for (uint32_t j = 0; j < n && !st; ++j) {
        bool lit = false;
        memcpy(rec, cloud + (size_t)j * 3, 3 * sizeof(float));
        for (uint64_t k = 0; k < r->lobes && !st; ++k) {
            bool lit_k = false;
            float *at = rec + 4 + k * r->one;
            st = get(user, j, (int)k, at, at + r->nv * 3, &lit_k);
            if (k == 0) lit = lit_k;
        }
        rec[3] = lit ? 1.0f : 0.0f;
        if (!st) st = prt__atomic_write(&f, rec, (r->floats + 4) * sizeof(float));
    }
    const size_t record_bytes = (r->floats + 4) * sizeof(float);
    for (uint64_t i = 0; i < r->records && !st; ++i) {
        if (used[i]) continue;
        if (pread(r->fd, rec, record_bytes, (off_t)(HEADER + i * record_bytes)) != (ssize_t)record_bytes)
            st = prt__fail(ctx, PRT_ERR_IO, "cannot read the kept light-cloud solutions");
        if (!st) st = prt__atomic_write(&f, rec, record_bytes);
    }
    if (f.fp) {
        if (st) prt__atomic_abort(&f);
        else st = prt__atomic_commit(&f);
    }
    free(used);
    free(rec);
    return st;
}
