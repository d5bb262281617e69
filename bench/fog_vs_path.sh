#!/bin/sh
# bench/fog_vs_path.sh [SPP] [WxH]: nbt-scatter's kernels for a Henyey-Greenstein
# medium against its path-traced reference of the same world (--method path),
# on the generated scenes, camera inside the medium. Per case one path-traced
# reference (SPP samples per pixel, default 256), then in the same script each
# kernel on the CPU (operator A, layered FFT on 64 quantised layers; the
# quantisation itself costs < 1e-4, see doc/screenspace.md) and the baselines:
# Elek et al.'s Gaussian carrying the fitted mass, the first order alone, and
# the Gaussian-phase moment kernel with the width B = (1 - g)/2 that the docs
# once gave. With overscan (column over) the path tracer renders a world 0.6
# of the frame larger on each side and the operators get the render with that
# overscan and continue it (--extend); else both see the render's world alone.
# Columns: 4x4-binned relative L1 of S, energy bias, the binned
# error within 12 px of the lamps, the reference's own binned noise, the
# operator's wall time. Then the cost of an HG kernel against a Gaussian one
# (layered FFT, 640x480). Run from the top of a built tree; takes ~20 min on
# 2 cores at the default SPP.
set -eu
spp=${1:-256}
size=${2:-160x120}
S=${NBT_SCATTER:-./nbt-scatter}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "# nbt-scatter $size, fov 40, walls at Z = 6 (lamps), HG media, camera inside; path reference $spp spp, seed 5;"
echo "# $(nproc) cores; $(date -u +%Y-%m-%d)"
printf "%-7s %5s %5s %5s %4s %-4s %-10s %8s %8s %8s %8s %7s\n" "#scene" g albedo tau over rgb kernel binned4 bias halo \
  ref_noise time_s
# case SCENE G ALBEDO SIGMA_T OVERSCAN RGB
case_() {
  sc=$1 g=$2 a=$3 st=$4 ov=$5 rgb=$6
  in="$tmp/$sc-$ov.exr"
  [ -e "$in" ] || "$S" scene "$sc" --size "$size" --overscan "$ov" -o "$in"
  # the world: the render itself (operators with --extend 0), or with overscan a world larger than the render
  # (0.6 of the frame on each side) and the operators on the overscanned render with their default extension
  world=$in ext="--extend 0"
  if [ "$ov" != 0 ]; then
    world="$tmp/$sc-wide.exr" ext=
    [ -e "$world" ] || "$S" scene "$sc" --size "$size" --overscan 0.6 -o "$world"
  fi
  if [ "$rgb" = rgb ]; then
    med="--sigma-t $st,$(echo "$st" | awk '{ print $1 * 0.7 }'),$(echo "$st" | awk '{ print $1 * 0.4 }') --albedo $a,0.95,0.99"
  else
    med="--sigma-t $st --albedo $a"
  fi
  M="--fov-y 40 $med --no-png --threads 2"
  "$S" "$world" -o "$tmp/ref.exr" $M --phase hg:g=$g --method path --spp "$spp" --seed 5 2>/dev/null
  tau=$(echo "$st" | awk '{ printf "%.2g", $1 * 6 }')
  for k in fitted elek first moment-B; do
    if [ $k = moment-B ]; then
      kk="--B $(echo "$g" | awk '{ print (1 - $1) / 2 }') --kernel moment"
    else
      kk="--phase hg:g=$g --kernel $k"
    fi
    line=$("$S" "$in" -o "$tmp/out.exr" $M $kk $ext --method ref-a --quantize 64 --compare "$tmp/ref.exr" 2>"$tmp/log")
    t=$(sed -n 's/.*: \([0-9.]*\) s$/\1/p' "$tmp/log" | head -1)
    set -- $line
    printf "%-7s %5s %5s %5s %4s %-4s %-10s %8.4f %8.4f %8.4f %8.4f %7.2f\n" "$sc" "$g" "$a" "$tau" "$ov" "$rgb" "$k" \
      "${12}" "$8" "${14}" "${16}" "$t"
  done
}
for g in 0.8 0.9 0.95; do
  for a in 0.9 0.99; do case_ lamps $g $a 0.3 0 grey; done
done
for st in 0.1 0.6; do case_ lamps 0.9 0.95 $st 0 grey; done
for sc in step slant blocks; do case_ $sc 0.9 0.95 0.3 0 grey; done
for g in 0.9 0.95; do case_ lamps $g 0.95 0.3 0.15 grey; done
case_ slant 0.9 0.95 0.3 0.15 grey
case_ lamps 0.9 0.9 0.3 0 rgb

echo "# cost of a kernel: layered FFT on 64 quantised layers, blocks 640x480, 2 threads (operator time, s)"
"$S" scene blocks --size 640x480 -o "$tmp/big.exr"
for r in 1; do
  for k in "--B 0.05 --kernel moment" "--phase hg:g=0.9 --kernel fitted" "--phase hg:g=0.9 --kernel elek"; do
    "$S" "$tmp/big.exr" -o "$tmp/out.exr" --fov-y 40 --sigma-t 0.3 --albedo 0.95 $k --method ref-a --quantize 64 \
      --threads 2 --no-png 2>"$tmp/log"
    echo "run $r: $k: $(sed -n 's/.*: \([0-9.]*\) s$/\1/p' "$tmp/log" | head -1) s"
  done
done
