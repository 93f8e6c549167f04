"""foreign8 terramechanics: rigid wheel on Bekker/Janosi soil (paper Eqs. 1-13).

Written blind from the seed paper and hardware.md.  Units: SI (N, m, Pa, rad).
Typos fixed per hardware.md: sigma = (kc/b + kphi) z^n, z(theta) = r(cos theta - cos theta1).

Static sinkage law (decision): Eq. (10) with W = the wheel's instantaneous
vertical load; slip sinkage models modify that sinkage (Eqs. 11-13).

Quadrature: our own Gauss-Legendre rule on [0, theta1] (or on [0, theta_m] and
[theta_m, theta1] for the Wong-Reece distribution), vectorised over samples.
check.py compares it with scipy.integrate.quad.
"""
import numpy as np

NODES = 96
_X, _WT = np.polynomial.legendre.leggauss(NODES)


def gl_nodes(a, b):
    """Nodes (..., NODES) and weights for the intervals [a, b] (arrays)."""
    a = np.asarray(a, float)[..., None]
    b = np.asarray(b, float)[..., None]
    half = 0.5 * (b - a)
    th = a + half * (_X + 1.0)
    w = half * _WT
    return th, w


def soil_si(s):
    """Terrain dict in lab units (kPa, deg, kN/m^(n+1), kN/m^(n+2)) -> SI."""
    return dict(c=s["c_kpa"] * 1e3, phi=np.radians(s["phi_deg"]), K=s["K_m"], n=s["n"],
                kc=s["kc"] * 1e3, kphi=s["kphi"] * 1e3)


def sinkage_eq10(W, r, b, kc, kphi, n):
    """Paper Eq. (10): static sinkage of a rigid wheel (Wong)."""
    W = np.maximum(np.asarray(W, float), 1.0)
    base = 3.0 * W / (np.sqrt(2.0 * r) * (kc + b * kphi) * (3.0 - n))
    return base ** (2.0 / (2.0 * n + 1.0))


