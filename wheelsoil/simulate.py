"""Field-test simulator: physical accelerate-brake runs as raw CAN frames, with a hidden effect.

The truth comes from :mod:`wheelsoil.sim`, an implementation independent of
``wheelsoil.model`` (adaptive quadrature of paper Eqs. 1-13 and the Wong-Reece
stress distribution, :mod:`wheelsoil.sim.terra`); the vehicle's speed is
produced by the soil's drawbar pull on the four driven wheels of the 3.6 t 4x4
(:mod:`wheelsoil.sim.vehicle`); a run on which it could not move is refused
with a message saying so. This module turns a run into the vehicle's real CAN
format: the same messages, ids, rates, DBC quantisation, frames and sign
conventions (hardware.md), with sensor noise, host timestamps with jitter (one
host clock for both buses), an unknown host/GPS clock offset and drift, a GNSS
velocity latency and lost WFT samples. The transducer signals carry the wheel's
inertia: ``Fx = Dp - m_w dV/dt``, ``My = T + I_w domega/dt``.

Hidden effects (:data:`EFFECTS`, :mod:`wheelsoil.sim.effects`): in family
(``none``, ``vasilev``, ``lyasko``, ``ding``, ``terrain_mismatch``,
``stress_distribution``, ``terrain_drift``) and out of family (``fx_gain``,
``my_gain``, ``load_gain``, ``angle_offset``, ``tyre_deflection``,
``bulldozing``, ``load_dependent``, ``vertical_balance``, ``width_error``, ``zero_drift``), each with the verdicts
acceptable for it. The recording holds only what a logger would record: the
vehicle configuration of the *simulated* wheel and a provenance record
``kind = "simulated"`` with the seed (never the effect); the truth goes to
``--truth FILE`` only when asked.

Library::

    run = simulate_run(load_terrain("sand"), effect="lyasko", seed=3, duration_s=240)
    write_simulation(run, "run.mcap")          # the vehicle's format, provenance "simulated"
    write_simulation(run, "run.log")           # candump -L, the input of `wheelsoil import`
    write_truth(run, "truth.json")             # the hidden truth, only when asked
    judge(run.info, report)                    # score a report.json against it

Command line: ``wheelsoil simulate --terrain sand --effect lyasko -o run.mcap``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from wheelsoil.sim.effects import (ACCEPTABLE, ALL_HELD_OUT, EFFECTS, GNSS_OFFSET_FADE_MPS, HELD_OUT, HELD_OUT_2, HELD_OUT_3,
                                   HELD_OUT_4, HELD_OUT_5, HELD_OUT_6, HELD_OUT_7, HELD_OUT_8, HELD_OUT_9,
                                   HELD_OUT_10, HELD_OUT_11, HELD_OUT_12, HELD_OUT_13, HELD_OUT_14, HELD_OUT_15, HELD_OUT_BATCHES, IN_FAMILY, OUT_OF_FAMILY,
                                   PARAM_NAMES, SENSOR_EFFECTS, VERDICTS, TruthModel, draw_effect, family_of)
from wheelsoil.sim.physics import bandlimited as _bandlimited
from wheelsoil.sim.terra import soil_dict
from wheelsoil.sim.vehicle import PROCEDURES

__all__ = ["EFFECTS", "IN_FAMILY", "OUT_OF_FAMILY", "HELD_OUT", "HELD_OUT_2", "HELD_OUT_3", "HELD_OUT_4",
           "HELD_OUT_5", "HELD_OUT_6", "HELD_OUT_7", "HELD_OUT_8", "HELD_OUT_9", "HELD_OUT_10", "HELD_OUT_11",
           "HELD_OUT_12", "HELD_OUT_13", "HELD_OUT_14", "HELD_OUT_15",
           "HELD_OUT_BATCHES", "ALL_HELD_OUT", "ACCEPTABLE", "VERDICTS",
           "SimulatedRun", "simulate_run", "write_simulation", "write_truth", "write_vehicle_config", "judge",
           "draw_case", "pack_signals", "vehicle_config_for", "SIMULATOR"]

#: Name and version of the simulator (in the provenance record and the truth).
SIMULATOR = "wheelsoil.sim/2 (reference quadrature, 4x4 dynamics)"

STATIC_LOAD_N = 8000.0          # left rear wheel, 3.6 t vehicle (paper 2.2)
WFT_RATE_HZ = 500.0
WSS_RATE_HZ = 100.0
GNSS_RATE_HZ = 20.0
GPS_UNIX_EPOCH_S = 315964800    # 1980-01-06T00:00:00Z in Unix seconds
GPS_LEAP_S = 18                 # GPS - UTC since 2017
GPS_WEEK_S = 604800
BUS_WFT = "can0"
BUS_VEH = "can1"

# Sensor noise (1 sigma) and behaviour; DBC quantisation comes on top.
WFT_FORCE_NOISE_N = 20.0
WFT_MOMENT_NOISE_NM = 4.0
WSS_NOISE_REL = 0.002
GNSS_SPEED_NOISE_MPS = 0.02
INS_SPEED_NOISE_MPS = 0.01

#: Wheel mass and polar inertia outboard of the transducer (hardware.md).
WHEEL_MASS_KG = 80.0
WHEEL_INERTIA_KGM2 = 11.5
DEFAULT_RADIUS_M = 0.47
DEFAULT_WIDTH_M = 0.32


def _wheel_dims(wheel) -> tuple[float, float]:
    if wheel is None:
        return DEFAULT_RADIUS_M, DEFAULT_WIDTH_M
    if isinstance(wheel, (tuple, list)):
        return float(wheel[0]), float(wheel[1])
    return float(wheel.radius), float(wheel.width)


def _terrain_values(terrain) -> tuple[str, dict]:
    """(name, SI soil dict) from a Terrain-like object, a mapping with a ``name`` or a built-in name."""
    if isinstance(terrain, str):
        from wheelsoil.model.terrain import load_terrain  # terrain values only (a dataclass)

        terrain = load_terrain(terrain)
    name = terrain.get("name", "soil") if isinstance(terrain, Mapping) else getattr(terrain, "name", "soil")
    return str(name), soil_dict(terrain)


@dataclass
class SimulatedRun:
    """One simulated field run: the hidden truth and the raw CAN frames.

    Attributes
    ----------
    truth : pandas.DataFrame
        On the WFT's 500 Hz sample grid, shape (N, ...): ``t_s`` (host seconds
        since the first frame), ``t_host_ns``, ``slip``, ``load_n`` (W),
        ``drawbar_pull_n`` (Dp), ``torque_nm`` (T), ``sinkage_m`` (z),
        ``speed_mps`` (V), ``omega_radps``, ``wheel_angle_deg``, ``phase``
        (``accel|brake|standstill|other``), ``cycle`` (accelerate-cycle id, -1
        outside one).
    frames : dict
        bus name -> ``wheelsoil.daq.FrameBatch``-compatible dict of arrays
        (``timestamp_ns`` int64 (M,), ``arbitration_id`` uint32, ``is_extended``
        bool, ``dlc`` uint8, ``data`` uint8 (M, 8)), sorted by host time.
    info : dict
        The hidden truth (effect, params, terrain actually used, latency, clock
        offset/drift, seed, ...). Never written into a recording.
    start_ns : int
        Host (Unix, ns) time of the first frame.
    wheel : (radius_m, width_m) of the simulated wheel; ``terrain_lab`` the lab soil dict.
    dynamics : dict of the vehicle's 10 ms states (:func:`wheelsoil.sim.vehicle.simulate_dynamics`).
    config : the ``VehicleConfig`` of the simulated wheel (attached to .mcap output).
    """

    truth: Any
    frames: dict[str, dict[str, np.ndarray]]
    info: dict[str, Any]
    start_ns: int
    wheel: Any = None
    terrain_lab: Any = None
    extras: dict[str, Any] = field(default_factory=dict)
    dynamics: Any = None
    config: Any = None

    def frame_batches(self):
        """The frames as ``wheelsoil.daq.FrameBatch`` objects, one per bus (dict)."""
        from wheelsoil.daq import FrameBatch

        out = {}
        for bus, f in self.frames.items():
            n = len(f["timestamp_ns"])
            flags = np.where(f["is_extended"], 1, 0).astype(np.uint8)
            out[bus] = FrameBatch(
                bus=bus,
                timestamp_ns=f["timestamp_ns"].astype(np.int64),
                arbitration_id=f["arbitration_id"].astype(np.uint32),
                is_extended=f["is_extended"].astype(bool),
                flags=flags,
                dlc=f["dlc"].astype(np.uint8),
                data=f["data"].reshape(n, 8).astype(np.uint8),
            )
        return out

    @property
    def duration_s(self) -> float:
        """Duration from the first to the last frame [s]."""
        last = max(int(f["timestamp_ns"][-1]) for f in self.frames.values() if len(f["timestamp_ns"]))
        return (last - self.start_ns) * 1e-9

    @property
    def n_frames(self) -> int:
        """Total number of frames on all buses."""
        return int(sum(len(f["timestamp_ns"]) for f in self.frames.values()))



# --------------------------------------------------------------------------- DBC
def _dbc_databases():
    """The shipped DBCs (package ``wheelsoil.dbc``) as cantools databases, by file stem."""
    from importlib import resources

    import cantools

    base = resources.files("wheelsoil.dbc")
    return {
        stem: cantools.database.load_string(
            (base / f"{stem}.dbc").read_text(encoding="utf-8"), database_format="dbc", strict=False
        )
        for stem in ("wft", "wheel_speed", "gps_rt_speedbox")
    }


def pack_signals(message, values: Mapping[str, Any], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Encode N frames of one DBC message, vectorised (the inverse of a DBC decode).

    Parameters
    ----------
    message : cantools.database.Message
        The message definition (signals, byte order, scale/offset).
    values : mapping
        signal name -> physical value, scalar or array of shape (N,). Signals
        not given are encoded as raw 0 (for multiplexed messages pass only the
        multiplexer and the signals of that multiplexer value).
    n : int
        Number of frames.

    Returns
    -------
    data : uint8 array (N, 8); bytes past the message length are zero.
    saturated : bool array (N,); True where a value was outside the signal's
        raw range and was clipped (a sensor saturates the same way).

    Raw values are ``round_half_even((value - offset) / scale)`` like cantools'
    ``Message.encode`` (the tests check equality with it). Intel (little
    endian) and Motorola (big endian, DBC start bit = MSB) byte orders.
    """
    word_le = np.zeros(n, dtype=np.uint64)
    word_be = np.zeros(n, dtype=np.uint64)
    saturated = np.zeros(n, dtype=bool)
    for sig in message.signals:
        if sig.name not in values:
            continue
        phys = np.broadcast_to(np.asarray(values[sig.name], dtype=float), (n,))
        if not np.all(np.isfinite(phys)):
            raise ValueError(f"{message.name}.{sig.name}: non-finite value to encode")
        raw = np.rint((phys - sig.offset) / sig.scale)
        length = sig.length
        lo, hi = ((-(2 ** (length - 1)), 2 ** (length - 1) - 1) if sig.is_signed else (0, 2**length - 1))
        saturated |= (raw < lo) | (raw > hi)
        raw = np.clip(raw, lo, hi).astype(np.int64)
        bits = (raw & ((1 << length) - 1)).astype(np.uint64)
        if sig.byte_order == "little_endian":
            word_le |= bits << np.uint64(sig.start)
        else:
            msb = (7 - sig.start // 8) * 8 + sig.start % 8
            word_be |= bits << np.uint64(msb - length + 1)
    data = word_le.astype("<u8").view(np.uint8).reshape(n, 8) | word_be.astype(">u8").view(np.uint8).reshape(n, 8)
    data[:, message.length:] = 0
    return data, saturated




# ------------------------------------------------------------------- simulation
def speed_channel_errors(effect: str, params: Mapping[str, Any], load_n: np.ndarray, static_load_n: float,
                         duration_s: float = 0.0):
    """What a sensor effect does to the speed channels slip is computed from: ``(gnss_read,
    rl_gain, rl_delay_s)``: ``gnss_read(v, t_s)``, what the GNSS reads for the true forward speed v (m/s,
    any shape) at run time t_s (s from the start, v's shape): g v for ``gnss_gain``, v + b min(v / 0.5 m/s, 1)
    for ``gnss_offset``, v + b within each burst of ``gnss_multipath`` (its start a fraction of
    ``duration_s`` [s]), v through a first-order lag of ``tau_s`` for ``gnss_lag`` (a series on a uniform
    grid t_s), else v; the left-rear wheel-speed reading's gain per sample (``(N,)`` like
    ``load_n`` [N], a rolling radius shrinking with the load, 1 - e (W/W0 - 1); None: none) and its
    delay [s] (0: none).  ``static_load_n`` W0 [N].  Used by :func:`simulate_run` for the frames and by
    the benchmark's imprint for the slip the fit sees.  Raises KeyError when ``params`` lacks the
    effect's parameter."""
    g = float(params["gain"]) if effect == "gnss_gain" else 1.0
    b = float(params["offset_mps"]) if effect == "gnss_offset" else 0.0
    bursts = [(x * duration_s, x * duration_s + d, o) for x, d, o in params["bursts"]] \
        if effect == "gnss_multipath" else []
    tau = float(params["tau_s"]) if effect == "gnss_lag" else 0.0

    def gnss_read(v, t_s):
        v = np.asarray(v, float)
        out = g * v + b * np.clip(np.abs(v) / GNSS_OFFSET_FADE_MPS, 0.0, 1.0)
        for t0, t1, o in bursts:
            out = out + o * ((t_s >= t0) & (t_s < t1))
        if tau and out.ndim == 1 and out.size > 1:  # the receiver's smoothing: a first-order lag on its grid
            from scipy.signal import lfilter

            a = -math.expm1(-float(np.median(np.diff(t_s))) / tau)
            out = lfilter([a], [1.0, a - 1.0], out, zi=[(1.0 - a) * out[0]])[0]
        return out

    rl_gain = 1.0 - params["e"] * (np.asarray(load_n, float) / static_load_n - 1.0) if effect == "load_radius" else None
    rl_delay_s = float(params["delay_s"]) if effect == "wheel_latency" else 0.0
    return gnss_read, rl_gain, rl_delay_s


def simulate_run(
    terrain,
    *,
    effect: str = "none",
    params: Mapping[str, Any] | None = None,
    size: float | None = None,
    wheel=None,
    added_load_n: float = 3000.0,
    gnss_latency_s: float = 0.1,
    drop_rate: float = 0.0,
    seed: int = 0,
    duration_s: float | None = None,
    n_cycles: int = 6,
    soil_variability: float = 0.02,
    usb_batching_s: float = 0.0,
    front_wheels: str = "driven",
    slip_max: float | None = None,
    procedure: str = "sweeps",
    wft_noise: float = 1.0,
    wft_noise_hz: float | None = None,
) -> SimulatedRun:
    """Simulate one physical field run of the instrumented left-rear wheel (paper section 2.2).

    Parameters
    ----------
    terrain : ``wheelsoil.model.Terrain``, a mapping (SI keys c, phi, K, n, kc, kphi, name) or a
        built-in terrain name: the laboratory soil.
    effect : one of :data:`EFFECTS` (in and out of family; :mod:`wheelsoil.sim.effects`).
    params : effect parameters (see :func:`wheelsoil.sim.effects.draw_effect`); missing ones drawn.
    size : effect size in [0, 1] (0 barely above the noise, 1 large); drawn when None.
    wheel : object with ``radius``/``width`` [m] or a (radius, width) tuple; default 0.47 x 0.32 m.
    added_load_n : ballast over the rear axle, per rear wheel [N] (paper: 3 kN clay, 5 kN sand).
    gnss_latency_s : receiver latency of the GNSS velocity messages [s] (0 .. 1).
    drop_rate : probability that a WFT sample's three frames are lost (0 .. 0.5).
    seed : seeds every random choice; same seed, same frames.
    duration_s : run length [s] (>= 30); default ``n_cycles`` accelerate-brake cycles.
    soil_variability : relative sd of c, kc, kphi along the track (random field, 3 m correlation), 0 .. 0.2.
    usb_batching_s : 0 (per-frame host stamps) or a USB adapter's poll period (0 .. 0.02 s).
    front_wheels : ``"driven"`` (the 4x4's front wheels on the FL/FR wheel-speed channels: they
        slip like the rear ones) or ``"reference"`` (an idealised undriven reference wheel there,
        r omega = V: what processing's GNSS-latency estimate assumes; the dynamics stay 4x4).
    slip_max : the highest slip the driver sweeps to, 0.2 .. 0.95 (each sweep peaks at 0.925 .. 1
        times it); default about 0.9, as in the paper's sweeps.
    procedure : ``"sweeps"`` (accelerate-brake slip sweeps, as in the paper), ``"tow"`` (the
        field's steady drawbar-pull test: slip levels held in turn against a towed load vehicle
        that holds the speed; :mod:`wheelsoil.sim.vehicle`) or ``"tow-down"`` (the levels from the
        highest down).
    wft_noise : scale of the transducer's sensor noise (0 .. 10; 1: Fx, Fz sd
        :data:`WFT_FORCE_NOISE_N`, moments sd :data:`WFT_MOMENT_NOISE_NM`, white).
    wft_noise_hz : None (white noise) or the corner [Hz] (0.05 .. 50) below which the same
        noise lies instead (2nd-order Butterworth low-pass of the same draws, rescaled to the
        same sd): slow wobbles, like vibration and drift a real transducer picks up, which
        the fit's within-cell noise estimate does not see in full.

    Returns
    -------
    SimulatedRun (``truth`` DataFrame at 500 Hz, ``frames``, ``info`` = the hidden truth (contract F),
    ``dynamics`` (10 ms vehicle states), ``config`` (VehicleConfig of the simulated wheel)).

    Raises
    ------
    ValueError
        Unknown effect, bad parameter, out-of-range option, a vehicle that cannot move on this
        soil/wheel/load (the message gives the numbers and what to change), a wheel that buries itself.
    """
    import pandas as pd

    from wheelsoil.sim.physics import simulate_physics

    family = family_of(effect)
    if not 0.0 <= gnss_latency_s <= 1.0:
        raise ValueError(f"gnss_latency_s={gnss_latency_s} outside 0..1 s")
    if not 0.0 <= drop_rate <= 0.5:
        raise ValueError(f"drop_rate={drop_rate} outside 0..0.5")
    if duration_s is not None and not 30.0 <= duration_s <= 3600.0:
        raise ValueError(f"duration_s={duration_s}: a run is 30 s (one accelerate-brake cycle) to 3600 s long")
    if duration_s is None and n_cycles < 1:
        raise ValueError("n_cycles must be at least 1")
    if not 0.0 <= usb_batching_s <= 0.02:
        raise ValueError(f"usb_batching_s={usb_batching_s} outside 0..0.02 s")
    if not 0.0 <= soil_variability <= 0.2:
        raise ValueError(f"soil_variability={soil_variability} outside 0..0.2")
    if added_load_n < 0 or added_load_n > 15000:
        raise ValueError(f"added_load_n={added_load_n} outside 0..15000 N")
    if front_wheels not in ("driven", "reference"):
        raise ValueError(f"front_wheels must be 'driven' or 'reference', got {front_wheels!r}")
    if slip_max is not None and not 0.2 <= slip_max <= 0.95:
        raise ValueError(f"slip_max={slip_max} outside 0.2..0.95")
    if procedure not in PROCEDURES:
        raise ValueError(f"procedure must be one of {PROCEDURES}, got {procedure!r}")
    if not 0.0 <= wft_noise <= 10.0:
        raise ValueError(f"wft_noise={wft_noise} outside 0..10")
    if wft_noise_hz is not None and not 0.05 <= wft_noise_hz <= 50.0:
        raise ValueError(f"wft_noise_hz={wft_noise_hz} outside 0.05..50 Hz")
    r, b = _wheel_dims(wheel)
    if not (0.05 <= r <= 2.0 and 0.02 <= b <= 2.0):
        raise ValueError(f"wheel {r} x {b} m: radius must be in 0.05..2 m and width in 0.02..2 m")
    name, soil = _terrain_values(terrain)
    rng = np.random.default_rng(seed)
    params = draw_effect(effect, rng, size=size, given=params)
    static = STATIC_LOAD_N + added_load_n
    truth_model = TruthModel(soil, r, b, effect if effect not in SENSOR_EFFECTS else "none", params, static)
    phys = simulate_physics(truth_model, rng, added_load_n=added_load_n, duration_s=duration_s,
                            n_cycles=n_cycles, soil_variability=soil_variability, slip_max=slip_max,
                            procedure=procedure)
    w = phys["wft"]
    n = len(w["t_s"])
    dt = 1.0 / WFT_RATE_HZ
    t_rel = w["t_s"]
    speed, omega, slip, load = w["speed_mps"], w["omega_radps"], w["slip"], w["load_n"]
    angle_rad = np.cumsum(omega) * dt + rng.uniform(0, 2 * np.pi)
    angle_deg = np.degrees(angle_rad) % 360.0
    # what the transducer reports: inertia included (physics), then its own errors (sensor effects)
    fx, my, w_meas = w["fx_n"].copy(), w["my_nm"].copy(), load.copy()
    ramp = (t_rel - t_rel[0]) / (t_rel[-1] - t_rel[0]) - 0.5  # -1/2 .. 1/2 over the run: the drifts' shape
    angle_err_deg = 0.0
    if effect == "fx_gain":
        fx *= params["gain"]
    elif effect == "my_gain":
        my *= params["gain"]
    elif effect == "load_gain":
        w_meas *= params["gain"]
    elif effect == "angle_offset":
        angle_err_deg = float(params["offset_deg"])
    elif effect == "zero_drift":
        my += params["drift_nm"] * ramp
    elif effect == "inertia_error":  # the true wheel is (1 + e) x the configured one: the reading's inertia too
        fx -= params["e"] * WHEEL_MASS_KG * w["accel_mps2"]
        my += params["e"] * WHEEL_INERTIA_KGM2 * w["omega_dot_radps2"]
    elif effect == "fx_gain_drift":  # the Fx gain drifts linearly over the run
        fx *= 1.0 + params["g"] * ramp
    elif effect == "fz_crosstalk":  # the load channel picks up k x the hub Fx
        w_meas += params["k"] * fx
    elif effect == "fz_zero_drift":  # the load channel's zero drifts linearly over the run
        w_meas += params["drift_ratio"] * static * ramp
    elif effect == "my_crosstalk":  # the torque channel picks up k x r x the hub Fx
        my += params["k"] * r * fx
    elif effect == "fx_saturation":  # F_s tanh(Fx/F_s): the run's largest |Fx| reads compression low
        from scipy.optimize import brentq

        u = brentq(lambda x: math.tanh(x) / x - (1.0 - float(params["compression"])), 1e-6, 1e3)
        f_s = float(np.max(np.abs(fx))) / u
        fx = f_s * np.tanh(fx / f_s)
    elif effect in ("load_lag", "my_lag"):  # a first-order filter of time constant tau_s on one channel
        from scipy.signal import lfilter

        a = dt / (float(params["tau_s"]) + dt)

        def lag(x):
            return lfilter([a], [1.0, a - 1.0], x, zi=[(1.0 - a) * x[0]])[0]

        if effect == "load_lag":
            w_meas = lag(w_meas)
        else:
            my = lag(my)
    gnss_read, rl_gain, rl_delay_s = speed_channel_errors(effect, params, load, static, float(t_rel[-1]))

    start_s = 1765416600 + int(seed % 5000) * 3607 + rng.uniform(0, 1)  # a December morning, seeded
    gps_offset_s = float(rng.uniform(-2.0, 2.0))       # GPS - (host UTC + leap) at the start
    gps_drift = float(rng.uniform(-30e-6, 30e-6))      # host clock rate error
    dbs = _dbc_databases()
    frames_wft = _wft_frames(dbs["wft"], rng, t_rel, w_meas, fx, my, angle_rad, angle_deg, drop_rate,
                             angle_err_deg=angle_err_deg, noise=(wft_noise, wft_noise_hz))
    frames_veh = _vehicle_bus_frames(dbs, rng, t_rel, speed, omega, slip, r, gnss_latency_s,
                                     start_s, gps_offset_s, gps_drift, front_wheels=front_wheels,
                                     gnss_read=gnss_read, rl_gain=rl_gain, rl_delay_s=rl_delay_s)
    start_ns = int(round(start_s * 1e9))
    frames = {}
    for bus, parts in ((BUS_WFT, frames_wft), (BUS_VEH, frames_veh)):
        ts = np.concatenate([p[0] for p in parts])
        order = np.argsort(ts, kind="stable")
        ts = ts[order]
        if usb_batching_s > 0:  # delivered at the next USB poll, stamped in a burst
            ph = rng.uniform(0, usb_batching_s)
            poll = np.ceil((ts - ph) / usb_batching_s) * usb_batching_s + ph
            ts = np.maximum.accumulate(poll + 60e-6 + _jitter(rng, len(ts), 3e-6))
        else:
            ts = np.maximum.accumulate(ts + _jitter(rng, len(ts)))
        frames[bus] = {
            "timestamp_ns": start_ns + np.round(ts * 1e9).astype(np.int64),
            "arbitration_id": np.concatenate([p[1] for p in parts])[order].astype(np.uint32),
            "is_extended": np.concatenate([p[2] for p in parts])[order].astype(bool),
            "dlc": np.concatenate([p[3] for p in parts])[order].astype(np.uint8),
            "data": np.concatenate([p[4] for p in parts])[order].astype(np.uint8),
        }
    first = min(int(f["timestamp_ns"][0]) for f in frames.values())
    t_host = start_ns + np.round(t_rel * 1e9).astype(np.int64)
    truth = pd.DataFrame({
        "t_s": (t_host - first) * 1e-9,
        "t_host_ns": t_host,
        "slip": slip,
        "load_n": load,
        "drawbar_pull_n": w["drawbar_pull_n"],
        "torque_nm": w["torque_nm"],
        "sinkage_m": w["sinkage_m"],
        "fx_n": fx,
        "my_nm": my,
        "load_measured_n": w_meas,
        "speed_mps": speed,
        "accel_mps2": w["accel_mps2"],
        "omega_radps": omega,
        "omega_dot_radps2": w["omega_dot_radps2"],
        "wheel_angle_deg": angle_deg,
        "distance_m": w["distance_m"],
        "soil_factor": w["soil_factor"],
        "phase": w["phase"],
        "cycle": w["cycle"],
    })
    dyn = phys["dyn"]
    lost = int(frames_wft[0][5]) if len(frames_wft[0]) > 5 else 0
    terrain_true = truth_model.soil_at(0.5)
    info = {
        "schema": "wheelsoil.simtruth/2",
        "simulator": SIMULATOR,
        "effect": effect,
        "family": family,
        "acceptable": list(ACCEPTABLE[effect]),
        "params": _jsonable(params),
        "size": params.get("size"),
        "seed": int(seed),
        "terrain": name,
        "terrain_named": _soil_json(soil),
        "terrain_true_mid_run": _soil_json({k: float(np.mean(v)) for k, v in terrain_true.items()}),
        "wheel": {"radius_m": r, "width_m": b, "wheel_mass_kg": WHEEL_MASS_KG,
                  "wheel_inertia_kgm2": WHEEL_INERTIA_KGM2},
        "static_load_n": STATIC_LOAD_N,
        "added_load_n": float(added_load_n),
        "vehicle": {"mass_kg": float(phys["mass_kg"]), "grade_rad": phys["grade"], "drive": "4x4, locked differentials",
                    "max_net_force_n": phys["can_move"]["max_net_force_n"],
                    "accel_max_mps2": phys["can_move"]["accel_max_mps2"],
                    "can_start": bool(phys["can_move"]["can_start"])},
        "force_table_max_error_n": phys["table_max_error_n"],
        "gnss_latency_s": float(gnss_latency_s),
        "gps_clock_offset_s": gps_offset_s,
        "gps_clock_drift": gps_drift,
        "gps_leap_s": GPS_LEAP_S,
        "drop_rate": float(drop_rate),
        "soil_variability": float(soil_variability),
        "usb_batching_s": float(usb_batching_s),
        "front_wheels": front_wheels,
        "slip_max": None if slip_max is None else float(slip_max),
        "procedure": procedure,
        "wft_noise": float(wft_noise),
        "wft_noise_hz": None if wft_noise_hz is None else float(wft_noise_hz),
        "lost_wft_samples": lost,
        "duration_s": float(n * dt),
        "n_cycles": int(w["cycle"].max() + 1) if n else 0,
        "distance_m": float(w["distance_m"][-1]) if n else 0.0,
        "start_unix_ns": first,
    }
    run = SimulatedRun(truth=truth, frames=frames, info=info, start_ns=first, wheel=(r, b), terrain_lab=soil)
    run.dynamics = dyn
    run.config = vehicle_config_for(r, b)
    return run


def _soil_json(soil: Mapping[str, Any]) -> dict[str, float]:
    return {"c_pa": float(soil["c"]), "phi_deg": math.degrees(float(soil["phi"])), "K_m": float(soil["K"]),
            "n": float(soil["n"]), "kc": float(soil["kc"]), "kphi": float(soil["kphi"])}


def _jsonable(x):
    if isinstance(x, Mapping):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    return x


def set_vehicle_keys(text: str, values: Mapping[str, float], *, where: str = "vehicle.toml") -> str:
    """The vehicle TOML ``text`` with ``values`` set in its ``[vehicle]`` table: a key present is
    replaced in place, a missing one appended to the table (comment: set by wheelsoil simulate).
    Raises ValueError when the text has no ``[vehicle]`` table followed by another table."""
    m = re.search(r"(?ms)^\[vehicle\]\s*\n(.*?)(?=^\[)", text)
    if not m:
        raise ValueError(f"{where}: no [vehicle] table to put the simulated wheel in")
    body = m.group(1)
    comment = "   # set by wheelsoil simulate (the simulated wheel)"
    for key, val in values.items():
        line = f"{key} = {float(val)!r}{comment}"
        pat = re.compile(rf"(?m)^{re.escape(key)}\s*=.*$")
        if pat.search(body):
            body = pat.sub(lambda _m: line, body)
        else:
            body = body.rstrip("\n") + "\n" + line + "\n\n"
    return text[:m.start(1)] + body + text[m.end(1):]


def vehicle_config_for(radius_m: float, width_m: float, *, wheel_mass_kg: float = WHEEL_MASS_KG,
                       wheel_inertia_kgm2: float = WHEEL_INERTIA_KGM2):
    """The shipped vehicle configuration with the ``[vehicle]`` wheel keys of the simulated wheel.

    Builds the TOML text from the default ``dbc/vehicle.toml``: ``wheel_radius_m``,
    ``wheel_width_m``, ``wheel_mass_kg``, ``wheel_inertia_kgm2`` (contract B) set in the
    ``[vehicle]`` table (replaced when present, added after ``wheel_width_m`` otherwise),
    and loads it with ``wheelsoil.daq.config``'s own loader (DBCs from the shipped folder).
    Returns a ``VehicleConfig`` whose ``text`` is that TOML (attached to recordings).
    Raises ValueError when the default file has no ``[vehicle]`` table.
    """
    from wheelsoil.daq.config import default_vehicle_path, tomllib, vehicle_config_from_dict

    src = default_vehicle_path()
    values = {"wheel_radius_m": radius_m, "wheel_width_m": width_m, "wheel_mass_kg": wheel_mass_kg,
              "wheel_inertia_kgm2": wheel_inertia_kgm2}
    text = set_vehicle_keys(src.read_text(encoding="utf-8"), values, where=str(src))
    return vehicle_config_from_dict(tomllib.loads(text), source=src, text=text)


def _jitter(rng, n, mean_s=150e-6):
    """Host receive-time jitter [s] (USB adapter buffering), exponential, (n,)."""
    return rng.exponential(mean_s, n)


def _sensor_noise(draws, sd, dt, noise):
    """The transducer's noise from white ``draws`` (n,) of sd ``sd``: scaled by ``noise[0]`` and,
    with a corner ``noise[1]`` [Hz], low-passed (Butterworth, 2nd order, zero phase) and rescaled
    to the same sd. See :func:`simulate_run` (``wft_noise``, ``wft_noise_hz``)."""
    scale, hz = noise
    if hz is None or draws.size < 32:
        return scale * draws
    from scipy import signal

    sos = signal.butter(2, min(hz * 2.0 * dt, 0.99), output="sos")
    x = signal.sosfiltfilt(sos, draws)
    return x * (scale * sd / max(float(np.std(x)), 1e-12))


def _wft_frames(db, rng, t_rel, load, fx, my_true, angle_rad, angle_deg, drop_rate, *, angle_err_deg=0.0,
                noise=(1.0, None)):
    """The WFT's 500 Hz Force/Moment/Angle frames plus 1 Hz Diag mux frames on can0.

    Hub forces (Fx = Dp - m_w dV/dt, Fz = W) are rotated into the wheel-fixed
    frame by inverting hardware.md's hub-from-wheel formula: Fx_w = Fx cos a -
    Fz sin a, Fz_w = Fx sin a + Fz cos a; ``my_true`` is the hub My (T + I_w
    domega/dt). ``angle_err_deg``: an encoder zero error added to the reported
    WheelAngle only; ``noise``: (scale, low-pass corner [Hz] or None) of the sensor noise
    (:func:`_sensor_noise`). Returns a list of parts (t [s], id, ext, dlc, data), the
    first one carrying the number of lost samples as a 6th item.
    """
    n = len(t_rel)
    m_force = db.get_message_by_name("WFT_RL_Force")
    m_moment = db.get_message_by_name("WFT_RL_Moment")
    m_angle = db.get_message_by_name("WFT_RL_Angle")
    m_diag = db.get_message_by_name("WFT_RL_Diag")
    ca, sa = np.cos(angle_rad), np.sin(angle_rad)
    dt = t_rel[1] - t_rel[0] if n > 1 else 0.002

    def nf(sd):  # the same draws in the same order whatever the noise options
        return _sensor_noise(rng.normal(0, sd, n), sd, dt, noise)

    fx_w = fx * ca - load * sa + nf(WFT_FORCE_NOISE_N)
    fz_w = fx * sa + load * ca + nf(WFT_FORCE_NOISE_N)
    fy_w = 150.0 * _bandlimited(rng, n, dt, 0.2, 5.0, 1.0) + nf(WFT_FORCE_NOISE_N)
    my = my_true + nf(WFT_MOMENT_NOISE_NM)
    mx_w = -0.05 * fy_w + nf(WFT_MOMENT_NOISE_NM)
    mz_w = nf(WFT_MOMENT_NOISE_NM) + 0.02 * fx
    counter = (np.arange(n) + int(rng.integers(256))) % 256
    f_data, sat_f = pack_signals(m_force, {"Fx_w": fx_w, "Fy_w": fy_w, "Fz_w": fz_w, "Counter": counter}, n)
    m_data, sat_m = pack_signals(m_moment, {"Mx_w": mx_w, "My": my, "Mz_w": mz_w, "Counter": counter}, n)
    a_data, _ = pack_signals(m_angle, {"WheelAngle": (angle_deg + angle_err_deg) % 360.0, "Counter": counter}, n)
    f_data[:, 7] = np.where(sat_f, 1, 0)  # Status bit 0: overload
    m_data[:, 7] = np.where(sat_m, 1, 0)
    # lost samples: all three frames of a sample, in short bursts
    keep = np.ones(n, dtype=bool)
    if drop_rate > 0:
        starts = rng.random(n) < drop_rate / 2.0
        burst = rng.integers(1, 4, n)  # 1..3 samples, mean 2
        idx = np.flatnonzero(starts)
        for i, b in zip(idx, burst[idx]):
            keep[i:i + b] = False
        keep[0] = keep[-1] = True  # losses show as counter gaps (the logger cannot see lost ends)
    t_tx = t_rel + 100e-6  # sample -> transmission
    parts = []
    for k, (msg, data) in enumerate(((m_force, f_data), (m_moment, m_data), (m_angle, a_data))):
        t = t_tx + k * 130e-6
        parts.append([t[keep], np.full(keep.sum(), msg.frame_id), np.zeros(keep.sum(), bool),
                      np.full(keep.sum(), msg.length), data[keep]])
    parts[0].append(int(n - keep.sum()))
    # diagnostics: 1 Hz per multiplexer value
    n_s = int(t_rel[-1]) + 1 if n else 0
    sec = np.arange(n_s, dtype=float)
    temp = 8.0 + 6.0 * (1 - np.exp(-sec / 600.0)) + rng.normal(0, 0.05, n_s)
    supply = 13.8 + rng.normal(0, 0.02, n_s)
    serial = 140321
    diag = [
        ({"DiagMux": 0, "BridgeTemp": temp, "SupplyVoltage": supply}, 0.25),
        ({"DiagMux": 1, "SerialNumber": serial}, 0.583),
        ({"DiagMux": 2, "FirmwareMajor": 2, "FirmwareMinor": 7, "CalibrationId": 1311}, 0.917),
    ]
    for vals, off in diag:
        data, _ = pack_signals(m_diag, vals, n_s)
        t = sec + off
        ok = t <= t_rel[-1]
        parts.append([t[ok], np.full(ok.sum(), m_diag.frame_id), np.zeros(ok.sum(), bool),
                      np.full(ok.sum(), m_diag.length), data[ok]])
    return parts


def _vehicle_bus_frames(dbs, rng, t_rel, speed, omega, slip, r, latency_s, start_s, gps_offset_s, gps_drift,
                        front_wheels="driven", gnss_read=None, rl_gain=None, rl_delay_s=0.0):
    """can1: wheel speeds (100 Hz), WSS status (10 Hz), GNSS speed/velocity/time (20 Hz), GPS status (1 Hz).

    All four wheels are driven through locked differentials: they turn at the
    instrumented wheel's omega (each tyre's rolling radius within +-0.3 %, so
    the wheel speeds differ by that). ``front_wheels="reference"`` puts an
    idealised undriven reference wheel (r omega = V, rolling slip -0.8 %) on the
    FL/FR channels instead (the dynamics stay 4x4); GNSS velocities are of the fix epoch
    and arrive ``latency_s`` later (their speeds read ``gnss_read(v, t)`` of the true ones, None: v); ``rl_gain``
    (on the ``t_rel`` grid, or None) multiplies the left-rear wheel-speed reading only, which
    reads the omega of ``rl_delay_s`` earlier (a late channel, 0: none);
    ``RT_SB_GPS_Time`` carries the fix's GPS week and time of week on the GPS clock (host
    clock + offset + drift).
    """
    duration = t_rel[-1]
    wss, gps = dbs["wheel_speed"], dbs["gps_rt_speedbox"]
    parts = []
    # --- wheel speed module
    m_ws = wss.get_message_by_name("WSS_WheelSpeeds")
    m_st = wss.get_message_by_name("WSS_Status")
    t_w = np.arange(rng.uniform(0, 0.01), duration, 1.0 / WSS_RATE_HZ)
    nw = len(t_w)
    om_rl = np.interp(t_w, t_rel, omega)
    tol = 1.0 + rng.uniform(-0.003, 0.003, 3)  # other tyres' rolling radii relative to the left rear
    om_f = om_rl / tol[0]
    om_fr = om_rl / tol[1]
    if front_wheels == "reference":  # an undriven reference wheel on the FL/FR channels: V/r, rolling slip
        v_w = np.interp(t_w, t_rel, speed)
        om_f = v_w / (r * 1.008) / tol[0]
        om_fr = v_w / (r * 1.008) / tol[1]
    om_rr = om_rl / tol[2]
    if rl_gain is not None:
        om_rl = om_rl * np.interp(t_w, t_rel, rl_gain)
    if rl_delay_s:
        om_rl = np.interp(t_w - rl_delay_s, t_rel, omega)

    def rpm(om):
        noisy = om * (1 + rng.normal(0, WSS_NOISE_REL, nw)) + rng.normal(0, 0.005, nw)
        return np.abs(noisy) * 60.0 / (2 * np.pi)

    data, _ = pack_signals(m_ws, {"WheelSpeed_FL": rpm(om_f), "WheelSpeed_FR": rpm(om_fr),
                                  "WheelSpeed_RL": rpm(om_rl), "WheelSpeed_RR": rpm(om_rr)}, nw)
    parts.append([t_w + 80e-6, np.full(nw, m_ws.frame_id), np.zeros(nw, bool),
                  np.full(nw, m_ws.length), data])
    t_s = t_w[::10] + 300e-6
    ns = len(t_s)
    data, _ = pack_signals(m_st, {"RollingCounter": np.arange(ns) % 16}, ns)
    parts.append([t_s, np.full(ns, m_st.frame_id), np.zeros(ns, bool), np.full(ns, m_st.length), data])
    # --- GNSS receiver: fix epochs on the GPS clock, 20 Hz
    gps0 = start_s - GPS_UNIX_EPOCH_S + GPS_LEAP_S + gps_offset_s  # GPS seconds at t_rel = 0
    step = 1.0 / GNSS_RATE_HZ
    k0 = math.ceil(gps0 / step)
    k1 = math.floor((gps0 + duration * (1 + gps_drift)) / step)
    gps_fix = np.arange(k0, k1 + 1) * step
    t_fix = (gps_fix - gps0) / (1 + gps_drift)  # host time of the fix epoch
    ng = len(t_fix)
    v_fix = np.interp(t_fix, t_rel, speed)
    if gnss_read is not None:
        v_fix = gnss_read(v_fix, t_fix)
    t_rx = t_fix + latency_s + np.abs(rng.normal(0, 1.5e-3, ng))
    m_spd = gps.get_message_by_name("RT_SB_GPS_Speed")
    m_vel = gps.get_message_by_name("RT_SB_INS_Vel_Body_Axes")
    m_time = gps.get_message_by_name("RT_SB_GPS_Time")
    m_stat = gps.get_message_by_name("RT_SB_GPS_Status")
    v2d = np.abs(v_fix + rng.normal(0, GNSS_SPEED_NOISE_MPS, ng))
    v3d = np.sqrt(v2d**2 + rng.normal(0, 0.02, ng) ** 2)
    data, _ = pack_signals(m_spd, {"GPS_Speed_2D": v2d, "GPS_Speed_3D": v3d, "Accuracy_GPS_Speed": 12,
                                   "Validity_GPS_Speed_2D": 1, "Validity_GPS_Speed_3D": 1}, ng)
    parts.append([t_rx, np.full(ng, m_spd.frame_id), np.ones(ng, bool), np.full(ng, m_spd.length), data])
    v_fwd = v_fix + rng.normal(0, INS_SPEED_NOISE_MPS, ng)
    v_side = 0.03 * np.sin(2 * np.pi * t_fix / 7.0) + rng.normal(0, INS_SPEED_NOISE_MPS, ng)
    data, _ = pack_signals(m_vel, {"INS_Vel_Forwards_2D": v_fwd, "INS_Vel_Sideways_2D": v_side,
                                   "Accuracy_INS_Vel_Body": 10, "Validity_INS_Vel_Forwards": 1,
                                   "Validity_INS_Vel_Sideways": 1}, ng)
    parts.append([t_rx + 260e-6, np.full(ng, m_vel.frame_id), np.ones(ng, bool), np.full(ng, m_vel.length), data])
    week = np.floor(gps_fix / GPS_WEEK_S)
    tow = gps_fix - week * GPS_WEEK_S
    data, _ = pack_signals(m_time, {"GPS_Week": week, "GPS_Time": tow, "Accuracy_GPS_Time": 3,
                                    "Validity_GPS_Week": 1, "Validity_GPS_Time": 1}, ng)
    parts.append([t_rx + 520e-6, np.full(ng, m_time.frame_id), np.ones(ng, bool), np.full(ng, m_time.length), data])
    sec_mask = np.isclose(np.mod(gps_fix, 1.0), 0.0, atol=1e-6) | np.isclose(np.mod(gps_fix, 1.0), 1.0, atol=1e-6)
    t_st = t_rx[sec_mask] + 780e-6
    nst = len(t_st)
    nsv = np.clip(np.round(11 + np.cumsum(rng.normal(0, 0.15, nst))), 6, 16)
    data, _ = pack_signals(m_stat, {"GPS_Status": 12, "GPS_nSv": nsv, "GPS_nSv_2": nsv - 1, "GPS_nSv_RTK": nsv - 2,
                                    "RTK_Status": 3, "Firmware_Version_Major": 2, "Firmware_Version_Intermediate": 4,
                                    "Firmware_Version_Minor": 1}, nst)
    parts.append([t_st, np.full(nst, m_stat.frame_id), np.ones(nst, bool), np.full(nst, m_stat.length), data])
    return parts




# ------------------------------------------------------------------------ output
#: Options whose values would give the hidden effect away: redacted in the recorded command.
_HIDDEN_OPTIONS = ("--effect", "--param", "--size", "--truth")


def _redacted_command() -> list[str] | None:
    """The ``wheelsoil`` command line that is running (as provenance records it), with the values of
    :data:`_HIDDEN_OPTIONS` replaced by ``<hidden>``; None when not run from the wheelsoil CLI."""
    import sys

    argv = list(sys.argv)
    if not argv:
        return None
    exe = Path(argv[0])
    if not (exe.name.startswith("wheelsoil") or (exe.name == "__main__.py" and exe.parent.name == "wheelsoil")):
        return None
    out, hide_next = ["wheelsoil"], False
    for a in argv[1:]:
        if hide_next:
            out.append("<hidden>")
            hide_next = False
        elif a in _HIDDEN_OPTIONS:
            out.append(a)
            hide_next = True
        elif a.split("=", 1)[0] in _HIDDEN_OPTIONS and "=" in a:
            out.append(a.split("=", 1)[0] + "=<hidden>")
        else:
            out.append(a)
    return out


def _write_mcap(run: SimulatedRun, path: Path, config=None) -> None:
    """Write ``run`` as an MCAP recording: frame batches per bus every
    ``wheelsoil.daq.logger.BATCH_INTERVAL_S`` in receive order (the logger's layout), the
    vehicle configuration of the simulated wheel, a provenance record ``simulated`` (seed,
    simulator), lost-frame counts in the summary. No logger status records and no logger
    facts: no logger made this file."""
    from wheelsoil.daq import RecordingWriter
    from wheelsoil.daq.provenance import make_provenance
    from wheelsoil.daq.stats import StatsAccumulator

    try:
        from wheelsoil.daq.logger import BATCH_INTERVAL_S
    except ImportError:  # pragma: no cover - older daq
        BATCH_INTERVAL_S = 0.5
    config = config or run.config or vehicle_config_for(*run.wheel)
    batches = run.frame_batches()
    acc = StatsAccumulator(config)
    t_end = max(int(b.timestamp_ns[-1]) for b in batches.values() if len(b)) + 1
    step = int(round(BATCH_INTERVAL_S * 1e9))
    edges = np.arange(run.start_ns, t_end + step, step, dtype=np.int64)
    cuts = {bus: np.searchsorted(b.timestamp_ns, edges) for bus, b in batches.items()}
    prov = make_provenance("simulated", command=_redacted_command(), seed=int(run.info["seed"]), simulator=SIMULATOR)
    with RecordingWriter(path, config=config, provenance=prov, fsync=False) as writer:
        for bus in sorted(batches):
            writer.add_bus(bus, interface="simulated", channel=bus)
        for w in range(len(edges) - 1):
            for bus in sorted(batches):
                lo, hi = cuts[bus][w], cuts[bus][w + 1]
                if hi > lo:
                    part = batches[bus].select(slice(lo, hi))
                    writer.write_batch(part)
                    acc.update(part)
            writer.flush()  # one chunk per batch interval, as the logger closes them (damage stays local)
        st = acc.stats
        writer.summary.update({"lost_frames": {k: int(v) for k, v in st.lost_frames.items()}})


def write_simulation(run: SimulatedRun, path, *, config=None) -> Path:
    """Write a simulated run as a recording, the format chosen by the suffix.

    ``.mcap``: through ``wheelsoil.daq.RecordingWriter`` with the vehicle
    configuration of the simulated wheel (:func:`vehicle_config_for`; ``config``
    overrides), frame batches per bus at the logger's batch interval, and the
    provenance record ``simulated`` with the seed (never the effect). ``.log`` (candump -L), ``.asc``, ``.blf``, ``.trc``:
    python-can's writers (``can.Logger``), exactly what ``wheelsoil import``
    reads; channel ``can0`` (WFT) and ``can1`` (wheel speeds, GNSS) (numbered
    0 and 1 in the formats with numeric channels).
    Raises ValueError for an unknown suffix; OSError when the file cannot be written.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".mcap":
        _write_mcap(run, path, config)
        return path
    if suffix not in OUTPUT_SUFFIXES:
        raise ValueError(f"{path}: unknown output format {suffix!r}; use .mcap, .log, .asc, .blf or .trc")
    import can

    merged = []
    for ch, (bus, f) in enumerate(sorted(run.frames.items())):
        merged.append((f["timestamp_ns"], np.full(len(f["timestamp_ns"]), ch), np.arange(len(f["timestamp_ns"]))))
    ts = np.concatenate([m[0] for m in merged])
    chs = np.concatenate([m[1] for m in merged])
    idx = np.concatenate([m[2] for m in merged])
    order = np.lexsort((chs, ts))
    buses = sorted(run.frames)
    tmp = path.with_name(f".{path.stem}.partial{suffix}")  # renamed into place when complete
    try:
        with can.Logger(str(tmp)) as logger:
            for i in order:
                bus = buses[chs[i]]
                f = run.frames[bus]
                j = idx[i]
                dlc = int(f["dlc"][j])
                channel: Any = bus if suffix == ".log" else int(bus.removeprefix("can") or 0)
                logger.on_message_received(can.Message(
                    timestamp=int(f["timestamp_ns"][j]) / 1e9,
                    arbitration_id=int(f["arbitration_id"][j]),
                    is_extended_id=bool(f["is_extended"][j]),
                    dlc=dlc,
                    data=bytes(f["data"][j, :dlc]),
                    channel=channel,
                    is_rx=True,
                ))
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def write_vehicle_config(run: SimulatedRun, path) -> Path:
    """Write the vehicle configuration of the simulated wheel as a TOML file (DBC paths made absolute,
    pointing at the shipped DBCs), e.g. for ``wheelsoil import run.log --vehicle FILE`` of a .log/.blf
    output (those formats carry no configuration). Raises OSError when it cannot be written."""
    from wheelsoil.daq.config import default_vehicle_path

    cfg = run.config or vehicle_config_for(*run.wheel)
    text = cfg.text
    base = default_vehicle_path().parent
    for bus_dbcs in cfg.buses.values():
        for p in bus_dbcs:
            text = text.replace(f'"{p.name}"', json.dumps(str(base / p.name)))
    path = Path(path)
    path.write_text(text, encoding="utf-8")
    return path


def write_truth(run: SimulatedRun, path) -> Path:
    """Write the hidden truth (contract F: ``effect``, ``family``, ``acceptable``, ``params``,
    ``seed``; plus terrain, wheel, loads, latency, clocks, ...) as JSON (schema wheelsoil.simtruth/2)."""
    path = Path(path)
    path.write_text(json.dumps(_jsonable(run.info), indent=2) + "\n", encoding="utf-8")
    return path




# ------------------------------------------------------------------ verification
#: Plausible runs (terrain, wheel [m], added load per rear wheel [N]) for benchmarks: the paper's
#: sand run (Fig. 5) with the default tyre; clay with 3 kN added (Fig. 4) needs the deflected tyre's
#: larger equivalent rigid wheel (Wong's model with the 0.47 x 0.32 m wheel at 11 kN gives Dp < 0
#: at every slip: the 4x4 could not move); clay with the default wheel without added load.
SCENARIOS = (
    {"terrain": "sand", "wheel": (0.47, 0.32), "added_load_n": 5000.0},
    {"terrain": "clay", "wheel": (0.55, 0.40), "added_load_n": 3000.0},
    {"terrain": "clay", "wheel": (0.47, 0.32), "added_load_n": 0.0},
    {"terrain": "sand", "wheel": (0.55, 0.40), "added_load_n": 3000.0},
)


def draw_case(seed: int, *, effect: str | None = None, terrains: Sequence[str] | None = None,
              effects: Sequence[str] = EFFECTS) -> dict[str, Any]:
    """A benchmark case from ``seed`` alone (so any case can be re-run by its seed).

    Effect ``effects[seed % len(effects)]`` unless given (so consecutive seeds cover every
    effect in and out of family equally; a batch of ``HELD_OUT_BATCHES``: the held-out causes),
    a scenario of :data:`SCENARIOS`, effect size uniform in [0, 1], GNSS latency 0.03-0.2 s,
    drop rate 0-1 %. ``terrains`` (built-in terrain slugs, ``wheelsoil terrains``): the
    scenario's soil replaced by one of them, drawn from the seed on a separate stream (the
    other draws stay those of the seed). Returns
    :func:`simulate_run` keyword arguments plus ``terrain``.
    """
    rng = np.random.default_rng([int(seed), 20261121])
    eff = effect or str(effects[int(seed) % len(effects)])
    sc = dict(SCENARIOS[int(rng.integers(len(SCENARIOS)))])
    if terrains:
        sc["terrain"] = str(terrains[int(np.random.default_rng([int(seed), 20261123]).integers(len(terrains)))])
    return {
        "terrain": sc["terrain"], "wheel": sc["wheel"], "added_load_n": sc["added_load_n"], "effect": eff,
        "size": float(rng.uniform(0.0, 1.0)), "gnss_latency_s": float(rng.uniform(0.03, 0.2)),
        "drop_rate": float(rng.uniform(0.0, 0.01)), "seed": int(seed),
    }


#: The verdicts that name a cause.
NAMED_CAUSES = ("slip_sinkage", "terrain_mismatch", "stress_distribution", "terrain_drift")
_FORMS = {"vasilev": "vasilev", "lyasko": "lyasko", "ding": "ding"}


def judge(truth: Mapping[str, Any], report: Mapping[str, Any]) -> dict[str, Any]:
    """Score a fit report (report.json) against the hidden truth (``simulate --truth``).

    Reads only ``report["diagnosis"]`` (``effect``, ``confidence``, ``model``) and the time sync.
    Returns a dict: ``effect``, ``family``, ``acceptable``, ``verdict``, ``model``,
    ``confidence``, ``right`` (verdict in ``acceptable``), ``wrong_cause`` (the verdict names
    a cause, slip_sinkage / terrain_mismatch / stress_distribution / terrain_drift, not in
    ``acceptable``), ``missed`` (verdict ``none`` although there is an effect),
    ``false_alarm`` (a verdict other than ``none`` for ``none``), ``form_ok`` (for a true
    slip-sinkage form named slip_sinkage: the model names that form; else None),
    ``latency_error_s`` (reported minus true GNSS latency, or None).
    """
    effect = truth["effect"]
    acceptable = list(truth.get("acceptable") or ACCEPTABLE[effect])
    diag = report.get("diagnosis") or {}
    verdict = diag.get("effect")
    model = diag.get("model")
    out: dict[str, Any] = {
        "effect": effect, "family": truth.get("family") or family_of(effect), "acceptable": acceptable,
        "verdict": verdict, "model": model, "confidence": diag.get("confidence"),
    }
    out["right"] = verdict in acceptable
    out["wrong_cause"] = verdict in NAMED_CAUSES and verdict not in acceptable
    out["missed"] = effect != "none" and verdict == "none"
    out["false_alarm"] = effect == "none" and verdict != "none"
    form_ok = None
    if effect in _FORMS and verdict == "slip_sinkage":
        form_ok = bool(model) and _FORMS[effect] in str(model).lower()
    out["form_ok"] = form_ok
    lat = (report.get("time_sync") or {}).get("gnss_latency_s")
    out["latency_error_s"] = None if lat is None or truth.get("gnss_latency_s") is None else \
        float(lat) - float(truth["gnss_latency_s"])
    return out


# --------------------------------------------------------------------------- CLI
_EPILOG = """\
examples:
  wheelsoil simulate --terrain sand --effect lyasko -o run.mcap
  wheelsoil simulate --terrain sand --effect vasilev --param H=0.08 --added-load 5000 -o run.log
  wheelsoil simulate --terrain clay --wheel-radius 0.55 --wheel-width 0.40 --effect ding \\
      --size 0.5 --seed 4 --truth truth.json -o run.mcap
  wheelsoil fit run.mcap --terrain clay -o report/      # the radius comes from the recording

