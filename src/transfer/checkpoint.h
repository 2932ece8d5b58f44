/* Checkpoints of a bake: every finished work unit's results, appended to a file as the unit
 * completes, so that a bake killed at any moment (kill -9 included) continues from where it was
 * (prt_bake_run_desc.checkpoint / resume).
 *
 * The file is a log: a header naming the bake (a fingerprint of the library version, the method,
 * its options and the scene), then records (stage, unit, payload) each with its own checksums.
 * A record is only ever appended whole; a torn last record (the process died inside write) fails
 * its checksum and is cut off when the bake resumes, so no rename dance is needed. Records are
 * written by whichever thread finished the unit, under a lock; stages whose units cannot be
 * restored (and the `whole` steps) run again on resume, deterministically. */
#ifndef PRT_TRANSFER_CHECKPOINT_H
#define PRT_TRANSFER_CHECKPOINT_H

#include "core/internal.h"

typedef struct prt__checkpoint prt__checkpoint;

/* The fingerprint of a bake: two independent 64-bit hashes of everything its results depend on. */
typedef struct prt__fingerprint { uint64_t a, b; } prt__fingerprint;
void prt__fingerprint_add(prt__fingerprint *f, const void *data, size_t size);

/* Opens path for the bake with fingerprint fp. With resume, an existing file's valid records are
 * indexed (a file of another bake is an error saying so; a missing file is an empty checkpoint);
 * without, any old file is replaced. */
prt_status prt__checkpoint_open(const prt_context *ctx, const char *path, const prt__fingerprint *fp, bool resume, prt__checkpoint **out);
/* Opens an existing checkpoint to read only (no lock, no repair, nothing appended: many bakes may
 * read one at once). fp NULL accepts any bake's; *got (may be NULL) is the file's fingerprint. */
prt_status prt__checkpoint_open_read(const prt_context *ctx, const char *path, const prt__fingerprint *fp, prt__fingerprint *got,
                                     prt__checkpoint **out);
/* The records in (stage, unit) order: their count, and the key of record i. */
size_t prt__checkpoint_size(const prt__checkpoint *c);
void prt__checkpoint_key(const prt__checkpoint *c, size_t i, int *stage, uint64_t *unit);
/* False for a checkpoint opened to read only (appends are dropped). */
bool prt__checkpoint_writable(const prt__checkpoint *c);
/* The stage number of a shard's description record (transfer/shard.c): above any bake's. */
#define PRT__CHECKPOINT_SHARD_STAGE 4096
/* Units of stage recorded in the file. */
uint64_t prt__checkpoint_count(const prt__checkpoint *c, int stage);
/* The payload of (stage, unit) into out (replacing its contents); false when not recorded. */
bool prt__checkpoint_find(prt__checkpoint *c, int stage, uint64_t unit, prt__bytes *out);
/* Appends a record; thread-safe. A failure to write turns checkpointing off with one warning. */
void prt__checkpoint_append(prt__checkpoint *c, int stage, uint64_t unit, const void *data, size_t size);
/* Records the file holds (read at open plus appended since). */
uint64_t prt__checkpoint_records(const prt__checkpoint *c);
/* Closes; remove deletes the file (the bake finished and its result is the caller's now). */
void prt__checkpoint_close(prt__checkpoint *c, bool remove);

#endif
