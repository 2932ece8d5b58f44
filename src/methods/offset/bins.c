/* Power-of-two vertical slicing and best-fit / largest-split binning of transfer maps. */
#include "methods/offset/bins.h"

typedef struct slice { int map, sx, sy, w, h; } slice;
typedef struct area { int bin, x, y, w, h; } area;

typedef struct growable {
    void *data;
    size_t count, cap, item;
} growable;

static void *push(growable *g)
{
    if (g->count == g->cap) {
        const size_t cap = g->cap ? g->cap * 2 : 64;
        void *d = realloc(g->data, cap * g->item);
        if (!d) return NULL;
        g->data = d;
        g->cap = cap;
    }
    return (char *)g->data + g->count++ * g->item;
}

prt_status prt__bin_maps(const prt_context *ctx, const int *w, const int *h, int count, int bin_size, prt__bin_piece **pieces, int *piece_count,
                         int *bin_count)
{
    *pieces = NULL;
    *piece_count = *bin_count = 0;
    if (bin_size < 1 || bin_size > 16384 || (bin_size & (bin_size - 1)) || count < 0)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "atlas size %d is not a power of two in 1..16384", bin_size);
    growable slices = {.item = sizeof(slice)}, areas = {.item = sizeof(area)}, out = {.item = sizeof(prt__bin_piece)};
    bool ok = true;
    /* Slices: the binary digits of each width, widest first; wider than an atlas: atlas-wide. */
    for (int i = 0; ok && i < count; ++i) {
        if (w[i] < 0 || h[i] < 0 || w[i] > 1 << 20 || h[i] > 1 << 20) {
            free(slices.data);
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "map %d is %d x %d", i, w[i], h[i]);
        }
        if (!w[i] || !h[i]) continue;
        int x = 0;
        for (int bit = bin_size; bit >= 1 && ok; bit >>= 1)
            while (w[i] - x >= bit && (bit == bin_size || ((w[i] - x) & bit))) {
                slice *s = push(&slices);
                if (!s) { ok = false; break; }
                *s = (slice){i, x, 0, bit, h[i]};
                x += bit;
            }
    }
    int bins = 0;
    size_t left = slices.count;
    slice *sl = slices.data;
    while (ok && left) {
        if (!areas.count) {
            area *a = push(&areas);
            if (!a) { ok = false; break; }
            *a = (area){bins++, 0, 0, bin_size, bin_size};
        }
        /* The widest free area (ties: the latest returned, so an atlas fills before the next). */
        area *as = areas.data;
        size_t pick = areas.count - 1;
        for (size_t i = areas.count; i-- > 0;)
            if (as[i].w > as[pick].w) pick = i;
        const area a = as[pick];
        as[pick] = as[--areas.count];
        /* The tallest slice of its width that fits, else the tallest of its width. */
        long fit = -1, tallest = -1;
        for (size_t i = 0; i < slices.count; ++i) {
            if (!sl[i].h || sl[i].w != a.w) continue;
            if (sl[i].h <= a.h && (fit < 0 || sl[i].h > sl[fit].h)) fit = (long)i;
            if (tallest < 0 || sl[i].h > sl[tallest].h) tallest = (long)i;
        }
        if (tallest < 0) {
            if (a.w > 1) {   /* no slice this wide: halve the area */
                area *l = push(&areas), *r = l ? push(&areas) : NULL;
                if (!r) { ok = false; break; }
                as = areas.data;
                as[areas.count - 2] = (area){a.bin, a.x, a.y, a.w / 2, a.h};
                as[areas.count - 1] = (area){a.bin, a.x + a.w / 2, a.y, a.w / 2, a.h};
            }
            continue;   /* a one-texel-wide area no slice can use stays empty */
        }
        slice *s = &sl[fit >= 0 ? fit : tallest];
        const int take = s->h <= a.h ? s->h : a.h;
        prt__bin_piece *p = push(&out);
        if (!p) { ok = false; break; }
        *p = (prt__bin_piece){s->map, s->sx, s->sy, s->w, take, a.bin, a.x, a.y};
        s->sy += take;
        s->h -= take;
        if (!s->h) left--;
        if (a.h > take) {
            area *rest = push(&areas);
            if (!rest) { ok = false; break; }
            *rest = (area){a.bin, a.x, a.y + take, a.w, a.h - take};
        }
    }
    free(slices.data);
    free(areas.data);
    if (!ok) { free(out.data); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory binning transfer maps"); }
    *pieces = out.data;
    *piece_count = (int)out.count;
    *bin_count = bins;
    return PRT_OK;
}

bool prt__map_crop(const float *map, int width, int height, int *x0, int *y0, int *w, int *h)
{
    int lx = width, ly = height, hx = -1, hy = -1;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const float *v = map + ((size_t)y * width + x) * 3;
            if (v[0] == 0 && v[1] == 0 && v[2] == 0) continue;
            if (x < lx) lx = x;
            if (x > hx) hx = x;
            if (y < ly) ly = y;
            if (y > hy) hy = y;
        }
    if (hx < 0) { *x0 = *y0 = *w = *h = 0; return false; }
    *x0 = lx; *y0 = ly; *w = hx - lx + 1; *h = hy - ly + 1;
    return true;
}
