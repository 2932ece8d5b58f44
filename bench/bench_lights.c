/* Benchmark of relighting with local lights through the method table, and of the reference path
 * tracer under local lights, each against a limit measured in the same run:
 *   relight:   for every method of the table and 1, 8 and 64 lights of each type it relights,
 *              the time of prt_relight  vs  a plain read of the method's transfer bytes (what a
 *              relight cannot beat); types a method refuses are reported as refused
 *   reference: paths/s with 8 point lights  vs  raw Embree rays/s on the same scene (a path of
 *              depth d traces about 2 d rays, so the ratio says how many rays a path costs)
 * Usage: prt_bench_lights [MESH] [--threads N]. Without MESH it uses ../shared/data's bunny if
 * present, else the procedural demo scene. JSON on stdout, a summary on stderr. */
#include "bench_common.h"

#include <string.h>
#include <unistd.h>

static prt_light make_light(prt_light_type type, int i, int n, const float lo[3], const float hi[3])
{
    /* Lights on a ring above the scene, aimed at its centre. */
    const float cx = 0.5f * (lo[0] + hi[0]), cy = 0.5f * (lo[1] + hi[1]), cz = 0.5f * (lo[2] + hi[2]);
    const float size = fmaxf(hi[0] - lo[0], fmaxf(hi[1] - lo[1], hi[2] - lo[2])), a = 6.2831853f * (float)i / (float)n;
    prt_light l;
    memset(&l, 0, sizeof l);
    l.type = type;
    l.position[0] = cx + size * cosf(a);
    l.position[1] = hi[1] + 0.5f * size;
    l.position[2] = cz + size * sinf(a);
    l.direction[0] = type == PRT_LIGHT_DIRECTIONAL ? cosf(a) : cx - l.position[0];
    l.direction[1] = type == PRT_LIGHT_DIRECTIONAL ? 1.0f : cy - l.position[1];
    l.direction[2] = type == PRT_LIGHT_DIRECTIONAL ? sinf(a) : cz - l.position[2];
    for (int c = 0; c < 3; ++c) l.intensity[c] = l.irradiance[c] = l.radiance[c] = 1.0f / (float)n;
    l.angle_deg = 40.0f;
    l.radius = 0.05f * size;
    prt_light_validate(&l);
    return l;
}

