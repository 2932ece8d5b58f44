/* Evaluating offsets' importance for prt__choose_offsets without stalls on a busy machine.
 *
 * The choice is sequential: each build of the density decides the next batch (about 20 offsets,
 * some 5 ms of work), 56 batches in all. A parallel region per batch (or worse, per offset) ends
 * in a barrier, and where cores are shared that barrier waits for whichever thread the scheduler
 * has set aside: a bake's offsets took 12.6 s on 2 threads against 0.37 s on 1. Here one region
 * holds the whole choice: the choosing thread publishes each batch as chunks (an offset times a
 * run of sample texels), helpers claim them, and when none is left to claim the choosing thread
 * computes itself any chunk still unfinished, never waiting for a helper. A chunk's result is its
 * largest and summed value over fixed texels, combined in chunk order: the same whoever computed
 * it, so the offsets do not depend on the thread count. Each batch's offsets stay where they were
 * published, and each thread writes only its own results, so a helper late from an earlier batch
 * reads nothing that changed (the room for offsets is never moved) and its result is simply not
 * taken. */
#include "methods/offset/importance.h"
#include "methods/offset/offset.h"

#include <omp.h>

#define CHUNK 64                  /* sample texels per chunk */
#define GEN_SHIFT 40              /* the claim word: batch << 40 | chunks << 20 | claimed */
#define FIELD ((1u << 20) - 1)
#define STATE_SHIFT 16            /* a chunk's state: batch << 16 | (0: not done, 1 + thread that did it) */

typedef struct team {
    const prt__offset_importance_desc *d;
    int threads;
    size_t per_offset;            /* chunks per offset */
    size_t max_chunks;            /* of one batch */
    int *xy;                      /* every batch's offsets, appended, never overwritten */
    size_t xy_used, xy_cap;
    size_t *start;                /* per batch: its first offset in xy */
    uint32_t batches, batch_cap;
    uint64_t next;                /* the claim word (atomic) */
    uint64_t *state;              /* [max_chunks] (atomic) */
    double *result;               /* [threads][max_chunks][2]: largest, sum */
    pthread_mutex_t lock;
    pthread_cond_t wake;
    uint32_t published;           /* under lock: the last batch helpers were woken for */
    int done;                     /* under lock */
    prt__progress *p;
} team;

/* The largest and summed importance of offset o over sample texels first..last-1. */
static void chunk_value(const prt__offset_importance_desc *d, const int *o, size_t first, size_t last, double out[2])
{
    const prt__texel_patches *pt = d->patches;
    const int W = pt->width, H = pt->height;
    double top = 0, sum = 0;
    for (size_t i = first; i < last; ++i) {
        const size_t t = d->sample[i];
        const int sx = (int)(t % (size_t)W) + o[0], sy = (int)(t / (size_t)W) + o[1];
        if (sx < 0 || sx >= W || sy < 0 || sy >= H) continue;
        const size_t s = (size_t)sy * W + sx;
        double v = 0;
        for (int k = 0; k < 2; ++k) {
            if (!(d->kinds & (1u << k))) continue;
            float tr[3];
            prt__offset_tr(&d->x[k], t, s, tr);
            v += fmax(tr[0], fmax(tr[1], tr[2])) * pt->area[s];
        }
        top = fmax(top, v);
        sum += v;
    }
    out[0] = top;
    out[1] = sum;
}

/* Chunk c of batch g into thread w's result, then marked done by w unless another finished it. */
static void run_chunk(team *tm, uint32_t g, uint32_t c, int w)
{
    const size_t b = c / tm->per_offset, first = (c % tm->per_offset) * CHUNK;
    chunk_value(tm->d, tm->xy + (tm->start[g] + b) * 2, first, first + CHUNK < tm->d->count ? first + CHUNK : tm->d->count,
                tm->result + ((size_t)w * tm->max_chunks + c) * 2);
    uint64_t expect = (uint64_t)g << STATE_SHIFT;
    __atomic_compare_exchange_n(&tm->state[c], &expect, expect | (uint64_t)(w + 1), false, __ATOMIC_RELEASE, __ATOMIC_RELAXED);
}

/* Claims and runs chunks of the batch published last until none is left. */
static void run_claims(team *tm, int w)
{
    uint64_t v = __atomic_load_n(&tm->next, __ATOMIC_ACQUIRE);
    for (;;) {
        const uint32_t total = (uint32_t)(v >> 20) & FIELD, c = (uint32_t)v & FIELD;
        if (c >= total) return;
        if (__atomic_compare_exchange_n(&tm->next, &v, v + 1, false, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE)) {
            run_chunk(tm, (uint32_t)(v >> GEN_SHIFT), c, w);
            v = __atomic_load_n(&tm->next, __ATOMIC_ACQUIRE);
        }
    }
}

static void helper(team *tm, int w)
{
    uint32_t seen = 0;
    for (;;) {
        pthread_mutex_lock(&tm->lock);
        while (!tm->done && tm->published == seen) pthread_cond_wait(&tm->wake, &tm->lock);
        const int done = tm->done;
        seen = tm->published;
        pthread_mutex_unlock(&tm->lock);
        if (done) return;
        run_claims(tm, w);
    }
}

