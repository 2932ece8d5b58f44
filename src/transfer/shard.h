/* Shards of a bake (transfer/shard.c, docs/CLUSTER.md): a checkpoint-format file holding the
 * records of one slice of one stage's units, closed by a description record (stage
 * PRT__CHECKPOINT_SHARD_STAGE) that names the stage, the slice I/N and the checkpoint the bake
 * continued. A shard cut off before its description is not a shard. */
#ifndef PRT_TRANSFER_SHARD_H
#define PRT_TRANSFER_SHARD_H

#include "transfer/checkpoint.h"

#include <prt/method.h>

/* A digest of every record a checkpoint holds (zero for none): what a shard continued. */
prt_status prt__checkpoint_digest(const prt_context *ctx, prt__checkpoint *c, prt__fingerprint *out);
/* Appends the description record that makes the checkpoint shard a whole shard of stage `stage`
 * (-1: none was left to spread) with `units` units; from (may be NULL) is the checkpoint the bake
 * continued. */
prt_status prt__shard_describe(const prt_context *ctx, prt__checkpoint *shard, const prt_bake_run_desc *run, int stage, const char *name,
                               uint64_t units, prt__checkpoint *from, const char *from_path);

#endif
