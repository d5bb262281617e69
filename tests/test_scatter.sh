#!/bin/sh
# tests/test_scatter.sh: nbt-scatter end to end: generated scenes, the layered
# FFT against brute force through files, the direct part, --compare, and bad
# input (exit 2, one message naming the problem, nothing written).
. "${top_srcdir:-.}/tests/testlib.sh"
S=$(abspath "${NBT_SCATTER:-./nbt-scatter}")
MK=$(abspath "${NBT_MKEXR:-./tests/mkexr}")
M0="--fov-y 35 --sigma-t 0.15 --albedo 0.9 --dtheta 10"
M="$M0 --method ref-a"   # the exact reference; the default method (nbt on GL builds) is tested below

"$S" --version >"$tmp/v" && grep -q "nbt-scatter (nbt)" "$tmp/v" && ok || bad "--version (exit status 0)"
"$S" --help | grep -q "Usage" && ok || bad "--help"
for s in plane step layers slant blocks; do
  "$S" scene $s -o "$tmp/$s.exr" --size 64x48 && [ -s "$tmp/$s.exr" ] && ok || bad "scene $s"
done
# blocks: ten boxes at six depths over a far wall (doc/screenspace.md), all inside the frame: the frame
# shows 7 distinct depths
[ "$("$MK" "$tmp/blocks.exr" depths)" = 7 ] && ok || bad "scene blocks: 7 depths in the frame, $("$MK" "$tmp/blocks.exr" depths)"

# layered depth (Z read as ray distance): FFT = brute force, both operators.
# --compare sets this run's S (double) against the file's S layer (float): each
# value differs by the float rounding, at most 2^-24 = 5.96e-8 of itself, plus
# the two operators' own difference (~1e-15), so relL1, max and |bias| are
# below 6e-8 (measured: 2.2e-8, 3.7e-8 and 5e-10)
for m in ref-a ref-b; do
  "$S" "$tmp/layers.exr" -o "$tmp/fft-$m.exr" $M --depth ray --method $m --no-png 2>"$tmp/log" || bad "$m fft"
  grep -q "layered FFT" "$tmp/log" && ok || bad "$m: layered scene uses the FFT: $(cat "$tmp/log")"
  words relL1:14 "$S" "$tmp/layers.exr" -o "$tmp/brute-$m.exr" $M --depth ray --method $m --layers 0 --no-png \
    --compare "$tmp/fft-$m.exr" 2>"$tmp/log"; set -- $w
  grep -q "brute force" "$tmp/log" && ok || bad "$m: --layers 0 uses brute force"
  [ "$1" = relL1 ] && [ "${9}" = max ] && awk -v a="$2" -v b="$8" -v m="${10}" \
    'BEGIN { exit !(a < 6e-8 && b < 6e-8 && b > -6e-8 && m < 6e-8) }' && ok ||
    bad "$m: brute force vs layered FFT through files: $*"
done
# operator B is not operator A: they differ by far more than round-off
words relL1:14 "$S" "$tmp/layers.exr" -o "$tmp/x.exr" $M --depth ray --method ref-b --no-png --compare "$tmp/fft-ref-a.exr" 2>/dev/null; set -- $w
awk -v a="$2" 'BEGIN { exit !(a > 0.02) }' && ok || bad "ref-b differs from ref-a: $*"
# planar depth (Blender's Z): a continuous ray distance, brute force; a preview is written
"$S" "$tmp/step.exr" -o "$tmp/step-out.exr" $M 2>"$tmp/log" && [ -s "$tmp/step-out.png" ] && ok || bad "step, planar depth"
grep -q "brute force" "$tmp/log" && ok || bad "planar depth: brute force"
# the off-screen fraction per pixel (layer offscreen.X) is mirror-symmetric: the step scene mirrored left to right
# gives, in its 3 left columns, what the original has in its 3 right columns (same kernels, float round-off;
# the step makes the two sides differ: 0.49 vs 0.42), and the other way round
"$MK" "$tmp/fstep.exr" flip "$tmp/step.exr" && "$S" "$tmp/fstep.exr" -o "$tmp/fstep-out.exr" $M --no-png 2>/dev/null || bad "step mirrored"
words offscreen.X:2 "$MK" "$tmp/step-out.exr" mean offscreen 61 0 64 48; a=$w
words offscreen.X:2 "$MK" "$tmp/fstep-out.exr" mean offscreen 0 0 3 48; b=$w
words offscreen.X:2 "$MK" "$tmp/step-out.exr" mean offscreen 0 0 3 48; c=$w
words offscreen.X:2 "$MK" "$tmp/fstep-out.exr" mean offscreen 61 0 64 48; d=$w
awk -v a="${a#* }" -v b="${b#* }" -v c="${c#* }" -v d="${d#* }" 'BEGIN { exit !(a > 0.3 && c > 0.3 && (a - b) ^ 2 < (1e-6 * a) ^ 2 &&
  (c - d) ^ 2 < (1e-6 * c) ^ 2 && (a - c) ^ 2 > 0.01 ^ 2) }' && ok || bad "offscreen.X mirror-symmetric at the right and left edges: $a $b $c $d"
