#include "core/progress.h"

#include <omp.h>
#include <time.h>

double prt__now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

void prt__progress_begin(prt__progress *p, const char *stage, uint64_t total)
{
    p->stage = stage;
    p->total = total;
    __atomic_store_n(&p->done, 0, __ATOMIC_RELAXED);
    p->last_report = 0.0;
    if (p->fn && p->fn(p->user, stage, 0, total)) __atomic_store_n(&p->cancelled, 1, __ATOMIC_RELAXED);
}

bool prt__progress_add(prt__progress *p, uint64_t n)
{
    uint64_t done = __atomic_add_fetch(&p->done, n, __ATOMIC_RELAXED);
    if (p->fn && omp_get_thread_num() == 0) {
        double now = prt__now();
        if (now - p->last_report > 0.1) {
            p->last_report = now;
            if (p->fn(p->user, p->stage, done, p->total)) __atomic_store_n(&p->cancelled, 1, __ATOMIC_RELAXED);
        }
    }
    return prt__progress_cancelled(p);
}

bool prt__progress_cancelled(prt__progress *p)
{
    if (__atomic_load_n(&p->cancelled, __ATOMIC_RELAXED)) return true;
    if (!prt__cancelled(p->ctx)) return false;
    __atomic_store_n(&p->cancelled, 1, __ATOMIC_RELAXED);
    return true;
}

void prt__progress_end(prt__progress *p)
{
    if (p->fn && !prt__progress_cancelled(p) && p->fn(p->user, p->stage, p->total, p->total))
        __atomic_store_n(&p->cancelled, 1, __ATOMIC_RELAXED);
}
