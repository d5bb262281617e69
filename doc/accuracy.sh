#!/bin/sh
# doc/accuracy.sh [PHOTONS]: reruns the narrow-beam accuracy experiment
# (bench/beam_accuracy) and redraws doc/figures/beam_rms.png with gnuplot
# (Debian: gnuplot-nox). Run from the top of a configured build tree.
# The tracked doc/beam_rms.txt and doc/figures/beam_rms.png are replaced only
# when the whole run (experiment and figure) succeeds.
set -eu
photons=${1:-2000000}
if ! command -v gnuplot >/dev/null 2>&1; then
  echo "doc/accuracy.sh: gnuplot is needed to draw the figure (Debian: apt-get install gnuplot-nox); nothing was run or changed" >&2
  exit 1
fi
make -s bench/beam_accuracy
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
./bench/beam_accuracy "$photons" "$out" >"$out/beam_rms.txt"
cat "$out/beam_rms.txt"
gnuplot <<GP
set terminal pngcairo size 1000,420 font ",10"
set output "$out/beam_rms.png"
set multiplot layout 1,2
set logscale y
set yrange [0.002:5]
set xlabel "albedo"
set ylabel "relative RMS of 2 pi r Psi vs photon counting"
set key bottom right font ",8"
set grid
do for [b=0:1] {
  set title sprintf("Gaussian phase, dtheta = %d deg, sigma_t = 1, z = 1..10", b == 0 ? 30 : 60)
  plot "$out/rms.dat" index b using 2:3 with lines dt 2 lc black title "MC std. error", \
       "" index b using 2:4 with linespoints title "moment kernel (eq. 26)", \
       "" index b using 2:5 with linespoints title "kernel, random-walk M2", \
       "" index b using 2:6 with linespoints title "line integral (eq. 16)", \
       "" index b using 2:7 with linespoints title "single scattering", \
       "" index b using 2:8 with linespoints title "Elek W(s)"
}
unset multiplot
GP
[ -s "$out/beam_rms.png" ] || { echo "doc/accuracy.sh: gnuplot wrote no figure; nothing was changed" >&2; exit 1; }
mv "$out/beam_rms.txt" doc/beam_rms.txt
mv "$out/beam_rms.png" doc/figures/beam_rms.png
echo "wrote doc/beam_rms.txt and doc/figures/beam_rms.png"
