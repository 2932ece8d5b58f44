#!/bin/sh
# make install into a fresh prefix, then use it as a user would: the command line runs, the man
# pages are there, each example builds with the command line its header documents (pkg-config),
# and a CMake project finds the package with find_package(prt).
# Usage: install_test.sh BUILD_DIR SOURCE_DIR
BUILD=$1
SRC=$2
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

cmake --install "$BUILD" --prefix "$T/prefix" >"$T/log" 2>&1 && ok || { bad "cmake --install"; cat "$T/log"; exit 1; }
P="$T/prefix"
"$P/bin/prt" info --help >/dev/null && ok || bad "the installed prt does not run"
for f in include/prt/prt.h share/man/man1/prt.1 share/man/man1/prt-bake.1; do [ -s "$P/$f" ] && ok || bad "not installed: $f"; done
PC=$(find "$P" -name prt.pc | head -n 1)
CONFIG=$(find "$P" -name prtConfig.cmake | head -n 1)
LIBDIR=$(dirname "$(find "$P" -name 'libprt.so' | head -n 1)")
[ -n "$PC" ] && [ -n "$CONFIG" ] && [ -d "$LIBDIR" ] && ok || { bad "prt.pc, prtConfig.cmake or libprt.so missing"; exit 1; }
grep -q '^\.TH PRT-BAKE' "$P/share/man/man1/prt-bake.1" && grep -q -- '--output' "$P/share/man/man1/prt-bake.1" && ok || bad "prt-bake.1 does not hold the --help text"

# Each example with its own documented command line.
export PKG_CONFIG_PATH="$(dirname "$PC")"
for ex in minimal wavelet; do
    line=$(sed -n 's/.*Build: \(cc .*\) \*\/.*/\1/p' "$SRC/examples/$ex.c")
    [ -n "$line" ] || { bad "examples/$ex.c documents no build line"; continue; }
    cp "$SRC/examples/$ex.c" "$T/"
    (cd "$T" && eval "$line -o $ex") >"$T/log" 2>&1 && ok || { bad "examples/$ex.c does not build with its line: $line"; sed 's/^/    /' "$T/log"; }
done
(cd "$T" && LD_LIBRARY_PATH="$LIBDIR" ./minimal) >"$T/log" 2>&1 && ok || { bad "the installed minimal example fails"; sed 's/^/    /' "$T/log"; }

# A CMake project.
mkdir -p "$T/user"
cat >"$T/user/CMakeLists.txt" <<'C'
cmake_minimum_required(VERSION 3.18)
project(use_prt C)
find_package(prt 0.1 REQUIRED)
add_executable(use main.c)
target_link_libraries(use PRIVATE prt::prt)
C
printf '#include <prt/prt.h>\n#include <stdio.h>\nint main(void) { puts(prt_version_string()); return 0; }\n' >"$T/user/main.c"
cmake -S "$T/user" -B "$T/user/build" -DCMAKE_PREFIX_PATH="$P" >"$T/log" 2>&1 && cmake --build "$T/user/build" >>"$T/log" 2>&1 && ok \
    || { bad "find_package(prt) project does not build"; sed 's/^/    /' "$T/log"; }
LD_LIBRARY_PATH="$LIBDIR" "$T/user/build/use" | grep -q '^[0-9]' && ok || bad "the find_package(prt) program does not run"

echo "install: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
