"""Loading libnbt, its error handler, and the ctypes mirrors of its structs.

The struct layouts follow the headers in libnbt/nbt/*.h field by field;
tests/test_python.sh checks every ctypes.sizeof here against the C compiler's
sizeof, so a header change that is not mirrored here fails make check.
"""
import ctypes
import ctypes.util
import os
import threading

import numpy as np

c_double_p = ctypes.POINTER(ctypes.c_double)
c_float_p = ctypes.POINTER(ctypes.c_float)
c_size_t = ctypes.c_size_t
c_int = ctypes.c_int
c_uint = ctypes.c_uint
c_double = ctypes.c_double
c_void_p = ctypes.c_void_p

# nbt_status (nbt/error.h)
NBT_OK, NBT_EDOM, NBT_ENOMEM, NBT_ETOL, NBT_EIO, NBT_EFORMAT, NBT_EINVAL = range(7)


class NbtError(Exception):
    """A libnbt call failed. status: the nbt_status code; the message is
    libnbt's own reason (from its error handler or the call's err buffer),
    else nbt_strerror of the status."""

    def __init__(self, message, status=NBT_EINVAL):
        super().__init__(message)
        self.status = status


def _candidates():
    """Where libnbt.so.0 may be, in the order documented in __init__.py."""
    here = os.path.dirname(os.path.abspath(__file__))
    env = os.environ.get("NBT_LIBRARY")
    if env:
        yield env
        return  # an explicit choice is never silently replaced
    yield os.path.join(here, "libnbt.so.0")
    try:
        from . import _paths  # written by make (the configured libdir)
        yield os.path.join(_paths.libdir, "libnbt.so.0")
    except ImportError:
        pass
    found = ctypes.util.find_library("nbt")
    if found:
        yield found
    yield "libnbt.so.0"
    # the build tree: python/nbt/ beside libnbt/.libs/
    yield os.path.join(here, "..", "..", "libnbt", ".libs", "libnbt.so.0")


def _load():
    tried = []
    for path in _candidates():
        if os.path.sep in path and not os.path.exists(path):
            tried.append(path + " (absent)")
            continue
        try:
            return ctypes.CDLL(path), path
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
    raise ImportError("nbt: cannot load libnbt.so.0; set NBT_LIBRARY to its path. Tried: " + "; ".join(tried))


lib, library_path = _load()

# ---- the error handler: the last reason libnbt gave (per thread, and the latest of any) ----
_last = threading.local()
_HANDLER = ctypes.CFUNCTYPE(None, ctypes.c_char_p, c_int)


_any = {"msg": None}  # the latest from any thread: libnbt may report from a worker thread


def _on_error(reason, status):
    msg = reason.decode("utf-8", "replace") if reason else None
    _last.msg = msg
    _any["msg"] = msg


_handler = _HANDLER(_on_error)  # kept alive for the library's lifetime
lib.nbt_set_error_handler.restype = c_void_p
lib.nbt_set_error_handler.argtypes = [_HANDLER]
lib.nbt_set_error_handler(_handler)
lib.nbt_strerror.restype = ctypes.c_char_p
lib.nbt_strerror.argtypes = [c_int]


def clear_error():
    _last.msg = None
    _any["msg"] = None


def last_error():
    """libnbt's latest reason: this thread's, else any thread's (None after a successful call's reset)."""
    return getattr(_last, "msg", None) or _any["msg"]


def raise_error(status, fallback=None, err_buf=None):
    msg = None
    if err_buf is not None and err_buf.value:
        msg = err_buf.value.decode("utf-8", "replace")
    if not msg:
        msg = last_error()
    if not msg:
        msg = fallback or lib.nbt_strerror(status).decode()
    raise NbtError(msg, status)


def check(status, err_buf=None, allow_etol=False):
    """Raise NbtError unless status is NBT_OK (or NBT_ETOL when allowed)."""
    if status == NBT_OK or (allow_etol and status == NBT_ETOL):
        return status
    raise_error(status, err_buf=err_buf)


