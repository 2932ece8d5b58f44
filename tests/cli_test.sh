#!/bin/sh
# End-to-end checks of the prt command line: every subcommand's --help, the happy path on the
# demo scene, documented exit codes for bad input, and an interrupted bake writing nothing.
# Usage: cli_test.sh PATH/TO/prt [SHARED_DATA_DIR]
set -u
PRT=$1
DATA=${2:-}
T=$(mktemp -d /tmp/prt_cli_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"

# A misspelt option: one line naming the closest one.
expect 2 "misspelt option" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --oder 3
says "did you mean --order"
[ "$(wc -l <"$T/err")" -eq 1 ] && ok || bad "a usage error takes one line, not $(wc -l <"$T/err")"

for cmd in bake merge relight export render env info demo-scene reference compare sweep; do
    expect 0 "$cmd --help" -- "$PRT" "$cmd" --help
    grep -q "Exit codes" "$T/out" && ok || bad "$cmd --help lacks exit codes"
done
expect 0 "prt --help" -- "$PRT" --help
expect 2 "no command" -- "$PRT"
expect 2 "unknown command" -- "$PRT" frobnicate
expect 2 "misspelt command" -- "$PRT" rendr
says "did you mean 'prt render'"
[ "$(wc -l <"$T/err")" -eq 1 ] && ok || bad "a misspelt command takes one line, not $(wc -l <"$T/err")"
# Two letters swapped are one edit: --ligth is --light, not --width.
expect 2 "swapped letters" -- "$PRT" render x.prt --ligth point:0,1,0:1
says "did you mean --light"
expect 2 "unknown option" -- "$PRT" bake --frobnicate x.obj -o y.prt
expect 2 "bake without output" -- "$PRT" bake x.obj
expect 2 "bad order" -- "$PRT" bake x.obj -o y.prt --order 11
says "order"
expect 2 "bad kind" -- "$PRT" bake x.obj -o y.prt --kinds glossy
says "glossy"

# Happy path on the demo scene.
expect 0 "demo-scene" -- "$PRT" demo-scene -o "$T/demo.obj"
[ -s "$T/demo.mtl" ] && ok || bad "demo.mtl missing"
# --no-refine: the file keeps the scene's vertices, which the sweeps below compare against. Bakes
# whose checks are not about refinement take it too: refining (the default) costs more than the bake.
expect 0 "bake" -- "$PRT" bake -q "$T/demo.obj" -o "$T/demo.prt" --order 4 --samples 128 --bounces 2 --no-refine
# Progress for scripts: one JSON object per line; a summary with each stage's time.
expect 0 "bake with JSON progress and a summary" -- "$PRT" bake "$T/demo.obj" -o "$T/p.prt" --order 2 --samples 32 --bounces 1 --progress json --summary "$T/sum.json" --compress pca
grep '^{"stage"' "$T/err" | tail -n 1 | grep -q '"percent": 100.0' && ok || bad "JSON progress did not reach 100%"
[ "$(grep -c '^{"stage"' "$T/err")" -ge 4 ] && ok || bad "JSON progress: too few lines"
grep -q '"name":[[:space:]]*"compress interreflected"' "$T/sum.json" && grep -q '"bake_seconds"' "$T/sum.json" && ok || bad "the summary lacks stage times"
says "refining them"   # the contact ring of the torus and sphere: refined by default
expect 0 "info of a default bake" -- "$PRT" info --json "$T/p.prt"
nv=$(sed -n 's/.*"vertices":[[:space:]]*\([0-9]*\).*/\1/p' "$T/out" | head -n 1)
[ -n "$nv" ] && [ "$nv" -gt 10195 ] && [ "$nv" -le 20390 ] && ok || bad "a default bake has $nv vertices, expected 10196..20390 (refined within its budget)"
expect 2 "--no-refine with --refine" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --no-refine --refine
says "contradicts"
expect 2 "bad --progress" -- "$PRT" bake "$T/demo.obj" -o "$T/p.prt" --progress loud
# Adaptive refinement: more vertices, within the budget, in the file the bake writes.
expect 0 "bake --refine" -- "$PRT" bake "$T/demo.obj" -o "$T/refined.prt" --order 2 --samples 32 --bounces 1 --refine --refine-vertices 3000
says "refine: .* levels added"
expect 0 "info of a refined bake" -- "$PRT" info --json "$T/refined.prt"
nv=$(sed -n 's/.*"vertices":[[:space:]]*\([0-9]*\).*/\1/p' "$T/out" | head -n 1)
[ -n "$nv" ] && [ "$nv" -gt 10195 ] && [ "$nv" -le 13195 ] && ok || bad "a refined bake has $nv vertices, expected 10196..13195"
expect 2 "bad --refine-threshold" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --refine-threshold 2
says "refine-threshold"
rm -f "$T/p2.prt"
expect 1 "a summary that cannot be written" -- "$PRT" bake -q "$T/demo.obj" -o "$T/p2.prt" --order 2 --samples 16 --bounces 1 --no-refine --no-checkpoint --summary "$T/none/sum.json"
says "summary"
[ ! -e "$T/p2.prt" ] && ok || bad "the bake wrote its file although its summary failed"
expect 0 "info" -- "$PRT" info "$T/demo.prt"
grep -q "interreflected" "$T/out" && ok || bad "info does not list interreflected"
expect 0 "info --json" -- "$PRT" info --json "$T/demo.prt"
grep -q '"order":[[:space:]]*4' "$T/out" && ok || bad "info --json lacks order 4"
expect 0 "relight ply" -- "$PRT" relight -q "$T/demo.prt" -o "$T/lit.ply" --kind shadowed
head -c 3 "$T/lit.ply" | grep -q ply && ok || bad "relight did not write a PLY"
grep -a -q "property uchar red" "$T/lit.ply" && ok || bad "PLY lacks 8-bit sRGB colours (the default, what viewers show)"
expect 0 "relight json" -- "$PRT" relight -q "$T/demo.prt" -o "$T/lit.json" --rotate 90,10
grep -q '"radiance"' "$T/lit.json" && ok || bad "relight JSON lacks radiance"
# Meshes for other tools through assimp: glTF with COLOR_0, PLY with 8-bit colours, OBJ with sRGB
# colours after each v equal to the JSON radiance encoded, float PLY on request.
expect 0 "relight glb" -- "$PRT" relight -q "$T/demo.prt" -o "$T/lit.glb" --rotate 90,10
head -c 4 "$T/lit.glb" | grep -q glTF && grep -a -q '"COLOR_0"' "$T/lit.glb" && ok || bad "the .glb lacks COLOR_0"
expect 0 "relight gltf" -- "$PRT" relight -q "$T/demo.prt" -o "$T/litg.gltf"
grep -q '"COLOR_0"' "$T/litg.gltf" && [ -s "$T/litg.bin" ] && ok || bad "the .gltf lacks COLOR_0 or its .bin"
ls -a "$T" | grep -q '\.tmp\.' && bad "an export left a temporary behind" || ok
# prt export: the same mesh, plus the SH transfer as custom glTF attributes and the GLSL that
# relights them (the GLSL's arithmetic against COLOR_0 was checked by hand: equal to 1e-7).
expect 0 "export with SH attributes" -- "$PRT" export -q "$T/demo.prt" -o "$T/sh.gltf" --sh --glsl "$T/sh.glsl"
grep -q '"_SH6"' "$T/sh.gltf" && ! grep -q '"COLOR_1"' "$T/sh.gltf" && ok || bad "the .gltf lacks the _SH attributes"
grep -q 'vec3 prtRadiance(vec3 light\[9\])' "$T/sh.glsl" && grep -q 'in vec4 _SH6;' "$T/sh.glsl" && ok || bad "the GLSL lacks prtRadiance or its inputs"
expect 0 "export shadowed, albedo attribute" -- "$PRT" export -q "$T/demo.prt" -o "$T/shs.glb" --sh -k shadowed
grep -a -q '"_ALBEDO"' "$T/shs.glb" && ok || bad "a one-channel export lacks _ALBEDO"
# Offset transfer maps: a light map, relit under a point light, drawn, exported as a mesh.
expect 0 "bake --method offset" -- "$PRT" bake -q "$T/demo.obj" --method offset --texels 32 --offsets 40 --iterations 60 -o "$T/offset.prt"
expect 0 "info of an offset bake" -- "$PRT" info "$T/offset.prt"
grep -q "light map:   32 x 32 texels" "$T/out" && ok || bad "info does not describe the light map"
grep -q "crops:.*of their texels hold data (.*in one box per map)" "$T/out" && ok || bad "info does not state how tightly the maps are cropped"
grep -q "energy cap:" "$T/out" && ok || bad "info does not report the offset maps' energy cap"
expect 0 "info --json of an offset bake" -- "$PRT" info --json "$T/offset.prt"
grep -q '"energy_cap"' "$T/out" && grep -q '"max_factor"' "$T/out" && ok || bad "info --json does not report the offset maps' energy cap"
expect 0 "relight offset" -- "$PRT" relight -q "$T/offset.prt" --env none --light point:0.3,1.2,0.4:2 -o "$T/offset.json"
grep -q '"indirect"' "$T/offset.json" && ok || bad "an offset relight lacks its indirect light"
expect 0 "render offset" -- $NOLEAK "$PRT" render -q "$T/offset.prt" --env none --light point:0.3,1.2,0.4:2 -o "$T/offset.png" --width 64 --height 48
expect 2 "offset: bounces out of range" -- "$PRT" relight "$T/offset.prt" --control bounces=99 -o "$T/x.json"
expect 0 "render offset: final and first-order side by side" -- $NOLEAK "$PRT" render -q "$T/offset.prt" -k final,first-order -o "$T/offset2.png" --width 64 --height 48
# The same passes on the GPU and the CPU: the same picture, under the sky and under a point light
# (whose direct part both draw per pixel with shadow maps).
expect 0 "render offset on the GPU" -- $NOLEAK "$PRT" render -q "$T/offset.prt" -o "$T/offset_gpu.exr" --width 64 --height 48 --accumulate gpu
expect 0 "render offset on the CPU" -- $NOLEAK "$PRT" render -q "$T/offset.prt" -o "$T/offset_cpu.exr" --width 64 --height 48 --accumulate cpu
expect 0 "GPU and CPU accumulation draw the same" -- "$PRT" compare --json "$T/cmp.json" "$T/offset_gpu.exr" "$T/offset_cpu.exr"
r=$(sed -n 's/.*"relative_l2":[[:space:]]*\([-0-9.eE+]*\).*/\1/p' "$T/cmp.json" | head -n 1)
awk -v r="$r" 'BEGIN { exit !(r != "" && r + 0 < 1e-3) }' && ok || bad "GPU and CPU offset renders differ (relative L2 '$r')"
expect 0 "render offset on the GPU, point light" -- $NOLEAK "$PRT" render -q "$T/offset.prt" --env none --light point:0.3,1.2,0.4:2 -o "$T/offset_gpu2.exr" --width 64 --height 48 --accumulate gpu
expect 0 "render offset on the CPU, point light" -- $NOLEAK "$PRT" render -q "$T/offset.prt" --env none --light point:0.3,1.2,0.4:2 -o "$T/offset_cpu2.exr" --width 64 --height 48 --accumulate cpu
expect 0 "GPU and CPU draw a point light alike" -- "$PRT" compare --json "$T/cmp.json" "$T/offset_gpu2.exr" "$T/offset_cpu2.exr"
r=$(sed -n 's/.*"relative_l2":[[:space:]]*\([-0-9.eE+]*\).*/\1/p' "$T/cmp.json" | head -n 1)
awk -v r="$r" 'BEGIN { exit !(r != "" && r + 0 < 1e-3) }' && ok || bad "GPU and CPU offset renders under a point light differ by relative L2 '$r'"
# Per-vertex methods sum on the GPU too (transform feedback): the same picture as the CPU's.
expect 0 "render SH on the GPU" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -o "$T/sh_gpu.exr" --width 64 --height 48 --accumulate gpu
expect 0 "render SH on the CPU" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -o "$T/sh_cpu.exr" --width 64 --height 48 --accumulate cpu
expect 0 "GPU and CPU SH sums draw the same" -- "$PRT" compare --json "$T/cmp.json" "$T/sh_gpu.exr" "$T/sh_cpu.exr"
r=$(sed -n 's/.*"relative_l2":[[:space:]]*\([-0-9.eE+]*\).*/\1/p' "$T/cmp.json" | head -n 1)
awk -v r="$r" 'BEGIN { exit !(r != "" && r + 0 < 1e-3) }' && ok || bad "GPU and CPU SH renders differ (relative L2 '$r')"
expect 2 "--accumulate gpu with --per-vertex" -- "$PRT" render "$T/offset.prt" --accumulate gpu --per-vertex -o "$T/x.png"
expect 2 "--accumulate nonsense" -- "$PRT" render "$T/offset.prt" --accumulate fpga -o "$T/x.png"
mkdir -p "$T/maps" && : >"$T/maps/radiosity_0999.exr" && : >"$T/maps/mine.txt"
expect 0 "export offset maps" -- "$PRT" export -q "$T/offset.prt" --maps "$T/maps"
grep -q '"radiosity"' "$T/maps/index.json" && [ "$(ls "$T/maps" | grep -c '\.exr$')" -gt 10 ] && ok || bad "export --maps wrote no index or too few maps"
grep -q '"pieces"' "$T/maps/index.json" && grep -q '"version":[[:space:]]*2' "$T/maps/index.json" && [ "$(ls "$T/maps" | grep -c '^radiosity_[0-9]\{4\}_[0-9]\{3\}\.exr$')" -gt 10 ] && ok || bad "export --maps lists no pieces per map"
[ ! -e "$T/maps/radiosity_0999.exr" ] && [ -e "$T/maps/mine.txt" ] && [ -s "$T/maps/surface.exr" ] && ok || bad "export --maps left an earlier map, removed another file or wrote no surface.exr"
expect 2 "export --maps of an SH file" -- "$PRT" export "$T/demo.prt" --maps "$T/nomaps"
says "method offset"
rm -f "$T/nomesh.glb"
expect 2 "export a mesh and --maps of an SH file" -- "$PRT" export "$T/demo.prt" -o "$T/nomesh.glb" --maps "$T/nomaps"
[ ! -e "$T/nomesh.glb" ] && ok || bad "a refused --maps left the mesh behind"
expect 2 "offset: --medium without subsurface transfer" -- "$PRT" bake "$T/demo.obj" --method offset --medium marble -o "$T/x.prt"
says "does not apply"
# Options a command cannot honour are refused, not ignored.
expect 2 "reference --brdf" -- "$PRT" reference "$T/demo.prt" -o "$T/r.json" --brdf phong:10
expect 2 "env --control" -- "$PRT" env --control order=2
expect 2 "compare --exposure" -- "$PRT" compare "$T/lit.json" "$T/lit.json" --exposure 1
expect 2 "demo-scene --cell without --room" -- "$PRT" demo-scene -o "$T/x.obj" --cell 0.1
expect 2 "export --sh to PLY" -- "$PRT" export "$T/demo.prt" -o "$T/sh.ply" --sh
says "glTF"
expect 2 "export to JSON" -- "$PRT" export "$T/demo.prt" -o "$T/sh.json"
says "prt relight"
expect 0 "relight ply, 8-bit sRGB" -- "$PRT" relight -q "$T/demo.prt" -o "$T/lit8.ply"
head -c 600 "$T/lit8.ply" | grep -a -q "property uchar red" && ok || bad "the PLY does not hold 8-bit colours"
expect 0 "relight ply, float linear" -- "$PRT" relight -q "$T/demo.prt" -o "$T/litf.ply" --colors linear
head -c 600 "$T/litf.ply" | grep -a -q "property float red" && ok || bad "--colors linear did not write float colours"
expect 0 "relight obj" -- "$PRT" relight -q "$T/demo.prt" -o "$T/lit.obj" --rotate 90,10 --exposure -3
r=$(sed -n 's/.*"radiance": \[\[\([-0-9.eE+]*\),.*/\1/p' "$T/lit.json")
o=$(awk '$1 == "v" { print $5; exit }' "$T/lit.obj")
awk -v r="$r" -v o="$o" 'BEGIN { x = r / 8; if (x > 1) x = 1; e = x <= 0.0031308 ? 12.92 * x : 1.055 * exp(log(x) / 2.4) - 0.055; exit !(o != "" && (e - o < 1e-4 && o - e < 1e-4)) }' \
    && ok || bad "OBJ colour $o is not the sRGB encoding of radiance $r at exposure -3"
expect 2 "--colors on JSON output" -- "$PRT" relight -q "$T/demo.prt" -o "$T/x.json" --colors srgb
expect 2 "unknown mesh format" -- "$PRT" relight -q "$T/demo.prt" -o "$T/x.stl"
expect 0 "render png" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -k all -o "$T/img.png" --width 64 --height 48
[ -s "$T/img.png" ] && ok || bad "render wrote no PNG"
expect 0 "render exr" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -o "$T/img.exr" --width 32 --height 32 --view 0,1,1
[ -s "$T/img.exr" ] && ok || bad "render wrote no EXR"
# Several inputs side by side: files under the same camera and light, images pasted as they are.
expect 0 "render one panel" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -o "$T/one.pfm" --width 32 --height 24
expect 0 "render files and an image side by side" -- $NOLEAK "$PRT" render -q "$T/demo.prt" "$T/one.pfm" "$T/demo.prt" -o "$T/three.pfm" --width 32 --height 24
[ "$(sed -n 2p "$T/three.pfm")" = "96 24" ] && ok || bad "three panels of 32x24 are not one 96x24 image: $(sed -n 2p "$T/three.pfm")"
expect 2 "an image of another size" -- "$PRT" render -q "$T/demo.prt" "$T/one.pfm" -o "$T/x.pfm" --width 40 --height 24
says "32x24"
expect 2 "--kind with several files" -- "$PRT" render -q "$T/demo.prt" "$T/demo.prt" -k shadowed -o "$T/x.png"
# Animations: an animated PNG whose lighting turns, or whose lights move to --light-to.
expect 0 "render --frames" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -o "$T/anim.png" --width 32 --height 24 --frames 3
grep -a -q acTL "$T/anim.png" && grep -a -q fdAT "$T/anim.png" && ok || bad "--frames wrote no animated PNG"
expect 0 "render --light-to" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -o "$T/anim2.png" --width 32 --height 24 --frames 2 --env none \
    --light directional:0,1,0:2 --light-to directional:1,1,0:2
expect 2 "--frames to an EXR" -- "$PRT" render -q "$T/demo.prt" -o "$T/x.exr" --frames 3
says "animated PNG"
expect 2 "--light-to without --frames" -- "$PRT" render -q "$T/demo.prt" -o "$T/x.png" --light directional:0,1,0:2 --light-to directional:1,1,0:2
expect 2 "--light-to of another type" -- "$PRT" render -q "$T/demo.prt" -o "$T/x.png" --frames 2 --light directional:0,1,0:2 --light-to point:1,1,0:2
says "same type"
expect 2 "an image cannot move" -- "$PRT" render -q "$T/demo.prt" "$T/one.pfm" -o "$T/x.png" --frames 2 --width 32 --height 24
expect 2 "a tone-mapped image as a panel" -- "$PRT" render -q "$T/demo.prt" "$T/anim.png" -o "$T/x.png" --width 32 --height 24
says "linear image"
expect 0 "env sky" -- "$PRT" env --order 3 --image "$T/irr.pfm" --irradiance -q
grep -q '"coefficients"' "$T/out" && ok || bad "env printed no coefficients"

# Ground truth and comparison on the same baked mesh.
expect 0 "reference of a .prt" -- "$PRT" reference -q "$T/demo.prt" -o "$T/ref.json" --samples 8 --seed 3
grep -q '"indirect"' "$T/ref.json" && grep -q '"std_error"' "$T/ref.json" && ok || bad "reference JSON lacks indirect or std_error"
expect 0 "compare prt with reference" -- "$PRT" compare "$T/demo.prt" "$T/ref.json" --json "$T/cmp.json"
grep -q '"relative_l2"' "$T/cmp.json" && ok || bad "compare JSON lacks relative_l2"
grep -q "relative L2" "$T/out" && ok || bad "compare printed no relative L2"
expect 0 "compare indirect" -- "$PRT" compare -q "$T/demo.prt" "$T/ref.json" --indirect --json -
grep -q '"indirect_only":[[:space:]]*true' "$T/out" && ok || bad "compare --indirect JSON"
expect 0 "compare error image" -- $NOLEAK "$PRT" compare -q "$T/demo.prt" "$T/ref.json" --error-image "$T/err.png" --width 48 --height 32
[ -s "$T/err.png" ] && ok || bad "no error image"
expect 0 "reference image" -- "$PRT" reference -q "$T/demo.prt" --image "$T/ref.exr" --width 32 --height 24 --samples 2
expect 0 "render for comparison" -- $NOLEAK "$PRT" render -q "$T/demo.prt" -o "$T/prt.exr" --width 32 --height 24
expect 0 "compare images" -- "$PRT" compare "$T/prt.exr" "$T/ref.exr"
grep -q "PSNR" "$T/out" && ok || bad "image compare printed no PSNR"
expect 2 "image against vertices" -- "$PRT" compare "$T/prt.exr" "$T/ref.json"
says "image"
"$PRT" bake -q "$T/demo.obj" -o "$T/fine.prt" --order 2 --samples 16 --max-edge 0.03 --no-refine >/dev/null 2>&1
expect 1 "different meshes" -- "$PRT" compare "$T/fine.prt" "$T/ref.json"
says "vertex counts differ"
expect 0 "sweep with plot" -- "$PRT" sweep -q "$T/demo.obj" --reference "$T/ref.json" -o "$T/sweep.csv" --plot "$T/sweep.png" --values 2,3 --samples 32 --kinds shadowed,interreflected
[ "$(wc -l <"$T/sweep.csv")" -eq 5 ] && ok || bad "sweep CSV should have a header and 4 rows"
[ -s "$T/sweep.png" ] && ok || bad "sweep wrote no plot"
expect 0 "sweep over a generated atlas (seam copies: more vertices than the reference)" -- "$PRT" sweep -q "$T/demo.obj" --reference "$T/ref.json" \
    -o "$T/sweep2.csv" --values 2 --samples 32 --kinds shadowed --texels 32 --uv atlas
[ "$(wc -l <"$T/sweep2.csv")" -eq 2 ] && ok || bad "atlas sweep CSV should have a header and 1 row"
expect 2 "sweep without reference" -- "$PRT" sweep "$T/demo.obj" -o "$T/s.csv"
expect 2 "sweep bad param" -- "$PRT" sweep "$T/demo.obj" --reference "$T/ref.json" -o "$T/s.csv" --param colour

# Bad inputs: exit 1 and a message naming the file.
expect 1 "missing mesh" -- "$PRT" bake "$T/nothing.obj" -o "$T/x.prt"
says "nothing.obj"
printf 'just some text\n' >"$T/text.ply"
expect 1 "not a mesh" -- "$PRT" bake "$T/text.ply" -o "$T/x.prt"
says "text.ply"
printf 'v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n' >"$T/flat.obj"
expect 1 "zero-area mesh" -- "$PRT" bake "$T/flat.obj" -o "$T/x.prt"
says "zero area"
[ ! -e "$T/x.prt" ] && ok || bad "a failed bake left x.prt"
head -c 1000 "$T/demo.prt" >"$T/cut.prt"
expect 1 "truncated prt" -- "$PRT" info "$T/cut.prt"
says "truncated"
printf 'PF\n2 1\n-1.0\n' >"$T/nan.pfm"
printf '\000\000\300\177\000\000\200\077\000\000\200\077\000\000\200\077\000\000\200\077\000\000\200\077' >>"$T/nan.pfm"
expect 1 "NaN probe" -- "$PRT" env "$T/nan.pfm"
says "not finite"
# A --max-edge that would make billions of triangles is refused before any work.
expect 2 "a tiny --max-edge" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --max-edge 1e-9
says "would make at least"
# A directory, and a header promising more pixels than the file holds: refused at once.
mkdir -p "$T/adir"
for cmd in info env; do expect 1 "$cmd of a directory" -- "$PRT" $cmd "$T/adir"; says "is a directory"; done
expect 1 "bake of a directory" -- "$PRT" bake "$T/adir" -o "$T/x.prt"
says "is a directory"
printf 'PF\n100000 40000\n-1.0\n\000\000\000\000' >"$T/liar.pfm"
expect 1 "a PFM promising 12 GiB" -- "$PRT" env "$T/liar.pfm"
says "truncated"
# Pixels near the float limit: the sums overflow, so the probe is refused (never 'null' or 'inf').
printf 'PF\n2 1\n-1.0\n' >"$T/huge.pfm"
for i in 1 2 3 4 5 6; do printf '\231\357\177\177' >>"$T/huge.pfm"; done
expect 1 "probe near FLT_MAX" -- "$PRT" env "$T/huge.pfm"
says "too bright"
expect 2 "lights near FLT_MAX" -- "$PRT" relight "$T/demo.prt" -o "$T/inf.json" --light directional:0,1,0:3e38,3e38,3e38
says "at most 1e30"
[ ! -e "$T/inf.json" ] && ok || bad "an overflowing relight wrote its output"
expect 1 "NaN probe in render" -- $NOLEAK "$PRT" render "$T/demo.prt" -o "$T/n.png" --env "$T/nan.pfm"
[ ! -e "$T/n.png" ] && ok || bad "render with a bad probe wrote an image"

# Glossy transfer: a scene with a Phong material, glossy matrices, rendering and relighting them.
printf '%s\n' '{ "materials": { "gloss": { "brdf": "phong:30:0.6:0.2" } },' \
    '  "meshes": [ { "file": "demo.obj" }, { "file": "demo.obj", "material": "gloss", "scale": 0.4, "translate": [0.3, 0.6, 0.2] } ] }' \
    >"$T/glossy.json"
expect 0 "glossy bake" -- "$PRT" bake -q "$T/glossy.json" -o "$T/glossy.prt" --order 3 --samples 64 --bounces 1 --no-refine \
    --kinds shadowed,interreflected,glossy-shadowed,glossy-interreflected
expect 0 "glossy info" -- "$PRT" info "$T/glossy.prt"
grep -q "glossy-interreflected" "$T/out" && grep -q "phong:30:0.6:0.2" "$T/out" && ok || bad "info does not list the glossy set and material"
expect 0 "glossy render" -- $NOLEAK "$PRT" render -q "$T/glossy.prt" -o "$T/glossy.png" --width 64 --height 48 -k interreflected,glossy-interreflected
expect 0 "glossy render, run-time lobe" -- $NOLEAK "$PRT" render -q "$T/glossy.prt" -o "$T/glossy2.png" --width 32 --height 32 --brdf blinn:80:0.3
# --brdf reshapes the glossy materials only, --brdf-all every surface: alike where every
# surface is glossy, different where some are diffuse; a file of diffuse materials refuses --brdf.
printf '%s\n' '{ "materials": { "gloss": { "brdf": "phong:30:0.6:0.2" } },' \
    '  "meshes": [ { "file": "demo.obj", "material": "gloss" } ] }' >"$T/allgloss.json"
expect 0 "all-glossy bake" -- "$PRT" bake -q "$T/allgloss.json" -o "$T/allgloss.prt" --order 3 --samples 32 --bounces 1 --no-refine --kinds shadowed,glossy-shadowed
for f in glossy allgloss; do
    for o in brdf brdf-all; do
        expect 0 "$f --$o" -- "$PRT" relight -q "$T/$f.prt" -k glossy-shadowed --eye 2,2,2 -o "$T/$f-$o.json" --$o blinn:80:0.3
    done
done
same "$T/allgloss-brdf.json" "$T/allgloss-brdf-all.json" 0 "--brdf and --brdf-all where every surface is glossy"
"$PRT" compare "$T/glossy-brdf.json" "$T/glossy-brdf-all.json" --json - -q >"$T/cmp" 2>"$T/err"
m=$(sed -n 's/.*"max_abs":[[:space:]]*\([0-9.eE+-]*\).*/\1/p' "$T/cmp")
awk -v m="$m" 'BEGIN { exit !(m != "" && m + 0 > 0) }' && ok || bad "--brdf gave the diffuse surfaces the lobe too (max |A-B| '$m')"
expect 0 "glossy kinds over diffuse materials" -- "$PRT" bake -q "$T/demo.obj" -o "$T/plain_glossy.prt" --order 3 --samples 32 --bounces 1 --no-refine --kinds shadowed,glossy-shadowed
expect 2 "--brdf without glossy materials" -- "$PRT" render "$T/plain_glossy.prt" -o "$T/x.png" --brdf phong:10
says "brdf-all"
expect 0 "--brdf-all without glossy materials" -- $NOLEAK "$PRT" render -q "$T/plain_glossy.prt" -o "$T/x.png" --width 32 --height 32 --brdf-all phong:10
expect 2 "glossy relight without eye" -- "$PRT" relight "$T/glossy.prt" -k glossy-shadowed -o "$T/g.json"
says "eye"
expect 0 "glossy relight" -- "$PRT" relight -q "$T/glossy.prt" -k glossy-shadowed --eye 2,2,2 -o "$T/g.json"
expect 2 "bad brdf" -- "$PRT" render "$T/glossy.prt" -o "$T/x.png" --brdf ward:3
says "unknown BRDF"
expect 2 "a BRDF to bake in without a glossy kind" -- "$PRT" bake -q "$T/demo.obj" -o "$T/x.prt" --brdf phong:10 --kinds shadowed
says "glossy kind"
expect 0 "bake a BRDF in" -- "$PRT" bake -q "$T/demo.obj" -o "$T/baked.prt" --order 3 --samples 64 --no-refine --kinds shadowed,glossy-shadowed --brdf lafortune:clay
expect 2 "run-time lobe on a file without glossy sets" -- "$PRT" render "$T/demo.prt" -o "$T/x.png" --brdf phong:10
says "glossy"
expect 2 "--view 0,0,0" -- "$PRT" render "$T/demo.prt" -o "$T/x.png" --view 0,0,0
says "not 0,0,0"
expect 2 "run-time lobe on a baked-in BRDF" -- $NOLEAK "$PRT" render "$T/baked.prt" -o "$T/x.png" --brdf phong:10
says "baked in"
expect 2 "glossy kind the file lacks" -- $NOLEAK "$PRT" render "$T/demo.prt" -o "$T/x.png" -k glossy-shadowed
says "glossy-shadowed"
printf '{"materials": {"m": {"albedo": 0.5, "brdf": "phong:8"}}, "meshes": [{"file": "demo.obj", "material": "m"}]}' >"$T/both.json"
expect 1 "albedo and brdf together" -- "$PRT" bake "$T/both.json" -o "$T/x.prt"
says "not both"
printf '{"meshes": [{"file": "demo.obj", "brdf": "phong:-2"}]}' >"$T/badb.json"
expect 1 "bad brdf in a scene" -- "$PRT" bake "$T/badb.json" -o "$T/x.prt"
says "exponent"

# The wavelet method: bake (direct and one bounce), the per-K error report, info, render, relight,
# compare, and its option errors.
expect 0 "wavelet bake" -- "$PRT" bake "$T/glossy.json" -o "$T/wavelet.prt" --method wavelet --supersample 1 --terms 2 --brdf-res 16 --bounces 1 --gather-res 8 --no-refine
says "K=2"
grep -q "<- used" "$T/err" && ok || bad "the per-K error report does not mark the K used"
expect 0 "wavelet info" -- "$PRT" info "$T/wavelet.prt"
grep -q "wavelet" "$T/out" && grep -q "2 separable terms" "$T/out" && grep -q "bytes per vertex" "$T/out" && ok || bad "info does not describe the wavelet file"
expect 0 "wavelet info json" -- "$PRT" info --json "$T/wavelet.prt"
grep -q '"method":[[:space:]]*"wavelet"' "$T/out" && grep -q '"bake_seconds"' "$T/out" && ok || bad "info --json lacks the wavelet method or bake time"
expect 0 "wavelet render" -- $NOLEAK "$PRT" render -q "$T/wavelet.prt" -o "$T/wavelet.png" --width 64 --height 48 --rotate 30
expect 2 "wavelet relight without eye" -- "$PRT" relight "$T/wavelet.prt" -o "$T/w.json"
says "eye"
expect 0 "wavelet relight" -- "$PRT" relight -q "$T/wavelet.prt" --eye 2,2,2 -o "$T/w.json"
grep -q '"kind":[[:space:]]*"wavelet"' "$T/w.json" && ok || bad "wavelet relight JSON lacks its kind"
expect 0 "wavelet compare" -- "$PRT" compare -q "$T/wavelet.prt" "$T/glossy.prt"
expect 2 "run-time lobe on wavelet" -- $NOLEAK "$PRT" render "$T/wavelet.prt" -o "$T/x.png" --brdf phong:10
says "baked in"
expect 2 "SH option with wavelet" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method wavelet --order 3
says "option of method sh"
expect 2 "wavelet option without wavelet" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --terms 3
says "method wavelet"
expect 2 "bad method" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method fourier
says "--method must be"
expect 2 "bad bits" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method wavelet --bits 12
says "8 or 16"
expect 2 "too many wavelet bounces" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method wavelet --bounces 9
says "0..8"
expect 2 "zero SH bounces" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --bounces 0
says "1..64"
expect 2 "wavelet kind on an SH file" -- $NOLEAK "$PRT" render "$T/demo.prt" -o "$T/x.png" -k wavelet
says "wavelet"

# Per-texel transfer over the demo scene's UV atlas, a normal map, the radiance map, and the errors.
expect 0 "texel bake" -- "$PRT" bake -q "$T/demo.obj" -o "$T/texels.prt" --order 3 --samples 64 --bounces 1 --texels 64 --kinds shadowed,interreflected
expect 0 "texel info" -- "$PRT" info "$T/texels.prt"
grep -q "^bounds: .* to .*(size" "$T/out" && ok || bad "info does not show the bounding box"
grep -q "64 x 64" "$T/out" && ok || bad "info does not show the texel sets"
expect 0 "texel map" -- "$PRT" relight -q "$T/texels.prt" --texels -o "$T/map.pfm" -k interreflected
expect 0 "texel render" -- $NOLEAK "$PRT" render -q "$T/texels.prt" -o "$T/texels.png" --width 64 --height 48
expect 1 "texel map without texels" -- "$PRT" relight "$T/demo.prt" --texels -o "$T/map2.pfm"
says "per-texel"
printf 'P3\n2 2\n255\n128 128 255 200 128 220 128 128 255 128 60 230\n' >"$T/nm.ppm"
expect 1 "unreadable normal map" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --texels 16 --normal-map "$T/nm.ppm"
says "normal map"
expect 2 "normal map without texels" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --normal-map "$T/nm.ppm"
printf 'v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n' >"$T/nouv.obj"
expect 2 "texels with --uv mesh, without UVs" -- "$PRT" bake "$T/nouv.obj" -o "$T/x.prt" --texels 16 --uv mesh
says "texture coordinates"
expect 0 "texels without UVs: a generated atlas" -- "$PRT" bake "$T/nouv.obj" -o "$T/x.prt" --texels 16 --samples 64
says "UV atlas"
printf 'PF\n1 1\n-1.0\n\000\000\000\077\000\000\000\077\000\000\200\077' >"$T/nm.pfm"
expect 2 "normal map with a generated atlas" -- "$PRT" bake "$T/nouv.obj" -o "$T/x.prt" --texels 16 --normal-map "$T/nm.pfm"
says "normal map"
expect 2 "--uv without --texels" -- "$PRT" bake "$T/nouv.obj" -o "$T/x.prt" --uv atlas
says "--texels"
expect 0 "neighbourhood bake" -- "$PRT" bake -q "$T/demo.obj" -o "$T/nb.prt" --order 2 --samples 64 --bounces 1 --no-refine --neighbourhood 4
expect 0 "neighbourhood info" -- "$PRT" info "$T/nb.prt"
grep -q "^neighbourhood: 4 x 4 x 4" "$T/out" && ok || bad "info does not show the neighbourhood grid"
expect 0 "probe render" -- $NOLEAK "$PRT" render -q "$T/nb.prt" -o "$T/probe.png" --width 64 --height 48 --probe 0,0.5,0 --probe 0.5,0.3,0.5,0.1
expect 1 "probe without a grid" -- $NOLEAK "$PRT" render "$T/texels.prt" -o "$T/probe.png" --width 64 --height 48 --per-vertex --probe 0,0.5,0
says "--neighbourhood"
expect 2 "bad probe" -- "$PRT" render "$T/nb.prt" -o "$T/probe.png" --probe 0,0.5
says "--probe"
expect 2 "probe with trailing junk" -- "$PRT" render "$T/nb.prt" -o "$T/probe.png" --probe 0,0.5,0,0.1x
expect 2 "grid too fine" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --neighbourhood 65
# Participating media: a scene's "volumes" baked, listed, rendered and path-traced; a bad one named.
printf '{"meshes": [{"file": "nouv.obj"}], "volumes": [{"procedural": "smoke", "resolution": [4, 6, 4], "min": [0, 0.1, -1], "max": [1, 1, 0], "extinction": 3, "albedo": 0.8, "g": 0.3}]}' >"$T/vol.json"
expect 0 "volume bake" -- "$PRT" bake -q "$T/vol.json" -o "$T/vol.prt" --order 2 --samples 64 --bounces 1
expect 0 "volume info" -- "$PRT" info "$T/vol.prt"
grep -q "^volumes: *4 x 6 x 4 voxels" "$T/out" && ok || bad "info does not show the volume"
expect 0 "volume render" -- $NOLEAK "$PRT" render -q "$T/vol.prt" -o "$T/vol.png" --width 64 --height 48
expect 0 "volume reference" -- "$PRT" reference -q "$T/vol.json" --image "$T/volref.exr" --width 16 --height 12 --samples 4
printf '{"meshes": [{"file": "nouv.obj"}], "volumes": [{"procedural": "fog", "min": [0, 0, 0], "max": [1, 1, 1]}]}' >"$T/badvol.json"
expect 1 "unknown procedural volume" -- "$PRT" bake "$T/badvol.json" -o "$T/x.prt"
says "volumes.0.: unknown procedural volume"
expect 0 "height map" -- "$PRT" bake -q "$T/demo.obj" -o "$T/h.prt" --order 2 --samples 64 --bounces 1 --texels 32 --kinds shadowed --height-map "$T/nm.pfm" --bump-height 0.05
expect 2 "height map without texels" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --height-map "$T/nm.pfm"
says "--texels"
expect 2 "bump height without a height map" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --texels 16 --bump-height 0.1
says "--height-map"
expect 2 "height map with a generated atlas" -- "$PRT" bake "$T/nouv.obj" -o "$T/x.prt" --texels 16 --height-map "$T/nm.pfm"
says "height map"
expect 1 "unreadable height map" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --texels 16 --height-map "$T/nm.ppm"
says "height map"

# An interrupted bake exits 130 and leaves neither the file nor a temporary.
# The signal goes once the bake reports progress (its handler is in place by then); the bake is
# sized to end by itself within a minute even under sanitizers, should the signal be lost.
"$PRT" bake "$T/demo.obj" -o "$T/long.prt" --samples 16384 --order 6 >/dev/null 2>"$T/err" &
pid=$!
for i in $(seq 1 600); do grep -q "visibility" "$T/err" 2>/dev/null && break; sleep 0.1; done
kill -INT "$pid"
wait "$pid"
rc=$?
[ "$rc" -eq 130 ] && ok || bad "interrupted bake exited $rc, expected 130"
[ -e "$T/long.prt" ] && bad "interrupted bake wrote long.prt" || ok
ls "$T" | grep -q "long.prt.tmp" && bad "interrupted bake left a temporary" || ok
# ... but keeps its finished work for --resume, and says so.
[ -s "$T/long.prt.checkpoint" ] && ok || bad "interrupted bake kept no checkpoint"
says "resume"
rm -f "$T/long.prt.checkpoint"

# Resumable bakes: kill -9 in the middle, then --resume finishes the same file (tests/test_resume.c
# checks every byte; here the command line: the relit result is identical, the checkpoint goes).
expect 0 "bake to compare with" -- "$PRT" bake "$T/demo.obj" -o "$T/whole.prt" --samples 512 --order 3 -q --no-checkpoint
[ -e "$T/whole.prt.checkpoint" ] && bad "--no-checkpoint wrote a checkpoint" || ok
"$PRT" bake "$T/demo.obj" -o "$T/killed.prt" --samples 512 --order 3 >/dev/null 2>"$T/err" &
pid=$!
for i in $(seq 1 600); do grep -q "bounce 1" "$T/err" 2>/dev/null && break; sleep 0.1; done
kill -KILL "$pid"
wait "$pid" 2>/dev/null
[ -s "$T/killed.prt.checkpoint" ] && ok || bad "a killed bake left no checkpoint"
cp "$T/killed.prt.checkpoint" "$T/other.prt.checkpoint"
expect 2 "resume another bake's checkpoint" -- "$PRT" bake "$T/demo.obj" -o "$T/other.prt" --samples 64 --order 3 --resume
says "another bake"
expect 2 "a bake over a checkpoint it was not told to resume" -- "$PRT" bake "$T/demo.obj" -o "$T/other.prt" --samples 64 --order 3
says "add --resume"
[ -s "$T/other.prt.checkpoint" ] && ok || bad "a refused bake touched the checkpoint"
rm -f "$T/other.prt.checkpoint"
expect 0 "resume a killed bake" -- "$PRT" bake "$T/demo.obj" -o "$T/killed.prt" --samples 512 --order 3 --resume
says "recovered from the checkpoint"
[ -e "$T/killed.prt.checkpoint" ] && bad "a finished bake kept its checkpoint" || ok
expect 0 "relight the resumed bake" -- "$PRT" relight "$T/killed.prt" -o "$T/killed.json" -q
expect 0 "relight the whole bake" -- "$PRT" relight "$T/whole.prt" -o "$T/whole.json" -q
cmp -s "$T/killed.json" "$T/whole.json" && ok || bad "a resumed bake relights differently from an uninterrupted one"
expect 0 "resume with no checkpoint" -- "$PRT" bake "$T/demo.obj" -o "$T/fresh.prt" --samples 64 --order 2 --resume
says "from the start"
expect 2 "--resume without a checkpoint" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --resume --no-checkpoint

# Mesh files are read by assimp in a child process: files that make assimp loop forever, abort
# on an assertion or crash end in one line and exit 1 (reproducers found by hand and fuzzing).
printf 'ply\nformat ascii\n' >"$T/hang.ply"
expect 1 "a PLY that makes assimp loop" -- "$PRT" bake "$T/hang.ply" -o "$T/x.prt" --import-timeout 2
says "no result after 2 s"
[ "$(wc -l <"$T/err")" -eq 1 ] && ok || bad "a hung import says more than one line"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n0\n' >"$T/abort.ply"
expect 1 "a PLY that makes assimp abort" -- "$PRT" bake "$T/abort.ply" -o "$T/x.prt"
says "aborted"
[ "$(wc -l <"$T/err")" -eq 1 ] && ok || bad "an aborted import says more than one line"
printf 'ply\nformat ascii 1.0\n\0' >"$T/segv.ply"
expect 1 "a PLY that crashes assimp" -- "$PRT" bake "$T/segv.ply" -o "$T/x.prt"
says "crashed"
printf '{"meshes": [{"file": "hang.ply"}]}' >"$T/hang.json"
expect 1 "a scene naming such a PLY" -- "$PRT" bake "$T/hang.json" -o "$T/x.prt" --import-timeout 1
says "hang.ply"
expect 2 "bad import timeout" -- "$PRT" bake "$T/hang.ply" -o "$T/x.prt" --import-timeout 0
# Ctrl-C stops a hung import at once (exit 130), not after its time limit.
"$PRT" bake "$T/hang.ply" -o "$T/x.prt" >/dev/null 2>"$T/err" &
pid=$!
sleep 1
start=$(date +%s)
kill -INT "$pid"
wait "$pid"
rc=$?
[ "$rc" -eq 130 ] && ok || bad "Ctrl-C during an import exited $rc, expected 130"
[ $(( $(date +%s) - start )) -le 2 ] && ok || bad "Ctrl-C took more than a second to stop an import"
# kill -9 of prt takes the importer with it: no parser left spinning.
"$PRT" bake "$T/hang.ply" -o "$T/x.prt" >/dev/null 2>&1 &
pid=$!
sleep 1
child=$(pgrep -P "$pid" | head -n 1)
kill -KILL "$pid"
wait "$pid" 2>/dev/null
sleep 0.5
# (a zombie waiting for whoever inherited it to reap it is dead enough)
if [ -n "$child" ]; then
    state=$(ps -o stat= -p "$child" 2>/dev/null | cut -c1)
    case "$state" in ""|Z) ok ;; *) bad "the importer outlived a killed prt (state $state)"; kill -KILL "$child" ;; esac
