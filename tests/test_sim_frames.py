"""The field-test simulator's frames: rates, counters, quantisation, timing, latency.

Every check decodes the simulator's raw frames independently (cantools, the
sensors' own DBCs) and compares them with the simulator's hidden truth.
"""

from __future__ import annotations

import math
from importlib import resources

import cantools
import numpy as np
import pytest

from wheelsoil.model import load_terrain
from wheelsoil.simulate import GPS_LEAP_S, GPS_UNIX_EPOCH_S, pack_signals, simulate_run


def _db(stem):
    text = (resources.files("wheelsoil.dbc") / f"{stem}.dbc").read_text()
    return cantools.database.load_string(text, database_format="dbc", strict=False)


WFT, WSS, GPS = _db("wft"), _db("wheel_speed"), _db("gps_rt_speedbox")


@pytest.fixture(scope="module")
def run():
    return simulate_run(load_terrain("clay"), effect="vasilev", params={"H": 0.05}, seed=11, wheel=(0.55, 0.40),
                        duration_s=60.0, gnss_latency_s=0.12, drop_rate=0.02)


def _frames_of(run, bus, frame_id):
    f = run.frames[bus]
    sel = f["arbitration_id"] == frame_id
    return f["timestamp_ns"][sel], f["data"][sel], f["dlc"][sel]


def _decode(db, frame_id, data, dlc):
    msg = db.get_message_by_frame_id(frame_id)
    return [msg.decode(bytes(d[:n]), decode_choices=False) for d, n in zip(data, dlc)]


def test_rates_per_message_match_hardware_contract(run):
    dur = run.duration_s
    expected = {  # hardware.md: id -> (bus, rate Hz)
        0x120: ("can0", 500), 0x121: ("can0", 500), 0x122: ("can0", 500), 0x123: ("can0", 3),
        0x300: ("can1", 100), 0x301: ("can1", 10),
        0x9567C22: ("can1", 20), 0x9588322: ("can1", 20), 0x9566D22: ("can1", 20), 0x9566C22: ("can1", 1),
    }
    for fid, (bus, rate) in expected.items():
        ts, _, _ = _frames_of(run, bus, fid)
        got = len(ts) / dur
        tol = 0.05 if fid in (0x120, 0x121, 0x122) else 0.03  # 2 % of WFT samples dropped
        assert abs(got - rate) <= tol * rate + 1.5 / dur, (hex(fid), got, rate)
    ext = run.frames["can1"]["is_extended"]
    ids = run.frames["can1"]["arbitration_id"]
    assert np.all(ext == (ids > 0x7FF))
    assert not run.frames["can0"]["is_extended"].any()


def test_host_timestamps_monotonic_with_jitter(run):
    for bus, f in run.frames.items():
        ts = f["timestamp_ns"]
        assert np.all(np.diff(ts) >= 0), bus
    ts, _, _ = _frames_of(run, "can1", 0x300)
    period = np.diff(ts) * 1e-9
    assert abs(np.median(period) - 0.01) < 2e-4
    assert period.std() > 1e-6  # jittered, not an ideal clock


def test_counter_shared_and_gaps_match_dropped_samples(run):
    counters = {}
    for fid in (0x120, 0x121, 0x122):
        ts, data, dlc = _frames_of(run, "can0", fid)
        byte = 6 if fid != 0x122 else 2
        counters[fid] = data[:, byte].astype(int)
    assert np.array_equal(counters[0x120], counters[0x121])
    assert np.array_equal(counters[0x120], counters[0x122])
    for fid in (0x120, 0x121, 0x122):  # each id in transmit order on the bus: never backwards
        st = np.diff(counters[fid]) % 256
        assert 1 <= st.min() and st.max() <= 8, hex(fid)
    steps = np.diff(counters[0x120]) % 256
    lost = int((steps - 1).sum())
    assert lost == run.info["lost_wft_samples"]
    n_samples = len(run.truth)
    assert 0.01 < lost / n_samples < 0.03  # drop_rate 0.02
    clean = simulate_run(load_terrain("clay"), seed=11, duration_s=40.0, wheel=(0.55, 0.40))
    _, data, _ = _frames_of(clean, "can0", 0x120)
    assert np.all(np.diff(data[:, 6].astype(int)) % 256 == 1)


