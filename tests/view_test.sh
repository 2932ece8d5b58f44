#!/bin/sh
# prt view under Xvfb: scripted screenshots equal prt render for the same camera and lighting,
# before and after rotating the environment; bad scripts and a missing display fail clearly.
# Usage: view_test.sh PATH/TO/prt. Exits 77 (skipped) when xvfb-run is not installed.
set -u
PRT=$1
if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "skipping: xvfb-run is not installed (scripts/setup-deps.sh installs xvfb)"
    exit 77
fi
T=$(mktemp -d /tmp/prt_view_XXXXXX)
trap 'rm -rf "$T"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
# xvfb-run, run again (up to three times in all) when xvfb-run itself failed to remove its
# temporary directory (exit 5, seen under load, twice in a row once), which says nothing about prt.
xrun() {
    xvfb-run "$@"
    xrc=$?
    for again in 1 2; do
        [ "$xrc" -eq 5 ] && grep -q "cleaning up temporary directory" "$T/err" 2>/dev/null || break
        xvfb-run "$@"
        xrc=$?
    done
    return $xrc
}
# LeakSanitizer cannot attribute Mesa's driver allocations (see cli_test.sh).
export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"

# The bakes keep the scene's mesh (--no-refine; the wavelet one without bounces, as web_test.sh's):
# every check compares the viewer with prt render of the same file, and refining costs more than baking.
"$PRT" demo-scene -o "$T/demo.obj" && "$PRT" bake -q "$T/demo.obj" -o "$T/demo.prt" --order 4 --samples 64 --bounces 1 --no-refine || { echo "FAIL: setup"; exit 1; }

cat >"$T/script.txt" <<'S'
# time  verb  arguments
0    screenshot  first.exr
0    env-rotate  90 0
0    screenshot  SHOTS/rotated.exr
0    key k
0    key [
0    key d
0.1  drag left 40 -20
0.1  drag left 30 10 ctrl
0.2  zoom 0.8
0.3  screenshot  SHOTS/moved.png
0.3  quit
S
sed -i "s#SHOTS#$T#" "$T/script.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/demo.prt" --width 320 --height 240 --script "$T/script.txt" --stats >"$T/stats" 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "scripted view exited $rc"; cat "$T/err"; }
grep -q '"relight_ms"' "$T/stats" && ok || bad "--stats printed no relight time"
for f in first.exr rotated.exr moved.png; do [ -s "$T/$f" ] && ok || bad "no screenshot $f"; done

"$PRT" render -q "$T/demo.prt" -o "$T/render_first.exr" --width 320 --height 240
"$PRT" render -q "$T/demo.prt" -o "$T/render_rotated.exr" --width 320 --height 240 --rotate 90
# Equal per pixel within half-float rounding: max |A - B| tiny against radiance near 1.
field() { sed -n "s/.*\"$1\":[[:space:]]*\([-0-9.eE+]*\).*/\1/p" "$2" | head -n 1; }
within() {
    "$PRT" compare --json - -q "$1" "$2" >"$T/cmp" || { bad "compare $1 $2 failed"; return; }
    m=$(field max_abs "$T/cmp")
    awk -v m="$m" -v t="$3" 'BEGIN { exit !(m != "" && m <= t) }' && ok || bad "$1 differs from $2: max |A-B| = $m"
}
within "$T/first.exr" "$T/render_first.exr" 0.002
within "$T/rotated.exr" "$T/render_rotated.exr" 0.002
"$PRT" compare --json - -q "$T/first.exr" "$T/render_rotated.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.05) }' && ok || bad "rotating the environment changed nothing (relative L2 $r)"

# The probe (j): a sphere at the view's target lit by the neighbourhood transfer, as prt render --probe draws it.
"$PRT" bake -q "$T/demo.obj" -o "$T/nb.prt" --order 3 --samples 64 --bounces 1 --no-refine --neighbourhood 4 || bad "neighbourhood bake"
printf '%s\n' "0 key j" "0.1 screenshot p.exr" "0.1 quit" >"$T/pscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/nb.prt" --width 160 --height 120 --eye 2.4,1.6,3 --target 1,0.3,0.9 --fov 45 --script "$T/pscript.txt" \
    >/dev/null 2>"$T/err" && ok || { bad "probe script"; sed 's/^/    /' "$T/err"; }