else bad "no importer process seen"; fi

# Spectral files of one scale (format version 2) relight to the numbers that version wrote
# (tests/data/spectral_v2/README.md).
SV=$(dirname "$0")/data/spectral_v2
SEEDS=$(dirname "$0")/../fuzz/regress/prt/spectral
expect 0 "one-scale spectral file" -- "$PRT" relight "$SEEDS/seed.prt" -o "$T/fx.json"
same "$T/fx.json" "$SV/seed.json" 1e-6 "one-scale spectral seed.prt"
expect 0 "one-scale glossy spectral file" -- "$PRT" relight "$SEEDS/seed_glossy.prt" --eye 3,2,4 -o "$T/fx.json"
same "$T/fx.json" "$SV/seed_glossy.json" 1e-6 "one-scale spectral seed_glossy.prt"

# Files written by prt 0.1 (before the method table) load and relight to the numbers that
# version wrote (tests/data/v0.1/README.md).
FX=$(dirname "$0")/data/v0.1
for k in unshadowed shadowed interreflected; do
    expect 0 "0.1 file as $k" -- "$PRT" relight "$FX/sh.prt" -k "$k" -o "$T/fx.json"
    same "$T/fx.json" "$FX/sh_$k.json" 1e-5 "0.1 sh.prt as $k"
