"""Step 1 of the diagnosis (:mod:`wheelsoil.model.diagnosis`): is Wong's error systematic, and is it relevant?

The residuals of a model on the cells (:mod:`wheelsoil.model.data`), each divided by the channel's model-free
cell noise, are tested against slip, load and distance along the run (:func:`_structure_cells`): F-tests of a
polynomial, binned means, a change point and a trend (:func:`_structure_1d`), over the independent units (the
accelerate cycles of a time series, the rows of a table), with Holm's step-down over all tests at family level
``ALPHA`` (:func:`_holm`).  A structure is *relevant* when its RMS is at least ``MIN_EFFECT`` cell-noise sigmas
and ``MIN_REL`` of the channel's magnitude (:func:`_relevant`).  Also here: the rising-against-falling-slip
test no static hypothesis can explain (:func:`_hysteresis_test`), the change point along the run that the step
drift is fixed at (:func:`_change_point`), the bounds on what a run cannot exclude (:func:`_loose`), and the
words for all of them.  Sources: Seber & Wild, Nonlinear Regression, §5.3 (nested-model F-tests); Holm 1979,
Scand. J. Statist. 6:65; Schuirmann 1987 (equivalence bounds).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from .data import FitData

ALPHA = 0.01  #: family-wise significance level (structure tests, Holm; "improves" per channel)
MIN_EFFECT = 1.0  #: relevant structure: RMS of the systematic part >= this many cell-noise sigmas
MIN_REL = 0.03  #: ... and >= this fraction of the RMS magnitude of the channel's cell means
#: (a margin, not a test: on runs with no effect our processing leaves significant systematic
#: errors of 0.1-0.3 % of the torque (inertia compensation, filters, time sync); another
#: transducer, filter chain or data source leaves more, and an error of a few per cent cannot be
#: told from the instrument's calibration; a structure below it is reported, not attributed)

CHANNEL_TITLES = {"drawbar_pull_n": "drawbar pull", "torque_nm": "torque", "sinkage_m": "sinkage"}


def _structure_1d(s_u: np.ndarray, e_u: np.ndarray, degree: int = 2, step: bool = False,
                  slope: bool = False) -> dict:
    """F-tests of unit means ``e_u`` (in noise sigmas) against a coordinate ``s_u``.

    A polynomial of ``degree`` against zero (no systematic error), a one-way
    ANOVA of up to 8 quantile bins against zero, with ``step`` a
    change point (:func:`_step_test`: two levels, split between any two
    neighbouring units, Bonferroni over the splits) and with ``slope`` a
    trend (the slope of a straight line, its level free: one numerator
    degree of freedom where the polynomial spends ``degree + 1``; the sinkage
    channel's pre-stated alternative, Eqs. 11-13 all growing with slip);
    ``p`` is their Bonferroni combination.  The residual scatter of the unit means about the
    fitted shape is the noise reference (the test does not trust the sigma).
    Returns dict ``p``, ``p_poly``, ``p_bins``, ``p_step``, ``p_slope``, ``F``, ``units``,
    ``degree``, ``effect`` (RMS of the fitted shape), ``shape_p``, ``coef``.
    Source: nested-model F-test (Seber & Wild, Nonlinear Regression, §5.3).
    """
    ok = np.isfinite(e_u) & np.isfinite(s_u)
    s_u, e_u = s_u[ok], e_u[ok]
    U = e_u.size
    d = int(min(degree, U - 3))
    out = {"p": float("nan"), "F": float("nan"), "units": int(U), "degree": d,
           "effect": float("nan"), "shape_p": float("nan"), "coef": [], "p_poly": float("nan"), "p_bins": float("nan")}
    if U < 3 or d < 0:
        out["effect"] = float(np.sqrt(np.mean(e_u**2))) if U else float("nan")
        return out
    x = (s_u - s_u.mean()) / (s_u.std() or 1.0)
    if np.unique(np.round(x, 9)).size <= d:
        d = max(0, np.unique(np.round(x, 9)).size - 1)
    V = np.vander(x, d + 1)
    coef, *_ = np.linalg.lstsq(V, e_u, rcond=None)
    fitted = V @ coef
    rss1 = float(np.sum((e_u - fitted) ** 2))
    rss0 = float(np.sum(e_u**2))
    rssc = float(np.sum((e_u - e_u.mean()) ** 2))
    df1, df2 = d + 1, U - d - 1
    s2 = rss1 / df2 if df2 > 0 else float("nan")
    if s2 > 0 and np.isfinite(s2):
        F = ((rss0 - rss1) / df1) / s2
        p = float(stats.f.sf(F, df1, df2))
        ps = float(stats.f.sf(((rssc - rss1) / max(d, 1)) / s2, d, df2)) if d > 0 else float("nan")
    elif rss0 > 0:
        F, p, ps = float("inf"), 0.0, float("nan")
    else:
        F, p, ps = 0.0, 1.0, float("nan")
    nb = int(min(8, U // 3))
    p_bins = float("nan")
    if nb >= 2:
        order = np.argsort(s_u, kind="stable")
        lab = np.empty(U, int)
        for j, idx in enumerate(np.array_split(order, nb)):
            lab[idx] = j
        cnt = np.bincount(lab, minlength=nb).astype(float)
        means = np.bincount(lab, weights=e_u, minlength=nb) / cnt
        within = float(np.sum((e_u - means[lab]) ** 2))
        dfw = U - nb
        if dfw > 0 and within > 0:
            p_bins = float(stats.f.sf((float(np.sum(cnt * means**2)) / nb) / (within / dfw), nb, dfw))
            fitted_b = means[lab]
            if p_bins < p and np.mean(fitted_b**2) > np.mean(fitted**2):
                fitted = fitted_b
    p_step = float("nan")
    if step:
        p_step, fitted_s, _ = _step_test(s_u, e_u)
        if np.isfinite(p_step) and p_step < min(p, p_bins if np.isfinite(p_bins) else 1.0) and \
                np.mean(fitted_s**2) > np.mean(fitted**2):
            fitted = fitted_s
    p_slope = float("nan")
    if slope and U >= 4 and np.unique(np.round(x, 9)).size >= 2:
        V1 = np.vander(x, 2)
        c1, *_ = np.linalg.lstsq(V1, e_u, rcond=None)
        fitted_l = V1 @ c1
        rss_l = float(np.sum((e_u - fitted_l) ** 2))
        if rss_l > 0:
            p_slope = float(stats.f.sf((rssc - rss_l) / (rss_l / (U - 2)), 1, U - 2))
            if p_slope < min(q for q in (p, p_bins, p_step, 1.0) if np.isfinite(q)) and \
                    np.mean(fitted_l**2) > np.mean(fitted**2):
                fitted = fitted_l
    ps_all = [q for q in (p, p_bins, p_step, p_slope) if np.isfinite(q)]
    p_comb = min(1.0, len(ps_all) * min(ps_all)) if ps_all else p
    out.update(p=p_comb, p_poly=p, p_bins=p_bins, p_step=p_step, p_slope=p_slope, F=float(F), degree=d,
               effect=float(np.sqrt(np.mean(fitted**2))), shape_p=ps, coef=[float(c) for c in coef],
               rms_upper=_rms_upper(float(F), df1, df2, s2, U))
    return out


def _rms_upper(F: float, df1: int, df2: int, s2: float, U: int, level: float = 0.95) -> float:
    """Upper ``level`` confidence bound on the RMS over the ``U`` units of a systematic error of the
    polynomial's form (in the units' sigma), from its F-test: the F statistic is noncentral F with
    noncentrality lambda = sum(mu^2)/sigma_u^2, and the bound is sqrt(lambda_U s2 / U), lambda_U the
    largest lambda with P(F <= F_obs) >= 1 - ``level`` (test inversion; equivalence testing,
    Wellek, Testing Statistical Hypotheses of Equivalence, 2nd ed. 2010, ch. 7).  NaN when the
    test could not be made; inf for a perfect fit (s2 = 0)."""
    if not (df1 > 0 and df2 > 0 and np.isfinite(F) and np.isfinite(s2) and U > 0):
        return float("inf") if F == float("inf") else float("nan")
    alpha = 1.0 - level
    if stats.f.cdf(F, df1, df2) <= alpha:  # smaller than the null expects: no error is the bound
        return 0.0
    from scipy.optimize import brentq

    hi = max(1.0, F * df1)
    while stats.ncf.cdf(F, df1, df2, hi) > alpha and hi < 1e12:
        hi *= 2.0
    try:
        lam = brentq(lambda nc: stats.ncf.cdf(F, df1, df2, nc) - alpha, 0.0, hi, xtol=1e-6, rtol=1e-6)
    except ValueError:  # the noncentral F's cdf did not bracket the level: no bound
        return float("nan")
    return float(math.sqrt(lam * s2 / U))


def _step_test(s_u: np.ndarray, e_u: np.ndarray, level: bool = False) -> tuple[float, np.ndarray, tuple]:
    """Change-point F-test of unit means ``e_u`` (U,) ordered by ``s_u`` (U,): two levels (before
    and after a split between neighbouring units, at least 2 units a side) against zero (any
    structure: a step or a level), or with ``level`` against one common level (a change: the
    level alone is no step), the best split, its p-value Bonferroni-corrected over the U - 3
    splits (conservative for a maximum of correlated statistics).  Another patch of ground from
    some point on is a step, which a low-order polynomial and fixed bins smear into their noise
    reference.
    Returns ``(p, fitted (U,), (s_before, s_after))``: the two coordinates the best split
    lies between (p NaN, bounds NaN for fewer than 5 units).
    Source: change-point detection by maximal F over splits (Hawkins 1977, JASA 72:180;
    Bonferroni bound as in Worsley 1979, JASA 74:365)."""
    U = e_u.size
    if U < 5:
        return float("nan"), np.zeros_like(e_u), (float("nan"), float("nan"))
    order = np.argsort(s_u, kind="stable")
    e = e_u[order]
    rss0 = float(np.sum((e - e.mean()) ** 2) if level else np.sum(e**2))
    df1 = 1 if level else 2
    best_f, best_k = -1.0, None
    for k in range(2, U - 1):
        a, b = e[:k], e[k:]
        rss1 = float(np.sum((a - a.mean()) ** 2) + np.sum((b - b.mean()) ** 2))
        if rss1 <= 0:  # an exact split: infinitely significant, unless there is nothing to split
            best_f, best_k = (float("inf") if rss0 > 0 else 0.0), k
            break
        f = ((rss0 - rss1) / df1) / (rss1 / (U - 2))
        if f > best_f:
            best_f, best_k = f, k
    fitted = np.empty(U)
    fitted[order[:best_k]] = e[:best_k].mean()
    fitted[order[best_k:]] = e[best_k:].mean()
    p = 0.0 if not np.isfinite(best_f) else float(stats.f.sf(best_f, df1, U - 2))
    s = s_u[order]
    return min(1.0, (U - 3) * p), fitted, (float(s[best_k - 1]), float(s[best_k]))


def _unit_means(data: FitData, values: np.ndarray):
    """Aggregate (N,) values over the cells: (slip (U,), value (U,), load (U,), t (U,), count (U,))."""
    units = data.cells.index if data.cells is not None and data.cells.index.size == data.n else data.units
    ok = np.isfinite(values) & (units >= 0)
    u = units[ok]
    uniq, inv = np.unique(u, return_inverse=True)
    cnt = np.bincount(inv).astype(float)

    def mean(x):
        return np.bincount(inv, weights=x[ok]) / cnt

    t = mean(data.t_s) if data.t_s is not None else mean(np.arange(data.n, dtype=float))
    return mean(data.slip), mean(values), mean(data.load_n), t, cnt


def structure_test(data: FitData, resid_w: np.ndarray, degree: int = 2) -> dict:
    """F-tests for systematic structure vs slip of (N,) weighted sample residuals ``resid_w``
    ((measured - model)/sigma), on the means over ``data``'s independent units (cells).
    Returns the dict of :func:`_structure_1d`."""
    s_u, e_u, _, _, _ = _unit_means(data, resid_w)
    return _structure_1d(s_u, e_u, degree)


def _slope_test(x, y, covariate=None) -> dict:
    """OLS slope of y on x (optionally with a covariate): slope, stderr, two-sided p, one-sided p(>0)."""
    ok = np.isfinite(x) & np.isfinite(y)
    cols = [np.ones(ok.sum()), x[ok]]
    if covariate is not None and np.std(covariate[ok]) > 1e-9 * max(1.0, np.max(np.abs(covariate[ok]))):
        cols.append(covariate[ok])
    A = np.column_stack(cols)
    n, k = A.shape
    if n <= k or np.std(x[ok]) == 0:
        return {"slope": float("nan"), "stderr": float("nan"), "p": float("nan"), "p_positive": float("nan"), "units": int(n)}
    coef, *_ = np.linalg.lstsq(A, y[ok], rcond=None)
    res = y[ok] - A @ coef
    s2 = float(res @ res) / (n - k)
    cov = s2 * np.linalg.pinv(A.T @ A)
    se = float(np.sqrt(max(cov[1, 1], 0.0)))
    if se > 0:
        tval = coef[1] / se
        p = float(2 * stats.t.sf(abs(tval), n - k))
        pp = float(stats.t.sf(tval, n - k))
    else:
        p = 0.0 if coef[1] != 0 else 1.0
        pp = 0.0 if coef[1] > 0 else 1.0
    return {"slope": float(coef[1]), "stderr": se, "p": p, "p_positive": pp, "units": int(n)}


def binned_residuals(data: FitData, resid: np.ndarray, n_bins: int = 10, level: float = 0.95) -> dict:
    """Binned means of (N,) sample residuals vs slip with confidence intervals (from the cell
    means, t-distribution).  Returns dict of lists ``slip``, ``mean``, ``lo``, ``hi``, ``units``."""
    s_u, e_u, _, _, _ = _unit_means(data, resid)
    U = e_u.size
    nb = int(max(1, min(n_bins, U // 3)))
    order = np.argsort(s_u, kind="stable")
    out = {"slip": [], "mean": [], "lo": [], "hi": [], "units": []}
    for idx in np.array_split(order, nb):
        if idx.size == 0:
            continue
        m = float(np.mean(e_u[idx]))
        half = (float(stats.t.ppf(0.5 + level / 2, idx.size - 1) * np.std(e_u[idx], ddof=1) / math.sqrt(idx.size))
                if idx.size > 1 else float("nan"))
        out["slip"].append(float(np.mean(s_u[idx])))
        out["mean"].append(m)
        out["lo"].append(m - half)
        out["hi"].append(m + half)
        out["units"].append(int(idx.size))
    return out


def _level_test(gm: np.ndarray) -> dict:
    """One-sample t-test of unit means ``gm`` (in noise sigmas) against zero; ``upper`` is the
    upper end of the two-sided 95 % t confidence interval of ``|mean|`` (how large a level
    error the units cannot exclude: equivalence testing, Schuirmann 1987)."""
    gm = gm[np.isfinite(gm)]
    G = gm.size
    out = {"p": float("nan"), "effect": float("nan"), "units": int(G)}
    if G < 3:
        return out
    m, sd = float(np.mean(gm)), float(np.std(gm, ddof=1))
    p = float(2 * stats.t.sf(abs(m) / (sd / math.sqrt(G)), G - 1)) if sd > 0 else (0.0 if m != 0 else 1.0)
    out.update(p=p, effect=abs(m), mean=m, upper=abs(m) + float(stats.t.ppf(0.975, G - 1)) * sd / math.sqrt(G))
    return out


def _magnitude(y: np.ndarray) -> float:
    """RMS of a channel's cell means ``y`` (C,), NaN ignored: what ``MIN_REL`` is a fraction of."""
    return float(np.sqrt(np.nanmean(y**2))) if np.isfinite(y).any() else float("nan")


