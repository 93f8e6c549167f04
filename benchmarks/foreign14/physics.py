"""foreign14 wheel-soil physics: Wong's semi-empirical rigid-wheel model (paper Eqs. 1-13,
the two typos fixed per hardware.md), vectorised over samples, with an own Gauss-Legendre
quadrature. Units inside: N, m, Pa, rad.  kc in N/m^(n+1), kphi in N/m^(n+2).

Static sinkage: Eq. (10) with W = the wheel's actual vertical load (not the vertical balance).
"""
import numpy as np

GL_N = 48
_X, _WGT = np.polynomial.legendre.leggauss(GL_N)
_X = 0.5 * (_X + 1.0)        # nodes on [0, 1]
_WGT = 0.5 * _WGT


def _col(v, n):
    v = np.asarray(v, dtype=float)
    if v.ndim == 0:
        v = np.full(n, float(v))
    return v[:, None]


def sinkage_eq10(W, r, b, kc, kphi, n):
    """Eq. (10): Z0 = [3W / ((3-n)(kc + b kphi) sqrt(2r))]^(2/(2n+1))."""
    W = np.maximum(np.asarray(W, float), 1.0)
    return (3.0 * W / ((3.0 - n) * (kc + b * kphi) * np.sqrt(2.0 * r))) ** (2.0 / (2.0 * n + 1.0))


def wheel_forces(s, W, r, b, soil, model="wong", mp=None, return_all=False):
    """Drawbar pull Dp (Eq. 8) and torque T (Eq. 9) of a rigid wheel, vectorised over samples.

    s, W: arrays (same length) or scalars.  soil: dict c, phi (rad), K, n, kc, kphi, each a
    scalar or an array of the samples' length.  model: 'wong', 'vasilev' (H), 'lyasko' (m1, m2),
    'ding' (n1), 'stress' (Wong-Reece a1, a2), 'moisture' (beta, sig_d: out-of-family).
    r may also be an array (eccentric rim).
    """
    mp = mp or {}
    s = np.atleast_1d(np.asarray(s, float))
    N = s.shape[0]
    W = np.broadcast_to(np.asarray(W, float), (N,))
    r = np.broadcast_to(np.asarray(r, float), (N,))
    c = np.broadcast_to(np.asarray(soil["c"], float), (N,))
    phi = np.broadcast_to(np.asarray(soil["phi"], float), (N,))
    K = np.broadcast_to(np.asarray(soil["K"], float), (N,))
    n = np.broadcast_to(np.asarray(soil["n"], float), (N,))
    kc = np.broadcast_to(np.asarray(soil["kc"], float), (N,))
    kphi = np.broadcast_to(np.asarray(soil["kphi"], float), (N,))

    nexp = n + mp["n1"] * s if model == "ding" else n          # Eq. (13), N replaces n everywhere
    Z0 = sinkage_eq10(W, r, b, kc, kphi, nexp)
    if model == "vasilev":
        Z = Z0 + mp["H"] * s                                   # Eq. (11)
    elif model == "lyasko":
        Z = (1.0 + mp["m1"] * s) / (1.0 - mp["m2"] * s) * Z0   # Eq. (12)
    else:
        Z = Z0
    Z = np.minimum(Z, 0.95 * r)
    th1 = np.arccos(1.0 - Z / r)                               # Eq. (1)
    keq = kc / b + kphi                                        # Eq. (2), typo fixed

    def integrand(th, lo_map=None):
        # th: (N, m) angles; returns tau, sigma
        R = r[:, None]
        T1 = th1[:, None]
        if lo_map is None:
            zz = R * (np.cos(th) - np.cos(T1))                 # Eq. (3), typo fixed
        else:
            zz = R * (np.cos(lo_map) - np.cos(T1))
        zz = np.maximum(zz, 0.0)
        sig = keq[:, None] * zz ** nexp[:, None]
        j = R * (T1 - th - (1.0 - s[:, None]) * (np.sin(T1) - np.sin(th)))   # Eq. (5)
        tanphi = np.tan(phi)[:, None]
        if model == "moisture":
            tanphi = tanphi * (1.0 - mp["beta"] * np.exp(-sig / mp["sig_d"]))
        tau = (c[:, None] + sig * tanphi) * (1.0 - np.exp(-j / K[:, None]))   # Eq. (4)
        return tau, sig

    def integrate(a, bnd, lo_map_fn=None):
        th = a[:, None] + (bnd - a)[:, None] * _X[None, :]
        w = (bnd - a)[:, None] * _WGT[None, :]
        lm = lo_map_fn(th) if lo_map_fn else None
        tau, sig = integrand(th, lm)
        I_tc = np.sum(w * tau * np.cos(th), axis=1)
        I_ss = np.sum(w * sig * np.sin(th), axis=1)
        I_t = np.sum(w * tau, axis=1)
        I_sc = np.sum(w * sig * np.cos(th), axis=1)
        I_ts = np.sum(w * tau * np.sin(th), axis=1)
        return I_tc, I_ss, I_t, I_sc, I_ts

    zero = np.zeros(N)
    if model == "stress":
        thm = (mp["a1"] + mp["a2"] * s) * th1                  # Wong-Reece theta_m
        thm = np.clip(thm, 1e-6, th1)
        f = integrate(thm, th1)
        # rear region 0..theta_m: sinkage mapped to theta1 - theta/theta_m (theta1 - theta_m)
        g = integrate(zero, thm, lambda th: th1[:, None] - th / thm[:, None] * (th1 - thm)[:, None])
        I = [fi + gi for fi, gi in zip(f, g)]
    else:
        I = integrate(zero, th1)
    I_tc, I_ss, I_t, I_sc, I_ts = I
    rr = r
    Dp = rr * b * (I_tc - I_ss)                                # Eq. (8)
    T = rr ** 2 * b * I_t                                      # Eq. (9)
    if return_all:
        Weq7 = rr * b * (I_sc + I_ts)                          # Eq. (7), for information
        return Dp, T, Z, th1, Weq7
    return Dp, T


