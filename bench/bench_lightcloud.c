/* Benchmark of the light cloud (Kristensen, Akenine-Moller & Jensen 2005):
 *   bake:    seconds per stage (the spectral transfer, the cloud lights' solutions, clustering
 *            and compression per zone) and the process's peak memory;
 *   run time: a light dragged through the scene in 200 steps, per-frame update time (weights,
 *            then every zone's CPCA evaluated; direct light left to the renderer as when
 *            drawing) and frames per second; the evaluation's bytes/s  vs  a plain read of the
 *            same number of bytes measured in the same run.
 * The paper's Table 1 (one 3.4 GHz Pentium 4 for Cornell and Window; Sponza on 32 PCs):
 * Cornell 4k triangles, 216 -> 53 lights, 1.5 h + 1.0 h, 190 fps; Sponza 114k triangles, 247
 * zones, 384 -> 127 lights, 4.5 h + 2 h, 30 fps.
 *   glossy:  with glossy vertices, the glossy part of the update alone (the zones' glossy blocks
 *            evaluated: the evaluation with exit SH minus without) against a plain read of the
 *            glossy blocks' bytes in the same run, and the exit SH evaluated towards an eye at
 *            every glossy vertex (what prt relight --eye does per vertex, the renderer per pixel).
 * With --resimulate it also bakes the same cloud uncompressed and a spectral transfer, and
 * measures how far each merged light's averaged response (what prt stores) is from a solution
 * computed at the merged light's position (the paper's alternative).
 * Usage: prt_bench_lightcloud [MESH] [--grid NX,NY,NZ] [--max-edge E] [--zone-vertices N]
 *                             [--samples N] [--threads N] [--resimulate] [--set NAME=VALUE]...
 *                             [--winding-keep] [--glossy-reference PATHS]
 * --glossy-reference: three point lights in the upper half of the scene, per-vertex radiance seen
 * from the eye (prt_relit_shade; all light as drawn, the lights' glossy highlights with it)
 * against the path tracer's towards the same eye: relative L2 over
 * the glossy vertices facing the eye and over the others, all light and indirect light.
 * (--set: any other bake option, e.g. --set merge-distance=0 --set vectors=48; MESH may be a JSON
 * scene: bench/lightcloud_glossy_bunny.sh benches the paper's glossy bunny so.)
 * Without MESH: ../shared/data's Cornell box (max edge 0.1) when present, else the procedural
 * room. Prints JSON on stdout and a summary on stderr. */
#include "bench_common.h"
#include "methods/lightcloud/lightcloud.h"

#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

typedef struct stages { double start[8], end[8]; char name[8][48]; int count; } stages;

static int progress(void *user, const char *stage, uint64_t done, uint64_t total)
{
    stages *k = user;
    int i = 0;
    while (i < k->count && strcmp(k->name[i], stage)) ++i;
    if (i == k->count && k->count < 8) {
        snprintf(k->name[k->count], sizeof k->name[0], "%s", stage);
        k->start[k->count++] = prt__now();
    }
    if (i < 8) k->end[i] = prt__now();
    if (isatty(2)) fprintf(stderr, "\r  %s %3.0f%%   ", stage, total ? 100.0 * (double)done / (double)total : 100.0);
    return 0;
}

static double stage_seconds(const stages *k, const char *prefix)
{
    double s = 0;
    for (int i = 0; i < k->count; ++i)
        if (!strncmp(k->name[i], prefix, strlen(prefix))) s += k->end[i] - k->start[i];
    return s;
}

static size_t block_bytes(const prt__lightcloud_block *b)
{
    if (!b->vertices) return 0;
    if (b->raw) return (size_t)b->vertices * b->dim * 4;
    return ((size_t)b->cpca->clusters * b->dim + b->cpca->vectors_total * b->dim + b->cpca->weights_total + b->vertices) * 4;
}

