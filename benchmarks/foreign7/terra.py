"""foreign7 terramechanics physics (written independently from the seed paper).

Wong's rigid-wheel model (paper Eqs. 1-10, with the two typo fixes of
hardware.md):
    sigma(theta) = (kc/b + kphi) * z(theta)^n,   z(theta) = r (cos theta - cos theta1)
    tau(theta)   = (c + sigma tan phi) (1 - exp(-j/K))           (Janosi, Eq. 4)
    j(theta)     = r [theta1 - theta - (1 - s)(sin theta1 - sin theta)]   (Eq. 5)
    W  = r b (int sigma cos + int tau sin)                        (Eq. 7)
    Dp = r b (int tau cos - int sigma sin)                        (Eq. 8)
    T  = r^2 b int tau                                            (Eq. 9)
    Z0 = [3 W / (sqrt(2r) (kc + b kphi)(3 - n))]^(2/(2n+1))       (Eq. 10)
theta2 = 0 (no rear contact).  Slip-sinkage laws Eqs. 11-13.

Everything is SI inside: c in Pa, kc in N/m^(n+1), kphi in N/m^(n+2).
All functions are vectorised over samples (numpy broadcasting); the
integrals use Gauss-Legendre quadrature on two sub-intervals of the contact
arc (the split is placed at the kink of the integrand where there is one).
"""
import numpy as np

_GL_CACHE = {}


def _gl(m):
    if m not in _GL_CACHE:
        _GL_CACHE[m] = np.polynomial.legendre.leggauss(m)
    return _GL_CACHE[m]


def static_sinkage_eq10(W, r, b, kc, kphi, n):
    """Paper Eq. 10 (closed form of the vertical balance with sigma only,
    small-angle approximation).  SI units."""
    W = np.asarray(W, float)
    base = 3.0 * W / (np.sqrt(2.0 * r) * (kc + b * kphi) * (3.0 - n))
    return np.power(np.maximum(base, 0.0), 2.0 / (2.0 * n + 1.0))


def sinkage_law(W, s, r, b, kc, kphi, n, form=None, H=0.0, m1=0.0, m2=0.0, n1=0.0):
    """Sinkage and effective sinkage exponent for slip s (clipped to [0, 0.99]
    in the slip-sinkage term: a braked/skidding wheel gets static sinkage).
    Returns (Z, N)."""
    s = np.clip(np.asarray(s, float), 0.0, 0.99)
    n = np.asarray(n, float) + 0.0 * s
    if form in (None, "none"):
        return static_sinkage_eq10(W, r, b, kc, kphi, n), n
    if form == "vasilev":
        return static_sinkage_eq10(W, r, b, kc, kphi, n) + H * s, n
    if form == "lyasko":
        return (1 + m1 * s) / (1 - m2 * s) * static_sinkage_eq10(W, r, b, kc, kphi, n), n
    if form == "ding":
        N = n + n1 * s
        return static_sinkage_eq10(W, r, b, kc, kphi, N), N
    raise ValueError(form)


def shear_janosi(tmax, j, K):
    return tmax * np.sign(j) * (1.0 - np.exp(-np.abs(j) / K))


def shear_brittle(tmax, j, Kw, Kr):
    """Wong's shear curve with a hump (peak at j = Kw, residual Kr*tmax)."""
    a = np.abs(j)
    e = np.exp(1.0)
    f = Kr * (1.0 + (1.0 / (Kr * (1.0 - 1.0 / e)) - 1.0) * np.exp(1.0 - a / Kw)) * (1.0 - np.exp(-a / Kw))
    return tmax * np.sign(j) * f


