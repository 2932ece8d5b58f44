#!/bin/sh
# prt export --web in a real browser: headless Chromium (SwiftShader's WebGL2, no GPU) opens the
# exported page from the file system, URL hash parameters drive it (environment rotation and
# intensity, the method's controls), and each screenshot matches prt render of the same view and
# lighting within a stated tolerance (relative L2 of the tone-mapped image, worst 16x16 block's
# mean absolute difference; tests/web_compare.js). Without WebGL2 the page says so; methods
# without a page are refused in one line. Skips (77) where chromium or node is missing
# (scripts/setup-deps.sh installs both).
# Usage: web_test.sh PATH/TO/prt SOURCE_DIR
set -u
PRT=$1
SRC=$2
CHROMIUM=${PRT_CHROMIUM:-}
for c in chromium chromium-browser google-chrome; do
    [ -z "$CHROMIUM" ] && command -v "$c" >/dev/null 2>&1 && CHROMIUM=$c
done
if [ -z "$CHROMIUM" ]; then
    echo "SKIP: no chromium (scripts/setup-deps.sh installs Debian's chromium for this test)"
    exit 77
fi
if ! command -v node >/dev/null 2>&1; then
    echo "SKIP: no node (Node.js) to compare the screenshots: scripts/setup-deps.sh installs it"
    exit 77
