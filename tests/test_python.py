#!/usr/bin/python3
"""tests/test_python.py REF: the nbt Python package against libnbt's C results.

REF is the output of tests/pyref (C, the same calls with the same inputs):
every value the package returns for those calls must equal C's double bit
for bit (the same code runs; only the marshalling differs, and a wrong
struct field, a float/double mix-up or a transposed image would change
bits). Besides, closed forms (HG moments g^k, two-term HG moments, T = e^{-sigma_t D})
and bad input raising NbtError with libnbt's own message.
"""
import math
import sys

import numpy as np

import nbt
from nbt import _lib

passed = failed = 0


def ok(cond, what):
    global passed, failed
    if cond:
        passed += 1
    else:
        failed += 1
        print("FAIL: " + what)


ref = {}
with open(sys.argv[1]) as f:
    for line in f:
        parts = line.split()
        if parts[0] == "sizeof":
            ref["sizeof " + parts[1]] = int(parts[2])
        else:
            ref[parts[0]] = np.array([float.fromhex(x) for x in parts[1:]])


def same(key, got):
    """bit-for-bit equality with C's values (NaN never expected here)"""
    want = ref[key]
    got = np.atleast_1d(np.asarray(got, dtype=np.float64)).ravel()
    if got.shape != want.shape:
        ok(False, "%s: %d values from Python, %d from C" % (key, got.size, want.size))
        return
    diff = np.flatnonzero(got.view(np.int64) != want.view(np.int64))
    ok(diff.size == 0, "%s: %d of %d values differ from C, first at %s: %r vs %r"
       % (key, diff.size, want.size, diff[:1], got[diff[:1]], want[diff[:1]]))


def raises(what, pattern, fn, *args, **kw):
    try:
        fn(*args, **kw)
    except nbt.NbtError as e:
        ok(pattern in str(e), "%s: message %r lacks %r" % (what, str(e), pattern))
        return
    except Exception as e:  # noqa: BLE001 - any other exception is a failure of the contract
        ok(False, "%s: raised %s (%s), not NbtError" % (what, type(e).__name__, e))
        return
    ok(False, "%s: no exception" % what)


# ---- the struct mirrors have C's sizes ----
for name, cls in _lib.STRUCTS.items():
    ok(ref["sizeof " + name] == __import__("ctypes").sizeof(cls),
       "sizeof %s: C %d, ctypes %d" % (name, ref["sizeof " + name], __import__("ctypes").sizeof(cls)))

# ---- phase functions ----
p2 = nbt.Phase("hg2:g1=0.8,g2=-0.3,w=0.7")
pg = nbt.Phase("gauss:B=0.05")
hg = nbt.Phase.hg(0.6)
same("hg2.eval", p2.eval(np.array([-0.9, -0.2, 0.0, 0.35, 0.99])))
same("hg2.moments", p2.moments(6))
same("hg2.g", p2.mean_cosine)
same("gauss.moments", pg.moments(5))
ok(p2.kind == "hg2" and hg.name == "hg:g=0.6", "kind %r, name %r" % (p2.kind, hg.name))
# eval keeps the array's shape (2 x 3, non-square)
mu = np.array([[-1.0, -0.5, 0.1], [0.2, 0.7, 1.0]])
pm = p2(mu)
ok(pm.shape == (2, 3) and pm[1, 1] == p2.eval(0.7), "eval over a 2x3 array")
# closed forms: HG b_k = g^k; two-term HG w g1^k + (1 - w) g2^k; HG p(mu)
k = np.arange(9)
ok(np.allclose(hg.moments(8), 0.6 ** k, rtol=1e-14, atol=0), "HG moments g^k")
ok(np.allclose(p2.moments(8), 0.7 * 0.8 ** k + 0.3 * (-0.3) ** k, rtol=1e-13, atol=1e-16), "HG2 moments")
hgp = (1 - 0.36) / (4 * math.pi * (1 + 0.36 - 1.2 * mu) ** 1.5)
ok(np.allclose(hg(mu), hgp, rtol=1e-14, atol=0), "HG p(mu) closed form")