def _structure_cells(data: FitData, pred: dict) -> dict:
    """Structure tests of cell residuals of one model, in cell-noise sigmas:
    ``{"<channel>": vs slip, "<channel>@load", "<channel>@x"}``.

    Tables: every row is an independent unit (:func:`_structure_1d` on the rows).
    Time series: the cells of one accelerate cycle share the cycle's soil and
    speed, so the cycle is the independent unit for anything constant within it.
    The level (mean error) is tested with a t-test over the cycle means; the
    shape against slip and against load on the residuals centred within each
    cycle; the dependence on distance/time (``@x``) on the cycle means against
    the cycle's mean x.  The channel's ``p`` combines level and shape
    (Bonferroni x2), its ``effect`` is the RMS of both parts.
    """
    cells = data.cells
    out = {}
    grp = cells.group
    n_g = np.unique(grp).size
    by_cycle = data.kind != "table" and n_g >= 3
    for c, y in cells.channels.items():
        e = (y - pred[c]) / cells.sigma[c]
        size = _magnitude(y)
        tests = {}
        if not by_cycle:
            tests[c] = _structure_1d(cells.slip, e, slope=c == "sinkage_m")
            if c == "drawbar_pull_n" and np.std(cells.load_n) > 0.01 * abs(np.mean(cells.load_n)):
                tests[c + "@load"] = _structure_1d(cells.load_n, e, degree=1)
        else:
            ok = np.isfinite(e)
            ug, inv = np.unique(grp[ok], return_inverse=True)
            cnt = np.bincount(inv).astype(float)
            gm = np.bincount(inv, weights=e[ok]) / cnt
            ec = e[ok] - gm[inv]
            lvl = _level_test(gm)
            shp = _structure_1d(cells.slip[ok], ec, slope=c == "sinkage_m")
            p = min(1.0, 2 * min(lvl["p"], shp["p"])) if np.isfinite(lvl["p"]) and np.isfinite(shp["p"]) else shp["p"]
            t = dict(shp)
            t.update(p=p, p_level=lvl["p"], p_shape=shp["p"], level_sigma=lvl.get("mean", float("nan")),
                     level_upper_sigma=lvl.get("upper", float("nan")),
                     effect=float(math.sqrt(np.nan_to_num(lvl["effect"]) ** 2 + np.nan_to_num(shp["effect"]) ** 2)),
                     units=int(ok.sum()), cycles=int(ug.size))
            tests[c] = t
            if cells.x is not None:
                xg = np.bincount(inv, weights=cells.x[ok]) / cnt
                tests[c + "@x"] = _structure_1d(xg, gm, step=True)
            if c == "drawbar_pull_n" and np.std(cells.load_n) > 0.01 * abs(np.mean(cells.load_n)):
                tests[c + "@load"] = _structure_1d(cells.load_n[ok], ec, degree=1)
        for k, t in tests.items():
            t["effect_abs"] = t["effect"] * cells.sigma[c]
            t["effect_rel"] = t["effect_abs"] / size if size > 0 else float("inf")
            if "level_upper_sigma" in t:
                t["level_upper_abs"] = t["level_upper_sigma"] * cells.sigma[c]
                t["level_upper_rel"] = t["level_upper_abs"] / size if size > 0 else float("inf")
            t["rms_upper_abs"] = t["rms_upper"] * cells.sigma[c]
            t["rms_upper_rel"] = t["rms_upper_abs"] / size if size > 0 else float("inf")
            t["sigma_rel"] = cells.sigma[c] / size if size > 0 else float("inf")
            t["channel"] = c
            out[k] = t
    _holm(out)
    return out


