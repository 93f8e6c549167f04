"""foreign10: an independent, vectorised Wong wheel-soil model (paper Eqs. 1-10,
with the two corrections of hardware.md), the slip-sinkage forms (Eqs. 11-13),
the Wong-Reece normal-stress distribution, and the out-of-family soil/tyre
variants used by this generator.  Written from the seed paper and textbook
knowledge only; shares nothing with the project's code.

All quantities in SI: N, m, Pa, rad.  kc in N/m^(n+1), kphi in N/m^(n+2)
(the paper's kN values times 1000).
"""
import math
import numpy as np

G = 9.81

# ---------------------------------------------------------------------------
# tanh-sinh (double exponential) quadrature on [-1, 1]; robust against the
# (theta1 - theta)^n endpoint behaviour of the Bekker stress.
_H = 1.0 / 10.0
_K = np.arange(-34, 35)
_U = 0.5 * math.pi * np.sinh(_K * _H)
TS_X = np.tanh(_U)
TS_W = _H * 0.5 * math.pi * np.cosh(_K * _H) / np.cosh(_U) ** 2
# keep the nodes strictly inside (-1, 1)
_m = np.abs(TS_X) < 1.0 - 1e-15
TS_X, TS_W = TS_X[_m], TS_W[_m]


def soil_si(lab):
    """Terrain dict in the TOML's units -> SI dict."""
    return dict(kc=lab["kc"] * 1e3, kphi=lab["kphi"] * 1e3, n=lab["n"],
                c=lab["c_kpa"] * 1e3, phi=math.radians(lab["phi_deg"]),
                K=lab["K_m"])


def k_eq(soil, b):
    return soil["kc"] / b + soil["kphi"]


def z0_eq10(W, keq, N, r, b):
    """Paper Eq. 10 (Bekker's law with the corrected k_eq = kc/b + kphi):
    Z0 = [3W / ((3-N) (kc + b kphi) sqrt(2r))]^(2/(2N+1))."""
    W = np.maximum(W, 1.0)
    return (3.0 * W / ((3.0 - N) * b * keq * np.sqrt(2.0 * r))) ** (2.0 / (2.0 * N + 1.0))


# ---------------------------------------------------------------------------
def _integrate_pieces(bp, func):
    """bp: (S, P+1) breakpoints from 0 to theta1 (ascending, may repeat).
    func(theta (S, Q)) -> tuple of integrand arrays (S, Q).  Returns the
    tuple of integrals (S,)."""
    S, P1 = bp.shape
    ths, wts = [], []
    for p in range(P1 - 1):
        a = bp[:, p:p + 1]
        b = bp[:, p + 1:p + 2]
        half = 0.5 * (b - a)
        ths.append(0.5 * (a + b) + half * TS_X[None, :])
        wts.append(half * TS_W[None, :])
    th = np.concatenate(ths, axis=1)
    w = np.concatenate(wts, axis=1)
    vals = func(th)
    return tuple(np.sum(v * w, axis=1) for v in vals)


def _shear(j, tmax, K, eff):
    """Shear stress for shear displacement j (sign-symmetric).  Janosi-Hanamoto
    (paper Eq. 4) or, for the brittle soil, Wong's hump-shaped curve
    tau = tmax*Kr*{1 + [1/(Kr(1-1/e)) - 1] exp(1 - j/Kw)} (1 - exp(-j/Kw))."""
    aj = np.abs(j)
    if eff.get("kind") == "brittle_shear":
        Kr = eff["Kr"]
        Kw = eff["Kw_over_K"] * K
        f = Kr * (1.0 + (1.0 / (Kr * (1.0 - math.exp(-1.0))) - 1.0) * np.exp(1.0 - aj / Kw)) \
            * (1.0 - np.exp(-aj / Kw))
    else:
        f = 1.0 - np.exp(-aj / K)
    return np.sign(j) * tmax * f