"$PRT" render -q "$T/nb.prt" -o "$T/p_ref.exr" --width 160 --height 120 --eye 2.4,1.6,3 --target 1,0.3,0.9 --fov 45 --probe 1,0.3,0.9
"$PRT" render -q "$T/nb.prt" -o "$T/p_none.exr" --width 160 --height 120 --eye 2.4,1.6,3 --target 1,0.3,0.9 --fov 45
within "$T/p.exr" "$T/p_ref.exr" 0.002
"$PRT" compare --json - -q "$T/p.exr" "$T/p_none.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.01) }' && ok || bad "the probe changed nothing in the picture (relative L2 $r)"

# Fly mode: w moves the eye forward and a drag turns the view (each changes the image); the
# camera options set the starting view as prt render's do; screenshot paths follow the script.
printf '%s\n' "0 screenshot f0.exr" "0 key f" "0 key w" "0 key w" "0.1 screenshot f1.exr" "0.1 drag left 20 0" "0.2 screenshot f2.exr" "0.2 quit" >"$T/fscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/demo.prt" --width 160 --height 120 --eye 0,1,3 --target 0,0.5,0 --fov 50 --script "$T/fscript.txt" >/dev/null 2>"$T/err" \
    && ok || { bad "fly script"; sed 's/^/    /' "$T/err"; }
"$PRT" render -q "$T/demo.prt" -o "$T/f_ref.exr" --width 160 --height 120 --eye 0,1,3 --target 0,0.5,0 --fov 50
within "$T/f0.exr" "$T/f_ref.exr" 0.002   # --eye --target --fov: the same first frame as prt render
for pair in "f0 f1" "f1 f2"; do
    set -- $pair
    "$PRT" compare "$T/$1.exr" "$T/$2.exr" --json - -q >"$T/cmp" 2>&1
    m=$(sed -n 's/.*"max_abs":[[:space:]]*\([0-9.eE+-]*\).*/\1/p' "$T/cmp")
    awk -v m="$m" 'BEGIN { exit !(m + 0 > 0.01) }' && ok || bad "fly mode: $1 and $2 are the same image"
done

# Bad scripts: a clear error, exit 2, before any window opens.
# Glossy: the viewer draws the view-dependent part per pixel exactly as prt render does, the
# environment rotates at run time, and moving the camera (no relight) changes the highlights.
printf '%s\n' '{"materials": {"g": {"brdf": "phong:40:0.7:0.1"}}, "meshes": [{"file": "demo.obj", "material": "g"}]}' >"$T/glossy.json"
"$PRT" bake -q "$T/glossy.json" -o "$T/glossy.prt" --order 4 --samples 64 --no-refine --kinds shadowed,glossy-shadowed || bad "glossy bake"
printf '%s\n' "0 screenshot $T/g1.exr" "0 env-rotate 90 0" "0 screenshot $T/g2.exr" "0.1 quit" >"$T/gscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/glossy.prt" --width 320 --height 240 --script "$T/gscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "glossy view exited $rc"; cat "$T/err"; }
"$PRT" render -q "$T/glossy.prt" -o "$T/rg1.exr" --width 320 --height 240
"$PRT" render -q "$T/glossy.prt" -o "$T/rg2.exr" --width 320 --height 240 --rotate 90
"$PRT" render -q "$T/glossy.prt" -o "$T/rd.exr" --width 320 --height 240 -k shadowed
within "$T/g1.exr" "$T/rg1.exr" 0.002
within "$T/g2.exr" "$T/rg2.exr" 0.002
"$PRT" compare --json - -q "$T/rg1.exr" "$T/rd.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.05) }' && ok || bad "the glossy part added nothing (relative L2 $r)"

