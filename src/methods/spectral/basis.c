/* The spectral mesh basis (Karni & Gotsman 2000, as Wang, Zhu & Humphreys 2007 use it): METIS
 * cuts the mesh into partitions of about equal vertex counts; each partition's basis is the
 * eigenvectors of smallest eigenvalue of L^T L, where L is the partition's topological Laplacian
 * (1 on the diagonal, -1/d_i for the d_i neighbours of vertex i inside the partition). These are
 * the right singular vectors of L with the smallest singular values - the paper computes them by
 * SVD - so they are orthonormal and the first is constant on each connected piece, whatever the
 * valences (L itself is not symmetric). Functions are spread over partitions in proportion to
 * their vertex counts, at least one each. */
#include "methods/spectral/spectral.h"

#include <lapacke.h>
#include <metis.h>
#include <omp.h>

void openblas_set_num_threads(int);
int openblas_get_num_threads(void);

void prt__spectral_basis_free(prt__spectral_basis *b)
{
    free(b->part_of);
    free(b->count);
    free(b->first);
    free(b->offset);
    free(b->members);
    free(b->member_start);
    free(b->values);
    memset(b, 0, sizeof *b);
}

bool prt__spectral_basis_index(prt__spectral_basis *b, size_t nv)
{
    const uint32_t np = b->partitions;
    if (!np || np > nv || !b->part_of || !b->count) return false;
    uint32_t *first = prt__calloc((size_t)np + 1, sizeof *first);
    uint32_t *mstart = prt__calloc((size_t)np + 1, sizeof *mstart);
    uint64_t *offset = prt__calloc(nv + 1, sizeof *offset);
    uint32_t *members = prt__calloc(nv, sizeof *members);
    bool ok = first && mstart && offset && members;
    for (size_t v = 0; v < nv && ok; ++v) {
        if (b->part_of[v] >= np) ok = false;
        else mstart[b->part_of[v] + 1]++;
    }
    uint64_t functions = 0;
    for (uint32_t p = 0; p < np && ok; ++p) {
        const uint32_t n = mstart[p + 1], k = b->count[p];
        if (!n || !k || k > n) ok = false;
        first[p] = (uint32_t)functions;
        functions += k;
        mstart[p + 1] += mstart[p];
    }
    if (ok && functions != b->functions) ok = false;
    if (ok) {
        first[np] = (uint32_t)functions;
        uint32_t *fill = prt__calloc(np, sizeof *fill);
        if (!fill) ok = false;
        for (size_t v = 0; v < nv && ok; ++v) {
            const uint32_t p = b->part_of[v];
            members[mstart[p] + fill[p]++] = (uint32_t)v;
            offset[v + 1] = offset[v] + b->count[p];
        }
        free(fill);
    }
    if (!ok) {
        free(first); free(mstart); free(offset); free(members);
        return false;
    }
    free(b->first); free(b->member_start); free(b->offset); free(b->members);
    b->first = first;
    b->member_start = mstart;
    b->offset = offset;
    b->members = members;
    return true;
}

/* Vertex adjacency from the triangles, as CSR with sorted, unique neighbour lists. */
static prt_status adjacency(const prt__mesh *m, uint32_t **xadj_out, uint32_t **adj_out)
{
    const size_t nv = m->vertex_count, nt = m->triangle_count;
    uint32_t *xadj = prt__calloc(nv + 1, sizeof *xadj);
    uint32_t *adj = prt__calloc(nt * 6 + 1, sizeof *adj);
    uint32_t *fill = prt__calloc(nv, sizeof *fill);
    if (!xadj || !adj || !fill) { free(xadj); free(adj); free(fill); return PRT_ERR_NO_MEMORY; }
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) xadj[m->indices[t * 3 + k] + 1] += 2;
    for (size_t v = 0; v < nv; ++v) xadj[v + 1] += xadj[v];
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t *tri = m->indices + t * 3;
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = tri[k];
            adj[xadj[a] + fill[a]++] = tri[(k + 1) % 3];
            adj[xadj[a] + fill[a]++] = tri[(k + 2) % 3];
        }
    }
    /* Sort and compact each list (insertion sort: lists are short). */
    size_t out = 0;
    for (size_t v = 0; v < nv; ++v) {
        uint32_t *l = adj + xadj[v];
        const uint32_t n = xadj[v + 1] - xadj[v];
        for (uint32_t i = 1; i < n; ++i)
            for (uint32_t j = i; j > 0 && l[j - 1] > l[j]; --j) { uint32_t s = l[j]; l[j] = l[j - 1]; l[j - 1] = s; }
        const size_t start = out;
        for (uint32_t i = 0; i < n; ++i)
            if ((i == 0 || l[i] != l[i - 1]) && l[i] != v) adj[out++] = l[i];
        xadj[v] = (uint32_t)start;
    }
    xadj[nv] = (uint32_t)out;   /* xadj[v < nv] already hold the compacted starts */
    free(fill);
    *xadj_out = xadj;
    *adj_out = adj;
    return PRT_OK;
}

