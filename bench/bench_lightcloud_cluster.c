/* Benchmark of the light cloud's clustering stage against the number of cloud lights (issue 28):
 * the candidate pairs (a grid of cells one merge distance wide) and the complete-linkage
 * clustering over them, against the all-pairs clustering they replaced (tests/methods/lightcloud/
 * all_pairs.h: a table of n(n-1)/2 distances). The lights lie on a grid over a unit cube (as
 * --cloud-grid places them; N is rounded to the nearest cube: 1000, 4096, 15625, 64000), the merge
 * distance is 3 x the spacing (the bake's default) and the metric is eq. 9 with synthetic
 * responses: each light's at 64 probe points, 1 / (d^2 + 0.25), merge error 0.5 (a zone's
 * responses cost the same in both and are left out of the time; their memory, 256 bytes per
 * light, is in the baseline). The visibility rays, one per candidate pair, are not run.
 * Both run on one thread; cpu_seconds (user + system) is the measure on a shared machine, where
 * the wall clock counts the time others' work takes.
 * Usage: prt_bench_lightcloud_cluster [--lights N] [--all-pairs]   (one run per process: the peak
 * memory is the process's). Prints JSON on stdout. */
#include "bench_common.h"
#include "methods/lightcloud/lightcloud.h"
#include "../tests/methods/lightcloud/all_pairs.h"

#include <stdio.h>
#include <sys/resource.h>

#define PROBES 64

typedef struct cloud { const float *p; float distance, w2; const float *resp; } cloud;

static float metric3(void *user, uint32_t j, uint32_t k)
{
    const cloud *c = user;
    float d[3];
    prt__v3_sub(c->p + (size_t)j * 3, c->p + (size_t)k * 3, d);
    const float m = prt__v3_len(d) / c->distance;
    if (m >= 1.0f) return m;
    float worst = 0;
    for (int i = 0; i < PROBES; ++i) worst = fmaxf(worst, fabsf(c->resp[(size_t)j * PROBES + i] - c->resp[(size_t)k * PROBES + i]));
    return m + c->w2 * worst;
}
static float metric4(void *user, uint32_t j, uint32_t k, uint64_t pair)
{
    (void)pair;
    return metric3(user, j, k);
}

static double cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 + (double)ru.ru_stime.tv_sec + ru.ru_stime.tv_usec * 1e-6;
}

static double rss_mib(void)   /* resident now */
{
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, resident = 0;
    if (f) {
        if (fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        fclose(f);
    }
    return (double)resident * (double)sysconf(_SC_PAGESIZE) / 1048576.0;
}

int main(int argc, char **argv)
{
    uint32_t n = 4096;
    bool all = false;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--lights") && i + 1 < argc) n = (uint32_t)atol(argv[++i]);
        else if (!strcmp(argv[i], "--all-pairs")) all = true;
        else { fprintf(stderr, "usage: %s [--lights N] [--all-pairs]\n", argv[0]); return 2; }
    }
    const uint32_t side = (uint32_t)lround(cbrt((double)n));
    if (side < 2) return 2;
    n = side * side * side;
    float *p = malloc((size_t)n * 3 * sizeof(float)), *resp = malloc((size_t)n * PROBES * sizeof(float)), probe[PROBES][3];
    uint32_t *cluster_of = malloc((size_t)n * sizeof(uint32_t));
    if (!p || !resp || !cluster_of) return 4;
    for (uint32_t j = 0; j < n; ++j) {
        p[(size_t)j * 3] = (j % side + 0.5f) / side;
        p[(size_t)j * 3 + 1] = (j / side % side + 0.5f) / side;
        p[(size_t)j * 3 + 2] = (j / side / side + 0.5f) / side;
    }
    uint64_t s = 0x853c49e6748fea9bull;
    for (int i = 0; i < PROBES * 3; ++i) {
        s ^= s << 13; s ^= s >> 7; s ^= s << 17;
        probe[i / 3][i % 3] = (float)((s >> 11) / 9007199254740992.0);
    }
    float largest = 0;
    for (uint32_t j = 0; j < n; ++j)
        for (int i = 0; i < PROBES; ++i) {
            float d[3];
            prt__v3_sub(p + (size_t)j * 3, probe[i], d);
            resp[(size_t)j * PROBES + i] = 1.0f / (prt__v3_dot(d, d) + 0.25f);
            largest = fmaxf(largest, resp[(size_t)j * PROBES + i]);
        }
    cloud c = {p, 3.0f * prt__lightcloud_spacing(p, n), 1.0f / (0.5f * largest), resp};
    const double base = rss_mib(), t0 = prt__now(), c0 = cpu_seconds();
    uint32_t clusters = 0;
    uint64_t pairs_count = 0;
    if (all) clusters = all_pairs(n, metric3, &c, cluster_of);
    else {
        prt__lightcloud_pairs pairs;
        if (prt__lightcloud_pairs_find(NULL, p, n, c.distance, 1, &pairs) || prt__lightcloud_cluster(NULL, &pairs, metric4, &c, cluster_of, &clusters))
            return 4;
        pairs_count = pairs.count;
        prt__lightcloud_pairs_free(&pairs);
    }
    const double seconds = prt__now() - t0, cpu = cpu_seconds() - c0;
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    const double peak = (double)ru.ru_maxrss / 1024.0;
    uint64_t h = 1469598103934665603ull;   /* the clusters' fingerprint: the same in both modes */
    for (uint32_t j = 0; j < n; ++j) h = (h ^ cluster_of[j]) * 1099511628211ull;
    printf("{\"lights\": %u, \"mode\": \"%s\", \"candidate_pairs\": %llu, \"clusters\": %u, \"fingerprint\": \"%016llx\", \"seconds\": %.3f, "
           "\"cpu_seconds\": %.3f, \"peak_mib\": %.1f, \"baseline_mib\": %.1f, \"clustering_mib\": %.1f}\n",
           n, all ? "all-pairs" : "candidate-pairs", (unsigned long long)pairs_count, clusters, (unsigned long long)h, seconds, cpu, peak, base, peak - base);
    free(p);
    free(resp);
    free(cluster_of);
    return 0;
}
