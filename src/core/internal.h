/* Private helpers shared by every layer of libprt. Nothing here is part of the API, and nothing
 * here knows the layers above core: each layer includes the public headers it implements. */
#ifndef PRT_INTERNAL_H
#define PRT_INTERNAL_H

#include "prt/base.h"
#include "prt/sh.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PRT_PI 3.14159265358979323846
/* The brightest radiance prt accepts in its inputs: sums over many pixels and samples stay far
 * from float overflow (3.4e38). */
#define PRT__MAX_RADIANCE 1e30f

struct prt_context {
    int threads;
    prt_log_fn log;
    void *log_user;
    prt_cancel_fn cancel;
    void *cancel_user;
    /* The ray-casting device (geom/raycast.c: Embree's), made on first use and published
     * atomically; core only releases it, through the function its maker left. */
    void *ray_device;
    void (*ray_device_release)(void *device);
};

/* True when the context's cancel hook asks to stop (ctx may be NULL). */
bool prt__cancelled(const prt_context *ctx);
/* Cheap polling from the iterations of a (parallel) loop: true once *stop is set, which happens
 * when the hook, asked on iterations i with (i & mask) == 0, says stop. Every thread then skips
 * the rest (`if (prt__cancel_poll(ctx, &stop, i, 255)) continue;`); the caller fails with
 * PRT_ERR_CANCELLED when stop is set after the loop. */
static inline bool prt__cancel_poll(const prt_context *ctx, int *stop, size_t i, size_t mask)
{
    if (__atomic_load_n(stop, __ATOMIC_RELAXED)) return true;
    if ((i & mask) || !prt__cancelled(ctx)) return false;
    __atomic_store_n(stop, 1, __ATOMIC_RELAXED);
    return true;
}

/* Records the failure message for prt_last_error(), sends it to the log hook (ctx may be NULL)
 * and returns status, so that callers can write `return prt__fail(ctx, PRT_ERR_IO, "...")`. */
prt_status prt__fail(const prt_context *ctx, prt_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void prt__log(const prt_context *ctx, prt_log_level level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* calloc of n*size with overflow check; NULL on failure. */
void *prt__calloc(size_t n, size_t size);
/* Sets *out = n*size when it does not overflow. */
bool prt__mul_ok(size_t n, size_t size, size_t *out);

/* A growable byte string (messages between processes, checkpoint records). After a failed
 * allocation every put is ignored and `failed` stays set. */
typedef struct prt__bytes {
    unsigned char *data;
    size_t size, capacity;
    bool failed;
} prt__bytes;
bool prt__bytes_put(prt__bytes *b, const void *p, size_t n);
void prt__bytes_free(prt__bytes *b);

uint32_t prt__crc32(const void *data, size_t size);
/* IEEE binary16 conversions (core/half.c), round to nearest even. */
uint16_t prt__half_from_float(float f);
float prt__half_to_float(uint16_t h);

/* Atomic file output: write to "<path>.tmp.<pid>", then fsync and rename. */
typedef struct prt__atomic_file {
    void *fp;
    char *final_path;
    char *temp_path;
} prt__atomic_file;
prt_status prt__atomic_open(prt__atomic_file *f, const char *path);
prt_status prt__atomic_write(prt__atomic_file *f, const void *data, size_t size);
prt_status prt__atomic_commit(prt__atomic_file *f);   /* closes; renames on success */
void prt__atomic_abort(prt__atomic_file *f);          /* closes and deletes the temporary */
/* A text file and a line end, written atomically: the whole of it or nothing. */
prt_status prt__atomic_write_text(const char *path, const char *text);

/* Reads a whole file; *data must be freed. */
prt_status prt__read_file(const char *path, void **data, size_t *size);
/* The file variant of a from-memory loader: reads path, hands its bytes to load, and puts the
 * path in front of a failure's message. */
typedef prt_status (*prt__bytes_fn)(void *user, const void *data, size_t size);
prt_status prt__load_path(const prt_context *ctx, const char *path, prt__bytes_fn load, void *user);

/* Low-discrepancy points: element i of the 2D Hammersley-like sequence (Sobol' first two
 * dimensions) scrambled by seed; results in [0,1). */
void prt__sobol2(uint32_t i, uint32_t seed, double *u, double *v);
/* K_lm of the SH recurrence (core/sh.c) at [l * PRT_SH_MAX_ORDER + m], m <= l; for shaders. */
void prt__sh_norms(float out[PRT_SH_MAX_ORDER * PRT_SH_MAX_ORDER]);
/* Uniform direction on the sphere from (u,v). */
void prt__sphere_dir(double u, double v, double dir[3]);
/* A cosine-distributed direction about n from (u1, u2) in [0,1)^2 (Malley's method: a uniform
 * point of the unit disc lifted onto the hemisphere), in the frame (tx, ty, n). */
void prt__cosine_dir(double u1, double u2, const float n[3], const float tx[3], const float ty[3], float out[3]);

/* Small vector helpers. */
static inline void prt__v3_sub(const float *a, const float *b, float *o) { o[0]=a[0]-b[0]; o[1]=a[1]-b[1]; o[2]=a[2]-b[2]; }
static inline void prt__v3_cross(const float *a, const float *b, float *o) {
    float x = a[1]*b[2]-a[2]*b[1], y = a[2]*b[0]-a[0]*b[2], z = a[0]*b[1]-a[1]*b[0];
    o[0]=x; o[1]=y; o[2]=z;
}
static inline float prt__v3_dot(const float *a, const float *b) { return a[0]*b[0]+a[1]*b[1]+a[2]*b[2]; }
static inline float prt__v3_len(const float *a) { return sqrtf(prt__v3_dot(a, a)); }
static inline bool prt__v3_normalize(float *a) {
    float l = prt__v3_len(a);
    if (!(l > 1e-30f) || !isfinite(l)) return false;
    a[0] /= l; a[1] /= l; a[2] /= l;
    return true;
}

/* Thread count for OpenMP regions. */
int prt__threads(const prt_context *ctx);

#endif
