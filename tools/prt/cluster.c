/* prt bake under mpirun (docs/CLUSTER.md): every process loads the scene and runs the bake's
 * `whole` steps; each stage that can be spread is spread by rank 0, which hands out units to the
 * others in batches as they ask (dynamic load balancing), computes units itself on its other
 * threads, takes the records back, then sends every process the whole stage's records, which the
 * next stages read. Only rank 0 writes the file. Any failure aborts the whole job (MPI_Abort), so
 * that no process waits forever on one that is gone; mpirun ends the job when a process dies. */
#include "cli.h"

#include <stdlib.h>
#include <string.h>

#ifdef PRT_HAVE_MPI
#include <mpi.h>
#include <omp.h>
#include <time.h>

static int rank, size = 1, started;

enum { TAG_STAGE = 71, TAG_RESULTS, TAG_UNITS };

/* The process was started by mpirun (Open MPI, MPICH, PMIx): only then is MPI started at all, so
 * that a plain `prt bake` neither needs nor starts a runtime. */
static bool launched(void)
{
    return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMI_SIZE") || getenv("PMIX_RANK");
}

bool cli_cluster_start(int *argc, char ***argv)
{
    if (started || !launched()) return false;
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) return false;
    started = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    return true;
}

int cli_cluster_rank(void) { return rank; }
int cli_cluster_size(void) { return size; }

void cli_cluster_end(int rc)
{
    if (!started) return;
    started = 0;
    if (rc && size > 1) MPI_Abort(MPI_COMM_WORLD, rc);   /* the others may be waiting on this one */
    MPI_Finalize();
}

static void die(const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, "prt bake: rank %d: ", rank);
    fprintf(stderr, fmt, a, b);
    fputc('\n', stderr);
    MPI_Abort(MPI_COMM_WORLD, EXIT_BACKEND);
}

/* A growing buffer of records: u64 count, then u64 unit, u64 size, bytes for each. */
typedef struct pack { unsigned char *data; size_t size, cap; uint64_t count; } pack;

static void pack_add(pack *p, uint64_t unit, const void *data, size_t n)
{
    if (!p->size) p->size = 8;
    if (p->size + 16 + n > p->cap) {
        size_t cap = p->cap ? p->cap : 4096;
        while (cap < p->size + 16 + n) cap *= 2;
        unsigned char *q = realloc(p->data, cap);
        if (!q) die("%s%s", "out of memory packing records", "");
        p->data = q;
        p->cap = cap;
    }
    const uint64_t sz = n;
    memcpy(p->data + p->size, &unit, 8);
    memcpy(p->data + p->size + 8, &sz, 8);
    if (n) memcpy(p->data + p->size + 16, data, n);
    p->size += 16 + n;
    p->count++;
    memcpy(p->data, &p->count, 8);
}

static void pack_reset(pack *p) { p->size = 0; p->count = 0; }

/* Puts every record of a received pack into the bake. */
static void unpack(prt_bake_work *w, const unsigned char *b, size_t n)
{
    uint64_t count = 0;
    if (n >= 8) memcpy(&count, b, 8);
    size_t at = 8;
    for (uint64_t i = 0; i < count; ++i) {
        uint64_t unit, sz;
        if (at + 16 > n) die("%s%s", "a truncated message of records", "");
        memcpy(&unit, b + at, 8);
        memcpy(&sz, b + at + 8, 8);
        if (sz > n - at - 16) die("%s%s", "a truncated message of records", "");
        if (prt_bake_work_put(w, unit, b + at + 16, (size_t)sz)) die("%s%s", prt_last_error(), "");
        at += 16 + (size_t)sz;
    }
}

