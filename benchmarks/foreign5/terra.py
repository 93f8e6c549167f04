"""Wheel-soil physics for the foreign5 generator (written from the paper, Eqs. 1-13).

All internal units are SI: N, m, Pa, rad.  Soil dictionaries use
    c [Pa], phi [rad], K [m], n [-], kc [N/m^(n+1)], kphi [N/m^(n+2)]
(`soil_from_field` converts the field units of lab_soil.toml).

The two typos of the paper are fixed (hardware.md):
    Eq. 2   sigma = (kc/b + kphi) * Z^n
    Eq. 3   Z(theta) = r (cos theta - cos theta1)

Sinkage Z0 always comes from Eq. 10 with the measured vertical load W (the
paper's convention); slip sinkage modifies it (Eqs. 11-13).  theta2 = 0.
Integrals (Eqs. 7-9) are done with fixed-order Gauss-Legendre quadrature
on [0, theta1] (vectorised over arrays of s and W); check.py compares this
with scipy.integrate.quad.
"""
import math
import numpy as np

NGL = 64
_GX, _GW = np.polynomial.legendre.leggauss(NGL)


def soil_from_field(d):
    """Field units (kPa, deg, kN/m^(n+1), kN/m^(n+2)) -> SI dict."""
    return dict(c=d["c_kpa"] * 1e3, phi=math.radians(d["phi_deg"]), K=d["K_m"],
                n=d["n"], kc=d["kc"] * 1e3, kphi=d["kphi"] * 1e3)


def soil_to_field(s):
    return dict(c_kpa=s["c"] / 1e3, phi_deg=math.degrees(s["phi"]), K_m=s["K"],
                n=s["n"], kc=s["kc"] / 1e3, kphi=s["kphi"] / 1e3)


def k_eq(soil, b):
    return soil["kc"] / b + soil["kphi"]


def z0_wong(W, soil, r, b, n=None):
    """Eq. 10: static sinkage of a rigid wheel [m]; W in N."""
    n = soil["n"] if n is None else n
    W = np.maximum(np.asarray(W, float), 1.0)
    den = math.sqrt(2.0 * r) * (soil["kc"] + b * soil["kphi"]) * (3.0 - n)
    return (3.0 * W / den) ** (2.0 / (2.0 * n + 1.0))


def sinkage(s, W, soil, r, b, model="wong", mp=None):
    """Total sinkage Z and the sinkage exponent N used for sigma."""
    mp = mp or {}
    s = np.asarray(s, float)
    n = soil["n"]
    if model == "ding":                       # Eq. 13: N = n + n1 s (used in Eq. 10 and Eq. 2)
        N = n + mp["n1"] * np.clip(s, 0.0, None)
        Z = z0_wong(W, soil, r, b, n=N)
        return Z, N
    Z0 = z0_wong(W, soil, r, b)
    sp = np.clip(s, 0.0, None)               # slip sinkage only for driving slip
    if model == "vasilev":                    # Eq. 11
        Z = Z0 + mp["H"] * sp
    elif model == "lyasko":                   # Eq. 12
        Z = (1.0 + mp["m1"] * sp) / (1.0 - mp["m2"] * sp) * Z0
    else:
        Z = Z0 * np.ones_like(sp)
    return Z, np.full_like(Z, n)


def shear_curve(j, tau_max, soil, shear=None):
    """Janosi-Hanamoto (Eq. 4) or, for shear={'kind':'hump',...}, Wong's
    peak-residual curve (strain-softening soil, out of family)."""
    K = soil["K"]
    if shear and shear.get("kind") == "hump":
        Kr, Kw = shear["Kr"], shear["Kw"]
        a = 1.0 / (Kr * (1.0 - math.exp(-1.0))) - 1.0
        jj = np.abs(j)
        f = Kr * (1.0 + a * np.exp(1.0 - jj / Kw)) * (1.0 - np.exp(-jj / Kw))
        return tau_max * f * np.sign(j)
    return tau_max * (1.0 - np.exp(-j / K))


def forces(s, W, soil, r, b, model="wong", mp=None, shear=None, parts=False):
    """See _forces.  For model='wongreece' the sinkage is not Eq. 10 directly:
    theta1 is chosen so that the Wong-Reece stresses carry the same vertical
    force (Eq. 7) as the paper's stresses do at the Eq. 10 sinkage, i.e. the
    wheel is supported by the same load; bisection on a sinkage factor."""
    if model != "wongreece":
        return _forces(s, W, soil, r, b, model, mp, shear, parts)
    s, W = np.broadcast_arrays(np.asarray(s, float), np.asarray(W, float))
    s = s.ravel(); W = W.ravel()
    target = _forces(s, W, soil, r, b, "wong", None, shear)["W7"]
    lo = np.full(s.shape, 0.8); hi = np.full(s.shape, 3.0)
    for _ in range(30):
        q = 0.5 * (lo + hi)
        w7 = _forces(s, W, soil, r, b, model, mp, shear, zfac=q)["W7"]
        big = w7 > target
        hi = np.where(big, q, hi); lo = np.where(big, lo, q)
    out = _forces(s, W, soil, r, b, model, mp, shear, parts, zfac=0.5 * (lo + hi))
    out["zfac"] = 0.5 * (lo + hi)
    return out


