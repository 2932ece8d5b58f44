/* The bake driver shared by every method: stages of independent work units on all threads, with
 * progress, cancellation and timing written once (see prt__bake_job in method/method.h). */
#include "method/method.h"

#include <omp.h>

prt_status prt__bake_drive(prt_context *ctx, prt__bake_job *job, const prt_bake_run_desc *run, prt_transfer *t)
{
    const double start = prt__now();
    prt__progress prog = {run ? run->progress : NULL, run ? run->progress_user : NULL, NULL, 0, 0, 0.0, 0};
    job->ctx = ctx;
    job->threads = prt__threads(ctx);
    prt_status st = PRT_OK;
    for (int index = 0; !st; ++index) {
        prt__stage s;
        memset(&s, 0, sizeof s);
        if ((st = job->stage(job, index, &s))) break;
        if (!s.units && !s.whole) break;
        prt__progress_begin(&prog, s.name, s.whole ? 1 : s.units);
        if (s.whole) {
            st = s.whole(job, ctx, &prog);
        } else {
            int failed = 0;
            prt_status first = PRT_OK;
            char why[512] = "";   /* errors are recorded per thread: keep the failing unit's */
            /* Units are claimed in order by whichever thread is free; each writes only its own
             * outputs, so the result is the same for any thread count and schedule. */
#pragma omp parallel for schedule(dynamic, 1) num_threads(job->threads)
            for (uint64_t u = 0; u < s.units; ++u) {
                if (__atomic_load_n(&failed, __ATOMIC_RELAXED) || prt__progress_cancelled(&prog)) continue;
                prt_status r = s.run(job, u, omp_get_thread_num());
                if (r && !__atomic_exchange_n(&failed, 1, __ATOMIC_RELAXED)) {
                    first = r;
                    snprintf(why, sizeof why, "%s", prt_last_error());
                }
                prt__progress_add(&prog, 1);
            }
            if (first) st = prt__fail(ctx, first, "%s", why[0] ? why : prt_status_string(first));
        }
        if (!st) prt__progress_end(&prog);
        if (!st && prt__progress_cancelled(&prog)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    }
    if (!st) st = job->finish(job, t);
    job->release(job);
    if (!st) {
        t->bake_seconds = prt__now() - start;
        t->threads = prt__threads(ctx);
    }
    return st;
}

prt_status prt__bake_with(prt_context *ctx, const prt_scene *scene, const prt__method *m, prt__bake_begin_fn begin, const void *desc,
                          const prt_bake_run_desc *run, prt_transfer **out)
{
    if (!ctx || !scene || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bake: context, scene and out are required");
    *out = NULL;
    prt_transfer *t = NULL;
    prt_status st = prt__transfer_from_scene(ctx, m, scene, &t);
    prt__bake_job *job = NULL;
    if (!st) st = begin(ctx, scene, desc, t, &job);
    if (!st) st = prt__bake_drive(ctx, job, run, t);
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}

/* The table entry's begin, with the options as its desc. */
static prt_status begin_from_options(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job)
{
    return t->method->bake_begin(ctx, scene, desc, t, job);
}

prt_status prt_bake(prt_context *ctx, const prt_scene *scene, const prt_method *m, const prt_options *o, const prt_bake_run_desc *run,
                    prt_transfer **out)
{
    if (!m) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake: a method is required");
    if (o && prt_options_method(o) != m)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake: options made for method %s, not %s", prt_method_name(prt_options_method(o)), m->name);
    return prt__bake_with(ctx, scene, m, begin_from_options, o, run, out);
}