# ---- beam kernels ----
m = nbt.Medium(1.3, 0.85, [0.02, 0.2], w=[0.6, 0.4])
for i, z in enumerate((0.7, 2.9)):
    M0, M2 = nbt.beam.moments(m, z)
    S0, S2 = nbt.beam.moments(m, z, "smallangle")
    same("beam.moments.%d" % i, [M0, M2, S0, S2])
same("beam.psi", [nbt.beam.psi(m, 2.1, 0.37, model) for model in ("ishimaru", "smallangle", "lineint", "single",
                                                                      "elek")])
same("beam.fit_psi", [nbt.beam.fit_psi(m, 2.1, 0.37), nbt.beam.fit_psi(m, 2.1, 0.37, infinite=True)])
# arrays broadcast: z (3, 1) against r (1, 4)
zz, rr = np.array([[0.5], [1.0], [2.1]]), np.array([[0.1, 0.2, 0.37, 0.9]])
grid = nbt.beam.psi(m, zz, rr, "single")
ok(grid.shape == (3, 4) and grid[2, 2] == ref["beam.psi"][3], "psi broadcasts (3,1) x (1,4)")
# eq. 25 closed form of M0 for one lobe: e^{-(1 - a) tau}(1 - e^{-a tau})
m1 = nbt.Medium(1.3, 0.85, 0.02)
M0, _ = nbt.beam.moments(m1, 2.0)
ok(abs(M0 - math.exp(-0.15 * 2.6) * (1 - math.exp(-0.85 * 2.6))) < 1e-15, "M0 closed form: %r" % M0)

# ---- H, J, airlight and surface radiance ----
same("hk", nbt.airlight.hk(5, 0.8, -0.3)[0])
same("jk", nbt.airlight.jk(3, 1, 1.4, 0.6)[0])
b = hg.moments(11)
same("airlight.series", nbt.airlight.airlight_series(b, 0.1, 0.25, 2.0, 5.0, 0.7, 8.0)[0])
same("surface.series", nbt.airlight.surface_series(b, 0.1, 0.25, 2.0, 3.0, 0.4, 1.1, 0.6, 0.3, 8)[0])
# the series against Nishita's integral (the truncation at 12 terms of HG 0.6: ~1e-3)
La, _ = nbt.airlight.airlight_series(hg.moments(60), 0.1, 0.25, 2.0, 5.0, 0.7, 8.0)
Ld, _ = nbt.airlight.airlight_direct(hg, 0.1, 0.25, 2.0, 5.0, 0.7, 8.0)
ok(abs(La / Ld - 1) < 1e-6, "airlight series (60 terms) vs direct: %r %r" % (La, Ld))

# ---- the planner and a table ----
pl = nbt.plan_table("H", 5.0, nterms=4, size=(17, 9), nthreads=1)
s0 = pl.set(0)
ok(len(pl) == 1 and s0["axes"][0]["n"] == 17 and s0["axes"][1]["n"] == 9 and s0["stem"] == "H", "plan %r" % s0)
tables, rel = pl.execute(0)
t = tables[0]
same("table.lookup", t.lookup([0.3, 1.7], [0.1, -0.8]))
same("airlight.table", nbt.airlight.airlight_table([t], b[:4], 0.1, 0.25, 2.0, 5.0, 0.7, 8.0)[0])
d = t.data
ok(d.shape == (1, 9, 17, 4) and t.orders == [0, 1, 2, 3], "table data (1, 9, 17, 4): %r" % (d.shape,))
# at a node the lookup returns the stored float: node (ix 3, iy 5)
# (to the mapping's round trip: the weights are 0 and 1 to ~1e-15; a transposed data array is off by far more)
nv = t.lookup(nbt.table.axis_node(t, 0, 3), nbt.table.axis_node(t, 1, 5))
ok(np.allclose(nv, d[0, 5, 3], rtol=1e-6, atol=0), "lookup at a node is the stored value: %r %r" % (nv, d[0, 5, 3]))
ax0, ax1 = t.axis(0), t.axis(1)
ok(ax0["map"] == "log1p_cbrt" and ax1["map"] == "cos", "planned mappings %r %r" % (ax0["map"], ax1["map"]))

