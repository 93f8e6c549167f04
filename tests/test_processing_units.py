"""Unit tests of the processing building blocks: counters, rotation, filters, slip, clocks."""

from __future__ import annotations

import numpy as np
import pytest

from wheelsoil.processing.filters import filter_to_grid, lowpass_segments, segments
from wheelsoil.processing.slip import accel_cycles, classify_phases, slip_ratio
from wheelsoil.processing.timesync import GPS_EPOCH_UNIX_S, estimate_latency, fit_gps_time_mapping
from wheelsoil.processing.wft import assemble_wft_samples, rotate_to_hub, unwrap_counter


def _wft_times(n, rng, period=0.002):
    return (1_700_000_000_000_000_000 + np.round((np.arange(n) * period
                                                   + rng.exponential(1e-4, n)) * 1e9)).astype(np.int64)


def test_unwrap_counts_gaps_longer_than_a_wrap():
    rng = np.random.default_rng(0)
    ts = _wft_times(3000, rng)
    counter = np.arange(3000) % 256
    keep = np.ones(3000, bool)
    keep[1000:1300] = False  # 300 samples lost: more than one wrap of the 8-bit counter
    keep[2000:2002] = False
    idx, period, jumps = unwrap_counter(ts[keep], counter[keep])
    assert period == pytest.approx(0.002, rel=0.05)
    assert jumps == 0
    np.testing.assert_array_equal(idx - idx[0], np.flatnonzero(keep))


def test_unwrap_tells_counter_jumps_from_lost_frames():
    rng = np.random.default_rng(1)
    ts = _wft_times(2000, rng)
    counter = np.arange(2000) % 256
    counter[700:] = (counter[700:] + 90) % 256   # corrupted counter, no time lost
    counter[1500:] = (counter[1500:] + 200) % 256
    keep = np.ones(2000, bool)
    keep[1100:1105] = False                       # real loss of 5 samples
    idx, _, jumps = unwrap_counter(ts[keep], counter[keep])
    assert jumps == 2
    np.testing.assert_array_equal(idx - idx[0], np.flatnonzero(keep))


def test_rotation_inverts_the_wheel_frame():
    rng = np.random.default_rng(2)
    dp, w, a = rng.normal(0, 2000, 100), rng.uniform(5000, 15000, 100), rng.uniform(0, 2 * np.pi, 100)
    fx_w = dp * np.cos(a) - w * np.sin(a)
    fz_w = dp * np.sin(a) + w * np.cos(a)
    fx, fz = rotate_to_hub(fx_w, fz_w, a)
    np.testing.assert_allclose(fx, dp, atol=1e-8)
    np.testing.assert_allclose(fz, w, atol=1e-8)
    fx, fz = rotate_to_hub(np.array([0.0]), np.array([1.0]), np.array([np.pi / 2]))
    assert fx[0] == pytest.approx(1.0) and fz[0] == pytest.approx(0.0, abs=1e-12)


def test_assemble_matches_frames_by_counter_and_time():
    rng = np.random.default_rng(3)
    n = 1500
    ts = _wft_times(n, rng)
    counter = (np.arange(n) + 77) % 256
    value = np.arange(n, dtype=float)
    keep_m = np.ones(n, bool)
    keep_m[:300] = False  # the moment stream starts later (another wrap offset)
    keep_m[900] = False   # and loses one frame
    streams = {
        "F": (ts, counter, {"fx": value}),
        "M": (ts[keep_m] + 130_000, counter[keep_m], {"my": 10 * value[keep_m]}),
    }
    ws = assemble_wft_samples(streams, reference="F")
    assert ws.index.size == n
    np.testing.assert_array_equal(ws.columns["fx"], value)
    ok = np.isfinite(ws.columns["my"])
    np.testing.assert_array_equal(ws.columns["my"][ok], 10 * value[ok])
    assert not ws.complete[900] and ws.complete[901] and not ws.complete[:300].any()
    assert ws.reports["M"].lost == 301 and ws.reports["F"].lost == 0


