#!/bin/sh
# Bakes held to a memory limit (prt bake --memory-limit, docs/CLI.md): sizes parsed, bad ones
# refused clearly; an SH bake forced to stream its ray hits through a scratch file (diffuse
# bounces, and the coupled glossy bounces) writes the same bytes outside META as a plain bake,
# also when resumed from the plain bake's checkpoint; a spectral bake forced to stream its
# transfer rows does the same (diffuse and glossy rows, any thread count, shards and resume; the
# light cloud's spectral stages too); every method refuses an impossible limit up
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

# Spectral: its transfer rows stream through a scratch file in blocks - diffuse, and the glossy
# final bounce's 16 rows a vertex - with the plain bake's bytes at any thread count, also resumed
# from a plain shard's records; a streamed shard merges with a plain one into those bytes too.
printf 'v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 3 2\nf 1 4 3\n' >floor.obj
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n' >cube.obj
printf 'f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 7 3\nf 4 8 7\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n' >>cube.obj
cat >glossy.json <<'JSON'
{"environment": "none", "materials": {"floor": {"albedo": 0.5}, "shiny": {"brdfs": ["phong:20:0.5:0.3", "lambert:0.6"]}},
 "meshes": [{"file": "floor.obj", "material": "floor"}, {"file": "cube.obj", "material": "shiny", "translate": [-0.5, 0, -0.5]}]}
JSON
SP="--method spectral --basis 48 --samples 64"
expect 0 "plain spectral bake" -- "$PRT" $B -o splain.prt $SP --no-checkpoint
# The limit between the streamed need and the plain one, both read from a refusal's line.
expect 2 "spectral's need" -- "$PRT" $B -o refused.prt $SP --memory-limit 1K
need=$(sed -n 's/.*would need about \([0-9.]*\) MiB even streaming, \([0-9.]*\) MiB without.*/\1 \2/p' err)
[ -n "$need" ] && ok || bad "spectral does not say what it needs streaming and without: $(cat err)"
mid=$(echo "${need:-0 0}" | awk '{ printf "%dK", ($1 + $2) / 2 * 1024 }')
expect 0 "streamed spectral bake" -- "$PRT" $B -o sstreamed.prt $SP --no-checkpoint --memory-limit "$mid"
says "stream through a scratch file"
"$SAME" splain.prt sstreamed.prt && ok || bad "a streamed spectral bake differs from the plain one"
ls "$T"/tmp* >/dev/null 2>&1 && bad "the spectral scratch file was left in TMPDIR" || ok
GB="bake glossy.json --max-edge 0.2 --no-refine"
GP="$SP --partition 200"   # small eigen problems: the rows, not the threads' solves, set the need
expect 0 "plain glossy spectral bake" -- "$PRT" $GB -j 2 -o gsplain.prt $GP --no-checkpoint
# One limit that streams at 1, 2 and 3 threads: over the plain need at -j 1, within the streamed one at -j 3.
expect 2 "glossy spectral's need at -j 1" -- "$PRT" $GB -j 1 -o refused.prt $GP --memory-limit 1K
need1=$(sed -n 's/.*would need about \([0-9.]*\) MiB even streaming, \([0-9.]*\) MiB without.*/\1 \2/p' err)
expect 2 "glossy spectral's need at -j 3" -- "$PRT" $GB -j 3 -o refused.prt $GP --memory-limit 1K
need=$(sed -n 's/.*would need about \([0-9.]*\) MiB even streaming, \([0-9.]*\) MiB without.*/\1 \2/p' err)
mid=$(echo "${need:-0 0} ${need1:-0 0}" | awk '{ printf "%dK", ($1 + $4) / 2 * 1024 }')
echo "${need:-0 0} ${need1:-0 0}" | awk '{ exit !($1 > 0 && $1 < $4) }' && ok || bad "no limit streams at both -j 1 and -j 3: needs $need (-j 3), $need1 (-j 1)"
for j in 1 2 3; do
    expect 0 "streamed glossy spectral bake, -j $j" -- "$PRT" $GB -j $j -o gs$j.prt $GP --no-checkpoint --memory-limit "$mid"
    says "stream through a scratch file"
    "$SAME" gsplain.prt gs$j.prt && ok || bad "a streamed glossy spectral bake at -j $j differs from the plain one"
done
expect 0 "spectral shard 1/2" -- "$PRT" $GB -j 2 -o gs1.shard $GP --shard 1/2
expect 0 "streamed spectral shard 2/2" -- "$PRT" $GB -j 2 -o gs2.shard $GP --shard 2/2 --memory-limit "$mid"
expect 0 "merge of a plain and a streamed shard" -- "$PRT" merge gs1.shard gs2.shard -o gsmerged.prt
"$SAME" gsplain.prt gsmerged.prt && ok || bad "a streamed spectral shard merged differs from the plain bake"
cp gs1.shard gsresumed.prt.checkpoint
expect 0 "streamed spectral bake resumed from a plain shard" -- "$PRT" $GB -j 2 -o gsresumed.prt $GP --resume --memory-limit "$mid"
says "stream through a scratch file"
says "came from"
"$SAME" gsplain.prt gsresumed.prt && ok || bad "a streamed spectral bake resumed from a checkpoint differs from the plain one"
# The light cloud runs the spectral stages: over its limit they stream their rows, same bytes.
LC="--method lightcloud --samples 64 --basis 48 --cloud-grid 2,2,2 --partition 200"
expect 0 "plain light cloud bake" -- "$PRT" $B -o lcplain.prt $LC --no-checkpoint
expect 2 "the light cloud's need" -- "$PRT" $B -o refused.prt $LC --memory-limit 1K
lcneed=$(sed -n 's/.*would need about \([0-9.]*\) MiB even streaming, \([0-9.]*\) MiB without.*/\1 \2/p' err)
[ -n "$lcneed" ] && ok || bad "the light cloud does not say what it needs streaming and without: $(cat err)"
lcmid=$(echo "${lcneed:-0 0}" | awk '{ printf "%dK", ($1 + $2) / 2 * 1024 }')
expect 0 "streamed light cloud bake" -- "$PRT" $B -o lcstreamed.prt $LC --no-checkpoint --memory-limit "$lcmid"
says "stream through a scratch file"
"$SAME" lcplain.prt lcstreamed.prt && ok || bad "a light cloud bake with streamed spectral rows differs from the plain one"

# Under the streamed need: refused up front in one line that says what streaming would need.
low=$(echo "${need:-0 0}" | awk '{ printf "%dK", $1 * 1024 * 0.9 }')
expect 2 "spectral under its streamed need" -- "$PRT" $GB -j 3 -o refused.prt $GP --memory-limit "$low"
says "would need about .* even streaming"
[ "$(grep -c "would need" err)" = 1 ] && ok || bad "the refusal is not one line: $(cat err)"
grep -q "%" err && bad "spectral: progress before the refusal" || ok
[ ! -e refused.prt ] && [ ! -e refused.prt.checkpoint ] && ok || bad "spectral: a refused bake left a file"
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
