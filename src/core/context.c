/* The context: threads, log and cancel hooks, and the services made on first use. */
#include "core/internal.h"

#include <omp.h>
#include <stdio.h>

prt_status prt_context_create(const prt_context_desc *desc, prt_context **out)
{
    prt_context_desc d = desc ? *desc : (prt_context_desc){0};
    if (!out) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_context_create: out is NULL");
    *out = NULL;
    if (d.threads < 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "threads must be >= 0 (got %d)", d.threads);
    prt_context *ctx = prt__calloc(1, sizeof *ctx);
    if (!ctx) return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory creating context");
    ctx->threads = d.threads > 0 ? d.threads : omp_get_num_procs();
    ctx->log = d.log;
    ctx->log_user = d.log_user;
    ctx->cancel = d.cancel;
    ctx->cancel_user = d.cancel_user;
    *out = ctx;
    return PRT_OK;
}

void prt_context_release(prt_context *ctx)
{
    if (!ctx) return;
    if (ctx->ray_device && ctx->ray_device_release) ctx->ray_device_release(ctx->ray_device);
    free(ctx);
}

int prt_context_threads(const prt_context *ctx) { return ctx ? ctx->threads : 1; }

int prt__threads(const prt_context *ctx) { return ctx && ctx->threads > 0 ? ctx->threads : 1; }

bool prt__cancelled(const prt_context *ctx) { return ctx && ctx->cancel && ctx->cancel(ctx->cancel_user) != 0; }
