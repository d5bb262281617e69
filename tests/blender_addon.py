# tests/blender_addon.py: run by tests/test_blender_addon.sh inside
# "blender -b --factory-startup --python tests/blender_addon.py -- ZIP TMP".
# Installs the nbt fog add-on from its zip, checks the camera and medium it
# reads against the formulas of doc/blender.md written out again here (and the
# field of view against Blender's own camera frame), checks what it refuses,
# then builds a 48x32 scene with a world Principled Volume, renders it with
# Cycles three ways (Render with nbt Fog with overscan, Apply to the render
# result, the post-render handler), applies it to an EXR file, and prints for each run the add-on's
# record and the parameters computed here, for the shell script to run the
# nbt-scatter CLI by hand and compare. Every line the shell reads starts with
# "NBT "; a failed check prints "FAIL: ..." and the script exits 1.
import json
import math
import os
import sys

import bpy

args = sys.argv[sys.argv.index('--') + 1:]
ZIP, TMP = args[0], args[1]
fails = []
checks = 0


def check(cond, what):
    global checks
    checks += 1
    if not cond:
        fails.append(what)
        print("FAIL: " + what)


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


# ---- the add-on from its zip ----
bpy.ops.preferences.addon_install(filepath=ZIP)
bpy.ops.preferences.addon_enable(module='nbt_fog')
check('nbt_fog' in bpy.context.preferences.addons, "the add-on is enabled after installing the zip")
import nbt_fog  # noqa: E402  (installed by addon_install above)
check(os.path.realpath(os.path.dirname(nbt_fog.__file__)).startswith(os.path.realpath(os.environ['HOME'])),
      "the add-on loaded from the user add-on directory the zip went to: %s" % nbt_fog.__file__)
NbtFogError = nbt_fog.params.NbtFogError

# ---- the scene: numbers chosen exactly representable in float32 ----
LENS, SW, SH = 42.5, 30.0, 17.5
W, H = 48, 32
sc = bpy.context.scene
for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob)
cam = bpy.data.cameras.new("Cam")
cam_ob = bpy.data.objects.new("Cam", cam)
sc.collection.objects.link(cam_ob)
sc.camera = cam_ob
cam_ob.location = (0.0, 0.0, 0.0)
cam_ob.rotation_euler = (0.0, 0.0, 0.0)  # looks along -Z, up +Y
cam.lens, cam.sensor_width, cam.sensor_height, cam.sensor_fit = LENS, SW, SH, 'AUTO'
r = sc.render
r.resolution_x, r.resolution_y, r.resolution_percentage = W, H, 100


def fov_formula(fit, w, h):
    """doc/blender.md: the fitted side spans the sensor size the fit names;
    Auto fits the width to the larger side (square pixels)."""
    if fit == 'VERTICAL':
        return 2 * math.atan(SH / (2 * LENS))
    if fit == 'HORIZONTAL' or w > h:
        return 2 * math.atan(SW / (2 * LENS) * h / w)
    return 2 * math.atan(SW / (2 * LENS))


def fov_blender(w, h):
    """Blender's own answer: the camera frame at depth 1 (Camera.view_frame)."""
    r.resolution_x, r.resolution_y = w, h
    fr = cam.view_frame(scene=sc)
    ys = [v.y / -v.z for v in fr]
    return 2 * math.atan((max(ys) - min(ys)) / 2)


# the field of view for every fit, landscape and portrait (a width/height swap
# or the wrong sensor side changes each by 14% to 2.3x)
for fit in ('AUTO', 'HORIZONTAL', 'VERTICAL'):
    for w, h in ((W, H), (H, W)):
        cam.sensor_fit = fit
        ref = fov_formula(fit, w, h)
        bl = fov_blender(w, h)
        r.resolution_x, r.resolution_y = w, h
        got = math.radians(nbt_fog.params.camera_parameters(sc)['fov_y'])
        check(rel(got, ref) < 1e-13, "fov_y %s %dx%d: add-on %.17g, formula %.17g" % (fit, w, h, got, ref))
        check(rel(got, bl) < 1e-6, "fov_y %s %dx%d: add-on %.17g, Blender's camera frame %.17g" % (fit, w, h, got, bl))