done
for k in glossy-shadowed glossy-interreflected; do
    expect 0 "0.1 file as $k" -- "$PRT" relight "$FX/sh.prt" -k "$k" --eye 3,2,4 -o "$T/fx.json"
    same "$T/fx.json" "$FX/sh_$k.json" 1e-5 "0.1 sh.prt as $k"
done
expect 0 "0.1 compressed file" -- "$PRT" relight "$FX/shc.prt" -o "$T/fx.json"
same "$T/fx.json" "$FX/shc.json" 1e-5 "0.1 shc.prt"
expect 0 "0.1 quantized file" -- "$PRT" relight "$FX/shq.prt" -k shadowed -o "$T/fx.json"
same "$T/fx.json" "$FX/shq.json" 1e-5 "0.1 shq.prt"
expect 0 "0.1 quantized glossy file" -- "$PRT" relight "$FX/shq.prt" -k glossy-shadowed --eye 3,2,4 -o "$T/fx.json"
same "$T/fx.json" "$FX/shq_g.json" 1e-5 "0.1 shq.prt glossy"
expect 0 "0.1 texel map" -- "$PRT" relight "$FX/sh.prt" --texels -o "$T/fx.pfm"
same "$T/fx.pfm" "$FX/sh_texels.pfm" 1e-5 "0.1 sh.prt texels"
expect 0 "0.1 wavelet file" -- "$PRT" relight "$FX/wav.prt" --eye 3,2,4 -o "$T/fx.json"
same "$T/fx.json" "$FX/wav.json" 1e-5 "0.1 wav.prt"
for f in sh shc shq wav; do expect 0 "info of the 0.1 $f.prt" -- "$PRT" info "$FX/$f.prt"; done

