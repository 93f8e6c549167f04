"""Inertia compensation (issue 10 item 2): the WFT measures Fx = Dp - m_w dV/dt and
My = T + I_w domega/dt (hardware.md); processing returns the soil's Dp and T."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from processing_sim import (FORCE_NOISE_N, MOMENT_NOISE_NM, WHEEL_INERTIA_KGM2, WHEEL_MASS_KG,  # noqa: E402
                            truth_profile, write_recording)

from wheelsoil.processing import process_recording  # noqa: E402
from wheelsoil.processing.filters import filter_to_grid  # noqa: E402


def _truth_on(res, truth, name):
    return np.interp(res.signals["t_s"].to_numpy(), truth.t_s, getattr(truth, name))


@pytest.fixture(scope="module")
def inertia_run(tmp_path_factory):
    """A run whose soil forces are smooth and whose WFT also carries the wheel's inertia."""
    truth = truth_profile(2)
    info = write_recording(tmp_path_factory.mktemp("inertia") / "run.mcap", truth, seed=3)
    on = process_recording(info["path"])
    off = process_recording(info["path"], inertia=False)
    return truth, on, off


def _rms(res, truth, col, mask):
    err = res.signals[col].to_numpy()[mask] - _truth_on(res, truth, col)[mask]
    return float(np.sqrt(np.mean(err ** 2)))


def test_shipped_config_has_wheel_mass_and_inertia():
    from wheelsoil.daq import load_vehicle_config

    cfg = load_vehicle_config()
    assert (cfg.wheel_mass_kg, cfg.wheel_inertia_kgm2) == (WHEEL_MASS_KG, WHEEL_INERTIA_KGM2)


def test_compensated_forces_equal_soil_forces_within_noise(inertia_run):
    truth, on, off = inertia_run
    s = on.signals
    acc = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    assert acc.sum() > 800
    # the wheel spins up fast in the accelerate phase: uncompensated, My is far off T
    assert _rms(off, truth, "torque_nm", acc) > 5 * MOMENT_NOISE_NM
    assert _rms(on, truth, "torque_nm", acc) <= MOMENT_NOISE_NM
    assert _rms(on, truth, "drawbar_pull_n", acc) <= FORCE_NOISE_N
    m = s["valid"].to_numpy()
    assert _rms(on, truth, "torque_nm", m) <= MOMENT_NOISE_NM
    assert _rms(on, truth, "drawbar_pull_n", m) <= FORCE_NOISE_N


def test_uncompensated_columns_and_result_fields(inertia_run):
    truth, on, off = inertia_run
    s = on.signals
    # fx_n / my_nm are what the WFT measured: the same with and without compensation
    np.testing.assert_allclose(s["fx_n"], off.signals["drawbar_pull_n"], equal_nan=True)
    np.testing.assert_allclose(s["my_nm"], off.signals["torque_nm"], equal_nan=True)
    # and compensated = measured + correction, the correction of the stated size
    corr_t = (s["my_nm"] - s["torque_nm"]).abs().max()
    corr_f = (s["drawbar_pull_n"] - s["fx_n"]).abs().max()
    true_t = WHEEL_INERTIA_KGM2 * np.abs(np.gradient(truth.omega_radps, truth.t_s)).max()
    assert on.inertia["applied"] is True and off.inertia["applied"] is False
    assert on.inertia["wheel_mass_kg"] == WHEEL_MASS_KG
    assert on.inertia["wheel_inertia_kgm2"] == WHEEL_INERTIA_KGM2
    assert on.inertia["max_abs_torque_nm"] == pytest.approx(corr_t, rel=1e-6)
    assert on.inertia["max_abs_force_n"] == pytest.approx(corr_f, rel=1e-6)
    assert 0.7 * true_t < corr_t < 1.1 * true_t
    assert "inertia compensated" in on.summary() and "NOT compensated" in off.summary()
    assert any("--no-inertia" in w for w in off.warnings)


def test_distance_is_integral_of_speed(inertia_run):
    truth, on, _ = inertia_run
    s = on.signals
    d = s["distance_m"].to_numpy()
    fin = np.isfinite(d)
    assert fin.mean() > 0.9
    assert np.all(np.diff(d[fin]) >= -1e-3)  # the truth never reverses (GNSS noise at standstill)
    # total distance: integral of the true speed over the same span, within 1 %
    t = s["t_s"].to_numpy()[fin]
    true_d = np.trapezoid(np.interp(np.linspace(t[0], t[-1], 20001), truth.t_s, truth.speed_mps),
                          np.linspace(t[0], t[-1], 20001))
    assert d[fin][-1] - d[fin][0] == pytest.approx(true_d, rel=0.01)


def test_derivative_is_the_filtered_derivative():
    """d/dt of the filtered series = the same filter applied to dx/dt (zero phase, same cutoff)."""
    fs = 100.0
    t = np.arange(0, 20, 1 / fs)
    x = np.sin(2 * np.pi * 0.7 * t) + 0.5 * np.sin(2 * np.pi * 1.9 * t + 0.3) + 0.2 * np.sin(2 * np.pi * 12 * t)
    dx = (2 * np.pi * 0.7 * np.cos(2 * np.pi * 0.7 * t) + 0.5 * 2 * np.pi * 1.9 * np.cos(2 * np.pi * 1.9 * t + 0.3)
          + 0.2 * 2 * np.pi * 12 * np.cos(2 * np.pi * 12 * t))
    grid = np.arange(0, 20, 0.01)
    _, d1 = filter_to_grid(t, x, 1 / fs, grid, 5.0, derivative=True)
    d2 = filter_to_grid(t, dx, 1 / fs, grid, 5.0)
    mid = (grid > 3) & (grid < 17)  # away from the ends' padding
    assert np.max(np.abs(d1[mid] - d2[mid])) < 0.02 * np.max(np.abs(d2[mid]))
    # and the 12 Hz component (above the 5 Hz cutoff) is gone from the derivative, as from x
    true_lo = dx - 0.2 * 2 * np.pi * 12 * np.cos(2 * np.pi * 12 * t)
    assert np.max(np.abs(d1[mid] - np.interp(grid[mid], t, true_lo))) < 0.1


def test_cli_no_inertia_and_wheel_radius(tmp_path, capsys):
    import pandas as pd

    from wheelsoil.cli import main

    info = write_recording(tmp_path / "r.mcap", truth_profile(1), seed=1)
    assert main(["process", str(info["path"]), "-o", str(tmp_path / "a.csv"), "--no-inertia",
                 "--wheel-radius", "0.45"]) == 0
    out = capsys.readouterr().out
    assert "NOT compensated" in out and "WHEEL RADIUS CONFLICT" in out
    df = pd.read_csv(tmp_path / "a.csv")
    assert {"distance_m", "fx_n", "my_nm"} <= set(df.columns)
    np.testing.assert_allclose(df["torque_nm"], df["my_nm"], equal_nan=True)