# the percentage scales the frame, not the angle
cam.sensor_fit = 'AUTO'
r.resolution_x, r.resolution_y, r.resolution_percentage = W, H, 50
p = nbt_fog.params.camera_parameters(sc)
check((p['width'], p['height']) == (W // 2, H // 2) and rel(math.radians(p['fov_y']), fov_formula('AUTO', W, H)) < 1e-13,
      "50%%: %dx%d, fov_y %.17g" % (p['width'], p['height'], p['fov_y']))
r.resolution_percentage = 100
print("NBT fov_y AUTO 48x32 %.17g deg" % math.degrees(fov_formula('AUTO', W, H)))


def refuses(setup, undo, pattern, what):
    setup()
    try:
        nbt_fog.run.scene_parameters(sc)
        check(False, "%s: accepted" % what)
    except NbtFogError as e:
        check(pattern in str(e), "%s: message '%s' lacks '%s'" % (what, e, pattern))
    finally:
        undo()


# ---- the world volume ----
world = bpy.data.worlds.new("World")
sc.world = world
world.use_nodes = True
nt = world.node_tree
out = next(n for n in nt.nodes if n.bl_idname == 'ShaderNodeOutputWorld')
bg = nt.nodes['Background']
bg.inputs['Color'].default_value = (0.25, 0.375, 0.5, 1.0)
bg.inputs['Strength'].default_value = 1.0


def clear_volume():
    for n in list(nt.nodes):
        if n not in (out, bg):
            nt.nodes.remove(n)


def medium_check(name, sig_s, sig_a, g):
    """The add-on's medium against sigma_t = sigma_s + sigma_a, albedo = sigma_s / sigma_t."""
    m = nbt_fog.params.world_medium(world)
    for c in range(3):
        st = sig_s[c] + sig_a[c]
        check(rel(m['sigma_t'][c], st) < 1e-13, "%s: sigma_t[%d] %.17g, expected %.17g" % (name, c, m['sigma_t'][c], st))
        check(rel(m['albedo'][c], sig_s[c] / st) < 1e-13,
              "%s: albedo[%d] %.17g, expected %.17g" % (name, c, m['albedo'][c], sig_s[c] / st))
    check(m['g'] == g, "%s: g %r, expected %r" % (name, m['g'], g))
    return m


# Volume Scatter + Volume Absorption through an Add Shader: sigma_s = d1 c1, sigma_a = d2 (1 - c2)
clear_volume()
vs = nt.nodes.new('ShaderNodeVolumeScatter')
va = nt.nodes.new('ShaderNodeVolumeAbsorption')
add = nt.nodes.new('ShaderNodeAddShader')
vs.inputs['Color'].default_value = (0.5, 0.75, 0.25, 1.0)
vs.inputs['Density'].default_value = 0.125
vs.inputs['Anisotropy'].default_value = -0.375
va.inputs['Color'].default_value = (0.875, 0.5, 0.625, 1.0)
va.inputs['Density'].default_value = 0.5
nt.links.new(vs.outputs[0], add.inputs[0])
nt.links.new(va.outputs[0], add.inputs[1])
nt.links.new(add.outputs[0], out.inputs['Volume'])
medium_check("scatter+absorption", [0.125 * c for c in (0.5, 0.75, 0.25)],
             [0.5 * (1 - c) for c in (0.875, 0.5, 0.625)], -0.375)
# a Mix Shader weighs its inputs (1 - fac, fac)
mix = nt.nodes.new('ShaderNodeMixShader')
mix.inputs['Fac'].default_value = 0.25
nt.links.new(vs.outputs[0], mix.inputs[1])
nt.links.new(va.outputs[0], mix.inputs[2])
nt.links.new(mix.outputs[0], out.inputs['Volume'])
medium_check("mix 0.25", [0.75 * 0.125 * c for c in (0.5, 0.75, 0.25)],
             [0.25 * 0.5 * (1 - c) for c in (0.875, 0.5, 0.625)], -0.375)
# refused: two lobes of different g, a texture into the density, another node
vs2 = nt.nodes.new('ShaderNodeVolumeScatter')
vs2.inputs['Anisotropy'].default_value = 0.5
nt.links.new(vs.outputs[0], add.inputs[0])
nt.links.new(vs2.outputs[0], add.inputs[1])
nt.links.new(add.outputs[0], out.inputs['Volume'])
refuses(lambda: None, lambda: None, "different anisotropy", "two HG lobes of different g")
tex = nt.nodes.new('ShaderNodeTexNoise')
lk = nt.links.new(tex.outputs['Fac'], vs2.inputs['Density'])
refuses(lambda: None, lambda: None, "'Density'", "a texture into the density")
nt.links.remove(lk)
emi = nt.nodes.new('ShaderNodeEmission')
nt.links.new(emi.outputs[0], add.inputs[1])
refuses(lambda: None, lambda: None, "not supported", "an Emission node")

# the medium of the render: Principled Volume, its absorption colour through
# sqrt (Cycles' svm_node_principled_volume)
D, C, A, G = 0.25, (0.75, 0.5, 0.875), (0.25, 0.5625, 0.0625), 0.625
clear_volume()
pv = nt.nodes.new('ShaderNodeVolumePrincipled')
pv.inputs['Density'].default_value = D
pv.inputs['Color'].default_value = C + (1.0,)
pv.inputs['Absorption Color'].default_value = A + (1.0,)
pv.inputs['Anisotropy'].default_value = G
vol_link = nt.links.new(pv.outputs['Volume'], out.inputs['Volume'])
SIG_S = [D * c for c in C]
SIG_A = [D * max(1 - c, 0) * max(1 - math.sqrt(a), 0) for c, a in zip(C, A)]
SIG_T = [s + a for s, a in zip(SIG_S, SIG_A)]
ALB = [s / t for s, t in zip(SIG_S, SIG_T)]
medium_check("principled", SIG_S, SIG_A, G)

# refused camera settings (the operator too: nothing written)
refuses(lambda: setattr(cam, 'shift_x', 0.125), lambda: setattr(cam, 'shift_x', 0.0), "shift", "lens shift")
refuses(lambda: setattr(r, 'pixel_aspect_x', 2.0), lambda: setattr(r, 'pixel_aspect_x', 1.0), "pixel aspect",
        "non-square pixels")
refuses(lambda: setattr(cam, 'type', 'ORTHO'), lambda: setattr(cam, 'type', 'PERSP'), "perspective",
        "an orthographic camera")

# ---- the render: floor at y = -1, two boxes, a lamp, sky above the horizon ----
bpy.ops.mesh.primitive_plane_add(size=60.0, location=(0.0, -1.0, -20.0), rotation=(math.pi / 2, 0.0, 0.0))
bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-0.8, 0.0, -4.0))
bpy.ops.mesh.primitive_cube_add(size=2.0, location=(1.2, 0.3, -9.0))
lamp = bpy.data.lights.new("Lamp", 'POINT')
lamp.energy = 300.0
lamp_ob = bpy.data.objects.new("Lamp", lamp)
sc.collection.objects.link(lamp_ob)
lamp_ob.location = (0.0, 2.0, -3.0)
sc.render.engine = 'CYCLES'
cy = sc.cycles
cy.device, cy.samples, cy.use_denoising, cy.seed = 'CPU', 4, False, 0
cy.use_adaptive_sampling = False
cy.max_bounces = 2
cy.pixel_filter_type, cy.filter_width = 'BOX', 0.01  # samples at the pixel centres: Z is the centre's depth
sc.view_layers[0].use_pass_z = False  # Render with nbt Fog turns it on for its render

