"""Field-test simulator: the paper's accelerate-brake runs as raw CAN frames.

No public recordings of the instrumented vehicle exist (``docs/hardware.md`` of
the shared material describes it), so this module produces field-realistic ones:
the same messages, ids, rates, DBC quantisation, frames and sign conventions as
the vehicle, with sensor noise, host timestamps with jitter (one host clock for
both buses), an unknown host/GPS clock offset and drift, a GNSS velocity latency
and lost WFT samples. The wheel-soil forces come from :mod:`wheelsoil.model`
with a *hidden effect*:

``none``              Wong's model (paper Eqs. 1-10) on the named lab terrain;
``vasilev``           slip sinkage z = z0 + H s (Eq. 11);
``lyasko``            z = z0 (1 + m1 s) / (1 - m2 s) (Eq. 12);
``ding``              N = n + n1 s (Eq. 13);
``terrain_mismatch``  Wong's structure, but the true soil's shear parameters K
                      and phi differ from the lab values of the named terrain.

Test procedure (paper section 2.2): straight accelerate-brake runs of a 3.6 t
vehicle, instrumented left-rear wheel with 8 kN static load plus an added load
(3 kN on clay, 5 kN on sand); each acceleration sweeps the slip from about 0 to
about 0.9 and back; several cycles, standstill between some of them.

Library::

    run = simulate_run(load_terrain("clay"), effect="lyasko", seed=3)
    write_simulation(run, "run.mcap")          # exactly what `wheelsoil log` writes
    write_simulation(run, "run.log")           # candump -L, the input of `wheelsoil import`
    write_truth(run, "truth.json")             # the hidden truth, only when asked

Command line: ``wheelsoil simulate --terrain clay --effect lyasko -o run.mcap``.
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

#: Hidden effects the simulator can put into a run.
EFFECTS = ("none", "vasilev", "lyasko", "ding", "terrain_mismatch")

#: Realistic ranges of the slip-sinkage coefficients drawn when not given
#: (paper Tab. 3: clay H 0.02, m1 0.1, m2 0.05, n1 0.35; sand H 0.08, m1 0.6,
#: m2 0.03, n1 0.53). Clipped to the model core's parameter bounds.
PARAM_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "vasilev": {"H": (0.02, 0.10)},
    "lyasko": {"m1": (0.1, 0.8), "m2": (0.02, 0.10)},
    "ding": {"n1": (0.2, 0.6)},
}

#: terrain_mismatch draws: true K = lab K x factor (factor in 0.4-0.7 or 1.5-2.5),
#: true phi = lab phi +- 3..6 deg. Parameters ``K`` [m] and ``phi_deg`` [deg].
MISMATCH_K_FACTORS = ((0.4, 0.7), (1.5, 2.5))
MISMATCH_PHI_DELTA_DEG = (3.0, 6.0)

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
    """

    truth: Any
    frames: dict[str, dict[str, np.ndarray]]
    info: dict[str, Any]
    start_ns: int
    wheel: Any = None
    terrain_lab: Any = None
    extras: dict[str, Any] = field(default_factory=dict)

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


# ------------------------------------------------------------------ drive profile
def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _bandlimited(rng, n, dt, lo_hz, hi_hz, sigma):
    """Zero-mean band-limited Gaussian noise (Butterworth band-pass of white noise), (n,)."""
    from scipy import signal

    if n < 32:
        return np.zeros(n)
    nyq = 0.5 / dt
    sos = signal.butter(2, [lo_hz / nyq, min(hi_hz / nyq, 0.99)], btype="band", output="sos")
    x = signal.sosfilt(sos, rng.standard_normal(n + 2000))[2000:]
    return x * (sigma / max(np.std(x), 1e-12))


def _spatial_field(rng, distance_m, corr_m, sigma):
    """Zero-mean Gaussian random field of travelled distance (Gaussian kernel of
    width ``corr_m`` on a 0.25 m grid), sd ``sigma``, sampled at ``distance_m`` (N,)."""
    if sigma <= 0 or len(distance_m) == 0:
        return np.zeros(len(distance_m))
    from scipy.ndimage import gaussian_filter1d

    grid = np.arange(0.0, float(distance_m[-1]) + 1.0, 0.25)
    white = rng.standard_normal(len(grid) + 80)
    field_ = gaussian_filter1d(white, corr_m / 0.25, mode="wrap")[40:40 + len(grid)]
    field_ *= sigma / max(float(np.std(field_)), 1e-12)
    return np.interp(distance_m, grid, field_)


