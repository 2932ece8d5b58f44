/* libFuzzer harness: the .prt reader and what reads a loaded file next (description, relighting,
 * the CPU view factor). A custom mutator fixes the chunk and table checksums after mutating, so
 * the fuzzer reaches the loaders' own checks instead of stopping at the CRCs. */
#include <prt/prt.h>

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static prt_context *ctx;
static prt_lighting *l;   /* made once: its map keeps the projections and cubes it builds */
static prt_lighting *local;   /* the sky plus one light of every local kind, for methods that relight them */
static prt_lighting *points;  /* point and sphere lights alone, for methods without distant light (lightcloud) */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!ctx) {
        prt_sky_desc sky = {0};
        sky.width = 32;
        prt_envmap *env = NULL;
        if (prt_context_create(&(prt_context_desc){.threads = 1}, &ctx) != PRT_OK || prt_lighting_create(&l) != PRT_OK ||
            prt_sky_create(&sky, &env) != PRT_OK || prt_lighting_set_envmap(l, env, NULL, 1.0f) != PRT_OK ||
            prt_lighting_copy(l, &local) != PRT_OK || prt_lighting_create(&points) != PRT_OK)
            abort();
        const char *specs[4] = {"point:0,2,0:5", "spot:0,2,0:0,-1,0:40,20:5", "directional:0.2,1,0.3:2", "sphere:1,2,0:0.3:10"};
        for (int i = 0; i < 4; ++i) {
            prt_light li;
            if (prt_light_parse(specs[i], &li) != PRT_OK || prt_lighting_add(local, &li, NULL) != PRT_OK) abort();
            if ((i == 0 || i == 3) && prt_lighting_add(points, &li, NULL) != PRT_OK) abort();
        }
    }
    prt_transfer *t = NULL;
    if (prt_transfer_load_memory(ctx, data, size, &t) != PRT_OK) return 0;
    char *text = NULL;
    if (prt_transfer_describe(t, "fuzz", 1, &text) == PRT_OK) free(text);
    {
        const unsigned can = prt_method_lighting(prt_transfer_method(t));
        const prt_lighting *lighting = !(can & PRT_LIGHTS_ENVIRONMENT) ? points : can & PRT_LIGHTS_POINT ? local : l;
        /* Drawn (local lights left for the renderer, then shaded on the CPU) and per vertex. */
        for (int k = 0; k < 2 * prt_transfer_variant_count(t) && k < 6; ++k) {
            const int v = k / 2;
            prt_relight_desc d = {.variant = v, .per_vertex = k & 1, .with_indirect = 1};
            prt_relit r;
            if (prt_relight(ctx, t, lighting, &d, &r) != PRT_OK) continue;
            float *rgb = malloc(prt_transfer_vertex_count(t) * 3 * sizeof(float));
            const float eye[3] = {1, 2, 3};
            if (rgb) prt_relit_shade(ctx, t, &r, eye, rgb);
            free(rgb);
            prt_relit_free(&r);
        }
    }
    prt_transfer_release(t);
    return 0;
}

#ifdef PRT_LIBFUZZER   /* the replay driver (fuzz/regress.c) has no mutator */
size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed);
size_t LLVMFuzzerMutate(uint8_t *data, size_t size, size_t max_size);

/* Mutates, then recomputes every chunk's CRC that lies inside the file and the table's. */
size_t LLVMFuzzerCustomMutator(uint8_t *data, size_t size, size_t max_size, unsigned int seed)
{
    (void)seed;
    size = LLVMFuzzerMutate(data, size, max_size);
    if (size < 24) return size;
    uint32_t count;
    memcpy(&count, data + 12, 4);
    if (count == 0 || count > 4096 || 24 + 24 * (size_t)count > size) return size;
    for (uint32_t i = 0; i < count; ++i) {
        uint8_t *e = data + 24 + 24 * (size_t)i;
        uint64_t off, len;
        memcpy(&off, e + 8, 8);
        memcpy(&len, e + 16, 8);
        if (off > size || len > size - off) continue;
        uint32_t crc = (uint32_t)crc32(0L, data + off, (uInt)len);
        memcpy(e + 4, &crc, 4);
    }
    memset(data + 20, 0, 4);
    uint32_t crc = (uint32_t)crc32(0L, data, (uInt)(24 + 24 * (size_t)count));
    memcpy(data + 20, &crc, 4);
    return size;
}
#endif
