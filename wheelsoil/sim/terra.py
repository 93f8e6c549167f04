"""Reference rigid-wheel terramechanics for the simulator's truth, by adaptive quadrature.

Written from the equations, independently of ``wheelsoil.model.wong`` (whose
fast fixed-order kernel the simulator is meant to check): nothing here is
imported from ``wheelsoil.model``. Soils are plain dicts (SI):
``{"c": Pa, "phi": rad, "K": m, "n": -, "kc": N/m^(n+1), "kphi": N/m^(n+2)}``;
every value may be a scalar or an array of shape (N,) (one soil per sample:
soil variability, terrain drift).

Equations (paper numbering; the two typos fixed as in hardware.md):

- (1)  theta1 = arccos(1 - z/r)
- (2)  sigma = (kc/b + kphi) z(theta)^n                 (Bekker)
- (3)  z(theta) = r (cos theta - cos theta1)
- (4)  tau = (c + sigma tan phi)(1 - exp(-j/K))          (Janosi-Hanamoto)
- (5)  j = r [theta1 - theta - (1 - s)(sin theta1 - sin theta)]
- (7)  W  = r b (int sigma cos theta + int tau sin theta)
- (8)  Dp = r b (int tau cos theta - int sigma sin theta)
- (9)  T  = r^2 b int tau
- (10) z0 = [3 W / (sqrt(2r)(kc + b kphi)(3 - n))]^(2/(2n+1))
- (11) Vasil'ev z = z0 + H s; (12) Lyasko z = z0 (1 + m1 s)/(1 - m2 s);
  (13) Ding N = n + n1 s (replaces n in Eqs. 2 and 10).

Wong-Reece normal stress (Wong, *Theory of Ground Vehicles*, 4th ed., ch. 2.x;
Wong & Reece, J. Terramechanics 4(1), 1967): maximum at
theta_m = (a1 + a2 s) theta1; front region theta_m..theta1 as Eq. (2);
rear region 0..theta_m
sigma2(theta) = (kc/b + kphi) r^n [cos(theta1 - theta/theta_m (theta1 - theta_m)) - cos theta1]^n
(exit angle theta2 = 0; a rebounding soil, ``exit_frac``: the rear region runs on to
-theta2 and theta_e = theta1 - (theta + theta2)/(theta_m + theta2) (theta1 - theta_m)).
a1 = a2 = 0 with theta2 = 0 is the paper's distribution exactly. ``hump``: Wong's
hump-shaped shear curve of compact soils instead of Eq. (4). ``slip_angle``: the wheel runs at
a slip angle alpha (a toe or crabbing misalignment): the soil is also sheared sideways,
j_y = r (1 - s)(theta1 - theta) tan alpha, the strength is mobilised by the resultant
displacement and only its longitudinal part tau j_x / |j| drives the wheel (Wong, *Theory of
Ground Vehicles*, 4th ed., ch. 2, lateral forces of a rigid wheel; Chiang & Wong). ``grouser``:
lugs of height h: the soil is sheared at the lug tips, radius r_g = r + h (j of Eq. 5 with r_g for
the wheel's own travel, the shear stress acting at r_g in Eqs. 7-9), the normal stress on the rim.
``envelope``: a curved failure envelope, the strength c + tan phi sigma0 (sigma/sigma0)^beta (a power
law, beta < 1: it meets the lab's straight Mohr-Coulomb line at sigma0; real envelopes curve at higher
normal stress). ``k_pressure``: a shear deformation modulus growing with the normal stress,
K (sigma/sigma0)^gamma (measured for many soils; Wong, ch. 2), the lab's K at sigma0. ``depth_power``: a
loose top layer, the strength (c + sigma tan phi) (d/d0)^a growing with the depth d = r (cos theta - cos
theta1) below the original surface (the lab's at d0). ``interface`` ``(sigma_x, f)``: the tyre-soil
interface, friction f tan phi, is weaker than the soil above the normal stress sigma_x (a smooth tread
on a frictional soil; Wong, ch. 2, on the tyre-soil interface): the strength c + sigma tan phi -
(1 - f) tan phi [softplus(sigma - sigma_x) - softplus(-sigma_x)], softplus(x) = k ln(1 + e^(x/k)),
k = sigma_x / 4: the soil's line below sigma_x, the interface's c + (1 - f) tan phi sigma_x + f tan phi
sigma above it, joined smoothly over about sigma_x / 4. ``rut`` ``(z_f, R)``: the wheel runs in the rut of
a wheel ahead (the front wheel of its side) that sank z_f into the soil at its peak pressure sigma_f =
(kc/b + kphi) z_f^n (Eq. 2); the rut rebounded by z_r = z_f / R when it passed, so its bottom lies z_f - z_r
below the surface.  Below the bottom the soil reloads on the stiff line sigma = k_u d, k_u = sigma_f /
z_r, up to sigma_f at depth z_r, and then follows the virgin curve (kc/b + kphi) (d + z_f - z_r)^n
(Wong, *Theory of Ground Vehicles*, 4th ed., ch. 2, response to repetitive loading: unloading and
reloading follow a line far stiffer than the virgin curve).  The contact and the shear displacement
(Eq. 5) start at the rut's bottom; the sinkage below it comes from the vertical balance (Eq. 7 = W).
``crust`` ``(d_c, dc)``: a cohesive surface crust (a dried, cemented or frozen top layer): the strength
plus dc exp(-d / d_c), d the depth below the original surface as for ``depth_power``.

Quadrature. ``scipy.integrate.quad_vec`` (adaptive Gauss-Kronrod 21, all
samples and the five integrals of one call in one vector) over a normalised
variable u in [0, 2] with a break point at u = 1: u in [0, 1] is the front
region, theta1 - theta = (theta1 - theta_m) u^2; u in [1, 2] the rear region,
theta = theta_m (u - 1)^2. The squares soften the (theta1 - theta)^n endpoint
singularity of Eq. (2) (and theta^n of the rear region); every integrand is
divided by a per-sample scale so the max-norm error control is relative
(default ``EPSREL`` 1e-10 of each integral's scale). In a rut the pressure has a
kink where the reloading line meets the virgin curve, at a different angle
theta_k in each sample; one shared subdivision would chase them all (300x the
work), so the front region is split there: u in [0, 1] runs from theta1 to
theta_k (squared, as above), u in [1, 2] linearly on to theta_m, and the rear
region is u in [2, 3].

Sinkage: Eq. (10) (``sinkage="eq10"``) or the vertical balance Eq. (7) = W
(``sinkage="balance"``), solved per sample by a vectorised bracketing
secant/bisection in log z (:func:`balance_sinkage`).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

__all__ = ["EPSREL", "SOIL_KEYS", "soil_dict", "sinkage_eq10", "wheel_forces", "balance_sinkage"]

#: Relative tolerance of the adaptive quadrature (of each integral's scale).
EPSREL = 1e-10
#: Keys of a soil dict (SI units).
SOIL_KEYS = ("c", "phi", "K", "n", "kc", "kphi")


def soil_dict(terrain: Any) -> dict[str, float]:
    """A plain soil dict from a mapping with :data:`SOIL_KEYS` or any object with those attributes
    (e.g. ``wheelsoil.model.Terrain``, read by attribute only). Raises ValueError on a missing key."""
    out = {}
    for k in SOIL_KEYS:
        v = terrain.get(k) if isinstance(terrain, Mapping) else getattr(terrain, k, None)
        if v is None:
            raise ValueError(f"soil lacks {k!r} (need {', '.join(SOIL_KEYS)} in SI units)")
        out[k] = float(v)
    return out


def sinkage_eq10(soil: Mapping[str, Any], radius_m: float, width_m: float, load_n, n=None) -> np.ndarray:
    """Static sinkage z0 [m], paper Eq. (10); ``load_n`` (N,), ``n`` overrides the exponent (Ding).

    z0 = [3 W / (sqrt(2 r) (kc + b kphi) (3 - n))]^(2/(2n+1)). Source: paper Eq. (10);
    Bekker (1956), Wong, Theory of Ground Vehicles, ch. 2.
    """
    n = np.asarray(soil["n"] if n is None else n, float)
    ksum = np.asarray(soil["kc"], float) + width_m * np.asarray(soil["kphi"], float)
    w = np.asarray(load_n, float)
    return (3.0 * w / (np.sqrt(2.0 * np.asarray(radius_m, float)) * ksum * (3.0 - n))) ** (2.0 / (2.0 * n + 1.0))


def _bc(x, size):
    return np.broadcast_to(np.asarray(x, float), (size,))


def _shear_factor(j, K, hump):
    """Shear stress over shear strength at shear displacement j (N,): Janosi-Hanamoto (Eq. 4),
    or with ``hump = (Kr, Kw_over_K)`` Wong's hump-shaped curve of compact soils
    Kr {1 + [1/(Kr (1 - 1/e)) - 1] exp(1 - j/Kw)} (1 - exp(-j/Kw)), Kw = Kw_over_K K: the peak
    (1 at j = Kw) falls to the residual Kr (Wong, Theory of Ground Vehicles, 4th ed., ch. 2)."""
    if hump is None:
        return -np.expm1(-j / K)
    kr, kw_over_k = hump
    kw = kw_over_k * K
    return kr * (1.0 + (1.0 / (kr * (1.0 - math.exp(-1.0))) - 1.0) * np.exp(1.0 - j / kw)) * (-np.expm1(-j / kw))


def _integrals(soil, r, b, z, s, n, theta_m_frac, epsrel, exit_frac=0.0, hump=None, tau_scale=1.0,
               slip_angle=0.0, grouser=0.0, envelope=None, k_pressure=None, depth_power=None, interface=None,
               rut=None, crust=None):
    """The five integrals of Eqs. (7)-(9) for each sample: returns W, Dp, T, theta1 (all (N,)).

    ``exit_frac``: the soil's rebound behind the wheel, exit angle theta2 = exit_frac theta1 (the
    rear region runs from theta_m to -theta2); ``hump``: see :func:`_shear_factor`; ``tau_scale``
    (N,) or scalar multiplies the shear strength; ``slip_angle`` [rad], ``grouser`` (lug height h
    [m]), ``envelope`` ``(sigma0 [Pa], beta)``, ``k_pressure`` ``(sigma0 [Pa], gamma)``,
    ``depth_power`` ``(d0 [m], a)``, ``interface`` ``(sigma_x [Pa], f)``, ``crust`` ``(d_c [m], dc [Pa])``
    and ``rut`` ``(z_f (N,) [m], R)`` (``z`` is then the sinkage below the rut's bottom): see the module doc."""
    from scipy.integrate import quad_vec

    size = len(z)
    c = _bc(soil["c"], size) * _bc(tau_scale, size)
    tanphi = np.tan(_bc(soil["phi"], size)) * _bc(tau_scale, size)
    K = _bc(soil["K"], size)
    k = _bc(soil["kc"], size) / b + _bc(soil["kphi"], size)
    n = _bc(n, size)
    s = _bc(s, size)
    th1 = np.arccos(1.0 - z / r)  # Eq. (1)
    thm = np.clip(_bc(theta_m_frac, size), 0.0, 0.999) * th1
    th2 = np.clip(_bc(exit_frac, size), 0.0, 1.0) * th1  # exit angle (rebound), 0 in the paper
    r_g = r + float(grouser)  # radius at which the soil is sheared (lug tips; r without lugs)
    tan_a = math.tan(float(slip_angle))
    if rut is not None:  # the front wheel's rut: reloading line up to its pressure, then the virgin curve
        z_f = _bc(rut[0], size)
        z_r = z_f / float(rut[1])  # the rut's elastic rebound
        k_u = k * z_f ** n / z_r  # reloading stiffness: the front wheel's peak pressure at depth z_r

    def pressure(zt):  # Eq. (2), or with a rut the pressure at depth zt below its bottom
        with np.errstate(divide="ignore", invalid="ignore"):
            virgin = k * np.where(zt > 0, zt + (0.0 if rut is None else z_f - z_r), 1.0) ** n * (zt > 0)
        return virgin if rut is None else np.where(zt <= z_r, k_u * np.maximum(zt, 0.0), virgin)

    # scales: the largest normal stress and shear stress (for relative error control)
    sig_max = np.maximum(pressure(z), 1e-300)
    tau_max = c + sig_max * tanphi + (0.0 if crust is None else crust[1])
    s_sig = np.maximum(sig_max * th1, 1e-300)
    s_tau = np.maximum(tau_max * th1, 1e-300)

    # a rut's kink (the reloading line meets the virgin curve at depth z_r): the front region is split
    # there, at u = 1 (u in [1, 2] runs on linearly to theta_m; the rear region is then u in [2, 3])
    thk = thm if rut is None else np.maximum(np.arccos(np.clip(np.cos(th1) + z_r / r, -1.0, 1.0)), thm)
    u_rear = 1.0 if rut is None else 2.0

    def integrand(u):
        if u <= 1.0:  # front region: theta1 - theta = (theta1 - theta_k) u^2 (theta_k = theta_m without a rut)
            d = (th1 - thk) * u * u
            jac = 2.0 * (th1 - thk) * u
        elif u <= u_rear:  # a rut's virgin part of the front region, linear from theta_k to theta_m
            d = (th1 - thk) + (thk - thm) * (u - 1.0)
            jac = thk - thm
        if u <= u_rear:
            theta = th1 - d
            # cos theta - cos theta1 = 2 sin((theta1 + theta)/2) sin(d/2)   (Eq. 3)
            zt = 2.0 * r * np.sin(th1 - 0.5 * d) * np.sin(0.5 * d)
        else:  # rear region: theta = -theta2 + (theta_m + theta2) v^2, stress of the mirrored front profile
            v = u - u_rear
            span = thm + th2
            theta = -th2 + span * v * v
            jac = 2.0 * span * v
            # equivalent angle theta_e = theta1 - (theta + theta2)/(theta_m + theta2) (theta1 - theta_m)
            with np.errstate(invalid="ignore", divide="ignore"):
                de = np.where(span > 0, ((theta + th2) / np.where(span > 0, span, 1.0)) * (th1 - thm), 0.0)
            d = th1 - theta  # for the shear displacement
            zt = 2.0 * r * np.sin(th1 - 0.5 * de) * np.sin(0.5 * de)
        sigma = pressure(np.maximum(zt, 0.0))  # Eq. (2)
        # Eq. (5): sin theta1 - sin theta = 2 cos((theta1 + theta)/2) sin(d/2)
        j = r_g * d - r * (1.0 - s) * 2.0 * np.cos(th1 - 0.5 * d) * np.sin(0.5 * d)
        if envelope is not None:  # curved failure envelope: the normal stress's share of the strength
            sigma_f = envelope[0] * (sigma / envelope[0]) ** envelope[1]
        else:
            sigma_f = sigma
        k_j = K  # Eq. (4)'s K, or growing with the normal stress
        if k_pressure is not None:
            k_j = K * (np.maximum(sigma, 1e-9 * k_pressure[0]) / k_pressure[0]) ** k_pressure[1]
        strength = c + sigma_f * tanphi  # Eq. (4)'s Mohr-Coulomb strength
        if crust is not None:  # a cohesive crust: more cohesion near the original surface (the depth at
            # theta itself, also in the rear region, whose stress follows the mirrored front profile)
            depth = 2.0 * r * np.sin(th1 - 0.5 * d) * np.sin(0.5 * d)
            strength = strength + crust[1] * np.exp(-np.maximum(depth, 0.0) / crust[0])
        if interface is not None:  # the tyre-soil interface: friction f tan phi above sigma_x, joined smoothly
            sx, f = interface
            kx = 0.25 * sx  # softplus(sigma - sigma_x) - softplus(-sigma_x): 0 at sigma = 0, sigma - sigma_x far above
            ramp = kx * (np.logaddexp(0.0, (sigma_f - sx) / kx) - np.logaddexp(0.0, -sx / kx))
            strength = strength - (1.0 - f) * tanphi * ramp
        if depth_power is not None:  # a loose top: the strength grows with the depth below the surface
            strength = strength * (np.maximum(zt, 1e-12 * depth_power[0]) / depth_power[0]) ** depth_power[1]
        if tan_a:  # sheared sideways too: the strength mobilised by |j|, its longitudinal part drives
            jy = r * (1.0 - s) * d * tan_a
            jr = np.hypot(j, jy)
            with np.errstate(invalid="ignore", divide="ignore"):
                tau = strength * _shear_factor(jr, k_j, hump) * np.where(jr > 0, j / jr, 0.0)
        else:
            tau = strength * _shear_factor(j, k_j, hump)  # Eq. (4)
        ct, st = np.cos(theta), np.sin(theta)
        return np.concatenate([
            jac * sigma * ct / s_sig, jac * tau * st / s_tau, jac * tau * ct / s_tau,
            jac * sigma * st / s_sig, jac * tau / s_tau,
        ])

    res, _err = quad_vec(integrand, 0.0, u_rear + 1.0, points=[1.0] if rut is None else [1.0, 2.0],
                         epsabs=epsrel * 1e-3, epsrel=epsrel, norm="max", limit=4000)
    i_sc, i_ts, i_tc, i_ss, i_t = res.reshape(5, size)
    w = r * b * i_sc * s_sig + r_g * b * i_ts * s_tau  # Eq. (7)
    dp = r_g * b * i_tc * s_tau - r * b * i_ss * s_sig  # Eq. (8)
    t = r_g * r_g * b * i_t * s_tau  # Eq. (9)
    return w, dp, t, th1


def balance_sinkage(soil, radius_m, width_m, load_n, slip, *, n=None, theta_m_frac=0.0, rut=None,
                    epsrel: float = 1e-9, tol: float = 1e-10) -> np.ndarray:
    """Sinkage z0 [m] with Eq. (7)(z0, s) = W for each sample (the exact vertical balance);
    with ``rut`` ``(z_f (N,), R)`` (module doc) the sinkage below the rut's bottom.

    Vectorised bracketing root finder in x = log z: false position with the Illinois
    modification inside a bracket, bisection when a step leaves it; converged when
    |log W_model - log W| < ``tol``. ``load_n``, ``slip`` (N,). Raises ValueError naming the first sample
    whose load the wheel cannot carry with sinkage < 0.99 r.
    Source: paper Eq. (7); root finding: Dowell & Jarratt (1971), the Illinois method (false position).
    """
    w = np.atleast_1d(np.asarray(load_n, float))
    size = len(w)
    r, b = _bc(radius_m, size), float(width_m)
    s = _bc(slip, size)
    nn = _bc(soil["n"] if n is None else n, size)
    tm = _bc(theta_m_frac, size)

    def g(x, idx):
        sub = {kk: (_bc(soil[kk], size)[idx]) for kk in SOIL_KEYS}
        sub_rut = None if rut is None else (_bc(rut[0], size)[idx], rut[1])
        wm, _, _, _ = _integrals(sub, r[idx], b, np.exp(x), s[idx], nn[idx], tm[idx], epsrel, rut=sub_rut)
        return np.log(wm) - np.log(w[idx])

    all_idx = np.arange(size)
    x_hi = np.log(0.99 * r)
    g_hi = g(x_hi, all_idx)
    if np.any(g_hi < 0):
        i = int(np.flatnonzero(g_hi < 0)[0])
        raise ValueError(f"load_n[{i}] = {w[i]:.1f} N: the wheel (r = {r[i]:.4g} m, b = {b} m) cannot carry it "
                         "with sinkage below 0.99 r (vertical balance, Eq. 7)")
    x0 = np.log(np.minimum(sinkage_eq10(soil if np.ndim(soil["n"]) == 0 else
                                        {kk: _bc(soil[kk], size) for kk in SOIL_KEYS}, r, b, w, nn), 0.9 * r))
    x_lo = np.log(1e-7 * r)
    g_lo = g(x_lo, all_idx)
    x = x0
    gx = g(x, all_idx)
    out = np.full(size, np.nan)
    active = all_idx
    side = np.zeros(size, dtype=int)  # which bracket end moved last (-1 low, +1 high): Illinois
    for _ in range(200):
        done = np.abs(gx) < tol
        out[active[done]] = np.exp(x[done])
        keep = ~done
        if not keep.any():
            return out
        active, x, gx, side = active[keep], x[keep], gx[keep], side[keep]
        x_lo, g_lo, x_hi, g_hi = x_lo[keep], g_lo[keep], x_hi[keep], g_hi[keep]
        lo_side = gx < 0
        # Illinois: an end kept twice in a row has its value halved (no one-sided stalling)
        g_hi = np.where(lo_side & (side == -1), 0.5 * g_hi, g_hi)
        g_lo = np.where(~lo_side & (side == 1), 0.5 * g_lo, g_lo)
        x_lo = np.where(lo_side, x, x_lo)
        g_lo = np.where(lo_side, gx, g_lo)
        x_hi = np.where(lo_side, x_hi, x)
        g_hi = np.where(lo_side, g_hi, gx)
        side = np.where(lo_side, -1, 1)
        x_new = x_lo - g_lo * (x_hi - x_lo) / (g_hi - g_lo)
        bad = ~np.isfinite(x_new) | (x_new <= x_lo) | (x_new >= x_hi)
        x = np.where(bad, 0.5 * (x_lo + x_hi), x_new)
        gx = g(x, active)
    raise RuntimeError("balance sinkage did not converge")  # pragma: no cover


def wheel_forces(soil: Mapping[str, Any], radius_m: float, width_m: float, load_n, slip, *,
                 sinkage: str = "eq10", H=None, m1=None, m2=None, n1=None, stress=None,
                 exit_frac: float = 0.0, hump=None, tau_scale=1.0, z_cap=None, slip_angle: float = 0.0,
                 grouser: float = 0.0, envelope=None, k_pressure=None, depth_power=None, interface=None,
                 rut=None, crust=None, epsrel: float = EPSREL) -> dict[str, np.ndarray]:
    """Reference forces of a rigid wheel on soil per sample (paper Eqs. 1-13, Wong-Reece stress).

    Parameters
    ----------
    soil : dict of SI soil values (:data:`SOIL_KEYS`), each scalar or (N,).
    radius_m, width_m : wheel radius r [m] (scalar or (N,): a deflected tyre's equivalent
        rigid wheel per sample) and width b [m].
    load_n, slip : W [N] and s [-], (N,) (broadcast); 0 <= s < 1.
    sinkage : ``"eq10"`` (paper) or ``"balance"`` (Eq. 7 = W at the sample's slip).
    H : Vasil'ev (Eq. 11) coefficient [m]; ``m1, m2`` Lyasko (Eq. 12); ``n1`` Ding (Eq. 13).
        Scalars or (N,); None = not applied. The transform is applied to z0 (of Eq. 10 or
        of the balance), as in the paper.
    stress : ``(a1, a2)`` Wong-Reece maximum at theta_m = (a1 + a2 s) theta1, or None (paper).
    exit_frac : exit angle theta2 = exit_frac theta1 of a rebounding soil (Wong-Reece rear region
        from theta_m to -theta2); 0 in the paper.
    hump : ``(Kr, Kw_over_K)``: Wong's hump-shaped shear curve instead of Eq. (4), or None.
    tau_scale : factor on the shear strength c + sigma tan phi (scalar or (N,)), 1 in the paper.
    z_cap : depth [m] of a firm layer the sinkage cannot pass (smooth cap (z^-8 + d^-8)^(-1/8),
        after any slip-sinkage transform), or None.
    slip_angle : the wheel's slip angle alpha [rad] (lateral shear, module doc); 0 in the paper.
    grouser : lug height h [m]: the soil sheared at r + h (module doc); 0 in the paper.
    envelope : ``(sigma0, beta)``: a curved failure envelope (module doc), or None (paper).
    k_pressure : ``(sigma0, gamma)``: K growing with the normal stress (module doc), or None (paper).
    depth_power : ``(d0, a)``: the strength x (d/d0)^a, d the depth below the surface (module doc), or None.
    interface : ``(sigma_x, f)``: above sigma_x the tyre-soil interface's friction f tan phi (module doc), or None.
    rut : ``(z_f, R)``: the wheel runs in the rut of a wheel ahead that sank z_f [m] ((N,) or scalar)
        into the soil, reloading R times stiffer than the virgin soil's secant (module doc); the
        sinkage then comes from the vertical balance whatever ``sinkage`` says, and ``sinkage_m``
        is measured from the original surface. None: virgin soil (paper).
    crust : ``(d_c, dc)``: a cohesive crust, the strength + dc [Pa] exp(-d/d_c [m]) (module doc), or None.
    epsrel : quadrature tolerance.

    Returns
    -------
    dict of (N,) arrays: ``sinkage_m`` z, ``static_sinkage_m`` z0, ``theta1_rad``,
    ``load_model_n`` (Eq. 7 with the sinkage used), ``drawbar_pull_n`` (Eq. 8),
    ``torque_nm`` (Eq. 9).

    Raises
    ------
    ValueError
        Non-finite input, W <= 0, s outside [0, 1), an exponent outside (0, 3),
        a sinkage outside (0, r), an unknown sinkage mode.
    """
    w, s = np.broadcast_arrays(np.atleast_1d(np.asarray(load_n, float)), np.atleast_1d(np.asarray(slip, float)))
    w, s = w.astype(float), s.astype(float)
    size = len(w)
    r, b = _bc(radius_m, size).copy(), float(width_m)
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(s))):
        raise ValueError("load_n and slip must be finite")
    if np.any(w <= 0):
        raise ValueError(f"load_n[{int(np.flatnonzero(w <= 0)[0])}] <= 0 N")
    if np.any((s < 0) | (s >= 1)):
        i = int(np.flatnonzero((s < 0) | (s >= 1))[0])
        raise ValueError(f"slip[{i}] = {s[i]}: the driving-wheel model needs 0 <= s < 1")
    if sinkage not in ("eq10", "balance"):
        raise ValueError(f"sinkage must be 'eq10' or 'balance', got {sinkage!r}")
    n = _bc(soil["n"], size).copy()
    if n1 is not None:
        n = n + _bc(n1, size) * s  # Eq. (13)
    if np.any((n <= 0) | (n >= 3)):
        raise ValueError("sinkage exponent outside (0, 3) (Eqs. 2, 10)")
    tm = 0.0
    if stress is not None:
        a1, a2 = stress
        tm = _bc(a1, size) + _bc(a2, size) * s
    soil_n = {kk: _bc(soil[kk], size) for kk in SOIL_KEYS}
    rut_n = None if rut is None else (_bc(rut[0], size), float(rut[1]))
    if sinkage == "eq10" and rut is None:
        z0 = sinkage_eq10(soil_n, r, b, w, n)
    else:
        z0 = balance_sinkage(soil_n, r, b, w, s, n=n, theta_m_frac=tm, rut=rut_n, epsrel=max(epsrel, 1e-10))
    z = z0.copy()
    if H is not None:
        z = z0 + _bc(H, size) * s  # Eq. (11)
    if m1 is not None or m2 is not None:
        mm1 = _bc(0.0 if m1 is None else m1, size)
        mm2 = _bc(0.0 if m2 is None else m2, size)
        if np.any(mm2 * s >= 1):
            raise ValueError("Lyasko: m2 s >= 1")
        z = z0 * (1.0 + mm1 * s) / (1.0 - mm2 * s)  # Eq. (12)
    if z_cap is not None:
        z = (z ** -8.0 + float(z_cap) ** -8.0) ** (-1.0 / 8.0)
    if np.any(~np.isfinite(z) | (z <= 0) | (z >= r)):
        i = int(np.flatnonzero(~np.isfinite(z) | (z <= 0) | (z >= r))[0])
        raise ValueError(f"sinkage[{i}] = {z[i]:.4g} m outside (0, r = {r[i]:.4g} m): the wheel buries itself")
    w_m, dp, t, th1 = _integrals(soil_n, r, b, z, s, n, tm, epsrel, exit_frac, hump, tau_scale, slip_angle, grouser,
                                 envelope, k_pressure, depth_power, interface, rut_n, crust)
    if rut_n is not None:  # below the original surface: the rut's permanent depth z_f (1 - 1/R) added
        z = z + rut_n[0] * (1.0 - 1.0 / rut_n[1])
    return {"sinkage_m": z, "static_sinkage_m": z0, "theta1_rad": th1, "load_model_n": w_m,
            "drawbar_pull_n": dp, "torque_nm": t}
