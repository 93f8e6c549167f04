"""The diagnosis names the right cause on synthetic data, and 'none' when there is none."""

import numpy as np
import pytest

from wheelsoil.model import DEFAULT_WHEEL, load_terrain
from wheelsoil.model.diagnosis import diagnose, structure_test
from wheelsoil.model.fit import synthetic_data

SAND = load_terrain("sand")
CLAY = load_terrain("clay")
W = DEFAULT_WHEEL


def _table(model, params=None, *, terrain=SAND, truth=None, seed=0, n=120, **kw):
    return synthetic_data(terrain, W, model, params, kind="table", n_rows=n, load_n=13000.0,
                          terrain_truth=truth, seed=seed, **kw)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_none_when_data_follow_wong(seed):
    d = diagnose(_table("wong", seed=seed), SAND, W)
    assert d.effect == "none" and d.model == "wong"
    assert "no significant systematic structure" in d.summary


@pytest.mark.parametrize(
    "model, params",
    [("vasilev", {"H": 0.08}), ("lyasko", {"m1": 0.6, "m2": 0.03}), ("ding", {"n1": 0.3})],
)
def test_slip_sinkage_and_its_form(model, params):
    d = diagnose(_table(model, params, seed=11), SAND, W)
    assert d.effect == "slip_sinkage"
    assert d.model == model
    g = d.gain
    assert g["cv_R0_n_after"] < 0.5 * g["cv_R0_n_before"]


def test_terrain_mismatch_when_lab_k_and_phi_are_wrong():
    truth = SAND.replace(phi=SAND.phi * 0.85, K=0.045)
    d = diagnose(_table("wong", truth=truth, seed=3), SAND, W)
    assert d.effect == "terrain_mismatch" and d.model == "terrain_mismatch"
    f = d.fits["terrain_mismatch"]
    assert abs(f.params["phi"] - truth.phi) < 4 * f.stderr["phi"] + 0.01


def test_terrain_mismatch_on_clay_with_torque():
    truth = CLAY.replace(phi=np.radians(18), K=0.015)
    d = diagnose(_table("wong", terrain=CLAY, truth=truth, seed=4), CLAY, W)
    assert d.effect == "terrain_mismatch"


def test_unexplained_when_no_candidate_fits_the_structure():
    df = _table("wong", seed=5)
    df["drawbar_pull_n"] += 150.0 * np.sin(2 * np.pi * df["slip"] / 0.35)
    d = diagnose(df, SAND, W)
    assert d.effect == "unexplained"


def test_autocorrelated_time_series_without_effect_is_none():
    """Filtered 100 Hz noise must not be mistaken for structure (cycle x slip-cell aggregation)."""
    for seed in (0, 1):
        df = synthetic_data(SAND, W, "wong", duration_s=40.0, load_n=13000.0, seed=seed)
        d = diagnose(df, SAND, W, models=("vasilev", "terrain_mismatch"))
        assert d.effect == "none", d.summary
        # a per-sample test would see overwhelming 'structure' in the same residuals
        data = d.data
        e = (data.channels["drawbar_pull_n"] - d.fits["wong"].predictions["drawbar_pull_n"]) / data.sigma["drawbar_pull_n"]
        naive = data.subset(np.ones(data.n, bool))
        object.__setattr__(naive, "units", np.arange(data.n))
        assert structure_test(naive, e)["p"] < structure_test(data, e)["p"]


def test_time_series_with_slip_sinkage():
    df = synthetic_data(SAND, W, "lyasko", {"m1": 0.6, "m2": 0.03}, duration_s=40.0, load_n=13000.0, seed=2)
    d = diagnose(df, SAND, W, models=("vasilev", "lyasko", "terrain_mismatch"))
    assert d.effect == "slip_sinkage" and d.model == "lyasko"
    assert d.fits["lyasko"].cv["group_kind"] == "accelerate cycles"


def test_measured_sinkage_growth_is_direct_evidence():
    df = _table("vasilev", {"H": 0.05}, seed=7, n=40, noise_z_m=0.004)
    d = diagnose(df, SAND, W)
    assert d.sinkage_evidence["significant"]
    assert d.effect == "slip_sinkage"
    assert "direct evidence" in " ".join(d.confidence_reasons)


def test_flat_measured_sinkage_vetoes_nothing_but_is_reported():
    df = _table("wong", seed=8, n=40, noise_z_m=0.004)
    d = diagnose(df, SAND, W)
    assert not d.sinkage_evidence["significant"]
    assert d.effect == "none"


def test_candidate_that_does_not_converge_is_reported():
    d = diagnose(_table("lyasko", {"m1": 0.6, "m2": 0.03}, seed=9), SAND, W, max_iter=1)
    assert any("did not converge" in f for f in d.failures)
    assert d.effect in ("slip_sinkage", "unexplained")  # never a wrong cause from a failed fit
    assert d.model not in [k for k, f in d.fits.items() if not f.success]


def test_detectable_but_negligible_error_is_reported_not_diagnosed():
    df = _table("wong", seed=10, n=400, noise_dp_n=5.0)
    df["drawbar_pull_n"] += 3.0  # a 0.6-sigma bias: significant with 400 rows, far below 1 sigma
    d = diagnose(df, SAND, W, models=("vasilev",))
    assert d.structure["wong"]["drawbar_pull_n"]["p"] < 1e-4
    assert d.effect == "none"
    assert "statistically detectable" in d.summary and "not attributed" in d.summary
