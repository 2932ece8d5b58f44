/* The offset method's run time on the GPU (Sunshine-Hill & Faloutsos 2006, sections 5.1-5.2),
 * described for the renderer (prt_render_passes): each map cropped to the boxes of its axial
 * slicing, cut into power-of-two vertical slices and binned into square atlases (bins.c); the
 * subsurface maps are the scatter set (replacing albedo x irradiance on translucent texels), the
 * radiosity maps the bounce set. The renderer packs and blends them (render/light_map_gl.c), the
 * same sums as the CPU pass (relight.c). */
#include "methods/offset/bins.h"
#include "methods/offset/offset.h"

void prt__offset_crops_free(prt__offset_crops *c)
{
    free(c->box);
    free(c->map);
    memset(c, 0, sizeof *c);
}

prt_status prt__offset_crop_maps(prt_context *ctx, const prt__offset_set *s, const float *maps, prt__offset_crops *out)
{
    memset(out, 0, sizeof *out);
    const int W = s->width, H = s->height, K = s->count;
    const size_t n = (size_t)W * H, nc = s->covered;
    float *full = malloc(n * 3 * sizeof *full);
    int cap = 0, mcap = 0;
    prt_status st = full ? PRT_OK : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory cropping the offset maps");
    for (int o = 0; o < K && !st; ++o) {
        memset(full, 0, n * 3 * sizeof *full);
        const float *m = maps + (size_t)o * nc * 3;
        for (size_t i = 0; i < nc; ++i) {
            memcpy(full + (size_t)s->texel[i] * 3, m + i * 3, 3 * sizeof *full);
            out->data += m[i * 3] != 0 || m[i * 3 + 1] != 0 || m[i * 3 + 2] != 0;
        }
        prt__offset_maps_drop(s);   /* a streamed bake's maps (maps.c): read map by map, not kept */
        int x0, y0, w, h;
        if (prt__map_crop(full, W, H, &x0, &y0, &w, &h)) out->whole += (int64_t)w * h;
        const int first = out->count;
        if ((st = prt__map_slice(ctx, full, W, H, PRT__SLICE_OVERHEAD, &out->box, &out->count, &cap))) break;
        if (out->count > mcap) {
            int *d = realloc(out->map, (size_t)cap * sizeof *d);
            if (!d) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory cropping the offset maps"); break; }
            out->map = d;
            mcap = cap;
        }
        for (int b = first; b < out->count; ++b) {
            out->map[b] = o;
            out->area += (int64_t)out->box[b].w * out->box[b].h;
        }
    }
    free(full);
    if (st) prt__offset_crops_free(out);
    return st;
}

/* Slices of one kind's maps in atlases of bin_size^2 texels: set->slices is owned by *slices. */
static prt_status slice_maps(prt_context *ctx, const prt__offset_set *s, const float *maps, int bin_size, prt_render_map_set *set,
                             prt_render_slice **slices)
{
    const int K = s->count;
    prt__offset_crops c;
    prt__bin_piece *pieces = NULL;
    int npieces = 0, nbins = 0, *bw = NULL, *bh = NULL;
    prt_status st = prt__offset_crop_maps(ctx, s, maps, &c);
    if (st) return st;
    /* The binning places each map's boxes as maps of their own. */
    bw = malloc((size_t)c.count * sizeof *bw + 1);
    bh = malloc((size_t)c.count * sizeof *bh + 1);
    if (!bw || !bh) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the offset atlases");
    for (int b = 0; !st && b < c.count; ++b) {
        bw[b] = c.box[b].w;
        bh[b] = c.box[b].h;
    }
    if (!st) st = prt__bin_maps(ctx, bw, bh, c.count, bin_size, &pieces, &npieces, &nbins);
    prt_render_slice *out = !st ? malloc((size_t)npieces * sizeof *out + 1) : NULL;
    if (!st && !out) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the offset atlases");
    for (int p = 0; !st && p < npieces; ++p) {
        const prt__bin_piece *pc = &pieces[p];
        const prt__map_box *b = &c.box[pc->map];
        out[p] = (prt_render_slice){c.map[pc->map], b->x0 + pc->sx, b->y0 + pc->sy, pc->w, pc->h, pc->bin, pc->dx, pc->dy};
    }
    if (!st) {
        /* What the GPU will hold against what the maps hold. */
        const double atlas_mib = (double)nbins * bin_size * bin_size * 3 * sizeof(float) / 1048576.0;   /* RGB32F layers */
        const double maps_mib = (double)K * s->covered * 3 * sizeof(uint16_t) / 1048576.0;
        prt__log(ctx, PRT_LOG_INFO,
                 "GPU atlases: %d maps cut into %d boxes (%.0f%% of their texels hold data, %.0f%% of one box per map), %d slices in %d atlases of "
                 "%d x %d texels, %.1f MiB (the maps as halves: %.1f MiB, %.2fx)",
                 K, c.count, c.area ? 100.0 * (double)c.data / (double)c.area : 0.0, c.whole ? 100.0 * (double)c.data / (double)c.whole : 0.0, npieces, nbins,
                 bin_size, bin_size, atlas_mib, maps_mib, maps_mib > 0 ? atlas_mib / maps_mib : 0.0);
        *set = (prt_render_map_set){K, maps, s->offsets, npieces, out, bin_size, nbins, NULL};
        *slices = out;
    } else {
        free(out);
    }
    prt__offset_crops_free(&c);
    free(bw); free(bh); free(pieces);
    return st;
}

prt_status prt__offset_gpu_passes(prt_context *ctx, const prt_transfer *t, const prt_render_passes **out)
{
    prt__offset_set *s = t->state;
    const prt_render_passes *ready = __atomic_load_n(&s->passes, __ATOMIC_ACQUIRE);
    if (ready) { *out = ready; return PRT_OK; }
    prt_status st = s->radiosity ? prt__offset_filter_ready(ctx, t, s) : PRT_OK;
    if (st) return st;
    pthread_mutex_lock(s->lock);
    if (!s->passes) {
        prt_render_passes *p = prt__calloc(1, sizeof *p);
        int bin_size = 1;
        while (bin_size < s->width || bin_size < s->height) bin_size *= 2;
        if (!p) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        if (!st && s->radiosity) st = slice_maps(ctx, s, s->radiosity, bin_size, &p->bounce, &s->slices[0]);
        if (!st && s->subsurface) st = slice_maps(ctx, s, s->subsurface, bin_size, &p->scatter, &s->slices[1]);
        if (!st) {
            p->id = t->serial;
            p->width = s->width;
            p->height = s->height;
            p->covered = s->covered;
            p->texel = s->texel;
            p->source = s->source;
            p->albedo = s->albedo;
            p->scatter_mask = s->subsurface ? s->medium : NULL;
            p->emission = s->emit;
            if (s->radiosity && s->levels) {   /* the bounces read prefiltered light, as the CPU's (prefilter.c) */
                p->bounce.levels = s->level;
                p->area = s->area;
                p->chart = s->chart;
                p->smooth_radius = prt__offset_smooth_radius(s);   /* as the CPU's (smooth.c) */
                p->normal = s->nrm;
            }
            __atomic_store_n(&s->passes, p, __ATOMIC_RELEASE);
        } else {
            free(p);
            free(s->slices[0]);
            free(s->slices[1]);
            s->slices[0] = s->slices[1] = NULL;
        }
    }
    pthread_mutex_unlock(s->lock);
    if (!st) *out = s->passes;
    return st;
}
