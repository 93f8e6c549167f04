"""Physical consistency (model/consistency.py): vertical balance by slip bin (Eq. 7), sinkage limits (Eq. 10)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from wheelsoil.model import DEFAULT_WHEEL, Wheel, get_model, load_terrain, wong_forces
from wheelsoil.model.consistency import physical_consistency
from wheelsoil.model.wong import sinkage_eq10

# The paper's sand run: 8 kN static + 5 kN added on the left rear wheel; Tab. 3 sand coefficients.
SAND_LOAD_N = 13000.0
TAB3_SAND = {"vasilev": {"H": 0.08}, "lyasko": {"m1": 0.6, "m2": 0.03}, "ding": {"n1": 0.53}}


def _sweep(load_n: float, count_per_bin: int = 20):
    """A slip sweep 0.1-0.9 with ``count_per_bin`` samples in each of the bins 0.1-0.2, ..., 0.8-0.9,
    plus a bin of samples at exactly s = 0.9."""
    slip = np.concatenate([np.linspace(k / 10 + 0.01, k / 10 + 0.09, count_per_bin) for k in range(1, 9)]
                          + [np.full(count_per_bin, 0.9)])
    return np.full(slip.shape, load_n), slip


@pytest.mark.parametrize("name, expected", [("vasilev", 1.66), ("lyasko", 2.24)])
def test_tab3_sand_slip_sinkage_models_carry_far_more_than_the_load(name, expected):
    # issue 10: Vasil'ev and Lyasko with the paper's Tab. 3 sand coefficients carry 1.66x and
    # 2.24x the measured load at s = 0.9 (Eq. 7), which the check must flag.
    sand = load_terrain("sand")
    w, s = _sweep(SAND_LOAD_N)
    forces = get_model(name).predict(sand, DEFAULT_WHEEL, w, s, TAB3_SAND[name])
    res = physical_consistency(forces, w, s, sand, DEFAULT_WHEEL)
    at_09 = [b for b in res["load_ratio_by_slip"] if b["slip_lo"] <= 0.9 < b["slip_hi"]]
    assert len(at_09) == 1 and at_09[0]["count"] == 20
    assert at_09[0]["ratio_median"] == pytest.approx(expected, abs=0.01)
    assert res["max_load_ratio_dev"] == pytest.approx(expected - 1.0, abs=0.01)
    assert res["load_ok"] is False and res["consistent"] is False
    assert any("Eq. 7" in r and f"{expected:.2f}x" in r for r in res["reasons"])
    # the ratio grows with slip: slip sinkage adds load-bearing sinkage the wheel does not have
    ratios = [b["ratio_median"] for b in res["load_ratio_by_slip"]]
    assert all(np.diff(ratios) > 0)


def test_plain_wong_on_paper_sand_is_ten_percent_over_and_beyond_d_over_6():
    sand = load_terrain("sand")
    w, s = _sweep(SAND_LOAD_N)
    forces = wong_forces(sand, DEFAULT_WHEEL, w, s)
    res = physical_consistency(forces, w, s, sand, DEFAULT_WHEEL)
    ratios = np.array([b["ratio_median"] for b in res["load_ratio_by_slip"]])
    assert np.all((ratios > 1.09) & (ratios < 1.12))  # Eq. (10) vs Eq. (7): ~+10 %
    # static sinkage above D/6 = r/3 (0.157 m for r = 0.47 m)
    assert res["sinkage_limit_m"] == pytest.approx(2 * 0.47 / 6)
    assert res["max_static_sinkage_m"] == pytest.approx(float(sinkage_eq10(sand, DEFAULT_WHEEL, SAND_LOAD_N)))
    assert res["max_static_sinkage_m"] > res["sinkage_limit_m"]
    assert res["sinkage_ok"] is False and res["consistent"] is False
    assert res["theta1_limit_deg"] == pytest.approx(math.degrees(math.acos(2 / 3)))
    assert any("D/6" in r for r in res["reasons"])
    # balance mode makes the load exact, but the sinkage is still beyond D/6
    bal = wong_forces(sand, DEFAULT_WHEEL, w, s, sinkage="balance")
    res_b = physical_consistency(bal, w, s, sand, DEFAULT_WHEEL)
    assert res_b["load_ok"] is True and res_b["max_load_ratio_dev"] < 1e-9
    assert res_b["sinkage_ok"] is False


def test_plain_wong_on_paper_clay_is_consistent():
    # clay run: 8 kN + 3 kN; Eq. (10) within ~3 % of Eq. (7) and z0 just below D/6
    clay = load_terrain("clay")
    w, s = _sweep(11000.0)
    res = physical_consistency(wong_forces(clay, DEFAULT_WHEEL, w, s), w, s, clay, DEFAULT_WHEEL)
    assert res["consistent"] is True and res["reasons"] == []
    assert res["max_load_ratio_dev"] < 0.05
    assert res["max_sinkage_m"] < res["sinkage_limit_m"]
    json.dumps(res)  # JSON-ready


def test_tolerance_and_limit_are_options_and_bins_need_enough_samples():
    sand = load_terrain("sand")
    w, s = _sweep(SAND_LOAD_N)
    forces = wong_forces(sand, DEFAULT_WHEEL, w, s)
    loose = physical_consistency(forces, w, s, sand, DEFAULT_WHEEL, load_tol=0.15, sinkage_limit_m=0.3)
    assert loose["consistent"] is True
    # a bin with fewer than min_count samples is listed but does not decide
    few = np.flatnonzero(s < 0.3).tolist() + np.flatnonzero(s == 0.9)[:3].tolist()
    f = get_model("lyasko").predict(sand, DEFAULT_WHEEL, w[few], s[few], TAB3_SAND["lyasko"])
    res = physical_consistency(f, w[few], s[few], sand, DEFAULT_WHEEL, load_tol=0.5, sinkage_limit_m=0.45)
    last = res["load_ratio_by_slip"][-1]
    assert last["count"] == 3 and last["used"] is False and last["ratio_median"] > 2
    assert res["load_ok"] is True and res["max_load_ratio_dev"] < 0.5
    res3 = physical_consistency(f, w[few], s[few], sand, DEFAULT_WHEEL, load_tol=0.5, sinkage_limit_m=0.45,
                                min_count=3)
    assert res3["load_ok"] is False and res3["max_load_ratio_dev"] > 1.0


def test_measured_load_noise_does_not_decide():
    # bin medians: a few wild load samples in a bin do not flag a consistent model
    clay = load_terrain("clay")
    w, s = _sweep(11000.0)
    forces = wong_forces(clay, DEFAULT_WHEEL, w, s)
    noisy = w.copy()
    noisy[::10] *= 0.5  # 10 % of the samples read half the load
    assert physical_consistency(forces, noisy, s, clay, DEFAULT_WHEEL)["load_ok"] is True


def test_bad_input():
    clay = load_terrain("clay")
    f = wong_forces(clay, DEFAULT_WHEEL, [8000.0, 9000.0], [0.2, 0.5])
    with pytest.raises(ValueError, match="does not match"):
        physical_consistency(f, [8000.0, 9000.0, 1.0], [0.2, 0.5, 0.6], clay, DEFAULT_WHEEL)
    with pytest.raises(ValueError, match=r"load_n\[1\] = -9.0: measured vertical load must be > 0"):
        physical_consistency(f, [8000.0, -9.0], [0.2, 0.5], clay, DEFAULT_WHEEL)
    with pytest.raises(ValueError, match="n_bins"):
        physical_consistency(f, [8000.0, 9000.0], [0.2, 0.5], clay, DEFAULT_WHEEL, n_bins=0)
    with pytest.raises(ValueError, match="load_tol"):
        physical_consistency(f, [8000.0, 9000.0], [0.2, 0.5], clay, DEFAULT_WHEEL, load_tol=float("nan"))
    with pytest.raises(ValueError, match="sinkage_limit_m"):
        physical_consistency(f, [8000.0, 9000.0], [0.2, 0.5], clay, DEFAULT_WHEEL, sinkage_limit_m=-1.0)
    with pytest.raises(ValueError, match="no sample"):
        physical_consistency(f, [np.nan, np.nan], [0.2, 0.5], clay, Wheel(0.47, 0.32))
    res = physical_consistency(f, [8000.0, np.nan], [0.2, 0.5], clay, DEFAULT_WHEEL)
    assert res["n_ignored"] == 1 and res["n_samples"] == 1
