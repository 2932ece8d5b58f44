# shellcheck shell=sh
# Where scripts/setup-deps.sh installs the Khronos glTF-Validator (npm gltf-validator) and which
# version: sourced by it and by tests/gltf_test.sh, so both name the same folder. Outside the
# source tree (a cache shared by build folders and worktrees); PRT_TOOLS_DIR moves it.
GLTF_VALIDATOR_VERSION=2.0.0-dev.3.10
GLTF_VALIDATOR_DIR="${PRT_TOOLS_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/prt}/gltf-validator-$GLTF_VALIDATOR_VERSION"

# True when that version is installed there.
gltf_validator_present() {
    grep -q "\"version\": *\"$GLTF_VALIDATOR_VERSION\"" "$GLTF_VALIDATOR_DIR/node_modules/gltf-validator/package.json" 2>/dev/null
}
