#!/bin/sh
# Bakes over many machines from the command line (docs/CLUSTER.md): for every method, 3 shards per
# stage merged stage by stage, and the bake under mpirun with 1, 2 and 3 processes, write the same
# bytes (outside META) as one plain bake; the stage list; merge's refusals and exit codes; a process
# killed under mpirun fails the run instead of hanging it. The MPI part skips when mpirun or the
# build's MPI is absent. Usage: cluster_test.sh PATH/TO/prt PATH/TO/same_chunks
set -u
PRT=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")   # the test runs in its own folder
SAME=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
T=$(mktemp -d /tmp/prt_cluster_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"
cd "$T" || exit 1

# A floor and a box, a few thousand vertices once split: every method bakes it in seconds.
cat >box.obj <<'OBJ'
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v -0.3 0 -0.3
v 0.3 0 -0.3
v 0.3 0 0.3
v -0.3 0 0.3
v -0.3 0.6 -0.3
v 0.3 0.6 -0.3
v 0.3 0.6 0.3
v -0.3 0.6 0.3
f 1 3 2
f 1 4 3
f 9 11 10
f 9 12 11
f 5 6 10
f 5 10 9
f 6 7 11
f 6 11 10
f 7 8 12
f 7 12 11
f 8 5 9
f 8 9 12
OBJ
SCENE="box.obj --max-edge 0.1 --no-refine"
method_options() {
    case $1 in
    sh) echo "--samples 64 --bounces 2 --compress cpca --clusters 4" ;;
    wavelet) echo "--bounces 1 --gather-res 8 --supersample 1" ;;
    spectral) echo "" ;;
    lightcloud) echo "--cloud-grid 3,2,3 --samples 64" ;;
    offset) echo "--texels 32 --offsets 16 --map-bounces 2 --walks 16" ;;
    *) echo "" ;;
    esac
}
METHODS=$("$PRT" bake --help | sed -n 's/^ \{25\}\([a-z]*\)  .*/\1/p')
[ -n "$METHODS" ] && ok || bad "no methods listed by prt bake --help"

for m in $METHODS; do
    # shellcheck disable=SC2046,SC2086
    set -- $SCENE --method "$m" $(method_options "$m") -j 2 -q
    expect 0 "$m: plain bake" -- "$PRT" bake "$@" --no-checkpoint -o "$m.prt"
    # --stage lists the stages up to the first to shard.
    expect 0 "$m: --stage" -- "$PRT" bake "$@" --stage
    grep -q "^0 " "$T/out" && ok || bad "$m: --stage lists no stage 0"
    # Shards of each stage until merge says done; --from is the last merge's output.
    from="" rounds=0
    while :; do
        for i in 1 2 3; do
            expect 0 "$m: shard $i/3 of round $rounds" -- "$PRT" bake "$@" ${from:+--from "$from"} --shard $i/3 -o "$m.$rounds.$i.shard"
        done
        out="$m.merged.$rounds"
        expect 0 "$m: merge round $rounds" -- "$PRT" merge -q "$m.$rounds.3.shard" "$m.$rounds.1.shard" "$m.$rounds.2.shard" -o "$out"
        next=$(cat "$T/out")
        rounds=$((rounds + 1))
        case $next in
        done) break ;;
        "next "*) from=$out ;;
        *) bad "$m: merge said '$next', not 'next K' or 'done'"; break ;;
        esac
        [ $rounds -lt 12 ] || { bad "$m: merge never said done"; break; }
    done
    "$SAME" "$m.prt" "$out" && ok || bad "$m: 3 shards per stage merged to other bytes than a plain bake"
    echo "$m: $rounds merge(s), the same bytes as one bake"
done

