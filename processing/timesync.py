"""Clocks: host -> GPS time mapping, and the GNSS velocity latency.

All signals stay on the host timebase (kernel receive time, int64 ns since
the Unix epoch; both buses share it, hardware.md "Buses"). Two things are
estimated from the data:

* :func:`fit_gps_time_mapping` — a robust straight line from host time to the
  receiver's GPS time (``RT_SB_GPS_Time``: GPS week and time of week of the
  fix): ``gps_s = gps_at_t0_s + (1 + drift) * (host_s - t0_s)``. Robust by an
  initial Theil-Sen line (scipy.stats.theilslopes on at most 400 points) and
  least squares on the points within 5 MADs (at least 2 ms) of it.
* :func:`estimate_tooth_lag` — a wheel-speed module's delay that grows at low
  speed (a tone wheel timed per tooth): ``lag + pitch / omega``.
* :func:`estimate_clock_offset` — the offset between the clocks of two buses that each read the
  same wheel's speed (a logger whose adapters stamp frames each on its own clock), by the
  correlation of the two speed histories over shifts of up to the run's length.
* :func:`estimate_latency` — the delay of the GNSS velocity behind a
  reference speed measured without delay: ``v_gnss(t) = a * v_ref(t - tau) + b``
  (the gain ``a`` absorbs an effective rolling radius different from r, ``b``
  small offsets). ``tau`` minimises the sum of squares over a grid
  (2 ms steps) and then by a bounded scalar minimisation; its standard error is
  the Gauss-Newton one, ``sigma^2 / sum((a dv_ref/dt)^2)``, inflated by
  ``(1 + rho)/(1 - rho)`` for the lag-1 autocorrelation ``rho`` of the residuals.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from .filters import filter_to_grid, lowpass_segments

__all__ = ["GPS_EPOCH_UNIX_S", "fit_gps_time_mapping", "LatencyEstimate", "estimate_latency",
           "estimate_latency_traction", "ToothLag", "estimate_tooth_lag", "ClockOffset", "estimate_clock_offset"]

#: 1980-01-06T00:00:00 (GPS epoch) in Unix seconds (UTC, no leap seconds).
GPS_EPOCH_UNIX_S = 315_964_800
SECONDS_PER_WEEK = 604_800


def fit_gps_time_mapping(host_ns: np.ndarray, gps_week: np.ndarray, gps_tow_s: np.ndarray,
                         *, t0_ns: int | None = None) -> dict:
    """Fit host receive time -> GPS time of the fix, robustly.

    Parameters: ``host_ns`` int64 (N,) host receive times of ``RT_SB_GPS_Time``
    frames; ``gps_week`` (N,) GPS week numbers; ``gps_tow_s`` (N,) time of week
    [s]; ``t0_ns`` the host time the offset is reported at (default the first
    frame).

    Returns a dict: ``t0_ns``; ``gps_at_t0_s`` GPS seconds since the GPS epoch
    at host ``t0``; ``offset_s`` = GPS time minus host time read as GPS time
    (``host Unix s - 315964800``); a host clock synchronised to UTC gives the
    GPS-UTC leap seconds (18 s since 2017) plus the receiver's output latency;
    ``drift_ppm`` rate difference of the clocks; ``residual_rms_s``,
    ``residual_max_s`` of the inliers; ``n``, ``n_outliers``.
    Frames with week 0 and time 0 (no fix) are ignored. Raises ``ValueError``
    with fewer than 3 usable frames.
    """
    host_ns = np.asarray(host_ns, dtype=np.int64)
    week = np.asarray(gps_week, dtype=np.float64)
    tow = np.asarray(gps_tow_s, dtype=np.float64)
    ok = np.isfinite(week) & np.isfinite(tow) & ((week > 0) | (tow > 0))
    if np.count_nonzero(ok) < 3:
        raise ValueError(f"only {np.count_nonzero(ok)} usable GPS time frames (need 3)")
    if t0_ns is None:
        t0_ns = int(host_ns[ok][0])
    x = (host_ns[ok] - t0_ns) * 1e-9
    gps = week[ok] * SECONDS_PER_WEEK + tow[ok]
    # subtract a whole-second reference so the fit works on small numbers
    ref = float(np.floor(np.median(gps - x)))
    y = gps - ref
    step = max(1, x.shape[0] // 400)
    slope, intercept, _, _ = stats.theilslopes(y[::step], x[::step])
    res = y - (intercept + slope * x)
    mad = float(np.median(np.abs(res - np.median(res)))) * 1.4826
    inl = np.abs(res) <= max(5 * mad, 2e-3)
    if np.count_nonzero(inl) >= 3:
        slope, intercept = np.polyfit(x[inl], y[inl], 1)
        res = y - (intercept + slope * x)
    gps_at_t0 = ref + float(intercept)
    host_as_gps = t0_ns * 1e-9 - GPS_EPOCH_UNIX_S
    r = res[inl]
    return {
        "t0_ns": int(t0_ns),
        "gps_at_t0_s": gps_at_t0,
        "gps_week_at_t0": int(gps_at_t0 // SECONDS_PER_WEEK),
        "gps_tow_at_t0_s": float(gps_at_t0 % SECONDS_PER_WEEK),
        "offset_s": gps_at_t0 - host_as_gps,
        "drift_ppm": (float(slope) - 1.0) * 1e6,
        "residual_rms_s": float(np.sqrt(np.mean(r**2))) if r.size else float("nan"),
        "residual_max_s": float(np.max(np.abs(r))) if r.size else float("nan"),
        "n": int(x.shape[0]),
        "n_outliers": int(np.count_nonzero(~inl)),
    }


@dataclass
class LatencyEstimate:
    """Result of :func:`estimate_latency`: ``latency_s``, ``stderr_s``, gain ``a``,
    offset ``b`` [m/s], residual RMS [m/s], points used ``n``, and a ``note``."""

    latency_s: float
    stderr_s: float
    gain: float
    offset_mps: float
    residual_rms_mps: float
    n: int
    note: str = ""


def _ar1_inflation(resid: np.ndarray | None) -> float:
    """``(1 + rho)/(1 - rho)`` for the lag-1 autocorrelation ``rho`` of the residuals ``resid`` (n,), ``rho``
    clipped to 0..0.95 (1 for fewer than 4 residuals, None or an undefined ``rho``): the factor by which
    correlated residuals inflate a least-squares variance (the estimators' standard errors)."""
    if resid is None or resid.size <= 3:
        return 1.0
    rho = float(np.corrcoef(resid[:-1], resid[1:])[0, 1])
    rho = min(max(rho, 0.0), 0.95) if np.isfinite(rho) else 0.0
    return (1 + rho) / (1 - rho)


def _fit_at(tau: float, t_g: np.ndarray, v_g: np.ndarray, t_ref: np.ndarray, v_ref: np.ndarray,
            keep_ref: np.ndarray):
    """Linear fit v_g ~ a*v_ref(t_g - tau) + b on usable points; returns (sse, a, b, mask, x)."""
    x = np.interp(t_g - tau, t_ref, v_ref, left=np.nan, right=np.nan)
    k = np.interp(t_g - tau, t_ref, keep_ref.astype(np.float64), left=0.0, right=0.0) > 0.999
    m = k & np.isfinite(x) & np.isfinite(v_g)
    if np.count_nonzero(m) < 10:
        return np.inf, np.nan, np.nan, m, x
    A = np.column_stack([x[m], np.ones(np.count_nonzero(m))])
    coef, *_ = np.linalg.lstsq(A, v_g[m], rcond=None)
    r = v_g[m] - A @ coef
    return float(r @ r) / np.count_nonzero(m), float(coef[0]), float(coef[1]), m, x


def estimate_latency(t_gnss_s: np.ndarray, v_gnss: np.ndarray, t_ref_s: np.ndarray, v_ref: np.ndarray,
                     *, usable_ref: np.ndarray | None = None, max_latency_s: float = 0.5,
                     min_speed_mps: float = 0.3, min_latency_s: float = 0.0) -> LatencyEstimate:
    """Estimate how late the GNSS velocity arrives relative to a reference speed.

    Parameters: ``t_gnss_s`` (N,) host receive times [s] of the GNSS speed,
    ``v_gnss`` (N,) [m/s]; ``t_ref_s`` (M,) sorted host times [s] of a
    reference speed with negligible delay (r*omega of free-rolling wheels,
    filtered), ``v_ref`` (M,) [m/s]; ``usable_ref`` (M,) bool: where the
    reference may be trusted (e.g. no hard braking); points with reference
    speed below ``min_speed_mps`` are not used; search range
    ``min_latency_s..max_latency_s`` (negative: the reference is itself read
    later than the GNSS speed, e.g. a tone-wheel module reporting the last
    tooth period).

    Returns :class:`LatencyEstimate` (``latency_s`` positive = GNSS late).
    Raises ``ValueError`` when fewer than 10 usable points overlap or the
    speed never varies (nothing to align).
    """
    t_g = np.asarray(t_gnss_s, dtype=np.float64)
    v_g = np.asarray(v_gnss, dtype=np.float64)
    t_r = np.asarray(t_ref_s, dtype=np.float64)
    v_r = np.asarray(v_ref, dtype=np.float64)
    keep = np.isfinite(v_r) & (v_r >= min_speed_mps)
    if usable_ref is not None:
        keep &= np.asarray(usable_ref, dtype=bool)
    taus = _lag_grid(min_latency_s, max_latency_s)
    sse = np.array([_fit_at(t, t_g, v_g, t_r, v_r, keep)[0] for t in taus])
    if not np.isfinite(sse).any():
        raise ValueError("fewer than 10 GNSS samples overlap a usable reference speed")
    i = int(np.nanargmin(sse))
    lo, hi = taus[max(i - 2, 0)], taus[min(i + 2, taus.size - 1)]
    res = optimize.minimize_scalar(lambda t: _fit_at(t, t_g, v_g, t_r, v_r, keep)[0],
                                   bounds=(lo, hi), method="bounded", options={"xatol": 1e-5})
    tau = float(res.x)
    mse, a, b, m, x = _fit_at(tau, t_g, v_g, t_r, v_r, keep)
    dv = np.gradient(v_r, t_r)
    slope = a * np.interp(t_g - tau, t_r, dv)[m]
    resid = v_g[m] - (a * x[m] + b)
    n = int(np.count_nonzero(m))
    s2 = float(resid @ resid) / max(n - 3, 1)
    # the information on tau given the fitted gain and offset (Gauss-Newton covariance of
    # (a, b, tau), Seber & Wild 1989, 2.1): a reference changing at a constant rate (a wheel
    # coasting at one deceleration) shifts by a constant that the offset takes up, and tells
    # nothing. A gap in the reference (lost frames: NaN) spreads to its neighbours' gradient;
    # the information comes from the points where the slope is defined.
    ok = np.isfinite(slope)
    J = np.column_stack([x[m][ok], np.ones(int(ok.sum())), slope[ok]])
    jtj = J.T @ J
    if not (ok.sum() > 3 and np.any(slope[ok] != 0)) or np.linalg.cond(jtj) > 1e12:
        raise ValueError("the reference speed never changes its rate: the latency cannot be estimated")
    stderr = float(np.sqrt(s2 * np.linalg.inv(jtj)[2, 2] * _ar1_inflation(resid)))
    note = ""
    if tau <= min_latency_s + 0.004 or tau >= max_latency_s - 0.004:
        note = _edge_note(min_latency_s, max_latency_s)
    return LatencyEstimate(tau, stderr, a, b, float(np.sqrt(mse)), n, note)


@dataclass
class ToothLag:
    """A wheel-speed module's delay that grows as the wheel slows (:func:`estimate_tooth_lag`).

    ``delay(omega) = lag_s + pitch_rad / max(|omega|, min_omega_radps)`` [s], at most ``max_s``
    (below the slowest speed fitted the delay is not extrapolated): a module that times the
    wheel over its last tooth interval (or over a fixed window, and over the last interval when
    fewer teeth pass in it) reports the speed of the middle of that interval, some time after its
    last edge: one tooth period ``2 pi / (N omega)`` later on average for N teeth, plus a constant
    delay of its own (a frame cycle, a gateway). ``pitch_rad`` is the angle the wheel turns in the
    speed-dependent part (2 pi / N for such a module), with standard errors ``stderr_lag_s``,
    ``stderr_pitch_rad``; ``gain`` the module's speed over the reference's, ``residual_rms``
    [rad/s], ``n`` readings used."""

    lag_s: float
    pitch_rad: float
    stderr_lag_s: float
    stderr_pitch_rad: float
    gain: float
    residual_rms: float
    n: int
    max_s: float
    min_omega_radps: float

    def delay_s(self, omega_radps: np.ndarray) -> np.ndarray:
        """The delay [s] (same shape as ``omega_radps`` [rad/s]; NaN speed: the slowest's)."""
        w = np.abs(np.asarray(omega_radps, dtype=np.float64))
        w = np.where(w >= self.min_omega_radps, w, self.min_omega_radps)  # NaN too
        return np.minimum(self.lag_s + self.pitch_rad / w, self.max_s)

    def unlag(self, t_s: np.ndarray, omega_radps: np.ndarray) -> np.ndarray:
        """The times [s] the readings (``t_s`` (n,) sorted times [s], ``omega_radps`` (n,) the
        module's speeds, best low-passed: the delay uses 1/omega) belong to: ``t - delay(omega)``;
        returns a bool mask (n,) of the readings to keep with ``t_s[mask] - delay[mask]``: a reading
        whose moved time is not after every earlier one's repeats an older interval (the wheel slowing
        faster than its teeth pass) and is dropped, so the times stay strictly increasing."""
        tn = np.asarray(t_s, dtype=np.float64) - self.delay_s(omega_radps)
        prev = np.concatenate([[-np.inf], np.maximum.accumulate(tn)[:-1]])
        return tn > prev


#: A per-tooth delay (:class:`ToothLag`) is taken when its pitch is this many standard errors
#: above zero (three sigma: a one-sided p of about 0.001).
TOOTH_LAG_MIN_Z = 3.0


def estimate_tooth_lag(t_mod_s: np.ndarray, omega_mod: np.ndarray, omega_mod_smooth: np.ndarray,
                       t_ref_s: np.ndarray, omega_ref: np.ndarray, *, start_lag_s: float,
                       min_lag_s: float, max_lag_s: float, min_omega_radps: float) -> ToothLag:
    """Fit a wheel-speed module's speed-dependent delay against a reference read without delay.

    The model (:class:`ToothLag`): ``omega_mod(t) = g * omega_ref(t - lag - pitch / omega)``, fitted
    by ``scipy.optimize.least_squares`` (bounds ``min_lag_s <= lag <= max_lag_s``, ``pitch >= 0``,
    gain ``g`` in 0.8..1.2) from ``lag = start_lag_s`` (the constant delay of
    :func:`estimate_latency`), pitch 0, g 1. The speed in ``1/omega`` is the module's own,
    low-passed (``omega_mod_smooth``): the only speed there is for the wheels without a reference.

    ``t_mod_s`` (M,) the module's reading times [s], ``omega_mod`` (M,) its speeds [rad/s] (|.|
    taken), ``omega_mod_smooth`` (M,) the same low-passed; ``t_ref_s`` (N,) sorted reference times
    [s], ``omega_ref`` (N,) the reference speed (the wheel angle's derivative on the forces' clock,
    low-passed); readings slower than ``min_omega_radps`` or whose delay reaches ``max_lag_s`` are
    not used. Standard errors are the Gauss-Newton ones inflated by ``(1 + rho)/(1 - rho)`` for the
    residuals' lag-1 autocorrelation, as :func:`estimate_latency`'s. Source: the delay of a
    period-measuring speed sensor, a tooth period at low speed (e.g. Bosch, *Automotive Handbook*,
    wheel-speed sensors; any tone-wheel period counter). Raises ``ValueError`` with fewer than 100
    usable readings or when the speed never changes its rate.
    """
    t_m = np.asarray(t_mod_s, dtype=np.float64)
    w_m = np.abs(np.asarray(omega_mod, dtype=np.float64))
    w_s = np.abs(np.asarray(omega_mod_smooth, dtype=np.float64))
    t_r = np.asarray(t_ref_s, dtype=np.float64)
    w_r = np.asarray(omega_ref, dtype=np.float64)
    fin = np.isfinite(w_r)
    t_r, w_r = t_r[fin], w_r[fin]
    if t_r.size < 10:
        raise ValueError("fewer than 10 reference speeds")
    dw_r = np.gradient(w_r, t_r)
    use = np.isfinite(w_m) & np.isfinite(w_s) & (w_s >= min_omega_radps) & (t_m > t_r[0]) & (t_m < t_r[-1])
    t_m, w_m, inv = t_m[use], w_m[use], 1.0 / w_s[use]
    if t_m.size < 100:
        raise ValueError(f"only {t_m.size} wheel speed readings above {min_omega_radps:g} rad/s overlap the "
                         "reference (need 100)")

    def parts(x):
        d = x[0] + x[1] * inv
        tq = t_m - d
        return d, np.interp(tq, t_r, w_r), np.interp(tq, t_r, dw_r)

    def resid(x):
        d, wr, _ = parts(x)
        return np.where(d < max_lag_s, w_m - x[2] * wr, 0.0)

    def jac(x):
        d, wr, dwr = parts(x)
        inside = (d < max_lag_s)[:, None]
        return np.where(inside, np.column_stack([x[2] * dwr, x[2] * dwr * inv, -wr]), 0.0)

    x0 = [min(max(start_lag_s, min_lag_s), max_lag_s - 1e-3), 0.0, 1.0]
    sol = optimize.least_squares(resid, x0, jac=jac, bounds=([min_lag_s, 0.0, 0.8], [max_lag_s, 1.0, 1.2]),
                                 x_scale=[0.01, 0.1, 0.01])
    d = sol.x[0] + sol.x[1] * inv
    m = d < max_lag_s
    r = sol.fun[m]
    J = sol.jac[m]
    n = int(m.sum())
    if n < 100 or np.linalg.cond(J.T @ J) > 1e12:
        raise ValueError("the wheel speed never changes its rate enough to fit a speed-dependent delay")
    s2 = float(r @ r) / max(n - 3, 1)
    cov = s2 * np.linalg.inv(J.T @ J) * _ar1_inflation(r)
    return ToothLag(lag_s=float(sol.x[0]), pitch_rad=float(sol.x[1]), stderr_lag_s=float(np.sqrt(cov[0, 0])),
                    stderr_pitch_rad=float(np.sqrt(cov[1, 1])), gain=float(sol.x[2]),
                    residual_rms=float(np.sqrt(s2)), n=n, max_s=float(max_lag_s),
                    min_omega_radps=float(min_omega_radps))


def _lag_grid(lo_s: float, hi_s: float) -> np.ndarray:
    """The 2 ms grid of lags [s] over ``lo_s..hi_s`` that both estimators search first."""
    if not hi_s > lo_s:
        raise ValueError(f"empty latency search range {lo_s:g}..{hi_s:g} s")
    return lo_s + np.arange(0.0, hi_s - lo_s + 1e-9, 0.002)


def _edge_note(lo_s: float, hi_s: float) -> str:
    return f"latency at the edge of the search range {lo_s:g}..{hi_s:g} s"


#: Slip range [-] used by :func:`estimate_latency_traction` (outside: locked or spinning wheel).
TRACTION_SLIP_RANGE = (-0.5, 0.95)
#: An estimate within this [s] (or two standard errors) of either end of the search range is
#: an edge hit (the profile may still fall beyond it).
TRACTION_EDGE_S = 0.010
#: Cutoff [Hz] of the zero-phase low-pass applied alike to the GNSS speed and the wheel's speed,
#: traction coefficient and load before :func:`estimate_latency_traction` computes slip (see there).
TRACTION_SMOOTH_HZ = 2.0


def _traction_sse(tau: float, t_g: np.ndarray, v_g: np.ndarray, t_ref: np.ndarray, w_ref: np.ndarray,
                  x_ref: np.ndarray, keep_ref: np.ndarray, n_knots: int, min_speed_mps: float,
                  dw_ref: np.ndarray | None = None):
    """Least-squares cubic spline of the traction coefficient on slip at lag ``tau``
    (plus a second spline times the relative load change ``dw_ref``, if given).

    Returns ``(sse, n, resid, mask)``: ``sse`` sum of squared residuals of
    ``x - g(s) - h(s) dW`` [-] over the usable GNSS samples (inf when the fit is impossible)."""
    from scipy.interpolate import BSpline

    tq = t_g - tau
    w = np.interp(tq, t_ref, w_ref, left=np.nan, right=np.nan)
    x = np.interp(tq, t_ref, x_ref, left=np.nan, right=np.nan)
    k = np.interp(tq, t_ref, keep_ref.astype(np.float64), left=0.0, right=0.0) > 0.999
    m = k & np.isfinite(w) & np.isfinite(x) & np.isfinite(v_g) & (w >= min_speed_mps)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = 1.0 - v_g / w
    m &= (s > TRACTION_SLIP_RANGE[0]) & (s < TRACTION_SLIP_RANGE[1])
    n = int(np.count_nonzero(m))
    if n < 10 * (n_knots + 4):
        return np.inf, n, None, m
    sm, xm = s[m], x[m]
    inner = np.quantile(sm, np.linspace(0.0, 1.0, n_knots + 2)[1:-1])
    knots = np.concatenate([[sm.min()] * 4, inner, [sm.max()] * 4])
    try:
        B = BSpline.design_matrix(sm, knots, 3).toarray()
    except ValueError:
        return np.inf, n, None, m
    if dw_ref is not None:
        dw = np.interp(tq, t_ref, dw_ref)[m]
        B = np.column_stack([B, B * dw[:, None]])
    # normal equations by einsum (no multi-threaded BLAS on the tall matrix: this runs ~260 times
    # and a threaded BLAS on a busy machine is ~30x slower); the small system by SVD least squares
    gram = np.einsum("ij,ik->jk", B, B)
    coef = np.linalg.lstsq(gram, np.einsum("ij,i->j", B, xm), rcond=1e-12)[0]
    r = xm - np.einsum("ij,j->i", B, coef)
    return float(np.einsum("i,i->", r, r)), n, r, m


def estimate_latency_traction(t_gnss_s: np.ndarray, v_gnss: np.ndarray, t_ref_s: np.ndarray,
                              wheel_speed_mps: np.ndarray, traction_coeff: np.ndarray, *,
                              load_n: np.ndarray | None = None, usable_ref: np.ndarray | None = None,
                              max_latency_s: float = 0.5, min_speed_mps: float = 1.0,
                              n_knots: int = 10, min_latency_s: float = 0.0,
                              smooth_hz: float | None = TRACTION_SMOOTH_HZ) -> LatencyEstimate:
    """GNSS latency from slip-traction consistency: needs no free-rolling wheel.

    A wheel's torque at a given load is a function of its slip (the paper's
    Eqs. 1-6: T(s) at load W; Wong, *Theory of Ground Vehicles*, ch. 2). With
    the GNSS speed shifted by the wrong lag, the slip ``s = 1 - V/(r omega)``
    (Eq. 6) computed from it is off by about ``(tau_true - tau) dV/dt /
    (r omega)``, which changes sign between accelerating and braking and scales
    with 1/speed, so the points of the torque-slip cloud scatter about any one
    curve (hysteresis loops). The latency is the lag that minimises the scatter
    ``sum (x - g(s))^2`` of the traction coefficient ``x = T/(r W)`` about a
    cubic least-squares spline ``g`` of slip (``n_knots`` interior knots at
    quantiles of s), on a 2 ms grid over ``min_latency_s..max_latency_s`` refined by a
    bounded scalar minimisation. With ``load_n`` the model is ``g(s) + h(s)
    (W/mean(W) - 1)`` (a second spline ``h``): the load transfer onto the wheel
    while accelerating changes ``T/(rW)`` at a given slip (``T`` is not
    proportional to ``W``, Eq. 10's sinkage grows with ``W``), in step with
    ``dV/dt``, which would otherwise read as a lag. The GNSS speed's white
    noise makes the slip a regressor with errors, which pulls the lag that
    minimises the scatter short (errors in variables: about a third of the lag
    with 0.015 m/s at 20 Hz in the ninth benchmark generator's runs); so with
    ``smooth_hz`` every signal the fit uses (GNSS speed, wheel speed, traction
    coefficient, load) first passes the same zero-phase low-pass
    (:func:`.filters.lowpass`, per gap-free segment; the wheel's ``t_ref_s`` is
    taken as a uniform grid at its median step, as processing's grid is), which
    keeps the lag and the slow torque-slip relation and removes most of that
    noise (None: no smoothing). Slips outside :data:`TRACTION_SLIP_RANGE` and speeds
    ``r omega < min_speed_mps`` are not used.

    Parameters: ``t_gnss_s`` (N,) host receive times [s] of the GNSS speed and
    ``v_gnss`` (N,) [m/s]; ``t_ref_s`` (M,) sorted host times [s] of the
    measured wheel's ``wheel_speed_mps`` (M,) ``r omega`` [m/s] and
    ``traction_coeff`` (M,) ``T/(r W)`` [-] (filtered, undelayed); ``load_n``
    (M,) W [N] or None; ``usable_ref`` (M,) bool. Standard error: ``2 sigma^2 / SSE''`` (curvature
    of the profile, ``sigma^2 = SSE/(n - p)``) inflated by ``(1 + rho)/(1 -
    rho)`` for the lag-1 autocorrelation ``rho`` of the residuals.

    Returns :class:`LatencyEstimate` (``gain`` 1, ``offset_mps`` 0,
    ``residual_rms_mps`` holds the RMS of ``x - g(s)`` [-]; ``note`` names an
    edge hit: within :data:`TRACTION_EDGE_S` or two standard errors of an end).
    Raises ``ValueError`` when too few samples overlap or the
    traction coefficient does not vary.
    """
    t_g = np.asarray(t_gnss_s, dtype=np.float64)
    v_g = np.asarray(v_gnss, dtype=np.float64)
    t_r = np.asarray(t_ref_s, dtype=np.float64)
    w_r = np.asarray(wheel_speed_mps, dtype=np.float64)
    x_r = np.asarray(traction_coeff, dtype=np.float64)
    ld = None if load_n is None else np.asarray(load_n, dtype=np.float64)
    if smooth_hz:
        fs_r = 1.0 / float(np.median(np.diff(t_r)))
        w_r, x_r = lowpass_segments(w_r, fs_r, smooth_hz), lowpass_segments(x_r, fs_r, smooth_hz)
        ld = None if ld is None else lowpass_segments(ld, fs_r, smooth_hz)
        ok = np.isfinite(t_g) & np.isfinite(v_g)
        if np.count_nonzero(ok) >= 2:
            v_g = filter_to_grid(t_g[ok], v_g[ok], float(np.median(np.diff(t_g[ok]))), t_g, smooth_hz)
    keep = np.isfinite(w_r) & np.isfinite(x_r) & (w_r >= min_speed_mps)
    if usable_ref is not None:
        keep &= np.asarray(usable_ref, dtype=bool)
    if np.count_nonzero(keep) < 200:
        raise ValueError(f"only {np.count_nonzero(keep)} wheel samples with torque and load above "
                         f"{min_speed_mps:g} m/s (need 200)")
    dw_r = None
    if ld is not None:
        keep &= np.isfinite(ld)
        mean_w = float(np.mean(ld[keep])) if keep.any() else float("nan")
        if mean_w > 0:
            dw_r = np.where(np.isfinite(ld), ld / mean_w - 1.0, 0.0)
    if np.count_nonzero(keep) < 200:
        raise ValueError(f"only {np.count_nonzero(keep)} wheel samples with torque and load above "
                         f"{min_speed_mps:g} m/s (need 200)")
    lo, hi = np.percentile(x_r[keep], [1, 99])
    if not hi - lo > 0.05:
        raise ValueError(f"the traction coefficient T/(rW) hardly varies ({lo:.3f}..{hi:.3f}): "
                         "no slip sweep to align")

    def sse(t):
        return _traction_sse(t, t_g, v_g, t_r, w_r, x_r, keep, n_knots, min_speed_mps, dw_r)[0]

    taus = _lag_grid(min_latency_s, max_latency_s)
    prof = np.array([sse(t) for t in taus])
    if not np.isfinite(prof).any():
        raise ValueError("too few GNSS samples overlap the wheel's traction data")
    i = int(np.nanargmin(prof))
    a, b = taus[max(i - 2, 0)], taus[min(i + 2, taus.size - 1)]
    res = optimize.minimize_scalar(sse, bounds=(a, b), method="bounded", options={"xatol": 1e-5})
    tau = float(res.x)
    s0, n, r, _ = _traction_sse(tau, t_g, v_g, t_r, w_r, x_r, keep, n_knots, min_speed_mps, dw_r)
    p = (n_knots + 4) * (1 if dw_r is None else 2) + 1
    s2 = s0 / max(n - p, 1)
    h = 0.006
    curv = (sse(tau + h) - 2 * s0 + sse(tau - h)) / h**2
    stderr = float(np.sqrt(2 * s2 / curv * _ar1_inflation(r))) if curv > 0 else float("inf")
    note = ""
    edge = max(TRACTION_EDGE_S, 2 * stderr) if np.isfinite(stderr) else TRACTION_EDGE_S
    if tau <= min_latency_s + edge or tau >= max_latency_s - edge:
        note = _edge_note(min_latency_s, max_latency_s)
    return LatencyEstimate(tau, stderr, 1.0, 0.0, float(np.sqrt(s0 / max(n, 1))), n, note)


#: Grid [s] on which :func:`estimate_clock_offset` compares the two speed histories (bin means).
CLOCK_GRID_S = 0.05
#: Its peak must be this far [s] from any other shift it compares against (the width of a peak of a
#: speed history: spin-ups of a few tenths of a second to seconds) ...
CLOCK_PEAK_SEPARATION_S = 2.0
#: ... reach at least this correlation (the same wheel read twice) ...
CLOCK_MIN_CORR = 0.9
#: ... and leave at most this share of the unexplained variance (1 - rho^2) that the best other shift
#: leaves: a run of identical slip sweeps correlates nearly as well one sweep later, and then the
#: shift cannot be told.
CLOCK_DISTINCT_RATIO = 0.5
#: The two histories must overlap over at least this share of the shorter one, and this long [s]: at the
#: true shift two records of one run overlap nearly whole, while a shift that pushes an odd stretch of one
#: (a sensor's dropout) off the other's end must not win by leaving it out.
CLOCK_MIN_OVERLAP = 0.8
CLOCK_MIN_OVERLAP_S = 10.0


@dataclass
class ClockOffset:
    """The offset between two clocks that time the same wheel's speed (:func:`estimate_clock_offset`).

    ``offset_s`` how much later the second series' times are than the first's for the same moment
    [s] (its times less ``offset_s`` put it on the first clock), to the grid's resolution
    (:data:`CLOCK_GRID_S`); ``corr`` the correlation of the two speed histories at that shift;
    ``corr_other`` the best correlation at least :data:`CLOCK_PEAK_SEPARATION_S` away from it;
    ``corr_zero`` the correlation at the best shift within ``near_s`` of zero (NaN if none
    overlaps); ``overlap_s`` the time compared at ``offset_s``; ``clear`` whether the peak is high and
    distinct (:data:`CLOCK_MIN_CORR`, :data:`CLOCK_DISTINCT_RATIO`); ``note`` why not."""

    offset_s: float
    corr: float
    corr_other: float
    corr_zero: float
    overlap_s: float
    clear: bool
    note: str = ""


def _bin_means(t_s: np.ndarray, v: np.ndarray, t0: float, n: int, h: float) -> np.ndarray:
    ok = np.isfinite(t_s) & np.isfinite(v)
    k = np.floor((t_s[ok] - t0) / h).astype(np.int64)
    inside = (k >= 0) & (k < n)
    s = np.bincount(k[inside], weights=v[ok][inside], minlength=n)
    c = np.bincount(k[inside], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(c > 0, s / np.maximum(c, 1), np.nan)


def _ranks(v: np.ndarray) -> np.ndarray:
    """The finite values of ``v`` (n,) replaced by their ranks (ties averaged), NaN kept: a correlation of ranks
    (Spearman's) is not carried by a few wild values (a sensor pinned at its range for a second)."""
    out = np.full(v.shape, np.nan)
    ok = np.isfinite(v)
    out[ok] = stats.rankdata(v[ok])
    return out


def estimate_clock_offset(t_a_s: np.ndarray, v_a: np.ndarray, t_b_s: np.ndarray, v_b: np.ndarray, *,
                          near_s: tuple[float, float] = (-0.1, 0.3)) -> ClockOffset:
    """The offset between the clocks of two series that measure the same speed, from the shift at which
    their histories correlate best.

    ``t_a_s`` (N,), ``v_a`` (N,): times [s] and speeds of the first series (e.g. the transducer's wheel
    angle's rate on its bus); ``t_b_s`` (M,), ``v_b`` (M,): the second (the wheel-speed module's reading
    of the same wheel on another bus), in any units shared with ``v_a`` (NaN allowed).  Both are
    averaged on a :data:`CLOCK_GRID_S` grid and the Pearson correlation of their ranks (Spearman's) is
    computed at every shift
    at which they overlap over at least :data:`CLOCK_MIN_OVERLAP` of the shorter series and
    :data:`CLOCK_MIN_OVERLAP_S` (by FFT: all shifts, including ones larger than the run, as two
    adapters stamping on their own clocks give).  ``near_s`` the shifts that are no clock offset (a
    module's own delay, which :func:`estimate_latency` measures finely).

    Returns :class:`ClockOffset`.  Raises ``ValueError`` when either series has fewer than 2 grid
    points with a value or they overlap at no shift.  Source: cross-correlation time-delay estimation
    (Knapp & Carter 1976), normalised per shift over the overlap (Pearson)."""
    from scipy import signal

    h = CLOCK_GRID_S
    t_a, t_b = np.asarray(t_a_s, float), np.asarray(t_b_s, float)
    va, vb = np.asarray(v_a, float), np.asarray(v_b, float)
    fa, fb = np.isfinite(t_a) & np.isfinite(va), np.isfinite(t_b) & np.isfinite(vb)
    if fa.sum() < 2 or fb.sum() < 2:
        raise ValueError("fewer than 2 values in a series: no clock offset can be estimated")
    a0, b0 = float(t_a[fa].min()), float(t_b[fb].min())
    na, nb = int((t_a[fa].max() - a0) / h) + 1, int((t_b[fb].max() - b0) / h) + 1
    x, y = _ranks(_bin_means(t_a, va, a0, na, h)), _ranks(_bin_means(t_b, vb, b0, nb, h))
    mx, my = np.isfinite(x).astype(float), np.isfinite(y).astype(float)
    x0, y0 = np.nan_to_num(x), np.nan_to_num(y)

    def corr(u, w):  # sum over i of u[i + k] w[i] for every k, lags from -(len(w) - 1)
        return signal.correlate(u, w, mode="full", method="fft")

    n = np.rint(corr(my, mx))
    sx, sy = corr(my, x0), corr(y0, mx)
    sxx, syy, sxy = corr(my, x0 * x0), corr(y0 * y0, mx), corr(y0, x0)
    lags = signal.correlation_lags(nb, na, mode="full")  # y[i + k] against x[i]: y's time b0 + (i + k) h, x's a0 + i h
    shift = (b0 - a0) + lags * h
    need = max(CLOCK_MIN_OVERLAP * min(mx.sum(), my.sum()), CLOCK_MIN_OVERLAP_S / h, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        cov = sxy - sx * sy / n
        var = (sxx - sx * sx / n) * (syy - sy * sy / n)
        rho = np.where((n >= need) & (var > 0), cov / np.sqrt(np.where(var > 0, var, 1.0)), np.nan)
    if not np.isfinite(rho).any():
        raise ValueError("the two series overlap at no shift (or one of them never changes)")
    i = int(np.nanargmax(rho))
    best, r_best = float(shift[i]), float(rho[i])
    far = np.abs(shift - best) > CLOCK_PEAK_SEPARATION_S
    r_other = float(np.nanmax(rho[far])) if np.isfinite(rho[far]).any() else float("nan")
    near = (shift >= near_s[0] - h) & (shift <= near_s[1] + h)
    r_zero = float(np.nanmax(rho[near])) if np.isfinite(rho[near]).any() else float("nan")
    note = ""
    if r_best < CLOCK_MIN_CORR:
        note = f"the best correlation of the two speed histories is {r_best:.2f} (< {CLOCK_MIN_CORR:g})"
    elif np.isfinite(r_other) and (1 - r_best ** 2) > CLOCK_DISTINCT_RATIO * (1 - r_other ** 2):
        note = (f"the correlation at {best:+.2f} s ({r_best:.3f}) is not distinct from another shift's "
                f"({r_other:.3f}): a run of repeated, alike manoeuvres")
    return ClockOffset(best, r_best, r_other, r_zero, float(n[i]) * h, not note, note)
