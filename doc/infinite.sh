#!/bin/sh
# doc/infinite.sh: the infinite medium (a source inside fog) against the
# half-space beam: relative excess of M0 (all forward crossings of plane z)
# per plane, sigma_t = 1, Gaussian phase dtheta = 30 deg (B = 0.0685) and
# 60 deg (B = 0.274), albedo 0.5 and 0.9. Pairs share a seed (their photon
# streams agree until a photon goes behind the source), so the standard
# error comes from the spread of the per-seed differences over SEEDS seeds.
# Usage: doc/infinite.sh [PHOTONS_PER_SEED] [SEEDS]   (run from the build tree)
NBT_FIT=${NBT_FIT:-./nbt-fit}
N=${1:-1000000}
S=${2:-4}
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT
echo "# relative excess of M0, infinite over half-space, in % (standard error); $S seeds x $N photons per mode"
printf '%-6s %-6s' dtheta albedo
for z in 1 2 3 4 5 6 7 8 9 10; do printf ' %-14s' "z=$z"; done
printf '\n'
for B in 0.0685 0.274; do
  for a in 0.5 0.9; do
    : >"$tmp/all"
    s=1
    while [ "$s" -le "$S" ]; do
      for mode in half inf; do
        flag=; [ "$mode" = inf ] && flag=--infinite
        "$NBT_FIT" mc --albedo "$a" --sigma-t 1 --B "$B" --photons "$N" --z-planes 1:10:10 --r-bins 1 \
          --seed "$s" $flag -o "$tmp/x.csv" 2>/dev/null | awk -v s="$s" -v m="$mode" '{ print s, m, $2, $3 }' >>"$tmp/all"
      done
      s=$((s + 1))
    done
    awk -v B="$B" -v a="$a" -v S="$S" '
      $2 == "half" { h[$1, $3] = $4 } $2 == "inf" { f[$1, $3] = $4 }
      END {
        printf "%-6s %-6s", (B == 0.0685 ? "30" : "60"), a
        for (z = 1; z <= 10; z++) {
          sh = 0; sd = 0; sd2 = 0
          for (s = 1; s <= S; s++) { d = f[s, z] - h[s, z]; sh += h[s, z]; sd += d; sd2 += d * d }
          mh = sh / S; md = sd / S; v = (sd2 / S - md * md) / (S - 1); if (v < 0) v = 0
          printf " %-14s", sprintf("%.4f (%.4f)", 100 * md / mh, 100 * sqrt(v) / mh)
        }
        printf "\n"
      }' "$tmp/all"
  done
done
