/* Running a parser in a child process (see isolate.h). */
#define _GNU_SOURCE
#include "io/isolate.h"

#include "core/progress.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
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
    char *line = nl ? nl + 1 : tail;
    for (char *p = line; *p; ++p)   /* errors are one printable line */
        if ((unsigned char)*p < 0x20 || *p == 0x7f) *p = ' ';
    return line;
}

static void reap(pid_t pid, int *status)
{
    while (waitpid(pid, status, 0) < 0 && errno == EINTR) {}
}

prt_status prt__run_isolated(const prt_context *ctx, prt__isolated_fn fn, void *arg, double seconds, size_t max_bytes, const char *what,
                             prt__bytes *out)
{
    memset(out, 0, sizeof *out);
    int data[2], err[2];
    if (pipe2(data, O_CLOEXEC) != 0) return prt__fail(ctx, PRT_ERR_BACKEND, "%s: cannot create a pipe: %s", what, strerror(errno));
    if (pipe2(err, O_CLOEXEC) != 0) {
        close(data[0]); close(data[1]);
        return prt__fail(ctx, PRT_ERR_BACKEND, "%s: cannot create a pipe: %s", what, strerror(errno));
    }
    fflush(NULL);   /* nothing buffered is written twice */
    const pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0) {
        close(data[0]); close(data[1]); close(err[0]); close(err[1]);
        return prt__fail(ctx, PRT_ERR_BACKEND, "%s: cannot start a process: %s", what, strerror(errno));
    }
    if (pid == 0) {
        /* The child dies with the parent (kill -9 of prt must not leave a parser spinning). */
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(4);
        /* Default dispositions and no blocked signals: the caller's crash handlers must not run
         * inside a crashing parser, and the parent decides when to stop it. No core files. */
        static const int sigs[] = {SIGINT, SIGTERM, SIGPIPE, SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGHUP, SIGQUIT};
        for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; ++i) signal(sigs[i], SIG_DFL);
        sigset_t none;
        sigemptyset(&none);
        sigprocmask(SIG_SETMASK, &none, NULL);
        struct rlimit no_core = {0, 0};
        setrlimit(RLIMIT_CORE, &no_core);
        /* stdin and stdout from /dev/null, stderr into the parent's hands, the result on fd 3;
         * every other descriptor (other threads' pipes, the caller's files) closed. */
        int null = open("/dev/null", O_RDWR);
        if (null < 0 || dup2(null, STDIN_FILENO) < 0 || dup2(null, STDOUT_FILENO) < 0 || dup2(err[1], STDERR_FILENO) < 0 ||
            dup2(data[1], 3) < 0)
            _exit(5);
        close_range(4, ~0U, 0);
        prt__bytes result = {0};
        fn(arg, &result);
        if (result.failed) _exit(3);
        write_all(3, result.data, result.size);
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
            if (i == 0 && out->size + (size_t)n > max_bytes)
                st = prt__fail(ctx, PRT_ERR_FORMAT, "%s: its result passed %zu MB, far more than the file could describe; stopped it", what,
                               max_bytes >> 20);
            else if (i == 0 && !prt__bytes_put(out, buf, (size_t)n))
                st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "%s: out of memory for its result", what);
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
    /* Both pipes closed: the child is exiting (tearing down a large address space can take a
     * moment, so it gets a grace period past the limit; one that hangs after closing them is killed). */
    const double exit_deadline = fmax(deadline, prt__now()) + 10.0;
    for (;;) {
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid) break;
        if (w < 0 && errno == ECHILD) { status = 0; break; }   /* the caller reaps children itself (SIGCHLD ignored) */
        if (prt__cancelled(ctx) || prt__now() > exit_deadline) {
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