/* METIS k-way partitioning; partitions METIS leaves empty are dropped. */
static prt_status partition(prt_context *ctx, const prt__mesh *m, const uint32_t *xadj, const uint32_t *adj, int size, prt__spectral_basis *b)
{
    const size_t nv = m->vertex_count;
    b->part_of = prt__calloc(nv, sizeof *b->part_of);
    if (!b->part_of) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    const size_t want = (nv + (size_t)size - 1) / (size_t)size;
    if (want > 1) {
        if (nv > (size_t)INT32_MAX / 2 || xadj[nv] > (uint32_t)INT32_MAX)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "the mesh is too large for METIS (%zu vertices)", nv);
        idx_t n = (idx_t)nv, ncon = 1, parts = (idx_t)want, cut = 0, options[METIS_NOPTIONS];
        METIS_SetDefaultOptions(options);
        options[METIS_OPTION_SEED] = 1;          /* the same partitions every run */
        options[METIS_OPTION_NUMBERING] = 0;
        idx_t *part = prt__calloc(nv, sizeof *part);
        if (!part) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        /* idx_t is 32 bits in Debian's METIS, as uint32_t here (checked at compile time). */
        _Static_assert(sizeof(idx_t) == sizeof(uint32_t), "METIS idx_t must be 32 bits");
        int r = METIS_PartGraphKway(&n, &ncon, (idx_t *)xadj, (idx_t *)adj, NULL, NULL, NULL, &parts, NULL, NULL, options, &cut, part);
        if (r != METIS_OK) {
            free(part);
            return prt__fail(ctx, r == METIS_ERROR_MEMORY ? PRT_ERR_NO_MEMORY : PRT_ERR_BACKEND, "METIS could not partition the mesh (error %d)", r);
        }
        for (size_t v = 0; v < nv; ++v) b->part_of[v] = (uint32_t)part[v];
        free(part);
    }
    /* Renumber partitions densely (METIS may leave some empty). */
    uint32_t *map = prt__calloc(want, sizeof *map);
    if (!map) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    for (size_t v = 0; v < nv; ++v) {
        if (b->part_of[v] >= want) { free(map); return prt__fail(ctx, PRT_ERR_BACKEND, "METIS returned a partition out of range"); }
        map[b->part_of[v]] = 1;
    }
    uint32_t np = 0;
    for (size_t p = 0; p < want; ++p) map[p] = map[p] ? np++ : UINT32_MAX;
    for (size_t v = 0; v < nv; ++v) b->part_of[v] = map[b->part_of[v]];
    free(map);
    b->partitions = np;
    return PRT_OK;
}

/* The lowest k eigenvectors of L^T L for the partition's n vertices (`members`, ascending) into
 * out (n x k row-major: vertex i, function j). Work buffers are the caller's. */
static bool partition_basis(const uint32_t *members, uint32_t n, uint32_t k, const uint32_t *xadj, const uint32_t *adj,
                            const uint32_t *part_of, const uint32_t *local, double *M, double *Z, double *w, lapack_int *isuppz,
                            float *out)
{
    memset(M, 0, (size_t)n * n * sizeof(double));
    const uint32_t p = part_of[members[0]];
    /* M = sum over rows r of L_r^T L_r; row r has 1 at r and -1/d at its d in-partition neighbours. */
    for (uint32_t r = 0; r < n; ++r) {
        const uint32_t v = members[r];
        uint32_t d = 0;
        for (uint32_t e = xadj[v]; e < xadj[v + 1]; ++e) d += part_of[adj[e]] == p;
        if (!d) continue;   /* an isolated vertex: a piece of its own, constant is exact */
        const double inv = 1.0 / d;
        M[(size_t)r * n + r] += 1.0;
        for (uint32_t e = xadj[v]; e < xadj[v + 1]; ++e) {
            if (part_of[adj[e]] != p) continue;
            const uint32_t a = local[adj[e]];
            M[(size_t)r * n + a] -= inv;
            M[(size_t)a * n + r] -= inv;
            for (uint32_t f = xadj[v]; f < xadj[v + 1]; ++f)
                if (part_of[adj[f]] == p) M[(size_t)a * n + local[adj[f]]] += inv * inv;
        }
    }
    lapack_int found = 0;
    lapack_int info = LAPACKE_dsyevr(LAPACK_ROW_MAJOR, 'V', 'I', 'U', (lapack_int)n, M, (lapack_int)n, 0.0, 0.0, 1, (lapack_int)k, 0.0, &found, w, Z,
                                     (lapack_int)k, isuppz);
    if (info != 0 || found != (lapack_int)k) return false;
    for (uint32_t j = 0; j < k; ++j) {
        /* Fix the sign (an eigenvector's is arbitrary): largest component positive. */
        uint32_t big = 0;
        for (uint32_t i = 1; i < n; ++i)
            if (fabs(Z[(size_t)i * k + j]) > fabs(Z[(size_t)big * k + j]) + 1e-12) big = i;
        const double s = Z[(size_t)big * k + j] < 0 ? -1.0 : 1.0;
        for (uint32_t i = 0; i < n; ++i) out[(size_t)i * k + j] = (float)(s * Z[(size_t)i * k + j]);
    }
    return true;
}

