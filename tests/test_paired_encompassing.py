"""Step 2's paired out-of-sample test (``_encompassing``): a hypothesis' held-out gain over Wong's,
fold by fold, regressed on how much the two models' held-out predictions differ in each fold.

Cells are simulated as a forecast-encompassing regression ``y - a = lambda (b - a) + e`` (a: Wong's
held-out prediction, b: the hypothesis', e: unit noise), which is what the test assumes; the fold
gains and prediction differences are then formed exactly as ``_paired`` forms them."""

import numpy as np
from scipy import stats

from wheelsoil.model.diagnosis import _encompassing
from wheelsoil.model.structure import ALPHA


def _folds(rng, delta_by_fold, lam, cells=12):
    """Fold gains d (G,) and squared prediction differences w (G,) in noise variances for folds whose
    prediction differences are ``delta_by_fold`` (G,) (cell differences spread about it)."""
    d, w = [], []
    for dg in delta_by_fold:
        delta = dg * (1.0 + 0.3 * rng.standard_normal(cells))
        resid_a = lam * delta + rng.standard_normal(cells)  # y - a
        resid_b = resid_a - delta  # y - b
        d.append(np.sum(resid_a**2 - resid_b**2))
        w.append(np.sum(delta**2))
    return np.array(d), np.array(w)


def test_a_gain_confined_to_the_folds_where_the_models_differ_is_found():
    """A drift from mid-run: the hypothesis is right (lambda = 1) and differs from Wong only in the last
    3 of 8 folds.  The paired t-test over the fold gains, diluted by the 5 folds where both predict
    alike, misses the level; the weighted regression finds it."""
    rng = np.random.default_rng(3)
    delta = np.array([0.0, 0.0, 0.0, 0.05, 0.1, 1.2, 1.5, 1.8])
    d, w = _folds(rng, delta, lam=1.0)
    beta, p_more, p_less = _encompassing(d, w)
    p_t = stats.ttest_1samp(d, 0.0, alternative="greater").pvalue
    assert p_t > ALPHA
    assert p_more < ALPHA and p_less > 0.5
    assert 0.5 < beta < 1.5


def test_a_hypothesis_that_fits_noise_loses():
    """Wong is right (lambda = 0): the hypothesis' held-out predictions only add their own error, and
    beta is near -1 with the improvement p-value near 1."""
    rng = np.random.default_rng(4)
    d, w = _folds(rng, np.full(10, 0.8), lam=0.0)
    beta, p_more, p_less = _encompassing(d, w)
    assert beta < -0.5 and p_more > 0.9 and p_less < ALPHA


def test_the_level_holds_at_the_null_boundary():
    """lambda = 1/2 (both models equally far from the data on average: no improvement to find),
    folds of very uneven prediction differences: the test rejects at about its level."""
    rng = np.random.default_rng(5)
    hits = 0
    reps = 4000
    for _ in range(reps):
        delta = rng.uniform(0.0, 2.0, 8) ** 3
        d, w = _folds(rng, delta, lam=0.5)
        hits += _encompassing(d, w)[1] < ALPHA
    assert hits / reps < 2 * ALPHA


def test_too_few_folds_where_the_models_differ_give_no_test():
    beta, p_more, p_less = _encompassing(np.array([0.0, 0.0, 3.0, 4.0]), np.array([0.0, 0.0, 3.0, 4.0]))
    assert np.isnan(p_more) and np.isnan(p_less)