def test_pack_signals_equals_cantools_encode():
    rng = np.random.default_rng(0)
    for db in (WFT, WSS, GPS):
        for msg in db.messages:
            if msg.is_multiplexed():
                continue
            n = 50
            vals = {}
            for sig in msg.signals:
                lo = sig.minimum if sig.minimum is not None else 0
                hi = sig.maximum if sig.maximum is not None else 1
                vals[sig.name] = np.round(rng.uniform(lo, hi, n) / sig.scale) * sig.scale
            data, sat = pack_signals(msg, vals, n)
            assert not sat.any()
            for i in range(n):
                ref = msg.encode({k: v[i] for k, v in vals.items()}, scaling=True, strict=False)
                assert bytes(data[i, :msg.length]) == ref, (msg.name, i)
    diag = WFT.get_message_by_name("WFT_RL_Diag")
    data, _ = pack_signals(diag, {"DiagMux": 1, "SerialNumber": 140321}, 1)
    assert diag.decode(bytes(data[0]))["SerialNumber"] == 140321


def test_wft_frames_decode_to_truth_in_hub_frame(run):
    tf, fdat, fdlc = _frames_of(run, "can0", 0x120)
    _, mdat, mdlc = _frames_of(run, "can0", 0x121)
    _, adat, adlc = _frames_of(run, "can0", 0x122)
    # the frames of the fastest-spinning second (the rotation matters most there)
    all_cnt = fdat[:, 6].astype(int)
    k_all = np.concatenate([[0], np.cumsum(np.diff(all_cnt) % 256)])
    om = run.truth.omega_radps.to_numpy()[k_all]
    i0 = int(np.argmax(np.convolve(om, np.ones(500), "valid")))
    sl = slice(i0, i0 + 500)
    n = 500
    assert om[sl].mean() > 15.0
    fdat, fdlc, mdat, mdlc, adat, adlc = fdat[sl], fdlc[sl], mdat[sl], mdlc[sl], adat[sl], adlc[sl]
    force = _decode(WFT, 0x120, fdat, fdlc)
    moment = _decode(WFT, 0x121, mdat, mdlc)
    angle = _decode(WFT, 0x122, adat, adlc)
    a = np.radians([d["WheelAngle"] for d in angle])
    fx_w = np.array([d["Fx_w"] for d in force])
    fz_w = np.array([d["Fz_w"] for d in force])
    fx = fx_w * np.cos(a) + fz_w * np.sin(a)   # hardware.md
    fz = -fx_w * np.sin(a) + fz_w * np.cos(a)
    my = np.array([d["My"] for d in moment])
    # which truth sample: the counter (no drops among the first frames is not assumed)
    cnt = np.array([d["Counter"] for d in force])
    assert np.array_equal(cnt, [d["Counter"] for d in angle])
    truth = run.truth.iloc[k_all[sl]]
    # 20 N noise per component -> residual std ~20 N; angle quantisation adds < 1 N
    # the transducer's hub values: Fx = Dp - m_w dV/dt, My = T + I_w domega/dt (hardware.md)
    for meas, true, sd in ((fx, truth.fx_n, 20.0), (fz, truth.load_n, 20.0), (my, truth.my_nm, 4.0)):
        res = meas - true.to_numpy()
        assert abs(res.mean()) < 3 * sd / math.sqrt(n) + 1.0
        assert 0.7 * sd < res.std() < 1.4 * sd
    # the angle frame is the integral of omega, within quantisation
    d_ang = np.degrees(np.unwrap(a))
    ang_true = np.unwrap(np.radians(truth.wheel_angle_deg.to_numpy()))
    assert np.max(np.abs(d_ang - np.degrees(ang_true))) <= 360.0 / 65536 + 1e-9
    # the encoder integrates the wheel speed: mean advance per sample = mean omega * dt
    steps = np.diff(k_all[sl])
    assert np.mean(np.diff(np.unwrap(a)) / steps) == pytest.approx(truth.omega_radps.mean() * 0.002, rel=0.01)


