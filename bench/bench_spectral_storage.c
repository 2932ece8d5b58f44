/* Storage against error of the spectral method's 16-bit transfer (issue 26): one bake keeps its
 * rows unquantized, then each storage is made from them and relit in float beside the rows
 * themselves:
 *   global     one scale for the matrix (the paper; prt before format version 3), entries
 *              below drop x the matrix's largest dropped
 *   partition  a scale per partition's functions (columns), drop x that block's largest
 *   row        a scale per row (what prt writes), drop x the row's largest
 * with bytes (2 + 2 per entry, a count per row, the scales), coefficients per vertex, the relative
 * L2 of the indirect light (3 bounces, per vertex) and of the glossy vertices' incident radiance
 * SH (the final glossy bounce's input), both against the unquantized, undropped rows. A last line
 * checks that the library's own relighting of its baked storage agrees with the row storage here.
 * Usage: prt_bench_spectral_storage [MESH|SCENE.json | --demo | --room [--cell D] | --bunny]
 *        [--plane] [--samples N] [--basis N] [--drops D,D,...] [--light SPEC] [--threads N]
 * (default --demo: the procedural demo scene; --bunny: ../shared/data's bunny; --plane adds a
 * ground plane three times the object's width). The table goes to stdout as Markdown. */
#include "bench_common.h"
#include "methods/spectral/spectral.h"

#include <string.h>

enum { GLOBAL, PARTITION, ROW, ROW_ABS, ROW_L1, SCHEMES };
static const char *scheme_name[SCHEMES] = {"global", "partition", "row", "row, drop vs matrix", "row, drop by L1"};

static const float *sort_key;
static int by_magnitude(const void *a, const void *b)
{
    const float x = fabsf(sort_key[*(const uint32_t *)a]), y = fabsf(sort_key[*(const uint32_t *)b]);
    return x < y ? -1 : x > y ? 1 : (*(const uint32_t *)a > *(const uint32_t *)b) - (*(const uint32_t *)a < *(const uint32_t *)b);
}

/* Sparse rows with dequantized float values. */
typedef struct rows_f {
    size_t rows;
    uint64_t *start;
    uint16_t *index;
    float *value;
} rows_f;

static void rows_free(rows_f *r) { free(r->start); free(r->index); free(r->value); }

/* The storage `scheme` makes of the raw rows, dequantized; bytes as stored. */
static rows_f quantize(const prt__spectral_basis *b, const uint64_t *start, const uint16_t *index, const float *value, size_t rows, int scheme,
                       float drop, double *bytes)
{
    const uint64_t n = start[rows];
    rows_f o = {rows, calloc(rows + 1, sizeof(uint64_t)), malloc((n ? n : 1) * sizeof(uint16_t)), malloc((n ? n : 1) * sizeof(float))};
    float *block = calloc(b->partitions, sizeof(float)), big = 0;
    uint32_t *part = malloc(b->functions * sizeof(uint32_t));
    for (uint32_t p = 0; p < b->partitions; ++p)
        for (uint32_t l = b->first[p]; l < b->first[p + 1]; ++l) part[l] = p;
    for (uint64_t i = 0; i < n; ++i) {
        big = fmaxf(big, fabsf(value[i]));
        block[part[index[i]]] = fmaxf(block[part[index[i]]], fabsf(value[i]));
    }
    uint32_t *keep = malloc(b->functions * sizeof(uint32_t));
    int16_t *q = malloc(b->functions * sizeof(int16_t));
    uint64_t at = 0;
    for (size_t r = 0; r < rows; ++r) {
        const uint64_t s0 = start[r], len = start[r + 1] - s0;
        if (scheme == ROW_ABS || scheme == ROW_L1) {
            /* Row scales; dropped: entries below drop x the matrix's largest (ROW_ABS), or the
             * smallest entries whose magnitudes sum to at most drop x the row's L1 norm (ROW_L1). */
            float m = 0, sum = 0;
            for (uint64_t i = s0; i < s0 + len; ++i) { m = fmaxf(m, fabsf(value[i])); sum += fabsf(value[i]); }
            bool *gone = calloc(len ? len : 1, sizeof(bool));
            if (scheme == ROW_ABS) {
                for (uint64_t i = 0; i < len; ++i) gone[i] = fabsf(value[s0 + i]) < drop * big;
            } else {
                uint32_t *order = malloc((len ? len : 1) * sizeof(uint32_t));
                for (uint32_t i = 0; i < len; ++i) order[i] = i;
                sort_key = value + s0;
                qsort(order, len, sizeof *order, by_magnitude);
                float cum = 0;
                for (uint64_t i = 0; i < len && cum + fabsf(value[s0 + order[i]]) <= drop * sum; ++i) {
                    cum += fabsf(value[s0 + order[i]]);
                    gone[order[i]] = true;
                }
                free(order);
            }
            const float scale = m / 32767.0f;
            for (uint64_t i = 0; i < len; ++i) {
                const long v = m > 0 ? lroundf(value[s0 + i] / scale) : 0;
                if (gone[i] || !v) continue;
                o.index[at] = index[s0 + i];
                o.value[at++] = (float)v * scale;
            }
            free(gone);
        } else if (scheme == ROW) {
            float scale;
            const uint32_t k = prt__spectral_quantize_row(value + s0, (uint32_t)len, drop, keep, q, &scale);
            for (uint32_t i = 0; i < k; ++i, ++at) { o.index[at] = index[s0 + keep[i]]; o.value[at] = q[i] * scale; }
        } else {
            for (uint64_t i = s0; i < s0 + len; ++i) {
                const float m = scheme == GLOBAL ? big : block[part[index[i]]], scale = m / 32767.0f;
                const long v = lroundf(value[i] / scale);
                if (fabsf(value[i]) < drop * m || !v) continue;
                o.index[at] = index[i];
                o.value[at++] = (float)v * scale;
            }
        }
        o.start[r + 1] = at;
    }
    *bytes = (double)at * 4 + (double)rows * 4 + (scheme == GLOBAL ? 4.0 : scheme == PARTITION ? 4.0 * b->partitions : 4.0 * rows);   /* row scales */
    free(block); free(part); free(keep); free(q);
    return o;
}

