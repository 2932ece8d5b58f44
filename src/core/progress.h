/* Progress reporting from parallel loops: workers count finished units; only OpenMP thread 0
 * calls the user's callback, at most every 100 ms, so the callback needs no locking.
 * Cancellation comes from the callback or from the context's cancel hook. */
#ifndef PRT_CORE_PROGRESS_H
#define PRT_CORE_PROGRESS_H

#include "core/internal.h"

typedef struct prt__progress {
    prt_progress_fn fn;
    void *user;
    const char *stage;
    uint64_t done, total;    /* done is updated atomically */
    double last_report;
    int cancelled;           /* read and written atomically */
    const prt_context *ctx;  /* its cancel hook stops the work too; may be NULL */
} prt__progress;

void prt__progress_begin(prt__progress *p, const char *stage, uint64_t total);
/* Adds n finished units; from thread 0, may call the callback. Returns true when cancelled. */
bool prt__progress_add(prt__progress *p, uint64_t n);
bool prt__progress_cancelled(prt__progress *p);
/* From the iterations of a (parallel) loop: the flag read every time (one relaxed load), the
 * context's hook asked when (i & mask) == 0. p may be NULL (then nothing stops the loop). */
static inline bool prt__progress_poll(prt__progress *p, size_t i, size_t mask)
{
    if (!p) return false;
    if (__atomic_load_n(&p->cancelled, __ATOMIC_RELAXED)) return true;
    return (i & mask) == 0 && prt__progress_cancelled(p);
}
/* Final report for the stage (done = total) unless cancelled. */
void prt__progress_end(prt__progress *p);
double prt__now(void);

#endif