# Wavelet: the worker computes K-vectors on lighting changes, the GPU applies the view factor per
# pixel; screenshots equal prt render, and a camera move alone changes the glossy shading.
"$PRT" bake -q "$T/glossy.json" -o "$T/wavelet.prt" --method wavelet --supersample 1 --terms 2 --brdf-res 16 --bounces 0 --no-refine || bad "wavelet bake"
printf '%s\n' "0 screenshot $T/w1.exr" "0 env-rotate 90 0" "0 screenshot $T/w2.exr" "0 key ]" "0.1 drag left 60 0" "0.2 screenshot $T/w3.exr" "0.3 quit" >"$T/wscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/wavelet.prt" --width 320 --height 240 --script "$T/wscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "wavelet view exited $rc"; cat "$T/err"; }
"$PRT" render -q "$T/wavelet.prt" -o "$T/rw1.exr" --width 320 --height 240
"$PRT" render -q "$T/wavelet.prt" -o "$T/rw2.exr" --width 320 --height 240 --rotate 90
within "$T/w1.exr" "$T/rw1.exr" 0.002
within "$T/w2.exr" "$T/rw2.exr" 0.002
"$PRT" compare --json - -q "$T/w2.exr" "$T/w3.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.05) }' && ok || bad "moving the camera changed nothing in the wavelet view (relative L2 $r)"
# The view factor per pixel agrees with the per-vertex evaluation it refines.
"$PRT" render -q "$T/wavelet.prt" -o "$T/rwv.exr" --width 320 --height 240 --per-vertex
"$PRT" compare --json - -q "$T/rw1.exr" "$T/rwv.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0 && r < 0.1) }' && ok || bad "per-pixel and per-vertex wavelet shading disagree or coincide (relative L2 $r)"

# Per-texel: the viewer samples the same radiance map prt render does.
"$PRT" bake -q "$T/demo.obj" -o "$T/texels.prt" --order 3 --samples 64 --texels 128 --kinds shadowed || bad "texel bake"
printf '%s\n' "0 screenshot $T/t1.exr" "0.1 quit" >"$T/tscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/texels.prt" --width 320 --height 240 --script "$T/tscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "texel view exited $rc"; cat "$T/err"; }
"$PRT" render -q "$T/texels.prt" -o "$T/rt1.exr" --width 320 --height 240
"$PRT" render -q "$T/texels.prt" -o "$T/rt2.exr" --width 320 --height 240 --per-vertex
within "$T/t1.exr" "$T/rt1.exr" 0.002
"$PRT" compare --json - -q "$T/rt1.exr" "$T/rt2.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.005) }' && ok || bad "per-texel and per-vertex drawings are identical (relative L2 $r)"

# Lights: the viewer adds the light types the method relights, draws them exactly as prt render
# does with the same --light, moves, dims, recolours and removes them; other types are refused.
printf '%s\n' "0 light-add directional" "0 screenshot $T/l1.exr" "0 light-move 2 1 0" "0 light-scale 2" "0 light-colour 1 0.5 0.25" \
    "0 screenshot $T/l2.exr" "0 light-remove" "0 screenshot $T/l3.exr" "0.1 quit" >"$T/lscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/demo.prt" --width 320 --height 240 --script "$T/lscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "light script exited $rc"; cat "$T/err"; }
"$PRT" render -q "$T/demo.prt" -o "$T/rl1.exr" --width 320 --height 240 --light directional:0.3,0.9,0.3:3,3,3
within "$T/l1.exr" "$T/rl1.exr" 0.002
within "$T/l3.exr" "$T/render_first.exr" 0.002
"$PRT" compare --json - -q "$T/l1.exr" "$T/l2.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.05) }' && ok || bad "moving, dimming and recolouring the light changed nothing (relative L2 $r)"
"$PRT" compare --json - -q "$T/l1.exr" "$T/render_first.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.05) }' && ok || bad "adding a light changed nothing (relative L2 $r)"
printf '0 light-add point\n' >"$T/point.txt"
xrun -a "$PRT" view "$T/wavelet.prt" --script "$T/point.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 2 ] && grep -q "cannot relight point lights" "$T/err" && ok || { bad "point light on a wavelet file in the viewer: exit $rc"; cat "$T/err"; }
printf '0 light-scale 2\n' >"$T/nolight.txt"
xrun -a "$PRT" view "$T/demo.prt" --script "$T/nolight.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 2 ] && grep -q "no light selected" "$T/err" && ok || { bad "light action without a light: exit $rc"; cat "$T/err"; }