def forces(s, W, soil, r, b, eff=None, omega=None, zf=None, rut_ratio=None,
           return_all=False):
    """Drawbar pull Dp, driving torque T (soil on wheel) and sinkage for slip s
    and normal load W (arrays, broadcast to 1-D).  soil: SI dict whose values
    may be arrays of the same length (soil varying along the track).
    eff: the effect dict of the run (only the soil/tyre part is used here).
    omega: wheel speed (rad/s) for the speed-sinkage effect.
    zf, rut_ratio: front-wheel rut depth and the sinkage ratio for the rut
    effect (see rut_table)."""
    eff = eff or {}
    kind = eff.get("kind", "none")
    s = np.atleast_1d(np.asarray(s, float))
    W = np.atleast_1d(np.asarray(W, float))
    S = max(s.size, W.size)
    s = np.broadcast_to(s, (S,)).copy()
    W = np.broadcast_to(W, (S,)).copy()
    sd = {k: np.broadcast_to(np.asarray(v, float), (S,)) for k, v in soil.items()}
    n = sd["n"]
    c = sd["c"]
    tphi = np.tan(sd["phi"])
    K = sd["K"]
    keq = sd["kc"] / b + sd["kphi"]
    sp = np.clip(s, 0.0, 1.0)             # slip-sinkage forms use s >= 0 only

    if kind == "reece_pressure":
        # Reece: sigma = (c k'c + gamma b k'phi) (z/b)^n  ->  for one width b this
        # is Bekker's law with k_eq' = (c k'c + gamma b k'phi) / b^n
        keq = (c * eff["kc_reece"] + eff["gamma"] * b * eff["kphi_reece"]) / b ** n

    N = n.copy()
    if kind == "slip_sinkage" and eff["form"] == "ding":
        N = n + eff["n1"] * sp                       # Eq. 13

    re = r                                            # radius of the contact arc
    Z0 = z0_eq10(W, keq, N, r, b)                     # Eq. 10
    hyst = np.zeros(S)
    if kind == "tyre_deflection":
        # Wong's flexible tyre: when the rigid-wheel peak pressure exceeds
        # p_gcr = p_inflation + p_carcass, the tyre flattens; its contact acts
        # like a rigid rim of a larger radius re whose peak ground pressure is
        # p_gcr (sinkage (p_gcr/keq)^(1/n)); re from Eq. 10 solved for r.
        pg = eff["p_inflation_kpa"] * 1e3 + eff["p_carcass_kpa"] * 1e3
        sig_max = keq * Z0 ** N
        Ze = (pg / keq) ** (1.0 / N)
        flex = sig_max > pg
        re_f = 0.5 * (3.0 * W / ((3.0 - N) * b * keq * Ze ** ((2.0 * N + 1.0) / 2.0))) ** 2
        re = np.where(flex, np.maximum(re_f, r), r)
        Z0 = np.where(flex, Ze, Z0)
        # tyre deflection (vertical), carcass flexing loss ~ deflection
        defl = np.where(flex, np.minimum(0.25 * r, W / (eff["tyre_kz_kn_m"] * 1e3)), 0.0)
        hyst = eff["hyst_coeff"] * W * defl / r
    else:
        re = np.full(S, r)
        defl = np.zeros(S)

    Z = Z0
    if kind == "slip_sinkage":
        f = eff["form"]
        if f == "vasilev":
            Z = Z0 + eff["H"] * sp                                  # Eq. 11
        elif f == "lyasko":
            Z = (1.0 + eff["m1"] * sp) / (1.0 - eff["m2"] * sp) * Z0  # Eq. 12
    if kind == "speed_sinkage":
        Z = Z0 * (1.0 + eff["kappa_s_per_m"] * r * np.abs(omega))
    if kind == "rut":
        Z = Z0 * rut_ratio                     # wheel-bottom depth below the virgin surface
    Z = np.minimum(Z, re * (1.0 - math.cos(math.radians(70.0))))
    th1 = np.arccos(1.0 - Z / re)               # Eq. 1

    # breakpoints of the piecewise stress
    if kind == "stress_distribution":
        thm = (eff["a1"] + eff["a2"] * sp) * th1
        bp = np.stack([np.zeros(S), thm, th1], axis=1)
    elif kind == "rut":
        fr = eff["overlap"]
        ku = eff["A_u"] * np.maximum(zf, 1e-4)
        pf = keq * np.maximum(zf, 0) ** n
        zs = np.maximum(zf - pf / ku, 0.0)
        # angles where the rim depth Z - re(1-cos th) equals zs and zf
        def ang(zz):
            return np.arccos(np.clip(1.0 - np.maximum(Z - zz, 0.0) / re, -1, 1))
        ths, thf = ang(zs), ang(zf)
        bp = np.sort(np.stack([np.zeros(S), thf, ths, th1], axis=1), axis=1)
    else:
        bp = np.stack([np.zeros(S), th1], axis=1)

    def integrand(th):
        c1 = np.cos(th1)[:, None]
        Nn = N[:, None]
        ke = keq[:, None]
        rr = re[:, None]
        if kind == "stress_distribution":
            tm = thm[:, None]
            t1 = th1[:, None]
            front = np.maximum(np.cos(th) - c1, 0.0)
            rear = np.maximum(np.cos(t1 - (th / np.maximum(tm, 1e-12)) * t1) - c1, 0.0)
            zeta = np.where(th >= tm, front, rear)
            sig = ke * (rr * zeta) ** Nn
        elif kind == "rut":
            z = np.maximum(Z[:, None] - rr * (1.0 - np.cos(th)), 0.0)
            virgin = ke * z ** Nn
            zfc, zsc, kuc = zf[:, None], zs[:, None], ku[:, None]
            reload = np.where(z <= zsc, 0.0, kuc * (z - zsc))
            rutsig = np.where(z <= zfc, reload, virgin)
            sig = eff["overlap"] * rutsig + (1.0 - eff["overlap"]) * virgin
        else:
            sig = ke * (rr * np.maximum(np.cos(th) - c1, 0.0)) ** Nn   # Eqs. 2-3 corrected
        sn1 = np.sin(th1)[:, None]
        j = rr * ((th1[:, None] - th) - (1.0 - s[:, None]) * (sn1 - np.sin(th)))   # Eq. 5
        tau = _shear(j, c[:, None] + sig * tphi[:, None], K[:, None], eff)      # Eq. 4
        return (sig * np.cos(th) + tau * np.sin(th),
                tau * np.cos(th) - sig * np.sin(th),
                tau)

    Iw, Id, It = _integrate_pieces(bp, integrand)
    Wm = re * b * Iw                      # Eq. 7
    Dp = re * b * Id                      # Eq. 8
    T = re * re * b * It                  # Eq. 9
    if kind == "tyre_deflection":
        T = (r - defl) * re * b * It      # shear acts at the deflected rolling radius
        Dp = Dp - hyst
        T = T + hyst * (r - defl)
    out = dict(Dp=Dp, T=T, Z=Z, th1=th1, W_model=Wm)
    if return_all:
        out.update(keq=keq, N=N, re=re, defl=defl)
    return out


