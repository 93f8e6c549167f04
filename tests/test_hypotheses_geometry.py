"""Wheel-geometry stand-ins (radius, width): a geometry error must not be blamed on the soil."""

import numpy as np

from wheelsoil.model import DEFAULT_WHEEL, Wheel, load_terrain, wong_forces
from wheelsoil.model.hypotheses import HYPOTHESES, Context, lab_prior

SAND = load_terrain("sand")


def test_width_hypothesis_is_wong_with_the_contact_width_b_times_1_plus_beta():
    ctx = Context(SAND, DEFAULT_WHEEL, "eq10", lab_prior(SAND, DEFAULT_WHEEL))
    w = np.full(4, 12000.0)
    s = np.linspace(0.2, 0.8, 4)
    f = HYPOTHESES["width"].predict(ctx, w, s, None, {"beta": -0.2})
    ref = wong_forces(SAND, Wheel(DEFAULT_WHEEL.radius, 0.8 * DEFAULT_WHEEL.width), w, s)
    np.testing.assert_allclose(f.drawbar_pull_n, ref.drawbar_pull_n, rtol=1e-9)
    np.testing.assert_allclose(f.torque_nm, ref.torque_nm, rtol=1e-9)
    base = wong_forces(SAND, DEFAULT_WHEEL, w, s)
    assert np.all(np.abs(f.torque_nm - base.torque_nm) > 1.0)  # the width matters


def test_width_is_not_tried_when_the_terrain_is_fitted_everywhere():
    ctx = Context(SAND, DEFAULT_WHEEL, "eq10", lab_prior(SAND, DEFAULT_WHEEL), fit_terrain=True)
    assert HYPOTHESES["width"].available(ctx, True)


def test_a_contact_width_error_is_not_named_a_terrain_mismatch():
    """Data from a wheel whose contact width is 0.8 b, fitted with b: the terrain re-fit can mimic
    it (b k_eq and b c), the width stand-in explains it with one parameter: not terrain_mismatch."""
    from wheelsoil.model.diagnosis import diagnose
    from wheelsoil.model.fit import synthetic_data

    true_wheel = Wheel(DEFAULT_WHEEL.radius, 0.8 * DEFAULT_WHEEL.width)
    df = synthetic_data(SAND, true_wheel, "wong", {}, kind="table", n_rows=60, load_n=13000.0,
                        noise_dp_n=20.0, noise_t_nm=10.0, seed=3)
    d = diagnose(df, SAND, DEFAULT_WHEEL, models=["terrain", "width", "radius"])
    assert d.effect != "terrain_mismatch"
    assert d.effect != "none"  # a 20 % width error is far above this noise
    assert d.probabilities["width"] > d.probabilities["terrain"]
