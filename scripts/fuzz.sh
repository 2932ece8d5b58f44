#!/bin/sh
# Runs every libFuzzer harness of fuzz/ for SECONDS each, starting from fuzz/regress/NAME and its
# folders (the seeds and every crash ever found; a method's in fuzz/regress/prt/METHOD/) plus the
# corpus grown so far in BUILD/corpus/NAME.
# Usage: scripts/fuzz.sh BUILD SECONDS. Prints executions and coverage per harness; exits 1 if
# any harness found a crash (saved under fuzz/crashes/NAME/).
set -u
B=$1
S=$2
status=0
for h in image prt scene mesh ies grid; do
    mkdir -p "$B/corpus/$h" "fuzz/crashes/$h"
    ASAN_OPTIONS=detect_leaks=1 "$B/fuzz_$h" "$B/corpus/$h" $(find "fuzz/regress/$h" -type d) -max_total_time="$S" -rss_limit_mb=4096 -timeout=10 \
        -artifact_prefix="fuzz/crashes/$h/" -print_final_stats=1 >"$B/fuzz_$h.log" 2>&1
    rc=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$B/fuzz_$h.log")
    cov=$(grep -o 'cov: [0-9]*' "$B/fuzz_$h.log" | tail -n 1)
    echo "fuzz $h: ${execs:-?} executions, ${cov:-cov: ?}, exit $rc"
    [ "$rc" -eq 0 ] || { status=1; tail -n 30 "$B/fuzz_$h.log"; }
done
exit $status
