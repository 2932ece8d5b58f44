/* Benchmark of the spectral method (Wang, Zhu & Humphreys 2007) against limits measured in the
 * same run:
 *   bake:    gathering rays/s  vs  raw Embree rtcIntersect16 on rays of the same kind
 *   relight: CPU update time (per-vertex radiance, no drawing) with a point light for direct light only, 1 and 3 bounces (with the
 *            default tail, and 3 without it); each bounce's non-zeros/s  vs  a bare sparse gather
 *            over the same matrix
 * and the storage. The paper's figures (one 1.83 GHz Core 2 core for the bake, two for the run
 * time, whole frames on its GPU): 30-54 min bakes for 25-35k vertices at 128 x 128 rays, its
 * bunny (31k vertices; ../shared/data's bun_zipper.ply has 36k and is another mesh) 66
 * coefficients per vertex, 8 MB, 130 / 26 / 17 fps for direct / 1 / 3 bounces.
 * Usage: prt_bench_spectral [MESH | --room] [--samples N] [--basis N] [--threads N]
 * Without MESH it uses ../shared/data's bunny if present, else the procedural demo scene; --room
 * bakes the procedural room of the paper's Fig. 6 (prt demo-scene --room, about 30k vertices).
 * Prints JSON on stdout and a summary on stderr. */
#include "bench_common.h"
#include "methods/spectral/spectral.h"

#include <string.h>
#include <unistd.h>

/* A bare y = T c over the matrix's rows with 3 floats per coefficient (best of several passes):
 * what one bounce's gather cannot beat. */
static double bare_gather(const prt__spectral_set *s, size_t nv, int threads)
{
    const size_t F = s->basis.functions;
    float *c = malloc(F * 3 * sizeof(float)), *y = malloc(nv * 3 * sizeof(float));
    for (size_t i = 0; i < F * 3; ++i) c[i] = (float)(i & 15);
    double best = 1e30;
    for (int pass = 0; pass < 10; ++pass) {
        const double t0 = prt__now();
#pragma omp parallel for schedule(static) num_threads(threads)
        for (size_t v = 0; v < nv; ++v) {
            float a = 0, b = 0, d = 0;
            for (uint64_t i = s->row_start[v]; i < s->row_start[v + 1]; ++i) {
                const float q = s->value[i], *x = c + (size_t)s->index[i] * 3;
                a += q * x[0]; b += q * x[1]; d += q * x[2];
            }
            y[v * 3] = a; y[v * 3 + 1] = b; y[v * 3 + 2] = d;
        }
        const double dt = prt__now() - t0;
        if (dt < best) best = dt;
    }
    if (y[0] == 42.0f) fputs("", stderr);
    free(c);
    free(y);
    return (double)s->row_start[nv] / best;
}

typedef struct clock_ { double transfer_start, transfer_end; } clock_;

static int progress(void *user, const char *stage, uint64_t done, uint64_t total)
{
    clock_ *k = user;
    if (!strcmp(stage, "spectral transfer")) {
        if (!k->transfer_start) k->transfer_start = prt__now();
        if (done == total) k->transfer_end = prt__now();
    }
    if (isatty(2)) fprintf(stderr, "\r  %s %3.0f%%   ", stage, total ? 100.0 * (double)done / (double)total : 100.0);
    return 0;
}