def test_sample_times_ignore_bursty_delivery():
    """Frames delivered in bursts of 20 (USB/UDP) still get their true sample times."""
    rng = np.random.default_rng(6)
    n = 5000
    true_ns = 1_700_000_000_000_000_000 + np.arange(n) * 2_000_000
    burst_end = (np.arange(n) // 20 + 1) * 20 - 1
    # each frame arrives with its burst's last one (in order, 2 us apart), bursts jitter by 0..1 ms
    ts = true_ns[burst_end] + (np.arange(n) % 20) * 2_000 + np.repeat(rng.integers(0, 1_000_000, n // 20), 20)
    counter = np.arange(n) % 256
    ws = assemble_wft_samples({"F": (ts, counter, {"x": np.zeros(n)})}, reference="F")
    err = ws.timestamp_ns - true_ns
    assert np.all(np.diff(ws.timestamp_ns) > 0)
    assert np.ptp(err) < 500_000  # constant delay allowed; spread < 0.5 ms (bursts: 38 ms, jitter 1 ms)


def test_filter_never_crosses_a_gap():
    x = np.concatenate([np.zeros(400), np.full(10, np.nan), np.full(400, 1000.0)])
    y = lowpass_segments(x, 500.0, 5.0)
    assert np.isnan(y[400:410]).all()
    assert np.abs(y[:400]).max() < 1e-9
    assert np.abs(y[410:] - 1000).max() < 1e-6
    assert segments(np.isfinite(x)) == [(0, 400), (410, 810)]


def test_filter_to_grid_bridges_short_gaps_only():
    t = np.arange(1000) * 0.002
    x = np.sin(2 * np.pi * 0.5 * t)
    x[100:103] = np.nan   # 3 lost samples: bridged
    x[500:510] = np.nan   # 10 lost samples: a gap
    grid = np.arange(0, 2.0, 0.01)
    y = filter_to_grid(t, x, 0.002, grid, 5.0)
    gap = (grid > t[499]) & (grid < t[510])
    assert np.isnan(y[gap]).all() and np.isfinite(y[~gap & (grid <= t[-1])]).all()
    ok = np.isfinite(y)
    np.testing.assert_allclose(y[ok], np.sin(2 * np.pi * 0.5 * grid[ok]), atol=2e-3)


def test_slip_eq6_nan_not_inf_and_range_flags():
    rw = np.array([2.0, 2.0, 0.0, 0.05, 1.0, 1.0, np.nan])
    v = np.array([1.0, 2.0, 1.0, 0.0, 2.0, 3.0, 1.0])
    s, ok = slip_ratio(rw, v, min_wheel_speed_mps=0.1)
    np.testing.assert_allclose(s[:2], [0.5, 0.0])
    assert np.isnan(s[2:4]).all() and np.isnan(s[6]) and not np.isinf(s).any()
    assert s[4] == -1.0 and ok[4]           # -1 is inside [-1, 1)
    assert s[5] == -2.0 and not ok[5]       # outside: flagged
    assert list(ok) == [True, True, False, False, True, False, False]


def test_phases_and_cycle_ids():
    t = np.arange(0, 30, 0.01)
    v = np.interp(t, [0, 2, 8, 10, 14, 16, 22, 24, 28, 30], [0, 0, 3, 3, 1, 1, 3.5, 3.5, 0, 0])
    T = np.where(np.gradient(v, t) > 0, 1500.0, np.where(np.gradient(v, t) < 0, -1500.0, 300.0))
    phase = classify_phases(t, v, v / 0.8, T)
    assert (phase[(t > 3) & (t < 7)] == "accel").all()
    assert (phase[(t > 11) & (t < 13)] == "brake").all()
    assert (phase[t < 1.5] == "standstill").all()
    assert (phase[(t > 8.5) & (t < 9.5)] == "drive").all()  # cruising with the torque on: steady driving
    coast = classify_phases(t, v, v / 0.8, np.where(np.gradient(v, t) < 0, 300.0, 0.0))
    assert (coast[(t > 8.5) & (t < 9.5)] == "other").all()  # no torque: coasting
    assert (coast[(t > 11) & (t < 13)] == "other").all()  # slowing with the torque still on: a transient
    cyc = accel_cycles(t, phase)
    assert set(np.unique(cyc)) == {-1, 0, 1}
    assert (cyc[(t > 3) & (t < 7)] == 0).all() and (cyc[(t > 17) & (t < 21)] == 1).all()


def test_gps_time_mapping_robust_with_drift_and_week_rollover():
    rng = np.random.default_rng(4)
    host_s = 1_700_000_000.0 + np.arange(0, 600, 0.05)
    drift = 25e-6
    gps = (host_s[0] - GPS_EPOCH_UNIX_S + 18.3) + (host_s - host_s[0]) * (1 + drift)
    gps = gps - gps[0] + 2300 * 604800 + 604800 - 300  # rolls into the next week after 300 s
    gps += rng.normal(0, 3e-4, gps.size)
    gps[::97] += 0.5  # outliers
    week = np.floor(gps / 604800)
    host_ns = np.round(host_s * 1e9).astype(np.int64)
    m = fit_gps_time_mapping(host_ns, week, gps - week * 604800)
    assert m["drift_ppm"] == pytest.approx(25, abs=1)
    assert m["gps_at_t0_s"] == pytest.approx(2300 * 604800 + 604800 - 300, abs=1e-3)
    assert m["n_outliers"] >= gps.size // 97
    assert m["residual_rms_s"] < 1e-3
    with pytest.raises(ValueError):
        fit_gps_time_mapping(host_ns[:2], week[:2], gps[:2])


def test_latency_estimate_recovers_delay():
    rng = np.random.default_rng(5)
    t_ref = np.arange(0, 120, 0.01)
    v_true = 2 + 1.5 * np.sin(2 * np.pi * t_ref / 9) + 0.5 * np.sin(2 * np.pi * t_ref / 3.7)
    t_fix = np.arange(0.3, 119, 0.05)
    v_g = np.interp(t_fix, t_ref, v_true) + rng.normal(0, 0.01, t_fix.size)
    est = estimate_latency(t_fix + 0.137, v_g, t_ref, v_true * 1.01)
    assert est.latency_s == pytest.approx(0.137, abs=0.002)
    assert 0 < est.stderr_s < 0.003
    with pytest.raises(ValueError):
        estimate_latency(t_fix, v_g, t_ref, np.full_like(t_ref, 0.1))  # below min speed: nothing usable


def test_smoothed_derivative_of_a_run_shorter_than_its_window_is_nan():
    """A few samples (a log cut after 50 lines) give no complete smoothing window: NaN, not a crash."""
    from wheelsoil.processing.slip import _smooth_derivative

    t = np.arange(5) * 0.01
    d = _smooth_derivative(t, 2.0 * t, smooth_s=0.5)
    assert d.shape == (5,) and np.isnan(d).all()
    t = np.arange(500) * 0.01
    assert np.nanmax(np.abs(_smooth_derivative(t, 2.0 * t, smooth_s=0.5) - 2.0)) < 1e-9
