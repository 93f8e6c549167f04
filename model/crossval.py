"""Fitting a hypothesis to the cell means, and cycle-level cross-validation.

:func:`fit_hypothesis` fits one :class:`~wheelsoil.model.hypotheses.Hypothesis`
to the :class:`~wheelsoil.model.data.Cells` of the data by penalised least
squares: the residuals are ``(model - cell mean) / sd_cell`` for every
measured channel, each channel weighted by its own model-free noise
(:func:`wheelsoil.model.data.cell_noise`), the model of a cell being its mean over
the cell's spread of slips (:func:`cell_forces`, not the model at the mean slip; the spread's
term is taken at a first optimum, held fixed, and one Gauss-Newton step moves the optimum by
what it changes), plus one residual
``(theta - prior mean) / prior sd`` per parameter with a lab prior (the
MAP estimate under Gaussian priors; Bishop, *PRML* §3.3).  The solver is
:func:`wheelsoil.model.solver.gauss_newton`, from the lab values (or from ``start``: the diagnosis
restarts a fit whose objective :func:`lower_at` finds lower at the values of a hypothesis that
contains it, or that it contains, than at its own optimum: a local optimum of a non-convex problem).

Standard errors (all in :attr:`HypFit.stderr`):

* the curvature of the penalised objective with the data rows scaled by the
  overdispersion ``c_hat = max(1, chi2_data / dof)`` (quasi-likelihood,
  McCullagh & Nelder 1989 §9.2): a misspecified model is not over-confident;
* parameters of a hypothesis that holds the lab terrain fixed also carry the
  lab terrain's uncertainty, propagated by the implicit-function theorem
  (``d theta / d t = -(J_th^T J_th)^-1 J_th^T J_t``, delta method);
* the jackknife over the cross-validation folds (accelerate cycles) when
  larger: cycle-to-cycle variation is invisible inside one fit.

:func:`cross_validate` refits the hypothesis without each fold (accelerate
cycle, or slip-rank fold of a table; beyond ``MAX_FOLDS`` cycles, contiguous blocks of
cycles), warm-started at the full-data optimum,
and predicts the held-out cells: the out-of-sample residuals the verdict's
paired tests use.

Evidence (:attr:`HypFit.log_evidence`): Laplace approximation
``-chi2/(2 c_hat) + 1/2 log det Sigma_post - 1/2 log det Sigma_prior``, where
parameters without a lab prior get the unit-information prior (sd = sqrt(n) x
their data standard error), which makes the approximation equal to -BIC/2 for
them (Kass & Wasserman 1995; Kass & Raftery 1995).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .data import CHANNELS, Cells, FitData
from .hypotheses import Context, Hypothesis
from .solver import FitResult, gauss_newton
from .wong import WheelForces

__all__ = ["HypFit", "fit_hypothesis", "lower_at", "meaningful", "cross_validate", "cell_forces", "predict_cells",
           "inv_psd", "FIT_FTOL"]

FIT_FTOL = 1e-8  #: relative cost change that ends a fit (statistically negligible)
FIT_MAX_ITER = 500  #: Gauss-Newton iteration limit of a fit (the ten-parameter drifts need ~200-250;
#: a fit stopped before it converged is left out of the verdict)
CV_MAX_ITER = 4  #: Gauss-Newton iterations of a warm-started fold refit (one fold moves the optimum
#: little and Gauss-Newton converges quadratically near it: 2-3 steps reach the fold's optimum)
CV_HALVINGS = 0  #: halvings of a fold refit's trial outside the model's domain (``gauss_newton``): none,
#: the damping is raised at once.  A fold refit starts at the full fit's optimum; where that lies at the
#: domain's edge (sinkage -> r), a step outward was halved 5 times at each damping, 6 kernel calls per
#: damping value instead of 1: 3/4 of ``bench_fit.py``'s fold evaluations, its held-out errors within
#: 0.5 % with none (fits away from the edge: the same numbers bit for bit)
MAX_FOLDS = 20  #: more accelerate cycles than this are merged into this many contiguous folds.
#: The cycles are the independent units of the diagnosis' paired test over folds: merging them
#: only lowers its power (its t over the folds has n - 1 degrees of freedom, and an effect
#: confined to the end of a run gains in few folds); the cap bounds the cost of the refits
#: (linear in the folds) for long recordings


def cv_folds(group: np.ndarray) -> np.ndarray:
    """Fold of each cell: the CV group (accelerate cycle, table fold), with more than
    ``MAX_FOLDS`` groups merged into ``MAX_FOLDS`` contiguous blocks of groups (cycles stay whole)."""
    uniq, inv = np.unique(group, return_inverse=True)
    if uniq.size <= MAX_FOLDS:
        return inv
    return (inv * MAX_FOLDS) // uniq.size


@dataclass
class HypFit:
    """One hypothesis fitted to the cells (see module doc).

    name : hypothesis name (the model form); effect : its effect; model : the
    slip-sinkage core (``wong``, ``vasilev``, ``lyasko``, ``ding``) for curves;
    terrain : the terrain used (fitted values substituted; for drift the
    mid-run terrain); params / stderr / stderr_fit : values and standard errors
    (SI; stderr includes the lab-prior uncertainty and the jackknife);
    units : name -> unit; at_bound : names on a bound; prior : name -> (mean,
    sd, log) of parameters with a prior; result : the :class:`FitResult`
    (None when nothing is free); cell_pred : channel -> (C,) in-sample
    predictions on the cells; cell_load_model : (C,) model W (Eq. 7);
    cell_sinkage : (C,) model sinkage; predictions : channel -> (N,) on the
    samples (filled by the diagnosis); chi2_data, chi2_prior, n_data, k, dof;
    log_evidence, bic; cv : cross-validation (``held_cells`` channel -> (C,),
    ``fold_params``, ``cv_R0`` channel -> RMS held-out error on the cells,
    ``cv_R0_n`` Dp, ``n_groups``, ``group_kind``, ``cv_score``); success,
    message, notes; sensitivity : the lab-prior part of the variance.
    """

    name: str
    effect: str
    model: str
    hypothesis: Hypothesis
    terrain: object
    params: dict
    stderr: dict
    stderr_fit: dict
    units: dict
    at_bound: tuple
    prior: dict
    result: FitResult | None
    cell_pred: dict
    cell_load_model: np.ndarray
    cell_sinkage: np.ndarray
    chi2_data: float
    chi2_prior: float
    n_data: int
    k: int
    dof: int
    log_evidence: float
    bic: float
    success: bool
    message: str
    predictions: dict = field(default_factory=dict)
    metrics: dict = field(default_factory=dict)
    channel_metrics: dict = field(default_factory=dict)
    cv: dict | None = None
    notes: tuple = ()
    fixed_terrain: tuple = ()
    n_eff: float = 0.0
    condition_number: float = float("nan")
    u: np.ndarray | None = field(default=None, repr=False)
    info: tuple = field(default=(), repr=False)
    hparams: tuple = field(default=(), repr=False)
    cov: np.ndarray | None = field(default=None, repr=False)
    ctx: Context | None = field(default=None, repr=False)
    spread: dict | None = field(default=None, repr=False)  #: the cells' slip-spread terms (:func:`_spread_terms`)

    def curve(self, load_n, slip, x=None):
        """WheelForces of the fitted hypothesis at (N,) loads and slips (drift: at mid-run, x = 0)."""
        return self.hypothesis.predict(self.ctx, load_n, slip, np.zeros(np.size(load_n)) if x is None else x,
                                       self.params)

    def evidence(self, c_hat: float, deff: float = 1.0) -> float:
        """Laplace log evidence with a given overdispersion ``c_hat`` (the diagnosis uses one
        common value for all hypotheses, from the best fit; quasi-likelihood practice) and design
        effect ``deff`` >= 1 (cells correlated within a fold: the data weigh as ``n_data / deff``
        independent cells, Kish 1965; the unit-information prior is unchanged by it)."""
        return _laplace(self.chi2_data, self.chi2_prior, self.info, self.hparams, self.n_data / deff, c_hat * deff)

    @property
    def c_hat(self) -> float:
        """The fit's own overdispersion, ``max(1, chi2_data / dof)`` (a scalar): the reduced chi-square where
        it exceeds one, by which its Laplace covariance is scaled.  Source: quasi-likelihood overdispersion,
        McCullagh & Nelder 1989 §9.2."""
        return max(1.0, self.chi2_data / max(self.dof, 1))

    @property
    def cv_R0_n(self) -> float | None:
        """Out-of-sample RMS error of Dp on the cells [N] (None before cross-validation)."""
        return None if self.cv is None else self.cv["cv_R0_n"]


class _Problem:
    """Penalised least squares of one hypothesis on one set of cells, in solver variables
    (ln for ``log`` parameters)."""

    def __init__(self, hyp: Hypothesis, ctx: Context, cells: Cells, spread: dict | None = None):
        self.hyp, self.ctx, self.cells = hyp, ctx, cells
        self.params = hyp.parameters(ctx)
        self.names = [q.name for q in self.params]
        self.log = np.array([q.log for q in self.params], bool)
        x0, lo, hi, sc = [], [], [], []
        for q in self.params:
            if q.log:
                x0.append(math.log(min(max(q.default, q.lower), q.upper)))
                lo.append(math.log(q.lower))
                hi.append(math.log(q.upper))
                sc.append(1.0)
            else:
                x0.append(min(max(q.default, q.lower), q.upper))
                lo.append(q.lower)
                hi.append(q.upper)
                rng = q.upper - q.lower
                sc.append(q.prior[1] if q.prior else max(abs(q.default), rng / 10 if math.isfinite(rng) else 1.0))
        self.x0, self.lo, self.hi = np.array(x0, float), np.array(lo, float), np.array(hi, float)
        self.sc = np.where(np.array(sc) > 0, sc, 1.0)
        self.prior_idx = [i for i, q in enumerate(self.params) if q.prior]
        self.prior_mu = np.array([self.params[i].prior[0] for i in self.prior_idx], float)
        self.prior_sd = np.array([self.params[i].prior[1] for i in self.prior_idx], float)
        self.chans = [c for c in cells.channels]
        ys, sds = [], []
        for c in self.chans:
            ys.append(cells.channels[c])
            sds.append(np.sqrt(cells.var[c]))
        y = np.concatenate(ys) if ys else np.zeros(0)
        sd = np.concatenate(sds) if sds else np.zeros(0)
        self.ok = np.isfinite(y)
        self.y, self.sd = y[self.ok], sd[self.ok]
        self.m_data = int(self.ok.sum())
        # ``spread``: channel -> (C,) the cells' slip-spread terms, held fixed (:func:`_spread_terms`)
        self.spread = 0.0 if spread is None else np.concatenate([spread[c] for c in self.chans])[self.ok]

    def vector(self, values: Mapping[str, float]) -> np.ndarray:
        """Name -> value (SI) -> solver vector, clipped into the bounds; the start values for the
        names ``values`` lacks."""
        x = self.x0.copy()
        for i, nme in enumerate(self.names):
            if nme in values and np.isfinite(values[nme]) and (values[nme] > 0 or not self.log[i]):
                x[i] = math.log(values[nme]) if self.log[i] else float(values[nme])
        return np.clip(x, self.lo, self.hi)

    def values(self, u) -> dict:
        """Solver vector -> name -> value (SI)."""
        x = np.array(u, dtype=float)
        x[self.log] = np.exp(x[self.log])
        return dict(zip(self.names, map(float, x)))

    def forces(self, u, cells: Cells | None = None):
        """The model at the cells' mean slips (the spread terms are added by :meth:`fun`)."""
        c = self.cells if cells is None else cells
        return self.hyp.predict(self.ctx, c.load_n, c.slip, c.x, self.values(u), inertia=c.inertia,
                                speed_mps=c.speed_mps)

    def stack(self, f) -> np.ndarray:
        return np.concatenate([np.asarray(getattr(f, CHANNELS[c]), float) for c in self.chans])[self.ok]

    def fun(self, u):
        try:
            with np.errstate(all="ignore"):
                f = self.forces(u)
            r = (self.stack(f) + self.spread - self.y) / self.sd
        except (ValueError, FloatingPointError, ZeroDivisionError):
            return np.full(self.m_data + len(self.prior_idx), np.inf)
        if self.prior_idx:
            r = np.concatenate([r, (np.asarray(u, float)[self.prior_idx] - self.prior_mu) / self.prior_sd])
        return r

    def solve(self, x0=None, max_iter=60, eps=1e-6, **kw):
        """:func:`~.solver.gauss_newton` on this problem (``kw``: its ``jac0``, ``covariance``, ``halvings``)."""
        return gauss_newton(self.fun, self.x0 if x0 is None else x0, bounds=(self.lo, self.hi), x_scale=self.sc,
                            names=self.names, eps=eps, max_iter=max_iter, ftol=FIT_FTOL, absolute_sigma=True, **kw)

    def data_rows(self, keep: np.ndarray) -> np.ndarray:
        """Boolean mask over this problem's data rows: those of the cells ``keep`` (n_cells,),
        i.e. the rows of the problem on ``cells.subset(keep)`` (every cell's prediction depends on
        that cell alone, so that problem's Jacobian is these rows of this one's)."""
        return np.tile(np.asarray(keep, bool), len(self.chans))[self.ok]


