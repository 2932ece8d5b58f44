/* Helpers shared by the cmocka tests: procedural meshes and a quiet context. */
#ifndef PRT_TEST_COMMON_H
#define PRT_TEST_COMMON_H

#include <math.h>
#include <setjmp.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>
#include <string.h>

#include <cmocka.h>
#include <prt/prt.h>
#include <zlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct test_mesh {
    float *pos, *nrm;
    uint32_t *idx;
    size_t nv, nt, cap_v, cap_t;
} test_mesh;

static inline void tm_vertex(test_mesh *m, float x, float y, float z, float nx, float ny, float nz)
{
    if (m->nv == m->cap_v) {
        m->cap_v = m->cap_v ? m->cap_v * 2 : 256;
        m->pos = realloc(m->pos, m->cap_v * 3 * sizeof(float));
        m->nrm = realloc(m->nrm, m->cap_v * 3 * sizeof(float));
    }
    float *p = m->pos + m->nv * 3, *n = m->nrm + m->nv * 3;
    p[0] = x; p[1] = y; p[2] = z; n[0] = nx; n[1] = ny; n[2] = nz;
    m->nv++;
}

static inline void tm_tri(test_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    if (m->nt == m->cap_t) {
        m->cap_t = m->cap_t ? m->cap_t * 2 : 256;
        m->idx = realloc(m->idx, m->cap_t * 3 * sizeof(uint32_t));
    }
    m->idx[m->nt * 3] = a; m->idx[m->nt * 3 + 1] = b; m->idx[m->nt * 3 + 2] = c;
    m->nt++;
}

