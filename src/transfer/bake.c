/* The bake driver shared by every method: stages of independent work units on all threads, with
 * progress, cancellation, checkpoints and timing written once (see prt__bake_job in
 * transfer/method.h and transfer/checkpoint.h). */
#include "transfer/method.h"
#include "transfer/checkpoint.h"
#include "transfer/shard.h"

#include <omp.h>

/* Puts back the units of stage `index` that the checkpoint holds; marks them in restored. */
static prt_status restore_units(prt_context *ctx, prt__bake_job *job, const prt__stage *s, int index, prt__checkpoint *cp,
                                unsigned char *restored, uint64_t *count)
{
    int bad = 0;
    uint64_t n = 0, bad_unit = 0;
#pragma omp parallel num_threads(job->threads) reduction(+ : n)
    {
        prt__bytes buf = {0};
#pragma omp for schedule(dynamic, 16)
        for (uint64_t u = 0; u < s->units; ++u) {
            if (__atomic_load_n(&bad, __ATOMIC_RELAXED) || !prt__checkpoint_find(cp, index, u, &buf)) continue;
            if (!s->load_unit(job, u, buf.data, buf.size)) {
                if (!__atomic_exchange_n(&bad, 1, __ATOMIC_RELAXED)) bad_unit = u;
                continue;
            }
            restored[u] = 1;
            n++;
        }
        prt__bytes_free(&buf);
    }
    *count = n;
    if (bad)
        return prt__fail(ctx, PRT_ERR_FORMAT, "the checkpoint's record of %s, unit %llu, does not fit this bake (a damaged file?); "
                         "delete the checkpoint, or bake without resuming", s->name, (unsigned long long)bad_unit);
    return PRT_OK;
}

/* One stage's units as they are run here or handed in from elsewhere (prt_bake_work in prt/method.h). */
struct prt_bake_work {
    prt__bake_job *job;
    const prt__stage *s;
    int index;
    unsigned char *done;        /* [units] */
    prt__bytes *out;            /* [threads] each thread's record */
    prt__checkpoint *record_to; /* appends (NULL: none) */
    prt__progress *prog;
};

int prt_bake_work_stage(const prt_bake_work *w) { return w->index; }
const char *prt_bake_work_name(const prt_bake_work *w) { return w->s->name; }
uint64_t prt_bake_work_units(const prt_bake_work *w) { return w->s->units; }
int prt_bake_work_threads(const prt_bake_work *w) { return w->job->threads; }
int prt_bake_work_done(const prt_bake_work *w, uint64_t unit) { return unit < w->s->units && __atomic_load_n(&w->done[unit], __ATOMIC_ACQUIRE); }
int prt_bake_work_cancelled(const prt_bake_work *w) { return prt__progress_cancelled(w->prog); }

prt_status prt_bake_work_record(prt_bake_work *w, uint64_t unit, int thread, const void **data, size_t *size)
{
    if (!w->s->save_unit || !prt_bake_work_done(w, unit) || thread < 0 || thread >= w->job->threads)
        return prt__fail(w->job->ctx, PRT_ERR_INVALID_ARG, "prt_bake_work_record: unit %llu of %s is not done, or thread %d out of range",
                         (unsigned long long)unit, w->s->name, thread);
    prt__bytes *b = &w->out[thread];
    b->size = 0;
    b->failed = false;
    w->s->save_unit(w->job, unit, b);
    if (b->failed) return prt__fail(w->job->ctx, PRT_ERR_NO_MEMORY, "out of memory");
    *data = b->data;
    *size = b->size;
    return PRT_OK;
}

