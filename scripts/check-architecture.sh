#!/bin/sh
# Checks that the source tree is cut as docs/ARCHITECTURE.md says, and says where it is not:
#
#  1. Outside src/methods/NAME/ and the table (src/methods/table.c), no source file of src/ or
#     tools/prt names method NAME: not its identifiers (whatever its own headers declare -
#     src/methods/NAME/*.h and the public headers marked "prt-method: NAME" - and the prefixes
#     prt_NAME_, prt__NAME_, PRT_NAME_, PRT__NAME_, prt__method_NAME), not its headers, not its
#     name as a string, not its options or controls looked up by name. A method may use
#     another's method-facing header (src/methods/OTHER/OTHER.h, OTHER's public header) only where
#     docs/ARCHITECTURE.md declares the dependency ("Dependencies between methods"), and those
#     dependencies run in no circle. Shared code never reads an option by name.
#  2. The layers of src/ are ordered (LAYERS below, lowest first): a file includes its own layer's
#     headers and lower ones', never a higher layer's - so no two layers include each other and no
#     include cycle runs between them. Embree is included only in geom/ (geom/raycast.h is the
#     one header through which the rest reaches it); no file of src/ includes the umbrella
#     prt/prt.h; tools/prt includes public headers only.
#
# Comments do not count (the C compiler's preprocessor drops them: $CC, default cc); strings do.
# Exit 0 when everything holds, 1 with one line per finding, 2 when it cannot check. `make test` runs it (ctest: architecture), and
# tests/architecture_test.sh plants each kind of finding in a copy of the tree to see it caught.
#
# The SH method is known by what its headers declare and by prt__method_sh, not by the prefix
# prt_sh_: that prefix is also the spherical-harmonics maths (prt/sh.h, prt_sh_light) every
# method shares.
set -eu
cd "${1:-$(dirname "$0")/..}"

LAYERS="core geom io light brdf compress render transfer methods"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
: >"$tmp/findings"
report() { printf '%s\n' "$*" >>"$tmp/findings"; }
CC=${CC:-cc}
strip() {
    "$CC" -fpreprocessed -dD -E -P -x c "$1" 2>"$tmp/cc" || { printf 'check-architecture: %s cannot read %s: %s\n' "$CC" "$1" "$(head -n 1 "$tmp/cc")" >&2; exit 2; }
}

