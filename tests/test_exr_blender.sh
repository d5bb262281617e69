#!/bin/sh
# tests/test_exr_blender.sh: EXR files written by nbt_image_write_exr_ex
# (through tests/mkexr) loaded by Blender headless: the compositor's Image node
# shows the view layer and the passes Combined, Alpha, Depth, S, T and
# offscreen, and the S and Combined passes composited out by Blender equal the
# file's values (compared with oiiotool). Skipped, with the reason, where
# blender or oiiotool is not installed.
. "${top_srcdir:-.}/tests/testlib.sh"
MK=$(abspath "${NBT_MKEXR:-./tests/mkexr}")
for t in blender oiiotool; do
  if ! command -v $t >/dev/null 2>&1; then
    echo "SKIP: $t is not installed (Debian packages blender and openimageio-tools)"; exit 77
  fi
done
. "${top_srcdir:-.}/tests/exr_inputs.sh"
cat >"$tmp/load.py" <<'PY'
import bpy, sys
path, out, passname = sys.argv[sys.argv.index('--') + 1:][:3]
img = bpy.data.images.load(path)
sc = bpy.context.scene
sc.use_nodes = True
tree = sc.node_tree
for nd in list(tree.nodes):
    tree.nodes.remove(nd)
n = tree.nodes.new('CompositorNodeImage')
n.image = img
print("NBT type=%s layer=%s" % (img.type, n.layer))
print("NBT passes=" + ",".join("%s:%s" % (o.name, o.type) for o in n.outputs))
c = tree.nodes.new('CompositorNodeComposite')
tree.links.new(n.outputs[passname], c.inputs['Image'])
sc.render.engine = 'CYCLES'
sc.cycles.samples = 1
sc.cycles.device = 'CPU'
sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 32, 24, 100
sc.render.use_compositing = True
sc.render.image_settings.file_format = 'OPEN_EXR'
sc.render.image_settings.color_depth = '32'
sc.render.filepath = out
bpy.ops.render.render(write_still=True)
PY
run_blender() {
  HOME=$tmp blender -b --factory-startup --python "$tmp/load.py" -- "$@" >"$tmp/blog" 2>&1
}
diff_ok() { oiiotool "$@" --diff >"$tmp/diff" 2>&1; grep -q "^PASS" "$tmp/diff"; }

run_blender "$tmp/out_bl.exr" "$tmp/bl_S.exr" S && ok || bad "blender ran: $(tail -5 "$tmp/blog")"
grep -qx "NBT type=MULTILAYER layer=ViewLayer" "$tmp/blog" && ok || bad "blender: multilayer, view layer: $(grep NBT "$tmp/blog")"
grep -qx "NBT passes=Combined:RGBA,Alpha:VALUE,Depth:VALUE,S:RGBA,T:RGBA,offscreen:VALUE" "$tmp/blog" && ok ||
  bad "blender: passes: $(grep NBT "$tmp/blog")"
diff_ok "$tmp/bl_S.exr" --ch R,G,B "$tmp/out_bl.exr" --ch ViewLayer.S.R,ViewLayer.S.G,ViewLayer.S.B --chnames R,G,B && ok ||
  bad "blender: pass S as composited = the file's S: $(cat "$tmp/diff")"
run_blender "$tmp/out_plain.exr" "$tmp/pl_C.exr" Combined && ok || bad "blender ran (plain): $(tail -5 "$tmp/blog")"
grep -qx "NBT passes=Combined:RGBA,Alpha:VALUE,S:RGBA,T:RGBA,offscreen:VALUE" "$tmp/blog" && ok ||
  bad "blender (plain): passes: $(grep NBT "$tmp/blog")"
diff_ok "$tmp/pl_C.exr" --ch R,G,B,A "$tmp/in_plain.exr" --crop 32x24+0+0 && ok ||
  bad "blender (plain): Combined as composited = the input's display window: $(cat "$tmp/diff")"
finish