prt_status prt_bake_work_run(prt_bake_work *w, uint64_t unit, int thread, const void **data, size_t *size)
{
    if (unit >= w->s->units || thread < 0 || thread >= w->job->threads)
        return prt__fail(w->job->ctx, PRT_ERR_INVALID_ARG, "prt_bake_work_run: unit %llu or thread %d out of range", (unsigned long long)unit, thread);
    prt_status st = w->s->run(w->job, unit, thread);
    if (st) return st;
    __atomic_store_n(&w->done[unit], 1, __ATOMIC_RELEASE);
    prt__progress_add(w->prog, 1);
    if (!data && (!w->record_to || !w->s->save_unit)) return PRT_OK;
    const void *d;
    size_t n;
    if (prt_bake_work_record(w, unit, thread, &d, &n)) {
        if (data) return PRT_ERR_NO_MEMORY;
        return PRT_OK;   /* out of memory loses this unit's checkpoint record, not the bake */
    }
    if (w->record_to) prt__checkpoint_append(w->record_to, w->index, unit, d, n);
    if (data) { *data = d; *size = n; }
    return PRT_OK;
}

prt_status prt_bake_work_put(prt_bake_work *w, uint64_t unit, const void *data, size_t size)
{
    if (unit >= w->s->units) return prt__fail(w->job->ctx, PRT_ERR_FORMAT, "a record of %s names unit %llu of %llu", w->s->name,
                                              (unsigned long long)unit, (unsigned long long)w->s->units);
    if (!w->s->load_unit(w->job, unit, data, size))
        return prt__fail(w->job->ctx, PRT_ERR_FORMAT, "the record of %s, unit %llu, does not fit this bake", w->s->name, (unsigned long long)unit);
    if (!__atomic_exchange_n(&w->done[unit], 1, __ATOMIC_ACQ_REL)) prt__progress_add(w->prog, 1);
    if (w->record_to) prt__checkpoint_append(w->record_to, w->index, unit, data, size);
    return PRT_OK;
}

/* Runs the units not yet done here on all threads; only those of slice shard/of when of > 0. */
static prt_status run_units(prt_context *ctx, prt_bake_work *w, int shard, int of)
{
    int failed = 0;
    prt_status first = PRT_OK;
    char why[512] = "";   /* errors are recorded per thread: keep the failing unit's */
    /* Units are claimed in order by whichever thread is free; each writes only its own
     * outputs, so the result is the same for any thread count and schedule. */
#pragma omp parallel for schedule(dynamic, 1) num_threads(w->job->threads)
    for (uint64_t u = 0; u < w->s->units; ++u) {
        if (w->done[u] || (of && u % (uint64_t)of != (uint64_t)(shard - 1)) || __atomic_load_n(&failed, __ATOMIC_RELAXED) ||
            prt__progress_cancelled(w->prog))
            continue;
        prt_status r = prt_bake_work_run(w, u, omp_get_thread_num(), NULL, NULL);
        if (r && !__atomic_exchange_n(&failed, 1, __ATOMIC_RELAXED)) {
            first = r;
            snprintf(why, sizeof why, "%s", prt_last_error());
        }
    }
    return first ? prt__fail(ctx, first, "%s", why[0] ? why : prt_status_string(first)) : PRT_OK;
}

/* The bake's checkpoints: `from` to resume from (read only when not writable), the shard to write,
 * the fingerprint both are named by. */
typedef struct drive_io {
    prt__checkpoint *from;
    const char *from_path;
    const prt__fingerprint *fp;
} drive_io;

