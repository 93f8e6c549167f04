"""Slip ratio (paper Eq. 6), manoeuvre phases and accelerate-cycle ids.

``s = (r*omega - V) / (r*omega)`` (Eq. 6 of the seed paper; hardware.md).
Where ``r*omega`` is below ``min_wheel_speed_mps`` the ratio is undefined
(standstill, locked wheel) and set to NaN, never +-inf. Values outside
``[-1, 1)`` are kept but flagged (``slip_in_range`` False): a driven wheel
in the paper's tests has ``0 <= s < 1``; ``s < -1`` means the vehicle moves
more than twice as fast as the wheel rim, a sign of bad data (e.g. reversing,
as the wheel-speed module does not sense direction).

Phases (per sample, on the filtered signals):

* ``standstill``: ``|V| < standstill_mps`` and ``r*omega < standstill_mps``;
* ``accel``: ``T > torque_min_nm`` and (``dV/dt > accel_min_mps2`` or
  ``d(r*omega)/dt > accel_min_mps2``): the driver opens the throttle, the
  wheel speeds up first (slip rises) and the vehicle follows;
* ``drive``: the wheel drives steadily: ``T > torque_min_nm``, neither accelerating
  (as above) nor slowing (``dV/dt >= -accel_min_mps2``): the slip levels held against a
  towed load in the field's steady drawbar-pull test (Wong, *Theory of Ground Vehicles*,
  4th ed., §4.1), cruising with traction;
* ``brake``: ``dV/dt < -accel_min_mps2`` and ``T <= torque_min_nm``;
* ``other``: everything else (coasting, slowing with the torque still on, unknown inputs).

Derivatives are taken of V and r*omega smoothed by a moving average over ``smooth_s``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["slip_ratio", "classify_phases", "accel_cycles", "PHASES"]

PHASES = ("accel", "drive", "brake", "standstill", "other")


def slip_ratio(wheel_speed_mps: np.ndarray, speed_mps: np.ndarray, *,
               min_wheel_speed_mps: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Slip by Eq. (6): ``s = (r*omega - V)/(r*omega)``.

    ``wheel_speed_mps`` (N,) is ``r*omega`` [m/s] (r from the vehicle
    configuration), ``speed_mps`` (N,) is V [m/s]. Returns ``(slip, in_range)``:
    slip float64 (N,), NaN where either input is NaN or
    ``|r*omega| < min_wheel_speed_mps``; ``in_range`` bool (N,) is
    ``-1 <= slip < 1`` (False for NaN).
    """
    rw = np.asarray(wheel_speed_mps, dtype=np.float64)
    v = np.asarray(speed_mps, dtype=np.float64)
    slip = np.full(rw.shape, np.nan)
    ok = np.isfinite(rw) & np.isfinite(v) & (np.abs(rw) >= min_wheel_speed_mps)
    slip[ok] = (rw[ok] - v[ok]) / rw[ok]
    with np.errstate(invalid="ignore"):
        in_range = (slip >= -1.0) & (slip < 1.0)
    return slip, in_range


def classify_phases(t_s: np.ndarray, speed_mps: np.ndarray, wheel_speed_mps: np.ndarray,
                    torque_nm: np.ndarray, *, standstill_mps: float = 0.1,
                    accel_min_mps2: float = 0.05, torque_min_nm: float = 50.0,
                    smooth_s: float = 0.5) -> np.ndarray:
    """Phase of each sample: ``accel``, ``brake``, ``standstill`` or ``other``.

    Inputs (N,): time [s] (uniform grid), V [m/s], r*omega [m/s], T [N m]
    (NaN allowed: a sample whose inputs are missing falls to ``other``, or
    ``standstill`` if both speeds say so). Rules in the module docstring.
    Returns an object array (N,) of phase names (:data:`PHASES`).
    """
    t = np.asarray(t_s, dtype=np.float64)
    v = np.asarray(speed_mps, dtype=np.float64)
    rw = np.asarray(wheel_speed_mps, dtype=np.float64)
    T = np.asarray(torque_nm, dtype=np.float64)
    n = t.shape[0]
    phase = np.full(n, "other", dtype=object)
    if n == 0:
        return phase
    dvdt = _smooth_derivative(t, v, smooth_s)
    drwdt = _smooth_derivative(t, rw, smooth_s)
    with np.errstate(invalid="ignore"):
        accel = (T > torque_min_nm) & ((dvdt > accel_min_mps2) | (drwdt > accel_min_mps2))
        brake = (dvdt < -accel_min_mps2) & (T <= torque_min_nm)
        drive = (T > torque_min_nm) & (dvdt >= -accel_min_mps2)
        stand = (np.abs(v) < standstill_mps) & (np.abs(rw) < standstill_mps)
    phase[drive] = "drive"
    phase[brake] = "brake"
    phase[accel] = "accel"
    phase[stand] = "standstill"
    return phase


def _smooth_derivative(t: np.ndarray, x: np.ndarray, smooth_s: float) -> np.ndarray:
    """d/dt of ``x`` (N,) after a moving average over ``smooth_s`` (NaN-aware; NaN where
    the window is not complete)."""
    n = t.shape[0]
    if n < 3:
        return np.full(n, np.nan)
    dt = float(np.median(np.diff(t)))
    w = max(1, int(round(smooth_s / dt)))
    if w > n:  # a run shorter than the window: no complete window anywhere
        return np.full(n, np.nan)
    kernel = np.ones(w) / w
    fin = np.isfinite(x)
    xs = np.convolve(np.where(fin, x, 0.0), kernel, mode="same")
    cnt = np.convolve(fin.astype(float), kernel, mode="same")
    with np.errstate(invalid="ignore", divide="ignore"):
        xs = np.where(cnt > 0.999, xs / cnt, np.nan)
    return np.gradient(xs, t)


def accel_cycles(t_s: np.ndarray, phase: np.ndarray, *, max_break_s: float = 1.0,
                 min_duration_s: float = 1.0) -> np.ndarray:
    """Accelerate-cycle id per sample, for leave-one-cycle-out cross-validation.

    A cycle is a run of ``accel`` samples; interruptions of at most
    ``max_break_s`` are bridged (the bridged samples get the id but keep their
    phase); runs shorter than ``min_duration_s`` are not cycles. Ids count
    0, 1, 2, ... in time order; -1 outside a cycle. Returns int64 (N,).
    """
    t = np.asarray(t_s, dtype=np.float64)
    is_acc = np.asarray(phase) == "accel"
    cycle = np.full(t.shape[0], -1, dtype=np.int64)
    idx = np.flatnonzero(is_acc)
    if idx.size == 0:
        return cycle
    breaks = np.flatnonzero(t[idx[1:]] - t[idx[:-1]] > max_break_s)
    starts = np.concatenate([[idx[0]], idx[breaks + 1]])
    ends = np.concatenate([idx[breaks], [idx[-1]]])
    k = 0
    for a, b in zip(starts, ends):
        if t[b] - t[a] >= min_duration_s:
            cycle[a:b + 1] = k
            k += 1
    return cycle
