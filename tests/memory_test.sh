#!/bin/sh
# Bakes held to a memory limit (prt bake --memory-limit, docs/CLI.md): sizes parsed, bad ones
# refused clearly; an SH bake forced to stream its ray hits through a scratch file (diffuse
# bounces, and the coupled glossy bounces) writes the same bytes outside META as a plain bake,
# also when resumed from the plain bake's checkpoint; every method refuses an impossible limit up
# front - before any progress, leaving no file and no checkpoint - saying what it would need and
# which option lowers it; prt info shows the peak. Usage: memory_test.sh PATH/TO/prt PATH/TO/same_chunks
set -u
PRT=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
SAME=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
T=$(mktemp -d /tmp/prt_memory_XXXXXX)
trap 'rm -rf "$T"' EXIT
. "$(dirname "$0")/shell_checks.sh"
cd "$T" || exit 1
export TMPDIR="$T"

# A floor and a box: a closed corner, so most rays hit something.
cat >box.obj <<'OBJ'
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v -0.3 0 -0.3
v 0.3 0 -0.3
v 0.3 0 0.3
v -0.3 0 0.3
v -0.3 0.6 -0.3
v 0.3 0.6 -0.3
v 0.3 0.6 0.3
v -0.3 0.6 0.3
f 1 3 2
f 1 4 3
f 9 11 10
f 9 12 11
f 5 6 10
f 5 10 9
f 6 7 11
f 6 11 10
f 7 8 12
f 7 12 11
f 8 5 9
f 8 9 12
OBJ
B="bake box.obj --max-edge 0.1 --no-refine -j 2"

# Sizes: bad ones are usage errors that say what a size is.
for bad_size in abc 0 -1 4Q 1.5GX "" 99999999T; do
    expect 2 "--memory-limit '$bad_size'" -- "$PRT" $B -o x.prt --method ao --memory-limit "$bad_size"
    says "memory"
done
for good in 4G 512M 1.5GiB 67108864 none; do
    expect 0 "--memory-limit $good" -- "$PRT" $B -o g.prt --method ao --samples 16 --no-checkpoint --memory-limit "$good"
done
expect 0 "prt info of a bake with no limit" -- "$PRT" info g.prt
grep -q "bake memory:.*peak .* resident (limit none)" out && ok || bad "prt info does not show the peak and the limit: $(grep memory out)"

# SH: plain, then forced to stream; the same bytes outside META.
SH="--method sh --order 3 --samples 64"
expect 0 "plain sh bake" -- "$PRT" $B -o plain.prt $SH --no-checkpoint
expect 0 "streamed sh bake" -- "$PRT" $B -o streamed.prt $SH --no-checkpoint --memory-limit 2M
says "stream through a scratch file"
"$SAME" plain.prt streamed.prt && ok || bad "a streamed sh bake differs from the plain one"
grep -q "peak resident memory" err && ok || bad "the bake does not print its peak"
ls "$T"/tmp* >/dev/null 2>&1 && bad "the scratch file was left in TMPDIR" || ok

# The coupled glossy bounces stream too.
G="--method sh --order 2 --samples 32 --kinds shadowed,interreflected,glossy-interreflected --bounces 2"
expect 0 "plain glossy sh bake" -- "$PRT" $B -o gplain.prt $G --no-checkpoint
expect 0 "streamed glossy sh bake" -- "$PRT" $B -o gstreamed.prt $G --no-checkpoint --memory-limit 2500K
says "stream through a scratch file"
"$SAME" gplain.prt gstreamed.prt && ok || bad "a streamed glossy sh bake differs from the plain one"

# A streamed bake resumed from a checkpoint of the visibility stage made by plain shards (records
# are the same either way: the hits go from the records into the scratch file): the plain bake's bytes.
expect 0 "sh bake to shard 1/2" -- "$PRT" $B -o s1.shard $SH --shard 1/2
expect 0 "sh bake to shard 2/2" -- "$PRT" $B -o s2.shard $SH --shard 2/2
expect 0 "merge of the shards" -- "$PRT" merge s1.shard s2.shard -o vis.checkpoint
if [ -e vis.checkpoint ]; then
    cp vis.checkpoint resumed.prt.checkpoint
    expect 0 "streamed sh bake resumed" -- "$PRT" $B -o resumed.prt $SH --resume --memory-limit 2M
    says "stream through a scratch file"
    says "recovered from the checkpoint"
    "$SAME" plain.prt resumed.prt && ok || bad "a streamed sh bake resumed from a checkpoint differs from the plain one"
fi