def cell_forces(hyp: Hypothesis, ctx: Context, cells: Cells, params: dict) -> WheelForces:
    """WheelForces of ``hyp`` with ``params`` on the cells: each field (C,) the model's mean over the
    cell's slips, not the model at the cell's mean slip.  A cell's measured mean is the mean of the
    forces over its samples; the model at the mean slip differs from it by f''(s) Var(s) / 2 (Jensen),
    about one cell-noise sigma per cell on a benchmark clay run whose Dp rises steeply with slip,
    which a five-value terrain re-fit absorbed and a one-value re-fit could not.  The mean is taken at the two
    points s_mean -+ sd_s (they match the cell's mean and variance of slip, so the rule is exact for a
    quadratic in s; ``cells.slip_sd``, clipped so both points stay in (0, 1)); tables (one test point
    per cell, ``slip_sd`` None) are evaluated at their slip.  Units as the kernel's (N, N m, m, rad).
    Source: paper Eqs. (1)-(10) through ``hyp.predict``; Jensen's inequality for the error of the
    model at the mean.  Raises ValueError where the hypothesis' kernel does (a slip or load outside
    the model, naming the element)."""
    sd = cells.slip_sd
    if sd is None or not np.any(sd > 0):
        return hyp.predict(ctx, cells.load_n, cells.slip, cells.x, params, inertia=cells.inertia,
                           speed_mps=cells.speed_mps)
    n = cells.n
    sd = np.minimum(sd, 0.999 * np.minimum(np.abs(cells.slip), np.abs(1.0 - cells.slip)))  # both points in (0, 1)
    two = np.concatenate
    f = hyp.predict(ctx, two([cells.load_n, cells.load_n]), two([cells.slip - sd, cells.slip + sd]),
                    None if cells.x is None else two([cells.x, cells.x]), params,
                    inertia={c: two([v, v]) for c, v in cells.inertia.items()},
                    speed_mps=None if cells.speed_mps is None else two([cells.speed_mps, cells.speed_mps]))
    return WheelForces(**{fl.name: 0.5 * (getattr(f, fl.name)[:n] + getattr(f, fl.name)[n:])
                          for fl in dataclasses.fields(WheelForces)})


