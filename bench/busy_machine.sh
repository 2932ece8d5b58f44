#!/bin/sh
# Bakes on a busy machine: every method baked with -j 1 and with -j 2 while LOAD busy-loop
# processes (default 2) compete for the cores, as on a CI runner or a workstation doing other
# work. Prints each stage's seconds (the bake's --summary) at both thread counts and their ratio
# j2 / j1. The property: no stage gets slower with more threads on a loaded machine - a ratio over
# LIMIT (default 1.5, room for the noise of a shared machine) on a stage that takes 0.1 s or more
# with -j 1 is reported as SLOWER and makes the script exit 1. A stage that opens many small
# parallel regions (one per offset, per iteration...) fails it: every region's barrier waits for
# a thread the scheduler has set aside.
# Scenes: the procedural demo scene (prt demo-scene) and the Stanford bunny (low-res, from
# SHARED_DATA/meshes/bunny) when present, else skipped saying so.
# Usage: bench/busy_machine.sh PATH/TO/prt OUTDIR [SHARED_DATA]
#   METHODS="sh offset" (default: every method), LOAD=N, LIMIT=R, REPEAT=N (bakes per thread
#   count, default 2: each stage's fastest is compared, the rest being other work); a method's
#   bake options in OPTS_<method> (defaults below keep each bake to seconds); SKIP="scene:method
#   ..." pairs left out (default demo:wavelet: its cube-map visibility takes a minute a bake on
#   the demo's 10,000 vertices; the bunny's 1,800 bake in seconds).
# Some 5 minutes on 2 cores.
set -eu
PRT=$1
OUT=$2
DATA=${3:-../shared/data}
METHODS=${METHODS:-sh wavelet spectral lightcloud offset ao}
LOAD=${LOAD:-2}
LIMIT=${LIMIT:-1.5}
REPEAT=${REPEAT:-2}
SKIP=${SKIP:-demo:wavelet}
OPTS_sh=${OPTS_sh:---samples 256 --no-refine}
OPTS_wavelet=${OPTS_wavelet:---supersample 1 --terms 2 --brdf-res 16 --bounces 1 --gather-res 8 --no-refine}
OPTS_spectral=${OPTS_spectral:---samples 512 --basis 256 --no-refine}
OPTS_lightcloud=${OPTS_lightcloud:---samples 512 --basis 256 --cloud-grid 3,3,3 --no-refine}
OPTS_offset=${OPTS_offset:---texels 64 --offsets 100 --walks 32}
OPTS_ao=${OPTS_ao:---no-refine}
mkdir -p "$OUT"

pids=""
# shellcheck disable=SC2317   # called by the traps
stop_load() { for p in $pids; do kill "$p" 2>/dev/null || true; done; pids=""; }
trap stop_load EXIT
trap 'stop_load; exit 130' INT TERM

"$PRT" demo-scene -o "$OUT/demo.obj" >/dev/null
scenes="demo"
if [ -f "$DATA/meshes/bunny/bunny_lowres.obj" ]; then
    cp "$DATA/meshes/bunny/bunny_lowres.obj" "$OUT/bunny.obj"
    scenes="$scenes bunny"
else
    echo "busy_machine: no bunny in $DATA/meshes/bunny: skipped" >&2
fi

i=0
while [ "$i" -lt "$LOAD" ]; do
    sh -c 'while :; do :; done' &
    pids="$pids $!"
    i=$((i + 1))
done

stages() {   # summary.json -> "name<TAB>seconds" lines
    python3 -c 'import json, sys
for s in json.load(open(sys.argv[1]))["stages"]: print("%s\t%.3f" % (s["name"], s["seconds"]))' "$1"
}

status=0
printf '%-7s %-11s %-20s %8s %8s %7s\n' scene method stage "j1 s" "j2 s" j2/j1
for scene in $scenes; do
    for m in $METHODS; do
        case " $SKIP " in *" $scene:$m "*) echo "busy_machine: $m on $scene skipped (SKIP)" >&2; continue ;; esac
        opts=""
        eval "opts=\$OPTS_$m"
        for j in 1 2; do
            : >"$OUT/${scene}_$m.j$j.all"
            r=0
            while [ "$r" -lt "$REPEAT" ]; do
                # shellcheck disable=SC2086
                if ! "$PRT" bake "$OUT/$scene.obj" -o "$OUT/${scene}_$m.j$j.prt" --method "$m" -j "$j" -q --no-checkpoint \
                    --summary "$OUT/${scene}_$m.j$j.json" $opts; then
                    echo "busy_machine: $m on $scene with -j $j failed" >&2
                    status=1
                    continue 3
                fi
                stages "$OUT/${scene}_$m.j$j.json" >>"$OUT/${scene}_$m.j$j.all"
                r=$((r + 1))
            done
            # Each stage's fastest run: the others' load comes and goes, a stage's own cost does not.
            awk -F'\t' '!($1 in best) { order[n++] = $1; best[$1] = $2 } $2 < best[$1] { best[$1] = $2 }
                END { for (i = 0; i < n; ++i) printf "%s\t%s\n", order[i], best[order[i]] }' "$OUT/${scene}_$m.j$j.all" >"$OUT/${scene}_$m.j$j.tsv"
        done
        if [ "$(wc -l <"$OUT/${scene}_$m.j1.tsv")" -ne "$(wc -l <"$OUT/${scene}_$m.j2.tsv")" ]; then
            echo "busy_machine: $m on $scene ran different stages with -j 1 and -j 2" >&2
        fi
        # Stage names hold spaces: side by side by line (both bakes run the same stages).
        rows=$(paste "$OUT/${scene}_$m.j1.tsv" "$OUT/${scene}_$m.j2.tsv")
        echo "$rows" | awk -F'\t' -v scene="$scene" -v m="$m" -v limit="$LIMIT" '
            { r = $2 > 0 ? $4 / $2 : 0; flag = ($2 >= 0.1 && r > limit) ? "  SLOWER" : ""
              printf "%-7s %-11s %-20s %8.3f %8.3f %7.2f%s\n", scene, m, $1, $2, $4, r, flag
              if (flag != "") bad = 1 }
            END { exit bad }' || status=1
    done
done
exit "$status"
