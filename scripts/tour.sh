#!/bin/sh
# Runs the README's tour exactly as written - the first ```sh block under "## A N-minute tour" -
# from the repository root, line by line, timing each command, so that the README stays true:
# `make tour` and the `tour` test run it. Lines that open a window (prt view) are skipped: they
# need a display and a person. Every other line must succeed. With TOUR_STRICT_TIME=1 (make
# tour) the whole tour must also finish within the minutes its title states.
set -eu
cd "$(dirname "$0")/.."
title=$(grep -m 1 '^## A [0-9]*-minute tour' README.md) || { echo "tour: README.md has no '## A N-minute tour' section" >&2; exit 1; }
minutes=$(echo "$title" | sed 's/^## A \([0-9]*\)-minute tour.*/\1/')
T=$(mktemp -d /tmp/prt_tour_XXXXXX)
trap 'rm -rf "$T"' EXIT
awk '/^## A [0-9]+-minute tour/ { f = 1; next } f && /^```sh/ { b = 1; next } b && /^```/ { exit } b { print }' README.md >"$T/block"
[ -s "$T/block" ] || { echo "tour: the tour section has no \`\`\`sh block" >&2; exit 1; }

# The line, quoted for an echo (at most 90 characters of it).
quoted() { printf '%s' "$1" | cut -c 1-90 | sed 's/["$`\\]/\\&/g'; }
# A command of the tour, then a line with its time.
timed() {
    printf 't0=$(now)\n%s\n' "$1"
    printf 'echo "tour: $(awk -v a="$(now)" -v b="$t0" '"'"'BEGIN { printf "%%6.1f", a - b }'"'"') s  %s"\n' "$(quoted "$1")"
}
# One script: each command and its time; comments and blank lines left out.
{
    echo 'set -eu'
    echo 'now() { date +%s.%N; }'
    while IFS= read -r line; do
        case "$line" in
        '' | '#'*) continue ;;
        *'$P view '*) printf 'echo "tour: skipped (needs a display): %s"\n' "$(quoted "$line")" ;;
        *'../shared/'*)
            if [ -d ../shared/data ]; then
                timed "$line"
            else
                printf 'echo "tour: skipped (../shared/data is absent): %s"\n' "$(quoted "$line")"
            fi
            ;;
        *)
            timed "$line"
            ;;
        esac
    done <"$T/block"
} >"$T/tour.sh"

start=$(date +%s)
if ! sh "$T/tour.sh"; then
    echo "tour: a command of the README's tour failed (above)" >&2
    exit 1
fi
took=$(($(date +%s) - start))
echo "tour: the whole tour took ${took} s; its title says ${minutes} minutes"
if [ "${TOUR_STRICT_TIME:-0}" = 1 ] && [ "$took" -gt $((minutes * 60)) ]; then
    echo "tour: over the time the README states: measure it again and fix the title or the tour" >&2
    exit 1
fi
