"""Acceptance tests of process_recording on simulated recordings with known truth,
bad inputs, and the ``wheelsoil process`` command."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from processing_sim import FORCE_NOISE_N, MOMENT_NOISE_NM, truth_profile, write_recording  # noqa: E402

from wheelsoil.processing import COLUMNS, process_recording  # noqa: E402
from wheelsoil.processing.pipeline import UNSTEADY_SLIP_SD  # noqa: E402

GPS_OFFSET_S = 1234.5678


def _truth_on(res, truth, name):
    return np.interp(res.signals["t_s"].to_numpy(), truth.t_s, getattr(truth, name))


@pytest.fixture(scope="module", params=[0.05, 0.2])
def processed(request, tmp_path_factory):
    latency = request.param
    truth = truth_profile(3)
    info = write_recording(tmp_path_factory.mktemp("rec") / "run.mcap", truth, latency_s=latency,
                           gps_offset_s=GPS_OFFSET_S, drop_wft_bursts=8, seed=int(latency * 100))
    return latency, truth, info, process_recording(info["path"])


def test_columns_exact_and_types(processed):
    _, _, _, res = processed
    s = res.signals
    assert tuple(s.columns) == COLUMNS
    assert s["valid"].dtype == bool
    assert set(s["phase"].unique()) <= {"accel", "drive", "brake", "standstill", "other"}
    assert np.allclose(np.diff(s["t_s"]), 0.01)
    assert res.cycle.shape == (len(s),)


def test_latency_recovered_within_10ms(processed):
    latency, _, _, res = processed
    assert res.gnss_latency_s is not None
    assert abs(res.gnss_latency_s - latency) < 0.010
    assert 0 < res.gnss_latency_stderr_s < 0.010


def test_slip_rms_on_accel_phases(processed):
    _, truth, _, res = processed
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    assert m.sum() > 1500  # three 8 s accelerations at 100 Hz, most of them found
    err = s["slip"].to_numpy()[m] - _truth_on(res, truth, "slip")[m]
    assert np.sqrt(np.mean(err**2)) <= 0.01


def test_a_grade_takes_the_speed_along_the_ground_from_the_3d_speed(tmp_path):
    """On an 18 % grade the GNSS 2D speed and the INS velocity are horizontal: V along the ground is
    found from the 3D speed over the 2D one, so slip matches the truth as on level ground (without it
    slip would read 1 - cos(atan 0.18) = 1.6 % of (1 - s) high), and the warning names the grade and
    the wheel's weight along the slope left in Fx."""
    truth = truth_profile(3)
    info = write_recording(tmp_path / "r.mcap", truth, latency_s=0.1, seed=4, grade=0.18)
    res = process_recording(info["path"])
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    err = s["slip"].to_numpy()[m] - _truth_on(res, truth, "slip")[m]
    assert abs(np.mean(err)) < 0.003 and np.sqrt(np.mean(err**2)) <= 0.01
    assert res.quality["grade"]["max_factor"] == pytest.approx(1 / np.cos(np.arctan(0.18)), abs=2e-3)
    said = [w for w in res.warnings if w.startswith("GNSS speed on a grade")]
    assert len(said) == 1 and "10.2 deg (18 %)" in said[0] and "m_w g sin(grade) = 139 N" in said[0], said


