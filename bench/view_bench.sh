#!/bin/sh
# Viewer frame rate and relight time on the bunny and the largest mesh in ../shared/data (the
# dragon), under whatever OpenGL the display offers (llvmpipe under xvfb-run on machines without
# a GPU). Every frame both moves the camera and rotates the lighting, so each one relights.
# Usage: bench/view_bench.sh [build/prt]   (prints one JSON line per mesh)
set -eu
PRT=${1:-build/prt}
OUT=${OUT:-out/view_bench}
DATA=../shared/data/meshes
mkdir -p "$OUT"
RUN=""
[ -n "${DISPLAY:-}" ] || RUN="xvfb-run -a -s -screen\ 0\ 1280x1024x24"
script="$OUT/script.txt"
: >"$script"
i=0
while [ $i -lt 60 ]; do
    t=$(awk "BEGIN { print $i * 0.05 }")
    printf '%s orbit 3 0\n%s drag left 8 0 ctrl\n' "$t" "$t" >>"$script"
    i=$((i + 1))
done
printf '3.1 quit\n' >>"$script"
for mesh in "$DATA/bunny/bun_zipper.ply" "$DATA/dragon/dragon_vrip_res2.ply"; do
    if [ ! -f "$mesh" ]; then echo "view_bench: $mesh not found; skipped" >&2; continue; fi
    name=$(basename "$mesh" .ply)
    [ -f "$OUT/$name.prt" ] || "$PRT" bake -q "$mesh" -o "$OUT/$name.prt" --order 5 --samples 512
    printf '%s: ' "$name"
    if [ -n "$RUN" ]; then
        xvfb-run -a -s "-screen 0 1280x1024x24" "$PRT" view -q "$OUT/$name.prt" --width 1024 --height 768 --script "$script" --stats
    else
        "$PRT" view -q "$OUT/$name.prt" --width 1024 --height 768 --script "$script" --stats
    fi
done
