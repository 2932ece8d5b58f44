#!/bin/sh
# "PRT Quality - Is SH basis well-suited?" (Kautz's SIGGRAPH 2004 course notes, after Sloan et al.
# 2002): a square blocker over a receiver plane, lit from the zenith by a point light and by 20 and
# 40 degree sources (cone angle: the disc's angular diameter), relit with SH of orders 2..10 and
# with Haar wavelets, against the exact (analytic) shadow. bench/sh_quality.py writes the scene
# and the light probes and measures; prt bakes and relights here as a user would.
# Usage: bench/sh_quality.sh PATH/TO/prt OUTDIR [CELLS] [SH_SAMPLES]
# (defaults 96 cells = 9,409 plane vertices, 16,384 SH directions per vertex: about 4 minutes on
# 2 cores). Writes OUTDIR/sh_quality.png (rows: light sizes; columns: SH orders, wavelet, exact),
# OUTDIR/sh_quality_profile.svg (the centre line), OUTDIR/results.json, and prints the tables.
# Environment: ORDERS (default 2,...,10), FIGURE_ORDERS (2,3,4,6,8,10), SIZES (0,20,40),
# WAVELET_SUPERSAMPLE (2), WAVELET_COEFFICIENTS and WAVELET_BITS (prt's defaults: 128 per vertex,
# 8-bit), REFERENCE_SAMPLES
# (1024 paths per vertex of `prt reference`, whose direct light checks the analytic shadow; 0: none),
# CHECK=1 to exit 1 unless the trends the notes show hold and the path tracer agrees.
set -eu
PRT=$1
OUT=$2
CELLS=${3:-96}
SAMPLES=${4:-16384}
ORDERS=${ORDERS:-2,3,4,5,6,7,8,9,10}
FIGURE_ORDERS=${FIGURE_ORDERS:-2,3,4,6,8,10}
SIZES=${SIZES:-0,20,40}
SUPERSAMPLE=${WAVELET_SUPERSAMPLE:-2}
COEFFS="${WAVELET_COEFFICIENTS:+--coefficients $WAVELET_COEFFICIENTS} ${WAVELET_BITS:+--bits $WAVELET_BITS}"
REFSAMPLES=${REFERENCE_SAMPLES:-1024}
HERE=$(cd "$(dirname "$0")" && pwd)
PY="python3 $HERE/sh_quality.py"
mkdir -p "$OUT"
MAXORDER=$(echo "$ORDERS" | tr ',' '\n' | sort -n | tail -n 1)

$PY scene "$OUT" --cells "$CELLS" --sizes "$SIZES"
# Shadowed diffuse transfer only (the exact answer has no interreflection), the mesh kept as
# written (--no-refine: the plane's vertices stay a grid), albedo 1 (exit radiance 1 on the open
# plane). SH floats (--quantize 32) and many directions so that what is left is the basis's
# truncation; one bake at the highest order, relit at each lower one (--control order=N).
"$PRT" bake "$OUT/scene.obj" -o "$OUT/sh.prt" --method sh --order "$MAXORDER" --kinds shadowed \
    --samples "$SAMPLES" --quantize 32 --no-refine --albedo 1 -q
# shellcheck disable=SC2086
"$PRT" bake "$OUT/scene.obj" -o "$OUT/wavelet.prt" --method wavelet --bounces 0 \
    --supersample "$SUPERSAMPLE" $COEFFS --no-refine --albedo 1 -q
# Vertex positions (the relit JSON holds radiance only).
"$PRT" relight "$OUT/sh.prt" -o "$OUT/sh.ply" --colors linear -q
"$PRT" relight "$OUT/wavelet.prt" -o "$OUT/wavelet.ply" --colors linear -q

for SIZE in $(echo "$SIZES" | tr ',' ' '); do
    if [ "$SIZE" = 0 ]; then
        TAG=point
        # irradiance pi from the zenith: exit radiance 1 where nothing blocks it
        LIGHT="--env none --light directional:0,1,0:3.14159265"
    else
        TAG=$SIZE
        LIGHT="--env $OUT/disc$SIZE.pfm --layout latlong --light none"
    fi
    for N in $(echo "$ORDERS" | tr ',' ' '); do
        # shellcheck disable=SC2086
        "$PRT" relight "$OUT/sh.prt" -o "$OUT/sh_${TAG}_o$N.json" --control order="$N" $LIGHT -q
    done
    # shellcheck disable=SC2086
    "$PRT" relight "$OUT/wavelet.prt" -o "$OUT/wavelet_$TAG.json" $LIGHT -q
    rm -f "$OUT/reference_$TAG.json"
    if [ "$REFSAMPLES" -gt 0 ]; then
        # shellcheck disable=SC2086
        "$PRT" reference "$OUT/sh.prt" -o "$OUT/reference_$TAG.json" --samples "$REFSAMPLES" $LIGHT -q
    fi
done

CHECKFLAG=
[ "${CHECK:-0}" = 1 ] && CHECKFLAG=--check
# shellcheck disable=SC2086
$PY analyse "$OUT" --orders "$ORDERS" --sizes "$SIZES" --figure-orders "$FIGURE_ORDERS" $CHECKFLAG
