/* prt_render_sums evaluated on the CPU: what the renderer falls back to where the GPU cannot hold
 * a description, and what tests compare the GPU's passes with. The same sums in the same order as
 * the shader (render/sums_gl.c), so both agree to float rounding. */
#include "core/internal.h"
#include "prt/render.h"

#include <stdlib.h>
#include <string.h>

prt_status prt__render_sums_check(const prt_render_sums *s, size_t vertex_count)
{
    if (!s || s->product_count < 1 || !s->products) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: no products");
    for (int k = 0; k < s->product_count; ++k) {
        const prt_render_product *p = &s->products[k];
        if (p->input < -1 || p->input >= k) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d reads product %d", k, p->input);
        const size_t in = p->input < 0 ? s->vector_length : s->products[p->input].rows;
        if (!p->start || (p->start[p->rows] && (!p->index || !p->weight)) || p->rows > (size_t)INT32_MAX)
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d lacks its arrays", k);
        if (p->shown && p->rows > vertex_count)
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d has %zu rows for %zu vertices", k, p->rows, vertex_count);
        if (p->start[0] != 0) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d's rows start at %u", k, p->start[0]);
        for (size_t r = 0; r < p->rows; ++r)
            if (p->start[r + 1] < p->start[r]) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d's row %zu ends before it starts", k, r);
        for (uint32_t e = 0; e < p->start[p->rows]; ++e)
            if (p->index[e] >= in) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d reads row %u of %zu", k, p->index[e], in);
        if (p->map_glsl && (!p->map_cpu || p->map_argc < 0 || p->map_argc > 3))
            return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d's map lacks its C or has %d arguments", k, p->map_argc);
        for (int j = 0; p->map_glsl && j < p->map_argc; ++j) {
            const int a = p->map_args[j];
            const size_t rows = a < 0 ? s->vector_length : a < k ? s->products[a].rows : 0;
            if (a < -1 || a >= k || (rows != p->rows && rows != 1))
                return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: product %d's map reads %d, of %zu rows for its %zu", k, a, rows, p->rows);
        }
    }
    return PRT_OK;
}

const prt_render_product *prt_render_sums_exit_product(const prt_render_sums *s)
{
    for (int k = 0; s && k < s->product_count; ++k)
        if (s->products[k].exit) return &s->products[k];
    return NULL;
}

const prt_render_product *prt_render_sums_kvec_product(const prt_render_sums *s)
{
    for (int k = 0; s && k < s->product_count; ++k)
        if (s->products[k].kvec) return &s->products[k];
    return NULL;
}

/* Every product's rows (RGB), or NULL after recording why. */
static float **eval_all(const prt_render_sums *s, const float *vector)
{
    prt_status st = PRT_OK;
    float **y = prt__calloc((size_t)s->product_count, sizeof *y);
    if (!y) { prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); return NULL; }
    for (int k = 0; !st && k < s->product_count; ++k) {
        const prt_render_product *p = &s->products[k];
        const float *x = p->input < 0 ? vector : y[p->input];
        if (!(y[k] = prt__calloc(p->rows ? p->rows * 3 : 1, sizeof(float)))) { st = prt__fail(NULL, PRT_ERR_NO_MEMORY, "out of memory"); break; }
        float *out = y[k];
#pragma omp parallel for schedule(static)
        for (size_t r = 0; r < p->rows; ++r) {
            float a0 = 0, a1 = 0, a2 = 0;
            for (uint32_t e = p->start[r]; e < p->start[r + 1]; ++e) {
                const float *w = p->weight + (size_t)e * 3, *xi = x + (size_t)p->index[e] * 3;
                a0 += w[0] * xi[0];
                a1 += w[1] * xi[1];
                a2 += w[2] * xi[2];
            }
            if (p->clamp) { a0 = a0 > 0 ? a0 : 0; a1 = a1 > 0 ? a1 : 0; a2 = a2 > 0 ? a2 : 0; }
            if (p->scale) { a0 *= p->scale[r * 3]; a1 *= p->scale[r * 3 + 1]; a2 *= p->scale[r * 3 + 2]; }
            out[r * 3] = a0;
            out[r * 3 + 1] = a1;
            out[r * 3 + 2] = a2;
            if (p->map_glsl) {
                static const float zero[3] = {0, 0, 0};
                const float *arg[3] = {zero, zero, zero};
                for (int j = 0; j < p->map_argc; ++j) {
                    const int a = p->map_args[j];
                    const float *src = a < 0 ? vector : y[a];
                    const size_t rows = a < 0 ? s->vector_length : s->products[a].rows;
                    arg[j] = src + (rows == 1 ? 0 : r * 3);
                }
                const float sum[3] = {a0, a1, a2};
                p->map_cpu(sum, arg, out + r * 3);
            }
        }
    }
    if (st) {
        for (int k = 0; k < s->product_count; ++k) free(y[k]);
        free(y);
        return NULL;
    }
    return y;
}