def _spread_terms(hyp: Hypothesis, ctx: Context, cells: Cells, params: dict) -> dict | None:
    """channel -> (C,) what the cells' slip spread adds to the model at their mean slips
    (:func:`cell_forces` minus the model there) with ``params``; None for a table.  A fit takes
    them at its first optimum and moves it by one Gauss-Newton step for them
    (:func:`fit_hypothesis`); its fold refits hold them fixed (:func:`cross_validate`).  They
    change with the parameters by a fraction of themselves (a few hundredths of a noise sigma),
    and every evaluation then costs one kernel call at the mean slips instead of two."""
    if cells.slip_sd is None or not np.any(cells.slip_sd > 0):
        return None
    mean = hyp.predict(ctx, cells.load_n, cells.slip, cells.x, params, inertia=cells.inertia,
                       speed_mps=cells.speed_mps)
    spread = cell_forces(hyp, ctx, cells, params)
    return {c: np.asarray(getattr(spread, a), float) - np.asarray(getattr(mean, a), float) for c, a in CHANNELS.items()}


def predict_cells(fit: HypFit, ctx: Context, cells: Cells):
    """WheelForces of a fitted hypothesis on (other) cells, their slip spread included (:func:`cell_forces`)."""
    return cell_forces(fit.hypothesis, ctx, cells, fit.params)


