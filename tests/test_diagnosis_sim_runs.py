"""The diagnosis on physical-simulator runs whose cause a simpler rule got wrong (in process:
simulate, write the MCAP, ``run_fit`` as a user would).

- A deflecting tyre (Wong's equivalent rigid wheel, larger than the tyre, at the same slip)
  is on no list: a 5-parameter terrain re-fit mimics it at one load, so without the
  equivalent-rigid-wheel stand-in (``tyre``) it was named a terrain mismatch.  It must not
  be named a listed cause, and the stand-in must explain it at least as well as the
  terrain re-fit.
- A terrain mismatch (cohesion off) is also fitted by Vasil'ev + terrain and Ding + terrain,
  whose slip-sinkage part does not pay off out of sample: their evidence counts for the
  terrain re-fit they contain, so the mismatch is named.
- A cohesion mismatch that a Wong-Reece stress shift fits as well out of sample (with
  fewer parameters, so more in-sample evidence) must not be named a stress distribution:
  a listed cause is named only over the other supported listed causes it holds against out of
  sample (it improves on them, or has decisive evidence and predicts new data no worse).
- A large stress shift on the same clay: the terrain re-fit also lowers the drawbar pull error
  but has far less evidence and does not predict new data better, so the stress distribution
  is named (it need not beat the re-fit significantly out of sample: not being worse suffices
  when the evidence is decisive).
- Another patch of ground from some point of the run on is a step along the run: the
  change-point test finds it in Wong's residuals and the step hypothesis (``drift_step``)
  explains it where a linear drift cannot.
- A soil whose stiffness follows the load (k_eq (W / W_static)^beta) is on no list: at the
  driving load, a few per cent above the static one, it is a constant k_eq mismatch to a
  terrain re-fit, which was named.  The load-dependence stand-in (``load_k``, referenced to
  the run's static load) explains it as well, so no listed cause is named.
- Benchmark seed 1398 (clay, default wheel, cohesion x0.82, 0.9 % lost frames, 170 ms GNSS
  latency) was named a stress distribution: the lost frames made the vehicle-dynamics latency
  estimate's standard error NaN, so a slip-traction estimate 134 ms off was applied; the
  terrain re-fit's Occam factor was 7.5 nats too large (its information matrix, in SI units,
  lost the c-phi direction to rounding); and a mismatch in one value had only the five-value
  re-fit.  The latency must be found and no wrong cause named.
- A transducer whose My zero drifts over the run is on no list: a terrain drift shifts the
  torque along the run too and was named.  The zero-drift stand-in (``zero_drift``) explains
  it as well, so no listed cause is named.
- Benchmark seeds on soils of the built-in library (``bench_diagnosis.py --terrains library``),
  which the rule was not developed on:
  - 2133, a 13 % My gain on a firm loam, was named slip sinkage (Ding + terrain): the
    sensor-gain stand-in scaled the compensated torque, not the reading with the wheel's
    inertia in it, and left 14 N m of the spin-up inertia's share unexplained;
  - 2203, a 0.75 deg wheel-angle offset (a Dp offset proportional to the load), was named a
    terrain mismatch: the terrain re-fit predicted the drawbar pull worse out of sample than
    the Dp-resistance stand-in, and won on a 0.4 % torque error from the soil's roughness;
  - 2209, a torque zero drift of 122 N m (under 1 % of the torque), was ``none`` at "high"
    while the posterior gave the zero drift probability 1;
  - 3172, a 1.03 deg wheel-angle offset on a sandy loam (Dp +250 N, 15 %), was named a
    terrain mismatch: the terrain re-fit explained the drawbar pull no better out of sample
    than the Dp-only stand-in, and won the posterior on a 0.16 % torque error, which the
    offset makes by tilting the measured load (W' = W cos d - Fx sin d).  The angle-offset
    stand-in (``angle_offset``) turns the hub forces as the offset does and explains both.
- Benchmark seed 2504, a Wong-Reece stress shift on clay (Wong's torque 13 % off): once a named
  cause had to hold out of sample against the stand-ins for causes on no list, the Dp-only
  drift stand-in, 1 N better on the held-out drawbar pull, blocked it, although it leaves the
  whole torque error that the stress shift removes.  A rival that leaves a relevant error the
  candidate explains does not explain the data as well.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from wheelsoil.model import load_terrain
from wheelsoil.pipeline import run_fit
from wheelsoil.simulate import draw_case, judge, simulate_run, write_simulation

pytestmark = pytest.mark.slow


def _fit(tmp_path, terrain, **case):
    run = simulate_run(load_terrain(terrain), duration_s=150.0, gnss_latency_s=0.05, drop_rate=0.002,
                       front_wheels="reference", **case)
    rec = write_simulation(run, tmp_path / "run.mcap")
    report = run_fit([rec], terrain, tmp_path / "report")
    return run, report


def test_a_deflecting_tyre_is_not_named_a_terrain_mismatch(tmp_path):
    run, report = _fit(tmp_path, "clay", effect="tyre_deflection", params={"kappa": 0.3}, wheel=(0.47, 0.32),
                       seed=9155)
    d = report["diagnosis"]
    v = judge(run.info, report)
    assert not v["wrong_cause"], d["summary"]
    p = d["probabilities"]
    assert p.get("tyre", 0.0) >= p.get("terrain", 0.0), p


def test_a_terrain_mismatch_shared_with_slip_sinkage_combinations_is_named(tmp_path):
    run, report = _fit(tmp_path, "clay", effect="terrain_mismatch", wheel=(0.55, 0.40), added_load_n=3000.0,
                       params={"changes": {"c": {"kind": "factor", "value": 2.0}}}, seed=9180)
    d = report["diagnosis"]
    assert d["effect"] == "terrain_mismatch", d["summary"]
    assert d["effect_probabilities"]["terrain_mismatch"] >= 0.9


def test_another_patch_of_ground_is_a_terrain_drift_with_a_step(tmp_path):
    run, report = _fit(tmp_path, "clay", effect="terrain_drift", wheel=(0.55, 0.40), added_load_n=3000.0,
                       params={"changes": {"n": {"kind": "delta", "value": -0.09}}, "mode": "patch",
                               "change_at": 0.62}, seed=9038)
    d = report["diagnosis"]
    assert d["effect"] == "terrain_drift", d["summary"]
    assert d["model"] in ("drift_step", "drift_step_n"), d["summary"]
    p = d["probabilities"]
    step = sum(v for k, v in p.items() if k.startswith("drift_step"))
    assert step > sum(v for k, v in p.items() if k.startswith("drift_") and not k.startswith("drift_step"))


def test_a_drift_in_one_soil_value_is_named_against_the_two_parameter_stand_ins(tmp_path):
    # k_eq compacting along the run: Dp moves, the torque hardly; the ten-parameter drift pays an
    # Occam factor that let the Dp-only drift stand-in (dp_drift, 2 parameters) out-score it
    run, report = _fit(tmp_path, "sand", effect="terrain_drift", wheel=(0.47, 0.32), added_load_n=5000.0,
                       params={"changes": {"k_eq": {"kind": "factor", "value": 0.75}}, "mode": "compaction"},
                       seed=9415)
    d = report["diagnosis"]
    assert d["effect"] == "terrain_drift", d["summary"]
    assert d["model"] == "drift_k_eq", d["summary"]
    assert d["probabilities"]["drift_k_eq"] > 10 * d["probabilities"].get("dp_drift", 0.0)
    # the five-value drift does not explain the data best: its narrower forms with the levels re-fitted are
    # not tried (the gate that spares their fits)
    assert "drift_k_eq+terrain" not in d["models"], sorted(d["models"])


def test_a_drift_in_one_soil_value_on_a_field_soil_off_the_lab_is_named(tmp_path):
    # the field soil a fraction of the lab's uncertainty off in every value (as every independent generator
    # draws it), k_eq compacting along the run: with the other four values at the lab's the one-value drift
    # cannot fit, and only the five-value drift (a catch-all, no cause named) did; with the five levels
    # re-fitted the k_eq drift explains it.  (Seeds 9501 and 9503 of this case stay `unexplained`: the
    # five-value drift predicts the drawbar pull a little better out of sample.)
    lab = load_terrain("sand")
    field = dataclasses.replace(lab, c=lab.c * 1.2, phi=lab.phi + math.radians(1.2), K=lab.K * 0.85, n=lab.n + 0.04,
                                kphi=lab.kphi * 1.1)
    run = simulate_run(field, effect="terrain_drift", wheel=(0.47, 0.32), added_load_n=5000.0,
                       params={"changes": {"k_eq": {"kind": "factor", "value": 0.7}}, "mode": "compaction"},
                       seed=9502, duration_s=150.0, gnss_latency_s=0.05, drop_rate=0.002, front_wheels="reference")
    report = run_fit([write_simulation(run, tmp_path / "run.mcap")], "sand", tmp_path / "report")
    d = report["diagnosis"]
    assert d["effect"] == "terrain_drift", d["summary"]
    assert d["model"] == "drift_k_eq+terrain", d["summary"]
    fitted = d["models"]["drift_k_eq+terrain"]["params"]["g_lnk"]
    assert abs(fitted["value"] - 2 * math.log(0.7)) < 3 * fitted["se"] + 0.1  # lab/0.7 to lab x 0.7


def test_another_patch_of_ground_differing_in_two_values_on_a_field_soil_is_named(tmp_path):
    # the field soil off the lab as above, another patch of ground from 55 % of the run with another k_eq and
    # phi (an independent generator's patches changed two values): only the five-value step explained it
    # (a catch-all, no cause named); the pair's step with the five levels re-fitted does
    lab = load_terrain("sand")
    field = dataclasses.replace(lab, c=lab.c * 1.2, phi=lab.phi + math.radians(1.2), K=lab.K * 0.85, n=lab.n + 0.04,
                                kphi=lab.kphi * 1.1)
    run = simulate_run(field, effect="terrain_drift", wheel=(0.47, 0.32), added_load_n=5000.0,
                       params={"changes": {"k_eq": {"kind": "factor", "value": 0.8}, "phi": {"kind": "delta", "value": -2.5}},
                               "mode": "patch", "change_at": 0.55},
                       seed=9511, duration_s=150.0, gnss_latency_s=0.05, drop_rate=0.002, front_wheels="reference")
    report = run_fit([write_simulation(run, tmp_path / "run.mcap")], "sand", tmp_path / "report")
    d = report["diagnosis"]
    assert d["effect"] == "terrain_drift", d["summary"]
    assert d["model"] == "drift_step_k_eq_phi+terrain", d["summary"]
    assert d["models"][d["model"]]["params"]["g_phi"]["value"] < 0  # phi falls on the second patch


def test_a_terrain_mismatch_a_stress_shift_fits_as_well_is_not_named_a_stress_distribution(tmp_path):
    run, report = _fit(tmp_path, "clay", effect="terrain_mismatch", wheel=(0.55, 0.40), added_load_n=3000.0,
                       params={"changes": {"c": {"kind": "factor", "value": 0.72}}}, seed=436)
    d = report["diagnosis"]
    v = judge(run.info, report)
    assert not v["wrong_cause"], d["summary"]


def test_a_stress_shift_the_terrain_refit_does_not_predict_better_is_named(tmp_path):
    run, report = _fit(tmp_path, "clay", effect="stress_distribution", wheel=(0.55, 0.40), added_load_n=3000.0,
                       params={"a1": 0.37, "a2": 0.0}, seed=9838)
    d = report["diagnosis"]
    assert d["effect"] == "stress_distribution", d["summary"]
    assert d["probabilities"]["wong_reece"] > 10 * d["probabilities"].get("terrain", 0.0)
    # the shift needs no re-fitted soil here (the simulator's soil is the lab's): the look-alike on a re-fitted
    # soil is not tried (its evidence gate, Hypothesis.tried_if), the one on the lab's soil is
    assert "shear_slip" in d["tried"] and "shear_slip+terrain" not in d["tried"], d["tried"]


def test_a_load_dependent_soil_is_not_named_a_terrain_mismatch(tmp_path):
    run, report = _fit(tmp_path, "sand", effect="load_dependent", wheel=(0.55, 0.40), added_load_n=3000.0,
                       params={"beta": 2.7}, seed=9285)
    d = report["diagnosis"]
    v = judge(run.info, report)
    assert not v["wrong_cause"], d["summary"]
    p = d["probabilities"]
    assert p.get("load_k", 0.0) >= p.get("terrain", 0.0), p


def _held_out_seed(tmp_path, seed: int, batch: str, effect: str):
    """A held-out benchmark seed as ``bench_diagnosis.py --effects BATCH --seed SEED`` runs it
    (180 s, free-rolling reference front wheels) through ``run_fit``: ``(run, diagnosis)``."""
    from wheelsoil.simulate import HELD_OUT_BATCHES

    case = draw_case(seed, effects=HELD_OUT_BATCHES[batch])
    terrain = case.pop("terrain")
    assert case["effect"] == effect
    run = simulate_run(terrain, duration_s=180.0, front_wheels="reference", **case)
    report = run_fit([write_simulation(run, tmp_path / "run.mcap")], terrain, tmp_path / "report")
    assert not judge(run.info, report)["wrong_cause"], report["diagnosis"]["summary"]
    return run, report["diagnosis"]


def test_a_soil_stiffer_at_the_wheels_loading_rate_is_not_named_a_k_eq_mismatch(tmp_path):
    """Held-out benchmark seed 14470 (``--effects held-out-10``): a clay whose moduli grow with the
    loading rate, kc and kphi x (1 + 0.065 ln(1 + V / 25 mm/s)), was named a k_eq mismatch at
    "medium" (as 22 of 33 such soils in two fresh rounds were): over the run's speeds it is mostly a constant
    k_eq 15-30 % above the lab's.  The speed-dependence stand-in (``speed_k``, k_eq (V/V_ref)^beta)
    contains that mismatch and predicts the torque better out of sample, so no listed cause is named."""
    _, d = _held_out_seed(tmp_path, 14470, "held-out-10", "rate_sinkage")
    assert d["effect"] == "unexplained" and "depends on the speed" in d["summary"], d["summary"]


def test_a_sinkage_driven_by_the_treads_speed_is_not_named_slip_sinkage(tmp_path):
    """Held-out benchmark seed 17019 (``--effects held-out-13``): a clay on which the wheel sinks by
    0.0054 m x r omega / (5 m/s) more than Eq. 10 says (a sinkage driven by the tread's speed, not by
    slip) was named slip sinkage (Vasil'ev, "medium") at the batch's first score, as 3 of its 22 such
    runs were: in a sweep r omega = V / (1 - s) grows with slip.  The stand-in ``speed_sinkage``
    (z0 + H_v r omega / 5 m/s) tells them apart where one slip is reached at different speeds."""
    _, d = _held_out_seed(tmp_path, 17019, "held-out-13", "speed_sinkage")
    assert d["effect"] == "unexplained" and d["model"] == "speed_sinkage", d["summary"]


def test_a_weaker_tyre_soil_interface_is_not_named_a_phi_mismatch(tmp_path):
    """Held-out benchmark seed 12481 (``--effects held-out-8``): a tyre-soil interface weaker than the
    soil at the higher stresses acts on the drawbar pull like a lower phi, and the one-value phi re-fit
    was named at "medium".  The five-value re-fit that contains it predicts a channel better out of
    sample at the level at which a named model's worsening is judged (p < WORSEN_ALPHA), so no listed
    cause is named."""
    _, d = _held_out_seed(tmp_path, 12481, "held-out-8", "interface")
    assert d["effect"] == "unexplained" and "better out of sample than" in d["summary"], d["summary"]


def test_a_drifting_torque_zero_is_not_named_a_terrain_drift(tmp_path):
    run, report = _fit(tmp_path, "clay", effect="zero_drift", wheel=(0.47, 0.32), added_load_n=0.0,
                       params={"drift_nm": 200.0}, seed=9048)
    d = report["diagnosis"]
    v = judge(run.info, report)
    assert not v["wrong_cause"], d["summary"]
    assert d["effect"] == "unexplained", d["summary"]


def test_benchmark_seed_1398_a_cohesion_mismatch_is_not_named_a_stress_distribution(tmp_path):
    case = draw_case(1398)
    terrain = case.pop("terrain")
    assert case["effect"] == "terrain_mismatch" and case["drop_rate"] > 0.008
    run = simulate_run(terrain, duration_s=180.0, front_wheels="reference", **case)
    report = run_fit([write_simulation(run, tmp_path / "run.mcap")], terrain, tmp_path / "report")
    d = report["diagnosis"]
    v = judge(run.info, report)
    assert abs(v["latency_error_s"]) < 0.02, report["time_sync"]
    assert not v["wrong_cause"], d["summary"]


@pytest.mark.parametrize("seed, terrain, wheel, added_load_n", [
    (2133, "north-gower-clayey-loam", (0.47, 0.32), 0.0),
    (2203, "north-gower-clayey-loam", (0.55, 0.40), 3000.0),
    (2209, "heavy-clay-25", (0.47, 0.32), 5000.0),
    (3172, "sandy-loam-michigan-11", (0.47, 0.32), 5000.0),
])
def test_transducer_errors_on_library_soils_are_no_named_cause_nor_a_sure_none(tmp_path, seed, terrain, wheel,
                                                                                added_load_n):
    case = draw_case(seed)
    case.pop("terrain")
    case.update(wheel=wheel, added_load_n=added_load_n)
    assert case["effect"] in ("my_gain", "angle_offset", "zero_drift")
    run = simulate_run(terrain, duration_s=180.0, front_wheels="reference", **case)
    report = run_fit([write_simulation(run, tmp_path / "run.mcap")], terrain, tmp_path / "report")
    d = report["diagnosis"]
    v = judge(run.info, report)
    assert not v["wrong_cause"], d["summary"]
    assert d["effect"] in ("unexplained", "none"), d["summary"]
    assert d["confidence"] != "high", d["summary"]
    if d["effect"] == "none":
        assert d["effect_probabilities"]["none"] < 0.99
        assert any("posterior probability of no effect" in r for r in d["confidence_reasons"])


def test_benchmark_seed_2504_a_dp_only_stand_in_does_not_block_a_stress_shift_that_explains_the_torque(tmp_path):
    case = draw_case(2504)
    terrain = case.pop("terrain")
    assert case["effect"] == "stress_distribution"
    run = simulate_run(terrain, duration_s=180.0, front_wheels="reference", **case)
    report = run_fit([write_simulation(run, tmp_path / "run.mcap")], terrain, tmp_path / "report")
    d = report["diagnosis"]
    assert d["effect"] == "stress_distribution", d["summary"]
    assert d["channels"]["torque_nm"]["improves"], d["channels"]["torque_nm"]


@pytest.mark.parametrize("seed,batch", [(5004, "held-out"), (5075, "held-out"), (6012, "held-out-2")])
def test_held_out_causes_are_not_named_listed_causes(tmp_path, seed, batch):
    """Held-out benchmark seeds (``bench_diagnosis.py --effects held-out`` and ``held-out-2``: causes
    added after the rule and first scored with it unchanged):

    - 5004, a soil rebounding to an exit angle 0.21 theta1 behind the wheel on sand,
      and 5075, a GNSS speed reading 2.7 % low on clay, were named terrain mismatches at "medium"
      (as 28 of 32 rebounding soils and 1 of 32 speed gains were): the five-value terrain re-fit
      mimics both;
    - 6012, a clay whose shear strength falls with slip (x (1 - 0.11 s)), was named a stress
      distribution (as 16 of 22 such soils were): a Wong-Reece maximum moving forward with slip
      lowers Dp and T at high slip as well.

    The stand-ins ``rebound``, ``speed_gain`` and ``shear_slip`` (one parameter each) explain them."""
    from wheelsoil.simulate import HELD_OUT_BATCHES

    case = draw_case(seed, effects=HELD_OUT_BATCHES[batch])
    terrain = case.pop("terrain")
    assert case["effect"] in ("exit_angle", "gnss_gain", "strength_softening")
    run = simulate_run(terrain, duration_s=180.0, front_wheels="reference", **case)
    report = run_fit([write_simulation(run, tmp_path / "run.mcap")], terrain, tmp_path / "report")
    d = report["diagnosis"]
    assert not judge(run.info, report)["wrong_cause"], d["summary"]
    assert d["effect"] == "unexplained", d["summary"]
    assert d["confidence"] != "high", d["summary"]
