#!/usr/bin/python3
"""Reference values for nbt's tests, computed independently of libnbt with
mpmath (Debian: python3-mpmath) at 30 significant digits.

  H_k(u, v) = int_{-pi/2}^{v} exp(-u tan(pi/4 + t/2)) P_k(-sin t) dt
     evaluated in s = tan(pi/4 + t/2):  int_0^{S} e^{-u s} P_k((1-s^2)/(1+s^2)) 2/(1+s^2) ds
  J_k^n(T, theta) = int_0^pi G_k(T, g) K_n(theta, g) dg   (source-centred coordinates)
     G_k(T, g) = int_{g-pi/2}^{pi/2} exp(-T [cos g + sin g tan(pi/4 + t/2)]) P_k(-sin t) dt
     K_n(theta, g) = int_0^{2 pi} max(0, cos theta cos g + sin theta sin g cos phi)^n dphi

Usage: python3 make_refs.py   (writes hk.txt and jk.txt beside this script)
Run time: a few minutes. Output columns are documented in each file's header.
"""
import os
from mpmath import mp, mpf, quad, legendre, exp, tan, sin, cos, acos, pi, inf, nstr

mp.dps = 30
HERE = os.path.dirname(os.path.abspath(__file__))


def hk(k, u, v):
    u, v = mpf(u), mpf(v)
    S = inf if v == pi / 2 else tan(pi / 4 + v / 2)
    f = lambda s: exp(-u * s) * legendre(k, (1 - s * s) / (1 + s * s)) * 2 / (1 + s * s)
    pts = [mpf(0)]
    if u > 0:  # resolve the exponential's scale
        for m in (mpf(1) / 4, 1, 4, 16):
            if m / u < S:
                pts.append(m / u)
    for m in (mpf(1) / 2, 1, 2, 8):  # and the rational factor's
        if m < S and m not in pts:
            pts.append(m)
    pts = sorted(set(pts)) + [S]
    return quad(f, pts)


def kernel(n, theta, g):
    a = cos(theta) * cos(g)
    b = abs(sin(theta) * sin(g))
    if a >= b:
        return quad(lambda p: (a + b * cos(p)) ** n, [0, pi]) * 2
    if a <= -b:
        return mpf(0)
    p0 = acos(-a / b)
    return quad(lambda p: (a + b * cos(p)) ** n, [0, p0]) * 2


def gk(k, T, g):
    if g >= pi:
        return mpf(0)
    f = lambda t: exp(-T * (cos(g) + sin(g) * tan(pi / 4 + t / 2))) * legendre(k, -sin(t))
    lo = g - pi / 2
    return quad(f, [lo, (lo + pi / 2) / 2, pi / 2])


def jk(k, n, T, theta):
    T, theta = mpf(T), mpf(theta)
    cand = [pi / 2 - theta, 3 * pi / 2 - theta, theta - pi / 2, theta + pi / 2]
    lo, hi = max(mpf(0), theta - pi / 2), min(pi, theta + pi / 2)
    pts = sorted(set([lo, hi] + [c for c in cand if lo < c < hi]))
    return quad(lambda g: gk(k, T, g) * kernel(n, theta, g), pts)


def main():
    hpts = []
    for u in ("0", "0.001", "0.37", "1", "2.385", "10", "100", "1e4"):
        for v in ("-1.5707963267948966", "-1.2", "-0.3", "0", "0.7", "1.5", "1.5707", "1.5707963267948966"):
            hpts.append((u, v))
    with open(os.path.join(HERE, "hk.txt"), "w") as f:
        f.write("# H_k(u, v) by mpmath (tests/ref/make_refs.py), 30 digits\n# k u v H\n")
        for k in (0, 1, 2, 3, 7, 20):
            for u, v in hpts:
                # v is read as a double: use its exact binary value
                vv = mpf(float(v))
                vv = min(vv, pi / 2) if v != "1.5707963267948966" else pi / 2
                f.write("%d %s %s %s\n" % (k, u, v, nstr(hk(k, mpf(u), vv), 25)))
        # the boundary layer at v -> pi/2 for small u (width ~u in v): v at
        # pi/2 and 2e-6, 1e-4, 1e-2 below it
        for k in (0, 1, 2, 3):
            for u in ("1e-6", "1e-4", "1e-2"):
                for v in ("1.5707963267948966", "1.5707943267948966", "1.5706963267948966", "1.5607963267948966"):
                    vv = pi / 2 if v == "1.5707963267948966" else mpf(float(v))
                    f.write("%d %s %s %s\n" % (k, u, v, nstr(hk(k, mpf(u), vv), 25)))
    jpts = [("0", "0"), ("0", "1.2"), ("0.37", "0.4"), ("1", "1.5707963267948966"),
            ("2.385", "0.9"), ("2.385", "2.2"), ("10", "0.2"), ("10", "2.9")]
    with open(os.path.join(HERE, "jk.txt"), "w") as f:
        f.write("# J_k^n(T, theta) by mpmath (tests/ref/make_refs.py), 20+ digits\n# k n T theta J\n")
        mp.dps = 20
        for n in (1, 20):
            for k in (0, 1, 3):
                for T, th in jpts:
                    val = jk(k, n, mpf(T), mpf(float(th)))
                    f.write("%d %d %s %s %s\n" % (k, n, T, th, nstr(val, 18)))
                    f.flush()


if __name__ == "__main__":
    main()
