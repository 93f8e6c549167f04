"""foreign9: independent implementation of Wong's semi-empirical wheel-soil model
(paper Eqs. 1-10, with the two typo corrections of hardware.md), slip-sinkage forms
(Eqs. 11-13), the Wong-Reece stress distribution and the out-of-family effects.

Units: SI throughout (N, m, Pa, rad).  Soil dict values are numpy arrays (or scalars):
  k   = kc/b + kphi   [N/m^(n+2)]
  n   sinkage exponent
  c   cohesion [Pa]
  tphi = tan(phi)
  K   shear deformation modulus [m]
"""
import numpy as np

NQ = 40
_X, _WG = np.polynomial.legendre.leggauss(NQ)


def _nodes(lo, hi):
    """Gauss-Legendre nodes/weights on [lo, hi] (arrays of shape (N,)) -> (N, NQ)."""
    half = 0.5 * (hi - lo)[:, None]
    th = lo[:, None] + half * (_X[None, :] + 1.0)
    w = half * _WG[None, :]
    return th, w


def static_sinkage(W, r, b, k, n):
    """Eq. 10 with kc + b*kphi = b*k."""
    return (3.0 * W / (np.sqrt(2.0 * r) * b * k * (3.0 - n))) ** (2.0 / (2.0 * n + 1.0))


def _integrals(th1, thm, s, r_geo, r_sh, b, k, N, c, tphi, K, eff, wr, tan_alpha, lam=None):
    """Return dict of integrals over [0, th1] split at thm (two GL pieces)."""
    out = {}
    z0 = np.zeros_like(th1)
    pieces = [(z0, thm, True), (thm, th1, False)]
    acc = {key: 0.0 for key in ("s_cos", "s_sin", "tx_cos", "tx_sin", "tx", "ty")}
    for lo, hi, rear in pieces:
        th, w = _nodes(lo, hi)
        t1 = th1[:, None]
        if wr and rear:
            tm = thm[:, None]
            tstar = t1 - (th / np.maximum(tm, 1e-12)) * (t1 - tm)
        else:
            tstar = th
        zz = np.clip(r_geo[:, None] * (np.cos(tstar) - np.cos(t1)), 0.0, None)
        sig = k[:, None] * zz ** N[:, None]
        if lam is not None:
            sig = sig * lam[:, None]
        jx = r_sh[:, None] * (t1 - th - (1.0 - s[:, None]) * (np.sin(t1) - np.sin(th)))
        if tan_alpha is not None:
            jy = r_sh[:, None] * (1.0 - s[:, None]) * (t1 - th) * tan_alpha[:, None]
            j = np.sqrt(jx * jx + jy * jy)
            jsafe = np.where(j > 1e-12, j, 1.0)
            ux = np.where(j > 1e-12, jx / jsafe, 1.0)
            uy = np.where(j > 1e-12, jy / jsafe, 0.0)
        else:
            j = np.abs(jx)
            ux = np.sign(jx)
            uy = 0.0
        tau = (c[:, None] + sig * tphi[:, None]) * (1.0 - np.exp(-j / K[:, None]))
        tx = tau * ux
        ty = tau * uy
        cs, sn = np.cos(th), np.sin(th)
        acc["s_cos"] = acc["s_cos"] + np.sum(w * sig * cs, axis=1)
        acc["s_sin"] = acc["s_sin"] + np.sum(w * sig * sn, axis=1)
        acc["tx_cos"] = acc["tx_cos"] + np.sum(w * tx * cs, axis=1)
        acc["tx_sin"] = acc["tx_sin"] + np.sum(w * tx * sn, axis=1)
        acc["tx"] = acc["tx"] + np.sum(w * tx, axis=1)
        acc["ty"] = acc["ty"] + np.sum(w * ty, axis=1) if tan_alpha is not None else np.zeros_like(th1)
    out.update(acc)
    return out


