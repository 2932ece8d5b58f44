/* Key-framed SH transfer (Kautz's course notes, "animated objects"): transfer baked at each key
 * frame of a deforming object, all frames' rows of a set compressed as one clustered PCA so that
 * frames share clusters and basis (VQ + PCA over all frames), and at run time positions, normals
 * and coefficients interpolated linearly between the two key frames around the time. */
#include "methods/sh/sh.h"

#include <math.h>

void prt__sh_frames_free(prt__sh_frames *f)
{
    free(f->positions);
    free(f->normals);
    for (int k = 0; k < PRT__KIND_COUNT; ++k) prt__cpca_free(f->sets[k]);
    memset(f, 0, sizeof *f);
}

int prt__sh_frame_count(const prt_transfer *t)
{
    const prt__sh_state *s = t->state;
    return s && s->frames.count ? s->frames.count : 1;
}

static size_t cpca_bytes(const prt__cpca *c, size_t rows)
{
    return ((size_t)c->clusters * c->dim + c->vectors_total * c->dim + c->weights_total) * sizeof(float) + rows * sizeof(uint32_t) +
           (size_t)c->clusters * sizeof(uint32_t);
}

size_t prt__sh_frames_bytes(const prt__sh_state *s, size_t nv)
{
    const prt__sh_frames *f = &s->frames;
    size_t bytes = (size_t)f->count * nv * 3 * sizeof(float) * (f->normals ? 2 : 1);
    for (int k = 0; k < PRT__KIND_COUNT; ++k)
        if (f->sets[k]) bytes += cpca_bytes(f->sets[k], (size_t)f->count * nv);
    return bytes;
}

/* Row `row` of c reconstructed: its cluster's mean plus its weighted PCA vectors. */
static void cpca_row(const prt__cpca *c, size_t row, float *out)
{
    const size_t dim = (size_t)c->dim;
    const uint32_t cl = c->cluster_of[row];
    memcpy(out, c->means + (size_t)cl * dim, dim * sizeof(float));
    for (uint32_t j = 0; j < c->counts[cl]; ++j) {
        const float w = c->weights[c->weight_start[row] + j], *b = c->basis + (c->basis_start[cl] + j) * dim;
        for (size_t i = 0; i < dim; ++i) out[i] += w * b[i];
    }
}

void prt__sh_frame_rows(const prt__cpca *c, size_t nv, int f, float *out)
{
    for (size_t v = 0; v < nv; ++v) cpca_row(c, (size_t)f * nv + v, out + v * (size_t)c->dim);
}

/* The frames' own check, beyond the scenes' (prt_bake_frames): what was baked must line up too. */
static prt_status frames_match(prt_context *ctx, prt_transfer *const *frames, int count)
{
    const prt__mesh *m0 = &frames[0]->mesh;
    const prt__sh_state *s0 = frames[0]->state;
    for (int f = 0; f < count; ++f) {
        const prt__sh_state *s = prt__sh_need(ctx, frames[f]);
        if (!s) return PRT_ERR_INVALID_ARG;
        const prt__mesh *m = &frames[f]->mesh;
        if (m->vertex_count != m0->vertex_count || m->triangle_count != m0->triangle_count ||
            memcmp(m->indices, m0->indices, m->triangle_count * 3 * sizeof(uint32_t)) || !m->normals != !m0->normals)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frame %d differs in topology from key frame 1", f + 1);
        if (s->texels.width) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frames hold per-vertex transfer: drop --texels");
        if (s->order != s0->order || s->glossy_exit != s0->glossy_exit)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frame %d was baked with other settings than key frame 1", f + 1);
        for (int k = 0; k < PRT__KIND_COUNT; ++k)
            if (s->sets[k].channels != s0->sets[k].channels || s->sets[k].cpca)
                return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frame %d holds other transfer sets than key frame 1", f + 1);
    }
    return PRT_OK;
}