def _hysteresis_test(data: FitData, pred: dict) -> dict:
    """Wong's residuals on rising against falling slip, cycle by cycle: what no hypothesis can make.

    Every hypothesis is a static function of slip, load and place, so at the same slip, load and
    place it predicts the same forces whether the slip is rising or falling; the cells pool both.
    A channel lagging the others (a different filter in an amplifier), a soil or sensor effect of
    the rates, a mis-set wheel inertia make the residuals differ by direction, and the pooled
    cells average that away.  In each accelerate cycle with both directions over a common slip
    range, the sample residuals ``e`` (channel - ``pred``, (N,)) are fitted with a cubic in slip
    (the static error, whatever model) plus ``h d/2``, d = +1 on rising and -1 on falling slip
    (the sign of ds/dt); the cycles' h are the independent units of a two-sided t-test.  The
    error's RMS is |mean h|/2, judged as a structure test is: relevant when >= ``MIN_EFFECT``
    cell-noise sigma and >= ``MIN_REL`` of the channel's magnitude; significant when p <
    ``ALPHA`` / the number of channels.  Returns channel -> ``{p, h, se, cycles, effect,
    effect_abs, effect_rel, significant, channel}`` for channels with >= 3 such cycles; empty for
    tables (no time).  Source: a direction (hysteresis) term in a regression on the
    cycles, Student's t over independent cycles (as the level test of the cells)."""
    out = {}
    if data.kind == "table" or data.t_s is None:
        return out
    gids = np.unique(data.groups)
    for c, y in data.channels.items():
        e = np.asarray(y, float) - np.asarray(pred[c], float)
        hs = []
        for g in gids:
            m = (data.groups == g) & np.isfinite(e)
            if m.sum() < 20:
                continue
            order = np.argsort(data.t_s[m], kind="stable")
            t, s, ee = data.t_s[m][order], data.slip[m][order], e[m][order]
            keep = np.r_[True, np.diff(t) > 0]
            t, s, ee = t[keep], s[keep], ee[keep]
            if t.size < 20:
                continue
            d = np.sign(np.gradient(s, t))
            up, dn = d > 0, d < 0
            if up.sum() < 10 or dn.sum() < 10:
                continue
            lo, hi = max(s[up].min(), s[dn].min()), min(s[up].max(), s[dn].max())
            sel = (s >= lo) & (s <= hi) & (up | dn)
            if hi - lo < 0.1 or (sel & up).sum() < 10 or (sel & dn).sum() < 10:
                continue
            u = (s[sel] - 0.5 * (lo + hi)) / (0.5 * (hi - lo))
            X = np.column_stack([np.ones_like(u), u, u**2, u**3, 0.5 * d[sel]])
            coef, *_ = np.linalg.lstsq(X, ee[sel], rcond=None)
            hs.append(coef[-1])
        if len(hs) < 3:
            continue
        h = np.asarray(hs)
        mean, se = float(h.mean()), float(h.std(ddof=1) / math.sqrt(h.size))
        p = float(2 * stats.t.sf(abs(mean) / se, h.size - 1)) if se > 0 else (0.0 if mean != 0 else 1.0)
        size = _magnitude(data.cells.channels[c])
        rms = abs(mean) / 2
        sigma = data.cells.sigma[c]
        out[c] = {"p": p, "h": mean, "se": se, "cycles": int(h.size), "effect": rms / sigma if sigma > 0 else float("inf"),
                  "effect_abs": rms, "effect_rel": rms / size if size > 0 else float("inf"), "channel": c}
    for t in out.values():
        t["significant"] = bool(t["p"] < ALPHA / len(out) and _relevant(t))
    return out


