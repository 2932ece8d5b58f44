/* Per-thread last error and the log hook. */
#include "core/internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static _Thread_local char last_error[1024];

const char *prt_last_error(void) { return last_error; }

static void emit(const prt_context *ctx, prt_log_level level, const char *msg)
{
    if (ctx && ctx->log) ctx->log(ctx->log_user, level, msg);
}

prt_status prt__fail(const prt_context *ctx, prt_status status, const char *fmt, ...)
{
    /* Format into a local buffer: callers may pass prt_last_error() itself as an argument. */
    char msg[sizeof last_error];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    memcpy(last_error, msg, sizeof msg);
    emit(ctx, PRT_LOG_ERROR, last_error);
    return status;
}

void prt__log(const prt_context *ctx, prt_log_level level, const char *fmt, ...)
{
    if (!ctx || !ctx->log) return;
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    emit(ctx, level, msg);
}

const char *prt_status_string(prt_status s)
{
    switch (s) {
    case PRT_OK: return "ok";
    case PRT_ERR_INVALID_ARG: return "invalid argument";
    case PRT_ERR_IO: return "i/o error";
    case PRT_ERR_FORMAT: return "bad or corrupt input";
    case PRT_ERR_NO_MEMORY: return "out of memory";
    case PRT_ERR_CANCELLED: return "cancelled";
    case PRT_ERR_BACKEND: return "backend failure";
    case PRT_ERR_EMPTY: return "empty input";
    }
    return "unknown status";
}

const char *prt_version_string(void) { return "0.1.0"; }
