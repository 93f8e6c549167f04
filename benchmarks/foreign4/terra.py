"""foreign4 wheel-soil physics (written from hardware.md and the seed paper only).

Wong's rigid-wheel model, paper Eqs. 1-10, with the two typos fixed:
  sigma = (kc/b + kphi) z^n              (Eq. 2, Bekker)
  z(theta) = r (cos theta - cos theta1)   (Eq. 3)
plus
  * the three slip-sinkage forms (Eqs. 11-13),
  * Wong & Reece's normal-stress distribution with a rear region,
    theta_m = (a1 + a2 s) theta1,
  * out-of-family physics: a partial rut from an earlier pass, a soft tyre
    whose contact patch is that of a larger equivalent rigid wheel.

Units inside this module are SI: Pa, m, N, rad.  Soil dictionaries:
  c [Pa], phi [rad], K [m], n [-], kc [N/m^(n+1)], kphi [N/m^(n+2)].

Two integrators are provided:
  * forces_quad  : scipy.integrate.quad (adaptive), scalar, the reference;
  * forces_gl    : vectorised Gauss-Legendre with a power substitution that
                   removes the (theta1-theta)^n endpoint singularity; used by
                   the generator and verified against forces_quad in check.py.
"""
import math
import numpy as np
from scipy import integrate

G = 9.81


def soil_from_field_units(d):
    """TOML-style field units -> SI dict."""
    return dict(c=d["c_kpa"] * 1e3, phi=np.radians(d["phi_deg"]), K=d["K_m"],
                n=d["n"], kc=d["kc"] * 1e3, kphi=d["kphi"] * 1e3)


# ----------------------------------------------------------------- sinkage --
def z0_static(W, r, b, n, kc, kphi):
    """Paper Eq. (10): static sinkage of a rigid wheel (W in N)."""
    W = np.maximum(np.asarray(W, float), 1.0)
    return (3.0 * W / (np.sqrt(2.0 * r) * (kc + b * kphi) * (3.0 - n))) ** (2.0 / (2.0 * n + 1.0))


def sinkage(W, s, soil, r, b, opts):
    """Sinkage Z (m) and the sinkage exponent actually in force (for Ding).

    opts['model']: 'wong' | 'vasilev' | 'lyasko' | 'ding'
    opts['r_contact']: equivalent rigid radius of the contact (soft tyre)
    """
    model = opts.get("model", "wong")
    rc = opts.get("r_contact", r)
    s = np.asarray(s, float)
    sp = np.clip(s, 0.0, 1.0)          # slip sinkage only under driving slip
    n = soil["n"]
    if model == "ding":
        n = n + opts["n1"] * sp
    Z0 = z0_static(W, rc, b, n, soil["kc"], soil["kphi"])
    if model == "vasilev":
        Z = Z0 + opts["H"] * sp
    elif model == "lyasko":
        Z = (1.0 + opts["m1"] * sp) / (1.0 - opts["m2"] * sp) * Z0
    else:
        Z = Z0
    return Z, n


# ------------------------------------------------------ stress distribution --
def _sigma(theta, theta1, thetam, r, b, n, kc, kphi, wr):
    keq = kc / b + kphi
    if wr:
        # Wong & Reece: rear region maps theta in [0, theta_m] onto the
        # equivalent front angle theta1 - theta/theta_m*(theta1-theta_m)
        th_eq = np.where(theta >= thetam, theta,
                         theta1 - theta / np.maximum(thetam, 1e-12) * (theta1 - thetam))
    else:
        th_eq = theta
    z = r * (np.cos(th_eq) - np.cos(theta1))
    return keq * np.maximum(z, 0.0) ** n


def _tau(theta, theta_in, sig, r, s, c, phi, K):
    j = r * ((theta_in - theta) - (1.0 - s) * (np.sin(theta_in) - np.sin(theta)))
    # symmetric Janosi law so that a skidding wheel (j < 0) gets negative shear
    return np.sign(j) * (c + sig * np.tan(phi)) * (1.0 - np.exp(-np.abs(j) / K))


# ------------------------------------------------------------ GL integrator --
_NGL = 40
_t, _w = np.polynomial.legendre.leggauss(_NGL)
_T01 = 0.5 * (_t + 1.0)
_W01 = 0.5 * _w
_P = 3.0   # power substitution exponent