static unsigned char *receive(int source, int tag, int *from, size_t *n)
{
    MPI_Status s;
    MPI_Probe(source, tag, MPI_COMM_WORLD, &s);
    int count;
    MPI_Get_count(&s, MPI_BYTE, &count);
    unsigned char *b = malloc(count ? (size_t)count : 1);
    if (!b) die("%s%s", "out of memory receiving records", "");
    MPI_Recv(b, count, MPI_BYTE, s.MPI_SOURCE, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (from) *from = s.MPI_SOURCE;
    *n = (size_t)count;
    return b;
}

/* Units are claimed in order, skipping those already done (a checkpoint's). */
static uint64_t claim(prt_bake_work *w, uint64_t *next)
{
    const uint64_t units = prt_bake_work_units(w);
    for (;;) {
        const uint64_t u = __atomic_fetch_add(next, 1, __ATOMIC_RELAXED);
        if (u >= units || !prt_bake_work_done(w, u)) return u;
    }
}

static void run_here(prt_bake_work *w, uint64_t unit, int thread)
{
    if (prt_bake_work_run(w, unit, thread, NULL, NULL)) die("%s%s", prt_last_error(), "");
}

static void lead(prt_bake_work *w)
{
    const uint64_t units = prt_bake_work_units(w);
    uint64_t next = 0;
    int told_done = 0;
    const int threads = prt_bake_work_threads(w);
#pragma omp parallel num_threads(threads)
    {
        const int thread = omp_get_thread_num();
        if (thread == 0) {
            /* The main thread serves the others' requests (MPI_THREAD_FUNNELED). It computes units
             * between requests only when it is rank 0's one thread: a unit can take seconds (a cloud
             * light), and a process waiting for its next batch all that time would idle. */
            while (told_done < size - 1) {
                int flag = 0;
                MPI_Status st;
                MPI_Iprobe(MPI_ANY_SOURCE, TAG_RESULTS, MPI_COMM_WORLD, &flag, &st);
                if (flag) {
                    int from;
                    size_t n;
                    unsigned char *b = receive(st.MPI_SOURCE, TAG_RESULTS, &from, &n);
                    uint64_t want = 0;
                    if (n >= 16) memcpy(&want, b + n - 8, 8);   /* the batch it asks for, after its records */
                    unpack(w, b, n - 8);
                    free(b);
                    uint64_t batch[257];
                    uint64_t k = 0;
                    for (; k < want && k < 256; ++k) {
                        const uint64_t u = claim(w, &next);
                        if (u >= units) break;
                        batch[1 + k] = u;
                    }
                    batch[0] = k;
                    told_done += k == 0;
                    MPI_Send(batch, (int)(1 + k) * 8, MPI_BYTE, from, TAG_UNITS, MPI_COMM_WORLD);
                } else {
                    const uint64_t u = threads == 1 ? claim(w, &next) : units;
                    if (u < units) run_here(w, u, 0);
                    else nanosleep(&(struct timespec){0, 200000}, NULL);
                }
            }
            for (uint64_t u; (u = claim(w, &next)) < units;) run_here(w, u, 0);
        } else {
            for (uint64_t u; (u = claim(w, &next)) < units;) run_here(w, u, thread);
        }
    }
}

static void follow(prt_bake_work *w)
{
    const int threads = prt_bake_work_threads(w);
    const uint64_t want = (uint64_t)threads * 2 < 256 ? (uint64_t)threads * 2 : 256;
    pack out = {0};
    uint64_t batch[257];
    char why[512] = "";
    for (;;) {
        /* The records of the last batch, then how many units it can take next. */
        pack_add(&out, 0, &want, 0);   /* room for the count when there are no records */
        out.count--;
        out.size -= 16;
        memcpy(out.data, &out.count, 8);
        pack_add(&out, want, NULL, 0);   /* 16 bytes, the first 8 `want`: all but the last 8 are sent */
        out.count--;
        memcpy(out.data, &out.count, 8);
        MPI_Send(out.data, (int)(out.size - 8), MPI_BYTE, 0, TAG_RESULTS, MPI_COMM_WORLD);
        pack_reset(&out);
        MPI_Recv(batch, (int)sizeof batch, MPI_BYTE, 0, TAG_UNITS, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        const int n = (int)batch[0];
        if (!n) break;
        unsigned char **copies = calloc((size_t)n, sizeof *copies);
        size_t *sizes = calloc((size_t)n, sizeof *sizes);
        if (!copies || !sizes) die("%s%s", "out of memory", "");
        int failed = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
        for (int i = 0; i < n; ++i) {
            const void *d;
            if (prt_bake_work_run(w, batch[1 + i], omp_get_thread_num(), &d, &sizes[i]) || !(copies[i] = malloc(sizes[i] ? sizes[i] : 1))) {
                if (!__atomic_exchange_n(&failed, 1, __ATOMIC_RELAXED)) snprintf(why, sizeof why, "%s", prt_last_error());
                continue;
            }
            memcpy(copies[i], d, sizes[i]);
        }
        if (failed) die("%s%s", why[0] ? why : "out of memory", "");
        for (int i = 0; i < n; ++i) {
            pack_add(&out, batch[1 + i], copies[i], sizes[i]);
            free(copies[i]);
        }
        free(copies);
        free(sizes);
    }
    free(out.data);
}

/* Rank 0 sends the whole stage's records to every other process, in pieces MPI's int counts take. */
static void share(prt_bake_work *w)
{
    pack all = {0};
    uint64_t n = 0;
    if (rank == 0) {
        for (uint64_t u = 0; u < prt_bake_work_units(w); ++u) {
            const void *d;
            size_t sz;
            if (prt_bake_work_record(w, u, 0, &d, &sz)) die("%s%s", prt_last_error(), "");
            pack_add(&all, u, d, sz);
        }
        n = all.size;
    }
    MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    if (rank != 0 && !(all.data = malloc(n ? (size_t)n : 1))) die("%s%s", "out of memory", "");
    const uint64_t piece = (uint64_t)1 << 30;
    for (uint64_t at = 0; at < n; at += piece)
        MPI_Bcast(all.data + at, (int)(n - at < piece ? n - at : piece), MPI_BYTE, 0, MPI_COMM_WORLD);
    if (rank != 0) unpack(w, all.data, (size_t)n);
    free(all.data);
}

prt_status cli_cluster_spread(void *user, prt_bake_work *w)
{
    (void)user;
    /* Every process must be at the same stage of the same bake (same scene, options, build). */
    uint64_t here[2] = {(uint64_t)prt_bake_work_stage(w), prt_bake_work_units(w)}, lead_[2] = {here[0], here[1]};
    MPI_Bcast(lead_, 2, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    if (lead_[0] != here[0] || lead_[1] != here[1])
        die("%s%s", "this process's bake differs from rank 0's (another scene file, options or prt build?): ", prt_bake_work_name(w));
    if (rank == 0) lead(w);
    else follow(w);
    share(w);
    return PRT_OK;
}

const char *cli_cluster_build(void) { return "MPI"; }

#else

bool cli_cluster_start(int *argc, char ***argv) { (void)argc; (void)argv; return false; }
int cli_cluster_rank(void) { return 0; }
int cli_cluster_size(void) { return 1; }
void cli_cluster_end(int rc) { (void)rc; }
prt_status cli_cluster_spread(void *user, prt_bake_work *w) { (void)user; (void)w; return PRT_ERR_BACKEND; }
const char *cli_cluster_build(void) { return NULL; }

#endif