prefs = bpy.context.preferences.addons['nbt_fog'].preferences
check(prefs.binary == "", "the binary preference is empty by default (PATH)")
s = sc.nbt_fog

# the operator refuses a camera nbt-scatter cannot represent, and writes nothing
s.output = os.path.join(TMP, "refused", "fog_####.exr")
cam.shift_y = 0.0625
try:
    bpy.ops.nbt.render_fog()
    check(False, "render_fog with lens shift: finished")
except RuntimeError as e:
    check("shift" in str(e), "render_fog with lens shift: %s" % e)
cam.shift_y = 0.0
check(not os.path.exists(os.path.join(TMP, "refused")), "render_fog with lens shift wrote nothing")


def report(tag, rec, window):
    print("NBT %s record %s" % (tag, json.dumps(rec)))
    print("NBT %s indep fov_y=%r sigma_t=%s albedo=%s g=%r window=%s" % (
        tag, math.degrees(fov_formula('AUTO', W, H)), ",".join(repr(x) for x in SIG_T),
        ",".join(repr(x) for x in ALB), G, "none" if window is None else "%d,%d,%d,%d" % window))
    check(rel(rec['fov_y'], math.degrees(fov_formula('AUTO', W, H))) < 1e-13, "%s: fov_y %r" % (tag, rec['fov_y']))
    for c in range(3):
        check(rel(rec['sigma_t'][c], SIG_T[c]) < 1e-13, "%s: sigma_t[%d] %r vs %r" % (tag, c, rec['sigma_t'][c], SIG_T[c]))
        check(rel(rec['albedo'][c], ALB[c]) < 1e-13, "%s: albedo[%d] %r vs %r" % (tag, c, rec['albedo'][c], ALB[c]))
    check(rec['g'] == G, "%s: g %r" % (tag, rec['g']))
    check((rec['display_window'] and tuple(rec['display_window'])) == window,
          "%s: display window %s, expected %s" % (tag, rec['display_window'], window))
    check(os.path.isfile(rec['output']), "%s: output %s written" % (tag, rec['output']))


