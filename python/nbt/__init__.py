"""nbt: Python access to libnbt (narrow-beam theory, airlight tables, screen-space scattering) through ctypes.

NumPy arrays in and out; no compiled extension. libnbt.so.0 is found by, in order:
  1. the environment variable NBT_LIBRARY (a path; used alone when set),
  2. libnbt.so.0 beside this package,
  3. the libdir this package was installed for (make install writes it into nbt/_paths.py),
  4. ctypes.util.find_library("nbt") and the dynamic linker's default search path,
  5. a build tree: ../../libnbt/.libs/ from this directory (python/nbt/ in the source tree).
Every failing libnbt call raises nbt.NbtError carrying libnbt's own message
(installed as libnbt's error handler, nbt_set_error_handler).

Modules: nbt.phase (Phase), nbt.beam (Medium, moments, psi, fit_psi), nbt.airlight
(H/J functions, airlight and surface radiance), nbt.table (Table, plan_scene,
plan_table), nbt.mc (run), nbt.screen (Kernel, layered, brute, path).
"""
from ._lib import NbtError, library_path, last_error
from .phase import Phase, legendre_p, hg_trunc_error
from . import phase, beam, airlight, table, mc, screen
from .beam import Medium
from .table import Table, plan_scene, plan_table
from .screen import Kernel

__all__ = ["NbtError", "library_path", "last_error", "Phase", "Medium", "Table", "Kernel", "plan_scene", "plan_table",
           "legendre_p", "hg_trunc_error", "phase", "beam", "airlight", "table", "mc", "screen"]
