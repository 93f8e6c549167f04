"""Wong's rigid-wheel model (paper Eqs. 1-10), vectorised over samples.

Equations (paper numbering; the two printed typos fixed as in hardware.md):

- (1)  theta1 = arccos(1 - z/r)  (computed as 2 asin(sqrt(z/2r)), same value)
- (2)  sigma(theta) = (kc/b + kphi) z(theta)^n          [typo kc/(b+kphi) fixed]
- (3)  z(theta) = r (cos theta - cos theta1)            [sign typo fixed]
- (4)  tau = (c + sigma tan phi) (1 - exp(-j/K))
- (5)  j(theta) = r [theta1 - theta - (1 - s)(sin theta1 - sin theta)]
- (7)  W  = r b (int sigma cos + int tau sin)
- (8)  Dp = r b (int tau cos - int sigma sin)
- (9)  T  = r^2 b int tau
- (10) z0 = [3 W / (sqrt(2r) (kc + b kphi) (3 - n))]^(2/(2n+1))
  integrals over theta in [0, theta1] (exit angle theta2 = 0; ``exit_ratio``:
  a rebounding soil's exit angle theta2 > 0, see ``wong_forces``).

Normal-stress distribution (``stress=``). ``None``: the paper's Eqs. (2)-(3),
maximum at theta = 0. ``(a1, a2)``: Wong-Reece (Wong, Theory of Ground
Vehicles, 4th ed., Wiley 2008, ch. 2; Wong & Reece, J. Terramechanics 4(1)
1967), maximum at theta_m = (a1 + a2 s) theta1:

- front  theta_m <= theta <= theta1: sigma = k_eq (r (cos theta - cos theta1))^n
- rear   0 <= theta <= theta_m:      sigma = k_eq (r (cos(theta1 - theta/theta_m
  (theta1 - theta_m)) - cos theta1))^n

with k_eq = kc/b + kphi, exit angle 0, shear by Eqs. (4)-(5) over the whole
contact and W, Dp, T by Eqs. (7)-(9); a1 = a2 = 0 is the paper's model.

Quadrature. sigma ~ (theta1 - theta)^n near the entrance angle, an endpoint
singularity for n < 1 that limits plain Gauss-Legendre to ~1e-5 with 32
points. We substitute theta1 - theta = theta1 u^3, dtheta = 3 theta1 u^2 du,
u in [0, 1]: the integrand becomes smooth times u^(3n+2), and a fixed
24-point Gauss-Legendre rule in u (``QUAD_ORDER``) agrees with
scipy.integrate.quad to 1e-8 relative on the built-in terrains and 5e-8 on
random custom terrains with n in [0.03, 2.9] (values >= 1 N; measured over
2000 points incl. theta1 up to 87 deg and s = 0; tests/test_model_wong.py,
benchmarks/bench_model.py).
All trigonometric terms are formed from sin/cos of (theta1 - theta)/2 and
theta1 by angle-sum identities, which avoids the cancellation in
cos(theta) - cos(theta1) and sin(theta1) - sin(theta) near theta1.
With the Wong-Reece distribution the stress has a kink at theta_m, so each
region gets its own rule: the front [theta_m, theta1] with theta1 - theta =
(theta1 - theta_m) u^3 (singular end theta1), the rear [0, theta_m] with
theta = theta_m u^3 (its stress vanishes like theta^n at theta = 0). The rear
region maps linearly onto the front, so at equal u both have the same stress
and it is computed once. Agreement with scipy.integrate.quad split at
theta_m, over 2000 random built-in terrains, wheels (r 0.2-0.6 m), loads,
slips and (a1, a2) in [0, 0.6]^2 (theta1 up to 89 deg): W and T to better
than 1e-8 relative, Dp to 2e-7 relative at worst, where Dp is a few newtons
left from cancelling kN terms (absolute error < 1e-6 N); every value within
the 1e-6 relative / 1e-3 N criterion (tests/test_model_wong.py). Cost ~1.6x
the paper distribution (benchmarks/bench_model.py).

Sinkage modes. ``eq10``: z0 from Eq. (10), as in the paper. Eq. (10) is a
small-angle approximation that also ignores the shear term of Eq. (7), so the
model's W differs from the input W: within ~3 % on the paper's clay, ~11 % on
its sand, up to ~20 % on the library's soils for theta1 < 60 deg.
``balance``: z0 solves Eq. (7)(z0, s) = W at each sample's slip (vectorised
safeguarded secant on log z vs log W, to 1e-13 relative). A slip-sinkage
transform z(z0, s) (Vasil'ev, Lyasko) is then applied to that z0, exactly as
to Eq. (10)'s z0: the balance replaces Eq. (10) as the estimate of the static
sinkage, and the slip sinkage comes on top (solving Eq. (7)(z(z0, s)) = W
instead would cancel any slip-sinkage model). Ding's N enters the balance
itself (it changes Eq. 2), so Ding keeps W_model = W in balance mode.
With ``stress=(a1, a2)`` the balance is solved with the Wong-Reece
distribution; Eq. (10) itself was derived for the paper's distribution, so in
``eq10`` mode a shifted maximum carries less than W (the rear region's stress
is below the paper's) -- use ``balance`` when the vertical balance matters.

Domain. The model is for a driven wheel: 0 <= s < 1. Skid (s < 0, braking)
is rejected with a ValueError naming the sample; callers filter those rows.
Sinkage must stay below r (theta1 < 90 deg).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .terrain import Terrain, Wheel

__all__ = ["WheelForces", "wong_forces", "sinkage_eq10", "QUAD_ORDER", "SINKAGE_MODES"]

#: Gauss-Legendre points in the substituted variable u.
QUAD_ORDER = 24
#: Exponent q of the substitution theta1 - theta = theta1 * u**q.
_Q = 3
_U, _WU = np.polynomial.legendre.leggauss(QUAD_ORDER)
_U = 0.5 * (_U + 1.0)
_WU = 0.5 * _WU
#: d = theta1 * _UQ; the integral's weight per theta1 is _G = q u^(q-1) w.
_UQ = _U**_Q
_G = _Q * _U ** (_Q - 1) * _WU
#: 1 - u^q at the nodes (rear region of the Wong-Reece distribution).
_1MUQ = 1.0 - _UQ

#: Samples per block (keeps the (block, QUAD_ORDER) temporaries in cache).
_BLOCK = 2048

SINKAGE_MODES = ("eq10", "balance")

ZFn = Callable[[np.ndarray, np.ndarray], np.ndarray]
NFn = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class WheelForces:
    """Model output per sample, every field a float array of shape (N,).

    ``sinkage_m`` z [m] (after any slip-sinkage transform), ``theta1_rad``
    entrance angle [rad] (Eq. 1), ``load_model_n`` the model's vertical load
    W [N] (Eq. 7), ``drawbar_pull_n`` Dp [N] (Eq. 8), ``torque_nm`` T [N m]
    (Eq. 9).
    """

    sinkage_m: np.ndarray
    theta1_rad: np.ndarray
    load_model_n: np.ndarray
    drawbar_pull_n: np.ndarray
    torque_nm: np.ndarray

    def __len__(self) -> int:
        return len(self.sinkage_m)


def _first_bad(mask: np.ndarray) -> tuple[int, int]:
    idx = np.flatnonzero(mask)
    return int(idx[0]), len(idx)


def _check(mask: np.ndarray, name: str, values: np.ndarray, rule: str) -> None:
    """Raise ValueError naming the first element where ``mask`` is True."""
    if mask.any():
        i, count = _first_bad(mask)
        more = f" ({count} elements violate this)" if count > 1 else ""
        raise ValueError(f"{name}[{i}] = {float(values[i])!r}: {rule}{more}")


def _as_samples(load_n, slip) -> tuple[np.ndarray, np.ndarray]:
    """Validate and broadcast load W [N] and slip s [-] to float arrays of shape (N,)."""
    if (type(load_n) is np.ndarray and type(slip) is np.ndarray and load_n.ndim == 1 and load_n.shape == slip.shape
            and load_n.dtype == np.float64 and slip.dtype == np.float64):  # the fitter's case: no broadcasting
        w, s = load_n.copy(), slip.copy()
    else:
        w = np.asarray(load_n, dtype=float)
        s = np.asarray(slip, dtype=float)
        try:
            w, s = np.broadcast_arrays(w, s)
        except ValueError:
            raise ValueError(f"load_n shape {w.shape} and slip shape {s.shape} do not match") from None
        if w.ndim > 1:
            raise ValueError(f"load_n and slip must be 1-D arrays of samples, got shape {w.shape}")
        w = np.atleast_1d(w).astype(float, copy=True)
        s = np.atleast_1d(s).astype(float, copy=True)
    if ((w > 0) & (w < np.inf) & (s >= 0) & (s < 1)).all():  # the common case: one pass, nothing to name
        return w, s
    _check(~np.isfinite(w), "load_n", w, "load W must be a finite number (NaN/inf given)")
    _check(~np.isfinite(s), "slip", s, "slip s must be a finite number (NaN/inf given)")
    _check(w <= 0, "load_n", w, "vertical load W must be > 0 N")
    _check(s < 0, "slip", s, "slip s must be >= 0: skid (braking, s < 0) is outside this "
           "driving-wheel model; filter those samples out")
    _check(s >= 1, "slip", s, "slip s must be < 1")
    return w, s


def _shaped(value, shape: tuple) -> np.ndarray:
    """``value`` as a float array of ``shape``: itself when it already is one (the fitter's case, where
    ``np.broadcast_to`` would cost more than the arithmetic it feeds), else a broadcast view.  Raises
    ValueError where numpy cannot broadcast it."""
    if type(value) is np.ndarray and value.dtype == np.float64 and value.shape == shape:
        return value
    return np.broadcast_to(np.asarray(value, dtype=float), shape)


def sinkage_eq10(terrain: Terrain, wheel: Wheel, load_n, n=None) -> np.ndarray:
    """Static sinkage z0 [m] from paper Eq. (10), shape (N,) like ``load_n``.

    z0 = [3 W / (sqrt(2r) (kc + b kphi) (3 - n))]^(2/(2n+1)); ``n`` (scalar or
    (N,)) overrides the terrain's exponent (Ding's N, Eq. 13). No input
    validation beyond what numpy does; ``wong_forces`` validates.
    Source: paper Eq. (10) (Bekker's small-angle rigid-wheel sinkage, as given
    in Wong, Theory of Ground Vehicles, ch. 2), with sqrt(2r) = sqrt(D).
    """
    n = terrain.n if n is None else n
    r, b = wheel.radius, wheel.width
    k = terrain.kc + b * terrain.kphi
    return (3.0 * np.asarray(load_n, float) / (math.sqrt(2.0 * r) * k * (3.0 - n))) ** (2.0 / (2.0 * n + 1.0))


def _integrals(terrain: Terrain, wheel: Wheel, z, s, n, load_only: bool = False, ratio=None, exit_ratio=None,
               tau_scale=None, shear_power=None):
    """Eqs. (1)-(9) by substituted Gauss-Legendre quadrature; z, s, n of shape (N,).

    ``ratio`` None: the paper's distribution (Eqs. 2-3 over [0, theta1]).
    ``ratio`` (N,) array theta_m/theta1 in [0, 1): the Wong-Reece distribution
    (front region [theta_m, theta1] and rear region [0, theta_m], see
    ``wong_forces``). ``exit_ratio`` (N,) theta2/theta1 >= 0: the rear region
    runs on to -theta2 (a rebounding soil; ``ratio`` None then means theta_m = 0).
    ``tau_scale`` (N,) multiplies the shear strength c + sigma tan phi of Eq. (4) per sample.
    ``shear_power`` (sigma0, beta, gamma) makes Eq. (4) stress-dependent (``wong_forces``).
    Returns theta1 and W (Eq. 7), and unless ``load_only`` also Dp, T; all (N,).
    """
    r, b = wheel.radius, wheel.width
    k = terrain.kc / b + terrain.kphi
    c, tanphi, inv_k = terrain.c, math.tan(terrain.phi), 1.0 / terrain.K
    size = len(z)
    theta1 = 2.0 * np.arcsin(np.sqrt(z / (2.0 * r)))
    w_out = np.empty(size)
    dp_out = None if load_only else np.empty(size)
    t_out = None if load_only else np.empty(size)
    n = _shaped(n, (size,))
    for lo in range(0, size, _BLOCK):
        sl = slice(lo, lo + _BLOCK)
        t1 = theta1[sl, None]
        nn = n[sl, None]
        ss = s[sl, None]
        if ratio is None and exit_ratio is None:
            tm = None
            span = t1
        else:
            tm = (0.0 if ratio is None else ratio[sl, None]) * t1  # theta_m, Wong-Reece
            span = t1 - tm  # front region length theta1 - theta_m
            t2 = 0.0 if exit_ratio is None else exit_ratio[sl, None] * t1  # exit angle theta2
            rear = tm + t2  # rear region length theta_m + theta2
        s1 = np.sin(t1)
        c1 = np.cos(t1)
        half = (0.5 * span) * _UQ  # (theta1 - theta)/2 on the front region's nodes
        sh = np.sin(half)
        ch = np.sqrt(1.0 - sh * sh)  # cos(half): half <= theta1/2 < 45 deg, cos > 0; a third of np.cos's time
        sin_m = s1 * ch - c1 * sh  # sin((theta1 + theta)/2)
        cos_m = c1 * ch + s1 * sh  # cos((theta1 + theta)/2)
        # Eq. (3): z(theta) = r (cos theta - cos theta1) = 2 r sin(m) sin(d/2)
        ztheta = (2.0 * r) * sin_m * sh
        with np.errstate(divide="ignore"):
            sigma = k * np.exp(nn * np.log(ztheta))  # Eq. (2)
        # Eq. (5): j = r [(theta1 - theta) - (1 - s)(sin theta1 - sin theta)]
        j = r * (2.0 * half - (1.0 - ss) * (2.0 * cos_m * sh))
        inv_kk = inv_k
        if shear_power is None:
            strength = c + sigma * tanphi
        else:  # Eq. (4) with a curved envelope and a stress-dependent K (wong_forces)
            s0, beta, gamma = shear_power
            rel = np.maximum(sigma / s0, 1e-12)
            strength = c + (tanphi * s0) * rel ** beta
            inv_kk = inv_k * rel ** (-gamma)
        if tau_scale is not None:
            strength = strength * tau_scale[sl, None]
        tau = strength * -np.expm1(-j * inv_kk)  # Eq. (4)
        # theta = theta1 - d with sin d = 2 sh ch, cos d = 1 - 2 sh^2
        sin_d = 2.0 * sh * ch
        cos_d = 1.0 - 2.0 * sh * sh
        cos_t = c1 * cos_d + s1 * sin_d
        sin_t = s1 * cos_d - c1 * sin_d
        scale = span[:, 0]
        w_blk = (r * b) * scale * ((sigma * cos_t + tau * sin_t) @ _G)  # Eq. (7)
        if not load_only:
            dp_blk = (r * b) * scale * ((tau * cos_t - sigma * sin_t) @ _G)  # Eq. (8)
            t_blk = (r * r * b) * scale * (tau @ _G)  # Eq. (9)
        if tm is not None:
            # Rear region, nodes theta = -theta2 + (theta_m + theta2) u^3 (the stress vanishes
            # like (theta + theta2)^n at the exit). Its stress is the front's at theta' = theta1 -
            # (theta + theta2)/(theta_m + theta2) (theta1 - theta_m) = theta1 - span u^3: the
            # front region's node for the same u, so ``sigma`` is reused as it is.
            th = rear * _UQ - t2
            sin_r = np.sin(th)
            cos_r = np.cos(th)
            # Eq. (5) over the same contact; theta1 - theta = span + (theta_m + theta2) (1 - u^3)
            j_r = r * ((span + rear * _1MUQ) - (1.0 - ss) * (s1 - sin_r))
            tau_r = strength * -np.expm1(-j_r * inv_kk)  # Eq. (4)
            scale_r = np.broadcast_to(rear, t1.shape)[:, 0]
            w_blk = w_blk + (r * b) * scale_r * ((sigma * cos_r + tau_r * sin_r) @ _G)
            if not load_only:
                dp_blk = dp_blk + (r * b) * scale_r * ((tau_r * cos_r - sigma * sin_r) @ _G)
                t_blk = t_blk + (r * r * b) * scale_r * (tau_r @ _G)
        w_out[sl] = w_blk
        if not load_only:
            dp_out[sl] = dp_blk
            t_out[sl] = t_blk
    return theta1, w_out, dp_out, t_out


def _balance_sinkage(terrain, wheel, w, s, n, z_start, ratio=None, exit_ratio=None, tau_scale=None,
                     shear_power=None) -> np.ndarray:
    """z0 with Eq. (7)(z0, s) = W, per sample; safeguarded secant in log z vs log W.

    Raises ValueError naming the first sample whose load exceeds what the
    wheel can carry with sinkage < r: its bracket closes on the top,
    z = r (1 - 1e-9), without ever finding a sinkage that carries W (W grows
    with z, so no load test at the top is evaluated up front).
    """
    r = wheel.radius
    size = len(w)
    n = _shaped(n, (size,)).copy()
    x_top = math.log(r * (1.0 - 1e-9))
    x_hi = np.full(size, x_top)
    too_large = np.zeros(size, dtype=bool)
    log_w = np.log(w)
    x_lo = np.full(size, -np.inf)
    x = np.log(np.minimum(z_start, 0.9 * r))
    slope = n + 0.5  # d log W / d log z of Eq. (10)
    x_prev = g_prev = None
    active = np.arange(size)
    out = np.empty(size)
    for _ in range(100):
        _, wm, _, _ = _integrals(terrain, wheel, np.exp(x), s[active], n[active], load_only=True,
                                 ratio=None if ratio is None else ratio[active],
                                 exit_ratio=None if exit_ratio is None else exit_ratio[active],
                                 tau_scale=None if tau_scale is None else tau_scale[active],
                                 shear_power=shear_power)
        g = np.log(wm) - log_w[active]
        done = np.abs(g) < 1e-13
        if x_prev is not None:
            dx = x - x_prev
            ok = np.abs(dx) > 0
            slope = np.where(ok, (g - g_prev) / np.where(ok, dx, 1.0), slope)
            slope = np.where(slope > 1e-3, slope, n[active] + 0.5)
        x_lo = np.where(g < 0, x, x_lo)
        x_hi = np.where(g > 0, x, x_hi)
        collapsed = (x_hi - x_lo) < 1e-15 * np.maximum(1.0, np.abs(x))
        too_large[active[collapsed & (g < 0) & (x_hi == x_top)]] = True
        done |= collapsed
        out[active[done]] = np.exp(x[done])
        keep = ~done
        if not keep.any():
            _check(too_large, "load_n", w, "load too large: balance-mode sinkage would reach the wheel "
                   f"radius r = {r} m (theta1 >= 90 deg)")
            return out
        active, x, g, slope = active[keep], x[keep], g[keep], np.broadcast_to(slope, keep.shape)[keep]
        x_lo, x_hi = x_lo[keep], x_hi[keep]
        x_new = x - g / slope
        outside = ~((x_new > x_lo) & (x_new < x_hi))
        mid = np.where(np.isfinite(x_lo), 0.5 * (x_lo + x_hi), x_hi - 2.0)
        x_prev, g_prev = x, g
        x = np.where(outside, mid, x_new)
    raise RuntimeError("balance-mode sinkage did not converge")  # pragma: no cover


def _small_angle_load_factor(ratio: np.ndarray, n: np.ndarray) -> np.ndarray:
    """W(Wong-Reece) / W(paper) at equal sinkage, small angles and no shear; (N,) like ``ratio``.

    With sigma ~ (theta1^2 - theta^2)^n and the rear region mapped linearly onto
    the front, W ~ int_rho^1 (1 - x^2)^n dx / (1 - rho) against int_0^1 for
    rho = theta_m/theta1 (incomplete beta function). Only a starting point for
    the balance-mode solver: it saves about one secant iteration.
    """
    from scipy.special import betainc

    return (1.0 - betainc(0.5, n + 1.0, ratio * ratio)) / (1.0 - ratio)


def _stress_ratio(stress, s: np.ndarray) -> np.ndarray | None:
    """theta_m/theta1 = a1 + a2 s of shape (N,) from ``stress = (a1, a2)``; None for None.

    a1, a2 are scalars or (N,) arrays. Raises ValueError for a malformed pair,
    a non-finite coefficient, or a ratio outside [0, 1) (naming the sample).
    """
    if stress is None:
        return None
    if isinstance(stress, (str, bytes)) or not hasattr(stress, "__len__") or len(stress) != 2:
        raise ValueError(f"stress must be None or a pair (a1, a2) of the Wong-Reece theta_m = "
                         f"(a1 + a2 s) theta1, got {stress!r}")
    size = len(s)
    coef = []
    for label, value in zip(("stress_a1", "stress_a2"), stress):
        try:
            arr = np.broadcast_to(np.asarray(value, dtype=float), (size,))
        except (TypeError, ValueError):
            raise ValueError(f"{label} must be a number or an array of shape ({size},), got {value!r}") from None
        _check(~np.isfinite(arr), label, arr, "Wong-Reece coefficient must be finite")
        coef.append(arr)
    ratio = coef[0] + coef[1] * s
    _check((ratio < 0) | (ratio >= 1), "stress_ratio", ratio,
           "theta_m/theta1 = a1 + a2*s must be in [0, 1) (the maximum normal stress lies "
           "inside the contact, between exit (theta = 0) and entry (theta1))")
    return ratio


def _per_sample(value, name: str, s: np.ndarray, bad, rule: str, neutral: float) -> np.ndarray | None:
    """``value`` (a number or (N,)) as a float array of ``s``'s shape (N,), checked finite and not
    ``bad``; None when ``value`` is None or ``neutral`` at every sample.  Raises ValueError naming
    the first offending element (``name[i]``) and ``rule``, or a value of the wrong shape."""
    if value is None:
        return None
    try:
        arr = np.broadcast_to(np.asarray(value, dtype=float), s.shape).copy()
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number or an array of shape ({len(s)},), got {value!r}") from None
    _check(~np.isfinite(arr) | bad(arr), name, arr, rule)
    return None if np.all(arr == neutral) else arr


def wong_forces(
    terrain: Terrain,
    wheel: Wheel,
    load_n,
    slip,
    *,
    sinkage: str = "eq10",
    z_fn: ZFn | None = None,
    n_fn: NFn | None = None,
    n_in_z0: bool = True,
    stress=None,
    exit_ratio=None,
    tau_scale=None,
    shear_power=None,
) -> WheelForces:
    """Wong's rigid-wheel forces for each sample (paper Eqs. 1-10).

    Inputs: ``load_n`` W [N] and ``slip`` s [-], arrays of shape (N,) (scalars
    broadcast). ``sinkage`` chooses the static sinkage z0:
    ``"eq10"`` Eq. (10) (small-angle closed form, the paper's choice), or
    ``"balance"`` solve Eq. (7)(z0, s) = W per sample (the exact vertical
    balance at the sample's slip, with the chosen stress distribution; Eq. (10)
    differs from it by several percent for n < 0.8). ``n_fn(slip) -> N``
    replaces the sinkage exponent in both Eq. (2) and Eq. (10) (Ding, Eq. 13),
    or with ``n_in_z0=False`` in Eq. (2) only, the static sinkage z0 (Eq. 10
    or the balance) taken with the terrain's n (the other reading of Eq. 13);
    ``z_fn(z0, slip) -> z`` maps the static sinkage to the sinkage used in
    Eqs. (1)-(9) (Vasil'ev Eq. 11, Lyasko Eq. 12). In balance mode the
    transform is applied to the balanced z0, so the model's W equals the input
    W only without ``z_fn``.

    ``stress`` chooses the normal-stress distribution:

    - ``None`` (default): the paper's, Eqs. (2)-(3) over [0, theta1]:
      sigma = k_eq (r (cos theta - cos theta1))^n, largest at theta = 0
      (bottom dead centre, where the exit angle theta2 = 0 lies).
    - ``(a1, a2)`` (floats, or (N,) arrays): Wong-Reece. The maximum lies at
      theta_m = (a1 + a2 s) theta1; front region theta_m <= theta <= theta1:
      sigma = k_eq (r (cos theta - cos theta1))^n; rear region
      0 <= theta <= theta_m: sigma = k_eq (r (cos(theta1 - theta/theta_m
      (theta1 - theta_m)) - cos theta1))^n (zero at the exit theta2 = 0);
      k_eq = kc/b + kphi. Shear from Eqs. (4)-(5) with j over the whole
      contact, W, Dp, T from Eqs. (7)-(9). ``(0, 0)`` is the paper's model
      (theta_m = 0, no rear region; same numbers bit for bit). a1 + a2 s must
      lie in [0, 1) for every sample. In ``eq10`` mode z0 still comes from
      Eq. (10) (derived for the paper's distribution); use ``balance`` for the
      vertical balance with this distribution.
      Source: Wong, Theory of Ground Vehicles, 4th ed., Wiley 2008, ch. 2
      (Wong & Reece, J. Terramechanics 4(1) 1967). Values commonly quoted
      from Wong & Reece for sand: a1 ~ 0.43, a2 ~ 0.32 (secondary citation,
      not checked against the 1967 paper here). A fitter should bound
      a1 + a2 s_max below 1 (e.g. a1 <= 0.6, a2 <= 0.35).

    ``exit_ratio`` (float or (N,) array, >= 0 and < 1; None or 0: the paper's exit
    theta2 = 0): a soil that rebounds behind the wheel, exit angle theta2 = exit_ratio
    theta1. The rear region then runs from theta_m down to -theta2 with
    sigma = k_eq (r (cos(theta1 - (theta + theta2)/(theta_m + theta2) (theta1 - theta_m))
    - cos theta1))^n (zero at the exit), Eq. (5) continued over it. Source: Wong, Theory
    of Ground Vehicles, 4th ed., ch. 2 (rear region with an exit angle); Wong & Reece 1967.

    ``tau_scale`` (float or (N,) array, > 0; None: 1) multiplies the shear strength
    c + sigma tan phi of Eq. (4) per sample (a shear strength that changes with slip, e.g.
    rate effects or remoulding: 1 + b s).

    ``shear_power`` (``(sigma0, beta, gamma)``, floats, sigma0 > 0 [Pa]; None: the paper's
    Eq. 4, same as ``(sigma0, 1, 0)``): shear parameters that depend on the normal stress,
    strength c + tan phi sigma0 (sigma/sigma0)^beta (a curved failure envelope, a power law
    that meets the straight Mohr-Coulomb line at sigma0) and modulus K (sigma/sigma0)^gamma.
    Source: paper Eq. (4) with power laws in the normal stress (a modelling alternative, not a
    law from the paper: the Mohr-Coulomb line of Eq. (4) is a straight fit over the lab's
    stress range).

    Quadrature: each region by the substituted 24-point Gauss-Legendre rule
    (u^3 substitution at the end where the stress vanishes like a power n);
    the kink at theta_m is a region boundary, so both integrands are smooth.

    Returns ``WheelForces`` with (N,) arrays: sinkage_m, theta1_rad,
    load_model_n (Eq. 7), drawbar_pull_n (Eq. 8), torque_nm (Eq. 9).

    Raises ``ValueError`` naming the element and the rule for: NaN/inf load
    or slip, W <= 0, s < 0 (skid is not modelled), s >= 1, a sinkage exponent
    outside (0, 3), kc/b + kphi <= 0, a sinkage < 0 or >= r (theta1 >= 90 deg),
    an unknown ``sinkage`` mode, a malformed ``stress`` or a non-finite
    coefficient, theta_m/theta1 = a1 + a2 s outside [0, 1) (``stress_ratio[i]``),
    an exit ratio that is not finite or outside [0, 1) (``exit_ratio[i]``), a shear-strength
    factor that is not finite and positive (``tau_scale[i]``), a ``shear_power`` that is not three
    finite numbers with sigma0 > 0 (``shear_power``).
    """
    if sinkage not in SINKAGE_MODES:
        raise ValueError(f"sinkage mode must be one of {', '.join(SINKAGE_MODES)}, got {sinkage!r}")
    w, s = _as_samples(load_n, slip)
    ratio = _stress_ratio(stress, s)
    # theta2 = 0 and a factor 1 are the paper's exit and Eq. (4): the same numbers bit for bit
    exit_ratio = _per_sample(exit_ratio, "exit_ratio", s, lambda v: (v < 0) | (v >= 1),
                             "exit angle theta2/theta1 must be in [0, 1)", neutral=0.0)
    tau_scale = _per_sample(tau_scale, "tau_scale", s, lambda v: v <= 0,
                            "the shear-strength factor must be finite and > 0", neutral=1.0)
    if shear_power is not None:
        try:
            shear_power = tuple(float(v) for v in shear_power)
        except (TypeError, ValueError):
            shear_power = ()
        if len(shear_power) != 3 or not all(map(math.isfinite, shear_power)) or shear_power[0] <= 0:
            raise ValueError(f"shear_power must be (sigma0 > 0 [Pa], beta, gamma), finite numbers; got {shear_power!r}")
        if shear_power[1:] == (1.0, 0.0):
            shear_power = None
    r, b = wheel.radius, wheel.width
    if terrain.kc / b + terrain.kphi <= 0:
        raise ValueError(
            f"terrain {terrain.name!r}: kc/b + kphi = {terrain.kc / b + terrain.kphi!r} must be > 0 "
            f"for wheel width b = {b} m (Eq. 2)"
        )
    if n_fn is None:
        n = np.full(len(w), terrain.n)
    else:
        n = _shaped(n_fn(s), w.shape).copy()
        _check(~np.isfinite(n) | (n <= 0) | (n >= 3), "sinkage_exponent", n,
               "sinkage exponent N must be in (0, 3) (Eqs. 2, 10)")
    n_z0 = n if n_in_z0 else np.full(len(w), terrain.n)
    z0 = sinkage_eq10(terrain, wheel, w, n_z0)
    if sinkage == "balance":
        z_start = z0 if ratio is None else z0 * _small_angle_load_factor(ratio, n_z0) ** (-1.0 / (n_z0 + 0.5))
        z0 = _balance_sinkage(terrain, wheel, w, s, n_z0, z_start, ratio, exit_ratio, tau_scale, shear_power)
    z = z0 if z_fn is None else _shaped(z_fn(z0, s), w.shape).copy()
    if not ((z >= 0) & (z < r)).all():  # NaN fails both: then name the first bad element
        _check(~np.isfinite(z), "sinkage_m", z, "sinkage is not finite")
        _check(z < 0, "sinkage_m", z, "sinkage must be >= 0 m")
        _check(z >= r, "sinkage_m", z, f"sinkage must be < wheel radius r = {r} m "
               "(theta1 >= 90 deg is outside the model)")
    theta1, w_model, dp, t = _integrals(terrain, wheel, z, s, n, ratio=ratio, exit_ratio=exit_ratio,
                                        tau_scale=tau_scale, shear_power=shear_power)
    return WheelForces(
        sinkage_m=z, theta1_rad=theta1, load_model_n=w_model, drawbar_pull_n=dp, torque_nm=t
    )


def wong_forces_quad(
    terrain: Terrain, wheel: Wheel, load_n, slip, *, sinkage_m=None, n=None, stress=None
) -> WheelForces:
    """Reference: Eqs. (1)-(10) written literally, one ``scipy.integrate.quad`` per integral and sample.

    Slow (about 1e3 samples/s); for tests and benchmarks only. ``sinkage_m``
    (N,) overrides Eq. (10); ``n`` overrides the exponent; ``stress``
    ``(a1, a2)`` (scalars or (N,) arrays) selects the Wong-Reece distribution
    exactly as in ``wong_forces`` (each integral split at theta_m, the kink of
    the stress). Same shapes and output as ``wong_forces``; no input validation.
    Source: paper Eqs. (1)-(10), typos fixed; Wong, Theory of Ground Vehicles,
    4th ed., ch. 2 (Wong-Reece distribution); scipy.integrate.quad (QUADPACK QAGS).
    """
    from scipy.integrate import quad

    w = np.atleast_1d(np.asarray(load_n, dtype=float))
    s_all = np.broadcast_to(np.atleast_1d(np.asarray(slip, dtype=float)), w.shape)
    nn = terrain.n if n is None else n
    n_all = np.broadcast_to(np.asarray(nn, dtype=float), w.shape)
    if stress is None:
        a1_all = a2_all = np.zeros(w.shape)
    else:
        a1_all = np.broadcast_to(np.asarray(stress[0], dtype=float), w.shape)
        a2_all = np.broadcast_to(np.asarray(stress[1], dtype=float), w.shape)
    r, b = wheel.radius, wheel.width
    c, phi, K, kc, kphi = terrain.c, terrain.phi, terrain.K, terrain.kc, terrain.kphi
    out = np.empty((5, len(w)))
    for i in range(len(w)):
        s, ni = float(s_all[i]), float(n_all[i])
        if sinkage_m is None:  # Eq. (10)
            z0 = (3 * w[i] / (math.sqrt(2 * r) * (kc + b * kphi) * (3 - ni))) ** (2 / (2 * ni + 1))
        else:
            z0 = float(np.broadcast_to(sinkage_m, w.shape)[i])
        th1 = math.acos(1 - z0 / r)  # Eq. (1)
        thm = (float(a1_all[i]) + float(a2_all[i]) * s) * th1  # Wong-Reece theta_m (0: paper)

        def sigma_front(th):  # Eqs. (2), (3)
            return (kc / b + kphi) * max(r * (math.cos(th) - math.cos(th1)), 0.0) ** ni

        def sigma_rear(th):  # Wong-Reece rear region: the front's stress at the mapped angle
            return sigma_front(th1 - th / thm * (th1 - thm))

        def tau(th, sigma):  # Eqs. (4), (5)
            j = r * (th1 - th - (1 - s) * (math.sin(th1) - math.sin(th)))
            return (c + sigma(th) * math.tan(phi)) * (1 - math.exp(-j / K))

        def integral(f):
            total = 0.0
            for lo, hi, sig in ((0.0, thm, sigma_rear), (thm, th1, sigma_front)):
                if hi > lo:
                    total += quad(lambda t: f(t, sig), lo, hi, epsabs=0.0, epsrel=1e-12, limit=200)[0]
            return total

        w_m = r * b * (integral(lambda t, g: g(t) * math.cos(t)) + integral(lambda t, g: tau(t, g) * math.sin(t)))
        dp = r * b * (integral(lambda t, g: tau(t, g) * math.cos(t)) - integral(lambda t, g: g(t) * math.sin(t)))
        tq = r * r * b * integral(tau)
        out[:, i] = (z0, th1, w_m, dp, tq)
    return WheelForces(*out)