tj, _ = nbt.plan_table("J", 4.0, nterms=4, n=1, size=(17, 9), nthreads=1).execute(0)
same("surface.table", nbt.airlight.surface_table(tj, [], b[:4], 0.1, 0.25, 2.0, 3.0, 0.4, 1.1, 0.6, 0.0, 1))
# EXR round trip: the same floats and axes back
import os
import tempfile
with tempfile.TemporaryDirectory() as td:
    t.write_exr(os.path.join(td, "H.exr"))
    t2 = nbt.Table.read_exr(os.path.join(td, "H.exr"))
    ok(np.array_equal(t2.data, d) and t2.axis(0) == t.axis(0) and t2.orders == t.orders, "EXR round trip")
    raises("read a missing EXR", "nope.exr", nbt.Table.read_exr, os.path.join(td, "nope.exr"))
# a scene plan with a fixed phase: the built H_p table against the exact H_p (nbt_h_phase) at
# off-node points, within the table's own recorded interpolation error (plus the quadrature's)
ph = nbt.Phase("hg:g=0.3")
sp = nbt.plan_scene(0.2, 10.0, phase=ph, diffuse=False, tol=2e-2, nthreads=1)
ok(len(sp) == 1 and sp.set(0)["kind"] == "H", "scene plan: one H set, got %d" % len(sp))
th, rel = sp.execute(0)
worst = 0.0
for u, v in ((0.37, -0.9), (1.3, 0.2), (0.05, 1.1)):
    exact = nbt.airlight.h_phase(ph, u, v)[0]
    worst = max(worst, abs(th[0].lookup(u, v)[0] - exact) / th[0].max_err[0])
print("H_p lookup: worst %.3g of max_err, rel_err %.3g" % (worst, rel))
ok(rel <= 2e-2 and worst <= 1.0 + 1e-6, "H_p lookup within max_err: worst %.3g of the bound, rel_err %.3g"
   % (worst, rel))

# ---- the photon counter ----
r = nbt.mc.run(1.0, 0.9, hg, [0.5, 1.5], r_bins=3, r_max_scale=0.8, photons=4096, seed=3, threads=1)
same("mc.psi", r["psi"])
same("mc.M0", r["M0"])
same("mc.M2", r["M2"])
ok(r["psi"].shape == (2, 3), "psi is planes x bins")

# ---- screen-space operators on a 9 x 5 image ----


