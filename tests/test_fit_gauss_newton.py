"""The generic Gauss–Newton / LM solver agrees with scipy and has honest errors."""

import warnings

import numpy as np
import pytest
from scipy.optimize import least_squares

from wheelsoil.model.fit import gauss_newton

T = np.linspace(0.0, 5.0, 120)


def _decay(x):
    return x[0] * np.exp(-x[1] * T) + x[2]


def _data(seed, noise=0.05, truth=(3.0, 0.7, 0.5)):
    rng = np.random.default_rng(seed)
    return _decay(truth) + rng.normal(0.0, noise, T.size)


@pytest.mark.parametrize(
    "bounds",
    [None, ([0.0, 0.0, -5.0], [10.0, 5.0, 5.0]), ([0.0, 0.0, -5.0], [10.0, 5.0, 0.3])],
    ids=["free", "bounded-inactive", "bounded-active"],
)
def test_same_optimum_as_least_squares(bounds):
    y = _data(1)
    fun = lambda x: _decay(x) - y  # noqa: E731
    gn = gauss_newton(fun, [1.0, 1.0, 0.0], bounds=bounds, eps=1e-12)
    ls = least_squares(fun, [1.0, 1.0, 0.0], bounds=bounds or (-np.inf, np.inf),
                       xtol=1e-14, ftol=1e-14, gtol=1e-14)
    assert gn.success, gn.message
    np.testing.assert_allclose(gn.x, ls.x, rtol=1e-6, atol=1e-8)
    assert gn.cost == pytest.approx(ls.cost, rel=1e-9)
    if bounds is not None and bounds[1][2] == 0.3:
        assert gn.at_bound == ("x2",)


def test_rosenbrock_from_the_classic_start():
    fun = lambda x: np.array([10 * (x[1] - x[0] ** 2), 1 - x[0]])  # noqa: E731
    r = gauss_newton(fun, [-1.2, 1.0])
    assert r.success
    np.testing.assert_allclose(r.x, [1.0, 1.0], atol=1e-7)


def test_analytic_jacobian_matches_finite_differences():
    y = _data(2)
    fun = lambda x: _decay(x) - y  # noqa: E731

    def jac(x):
        e = np.exp(-x[1] * T)
        return np.column_stack([e, -x[0] * T * e, np.ones_like(T)])

    a = gauss_newton(fun, [1.0, 1.0, 0.0], jac=jac)
    b = gauss_newton(fun, [1.0, 1.0, 0.0])
    np.testing.assert_allclose(a.x, b.x, rtol=1e-6)
    np.testing.assert_allclose(list(a.stderr.values()), list(b.stderr.values()), rtol=1e-4)


def test_warm_refit_with_the_start_jacobian_and_no_covariance_finds_the_same_optimum():
    """A cross-validation refit: start at a fit on all data, pass that fit's Jacobian rows
    (jac0) and skip the covariance; the optimum is the plain refit's, with fewer calls."""
    y = _data(3)
    full = gauss_newton(lambda x: _decay(x) - y, [1.0, 1.0, 0.0], eps=1e-10)
    keep = np.arange(T.size) % 5 != 0  # one fold out

    def fold(x):
        return (_decay(x) - y)[keep]

    plain = gauss_newton(fold, full.x, eps=1e-10)
    warm = gauss_newton(fold, full.x, eps=1e-10, jac0=full.jac[keep], covariance=False)
    np.testing.assert_allclose(warm.x, plain.x, rtol=1e-7)
    assert warm.nfev < plain.nfev
    assert np.isnan(warm.covariance).all() and np.isnan(warm.jac).all()
    assert np.isfinite(plain.covariance).all()
    with pytest.raises(ValueError, match="jac0 has shape"):
        gauss_newton(fold, full.x, jac0=full.jac)


def test_a_refit_at_the_domain_edge_without_halvings_stays_there_with_fewer_calls():
    """A model undefined beyond x2 = 0.3 (as Wong's beyond sinkage r) whose data want x2 = 0.5: the
    fit stops at the edge; a fold refit from there with ``halvings=0`` (damping raised at once on a
    trial outside the domain) ends where the halving one does, with fewer calls."""
    y = _data(3)

    def model(x, rows=slice(None)):
        r = (_decay(x) - y)[rows]
        return np.full(r.size, np.inf) if x[2] > 0.3 else r

    full = gauss_newton(model, [1.0, 1.0, 0.0])
    assert full.success and 0.29 < full.x[2] <= 0.3
    keep = np.arange(T.size) % 5 != 0
    refits = [gauss_newton(lambda x: model(x, keep), full.x, eps=1e-4, max_iter=4, jac0=full.jac[keep],
                           covariance=False, halvings=h) for h in (5, 0)]
    assert all(np.isfinite(r.cost) for r in refits)
    np.testing.assert_allclose(refits[1].x, refits[0].x, rtol=1e-4, atol=1e-6)
    assert refits[1].cost == pytest.approx(refits[0].cost, rel=1e-6)
    assert refits[1].nfev < refits[0].nfev


