#!/bin/sh
# Every glTF prt writes passes the Khronos glTF-Validator with no error and no warning: a small
# room baked by every method of the table, relit as each of its kinds to .glb and .gltf, and
# exported to both plain and with each of its method's export options; a written .glb read back
# by a bake. Skips (77) where Node.js or the validator is missing (scripts/setup-deps.sh installs
# them; `make deps` says why it could not).
# Usage: gltf_test.sh PATH/TO/prt SOURCE_DIR
set -u
PRT=$1
SRC=$2
. "$SRC/scripts/gltf-validator.sh"
if ! command -v node >/dev/null 2>&1; then
    echo "SKIP: no node (Node.js): scripts/setup-deps.sh installs it"
    exit 77
fi
if ! gltf_validator_present; then
    echo "SKIP: gltf-validator $GLTF_VALIDATOR_VERSION is not in $GLTF_VALIDATOR_DIR: make deps installs it from npm (it says why when it cannot)"
    exit 77
fi
T=$(mktemp -d /tmp/prt_gltf_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$SRC/tests/shell_checks.sh"

# The methods of the table, as prt bake --help lists them.
METHODS=$("$PRT" bake --help | sed -n 's/^ \{25\}\([a-z][a-z0-9_-]*\)  .*/\1/p')
[ -n "$METHODS" ] && ok || bad "no method list in prt bake --help"

expect 0 "demo-scene --room" -- "$PRT" demo-scene --room --cell 0.5 -o "$T/room.obj"
# Quick settings for whichever of these options a method declares (an option named like another
# method's means the same): small enough for a bake in about a second, with a light map for methods
# that make one.
QUICK="samples=64 bounces=1 order=3 texels=32 offsets=20 iterations=1 walks=16 coefficients=32 supersample=1
gather-res=8 brdf-res=8 basis=64 cloud-grid=2,2,2"

for m in $METHODS; do
    help=$("$PRT" bake --method "$m" --help)
    opts=""
    for q in $QUICK; do
        name=${q%%=*}
        printf '%s\n' "$help" | grep -q -- "^ *--$name " && opts="$opts --$name ${q#*=}"
    done
    # shellcheck disable=SC2086
    expect 0 "bake $m" -- "$PRT" bake -q "$T/room.obj" -o "$T/$m.prt" --method "$m" --no-refine --no-checkpoint \
        --light point:0.5,2,0.5:5 $opts
    [ -s "$T/$m.prt" ] || continue

    # What the file can be relit as: the refusal of a kind it lacks lists them.
    "$PRT" relight "$T/$m.prt" -o "$T/none.glb" -k no-such-kind >/dev/null 2>"$T/err"
    kinds=$(sed -n 's/.*(it holds \([^)]*\)).*/\1/p' "$T/err" | tr -d ,)
    [ -n "$kinds" ] && ok || { bad "$m: no kinds listed in '$(cat "$T/err")'"; continue; }
    # Its export options, as prt info lists them: --NAME, or --NAME VALUE (given a path in $T).
    exports=$("$PRT" info "$T/$m.prt" | sed -n '/^exports:/,/^[a-z]/s/^[a-z: ]*\(--[a-z0-9-]*\)\( [A-Z]*\)\{0,1\}$/\1\2/p')
    files=""
    for k in $kinds; do
        # View-dependent kinds are seen from an eye inside the room.
        eye=""
        "$PRT" relight -q "$T/$m.prt" -k "$k" -o "$T/probe.json" 2>"$T/err" || { grep -q -- "--eye" "$T/err" && eye="--eye 0,1.5,1.5"; }
        for ext in glb gltf; do
            out="$T/$m-$k-relight.$ext"
            # shellcheck disable=SC2086
            expect 0 "relight $m -k $k -o .$ext" -- "$PRT" relight -q "$T/$m.prt" -k "$k" $eye -o "$out"
            [ -s "$out" ] && files="$files $out"
            [ -z "${first:-}" ] && [ -s "$out" ] && [ "$ext" = glb ] && first=$out && first_m=$m && first_opts=$opts
            out="$T/$m-$k-export.$ext"
            # shellcheck disable=SC2086
            expect 0 "export $m -k $k -o .$ext" -- "$PRT" export -q "$T/$m.prt" -k "$k" $eye -o "$out"
            [ -s "$out" ] && files="$files $out"
            printf '%s\n' "$exports" | while read -r opt arg; do
                [ -n "$opt" ] || continue
                out="$T/$m-$k-export${opt#-}.$ext"
                value=""
                [ -n "$arg" ] && value="$T/$m-$k-$ext${opt#-}-value"
                # Some kinds may not carry what an option exports: a refusal names the option.
                # shellcheck disable=SC2086
                if "$PRT" export -q "$T/$m.prt" -k "$k" $eye -o "$out" "$opt" $value >"$T/out" 2>"$T/err"; then
                    echo "$out" >>"$T/optfiles"
                elif ! grep -q -- "$opt\|$k" "$T/err"; then
                    echo "FAIL: export $m -k $k $opt -o .$ext: $(cat "$T/err")" >>"$T/optfail"
                fi
            done
        done
    done
    [ -s "$T/optfiles" ] && files="$files $(cat "$T/optfiles")"
    [ -s "$T/optfail" ] && { bad "$(cat "$T/optfail")"; rm -f "$T/optfail"; }
    rm -f "$T/optfiles"
    # shellcheck disable=SC2086
    if node "$SRC/tests/gltf_validate.js" "$GLTF_VALIDATOR_DIR" $files >"$T/report" 2>&1; then
        ok
        echo "$m: $(echo $files | wc -w) glTF files valid"
    else
        bad "$m: the glTF-Validator reports errors or warnings:"
        sed 's/^/    /' "$T/report"
    fi
done

# A .glb prt wrote reads back as a scene: the triangles and bounds of the file it came from.
if [ -n "${first:-}" ]; then
    # shellcheck disable=SC2086
    expect 0 "bake a written .glb" -- "$PRT" bake -q "$first" -o "$T/back.prt" --method "$first_m" --no-refine --no-checkpoint $first_opts
    "$PRT" info "$T/$first_m.prt" | grep -E "^(mesh|bounds):" | sed 's/, with UVs//' >"$T/was"
    "$PRT" info "$T/back.prt" | grep -E "^(mesh|bounds):" | sed 's/, with UVs//' >"$T/now"
    sed -i 's/[0-9]* vertices, //' "$T/was" "$T/now"   # assimp joins identical vertices
    cmp -s "$T/was" "$T/now" && ok || bad "the .glb read back differs: $(cat "$T/now") from $(cat "$T/was")"
fi

echo "gltf: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