# the warning's "more overscan would leave": growing the window by 15% and 50% of the width per side can only
# lower each pixel's outside fraction, and 50% (32 px, several kernel widths here) leaves under 1%
sed -n 's/.*on average \([0-9.]*\)%.* would leave \([0-9.]*\)%, 50% would leave \([0-9.]*\)%.*/\1 \2 \3/p' "$tmp/log" >"$tmp/lv"
awk 'NF == 3 { n++; if (!($3 < $2 && $2 < $1 && $3 < 1)) bad = 1 } END { exit bad || n != 1 }' "$tmp/lv" && ok ||
  bad "overscan advice: mean > 15% grown > 50% grown, < 1%: $(cat "$tmp/log")"
# and its "(at most X%)": the largest pixel fraction, a fraction (<= 100%) no smaller than the frame's mean nor the
# mean over the 3 right columns (offscreen.X above, 0.49; printed to 0.1%)
m=$(sed -n 's/.*on average \([0-9.]*\)% of a frame pixel.s kernel (at most \([0-9.]*\)%).*/\1 \2/p' "$tmp/log")
awk -v m="$m" -v a="${a#* }" 'BEGIN { n = split(m, v, " "); exit !(n == 2 && v[2] <= 100 && v[2] + 0.05 >= v[1] && v[2] + 0.05 >= 100 * a) }' &&
  ok || bad "overscan warning's largest fraction (mean, at most: $m) vs the right columns' offscreen.X ${a#* }: $(cat "$tmp/log")"
# the frame is the direct part plus the scattered one, channel by channel: RGB = T.RGB input + S.RGB
# (float round-off; an index or channel slip shows at the step's edge and in the tinted halves)
words composite:2 "$MK" "$tmp/step-out.exr" composite "$tmp/step.exr"; set -- $w
[ "$1" = composite ] && awk -v d="$2" 'BEGIN { exit !(d < 1e-6) }' && ok || bad "frame = T input + S: $*"
# a clear medium (albedo 0, tiny sigma_t) leaves the image as it was, scaled by T
"$S" "$tmp/plane.exr" -o "$tmp/clear.exr" --fov-y 35 --sigma-t 1e-9 --albedo 0 --B 0.01 --depth ray --no-png \
  --method ref-a 2>/dev/null
words relL1:14 "$S" "$tmp/plane.exr" -o "$tmp/y.exr" --fov-y 35 --sigma-t 1e-9 --albedo 0 --B 0.01 --depth ray --no-png --method ref-a \
  --compare "$tmp/clear.exr" 2>/dev/null; set -- $w
[ "$1" = relL1 ] && ok || bad "--compare prints its line: $*"
# colour symmetry: a grey medium treats R, G and B alike, so a lamp (1000 in one channel, near the
# left edge of a 0.5 grey render) scatters the same light into its own channel whichever channel it
# is in. Operators are the same float arithmetic per channel (measured equal to 9 digits), so 1e-6
# for S (mkexr prints 9 digits) and 1e-5 for --compare's halo (printed to 6).
# This holds the mirror continuation's lamp cap (all three channels scaled by cap / (R + G + B)),
# --compare's lamp finder for the halo measure (R + G + B over 30 x the mean), and the header's
# nbt.kernel (the kernel that ran)
for c in 0 1; do
  "$MK" "$tmp/lamp$c.exr" lamp$c &&
    "$S" "$tmp/lamp$c.exr" -o "$tmp/lamp$c-a.exr" $M0 --method ref-a --no-png 2>/dev/null || bad "lamp$c run"
  "$S" "$tmp/lamp$c.exr" -o "$tmp/lamp$c-b.exr" $M0 --method ref-b --no-png --compare "$tmp/lamp$c-a.exr" \
    2>/dev/null >"$tmp/lamp$c.cmp" || bad "lamp$c --compare"
done
# --compare refuses a reference made from another input (nbt.input hashes every channel and the depth):
# the grey frame differs from lamp1 only in one pixel's G
"$MK" "$tmp/grey.exr" grey || bad "grey frame"
expect_usage "compare refuses an input that differs only in G" "nbt.input" "$S" "$tmp/grey.exr" -o "$tmp/x.exr" $M0 \
  --method ref-b --no-png --compare "$tmp/lamp1-a.exr"
words S.R:2 "$MK" "$tmp/lamp0-a.exr" mean S; sr=${w#* }; words S.G:2 "$MK" "$tmp/lamp1-a.exr" mean S; sg=${w#* }
awk -v a="$sr" -v b="$sg" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a > 1 && d <= 1e-6 * a) }' && ok ||
  bad "red lamp's S.R $sr = green lamp's S.G $sg"