int main(int argc, char **argv)
{
    const char *mesh = NULL, *grid = NULL, *zone_vertices = NULL, *samples = "1024";
    float max_edge = -1;
    int threads = 0;
    bool resimulate = false;
    const char *sets[16];
    bool winding_keep = false;   /* a room seen from inside (closed, faces inwards) as it is */
    int glossy_reference = 0;    /* paths per vertex of the glossy check against the path tracer; 0: none */
    int set_count = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--resimulate")) { resimulate = true; continue; }
        if (!strcmp(argv[i], "--winding-keep")) { winding_keep = true; continue; }
        if (!strcmp(argv[i], "--glossy-reference") && i + 1 < argc) { glossy_reference = atoi(argv[++i]); continue; }
        if (!strcmp(argv[i], "--set") && i + 1 < argc && set_count < 16 && strchr(argv[i + 1], '=')) { sets[set_count++] = argv[++i]; continue; }
        if (!strcmp(argv[i], "--grid") && i + 1 < argc) grid = argv[++i];
        else if (!strcmp(argv[i], "--max-edge") && i + 1 < argc) max_edge = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--zone-vertices") && i + 1 < argc) zone_vertices = argv[++i];
        else if (!strcmp(argv[i], "--samples") && i + 1 < argc) samples = argv[++i];
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (argv[i][0] != '-' && !mesh) mesh = argv[i];
        else {
            fprintf(stderr, "usage: prt_bench_lightcloud [MESH] [--grid NX,NY,NZ] [--max-edge E] [--zone-vertices N] [--samples N] [--threads N] "
                            "[--resimulate] [--set NAME=VALUE]... [--winding-keep] [--glossy-reference PATHS]\n");
            return 2;
        }
    }
    static const char *cornell = "../shared/data/meshes/cornell_box/CornellBox-Original.obj";
    static char room[] = "/tmp/prt_bench_lc_room.obj";
    if (!mesh) {
        if (access(cornell, R_OK) == 0) {
            mesh = cornell;
            if (max_edge < 0) max_edge = 0.1f;
        } else {
            fprintf(stderr, "bench: %s not found; using the procedural room\n", cornell);
            if (prt_demo_room_write(room, 0.125f)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
            mesh = room;
        }
    }
    prt_context *ctx = NULL;
    prt_scene *s = NULL;
    prt_scene_desc sd = {0};
    if (max_edge > 0) sd.max_edge = max_edge;
    if (winding_keep) sd.winding = PRT_WINDING_KEEP;
    if (prt_context_create(&(prt_context_desc){.threads = threads}, &ctx) || prt_scene_load(ctx, mesh, &sd, &s)) {
        fprintf(stderr, "bench: %s\n", prt_last_error());
        return 1;
    }
    threads = prt__threads(ctx);
    const prt_method *m = prt_method_find("lightcloud");
    prt_options *o = NULL;
    prt_options_create(m, &o);
    if (prt_options_set(o, "samples", samples) || (grid && prt_options_set(o, "cloud-grid", grid)) ||
        (zone_vertices && prt_options_set(o, "zone-vertices", zone_vertices))) {
        fprintf(stderr, "bench: %s\n", prt_last_error());
        return 1;
    }
    for (int i = 0; i < set_count; ++i) {
        char name[64];
        const char *eq = strchr(sets[i], '=');
        snprintf(name, sizeof name, "%.*s", (int)(eq - sets[i]), sets[i]);
        if (prt_options_set(o, name, eq + 1)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    }
    stages k = {0};
    prt_bake_run_desc run = {.progress = progress, .progress_user = &k};
    prt_transfer *t = NULL;
    const double t0 = prt__now();
    if (prt_bake(ctx, s, m, o, &run, &t)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    const double bake = prt__now() - t0;
    if (isatty(2)) fputc('\n', stderr);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    const double peak_mb = ru.ru_maxrss / 1024.0;
    const prt__lightcloud_set *set = t->state;
    const size_t nv = t->mesh.vertex_count;
    double merged = 0;
    size_t bytes = 0, glossy_bytes = 0;
    for (uint32_t z = 0; z < set->zone_count; ++z) {
        merged += set->zones[z].lights;
        bytes += block_bytes(&set->zones[z].diffuse) + block_bytes(&set->zones[z].glossy);
        glossy_bytes += block_bytes(&set->zones[z].glossy);
    }
    merged /= set->zone_count;

    /* A light dragged across the scene at 60% of its height, from one end of the cloud's box to the other. */
    float lo[3], hi[3];
    prt_scene_bounds(s, lo, hi);
    const int frames = 200;
    float *w = malloc(set->cloud_count * 3 * sizeof(float)), *rgb = malloc(nv * 3 * sizeof(float));
    float *sh = set->glossy_count ? malloc(nv * 48 * sizeof(float)) : NULL;
    double update = 0, weights = 0, eval = 0, eval_diffuse = 0, shade = 0;
    /* The eye for the glossy shading: above the scene's centre, in front of it. */
    const float eye[3] = {0.5f * (lo[0] + hi[0]), lo[1] + 0.6f * (hi[1] - lo[1]), lo[2] + 0.9f * (hi[2] - lo[2])};
    float sink = 0;
    for (int f = 0; f < frames; ++f) {
        const float u = (f + 0.5f) / frames;
        prt_lighting *l = NULL;
        prt_lighting_create(&l);
        prt_light bulb = {.type = PRT_LIGHT_POINT,
                          .position = {lo[0] + (0.15f + 0.7f * u) * (hi[0] - lo[0]), lo[1] + 0.6f * (hi[1] - lo[1]), lo[2] + (0.3f + 0.4f * u) * (hi[2] - lo[2])},
                          .intensity = {5, 5, 5}};
        prt_lighting_add(l, &bulb, NULL);
        prt_lighting_set_emission(l, 0);
        prt_relit r;
        const double a = prt__now();
        if (prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1}, &r)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
        const double b = prt__now();
        prt_relit_free(&r);
        /* The two halves of the cloud's own work, timed alone. */
        prt__lightcloud_weights(ctx, t, l, 8, w);
        const double c = prt__now();
        memset(rgb, 0, nv * 3 * sizeof(float));
        if (sh) memset(sh, 0, nv * 48 * sizeof(float));
        prt__lightcloud_eval(ctx, t, w, rgb, sh);
        const double d = prt__now();
        double e = d, g = d, h = d;
        if (sh) {
            memset(rgb, 0, nv * 3 * sizeof(float));
            e = prt__now();
            prt__lightcloud_eval(ctx, t, w, rgb, NULL);
            g = prt__now();
            /* The exit SH towards the eye at every glossy vertex. */
            const float *P = t->mesh.positions, *N = t->mesh.normals;
            for (size_t v = 0; v < nv; ++v) {
                if (set->glossy_of[v] == UINT32_MAX) continue;
                const float to_eye[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]};
                float out[3];
                prt_glossy_eval(4, sh + v * 48, 0, N + v * 3, to_eye, out);
                sink += out[0] + out[1] + out[2];
            }
            h = prt__now();
        }
        if (f >= 5) { update += b - a; weights += c - b; eval += d - c; eval_diffuse += g - e; shade += h - g; }   /* the first frames build the caches */
        prt_lighting_release(l);
    }
    const int timed = frames - 5;
    update /= timed;
    weights /= timed;
    eval /= timed;
    eval_diffuse /= timed;
    shade /= timed;
    const double read_bw = bench_read_bandwidth(bytes > (64u << 20) ? bytes : (64u << 20), threads);
    const double eval_bw = (double)bytes / eval;
    printf("{\"mesh\": \"%s\", \"vertices\": %zu, \"triangles\": %zu, \"threads\": %d, \"cloud_lights\": %u, \"zones\": %u, \"merged_lights_per_zone\": %.1f,\n",
           mesh, nv, t->mesh.triangle_count, threads, set->cloud_count, set->zone_count, merged);
    printf(" \"bake_seconds\": %.2f, \"spectral_seconds\": %.2f, \"cloud_light_seconds\": %.2f, \"zone_seconds\": %.2f, \"peak_memory_mb\": %.1f,\n", bake,
           stage_seconds(&k, "spectral"), stage_seconds(&k, "cloud lights"), stage_seconds(&k, "zones"), peak_mb);
    printf(" \"transfer_bytes\": %zu, \"update_ms\": %.3f, \"updates_per_second\": %.1f, \"weights_ms\": %.3f, \"eval_ms\": %.3f,\n", bytes, update * 1e3, 1 / update,
           weights * 1e3, eval * 1e3);
    printf(" \"eval_bytes_per_second\": %.4g, \"read_bytes_per_second\": %.4g, \"eval_read_ratio\": %.3f", eval_bw, read_bw, eval_bw / read_bw);
    if (sh) {
        /* The glossy blocks' part of the evaluation, against reading their bytes. */
        const double glossy_eval = eval - eval_diffuse > 0 ? eval - eval_diffuse : 1e-9;
        const double glossy_read_bw = bench_read_bandwidth(glossy_bytes > (64u << 20) ? glossy_bytes : (64u << 20), threads);
        printf(",\n \"glossy_vertices\": %u, \"glossy_bytes\": %zu, \"glossy_eval_ms\": %.3f, \"glossy_eval_read_ratio\": %.3f, \"glossy_shade_ms\": %.3f, "
               "\"glossy_update_ms\": %.3f",
               set->glossy_count, glossy_bytes, glossy_eval * 1e3, (double)glossy_bytes / glossy_eval / glossy_read_bw, shade * 1e3, (glossy_eval + shade) * 1e3);
        fprintf(stderr, "  glossy: %u vertices, %.2f MB of blocks: evaluated in %.2f ms (%.0f%% of a plain read of them), exit SH towards an eye %.2f ms%s\n",
                set->glossy_count, glossy_bytes / 1e6, glossy_eval * 1e3, 100.0 * glossy_bytes / glossy_eval / glossy_read_bw, shade * 1e3,
                sink == 12345.0f ? " " : "");
    }
    printf("}\n");
    fprintf(stderr,
            "bench: %s, %zu vertices, %u cloud lights -> %.1f per zone over %u zones, %d threads\n"
            "  bake %.1f s: spectral transfer %.1f s, cloud lights %.1f s, clustering + CPCA %.1f s; peak memory %.0f MB\n"
            "  drag: CPU update %.2f ms per light move (%.0f updates/s, no drawing): weights %.2f ms, CPCA evaluation %.2f ms = %.3g bytes/s, %.0f%% of a plain read\n",
            mesh, nv, set->cloud_count, merged, set->zone_count, threads, bake, stage_seconds(&k, "spectral"), stage_seconds(&k, "cloud lights"),
            stage_seconds(&k, "zones"), peak_mb, update * 1e3, 1 / update, weights * 1e3, eval * 1e3, eval_bw, 100 * eval_bw / read_bw);
    if (glossy_reference > 0) {
        prt_scene *traced = NULL;
        if (prt_transfer_scene(ctx, t, &traced)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
        const float *P = t->mesh.positions, *N = t->mesh.normals;
        float *ra = malloc(nv * 3 * sizeof(float)), *ri = malloc(nv * 3 * sizeof(float));
        /* [glossy facing the eye, the rest][all, indirect]: squared error, squared reference, squared noise */
        double se[2][2] = {{0}}, sb[2][2] = {{0}}, sn[2][2] = {{0}};
        for (int i = 0; i < 3; ++i) {
            prt_lighting *l = NULL;
            prt_lighting_create(&l);
            const float u[3][3] = {{0.75f, 0.75f, 0.8f}, {0.2f, 0.6f, 0.3f}, {0.5f, 0.9f, 0.15f}};
            prt_light bulb = {.type = PRT_LIGHT_POINT,
                              .position = {lo[0] + u[i][0] * (hi[0] - lo[0]), lo[1] + u[i][1] * (hi[1] - lo[1]), lo[2] + u[i][2] * (hi[2] - lo[2])},
                              .intensity = {1, 1, 1}};
            prt_lighting_add(l, &bulb, NULL);
            prt_lighting_set_emission(l, 0);
            prt_relit a, b;
            prt_reference_desc rd = {0};
            rd.samples = glossy_reference;
            rd.lighting = l;
            rd.eye = eye;
            prt_reference_vertices ref;
            /* All light as drawn (the point light's direct light, its glossy highlight too, added per
             * vertex by prt_relit_shade as the renderer adds it per pixel); indirect as baked. */
            if (prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1}, &a) ||
                prt_relight(ctx, t, l, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT}, &b) ||
                prt_relit_shade(ctx, t, &a, eye, ra) || prt_relit_shade(ctx, t, &b, eye, ri) || prt_reference_trace_vertices(ctx, traced, NULL, &rd, &ref)) {
                fprintf(stderr, "bench: %s\n", prt_last_error());
                return 1;
            }
            for (size_t v = 0; v < nv; ++v) {
                const float d[3] = {eye[0] - P[v * 3], eye[1] - P[v * 3 + 1], eye[2] - P[v * 3 + 2]};
                const bool facing = d[0] * N[v * 3] + d[1] * N[v * 3 + 1] + d[2] * N[v * 3 + 2] > 0;
                if (set->glossy_of[v] != UINT32_MAX && !facing) continue;   /* the reference sees nothing from behind */
                const int g = set->glossy_of[v] != UINT32_MAX ? 0 : 1;
                for (int c = 0; c < 3; ++c) {
                    const size_t k = v * 3 + c;
                    const double x[2] = {ra[k], ri[k]}, y[2] = {ref.radiance[k], ref.indirect[k]}, n[2] = {ref.std_error[k], ref.std_error_indirect[k]};
                    for (int q = 0; q < 2; ++q) {
                        se[g][q] += (x[q] - y[q]) * (x[q] - y[q]);
                        sb[g][q] += y[q] * y[q];
                        sn[g][q] += n[q] * n[q];
                    }
                }
            }
            prt_relit_free(&a);
            prt_relit_free(&b);
            prt_reference_vertices_free(&ref);
            prt_lighting_release(l);
        }
        const char *name[2] = {"glossy vertices facing the eye", "other vertices"};
        for (int g = 0; g < 2; ++g) {
            if (sb[g][0] <= 0) continue;
            const double e0 = sqrt(se[g][0] / sb[g][0]), n0 = sqrt(sn[g][0] / sb[g][0]), e1 = sqrt(se[g][1] / sb[g][1]), n1 = sqrt(sn[g][1] / sb[g][1]);
            fprintf(stderr, "  vs path tracer (%d paths, 3 lights, eye %.2f,%.2f,%.2f), %s: all light %.3f (noise %.3f), indirect %.3f (noise %.3f)\n",
                    glossy_reference, eye[0], eye[1], eye[2], name[g], e0, n0, e1, n1);
            printf("{\"reference_vertices\": \"%s\", \"relative_l2\": %.4f, \"reference_noise\": %.4f, \"indirect_relative_l2\": %.4f, "
                   "\"indirect_reference_noise\": %.4f}\n", g ? "other" : "glossy_facing_eye", e0, n0, e1, n1);
        }
        free(ra);
        free(ri);
        prt_scene_release(traced);
    }
    if (resimulate) {
        /* Averaged merged responses against solutions at the merged positions, zone by zone. */
        prt_options *raw_o = NULL, *sp_o = NULL;
        prt_options_create(m, &raw_o);
        prt_options_create(prt_method_find("spectral"), &sp_o);
        prt_options_set(raw_o, "samples", samples);
        prt_options_set(raw_o, "compress", "none");
        prt_options_set(sp_o, "samples", samples);
        if (grid) prt_options_set(raw_o, "cloud-grid", grid);
        if (zone_vertices) prt_options_set(raw_o, "zone-vertices", zone_vertices);
        prt_transfer *raw = NULL, *sp = NULL;
        if (prt_bake(ctx, s, m, raw_o, NULL, &raw) || prt_bake(ctx, s, prt_method_find("spectral"), sp_o, NULL, &sp)) {
            fprintf(stderr, "bench: %s\n", prt_last_error());
            return 1;
        }
        const prt__lightcloud_set *rs = raw->state;
        double sum = 0, worst = 0;
        int merged_lights = 0;
        const int bounces[2] = {16, 1};   /* as the bake solves each cloud light: 16 bounces and the tail */
        for (uint32_t z = 0; z < rs->zone_count; ++z) {
            const prt__lightcloud_zone *zone = &rs->zones[z];
            uint32_t *members = prt__calloc(zone->lights, sizeof(uint32_t));
            for (uint32_t j = 0; j < rs->cloud_count; ++j) members[zone->light_of[j]]++;
            const uint32_t *verts = rs->members + rs->member_start[z];
            const uint32_t nz = rs->member_start[z + 1] - rs->member_start[z];
            for (uint32_t l = 0; l < zone->lights; ++l) {
                if (members[l] < 2) continue;
                prt_lighting *li = NULL;
                prt_lighting_create(&li);
                prt_light p = {.type = PRT_LIGHT_POINT, .position = {zone->positions[l * 3], zone->positions[l * 3 + 1], zone->positions[l * 3 + 2]},
                               .intensity = {1, 1, 1}};
                prt_lighting_add(li, &p, NULL);
                prt_lighting_set_emission(li, 0);
                prt_relit r;
                if (prt_relight(ctx, sp, li, &(prt_relight_desc){.variant = -1, .per_vertex = 1, .component = PRT_COMPONENT_INDIRECT, .controls = bounces}, &r)) {
                    fprintf(stderr, "bench: %s\n", prt_last_error());
                    return 1;
                }
                double se = 0, sb = 0;
                for (uint32_t i = 0; i < nz; ++i)
                    for (int c = 0; c < 3; ++c) {
                        const double avg = zone->diffuse.raw[((size_t)i * 3 + c) * zone->lights + l], sim = r.radiance[(size_t)verts[i] * 3 + c];
                        se += (avg - sim) * (avg - sim);
                        sb += sim * sim;
                    }
                if (sb > 0) {
                    const double e = sqrt(se / sb);
                    sum += e;
                    worst = e > worst ? e : worst;
                    merged_lights++;
                }
                prt_relit_free(&r);
                prt_lighting_release(li);
            }
            free(members);
        }
        fprintf(stderr, "  merged lights: averaged responses vs re-simulated at the mean position: relative L2 %.4f mean, %.4f worst over %d merged lights\n",
                merged_lights ? sum / merged_lights : 0, worst, merged_lights);
        printf("{\"resimulation_relative_l2_mean\": %.4f, \"resimulation_relative_l2_worst\": %.4f, \"merged_lights_checked\": %d}\n",
               merged_lights ? sum / merged_lights : 0, worst, merged_lights);
        prt_transfer_release(raw);
        prt_transfer_release(sp);
        prt_options_release(raw_o);
        prt_options_release(sp_o);
    }
    free(w);
    free(rgb);
    free(sh);
    prt_options_release(o);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
    return 0;
}
