#!/bin/sh
# prt bake under mpirun with 1 and 2 processes, and 2 shards plus a merge, against a plain bake
# of the same scene and options: wall seconds of each, bytes each stage's records take (what
# crosses the network), and whether the file is the plain bake's (outside META). On one machine
# the processes share its cores, so this measures the overhead of spreading (every process loads
# the scene and runs the whole steps; records go to rank 0 and back out), not a speed-up; across
# machines each rank brings its own cores. JSON on stdout.
# Scene: the Stanford bunny from SHARED_DATA (the procedural demo scene when absent).
# Usage: bench/cluster_ranks.sh PATH/TO/prt PATH/TO/same_chunks [SHARED_DATA]
#   THREADS per process (default: all cores / processes), METHOD and OPTIONS to bake.
set -eu
PRT=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SAME=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
DATA=${3:-../shared/data}
METHOD=${METHOD:-sh}
OPTIONS=${OPTIONS:---order 4 --samples 1024 --bounces 1}
T=$(mktemp -d /tmp/prt_cluster_bench_XXXXXX)
trap 'rm -rf "$T"' EXIT
if [ -f "$DATA/meshes/bunny/bun_zipper.ply" ]; then
    cp "$DATA/meshes/bunny/bun_zipper.ply" "$T/scene.ply"
    SCENE="$T/scene.ply"
else
    echo "cluster_ranks: no bunny in $DATA: the demo scene instead" >&2
    "$PRT" demo-scene -o "$T/demo.obj" >/dev/null
    SCENE="$T/demo.obj"
fi
CORES=$(nproc)
THREADS=${THREADS:-}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", b - a }'; }
# shellcheck disable=SC2086
set -- "$SCENE" --no-refine --method "$METHOD" $OPTIONS -q

t0=$(now); "$PRT" bake "$@" -j "${THREADS:-$CORES}" --no-checkpoint -o "$T/plain.prt"; t1=$(now)
plain=$(secs "$t0" "$t1")

ranks=""
if command -v mpirun >/dev/null 2>&1 && "$PRT" bake --help | grep -q "Under mpirun"; then
    for n in 1 2; do
        j=${THREADS:-$(( CORES / n > 0 ? CORES / n : 1 ))}
        t0=$(now); mpirun --oversubscribe -n $n "$PRT" bake "$@" -j "$j" -o "$T/mpi$n.prt"; t1=$(now)
        same=false; "$SAME" "$T/plain.prt" "$T/mpi$n.prt" && same=true
        ranks="$ranks${ranks:+, }{\"ranks\": $n, \"threads_each\": $j, \"seconds\": $(secs "$t0" "$t1"), \"same_bytes\": $same}"
    done
else
    echo "cluster_ranks: no mpirun, or prt built without MPI: the mpirun rows are left out" >&2
fi

# Two shards per stage, one after the other (as two machines would run them side by side).
j=${THREADS:-$CORES}
from="" rounds=0 shard_s=0 merge_s=0 stage_bytes=""
while :; do
    for i in 1 2; do
        t0=$(now); "$PRT" bake "$@" -j "$j" ${from:+--from "$from"} --shard $i/2 -o "$T/r$rounds.$i.shard"; t1=$(now)
        shard_s=$(awk -v a="$shard_s" -v b="$(secs "$t0" "$t1")" 'BEGIN { print a + b }')
    done
    bytes=$(cat "$T/r$rounds.1.shard" "$T/r$rounds.2.shard" | wc -c)
    stage_bytes="$stage_bytes${stage_bytes:+, }$bytes"
    t0=$(now); next=$("$PRT" merge -q -j "$j" "$T/r$rounds.1.shard" "$T/r$rounds.2.shard" -o "$T/m$rounds"); t1=$(now)
    merge_s=$(awk -v a="$merge_s" -v b="$(secs "$t0" "$t1")" 'BEGIN { print a + b }')
    [ "$next" = done ] && break
    from="$T/m$rounds"
    rounds=$((rounds + 1))
done
same=false; "$SAME" "$T/plain.prt" "$T/m$rounds" && same=true
printf '{"bench": "cluster_ranks", "scene": "%s", "method": "%s", "options": "%s", "cores": %d,\n' "$(basename "$SCENE")" "$METHOD" "$OPTIONS" "$CORES"
printf ' "plain_seconds": %s,\n "mpirun": [%s],\n' "$plain" "$ranks"
printf ' "shards": {"per_stage": 2, "stages": %d, "shard_seconds_total": %s, "merge_seconds_total": %s, "shard_bytes_per_stage": [%s], "same_bytes": %s}}\n' \
    "$((rounds + 1))" "$shard_s" "$merge_s" "$stage_bytes" "$same"
