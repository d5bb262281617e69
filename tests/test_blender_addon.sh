#!/bin/sh
# tests/test_blender_addon.sh: the Blender add-on (blender/nbt_fog, packaged
# by make as blender/nbt_fog.zip) installed from its zip in Blender headless
# (tests/blender_addon.py builds the scene, renders it three ways and checks
# the camera and medium the add-on reads against doc/blender.md's formulas
# and Blender's own camera frame). Here, for each of the four runs (three
# renders, one EXR file given to Apply): the
# nbt-scatter CLI run by hand on the add-on's input EXR with the parameters
# the test computed itself gives the add-on's output to float round-off; the
# output is fogged (S > 0, T < 1); the render's floor depth matches the field
# of view (Z = 1/tan of each pixel row's angle below the axis, camera 1 above
# the floor), overscan included. Skipped, with the reason, where blender or
# oiiotool is not installed.
. "${top_srcdir:-.}/tests/testlib.sh"
for t in blender oiiotool; do
  if ! command -v $t >/dev/null 2>&1; then
    echo "SKIP: $t is not installed (Debian packages blender and openimageio-tools)"; exit 77
  fi
done
ZIP=$(abspath "${NBT_BLENDER_ZIP:-${top_builddir:-.}/blender/nbt_fog.zip}")
SCATTER=$(abspath "${NBT_SCATTER:-./nbt-scatter}")
[ -f "$ZIP" ] || { echo "FAIL: $ZIP not built (make builds it)"; exit 1; }
# the add-on finds nbt-scatter on PATH (its preference is empty by default)
mkdir -p "$tmp/bin" "$tmp/home" && ln -s "$SCATTER" "$tmp/bin/nbt-scatter"
HOME=$tmp/home PATH=$tmp/bin:$PATH blender -b --factory-startup --python-exit-code 1 \
  --python "${top_srcdir:-.}/tests/blender_addon.py" -- "$ZIP" "$tmp" >"$tmp/blog" 2>&1 && ok ||
  bad "blender with the add-on: $(grep -E 'FAIL|Error|error' "$tmp/blog" | head -20; tail -5 "$tmp/blog")"
grep -E "^(FAIL|NBT checks|NBT fov_y)" "$tmp/blog"
grep -q "^NBT checks [1-9][0-9]* failed 0$" "$tmp/blog" && ok || bad "the Blender-side checks: $(grep '^NBT checks' "$tmp/blog")"

# the largest |a - b| over every channel of two EXRs of the same size and
# channels (oiiotool --diff's report; identical files: only "PASS", 0)
maxdiff() {
  oiiotool "$1" "$2" --diff >"$tmp/diff" 2>&1
  if grep -q "Max error" "$tmp/diff"; then sed -n 's/.*Max error *= *\([0-9.eE+-]*\).*/\1/p' "$tmp/diff" | head -1
  elif grep -qx "PASS" "$tmp/diff"; then echo 0
  fi
}
# the mean over the display window of a channel list (oiiotool --printstats)
mean_of() {
  oiiotool "$1" --ch "$2" --printstats 2>&1 | sed -n 's/.*Stats Avg: *//p' | awk '{ print $1 }'
}

