"""The pipeline on runs of independent generators (benchmarks/foreign/ to foreign5/: written from
hardware.md, the DBCs and the paper alone, importing nothing from wheelsoil). The first: front wheels locked to the instrumented one, which coasts without torque
while the vehicle is braked elsewhere."""

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_foreign import (CASES, CASES2, CSV_GENERATORS, GEN, GEN2, GEN3, GEN4, GEN5, GEN6, GEN7, GEN8, GEN9, GEN10, GEN11,  # noqa: E402
                           GEN12, GEN13, GEN14,
                           NAMED, ROUND2, STRESS, _run_csv_case, generate, round_runs, run_case, run_case2, run_case6)


def _load(gen_path, name):
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, gen_path)
    gen = importlib.util.module_from_spec(spec)
    # the generators' sibling modules share names (terra.py in foreign3/ and foreign4/): each import
    # must find its own folder's, not one another generator's loaded first
    own = {f.stem for f in gen_path.parent.glob("*.py")}
    saved = {m: sys.modules.pop(m) for m in list(sys.modules) if m in own}
    sys.path.insert(0, str(gen_path.parent))
    try:
        spec.loader.exec_module(gen)
    finally:
        sys.path.remove(str(gen_path.parent))
        for m in own:
            sys.modules.pop(m, None)
        sys.modules.update(saved)
    return gen


@pytest.mark.parametrize("folder", [g.parent for g in (GEN, GEN2, GEN3, GEN4, GEN5, GEN6, GEN7, GEN8, GEN9, GEN10,
                                                         GEN11, GEN12, GEN13, GEN14)], ids=lambda folder: folder.name)
def test_the_independent_generators_import_nothing_from_wheelsoil(folder):
    files = list(folder.glob("*.py"))
    assert files
    for f in files:
        lines = [ln.strip() for ln in f.read_text().splitlines()]
        assert not [ln for ln in lines if ln.startswith(("import wheelsoil", "from wheelsoil"))], f


def test_every_case_of_the_third_generators_rounds_is_one_of_its_cases_with_its_parameters():
    """``bench_foreign.py --generator foreign2`` (its 36, ``--stress``, ``--round2``): each case names a case
    of the generator and sets only that case's parameters, and no seed is used twice (a case re-run alone
    by its seed is the run scored)."""
    gen = _load(GEN2, "foreign2_gen")
    rows = CASES2 + STRESS + ROUND2
    for name, case, _seed, latency_s, params, *_ in rows:
        assert case in gen.CASES, name
        assert set(params) <= set(gen.CASES[case][2]), (name, params)
        assert 0.0 < latency_s < 1.0, name
    seeds = [r[2] for r in rows]
    assert len(seeds) == len(set(seeds))
    assert len({r[0] for r in rows}) == len(rows)


def test_every_run_of_the_fourth_generators_round_is_one_of_its_cases_with_its_parameters():
    """``bench_foreign.py --generator foreign3 [--round2]`` (``foreign3/round1.json``, ``round2.json``): each
    run names a case of the generator, sets only that case's parameters, in a log format the pipeline reads
    directly; no seed or name twice."""
    gen = _load(GEN3, "foreign3_gen")
    rows = round_runs("foreign3", 1) + round_runs("foreign3", 2)
    for r in rows:
        assert r["case"] in gen.CASES, r
        assert set(r["params"]) <= set(gen.CASES[r["case"]]["defaults"]), r
        assert r["format"] in ("asc", "blf", "log"), r
    assert len({r["seed"] for r in rows}) == len(rows) == len({r["name"] for r in rows})