/* 3 bounces of the run time (relight.c) over float rows: indirect radiance per vertex. */
static void bounces(const prt__spectral_basis *b, const rows_f *T, const float *albedo, const float *direct, size_t nv, int threads, float *indirect)
{
    float *coeffs = calloc((size_t)b->functions * 3, sizeof(float)), *cur = malloc(nv * 3 * sizeof(float));
    memset(indirect, 0, nv * 3 * sizeof(float));
    const float *from = direct;
    for (int bounce = 0; bounce < 3; ++bounce) {
        prt__spectral_project(b, from, coeffs, threads);
#pragma omp parallel for schedule(static) num_threads(threads)
        for (size_t v = 0; v < nv; ++v) {
            float e[3] = {0, 0, 0};
            for (uint64_t i = T->start[v]; i < T->start[v + 1]; ++i)
                for (int c = 0; c < 3; ++c) e[c] += T->value[i] * coeffs[(size_t)T->index[i] * 3 + c];
            for (int c = 0; c < 3; ++c) cur[v * 3 + c] = albedo[v * 3 + c] / (float)PRT_PI * (e[c] > 0 ? e[c] : 0);
        }
        for (size_t i = 0; i < nv * 3; ++i) indirect[i] += cur[i];
        from = cur;
    }
    free(coeffs);
    free(cur);
}

