/* Prefiltered light for the bounce maps (offset.h, prt__offset_filter): a pyramid of area-weighted
 * light sums over blocks of 2^l x 2^l texels, each block knowing whether its surface lies on one
 * chart, and per offset the level its cell's size asks for. */
#include "methods/offset/offset.h"

#include "methods/offset/sampling.h"
#include "geom/texel_raster.h"
#include "geom/uv_islands.h"

#define MIXED (-1)   /* a block whose surface spans charts */
#define EMPTY (-2)   /* a block holding no surface */
#define NO_CHART (-3)   /* a surface texel without a triangle of its own (none in practice): reads at level 0 only */

prt_status prt__offset_filter_ready(prt_context *ctx, const prt_transfer *t, prt__offset_set *s)
{
    pthread_mutex_lock(s->lock);
    prt_status st = PRT_OK;
    if (!s->filter_ready) {
        const int W = s->width, H = s->height, K = s->count;
        const size_t n = (size_t)W * H, nc = s->covered;
        const prt__mesh *m = &t->mesh;
        uint32_t *owner = prt__calloc(n, sizeof *owner), *island = malloc(m->triangle_count * sizeof *island + 1), islands = 0;
        float *bary = malloc(n * 2 * sizeof *bary);
        uint64_t *area = prt__calloc((size_t)K + 1, sizeof *area);
        int32_t *chart = malloc(nc * sizeof *chart + 1);
        uint8_t *level = prt__calloc((size_t)K + 1, 1);
        size_t overlap, outside;
        if (!owner || !island || !bary || !area || !chart || !level || !prt__texel_raster(m, W, H, owner, bary, &overlap, &outside))
            st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st) st = prt__uv_islands(ctx, m, island, &islands);
        for (size_t i = 0; !st && i < nc; ++i) {
            const uint32_t tri = owner[s->texel[i]];
            chart[i] = tri && tri <= m->triangle_count ? (int32_t)island[tri - 1] : NO_CHART;
        }
        /* The levels: a cell of A texels (the integer offsets nearest it, as eq. 8 labels them)
         * reads blocks of side 2^l <= sqrt(A) / 2, so the block stays inside the cell wherever in
         * the block the representative lies. */
        int top = 0;
        while ((2 << top) <= (W < H ? W : H) && top < 15) top++;
        int32_t *label = NULL;
        if (!st) st = prt__offset_labels(ctx, W, H, s->offsets, K, &label);
        for (size_t i = 0, n2 = (size_t)(2 * W - 1) * (2 * H - 1); !st && i < n2; ++i) area[label[i]]++;
        free(label);
        for (int k = 0; !st && k < K; ++k) {
            const double side = sqrt((double)area[k]) / 2;
            int l = 0;
            while (l < top && (double)(2 << l) <= side) l++;
            level[k] = (uint8_t)(s->offsets[k * 2] || s->offsets[k * 2 + 1] ? l : 0);
        }
        int levels = 0;
        for (int k = 0; !st && k < K; ++k) levels = level[k] > levels ? level[k] : levels;
        if (!st) {
            s->chart = chart;
            s->level = level;
            s->levels = levels;
            s->filter_ready = true;
            chart = NULL;
            level = NULL;
        }
        free(owner); free(island); free(bary); free(area); free(chart); free(level);
    }
    pthread_mutex_unlock(s->lock);
    return st;
}

/* Pyramid level l: ceil(W / 2^l) x ceil(H / 2^l) blocks of (sum A L [3], sum A, chart). */
static size_t level_blocks(const prt__offset_set *s, int l)
{
    const size_t w = ((size_t)s->width + ((size_t)1 << l) - 1) >> l, h = ((size_t)s->height + ((size_t)1 << l) - 1) >> l;
    return w * h;
}

size_t prt__offset_filter_scratch(const prt__offset_set *s)
{
    size_t blocks = 0;
    for (int l = 0; l <= s->levels; ++l) blocks += level_blocks(s, l);
    return blocks * 5 + (size_t)s->levels * s->covered * 3 + 1;
}

float *prt__offset_filter_take(prt__offset_set *s)
{
    pthread_mutex_lock(s->lock);
    float *p = s->pyramid_count ? s->pyramids[--s->pyramid_count] : NULL;
    pthread_mutex_unlock(s->lock);
    return p ? p : malloc(prt__offset_filter_scratch(s) * sizeof *p);
}

