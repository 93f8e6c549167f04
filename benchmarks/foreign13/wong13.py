"""foreign13: an independent implementation of Wong's rigid-wheel model.

Paper Eqs. 1-10 with the two typos fixed (hardware.md):
    sigma(z) = (kc/b + kphi) z^n,   z(theta) = r (cos theta - cos theta1)
Janosi-Hanamoto shear  tau = (c + sigma tan phi)(1 - exp(-j/K)),
    j(theta) = r [theta1 - theta - (1 - s)(sin theta1 - sin theta)]
W  = r b  int_0^th1 (sigma cos + tau sin) dtheta
Dp = r b  int_0^th1 (tau cos - sigma sin) dtheta
T  = r^2 b int_0^th1 tau dtheta
(theta2 = 0).  Quadrature: Gauss-Legendre on [0, theta1] (split at theta_m for
the Wong-Reece distribution).  The entrance angle is found from the vertical
balance (Eq. 7 = measured load, shear term included); the paper's slip
sinkage forms (Eqs. 11-13) then modify the sinkage.

Everything is vectorised over points: pass arrays of shape (M,) (or scalars).
Units: SI (Pa, N/m^(n+1), N/m^(n+2), m, rad, N, N m).

`law` (dict) selects the physics; keys (all optional):
  wr     = (a1, a2)            Wong-Reece normal stress with a rear region
  ss     = ("vasilev", H) | ("lyasko", m1, m2) | ("ding", n1)
  smooth = (c_a, delta)        tyre-soil interface limit tau <= c_a + sigma tan(delta)
  crust  = (Ak, Ac, h)         stiffness and cohesion x (1 + A exp(-z/h))
  snow   = dict(z=..., sig=..., c=, phi=, K=)   snow layer on the soil (series)
  rut    = dict(Au=..., kappa=...)  rear wheel in the front wheel's rut
                               (Wong's unloading-reloading line k_u = Au z_u,
                               residual shear displacement kappa * j_front(0));
                               needs per-point 'Wf' (load of the front wheel) in P
"""
import math
import numpy as np

NQ = 64
_X, _WQ = np.polynomial.legendre.leggauss(NQ)
TH1_MAX = 1.25          # rad; beyond this the vehicle bellies


def lab_soil(lab, b):
    """Lab TOML dict -> SI parameter dict for a wheel of width b."""
    kc = lab["kc_kn"] * 1e3
    kphi = lab["kphi_kn"] * 1e3
    return dict(c=lab["c_kpa"] * 1e3, phi=math.radians(lab["phi_deg"]),
                K=lab["K_m"], n=lab["n"], kc=kc, kphi=kphi, keq=kc / b + kphi)


def _col(v, M):
    a = np.asarray(v, dtype=float)
    if a.ndim == 0:
        a = np.full(M, float(a))
    return a.reshape(M, 1)


def _nodes(lo, hi):
    """GL nodes/weights on [lo, hi] (column arrays (M,1)) -> (M,NQ) each."""
    half = 0.5 * (hi - lo)
    th = lo + half * (_X[None, :] + 1.0)
    w = half * _WQ[None, :]
    return th, w


def stresses(th, th_eq, th1, s, P, law, r, z_override=None):
    """Normal and shear stress at contact angles th (M,Q).

    th_eq: the angle whose geometric sinkage gives sigma (== th except in the
    Wong-Reece rear region).  Returns sigma, tau (M,Q)."""
    z = r * np.clip(np.cos(th_eq) - np.cos(th1), 0.0, None)
    keq, n = P["keq"], P["n"]
    c, tphi, K = P["c"], np.tan(P["phi"]), P["K"]
    j = r * ((th1 - th) - (1.0 - s) * (np.sin(th1) - np.sin(th)))
    if "crust" in law:
        Ak, Ac, h = law["crust"]
        e = np.exp(-z / h)
        sig = keq * z ** n * (1.0 + Ak * e)
        c = c * (1.0 + Ac * e)
    elif "snow" in law:
        sn = law["snow"]
        sig = np.interp(z, sn["z"], sn["sig"])
    elif "rut" in law:
        zfl, reb, ku, jres = P["zfloor"], P["rebound"], P["ku"], P["jres"]
        sig = np.where(z < reb, ku * z, keq * (zfl + z) ** n)
        j = j + jres
    else:
        sig = keq * z ** n
    tau = (c + sig * tphi) * (1.0 - np.exp(-j / K))
    if "snow" in law:
        sn = law["snow"]
        tau_s = (sn["c"] + sig * math.tan(sn["phi"])) * (1.0 - np.exp(-j / sn["K"]))
        tau = np.minimum(tau, tau_s)
    if "smooth" in law:
        ca, dl = law["smooth"]
        tau = np.minimum(tau, ca + sig * math.tan(dl))
    return sig, tau