def _forces(s, W, soil, r, b, model="wong", mp=None, shear=None, parts=False, zfac=1.0):
    """Drawbar pull Dp [N], torque T [N m], sinkage Z [m], theta1 for arrays s, W.

    model: 'wong' | 'vasilev' | 'lyasko' | 'ding' | 'wongreece'
    mp: model parameters (H; m1, m2; n1; a1, a2)
    With parts=True also returns the shear and normal parts of Dp.
    """
    mp = mp or {}
    s, W = np.broadcast_arrays(np.asarray(s, float), np.asarray(W, float))
    s = s.ravel(); W = W.ravel()
    Z, N = sinkage(s, W, soil, r, b, model if model != "wongreece" else "wong", mp)
    Z = np.minimum(Z * zfac, 0.95 * r)
    th1 = np.arccos(1.0 - Z / r)                                  # Eq. 1
    # quadrature nodes on [0, th1]
    th = 0.5 * th1[:, None] * (_GX[None, :] + 1.0)
    wq = 0.5 * th1[:, None] * _GW[None, :]
    keq = soil["kc"] / b + soil["kphi"]
    Nn = N[:, None]
    if model == "wongreece":
        thm = (mp["a1"] + mp["a2"] * np.clip(s, 0, None))[:, None] * th1[:, None]
        front = th >= thm
        th_eq = np.where(front, th, th1[:, None] - th / np.maximum(thm, 1e-9) * (th1[:, None] - thm))
        zt = r * (np.cos(th_eq) - np.cos(th1[:, None]))
    else:
        zt = r * (np.cos(th) - np.cos(th1[:, None]))               # Eq. 3 (fixed)
    sig = keq * np.maximum(zt, 0.0) ** Nn                          # Eq. 2 (fixed)
    j = r * ((th1[:, None] - th) - (1.0 - s[:, None]) * (np.sin(th1[:, None]) - np.sin(th)))  # Eq. 5
    tau = shear_curve(j, soil["c"] + sig * math.tan(soil["phi"]), soil, shear)               # Eq. 4
    Dtau = r * b * np.sum(wq * tau * np.cos(th), axis=1)
    Dsig = r * b * np.sum(wq * sig * np.sin(th), axis=1)
    Dp = Dtau - Dsig                                               # Eq. 8
    T = r * r * b * np.sum(wq * tau, axis=1)                       # Eq. 9
    Wm = r * b * np.sum(wq * (sig * np.cos(th) + tau * np.sin(th)), axis=1)  # Eq. 7
    out = dict(Dp=Dp, T=T, Z=Z, th1=th1, W7=Wm)
    if parts:
        out.update(Dtau=Dtau, Dsig=Dsig)
    return out


class Table:
    """Bilinear lookup of Dp, T (and the shear part of Dp) over (s, W)."""

    def __init__(self, soil, r, b, model="wong", mp=None, shear=None,
                 s_grid=None, W_grid=None):
        self.s = np.linspace(-0.4, 0.97, 275) if s_grid is None else s_grid
        self.W = np.linspace(2000.0, 24000.0, 45) if W_grid is None else W_grid
        S, WW = np.meshgrid(self.s, self.W, indexing="ij")
        f = forces(S, WW, soil, r, b, model, mp, shear, parts=True)
        sh = S.shape
        self.Dp = f["Dp"].reshape(sh); self.T = f["T"].reshape(sh)
        self.Dtau = f["Dtau"].reshape(sh); self.Z = f["Z"].reshape(sh)

    def __call__(self, s, W, what=("Dp", "T")):
        s = np.clip(np.asarray(s, float), self.s[0], self.s[-1])
        W = np.clip(np.asarray(W, float), self.W[0], self.W[-1])
        fi = (s - self.s[0]) / (self.s[1] - self.s[0])
        gi = (W - self.W[0]) / (self.W[1] - self.W[0])
        i = np.minimum(fi.astype(int), len(self.s) - 2)
        k = np.minimum(gi.astype(int), len(self.W) - 2)
        u = fi - i; v = gi - k
        res = []
        for name in what:
            A = getattr(self, name)
            res.append((1 - u) * (1 - v) * A[i, k] + u * (1 - v) * A[i + 1, k]
                       + (1 - u) * v * A[i, k + 1] + u * v * A[i + 1, k + 1])
        return res
