#!/bin/sh
# Million-vertex scenes in bounded memory: Sponza (SHARED_DATA/meshes/sponza, skipped saying so
# when absent) subdivided to about 100k, 300k and 1M vertices (--max-edge), and each method's
#  - up-front estimate: the need a refusal under a 1 KiB limit prints (costs the scene's load only),
#  - bake under --memory-limit LIMIT (default 5G): seconds and peak resident memory (what prt bake
#    prints at the end), or the refusal's line when the estimate is over the limit,
# for the method:size pairs in BAKE (the rest: estimate only). SH is also baked twice more at STREAM_SIZE
# with 256 directions (so that its ray hits dominate): with no limit, and with STREAM_LIMIT (under
# its estimate), when it streams its hits: the peak before and after; spectral likewise at
# SPECTRAL_STREAM_SIZE with SPECTRAL_STREAM_LIMIT, when it streams its transfer rows. Low sample counts throughout (OPTS_<method> below): this measures memory, not quality.
# Writes OUTDIR/memory.csv, OUTDIR/memory.md (a table) and, with gnuplot, OUTDIR/memory.png
# (PLOT_ONLY=1: only the table and plot, from an OUTDIR/memory.csv already there).
# Usage: bench/memory_scale.sh PATH/TO/prt OUTDIR [SHARED_DATA]
#   SIZES="100k:0.85 300k:0.49 1M:0.243" (label:max-edge), METHODS, BAKE="sh:100k ao:1M ...",
#   LIMIT=5G, STREAM_SIZE (default 300k) and STREAM_LIMIT (default 400M: under SH's estimate
#   there), SPECTRAL_STREAM_SIZE (default 300k) and SPECTRAL_STREAM_LIMIT (default 600M: between
#   spectral's streamed and plain estimates there), THREADS (default 2).
set -eu
PRT=$1
OUT=$2
DATA=${3:-../shared/data}
SCENE=$DATA/meshes/sponza/sponza_dabrovic.obj
if [ ! -f "$SCENE" ]; then echo "memory_scale: $SCENE is absent: skipped"; exit 0; fi
SIZES=${SIZES:-100k:0.85 300k:0.49 1M:0.243}
METHODS=${METHODS:-sh wavelet spectral lightcloud offset ao}
BAKE=${BAKE:-sh:100k sh:300k sh:1M ao:100k ao:300k ao:1M offset:100k spectral:100k}
LIMIT=${LIMIT:-5G}
STREAM_LIMIT=${STREAM_LIMIT:-400M}
STREAM_SIZE=${STREAM_SIZE:-300k}
SPECTRAL_STREAM_LIMIT=${SPECTRAL_STREAM_LIMIT:-600M}
SPECTRAL_STREAM_SIZE=${SPECTRAL_STREAM_SIZE:-300k}
THREADS=${THREADS:-2}
OPTS_sh="--order 3 --samples 64 --bounces 2"
OPTS_sh_stream="--order 3 --samples 256 --bounces 2"
OPTS_wavelet="--supersample 1 --terms 2 --brdf-res 16 --bounces 1 --gather-res 8 --coefficients 32"
OPTS_spectral="--samples 256 --basis 256"
OPTS_lightcloud="--samples 256 --basis 256 --cloud-grid 3,3,3 --bounces 4"
OPTS_offset="--offsets 20 --texels 128 --iterations 0"
OPTS_ao="--samples 32"
mkdir -p "$OUT"
CSV=$OUT/memory.csv
[ -n "${PLOT_ONLY:-}" ] && SIZES=""
[ -n "${PLOT_ONLY:-}" ] || echo "method,size,vertices,estimate_mib,limit,result,seconds,peak_mib" >"$CSV"
mib() { awk -v x="$1" -v u="$2" 'BEGIN { f = u == "GiB" ? 1024 : u == "KiB" ? 1 / 1024 : u == "bytes" ? 1 / 1048576 : 1; printf "%.0f", x * f }'; }