prt_status prt__sh_join_frames(prt_context *ctx, prt_transfer *const *frames, int count, const prt_options *o, prt_transfer **out)
{
    *out = NULL;
    prt_status st = frames_match(ctx, frames, count);
    if (st) return st;
    const prt__sh_state *s0 = frames[0]->state;
    const size_t nv = frames[0]->mesh.vertex_count, rows = (size_t)count * nv;
    /* Always compressed: storing every frame whole is what key-framing across frames saves.
     * --compress, --clusters and --vectors choose how, as for one pose (default clustered PCA). */
    prt_compress_desc cd = {.method = (prt_compress_method)prt__opt_choice(o, "compress", 0), .clusters = prt__opt_int(o, "clusters", 0),
                            .vectors = prt__opt_int(o, "vectors", 0), .seed = s0->seed};
    if ((st = prt__compress_desc_check(ctx, &cd))) return st;
    if (prt__opt(o, "quantize") && prt__opt_int(o, "quantize", 32) != 32)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frames are stored compressed across frames: drop --quantize");
    prt_transfer *t = NULL;
    if ((st = prt__transfer_copy_frame(ctx, frames[0], &t))) return st;
    prt__sh_state *n = prt__sh_state_new();
    if (!n) { prt_transfer_release(t); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    t->state = n;
    n->order = s0->order;
    n->samples = s0->samples;
    n->bounces = s0->bounces;
    n->seed = s0->seed;
    n->glossy_exit = s0->glossy_exit;
    prt__sh_frames *fr = &n->frames;
    fr->count = count;
    fr->positions = malloc(rows * 3 * sizeof(float));
    fr->normals = frames[0]->mesh.normals ? malloc(rows * 3 * sizeof(float)) : NULL;
    if (!fr->positions || (frames[0]->mesh.normals && !fr->normals)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (int f = 0; !st && f < count; ++f) {
        memcpy(fr->positions + (size_t)f * nv * 3, frames[f]->mesh.positions, nv * 3 * sizeof(float));
        if (fr->normals) memcpy(fr->normals + (size_t)f * nv * 3, frames[f]->mesh.normals, nv * 3 * sizeof(float));
    }
    prt__progress prog = {cd.progress, cd.progress_user, NULL, 0, 0, 0.0, 0, ctx};
    for (int k = 0; !st && k < PRT__KIND_COUNT; ++k) {
        if (!s0->sets[k].channels) continue;
        const size_t dim = prt__set_dim(s0, k);
        float *x = malloc(rows * dim * sizeof(float));
        if (!x) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
        for (int f = 0; f < count; ++f) {
            const prt__sh_state *s = frames[f]->state;
            memcpy(x + (size_t)f * nv * dim, s->sets[k].coeffs, nv * dim * sizeof(float));
        }
        char stage[48];
        snprintf(stage, sizeof stage, "compress %d frames' %s", count, prt_transfer_kind_name(prt__kind_from_index(k)));
        prt__progress_begin(&prog, stage, (uint64_t)cd.iterations);
        st = prt__cpca_build(ctx, x, rows, (int)dim, &cd, &prog, &fr->sets[k]);
        prt__progress_end(&prog);
        free(x);
        n->sets[k].channels = s0->sets[k].channels;
        /* Key frame 0 as the file will give it back, for relighting without a time. */
        if (!st && !(n->sets[k].coeffs = malloc(nv * dim * sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st) prt__sh_frame_rows(fr->sets[k], nv, 0, n->sets[k].coeffs);
    }
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}

prt_status prt__sh_at_time(prt_context *ctx, const prt_transfer *t, int frame, float w, prt_transfer *out)
{
    const prt__sh_state *s = t->state;
    const prt__sh_frames *fr = &s->frames;
    const size_t nv = t->mesh.vertex_count;
    prt__sh_state *n = prt__sh_state_new();
    if (!n) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    out->state = n;
    n->order = s->order;
    n->samples = s->samples;
    n->bounces = s->bounces;
    n->seed = s->seed;
    n->glossy_exit = s->glossy_exit;
    const float a = 1.0f - w;
    const float *p0 = fr->positions + (size_t)frame * nv * 3, *p1 = p0 + nv * 3;
    for (size_t i = 0; i < nv * 3; ++i) out->mesh.positions[i] = a * p0[i] + w * p1[i];
    if (fr->normals && out->mesh.normals) {
        const float *n0 = fr->normals + (size_t)frame * nv * 3, *n1 = n0 + nv * 3;
        for (size_t v = 0; v < nv; ++v) {
            float *d = out->mesh.normals + v * 3;
            for (int c = 0; c < 3; ++c) d[c] = a * n0[v * 3 + c] + w * n1[v * 3 + c];
            const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            /* Opposite normals of the two frames average to nothing: keep the nearer frame's. */
            if (len > 1e-6f) for (int c = 0; c < 3; ++c) d[c] /= len;
            else memcpy(d, (w < 0.5f ? n0 : n1) + v * 3, 3 * sizeof(float));
        }
    }
    for (int k = 0; k < PRT__KIND_COUNT; ++k) {
        if (!s->sets[k].channels || !fr->sets[k]) continue;
        const size_t dim = prt__set_dim(s, k);
        float *c = malloc(nv * dim * sizeof(float)), *row = malloc(dim * sizeof(float));
        if (!c || !row) { free(c); free(row); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
        n->sets[k].channels = s->sets[k].channels;
        n->sets[k].coeffs = c;
        for (size_t v = 0; v < nv; ++v) {
            float *x = c + v * dim;
            cpca_row(fr->sets[k], (size_t)frame * nv + v, x);
            if (w == 0.0f) continue;
            cpca_row(fr->sets[k], (size_t)(frame + 1) * nv + v, row);
            for (size_t i = 0; i < dim; ++i) x[i] = a * x[i] + w * row[i];
        }
        free(row);
    }
    return PRT_OK;
}
