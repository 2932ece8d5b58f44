/* The offset method's chunks in .prt files (docs/FORMAT.md): what it writes beside the
 * method-independent ones (transfer/file.c), and their loading, every count checked against the
 * chunk's size, the mesh and every other count before it sizes an allocation. */
#include "methods/offset/offset.h"

#include "geom/texel_raster.h"

#define CHUNK_OFSP PRT__FOURCC('O', 'F', 'S', 'P')
#define CHUNK_OFST PRT__FOURCC('O', 'F', 'S', 'T')
#define CHUNK_OFSR PRT__FOURCC('O', 'F', 'S', 'R')
#define CHUNK_OFSS PRT__FOURCC('O', 'F', 'S', 'S')
#define CHUNK_OFSD PRT__FOURCC('O', 'F', 'S', 'D')
/* The maps as halves (files before them hold floats in OFSR and OFSS, still read). */
#define CHUNK_OFHR PRT__FOURCC('O', 'F', 'H', 'R')
#define CHUNK_OFHS PRT__FOURCC('O', 'F', 'H', 'S')
/* The bake's energy cap per kind (optional: files before it lack it, readers before it skip it). */
#define CHUNK_OFSC PRT__FOURCC('O', 'F', 'S', 'C')
#define OFSP_HEADER 72