def _hysteresis_text(hyst: dict) -> str:
    sig = [t for t in hyst.values() if t["significant"]]
    parts = [f"the {CHANNEL_TITLES[t['channel']]} by {_fmt(abs(t['h']), _UNITS[t['channel']])} "
             f"({'higher' if t['h'] > 0 else 'lower'} on rising slip; RMS {t['effect_rel']:.1%} of the channel, "
             f"p = {t['p']:.2g} over {t['cycles']} cycles)" for t in sig]
    return ("Wong's residuals differ between rising and falling slip at the same slip: " + "; ".join(parts)
            + ". No hypothesis can make that (each is a static function of slip, load and place): a channel "
            "lagging the others, an effect of the loading or shear rate, or a wrong wheel inertia in the "
            "compensation could")


_UNITS = {"drawbar_pull_n": "N", "torque_nm": "N m", "sinkage_m": "m"}  #: SI unit of each channel


def _relevant(t: dict) -> bool:
    return t["effect"] >= MIN_EFFECT and t.get("effect_rel", float("inf")) >= MIN_REL


def _holm(tests: dict) -> None:
    """Holm's step-down adjusted p-values of one model's structure tests, in place (``p_holm``).

    The tests are sorted by ``p``; the i-th smallest (0-based) of m gets ``(m - i) p``, made
    non-decreasing along the order and capped at 1; a test is significant when ``p_holm < ALPHA``.
    This controls the family-wise error at ``ALPHA`` under any dependence between the tests, as
    Bonferroni (``m p``) does, and rejects everything Bonferroni rejects and more: once one test
    is rejected, the rest compete among fewer (Holm 1979, Scand. J. Statist. 6:65).  A test
    without a p-value counts in m and is never significant."""
    m = len(tests)
    order = sorted(tests, key=lambda k: tests[k]["p"] if np.isfinite(tests[k]["p"]) else np.inf)
    run = 0.0
    for i, k in enumerate(order):
        p = tests[k]["p"]
        run = max(run, min(1.0, (m - i) * p)) if np.isfinite(p) else float("nan")
        tests[k]["p_holm"] = run