fi
T=$(mktemp -d /tmp/prt_web_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$SRC/tests/shell_checks.sh"

W=320
H=240
# Headless, software WebGL2 (SwiftShader through ANGLE), one CSS pixel per pixel, a profile of
# its own (tests run in parallel); the window is wider than the canvas by the panel.
browser() {
    timeout 120 "$CHROMIUM" --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --force-device-scale-factor=1 \
        --hide-scrollbars --no-first-run --disable-extensions --user-data-dir="$T/profile" --window-size=$((W + 260)),$H "$@" 2>>"$T/chromium.log"
}
# One browser, with those flags, for every screenshot: a start of chromium costs seconds of CPU, a
# tab (tests/web_shot.js: a new tab per shot, shot at the load event as --screenshot does) little.
# A Node without WebSocket (before 20.10) has each shot start a browser of its own.
shooter=
WS=
node -e 'process.exit(typeof WebSocket === "function" ? 0 : 1)' 2>/dev/null || WS=--experimental-websocket
if node $WS -e 'process.exit(typeof WebSocket === "function" ? 0 : 1)' 2>/dev/null; then
    "$CHROMIUM" --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --force-device-scale-factor=1 \
        --hide-scrollbars --no-first-run --disable-extensions --user-data-dir="$T/shots" --window-size=$((W + 260)),$H \
        --remote-debugging-port=0 about:blank >/dev/null 2>>"$T/chromium.log" &
    shooter=$!
    trap 'kill "$shooter" 2>/dev/null; wait "$shooter" 2>/dev/null; rm -rf "$T"' EXIT
    for i in $(seq 1 600); do [ -s "$T/shots/DevToolsActivePort" ] && break; sleep 0.1; done
    # No DevTools port after a minute: a browser per shot, as without WebSocket.
    [ -s "$T/shots/DevToolsActivePort" ] || { kill "$shooter" 2>/dev/null; wait "$shooter" 2>/dev/null; shooter=; }
fi
# shot PAGE HASH OUT.png: a screenshot of the page opened from the file system at #HASH.
shot() {
    rm -f "$3"
    if [ -n "$shooter" ]; then
        timeout 120 node $WS "$SRC/tests/web_shot.js" "$T/shots" "file://$1/index.html#$2" "$3" $((W + 260)) $H 2>>"$T/chromium.log"
    else
        browser --screenshot="$3" "file://$1/index.html#$2" >/dev/null
    fi
    [ -s "$3" ] && ok || { bad "no screenshot of $1#$2"; tail -n 5 "$T/chromium.log"; }
}
# within A.png B.png L2 BLOCK WHAT: relative L2 <= L2 and worst block <= BLOCK.
within() {
    node "$SRC/tests/web_compare.js" "$1" "$2" $W $H >"$T/cmp" 2>"$T/err" || { bad "$5: compare failed"; cat "$T/err"; return; }
    l2=$(sed -n 's/.*"relative_l2":\([0-9.eE+-]*\).*/\1/p' "$T/cmp")
    wb=$(sed -n 's/.*"worst_block":\([0-9.eE+-]*\).*/\1/p' "$T/cmp")
    echo "$5: relative L2 $l2, worst block $wb"
    awk -v a="$l2" -v b="$wb" -v ta="$3" -v tb="$4" 'BEGIN { exit !(a != "" && b != "" && a + 0 <= ta + 0 && b + 0 <= tb + 0) }' && ok ||
        bad "$5: relative L2 $l2 (at most $3), worst block $wb (at most $4)"
}
# apart A.png B.png MIN WHAT: the images differ (relative L2 > MIN): the change reached the page.
apart() {
    node "$SRC/tests/web_compare.js" "$1" "$2" $W $H >"$T/cmp" 2>"$T/err" || { bad "$4: compare failed"; return; }
    l2=$(sed -n 's/.*"relative_l2":\([0-9.eE+-]*\).*/\1/p' "$T/cmp")
    awk -v a="$l2" -v t="$3" 'BEGIN { exit !(a != "" && a + 0 > t + 0) }' && ok || bad "$4 changed nothing (relative L2 $l2)"
}
render() { $NOLEAK "$PRT" render -q --per-vertex --width $W --height $H "$@"; }

expect 0 "demo-scene" -- "$PRT" demo-scene -o "$T/demo.obj"

# ---- SH: the environment rotated and scaled in the browser, the order control ----
expect 0 "bake sh" -- "$PRT" bake -q "$T/demo.obj" --method sh -o "$T/sh.prt" --order 4 --samples 64 --bounces 1 --no-refine
expect 0 "export --web sh" -- "$PRT" export "$T/sh.prt" --web "$T/sh" --width $W --height $H
for f in index.html data.js prt.js method.js; do [ -s "$T/sh/$f" ] && ok || bad "the page has no $f"; done
grep -q '<script src="data.js">' "$T/sh/index.html" && ! grep -q 'type="module"\|fetch(' "$T/sh/index.html" "$T/sh/prt.js" "$T/sh/method.js" && ok ||
    bad "the page loads its scripts otherwise than by classic <script src> (file:// refuses fetch and modules)"
render "$T/sh.prt" -o "$T/sh_render.png"
shot "$T/sh" "" "$T/sh_page.png"
within "$T/sh_page.png" "$T/sh_render.png" 0.03 0.02 "sh, as exported"
render "$T/sh.prt" -o "$T/sh_render_rot.png" --rotate 120,25,-10 --intensity 1.7 --control order=3
shot "$T/sh" "rotate=120,25,-10&intensity=1.7&order=3" "$T/sh_page_rot.png"
within "$T/sh_page_rot.png" "$T/sh_render_rot.png" 0.03 0.02 "sh, environment rotated and scaled, order 3"
apart "$T/sh_page_rot.png" "$T/sh_page.png" 0.05 "rotating the environment in the page"
# The camera given: the page opens where prt render looks from.
expect 0 "export --web sh --eye --target --fov" -- "$PRT" export "$T/sh.prt" --web "$T/sh_eye" --width $W --height $H --eye 2.5,1.2,-2 --target 0,0.4,0 --fov 50
render "$T/sh.prt" -o "$T/sh_render_eye.png" --eye 2.5,1.2,-2 --target 0,0.4,0 --fov 50
shot "$T/sh_eye" "" "$T/sh_page_eye.png"
within "$T/sh_page_eye.png" "$T/sh_render_eye.png" 0.03 0.02 "sh, camera given"
# A file exported under a rotated, brighter environment opens under it.
expect 0 "export --web sh --rotate" -- "$PRT" export "$T/sh.prt" --web "$T/sh_rot" --width $W --height $H --rotate 120,25,-10 --intensity 1.7 --control order=3
shot "$T/sh_rot" "" "$T/sh_page_rot2.png"
within "$T/sh_page_rot2.png" "$T/sh_render_rot.png" 0.03 0.02 "sh, exported rotated"

# ---- wavelet: the environment rotated with exact areas, Haar-transformed and truncated in the
# browser (a quick bake: no bounces, no refinement) ----
expect 0 "bake wavelet" -- "$PRT" bake -q "$T/demo.obj" --method wavelet -o "$T/wl.prt" --supersample 1 --bounces 0 --no-refine
expect 0 "export --web wavelet" -- "$PRT" export "$T/wl.prt" --web "$T/wl" --width $W --height $H
render "$T/wl.prt" -o "$T/wl_render.png"
shot "$T/wl" "" "$T/wl_page.png"
within "$T/wl_page.png" "$T/wl_render.png" 0.03 0.02 "wavelet, as exported"
render "$T/wl.prt" -o "$T/wl_render_rot.png" --rotate 120,25,-10 --intensity 1.7 --control light-coefficients=1024
shot "$T/wl" "rotate=120,25,-10&intensity=1.7&light-coefficients=1024" "$T/wl_page_rot.png"
within "$T/wl_page_rot.png" "$T/wl_render_rot.png" 0.03 0.02 "wavelet, environment rotated and scaled, 1024 coefficients"
apart "$T/wl_page_rot.png" "$T/wl_page.png" 0.05 "rotating the environment in the wavelet page"
# Glossy (a Phong lobe on every surface): the view factor per pixel from the separable BRDF's
# view maps, seen from a camera moved through the hash and under a turned environment; prt render
# draws it per pixel too.
expect 0 "bake wavelet glossy" -- "$PRT" bake -q "$T/demo.obj" --method wavelet -o "$T/wlg.prt" --supersample 1 --bounces 0 --no-refine --brdf phong:30:0.5:0.4 --terms 2 --brdf-res 24
expect 0 "export --web wavelet glossy" -- "$PRT" export "$T/wlg.prt" --web "$T/wlg" --width $W --height $H
$NOLEAK "$PRT" render -q --width $W --height $H "$T/wlg.prt" -o "$T/wlg_render.png" --rotate 60,10,0 --eye 2.2,1.4,2.6 --target 0,0.5,0
shot "$T/wlg" "rotate=60,10,0&eye=2.2,1.4,2.6&target=0,0.5,0" "$T/wlg_page.png"
within "$T/wlg_page.png" "$T/wlg_render.png" 0.03 0.02 "wavelet glossy, environment turned, camera moved"

# ---- spectral: point lights per pixel with the page's shadow cubes (drawn as prt render draws
# them, without --per-vertex), their light at the vertices bounced through the basis; lights moved
# and added through the hash ----
expect 0 "bake spectral" -- "$PRT" bake -q "$T/demo.obj" --method spectral -o "$T/sp.prt" --samples 512 --no-refine
expect 0 "export --web spectral" -- "$PRT" export "$T/sp.prt" --web "$T/sp" --width $W --height $H --light point:0.5,1.2,0.6:3,3,3
$NOLEAK "$PRT" render -q --width $W --height $H "$T/sp.prt" -o "$T/sp_render.png" --light point:0.5,1.2,0.6:3,3,3
shot "$T/sp" "markers=0" "$T/sp_page.png"
within "$T/sp_page.png" "$T/sp_render.png" 0.03 0.02 "spectral, sky and a point light"
shot "$T/sp" "" "$T/sp_page_markers.png"
apart "$T/sp_page_markers.png" "$T/sp_page.png" 0.001 "the lights' markers (shown unless markers=0)"
expect 0 "export --web spectral, no environment" -- "$PRT" export "$T/sp.prt" --web "$T/sp_dark" --width $W --height $H --env none --light point:0.5,1.2,0.6:3,3,3
$NOLEAK "$PRT" render -q --width $W --height $H "$T/sp.prt" -o "$T/sp_render_moved.png" --env none --light point:-0.6,0.9,0.5:2,1.5,1 --light point:0.8,1.3,-0.4:1,1,2 --control bounces=2
shot "$T/sp_dark" "markers=0&lights=-0.6,0.9,0.5:2,1.5,1|0.8,1.3,-0.4:1,1,2&bounces=2" "$T/sp_page_moved.png"
within "$T/sp_page_moved.png" "$T/sp_render_moved.png" 0.03 0.02 "spectral, a light moved and one added, 2 bounces"
$NOLEAK "$PRT" render -q --width $W --height $H "$T/sp.prt" -o "$T/sp_render_dark.png" --env none --light point:0.5,1.2,0.6:3,3,3
apart "$T/sp_page_moved.png" "$T/sp_render_dark.png" 0.05 "moving and adding lights in the spectral page"
expect 2 "--web spectral with a spot light" -- "$PRT" export "$T/sp.prt" --web "$T/x" --light spot:0,1.4,0:0,-1,0:40:3,3,3
says "point lights"

# ---- light cloud: the weights over the cloud with the page's own ray caster, the zones'
# clustered-PCA responses, the direct light per pixel ----
expect 0 "bake lightcloud" -- "$PRT" bake -q "$T/demo.obj" --method lightcloud -o "$T/lc.prt" --cloud-grid 3,2,3 --samples 512 --no-refine
expect 0 "export --web lightcloud" -- "$PRT" export "$T/lc.prt" --web "$T/lc" --width $W --height $H --env none --light point:0.5,1.2,0.6:3,3,3
$NOLEAK "$PRT" render -q --width $W --height $H "$T/lc.prt" -o "$T/lc_render.png" --env none --light point:0.5,1.2,0.6:3,3,3
shot "$T/lc" "markers=0" "$T/lc_page.png"
within "$T/lc_page.png" "$T/lc_render.png" 0.03 0.02 "lightcloud, a point light"
$NOLEAK "$PRT" render -q --width $W --height $H "$T/lc.prt" -o "$T/lc_render_moved.png" --env none --light point:-0.6,0.9,0.5:2,1.5,1 --light point:0.8,1.3,-0.4:1,1,2 --control neighbours=4
shot "$T/lc" "markers=0&lights=-0.6,0.9,0.5:2,1.5,1|0.8,1.3,-0.4:1,1,2&neighbours=4" "$T/lc_page_moved.png"
within "$T/lc_page_moved.png" "$T/lc_render_moved.png" 0.03 0.02 "lightcloud, a light moved and one added, 4 neighbours"
apart "$T/lc_page_moved.png" "$T/lc_page.png" 0.05 "moving and adding lights in the light-cloud page"

# ---- offset: the light map's first-order light at the texels' shadow points, the offset maps'
# passes over a prefiltered pyramid, the map drawn per texel and the lights per pixel ----
expect 0 "bake offset" -- "$PRT" bake -q "$T/demo.obj" --method offset -o "$T/off.prt" --texels 64 --offsets 48 --iterations 100 --walks 32 --no-refine
expect 0 "export --web offset" -- "$PRT" export "$T/off.prt" --web "$T/off" --width $W --height $H --light point:0.5,1.2,0.6:3,3,3
$NOLEAK "$PRT" render -q --width $W --height $H "$T/off.prt" -o "$T/off_render.png" --light point:0.5,1.2,0.6:3,3,3
shot "$T/off" "markers=0" "$T/off_page.png"
within "$T/off_page.png" "$T/off_render.png" 0.03 0.02 "offset, sky and a point light"
$NOLEAK "$PRT" render -q --width $W --height $H "$T/off.prt" -o "$T/off_render_moved.png" --light point:-0.6,0.9,0.5:2,1.5,1 --light point:0.8,1.3,-0.4:1,1,2 --rotate 120,25,-10 --intensity 0.5 --control bounces=0
shot "$T/off" "markers=0&lights=-0.6,0.9,0.5:2,1.5,1|0.8,1.3,-0.4:1,1,2&rotate=120,25,-10&intensity=0.5&bounces=0" "$T/off_page_moved.png"
within "$T/off_page_moved.png" "$T/off_render_moved.png" 0.03 0.02 "offset, lights moved and added, sky turned, no bounce"
apart "$T/off_page_moved.png" "$T/off_page.png" 0.05 "moving lights and turning the sky in the offset page"
# Subsurface scattering (examples/skin.json: the torus of skin): the dipole's pass, and the
# dipole's albedo under the per-pixel lights.
# Its mesh is the tour's out/scene.obj, the demo scene: here demo.obj, so that the test needs no tour
# run before it (a clean checkout has no out/; ctest runs the tour beside this test).
sed 's#"\.\./out/scene\.obj"#"demo.obj"#' "$SRC/examples/skin.json" >"$T/skin.json"
grep -q '"demo.obj"' "$T/skin.json" && ok || bad "examples/skin.json no longer names ../out/scene.obj: update this test"
expect 0 "bake offset skin" -- "$PRT" bake -q "$T/skin.json" --method offset -o "$T/skin.prt" --texels 64 --offsets 48 --iterations 100 --walks 32
expect 0 "export --web offset skin" -- "$PRT" export "$T/skin.prt" --web "$T/skin" --width $W --height $H --light point:0.5,1.2,0.6:3,3,3
$NOLEAK "$PRT" render -q --width $W --height $H "$T/skin.prt" -o "$T/skin_render.png" --light point:0.5,1.2,0.6:3,3,3
shot "$T/skin" "markers=0" "$T/skin_page.png"
within "$T/skin_page.png" "$T/skin_render.png" 0.03 0.02 "offset, subsurface (skin) and a point light"
expect 2 "--web offset's first-order light" -- "$PRT" export "$T/off.prt" --web "$T/x" -k first-order
says "final light"

# ---- ao: the environment's SH convolved with the clamped cosine, times accessibility ----
expect 0 "bake ao" -- "$PRT" bake -q "$T/demo.obj" --method ao -o "$T/ao.prt" --samples 16
expect 0 "export --web ao" -- "$PRT" export "$T/ao.prt" --web "$T/ao" --width $W --height $H
render "$T/ao.prt" -o "$T/ao_render.png" --rotate 120,25,-10 --intensity 1.7
shot "$T/ao" "rotate=120,25,-10&intensity=1.7" "$T/ao_page.png"
within "$T/ao_page.png" "$T/ao_render.png" 0.03 0.02 "ao, environment turned and scaled"

# ---- without WebGL2 the page says so ----
browser --disable-3d-apis --dump-dom --virtual-time-budget=3000 "file://$T/sh/index.html" >"$T/dom"
grep -q 'id="message">This page relights the scene with WebGL2' "$T/dom" && ok || bad "without WebGL the page shows no message"

# ---- usage ----
expect 2 "--web with -o" -- "$PRT" export "$T/sh.prt" --web "$T/x" -o "$T/x.glb"
says "leave out -o"
expect 2 "--eye without --target" -- "$PRT" export "$T/sh.prt" --web "$T/x" --eye 1,1,1
says "go together"
expect 2 "--fov without --web" -- "$PRT" export "$T/sh.prt" -o "$T/x.glb" --fov 30
says "go with --web"
# What a page cannot show is refused in one line, and nothing is written.
expect 2 "--web spectral with a directional light" -- "$PRT" export "$T/sp.prt" --web "$T/x" --light directional:0,1,0:3,3,3
[ "$(wc -l <"$T/err")" -eq 1 ] && ok || bad "the refusal is not one line"
[ ! -e "$T/x" ] && ok || bad "a refused export left a page"

echo "web: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
