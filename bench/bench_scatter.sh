#!/bin/sh
# bench/bench_scatter.sh [WxH] [DTHETA]: error against time for every
# screen-space method and knob, on nbt-scatter's generated scenes, against
# the exact references run in the same script (operator A; operator B for
# elek too). Prints one row per run: scene, method, knob, relative L1, edge
# band RMS, energy bias, max error, wall time (s) and GPU time (ms, GL
# methods; llvmpipe without a GPU). Run from the top of a built tree.
# The references get --extend 0: the GL methods see only the frame, so A
# and B must too (ref-a's default continues the frame beyond its edge, and
# against that every method read about -17% bias on these scenes).
set -eu
size=${1:-160x120}
dth=${2:-10}
S=${NBT_SCATTER:-./nbt-scatter}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
M="--fov-y 40 --sigma-t 0.15 --albedo 0.9 --dtheta $dth --depth ray --no-png"
gl=0
"$S" --help | grep -q "On GL" && gl=1
echo "# nbt-scatter $size, fov 40, sigma_t 0.15, albedo 0.9, dtheta $dth deg, Z as ray distance; $(nproc) cores"
printf "%-7s %-15s %-10s %-4s %9s %9s %9s %9s %8s %9s\n" "#scene" method knob ref relL1 edge bias max time_s gpu_ms
run() { # scene ref label knob args...
  sc=$1 ref=$2 label=$3 knob=$4; shift 4
  line=$("$S" "$tmp/$sc.exr" -o "$tmp/out.exr" $M "$@" --compare "$tmp/$sc-$ref.exr" 2>"$tmp/log") || {
    echo "# $sc $label $knob failed: $(cat "$tmp/log")"; return 0; }
  t=$(sed -n 's/.*: \([0-9.]*\) s$/\1/p' "$tmp/log" | tail -1)
  g=$(sed -n 's/.*(\([0-9.]*\) ms GPU time).*/\1/p' "$tmp/log" | tail -1)
  set -- $line
  printf "%-7s %-15s %-10s %-4s %9.4f %9.4f %9.4f %9.4f %8.3f %9s\n" "$sc" "$label" "$knob" "$ref" "$2" "$6" "$8" "${10}" \
    "$t" "${g:--}"
}
for sc in plane step layers slant blocks; do
  "$S" scene $sc -o "$tmp/$sc.exr" --size "$size"
  "$S" "$tmp/$sc.exr" -o "$tmp/$sc-A.exr" $M --method ref-a --extend 0 2>"$tmp/logA"
  "$S" "$tmp/$sc.exr" -o "$tmp/$sc-B.exr" $M --method ref-b --extend 0 2>"$tmp/logB"
  printf "%-7s %-15s %-10s %-4s %9s %9s %9s %9s %8.3f %9s\n" "$sc" ref-a "$(grep -q FFT "$tmp/logA" && echo fft || echo brute)" \
    A 0 0 0 0 "$(sed -n 's/.*: \([0-9.]*\) s$/\1/p' "$tmp/logA")" -
  for L in 8 16 32 64; do run $sc A ref-a "quant=$L" --method ref-a --quantize $L --extend 0; done
  [ $gl -eq 1 ] || continue
  for c in 1 2 3 5; do run $sc A shinya "cut=$c" --method shinya --cut $c; done
  run $sc A shinya-literal - --method shinya-literal
  run $sc A naive - --method naive
  for e in 0 0.1 0.5; do run $sc A elek "eps=$e" --method elek --eps $e; run $sc B elek "eps=$e" --method elek --eps $e; done
  if "$S" --help | grep -q " nbt "; then run $sc A nbt - --method nbt; fi
done
