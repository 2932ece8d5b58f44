#!/bin/sh
# The demo: generate the procedural scene, bake the three diffuse transfer kinds, and render
# them side by side under the procedural sky and under a rotated environment; then glossy
# transfer matrices (a Phong lobe on every surface) and per-texel transfer over the scene's UVs.
set -eu
PRT=${1:-build/prt}
OUT=${2:-out/demo}
mkdir -p "$OUT"
"$PRT" demo-scene -o "$OUT/scene.obj"
"$PRT" bake "$OUT/scene.obj" -o "$OUT/scene.prt" --order 6 --samples 1024 --bounces 3
"$PRT" info "$OUT/scene.prt"
"$PRT" render "$OUT/scene.prt" --kind all -o "$OUT/sky.png" --width 480 --height 360
"$PRT" render "$OUT/scene.prt" --kind all -o "$OUT/sky_rotated.png" --width 480 --height 360 --rotate 150
"$PRT" render "$OUT/scene.prt" --kind interreflected -o "$OUT/interreflected.exr" --width 480 --height 360
"$PRT" env --order 6 --image "$OUT/sky_irradiance.png" --irradiance -o "$OUT/sky_sh.json" -q
"$PRT" bake "$OUT/scene.obj" -o "$OUT/glossy.prt" --order 5 --samples 512 --bounces 2 \
    --kinds shadowed,interreflected,glossy-shadowed,glossy-interreflected
"$PRT" render "$OUT/glossy.prt" --kind interreflected,glossy-interreflected -o "$OUT/glossy.png" --width 480 --height 360 --brdf phong:40:0.4
"$PRT" bake "$OUT/scene.obj" -o "$OUT/texels.prt" --order 5 --samples 512 --bounces 2 --texels 512 --kinds shadowed,interreflected
"$PRT" render "$OUT/texels.prt" --kind shadowed,interreflected -o "$OUT/texels.png" --width 480 --height 360
"$PRT" relight "$OUT/texels.prt" --texels --kind interreflected -o "$OUT/lightmap.png" -q
"$PRT" bake "$OUT/scene.obj" -o "$OUT/wavelet.prt" --method wavelet --brdf phong:30:0.4:0.5 --bounces 1
"$PRT" render "$OUT/wavelet.prt" -o "$OUT/wavelet.png" --width 480 --height 360
"$PRT" render "$OUT/wavelet.prt" -o "$OUT/wavelet_rotated.png" --width 480 --height 360 --rotate 150
PROBE=../shared/data/envmaps/probulator_ict/grace.hdr
if [ -f "$PROBE" ]; then
    "$PRT" render "$OUT/scene.prt" --kind all -o "$OUT/grace.png" --width 480 --height 360 --env "$PROBE" --exposure -1
    "$PRT" render "$OUT/scene.prt" --kind all -o "$OUT/grace_rotated.png" --width 480 --height 360 --env "$PROBE" --rotate 90 --exposure -1
else
    echo "demo: $PROBE not found; skipping the light-probe renders" >&2
fi
echo
echo "Demo images (sky*, grace*: unshadowed, shadowed, inter-reflected; glossy: diffuse, then with the"
echo "Phong lobe evaluated per pixel; texels: per-texel shadowed, inter-reflected; lightmap: the map;"
echo "wavelet*: all-frequency glossy transfer, one bounce, Haar-wavelet lighting):"
for f in "$OUT"/*.png "$OUT"/*.exr; do echo "  $f"; done
