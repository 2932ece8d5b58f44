/* prt export of offset files (--maps DIR): each transfer map as OpenEXR files of the boxes of its
 * axial slicing (bins.c), the surface and medium masks, and an index naming each map's kind,
 * offset and pieces - what the paper's pipeline hands its binning and rendering programs. */
#include "methods/offset/bins.h"
#include "methods/offset/offset.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <sys/stat.h>

/* Removes what an earlier export left in dir (its maps, medium.exr, surface.exr, index.json), so
 * that a file with fewer maps or kinds never leaves stale maps beside its index; other files stay. */
static prt_status clear_maps(prt_context *ctx, const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return prt__fail(ctx, PRT_ERR_IO, "cannot read '%s': %s", dir, strerror(errno));
    prt_status st = PRT_OK;
    for (struct dirent *e; !st && (e = readdir(d));) {
        const char *n = e->d_name;
        /* kind_NNNN_PPP.exr (a map's pieces), or kind_NNNN.exr (one box per map, before axial
         * slicing): four digits or more (%04d), then three or more (%03d) */
        const char *digits = !strncmp(n, "radiosity_", 10) ? n + 10 : !strncmp(n, "subsurface_", 11) ? n + 11 : NULL;
        size_t nd = 0, np = 0;
        while (digits && digits[nd] >= '0' && digits[nd] <= '9') nd++;
        if (digits && nd >= 4 && digits[nd] == '_')
            while (digits[nd + 1 + np] >= '0' && digits[nd + 1 + np] <= '9') np++;
        const bool map = digits && nd >= 4 && !strcmp(digits + nd + (np >= 3 ? 1 + np : 0), ".exr");
        if (!map && strcmp(n, "medium.exr") && strcmp(n, "surface.exr") && strcmp(n, "index.json")) continue;
        char path[4200];
        snprintf(path, sizeof path, "%s/%s", dir, n);
        if (remove(path) != 0 && errno != ENOENT) st = prt__fail(ctx, PRT_ERR_IO, "cannot remove the earlier export's '%s': %s", path, strerror(errno));
    }
    closedir(d);
    return st;
}

/* Records a written file, so that an export whose mesh then fails takes it back. */
static prt_status keep(prt_context *ctx, prt_export_result *out, const char *path)
{
    if (prt__export_file(out, path)) return PRT_OK;
    remove(path);
    return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory writing the maps");
}

/* A width x height mask (0 or 1, or a medium index) as an image, texel row 0 at the bottom. */
static prt_status save_mask(prt_context *ctx, prt_export_result *out, const char *dir, const char *name, const float *values, int W, int H)
{
    prt_image img = {W, H, malloc((size_t)W * H * 3 * sizeof(float))};
    if (!img.rgb) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory writing the maps");
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int ch = 0; ch < 3; ++ch) img.rgb[((size_t)(H - 1 - y) * W + x) * 3 + ch] = values[(size_t)y * W + x];
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    prt_status st = prt_image_save(path, &img, NULL);
    prt_image_free(&img);
    return st ? prt__fail(ctx, st, "cannot write '%s': %s", path, prt_last_error()) : keep(ctx, out, path);
}