static prt_status drive(prt_context *ctx, prt__bake_job *job, const prt_bake_run_desc *run, const drive_io *io, prt_transfer *t,
                        int *stopped)
{
    const double start = prt__now();
    const uint64_t limit = job->memory_limit ? job->memory_limit : UINT64_MAX;
    prt__progress prog = {run ? run->progress : NULL, run ? run->progress_user : NULL, NULL, 0, 0, 0.0, 0, ctx};
    prt__checkpoint *cp = io ? io->from : NULL, *shard = NULL;
    const bool sharding = run && run->shard_count > 0, stopping = run && run->stop_at_missing;
    *stopped = -1;
    job->ctx = ctx;
    job->threads = prt__threads(ctx);
    uint64_t recovered = 0, total = 0;
    prt__bytes *out = prt__calloc((size_t)job->threads, sizeof *out);
    prt_status st = !out ? prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory") : PRT_OK;
    for (int index = 0; !st && *stopped < 0; ++index) {
        prt__stage s;
        memset(&s, 0, sizeof s);
        if ((st = job->stage(job, index, &s))) break;
        if (!s.units && !s.whole) break;
        const bool spreadable = s.units && s.save_unit && s.load_unit;
        prt__progress_begin(&prog, s.name, s.whole ? 1 : s.units);
        if (s.whole) {
            if (run && run->stage_seen) run->stage_seen(run->stage_user, index, s.name, 0, 0, 0);
            st = s.whole(job, ctx, &prog);
        } else {
            total += s.units;
            prt_bake_work w = {job, &s, index, prt__calloc((size_t)s.units, 1), out, prt__checkpoint_writable(cp) ? cp : NULL, &prog};
            if (!w.done) { st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory"); break; }
            uint64_t from_checkpoint = 0;
            if (cp && s.load_unit && prt__checkpoint_count(cp, index)) {
                if ((st = restore_units(ctx, job, &s, index, cp, w.done, &from_checkpoint))) { free(w.done); break; }
                prt__log(ctx, PRT_LOG_INFO, "%s: %llu of %llu work units recovered from the checkpoint", s.name,
                         (unsigned long long)from_checkpoint, (unsigned long long)s.units);
                recovered += from_checkpoint;
                prt__progress_add(&prog, from_checkpoint);
            }
            if (run && run->stage_seen) run->stage_seen(run->stage_user, index, s.name, s.units, spreadable, from_checkpoint);
            const bool missing = spreadable && from_checkpoint < s.units;
            if (missing && (sharding || stopping)) {
                *stopped = index;
                if (sharding && run->stage_given && run->stage < index)
                    st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "stage %d is not the next to spread: the checkpoint holds it, and stage %d (%s) "
                                   "comes next", run->stage, index, s.name);
                else if (sharding && run->stage_given && run->stage > index)
                    st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "stage %d is not the next to spread: stage %d (%s) comes first, and %s", run->stage,
                                   index, s.name, cp ? "the checkpoint holds it only in part" : "no finished stages were given");
                else if (sharding && !(st = prt__checkpoint_open(ctx, run->shard, io->fp, false, &shard))) {
                    w.record_to = shard;
                    st = run_units(ctx, &w, run->shard_index, run->shard_count);
                    if (!st && !prt__progress_cancelled(&prog))
                        st = prt__shard_describe(ctx, shard, run, index, s.name, s.units, cp, io->from_path);
                }
            } else if (spreadable && run && run->spread) {
                /* Every process of a spread bake takes part in every spreadable stage, even one
                 * this process holds whole: the others wait on it. */
                st = run->spread(run->spread_user, &w);
                for (uint64_t u = 0; !st && u < s.units; ++u)
                    if (!w.done[u]) st = prt__fail(ctx, PRT_ERR_BACKEND, "%s: unit %llu was left undone by the spread", s.name, (unsigned long long)u);
            } else {
                st = run_units(ctx, &w, 0, 0);
            }
            free(w.done);
        }
        if (!st) prt__progress_end(&prog);
        if (!st && prt__progress_cancelled(&prog)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    }
    if (!st && sharding && *stopped < 0) {
        if (run->stage_given) st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "stage %d: no stage is left to spread (the checkpoint holds them all)", run->stage);
        else if (!(st = prt__checkpoint_open(ctx, run->shard, io->fp, false, &shard)))
            st = prt__shard_describe(ctx, shard, run, -1, "", 0, cp, io->from_path);
        *stopped = -1;
    }
    if (shard) prt__checkpoint_close(shard, st != PRT_OK);
    if (!st && !(sharding || (stopping && *stopped >= 0))) st = job->finish(job, t);
    const int threads = job->threads;   /* release frees the job */
    job->release(job);
    for (int i = 0; out && i < threads; ++i) prt__bytes_free(&out[i]);
    free(out);
    if (run && run->recovered_units) *run->recovered_units = recovered;
    if (run && run->total_units) *run->total_units = total;
    if (!st) {
        t->bake_seconds = prt__now() - start;
        t->threads = prt__threads(ctx);
        t->peak_bytes = prt_memory_peak_resident();
        t->memory_limit = limit;
    }
    return st;
}