def _significant_tests(tests: dict) -> list:
    """Tests significant at family level ``ALPHA`` (Holm, :func:`_holm`) and relevant."""
    return [k for k, t in tests.items() if t.get("p_holm", np.nan) < ALPHA and _relevant(t)]


def _detectable_only(tests: dict) -> list:
    """Tests significant at family level ``ALPHA`` (Holm) but below the relevance floors."""
    return [k for k, t in tests.items() if t.get("p_holm", np.nan) < ALPHA and not _relevant(t)]


def _change_point(data: FitData, pred: dict):
    """The change point along the run in the residuals ``pred`` leaves (a constant soil's: Wong's, or
    the five-value re-fit's): the channel whose cycle means show the most significant change of level
    (:func:`_step_test` against one level, significant at ``ALPHA`` over the channels; a level error
    alone is a mismatch, not a change), the split refined over the cells between the two cycles around
    it (least squares of two levels on the cell residuals of every channel, in noise units).
    Returns ``(x_step, n_splits)`` (normalised drift coordinate, the number of candidate
    splits), or None (a table, fewer than 5 cycles, or no significant step)."""
    cells = data.cells
    if data.kind == "table" or cells.x is None:
        return None
    ug, inv = np.unique(cells.group, return_inverse=True)
    if ug.size < 5:
        return None
    cnt = np.bincount(inv).astype(float)
    xg = np.bincount(inv, weights=cells.x) / cnt
    best = None
    E = []
    for c, y in cells.channels.items():
        e = (y - pred[c]) / cells.sigma[c]
        if not np.isfinite(e).all():
            continue
        E.append(e)
        gm = np.bincount(inv, weights=e) / cnt
        p, _, bounds = _step_test(xg, gm, level=True)
        if np.isfinite(p) and (best is None or p < best[0]):
            best = (p, bounds)
    if best is None or best[0] >= ALPHA / max(len(E), 1):
        return None
    lo, hi = best[1]
    E = np.vstack(E)
    xs = np.unique(cells.x[(cells.x >= lo - 0.5 * (hi - lo)) & (cells.x <= hi + 0.5 * (hi - lo))])
    cand = 0.5 * (xs[1:] + xs[:-1]) if xs.size > 1 else np.array([0.5 * (lo + hi)])
    sse = []
    for x0 in cand:
        m = cells.x > x0
        r = 0.0
        for e in E:
            for part in (e[m], e[~m]):
                if part.size:
                    r += float(np.sum((part - part.mean()) ** 2))
        sse.append(r)
    return float(cand[int(np.argmin(sse))]), int(ug.size - 3)


