#!/bin/sh
# doc/kernelmodel.sh: fit the narrow-beam kernel model libnbt ships
# (nbt_beam_fit_default, doc/fit.md "A kernel model over the parameter
# space") and measure it on photon counts it was not fitted to.
#
#   doc/kernelmodel.sh DIR              (run from the build tree; DIR keeps the runs)
#   sh PREFIX/share/nbt/scripts/kernelmodel.sh DIR   (installed: the nbt-fit on PATH)
#
# 1. training runs: sigma_t = 1, Gaussian phase dtheta in {10,20,30,45,60} deg
#    (B = dtheta^2/4), albedo in {0.1,0.3,0.5,0.7,0.9,0.95,0.99}, both
#    geometries (a beam entering a half-space, a source inside the medium),
#    planes z = 0.5..10 (20), r in [0, 1.5 z) in 30 annuli, PHOTONS each, seed 1;
# 2. nbt-fit model on them -> DIR/model.txt, and with UPDATE=1 (run from a
#    build in the source tree) libnbt/beam_fit_data.h (the compiled-in default)
#    and doc/kernelmodel_rms.txt (step 3's table);
# 4. (after 3) layered media: three density profiles (DIR/dens-*.txt), dtheta = 30 deg,
#    albedo 0.5 and 0.9 (half-space) and 0.9 (infinite), nbt-fit model --apply --density:
#    DIR/rms_layers.txt (doc/kernelmodel_layers.txt with UPDATE=1);
# 3. evaluation runs with other seeds, planes z = 1..10, r in [0, z) in 20
#    annuli (the RMS definition of doc/beam_rms.txt): the same dtheta x
#    {0.1,0.5,0.9,0.99} grid (seed 101..), and off-grid (dtheta, albedo)
#    pairs (seed 201..); nbt-fit model --apply writes the relative RMS of
#    2 pi r Psi for the model and the moment kernel, with the counts' own
#    noise floor, to DIR/rms.txt.
#
# Your own phase function: PHASE=SPEC B=B_EFF doc/kernelmodel.sh DIR runs step 1
# for that phase only (any SPEC nbt-fit mc takes; B_EFF is the B the model is
# evaluated with, e.g. its B_mix) and fits a model whose B terms drop out.
# PHOTONS (default 2e6), THREADS (default 1). Runs already in DIR are reused.
set -eu
# the build tree's nbt-fit when run from there, else the installed one
if [ -z "${NBT_FIT:-}" ]; then if [ -x ./nbt-fit ]; then NBT_FIT=./nbt-fit; else NBT_FIT=nbt-fit; fi; fi
DIR=${1:?usage: kernelmodel.sh DIR}
if [ "${UPDATE:-0}" = 1 ] && [ ! -f libnbt/beam_fit_data.h ]; then
    echo "kernelmodel.sh: UPDATE=1 rewrites libnbt/beam_fit_data.h: run it from the top of nbt's source tree" >&2
    exit 2
fi
PHOTONS=${PHOTONS:-2e6}
THREADS=${THREADS:-1}
PHASE=${PHASE:-}
mkdir -p "$DIR"

bof() { awk -v d="$1" 'BEGIN { r = d * 3.14159265358979 / 180; printf "%.6g", r * r / 4 }'; }

# run NAME SEED PLANES BINS F ALBEDO GEOMETRY (phase from $ph)
run() {
    f="$DIR/$1.exr"
    [ -s "$f" ] && return 0
    flag=; [ "$7" = infinite ] && flag=--infinite
    "$NBT_FIT" mc --albedo "$6" --sigma-t 1 $ph --photons "$PHOTONS" --seed "$2" --threads "$THREADS" \
        --z-planes "$3" --r-bins "$4" --r-max-scale "$5" $flag -o "$f.tmp.exr" >/dev/null 2>&1
    mv "$f.tmp.exr" "$f"
}

train=""
if [ -n "$PHASE" ]; then
    : "${B:?PHASE needs B (the B the model is evaluated with)}"
    thetas=user
else
    thetas="10 20 30 45 60"
fi
for g in half infinite; do
    for d in $thetas; do
        if [ "$d" = user ]; then ph="--phase $PHASE"; else ph="--B $(bof "$d")"; fi
        for a in 0.1 0.3 0.5 0.7 0.9 0.95 0.99; do
            run "train-$g-$d-$a" 1 0.5:10:20 30 1.5 "$a" "$g"
            train="$train $DIR/train-$g-$d-$a.exr"
        done
    done
done
extra=; [ -n "$PHASE" ] && extra="--B $B"
# shellcheck disable=SC2086
"$NBT_FIT" model $train $extra -o "$DIR/model.txt" 2>"$DIR/fit.log" || { cat "$DIR/fit.log"; exit 1; }
cat "$DIR/fit.log"
[ -n "$PHASE" ] && exit 0

evals=""
s=101
for g in half infinite; do
    for d in 10 20 30 45 60; do
        ph="--B $(bof "$d")"
        for a in 0.1 0.5 0.9 0.99; do
            run "eval-$g-$d-$a" $s 1:10:10 20 1 "$a" "$g"
            evals="$evals $DIR/eval-$g-$d-$a.exr"
            s=$((s + 1))
        done
    done