def _drive_profile(rng, dt, n_cycles, duration_s, wheel_radius_m):
    """Vehicle speed V(t), slip s(t), phase and cycle id on a grid of step dt.

    Each cycle: [standstill, pull-away] or cruise, an acceleration whose slip
    sweeps from ~0.04 up to ~0.85-0.92 and back while V rises, a short cruise,
    then braking with negative slip down to a crawl or to standstill. With
    ``duration_s`` the run is cut there (the last cycle may be partial);
    otherwise ``n_cycles`` cycles and a final standstill.
    Returns arrays of shape (N,): speed_mps, slip, phase (object), cycle (int).
    """
    segs = []  # (n, V array, s array, phase, cycle)
    v_prev, s_prev = 0.0, 0.0

    def seg(T, vfun, sfun, phase, cycle):
        n = max(int(round(T / dt)), 2)
        u = np.arange(n) / n
        segs.append((vfun(u), sfun(u), np.full(n, phase, dtype=object), np.full(n, cycle)))

    total = 0.0
    c = 0
    want_cycles = n_cycles if duration_s is None else 10**6
    standstill_next = True
    while c < want_cycles:
        t_cycle = 0.0
        s_roll = rng.uniform(0.03, 0.06)
        if standstill_next:
            T = rng.uniform(2.0, 4.0)
            seg(T, lambda u: np.zeros_like(u), lambda u: np.zeros_like(u), "standstill", -1)
            t_cycle += T
            v0 = rng.uniform(0.7, 1.2)
            T = rng.uniform(2.0, 3.0)
            seg(T, lambda u, v0=v0: v0 * _smoothstep(u), lambda u, s=s_roll: np.full_like(u, s), "other", -1)
            t_cycle += T
            v_prev, s_prev = v0, s_roll
        else:
            T = rng.uniform(1.0, 2.0)
            vp, sp = v_prev, s_prev
            seg(T, lambda u, vp=vp: np.full_like(u, vp),
                lambda u, sp=sp, s=s_roll: sp + (s - sp) * _smoothstep(2 * u), "other", -1)
            t_cycle += T
            s_prev = s_roll
        # acceleration: slip sweep 0 -> ~0.9 -> 0, V rises mostly once traction returns
        T = rng.uniform(7.0, 10.0)
        s_max = rng.uniform(0.85, 0.92)
        v_end = rng.uniform(3.0, 4.5)
        va, sa = v_prev, s_prev
        seg(T, lambda u, va=va, vb=v_end: va + (vb - va) * _smoothstep((u - 0.25) / 0.75),
            lambda u, sa=sa, sm=s_max: sa + (sm - sa) * np.sin(np.pi * u) ** 1.3, "accel", c)
        t_cycle += T
        # short cruise
        T = rng.uniform(0.5, 1.5)
        seg(T, lambda u, v=v_end: np.full_like(u, v), lambda u, s=sa: np.full_like(u, s), "other", -1)
        t_cycle += T
        # braking (skid: negative slip), to standstill or a crawl
        c += 1
        last = c >= want_cycles
        standstill_next = last or rng.random() < 0.5
        v_stop = 0.0 if standstill_next else rng.uniform(0.8, 1.4)
        T = rng.uniform(3.0, 5.0)
        s_br = rng.uniform(0.1, 0.35)
        seg(T, lambda u, vb=v_end, vs=v_stop: vb + (vs - vb) * _smoothstep(u),
            lambda u, s0=sa, sb=s_br: s0 * (1 - _smoothstep(3 * u)) - sb * np.sin(np.pi * u) ** 2,
            "brake", -1)
        t_cycle += T
        v_prev, s_prev = v_stop, 0.0
        total += t_cycle
        if duration_s is not None and total >= duration_s:
            break  # the logger is stopped at duration_s, wherever the driver is
    if duration_s is None:  # final standstill
        seg(2.0, lambda u: np.zeros_like(u), lambda u: np.zeros_like(u), "standstill", -1)
    speed = np.concatenate([s[0] for s in segs])
    slip = np.concatenate([s[1] for s in segs])
    phase = np.concatenate([s[2] for s in segs])
    cycle = np.concatenate([s[3] for s in segs]).astype(int)
    if duration_s is not None:
        n = int(round(duration_s / dt))
        speed, slip, phase, cycle = speed[:n], slip[:n], phase[:n], cycle[:n]
    return speed, slip, phase, cycle


# ----------------------------------------------------------------- hidden effect
def draw_effect_params(effect: str, terrain, rng: np.random.Generator, *, wheel=None,
                       load_n: float = 11000.0, given: Mapping[str, float] | None = None) -> dict[str, float]:
    """Random coefficients of a hidden effect in realistic ranges.

    ``vasilev`` H [m], ``lyasko`` m1, m2, ``ding`` n1 (ranges in PARAM_RANGES,
    clipped to the model core's Param bounds); ``terrain_mismatch`` the true
    ``K`` [m] and ``phi_deg`` [deg]; ``none`` no parameters. Values in
    ``given`` are kept. Slip-sinkage draws are repeated (up to 100 times)
    until the sinkage at s = 0.93 and 1.15 x ``load_n`` [N] stays below 0.85 r
    of ``wheel`` (default DEFAULT_WHEEL), so the wheel does not bury itself.
    Raises ValueError for an unknown effect.
    """
    given = dict(given or {})
    if effect == "none":
        return {}
    if effect == "terrain_mismatch":
        lo, hi = MISMATCH_K_FACTORS[int(rng.integers(2))]
        k_factor = math.exp(rng.uniform(math.log(lo), math.log(hi)))
        dphi = rng.uniform(*MISMATCH_PHI_DELTA_DEG) * (1 if rng.random() < 0.5 else -1)
        return {"K": terrain.K * k_factor, "phi_deg": math.degrees(terrain.phi) + dphi, **given}
    if effect not in PARAM_RANGES:
        raise ValueError(f"unknown effect {effect!r}; choose one of {', '.join(EFFECTS)}")
    from wheelsoil.model import DEFAULT_WHEEL, get_model

    wheel = wheel or DEFAULT_WHEEL
    model = get_model(effect)
    if set(PARAM_RANGES[effect]) <= set(given):
        return given
    bounds = {p.name: (p.lower, p.upper) for p in model.params}
    out: dict[str, float] = {}
    for _ in range(100):
        out = {}
        for name, (lo, hi) in PARAM_RANGES[effect].items():
            blo, bhi = bounds.get(name, (lo, hi))
            out[name] = float(rng.uniform(max(lo, blo), min(hi, bhi)))
        out.update(given)
        try:
            z = model.predict(terrain, wheel, np.full(2, 1.15 * load_n), np.array([0.5, 0.93]), out).sinkage_m
        except ValueError:
            continue
        if np.all(z < 0.85 * wheel.radius):
            return out
    raise ValueError(f"{effect}: no coefficients with a sinkage below 0.85 r found for "
                     f"{terrain.name} at {1.15 * load_n:.0f} N (given {given})")