# The method table: --help from the declarations, options of another method named as such,
# every method's variants by name.
expect 0 "bake --method wavelet --help" -- "$PRT" bake --method wavelet --help
grep -q -- "--terms" "$T/out" && ! grep -q -- "--order" "$T/out" && ok || bad "bake --method wavelet --help shows other methods' options"
expect 0 "bake --help" -- "$PRT" bake --help
grep -q "Method sh" "$T/out" && grep -q "Method wavelet" "$T/out" && ok || bad "bake --help does not list every method's options"
expect 2 "another method's option" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method wavelet --kinds shadowed
says "option of method sh"
expect 2 "a kind the file lacks" -- "$PRT" relight "$FX/wav.prt" -k shadowed -o "$T/x.json"
says "holds wavelet"

# Local lights: parsed strictly, relit by the methods that can, refused clearly by the others.
expect 2 "bad light" -- "$PRT" relight "$T/demo.prt" --light point:1,2 -o "$T/x.json"
says "expected point:X,Y,Z"
expect 2 "point light on a wavelet file" -- "$PRT" relight "$FX/wav.prt" --light point:0,2,0:10,10,10 -o "$T/x.json"
says "cannot relight point lights"
expect 0 "point light on SH (its SH per vertex)" -- "$PRT" relight "$T/demo.prt" --env none --light point:0,2,0:10,10,10 -o "$T/pt.json"
grep -q '"radiance": \[\[0, 0, 0\]' "$T/pt.json" && bad "a point light on SH lit nothing" || ok
expect 0 "spot, sphere, directional and the environment on SH" -- "$PRT" relight "$T/demo.prt" --light spot:0,2,0:0,-1,0:40,30:5 \
    --light sphere:1,1.5,1:0.2:20 --light directional:0.3,1,0.2:1 -o "$T/x.json"
