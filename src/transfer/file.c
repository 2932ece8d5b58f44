/* .prt files: the method-independent chunks (META, MESH, MATL, UVS0, EMIS) here, the method's
 * own through its table entry, the framing in io/container.c (docs/FORMAT.md). */
#include "transfer/method.h"

#define CHUNK_META PRT__FOURCC('M', 'E', 'T', 'A')
#define CHUNK_MESH PRT__FOURCC('M', 'E', 'S', 'H')
#define CHUNK_MATL PRT__FOURCC('M', 'A', 'T', 'L')
#define CHUNK_UVS PRT__FOURCC('U', 'V', 'S', '0')
#define CHUNK_EMIS PRT__FOURCC('E', 'M', 'I', 'S')
#define CHUNK_SURF PRT__FOURCC('S', 'U', 'R', 'F')

void prt__brdf_put(unsigned char *p, const prt_brdf *b)
{
    float f[38];
    memcpy(f, b->diffuse, 12);
    memcpy(f + 3, b->specular, 12);
    f[6] = b->exponent;
    f[7] = b->exponent_v;
    memcpy(f + 8, b->cxy, 36);
    memcpy(f + 17, b->cz, 36);
    memcpy(f + 26, b->n, 36);
    f[35] = f[36] = f[37] = 0;
    prt__put32(p, (uint32_t)b->model);
    prt__put32(p + 4, (uint32_t)b->lobes);
    memcpy(p + 8, f, sizeof f);
}

void prt__brdf_get(const unsigned char *p, prt_brdf *b)
{
    float f[38];
    memset(b, 0, sizeof *b);
    b->model = (prt_brdf_model)prt__get32(p);
    b->lobes = (int)prt__get32(p + 4);
    memcpy(f, p + 8, sizeof f);
    memcpy(b->diffuse, f, 12);
    memcpy(b->specular, f + 3, 12);
    b->exponent = f[6];
    b->exponent_v = f[7];
    memcpy(b->cxy, f + 8, 36);
    memcpy(b->cz, f + 17, 36);
    memcpy(b->n, f + 26, 36);
}

static char *meta_text(const prt_transfer *t)
{
    cJSON *meta = cJSON_CreateObject();
    cJSON_AddStringToObject(meta, "method", t->method->name);
    cJSON_AddStringToObject(meta, "prt_version", prt_version_string());
    cJSON_AddNumberToObject(meta, "threads", t->threads);
    cJSON_AddNumberToObject(meta, "bake_seconds", t->bake_seconds);
    if (t->peak_bytes) cJSON_AddNumberToObject(meta, "peak_resident_bytes", (double)t->peak_bytes);
    if (t->memory_limit) cJSON_AddNumberToObject(meta, "memory_limit_bytes", t->memory_limit == UINT64_MAX ? -1.0 : (double)t->memory_limit);
    cJSON_AddStringToObject(meta, "source", t->source);
    if (t->has_env) {
        cJSON *e = cJSON_AddObjectToObject(meta, "environment");
        if (t->env.none) cJSON_AddBoolToObject(e, "none", 1);
        cJSON_AddStringToObject(e, "file", t->env.path);
        cJSON_AddNumberToObject(e, "layout", t->env.layout);
        cJSON_AddItemToObject(e, "rotate", cJSON_CreateFloatArray(t->env.rotate_deg, 3));
        cJSON_AddItemToObject(e, "sun", cJSON_CreateFloatArray(t->env.sun_dir, 3));
        cJSON_AddNumberToObject(e, "intensity", t->env.intensity);
    }
    if (t->light_count) {
        cJSON *a = cJSON_AddArrayToObject(meta, "lights");
        for (int i = 0; i < t->light_count; ++i) {
            char spec[512];
            prt_light_format(&t->lights[i], spec, sizeof spec);
            cJSON_AddItemToArray(a, cJSON_CreateString(spec));
        }
    }
    if (t->method->save_meta) t->method->save_meta(t, meta);
    char *text = cJSON_PrintUnformatted(meta);
    cJSON_Delete(meta);
    return text;
}

