#!/bin/sh
# The glossy bunny of Kristensen et al. 2005 (Fig. 9, Table 1: 15k triangles, 19 zones, n_b = 16,
# 64 cloud lights not merged, CPCA 23 clusters, 48 coefficients, 1.5 h + 2.0 h of precomputation,
# 20 fps on a GeForce 6600), as far as the paper describes it: the Stanford bunny (the low-res one
# from SHARED_DATA, 1 unit long) glossy (Phong exponent 12, as the paper's) in a closed box with a
# red and a blue wall (bench/bunny_box.sh), a 4 x 4 x 4 cloud, no merging, zones of at most 250
# vertices, CPCA with one cluster per zone and 48 vectors. Prints the bench's JSON and summary:
# bake stages, per-frame update (and its glossy part against a plain read of the glossy blocks),
# and the error against the path tracer from a fixed eye, on the glossy vertices facing it.
# Skips (exit 0, saying so) when the bunny is absent.
# Usage: bench/lightcloud_glossy_bunny.sh BUILD_DIR OUTDIR [SHARED_DATA]   (some 10 minutes on 2 cores)
set -eu
BUILD=$1
OUT=$2
DATA=${3:-../shared/data}
HERE=$(cd "$(dirname "$0")" && pwd)
BUNNY="$DATA/meshes/bunny/bunny_lowres.obj"
[ -f "$BUNNY" ] || { echo "lightcloud_glossy_bunny: $BUNNY is absent: nothing to measure" >&2; exit 0; }
"$HERE/bunny_box.sh" "$BUNNY" "$OUT" glossy
nice "$BUILD/prt_bench_lightcloud" "$OUT/bunny_glossy.json" --winding-keep --max-edge 0.2 --grid 4,4,4 --zone-vertices 250 --samples 1024 \
    --set merge-distance=0 --set clusters=1 --set vectors=48 --glossy-reference 512
