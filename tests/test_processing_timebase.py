"""A robust time base (issue 12 item 4): outlier timestamps set aside and reported, logs
joined out of order sorted (or refused when they overlap), the grid spans the run."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from processing_sim import truth_profile, write_recording  # noqa: E402

from wheelsoil.processing import process_recording  # noqa: E402
from wheelsoil.processing.timebase import find_time_outliers, split_joined_parts  # noqa: E402

S = 10 ** 9
DAY = 86400 * S
I64 = np.iinfo(np.int64)


@pytest.fixture(scope="module")
def truth():
    return truth_profile(1)


@pytest.fixture(scope="module")
def clean(truth, tmp_path_factory):
    info = write_recording(tmp_path_factory.mktemp("clean") / "c.mcap", truth)
    return process_recording(info["path"])


def _set(i, value=None, add=0):
    def edit(bus, ts):
        if bus == "can0":
            ts[i] = value if value is not None else ts[i] + add
        return ts
    return edit


@pytest.mark.parametrize("edit, claim", [
    (_set(4000, add=DAY), "+1 days"),
    (_set(4000, value=I64.min), "impossible timestamp"),   # a NaN stored as int64
    (_set(4000, value=I64.max), "impossible timestamp"),   # 1e20 saturated
    (_set(0, value=I64.min), "impossible timestamp"),      # the very first frame
    (_set(-1, add=-DAY), "-24 h"),                         # the very last frame
])
def test_one_outlier_timestamp_is_set_aside(truth, clean, tmp_path, edit, claim):
    info = write_recording(tmp_path / "o.mcap", truth, ts_edit=edit)
    res = process_recording(info["path"])
    assert abs(len(res.signals) - len(clean.signals)) <= 1  # the grid spans the run, not the outlier
    ts = res.quality["timestamps"]
    assert ts["outlier_frames"] == 1 and sum(ts["outliers_by_message"].values()) == 1
    ex = [e for e in res.excluded if e["reason"].startswith("outlier timestamp")]
    assert len(ex) == 1 and claim in ex[0]["reason"] and ex[0]["frames"] == 1
    assert 0.0 <= ex[0]["t0_s"] <= ex[0]["t1_s"] <= res.signals["t_s"].iloc[-1] + 0.01  # where in the run
    assert any("set aside" in w and claim in w for w in res.warnings)
    # the same signals at the same host times as without the outlier
    t = res.signals["t_s"].to_numpy() + (res.t0_ns - clean.t0_ns) * 1e-9
    ref = np.interp(t, clean.signals["t_s"], clean.signals["load_n"])
    got = res.signals["load_n"].to_numpy()
    m = np.isfinite(got) & np.isfinite(ref) & (t > 0.5) & (t < t[-1] - 0.5)
    assert m.mean() > 0.9 and np.max(np.abs(got[m] - ref[m])) < 25


def test_block_of_frames_days_off_is_set_aside(truth, clean, tmp_path):
    def edit(bus, ts):
        ts[1000:1060] += 30 * DAY
        return ts
    info = write_recording(tmp_path / "b.mcap", truth, ts_edit=edit)
    res = process_recording(info["path"])
    assert abs(len(res.signals) - len(clean.signals)) <= 1
    q = res.quality["timestamps"]
    # 60 frames on each bus, less those of messages processing does not read (WFT_RL_Diag, WSS_Status)
    assert 100 <= q["outlier_frames"] <= 120
    assert {"WFT_RL_Force", "WSS_WheelSpeeds"} <= set(q["outliers_by_message"])
    assert res.gnss_latency_s == pytest.approx(clean.gnss_latency_s, abs=0.005)


def _join(shift_s):
    """The second half of each bus first in the file, shifted by ``shift_s`` (two logs joined
    in the wrong order)."""
    def edit(bus, ts):
        n = ts.size // 2
        perm = np.concatenate([np.arange(n, ts.size), np.arange(n)])
        return np.concatenate([ts[n:] + int(shift_s * S), ts[:n]]), perm
    return edit


def test_logs_joined_out_of_order_are_sorted(tmp_path):
    truth = truth_profile(2)
    info = write_recording(tmp_path / "j.mcap", truth, ts_edit=_join(100.0), drop_wft_bursts=5, latency_s=0.1)
    res = process_recording(info["path"])
    assert res.quality["timestamps"]["joined_parts"] == 1
    assert set(res.quality["timestamps"]["non_monotonic"]) == {"can0", "can1"}
    assert res.gnss_latency_s == pytest.approx(0.1, abs=0.01)   # not 12.7 ms
    for name in ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle"):
        assert res.lost_frames[name]["lost"] == info["lost_samples"]  # the 100 s between parts is no loss
    assert res.lost_frames["WSS_WheelSpeeds"]["lost"] <= 2
    between = [e for e in res.excluded if "joined out of order" in e["reason"]]
    assert between and all(99.0 < e["t1_s"] - e["t0_s"] < 101.0 for e in between)
    assert not any("50000" in e["reason"] for e in res.excluded)
    assert len(res.signals) == pytest.approx((truth.t_s[-1] + 100.0) * 100, abs=5)
    assert any("joined out of order" in w and "sorted" in w for w in res.warnings)


def test_overlapping_joined_logs_are_refused(tmp_path):
    info = write_recording(tmp_path / "ov.mcap", truth_profile(1), ts_edit=_join(-5.0))
    with pytest.raises(ValueError, match=r"ov.mcap: .* on bus can\d: time runs backwards and the parts overlap"):
        process_recording(info["path"])


def _later(shift_ns, buses=("can0", "can1")):
    def edit(bus, ts):  # the second half of each bus's frames later by shift_ns
        if bus in buses:
            ts[ts.size // 2:] += shift_ns
        return ts
    return edit


def test_grid_size_is_capped_with_a_clear_error(tmp_path):
    # the second half 40 days later and no GPS time to tell a clock step: a grid of 346 million rows
    info = write_recording(tmp_path / "far.mcap", truth_profile(1), ts_edit=_later(40 * DAY), no_gnss=True)
    with pytest.raises(ValueError, match=r"far.mcap: the run spans .* grid rows .* split the recording"):
        process_recording(info["path"])


@pytest.mark.parametrize("shift_s", [3600.0, 40 * 86400.0, -30.0])
def test_a_host_clock_step_that_gps_time_shows_is_undone(tmp_path, clean, truth, shift_s):
    """The host clock stepping forward (NTP sync, an RTC that started at 1970) or back while the
    receiver's GPS time runs on: before, the step was a gap of millions of lost frames (or, back,
    two logs of the same time, refused).  Now every later timestamp moves by minus the step and
    the run is processed as the clean one, with a warning; no frames are counted lost in it."""
    info = write_recording(tmp_path / "step.mcap", truth, ts_edit=_later(int(shift_s * S)))
    res = process_recording(info["path"])
    steps = res.quality["timestamps"]["clock_steps"]
    assert len(steps) == 1 and steps[0]["undone"] and steps[0]["step_s"] == pytest.approx(shift_s, abs=0.01)
    assert any("the host clock stepped" in w and "no frames were lost" in w for w in res.warnings)
    if shift_s >= 3600:  # 'info' reads no GPS time: it lists the gap and says what process makes of it
        from wheelsoil.daq.cli import format_info
        from wheelsoil.daq.info import read_recording_info

        rinfo = read_recording_info(info["path"])
        assert "a step of the host clock that 'wheelsoil process' finds with GPS time" in format_info(rinfo)
        # ... and counts no frame lost across it: each message has one interval > 1 h, not counted
        clean_info = read_recording_info(write_recording(tmp_path / "clean.mcap", truth)["path"])
        assert rinfo.stats.lost_frames == clean_info.stats.lost_frames
        assert rinfo.stats.lost_frames_estimated == clean_info.stats.lost_frames_estimated
        assert rinfo.stats.long_gaps and set(rinfo.stats.long_gaps.values()) == {1}
    assert len(res.signals) == pytest.approx(len(clean.signals), abs=2)
    for name in ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle"):
        assert res.lost_frames[name]["lost"] == clean.lost_frames[name]["lost"]
    n = min(len(res.signals), len(clean.signals))
    ok = res.signals["valid"].to_numpy()[:n] & clean.signals["valid"].to_numpy()[:n]
    assert ok.mean() > 0.5
    err = res.signals["drawbar_pull_n"].to_numpy()[:n][ok] - clean.signals["drawbar_pull_n"].to_numpy()[:n][ok]
    assert np.sqrt(np.mean(err ** 2)) < 5.0


def test_a_gps_time_jump_that_the_other_bus_does_not_share_is_not_undone(tmp_path, truth):
    """Only the GNSS bus's host times jump (can1): not a clock step (the WFT's frames do not jump
    with it); it is reported and left as it is, not 'repaired' into something else."""
    info = write_recording(tmp_path / "one.mcap", truth, ts_edit=_later(3600 * S, buses=("can1",)))
    res = process_recording(info["path"])
    steps = res.quality["timestamps"]["clock_steps"]
    assert steps and not any(st["undone"] for st in steps)
    assert any("WFT_RL_Force, WFT_RL_Moment, WFT_RL_Angle do(es) not jump with it: not a clock step, left as it "
               "is" in w for w in res.warnings)


def test_find_time_outliers_keeps_real_pauses():
    rng = np.random.default_rng(0)
    t = np.concatenate([np.arange(0, 30, 0.01), [150.0], np.arange(270, 300, 0.01)])  # lone frame between pauses
    ts = (1.7e18 + t * 1e9 + rng.normal(0, 1e5, t.size)).astype(np.int64)
    keep, runs = find_time_outliers(ts)
    assert keep.all() and runs == []
    ts2 = ts.copy()
    ts2[100] += 7 * 3600 * S
    ts2[-1] = I64.min
    keep, runs = find_time_outliers(ts2)
    assert np.flatnonzero(~keep).tolist() == [100, ts.size - 1]
    assert runs[0]["before_ns"] == ts[99] and runs[0]["after_ns"] == ts[101] and runs[1]["after_ns"] is None
    assert split_joined_parts(ts) == [(0, ts.size)]