def call(fn, *args, err_buf=None, allow_etol=False):
    clear_error()
    return check(fn(*args), err_buf=err_buf, allow_etol=allow_etol)


def errbuf():
    return ctypes.create_string_buffer(512)


def as_c(a, dtype):
    """A C-contiguous array of dtype (a copy only when needed)."""
    return np.ascontiguousarray(a, dtype=dtype)


def ptr(a, ctype):
    return a.ctypes.data_as(ctypes.POINTER(ctype))


def proto(name, restype, argtypes):
    f = getattr(lib, name)
    f.restype = restype
    f.argtypes = argtypes
    return f


# ---- struct mirrors ----
class Axis(ctypes.Structure):  # nbt_axis
    _fields_ = [("lo", c_double), ("hi", c_double), ("map", c_int), ("c", c_double), ("n", c_size_t)]


class TableStruct(ctypes.Structure):  # nbt_table
    _fields_ = [("kind", c_int), ("axis", Axis * 3), ("nch", c_size_t), ("k", c_int * 4), ("n", c_int),
                ("phase", ctypes.c_char * 128), ("quad_tol", c_double), ("quad_err", c_double),
                ("max_err", c_double * 4), ("max_abs", c_double * 4), ("half", c_int), ("form", c_int),
                ("interp2", c_int), ("cell_err", c_double_p), ("data", c_float_p),
                ("row_err", c_double_p), ("theta_cells", c_size_t), ("theta_err", c_double_p),
                ("sub_decay", c_int), ("sub_w", c_double), ("sub_c", (c_double * 10) * 4)]


BEAM_MAX_LOBES = 16
_RHO_FN = ctypes.CFUNCTYPE(c_double, c_double, c_void_p)


class BeamMedium(ctypes.Structure):  # nbt_beam_medium
    _fields_ = [("sigma_t", c_double), ("albedo", c_double), ("nlobes", c_size_t),
                ("w", c_double * BEAM_MAX_LOBES), ("B", c_double * BEAM_MAX_LOBES), ("nlayers", c_size_t),
                ("z", c_double_p), ("rho", c_double_p), ("rho_fn", c_void_p), ("rho_data", c_void_p)]


class AirlightGeom(ctypes.Structure):  # nbt_airlight_geom
    _fields_ = [(n, c_double) for n in ("kappa_s", "kappa_t", "I0", "dsv", "gamma", "dvp")]


class SurfaceGeom(ctypes.Structure):  # nbt_surface_geom
    _fields_ = [(n, c_double) for n in ("kappa_s", "kappa_t", "I0", "dsp", "theta_s", "theta_r", "kd", "ks")] + \
        [("n", c_int)]


class BuildOpts(ctypes.Structure):  # nbt_build_opts
    _fields_ = [("quad_tol", c_double), ("measure_error", c_int), ("nthreads", c_uint)]


SCREEN_MAX_ATOMS = 128


class ScreenKern(ctypes.Structure):  # nbt_screen_kern
    _fields_ = [("T", c_double), ("n", c_size_t), ("shape", c_int * SCREEN_MAX_ATOMS),
                ("mass", c_double * SCREEN_MAX_ATOMS), ("scale", c_double * SCREEN_MAX_ATOMS)]


class ScreenInput(ctypes.Structure):  # nbt_screen_input
    _fields_ = [("w", c_size_t), ("h", c_size_t), ("rgb", c_float_p), ("D", c_float_p), ("dtheta", c_double),
                ("pix", c_void_p)]


class ScreenWorld(ctypes.Structure):  # nbt_screen_world
    _fields_ = [("w", c_size_t), ("h", c_size_t), ("rgb", c_float_p), ("Z", c_float_p), ("dtheta", c_double),
                ("cx", c_double), ("cy", c_double), ("x0", c_size_t), ("y0", c_size_t), ("ow", c_size_t),
                ("oh", c_size_t)]


class ScreenPathMedium(ctypes.Structure):  # nbt_screen_path_medium
    _fields_ = [("sigma_t", c_double * 3), ("albedo", c_double * 3), ("phase", c_void_p), ("radius", c_double),
                ("sky", c_double * 3)]


