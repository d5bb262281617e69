#!/bin/sh
# doc/accuracy.sh [PHOTONS]: reruns the narrow-beam accuracy experiment
# (bench/beam_accuracy) and redraws doc/figures/beam_rms.png with gnuplot
# (Debian: gnuplot-nox). Run from the top of a configured build tree.
set -eu
photons=${1:-2000000}
make -s bench/beam_accuracy
out=$(mktemp -d)
./bench/beam_accuracy "$photons" "$out" | tee doc/beam_rms.txt
gnuplot <<GP
set terminal pngcairo size 1000,420 font ",10"
set output "doc/figures/beam_rms.png"
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
rm -rf "$out"
echo "wrote doc/beam_rms.txt and doc/figures/beam_rms.png"
