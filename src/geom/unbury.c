/* Ray origins that start inside geometry. A vertex of a scan folded through itself, or of a floor
 * running under a box, sends its rays from inside a closed surface: every one is blocked, and the
 * vertex bakes black (or, looking out of the far side, white). Lightmappers catch such samples by
 * the share of their rays that meet back faces; prt moves each one to a free point of its own
 * triangle fan, or says how many it could not. */
#include "geom/raycast.h"

#include <string.h>

#define PROBES 24          /* hemisphere rays per test */
#define BACK_SHARE 0.5     /* buried when more than this share of the probes meets back faces */
#define MAX_CANDIDATES 12   /* fan triangles tried */

/* The share of PROBES rays over the hemisphere about n from o that meet a back face first. */
static double hemisphere_back_share(const prt__raycaster *rc, const float o[3], const float n[3])
{
    float t1[3], t2[3], h[3] = {0, 0, 0};
    h[fabsf(n[0]) < 0.6f ? 0 : fabsf(n[1]) < 0.6f ? 1 : 2] = 1;
    prt__v3_cross(n, h, t1);
    if (!prt__v3_normalize(t1)) return 0;
    prt__v3_cross(n, t1, t2);
    int back = 0;
    for (int k = 0; k < PROBES; ++k) {
        /* A Fibonacci spiral over the hemisphere, cosine-spaced towards the normal. */
        const float z = 1.0f - (k + 0.5f) / PROBES, r = sqrtf(fmaxf(0.0f, 1.0f - z * z)), phi = 2.39996323f * k;
        float d[3];
        for (int c = 0; c < 3; ++c) d[c] = r * cosf(phi) * t1[c] + r * sinf(phi) * t2[c] + z * n[c];
        prt__ray_hit h;
        if (prt__raycaster_hit(rc, o, d, &h) && h.ng[0] * d[0] + h.ng[1] * d[1] + h.ng[2] * d[2] > 0.0f) back++;
    }
    return (double)back / PROBES;
}

/* Inside geometry: most rays over the hemisphere the sample sees meet back faces. Behind a
 * surface it touches (a torus or sphere resting on a floor, its contact ring offset below the
 * floor): most rays back into its own surface meet the other surface's back first, where a free
 * sample meets its own surface's front. The larger of the two shares. */
double prt__origin_back_share(const prt__raycaster *rc, const float o[3], const float n[3])
{
    const float back_n[3] = {-n[0], -n[1], -n[2]};
    return fmax(hemisphere_back_share(rc, o, n), hemisphere_back_share(rc, o, back_n));
}