@pytest.mark.parametrize("run", ["r1_01", "r1_07"])
def test_the_fourth_generators_towed_clay_runs_fitted_from_their_logs(tmp_path, run):
    """The fourth generator (benchmarks/foreign3: the paper's clay, on which the vehicle cannot drive
    itself, so a tractor tows it while the driver sweeps the rear wheels' slip; an ASC log, a candump
    log): the logs are fitted directly, no effect gives `none`; kc and kphi x0.75 lie within the lab's
    default uncertainty of k_eq (30 %, one sd of its logarithm 0.96 sd away): the k_eq re-fit finds it, and no
    mismatch is named (`within_lab`; it was named a k_eq mismatch before: a soil within the lab's uncertainty
    agrees with the lab). Its wheel-speed module reports each wheel's last tooth period (48 teeth), so its
    readings are late by about a tooth period, longer at the free-rolling fronts' low speed than at the
    slipping rear wheel's: the per-tooth delay is found against the transducer's angle and each reading
    moved back by its own, so the GNSS latency found against the fronts is its own (before, with one
    constant shift, 30-40 ms short)."""
    import json

    from bench_foreign import run_case3

    r = next(x for x in round_runs("foreign3", 1) if x["name"] == run)
    row = run_case3(r["name"], r["case"], r["seed"], r["params"], r["format"], tmp_path)
    rep = json.loads((tmp_path / f"rep_{run}" / "report.json").read_text())
    tooth = rep["data_quality"][0]["processing_quality"]["wheel_speed_lag"]["per_tooth"]
    assert tooth["applied"] and 40 < tooth["teeth"] < 56, tooth
    assert abs(row["latency_s"] - row["latency_true_s"]) < 0.015, row
    if r["case"] == "none":
        assert row["score"] == "right" and row["effect"] == "none", row
    else:
        d = json.loads((tmp_path / f"rep_{run}" / "report.json").read_text())["diagnosis"]
        assert row["effect"] == "unexplained" and d["why"] == "within_lab", d["summary"]
        assert d["model"].startswith("terrain_k_eq"), d["summary"]


def test_slip_sinkage_and_the_latency_found_on_an_independent_generators_run(tmp_path):
    """Vasil'ev slip sinkage lowering Dp at s = 0.5 by 15 %, GNSS 75 ms late, driven front wheels: the
    latency comes from the instrumented wheel where it coasts (before: not estimated, or tens to
    hundreds of ms off, on the generator's runs with driven fronts, and a Lyasko case came out
    `unexplained`), and slip sinkage is named."""
    case = next(c for c in CASES if c[0] == "v15")
    row = run_case(*case, tmp_path)
    assert row["latency_s"] is not None and abs(row["latency_s"] - row["latency_true_s"]) <= 0.02, row
    assert row["latency_method"] == "wheel_reference"
    assert row["score"] == "right" and row["effect"] == "slip_sinkage", row