int main(int argc, char **argv)
{
    const char *mesh = NULL;
    int threads = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (argv[i][0] != '-') mesh = argv[i];
        else { fprintf(stderr, "usage: prt_bench_lights [MESH] [--threads N]\n"); return 2; }
    }
    prt_context *ctx = NULL;
    prt_scene *s = NULL;
    if (!bench_load(mesh, threads, &ctx, &s, &mesh)) return 1;
    threads = prt_context_threads(ctx);
    float lo[3], hi[3];
    prt_scene_bounds(s, lo, hi);
    printf("{\"mesh\": \"%s\", \"vertices\": %zu, \"threads\": %d, \"relight\": [", mesh, prt_scene_vertex_count(s), threads);
    static const prt_light_type types[4] = {PRT_LIGHT_POINT, PRT_LIGHT_SPOT, PRT_LIGHT_DIRECTIONAL, PRT_LIGHT_SPHERE};
    static const int counts[3] = {1, 8, 64};
    bool first = true;
    for (int mi = 0; mi < prt_method_count(); ++mi) {
        const prt_method *m = prt_method_at(mi);
        /* Small bakes: the relight cost depends on the storage, not on the bake's quality. */
        prt_options *o = NULL;
        prt_options_create(m, &o);
        if (prt_method_option(m, "samples")) prt_options_set(o, "samples", "64");
        if (prt_method_option(m, "kinds")) prt_options_set(o, "kinds", "shadowed");   /* one set: the bytes a relight reads */
        if (prt_method_option(m, "supersample")) prt_options_set(o, "supersample", "1");
        prt_transfer *t = NULL;
        double t0 = prt__now();
        if (prt_bake(ctx, s, m, o, NULL, &t)) { fprintf(stderr, "bench: %s: %s\n", prt_method_name(m), prt_last_error()); return 1; }
        const double bake = prt__now() - t0;
        prt_transfer_info info;
        prt_transfer_get_info(t, &info);
        const double bandwidth = bench_read_bandwidth(info.transfer_bytes, threads), limit = (double)info.transfer_bytes / bandwidth;
        fprintf(stderr, "bench: %s: baked in %.1f s, %.1f MiB; a plain read of it takes %.3f ms\n", prt_method_name(m), bake,
                info.transfer_bytes / 1048576.0, limit * 1e3);
        for (int ti = 0; ti < 4; ++ti)
            for (int ci = 0; ci < 3; ++ci) {
                prt_lighting *l = NULL;
                prt_lighting_create(&l);
                for (int i = 0; i < counts[ci]; ++i) {
                    prt_light x = make_light(types[ti], i, counts[ci], lo, hi);
                    prt_lighting_add(l, &x, NULL);
                }
                printf("%s\n  {\"method\": \"%s\", \"light\": \"%s\", \"count\": %d, ", first ? "" : ",", prt_method_name(m), prt_light_type_name(types[ti]),
                       counts[ci]);
                first = false;
                if (prt_method_check_lighting(m, prt_light_type_bit(types[ti]))) {
                    printf("\"refused\": true}");
                    if (ci == 0) fprintf(stderr, "bench: %s refuses %s lights\n", prt_method_name(m), prt_light_type_name(types[ti]));
                    prt_lighting_release(l);
                    continue;
                }
                double best = 1e30;
                for (int rep = 0; rep < 10; ++rep) {
                    prt_relit r;
                    double a = prt__now();
                    if (prt_relight(ctx, t, l, NULL, &r)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
                    best = fmin(best, prt__now() - a);
                    prt_relit_free(&r);
                }
                printf("\"relight_ms\": %.3f, \"read_limit_ms\": %.3f, \"ratio_to_limit\": %.3f}", best * 1e3, limit * 1e3, limit / best);
                fprintf(stderr, "bench: %s, %2d %-11s lights: %.2f ms (%.2fx a plain read of the transfer)\n", prt_method_name(m), counts[ci],
                        prt_light_type_name(types[ti]), best * 1e3, limit / best);
                prt_lighting_release(l);
            }
        prt_transfer_release(t);
        prt_options_release(o);
    }
    /* The reference path tracer with 8 point lights against raw Embree rays from the vertices. */
    prt_lighting *l = NULL;
    prt_lighting_create(&l);
    for (int i = 0; i < 8; ++i) {
        prt_light x = make_light(PRT_LIGHT_POINT, i, 8, lo, hi);
        prt_lighting_add(l, &x, NULL);
    }
    prt_reference_desc rd = {0};
    rd.samples = 16;
    rd.lighting = l;
    prt_reference_vertices res;
    double t0 = prt__now();
    if (prt_reference_trace_vertices(ctx, s, NULL, &rd, &res)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    const double pt = prt__now() - t0, paths = (double)res.vertex_count * rd.samples;
    prt_reference_vertices_free(&res);
    prt__raycaster rc;
    float *org = NULL, *dirs = malloc(256 * 3 * sizeof(float));
    prt__raycaster_create(ctx, &s->mesh, &rc);
    prt__vertex_origins(&s->mesh, prt__ray_offset(&s->mesh), &org);
    for (int j = 0; j < 256; ++j) {
        double u, v, d[3];
        prt__sobol2((uint32_t)j, 0, &u, &v);
        prt__sphere_dir(u, v, d);
        for (int c = 0; c < 3; ++c) dirs[j * 3 + c] = (float)d[c];
    }
    uint64_t rays = 0;
    const double raw = bench_raw_rays(&s->mesh, &rc, org, dirs, 256, 1, true, threads, &rays);
    const double rays_s = (double)rays / raw, paths_s = paths / pt;
    printf("\n], \"reference\": {\"lights\": 8, \"paths_per_s\": %.0f, \"raw_embree_rays_per_s\": %.0f, \"rays_per_path_budget\": %.2f}}\n", paths_s, rays_s,
           rays_s / paths_s);
    fprintf(stderr, "bench: reference with 8 point lights: %.2f M paths/s; raw Embree %.2f M rays/s (a path costs as much as %.1f raw rays)\n",
            paths_s * 1e-6, rays_s * 1e-6, rays_s / paths_s);
    free(org);
    free(dirs);
    prt__raycaster_release(&rc);
    prt_lighting_release(l);
    prt_scene_release(s);
    prt_context_release(ctx);
    return 0;
}
