"""GNSS latency when the front wheels are no free-rolling reference (all wheels driven,
locked differentials): found from the vehicle dynamics (GNSS dV/dt against the measured Fx),
not left at the edge of the search range."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from processing_sim import truth_dynamic, write_recording  # noqa: E402

from wheelsoil.processing import process_recording  # noqa: E402


@pytest.fixture(scope="module")
def truth():
    return truth_dynamic(3)


def test_coupled_front_wheels_latency_from_vehicle_dynamics(truth, tmp_path):
    info = write_recording(tmp_path / "awd.mcap", truth, fronts_coupled=True, latency_s=0.1, seed=7)
    res = process_recording(info["path"])
    assert res.gnss_latency_s == pytest.approx(0.1, abs=0.02)
    assert 0 < res.gnss_latency_stderr_s < 0.02
    assert "vehicle dynamics" in res.latency_reference
    assert any("front wheels turn with the measured wheel" in w for w in res.warnings)
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    err = s["slip"].to_numpy()[m] - np.interp(s["t_s"].to_numpy()[m], truth.t_s, truth.slip)
    assert np.sqrt(np.mean(err ** 2)) < 0.02


def test_free_rolling_fronts_still_the_reference(truth, tmp_path):
    info = write_recording(tmp_path / "rwd.mcap", truth, latency_s=0.1, seed=7)
    res = process_recording(info["path"])
    assert res.gnss_latency_s == pytest.approx(0.1, abs=0.005)
    assert res.latency_reference.startswith("front wheels")


def test_lost_reference_samples_leave_a_finite_standard_error():
    """Gaps in the reference (lost frames: NaN) must not turn the estimate's standard error into
    NaN: the vehicle-dynamics estimate (GNSS dV/dt against the filtered Fx, which has NaN gaps)
    was dropped as 'no finite standard error' and a wrong slip-traction latency was applied."""
    from wheelsoil.processing.timesync import estimate_latency

    rng = np.random.default_rng(3)
    t_ref = np.arange(0.0, 120.0, 0.01)
    v_ref = 5.0 + 2.0 * np.sin(0.5 * t_ref) + np.sin(1.3 * t_ref)
    for start in rng.integers(100, t_ref.size - 100, size=40):  # 40 gaps of 5-30 samples
        v_ref[start:start + rng.integers(5, 30)] = np.nan
    t_g = np.arange(0.0, 120.0, 0.05)
    v_true = 5.0 + 2.0 * np.sin(0.5 * (t_g - 0.12)) + np.sin(1.3 * (t_g - 0.12))
    v_g = v_true + rng.normal(0.0, 0.02, t_g.size)
    est = estimate_latency(t_g, v_g, t_ref, v_ref)
    assert np.isfinite(est.stderr_s) and 0 < est.stderr_s < 0.01
    assert abs(est.latency_s - 0.12) < 3 * est.stderr_s + 0.002


def test_wheel_speeds_read_later_than_the_gnss_speed(truth, tmp_path):
    """A wheel-speed module that reads 60 ms late (a tone wheel reporting its last tooth period, a
    gateway) while the GNSS speed arrives 20 ms late: the module's lag is found against the
    transducer's wheel angle (its own clock, the forces' time base) and removed, so the GNSS latency
    found is its own and slip belongs to the moment of the forces. Before, the latency was sought
    from 0 against the late wheel speeds: none was found (-40 ms relative), or a wrong one."""
    info = write_recording(tmp_path / "late_wheels.mcap", truth, latency_s=0.02, wheel_speed_lag_s=0.06, seed=7)
    res = process_recording(info["path"])
    lag = res.quality["wheel_speed_lag"]
    assert lag["applied"] and lag["estimate_s"] == pytest.approx(0.06, abs=0.003) and lag["fronts_shifted"]
    assert any("read" in w and "late against the transducer's clock" in w for w in res.warnings)
    assert res.gnss_latency_s == pytest.approx(0.02, abs=0.005)
    assert res.quality["latency"]["reliable"], res.quality["latency"]["reasons"]
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    err = s["slip"].to_numpy()[m] - np.interp(s["t_s"].to_numpy()[m], truth.t_s, truth.slip)
    assert np.sqrt(np.mean(err ** 2)) < 0.01


def test_no_module_lag_leaves_the_wheel_speeds_as_they_are(truth, tmp_path):
    info = write_recording(tmp_path / "plain.mcap", truth, latency_s=0.1, seed=7)
    lag = process_recording(info["path"]).quality["wheel_speed_lag"]
    assert abs(lag["estimate_s"]) < 0.003 and not lag["applied"]


def test_a_reference_read_later_than_the_gnss_speed_gives_a_negative_latency():
    """Without the transducer's angle the wheel speeds cannot be put on its clock, and the GNSS
    speed is aligned with them as they are: its delay relative to them may be negative."""
    from wheelsoil.processing.timesync import estimate_latency

    rng = np.random.default_rng(5)
    t_ref = np.arange(0.0, 120.0, 0.01)
    speed = lambda t: 5.0 + 2.0 * np.sin(0.5 * t) + np.sin(1.3 * t)  # noqa: E731
    v_ref = speed(t_ref - 0.05)  # the reference reads 50 ms late
    t_g = np.arange(0.0, 120.0, 0.05)
    v_g = speed(t_g - 0.02) + rng.normal(0.0, 0.02, t_g.size)  # the GNSS 20 ms late
    est = estimate_latency(t_g, v_g, t_ref, v_ref, min_latency_s=-0.1)
    assert est.latency_s == pytest.approx(-0.03, abs=0.003) and not est.note
    assert "edge" in estimate_latency(t_g, v_g, t_ref, v_ref).note  # searched from 0: an edge hit


def test_another_wheel_mass_and_inertia_given(truth, tmp_path):
    """A wheel of 40 kg and 5 kg m^2 instead of the configured 80 kg and 11.5 kg m^2: with the
    configured values the compensation adds (11.5 - 5) domega/dt of torque that is not there;
    given (--wheel-mass, --wheel-inertia) the compensated torque is what the configured wheel's
    recording of the same run (same noise) gives."""
    light = write_recording(tmp_path / "light.mcap", truth, wheel_mass_kg=40.0, wheel_inertia_kgm2=5.0, seed=3)
    usual = write_recording(tmp_path / "usual.mcap", truth, seed=3)
    ref = process_recording(usual["path"]).signals
    given = process_recording(light["path"], wheel_mass_kg=40.0, wheel_inertia_kgm2=5.0)
    assumed = process_recording(light["path"]).signals
    assert given.inertia["wheel_inertia_kgm2"] == 5.0 and "given" in given.inertia["source"]

    def off(s, col):
        d = s[col].to_numpy() - ref[col].to_numpy()
        return np.sqrt(np.nanmean(d ** 2))

    for col in ("torque_nm", "drawbar_pull_n"):
        assert off(given.signals, col) < 0.15 * off(assumed, col), col  # (quantisation differs)
    with pytest.raises(ValueError, match="--wheel-inertia"):
        process_recording(light["path"], wheel_inertia_kgm2=-1.0)


def test_a_lag_of_the_measured_wheels_channel_alone_leaves_the_fronts(truth, tmp_path):
    """Only the measured wheel's channel lags (100 ms: a filter in its sensor): its times are moved
    back, the fronts' are not (shifting them too would put the GNSS latency 100 ms off and make it
    disagree with the slip-traction estimate, which needs no front wheel)."""
    info = write_recording(tmp_path / "late_rl.mcap", truth, latency_s=0.12, rl_lag_s=0.1, seed=7)
    res = process_recording(info["path"])
    lag = res.quality["wheel_speed_lag"]
    assert lag["applied"] and lag["estimate_s"] == pytest.approx(0.1, abs=0.003) and not lag["fronts_shifted"]
    assert res.gnss_latency_s == pytest.approx(0.12, abs=0.005) and res.quality["latency"]["reliable"]
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    err = s["slip"].to_numpy()[m] - np.interp(s["t_s"].to_numpy()[m], truth.t_s, truth.slip)
    assert np.sqrt(np.mean(err ** 2)) < 0.01


def test_a_module_timed_per_tooth_is_found_and_removed(truth, tmp_path, monkeypatch):
    """A wheel-speed module that times each wheel over its last tooth interval (48 teeth: one tooth
    period, 2 pi / (48 omega), late, plus 5 ms of its own) while the GNSS speed arrives 80 ms late:
    the delay's growth at low speed is found against the transducer's wheel angle and each reading
    moved back by its own delay, the fronts' too, so the GNSS latency found against the free-rolling
    fronts is its own. With one constant shift (the per-tooth fit switched off) the fronts, slower
    than the slipping measured wheel, stay late and the latency comes out further off."""
    import wheelsoil.processing.pipeline as pp

    pitch = 2 * np.pi / 48
    info = write_recording(tmp_path / "teeth.mcap", truth, latency_s=0.08, wheel_speed_lag_s=0.005,
                           wheel_speed_pitch_rad=pitch, seed=7)
    res = process_recording(info["path"])
    q = res.quality["wheel_speed_lag"]
    tooth = q["per_tooth"]
    assert tooth["applied"] and q["fronts_shifted"] and q["fronts_pitch"]["shared"], q
    assert q["fronts_pitch"]["pitch_rad"] == pytest.approx(pitch, rel=0.15)
    assert tooth["pitch_rad"] == pytest.approx(pitch, rel=0.1)
    assert tooth["lag_s"] == pytest.approx(0.005, abs=0.003)
    assert any("a tone wheel timed per tooth" in w for w in res.warnings)
    err = abs(res.gnss_latency_s - 0.08)
    assert err < 0.005
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    slip_err = s["slip"].to_numpy()[m] - np.interp(s["t_s"].to_numpy()[m], truth.t_s, truth.slip)
    assert np.sqrt(np.mean(slip_err ** 2)) < 0.01

    monkeypatch.setattr(pp, "TOOTH_LAG_MIN_Z", np.inf)  # the constant shift alone
    const = process_recording(info["path"])
    assert not const.quality["wheel_speed_lag"]["per_tooth"]["applied"]
    assert abs(const.gnss_latency_s - 0.08) > err + 0.005


@pytest.mark.parametrize("traction", [True, False])
def test_a_per_tooth_delay_of_the_measured_wheel_alone_leaves_the_fronts(truth, tmp_path, monkeypatch, traction):
    """The measured wheel timed per tooth (48 teeth) while the fronts, in the same message, carry no
    delay (another module reads them): their own delay against the GNSS speed does not grow as they
    slow, so only the measured wheel's readings move back (moving the fronts' back by their own tooth
    period too would put the GNSS latency against them some 25 ms late). The fronts' own fit needs no
    slip-traction estimate: the same without one."""
    import wheelsoil.processing.pipeline as pp

    if not traction:
        def no_traction(*a, **k):
            raise ValueError("switched off by the test")
        monkeypatch.setattr(pp, "estimate_latency_traction", no_traction)
    info = write_recording(tmp_path / "teeth_rear.mcap", truth, latency_s=0.08, wheel_speed_lag_s=0.005,
                           wheel_speed_pitch_rad=2 * np.pi / 48, fronts_undelayed=True, seed=7)
    res = process_recording(info["path"])
    q = res.quality["wheel_speed_lag"]
    assert q["per_tooth"]["applied"] and not q["fronts_shifted"], q
    assert q["fronts_pitch"]["shared"] is False
    assert abs(q["fronts_pitch"]["pitch_rad"]) < 3 * q["fronts_pitch"]["stderr_pitch_rad"] + 0.01
    assert (res.quality["latency"]["candidates"]["traction"]["estimate_s"] is None) != traction
    assert any("not as late as the measured wheel's" in w for w in res.warnings)
    assert res.gnss_latency_s == pytest.approx(0.08, abs=0.005)


def test_a_constant_module_lag_is_not_taken_for_a_per_tooth_one(truth, tmp_path):
    """The module 60 ms late at every speed: the per-tooth pitch is not shown above zero, and the
    constant shift is what is removed."""
    info = write_recording(tmp_path / "late.mcap", truth, latency_s=0.02, wheel_speed_lag_s=0.06, seed=11)
    q = process_recording(info["path"]).quality["wheel_speed_lag"]
    assert q["applied"] and not q["per_tooth"]["applied"] and "standard errors above zero" in q["per_tooth"]["note"]


def test_estimate_tooth_lag_recovers_a_known_delay():
    """``omega_mod(t) = omega(t - 8 ms - 0.2 rad / omega)`` on a speed swinging between 1 and 9 rad/s:
    the fit returns the constant and the pitch within a few standard errors, and the moved times
    (:meth:`ToothLag.unlag`) put the readings back on the true speed."""
    from wheelsoil.processing.timesync import estimate_tooth_lag

    rng = np.random.default_rng(2)
    omega = lambda t: 5.0 + 4.0 * np.sin(0.7 * t)  # noqa: E731
    t_ref = np.arange(0.0, 60.0, 0.002)
    t_mod = np.arange(0.0, 60.0, 0.01)
    delay = 0.008 + 0.2 / omega(t_mod)  # the delay at the current speed (the module's 1/omega)
    w_mod = omega(t_mod - delay) * (1 + rng.normal(0, 0.002, t_mod.size))
    fit = estimate_tooth_lag(t_mod, w_mod, omega(t_mod), t_ref, omega(t_ref), start_lag_s=0.03,
                             min_lag_s=-0.1, max_lag_s=0.3, min_omega_radps=0.5)
    assert abs(fit.pitch_rad - 0.2) < max(4 * fit.stderr_pitch_rad, 0.004)
    assert abs(fit.lag_s - 0.008) < max(4 * fit.stderr_lag_s, 0.0005)
    keep = fit.unlag(t_mod, omega(t_mod))
    moved = t_mod[keep] - fit.delay_s(omega(t_mod[keep]))
    assert np.all(np.diff(moved) > 0)
    unmoved = np.sqrt(np.mean((w_mod - omega(t_mod)) ** 2))
    assert np.sqrt(np.mean((w_mod[keep] - omega(moved)) ** 2)) < 0.2 * unmoved


def test_a_per_tooth_delay_at_standstill_is_the_slowest_fitted_speeds():
    """Below the slowest speed fitted (and for a lost reading) the delay is that speed's, not
    extrapolated towards infinity; a wheel slowing to rest keeps its readings in time order, and
    only the readings its growing delay would put before earlier ones are dropped: no more than
    that growth's worth."""
    from wheelsoil.processing.timesync import ToothLag

    lag = ToothLag(lag_s=0.005, pitch_rad=0.13, stderr_lag_s=0.001, stderr_pitch_rad=0.01, gain=1.0,
                   residual_rms=0.01, n=1000, max_s=0.3, min_omega_radps=1.0)
    assert np.allclose(lag.delay_s(np.array([0.0, np.nan, 0.5, -1.0])), 0.135)
    t = np.arange(0.0, 5.0, 0.01)
    w = np.clip(10.0 * (1.0 - t / 0.5), 0.0, None)  # 10 rad/s to rest in 0.5 s, then standing
    keep = lag.unlag(t, w)
    moved = t[keep] - lag.delay_s(w[keep])
    assert np.all(np.diff(moved) > 0)
    growth = lag.delay_s(np.array([1.0]))[0] - lag.delay_s(np.array([10.0]))[0]
    assert 0 < np.count_nonzero(~keep) * 0.01 <= growth + 0.01
