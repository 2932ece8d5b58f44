# The checks the command-line test scripts share (sourced after PRT and T are set): counters,
# expected exit codes, messages, and results that must agree.
pass=0
fail=0
# Mesa's llvmpipe leaks 112 bytes inside its driver, which EGL unloads before LeakSanitizer
# reports, so LSan cannot name (or suppress) it: render commands run without leak checking.
# Everything else, and the library tests, keep it.
NOLEAK="env ASAN_OPTIONS=${ASAN_OPTIONS:-}:detect_leaks=0"

ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

# expect CODE DESCRIPTION -- COMMAND...: runs it, checks the exit code; stdout in $T/out, stderr in $T/err.
expect() {
    code=$1; what=$2; shift 3
    "$@" >"$T/out" 2>"$T/err"
    rc=$?
    if [ "$rc" -eq "$code" ]; then ok; else bad "$what: exit $rc, expected $code"; sed 's/^/    /' "$T/err"; fi
}
# same A B TOL WHAT: two results (per-vertex JSON or images) differ by at most TOL anywhere.
same() {
    if ! "$PRT" compare "$1" "$2" --json - -q >"$T/cmp" 2>"$T/err"; then bad "$4: compare failed"; sed 's/^/    /' "$T/err"; return; fi
    m=$(sed -n 's/.*"max_abs":[[:space:]]*\([0-9.eE+-]*\).*/\1/p' "$T/cmp")
    if awk -v m="$m" -v t="$3" 'BEGIN { exit !(m != "" && m + 0 <= t + 0) }'; then ok; else bad "$4: max |A-B| = $m, more than $3"; fi
}
# The last stderr holds one clear line mentioning WORD.
says() {
    if grep -qi -- "$1" "$T/err"; then ok; else bad "stderr does not mention '$1':"; sed 's/^/    /' "$T/err"; fi
}
