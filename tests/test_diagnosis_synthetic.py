"""The diagnosis names the right cause on synthetic data, 'none' when there is none, and never
a cause that worsens the drawbar pull out of sample (issue 10, 'Why' bullets)."""

import math

import numpy as np
import pytest

from wheelsoil.model import DEFAULT_WHEEL, load_terrain, wong_forces
from wheelsoil.model.diagnosis import EFFECTS, TITLES, WHY_UNEXPLAINED, diagnose
from wheelsoil.model.structure import MIN_REL, _fmt, structure_test
from wheelsoil.model.fit import synthetic_data

SAND = load_terrain("sand")
CLAY = load_terrain("clay")
W = DEFAULT_WHEEL
CONTRACT_KEYS = {"effect", "model", "confidence", "summary", "channels", "probabilities", "alternatives",
                 "separating_measurement", "not_excluded", "consistency", "flags", "models", "why"}


def _table(model="wong", params=None, *, terrain=SAND, truth=None, seed=0, n=120, **kw):
    return synthetic_data(terrain, W, model, params, kind="table", n_rows=n, load_n=13000.0,
                          terrain_truth=truth, seed=seed, **kw)


def _invariants(d):
    """What must hold for every verdict: contract D, probabilities, and no named cause that
    fails to lower the drawbar pull out of sample or worsens a measured channel."""
    out = d.to_dict()
    assert CONTRACT_KEYS <= set(out)
    assert out["effect"] in EFFECTS and out["confidence"] in ("high", "medium", "low")
    assert abs(sum(out["probabilities"].values()) - 1.0) < 1e-9
    assert set(out["channels"]) == {"drawbar_pull_n", "torque_nm", "sinkage_m"}
    if d.effect not in ("none", "unexplained"):
        pr = d.paired[d.model]
        assert d.target_channels and all(pr[c]["improves"] for c in d.target_channels), \
            "a named cause must lower the error of every target channel out of sample"
        if "drawbar_pull_n" in {t["channel"] for k, t in d.structure["wong"].items() if k in d._sig_w}:
            assert d.target_channels == ["drawbar_pull_n"]
        assert not any(r["worsens"] for r in pr.values()), "a named cause must worsen no channel"
        assert d.fits[d.model].effect == d.effect
        # every supported rival of another effect is an alternative or says how the cause held against it
        for k, route in d.holds_against.items():
            assert k in d.supported and route in ("out of sample", "relevant error", "evidence", "leaves structure",
                                                  None)
            assert (route is None) == (k in d.alternatives) and out["holds_against"][k] == route
        if any(d.holds_against.values()):
            assert "Named over the other supported causes" in d.summary
        # forms of the named effect that explain the data as well are listed as such (c against phi)
        same = [k for k in d.alternatives if d.fits[k].effect == d.effect]
        assert d.indistinguishable_forms == same and d.forms_distinguishable == (not same)
    # every hypothesis tried is either supported or says why not, in the summary's words
    for k, m in out["models"].items():
        if k != "wong":
            assert m["supported"] == (m["not_supported_because"] is None), k
            why = m["not_supported_because"]
            pr = d.paired[k]
            if why and "error out of sample" in why and "only inconsistently" in why:
                assert all(pr[c]["gain_noise_var"] > 0 for c in d.target_channels), k  # it does lower the error
            if why and why.startswith("does not lower"):
                assert any(pr[c]["gain_noise_var"] <= 0 for c in d.target_channels), k
    # an unexplained verdict says, as a code, which test of the rule stopped the naming
    assert (out["why"] in WHY_UNEXPLAINED) if d.effect == "unexplained" else out["why"] is None, out["why"]
    if d.effect == "unexplained":
        assert d.confidence != "high"
        top = max(d.probabilities, key=d.probabilities.get)
        if top in d.why_not:  # the most probable hypothesis, not named: its out-of-sample numbers are quoted
            assert f"The most probable hypothesis, {TITLES[top]}" in d.summary
            r = d.paired[top]["drawbar_pull_n"]
            assert f"drawbar pull {_fmt(r['wong_cv_rmse'])} -> {_fmt(r['cv_rmse'])}" in d.summary
    if d.effect == "none" and not d.lab_uncertainty:  # a run that cannot exclude a relevant error says so
        from wheelsoil.model.structure import _loose, _noisy

        loose = bool(_loose(d.structure["wong"]))
        assert ("cannot exclude one either" in d.summary) == loose
        assert not loose or d.confidence != "high"
        assert not _noisy(d.structure["wong"]) or d.confidence != "high"
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_none_when_data_follow_wong(seed):
    d = diagnose(_table(seed=seed), SAND, W)
    _invariants(d)
    assert d.effect == "none" and d.model == "wong"
    assert "no significant systematic structure" in d.summary


def test_autocorrelated_time_series_without_effect_is_none():
    """Filtered 100 Hz noise must not be mistaken for structure (cycle x slip-cell aggregation)."""
    df = synthetic_data(SAND, W, "wong", duration_s=40.0, load_n=13000.0, seed=0)
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect == "none", d.summary
    data = d.data
    e = (data.channels["drawbar_pull_n"] - d.fits["wong"].predictions["drawbar_pull_n"]) / data.sigma["drawbar_pull_n"]
    naive = data.subset(np.ones(data.n, bool))
    object.__setattr__(naive, "units", np.arange(data.n))
    assert structure_test(naive, e)["p"] < structure_test(data, e)["p"]


def test_time_series_with_slip_sinkage_names_it_and_its_form():
    df = synthetic_data(SAND, W, "lyasko", {"m1": 0.6, "m2": 0.03}, duration_s=60.0, load_n=13000.0, seed=2)
    d = diagnose(df, SAND, W)
    out = _invariants(d)
    assert d.effect == "slip_sinkage" and d.model == "lyasko"
    assert out["probabilities"]["lyasko"] > 0.9
    assert out["channels"]["drawbar_pull_n"]["effect"] == "slip_sinkage"
    assert out["channels"]["drawbar_pull_n"]["improves"] is True


def test_ding_read_with_n_in_the_stress_only_is_slip_sinkage():
    """Eq. (13)'s other reading (N in Eq. 2 only, Eq. 10's sinkage at the lab n), as an independent
    generator wrote it: the effect is slip sinkage, the form Ding's."""
    df = synthetic_data(SAND, W, "ding_stress", {"n1": 0.3}, duration_s=60.0, load_n=13000.0, seed=2)
    d = diagnose(df, SAND, W)
    out = _invariants(d)
    assert d.effect == "slip_sinkage" and d.model.startswith("ding"), d.summary
    assert sum(v for k, v in out["probabilities"].items() if k.startswith("ding_stress")) > 0.9


@pytest.mark.parametrize("kind", ["table", "timeseries"])
def test_lab_exponent_off_without_slip_sinkage_is_not_slip_sinkage(kind):
    """Why-bullet: n + 0.1 and no slip sinkage gave 'slip_sinkage' (Ding) at high confidence."""
    truth = SAND.replace(n=SAND.n + 0.1)
    if kind == "table":
        df = _table(truth=truth, seed=3)
    else:
        df = synthetic_data(SAND, W, "wong", duration_s=120.0, load_n=13000.0, terrain_truth=truth, seed=3)
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect != "slip_sinkage"
    assert d.effect in ("terrain_mismatch", "unexplained")
    if d.effect == "terrain_mismatch":
        assert d.gain["cv_R0_n_after"] < d.gain["cv_R0_n_before"]


@pytest.mark.parametrize("terrain", [SAND, CLAY], ids=["sand", "clay"])
def test_cohesion_halved_is_a_terrain_mismatch_in_c(terrain):
    """Why-bullet: cohesion halved gave terrain_mismatch with wrong K and phi."""
    d = diagnose(_table(terrain=terrain, truth=terrain.replace(c=terrain.c / 2), seed=4), terrain, W)
    _invariants(d)
    assert d.effect in ("terrain_mismatch", "unexplained")
    if d.effect == "terrain_mismatch":
        f = d.fits[d.model]
        assert abs(f.params["c"] - terrain.c / 2) < abs(f.params["c"] - terrain.c)


def test_a_model_that_worsens_the_drawbar_pull_is_never_named():
    """A torque-only error (a transducer gain in My) that slip sinkage can mimic in torque but
    that leaves Dp right: no cause may be named on the strength of the torque."""
    df = _table(seed=5)
    df["torque_nm"] *= 1.0 + 0.3 * df["slip"]
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect in ("none", "unexplained")
    assert d.channels["torque_nm"]["effect"] != "none"