def test_a_wheel_speed_oscillating_faster_than_the_filter_is_not_fitted(tmp_path):
    """A driveline oscillating at 12 Hz (the wheel speed +-30 %) for 3 s of an accelerate phase: the 5 Hz
    low-pass averages it away, so the filtered slip is biased and the forces average over slips it does
    not show. Those samples are not valid, the spans are listed and a warning says why; the same run
    without it flags nothing."""
    truth = truth_profile(3)
    t_acc = float(truth.t_s[np.flatnonzero(truth.phase == "accel")[len(truth.t_s) // 20]])
    clean = process_recording(write_recording(tmp_path / "a.mcap", truth, seed=5)["path"])
    res = process_recording(write_recording(tmp_path / "b.mcap", truth, seed=5,
                                            chatter=(t_acc, t_acc + 3.0, 0.3, 12.0))["path"])
    assert "unsteady_slip" not in clean.quality and not any("UNSTEADY" in w for w in clean.warnings)
    t = res.signals["t_s"].to_numpy()  # on the truth's time axis (as _truth_on reads it)
    lost = clean.signals["valid"].to_numpy() & ~res.signals["valid"].to_numpy()
    assert lost.any()
    inside = (t >= t_acc - 0.3) & (t <= t_acc + 3.3)  # the window, widened by the filter's reach
    assert not np.any(lost & ~inside), "only the oscillating span is set aside"
    assert np.count_nonzero(lost) / res.rate_hz > 1.5
    said = [w for w in res.warnings if w.startswith("WHEEL SPEED UNSTEADY")]
    assert len(said) == 1 and res.quality["unsteady_slip"]["max_sd"] > UNSTEADY_SLIP_SD
    assert any(e["reason"].startswith("wheel speed unsteady") for e in res.excluded)


def test_a_wheel_speed_module_with_a_wrong_tooth_count_is_rescaled_to_the_transducer_angle(tmp_path):
    """The module's tone wheel has 48 teeth, configured as 50: it reads 0.96 of the wheel's speed, and slip
    (Eq. 6) would read (1 - s) 4 % high. The transducer's wheel angle, which wraps once per revolution,
    measures the same rotation: the gain is found, the speed divided by it, and slip matches the truth;
    the same run with the right count is left alone."""
    truth = truth_profile(3)
    res = process_recording(write_recording(tmp_path / "r.mcap", truth, seed=6, rl_scale=0.96)["path"])
    q = res.quality["wheel_speed_scale"]
    assert q["applied"] and q["gain"] == pytest.approx(0.96, abs=2e-3)
    said = [w for w in res.warnings if w.startswith("WHEEL SPEED SCALE CORRECTED")]
    assert len(said) == 1 and "0.96" in said[0]
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    err = s["slip"].to_numpy()[m] - _truth_on(res, truth, "slip")[m]
    assert abs(np.mean(err)) < 0.003
    clean = process_recording(write_recording(tmp_path / "c.mcap", truth, seed=6)["path"])
    assert not clean.quality["wheel_speed_scale"]["applied"]
    assert not any(w.startswith("WHEEL SPEED SCALE") for w in clean.warnings)


def test_another_wheels_speed_is_not_rescaled_to_the_transducer_angle():
    """A channel of another wheel scatters against the measured wheel's rotation with the two wheels'
    slips: its median ratio is no tooth count, and nothing is rescaled."""
    from wheelsoil.processing.pipeline import _angle_rate, _wheel_speed_scale

    t_w = np.arange(0, 60, 0.002)
    omega = 5.0 + 3.0 * np.sin(t_w / 3.0) ** 2
    angle = np.mod(np.cumsum(omega) * 0.002, 2 * np.pi)
    t_m = np.arange(0, 60, 0.01)
    om_m = np.interp(t_m, t_w, omega)
    rate = _angle_rate(t_w, angle, 0.002)
    assert _wheel_speed_scale(*rate, t_m, 0.97 * om_m, 0.01)["applied"]
    other = om_m * (1 - 0.12 * np.sin(t_m / 2.0) ** 2)  # a wheel slipping differently
    q = _wheel_speed_scale(*rate, t_m, other, 0.01)
    assert not q["applied"] and "scatters" in q["note"]


def test_the_unresolved_slip_spread_is_the_slip_change_of_the_wheel_speed_the_filter_removes():
    """(1 - s) RMS(omega_raw - omega) / omega: for an oscillation of amplitude a around omega, a / sqrt(2)."""
    from wheelsoil.processing.pipeline import unresolved_slip_sd

    t = np.arange(0, 4, 0.01)
    omega = np.full(t.size, 10.0)
    slip = np.full(t.size, 0.4)
    raw = omega * (1 + 0.2 * np.sin(2 * np.pi * 15 * t))
    sd = unresolved_slip_sd(raw, omega, slip, 100.0, 5.0)
    assert np.allclose(sd[50:-50], 0.6 * 0.2 / np.sqrt(2), rtol=0.05)
    assert np.all(unresolved_slip_sd(omega, omega, slip, 100.0, 5.0) == 0)
    raw[100:110] = np.nan
    assert np.isnan(unresolved_slip_sd(raw, omega, slip, 100.0, 5.0)[100:110]).all()


def test_level_ground_with_a_noisy_vertical_speed_is_not_corrected():
    """The vertical velocity's noise lifts the 3D speed over the 2D one by sigma^2 / (2 V^2): at three
    times a receiver's 0.02 m/s, nothing is corrected on level ground."""
    from wheelsoil.processing.pipeline import _grade_factor

    rng = np.random.default_rng(0)
    t = np.arange(0, 120, 0.05)
    v2 = 1.0 + 0.8 * np.abs(np.sin(t / 9))
    v3 = np.hypot(v2, rng.normal(0, 0.06, t.size))
    assert _grade_factor(t, v2, t, v3, 0.05, t) is None
    v3 = np.where(t > 60, v2 / np.cos(np.arctan(0.12)), v3)  # a 12 % climb in the second minute
    k = _grade_factor(t, v2, t, v3, 0.05, t)
    assert k is not None and np.allclose(k[t > 62], 1 / np.cos(np.arctan(0.12)), rtol=1e-9)
    assert np.all(k[t < 58] < 1.005)


def test_forces_within_sensor_noise(processed):
    _, truth, _, res = processed
    s = res.signals
    m = s["valid"].to_numpy()
    for col, noise in (("drawbar_pull_n", FORCE_NOISE_N), ("load_n", FORCE_NOISE_N),
                       ("torque_nm", MOMENT_NOISE_NM)):
        err = s[col].to_numpy()[m] - _truth_on(res, truth, col)[m]
        assert np.sqrt(np.mean(err**2)) <= noise, col


def test_speed_and_omega(processed):
    _, truth, _, res = processed
    s = res.signals
    m = s["valid"].to_numpy()
    assert np.sqrt(np.mean((s["speed_mps"].to_numpy()[m] - _truth_on(res, truth, "speed_mps")[m]) ** 2)) < 0.02
    assert np.sqrt(np.mean((s["omega_radps"].to_numpy()[m] - _truth_on(res, truth, "omega_radps")[m]) ** 2)) < 0.05


def test_lost_frames_and_gps_mapping(processed):
    latency, _, info, res = processed
    for name in ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle"):
        assert res.lost_frames[name]["lost"] == info["lost_samples"]
    g = res.gps_time_mapping
    # GPS time of a fix = host receive time + offset - latency (the receiver's clock offset)
    assert abs(g["offset_s"] - (GPS_OFFSET_S - latency)) < 2e-3
    assert abs(g["drift_ppm"]) < 20
    assert g["residual_rms_s"] < 2e-3


def test_phases_and_cycles_follow_truth(processed):
    _, truth, _, res = processed
    s = res.signals
    idx = np.clip(np.searchsorted(truth.t_s, s["t_s"].to_numpy()), 0, truth.t_s.size - 1)
    true_phase = truth.phase[idx]
    acc = true_phase == "accel"
    assert np.mean(s["phase"].to_numpy()[acc] == "accel") > 0.85
    assert np.mean(s["phase"].to_numpy()[true_phase == "brake"] != "accel") > 0.95
    assert res.cycle.max() == 2  # three accelerate cycles, ids 0..2
    assert set(np.unique(res.cycle[acc])) <= {-1, 0, 1, 2}


# --------------------------------------------------------------------------- bad input
@pytest.fixture(scope="module")
def short_truth():
    return truth_profile(1)


def test_no_gnss(tmp_path, short_truth):
    info = write_recording(tmp_path / "r.mcap", short_truth, no_gnss=True)
    res = process_recording(info["path"])
    s = res.signals
    assert res.gnss_latency_s is None and res.gps_time_mapping is None
    assert any("no GNSS velocity" in w and "still computed" in w for w in res.warnings)
    assert s["speed_mps"].isna().all() and s["slip"].isna().all() and not s["valid"].any()
    assert s["load_n"].notna().mean() > 0.99 and s["omega_radps"].notna().mean() > 0.99


def test_no_wheel_speed(tmp_path, short_truth):
    info = write_recording(tmp_path / "r.mcap", short_truth, no_wheel_speed=True)
    res = process_recording(info["path"])
    s = res.signals
    assert any("no wheel speed" in w for w in res.warnings)
    assert any("latency not estimated" in w for w in res.warnings)
    assert s["omega_radps"].isna().all() and s["slip"].isna().all() and not s["valid"].any()
    assert s["speed_mps"].notna().mean() > 0.95 and s["fx_n"].notna().mean() > 0.99
    # Dp = Fx + m_w dV/dt is there wherever V is (the inertia correction needs dV/dt)
    assert (s["drawbar_pull_n"].notna() == (s["speed_mps"].notna() & s["fx_n"].notna())).mean() > 0.99
    assert s["torque_nm"].isna().all() and s["my_nm"].notna().mean() > 0.99  # T needs domega/dt


def test_jumping_wft_counter(tmp_path, short_truth):
    info = write_recording(tmp_path / "r.mcap", short_truth, counter_jumps=4, drop_wft_bursts=3, seed=5)
    res = process_recording(info["path"])
    assert any("counter jumped" in w for w in res.warnings)
    assert res.lost_frames["WFT_RL_Force"]["counter_jumps"] == 4
    assert res.lost_frames["WFT_RL_Force"]["lost"] == info["lost_samples"]
    s = res.signals
    m = s["valid"].to_numpy()
    err = s["load_n"].to_numpy()[m] - _truth_on(res, short_truth, "load_n")[m]
    assert np.sqrt(np.mean(err**2)) <= FORCE_NOISE_N


def test_wheel_speed_zero_for_a_minute(tmp_path):
    truth = truth_profile(5)
    info = write_recording(tmp_path / "r.mcap", truth, wheel_speed_zero=(8.0, 68.0))
    res = process_recording(info["path"])
    s = res.signals
    window = (s["t_s"] > 9) & (s["t_s"] < 67)
    assert not np.isinf(s["slip"]).any()
    assert s["slip"][window].isna().all() and not s["valid"][window].any()
    assert any("slip undefined" in w and "vehicle moved" in w for w in res.warnings)
    assert s["load_n"][window].notna().all() and s["speed_mps"][window].notna().all()
    assert s["valid"][s["t_s"] > 70].mean() > 0.5  # the rest is still usable


def test_recording_without_configured_messages(tmp_path):
    from wheelsoil.daq import FrameBatch, RecordingWriter

    path = tmp_path / "other.mcap"
    with RecordingWriter(path, config=None, metadata={}) as w:
        w.write_batch(FrameBatch.from_columns("can0", np.arange(10) * 1000, np.full(10, 0x7AB),
                                              np.zeros(10), np.full(10, 8), np.zeros((10, 8))))
    with pytest.raises(ValueError, match="none of the configured messages"):
        process_recording(path)
    with pytest.raises(OSError, match="no such file"):
        process_recording(tmp_path / "missing.mcap")
    with pytest.raises(ValueError, match="at most 1000 Hz"):
        process_recording(path, rate_hz=1e5)
    for cutoff in (0.001, 0.0, -1.0):  # a filter narrower than an accelerate cycle: refused, not unstable
        with pytest.raises(ValueError, match="at least 0.1 Hz"):
            process_recording(path, cutoff_hz=cutoff)



def test_an_mcap_in_another_layout_is_refused_naming_what_it_holds(tmp_path):
    """An MCAP whose CAN frames are in another schema (another tool's JSON frames) is an error
    naming its channels and the way in (a log file and ``wheelsoil import``), not "no frames"."""
    import json

    from mcap.writer import Writer

    path = tmp_path / "foreign.mcap"
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        cid = w.register_channel("/can0", "json", w.register_schema("can_frame", "jsonschema", b"{}"))
        for i in range(5):
            w.add_message(cid, log_time=i, publish_time=i, data=json.dumps({"id": 256}).encode())
        w.finish()
    with pytest.raises(ValueError, match=r"foreign\.mcap: the recording holds no CAN frames in the layout "
                       r"wheelsoil reads .*it has /can0 \(schema 'can_frame', json\).*'wheelsoil import'"):
        process_recording(path)


def test_short_wft_frames_are_dropped_not_decoded_into_forces(tmp_path, short_truth):
    """A WFT frame whose payload is shorter than its DBC layout (a DLC mismatch) has no counter:
    it is dropped as a lost sample, with a warning, and the forces stay as the whole frames give."""
    from wheelsoil.daq.convert import export_recording

    info = write_recording(tmp_path / "r.mcap", short_truth, latency_s=0.1)
    export_recording(info["path"], tmp_path / "r.log")
    lines = (tmp_path / "r.log").read_text().splitlines()
    force = [i for i, ln in enumerate(lines) if " 120#" in ln]
    for i in force[::7]:  # every 7th force frame cut to 4 bytes
        head, data = lines[i].split("#", 1)
        lines[i] = f"{head}#{data.split()[0][:8]}"
    (tmp_path / "short.log").write_text("\n".join(lines) + "\n")
    a = process_recording(tmp_path / "r.log")
    b = process_recording(tmp_path / "short.log")
    assert any("DLC mismatch" in w and f"{len(force[::7])} WFT_RL_Force" in w for w in b.warnings)
    ok = a.signals["valid"].to_numpy() & b.signals["valid"].to_numpy()
    assert ok.mean() > 0.5
    err = b.signals["drawbar_pull_n"].to_numpy()[ok] - a.signals["drawbar_pull_n"].to_numpy()[ok]
    assert np.sqrt(np.mean(err**2)) < 3 * FORCE_NOISE_N


def test_wft_frames_of_another_multiplexer_value_are_not_called_short(tmp_path, short_truth):
    """A DBC whose force message is multiplexed (the forces in frames whose Status byte is 0): frames
    carrying another value lose their forces as lost samples, and the warning names the multiplexer
    and its values, not a DLC mismatch (their payload is whole); none carrying it is said as such."""
    from daq_helpers import copy_default_vehicle

    from wheelsoil.daq import load_vehicle_config
    from wheelsoil.daq.convert import export_recording

    toml = copy_default_vehicle(tmp_path)
    dbc = tmp_path / "wft.dbc"
    text = dbc.read_text()
    for a, b in ((" SG_ Fx_w : 0|16", " SG_ Fx_w m0 : 0|16"), (" SG_ Fz_w : 32|16", " SG_ Fz_w m0 : 32|16"),
                 (" SG_ Status : 56|8@1+ (1,0) [0|255] \"\" DAQ\n\nBO_ 289",
                  " SG_ Status M : 56|8@1+ (1,0) [0|255] \"\" DAQ\n\nBO_ 289")):
        assert a in text
        text = text.replace(a, b, 1)
    dbc.write_text(text)
    cfg = load_vehicle_config(toml)
    info = write_recording(tmp_path / "r.mcap", short_truth, latency_s=0.1)
    export_recording(info["path"], tmp_path / "r.log")
    lines = (tmp_path / "r.log").read_text().splitlines()
    force = [i for i, ln in enumerate(lines) if " 120#" in ln]
    assert all(lines[i].split("#", 1)[1][14:16] == "00" for i in force)  # the Status byte: 0 in every frame
    for i in force[::7]:
        head, data = lines[i].split("#", 1)
        lines[i] = f"{head}#{data[:14]}03{data[16:]}"
    (tmp_path / "mux.log").write_text("\n".join(lines) + "\n")
    res = process_recording(tmp_path / "mux.log", config=cfg)
    said = [w for w in res.warnings if "WFT_RL_Force" in w and "lost samples" in w]
    assert any(f"{len(force[::7])} WFT_RL_Force" in w and "Status = 3, not the 0 that Fx_w, Fz_w need" in w
               for w in said), said
    assert not any("DLC mismatch" in w for w in said), said
    assert res.signals["valid"].mean() > 0.5
    for i in force:
        head, data = lines[i].split("#", 1)
        lines[i] = f"{head}#{data[:14]}01{data[16:]}"
    (tmp_path / "none.log").write_text("\n".join(lines) + "\n")
    res = process_recording(tmp_path / "none.log", config=cfg)
    assert any("no WFT_RL_Force frame on can0 carries the multiplexer value" in w for w in res.warnings), \
        res.warnings


def test_long_wft_frames_are_not_decoded_and_29_bit_twins_are_named(tmp_path, short_truth):
    """A frame on a WFT id with a payload longer than its DBC message (12 bytes where the DBC says
    8: a CAN FD variant with another layout) is not decoded into forces but lost, with a warning;
    ids logged as 29-bit where the DBC says 11-bit are named when their message is missing."""
    from wheelsoil.daq.convert import export_recording

    info = write_recording(tmp_path / "r.mcap", short_truth, latency_s=0.1)
    export_recording(info["path"], tmp_path / "r.log")
    lines = (tmp_path / "r.log").read_text().splitlines()
    force = [i for i, ln in enumerate(lines) if " 120#" in ln]
    long_lines = list(lines)
    for i in force[::7]:  # every 7th force frame as a 12-byte FD frame of another layout
        head = long_lines[i].split("#", 1)[0]
        long_lines[i] = f"{head}##0{'7F' * 12}"
    (tmp_path / "long.log").write_text("\n".join(long_lines) + "\n")
    a = process_recording(tmp_path / "r.log")
    b = process_recording(tmp_path / "long.log")
    assert any(f"{len(force[::7])} frame(s) of WFT_RL_Force on can0 have a payload of up to 12 bytes where its "
               "DBC says 8" in w for w in b.warnings)
    ok = a.signals["valid"].to_numpy() & b.signals["valid"].to_numpy()
    assert ok.mean() > 0.5
    err = b.signals["drawbar_pull_n"].to_numpy()[ok] - a.signals["drawbar_pull_n"].to_numpy()[ok]
    assert np.sqrt(np.mean(err**2)) < 3 * FORCE_NOISE_N

    ext = [ln.replace(" 121#", " 00000121#") for ln in lines]
    (tmp_path / "ext.log").write_text("\n".join(ext) + "\n")
    c = process_recording(tmp_path / "ext.log")
    assert any("no frames of WFT_RL_Moment on can0, but" in w and "0x121 as a 29-bit identifier where the DBC "
               "says 11-bit" in w for w in c.warnings)
    assert not any("WFT_RL_Force" in w and "identifier" in w for w in c.warnings)
    assert c.signals["torque_nm"].isna().all()


# --------------------------------------------------------------------------- CLI
def test_cli_writes_csv_and_parquet(tmp_path, short_truth, capsys):
    from wheelsoil.cli import main

    info = write_recording(tmp_path / "r.mcap", short_truth, latency_s=0.1)
    assert main(["process", str(info["path"]), "-o", str(tmp_path / "s.csv")]) == 0
    out = capsys.readouterr().out
    assert "GNSS latency:" in out and "GPS time:" in out and "lost frames" in out and "valid samples" in out
    df = pd.read_csv(tmp_path / "s.csv")
    assert tuple(df.columns) == COLUMNS
    assert main(["process", str(info["path"]), "-o", str(tmp_path / "s.parquet"), "--rate", "50",
                 "--cutoff", "3"]) == 0
    pq = pd.read_parquet(tmp_path / "s.parquet")
    assert tuple(pq.columns) == COLUMNS and np.allclose(np.diff(pq["t_s"]), 0.02)
    assert main(["process", str(info["path"]), "-o", str(tmp_path / "s.txt")]) == 2
    assert "csv" in capsys.readouterr().err
    # an existing table is kept (refused before processing) unless --overwrite
    (tmp_path / "s.csv").write_text("kept\n")
    assert main(["process", str(info["path"]), "-o", str(tmp_path / "s.csv")]) == 2
    assert "s.csv exists (--overwrite replaces it)" in capsys.readouterr().err
    assert (tmp_path / "s.csv").read_text() == "kept\n"
    assert main(["process", str(info["path"]), "-o", str(tmp_path / "s.csv"), "--overwrite"]) == 0
    assert tuple(pd.read_csv(tmp_path / "s.csv").columns) == COLUMNS
    assert not list(tmp_path.glob(".*.part"))


def test_log_file_input_is_imported_first(tmp_path, short_truth):
    from wheelsoil.daq.convert import export_recording

    info = write_recording(tmp_path / "r.mcap", short_truth, latency_s=0.1)
    export_recording(info["path"], tmp_path / "r.log")
    a = process_recording(info["path"])
    b = process_recording(tmp_path / "r.log")
    assert any("imported" in w for w in b.warnings)
    assert b.gnss_latency_s == pytest.approx(a.gnss_latency_s, abs=1e-3)
    assert len(a.signals) == len(b.signals)
    np.testing.assert_allclose(b.signals["load_n"], a.signals["load_n"], atol=1.0, equal_nan=True)
    assert (a.signals["valid"] == b.signals["valid"]).mean() > 0.99