# Spectral transfer: the scene's point light drawn per pixel with shadow maps exactly as prt render
# draws it; a surface recoloured from the keyboard equals prt render --albedo-of.
"$PRT" bake -q "$T/demo.obj" -o "$T/spec.prt" --method spectral --basis 64 --samples 64 --no-refine || bad "spectral bake"
printf '%s\n' "0 screenshot $T/s1.exr" "0 key m" "0 key a" "0 screenshot $T/s2.exr" "0.1 quit" >"$T/sscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/spec.prt" --env none --light point:0.3,1.5,0.4:4 --width 320 --height 240 --script "$T/sscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "spectral script exited $rc"; cat "$T/err"; }
"$PRT" render -q "$T/spec.prt" -o "$T/rs1.exr" --width 320 --height 240 --env none --light point:0.3,1.5,0.4:4
"$PRT" render -q "$T/spec.prt" -o "$T/rs2.exr" --width 320 --height 240 --env none --light point:0.3,1.5,0.4:4 --albedo-of floor=0.8,0.8,0.8
within "$T/s1.exr" "$T/rs1.exr" 0.002
within "$T/s2.exr" "$T/rs2.exr" 0.002
"$PRT" compare --json - -q "$T/s1.exr" "$T/s2.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.005) }' && ok || bad "recolouring the floor changed nothing (relative L2 $r)"

# Offset maps: accumulated on the GPU by default, the picture prt render --accumulate gpu draws;
# b puts the first-order light beside the final one; g on the CPU draws what prt render draws by
# default. Both draw the point light's direct light per pixel: the same picture (to float rounding).
"$PRT" bake -q "$T/demo.obj" -o "$T/off.prt" --method offset --texels 32 --offsets 40 --iterations 60 || bad "offset bake"
printf '%s\n' "0 screenshot $T/o1.exr" "0 key b" "0.05 screenshot $T/o2.exr" "0.05 key g" "0.1 screenshot $T/o3.exr" "0.1 key b" \
    "0.15 screenshot $T/o4.exr" "0.2 quit" >"$T/oscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/off.prt" --env none --light point:0.3,1.5,0.4:4 --width 320 --height 240 --script "$T/oscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "offset script exited $rc"; cat "$T/err"; }
"$PRT" render -q "$T/off.prt" -o "$T/ro1.exr" --width 320 --height 240 --env none --light point:0.3,1.5,0.4:4 --accumulate gpu
"$PRT" render -q "$T/off.prt" -o "$T/ro3.exr" --width 320 --height 240 --env none --light point:0.3,1.5,0.4:4 --accumulate cpu
within "$T/o1.exr" "$T/ro1.exr" 0.002
within "$T/o3.exr" "$T/ro3.exr" 0.002
within "$T/o1.exr" "$T/o3.exr" 0.001
within "$T/ro1.exr" "$T/ro3.exr" 0.001
"$PRT" compare --json - -q "$T/o2.exr" "$T/o1.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.05) }' && ok || bad "side by side drew the same as the final view (relative L2 $r)"
within "$T/o4.exr" "$T/o2.exr" 0.002   # b on the CPU turns the GPU passes back on, side by side

# Painting first-order light (offset files): dabs under the cursor light the scene and bounce; the
# painting saved by the script renders the same with prt render --paint; painting nothing changes
# nothing; paint-clear takes it all off; an SH file refuses painting with the reason.
printf '%s\n' "0 screenshot $T/p0.exr" "0 paint 160 200 0.3 4,1,0.5" "0 paint 120 190 0.2 0,0,0" "0 screenshot $T/p1.exr" \
    "0 paint-save $T/painting.pfm" "0 key g" "0.05 screenshot $T/p2.exr" "0.05 paint-clear" "0.1 screenshot $T/p3.exr" "0.1 quit" >"$T/pscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/off.prt" --env none --light point:0.3,1.5,0.4:4 --width 320 --height 240 --script "$T/pscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "paint script exited $rc"; cat "$T/err"; }
