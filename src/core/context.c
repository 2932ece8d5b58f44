/* The context: Embree device, threads, log hook. */
#include "core/internal.h"

#include <omp.h>
#include <stdio.h>

static void embree_error(void *user, enum RTCError code, const char *str)
{
    prt__log((const prt_context *)user, PRT_LOG_ERROR, "embree error %d: %s", (int)code, str ? str : "");
}

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
    char cfg[64];
    snprintf(cfg, sizeof cfg, "threads=%d", ctx->threads);
    ctx->device = rtcNewDevice(cfg);
    if (!ctx->device) {
        free(ctx);
        return prt__fail(NULL, PRT_ERR_BACKEND, "could not create the Embree device");
    }
    rtcSetDeviceErrorFunction(ctx->device, embree_error, ctx);
    *out = ctx;
    return PRT_OK;
}

void prt_context_release(prt_context *ctx)
{
    if (!ctx) return;
    if (ctx->device) rtcReleaseDevice(ctx->device);
    free(ctx);
}

int prt_context_threads(const prt_context *ctx) { return ctx ? ctx->threads : 1; }

int prt__threads(const prt_context *ctx) { return ctx && ctx->threads > 0 ? ctx->threads : 1; }

bool prt__cancelled(const prt_context *ctx) { return ctx && ctx->cancel && ctx->cancel(ctx->cancel_user) != 0; }