fwords relL1:14 "$tmp/lamp0.cmp"; h0=${w##* }; fwords relL1:14 "$tmp/lamp1.cmp"; h1=${w##* }
awk -v a="$h0" -v b="$h1" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a > 0.1 && d <= 1e-5 * a) }' && ok ||
  bad "--compare halo: red lamp $h0 = green lamp $h1"
# the halo measure is left-right symmetric: 4x4 bins from x = 0 tile a 64-wide frame, each lamp's bins
# reach 12 px both ways; the lamps scene and its mirror (mkexr flip) give the same halo (printed to 6 digits: 1e-5)
"$S" scene lamps -o "$tmp/lamps.exr" --size 64x48 2>/dev/null && "$MK" "$tmp/lampsf.exr" flip "$tmp/lamps.exr" || bad "lamps scene"
for f in lamps lampsf; do
  "$S" "$tmp/$f.exr" -o "$tmp/la-$f.exr" $M0 --method ref-a --no-png --extend 0 2>/dev/null
  "$S" "$tmp/$f.exr" -o "$tmp/x.exr" $M0 --method ref-b --no-png --extend 0 --compare "$tmp/la-$f.exr" 2>/dev/null >"$tmp/$f.cmp" ||
    bad "$f --compare"
done
fwords relL1:14 "$tmp/lamps.cmp"; h0=${w##* }; fwords relL1:14 "$tmp/lampsf.cmp"; h1=${w##* }
awk -v a="$h0" -v b="$h1" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a > 0.1 && d <= 1e-5 * a) }' && ok ||
  bad "--compare halo of the lamps scene $h0 = of its mirror $h1"
# and top-bottom symmetric (12 bins of 4 tile the 48 rows): the scene mirrored upside down, the same halo
"$MK" "$tmp/lampsv.exr" vflip "$tmp/lamps.exr" || bad "mkexr vflip"
"$S" "$tmp/lampsv.exr" -o "$tmp/la-lampsv.exr" $M0 --method ref-a --no-png --extend 0 2>/dev/null
words relL1:14 "$S" "$tmp/lampsv.exr" -o "$tmp/x.exr" $M0 --method ref-b --no-png --extend 0 --compare "$tmp/la-lampsv.exr" 2>/dev/null
h2=${w##* }
awk -v a="$h0" -v b="$h2" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a > 0.1 && d <= 1e-5 * a) }' && ok ||
  bad "--compare halo of the lamps scene $h0 = of it upside down $h2"
# --compare's lamps are pixels whose R + G + B exceeds 10 x the frame's mean R + G + B (30 x the mean of all
# RGB values). mkexr halo SUM: grey 0.5 over the top two thirds, 2.0 over the bottom third, one pixel of
# R + G + B = SUM, so the threshold is (190.5 + SUM + 384) / 19.2: SUM 30 lies 5% under it (no lamp: halo 0),
# SUM 33 4% over it, and its 12 px reach then covers every 4x4 bin of the 16x12 frame (halo = binned4, both
# printed to 6 digits). A mean over the top two thirds alone would make SUM > 10.5 a lamp.
for s in 30 33; do
  "$MK" "$tmp/h$s.exr" halo $s && "$S" "$tmp/h$s.exr" -o "$tmp/h$s-a.exr" $M0 --method ref-a --no-png 2>/dev/null ||
    bad "halo scene $s"
  words relL1:14 "$S" "$tmp/h$s.exr" -o "$tmp/x.exr" $M0 --method ref-b --no-png --compare "$tmp/h$s-a.exr" 2>/dev/null
  set -- $w; eval "h$s=\${14}; b$s=\${12}"
done
[ "$h30" = 0 ] && awk -v h="$h33" -v b="$b33" 'BEGIN { d = h - b; if (d < 0) d = -d; exit !(b > 0.01 && d <= 1e-5 * b) }' && ok ||
  bad "--compare's lamp threshold 10 x the frame's mean: halo $h30 at R+G+B = 30 (want 0), $h33 at 33 (want binned4 $b33)"
# the same lamp (SUM 33) in the frame's top row, (5, 0): its 12 px reach covers all 4 x 3 bins again, so
# halo = binned4 (a finder that starts at row 1 sees no lamp: halo 0)
"$MK" "$tmp/h33t.exr" halo 33 0 && "$S" "$tmp/h33t.exr" -o "$tmp/h33t-a.exr" $M0 --method ref-a --no-png 2>/dev/null ||
  bad "halo scene, lamp in row 0"
words relL1:14 "$S" "$tmp/h33t.exr" -o "$tmp/x.exr" $M0 --method ref-b --no-png --compare "$tmp/h33t-a.exr" 2>/dev/null
set -- $w
awk -v h="${14}" -v b="${12}" 'BEGIN { d = h - b; if (d < 0) d = -d; exit !(b > 0.01 && d <= 1e-5 * b) }' && ok ||
  bad "--compare's lamp finder: a lamp in row 0 gives halo ${14}, want binned4 ${12}"