def forces(s, W, soil, wheel, eff=None, vslip=None, return_parts=False):
    """Drawbar pull Dp, torque T, model vertical load Wm and sinkage z0 of the
    rigid wheel at slip s (array) under vertical load W (array).

    soil: SI dict (c, phi, K, n, kc, kphi) - values may be arrays (drift).
    wheel: dict r, b.
    eff: hidden-effect options (dict):
      sinkage: 'wong' | 'vasilev' (H) | 'lyasko' (m1, m2) | 'ding' (n1)
      stress:  'bekker' | 'wong_reece' (a1, a2)
      shear:   'janosi' | 'softening' (Kr, Kw) | 'rate' (beta, v0)
      r_soil_factor: equivalent rigid radius of a flexible tyre (soil side)
      hardpan_h: depth of a hard layer (sinkage saturates at it)
      bulldoze: factor on Bekker-type bulldozing resistance
    """
    eff = eff or {}
    s = np.asarray(s, float)
    W = np.asarray(W, float)
    s, W = np.broadcast_arrays(s, W)
    r = wheel["r"] * eff.get("r_soil_factor", 1.0)
    b = wheel["b"]
    c = np.broadcast_to(np.asarray(soil["c"], float), s.shape)
    phi = np.broadcast_to(np.asarray(soil["phi"], float), s.shape)
    K = np.broadcast_to(np.asarray(soil["K"], float), s.shape)
    n = np.broadcast_to(np.asarray(soil["n"], float), s.shape)
    kc = np.broadcast_to(np.asarray(soil["kc"], float), s.shape)
    kphi = np.broadcast_to(np.asarray(soil["kphi"], float), s.shape)

    sp = np.clip(s, 0.0, 0.99)          # slip sinkage acts on driving slip only
    mode = eff.get("sinkage", "wong")
    N = n
    if mode == "ding":                    # Eq. (13): N = n + n1 s replaces n
        N = n + eff["n1"] * sp
    z0 = sinkage_eq10(W, r, b, kc, kphi, N)
    if mode == "vasilev":                 # Eq. (11)
        z0 = z0 + eff["H"] * sp
    elif mode == "lyasko":                # Eq. (12)
        z0 = z0 * (1.0 + eff["m1"] * sp) / (1.0 - eff["m2"] * sp)
    h = eff.get("hardpan_h")
    if h:                                 # hard layer: sinkage saturates at h
        z0 = h * np.tanh(z0 / h)
    z0 = np.minimum(z0, 0.95 * r)
    th1 = np.arccos(1.0 - z0 / r)         # Eq. (1)
    keq = kc / b + kphi                   # Eq. (2), typo fixed

    def sigma_front(th, th1_, N_, keq_):
        zz = np.maximum(r * (np.cos(th) - np.cos(th1_)), 0.0)   # Eq. (3), typo fixed
        return keq_ * zz ** N_

    def shear(th, sig, th1_, s_, c_, phi_, K_, vs_):
        j = r * ((th1_ - th) - (1.0 - s_) * (np.sin(th1_) - np.sin(th)))    # Eq. (5)
        tmax = c_ + sig * np.tan(phi_)
        sh = eff.get("shear", "janosi")
        aj = np.abs(j)
        if sh == "softening":             # Wong's hump-shaped (brittle) shear curve
            Kr, Kw = eff["Kr"], eff["Kw"]
            f = Kr * (1.0 + (1.0 / (Kr * (1.0 - np.exp(-1.0))) - 1.0) * np.exp(1.0 - aj / Kw)) \
                * (1.0 - np.exp(-aj / Kw))
        else:                             # Janosi-Hanamoto, Eq. (4), odd in j
            f = 1.0 - np.exp(-aj / K_)
        tau = np.sign(j) * tmax * f
        if sh == "rate":                  # viscous soil: strength grows with shear rate
            tau = tau * (1.0 + eff["beta"] * np.log10(1.0 + np.abs(vs_) / eff["v0"]))
        return tau

    E = lambda a: a[..., None]
    vs = np.zeros_like(s) if vslip is None else np.broadcast_to(np.asarray(vslip, float), s.shape)
    stress = eff.get("stress", "bekker")
    parts = []
    if stress == "wong_reece":
        thm = (eff["a1"] + eff["a2"] * sp) * th1
        # front region theta_m..theta1: Bekker; rear region 0..theta_m mapped
        thf, wf = gl_nodes(thm, th1)
        sf = sigma_front(thf, E(th1), E(N), E(keq))
        parts.append((thf, wf, sf))
        thr, wr = gl_nodes(np.zeros_like(th1), thm)
        with np.errstate(invalid="ignore", divide="ignore"):
            thr_eq = E(th1) - thr / np.maximum(E(thm), 1e-12) * (E(th1) - E(thm))
        sr = sigma_front(thr_eq, E(th1), E(N), E(keq))
        parts.append((thr, wr, sr))
    else:
        th, w = gl_nodes(np.zeros_like(th1), th1)
        parts.append((th, w, sigma_front(th, E(th1), E(N), E(keq))))

    Wm = np.zeros_like(s)
    Dp = np.zeros_like(s)
    T = np.zeros_like(s)
    for th, w, sig in parts:
        tau = shear(th, sig, E(th1), E(s), E(c), E(phi), E(K), E(vs))
        Wm += r * b * np.sum(w * (sig * np.cos(th) + tau * np.sin(th)), axis=-1)   # Eq. (7)
        Dp += r * b * np.sum(w * (tau * np.cos(th) - sig * np.sin(th)), axis=-1)   # Eq. (8)
        T += r * r * b * np.sum(w * tau, axis=-1)                                   # Eq. (9)
    bd = eff.get("bulldoze")
    if bd:
        # Bekker-type bulldozing of the soil wedge in front of the wheel
        # (Kpc ~ 10, Kpg ~ 4, gamma ~ 16 kN/m^3), scaled by `bd`.
        Rb = b * (0.67 * c * z0 * 10.0 + 0.5 * z0 ** 2 * 16e3 * 4.0)
        Dp = Dp - bd * Rb
    if return_parts:
        return Dp, T, Wm, z0, parts
    return Dp, T, Wm, z0
