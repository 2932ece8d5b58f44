/* Clustered PCA of per-vertex transfer vectors (see prt/compress.h). Per-cluster covariance
 * matrices are eigen-decomposed with LAPACKE; vertices are reassigned in parallel, each
 * independently, so results never depend on the thread count. */
#include "core/progress.h"
#include "compress/cpca.h"

#include <cblas.h>
#include <lapacke.h>
#include <omp.h>
#include <string.h>

void prt__cpca_free(prt__cpca *c)
{
    if (!c) return;
    free(c->counts); free(c->basis_start); free(c->means); free(c->basis);
    free(c->cluster_of); free(c->weight_start); free(c->weights);
    free(c);
}

bool prt__cpca_index(prt__cpca *c, size_t nv)
{
    free(c->basis_start);
    free(c->weight_start);
    c->basis_start = prt__calloc((size_t)c->clusters + 1, sizeof(size_t));
    c->weight_start = prt__calloc(nv + 1, sizeof(size_t));
    if (!c->basis_start || !c->weight_start) return false;
    for (int k = 0; k < c->clusters; ++k) {
        if (c->counts[k] > (uint32_t)c->dim) return false;
        c->basis_start[k + 1] = c->basis_start[k] + c->counts[k];
    }
    if (c->basis_start[c->clusters] != c->vectors_total) return false;
    for (size_t v = 0; v < nv; ++v) {
        if (c->cluster_of[v] >= (uint32_t)c->clusters) return false;
        c->weight_start[v + 1] = c->weight_start[v] + c->counts[c->cluster_of[v]];
    }
    return c->weight_start[nv] == c->weights_total;
}

static uint64_t mix(uint64_t x)
{
    x ^= x >> 33; x *= 0xff51afd7ed558ccdULL; x ^= x >> 33; x *= 0xc4ceb9fe1a85ec53ULL; x ^= x >> 33;
    return x;
}

static double dist2(const float *a, const float *b, int dim)
{
    double s = 0;
    for (int i = 0; i < dim; ++i) { double d = (double)a[i] - b[i]; s += d * d; }
    return s;
}

/* Per-cluster model during the iteration: mean, eigenvectors (descending), eigenvalues. */
typedef struct model { double *mean, *vecs, *vals; size_t members; } model;

/* Squared reconstruction error of x with the cluster's first n vectors. */
static double recon_err(const float *x, const model *m, int dim, int n)
{
    double e = 0;
    for (int i = 0; i < dim; ++i) { double r = x[i] - m->mean[i]; e += r * r; }
    for (int j = 0; j < n; ++j) {
        const double *b = m->vecs + (size_t)j * dim;
        double p = 0;
        for (int i = 0; i < dim; ++i) p += b[i] * (x[i] - m->mean[i]);
        e -= p * p;
    }
    return e > 0 ? e : 0;
}

/* Vectors longer than this (glossy matrices) get the leading eigenvectors by subspace
 * iteration instead of a full covariance decomposition, whose dim^3 cost would dominate. */
#define FULL_EIGEN_MAX_DIM 512

static double unit_hash(uint64_t a) { return (double)(mix(a) >> 11) / 9007199254740992.0 * 2.0 - 1.0; }

/* Orthonormalizes the p rows of Q (dim each) in place, modified Gram-Schmidt; rows that
 * vanish stay zero. */
static void orthonormalize(double *Q, int p, int dim)
{
    for (int a = 0; a < p; ++a) {
        double *qa = Q + (size_t)a * dim;
        for (int b = 0; b < a; ++b) {
            const double *qb = Q + (size_t)b * dim;
            double d = 0;
            for (int i = 0; i < dim; ++i) d += qa[i] * qb[i];
            for (int i = 0; i < dim; ++i) qa[i] -= d * qb[i];
        }
        double l = 0;
        for (int i = 0; i < dim; ++i) l += qa[i] * qa[i];
        l = sqrt(l);
        for (int i = 0; i < dim; ++i) qa[i] = l > 1e-300 ? qa[i] / l : 0.0;
    }
}

/* Leading p-dimensional subspace of the n centred members' scatter (rows of Q) and the
 * projected scatter C = (R Q^T)^T (R Q^T), p x p, by three rounds of subspace iteration. */