def _loose(tests_w: dict) -> list:
    """The structure tests whose 95 % bound on Wong's error reaches ``MIN_REL`` of the channel:
    the mean error over the cycles, or the RMS of an error of the test's form (against slip, load
    or along the run; :func:`_rms_upper`): the run cannot exclude a relevant error there.
    Returns ``(test, kind, bound_abs, bound_rel, channel)`` tuples, kind ``mean`` or ``rms``."""
    out = []
    for k, t in tests_w.items():
        if t.get("level_upper_rel", 0.0) >= MIN_REL:
            out.append((k, "mean", t["level_upper_abs"], t["level_upper_rel"], t["channel"]))
        elif not t.get("rms_upper_rel", 0.0) < MIN_REL:  # NaN (no test possible) proves nothing either
            out.append((k, "rms", t.get("rms_upper_abs", float("nan")), t.get("rms_upper_rel", float("nan")),
                        t["channel"]))
    return out


def _noisy(tests_w: dict) -> dict:
    """Channels whose cell noise sets the relevance threshold: ``MIN_EFFECT`` cell-noise sigmas reach
    ``MIN_REL`` of the channel's magnitude.  An error of the relevant size in a form no structure test
    looks for (within the accelerate cycles, slip and distance together) then passes for noise: the
    noise is what no smooth function of slip, load and distance explains
    (:func:`wheelsoil.model.data.cell_noise`).  Returns ``{channel: sigma / magnitude}``."""
    out = {}
    for t in tests_w.values():
        r = t.get("sigma_rel", 0.0)
        if MIN_EFFECT * r >= MIN_REL:
            out[t["channel"]] = r
    return out