prt_status prt__spectral_basis_build(prt_context *ctx, const prt__mesh *m, int partition_size, int functions, prt__progress *p,
                                     prt__spectral_basis *out)
{
    memset(out, 0, sizeof *out);
    const size_t nv = m->vertex_count;
    if (partition_size < 2 || functions < 1) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "spectral basis: bad partition size or function count");
    uint32_t *xadj = NULL, *adj = NULL;
    if (adjacency(m, &xadj, &adj)) return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt__spectral_basis *b = out;
    prt_status st = partition(ctx, m, xadj, adj, partition_size, b);
    uint32_t *local = NULL;
    if (!st) {
        /* Functions in proportion to vertex counts, at least one and at most n per partition. */
        b->count = prt__calloc(b->partitions, sizeof *b->count);
        uint32_t *sizes = prt__calloc(b->partitions, sizeof *sizes);
        local = prt__calloc(nv, sizeof *local);
        if (!b->count || !sizes || !local) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        for (size_t v = 0; v < nv && !st; ++v) local[v] = sizes[b->part_of[v]]++;
        uint64_t total = 0;
        for (uint32_t q = 0; q < b->partitions && !st; ++q) {
            if (sizes[q] > PRT__SPECTRAL_MAX_PARTITION)
                st = prt__fail(ctx, PRT_ERR_BACKEND, "METIS made a partition of %u vertices (at most %d): use a smaller --partition", sizes[q],
                               PRT__SPECTRAL_MAX_PARTITION);
            double share = (double)functions * sizes[q] / (double)nv;
            uint32_t k = (uint32_t)lround(share);
            if (k < 1) k = 1;
            if (k > sizes[q]) k = sizes[q];
            b->count[q] = k;
            total += k;
        }
        free(sizes);
        if (!st && total > PRT__SPECTRAL_MAX_FUNCTIONS)
            st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "%llu basis functions: at most %d (fewer --functions or larger --partition)", (unsigned long long)total,
                           PRT__SPECTRAL_MAX_FUNCTIONS);
        b->functions = (uint32_t)total;
        if (!st && total != (uint64_t)functions)
            prt__log(ctx, PRT_LOG_INFO, "spectral basis: %llu functions over %u partitions (asked for %d: each partition gets its share by vertex count, at least one)",
                     (unsigned long long)total, b->partitions, functions);
    }
    if (!st && !prt__spectral_basis_index(b, nv)) st = prt__fail(ctx, PRT_ERR_BACKEND, "spectral basis: inconsistent partitions");
    if (!st && !(b->values = prt__calloc(b->offset[nv] ? b->offset[nv] : 1, sizeof(float)))) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    if (!st) {
        uint32_t biggest = 0;
        for (uint32_t q = 0; q < b->partitions; ++q)
            if (b->member_start[q + 1] - b->member_start[q] > biggest) biggest = b->member_start[q + 1] - b->member_start[q];
        /* The eigen problems are dense and independent: one per thread, OpenBLAS single-threaded
         * meanwhile (its pool would only fight prt's threads), so results do not depend on the
         * thread count. */
        const int blas_threads = openblas_get_num_threads();
        openblas_set_num_threads(1);
        int failed = 0, no_memory = 0;
        prt__progress_begin(p, p->stage, b->partitions);
#pragma omp parallel num_threads(prt__threads(ctx))
        {
            double *M = malloc((size_t)biggest * biggest * sizeof(double));
            double *Z = malloc((size_t)biggest * biggest * sizeof(double));
            double *w = malloc((size_t)biggest * sizeof(double));
            float *tmp = malloc((size_t)biggest * biggest * sizeof(float));
            lapack_int *isuppz = malloc((size_t)2 * biggest * sizeof(lapack_int));
            if (!M || !Z || !w || !tmp || !isuppz) __atomic_store_n(&no_memory, 1, __ATOMIC_RELAXED);
#pragma omp for schedule(dynamic, 1)
            for (uint32_t q = 0; q < b->partitions; ++q) {
                if (__atomic_load_n(&no_memory, __ATOMIC_RELAXED) || __atomic_load_n(&failed, __ATOMIC_RELAXED) || prt__progress_cancelled(p)) continue;
                const uint32_t *mem = b->members + b->member_start[q];
                const uint32_t n = b->member_start[q + 1] - b->member_start[q], k = b->count[q];
                if (!partition_basis(mem, n, k, xadj, adj, b->part_of, local, M, Z, w, isuppz, tmp)) {
                    __atomic_store_n(&failed, 1, __ATOMIC_RELAXED);
                    continue;
                }
                for (uint32_t i = 0; i < n; ++i) memcpy(b->values + b->offset[mem[i]], tmp + (size_t)i * k, k * sizeof(float));
                prt__progress_add(p, 1);
            }
            free(M); free(Z); free(w); free(tmp); free(isuppz);
        }
        openblas_set_num_threads(blas_threads);
        if (no_memory) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory for the spectral basis (partitions of up to %u vertices)", biggest);
        else if (failed) st = prt__fail(ctx, PRT_ERR_BACKEND, "LAPACK could not find the eigenvectors of a partition");
        else if (prt__progress_cancelled(p)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "cancelled");
        else prt__progress_end(p);
    }
    free(xadj);
    free(adj);
    free(local);
    if (st) prt__spectral_basis_free(b);
    return st;
}

