#!/bin/sh
# The glossy-bunny scene of Kristensen et al. 2005 (Fig. 9), as far as the paper describes it: the
# Stanford bunny in a closed enclosure with a red and a blue wall (x = -1.2 red, x = +1.2 blue,
# the rest white; 2.4 x 2 x 2.4, faces towards the inside), the bunny 1 unit long on the floor.
# Writes OUTDIR/bunny_box.obj (+ .mtl) and OUTDIR/bunny_MATERIAL.json: the bunny diffuse
# (MATERIAL diffuse, albedo 0.7) or glossy (MATERIAL glossy: Phong exponent 12 as the paper's,
# ks 0.4, kd 0.4).
# Usage: bench/bunny_box.sh PATH/TO/bunny_lowres.obj OUTDIR diffuse|glossy
set -eu
BUNNY=$1
OUT=$2
KIND=$3
mkdir -p "$OUT"
cp "$BUNNY" "$OUT/bunny_lowres.obj"
cat >"$OUT/bunny_box.mtl" <<'MTL'
newmtl white
Kd 0.7 0.7 0.7
newmtl red
Kd 0.7 0.1 0.08
newmtl blue
Kd 0.1 0.15 0.7
MTL
cat >"$OUT/bunny_box.obj" <<'OBJ'
# closed box, faces towards the inside
mtllib bunny_box.mtl
v -1.2 0 -1.2
v 1.2 0 -1.2
v 1.2 0 1.2
v -1.2 0 1.2
v -1.2 2 -1.2
v 1.2 2 -1.2
v 1.2 2 1.2
v -1.2 2 1.2
usemtl white
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
usemtl red
f 1 5 8 4
usemtl blue
f 2 3 7 6
OBJ
if [ "$KIND" = glossy ]; then MAT='{ "brdf": "phong:12:0.4:0.4" }'; else MAT='{ "albedo": 0.7 }'; fi
cat >"$OUT/bunny_$KIND.json" <<JSON
{
  "materials": { "bunny": $MAT },
  "environment": "none",
  "meshes": [
    { "file": "bunny_box.obj" },
    { "file": "bunny_lowres.obj", "material": "bunny", "scale": 0.1 }
  ]
}
JSON