/* Incident radiance SH of every glossy row (3 per row) from basis coefficients. */
static void glossy_in(const rows_f *G, const float *coeffs, float *in)
{
    for (size_t r = 0; r < G->rows; ++r) {
        float e[3] = {0, 0, 0};
        for (uint64_t i = G->start[r]; i < G->start[r + 1]; ++i)
            for (int c = 0; c < 3; ++c) e[c] += G->value[i] * coeffs[(size_t)G->index[i] * 3 + c];
        memcpy(in + r * 3, e, sizeof e);
    }
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The 99th percentile over vertices of |a - ref| / |ref| (RGB lengths), over the vertices whose
 * indirect light is at least 1% of the mean: how far off a dim vertex may be, which L2 hides. */
static double vertex_p99(const float *a, const float *ref, size_t nv, double mean)
{
    double *e = malloc((nv ? nv : 1) * sizeof(double));
    size_t n = 0;
    for (size_t v = 0; v < nv; ++v) {
        double d = 0, r = 0;
        for (int c = 0; c < 3; ++c) { d += ((double)a[v * 3 + c] - ref[v * 3 + c]) * ((double)a[v * 3 + c] - ref[v * 3 + c]); r += (double)ref[v * 3 + c] * ref[v * 3 + c]; }
        if (sqrt(r) >= 0.01 * mean * sqrt(3.0)) e[n++] = sqrt(d / r);
    }
    qsort(e, n, sizeof *e, cmp_double);
    const double p = n ? e[(size_t)(0.99 * (double)(n - 1))] : 0;
    free(e);
    return p;
}

static double rel_l2(const float *a, const float *ref, size_t n)
{
    double num = 0, den = 0;
    for (size_t i = 0; i < n; ++i) { num += ((double)a[i] - ref[i]) * ((double)a[i] - ref[i]); den += (double)ref[i] * ref[i]; }
    return den > 0 ? sqrt(num / den) : 0;
}

static prt_status begin(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job)
{
    (void)scene;
    prt_status st = prt__spectral_bake_begin(ctx, desc, t, job);
    if (!st && !(((prt__spectral_set *)t->state)->cache = prt__spectral_cache_new())) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    return st;
}

int main(int argc, char **argv)
{
    const char *scene_path = NULL, *drops = "0,1e-4,3e-4,1e-3,3e-3,1e-2,3e-2,0.1", *light = NULL;
    int threads = 0, samples = 4096, basis = 1024;
    float cell = 0.0625f;
    bool room = false, bunny = false, plane = false;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--samples") && i + 1 < argc) samples = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--basis") && i + 1 < argc) basis = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--drops") && i + 1 < argc) drops = argv[++i];
        else if (!strcmp(argv[i], "--light") && i + 1 < argc) light = argv[++i];
        else if (!strcmp(argv[i], "--cell") && i + 1 < argc) cell = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--room")) room = true;
        else if (!strcmp(argv[i], "--bunny")) bunny = true;
        else if (!strcmp(argv[i], "--plane")) plane = true;
        else if (!strcmp(argv[i], "--demo")) scene_path = NULL;
        else if (argv[i][0] != '-' && !scene_path) scene_path = argv[i];
        else {
            fprintf(stderr, "usage: prt_bench_spectral_storage [MESH|SCENE.json | --demo | --room [--cell D] | --bunny] [--plane] [--samples N] [--basis N] "
                            "[--drops D,...] [--light SPEC] [--threads N]\n");
            return 2;
        }
    }
    static char room_path[] = "/tmp/prt_bench_storage_room.obj", demo_path[] = "/tmp/prt_bench_storage_demo.obj";
    if (room) {
        if (prt_demo_room_write(room_path, cell)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
        scene_path = room_path;
    } else if (bunny) {
        scene_path = "../shared/data/meshes/bunny/bun_zipper.ply";
        if (access(scene_path, R_OK)) { fprintf(stderr, "bench: %s is absent: skipping\n", scene_path); return 0; }
    } else if (!scene_path) {
        if (prt_demo_scene_write(demo_path)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
        scene_path = demo_path;
    }
    prt_context *ctx = NULL;
    prt_scene *s = NULL;
    if (!bench_load(scene_path, threads, &ctx, &s, &scene_path)) return 1;
    threads = prt__threads(ctx);
    if (plane && !bench_ground_plane(&s->mesh, s->mesh.vertex_count, 100)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }

    prt__spectral_bake_desc d = {.functions = basis, .samples = samples, .drop_below = PRT__SPECTRAL_DROP_DEFAULT, .keep_rows = true};
    prt_transfer *t = NULL;
    const double t0 = prt__now();
    if (prt__bake_with(ctx, s, &prt__method_spectral, begin, &d, NULL, &t)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    const double bake = prt__now() - t0;
    const prt__spectral_set *set = t->state;
    const prt__spectral_basis *b = &set->basis;
    const size_t nv = t->mesh.vertex_count, ng = (size_t)set->glossy_count * PRT__SPECTRAL_GLOSSY_N;

    /* The lighting: a point light above the middle of the scene unless given. */
    float lo[3], hi[3];
    prt_scene_bounds(s, lo, hi);
    prt_lighting *l = NULL;
    prt_lighting_create(&l);
    prt_light lamp = {.type = PRT_LIGHT_POINT, .position = {0.5f * (lo[0] + hi[0]), lo[1] + 0.8f * (hi[1] - lo[1]), 0.5f * (lo[2] + hi[2])},
                      .intensity = {5, 5, 5}};
    if (light && prt_light_parse(light, &lamp)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    prt_lighting_add(l, &lamp, NULL);
    float *E = calloc(nv * 3, sizeof(float)), *direct = malloc(nv * 3 * sizeof(float));
    float *ref = malloc(nv * 3 * sizeof(float)), *ind = malloc(nv * 3 * sizeof(float)), *out = malloc(nv * 3 * sizeof(float));
    float *coeffs = calloc((size_t)b->functions * 3, sizeof(float));
    float *gref = malloc((ng ? ng : 1) * 3 * sizeof(float)), *gin = malloc((ng ? ng : 1) * 3 * sizeof(float));
    if (prt__spectral_direct(ctx, t, l, E, NULL, 0)) { fprintf(stderr, "bench: %s\n", prt_last_error()); return 1; }
    for (size_t i = 0; i < nv * 3; ++i) direct[i] = t->mesh.albedo[i] / (float)PRT_PI * E[i];

    /* The reference: the raw rows as they are. */
    rows_f raw = {nv, set->raw_start, set->raw_index, set->raw_value}, graw = {ng, set->raw_gstart, set->raw_gindex, set->raw_gvalue};
    bounces(b, &raw, t->mesh.albedo, direct, nv, threads, ref);
    for (size_t i = 0; i < nv * 3; ++i) out[i] = direct[i] + ref[i];
    prt__spectral_project(b, out, coeffs, threads);
    glossy_in(&graw, coeffs, gref);
    double mean = 0;
    for (size_t i = 0; i < nv * 3; ++i) mean += ref[i];
    mean /= (double)(nv * 3);

    fprintf(stderr, "bench: %s%s, %zu vertices (%u glossy), %u functions over %u partitions, %d rays per vertex, bake %.1f s, %d threads\n", scene_path,
            plane ? " + ground plane" : "", nv, set->glossy_count, b->functions, b->partitions, samples, bake, threads);
    printf("%s%s: %zu vertices, %u glossy; unquantized rows %.1f coefficients per vertex (%.1f per glossy row); mean indirect %.4g\n\n", scene_path,
           plane ? " + ground plane" : "", nv, set->glossy_count, (double)raw.start[nv] / (double)nv, ng ? (double)graw.start[ng] / (double)ng : 0.0, mean);
    printf("| scales | drop below | coefficients per vertex | bytes per vertex | indirect rel. L2 | 99th pct. vertex rel. error |%s\n",
           ng ? " glossy coefficients per glossy vertex | glossy incident rel. L2 |" : "");
    printf("| --- | ---: | ---: | ---: | ---: | ---: |%s\n", ng ? " ---: | ---: |" : "");
    for (int sc = 0; sc < SCHEMES; ++sc) {
        char list[256];
        snprintf(list, sizeof list, "%s", drops);
        for (char *tok = strtok(list, ","); tok; tok = strtok(NULL, ",")) {
            const float drop = (float)atof(tok);
            double bytes = 0, gbytes = 0;
            rows_f q = quantize(b, raw.start, raw.index, raw.value, nv, sc, drop, &bytes);
            bounces(b, &q, t->mesh.albedo, direct, nv, threads, ind);
            printf("| %s | %g | %.1f | %.0f", scheme_name[sc], drop, (double)q.start[nv] / (double)nv, bytes / (double)nv);
            printf(" | %.2e | %.2e |", rel_l2(ind, ref, nv * 3), vertex_p99(ind, ref, nv, mean));
            if (ng) {
                rows_f gq = quantize(b, graw.start, graw.index, graw.value, ng, sc, drop, &gbytes);
                glossy_in(&gq, coeffs, gin);
                printf(" %.1f | %.2e |", (double)gq.start[ng] / set->glossy_count, rel_l2(gin, gref, ng * 3));
                rows_free(&gq);
            }
            printf("\n");
            fflush(stdout);
            rows_free(&q);
        }
    }
    /* The library's run time over what the bake stored (row scales, the default drop) against
     * the row storage above: the same numbers up to float rounding. */
    rows_f q = quantize(b, raw.start, raw.index, raw.value, nv, ROW, PRT__SPECTRAL_DROP_DEFAULT, &(double){0});
    bounces(b, &q, t->mesh.albedo, direct, nv, threads, ind);
    float *lib = malloc(nv * 3 * sizeof(float));
    prt__spectral_bounces(ctx, t, t->mesh.albedo, direct, 3, 0, lib);   /* no tail: the rows above bounce 3 times */
    printf("\nlibrary relight vs the row storage at drop %g: rel. L2 %.1e; stored %.1f coefficients per vertex, %zu bytes\n", PRT__SPECTRAL_DROP_DEFAULT,
           rel_l2(lib, ind, nv * 3), (double)set->row_start[nv] / (double)nv, t->method->transfer_bytes(t));
    rows_free(&q);
    free(lib); free(E); free(direct); free(ref); free(ind); free(out); free(coeffs); free(gref); free(gin);
    prt_lighting_release(l);
    prt_transfer_release(t);
    prt_scene_release(s);
    prt_context_release(ctx);
    return 0;
}