for run in A B C D; do
  rec=$(sed -n "s/^NBT $run record //p" "$tmp/blog")
  ind=$(sed -n "s/^NBT $run indep //p" "$tmp/blog")
  [ -n "$rec" ] && [ -n "$ind" ] || { bad "$run: no record in the Blender log"; continue; }
  field() { printf '%s\n' "$rec" | /usr/bin/python3 -c "import json, sys; print(json.load(sys.stdin)['$1'])"; }
  in=$(field input); out=$(field output)
  eval "$(printf '%s\n' "$ind" | tr ' ' '\n' | sed -n 's/^\([a-z_]*\)=\(.*\)$/i_\1=\2/p')"
  set -- --fov-y "$i_fov_y" --sigma-t "$i_sigma_t" --albedo "$i_albedo" --phase "hg:g=$i_g" --method ref-a \
    --extend 0.25 --threads 0 --no-png
  [ "$i_window" = none ] || set -- "$@" --display-window "$i_window"
  "$SCATTER" "$in" -o "$tmp/cli_$run.exr" "$@" >"$tmp/cli.log" 2>&1 && ok || { bad "$run: CLI by hand: $(tail -2 "$tmp/cli.log")"; continue; }
  d=$(maxdiff "$out" "$tmp/cli_$run.exr")
  # float round-off of values up to ~10: 1e-6 absolute (a 1e-4 change of fov_y moves them by 4e-5)
  echo "$run: add-on vs CLI by hand: max |diff| $d"
  awk -v d="$d" 'BEGIN { exit !(d != "" && d + 0 <= 1e-6) }' && ok || bad "$run: add-on vs CLI by hand: max |diff| '$d'"
  # fogged: scattered light added, transmittance below 1
  s=$(mean_of "$out" ViewLayer.S.R,ViewLayer.S.G,ViewLayer.S.B)
  t=$(mean_of "$out" ViewLayer.T.R)
  echo "$run: mean S $s, mean T.R $t"
  awk -v s="$s" -v t="$t" 'BEGIN { exit !(s + 0 > 1e-4 && t + 0 > 0 && t + 0 < 0.9) }' && ok || bad "$run: not fogged: mean S '$s', mean T.R '$t'"
  # the render's depth against the field of view: pixel row y (EXR, from the
  # top) of a render Hr rows high looks tan = (Hr/2 - y - 0.5) * 2 tan(fov/2) / 32
  # below the axis; the floor 1 below the camera is at planar depth 1/tan.
  # The bottom 6 rows of the frame see only floor. 1e-3: the 0.01 px filter
  # moves a sample by <= 0.005 px, <= 4.8e-4 of the nearest row's 10.5 px off the axis.
  oiiotool "$in" --ch ViewLayer.Depth.Z -o "$tmp/z_$run.exr" >/dev/null 2>&1 && oiiotool --dumpdata "$tmp/z_$run.exr" >"$tmp/z.txt" 2>&1 && ok ||
    { bad "$run: depth of $in"; continue; }
  case $i_window in none) top=0; hr=32 ;; *) top=$(echo "$i_window" | cut -d, -f2); hr=$((32 + 2 * top)) ;; esac
  awk -v fov="$i_fov_y" -v hr="$hr" -v top="$top" '
    /Pixel \(/ { gsub(/[(),:]/, " "); x = $2; y = $3; z = $4
      if (y < top + 26 || y >= top + 32) next
      th = fov * 3.14159265358979324 / 360; t = (y + 0.5 - hr / 2) * 2 * (sin(th) / cos(th)) / 32
      e = z * t - 1; if (e < 0) e = -e; n++; if (e > m) m = e }
    END { printf "%d %.3g\n", n, m; exit !(n == 6 * (hr == 32 ? 48 : 60) && m < 1e-3) }' "$tmp/z.txt" >"$tmp/zcheck" && ok ||
    bad "$run: floor depth vs fov_y $i_fov_y (pixels, worst relative error): $(cat "$tmp/zcheck")"
  echo "$run: floor depth against fov_y (pixels, worst relative error): $(cat "$tmp/zcheck")"
  # the output carries the medium and camera as nbt.* attributes
  oiiotool --info -v "$out" >"$tmp/info" 2>&1
  grep -q "nbt.fov_y" "$tmp/info" && ok || bad "$run: no nbt.fov_y attribute"
done
# the sensitivity of the comparison: a field of view 1e-4 off changes the output by more than the tolerance
set -- --fov-y "$(awk -v f="$i_fov_y" 'BEGIN { printf "%.17g", f * 1.0001 }')" --sigma-t "$i_sigma_t" --albedo "$i_albedo" \
  --phase "hg:g=$i_g" --method ref-a --extend 0.25 --threads 0 --no-png
"$SCATTER" "$in" -o "$tmp/cli_off.exr" "$@" >"$tmp/cli.log" 2>&1 && d=$(maxdiff "$out" "$tmp/cli_off.exr") && echo "fov 1e-4 off: max |diff| $d" &&
  awk -v d="$d" 'BEGIN { exit !(d + 0 > 1e-6) }' && ok || bad "fov 1e-4 off is not seen: max |diff| '$d'"
finish
