#!/bin/sh
# Installs the Debian packages prt builds and tests with. Idempotent and silent when
# everything is already present; needs root (or sudo) only when something is missing.
set -eu

PKGS="build-essential cmake pkg-config
libembree-dev libassimp-dev libstb-dev libopenexr-dev libcjson-dev zlib1g-dev
libcmocka-dev libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri gnuplot-nox
libglfw3-dev xvfb xauth liblapacke-dev libopenblas-dev libmetis-dev libqhull-dev clang libomp-dev valgrind"

missing=""
for p in $PKGS; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
[ -z "$missing" ] && exit 0

echo "setup-deps: installing:$missing" >&2
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq >/dev/null
# shellcheck disable=SC2086
$SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