def _equilibrate(A):
    """``(D A D, d)`` with ``D = diag(d)``, ``d = 1/sqrt(diag A)`` (1 where the diagonal is not
    positive): the parameters are in SI units of very different scale (c in Pa next to phi in
    rad: information 1e-3 against 1e7), so an eigen-decomposition or a relative pseudo-inverse
    cut-off of ``A`` itself loses the weakly determined directions to rounding; on the unit
    diagonal they keep their precision (Jacobi scaling, Golub & Van Loan, Matrix Computations,
    3rd ed., section 3.5.2)."""
    dg = np.diag(A)
    d = np.where(dg > 0, 1.0 / np.sqrt(np.where(dg > 0, dg, 1.0)), 1.0)
    return A * np.outer(d, d), d


def inv_psd(A: np.ndarray) -> np.ndarray:
    """Pseudo-inverse of a symmetric positive semi-definite (k, k) matrix (an information matrix:
    covariance = its inverse), computed on the Jacobi-equilibrated form ``D A D`` (unit diagonal,
    :func:`_equilibrate`) and scaled back, so that parameters of very different SI scale (c in
    Pa beside phi in rad) keep their weakly determined directions (Golub & Van Loan,
    *Matrix Computations* §3.5.2, equilibration).  Returns (k, k); all NaN where the
    decomposition fails (never raises)."""
    try:
        As, d = _equilibrate(A)
        return np.linalg.pinv(As, rcond=1e-12, hermitian=True) * np.outer(d, d)
    except np.linalg.LinAlgError:  # pragma: no cover
        return np.full(A.shape, np.nan)