prt_status prt_transfer_save(const prt_transfer *t, const char *path)
{
    if (!t || !path) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_transfer_save: transfer and path are required");
    const prt__mesh *m = &t->mesh;
    prt__chunk_list l = {0};
    char *meta = meta_text(t);
    if (!meta) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    prt__chunks_add(&l, CHUNK_META, meta, strlen(meta), NULL);
    unsigned char *mesh_head = prt__chunks_alloc(&l, 16);
    const size_t v3 = m->vertex_count * 3 * sizeof(float);
    if (mesh_head) {
        prt__put64(mesh_head, m->vertex_count);
        prt__put64(mesh_head + 8, m->triangle_count);
    }
    prt__chunks_add(&l, CHUNK_MESH, mesh_head, (size_t)16, m->positions, v3, m->normals, v3, m->albedo, v3, m->indices,
                    m->triangle_count * 3 * sizeof(uint32_t), NULL);
    if (t->brdf_count) {
        /* count, pad, the BRDF records, then one material id per vertex padded to 8 bytes. */
        size_t bytes = 8 + (size_t)t->brdf_count * PRT__BRDF_RECORD + ((m->vertex_count + 7) & ~(size_t)7);
        unsigned char *matl = prt__chunks_alloc(&l, bytes);
        if (matl) {
            prt__put32(matl, (uint32_t)t->brdf_count);
            for (int k = 0; k < t->brdf_count; ++k) prt__brdf_put(matl + 8 + (size_t)k * PRT__BRDF_RECORD, &t->brdfs[k]);
            if (m->material) memcpy(matl + 8 + (size_t)t->brdf_count * PRT__BRDF_RECORD, m->material, m->vertex_count);
        }
        prt__chunks_add(&l, CHUNK_MATL, matl, bytes, NULL);
    }
    if (prt__mesh_has_uv(m)) prt__chunks_add(&l, CHUNK_UVS, m->uv, m->vertex_count * 2 * sizeof(float), NULL);
    if (m->emission) prt__chunks_add(&l, CHUNK_EMIS, m->emission, v3, NULL);
    if (m->surface_count && m->surface) {
        /* count, pad, the names (64 bytes each, NUL-padded), one id per vertex padded to 4 bytes. */
        static const unsigned char zero4[4] = {0};
        unsigned char *head = prt__chunks_alloc(&l, 8);
        if (head) prt__put32(head, (uint32_t)m->surface_count);
        const size_t ids = m->vertex_count * sizeof(uint16_t);
        prt__chunks_add(&l, CHUNK_SURF, head, (size_t)8, m->surface_names, (size_t)m->surface_count * PRT__SURFACE_NAME, m->surface, ids, zero4,
                        ((ids + 3) & ~(size_t)3) - ids, NULL);
    }
    prt_status st = t->method->save(t, &l);
    if (!st) st = prt__container_write(path, &l);
    prt__chunks_free(&l);
    cJSON_free(meta);
    return st;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "%s", msg); }

static void read_environment(const cJSON *x, prt_transfer *t)
{
    const cJSON *f = cJSON_GetObjectItemCaseSensitive(x, "file"), *l = cJSON_GetObjectItemCaseSensitive(x, "layout"),
                *r = cJSON_GetObjectItemCaseSensitive(x, "rotate"), *s = cJSON_GetObjectItemCaseSensitive(x, "sun"),
                *in = cJSON_GetObjectItemCaseSensitive(x, "intensity");
    t->has_env = true;
    t->env.none = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(x, "none"));
    if (cJSON_IsString(f)) snprintf(t->env.path, sizeof t->env.path, "%s", f->valuestring);
    if (cJSON_IsNumber(l) && l->valueint >= 0 && l->valueint <= PRT_ENV_VCROSS) t->env.layout = (prt_env_layout)l->valueint;
    for (int k = 0; k < 3; ++k) {
        const cJSON *a = cJSON_GetArrayItem(r, k), *b = cJSON_GetArrayItem(s, k);
        if (cJSON_IsNumber(a) && isfinite(a->valuedouble)) t->env.rotate_deg[k] = (float)a->valuedouble;
        if (cJSON_IsNumber(b) && isfinite(b->valuedouble)) t->env.sun_dir[k] = (float)b->valuedouble;
    }
    if (cJSON_IsNumber(in) && in->valuedouble >= 0 && isfinite(in->valuedouble)) t->env.intensity = (float)in->valuedouble;
}

