"""Small field-run simulator for the processing tests (known truth -> MCAP recording).

Truth on a 500 Hz grid: vehicle speed V, slip s (so omega = V / (r (1 - s))),
load W, drawbar pull Dp, torque T, all smooth (content below ~2 Hz). Frames
at the hardware rates (hardware.md), encoded one by one with cantools from
the shipped DBCs: WFT force/moment/angle at 500 Hz in the rotating frame
with a shared counter, wheel speeds at 100 Hz (free-rolling fronts),
GNSS velocity/speed/time at 20 Hz arriving ``latency_s`` late, with sensor
noise, host receive jitter and a GPS clock offset; written with
``wheelsoil.daq.RecordingWriter``. Options remove or damage parts for the
bad-input tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cantools
import numpy as np

from wheelsoil.daq import FrameBatch, RecordingWriter, load_vehicle_config

DBC = Path(__file__).resolve().parents[1] / "dbc"
R = 0.47
FORCE_NOISE_N = 30.0
MOMENT_NOISE_NM = 5.0
GPS_EPOCH_UNIX_S = 315_964_800
#: hardware.md: rim + tyre outboard of the WFT (and dbc/vehicle.toml's [vehicle] values).
WHEEL_MASS_KG = 80.0
WHEEL_INERTIA_KGM2 = 11.5


@dataclass
class Truth:
    t_s: np.ndarray  # (N,) host seconds since the first WFT sample
    speed_mps: np.ndarray
    slip: np.ndarray
    omega_radps: np.ndarray
    load_n: np.ndarray
    drawbar_pull_n: np.ndarray
    torque_nm: np.ndarray
    phase: np.ndarray
    radius_m: float = R


def _smooth(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)


def truth_profile(n_cycles: int = 3, dt: float = 0.002, *, standstill_s: float = 1.5,
                  radius_m: float = R) -> Truth:
    """Accelerate-brake cycles: standstill, accel (slip sweep 0.05->0.8->0.1), cruise, brake."""
    v_parts, s_parts, ph = [], [], []

    def seg(T, vf, sf, phase):
        u = np.arange(int(round(T / dt))) / round(T / dt)
        v_parts.append(vf(u))
        s_parts.append(sf(u))
        ph.append(np.full(u.size, phase, dtype=object))

    seg(standstill_s, lambda u: 0 * u, lambda u: 0 * u, "standstill")
    seg(2.0, lambda u: 1.0 * _smooth(u), lambda u: 0.05 + 0 * u, "other")
    v = 1.0
    for _ in range(n_cycles):
        vb = 3.5
        seg(8.0, lambda u, va=v, vb=vb: va + (vb - va) * _smooth((u - 0.2) / 0.8),
            lambda u: 0.05 + 0.75 * np.sin(np.pi * u) ** 2, "accel")
        seg(1.5, lambda u, vb=vb: vb + 0 * u, lambda u: 0.05 + 0 * u, "other")
        seg(4.0, lambda u, vb=vb: vb + (1.0 - vb) * _smooth(u),
            lambda u: 0.05 - 0.2 * np.sin(np.pi * u) ** 2, "brake")
        seg(1.0, lambda u: 1.0 + 0 * u, lambda u: 0.05 + 0 * u, "other")
        v = 1.0
    speed = np.concatenate(v_parts)
    slip = np.concatenate(s_parts)
    t = np.arange(speed.size) * dt
    omega = np.where(speed > 0, speed / (radius_m * (1 - slip)), 0.0)
    load = 11000.0 + 400.0 * np.sin(2 * np.pi * 0.3 * t) + 200.0 * np.sin(2 * np.pi * 1.1 * t)
    dp = load * (0.45 * (1 - np.exp(-np.maximum(slip, -0.5) / 0.15)) - 0.08)
    moving = _smooth(speed / 0.5)  # forces build up smoothly as the wheel starts rolling
    dp = dp * moving
    torque = radius_m * (dp + 0.1 * load) * moving
    return Truth(t, speed, slip, omega, load, dp, torque, np.concatenate(ph), radius_m)


def truth_dynamic(n_cycles: int = 3, dt: float = 0.002, *, mass_kg: float = 8000.0,
                  radius_m: float = R) -> Truth:
    """A run whose vehicle speed follows the soil forces (all wheels alike, as in a 4x4 with
    locked differentials): ``dV/dt = (4 Dp - 600 N) / mass_kg``; accelerate 6 s (slip sweep
    0.05 -> 0.5 -> 0.05), brake at slip -0.05 until V < 1.2 m/s, roll 1 s; from V = 1 m/s."""
    load0 = 11000.0
    v, t = 1.0, 0.0
    ts, vs, ss, ph = [], [], [], []

    def dp_of(s, load):
        return load * (0.45 * (1 - np.exp(-s / 0.15)) - 0.08)

    def step(s, phase):
        nonlocal v, t
        load = load0 + 400.0 * np.sin(2 * np.pi * 0.3 * t)
        ts.append(t), vs.append(v), ss.append(s), ph.append(phase)
        v = max(v + dt * (4 * dp_of(s, load) - 600.0) / mass_kg, 0.05)
        t += dt

    for _ in range(n_cycles):
        for u in np.arange(0, 1, dt / 6.0):
            step(0.05 + 0.45 * np.sin(np.pi * u) ** 2, "accel")
        k = 0
        while v > 1.2 or k < 250:
            step(-0.05 * min(k / 250, 1.0), "brake")
            k += 1
        for _ in range(500):
            step(0.02, "other")
    t_s, speed, slip = np.array(ts), np.array(vs), np.array(ss)
    load = load0 + 400.0 * np.sin(2 * np.pi * 0.3 * t_s)
    dp = dp_of(slip, load)
    omega = speed / (radius_m * (1 - slip))
    torque = radius_m * (dp + 0.1 * load)
    return Truth(t_s, speed, slip, omega, load, dp, torque, np.array(ph, dtype=object), radius_m)


def write_recording(path, truth: Truth, *, latency_s: float = 0.1, seed: int = 0,
                    gps_offset_s: float = 1234.5678, no_gnss: bool = False, no_wheel_speed: bool = False,
                    drop_wft_bursts: int = 0, counter_jumps: int = 0,
                    wheel_speed_zero: tuple[float, float] | None = None,
                    wheel_mass_kg: float = WHEEL_MASS_KG, wheel_inertia_kgm2: float = WHEEL_INERTIA_KGM2,
                    config=None, ts_edit=None, drop_wft_runs=(), drop_frames: dict | None = None,
                    burst_s: float = 0.0, fronts_coupled: bool = False, at_max: dict | None = None,
                    fx_w_gain: float = 1.0, fx_w_offset_n: float = 0.0, angle_jumps=(),
                    gnss_outages=(), wheel_speed_lag_s: float = 0.0, rl_lag_s: float = 0.0,
                    wheel_speed_pitch_rad: float = 0.0, fronts_undelayed: bool = False, grade: float = 0.0,
                    chatter: tuple[float, float, float, float] | None = None, rl_scale: float = 1.0,
                    fx_w_spikes=()) -> dict:
    """Encode ``truth`` as frames and write an MCAP recording.

    ``drop_wft_bursts``: that many runs of 1..12 lost WFT samples;
    ``counter_jumps``: that many random jumps of the WFT counter (all three
    messages) by 17..200 without lost time; ``wheel_speed_zero`` (t0, t1):
    the measured wheel's speed reads 0 rpm in that window.

    The WFT measures what the wheel assembly transmits (hardware.md):
    ``Fx = Dp - m_w dV/dt``, ``My = T + I_w domega/dt`` with ``wheel_mass_kg``,
    ``wheel_inertia_kgm2`` (0 for none); ``truth`` holds the soil's Dp and T.
    ``grade``: the track's grade (rise over run): truth's speed is along the ground, the GNSS 2D
    speed and the INS forward velocity horizontal (x cos), the 3D speed along the ground;
    ``config`` the VehicleConfig attached (default: the shipped one);
    ``ts_edit(bus, ts_ns) -> ts_ns`` edits a bus's int64 timestamps (in
    file order) before writing, for time-base tests (or returns ``(ts_ns,
    perm)`` to also reorder the frames: ``perm`` indexes the sorted frames); ``drop_wft_runs``
    ``[(t_s, n_samples), ...]`` removes runs of WFT samples (all three
    messages); ``drop_frames`` ``{message name: fraction}`` drops that share
    of a message's frames at random (no counter tells); ``burst_s`` > 0
    delivers each bus's frames in bursts: receive times rounded up to the
    next multiple of ``burst_s`` (as USB/UDP adapters do); ``fronts_coupled``:
    the front wheels turn with the measured one (all wheels driven, locked
    differentials) instead of rolling freely; ``at_max`` ``{signal name: (t0_s, t1_s)}``:
    ``Fx_w`` or ``WheelSpeed_RL`` reads its DBC maximum in that window (a clipped sensor, or
    the all-ones "not available" code); ``fx_w_gain``, ``fx_w_offset_n``: the rotating Fx_w
    bridge reads with that gain and offset (a calibration fault); ``angle_jumps`` ``[(t_s, deg), ...]``:
    the reported WheelAngle jumps by that much at t_s and keeps it (an encoder losing or gaining
    counts; the forces stay in the true rotating frame); ``gnss_outages`` ``[(t0_s, t1_s, drift_mps2), ...]``:
    the INS coasts through a GNSS outage, its velocity drifting by ``drift_mps2 (t - t0)``, still flagged
    valid, the accuracy figures 40 instead of 10; ``wheel_speed_lag_s``: every
    wheel speed is the speed that long before its frame (a module that reads late); ``rl_lag_s``:
    the measured (left-rear) wheel's channel alone lags that much more (a filter in its sensor);
    ``wheel_speed_pitch_rad``: every wheel speed lags ``pitch / omega`` more, at most 0.3 s in all
    (a module timing each wheel over its last tooth interval: one tooth period late); ``fronts_undelayed``:
    the front wheels' speeds carry neither delay (read by another module, in the same message); ``chatter``
    ``(t0_s, t1_s, amplitude, frequency_hz)``: the measured wheel's speed oscillates by that relative
    amplitude at that frequency in the window (a driveline oscillating; the forces do not follow it);
    ``rl_scale``: the measured wheel's speed reads that many times its true speed (a tone wheel's tooth
    count configured off: 48 teeth read as 50 is 0.96); ``fx_w_spikes`` ``[(t_s, size_n), ...]``: the
    Fx_w sample at t_s reads size_n more (an electrical glitch in one frame).

    Returns ``{"path", "lost_samples", "start_ns", "dropped_frames"}``
    (``dropped_frames``: message -> frames removed by ``drop_frames``).
    """
    rng = np.random.default_rng(seed)
    wft = cantools.database.load_file(str(DBC / "wft.dbc"))
    wss = cantools.database.load_file(str(DBC / "wheel_speed.dbc"))
    gps = cantools.database.load_file(str(DBC / "gps_rt_speedbox.dbc"))
    start_ns = 1_765_000_000_000_000_000
    t = truth.t_s
    n = t.size

    def jitter(k):
        return rng.exponential(1.5e-4, k)

    # ---- WFT, 500 Hz
    angle = np.cumsum(truth.omega_radps) * (t[1] - t[0])
    ca, sa = np.cos(angle), np.sin(angle)
    fx_hub = truth.drawbar_pull_n - wheel_mass_kg * np.gradient(truth.speed_mps, t)
    my_hub = truth.torque_nm + wheel_inertia_kgm2 * np.gradient(truth.omega_radps, t)
    fx_w = fx_hub * ca - truth.load_n * sa + rng.normal(0, FORCE_NOISE_N, n)
    fx_w = fx_w * fx_w_gain + fx_w_offset_n
    for t_spike, size in fx_w_spikes:
        fx_w[int(np.searchsorted(t, t_spike))] += size
    angle_rep = angle.copy()
    for t0, deg in angle_jumps:
        angle_rep[t >= t0] += np.radians(deg)
    at_max = at_max or {}
    if "Fx_w" in at_max:
        fx_w[(t >= at_max["Fx_w"][0]) & (t < at_max["Fx_w"][1])] = \
            wft.get_message_by_name("WFT_RL_Force").get_signal_by_name("Fx_w").maximum
    fz_w = fx_hub * sa + truth.load_n * ca + rng.normal(0, FORCE_NOISE_N, n)
    my = my_hub + rng.normal(0, MOMENT_NOISE_NM, n)
    counter = np.arange(n) % 256
    for j in rng.integers(100, n - 100, counter_jumps):
        counter[j:] = (counter[j:] + rng.integers(17, 200)) % 256
    keep = np.ones(n, bool)
    for j in rng.integers(100, n - 100, drop_wft_bursts):
        keep[j:j + rng.integers(1, 13)] = False
    for t_drop, k in drop_wft_runs:
        j = int(np.searchsorted(t, t_drop))
        keep[j:j + int(k)] = False
    m_f, m_m, m_a = (wft.get_message_by_name(x) for x in ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle"))
    can0 = []
    for i in np.flatnonzero(keep):
        c = int(counter[i])
        can0.append((t[i] + 1e-4, m_f, m_f.encode({"Fx_w": fx_w[i], "Fy_w": 0.0, "Fz_w": fz_w[i], "Counter": c,
                                                    "Status": 0}, strict=False)))
        can0.append((t[i] + 2.3e-4, m_m, m_m.encode({"Mx_w": 0.0, "My": my[i], "Mz_w": 0.0, "Counter": c,
                                                     "Status": 0}, strict=False)))
        can0.append((t[i] + 3.6e-4, m_a, m_a.encode({"WheelAngle": np.degrees(angle_rep[i]) % 360.0, "Counter": c,
                                                     "Status": 0}, strict=False)))
    m_d = wft.get_message_by_name("WFT_RL_Diag")  # multiplexed diagnostics, 1 Hz per mux value
    for sec in np.arange(0.0, t[-1], 1.0):
        can0.append((sec + 0.25, m_d, m_d.encode({"DiagMux": 0, "BridgeTemp": 21.5 + rng.normal(0, 0.1),
                                                   "SupplyVoltage": 13.8})))
        can0.append((sec + 0.5, m_d, m_d.encode({"DiagMux": 1, "SerialNumber": 140321})))
        can0.append((sec + 0.75, m_d, m_d.encode({"DiagMux": 2, "FirmwareMajor": 2, "FirmwareMinor": 7,
                                                  "CalibrationId": 1311})))
    # ---- wheel speeds, 100 Hz (Motorola, unsigned rpm), status 10 Hz
    can1 = []
    m_st = wss.get_message_by_name("WSS_Status")
    for k, tw in enumerate(np.arange(0.005, t[-1], 0.1)):
        can1.append((tw, m_st, m_st.encode({"RollingCounter": k % 16, "SensorFault_FL": 0, "SensorFault_FR": 0,
                                             "SensorFault_RL": 0, "SensorFault_RR": 0})))
    m_ws = wss.get_message_by_name("WSS_WheelSpeeds")
    if not no_wheel_speed:
        for tw in np.arange(0.003, t[-1], 0.01):
            def late(w):  # the per-tooth part of the delay at the wheel speed w [rad/s]
                return min(wheel_speed_pitch_rad / abs(w), 0.3 - wheel_speed_lag_s) if w else 0.0

            v = np.interp(tw - wheel_speed_lag_s, t, truth.speed_mps)
            v = np.interp(tw - wheel_speed_lag_s - late(v / truth.radius_m), t, truth.speed_mps)
            if fronts_undelayed:
                v = np.interp(tw, t, truth.speed_mps)
            om = np.interp(tw - wheel_speed_lag_s - rl_lag_s, t, truth.omega_radps)
            om = np.interp(tw - wheel_speed_lag_s - rl_lag_s - late(om), t, truth.omega_radps)
            if fronts_coupled:
                v = om * truth.radius_m
            if wheel_speed_zero and wheel_speed_zero[0] <= tw < wheel_speed_zero[1]:
                om = 0.0
            if chatter and chatter[0] <= tw < chatter[1]:
                om *= 1.0 + chatter[2] * np.sin(2 * np.pi * chatter[3] * tw)
            rpm = lambda w: float(np.clip(abs(w * (1 + rng.normal(0, 0.002))) * 60 / (2 * np.pi), 0, 655))
            rl = rpm(om) * rl_scale
            if "WheelSpeed_RL" in at_max and at_max["WheelSpeed_RL"][0] <= tw < at_max["WheelSpeed_RL"][1]:
                rl = m_ws.get_signal_by_name("WheelSpeed_RL").maximum
            can1.append((tw, m_ws, m_ws.encode({"WheelSpeed_FL": rpm(v / truth.radius_m),
                                                 "WheelSpeed_FR": rpm(v / truth.radius_m),
                                                 "WheelSpeed_RL": rl, "WheelSpeed_RR": rpm(om)})))
    # ---- GNSS, 20 Hz fixes on the GPS clock, received latency_s later
    if not no_gnss:
        m_v = gps.get_message_by_name("RT_SB_INS_Vel_Body_Axes")
        m_s = gps.get_message_by_name("RT_SB_GPS_Speed")
        m_t = gps.get_message_by_name("RT_SB_GPS_Time")
        gps0 = start_ns * 1e-9 - GPS_EPOCH_UNIX_S + gps_offset_s
        first = np.ceil(gps0 * 20) / 20
        for gfix in np.arange(first, gps0 + t[-1] - 0.3, 0.05):
            tf = gfix - gps0  # host time of the fix
            v = float(np.interp(tf, t, truth.speed_mps))
            rx = tf + latency_s + abs(rng.normal(0, 5e-4))
            vel = v + rng.normal(0, 0.01)
            acc = 10
            for t0, t1, drift in gnss_outages:
                if t0 <= tf < t1:
                    vel, acc = vel + drift * (tf - t0), 40
            vel, vel_3d = vel * math.cos(math.atan(grade)), vel
            can1.append((rx, m_s, m_s.encode({"GPS_Speed_2D": abs(vel), "GPS_Speed_3D": abs(vel_3d),
                                               "Accuracy_GPS_Speed": acc, "Validity_GPS_Speed_2D": 1,
                                               "Validity_GPS_Speed_3D": 1})))
            can1.append((rx + 2e-4, m_v, m_v.encode({"INS_Vel_Forwards_2D": vel, "INS_Vel_Sideways_2D": 0.0,
                                                      "Accuracy_INS_Vel_Body": acc, "Validity_INS_Vel_Forwards": 1,
                                                      "Validity_INS_Vel_Sideways": 1})))
            week = np.floor(gfix / 604800)
            can1.append((rx + 4e-4, m_t, m_t.encode({"GPS_Week": week, "GPS_Time": round(gfix - week * 604800, 3),
                                                      "Accuracy_GPS_Time": 3, "Validity_GPS_Week": 1,
                                                      "Validity_GPS_Time": 1})))
    dropped: dict = {}
    cfg = load_vehicle_config() if config is None else config
    path = Path(path)
    with RecordingWriter(path, config=cfg, metadata={"source": "tests/processing_sim.py"}) as w:
        for bus, frames in (("can0", can0), ("can1", can1)):
            if not frames:
                continue
            frames.sort(key=lambda f: f[0])
            if drop_frames:
                before: dict = {}
                for f in frames:
                    before[f[1].name] = before.get(f[1].name, 0) + 1
                frames = [f for f in frames if rng.random() >= drop_frames.get(f[1].name, 0.0)]
                for f in frames:
                    before[f[1].name] -= 1
                dropped.update({k: v for k, v in before.items() if k in drop_frames})
            ts = np.array([f[0] for f in frames]) + jitter(len(frames))
            ts = np.sort(ts)
            if burst_s > 0:
                ts = np.ceil(ts / burst_s) * burst_s + np.arange(ts.size) % 50 * 2e-6
                ts = np.sort(ts)
            ids = np.array([f[1].frame_id for f in frames], np.uint32)
            ext = np.array([f[1].is_extended_frame for f in frames], np.uint8)
            dlc = np.array([len(f[2]) for f in frames], np.uint8)
            data = np.zeros((len(frames), 8), np.uint8)
            for i, f in enumerate(frames):
                data[i, :len(f[2])] = np.frombuffer(f[2], np.uint8)
            ts_ns = start_ns + np.round(ts * 1e9).astype(np.int64)
            if ts_edit is not None:
                edited = ts_edit(bus, ts_ns.copy())
                if isinstance(edited, tuple):  # (timestamps, permutation of the frames in file order)
                    edited, perm = edited
                    ids, ext, dlc, data = ids[perm], ext[perm], dlc[perm], data[perm]
                ts_ns = np.asarray(edited, dtype=np.int64)
            for a in range(0, len(frames), 2000):
                w.write_batch(FrameBatch.from_columns(bus, ts_ns[a:a + 2000], ids[a:a + 2000], ext[a:a + 2000],
                                                      dlc[a:a + 2000], data[a:a + 2000]))
    return {"path": path, "lost_samples": int(n - keep.sum()), "start_ns": start_ns, "dropped_frames": dropped}