int main(int argc, char **argv)
{
    const char *mesh = NULL, *samples = "4096", *basis = "1024";
    int threads = 0;
    bool room = false;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--samples") && i + 1 < argc) samples = argv[++i];
        else if (!strcmp(argv[i], "--basis") && i + 1 < argc) basis = argv[++i];
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--room")) room = true;
        else if (argv[i][0] != '-' && !mesh) mesh = argv[i];
        else { fprintf(stderr, "usage: prt_bench_spectral [MESH | --room] [--samples N] [--basis N] [--threads N]\n"); return 2; }
    }
    static char room_path[] = "/tmp/prt_bench_room.obj";
    if (room) {
        if (prt_demo_room_write(room_path, 0.0625f)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
        mesh = room_path;
    }
    prt_context *ctx = NULL;
    prt_scene *s = NULL;
    if (!bench_load(mesh, threads, &ctx, &s, &mesh)) return 1;
    threads = prt__threads(ctx);
    const prt_method *m = prt_method_find("spectral");
    prt_options *o = NULL;
    prt_options_create(m, &o);
    if (prt_options_set(o, "samples", samples) || prt_options_set(o, "basis", basis)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    clock_ k = {0};
    prt_bake_run_desc run = {.progress = progress, .progress_user = &k};
    prt_transfer *t = NULL;
    const double t0 = prt__now();
    if (prt_bake(ctx, s, m, o, &run, &t)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    const double bake = prt__now() - t0;
    if (isatty(2)) fputc('\n', stderr);
    const prt__spectral_set *set = t->state;
    const size_t nv = t->mesh.vertex_count;
    const double gather_seconds = k.transfer_end - k.transfer_start;
    const double rays = (double)nv * atof(samples);

    /* Raw Embree on rays of the same kind: the cube's directions over every 8th vertex. */
    prt__raycaster rc;
    float *origins = NULL;
    if (prt__raycaster_create(ctx, &t->mesh, &rc) || prt__vertex_origins(&t->mesh, set->ray_offset, &origins)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    const int ndirs = 2 * atoi(samples) > 2048 ? 2048 : 2 * atoi(samples);
    float *dirs = malloc((size_t)ndirs * 3 * sizeof(float));
    for (int i = 0; i < ndirs; ++i) {
        double u, v, d[3];
        prt__sobol2((uint32_t)i, 7u, &u, &v);
        prt__sphere_dir(u, v, d);
        for (int c = 0; c < 3; ++c) dirs[i * 3 + c] = (float)d[c];
    }
    uint64_t raw_rays = 0;
    const double raw_time = bench_raw_rays(&t->mesh, &rc, origins, dirs, ndirs, 8, true, threads, &raw_rays);

    /* Relighting: a point light in the middle of the scene's bounds, drawn (per-pixel lights). */
    float lo[3], hi[3];
    prt_scene_bounds(s, lo, hi);
    prt_lighting *l = NULL;
    prt_lighting_create(&l);
    prt_light bulb = {.type = PRT_LIGHT_POINT, .position = {0.5f * (lo[0] + hi[0]), lo[1] + 0.8f * (hi[1] - lo[1]), 0.5f * (lo[2] + hi[2])},
                      .intensity = {5, 5, 5}};
    prt_lighting_add(l, &bulb, NULL);
    bench_relight_time(ctx, t, l, 0);   /* builds the shadow-ray cache */
    const double r0 = bench_relight_time(ctx, t, l, 0), r1 = bench_relight_time(ctx, t, l, 1), r3 = bench_relight_time(ctx, t, l, 3);
    const double r3_exact = bench_relight_time_controls(ctx, t, l, (const int[2]){3, 0});   /* the default less its tail */
    const double per_bounce = (r3_exact - r0) / 3.0, nnz = (double)set->row_start[nv];
    const double bounce_rate = per_bounce > 0 ? nnz / per_bounce : 0, limit = bare_gather(set, nv, threads);
    prt_spectral_info info;
    prt_transfer_spectral_info(t, &info);

    printf("{\"mesh\": \"%s\", \"vertices\": %zu, \"threads\": %d, \"samples\": %s, \"functions\": %d, \"partitions\": %d,\n", mesh, nv, threads, samples,
           info.functions, info.partitions);
    printf(" \"bake_seconds\": %.2f, \"gather_seconds\": %.2f, \"gather_rays_per_second\": %.4g, \"raw_rays_per_second\": %.4g, \"bake_ray_ratio\": %.3f,\n",
           bake, gather_seconds, rays / gather_seconds, (double)raw_rays / raw_time, rays / gather_seconds / ((double)raw_rays / raw_time));
    printf(" \"coefficients_per_vertex\": %.1f, \"transfer_bytes\": %zu, \"basis_bytes\": %zu,\n", nnz / (double)nv, info.transfer_bytes, info.basis_bytes);
    printf(" \"relight_seconds\": {\"direct\": %.5f, \"one_bounce\": %.5f, \"three_bounces\": %.5f, \"three_bounces_no_tail\": %.5f},\n", r0, r1, r3,
           r3_exact);
    printf(" \"updates_per_second\": {\"direct\": %.1f, \"one_bounce\": %.1f, \"three_bounces\": %.1f},\n", 1 / r0, 1 / r1, 1 / r3);
    printf(" \"bounce_nonzeros_per_second\": %.4g, \"bare_gather_nonzeros_per_second\": %.4g, \"gather_ratio\": %.3f}\n", bounce_rate, limit,
           limit > 0 ? bounce_rate / limit : 0);
    fprintf(stderr,
            "bench: %s, %zu vertices, %d functions over %d partitions, %s rays per vertex, %d threads\n"
            "  bake %.1f s (gathering %.1f s: %.3g rays/s = %.0f%% of raw Embree closest hits, %.3g rays/s)\n"
            "  storage %.1f coefficients per vertex, %.2f MB transfer + %.2f MB basis\n"
            "  relight %.1f / %.1f / %.1f CPU updates/s (no drawing) for direct / 1 / 3 bounces (%.1f ms per bounce; the tail %.2f ms)\n"
            "  bounce gather %.3g non-zeros/s = %.0f%% of a bare sparse gather on the same matrix (%.3g)\n",
            mesh, nv, info.functions, info.partitions, samples, threads, bake, gather_seconds, rays / gather_seconds,
            100.0 * rays / gather_seconds / ((double)raw_rays / raw_time), (double)raw_rays / raw_time, nnz / (double)nv, info.transfer_bytes / 1e6,
            info.basis_bytes / 1e6, 1 / r0, 1 / r1, 1 / r3, 1000 * per_bounce, 1000 * (r3 - r3_exact), bounce_rate, limit > 0 ? 100 * bounce_rate / limit : 0, limit);
    free(dirs);
    free(origins);
    prt__raycaster_release(&rc);
    prt_lighting_release(l);
    prt_options_release(o);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
    return 0;
}