/* A grid quad from origin o spanned by edges u, v (n x n cells); normal u x v. */
static inline void tm_quad(test_mesh *m, const float o[3], const float u[3], const float v[3], int n)
{
    float nn[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    float l = sqrtf(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
    uint32_t base = (uint32_t)m->nv;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            float s = (float)i / n, t = (float)j / n;
            tm_vertex(m, o[0] + s * u[0] + t * v[0], o[1] + s * u[1] + t * v[1], o[2] + s * u[2] + t * v[2], nn[0] / l, nn[1] / l, nn[2] / l);
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            uint32_t a = base + (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
            tm_tri(m, a, b, c);
            tm_tri(m, b, d, c);
        }
}

/* UV sphere with outward normals; poles are single vertices so no triangle is degenerate. */
static inline void tm_sphere(test_mesh *m, const float c[3], float r, int rings, int segs)
{
    uint32_t base = (uint32_t)m->nv;
    tm_vertex(m, c[0], c[1] + r, c[2], 0, 1, 0);
    for (int i = 1; i < rings; ++i) {
        float th = (float)M_PI * i / rings;
        for (int j = 0; j < segs; ++j) {
            float ph = 2.0f * (float)M_PI * j / segs;
            float n[3] = {sinf(th) * cosf(ph), cosf(th), sinf(th) * sinf(ph)};
            tm_vertex(m, c[0] + r * n[0], c[1] + r * n[1], c[2] + r * n[2], n[0], n[1], n[2]);
        }
    }
    uint32_t south = (uint32_t)m->nv;
    tm_vertex(m, c[0], c[1] - r, c[2], 0, -1, 0);
    for (int j = 0; j < segs; ++j) {
        uint32_t a = base + 1 + (uint32_t)j, b = base + 1 + (uint32_t)((j + 1) % segs);
        tm_tri(m, base, b, a);
        uint32_t la = base + 1 + (uint32_t)((rings - 2) * segs + j), lb = base + 1 + (uint32_t)((rings - 2) * segs + (j + 1) % segs);
        tm_tri(m, south, la, lb);
    }
    for (int i = 0; i < rings - 2; ++i)
        for (int j = 0; j < segs; ++j) {
            uint32_t a = base + 1 + (uint32_t)(i * segs + j), b = base + 1 + (uint32_t)(i * segs + (j + 1) % segs);
            uint32_t c2 = a + (uint32_t)segs, d = b + (uint32_t)segs;
            tm_tri(m, a, b, c2);
            tm_tri(m, b, d, c2);
        }
}

/* A closed box from lo to hi, a separate n x n grid per face (normals split at every edge, as
 * files bring them), faces outwards. */
static inline void tm_closed_box(test_mesh *m, const float lo[3], const float hi[3], int n)
{
    const float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    tm_quad(m, (float[3]){lo[0], hi[1], hi[2]}, (float[3]){dx, 0, 0}, (float[3]){0, 0, -dz}, n);   /* top, up */
    tm_quad(m, (float[3]){lo[0], lo[1], lo[2]}, (float[3]){dx, 0, 0}, (float[3]){0, 0, dz}, n);    /* bottom, down */
    tm_quad(m, (float[3]){hi[0], lo[1], hi[2]}, (float[3]){0, 0, -dz}, (float[3]){0, dy, 0}, n);   /* +x */
    tm_quad(m, (float[3]){lo[0], lo[1], lo[2]}, (float[3]){0, 0, dz}, (float[3]){0, dy, 0}, n);    /* -x */
    tm_quad(m, (float[3]){lo[0], lo[1], hi[2]}, (float[3]){dx, 0, 0}, (float[3]){0, dy, 0}, n);    /* +z */
    tm_quad(m, (float[3]){hi[0], lo[1], lo[2]}, (float[3]){-dx, 0, 0}, (float[3]){0, dy, 0}, n);   /* -z */
}

/* An open box (a pit) of side 1 with inward normals, n x n cells per face: its floor centre
 * sees the sky only through the top. */
static inline void tm_pit(test_mesh *m, int n)
{
    tm_quad(m, (float[3]){-0.5f, 0, 0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 0, -1}, n);   /* floor, up */
    tm_quad(m, (float[3]){-0.5f, 0, 0.5f}, (float[3]){0, 0, -1}, (float[3]){0, 1, 0}, n);   /* x = -0.5, facing +x */
    tm_quad(m, (float[3]){0.5f, 0, -0.5f}, (float[3]){0, 0, 1}, (float[3]){0, 1, 0}, n);    /* x = +0.5, facing -x */
    tm_quad(m, (float[3]){-0.5f, 0, -0.5f}, (float[3]){1, 0, 0}, (float[3]){0, 1, 0}, n);   /* z = -0.5, facing +z */
    tm_quad(m, (float[3]){0.5f, 0, 0.5f}, (float[3]){-1, 0, 0}, (float[3]){0, 1, 0}, n);    /* z = +0.5, facing -z */
}

static inline void tm_free(test_mesh *m) { free(m->pos); free(m->nrm); free(m->idx); memset(m, 0, sizeof *m); }

static inline prt_context *test_context(int threads)
{
    prt_context *ctx = NULL;
    prt_context_desc d = {0};
    d.threads = threads;
    assert_int_equal(prt_context_create(&d, &ctx), PRT_OK);
    return ctx;
}

static inline prt_scene *tm_scene(prt_context *ctx, const test_mesh *m, float albedo)
{
    prt_scene_desc sd = {0};
    sd.default_albedo[0] = sd.default_albedo[1] = sd.default_albedo[2] = albedo;
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_create_copy(ctx, m->pos, m->nrm, NULL, m->nv, m->idx, m->nt, &sd, &s), PRT_OK);
    return s;
}

/* Uniform unit radiance from every direction: only L_00 = sqrt(4 pi). */
static inline prt_sh_light uniform_light(int order)
{
    prt_sh_light l;
    memset(&l, 0, sizeof l);
    l.order = order;
    for (int c = 0; c < 3; ++c) l.coeffs[c][0] = (float)sqrt(4.0 * M_PI);
    return l;
}

/* Index of the vertex nearest to p. */
static inline size_t nearest_vertex(const float *pos, size_t nv, const float p[3])
{
    size_t best = 0;
    float bd = INFINITY;
    for (size_t v = 0; v < nv; ++v) {
        float dx = pos[v * 3] - p[0], dy = pos[v * 3 + 1] - p[1], dz = pos[v * 3 + 2] - p[2];
        float d = dx * dx + dy * dy + dz * dz;
        if (d < bd) { bd = d; best = v; }
    }
    return best;
}

/* A scratch directory per test program, removed afterwards: use as group setup/teardown. */
static char test_dir[256];

static inline int test_dir_setup(void **state)
{
    (void)state;
    /* mkdtemp's template ends in six 'X' that it replaces. */
    int n = snprintf(test_dir, sizeof test_dir, "/tmp/prt_test_%06d", 0);
    memset(test_dir + n - 6, 'X', 6);
    return mkdtemp(test_dir) ? 0 : -1;
}

static inline int test_dir_teardown(void **state)
{
    (void)state;
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", test_dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* A whole file's bytes (malloc'd), and back. */
static inline void *test_slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *size = (size_t)ftell(f);
    rewind(f);
    void *p = malloc(*size);
    assert_int_equal(fread(p, 1, *size, f), *size);
    fclose(f);
    return p;
}

static inline void test_spit(const char *path, const void *p, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(p, 1, n, f), n);
    fclose(f);
}

/* The table entry of chunk `id` in a .prt file held in memory (its chunk count in *count), or
 * NULL. An entry: id, CRC, offset, length. */
static inline unsigned char *test_chunk_entry(unsigned char *file, const char *id, uint32_t *count)
{
    memcpy(count, file + 12, 4);
    for (uint32_t i = 0; i < *count; ++i)
        if (!memcmp(file + 24 + 24 * (size_t)i, id, 4)) return file + 24 + 24 * (size_t)i;
    return NULL;
}