prt_status prt__unbury_origins(const prt_context *ctx, const prt__raycaster *rc, const prt__mesh *m, float offset, float *origins,
                               uint8_t *status, prt_log_level level)
{
    const size_t nv = m->vertex_count, nt = m->triangle_count;
    uint32_t *start = prt__calloc(nv + 1, sizeof *start), *fan = malloc(nt * 3 * sizeof *fan + 1), *fill = prt__calloc(nv, sizeof *fill);
    if (!start || !fan || !fill) { free(start); free(fan); free(fill); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory checking ray origins"); }
    for (size_t i = 0; i < nt * 3; ++i) start[m->indices[i] + 1]++;
    for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) { uint32_t v = m->indices[t * 3 + k]; fan[start[v] + fill[v]++] = (uint32_t)t; }
    free(fill);
    size_t found = 0, moved = 0;
    int stop = 0;   /* a buried vertex tests up to 26 points of 48 rays: look every 64 vertices */
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : found, moved) num_threads(prt__threads(ctx))
    for (size_t v = 0; v < nv; ++v) {
        if (status) status[v] = 0;
        if (prt__cancel_poll(ctx, &stop, v, 63)) continue;
        const float *n = m->normals + v * 3, *p = m->positions + v * 3;
        float *o = origins + v * 3;
        if (prt__origin_back_share(rc, o, n) <= BACK_SHARE) continue;
        found++;
        /* Candidates: halfway and nine tenths of the way to each fan triangle's centroid, lifted
         * off that triangle; then further along the vertex normal. The one with the fewest back
         * faces wins (the first, on a tie). */
        float best[3];
        memcpy(best, o, sizeof best);
        double best_share = 2;
        const uint32_t count = start[v + 1] - start[v] < MAX_CANDIDATES ? start[v + 1] - start[v] : MAX_CANDIDATES;
        for (uint32_t k = 0; k < 2 * count + 2 && best_share > 0; ++k) {
            float q[3], qn[3];
            if (k < 2 * count) {   /* halfway to each centroid, then nearly all the way */
                const uint32_t *ix = m->indices + (size_t)fan[start[v] + k % count] * 3;
                const float way = k < count ? 0.5f : 0.9f;
                const float *a = m->positions + ix[0] * 3, *b = m->positions + ix[1] * 3, *c = m->positions + ix[2] * 3;
                float e1[3], e2[3];
                prt__v3_sub(b, a, e1);
                prt__v3_sub(c, a, e2);
                prt__v3_cross(e1, e2, qn);
                if (!prt__v3_normalize(qn)) continue;
                if (prt__v3_dot(qn, n) < 0) for (int i = 0; i < 3; ++i) qn[i] = -qn[i];
                for (int i = 0; i < 3; ++i) q[i] = p[i] + way * ((a[i] + b[i] + c[i]) / 3.0f - p[i]) + qn[i] * offset;
            } else {
                const float lift = offset * (k == 2 * count ? 8.0f : 64.0f);
                for (int i = 0; i < 3; ++i) { q[i] = p[i] + n[i] * lift; qn[i] = n[i]; }
            }
            const double s = prt__origin_back_share(rc, q, n);
            if (s < best_share) { best_share = s; memcpy(best, q, sizeof best); }
        }
        if (best_share <= BACK_SHARE) {
            memcpy(o, best, sizeof best);
            moved++;
            if (status) status[v] = 1;
        } else if (status) {
            status[v] = 2;
        }
    }
    free(start);
    free(fan);
    if (stop || prt__cancelled(ctx)) return prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled while checking ray origins");
    if (found)
        prt__log(ctx, level, "%zu of %zu vertices started their rays inside geometry (most met back faces): %zu moved to a free point "
                             "of their triangles, %zu left (their whole fan is buried)", found, nv, moved, found - moved);
    return PRT_OK;
}

prt_status prt__fill_buried(const prt__mesh *m, const uint8_t *status, float *data, size_t stride, size_t *unfilled)
{
    const size_t nv = m->vertex_count, nt = m->triangle_count;
    uint8_t *state = malloc(nv);   /* 0 has a value, 1 waiting, 2 filled this round */
    float *sum = NULL;
    uint32_t *count = NULL;
    size_t waiting = 0;
    if (unfilled) *unfilled = 0;
    if (!state) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory filling buried vertices");
    for (size_t v = 0; v < nv; ++v) { state[v] = status[v] == 2; waiting += state[v]; }
    if (waiting) {
        sum = malloc(nv * stride * sizeof *sum);
        count = malloc(nv * sizeof *count);
    }
    /* Ring by ring from the vertices that have values: each waiting vertex next to one takes the
     * mean of such neighbours (over its triangles' edges), so the result is the same in any order. */
    while (waiting && sum && count) {
        memset(count, 0, nv * sizeof *count);
        for (size_t t = 0; t < nt; ++t)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = m->indices[t * 3 + k];
                if (state[a] != 1) continue;
                for (int j = 1; j < 3; ++j) {
                    const uint32_t b = m->indices[t * 3 + (k + j) % 3];
                    if (state[b] != 0) continue;
                    if (!count[a]) memset(sum + (size_t)a * stride, 0, stride * sizeof *sum);
                    for (size_t i = 0; i < stride; ++i) sum[(size_t)a * stride + i] += data[(size_t)b * stride + i];
                    count[a]++;
                }
            }
        size_t done = 0;
        for (size_t v = 0; v < nv; ++v)
            if (state[v] == 1 && count[v]) {
                for (size_t i = 0; i < stride; ++i) data[v * stride + i] = sum[v * stride + i] / (float)count[v];
                state[v] = 2;
                done++;
            }
        if (!done) break;   /* the rest has no neighbour with a value */
        for (size_t v = 0; v < nv; ++v) if (state[v] == 2) state[v] = 0;
        waiting -= done;
    }
    const bool short_of_memory = waiting && (!sum || !count);
    free(sum);
    free(count);
    free(state);
    if (short_of_memory) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory filling buried vertices");
    if (unfilled) *unfilled = waiting;
    return PRT_OK;
}
