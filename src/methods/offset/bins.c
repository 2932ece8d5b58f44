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

/* Axial slicing over a summed-area table of the non-zero texels, so that a box's rows and columns
 * are counted in O(1) each. */
typedef struct slicer {
    const int32_t *sat;   /* (height + 1) x (width + 1): non-zero texels above and left of each corner */
    int stride, overhead;
    prt__map_box *box;
    int count, cap;
    bool oom;
} slicer;

static int32_t filled(const slicer *s, int x0, int y0, int w, int h)
{
    const int32_t *top = s->sat + (size_t)y0 * s->stride, *bottom = s->sat + (size_t)(y0 + h) * s->stride;
    return bottom[x0 + w] - bottom[x0] - top[x0 + w] + top[x0];
}

/* The minimal box of b's non-zero texels (b holds at least one). */
static prt__map_box shrink(const slicer *s, prt__map_box b)
{
    while (!filled(s, b.x0, b.y0, b.w, 1)) b.y0++, b.h--;
    while (!filled(s, b.x0, b.y0 + b.h - 1, b.w, 1)) b.h--;
    while (!filled(s, b.x0, b.y0, 1, b.h)) b.x0++, b.w--;
    while (!filled(s, b.x0 + b.w - 1, b.y0, 1, b.h)) b.w--;
    return b;
}

static void append(slicer *s, prt__map_box b)
{
    if (s->count == s->cap) {
        const int cap = s->cap ? s->cap * 2 : 16;
        prt__map_box *d = cap > s->cap ? realloc(s->box, (size_t)cap * sizeof *d) : NULL;
        if (!d) { s->oom = true; return; }
        s->box = d;
        s->cap = cap;
    }
    s->box[s->count++] = b;
}

/* Appends the pieces of minimal box b and returns what they cost: their texels plus the
 * overhead of each. */
static int64_t slice_box(slicer *s, prt__map_box b)
{
    const int64_t whole = (int64_t)b.w * b.h + s->overhead;
    /* The empty band that leaves out the most texels; b's own edges are never empty. */
    int64_t best = 0;
    int axis = -1, lo = 0, len = 0;
    for (int y = 1, run = 0; y < b.h - 1; ++y) {
        run = filled(s, b.x0, b.y0 + y, b.w, 1) ? 0 : run + 1;
        if ((int64_t)run * b.w > best) best = (int64_t)run * b.w, axis = 0, lo = y - run + 1, len = run;
    }
    for (int x = 1, run = 0; x < b.w - 1; ++x) {
        run = filled(s, b.x0 + x, b.y0, 1, b.h) ? 0 : run + 1;
        if ((int64_t)run * b.h > best) best = (int64_t)run * b.h, axis = 1, lo = x - run + 1, len = run;
    }
    if (axis < 0) { append(s, b); return whole; }
    const prt__map_box a = axis ? (prt__map_box){b.x0, b.y0, lo, b.h} : (prt__map_box){b.x0, b.y0, b.w, lo};
    const prt__map_box c = axis ? (prt__map_box){b.x0 + lo + len, b.y0, b.w - lo - len, b.h} : (prt__map_box){b.x0, b.y0 + lo + len, b.w, b.h - lo - len};
    const int mark = s->count;
    const int64_t cost = slice_box(s, shrink(s, a)) + slice_box(s, shrink(s, c));
    if (cost < whole) return cost;
    s->count = mark;   /* not worth its pieces: the box whole */
    append(s, b);
    return whole;
}

prt_status prt__map_slice(const prt_context *ctx, const float *map, int width, int height, int overhead, prt__map_box **boxes, int *count,
                          int *cap)
{
    if (width < 1 || height < 1 || width > 16384 || height > 16384 || overhead < 0 || *count < 0 || *cap < *count)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "cannot slice a map of %d x %d texels", width, height);
    const int stride = width + 1;
    int32_t *sat = calloc((size_t)stride * (height + 1), sizeof *sat);
    if (!sat) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory slicing a transfer map");
    for (int y = 0; y < height; ++y) {
        int32_t row = 0;
        for (int x = 0; x < width; ++x) {
            const float *v = map + ((size_t)y * width + x) * 3;
            row += v[0] != 0 || v[1] != 0 || v[2] != 0;
            sat[(size_t)(y + 1) * stride + x + 1] = sat[(size_t)y * stride + x + 1] + row;
        }
    }
    slicer s = {sat, stride, overhead, *boxes, *count, *cap, false};
    if (filled(&s, 0, 0, width, height)) slice_box(&s, shrink(&s, (prt__map_box){0, 0, width, height}));
    free(sat);
    *boxes = s.box;
    *count = s.count;
    *cap = s.cap;
    return s.oom ? prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory slicing a transfer map") : PRT_OK;
}