def test_unexplained_when_no_hypothesis_fits_the_structure():
    df = _table(seed=6)
    df["drawbar_pull_n"] += 150.0 * np.sin(2 * np.pi * df["slip"] / 0.35)
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect == "unexplained"
    assert "tried" in d.summary or "leaves significant structure" in d.summary or "Candidates" in d.summary


def test_terrain_drift_along_the_run_is_not_slip_sinkage():
    """Soil compacted by earlier passes: phi and k_eq grow along the run."""
    df = synthetic_data(SAND, W, "wong", duration_s=120.0, load_n=13000.0, seed=7)
    x = df["distance_m"].to_numpy() / df["distance_m"].max() - 0.5
    drive = (df["slip"] > 0) & (df["slip"] < 1)
    cyc = df["cycle"].to_numpy()
    for c in np.unique(cyc[drive.to_numpy()]):
        m = drive.to_numpy() & (cyc == c)
        xc = float(np.mean(x[m]))
        t = SAND.replace(phi=SAND.phi + math.radians(8.0) * xc, kc=0.0, kphi=SAND.k_eq(W.width) * math.exp(0.8 * xc))
        f0 = wong_forces(SAND, W, df["load_n"][m], df["slip"][m])
        f1 = wong_forces(t, W, df["load_n"][m], df["slip"][m])
        df.loc[m, "drawbar_pull_n"] += f1.drawbar_pull_n - f0.drawbar_pull_n
        df.loc[m, "torque_nm"] += f1.torque_nm - f0.torque_nm
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect in ("terrain_drift", "unexplained")
    assert d.structure["wong"]["drawbar_pull_n@x"]["p"] < 0.01


def test_a_drawbar_pull_drifting_alone_is_not_named_a_terrain_drift():
    """An Fx offset growing along the run (300 N end to end), torque untouched: a soil changing
    along the run would move the torque with it.  The Dp-only drift stand-in explains it as
    well, so it is not named a terrain drift (a 5-slope terrain drift fitted it and was named,
    at "high" on the default wheel in clay)."""
    df = synthetic_data(SAND, W, "wong", duration_s=120.0, load_n=13000.0, seed=7)
    x = df["distance_m"].to_numpy() / df["distance_m"].max() - 0.5
    df["drawbar_pull_n"] += 300.0 * x
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect != "terrain_drift", d.summary
    assert d.structure["wong"]["drawbar_pull_n@x"]["p"] < 0.01


def test_parameters_at_a_bound_and_correlations_are_flagged():
    df = _table(seed=8)
    df["drawbar_pull_n"] += 200.0  # more pull than Wong: slip sinkage (which only lowers Dp) sits at H = 0
    d = diagnose(df, SAND, W, models=("vasilev", "lyasko", "terrain"))
    kinds = {(f["model"], f["kind"]) for f in d.flags}
    assert ("vasilev", "at_bound") in kinds
    assert d.to_dict()["models"]["vasilev"]["params"]["H"]["at_bound"] is True
    assert any(f["kind"] in ("correlation", "ill_conditioned") for f in d.flags)


def test_measured_sinkage_growth_is_found_in_the_sinkage_channel():
    df = _table("vasilev", {"H": 0.05}, seed=9, n=40, noise_z_m=0.004)
    d = diagnose(df, SAND, W)
    out = _invariants(d)
    assert d.sinkage_evidence["significant"]
    assert out["channels"]["sinkage_m"]["effect"] == "slip_sinkage"
    assert d.effect == "slip_sinkage"
    assert "direct evidence" in " ".join(d.confidence_reasons)


def test_slip_sinkage_is_not_named_when_the_measured_sinkage_does_not_grow_with_slip():
    """The forces of a Vasil'ev slip sinkage (H = 5 cm) with a measured sinkage that stays at its static
    value at every slip (the table above, the growth H s taken out): whatever explains the forces, it is
    not a sinkage growing with slip, and the measurement says so (``_sinkage_contradicts``)."""
    df = _table("vasilev", {"H": 0.05}, seed=9, n=40, noise_z_m=0.004)
    df["sinkage_m"] -= 0.05 * df["slip"]
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert not d.sinkage_evidence["significant"]
    assert d.effect != "slip_sinkage", d.summary
    if d.model in d.fits and d.fits[d.model].effect == "slip_sinkage":
        assert d.why == "sinkage_contradicts" and "does not grow with slip as" in d.summary, d.summary


def test_a_slip_sinkage_fit_whose_sinkage_growth_the_measurement_contradicts_is_flagged():
    """``_sinkage_contradicts`` on its own: a measured sinkage flat in slip (1 mm noise, three loads)
    against a slip-sinkage fit whose cell sinkage grows 8 mm per unit slip is contradicted; a fit
    growing as little as the measurement is not, nor is a fit of another effect."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import _sinkage_contradicts
    from wheelsoil.model.structure import _slope_test

    rng = np.random.default_rng(3)
    slip = np.tile(np.linspace(0.12, 0.88, 9), 6)
    load = np.repeat([9000.0, 12000.0, 15000.0], 18)
    z0 = 0.04 * (load / 12000.0) ** 0.8
    data = SimpleNamespace(cells=SimpleNamespace(slip=slip, load_n=load))
    z = z0 + 0.001 * rng.standard_normal(slip.size)
    ev = _slope_test(slip, z, covariate=load)

    def fit(effect, growth, grows=True):
        return SimpleNamespace(effect=effect, cell_pred={"sinkage_m": z0 + growth * slip},
                               hypothesis=SimpleNamespace(sinkage_grows=grows))

    hit = _sinkage_contradicts(data, fit("slip_sinkage", 0.008), ev)
    assert hit is not None and hit[3] < 0.01 and abs(hit[2] - 0.008) < 1e-3 and abs(hit[0]) < 3 * hit[1]
    assert _sinkage_contradicts(data, fit("slip_sinkage", ev["slope"]), ev) is None
    assert _sinkage_contradicts(data, fit("stress_distribution", 0.008), ev) is None
    assert _sinkage_contradicts(data, fit("slip_sinkage", 0.008), None) is None
    # a measured sinkage that grows with slip (significantly), less steeply than the fitted form's, shows slip
    # sinkage: the form's size is for the structure test of its residuals, not a contradiction
    zg = z + 0.030 * slip
    evg = _slope_test(slip, zg, covariate=load)
    evg["significant"] = evg["p_positive"] < 0.01
    assert evg["significant"] and evg["slope"] + 3 * evg["stderr"] < 0.040
    assert _sinkage_contradicts(data, fit("slip_sinkage", 0.040), evg) is None
    evg["significant"] = False  # the same slopes, the growth not shown: contradicted
    assert _sinkage_contradicts(data, fit("slip_sinkage", 0.040), evg) is not None
    # a form whose sinkage does not grow (Ding's other reading) is slip sinkage only where the measurement
    # shows a growth: flat against flat is contradicted (nothing shows one), a shown growth is not
    flat = _sinkage_contradicts(data, fit("slip_sinkage", 0.0, grows=False), ev)
    assert flat is not None and flat[3] == pytest.approx(ev["p_positive"], rel=1e-6) and flat[3] >= 0.01
    evg["significant"] = True
    assert _sinkage_contradicts(data, fit("slip_sinkage", 0.0, grows=False), evg) is None


def test_consistency_is_reported_for_every_model():
    d = diagnose(_table("lyasko", {"m1": 0.6, "m2": 0.03}, seed=10), SAND, W, models=("lyasko", "vasilev"))
    for k, c in d.consistency.items():
        assert {"load_ratio_by_slip", "sinkage_ok", "consistent"} <= set(c)
    # Lyasko with the paper's sand coefficients carries far more than the measured load at high slip
    assert not d.consistency["lyasko"]["consistent"]
    assert d.confidence != "high"


def test_candidate_that_does_not_converge_is_reported_and_not_named():
    d = diagnose(_table("lyasko", {"m1": 0.6, "m2": 0.03}, seed=11), SAND, W, max_iter=1)
    assert any("did not converge" in f for f in d.failures)
    assert d.model not in [k for k, f in d.fits.items() if not f.success]


def test_detectable_but_negligible_error_is_reported_not_diagnosed():
    df = _table(seed=12, n=400, noise_dp_n=5.0)
    df["drawbar_pull_n"] += 3.0  # a 0.6-sigma bias: significant with 400 rows, below one sigma
    d = diagnose(df, SAND, W, models=("vasilev",))
    assert d.structure["wong"]["drawbar_pull_n"]["p"] < 1e-4
    assert d.effect == "none"
    assert "statistically detectable" in d.summary and "not attributed" in d.summary


def test_slip_sinkage_seen_in_the_torque_alone_is_named_and_capped_at_medium():
    """When Wong's drawbar pull has no relevant error (here: buried in 2 kN noise) but the torque
    has, a cause must explain the torque and keep the drawbar pull as good as Wong's (rule step 3);
    the verdict rests on one channel, so its confidence is at most medium."""
    df = _table("vasilev", {"H": 0.03}, noise_dp_n=2000.0, noise_t_nm=5.0, seed=3)
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.target_channels == ["torque_nm"], d.summary
    assert d.effect == "slip_sinkage" and d.confidence != "high", d.summary
    assert not d.paired[d.model]["drawbar_pull_n"]["worsens"]


def test_a_torque_gain_alone_is_not_named_a_listed_cause():
    """The same situation made by a transducer gain (My reads 8 % high): the torque alone is off,
    and no listed cause may take the credit."""
    df = _table(noise_dp_n=2000.0, noise_t_nm=5.0, seed=4)
    df["torque_nm"] *= 1.08
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.target_channels == ["torque_nm"]
    assert d.effect == "unexplained", d.summary


def test_design_effect_counts_correlated_cells_of_one_cycle_as_fewer():
    """Cells of one accelerate cycle that share a random offset (the soil of that patch) are not
    independent: the evidence's design effect rises above 1 (Kish), and stays near 1 without."""
    df = synthetic_data(SAND, W, "wong", duration_s=60.0, load_n=13000.0, seed=5)
    d0 = diagnose(df, SAND, W, models=["terrain"])
    shared = df.copy()
    rng = np.random.default_rng(5)
    offset = rng.normal(0.0, 150.0, shared["cycle"].max() + 1)
    shared["drawbar_pull_n"] += offset[shared["cycle"].to_numpy()]
    d1 = diagnose(shared, SAND, W, models=["terrain"])
    assert d0.deff < 1.5 and d1.deff > 2.0, (d0.deff, d1.deff)