static prt_status write_maps(prt_context *ctx, const prt_transfer *t, const char *dir, prt_export_result *out)
{
    prt_offset_info info;
    prt_transfer_offset_info(t, &info);
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) return prt__fail(ctx, PRT_ERR_IO, "cannot create '%s': %s", dir, strerror(errno));
    prt_status st = clear_maps(ctx, dir);
    if (st) return st;
    const int W = info.width, H = info.height;
    float *map = malloc((size_t)W * H * 3 * sizeof *map);
    cJSON *index = cJSON_CreateObject(), *kinds = index ? cJSON_AddObjectToObject(index, "kinds") : NULL;
    if (!map || !kinds) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory writing the maps");
    if (!st) {
        cJSON_AddNumberToObject(index, "width", W);
        cJSON_AddNumberToObject(index, "height", H);
        cJSON_AddNumberToObject(index, "version", 2);
        cJSON_AddStringToObject(index, "layout", "each map lists its pieces: disjoint boxes crop = [x0, y0, w, h] of its texels (texel rows from v = 0 at the image's bottom), "
                                                 "each in its file, which between them hold every non-zero texel of the map; the map is zero elsewhere, and no "
                                                 "pieces: zero everywhere (version 1 had one box per map: its file, or null, and crop). "
                                                 "A pass over a kind's maps: out(t) = sum over its maps of in(s(t + offset)) * map(t), where s(u) = u on the surface (surface.exr "
                                                 "above 0) and otherwise the surface texel that fills u's gutter: rings grow outwards from the "
                                                 "charts, each texel taking the source of its first neighbour (left, right, down, up) in the ring before. subsurface: in = "
                                                 "irradiance / pi, and out replaces albedo * in on the texels of medium.exr above 0; radiosity: in = the "
                                                 "first-order light map; maps holding map_bounces > 1 bounces give them all in one pass (final = first + "
                                                 "out), maps of 1 are a pass per bounce over what the last one gave (final = first + every pass). "
                                                 "prt's own radiosity pass reads far maps' light prefiltered (an area-weighted pyramid per chart, "
                                                 "src/methods/offset/prefilter.c) and shows the bounced light averaged over each texel's chart within a few texels "
                                                 "(src/methods/offset/smooth.c), which this export does not describe: the sum above is the paper's");
        cJSON_AddNumberToObject(index, "map_bounces", info.map_bounces);
    }
    static const char *const names[2] = {"radiosity", "subsurface"};
    size_t files = 0;
    int maps = 0, cap = 0;
    prt__map_box *boxes = NULL;
    for (int kind = 0; kind < 2 && !st; ++kind) {
        if (!info.has[kind]) continue;
        cJSON *list = cJSON_AddArrayToObject(kinds, names[kind]);
        for (int k = 0; k < info.count && !st; ++k) {
            int off[2], count = 0;
            if ((st = prt_transfer_offset_map(t, (prt_offset_kind)kind, k, off, map))) break;
            if ((st = prt__map_slice(ctx, map, W, H, PRT__SLICE_OVERHEAD, &boxes, &count, &cap))) break;
            cJSON *e = cJSON_CreateObject();
            cJSON *o = cJSON_AddArrayToObject(e, "offset");
            cJSON_AddItemToArray(o, cJSON_CreateNumber(off[0]));
            cJSON_AddItemToArray(o, cJSON_CreateNumber(off[1]));
            cJSON_AddItemToArray(list, e);
            cJSON *pieces = cJSON_AddArrayToObject(e, "pieces");
            maps += count > 0;
            for (int b = 0; b < count && !st; ++b) {
                const prt__map_box *x = &boxes[b];
                prt_image img = {x->w, x->h, malloc((size_t)x->w * x->h * 3 * sizeof(float))};
                if (!img.rgb) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory writing the maps"); break; }
                for (int y = 0; y < x->h; ++y)   /* texel row 0 is v near 0: the image's bottom */
                    memcpy(img.rgb + (size_t)(x->h - 1 - y) * x->w * 3, map + ((size_t)(x->y0 + y) * W + x->x0) * 3, (size_t)x->w * 3 * sizeof(float));
                char name[64], path[4200];
                snprintf(name, sizeof name, "%s_%04d_%03d.exr", names[kind], k, b);
                snprintf(path, sizeof path, "%s/%s", dir, name);
                st = prt_image_save(path, &img, NULL);
                prt_image_free(&img);
                if (st) { st = prt__fail(ctx, st, "cannot write '%s': %s", path, prt_last_error()); break; }
                if ((st = keep(ctx, out, path))) break;
                files++;
                cJSON *p = cJSON_CreateObject();
                cJSON_AddItemToArray(pieces, p);
                cJSON_AddStringToObject(p, "file", name);
                cJSON *crop = cJSON_AddArrayToObject(p, "crop");
                const int box[4] = {x->x0, x->y0, x->w, x->h};
                for (int i = 0; i < 4; ++i) cJSON_AddItemToArray(crop, cJSON_CreateNumber(box[i]));
            }
        }
    }
    free(boxes);
    if (!st) {   /* which texels are on the surface */
        int32_t *src = malloc((size_t)W * H * sizeof *src);
        float *surface = malloc((size_t)W * H * sizeof *surface);
        st = src && surface ? prt_transfer_offset_sources(t, src) : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory writing the maps");
        for (size_t i = 0; !st && i < (size_t)W * H; ++i) surface[i] = src[i] == (int32_t)i ? 1.0f : 0.0f;
        if (!st) st = save_mask(ctx, out, dir, "surface.exr", surface, W, H);
        if (!st) cJSON_AddStringToObject(index, "surface", "surface.exr");
        free(src);
        free(surface);
    }
    if (!st && info.has[PRT_OFFSET_SUBSURFACE]) {   /* which texels the subsurface pass replaces */
        float *med = malloc((size_t)W * H * sizeof *med);
        st = med ? prt_transfer_offset_medium(t, med) : prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory writing the maps");
        if (!st) st = save_mask(ctx, out, dir, "medium.exr", med, W, H);
        if (!st) cJSON_AddStringToObject(index, "medium", "medium.exr");
        free(med);
    }
    /* The index last: a directory with an index holds every map it names. */
    char *text = !st ? cJSON_Print(index) : NULL;
    if (!st && !text) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory writing the maps");
    if (!st) {
        char path[4200];
        snprintf(path, sizeof path, "%s/index.json", dir);
        st = prt__atomic_write_text(path, text);
        if (st) st = prt__fail(ctx, st, "%s", prt_last_error());
        else st = keep(ctx, out, path);
        if (!st) prt__export_report(out, "wrote %d maps in %zu pieces and %s", maps, files, path);
    }
    cJSON_free(text);
    cJSON_Delete(index);
    free(map);
    return st;
}

prt_status prt__offset_export(prt_context *ctx, const prt_transfer *t, const prt_export_desc *d, prt_export_result *out)
{
    const char *dir = prt__opt(d->options, "maps");
    return dir ? write_maps(ctx, t, dir, out) : PRT_OK;
}