def wheel_forces(s, Z, r, b, c, phi, K, n, kc, kphi, dist="wong", a1=0.4, a2=0.2,
                 shear="janosi", Kr=0.6, Kw=None, h_g=0.0, M=40):
    """Soil forces on a driven rigid wheel at slip s and sinkage Z (at the rim).

    dist:  "wong"  paper distribution (max of sigma at theta = 0, theta2 = 0)
           "wong_reece" Wong & Reece 1967: max at theta_m = (a1 + a2 s) theta1,
                  rear region sigma(theta) = sigma_front(theta1 - theta/theta_m (theta1 - theta_m))
    shear: "janosi" or "brittle" (hump, parameters Kw, Kr)
    h_g:   grouser height; shear then acts on the cylinder through the grouser
           tips (radius r + h_g), normal stress on the rim.
    Returns dict W, Dp, T (N, N, N m) and theta1.
    """
    s, Z, c, phi, K, n, kc, kphi = np.broadcast_arrays(*[np.asarray(v, float) for v in (s, Z, c, phi, K, n, kc, kphi)])
    shape = s.shape
    s, Z, c, phi, K, n, kc, kphi = [v.reshape(-1, 1) for v in (s, Z, c, phi, K, n, kc, kphi)]
    keq = kc / b + kphi
    Zc = np.clip(Z, 1e-9, 0.9 * r)
    th1 = np.arccos(1.0 - Zc / r)
    rs = r + h_g
    H = r - Zc                                  # axle height above the undisturbed surface
    th1s = np.arccos(np.clip(H / rs, -1, 1)) if h_g > 0 else th1
    if dist == "wong_reece":
        thm = np.clip((a1 + a2 * np.clip(s, 0, 1)) * th1, 0.02 * th1, 0.98 * th1)
        split = thm
    elif h_g > 0:
        split = th1
    else:
        split = 0.5 * th1
    x, w = _gl(M)
    x = x.reshape(1, -1)
    w = w.reshape(1, -1)
    # segment A [0, split], segment B [split, th1s]
    thA = 0.5 * split * (x + 1.0)
    wA = 0.5 * split * w
    thB = split + 0.5 * (th1s - split) * (x + 1.0)
    wB = 0.5 * (th1s - split) * w
    th = np.concatenate([thA, thB], axis=1)
    wt = np.concatenate([wA, wB], axis=1)
    cos1 = np.cos(th1)

    def sig_front(t):
        z = np.clip(r * (np.cos(t) - cos1), 0.0, None)
        return keq * np.power(z, n)

    if dist == "wong_reece":
        rear = th < thm
        teq = th1 - th / thm * (th1 - thm)
        sig = np.where(rear, sig_front(teq), sig_front(th))
    else:
        sig = sig_front(th)
    sig = np.where(th <= th1, sig, 0.0)
    # shear displacement along the shear surface (radius rs); slip of that surface
    one_minus_s_s = (1.0 - s) * r / rs
    j = rs * (th1s - th - one_minus_s_s * (np.sin(th1s) - np.sin(th)))
    tmax = c + sig * np.tan(phi)
    if shear == "brittle":
        tau = shear_brittle(tmax, j, Kw if Kw is not None else K, Kr)
    else:
        tau = shear_janosi(tmax, j, K)
    I_sc = np.sum(wt * sig * np.cos(th), axis=1)
    I_ss = np.sum(wt * sig * np.sin(th), axis=1)
    I_tc = np.sum(wt * tau * np.cos(th), axis=1)
    I_ts = np.sum(wt * tau * np.sin(th), axis=1)
    I_t = np.sum(wt * tau, axis=1)
    W = b * (r * I_sc + rs * I_ts)
    Dp = b * (rs * I_tc - r * I_ss)
    T = rs * rs * b * I_t
    return {"W": W.reshape(shape), "Dp": Dp.reshape(shape), "T": T.reshape(shape),
            "theta1": th1.reshape(shape)}


def bulldozing(Z, b, c, phi, gamma=16000.0, f_b=1.0):
    """Rankine passive-earth estimate of the frontal bulldozing resistance of the
    soil wedge pushed ahead of a sunk wheel, times an amplification factor f_b
    (berm height above the surface, wedge shape).  N."""
    Kp = np.tan(np.pi / 4 + phi / 2) ** 2
    return f_b * b * (2.0 * c * Z * np.sqrt(Kp) + 0.5 * gamma * Z * Z * Kp)


def soil_si(d):
    """Convert a TOML-like dict (kPa, deg, kN/m^...) to SI values."""
    return {"c": d["c_kpa"] * 1e3, "phi": np.radians(d["phi_deg"]), "K": d["K_m"],
            "n": d["n"], "kc": d["kc"] * 1e3, "kphi": d["kphi"] * 1e3}


def forces_simple(s, W, r, b, soil, form=None, sparams=None, dist="wong", **kw):
    """Convenience: steady-state Z, Dp, T for slip s and load W (SI soil dict)."""
    sp = sparams or {}
    Z, N = sinkage_law(W, s, r, b, soil["kc"], soil["kphi"], soil["n"], form, **sp)
    f = wheel_forces(s, Z, r, b, soil["c"], soil["phi"], soil["K"], N, soil["kc"], soil["kphi"], dist=dist, **kw)
    f["Z"] = Z
    return f