expect 2 "a bad light window" -- "$PRT" relight "$T/demo.prt" --light point:0,2,0:1 --control light-window=3 -o "$T/x.json"
says "out of range 0..2"
expect 0 "export --sh with a point light: left out, saying so" -- "$PRT" export "$T/demo.prt" -o "$T/shp.gltf" --sh --light point:0,2,0:1
says "left out 1 point"
expect 0 "directional light, no environment" -- "$PRT" relight "$T/demo.prt" --env none --light directional:0.3,1,0.2:3,3,3 -o "$T/dir.json"
expect 0 "nothing but a directional light renders" -- $NOLEAK "$PRT" render "$T/demo.prt" --env none --light directional:0.3,1,0.2:3,3,3 -o "$T/dir.png" --width 64 --height 48
expect 0 "no light at all" -- "$PRT" relight "$T/demo.prt" --env none -o "$T/dark.json"
grep -q '"radiance": \[\[0, 0, 0\]' "$T/dark.json" && ok || bad "no lighting should give zero radiance"
cat >"$T/lamp.json" <<EOF
{ "meshes": [ { "file": "demo.obj" } ],
  "lights": [ { "type": "point", "position": [0, 3, 0], "intensity": [20, 20, 20] },
              { "type": "directional", "direction": [0, 1, 0.2], "irradiance": 2 } ] }
