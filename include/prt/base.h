/* prt/base.h - status codes, the context, logging and progress.
 *
 * A prt_context owns everything process-wide that prt needs: the Embree device, the thread
 * count, and the log hook. Every other object is created from a context and must be released
 * before it. A context may be used from one thread at a time; objects made from it are
 * immutable once built and may be read from any number of threads.
 *
 * Every call that can fail returns a prt_status. The human-readable reason of the last failure
 * on the calling thread is returned by prt_last_error() and is also passed to the log hook.
 * The library never prints, never exits and never asserts on user input. */
#ifndef PRT_BASE_H
#define PRT_BASE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PRT_VERSION_MAJOR 0
#define PRT_VERSION_MINOR 1
#define PRT_VERSION_PATCH 0

typedef enum prt_status {
    PRT_OK = 0,
    PRT_ERR_INVALID_ARG,   /* a parameter is out of range or inconsistent */
    PRT_ERR_IO,            /* a file could not be opened, read or written */
    PRT_ERR_FORMAT,        /* input exists but is malformed, corrupt, truncated or unsupported */
    PRT_ERR_NO_MEMORY,     /* an allocation failed or a size would overflow */
    PRT_ERR_CANCELLED,     /* the progress callback asked to stop */
    PRT_ERR_BACKEND,       /* Embree, EGL/OpenGL or another library failed */
    PRT_ERR_EMPTY          /* input holds nothing usable (no triangles, no pixels) */
} prt_status;

typedef enum prt_log_level { PRT_LOG_DEBUG, PRT_LOG_INFO, PRT_LOG_WARN, PRT_LOG_ERROR } prt_log_level;

typedef void (*prt_log_fn)(void *user, prt_log_level level, const char *message);

/* Called with done/total units of work; return non-zero to cancel the operation, which then
 * returns PRT_ERR_CANCELLED and writes nothing. Called from one thread only. */
typedef int (*prt_progress_fn)(void *user, const char *stage, uint64_t done, uint64_t total);

/* Polled by the long operations made from the context (mesh import, subdivision, the ray-tracing
 * build, bakes, compression, the path tracer) about every 100 ms of work, from any thread;
 * return non-zero to stop them: they return PRT_ERR_CANCELLED and write nothing (a bake keeps its
 * checkpoint). Must be thread-safe and cheap (read a flag that a signal handler sets). */
typedef int (*prt_cancel_fn)(void *user);

typedef struct prt_context prt_context;

typedef struct prt_context_desc {
    int threads;          /* worker threads for bakes and relighting; 0 = all cores */
    prt_log_fn log;       /* receives warnings and errors; NULL = silent */
    void *log_user;
    prt_cancel_fn cancel; /* NULL = nothing is cancelled from outside (progress callbacks still can) */
    void *cancel_user;
} prt_context_desc;

prt_status prt_context_create(const prt_context_desc *desc, prt_context **out);
void prt_context_release(prt_context *ctx);
int prt_context_threads(const prt_context *ctx);

/* The message of the last failure on this thread ("" if none). Valid until the next prt call. */
const char *prt_last_error(void);
const char *prt_status_string(prt_status status);
const char *prt_version_string(void);

/* ---- Memory (bakes bounded by prt_bake_run_desc.memory_limit) ----
 * A size as people write it: a number with an optional fraction and an optional K, M, G or T
 * (powers of 1024; "iB" or "B" may follow: 4G, 512M, 1.5GiB, 65536), or "none" (no limit:
 * UINT64_MAX). PRT_ERR_INVALID_ARG, with a message saying why, for anything else, zero, or a size
 * past 2^63 bytes. */
prt_status prt_memory_size_parse(const char *text, uint64_t *bytes);
/* "3.2 GiB", "512 MiB", "none" (UINT64_MAX): into buf of size n; returns buf. */
const char *prt_memory_size_format(uint64_t bytes, char *buf, size_t n);
/* The machine's physical memory in bytes (0 when it cannot be told). */
uint64_t prt_memory_physical(void);
/* What a bake is held to when it names no limit: half the physical memory (4 GiB when that
 * cannot be told). */
uint64_t prt_memory_default_limit(void);
/* The process's peak resident memory so far, in bytes (0 when it cannot be told). */
uint64_t prt_memory_peak_resident(void);

#ifdef __cplusplus
}
#endif
#endif
