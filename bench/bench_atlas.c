/* Benchmark of generated UV atlases (geom/uv_atlas.c): for each mesh and map size, the seconds
 * the atlas takes, its charts, and its coverage both ways prt counts it: texels the charts touch
 * (the atlas's report, the bake's log) and texels the raster samples on the surface (prt info's
 * atlas_coverage, what the offset method bakes; since border texels are sampled, the same), and
 * the texels the charts' bilinear reads reach (their own gutter rings too; the rest lies free).
 * --ppm DIR writes each layout as a picture (charts in colours, sampled texels bright,
 * touched-only texels dim, gutter black).
 * Usage: prt_bench_atlas [MESH...] [--sizes 128,256,512] [--threads N] [--ppm DIR]
 * Without MESH: ../shared/data's bunny, else the procedural demo scene. JSON lines on stdout. */
#include "bench_common.h"
#include "geom/texel_raster.h"
#include "geom/uv_atlas.h"
#include "geom/uv_islands.h"

#include <string.h>

static void write_ppm(const prt_context *ctx, const char *path, const prt__mesh *m, int res, const uint32_t *owner, const float *area)
{
    uint32_t *island = malloc(m->triangle_count * sizeof *island + 1), count = 0;
    uint8_t *rgb = calloc((size_t)res * res * 3, 1);
    FILE *f = fopen(path, "wb");
    if (island && rgb && f && !prt__uv_islands(ctx, m, island, &count)) {
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                const size_t i = (size_t)y * res + x, o = (size_t)(res - 1 - y) * res + x;   /* v up */
                if (!(area[i] > 0)) continue;
                uint32_t h = island[owner[i] ? owner[i] - 1 : 0] * 2654435761u + 12345;
                const bool centre = owner[i] != 0;
                for (int c = 0; c < 3; ++c) {
                    h = h * 1664525u + 1013904223u;
                    const int v = 80 + (int)(h >> 25);
                    rgb[o * 3 + c] = (uint8_t)(centre ? v : v / 3);
                }
            }
        fprintf(f, "P6\n%d %d\n255\n", res, res);
        fwrite(rgb, 1, (size_t)res * res * 3, f);
    }
    if (f) fclose(f);
    free(island);
    free(rgb);
}

int main(int argc, char **argv)
{
    const char *meshes[64];
    int nmesh = 0, threads = 0, sizes[16] = {128, 256, 512}, nsizes = 3;
    const char *ppm = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--ppm") && i + 1 < argc) ppm = argv[++i];
        else if (!strcmp(argv[i], "--sizes") && i + 1 < argc) {
            nsizes = 0;
            for (char *p = argv[++i]; *p && nsizes < 16;) {
                sizes[nsizes++] = (int)strtol(p, &p, 10);
                if (*p == ',') p++;
                else break;
            }
        } else if (argv[i][0] != '-' && nmesh < 64) meshes[nmesh++] = argv[i];
        else { fprintf(stderr, "usage: prt_bench_atlas [MESH...] [--sizes 128,256,512] [--threads N] [--ppm DIR]\n"); return 2; }
    }
    if (!nmesh) meshes[nmesh++] = NULL;
    for (int k = 0; k < nmesh; ++k)
        for (int si = 0; si < nsizes; ++si) {
            prt_context *ctx = NULL;
            prt_scene *s = NULL;
            const char *used = NULL;
            if (!bench_load(meshes[k], threads, &ctx, &s, &used)) return 1;
            prt__mesh *m = &s->mesh;
            for (size_t v = 0; v < m->vertex_count * 2; ++v) m->uv[v] = NAN;
            const int res = sizes[si];
            prt__atlas_report r;
            const double t0 = prt__now();
            const prt_status st = prt__uv_atlas(ctx, m, &(prt__atlas_desc){.resolution = res}, &r);
            const double dt = prt__now() - t0;
            if (st) {
                printf("{\"mesh\": \"%s\", \"texels\": %d, \"error\": \"%s\", \"seconds\": %.3f}\n", used, res, prt_last_error(), dt);
                prt_scene_release(s);
                prt_context_release(ctx);
                continue;
            }
            /* Sampled texels on the surface, counted as the offset bake counts them (prt info). */
            const size_t n = (size_t)res * res;
            uint32_t *owner = calloc(n, sizeof *owner);
            float *bary = calloc(n * 2, sizeof *bary), *area = calloc(n, sizeof *area);
            size_t overlap = 0, outside = 0, centres = 0, touched = 0;
            if (!owner || !bary || !area || !prt__texel_raster(m, res, res, owner, bary, &overlap, &outside) || !prt__texel_areas(m, res, res, area)) return 1;
            for (size_t i = 0; i < n; ++i) { centres += owner[i] && area[i] > 0; touched += area[i] > 0; }
            /* Texels a chart's bilinear reads reach (its data and its own gutter ring): the rest is free. */
            int32_t *label = malloc(n * sizeof *label);
            size_t reached = 0;
            if (!label || prt__texel_support_charts(ctx, m, res, res, label)) return 1;
            for (size_t i = 0; i < n; ++i) reached += label[i] >= 0;
            free(label);
            printf("{\"mesh\": \"%s\", \"texels\": %d, \"charts\": %zu, \"shared\": %zu, \"glued\": %zu, \"seconds\": %.3f, \"touched\": %.4f, \"centres\": %.4f, "
                   "\"reached\": %.4f, \"worst_stretch\": %.3f, \"overlap\": %zu}\n",
                   used, res, r.charts, r.shared, r.glued, dt, (double)touched / n, (double)centres / n, (double)reached / n, r.worst_stretch, overlap);
            fflush(stdout);
            if (ppm) {
                const char *base = strrchr(used, '/');
                char path[1024];
                snprintf(path, sizeof path, "%s/%s_%d.ppm", ppm, base ? base + 1 : used, res);
                write_ppm(ctx, path, m, res, owner, area);
            }
            free(owner); free(bary); free(area);
            prt_scene_release(s);
            prt_context_release(ctx);
        }
    return 0;
}
