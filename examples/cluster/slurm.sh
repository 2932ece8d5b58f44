#!/bin/sh
# A prt bake spread over a Slurm cluster as job arrays, one array per stage that can be spread
# (docs/CLUSTER.md). Run it on the login node, in a folder every node sees at the same path (the
# scene, the shards and the merged stages live there):
#     sh slurm.sh scene.obj out.prt 16 --method sh --order 6 --samples 2048 --bounces 2
# Each array task bakes shard I/N of the next stage; one merge job, after the whole array, puts the
# stage together and says `next K` (another round) or `done` (out.prt is written).
set -eu
SCENE=$1 OUT=$2 N=$3
shift 3
PRT=${PRT:-prt}
CPUS=${CPUS:-16}            # cores per task: each shard runs on all of its task's cores
from="" round=0
while :; do
    # The array: task I computes slice I of N (SLURM_ARRAY_TASK_ID counts from 1 here).
    job=$(sbatch --parsable --array=1-"$N" --cpus-per-task="$CPUS" --job-name="prt-$round" --wrap \
        "$PRT bake '$SCENE' $* ${from:+--from '$from'} -j $CPUS -q --shard \$SLURM_ARRAY_TASK_ID/$N -o '$OUT.$round.'\$SLURM_ARRAY_TASK_ID.shard")
    # The merge, once every task of the array has ended well; its stdout says what comes next.
    merge=$(sbatch --parsable --dependency=afterok:"$job" --cpus-per-task="$CPUS" --job-name="prt-merge-$round" \
        --output="$OUT.$round.next" --wrap "$PRT merge -q -j $CPUS $OUT.$round.*.shard -o '$OUT.merged.$round'")
    # Wait for it (srun --dependency would hold a node; polling squeue holds nothing).
    while squeue -h -j "$merge" 2>/dev/null | grep -q .; do sleep 30; done
    next=$(cat "$OUT.$round.next" 2>/dev/null || true)
    case $next in
    done) mv "$OUT.merged.$round" "$OUT"; rm -f "$OUT".*.shard "$OUT".*.next "$OUT".merged.*; echo "wrote $OUT"; exit 0 ;;
    "next "*) from="$OUT.merged.$round"; round=$((round + 1)) ;;
    *) echo "slurm.sh: the merge of round $round failed (see slurm-$merge.out)" >&2; exit 1 ;;
    esac
done