# the mirrored-lamp cap: beyond the frame the border continues as its mirror image, each pixel capped at 4 x the
# median R + G + B of the 8-pixel border band. mkexr capband: a 40x30 frame whose band has median 1 (cap 4) with a
# lamp of 3 and one of 100 on the left edge; capband-ext: the same frame with the continuation written out as
# 10 px of overscan (the lamps' mirror images at 3 and at the cap, 4). --extend 0.25 (10 px) on the first and
# --extend 0 on the second see the same pixels, so S agrees to float rounding (measured 2e-8; 1e-6 allowed;
# a band median read from the wrong pixels, 0.3, caps both lamps at 1.2: 2.7e-3)
"$MK" "$tmp/cb.exr" capband && "$MK" "$tmp/cbx.exr" capband-ext &&
  "$S" "$tmp/cb.exr" -o "$tmp/cb-a.exr" $M0 --method ref-a --depth ray --extend 0.25 --no-png 2>/dev/null || bad "capband run"
words relL1:14 "$S" "$tmp/cbx.exr" -o "$tmp/x.exr" $M0 --method ref-a --depth ray --extend 0 --no-png --compare "$tmp/cb-a.exr" \
  2>/dev/null
set -- $w
awk -v a="$2" -v m="${10}" 'BEGIN { exit !(a <= 1e-6 && m <= 1e-6) }' && ok ||
  bad "mirrored border, lamps capped at 4 x the band's median = the continuation as overscan: $*"
# a reference without S.G falls back to its RGB - T x input for all three channels: the same relL1
# as with its S layer, but for RGB's float rounding (2^-24 of RGB, summed: below 1e-5 here; measured 1e-6)
"$MK" "$tmp/lamp0-noG.exr" rename "$tmp/lamp0-a.exr" S.G X.G || bad "mkexr rename"
words relL1:14 "$S" "$tmp/lamp0.exr" -o "$tmp/x.exr" $M0 --method ref-b --no-png --compare "$tmp/lamp0-noG.exr" 2>/dev/null; set -- $w
r0=$(cut -d' ' -f2 "$tmp/lamp0.cmp")   # lamp0.cmp's layout is checked above
[ "$1" = relL1 ] && awk -v a="$2" -v b="$r0" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(b > 0.1 && d <= 1e-5) }' && ok ||
  bad "--compare, reference without S.G: $* (with S: relL1 $r0)"
# a reference's S layer under a view-layer prefix (ViewLayer.S.R, as Blender writes) is its S layer too:
# the same line as with the bare S.R (mkexr layers: S = 0.25 RGB, not RGB - T x input, so a reference
# read the other way differs: relL1 0.695 against 1.078 here)
"$MK" "$tmp/ref-S.exr" layers "$tmp/lamp0-a.exr" full && "$MK" "$tmp/ref-VS.exr" layers "$tmp/lamp0-a.exr" full ViewLayer ||
  bad "mkexr layers with a prefix"
"$S" "$tmp/lamp0.exr" -o "$tmp/x.exr" $M0 --method ref-b --no-png --compare "$tmp/ref-S.exr" 2>/dev/null >"$tmp/cS" &&
  "$S" "$tmp/lamp0.exr" -o "$tmp/x.exr" $M0 --method ref-b --no-png --compare "$tmp/ref-VS.exr" 2>/dev/null >"$tmp/cVS" &&
  grep -q "^relL1 " "$tmp/cS" && cmp -s "$tmp/cS" "$tmp/cVS" && ok ||
  bad "--compare, S layer as ViewLayer.S: $(cat "$tmp/cVS") vs S: $(cat "$tmp/cS")"
rm -f "$tmp/ref-S.exr" "$tmp/ref-VS.exr" "$tmp/cS" "$tmp/cVS"
LC_ALL=C grep -aq 'nbt\.kernel.string.....moment' "$tmp/lamp0-a.exr" && LC_ALL=C grep -aq 'nbt\.kernel.string.....elek' "$tmp/lamp0-b.exr" &&
  ok || bad "nbt.kernel names the kernel (moment for ref-a, elek for ref-b)"
# the preview's tone map: the median luminance (Rec. 709: 0.2126 R + 0.7152 G + 0.0722 B) goes to
# 0.18, then x / (1 + x) and sRGB. 10 green columns and 6 red ones through a clear medium: the median
# is green's 0.7152, so a green pixel's G and a red pixel's R are both 255 sRGB(v / (1 + v)),
# v = 0.18 / 0.7152 (124); pngcheck's luma is 0.587 G and 0.299 R there (8-bit rounding: 1)
"$MK" "$tmp/gr.exr" greenred && "$S" "$tmp/gr.exr" -o "$tmp/gr-out.exr" --fov-y 35 --sigma-t 1e-9 --albedo 0 --B 0.01 \
  --depth ray --method ref-a 2>/dev/null || bad "green/red run"