prt_status prt__bake_drive_checkpointed(prt_context *ctx, prt__bake_job *job, const prt_bake_run_desc *run, prt__checkpoint *cp,
                                        prt_transfer *t)
{
    const drive_io io = {cp, NULL, NULL};
    int stopped;
    return drive(ctx, job, run, &io, t, &stopped);
}

prt_status prt__bake_drive(prt_context *ctx, prt__bake_job *job, const prt_bake_run_desc *run, prt_transfer *t)
{
    return prt__bake_drive_checkpointed(ctx, job, run, NULL, t);
}

void prt__transfer_fingerprint_scene(const prt_transfer *t, prt__fingerprint *fp)
{
    const prt__mesh *mesh = &t->mesh;
    const size_t nv = mesh->vertex_count, nt = mesh->triangle_count;
    prt__fingerprint_add(fp, &nv, sizeof nv);
    prt__fingerprint_add(fp, &nt, sizeof nt);
    prt__fingerprint_add(fp, mesh->positions, nv * 3 * sizeof(float));
    prt__fingerprint_add(fp, mesh->normals, nv * 3 * sizeof(float));
    prt__fingerprint_add(fp, mesh->albedo, nv * 3 * sizeof(float));
    prt__fingerprint_add(fp, mesh->material, nv);
    if (mesh->uv) prt__fingerprint_add(fp, mesh->uv, nv * 2 * sizeof(float));
    if (mesh->emission) prt__fingerprint_add(fp, mesh->emission, nv * 3 * sizeof(float));
    prt__fingerprint_add(fp, mesh->indices, nt * 3 * sizeof(uint32_t));
    prt__fingerprint_add(fp, &t->brdf_count, sizeof t->brdf_count);
    for (int i = 0; i < t->brdf_count; ++i) {
        /* Field by field at full precision: not the struct's padding, not lobes it does not use. */
        const prt_brdf *b = &t->brdfs[i];
        const int model = (int)b->model, lobes = b->lobes > 0 && b->lobes <= PRT_BRDF_MAX_LOBES ? b->lobes : 0;
        prt__fingerprint_add(fp, &model, sizeof model);
        prt__fingerprint_add(fp, b->diffuse, sizeof b->diffuse);
        prt__fingerprint_add(fp, b->specular, sizeof b->specular);
        prt__fingerprint_add(fp, &b->exponent, sizeof b->exponent);
        prt__fingerprint_add(fp, &b->exponent_v, sizeof b->exponent_v);
        prt__fingerprint_add(fp, &lobes, sizeof lobes);
        for (int l = 0; l < lobes; ++l) {
            prt__fingerprint_add(fp, b->cxy[l], sizeof b->cxy[l]);
            prt__fingerprint_add(fp, b->cz[l], sizeof b->cz[l]);
            prt__fingerprint_add(fp, b->n[l], sizeof b->n[l]);
        }
    }
}

uint64_t prt__memory_scene_bytes(const prt_transfer *t)
{
    const prt__mesh *m = &t->mesh;
    const uint64_t nv = m->vertex_count, nt = m->triangle_count;
    /* Positions, normals, albedo, UVs, emission, material, surface and the vertex origins every
     * bake sends rays from; the indices; Embree's tree with its triangles (about 100 bytes a
     * triangle at its build quality, measured on Sponza). The loaded scene the bake copied from
     * stays too: twice the mesh. */
    const uint64_t mesh = nv * (3 + 3 + 3 + 2 + (m->emission ? 3 : 0)) * sizeof(float) + nv * 3 + nt * 3 * sizeof(uint32_t);
    return 2 * mesh + nv * 3 * sizeof(float) + nt * 100;
}

/* The memory the bake may hold and the method's estimate of it (options bakes only): refused up
 * front when even streaming would not fit. */
