"""The evidence's log-determinant and the covariance on parameters of very different scale.

In SI units a terrain fit's information matrix spans ten orders of magnitude (c in Pa next to
phi in rad); its eigen-decomposition or a relative pseudo-inverse cut-off then loses the weakly
determined directions, which gave a cohesion standard error of 3e-7 Pa and an Occam factor 7.5
nats too large for the terrain re-fit.  Both are computed on the equilibrated matrix now."""

import numpy as np

from wheelsoil.model.crossval import inv_psd, _logdet_psd


#: The terrain re-fit's posterior information (data with the design effect, plus the lab prior) on
#: seed 1398 of the diagnosis benchmark: k_eq and K on the log scale, n, c [Pa], phi [rad].
A_TERRAIN = np.array([
    [1.3719710382559504e+04, -3.0098744938392007e+04, 5.3507070095403175e-01, 4.7540257849283960e+04,
     -7.9405743212458231e+02],
    [-3.0098744938392007e+04, 7.7516114292356520e+04, 1.1918645188810326e+00, 9.5207004690009606e+04,
     -3.9719204977091449e+03],
    [5.3507070095403175e-01, 1.1918645188810326e+00, 5.1753608465191208e-04, 4.3697325112184068e+01,
     -1.2002435605403314e+00],
    [4.7540257849283960e+04, 9.5207004690009606e+04, 4.3697325112184068e+01, 3.6921814463202748e+06,
     -1.0164289266512949e+05],
    [-7.9405743212458231e+02, -3.9719204977091449e+03, -1.2002435605403314e+00, -1.0164289266512949e+05,
     3.2299161812686707e+03]])


def _terrain_like_information():
    """``(B, d, A)``: A = D B D with D = diag(d) its square-root diagonal and B its correlation
    form (well conditioned: the exact answers come from B)."""
    d = np.sqrt(np.diag(A_TERRAIN))
    B = A_TERRAIN / np.outer(d, d)
    assert np.linalg.eigvalsh(B).min() > 1e-5
    return B, d, A_TERRAIN


def test_logdet_is_exact_on_badly_scaled_information():
    B, d, A = _terrain_like_information()
    exact = np.linalg.slogdet(B)[1] + 2 * np.sum(np.log(d))
    assert abs(_logdet_psd(A) - exact) < 1e-6


def test_covariance_keeps_the_weakly_determined_direction():
    B, d, A = _terrain_like_information()
    se = np.sqrt(np.diag(inv_psd(A)))
    exact = np.sqrt(np.diag(np.linalg.inv(B))) / d
    np.testing.assert_allclose(se, exact, rtol=1e-6)


def test_null_directions_are_left_out_not_inflated():
    """A parameter the data do not touch (zero row and column) has no information: the
    pseudo-determinant is that of the rest, and its variance is zero (pinv), not infinite."""
    B, d, A = _terrain_like_information()
    Z = np.zeros((6, 6))
    Z[:5, :5] = A
    assert abs(_logdet_psd(Z) - _logdet_psd(A)) < 1e-9
    assert inv_psd(Z)[5, 5] == 0.0


def test_cells_are_predicted_as_the_mean_over_their_slips_not_at_the_mean_slip():
    """A cell's measured mean is the forces averaged over its samples' slips; Wong's Dp is concave
    in slip, so the model at the mean slip errs by f'' Var(s) / 2 (Jensen).  On noise-free data of
    the model itself, ``cell_forces`` (two points mean -+ sd) must come far closer to the cell means
    than the model at the mean slip does."""
    from wheelsoil.model import DEFAULT_WHEEL, load_terrain
    from wheelsoil.model.crossval import cell_forces
    from wheelsoil.model.data import make_cells, prepare_data, synthetic_data
    from wheelsoil.model.hypotheses import HYPOTHESES, Context

    sand = load_terrain("sand")
    df = synthetic_data(sand, DEFAULT_WHEEL, kind="timeseries", duration_s=60.0, noise_dp_n=1e-9, noise_t_nm=1e-9)
    cells = make_cells(prepare_data(df))
    assert cells.slip_sd is not None and np.median(cells.slip_sd) > 0.005  # cells span a slip bin
    ctx = Context(sand, DEFAULT_WHEEL)
    wong = HYPOTHESES["wong"]
    y = cells.channels["drawbar_pull_n"]
    at_mean = wong.predict(ctx, cells.load_n, cells.slip, cells.x, {}).drawbar_pull_n
    averaged = cell_forces(wong, ctx, cells, {}).drawbar_pull_n
    err_at_mean = np.sqrt(np.mean((y - at_mean) ** 2))
    err_averaged = np.sqrt(np.mean((y - averaged) ** 2))
    assert err_at_mean > 0.2  # N: the Jensen error is there to be removed
    assert err_averaged < 0.3 * err_at_mean
    # a table row is one test point: evaluated at its slip
    table = make_cells(prepare_data(synthetic_data(sand, DEFAULT_WHEEL, kind="table", n_rows=30)))
    assert table.slip_sd is None
    np.testing.assert_array_equal(cell_forces(wong, ctx, table, {}).drawbar_pull_n,
                                  wong.predict(ctx, table.load_n, table.slip, table.x, {}).drawbar_pull_n)


