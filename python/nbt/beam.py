"""Narrow-beam kernels (nbt/beam.h) for homogeneous media with Gaussian lobes."""
import ctypes

import numpy as np

from ._lib import BeamMedium, NbtError, BEAM_MAX_LOBES, NBT_EDOM, as_c, call, c_double, c_double_p, c_int, c_void_p, \
    lib, proto, ptr

_moments = proto("nbt_beam_moments", c_int, [ctypes.POINTER(BeamMedium), c_int, c_double, c_double_p, c_double_p,
                                             c_double_p])
_kparams = proto("nbt_beam_kernel_params", None, [c_double, c_double, c_double_p, c_double_p])
_kernel = proto("nbt_beam_kernel", c_double, [c_double, c_double, c_double])
_psi = proto("nbt_beam_psi", c_int, [ctypes.POINTER(BeamMedium), c_int, c_double, c_double, c_double_p, c_double_p])
_check = proto("nbt_beam_check", c_int, [ctypes.POINTER(BeamMedium)])
_direct = proto("nbt_beam_direct", c_double, [ctypes.POINTER(BeamMedium), c_double])
_fit_default = proto("nbt_beam_fit_default", c_void_p, [])
_fit_psi = proto("nbt_beam_fit_psi", c_int, [c_void_p, c_int, ctypes.POINTER(BeamMedium), c_double, c_double,
                                             c_double_p])
_fit_params = proto("nbt_beam_fit_params", c_int, [c_void_p, c_int, c_double, c_double, c_double, c_double_p])

MOMENT_MODELS = {"ishimaru": 0, "smallangle": 1}
PSI_MODELS = {"ishimaru": 0, "smallangle": 1, "lineint": 2, "single": 3, "elek": 4}


def _model(name, table):
    try:
        return table[name]
    except KeyError:
        raise NbtError("unknown model %r: accepted are %s" % (name, ", ".join(table)), NBT_EDOM) from None


class Medium:
    """A homogeneous medium: extinction sigma_t at unit density, albedo, and
    Gaussian lobes of spread B (a number: one lobe) with weights w (summing
    to 1). Checked by libnbt (nbt_beam_check) on creation."""

    def __init__(self, sigma_t, albedo, B, w=None):
        B = np.atleast_1d(np.asarray(B, dtype=np.float64))
        w = np.ones(1) if w is None else np.atleast_1d(np.asarray(w, dtype=np.float64))
        if B.ndim != 1 or w.shape != B.shape or not 1 <= len(B) <= BEAM_MAX_LOBES:
            raise NbtError("Medium: B and w must hold 1..%d lobes of one length, got %d and %d"
                           % (BEAM_MAX_LOBES, B.size, w.size), NBT_EDOM)
        m = BeamMedium()
        m.sigma_t = sigma_t
        m.albedo = albedo
        m.nlobes = len(B)
        for i in range(len(B)):
            m.w[i] = w[i]
            m.B[i] = B[i]
        call(_check, ctypes.byref(m))
        self._m = m

    @property
    def struct(self):
        return self._m


def _broadcast_call(fn, *arrays):
    """fn(*scalars) over numpy-broadcast arrays; a scalar when all are scalars."""
    b = np.broadcast(*[np.asarray(a, dtype=np.float64) for a in arrays])
    out = np.empty(b.shape)
    for i, vals in enumerate(b):
        out.flat[i] = fn(*[float(v) for v in vals])
    return float(out) if out.ndim == 0 else out


def moments(medium, z, model="ishimaru"):
    """(M0, M2) of the scattered light on the plane at depth z (a number or an array)."""
    mi = _model(model, MOMENT_MODELS)
    zz = np.asarray(z, dtype=np.float64)
    M0, M2 = np.empty(zz.shape), np.empty(zz.shape)
    a, b = c_double(), c_double()
    for i, v in np.ndenumerate(zz):
        call(_moments, ctypes.byref(medium.struct), mi, float(v), ctypes.byref(a), ctypes.byref(b), None)
        M0[i], M2[i] = a.value, b.value
    return (float(M0), float(M2)) if zz.ndim == 0 else (M0, M2)


def kernel_params(M0, M2):
    """(alpha, beta) of the heuristic kernel alpha/r G(r/beta) reproducing M0 and M2."""
    a, b = c_double(), c_double()
    _kparams(M0, M2, ctypes.byref(a), ctypes.byref(b))
    return a.value, b.value


def kernel(alpha, beta, r):
    """alpha/r G(r/beta), G(x) = erfc(x/sqrt 2)/2 (arrays broadcast)."""
    return _broadcast_call(_kernel, alpha, beta, r)


def psi(medium, z, r, model="ishimaru"):
    """Psi(z, r) by model: 'ishimaru', 'smallangle' (moment kernels), 'lineint',
    'single', 'elek' (nbt_beam_psi); z and r broadcast."""
    mi = _model(model, PSI_MODELS)

    def one(zz, rr):
        out = c_double()
        call(_psi, ctypes.byref(medium.struct), mi, zz, rr, ctypes.byref(out), None)
        return out.value
    return _broadcast_call(one, z, r)


def fit_psi(medium, z, r, infinite=False):
    """Psi(z, r) of the fitted kernel model libnbt ships (nbt_beam_fit_default)."""
    f = _fit_default()

    def one(zz, rr):
        out = c_double()
        call(_fit_psi, f, 1 if infinite else 0, ctypes.byref(medium.struct), zz, rr, ctypes.byref(out))
        return out.value
    return _broadcast_call(one, z, r)


def fit_params(tau, albedo, B, infinite=False):
    """(a, b, M, s, h) of the fitted model at optical depth tau (nbt_beam_fit_params)."""
    p = np.empty(5)
    call(_fit_params, _fit_default(), 1 if infinite else 0, tau, albedo, B, ptr(p, c_double))
    return p


def direct(medium, z):
    """exp(-tau(z)): the unscattered part at depth z."""
    return _broadcast_call(lambda zz: _direct(ctypes.byref(medium.struct), zz), z)
