#!/bin/sh
# scripts/check-architecture.sh on the tree as it is (it must pass), then on a copy with one of
# each kind of finding planted in a different file (each must be reported): a checker that
# cannot fail would pass the first half too.
# usage: architecture_test.sh SOURCE_DIR
set -u
src=$1
fails=0
ok() { :; }
bad() { printf 'FAIL: %s\n' "$*"; fails=$((fails + 1)); }
t=$(mktemp -d)
trap 'rm -rf "$t"' EXIT
trap 'exit 130' INT TERM

if sh "$src/scripts/check-architecture.sh" "$src" >"$t/clean" 2>&1; then ok; else bad "the tree does not pass:"; cat "$t/clean"; fi

cp -r "$src/src" "$src/tools" "$src/include" "$src/docs" "$src/scripts" "$t/"
# plant FILE LINE: appends LINE to FILE (created when missing).
plant() { mkdir -p "$(dirname "$t/$1")"; printf '%s\n' "$2" >>"$t/$1"; }
plant src/render/draw.c '#include "methods/offset/offset.h"'
plant src/transfer/file.c 'static const char *const which = "wavelet";'
plant tools/prt/cmd_info.c 'static const prt_transfer_kind sh_kind = PRT_TRANSFER_SHADOWED;'
plant src/core/util.c '#include "geom/mesh.h"'
plant src/light/lights.c '#include <embree3/rtcore.h>'
plant tools/prt/cmd_compare.c 'static const char *texels(const prt_options *o) { return prt_options_get(o, "texels"); }'
plant tools/prt/view_controls.c 'static int is_neighbours(const prt_control_desc *control) { return !strcmp(control->name, "neighbours"); }'
plant src/methods/wavelet/method.c '#include "methods/spectral/spectral.h"'
plant src/geom/kdtree.c 'static float (*const spacing)(const float *, uint32_t) = prt__lightcloud_spacing;'
plant tools/prt/cmd_env.c '#include "core/internal.h"'
plant src/render/camera.c 'typedef int prt__offset_pass;'
plant src/brdf/medium.c '#include "prt/spectral.h"'
plant src/compress/sparse.c '#include "prt/prt.h"'
plant src/io/rgbe.c '#include "../methods/sh/sh.h"'
plant src/geom/mesh.h '/* prt__method_wavelet in a comment is not code */'
plant src/io/rgbe.h '/* #include "methods/sh/sh.h" in a comment is no include */'
plant src/extra/thing.c 'int prt__thing;'
plant docs/ARCHITECTURE.md '
### Dependencies between methods
| `spectral` | `lightcloud` | a circle, planted |'

sh "$src/scripts/check-architecture.sh" "$t" >"$t/out" 2>&1
rc=$?
[ "$rc" -eq 1 ] && ok || bad "the checker exited $rc on a tree with planted findings, not 1"
expect() {
    if grep -F -- "$1" "$t/out" | grep -qF -- "$2"; then ok; else bad "not reported: $1 ... $2"; fi
}
expect "src/render/draw.c" "names method offset: its header methods/offset/offset.h"
expect "src/transfer/file.c" 'names method wavelet: the string "wavelet"'
expect "tools/prt/cmd_info.c" "names method sh: PRT_TRANSFER_SHADOWED"
expect "src/core/util.c" "includes geom/mesh.h, of a layer above core"
expect "src/light/lights.c" "only geom/ does"
expect "tools/prt/cmd_compare.c" "reads a method's option by name"
expect "tools/prt/view_controls.c" "names method lightcloud: its option or control \"neighbours\""
expect "src/methods/wavelet/method.c" "names method spectral: its header methods/spectral/spectral.h"
expect "src/geom/kdtree.c" "names method lightcloud: prt__lightcloud_spacing"
expect "tools/prt/cmd_env.c" "the command line includes library internals: core/internal.h"
expect "src/render/camera.c" "names method offset: prt__offset_pass"
expect "src/brdf/medium.c" "names method spectral: its header prt/spectral.h"
expect "src/compress/sparse.c" "the umbrella prt/prt.h"
expect "src/extra/thing.c" "not in the layer order"
expect "src/io/rgbe.c" "by a relative path"
if grep -qF "src/geom/mesh.h" "$t/out" || grep -qF "src/io/rgbe.h" "$t/out"; then bad "a comment was taken for code"; fi
expect "docs/ARCHITECTURE.md" "run in a circle"
if [ "$fails" -ne 0 ]; then
    echo "what the checker said:"
    sed 's/^/    /' "$t/out"
    exit 1
fi
echo "architecture: the tree passes, every planted finding is reported, comments are not"
