#!/bin/sh
# The spectral paper's Fig. 6 experiment (Wang, Zhu & Humphreys 2007): indirect light in a closed
# room lit through a small window, relative L2 against the path tracer per vertex, for 32..2048
# basis functions and for no truncation at all (--full-basis: the same vertex sampling, every
# vertex its own function), with the reference's own noise taken out (relative_l2_above_noise).
# Usage: bench/spectral_fig6.sh PATH/TO/prt OUTDIR [CELL_METRES] [REFERENCE_PATHS]
# (defaults 0.0625 = about 30,000 vertices, 2048 paths per vertex: some 20 minutes on 2 cores).
set -eu
PRT=$1
OUT=$2
CELL=${3:-0.0625}
PATHS=${4:-2048}
mkdir -p "$OUT"
LIGHT="--env none --light directional:0.3,0.6,1:30"
"$PRT" demo-scene --room --cell "$CELL" -o "$OUT/room.obj"
# shellcheck disable=SC2086
[ -s "$OUT/reference.json" ] || "$PRT" reference "$OUT/room.obj" $LIGHT --samples "$PATHS" -o "$OUT/reference.json" -q
# shellcheck disable=SC2086
"$PRT" sweep "$OUT/room.obj" --method spectral --param basis --values 32,64,128,256,512,1024,2048 --reference "$OUT/reference.json" \
    --indirect $LIGHT --control bounces=16 -o "$OUT/basis.csv" --plot "$OUT/basis.png" -q
# shellcheck disable=SC2086
"$PRT" sweep "$OUT/room.obj" --method spectral --param samples --values 4096 --full-basis --reference "$OUT/reference.json" \
    --indirect $LIGHT --control bounces=16 -o "$OUT/full.csv" -q
echo "| basis functions | relative L2 | above the reference's noise | bytes per vertex | bake s |"
echo "| ---: | ---: | ---: | ---: | ---: |"
tail -n +2 "$OUT/basis.csv" | awk -F, '{ printf "| %s | %.4f | %.4f | %d | %.1f |\n", $2, $5, $9, $7, $8 }'
tail -n +2 "$OUT/full.csv" | awk -F, '{ printf "| all (one per vertex) | %.4f | %.4f | %d | %.1f |\n", $5, $9, $7, $8 }'