done
s=201
for g in half infinite; do
    for p in 12:0.97 15:0.2 25:0.6 35:0.8 40:0.95 50:0.4 55:0.98 58:0.15; do
        d=${p%%:*} a=${p#*:}
        ph="--B $(bof "$d")"
        run "held-$g-$d-$a" $s 1:10:10 20 1 "$a" "$g"
        evals="$evals $DIR/held-$g-$d-$a.exr"
        s=$((s + 1))
    done
done
# shellcheck disable=SC2086
"$NBT_FIT" model --apply "$DIR/model.txt" $evals | sed "s|$DIR/||g" >"$DIR/rms.txt"
cat "$DIR/rms.txt"
# layered media: the model through zeta and the eq. 28/29 moments (nbt_beam_fit_psi)
printf '# dense, then thin\n0 2\n3 0.5\n' >"$DIR/dens-A.txt"
printf '# thin, dense, then 1\n0 0.5\n2 2\n5 1\n' >"$DIR/dens-B.txt"
printf '# a vacuum gap from z = 2 to 4\n0 1\n2 0\n4 1\n' >"$DIR/dens-C.txt"
: >"$DIR/rms_layers.txt"
s=301
for L in A B C; do
    for p in half:0.5 half:0.9 infinite:0.9; do
        g=${p%%:*} a=${p#*:}
        f="$DIR/layer-$L-$g-$a.exr"
        if [ ! -s "$f" ]; then
            flag=; [ "$g" = infinite ] && flag=--infinite
            "$NBT_FIT" mc --albedo "$a" --sigma-t 1 --B "$(bof 30)" --photons "$PHOTONS" --seed $s --threads "$THREADS" \
                --z-planes 1:10:10 --r-bins 20 --density "$DIR/dens-$L.txt" $flag -o "$f.tmp.exr" >/dev/null 2>&1
            mv "$f.tmp.exr" "$f"
        fi
        s=$((s + 1))
    done
    "$NBT_FIT" model --apply "$DIR/model.txt" --density "$DIR/dens-$L.txt" "$DIR"/layer-$L-*.exr | sed "s|$DIR/||g" >>"$DIR/rms_layers.txt"
done
cat "$DIR/rms_layers.txt"
if [ "${UPDATE:-0}" = 1 ]; then
    awk 'BEGIN { print "/* written by doc/kernelmodel.sh from nbt-fit model: see doc/fit.md */" }
         /^(half|infinite) P[0-4] / { g = ($1 == "half") ? 0 : 1; i = substr($2, 2) + 0
             s = "{"; for (k = 3; k <= NF; k++) s = s $k (k < NF ? ", " : ""); c[g, i] = s "}"; have[g] = 1 }
         /^range / { rg[$2] = "{" $3 ", " $4 "}" }
         END { printf "{"; for (g = 0; g < 2; g++) { printf "{"; for (i = 0; i < 5; i++) printf "%s%s", (have[g] ? c[g, i] : "{0}"), (i < 4 ? ",\n  " : ""); printf "}%s", (g < 1 ? ",\n " : "") }
               printf "},\n{%d, %d},\n{%s, %s, %s}\n", have[0] + 0, have[1] + 0, rg["tau"], rg["albedo"], rg["B"] }' "$DIR/model.txt" >libnbt/beam_fit_data.h.tmp
    mv libnbt/beam_fit_data.h.tmp libnbt/beam_fit_data.h
    { echo "# doc/kernelmodel.sh: $PHOTONS photons per run, sigma_t = 1, z = 1..10, r in [0, z) in 20 annuli;"
      echo "# eval-*: the training grid's (dtheta, albedo) with other seeds; held-*: off-grid pairs"
      cat "$DIR/rms.txt"; } >doc/kernelmodel_rms.txt
    { echo "# doc/kernelmodel.sh: layered media, $PHOTONS photons per run, dtheta = 30 deg, z = 1..10, r in [0, z) in 20 annuli;"
      echo "# density A: 2 on [0, 3), 0.5 beyond; B: 0.5 on [0, 2), 2 on [2, 5), 1 beyond; C: 1, vacuum on [2, 4), 1"
      cat "$DIR/rms_layers.txt"; } >doc/kernelmodel_layers.txt
    # the figure: RMS against albedo on the evaluation grid, model (filled) and moment kernel (open), per dtheta
    if command -v gnuplot >/dev/null 2>&1; then
        for g in half infinite; do grep "^$g .*eval-" "$DIR/rms.txt" >"$DIR/$g.dat"; done
        gnuplot <<GP && mv "$DIR/fig.png" doc/figures/kernelmodel_rms.png
set terminal pngcairo size 1300,450 font ",10"
set output "$DIR/fig.png"
set multiplot layout 1,2
set logscale y
set yrange [0.008:0.6]
set xrange [0.05:1.04]
set xlabel "albedo"
set ylabel "relative RMS of 2 pi r Psi vs photon counting"
set key outside right maxrows 11 font ",8"
set grid
do for [g in "half infinite"] {
  set title (g eq "half" ? "beam entering a half-space" : "source inside the medium (--infinite)")
  plot for [i=0:4] "$DIR/".g.".dat" every ::(4*i)::(4*i+3) using 3:5 with linespoints pt 7 lc i+1 title sprintf("model %s deg", word("10 20 30 45 60", i+1)), \\
       for [i=0:4] "$DIR/".g.".dat" every ::(4*i)::(4*i+3) using 3:6 with linespoints pt 6 dt 2 lc i+1 title sprintf("moment %s deg", word("10 20 30 45 60", i+1)), \\
       0.05 with lines lc rgb "black" dt 3 title "5 %"
}
unset multiplot
GP
    fi
fi
