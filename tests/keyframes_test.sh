#!/bin/sh
# Key-framed PRT on the command line (issue 27, animated objects): prt bake --frames of three OBJ
# key frames (a blocker moving over a floor), relight and render --time, prt info; what is not a
# key frame of the same object, or not a time the file holds, is refused by name.
# Usage: keyframes_test.sh PATH/TO/prt
set -u
PRT=$1
T=$(mktemp -d /tmp/prt_keyframes_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"

# frame NAME X [EXTRA]: a 16 x 16 floor and a 0.6 x 0.6 blocker at height 0.4 centred on x; EXTRA
# adds a triangle to the blocker (other topology).
frame() {
    awk -v x="$2" -v extra="${3:-}" 'BEGIN {
        n = 16; print "o floor"
        for (j = 0; j <= n; j++) for (i = 0; i <= n; i++) printf "v %g 0 %g\n", -1 + 2 * i / n, -1 + 2 * j / n
        for (j = 0; j < n; j++) for (i = 0; i < n; i++) { a = j * (n + 1) + i + 1; printf "f %d %d %d\nf %d %d %d\n", a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2 }
        b = (n + 1) * (n + 1); print "o blocker"
        printf "v %g 0.4 -0.3\nv %g 0.4 -0.3\nv %g 0.4 0.3\nv %g 0.4 0.3\n", x - 0.3, x + 0.3, x + 0.3, x - 0.3
        printf "f %d %d %d\nf %d %d %d\n", b + 1, b + 2, b + 3, b + 1, b + 3, b + 4
        if (extra != "") printf "f %d %d %d\n", b + 1, b + 2, b + 4
    }' >"$T/$1.obj"
}
frame f0 -0.3; frame f1 0; frame f2 0.3; frame odd 0.3 extra
BAKE="--order 4 --samples 256 --bounces 1"
expect 0 "bake --frames" -- "$PRT" bake -q --frames "$T/f0.obj" "$T/f1.obj" "$T/f2.obj" -o "$T/anim.prt" $BAKE
for f in 0 1 2; do
    expect 0 "bake key frame $f alone" -- "$PRT" bake -q "$T/f$f.obj" -o "$T/s$f.prt" $BAKE --no-refine
    expect 0 "relight key frame $f alone" -- "$PRT" relight -q "$T/s$f.prt" -o "$T/s$f.json"
    expect 0 "relight --time $f" -- "$PRT" relight -q "$T/anim.prt" --time $f -o "$T/a$f.json"
    same "$T/a$f.json" "$T/s$f.json" 0.02 "--time $f against key frame $f's own bake"
done
expect 0 "relight --time 0.5" -- "$PRT" relight -q "$T/anim.prt" --time 0.5 -o "$T/a05.json"
# Between the key frames: neither of them.
"$PRT" compare "$T/a05.json" "$T/a0.json" --json - -q >"$T/cmp" 2>/dev/null
grep -q '"max_abs":[[:space:]]*0[,}]' "$T/cmp" && bad "--time 0.5 relights as key frame 0" || ok
expect 0 "info" -- "$PRT" info "$T/anim.prt"
grep -q "key frames: *3 (times 0 to 2)" "$T/out" && ok || bad "prt info does not give the key frames: $(grep -i frame "$T/out")"
expect 0 "info --json" -- "$PRT" info --json "$T/anim.prt"
grep -q '"key_frames"' "$T/out" && ok || bad "prt info --json has no key_frames"

expect 2 "a time past the last key frame" -- "$PRT" relight -q "$T/anim.prt" --time 2.5 -o "$T/x.json"
says "outside the key frames"
expect 2 "a time on a file of one pose" -- "$PRT" relight -q "$T/s0.prt" --time 0 -o "$T/x.json"
says "one pose"
expect 2 "another topology" -- "$PRT" bake -q --frames "$T/f0.obj" "$T/f1.obj" "$T/odd.obj" -o "$T/x.prt" $BAKE
says "odd.obj' differs in topology"
expect 2 "one key frame" -- "$PRT" bake -q --frames "$T/f0.obj" -o "$T/x.prt" $BAKE
says "2 to 1024 key frames"
expect 2 "key frames refined" -- "$PRT" bake -q --frames "$T/f0.obj" "$T/f1.obj" -o "$T/x.prt" $BAKE --refine
says "without refinement"
expect 2 "key frames quantized" -- "$PRT" bake -q --frames "$T/f0.obj" "$T/f1.obj" -o "$T/x.prt" $BAKE --quantize 8
says "drop --quantize"
expect 2 "key frames per texel" -- "$PRT" bake -q --frames "$T/f0.obj" "$T/f1.obj" -o "$T/x.prt" $BAKE --texels 64
says "drop --texels"
[ -e "$T/x.prt" ] && bad "a refused bake wrote its file" || ok

# render --time draws the pose between the key frames (headless EGL; skipped where it cannot start).
if $NOLEAK "$PRT" render -q "$T/anim.prt" --time 1.5 --width 64 --height 48 -o "$T/r.png" 2>"$T/err"; then
    [ -s "$T/r.png" ] && ok || bad "render --time wrote no image"
else
    grep -qi "egl\|opengl\|display" "$T/err" && echo "skipping render --time: $(head -n 1 "$T/err")" || { bad "render --time failed"; sed 's/^/    /' "$T/err"; }
fi

# prt view under Xvfb: --time starts at a pose, / and \ step a tenth of a frame, space plays
# and pauses; screenshots equal prt render --time of the same pose.
if command -v xvfb-run >/dev/null 2>&1; then
    printf '%s\n' "0 screenshot $T/v10.exr" "0 key /" "0 key /" "0 screenshot $T/v12.exr" "0 key space" "0.3 key space" "0.3 key \\" \
        "0.4 screenshot $T/vp.exr" "0.4 quit" >"$T/vs.txt"
    if $NOLEAK xvfb-run -a -s "-screen 0 640x480x24" "$PRT" view "$T/anim.prt" --time 1 --width 160 --height 120 --script "$T/vs.txt" >/dev/null 2>"$T/err"; then
        ok
        for tm in 1 1.2; do
            expect 0 "render --time $tm" -- $NOLEAK "$PRT" render -q "$T/anim.prt" --time $tm --width 160 --height 120 -o "$T/r$tm.exr"
        done
        same "$T/v10.exr" "$T/r1.exr" 0.002 "view --time 1 against render --time 1"
        same "$T/v12.exr" "$T/r1.2.exr" 0.002 "view after two steps against render --time 1.2"
        [ -s "$T/vp.exr" ] && ok || bad "no screenshot after playing"
    else
        bad "scripted view of key frames"; sed 's/^/    /' "$T/err"
    fi
    expect 2 "view --time past the key frames" -- $NOLEAK "$PRT" view "$T/anim.prt" --time 3
    says "outside the key frames"
    expect 2 "view --play of one pose" -- $NOLEAK "$PRT" view "$T/s0.prt" --play
    says "one pose"
else
    echo "skipping the viewer checks: xvfb-run is not installed"
fi

echo "keyframes: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