static bool subspace(const float *X, const size_t *members, size_t n, const double *mean, int dim, int p, uint64_t seed,
                     double *Q, double *C, prt__progress *prog)
{
    double *Y = malloc(n * (size_t)p * sizeof(double)), *Z = malloc((size_t)p * dim * sizeof(double)), *r = malloc((size_t)dim * sizeof(double));
    if (!Y || !Z || !r) { free(Y); free(Z); free(r); return false; }
    for (size_t k = 0; k < (size_t)p * dim; ++k) Q[k] = unit_hash(seed * 0x9e3779b97f4a7c15ULL + k);
    orthonormalize(Q, p, dim);
    for (int round = 0; round <= 3; ++round) {
        for (size_t m = 0; m < n; ++m) {   /* Y = R Q^T */
            if (prt__progress_poll(prog, m, 255)) break;   /* the caller sees it and fails */
            const float *x = X + members[m] * dim;
            for (int i = 0; i < dim; ++i) r[i] = x[i] - mean[i];
            for (int a = 0; a < p; ++a) {
                const double *q = Q + (size_t)a * dim;
                double s = 0;
                for (int i = 0; i < dim; ++i) s += q[i] * r[i];
                Y[m * p + a] = s;
            }
        }
        if (round == 3) break;
        memset(Z, 0, (size_t)p * dim * sizeof(double));   /* Z = (R^T Y)^T */
        for (size_t m = 0; m < n; ++m) {
            if (prt__progress_poll(prog, m, 255)) break;
            const float *x = X + members[m] * dim;
            for (int i = 0; i < dim; ++i) r[i] = x[i] - mean[i];
            for (int a = 0; a < p; ++a) {
                const double y = Y[m * p + a];
                double *z = Z + (size_t)a * dim;
                for (int i = 0; i < dim; ++i) z[i] += y * r[i];
            }
        }
        memcpy(Q, Z, (size_t)p * dim * sizeof(double));
        orthonormalize(Q, p, dim);
    }
    for (int a = 0; a < p; ++a)
        for (int b = 0; b < p; ++b) {
            double s = 0;
            for (size_t m = 0; m < n; ++m) s += Y[m * p + a] * Y[m * p + b];
            C[a * p + b] = s;
        }
    free(Y); free(Z); free(r);
    return true;
}

/* The threads for a parallel pass of about `work` multiply-adds: one below a millisecond's worth.
 * A pass ends in a barrier that waits for every thread of its team, and where cores are shared
 * that wait is a scheduler's time slice: the light cloud's zones (clustered PCA of a few thousand
 * short vectors each, K + 2 passes per iteration) took 4.6 times as long on 2 threads as on 1
 * beside two busy processes. Called from a parallel region (one zone per thread), one: the
 * caller's threads are busy already. The result does not depend on the team. */
static int team(const prt_context *ctx, double work) { return work < (double)(1 << 21) || omp_in_parallel() ? 1 : prt__threads(ctx); }

prt_status prt__cpca_build(prt_context *ctx, const float *X, size_t nv, int dim, const prt_compress_desc *d, prt__progress *prog, prt__cpca **out)
{
    return prt__cpca_build_ex(ctx, X, nv, dim, d, FULL_EIGEN_MAX_DIM, prog, out);
}