def _check_params(effect: str, params: Mapping[str, float]) -> None:
    if effect == "none":
        if params:
            raise ValueError("effect 'none' takes no --param")
        return
    if effect == "terrain_mismatch":
        allowed = {"K", "phi_deg"}
    else:
        from wheelsoil.model import get_model

        allowed = {p.name for p in get_model(effect).params}
    bad = set(params) - allowed
    if bad:
        raise ValueError(f"effect {effect!r} has no parameter(s) {sorted(bad)}; known: {sorted(allowed)}")


def true_forces(terrain, wheel, effect: str, params: Mapping[str, float], load_n, slip):
    """Dp, T, z of the true soil for drive phases, arrays (N,) in, WheelForces out.

    ``none``/``terrain_mismatch``: Wong's model (Eqs. 1-10) on ``terrain`` (for a
    mismatch pass the true terrain); slip-sinkage effects: the model core's
    ``vasilev``/``lyasko``/``ding`` (Eqs. 11-13) with ``params``.
    """
    from wheelsoil.model import get_model

    name = effect if effect in PARAM_RANGES else "wong"
    model = get_model(name)
    return model.predict(terrain, wheel, np.asarray(load_n, float), np.asarray(slip, float),
                         dict(params) if name != "wong" else None)


# ------------------------------------------------------------------- simulation
def simulate_run(
    terrain,
    *,
    effect: str = "none",
    params: Mapping[str, float] | None = None,
    wheel=None,
    added_load_n: float = 3000.0,
    gnss_latency_s: float = 0.1,
    drop_rate: float = 0.0,
    seed: int = 0,
    duration_s: float | None = None,
    n_cycles: int = 6,
    soil_variability: float = 0.03,
    usb_batching_s: float = 0.0,
) -> SimulatedRun:
    """Simulate one field run of the instrumented left-rear wheel (paper section 2.2).

    Parameters
    ----------
    terrain : wheelsoil.model.Terrain
        The named (laboratory) terrain; with ``effect="terrain_mismatch"`` the
        true soil differs from it in K and phi.
    effect : str
        Hidden effect, one of :data:`EFFECTS`.
    params : mapping, optional
        Coefficients of the effect (H; m1, m2; n1; K [m], phi_deg [deg]);
        missing ones are drawn at random in realistic ranges
        (:func:`draw_effect_params`).
    wheel : wheelsoil.model.Wheel, optional
        Default ``DEFAULT_WHEEL`` (r = 0.47 m, b = 0.32 m).
    added_load_n : float
        Load added to the 8 kN static wheel load [N] (paper: 3 kN clay, 5 kN sand).
    gnss_latency_s : float
        Receiver latency of the GNSS speed/velocity messages [s] (0 .. 1).
    drop_rate : float
        Probability that a WFT sample's three frames are all lost (0 .. 0.5).
    seed : int
        Seeds every random choice; same seed, same frames.
    duration_s : float, optional
        Run length [s] (at least 30 s); cycles are added to fill it. Default:
        ``n_cycles`` accelerate-brake cycles.
    n_cycles : int
        Number of accelerate-brake cycles when ``duration_s`` is None.
    soil_variability : float
        Relative sd of the soil's c, kc, kphi along the track (spatial random
        field, correlation length 3 m; 0 .. 0.2, default 0.03): the field's
        soil is never the lab sample.
    usb_batching_s : float
        0 (default): the host stamps every frame on receipt with a small
        exponential jitter (mean 0.15 ms), as a PCIe/SocketCAN adapter does.
        > 0 (e.g. 0.001): a USB adapter that delivers frames in batches every
        ``usb_batching_s`` seconds, all frames of a batch stamped within a few
        microseconds of each other (0 .. 0.02 s).

    Returns
    -------
    SimulatedRun

    Raises
    ------
    ValueError
        Unknown effect or parameter, out-of-range latency/drop rate/duration.
    """
    import pandas as pd

    from wheelsoil.model import DEFAULT_WHEEL

    if effect not in EFFECTS:
        raise ValueError(f"unknown effect {effect!r}; choose one of {', '.join(EFFECTS)}")
    if not 0.0 <= gnss_latency_s <= 1.0:
        raise ValueError(f"gnss_latency_s={gnss_latency_s} outside 0..1 s")
    if not 0.0 <= drop_rate <= 0.5:
        raise ValueError(f"drop_rate={drop_rate} outside 0..0.5")
    if duration_s is not None and duration_s < 30.0:
        raise ValueError(f"duration_s={duration_s} is too short: at least 30 s (one accelerate-brake cycle)")
    if duration_s is None and n_cycles < 1:
        raise ValueError("n_cycles must be at least 1")
    if not 0.0 <= usb_batching_s <= 0.02:
        raise ValueError(f"usb_batching_s={usb_batching_s} outside 0..0.02 s")
    if not 0.0 <= soil_variability <= 0.2:
        raise ValueError(f"soil_variability={soil_variability} outside 0..0.2")
    if added_load_n < 0 or added_load_n > 15000:
        raise ValueError(f"added_load_n={added_load_n} outside 0..15000 N")
    wheel = wheel or DEFAULT_WHEEL
    r = float(wheel.radius)
    rng = np.random.default_rng(seed)

    # -- hidden effect
    params = dict(params or {})
    _check_params(effect, params)
    drawn = draw_effect_params(effect, terrain, rng, wheel=wheel, load_n=STATIC_LOAD_N + added_load_n,
                               given=params)
    params = {**drawn, **params}
    terrain_true = terrain
    if effect == "terrain_mismatch":
        terrain_true = terrain.replace(K=float(params["K"]), phi=math.radians(float(params["phi_deg"])))

    # -- kinematics on the WFT's 500 Hz grid (host time)
    dt = 1.0 / WFT_RATE_HZ
    speed, slip_plan, phase, cycle = _drive_profile(rng, dt, n_cycles, duration_s, r)
    n = len(speed)
    moving = speed > 0.05
    slip = slip_plan + np.where(moving, _bandlimited(rng, n, dt, 0.2, 3.0, 0.008), 0.0)
    slip = np.clip(slip, -0.6, 0.93)
    # keep the wheel speed below the WSS range (655 rpm)
    omega_max = 600.0 * 2 * np.pi / 60
    slip = np.minimum(slip, 1.0 - speed / (r * omega_max))
    omega = speed / (r * (1.0 - slip))
    accel_mps2 = np.gradient(speed, dt)

    # -- wheel load: static + added + pitch (load transfer, body pitch mode) + bumps
    from scipy import signal

    wn, zeta = 2 * np.pi * 1.4, 0.35  # body pitch mode
    b, a = signal.bilinear([wn**2], [1, 2 * zeta * wn, wn**2], fs=WFT_RATE_HZ)
    transfer = signal.lfilter(b, a, 520.0 * accel_mps2)  # N per m/s^2 to the rear wheel
    bumps = _bandlimited(rng, n, dt, 0.5, 8.0, 1.0) * 0.025 * (STATIC_LOAD_N + added_load_n)
    load = STATIC_LOAD_N + added_load_n + transfer + bumps * _smoothstep(speed / 1.0)
    load = np.maximum(load, 0.3 * STATIC_LOAD_N)

    # -- soil forces: the model with the hidden effect while driving (s >= 0)
    # Soil variability along the track: c, kc and kphi of the true soil scaled by
    # a spatial random field (correlation length ~3 m, relative sd soil_variability),
    # evaluated on a few factor levels to keep the model calls few.
    s_drive = np.clip(slip, 0.0, 0.93)
    distance = np.cumsum(speed) * dt
    soil_factor = 1.0 + _spatial_field(rng, distance, 3.0, soil_variability)
    levels = np.round(soil_factor / 0.005) * 0.005
    dp = np.empty(n)
    torque = np.empty(n)
    sinkage = np.empty(n)
    for lev in np.unique(levels):
        sel = levels == lev
        t_here = terrain_true.replace(c=terrain_true.c * lev, kc=terrain_true.kc * lev, kphi=terrain_true.kphi * lev)
        f = true_forces(t_here, wheel, effect, params, load[sel], s_drive[sel])
        dp[sel], torque[sel], sinkage[sel] = f.drawbar_pull_n, f.torque_nm, f.sinkage_m
    # braking (s < 0): not what the model is for; blend from the model's
    # forces at s = 0 into a brake-slip curve (rolling resistance 6 % of W
    # plus a skid force saturating at 0.45 W), torque r times the brake force
    brake_w = _smoothstep(-slip / 0.05)
    mu_brake = 0.45 * (1.0 - np.exp(np.minimum(slip, 0.0) / 0.08))  # >= 0
    dp_brake = -(0.06 + mu_brake) * load
    t_brake = -r * mu_brake * load
    dp = (1 - brake_w) * dp + brake_w * dp_brake
    torque = (1 - brake_w) * torque + brake_w * t_brake
    # standstill: brakes held, no soil forces; the drive forces build up over the
    # first centimetres per second of a pull-away (below the speed where slip is defined)
    w_move = _smoothstep(speed / 0.05)
    dp *= w_move
    torque *= w_move

    # -- wheel angle (encoder) by integrating omega
    angle_rad = np.cumsum(omega) * dt + rng.uniform(0, 2 * np.pi)
    angle_deg = np.degrees(angle_rad) % 360.0

    # -- host clock and GPS clock
    start_s = 1765416600 + int(seed % 5000) * 3607 + rng.uniform(0, 1)  # a December morning, seeded
    t_rel = np.arange(n) * dt
    gps_offset_s = float(rng.uniform(-2.0, 2.0))       # GPS - (host UTC + leap) at the start
    gps_drift = float(rng.uniform(-30e-6, 30e-6))      # host clock rate error
    dbs = _dbc_databases()
    frames_wft = _wft_frames(dbs["wft"], rng, t_rel, load, dp, torque, angle_rad, angle_deg, drop_rate)
    frames_veh = _vehicle_bus_frames(dbs, rng, t_rel, speed, omega, slip, r, gnss_latency_s,
                                     start_s, gps_offset_s, gps_drift)
    start_ns = int(round(start_s * 1e9))
    frames = {}
    for bus, parts in ((BUS_WFT, frames_wft), (BUS_VEH, frames_veh)):
        # frames leave the bus in transmit order; the host stamps them on receipt
        # (adapter/USB latency: jitter), never out of order
        ts = np.concatenate([p[0] for p in parts])
        order = np.argsort(ts, kind="stable")
        ts = ts[order]
        if usb_batching_s > 0:  # delivered at the next USB poll, stamped in a burst
            phase = rng.uniform(0, usb_batching_s)
            poll = np.ceil((ts - phase) / usb_batching_s) * usb_batching_s + phase
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
    truth = pd.DataFrame({
        "t_s": (start_ns + np.round(t_rel * 1e9).astype(np.int64) - first) * 1e-9,
        "t_host_ns": start_ns + np.round(t_rel * 1e9).astype(np.int64),
        "slip": np.where(moving, slip, np.nan),
        "load_n": load,
        "drawbar_pull_n": dp,
        "torque_nm": torque,
        "sinkage_m": sinkage,
        "speed_mps": speed,
        "omega_radps": omega,
        "wheel_angle_deg": angle_deg,
        "phase": phase,
        "cycle": cycle,
    })
    lost = int(frames_wft[0][5]) if len(frames_wft[0]) > 5 else 0
    info = {
        "schema": "wheelsoil.simtruth/1",
        "effect": effect,
        "params": {k: float(v) for k, v in params.items()},
        "terrain_named": _terrain_dict(terrain),
        "terrain_true": _terrain_dict(terrain_true),
        "wheel": {"radius_m": r, "width_m": float(wheel.width)},
        "static_load_n": STATIC_LOAD_N,
        "added_load_n": float(added_load_n),
        "gnss_latency_s": float(gnss_latency_s),
        "gps_clock_offset_s": gps_offset_s,
        "gps_clock_drift": gps_drift,
        "gps_leap_s": GPS_LEAP_S,
        "drop_rate": float(drop_rate),
        "soil_variability": float(soil_variability),
        "usb_batching_s": float(usb_batching_s),
        "lost_wft_samples": lost,
        "seed": int(seed),
        "duration_s": float(n * dt),
        "n_cycles": int(cycle.max() + 1) if n else 0,
        "start_unix_ns": first,
    }
    return SimulatedRun(truth=truth, frames=frames, info=info, start_ns=first, wheel=wheel, terrain_lab=terrain)