static prt_status memory_check(prt_context *ctx, const prt__method *m, const prt_options *o, const prt_transfer *t, uint64_t limit, bool *over)
{
    *over = false;
    prt__memory_estimate e;
    memset(&e, 0, sizeof e);
    if (m->memory_estimate) m->memory_estimate(t, o, prt__threads(ctx), &e);
    const uint64_t scene = prt__memory_scene_bytes(t), bytes = scene + e.bytes, least = scene + (e.least ? e.least : e.bytes);
    char b[32], l[32], lim[32];
    prt_memory_size_format(bytes, b, sizeof b);
    prt_memory_size_format(least, l, sizeof l);
    prt_memory_size_format(limit, lim, sizeof lim);
    if (least > limit)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "baking %zu vertices with --method %s would need about %s%s%s%s%s%s%s, over the memory limit of %s: %s%s"
                         "or raise --memory-limit", t->mesh.vertex_count, m->name, l, least < bytes ? " even streaming, " : "", least < bytes ? b : "",
                         least < bytes ? " without" : "", e.what[0] ? " (" : "", e.what, e.what[0] ? ")" : "", lim, e.lower[0] ? e.lower : "",
                         e.lower[0] ? " lower it, " : "");
    *over = bytes > limit;
    if (*over)
        prt__log(ctx, PRT_LOG_INFO, "memory: the bake's estimate is %s%s%s%s, over the limit of %s: it streams, holding about %s", b, e.what[0] ? " (" : "",
                 e.what, e.what[0] ? ")" : "", lim, l);
    else
        prt__log(ctx, PRT_LOG_INFO, "memory: the bake's estimate is %s%s%s%s (limit %s)", b, e.what[0] ? " (" : "", e.what, e.what[0] ? ")" : "", lim);
    return PRT_OK;
}

/* Everything a bake's results depend on, so that a checkpoint is only ever resumed by the same
 * bake: the library version, the method and its options, and the scene as the transfer holds it. */
static void fingerprint(const prt__method *m, const prt_options *o, const prt_transfer *t, const prt_scene *scene, prt__fingerprint *fp)
{
    memset(fp, 0, sizeof *fp);
    const char *v = prt_version_string();
    prt__fingerprint_add(fp, v, strlen(v) + 1);
    prt__fingerprint_add(fp, m->name, strlen(m->name) + 1);
    prt__options_fingerprint(o, fp);
    prt__transfer_fingerprint_scene(t, fp);
    /* BRDF sets decide which vertices have glossy rows (only where kept: older checkpoints stay valid). */
    for (int i = 0; m->brdf_set && i < scene->brdf_set_count; ++i) {
        prt__fingerprint_add(fp, &scene->brdf_set[i].surface, sizeof scene->brdf_set[i].surface);
        prt__fingerprint_add(fp, &scene->brdf_set[i].brdf, sizeof scene->brdf_set[i].brdf);
    }
    /* Translucent and specular surfaces change what units compute (only where named: older
     * checkpoints stay valid); field by field, names with their terminators. */
    for (int i = 0; i < scene->medium_count; ++i) {
        const prt_medium *md = &scene->media[i].m;
        prt__fingerprint_add(fp, scene->media[i].name, strlen(scene->media[i].name) + 1);
        prt__fingerprint_add(fp, md->sigma_a, sizeof md->sigma_a);
        prt__fingerprint_add(fp, md->sigma_s, sizeof md->sigma_s);
        prt__fingerprint_add(fp, &md->eta, sizeof md->eta);
        prt__fingerprint_add(fp, &md->falloff_mm, sizeof md->falloff_mm);
    }
    for (int i = 0; i < scene->specular_count; ++i) {
        const prt_specular *sp = &scene->speculars[i].s;
        const int32_t type = (int32_t)sp->type;
        prt__fingerprint_add(fp, scene->speculars[i].name, strlen(scene->speculars[i].name) + 1);
        prt__fingerprint_add(fp, &type, sizeof type);
        prt__fingerprint_add(fp, &sp->reflectance, sizeof sp->reflectance);
        prt__fingerprint_add(fp, &sp->ior, sizeof sp->ior);
    }
    /* Volumes shadow the surfaces (only where named: older checkpoints stay valid). */
    for (int i = 0; i < scene->volume_count; ++i) {
        const prt__volume *v = &scene->volumes[i];
        prt__fingerprint_add(fp, v->dims, sizeof v->dims);
        prt__fingerprint_add(fp, v->lo, sizeof v->lo);
        prt__fingerprint_add(fp, v->hi, sizeof v->hi);
        prt__fingerprint_add(fp, &v->sigma_t, sizeof v->sigma_t);
        prt__fingerprint_add(fp, v->albedo, sizeof v->albedo);
        prt__fingerprint_add(fp, &v->g, sizeof v->g);
        prt__fingerprint_add(fp, v->density, prt__volume_voxels(v) * sizeof(float));
    }
}

