"""Lookup tables (nbt/table.h) and the table planner (nbt/plan.h)."""
import ctypes

import numpy as np

from ._lib import Axis, NbtError, NBT_EDOM, PlanRequest, PlanSet, Scene, TableSet, TableStruct, as_c, call, \
    c_double, c_double_p, c_int, c_size_t, c_void_p, errbuf, proto, ptr, SCENE_MAX_PHONG

_TP = ctypes.POINTER(TableStruct)
_free = proto("nbt_table_free", None, [_TP])
_read = proto("nbt_table_read_exr", c_int, [ctypes.c_char_p, ctypes.POINTER(_TP), ctypes.c_char_p, c_size_t])
_write = proto("nbt_table_write_exr", c_int, [_TP, ctypes.c_char_p, c_int])
_lookup = proto("nbt_table_lookup", None, [_TP, c_double, c_double, c_double_p])
_lookup3 = proto("nbt_table_lookup3", None, [_TP, c_double, c_double, c_double, c_double_p])
_dup = proto("nbt_table_dup", _TP, [_TP])
_map_name = proto("nbt_axis_map_name", ctypes.c_char_p, [c_int])
_kind_name = proto("nbt_table_kind_name", ctypes.c_char_p, [c_int])
_scene_init = proto("nbt_scene_init", None, [ctypes.POINTER(Scene)])
_plan_scene = proto("nbt_plan_scene", c_int, [ctypes.POINTER(Scene), ctypes.c_uint, ctypes.POINTER(c_void_p),
                                              ctypes.POINTER(c_size_t), ctypes.c_char_p, c_size_t])
_plan_tables = proto("nbt_plan_tables", c_int, [ctypes.POINTER(PlanRequest), c_size_t, ctypes.c_uint,
                                                ctypes.POINTER(c_void_p), ctypes.c_char_p, c_size_t])
_plan_free = proto("nbt_plan_free", None, [c_void_p])
_plan_count = proto("nbt_plan_count", c_size_t, [c_void_p])
_plan_get = proto("nbt_plan_get", ctypes.POINTER(PlanSet), [c_void_p, c_size_t])
_plan_execute = proto("nbt_plan_execute", c_int, [c_void_p, c_size_t, ctypes.POINTER(TableSet), ctypes.c_char_p,
                                                  c_size_t])
_plan_stem = proto("nbt_plan_stem", None, [ctypes.POINTER(PlanRequest), ctypes.c_char_p, c_size_t])

KINDS = {"H": 0, "J": 1}


class Table:
    """A libnbt table (owned). data: a NumPy copy shaped (n2, n1, n0, nch)."""

    def __init__(self, handle):
        if not handle:
            raise NbtError("Table: no table", NBT_EDOM)
        self._t = handle

    @classmethod
    def read_exr(cls, path):
        out = _TP()
        err = errbuf()
        call(_read, str(path).encode(), ctypes.byref(out), err, len(err), err_buf=err)
        return cls(out)

    def write_exr(self, path, compression="zip"):
        if compression not in ("zip", "none"):
            raise NbtError("write_exr: compression %r is not 'zip' or 'none'" % compression, NBT_EDOM)
        call(_write, self._t, str(path).encode(), 0 if compression == "zip" else 1)

    def __del__(self):
        if getattr(self, "_t", None):
            _free(self._t)
            self._t = None

    @property
    def struct_ptr(self):
        return self._t

    @property
    def struct(self):
        return self._t.contents

    @property
    def kind(self):
        return _kind_name(self.struct.kind).decode()

    @property
    def nch(self):
        return self.struct.nch

    @property
    def orders(self):
        """Legendre order per channel (-1: fixed phase)."""
        return [self.struct.k[c] for c in range(self.nch)]

    @property
    def phase(self):
        return self.struct.phase.decode()

    def axis(self, i):
        a = self.struct.axis[i]
        return {"lo": a.lo, "hi": a.hi, "map": _map_name(a.map).decode(), "c": a.c, "n": a.n}

    @property
    def max_err(self):
        return np.array([self.struct.max_err[c] for c in range(self.nch)])

    @property
    def data(self):
        s = self.struct
        shape = (s.axis[2].n, s.axis[1].n, s.axis[0].n, s.nch)
        return np.ctypeslib.as_array(s.data, shape=(int(np.prod(shape)),)).reshape(shape).copy()

    def lookup(self, x0, x1, x2=None):
        """Interpolated values at (x0, x1[, x2]) as a GPU sampler reads them
        (nbt_table_lookup / lookup3); arrays broadcast, result shape + (nch,)."""
        arrays = [np.asarray(x0, np.float64), np.asarray(x1, np.float64)]
        if x2 is not None:
            arrays.append(np.asarray(x2, np.float64))
        b = np.broadcast(*arrays)
        out = np.empty(b.shape + (self.nch,))
        flat = out.reshape(-1, self.nch)
        v = (c_double * 4)()
        for i, xs in enumerate(b):
            if x2 is None:
                _lookup(self._t, float(xs[0]), float(xs[1]), v)
            else:
                _lookup3(self._t, float(xs[0]), float(xs[1]), float(xs[2]), v)
            flat[i] = v[:self.nch]
        return out