words 1 "${NBT_PNGCHECK:-./tests/pngcheck}" --max-luma 3 5 1 1 "$tmp/gr-out.png"; lg=$w
words 1 "${NBT_PNGCHECK:-./tests/pngcheck}" --max-luma 13 5 1 1 "$tmp/gr-out.png"; lr=$w
awk -v g="$lg" -v r="$lr" 'BEGIN { v = 0.18 / 0.7152; v = v / (1 + v); e = 255 * (1.055 * exp(log(v) / 2.4) - 0.055)
  dg = g / 0.587 - e; dr = r / 0.299 - e; exit !(dg * dg <= 1.01 && dr * dr <= 1.01) }' && ok ||
  bad "preview tone map: green pixel luma $lg, red $lr (0.587 and 0.299 x 124 expected)"
# an all-red frame: its median luminance is red's 0.2126, so R = 255 sRGB(v / (1 + v)), v = 0.18 / 0.2126
# (180); a luminance that read R from another pixel's channel gave the median 0 and exposure 1 (188)
"$MK" "$tmp/red.exr" red && "$S" "$tmp/red.exr" -o "$tmp/red-out.exr" --fov-y 35 --sigma-t 1e-9 --albedo 0 --B 0.01 \
  --depth ray --method ref-a 2>/dev/null || bad "all-red run"
words 1 "${NBT_PNGCHECK:-./tests/pngcheck}" --max-luma 7 5 1 1 "$tmp/red-out.png"; lr=$w
awk -v r="$lr" 'BEGIN { v = 0.18 / 0.2126; v = v / (1 + v); e = 255 * (1.055 * exp(log(v) / 2.4) - 0.055)
  dr = r / 0.299 - e; exit !(dr * dr <= 1.01) }' && ok ||
  bad "preview tone map: all-red frame, red pixel luma $lr (0.299 x 180 expected)"
# --display-window X0,Y0,X1,Y1 (inclusive) makes the frame: 12 x 10 of the 16 x 12 render, as its preview shows
"$S" "$tmp/lamp0.exr" -o "$tmp/dw.exr" $M --display-window 2,1,13,10 2>/dev/null &&
  [ "$("${NBT_PNGCHECK:-./tests/pngcheck}" "$tmp/dw.png")" = "12 10" ] && ok || bad "--display-window 2,1,13,10: a 12x10 frame"
# kernels by name, and a correction file for the corrected kernel
for k in moment smallangle single lineint elek; do
  "$S" "$tmp/layers.exr" -o "$tmp/k-$k.exr" $M --depth ray --kernel $k --no-png 2>/dev/null && ok || bad "--kernel $k"
done
printf 'beta 0.1 0 0 0 0 0 0\nalpha -0.05 0 0 0 0 0 0\n' >"$tmp/corr.txt"
"$S" "$tmp/layers.exr" -o "$tmp/k-corr.exr" $M --depth ray --kernel corrected --correction "$tmp/corr.txt" --no-png \
  2>/dev/null && ok || bad "--kernel corrected"

