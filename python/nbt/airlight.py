"""Airlight (nbt/airlight.h) and surface radiance (nbt/surface.h) of a point source in a medium."""
import ctypes

import numpy as np

from ._lib import AirlightGeom, SurfaceGeom, NbtError, NBT_EDOM, as_c, call, c_double, c_double_p, c_int, c_size_t, \
    c_void_p, proto, ptr, TableStruct

_TP = ctypes.POINTER(TableStruct)
_hk = proto("nbt_hk", c_int, [c_size_t, c_double, c_double, c_double, c_double_p, c_double_p])
_h_phase = proto("nbt_h_phase", c_int, [c_void_p, c_double, c_double, c_double, c_double_p, c_double_p])
_al_direct = proto("nbt_airlight_direct", c_int, [c_void_p, ctypes.POINTER(AirlightGeom), c_double, c_double_p,
                                                  c_double_p])
_al_series = proto("nbt_airlight_series", c_int, [c_double_p, c_size_t, ctypes.POINTER(AirlightGeom), c_double,
                                                  c_double_p, c_double_p])
_al_table_e = proto("nbt_airlight_table_e", c_int, [ctypes.POINTER(_TP), c_size_t, c_double_p, c_size_t, c_void_p,
                                                    ctypes.POINTER(AirlightGeom), c_double_p, c_double_p])
_jk = proto("nbt_jk", c_int, [c_size_t, c_int, c_double, c_double, c_double, c_double_p, c_double_p])
_j_phase = proto("nbt_j_phase", c_int, [c_void_p, c_int, c_double, c_double, c_double, c_double_p, c_double_p])
_sf_direct = proto("nbt_surface_direct", c_int, [c_void_p, ctypes.POINTER(SurfaceGeom), c_double, c_double_p,
                                                 c_double_p])
_sf_series = proto("nbt_surface_series", c_int, [c_double_p, c_size_t, ctypes.POINTER(SurfaceGeom), c_double,
                                                 c_double_p, c_double_p])
_sf_table = proto("nbt_surface_table", c_int, [ctypes.POINTER(_TP), c_size_t, ctypes.POINTER(_TP), c_size_t,
                                               c_double_p, c_size_t, ctypes.POINTER(SurfaceGeom), c_double_p])


def hk(kmax, u, v, tol=1e-10):
    """(H_0..H_kmax, abserr) at (u, v) (thesis eq. 4.17)."""
    H, e = np.empty(kmax + 1), np.empty(kmax + 1)
    call(_hk, kmax, u, v, tol, ptr(H, c_double), ptr(e, c_double))
    return H, e


def h_phase(phase, u, v, tol=1e-10):
    """(H_p(u, v), abserr) for a fixed phase."""
    H, e = c_double(), c_double()
    call(_h_phase, phase.handle, u, v, tol, ctypes.byref(H), ctypes.byref(e))
    return H.value, e.value


def _ageom(kappa_s, kappa_t, I0, dsv, gamma, dvp):
    return AirlightGeom(kappa_s, kappa_t, I0, dsv, gamma, dvp)


def airlight_direct(phase, kappa_s, kappa_t, I0, dsv, gamma, dvp, tol=1e-8):
    """(L_a, abserr): Nishita's integral along the ray (the reference)."""
    g = _ageom(kappa_s, kappa_t, I0, dsv, gamma, dvp)
    L, e = c_double(), c_double()
    call(_al_direct, phase.handle, ctypes.byref(g), tol, ctypes.byref(L), ctypes.byref(e))
    return L.value, e.value


def airlight_series(b, kappa_s, kappa_t, I0, dsv, gamma, dvp, tol=1e-8):
    """(L_a, abserr): the Legendre series with moments b over exact H_k."""
    b = as_c(b, np.float64)
    g = _ageom(kappa_s, kappa_t, I0, dsv, gamma, dvp)
    L, e = c_double(), c_double()
    call(_al_series, ptr(b, c_double), len(b), ctypes.byref(g), tol, ctypes.byref(L), ctypes.byref(e))
    return L.value, e.value


def _tables(ts):
    ts = list(ts)
    arr = (_TP * max(1, len(ts)))(*[t.struct_ptr for t in ts])
    return arr, len(ts)


def airlight_table(tables, b, kappa_s, kappa_t, I0, dsv, gamma, dvp, fixed=None):
    """(L_a, abserr) by table lookup (nbt_airlight_table_e): Legendre tables
    with moments b (indexed by order), or one fixed-phase table (b None).
    NBT_ETOL (u beyond the table) is not an error here: the lookup is returned."""
    arr, n = _tables(tables)
    bb = as_c(b if b is not None else [1.0], np.float64)
    g = _ageom(kappa_s, kappa_t, I0, dsv, gamma, dvp)
    L, e = c_double(), c_double()
    call(_al_table_e, arr, n, ptr(bb, c_double), len(bb) if b is not None else 0,
         fixed.handle if fixed is not None else None, ctypes.byref(g), ctypes.byref(L), ctypes.byref(e),
         allow_etol=True)
    return L.value, e.value


def jk(kmax, n, T, theta, tol=1e-10):
    """(J_0^n..J_kmax^n, abserr) at (T, theta)."""
    J, e = np.empty(kmax + 1), np.empty(kmax + 1)
    call(_jk, kmax, n, T, theta, tol, ptr(J, c_double), ptr(e, c_double))
    return J, e


def j_phase(phase, n, T, theta, tol=1e-10):
    J, e = c_double(), c_double()
    call(_j_phase, phase.handle, n, T, theta, tol, ctypes.byref(J), ctypes.byref(e))
    return J.value, e.value


def _sgeom(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n):
    if int(n) != n or n < 1:
        raise NbtError("surface: the Phong exponent n = %r must be an integer >= 1" % n, NBT_EDOM)
    return SurfaceGeom(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, int(n))


def surface_direct(phase, kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n=1, tol=1e-6):
    """(L_p, abserr): the physical integral (slow reference)."""
    g = _sgeom(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n)
    L, e = c_double(), c_double()
    call(_sf_direct, phase.handle, ctypes.byref(g), tol, ctypes.byref(L), ctypes.byref(e))
    return L.value, e.value


def surface_series(b, kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n=1, tol=1e-8):
    """(L_p, abserr): the Legendre series over exact J_k^n."""
    b = as_c(b, np.float64)
    g = _sgeom(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n)
    L, e = c_double(), c_double()
    call(_sf_series, ptr(b, c_double), len(b), ctypes.byref(g), tol, ctypes.byref(L), ctypes.byref(e))
    return L.value, e.value


def surface_table(diffuse, specular, b, kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n=1):
    """L_p by table lookup: diffuse tables (n = 1) and specular ones (n = the Phong exponent)."""
    da, dn = _tables(diffuse)
    sa, sn = _tables(specular)
    bb = as_c(b if b is not None else [1.0], np.float64)
    g = _sgeom(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n)
    L = c_double()
    call(_sf_table, da, dn, sa, sn, ptr(bb, c_double), len(bb) if b is not None else 0, ctypes.byref(g),
         ctypes.byref(L))
    return L.value
