/* The ambient-occlusion method's chunks in .prt files (docs/FORMAT.md): AOCP, its parameters, and
 * AOCA, one accessibility per vertex; loading checks every count against the chunk's size and the
 * mesh before it sizes an allocation, and every value against its range. */
#include "methods/ao/ao.h"
#include "geom/raycast.h"

#define CHUNK_AOCP PRT__FOURCC('A', 'O', 'C', 'P')
#define CHUNK_AOCA PRT__FOURCC('A', 'O', 'C', 'A')
#define AOCP_SIZE 24   /* samples, seed, ray offset (f32), buried vertices, vertex count (u64) */

prt_status prt__ao_save(const prt_transfer *t, prt__chunk_list *l)
{
    const prt__ao_set *s = t->state;
    const size_t nv = t->mesh.vertex_count;
    unsigned char *head = prt__chunks_alloc(l, AOCP_SIZE);
    if (!head) return PRT_OK;   /* the list records the failure */
    prt__put32(head, (uint32_t)s->samples);
    prt__put32(head + 4, s->seed);
    memcpy(head + 8, &s->ray_offset, 4);
    prt__put32(head + 12, s->buried);
    prt__put64(head + 16, nv);
    prt__chunks_add(l, CHUNK_AOCP, head, (size_t)AOCP_SIZE, NULL);
    prt__chunks_add(l, CHUNK_AOCA, s->access, nv * sizeof(float), NULL);
    return PRT_OK;
}

static prt_status bad(prt_context *ctx, const char *msg) { return prt__fail(ctx, PRT_ERR_FORMAT, "corrupt .prt file: %s", msg); }

static prt_status load_params(prt_context *ctx, const prt_transfer *t, prt__ao_set *s, const prt__chunk_in *c)
{
    const unsigned char *p = c->data;
    const uint64_t nv = t->mesh.vertex_count;
    if (c->size != AOCP_SIZE || prt__get64(p + 16) != nv) return bad(ctx, "invalid ambient occlusion parameter chunk");
    const uint32_t samples = prt__get32(p);
    s->seed = prt__get32(p + 4);
    memcpy(&s->ray_offset, p + 8, 4);
    s->buried = prt__get32(p + 12);
    if (samples < PRT__AO_MIN_SAMPLES || samples > PRT__AO_MAX_SAMPLES || s->buried > nv)
        return bad(ctx, "ambient occlusion parameters out of range");
    /* The bake refuses offsets beyond the scene's size (prt__vertex_origins): so does the file. */
    if (!(s->ray_offset > 0.0f) || !(s->ray_offset <= fmaxf(1e4f * prt__ray_offset(&t->mesh), 1e-6f)))
        return bad(ctx, "ambient occlusion ray offset out of range");
    s->samples = (int)samples;
    return PRT_OK;
}

static prt_status load_access(prt_context *ctx, size_t nv, prt__ao_set *s, const prt__chunk_in *c)
{
    if (c->size != (uint64_t)nv * sizeof(float)) return bad(ctx, "ambient occlusion chunk size mismatch");
    if (!(s->access = malloc(nv * sizeof(float)))) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(s->access, c->data, nv * sizeof(float));
    for (size_t v = 0; v < nv; ++v)
        if (!(s->access[v] >= 0.0f && s->access[v] <= 1.0f)) return bad(ctx, "an ambient occlusion value is outside [0, 1]");
    return PRT_OK;
}

prt_status prt__ao_load(prt_context *ctx, prt_transfer *t, const cJSON *meta, prt__chunk_in *chunks, int count)
{
    (void)meta;
    prt__ao_set *s = prt__calloc(1, sizeof *s);
    if (!s) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    t->state = s;
    prt__chunk_in *c = prt__chunk_take(chunks, count, CHUNK_AOCP);
    prt_status st = c ? load_params(ctx, t, s, c) : bad(ctx, "ambient occlusion parameter chunk missing");
    if (!st) st = (c = prt__chunk_take(chunks, count, CHUNK_AOCA)) ? load_access(ctx, t->mesh.vertex_count, s, c)
                                                                   : bad(ctx, "ambient occlusion chunk missing");
    if (!st && (prt__chunk_take(chunks, count, CHUNK_AOCP) || prt__chunk_take(chunks, count, CHUNK_AOCA)))
        st = bad(ctx, "an ambient occlusion chunk appears twice");
    return st;
}
