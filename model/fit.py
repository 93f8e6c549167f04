"""Compatibility layer: the fitting API in one import.

The code lives in:

* :mod:`wheelsoil.model.solver` — generic bounded Gauss–Newton / LM (:func:`gauss_newton`, :class:`FitResult`);
* :mod:`wheelsoil.model.data` — data selection, cells, model-free noise (:func:`prepare_data`, :class:`FitData`);
* :mod:`wheelsoil.model.hypotheses` — the registry of causes (:data:`HYPOTHESES`);
* :mod:`wheelsoil.model.crossval` — fitting a hypothesis, cross-validation (:func:`fit_hypothesis`).

:func:`fit_model` fits one model by name, optionally with terrain parameters.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .crossval import FIT_MAX_ITER, HypFit, cross_validate as _cv_cells, fit_hypothesis, sample_predictions
from .data import CHANNELS, Cells, FitData, cell_noise, estimate_noise, make_cells, prepare_data, synthetic_data
from .hypotheses import HYPOTHESES, Context, get_hypothesis, lab_prior
from .solver import FitResult, gauss_newton

__all__ = [
    "FitResult", "gauss_newton", "FitData", "Cells", "prepare_data", "estimate_noise", "cell_noise", "make_cells",
    "synthetic_data", "fit_model", "cross_validate", "TERRAIN_PARAMS", "CANDIDATES", "CHANNELS", "HypFit",
]

#: Terrain parameters a fit can re-fit: name -> (unit, doc).  ``k_eq`` = kc/b + kphi (one
#: wheel width cannot separate kc and kphi).
TERRAIN_PARAMS: dict[str, tuple[str, str]] = {
    "k_eq": ("N/m^(n+2)", "combined pressure-sinkage modulus kc/b + kphi (Eq. 2)"),
    "n": ("-", "sinkage exponent (Eq. 2)"),
    "c": ("Pa", "cohesion (Eq. 4)"),
    "phi": ("rad", "internal friction angle (Eq. 4)"),
    "K": ("m", "shear deformation modulus (Eq. 4)"),
}

#: Names accepted as candidates (the hypotheses, plus ``terrain_mismatch`` for ``terrain``).
CANDIDATES: dict[str, str] = {**{k: h.effect for k, h in HYPOTHESES.items()}, "terrain_mismatch": "terrain_mismatch"}


def _metrics(measured, predicted) -> dict:
    """Paper §1.3 metrics on finite pairs: M0 (%), R0, R^2 (None when undefined)."""
    from .metrics import m0_pct, r0, r2

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


def fit_model(data, terrain, wheel, model: str = "lyasko", *, slip_min: float = 0.1,
              terrain_params: Sequence[str] = (), sinkage: str = "eq10", max_iter: int = FIT_MAX_ITER,
              cv: bool = True) -> HypFit:
    """Fit one hypothesis by name to measured data (cell means, penalised Gauss–Newton).

    Parameters
    ----------
    data : pandas DataFrame (:func:`prepare_data`) or :class:`FitData`.
    terrain, wheel : lab terrain (prior centre) and wheel.
    model : a hypothesis name (``wong``, ``vasilev``, ``lyasko``, ``ding``, ``terrain``
        (``terrain_mismatch``), ``vasilev+terrain``, ``lyasko+terrain``, ``ding+terrain``, ``wong_reece``,
        ``drift_linear``
        and the stand-ins of :data:`~wheelsoil.model.hypotheses.HYPOTHESES`; ``drift_step`` needs the
        change point the diagnosis finds).
    terrain_params : non-empty -> the terrain (k_eq, n, c, phi, K) is fitted too, against the
        terrain's values as priors widened for a library entry (``--fit-terrain``); every terrain
        parameter is fitted (the prior keeps unidentified ones at their library value).
    sinkage : ``eq10`` | ``balance``.
    cv : also cross-validate (sets ``fit.cv``, jackknife standard errors).

    Returns :class:`~wheelsoil.model.crossval.HypFit` with ``predictions`` and ``metrics`` on the samples.
    Raises ValueError for an unknown model or terrain parameter, a hypothesis not available on
    these data (``drift_step``; a drift on a table) and bad data.
    """
    from .hypotheses import LIBRARY_PRIOR_WIDEN

    for p in terrain_params:
        if p not in TERRAIN_PARAMS:
            raise ValueError(f"unknown terrain parameter {p!r}; choose from {', '.join(TERRAIN_PARAMS)}")
    if not isinstance(data, FitData):
        data = prepare_data(data, slip_min=slip_min)
    fit_terrain = bool(terrain_params)
    ctx = Context(terrain, wheel, sinkage, lab_prior(terrain, wheel, widen=LIBRARY_PRIOR_WIDEN if fit_terrain else 1.0),
                  fit_terrain, w_static=data.load_static_n)
    h = get_hypothesis(model)
    why = h.available(ctx, data.cells.x is not None)
    if why:
        raise ValueError(f"{h.title} ({h.name}) cannot be fitted on its own here: {why}"
                         + (" (the diagnosis locates the change point; use wheelsoil.model.diagnose)"
                            if h.name == "drift_step" else ""))
    f = fit_hypothesis(h, ctx, data.cells, max_iter=max_iter)
    if cv:
        f = _cv_cells(f, ctx, data.cells, data.group_kind)
    f.predictions = sample_predictions(f, ctx, data)
    f.metrics = _metrics(data.channels["drawbar_pull_n"], f.predictions["drawbar_pull_n"])
    f.channel_metrics = {c: {"R0": _metrics(y, f.predictions[c])["R0_n"], "R2": _metrics(y, f.predictions[c])["R2"]}
                         for c, y in data.channels.items()}
    return f


def cross_validate(data: FitData, fit: HypFit, terrain, wheel, *, sinkage: str = "eq10", **_ignored) -> HypFit:
    """Cross-validate a fitted model on ``data``'s cells (see :func:`wheelsoil.model.crossval.cross_validate`)."""
    ctx = Context(terrain, wheel, sinkage, lab_prior(terrain, wheel), False, w_static=data.load_static_n)
    return _cv_cells(fit, ctx, data.cells, data.group_kind)
