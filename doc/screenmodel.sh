#!/bin/sh
# doc/screenmodel.sh: fits the model of the higher scattering orders that
# libnbt ships for nbt-scatter's HG kernels (nbt_screen_model_default) and
# writes it as libnbt/screen_model_hg.h. Run from the top of a built tree:
#     sh doc/screenmodel.sh            (about 30 min on 2 cores)
# The photon counts are deterministic for the seed and any thread count, so
# the header is reproducible. The grid: g 0, 0.3, ..., 0.95 (nbt-fit's
# default), albedo 0.2 ... 0.999, optical depth 1/8 ... 16 (deeper walls
# extrapolate: doc/screenspace.md), both geometries, 1e6 photons per g and
# geometry. Check a model off its grid with
#     ./nbt-fit screenmodel --check default --g 0.87 --albedo 0.93 --tau 0.7,3
set -eu
fit=${NBT_FIT:-./nbt-fit}
out=libnbt/screen_model_hg.h
tmp=$(mktemp)
trap 'rm -f "$tmp" "$tmp.h"' EXIT
"$fit" screenmodel -o "$tmp" --tau 0.125,0.25,0.5,1,2,4,8,16 --photons 1e6 --seed 1 --threads 0
{
  echo "/* written by doc/screenmodel.sh from nbt-fit screenmodel: see doc/screenspace.md */"
  sed -e 's/\\/\\\\/g' -e 's/"/\\"/g' -e 's/^/"/' -e 's/$/\\n"/' "$tmp"
} > "$tmp.h"
mv "$tmp.h" "$out"
echo "doc/screenmodel.sh: wrote $out ($(wc -l < "$tmp") lines)"
