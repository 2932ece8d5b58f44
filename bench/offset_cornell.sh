#!/bin/sh
# Issue 30's check of the offset method: the Cornell box from ../shared/data under a point light
# just under its ceiling light (emission off, no environment), baked at the defaults (or OFFSETS),
# rendered from the front and compared with the path tracer's image of the same view: relative L2
# over the image, the worst 16 x 16-pixel block (all blocks, and those at least a quarter of the
# image's mean: dark blocks are the path tracer's noise), and two path-traced images against each
# other for the noise floor. The blocks are measured by bench/image_blocks.py.
# Usage: bench/offset_cornell.sh PATH/TO/prt OUTDIR [SHARED_DATA]   (about 15 minutes on 2 cores,
# most of it the two reference images). Environment: OFFSETS (default: prt's, 200), SAMPLES (256).
set -eu
PRT=$1
OUT=$2
DATA=${3:-../shared/data}
HERE=$(cd "$(dirname "$0")" && pwd)
BOX="$DATA/meshes/cornell_box/CornellBox-Original.obj"
[ -f "$BOX" ] || { echo "offset_cornell: $BOX is absent: nothing to measure" >&2; exit 0; }
mkdir -p "$OUT"
LIGHT="point:0,1.85,0:1,1,1"
VIEW="--eye 0,1,3.6 --target 0,1,0 --fov 38 --env none --emission 0 --light $LIGHT"
SAMPLES=${SAMPLES:-256}
MORE=""
[ -n "${OFFSETS:-}" ] && MORE="--offsets $OFFSETS"
start=$(date +%s)
# shellcheck disable=SC2086
"$PRT" bake "$BOX" --method offset --light "$LIGHT" $MORE -o "$OUT/box.prt" -q
echo "bake: $(( $(date +%s) - start )) s, $(wc -c <"$OUT/box.prt") bytes"
# shellcheck disable=SC2086
"$PRT" render "$OUT/box.prt" $VIEW -o "$OUT/offset.pfm" -q
for seed in 0 1; do
    # shellcheck disable=SC2086
    [ -s "$OUT/ref$seed.pfm" ] || "$PRT" reference "$OUT/box.prt" --image "$OUT/ref$seed.pfm" --samples "$SAMPLES" --seed $seed $VIEW -q
done
# shellcheck disable=SC2086
"$PRT" render "$OUT/box.prt" "$OUT/ref0.pfm" $VIEW -o "$OUT/compare.png" -q
echo "offset against the path tracer:"
python3 "$HERE/image_blocks.py" "$OUT/offset.pfm" "$OUT/ref0.pfm"
echo "path tracer against itself (another seed):"
python3 "$HERE/image_blocks.py" "$OUT/ref1.pfm" "$OUT/ref0.pfm"