def integrate(th1, s, P, law, r, b):
    """W, Dp, T for entrance angles th1 (M,), slips s (M,), params P."""
    th1 = np.atleast_1d(np.asarray(th1, float))
    M = th1.size
    th1c = th1.reshape(M, 1)
    sc = _col(s, M)
    Pc = {k: _col(v, M) for k, v in P.items()}
    if "wr" in law:
        a1, a2 = law["wr"]
        thm = np.clip((a1 + a2 * np.clip(sc, 0.0, 1.0)) * th1c, 1e-9, None)
        thm = np.minimum(thm, th1c)
        # front region [thm, th1]: geometric sinkage
        tf, wf = _nodes(thm, th1c)
        # rear region [0, thm]: equivalent angle th1 - th/thm (th1 - thm)
        tr, wr_ = _nodes(np.zeros_like(thm), thm)
        teq = th1c - tr / thm * (th1c - thm)
        th = np.concatenate([tr, tf], axis=1)
        the = np.concatenate([teq, tf], axis=1)
        wq = np.concatenate([wr_, wf], axis=1)
    elif "rut" in law:
        # split where the reloading line meets the virgin curve (kink of sigma)
        ck = np.cos(th1c) + Pc["rebound"] / r
        thk = np.where(ck < 1.0, np.arccos(np.clip(ck, -1.0, 1.0)), 0.0)
        thk = np.clip(thk, 0.0, th1c)
        t1, w1 = _nodes(np.zeros_like(thk), thk)
        t2, w2 = _nodes(thk, th1c)
        th = np.concatenate([t1, t2], axis=1)
        wq = np.concatenate([w1, w2], axis=1)
        the = th
    else:
        th, wq = _nodes(np.zeros_like(th1c), th1c)
        the = th
    sig, tau = stresses(th, the, th1c, sc, Pc, law, r)
    ct, st = np.cos(th), np.sin(th)
    W = r * b * np.sum((sig * ct + tau * st) * wq, axis=1)
    Dp = r * b * np.sum((tau * ct - sig * st) * wq, axis=1)
    T = r * r * b * np.sum(tau * wq, axis=1)
    return W, Dp, T


def balance_theta1(Wt, s, P, law, r, b, iters=11):
    """Entrance angle with model vertical load == Wt (vectorised Illinois
    false position inside a bracket from Eq. 10's sinkage).  NaN where even
    TH1_MAX cannot carry the load."""
    Wt = np.atleast_1d(np.asarray(Wt, float))
    M = Wt.size
    s = np.broadcast_to(np.asarray(s, float), (M,)).copy()
    keq = np.broadcast_to(np.asarray(P["keq"], float), (M,))
    n = np.broadcast_to(np.asarray(P["n"], float), (M,))
    z10 = (3.0 * Wt / ((3.0 - n) * b * keq * math.sqrt(2.0 * r))) ** (2.0 / (2.0 * n + 1.0))
    g = np.arccos(np.clip(1.0 - z10 / r, -1.0, 1.0))
    lo = np.clip(0.6 * g, 1e-4, TH1_MAX)
    hi = np.clip(1.6 * g, 1e-4, TH1_MAX)
    flo = integrate(lo, s, P, law, r, b)[0] - Wt
    fhi = integrate(hi, s, P, law, r, b)[0] - Wt
    m = flo > 0
    if m.any():
        lo[m] = 1e-4
        flo[m] = -Wt[m]
    m = fhi < 0
    if m.any():
        hi[m] = TH1_MAX
        fhi[m] = integrate(hi, s, P, law, r, b)[0][m] - Wt[m]
    bad = fhi < 0
    side = np.zeros(M)
    for _ in range(iters):
        den = fhi - flo
        x = np.where(den > 0, (lo * fhi - hi * flo) / np.where(den > 0, den, 1.0), 0.5 * (lo + hi))
        x = np.clip(x, lo, hi)
        fx = integrate(x, s, P, law, r, b)[0] - Wt
        up = fx < 0
        # Illinois: halve the retained end's value when the same side is kept twice
        lo_new = np.where(up, x, lo)
        hi_new = np.where(up, hi, x)
        flo_new = np.where(up, fx, np.where(side < 0, 0.5 * flo, flo))
        fhi_new = np.where(up, np.where(side > 0, 0.5 * fhi, fhi), fx)
        side = np.where(up, 1.0, -1.0)
        lo, hi, flo, fhi = lo_new, hi_new, flo_new, fhi_new
    th1 = np.where(np.abs(flo) < np.abs(fhi), lo, hi)
    th1[bad] = np.nan
    return th1


