/* Benchmark of offset radiance transfer maps (Sunshine-Hill & Faloutsos 2006) beside the paper's
 * Table 1 (a 3,686-vertex face on a Pentium 4 and a GeForce 6800; 256^2: 22-57 s to make 50-400
 * maps, 30.1-2.0 fps; 512^2: 197-226 s, 1.7-1.0 fps for 100-200 maps), for 50/100/200/400 offsets
 * at 256^2 and 512^2:
 *   bake:    seconds to choose the offsets and make the maps;
 *   relight: one accumulation pass (eq. 9, every map once) per second, and its bytes of maps read
 *            per second  vs  plain read bandwidth over a buffer of the same size, measured here;
 *   GPU:     the same passes in the renderer (binned atlases, additive blending; prt_render_light_map
 *            with its read-back): passes per second, and frames per second of a whole relight
 *            (first-order light on the CPU, the passes on the GPU: one for maps of every bounce). On a machine without
 *            a GPU this is Mesa's llvmpipe on the CPU; the renderer's name is printed.
 * Usage: prt_bench_offset [MESH] [--threads N] [--sizes 256,512] [--offsets 50,100,200,400]
 * Without MESH it uses ../shared/data's bunny_lowres.obj (1.8k vertices: a smaller, different mesh
 * from the paper's face) if present, else the procedural demo scene. JSON on stdout, a table on stderr. */
#include "bench_common.h"
#include "methods/offset/offset.h"

#include <string.h>

/* Best of 5: the GPU passes for an input relit with gpu_finish (upload, passes, read-back). */
static double gpu_time(prt_context *ctx, prt_renderer *ren, const prt_transfer *t, const prt_lighting *l, int bounces, float *map)
{
    prt_relit r;
    if (prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .controls = &bounces, .gpu_finish = 1}, &r)) { fprintf(stderr, "bench: %s\n", prt_last_error()); exit(1); }
    prt_render_mesh rm;
    prt_relit_render_mesh(t, &r, &rm);
    double best = 1e30;
    for (int run = 0; run < 5; ++run) {
        const double t0 = prt__now();
        if (prt_render_light_map(ren, &rm, map, NULL)) { fprintf(stderr, "bench: %s\n", prt_last_error()); exit(1); }
        const double dt = prt__now() - t0;
        if (dt < best) best = dt;
    }
    prt_relit_free(&r);
    return best;
}

static int parse_list(const char *text, int *out, int max)
{
    int n = 0;
    for (const char *p = text; *p && n < max;) {
        out[n++] = atoi(p);
        const char *comma = strchr(p, ',');
        if (!comma) break;
        p = comma + 1;
    }
    return n;
}

