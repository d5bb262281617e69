# nbt_fog/params.py: the scene's camera and world volume in nbt-scatter's
# terms. The formulas and where they come from are in doc/blender.md; this
# module only reads properties, so the arithmetic can be checked without a
# render.
import math


class NbtFogError(Exception):
    """A setting nbt-scatter cannot represent, or a failed run; the message
    names the setting and what is accepted."""


# ---- camera ------------------------------------------------------------

def vertical_fov(lens, sensor_width, sensor_height, sensor_fit, width, height,
                 pixel_aspect_x=1.0, pixel_aspect_y=1.0):
    """The vertical angle (radians) of a width x height frame, as Cycles sets
    up its camera (intern/cycles/blender/camera.cpp, blender_camera_viewplane
    and blender_camera_sync): the fitted side spans the sensor size the fit
    names; Auto fits the sensor width to the larger side (horizontal when
    width * pixel_aspect_x > height * pixel_aspect_y)."""
    xr = width * pixel_aspect_x
    yr = height * pixel_aspect_y
    if sensor_fit == 'AUTO':
        horizontal, size = xr > yr, sensor_width
    elif sensor_fit == 'HORIZONTAL':
        horizontal, size = True, sensor_width
    elif sensor_fit == 'VERTICAL':
        horizontal, size = False, sensor_height
    else:
        raise NbtFogError("camera sensor fit '%s' is not accepted: AUTO, HORIZONTAL or VERTICAL" % sensor_fit)
    if horizontal:
        # the sensor spans the width; the height is yr/xr of it
        tan_half = 0.5 * size * yr / (lens * xr)
    else:
        tan_half = 0.5 * size / lens
    return 2.0 * math.atan(tan_half)


def fitted_side(sensor_fit, width, height):
    """'HORIZONTAL' or 'VERTICAL': the side the sensor size spans (square pixels)."""
    if sensor_fit == 'AUTO':
        return 'HORIZONTAL' if width > height else 'VERTICAL'
    return sensor_fit