static prt_status read_meta(prt_context *ctx, const cJSON *meta, prt_transfer *t)
{
    const cJSON *x;
    if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "threads"))) t->threads = x->valueint;
    if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "bake_seconds"))) t->bake_seconds = x->valuedouble;
    if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "peak_resident_bytes")) && x->valuedouble >= 0 && x->valuedouble < 1.8e19)
        t->peak_bytes = (uint64_t)x->valuedouble;
    if (cJSON_IsNumber(x = cJSON_GetObjectItemCaseSensitive(meta, "memory_limit_bytes")))
        t->memory_limit = x->valuedouble < 0 ? UINT64_MAX : x->valuedouble < 1.8e19 ? (uint64_t)x->valuedouble : 0;
    if (cJSON_IsString(x = cJSON_GetObjectItemCaseSensitive(meta, "source"))) snprintf(t->source, sizeof t->source, "%s", x->valuestring);
    if (cJSON_IsObject(x = cJSON_GetObjectItemCaseSensitive(meta, "environment"))) read_environment(x, t);
    if ((x = cJSON_GetObjectItemCaseSensitive(meta, "lights"))) {
        int n = cJSON_GetArraySize(x);
        if (!cJSON_IsArray(x) || n > 100000) return bad(ctx, "corrupt .prt file: invalid light list");
        t->lights = n ? prt__calloc((size_t)n, sizeof *t->lights) : NULL;
        if (n && !t->lights) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        const cJSON *e;
        cJSON_ArrayForEach(e, x) {
            /* A file's lights come from its scene, which names no IES lights: a file naming one
             * would read another file while loading. */
            if (cJSON_IsString(e) && !strncmp(e->valuestring, "ies:", 4)) return bad(ctx, "corrupt .prt file: an IES light among the scene's lights");
            if (!cJSON_IsString(e) || prt_light_parse(e->valuestring, &t->lights[t->light_count]))
                return bad(ctx, "corrupt .prt file: a light of the scene is unreadable");
            t->light_count++;
        }
    }
    return PRT_OK;
}

static prt_status read_mesh(prt_context *ctx, const prt__chunk_in *c, prt__mesh *m)
{
    const unsigned char *p = c->data;
    const uint64_t len = c->size;
    if (len < 16) return bad(ctx, "corrupt .prt file: bad mesh chunk");
    uint64_t nv = prt__get64(p), nt = prt__get64(p + 8);
    /* Bound the counts by the chunk's length before any arithmetic can overflow. */
    if (nv == 0 || nt == 0 || nv > len / 36 || nt > len / 12 || 16 + nv * 36 + nt * 12 != len)
        return bad(ctx, "corrupt .prt file: mesh chunk sizes are inconsistent");
    m->positions = malloc(nv * 12); m->normals = malloc(nv * 12); m->albedo = malloc(nv * 12);
    m->indices = malloc(nt * 12);
    m->material = calloc(nv, 1);
    m->surface = calloc(nv, sizeof(uint16_t));
    m->uv = malloc(nv * 8);
    if (m->uv) for (uint64_t k = 0; k < nv * 2; ++k) m->uv[k] = NAN;
    if (!m->positions || !m->normals || !m->albedo || !m->indices || !m->material || !m->surface || !m->uv) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(m->positions, p + 16, nv * 12);
    memcpy(m->normals, p + 16 + nv * 12, nv * 12);
    memcpy(m->albedo, p + 16 + nv * 24, nv * 12);
    memcpy(m->indices, p + 16 + nv * 36, nt * 12);
    m->vertex_count = nv;
    m->triangle_count = nt;
    for (uint64_t k = 0; k < nt * 3; ++k)
        if (m->indices[k] >= nv) return bad(ctx, "corrupt .prt file: a triangle index is out of range");
    if (!(prt__all_finite(m->positions, nv * 3) && prt__all_finite(m->normals, nv * 3) && prt__all_finite(m->albedo, nv * 3)))
        return bad(ctx, "corrupt .prt file: non-finite vertex data");
    /* Bounded coordinates, unit normals and albedo in [0, 1], as scenes are made: every later
     * computation (frames, BRDF maps, ray offsets) relies on them. */
    for (uint64_t v = 0; v < nv; ++v) {
        const float *p = m->positions + v * 3, *n = m->normals + v * 3, *a = m->albedo + v * 3;
        const float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (fabsf(p[0]) > 1e15f || fabsf(p[1]) > 1e15f || fabsf(p[2]) > 1e15f) return bad(ctx, "corrupt .prt file: a vertex position is out of range");
        if (!(fabsf(len - 1.0f) < 1e-3f)) return bad(ctx, "corrupt .prt file: a vertex normal is not of unit length");
        for (int c = 0; c < 3; ++c)
            if (!(a[c] >= 0.0f && a[c] <= 1.0f)) return bad(ctx, "corrupt .prt file: an albedo is outside [0, 1]");
    }
    return PRT_OK;
}