prt_status prt__cpca_build_ex(prt_context *ctx, const float *X, size_t nv, int dim, const prt_compress_desc *d, int full_max_dim, prt__progress *prog,
                              prt__cpca **out)
{
    *out = NULL;
    int K = d->clusters;
    if ((size_t)K > nv) K = (int)nv;
    const int iterations = d->iterations;
    size_t budget = (size_t)d->vectors * (size_t)K;
    if (budget > (size_t)K * (size_t)dim) budget = (size_t)K * (size_t)dim;   /* tightened below for long vectors */
    prt_status st = PRT_OK;
    uint32_t *assign = prt__calloc(nv, sizeof(uint32_t)), *counts = prt__calloc((size_t)K, sizeof(uint32_t));
    size_t *order = prt__calloc(nv, sizeof(size_t)), *first = prt__calloc((size_t)K + 1, sizeof(size_t));
    model *M = prt__calloc((size_t)K, sizeof(model));
    double *best = prt__calloc(nv, sizeof(double));
    /* Large vectors keep only the leading eigenvectors a cluster can be given (vector budgets
     * stay well below these), found in a subspace a few vectors wider. */
    const bool large = dim > full_max_dim || dim > FULL_EIGEN_MAX_DIM;
    int keep = dim;
    if (large) {
        keep = 2 * d->vectors + 8;
        if (keep < 16) keep = 16;
        if (keep > dim) keep = dim;
    }
    const int sub = large ? (keep + 8 < dim ? keep + 8 : dim) : dim;
    if (budget > (size_t)K * (size_t)keep) budget = (size_t)K * (size_t)keep;
    if (!assign || !counts || !order || !first || !M || !best) {
        st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
        goto done;
    }
    for (int k = 0; k < K; ++k) {
        M[k].mean = prt__calloc((size_t)dim, sizeof(double));
        M[k].vecs = prt__calloc((size_t)sub * dim, sizeof(double));
        M[k].vals = prt__calloc((size_t)sub, sizeof(double));
        if (!M[k].mean || !M[k].vecs || !M[k].vals) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
    }
    /* k-means++ seeding with hashed uniforms: deterministic for the seed. */
    {
        size_t c0 = mix(d->seed * 0x9e3779b97f4a7c15ULL + 1) % nv;
        for (int i = 0; i < dim; ++i) M[0].mean[i] = X[c0 * dim + i];
        for (size_t v = 0; v < nv; ++v) best[v] = INFINITY;
        for (int k = 1; k <= K; ++k) {
            /* K passes over every vector: long ones (glossy matrices) take a second or more. */
            if (prog && prt__progress_cancelled(prog)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "compression cancelled"); goto done; }
            const int prev = k - 1;
#pragma omp parallel for schedule(static) num_threads(team(ctx, (double)nv * dim))
            for (size_t v = 0; v < nv; ++v) {
                if (prt__progress_poll(prog, v, 1023)) continue;
                double e = 0;
                for (int i = 0; i < dim; ++i) { double t = X[v * dim + i] - M[prev].mean[i]; e += t * t; }
                if (e < best[v]) { best[v] = e; assign[v] = (uint32_t)prev; }
            }
            /* Summed in vertex order, not per thread: the pick must not depend on the thread count. */
            double total = 0;
            for (size_t v = 0; v < nv; ++v) total += best[v];
            if (k == K) break;
            if (prog && prt__progress_cancelled(prog)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "compression cancelled"); goto done; }
            double u = (double)(mix(d->seed * 0x9e3779b97f4a7c15ULL + (uint64_t)k * 7919 + 2) >> 11) / 9007199254740992.0 * total, acc = 0;
            size_t pick = nv - 1;
            for (size_t v = 0; v < nv; ++v) { acc += best[v]; if (acc >= u && best[v] > 0) { pick = v; break; } }
            for (int i = 0; i < dim; ++i) M[k].mean[i] = X[pick * dim + i];
        }
    }
    /* The eigen problems are tiny (at most 300 x 300): OpenBLAS's own thread pool would only spin
     * against prt's threads (40x slower measured), so it runs single-threaded meanwhile. */
    const bool nested = omp_in_parallel();   /* the caller's team sets OpenBLAS's threads (racing here would undo it) */
    const int blas_threads = nested ? 0 : openblas_get_num_threads();
    if (!nested) openblas_set_num_threads(1);
    size_t total_vectors = 0;
    for (int it = 0; it <= iterations && !st; ++it) {
        /* Members of each cluster, in vertex order. */
        memset(first, 0, ((size_t)K + 1) * sizeof(size_t));
        for (size_t v = 0; v < nv; ++v) first[assign[v] + 1]++;
        for (int k = 0; k < K; ++k) first[k + 1] += first[k];
        {
            size_t *fill = prt__calloc((size_t)K, sizeof(size_t));
            if (!fill) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
            for (size_t v = 0; v < nv; ++v) order[first[assign[v]] + fill[assign[v]]++] = v;
            free(fill);
        }
        /* Local PCA per cluster (clusters in parallel: each sums its own members in order). */
        int lapack_failed = 0;
        double *small = large ? malloc((size_t)K * sub * sub * sizeof(double)) : NULL;   /* projected scatter per cluster */
        if (large && !small) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
#pragma omp parallel for schedule(dynamic, 1) num_threads(team(ctx, (double)nv * dim * sub))
        for (int k = 0; k < K; ++k) {
            size_t n = first[k + 1] - first[k];
            M[k].members = n;
            if (n == 0) { memset(M[k].vals, 0, (size_t)sub * sizeof(double)); continue; }   /* keeps its old mean */
            double *mean = M[k].mean, *cov = M[k].vecs;
            memset(mean, 0, (size_t)dim * sizeof(double));
            for (size_t j = first[k]; j < first[k + 1]; ++j) {
                if (prt__progress_poll(prog, j, 1023)) break;   /* one cluster may hold most vertices */
                for (int i = 0; i < dim; ++i) mean[i] += X[order[j] * dim + i];
            }
            for (int i = 0; i < dim; ++i) mean[i] /= (double)n;
            if (large) {
                if (!subspace(X, order + first[k], n, mean, dim, sub, d->seed + (uint64_t)k * 131 + (uint64_t)it * 7919, M[k].vecs,
                              small + (size_t)k * sub * sub, prog))
                    __atomic_store_n(&lapack_failed, 1, __ATOMIC_RELAXED);
                continue;
            }
            memset(cov, 0, (size_t)dim * dim * sizeof(double));
            double r[512];
            for (size_t j = first[k]; j < first[k + 1]; ++j) {
                if (prt__progress_poll(prog, j, 255)) break;
                for (int i = 0; i < dim; ++i) r[i] = X[order[j] * dim + i] - mean[i];
                for (int a = 0; a < dim; ++a)
                    for (int b = a; b < dim; ++b) cov[(size_t)a * dim + b] += r[a] * r[b];
            }
        }
        /* Cancelled while summing: the sums are partial, and subspace() may have given up. */
        if (prog && prt__progress_cancelled(prog)) { free(small); st = prt__fail(ctx, PRT_ERR_CANCELLED, "compression cancelled"); break; }
        /* Eigen decompositions one after another: OpenBLAS is not meant to be entered from several
         * OpenMP threads at once. Hundreds of them take seconds: look between them. */
        double *tmp = malloc((size_t)sub * dim * sizeof(double));
        bool stopped = false;
        for (int k = 0; k < K && tmp && !lapack_failed && large && !stopped; ++k) {
            if (M[k].members == 0) continue;
            if ((k & 7) == 7 && prog && prt__progress_cancelled(prog)) { stopped = true; break; }
            double *C = small + (size_t)k * sub * sub, w[FULL_EIGEN_MAX_DIM];
            if (LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', sub, C, sub, w) != 0) { lapack_failed = 1; break; }
            for (int j = 0; j < sub; ++j) {   /* descending; eigenvector j of the scatter = sum_a V[a][src] Q_a */
                int src = sub - 1 - j;
                M[k].vals[j] = w[src] > 0 ? w[src] : 0;
                double *out = tmp + (size_t)j * dim;
                memset(out, 0, (size_t)dim * sizeof(double));
                for (int a = 0; a < sub; ++a) {
                    const double va = C[(size_t)a * sub + src], *q = M[k].vecs + (size_t)a * dim;
                    for (int i = 0; i < dim; ++i) out[i] += va * q[i];
                }
            }
            memcpy(M[k].vecs, tmp, (size_t)sub * dim * sizeof(double));
        }
        free(small);
        for (int k = 0; k < K && tmp && !lapack_failed && !large && !stopped; ++k) {
            if (M[k].members == 0) continue;
            if ((k & 7) == 7 && prog && prt__progress_cancelled(prog)) { stopped = true; break; }
            double *cov = M[k].vecs, w[FULL_EIGEN_MAX_DIM];
            /* Row-major upper triangle; eigenvalues come back ascending, vectors in columns. */
            if (LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', dim, cov, dim, w) != 0) { lapack_failed = 1; break; }
            for (int j = 0; j < dim; ++j) {   /* descending order, one vector per row */
                int src = dim - 1 - j;
                M[k].vals[j] = w[src] > 0 ? w[src] : 0;
                for (int i = 0; i < dim; ++i) tmp[(size_t)j * dim + i] = cov[(size_t)i * dim + src];
            }
            memcpy(cov, tmp, (size_t)dim * dim * sizeof(double));
        }
        if (!tmp) lapack_failed = 1;
        free(tmp);
        if (stopped) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "compression cancelled"); break; }
        if (lapack_failed) { st = prt__fail(ctx, PRT_ERR_BACKEND, "LAPACK eigen decomposition failed"); break; }
        /* Half an iteration can take a second on large meshes: look before reassigning too. */
        if (prog && prt__progress_cancelled(prog)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "compression cancelled"); break; }
        for (int k = 0; k < K; ++k)
            if ((size_t)counts[k] > M[k].members) { total_vectors -= counts[k] - M[k].members; counts[k] = (uint32_t)M[k].members; }
        if (it == iterations) break;   /* the last pass only refits the final clusters */
        /* Spend the vector budget gradually over the first half of the iterations, each vector
         * where the next eigenvalue per member vertex - the error it removes per vertex - is largest. */
        size_t half = iterations > 1 ? (size_t)iterations / 2 : 1;
        size_t target = (size_t)it + 1 >= half ? budget : budget * ((size_t)it + 1) / half;
        while (total_vectors < target) {
            int pick = -1;
            double gain = 0;
            for (int k = 0; k < K; ++k) {
                if (counts[k] >= (uint32_t)keep || counts[k] >= M[k].members || M[k].members == 0) continue;
                double g = M[k].vals[counts[k]] / (double)M[k].members;
                if (g > gain) { gain = g; pick = k; }
            }
            if (pick < 0) break;
            counts[pick]++;
            total_vectors++;
        }
        /* Reassign every vertex to the cluster that reconstructs it best. */
        size_t moved = 0;
