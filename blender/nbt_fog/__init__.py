# nbt fog: Blender add-on that puts a render through nbt-scatter (screen-space
# multiple scattering) with the scene's camera and its world volume as the
# medium. How to install and use it, the conversion formulas and the limits:
# doc/blender.md (installed with nbt).
bl_info = {
    "name": "nbt fog",
    "author": "nbt",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > nbt fog",
    "description": "Multiple scattering in the world volume's medium applied to the render (nbt-scatter)",
    "doc_url": "",
    "category": "Render",
}

import bpy
from bpy.app.handlers import persistent

from . import params, run
from .params import NbtFogError

_busy = False  # set while the add-on itself renders: the post-render handler leaves that render alone


def _prefs(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def _job(context):
    """What both operators start from: the nbt-scatter binary, the scene's camera
    and medium, and the frame's input and output paths (may raise NbtFogError)."""
    scene = context.scene
    prefs = _prefs(context)
    binary = run.find_binary(prefs.binary if prefs else "")
    cam, med = run.scene_parameters(scene)
    src, out = run.output_paths(scene.nbt_fog.output, scene.frame_current)
    return binary, cam, med, src, out


class NBT_AddonPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    binary: bpy.props.StringProperty(
        name="nbt-scatter", subtype='FILE_PATH', default="",
        description="Path of the nbt-scatter program (empty: the one on PATH)")

    def draw(self, context):
        self.layout.prop(self, "binary")


class NBT_FogSettings(bpy.types.PropertyGroup):
    output: bpy.props.StringProperty(
        name="Output", subtype='FILE_PATH', default="//nbt_fog/fog_####.exr",
        description="The fogged EXR ('#' is the frame number); the render goes beside it as NAME_render.exr")
    method: bpy.props.EnumProperty(
        name="Method", default='ref-a',
        items=[('ref-a', "Operator A", "Shinya et al.'s corrected operator, exact on the CPU (default)"),
               ('ref-b', "Operator B", "Elek et al.'s PSF rule, exact on the CPU"),
               ('path', "Path traced", "A path-traced reference of the world the image describes (slow)")])
    quantize: bpy.props.IntProperty(
        name="Depth layers", default=-1, min=-1, max=4096,
        description="--quantize: snap depth to this many layers (fast FFT); -1: nbt-scatter's default (64 for "
                    "continuous depth); 0: exact brute force (slow)")
    extend: bpy.props.FloatProperty(
        name="Extend", default=0.25, min=0.0, max=4.0,
        description="--extend: continue the frame as its mirror image for this fraction of its larger side")
    spp: bpy.props.IntProperty(name="Samples", default=64, min=1, max=1 << 20,
                               description="Path traced: samples per pixel")
    threads: bpy.props.IntProperty(name="Threads", default=0, min=0, max=1024,
                                   description="Worker threads (0: all cores)")
    overscan: bpy.props.FloatProperty(
        name="Overscan", default=0.0, min=0.0, max=1.0,
        description="Render with fog: render this fraction of the width and height more on each side (the "
                    "sensor scaled alike) so that light from outside the frame scatters into it")
    mute_volume: bpy.props.BoolProperty(
        name="Render without the volume", default=True,
        description="Render with fog: mute the world volume's link while Blender renders, so the fog is "
                    "nbt's alone")
    auto_apply: bpy.props.BoolProperty(
        name="Apply after every render", default=False,
        description="Run nbt-scatter on each finished render (render_post handler)")
    preview: bpy.props.BoolProperty(name="PNG preview", default=False,
                                    description="Let nbt-scatter write a tone-mapped PNG beside the EXR")
    load_result: bpy.props.BoolProperty(name="Load result", default=True,
                                        description="Load the fogged EXR as an image")
    show_in_editor: bpy.props.BoolProperty(name="Show in Image Editor", default=True)
    use_compositor: bpy.props.BoolProperty(
        name="Compositor node", default=False,
        description="Put the fogged EXR in the compositor as an Image node named 'nbt fog'")
    last_run: bpy.props.StringProperty(
        name="Last run", default="",
        description="What the last run passed to nbt-scatter (JSON: camera, medium, command line)")


def _finish(context, scene, record, report):
    settings = scene.nbt_fog
    if settings.load_result:
        run.load_result(record['output'], settings, context)
    for w in record['warnings']:
        report({'WARNING'}, "nbt fog: " + w)
    st, al = record['sigma_t'], record['albedo']
    report({'INFO'}, "nbt fog: fov_y %.4g deg, sigma_t %.4g,%.4g,%.4g, albedo %.4g,%.4g,%.4g, g %.4g -> %s"
           % (record['fov_y'], st[0], st[1], st[2], al[0], al[1], al[2], record['g'], record['output']))


class NBT_OT_apply_fog(bpy.types.Operator):
    """Run nbt-scatter on the render result (or an EXR file) with this scene's camera and world volume"""
    bl_idname = "nbt.apply_fog"
    bl_label = "Apply nbt Fog"
    bl_options = {'REGISTER'}

    source: bpy.props.EnumProperty(
        name="Source", default='RENDER',
        items=[('RENDER', "Render Result", "The last render (needs the Z pass)"),
               ('FILE', "EXR file", "A multilayer EXR render with a Depth pass, made with this scene's camera")])
    filepath: bpy.props.StringProperty(name="EXR file", subtype='FILE_PATH', default="")

    def execute(self, context):
        scene = context.scene
        settings = scene.nbt_fog
        try:
            binary, cam, med, src, out = _job(context)
            if self.source == 'FILE':
                if not self.filepath:
                    raise NbtFogError("no EXR file given (source FILE needs filepath)")
                src = bpy.path.abspath(self.filepath)
                run.check_file_size(src, cam)
            else:
                if not any(vl.use_pass_z for vl in scene.view_layers if vl.use):
                    raise NbtFogError("the view layer has no Z pass: enable View Layer > Passes > Z and render "
                                      "again (or use Render with nbt Fog)")
                run.save_render_result(scene, src)
            record = run.apply(scene, src, out, settings, binary, cam=cam, med=med)
        except NbtFogError as e:
            self.report({'ERROR'}, str(e))
            return {'CANCELLED'}
        if med['rendered'] and self.source == 'RENDER':
            record['warnings'].append("the world volume is connected: Blender rendered it too (mute its link "
                                      "or use Render with nbt Fog)")
        _finish(context, scene, record, self.report)
        return {'FINISHED'}


class NBT_OT_render_fog(bpy.types.Operator):
    """Render the frame (without the world volume, with overscan when set) and apply nbt-scatter to it"""
    bl_idname = "nbt.render_fog"
    bl_label = "Render with nbt Fog"
    bl_options = {'REGISTER'}

    def execute(self, context):
        global _busy
        scene = context.scene
        settings = scene.nbt_fog
        try:
            binary, cam, med, src, out = _job(context)
            _busy = True
            try:
                with run.Overscan(scene, settings.overscan, settings.mute_volume) as ov:
                    bpy.ops.render.render()
                    run.save_render_result(scene, src)
                    window = ov.display_window
            except RuntimeError as e:  # the render itself failed (Blender's message)
                raise NbtFogError("the render failed: %s" % e)
            finally:
                _busy = False
            record = run.apply(scene, src, out, settings, binary, display_window=window, cam=cam, med=med)
        except NbtFogError as e:
            self.report({'ERROR'}, str(e))
            return {'CANCELLED'}
        if med['rendered'] and not settings.mute_volume:
            record['warnings'].append("the world volume was rendered by Blender too (Render without the volume "
                                      "is off)")
        _finish(context, scene, record, self.report)
        return {'FINISHED'}


def _print_report(kind, msg):
    print("%s: %s" % (next(iter(kind)), msg))


@persistent
def _render_post(scene, *args):
    settings = getattr(scene, "nbt_fog", None)
    if _busy or settings is None or not settings.auto_apply:
        return
    try:
        prefs = _prefs(bpy.context)
        binary = run.find_binary(prefs.binary if prefs else "")
        cam, med = run.scene_parameters(scene)
        src, out = run.output_paths(settings.output, scene.frame_current)
        run.save_render_result(scene, src)
        record = run.apply(scene, src, out, settings, binary, cam=cam, med=med)
    except NbtFogError as e:
        print("nbt fog: ERROR: %s" % e)
        return
    if med['rendered']:
        record['warnings'].append("the world volume is connected: Blender rendered it too (mute its link)")
    if bpy.app.background:
        _finish(None, scene, record, _print_report)
    else:
        # the render job's thread: load the image on the main thread
        def later():
            _finish(bpy.context, scene, record, _print_report)
            return None
        bpy.app.timers.register(later, first_interval=0.0)


class NBT_PT_fog(bpy.types.Panel):
    bl_label = "nbt fog"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        s = scene.nbt_fog
        row = layout.row(align=True)
        row.operator(NBT_OT_render_fog.bl_idname, icon='RENDER_STILL')
        row.operator(NBT_OT_apply_fog.bl_idname, icon='IMAGE_DATA').source = 'RENDER'
        layout.prop(s, "output")
        col = layout.column()
        col.prop(s, "method")
        if s.method == 'path':
            col.prop(s, "spp")
        else:
            col.prop(s, "quantize")
            col.prop(s, "extend")
        col.prop(s, "threads")
        col.prop(s, "overscan")
        col.prop(s, "mute_volume")
        col.prop(s, "auto_apply")
        col.prop(s, "preview")
        col.prop(s, "load_result")
        col.prop(s, "show_in_editor")
        col.prop(s, "use_compositor")
        box = layout.box()
        try:
            cam, med = run.scene_parameters(scene)
            box.label(text="fov_y %.4g deg (%dx%d, fit %s)" % (cam['fov_y'], cam['width'], cam['height'],
                                                                 cam['sensor_fit']))
            box.label(text="sigma_t %.4g, %.4g, %.4g" % tuple(med['sigma_t']))
            box.label(text="albedo %.4g, %.4g, %.4g   g %.4g" % (tuple(med['albedo']) + (med['g'],)))
            for w in med['warnings']:
                box.label(text=w, icon='INFO')
        except NbtFogError as e:
            box.label(text=str(e), icon='ERROR')


_classes = (NBT_AddonPreferences, NBT_FogSettings, NBT_OT_apply_fog, NBT_OT_render_fog, NBT_PT_fog)


def register():
    for c in _classes:
        bpy.utils.register_class(c)
    bpy.types.Scene.nbt_fog = bpy.props.PointerProperty(type=NBT_FogSettings)
    if _render_post not in bpy.app.handlers.render_post:
        bpy.app.handlers.render_post.append(_render_post)


def unregister():
    if _render_post in bpy.app.handlers.render_post:
        bpy.app.handlers.render_post.remove(_render_post)
    del bpy.types.Scene.nbt_fog
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