def _terrain_dict(t) -> dict[str, Any]:
    return {"name": t.name, "c_pa": float(t.c), "phi_deg": math.degrees(t.phi), "K_m": float(t.K),
            "n": float(t.n), "kc": float(t.kc), "kphi": float(t.kphi)}


def _jitter(rng, n, mean_s=150e-6):
    """Host receive-time jitter [s] (USB adapter buffering), exponential, (n,)."""
    return rng.exponential(mean_s, n)


def _wft_frames(db, rng, t_rel, load, dp, torque, angle_rad, angle_deg, drop_rate):
    """The WFT's 500 Hz Force/Moment/Angle frames plus 1 Hz Diag mux frames on can0.

    Hub forces (Dp, W) are rotated into the wheel-fixed frame by inverting
    hardware.md's hub-from-wheel formula: Fx_w = Fx cos a - Fz sin a,
    Fz_w = Fx sin a + Fz cos a. Returns a list of parts (t [s], id, ext, dlc,
    data), the first one carrying the number of lost samples as a 6th item.
    """
    n = len(t_rel)
    m_force = db.get_message_by_name("WFT_RL_Force")
    m_moment = db.get_message_by_name("WFT_RL_Moment")
    m_angle = db.get_message_by_name("WFT_RL_Angle")
    m_diag = db.get_message_by_name("WFT_RL_Diag")
    ca, sa = np.cos(angle_rad), np.sin(angle_rad)
    fx_w = dp * ca - load * sa + rng.normal(0, WFT_FORCE_NOISE_N, n)
    fz_w = dp * sa + load * ca + rng.normal(0, WFT_FORCE_NOISE_N, n)
    fy_w = 150.0 * _bandlimited(rng, n, t_rel[1] - t_rel[0], 0.2, 5.0, 1.0) + rng.normal(0, WFT_FORCE_NOISE_N, n)
    my = torque + rng.normal(0, WFT_MOMENT_NOISE_NM, n)
    mx_w = -0.05 * fy_w + rng.normal(0, WFT_MOMENT_NOISE_NM, n)
    mz_w = rng.normal(0, WFT_MOMENT_NOISE_NM, n) + 0.02 * dp
    counter = (np.arange(n) + int(rng.integers(256))) % 256
    f_data, sat_f = pack_signals(m_force, {"Fx_w": fx_w, "Fy_w": fy_w, "Fz_w": fz_w, "Counter": counter}, n)
    m_data, sat_m = pack_signals(m_moment, {"Mx_w": mx_w, "My": my, "Mz_w": mz_w, "Counter": counter}, n)
    a_data, _ = pack_signals(m_angle, {"WheelAngle": angle_deg, "Counter": counter}, n)
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


