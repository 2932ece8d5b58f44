#!/bin/sh
# The demo: every method of the table on the procedural demo scene (a sphere and a torus on a
# floor between a red and a green wall), each as an animated PNG of its lighting moving - the sky
# turning for the methods that relight distant light, a point light crossing the scene for those
# that relight local light - and two stills of all of them side by side beside the path tracer.
# Bakes use each method's defaults except where a cheaper setting keeps the demo within its
# time (stated beside each); `prt pick out/demo/scene.obj` measures them all properly.
set -eu
PRT=${1:-build/prt}
OUT=${2:-out/demo}
mkdir -p "$OUT"
W=320
H=240
SIZE="--width $W --height $H"
POINT_FROM=point:1.0,0.9,-0.9:3
POINT_TO=point:-0.9,0.9,1.0:3
POINT_MID=point:0.05,0.9,0.05:3
start=$(date +%s)
step() { printf '%-58s' "$1"; }
took() { echo " $(($(date +%s) - $1)) s"; }

"$PRT" demo-scene -o "$OUT/scene.obj"
# The sphere and torus glossy (the walls and floor stay diffuse): every method bakes this scene,
# and each draws what it can of it (ao and offset reflect diffusely).
printf '%s\n' '{ "materials": { "sphere": { "brdf": "phong:30:0.5:0.4" }, "torus": { "brdf": "blinn:60:0.4:0.5" } },' \
    '  "meshes": [ { "file": "scene.obj" } ] }' >"$OUT/glossy.json"

t=$(date +%s); step "sh: SH PRT, order 5, inter-reflected + glossy"
"$PRT" bake -q "$OUT/glossy.json" -o "$OUT/sh.prt" --order 5 --kinds shadowed,interreflected,glossy-shadowed,glossy-interreflected; took "$t"
t=$(date +%s); step "wavelet: all-frequency glossy (--supersample 1: 6x64x64)"
"$PRT" bake -q "$OUT/glossy.json" -o "$OUT/wavelet.prt" --method wavelet --supersample 1; took "$t"
t=$(date +%s); step "ao: ambient occlusion"
"$PRT" bake -q "$OUT/glossy.json" -o "$OUT/ao.prt" --method ao; took "$t"
t=$(date +%s); step "spectral: direct-to-indirect transfer"
"$PRT" bake -q "$OUT/glossy.json" -o "$OUT/spectral.prt" --method spectral; took "$t"
t=$(date +%s); step "lightcloud: light clouds (--cloud-grid 3,2,3: 18 lights)"
"$PRT" bake -q "$OUT/glossy.json" -o "$OUT/lightcloud.prt" --method lightcloud --cloud-grid 3,2,3; took "$t"
t=$(date +%s); step "offset: offset radiance transfer maps"
"$PRT" bake -q "$OUT/glossy.json" -o "$OUT/offset.prt" --method offset; took "$t"

t=$(date +%s); step "path-traced references (prt reference --image)"
"$PRT" reference -q "$OUT/glossy.json" --image "$OUT/reference_sky.exr" $SIZE --samples 64
"$PRT" reference -q "$OUT/glossy.json" --image "$OUT/reference_point.exr" $SIZE --samples 64 --env none --light "$POINT_MID"
took "$t"

t=$(date +%s); step "stills: every method beside the path tracer"
"$PRT" render -q "$OUT/sh.prt" "$OUT/wavelet.prt" "$OUT/ao.prt" "$OUT/spectral.prt" "$OUT/offset.prt" "$OUT/reference_sky.exr" \
    -o "$OUT/all_sky.png" $SIZE
"$PRT" render -q "$OUT/spectral.prt" "$OUT/lightcloud.prt" "$OUT/offset.prt" "$OUT/reference_point.exr" \
    -o "$OUT/all_point.png" $SIZE --env none --light "$POINT_MID"
took "$t"

t=$(date +%s); step "animations: the sky turning, a point light crossing"
for m in sh wavelet ao; do
    "$PRT" render -q "$OUT/$m.prt" -o "$OUT/${m}_sky.png" $SIZE --frames 10
done
for m in spectral lightcloud offset; do
    "$PRT" render -q "$OUT/$m.prt" -o "$OUT/${m}_point.png" $SIZE --frames 10 --env none --light "$POINT_FROM" --light-to "$POINT_TO"
done
took "$t"

cat <<EOF

Demo done in $(($(date +%s) - start)) s. Pictures in $OUT/ (the .png files are animated PNGs where
named *_sky or *_point: open them in a web browser):
  all_sky.png       under the procedural sky, left to right: sh (glossy sphere and torus), wavelet
                    (all-frequency: sharper shadows and highlights), ao (occlusion only: no colour
                    bleeding), spectral, offset, and the path tracer (64 paths per pixel)
  all_point.png     under a point light above the scene: spectral, lightcloud, offset, and the
                    path tracer (the methods that relight local lights)
  sh_sky.png wavelet_sky.png ao_sky.png
                    the sky turning once about the scene: shadows and colour bleeding follow it
  spectral_point.png lightcloud_point.png offset_point.png
                    a point light crossing the scene: direct light, shadows and indirect light
                    (red and green bleeding onto the floor) follow it
Next: prt view $OUT/spectral.prt (drag lights live), prt info $OUT/sh.prt, and
prt pick $OUT/scene.obj to measure every method against the path tracer.
EOF
