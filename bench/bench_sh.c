/* Benchmark of SH PRT against limits measured in the same run:
 *   bake:    transfer-bake rays/s  vs  raw Embree rays/s on exactly the same rays
 *            (rtcOccluded16 for shadowed-only bakes, rtcIntersect16 when hits are needed)
 *   relight: bytes of transfer read per frame / frame time  vs  plain memory read bandwidth
 * Usage: prt_bench_sh [MESH] [--samples N] [--order N] [--threads N]
 * Without MESH it uses ../shared/data's bunny if present, else the procedural demo scene.
 * Prints JSON on stdout (with the process's peak resident memory) and a summary on stderr. */
#include "bench_common.h"

#include <omp.h>
#include <sys/resource.h>
#include <string.h>
#include <unistd.h>

typedef struct rays { float *dirs; int samples; float offset; } rays;

/* The bake's rays (every vertex, every direction above its normal) from the vertex offset along
 * its normal, as bench_raw_rays traces them. */
static double raw_embree(const prt_scene *s, const prt__raycaster *rc, const rays *r, bool intersect, int threads, uint64_t *count)
{
    const prt__mesh *m = &s->mesh;
    float *org = malloc(m->vertex_count * 3 * sizeof(float));
    if (!org) { *count = 0; return 1e30; }
    for (size_t v = 0; v < m->vertex_count * 3; ++v) org[v] = m->positions[v] + m->normals[v] * r->offset;
    double t = bench_raw_rays(m, rc, org, r->dirs, r->samples, 1, intersect, threads, count);
    free(org);
    return t;
}

