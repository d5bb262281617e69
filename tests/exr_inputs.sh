# tests/exr_inputs.sh (sourced by the EXR tool tests): two overscanned
# renders made by oiiotool, 48 x 36 data windows at (-6, -4) around a 32 x 24
# display window at (0, 0), gradients that differ per channel: in_plain.exr
# (R, G, B, A as half, string/float/matrix attributes) and in_bl.exr (Blender
# multilayer names ViewLayer.Combined.*, ViewLayer.Depth.Z), then
# tests/mkexr's layers S, T and offscreen over the display window of each.
GRAD=fill:topleft=0.1,0.2,0.3,1,5:topright=2,0.5,0.25,0.5,7:bottomleft=0,4,1,0.25,9:bottomright=8,1,0.5,0.75,11
oiiotool --pattern "$GRAD" 48x36 5 --ch 0,1,2,3 --chnames R,G,B,A --origin -6-4 --fullsize 32x24+0+0 \
  --attrib owner "nbt tools test" --attrib:type=float test.fov 0.6789 \
  --attrib:type=matrix worldToCamera 1,0,0,0,0,1,0,0,0,0,1,0,2,3,4,1 -d half -o "$tmp/in_plain.exr" &&
oiiotool --pattern "$GRAD" 48x36 5 \
  --chnames ViewLayer.Combined.R,ViewLayer.Combined.G,ViewLayer.Combined.B,ViewLayer.Combined.A,ViewLayer.Depth.Z \
  --origin -6-4 --fullsize 32x24+0+0 --attrib BlenderMultiChannel "Blender V2.55.1 and newer" -d float \
  -o "$tmp/in_bl.exr" && ok || bad "oiiotool made the inputs"
for k in plain bl; do
  "$MK" "$tmp/out_$k.exr" layers "$tmp/in_$k.exr" crop && ok || bad "mkexr layers $k"
done