def image(w, h, near, far):
    x, y, c = np.meshgrid(np.arange(w), np.arange(h), np.arange(3))
    rgb = (0.05 + 0.9 * (((x * 7 + y * 3 + c * 5) % 11) / 10.0)).astype(np.float32)
    D = np.where(np.arange(w)[None, :] < w // 2, near, far) * np.ones((h, 1))
    D = D.astype(np.float32)
    D[0, w - 1] = 1e10
    return rgb, D


rgb, D = image(9, 5, 2.5, 7.0)
kf = nbt.Kernel.phase("fitted", 0.4, 0.8, hg, "entering")
S, T = nbt.screen.layered(rgb, D, 0.02, kf, max_layers=4, nthreads=1)
same("screen.layered.S", S)
same("screen.layered.T", T)
ok(S.shape == (5, 9, 3) and T.shape == (5, 9), "layered shapes %r %r" % (S.shape, T.shape))
ok(abs(T[1, 0] - math.exp(-0.4 * 2.5)) < 1e-16 and T[0, 8] == 0.0, "T = exp(-sigma_t D), sky 0: %r" % T[1, 0])
ke = nbt.Kernel.phase("elek", 0.4, 0.8, hg, "inside")
same("screen.brute.elek", nbt.screen.brute(rgb, D, 0.02, ke, rule="source", nthreads=1)[0])
km = nbt.Kernel.beam("moment", m)
same("screen.brute.moment", nbt.screen.brute(rgb, D, 0.02, km, nthreads=1)[0])
kk = kf.eval(3.3)
same("kernel.T", kk["T"])
same("kernel.mass", kk["mass"])
same("kernel.scale", kk["scale"])
# an RGB kernel: channel c is what the grey kernel of channel c's medium gives in channel c
sig = (0.3, 0.45, 0.6)
krgb = nbt.Kernel.rgb(*[nbt.Kernel.phase("first", s_, 0.8, hg, "inside") for s_ in sig])
ok(krgb.channels == 3, "an RGB kernel has 3 channels")
Srgb, _ = nbt.screen.layered(rgb, D, 0.02, krgb, max_layers=4, nthreads=1)
for c_, s_ in enumerate(sig):
    Sg, Tg = nbt.screen.layered(rgb, D, 0.02, nbt.Kernel.phase("first", s_, 0.8, hg, "inside"), max_layers=4,
                                nthreads=1)
    err_ = np.max(np.abs(Srgb[..., c_] - Sg[..., c_])) / np.max(Sg[..., c_])
    ok(err_ <= 1e-12, "RGB kernel channel %d against its grey kernel: %g" % (c_, err_))
# layered and brute are the same operator (round-off apart)
Sb, Tb = nbt.screen.brute(rgb, D, 0.02, kf, nthreads=1)
ok(np.max(np.abs(Sb - S)) <= 1e-12 * np.max(S), "brute vs layered: %g" % np.max(np.abs(Sb - S)))

prgb, PZ = image(7, 4, 1.5, 4.0)
PS, Pse, done = nbt.screen.path(prgb, PZ, 0.05, [0.3, 0.35, 0.4], [0.9, 0.8, 0.7], hg, spp=4, seed=11, cx=3.2, cy=2.1,
                                window=(1, 1, 5, 3), sky=[0.1, 0.2, 0.3], nthreads=1)
same("path.S", PS)
same("path.se", Pse)
ok(PS.shape == (3, 5, 3) and done == 4, "path shape %r, spp %r" % (PS.shape, done))

# ---- errors carry libnbt's message ----
raises("bad phase spec", "g must be a number in (-1, 1)", nbt.Phase, "hg:g=1.5")
raises("unknown phase", "nope", nbt.Phase, "nope:x=1")
raises("albedo 1.5", "albedo = 1.5 is not accepted", nbt.Medium, 1.0, 1.5, 0.1)
raises("Phase.hg(1)", "(-1, 1)", nbt.Phase.hg, 1.0)
bad = D.copy()
bad[3, 2] = np.nan
raises("NaN depth at row 3, column 2", "pixel (2, 3): depth nan", nbt.screen.layered, rgb, bad, 0.02, kf)
raises("transposed depth", "(5, 9)", nbt.screen.layered, rgb, D.T, 0.02, kf)
raises("path spp 1", "spp", nbt.screen.path, prgb, PZ, 0.05, 0.3, 0.9, hg, spp=1)
raises("plan xmax -1", "xmax", nbt.plan_table, "H", -1.0, nterms=4)
raises("kernel kind", "accepted are fitted, first, elek", nbt.Kernel.phase, "moment", 0.4, 0.8, hg)
raises("mc photons", "photons", nbt.mc.run, 1.0, 0.9, hg, [1.0], photons=10)
raises("mc bad plane", "", nbt.mc.run, 1.0, 0.9, hg, [-1.0], photons=64)
ok(nbt.last_error() is not None, "last_error holds libnbt's reason")

print("%d passed, %d failed" % (passed, failed))
sys.exit(1 if failed else 0)