# A: Render with nbt Fog, 1/8 overscan (6 and 4 pixels each side), the world volume muted while it renders
s.output = os.path.join(TMP, "a", "fog_####.exr")
s.overscan = 0.125
before = (r.resolution_x, r.resolution_y, cam.sensor_fit, cam.sensor_width, cam.sensor_height,
          sc.view_layers[0].use_pass_z, vol_link.is_muted)
bpy.ops.nbt.render_fog()
rec = json.loads(s.last_run)
report("A", rec, (6, 4, 6 + W - 1, 4 + H - 1))
after = (r.resolution_x, r.resolution_y, cam.sensor_fit, cam.sensor_width, cam.sensor_height,
         sc.view_layers[0].use_pass_z, vol_link.is_muted)
check(after == before, "render_fog restored the scene: %s, was %s" % (after, before))
check(rec['output'] == os.path.join(TMP, "a", "fog_0001.exr"), "A: output name %s" % rec['output'])
img = bpy.data.images.get("fog_0001.exr")
check(img is not None and bpy.path.abspath(img.filepath) == rec['output'], "A: the result is loaded as an image")

# B: Apply to the render result of a plain render (the test mutes the volume itself)
s.output = os.path.join(TMP, "b", "fog_####.exr")
s.overscan = 0.0
sc.view_layers[0].use_pass_z = True
vol_link.is_muted = True
bpy.ops.render.render()
bpy.ops.nbt.apply_fog(source='RENDER')
b_render = json.loads(s.last_run)['input']
report("B", json.loads(s.last_run), None)

# C: the post-render handler, on frame 3, into the compositor
s.output = os.path.join(TMP, "c", "fog_####.exr")
s.auto_apply = True
s.use_compositor = True
sc.frame_set(3)
bpy.ops.render.render()
rec = json.loads(s.last_run)
report("C", rec, None)
check(rec['output'] == os.path.join(TMP, "c", "fog_0003.exr"), "C: output name %s" % rec['output'])
node = sc.node_tree.nodes.get("nbt fog") if sc.node_tree else None
check(node is not None and node.image is not None and bpy.path.abspath(node.image.filepath) == rec['output'],
      "C: the compositor's 'nbt fog' Image node shows the result")

# D: Apply to an EXR file (B's render); a file of another size is refused
s.auto_apply = False
s.output = os.path.join(TMP, "d", "fog_####.exr")
bpy.ops.nbt.apply_fog(source='FILE', filepath=b_render)
rec = json.loads(s.last_run)
check(rec['input'] == b_render, "D: input %s" % rec['input'])
report("D", rec, None)
r.resolution_x = 40
try:
    bpy.ops.nbt.apply_fog(source='FILE', filepath=b_render)
    check(False, "a 48x32 EXR for a 40x32 frame: accepted")
except RuntimeError as e:
    check("48x32" in str(e) and "40x32" in str(e), "a 48x32 EXR for a 40x32 frame: %s" % e)
r.resolution_x = W

print("NBT checks %d failed %d" % (checks, len(fails)))
sys.exit(1 if fails else 0)