/* Surface names: each NUL-terminated inside its 64 bytes, not empty, no control characters, no
 * matter if two are alike (they are recoloured together); every vertex's id at most the count. */
static prt_status read_surfaces(prt_context *ctx, const prt__chunk_in *c, prt__mesh *m)
{
    const unsigned char *p = c->data;
    const uint64_t nv = m->vertex_count, len = c->size;
    const uint32_t n = len >= 8 ? prt__get32(p) : 0;
    const uint64_t ids = nv * 2;
    if (n == 0 || n > PRT__MAX_SURFACES || 8 + (uint64_t)n * PRT__SURFACE_NAME + ((ids + 3) & ~3ull) != len)
        return bad(ctx, "corrupt .prt file: invalid surface name chunk");
    if (!(m->surface_names = malloc((size_t)n * PRT__SURFACE_NAME))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(m->surface_names, p + 8, (size_t)n * PRT__SURFACE_NAME);
    m->surface_count = (int)n;
    for (uint32_t k = 0; k < n; ++k) {
        const char *name = m->surface_names[k];
        const size_t l = strnlen(name, PRT__SURFACE_NAME);
        if (l == 0 || l == PRT__SURFACE_NAME) return bad(ctx, "corrupt .prt file: a surface name is empty or unterminated");
        for (size_t i = 0; i < l; ++i)
            if ((unsigned char)name[i] < 32 || name[i] == 127) return bad(ctx, "corrupt .prt file: a surface name holds control characters");
    }
    memcpy(m->surface, p + 8 + (size_t)n * PRT__SURFACE_NAME, nv * sizeof(uint16_t));
    for (uint64_t v = 0; v < nv; ++v)
        if (m->surface[v] > n) return bad(ctx, "corrupt .prt file: a surface id is out of range");
    return PRT_OK;
}

static prt_status read_materials(prt_context *ctx, const prt__chunk_in *c, prt_transfer *t)
{
    const unsigned char *p = c->data;
    const uint64_t nv = t->mesh.vertex_count, len = c->size;
    uint32_t nb = len >= 8 ? prt__get32(p) : 0;
    if (nb == 0 || nb > PRT__MAX_BRDFS || 8 + (uint64_t)nb * PRT__BRDF_RECORD + ((nv + 7) & ~7ull) != len)
        return bad(ctx, "corrupt .prt file: invalid material chunk");
    for (uint32_t k = 0; k < nb; ++k) {
        prt__brdf_get(p + 8 + (size_t)k * PRT__BRDF_RECORD, &t->brdfs[k]);
        if (prt_brdf_validate(&t->brdfs[k])) return bad(ctx, "corrupt .prt file: invalid BRDF in the material chunk");
    }
    t->brdf_count = (int)nb;
    memcpy(t->mesh.material, p + 8 + (size_t)nb * PRT__BRDF_RECORD, nv);
    for (uint64_t v = 0; v < nv; ++v)
        if (t->mesh.material[v] > nb) return bad(ctx, "corrupt .prt file: a material id is out of range");
    return PRT_OK;
}

static prt_status load(prt_context *ctx, prt__chunk_in *chunks, int count, prt_transfer *t)
{
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_META);
    if (!c) return bad(ctx, "corrupt .prt file: metadata chunk missing");
    cJSON *meta = cJSON_ParseWithLength((const char *)c->data, (size_t)c->size);
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(meta, "method");
    if (!meta || !cJSON_IsString(name)) { cJSON_Delete(meta); return bad(ctx, "corrupt .prt file: unreadable metadata"); }
    const prt_method *m = prt_method_find(name->valuestring);
    if (!m) {
        char known[256] = "";
        for (int i = 0; i < prt_method_count(); ++i)
            snprintf(known + strlen(known), sizeof known - strlen(known), "%s%s", i ? ", " : "", prt_method_name(prt_method_at(i)));
        prt_status st = prt__fail(ctx, PRT_ERR_FORMAT, "this prt cannot read method '%.64s' (it knows %s): upgrade prt", name->valuestring, known);
        cJSON_Delete(meta);
        return st;
    }
    t->method = m;
    prt_status st = read_meta(ctx, meta, t);
    if (!st && !(c = prt__chunk_take(chunks, count, CHUNK_MESH))) st = bad(ctx, "corrupt .prt file: mesh chunk missing");
    if (!st) st = read_mesh(ctx, c, &t->mesh);
    if (!st && (c = prt__chunk_take(chunks, count, CHUNK_MATL))) st = read_materials(ctx, c, t);
    if (!st && (c = prt__chunk_take(chunks, count, CHUNK_SURF))) st = read_surfaces(ctx, c, &t->mesh);
    if (!st && (c = prt__chunk_take(chunks, count, CHUNK_UVS))) {
        if (c->size != t->mesh.vertex_count * 8) st = bad(ctx, "corrupt .prt file: texture coordinate chunk size mismatch");
        else {
            memcpy(t->mesh.uv, c->data, c->size);
            if (!prt__mesh_has_uv(&t->mesh)) st = bad(ctx, "corrupt .prt file: non-finite texture coordinates");
        }
    }
    if (!st && (c = prt__chunk_take(chunks, count, CHUNK_EMIS))) {
        if (c->size != t->mesh.vertex_count * 12) st = bad(ctx, "corrupt .prt file: emission chunk size mismatch");
        else if (!(t->mesh.emission = malloc(c->size))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        else {
            memcpy(t->mesh.emission, c->data, c->size);
            for (size_t i = 0; i < t->mesh.vertex_count * 3 && !st; ++i)
                if (!(t->mesh.emission[i] >= 0 && t->mesh.emission[i] < 1e30f)) st = bad(ctx, "corrupt .prt file: invalid emission");
        }
    }
    static const uint32_t once[] = {CHUNK_META, CHUNK_MESH, CHUNK_MATL, CHUNK_UVS, CHUNK_EMIS};
    for (size_t i = 0; !st && i < sizeof once / sizeof once[0]; ++i)
        if (prt__chunk_take(chunks, count, once[i])) {
            char name[5];
            prt__chunk_name(once[i], name);
            st = prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: two %s chunks", name);
        }
    if (!st) st = m->load(ctx, t, meta, chunks, count);
    cJSON_Delete(meta);
    return st;
}

prt_status prt_transfer_load_memory(prt_context *ctx, const void *data, size_t size, prt_transfer **out)
{
    if (!out || (!data && size)) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_transfer_load_memory: data and out are required");
    *out = NULL;
    prt__chunk_in *chunks = NULL;
    int count = 0;
    prt_status st = prt__container_read(ctx, data, size, &chunks, &count);
    if (st) return st;
    prt_transfer *t = prt__calloc(1, sizeof *t);
    if (!t) { free(chunks); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    t->serial = prt__transfer_serial();
    st = load(ctx, chunks, count, t);
    free(chunks);
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}

typedef struct load_target { prt_context *ctx; prt_transfer **out; } load_target;

static prt_status load_bytes(void *user, const void *data, size_t size)
{
    load_target *l = user;
    return prt_transfer_load_memory(l->ctx, data, size, l->out);
}

prt_status prt_transfer_load(prt_context *ctx, const char *path, prt_transfer **out)
{
    if (out) *out = NULL;
    load_target l = {ctx, out};
    return prt__load_path(ctx, path, load_bytes, &l);
}