#pragma omp parallel for schedule(static) num_threads(team(ctx, (double)nv * dim * (large ? 5 : K) * (K ? total_vectors / (size_t)K + 1 : 1))) reduction(+ : moved)
        for (size_t v = 0; v < nv; ++v) {
            if (prt__progress_poll(prog, v, 255)) continue;   /* assign[v] stays: the pass is thrown away */
            double be = INFINITY;
            uint32_t bk = assign[v];
            /* Long vectors try their own cluster and the four with the nearest means only: testing
             * every cluster's subspace would cost K times the vector's length times its vectors. */
            enum { NEAR = 4 };
            int cand[NEAR + 1], nc = 0;
            if (large) {
                double cd[NEAR];
                for (int k = 0; k < K; ++k) {
                    if (M[k].members == 0 || k == (int)assign[v]) continue;
                    double e = 0;
                    for (int i = 0; i < dim; ++i) { double t = X[v * dim + i] - M[k].mean[i]; e += t * t; }
                    int pos = nc < NEAR ? nc++ : NEAR;
                    if (pos == NEAR && e >= cd[NEAR - 1]) continue;
                    if (pos == NEAR) pos = NEAR - 1;
                    while (pos > 0 && cd[pos - 1] > e) { cd[pos] = cd[pos - 1]; cand[pos] = cand[pos - 1]; pos--; }
                    cd[pos] = e;
                    cand[pos] = k;
                }
                cand[nc++] = (int)assign[v];
            }
            for (int ci = 0; ci < (large ? nc : K); ++ci) {
                int k = large ? cand[ci] : ci;
                if (M[k].members == 0 && k != (int)assign[v]) continue;
                double e = recon_err(X + v * dim, &M[k], dim, (int)counts[k]);
                if (e < be || (e == be && (uint32_t)k < bk)) { be = e; bk = (uint32_t)k; }
            }
            moved += bk != assign[v];
            assign[v] = bk;
        }
        if (prog) prt__progress_add(prog, 1);
        if (prog && prt__progress_cancelled(prog)) { st = prt__fail(ctx, PRT_ERR_CANCELLED, "compression cancelled"); break; }
        if (moved == 0 && total_vectors == budget) it = iterations - 1;   /* converged: go to the final refit */
    }
    if (!nested) openblas_set_num_threads(blas_threads);
    if (st) goto done;
    /* Keep the non-empty clusters; store means, vectors and per-vertex weights. */
    prt__cpca *c = prt__calloc(1, sizeof *c);
    int *remap = prt__calloc((size_t)K, sizeof(int));
    if (!c || !remap) { free(c); free(remap); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
    int kept = 0;
    size_t vec_total = 0;
    for (int k = 0; k < K; ++k) {
        remap[k] = M[k].members ? kept++ : -1;
        if (M[k].members) vec_total += counts[k];
    }
    c->method = d->method;
    c->clusters = kept;
    c->dim = dim;
    c->vectors_total = vec_total;
    c->counts = prt__calloc((size_t)kept, sizeof(uint32_t));
    c->means = prt__calloc((size_t)kept * dim, sizeof(float));
    c->basis = prt__calloc(vec_total ? vec_total * dim : 1, sizeof(float));
    c->cluster_of = prt__calloc(nv, sizeof(uint32_t));
    if (!c->counts || !c->means || !c->basis || !c->cluster_of) { free(remap); prt__cpca_free(c); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
    size_t vb = 0;
    for (int k = 0; k < K; ++k) {
        if (remap[k] < 0) continue;
        c->counts[remap[k]] = counts[k];
        for (int i = 0; i < dim; ++i) c->means[(size_t)remap[k] * dim + i] = (float)M[k].mean[i];
        for (uint32_t j = 0; j < counts[k]; ++j, ++vb)
            for (int i = 0; i < dim; ++i) c->basis[vb * dim + i] = (float)M[k].vecs[(size_t)j * dim + i];
    }
    size_t wt = 0;
    for (size_t v = 0; v < nv; ++v) { c->cluster_of[v] = (uint32_t)remap[assign[v]]; wt += counts[assign[v]]; }
    free(remap);
    c->weights_total = wt;
    c->weights = prt__calloc(wt ? wt : 1, sizeof(float));
    if (!c->weights || !prt__cpca_index(c, nv)) { prt__cpca_free(c); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
    /* Per-vertex errors summed in vertex order afterwards: the reported errors are bytes of the
     * file, the same for any thread count. */
    double *verr = prt__calloc(2 * nv, sizeof(double));
    if (!verr) { prt__cpca_free(c); st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); goto done; }
#pragma omp parallel for schedule(static) num_threads(team(ctx, (double)nv * dim * (wt / (nv ? nv : 1) + 1)))
    for (size_t v = 0; v < nv; ++v) {
        if (prt__progress_poll(prog, v, 1023)) continue;
        uint32_t k = c->cluster_of[v];
        const float *x = X + v * dim, *m = c->means + (size_t)k * dim;
        float rec[dim];   /* a few KB at most: 3 x 625 floats for order-5 RGB matrices */
        for (int i = 0; i < dim; ++i) rec[i] = m[i];
        for (uint32_t j = 0; j < c->counts[k]; ++j) {
            const float *b = c->basis + (c->basis_start[k] + j) * dim;
            double p = 0;
            for (int i = 0; i < dim; ++i) p += (double)b[i] * (x[i] - m[i]);
            c->weights[c->weight_start[v] + j] = (float)p;
            for (int i = 0; i < dim; ++i) rec[i] += (float)p * b[i];
        }
        verr[v] = dist2(x, rec, dim);
        double n2 = 0;
        for (int i = 0; i < dim; ++i) n2 += (double)x[i] * x[i];
        verr[nv + v] = n2;
    }
    if (prog && prt__progress_cancelled(prog)) { free(verr); prt__cpca_free(c); st = prt__fail(ctx, PRT_ERR_CANCELLED, "compression cancelled"); goto done; }
    double err = 0, norm = 0;
    for (size_t v = 0; v < nv; ++v) { err += verr[v]; norm += verr[nv + v]; }
    free(verr);
    c->rms_error = sqrt(err / (double)nv);
    c->relative_error = norm > 0 ? sqrt(err / norm) : 0;
    *out = c;
done:
    if (M)
        for (int k = 0; k < K; ++k) { free(M[k].mean); free(M[k].vecs); free(M[k].vals); }
    free(M); free(assign); free(counts); free(order); free(first); free(best);
    return st;
}
