"""Generic bounded Gauss–Newton / Levenberg–Marquardt solver and its result.

:func:`gauss_newton` is a bounded nonlinear least-squares solver (paper §1.2:
``Theta_{k+1} = Theta_k + (J^T J)^-1 J^T r`` until the relative step is below
``eps``) with Levenberg–Marquardt damping (Marquardt's ``diag(J^T J)``
scaling) and bound handling by projection with an active set, so that it
converges from the parameters' defaults.  It returns a :class:`FitResult`
with the parameters, standard errors, covariance and correlation (as
``lmfit`` reports them) and the residuals.  Nothing here knows about wheels.

Sources: Levenberg (1944), Marquardt (1963) for the damping; Nocedal & Wright,
*Numerical Optimization* (2006) §10.3 for the Gauss–Newton step and the
covariance ``s^2 (J^T J)^-1`` of the estimate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

__all__ = ["FitResult", "gauss_newton", "covariance_from_jacobian"]

_EPS_MACH = np.finfo(float).eps


# --------------------------------------------------------------------------------------
# Generic Gauss–Newton / Levenberg–Marquardt
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FitResult:
    """Result of :func:`gauss_newton` (like ``scipy.optimize.least_squares``'s
    ``OptimizeResult`` plus ``lmfit``'s uncertainty report).

    Attributes
    ----------
    x : (p,) parameter vector at the optimum.
    names : parameter names, length p.
    params, stderr : dicts name -> value / standard error (``nan`` if not
        identifiable, i.e. the Jacobian is rank-deficient in that direction).
    covariance : (p, p) covariance of the estimate; ``s^2 (J^T J)^-1`` with
        ``s^2 = 2 cost / dof`` (reduced chi-square) unless ``absolute_sigma``.
    correlation : (p, p) correlation matrix from the covariance.
    residuals : (m,) unweighted residuals ``fun(x)`` at the optimum.
    weighted_residuals : (m,) residuals divided by ``sigma`` (= residuals if None).
    jac : (m, p) Jacobian of the weighted residuals at the optimum.
    cost : ``0.5 * sum(weighted_residuals**2)``.
    iterations, nfev : Gauss–Newton iterations and function evaluations.
    success, status, message : convergence flag, code and text.  Status:
        1 relative step < eps, 2 relative cost change < ftol, 3 gradient zero,
        0 max_iter reached, -1 non-finite residuals, -2 damping exhausted,
        -3 a Jacobian column not finite (its entries are returned as 0).
    n_obs, dof : number of residuals and ``n_obs - p``.
    condition_number : of the scaled Jacobian (large -> poorly identified).
    at_bound : names of parameters that ended on a bound.
    """

    x: np.ndarray
    names: tuple[str, ...]
    params: dict
    stderr: dict
    covariance: np.ndarray
    correlation: np.ndarray
    residuals: np.ndarray
    weighted_residuals: np.ndarray
    jac: np.ndarray
    cost: float
    iterations: int
    nfev: int
    success: bool
    status: int
    message: str
    n_obs: int
    dof: int
    condition_number: float
    at_bound: tuple[str, ...] = ()

    def report(self) -> str:
        """Plain-text report: status, fit statistics, values ± stderr (and the
        relative error), and the correlations above 0.5 (like ``lmfit``)."""
        lines = [
            f"[[Fit]] {'converged' if self.success else 'NOT converged'}: {self.message}",
            f"    iterations = {self.iterations}, evaluations = {self.nfev}",
            f"    data points = {self.n_obs}, variables = {len(self.x)}, dof = {self.dof}",
            f"    chi-square = {2 * self.cost:.6g}, reduced chi-square = "
            f"{(2 * self.cost / self.dof) if self.dof > 0 else float('nan'):.6g}",
            f"    condition number = {self.condition_number:.3g}",
            "[[Variables]]",
        ]
        for name in self.names:
            v, e = self.params[name], self.stderr[name]
            rel = abs(e / v) * 100 if (np.isfinite(e) and v != 0) else float("nan")
            bound = "  (at bound)" if name in self.at_bound else ""
            lines.append(f"    {name:>10s} = {v:.6g} +/- {e:.3g} ({rel:.1f}%){bound}")
        pairs = []
        for i in range(len(self.names)):
            for j in range(i + 1, len(self.names)):
                c = self.correlation[i, j]
                if np.isfinite(c) and abs(c) > 0.5:
                    pairs.append((abs(c), f"    C({self.names[i]}, {self.names[j]}) = {c:+.4f}"))
        if pairs:
            lines.append("[[Correlations]] (|C| > 0.5)")
            lines.extend(p[1] for p in sorted(pairs, reverse=True))
        return "\n".join(lines)


def _fd_jacobian(fun_w, x, r0, lo, hi, d):
    """Forward-difference Jacobian (m, p) of ``fun_w`` at ``x``; the step is
    ``sqrt(eps_mach) * max(|x_i|, d_i)``, taken backwards next to an upper bound
    or where the forward point is outside the model's domain, and shortened (up to
    three times, by 16 each) where both points are (a model whose domain edge is
    ragged at this scale, e.g. a sinkage root that fails near the wheel's radius).
    A column still not finite stays so (the caller stops: :func:`gauss_newton`)."""
    p = len(x)
    J = np.empty((len(r0), p))
    for i in range(p):
        h = math.sqrt(_EPS_MACH) * max(abs(x[i]), d[i])
        if x[i] + h > hi[i]:
            h = -h
        for _ in range(4):  # outside the model's domain both ways at this step: a shorter one
            col = _fd_column(fun_w, x, r0, i, h)
            if not np.isfinite(col).all() and lo[i] <= x[i] - h <= hi[i]:  # step back
                col = _fd_column(fun_w, x, r0, i, -h)
            if np.isfinite(col).all():
                break
            h /= 16.0
        J[:, i] = col
    return J


def _not_finite(J, names) -> str:
    """Status -3's message naming the parameters whose Jacobian column (of ``J`` (m, p)) is not
    finite, or "" when every column is."""
    bad = [names[i] for i in np.flatnonzero(~np.isfinite(J).all(axis=0))]
    return ("the Jacobian is not finite in " + ", ".join(bad) + ": the model is undefined on both sides of the "
            "point reached") if bad else ""


def _fd_column(fun_w, x, r0, i, h):
    """One forward-difference column: ``(fun_w(x + h e_i) - r0) / h``."""
    xh = x.copy()
    xh[i] += h
    return (fun_w(xh) - r0) / h


def gauss_newton(
    fun: Callable[[np.ndarray], np.ndarray],
    x0: Sequence[float],
    *,
    bounds: tuple[Sequence[float], Sequence[float]] | None = None,
    jac: Callable[[np.ndarray], np.ndarray] | None = None,
    x_scale: Sequence[float] | None = None,
    eps: float = 1e-8,
    max_iter: int = 100,
    sigma: float | np.ndarray | None = None,
    names: Sequence[str] | None = None,
    absolute_sigma: bool = False,
    ftol: float = 1e-12,
    jac0: np.ndarray | None = None,
    covariance: bool = True,
    halvings: int = 5,
) -> FitResult:
    """Bounded Gauss–Newton with Levenberg–Marquardt damping.

    Minimises ``0.5 * sum((fun(x) / sigma)**2)``.  Each iteration solves
    ``(J^T J + lam diag(J^T J)) dx = -J^T r`` in the scaled variables
    ``u = x / x_scale`` (``lam -> 0`` is the paper's Gauss–Newton step, §1.2),
    projects ``x + dx`` onto the bounds, and freezes parameters that sit on a
    bound with the gradient pointing outwards (active set).  A trial where
    ``fun`` is not finite (outside the model's domain) is halved, up to
    ``halvings`` times; a step still outside it counts as rejected.  A step
    that does not lower the cost is rejected and ``lam`` raised tenfold; an
    accepted one lowers it tenfold.  Stops when the relative step ``|du| < eps (|u| + eps)``, or the
    relative cost change is below ``ftol``, or after ``max_iter`` iterations.

    Parameters
    ----------
    fun : callable ``x (p,) -> r (m,)``, residuals (model - data, any sign convention).
    x0 : (p,) start, clipped into the bounds.
    bounds : ``(lower (p,), upper (p,))``, ``±inf`` for none.
    jac : callable ``x -> (m, p)`` Jacobian of ``fun`` (unweighted); forward
        differences when None.
    x_scale : (p,) typical magnitudes; default ``|x0|`` or, where that is 0, a
        tenth of the bound range (else 1).
    eps : relative step tolerance.
    max_iter : iteration limit.
    sigma : scalar or (m,) standard deviations of the residuals (weights 1/sigma).
    names : parameter names (default ``x0, x1, ...``).
    absolute_sigma : if True the covariance is ``(J^T J)^-1`` (sigma taken as the
        true noise); otherwise it is scaled by the reduced chi-square.
    ftol : relative cost-change tolerance.
    jac0 : (m, p) Jacobian of the weighted residuals ``fun(x) / sigma`` at ``x0``
        when the caller already has it (a warm start from a fit on a superset
        of the residuals: its rows); saves the first Jacobian evaluation
        (p calls of ``fun`` with forward differences).
    covariance : False when only the optimum is wanted (a cross-validation
        refit): the Jacobian is not evaluated at the last point, and ``jac``,
        ``covariance``, ``stderr``, ``correlation`` and ``condition_number``
        are NaN.
    halvings : how often a trial outside the model's domain is halved along its
        direction before it counts as rejected (``lam`` raised tenfold, which
        shortens the step and turns it toward the gradient, as a trust region
        shrinks on a non-finite residual in ``scipy.optimize.least_squares``).
        Halving finds the way along a domain edge when the start is far from
        the optimum; 0 when the start is at an optimum already (a fold refit).

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Shapes disagree (``jac0`` included), ``x0`` is not finite, ``lower > upper``,
        or ``sigma`` is not positive.
    """
    x0 = np.atleast_1d(np.asarray(x0, dtype=float)).copy()
    p = x0.size
    if not np.all(np.isfinite(x0)):
        raise ValueError(f"gauss_newton: start x0 has non-finite values: {x0}")
    names = tuple(names) if names is not None else tuple(f"x{i}" for i in range(p))
    if len(names) != p:
        raise ValueError(f"gauss_newton: {len(names)} names for {p} parameters")
    if bounds is None:
        lo, hi = np.full(p, -np.inf), np.full(p, np.inf)
    else:
        lo = np.broadcast_to(np.asarray(bounds[0], dtype=float), (p,)).copy()
        hi = np.broadcast_to(np.asarray(bounds[1], dtype=float), (p,)).copy()
    if np.any(lo > hi):
        raise ValueError(f"gauss_newton: lower bound above upper bound: {lo} > {hi}")
    if x_scale is None:
        rng = np.where(np.isfinite(hi - lo), (hi - lo) / 10.0, 1.0)
        d = np.where(np.abs(x0) > 0, np.abs(x0), rng)
    else:
        d = np.broadcast_to(np.asarray(x_scale, dtype=float), (p,)).copy()
    d = np.where(np.isfinite(d) & (d > 0), d, 1.0)
    if sigma is not None:
        sig = np.asarray(sigma, dtype=float)
        if np.any(~np.isfinite(sig)) or np.any(sig <= 0):
            raise ValueError("gauss_newton: sigma must be finite and > 0")
    else:
        sig = 1.0

    nfev = 0

    def fun_w(x):
        nonlocal nfev
        nfev += 1
        return np.asarray(fun(x), dtype=float).ravel() / sig

    def jac_w(x, r):
        if jac is None:
            return _fd_jacobian(fun_w, x, r, lo, hi, d)
        J = np.asarray(jac(x), dtype=float)
        return J / (sig[:, None] if np.ndim(sig) else sig)

    x = np.clip(x0, lo, hi)
    r = fun_w(x)
    m = r.size
    if p > 0 and m < 1:
        raise ValueError("gauss_newton: fun returned no residuals")
    status, message = 0, "maximum number of iterations reached"
    it = 0
    J = np.zeros((m, p))
    if not np.all(np.isfinite(r)):
        status, message = -1, "residuals are not finite at the start point"
    elif p == 0:
        status, message = 1, "no free parameters"
    else:
        cost = 0.5 * float(r @ r)
        lam = 1e-3
        if jac0 is not None and np.array_equal(x, x0):
            J = np.asarray(jac0, dtype=float)
            if J.shape != (m, p):
                raise ValueError(f"gauss_newton: jac0 has shape {J.shape}, expected {(m, p)}")
        else:
            J = jac_w(x, r)
        for it in range(1, max_iter + 1):
            if bad := _not_finite(J, names):
                status, message = -3, bad
                break
            Js = J * d
            g = Js.T @ r
            at_lo = (x <= lo) & (g > 0)
            at_hi = (x >= hi) & (g < 0)
            free = ~(at_lo | at_hi)
            if not free.any():
                status, message = 3, "all parameters held at bounds by the gradient"
                break
            A = Js[:, free].T @ Js[:, free]
            gf = g[free]
            if np.max(np.abs(gf)) <= 1e-15 * max(1.0, 2 * cost):
                status, message = 3, "gradient is zero"
                break
            diagA = np.maximum(np.diag(A), 1e-12 * max(1.0, np.max(np.diag(A))))
            accepted = False
            while lam <= 1e12:
                try:
                    du_f = -np.linalg.solve(A + lam * np.diag(diagA), gf)
                except np.linalg.LinAlgError:
                    lam *= 10
                    continue
                du = np.zeros(p)
                du[free] = du_f
                for _ in range(halvings + 1):  # infeasible trial (model undefined there): halve the step
                    x_new = np.clip(x + d * du, lo, hi)
                    r_new = fun_w(x_new)
                    if np.isfinite(r_new).all():
                        break
                    du *= 0.5
                cost_new = 0.5 * float(r_new @ r_new) if np.isfinite(r_new).all() else np.inf
                if cost_new <= cost:
                    accepted = True
                    break
                lam *= 10
            if not accepted:
                status, message = -2, "no step lowers the cost (damping exhausted)"
                # a stationary point that cannot be improved: converged in practice
                if np.max(np.abs(gf)) <= 1e-6 * max(1.0, 2 * cost) ** 0.5 * max(1.0, np.sqrt(np.max(diagA))):
                    status, message = 3, "no descent step left (stationary point)"
                break
            step_u = (x_new - x) / d
            dcost = cost - cost_new
            x, r, cost = x_new, r_new, cost_new
            lam = max(lam / 10.0, 1e-15)
            if np.linalg.norm(step_u) <= eps * (np.linalg.norm(x / d) + eps):
                status, message = 1, f"relative step below eps={eps:g}"
            elif dcost <= ftol * max(cost, 1e-300):
                status, message = 2, f"relative cost change below ftol={ftol:g}"
            if covariance or (status == 0 and it < max_iter):
                J = jac_w(x, r)  # at the new point: the next step's, or the covariance's
            if status:
                break
    if p and status >= 0 and (bad := _not_finite(J, names)):  # the optimum's own Jacobian (for the covariance)
        status, message = -3, bad
    J = np.nan_to_num(J, nan=0.0, posinf=0.0, neginf=0.0)  # a column not finite carries no information
    cost = 0.5 * float(r @ r) if np.all(np.isfinite(r)) else float("nan")
    dof = m - p
    if covariance:
        cov, cond = _covariance(J, d, cost, dof, absolute_sigma)
    else:  # J may be from an earlier point: none of it is returned
        J, cov, cond = np.full((m, p), np.nan), np.full((p, p), np.nan), float("nan")
    se = np.sqrt(np.clip(np.diag(cov), 0, None)) if p else np.zeros(0)
    se = np.where(np.isfinite(np.diag(cov)), se, np.nan) if p else se
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se) if p else np.zeros((0, 0))
    raw = r * sig
    at_bound = tuple(n for n, xi, a, b in zip(names, x, lo, hi) if xi <= a or xi >= b)
    return FitResult(
        x=x.copy(),
        names=names,
        params={n: float(v) for n, v in zip(names, x)},
        stderr={n: float(v) for n, v in zip(names, se)},
        covariance=cov,
        correlation=corr,
        residuals=raw,
        weighted_residuals=r,
        jac=J,
        cost=cost,
        iterations=it,
        nfev=nfev,
        success=status > 0,
        status=status,
        message=message,
        n_obs=m,
        dof=dof,
        condition_number=cond,
        at_bound=at_bound,
    )


def _covariance(J, d, cost, dof, absolute_sigma):
    """Covariance ``s^2 (J^T J)^-1`` via the SVD of the scaled Jacobian; directions
    with singular value below ``1e-10 * max`` are unidentifiable (their
    parameters get ``nan`` variance).  Returns ``(cov (p, p), condition number)``."""
    p = J.shape[1]
    if p == 0:
        return np.zeros((0, 0)), 1.0
    Js = J * d
    try:
        _, sv, vt = np.linalg.svd(Js, full_matrices=False)
    except np.linalg.LinAlgError:
        return np.full((p, p), np.nan), float("inf")
    if sv.size == 0 or sv[0] == 0:
        return np.full((p, p), np.nan), float("inf")
    if not np.all(np.isfinite(sv)):
        return np.full((p, p), np.nan), float("inf")
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    keep = sv > 1e-10 * sv[0]
    vk = vt[keep]
    cov_u = (vk.T / sv[keep] ** 2) @ vk
    cov = cov_u * np.outer(d, d)
    if not absolute_sigma:
        s2 = 2 * cost / dof if dof > 0 else float("nan")
        cov = cov * s2
    if not keep.all():
        null = vt[~keep]
        bad = np.any(np.abs(null) > 1e-3, axis=0)
        cov[bad, :] = np.nan
        cov[:, bad] = np.nan
    return cov, cond



def covariance_from_jacobian(J: np.ndarray, scale: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Covariance ``(J^T J)^-1`` (absolute sigma) of a weighted Jacobian J (m, p).

    ``scale`` (p,) the variables' typical magnitudes (the pseudo-inverse is
    taken in scaled variables; default ones).  Returns ``(cov (p, p), condition
    number of the column-normalised Jacobian)``; unidentifiable directions give
    ``nan`` rows.  Source: Nocedal & Wright (2006) §10.3; Belsley, Kuh & Welsch,
    *Regression Diagnostics* (1980) for the column-normalised condition number.
    """
    p = J.shape[1]
    d = np.ones(p) if scale is None else np.asarray(scale, float)
    cov, _ = _covariance(J, d, 0.5, 1, True)
    norms = np.linalg.norm(J, axis=0)
    ok = norms > 0
    if ok.sum() == 0:
        return cov, float("inf")
    sv = np.linalg.svd(J[:, ok] / norms[ok], compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if not ok.all():
        cond = float("inf")
    return cov, cond

