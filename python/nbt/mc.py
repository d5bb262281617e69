"""The photon counter (nbt/mc.h): a pencil beam in a homogeneous medium, tallied on planes."""
import ctypes

import numpy as np

from ._lib import McConfig, McResult, NbtError, NBT_EDOM, as_c, call, c_double, c_int, proto, ptr

_run = proto("nbt_mc_run", c_int, [ctypes.POINTER(McConfig), ctypes.POINTER(ctypes.POINTER(McResult))])
_free = proto("nbt_mc_result_free", None, [ctypes.POINTER(McResult)])


def run(sigma_t, albedo, phase, z_planes, r_bins=32, r_max_scale=1.0, photons=100000, seed=1, threads=0,
        infinite=False, slab=0.0, order_max=0, weighted=False, z_cut=0.0):
    """nbt_mc_run on a homogeneous medium (rho = 1 for z >= 0, or all space
    with infinite, or a slab). Returns a dict of NumPy arrays: psi and psi_se
    (planes x r_bins, per unit area per photon, bins of [0, r_max_scale z)),
    M0, M0_se, M2, M2_se (per plane), and R, R_se, T, T_se (slab), seconds,
    interactions. Deterministic per seed for any thread count."""
    zp = as_c(np.atleast_1d(z_planes), np.float64)
    cfg = McConfig()
    cfg.sigma_t = sigma_t
    cfg.albedo = albedo
    cfg.phase = phase.handle
    cfg.slab = slab
    cfg.nplanes = len(zp)
    cfg.z_planes = ptr(zp, c_double) if len(zp) else None
    cfg.r_bins = r_bins
    cfg.r_max_scale = r_max_scale
    cfg.z_cut = z_cut
    if photons < 64 or int(photons) != photons:
        raise NbtError("mc.run: photons = %r must be an integer >= 64" % photons, NBT_EDOM)
    cfg.photons = int(photons)
    cfg.seed = seed
    cfg.threads = threads
    cfg.infinite = 1 if infinite else 0
    cfg.order_max = order_max
    cfg.estimator = 1 if weighted else 0
    res = ctypes.POINTER(McResult)()
    call(_run, ctypes.byref(cfg), ctypes.byref(res))
    try:
        r = res.contents
        npl, nb = r.nplanes, r.r_bins

        def arr(p, n):
            return np.ctypeslib.as_array(p, shape=(n,)).copy() if n and p else np.empty(0)
        return {"psi": arr(r.psi, npl * nb).reshape(npl, nb), "psi_se": arr(r.psi_se, npl * nb).reshape(npl, nb),
                "M0": arr(r.M0, npl), "M0_se": arr(r.M0_se, npl), "M2": arr(r.M2, npl), "M2_se": arr(r.M2_se, npl),
                "R": r.R, "R_se": r.R_se, "T": r.T, "T_se": r.T_se, "seconds": r.seconds,
                "interactions": r.interactions}
    finally:
        _free(res)
