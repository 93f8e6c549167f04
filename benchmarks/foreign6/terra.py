"""Rigid-wheel terramechanics for the foreign6 generator (written from first principles).

Wong's rigid-wheel model as in the seed paper, Eqs. 1-10, with the two typo fixes of
hardware.md:
  Eq. 2 (fixed)  sigma = (kc/b + kphi) * z^n                     (Bekker)
  Eq. 3 (fixed)  z(theta) = r (cos(theta) - cos(theta1))          (>= 0 under the wheel)
  Eq. 1          theta1 = arccos(1 - Z/r)        (Z = sinkage of the lowest point)
  Eq. 4          tau = (c + sigma tan(phi)) (1 - exp(-j/K))       (Janosi-Hanamoto)
  Eq. 5          j = r [theta1 - theta - (1 - s)(sin(theta1) - sin(theta))]
  Eq. 7-9        W, Dp, T as integrals over 0..theta1 (theta2 = 0)
  Eq. 10         closed-form static sinkage (only used for comparison, see README)

All units SI inside (Pa, N, m, rad).  Soil moduli: kc in N/m^(n+1), kphi in N/m^(n+2).

The integrals are evaluated with composite Gauss-Legendre quadrature (own nodes from
numpy.polynomial.legendre.leggauss), split at every kink of the integrand (theta_m of the
Wong-Reece distribution, the depth where a multipass soil leaves its reloading line).
check.py compares every integral against scipy.integrate.quad.

Generalisations used by the effects of the generator (each optional, default = paper model):
  - n_eff          Ding's slip-dependent exponent N = n + n1 s (Eq. 13) is passed here
  - dist           ("wr", a1, a2): Wong-Reece normal stress with its maximum at
                   theta_m = (a1 + a2 s) theta1 and the rear region mapped onto the front
                   law (Wong & Reece 1967; Wong, Theory of Ground Vehicles)
  - shear          ("peak", Kr, Kw): Wong's hump shear curve (dense soils)
  - law            a pressure-sinkage law other than Bekker (multipass reloading)
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

_GX, _GW = np.polynomial.legendre.leggauss(40)
E1 = 1.0 - math.exp(-1.0)


@dataclass(frozen=True)
class Soil:
    c: float      # Pa
    phi: float    # rad
    K: float      # m
    n: float
    kc: float     # N/m^(n+1)
    kphi: float   # N/m^(n+2)

    @classmethod
    def from_lab(cls, c_kpa, phi_deg, K_m, n, kc, kphi):
        """Lab units: c kPa, phi deg, K m, kc kN/m^(n+1), kphi kN/m^(n+2)."""
        return cls(c_kpa * 1e3, math.radians(phi_deg), K_m, n, kc * 1e3, kphi * 1e3)

    def keq(self, b):
        return self.kc / b + self.kphi

    def lab_dict(self):
        return dict(c_kpa=self.c / 1e3, phi_deg=math.degrees(self.phi), K_m=self.K,
                    n=self.n, kc=self.kc / 1e3, kphi=self.kphi / 1e3)

    def with_(self, **kw):
        return replace(self, **kw)


@dataclass(frozen=True)
class Wheel:
    r: float
    b: float


# ----------------------------------------------------------------------------- laws
class Bekker:
    """sigma = k z^n (z depth below the undisturbed surface, m)."""

    def __init__(self, k, n):
        self.k, self.n, self.surface = k, n, 0.0
        self.kinks = ()

    def __call__(self, z):
        z = np.maximum(z, 0.0)
        return self.k * z ** self.n

    def inverse(self, p):
        return (p / self.k) ** (1.0 / self.n)


class Reload:
    """Soil already loaded once to depth z1 (pressure p1 = k z1^n) and unloaded:
    reloading follows the linear unload-reload line of slope ku from the rebound
    surface ze = z1 - p1/ku up to z1, then the virgin Bekker curve (Wong's repetitive
    loading model)."""

    def __init__(self, k, n, z1, ku):
        self.k, self.n, self.z1, self.ku = k, n, z1, ku
        self.p1 = k * z1 ** n
        self.surface = max(z1 - self.p1 / ku, 0.0)
        self.kinks = (z1,)

    def __call__(self, z):
        z = np.asarray(z, float)
        lin = self.ku * np.maximum(z - self.surface, 0.0)
        vir = self.k * np.maximum(z, 0.0) ** self.n
        return np.where(z <= self.z1, lin, vir)


# ----------------------------------------------------------------------------- shear
def shear_fn(j, spec, K):
    if spec is None or spec == "janosi":
        return 1.0 - np.exp(-j / K)
    kind, Kr, Kw = spec
    assert kind == "peak"
    # Wong's hump curve; equals 1 at j = Kw, tends to Kr for large j
    return Kr * (1.0 + (1.0 / (Kr * E1) - 1.0) * np.exp(1.0 - j / Kw)) * (1.0 - np.exp(-j / Kw))


# ----------------------------------------------------------------------------- integrals
def _nodes(a, b):
    h = 0.5 * (b - a)
    return a + h * (_GX + 1.0), h * _GW


def contact_theta1(Z, wheel, law):
    depth = Z - law.surface
    if depth <= 0:
        return 0.0
    return math.acos(max(-1.0, 1.0 - depth / wheel.r))


def stresses(theta, Z, s, wheel, soil, law, dist=None, shear=None, tau_mult=1.0):
    """sigma(theta), tau(theta) on the rim for a wheel whose lowest point is at depth Z."""
    r = wheel.r
    th1 = contact_theta1(Z, wheel, law)
    theta = np.asarray(theta, float)
    if dist is None:
        th_eq = theta
    else:
        _, a1, a2 = dist
        thm = min(max((a1 + a2 * s), 1e-6), 0.999) * th1
        th_eq = np.where(theta >= thm, theta, th1 - theta / thm * (th1 - thm))
    depth = Z - r * (1.0 - np.cos(th_eq))
    sigma = law(depth)
    j = r * ((th1 - theta) - (1.0 - s) * (math.sin(th1) - np.sin(theta)))
    j = np.maximum(j, 0.0)
    tau = tau_mult * (soil.c + sigma * math.tan(soil.phi)) * shear_fn(j, shear, soil.K)
    return sigma, tau


def _breaks(Z, s, wheel, law, dist):
    th1 = contact_theta1(Z, wheel, law)
    pts = [0.0, th1]
    if dist is not None:
        _, a1, a2 = dist
        thm = min(max((a1 + a2 * s), 1e-6), 0.999) * th1
        pts.append(thm)
        # rear region kink images of the law kinks
        for zk in law.kinks:
            if law.surface < zk < Z:
                thk = math.acos(1.0 - (Z - zk) / wheel.r)
                if thk < th1:
                    pts.append(thk)
                    if thk > thm:
                        pass
                    # image in the rear region: th_eq = thk -> theta = (th1-thk)/(th1-thm)*thm
                    if th1 > thm and thk >= thm:
                        pts.append((th1 - thk) / (th1 - thm) * thm)
    else:
        for zk in law.kinks:
            if law.surface < zk < Z:
                pts.append(math.acos(1.0 - (Z - zk) / wheel.r))
    pts.append(0.5 * th1)
    return sorted(set(p for p in pts if 0.0 <= p <= th1))


def forces(Z, s, wheel, soil, law=None, dist=None, shear=None, tau_mult=1.0):
    """(W, Dp, T) of Eqs. 7-9 for sinkage Z (m) and slip s."""
    if law is None:
        law = Bekker(soil.keq(wheel.b), soil.n)
    th1 = contact_theta1(Z, wheel, law)
    if th1 <= 0:
        return 0.0, 0.0, 0.0
    br = _breaks(Z, s, wheel, law, dist)
    W = Dp = T = 0.0
    for a, b in zip(br[:-1], br[1:]):
        if b - a < 1e-12:
            continue
        th, w = _nodes(a, b)
        sg, ta = stresses(th, Z, s, wheel, soil, law, dist, shear, tau_mult)
        c, sn = np.cos(th), np.sin(th)
        W += np.dot(w, sg * c + ta * sn)
        Dp += np.dot(w, ta * c - sg * sn)
        T += np.dot(w, ta)
    r, b_ = wheel.r, wheel.b
    return r * b_ * W, r * b_ * Dp, r * r * b_ * T


def solve_sinkage(Wt, s, wheel, soil, law=None, dist=None, shear=None, tau_mult=1.0):
    """Sinkage Z such that the vertical force balance Eq. 7 = W holds."""
    if law is None:
        law = Bekker(soil.keq(wheel.b), soil.n)
    lo = law.surface + 1e-7
    hi = law.surface + 0.02 * wheel.r
    f = lambda Z: forces(Z, s, wheel, soil, law, dist, shear, tau_mult)[0] - Wt
    while f(hi) < 0:
        hi = law.surface + min((hi - law.surface) * 1.6, 1.9 * wheel.r)
        if hi >= law.surface + 1.9 * wheel.r - 1e-9:
            raise RuntimeError("wheel cannot carry the load (sinkage > r)")
    return brentq(f, lo, hi, xtol=1e-9, rtol=1e-10)


def eq10_sinkage(Wt, wheel, soil, n=None):
    """Closed-form static sinkage, paper Eq. 10 (SI units)."""
    n = soil.n if n is None else n
    return (3.0 * Wt / (math.sqrt(2.0 * wheel.r) * (soil.kc + wheel.b * soil.kphi) * (3.0 - n))) ** (2.0 / (2.0 * n + 1.0))


# ----------------------------------------------------------------------------- flexible tyre
def flexible_forces(delta, z0, s, wheel, soil, pg, shear=None):
    """Tyre in the 'elastic' mode (Wong): circular front arc of the undeflected radius from
    the surface down to depth z0, then a flat section at depth z0 with uniform pressure pg.
    delta = tyre deflection.  Returns W, Dp, T."""
    r, b = wheel.r, wheel.b
    law = Bekker(soil.keq(b), soil.n)
    thf = math.acos(1.0 - delta / r)
    th1 = math.acos(1.0 - (z0 + delta) / r)
    W = Dp = T = 0.0
    # arc: depth(theta) = r(cos theta - cos th1); shear displacement Eq. 5
    for a, bb in ((thf, 0.5 * (thf + th1)), (0.5 * (thf + th1), th1)):
        th, w = _nodes(a, bb)
        sg = law(r * (np.cos(th) - math.cos(th1)))
        j = np.maximum(r * ((th1 - th) - (1.0 - s) * (math.sin(th1) - np.sin(th))), 0.0)
        ta = (soil.c + sg * math.tan(soil.phi)) * shear_fn(j, shear, soil.K)
        W += r * b * np.dot(w, sg * np.cos(th) + ta * np.sin(th))
        Dp += r * b * np.dot(w, ta * np.cos(th) - sg * np.sin(th))
        T += r * r * b * np.dot(w, ta)
    if delta > 0:
        lf = 2.0 * r * math.sin(thf)
        jf = r * ((th1 - thf) - (1.0 - s) * (math.sin(th1) - math.sin(thf)))
        x, w = _nodes(0.0, lf)
        ta = (soil.c + pg * math.tan(soil.phi)) * shear_fn(jf + s * x, shear, soil.K)
        Fx = b * np.dot(w, ta)
        W += pg * b * lf
        Dp += Fx
        T += (r - delta) * Fx
    return W, Dp, T


def flexible_solve(Wt, s, wheel, soil, pg, shear=None):
    """Returns (sinkage, W, Dp, T, deflection).  Rigid mode if the rigid wheel's peak
    pressure stays below pg."""
    Zr = solve_sinkage(Wt, s, wheel, soil, shear=shear)
    law = Bekker(soil.keq(wheel.b), soil.n)
    if law(Zr) <= pg:
        W, Dp, T = forces(Zr, s, wheel, soil, shear=shear)
        return Zr, W, Dp, T, 0.0
    z0 = law.inverse(pg)
    f = lambda d: flexible_forces(d, z0, s, wheel, soil, pg, shear)[0] - Wt
    d = brentq(f, 0.0, 0.6 * wheel.r, xtol=1e-10)
    W, Dp, T = flexible_forces(d, z0, s, wheel, soil, pg, shear)
    return z0, W, Dp, T, d