EOF
expect 0 "bake a scene with lights" -- "$PRT" bake "$T/lamp.json" -o "$T/lamp.prt" --order 3 --samples 64 --no-refine -q
expect 0 "info lists the scene's lights" -- "$PRT" info "$T/lamp.prt"
grep -q "point:0,3,0" "$T/out" && grep -q "directional:" "$T/out" && ok || bad "info does not list the lights"
expect 0 "the scene's point light on SH" -- "$PRT" relight "$T/lamp.prt" -o "$T/x.json"
grep -q "left out" "$T/err" && bad "SH left the scene's point light out" || ok
expect 2 "an unknown option in one line" -- "$PRT" relight "$T/lamp.prt" -o "$T/x.json" --oder 3
says "unknown option '--oder'"
expect 2 "a missing value" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --order
says "needs a value"
expect 2 "an abbreviated method option" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --meth wavelet
says "--method"
expect 0 "the scene's lights replaced" -- "$PRT" relight "$T/lamp.prt" --light directional:0,1,0:1,1,1 -o "$T/x.json"
expect 0 "reference under the scene's lights" -- "$PRT" reference "$T/lamp.prt" -o "$T/lampref.json" --samples 4 -q

# The spectral method: local lights with bounces, colours changed without a rebake, controls.
expect 0 "spectral bake" -- "$PRT" bake -q "$T/lamp.json" -o "$T/spec.prt" --method spectral --basis 64 --samples 64 --no-refine
expect 0 "spectral info" -- "$PRT" info "$T/spec.prt"
grep -q "partitions" "$T/out" && grep -q "red_wall" "$T/out" && grep -q "bounces 0..64" "$T/out" && grep -q "tail 0..1 (default 1)" "$T/out" && ok || bad "info lacks partitions, surfaces or controls"
expect 0 "spectral relight with the scene's lights" -- "$PRT" relight -q "$T/spec.prt" -o "$T/spec.json"
grep -q '"direct"' "$T/spec.json" && grep -q '"indirect"' "$T/spec.json" && ok || bad "spectral relight JSON lacks direct and indirect"
expect 0 "spectral relight, recoloured" -- "$PRT" relight -q "$T/spec.prt" -o "$T/spec_red.json" --albedo-of floor=0.9,0.1,0.1 --control bounces=1
cmp -s "$T/spec.json" "$T/spec_red.json" && bad "--albedo-of changed nothing" || ok
# The tail (default on) adds the bounces past the last; tail=0 stops at them.
expect 0 "spectral relight without the tail" -- "$PRT" relight -q "$T/spec.prt" -o "$T/spec_cut.json" --control tail=0
cmp -s "$T/spec.json" "$T/spec_cut.json" && bad "--control tail=0 changed nothing" || ok
expect 2 "a tail out of range" -- "$PRT" relight "$T/spec.prt" -o "$T/x.json" --control tail=2
says "out of range 0..1"
expect 0 "spectral render, lights per pixel" -- $NOLEAK "$PRT" render -q "$T/spec.prt" -o "$T/spec.png" --width 64 --height 48 --light sphere:0,2,0:0.2:30
expect 2 "an unknown surface" -- "$PRT" relight "$T/spec.prt" -o "$T/x.json" --albedo-of carpet=0.5
says "no surface is called 'carpet'"
expect 2 "albedo above 1" -- "$PRT" relight "$T/spec.prt" -o "$T/x.json" --albedo-of floor=2
says "\[0, 1\]"
expect 2 "a control out of range" -- "$PRT" relight "$T/spec.prt" -o "$T/x.json" --control bounces=99
says "out of range 0..64"
expect 2 "a control the method lacks" -- "$PRT" relight "$T/spec.prt" -o "$T/x.json" --control order=3
says "no setting 'order'"
expect 2 "colours of a method that bakes them" -- "$PRT" relight "$T/lamp.prt" -o "$T/x.json" --albedo-of floor=0.5
says "needs a rebake"

