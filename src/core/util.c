/* Allocation with overflow checks, CRC (zlib), whole-file reads and atomic writes. */
#include "core/internal.h"

#include <dirent.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/types.h>

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

bool prt__mul_ok(size_t n, size_t size, size_t *out)
{
    if (size && n > SIZE_MAX / size) return false;
    *out = n * size;
    return true;
}

void *prt__calloc(size_t n, size_t size)
{
    size_t bytes;
    if (!prt__mul_ok(n, size, &bytes)) return NULL;
    return calloc(bytes ? bytes : 1, 1);
}

uint32_t prt__crc32(const void *data, size_t size)
{
    uLong crc = crc32(0L, Z_NULL, 0);
    const unsigned char *p = data;
    while (size > 0) {   /* zlib takes uInt lengths */
        uInt chunk = size > 0x40000000u ? 0x40000000u : (uInt)size;
        crc = crc32(crc, p, chunk);
        p += chunk;
        size -= chunk;
    }
    return (uint32_t)crc;
}

prt_status prt__read_file(const char *path, void **data, size_t *size)
{
    *data = NULL;
    *size = 0;
    FILE *fp = fopen(path, "rb");
    if (!fp) return prt__fail(NULL, PRT_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    struct stat sb;
    if (fstat(fileno(fp), &sb) != 0 || !S_ISREG(sb.st_mode)) {
        const bool dir = S_ISDIR(sb.st_mode);
        fclose(fp);
        return prt__fail(NULL, PRT_ERR_IO, "'%s' is %s, not a file", path, dir ? "a directory" : "not a regular file");
    }
    if (fseek(fp, 0, SEEK_END) != 0) { fclose(fp); return prt__fail(NULL, PRT_ERR_IO, "cannot seek '%s'", path); }
    long len = ftell(fp);
    if (len < 0) { fclose(fp); return prt__fail(NULL, PRT_ERR_IO, "cannot read '%s' (not a regular file?)", path); }
    rewind(fp);
    unsigned char *buf = malloc((size_t)len + 1);
    if (!buf) { fclose(fp); return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory reading '%s'", path); }
    size_t got = fread(buf, 1, (size_t)len, fp);
    fclose(fp);
    if (got != (size_t)len) { free(buf); return prt__fail(NULL, PRT_ERR_IO, "short read on '%s'", path); }
    buf[len] = 0;
    *data = buf;
    *size = (size_t)len;
    return PRT_OK;
}

prt_status prt__load_path(const prt_context *ctx, const char *path, prt__bytes_fn load, void *user)
{
    void *data;
    size_t size;
    prt_status st = prt__read_file(path, &data, &size);
    if (st) return prt__fail(ctx, st, "%s", prt_last_error());
    st = load(user, data, size);
    free(data);
    if (st) {
        char msg[900];
        snprintf(msg, sizeof msg, "%s", prt_last_error());
        return prt__fail(ctx, st, "'%s': %s", path, msg);
    }
    return PRT_OK;
}

/* Temporaries "<path>.tmp.<pid>" of writers that died (kill -9 mid-write) are removed before the
 * next write of the same path: a process of that id no longer exists. */
static void remove_stale_temps(const char *path)
{
    char dir[1024];
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    if (slash) snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    else snprintf(dir, sizeof dir, ".");
    if (!dir[0]) snprintf(dir, sizeof dir, "/");
    DIR *d = opendir(dir);
    if (!d) return;
    const size_t bl = strlen(base);
    struct dirent *e;
    while ((e = readdir(d))) {
        if (strncmp(e->d_name, base, bl) || strncmp(e->d_name + bl, ".tmp.", 5)) continue;
        const char *digits = e->d_name + bl + 5;
        char *end;
        errno = 0;
        long pid = strtol(digits, &end, 10);
        if (end == digits || *end || errno || pid <= 0 || pid == (long)getpid()) continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;   /* alive, or not ours to judge */
        char full[2048];
        snprintf(full, sizeof full, "%s/%s", dir, e->d_name);
        remove(full);
    }
    closedir(d);
}

prt_status prt__atomic_open(prt__atomic_file *f, const char *path)
{
    memset(f, 0, sizeof *f);
    remove_stale_temps(path);
    size_t n = strlen(path);
    f->final_path = malloc(n + 1);
    f->temp_path = malloc(n + 32);
    if (!f->final_path || !f->temp_path) {
        free(f->final_path); free(f->temp_path);
        return prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory");
    }
    memcpy(f->final_path, path, n + 1);
    snprintf(f->temp_path, n + 32, "%s.tmp.%ld", path, (long)getpid());
    f->fp = fopen(f->temp_path, "wb");
    if (!f->fp) {
        prt_status s = prt__fail(NULL, PRT_ERR_IO, "cannot create '%s': %s", f->temp_path, strerror(errno));
        free(f->final_path); free(f->temp_path);
        memset(f, 0, sizeof *f);
        return s;
    }
    return PRT_OK;
}

prt_status prt__atomic_write(prt__atomic_file *f, const void *data, size_t size)
{
    if (size && fwrite(data, 1, size, (FILE *)f->fp) != size)
        return prt__fail(NULL, PRT_ERR_IO, "write to '%s' failed: %s", f->temp_path, strerror(errno));
    return PRT_OK;
}

prt_status prt__atomic_commit(prt__atomic_file *f)
{
    FILE *fp = f->fp;
    int bad = fflush(fp) != 0 || fsync(fileno(fp)) != 0;
    bad |= fclose(fp) != 0;
    f->fp = NULL;
    if (bad || rename(f->temp_path, f->final_path) != 0) {
        prt_status s = prt__fail(NULL, PRT_ERR_IO, "cannot write '%s': %s", f->final_path, strerror(errno));
        remove(f->temp_path);
        free(f->final_path); free(f->temp_path);
        return s;
    }
    free(f->final_path); free(f->temp_path);
    memset(f, 0, sizeof *f);
    return PRT_OK;
}

prt_status prt__atomic_write_text(const char *path, const char *text)
{
    prt__atomic_file f;
    prt_status st = prt__atomic_open(&f, path);
    if (st) return st;
    st = prt__atomic_write(&f, text, strlen(text));
    if (!st) st = prt__atomic_write(&f, "\n", 1);
    if (st) { prt__atomic_abort(&f); return st; }
    return prt__atomic_commit(&f);
}

void prt__atomic_abort(prt__atomic_file *f)
{
    if (f->fp) fclose((FILE *)f->fp);
    if (f->temp_path) remove(f->temp_path);
    free(f->final_path); free(f->temp_path);
    memset(f, 0, sizeof *f);
}