class ScreenPathOpts(ctypes.Structure):  # nbt_screen_path_opts
    _fields_ = [("spp", ctypes.c_ulong), ("target_noise", c_double), ("max_spp", ctypes.c_ulong), ("bin", c_uint),
                ("seed", ctypes.c_uint64), ("nthreads", c_uint), ("max_order", c_uint), ("progress", c_int),
                ("no_nee", c_int)]


class McConfig(ctypes.Structure):  # nbt_mc_config
    _fields_ = [("sigma_t", c_double), ("albedo", c_double), ("phase", c_void_p), ("nlayers", c_size_t),
                ("z", c_double_p), ("rho", c_double_p), ("rho_fn", c_void_p), ("rho_data", c_void_p),
                ("rho_max", c_double), ("slab", c_double), ("nplanes", c_size_t), ("z_planes", c_double_p),
                ("r_bins", c_size_t), ("r_max_scale", c_double), ("z_cut", c_double), ("photons", ctypes.c_uint64),
                ("seed", ctypes.c_uint64), ("threads", c_uint), ("progress", c_void_p), ("progress_data", c_void_p),
                ("infinite", c_int), ("order_max", c_uint), ("estimator", c_int), ("roulette_weight", c_double)]


class McResult(ctypes.Structure):  # nbt_mc_result
    _fields_ = [("nplanes", c_size_t), ("r_bins", c_size_t), ("psi", c_double_p), ("psi_se", c_double_p),
                ("M0", c_double_p), ("M0_se", c_double_p), ("M2", c_double_p), ("M2_se", c_double_p),
                ("R", c_double), ("R_se", c_double), ("T", c_double), ("T_se", c_double), ("seconds", c_double),
                ("interactions", ctypes.c_uint64)]


SCENE_MAX_PHONG = 16
PLAN_MAX_PACKS = 128


class Scene(ctypes.Structure):  # nbt_scene
    _fields_ = [("kappa_t", c_double * 2), ("kappa_s", c_double * 2), ("distance", c_double * 2), ("have_g", c_int),
                ("g", c_double * 2), ("phase", c_void_p), ("airlight", c_int), ("diffuse", c_int),
                ("phong", c_int * SCENE_MAX_PHONG), ("nphong", c_size_t), ("tol", c_double),
                ("orders_max", c_size_t), ("half", c_int), ("basis", c_int), ("sub", c_int)]


class PlanRequest(ctypes.Structure):  # nbt_plan_request
    _fields_ = [("kind", c_int), ("n", c_int), ("nterms", c_size_t), ("phase", c_void_p), ("xmax", c_double),
                ("tol", c_double), ("size", c_size_t * 2), ("half", c_int), ("sub", c_int)]


class PlanSet(ctypes.Structure):  # nbt_plan_set
    _fields_ = [("req", PlanRequest), ("axis", Axis * 2), ("npacks", c_size_t), ("pred_err", c_double),
                ("pred_seconds", c_double)]


class TableSet(ctypes.Structure):  # nbt_tableset
    _fields_ = [("t", ctypes.POINTER(TableStruct) * PLAN_MAX_PACKS), ("count", c_size_t), ("scale", c_double),
                ("rel_err", c_double), ("seconds", c_double)]


STRUCTS = {"nbt_axis": Axis, "nbt_table": TableStruct, "nbt_beam_medium": BeamMedium,
           "nbt_airlight_geom": AirlightGeom, "nbt_surface_geom": SurfaceGeom, "nbt_build_opts": BuildOpts,
           "nbt_screen_kern": ScreenKern, "nbt_screen_input": ScreenInput, "nbt_screen_world": ScreenWorld,
           "nbt_screen_path_medium": ScreenPathMedium, "nbt_screen_path_opts": ScreenPathOpts,
           "nbt_mc_config": McConfig, "nbt_mc_result": McResult, "nbt_scene": Scene,
           "nbt_plan_request": PlanRequest, "nbt_plan_set": PlanSet, "nbt_tableset": TableSet}