prt_status prt__spectral_basis_full(prt_context *ctx, size_t nv, prt__spectral_basis *b)
{
    memset(b, 0, sizeof *b);
    if (nv > PRT__SPECTRAL_MAX_FUNCTIONS)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "--full-basis: %zu vertices, at most %d (one function each)", nv, PRT__SPECTRAL_MAX_FUNCTIONS);
    b->partitions = b->functions = (uint32_t)nv;
    b->part_of = prt__calloc(nv, sizeof *b->part_of);
    b->count = prt__calloc(nv, sizeof *b->count);
    b->values = prt__calloc(nv, sizeof(float));
    if (!b->part_of || !b->count || !b->values) { prt__spectral_basis_free(b); return prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); }
    for (size_t v = 0; v < nv; ++v) { b->part_of[v] = (uint32_t)v; b->count[v] = 1; b->values[v] = 1.0f; }
    if (!prt__spectral_basis_index(b, nv)) { prt__spectral_basis_free(b); return prt__fail(ctx, PRT_ERR_BACKEND, "spectral basis: inconsistent partitions"); }
    return PRT_OK;
}

void prt__spectral_project(const prt__spectral_basis *b, const float *signal, float *coeffs, int threads)
{
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
    for (uint32_t q = 0; q < b->partitions; ++q) {
        const uint32_t k = b->count[q];
        float *c = coeffs + (size_t)b->first[q] * 3;
        memset(c, 0, (size_t)k * 3 * sizeof(float));
        for (uint32_t i = b->member_start[q]; i < b->member_start[q + 1]; ++i) {
            const uint32_t v = b->members[i];
            const float *s = b->values + b->offset[v], *x = signal + (size_t)v * 3;
            for (uint32_t j = 0; j < k; ++j) {
                c[j * 3 + 0] += s[j] * x[0];
                c[j * 3 + 1] += s[j] * x[1];
                c[j * 3 + 2] += s[j] * x[2];
            }
        }
    }
}

void prt__spectral_reconstruct(const prt__spectral_basis *b, size_t nv, const float *coeffs, float *signal, int threads)
{
#pragma omp parallel for schedule(static) num_threads(threads)
    for (size_t v = 0; v < nv; ++v) {
        const uint32_t q = b->part_of[v], k = b->count[q];
        const float *s = b->values + b->offset[v], *c = coeffs + (size_t)b->first[q] * 3;
        float r = 0, g = 0, bl = 0;
        for (uint32_t j = 0; j < k; ++j) { r += s[j] * c[j * 3]; g += s[j] * c[j * 3 + 1]; bl += s[j] * c[j * 3 + 2]; }
        signal[v * 3] = r;
        signal[v * 3 + 1] = g;
        signal[v * 3 + 2] = bl;
    }
}