def _nodes_sing_hi(a, bnd):
    """Nodes/weights on [a, bnd] clustering at bnd: theta = bnd - L u^P."""
    L = (bnd - a)[..., None]
    u = _T01[None, :]
    th = bnd[..., None] - L * u ** _P
    wt = L * _P * u ** (_P - 1.0) * _W01[None, :]
    return th, wt


def _nodes_sing_lo(a, bnd):
    """Nodes/weights on [a, bnd] clustering at a: theta = a + L u^P."""
    L = (bnd - a)[..., None]
    u = _T01[None, :]
    th = a[..., None] + L * u ** _P
    wt = L * _P * u ** (_P - 1.0) * _W01[None, :]
    return th, wt


def _nodes_plain(a, bnd):
    L = (bnd - a)[..., None]
    th = a[..., None] + L * _T01[None, :]
    wt = L * _W01[None, :]
    return th, wt


def _bc(x, N):
    return np.broadcast_to(np.asarray(x, float), (N,)).astype(float)


def _strip_gl(Z, s, r, b, n, c, phi, K, kc, kphi, wr, a1, a2, zcut=None):
    """Integrals for one contact strip (vectorised over samples).

    zcut: if given, the strip is a rut of depth zcut: the soil surface is
    lower by zcut, contact only where r(1-cos th) < Z - zcut, and the soil
    in the rut responds as pre-loaded soil (stress = Bekker at the depth
    below the ORIGINAL surface, i.e. reloading follows the virgin curve).
    Returns (Wint, Dint, Tint) = (int s cos + t sin, int t cos - s sin, int t).
    """
    theta1 = np.arccos(np.clip(1.0 - Z / r, -1.0, 1.0))
    N = theta1.shape[0]
    if zcut is None:
        theta_in = theta1
    else:
        zz = np.maximum(Z - zcut, 0.0)
        theta_in = np.arccos(np.clip(1.0 - zz / r, -1.0, 1.0))
    zero = np.zeros(N)
    if wr and zcut is None:
        thm = np.clip(a1 + a2 * np.clip(s, 0.0, 1.0), 0.0, 1.0) * theta1
        segs = [_nodes_sing_lo(zero, thm), _nodes_sing_hi(thm, theta1)]
    elif zcut is None:
        thm = theta1
        segs = [_nodes_sing_hi(zero, theta1)]
    else:
        thm = theta1
        segs = [_nodes_plain(zero, theta_in)]
    Wi = np.zeros(N); Di = np.zeros(N); Ti = np.zeros(N)
    n_ = n[:, None]; s_ = s[:, None]
    for th, wt in segs:
        sig = _sigma(th, theta1[:, None], thm[:, None], r, b, n_, kc[:, None], kphi[:, None],
                     wr and zcut is None)
        tau = _tau(th, theta_in[:, None], sig, r, s_, c[:, None], phi[:, None], K[:, None])
        ct, st = np.cos(th), np.sin(th)
        Wi += np.sum((sig * ct + tau * st) * wt, axis=1)
        Di += np.sum((tau * ct - sig * st) * wt, axis=1)
        Ti += np.sum(tau * wt, axis=1)
    return Wi, Di, Ti


def forces_gl(Z, s, soil, r, b, opts, n_override=None):
    """Vectorised Eqs. (7)-(9). Z, s arrays; soil values scalars or arrays.

    Returns dict W (Eq. 7), Dp (Eq. 8), T (Eq. 9) in N, N, N m.
    opts: wr=(a1,a2) or None; r_contact (soft tyre; torque arm stays r);
          rut=(fraction_of_width, depth_m) or None.
    """
    Z = np.atleast_1d(np.asarray(Z, float))
    N = Z.shape[0]
    s = _bc(s, N)
    rr = r
    rc = opts.get("r_contact", r)
    n = _bc(soil["n"] if n_override is None else n_override, N)
    c = _bc(soil["c"], N); phi = _bc(soil["phi"], N); K = _bc(soil["K"], N)
    kc = _bc(soil["kc"], N); kphi = _bc(soil["kphi"], N)
    wr = opts.get("wr")
    a1, a2 = (wr if wr else (0.0, 0.0))
    rut = opts.get("rut")
    if rut:
        f, zr = rut
        W1, D1, T1 = _strip_gl(Z, s, rc, b, n, c, phi, K, kc, kphi, bool(wr), a1, a2)
        W2, D2, T2 = _strip_gl(Z, s, rc, b, n, c, phi, K, kc, kphi, False, a1, a2, zcut=zr)
        Wi = (1 - f) * W1 + f * W2; Di = (1 - f) * D1 + f * D2; Ti = (1 - f) * T1 + f * T2
    else:
        Wi, Di, Ti = _strip_gl(Z, s, rc, b, n, c, phi, K, kc, kphi, bool(wr), a1, a2)
    return dict(W=rc * b * Wi, Dp=rc * b * Di, T=rr * rc * b * Ti)


