#!/bin/sh
# Key-framed PRT (Kautz's course notes, "animated objects"; issue 27): a strip of 2 x 0.5 that
# curls up from flat into a half circle (uniform curvature, angle 0 to 180 degrees), as 3, 5 and 9
# key frames over the same motion, baked with prt bake --frames (one clustered PCA over every
# frame's rows) and relit under the default sky. Measures, as relative L2 of the per-vertex
# radiance: each key frame against its own bake (the compression across frames alone), and the
# pose halfway between two key frames (--time K+0.5) against a bake of that pose itself. Storage:
# the key-framed file against the key frames as separate files (prt's default 16-bit sets).
# Usage: bench/keyframes.sh PATH/TO/prt OUTDIR [CELLS] [SAMPLES]
# (defaults 96 cells along the strip, 24 across = 2,425 vertices, 512 directions; 17 poses baked
# alone and 3 key-framed bakes, a few minutes on 2 cores). Environment: BAKE (more bake options,
# e.g. "--clusters 32 --vectors 4").
set -eu
PRT=$1
OUT=$2
CELLS=${3:-96}
SAMPLES=${4:-512}
OPTS="--samples $SAMPLES --no-refine --winding keep -q ${BAKE:-}"
mkdir -p "$OUT"
# pose NAME ANGLE: the strip curled by ANGLE degrees.
pose() {
    awk -v n="$CELLS" -v a="$2" 'BEGIN {
        m = n / 4; A = a * 3.14159265358979 / 180
        for (j = 0; j <= m; j++) for (i = 0; i <= n; i++) {
            s = 2 * i / n; z = -0.25 + 0.5 * j / m
            if (A == 0) { x = -1 + s; y = 0 } else { R = 2 / A; x = -1 + R * sin(A * s / 2); y = R * (1 - cos(A * s / 2)) }
            printf "v %.7f %.7f %.7f\n", x, y, z
        }
        for (j = 0; j < m; j++) for (i = 0; i < n; i++) {
            p = j * (n + 1) + i + 1
            printf "f %d %d %d\nf %d %d %d\n", p, p + n + 1, p + 1, p + 1, p + n + 1, p + n + 2
        }
    }' >"$OUT/$1.obj"
}
rel() { "$PRT" compare "$1" "$2" --json - -q | sed -n 's/.*"relative_l2":[[:space:]]*\([0-9.eE+-]*\).*/\1/p'; }
size() { wc -c <"$1" | tr -d ' '; }
# The 9 key poses (every 22.5 degrees) hold those of 5 and 3 key frames; 8 more poses halfway.
for k in 0 1 2 3 4 5 6 7 8; do
    pose "k$k" "$(awk -v k=$k 'BEGIN { print 22.5 * k }')"
    "$PRT" bake "$OUT/k$k.obj" -o "$OUT/k$k.prt" $OPTS
    "$PRT" relight -q "$OUT/k$k.prt" -o "$OUT/k$k.json"
done
for k in 0 1 2 3 4 5 6 7; do
    pose "m$k" "$(awk -v k=$k 'BEGIN { print 22.5 * k + 11.25 }')"
    "$PRT" bake "$OUT/m$k.obj" -o "$OUT/m$k.prt" $OPTS
    "$PRT" relight -q "$OUT/m$k.prt" -o "$OUT/m$k.json"
done
printf '%-6s %-12s %-12s %-14s %-16s %-14s %s\n' keys file_bytes separate ratio key_rel_l2 mid_rel_l2 nearest_key_rel_l2
for F in 3 5 9; do
    step=$((8 / (F - 1)))
    frames="" separate=0 k=0
    while [ $k -le 8 ]; do frames="$frames $OUT/k$k.obj"; separate=$((separate + $(size "$OUT/k$k.prt"))); k=$((k + step)); done
    "$PRT" bake --frames $frames -o "$OUT/anim$F.prt" $OPTS
    key=0 mid=0 near=0 n=0
    for i in $(seq 0 $((F - 2))); do
        "$PRT" relight -q "$OUT/anim$F.prt" --time "$i" -o "$OUT/a$F-$i.json"
        "$PRT" relight -q "$OUT/anim$F.prt" --time "$i.5" -o "$OUT/a$F-$i.5.json"
        # The pose halfway between key frames i and i + 1: 9-key pose (i + 0.5) * step, a key
        # pose of the 9 or a midpoint.
        h2=$(( (2 * i + 1) * step ))   # in units of 11.25 degrees
        if [ $((h2 % 2)) -eq 0 ]; then truth="$OUT/k$((h2 / 2)).json"; else truth="$OUT/m$((h2 / 2)).json"; fi
        key=$(awk -v a="$key" -v b="$(rel "$OUT/a$F-$i.json" "$OUT/k$((i * step)).json")" 'BEGIN { print a + b }')
        mid=$(awk -v a="$mid" -v b="$(rel "$OUT/a$F-$i.5.json" "$truth")" 'BEGIN { print a + b }')
        near=$(awk -v a="$near" -v b="$(rel "$OUT/k$((i * step)).json" "$truth")" 'BEGIN { print a + b }')
        n=$((n + 1))
    done
    fb=$(size "$OUT/anim$F.prt")
    awk -v F=$F -v fb=$fb -v sep=$separate -v key=$key -v mid=$mid -v near=$near -v n=$n \
        'BEGIN { printf "%-6d %-12d %-12d %-14.2f %-16.4f %-14.4f %.4f\n", F, fb, sep, sep / fb, key / n, mid / n, near / n }'
done
"$PRT" info "$OUT/anim9.prt" | grep -A4 "key frames"