static prt_status begin_from_options(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job);

prt_status prt__bake_with(prt_context *ctx, const prt_scene *scene, const prt__method *m, prt__bake_begin_fn begin, const void *desc,
                          const prt_bake_run_desc *run, prt_transfer **out)
{
    if (!ctx || !scene || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "bake: context, scene and out are required");
    *out = NULL;
    prt_transfer *t = NULL;
    /* Copying a mesh of tens of millions of triangles takes a second: not when already stopped. */
    prt_status st = prt__cancelled(ctx) ? prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled") : prt__transfer_from_scene(ctx, m, scene, &t);
    prt__bake_job *job = NULL;
    prt__checkpoint *cp = NULL;
    prt__fingerprint fp = {0, 0};
    /* Shards and merges read their checkpoint, which many processes may share, and write nothing to it. */
    const bool reading = run && (run->shard_count > 0 || run->stop_at_missing);
    if (!st && run && run->shard_count > 0 && (run->shard_index < 1 || run->shard_index > run->shard_count || !run->shard))
        st = prt__fail(ctx, PRT_ERR_INVALID_ARG, "bake: shard %d/%d is not one of 1..%d, or no shard file was given", run->shard_index,
                       run->shard_count, run->shard_count);
    /* The memory the bake may hold: said up front, before the checkpoint (a refusal leaves one
     * to resume as it was), the ray caster and the origins. */
    const uint64_t limit = !run || !run->memory_limit ? prt_memory_default_limit() : run->memory_limit;
    bool over = false;
    if (!st && begin == begin_from_options) st = memory_check(ctx, m, desc, t, limit, &over);
    /* Setting up a bake of tens of millions of triangles takes seconds a step: look between steps. */
    if (!st && prt__cancelled(ctx)) st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    if (!st && run && (run->checkpoint || run->shard_count > 0)) {
        /* Only prt_bake passes options as desc (checkpoints need them for the fingerprint). */
        fingerprint(m, desc, t, scene, &fp);
        if (run->checkpoint && reading) st = prt__checkpoint_open_read(ctx, run->checkpoint, &fp, NULL, &cp);
        else if (run->checkpoint) st = prt__checkpoint_open(ctx, run->checkpoint, &fp, run->resume != 0, &cp);
    }
    if (!st) st = begin(ctx, scene, desc, t, &job);
    if (!st) {
        job->memory_limit = limit;
        job->memory_over = over;
    }
    if (!st && prt__cancelled(ctx)) {
        job->release(job);
        st = prt__fail(ctx, PRT_ERR_CANCELLED, "bake cancelled");
    }
    int stopped = -1;
    const drive_io io = {cp, run ? run->checkpoint : NULL, &fp};
    if (!st) st = drive(ctx, job, run, &io, t, &stopped);
    if (run && run->stopped_stage) *run->stopped_stage = stopped;
    /* A checkpoint stays when its bake can go on later: cancelled, or stopped by memory, I/O or a
     * backend. One without a finished unit, or of a bake that would fail the same way again (bad
     * options, bad input), goes, so that the next bake is not asked whether to resume it. */
    const bool worth_keeping = st == PRT_ERR_CANCELLED || st == PRT_ERR_NO_MEMORY || st == PRT_ERR_IO || st == PRT_ERR_BACKEND;
    prt__checkpoint_close(cp, st != PRT_OK && (!worth_keeping || prt__checkpoint_records(cp) == 0));
    if (!st && (stopped >= 0 || (run && run->shard_count > 0))) { prt_transfer_release(t); t = NULL; }   /* a shard, or stages remain */
    if (st) { prt_transfer_release(t); return st; }
    *out = t;
    return PRT_OK;
}