def _vehicle_bus_frames(dbs, rng, t_rel, speed, omega, slip, r, latency_s, start_s, gps_offset_s, gps_drift):
    """can1: wheel speeds (100 Hz), WSS status (10 Hz), GNSS speed/velocity/time (20 Hz), GPS status (1 Hz).

    Front wheels roll freely (r*omega_f ~ V, small rolling slip), the right
    rear is driven like the left rear; GNSS velocities are of the fix epoch
    and arrive ``latency_s`` later; ``RT_SB_GPS_Time`` carries the fix's GPS
    week and time of week on the GPS clock (host clock + offset + drift).
    """
    dt = t_rel[1] - t_rel[0]
    duration = t_rel[-1]
    wss, gps = dbs["wheel_speed"], dbs["gps_rt_speedbox"]
    parts = []
    # --- wheel speed module
    m_ws = wss.get_message_by_name("WSS_WheelSpeeds")
    m_st = wss.get_message_by_name("WSS_Status")
    t_w = np.arange(rng.uniform(0, 0.01), duration, 1.0 / WSS_RATE_HZ)
    nw = len(t_w)
    v_w = np.interp(t_w, t_rel, speed)
    s_w = np.interp(t_w, t_rel, slip)
    om_rl = np.interp(t_w, t_rel, omega)
    s_front = np.where(s_w < 0, 0.4 * s_w, -0.008) + rng.normal(0, 0.002, nw)
    rr_factor = rng.uniform(0.85, 1.1)
    s_rr = np.clip(np.where(s_w > 0, s_w * rr_factor, s_w), -0.6, 0.93)
    om_f = v_w / (r * (1 - s_front))
    om_rr = v_w / (r * (1 - s_rr))

    def rpm(om):
        noisy = om * (1 + rng.normal(0, WSS_NOISE_REL, nw)) + rng.normal(0, 0.005, nw)
        return np.abs(noisy) * 60.0 / (2 * np.pi)

    data, _ = pack_signals(m_ws, {"WheelSpeed_FL": rpm(om_f), "WheelSpeed_FR": rpm(om_f * 1.002),
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
def logger_metadata(run: SimulatedRun, path) -> dict[str, str]:
    """The recording facts ``wheelsoil log`` writes (start time, host, command, bus specs), nothing else.

    The start time is just before the first frame's receive time; the host is
    the vehicle's logging PC. Nothing about the simulation or its hidden effect.
    """
    import time as _time

    start_ns = run.start_ns - 180_000_000  # logger start, just before the first frame
    buses = sorted(run.frames)
    return {
        "start_time_ns": str(start_ns),
        "start_time_utc": _time.strftime("%Y-%m-%dT%H:%M:%SZ", _time.gmtime(start_ns / 1e9)),
        "host": "wft-logger",
        "command": "wheelsoil log " + " ".join(f"--bus socketcan:{b}" for b in buses) + f" -o {Path(path).name}",
        "bus_specs": " ".join(f"{b}=socketcan:{b}" for b in buses),
        "file_index": "1",
    }


def _write_mcap(run: SimulatedRun, path: Path, config=None) -> None:
    """Write ``run`` as ``wheelsoil log`` does: frame batches per bus every
    ``wheelsoil.daq.logger.BATCH_INTERVAL_S`` in receive order, a logger status
    record every second, the summary counters on close."""
    from wheelsoil.daq import RecordingWriter, load_vehicle_config
    from wheelsoil.daq.stats import StatsAccumulator

    try:
        from wheelsoil.daq.logger import BATCH_INTERVAL_S
    except ImportError:  # pragma: no cover - older daq
        BATCH_INTERVAL_S = 0.1
    config = config or load_vehicle_config()
    batches = run.frame_batches()
    acc = StatsAccumulator(config)
    t_end = max(int(b.timestamp_ns[-1]) for b in batches.values() if len(b)) + 1
    step = int(round(BATCH_INTERVAL_S * 1e9))
    per_status = max(1, int(round(1.0 / BATCH_INTERVAL_S)))
    edges = np.arange(run.start_ns, t_end + step, step, dtype=np.int64)
    cuts = {bus: np.searchsorted(b.timestamp_ns, edges) for bus, b in batches.items()}
    prev_frames = {bus: 0 for bus in batches}
    t0 = run.start_ns - 180_000_000

    def status(w, t_ns, dt_s):
        st = acc.stats
        buses = {}
        for bus in sorted(batches):
            names = set(st.names.get(bus, {}).values())
            n = st.frames.get(bus, 0)
            buses[bus] = {
                "frames": n, "fps": round((n - prev_frames[bus]) / dt_s, 1),
                "lost_wft_frames": int(sum(v for k, v in st.lost_frames.items() if k in names)),
                "error_frames": st.error_frames.get(bus, 0), "bus_errors": 0, "rx_dropped": 0,
                "unknown_id_frames": sum(st.unknown_ids.get(bus, {}).values()),
                "dlc_mismatch_frames": sum(st.dlc_mismatch.get(bus, {}).values()), "queued": 0,
            }
            prev_frames[bus] = n
        return {"elapsed_s": round((t_ns - t0) * 1e-9, 3), "file": Path(path).name, "file_bytes": w.file_size(),
                "files": 1, "bad_frames": 0, "last_error": "", "buses": buses}

    with RecordingWriter(path, config=config, metadata=logger_metadata(run, path)) as writer:
        for bus in sorted(batches):
            writer.add_bus(bus, interface="socketcan", channel=bus)
        for w in range(len(edges) - 1):
            for bus in sorted(batches):
                lo, hi = cuts[bus][w], cuts[bus][w + 1]
                if hi > lo:
                    part = batches[bus].select(slice(lo, hi))
                    writer.write_batch(part)
                    acc.update(part)
            if (w + 1) % per_status == 0:
                writer.write_status(status(writer, int(edges[w + 1]), per_status * BATCH_INTERVAL_S),
                                    time_ns=int(edges[w + 1]))
        st = acc.stats
        last = status(writer, t_end, max(((len(edges) - 1) % per_status) * BATCH_INTERVAL_S, BATCH_INTERVAL_S))
        writer.summary.update({
            "end_time_ns": str(t_end + 120_000_000),  # the logger stops just after the last frame
            "lost_frames": {k: int(v) for k, v in st.lost_frames.items()},
            "rx_dropped": {b: 0 for b in batches}, "error_frames": {b: st.error_frames.get(b, 0) for b in batches},
            "bus_errors": {b: 0 for b in batches}, "bad_frames": 0, "logger_status": last,
        })
        writer.write_status(last, time_ns=t_end)


def write_simulation(run: SimulatedRun, path, *, config=None) -> Path:
    """Write a simulated run as a recording, the format chosen by the suffix.

    ``.mcap``: through ``wheelsoil.daq.RecordingWriter`` with the vehicle
    configuration (default: the shipped one), laid out as ``wheelsoil log``
    writes it (frame batches per bus at the logger's batch interval, a status
    record per second, logger metadata). ``.log`` (candump -L), ``.asc``, ``.blf``, ``.trc``:
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
    with can.Logger(str(path)) as logger:
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
    return path


def write_truth(run: SimulatedRun, path) -> Path:
    """Write the hidden truth (effect, params, terrain used, latency, clock offset, seed) as JSON."""
    path = Path(path)
    path.write_text(json.dumps(run.info, indent=2) + "\n", encoding="utf-8")
    return path


# ------------------------------------------------------------------ verification
#: Diagnosis verdict expected for each hidden effect (report.json ``diagnosis.effect``).
EXPECTED_VERDICT = {"none": "none", "vasilev": "slip_sinkage", "lyasko": "slip_sinkage",
                    "ding": "slip_sinkage", "terrain_mismatch": "terrain_mismatch"}


def draw_case(seed: int) -> dict[str, Any]:
    """A hidden-effect test case drawn at random from ``seed``.

    Returns a dict of :func:`simulate_run` keyword arguments plus ``terrain``
    (``clay`` +3 kN or ``sand`` +5 kN, as in the paper): ``effect`` uniform over
    :data:`EFFECTS` (coefficients then drawn by the simulator), GNSS latency
    0.03-0.2 s, drop rate 0-1 %, ``seed``.
    """
    rng = np.random.default_rng([int(seed), 20141211])
    effect = str(EFFECTS[int(rng.integers(len(EFFECTS)))])
    terrain = "clay" if rng.random() < 0.5 else "sand"
    return {
        "terrain": terrain, "effect": effect, "added_load_n": 3000.0 if terrain == "clay" else 5000.0,
        "gnss_latency_s": float(rng.uniform(0.03, 0.2)), "drop_rate": float(rng.uniform(0.0, 0.01)),
        "seed": int(seed),
    }


def judge(truth: Mapping[str, Any], report: Mapping[str, Any], *, k_sigma: float = 3.0,
          rel_floor: float = 0.03) -> dict[str, Any]:
    """Compare a fit report (``report.json``, schema wheelsoil.report/1) with the hidden truth.

    Checks: the verdict (``diagnosis.effect``) is the expected one
    (:data:`EXPECTED_VERDICT`); for slip sinkage the chosen form is the true
    one, or the report says the true form is indistinguishable from it; the
    fitted coefficients of the true form (or K, phi of ``terrain_mismatch``)
    are within ``k_sigma`` standard errors of the truth, the standard error
    floored at ``rel_floor`` x |true value| (processing and soil variability
    bias the estimates beyond the purely statistical error; the z-scores with
    the bare standard errors are returned too); an effect gives a positive
    out-of-sample gain (``cv_R0_n_after < cv_R0_n_before``).

    Returns a dict: ``expected``, ``verdict``, ``model``, ``effect_ok``,
    ``form_ok``, ``params_ok``, ``param_z`` (bare), ``param_z_floored``,
    ``gain_ok``, ``latency_error_s``, ``ok`` (all checks), ``miss``
    (``None``, ``"unexplained"`` or ``"wrong cause"``).
    """
    effect = truth["effect"]
    expected = EXPECTED_VERDICT[effect]
    diag = report.get("diagnosis", {})
    verdict = diag.get("effect")
    model = diag.get("model")
    out: dict[str, Any] = {"expected": expected, "verdict": verdict, "model": model,
                           "effect_ok": verdict == expected}
    form_ok = True
    if effect in PARAM_RANGES and verdict == "slip_sinkage":
        tied = set(diag.get("indistinguishable_forms") or [])
        form_ok = model == effect or (effect in tied and not diag.get("forms_distinguishable"))
    out["form_ok"] = form_ok
    # coefficients of the true form
    z_bare, z_floor = {}, {}
    if effect in PARAM_RANGES or effect == "terrain_mismatch":
        fit = report.get("models", {}).get(effect, {})
        true = dict(truth["params"])
        if effect == "terrain_mismatch":
            true = {"K": true["K"], "phi": math.radians(true["phi_deg"])}
        for name, tv in true.items():
            fv = (fit.get("params") or {}).get(name)
            se = (fit.get("stderr") or {}).get(name)
            if fv is None or se is None or not np.isfinite(se):
                z_bare[name] = z_floor[name] = float("inf")
                continue
            z_bare[name] = abs(fv - tv) / max(se, 1e-300)
            z_floor[name] = abs(fv - tv) / max(se, rel_floor * abs(tv))
    out["param_z"] = z_bare
    out["param_z_floored"] = z_floor
    # with tied forms (highly correlated m1, m2) only the chosen form's curve is pinned down
    check_params = effect == "terrain_mismatch" or (effect in PARAM_RANGES and model == effect)
    out["params_ok"] = (not check_params) or all(z <= k_sigma for z in z_floor.values())
    gain = report.get("gain") or {}
    if effect == "none":
        out["gain_ok"] = True
    else:
        before, after = gain.get("cv_R0_n_before"), gain.get("cv_R0_n_after")
        out["gain_ok"] = before is not None and after is not None and after < before
    lat = (report.get("time_sync") or {}).get("gnss_latency_s")
    out["latency_error_s"] = None if lat is None else float(lat) - float(truth["gnss_latency_s"])
    out["ok"] = bool(out["effect_ok"] and form_ok and out["params_ok"] and out["gain_ok"])
    out["miss"] = None if out["effect_ok"] else ("unexplained" if verdict == "unexplained" else "wrong cause")
    return out


# --------------------------------------------------------------------------- CLI
_EPILOG = """\
examples:
  wheelsoil simulate --terrain clay --effect lyasko -o run.mcap
  wheelsoil simulate --terrain sand --effect vasilev --param H=0.08 --added-load 5000 -o run.log
  wheelsoil simulate --terrain clay --effect terrain_mismatch --seed 4 --truth truth.json -o run.blf

The recording holds only what the vehicle's logger would record; the effect
and its coefficients go to --truth FILE, and only when asked.
effects: none (Wong), vasilev (H [m]), lyasko (m1, m2), ding (n1),
terrain_mismatch (K [m], phi_deg [deg] of the true soil). Coefficients not
given are drawn at random (seeded) in realistic ranges.
"""


def register(subparsers) -> None:
    """Add ``wheelsoil simulate`` to the CLI."""
    p = subparsers.add_parser(
        "simulate",
        help="simulate a field run (accelerate-brake cycles) as a recording with a hidden effect",
        description="Simulate the paper's accelerate-brake field runs of the instrumented left-rear "
        "wheel as raw CAN frames (WFT on can0; wheel speeds and GNSS on can1) with noise, DBC "
        "quantisation, timestamp jitter, a host/GPS clock offset, GNSS latency and lost frames.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--terrain", required=True, help="built-in terrain name (clay, sand, ...) or a terrain TOML file")
    p.add_argument("--effect", default="none", choices=EFFECTS, help="hidden effect (default none)")
    p.add_argument("--param", action="append", default=[], metavar="K=V",
                   help="coefficient of the effect, repeatable (e.g. m1=0.6); others drawn at random")
    p.add_argument("--added-load", type=float, default=None, metavar="N",
                   help="load added to the 8 kN static wheel load [N] (default 3000 for clay, 5000 for sand, else 3000)")
    p.add_argument("--gnss-latency", type=float, default=0.1, metavar="S", help="GNSS velocity latency [s] (default 0.1)")
    p.add_argument("--drop-rate", type=float, default=0.0, metavar="P",
                   help="probability of losing a WFT sample's frames (default 0)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--soil-variability", type=float, default=0.03, metavar="F",
                   help="relative sd of c, kc, kphi along the track (default 0.03; 0 = the lab soil everywhere)")
    p.add_argument("--usb-batching", type=float, default=0.0, metavar="S",
                   help="host timestamps of a USB adapter polled every S seconds, e.g. 0.001 (default 0: per frame)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="run length [s] (>= 30); default: --cycles accelerate-brake cycles")
    p.add_argument("--cycles", type=int, default=6, help="accelerate-brake cycles when no --duration (default 6)")
    p.add_argument("--wheel-radius", type=float, default=None, metavar="M",
                   help="wheel radius [m] (default 0.47; the recording carries the shipped vehicle "
                   "configuration, so fit such a run with the same --wheel-radius/--wheel-width)")
    p.add_argument("--wheel-width", type=float, default=None, metavar="M", help="wheel width [m] (default 0.32)")
    p.add_argument("--truth", default=None, metavar="FILE", help="also write the hidden truth to this JSON file")
    p.add_argument("-o", "--output", required=True, help="output: .mcap (like `wheelsoil log`) or .log/.asc/.blf/.trc")
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


OUTPUT_SUFFIXES = (".mcap", ".log", ".asc", ".blf", ".trc")


def _cmd_simulate(args) -> int:
    from wheelsoil.model import DEFAULT_WHEEL, Wheel, load_terrain

    if Path(args.output).suffix.lower() not in OUTPUT_SUFFIXES:
        raise ValueError(f"{args.output}: unknown output format {Path(args.output).suffix!r}; "
                         f"use {', '.join(OUTPUT_SUFFIXES)}")

    terrain = load_terrain(args.terrain)
    wheel = Wheel(args.wheel_radius or DEFAULT_WHEEL.radius, args.wheel_width or DEFAULT_WHEEL.width)
    added = args.added_load
    if added is None:
        added = 5000.0 if terrain.name.lower().startswith("sand") else 3000.0
    run = simulate_run(
        terrain, effect=args.effect, params=_parse_params(args.param), wheel=wheel, added_load_n=added,
        gnss_latency_s=args.gnss_latency, drop_rate=args.drop_rate, seed=args.seed,
        duration_s=args.duration, n_cycles=args.cycles, soil_variability=args.soil_variability,
        usb_batching_s=args.usb_batching,
    )
    out = write_simulation(run, args.output)
    per_bus = ", ".join(f"{b}: {len(f['timestamp_ns'])}" for b, f in sorted(run.frames.items()))
    print(f"wrote {out}: {run.duration_s:.1f} s, {run.n_frames} frames ({per_bus}), "
          f"{out.stat().st_size / 1e6:.2f} MB")
    if args.truth:
        write_truth(run, args.truth)
        print(f"hidden truth -> {args.truth}")
    return 0