def wheel_forces(W, s, soil, r, b, eff=None, V=None):
    """Vectorised model.  W, s: arrays (N,).  soil: dict of arrays (N,) or scalars.
    r: rolling radius (array or scalar).  eff: effect dict (case + parameters).
    Returns dict: Dp, T, Fy, Z, th1 (arrays)."""
    eff = eff or {}
    case = eff.get("case", "none")
    W = np.atleast_1d(np.asarray(W, float))
    N_ = W.shape[0]
    s = np.broadcast_to(np.asarray(s, float), (N_,)).copy()
    f = lambda v: np.broadcast_to(np.asarray(v, float), (N_,)).copy()
    r = f(r)
    k, n, c, tphi, K = (f(soil[key]) for key in ("k", "n", "c", "tphi", "K"))
    if case == "rate":  # loading-rate dependent stiffness
        v = np.maximum(f(V if V is not None else 1.0), 0.1)
        k = k * (v / eff.get("v_ref", 1.0)) ** eff["beta"]
    r_geo = r.copy()
    if case == "flextyre":  # equivalent rigid wheel of a deflected tyre
        r_geo = r * (1.0 + eff["e"] * W / eff.get("W_ref", 10000.0))
    r_sh = r_geo.copy()
    if case == "lugs":
        r_sh = r + eff["h"]
    Z0 = static_sinkage(W, r_geo, b, k, n)
    Z = Z0.copy()
    N = n.copy()
    sp = np.clip(s, 0.0, None)  # slip sinkage grows with positive slip only
    if case == "vasilev":
        Z = Z0 + eff["H"] * sp
    elif case == "lyasko":
        Z = (1.0 + eff["m1"] * sp) / (1.0 - eff["m2"] * sp) * Z0
    elif case == "ding":
        N = n + eff["n1"] * sp
    capped = None
    if case == "hardpan":
        d = eff["depth"]
        capped = Z > d
        Zfree = Z.copy()
        Z = np.minimum(Z, d)
    Z = np.minimum(Z, 0.95 * r_geo)
    th1 = np.arccos(1.0 - Z / r_geo)
    wr = case == "stress_distribution"
    thm = (eff["a1"] + eff["a2"] * sp) * th1 if wr else 0.5 * th1
    tan_alpha = f(np.tan(np.radians(eff["alpha_deg"]))) if case == "steer" else None
    lam = None
    if capped is not None and np.any(capped):
        # the hard layer carries what the sinkage cap removes: stresses scaled so the
        # vertical support (Eq. 7 sigma part) equals that of the free sinkage
        th1f = np.arccos(1.0 - np.minimum(Zfree, 0.95 * r_geo) / r_geo)
        If = _integrals(th1f, 0.5 * th1f, s, r_geo, r_sh, b, k, N, c, tphi, K, eff, False, tan_alpha)
        Ic = _integrals(th1, thm, s, r_geo, r_sh, b, k, N, c, tphi, K, eff, False, tan_alpha)
        lam = np.where(capped, If["s_cos"] / np.maximum(Ic["s_cos"], 1e-9), 1.0)
    I = _integrals(th1, thm, s, r_geo, r_sh, b, k, N, c, tphi, K, eff, wr, tan_alpha, lam)
    Dp = r_sh * b * I["tx_cos"] - r_geo * b * I["s_sin"]
    if case == "lugs":
        T = r_sh * r_sh * b * I["tx"]
    else:
        T = r * r_sh * b * I["tx"]
    Fy = r_sh * b * I["ty"]
    if case == "bulldoze":
        phi = np.arctan(tphi)
        Kp = np.tan(np.pi / 4 + phi / 2) ** 2
        gamma = eff.get("gamma", 16000.0)
        Rb = eff["kb"] * b * (0.5 * gamma * Z * Z * Kp + 2.0 * c * Z * np.sqrt(Kp))
        Dp = Dp - Rb
    W7 = r_geo * b * (I["s_cos"] + I["tx_sin"])
    return {"Dp": Dp, "T": T, "Fy": Fy, "Z": Z, "th1": th1, "W7": W7}
