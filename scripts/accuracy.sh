#!/bin/sh
# Reproduces the README's accuracy tables: SH PRT (unshadowed, shadowed, inter-reflected) at
# orders 3..10 against the path-traced reference, on the demo scene and on the bunny from
# ../shared/data, under the procedural sky. Writes CSVs and plots into out/accuracy/.
set -eu
PRT=${1:-build/prt}
OUT=${2:-out/accuracy}
mkdir -p "$OUT"
"$PRT" demo-scene -o "$OUT/demo.obj"
"$PRT" reference "$OUT/demo.obj" -o "$OUT/demo_ref.json" --samples 4096
"$PRT" sweep "$OUT/demo.obj" --reference "$OUT/demo_ref.json" -o "$OUT/demo.csv" --plot "$OUT/demo.png" --samples 4096
"$PRT" sweep "$OUT/demo.obj" --reference "$OUT/demo_ref.json" -o "$OUT/demo_indirect.csv" --indirect --samples 4096
BUNNY=../shared/data/meshes/bunny/bun_zipper.ply
if [ -f "$BUNNY" ]; then
    "$PRT" reference "$BUNNY" -o "$OUT/bunny_ref.json" --samples 2048
    "$PRT" sweep "$BUNNY" --reference "$OUT/bunny_ref.json" -o "$OUT/bunny.csv" --plot "$OUT/bunny.png" --samples 2048
else
    echo "accuracy: $BUNNY not found; skipping the bunny" >&2
fi
echo "accuracy: tables in $OUT/*.csv, plots in $OUT/*.png"