# ---------------------------------------------------------- quad reference --
def forces_quad(Z, s, soil, r, b, opts, n_override=None):
    """Scalar reference by scipy.integrate.quad (adaptive)."""
    rc = opts.get("r_contact", r)
    n = soil["n"] if n_override is None else n_override
    c, phi, K, kc, kphi = soil["c"], soil["phi"], soil["K"], soil["kc"], soil["kphi"]
    wr = opts.get("wr")
    rut = opts.get("rut")

    def strip(zcut, use_wr):
        th1 = math.acos(max(-1.0, min(1.0, 1.0 - Z / rc)))
        if zcut is None:
            thin = th1
        else:
            thin = math.acos(max(-1.0, min(1.0, 1.0 - max(Z - zcut, 0.0) / rc)))
        if use_wr:
            thm = min(max(wr[0] + wr[1] * min(max(s, 0.0), 1.0), 0.0), 1.0) * th1
        else:
            thm = th1

        def sig(th):
            return float(_sigma(np.array(th), th1, thm, rc, b, n, kc, kphi, use_wr))

        def tau(th):
            return float(_tau(np.array(th), thin, sig(th), rc, s, c, phi, K))

        pts = [thm] if (use_wr and 0 < thm < thin) else None
        kw = dict(limit=200, epsabs=1e-10, epsrel=1e-10, points=pts)
        Wi = integrate.quad(lambda t: sig(t) * math.cos(t) + tau(t) * math.sin(t), 0, thin, **kw)[0]
        Di = integrate.quad(lambda t: tau(t) * math.cos(t) - sig(t) * math.sin(t), 0, thin, **kw)[0]
        Ti = integrate.quad(tau, 0, thin, **kw)[0]
        return Wi, Di, Ti

    if rut:
        f, zr = rut
        a = strip(None, bool(wr)); bb = strip(zr, False)
        Wi, Di, Ti = [(1 - f) * x + f * y for x, y in zip(a, bb)]
    else:
        Wi, Di, Ti = strip(None, bool(wr))
    return dict(W=rc * b * Wi, Dp=rc * b * Di, T=r * rc * b * Ti)


# ------------------------------------------------------------- rut sinkage --
def rut_sinkage(W, r, b, soil, f, zr, n=None):
    """Sinkage (below the ORIGINAL surface) of a wheel whose width fraction f
    runs in a rut of depth zr, with the same plate approximation as Eq. (10):
    W = b keq [ (1-f) (3-n)/3 sqrt(D) Z^(n+1/2) + f Z^n (l - n l^3/(3 D Z)) ],
    l = sqrt(D (Z - zr)).  Solved by bisection (vectorised)."""
    n = soil["n"] if n is None else n
    keq = soil["kc"] / b + soil["kphi"]
    D = 2.0 * r
    W = np.atleast_1d(np.asarray(W, float))

    def load(Z):
        l = np.sqrt(D * np.maximum(Z - zr, 0.0))
        lr = Z ** n * (l - n * l ** 3 / (3.0 * D * np.maximum(Z, 1e-9)))
        lv = (3.0 - n) / 3.0 * math.sqrt(D) * Z ** (n + 0.5)
        return b * keq * ((1 - f) * lv + f * lr)

    lo = np.full_like(W, 1e-5); hi = np.full_like(W, 0.6)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        big = load(mid) > W
        hi = np.where(big, mid, hi); lo = np.where(big, lo, mid)
    return 0.5 * (lo + hi)


# ------------------------------------------------------------ full wheel ----
def wheel(W, s, soil, r, b, opts):
    """Dp, T, Z for load W (N) and slip s under the options (vectorised)."""
    W = np.atleast_1d(np.asarray(W, float))
    s = _bc(s, W.shape[0])
    rc = opts.get("r_contact", r)
    if opts.get("rut"):
        f, zr = opts["rut"]
        Z = rut_sinkage(W, rc, b, soil, f, zr)
        nn = None
    else:
        Z, nn = sinkage(W, s, soil, r, b, opts)
        if opts.get("model") != "ding":
            nn = None
    out = forces_gl(Z, s, soil, r, b, opts, n_override=nn)
    out["Z"] = Z
    return out