def frame_size(render):
    """The rendered frame in pixels: resolution scaled by the percentage, as
    Blender does it (integer arithmetic)."""
    return (render.resolution_x * render.resolution_percentage // 100,
            render.resolution_y * render.resolution_percentage // 100)


def camera_parameters(scene):
    """The scene camera as nbt-scatter needs it: {'fov_y': degrees, 'width',
    'height', 'sensor_fit', 'lens', 'sensor_width', 'sensor_height'}.
    Raises NbtFogError for what nbt-scatter cannot represent (its optical
    axis is the frame's centre, its pixels are square)."""
    ob = scene.camera
    if ob is None:
        raise NbtFogError("the scene has no camera: nbt-scatter needs the camera's field of view")
    if ob.type != 'CAMERA':
        raise NbtFogError("the scene camera '%s' is a %s object, not a camera" % (ob.name, ob.type))
    cam = ob.data
    if cam.type != 'PERSP':
        raise NbtFogError("camera '%s' is %s: nbt-scatter needs a perspective camera (type PERSP)"
                          % (ob.name, cam.type))
    if cam.shift_x != 0.0 or cam.shift_y != 0.0:
        raise NbtFogError("camera '%s' has lens shift (%g, %g): not supported, nbt-scatter's optical axis is "
                          "the frame's centre (set shift X and Y to 0)" % (ob.name, cam.shift_x, cam.shift_y))
    r = scene.render
    if r.pixel_aspect_x != r.pixel_aspect_y:
        raise NbtFogError("pixel aspect %g:%g is not supported: nbt-scatter needs square pixels (equal X and Y "
                          "aspect)" % (r.pixel_aspect_x, r.pixel_aspect_y))
    if r.use_border:
        raise NbtFogError("render region (border) is on: nbt-scatter needs the whole frame (turn Render Region off)")
    if r.use_multiview:
        raise NbtFogError("stereoscopy (multiview) is on: not supported, render one view")
    w, h = frame_size(r)
    if w < 1 or h < 1:
        raise NbtFogError("the frame is %dx%d pixels: nothing to render" % (w, h))
    fov = vertical_fov(cam.lens, cam.sensor_width, cam.sensor_height, cam.sensor_fit, w, h,
                       r.pixel_aspect_x, r.pixel_aspect_y)
    return {'fov_y': math.degrees(fov), 'width': w, 'height': h, 'sensor_fit': cam.sensor_fit,
            'lens': cam.lens, 'sensor_width': cam.sensor_width, 'sensor_height': cam.sensor_height}


# ---- world volume --------------------------------------------------------

# Cycles drops a Principled Volume whose density (times its mix weight) is at
# most CLOSURE_WEIGHT_CUTOFF (intern/cycles/kernel/svm/types.h).
CLOSURE_WEIGHT_CUTOFF = 1e-5

SUPPORTED_NODES = "Principled Volume, Volume Scatter, Volume Absorption, Add Shader, Mix Shader, Reroute"


def _constant(node, name):
    sock = node.inputs[name]
    if any(not lk.is_muted for lk in sock.links):
        raise NbtFogError("world volume: input '%s' of node '%s' is connected to another node: nbt reads constant "
                          "values only (a homogeneous medium); disconnect it and type the value" % (name, node.name))
    v = sock.default_value
    if hasattr(v, '__len__'):
        return tuple(float(c) for c in v[:3])
    return float(v)


def _source(sock):
    """The node feeding an input socket (through unmuted links), or None."""
    links = [lk for lk in sock.links if not lk.is_muted]
    return links[0].from_node if links else None


def _collect(node, weight, acc, depth=0):
    if depth > 64:
        raise NbtFogError("world volume: the node tree is nested too deeply (a cycle?)")
    if node.mute:
        raise NbtFogError("world volume: node '%s' is muted: not supported (remove it or unmute it)" % node.name)
    kind = node.bl_idname
    if kind == 'NodeReroute':
        src = _source(node.inputs[0])
        if src is not None:
            _collect(src, weight, acc, depth + 1)
        return
    if kind == 'ShaderNodeAddShader':
        for sock in node.inputs[:2]:
            src = _source(sock)
            if src is not None:
                _collect(src, weight, acc, depth + 1)
        return
    if kind == 'ShaderNodeMixShader':
        # svm_node_mix_closure: the factor clamped to [0, 1]; the first shader
        # gets 1 - fac, the second fac
        fac = min(max(_constant(node, 'Fac'), 0.0), 1.0)
        for sock, w in ((node.inputs[1], weight * (1.0 - fac)), (node.inputs[2], weight * fac)):
            src = _source(sock)
            if src is not None and w > 0.0:
                _collect(src, w, acc, depth + 1)
        return
    if kind == 'ShaderNodeVolumePrincipled':
        color = _constant(node, 'Color')
        d = weight * max(_constant(node, 'Density'), 0.0)
        g = _constant(node, 'Anisotropy')
        absorption_color = _constant(node, 'Absorption Color')
        if _constant(node, 'Emission Strength') > 1e-5 or _constant(node, 'Blackbody Intensity') > 1e-3:
            acc['warnings'].append("node '%s': emission is not part of nbt's medium (ignored)" % node.name)
        if min(color) < 0.0:
            raise NbtFogError("world volume: node '%s' has a negative Color %s: scattering must be >= 0"
                              % (node.name, _fmt3(color)))
        if d <= CLOSURE_WEIGHT_CUTOFF:
            return
        # Cycles' svm_node_principled_volume (intern/cycles/kernel/svm/closure.h
        # in blender/blender; Blender 3.4.1 ships it as scripts/addons/cycles/
        # source/kernel/svm/closure.h): an HG closure of weight color * density
        # (the scattering coefficient) and the extinction
        #   (color + max(1 - color, 0) * max(1 - sqrt(absorption_color), 0)) * density,
        # so absorption = max(1 - color, 0) * max(1 - sqrt(max(absorption_color, 0)), 0) * density
        sig_s = tuple(c * d for c in color)
        sig_a = tuple(max(1.0 - c, 0.0) * max(1.0 - math.sqrt(max(a, 0.0)), 0.0) * d
                      for c, a in zip(color, absorption_color))
        _add(acc, node, sig_s, sig_a, g)
        return
    if kind == 'ShaderNodeVolumeScatter':
        # svm_node_closure_volume: weight color * density, scattering and extinction
        color = _constant(node, 'Color')
        d = weight * max(_constant(node, 'Density'), 0.0)
        if min(color) < 0.0:
            raise NbtFogError("world volume: node '%s' has a negative Color %s: scattering must be >= 0"
                              % (node.name, _fmt3(color)))
        _add(acc, node, tuple(c * d for c in color), (0.0, 0.0, 0.0), _constant(node, 'Anisotropy'))
        return
    if kind == 'ShaderNodeVolumeAbsorption':
        # svm_node_closure_volume: weight (1 - color) * density, extinction only
        color = _constant(node, 'Color')
        d = weight * max(_constant(node, 'Density'), 0.0)
        if max(color) > 1.0:
            raise NbtFogError("world volume: node '%s' has Color %s above 1: absorption (1 - color) * density "
                              "would be negative" % (node.name, _fmt3(color)))
        _add(acc, node, (0.0, 0.0, 0.0), tuple((1.0 - c) * d for c in color), None)
        return
    raise NbtFogError("world volume: node '%s' (%s) is not supported: nbt reads %s with constant inputs"
                      % (node.name, node.bl_label or kind, SUPPORTED_NODES))


def cycles_g(g):
    """The phase Cycles uses for anisotropy g (intern/cycles/kernel/closure/
    volume.h): |g| clamped to 1 - 1e-3, isotropic for |g| < 1e-3."""
    g = math.copysign(min(abs(g), 1.0 - 1e-3), g)
    return 0.0 if abs(g) < 1e-3 else g


def _add(acc, node, sig_s, sig_a, g):
    acc['sigma_s'] = [a + b for a, b in zip(acc['sigma_s'], sig_s)]
    acc['sigma_a'] = [a + b for a, b in zip(acc['sigma_a'], sig_a)]
    if g is not None and max(sig_s) > 0.0:
        acc['lobes'].append((cycles_g(g), node.name))


def _fmt3(v):
    return "(%s)" % ", ".join("%g" % x for x in v)


def world_output(world, engine='CYCLES'):
    """The World Output node the render uses: the active one for this
    engine, else the active one for all engines."""
    outs = [n for n in world.node_tree.nodes if n.bl_idname == 'ShaderNodeOutputWorld']
    target = 'EEVEE' if engine.startswith('BLENDER_EEVEE') else 'CYCLES' if engine == 'CYCLES' else None
    for want in (target, 'ALL'):
        for n in outs:
            if n.is_active_output and n.target == want:
                return n
    for n in outs:
        if n.is_active_output:
            return n
    return outs[0] if outs else None


def volume_link(world, engine='CYCLES'):
    """The link into the World Output's Volume input (muted or not), or None."""
    if world is None or not world.use_nodes or world.node_tree is None:
        return None
    out = world_output(world, engine)
    if out is None:
        return None
    links = out.inputs['Volume'].links
    return links[0] if links else None


def world_medium(world, engine='CYCLES'):
    """The world volume as nbt-scatter's medium: {'sigma_t': [R, G, B],
    'albedo': [R, G, B], 'g': g, 'sigma_s', 'sigma_a', 'rendered': whether
    Blender renders the volume too (its link to the World Output is not
    muted), 'warnings': [...]}. A muted link into the World Output's Volume
    input still names the medium (that is how to keep Blender from rendering
    it as well)."""
    if world is None:
        raise NbtFogError("the scene has no world: nbt reads the medium from the world's volume")
    link = volume_link(world, engine)
    if link is None:
        raise NbtFogError("world '%s' has no volume: connect a Principled Volume (or Volume Scatter and Volume "
                          "Absorption) to the World Output's Volume input" % world.name)
    acc = {'sigma_s': [0.0, 0.0, 0.0], 'sigma_a': [0.0, 0.0, 0.0], 'lobes': [], 'warnings': []}
    _collect(link.from_node, 1.0, acc)
    gs = sorted(set(g for g, _ in acc['lobes']))
    if len(gs) > 1:
        raise NbtFogError("world volume: scattering nodes with different anisotropy (%s): nbt-scatter's "
                          "medium has one Henyey-Greenstein lobe; give them the same anisotropy"
                          % ", ".join("%s g=%g" % (name, g) for g, name in acc['lobes']))
    sigma_t = [s + a for s, a in zip(acc['sigma_s'], acc['sigma_a'])]
    for c, st in zip("RGB", sigma_t):
        if not st > 0.0 or not math.isfinite(st):
            raise NbtFogError("world volume: extinction %g in channel %s: nbt-scatter needs a finite extinction "
                              "> 0 in every channel (raise the density)" % (st, c))
    albedo = [min(s / t, 1.0) for s, t in zip(acc['sigma_s'], sigma_t)]
    return {'sigma_t': sigma_t, 'albedo': albedo, 'g': gs[0] if gs else 0.0,
            'sigma_s': acc['sigma_s'], 'sigma_a': acc['sigma_a'], 'rendered': not link.is_muted,
            'warnings': acc['warnings']}
