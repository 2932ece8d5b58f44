/* Shards of a bake and their merge (see transfer/shard.h and docs/CLUSTER.md). */
#include "transfer/shard.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

prt_status prt__checkpoint_digest(const prt_context *ctx, prt__checkpoint *c, prt__fingerprint *out)
{
    memset(out, 0, sizeof *out);
    prt__bytes b = {0};
    const size_t n = prt__checkpoint_size(c);
    for (size_t i = 0; i < n; ++i) {
        int stage;
        uint64_t unit;
        prt__checkpoint_key(c, i, &stage, &unit);
        if (stage == PRT__CHECKPOINT_SHARD_STAGE) continue;   /* a shard's description is not a result */
        if (!prt__checkpoint_find(c, stage, unit, &b)) { prt__bytes_free(&b); return prt__fail(ctx, PRT_ERR_IO, "cannot read a checkpoint's record"); }
        prt__fingerprint_add(out, &stage, sizeof stage);
        prt__fingerprint_add(out, &unit, sizeof unit);
        prt__fingerprint_add(out, b.data, b.size);
    }
    prt__bytes_free(&b);
    return PRT_OK;
}

static void put_hex(cJSON *j, const char *name, const prt__fingerprint *f)
{
    char hex[40];
    snprintf(hex, sizeof hex, "%016llx%016llx", (unsigned long long)f->a, (unsigned long long)f->b);
    cJSON_AddStringToObject(j, name, hex);
}

prt_status prt__shard_describe(const prt_context *ctx, prt__checkpoint *shard, const prt_bake_run_desc *run, int stage, const char *name,
                               uint64_t units, prt__checkpoint *from, const char *from_path)
{
    prt__fingerprint digest;
    prt_status st = prt__checkpoint_digest(ctx, from, &digest);
    if (st) return st;
    cJSON *j = cJSON_CreateObject();
    if (!j) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    cJSON_AddNumberToObject(j, "index", run->shard_index);
    cJSON_AddNumberToObject(j, "count", run->shard_count);
    cJSON_AddNumberToObject(j, "stage", stage);
    cJSON_AddStringToObject(j, "name", name);
    cJSON_AddNumberToObject(j, "units", (double)units);
    cJSON_AddNumberToObject(j, "records", (double)prt__checkpoint_records(shard));
    cJSON_AddStringToObject(j, "from", from_path && from ? from_path : "");
    put_hex(j, "from_digest", &digest);
    cJSON_AddStringToObject(j, "note", run->shard_note ? run->shard_note : "");
    char *text = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    if (!text) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const uint64_t before = prt__checkpoint_records(shard);
    prt__checkpoint_append(shard, PRT__CHECKPOINT_SHARD_STAGE, 0, text, strlen(text));
    cJSON_free(text);
    if (prt__checkpoint_records(shard) == before) return prt__fail(ctx, PRT_ERR_IO, "cannot write the shard %s", run->shard);
    return PRT_OK;
}

/* An open shard and its description. */
typedef struct shard {
    prt__checkpoint *c;
    prt__fingerprint fp;
    prt_bake_shard info;
    char digest[40];
} shard;

static prt_status open_shard(prt_context *ctx, const char *path, shard *s)
{
    memset(s, 0, sizeof *s);
    prt_status st = prt__checkpoint_open_read(ctx, path, NULL, &s->fp, &s->c);
    if (st) return st;
    prt__bytes b = {0};
    if (!prt__checkpoint_find(s->c, PRT__CHECKPOINT_SHARD_STAGE, 0, &b) || !prt__bytes_put(&b, "", 1)) {
        prt__bytes_free(&b);
        return prt__fail(ctx, PRT_ERR_FORMAT, "'%s' is not a whole shard (no description: a checkpoint, or a shard cut off before it was done)", path);
    }
    cJSON *j = cJSON_Parse((const char *)b.data);
    prt__bytes_free(&b);
    const cJSON *f[9];
    static const char *const names[9] = {"index", "count", "stage", "name", "units", "records", "from", "from_digest", "note"};
    bool ok = j != NULL;
    for (int i = 0; ok && i < 9; ++i) {
        f[i] = cJSON_GetObjectItemCaseSensitive(j, names[i]);
        ok = i == 3 || i >= 6 ? cJSON_IsString(f[i]) : cJSON_IsNumber(f[i]);
    }
    if (ok) {
        s->info.index = f[0]->valueint;
        s->info.count = f[1]->valueint;
        s->info.stage = f[2]->valueint;
        snprintf(s->info.stage_name, sizeof s->info.stage_name, "%s", f[3]->valuestring);
        s->info.units = (uint64_t)f[4]->valuedouble;
        s->info.records = (uint64_t)f[5]->valuedouble;
        snprintf(s->info.from, sizeof s->info.from, "%s", f[6]->valuestring);
        snprintf(s->digest, sizeof s->digest, "%s", f[7]->valuestring);
        ok = (s->info.note = strdup(f[8]->valuestring)) != NULL && s->info.count >= 1 && s->info.index >= 1 && s->info.index <= s->info.count &&
             s->info.stage >= -1 && s->info.stage < PRT__CHECKPOINT_SHARD_STAGE;
    }
    cJSON_Delete(j);
    if (!ok) return prt__fail(ctx, PRT_ERR_FORMAT, "'%s': its shard description is damaged", path);
    return PRT_OK;
}

static void close_shard(shard *s)
{
    prt__checkpoint_close(s->c, false);
    free(s->info.note);
    memset(s, 0, sizeof *s);
}

