"""Phase functions (nbt/phase.h): p(mu) per steradian, normalised over the sphere."""
import ctypes

import numpy as np

from ._lib import NbtError, as_c, call, c_double, c_double_p, c_int, c_size_t, c_void_p, errbuf, lib, proto, ptr, \
    raise_error, clear_error, NBT_EDOM

_parse = proto("nbt_phase_parse", c_int, [ctypes.c_char_p, ctypes.POINTER(c_void_p), ctypes.c_char_p, c_size_t])
_free = proto("nbt_phase_free", None, [c_void_p])
_eval = proto("nbt_phase_eval", c_double, [c_void_p, c_double])
_moments = proto("nbt_phase_moments", c_int, [c_void_p, c_size_t, c_double_p])
_mean_cosine = proto("nbt_phase_mean_cosine", c_double, [c_void_p])
_name = proto("nbt_phase_name", ctypes.c_char_p, [c_void_p])
_kind = proto("nbt_phase_get_kind", c_int, [c_void_p])
_hg = proto("nbt_phase_hg", c_void_p, [c_double])
_hg2 = proto("nbt_phase_hg2", c_void_p, [c_double, c_double, c_double])
_gauss = proto("nbt_phase_gauss", c_void_p, [c_double])
_sog = proto("nbt_phase_sog", c_void_p, [c_size_t, c_double_p, c_double_p])
_tab = proto("nbt_phase_tabulated", c_void_p, [c_size_t, c_double_p, c_double_p])
_legendre = proto("nbt_legendre_p", None, [c_size_t, c_double, c_double_p])
_trunc = proto("nbt_phase_hg_trunc_error", c_double, [c_double, c_size_t, c_int])

KINDS = ("iso", "hg", "rayleigh", "gauss", "sog", "table", "hg2")


class Phase:
    """A libnbt phase function. Phase("hg:g=0.8") parses a SPEC as nbt-gen
    does ("iso", "rayleigh", "hg:g=G", "hg2:g1=..,g2=..,w=..", "gauss:B=..",
    "table:FILE", "sog:FILE"); a bad SPEC raises NbtError with libnbt's reason."""

    def __init__(self, spec):
        out = c_void_p()
        err = errbuf()
        call(_parse, spec.encode(), ctypes.byref(out), err, len(err), err_buf=err)
        self._p = out.value

    @classmethod
    def _wrap(cls, handle, what):
        if not handle:
            raise_error(NBT_EDOM, fallback=what)
        obj = cls.__new__(cls)
        obj._p = handle
        return obj

    @classmethod
    def hg(cls, g):
        clear_error()
        return cls._wrap(_hg(g), "nbt_phase_hg: g = %r is outside (-1, 1)" % g)

    @classmethod
    def hg2(cls, g1, g2, w):
        clear_error()
        return cls._wrap(_hg2(g1, g2, w), "nbt_phase_hg2: need -1 < g1, g2 < 1 and 0 <= w <= 1, got %r, %r, %r"
                         % (g1, g2, w))

    @classmethod
    def gauss(cls, B):
        clear_error()
        return cls._wrap(_gauss(B), "nbt_phase_gauss: B = %r is outside (0, 1000]" % B)

    @classmethod
    def sog(cls, w, B):
        w = as_c(w, np.float64)
        B = as_c(B, np.float64)
        if w.shape != B.shape or w.ndim != 1:
            raise NbtError("nbt_phase_sog: w and B must be 1-D arrays of one length", NBT_EDOM)
        clear_error()
        return cls._wrap(_sog(len(w), ptr(w, c_double), ptr(B, c_double)),
                         "nbt_phase_sog: weights must be >= 0 and spreads in (0, 1000]")

    @classmethod
    def tabulated(cls, mu, p):
        mu = as_c(mu, np.float64)
        p = as_c(p, np.float64)
        if mu.shape != p.shape or mu.ndim != 1:
            raise NbtError("nbt_phase_tabulated: mu and p must be 1-D arrays of one length", NBT_EDOM)
        clear_error()
        return cls._wrap(_tab(len(mu), ptr(mu, c_double), ptr(p, c_double)),
                         "nbt_phase_tabulated: need n >= 2 increasing mu from -1 to 1 and p >= 0")

    def __del__(self):
        if getattr(self, "_p", None):
            _free(self._p)
            self._p = None

    @property
    def handle(self):
        return self._p

    @property
    def name(self):
        return _name(self._p).decode()

    @property
    def kind(self):
        return KINDS[_kind(self._p)]

    def __repr__(self):
        return "nbt.Phase(%r)" % self.name

    def __call__(self, mu):
        return self.eval(mu)

    def eval(self, mu):
        """p(mu) per steradian; mu a number or an array (any shape)."""
        m = np.asarray(mu, dtype=np.float64)
        out = np.empty(m.shape)
        for i, x in np.ndenumerate(m):
            out[i] = _eval(self._p, float(x))
        return float(out) if out.ndim == 0 else out

    def moments(self, kmax):
        """Legendre moments b_0..b_kmax (b_0 = 1, b_1 = g)."""
        if kmax < 0:
            raise NbtError("moments: kmax = %r must be >= 0" % kmax, NBT_EDOM)
        b = np.empty(kmax + 1)
        call(_moments, self._p, kmax, ptr(b, c_double))
        return b

    @property
    def mean_cosine(self):
        return _mean_cosine(self._p)


def legendre_p(kmax, x):
    """P_0..P_kmax at x."""
    P = np.empty(kmax + 1)
    _legendre(kmax, x, ptr(P, c_double))
    return P


def hg_trunc_error(g, N, norm="max"):
    """Relative truncation error of the HG series kept to orders 0..N (norm 'max' or 'l2')."""
    if norm not in ("max", "l2"):
        raise NbtError("hg_trunc_error: norm %r is not 'max' or 'l2'" % norm, NBT_EDOM)
    return _trunc(g, N, 0 if norm == "max" else 1)