[ -s "$T/painting.pfm" ] && ok || bad "paint-save wrote nothing"
within "$T/p0.exr" "$T/o1.exr" 0.002
"$PRT" compare --json - -q "$T/p0.exr" "$T/p1.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.05) }' && ok || bad "painting light changed nothing (relative L2 $r)"
"$PRT" render -q "$T/off.prt" -o "$T/rp1.exr" --width 320 --height 240 --env none --light point:0.3,1.5,0.4:4 --accumulate gpu --paint "$T/painting.pfm"
"$PRT" render -q "$T/off.prt" -o "$T/rp2.exr" --width 320 --height 240 --env none --light point:0.3,1.5,0.4:4 --paint "$T/painting.pfm"
within "$T/p1.exr" "$T/rp1.exr" 0.002
within "$T/p2.exr" "$T/rp2.exr" 0.002
within "$T/p3.exr" "$T/ro3.exr" 0.002
"$PRT" relight -q "$T/off.prt" -o "$T/pv.ply" --paint "$T/painting.pfm" && ok || bad "prt relight --paint"
printf '0 paint 160 120 0.3 1,1,1\n' >"$T/shpaint.txt"
xrun -a "$PRT" view "$T/demo.prt" --script "$T/shpaint.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 2 ] && grep -q "cannot paint light on a file of the sh method" "$T/err" && ok || { bad "painting an SH file in the viewer: exit $rc"; cat "$T/err"; }
"$PRT" render -q "$T/demo.prt" -o "$T/x.png" --paint "$T/painting.pfm" 2>"$T/err"
rc=$?
[ "$rc" -ne 0 ] && [ "$(wc -l <"$T/err")" -eq 1 ] && grep -q "first-order light map" "$T/err" && ok || { bad "prt render --paint on an SH file: exit $rc"; cat "$T/err"; }
printf '0 paint 160 120 -1 1,1,1\n' >"$T/badpaint.txt"
xrun -a "$PRT" view "$T/off.prt" --script "$T/badpaint.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 2 ] && grep -q "paint takes X Y RADIUS" "$T/err" && ok || { bad "a bad paint line: exit $rc"; cat "$T/err"; }

# Light cloud: a light dragged about in the viewer and back to where it started gives the picture
# prt render draws there (relighting keeps no history: nothing lags or sticks).
"$PRT" bake -q "$T/demo.obj" -o "$T/lc.prt" --method lightcloud --cloud-grid 3,2,3 --samples 64 --basis 64 --no-refine || bad "lightcloud bake"
printf '%s\n' "0 light-select 1" "0 light-move 0.1 0 0" "0.05 light-move 0.1 0 0" "0.05 light-move 0 0.1 -0.2" "0.05 screenshot $T/lc0.exr" \
    "0.05 light-move 0 -0.1 0.2" "0.05 light-move -0.2 0 0" "0.1 screenshot $T/lc1.exr" "0.1 quit" >"$T/lcscript.txt"
xrun -a -s "-screen 0 1024x768x24" "$PRT" view "$T/lc.prt" --light point:0,0.8,0.3:2 --width 320 --height 240 --script "$T/lcscript.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 0 ] && ok || { bad "lightcloud script exited $rc"; cat "$T/err"; }
"$PRT" render -q "$T/lc.prt" -o "$T/rlc1.exr" --width 320 --height 240 --light point:0,0.8,0.3:2
within "$T/lc1.exr" "$T/rlc1.exr" 0.002
"$PRT" compare --json - -q "$T/lc0.exr" "$T/lc1.exr" >"$T/cmp"
r=$(field relative_l2 "$T/cmp")
awk -v r="$r" 'BEGIN { exit !(r != "" && r > 0.01) }' && ok || bad "moving the light changed nothing (relative L2 $r)"

printf '0 frobnicate 1 2\n' >"$T/bad.txt"
xrun -a "$PRT" view "$T/demo.prt" --script "$T/bad.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 2 ] && grep -q "bad.txt:1" "$T/err" && ok || { bad "bad script: exit $rc"; cat "$T/err"; }
printf '0 key F9\n' >"$T/badkey.txt"
xrun -a "$PRT" view "$T/demo.prt" --script "$T/badkey.txt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 2 ] && grep -q "no control is bound" "$T/err" && ok || { bad "unbound key: exit $rc"; cat "$T/err"; }

# No display: exit 3 with a message, no crash.
env -u DISPLAY -u WAYLAND_DISPLAY "$PRT" view "$T/demo.prt" >/dev/null 2>"$T/err"
rc=$?
[ "$rc" -eq 3 ] && grep -qi "display" "$T/err" && ok || { bad "no display: exit $rc"; cat "$T/err"; }

echo "view: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