prt_status prt_bake_shard_info(prt_context *ctx, const char *path, prt_bake_shard *out)
{
    if (!path || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake_shard_info: path and out are required");
    shard s;
    prt_status st = open_shard(ctx, path, &s);
    if (!st) {
        *out = s.info;
        s.info.note = NULL;   /* the caller's now */
    }
    close_shard(&s);
    return st;
}

/* Appends every record of c but shard descriptions to out. */
static prt_status copy_records(prt_context *ctx, prt__checkpoint *c, prt__checkpoint *out, unsigned char *have, int stage, uint64_t units)
{
    prt__bytes b = {0};
    const size_t n = prt__checkpoint_size(c);
    const uint64_t before = prt__checkpoint_records(out);
    uint64_t added = 0;
    for (size_t i = 0; i < n; ++i) {
        int s;
        uint64_t u;
        prt__checkpoint_key(c, i, &s, &u);
        if (s == PRT__CHECKPOINT_SHARD_STAGE) continue;
        if (s == stage && u < units) {
            if (have[u]) continue;   /* kept once */
            have[u] = 1;
        }
        if (!prt__checkpoint_find(c, s, u, &b)) { prt__bytes_free(&b); return prt__fail(ctx, PRT_ERR_IO, "cannot read a record"); }
        prt__checkpoint_append(out, s, u, b.data, b.size);
        added++;
    }
    prt__bytes_free(&b);
    if (prt__checkpoint_records(out) != before + added) return prt__fail(ctx, PRT_ERR_IO, "cannot write the merged checkpoint");
    return PRT_OK;
}

prt_status prt_bake_merge_shards(prt_context *ctx, const char *const *paths, int count, const char *out, prt_bake_shard *info)
{
    if (info) memset(info, 0, sizeof *info);
    if (!paths || count < 1 || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "merge: shards and an output are required");
    shard *s = prt__calloc((size_t)count, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = PRT_OK;
    for (int i = 0; !st && i < count; ++i) st = open_shard(ctx, paths[i], &s[i]);
    /* Everything compared with the first; each refusal names both files and what differs. */
    const shard *a = &s[0];
    const char *p0 = paths[0];
    for (int i = 1; !st && i < count; ++i) {
        const shard *b = &s[i];
        if (b->fp.a != a->fp.a || b->fp.b != a->fp.b)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' is a shard of another bake than '%s' (other scene, method, options, seed or prt version)",
                           paths[i], p0);
        else if (b->info.count != a->info.count)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' is shard %d/%d, '%s' one of %d shards", paths[i], b->info.index, b->info.count, p0,
                           a->info.count);
        else if (b->info.stage != a->info.stage)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' holds stage %d (%s), '%s' stage %d (%s)", paths[i], b->info.stage, b->info.stage_name, p0,
                           a->info.stage, a->info.stage_name);
        else if (strcmp(b->digest, a->digest) != 0)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' continued other finished stages than '%s' (--from '%s', not '%s')", paths[i], p0,
                           b->info.from, a->info.from);
        for (int k = 0; !st && k < i; ++k)
            if (s[k].info.index == b->info.index)
                st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' and '%s' are both shard %d/%d", paths[k], paths[i], b->info.index, b->info.count);
    }
    if (!st && count != a->info.count) {
        char missing[256] = "";
        size_t at = 0;
        for (int k = 1; k <= a->info.count && at < sizeof missing - 16; ++k) {
            bool have = false;
            for (int i = 0; i < count; ++i) have |= s[i].info.index == k;
            if (!have) at += (size_t)snprintf(missing + at, sizeof missing - at, "%s%d/%d", at ? ", " : "", k, a->info.count);
        }
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%d of %d shards given: missing %s", count, a->info.count, missing);
    }
    /* The checkpoint they continued, where it was (the same bytes: its digest). */
    prt__checkpoint *from = NULL;
    if (!st && a->info.from[0]) {
        prt__fingerprint d;
        char hex[40];
        if ((st = prt__checkpoint_open_read(ctx, a->info.from, &a->fp, NULL, &from))) {
            char why[512];
            snprintf(why, sizeof why, "%s", prt_last_error());
            st = prt__fail(ctx, st, "the shards continued '%s': %s", a->info.from, why);
        }
        else if (!(st = prt__checkpoint_digest(ctx, from, &d))) {
            snprintf(hex, sizeof hex, "%016llx%016llx", (unsigned long long)d.a, (unsigned long long)d.b);
            if (strcmp(hex, a->digest) != 0)
                st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "'%s' has changed since the shards continued it", a->info.from);
        }
    }
    prt__checkpoint *o = NULL;
    unsigned char *have = NULL;
    const uint64_t units = a->info.stage >= 0 ? a->info.units : 0;
    if (!st && !(have = prt__calloc((size_t)units + 1, 1))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) st = prt__checkpoint_open(ctx, out, &a->fp, false, &o);
    if (!st && from) st = copy_records(ctx, from, o, have, a->info.stage, units);
    for (int i = 0; !st && i < count; ++i) st = copy_records(ctx, s[i].c, o, have, a->info.stage, units);
    uint64_t held = 0;
    for (uint64_t u = 0; !st && u < units; ++u) held += have[u];
    if (!st && held != units)
        st = prt__fail(ctx, PRT_ERR_FORMAT, "the shards hold %llu of the %llu units of stage %d (%s): a shard is damaged", (unsigned long long)held,
                       (unsigned long long)units, a->info.stage, a->info.stage_name);
    prt__checkpoint_close(o, st != PRT_OK);
    prt__checkpoint_close(from, false);
    free(have);
    if (!st && info) {
        *info = a->info;
        s[0].info.note = NULL;
    }
    for (int i = 0; i < count; ++i) close_shard(&s[i]);
    free(s);
    return st;
}
