# nbt_fog/run.py: the render as an EXR, the nbt-scatter command line for the
# scene, running it, and the result back in Blender.
import json
import os
import shutil
import struct
import subprocess
import tempfile

import bpy

from .params import NbtFogError, camera_parameters, world_medium, volume_link


def find_binary(configured):
    """The nbt-scatter to run: the add-on preference when set, else the one on PATH."""
    if configured:
        path = bpy.path.abspath(configured)
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            raise NbtFogError("nbt-scatter binary '%s' (add-on preferences) is not an executable file" % path)
        return path
    path = shutil.which("nbt-scatter")
    if not path:
        raise NbtFogError("nbt-scatter is not on PATH: install nbt, or set its path in the nbt fog add-on's "
                          "preferences")
    return path


def output_paths(template, frame):
    """(render EXR, fogged EXR) for a frame: the template's last run of '#' becomes the zero-padded frame
    number; '//' is the .blend file's directory (the system's temporary directory for an unsaved file)."""
    if template.startswith("//") and not bpy.data.filepath:
        template = os.path.join(tempfile.gettempdir(), template[2:])
    path = bpy.path.abspath(template)
    end = path.rfind('#')
    if end >= 0:
        start = end
        while start > 0 and path[start - 1] == '#':
            start -= 1
        path = path[:start] + "%0*d" % (end - start + 1, frame) + path[end + 1:]
    if not path.lower().endswith(".exr"):
        raise NbtFogError("output '%s' is not accepted: it must end in .exr" % path)
    return path[:-4] + "_render.exr", path


def _num(x):
    # shortest text that reads back as the same double
    return repr(float(x))


def scatter_command(binary, src, out, cam, med, settings, display_window=None):
    """The nbt-scatter command line for the camera and medium dictionaries of params.py."""
    cmd = [binary, src, "-o", out, "--fov-y", _num(cam['fov_y']),
           "--sigma-t", ",".join(_num(x) for x in med['sigma_t']),
           "--albedo", ",".join(_num(x) for x in med['albedo']),
           "--phase", "hg:g=" + _num(med['g']), "--method", settings.method]
    if display_window is not None:
        cmd += ["--display-window", "%d,%d,%d,%d" % display_window]
    if settings.method == 'path':
        cmd += ["--spp", str(settings.spp)]
    else:
        cmd += ["--extend", _num(settings.extend)]
        if settings.quantize >= 0:
            cmd += ["--quantize", str(settings.quantize)]
    cmd += ["--threads", str(settings.threads)]
    if not settings.preview:
        cmd.append("--no-png")
    return cmd


def run_scatter(cmd):
    """Runs nbt-scatter; its first error line becomes the exception's message."""
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    except OSError as e:
        raise NbtFogError("cannot run %s: %s" % (cmd[0], e))
    if p.returncode != 0:
        lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
        raise NbtFogError("nbt-scatter failed (exit %d): %s" % (p.returncode, lines[-1] if lines else "no message"))
    return p.stderr


def save_render_result(scene, path):
    """Writes Blender's Render Result as a float multilayer EXR (all passes: Combined, Depth, ...)."""
    img = bpy.data.images.get("Render Result")
    if img is None:
        raise NbtFogError("there is no render result: render first (F12), or give an EXR file")
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    s = scene.render.image_settings
    saved = (s.file_format, s.color_depth, s.exr_codec)
    try:
        s.file_format = 'OPEN_EXR_MULTILAYER'
        s.color_depth = '32'
        s.exr_codec = 'ZIP'
        img.save_render(path, scene=scene)
    except RuntimeError as e:
        raise NbtFogError("the render result could not be written to %s (render first): %s" % (path, e))
    finally:
        s.file_format, s.color_depth, s.exr_codec = saved


def exr_display_size(path):
    """(width, height) of an OpenEXR file's display window, from its (first) header: after the magic
    number and version, attributes "name\\0type\\0" int32 size, value, up to an empty name; displayWindow
    is a box2i (xmin, ymin, xmax, ymax). (Blender cannot tell a multilayer EXR's size before it is shown.)"""
    try:
        with open(path, 'rb') as f:
            data = f.read(1 << 20)
    except OSError as e:
        raise NbtFogError("EXR file '%s' cannot be read: %s" % (path, e.strerror))
    if data[:4] != b'\x76\x2f\x31\x01':
        raise NbtFogError("'%s' is not an OpenEXR file" % path)
    pos = 8
    while pos < len(data) and data[pos] != 0:
        end = data.find(b'\0', pos)
        tend = data.find(b'\0', end + 1)
        if end < 0 or tend < 0 or tend + 5 > len(data):
            break
        name, size = data[pos:end], struct.unpack_from('<i', data, tend + 1)[0]
        if name == b'displayWindow' and size == 16 and tend + 5 + 16 <= len(data):
            x0, y0, x1, y1 = struct.unpack_from('<4i', data, tend + 5)
            return x1 - x0 + 1, y1 - y0 + 1
        pos = tend + 5 + size
    raise NbtFogError("EXR file '%s' has no display window in its header" % path)


