/* Replays saved inputs through a libFuzzer harness without libFuzzer: every file named on the
 * command line, or every file in the directories named and their subdirectories (a method's
 * seeds and crashes sit in a folder of their own: fuzz/regress/prt/NAME/). Built with the normal
 * compiler, so the regular test run (and the sanitizer run) checks every crash ever found stays
 * fixed. */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) { fprintf(stderr, "regress: cannot open %s\n", path); return 1; }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    rewind(f);
    uint8_t *buf = malloc(n > 0 ? (size_t)n : 1);
    if (!buf || fread(buf, 1, (size_t)n, f) != (size_t)n) { fclose(f); free(buf); return 1; }
    fclose(f);
    LLVMFuzzerTestOneInput(buf, (size_t)n);
    free(buf);
    return 0;
}

/* Replays path: a file, or everything under a directory. */
static int run_path(const char *path, int *files)
{
    struct stat sb;
    if (stat(path, &sb) != 0) { fprintf(stderr, "regress: %s is missing\n", path); return 1; }
    if (!S_ISDIR(sb.st_mode)) { (*files)++; return run_file(path); }
    int bad = 0;
    DIR *d = opendir(path);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char sub[4096];
        snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
        bad += run_path(sub, files);
    }
    if (d) closedir(d);
    return bad;
}

int main(int argc, char **argv)
{
    int files = 0, bad = 0;
    for (int i = 1; i < argc; ++i) bad += run_path(argv[i], &files);
    printf("regress: %d inputs replayed\n", files);
    return bad ? 1 : 0;
}
