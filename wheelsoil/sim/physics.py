"""One physical field run: vehicle dynamics, then the instrumented wheel's true forces at 500 Hz.

:func:`simulate_physics` builds the true soil model (:class:`~.effects.TruthModel`),
tabulates its drawbar pull for the dynamics (:class:`~.vehicle.ForceTable`, error
checked), refuses a run the vehicle could not drive, integrates the 4x4
(:func:`~.vehicle.simulate_dynamics`), and then evaluates the left-rear wheel's
soil forces *exactly* (reference quadrature, :mod:`.terra`) on the transducer's
500 Hz grid, with the soil's spatial variability and any terrain drift at the
wheel's position. The transducer signals carry the wheel's inertia
(hardware.md): ``Fx = Dp - m_w dV/dt``, ``My = T + I_w domega/dt``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .effects import ALONG_RUN, TruthModel
from .vehicle import DT_S, ForceTable, VehicleParams, check_can_move, simulate_dynamics, skid_forces

__all__ = ["simulate_physics", "WFT_RATE_HZ"]

WFT_RATE_HZ = 500.0


def bandlimited(rng, n, dt, lo_hz, hi_hz, sigma):
    """Zero-mean band-limited Gaussian noise (Butterworth band-pass of white noise), shape (n,)."""
    from scipy import signal

    if n < 32:
        return np.zeros(n)
    nyq = 0.5 / dt
    sos = signal.butter(2, [lo_hz / nyq, min(hi_hz / nyq, 0.99)], btype="band", output="sos")
    x = signal.sosfilt(sos, rng.standard_normal(n + 2000))[2000:]
    return x * (sigma / max(float(np.std(x)), 1e-12))


def spatial_field(rng, distance_m, corr_m, sigma):
    """Zero-mean Gaussian random field of travelled distance (Gaussian kernel of width
    ``corr_m`` on a 0.25 m grid), sd ``sigma``, sampled at ``distance_m`` (N,)."""
    if sigma <= 0 or len(distance_m) == 0:
        return np.zeros(len(distance_m))
    from scipy.ndimage import gaussian_filter1d

    grid = np.arange(0.0, float(distance_m[-1]) + 1.0, 0.25)
    white = rng.standard_normal(len(grid) + 80)
    f = gaussian_filter1d(white, corr_m / 0.25, mode="wrap")[40:40 + len(grid)]
    f *= sigma / max(float(np.std(f)), 1e-12)
    return np.interp(distance_m, grid, f)


def simulate_physics(truth: TruthModel, rng: np.random.Generator, *, added_load_n: float,
                     duration_s: float | None, n_cycles: int = 6, soil_variability: float = 0.02,
                     vehicle: VehicleParams | None = None, slip_max: float | None = None,
                     procedure: str = "sweeps") -> dict[str, Any]:
    """Simulate the run's physics; returns a dict.

    ``wft``: dict of arrays on the 500 Hz grid (shape (N,)): ``t_s``, ``speed_mps`` V,
    ``accel_mps2`` dV/dt, ``omega_radps``, ``omega_dot_radps2``, ``slip`` (Eq. 6, NaN at
    standstill), ``load_n`` W, ``drawbar_pull_n`` Dp and ``torque_nm`` T (soil),
    ``sinkage_m`` (NaN when not driving), ``fx_n`` = Dp - m_w dV/dt and ``my_nm`` =
    T + I_w domega/dt (what the transducer sees before its own errors), ``phase``,
    ``cycle``, ``distance_m``. ``dyn``: the 10 ms dynamics (see
    :func:`~.vehicle.simulate_dynamics`). ``table_max_error_n``: the force table's
    largest interpolation error on random points; ``can_move``: :func:`check_can_move`'s dict;
    ``grade``, ``vehicle`` (VehicleParams). ``slip_max``: the highest slip of the driver's sweeps
    (None: about 0.9, see :func:`~.vehicle.simulate_dynamics`). ``procedure``: ``"sweeps"``
    (accelerate-brake slip sweeps), ``"tow"`` or ``"tow-down"`` (steady drawbar-pull passes against a
    towed load, the slip levels from the lowest up or from the highest down).

    Raises ValueError when the vehicle cannot move (message says why and what to change)
    or the wheel would bury itself.
    """
    veh = vehicle or VehicleParams()
    m, wf0, wr0 = veh.loads(added_load_n)
    r = truth.radius_m
    grade = float(rng.uniform(-0.005, 0.005))
    drift = truth.effect in ALONG_RUN
    fracs = np.linspace(0.0, 1.0, 9) if drift else (0.5,)
    lo, hi = 0.45 * min(wf0, wr0), 1.35 * max(wf0, wr0)
    table = ForceTable(truth, (lo, hi), fracs=fracs)
    where = f" on this soil with a {r} x {truth.width_m} m wheel"
    can_move = check_can_move(table, veh, added_load_n, grade, what=where)
    table_err = table.max_error(rng, 60)

    n_max = int(((duration_s or 600.0) + 60.0) / DT_S)
    slip_noise = bandlimited(rng, n_max, DT_S, 0.2, 3.0, 0.008)
    bf = bandlimited(rng, n_max, DT_S, 0.5, 8.0, 0.025 * wf0)
    br = bandlimited(rng, n_max, DT_S, 0.5, 8.0, 0.025 * wr0)
    if truth.effect == "bouncing":  # rough ground: every wheel's load oscillates (held-out batch 8)
        hz, ph = float(rng.uniform(1.5, 3.0)), float(rng.uniform(0.0, 2.0 * math.pi))
        wave = np.sin(2.0 * math.pi * hz * np.arange(n_max) * DT_S + ph) * truth.params["amplitude"]
        bf, br = bf + wave * wf0, br - wave * wr0  # the body pitches: front and rear in opposite phase

    def bump(arr):
        return lambda t: float(arr[min(int(round(t / DT_S)), len(arr) - 1)])

    dist_guess = 300.0
    driver_seed = int(rng.integers(2**63))
    for _ in range(3 if drift else 1):  # drift is a function of the run's distance fraction
        sub = np.random.default_rng(driver_seed)  # the same driver choices on each pass
        dyn = simulate_dynamics(table, veh, sub, added_load_n=added_load_n, radius_m=r, duration_s=duration_s,
                                n_cycles=n_cycles, grade=grade, bumps_front=bump(bf), bumps_rear=bump(br),
                                dist_total_guess_m=dist_guess, slip_noise=slip_noise,
                                can_start=can_move["can_start"], slip_best=can_move["slip_at_max"],
                                slip_max=slip_max, procedure=procedure)
        total = max(float(dyn["distance_m"][-1]), 1.0)
        if abs(total - dist_guess) < 0.5:
            break
        dist_guess = total

    # ---- the instrumented (left rear) wheel on the transducer's 500 Hz grid: V and omega
    # linear between the 10 ms states, their rates the dynamics' own (piecewise constant)
    t_dyn = dyn["t_s"]
    dt = 1.0 / WFT_RATE_HZ
    n = int(round(t_dyn[-1] / dt)) + 1
    t = np.arange(n) * dt
    V = np.interp(t, t_dyn, dyn["speed_mps"])
    om = np.interp(t, t_dyn, dyn["omega_radps"])
    k = np.clip(np.floor(t / DT_S + 1e-9).astype(int), 0, len(t_dyn) - 2)
    accel = np.diff(dyn["speed_mps"])[k] / DT_S
    om_dot = np.diff(dyn["omega_radps"])[k] / DT_S
    idx = np.clip(np.round(t / DT_S).astype(int), 0, len(t_dyn) - 1)
    standstill = (dyn["phase"] == "standstill")[idx] & (V <= 0) & (om <= 0)
    load = np.interp(t, t_dyn, dyn["load_rear_n"])
    # bumps above the dynamics' 50 Hz Nyquist are not needed; add a little 500 Hz detail
    with np.errstate(divide="ignore", invalid="ignore"):
        slip = np.where(om * r > 1e-6, 1.0 - V / (om * r), np.nan)
    slip = np.where(standstill, np.nan, slip)
    distance = np.interp(t, t_dyn, dyn["distance_m"])
    frac = np.clip(distance / max(distance[-1], 1.0), 0.0, 1.0)
    var = 1.0 + spatial_field(rng, distance, 3.0, soil_variability)

    dp = np.zeros(n)
    tq = np.zeros(n)
    z = np.full(n, np.nan)
    s_soil = slip  # the slip the soil sees: the computed one but for an out-of-round tyre
    if truth.effect == "runout":  # rolling radius r (1 + e sin psi), psi the wheel's angle
        psi = np.cumsum(om) * dt + rng.uniform(0.0, 2.0 * math.pi)
        s_soil = 1.0 - (1.0 - slip) / (1.0 + truth.params["e"] * np.sin(psi))  # NaN stays NaN
    drive = ~standstill & np.isfinite(s_soil) & (s_soil >= 0)
    s_drive = np.clip(s_soil[drive], 0.0, 0.97)
    lag = None
    if truth.effect == "slip_sinkage_lag":  # the excavation's slip memory: a first-order lag of the slip
        from scipy.signal import lfilter

        a = dt / (float(truth.params["tau_s"]) + dt)
        s_in = np.clip(np.nan_to_num(slip, nan=0.0), 0.0, 0.97)
        lag = lfilter([a], [1.0, a - 1.0], s_in, zi=[(1.0 - a) * s_in[0]])[0][drive]
    f = truth.drive_forces(load[drive], s_drive, frac=frac[drive], variability=var[drive], slip_lag=lag,
                           speed_mps=V[drive])
    dp[drive], tq[drive], z[drive] = f["drawbar_pull_n"], f["torque_nm"], f["sinkage_m"]
    skid = ~standstill & np.isfinite(s_soil) & (s_soil < 0)
    if skid.any():
        f0 = truth.drive_forces(load[skid], np.zeros(skid.sum()), frac=frac[skid], variability=var[skid],
                                speed_mps=V[skid])
        dp[skid], tq[skid] = skid_forces(f0["drawbar_pull_n"], f0["torque_nm"], load[skid], s_soil[skid], r,
                                         veh.rolling_skid)
        z[skid] = f0["sinkage_m"]
    # pull-away from standstill: the soil forces build up over the first cm/s
    w_move = np.clip(np.maximum(V, om * r) / 0.05, 0.0, 1.0)
    w_move = w_move * w_move * (3 - 2 * w_move)
    dp *= w_move
    tq *= w_move
    phase = dyn["phase"][k]
    cycle = dyn["cycle"][k]
    wft = {
        "t_s": t, "speed_mps": V, "accel_mps2": accel, "omega_radps": om, "omega_dot_radps2": om_dot,
        "slip": slip, "load_n": load, "drawbar_pull_n": dp, "torque_nm": tq, "sinkage_m": z,
        "fx_n": dp - veh.wheel_mass_kg * accel, "my_nm": tq + veh.wheel_inertia_kgm2 * om_dot,
        "phase": phase, "cycle": cycle, "distance_m": distance, "soil_factor": var,
    }
    return {"wft": wft, "dyn": dyn, "table_max_error_n": table_err, "can_move": can_move, "grade": grade,
            "vehicle": veh, "mass_kg": m}