/* The checksums of chunk entry e (its bytes at off, len long) and of the header and table of a
 * .prt file held in memory with count chunks, recomputed. */
static inline void test_fix_chunk_crc(unsigned char *file, uint32_t count, unsigned char *e, uint64_t off, uint64_t len)
{
    uint32_t crc = (uint32_t)crc32(0L, file + off, (uInt)len);
    memcpy(e + 4, &crc, 4);
    uint32_t zero = 0;
    memcpy(file + 20, &zero, 4);
    crc = (uint32_t)crc32(0L, file, (uInt)(24 + 24 * (size_t)count));
    memcpy(file + 20, &crc, 4);
}

/* Overwrites bytes of chunk `id` of a .prt file held in memory at `offset` and fixes every
 * checksum, so that only the loader's own checks can catch the change. */
static inline void test_patch_chunk(unsigned char *file, const char *id, size_t offset, const void *bytes, size_t n)
{
    uint32_t count;
    unsigned char *e = test_chunk_entry(file, id, &count);
    if (!e) fail_msg("no chunk %s", id);
    uint64_t off, len;
    memcpy(&off, e + 8, 8);
    memcpy(&len, e + 16, 8);
    assert_true(offset + n <= len);
    memcpy(file + off + offset, bytes, n);
    test_fix_chunk_crc(file, count, e, off, len);
}

/* Gives chunk `id` of a .prt file held in memory `len` bytes (shorter: its tail cut off; longer:
 * the padding and the next chunk's bytes read as its own, within the file's `size`) and fixes
 * every checksum, so that only the loader's own checks can catch it. */
static inline void test_resize_chunk(unsigned char *file, size_t size, const char *id, uint64_t len)
{
    uint32_t count;
    unsigned char *e = test_chunk_entry(file, id, &count);
    if (!e) fail_msg("no chunk %s", id);
    uint64_t off;
    memcpy(&off, e + 8, 8);
    assert_true(off + len <= size);
    memcpy(e + 16, &len, 8);
    test_fix_chunk_crc(file, count, e, off, len);
}

