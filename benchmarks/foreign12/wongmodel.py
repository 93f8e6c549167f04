"""foreign12: own implementation of Wong's rigid-wheel model (paper Eqs. 1-10, with
hardware.md's two corrections) plus the slip-sinkage forms (Eqs. 11-13), the
Wong-Reece stress distribution and the out-of-family soil variants used by gen.py.

Units inside: SI (Pa, N, m, rad).  Soil dict entries may be scalars or arrays
broadcastable to the slip array: c_kpa, phi_deg, K_m, n, kc (kN/m^(n+1)),
kphi (kN/m^(n+2)).
"""
import numpy as np

_GL_CACHE = {}


def nodes(nq):
    """Gauss-Legendre nodes on [0,1] mapped by the quintic smoothstep
    t = u^3 (10 - 15u + 6u^2), which clusters nodes at both ends and removes the
    (theta1-theta)^n endpoint singularities of the Bekker stress."""
    if nq not in _GL_CACHE:
        x, w = np.polynomial.legendre.leggauss(nq)
        u = 0.5 * (x + 1.0)
        wu = 0.5 * w
        t = u ** 3 * (10.0 - 15.0 * u + 6.0 * u * u)
        dt = 30.0 * u * u * (1.0 - u) ** 2
        _GL_CACHE[nq] = (t, wu * dt)
    return _GL_CACHE[nq]


def sinkage(W, r, b, soil, s, eff):
    """Total sinkage z (m) and the exponent N in use."""
    kind = eff.get("kind", "none")
    sp = np.clip(s, 0.0, 1.0)
    n = np.asarray(soil["n"], float)
    N = n + eff["n1"] * sp if kind == "ding" else n + 0.0 * sp
    kc = np.asarray(soil["kc"], float) * 1e3
    kphi = np.asarray(soil["kphi"], float) * 1e3
    # Eq. (10), D = 2r
    z0 = (3.0 * W / (np.sqrt(2.0 * r) * (kc + b * kphi) * (3.0 - N))) ** (2.0 / (2.0 * N + 1.0))
    if kind == "vasilev":          # Eq. (11)
        z = z0 + eff["H"] * sp
    elif kind == "lyasko":         # Eq. (12)
        z = z0 * (1.0 + eff["m1"] * sp) / (1.0 - eff["m2"] * sp)
    else:
        z = z0
    z = np.minimum(z, 0.8 * r)
    return z, N


def _stress_shear(th, th1, s, r, keq, N, c, tphi, K, region, eff, sig0=None, th_m=None, th2=None):
    """sigma and tau at angles th (arrays broadcast (M, nq))."""
    if region == "front":
        zz = np.maximum(r * (np.cos(th) - np.cos(th1)), 0.0)
        sig = keq * zz ** N
    elif region == "wr_rear":
        thq = th1 - (th / th_m) * (th1 - th_m)
        zz = np.maximum(r * (np.cos(thq) - np.cos(th1)), 0.0)
        sig = keq * zz ** N
    elif region == "rebound":
        sig = sig0 * np.maximum(np.cos(th) - np.cos(th2), 0.0) / (1.0 - np.cos(th2))
    else:
        raise ValueError(region)
    j = r * ((th1 - th) - (1.0 - s) * (np.sin(th1) - np.sin(th)))
    if eff.get("kind") == "curved_envelope":
        phi_eff = np.degrees(np.arctan(tphi)) - eff["dphi_per_decade"] * np.log10(
            1.0 + sig / (eff["sigma_ref_kpa"] * 1e3))
        tp = np.tan(np.radians(phi_eff))
    else:
        tp = tphi
    tau = (c + sig * tp) * (1.0 - np.exp(-np.abs(j) / K)) * np.sign(j)
    return sig, tau


def wheel(s, W, r, b, soil, eff=None, nq=64):
    """Return dict with Wint (Eq. 7), Dp (Eq. 8), T (Eq. 9), z, th1 for each sample.
    s: slip (Eq. 6), W: vertical load (N) that sets the sinkage via Eq. 10."""
    eff = eff or {"kind": "none"}
    s = np.atleast_1d(np.asarray(s, float))
    W = np.broadcast_to(np.asarray(W, float), s.shape)
    sh = s.shape
    soil = {k: np.broadcast_to(np.asarray(v, float), sh) for k, v in soil.items()}
    z, N = sinkage(W, r, b, soil, s, eff)
    th1 = np.arccos(1.0 - z / r)
    kc = soil["kc"] * 1e3
    kphi = soil["kphi"] * 1e3
    keq = kc / b + kphi                       # Bekker, corrected Eq. (2)
    c = soil["c_kpa"] * 1e3
    tphi = np.tan(np.radians(soil["phi_deg"]))
    K = soil["K_m"]
    t, w = nodes(nq)
    col = lambda a: np.asarray(a)[..., None]
    kind = eff.get("kind", "none")
    segs = []
    if kind == "stress_distribution":
        sp = np.clip(s, 0.0, 1.0)
        th_m = (eff["a1"] + eff["a2"] * sp) * th1
        segs.append((np.zeros(sh), th_m, "wr_rear"))
        segs.append((th_m, th1, "front"))
    else:
        th_m = None
        segs.append((np.zeros(sh), th1, "front"))
    th2 = sig0 = None
    if kind == "soil_rebound":
        th2 = np.arccos(1.0 - eff["rebound_ratio"] * z / r)
        sig0 = keq * z ** N
        segs.append((-th2, np.zeros(sh), "rebound"))
    Iv = np.zeros(sh); Ih = np.zeros(sh); It = np.zeros(sh)
    for a, bnd, reg in segs:
        L = bnd - a
        th = col(a) + col(L) * t
        ww = col(L) * w
        sig, tau = _stress_shear(th, col(th1), col(s), r, col(keq), col(N), col(c), col(tphi), col(K), reg, eff,
                                 sig0=None if sig0 is None else col(sig0),
                                 th_m=None if th_m is None else col(th_m),
                                 th2=None if th2 is None else col(th2))
        ct, st = np.cos(th), np.sin(th)
        Iv += np.sum(ww * (sig * ct + tau * st), axis=-1)
        Ih += np.sum(ww * (tau * ct - sig * st), axis=-1)
        It += np.sum(ww * tau, axis=-1)
    return {"Wint": r * b * Iv, "Dp": r * b * Ih, "T": r * r * b * It, "z": z, "th1": th1, "N": N}