def test_recovers_truth_within_two_standard_errors_in_90_percent_of_seeds():
    truth = np.array([3.0, 0.7, 0.5])
    hits, total = 0, 0
    for seed in range(40):
        y = _data(100 + seed, noise=0.1, truth=truth)
        r = gauss_newton(lambda x: _decay(x) - y, [1.0, 1.0, 0.0], names=["a", "k", "c"])
        assert r.success, r.message
        se = np.array([r.stderr[n] for n in ("a", "k", "c")])
        inside = np.abs(r.x - truth) <= 2 * se
        hits += int(inside.sum())
        total += inside.size
    assert hits / total >= 0.90, f"{hits}/{total}"


def test_sigma_weights_and_absolute_sigma():
    rng = np.random.default_rng(3)
    sig = np.where(T < 2.5, 0.01, 1.0)  # precise first half, noisy second half
    y = _decay([3.0, 0.7, 0.5]) + rng.normal(0.0, 1.0, T.size) * sig
    fun = lambda x: _decay(x) - y  # noqa: E731
    w = gauss_newton(fun, [1.0, 1.0, 0.0], sigma=sig, absolute_sigma=True)
    u = gauss_newton(fun, [1.0, 1.0, 0.0])
    # the weighted fit trusts the precise half: far smaller errors than unweighted
    assert w.stderr["x0"] < 0.5 * u.stderr["x0"]
    # with the true sigma, reduced chi-square is near 1
    assert 0.6 < 2 * w.cost / w.dof < 1.5
    np.testing.assert_allclose(w.residuals, fun(w.x))


def test_unidentifiable_direction_is_flagged():
    fun = lambda x: np.array([x[0] + x[1] - 1.0, x[0] + x[1] - 1.2, x[0] + x[1] - 0.8])  # noqa: E731
    r = gauss_newton(fun, [0.2, 0.3])
    assert r.x.sum() == pytest.approx(1.0, abs=1e-8)
    assert np.isnan(r.stderr["x0"]) and np.isnan(r.stderr["x1"])
    assert r.condition_number > 1e8


def test_non_finite_start_reports_failure():
    r = gauss_newton(lambda x: np.array([np.nan, 1.0]), [1.0])
    assert not r.success and r.status == -1 and "not finite" in r.message
    with pytest.raises(ValueError, match="non-finite"):
        gauss_newton(lambda x: x, [np.nan])
    with pytest.raises(ValueError, match="lower bound"):
        gauss_newton(lambda x: x, [1.0], bounds=([2.0], [1.0]))


def test_report_text_names_parameters_and_correlations():
    y = _data(4)
    r = gauss_newton(lambda x: _decay(x) - y, [1.0, 1.0, 0.0], names=["a", "k", "c"])
    text = r.report()
    assert "converged" in text and "k =" in text and "C(k, c)" in text


def test_a_ragged_domain_edge_at_the_bound_gets_a_shorter_difference_step():
    """The data want x2 below its lower bound 0.2, and the model is undefined in a thin band just
    above 0.2 (as Wong's sinkage root fails in patches near the wheel's radius): the forward step
    from the bound lands in the band and the backward one is out of bounds, so a shorter step
    gives the Jacobian column; the fit ends at the bound with finite standard errors, quietly."""
    y = _data(3)
    lo, hi = [0.0, 0.0, 0.2], [10.0, 10.0, 1.0]

    def model(x):
        r = _decay([x[0], x[1], x[2] + 0.3]) - y  # optimum at x2 = -0.3, outside the bounds
        return np.full(r.size, np.inf) if 0.2 + 1e-10 < x[2] < 0.2 + 1e-8 else r

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        fit = gauss_newton(model, [1.0, 1.0, 0.5], bounds=(lo, hi))
    assert fit.x[2] == 0.2 and fit.success, fit.message
    assert np.all(np.isfinite(fit.jac)) and np.all(np.isfinite(list(fit.stderr.values())))


def test_a_jacobian_column_undefined_both_ways_stops_the_fit_and_names_the_parameter():
    """A model defined on the line b = 1 alone: no difference step in b is finite, so the fit stops
    with status -3 naming b, the column zeroed (no information), and no overflow downstream."""
    def model(x):
        return np.array([x[0] - 2.0, x[0] + 1.0, 0.5]) if x[1] == 1.0 else np.full(3, np.nan)

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        fit = gauss_newton(model, [0.0, 1.0], names=["a", "b"])
    assert not fit.success and fit.status == -3 and "not finite in b" in fit.message
    assert np.all(fit.jac[:, 1] == 0.0)