def test_a_step_along_the_run_is_found_and_noise_alone_is_not():
    """Another patch of ground from some cycle on is a step in the cycle means: the change-point
    test finds it where a quadratic and three fixed bins smear it into their noise reference; on
    independent noise it keeps its level (Bonferroni over the splits is conservative)."""
    from wheelsoil.model.structure import ALPHA, _structure_1d

    x = np.linspace(-0.5, 0.5, 10)
    rng = np.random.default_rng(3)
    e = np.where(np.arange(10) < 6, 2.0, -2.0) + 0.3 * rng.standard_normal(10)
    with_step = _structure_1d(x, e, step=True)
    assert with_step["p_step"] < ALPHA / 5 and with_step["p"] < ALPHA / 5
    assert max(with_step["p_poly"], with_step["p_bins"]) > with_step["p_step"] * 100
    assert with_step["effect"] > 1.5
    null = [_structure_1d(x, rng.standard_normal(10), step=True)["p_step"] for _ in range(2000)]
    assert np.mean(np.array(null) < ALPHA) <= 1.5 * ALPHA


def test_a_level_error_alone_puts_no_change_point_along_the_run():
    """The step form's change point needs a change, not an error: cycle means all off by one level
    (a constant mismatch) give none; the same level stepping half-way gives one within the two
    cycles around the step (refined over their cells), and on independent noise about a level the
    test keeps its size."""
    from types import SimpleNamespace

    from wheelsoil.model.structure import ALPHA, _change_point, _step_test

    cycles, per = 12, 8
    group = np.repeat(np.arange(cycles), per)
    x = (group + np.tile(np.linspace(0.0, 0.9, per), cycles)) / cycles - 0.5
    rng = np.random.default_rng(5)

    def data_with(level):  # one channel, unit noise, Wong predicting zero
        y = level[group] + rng.standard_normal(group.size)
        cells = SimpleNamespace(x=x, group=group, channels={"drawbar_pull_n": y},
                                sigma={"drawbar_pull_n": 1.0})
        return SimpleNamespace(kind="time_series", cells=cells)

    pred = {"drawbar_pull_n": np.zeros(group.size)}
    assert _change_point(data_with(np.full(cycles, 4.0)), pred) is None
    stepped = np.where(np.arange(cycles) < 7, 4.0, 1.0)
    x_step, n_splits = _change_point(data_with(stepped), pred)
    assert x[group == 6].min() < x_step < x[group == 7].max() and n_splits == cycles - 3
    u = np.linspace(-0.5, 0.5, cycles)
    null = [_step_test(u, 3.0 + rng.standard_normal(cycles), level=True)[0] for _ in range(2000)]
    assert np.mean(np.array(null) < ALPHA) <= 1.5 * ALPHA