int main(int argc, char **argv)
{
    const char *mesh = NULL;
    int threads = 0, sizes[4] = {256, 512}, nsizes = 2, counts[8] = {50, 100, 200, 400}, ncounts = 4;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--sizes") && i + 1 < argc) nsizes = parse_list(argv[++i], sizes, 4);
        else if (!strcmp(argv[i], "--offsets") && i + 1 < argc) ncounts = parse_list(argv[++i], counts, 8);
        else if (argv[i][0] != '-' && !mesh) mesh = argv[i];
        else { fprintf(stderr, "usage: prt_bench_offset [MESH] [--threads N] [--sizes 256,512] [--offsets 50,100,200,400]\n"); return 2; }
    }
    if (!mesh && access("../shared/data/meshes/bunny/bunny_lowres.obj", R_OK) == 0) mesh = "../shared/data/meshes/bunny/bunny_lowres.obj";
    prt_context *ctx = NULL;
    prt_scene *s = NULL;
    if (!bench_load(mesh, threads, &ctx, &s, &mesh)) return 1;
    threads = prt__threads(ctx);
    float lo[3], hi[3];
    prt_scene_bounds(s, lo, hi);
    prt_lighting *l = NULL;
    prt_lighting_create(&l);
    prt_light bulb = {.type = PRT_LIGHT_POINT, .position = {0.5f * (lo[0] + hi[0]), hi[1] + 0.5f * (hi[1] - lo[1]), hi[2] + 0.5f * (hi[2] - lo[2])},
                      .intensity = {5, 5, 5}};
    prt_lighting_add(l, &bulb, NULL);
    const prt_method *m = prt_method_find("offset");
    prt_renderer *ren = NULL;
    if (prt_renderer_create(ctx, &(prt_renderer_desc){64, 64, 1}, &ren)) fprintf(stderr, "bench: no OpenGL context (%s): no GPU numbers\n", prt_last_error());
    int largest = 0;
    for (int a = 0; a < nsizes; ++a) largest = sizes[a] > largest ? sizes[a] : largest;
    float *map = malloc((size_t)largest * largest * 3 * sizeof *map + 1);
    fprintf(stderr, "bench: %s, %zu vertices, %d threads; GPU: %s\n  %-6s %-8s %-8s %-10s %-10s %-12s %-34s %-12s %s\n", mesh, prt_scene_vertex_count(s), threads,
            ren ? prt_renderer_name(ren) : "none", "size", "offsets", "texels", "bake s", "MiB", "passes/s", "maps read / plain read bandwidth", "GPU passes/s",
            "GPU fps");
    printf("{\"mesh\": \"%s\", \"vertices\": %zu, \"threads\": %d, \"gpu\": \"%s\", \"runs\": [", mesh, prt_scene_vertex_count(s), threads,
           ren ? prt_renderer_name(ren) : "");
    for (int a = 0; a < nsizes; ++a)
        for (int b = 0; b < ncounts; ++b) {
            char tx[16], nc[16];
            snprintf(tx, sizeof tx, "%d", sizes[a]);
            snprintf(nc, sizeof nc, "%d", counts[b]);
            prt_options *o = NULL;
            prt_options_create(m, &o);
            if (prt_options_set(o, "texels", tx) || prt_options_set(o, "offsets", nc)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
            prt_transfer *t = NULL;
            const double t0 = prt__now();
            if (prt_bake(ctx, s, m, o, NULL, &t)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
            const double bake = prt__now() - t0;
            const prt__offset_set *set = t->state;
            bench_relight_time(ctx, t, l, 0);   /* builds the shadow-ray cache */
            /* A frame: the maps' passes - one for maps holding every bounce (the default), the
             * default count of them for single-bounce maps. */
            int lo, passes, def;
            prt_transfer_control_range(t, 0, &lo, &passes, &def);
            passes = def;
            const double p0 = bench_relight_time(ctx, t, l, 0), pn = bench_relight_time(ctx, t, l, passes), pass = (pn - p0) / passes;
            const double bytes = (double)set->count * set->covered * 3 * sizeof(float);
            const double limit = bench_read_bandwidth((size_t)bytes, threads);
            double gpass = 0, gframe = 0;
            if (ren && map) {
                const double g0 = gpu_time(ctx, ren, t, l, 0, map), gn = gpu_time(ctx, ren, t, l, passes, map);
                gpass = (gn - g0) / passes;
                gframe = p0 + gn;   /* the first-order light on the CPU, then every GPU pass and the read-back */
            }
            char bw[64];
            snprintf(bw, sizeof bw, "%.0f%% (%.3g of %.3g B/s)", pass > 0 && limit > 0 ? 100 * bytes / pass / limit : 0, pass > 0 ? bytes / pass : 0, limit);
            fprintf(stderr, "  %-6d %-8d %-8u %-10.2f %-10.1f %-12.1f %-34s %-12.1f %.1f\n", sizes[a], counts[b], set->covered, bake, bytes / 1048576.0,
                    pass > 0 ? 1 / pass : 0, bw, gpass > 0 ? 1 / gpass : 0, gframe > 0 ? 1 / gframe : 0);
            printf("%s{\"size\": %d, \"offsets\": %d, \"texels\": %u, \"bake_seconds\": %.3f, \"map_bytes\": %.0f, \"pass_seconds\": %.6f, "
                   "\"first_order_seconds\": %.6f, \"read_ratio\": %.3f, \"gpu_pass_seconds\": %.6f, \"gpu_frame_seconds\": %.6f}",
                   a || b ? ", " : "", sizes[a], counts[b], set->covered, bake, bytes, pass, p0, pass > 0 && limit > 0 ? bytes / pass / limit : 0, gpass, gframe);
            prt_transfer_release(t);
            prt_options_release(o);
        }
    printf("]}\n");
    free(map);
    prt_renderer_release(ren);
    prt_lighting_release(l);
    prt_scene_release(s);
    prt_context_release(ctx);
    return 0;
}
