/* A growable byte string. */
#include "core/internal.h"

#include <stdlib.h>
#include <string.h>

bool prt__bytes_put(prt__bytes *b, const void *p, size_t n)
{
    if (b->failed) return false;
    if (n > SIZE_MAX - b->size) { b->failed = true; return false; }
    if (b->size + n > b->capacity) {
        size_t cap = b->capacity ? b->capacity : 4096;
        while (cap < b->size + n) cap = cap > SIZE_MAX / 2 ? b->size + n : cap * 2;
        unsigned char *q = realloc(b->data, cap);
        if (!q) { b->failed = true; return false; }
        b->data = q;
        b->capacity = cap;
    }
    if (n) memcpy(b->data + b->size, p, n);
    b->size += n;
    return true;
}

void prt__bytes_free(prt__bytes *b)
{
    free(b->data);
    memset(b, 0, sizeof *b);
}