for size in $SIZES; do
    label=${size%%:*}
    edge=${size#*:}
    for m in $METHODS; do
        eval "opts=\$OPTS_$m"
        # The estimate: refused under 1 KiB, the line says what the bake would need.
        log=$OUT/$m-$label.estimate.log
        "$PRT" bake "$SCENE" --max-edge "$edge" --no-refine -j "$THREADS" --method "$m" $opts -o "$OUT/x.prt" --memory-limit 1K >"$log" 2>&1 || true
        nv=$(sed -n 's/.*: \([0-9]*\) vertices, .*/\1/p' "$log" | head -1)
        need=$(sed -n 's/.*even streaming, \([0-9.]*\) \([KMG]iB\|bytes\) without.*/\1 \2/p' "$log" | head -1)
        [ -n "$need" ] || need=$(sed -n 's/.*would need about \([0-9.]*\) \([KMG]iB\|bytes\).*/\1 \2/p' "$log" | head -1)
        est=$(mib ${need:-0 MiB})
        case " $BAKE " in *" $m:$label "*) ;; *) echo "$m,$label,$nv,$est,,estimate only,," >>"$CSV"; continue ;; esac
        run() {   # LIMIT TAG NAME
            blog=$OUT/$m-$label-$2.log
            start=$(date +%s)
            if "$PRT" bake "$SCENE" --max-edge "$edge" --no-refine -j "$THREADS" --method "$m" $opts -o "$OUT/$m-$label.prt" --no-checkpoint \
                --memory-limit "$1" >"$blog" 2>&1; then
                secs=$(($(date +%s) - start))
                peak=$(sed -n 's/.*peak resident memory \([0-9.]*\) \([KMG]iB\).*/\1 \2/p' "$blog" | head -1)
                result=baked
                if grep -q "stream through a scratch file" "$blog"; then
                    if [ "$m" = spectral ]; then result="baked; rows streamed"; else result="baked; hits streamed"; fi
                fi
                e=$(sed -n "s/.*the bake's estimate is \([0-9.]*\) \([KMG]iB\).*/\1 \2/p" "$blog" | head -1)
                echo "$3,$label,$nv,$(mib ${e:-0 MiB}),$1,$result,$secs,$(mib $peak)" >>"$CSV"
            elif grep -q "would need" "$blog"; then
                echo "$3,$label,$nv,$est,$1,refused up front,," >>"$CSV"
            else
                echo "$3,$label,$nv,$est,$1,failed (see $blog),," >>"$CSV"
            fi
            rm -f "$OUT/$m-$label.prt"
        }
        run "$LIMIT" limit "$m"
        if [ "$m" = sh ] && [ "$label" = "$STREAM_SIZE" ]; then   # before and after: more samples, so that the hits dominate
            opts=$OPTS_sh_stream
            run none plain "sh 256 directions"
            run "$STREAM_LIMIT" stream "sh 256 directions"
        fi
        if [ "$m" = spectral ] && [ "$label" = "$SPECTRAL_STREAM_SIZE" ]; then   # its rows: plain, then streamed
            run none plain "spectral"
            run "$SPECTRAL_STREAM_LIMIT" stream "spectral"
        fi
    done
done

{
    echo "| method | scene | vertices | estimate (MiB) | --memory-limit | result | seconds | peak resident (MiB) |"
    echo "| --- | --- | ---: | ---: | --- | --- | ---: | ---: |"
    tail -n +2 "$CSV" | awk -F, '{ printf "| %s | Sponza %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8 }'
} >"$OUT/memory.md"
cat "$OUT/memory.md"

if command -v gnuplot >/dev/null 2>&1; then
    for m in $METHODS; do awk -F, -v m="$m" '$1 == m { print $3, $4, ($8 == "" ? "NaN" : $8) }' "$CSV" | sort -n >"$OUT/$m.dat"; done
    {
        echo "set terminal pngcairo size 900,560; set output '$OUT/memory.png'"
        echo "set logscale xy; set xrange [8e4:1.5e6]; set xlabel 'vertices (Sponza subdivided)'; set ylabel 'MiB'; set key outside right"
        echo "set title 'Bake memory: up-front estimate (lines) and measured peak (points), --memory-limit $LIMIT'"
        printf "plot "
        sep=""
        i=1
        for m in $METHODS; do
            printf "%s'%s/%s.dat' using 1:2 with lines lc %d title '%s estimate', '%s/%s.dat' using 1:3 with points pt 7 lc %d title '%s peak'" \
                "$sep" "$OUT" "$m" "$i" "$m" "$OUT" "$m" "$i" "$m"
            sep=", "
            i=$((i + 1))
        done
        echo
    } | gnuplot && echo "memory_scale: wrote $OUT/memory.png"
fi