# The light cloud: point lights anywhere in a region with full global illumination.
expect 0 "lightcloud bake" -- "$PRT" bake -q "$T/demo.obj" -o "$T/lc.prt" --method lightcloud --cloud-grid 3,2,3 --samples 64 --basis 64 --zone-vertices 3000 --no-refine
# A bad cloud is refused before any work: no stage ran, so no checkpoint of finished work is left.
printf '[[0, 1, 0], [1, "a", 2]]\n' >"$T/badcloud.json"
expect 1 "bad --cloud list" -- "$PRT" bake -q "$T/demo.obj" -o "$T/badlc.prt" --method lightcloud --cloud "$T/badcloud.json"
says "light 1 is not a position"
[ ! -e "$T/badlc.prt.checkpoint" ] && ok || bad "a bad --cloud list was read after work had begun"
expect 2 "absurd --cloud-grid" -- "$PRT" bake -q "$T/demo.obj" -o "$T/badlc.prt" --method lightcloud --cloud-grid 4000,4000,4000
says "at most 1048576"
[ ! -e "$T/badlc.prt.checkpoint" ] && ok || bad "an absurd --cloud-grid was refused after work had begun"
expect 0 "lightcloud info" -- "$PRT" info "$T/lc.prt"
grep -q "cloud:" "$T/out" && grep -q "zones:" "$T/out" && grep -q "neighbours" "$T/out" && ok || bad "info lacks the cloud, zones or control"
expect 0 "lightcloud relight" -- "$PRT" relight -q "$T/lc.prt" -o "$T/lc.json" --light point:0.2,0.8,0.1:2 --control neighbours=4
grep -q '"indirect"' "$T/lc.json" && ok || bad "lightcloud relight JSON lacks indirect"
expect 0 "lightcloud render" -- $NOLEAK "$PRT" render -q "$T/lc.prt" -o "$T/lc.png" --width 64 --height 48 --light point:0.2,0.8,0.1:2
expect 0 "lightcloud reference" -- "$PRT" reference -q "$T/lc.prt" -o "$T/lcref.json" --light point:0.2,0.8,0.1:2 --samples 4
expect 0 "lightcloud sweep (no sky for a method without one)" -- "$PRT" sweep -q "$T/demo.obj" --method lightcloud --param vectors --values 2,4 \
    --reference "$T/lcref.json" --light point:0.2,0.8,0.1:2 --cloud-grid 3,2,3 --samples 64 --basis 64 --zone-vertices 3000 -o "$T/lcsweep.csv"