def wheel_forces_quad(s, W, r, b, soil, model="wong", mp=None):
    """Reference: the same model integrated with scipy.integrate.quad (scalar)."""
    from scipy.integrate import quad
    mp = mp or {}
    n = soil["n"] + (mp["n1"] * s if model == "ding" else 0.0)
    Z0 = float(sinkage_eq10(W, r, b, soil["kc"], soil["kphi"], n))
    if model == "vasilev":
        Z = Z0 + mp["H"] * s
    elif model == "lyasko":
        Z = (1 + mp["m1"] * s) / (1 - mp["m2"] * s) * Z0
    else:
        Z = Z0
    Z = min(Z, 0.95 * r)
    th1 = np.arccos(1 - Z / r)
    keq = soil["kc"] / b + soil["kphi"]
    thm = (mp["a1"] + mp["a2"] * s) * th1 if model == "stress" else 0.0

    def sig(th):
        if model == "stress" and th < thm:
            th_e = th1 - th / thm * (th1 - thm)
        else:
            th_e = th
        return keq * max(r * (np.cos(th_e) - np.cos(th1)), 0.0) ** n

    def tau(th):
        j = r * (th1 - th - (1 - s) * (np.sin(th1) - np.sin(th)))
        sg = sig(th)
        tp = np.tan(soil["phi"])
        if model == "moisture":
            tp = tp * (1 - mp["beta"] * np.exp(-sg / mp["sig_d"]))
        return (soil["c"] + sg * tp) * (1 - np.exp(-j / soil["K"]))

    pts = [thm] if model == "stress" else None
    kw = dict(limit=200, epsabs=1e-10, epsrel=1e-10)
    if pts:
        kw["points"] = pts
    a = quad(lambda t: tau(t) * np.cos(t), 0, th1, **kw)[0]
    bq = quad(lambda t: sig(t) * np.sin(t), 0, th1, **kw)[0]
    ct = quad(tau, 0, th1, **kw)[0]
    return r * b * (a - bq), r * r * b * ct


def soil_si(s):
    """Soil dict in SI from lab-style units (c_kpa, phi_deg, K_m, n, kc kN, kphi kN)."""
    return dict(c=s["c_kpa"] * 1e3, phi=np.radians(s["phi_deg"]), K=s["K_m"], n=s["n"],
                kc=s["kc"] * 1e3, kphi=s["kphi"] * 1e3)
