#!/bin/sh
# tests/test_exr_oiio.sh: EXR files written by nbt_image_write_exr_ex (through
# tests/mkexr) as OpenImageIO sees them: the layers listed by
# `oiiotool --info -v`, the display window cropped out of an overscanned
# input, the input's attributes beside nbt's, and pixel values compared by
# oiiotool with the input cropped by oiiotool itself.
. "${top_srcdir:-.}/tests/testlib.sh"
MK=$(abspath "${NBT_MKEXR:-./tests/mkexr}")
if ! command -v oiiotool >/dev/null 2>&1; then
  echo "SKIP: oiiotool is not installed (Debian package openimageio-tools)"; exit 77
fi
. "${top_srcdir:-.}/tests/exr_inputs.sh"

oiiotool --info -v "$tmp/out_plain.exr" >"$tmp/info" 2>&1
want="channel list: R (float), G (float), B (float), A (half), S.R (float), S.G (float), S.B (float), T.R (float), T.G (float), T.B (float), offscreen.X (float)"
grep -qF "$want" "$tmp/info" && ok || bad "plain: layers listed: $(grep 'channel list' "$tmp/info")"
grep -q ": *32 x *24, 11 channel" "$tmp/info" && ok || bad "plain: 32 x 24 display window written: $(head -2 "$tmp/info")"
grep -q "pixel data origin\|full/display" "$tmp/info" && bad "plain: data window = display window at (0, 0)" || ok
grep -qF 'Copyright: "nbt tools test"' "$tmp/info" && grep -qF "test.fov: 0.6789" "$tmp/info" &&
  grep -qF "worldToCamera: 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2, 3, 4, 1" "$tmp/info" &&
  grep -qF 'nbt.method: "layers"' "$tmp/info" && ok || bad "plain: input attributes and nbt.method: $(cat "$tmp/info")"

oiiotool --info -v "$tmp/out_bl.exr" >"$tmp/info" 2>&1
want="channel list: ViewLayer.Combined.R, ViewLayer.Combined.G, ViewLayer.Combined.B, ViewLayer.Combined.A, ViewLayer.Depth.Z, ViewLayer.S.R, ViewLayer.S.G, ViewLayer.S.B, ViewLayer.T.R, ViewLayer.T.G, ViewLayer.T.B, ViewLayer.offscreen.X"
grep -qF "$want" "$tmp/info" && ok || bad "blender: layers listed: $(grep 'channel list' "$tmp/info")"
grep -qF 'BlenderMultiChannel: "Blender V2.55.1 and newer"' "$tmp/info" && ok || bad "blender: BlenderMultiChannel kept"

# pixels: the output's RGBA is the input's display window (cropped by oiiotool); S = RGB / 4
diff_ok() { oiiotool "$@" --diff >"$tmp/diff" 2>&1; grep -q "^PASS" "$tmp/diff"; }
diff_ok "$tmp/out_plain.exr" --ch R,G,B,A "$tmp/in_plain.exr" --crop 32x24+0+0 && ok ||
  bad "plain: RGBA = input cropped to the display window: $(cat "$tmp/diff")"
diff_ok "$tmp/out_plain.exr" --ch S.R,S.G,S.B --chnames R,G,B --mulc 4 "$tmp/out_plain.exr" --ch R,G,B && ok ||
  bad "plain: S = RGB / 4: $(cat "$tmp/diff")"
diff_ok "$tmp/out_bl.exr" --ch ViewLayer.Depth.Z "$tmp/in_bl.exr" --crop 32x24+0+0 --ch ViewLayer.Depth.Z && ok ||
  bad "blender: depth = input cropped: $(cat "$tmp/diff")"
# the check can fail: one column off is not the same picture
diff_ok "$tmp/out_plain.exr" --ch R,G,B,A "$tmp/in_plain.exr" --crop 32x24+1+0 --origin +0+0 &&
  bad "plain: a crop shifted by one column compares equal" || ok
finish