def test_wheel_speed_frames_decode_to_truth(run):
    ts, data, dlc = _frames_of(run, "can1", 0x300)
    dec = _decode(WSS, 0x300, data[::5], dlc[::5])
    t = (ts[::5] - run.truth.t_host_ns.iloc[0]) * 1e-9
    rpm_rl = np.array([d["WheelSpeed_RL"] for d in dec])
    om = rpm_rl * 2 * np.pi / 60
    om_true = np.interp(t, (run.truth.t_host_ns - run.truth.t_host_ns.iloc[0]) * 1e-9, run.truth.omega_radps)
    moving = om_true > 2.0
    rel = (om[moving] - om_true[moving]) / om_true[moving]
    assert np.sqrt(np.mean(rel**2)) < 0.01
    # 4x4, locked differentials: every wheel turns at the instrumented wheel's omega (tyre tolerance 0.3 %)
    for name in ("WheelSpeed_FL", "WheelSpeed_FR", "WheelSpeed_RR"):
        om_o = np.array([d[name] for d in dec]) * 2 * np.pi / 60
        assert np.median(np.abs(om_o[moving] / om_true[moving] - 1)) < 0.006


def test_reference_front_wheels_carry_the_vehicle_speed():
    r = simulate_run(load_terrain("sand"), seed=12, duration_s=30.0, added_load_n=5000, front_wheels="reference")
    ts, data, dlc = _frames_of(r, "can1", 0x300)
    dec = _decode(WSS, 0x300, data[::5], dlc[::5])
    t = (ts[::5] - r.truth.t_host_ns.iloc[0]) * 1e-9
    v_true = np.interp(t, (r.truth.t_host_ns - r.truth.t_host_ns.iloc[0]) * 1e-9, r.truth.speed_mps)
    om_f = np.array([d["WheelSpeed_FL"] for d in dec]) * 2 * np.pi / 60
    drive = v_true > 1.0
    assert np.median(np.abs(0.47 * om_f[drive] - v_true[drive]) / v_true[drive]) < 0.015


def test_gnss_latency_and_gps_clock(run):
    ts, data, dlc = _frames_of(run, "can1", 0x9588322)
    dec = _decode(GPS, 0x9588322, data, dlc)
    v = np.array([d["INS_Vel_Forwards_2D"] for d in dec])
    t_host = ts * 1e-9
    t_truth = run.truth.t_host_ns.to_numpy() * 1e-9
    lags = np.arange(0.0, 0.3, 0.005)
    err = [np.mean((v - np.interp(t_host - lag, t_truth, run.truth.speed_mps)) ** 2) for lag in lags]
    best = lags[int(np.argmin(err))]
    assert abs(best - 0.12) <= 0.01
    # GPS time of the fix = host time of the fix + leap + offset (+ drift)
    ts_t, data_t, dlc_t = _frames_of(run, "can1", 0x9566D22)
    dec = _decode(GPS, 0x9566D22, data_t, dlc_t)
    gps = np.array([d["GPS_Week"] * 604800 + d["GPS_Time"] for d in dec])
    fix_host = ts_t * 1e-9 - 0.12
    diff = gps - (fix_host - GPS_UNIX_EPOCH_S + GPS_LEAP_S)
    assert abs(np.median(diff) - run.info["gps_clock_offset_s"]) < 0.01
    assert np.all(np.abs(np.round(np.mod(gps, 0.05) / 0.05) - np.mod(gps, 0.05) / 0.05) < 0.03)


def test_slip_truth_is_eq6_and_sweeps_to_high_slip(run):
    tr = run.truth
    mv = tr.speed_mps > 0.1
    s = (0.55 * tr.omega_radps[mv] - tr.speed_mps[mv]) / (0.55 * tr.omega_radps[mv])
    assert np.allclose(s, tr.slip[mv], atol=1e-9)
    acc = tr[tr.phase == "accel"]
    assert acc.slip.max() > 0.8 and acc.slip.min() < 0.1
    assert (tr[tr.phase == "brake"].slip < 0).mean() > 0.5
    # standstills when the vehicle can pull away from rest; else it starts rolling (soft soil)
    assert (tr.phase == "standstill").any() == run.info["vehicle"]["can_start"]
    assert tr.load_n.mean() == pytest.approx(11000, rel=0.05)