# ---- light cloud (issue 28: lights and zones in flight bounded) ----
# Over the limit, fewer cloud lights and zones are in flight than threads: on 4 threads, a limit
# one and a half threads' worth under the plain bake's estimate lets two run at once; the same
# bytes. Under the least (the rest and one in flight) it is refused up front, saying so.
LC="--method lightcloud --cloud-grid 4,4,4 --samples 256 --basis 64"
expect 0 "plain lightcloud bake" -- "$PRT" $B -o lcplain.prt $LC -j 4 --no-checkpoint
lc_est=$(sed -n "s/.*the bake's estimate is \([0-9.]*\) MiB.*/\1/p" err | head -n 1)
lc_per=$(sed -n 's/.*, \([0-9.]*\) MiB a thread for the solves.*/\1/p' err | head -n 1)
if [ -n "$lc_est" ] && [ -n "$lc_per" ]; then
    lc_limit=$(awk -v e="$lc_est" -v p="$lc_per" 'BEGIN { printf "%dK", (e - 1.5 * p) * 1024 }')
    expect 0 "lightcloud bake under $lc_limit" -- "$PRT" $B -o lclimited.prt $LC -j 4 --no-checkpoint --memory-limit "$lc_limit"
    says "in flight at a time of 4 threads"
    "$SAME" lcplain.prt lclimited.prt && ok || bad "a lightcloud bake held to $lc_limit differs from the plain one"
    lc_low=$(awk -v e="$lc_est" -v p="$lc_per" 'BEGIN { printf "%dK", (e - 5 * p) * 1024 }')
    expect 2 "lightcloud under $lc_low" -- "$PRT" $B -o refused.prt $LC -j 4 --memory-limit "$lc_low"
    says "even streaming"
    [ "$(wc -l <err)" -le 3 ] && ok || bad "the lightcloud refusal is not a line or two: $(cat err)"
else
    bad "the plain lightcloud bake does not say its estimate: $(grep memory err)"
fi
ls "$T"/tmp* >/dev/null 2>&1 && bad "a lightcloud scratch file was left in TMPDIR" || ok
# ---- end light cloud ----

# ---- offset (issue 28: maps in a mapped scratch file) ----
# Over the limit, the maps live in a scratch file and only a block's pages stay resident: the same
# bytes, with and without the maps' bounces (whose units write and checkpoint the maps too), also
# resumed from a plain bake's checkpoint of the maps and a part of the bounces.
OF="--method offset --texels 128 --offsets 100"
for mb in "1" "2 --walks 16"; do
    expect 0 "plain offset bake, --map-bounces $mb" -- "$PRT" $B -o ofplain${mb%% *}.prt $OF --map-bounces $mb --no-checkpoint
    expect 0 "offset bake under 24M, --map-bounces $mb" -- "$PRT" $B -o oflimited${mb%% *}.prt $OF --map-bounces $mb --no-checkpoint --memory-limit 24M
    says "maps stream through a scratch file"
    "$SAME" ofplain${mb%% *}.prt oflimited${mb%% *}.prt && ok || bad "an offset bake held to 24M (--map-bounces $mb) differs from the plain one"
done
expect 0 "offset bounces, shard 1/3" -- "$PRT" $B -o of1.shard $OF --map-bounces 2 --walks 16 --shard 1/3
if [ -e of1.shard ]; then
    cp of1.shard ofresumed.prt.checkpoint
    expect 0 "offset bake under 24M resumed" -- "$PRT" $B -o ofresumed.prt $OF --map-bounces 2 --walks 16 --resume --memory-limit 24M
    says "recovered from the checkpoint"
    "$SAME" ofplain2.prt ofresumed.prt && ok || bad "an offset bake held to 24M and resumed differs from the plain one"
fi
expect 2 "offset under 12M" -- "$PRT" $B -o refused.prt $OF --memory-limit 12M
says "even streaming"
[ "$(wc -l <err)" -le 3 ] && ok || bad "the offset refusal is not a line or two: $(cat err)"
ls "$T"/tmp* >/dev/null 2>&1 && bad "an offset scratch file was left in TMPDIR" || ok
# ---- end offset ----

# An impossible limit: refused before any progress, nothing left behind, the need and the option said.
for m in sh wavelet spectral lightcloud offset ao; do
    expect 2 "$m under 64K" -- "$PRT" $B -o refused.prt --method $m --memory-limit 64K
    says "would need about"
    says "raise --memory-limit"
    grep -q "%" err && bad "$m: progress before the refusal" || ok
    [ ! -e refused.prt ] && [ ! -e refused.prt.checkpoint ] && ok || bad "$m: a refused bake left a file"
done

echo "memory_test: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