def _noisy_text(noisy: dict) -> str:
    chans = "; ".join(f"{CHANNEL_TITLES[c]} {r:.1%}" for c, r in noisy.items())
    return (f"the cell noise reaches the {MIN_REL:.0%} relevance floor ({chans} of the channel's magnitude): an error "
            "of relevant size in a form the structure tests do not look for (within the accelerate cycles, or "
            "slip and distance together) would pass for noise")


_AGAINST = {"": "against slip", "@load": "against load", "@x": "along the run"}


def structure_title(key: str) -> str:
    """The words for a structure test's key (:func:`_structure_cells`): ``"drawbar_pull_n@x"`` ->
    ``"drawbar pull along the run"``."""
    c, at, against = key.partition("@")
    return f"{CHANNEL_TITLES.get(c, c)} {_AGAINST.get(at + against, 'against ' + against)}"


def _tests_text(keys) -> str:
    return ", ".join(structure_title(k) for k in keys)


def _loose_text(loose: list) -> str:
    parts = []
    for key, kind, b_abs, b_rel, c in loose:
        what = f"{'mean' if kind == 'mean' else 'RMS'} error in the {CHANNEL_TITLES[c]}" + (
            "" if kind == "mean" else " " + _AGAINST.get(key[len(c):], ""))
        size = f"{_fmt(b_abs, _UNITS[c])} ({b_rel:.1%})" if np.isfinite(b_rel) else "(too few units to bound it)"
        parts.append(f"{what} up to {size}")
    return "Wong's " + "; ".join(parts) + " (95 % confidence bounds)"


def _fmt(v, unit="N", nd=3):
    if v is None or not np.isfinite(v):
        return "n/a"
    return f"{v:.{nd}g} {unit}".strip()
