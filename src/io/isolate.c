/* Running a parser in a child process (see isolate.h). */
#define _GNU_SOURCE
#include "io/isolate.h"

#include "core/progress.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

static void write_all(int fd, const unsigned char *p, size_t n)
{
    while (n) {
        ssize_t w = write(fd, p, n > (1u << 20) ? (1u << 20) : n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return;
        p += w;
        n -= (size_t)w;
    }
}

/* The child's stderr is kept for the error message, up to its last few lines. */
static void keep_tail(char *tail, size_t cap, size_t *len, const char *p, size_t n)
{
    if (n >= cap - 1) { p += n - (cap - 1); n = cap - 1; *len = 0; }
    if (*len + n > cap - 1) {
        size_t drop = *len + n - (cap - 1);
        memmove(tail, tail + drop, *len - drop);
        *len -= drop;
    }
    memcpy(tail + *len, p, n);
    *len += n;
    tail[*len] = 0;
}

static const char *last_line(char *tail, size_t len)
{
    while (len && (tail[len - 1] == '\n' || tail[len - 1] == '\r' || tail[len - 1] == ' ')) tail[--len] = 0;
    char *nl = strrchr(tail, '\n');
    return nl ? nl + 1 : tail;
}

static void reap(pid_t pid, int *status)
{
    while (waitpid(pid, status, 0) < 0 && errno == EINTR) {}
}

prt_status prt__run_isolated(const prt_context *ctx, prt__isolated_fn fn, void *arg, double seconds, const char *what, prt__bytes *out)
{
    memset(out, 0, sizeof *out);
    int data[2], err[2];
    if (pipe2(data, O_CLOEXEC) != 0) return prt__fail(ctx, PRT_ERR_BACKEND, "%s: cannot create a pipe: %s", what, strerror(errno));
    if (pipe2(err, O_CLOEXEC) != 0) {
        close(data[0]); close(data[1]);
        return prt__fail(ctx, PRT_ERR_BACKEND, "%s: cannot create a pipe: %s", what, strerror(errno));
    }
    fflush(NULL);   /* nothing buffered is written twice */
    pid_t pid = fork();
    if (pid < 0) {
        close(data[0]); close(data[1]); close(err[0]); close(err[1]);
        return prt__fail(ctx, PRT_ERR_BACKEND, "%s: cannot start a process: %s", what, strerror(errno));
    }
    if (pid == 0) {
        /* The child: default signal dispositions (the parent decides when to stop it), stderr
         * into the parent's hands, the result down the data pipe, then out without running the
         * parent's atexit handlers or flushing its buffers. */
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        signal(SIGPIPE, SIG_DFL);
        close(data[0]);
        close(err[0]);
        dup2(err[1], STDERR_FILENO);
        prt__bytes result = {0};
        fn(arg, &result);
        if (result.failed) _exit(3);
        write_all(data[1], result.data, result.size);
        _exit(0);
    }
    close(data[1]);
    close(err[1]);
    const double deadline = prt__now() + seconds;
    char tail[512];
    size_t tail_len = 0;
    tail[0] = 0;
    struct pollfd fds[2] = {{data[0], POLLIN, 0}, {err[0], POLLIN, 0}};
    int open_fds = 2;
    prt_status st = PRT_OK;
    unsigned char buf[65536];
    while (open_fds > 0 && !st) {
        int r = poll(fds, 2, 100);
        if (r < 0 && errno != EINTR) { st = prt__fail(ctx, PRT_ERR_BACKEND, "%s: poll failed: %s", what, strerror(errno)); break; }
        for (int i = 0; i < 2 && r > 0; ++i) {
            if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            ssize_t n = read(fds[i].fd, buf, sizeof buf);
            if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
            if (n <= 0) { close(fds[i].fd); fds[i].fd = -1; open_fds--; continue; }
            if (i == 0 && !prt__bytes_put(out, buf, (size_t)n)) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "%s: out of memory for its result", what);
            if (i == 1) keep_tail(tail, sizeof tail, &tail_len, (const char *)buf, (size_t)n);
        }
        if (st) break;
        if (prt__cancelled(ctx)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "%s: cancelled", what);
        else if (prt__now() > deadline)
            st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: no result after %.3g s, stopped it (a malformed file can make the parser loop; "
                           "if the file is just large, raise the time limit)", what, seconds);
    }
    for (int i = 0; i < 2; ++i)
        if (fds[i].fd >= 0) close(fds[i].fd);
    int status = 0;
    if (st) {
        kill(pid, SIGKILL);
        reap(pid, &status);
        prt__bytes_free(out);
        return st;
    }
    /* Both pipes closed: the child is exiting (or closed them and hangs; it gets the rest of its time). */
    for (;;) {
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid) break;
        if (w < 0 && errno == ECHILD) { status = 0; break; }   /* the caller reaps children itself (SIGCHLD ignored) */
        if (prt__cancelled(ctx) || prt__now() > deadline) {
            kill(pid, SIGKILL);
            reap(pid, &status);
            prt__bytes_free(out);
            return prt__fail(ctx, prt__cancelled(ctx) ? PRT_ERR_CANCELLED : PRT_ERR_FORMAT, "%s: the parser did not exit", what);
        }
        usleep(10000);
    }
    const char *said = last_line(tail, tail_len);
    if (WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        prt__bytes_free(out);
        return prt__fail(ctx, PRT_ERR_FORMAT, "%s: the parser %s (%s)%s%s", what, sig == SIGABRT ? "aborted" : "crashed", strsignal(sig),
                         said[0] ? ": " : "", said);
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) != 0) {
        prt__bytes_free(out);
        return prt__fail(ctx, WEXITSTATUS(status) == 3 ? PRT_ERR_NO_MEMORY : PRT_ERR_FORMAT, "%s: the parser failed (exit %d)%s%s", what,
                         WEXITSTATUS(status), said[0] ? ": " : "", said);
    }
    return PRT_OK;
}
