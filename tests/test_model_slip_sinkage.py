"""Slip-sinkage models (paper Eqs. 11-13) and their common interface."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wheelsoil.model import DEFAULT_WHEEL, MODELS, Param, SinkageModel, get_model, load_terrain, wong_forces
from wheelsoil.model.wong import sinkage_eq10

CLAY = load_terrain("clay")
W = np.array([8000.0, 11000.0, 11000.0, 13000.0])
S = np.array([0.0, 0.2, 0.5, 0.9])


def test_registry_and_parameters():
    assert list(MODELS) == ["wong", "vasilev", "lyasko", "ding", "ding_stress"]
    assert get_model("wong").params == ()
    assert [p.name for p in get_model("lyasko").params] == ["m1", "m2"]
    assert [p.name for p in get_model("vasilev").params] == ["H"]
    assert [p.name for p in get_model("ding").params] == [p.name for p in get_model("ding_stress").params] == ["n1"]
    for model in MODELS.values():
        assert isinstance(model, SinkageModel) and model.source
        for p in model.params:
            assert isinstance(p, Param) and p.lower <= p.default <= p.upper and p.unit and p.doc
    assert get_model("lyasko").params[1].upper < 1  # m2 * s < 1 for every s < 1
    with pytest.raises(ValueError, match="unknown model 'reece'.*wong, vasilev, lyasko, ding, ding_stress"):
        get_model("reece")


@pytest.mark.parametrize("name", list(MODELS))
def test_defaults_reduce_to_wong(name):
    a = get_model(name).predict(CLAY, DEFAULT_WHEEL, W, S)
    b = wong_forces(CLAY, DEFAULT_WHEEL, W, S)
    np.testing.assert_allclose(a.drawbar_pull_n, b.drawbar_pull_n, rtol=1e-13)
    np.testing.assert_allclose(a.sinkage_m, b.sinkage_m, rtol=1e-13)


def test_vasilev_adds_h_times_slip():
    f = get_model("vasilev").predict(CLAY, DEFAULT_WHEEL, W, S, {"H": 0.02})
    np.testing.assert_allclose(f.sinkage_m, sinkage_eq10(CLAY, DEFAULT_WHEEL, W) + 0.02 * S, rtol=1e-13)


def test_lyasko_ratio():
    f = get_model("lyasko").predict(CLAY, DEFAULT_WHEEL, W, S, {"m1": 0.1, "m2": 0.05})
    ratio = (1 + 0.1 * S) / (1 - 0.05 * S)
    np.testing.assert_allclose(f.sinkage_m, ratio * sinkage_eq10(CLAY, DEFAULT_WHEEL, W), rtol=1e-13)


def test_ding_exponent_in_eq2_and_eq10():
    f = get_model("ding").predict(CLAY, DEFAULT_WHEEL, W, S, {"n1": 0.35})
    big_n = CLAY.n + 0.35 * S
    np.testing.assert_allclose(f.sinkage_m, sinkage_eq10(CLAY, DEFAULT_WHEEL, W, big_n), rtol=1e-13)
    # Eq. (2) with N: the same as a terrain whose n is N, sample by sample
    for i in range(len(S)):
        ref = wong_forces(CLAY.replace(n=float(big_n[i])), DEFAULT_WHEEL, W[i : i + 1], S[i : i + 1])
        assert f.drawbar_pull_n[i] == pytest.approx(ref.drawbar_pull_n[0], rel=1e-12)


@pytest.mark.parametrize("sinkage", ["eq10", "balance"])
def test_ding_other_reading_exponent_in_eq2_only(sinkage):
    """Eq. (13)'s other reading: the static sinkage is Wong's (the lab n), the stress takes N."""
    f = get_model("ding_stress").predict(CLAY, DEFAULT_WHEEL, W, S, {"n1": 0.35}, sinkage=sinkage)
    z0 = wong_forces(CLAY, DEFAULT_WHEEL, W, S, sinkage=sinkage).sinkage_m
    np.testing.assert_allclose(f.sinkage_m, z0, rtol=1e-13)
    big_n = CLAY.n + 0.35 * S
    for i in range(len(S)):  # Eq. (2) with N at Wong's sinkage, sample by sample
        ref = wong_forces(CLAY.replace(n=float(big_n[i])), DEFAULT_WHEEL, W[i : i + 1], S[i : i + 1],
                          z_fn=lambda z, s, z0=z0[i]: np.full_like(z, z0))
        assert f.drawbar_pull_n[i] == pytest.approx(ref.drawbar_pull_n[0], rel=1e-12)
        assert f.torque_nm[i] == pytest.approx(ref.torque_nm[0], rel=1e-12)
    # at a sinkage under 1 m a larger N lowers the stress: the model carries less than the load as slip grows
    assert np.all(np.diff(f.load_model_n[1:] / W[1:]) < 0)


@settings(max_examples=30, deadline=None)
@given(
    m1=st.floats(0.0, 1.0),
    m2=st.floats(0.0, 0.3),
    h=st.floats(0.0, 0.05),
    s=st.floats(0.01, 0.95),
)
def test_slip_sinkage_increases_sinkage_and_torque(m1, m2, h, s):
    base = wong_forces(CLAY, DEFAULT_WHEEL, [8000.0], [s])
    for name, params in (("lyasko", {"m1": m1, "m2": m2}), ("vasilev", {"H": h})):
        f = get_model(name).predict(CLAY, DEFAULT_WHEEL, [8000.0], [s], params)
        assert f.sinkage_m[0] >= base.sinkage_m[0]
        assert f.torque_nm[0] >= base.torque_nm[0] * (1 - 1e-12)


def test_balance_mode_applies_transform_to_balanced_z0():
    wong = get_model("wong").predict(CLAY, DEFAULT_WHEEL, W, S, sinkage="balance")
    np.testing.assert_allclose(wong.load_model_n, W, rtol=1e-9)
    f = get_model("vasilev").predict(CLAY, DEFAULT_WHEEL, W, S, {"H": 0.02}, sinkage="balance")
    np.testing.assert_allclose(f.sinkage_m, wong.sinkage_m + 0.02 * S, rtol=1e-12)
    ding = get_model("ding").predict(CLAY, DEFAULT_WHEEL, W, S, {"n1": 0.35}, sinkage="balance")
    np.testing.assert_allclose(ding.load_model_n, W, rtol=1e-9)  # Ding changes the balance itself


def test_lyasko_m2_s_at_least_one_names_sample():
    with pytest.raises(ValueError, match=r"slip\[2\] = 0.8: Lyasko m2\*s must be < 1 \(m2 = 1.25\)"):
        get_model("lyasko").predict(CLAY, DEFAULT_WHEEL, [1e4] * 3, [0.1, 0.2, 0.8], {"m1": 0.1, "m2": 1.25})


def test_sinkage_beyond_radius_from_h_names_sample():
    with pytest.raises(ValueError, match=r"sinkage_m\[1\] = .*< wheel radius"):
        get_model("vasilev").predict(CLAY, DEFAULT_WHEEL, [1e4, 1e4], [0.1, 0.9], {"H": 0.5})


def test_ding_exponent_out_of_range():
    with pytest.raises(ValueError, match=r"sinkage_exponent\[1\] = .*\(0, 3\)"):
        get_model("ding").predict(CLAY, DEFAULT_WHEEL, [1e4, 1e4], [0.0, 0.9], {"n1": 3.0})


def test_bad_parameters():
    with pytest.raises(ValueError, match="no parameter 'm3' .*m1, m2"):
        get_model("lyasko").predict(CLAY, DEFAULT_WHEEL, [1e4], [0.1], {"m3": 1.0})
    with pytest.raises(ValueError, match="parameter H must be finite"):
        get_model("vasilev").predict(CLAY, DEFAULT_WHEEL, [1e4], [0.1], {"H": float("nan")})
    with pytest.raises(ValueError, match="no parameter 'H' .*none"):
        get_model("wong").predict(CLAY, DEFAULT_WHEEL, [1e4], [0.1], {"H": 0.1})


def test_a_new_model_is_one_small_class():
    class Quadratic(SinkageModel):
        name = "quadratic"
        params = (Param("a", 0.0, 0.0, 1.0, "m", "z = z0 + a s^2"),)

        def sinkage(self, z0, slip, p):
            return z0 + p["a"] * slip**2

    f = Quadratic().predict(CLAY, DEFAULT_WHEEL, W, S, {"a": 0.03})
    np.testing.assert_allclose(f.sinkage_m, sinkage_eq10(CLAY, DEFAULT_WHEEL, W) + 0.03 * S**2, rtol=1e-13)