# GL methods (Mesa llvmpipe in CI): shinya approximates operator A closely, the pyramids roughly;
# a build without GL must refuse them clearly
"$S" "$tmp/layers.exr" -o "$tmp/ref.exr" $M --depth ray --no-png --extend 0 2>/dev/null
# Mesa's driver leaks at eglTerminate: no leak report for the GL runs in sanitizer builds
gl() { ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 "$@"; }
if "$S" --help | grep -q "On GL"; then
  words relL1:14 gl "$S" "$tmp/layers.exr" -o "$tmp/gl.exr" $M --depth ray --method shinya --no-png --compare "$tmp/ref.exr" 2>"$tmp/log"; set -- $w
  [ "$1" = relL1 ] && awk -v a="$2" 'BEGIN { exit !(a < 3e-3) }' && ok || bad "GL shinya vs ref-a: $* $(cat "$tmp/log")"
  grep -q "GPU time" "$tmp/log" && ok || bad "GL methods report their GPU time"
  words relL1:14 gl "$S" "$tmp/layers.exr" -o "$tmp/gl.exr" $M0 --depth ray --no-png --compare "$tmp/ref.exr" 2>"$tmp/log"; set -- $w
  grep -q "^nbt-scatter: nbt " "$tmp/log" && [ "$1" = relL1 ] && awk -v a="$2" -v b="$8" 'BEGIN { exit !(a < 0.05 && b < 0.02 && b > -0.02) }' \
    && ok || bad "default method nbt vs ref-a (L1 < 5%, |bias| < 2%): $* $(cat "$tmp/log")"
  # a wide frame (448 x 24: padded to 448, wider than the 372 px where a pyramid level sized for a third of
  # the width instead of a half starts to drop columns): nbt within 5% of ref-a in L1 and bias (measured 1.1%, 0.5%)
  "$S" scene step --size 448x24 -o "$tmp/wide.exr" 2>/dev/null &&
    "$S" "$tmp/wide.exr" -o "$tmp/wide-ref.exr" --fov-y 35 --sigma-t 0.15 --albedo 0.9 --B 0.05 --depth ray --no-png \
      --extend 0 --method ref-a 2>/dev/null || bad "wide frame: scene and ref-a"
  words relL1:14 gl "$S" "$tmp/wide.exr" -o "$tmp/wide-gl.exr" --fov-y 35 --sigma-t 0.15 --albedo 0.9 --B 0.05 --depth ray \
    --no-png --method nbt --compare "$tmp/wide-ref.exr" 2>/dev/null; set -- $w
  [ "$1" = relL1 ] && awk -v a="$2" -v b="$8" 'BEGIN { exit !(a < 0.05 && b < 0.02 && b > -0.02) }' && ok ||
    bad "GL nbt on a 448-wide frame vs ref-a (L1 < 5%, |bias| < 2%): $*"
  # mirror symmetry with a phase (a kernel of many atoms, grouped into bands by each pixel's own depth):
  # the step scene and its left-right mirror give mirrored S, column by column, at the depth edge
  # (x = 31, 32) and both borders; measured equal to 4e-8 (float), 1e-4 allowed
  "$MK" "$tmp/stepf.exr" flip "$tmp/step.exr" || bad "mkexr flip"
  for f in step stepf; do
    gl "$S" "$tmp/$f.exr" -o "$tmp/gp-$f.exr" --fov-y 35 --sigma-t 0.15 --albedo 0.9 --phase hg:g=0.9 --depth ray --no-png \
      --method nbt 2>/dev/null || bad "GL nbt with a phase on $f"
  done
  for c in 0 31 32 63; do
    a=$("$MK" "$tmp/gp-step.exr" mean S $c 0 $((c + 1)) 48 | awk '{ s = s " " $2 } END { print s }')
    b=$("$MK" "$tmp/gp-stepf.exr" mean S $((63 - c)) 0 $((64 - c)) 48 | awk '{ s = s " " $2 } END { print s }')
    echo "$a $b" | awk '{ for (i = 1; i <= 3; i++) { d = $i - $(i + 3); if (d < 0) d = -d; if (!($i > 0 && d <= 1e-4 * $i)) bad = 1 } }
      END { exit bad || NR != 1 || NF != 6 }' && ok || bad "GL nbt, phase: column $c ($a) = mirrored column $((63 - c)) ($b)"
  done
  for m in shinya-literal naive elek; do
    words relL1:14 gl "$S" "$tmp/layers.exr" -o "$tmp/gl-$m.exr" $M --depth ray --method $m --no-png --compare "$tmp/ref.exr" 2>/dev/null; set -- $w
    awk -v a="$2" 'BEGIN { exit !(a > 0.01 && a < 2) }' && ok || bad "GL $m runs and differs from operator A: $*"
  done
  # sky receivers (rows 0-6 of layers: Z = 1e10): A and B let them receive from nearer pixels; elek gathers
  # at the blurred width of the sources around them (within its 12-34% of B elsewhere: a factor 1.5 here),
  # naive has no width to read at and leaves them at 0 (documented)
  "$S" "$tmp/layers.exr" -o "$tmp/refb.exr" $M --depth ray --method ref-b --no-png --extend 0 2>/dev/null
  # (the three channels' sum; nothing when mkexr fails or prints another layout)
  sky() { "$MK" "$1" mean S 0 0 64 7 >"$tmp/sky" && awk '/^S\.[RGB] / && NF == 2 { s += $2; n++ } END { if (n == 3 && NR == 3) print s }' "$tmp/sky"; }
  gl "$S" "$tmp/layers.exr" -o "$tmp/gl-elek.exr" $M --depth ray --method elek --no-png 2>"$tmp/log"
  awk -v a="$(sky "$tmp/gl-elek.exr")" -v b="$(sky "$tmp/refb.exr")" 'BEGIN { exit !(b > 0 && a > b / 1.5 && a < 1.5 * b) }' \
    && ok || bad "GL elek: the sky band receives as in operator B: $(sky "$tmp/gl-elek.exr") vs $(sky "$tmp/refb.exr")"
  grep -q "approximating operator B" "$tmp/log" && ok || bad "elek's status line names operator B: $(cat "$tmp/log")"
  gl "$S" "$tmp/layers.exr" -o "$tmp/gl-naive.exr" $M --depth ray --method naive --no-png 2>"$tmp/log"
  [ "$(sky "$tmp/gl-naive.exr")" = 0 ] && grep -q "sky receives nothing" "$tmp/log" && ok ||
    bad "GL naive leaves the sky at 0 and says so: $(sky "$tmp/gl-naive.exr") $(cat "$tmp/log")"
  expect_usage "GL with lineint" "--kernel lineint" "$S" "$tmp/layers.exr" -o "$tmp/out.exr" $M --method naive --kernel lineint