def fit_hypothesis(hyp: Hypothesis, ctx: Context, cells: Cells, *, max_iter: int = FIT_MAX_ITER,
                   eps: float = 1e-6, terrain_uncertainty: bool = True, start: Mapping[str, float] | None = None,
                   spread: dict | None = None) -> HypFit:
    """Fit ``hyp`` to ``cells`` (module doc).  Returns :class:`HypFit`.

    ``terrain_uncertainty``: add the lab terrain's prior variance to the
    standard errors of a hypothesis that holds the terrain fixed.
    ``start``: parameter name -> value (SI) to start from instead of the defaults (the lab values);
    names the hypothesis does not have are ignored, values are clipped into the bounds.
    ``spread``: channel -> (C,) the cells' slip-spread terms to hold in a first fit (those of a fit
    elsewhere, ``HypFit.spread``), refreshed at its optimum for a second; None: fitted without them,
    then one step for them (module doc).
    Raises ValueError when the hypothesis cannot be evaluated at its start.
    """
    held = spread is not None
    prob = _Problem(hyp, ctx, cells, spread)
    if start:
        prob.x0 = prob.vector(start)
    k = len(prob.names)
    notes: list[str] = []
    if k == 0:
        spread = _spread_terms(hyp, ctx, cells, {})
        prob = _Problem(hyp, ctx, cells, spread)
        f = prob.forces(np.zeros(0))
        r = (prob.stack(f) + prob.spread - prob.y) / prob.sd
        if not np.all(np.isfinite(r)):
            raise ValueError(f"{hyp.title}: the model cannot be evaluated on these data")
        res, u = None, np.zeros(0)
        success, message = True, "no free parameters"
        chi2_d, chi2_p = float(r @ r), 0.0
        J = np.zeros((prob.m_data, 0))
    else:
        r0 = prob.fun(prob.x0)
        if not np.all(np.isfinite(r0)):
            raise ValueError(f"{hyp.title}: the model cannot be evaluated at its start values")
        res = prob.solve(max_iter=max_iter, eps=eps)
        if held and np.all(np.isfinite(res.x)):
            # the held terms are those of another point: once more with the terms of this optimum
            try:
                spread = _spread_terms(hyp, ctx, cells, prob.values(res.x))
                prob = _Problem(hyp, ctx, cells, spread)
                res = prob.solve(x0=res.x, max_iter=max_iter, eps=eps)
            except ValueError:
                pass
        elif np.all(np.isfinite(res.x)) and np.all(np.isfinite(res.jac)):
            try:
                spread = _spread_terms(hyp, ctx, cells, prob.values(res.x))
            except ValueError:
                spread = None
            if spread is not None:
                # the slip-spread terms move the optimum by a fraction of a standard error: one
                # Gauss-Newton step for what they change, with the first optimum's Jacobian (exact to
                # second order in that move), kept when it lowers the cost; the Jacobian, covariance
                # and bounds stay those of the first optimum
                prob = _Problem(hyp, ctx, cells, spread)
                x, r = res.x, prob.fun(res.x)
                if np.all(np.isfinite(r)):
                    change = r - res.weighted_residuals  # what the spread terms change in the residuals
                    x1 = np.clip(x - np.linalg.lstsq(res.jac, change, rcond=None)[0], prob.lo, prob.hi)
                    r1 = prob.fun(x1)
                    if np.all(np.isfinite(r1)) and float(r1 @ r1) < float(r @ r):
                        x, r = x1, r1
                    res = dataclasses.replace(res, x=x, params=dict(zip(res.names, map(float, x))), residuals=r,
                                              weighted_residuals=r, cost=0.5 * float(r @ r), nfev=res.nfev + 2)
        u = res.x
        r = res.weighted_residuals
        chi2_d = float(r[: prob.m_data] @ r[: prob.m_data])
        chi2_p = float(r[prob.m_data:] @ r[prob.m_data:])
        success, message = res.success, res.message
        J = res.jac
        f = prob.forces(u)
    m = prob.m_data
    dof = max(m - k, 1)
    c_hat = max(1.0, chi2_d / dof)
    values = prob.values(u)
    # covariance of the penalised estimate in solver variables, data rows scaled by c_hat
    se_fit = {}
    se_tot = {}
    cov_u = np.zeros((k, k))
    cov_si = np.zeros((k, k))
    cond = float("nan")
    at_bound = tuple(res.at_bound) if res is not None else ()
    prior_info = {}
    if k:
        Jd, Jp = J[:m], J[m:]
        A = Jd.T @ Jd / c_hat + Jp.T @ Jp
        cov_u = inv_psd(A)
        cn = np.linalg.norm(J, axis=0)
        if np.all(cn > 0):
            sv = np.linalg.svd(J / cn, compute_uv=False)
            cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
        else:
            cond = float("inf")
        g = np.ones(k)
        g[prob.log] = np.exp(u[prob.log])  # delta method back to SI
        cov = cov_u * np.outer(g, g)
        cov_si = cov
        var_extra = np.zeros(k)
        if terrain_uncertainty and not (hyp.terrain_block or ctx.fit_terrain):
            var_extra = _lab_terrain_variance(prob, u, Jd, ctx) * g**2
            prior_info["lab_terrain_variance"] = dict(zip(prob.names, map(float, var_extra)))
        d = np.diag(cov)
        for i, nme in enumerate(prob.names):
            se_fit[nme] = float(math.sqrt(d[i])) if np.isfinite(d[i]) and d[i] >= 0 else float("nan")
            v = d[i] + var_extra[i]
            se_tot[nme] = float(math.sqrt(v)) if np.isfinite(v) and v >= 0 else float("nan")
    info = (J[:m].T @ J[:m], J[m:].T @ J[m:]) if k else (np.zeros((0, 0)), np.zeros((0, 0)))
    log_ev = _laplace(chi2_d, chi2_p, info, prob.params, m, c_hat)
    bic = chi2_d / c_hat + chi2_p + k * math.log(max(m, 1))
    chans = {c: np.full(cells.n, np.nan) for c in prob.chans}
    for c in prob.chans:
        chans[c] = np.asarray(getattr(f, CHANNELS[c]), float) + (0.0 if spread is None else spread[c])
    terrain = ctx.terrain
    if hyp.terrain_block or ctx.fit_terrain:
        from .hypotheses import apply_terrain

        try:
            terrain = apply_terrain(ctx.terrain, values)
        except ValueError:
            pass
    units = {q.name: q.unit for q in prob.params}
    prior = {q.name: q.prior for q in prob.params if q.prior}
    if prior_info:
        notes.append("standard errors include the lab terrain's prior uncertainty")
    return HypFit(
        name=hyp.name, effect=hyp.effect, model=hyp.core, hypothesis=hyp, terrain=terrain, params=values,
        stderr=se_tot, stderr_fit=se_fit, units=units, at_bound=at_bound, prior=prior, result=res,
        cell_pred=chans, cell_load_model=np.asarray(f.load_model_n, float), cell_sinkage=np.asarray(f.sinkage_m, float),
        chi2_data=chi2_d, chi2_prior=chi2_p, n_data=m, k=k, dof=dof, log_evidence=float(log_ev), bic=float(bic),
        success=bool(success), message=message, notes=tuple(notes), n_eff=float(cells.n), condition_number=cond,
        u=np.asarray(u, float), info=info, hparams=tuple(prob.params), cov=cov_si, ctx=ctx, spread=spread,
    )


