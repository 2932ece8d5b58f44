#!/bin/sh
# Installs the Debian packages prt builds and tests with. Idempotent and silent when
# everything is already present; needs root (or sudo) only when something is missing. Node.js, npm
# and the glTF validator serve one test only: failing to get them is said, and that test skips.
set -eu

PKGS="build-essential cmake pkg-config
libembree-dev libassimp-dev libstb-dev libopenexr-dev libcjson-dev zlib1g-dev
libcmocka-dev libepoxy-dev libegl-dev libegl-mesa0 libgl1-mesa-dri gnuplot-nox
libglfw3-dev xvfb xauth liblapacke-dev libopenblas-dev libmetis-dev libqhull-dev clang libomp-dev valgrind
libopenmpi-dev openmpi-bin"

missing=""
for p in $PKGS; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
# Node.js and npm run the Khronos glTF-Validator over prt's glTF output in `make test`
# (tests/gltf_test.sh). Nothing builds with them, so without them that test skips: a failure to
# install them is said, not fatal. Asked by command, not package: Node.js from elsewhere (NodeSource
# bundles npm) serves as well and Debian's npm would conflict with it.
node_missing=""
command -v node >/dev/null 2>&1 || node_missing="nodejs"
command -v npm >/dev/null 2>&1 || node_missing="$node_missing npm"
# Chromium runs prt export --web's page headless in `make test` (tests/web_test.sh, with node
# comparing its screenshots to prt render's); without it that test skips, so failing to install it
# is said, not fatal. Any chromium on the PATH serves (the test also takes $PRT_CHROMIUM).
chromium_missing=""
command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || command -v google-chrome >/dev/null 2>&1 ||
    chromium_missing="chromium"

if [ -n "$missing$node_missing$chromium_missing" ]; then
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    export DEBIAN_FRONTEND=noninteractive
    if [ -n "$missing" ]; then
        echo "setup-deps: installing:$missing" >&2
        $SUDO apt-get update -qq >/dev/null
        # shellcheck disable=SC2086
        $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
    fi
    if [ -n "$node_missing" ]; then
        echo "setup-deps: installing:$node_missing (for the glTF validation test)" >&2
        # shellcheck disable=SC2086
        { [ -n "$missing" ] || $SUDO apt-get update -qq; } >/dev/null 2>&1 &&
            $SUDO apt-get install -y -qq --no-install-recommends $node_missing >/dev/null 2>&1 ||
            echo "setup-deps: could not install$node_missing: the glTF validation test will skip" >&2
    fi
    if [ -n "$chromium_missing" ]; then
        echo "setup-deps: installing: chromium (for the web page test)" >&2
        { [ -n "$missing$node_missing" ] || $SUDO apt-get update -qq; } >/dev/null 2>&1 &&
            $SUDO apt-get install -y -qq --no-install-recommends chromium >/dev/null 2>&1 ||
            echo "setup-deps: could not install chromium: the web page test will skip" >&2
    fi
fi

# The validator itself, a pinned version from npm, into a folder outside the source tree
# (scripts/gltf-validator.sh names it). Unreachable npm leaves it out, says so once, and tries
# again a day later (or when the .failed stamp beside the folder is removed).
. "$(dirname "$0")/gltf-validator.sh"
if ! gltf_validator_present && command -v npm >/dev/null 2>&1; then
    stamp="$GLTF_VALIDATOR_DIR.failed"
    if [ -z "$(find "$stamp" -mmin -1440 2>/dev/null)" ]; then
        echo "setup-deps: installing gltf-validator@$GLTF_VALIDATOR_VERSION into $GLTF_VALIDATOR_DIR" >&2
        # Into a fresh folder renamed into place: a run cut short or a second one at once leaves
        # no half-installed validator under the final name.
        tmp="$GLTF_VALIDATOR_DIR.tmp.$$"
        rm -rf "$tmp"
        if mkdir -p "$tmp" &&
            timeout 300 npm install --no-audit --no-fund --no-update-notifier --fetch-retries 1 --fetch-timeout 30000 \
                --prefix "$tmp" "gltf-validator@$GLTF_VALIDATOR_VERSION" >"$tmp.log" 2>&1 &&
            { rm -rf "$GLTF_VALIDATOR_DIR"; mv "$tmp" "$GLTF_VALIDATOR_DIR"; } && gltf_validator_present; then
            rm -f "$stamp" "$tmp.log"
        else
            echo "setup-deps: could not install gltf-validator from npm (its registry unreachable?): the glTF" \
                 "validation test will skip; tried again after a day, or at once when $stamp is removed" >&2
            sed 's/^/    /' "$tmp.log" 2>/dev/null | tail -n 5 >&2
            rm -rf "$tmp" "$tmp.log"
            touch "$stamp" 2>/dev/null || true
        fi
    fi
fi