else
  expect_usage "no GL in this build" "this build has no GL" "$S" "$tmp/layers.exr" -o "$tmp/out.exr" $M --method shinya
fi

# heterogeneous media: a constant density grid reproduces the homogeneous medium (blocks: no sky),
# converging with the march step; the grid must hold the camera
"$MK" "$tmp/c1.raw" grid 1 || bad "mkexr grid"
"$S" "$tmp/blocks.exr" -o "$tmp/hom.exr" $M --layers 0 --no-png --extend 0 2>/dev/null || bad "blocks, homogeneous"
words relL1:14 "$S" "$tmp/blocks.exr" -o "$tmp/het.exr" $M --density "$tmp/c1.raw" --step 0.05 --no-png \
  --compare "$tmp/hom.exr" 2>"$tmp/log"; set -- $w
[ "$1" = relL1 ] && awk -v a="$2" 'BEGIN { exit !(a < 3e-5) }' && ok || bad "constant grid = homogeneous medium: $*"
grep -q "halving the step" "$tmp/log" && ok || bad "the march reports its error estimate"
# the camera rolled 90 degrees (up = +x, view along -z: view x up = (0, -1, 0), non-zero): a constant grid
# looks the same from any roll, so this too is the homogeneous medium to the march's 3e-5
words relL1:14 "$S" "$tmp/blocks.exr" -o "$tmp/het-roll.exr" $M --density "$tmp/c1.raw" --step 0.05 --up 1,0,0 --no-png \
  --compare "$tmp/hom.exr" 2>/dev/null; set -- $w
[ "$1" = relL1 ] && awk -v a="$2" 'BEGIN { exit !(a < 3e-5) }' && ok ||
  bad "constant grid, camera rolled (--up 1,0,0) = homogeneous medium: $*"