def check_file_size(path, cam):
    """An EXR file given to Apply must be a render of this scene's frame (the field of view is the frame's)."""
    w, h = exr_display_size(path)
    if (w, h) != (cam['width'], cam['height']):
        raise NbtFogError("EXR file '%s' is %dx%d, the scene's frame %dx%d: give a render made with this scene's "
                          "camera and resolution" % (path, w, h, cam['width'], cam['height']))


def scene_parameters(scene):
    """Camera and medium of the scene (params.py), checked for a render nbt-scatter can use."""
    cam = camera_parameters(scene)
    med = world_medium(scene.world, scene.render.engine)
    return cam, med


def apply(scene, src, out, settings, binary, display_window=None, cam=None, med=None):
    """nbt-scatter on the EXR src for this scene's camera and world volume; records what it passed in
    settings.last_run (JSON) and returns that record."""
    if cam is None or med is None:
        cam, med = scene_parameters(scene)
    os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
    cmd = scatter_command(binary, src, out, cam, med, settings, display_window)
    log = run_scatter(cmd)
    record = {'input': src, 'output': out, 'fov_y': cam['fov_y'], 'width': cam['width'], 'height': cam['height'],
              'sigma_t': med['sigma_t'], 'albedo': med['albedo'], 'g': med['g'],
              'sigma_s': med['sigma_s'], 'sigma_a': med['sigma_a'], 'display_window': display_window,
              'command': cmd, 'warnings': med['warnings'], 'log': log}
    settings.last_run = json.dumps(record)
    return record


def load_result(path, settings, context=None):
    """The fogged EXR as an image (reloaded when it is already loaded), optionally shown in the image
    editors and put in the compositor as an Image node named 'nbt fog'."""
    img = None
    for im in bpy.data.images:
        if im.filepath and bpy.path.abspath(im.filepath) == path:
            img = im
            img.reload()
            break
    if img is None:
        img = bpy.data.images.load(path, check_existing=False)
    if settings.use_compositor:
        scene = settings.id_data
        scene.use_nodes = True
        tree = scene.node_tree
        node = tree.nodes.get("nbt fog")
        if node is None:
            node = tree.nodes.new('CompositorNodeImage')
            node.name = node.label = "nbt fog"
        node.image = img
    if settings.show_in_editor and context is not None and context.screen is not None:
        for area in context.screen.areas:
            if area.type == 'IMAGE_EDITOR':
                area.spaces.active.image = img
    return img


class Overscan:
    """A render larger than the frame by pad pixels on each side with the same pixel angle (the sensor
    scaled with the resolution), the world volume's link muted while it renders; restores everything."""

    def __init__(self, scene, fraction, mute_volume):
        self.scene, self.fraction, self.mute_volume = scene, fraction, mute_volume

    def __enter__(self):
        sc = self.scene
        r, cam = sc.render, sc.camera.data
        w, h = r.resolution_x * r.resolution_percentage // 100, r.resolution_y * r.resolution_percentage // 100
        self.saved_render = (r.resolution_x, r.resolution_y, r.resolution_percentage)
        self.saved_cam = (cam.sensor_fit, cam.sensor_width, cam.sensor_height)
        self.saved_z = [(vl, vl.use_pass_z) for vl in sc.view_layers]
        self.link = volume_link(sc.world, r.engine) if self.mute_volume else None
        self.saved_mute = self.link.is_muted if self.link is not None else None
        px, py = round(self.fraction * w), round(self.fraction * h)
        self.display_window = (px, py, px + w - 1, py + h - 1) if px or py else None
        try:
            for vl in sc.view_layers:
                vl.use_pass_z = True
            if self.link is not None:
                self.link.is_muted = True
            if self.display_window:
                # the fitted side spans the sensor: scale the sensor with that side
                side = 'HORIZONTAL' if (cam.sensor_fit == 'HORIZONTAL' or
                                        (cam.sensor_fit == 'AUTO' and w > h)) else 'VERTICAL'
                size = cam.sensor_height if cam.sensor_fit == 'VERTICAL' else cam.sensor_width
                r.resolution_percentage = 100
                r.resolution_x, r.resolution_y = w + 2 * px, h + 2 * py
                cam.sensor_fit = side
                if side == 'HORIZONTAL':
                    cam.sensor_width = size * (w + 2 * px) / w
                else:
                    cam.sensor_height = size * (h + 2 * py) / h
        except Exception:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc):
        sc = self.scene
        r, cam = sc.render, sc.camera.data
        r.resolution_x, r.resolution_y, r.resolution_percentage = self.saved_render
        cam.sensor_fit, cam.sensor_width, cam.sensor_height = self.saved_cam
        for vl, z in self.saved_z:
            vl.use_pass_z = z
        if self.link is not None:
            self.link.is_muted = self.saved_mute
        return False