def test_a_fit_and_its_fold_refits_model_the_cells_slip_spread():
    """The fit holds the slip-spread terms of its first optimum fixed and steps once; its cell
    predictions must still equal the two-point cell means at its parameters (to a small fraction
    of the noise), and a fold's held-out prediction must include the spread term."""
    from wheelsoil.model import DEFAULT_WHEEL, load_terrain
    from wheelsoil.model.crossval import cross_validate, fit_hypothesis, predict_cells
    from wheelsoil.model.data import make_cells, prepare_data, synthetic_data
    from wheelsoil.model.hypotheses import HYPOTHESES, Context, lab_prior

    clay = load_terrain("clay")
    truth = clay.replace(phi=clay.phi + 0.05)
    df = synthetic_data(clay, DEFAULT_WHEEL, kind="timeseries", duration_s=60.0, noise_dp_n=20.0, noise_t_nm=10.0,
                        terrain_truth=truth, load_n=13000.0, seed=3)
    cells = make_cells(prepare_data(df))
    ctx = Context(clay, DEFAULT_WHEEL, prior=lab_prior(clay, DEFAULT_WHEEL))
    fit = fit_hypothesis(HYPOTHESES["terrain_phi"], ctx, cells)
    assert fit.success and fit.spread is not None
    exact = predict_cells(fit, ctx, cells)
    for c in ("drawbar_pull_n", "torque_nm"):
        gap = np.abs(fit.cell_pred[c] - getattr(exact, c)) / cells.sigma[c]
        assert np.max(gap) < 0.05, (c, np.max(gap))
        assert np.max(np.abs(fit.spread[c])) > 0.0
    cross_validate(fit, ctx, cells)
    held = fit.cv["held_cells"]["drawbar_pull_n"]
    assert np.all(np.isfinite(held))
    # one cycle moves phi little: where the spread term is largest, the held-out prediction stays
    # far closer to the full fit's (spread included) than the spread term itself
    i = int(np.argmax(np.abs(fit.spread["drawbar_pull_n"])))
    assert abs(held[i] - fit.cell_pred["drawbar_pull_n"][i]) < 0.5 * abs(fit.spread["drawbar_pull_n"][i])


def test_a_fit_stopped_short_of_its_optimum_is_refitted_from_a_model_that_contains_it():
    """A terrain re-fit that stopped where its objective is higher than at the values of a fitted
    hypothesis containing it (Vasil'ev + terrain, whose H is null on these data) is refitted from
    those values and replaced, with a note; between fits at their optima nothing moves."""
    from wheelsoil.model import DEFAULT_WHEEL, load_terrain
    from wheelsoil.model.crossval import FIT_MAX_ITER, cross_validate, fit_hypothesis, meaningful
    from wheelsoil.model.data import prepare_data, synthetic_data
    from wheelsoil.model.diagnosis import _escape_local_optima
    from wheelsoil.model.hypotheses import HYPOTHESES, Context, lab_prior

    clay = load_terrain("clay")
    truth = clay.replace(phi=clay.phi + 0.05, n=clay.n + 0.05)
    df = synthetic_data(clay, DEFAULT_WHEEL, kind="timeseries", duration_s=60.0, noise_dp_n=20.0, noise_t_nm=10.0,
                        terrain_truth=truth, load_n=13000.0, seed=3)
    data = prepare_data(df)
    ctx = Context(clay, DEFAULT_WHEEL, prior=lab_prior(clay, DEFAULT_WHEEL))
    fit = lambda name, **kw: cross_validate(fit_hypothesis(HYPOTHESES[name], ctx, data.cells, **kw), ctx, data.cells)
    stuck = fit("terrain", max_iter=1)
    fits = {"terrain": stuck, "vasilev+terrain": fit("vasilev+terrain")}
    _escape_local_optima(fits, "vasilev+terrain", ctx, data, FIT_MAX_ITER)
    new = fits["terrain"]
    assert new is not stuck and new.cv is not None
    assert (stuck.chi2_data + stuck.chi2_prior) - (new.chi2_data + new.chi2_prior) > meaningful(stuck)
    assert any("local optimum" in n for n in new.notes)
    settled = dict(fits)
    _escape_local_optima(settled, "vasilev+terrain", ctx, data, FIT_MAX_ITER)
    assert all(settled[k] is fits[k] for k in fits)