rm -f "$tmp/het-roll.exr"
# the per-pixel kernels through a GL method (shinya): the constant grid = the homogeneous medium by the
# same method (measured relL1 6e-6: both float GL; a kernel width read from the neighbour pixel: 9e-3)
if "$S" "$tmp/blocks.exr" -o "$tmp/glhom.exr" $M0 --method shinya --no-png 2>/dev/null; then
  words relL1:14 "$S" "$tmp/blocks.exr" -o "$tmp/glhet.exr" $M0 --method shinya --density "$tmp/c1.raw" --step 0.05 --no-png \
    --compare "$tmp/glhom.exr" 2>/dev/null; set -- $w
  [ "$1" = relL1 ] && awk -v a="$2" 'BEGIN { exit !(a < 1e-4) }' && ok || bad "GL shinya: constant grid = homogeneous medium: $*"
  # and the transmittance layer: the march's T of the constant grid per pixel against exp(-sigma_t D) of the
  # homogeneous run (measured equal to 9 digits; 1e-5 for float rounding), over the frame and in its first
  # 8x8 pixels (pixel 0 is where a T read from the previous pixel would come from outside the array)
  words T.R:2 "$MK" "$tmp/glhom.exr" mean T; th=${w#* }; words T.R:2 "$MK" "$tmp/glhet.exr" mean T; te=${w#* }
  words T.R:2 "$MK" "$tmp/glhom.exr" mean T 0 0 8 8; th8=${w#* }; words T.R:2 "$MK" "$tmp/glhet.exr" mean T 0 0 8 8; te8=${w#* }
  awk -v a="$te" -v b="$th" -v c="$te8" -v d="$th8" 'BEGIN { x = a - b; y = c - d; if (x < 0) x = -x; if (y < 0) y = -y
    exit !(b > 0.1 && d > 0.1 && x <= 1e-5 * b && y <= 1e-5 * d) }' && ok ||
    bad "GL shinya: T of the constant grid $te ($te8 in 8x8) = homogeneous $th ($th8)"
  rm -f "$tmp/glhom.exr" "$tmp/glhet.exr"
fi
words relL1:14 "$S" "$tmp/blocks.exr" -o "$tmp/het2.exr" $M --density "$tmp/c1.raw" --step 0.5 --no-png \
  --compare "$tmp/hom.exr" 2>/dev/null; set -- $w
awk -v a="$2" 'BEGIN { exit !(a > 3e-5 && a < 3e-3) }' && ok || bad "a coarser step is less accurate: $*"
# the same grid as OpenVDB gives the same image (or a clear refusal without OpenVDB)
if "$MK" "$tmp/c1.vdb" grid 1 2>/dev/null; then
  words relL1:14 "$S" "$tmp/blocks.exr" -o "$tmp/het3.exr" $M --density "$tmp/c1.vdb" --step 0.05 --no-png \
    --compare "$tmp/het.exr" 2>/dev/null; set -- $w
  [ "$1" = relL1 ] && awk -v a="$2" 'BEGIN { exit !(a < 1e-6) }' && ok || bad ".vdb grid = raw grid: $*"
  expect_usage "no such vdb grid" "temperature" "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M --density "$tmp/c1.vdb" \
    --grid temperature
else
  : >"$tmp/c1.vdb"
  expect_usage "no OpenVDB in this build" "no OpenVDB" "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M --density "$tmp/c1.vdb"
fi
expect_usage "grid misses the camera" "does not hold the camera" "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M \
  --density "$tmp/c1.raw" --camera 0,0,5
# a box whose x and y ranges differ ([-20,20] x [-10,30] x [-40,1]), the camera looking along -y: the
# far wall (15 away) lies beyond y = -10, and the message gives the box as it is
"$MK" "$tmp/gy.raw" gridy 1 || bad "mkexr gridy"
expect_usage "grid misses the surface" "box \[-20,20\]x\[-10,30\]x\[-40,1\] does not hold the surface seen in pixel" \
  "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M --density "$tmp/gy.raw" --look-at 0,-1,0 --up 0,0,1
expect_usage "grid misses the camera (y)" "box \[-20,20\]x\[-10,30\]x\[-40,1\] does not hold the camera (0,-15,0)" \
  "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M --density "$tmp/gy.raw" --camera 0,-15,0
expect_usage "grid with ref-b" "heterogeneous media use operator A" "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M \
  --density "$tmp/c1.raw" --method ref-b
expect_usage "not a grid" "not an nbt raw grid" "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M --density "$tmp/corr.txt"
expect_usage "bad --camera" "--camera: '1,2'" "$S" "$tmp/blocks.exr" -o "$tmp/out.exr" $M --density "$tmp/c1.raw" \
  --camera 1,2

# bad input: exit 2, one line, nothing written
"$MK" "$tmp/noz.exr" noz && "$MK" "$tmp/nan.exr" nan && "$MK" "$tmp/neg.exr" negative && "$MK" "$tmp/sky.exr" inf || bad mkexr
o="$tmp/out.exr"
expect_usage "no Z channel" "no depth channel Z" "$S" "$tmp/noz.exr" -o "$o" $M
expect_usage "NaN depth" "pixel (3, 5) is nan" "$S" "$tmp/nan.exr" -o "$o" $M
expect_usage "negative depth" "pixel (3, 5) is -2" "$S" "$tmp/neg.exr" -o "$o" $M
"$S" "$tmp/sky.exr" -o "$tmp/sky-out.exr" $M --no-png 2>/dev/null && ok || bad "an inf depth is sky"
expect_usage "unknown method" "--method: 'magic'" "$S" "$tmp/plane.exr" -o "$o" $M --method magic
expect_usage "unknown kernel" "--kernel: 'x'" "$S" "$tmp/plane.exr" -o "$o" $M --kernel x
expect_usage "fov 0" "--fov-y: '0'" "$S" "$tmp/plane.exr" -o "$o" --fov-y 0 --sigma-t 0.1 --albedo 0.9 --B 0.01
expect_usage "fov 180" "--fov-y: '180'" "$S" "$tmp/plane.exr" -o "$o" --fov-y 180 --sigma-t 0.1 --albedo 0.9 --B 0.01
expect_usage "albedo" "--albedo: '1.2'" "$S" "$tmp/plane.exr" -o "$o" --fov-y 30 --sigma-t 0.1 --albedo 1.2 --B 0.01
expect_usage "no phase width" "--phase SPEC (e.g. hg:g=0.9) or --B B" "$S" "$tmp/plane.exr" -o "$o" --fov-y 30 --sigma-t 0.1 --albedo 0.9
expect_usage "both widths" "give one phase width" "$S" "$tmp/plane.exr" -o "$o" $M --B 0.01
expect_usage "missing input" "nonexistent.exr" "$S" "$tmp/nonexistent.exr" -o "$o" $M
expect_usage "not an EXR" "tmp" "$S" "$tmp/corr.txt" -o "$o" $M
expect_usage "compare size" "--compare" "$S" "$tmp/plane.exr" -o "$o" $M --compare "$tmp/noz.exr"
expect_usage "scene name" "scene: 'moon'" "$S" scene moon -o "$o"
"$S" "$tmp/plane.exr" -o "$tmp/nodir/out.exr" $M 2>"$tmp/err"; rc=$?
[ $rc -eq 1 ] && grep -q "No such file" "$tmp/err" && ok || bad "unwritable output: rc $rc, $(cat "$tmp/err")"
[ ! -e "$o" ] && [ ! -e "$tmp/out.png" ] && [ -z "$(ls "$tmp" | grep tmp)" ] && ok || bad "nothing written on bad input"
finish
