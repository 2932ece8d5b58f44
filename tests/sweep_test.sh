#!/bin/sh
# prt sweep --method all (and prt pick): every method of the table on a small room under a point
# light, against a reference traced in the same process; the cache reused on a rerun and
# invalidated by a changed option; one-line usage errors. No wall-clock assertions.
# Usage: sweep_test.sh PATH/TO/prt
set -u
PRT=$1
T=$(mktemp -d /tmp/prt_sweep_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"   # the sweep draws frames: its renders take $NOLEAK
one_line() {
    [ "$(wc -l <"$T/err")" -eq 1 ] && ok || { bad "$1: a usage error takes one line, not $(wc -l <"$T/err")"; sed 's/^/    /' "$T/err"; }
}

# The methods of the table, as prt bake --help lists them.
METHODS=$("$PRT" bake --help | sed -n 's/^ \{25\}\([a-z][a-z0-9_-]*\)  .*/\1/p')
[ -n "$METHODS" ] && ok || bad "no method list in prt bake --help"

for cmd in "sweep --method all" pick; do
    expect 0 "$cmd --help" -- $PRT $cmd --help
    grep -q "Exit codes" "$T/out" && grep -q -- "--reference-samples" "$T/out" && grep -q -- "--cache" "$T/out" && ok || bad "$cmd --help is incomplete"
done

expect 0 "demo-scene --room" -- "$PRT" demo-scene --room --cell 0.5 -o "$T/room.obj"
SCENE="$T/room.obj"
LIGHT="--env none --light point:0.5,2,0.5:5"

# First run: every method baked (or skipped with a reason), the reference traced and cached.
expect 0 "sweep --method all" -- $NOLEAK "$PRT" sweep --method all "$SCENE" $LIGHT --reference-samples 64 --json "$T/s.json" --plot "$T/s" --progress lines
cp "$T/out" "$T/first.txt"
says "reference: tracing 64 paths"
[ -s "$T/s-error-vs-bake.png" ] && [ -s "$T/s-error-vs-size.png" ] && ok || bad "no plots written"
[ -d "$T/room.sweep" ] && ok || bad "no default cache directory room.sweep/ beside the scene"
tail -n 1 "$T/first.txt" | grep -q "^pick .* for the lowest error" && ok || bad "the last line does not say what to pick: $(tail -n 1 "$T/first.txt")"

# check_json FILE REUSED: an entry per method; each measured one finite, below 0.5, with sizes and
# times; the skipped ones with a reason; "reused" as expected for the measured ones.
check_json() {
    if command -v python3 >/dev/null 2>&1; then
        if python3 - "$1" "$2" $METHODS <<'PY'
import json, math, sys
d = json.load(open(sys.argv[1]))
reused = sys.argv[2] == "yes"
want = sys.argv[3:]
rows = {m["method"]: m for m in d["methods"]}
errors = []
if sorted(rows) != sorted(want):
    errors.append("methods %s, expected %s" % (sorted(rows), sorted(want)))
measured = 0
for name, m in rows.items():
    if m["skipped"]:
        if m["relative_l2"] is not None:
            errors.append(name + ": skipped but has an error")
        continue
    measured += 1
    e = m["relative_l2"]
    if not (isinstance(e, (int, float)) and math.isfinite(e) and 0 <= e < 0.5):
        errors.append("%s: relative_l2 %r" % (name, e))
    ei = m["relative_l2_indirect"]
    if ei is not None and not (math.isfinite(ei) and ei >= 0):
        errors.append("%s: relative_l2_indirect %r" % (name, ei))
    for k in ("bake_seconds", "file_bytes", "relight_seconds", "frame_seconds"):
        if not (isinstance(m[k], (int, float)) and m[k] > 0):
            errors.append("%s: %s %r" % (name, k, m[k]))
    if m["reused"] != reused:
        errors.append("%s: reused %r" % (name, m["reused"]))
for name in ("lightcloud", "spectral", "offset"):
    if name in rows and rows[name]["skipped"]:
        errors.append(name + " relights point lights but was skipped: " + rows[name]["skipped"])
# ao relights no point light; SH relights them but not inside a closed room (its transfer finds
# every direction blocked beyond the lamp): both skipped, saying why.
for name in ("ao", "sh"):
    if name in rows and not rows[name]["skipped"]:
        errors.append(name + " cannot relight this room's point light but was not skipped")
if "sh" in rows and "inside the scene" not in rows["sh"]["skipped"]:
    errors.append("sh skipped for another reason: " + rows["sh"]["skipped"])
if measured == 0:
    errors.append("nothing measured")
if not d.get("pick"):
    errors.append("no pick")
if errors:
    print("\n".join(errors))
sys.exit(1 if errors else 0)
PY
        then ok; else bad "$1 (reused: $2): see above"; fi
    else
        for m in $METHODS; do grep -q "\"method\":[[:space:]]*\"$m\"" "$1" && ok || bad "$1 has no entry for $m"; done
    fi
}
check_json "$T/s.json" no

# Second run, the same inputs: bakes and reference come from the cache, and it says so.
expect 0 "sweep --method all again (prt pick)" -- $NOLEAK "$PRT" pick "$SCENE" $LIGHT --reference-samples 64 --json "$T/s2.json"
says "reference: reusing"
says "reusing .*room.sweep/spectral-"
grep -q "baking with its defaults" "$T/err" && bad "the rerun baked again" || ok
check_json "$T/s2.json" yes
[ "$(grep -c "(bake reused)" "$T/out")" -ge 1 ] && ok || bad "the table does not mark reused bakes"

# A changed bake option (one every method declares) bakes again; the reference stays.
expect 0 "sweep --method all with another --ray-offset" -- $NOLEAK "$PRT" sweep --method all "$SCENE" $LIGHT --reference-samples 64 -q \
    --ray-offset 0.002 --json "$T/s3.json"
grep -q "(bake reused)" "$T/out" && bad "a changed option reused a bake" || ok
check_json "$T/s3.json" no

# Usage errors: exit 2, one line.
expect 2 "a method's own option" -- "$PRT" sweep --method all "$SCENE" --order 4
one_line "--order"
says "sh"
expect 2 "--param with --method all" -- "$PRT" sweep --method all "$SCENE" --param order
one_line "--param"
expect 2 "-o with --method all" -- "$PRT" pick "$SCENE" -o "$T/x.csv"
one_line "-o"
expect 2 "--brdf with --method all" -- "$PRT" pick "$SCENE" --brdf phong:10
one_line "--brdf"
expect 2 "misspelt option" -- "$PRT" pick "$SCENE" --refrence-samples 8
one_line "misspelt"
says "did you mean --reference-samples"
expect 2 "bad --reference-samples" -- "$PRT" pick "$SCENE" --reference-samples 0
one_line "--reference-samples 0"
expect 2 "no scene" -- "$PRT" pick
one_line "no scene"
expect 1 "missing scene" -- "$PRT" pick "$T/none.obj"
expect 1 "a --reference that is no per-vertex result" -- "$PRT" pick "$SCENE" $LIGHT --reference "$T/s.json"

echo "sweep_test: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