what is simulated: a 3.6 t 4x4 (all wheels driven, locked differentials) in straight
accelerate-brake runs; the driver sweeps the wheels' slip from ~0 to ~0.9 and back; the
vehicle's speed comes from the four wheels' drawbar pull (the true soil model, computed
by adaptive quadrature independently of the fitter's kernel); the left-rear wheel force
transducer sees Fx = Dp - m_w dV/dt and My = T + I_w domega/dt (m_w 80 kg, I_w 11.5 kg m^2).
A soil/wheel/load on which the vehicle could not pull away is refused with the numbers
(e.g. the paper's clay with the 0.47 x 0.32 m wheel at 8 + 3 kN: use --wheel-radius 0.55
--wheel-width 0.40, Wong's equivalent rigid wheel of the deflected tyre, or --added-load 0).

effects (--effect; parameters with --param NAME=VALUE, the others drawn at --size):
  in family (a verdict should name them):
    none                 Wong's model on the lab soil
    vasilev              z = z0 + H s (H [m])                         -> slip_sinkage
    lyasko               z = z0 (1 + m1 s)/(1 - m2 s)                 -> slip_sinkage
    ding                 N = n + n1 s                                 -> slip_sinkage
    terrain_mismatch     lab k_eq, n, c, phi or K wrong               -> terrain_mismatch
    stress_distribution  Wong-Reece stress, theta_m = (a1 + a2 s) theta1 -> stress_distribution
    terrain_drift        a soil value drifts along the run (compaction / another patch) -> terrain_drift
  out of family (no hypothesis models them: 'unexplained' is the honest verdict):
    fx_gain, my_gain     transducer Fx / My calibration gain (gain)
    load_gain            transducer Fz gain (gain); exactly a k_eq mismatch under Eq. 10,
                         so terrain_mismatch is acceptable too
    angle_offset         wheel-angle encoder zero error (offset_deg): W leaks into Fx
    tyre_deflection      equivalent rigid wheel r (1 + kappa W/W_static) (kappa)
    bulldozing           Bekker bulldozing resistance x factor (factor)
    load_dependent       k_eq (W/W_static)^beta (beta)
    vertical_balance     true sinkage from the vertical balance Eq. 7, not Eq. 10
    width_error          the tyre's effective contact width is factor x b (factor); exactly
                         kphi and c x factor, so terrain_mismatch is acceptable too
    zero_drift           the transducer's My zero drifts over the run (drift_nm, end - start)
  held out (out of family, added after the diagnosis' rule to score it on causes it was
  not developed on; bench_diagnosis.py --effects held-out / held-out-2 / ... / -13):
    exit_angle           a rebounding soil: contact on to theta2 = exit_frac theta1 behind the
                         bottom (a stress distribution: stress_distribution acceptable too)
    shear_hump           Wong's hump-shaped shear curve, residual Kr x the strength
    gnss_gain            the GNSS speed reads gain x the true speed (slip from a wrong speed)
    strength_softening   shear strength x (1 - beta s): a soil remoulded at high slip
    tyre_hysteresis      the tyre's internal losses: hub torque + f W r, Dp unchanged
    inertia_error        the wheel's mass and inertia are (1 + e) x the configured ones
    hard_layer           a firm layer at depth_ratio x the static sinkage caps the sinkage
    fz_crosstalk         the transducer's load channel reads W + k Fx
    load_radius          rolling radius r (1 - e (W - W0)/W0): slip off with the load
    slip_angle           the wheel runs at a slip angle angle_deg: the soil is sheared sideways too
    grouser              lugs of height_ratio x r: the soil is sheared at the lug tips
    wheel_latency        the left-rear wheel-speed channel arrives delay_s late
    fx_gain_drift        the transducer's Fx gain drifts by g over the run (1 + g (t/t_end - 1/2))
    mud_buildup          mud on the tyre: the radius grows to r (1 + e) along the run
    curved_envelope      a curved failure envelope: c + tan phi sigma0 (sigma/sigma0)^beta
    load_lag             the transducer's load channel lags with time constant tau_s
    pressure_k           K grows with the normal stress: K (sigma/sigma0)^gamma
    radius_error         the tyre's true rolling radius is (1 + e) r (slip computed with r)
    fz_zero_drift        the transducer's load zero drifts by drift_ratio x the static load
    my_crosstalk         the transducer's torque channel reads My + k r Fx
    rate_shear           shear strength x (1 + beta ln(1 + s/0.02)): a rate-dependent soil
    loose_top            shear strength x (d/z0)^a, d the depth below the surface: a loose top layer
    interface            friction f tan phi above sigma0/2: a tyre-soil interface weaker than the soil
    bouncing             every wheel's load oscillates at 1.5-3 Hz by amplitude x its static load
    fx_saturation        the transducer's Fx saturates: F_s tanh(Fx/F_s), the largest |Fx| compression low
    tyre_compliance      the tread's deformation slip e T/(r W0) is part of the computed slip
    slip_sinkage_lag     Vasil'ev slip sinkage H s_lag, the slip through a first-order lag tau_s
    speed_resistance     Dp less e W (V / 5 m/s)^2: a resistance growing with the forward speed
    rate_sinkage         kc, kphi x (1 + e ln(1 + V / 0.025 m/s)): a soil stiffer at the wheel's loading rate
    my_lag               the torque channel through a first-order lag of time constant tau_s
    saturating_drift     a soil value drifting fast, then slowly (1 - exp(-x/length)) -> terrain_drift or unexplained
    gradual_patch        another patch of ground over a transition of width x the run -> terrain_drift or unexplained
    patchy_ground        a soil value alternating along the track, cycles periods -> terrain_drift or unexplained
    rut                  the wheel in the rut of a front wheel at load_ratio x the static load, the soil
                         below reloading R x stiffer
    tyre_pressure_loss   the tyre's deflection growing along the run to r (1 + kappa W/W_static)
    moisture             k_eq, c and phi falling (rising) together along the run -> terrain_drift or unexplained
    speed_sinkage        sinkage z0 + H r omega / (5 m/s): growing with the tread's speed, not with slip
    gnss_offset          the GNSS speed reads V + offset_mps (faded in over the first 0.5 m/s)
    tyre_growth          the rolling radius grows with speed, r (1 + kappa (r omega / 10 m/s)^2)
    runout               an out-of-round tyre: rolling radius r (1 + e sin psi), psi the wheel's angle
    gnss_multipath       bursts of GNSS speed error: [start fraction, duration s, offset m/s] per burst
    tyre_warmup          torque + f W r exp(-x/length): a cold tyre's rolling resistance fading along the run
    crust                a cohesive crust: strength + a (c + sigma0 tan phi) exp(-d / (depth_ratio z0))
    slip_k               a shear deformation modulus growing with slip, K (1 + a s)
    gnss_lag             the GNSS velocity through a first-order lag of tau_s (the receiver's smoothing)

The recording holds only what a logger would record plus a provenance record
(kind "simulated", the seed): the effect and its parameters go to --truth FILE
(keys effect, family, acceptable, params, seed, ...), only when asked.
"""


def register(subparsers) -> None:
    """Add ``wheelsoil simulate`` to the CLI."""
    p = subparsers.add_parser(
        "simulate",
        help="simulate a physical field run (4x4 accelerate-brake slip sweeps) as a recording with a hidden effect",
        description="Simulate the paper's accelerate-brake field runs of the instrumented left-rear wheel as raw "
        "CAN frames (WFT on can0; wheel speeds and GNSS on can1): vehicle dynamics driven by the soil forces, "
        "wheel inertia in the transducer signals, noise, DBC quantisation, timestamp jitter, a host/GPS clock "
        "offset, GNSS latency and lost frames, and a hidden effect in or out of the diagnosis' family.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--terrain", required=True, help="built-in terrain name (clay, sand, ...) or a terrain TOML file")
    p.add_argument("--effect", default="none", choices=EFFECTS + ALL_HELD_OUT, metavar="EFFECT",
                   help="hidden effect (default none; list below)")
    p.add_argument("--param", action="append", default=[], metavar="K=V",
                   help="a parameter of the effect, repeatable (e.g. m1=0.6); others drawn at --size")
    p.add_argument("--size", type=float, default=None, metavar="U",
                   help="effect size in [0, 1] for drawn parameters: 0 barely above the noise, 1 large "
                   "(default: drawn)")
    p.add_argument("--added-load", type=float, default=None, metavar="N",
                   help="ballast per rear wheel on top of the 8 kN static load [N] (default 3000 for clay, "
                   "5000 for sand, else 3000)")
    p.add_argument("--gnss-latency", type=float, default=0.1, metavar="S", help="GNSS velocity latency [s] (default 0.1)")
    p.add_argument("--drop-rate", type=float, default=0.0, metavar="P",
                   help="probability of losing a WFT sample's frames (default 0)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--soil-variability", type=float, default=0.02, metavar="F",
                   help="relative sd of c, kc, kphi along the track (default 0.02; 0 = the lab soil everywhere)")
    p.add_argument("--usb-batching", type=float, default=0.0, metavar="S",
                   help="host timestamps of a USB adapter polled every S seconds, e.g. 0.001 (default 0: per frame)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="run length [s] (>= 30); default: --cycles accelerate-brake cycles")
    p.add_argument("--cycles", type=int, default=6, help="accelerate-brake cycles when no --duration (default 6)")
    p.add_argument("--wheel-radius", type=float, default=None, metavar="M",
                   help="wheel radius [m] (default 0.47); the recording's vehicle configuration carries it, "
                   "so `wheelsoil fit` uses it without options")
    p.add_argument("--wheel-width", type=float, default=None, metavar="M", help="wheel width [m] (default 0.32)")
    p.add_argument("--front-wheels", choices=("driven", "reference"), default="driven",
                   help="what the FL/FR wheel-speed channels carry: the 4x4's driven front wheels (default, "
                   "physical) or an idealised undriven reference wheel (r omega = V)")
    p.add_argument("--slip-max", type=float, default=None, metavar="S",
                   help="the highest slip the driver sweeps to, 0.2 .. 0.95 (default: about 0.9, as in the paper)")
    p.add_argument("--procedure", choices=PROCEDURES, default="sweeps",
                   help="the test: 'sweeps' (default; accelerate-brake slip sweeps, as in the paper), 'tow' (the "
                   "field's steady drawbar-pull test: slip levels held a few seconds each against a towed load "
                   "vehicle that holds the speed; --cycles then counts the passes) or 'tow-down' (the same, the "
                   "levels from the highest down)")
    p.add_argument("--wft-noise", type=float, default=1.0, metavar="F",
                   help="scale of the transducer's sensor noise (default 1: Fx, Fz sd %g N, moments %g N m)"
                   % (WFT_FORCE_NOISE_N, WFT_MOMENT_NOISE_NM))
    p.add_argument("--wft-noise-hz", type=float, default=None, metavar="HZ",
                   help="put that noise below HZ instead of white (same sd; slow wobbles such as vibration "
                   "and drift, e.g. 2)")
    p.add_argument("--truth", default=None, metavar="FILE", help="also write the hidden truth to this JSON file")
    p.add_argument("--vehicle-out", default=None, metavar="TOML",
                   help="also write the simulated wheel's vehicle configuration (for `wheelsoil import "
                   "run.log --vehicle TOML`; an .mcap output carries it already)")
    p.add_argument("-o", "--output", required=True, help="output: .mcap, or .log/.asc/.blf/.trc (then `wheelsoil import`)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace OUTPUT (and the --truth, --vehicle-out files) if they exist (default: keep them, refuse)")
    p.set_defaults(func=_cmd_simulate)


def _parse_params(items) -> dict[str, float]:
    out = {}
    for item in items:
        key, sep, val = item.partition("=")
        if not sep:
            raise ValueError(f"--param {item!r}: expected NAME=VALUE")
        try:
            out[key.strip()] = float(val)
        except ValueError:
            raise ValueError(f"--param {item!r}: {val!r} is not a number") from None
    return out


#: Parameters each effect takes on the command line: the drawn ones, but a terrain change as its soil values.
SOIL_VALUES = ("k_eq", "n", "c", "phi", "K")
CLI_PARAMS = {**PARAM_NAMES, "terrain_mismatch": SOIL_VALUES, "terrain_drift": SOIL_VALUES,
              **{e: SOIL_VALUES + tuple(k for k in PARAM_NAMES[e] if k != "changes") for e in HELD_OUT_11},
              "moisture": SOIL_VALUES}

OUTPUT_SUFFIXES = (".mcap", ".log", ".asc", ".blf", ".trc")


def _cli_params(effect: str, given: dict[str, float]) -> dict[str, Any]:
    allowed = CLI_PARAMS[effect]
    bad = set(given) - set(allowed)
    if bad:
        raise ValueError(f"effect {effect!r} has no parameter(s) {sorted(bad)}; known: {list(allowed) or 'none'}")
    if effect in ("terrain_mismatch", "terrain_drift", "moisture") + HELD_OUT_11 and set(given) & set(SOIL_VALUES):
        # k_eq, c, K as factors on the lab value; n, phi as deltas (phi in degrees); a drift's shape as given
        changes, shape = {}, {k: v for k, v in given.items() if k not in SOIL_VALUES}
        for k, v in given.items():
            if k not in SOIL_VALUES:
                continue
            if k in ("n",):
                changes[k] = {"kind": "delta", "value": v}
            elif k == "phi":
                changes[k] = {"kind": "delta_deg", "value": v}
            else:
                changes[k] = {"kind": "factor", "value": v}
        return {"changes": changes, **shape}
    return dict(given)


def _cmd_simulate(args) -> int:
    if Path(args.output).suffix.lower() not in OUTPUT_SUFFIXES:
        raise ValueError(f"{args.output}: unknown output format {Path(args.output).suffix!r}; "
                         f"use {', '.join(OUTPUT_SUFFIXES)}")
    from wheelsoil.daq.recording import check_output

    outs = [args.output, *(o for o in (args.truth, args.vehicle_out) if o)]
    if len(set(map(os.path.abspath, outs))) < len(outs):
        raise ValueError(f"{', '.join(outs)}: the same file is given for two outputs")
    for o in outs:  # before the simulation: a field file of the same name is never replaced unasked
        check_output(o, overwrite=args.overwrite)
    from wheelsoil.model.terrain import load_terrain  # the lab terrain's values (a dataclass)

    terrain = load_terrain(args.terrain)
    from wheelsoil.processing.pipeline import check_wheel_radius, check_wheel_width

    wheel = (DEFAULT_RADIUS_M if args.wheel_radius is None else check_wheel_radius(args.wheel_radius, "--wheel-radius"),
             DEFAULT_WIDTH_M if args.wheel_width is None else check_wheel_width(args.wheel_width, "--wheel-width"))
    added = args.added_load
    if added is None:
        added = 5000.0 if terrain.name.lower().startswith("sand") else 3000.0
    run = simulate_run(
        terrain, effect=args.effect, params=_cli_params(args.effect, _parse_params(args.param)), size=args.size,
        wheel=wheel, added_load_n=added, gnss_latency_s=args.gnss_latency, drop_rate=args.drop_rate,
        seed=args.seed, duration_s=args.duration, n_cycles=args.cycles, soil_variability=args.soil_variability,
        usb_batching_s=args.usb_batching, front_wheels=args.front_wheels, slip_max=args.slip_max,
        procedure=args.procedure, wft_noise=args.wft_noise, wft_noise_hz=args.wft_noise_hz,
    )
    out = write_simulation(run, args.output)
    per_bus = ", ".join(f"{b}: {len(f['timestamp_ns'])}" for b, f in sorted(run.frames.items()))
    print(f"wrote {out}: {run.duration_s:.1f} s, {run.n_frames} frames ({per_bus}), "
          f"{out.stat().st_size / 1e6:.2f} MB; wheel {wheel[0]} x {wheel[1]} m, vehicle {run.info['vehicle']['mass_kg']:.0f} kg")
    if args.vehicle_out:
        write_vehicle_config(run, args.vehicle_out)
        print(f"vehicle configuration -> {args.vehicle_out}")
    if args.truth:
        write_truth(run, args.truth)
        print(f"hidden truth -> {args.truth}")
    return 0
