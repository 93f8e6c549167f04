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