[ "$(wc -l <"$T/lcsweep.csv")" -eq 3 ] && ok || bad "lightcloud sweep wrote $(wc -l <"$T/lcsweep.csv") lines"
expect 2 "a ray offset beyond the scene" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --ray-offset 1e30 --samples 16
says "scene's size"
expect 2 "a spot light on an isotropic light cloud" -- "$PRT" relight "$T/lc.prt" -o "$T/x.json" --light spot:0,1,0:0,-1,0:30:1
says "need --emission-order 2 or 3"
# IES luminaires: the path tracer takes them; an isotropic light cloud refuses them; a bad file
# is refused with the line and what is wrong.
IES="$(dirname "$0")/../fuzz/regress/ies/seed_downlight.ies"
expect 0 "an ies light in the path tracer" -- "$PRT" reference -q "$T/lc.prt" -o "$T/iesref.json" --light "ies:$IES:0.2,0.8,0.1:0,-1,0:0.002" --samples 4
expect 2 "an ies light on an isotropic light cloud" -- "$PRT" relight "$T/lc.prt" -o "$T/x.json" --light "ies:$IES:0.2,0.8,0.1"
says "need --emission-order 2 or 3"
printf 'IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1 10\n0 60 45\n0\n1 2 3\n' >"$T/bad.ies"
expect 2 "a bad IES file" -- "$PRT" reference -q "$T/lc.prt" -o "$T/x.json" --light "ies:$T/bad.ies:0,1,0"
says "line 5: a vertical angle must increase strictly"
expect 2 "a bad cloud grid" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method lightcloud --cloud-grid 3,0,3
says "--cloud-grid"
printf '{"lights": [[0, 1, 0], [0.5, "high", 0]]}' >"$T/cloud.json"
expect 1 "a bad cloud list" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method lightcloud --cloud "$T/cloud.json" --samples 16
says "light 1"
expect 1 "a missing cloud list" -- "$PRT" bake "$T/demo.obj" -o "$T/x.prt" --method lightcloud --cloud "$T/nothere.json" --samples 16
says "nothere.json"
expect 2 "an environment on a light cloud" -- "$PRT" relight "$T/lc.prt" -o "$T/x.json" --sun 0,1,0 --light point:0,1,0:1
says "cannot relight environment.*to leave it out: --env none"

# A writer killed mid-write leaves "NAME.tmp.PID"; the next write of NAME removes it (that
# process is gone) and leaves other files alone.
sh -c 'exit 0' & dead=$!; wait $dead
: >"$T/stale.prt.tmp.$dead"
: >"$T/stale.prt.keep"
expect 0 "a write after a killed one" -- "$PRT" bake "$T/demo.obj" -o "$T/stale.prt" --order 2 --samples 16 --bounces 1 --no-refine -q
[ ! -e "$T/stale.prt.tmp.$dead" ] && [ -e "$T/stale.prt.keep" ] && ok || bad "a stale temporary was not removed, or too much was"

# Real probes from ../shared/data, when present.
if [ -n "$DATA" ] && [ -f "$DATA/envmaps/probulator_ict/grace.hdr" ]; then
    expect 0 "env grace" -- "$PRT" env "$DATA/envmaps/probulator_ict/grace.hdr" --order 5 -o "$T/grace.json"
    grep -q '"latlong"' "$T/grace.json" && ok || bad "grace.hdr not detected as lat-long"
else
    echo "skipping real-probe checks: ../shared/data is absent"
fi

echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