/* Writes text into the scratch directory as name; path gets the full path. */
static inline void write_text(const char *name, const char *text, char *path, size_t n)
{
    snprintf(path, n, "%s/%s", test_dir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* The bytes of every chunk but META (which holds the thread count and the bake time). */
static inline unsigned char *chunks_but_meta(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    size_t size = (size_t)ftell(f);
    rewind(f);
    unsigned char *b = malloc(size), *out = malloc(size);
    assert_int_equal(fread(b, 1, size, f), size);
    fclose(f);
    uint32_t count;
    memcpy(&count, b + 12, 4);
    *n = 0;
    for (uint32_t i = 0; i < count; ++i) {
        const unsigned char *e = b + 24 + 24 * (size_t)i;
        uint64_t off, len;
        memcpy(&off, e + 8, 8);
        memcpy(&len, e + 16, 8);
        if (!memcmp(e, "META", 4)) continue;
        memcpy(out + *n, e, 8);   /* id and CRC */
        memcpy(out + *n + 8, b + off, len);
        *n += 8 + len;
    }
    free(b);
    return out;
}

/* The two files hold the same bytes in every chunk but META. */
static inline void assert_same_chunks(const char *pa, const char *pb)
{
    size_t na, nb;
    unsigned char *ca = chunks_but_meta(pa, &na), *cb = chunks_but_meta(pb, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(ca, cb, na);
    free(ca);
    free(cb);
}

/* Saves a and b into the scratch directory (names from tag) and compares them as above. */
static inline void assert_same_file(prt_transfer *a, prt_transfer *b, const char *tag)
{
    char pa[512], pb[512];
    snprintf(pa, sizeof pa, "%s/%s_a.prt", test_dir, tag);
    snprintf(pb, sizeof pb, "%s/%s_b.prt", test_dir, tag);
    assert_int_equal(prt_transfer_save(a, pa), PRT_OK);
    assert_int_equal(prt_transfer_save(b, pb), PRT_OK);
    assert_same_chunks(pa, pb);
}

/* Writes the procedural demo scene into the scratch directory and loads it. */
/* A bake by method name with options as NULL-terminated key, value pairs (kv may be NULL). */
static inline prt_transfer *test_bake_with(prt_context *ctx, const prt_scene *scene, const char *method, const char *const *kv)
{
    prt_options *o = NULL;
    assert_int_equal(prt_options_create(prt_method_find(method), &o), PRT_OK);
    for (int i = 0; kv && kv[i]; i += 2) assert_int_equal(prt_options_set(o, kv[i], kv[i + 1]), PRT_OK);
    prt_transfer *t = NULL;
    assert_int_equal(prt_bake(ctx, scene, prt_method_find(method), o, NULL, &t), PRT_OK);
    prt_options_release(o);
    return t;
}

static inline prt_scene *load_demo_scene(prt_context *ctx)
{
    char path[512];
    snprintf(path, sizeof path, "%s/demo.obj", test_dir);
    assert_int_equal(prt_demo_scene_write(path), PRT_OK);
    prt_scene *s = NULL;
    assert_int_equal(prt_scene_load(ctx, path, NULL, &s), PRT_OK);
    return s;
}

/* Where ../shared/data lives, or NULL (tests that need it then skip). */
static inline const char *shared_data_dir(void)
{
    const char *d = getenv("PRT_SHARED_DATA");
    return d && d[0] ? d : NULL;
}

/* The Cornell box of ../shared/data, or NULL after saying why (the caller skips). */
static inline const char *cornell_box_path(void)
{
    static char path[1024];
    const char *data = shared_data_dir();
    if (data) snprintf(path, sizeof path, "%s/meshes/cornell_box/CornellBox-Original.obj", data);
    if (!data || access(path, R_OK) != 0) {
        print_message("skipping: ../shared/data is absent (the Cornell box test needs it)\n");
        return NULL;
    }
    return path;
}

/* Per-vertex results against the path tracer, emitters (emit > 0) left out: out[0] the relative L2
 * of radiance, out[1] the reference's own relative noise, out[2] and out[3] the same for the
 * indirect part (zero when indirect is NULL). */
static inline void vs_reference(const float *radiance, const float *indirect, const prt_reference_vertices *ref, size_t nv, const float *emit,
                                double out[4])
{
    double se = 0, sb = 0, sn = 0, sei = 0, sbi = 0, sni = 0;
    for (size_t k = 0; k < nv * 3; ++k) {
        if (emit && emit[k - k % 3] > 0) continue;
        se += ((double)radiance[k] - ref->radiance[k]) * ((double)radiance[k] - ref->radiance[k]);
        sb += (double)ref->radiance[k] * ref->radiance[k];
        sn += (double)ref->std_error[k] * ref->std_error[k];
        if (!indirect) continue;
        sei += ((double)indirect[k] - ref->indirect[k]) * ((double)indirect[k] - ref->indirect[k]);
        sbi += (double)ref->indirect[k] * ref->indirect[k];
        sni += (double)ref->std_error_indirect[k] * ref->std_error_indirect[k];
    }
    out[0] = sqrt(se / sb);
    out[1] = sqrt(sn / sb);
    out[2] = sbi > 0 ? sqrt(sei / sbi) : 0;
    out[3] = sbi > 0 ? sqrt(sni / sbi) : 0;
}

/* SH order-3 coefficients of a smooth, positive test environment (index l(l+1)+m). */
static const float test_known_sh[9] = {4.0f, 0.4f, 0.8f, -0.5f, 0.2f, -0.15f, 0.3f, 0.1f, -0.25f};

/* A lat-long environment that is exactly band-limited: test_known_sh, tinted (1, 0.8, 0.6). */
static inline prt_envmap *band_limited_env(int width)
{
    prt_image img = {width, width / 2, malloc((size_t)width * width / 2 * 3 * sizeof(float))};
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < width; ++x) {
            double th = M_PI * (y + 0.5) / img.height, ph = 2 * M_PI * ((x + 0.5) / width - 0.5), yv[9];
            double d[3] = {sin(th) * sin(ph), cos(th), -sin(th) * cos(ph)};
            prt_sh_eval(3, d, yv);
            double v = 0;
            for (int i = 0; i < 9; ++i) v += test_known_sh[i] * yv[i];
            for (int c = 0; c < 3; ++c) img.rgb[((size_t)y * width + x) * 3 + c] = (float)v * (c == 0 ? 1.0f : c == 1 ? 0.8f : 0.6f);
        }
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    return env;
}

/* Radiance v from every direction. */
static inline prt_envmap *constant_env(float v)
{
    prt_image img = {64, 32, malloc(64 * 32 * 3 * sizeof(float))};
    for (int i = 0; i < 64 * 32 * 3; ++i) img.rgb[i] = v;
    prt_envmap *env = NULL;
    assert_int_equal(prt_envmap_from_image(&img, PRT_ENV_LATLONG, &env), PRT_OK);
    return env;
}

/* A unit tangent perpendicular to the unit vector n. */
static inline void tangent_of(const float n[3], float t[3])
{
    float a[3] = {0, 0, 0};
    a[fabsf(n[0]) < 0.6f ? 0 : 2] = 1;
    t[0] = a[1] * n[2] - a[2] * n[1];
    t[1] = a[2] * n[0] - a[0] * n[2];
    t[2] = a[0] * n[1] - a[1] * n[0];
    float l = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int c = 0; c < 3; ++c) t[c] /= l;
}

#endif
