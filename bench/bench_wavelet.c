/* Benchmark of the wavelet method (Wang, Tran & Luebke 2005) on the bunny over a ground plane,
 * against limits measured in the same run:
 *   bake:    wavelet-bake rays/s  vs  raw Embree rtcOccluded16 on the same cube-map rays
 *   light:   relight non-zeros/s and bytes/s  vs  a plain read of the same bytes
 *   view:    the view factor per vertex (time only; it is a few map lookups per vertex)
 * and the storage per vertex. The paper's figures (a 2.4 GHz Pentium 4): bunny (36k vertices),
 * 1-term direct bake 5.6 min (GPU-assisted), 4-term 14 min, light change 12 fps 1-term / 4.8 fps
 * 4-term on the CPU.
 * Usage: prt_bench_wavelet [MESH] [--terms K] [--supersample S] [--bounces B] [--threads N]
 * Without MESH it uses ../shared/data's bunny if present, else the procedural demo scene. Prints
 * JSON on stdout and a summary on stderr. */
#include "bench_common.h"
#include "core/cubemap.h"
#include "methods/wavelet/wavelet.h"

#include <immintrin.h>
#include <string.h>
#include <unistd.h>

/* The limit of the sparse inner products with these indices: fetch each non-zero's RGB(0) light
 * texel and add it up, 16 bytes per load as the relight kernel does, without decoding any
 * coefficient (best of several passes). */
static double raw_gather(const uint16_t *index, size_t count, int threads)
{
    float *table = malloc((size_t)PRT_WAVELET_DIM * 4 * sizeof(float));
    for (int i = 0; i < PRT_WAVELET_DIM * 4; ++i) table[i] = (float)(i & 255);
    double best = 1e30, sink = 0;
    for (int pass = 0; pass < 10; ++pass) {
        double t0 = prt__now();
        float s = 0;
#pragma omp parallel num_threads(threads) reduction(+ : s)
        {
            __m128 a = _mm_setzero_ps(), b = _mm_setzero_ps();
#pragma omp for schedule(static)
            for (size_t i = 0; i < count / 2; ++i) {
                a = _mm_add_ps(a, _mm_loadu_ps(table + (size_t)index[2 * i] * 4));
                b = _mm_add_ps(b, _mm_loadu_ps(table + (size_t)index[2 * i + 1] * 4));
            }
            float o[4];
            _mm_storeu_ps(o, _mm_add_ps(a, b));
            s += o[0] + o[1] + o[2];
        }
        double dt = prt__now() - t0;
        sink += s;
        if (dt < best) best = dt;
    }
    free(table);
    if (sink == 42.0) fputs("", stderr);
    return (double)count / best;
}

/* Seconds spent in the direct pass and in everything after it (bounce passes and sums), from the
 * bake's progress stages. */
typedef struct stage_clock { double start, direct_end; bool in_direct; } stage_clock;

static int progress(void *user, const char *stage, uint64_t done, uint64_t total)
{
    stage_clock *clk = user;
    const bool direct = !strcmp(stage, "wavelet direct");
    if (clk->in_direct && !direct && !clk->direct_end) clk->direct_end = prt__now();
    if (direct && done == total) clk->direct_end = prt__now();
    clk->in_direct = direct;
    if (isatty(2)) fprintf(stderr, "\r  %s %3.0f%%   ", stage, total ? 100.0 * (double)done / (double)total : 100.0);
    return 0;
}