int main(int argc, char **argv)
{
    const char *mesh = NULL;
    int samples = 1024, order = 5, threads = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--samples") && i + 1 < argc) samples = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--order") && i + 1 < argc) order = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (argv[i][0] != '-') mesh = argv[i];
        else { fprintf(stderr, "usage: prt_bench_sh [MESH] [--samples N] [--order N] [--threads N]\n"); return 2; }
    }
    prt_context *ctx = NULL;
    prt_scene *s = NULL;
    if (!bench_load(mesh, threads, &ctx, &s, &mesh)) return 1;
    threads = prt_context_threads(ctx);

    rays r = {malloc((size_t)samples * 3 * sizeof(float)), samples, prt__ray_offset(&s->mesh)};
    for (int j = 0; j < samples; ++j) {
        double u, v, d[3];
        prt__sobol2((uint32_t)j, 0, &u, &v);
        prt__sphere_dir(u, v, d);
        for (int c = 0; c < 3; ++c) r.dirs[j * 3 + c] = (float)d[c];
    }
    prt__raycaster rc;
    if (prt__raycaster_create(ctx, &s->mesh, &rc)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }

    uint64_t nrays = 0;
    raw_embree(s, &rc, &r, false, threads, &nrays);   /* warm-up */
    double raw_occ = raw_embree(s, &rc, &r, false, threads, &nrays);
    double raw_hit = raw_embree(s, &rc, &r, true, threads, &nrays);

    prt_bake_desc bd = {0};
    bd.order = order;
    bd.samples = samples;
    bd.kinds = PRT_TRANSFER_SHADOWED;
    prt_transfer *t = NULL;
    double t0 = prt__now();
    if (prt_bake_sh(ctx, s, &bd, &t)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    double bake_occ = prt__now() - t0;
    prt_transfer_release(t);
    bd.kinds = 0;   /* all kinds: hits recorded, bounces gathered */
    t0 = prt__now();
    if (prt_bake_sh(ctx, s, &bd, &t)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    double bake_all = prt__now() - t0;

    /* Relight: the three-channel inter-reflected set is the largest per frame. */
    const size_t nv = prt_transfer_vertex_count(t);
    float *rgb = malloc(nv * 3 * sizeof(float));
    prt_envmap *sky;
    prt_sh_light L;
    prt_sky_create(NULL, &sky);
    prt_envmap_project_sh(sky, order, &L);
    const int frames = 200;
    double relight[2], relight_z[2];
    const prt_transfer_kind kinds[2] = {PRT_TRANSFER_SHADOWED, PRT_TRANSFER_INTERREFLECTED};
    for (int k = 0; k < 2; ++k) {
        prt_relight_sh(ctx, t, kinds[k], &L, rgb);
        double best = 1e30;
        for (int f = 0; f < frames; ++f) {
            L.coeffs[0][0] += 1e-3f;   /* a new lighting each frame */
            double a = prt__now();
            prt_relight_sh(ctx, t, kinds[k], &L, rgb);
            double dt = prt__now() - a;
            if (dt < best) best = dt;
        }
        relight[k] = best;
    }
    /* The same lighting changes on clustered-PCA sets (64 clusters, 8 vectors on average). */
    prt_transfer *z = NULL;
    double t_comp = prt__now();
    if (prt_transfer_compress(ctx, t, NULL, &z)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    t_comp = prt__now() - t_comp;
    prt_compress_info zi;
    prt_transfer_compress_info(z, PRT_TRANSFER_INTERREFLECTED, &zi);
    for (int k = 0; k < 2; ++k) {
        double best = 1e30;
        for (int f = 0; f < frames; ++f) {
            L.coeffs[0][0] += 1e-3f;
            double a = prt__now();
            prt_relight_sh(ctx, z, kinds[k], &L, rgb);
            double dt = prt__now() - a;
            if (dt < best) best = dt;
        }
        relight_z[k] = best;
    }
    prt_transfer_release(z);

    /* Glossy matrices at the bench's order: a lighting change relights them into exit SH vectors;
     * a view change only re-evaluates those vectors in new directions (per pixel in the renderer;
     * here per vertex on the CPU). */
    const int gorder = order, gn = gorder * gorder;
    bd.order = gorder;
    bd.kinds = PRT_TRANSFER_GLOSSY_SHADOWED;
    prt_transfer *g = NULL, *gz = NULL;
    t0 = prt__now();
    if (prt_bake_sh(ctx, s, &bd, &g)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    double bake_glossy = prt__now() - t0;
    t0 = prt__now();
    if (prt_transfer_compress(ctx, g, NULL, &gz)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    double compress_glossy = prt__now() - t0;
    prt_compress_info gzi;
    prt_transfer_compress_info(gz, PRT_TRANSFER_GLOSSY_SHADOWED, &gzi);
    prt_brdf lobe;
    prt_brdf_parse("phong:32", &lobe);
    prt_sh_light gl;
    prt_envmap_project_sh(sky, gorder, &gl);
    float *exit = malloc(nv * 3 * (size_t)gn * sizeof(float)), *vrgb = malloc(nv * 3 * sizeof(float));
    double glossy_light[2];
    for (int k = 0; k < 2; ++k) {
        prt_transfer *which = k ? gz : g;
        prt_relight_sh_glossy(ctx, which, PRT_TRANSFER_GLOSSY_SHADOWED, &gl, &lobe, exit);
        double best = 1e30;
        for (int f = 0; f < frames / 4; ++f) {
            gl.coeffs[0][0] += 1e-3f;
            double a = prt__now();
            prt_relight_sh_glossy(ctx, which, PRT_TRANSFER_GLOSSY_SHADOWED, &gl, &lobe, exit);
            double dt = prt__now() - a;
            if (dt < best) best = dt;
        }
        glossy_light[k] = best;
    }
    const float *P = prt_transfer_positions(g), *N = prt_transfer_normals(g);
    double glossy_view = 1e30;
    for (int f = 0; f < frames / 4; ++f) {
        float eye[3] = {2.0f * cosf(0.01f * f), 1.0f, 2.0f * sinf(0.01f * f)};
        double a = prt__now();
#pragma omp parallel for schedule(static) num_threads(threads)
        for (size_t v = 0; v < nv; ++v) {
            float to_eye[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]};
            prt_glossy_eval(gorder, exit + v * 3 * gn, 1, N + v * 3, to_eye, vrgb + v * 3);
        }
        double dt = prt__now() - a;
        if (dt < glossy_view) glossy_view = dt;
    }
    const double bytes_glossy = (double)nv * gn * gn * 4;
    double bw_glossy = bench_read_bandwidth((size_t)bytes_glossy, threads);
    free(exit);
    free(vrgb);
    prt_transfer_release(gz);
    prt_transfer_release(g);
    const double n2 = (double)order * order;
    double bytes_sh = nv * (n2 * 4 + 12 + 12), bytes_ir = nv * (3 * n2 * 4 + 12);
    double bw_dram = bench_read_bandwidth((size_t)512 << 20, threads);
    double bw_sh = bench_read_bandwidth((size_t)bytes_sh, threads), bw_ir = bench_read_bandwidth((size_t)bytes_ir, threads);

    double occ_rate = nrays / raw_occ, hit_rate = nrays / raw_hit;
    double bake_occ_rate = nrays / bake_occ, bake_all_rate = nrays / bake_all;
    printf("{\n  \"mesh\": \"%s\", \"vertices\": %zu, \"triangles\": %zu, \"threads\": %d, \"order\": %d, \"samples\": %d,\n", mesh, nv,
           prt_transfer_triangle_count(t), threads, order, samples);
    printf("  \"rays\": %llu,\n", (unsigned long long)nrays);
    printf("  \"raw_embree_occluded_rays_per_s\": %.0f, \"raw_embree_intersect_rays_per_s\": %.0f,\n", occ_rate, hit_rate);
    printf("  \"bake_shadowed_s\": %.3f, \"bake_shadowed_rays_per_s\": %.0f, \"bake_shadowed_ratio\": %.3f,\n", bake_occ, bake_occ_rate,
           bake_occ_rate / occ_rate);
    printf("  \"bake_all_kinds_s\": %.3f, \"bake_all_kinds_rays_per_s\": %.0f, \"bake_all_kinds_ratio_vs_intersect\": %.3f,\n", bake_all,
           bake_all_rate, bake_all_rate / hit_rate);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("  \"read_bandwidth_dram_GBps\": %.2f, \"peak_memory_MiB\": %.1f,\n", bw_dram / 1e9, ru.ru_maxrss / 1024.0);
    printf("  \"relight_shadowed_ms\": %.4f, \"relight_shadowed_GBps\": %.2f, \"read_same_bytes_shadowed_GBps\": %.2f, \"relight_shadowed_ratio\": %.3f,\n",
           relight[0] * 1e3, bytes_sh / relight[0] / 1e9, bw_sh / 1e9, bytes_sh / relight[0] / bw_sh);
    printf("  \"compress_s\": %.3f, \"cpca_interreflected_relative_error\": %.4f, \"cpca_interreflected_bytes_per_vertex\": %.1f,\n"
           "  \"relight_cpca_shadowed_ms\": %.4f, \"relight_cpca_interreflected_ms\": %.4f,\n",
           t_comp, zi.relative_error, (double)zi.bytes / (double)nv, relight_z[0] * 1e3, relight_z[1] * 1e3);
    printf("  \"relight_interreflected_ms\": %.4f, \"relight_interreflected_GBps\": %.2f, \"read_same_bytes_interreflected_GBps\": %.2f, \"relight_interreflected_ratio\": %.3f,\n",
           relight[1] * 1e3, bytes_ir / relight[1] / 1e9, bw_ir / 1e9, bytes_ir / relight[1] / bw_ir);
    printf("  \"glossy_order\": %d, \"bake_glossy_shadowed_s\": %.3f, \"compress_glossy_s\": %.3f, \"cpca_glossy_relative_error\": %.4f,\n"
           "  \"cpca_glossy_bytes_per_vertex\": %.1f, \"glossy_bytes_per_vertex\": %.1f,\n"
           "  \"glossy_light_change_ms\": %.4f, \"glossy_light_change_ratio_vs_read\": %.3f, \"cpca_glossy_light_change_ms\": %.4f,\n"
           "  \"glossy_view_change_ms\": %.4f, \"read_same_bytes_glossy_GBps\": %.2f\n}\n",
           gorder, bake_glossy, compress_glossy, gzi.relative_error, (double)gzi.bytes / (double)nv, (double)gn * gn * 4,
           glossy_light[0] * 1e3, bytes_glossy / glossy_light[0] / bw_glossy, glossy_light[1] * 1e3, glossy_view * 1e3, bw_glossy / 1e9);
    fprintf(stderr,
            "bench: %s, %zu vertices, %d threads, order %d, %d samples\n"
            "  bake shadowed      %.2f s  %.2f Mrays/s  = %.2f x raw Embree occlusion (%.2f Mrays/s)\n"
            "  bake all kinds     %.2f s  %.2f Mrays/s  = %.2f x raw Embree intersection (%.2f Mrays/s)\n"
            "  relight shadowed   %.3f ms  %.1f GB/s = %.2f x a plain read of the same bytes (%.1f GB/s)\n"
            "  relight interrefl. %.3f ms  %.1f GB/s = %.2f x a plain read of the same bytes (%.1f GB/s)\n"
            "  DRAM read bandwidth %.1f GB/s\n"
            "  clustered PCA (64 x 8): relight shadowed %.3f ms, inter-reflected %.3f ms (uncompressed above); %.1f B/vertex, error %.4f\n"
            "  glossy order %d: bake %.2f s; light change %.3f ms (%.2f x a read of the matrices), clustered PCA %.3f ms\n"
            "                  (%.0f instead of %.0f B/vertex, error %.4f, compressed in %.1f s); view change %.3f ms\n",
            mesh, nv, threads, order, samples, bake_occ, bake_occ_rate / 1e6, bake_occ_rate / occ_rate, occ_rate / 1e6, bake_all,
            bake_all_rate / 1e6, bake_all_rate / hit_rate, hit_rate / 1e6, relight[0] * 1e3, bytes_sh / relight[0] / 1e9,
            bytes_sh / relight[0] / bw_sh, bw_sh / 1e9, relight[1] * 1e3, bytes_ir / relight[1] / 1e9, bytes_ir / relight[1] / bw_ir,
            bw_ir / 1e9, bw_dram / 1e9, relight_z[0] * 1e3, relight_z[1] * 1e3, (double)zi.bytes / (double)nv, zi.relative_error,
            gorder, bake_glossy, glossy_light[0] * 1e3, bytes_glossy / glossy_light[0] / bw_glossy, glossy_light[1] * 1e3,
            (double)gzi.bytes / (double)nv, (double)gn * gn * 4, gzi.relative_error, compress_glossy, glossy_view * 1e3);
    free(rgb);
    free(r.dirs);
    prt_envmap_release(sky);
    prt__raycaster_release(&rc);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
    return 0;
}