void prt__offset_filter_give(prt__offset_set *s, float *scratch)
{
    if (!scratch) return;
    pthread_mutex_lock(s->lock);
    if (s->pyramid_count == s->pyramid_cap) {   /* as many as relights ever ran at once */
        const int cap = s->pyramid_cap ? 2 * s->pyramid_cap : 2;
        float **p = realloc(s->pyramids, (size_t)cap * sizeof *p);
        if (p) { s->pyramids = p; s->pyramid_cap = cap; }
    }
    if (s->pyramid_count < s->pyramid_cap) { s->pyramids[s->pyramid_count++] = scratch; scratch = NULL; }
    pthread_mutex_unlock(s->lock);
    free(scratch);   /* no room to keep it: the next relight allocates again */
}

void prt__offset_filter(const prt__offset_set *s, const float *in, float *scratch, const float **out)
{
    const int W = s->width, L = s->levels;
    const size_t nc = s->covered;
    out[0] = in;
    if (!L) return;
    float *pyr[16];
    pyr[0] = scratch;
    for (int l = 1; l <= L; ++l) pyr[l] = pyr[l - 1] + level_blocks(s, l - 1) * 5;
    float *res = pyr[L] + level_blocks(s, L) * 5;
    /* Level 0: the covered texels; the rest empty. Chart ids are stored as floats: exact below 2^24. */
    for (size_t b = 0, n = level_blocks(s, 0); b < n; ++b) {
        float *q = pyr[0] + b * 5;
        q[0] = q[1] = q[2] = q[3] = 0;
        q[4] = EMPTY;
    }
    for (size_t i = 0; i < nc; ++i) {
        float *q = pyr[0] + (size_t)s->texel[i] * 5;
        for (int c = 0; c < 3; ++c) q[c] = s->area[i] * in[i * 3 + c];
        q[3] = s->area[i];
        q[4] = s->chart[i] < 0 ? MIXED : (float)s->chart[i];   /* no chart of its own: no block is pure with it */
    }
    for (int l = 1; l <= L; ++l) {
        const int pw = (W + (1 << (l - 1)) - 1) >> (l - 1), ph = ((int)s->height + (1 << (l - 1)) - 1) >> (l - 1);
        const int w = (pw + 1) / 2, h = (ph + 1) / 2;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                float *q = pyr[l] + ((size_t)y * w + x) * 5;
                q[0] = q[1] = q[2] = q[3] = 0;
                q[4] = EMPTY;
                for (int j = 0; j < 4; ++j) {   /* children in a fixed order: (0,0) (1,0) (0,1) (1,1) */
                    const int cx = x * 2 + (j & 1), cy = y * 2 + (j >> 1);
                    if (cx >= pw || cy >= ph) continue;
                    const float *c = pyr[l - 1] + ((size_t)cy * pw + cx) * 5;
                    for (int k = 0; k < 4; ++k) q[k] += c[k];
                    if (c[4] == EMPTY) continue;
                    q[4] = q[4] == EMPTY ? c[4] : q[4] == c[4] ? q[4] : MIXED;
                }
            }
    }
    /* Each level's light per covered texel: the four blocks around its centre, bilinearly weighted
     * - each block whose surface is all on the texel's chart by its mean light, any other by the
     * texel's own light of the level below - so the light changes smoothly as the representative
     * moves, with no edge at block borders nor where blocks start to straddle a chart's border.
     * The GPU's pass (render/light_map_gl.c) does this arithmetic in the same order. */
    for (int l = 1; l <= L; ++l) {
        float *o = res + (size_t)(l - 1) * nc * 3;
        const int w = (W + (1 << l) - 1) >> l, h = ((int)s->height + (1 << l) - 1) >> l;
        const float inv = 1.0f / (float)(1 << l);
        for (size_t i = 0; i < nc; ++i) {
            const int x = (int)(s->texel[i] % (uint32_t)W), y = (int)(s->texel[i] / (uint32_t)W);
            const float fx = ((float)x + 0.5f) * inv - 0.5f, fy = ((float)y + 0.5f) * inv - 0.5f;
            const int x0 = (int)floorf(fx), y0 = (int)floorf(fy);
            const float ax = fx - (float)x0, ay = fy - (float)y0, own = (float)s->chart[i], *below = out[l - 1] + i * 3;
            float v[3] = {0, 0, 0};
            for (int j = 0; j < 4; ++j) {
                const int bx = x0 + (j & 1), by = y0 + (j >> 1);
                const float wt = ((j & 1) ? ax : 1.0f - ax) * ((j >> 1) ? ay : 1.0f - ay);
                const float *q = bx >= 0 && by >= 0 && bx < w && by < h ? pyr[l] + ((size_t)by * w + bx) * 5 : NULL;
                if (q && q[4] == own && q[3] > 0)
                    for (int c = 0; c < 3; ++c) v[c] += wt * (q[c] / q[3]);
                else
                    for (int c = 0; c < 3; ++c) v[c] += wt * below[c];
            }
            memcpy(o + i * 3, v, sizeof v);
        }
        out[l] = o;
    }
}
