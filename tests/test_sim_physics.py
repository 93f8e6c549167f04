"""Physical plausibility of the simulated runs: the vehicle moves by its wheels' drawbar pull,
the transducer carries the wheel's inertia, impossible runs are refused."""

from __future__ import annotations

import numpy as np
import pytest

from wheelsoil.simulate import simulate_run
from wheelsoil.sim.vehicle import VehicleParams


@pytest.fixture(scope="module")
def run():
    return simulate_run("sand", effect="none", seed=21, duration_s=60.0, added_load_n=5000.0,
                        soil_variability=0.0)


def test_vehicle_accelerates_only_by_the_wheels_summed_drawbar_pull(run):
    d = run.dynamics
    m = d["mass_kg"]
    net = 2 * d["dp_front_n"] + 2 * d["dp_rear_n"] - d["resistance_n"]
    moving = d["phase"] != "standstill"
    a = d["accel_mps2"]
    # Newton: m dV/dt = sum of the four wheels' Dp - grade/air resistance, except where the brakes
    # hold the vehicle at V = 0 (then a = 0 while the net force is negative)
    held = (d["speed_mps"] <= 0) & (net < 0)
    np.testing.assert_allclose(m * a[moving & ~held], net[moving & ~held], rtol=1e-9, atol=1e-6)
    # speed changes only by the integral of that acceleration, never below zero
    dv = np.diff(d["speed_mps"])
    assert np.all(d["speed_mps"] >= 0)
    up = dv > 1e-9
    assert np.all(net[:-1][up] > 0), "the vehicle gained speed without a positive summed drawbar pull"
    # it really drives: slip sweeps to ~0.9 and the speed reaches a few m/s
    assert d["speed_mps"].max() > 2.0
    assert np.nanmax(run.truth.slip[run.truth.phase == "accel"]) > 0.8


def test_instrumented_wheel_truth_is_the_force_the_dynamics_used(run):
    """The left rear wheel's exact (quadrature) Dp at 500 Hz equals the tabulated force the dynamics
    integrated for a rear wheel, within the table's interpolation error."""
    tr, d = run.truth, run.dynamics
    t = np.arange(len(d["t_s"])) * 0.01
    drive = (d["phase"] == "accel") & (d["slip"] > 0.05)
    dp_exact = np.interp(t[drive], tr.t_s - tr.t_s.iloc[0], tr.drawbar_pull_n)
    assert np.max(np.abs(dp_exact - d["dp_rear_n"][drive])) < 5.0 + 2 * run.info["force_table_max_error_n"]
    assert run.info["force_table_max_error_n"] < 5.0


def test_inertia_of_the_wheel_is_in_the_transducer_signals(run):
    tr = run.truth
    veh = VehicleParams()
    np.testing.assert_allclose(tr.fx_n, tr.drawbar_pull_n - veh.wheel_mass_kg * tr.accel_mps2, atol=1e-9)
    np.testing.assert_allclose(tr.my_nm, tr.torque_nm + veh.wheel_inertia_kgm2 * tr.omega_dot_radps2, atol=1e-9)
    # the rates are those of the speeds: integrate them back
    dt = 1.0 / 500.0
    v = tr.speed_mps.to_numpy()
    assert np.max(np.abs(np.cumsum(tr.accel_mps2.to_numpy()[:-1]) * dt - (v[1:] - v[0]))) < 0.02
    # in a slip sweep the wheel's spin-up torque stands far above the 4 N m torque noise
    assert np.max(np.abs(tr.my_nm - tr.torque_nm)) > 40.0


def test_a_run_the_vehicle_could_not_drive_is_refused():
    # the paper's clay, default 0.47 x 0.32 m wheel, 8 + 3 kN: Wong's Dp < 0 at every slip
    with pytest.raises(ValueError, match="cannot move"):
        simulate_run("clay", seed=1, duration_s=30.0, added_load_n=3000.0)
    # the equivalent rigid wheel of the deflected tyre moves
    r = simulate_run("clay", seed=1, duration_s=30.0, added_load_n=3000.0, wheel=(0.55, 0.40))
    assert r.info["vehicle"]["accel_max_mps2"] > 0.15


def test_wheel_speed_stays_in_the_sensor_range_and_loads_transfer_with_acceleration(run):
    tr, d = run.truth, run.dynamics
    assert tr.omega_radps.max() * 60 / (2 * np.pi) <= 655.0
    # pitch: the rear wheels carry more while accelerating than while braking
    acc = d["phase"] == "accel"
    brk = (d["phase"] == "brake") & (d["speed_mps"] > 0.5)
    assert d["load_rear_n"][acc].mean() > d["load_rear_n"][brk].mean() + 100.0
    assert d["load_rear_n"].mean() == pytest.approx(13000.0, rel=0.05)


def test_tow_procedure_holds_slip_levels_at_a_held_speed_by_newton():
    """The steady drawbar-pull test: the towed load vehicle's brake force is never negative (it
    cannot push), Newton holds with it, and the slip is held at several levels while the speed
    stays near the test speed (the holds are steady: no acceleration to speak of)."""
    r = simulate_run("sand", effect="none", seed=8, duration_s=90.0, added_load_n=5000.0, procedure="tow")
    d = r.dynamics
    m = d["mass_kg"]
    tow = d["tow_n"]
    assert np.all(tow >= 0) and tow.max() > 1000.0
    net = 2 * d["dp_front_n"] + 2 * d["dp_rear_n"] - d["resistance_n"] - tow
    moving = (d["phase"] != "standstill") & ~((d["speed_mps"] <= 0) & (net < 0))
    np.testing.assert_allclose(m * d["accel_mps2"][moving], net[moving], rtol=1e-9, atol=1e-6)
    held = d["phase"] == "tow"
    s = d["slip"][held]
    # slip levels from ~0.1 to ~0.9, each held: most steps change the slip by little
    assert s.min() < 0.2 and s.max() > 0.7
    assert np.median(np.abs(np.diff(s))) < 0.002
    steady = held & (np.abs(d["accel_mps2"]) < 0.05)
    assert steady.mean() > 0.5 * held.mean(), "the holds should be steady"
    assert r.info["procedure"] == "tow"
    # from the top down: the same passes, the first level the highest
    down = simulate_run("sand", effect="none", seed=8, duration_s=90.0, added_load_n=5000.0, procedure="tow-down")
    dd = down.dynamics
    first = dd["slip"][(dd["phase"] == "tow") & (dd["cycle"] == 0)]
    assert np.median(first[: first.size // 4]) > 0.6 > np.median(first[-first.size // 4:])
    with pytest.raises(ValueError, match="procedure"):
        simulate_run("sand", duration_s=60.0, procedure="coast")
