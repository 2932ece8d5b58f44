#!/bin/sh
# How a merged light's response is formed (Kristensen et al. 2005, section 4.1), measured against
# the path tracer: the mean of its lights' responses, their harmonic mean (the paper's wording), and
# a solution at the merged light's position (the paper's "higher quality" alternative), on the same
# scenes, lights and references, at the default merge distance (3 x the cloud spacing) and at half
# of it; "raw" keeps every cloud light (no merging) as the floor the three approach. Uncompressed
# (--compress none) so that only merging differs. Per scene 8 point lights at fixed random
# positions, per light the relative L2 of per-vertex total and indirect radiance against a
# reference of 512 paths per vertex, with the reference's own noise taken out ("beyond noise").
# Scenes: the Cornell box from SHARED_DATA (closed; max edge 0.15), the procedural demo scene
# (open), and the Stanford bunny (low-res, from SHARED_DATA) in a closed box with a red and a
# blue wall. Scenes whose data is absent are skipped, saying so.
# Usage: bench/lightcloud_merge.sh PATH/TO/prt OUTDIR [SHARED_DATA]   (some 30 minutes on 2 cores)
set -eu
PRT=$1
OUT=$2
DATA=${3:-../shared/data}
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
SAMPLES=${SAMPLES:-512}
LIGHTS=${LIGHTS:-8}

seed=4242
coord() {   # LO SPAN: LO + SPAN x a number in [0, 1) from a fixed LCG, into C
    seed=$(( (seed * 1103515245 + 12345) % 2147483648 ))
    C=$(awk -v s="$seed" -v lo="$1" -v span="$2" 'BEGIN { printf "%.3f", lo + span * s / 2147483648 }')
}
metric() {   # file, reference, light, extra -> "relative_l2 above_noise"
    # shellcheck disable=SC2086
    "$PRT" compare "$1" "$2" --light "$3" --env none --emission 0 $4 --json - -q |
        awk -F'[:,}]' '{ for (i = 1; i <= NF; ++i) { if ($i ~ /"relative_l2"/) r = $(i + 1); if ($i ~ /"relative_l2_above_noise"/) a = $(i + 1) } } END { print r, a }'
}

scenes=""
if [ -f "$DATA/meshes/cornell_box/CornellBox-Original.obj" ]; then
    cp "$DATA/meshes/cornell_box/CornellBox-Original.obj" "$OUT/cornell.obj"
    cp "$DATA/meshes/cornell_box/CornellBox-Original.mtl" "$OUT/"
    scenes="$scenes cornell"
else
    echo "lightcloud_merge: no Cornell box in $DATA: skipped" >&2
fi
"$PRT" demo-scene -o "$OUT/demo.obj"
scenes="$scenes demo"
if [ -f "$DATA/meshes/bunny/bunny_lowres.obj" ]; then
    "$HERE/bunny_box.sh" "$DATA/meshes/bunny/bunny_lowres.obj" "$OUT" diffuse
    scenes="$scenes bunny"
else
    echo "lightcloud_merge: no bunny in $DATA: skipped" >&2
fi

for scene in $scenes; do
    case $scene in
    cornell) SRC="$OUT/cornell.obj"; MESH="--max-edge 0.15"; lo="-0.75 1.5 1.25 0.6 -0.8 1.6" ;;
    demo) SRC="$OUT/demo.obj"; MESH=""; lo="-1.3 2.6 0.9 0.55 -1.3 2.6" ;;
    bunny) SRC="$OUT/bunny_diffuse.json"; MESH="--max-edge 0.2 --winding keep"; lo="-0.9 1.8 1.1 0.7 -0.9 1.8" ;;
    esac
    bake() {   # name, options...
        name=$1; shift
        # shellcheck disable=SC2086
        [ -s "$OUT/$scene-$name.prt" ] || nice "$PRT" bake "$SRC" $MESH --method lightcloud --samples 512 --no-refine --cloud-grid 5,5,5 --compress none "$@" \
            -o "$OUT/$scene-$name.prt" -q
    }
    bake raw --merge-distance 0
    spacing=$("$PRT" info "$OUT/$scene-raw.prt" --json | tr -d '\n\t ' | sed 's/.*"cloud_spacing":\([0-9.e+-]*\).*/\1/')
    half=$(awk -v s="$spacing" 'BEGIN { printf "%.4f", 1.5 * s }')
    for how in mean harmonic solve; do
        bake "$how" --merge-response "$how"
        bake "$how-near" --merge-response "$how" --merge-distance "$half"
    done
    : >"$OUT/$scene-lights.txt"
    set -- $lo
    for i in $(seq 1 "$LIGHTS"); do
        coord "$1" "$2"; x=$C; coord "$3" "$4"; y=$C; coord "$5" "$6"; z=$C
        L="point:$x,$y,$z:0.6"
        echo "$L" >>"$OUT/$scene-lights.txt"
        [ -s "$OUT/$scene-ref$i.json" ] || nice "$PRT" reference "$OUT/$scene-raw.prt" --light "$L" --env none --emission 0 --samples "$SAMPLES" -o "$OUT/$scene-ref$i.json" -q
    done
done

for scene in $scenes; do
    echo
    echo "| $scene: merge | responses | total | beyond noise | indirect | beyond noise | merged lights per zone |"
    echo "| --- | --- | ---: | ---: | ---: | ---: | ---: |"
    for name in raw mean harmonic solve mean-near harmonic-near solve-near; do
        f="$OUT/$scene-$name.prt"
        sums=$(i=0; while read -r L; do i=$((i + 1)); echo "$(metric "$f" "$OUT/$scene-ref$i.json" "$L" "") $(metric "$f" "$OUT/$scene-ref$i.json" "$L" --indirect)"; done <"$OUT/$scene-lights.txt" |
               awk '{ a += $1; b += $2; c += $3; d += $4; n++ } END { printf "%.4f %.4f %.4f %.4f", a / n, b / n, c / n, d / n }')
        lights=$("$PRT" info "$f" --json | tr -d '\n\t ' | sed 's/.*"merged_lights_per_zone":\[\([^]]*\)\].*/\1/' | awk -F, '{ for (i = 1; i <= NF; ++i) s += $i; printf "%.1f", s / NF }')
        case $name in raw) d="none"; h="-" ;; *-near) d="1.5 x spacing"; h=${name%-near} ;; *) d="3 x spacing (default)"; h=$name ;; esac
        echo "$sums $lights" | awk -v d="$d" -v h="$h" '{ printf "| %s | %s | %.3f | %.3f | %.3f | %.3f | %s |\n", d, h, $1, $2, $3, $4, $5 }'
    done
done