/* The importance callback, on the choosing thread (thread 0 of the team). */
static void importance(void *user, const int *offsets, size_t n, double *out)
{
    team *tm = user;
    for (size_t b = 0; b < n; ++b) out[b] = 0;
    if (prt__progress_cancelled(tm->p)) return;
    for (size_t b0 = 0; b0 < n;) {   /* batches larger than a published one in pieces */
        const size_t nb = n - b0 < tm->max_chunks / tm->per_offset ? n - b0 : tm->max_chunks / tm->per_offset;
        const uint32_t g = tm->batches + 1, total = (uint32_t)(nb * tm->per_offset);
        if (g >= tm->batch_cap || tm->xy_used + nb > tm->xy_cap) {
            /* More than prt__choose_offsets asks for (the room is never moved: a helper late from
             * an earlier batch may still read it): this thread alone, the same values. */
            for (size_t b = 0; b < nb; ++b) {
                double top = 0, sum = 0, r[2];
                for (size_t k = 0; k < tm->per_offset; ++k) {
                    chunk_value(tm->d, offsets + (b0 + b) * 2, k * CHUNK, (k + 1) * CHUNK < tm->d->count ? (k + 1) * CHUNK : tm->d->count, r);
                    top = fmax(top, r[0]);
                    sum += r[1];
                }
                out[b0 + b] = tm->d->mean ? sum / (double)tm->d->count : top;
            }
            prt__progress_add(tm->p, nb);
            b0 += nb;
            continue;
        }
        tm->start[g] = tm->xy_used;
        memcpy(tm->xy + tm->xy_used * 2, offsets + b0 * 2, nb * 2 * sizeof *offsets);
        tm->xy_used += nb;
        tm->batches = g;
        for (uint32_t c = 0; c < total; ++c) __atomic_store_n(&tm->state[c], (uint64_t)g << STATE_SHIFT, __ATOMIC_RELAXED);
        __atomic_store_n(&tm->next, (uint64_t)g << GEN_SHIFT | (uint64_t)total << 20, __ATOMIC_RELEASE);
        if (tm->threads > 1) {
            pthread_mutex_lock(&tm->lock);
            tm->published = g;
            pthread_cond_broadcast(&tm->wake);
            pthread_mutex_unlock(&tm->lock);
        }
        run_claims(tm, 0);
        /* Whatever a helper still holds, done here too: the first to finish is taken. */
        for (uint32_t c = 0; c < total; ++c)
            if (!(__atomic_load_n(&tm->state[c], __ATOMIC_ACQUIRE) & 0xFFFF)) run_chunk(tm, g, c, 0);
        for (size_t b = 0; b < nb; ++b) {
            double top = 0, sum = 0;
            for (size_t k = 0; k < tm->per_offset; ++k) {
                const uint32_t c = (uint32_t)(b * tm->per_offset + k);
                const int by = (int)(__atomic_load_n(&tm->state[c], __ATOMIC_ACQUIRE) & 0xFFFF) - 1;
                const double *r = tm->result + ((size_t)by * tm->max_chunks + c) * 2;
                top = fmax(top, r[0]);
                sum += r[1];
            }
            out[b0 + b] = tm->d->mean ? sum / (double)tm->d->count : top;
        }
        prt__progress_add(tm->p, nb);
        b0 += nb;
    }
}

prt_status prt__offset_choose(prt_context *ctx, const prt__offset_importance_desc *d, const prt__offset_desc *od, prt__progress *p, int **offsets,
                              int *count)
{
    *offsets = NULL;
    *count = 0;
    if (!d->count) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "no texel to weigh offsets with");
    int threads = prt__threads(ctx);
    if (threads > 0xFFFE) threads = 0xFFFE;
    team tm = {.d = d, .threads = threads, .p = p};
    tm.per_offset = (d->count + CHUNK - 1) / CHUNK;
    /* Room for the largest batch prt__choose_offsets evaluates, the 121 seeds, and every batch's
     * offsets: the seeds, then one per refinement. */
    tm.max_chunks = 121 * tm.per_offset;
    const int iterations = od->iterations > 0 ? od->iterations : 1000;
    tm.xy_cap = 121 + (size_t)iterations + 1;
    tm.batch_cap = (uint32_t)(iterations / 20 + 8);
    tm.xy = malloc(tm.xy_cap * 2 * sizeof *tm.xy);
    tm.start = malloc(tm.batch_cap * sizeof *tm.start);
    tm.state = prt__calloc(tm.max_chunks, sizeof *tm.state);
    tm.result = malloc((size_t)threads * tm.max_chunks * 2 * sizeof *tm.result);
    prt_status st = PRT_OK;
    if (!tm.xy || !tm.start || !tm.state || !tm.result || pthread_mutex_init(&tm.lock, NULL)) {
        free(tm.xy); free(tm.start); free(tm.state); free(tm.result);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    }
    if (pthread_cond_init(&tm.wake, NULL)) {
        pthread_mutex_destroy(&tm.lock);
        free(tm.xy); free(tm.start); free(tm.state); free(tm.result);
        return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory choosing offsets");
    }
    /* One region for the whole choice: its one barrier, at the end, is the only wait. */
#pragma omp parallel num_threads(threads)
    {
        if (omp_get_thread_num() == 0) {
            st = prt__choose_offsets(ctx, od, importance, &tm, offsets, count);
            pthread_mutex_lock(&tm.lock);
            tm.done = 1;
            pthread_cond_broadcast(&tm.wake);
            pthread_mutex_unlock(&tm.lock);
        } else {
            helper(&tm, omp_get_thread_num());
        }
    }
    pthread_cond_destroy(&tm.wake);
    pthread_mutex_destroy(&tm.lock);
    free(tm.xy); free(tm.start); free(tm.state); free(tm.result);
    return st;
}
