#!/bin/sh
# The gallery of docs/GALLERY.md: one picture per method of the table, made from the bakes of
# `make demo` (scripts/demo.sh) with the commands docs/GALLERY.md shows beside each, and the
# path tracer's picture of each lighting. Usage: gallery.sh [PRT] [DEMO_OUT] [IMAGES_DIR]
set -eu
PRT=${1:-build/prt}
DEMO=${2:-out/demo}
IMAGES=${3:-docs/images}
for m in sh wavelet ao spectral lightcloud offset; do
    [ -f "$DEMO/$m.prt" ] || { echo "gallery: $DEMO/$m.prt is missing: run make demo first" >&2; exit 1; }
done
mkdir -p "$IMAGES"
SIZE="--width 480 --height 360"
POINT=point:0.05,0.9,0.05:3
for m in sh wavelet ao; do
    "$PRT" render -q "$DEMO/$m.prt" -o "$IMAGES/gallery_$m.png" $SIZE
done
for m in spectral lightcloud offset; do
    "$PRT" render -q "$DEMO/$m.prt" -o "$IMAGES/gallery_$m.png" $SIZE --env none --light "$POINT"
done
"$PRT" reference -q "$DEMO/glossy.json" --image "$IMAGES/gallery_reference_sky.png" $SIZE --samples 256
"$PRT" reference -q "$DEMO/glossy.json" --image "$IMAGES/gallery_reference_point.png" $SIZE --samples 256 --env none --light "$POINT"
echo "gallery: wrote $IMAGES/gallery_*.png"
