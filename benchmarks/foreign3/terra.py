"""Independent implementation of Wong's semi-empirical rigid-wheel model
(seed paper Eqs. 1-13, with the two typo corrections of hardware.md) plus the
extra physics used by the foreign3 generator.

Units: SI throughout (Pa, N, m, rad).  `lab_soil()` converts the paper's
table units (kPa, deg, kN/m^(n+1), kN/m^(n+2)) to SI.

Everything is integrated with scipy.integrate.quad.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.integrate import quad

# Paper Tab. 1, clay, in the paper's units
CLAY_TABLE = dict(c=7.58, phi=14.0, K=0.025, n=0.85, kc=43.68, kphi=499.3)
R_WHEEL = 0.47
B_WHEEL = 0.32


@dataclass
class Soil:
    c: float      # Pa
    phi: float    # rad
    K: float      # m
    n: float      # -
    kc: float     # N/m^(n+1)
    kphi: float   # N/m^(n+2)

    @staticmethod
    def from_table(t: dict) -> "Soil":
        return Soil(c=t["c"] * 1e3, phi=math.radians(t["phi"]), K=t["K"],
                    n=t["n"], kc=t["kc"] * 1e3, kphi=t["kphi"] * 1e3)

    def to_table(self) -> dict:
        return dict(c=self.c / 1e3, phi=math.degrees(self.phi), K=self.K,
                    n=self.n, kc=self.kc / 1e3, kphi=self.kphi / 1e3)

    def scaled(self, **f) -> "Soil":
        """Multiply fields by factors, e.g. scaled(c=1.2, k=0.9) (k = kc & kphi)."""
        d = dict(self.__dict__)
        for key, v in f.items():
            if key == "k":
                d["kc"] *= v
                d["kphi"] *= v
            else:
                d[key] *= v
        return Soil(**d)


def lab_soil() -> Soil:
    return Soil.from_table(CLAY_TABLE)


@dataclass
class Physics:
    """Which physics the soil/wheel contact follows.

    sinkage: 'wong' (Eq. 10), 'vasilev' (Eq. 11, H), 'lyasko' (Eq. 12, m1, m2),
             'ding' (Eq. 13, n1: N = n + n1 s replaces n in Eqs. 2 and 10)
    stress:  'wong' (Bekker law of the local sinkage, maximum at theta = 0, paper Eq. 2-3)
             'wong_reece' (maximum at theta_m = (a1 + a2 s) theta1)
    shear:   'janosi' (Eq. 4) | 'hump' (Wong's peak/residual shear curve, Kr, Kw)
    visc_beta, visc_vref: rate-dependent cohesion c*(1 + beta*log10(1 + v_j/vref))
    crab: wheel slip angle (rad): combined longitudinal/lateral shear displacement
    """
    sinkage: str = "wong"
    H: float = 0.0
    m1: float = 0.0
    m2: float = 0.0
    n1: float = 0.0
    stress: str = "wong"
    a1: float = 0.0
    a2: float = 0.0
    shear: str = "janosi"
    Kr: float = 1.0
    Kw: float = 0.025
    visc_beta: float = 0.0
    visc_vref: float = 0.01
    crab: float = 0.0


WONG = Physics()


def static_sinkage(W: float, soil: Soil, r: float, b: float, n: float | None = None) -> float:
    """Paper Eq. (10)."""
    n = soil.n if n is None else n
    base = 3.0 * W / (math.sqrt(2.0 * r) * (soil.kc + b * soil.kphi) * (3.0 - n))
    return base ** (2.0 / (2.0 * n + 1.0))


def sinkage(s: float, W: float, soil: Soil, r: float, b: float, ph: Physics) -> tuple[float, float]:
    """Total sinkage Z and the sinkage exponent used in the stress law."""
    if ph.sinkage == "ding":
        N = soil.n + ph.n1 * s
        return static_sinkage(W, soil, r, b, N), N
    z0 = static_sinkage(W, soil, r, b)
    if ph.sinkage == "wong":
        return z0, soil.n
    if ph.sinkage == "vasilev":
        return z0 + ph.H * s, soil.n
    if ph.sinkage == "lyasko":
        return (1.0 + ph.m1 * s) / (1.0 - ph.m2 * s) * z0, soil.n
    raise ValueError(ph.sinkage)


def wheel_forces(s: float, W: float, soil: Soil, r: float = R_WHEEL, b: float = B_WHEEL,
                 ph: Physics = WONG, V: float = 2.0, Z: float | None = None,
                 with_w7: bool = True) -> dict:
    """Drawbar pull Dp (Eq. 8), torque T (Eq. 9), vertical force W7 (Eq. 7),
    lateral force Fy (crab only), sinkage Z and entry angle theta1 (Eq. 1).
    Exit angle theta2 = 0.  V (m/s) matters only for rate-dependent cohesion."""
    if Z is None:
        Z, N = sinkage(s, W, soil, r, b, ph)
    else:
        N = soil.n
    Z = min(Z, 0.999 * r)
    t1 = math.acos(1.0 - Z / r)
    kk = soil.kc / b + soil.kphi            # corrected Eq. (2): kc/b + kphi
    ct1, st1 = math.cos(t1), math.sin(t1)
    tp = math.tan(soil.phi)

    if ph.stress == "wong":
        def sig(t):
            z = r * (math.cos(t) - ct1)     # corrected Eq. (3)
            return kk * z ** N if z > 0.0 else 0.0
        breaks = None
    elif ph.stress == "wong_reece":
        tm = (ph.a1 + ph.a2 * s) * t1

        def sig(t):
            if t >= tm:
                z = r * (math.cos(t) - ct1)
            else:   # rear region, theta2 = 0
                z = r * (math.cos(t1 - t / tm * (t1 - tm)) - ct1)
            return kk * z ** N if z > 0.0 else 0.0
        breaks = [tm]
    else:
        raise ValueError(ph.stress)

    one_s = 1.0 - s
    tana = math.tan(ph.crab)
    omega = V / (r * one_s) if one_s > 0 else 1e9

    def shear_parts(t):
        """(tau_x, tau_y) on the wheel rim at angle t."""
        jx = r * ((t1 - t) - one_s * (st1 - math.sin(t)))     # Eq. (5)
        jy = r * one_s * (t1 - t) * tana
        j = math.hypot(jx, jy)
        c = soil.c
        if ph.visc_beta:
            vj = max(r * omega - V * math.cos(t), 0.0)     # tangential slip velocity
            c = c * (1.0 + ph.visc_beta * math.log10(1.0 + vj / ph.visc_vref))
        tmax = c + sig(t) * tp
        if ph.shear == "janosi":
            f = 1.0 - math.exp(-j / soil.K)               # Eq. (4)
        else:  # 'hump' (Wong, Theory of Ground Vehicles: peak at j = Kw, residual Kr)
            Kr, Kw = ph.Kr, ph.Kw
            f = Kr * (1.0 + (1.0 / (Kr * (1.0 - 1.0 / math.e)) - 1.0)
                      * math.exp(1.0 - j / Kw)) * (1.0 - math.exp(-j / Kw))
        tau = tmax * f
        if j <= 0.0:
            return tau, 0.0
        return tau * jx / j, tau * jy / j

    opts = dict(epsabs=1e-10, epsrel=1e-9, limit=200)
    if breaks:
        opts["points"] = breaks

    def I(fun):
        return quad(fun, 0.0, t1, **opts)[0]

    tx_cos = I(lambda t: shear_parts(t)[0] * math.cos(t))
    s_sin = I(lambda t: sig(t) * math.sin(t))
    tx = I(lambda t: shear_parts(t)[0])
    out = dict(Dp=r * b * (tx_cos - s_sin), T=r * r * b * tx, Z=Z, theta1=t1,
               Rc=r * b * s_sin, H=r * b * tx_cos)
    if with_w7:
        out["W7"] = r * b * (I(lambda t: sig(t) * math.cos(t))
                             + I(lambda t: shear_parts(t)[0] * math.sin(t)))
    if ph.crab:
        # wheel sliding sideways to the right (crab > 0): the soil pushes it to
        # the left, i.e. +y of the hub frame (x fwd, z up, y left)
        out["Fy"] = r * b * I(lambda t: shear_parts(t)[1])
    else:
        out["Fy"] = 0.0
    return out


def dp_at(s, W, soil, ph=WONG, r=R_WHEEL, b=B_WHEEL, V=2.0):
    return wheel_forces(s, W, soil, r, b, ph, V)["Dp"]
