"""Screen-space multiple scattering on NumPy images (nbt/screen.h, nbt/screen_path.h).

Images are float32 arrays of shape (h, w, 3) (linear RGB) with a distance
(or planar depth for path) array of shape (h, w); the results are float64
arrays S (h, w, 3) and T (h, w)."""
import ctypes
import math

import numpy as np

from ._lib import BeamMedium, NbtError, NBT_EDOM, ScreenInput, ScreenKern, ScreenPathMedium, ScreenPathOpts, \
    ScreenWorld, as_c, call, c_double, c_int, c_size_t, c_void_p, clear_error, lib, proto, ptr, raise_error

_kphase = proto("nbt_screen_kernel_phase", c_void_p, [c_int, c_double, c_double, c_void_p, c_int, c_void_p])
_kalloc = proto("nbt_screen_kernel_alloc", c_void_p, [c_int, ctypes.POINTER(BeamMedium), c_void_p])
_krgb = proto("nbt_screen_kernel_rgb", c_void_p, [c_void_p, c_void_p, c_void_p])
_kfree = proto("nbt_screen_kernel_free", None, [c_void_p])
_keval_ch = proto("nbt_screen_kernel_eval_ch", c_int, [c_void_p, ctypes.c_uint, c_double, ctypes.POINTER(ScreenKern)])
_kchannels = proto("nbt_screen_kernel_channels", ctypes.c_uint, [c_void_p])
_layered = proto("nbt_screen_layered", c_int, [ctypes.POINTER(ScreenInput), c_void_p, c_int, c_double, c_size_t,
                                               ctypes.c_uint, ctypes.POINTER(c_double), ctypes.POINTER(c_double)])
_brute = proto("nbt_screen_brute", c_int, [ctypes.POINTER(ScreenInput), c_void_p, c_int, c_double, ctypes.c_uint,
                                           ctypes.POINTER(c_double), ctypes.POINTER(c_double)])
_path = proto("nbt_screen_path", c_int, [ctypes.POINTER(ScreenWorld), ctypes.POINTER(ScreenPathMedium),
                                         ctypes.POINTER(ScreenPathOpts), ctypes.POINTER(c_double),
                                         ctypes.POINTER(c_double), ctypes.POINTER(ctypes.c_ulong)])
_quantize = proto("nbt_screen_quantize", None, [ctypes.POINTER(ctypes.c_float), c_size_t, c_size_t,
                                                ctypes.POINTER(ctypes.c_float)])
_atom_pixel = proto("nbt_screen_atom_pixel", c_double, [c_int, c_double, ctypes.c_long, ctypes.c_long])

SKY = 1e10
KINDS = {"moment": 0, "smallangle": 1, "corrected": 2, "single": 3, "lineint": 4, "elek": 5, "fitted": 6,
         "first": 7}
GEOMETRIES = {"inside": 0, "entering": 1}
RULES = {"near": 0, "source": 1}
ATOMS = ("erfc", "gauss")


def _choice(name, table, what):
    try:
        return table[name]
    except KeyError:
        raise NbtError("%s %r: accepted are %s" % (what, name, ", ".join(table)), NBT_EDOM) from None


class Kernel:
    """A kernel family over depth (nbt_screen_kernel)."""

    def __init__(self, handle, keep=()):
        self._k = handle
        self._keep = list(keep)  # phases the kernel borrows

    @classmethod
    def phase(cls, kind, sigma_t, albedo, phase, geometry="inside"):
        """Kernels built for a phase (nbt_screen_kernel_phase): kind 'fitted'
        (first order + the shipped model of the higher orders), 'first' or
        'elek'; geometry 'inside' or 'entering'."""
        k = _choice(kind, KINDS, "Kernel.phase: kind")
        if k not in (5, 6, 7):
            raise NbtError("Kernel.phase: kind %r: accepted are fitted, first, elek" % kind, NBT_EDOM)
        clear_error()
        h = _kphase(k, sigma_t, albedo, phase.handle, _choice(geometry, GEOMETRIES, "geometry"), None)
        if not h:
            raise_error(NBT_EDOM, fallback="nbt_screen_kernel_phase failed")
        return cls(h, [phase])

    @classmethod
    def beam(cls, kind, medium):
        """Narrow-beam kernels of a Gaussian-phase medium (nbt_screen_kernel_alloc):
        kind 'moment', 'smallangle', 'single', 'lineint' or 'elek'; medium a nbt.beam.Medium."""
        k = _choice(kind, KINDS, "Kernel.beam: kind")
        if k in (2, 6, 7):
            raise NbtError("Kernel.beam: kind %r: accepted are moment, smallangle, single, lineint, elek" % kind,
                           NBT_EDOM)
        clear_error()
        h = _kalloc(k, ctypes.byref(medium.struct), None)
        if not h:
            raise_error(NBT_EDOM, fallback="nbt_screen_kernel_alloc failed")
        return cls(h, [medium])

    @classmethod
    def rgb(cls, r, g, b):
        """One kernel per channel; takes r, g, b over (they become unusable)."""
        hs = []
        for k in (r, g, b):
            if not k._k:
                raise NbtError("Kernel.rgb: a kernel was already used", NBT_EDOM)
            hs.append(k._k)
        keep = r._keep + g._keep + b._keep
        for k in (r, g, b):
            k._k = None
        clear_error()
        h = _krgb(*hs)
        if not h:
            raise_error(NBT_EDOM, fallback="nbt_screen_kernel_rgb failed")
        return cls(h, keep)

    def __del__(self):
        if getattr(self, "_k", None):
            _kfree(self._k)
            self._k = None

    @property
    def handle(self):
        if not self._k:
            raise NbtError("Kernel: used up by Kernel.rgb", NBT_EDOM)
        return self._k

    @property
    def channels(self):
        return _kchannels(self.handle)

    def eval(self, D, channel=0):
        """The kernel at distance D: dict T, shape (list of 'erfc'/'gauss'), mass, scale (arrays)."""
        out = ScreenKern()
        call(_keval_ch, self.handle, channel, D, ctypes.byref(out))
        n = out.n
        return {"T": out.T, "shape": [ATOMS[out.shape[i]] for i in range(n)],
                "mass": np.array(out.mass[:n]), "scale": np.array(out.scale[:n])}


