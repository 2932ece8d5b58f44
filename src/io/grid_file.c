/* Raw density grid files (docs/FORMAT.md "Density grid files"): a header, float32 densities and
 * a CRC-32, all little-endian. Every count is checked against the file's size before the grid
 * is allocated, so a lying header costs nothing. */
#include "core/internal.h"
#include "prt/volume.h"

#include <stdlib.h>
#include <string.h>

#define GRID_MAGIC "PRTGRID"   /* 8 bytes with its NUL */
#define GRID_VERSION 1u
#define GRID_HEADER 28u         /* magic 8, version 4, dims 12, flags 4 */

static uint32_t rd32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static void wr32(unsigned char *p, uint32_t v) { p[0] = (unsigned char)v; p[1] = (unsigned char)(v >> 8); p[2] = (unsigned char)(v >> 16); p[3] = (unsigned char)(v >> 24); }

prt_status prt_volume_grid_parse(prt_context *ctx, const void *data, size_t size, int dims[3], float **density)
{
    if (!data || !dims || !density) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_volume_grid_parse: data, dims and density are required");
    *density = NULL;
    const unsigned char *p = data;
    if (size < GRID_HEADER + 4) return prt__fail(ctx, PRT_ERR_FORMAT, "not a density grid: %zu bytes, shorter than its header", size);
    if (memcmp(p, GRID_MAGIC, 8)) return prt__fail(ctx, PRT_ERR_FORMAT, "not a density grid (no PRTGRID magic)");
    const uint32_t version = rd32(p + 8);
    if (version != GRID_VERSION) return prt__fail(ctx, PRT_ERR_FORMAT, "density grid version %u; this build reads version %u", version, GRID_VERSION);
    uint64_t n = 1;
    int d[3];
    for (int c = 0; c < 3; ++c) {
        const uint32_t v = rd32(p + 12 + 4 * c);
        if (v < 1 || v > PRT_VOLUME_MAX_DIM) return prt__fail(ctx, PRT_ERR_FORMAT, "density grid size %u along axis %d out of range 1..%d", v, c, PRT_VOLUME_MAX_DIM);
        d[c] = (int)v;
        n *= v;
    }
    if (rd32(p + 24)) return prt__fail(ctx, PRT_ERR_FORMAT, "density grid flags 0x%x: version 1 has none", rd32(p + 24));
    if ((uint64_t)size != GRID_HEADER + 4 * n + 4)
        return prt__fail(ctx, PRT_ERR_FORMAT, "density grid of %d x %d x %d voxels needs %llu bytes; the file has %zu", d[0], d[1], d[2],
                         (unsigned long long)(GRID_HEADER + 4 * n + 4), size);
    if (prt__crc32(p, size - 4) != rd32(p + size - 4)) return prt__fail(ctx, PRT_ERR_FORMAT, "density grid CRC mismatch (the file is damaged)");
    float *out = malloc((size_t)n * sizeof *out);
    if (!out) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for a grid of %llu voxels", (unsigned long long)n);
    for (uint64_t i = 0; i < n; ++i) {
        const uint32_t bits = rd32(p + GRID_HEADER + 4 * i);
        float f;
        memcpy(&f, &bits, sizeof f);
        if (!(f >= 0) || !isfinite(f)) {
            free(out);
            return prt__fail(ctx, PRT_ERR_FORMAT, "density grid voxel %llu holds %g (densities are finite and >= 0)", (unsigned long long)i, (double)f);
        }
        out[i] = f;
    }
    memcpy(dims, d, sizeof d);
    *density = out;
    return PRT_OK;
}

typedef struct load_args { prt_context *ctx; int *dims; float **density; } load_args;

static prt_status load_bytes(void *user, const void *data, size_t size)
{
    load_args *a = user;
    return prt_volume_grid_parse(a->ctx, data, size, a->dims, a->density);
}

prt_status prt_volume_grid_load(prt_context *ctx, const char *path, int dims[3], float **density)
{
    if (!path || !dims || !density) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_volume_grid_load: path, dims and density are required");
    *density = NULL;
    load_args a = {ctx, dims, density};
    return prt__load_path(ctx, path, load_bytes, &a);
}

prt_status prt_volume_grid_save(prt_context *ctx, const char *path, const int dims[3], const float *density)
{
    if (!path || !dims || !density) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_volume_grid_save: path, dims and density are required");
    size_t n = 1;
    for (int c = 0; c < 3; ++c) {
        if (dims[c] < 1 || dims[c] > PRT_VOLUME_MAX_DIM) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "density grid size %d out of range 1..%d", dims[c], PRT_VOLUME_MAX_DIM);
        n *= (size_t)dims[c];
    }
    for (size_t i = 0; i < n; ++i)
        if (!(density[i] >= 0) || !isfinite(density[i])) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "density %zu is not finite and >= 0", i);
    const size_t size = GRID_HEADER + 4 * n + 4;
    unsigned char *buf = malloc(size);
    if (!buf) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    memcpy(buf, GRID_MAGIC, 8);
    wr32(buf + 8, GRID_VERSION);
    for (int c = 0; c < 3; ++c) wr32(buf + 12 + 4 * c, (uint32_t)dims[c]);
    wr32(buf + 24, 0);
    for (size_t i = 0; i < n; ++i) {
        uint32_t bits;
        memcpy(&bits, &density[i], sizeof bits);
        wr32(buf + GRID_HEADER + 4 * i, bits);
    }
    wr32(buf + size - 4, prt__crc32(buf, size - 4));
    prt__atomic_file f;
    prt_status st = prt__atomic_open(&f, path);
    if (!st) {
        st = prt__atomic_write(&f, buf, size);
        if (st) prt__atomic_abort(&f);
        else st = prt__atomic_commit(&f);
    }
    free(buf);
    return st ? prt__fail(ctx, st, "'%s': %s", path, prt_last_error()) : PRT_OK;
}