def _logdet_psd(A) -> float:
    """log det of a symmetric positive semi-definite (k, k) matrix over its non-null
    eigen-directions, taken on its equilibrated form (:func:`_equilibrate`) and scaled back."""
    if A.size == 0:
        return 0.0
    As, d = _equilibrate(A)
    w = np.linalg.eigvalsh(As)
    keep = w > 1e-12 * max(float(w.max()), 1e-300)
    return float(np.sum(np.log(w[keep])) - 2.0 * np.sum(np.log(d)))


def _laplace(chi2_d, chi2_p, info, params, m, c_hat) -> float:
    """Laplace log evidence (module doc): ``-chi2/2 + 1/2 [log det A_prior - log det A_post]``
    with information matrices A.  ``A_post = I_data / c_hat + I_prior``; the prior information is
    ``1/sd^2`` for parameters with a lab prior and, for the others, the unit-information prior
    ``I_data[free, free] / (c_hat m)`` (Kass & Wasserman 1995), which gives their BIC penalty
    ``k/2 log m`` exactly, correlated or not."""
    k = len(params)
    val = -0.5 * (chi2_d / c_hat + chi2_p)
    if k == 0:
        return float(val)
    A_post = info[0] / c_hat + info[1]
    pri = np.array([q.prior is not None for q in params], bool)
    ld_prior = float(sum(-2 * math.log(q.prior[1]) for q in params if q.prior))
    if (~pri).any():
        sub = info[0][np.ix_(~pri, ~pri)] / (c_hat * max(m, 1))
        ld_prior += _logdet_psd(sub)
    return float(val + 0.5 * (ld_prior - _logdet_psd(A_post)))