# ---------------------------------------------------------------------------
def rut_ratio_table(soil, r, b, eff, Wgrid, zgrid):
    """Sinkage ratio for the rear wheel in the front wheel's rut: the wheel
    bottom depth from the vertical balance with the rut stress divided by the
    same balance on virgin soil; the run then uses Z = Z0(Eq. 10) * ratio,
    which reduces to Eq. 10 without a rut (zf = 0)."""
    Wg, Zg = np.meshgrid(Wgrid, zgrid, indexing="ij")
    Wf, zf = Wg.ravel(), Zg.ravel()
    base = {k: float(np.mean(v)) for k, v in soil.items()}

    def balance(zfv, eff_):
        lo = np.full(Wf.size, 1e-4)
        hi = np.full(Wf.size, 0.6 * r)
        for _ in range(45):
            mid = 0.5 * (lo + hi)
            # forces() expects Z from Eq.10 * ratio; pass ratio = mid/Z0
            Z0 = z0_eq10(Wf, base["kc"] / b + base["kphi"], base["n"], r, b)
            o = forces(np.zeros(Wf.size), Wf, base, r, b, eff_, zf=zfv,
                       rut_ratio=mid / Z0)
            big = o["W_model"] > Wf
            hi = np.where(big, mid, hi)
            lo = np.where(big, lo, mid)
        return 0.5 * (lo + hi)

    z_rut = balance(zf, eff)
    z_vir = balance(np.zeros_like(zf), dict(eff, overlap=0.0))
    return (z_rut / z_vir).reshape(Wg.shape)