def test_same_seed_same_frames_and_bad_input():
    a = simulate_run(load_terrain("sand"), effect="ding", seed=5, duration_s=30.0, size=0.2)
    b = simulate_run(load_terrain("sand"), effect="ding", seed=5, duration_s=30.0, size=0.2)
    assert a.info == b.info
    assert np.array_equal(a.frames["can0"]["data"], b.frames["can0"]["data"])
    with pytest.raises(ValueError, match="effect"):
        simulate_run(load_terrain("sand"), effect="magic")
    with pytest.raises(ValueError, match="no parameter"):
        simulate_run(load_terrain("sand"), effect="lyasko", params={"H": 0.1})
    with pytest.raises(ValueError, match="drop_rate"):
        simulate_run(load_terrain("sand"), drop_rate=0.9)


def test_usb_batching_stamps_frames_in_bursts():
    r = simulate_run(load_terrain("sand"), seed=2, duration_s=30.0, usb_batching_s=0.001)
    ts = r.frames["can0"]["timestamp_ns"]
    gaps = np.diff(ts) * 1e-9
    assert np.all(gaps >= 0)
    # frames of one poll arrive in one burst, microseconds apart (3 frames per 2 ms sample, 2 polls
    # per sample: at least a third of the gaps); bursts are whole poll periods apart
    assert np.mean(gaps < 20e-6) > 0.3
    big = gaps[gaps > 200e-6] / 0.001
    assert np.mean(np.abs(big - np.round(big)) < 0.05) > 0.95
    assert r.info["usb_batching_s"] == 0.001


def test_slip_max_caps_the_drivers_sweeps_and_is_checked():
    r = simulate_run(load_terrain("sand"), seed=5, duration_s=60.0, slip_max=0.5, front_wheels="reference")
    acc = r.truth[r.truth.phase == "accel"]
    assert 0.4 < acc.slip.max() < 0.6 and acc.slip.min() < 0.1
    assert r.info["slip_max"] == 0.5
    with pytest.raises(ValueError, match="slip_max"):
        simulate_run(load_terrain("sand"), slip_max=0.1)


def _fz_noise(r):
    """Measured hub Fz minus the true load [N] of every WFT sample (decoded with cantools)."""
    _, fdat, fdlc = _frames_of(r, "can0", 0x120)
    _, adat, adlc = _frames_of(r, "can0", 0x122)
    force, angle = _decode(WFT, 0x120, fdat, fdlc), _decode(WFT, 0x122, adat, adlc)
    a = np.radians([d["WheelAngle"] for d in angle])
    fz = -np.array([d["Fx_w"] for d in force]) * np.sin(a) + np.array([d["Fz_w"] for d in force]) * np.cos(a)
    cnt = np.array([d["Counter"] for d in force])
    k = np.concatenate([[0], np.cumsum(np.diff(cnt) % 256)])  # truth sample of each frame (no drops here)
    return fz - r.truth.load_n.to_numpy()[k]


def test_wft_noise_scale_and_colour():
    kw = dict(seed=3, duration_s=30.0, front_wheels="reference")
    white = _fz_noise(simulate_run(load_terrain("sand"), **kw))
    loud = simulate_run(load_terrain("sand"), wft_noise=3.0, wft_noise_hz=2.0, **kw)
    slow = _fz_noise(loud)
    assert loud.info["wft_noise"] == 3.0 and loud.info["wft_noise_hz"] == 2.0
    # scale: 3x the sd; colour: white noise is independent sample to sample, the low-passed one
    # (2 Hz at 500 Hz) barely changes over one sample
    assert 2.7 < slow.std() / white.std() < 3.3
    assert abs(np.corrcoef(white[:-1], white[1:])[0, 1]) < 0.1
    assert np.corrcoef(slow[:-1], slow[1:])[0, 1] > 0.99
    with pytest.raises(ValueError, match="wft_noise"):
        simulate_run(load_terrain("sand"), wft_noise=-1.0)
    with pytest.raises(ValueError, match="wft_noise_hz"):
        simulate_run(load_terrain("sand"), wft_noise_hz=0.0)
