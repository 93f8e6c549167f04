"""Independent implementation of Wong's semi-empirical rigid-wheel model.

Written from the seed paper (Eqs. 1-13) with the two typo corrections of
hardware.md:
  Eq. (2)  sigma = (kc/b + kphi) z^n          (Bekker)
  Eq. (3)  z(theta) = r (cos theta - cos theta1)
Shear: Janosi-Hanamoto, Eq. (4), with the shear displacement of Eq. (5).
Forces: Eqs. (7)-(9), integrated with scipy.integrate.quad.
Static sinkage: Eq. (10).  Slip sinkage: Eqs. (11)-(13).
Optional: Wong & Reece (1967) normal-stress distribution (maximum at
theta_m = (a1 + a2 s) theta1, rear region by the equivalent angle).

Units: SI throughout (Pa, m, N, rad).  kc in N/m^(n+1), kphi in N/m^(n+2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from scipy.integrate import quad

QUAD_KW = dict(epsabs=1e-3, epsrel=1e-7, limit=200)


@dataclass(frozen=True)
class Soil:
    c: float = 1.00e3        # Pa
    phi_deg: float = 25.0    # deg
    K: float = 0.025         # m
    n: float = 1.04
    kc: float = 1.00e3       # N/m^(n+1)
    kphi: float = 580.0e3    # N/m^(n+2)

    @property
    def tanphi(self) -> float:
        return math.tan(math.radians(self.phi_deg))

    def scaled(self, k_factor: float = 1.0, tan_factor: float = 1.0) -> "Soil":
        """kc and kphi scaled together by k_factor; tan(phi) by tan_factor."""
        phi = math.degrees(math.atan(self.tanphi * tan_factor))
        return replace(self, kc=self.kc * k_factor, kphi=self.kphi * k_factor,
                       phi_deg=phi)


SAND = Soil()                       # paper Tab. 1, sandy soil
CLAY = Soil(c=7.58e3, phi_deg=14.0, K=0.025, n=0.85, kc=43.68e3, kphi=499.3e3)


@dataclass(frozen=True)
class Wheel:
    r: float = 0.47
    b: float = 0.32


def static_sinkage(W: float, soil: Soil, wheel: Wheel, n: float | None = None) -> float:
    """Paper Eq. (10). n may be overridden (Ding's N)."""
    n = soil.n if n is None else n
    r, b = wheel.r, wheel.b
    base = 3.0 * W / (math.sqrt(2.0 * r) * (soil.kc + b * soil.kphi) * (3.0 - n))
    return base ** (2.0 / (2.0 * n + 1.0))


def sinkage(W: float, s: float, soil: Soil, wheel: Wheel, slip_model: str = "wong",
            p: dict | None = None) -> tuple[float, float]:
    """Total sinkage Z and the pressure-sinkage exponent used in sigma.

    wong    : Z = Z0                                  (Eq. 10)
    vasilev : Z = Z0 + H s                            (Eq. 11)
    lyasko  : Z = (1 + m1 s)/(1 - m2 s) Z0            (Eq. 12)
    ding    : N = n + n1 s replaces n, in Eq. 10 and in Eq. 2  (Eq. 13)
    Slip sinkage is applied for s > 0 only (the paper's models are for
    driving); for s <= 0 (braking) the static sinkage is used.
    """
    p = p or {}
    sp = max(s, 0.0)
    if slip_model in ("wong", "none", None):
        return static_sinkage(W, soil, wheel), soil.n
    if slip_model == "vasilev":
        return static_sinkage(W, soil, wheel) + p["H"] * sp, soil.n
    if slip_model == "lyasko":
        z0 = static_sinkage(W, soil, wheel)
        return z0 * (1.0 + p["m1"] * sp) / (1.0 - p["m2"] * sp), soil.n
    if slip_model == "ding":
        N = soil.n + p["n1"] * sp
        return static_sinkage(W, soil, wheel, n=N), N
    raise ValueError(slip_model)


def _shear_disp(theta, theta1, s, r):
    """Paper Eq. (5)."""
    return r * (theta1 - theta - (1.0 - s) * (math.sin(theta1) - math.sin(theta)))


def make_stresses(Z: float, s: float, soil: Soil, wheel: Wheel, n: float,
                  dist: str = "wong", a1: float = 0.0, a2: float = 0.0):
    """Return (sigma(theta), tau(theta), theta1, theta_m)."""
    r, b = wheel.r, wheel.b
    Z = min(Z, r * 0.999)
    theta1 = math.acos(1.0 - Z / r)                     # Eq. (1)
    kk = (soil.kc / b + soil.kphi) * r ** n             # Eq. (2) corrected
    c1 = math.cos(theta1)
    tanphi, K, c = soil.tanphi, soil.K, soil.c

    def bekker(th):
        d = math.cos(th) - c1                           # Eq. (3) corrected
        return kk * d ** n if d > 0.0 else 0.0

    if dist == "wong":
        theta_m = 0.0
        sigma = bekker
    elif dist == "wong_reece":
        theta_m = min(max(a1 + a2 * max(s, 0.0), 0.0), 0.95) * theta1

        def sigma(th):
            if th >= theta_m:
                return bekker(th)
            # rear region: equivalent angle, sigma -> 0 at theta2 = 0
            th_e = theta1 - th / theta_m * (theta1 - theta_m)
            return bekker(th_e)
    else:
        raise ValueError(dist)

    def tau(th):
        j = _shear_disp(th, theta1, s, r)
        mob = 1.0 - math.exp(-abs(j) / K)                # Eq. (4)
        return math.copysign((c + sigma(th) * tanphi) * mob, j)

    return sigma, tau, theta1, theta_m


def _q(f, a, b, pts):
    """quad over [a, b] split at the given breakpoints."""
    edges = [a] + [p for p in pts if a < p < b] + [b]
    tot = 0.0
    err = 0.0
    for lo, hi in zip(edges[:-1], edges[1:]):
        v, e = quad(f, lo, hi, **QUAD_KW)
        tot += v
        err += e
    return tot, err


def forces(s: float, W: float, soil: Soil = SAND, wheel: Wheel = Wheel(),
           slip_model: str = "wong", p: dict | None = None, dist: str = "wong",
           a1: float = 0.0, a2: float = 0.0, torque_radius: float | None = None,
           full: bool = False):
    """Drawbar pull Dp, torque T and the vertical integral Wint (Eqs. 7-9)
    for slip s and wheel load W (W sets the sinkage through Eq. 10).

    torque_radius: radius at which the shear acts for the axle torque
    (default wheel.r; used by the equivalent-rigid-wheel tyre model).
    """
    Z, n = sinkage(W, s, soil, wheel, slip_model, p)
    sigma, tau, th1, thm = make_stresses(Z, s, soil, wheel, n, dist, a1, a2)
    r, b = wheel.r, wheel.b
    pts = [thm] if thm > 0 else []
    sc, e1 = _q(lambda t: sigma(t) * math.cos(t), 0.0, th1, pts)
    ss, e2 = _q(lambda t: sigma(t) * math.sin(t), 0.0, th1, pts)
    tc, e3 = _q(lambda t: tau(t) * math.cos(t), 0.0, th1, pts)
    ts, e4 = _q(lambda t: tau(t) * math.sin(t), 0.0, th1, pts)
    tt, e5 = _q(tau, 0.0, th1, pts)
    Wint = r * b * (sc + ts)                             # Eq. (7)
    Dp = r * b * (tc - ss)                               # Eq. (8)
    rt = wheel.r if torque_radius is None else torque_radius
    T = rt * r * b * tt                                  # Eq. (9): r^2 b int tau
    if full:
        return dict(Dp=Dp, T=T, Wint=Wint, Z=Z, n=n, theta1=th1, theta_m=thm,
                    err=max(e1, e2, e3, e4, e5) * r * b * max(r, rt))
    return Dp, T, Wint, Z