prt_status prt__offset_save(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__offset_set *s = t->state;
    const size_t nc = s->covered;
    unsigned char *head = prt__chunks_alloc(l, OFSP_HEADER);
    float *texels = prt__chunks_alloc(l, nc * PRT__OFFSET_TEXEL_FLOATS * sizeof(float));
    if (!head || !texels) return PRT_OK;   /* the list records the failure */
    const uint32_t p32[8] = {(uint32_t)s->width, (uint32_t)s->height, (uint32_t)s->count, s->kinds, (uint32_t)s->iterations,
                             (uint32_t)s->importance, s->covered, s->emit != NULL};
    for (int i = 0; i < 8; ++i) prt__put32(head + 4 * i, p32[i]);
    const float f[10] = {s->ray_offset, s->eta, s->mm_per_unit, s->sigma_a[0], s->sigma_a[1], s->sigma_a[2], s->sigma_s[0], s->sigma_s[1], s->sigma_s[2],
                         s->map_bounces > 1 ? (float)s->map_bounces : 0.0f};
    memcpy(head + 32, f, sizeof f);
    prt__chunks_add(l, CHUNK_OFSP, head, (size_t)OFSP_HEADER, s->offsets, (size_t)s->count * 2 * sizeof(int32_t), NULL);
    for (size_t i = 0; i < nc; ++i) {
        float *e = texels + i * PRT__OFFSET_TEXEL_FLOATS;
        memcpy(e, s->pos + i * 3, 12);
        memcpy(e + 3, s->nrm + i * 3, 12);
        memcpy(e + 6, s->albedo + i * 3, 12);
        e[9] = s->area[i];
        memcpy(e + 10, s->env + i * PRT__OFFSET_ENV_COEFFS, PRT__OFFSET_ENV_COEFFS * sizeof(float));
    }
    prt__chunks_add(l, CHUNK_OFST, s->texel, nc * sizeof(uint32_t), texels, nc * PRT__OFFSET_TEXEL_FLOATS * sizeof(float), s->emit, s->emit ? nc * 3 * sizeof(float) : 0,
                    s->emit_in, s->emit ? nc * 3 * sizeof(float) : 0, NULL);
    const size_t values = (size_t)s->count * nc * 3;
    for (int k = 0; k < 2; ++k) {
        const float *maps = k ? s->subsurface : s->radiosity;
        uint16_t *h = maps ? prt__chunks_alloc(l, values * sizeof(uint16_t) + 2) : NULL;   /* + 2: 4-byte chunks */
        if (!maps) continue;
        if (!h) return PRT_OK;
        /* A streamed bake's maps (maps.c): their pages handed back as they are read. */
        const size_t step = (size_t)PRT__OFFSET_MAP_BLOCK * (size_t)(s->count > 0 ? s->count : 1) * 3;
        for (size_t first = 0; first < values; first += step) {
            const size_t end = values - first > step ? first + step : values;
            for (size_t i = first; i < end; ++i) h[i] = prt__half_from_float(maps[i]);
            prt__offset_maps_drop(s);
        }
        if (l->version < 2) l->version = 2;   /* readers of version 1 would miss the maps */
        h[values] = 0;
        prt__chunks_add(l, k ? CHUNK_OFHS : CHUNK_OFHR, h, values * sizeof(uint16_t) + (values & 1 ? 2 : 0), NULL);
    }
    if (s->cap_known) {
        unsigned char *cap = prt__chunks_alloc(l, 24);
        if (!cap) return PRT_OK;
        for (int k = 0; k < 2; ++k) {
            prt__put32(cap + 12 * k, s->cap[k].texels);
            memcpy(cap + 12 * k + 4, &s->cap[k].max, 4);
            memcpy(cap + 12 * k + 8, &s->cap[k].mean, 4);
        }
        prt__chunks_add(l, CHUNK_OFSC, cap, (size_t)24, NULL);
    }
    if (s->subsurface) {
        /* The media: count, 7 floats each, then each texel's (padded to 4 bytes). */
        static const unsigned char zero4[4] = {0};
        unsigned char *head = prt__chunks_alloc(l, 4);
        if (!head) return PRT_OK;
        prt__put32(head, (uint32_t)s->medium_count);
        prt__chunks_add(l, CHUNK_OFSD, head, (size_t)4, s->media, (size_t)s->medium_count * sizeof(prt_medium), s->medium, nc, zero4,
                        ((nc + 3) & ~(size_t)3) - nc, NULL);
    }
    return PRT_OK;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %s", msg); }

/* A texel gathers at most all it sees (radiosity: its albedo) or all it scatters (subsurface:
 * under 1), as the bake caps them; a file with more would make light grow bounce by bounce. */
static prt_status load_maps(prt_context *ctx, const prt__offset_set *s, const prt__chunk_in *c, bool halves, bool radiosity, float **out)
{
    const uint64_t n = (uint64_t)s->count * s->covered * 3;
    if (halves ? c->size != ((n * 2 + 3) & ~(uint64_t)3) : c->size != n * sizeof(float)) return bad(ctx, "offset transfer map chunk size mismatch");
    if (!(*out = malloc(n * sizeof(float) + 1))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (halves) {
        const unsigned char *d = c->data;
        for (uint64_t i = 0; i < n; ++i) {
            uint16_t h;
            memcpy(&h, d + i * 2, 2);
            (*out)[i] = prt__half_to_float(h);
        }
    } else {
        memcpy(*out, c->data, n * sizeof(float));
    }
    for (uint64_t i = 0; i < n; ++i)
        if (!((*out)[i] >= 0 && (*out)[i] <= 1e30f)) return bad(ctx, "offset transfer map values out of range");
    /* Multi-bounce maps: bounce k adds at most the texel's albedo times the brightest albedo to the
     * power k - 1. */
    double series[3] = {1, 1, 1};
    if (radiosity && s->map_bounces > 1) {
        double top[3] = {0, 0, 0};
        for (size_t i = 0; i < s->covered; ++i)
            for (int ch = 0; ch < 3; ++ch) top[ch] = fmax(top[ch], s->albedo[i * 3 + ch]);
        for (int ch = 0; ch < 3; ++ch) {
            double power = 1;
            for (int k = 1; k < s->map_bounces; ++k) { power *= top[ch]; series[ch] += power; }
        }
    }
    for (size_t i = 0; i < s->covered; ++i)
        for (int ch = 0; ch < 3; ++ch) {
            double sum = 0;
            for (int k = 0; k < s->count; ++k) sum += (*out)[((size_t)k * s->covered + i) * 3 + ch];
            const double bound = radiosity ? s->albedo[i * 3 + ch] * series[ch] : 1.0;
            /* 0.1% for halves' relative rounding, 6e-8 each for their absolute one near zero. */
            if (!(sum <= bound * 1.001 + 6e-8 * s->count + 1e-6)) return bad(ctx, "an offset texel gathers more light than it can");
        }
    return PRT_OK;
}

static int key_cmp(const void *a, const void *b)
{
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

prt_status prt__offset_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    (void)meta;
    prt__offset_set *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = s;
    if (!prt__offset_cache_new(s)) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!prt__mesh_has_uv(&t->mesh)) return bad(ctx, "an offset file's mesh has no texture coordinates for its light map");
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_OFSP);
    if (!c || c->size < OFSP_HEADER) return bad(ctx, "offset parameter chunk missing or short");
    const unsigned char *p = c->data;
    s->width = (int)prt__get32(p);
    s->height = (int)prt__get32(p + 4);
    s->count = (int)prt__get32(p + 8);
    s->kinds = prt__get32(p + 12);
    s->iterations = (int)prt__get32(p + 16);
    s->importance = (int)prt__get32(p + 20);
    s->covered = prt__get32(p + 24);
    const uint32_t emits = prt__get32(p + 28);
    float f[10];
    memcpy(f, p + 32, sizeof f);
    s->ray_offset = f[0]; s->eta = f[1]; s->mm_per_unit = f[2];
    for (int k = 0; k < 3; ++k) { s->sigma_a[k] = f[3 + k]; s->sigma_s[k] = f[6 + k]; }
    /* Files of maps holding one bounce wrote 0 here. */
    if (!(f[9] == 0 || (f[9] >= 2 && f[9] <= PRT__OFFSET_MAX_MAP_BOUNCES && f[9] == floorf(f[9])))) return bad(ctx, "offset map bounces out of range");
    s->map_bounces = f[9] >= 2 ? (int)f[9] : 1;
    if (s->map_bounces > 1 && !(s->kinds & PRT__OFFSET_RADIOSITY_BIT)) return bad(ctx, "offset map bounces without radiosity maps");
    const uint64_t n = (uint64_t)(uint32_t)s->width * (uint32_t)s->height;
    if (s->width < 8 || s->width > 4096 || s->height < 8 || s->height > 4096 || s->count < 1 || !s->kinds || s->kinds > 3 || s->iterations < 0 ||
        (s->importance != 0 && s->importance != 1) || !s->covered || s->covered > n || emits > 1 ||
        (uint64_t)s->count > (uint64_t)(2 * s->width - 1) * (uint64_t)(2 * s->height - 1) || n * (uint64_t)s->count > PRT__OFFSET_MAX_ENTRIES ||
        !(s->ray_offset > 0) || !(s->ray_offset <= fmaxf(1e4f * prt__ray_offset(&t->mesh), 1e-6f)) || !(s->eta >= 1 && s->eta <= 4) ||
        !(s->mm_per_unit > 0 && s->mm_per_unit <= 1e9f))
        return bad(ctx, "offset parameters out of range");
    if (c->size != OFSP_HEADER + (uint64_t)s->count * 8) return bad(ctx, "offset parameter chunk size mismatch");
    if (!(s->offsets = malloc((size_t)s->count * 2 * sizeof(int)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int k = 0; k < s->count * 2; ++k) {
        s->offsets[k] = (int32_t)prt__get32(p + OFSP_HEADER + 4 * k);
        const int lim = k % 2 ? s->height : s->width;
        if (s->offsets[k] <= -lim || s->offsets[k] >= lim) return bad(ctx, "an offset lies beyond the light map");
    }
    if (s->offsets[0] || s->offsets[1]) return bad(ctx, "the first offset is not (0, 0)");
    /* Distinct offsets: the run time labels every integer offset by its nearest one. */
    int64_t *key = malloc((size_t)s->count * sizeof *key + 1);
    if (!key) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int k = 0; k < s->count; ++k) key[k] = (int64_t)s->offsets[k * 2] * 16384 + s->offsets[k * 2 + 1];
    qsort(key, (size_t)s->count, sizeof *key, key_cmp);
    bool repeated = false;
    for (int k = 1; k < s->count && !repeated; ++k) repeated = key[k] == key[k - 1];
    free(key);
    if (repeated) return bad(ctx, "an offset repeats another");
    if (!(c = prt__chunk_take(chunks, count, CHUNK_OFST))) return bad(ctx, "offset texel chunk missing");
    const size_t nc = s->covered;
    if (c->size != (uint64_t)nc * (4 + PRT__OFFSET_TEXEL_FLOATS * 4 + (emits ? 24 : 0))) return bad(ctx, "offset texel chunk size mismatch");
    s->texel = malloc(nc * sizeof *s->texel);
    s->pos = malloc(nc * 12); s->nrm = malloc(nc * 12); s->albedo = malloc(nc * 12); s->area = malloc(nc * 4);
    s->env = malloc(nc * PRT__OFFSET_ENV_COEFFS * sizeof(float));
    if (emits) { s->emit = malloc(nc * 12); s->emit_in = malloc(nc * 12); }
    if (!s->texel || !s->pos || !s->nrm || !s->albedo || !s->area || !s->env || (emits && (!s->emit || !s->emit_in)))
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(s->texel, c->data, nc * 4);
    const float *e = (const float *)(const void *)(c->data + nc * 4);
    float row[PRT__OFFSET_TEXEL_FLOATS];
    /* Texel points lie on the mesh (rays start there): inside its bounds, with unit normals and
     * no more area than the whole surface. */
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < t->mesh.vertex_count; ++v)
        for (int k = 0; k < 3; ++k) { lo[k] = fminf(lo[k], t->mesh.positions[v * 3 + k]); hi[k] = fmaxf(hi[k], t->mesh.positions[v * 3 + k]); }
    double surface = 0;
    for (size_t f = 0; f < t->mesh.triangle_count; ++f) {
        const uint32_t *ix = t->mesh.indices + f * 3;
        float e1[3], e2[3], cr[3];
        prt__v3_sub(t->mesh.positions + ix[1] * 3, t->mesh.positions + ix[0] * 3, e1);
        prt__v3_sub(t->mesh.positions + ix[2] * 3, t->mesh.positions + ix[0] * 3, e2);
        prt__v3_cross(e1, e2, cr);
        surface += 0.5 * prt__v3_len(cr);
    }
    const float margin = 1e-3f * (hi[0] - lo[0] + hi[1] - lo[1] + hi[2] - lo[2]) + 1e-6f;
    for (size_t i = 0; i < nc; ++i) {
        memcpy(row, (const unsigned char *)e + i * sizeof row, sizeof row);
        if (!prt__all_finite(row, PRT__OFFSET_TEXEL_FLOATS) || !(row[9] > 0) || !(row[9] <= surface * 1.01 + 1e-12)) return bad(ctx, "offset texel values out of range");
        for (int k = 0; k < 3; ++k)
            if (!(row[k] >= lo[k] - margin && row[k] <= hi[k] + margin)) return bad(ctx, "an offset texel lies outside the mesh");
        if (!(fabsf(prt__v3_len(row + 3) - 1.0f) < 1e-3f)) return bad(ctx, "an offset texel normal is not of unit length");
        for (int k = 10; k < PRT__OFFSET_TEXEL_FLOATS; ++k)
            if (!(fabsf(row[k]) <= 10.0f)) return bad(ctx, "offset texel environment transfer out of range");
        for (int k = 6; k < 9; ++k)
            if (!(row[k] >= 0 && row[k] <= 1)) return bad(ctx, "offset texel albedo out of range");
        memcpy(s->pos + i * 3, row, 12);
        memcpy(s->nrm + i * 3, row + 3, 12);
        memcpy(s->albedo + i * 3, row + 6, 12);
        s->area[i] = row[9];
        memcpy(s->env + i * PRT__OFFSET_ENV_COEFFS, row + 10, PRT__OFFSET_ENV_COEFFS * sizeof(float));
    }
    if (emits) {
        memcpy(s->emit, c->data + nc * (4 + PRT__OFFSET_TEXEL_FLOATS * 4), nc * 12);
        memcpy(s->emit_in, c->data + nc * (4 + PRT__OFFSET_TEXEL_FLOATS * 4 + 12), nc * 12);
        for (size_t i = 0; i < nc * 3; ++i)
            if (!(s->emit[i] >= 0 && s->emit[i] <= PRT__MAX_RADIANCE) || !(s->emit_in[i] >= 0 && s->emit_in[i] <= 1e30f))
                return bad(ctx, "offset texel emission out of range");
    }
    int32_t *label = malloc((size_t)s->width * s->height * sizeof *label);
    if (!label) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_status st = prt__texel_support_charts(ctx, &t->mesh, s->width, s->height, label);
    const bool indexed = !st && prt__offset_set_index(s, label);
    free(label);
    if (st) return st;
    if (!indexed) return bad(ctx, "offset texels out of order or beyond the light map");
    for (int k = 0; k < 2; ++k) {   /* radiosity, then subsurface: halves, or floats (older files) */
        prt__chunk_in *f = prt__chunk_take(chunks, count, k ? CHUNK_OFSS : CHUNK_OFSR), *h = prt__chunk_take(chunks, count, k ? CHUNK_OFHS : CHUNK_OFHR);
        if (f && h) return bad(ctx, "an offset map chunk appears as floats and as halves");
        c = h ? h : f;
        if (!c != !(s->kinds & (k ? PRT__OFFSET_SUBSURFACE_BIT : PRT__OFFSET_RADIOSITY_BIT)))
            return bad(ctx, k ? "the subsurface map chunk does not match the transfer kinds" : "the radiosity map chunk does not match the transfer kinds");
        if (c && (st = load_maps(ctx, s, c, h != NULL, k == 0, k ? &s->subsurface : &s->radiosity))) return st;
    }
    c = prt__chunk_take(chunks, count, CHUNK_OFSD);
    if (!c != !s->subsurface) return bad(ctx, "the subsurface media chunk does not match the transfer kinds");
    if (c) {
        if (c->size < 4) return bad(ctx, "offset media chunk short");
        s->medium_count = (int)prt__get32(c->data);
        if (s->medium_count < 1 || s->medium_count > PRT__OFFSET_MAX_MEDIA ||
            c->size != 4 + (uint64_t)s->medium_count * sizeof(prt_medium) + (((uint64_t)nc + 3) & ~3ull))
            return bad(ctx, "offset media chunk size mismatch");
        s->media = malloc((size_t)s->medium_count * sizeof(prt_medium));
        s->medium = malloc(nc + 1);
        if (!s->media || !s->medium) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        memcpy(s->media, c->data + 4, (size_t)s->medium_count * sizeof(prt_medium));
        memcpy(s->medium, c->data + 4 + (size_t)s->medium_count * sizeof(prt_medium), nc);
        for (int k = 0; k < s->medium_count; ++k)
            if (prt_medium_check(&s->media[k])) return bad(ctx, "an offset medium is out of range");
        for (size_t i = 0; i < nc; ++i)
            if (s->medium[i] > s->medium_count) return bad(ctx, "a texel's medium is out of range");
    }
    if ((c = prt__chunk_take(chunks, count, CHUNK_OFSC))) {
        if (c->size != 24)
            return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: offset cap chunk size mismatch (%llu bytes, 24 expected)", (unsigned long long)c->size);
        for (int k = 0; k < 2; ++k) {
            prt__offset_cap *cap = &s->cap[k];
            cap->texels = prt__get32(c->data + 12 * k);
            memcpy(&cap->max, c->data + 12 * k + 4, 4);
            memcpy(&cap->mean, c->data + 12 * k + 8, 4);
            const bool baked = s->kinds & (k ? PRT__OFFSET_SUBSURFACE_BIT : PRT__OFFSET_RADIOSITY_BIT);
            const char *kind = k ? "subsurface" : "radiosity";
            if (cap->texels > s->covered)
                return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: offset cap out of range: %u %s texels capped of the %u covered", cap->texels, kind,
                                 s->covered);
            if (!baked && cap->texels)
                return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: offset cap out of range: %u %s texels capped, but the file has no %s maps",
                                 cap->texels, kind, kind);
            /* Factors are gathered / bound over capped texels: at least 1, the mean at most the
             * largest, both exactly 1 when none was capped (NaN fails every comparison). */
            if (!(cap->max >= 1 && cap->max <= 1e30f) || !(cap->mean >= 1 && cap->mean <= cap->max) || (!cap->texels && (cap->max != 1 || cap->mean != 1)))
                return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: offset cap out of range: %s factors largest %g, mean %g over %u texels", kind,
                                 (double)cap->max, (double)cap->mean, cap->texels);
        }
        s->cap_known = true;
    }
    static const uint32_t ids[8] = {CHUNK_OFSP, CHUNK_OFST, CHUNK_OFSR, CHUNK_OFSS, CHUNK_OFHR, CHUNK_OFHS, CHUNK_OFSD, CHUNK_OFSC};
    for (int i = 0; i < 8; ++i)
        if (prt__chunk_take(chunks, count, ids[i])) return bad(ctx, "an offset chunk appears twice");
    return PRT_OK;
}