def rut_state(Wf, s, P, r, b, Au):
    """State of the rut left by a front wheel of load Wf at slip s (virgin
    Bekker soil), Wong's unloading/reloading: k_u = Au * z_u (k0 = 0)."""
    th1f = balance_theta1(Wf, s, P, {}, r, b)
    zf = r * (1.0 - np.cos(th1f))
    keq = np.asarray(P["keq"], float)
    n = np.asarray(P["n"], float)
    sig_u = keq * zf ** n
    ku = Au * zf
    reb = sig_u / ku
    jres = r * (th1f - (1.0 - np.asarray(s)) * np.sin(th1f))
    return dict(zfloor=zf - reb, rebound=reb, ku=ku, jres=np.clip(jres, 0.0, None), zf=zf)


def wheel(W, s, P, law, r, b):
    """Forces of a wheel carrying load W at slip s.  Returns dict with
    Dp, T, th1 (entrance angle used), z (sinkage), z0 (balance sinkage)."""
    W = np.atleast_1d(np.asarray(W, float))
    M = W.size
    s = np.broadcast_to(np.asarray(s, float), (M,)).copy()
    P = {k: np.broadcast_to(np.asarray(v, float), (M,)).copy() for k, v in P.items()}
    law = dict(law)
    ss = law.pop("ss", None)
    if ss is not None and ss[0] == "ding":
        P["n"] = P["n"] + ss[1] * np.clip(s, 0.0, None)
    if "rut" in law:
        st = rut_state(P.pop("Wf"), s, P, r, b, law["rut"]["Au"])
        st["jres"] = st["jres"] * law["rut"].get("kappa", 1.0)
        for k in ("zfloor", "rebound", "ku", "jres"):
            P[k] = st[k]
    th0 = balance_theta1(W, s, P, law, r, b)
    z0 = r * (1.0 - np.cos(th0))
    z = z0
    if ss is not None and ss[0] in ("vasilev", "lyasko"):
        sp = np.clip(s, 0.0, None)
        if ss[0] == "vasilev":
            z = z0 + ss[1] * sp
        else:
            z = (1.0 + ss[1] * sp) / (1.0 - ss[2] * sp) * z0
    zmax = r * (1.0 - math.cos(TH1_MAX))
    z = np.minimum(z, zmax)
    th1 = np.arccos(1.0 - z / r)
    Wm, Dp, T = integrate(th1, s, P, law, r, b)
    return dict(Dp=Dp, T=T, th1=th1, z=z, z0=z0, Wmodel=Wm)


def snow_table(P, sn):
    """sigma(z) for a snow layer (Wong: p = -p_w ln(1 - z/z_w)) in series
    with the Bekker soil: z = z_w (1 - exp(-p/p_w)) + (p/keq)^(1/n)."""
    p = np.concatenate([[0.0], np.geomspace(1.0, 2e6, 3000)])
    z = sn["zw"] * (1.0 - np.exp(-p / sn["pw"])) + (p / P["keq"]) ** (1.0 / P["n"])
    return z, p
