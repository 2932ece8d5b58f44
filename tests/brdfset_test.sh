#!/bin/sh
# BRDFs switched at run time among a set baked per material (the spectral paper's Fig. 7, issue
# 26): switching gives what a bake wearing that BRDF gives, to the bit; what was not baked is
# refused with the set listed.
# Usage: brdfset_test.sh PATH/TO/prt
set -u
PRT=$1
T=$(mktemp -d /tmp/prt_brdfset_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"

# A 4 x 4 floor and a 1 x 1 x 1 box on it, each a material of the JSON scene.
printf 'v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 3 2\nf 1 4 3\n' >"$T/floor.obj"
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n' >"$T/box.obj"
printf 'f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 7 3\nf 4 8 7\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n' >>"$T/box.obj"
scene() {   # scene NAME MATERIAL-JSON
    printf '{"environment": "none", "materials": {"floor": {"albedo": 0.5}, "shiny": %s},\n' "$2" >"$T/$1.json"
    printf ' "meshes": [{"file": "floor.obj", "material": "floor"}, {"file": "box.obj", "material": "shiny", "translate": [-0.5, 0, -0.5]}]}\n' >>"$T/$1.json"
}
scene set '{"brdfs": ["phong:20:0.5:0.3", "blinn:40:0.5:0.3", "lambert:0.6"]}'
scene blinn '{"brdf": "blinn:40:0.5:0.3"}'
scene lambert '{"brdf": "lambert:0.6"}'
BAKE="--method spectral --basis 48 --samples 64 --max-edge 0.3 --no-refine"
for s in set blinn lambert; do expect 0 "bake $s" -- "$PRT" bake -q "$T/$s.json" -o "$T/$s.prt" $BAKE; done
expect 0 "info lists the set" -- "$PRT" info "$T/set.prt"
grep -q "brdf sets: *shiny: phong:20:0.5:0.3, blinn:40:0.5:0.3, lambert:0.6" "$T/out" && ok || bad "prt info does not list the BRDF set: $(grep -i brdf "$T/out")"
expect 0 "info --json lists the set" -- "$PRT" info --json "$T/set.prt"
grep -q '"brdfs"' "$T/out" && ok || bad "prt info --json has no \"brdfs\""

LIGHT0="--env none --light point:0.8,1.5,0.8:4"
LIGHT="$LIGHT0 --eye 3,2,3"
# Switched at run time = baked wearing it (the glossy rows hold incident radiance whatever the
# BRDF; the set's SH projections were made at bake time). Spelt differently, the same BRDF.
expect 0 "relight switched to blinn" -- "$PRT" relight -q "$T/set.prt" $LIGHT --brdf-of shiny=blinn:40:0.50:0.30 -o "$T/sw.json"
expect 0 "relight the blinn bake" -- "$PRT" relight -q "$T/blinn.prt" $LIGHT -o "$T/b.json"
same "$T/sw.json" "$T/b.json" 0 "switched to blinn vs baked with blinn"
expect 0 "relight switched to lambert" -- "$PRT" relight -q "$T/set.prt" $LIGHT --brdf-of shiny=lambert:0.6 -o "$T/swl.json"
expect 0 "relight the lambert bake" -- "$PRT" relight -q "$T/lambert.prt" $LIGHT0 -o "$T/l.json"
same "$T/swl.json" "$T/l.json" 0 "switched to lambert vs baked with lambert"
# The baked default and the switch differ (the glossy reflection changed).
expect 0 "relight as baked" -- "$PRT" relight -q "$T/set.prt" $LIGHT -o "$T/def.json"
"$PRT" compare "$T/def.json" "$T/sw.json" --json - -q >"$T/cmp" 2>/dev/null
m=$(sed -n 's/.*"max_abs":[[:space:]]*\([0-9.eE+-]*\).*/\1/p' "$T/cmp")
awk -v m="$m" 'BEGIN { exit !(m != "" && m + 0 > 1e-4) }' && ok || bad "switching the BRDF changed nothing (max |A-B| '$m')"
# --albedo-of wins over the switched BRDF's diffuse part.
expect 0 "switched and recoloured" -- "$PRT" relight -q "$T/set.prt" $LIGHT --brdf-of shiny=lambert:0.6 --albedo-of shiny=0.6 -o "$T/swp.json"
same "$T/swp.json" "$T/l.json" 0 "--albedo-of with the same colour"
expect 0 "render switched" -- $NOLEAK "$PRT" render "$T/set.prt" $LIGHT --target 0,0.5,0 --brdf-of shiny=blinn:40:0.5:0.3 --width 64 --height 48 -o "$T/sw.png"

# The same set from the bake's command line, beside what the surface wears (listed first).
expect 0 "bake with --brdf-set" -- "$PRT" bake -q "$T/blinn.json" -o "$T/flag.prt" $BAKE --brdf-set shiny=phong:20:0.5:0.3,lambert:0.6
expect 0 "info of the --brdf-set bake" -- "$PRT" info "$T/flag.prt"
grep -q "brdf sets: *shiny: blinn:40:0.5:0.3, phong:20:0.5:0.3, lambert:0.6" "$T/out" && ok || bad "--brdf-set: $(grep -i "brdf sets" "$T/out")"
expect 0 "switch the --brdf-set bake" -- "$PRT" relight -q "$T/flag.prt" $LIGHT --brdf-of shiny=phong:20:0.5:0.3 -o "$T/flag.json"
same "$T/flag.json" "$T/def.json" 0 "--brdf-set bake switched to phong vs the JSON set's bake as baked"
expect 2 "--brdf-set on an unknown surface" -- "$PRT" bake -q "$T/blinn.json" -o "$T/x.prt" $BAKE --brdf-set shine=phong:20
says "no surface 'shine' (the scene has floor, shiny)"

# Against the path tracer tracing each BRDF worn (the spectral test's glossy floor before a
# glowing wall, seen from one eye: the floor shows the wall only through the glossy final bounce).
# Switched to each BRDF of the set, the floor is closest to the reference of that BRDF, and within
# its noise plus what the 16 SH bases cost (measured: lambert 4.3%, phong:2 4.7%, phong:8 6.7%
# against 4.2% noise; across BRDFs 8% to 160%. With 2048 rays and 1024 paths: 3.1%, 3.2%, 5.5%
# against 3.0%).
printf 'v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nf 1 2 3\nf 1 3 4\n' >"$T/gfloor.obj"
printf 'v -1 0 -1\nv 1 0 -1\nv 1 1 -1\nv -1 1 -1\nf 1 2 3\nf 1 3 4\n' >"$T/gwall.obj"
glowing() {   # glowing NAME FLOOR-MATERIAL-JSON
    printf '{"environment": "none", "materials": {"floor": %s, "wall": {"albedo": 0, "emission": 1}},' "$2" >"$T/$1.json"
    printf ' "meshes": [{"file": "gfloor.obj", "material": "floor"}, {"file": "gwall.obj", "material": "wall"}]}\n' >>"$T/$1.json"
}
SET3="lambert:0.3 phong:2:0.3:0.5 phong:8:0.3:0.5"
glowing gset '{"brdfs": ["lambert:0.3", "phong:2:0.3:0.5", "phong:8:0.3:0.5"]}'
expect 0 "bake the glossy floor's set" -- "$PRT" bake -q "$T/gset.json" -o "$T/gset.prt" --method spectral --basis 128 --samples 1024 --max-edge 0.125 --no-refine
i=0
for b in $SET3; do
    i=$((i + 1))
    glowing "g$i" "{\"brdf\": \"$b\"}"
    expect 0 "trace the floor wearing $b" -- "$PRT" reference -q "$T/g$i.json" --eye 0,0.6,2.5 --target 0,0,0 --samples 512 --max-edge 0.125 -o "$T/gr$i.json"
    expect 0 "switch the floor to $b" -- "$PRT" relight -q "$T/gset.prt" --eye 0,0.6,2.5 --brdf-of "floor=$b" -o "$T/gs$i.json"
done
# Relative L2 over the floor (the wall glows 1 in both), the reference's noise left in.
rows() {   # the radiance of a per-vertex JSON, one "r g b" line per vertex
    sed -n 's/^ *"radiance": \[\[\(.*\)\]\],*$/\1/p' "$1" | sed 's/\], \[/\n/g' | tr -d ','
}
floor_l2() {
    rows "$1" >"$T/a.txt"
    rows "$2" >"$T/b.txt"
    paste -d' ' "$T/a.txt" "$T/b.txt" | awk 'NF == 6 && $4 < 0.9 { for (c = 1; c <= 3; ++c) { d = $c - $(c + 3); n += d * d; s += $(c + 3) * $(c + 3) } }
                                         END { if (s > 0) printf "%.4f", sqrt(n / s) }'
}
for a in 1 2 3; do
    row=""
    for b in 1 2 3; do row="$row $(floor_l2 "$T/gs$a.json" "$T/gr$b.json")"; done
    echo "switched to BRDF $a against the references of BRDFs 1..3:$row"
    set -- $row
    eval "own=\$$a"
    best=$(printf '%s\n' "$@" | sort -g | head -n 1)
    [ "$own" = "$best" ] && ok || bad "switched to BRDF $a, the floor is nearer another BRDF's reference ($row)"
    awk -v e="$own" 'BEGIN { exit !(e != "" && e + 0 < 0.09) }' && ok || bad "switched to BRDF $a: $own from its reference (noise 0.04)"
done

# Refusals, one line each, naming what there is.
expect 2 "a BRDF not baked" -- "$PRT" relight "$T/set.prt" $LIGHT --brdf-of shiny=phong:80 -o "$T/x.json"
says "not in the set baked for 'shiny' (phong:20:0.5:0.3, blinn:40:0.5:0.3, lambert:0.6)"
expect 2 "a surface without a set" -- "$PRT" relight "$T/set.prt" $LIGHT --brdf-of floor=lambert:0.5 -o "$T/x.json"
says "no BRDF set"
expect 2 "an unknown surface" -- "$PRT" relight "$T/set.prt" $LIGHT --brdf-of flor=lambert:0.5 -o "$T/x.json"
says "it has floor, shiny"
expect 2 "a bad BRDF" -- "$PRT" relight "$T/set.prt" $LIGHT --brdf-of shiny=glass -o "$T/x.json"
expect 2 "a file without sets" -- "$PRT" relight "$T/blinn.prt" $LIGHT --brdf-of shiny=blinn:40:0.5:0.3 -o "$T/x.json"
says "no BRDF set"
expect 2 "reference takes none" -- "$PRT" reference "$T/set.json" --brdf-of shiny=lambert:0.6 -o "$T/x.json"
expect 0 "a method that keeps no sets" -- "$PRT" bake "$T/set.json" -o "$T/sh.prt" --method ao --samples 16 --max-edge 0.3 --no-refine
says "spectral files do"
scene aniso '{"brdfs": ["phong:20:0.5:0.3", "ashikhmin:100:10:0.5:0.3"]}'
expect 1 "an anisotropic candidate" -- "$PRT" bake -q "$T/aniso.json" -o "$T/x.prt" $BAKE
says "anisotropic"
scene badset '{"brdfs": []}'
expect 1 "an empty set" -- "$PRT" bake -q "$T/badset.json" -o "$T/x.prt" $BAKE
says "brdfs"

# Light clouds bake colours into every stored response: --albedo-of is refused saying why, and
# --brdf-of finds no set.
LC="$(dirname "$0")/../fuzz/regress/prt/lightcloud/seed.prt"
expect 2 "light cloud colours" -- "$PRT" relight "$LC" --light point:0,1,0:1 --albedo-of floor=0.5 -o "$T/x.json"
says "every bounce of each stored cloud-light response was multiplied by the baked colours"
[ "$(wc -l <"$T/err")" -eq 1 ] && ok || bad "the light cloud's refusal takes one line, not $(wc -l <"$T/err")"
expect 2 "light cloud BRDFs" -- "$PRT" relight "$LC" --light point:0,1,0:1 --brdf-of floor=lambert:0.5 -o "$T/x.json"
says "no BRDF set"

# The viewer: m selects a surface, r gives it the next BRDF of its set; the frame is what prt
# render draws with --brdf-of, and three presses come back to the baked one.
if command -v xvfb-run >/dev/null 2>&1; then
    CAM="--width 160 --height 120 --eye 3,2,3 --target 0,0.5,0 --fov 50"
    printf '%s\n' "0 screenshot v0.exr" "0 key m" "0 key m" "0 key r" "0.1 screenshot v1.exr" "0.1 key r" "0.1 key r" "0.2 screenshot v2.exr" "0.2 quit" >"$T/script.txt"
    expect 0 "view cycles the set" -- $NOLEAK xvfb-run -a -s "-screen 0 1024x768x24" "$PRT" view "$T/set.prt" $LIGHT0 $CAM --script "$T/script.txt"
    expect 0 "render as baked" -- $NOLEAK "$PRT" render -q "$T/set.prt" $LIGHT0 $CAM -o "$T/r0.exr"
    expect 0 "render switched" -- $NOLEAK "$PRT" render -q "$T/set.prt" $LIGHT0 $CAM --brdf-of shiny=blinn:40:0.5:0.3 -o "$T/r1.exr"
    same "$T/v0.exr" "$T/r0.exr" 0.002 "the viewer's first frame vs prt render"
    same "$T/v1.exr" "$T/r1.exr" 0.002 "the viewer after r vs prt render --brdf-of"
    same "$T/v2.exr" "$T/r0.exr" 0.002 "the viewer after r r r vs as baked"
    expect 0 "view help" -- $NOLEAK xvfb-run -a -s "-screen 0 1024x768x24" "$PRT" view "$T/set.prt" $LIGHT0 --help
    grep -q "BRDF" "$T/out" && ok || bad "prt view --help does not mention switching BRDFs"
else
    echo "skipping the viewer checks: xvfb-run is not installed"
fi

echo "brdfset: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
