#!/bin/sh
# The SH course notes' "Is SH basis well-suited?" experiment in small (bench/sh_quality.sh, issue
# 27): a square blocker over a plane under a point light and 20 and 40 degree sources, against
# the analytic shadow. Asserts the notes' trends: SH error falls with order under the 40 degree
# source; wavelets beat low-order SH (error and penumbra width) under the point light and the
# 20 degree source; the path tracer's direct light agrees with the analytic shadow. Then plants
# a reversed trend to see the check catch it. Skipped (77) without python3.
# Usage: sh_quality_test.sh PATH/TO/prt
set -u
PRT=$1
command -v python3 >/dev/null 2>&1 || { echo "python3 not found: skipped"; exit 77; }
T=$(mktemp -d /tmp/prt_sh_quality_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"
BENCH="$(dirname "$0")/../bench"

# 32 x 32 cells (1,089 plane vertices, spacing 0.0625), orders far enough apart that SH's own
# sampling noise cannot reorder them.
expect 0 "the small experiment and its checks" -- env CHECK=1 ORDERS=2,4,6,8,10 FIGURE_ORDERS=2,6,10 \
    REFERENCE_SAMPLES=256 WAVELET_SUPERSAMPLE=1 sh "$BENCH/sh_quality.sh" "$PRT" "$T/q" 32 4096
cat "$T/out"
sed 's/^/    /' "$T/err"
for f in sh_quality.png sh_quality_profile.png sh_quality_profile.svg results.json; do
    [ -s "$T/q/$f" ] && ok || bad "$f was not written"
done
head -c 8 "$T/q/sh_quality.png" | od -c | grep -q 'P   N   G' && ok || bad "sh_quality.png is not a PNG"

# Order 10 relabelled order 2 and back: the check must say the error no longer falls with order.
mv "$T/q/sh_40_o2.json" "$T/q/swap.json"
mv "$T/q/sh_40_o10.json" "$T/q/sh_40_o2.json"
mv "$T/q/swap.json" "$T/q/sh_40_o10.json"
expect 1 "a reversed trend fails the check" -- python3 "$BENCH/sh_quality.py" analyse "$T/q" --orders 2,4,6,8,10 --check
says "does not fall with order"

echo "sh_quality: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