def test_a_fit_with_the_other_sinkage_law_names_no_cause(tmp_path):
    """The generator's run with no effect, its sinkage from Eq. (10), fitted with ``--sinkage balance``:
    before, slip sinkage (Ding + terrain) was named; the converse stand-in (static sinkage from Eq. 10)
    now explains it, a model-form alternative on no list."""
    import warnings

    from wheelsoil.daq.convert import import_log
    from wheelsoil.pipeline import run_fit

    case = next(c for c in CASES if c[0] == "a1")
    generate(*case, tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = import_log(tmp_path / "a1.log", tmp_path / "a1.mcap").output
        d = run_fit([rec], "sand", tmp_path / "rep", sinkage="balance")["diagnosis"]
    assert d["effect"] not in NAMED, d["summary"]
    assert "eq10" in d["models"]


def test_ding_slip_sinkage_on_the_third_generators_run(tmp_path):
    """The third generator (benchmarks/foreign2: a 4x4 whose speed comes from the four wheels' drawbar pull,
    soil varying along the track, its own quadrature): Ding's N = n + n1 s with n1 = 0.25, GNSS 35 ms
    late. The latency is found and slip sinkage named in Ding's form."""
    row = run_case2(*next(c for c in CASES2 if c[0] == "ding2"), tmp_path)
    assert row["latency_s"] is not None and abs(row["latency_s"] - row["latency_true_s"]) <= 0.02, row
    assert row["score"] == "right" and row["effect"] == "slip_sinkage" and row["form"], row


def test_a_clean_one_value_mismatch_the_five_value_refit_outscores_is_reported_with_its_value(tmp_path):
    """The third generator without soil variability, phi 24 deg against the lab's 25 (0.4 of the lab's default
    standard deviation, 2.5 deg): the phi re-fit finds 24 deg, the five-value re-fit absorbs a ~0.2 % discrepancy
    between the generator's model and ours and has more evidence, and its values lie within the lab's
    uncertainty, so no mismatch is named; on these noise-free data a transducer gain on a re-fitted soil
    (``sensor_gain+terrain``, which contains the five-value re-fit) predicts the torque better out of sample
    still (its gain takes up the models' discrepancy), so the verdict is `unexplained` (``stand_in_better``)
    rather than `none` ("within what the lab values' stated uncertainty allows", which it was before that
    stand-in was tried); the report still carries what the single-value re-fit found."""
    import math
    import warnings

    from bench_foreign import _run_generator
    from wheelsoil.daq.convert import import_log
    from wheelsoil.pipeline import run_fit

    _run_generator(GEN2, ["terrain_phi", "--seed", "302", "--latency", "0.12", "--soil-var", "0", "--p", "phi_deg=24.0"],
                   "c_phi", tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = import_log(tmp_path / "c_phi.log", tmp_path / "c_phi.mcap").output
        d = run_fit([rec], "sand", tmp_path / "rep")["diagnosis"]
    assert d["effect"] not in NAMED, d["summary"]
    phi = d["models"]["terrain_phi"]["params"]["phi"]["value"]
    assert abs(math.degrees(phi) - 24.0) < 0.3, phi
    assert d["effect"] == "unexplained" and d["why"] == "stand_in_better", d["summary"]
    assert "a gain error of the force transducer + terrain re-fitted" in d["summary"], d["summary"]
    z = {q: v["data_estimate"]["z"] for q, v in d["models"]["terrain"]["params"].items()}
    assert all(abs(v) < 2.0 for v in z.values()) and abs(z["phi"]) < 1.0, z


def test_every_run_of_the_fifth_generators_round_is_one_of_its_cases():
    """``bench_foreign.py --generator foreign4 [--round2]`` (``foreign4/round1.json``, ``round2.json``): each run names a case of the
    generator, sets only parameters that case knows (a terrain mismatch: one lab value), in a log format
    the pipeline reads directly; no seed or name twice."""
    gen = _load(GEN4, "foreign4_gen")
    rows = round_runs("foreign4", 1) + round_runs("foreign4", 2)
    for r in rows:
        assert r["case"] in gen.CASES, r
        known = set(gen.DEFAULTS.get(r["case"], {})) | {"terrain_mismatch": set(gen.MISMATCH_KEYS),
                                                        "terrain_drift": {"at"}}.get(r["case"], set())
        assert set(r["params"]) <= known, r
        assert r["format"] in ("asc", "blf", "log"), r
    assert len({r["seed"] for r in rows}) == len(rows) == len({r["name"] for r in rows})


def test_the_fifth_generators_k_mismatch_far_from_its_stated_lab_uncertainty(tmp_path):
    """The fifth generator (benchmarks/foreign4: its own soil file, k_eq stated to 12 %, a 0.41 m wheel of
    62 kg fitted with --wheel-mass/--wheel-inertia, fronts braked now and then): k x0.65, 3.5 stated sigmas
    from the lab value, was refused as a prior-data conflict and left `unexplained`; it is a k_eq mismatch."""
    from bench_foreign import run_case4

    r = next(x for x in round_runs("foreign4", 1) if x["name"] == "r1_02")
    row = run_case4(r["name"], r["case"], r["seed"], r["params"], r["format"], tmp_path)
    assert row["score"] == "right" and row["model"] == "terrain_k_eq", row


def test_every_run_of_the_sixth_generators_round_is_one_of_its_cases():
    """``bench_foreign.py --generator foreign5`` (``foreign5/round1.json``): each run names a case of the
    generator, sets only parameters that case or its log damage knows, in a log format the pipeline reads
    directly (PEAK TRC among them); no seed or name twice."""
    gen = _load(GEN5, "foreign5_gen")
    rows = round_runs("foreign5", 1) + round_runs("foreign5", 2)
    for r in rows:
        assert r["case"] in gen.IN + gen.OUT, r
        assert set(r["params"]) <= set(gen.DEFAULTS.get(r["case"], {})) | set(gen.LOGDEF), r
        assert r["format"] in ("asc", "blf", "log", "trc"), r
    assert len({r["seed"] for r in rows}) == len(rows) == len({r["name"] for r in rows})


@pytest.mark.parametrize("run,model", [("f5r1_07", "ding"), ("f5r1_14", "wong_reece_load")])
def test_the_sixth_generators_ding_and_stress_shift_from_damaged_trc_and_blf_logs(tmp_path, run, model):
    """The sixth generator (benchmarks/foreign5: a loose loamy sand with n = 1.18, a 0.43 m wheel, other ECUs'
    frames, error frames, duplicates and a logging stall in the logs): its Ding form with n1 = 1.2 was
    `unexplained` with n1 at the old bound of 1; its Wong-Reece shift, whose sinkage is re-balanced so the
    shifted stresses carry the paper's load, was `unexplained` (the Eq. 10 form worsened the torque). Each
    is named, in its own form."""
    from bench_foreign import run_case5

    r = next(x for x in round_runs("foreign5", 1) if x["name"] == run)
    row = run_case5(r["name"], r["case"], r["seed"], r["params"], r["format"], tmp_path)
    assert row["score"] == "right" and row["model"] == model, row


def test_every_table_of_the_seventh_generators_rounds_is_one_of_its_cases():
    """foreign6 writes soil-bin testbed tables: every case of its two rounds is one of its cases, round 2 on
    other seeds than round 1."""
    r1, r2 = round_runs("foreign6", 1), round_runs("foreign6", 2)
    assert len(r1) == len(r2) == 30 and not {r["seed"] for r in r1} & {r["seed"] for r in r2}
    gen = _load(GEN6, "foreign6_gen")
    assert {r["case"] for r in r1 + r2} <= set(gen.ALL_CASES)


def test_the_static_sinkage_law_is_chosen_by_a_tables_measured_sinkage(tmp_path):
    """The seventh generator's table of Ding slip sinkage (f6r1_10), its static sinkage from the vertical
    balance (Eq. 7 = W), fitted as its truth says (the default ``--sinkage auto``): the data choose the
    balance by a Bayes factor over 10 and Ding is named (with Eq. 10 the verdict was ``unexplained``)."""
    run = next(r for r in round_runs("foreign6", 1) if r["name"] == "f6r1_10")
    row = run_case6(run["name"], run["case"], run["seed"], run["params"], tmp_path)
    import json

    d = json.loads((tmp_path / "rep_f6r1_10" / "report.json").read_text())["diagnosis"]
    assert d["sinkage_law"]["law"] == "balance" and d["sinkage_law"]["ln_bayes_factor"] > 2.3, d["sinkage_law"]
    assert d["sinkage_law"]["other"]["law"] == "eq10"
    assert row["score"] == "right" and d["model"] == "ding", d["summary"]


def test_a_stress_shift_whose_sinkage_carries_the_load_is_not_named_slip_sinkage(tmp_path):
    """The seventh generator's Wong-Reece table (f6r1_18: a dry sand, three dead-weight loads, sinkage from the
    vertical balance with the shifted stresses, no torque): its measured sinkage grows with slip, as slip
    sinkage's does.  While the stress forms whose sinkage grows with slip were left out wherever the measured
    sinkage grew, Ding + terrain was named at "medium", a wrong cause; tried, the stress shift competes."""
    run = next(r for r in round_runs("foreign6", 1) if r["name"] == "f6r1_18")
    row = run_case6(run["name"], run["case"], run["seed"], run["params"], tmp_path)
    import json

    d = json.loads((tmp_path / "rep_f6r1_18" / "report.json").read_text())["diagnosis"]
    assert d["sinkage_evidence"]["significant"]
    assert "wong_reece" in d["tried"] and d["effect"] != "slip_sinkage", d["summary"]
    assert row["score"] in ("right", "miss"), row


def test_every_run_of_the_eighth_generators_rounds_is_one_of_its_cases():
    """foreign7 writes single-wheel rig time series: every case of its two rounds is one of its cases, round 2 on
    other seeds than round 1."""
    r1, r2 = round_runs("foreign7", 1), round_runs("foreign7", 2)
    assert r1 and r2 and not {r["seed"] for r in r1} & {r["seed"] for r in r2}
    gen = _load(GEN7, "foreign7_gen")
    assert {r["case"] for r in r1 + r2} <= set(gen.CASES)


def test_a_stress_shift_on_a_soil_off_the_lab_values_is_named_with_the_soil_refitted(tmp_path):
    """The ninth generator's f8r2_14: a Wong-Reece shift (a1 0.42, a2 0.35) on a field soil drawn within the
    lab's uncertainty, a vehicle CAN log. On the lab's soil the shift leaves a relevant drawbar-pull error
    (about 100 N out of sample), and the verdict was `unexplained`. With the soil re-fitted under the shift
    (``wong_reece+terrain``) the shift is found (a1, a2 within 0.05 of the generator's), the error falls to
    a third on new data, and a stress shift is named."""
    import json

    from bench_foreign import run_case8

    r = next(x for x in round_runs("foreign8", 2) if x["name"] == "f8r2_14")
    row = run_case8(r["name"], r["case"], r["seed"], r["params"], tmp_path)
    d = json.loads((tmp_path / "rep_f8r2_14" / "report.json").read_text())["diagnosis"]
    assert row["score"] == "right" and d["effect"] == "stress_distribution", d["summary"]
    assert d["model"] == "wong_reece+terrain", d["summary"]
    p = d["models"]["wong_reece+terrain"]["params"]
    assert abs(p["a1"]["value"] - 0.42) < 0.05 and abs(p["a2"]["value"] - 0.35) < 0.05, p
    dp = {k: d["models"][k]["metrics"]["drawbar_pull_n"]["cv_R0"] for k in ("wong_reece", "wong_reece+terrain")}
    assert dp["wong_reece+terrain"] < 0.5 * dp["wong_reece"], dp


def test_a_hump_shaped_shear_curve_is_not_named_a_stress_shift(tmp_path):
    """The fourth generator's r1_24: a shear curve with a hump (Wong's compact-soil form, the residual
    strength 0.75 of the peak), a cause on no list. A stress shift on a re-fitted soil mimics it and was
    named ("medium") until its look-alike on no list, a shear strength changing with slip, was tried on a
    re-fitted soil too (``shear_slip+terrain``): no cause is named."""
    import json

    from bench_foreign import run_case3

    r = next(x for x in round_runs("foreign3", 1) if x["name"] == "r1_24")
    row = run_case3(r["name"], r["case"], r["seed"], r["params"], r["format"], tmp_path)
    d = json.loads((tmp_path / "rep_r1_24" / "report.json").read_text())["diagnosis"]
    assert row["score"] == "right" and d["effect"] not in NAMED, d["summary"]
    assert "shear_slip+terrain" in d["models"], sorted(d["models"])


@pytest.mark.parametrize("run", ["f6r1_01", "f6r2_11"])
def test_a_bin_soil_within_the_lab_uncertainty_is_none(tmp_path, run):
    """The seventh generator's `none` tables: the bin soil differs from the lab values by up to one lab
    sigma in every value (its README: "a real lab value is never exact"). Wong with the lab's values errs
    significantly; the five-value re-fit within two lab sigmas explains it, and the candidate (a stand-in
    within a Bayes factor of 10 of it on f6r1_01, the five-value re-fit itself on f6r2_11) shows no cause
    beyond the lab's uncertainty: `none`, at low confidence, saying so (both were `unexplained`)."""
    import json

    rnd = 1 if run.startswith("f6r1") else 2
    r = next(x for x in round_runs("foreign6", rnd) if x["name"] == run)
    row = run_case6(r["name"], r["case"], r["seed"], r["params"], tmp_path)
    d = json.loads((tmp_path / f"rep_{run}" / "report.json").read_text())["diagnosis"]
    lu = d["lab_uncertainty"]
    assert row["score"] == "right" and d["effect"] == "none" and d["confidence"] == "low", d["summary"]
    assert lu and max(abs(v) for v in lu["z"].values()) <= lu["lab_z"]
    assert "within what the lab values' stated uncertainty allows" in d["summary"]


def test_every_run_of_the_ninth_generators_rounds_is_one_of_its_cases():
    """foreign8 writes vehicle CAN logs of a tow test: every run of its two rounds is one of its cases, both
    families in each round, round 2 on other seeds than round 1."""
    r1, r2 = round_runs("foreign8", 1), round_runs("foreign8", 2)
    assert r1 and r2 and not {r["seed"] for r in r1} & {r["seed"] for r in r2}
    gen = _load(GEN8, "foreign8_gen")
    assert {r["case"] for r in r1 + r2} <= set(gen.CASES)
    for rnd in (r1, r2):
        assert {gen.CASES[r["case"]] for r in rnd} == {"in", "out"}


def test_every_run_of_the_tenth_generators_rounds_is_one_of_its_cases():
    """foreign9 writes vehicle CAN logs of field runs against a dynamometer vehicle: every run of its two rounds
    is one of its cases, both families in each round, round 2 on other seeds than round 1."""
    r1, r2 = round_runs("foreign9", 1), round_runs("foreign9", 2)
    assert r1 and r2 and not {r["seed"] for r in r1} & {r["seed"] for r in r2}
    gen = _load(GEN9, "foreign9_gen")
    assert {r["case"] for r in r1 + r2} <= set(gen.CASES)
    for rnd in (r1, r2):
        assert {r["case"] in gen.IN_FAMILY for r in rnd} == {True, False}


def test_a_latency_the_data_cannot_pin_down_is_not_claimed_reliable_and_names_no_cause(tmp_path):
    """foreign9's f9r1_26 (a BLF log): soil sticking to the wheel, a cause on no list, on a field soil varying
    along the track, with a rotating transducer's crosstalk and GNSS outages.  Only the slip-traction estimator
    of the GNSS latency is usable there, and it lands far from the generator's (about 0.16 s off): the estimate
    must be flagged unreliable, and no listed cause named on it."""
    from bench_foreign import run_case9

    r = next(x for x in round_runs("foreign9", 1) if x["name"] == "f9r1_26")
    row = run_case9(r["name"], r["case"], r["seed"], r["params"], tmp_path)
    assert row["effect"] not in NAMED, row
    if abs(row["latency_s"] - row["latency_true_s"]) > 0.05:
        assert row["latency_reliable"] is False, row


def _run_named(name, tmp_path):
    """One run of a CSV generator's round, by its name: fNNrK_MM is run MM of round K of ``foreignNN``."""
    gen, k = name[1:].split("_")[0].split("r")
    r = next(x for x in round_runs(f"foreign{gen}", int(k)) if x["name"] == name)
    return _run_csv_case(CSV_GENERATORS[f"foreign{gen}"], r["name"], r["case"], r["seed"], r["params"], tmp_path)


def test_a_field_soil_within_the_lab_uncertainty_whose_correlated_values_moved_together_is_none(tmp_path):
    """The fifteenth generator's f14r1_16 (`none`: every value within one lab sd, c 0.98 sd off). The five-value
    re-fit moves c with phi and K (one shear strength), so c's posterior sd stays near the lab's while its place
    moves; undoing the lab prior's pull value by value placed it 67 lab sd off, "beyond one lab sd", and the
    verdict was `unexplained` (catch-all). With the other values held where the fit put them, every estimate
    lies within two lab sd and the verdict is `none` by the lab-uncertainty route."""
    import json

    row = _run_named("f14r1_16", tmp_path)
    d = json.loads((tmp_path / "rep_f14r1_16" / "report.json").read_text())["diagnosis"]
    assert row["score"] == "right" and d["effect"] == "none" and d["lab_uncertainty"], d["summary"]
    est = {q: v["data_estimate"] for q, v in d["models"]["terrain"]["params"].items() if v.get("data_estimate")}
    assert "c" in est and all(abs(e["z"]) < 2.0 and not e["beyond_one_sd"] for e in est.values()), est


def test_a_transducer_channel_that_changes_sign_part_way_is_refused_with_the_file_named(tmp_path):
    """f14r1_08: the generator's Fx channel changes sign after 42 % of the run (a calibration reload). The
    in-plane forces then beat once per wheel revolution far beyond any bridge gain: the pipeline refuses the log
    with an error naming it, so no cause is named; the benchmark scores the run `refused`."""
    row = _run_named("f14r1_08", tmp_path)
    assert row["effect"] == "refused" and row["score"] == "refused", row
    said = (tmp_path / "f14r1_08.fit.txt").read_text()
    assert "f14r1_08.asc" in said and "not physical" in said, said[-2000:]


def test_a_rival_weighed_against_the_cause_not_its_weakest_form(tmp_path):
    """The thirteenth generator's f12r1_14: a Wong-Reece shift (a1 0.455, a2 0.191) on a loess within the lab's
    uncertainty, three sled pulls. The shift on the lab's soil is the supported candidate but has almost no evidence
    (about 1e-92); the same shift on the re-fitted soil has nearly all of it and is held back only because it
    does not beat that candidate over three folds. A Ding form on a re-fitted soil, with 1e-17 of the evidence,
    out-weighed the candidate alone and held the verdict at `unexplained` (a rival with more evidence). Weighed
    against the cause's held-back form, it is no rival: the shift is named with the soil re-fitted, a1 and a2
    within 0.02 of the generator's, at "low" confidence (the route of a cause on a soil within the lab's
    uncertainty)."""
    import json

    row = _run_named("f12r1_14", tmp_path)
    d = json.loads((tmp_path / "rep_f12r1_14" / "report.json").read_text())["diagnosis"]
    assert row["score"] == "right" and d["effect"] == "stress_distribution", d["summary"]
    assert d["model"] == "wong_reece+terrain" and d["confidence"] == "low", d["summary"]
    m = d["models"]
    rivals = [k for k, v in m.items() if k != "wong" and not v["supported"] and v["effect"] != "stress_distribution"
              and v["probability"] > m["wong_reece"]["probability"]]
    assert rivals and all(m[k]["probability"] < m["wong_reece+terrain"]["probability"] for k in rivals), rivals
    p = m["wong_reece+terrain"]["params"]
    truth = json.loads((tmp_path / "f12r1_14_truth.json").read_text())["params"]
    assert abs(p["a1"]["value"] - truth["a1"]) < 0.02 and abs(p["a2"]["value"] - truth["a2"]) < 0.02, p


def test_a_wheel_out_of_round_is_fitted_with_its_ripple_said_not_refused_as_a_decoding_error(tmp_path):
    """f14r2_16: a rim with 18 mm of runout beats the load by 2.2 kN (20 % of it) once per wheel revolution, the
    moment with it. Processing refused the log as two force signals decoded with different factors, which beat
    at twice the wheel angle, not once. Now the once-per-revolution part is said and taken out, the run is
    fitted, and no cause is named; a channel changing sign part-way (f14r1_08) is still refused (test above)."""
    row = _run_named("f14r2_16", tmp_path)
    assert row["effect"] not in ("refused", *NAMED), row
    said = (tmp_path / "rep_f14r2_16" / "report.json").read_text()
    assert "once per wheel revolution" in said and "out of round" in said


def test_evidence_the_smaller_model_cannot_produce_counts_for_no_listed_cause(tmp_path):
    """The fourteenth generator's f13r2_11: the inner wheel of a curve (a cause on no list). Ding's stress-only form
    on a re-fitted soil has nearly all the evidence, 1e57 times the five-value re-fit's, yet its n1 is not told from
    zero over the folds. Counted for the terrain re-fit it reduces to, its evidence made a terrain mismatch 1.0
    probable and a phi and K mismatch was named. The smaller model cannot produce that evidence, so it counts for
    no listed cause, and the run is `unexplained`."""
    import json

    from wheelsoil.model.diagnosis import BF_NESTED, P_NAME

    row = _run_named("f13r2_11", tmp_path)
    d = json.loads((tmp_path / "rep_f13r2_11" / "report.json").read_text())["diagnosis"]
    assert row["effect"] not in NAMED and d["effect"] == "unexplained", d["summary"]
    m = d["models"]
    why = m["ding_stress+terrain"]["not_supported_because"]
    assert "not distinguishable from zero" in why and "times less evidence" in why, why  # the report says so
    assert m["ding_stress+terrain"]["probability"] > BF_NESTED * m["terrain"]["probability"]
    assert d["effect_probabilities"]["terrain_mismatch"] < P_NAME
