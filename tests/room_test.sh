#!/bin/sh
# A closed room wound inwards with nothing in it but a light or the camera keeps its winding
# (issue 26): whether the light comes from prt bake --light, the JSON scene's "lights", or the
# camera is the JSON scene's "camera" or --eye. Flipped inside out, every vertex would be black.
# Usage: room_test.sh PATH/TO/prt
set -u
PRT=$1
T=$(mktemp -d /tmp/prt_room_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"

# A 2 x 2 x 2 box without normals, every face counter-clockwise seen from inside.
cat >"$T/room.obj" <<'OBJ'
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v -1 2 -1
v 1 2 -1
v 1 2 1
v -1 2 1
f 3 2 1
f 4 3 1
f 7 8 5
f 6 7 5
f 6 5 1
f 2 6 1
f 7 6 2
f 3 7 2
f 8 7 3
f 4 8 3
f 5 8 4
f 1 5 4
OBJ
printf '{"environment": "none", "meshes": [{"file": "room.obj"}], "lights": [{"type": "point", "position": [0, 1.5, 0], "intensity": 5}]}\n' >"$T/light.json"
printf '{"environment": "none", "meshes": [{"file": "room.obj"}], "camera": {"eye": [0, 1, 0.9], "target": [0, 0.5, 0], "fov": 60}}\n' >"$T/camera.json"

# lit FILE WHAT: no vertex of the per-vertex JSON FILE is black.
lit() {
    n=$(sed -n 's/.*"vertex_count":[[:space:]]*\([0-9]*\).*/\1/p' "$1")
    z=$(sed -n '/"radiance"/p' "$1" | grep -o '\[0, 0, 0\]' | wc -l)
    [ -n "$n" ] && [ "$n" -gt 0 ] && [ "$z" -eq 0 ] && ok || bad "$2: $z of $n vertices black (the room was turned inside out)"
}

# 1. The light given to prt bake: kept, stored in the file and lighting its relight.
expect 0 "bake with --light" -- "$PRT" bake "$T/room.obj" -o "$T/a.prt" --method spectral --no-refine --light point:0,1.5,0:5
says "a room seen from inside"
expect 0 "relight under the stored light" -- "$PRT" relight -q "$T/a.prt" -o "$T/a.json"
lit "$T/a.json" "bake --light"
expect 0 "info lists the stored light" -- "$PRT" info "$T/a.prt"
grep -qi "point" "$T/out" && ok || bad "prt info does not show the --light of the bake"
for spec in spot:0,1.5,0:0,-1,0:40:5 sphere:0.3,1,0:0.1:20; do
    expect 0 "bake with --light $spec" -- "$PRT" bake "$T/room.obj" -o "$T/s.prt" --method spectral --no-refine --light "$spec"
    says "a room seen from inside"
done
# A directional light has no position: the lone room is an object seen from outside.
expect 0 "bake with a directional --light" -- "$PRT" bake "$T/room.obj" -o "$T/d.prt" --method spectral --no-refine --light directional:0,1,0:1
says "flipped"
expect 2 "bad --light" -- "$PRT" bake "$T/room.obj" -o "$T/x.prt" --light point:0,1
says "light"
# 2. The light the JSON scene names.
expect 0 "bake a scene with a light" -- "$PRT" bake -q "$T/light.json" -o "$T/b.prt" --method spectral --no-refine
expect 0 "relight the scene's light" -- "$PRT" relight -q "$T/b.prt" -o "$T/b.json"
lit "$T/b.json" "JSON light"
# 3. The camera the JSON scene names; lit afterwards at run time.
expect 0 "bake a scene with a camera" -- "$PRT" bake "$T/camera.json" -o "$T/c.prt" --method spectral --no-refine
says "a room seen from inside"
expect 0 "relight with a light" -- "$PRT" relight -q "$T/c.prt" --light point:0,1.5,0:5 -o "$T/c.json"
lit "$T/c.json" "JSON camera"
# The path tracer on the mesh file: the room is kept around its --light and around its --eye.
expect 0 "reference with --light" -- "$PRT" reference "$T/room.obj" --env none --light point:0,1.5,0:5 --samples 4 -o "$T/r.json"
says "a room seen from inside"
lit "$T/r.json" "reference --light"
expect 0 "reference with --eye" -- "$PRT" reference "$T/room.obj" --env none --light none --eye 0,1,0.9 --target 0,0.5,0 --samples 1 -o "$T/e.json"
says "a room seen from inside"

echo "room: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
