#!/bin/sh
# A prt bake spread over machines reachable by ssh with GNU parallel (docs/CLUSTER.md). Every
# machine needs prt (the same version) and the same folder at the same path (NFS, or copy the
# scene there first); the shards and merged stages are written there too.
#     sh parallel.sh hosts.txt scene.obj out.prt --method wavelet --bounces 2
# hosts.txt: one ssh login a line (`4/node1` runs 4 jobs on node1; `:` is this machine).
set -eu
HOSTS=$1 SCENE=$2 OUT=$3
shift 3
PRT=${PRT:-prt}
DIR=$(pwd)
N=${N:-$(grep -c . "$HOSTS")}    # one shard per host line by default
from="" round=0
while :; do
    # Shard I of N on whichever host is free; --halt stops at the first failure.
    seq 1 "$N" | parallel --sshloginfile "$HOSTS" --halt now,fail=1 \
        "cd '$DIR' && $PRT bake '$SCENE' $* ${from:+--from '$from'} -q --shard {}/$N -o '$OUT.$round.{}.shard'"
    next=$($PRT merge -q "$OUT.$round".*.shard -o "$OUT.merged.$round")
    rm -f "$OUT.$round".*.shard
    case $next in
    done) mv "$OUT.merged.$round" "$OUT"; rm -f "$OUT".merged.*; echo "wrote $OUT"; exit 0 ;;
    "next "*) from="$OUT.merged.$round"; round=$((round + 1)) ;;
    *) echo "parallel.sh: the merge of round $round failed" >&2; exit 1 ;;
    esac
done