def _image(rgb, D, what):
    rgb = as_c(rgb, np.float32)
    D = as_c(D, np.float32)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise NbtError("%s: rgb must have shape (h, w, 3), got %r" % (what, rgb.shape), NBT_EDOM)
    if D.shape != rgb.shape[:2]:
        raise NbtError("%s: the depth must have shape %r (the image's h, w), got %r" % (what, rgb.shape[:2], D.shape),
                       NBT_EDOM)
    return rgb, D


def dtheta_from_fov(fov_y, h):
    """Pixel angle 2 tan(fov_y/2)/h (fov_y in radians)."""
    return 2.0 * math.tan(0.5 * fov_y) / h


def _operator(fn, rgb, D, dtheta, kernel, rule, tail, nthreads, *extra):
    rgb, D = _image(rgb, D, fn.__name__)
    h, w = D.shape
    inp = ScreenInput(w, h, ptr(rgb, ctypes.c_float), ptr(D, ctypes.c_float), dtheta, None)
    S = np.zeros((h, w, 3))
    T = np.zeros((h, w))
    args = [ctypes.byref(inp), kernel.handle, _choice(rule, RULES, "rule"), tail] + list(extra) + \
        [nthreads, ptr(S, c_double), ptr(T, c_double)]
    call(fn, *args)
    return S, T


def layered(rgb, D, dtheta, kernel, rule="near", tail=1e-7, max_layers=16, nthreads=0):
    """(S, T) by FFT convolution (nbt_screen_layered): exact for a depth map of
    at most max_layers distinct values (sky counts as one). J = T c + S."""
    return _operator(_layered, rgb, D, dtheta, kernel, rule, tail, nthreads, max_layers)


def brute(rgb, D, dtheta, kernel, rule="near", tail=1e-7, nthreads=0):
    """(S, T) by brute force, any depth map (small images)."""
    return _operator(_brute, rgb, D, dtheta, kernel, rule, tail, nthreads)


def quantize(D, L):
    """D snapped to L log-spaced layers (0 and sky unchanged)."""
    D = as_c(D, np.float32)
    out = np.empty_like(D)
    _quantize(ptr(D, ctypes.c_float), D.size, L, ptr(out, ctypes.c_float))
    return out


def atom_pixel(shape, scale_px, dx, dy):
    """The integral of a unit-mass atom ('erfc' or 'gauss') over pixel (dx, dy)."""
    return _atom_pixel(_choice(shape, {"erfc": 0, "gauss": 1}, "atom shape"), scale_px, dx, dy)


def _triple(v, what):
    a = np.broadcast_to(np.asarray(v, np.float64), (3,))
    return a


def path(rgb, Z, dtheta, sigma_t, albedo, phase, spp=16, seed=1, cx=None, cy=None, window=None, radius=math.inf,
         sky=(0.0, 0.0, 0.0), target_noise=0.0, max_spp=0, bin=4, nthreads=0, max_order=0):
    """The path-traced reference (nbt_screen_path): (S, se, spp_done) over the
    display window (x0, y0, ow, oh) (default: the whole image); Z planar depth
    (>= 1e10 or inf: sky); sigma_t and albedo one value or one per channel;
    cx, cy the optical axis in pixels (default the image centre)."""
    rgb, Z = _image(rgb, Z, "path")
    h, w = Z.shape
    x0, y0, ow, oh = window if window is not None else (0, 0, w, h)
    world = ScreenWorld(w, h, ptr(rgb, ctypes.c_float), ptr(Z, ctypes.c_float), dtheta,
                        0.5 * w if cx is None else cx, 0.5 * h if cy is None else cy, x0, y0, ow, oh)
    m = ScreenPathMedium()
    for c, (s, a, k) in enumerate(zip(_triple(sigma_t, "sigma_t"), _triple(albedo, "albedo"), _triple(sky, "sky"))):
        m.sigma_t[c], m.albedo[c], m.sky[c] = s, a, k
    m.phase = phase.handle
    m.radius = radius
    o = ScreenPathOpts()
    o.spp, o.target_noise, o.max_spp, o.bin, o.seed = spp, target_noise, max_spp, bin, seed
    o.nthreads, o.max_order = nthreads, max_order
    S = np.zeros((oh, ow, 3))
    se = np.zeros((oh, ow, 3))
    done = ctypes.c_ulong()
    call(_path, ctypes.byref(world), ctypes.byref(m), ctypes.byref(o), ptr(S, c_double), ptr(se, c_double),
         ctypes.byref(done))
    return S, se, done.value