def _lab_terrain_variance(prob: _Problem, u, Jd, ctx: Context) -> np.ndarray:
    """Variance of the fitted parameters (solver variables) caused by the lab terrain's
    uncertainty: S diag(sd_t^2) S^T with S = -(J_th^T J_th)^-1 J_th^T J_t (implicit function)."""
    from .hypotheses import lab_prior

    pr = ctx.prior or lab_prior(ctx.terrain, ctx.wheel)
    k = len(u)
    if k == 0 or prob.m_data == 0:
        return np.zeros(k)
    base = prob.stack(prob.forces(u))
    cols, sds = [], []
    t0 = ctx.terrain
    kq = t0.k_eq(ctx.wheel.width)
    for name, (mu, sd, is_log) in pr.items():
        h = 1e-4 if is_log else 1e-4 * max(abs(getattr(t0, name)) if name != "k_eq" else kq, sd)
        vals = {"k_eq": kq, "n": t0.n, "c": t0.c, "phi": t0.phi, "K": t0.K}
        if is_log:
            vals[name] = vals[name] * math.exp(h)
        else:
            vals[name] = vals[name] + h
        from .hypotheses import apply_terrain

        try:
            ctx2 = dataclasses.replace(ctx, terrain=apply_terrain(t0, vals), fit_terrain=False)
            f = prob.hyp.predict(ctx2, prob.cells.load_n, prob.cells.slip, prob.cells.x, prob.values(u),
                                 inertia=prob.cells.inertia, speed_mps=prob.cells.speed_mps)
            col = (prob.stack(f) - base) / prob.sd / h
        except ValueError:
            continue
        if np.all(np.isfinite(col)):
            cols.append(col)
            sds.append(sd)
    if not cols:
        return np.zeros(k)
    Jt = np.column_stack(cols)
    S = -inv_psd(Jd.T @ Jd) @ (Jd.T @ Jt)
    return np.sum(S**2 * np.square(sds)[None, :], axis=1)


def lower_at(fit: HypFit, ctx: Context, cells: Cells, start: Mapping[str, float]) -> bool:
    """True when ``fit``'s penalised objective (data and lab prior, with its slip-spread terms) is lower
    at ``start`` (its parameters taken from ``start`` where named) than at its optimum by more than
    :func:`meaningful`: the fit stopped in a local optimum, and a refit from ``start``
    (:func:`fit_hypothesis`) may find a better one.  ``start``: name -> value (SI), scalars.  False for
    a fit without parameters or one whose objective cannot be evaluated at ``start`` (outside the model's
    domain); raises nothing of its own.  Source: a restart test for non-convex least squares (Nocedal &
    Wright 2006, ch. 10)."""
    if not fit.k or fit.result is None:
        return False
    prob = _Problem(fit.hypothesis, ctx, cells, fit.spread)
    r = prob.fun(prob.vector(start))
    cost = float(r @ r) if np.all(np.isfinite(r)) else np.inf
    return fit.chi2_data + fit.chi2_prior - cost > meaningful(fit)


def meaningful(fit: HypFit) -> float:
    """The least fall of ``fit``'s penalised chi-square that is more than numerical noise or an
    overdispersed model's scatter: one unit, or the reduced chi-square where that is larger (a scalar,
    chi-square units; :attr:`HypFit.c_hat`).  Source: quasi-likelihood overdispersion, McCullagh & Nelder 1989 §9.2."""
    return fit.c_hat


