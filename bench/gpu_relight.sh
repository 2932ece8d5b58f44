#!/bin/sh
# Whole frames per second of every method with its last sums on the CPU and on the GPU
# (--accumulate cpu / gpu; prt_bench_gpu), on the dragon (SHARED_DATA/meshes/dragon, res3), the
# room (prt demo-scene --room) and Sponza (SHARED_DATA/meshes/sponza) - each skipped, saying so,
# when absent. Each frame turns the environment / moves the lights, relights, draws and reads the
# image back; prt_bench_gpu measures in the same run the limit those frames cannot beat (the same
# drawing with colours fixed). Bakes are small (seconds to minutes on 2 cores): the frame rates,
# not the pictures, are the point. One JSON line per file and method, then a table.
# On a machine without a GPU this runs on llvmpipe (the "GPU" is the same CPU cores). On a real
# GPU: run it where EGL finds the vendor driver (check the "renderer" field: not llvmpipe), e.g.
#   __EGL_VENDOR_LIBRARY_FILENAMES=/usr/share/glvnd/egl_vendor.d/10_nvidia.json bench/gpu_relight.sh
# with libprt built there (make build) - nothing else changes.
# Usage: bench/gpu_relight.sh [build] [outdir] [SHARED_DATA]
#   METHODS="sh sh-cpca wavelet spectral lightcloud offset ao" (default: all but wavelet, whose
#   cube-map bake takes many minutes on these meshes), SCENES="dragon room sponza", FRAMES=N,
#   SIZE=WxH.
set -eu
BUILD=${1:-build}
OUT=${2:-out/gpu_relight}
DATA=${3:-../shared/data}
METHODS=${METHODS:-sh sh-cpca spectral lightcloud offset ao}
SCENES=${SCENES:-dragon room sponza}
FRAMES=${FRAMES:-20}
SIZE=${SIZE:-640x480}
PRT=$BUILD/prt
mkdir -p "$OUT"
opts() {   # method -> bake options
    case $1 in
    sh) echo "--method sh --order 4 --samples 64 --no-refine" ;;
    sh-cpca) echo "--method sh --order 4 --samples 64 --no-refine --clusters 64 --vectors 8" ;;
    wavelet) echo "--method wavelet --supersample 1 --terms 2 --brdf-res 16 --bounces 0 --gather-res 8 --no-refine" ;;
    spectral) echo "--method spectral --samples 128 --basis 256 --no-refine" ;;
    lightcloud) echo "--method lightcloud --samples 128 --basis 256 --cloud-grid 3,3,3 --no-refine" ;;
    offset) echo "--method offset --texels 64 --offsets 60 --walks 16" ;;
    ao) echo "--method ao --samples 64 --no-refine" ;;
    esac
}
for scene in $SCENES; do
    case $scene in
    dragon) src=$DATA/meshes/dragon/dragon_vrip_res3.ply ;;
    sponza) src=$DATA/meshes/sponza/sponza_dabrovic.obj ;;
    room) src=$OUT/room.obj; [ -f "$src" ] || "$PRT" demo-scene --room -o "$src" >/dev/null ;;
    *) echo "gpu_relight: unknown scene $scene" >&2; continue ;;
    esac
    if [ ! -f "$src" ]; then echo "gpu_relight: $src not found: $scene skipped" >&2; continue; fi
    for m in $METHODS; do
        f=$OUT/$scene-$m.prt
        # shellcheck disable=SC2046   # the options are words
        [ -f "$f" ] || "$PRT" bake -q "$src" -o "$f" $(opts "$m") || { echo "gpu_relight: $scene $m: bake failed" >&2; continue; }
        "$BUILD/prt_bench_gpu" --frames "$FRAMES" --size "$SIZE" "$f" | tee -a "$OUT/results.jsonl"
    done
done
python3 - "$OUT/results.jsonl" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
print("| file | vertices | limit fps | CPU fps (relight ms) | GPU fps (CPU part ms, GPU sums ms) | GPU path |")
print("| --- | ---: | ---: | ---: | ---: | --- |")
for r in rows:
    g = r["gpu"]
    print("| %s | %d | %.1f | %.1f (%.1f) | %.1f (%.1f, %s) | %s |" % (r["file"].split("/")[-1], r["vertices"], r["limit_fps"], r["cpu"]["fps"], r["cpu"]["relight_ms"],
          g["fps"], g["relight_ms"], "%.1f" % g["sums_ms"] if g.get("sums_ms", -1) >= 0 else "-", "yes, sums on " + g["sums_on"] if g["taken"] else "no (CPU)"))
PY
