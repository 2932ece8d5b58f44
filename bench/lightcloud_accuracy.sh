#!/bin/sh
# The light cloud against the path tracer (Kristensen et al. 2005, Table 1 and Fig. 7 scenes):
# the Cornell box from ../shared/data, and the same box with a window cut into its right wall and
# the cloud reaching outside it. 20 point lights at random positions that are not cloud lights
# (inside the box; for the window box half of them outside, near the window); per light the
# relative L2 of per-vertex radiance and of its indirect part against the reference (512 paths per
# vertex), with the reference's own noise taken out; the mean over the lights, for cloud
# densities 4^3..8^3 and CPCA vectors 2..16 per cluster, raw (no merging, no compression) and merged
# but not compressed (m6).
# Usage: bench/lightcloud_accuracy.sh PATH/TO/prt OUTDIR [SHARED_DATA]   (some 25 minutes on 2 cores)
set -eu
PRT=$1
OUT=$2
DATA=${3:-../shared/data}
BOX="$DATA/meshes/cornell_box/CornellBox-Original.obj"
[ -f "$BOX" ] || { echo "lightcloud_accuracy: $BOX is absent: nothing to measure" >&2; exit 0; }
mkdir -p "$OUT"
cp "$BOX" "$OUT/box.obj"
cp "$(dirname "$BOX")/CornellBox-Original.mtl" "$OUT/"
# The window box: the right wall (x = 1) as four quads around a 0.7 x 0.6 opening.
awk '
/^## Object rightwall/ { skip = 1
  print "## Object rightwall with a window"
  q(-1.04, 0.99, 0.00, 0.80); q(-1.04, 0.99, 1.40, 1.99); q(-1.04, -0.40, 0.80, 1.40); q(0.30, 0.99, 0.80, 1.40)
  print "g rightWall"; print "usemtl rightWall"
  for (i = 0; i < 4; ++i) print "f " (-16 + 4 * i) " " (-15 + 4 * i) " " (-14 + 4 * i) " " (-13 + 4 * i)
  next }
/^## Object leftWall/ { skip = 0 }
skip { next }
{ print }
function q(z0, z1, y0, y1) { printf "v 1.00 %.2f %.2f\nv 1.00 %.2f %.2f\nv 1.00 %.2f %.2f\nv 1.00 %.2f %.2f\n", y0, z0, y0, z1, y1, z1, y1, z0 }
' "$BOX" >"$OUT/window.obj"

seed=12345
coord() {   # LO SPAN: LO + SPAN x a number in [0, 1) from a fixed LCG (the same lights every run), into C
    seed=$(( (seed * 1103515245 + 12345) % 2147483648 ))
    C=$(awk -v s="$seed" -v lo="$1" -v span="$2" 'BEGIN { printf "%.3f", lo + span * s / 2147483648 }')
}

for scene in box window; do
    if [ "$scene" = box ]; then CLOUD=""; else CLOUD="--cloud-box -0.9,0.15,-0.95,2.4,1.85,0.9"; fi
    bake() {   # name, options...
        name=$1; shift
        # shellcheck disable=SC2086
        [ -s "$OUT/$scene-$name.prt" ] || "$PRT" bake "$OUT/$scene.obj" --max-edge 0.1 --method lightcloud --samples 1024 $CLOUD "$@" -o "$OUT/$scene-$name.prt" -q
    }
    bake g4 --cloud-grid 4,4,4
    bake g5 --cloud-grid 5,5,5
    bake g6 --cloud-grid 6,6,6
    bake g8 --cloud-grid 8,8,8
    bake raw6 --cloud-grid 6,6,6 --compress none --merge-distance 0
    bake m6 --cloud-grid 6,6,6 --compress none
    bake v2 --cloud-grid 6,6,6 --vectors 2
    bake v4 --cloud-grid 6,6,6 --vectors 4
    bake v16 --cloud-grid 6,6,6 --vectors 16
    : >"$OUT/$scene-lights.txt"
    for i in $(seq 1 20); do
        if [ "$scene" = window ] && [ $((i % 2)) -eq 0 ]; then   # outside, in front of the window
            coord 1.2 1.0; x=$C; coord 0.9 0.4; y=$C; coord -0.3 0.5; z=$C
        else
            coord -0.75 1.5; x=$C; coord 1.25 0.6; y=$C; coord -0.8 1.6; z=$C
        fi
        L="point:$x,$y,$z:0.6"
        echo "$L" >>"$OUT/$scene-lights.txt"
        [ -s "$OUT/$scene-ref$i.json" ] || "$PRT" reference "$OUT/$scene-g6.prt" --light "$L" --env none --emission 0 --samples 512 -o "$OUT/$scene-ref$i.json" -q
    done
done

metric() {   # file, reference, light, extra -> "relative_l2 above_noise"
    "$PRT" compare "$1" "$2" --light "$3" --env none --emission 0 $4 --json - -q |
        awk -F'[:,}]' '{ for (i = 1; i <= NF; ++i) { if ($i ~ /"relative_l2"/) r = $(i + 1); if ($i ~ /"relative_l2_above_noise"/) a = $(i + 1) } } END { print r, a }'
}

for scene in box window; do
    echo
    echo "$scene: mean over 20 lights | total | total above noise | indirect | indirect above noise | merged lights per zone | coefficients per vertex | MiB"
    echo "| $scene | total | above noise | indirect | above noise | lights per zone | coefficients | MiB |"
    echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    for name in g4 g5 g6 g8 raw6 m6 v2 v4 v16; do
        f="$OUT/$scene-$name.prt"
        sums=$(i=0; while read -r L; do i=$((i + 1)); echo "$(metric "$f" "$OUT/$scene-ref$i.json" "$L" "") $(metric "$f" "$OUT/$scene-ref$i.json" "$L" --indirect)"; done <"$OUT/$scene-lights.txt" |
               awk '{ a += $1; b += $2; c += $3; d += $4; n++ } END { printf "%.4f %.4f %.4f %.4f", a / n, b / n, c / n, d / n }')
        info=$("$PRT" info "$f" --json)
        lights=$(echo "$info" | tr -d '\n\t ' | sed 's/.*"merged_lights_per_zone":\[\([^]]*\)\].*/\1/' | awk -F, '{ for (i = 1; i <= NF; ++i) s += $i; printf "%.1f", s / NF }')
        coeffs=$(echo "$info" | tr -d '\n\t ' | sed 's/.*"coefficients_per_vertex":\([0-9.e+-]*\).*/\1/')
        bytes=$(echo "$info" | tr -d '\n\t ' | sed 's/.*"transfer_bytes":\([0-9.e+]*\).*/\1/')
        echo "$sums $lights $coeffs $bytes" | awk -v n="$name" '{ printf "| %s | %.3f | %.3f | %.3f | %.3f | %s | %.1f | %.2f |\n", n, $1, $2, $3, $4, $5, $6, $7 / 1048576 }'
    done
done