def cross_validate(fit: HypFit, ctx: Context, cells: Cells, group_kind: str = "") -> HypFit:
    """Leave-one-fold-out refits (folds: :func:`cv_folds` of ``cells.group``), held-out cell predictions.

    Each fold is refitted from the full-data optimum (at most ``CV_MAX_ITER``
    Gauss-Newton iterations, the first with the full fit's Jacobian rows of
    the training cells, ``CV_HALVINGS`` halvings of a trial outside the model's domain, no covariance at
    the end) without the fold's cells;
    its cells are then predicted.  Sets ``fit.cv`` (see :class:`HypFit`) and raises the
    standard errors to the jackknife over folds where that is larger (with
    >= 5 folds).  A fold whose refit fails is predicted with the full fit and
    counted in ``failed_folds``.  Returns ``fit`` (modified in place).
    """
    fold = cv_folds(cells.group)
    groups = np.unique(fold)
    held = {c: np.full(cells.n, np.nan) for c in fit.cell_pred}
    fold_params = []
    failed = 0
    full, J_full = None, None
    if fit.k and fit.result is not None:  # the full fit's Jacobian, if the fit is of these cells and ctx
        full = _Problem(fit.hypothesis, ctx, cells, fit.spread)
        r = full.fun(fit.u)
        if fit.result.jac.shape == (r.size, fit.k) and np.allclose(r, fit.result.weighted_residuals, atol=1e-9):
            J_full = fit.result.jac
    spread = fit.spread
    for g in groups:
        test = fold == g
        if fit.k == 0 or groups.size < 2:
            for c in held:
                held[c][test] = fit.cell_pred[c][test]
            continue
        train = cells.subset(~test)
        prob = _Problem(fit.hypothesis, ctx, train, None if spread is None else {c: v[~test] for c, v in spread.items()})
        # the refit starts at the full-data optimum, where the Jacobian is the full fit's, on the
        # training cells' rows (and the prior rows)
        jac0 = None if J_full is None else np.vstack([J_full[:full.m_data][full.data_rows(~test)],
                                                      J_full[full.m_data:]])
        try:
            res = prob.solve(x0=fit.u, max_iter=CV_MAX_ITER, eps=1e-4, jac0=jac0, covariance=False, halvings=CV_HALVINGS)
            u = res.x if np.all(np.isfinite(res.x)) and np.isfinite(res.cost) else fit.u
            if u is fit.u:
                failed += 1
            vals = prob.values(u)
            f = prob.forces(u, cells.subset(test))
        except (ValueError, FloatingPointError, np.linalg.LinAlgError):
            failed += 1
            vals = dict(fit.params)
            for c in held:
                held[c][test] = fit.cell_pred[c][test]
            fold_params.append(vals)
            continue
        fold_params.append(vals)
        for c in held:
            held[c][test] = np.asarray(getattr(f, CHANNELS[c]), float) + (0.0 if spread is None else spread[c][test])
    cv_r0 = {}
    for c, y in cells.channels.items():
        e = y - held[c]
        ok = np.isfinite(e)
        cv_r0[c] = float(np.sqrt(np.mean(e[ok] ** 2))) if ok.any() else None
    ws = [((y - held[c]) / np.sqrt(cells.var[c])) for c, y in cells.channels.items()]
    wcat = np.concatenate([w[np.isfinite(w)] for w in ws]) if ws else np.zeros(0)
    fit.cv = {
        "cv_score": float(np.sqrt(np.mean(wcat**2))) if wcat.size else None,
        "held_cells": held,
        "fold": fold,
        "fold_params": fold_params,
        "cv_R0": cv_r0,
        "cv_R0_n": cv_r0.get("drawbar_pull_n"),
        "n_groups": int(groups.size),
        "group_kind": group_kind,
        "failed_folds": failed,
        "method": f"refit per fold (warm start, <= {CV_MAX_ITER} iterations), predicted on the held-out cells",
    }
    if fit.k and len(fold_params) >= 5:
        P = np.array([[fp[n] for n in fit.params] for fp in fold_params])
        G = P.shape[0]
        jk = np.sqrt((G - 1) / G * np.sum((P - P.mean(axis=0)) ** 2, axis=0))
        fit.cv["stderr_jackknife"] = dict(zip(fit.params, map(float, jk)))
        fit.stderr = {n: (max(v, j) if np.isfinite(v) else v) for (n, v), j in zip(fit.stderr.items(), jk)}
    return fit


def sample_predictions(fit: HypFit, ctx: Context, data: FitData) -> dict:
    """channel -> (N,) predictions of a fitted hypothesis on the used samples (for the
    paper's metrics and the report's figures); NaN arrays when it cannot be evaluated."""
    x = data.cells.x_of(data.x_raw) if data.cells is not None else None
    try:
        f = fit.hypothesis.predict(ctx, data.load_n, data.slip, x, fit.params, inertia=data.inertia,
                                   speed_mps=data.speed_mps)
        return {c: np.asarray(getattr(f, CHANNELS[c]), float) for c in CHANNELS}
    except (ValueError, FloatingPointError):
        return {c: np.full(data.n, np.nan) for c in CHANNELS}