# Refusals: each names the file and what differs; exit 2 for shards that do not belong together,
# 1 for a damaged one.
# shellcheck disable=SC2086
set -- $SCENE --method sh --samples 64 --bounces 1 -j 2 -q
for i in 1 2 3; do "$PRT" bake "$@" --shard $i/3 -o r$i.shard; done
"$PRT" bake "$@" --seed 7 --shard 2/3 -o seed.shard 2>/dev/null ||
    "$PRT" bake "$@" --samples 128 --shard 2/3 -o seed.shard
"$PRT" bake "$@" --shard 2/4 -o four.shard
expect 2 "merge a shard of another bake" -- "$PRT" merge r1.shard seed.shard r3.shard -o x
says "seed.shard"
says "another bake"
expect 2 "merge shards of another N" -- "$PRT" merge r1.shard four.shard r3.shard -o x
says "four.shard"
expect 2 "merge a missing shard" -- "$PRT" merge r1.shard r3.shard -o x
says "missing 2/3"
expect 2 "merge a shard twice" -- "$PRT" merge r1.shard r2.shard r2.shard -o x
says "both shard 2/3"
head -c 1000 r2.shard >cut.shard
expect 1 "merge a shard cut off" -- "$PRT" merge r1.shard cut.shard r3.shard -o x
says "cut.shard"
[ ! -e x ] && [ ! -e x.merging ] && ok || bad "a refused merge left a file"
expect 2 "--stage K that is not next" -- "$PRT" bake "$@" --shard 1/3 --stage 1 -o y.shard
says "not the next"
expect 2 "--shard out of range" -- "$PRT" bake "$@" --shard 4/3 -o y.shard
expect 2 "--from without --shard" -- "$PRT" bake "$@" --from r1.shard -o y.prt
expect 0 "merge --help" -- "$PRT" merge --help
grep -q "Exit codes" "$T/out" && ok || bad "merge --help lacks exit codes"

# Under mpirun: 1, 2 and 3 processes write the bytes of one.
if ! command -v mpirun >/dev/null 2>&1; then
    echo "cluster_test: mpirun not found: the MPI part skips"
elif ! "$PRT" bake --help | grep -q "Under mpirun"; then
    echo "cluster_test: prt was built without MPI: the MPI part skips"
else
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
    # Open MPI's own allocations outlive MPI_Finalize: under ASan, no leak checking for these runs.
    MPIRUN="$NOLEAK mpirun --oversubscribe"
    for m in $METHODS; do
        # shellcheck disable=SC2046,SC2086
        set -- $SCENE --method "$m" $(method_options "$m") -j 1 -q
        for n in 1 2 3; do
            expect 0 "$m: mpirun -n $n" -- timeout 300 $MPIRUN -n $n "$PRT" bake "$@" -o "$m.mpi$n.prt"
            "$SAME" "$m.prt" "$m.mpi$n.prt" && ok || bad "$m: mpirun -n $n wrote other bytes than one process"
        done
    done
    # A process killed in the middle: the run fails, and soon (no hang).
    # shellcheck disable=SC2086
    set -- $SCENE --method sh --samples 30000 --order 6 --bounces 3 -j 1 -q
    timeout 300 $MPIRUN -n 2 "$PRT" bake "$@" -o killed.prt >/dev/null 2>"$T/err" &
    job=$!
    victim=""
    for _ in $(seq 1 100); do
        for p in $(pgrep -f "prt bake.*killed.prt" || true); do
            tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -q '^OMPI_COMM_WORLD_RANK=1$' && victim=$p
        done
        [ -n "$victim" ] && break
        sleep 0.1
    done
    sleep 0.5
    [ -n "$victim" ] && kill -9 "$victim"
    wait $job
    rc=$?
    [ -n "$victim" ] && ok || bad "found no rank 1 to kill"
    [ "$rc" -ne 0 ] && [ "$rc" -ne 124 ] && ok || bad "a killed process: mpirun exited $rc (0: it went on; 124: it hung)"
    [ ! -e killed.prt ] && ok || bad "a run with a killed process wrote its file"
fi

echo "cluster_test: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