static void free_all(const prt_render_sums *s, float **y)
{
    for (int k = 0; k < s->product_count; ++k) free(y[k]);
    free(y);
}

prt_status prt_render_sums_cpu(const prt_render_sums *s, const float *vector, size_t vertex_count, float *rgb)
{
    if (!vector || !rgb) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render_sums_cpu: vector and output are required");
    prt_status st = prt__render_sums_check(s, vertex_count);
    if (st) return st;
    float **y = eval_all(s, vector);
    if (!y) return PRT_ERR_NO_MEMORY;
    for (int k = 0; k < s->product_count; ++k)
        if (s->products[k].shown)
            for (size_t i = 0; i < s->products[k].rows * 3; ++i) rgb[i] += y[k][i];
    free_all(s, y);
    return PRT_OK;
}

prt_status prt_render_sums_exit_cpu(const prt_render_sums *s, const float *vector, size_t vertex_count, int order, float *exit_sh)
{
    if (!vector || !exit_sh) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render_sums_exit_cpu: vector and output are required");
    prt_status st = prt__render_sums_check(s, vertex_count);
    if (st) return st;
    const prt_render_product *e = prt_render_sums_exit_product(s);
    const size_t n = (size_t)order * order;
    if (!e || order < 1 || e->rows != vertex_count * n)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: no exit product of %zu rows", vertex_count * n);
    float **y = eval_all(s, vector);
    if (!y) return PRT_ERR_NO_MEMORY;
    const float *rows = y[e - s->products];
    for (size_t v = 0; v < vertex_count; ++v)
        for (size_t i = 0; i < n; ++i)
            for (int c = 0; c < 3; ++c) exit_sh[(v * 3 + (size_t)c) * n + i] = rows[(v * n + i) * 3 + (size_t)c];
    free_all(s, y);
    return PRT_OK;
}

prt_status prt_render_sums_kvec_cpu(const prt_render_sums *s, const float *vector, size_t vertex_count, int terms, float *kvec)
{
    if (!vector || !kvec) return prt__fail(NULL, PRT_ERR_INVALID_ARG, "prt_render_sums_kvec_cpu: vector and output are required");
    prt_status st = prt__render_sums_check(s, vertex_count);
    if (st) return st;
    const prt_render_product *e = prt_render_sums_kvec_product(s);
    if (!e || terms < 1 || e->rows != vertex_count * (size_t)terms)
        return prt__fail(NULL, PRT_ERR_INVALID_ARG, "GPU sums: no kvec product of %zu rows", vertex_count * (size_t)(terms > 0 ? terms : 0));
    float **y = eval_all(s, vector);
    if (!y) return PRT_ERR_NO_MEMORY;
    memcpy(kvec, y[e - s->products], e->rows * 3 * sizeof(float));   /* the rows are the layout */
    free_all(s, y);
    return PRT_OK;
}