/* The table entry's begin, with the options as its desc. */
static prt_status begin_from_options(prt_context *ctx, const prt_scene *scene, const void *desc, prt_transfer *t, prt__bake_job **job)
{
    return t->method->bake_begin(ctx, scene, desc, t, job);
}

prt_status prt_bake(prt_context *ctx, const prt_scene *scene, const prt_method *m, const prt_options *o, const prt_bake_run_desc *run,
                    prt_transfer **out)
{
    if (!m) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake: a method is required");
    if (o && prt_options_method(o) != m)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake: options made for method %s, not %s", prt_method_name(prt_options_method(o)), m->name);
    if (prt__options_exporting(o))
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake takes bake options (prt_options_create), not export options");
    if (scene && scene->brdf_set_count && !m->brdf_set)
        prt__log(ctx, PRT_LOG_WARN, "the scene's materials list \"brdfs\" to switch among at run time, which %s files do not keep "
                 "(spectral files do): each surface keeps the BRDF it wears", m->name);
    return prt__bake_with(ctx, scene, m, begin_from_options, o, run, out);
}

/* Key frames must share their topology: a transfer row of one frame is a row of the same vertex
 * in every other, and the triangles between them the same. */
static prt_status same_topology(prt_context *ctx, const prt_scene *const *frames, int count)
{
    const size_t nv = prt_scene_vertex_count(frames[0]), nt = prt_scene_triangle_count(frames[0]);
    for (int f = 1; f < count; ++f) {
        const size_t v = prt_scene_vertex_count(frames[f]), t = prt_scene_triangle_count(frames[f]);
        if (v != nv || t != nt)
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frame %d differs in topology from key frame 1: %zu vertices and %zu triangles, not %zu and %zu",
                             f + 1, v, t, nv, nt);
        if (memcmp(prt_scene_indices(frames[f]), prt_scene_indices(frames[0]), nt * 3 * sizeof(uint32_t)))
            return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key frame %d differs in topology from key frame 1: its triangles join other vertices", f + 1);
    }
    return PRT_OK;
}

prt_status prt_bake_frames(prt_context *ctx, const prt_scene *const *frames, int count, const prt_method *m, const prt_options *o,
                           const prt_bake_run_desc *run, prt_transfer **out)
{
    if (!ctx || !frames || !m || !out) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake_frames: context, frames, method and out are required");
    *out = NULL;
    if (count < 2 || count > 1024) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "key-framed bakes take 2 to 1024 key frames (got %d)", count);
    for (int f = 0; f < count; ++f)
        if (!frames[f]) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake_frames: key frame %d is missing", f + 1);
    if (!m->join_frames) return prt__fail(ctx, PRT_ERR_INVALID_ARG, "%s transfer holds one pose: --method %s bakes no key frames", m->name, m->name);
    if (o && prt_options_method(o) != m)
        return prt__fail(ctx, PRT_ERR_INVALID_ARG, "prt_bake_frames: options made for method %s, not %s", prt_method_name(prt_options_method(o)), m->name);
    prt_status st = same_topology(ctx, frames, count);
    prt_options *ko = NULL;
    if (!st) st = prt__options_keyframe_copy(m, o, &ko);
    prt_transfer **baked = st ? NULL : prt__calloc((size_t)count, sizeof *baked);
    if (!st && !baked) st = prt__fail(ctx, PRT_ERR_NO_MEMORY, "out of memory");
    prt_bake_run_desc r = run ? *run : (prt_bake_run_desc){0};
    r.checkpoint = NULL;
    r.resume = 0;
    double seconds = 0;
    for (int f = 0; !st && f < count; ++f) {
        st = prt_bake(ctx, frames[f], m, ko, &r, &baked[f]);
        if (st) prt__fail(ctx, st, "key frame %d: %s", f + 1, prt_last_error());
        else seconds += baked[f]->bake_seconds;
    }
    if (!st) st = m->join_frames(ctx, baked, count, o, out);
    if (!st) (*out)->bake_seconds = seconds;
    for (int f = 0; baked && f < count; ++f) prt_transfer_release(baked[f]);
    free(baked);
    prt_options_release(ko);
    return st;
}