class Plan:
    """A table plan (nbt_plan_scene / nbt_plan_tables); keeps the phases it borrows alive."""

    def __init__(self, handle, keep):
        self._p = handle
        self._keep = keep

    def __del__(self):
        if getattr(self, "_p", None):
            _plan_free(self._p)
            self._p = None

    def __len__(self):
        return _plan_count(self._p)

    def set(self, i):
        """What the plan decided for set i: kind, n, nterms, axes, npacks, predictions, stem."""
        if not 0 <= i < len(self):
            raise NbtError("Plan.set: index %r outside 0..%d" % (i, len(self) - 1), NBT_EDOM)
        s = _plan_get(self._p, i).contents
        stem = ctypes.create_string_buffer(128)
        _plan_stem(ctypes.byref(s.req), stem, len(stem))
        ax = [{"lo": a.lo, "hi": a.hi, "map": _map_name(a.map).decode(), "c": a.c, "n": a.n} for a in s.axis]
        return {"kind": "H" if s.req.kind == 0 else "J", "n": s.req.n, "nterms": s.req.nterms, "axes": ax,
                "npacks": s.npacks, "pred_err": s.pred_err, "pred_seconds": s.pred_seconds,
                "stem": stem.value.decode()}

    def execute(self, i):
        """Build set i: a list of Tables (its packs) and the measured relative error."""
        if not 0 <= i < len(self):
            raise NbtError("Plan.execute: index %r outside 0..%d" % (i, len(self) - 1), NBT_EDOM)
        ts = TableSet()
        err = errbuf()
        call(_plan_execute, self._p, i, ctypes.byref(ts), err, len(err), err_buf=err)
        # the Tables own the packs now (nbt_tableset_free would free the same pointers)
        return [Table(ts.t[j]) for j in range(ts.count)], ts.rel_err


def plan_scene(kappa_t, distance, g=None, phase=None, kappa_s=None, airlight=True, diffuse=True, phong=(),
               tol=1e-3, orders_max=16, half=False, nthreads=0):
    """Plan a scene (the keys of nbt-gen's scene files): kappa_t and distance
    as a number (the upper end) or (lo, hi); exactly one of g = (lo, hi)
    (Legendre tables for HG g at run time) and phase (a Phase)."""
    s = Scene()
    _scene_init(ctypes.byref(s))
    kt = (0.0, kappa_t) if np.isscalar(kappa_t) else tuple(kappa_t)
    dist = (0.0, distance) if np.isscalar(distance) else tuple(distance)
    s.kappa_t[0], s.kappa_t[1] = kt
    s.distance[0], s.distance[1] = dist
    if kappa_s is not None:
        ks = (0.0, kappa_s) if np.isscalar(kappa_s) else tuple(kappa_s)
        s.kappa_s[0], s.kappa_s[1] = ks
    if (g is None) == (phase is None):
        raise NbtError("plan_scene: give exactly one of g = (lo, hi) and phase", NBT_EDOM)
    if g is not None:
        s.have_g = 1
        s.g[0], s.g[1] = (g, g) if np.isscalar(g) else tuple(g)
    else:
        s.phase = phase.handle
    s.airlight = 1 if airlight else 0
    s.diffuse = 1 if diffuse else 0
    if len(phong) > SCENE_MAX_PHONG:
        raise NbtError("plan_scene: at most %d Phong exponents, got %d" % (SCENE_MAX_PHONG, len(phong)), NBT_EDOM)
    for i, n in enumerate(phong):
        s.phong[i] = int(n)
    s.nphong = len(phong)
    s.tol = tol
    s.orders_max = orders_max
    s.half = 1 if half else 0
    out = c_void_p()
    needed = c_size_t()
    err = errbuf()
    call(_plan_scene, ctypes.byref(s), nthreads, ctypes.byref(out), ctypes.byref(needed), err, len(err),
         err_buf=err)
    return Plan(out.value, [phase])


def plan_table(kind, xmax, nterms=None, phase=None, n=0, tol=0.0, size=(33, 33), half=False, nthreads=0):
    """Plan one table set: kind 'H' or 'J' (cosine exponent n), Legendre orders
    0..nterms-1 or one fixed phase, over [0, xmax]; tol > 0 sizes it, else size."""
    if kind not in KINDS:
        raise NbtError("plan_table: kind %r is not 'H' or 'J'" % (kind,), NBT_EDOM)
    r = PlanRequest()
    r.kind = KINDS[kind]
    r.n = n if kind == "J" else 0
    r.nterms = nterms or 0
    r.phase = phase.handle if phase is not None else None
    r.xmax = xmax
    r.tol = tol
    r.size[0], r.size[1] = size
    r.half = 1 if half else 0
    out = c_void_p()
    err = errbuf()
    call(_plan_tables, ctypes.byref(r), 1, nthreads, ctypes.byref(out), err, len(err), err_buf=err)
    return Plan(out.value, [phase])


_axis_node = proto("nbt_axis_node", c_double, [ctypes.POINTER(Axis), c_size_t])


def axis_node(table, axis, i):
    """The physical value of node i on the table's axis (nbt_axis_node)."""
    a = table.struct.axis[axis]
    if not 0 <= i < a.n:
        raise NbtError("axis_node: node %r outside 0..%d" % (i, a.n - 1), NBT_EDOM)
    return _axis_node(ctypes.byref(a), i)