int main(int argc, char **argv)
{
    const char *mesh = NULL;
    int terms = 4, supersample = 2, bounces = 0, threads = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--terms") && i + 1 < argc) terms = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--supersample") && i + 1 < argc) supersample = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--bounces") && i + 1 < argc) bounces = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (argv[i][0] != '-') mesh = argv[i];
        else { fprintf(stderr, "usage: prt_bench_wavelet [MESH] [--terms K] [--supersample S] [--bounces B] [--threads N]\n"); return 2; }
    }
    static const char *probe = "../shared/data/envmaps/probulator_ict/grace.hdr";
    prt_context *ctx = NULL;
    prt_scene *s = NULL;
    if (!bench_load(mesh, threads, &ctx, &s, &mesh)) return 1;
    threads = prt_context_threads(ctx);
    /* A glossy object on a diffuse ground plane three times its width (the paper's setting). */
    prt__mesh *m = &s->mesh;
    const size_t object_nv = m->vertex_count;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < object_nv; ++v)
        for (int c = 0; c < 3; ++c) { lo[c] = fminf(lo[c], m->positions[v * 3 + c]); hi[c] = fmaxf(hi[c], m->positions[v * 3 + c]); }
    /* The plane's size and centre place the eye below. */
    const float size = 3.0f * fmaxf(hi[0] - lo[0], hi[2] - lo[2]), cx = 0.5f * (lo[0] + hi[0]), cz = 0.5f * (lo[2] + hi[2]);
    if (!bench_ground_plane(m, object_nv, 100)) {
        fprintf(stderr, "bench: %s\n", prt_last_error());
        return 1;
    }
    prt_brdf phong;
    prt_brdf_parse("phong:50:0.4:0.5", &phong);   /* the paper's Phong, exponent 50 */
    if (prt_scene_set_brdf(s, 0, object_nv, &phong)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    const size_t nv = m->vertex_count;

    /* Raw Embree on every 16th vertex's cube-map rays. */
    prt__raycaster rc;
    float *origins = NULL;
    float *dirs = malloc((size_t)PRT_WAVELET_DIM * 3 * sizeof(float));
    for (int i = 0; i < PRT_WAVELET_DIM; ++i) prt_wavelet_texel(i, dirs + (size_t)i * 3, NULL);
    if (prt__raycaster_create(ctx, m, &rc) || prt__vertex_origins(m, prt__ray_offset(m), &origins)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    uint64_t raw_rays = 0;
    bench_raw_rays(m, &rc, origins, dirs, PRT_WAVELET_DIM, 64, false, threads, &raw_rays);   /* warm-up */
    /* Every 16th vertex, the direct pass's texel-centre directions. */
    double raw_t = bench_raw_rays(m, &rc, origins, dirs, PRT_WAVELET_DIM, 16, false, threads, &raw_rays);
    const double raw_rate = (double)raw_rays / raw_t;
    prt__raycaster_release(&rc);
    free(origins);
    free(dirs);

    fprintf(stderr, "bench: %s + ground plane, %zu vertices, K = %d, %dx%d rays per texel, %d bounce(s), %d threads\n", mesh, nv, terms, supersample,
            supersample, bounces, threads);
    stage_clock clk = {0};
    prt_wavelet_bake_desc bd = {.terms = terms, .supersample = supersample, .bounces = bounces, .progress = progress, .progress_user = &clk};
    prt_transfer *t = NULL;
    double t0 = prt__now();
    clk.start = t0;
    if (prt_bake_wavelet(ctx, s, &bd, &t)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    const double bake = prt__now() - t0, direct_s = (clk.direct_end ? clk.direct_end : prt__now()) - t0, bounce_s = bake - direct_s;
    if (isatty(2)) fputs("\r", stderr);
    /* Rays the bake's direct pass traced: texels above each vertex's normal, times supersampling. */
    uint64_t bake_rays = 0;
    {
        const int n = 64 * supersample;
        for (size_t v = 0; v < nv; ++v)
            for (int f = 0; f < 6; ++f)
                for (int y = 0; y < n; ++y)
                    for (int x = 0; x < n; ++x) {
                        float d[3];
                        prt__cube_dir(f, 2.0f * (x + 0.5f) / n - 1.0f, 2.0f * (y + 0.5f) / n - 1.0f, d);
                        bake_rays += prt__v3_dot(d, m->normals + v * 3) > 0;
                    }
    }

    /* Lighting: the probe if present (else the sky), projected and relit many times. */
    prt_envmap *env = NULL;
    if (access(probe, R_OK) != 0 || prt_envmap_load(probe, PRT_ENV_AUTO, &env)) {
        prt_sky_desc sky = {0};
        prt_sky_create(&sky, &env);
    }
    prt_wavelet_info wi;
    prt_transfer_wavelet_info(t, &wi);
    float *kvec = malloc(nv * (size_t)wi.terms * 3 * sizeof(float)), *rgb = malloc(nv * 3 * sizeof(float));
    prt_wavelet_light *wl = NULL;
    double light_best = 1e30, relight_best = 1e30, shade_best = 1e30;
    for (int rep = 0; rep < 10; ++rep) {
        double rot[9];
        prt_rotation_from_euler_deg(rep * 17.0, 0, 0, rot);
        prt_wavelet_light_desc ld = {0};
        memcpy(ld.rotation, rot, sizeof rot);
        double a = prt__now();
        prt_wavelet_light_release(wl);
        if (prt_wavelet_light_create(ctx, env, &ld, &wl)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
        double b = prt__now();
        prt_relight_wavelet(ctx, t, wl, kvec);
        double c = prt__now();
        prt_wavelet_shade(ctx, t, kvec, (float[3]){cx + size, hi[1] + size * 0.5f, cz + size}, rgb);
        double d = prt__now();
        light_best = fmin(light_best, b - a);
        relight_best = fmin(relight_best, c - b);
        shade_best = fmin(shade_best, d - c);
    }
    const double nonzeros = (double)wi.vectors * wi.coefficients, bytes = (double)wi.bytes;
    const double bw = bench_read_bandwidth((size_t)bytes, threads), gather = raw_gather(prt__wavelet(t)->store.index, (size_t)nonzeros, threads);
    const double bake_rate = (double)bake_rays / direct_s;
    printf("{\n  \"mesh\": \"%s\", \"vertices\": %zu, \"object_vertices\": %zu, \"terms\": %d, \"supersample\": %d, \"bounces\": %d, \"threads\": %d,\n", mesh, nv,
           object_nv, terms, supersample, bounces, threads);
    printf("  \"bake_s\": %.3f, \"direct_s\": %.3f, \"bounce_s\": %.3f, \"direct_rays\": %llu, \"direct_rays_per_s\": %.0f,\n", bake, direct_s,
           bounce_s, (unsigned long long)bake_rays, bake_rate);
    printf("  \"raw_embree_occluded_rays_per_s\": %.0f, \"direct_vs_raw\": %.3f,\n", raw_rate, bake_rate / raw_rate);
    printf("  \"vectors\": %zu, \"coefficients\": %d, \"bits\": %d, \"bytes\": %.0f, \"bytes_per_vertex\": %.1f,\n", wi.vectors, wi.coefficients, wi.bits,
           bytes, bytes / (double)nv);
    printf("  \"light_project_ms\": %.3f, \"light_relight_ms\": %.3f, \"view_ms\": %.3f,\n", light_best * 1e3, relight_best * 1e3, shade_best * 1e3);
    printf("  \"relight_nonzeros_per_s\": %.0f, \"raw_gather_nonzeros_per_s\": %.0f, \"relight_vs_gather\": %.3f,\n", nonzeros / relight_best, gather,
           nonzeros / relight_best / gather);
    printf("  \"relight_bytes_per_s\": %.0f, \"read_bandwidth_bytes_per_s\": %.0f, \"relight_vs_read\": %.3f\n}\n", bytes / relight_best, bw,
           bytes / relight_best / bw);
    fprintf(stderr,
            "  bake              %.1f s: direct pass %.1f s, %.2f Mrays/s = %.2f x raw Embree occlusion on the same rays (%.2f Mrays/s);\n"
            "                    interreflection passes %.1f s\n"
            "  storage           %.0f bytes/vertex (%zu vectors x %d coefficients, %d-bit)\n"
            "  light change      %.1f ms project + %.1f ms relight (%.2f G non-zeros/s = %.2f x fetching the same light texels,\n"
            "                    %.2f x a plain read of the same %.1f MB)\n"
            "  view change       %.2f ms\n",
            bake, direct_s, bake_rate / 1e6, bake_rate / raw_rate, raw_rate / 1e6, bounce_s, bytes / (double)nv, wi.vectors, wi.coefficients, wi.bits, light_best * 1e3,
            relight_best * 1e3, nonzeros / relight_best / 1e9, nonzeros / relight_best / gather, bytes / relight_best / bw, bytes / 1e6, shade_best * 1e3);
    free(kvec); free(rgb);
    prt_wavelet_light_release(wl);
    prt_envmap_release(env);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
    return 0;
}
