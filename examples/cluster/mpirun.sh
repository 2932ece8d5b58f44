#!/bin/sh
# A prt bake spread over the machines of an MPI hostfile (docs/CLUSTER.md): one command, every
# stage shared out as it comes, one file written by rank 0. prt must be built with MPI
# (libopenmpi-dev present at configure time: `prt bake --help` then says "Under mpirun"), the same
# build on every machine, and the scene at the same path on each.
#     sh mpirun.sh hostfile scene.obj out.prt --method sh --order 6 --samples 4096
# hostfile: Open MPI's format, one machine a line with one slot each (`node1 slots=1`): one process
# per machine, which uses all of that machine's cores.
set -eu
HOSTFILE=$1 SCENE=$2 OUT=$3
shift 3
PRT=${PRT:-prt}
RANKS=${RANKS:-$(grep -c . "$HOSTFILE")}
# --map-by node: one process per machine; --bind-to none: its threads may use every core there.
# As root, Open MPI wants OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 as well.
exec mpirun --hostfile "$HOSTFILE" -n "$RANKS" --map-by node --bind-to none \
    "$PRT" bake "$SCENE" "$@" -o "$OUT"
