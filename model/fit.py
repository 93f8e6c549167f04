"""Gauss–Newton / Levenberg–Marquardt fitting of the wheel–soil models.

Two layers:

* :func:`gauss_newton` – a generic bounded nonlinear least-squares solver
  (paper §1.2: ``Theta_{k+1} = Theta_k + (J^T J)^-1 J^T r`` until the relative
  step is below ``eps``), with Levenberg–Marquardt damping (Marquardt's
  ``diag(J^T J)`` scaling) and bound handling by projection with an active set,
  so that it converges from the parameters' defaults.  It returns a
  :class:`FitResult` with the parameters, standard errors, covariance and
  correlation (as ``lmfit`` reports them) and the residuals.
* :func:`fit_model` – fits one slip-sinkage model (``wheelsoil.model.MODELS``)
  and optionally terrain parameters to measured data: drawbar pull, and jointly
  torque and sinkage when those are measured, each channel weighted by its
  noise (:func:`estimate_noise`).

Sources: Levenberg (1944), Marquardt (1963) for the damping; Nocedal & Wright,
*Numerical Optimization* (2006) §10.3 for the Gauss–Newton step and the
covariance ``s^2 (J^T J)^-1`` of the estimate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

__all__ = [
    "FitResult",
    "gauss_newton",
    "ModelFit",
    "FitData",
    "prepare_data",
    "estimate_noise",
    "fit_model",
    "cross_validate",
    "TERRAIN_PARAMS",
]

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
        0 max_iter reached, -1 non-finite residuals, -2 damping exhausted.
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
    or where the forward point is outside the model's domain."""
    p = len(x)
    J = np.empty((len(r0), p))
    for i in range(p):
        h = math.sqrt(_EPS_MACH) * max(abs(x[i]), d[i])
        if x[i] + h > hi[i]:
            h = -h
        xh = x.copy()
        xh[i] += h
        col = (fun_w(xh) - r0) / h
        if not np.all(np.isfinite(col)) and x[i] - h >= lo[i]:  # outside the model's domain: step back
            xh[i] = x[i] - h
            col = (fun_w(xh) - r0) / -h
        J[:, i] = col
    return J


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
) -> FitResult:
    """Bounded Gauss–Newton with Levenberg–Marquardt damping.

    Minimises ``0.5 * sum((fun(x) / sigma)**2)``.  Each iteration solves
    ``(J^T J + lam diag(J^T J)) dx = -J^T r`` in the scaled variables
    ``u = x / x_scale`` (``lam -> 0`` is the paper's Gauss–Newton step, §1.2),
    projects ``x + dx`` onto the bounds, and freezes parameters that sit on a
    bound with the gradient pointing outwards (active set).  A trial where
    ``fun`` is not finite (outside the model's domain) is halved, up to 6
    times.  A step that does not lower the cost is rejected and ``lam`` raised tenfold; an accepted one lowers
    it tenfold.  Stops when the relative step ``|du| < eps (|u| + eps)``, or the
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

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Shapes disagree, ``x0`` is not finite, ``lower > upper``, or ``sigma``
        is not positive.
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
        J = jac_w(x, r)
        for it in range(1, max_iter + 1):
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
                for _ in range(6):  # infeasible trial (model undefined there): halve the step
                    x_new = np.clip(x + d * du, lo, hi)
                    r_new = fun_w(x_new)
                    if np.all(np.isfinite(r_new)):
                        break
                    du *= 0.5
                cost_new = 0.5 * float(r_new @ r_new) if np.all(np.isfinite(r_new)) else np.inf
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
            J = jac_w(x, r)
            if np.linalg.norm(step_u) <= eps * (np.linalg.norm(x / d) + eps):
                status, message = 1, f"relative step below eps={eps:g}"
                break
            if dcost <= ftol * max(cost, 1e-300):
                status, message = 2, f"relative cost change below ftol={ftol:g}"
                break
    if p == 0 or not np.all(np.isfinite(J)):
        J = np.nan_to_num(J)
    cost = 0.5 * float(r @ r) if np.all(np.isfinite(r)) else float("nan")
    dof = m - p
    cov, cond = _covariance(J, d, cost, dof, absolute_sigma)
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


# --------------------------------------------------------------------------------------
# Fitting the wheel–soil models to measured data
# --------------------------------------------------------------------------------------

#: Terrain parameters ``fit_model`` can fit: name -> (unit, doc).  ``k_eq`` is the
#: combined modulus ``kc/b + kphi`` [N/m^(n+2)]: with one wheel width kc and kphi
#: enter the model only through it (Eq. 2 uses kc/b + kphi, Eq. 10 b times it),
#: so they cannot be separated; a fitted terrain has ``kc = 0, kphi = k_eq``.
TERRAIN_PARAMS: dict[str, tuple[str, str]] = {
    "k_eq": ("N/m^(n+2)", "combined pressure-sinkage modulus kc/b + kphi (Eq. 2)"),
    "n": ("-", "sinkage exponent (Eq. 2)"),
    "c": ("Pa", "cohesion (Eq. 4)"),
    "phi": ("rad", "internal friction angle (Eq. 4)"),
    "K": ("m", "shear deformation modulus (Eq. 4)"),
}

#: Candidate models of the diagnosis: name -> (model core name, terrain parameters
#: re-fitted).  ``terrain_mismatch`` keeps Wong's structure and re-fits the lab
#: terrain's shear parameters K and phi.
CANDIDATES: dict[str, tuple[str, tuple[str, ...]]] = {
    "wong": ("wong", ()),
    "vasilev": ("vasilev", ()),
    "lyasko": ("lyasko", ()),
    "ding": ("ding", ()),
    "terrain_mismatch": ("wong", ("K", "phi")),
}

#: Measured channels a model is fitted against, in order: data column -> WheelForces field.
CHANNELS: dict[str, str] = {
    "drawbar_pull_n": "drawbar_pull_n",
    "torque_nm": "torque_nm",
    "sinkage_m": "sinkage_m",
}

_ZERO_SLIP = 0.02  # |s| below this counts as "s ~ 0" in the exclusion notes


def estimate_noise(values: np.ndarray, slip: np.ndarray, load_n: np.ndarray | None = None,
                   groups: np.ndarray | None = None) -> float:
    """Noise standard deviation of one measured channel, model-free.

    Nearest-neighbour local-difference estimator (von Neumann / Rice, in the
    model's input space): for every sample take its nearest neighbour in
    standardised (slip, load) and ``sigma = 1.4826 * MAD(y_i - y_nn(i)) / sqrt(2)``.
    With ``groups`` (time series) the neighbour must come from another group
    (accelerate cycle / block), so the autocorrelation of filtered 100 Hz data
    does not shrink the estimate.  It contains measurement noise plus any
    variation the inputs (s, W) do not explain.  Used for the relative weights
    of the channels (Dp, T, z); parameter standard errors use the fitted
    residual variance instead (reduced chi-square scaling), so a misestimated
    level does not make them over-confident.

    values, slip, load_n, groups : (N,) arrays; NaNs in ``values`` are ignored.
    Returns a positive float (falls back to the std of the differences, then to
    ``1e-6 * max|values|``).  Raises ValueError with fewer than 2 finite values.
    """
    from scipy.spatial import cKDTree

    v = np.asarray(values, dtype=float)
    cols = [np.asarray(slip, dtype=float)]
    if load_n is not None:
        cols.append(np.asarray(load_n, dtype=float))
    ok = np.isfinite(v)
    for c in cols:
        ok &= np.isfinite(c)
    if ok.sum() < 2:
        raise ValueError("estimate_noise: fewer than 2 finite values")
    X = []
    for c in cols:
        c = c[ok]
        sd = np.std(c)
        if sd > 1e-9 * max(1.0, np.max(np.abs(c))):
            X.append((c - c.mean()) / sd)
    X = np.column_stack(X) if X else np.zeros((int(ok.sum()), 1))
    y = v[ok]
    X = X + 1e-12 * np.arange(len(y))[:, None]  # break exact ties deterministically
    if groups is not None and np.unique(np.asarray(groups)[ok]).size >= 2:
        g = np.asarray(groups)[ok]
        if len(y) > 5000:  # plenty for a noise level; keeps long recordings fast
            pick = np.random.default_rng(0).choice(len(y), 5000, replace=False)
            X, y, g = X[pick], y[pick], g[pick]
        nn = np.empty(len(y), int)
        idx_all = np.arange(len(y))
        for gv in np.unique(g):
            inside = g == gv
            others = idx_all[~inside]
            _, j = cKDTree(X[others]).query(X[inside], k=1)
            nn[inside] = others[j]
    else:
        _, nb = cKDTree(X).query(X, k=min(len(y), 2))
        nn = nb.reshape(len(y), -1)[:, -1]
    dv = y - y[nn]
    s = 1.4826 * np.median(np.abs(dv - np.median(dv))) / math.sqrt(2)
    if not (np.isfinite(s) and s > 0):
        s = float(np.std(dv)) / math.sqrt(2)
    if not (np.isfinite(s) and s > 0):
        s = 1e-6 * max(float(np.max(np.abs(y))), 1e-9)
    return float(s)


@dataclass(frozen=True)
class FitData:
    """Measured samples prepared for fitting (the rows actually used).

    slip, load_n : (N,) arrays.
    channels : data column -> (N,) measured values (``drawbar_pull_n`` always;
        ``torque_nm``/``sinkage_m`` when measured), NaN where missing.
    sigma : data column -> noise std (:func:`estimate_noise`).
    groups : (N,) int cross-validation groups (accelerate cycles, or contiguous blocks).
    units : (N,) int "independent units" for aggregation: table rows, or
        (group, slip-decile) cells of a time series.
    run : (N,) int input index (0 when one input).
    t_s : (N,) time or None (tables).
    kind : "table" or "timeseries".
    notes : list of plain-English notes on excluded rows and choices.
    n_input : rows before filtering; slip_min : threshold used.
    """

    slip: np.ndarray
    load_n: np.ndarray
    channels: dict
    sigma: dict
    groups: np.ndarray
    units: np.ndarray
    run: np.ndarray
    t_s: np.ndarray | None
    kind: str
    notes: list
    n_input: int
    slip_min: float
    group_kind: str = "blocks"

    @property
    def n(self) -> int:
        """Number of samples used."""
        return int(self.slip.size)

    @property
    def n_units(self) -> int:
        """Number of independent units (rows of a table, cells of a time series)."""
        return int(np.unique(self.units).size)

    def subset(self, mask: np.ndarray) -> "FitData":
        """The samples where ``mask`` (N,) bool is True (same noise levels)."""
        return dataclasses_replace(
            self,
            slip=self.slip[mask],
            load_n=self.load_n[mask],
            channels={k: v[mask] for k, v in self.channels.items()},
            groups=self.groups[mask],
            units=self.units[mask],
            run=self.run[mask],
            t_s=None if self.t_s is None else self.t_s[mask],
        )


def dataclasses_replace(obj, **kw):
    """``dataclasses.replace`` (kept local to avoid shadowing the field name)."""
    import dataclasses

    return dataclasses.replace(obj, **kw)


def prepare_data(df, *, slip_min: float = 0.1, source: str = "data", n_blocks: int | None = None) -> FitData:
    """Select and check the samples a driving model is fitted to.

    ``df``: pandas DataFrame with columns ``slip``, ``load_n``, ``drawbar_pull_n``
    and optionally ``torque_nm``, ``sinkage_m``, ``valid`` (bool), ``cycle``
    (accelerate-cycle id, -1 outside), ``run`` (input index), ``t_s`` (time; its
    presence marks a time series).  Kept: rows marked valid, with finite slip,
    load and drawbar pull, ``slip_min < s < 1`` and ``W > 0``.  Skid rows
    (s < 0) and rows with s ~ 0 are excluded from a driving model with a note.

    Cross-validation groups: accelerate cycles (``cycle >= 0``; samples outside a
    cycle join the nearest block), else contiguous blocks in row order (tables:
    ``max(2, min(5, N // 3))`` blocks; time series: 5 blocks per run).

    Raises
    ------
    ValueError
        (naming ``source``) for a missing column, an empty table, no rows left
        after the selection, or only one distinct slip value (no slip
        dependence can be fitted).
    """
    import pandas as pd

    if not isinstance(df, pd.DataFrame):
        raise ValueError(f"{source}: expected a pandas DataFrame, got {type(df).__name__}")
    missing = [c for c in ("slip", "load_n", "drawbar_pull_n") if c not in df.columns]
    if missing:
        raise ValueError(
            f"{source}: missing column(s) {', '.join(missing)}; a table needs slip, load_n, "
            "drawbar_pull_n (optional torque_nm, sinkage_m)"
        )
    n_input = len(df)
    if n_input == 0:
        raise ValueError(f"{source}: the table is empty (no rows)")
    notes: list[str] = []
    s = pd.to_numeric(df["slip"], errors="coerce").to_numpy(float)
    w = pd.to_numeric(df["load_n"], errors="coerce").to_numpy(float)
    dp = pd.to_numeric(df["drawbar_pull_n"], errors="coerce").to_numpy(float)
    keep = np.ones(n_input, bool)
    if "valid" in df.columns:
        valid = df["valid"].fillna(False).astype(bool).to_numpy()
        if (~valid).any():
            notes.append(f"{int((~valid).sum())} of {n_input} samples marked invalid by processing were excluded.")
        keep &= valid
    bad = ~(np.isfinite(s) & np.isfinite(w) & np.isfinite(dp))
    if (bad & keep).any():
        rows = np.flatnonzero(bad & keep)
        notes.append(
            f"{rows.size} row(s) with NaN or non-numeric slip/load_n/drawbar_pull_n excluded "
            f"(first at row {int(rows[0])})."
        )
    keep &= ~bad
    if not keep.any():
        raise ValueError(f"{source}: no row has finite slip, load_n and drawbar_pull_n")
    with np.errstate(invalid="ignore"):
        skid = keep & (s < -_ZERO_SLIP)
        zero = keep & (np.abs(s) <= _ZERO_SLIP)
        low = keep & (s > _ZERO_SLIP) & (s <= slip_min)
        high = keep & (s >= 1.0)
        noload = keep & (w <= 0)
    if skid.any():
        notes.append(f"{int(skid.sum())} skid row(s) (s < 0, braked or locked wheel) excluded: the models are for a driven wheel.")
    if zero.any():
        notes.append(f"{int(zero.sum())} row(s) with s ~ 0 (|s| <= {_ZERO_SLIP}) excluded.")
    if low.any():
        notes.append(f"{int(low.sum())} row(s) with 0 < s <= slip_min = {slip_min:g} excluded (small Dp is dominated by measurement uncertainty, paper §3).")
    if high.any():
        notes.append(f"{int(high.sum())} row(s) with s >= 1 excluded (slip must be < 1).")
    if noload.any():
        notes.append(f"{int(noload.sum())} row(s) with load_n <= 0 excluded.")
    keep &= (s > slip_min) & (s < 1.0) & (w > 0)
    n = int(keep.sum())
    if n == 0:
        raise ValueError(
            f"{source}: no sample with slip_min = {slip_min:g} < s < 1, a finite positive load and a "
            f"finite drawbar pull ({n_input} rows read); lower --slip-min or check the slip column"
        )
    if np.unique(np.round(s[keep], 4)).size < 2:
        raise ValueError(
            f"{source}: only one slip value (s = {s[keep][0]:.4g}) above slip_min = {slip_min:g}; "
            "a slip dependence cannot be fitted from one slip"
        )
    channels = {"drawbar_pull_n": dp[keep]}
    for col in ("torque_nm", "sinkage_m"):
        if col in df.columns:
            v = pd.to_numeric(df[col], errors="coerce").to_numpy(float)[keep]
            n_ok = int(np.isfinite(v).sum())
            if n_ok >= max(3, n // 2):
                channels[col] = v
                if n_ok < n:
                    notes.append(f"{col}: {n - n_ok} of {n} used rows have no value; fitted where present.")
            elif n_ok:
                notes.append(f"{col}: only {n_ok} of {n} used rows have a value; channel not used.")
    slip = s[keep]
    run = (
        pd.to_numeric(df["run"], errors="coerce").fillna(0).to_numpy(int)[keep]
        if "run" in df.columns
        else np.zeros(n, int)
    )
    t_s = pd.to_numeric(df["t_s"], errors="coerce").to_numpy(float)[keep] if "t_s" in df.columns else None
    kind = "timeseries" if t_s is not None else "table"
    groups, group_kind = _cv_groups(df, keep, run, kind, n_blocks)
    if kind == "table" and group_kind == "contiguous blocks":
        ds = np.diff(s[keep])
        if ds.size and (np.all(ds >= 0) or np.all(ds <= 0)):
            notes.append(
                "The table is sorted by slip, so the contiguous cross-validation blocks are slip ranges: the "
                "out-of-sample errors measure prediction at slips not seen in the fit (extrapolation at the ends)."
            )
    sigma = {
        c: estimate_noise(v, slip, w[keep], groups if kind == "timeseries" else None)
        for c, v in channels.items()
    }
    if kind == "table":
        units = np.arange(n)
    else:
        edges = np.quantile(slip, np.linspace(0, 1, 11)[1:-1])
        units = groups * 16 + np.searchsorted(edges, slip)
        _, units = np.unique(units, return_inverse=True)
    return FitData(
        slip=slip,
        load_n=w[keep],
        channels=channels,
        sigma=sigma,
        groups=groups,
        units=units,
        run=run,
        t_s=t_s,
        kind=kind,
        notes=notes,
        n_input=n_input,
        slip_min=float(slip_min),
        group_kind=group_kind,
    )


def _cv_groups(df, keep, run, kind, n_blocks):
    """Cross-validation groups for the kept rows: (groups (N,), description)."""
    n = int(keep.sum())
    if "cycle" in df.columns:
        cyc = np.asarray(df["cycle"].to_numpy(), dtype=float)[keep]
        cyc = np.where(np.isfinite(cyc), cyc, -1).astype(int)
        key = run * 1_000_000 + cyc
        ok = cyc >= 0
        if np.unique(key[ok]).size >= 2:
            # samples outside a cycle join the previous cycle (row order)
            filled = np.where(ok, key, -1)
            last = -1
            for i in range(n):
                if filled[i] < 0:
                    filled[i] = last if last >= 0 else key[ok][0]
                last = filled[i]
            _, g = np.unique(filled, return_inverse=True)
            return g, "accelerate cycles"
    k = n_blocks or (max(2, min(5, n // 3)) if kind == "table" else 5)
    k = max(1, min(k, n))
    g = np.zeros(n, int)
    nxt = 0
    for r in np.unique(run):
        idx = np.flatnonzero(run == r)
        kr = k if np.unique(run).size == 1 else max(1, min(k, idx.size // 2))
        g[idx] = nxt + (np.arange(idx.size) * kr) // idx.size
        nxt += kr
    return g, "contiguous blocks"


@dataclass(frozen=True)
class ModelFit:
    """One candidate model fitted to :class:`FitData`.

    name : candidate name (``wong``, ``vasilev``, ``lyasko``, ``ding``,
        ``terrain_mismatch``); model : model-core name; terrain : the terrain used
        (with fitted parameters substituted); params/stderr : fitted values
        (model and terrain parameters, SI units; ``phi`` in rad);
    fixed_terrain : terrain parameters tried but not identified by the data
        (held at their start values); result : the :class:`FitResult` (None when
        nothing was free); predictions : channel -> (N,) model values on the
        used samples; metrics : Dp metrics ``M0_pct``, ``R0_n``, ``R2`` (paper
        §1.3); channel_metrics : channel -> {R0, R2}; cv : cross-validation
        summary (``cv_R0_n`` on Dp, ``cv_score`` weighted RMS over channels) or
        None; bic : BIC with the effective sample size ``n_eff``; k : number of
        fitted parameters; success/message : fit status.
    """

    name: str
    model: str
    terrain: object
    params: dict
    stderr: dict
    fixed_terrain: tuple
    result: FitResult | None
    predictions: dict
    metrics: dict
    channel_metrics: dict
    bic: float
    n_eff: float
    k: int
    success: bool
    message: str
    cv: dict | None = None
    notes: tuple = ()
    aux: dict | None = field(default=None, repr=False, compare=False)

    @property
    def cv_R0_n(self) -> float | None:
        """Out-of-sample R0 of the drawbar pull [N] (None before cross-validation)."""
        return None if self.cv is None else self.cv["cv_R0_n"]

    def weighted_residuals(self, data: FitData) -> dict:
        """channel -> (N,) residuals (measured - model) / sigma."""
        return {c: (data.channels[c] - self.predictions[c]) / data.sigma[c] for c in data.channels}


def _terrain_with(terrain, wheel, values: Mapping[str, float]):
    """The terrain with fitted terrain parameters substituted (``k_eq`` -> kc=0, kphi=k_eq)."""
    kw = {k: v for k, v in values.items() if k in ("n", "c", "phi", "K")}
    if "k_eq" in values:
        kw["kc"] = 0.0
        kw["kphi"] = float(values["k_eq"])
    return terrain.replace(**kw) if kw else terrain


def _terrain_start(terrain, wheel, name):
    """(start, lower, upper, scale) of a terrain parameter, from the lab/start terrain."""
    if name == "k_eq":
        k0 = terrain.k_eq(wheel.width)
        k0 = k0 if k0 > 0 else 1e5
        return k0, k0 / 1e3, k0 * 1e3, k0
    v = float(getattr(terrain, name))
    if name == "n":
        return v, 0.2, 2.5, max(v, 0.1)
    if name == "c":
        return v, 0.0, 100e3, max(v, 1e3)
    if name == "phi":
        return v, math.radians(1.0), math.radians(60.0), max(v, 0.1)
    if name == "K":
        return v, 1e-4, 0.3, max(v, 1e-3)
    raise ValueError(f"unknown terrain parameter {name!r}; choose from {', '.join(TERRAIN_PARAMS)}")


def _predict(model_obj, terrain, wheel, data: FitData, mp: Mapping[str, float], tv: Mapping[str, float], sinkage):
    """Model forces on the used samples, as a dict of (N,) arrays per channel."""
    t = _terrain_with(terrain, wheel, tv)
    f = model_obj.predict(t, wheel, data.load_n, data.slip, dict(mp), sinkage=sinkage)
    return {c: np.asarray(getattr(f, field), dtype=float) for c, field in CHANNELS.items()}


def _metrics(measured, predicted) -> dict:
    """Paper §1.3 metrics on finite pairs: M0 (%), R0, R^2 (None when undefined)."""
    from wheelsoil.model import m0_pct, r0, r2

    ok = np.isfinite(measured) & np.isfinite(predicted)
    out = {"M0_pct": None, "R0_n": None, "R2": None}
    if ok.sum() < 1:
        return out
    y, p = measured[ok], predicted[ok]
    for key, fn in (("M0_pct", m0_pct), ("R0_n", r0), ("R2", r2)):
        try:
            v = float(fn(y, p))
            out[key] = v if math.isfinite(v) else None
        except (ValueError, ZeroDivisionError, FloatingPointError):
            out[key] = None
    return out


def fit_model(
    data,
    terrain,
    wheel,
    model: str = "lyasko",
    *,
    slip_min: float = 0.1,
    terrain_params: Sequence[str] = (),
    prune: bool = True,
    sinkage: str = "eq10",
    start: Mapping[str, float] | None = None,
    max_iter: int = 60,
    eps: float = 1e-6,
    name: str | None = None,
) -> ModelFit:
    """Fit a model's parameters (and optionally terrain parameters) by Gauss–Newton.

    The objective stacks, for every measured channel (drawbar pull always, torque
    and sinkage when present), ``(measured - model) / sigma_channel`` over the
    used samples, ``sigma`` from :func:`estimate_noise` (paper §1.2, with the
    channels weighted by their noise).

    Parameters
    ----------
    data : pandas DataFrame (see :func:`prepare_data`) or a prepared :class:`FitData`.
    terrain, wheel : ``wheelsoil.model.Terrain`` / ``Wheel`` (lab or start values).
    model : a model-core name (``wong``, ``vasilev``, ``lyasko``, ``ding``) or a
        candidate of :data:`CANDIDATES` (``terrain_mismatch`` = Wong with K and phi
        re-fitted).
    slip_min : samples with s <= slip_min are not used (DataFrame input only).
    terrain_params : extra terrain parameters to fit, from :data:`TERRAIN_PARAMS`
        (``k_eq`` = kc/b + kphi, ``n``, ``c``, ``phi``, ``K``).
    prune : select the terrain parameters the data identifies by forward
        selection (:func:`_select_terrain`: BIC must drop by >= 2 and the relative
        standard error stay < 0.5); the others are held at the given terrain's
        values and listed in ``fixed_terrain``.  False: fit all of them.
    sinkage : ``"eq10"`` or ``"balance"`` (passed to the model core).
    start : optional start values (name -> value).
    max_iter, eps : Gauss–Newton limits.

    Returns
    -------
    ModelFit (``success`` False, with the solver's message, when it did not converge).

    Raises
    ------
    ValueError
        Unknown model or terrain parameter; bad data (see :func:`prepare_data`).
    """
    from wheelsoil.model import get_model

    if not isinstance(data, FitData):
        data = prepare_data(data, slip_min=slip_min)
    cand_name = name or model
    if model in CANDIDATES and model not in ("wong",):
        core, extra = CANDIDATES[model]
    else:
        core, extra = model, ()
    model_obj = get_model(core)
    tparams = list(dict.fromkeys([*extra, *terrain_params]))
    for p in tparams:
        if p not in TERRAIN_PARAMS:
            raise ValueError(f"unknown terrain parameter {p!r}; choose from {', '.join(TERRAIN_PARAMS)}")
    start = dict(start or {})
    fixed: list[str] = []
    notes: list[str] = []
    user = [t for t in tparams if t not in extra]
    if user and prune:
        chosen, fixed, notes = _select_terrain(model_obj, terrain, wheel, data, list(extra), user, start,
                                               sinkage, max(max_iter, 200), eps)
        tparams = [*extra, *chosen]
    res, mp, tv, aux = _fit_once(model_obj, terrain, wheel, data, tparams, start, sinkage,
                                 max(max_iter, 200) if tparams else max_iter, eps)
    mf = _make_model_fit(cand_name, core, model_obj, terrain, wheel, data, res, mp, tv, tuple(fixed), sinkage, notes)
    return dataclasses_replace(mf, aux=aux)


class _Problem:
    """The least-squares problem of one model on one data set, in solver space.

    Solver variables are the model parameters then the terrain parameters;
    ``k_eq`` is ``ln(k_eq)`` there (it spans decades and trades off with n).
    ``fun(u)`` returns (model - measured) over the stacked channels (rows where
    a measurement exists); ``rows`` maps each residual to its sample index.
    """

    def __init__(self, model_obj, terrain, wheel, data, tparams, start, sinkage):
        self.model_obj, self.terrain, self.wheel, self.data, self.sinkage = model_obj, terrain, wheel, data, sinkage
        names, x0, lo, hi, sc = [], [], [], [], []
        for p in model_obj.params:
            names.append(p.name)
            x0.append(float(start.get(p.name, p.default)))
            lo.append(float(p.lower))
            hi.append(float(p.upper))
            rng = float(p.upper) - float(p.lower)
            sc.append(max(abs(x0[-1]), rng / 10 if math.isfinite(rng) else 1.0))
        self.n_model = len(names)
        self.log_idx = []
        for t in tparams:
            v0, a, b, s = _terrain_start(terrain, wheel, t)
            names.append(t)
            v = float(start.get(t, v0))
            if t == "k_eq":
                self.log_idx.append(len(x0))
                v, a, b, s = math.log(min(max(v, a), b)), math.log(a), math.log(b), 1.0
            x0.append(v)
            lo.append(a)
            hi.append(b)
            sc.append(s)
        self.names, self.x0 = names, np.array(x0, float)
        self.lo, self.hi, self.sc = np.array(lo, float), np.array(hi, float), np.array(sc, float)
        self.chans = list(data.channels)
        meas = np.concatenate([data.channels[c] for c in self.chans])
        sig = np.concatenate([np.full(data.n, data.sigma[c]) for c in self.chans])
        self.okm = np.isfinite(meas)
        self.meas, self.sig = meas[self.okm], sig[self.okm]
        self.rows = np.tile(np.arange(data.n), len(self.chans))[self.okm]

    def split(self, u):
        """Solver vector -> (model params dict, terrain values dict) in SI."""
        x = np.array(u, dtype=float)
        x[self.log_idx] = np.exp(x[self.log_idx])
        return dict(zip(self.names[: self.n_model], x[: self.n_model])), dict(zip(self.names[self.n_model:], x[self.n_model:]))

    def fun(self, u):
        mp, tv = self.split(u)
        try:
            pred = _predict(self.model_obj, self.terrain, self.wheel, self.data, mp, tv, self.sinkage)
        except (ValueError, FloatingPointError):
            return np.full(self.meas.size, np.inf)
        return np.concatenate([pred[c] for c in self.chans])[self.okm] - self.meas

    def solve(self, max_iter, eps, ftol):
        """Gauss–Newton; returns (FitResult in SI, model params, terrain values, aux dict)."""
        res = gauss_newton(self.fun, self.x0, bounds=(self.lo, self.hi), x_scale=self.sc, sigma=self.sig,
                           names=self.names, eps=eps, max_iter=max_iter, ftol=ftol)
        mp, tv = self.split(res.x)
        aux = {"u": res.x.copy(), "jac": res.jac, "r": res.weighted_residuals, "lo": self.lo, "hi": self.hi,
               "rows": self.rows, "split": self.split}
        if self.data.kind == "timeseries" and np.all(np.isfinite(res.jac)):
            res = _cluster_robust(res, self.data.units[self.rows])
        if self.log_idx:  # back to k_eq: delta method, se(k) = k se(ln k); correlations unchanged
            g = np.ones(len(self.names))
            x = res.x.copy()
            x[self.log_idx] = np.exp(x[self.log_idx])
            g[self.log_idx] = x[self.log_idx]
            cov = res.covariance * np.outer(g, g)
            se = np.sqrt(np.clip(np.diag(cov), 0, None))
            se = np.where(np.isfinite(np.diag(cov)), se, np.nan)
            res = dataclasses_replace(res, x=x, params=dict(zip(self.names, map(float, x))),
                                      stderr=dict(zip(self.names, map(float, se))), covariance=cov)
        return res, mp, tv, aux


def _cluster_robust(res: FitResult, clusters: np.ndarray) -> FitResult:
    """Replace the covariance by the cluster-robust (sandwich) estimate.

    ``cov = B M B * G/(G-1)`` with ``B = (J^T J)^-1`` and
    ``M = sum_g (J_g^T r_g)(J_g^T r_g)^T`` over clusters g (Liang & Zeger 1986;
    Cameron & Miller 2015): residuals of filtered 100 Hz data are correlated
    within a (cycle, slip-cell) unit, and the plain ``s^2 (J^T J)^-1`` would
    understate the standard errors by about the square root of the samples per
    independent unit.  Falls back to the plain covariance with < 5 clusters.
    """
    uniq, inv = np.unique(clusters, return_inverse=True)
    G = uniq.size
    p = res.jac.shape[1]
    if G < 5 or p == 0:
        return res
    J, r = res.jac, res.weighted_residuals
    scores = np.zeros((G, p))
    np.add.at(scores, inv, J * r[:, None])
    meat = scores.T @ scores * (G / (G - 1))
    bread = np.linalg.pinv(J.T @ J)
    cov = bread @ meat @ bread
    bad = ~np.isfinite(np.diag(res.covariance))
    cov[bad, :] = np.nan
    cov[:, bad] = np.nan
    d = np.diag(cov)
    se = np.where(np.isfinite(d), np.sqrt(np.clip(d, 0, None)), np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    return dataclasses_replace(res, covariance=cov, correlation=corr,
                               stderr=dict(zip(res.names, map(float, se))),
                               message=res.message + "; cluster-robust standard errors")


FIT_FTOL = 1e-8  #: relative cost change that ends a model fit (statistically negligible)


def _fit_once(model_obj, terrain, wheel, data, tparams, start, sinkage, max_iter, eps, ftol=FIT_FTOL):
    """One Gauss–Newton run: returns (FitResult | None, model params, terrain values, aux | None)."""
    prob = _Problem(model_obj, terrain, wheel, data, tparams, start, sinkage)
    if not prob.names:
        return None, {}, {}, None
    return prob.solve(max_iter, eps, ftol)


SELECT_BIC_DROP = 2.0  #: a terrain parameter joins the fit only if BIC drops by at least this
SELECT_MAX_REL_SE = 0.5  #: ... and its relative standard error stays below this


def _bic_of(res: FitResult, data: FitData) -> float:
    """BIC of a fit with the effective sample size (see :class:`ModelFit`)."""
    n_eff = res.n_obs * data.n_units / max(data.n, 1)
    rss = max(2 * res.cost, 1e-300)
    return n_eff * math.log(rss / res.n_obs) + len(res.x) * math.log(max(n_eff, 1.0))


def _identified(res: FitResult, names, terrain, wheel) -> bool:
    """True when every parameter in ``names`` has a finite relative standard error
    below SELECT_MAX_REL_SE (relative to max(|value|, typical scale)) and is not on a bound."""
    for t in names:
        se = res.stderr[t]
        scale = max(abs(res.params[t]), _terrain_start(terrain, wheel, t)[3] if t in TERRAIN_PARAMS else 0.0)
        if not np.isfinite(se) or scale <= 0 or se / scale > SELECT_MAX_REL_SE or t in res.at_bound:
            return False
    return True


def _select_terrain(model_obj, terrain, wheel, data, base, pool, start, sinkage, max_iter, eps):
    """Forward selection of the terrain parameters the data identifies.

    Starting from the model's own parameters (plus ``base``), add, one at a
    time, the parameter of ``pool`` that lowers the BIC most, as long as the BIC
    drops by at least SELECT_BIC_DROP, the fit converges, and every added
    terrain parameter stays identified (relative stderr < SELECT_MAX_REL_SE,
    not on a bound).  Returns (chosen, not chosen, notes).
    """
    chosen: list[str] = []
    res0, _, _, _ = _fit_once(model_obj, terrain, wheel, data, base, start, sinkage, max_iter, eps)
    best_bic = _bic_of(res0, data) if res0 is not None else None
    if best_bic is None:  # no free parameter at all: compare with the plain prediction
        chans = list(data.channels)
        try:
            pred = _predict(model_obj, terrain, wheel, data, {}, {}, sinkage)
            e = np.concatenate([(data.channels[c] - pred[c]) / data.sigma[c] for c in chans])
            e = e[np.isfinite(e)]
            n_eff = e.size * data.n_units / max(data.n, 1)
            best_bic = n_eff * math.log(max(float(e @ e), 1e-300) / e.size)
        except ValueError:
            best_bic = float("inf")
    remaining = list(pool)
    while remaining:
        trials = []
        for t in remaining:
            res, _, _, _ = _fit_once(model_obj, terrain, wheel, data, [*base, *chosen, t], start, sinkage, max_iter, eps)
            if res is None or not res.success or not np.isfinite(res.cost):
                continue
            if not _identified(res, [*chosen, t], terrain, wheel):
                continue
            trials.append((_bic_of(res, data), t))
        if not trials:
            break
        bic, t = min(trials)
        if bic > best_bic - SELECT_BIC_DROP:
            break
        chosen.append(t)
        remaining.remove(t)
        best_bic = bic
    notes = []
    if remaining:
        notes.append(
            "terrain parameter(s) " + ", ".join(remaining) + " not identified by the data (forward selection: "
            f"BIC drop >= {SELECT_BIC_DROP:g}, relative stderr < {SELECT_MAX_REL_SE:g}); held at the given terrain's values"
        )
    return chosen, remaining, notes


def _make_model_fit(cand_name, core, model_obj, terrain, wheel, data, res, mp, tv, fixed, sinkage, notes):
    """Assemble a :class:`ModelFit` (predictions, metrics, BIC) from a fit."""
    try:
        pred = _predict(model_obj, terrain, wheel, data, mp, tv, sinkage)
        ok_pred = True
    except (ValueError, FloatingPointError) as exc:
        pred = {c: np.full(data.n, np.nan) for c in CHANNELS}
        ok_pred = False
        notes = [*notes, f"model could not be evaluated: {exc}"]
    metrics = _metrics(data.channels["drawbar_pull_n"], pred["drawbar_pull_n"])
    chm = {}
    rss, nobs = 0.0, 0
    for c, y in data.channels.items():
        m = _metrics(y, pred[c])
        chm[c] = {"R0": m["R0_n"], "R2": m["R2"]}
        e = (y - pred[c]) / data.sigma[c]
        e = e[np.isfinite(e)] if ok_pred else e
        rss += float(np.sum(e**2))
        nobs += int(np.sum(np.isfinite(y)))
    k = 0 if res is None else len(res.x)
    n_eff = nobs * data.n_units / max(data.n, 1)
    bic = n_eff * math.log(max(rss, 1e-300) / max(nobs, 1)) + k * math.log(max(n_eff, 1.0)) if ok_pred else float("nan")
    if res is None:
        params, stderr, success, message = {}, {}, ok_pred, "no free parameters" if ok_pred else notes[-1]
    else:
        params, stderr = dict(res.params), dict(res.stderr)
        success, message = res.success and ok_pred, res.message
    return ModelFit(
        name=cand_name,
        model=core,
        terrain=_terrain_with(terrain, wheel, tv),
        params=params,
        stderr=stderr,
        fixed_terrain=tuple(fixed),
        result=res,
        predictions=pred,
        metrics=metrics,
        channel_metrics=chm,
        bic=bic,
        n_eff=n_eff,
        k=k,
        success=success,
        message=message,
        notes=tuple(notes),
    )


def cross_validate(data: FitData, fit: ModelFit, terrain, wheel, *, sinkage: str = "eq10",
                   method: str = "linear", max_iter: int = 20, eps: float = 1e-5) -> ModelFit:
    """Leave-one-group-out cross-validation of a fitted model.

    For each group of ``data.groups`` (accelerate cycles, or contiguous blocks
    for tables) the parameters are re-estimated without the group and the
    held-out group is predicted with the model (an exact model evaluation).
    ``method="linear"`` (default) re-estimates by one Gauss–Newton step of the
    training objective from the full-data optimum, using the full-data
    Jacobian's training rows: ``du = -pinv(J_train) r_train`` (the standard
    one-step approximation of leave-group-out refits; exact for a linear model,
    and close here because one group moves the optimum little).  ``"refit"``
    runs Gauss–Newton to convergence per fold (started at the optimum).

    With accelerate cycles as groups, the fold estimates also give a jackknife
    standard error over cycles (``cv["stderr_jackknife"]``); the returned fit's
    ``stderr`` is the larger of it and the cluster-robust one, because
    cycle-to-cycle variation (soil, speed) is invisible inside one cycle.

    Pooled held-out errors give ``cv_R0_n`` (RMS error of Dp [N]), ``cv_R0``
    (per channel) and ``cv_score`` (RMS of the noise-weighted residuals over
    all channels).  Returns a copy of ``fit`` with ``cv`` set; with one group or
    no free parameters the held-out predictions are the model's predictions.
    Raises ValueError for an unknown method.
    """
    from wheelsoil.model import get_model

    if method not in ("linear", "refit"):
        raise ValueError(f"cross_validate: method must be 'linear' or 'refit', got {method!r}")
    model_obj = get_model(fit.model)
    groups = np.unique(data.groups)
    held = {c: np.full(data.n, np.nan) for c in data.channels}
    free_t = [n for n in fit.params if n in TERRAIN_PARAMS]
    failed = 0
    aux = fit.aux
    if fit.k == 0 or groups.size < 2 or aux is None:
        for c in data.channels:
            held[c] = fit.predictions[c]
    else:
        split = aux["split"]
        fold_params = []
        for g in groups:
            test = data.groups == g
            if method == "linear":
                train_rows = ~test[aux["rows"]]
                J, r = aux["jac"][train_rows], aux["r"][train_rows]
                ok = np.all(np.isfinite(J)) and np.all(np.isfinite(r))
                du = np.zeros_like(aux["u"])
                # parameters at a bound stay there (a step along a nearly degenerate
                # direction, then clipped, would wreck the held-out prediction)
                free = ~(np.isclose(aux["u"], aux["lo"]) | np.isclose(aux["u"], aux["hi"]))
                if ok and free.any():
                    du[free] = np.linalg.lstsq(J[:, free], -r, rcond=None)[0]
                mp, tv = split(np.clip(aux["u"] + du, aux["lo"], aux["hi"]))
            else:
                res, mp, tv, _ = _fit_once(model_obj, terrain, wheel, data.subset(~test), free_t,
                                           fit.params, sinkage, max_iter, eps)
                if res is None or not np.all(np.isfinite(res.x)):
                    failed += 1
                    mp, tv = split(aux["u"])
            fold_params.append({**mp, **tv})
            try:
                pred = _predict(model_obj, terrain, wheel, data.subset(test), mp, tv, sinkage)
            except (ValueError, FloatingPointError):
                try:  # the step left the feasible region: fall back to the full-data fit
                    pred = _predict(model_obj, terrain, wheel, data.subset(test), *split(aux["u"]), sinkage)
                    failed += 1
                except (ValueError, FloatingPointError):
                    failed += 1
                    continue
            for c in data.channels:
                held[c][test] = pred[c]
    dp = data.channels["drawbar_pull_n"]
    e = dp - held["drawbar_pull_n"]
    ok = np.isfinite(e)
    cv_r0 = float(np.sqrt(np.mean(e[ok] ** 2))) if ok.any() else None
    cv_ch = {}
    for c, y in data.channels.items():
        ec = y - held[c]
        okc = np.isfinite(ec)
        cv_ch[c] = float(np.sqrt(np.mean(ec[okc] ** 2))) if okc.any() else None
    ws = []
    for c, y in data.channels.items():
        w = (y - held[c]) / data.sigma[c]
        ws.append(w[np.isfinite(w)])
    wcat = np.concatenate(ws) if ws else np.zeros(0)
    score = float(np.sqrt(np.mean(wcat**2))) if wcat.size else None
    cv = {
        "cv_R0_n": cv_r0,
        "cv_score": score,
        "cv_R0": cv_ch,
        "n_groups": int(groups.size),
        "group_kind": data.group_kind,
        "method": method,
        "failed_folds": failed,
        "held_out": held,
    }
    stderr = fit.stderr
    if fit.k and groups.size >= 2 and aux is not None and data.group_kind == "accelerate cycles":
        # jackknife over accelerate cycles: catches cycle-level variation (soil, speed)
        # that the within-run cluster-robust errors cannot see; the larger one is kept
        names = list(fit.params)
        P = np.array([[fp[n] for n in names] for fp in fold_params])
        G = P.shape[0]
        jk = np.sqrt((G - 1) / G * np.sum((P - P.mean(axis=0)) ** 2, axis=0))
        cv["stderr_jackknife"] = dict(zip(names, map(float, jk)))
        stderr = {n: (max(v, j) if np.isfinite(v) else v) for (n, v), j in zip(fit.stderr.items(), jk)}
    return dataclasses_replace(fit, cv=cv, stderr=stderr)


def synthetic_data(
    terrain,
    wheel,
    model: str = "wong",
    params: Mapping[str, float] | None = None,
    *,
    kind: str = "timeseries",
    duration_s: float = 60.0,
    rate_hz: float = 100.0,
    n_rows: int = 60,
    load_n: float = 11000.0,
    noise_dp_n: float = 40.0,
    noise_t_nm: float = 20.0,
    noise_z_m: float | None = None,
    cycle_s: float = 10.0,
    cutoff_hz: float = 5.0,
    terrain_truth=None,
    seed: int = 0,
):
    """Synthetic measured data from the model core plus noise (for tests, benchmarks
    and power studies).

    ``kind="timeseries"``: ``duration_s`` at ``rate_hz`` of repeated
    accelerate-brake cycles (``cycle_s`` long: slip ramps 0 -> 0.9 and back, then
    a skid phase), load ``load_n`` +/- 5 % slow variation, noise low-pass
    filtered at ``cutoff_hz`` (so it is autocorrelated like processed data);
    columns ``t_s, slip, load_n, drawbar_pull_n, torque_nm, valid, cycle``.
    ``kind="table"``: ``n_rows`` independent rows, slip uniform in [0.05, 0.9],
    white noise; columns ``slip, load_n, drawbar_pull_n, torque_nm``.
    ``noise_z_m`` adds a ``sinkage_m`` column.  The data follow ``model`` with
    ``params`` on ``terrain_truth`` (default ``terrain``).

    Returns a pandas DataFrame.  Raises ValueError for an unknown kind/model.
    """
    import pandas as pd
    from scipy.signal import butter, sosfiltfilt

    from wheelsoil.model import get_model

    rng = np.random.default_rng(seed)
    truth = terrain_truth or terrain
    m = get_model(model)
    if kind == "timeseries":
        n = int(round(duration_s * rate_hz))
        t = np.arange(n) / rate_hz
        ph = (t % cycle_s) / cycle_s
        up = np.clip(ph / 0.4, 0, 1)
        down = np.clip((0.7 - ph) / 0.3, 0, 1)
        slip = np.where(ph < 0.4, 0.9 * up, np.where(ph < 0.7, 0.9 * down, -0.3 * np.sin(np.pi * (ph - 0.7) / 0.3)))
        cycle = np.where(ph < 0.4, (t // cycle_s).astype(int), -1)
        w = load_n * (1 + 0.05 * np.sin(2 * np.pi * t / 7.3) + 0.02 * np.sin(2 * np.pi * t / 2.1))
        sos = butter(2, cutoff_hz, fs=rate_hz, output="sos")

        def noise(sd):
            e = sosfiltfilt(sos, rng.normal(0, 1, n))
            return sd * e / np.std(e)
    elif kind == "table":
        n = int(n_rows)
        t = None
        slip = rng.uniform(0.05, 0.9, n)
        cycle = None
        w = load_n * (1 + 0.05 * rng.uniform(-1, 1, n))

        def noise(sd):
            return rng.normal(0, sd, n)
    else:
        raise ValueError(f"kind must be 'timeseries' or 'table', got {kind!r}")
    drive = (slip > 0) & (slip < 1)
    dp = np.zeros(n)
    tq = np.zeros(n)
    z = np.zeros(n)
    f = m.predict(truth, wheel, w[drive], slip[drive], dict(params or {}))
    dp[drive], tq[drive], z[drive] = f.drawbar_pull_n, f.torque_nm, f.sinkage_m
    # skid samples: a crude braking-force placeholder (excluded from the driving fit)
    dp[~drive] = slip[~drive] * 0.5 * w[~drive]
    cols = {"slip": slip, "load_n": w, "drawbar_pull_n": dp + noise(noise_dp_n), "torque_nm": tq + noise(noise_t_nm)}
    if noise_z_m is not None:
        cols["sinkage_m"] = z + noise(noise_z_m)
    df = pd.DataFrame(cols)
    if kind == "timeseries":
        df.insert(0, "t_s", t)
        df["valid"] = True
        df["cycle"] = cycle
    return df
