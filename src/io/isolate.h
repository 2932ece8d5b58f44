/* Runs a third-party parser in a child process: a file that makes it loop, abort or crash ends
 * in an error for the caller, within a time limit and on cancellation, and whatever the parser
 * leaks dies with the child. The child hands its result back as bytes, which the caller must
 * validate like any other input. */
#ifndef PRT_IO_ISOLATE_H
#define PRT_IO_ISOLATE_H

#include "core/internal.h"

/* Fills out with the result; runs in the child, which exits after it. */
typedef void (*prt__isolated_fn)(void *arg, prt__bytes *out);

/* Runs fn(arg) in a child process and returns what it produced in out (caller frees).
 * what names the work in errors ("assimp reading 'x.ply'"). Fails with PRT_ERR_FORMAT when the
 * child dies by a signal, overruns `seconds` or hands back more than max_bytes (it is killed; its
 * last line on stderr is quoted), PRT_ERR_CANCELLED when the context's cancel hook fires (within
 * 100 ms), PRT_ERR_BACKEND when no child can be started. The child dies with the caller, runs
 * with default signal handlers, no core files and only its two pipes open. A caller that reaps
 * every child itself (SIGCHLD ignored, waitpid(-1)) loses the child's exit status: then a result
 * is judged by its bytes alone. */
prt_status prt__run_isolated(const prt_context *ctx, prt__isolated_fn fn, void *arg, double seconds, size_t max_bytes, const char *what,
                             prt__bytes *out);

#endif
