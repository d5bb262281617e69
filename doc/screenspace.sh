#!/bin/sh
# doc/screenspace.sh [WxH] [DTHETA]: reruns bench/bench_scatter.sh into
# doc/screenspace_bench.txt and draws doc/figures/screenspace_error_time.png
# (relative L1 against operator A over time, every method and knob, every
# scene) with gnuplot (Debian: gnuplot-nox). Run from the top of a built tree.
set -eu
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
if [ "${1:-}" != "--plot-only" ]; then
  NBT_SCATTER=./nbt-scatter sh bench/bench_scatter.sh "${1:-160x120}" "${2:-10}" >"$out/bench.txt"
  cp "$out/bench.txt" doc/screenspace_bench.txt
fi
command -v gnuplot >/dev/null || { echo "doc/screenspace.sh: gnuplot not found (apt-get install gnuplot-nox)" >&2; exit 1; }
# one data block per method/knob: time (GPU ms, or wall ms for the CPU references), relative L1 against A
awk '!/^#/ && $4 == "A" && $5 > 0 { t = ($10 == "-") ? 1000 * $9 : $10; k = $2 " " $3; print k "\t" t "\t" $5 }' \
  doc/screenspace_bench.txt | sort -s -k1,2 >"$out/pts.txt"
awk -F'\t' '{ if ($1 != last) { if (NR > 1) print "\n"; print "# " $1; last = $1 } print $2, $3 }' "$out/pts.txt" >"$out/blocks.dat"
titles=$(awk -F'\t' '{ if ($1 != last) { printf "%s%s", (n++ ? "|" : ""), $1; last = $1 } }' "$out/pts.txt")
head=$(head -1 doc/screenspace_bench.txt | sed 's/^# //')
gnuplot <<GP
set terminal pngcairo size 900,560 font ",10" noenhanced
set output "doc/figures/screenspace_error_time.png"
set logscale xy
set xlabel "time per frame, ms (GL methods: GPU time on Mesa llvmpipe; ref-a --quantize: CPU wall time)"
set ylabel "relative L1 of the scattered part vs operator A"
set title "$head" font ",9"
set key outside right font ",8"
set grid
set yrange [1e-5:3]
n = words("$(echo "$titles" | tr ' |' '~ ')")
plot for [i=0:n-1] "$out/blocks.dat" index i using 1:2 with points pt (i % 13) + 1 ps 1.2 title word("$(echo "$titles" | tr ' |' '~ ')", i + 1)
GP
echo "wrote doc/screenspace_bench.txt and doc/figures/screenspace_error_time.png"