methods=$(for d in src/methods/*/; do [ -d "$d" ] && basename "$d"; done)

# Declared dependencies: rows "| `A` | `B` | ..." under "### Dependencies between methods".
awk '/^### Dependencies between methods/ { on = 1; next } on && /^#/ { on = 0 }
     on && /^\| *`[a-z0-9_]+` *\| *`[a-z0-9_]+` *\|/ { gsub(/[`|]/, " "); print $1, $2 }' docs/ARCHITECTURE.md >"$tmp/deps"
while read -r a b; do
    [ -d "src/methods/$a" ] && [ -d "src/methods/$b" ] || report "docs/ARCHITECTURE.md: the dependency of '$a' on '$b' names no method folder"
done <"$tmp/deps"
tsort "$tmp/deps" >/dev/null 2>"$tmp/tsort" ||
    report "docs/ARCHITECTURE.md: the dependencies between methods run in a circle through $(grep -v 'loop' "$tmp/tsort" | sed 's/^tsort: //' | tr '\n' ' ')"

# Every source file once: code without comments, its identifiers, its strings, its strings on
# lines about options or controls, its includes. Files are numbered; list holds "N path".
mkdir "$tmp/c" "$tmp/t" "$tmp/s" "$tmp/l" "$tmp/i"
n=0
for f in $(find src tools/prt -name '*.c' -o -name '*.h' | sort); do
    n=$((n + 1))
    echo "$n $f" >>"$tmp/list"
    strip "$f" >"$tmp/c/$n"
    sed -E 's/"([^"\\]|\\.)*"/""/g' "$tmp/c/$n" | grep -oE '[A-Za-z_][A-Za-z0-9_]*' | sort -u >"$tmp/t/$n" || true
    # Strings, less getopt tables' flag names (a command's own flags, whatever they are called:
    # `prt env --order` is the SH maths' order, `prt sweep --param` no method's); and the strings
    # on lines about options or controls, where one would be looked up by name.
    grep -vE '\{ *"[^"]*", *(no|required|optional)_argument' "$tmp/c/$n" >"$tmp/noopt" || true
    grep -oE '"([^"\\]|\\.)*"' "$tmp/noopt" | sort -u >"$tmp/s/$n" || true
    grep -iE 'option|control' "$tmp/noopt" | grep -oE '"([^"\\]|\\.)*"' | sort -u >"$tmp/l/$n" || true
    grep -E '^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"]' "$tmp/c/$n" | sed -E 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*[<"]([^>"]*).*/\1/' >"$tmp/i/$n" || true
done
path_of() { sed -n "s/^$1 //p" "$tmp/list"; }
number_of() { echo "${1##*/}"; }

# Each method's public headers and identifiers, and the option and control names only it declares.
: >"$tmp/names"
for m in $methods; do
    grep -lE "prt-method: $m( |\$)" include/prt/*.h 2>/dev/null | sed 's#^include/##' >"$tmp/pub.$m" || true
    for h in src/methods/"$m"/*.h $(sed 's#^#include/#' "$tmp/pub.$m"); do
        [ -f "$h" ] && strip "$h" | awk -f scripts/declared.awk
    done | sort -u >"$tmp/ids.$m"
    echo "prt__method_$m" >>"$tmp/ids.$m"
    for c in src/methods/"$m"/*.c; do [ -f "$c" ] && strip "$c"; done | tr '\n' ' ' |
        grep -oE '\{ *"[a-z0-9-]+", *(NULL|"[^"]*"), *PRT_OPTION_|\{ *"[a-z0-9-]+", *"[^"]*", *'"'"'.'"'"' *, *'"'" |
        sed -E 's/^\{ *"([a-z0-9-]+)".*/\1/' | sort -u | sed "s/\$/ $m/" >>"$tmp/names" || true
done
for m in $methods; do
    sort "$tmp/names" | awk -v m="$m" '{ n[$1]++; o[$1] = $2 } END { for (k in n) if (n[k] == 1 && o[k] == m) print "\"" k "\"" }' >"$tmp/own.$m"
    echo "\"$m\"" >"$tmp/name.$m"
done

# 1. Naming: per method, the files that name it, minus its own folder, the table and declared
# dependents.
for m in $methods; do
    {
        grep -lFxf "$tmp/ids.$m" "$tmp"/t/* || true
        [ "$m" = sh ] || grep -liE "^(prt__?|PRT__?)${m}_" "$tmp"/t/* || true
        grep -lFxf "$tmp/name.$m" "$tmp"/s/* || true
        [ -s "$tmp/own.$m" ] && grep -lFxf "$tmp/own.$m" "$tmp"/l/* || true
        grep -l "^methods/$m/" "$tmp"/i/* || true
        [ -s "$tmp/pub.$m" ] && grep -lFxf "$tmp/pub.$m" "$tmp"/i/* || true
    } | while read -r hit; do number_of "$hit"; done | sort -un >"$tmp/hits.$m"
    while read -r k; do
        f=$(path_of "$k")
        case "$f" in src/methods/table.c | src/methods/"$m"/*) continue ;; esac
        own=""
        case "$f" in src/methods/*/*) own=$(echo "$f" | cut -d/ -f3) ;; esac
        if [ -n "$own" ] && grep -qx "$own $m" "$tmp/deps"; then
            inc=$(grep "^methods/$m/" "$tmp/i/$k" | grep -vx "methods/$m/$m.h" | tr '\n' ' ' || true)
            [ -z "$inc" ] || report "$f: includes more of method $m than its method-facing header methods/$m/$m.h: $inc"
            continue
        fi
        what=$( {
            grep -Fxf "$tmp/ids.$m" "$tmp/t/$k" || true
            [ "$m" = sh ] || grep -iE "^(prt__?|PRT__?)${m}_" "$tmp/t/$k" || true
            grep -Fxf "$tmp/name.$m" "$tmp/s/$k" | sed 's/^/the string /' || true
            [ -s "$tmp/own.$m" ] && grep -Fxf "$tmp/own.$m" "$tmp/l/$k" | sed 's/^/its option or control /' || true
            grep "^methods/$m/" "$tmp/i/$k" | sed 's/^/its header /' || true
            [ -s "$tmp/pub.$m" ] && grep -Fxf "$tmp/pub.$m" "$tmp/i/$k" | sed 's/^/its header /' || true
        } | sort -u | head -n 4 | tr '\n' ',' | sed 's/,$//; s/,/, /g')
        report "$f: names method $m: $what"
    done <"$tmp/hits.$m"
done
# Options are a method's own: shared code never reads one by name.
grep -nE '(prt_options_(get|set)|prt_method_(export_)?option|prt__opt[a-z_]*) *\([^,()]*, *"' "$tmp"/c/* 2>/dev/null |
    while IFS=: read -r file line text; do
        f=$(path_of "$(number_of "$file")")
        case "$f" in src/methods/*/*) ;; *) printf '%s:%s: reads a method'"'"'s option by name: %s\n' "$f" "$line" "$(printf '%s' "$text" | sed 's/^ *//')" ;; esac
    done >>"$tmp/findings"

# 2. Layers.
for l in $LAYERS; do echo "$l"; done | awk '{ print $1, NR }' >"$tmp/ranks"
while read -r k f; do
    case "$f" in
    src/*)
        layer=$(echo "$f" | cut -d/ -f2)
        grep -qx "$layer [0-9]*" "$tmp/ranks" || report "$f: src/$layer is not in the layer order (LAYERS in scripts/check-architecture.sh)"
        awk -v f="$f" -v layer="$layer" 'NR == FNR { rank[$1] = $2; next }
            $0 == "prt/prt.h" { print f ": includes the umbrella prt/prt.h (include the public headers it implements)"; next }
            /^\.\.\// || /\/\.\.\// { print f ": includes " $0 " by a relative path (name the layer: LAYER/file.h)"; next }
            /^embree3\// { if (layer != "geom") print f ": includes Embree (" $0 "): only geom/ does (geom/raycast.h)"; next }
            { top = $0; sub(/\/.*/, "", top) }
            (top in rank) && (layer in rank) && rank[top] > rank[layer] { print f ": includes " $0 ", of a layer above " layer }' \
            "$tmp/ranks" "$tmp/i/$k" >>"$tmp/findings"
        ;;
    tools/*)
        grep -E "^($(echo $LAYERS | tr ' ' '|'))/|\.\./" "$tmp/i/$k" | sed "s#^#$f: the command line includes library internals: #" >>"$tmp/findings" || true
        ;;
    esac
done <"$tmp/list"

if [ -s "$tmp/findings" ]; then
    cat "$tmp/findings"
    exit 1
fi
echo "architecture: $(echo $methods | wc -w) methods, each named only in its folder and the table; layers include downwards only"