def test_a_soil_off_everywhere_under_loads_stepped_pass_by_pass_tries_no_change_of_ground():
    """A lab phi 4 deg too high and a rig stepping its load every four cycles (0.7, 1.0, 1.3 x):
    Wong's error grows with the load, so its cycle means change along the run, but the five-value
    re-fit of a constant soil leaves no change, and the step drift (another patch of ground) is not
    tried; the mismatch is not called a drift."""
    from wheelsoil.model.structure import _change_point
    from wheelsoil.model.fit import prepare_data

    df = synthetic_data(SAND, W, "wong", duration_s=120.0, load_n=13000.0, seed=4)
    truth = SAND.replace(phi=SAND.phi - math.radians(4.0))
    drive = ((df["slip"] > 0) & (df["slip"] < 1)).to_numpy()
    factor = np.array([0.7, 1.0, 1.3])[np.minimum(df["t_s"].to_numpy() // 40.0, 2).astype(int)]
    w0 = df["load_n"].to_numpy()
    f0 = wong_forces(SAND, W, w0[drive], df["slip"].to_numpy()[drive])
    f1 = wong_forces(truth, W, (w0 * factor)[drive], df["slip"].to_numpy()[drive])
    df["load_n"] = w0 * factor
    df.loc[drive, "drawbar_pull_n"] += f1.drawbar_pull_n - f0.drawbar_pull_n
    df.loc[drive, "torque_nm"] += f1.torque_nm - f0.torque_nm
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert _change_point(prepare_data(df, slip_min=0.1), d.fits["wong"].cell_pred) is not None
    assert "drift_step" not in d.tried and d.effect != "terrain_drift", d.summary


def test_summary_counts_cycles_and_the_folds_they_were_merged_into(monkeypatch):
    """More accelerate cycles than MAX_FOLDS are merged into MAX_FOLDS folds; the summary says both."""
    import wheelsoil.model.crossval as cv

    df = synthetic_data(SAND, W, "wong", duration_s=40.0, load_n=13000.0, seed=0)
    monkeypatch.setattr(cv, "MAX_FOLDS", 2)
    d = diagnose(df, SAND, W)
    cycles = np.unique(d.data.cells.group).size
    assert cycles > 2
    assert d.fits["wong"].cv["n_groups"] == 2
    assert f"{cycles} {d.data.group_kind} merged into 2 contiguous cross-validation folds" in d.summary


def test_none_on_rough_ground_is_not_high():
    """Rough ground: each accelerate cycle on its own soil, Dp offset by a random 15 % of its
    magnitude.  Whatever the verdict, 'none' cannot be 'high' when the cycles' scatter leaves
    room for a relevant mean error (equivalence bound); on even ground that reason is absent."""
    df = synthetic_data(SAND, W, "wong", duration_s=120.0, load_n=13000.0, seed=11)
    even = diagnose(df, SAND, W)
    _invariants(even)
    assert even.effect == "none", even.summary
    assert not any("scatter too much" in r for r in even.confidence_reasons)
    rng = np.random.default_rng(11)
    cyc = df["cycle"].to_numpy()
    ids = np.unique(cyc[cyc >= 0])
    size = float(np.sqrt(np.mean(df["drawbar_pull_n"].to_numpy() ** 2)))
    offset = dict(zip(ids, rng.normal(0.0, 0.15 * size, ids.size)))
    rough = df.copy()
    rough["drawbar_pull_n"] += np.array([offset.get(c, 0.0) for c in cyc])
    d = diagnose(rough, SAND, W)
    _invariants(d)
    assert d.effect in ("none", "unexplained"), d.summary
    if d.effect == "none":
        assert d.confidence != "high"
        assert any("scatter too much" in r for r in d.confidence_reasons), d.confidence_reasons


def test_none_from_a_few_units_that_cannot_exclude_a_relevant_error_is_low():
    """A run of few independent units whose scatter leaves room for a relevant mean error (a vehicle that
    barely moves: library round 4915, heavy clay) cannot tell 'none': low; with many units, or precise
    enough, at most medium."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import MIN_UNITS_HIGH, _confidence
    from wheelsoil.model.structure import MIN_REL

    def conf(n_units, upper_rel):
        tests = {"drawbar_pull_n": {"p": 0.5, "channel": "drawbar_pull_n", "level_upper_rel": upper_rel,
                                    "level_upper_abs": upper_rel * 1000.0}}
        return _confidence("none", "wong", {}, {"none": 1.0}, {}, SimpleNamespace(n_units=n_units), tests, None,
                           [], [], {}, {}, [])[0]

    assert conf(MIN_UNITS_HIGH - 1, 10 * MIN_REL) == "low"
    assert conf(MIN_UNITS_HIGH + 20, 10 * MIN_REL) == "medium"
    assert conf(MIN_UNITS_HIGH - 1, 0.5 * MIN_REL) == "medium"  # few units cap "high" only
    assert conf(MIN_UNITS_HIGH + 20, 0.5 * MIN_REL) == "high"


def test_none_counts_the_cycles_behind_a_loose_bound_and_follows_its_posterior():
    """A time series of many cells but few accelerate cycles whose mean error or error along the run
    the cycles cannot bound (a soil alternating along the track, held-out batch 11): 'none' is low;
    and, as for a named cause, a posterior of no effect under P_NAME makes it low."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import MIN_UNITS_HIGH, P_HIGH, P_NAME, _confidence
    from wheelsoil.model.structure import MIN_REL

    def conf(cycles, upper_rel, p_none=1.0, key="drawbar_pull_n"):
        t = {"p": 0.5, "channel": "drawbar_pull_n", "units": 170 if key == "drawbar_pull_n" else cycles,
             "level_upper_rel": upper_rel, "level_upper_abs": upper_rel * 1000.0}
        if key == "drawbar_pull_n":
            t["cycles"] = cycles
        else:  # along the run: the cycle means are the units of the RMS bound
            t.update(level_upper_rel=0.0, rms_upper_rel=upper_rel, rms_upper_abs=upper_rel * 1000.0)
        return _confidence("none", "wong", {}, {"none": p_none, "unexplained": 1.0 - p_none}, {},
                           SimpleNamespace(n_units=170), {key: t}, None, [], [], {}, {}, [])[0]

    assert conf(MIN_UNITS_HIGH - 3, 10 * MIN_REL) == "low"
    assert conf(MIN_UNITS_HIGH - 3, 10 * MIN_REL, key="drawbar_pull_n@x") == "low"
    assert conf(MIN_UNITS_HIGH + 5, 10 * MIN_REL) == "medium"
    assert conf(MIN_UNITS_HIGH - 3, 0.5 * MIN_REL) == "high"  # the cycles bound the error: not loose
    assert conf(MIN_UNITS_HIGH + 5, 0.5 * MIN_REL, p_none=0.5 * (P_NAME + P_HIGH)) == "medium"
    assert conf(MIN_UNITS_HIGH + 5, 0.5 * MIN_REL, p_none=0.5 * P_NAME) == "low"


def test_none_is_high_only_when_the_run_bounds_an_error_of_every_tested_form():
    """An error with no mean (a gain drifting over the run, an error following the load) passes a bound on
    the mean; "none" at "high" also needs the 95 % bound on the RMS of an error of each structure test's
    form below MIN_REL, and that bound covers the true RMS."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import MIN_UNITS_HIGH, _confidence
    from wheelsoil.model.structure import MIN_REL, _structure_1d

    def conf(rms_rel):
        tests = {"drawbar_pull_n@x": {"p": 0.5, "channel": "drawbar_pull_n", "level_upper_rel": 0.2 * MIN_REL,
                                      "level_upper_abs": 1.0, "rms_upper_rel": rms_rel, "rms_upper_abs": 9.0}}
        return _confidence("none", "wong", {}, {"none": 1.0}, {}, SimpleNamespace(n_units=MIN_UNITS_HIGH + 20),
                           tests, None, [], [], {}, {}, [])

    assert conf(0.5 * MIN_REL)[0] == "high"
    word, why = conf(2 * MIN_REL)
    assert word == "medium" and any("RMS error in the drawbar pull along the run" in w for w in why), why
    assert conf(float("nan"))[0] == "medium"  # a bound that could not be computed proves nothing
    rng = np.random.default_rng(5)
    x = np.linspace(-0.5, 0.5, 12)
    mu = 0.8 * (x / np.sqrt(np.mean(x**2)))  # a drift of RMS 0.8 sigma with no mean
    covered = [_structure_1d(x, mu + rng.standard_normal(x.size))["rms_upper"] >= 0.8 for _ in range(300)]
    assert 0.90 <= np.mean(covered) < 1.0
    bounds = [_structure_1d(np.linspace(-1, 1, u), rng.standard_normal(u))["rms_upper"] for u in (8, 200)
              for _ in range(50)]
    assert np.median(bounds[50:]) < 0.5 * np.median(bounds[:50])  # more units, a tighter bound


def test_the_separating_measurement_names_what_tells_each_stand_in_from_a_listed_cause():
    from wheelsoil.model.diagnosis import _separating

    for name, words in (("speed_gain", "vehicle speed"), ("rebound", "rut depth"), ("shear_slip", "shear rates"),
                        ("angle_offset", "calibration"), ("load_k", "second static load"),
                        ("envelope", "range of normal stress"), ("k_stress", "range of normal stress")):
        text = _separating({"terrain_mismatch", "unexplained"}, {"drawbar_pull_n", "torque_nm"}, [name])
        assert text and words in text, (name, text)
    text = _separating({"slip_sinkage", "unexplained"}, {"drawbar_pull_n", "torque_nm"}, ["speed_sinkage"])
    assert text and "another forward speed" in text, text
    assert _separating({"none"}, {"drawbar_pull_n"}, []) is None
    assert "where the wheel ran" in _separating({"terrain_mismatch"}, {"drawbar_pull_n"}, ["terrain"])


def test_a_named_cause_says_which_causes_on_no_list_it_does_not_exclude():
    from wheelsoil.model.diagnosis import _not_excluded

    assert "firm layer" in _not_excluded("terrain_mismatch", None)  # measured: held-out batches 3 and 4
    assert "interface" in _not_excluded("terrain_mismatch", None)  # measured: held-out batch 8
    assert "falls with slip" in _not_excluded("stress_distribution", None)
    assert "interface weaker" in _not_excluded("stress_distribution", None)  # measured: foreign13's f13r2_16
    assert "sinkage against slip" in _not_excluded("slip_sinkage", {"significant": False})
    assert _not_excluded("slip_sinkage", {"significant": True}) is None  # the sinkage channel rules them out
    assert _not_excluded("none", None) is None and _not_excluded("unexplained", None) is None


def test_only_the_five_value_terrain_refit_explains_it_then_no_cause_is_named():
    """The five-value re-fit follows causes on no list as well as a terrain mismatch (held-out
    batches): when no re-fit of one or two lab values (nor of one lab test's values) explains the data,
    here three values off (K x0.5, k_eq x1.3, phi +3 deg), Wong is shown to err, not that a soil value is
    what is wrong."""
    truth = SAND.replace(K=SAND.K * 0.5, kc=SAND.kc * 1.3, kphi=SAND.kphi * 1.3, phi=SAND.phi + math.radians(3))
    d = diagnose(_table(truth=truth, seed=1, n=150), SAND, W)
    _invariants(d)
    assert d.model == "terrain" and d.effect == "unexplained" and d.why == "catch_all", d.summary
    assert "the data do not show which value is wrong" in d.summary and d.not_excluded is None
    # the value the data place beyond one lab sd (K x0.5: 2.3 lab sd) is reported, with its standard error
    assert "the data's own estimate (the lab prior's pull undone) places K -" in d.summary
    est = d.to_dict()["models"]["terrain"]["params"]["K"]["data_estimate"]
    assert est["beyond_one_sd"] and est["z"] < -1.0 - 1.96 * est["se"], est
    # what would tell a soil of other values from a cause acting like one: the soil's own tests, where it ran
    assert "plate-sinkage and shear tests of this soil where the wheel ran" in d.separating_measurement
    assert d.to_dict()["channels"]["drawbar_pull_n"]["effect"] == "unexplained"


def test_the_catch_alls_are_the_five_value_refit_its_drifts_and_the_shear_tests_refit():
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import _catch_all
    from wheelsoil.model.hypotheses import HYPOTHESES

    caught = {k for k, h in HYPOTHESES.items() if _catch_all(SimpleNamespace(effect=h.effect, hypothesis=h))}
    # slip sinkage + terrain names its slip part; the plate test's re-fit and the pairs name a lab error
    assert caught == {"terrain", "drift_linear", "drift_step", "terrain_shear"}


def test_a_none_that_cannot_exclude_a_relevant_error_says_so():
    """Three short cycles of a Wong soil under a noise far above the effects' sizes: no structure,
    and the cycles cannot bound Wong's mean error below 3 %: the summary says Wong is kept for want of
    evidence, not confirmed (library round 4915, seed 4931: a vehicle that barely moves)."""
    df = synthetic_data(SAND, W, "wong", duration_s=30.0, load_n=13000.0, noise_dp_n=1500.0, noise_t_nm=900.0,
                        seed=2)
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect == "none", d.summary
    assert "cannot exclude one either" in d.summary and d.confidence != "high"


def test_the_evidence_route_needs_no_more_parameters_than_the_rival():
    """Two fits that predict the held-out cells alike: the candidate holds against the rival by
    evidence only when it has no more fitted parameters (a more flexible form's in-sample edge may
    be absorbed model discrepancy; seed 5869 of the benchmark), or when the rival leaves a relevant
    systematic error that the candidate does not (seed 7196: a clay stress shift against a phi
    re-fit leaving 6 % of Dp)."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import _holds_against

    rng = np.random.default_rng(0)
    y = rng.normal(1000.0, 50.0, 40)
    pred = y + rng.normal(0.0, 5.0, 40)
    cells = SimpleNamespace(channels={"drawbar_pull_n": y}, var={"drawbar_pull_n": np.full(40, 25.0)})
    data = SimpleNamespace(cells=cells)
    cv = {"fold": np.repeat(np.arange(10), 4), "held_cells": {"drawbar_pull_n": pred}, "cv_R0": {}}

    def fit(k):
        return SimpleNamespace(k=k, cv=cv)

    assert _holds_against(data, fit(1), fit(1), ["drawbar_pull_n"]) == "evidence"
    assert _holds_against(data, fit(1), fit(2), ["drawbar_pull_n"]) == "evidence"
    assert _holds_against(data, fit(2), fit(1), ["drawbar_pull_n"]) is None
    # ... unless the simpler rival leaves a relevant systematic error of its own that the candidate
    # does not (asked only when no other route holds)
    assert _holds_against(data, fit(2), fit(1), ["drawbar_pull_n"], leaves=lambda: True) == "leaves structure"
    assert _holds_against(data, fit(2), fit(1), ["drawbar_pull_n"], leaves=lambda: False) is None
    asked = []
    _holds_against(data, fit(1), fit(1), ["drawbar_pull_n"], leaves=lambda: asked.append(1) or True)
    assert not asked
    # and never for a candidate that predicts new data worse than the rival
    worse = SimpleNamespace(k=2, cv={**cv, "held_cells": {"drawbar_pull_n": y + rng.normal(0.0, 60.0, 40)}})
    assert _holds_against(data, worse, fit(1), ["drawbar_pull_n"], leaves=lambda: True) is None


def test_a_one_value_refit_falls_short_when_its_whole_predicts_a_channel_better():
    """A one-value terrain re-fit is named only when the five-value re-fit (its whole) predicts no
    measured channel better out of sample and worsens none (batch 8 of the benchmark: a tyre-soil
    interface weaker than the soil named a phi mismatch while the five values predicted the torque
    better on every held-out cycle)."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import _whole_better
    from wheelsoil.model.hypotheses import HYPOTHESES

    rng = np.random.default_rng(1)
    n, chans = 40, ("drawbar_pull_n", "torque_nm")
    y = {c: rng.normal(1000.0, 50.0, n) for c in chans}
    cells = SimpleNamespace(channels=y, var={c: np.full(n, 25.0) for c in chans})
    data = SimpleNamespace(cells=cells)
    fold = np.repeat(np.arange(10), 4)

    def fit(name, off):  # held-out predictions off the data by `off` noise sigmas (+ a little scatter)
        held = {c: y[c] + 5.0 * (off[c] + 0.1 * rng.standard_normal(n)) for c in chans}
        return SimpleNamespace(name=name, hypothesis=HYPOTHESES[name], success=True,
                               cv={"fold": fold, "held_cells": held, "cv_R0": {}})

    one = fit("terrain_phi", {"drawbar_pull_n": 0.3, "torque_nm": 1.0})
    wholes = {k: h.whole for k, h in HYPOTHESES.items() if h.whole}
    drifting = ("k_eq", "n", "c", "phi", "K", "k_eq_n", "k_eq_c", "k_eq_phi", "k_eq_K", "n_c", "n_phi", "n_K", "c_K",
                "phi_K")  # one value or two, the five levels re-fitted
    assert wholes == {**{f"terrain_{p}": "terrain" for p in ("k_eq", "n", "c", "phi", "K", "plate", "shear", "k_eq_c",
                                                             "k_eq_phi", "k_eq_K", "n_c", "n_phi", "n_K", "c_K",
                                                             "phi_K")},
                      **{f"drift_{p}": "drift_linear" for p in ("k_eq", "n", "c", "phi", "K")},
                      **{f"drift_step_{p}": "drift_step" for p in ("k_eq", "n", "c", "phi", "K")},
                      **{f"drift_{p}+terrain": "drift_linear" for p in drifting},
                      **{f"drift_step_{p}+terrain": "drift_step" for p in drifting}}
    better = fit("terrain", {"drawbar_pull_n": 0.3, "torque_nm": 0.2})
    assert _whole_better(data, {"terrain_phi": one, "terrain": better}, one) == ["torque_nm"]
    same = fit("terrain", {"drawbar_pull_n": 0.3, "torque_nm": 1.0})
    assert _whole_better(data, {"terrain_phi": one, "terrain": same}, one) == []
    trade = fit("terrain", {"drawbar_pull_n": 1.5, "torque_nm": 0.2})  # better torque, worse Dp: no verdict on it
    assert _whole_better(data, {"terrain_phi": one, "terrain": trade}, one) == []
    assert _whole_better(data, {"terrain_phi": one}, one) == []  # the whole not fitted
    assert _whole_better(data, {"terrain": better}, better) == []  # no whole


def test_the_refits_of_two_or_three_lab_values_share_the_prior_mass_of_one_form():
    """Each effect has prior mass 1, split equally among its forms; the ten re-fits of two or three
    lab values (the lab tests' and the pairs') count as one form, so that adding them takes from the
    one-value re-fits only the share of one more form (a one-value k_eq mismatch of the third
    generator, tk2, tied with a stand-in within a Bayes factor of 10 once eight forms shared the
    effect's mass equally)."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import _prior_masses
    from wheelsoil.model.hypotheses import HYPOTHESES

    names = [k for k, h in HYPOTHESES.items() if h.effect in ("terrain_mismatch", "none")] + ["dp_resistance"]
    fits = {k: SimpleNamespace(effect=HYPOTHESES[k].effect, hypothesis=HYPOTHESES[k]) for k in names}
    mass = _prior_masses(fits, names)
    several = [k for k in names if HYPOTHESES[k].prior_group]
    assert sorted(several) == sorted(["terrain_plate", "terrain_shear", "terrain_k_eq_c", "terrain_k_eq_phi",
                                      "terrain_k_eq_K", "terrain_n_c", "terrain_n_phi", "terrain_n_K",
                                      "terrain_c_K", "terrain_phi_K"])
    assert mass["terrain_k_eq"] == pytest.approx(1 / 7) and mass["terrain"] == pytest.approx(1 / 7)
    assert mass["terrain_shear"] == pytest.approx(1 / 7 / 10)
    assert sum(m for k, m in mass.items() if fits[k].effect == "terrain_mismatch") == pytest.approx(1.0)
    assert mass["wong"] == 1.0 and mass["dp_resistance"] == 1.0


def test_a_catch_all_gives_way_to_a_narrower_form_it_neither_outweighs_strongly_nor_outpredicts():
    """The five-value drift with 6x the evidence of the one-value k_eq drift (benchmark seed 8251, a
    clay k_eq drift x1.35): the catch-all is not strongly preferred (Bayes factor < 10), and when it
    predicts no channel better out of sample the one-value drift becomes the candidate; with a Bayes
    factor above 10, or a catch-all that predicts a channel better on new data, the catch-all stays."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import BF_ALTERNATIVE, _narrower
    from wheelsoil.model.hypotheses import HYPOTHESES

    rng = np.random.default_rng(3)
    n, chans = 40, ("drawbar_pull_n", "torque_nm")
    y = {c: rng.normal(1000.0, 50.0, n) for c in chans}
    data = SimpleNamespace(cells=SimpleNamespace(channels=y, var={c: np.full(n, 25.0) for c in chans}))
    fold = np.repeat(np.arange(10), 4)

    def fit(name, off):
        held = {c: y[c] + 5.0 * (off[c] + 0.1 * rng.standard_normal(n)) for c in chans}
        h = HYPOTHESES[name]
        return SimpleNamespace(name=name, hypothesis=h, effect=h.effect, success=True,
                               cv={"fold": fold, "held_cells": held, "cv_R0": {}})

    one = fit("drift_k_eq", {"drawbar_pull_n": 0.3, "torque_nm": 1.0})
    same = fit("drift_linear", {"drawbar_pull_n": 0.3, "torque_nm": 1.0})
    better = fit("drift_linear", {"drawbar_pull_n": 0.3, "torque_nm": 0.2})
    other = fit("dp_drift", {"drawbar_pull_n": 0.3, "torque_nm": 0.3})  # another effect: never the narrower form
    supported = ["drift_linear", "drift_k_eq", "dp_drift"]
    close = {"drift_linear": 0.86, "drift_k_eq": 0.14, "dp_drift": 0.5}
    far = {"drift_linear": 0.99, "drift_k_eq": 0.99 / (2 * BF_ALTERNATIVE), "dp_drift": 0.5}
    fits = {"drift_linear": same, "drift_k_eq": one, "dp_drift": other}
    assert _narrower(data, fits, "drift_linear", supported, close) == "drift_k_eq"
    assert _narrower(data, fits, "drift_linear", supported, far) == "drift_linear"
    assert _narrower(data, {**fits, "drift_linear": better}, "drift_linear", supported, close) == "drift_linear"
    assert _narrower(data, fits, "drift_linear", ["drift_linear", "dp_drift"], close) == "drift_linear"


def test_a_named_model_outweighed_by_a_turned_down_sibling_is_low():
    """The effect's probability may come from a hypothesis of the same effect that the out-of-sample
    gates turned down (batch 10, seed 14062: a k_eq re-fit with 116x the evidence failed the paired
    test, an n re-fit passed and was named at 'high'): it does not back the named model's claim."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import BF_ALTERNATIVE, MIN_UNITS_HIGH, _confidence

    def conf(p_sibling, p_named):
        fits = {k: SimpleNamespace(effect="terrain_mismatch", cv={}, prior={}, chi2_prior=0.0) for k in ("terrain_n", "terrain_k_eq")}
        paired = {"terrain_n": {"drawbar_pull_n": {"wong_cv_rmse": 46.0, "cv_rmse": 35.0, "p_improve": 0.003,
                                                   "folds": 13}}}
        probs = {"terrain_n": p_named, "terrain_k_eq": p_sibling}
        return _confidence("terrain_mismatch", "terrain_n", fits, {"terrain_mismatch": 1.0}, {},
                           SimpleNamespace(n_units=MIN_UNITS_HIGH + 50), {}, None, [], ["terrain_n"], probs,
                           paired, ["drawbar_pull_n"])

    word, why = conf(0.9, 0.9 / (2 * BF_ALTERNATIVE))
    assert word == "low" and any("not supported out of sample" in w for w in why)
    word, why = conf(0.9, 0.9 / (0.5 * BF_ALTERNATIVE))  # within the Bayes factor: as before
    assert word == "medium" and not any("not supported out of sample" in w for w in why)


def test_a_named_cause_is_high_only_when_its_look_alikes_are_excluded():
    """The posterior is over the causes tried: a terrain mismatch (on Dp and T, look-alikes such as a
    soil stiffer at the wheel's loading rate not excluded) is at most "medium" however probable; slip
    sinkage with the measured sinkage growing with slip can be "high"."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import MIN_UNITS_HIGH, _confidence

    def conf(effect, model, sink_ev):
        fits = {model: SimpleNamespace(effect=effect, cv={}, prior={}, chi2_prior=0.0)}
        paired = {model: {"drawbar_pull_n": {"wong_cv_rmse": 46.0, "cv_rmse": 35.0, "p_improve": 0.003, "folds": 17}}}
        return _confidence(effect, model, fits, {effect: 0.999}, {}, SimpleNamespace(n_units=MIN_UNITS_HIGH + 50),
                           {}, sink_ev, [], [model], {model: 0.999}, paired, ["drawbar_pull_n"])

    word, why = conf("terrain_mismatch", "terrain_k_eq", None)
    assert word == "medium" and any("not excluded by these data" in w for w in why)
    grows = {"significant": True, "p_positive": 1e-6}
    assert conf("slip_sinkage", "lyasko", grows)[0] == "high"
    assert conf("slip_sinkage", "lyasko", None)[0] == "medium"


def test_none_is_not_high_when_the_cell_noise_reaches_the_relevance_floor():
    """A channel whose cell noise is MIN_REL of its magnitude or more has its relevance threshold set by
    the noise: an error at the floor in a form no structure test looks for (a gain drifting over the
    run, a lagging load channel: held-out batches 5 and 6) passes for noise, so 'none' is at most
    medium, with the reason; well under the floor nothing changes."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import MIN_UNITS_HIGH, _confidence
    from wheelsoil.model.structure import MIN_EFFECT

    def conf(sigma_rel):
        tests = {"torque_nm": {"p": 0.5, "channel": "torque_nm", "level_upper_rel": 0.2 * MIN_REL,
                               "level_upper_abs": 1.0, "rms_upper_rel": 0.2 * MIN_REL, "rms_upper_abs": 1.0,
                               "sigma_rel": 0.1 * MIN_REL},
                 "drawbar_pull_n": {"p": 0.5, "channel": "drawbar_pull_n", "level_upper_rel": 0.2 * MIN_REL,
                                    "level_upper_abs": 1.0, "rms_upper_rel": 0.2 * MIN_REL, "rms_upper_abs": 1.0,
                                    "sigma_rel": sigma_rel}}
        return _confidence("none", "wong", {}, {"none": 1.0}, {}, SimpleNamespace(n_units=MIN_UNITS_HIGH + 20),
                           tests, None, [], [], {}, {}, [])

    assert conf(0.5 * MIN_REL / MIN_EFFECT) == ("high", [])
    word, why = conf(1.2 * MIN_REL / MIN_EFFECT)
    assert word == "medium" and any("drawbar pull" in w and "pass for noise" in w for w in why), why
    assert not any("torque" in w for w in why)
    # end to end: the report's structure tests carry the noise floor a run's confidence is judged by
    df = synthetic_data(SAND, W, "wong", duration_s=40.0, load_n=13000.0, noise_dp_n=600.0, seed=3)
    d = diagnose(df, SAND, W)
    _invariants(d)
    rel = d.structure["wong"]["drawbar_pull_n"]["sigma_rel"]
    assert MIN_EFFECT * rel >= MIN_REL, rel
    assert d.effect != "none" or d.confidence != "high", (d.effect, d.confidence_reasons)


def test_a_lagging_torque_channel_is_unexplained_not_none_nor_a_cause():
    """A torque channel behind the force channels by a first-order lag (held-out batch 10's torque
    lags): the accelerate cycles' cells pool rising and falling slip and average the lag away, so the
    static hypotheses saw `none` or, from the torque alone, slip sinkage.  Wong's residuals differ
    between rising and falling slip, which no static hypothesis can make: `unexplained`, with the
    reason and the torque's verdict; the same run without the lag shows no such difference."""
    from scipy.signal import lfilter, lfilter_zi

    df = synthetic_data(SAND, W, "wong", duration_s=120.0, load_n=13000.0, seed=4)
    # each cycle with its falling ramp, as processing labels a recording's accelerate cycles
    # (synthetic_data labels the rising ramp only)
    cyc = df["cycle"].where(df["cycle"] >= 0).ffill()
    df["cycle"] = np.where(df["slip"] > 0, cyc, -1).astype(int)
    d0 = diagnose(df, SAND, W)
    _invariants(d0)
    assert d0.effect == "none", d0.summary
    assert d0.hysteresis_test["torque_nm"]["cycles"] >= 3
    assert not any(t["significant"] for t in d0.hysteresis_test.values()), d0.hysteresis_test
    tau_s, dt = 0.8, float(np.median(np.diff(df["t_s"])))
    a = dt / (tau_s + dt)
    x = df["torque_nm"].to_numpy()
    lagged = df.copy()
    lagged["torque_nm"] = lfilter([a], [1.0, a - 1.0], x, zi=lfilter_zi([a], [1.0, a - 1.0]) * x[0])[0]
    d = diagnose(lagged, SAND, W)
    _invariants(d)
    h = d.hysteresis_test["torque_nm"]
    assert h["significant"] and h["h"] < 0, h  # a lagging torque reads low on rising slip
    assert d.effect == "unexplained" and d.confidence != "high", d.summary
    assert "rising and falling slip" in d.summary
    assert "ramp rate" in d.separating_measurement
    assert d.to_dict()["channels"]["torque_nm"]["effect"] == "unexplained"
    assert diagnose(_table(seed=0), SAND, W).hysteresis_test == {}  # a table has no time


def test_a_sinkage_trend_is_tested_with_one_degree_of_freedom():
    """A residual growing linearly with slip on 12 rows (a table's sinkage under slip sinkage, Eqs. 11-13):
    the straight-line trend test, one numerator degree of freedom, finds it with a smaller p than the
    quadratic and binned-means tests, which spend three and four; over ten noise draws its combined p is
    lower in every one. Without ``slope`` (the drawbar pull, the torque) the test is as before."""
    from wheelsoil.model.structure import _structure_1d

    s = np.linspace(0.15, 0.9, 12)
    for seed in range(10):
        e = (s - s.mean()) / s.std() + np.random.default_rng(seed).normal(0.0, 1.0, s.size)
        with_trend, without = _structure_1d(s, e, slope=True), _structure_1d(s, e)
        assert with_trend["p_slope"] < with_trend["p_poly"], seed
        assert with_trend["p"] < without["p"], seed
        assert np.isnan(without["p_slope"]) and without["p_poly"] == with_trend["p_poly"]


def test_a_patch_change_a_short_run_cannot_confirm_is_reported_with_its_numbers():
    """Another patch of ground (phi -1.5 deg) over the second half of a 60 s run (6 folds): the step
    drift is by far the most probable hypothesis and lowers the held-out error, but too few folds carry
    the change for the paired test; the verdict is then not a cause, and the summary says what that
    hypothesis does on new data and that a longer run would tell (foreign2's dr2 case in small)."""
    df = synthetic_data(SAND, W, "wong", duration_s=60.0, load_n=13000.0, seed=11)
    x = df["distance_m"].to_numpy() / df["distance_m"].max()
    m = (x > 0.5) & (df["slip"] > 0).to_numpy() & (df["slip"] < 1).to_numpy()
    f0 = wong_forces(SAND, W, df["load_n"][m], df["slip"][m])
    f1 = wong_forces(SAND.replace(phi=SAND.phi - math.radians(1.5)), W, df["load_n"][m], df["slip"][m])
    df.loc[m, "drawbar_pull_n"] += f1.drawbar_pull_n - f0.drawbar_pull_n
    df.loc[m, "torque_nm"] += f1.torque_nm - f0.torque_nm
    d = diagnose(df, SAND, W)
    _invariants(d)
    assert d.effect in ("terrain_drift", "unexplained")
    top = max(d.probabilities, key=d.probabilities.get)
    assert d.fits[top].effect == "terrain_drift"
    if d.effect == "unexplained":
        assert top in d.why_not and "only inconsistently over the folds" in d.why_not[top]
        r = d.paired[top]["drawbar_pull_n"]
        assert r["cv_rmse"] < r["wong_cv_rmse"]
        assert "a run with more accelerate cycles would tell" in d.summary


def test_a_lab_value_far_beyond_its_stated_uncertainty_is_still_a_terrain_mismatch():
    """A field soil far from the lab sample in one value: sand k_eq x3, about 3.7 of the lab's
    stated standard deviations (30 %) of its logarithm. The one-value re-fit was refused as a prior-data conflict
    and the run left `unexplained`; a mismatch of one lab value is what the cause says, and the
    report says how far the value lies from the lab's."""
    k_eq = SAND.kc / W.width + SAND.kphi
    truth = SAND.replace(kc=SAND.kc * 3.0, kphi=SAND.kphi * 3.0)
    d = diagnose(_table(truth=truth, seed=2), SAND, W)
    _invariants(d)
    assert d.effect == "terrain_mismatch" and d.model == "terrain_k_eq"
    assert abs(d.fits[d.model].params["k_eq"] - 3.0 * k_eq) < abs(d.fits[d.model].params["k_eq"] - k_eq)
    assert d.fits[d.model].chi2_prior > 10.83  # beyond the 0.999 quantile on one parameter
    assert any("far from the lab value" in r for r in d.confidence_reasons)
    assert not any("off the lab only weakly" in r for r in d.confidence_reasons)


def test_a_mismatch_the_data_show_only_weakly_is_named_at_low_confidence():
    """The clay's shear test off by K x1.5 and phi +3 deg, about 1.5 lab sd each: the pair is named (the point
    estimates lie beyond one lab sd), but the data's own estimates, phi about 1.2 +/- 0.6 sd and K 1.4 +/- 1.3 sd,
    lie within what a soil within the lab's uncertainty gives at one sigma, so the confidence is "low" and says
    why; K x2 and phi +5 deg, beyond it, are named without that cap."""
    from wheelsoil.model.diagnosis import _lab_departure

    for k_factor, dphi, weak in ((1.5, 3.0, True), (2.0, 5.0, False)):
        truth = CLAY.replace(K=CLAY.K * k_factor, phi=CLAY.phi + math.radians(dphi))
        d = diagnose(_table(terrain=CLAY, truth=truth, seed=1), CLAY, W)
        _invariants(d)
        assert d.effect == "terrain_mismatch", d.summary
        m2, q, est = _lab_departure(d.fits[d.model])
        said = [r for r in d.confidence_reasons if "off the lab only weakly" in r]
        assert (m2 <= q) == weak and bool(said) == weak, (m2, q, est)
        if weak:
            assert d.confidence == "low" and "phi" in said[0] and f"against {q:.2g}" in said[0]


@pytest.mark.parametrize("terrain, change, test", [
    (CLAY, {"K": 1.5, "phi_deg": 3.0}, "phi_K"),
    (SAND, {"k_eq": 0.6, "n": 0.15}, "plate"),
    (SAND, {"K": 0.5, "k_eq": 1.3}, "k_eq_K"),
], ids=["clay-shear", "sand-plate", "sand-one-of-each"])
def test_two_values_wrong_are_a_terrain_mismatch_in_those_values(terrain, change, test):
    """Two values of one lab test off together (a faulty shear test: K x1.5 and phi +3 deg on clay, named
    by the pair of K and phi, as the shear test's three values together are a catch-all; a faulty plate
    test: k_eq x0.6 and n +0.15 on sand, 1.7 and 1.5 of the lab's default standard deviations), or one of each (a field soil other than the sample: K x0.5 and
    k_eq x1.3 on sand): no one-value re-fit follows them, and the five-value re-fit names no cause; the
    re-fit of those values does (benchmark seed 8232, a clay K x1.50 and phi +3.1 deg, and 8266, a sand
    c x0.65 and n -0.15, were `unexplained` with the five-value re-fit the candidate)."""
    repl = {}
    if "K" in change:
        repl["K"] = terrain.K * change["K"]
    if "phi_deg" in change:
        repl["phi"] = terrain.phi + math.radians(change["phi_deg"])
    if "k_eq" in change:
        repl.update(kc=terrain.kc * change["k_eq"], kphi=terrain.kphi * change["k_eq"])
    if "n" in change:
        repl["n"] = terrain.n + change["n"]
    truth = terrain.replace(**repl)
    d = diagnose(_table(terrain=terrain, truth=truth, seed=1), terrain, W)
    _invariants(d)
    assert d.effect == "terrain_mismatch" and d.model == f"terrain_{test}", d.summary
    f = d.fits[d.model]
    true_values = {"k_eq": truth.k_eq(W.width), "n": truth.n, "c": truth.c, "phi": truth.phi, "K": truth.K}
    lab_values = {"k_eq": terrain.k_eq(W.width), "n": terrain.n, "c": terrain.c, "phi": terrain.phi, "K": terrain.K}
    for p in ({"phi_deg": "phi"}.get(k, k) for k in change):
        assert abs(f.params[p] - true_values[p]) < abs(f.params[p] - lab_values[p]), p


@pytest.mark.parametrize("seed", [1, 2])
def test_a_soil_within_the_lab_uncertainty_is_none_not_unexplained(seed):
    """A field soil that differs from the lab's in every value, each well within the lab's stated
    uncertainty (k_eq x1.12, n +0.04, phi -1 deg, K x0.92, c x1.1 on clay): Wong with the lab's values errs
    significantly, and only re-fits of the soil explain it. The lab's own uncertainty allows that soil, so no
    cause is shown: `none`, saying why, at low confidence (two independent generators, the seventh and
    eighth, draw their `none` soils so; the pipeline said `unexplained` on them)."""
    truth = CLAY.replace(kc=CLAY.kc * 1.12, kphi=CLAY.kphi * 1.12, n=CLAY.n + 0.04, phi=CLAY.phi - math.radians(1.0),
                         K=CLAY.K * 0.92, c=CLAY.c * 1.1)
    d = diagnose(_table(terrain=CLAY, truth=truth, seed=seed, n=150), CLAY, W)
    out = _invariants(d)
    assert d._sig_w, "Wong's error must be significant for the test to mean anything"  # noqa: SLF001
    assert d.effect == "none" and d.confidence == "low", d.summary
    lu = out["lab_uncertainty"]
    assert lu and lu["max_abs_z"] <= lu["lab_z"] and set(lu["z"]) == {"k_eq", "n", "c", "phi", "K"}
    assert d.fits[lu["candidate"]].effect == "terrain_mismatch"
    assert "within what the lab values' stated uncertainty allows" in d.summary
    assert all(r["effect"] == "none" for r in out["channels"].values() if r["measured"])


def test_a_soil_beyond_the_lab_uncertainty_is_not_passed_off_as_none():
    """The same clay with K x2.5 (about 4.4 lab standard deviations of its logarithm) besides the small
    offsets: the re-fit leaves the lab's range, so the lab's uncertainty does not explain Wong's error."""
    truth = CLAY.replace(kc=CLAY.kc * 1.12, kphi=CLAY.kphi * 1.12, n=CLAY.n + 0.04, K=CLAY.K * 2.5)
    d = diagnose(_table(terrain=CLAY, truth=truth, seed=1, n=150), CLAY, W)
    _invariants(d)
    assert d.lab_uncertainty is None and d.effect != "none", d.summary


def test_a_value_the_prior_pulls_within_the_lab_range_is_judged_by_the_datas_own_estimate():
    """A re-fitted value 1.7 lab sd from the lab with a posterior standard error of 0.72 lab sd: the prior's pull
    hides a data estimate of 1.7 / (1 - 0.72^2) = 3.5 sd (+/- 1.04), beyond one lab sd at the 97.5 % level (an
    independent generator's k_eq 3.5 sd off); the same offset measured precisely (0.1 sd) lies within one sd
    only when it is under it: 0.9 is, 1.5 is not; a value the data do not constrain is placed nowhere."""
    from types import SimpleNamespace

    from wheelsoil.model.diagnosis import _beyond_lab_sd

    def fit(z, s):
        return SimpleNamespace(prior={"n": (1.0, 0.1)}, params={"n": 1.0 + 0.1 * z},
                               stderr_fit={"n": 0.1 * s}, stderr={"n": 0.1 * s})

    assert _beyond_lab_sd(fit(1.7, 0.72)) == ["n"]
    assert _beyond_lab_sd(fit(0.9, 0.1)) == []
    assert _beyond_lab_sd(fit(1.5, 0.1)) == ["n"]
    assert _beyond_lab_sd(fit(1.5, 0.999)) == []


def test_a_refit_within_one_lab_sd_names_no_mismatch():
    """The sand's plate test off by k_eq x0.75 and n +0.08, 1.0 and 0.8 of the lab's default standard
    deviations (30 % and 0.1): the plate re-fit finds them, but a soil within the lab's stated uncertainty
    agrees with the lab, so no mismatch is named (`within_lab`), and the error stays `unexplained` (on the
    held-out testbed tables, such re-fits were causes on no list: a loading-rate-stiffened soil, a K growing
    with slip, lugs)."""
    truth = SAND.replace(kc=SAND.kc * 0.75, kphi=SAND.kphi * 0.75, n=SAND.n + 0.08)
    d = diagnose(_table(truth=truth, seed=1), SAND, W)
    _invariants(d)
    assert d.effect == "unexplained" and d.why == "within_lab" and d.model == "terrain_plate", d.summary
    assert "places no lab value beyond one lab standard deviation" in d.summary


@pytest.mark.parametrize("chi2_refit, chi2_cause, held_back", [(56.0, 4.0, False), (4.0, 4.0, True), (56.0, 21.5, True)],
                         ids=["refit-in-conflict", "both-credible", "both-in-conflict"])
def test_a_nested_refit_with_a_soil_in_conflict_with_the_lab_holds_back_only_a_credible_cause(
        monkeypatch, chi2_refit, chi2_cause, held_back):
    """A cause + terrain that predicts new data no better than the five-value re-fit it contains is held back
    by it unless that re-fit's soil lies beyond the lab prior while the cause's does not (a prior chi-square
    of 56 against 4 on 5 values, an independent generator's Vasil'ev run): the re-fit is then no credible
    explanation, and the out-of-sample tie says nothing against the cause.  With both soils beyond the prior
    (21.5: another generator's k_eq x0.45, a stress shift + terrain the most probable) the cause's evidence
    is that of a soil far from the lab's, and it is held back.  (The paired test is stubbed to a tie; the fit
    objects carry what the rule reads.)"""
    from types import SimpleNamespace

    from wheelsoil.model import diagnosis as dg

    monkeypatch.setattr(dg, "_paired", lambda data, g, f: {"drawbar_pull_n": {"worsens": False, "improves": False}})
    soil = {p: (0.0, 1.0) for p in ("k_eq", "n", "c", "phi", "K")}
    refit = SimpleNamespace(success=True, cv={}, prior=soil, effect="terrain_mismatch", chi2_prior=chi2_refit)
    cause = SimpleNamespace(hypothesis=SimpleNamespace(nested=("terrain",), terrain_block=False), prior=soil,
                            effect="slip_sinkage", chi2_prior=chi2_cause)
    q = dg.stats.chi2.ppf(1 - dg.PRIOR_CONFLICT_ALPHA, len(soil))  # the conflict quantile on 5 values (20.5)
    assert dg._prior_conflict(refit) == (chi2_refit > q) and dg._prior_conflict(cause) == (chi2_cause > q)
    assert dg._not_better_than_nested(None, {"terrain": refit}, cause, ["drawbar_pull_n"]) == (
        ["terrain"] if held_back else [])


def test_a_cause_whose_lab_soil_form_leaves_structure_is_named_only_on_a_soil_within_the_lab_uncertainty():
    """The route of ``_on_soil_within_lab`` (rule step 5): the most probable hypothesis, Lyasko with the soil
    re-fitted, held back only by the lab-soil Lyasko it does not beat on new data, is named in Lyasko's place;
    not when that lab-soil form is not supported, when nothing held it back, when the most probable
    hypothesis is of another effect, or when it leaves structure itself."""
    from wheelsoil.model.diagnosis import _on_soil_within_lab
    from wheelsoil.model.fit import prepare_data

    field = SAND.with_values(n=SAND.n + 0.05, phi=SAND.phi + math.radians(1.0))
    df = synthetic_data(SAND, DEFAULT_WHEEL, "lyasko", {"m1": 0.5, "m2": 0.05}, duration_s=30.0, load_n=9000.0,
                        terrain_truth=field, seed=0)
    d = diagnose(prepare_data(df, slip_min=0.1), SAND, DEFAULT_WHEEL)
    probs = dict(d.probabilities)
    top = max(probs, key=probs.get)
    assert top == "lyasko+terrain" and d.effect == "slip_sinkage"
    supported = [*d.supported, "lyasko"]
    held = {top: ["lyasko"]}
    assert _on_soil_within_lab(d.data, d.fits, "lyasko", supported, held, probs) == top
    assert _on_soil_within_lab(d.data, d.fits, "lyasko", [k for k in supported if k != "lyasko"], held, probs) is None
    assert _on_soil_within_lab(d.data, d.fits, "lyasko", supported, {}, probs) is None
    assert _on_soil_within_lab(d.data, d.fits, "lyasko", supported, held, {**probs, "terrain": 2.0}) is None
    wong_like = d.fits[top].__class__(**{**vars(d.fits[top]), "cell_pred": d.fits["wong"].cell_pred})
    assert _on_soil_within_lab(d.data, {**d.fits, top: wong_like}, "lyasko", supported, held, probs) is None
