"""The fitted-model report: ``report.html`` (one self-contained file), ``*.png``, ``report.json``.

:func:`write_report` turns a :class:`wheelsoil.model.diagnosis.Diagnosis` (and,
from the pipeline, the provenance and the processed signals of each input) into

* ``report.json`` (schema ``wheelsoil.report/1``, strict JSON: no NaN, ``null``
  instead; SI units, the unit in every key where it is ambiguous), with the
  keys of :data:`REQUIRED_KEYS` and ``provenance`` (what was run on what, enough
  to re-run it), ``data_quality`` (per input), per-model ``parameters`` with
  their flags, ``per_channel`` metrics, ``flags``, ``findings`` (the report's
  statements, generated from the numbers next to them);
* ``overview.png`` (``overview_<i>.png`` for several inputs): V, r*omega, slip,
  W, Dp, T against time with the phases shaded and every span excluded from
  the fit marked with its reason; ``dp_vs_slip.png`` (paper Figs. 4-5),
  ``residuals.png`` (Wong's residuals vs slip, load, time) and
  ``sinkage_vs_slip.png``; curves that overlap are drawn once and said to;
  ``soil_values.png`` (the five-value re-fit against the lab, in lab sd);
* ``report.html``: one file, figures embedded as base64 PNG ``data:`` URIs,
  inline CSS only (responsive: readable at phone width, tables scroll; a
  print style), no scripts, fonts or links, so it opens offline.

One display convention (:func:`fmt`): forces in N, torques in N m, sinkage and
lengths (K, H) in mm, cohesion in kPa, angles in degrees, kc in kN/m^(n+1),
kphi and k_eq in kN/m^(n+2), three significant figures (standard errors two).

The diagnosis object comes from ``Diagnosis.to_dict()`` when the diagnosis
provides it (team contract D: effect, model, confidence, summary, channels,
probabilities, alternatives, consistency, flags, models); every key is
optional here, and what today's :class:`Diagnosis` lacks (flags) is derived
from its fits.  Metrics: paper section 1.3 (M0, R0, R^2).
"""

from __future__ import annotations

import base64
import html
import json
import math
import re
import textwrap
from pathlib import Path

import numpy as np

from .diagnosis import EFFECT_TITLES, LAB_Z, SLIP_SINKAGE_MODELS, TITLES, WHY_UNEXPLAINED, data_estimates, prior_z
from .diagnosis import json_ready as _clean
from .structure import CHANNEL_TITLES, structure_title

__all__ = ["write_report", "report_dict", "fmt", "fmt_param", "param_unit", "SCHEMA", "ALL_MODELS",
           "REQUIRED_KEYS", "CORRELATION_LIMIT", "CONDITION_LIMIT", "exclusion_masks"]

SCHEMA = "wheelsoil.report/1"
#: Models always listed (a missing one says why); others the diagnosis fits are appended.
ALL_MODELS = ("wong", "vasilev", "lyasko", "ding", "terrain_mismatch", "vasilev+terrain", "lyasko+terrain",
              "ding+terrain", "wong_reece", "drift_linear")
#: report name -> the diagnosis's fit name where they differ (the terrain hypothesis)
_FIT_ALIAS = {"terrain_mismatch": "terrain"}
#: Top-level keys every report.json has.
REQUIRED_KEYS = ("schema", "input", "provenance", "terrain", "wheel", "samples_used", "slip_min", "time_sync",
                 "models", "diagnosis", "gain", "flags", "data_quality", "findings", "metric_definitions")
#: terrain parameters a fit can identify (k_eq = kc/b + kphi: one wheel width cannot separate kc and kphi)
TERRAIN_KEYS = ("k_eq", "n", "c", "phi", "K")
MAX_POINTS = 4000  #: samples drawn per scatter panel (every k-th; file size, readability)
CORRELATION_LIMIT = 0.95  #: |correlation| of two fitted parameters above this is flagged
#: A loud note (``WHEEL RADIUS CONFLICT: ...``, ``f.asc: GNSS LATENCY UNRELIABLE: ...``): shown under the
#: verdict in report.html and printed on the terminal, not only in the notes at the end.
LOUD_NOTE = re.compile(r"^(\S+: )?[A-Z]{4,}( [A-Z]{2,})+:")
CONDITION_LIMIT = 100.0  #: condition number of the scaled Jacobian above this is flagged (derived flags)
_PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf", "#bcbd22")
COLORS = {"wong": "#444444", "vasilev": "#1f77b4", "lyasko": "#d62728", "ding": "#2ca02c",
          "terrain_mismatch": "#9467bd", "vasilev+terrain": "#17becf", "lyasko+terrain": "#ff9896",
          "ding+terrain": "#bcbd22",
          "wong_reece": "#8c564b", "drift_linear": "#e377c2", "drift_step": "#7f7f7f"}
_CHANNEL_UNIT = {"drawbar_pull_n": "force", "torque_nm": "torque", "sinkage_m": "length_mm"}
_CHANNEL_SUFFIX = {"drawbar_pull_n": "n", "torque_nm": "nm", "sinkage_m": "m"}


def _canon(name):
    """The report's name of a fit (``terrain`` -> ``terrain_mismatch``)."""
    for k, v in _FIT_ALIAS.items():
        if name == v:
            return k
    return name


def _fit_of(diag, name):
    """The fit shown under ``name`` (``terrain_mismatch`` is the diagnosis's ``terrain`` hypothesis)."""
    fits = getattr(diag, "fits", {}) or {}
    return fits.get(name) if name in fits else fits.get(_FIT_ALIAS.get(name, name))


def _fit_names(diag) -> list:
    """Report names of the fitted models, in display order."""
    return sorted({_canon(k) for k in (getattr(diag, "fits", {}) or {})}, key=_model_order)


#: a fitted model with a lower posterior probability gets no panel of its own in dp_vs_slip.png
FIG_MIN_PROBABILITY = 0.01
#: always drawn: Wong and the paper's three slip-sinkage forms (paper Figs. 4-5)
FIG_ALWAYS = ("wong", *SLIP_SINKAGE_MODELS)


def _figure_names(diag, names: list) -> list:
    """The models of ``names`` (:func:`_fit_names`) drawn in ``dp_vs_slip.png``, in that order:
    :data:`FIG_ALWAYS`, the chosen model, the listed alternatives, the fit with the lowest
    out-of-sample drawbar-pull error (CV R0) and every other fit with posterior probability at
    least :data:`FIG_MIN_PROBABILITY` (the rest are in the models table; one panel each for 34
    hypotheses would be unreadable)."""
    fits = getattr(diag, "fits", {}) or {}
    probs = {_canon(k): v for k, v in (getattr(diag, "probabilities", {}) or {}).items()}
    cv = {k: ((getattr(f, "cv", None) or {}).get("cv_R0") or {}).get("drawbar_pull_n") for k, f in fits.items()}
    cv = {k: v for k, v in cv.items() if v is not None and np.isfinite(v)}
    best_cv = [min(cv, key=cv.get)] if cv else []
    keep = set(FIG_ALWAYS) | {_canon(k) for k in [getattr(diag, "model", None), *(getattr(diag, "alternatives", []) or []),
                                                 *best_cv] if k}
    return [k for k in names if k in keep or probs.get(k, 0.0) >= FIG_MIN_PROBABILITY]


def _title(name) -> str:
    return TITLES.get(name, str(name).replace("_", " ")) if name is not None else "none"


def _color(name, i=0) -> str:
    return COLORS.get(name, _PALETTE[i % len(_PALETTE)])


def _distinct_colors(names) -> list:
    """One colour per name, its own where it has one, never the same twice (up to 20 names)."""
    import matplotlib

    tab = [matplotlib.colors.to_hex(c) for c in matplotlib.colormaps["tab20"].colors]
    spare = tab[::2] + ["#000000", "#7f0000", "#004c6d", "#5a3e00"] + tab[1::2]  # strong colours first
    out, used = [], set()
    for n in names:
        c = COLORS.get(n)
        if c is None or c in used:
            c = next((x for x in spare if x not in used), "#000000")
        used.add(c)
        out.append(c)
    return out


# ============================================================================ display convention

#: quantity -> (SI unit, display unit, factor SI -> display)
QUANTITIES = {
    "force": ("N", "N", 1.0),
    "torque": ("N m", "N m", 1.0),
    "length_mm": ("m", "mm", 1e3),
    "length_m": ("m", "m", 1.0),
    "pressure": ("Pa", "kPa", 1e-3),
    "angle": ("rad", "deg", 180.0 / math.pi),
    "kc": ("N/m^(n+1)", "kN/m^(n+1)", 1e-3),
    "kphi": ("N/m^(n+2)", "kN/m^(n+2)", 1e-3),
    "ratio": ("1", "", 1.0),
    "percent": ("%", "%", 1.0),
    "time": ("s", "s", 1.0),
    "latency": ("s", "ms", 1e3),
    "speed": ("m/s", "m/s", 1.0),
    "mass": ("kg", "kg", 1.0),
    "inertia": ("kg m^2", "kg m^2", 1.0),
}
#: fitted parameter -> quantity (field symbols of the DEVELOPERS guide)
PARAM_QUANTITY = {"c": "pressure", "phi": "angle", "K": "length_mm", "H": "length_mm", "kc": "kc",
                  "kphi": "kphi", "k_eq": "kphi", "n": "ratio", "n1": "ratio", "m1": "ratio", "m2": "ratio",
                  "a1": "ratio", "a2": "ratio"}


def num(x, sig: int = 3) -> str:
    """``x`` with ``sig`` significant figures, plain decimals for 1e-3 <= |x| < 1e6, else
    ``m.mme-k``; ``n/a`` for None or non-finite.  The one number formatter of the report."""
    if x is None or isinstance(x, (str, bool)):
        return "n/a" if x is None else str(x)
    try:
        v = float(x)
    except (TypeError, ValueError):
        return str(x)
    if not math.isfinite(v):
        return "n/a"
    if v == 0:
        return "0"
    e = int(math.floor(math.log10(abs(v))))
    if -3 <= e < 6:
        dec = max(0, sig - 1 - e)
        r = round(v, dec) if dec > 0 else round(v, sig - 1 - e)
        if r != 0 and int(math.floor(math.log10(abs(r)))) > e:  # 9.996 -> 10.0
            dec = max(0, dec - 1)
        return f"{r:.{dec}f}"
    m = f"{v:.{sig - 1}e}"
    mant, _, ex = m.partition("e")
    return f"{mant}e{int(ex)}"


def fmt(v, quantity: str = "ratio", sig: int = 3, unit: bool = True) -> str:
    """An SI value in the report's display unit of ``quantity`` (see :data:`QUANTITIES`),
    e.g. ``fmt(0.0312, "length_mm") == "31.2 mm"``; ``n/a`` for None/NaN."""
    _, disp, k = QUANTITIES.get(quantity, ("", "", 1.0))
    if v is None or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(float(v)):
        return "n/a"
    txt = num(float(v) * k, sig)
    return f"{txt} {disp}" if unit and disp else txt


def param_unit(name: str, display: bool = False) -> str:
    """SI unit (or the display unit) of a fitted parameter; ``"1"`` / ``""`` when dimensionless."""
    si, disp, _ = QUANTITIES[PARAM_QUANTITY.get(name, "ratio")]
    return disp if display else si


def fmt_param(name: str, value, se=None, unit: bool = True) -> str:
    """``value ± se unit`` of a fitted parameter in display units (se with 2 significant figures)."""
    q = PARAM_QUANTITY.get(name, "ratio")
    txt = fmt(value, q, 3, unit=False)
    if se is not None:
        txt += " ± " + fmt(se, q, 2, unit=False)
    u = QUANTITIES[q][1]
    return f"{txt} {u}" if unit and u else txt


def _chan_fmt(v, channel, sig=3) -> str:
    return fmt(v, _CHANNEL_UNIT.get(channel, "ratio"), sig)


def _chan_unit(channel) -> str:
    return QUANTITIES[_CHANNEL_UNIT.get(channel, "ratio")][1]


# ============================================================================ JSON helpers


def _terrain_dict(t, wheel) -> dict:
    """Terrain values in SI with the unit in each key (JSON)."""
    return {
        "name": t.name,
        "c_pa": t.c,
        "phi_deg": t.phi_deg,
        "phi_rad": t.phi,
        "k_m": t.K,
        "n": t.n,
        "kc": t.kc,
        "kphi": t.kphi,
        "k_eq": t.k_eq(wheel.width),
        "kc_unit": "N/m^(n+1)",
        "kphi_unit": "N/m^(n+2)",
        "source": getattr(t, "source", ""),
    }


def _finite(v):
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


# ============================================================================ diagnosis object


def _legacy_diagnosis(diag) -> dict:
    """The diagnosis keys today's :class:`Diagnosis` has (every attribute optional)."""
    g = lambda k, d=None: getattr(diag, k, d)  # noqa: E731
    structure = {}
    for k, v in (g("structure") or {}).items():
        structure[_canon(k)] = {c: {"p": t.get("p"), "p_holm": t.get("p_holm"), "p_poly": t.get("p_poly"),
                                    "p_bins": t.get("p_bins"),
                                    "effect_sigma": t.get("effect"), "effect_abs": t.get("effect_abs"),
                                    "effect_rel": t.get("effect_rel"), "units": t.get("units"),
                                    "channel": t.get("channel", c.partition("@")[0])}
                                for c, t in v.items()}
    data = g("data")
    out = {
        "effect": g("effect"),
        "model": g("model"),
        "confidence": g("confidence"),
        "confidence_reasons": list(g("confidence_reasons") or []),
        "summary": g("summary") or "",
        "forms_distinguishable": g("forms_distinguishable"),
        "indistinguishable_forms": list(g("indistinguishable_forms") or []),
        "structure_tests": structure,
        "load_test": g("load_test"),
        "time_test": g("time_test"),
        "sinkage_evidence": g("sinkage_evidence"),
        "thresholds": dict(g("thresholds") or {}),
        "fit_terrain": g("fit_terrain", False),
        "identifiability": g("identifiability") or {},
        "cross_validation": getattr(data, "group_kind", None),
    }
    return out


def diagnosis_dict(diag) -> dict:
    """The JSON ``diagnosis`` object: today's keys, overlaid by ``diag.to_dict()`` (contract D)
    when the diagnosis provides it; ``flags`` derived from the fits when it does not."""
    out = _legacy_diagnosis(diag)
    to_dict = getattr(diag, "to_dict", None)
    if callable(to_dict):
        try:
            d = to_dict()
        except Exception as exc:  # noqa: BLE001 - a report must still be written
            out.setdefault("notes", []).append(f"Diagnosis.to_dict() failed: {type(exc).__name__}: {exc}")
            d = {}
        out.update(_clean(d) if isinstance(d, dict) else {})
    if "flags" not in out or out["flags"] is None:
        out["flags"] = derived_flags(getattr(diag, "fits", {}) or {})
        out["flags_source"] = "derived by the report from the fits (the diagnosis gives none)"
    return _clean(out)


def derived_flags(fits: dict) -> list:
    """Flags of degenerate fits from :class:`~wheelsoil.model.fit.ModelFit` objects:
    parameters at a bound, |correlation| > :data:`CORRELATION_LIMIT`, condition number >
    :data:`CONDITION_LIMIT`.  Returns contract-D flag dicts ``{model, parameter, kind, detail}``."""
    flags = []
    for name in sorted(fits, key=_model_order):
        f = fits[name]
        res = getattr(f, "result", None)
        if res is None:
            continue
        for p in getattr(res, "at_bound", ()) or ():
            v = f.params.get(p, res.params.get(p) if hasattr(res, "params") else None)
            flags.append({"model": name, "parameter": p, "kind": "at_bound",
                          "detail": f"{p} = {fmt_param(p, v)} ended on a bound of its allowed range: the best "
                                    "fit lies at the edge, so its standard error is not a confidence interval"})
        names = list(getattr(res, "names", ()) or ())
        corr = np.asarray(getattr(res, "correlation", np.empty((0, 0))), dtype=float)
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                if i < corr.shape[0] and j < corr.shape[1]:
                    c = corr[i, j]
                    if np.isfinite(c) and abs(c) > CORRELATION_LIMIT:
                        flags.append({"model": name, "parameter": f"{names[i]},{names[j]}", "kind": "correlation",
                                      "value": float(c),
                                      "detail": f"correlation({names[i]}, {names[j]}) = {c:+.5f}: the data pin down "
                                                "one combination of the two, not each"})
        cn = _finite(getattr(res, "condition_number", None))
        if cn is not None and cn > CONDITION_LIMIT:
            flags.append({"model": name, "parameter": None, "kind": "ill_conditioned", "value": cn,
                          "detail": f"condition number {num(cn)} > {num(CONDITION_LIMIT)}: some parameter "
                                    "combinations are poorly determined"})
    return flags


def _model_order(name) -> tuple:
    return (ALL_MODELS.index(name), "") if name in ALL_MODELS else (len(ALL_MODELS), str(name))


# ============================================================================ report.json


def _per_channel(data, fit) -> dict:
    """channel -> in-sample M0/R0/R^2 and out-of-sample R0, unit suffix in the keys."""
    from .fit import _metrics

    out = {}
    cvr = (fit.cv or {}).get("cv_R0") or {}
    for c in data.channels:
        sfx = _CHANNEL_SUFFIX.get(c, "si")
        m = _metrics(data.channels[c], fit.predictions[c]) if c in fit.predictions else {}
        out[c] = {"M0_pct": m.get("M0_pct"), f"R0_{sfx}": m.get("R0_n"), "R2": m.get("R2"),
                  f"cv_R0_{sfx}": cvr.get(c) if c != "drawbar_pull_n" else fit.cv_R0_n}
    return out


def _r0(pc: dict, c: str, cv: bool = False):
    sfx = _CHANNEL_SUFFIX.get(c, "si")
    return (pc.get(c) or {}).get(("cv_" if cv else "") + f"R0_{sfx}")


def _worse_than_wong(models: dict, channels: list) -> dict:
    """model -> channel -> {in_sample, out_of_sample, reason} where a fitted model is worse than Wong."""
    wong = models.get("wong", {}).get("per_channel") or {}
    out = {}
    for k, m in models.items():
        pc = m.get("per_channel")
        if k == "wong" or not pc:
            continue
        better = {c: (_r0(pc, c) is not None and _r0(wong, c) is not None and _r0(pc, c) < _r0(wong, c))
                  for c in channels}
        for c in channels:
            a, b = _r0(wong, c), _r0(pc, c)
            ca, cb = _r0(wong, c, True), _r0(pc, c, True)
            ins = a is not None and b is not None and b > a * 1.001
            oos = ca is not None and cb is not None and cb > ca * 1.001
            if not (ins or oos):
                continue
            others = [o for o in channels if o != c and better.get(o)]
            if ins and others:
                why = (f"joint fit with {', '.join(CHANNEL_TITLES.get(o, o) for o in others)}: the fit minimises "
                       "the noise-weighted error of all measured channels together and trades "
                       f"{CHANNEL_TITLES.get(c, c)} accuracy for "
                       + ", ".join(f"{CHANNEL_TITLES.get(o, o)} ({_chan_fmt(_r0(wong, o), o)} -> "
                                   f"{_chan_fmt(_r0(pc, o), o)} in sample)" for o in others))
            elif ins:
                why = ("the model's form cannot follow this channel: it is worse in sample although it contains "
                       "more freedom than Wong; see its flags")
            else:
                why = ("better in sample but worse out of sample: the fitted parameters do not carry over to "
                       "held-out cycles (over-fitting or an unstable parameter, see its flags)")
            out.setdefault(k, {})[c] = {"in_sample": ins, "out_of_sample": oos, "reason": why}
    return out


def _model_entry(name, f, data, wheel, dd_model: dict | None) -> dict:
    res = f.result
    at_bound = set(getattr(f, "at_bound", ()) or ()) | (set(getattr(res, "at_bound", ()) or ()) if res is not None else set())
    params = {}
    for p, v in f.params.items():
        params[p] = {"value": v, "se": f.stderr.get(p), "unit": (getattr(f, "units", None) or {}).get(p) or param_unit(p),
                     "at_bound": p in at_bound}
    for p, e in ((dd_model or {}).get("params") or {}).items():  # contract D overrides
        if isinstance(e, dict):
            params.setdefault(p, {}).update({k: e[k] for k in ("value", "se", "unit", "at_bound") if k in e})
    return {
        "status": "ok" if f.success else f"did not converge: {f.message}",
        "fit_name": getattr(f, "name", name),
        "effect": getattr(f, "effect", None),
        "params": {k: v for k, v in f.params.items()},
        "stderr": {k: v for k, v in f.stderr.items()},
        "params_unit": {k: (getattr(f, "units", None) or {}).get(k) or param_unit(k) for k in f.params},
        "parameters": params,
        "params_fixed_terrain": list(getattr(f, "fixed_terrain", ()) or ()),
        "terrain_fitted": [p for p in TERRAIN_KEYS if p in f.params],
        "terrain_held_fixed": [p for p in TERRAIN_KEYS if p not in f.params],
        "terrain_used": _terrain_dict(f.terrain, wheel),
        "metrics": dict(f.metrics),
        "channel_metrics": f.channel_metrics,
        "per_channel": _per_channel(data, f),
        "cv_R0_n": f.cv_R0_n,
        "cv_R0": f.cv["cv_R0"] if f.cv else None,
        "cv_score": f.cv["cv_score"] if f.cv else None,
        "cv_folds": f.cv["n_groups"] if f.cv else None,
        "stderr_jackknife": f.cv.get("stderr_jackknife") if f.cv else None,
        "probability": None,
        "stderr_method": ("max(cluster-robust over cycle x slip cells, jackknife over cycles)"
                          if f.cv and f.cv.get("stderr_jackknife") else
                          "cluster-robust over cycle x slip cells" if data.kind == "timeseries"
                          else "s^2 (J^T J)^-1 (reduced chi-square)"),
        "bic": f.bic,
        "log_evidence": (dd_model or {}).get("log_evidence"),
        "n_eff": f.n_eff,
        "k": f.k,
        "iterations": None if res is None else res.iterations,
        "correlation": None if res is None else {"names": list(res.names), "matrix": res.correlation},
        "condition_number": getattr(f, "condition_number", None) if res is None or getattr(f, "condition_number", None)
        is not None else res.condition_number,
        "notes": list(f.notes),
    }


def _per_run(diag) -> list:
    """Per-run Dp metrics of every fitted model (only when several runs)."""
    from .fit import _metrics

    data = diag.data
    runs = np.unique(data.run)
    if runs.size < 2:
        return []
    out = []
    for r in runs:
        m = data.run == r
        row = {"run": int(r), "samples": int(m.sum()), "models": {}}
        for k in _fit_names(diag):
            f = _fit_of(diag, k)
            row["models"][k] = _metrics(data.channels["drawbar_pull_n"][m], f.predictions["drawbar_pull_n"][m])
        out.append(row)
    return out


METRIC_DEFINITIONS = {
    "M0_pct": "maximum error rate (paper section 1.3): M0 = 100 max_i |y_p,i - y_a,i| / |y_a,i| [%]; one sample "
              "with a measured value near zero dominates it (small Dp at small slip), so it is shown but not used "
              "to rank models.",
    "R0": "root mean squared error (paper section 1.3): R0 = [1/N sum_i (y_p,i - y_a,i)^2]^(1/2), in the "
          "channel's unit (N for Dp, N m for T, mm for z); lower is better.",
    "R2": "squared correlation coefficient (paper section 1.3): R^2 = [cov(y_a, y_p) / (sigma_a sigma_p)]^2. "
          "It says whether prediction and measurement go up and down together, not whether the prediction is the "
          "right size: a model offset by 1 kN can have R^2 = 1, and a model whose prediction hardly varies over "
          "the samples has R^2 near 0 however close it is. Meaningful only when the samples span a range of the "
          "channel much larger than the noise (a wide slip sweep) and the model is unbiased; rank models by R0 "
          "and CV R0 instead.",
    "cv_R0": "out-of-sample R0: each cross-validation group (accelerate cycle, or block of table rows) is "
             "predicted by the model fitted without it; R0 over all held-out predictions.",
    "cv_score": "out-of-sample RMS of the noise-weighted residuals over all measured channels (the rule's score).",
    "bic": "Bayesian information criterion with the effective number of independent observations n_eff: "
           "n_eff ln(RSS/N) + k ln(n_eff); lower is better; a difference of 10 or more is 'very strong' "
           "evidence (Kass & Raftery 1995). Shown as the difference to Wong.",
    "evidence": "2 ln(Z / Z_Wong): twice the natural log of the ratio of the model's evidence Z (the Laplace "
                "approximation the probabilities are computed from: the fit on the cell means, weighed by their "
                "design effect, with the lab priors) to Wong's; higher is better, 10 or more is 'very strong' "
                "(Kass & Raftery 1995). With the hypotheses' prior weights it gives the probability.",
    "probability": "posterior probability of each hypothesis given the data (evidence of the fits with the "
                   "effective number of independent units, and the lab priors); they sum to 1 over the "
                   "hypotheses tried, so they compare the candidates with each other, not with causes not on "
                   "the list.",
    "condition_number": "condition number of the scaled Jacobian of the fit: above "
                        f"{CONDITION_LIMIT:g}, some parameter combination is poorly determined.",
    "correlation": f"|correlation| of two fitted parameters above {CORRELATION_LIMIT:g}: the data determine one "
                   "combination of them, not each.",
}


def _definitions(data, dd) -> dict:
    """:data:`METRIC_DEFINITIONS`, adapted to how this diagnosis computed them (cell means, BIC form)."""
    out = dict(METRIC_DEFINITIONS)
    if getattr(data, "cells", None) is not None:
        out["cv_R0"] = ("out-of-sample R0: each cross-validation group (accelerate cycle, or block of table rows) "
                        "is predicted by the model fitted without it; RMS of the held-out errors of the cell means "
                        "(averages over cycle x slip cells, the units the models are fitted to), so it is smaller "
                        "than the in-sample R0 over the samples: compare CV R0 between models, not with R0.")
    if "c_hat" in dd:
        out["bic"] = ("Bayesian information criterion of the fit on the cell means: chi-square of the data divided "
                      "by the common overdispersion c_hat, plus the chi-square of the lab priors, plus k ln(number "
                      "of cells); lower is better; a difference of 10 or more is 'very strong' evidence (Kass & "
                      "Raftery 1995). Shown as the difference to Wong; the probabilities (Laplace evidence, the cells weighed "
                      "by their design effect: the correlated cells of one cycle count as fewer independent ones) "
                      "are the verdict's measure.")
    return out


def report_dict(diag, *, terrain, wheel, inputs, time_sync: dict | None = None,
                figures: list | None = None, extra_notes: list | None = None, provenance: dict | None = None,
                data_quality: list | None = None, figure_notes: dict | None = None) -> dict:
    """The ``report.json`` content (schema ``wheelsoil.report/1``) as a JSON-safe dict.

    ``terrain``/``wheel``: the terrain and wheel given by the user; ``inputs``:
    list of input paths (str); ``time_sync``: ``{"gnss_latency_s": ...}`` (None
    values for tables); ``provenance``: the run's provenance (see
    :func:`wheelsoil.pipeline.run_fit`), ``data_quality``: per-input dicts;
    ``figure_notes``: file name -> list of sentences (e.g. overlapping curves).
    Every model of :data:`ALL_MODELS` has an entry; one that was not fitted
    has ``"status"`` saying why and null numbers.
    """
    data = diag.data
    dd = diagnosis_dict(diag)
    dmodels = dd.get("models") if isinstance(dd.get("models"), dict) else {}
    models = {}
    names = list(ALL_MODELS) + [k for k in _fit_names(diag) if k not in ALL_MODELS]
    for name in names:
        f = _fit_of(diag, name)
        if f is None:
            why = "not fitted"
            for msg in list(getattr(diag, "failures", [])) + list(getattr(diag, "notes", [])):
                if msg.startswith(_title(name)) or msg.startswith(name):
                    why = msg
            models[name] = {"status": why, "params": None, "stderr": None, "parameters": None,
                            "metrics": {"M0_pct": None, "R0_n": None, "R2": None},
                            "cv_R0_n": None, "bic": None, "log_evidence": None, "flags": []}
            continue
        models[name] = _model_entry(name, f, data, wheel, dmodels.get(name, dmodels.get(_FIT_ALIAS.get(name))))
    flags = [fl for fl in dd.get("flags") or [] if isinstance(fl, dict)]
    for name, m in models.items():
        m["flags"] = [fl for fl in flags if _canon(fl.get("model")) == name]
        for p, e in (m.get("parameters") or {}).items():
            e["flags"] = sorted({fl.get("kind") for fl in m["flags"]
                                 if p in str(fl.get("parameter") or "").split(",") or
                                 (fl.get("kind") == "at_bound" and fl.get("parameter") == p)} - {None})
            if e.get("at_bound") and "at_bound" not in e["flags"]:
                e["flags"].append("at_bound")
    probs = dd.get("probabilities") or {}
    for name, m in models.items():
        m["probability"] = probs.get(name, probs.get(_FIT_ALIAS.get(name)))
    worse = _worse_than_wong(models, list(data.channels))
    for k, v in worse.items():
        models[k]["worse_than_wong"] = v
    out = {
        "schema": SCHEMA,
        "input": list(inputs),
        "provenance": provenance or {},
        "terrain": _terrain_dict(terrain, wheel),
        "wheel": {"radius_m": wheel.radius, "width_m": wheel.width},
        "samples_used": data.n,
        "samples_read": data.n_input,
        "independent_units": data.n_units,
        "slip_min": data.slip_min,
        "channels": list(data.channels),
        "noise_sigma": dict(data.sigma),
        "time_sync": dict(time_sync) if time_sync else {"gnss_latency_s": None},
        "data_quality": list(data_quality or []),
        "models": models,
        "diagnosis": dd,
        "flags": flags,
        "gain": dict(diag.gain),
        "per_run": _per_run(diag),
        "binned_wong_residuals": diag.binned,
        "notes": list(getattr(diag, "notes", [])) + list(extra_notes or []),
        "not_done": list(getattr(diag, "failures", [])),
        "figures": list(figures or []),
        "figure_notes": dict(figure_notes or {}),
        "metric_definitions": _definitions(data, dd),
    }
    out = _clean(out)
    out["findings"] = findings(out)
    return out


# ============================================================================ findings (text from the numbers)


def _test_level(rep, t: dict) -> tuple[float | None, float | None, str]:
    """``(p, level, name of p)`` a structure test is judged by: Holm's adjusted p against the family level
    (``p_holm``, module :mod:`wheelsoil.model.diagnosis`); a report written before it existed used
    Bonferroni: the raw p against alpha over the number of tests (the load test was once separate)."""
    d = rep["diagnosis"]
    alpha = (d.get("thresholds") or {}).get("alpha")
    if "p_holm" in t:
        return t["p_holm"], alpha, "Holm-adjusted p"
    tests = (d.get("structure_tests") or {}).get("wong") or {}
    n = len(tests) if any("@" in k for k in tests) else len(tests) + (1 if d.get("load_test") else 0)
    return t.get("p"), (alpha / max(1, n) if alpha is not None else None), "p"




def structure_statements(rep) -> list:
    """One sentence per channel on Wong's residual structure, from the test numbers and the rule's
    thresholds: significant and large enough / significant but too small (which size rule failed) /
    not significant.  Returns list of dicts ``{test, channel, kind, text}`` (kind: ``systematic``,
    ``small``, ``not_significant``, ``untested``)."""
    d = rep["diagnosis"]
    th = d.get("thresholds") or {}
    tests = (d.get("structure_tests") or {}).get("wong") or {}
    alpha = th.get("alpha")
    min_s, min_r = th.get("min_effect_sigma"), th.get("min_effect_rel")
    out = []
    if alpha is None or not tests:
        return out
    for key, t in tests.items():
        c = t.get("channel") or key.partition("@")[0]
        p, lvl, adj = _test_level(rep, t)
        es, er, ea = t.get("effect_sigma"), t.get("effect_rel"), t.get("effect_abs")
        ch = structure_title(key)
        if p is None:
            out.append({"test": key, "channel": c, "kind": "untested", "text": f"{ch}: too few independent units to test."})
            continue
        size = (f"{_chan_fmt(ea, c)} RMS, {num(es, 2)} noise sigma, {num(100 * er, 2) if er is not None else 'n/a'} % "
                f"of the channel's magnitude")
        if p < lvl:
            fails = []
            if min_s is not None and (es is None or es < min_s):
                fails.append(f"{num(es, 2)} sigma < {num(min_s, 2)} sigma")
            if min_r is not None and (er is None or er < min_r):
                fails.append(f"{num(100 * er, 2) if er is not None else 'n/a'} % < {num(100 * min_r, 2)} %")
            if fails:
                out.append({"test": key, "channel": c, "kind": "small", "text":
                            f"{ch}: statistically significant ({adj} = {num(p, 2)} < {num(lvl, 2)}) but too small to "
                            f"attribute to a cause ({size}; size rule failed: {'; '.join(fails)})."})
            else:
                out.append({"test": key, "channel": c, "kind": "systematic", "text":
                            f"{ch}: systematic ({adj} = {num(p, 2)} < {num(lvl, 2)}) and large enough ({size})."})
        else:
            out.append({"test": key, "channel": c, "kind": "not_significant", "text":
                        f"{ch}: not significant ({adj} = {num(p, 2)} >= {num(lvl, 2)}; {size})."})
    return out


def worse_than_wong_rows(rep) -> list:
    """Every (model, channel) on which a fitted model is worse than Wong, in the report's model order:
    list of dicts ``model, channel, where`` ("in sample and out of sample"), ``r0`` and ``cv_r0``
    (Wong's and the model's R0 in the channel's display unit, str pairs), ``reason`` and ``text``
    (the sentence of :func:`findings`)."""
    w = (rep["models"].get("wong") or {}).get("per_channel") or {}
    rows = []
    for k, chans in sorted(((k, v.get("worse_than_wong")) for k, v in rep["models"].items()
                            if v.get("worse_than_wong")), key=lambda kv: _model_order(kv[0])):
        pc = rep["models"][k]["per_channel"]
        for c, v in chans.items():
            where = " and ".join(x for x, flag in (("in sample", v["in_sample"]), ("out of sample", v["out_of_sample"]))
                                 if flag)
            r0 = (_chan_fmt(_r0(w, c), c), _chan_fmt(_r0(pc, c), c))
            cv = (_chan_fmt(_r0(w, c, True), c), _chan_fmt(_r0(pc, c, True), c))
            rows.append({"model": k, "channel": c, "where": where, "r0": r0, "cv_r0": cv, "reason": v["reason"],
                         "text": f"{_title(k)} is worse than Wong on the {CHANNEL_TITLES.get(c, c)} {where} "
                                 f"(R0 {r0[0]} -> {r0[1]}, out of sample {cv[0]} -> {cv[1]}): {v['reason']}."})
    return rows


def findings(rep) -> list:
    """The report's own statements around the diagnosis summary, each generated from the numbers it
    cites (list of str): the structure test per channel, what the chosen model does per channel, the
    models worse than Wong and why, the terrain parameters fitted/held fixed, the flags."""
    d = rep["diagnosis"]
    out = [s["text"] for s in structure_statements(rep)]
    lt = d.get("load_test")
    if lt and lt.get("p") is not None and lt.get("slope") is not None:
        out.append(f"Drawbar pull error against load: slope {num(lt.get('slope'), 2)} per N "
                   f"(p = {num(lt.get('p'), 2)}).")
    chosen = _canon(d.get("model"))
    m = rep["models"].get(chosen) if chosen else None
    w = rep["models"].get("wong") or {}
    if chosen and chosen != "wong" and m and m.get("per_channel"):
        for c in rep["channels"]:
            a, b = _r0(w.get("per_channel") or {}, c, True), _r0(m["per_channel"], c, True)
            if a is None or b is None:
                continue
            verb = "lowers" if b < a else ("raises" if b > a else "leaves")
            out.append(f"{_title(chosen)} {verb} the out-of-sample {CHANNEL_TITLES.get(c, c)} error: "
                       f"{_chan_fmt(a, c)} (Wong) -> {_chan_fmt(b, c)}.")
    out.extend(r["text"] for r in worse_than_wong_rows(rep))
    shown = chosen if chosen in rep["models"] else "wong"
    if d.get("fit_terrain") and (rep["models"].get(shown) or {}).get("params") is not None:
        mm = rep["models"][shown]
        fitted = list(mm.get("terrain_fitted") or [])
        fixed = list(mm.get("terrain_held_fixed") or [])
        out.append(f"Terrain parameters fitted in {_title(shown)}: {', '.join(fitted) or 'none'}; held at the "
                   f"given terrain's values: {', '.join(fixed) or 'none'} (as in the coefficient table).")
    flags = rep.get("flags") or []
    for fl in flags:
        if _canon(fl.get("model")) == chosen:
            par = f", {fl['parameter']}" if fl.get("parameter") else ""
            out.append(f"Flag on the chosen model ({fl.get('kind')}{par}): {fl.get('detail') or ''}".rstrip(": "))
    others = sorted({_canon(fl.get("model")) for fl in flags if _canon(fl.get("model")) != chosen} - {None},
                    key=_model_order)
    if others:
        out.append(f"{sum(_canon(fl.get('model')) != chosen for fl in flags)} flag(s) on other models ("
                   + ", ".join(_title(k) for k in others) + "): see the coefficient table and Flags.")
    return out


# ============================================================================ figures


def exclusion_masks(signals, slip_min: float, excluded_spans=None, used=None) -> tuple:
    """Why each sample of a processed recording is or is not used by the fit.

    ``signals``: DataFrame of :func:`wheelsoil.processing.process_recording`
    (``t_s, slip, load_n, drawbar_pull_n, phase, valid``); ``slip_min`` as
    given to the fit; ``excluded_spans``: processing's ``ProcessResult.excluded``
    (``{t0_s, t1_s, reason}``).  The selection is that of
    :func:`wheelsoil.model.fit.prepare_data` (valid, finite s/W/Dp,
    slip_min < s < 1, W > 0).

    Returns ``(used (N,) bool, {reason: (N,) bool})``; reasons overlap (a
    standstill sample has no slip either).
    """
    from .data import _ZERO_SLIP, DRIVING_PHASES

    t = signals["t_s"].to_numpy(float)
    s = signals["slip"].to_numpy(float)
    w = signals["load_n"].to_numpy(float)
    dp = signals["drawbar_pull_n"].to_numpy(float)
    valid = signals["valid"].fillna(False).astype(bool).to_numpy() if "valid" in signals else np.ones(t.size, bool)
    phase = signals["phase"].astype(str).to_numpy() if "phase" in signals else np.full(t.size, "")
    fin = np.isfinite(s) & np.isfinite(w) & np.isfinite(dp)
    cyc = signals["cycle"].to_numpy(float) if "cycle" in signals else np.zeros(t.size)
    with np.errstate(invalid="ignore"):
        driving = valid & fin & (s > slip_min) & (s < 1.0) & (w > 0)
        steady = np.isin(phase, DRIVING_PHASES)
        outside = driving & ~(cyc >= 0) & ~steady if (cyc >= 0).any() else np.zeros(t.size, bool)
        given = used is not None
        used = np.asarray(used, bool) if given else driving & ~outside
        reasons = {
            "marked invalid by processing": ~valid,
            "standstill": phase == "standstill",
            "no slip (r omega < 0.1 m/s) or no W/Dp": valid & ~fin,
            "skid / braking (s < 0)": valid & fin & (s < -_ZERO_SLIP),
            "s ~ 0": valid & fin & (np.abs(s) <= _ZERO_SLIP),
            f"0 < s <= slip_min = {slip_min:g}": valid & fin & (s > _ZERO_SLIP) & (s <= slip_min),
            "s >= 1 or W <= 0": valid & fin & ((s >= 1.0) | (w <= 0)),
            "outside the accelerate cycles, not driving steadily (transients)": outside,
        }
    for e in excluded_spans or []:
        try:
            t0, t1 = float(e.get("t0_s")), float(e.get("t1_s"))
        except (TypeError, ValueError):
            continue
        key = f"processing: {e.get('reason', 'excluded')}"
        m = (t >= t0) & (t <= t1)
        reasons[key] = reasons.get(key, np.zeros(t.size, bool)) | m
        if not given:
            used &= ~m
    listed = np.zeros(t.size, bool)
    for v in reasons.values():
        listed |= v
    reasons["other (the fit's own selection)"] = ~used & ~listed
    return used, {k: v for k, v in reasons.items() if v.any()}


def _runs(mask: np.ndarray) -> list:
    """(start, stop) index pairs of the True runs of a bool array."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    d = np.diff(m.astype(np.int8))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


_PHASE_COLORS = {"accel": ("#2ca02c", "shaded: accelerate phase"), "drive": ("#bcbd22", "shaded: steady driving"),
                 "brake": ("#d62728", "shaded: brake phase"),
                 "standstill": ("#7f7f7f", "shaded: standstill")}
#: characters per line of a reason in the overview's exclusion strip (longer ones wrap)
_STRIP_WRAP = 140
#: the overview's exclusion strip, in its own y units: a label line, a bar (and the gap under it)
_STRIP_LINE, _STRIP_BAR = 0.5, 0.9
_STRIP_IN = 0.36  #: inches of figure height per strip y unit (a label line of 8 pt fits in _STRIP_LINE)


def _strip_layout(keys) -> tuple:
    """The exclusion strip's rows: ``(lines, label_top, bar_centre)`` per reason (y grows downwards) and
    the strip's height in its y units. Each reason is written in full over its bar, wrapped, so a long one
    takes lines, not the plots' width."""
    rows, y = [], 0.0
    for k in keys:
        lines = textwrap.wrap(str(k), _STRIP_WRAP, break_long_words=True) or [str(k)]
        top = y
        y += _STRIP_LINE * len(lines)
        rows.append((lines, top, y + 0.4 * _STRIP_BAR))
        y += _STRIP_BAR
    return rows, max(y, 1.0)


def overview_figure(signals, wheel_radius_m: float, slip_min: float, excluded_spans, path: Path, title: str,
                    plt, used=None) -> dict:
    """The run at a glance: V and r*omega, slip, W, Dp, T against time, phases shaded, and a strip of
    the spans excluded from the fit with their reasons.  Writes ``path``; returns
    ``{"used": n, "samples": N, "excluded": {reason: n}}``.

    The plots take the figure's width whatever the reasons: each reason is written over its bar in the
    strip (wrapped when long), not beside it, and what the shading means is said in a legend under the
    plots."""
    from matplotlib.patches import Patch

    t = signals["t_s"].to_numpy(float)
    used, reasons = exclusion_masks(signals, slip_min, excluded_spans, used)
    phase = signals["phase"].astype(str).to_numpy() if "phase" in signals else np.full(t.size, "")
    keys = list(reasons)
    rows, strip_units = _strip_layout(keys)
    panel_in = 2.3
    strip_in = 0.5 + _STRIP_IN * strip_units
    fig, axes = plt.subplots(6, 1, figsize=(12, 5 * panel_in + strip_in + 2.6), sharex=True, layout="constrained",
                             gridspec_kw={"height_ratios": [1, 1, 1, 1, 1, strip_in / panel_in]})

    def shade(ax):
        for ph, (col, _) in _PHASE_COLORS.items():
            m = phase == ph
            if m.any():
                ax.fill_between(t, 0, 1, where=m, transform=ax.get_xaxis_transform(), color=col, alpha=0.10,
                                lw=0, step="mid")

    v = signals["speed_mps"].to_numpy(float) if "speed_mps" in signals else np.full(t.size, np.nan)
    om = signals["omega_radps"].to_numpy(float) if "omega_radps" in signals else np.full(t.size, np.nan)
    ax = axes[0]
    ax.plot(t, v, color="#1f77b4", lw=1.2, label="V (GNSS, latency removed)")
    ax.plot(t, wheel_radius_m * om, color="#ff7f0e", lw=1.0, ls="--", label=f"r omega (r = {num(wheel_radius_m)} m)")
    ax.set_ylabel("speed [m/s]")
    s = signals["slip"].to_numpy(float)
    ax = axes[1]
    ax.plot(t, s, color="#bbbbbb", lw=0.8, label="slip s, all samples (Eq. 6)")
    ax.plot(t[used], s[used], ".", ms=1.5, color="#000000", label="samples used in the fit")
    ax.axhline(slip_min, color="#9467bd", ls=":", lw=1.2, label=f"slip_min = {slip_min:g}")
    ax.set_ylabel("slip s [-]")
    lo, hi = np.nanpercentile(s, [0.5, 99.5]) if np.isfinite(s).any() else (-1, 1)
    ax.set_ylim(max(lo - 0.05, -1.5), min(hi + 0.05, 1.5))
    for ax, col, lab, unit, c in ((axes[2], "load_n", "vertical load W", "N", "#8c564b"),
                                  (axes[3], "drawbar_pull_n", "drawbar pull Dp", "N", "#2ca02c"),
                                  (axes[4], "torque_nm", "torque T", "N m", "#d62728")):
        y = signals[col].to_numpy(float) if col in signals else np.full(t.size, np.nan)
        ax.plot(t, y, color=c, lw=0.9, label=f"{lab} (WFT)")
        ax.set_ylabel(f"{lab.split()[-1]} [{unit}]")
        if not np.isfinite(y).any():
            ax.text(0.5, 0.5, "not measured", transform=ax.transAxes, ha="center", va="center", color="#888")
    handles = [Patch(color=col, alpha=0.25, label=lab) for ph, (col, lab) in _PHASE_COLORS.items() if (phase == ph).any()]
    for ax in axes[:5]:
        shade(ax)
        ax.grid(alpha=0.3)
        h, lab = ax.get_legend_handles_labels()
        _legend(ax, handles=h, labels=lab, markerscale=4.0, fontsize=8, loc="lower left", bbox_to_anchor=(0.0, 1.0),
                ncol=max(min(len(h), 4), 1), frameon=False, borderaxespad=0.1)
    if handles:  # the phase shading of every panel, said once under the plots (a legend of the figure)
        leg = fig.legend(handles=handles, labels=[x.get_label() for x in handles], loc="outside lower center",
                         ncol=len(handles), fontsize=8, frameon=False, title="background of the five panels above",
                         title_fontsize=8)
        for h in getattr(leg, "legend_handles", []):
            h.set_alpha(0.25)
    # exclusion strip: each reason in full over its bar
    ax = axes[5]
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    ytr = ax.get_yaxis_transform()  # x in axes, y in data
    for i, (k, (lines, top, mid)) in enumerate(zip(keys, rows)):
        segs = [(t[a], max(t[b - 1] - t[a] + dt, dt)) for a, b in _runs(reasons[k])]
        col = _PALETTE[i % len(_PALETTE)]
        ax.broken_barh(segs, (mid - 0.35 * _STRIP_BAR, 0.7 * _STRIP_BAR), color=col, label=k)
        ax.text(0.004, top + 0.05, "\n".join(lines), transform=ytr, ha="left", va="top", fontsize=8,
                color="#222222", linespacing=1.1, clip_on=True,
                bbox={"facecolor": "white", "alpha": 0.75, "edgecolor": "none", "pad": 0.5})
    ax.set_yticks([])
    ax.set_ylim(strip_units + 0.05, -0.05)  # the first reason on top
    ax.set_title("excluded from the fit (a sample may have several reasons)", fontsize=9, loc="left")
    if not keys:
        ax.text(0.5, 0.5, "nothing excluded", transform=ax.transAxes, ha="center", va="center")
    ax.set_xlabel("time t [s] since the first frame")
    ax.grid(alpha=0.3, axis="x")
    fig.suptitle(title, fontsize=11)
    _save(fig, path, plt)
    return {"samples": int(t.size), "used": int(used.sum()),
            "excluded": {k: int(v.sum()) for k, v in reasons.items()}}


def _model_curves(diag, wheel, slip_grid, load):
    """name -> WheelForces on a slip grid at one load (models that cannot be evaluated are skipped)."""
    from wheelsoil.model import get_model

    out = {}
    for k in _fit_names(diag):
        f = _fit_of(diag, k)
        try:
            if hasattr(f, "curve"):  # hypothesis fits evaluate themselves (drift: mid-run)
                out[k] = f.curve(np.full(slip_grid.size, load), slip_grid)
                continue
            mobj = get_model(f.model)
            mp = {p: v for p, v in f.params.items() if p in {q.name for q in mobj.params}}
            out[k] = mobj.predict(f.terrain, wheel, np.full(slip_grid.size, load), slip_grid, mp)
        except (ValueError, KeyError, TypeError):
            continue
    return out


def overlapping_groups(curves: dict, rtol: float = 0.005, atol: float = 0.0) -> list:
    """Group curves (name -> (M,) array) that overlap: max |a - b| <= atol + rtol * (range of all
    curves).  Returns a list of name lists, in the input order; a curve overlaps itself only."""
    names = list(curves)
    if not names:
        return []
    allv = np.concatenate([np.asarray(curves[k], float)[np.isfinite(curves[k])] for k in names] or [np.zeros(1)])
    span = float(np.ptp(allv)) if allv.size else 0.0
    tol = atol + rtol * max(span, 1e-12)
    groups: list[list] = []
    for k in names:
        y = np.asarray(curves[k], float)
        for g in groups:
            yg = np.asarray(curves[g[0]], float)
            ok = np.isfinite(y) & np.isfinite(yg)
            if ok.any() and np.array_equal(np.isfinite(y), np.isfinite(yg)) and np.max(np.abs(y[ok] - yg[ok])) <= tol:
                g.append(k)
                break
        else:
            groups.append([k])
    return groups


def _figures(diag, wheel, out_dir: Path, plt) -> tuple:
    """dp_vs_slip.png, residuals.png, sinkage_vs_slip.png; returns (paths, {file: [notes]})."""
    data = diag.data
    s, dp = data.slip, data.channels["drawbar_pull_n"]
    big = data.n > 500
    # every k-th sample is drawn (at most MAX_POINTS per panel; the numbers use all of them)
    step = max(1, int(math.ceil(data.n / MAX_POINTS)))
    sub = np.arange(0, data.n, step)
    meas = dict(s=5 if big else 28, alpha=0.3 if big else 0.9, color="#9a9a9a", lw=0, marker="o")
    load = float(np.median(data.load_n))
    grid = np.linspace(max(data.slip_min, 1e-3), min(float(s.max()) + 0.02, 0.98), 120)
    curves = _model_curves(diag, wheel, grid, load)
    files, notes = [], {}

    # 1. Dp vs slip, one panel per model that matters (paper Figs. 4-5)
    fitted = _fit_names(diag)
    names = _figure_names(diag, fitted)
    left = len(fitted) - len(names)
    if left:
        notes["dp_vs_slip.png"] = [f"{left} other fitted model(s), each with posterior probability below "
                                   f"{FIG_MIN_PROBABILITY:.0%}, are in the models table, not drawn"]
    ncol = 3 if len(names) > 2 else len(names)
    nrow = int(math.ceil(len(names) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.6 * ncol, 4.6 * nrow), squeeze=False, sharey=True)
    order = sub[np.argsort(s[sub], kind="stable")]
    palette = _distinct_colors(names)
    for i, (ax, k) in enumerate(zip(axes.flat, names)):
        f = _fit_of(diag, k)
        col = palette[i]
        ax.plot(s[order[::3]], f.predictions["drawbar_pull_n"][order[::3]], "x", ms=2.5 if big else 5, mew=0.8, color=col,
                alpha=0.4 if big else 1.0, label="model at each sample's measured W", zorder=2)
        ax.scatter(s[sub], dp[sub], label="measured Dp", zorder=3, **meas)
        if k in curves:
            ax.plot(grid, curves[k].drawbar_pull_n, "-", color=col, lw=2.2, label=f"model curve at W = {fmt(load, 'force')}")
        m = f.metrics
        ax.set_title(f"{_title(k)}\nM0 {fmt(m.get('M0_pct'), 'percent')}   R0 {fmt(m.get('R0_n'), 'force')}   "
                     f"CV R0 {fmt(f.cv_R0_n, 'force')}   R² {num(m.get('R2'))}", fontsize=10)
        ax.set_xlabel("slip s [-]")
        ax.grid(alpha=0.3)
        _legend(ax, fontsize=8, loc="best")
    for ax in axes[:, 0]:
        ax.set_ylabel("drawbar pull Dp [N]")
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    fig.tight_layout()
    files.append(_save(fig, out_dir / "dp_vs_slip.png", plt))

    # 2. Wong's residuals vs slip (binned means, CI), vs load, vs time
    chans = list(data.channels)
    wong = diag.fits["wong"]
    fig, axes = plt.subplots(len(chans), 3, figsize=(16, 4.2 * len(chans)), squeeze=False)
    scale = {"drawbar_pull_n": (1.0, "N"), "torque_nm": (1.0, "N m"), "sinkage_m": (1e3, "mm")}
    t = data.t_s if data.t_s is not None else np.arange(data.n)
    for i, c in enumerate(chans):
        k, unit = scale.get(c, (1.0, ""))
        e = (data.channels[c] - wong.predictions[c]) * k
        b = diag.binned[c]
        ax = axes[i, 0]
        ax.scatter(s[sub], e[sub], label="measured - Wong, per sample", **meas)
        if b["mean"]:
            mean = np.array(b["mean"], float)
            ax.errorbar(b["slip"], mean * k,
                        yerr=np.abs(np.vstack([mean - np.array(b["lo"], float), np.array(b["hi"], float) - mean])) * k,
                        fmt="s-", color="#d62728", capsize=3, label="binned mean of independent units, 95 % CI")
        ax.axhline(0, color="k", lw=0.8, label="zero error")
        p = ((getattr(diag, "structure", {}) or {}).get("wong", {}).get(c) or {}).get("p")
        ax.set_title(f"Wong's {CHANNEL_TITLES.get(c, c)} error vs slip (structure test p = {num(p, 2)})", fontsize=10)
        ax.set_xlabel("slip s [-]")
        ax.set_ylabel(f"measured - Wong [{unit}]")
        _legend(ax, fontsize=8)
        axes[i, 1].scatter(data.load_n[sub], e[sub], label="measured - Wong, per sample", **meas)
        axes[i, 1].axhline(0, color="k", lw=0.8, label="zero error")
        axes[i, 1].set_xlabel("vertical load W [N]")
        axes[i, 1].set_title(f"vs load", fontsize=10)
        axes[i, 2].scatter(t[sub], e[sub], label="measured - Wong, per sample", **meas)
        axes[i, 2].axhline(0, color="k", lw=0.8, label="zero error")
        axes[i, 2].set_xlabel("time t [s]" if data.t_s is not None else "table row")
        axes[i, 2].set_title("vs time" if data.t_s is not None else "vs row order", fontsize=10)
        for ax in axes[i, 1:]:
            _legend(ax, fontsize=8)
        for ax in axes[i]:
            ax.grid(alpha=0.3)
    fig.tight_layout()
    files.append(_save(fig, out_dir / "residuals.png", plt))

    # 3. sinkage vs slip per model; overlapping curves drawn once
    fig, ax = plt.subplots(figsize=(10, 6.0 + 0.22 * (len(names) + 2)), layout="constrained")
    if "sinkage_m" in data.channels:
        ax.scatter(s[sub], data.channels["sinkage_m"][sub] * 1e3, label="measured z", **meas)
    zc = {k: curves[k].sinkage_m * 1e3 for k in names if k in curves}
    groups = overlapping_groups(zc)
    ov = []
    colors = _distinct_colors([g[0] for g in groups])
    for i, g in enumerate(groups):
        lab = " = ".join(_title(k) for k in g)
        if len(g) > 1:
            lab += " (curves overlap)"
            ov.append(f"sinkage curves of {', '.join(_title(k) for k in g)} overlap (within 0.5 % of the plotted "
                      "range): drawn as one line")
        ax.plot(grid, zc[g[0]], "-", color=colors[i], lw=2.4 if len(g) > 1 else 2.0,
                label=textwrap.fill(lab, 90, subsequent_indent="   "))
    ax.set_xlabel("slip s [-]")
    ax.set_ylabel("sinkage z [mm]")
    ax.set_title(f"sinkage vs slip: model curves at W = {fmt(load, 'force')}"
                 + ("" if "sinkage_m" in data.channels else " (sinkage not measured)"), fontsize=10)
    ax.grid(alpha=0.3)
    h, lab = ax.get_legend_handles_labels()
    leg = fig.legend(h, lab, loc="outside lower center", ncol=1, fontsize=8, markerscale=2.0)
    for x in getattr(leg, "legend_handles", []):
        x.set_alpha(1.0)
    files.append(_save(fig, out_dir / "sinkage_vs_slip.png", plt))
    if ov:
        notes["sinkage_vs_slip.png"] = ov
    if step > 1:
        for f in ("dp_vs_slip.png", "residuals.png"):
            notes.setdefault(f, []).append(f"every {_ordinal(step)} of the {data.n} samples is drawn (all are used in the "
                                           "numbers)")
    if "sinkage_m" in data.channels and step > 1:
        notes.setdefault("sinkage_vs_slip.png", []).append(f"every {_ordinal(step)} sample is drawn")
    soil = _soil_figure(diag, out_dir / "soil_values.png", plt)
    if soil is not None:
        files.append(soil)
    return files, notes


def _soil_figure(diag, path: Path, plt) -> Path | None:
    """soil_values.png: the re-fit of all five lab values (``terrain``) against the lab, each value in lab
    standard deviations from its lab value (ln k_eq and ln K): the re-fitted value (the lab prior's pull
    included) and the data's own estimate with its 95 % interval (:func:`~wheelsoil.model.diagnosis.data_estimates`),
    over the band of the lab's stated uncertainty (1 sd) and ``LAB_Z`` sd.  Where would a user re-measure
    the soil, and is the soil what differs at all?  Returns the path, or None when the five-value re-fit was
    not fitted (``--fit-terrain``) or did not converge."""
    f = diag.fits.get("terrain")
    if f is None or not f.success or not f.prior:
        return None
    names = list(f.prior)
    z_fit, est = prior_z(f), data_estimates(f)
    x = np.arange(len(names))
    fig, ax = plt.subplots(figsize=(8.5, 4.6), layout="constrained")
    ax.axhspan(-1.0, 1.0, color="#2ca02c", alpha=0.15, label="the lab's stated uncertainty (1 sd)")
    for y in (-LAB_Z, LAB_Z):
        ax.axhline(y, color="#2ca02c", lw=0.8, ls="--", label=f"{LAB_Z:g} lab sd" if y > 0 else None)
    ax.axhline(0.0, color="k", lw=0.8)
    ax.plot(x, [z_fit[p] for p in names], "o", mfc="none", mec="#1f77b4", ms=9, mew=1.6,
            label="re-fitted value (lab prior included)")
    shown = [i for i, p in enumerate(names) if p in est]
    ax.errorbar([x[i] for i in shown], [est[names[i]][0] for i in shown],
                yerr=[1.96 * est[names[i]][1] for i in shown], fmt="s", color="#d62728", capsize=4,
                label="the data's own estimate (prior's pull undone), 95 %")
    for i, p in enumerate(names):
        if p not in est:
            ax.annotate("not constrained\nby the data", (x[i], 0.0), textcoords="offset points", xytext=(0, 12),
                        ha="center", fontsize=8, color="#555555")
    ax.set_xticks(x, [{"phi": "phi", "K": "K (ln)", "k_eq": "k_eq (ln)"}.get(p, p) for p in names])
    ax.set_ylabel("(value - lab) / lab sd")
    ax.set_title("The soil the data point at: all five lab values re-fitted, against the lab", fontsize=10)
    ax.grid(alpha=0.3, axis="y")
    _legend(ax, fontsize=8, loc="best", markerscale=1.0)
    return _save(fig, path, plt)


def _ordinal(k: int) -> str:
    return f"{k}{'th' if 10 <= k % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(k % 10, 'th')}"


def _legend(ax, **kw):
    """A legend whose markers are opaque and large enough to see (the points may be faint)."""
    from matplotlib.patches import Rectangle

    leg = ax.legend(markerscale=kw.pop("markerscale", 2.0), **kw)
    for h in getattr(leg, "legend_handles", getattr(leg, "legendHandles", [])):
        if isinstance(h, Rectangle):  # shading keeps its own transparency
            continue
        try:
            h.set_alpha(1.0)
        except AttributeError:
            pass
    return leg


def _save(fig, path: Path, plt) -> Path:
    fig.savefig(path, dpi=100, metadata={"Software": None})  # no version string: byte-stable output
    plt.close(fig)
    return path


# ============================================================================ HTML

_CSS = """
*{box-sizing:border-box}
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1200px;margin:1.2em auto;padding:0 1em;
color:#222;line-height:1.45}
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
h3{font-size:1.05em;margin-top:1.2em}
.scroll{overflow-x:auto;-webkit-overflow-scrolling:touch;max-width:100%}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right;vertical-align:top}th{background:#f0f0f0}
td:first-child,th:first-child,td.l{text-align:left}
.verdict{padding:.8em 1em;border-radius:6px;background:#eef5ff;border:1px solid #9bc}
.effect{font-size:1.3em;font-weight:bold}.verdict table{background:#fff}.full{font-size:.9em;color:#333}
.warn{background:#fff4e0;border:1px solid #e0b060;padding:.5em 1em;border-radius:6px}
.sim{background:#f3eefc;border:1px solid #a58bd0;padding:.5em 1em;border-radius:6px;margin:.6em 0}
.flag{color:#a40000;font-weight:bold;white-space:nowrap}
figure{margin:1em 0}figcaption{font-size:.9em;color:#444}
img{max-width:100%;height:auto;border:1px solid #ddd}
code{background:#f4f4f4;padding:0 .2em;word-break:break-all}
dl dt{font-weight:bold;margin-top:.4em}dl dd{margin-left:1.2em}
@media (max-width:640px){body{padding:0 .4em;font-size:15px}table{font-size:.8em}th,td{padding:.2em .35em}
.effect{font-size:1.1em}}
@media print{body{max-width:none;margin:0;font-size:10pt}.scroll{overflow:visible}
figure,table,.verdict{page-break-inside:avoid;break-inside:avoid}h2{page-break-after:avoid;break-after:avoid}
a{color:inherit;text-decoration:none}}
"""


def _e(x) -> str:
    return html.escape(str(x), quote=True)


def _glance(d: dict) -> str:
    """The verdict at a glance (HTML): each measured channel's out-of-sample error under Wong and the
    best supported model with the channel's own verdict, the effects' probabilities, and why the
    confidence is what it is; every number from ``d`` (``report.json``'s ``diagnosis``)."""
    rows = []
    out = _not_named(d)
    for c, v in (d.get("channels") or {}).items():
        if not isinstance(v, dict) or not v.get("measured"):
            continue
        best = v.get("best_cv_rmse")  # the error of the model compared on this channel: the named one, else
        shown = v.get("compared_model") or v.get("model")  # the channel's own (diagnosis, per-channel verdicts)
        rows.append([CHANNEL_TITLES.get(c, c), _chan_fmt(v.get("wong_cv_rmse"), c),
                     (f"{_chan_fmt(best, c)} ({_title(_canon(shown))})" if best is not None and shown
                      else "n/a (no model supported on this channel)"),
                     _effect_word(v.get("effect"))])
    if rows:
        out += _table(["channel", "Wong's error on new data (CV R0)", "the compared model's (named, else the "
                       "channel's best supported)", "this channel's verdict"], rows)
    probs = sorted(((k, p) for k, p in (d.get("effect_probabilities") or {}).items() if p is not None and p >= 1e-3),
                   key=lambda kp: -kp[1])
    if probs:
        hp = {k: p for k, p in (d.get("probabilities") or {}).items() if p is not None}
        top_h = max(hp, key=hp.get) if hp else None
        own = ((d.get("models") or {}).get(top_h) or {}).get("effect")
        counted = ""
        if own and own != probs[0][0] and top_h is not None:
            counted = (f" The most probable hypothesis, {TITLES.get(_canon(top_h), top_h)} ({num(hp[top_h], 2)}), counts "
                       f"for {_effect_word(probs[0][0])}: what it adds does not improve its predictions of new data.")
        out += ("<p>Probability of each effect, over the hypotheses tried: "
                + _e(", ".join(f"{_effect_word(k)} {num(p, 2)}" for k, p in probs)) + "." + _e(counted)
                + (" A probable effect is named only when its model also holds on new data and against the "
                   "causes on no list that act alike (below)." if probs[0][0] != d.get("effect") else "") + "</p>")
    why = d.get("confidence_reasons") or []
    if why:
        out += (f"<p>Confidence {_e(d.get('confidence'))}:</p><ul>"
                + "".join(f"<li>{_e(x)}</li>" for x in why) + "</ul>")
    return out


def _not_named(d: dict) -> str:
    """When no cause is named (``none``, ``unexplained``) but an effect is the most probable: one line (HTML)
    saying which, with its probability, and why the rule does not name it (``d["why"]``, a code of
    :data:`~wheelsoil.model.diagnosis.WHY_UNEXPLAINED`; for ``none``: no structure of relevant size in
    Wong's residuals), so the probabilities under the headline do not read as a contradiction of it."""
    eff = d.get("effect")
    probs = {k: p for k, p in (d.get("effect_probabilities") or {}).items()
             if p is not None and k not in ("none", "unexplained")}
    if eff not in ("none", "unexplained") or not probs:
        return ""
    top = max(probs, key=probs.get)
    if probs[top] < 0.5:
        return ""
    why = (WHY_UNEXPLAINED.get(d.get("why"), d.get("why")) if eff == "unexplained" else
           "Wong's residuals show no systematic error of relevant size (the structure tests, thresholds below): "
           "the rule names a cause only for an error it can see")
    return (f"<p><b>Not named:</b> the most probable effect is {_e(_effect_word(top))} (probability "
            f"{_e(num(probs[top], 2))}), but {_e(why or 'the rule did not name it')}.</p>")


def _effect_word(effect) -> str:
    """An effect's words for the reader (``slip_sinkage`` -> "slip sinkage"; report.json keeps the codes)."""
    return EFFECT_TITLES.get(effect, str(effect or "n/a").replace("_", " "))


def _table(headers, rows, raw: bool = False) -> str:
    """A scrollable table; cells escaped unless ``raw`` (then the caller escaped them)."""
    h = "".join(f"<th>{_e(x)}</th>" for x in headers)
    cell = (lambda x: str(x)) if raw else _e
    body = "".join("<tr>" + "".join(f"<td>{cell(x)}</td>" for x in r) + "</tr>" for r in rows)
    return f"<div class='scroll'><table><thead><tr>{h}</tr></thead><tbody>{body}</tbody></table></div>"


def _img(path: Path, alt: str, caption: str = "") -> str:
    b64 = base64.b64encode(path.read_bytes()).decode("ascii")
    cap = f"<figcaption>{caption}</figcaption>" if caption else ""
    return f"<figure><img alt='{_e(alt)}' src='data:image/png;base64,{b64}'>{cap}</figure>"


def _flag_marks(flags: list) -> str:
    return "".join(f" <span class='flag' title='{_e(k)}'>[{_e(k.replace('_', ' '))}]</span>" for k in flags)


def _provenance_html(p: dict) -> str:
    if not p:
        return "<p>No provenance given (library call without it).</p>"
    parts = []
    cmd = p.get("command")
    rows = [["wheelsoil version", _e(p.get("version"))],
            ["command", f"<code>{_e(' '.join(map(str, cmd)))}</code>" if cmd else "n/a"],
            ["working directory", f"<code>{_e(p.get('cwd'))}</code>"],
            ["analysis time (UTC)", _e(p.get("created"))]]
    env = p.get("environment") or {}
    if env:
        rows.append(["environment", _e(", ".join(f"{k} {v}" for k, v in env.items()))])
    parts.append(_table(["item", "value"], rows, raw=True))
    parts.append("<h3>Inputs</h3>")
    irows = []
    for inp in p.get("inputs") or []:
        pv = inp.get("provenance") or {}
        kind = pv.get("kind", "unknown")
        detail = ", ".join(f"{k}: {v}" for k, v in pv.items() if k not in ("kind",) and v not in (None, "", []))
        irows.append([f"<code>{_e(inp.get('path'))}</code>", _e(kind), f"<code>{_e(inp.get('sha256'))}</code>",
                      _e(_plain(inp.get("size_bytes"))) + " bytes", _e(detail)])
    parts.append(_table(["path", "origin", "sha256", "size", "its own provenance"], irows, raw=True))
    vc = p.get("vehicle_config") or {}
    if vc:
        parts.append("<h3>Vehicle configuration used</h3>")
        rows = [["source", _e(vc.get("source"))]]
        for k, q in (("wheel_radius_m", "length_m"), ("wheel_width_m", "length_m"), ("wheel_mass_kg", "mass"),
                     ("wheel_inertia_kgm2", "inertia")):
            if k in vc:
                rows.append([_e(k), _e(fmt(vc.get(k), q))])
        if vc.get("sha256"):
            rows.append(["vehicle.toml sha256", f"<code>{_e(vc['sha256'])}</code>"])
        for dbc in vc.get("dbcs") or []:
            rows.append([f"DBC {_e(dbc.get('name'))}", f"<code>{_e(dbc.get('sha256'))}</code>"])
        parts.append(_table(["item", "value"], rows, raw=True))
    st = p.get("settings") or {}
    if st:
        parts.append("<h3>Settings</h3>")
        rows = []
        for k, v in st.items():  # 6 significant figures: the values a re-run must match
            if isinstance(v, dict):
                v = ", ".join(f"{a} = {_plain(b, 6)}" for a, b in v.items() if not isinstance(b, dict)) + "".join(
                    f"; {a}: " + ", ".join(f"{x} = {_plain(y, 6)}" for x, y in b.items())
                    for a, b in v.items() if isinstance(b, dict))
            elif isinstance(v, list):
                v = ", ".join(map(str, v))
            else:
                v = _plain(v, 6)
            rows.append([k, v])
        parts.append(_table(["setting", "value (SI)"], rows))
    return "".join(parts)


def _plain(v, sig: int = 3) -> str:
    """A value of a generic dict: integers as they are, floats by the one formatter."""
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return num(v, sig)
    return json.dumps(v, sort_keys=True) if isinstance(v, (dict, list)) else str(v)


#: key suffix -> unit of a value in a data-quality dict (longest first; ``_s`` is shown in ms below 1 s)
_KEY_UNITS = (("_kgm2", "kg m^2"), ("_radps", "rad/s"), ("_mps", "m/s"), ("_nm", "N m"), ("_ns", "ns"),
              ("_hz", "Hz"), ("_kg", "kg"), ("_rad", "rad"), ("_deg", "deg"), ("_n", "N"), ("_m", "m"), ("_s", "s"))
#: data-quality keys that are internal (shown through what they give: the WFT ripple's fitted coefficients
#: are its amplitudes and what was taken out)
_QUALITY_INTERNAL = {"coef"}
_TEETH_MAX = 1000  #: a tone wheel with more "teeth" than this is a pitch of ~0: none was found


def _key_unit(key: str) -> tuple[str, str]:
    """``("max abs force", "N")`` of ``"max_abs_force_n"``: the key in words and the unit its suffix names."""
    k = str(key)
    for suf, unit in _KEY_UNITS:
        if k.endswith(suf) and len(k) > len(suf):
            return k[: -len(suf)].replace("_", " "), unit
    return k.replace("_", " "), ""


def _time_scale(values) -> tuple[float, str]:
    """ms for times all below 1 s (latencies, lags), else s."""
    vals = [abs(float(v)) for v in values if isinstance(v, (int, float, np.integer, np.floating))
            and not isinstance(v, bool) and math.isfinite(float(v))]
    return (1e3, "ms") if vals and max(vals) < 1.0 else (1.0, "s")


def _qval(v, unit: str = "", se=None, sig: int = 3) -> str:
    """One value of a data-quality dict in words: a count as an integer, a number with 3 significant figures
    and its unit (``± se`` with 2), yes/no, lists and dicts as text (never ``{...}`` or ``[...]``)."""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if v is None:
        return "n/a"
    if isinstance(v, (int, np.integer, float, np.floating)):
        k, u = _time_scale([v]) if unit == "s" else (1.0, unit)
        txt = str(int(v)) if isinstance(v, (int, np.integer)) else num(float(v) * k, sig)
        if se is not None and isinstance(se, (int, float, np.integer, np.floating)) and not isinstance(se, bool):
            txt += f" ± {num(float(se) * k, 2)}"
        return f"{txt} {u}" if u else txt
    if isinstance(v, dict):
        return "; ".join(_qflat(v)) or "none"
    if isinstance(v, (list, tuple)):
        if not v:
            return "none"
        if all(isinstance(x, (list, tuple)) and len(x) == 2 and not any(isinstance(y, (list, tuple, dict, str))
                                                                      for y in x) for x in v):  # spans
            k, u = _time_scale([y for x in v for y in x]) if unit == "s" else (1.0, unit)
            end = (lambda y: num(float(y) * k) if isinstance(y, (int, float)) and not isinstance(y, bool)
                   else _qval(y))
            return ", ".join(f"{end(x[0])}-{end(x[1])}" for x in v) + (f" {u}" if u else "")
        if all(isinstance(x, dict) for x in v):
            return " | ".join(", ".join(_qflat(x)) or "none" for x in v)
        if unit and len(v) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):  # a range
            k, u = _time_scale(v) if unit == "s" else (1.0, unit)
            return f"{num(v[0] * k)} to {num(v[1] * k)} {u}"
        return ", ".join(_qval(x, unit) for x in v)
    return str(v)


def _qflat(d: dict, prefix: str = "") -> list:
    """``["key: value", ...]`` of a (nested) data-quality dict: nested keys are prefixed with their parent's,
    a unit suffix of a key becomes the value's unit, ``x`` and ``stderr_x`` (``estimate_x`` and ``stderr_x``)
    one ``x ± se``; empty notes and internal values are left out; a tone wheel of ~0 pitch says so."""
    out = []
    for k, v in d.items():
        ks = str(k)
        if ks in _QUALITY_INTERNAL or (isinstance(v, str) and not v.strip()):
            continue
        if ks.startswith("stderr_"):
            base = ks[len("stderr_"):]
            if base in d or f"estimate_{base}" in d:
                continue  # shown with its value
        name, unit = _key_unit(ks)
        if ks.startswith("estimate_"):
            name = _key_unit(ks[len("estimate_"):])[0] if ks != "estimate_s" else "estimate"
        label = f"{prefix}{name}"
        if ks == "teeth":
            ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and 0 < v <= _TEETH_MAX
            out.append(f"{prefix}tone wheel: " + (f"about {v:.0f} teeth" if ok else "none found (pitch ~0)"))
            continue
        if isinstance(v, dict) and v:
            out.extend(_qflat(v, f"{label} "))
            continue
        se_key = "stderr_" + (ks[len("estimate_"):] if ks.startswith("estimate_") else ks)
        out.append(f"{label}: {_qval(v, unit, d.get(se_key))}")
    return out


def _ms_pm(est, se) -> str:
    """``110.7 ± 3.1 ms`` of a latency [s] and its standard error."""
    if not isinstance(est, (int, float)) or isinstance(est, bool) or not math.isfinite(est):
        return "none"
    txt = f"{est * 1e3:.1f}"
    if isinstance(se, (int, float)) and not isinstance(se, bool) and math.isfinite(se):
        txt += f" ± {se * 1e3:.1f}"
    return txt + " ms"


def _latency_rows(lat) -> list:
    """processing's GNSS latency (``quality["latency"]``): the estimate, how and whether it is reliable, then
    each candidate method."""
    if not isinstance(lat, dict):
        return [["processing: GNSS latency", _qval(lat)]]
    how = [str(lat["method"])] if lat.get("method") else []
    if "reliable" in lat:
        why = "; ".join(str(r) for r in lat.get("reasons") or [])
        how.append("reliable" if lat["reliable"] else "unreliable" + (f": {why}" if why else ""))
    val = _ms_pm(lat.get("estimate_s"), lat.get("stderr_s")) + (f" ({'; '.join(how)})" if how else "")
    rest = {k: v for k, v in lat.items()
            if k not in ("estimate_s", "stderr_s", "method", "reliable", "reasons", "candidates")}
    if rest:
        val += "; " + "; ".join(_qflat(rest))
    rows = [["processing: GNSS latency", val]]
    cands = lat.get("candidates")
    if isinstance(cands, dict) and cands:
        parts = []
        for name, c in cands.items():
            if not isinstance(c, dict):
                parts.append(f"{name}: {_qval(c)}")
                continue
            bits = []
            if c.get("estimate_s") is not None:  # the parts of its standard error
                bits.append(", ".join(f"{w} {_ms_pm(c[k], None)}" for k, w in (("stderr_stat_s", "statistical"),
                                                                              ("systematic_s", "systematic"))
                                      if c.get(k) is not None))
            if c.get("n") is not None:
                bits.append(f"n = {_qval(c['n'])}")
            if "usable" in c:
                bits.append("usable" if c["usable"] else "not usable")
            if c.get("note"):
                bits.append(str(c["note"]))
            extra = {k: v for k, v in c.items() if k not in ("estimate_s", "stderr_s", "stderr_stat_s", "systematic_s",
                                                             "n", "usable", "note", "method")}
            bits = [b for b in bits + _qflat(extra) if b]
            parts.append(f"{name}: {_ms_pm(c.get('estimate_s'), c.get('stderr_s'))} (" + "; ".join(bits) + ")"
                         + (f", from {c['method']}" if c.get("method") else ""))
        rows.append(["processing: GNSS latency candidates", " | ".join(parts)])
    return rows


def _ripple_text(r) -> str:
    """The WFT ripple locked to the wheel angle: amplitude per channel and order, and which were taken out."""
    if r is None:
        return "not estimated (too few revolutions turned fast enough)"
    if not isinstance(r, dict):
        return _qval(r)
    removed = r.get("removed")
    parts, known = [], {"coef", "removed", "samples", "revolutions"}
    for ch, suf, unit, lab in (("fx", "n", "N", "Fx"), ("fz", "n", "N", "Fz"), ("my", "nm", "N m", "My")):
        items = []
        for o in (1, 2):
            key = f"{ch}_{o}x_{suf}"
            known.add(key)
            if r.get(key) is None:
                continue
            txt = f"{_ordinal(o)} order {num(r[key])} {unit}"
            if removed is not None:
                txt += " (taken out)" if f"{ch}_{o}x" in removed else " (left in)"
            items.append(txt)
        if items:
            parts.append(f"{lab}: " + ", ".join(items))
    seen = []
    if r.get("revolutions") is not None:
        seen.append(f"{num(r['revolutions'])} revolutions")
    if r.get("samples") is not None:
        seen.append(f"{_qval(r['samples'])} samples")
    txt = "; ".join(parts) or "no amplitudes"
    if seen:
        txt += " (over " + ", ".join(seen) + ")"
    if removed is not None and not removed:
        txt += "; none taken out"
    rest = {k: v for k, v in r.items() if k not in known}
    return txt + ("; " + "; ".join(_qflat(rest)) if rest else "")


def _lost_frames_text(pq: dict, lf: dict) -> str | None:
    """processing's lost-frame summary; the counts per message only where they differ from the rows above."""
    total, unknown, per = pq.get("lost_frames_known_total"), pq.get("lost_frames_unknown"), pq.get("lost_frames")
    if total is None and unknown is None and per is None:
        return None
    bits = []
    if total is not None:
        bits.append(f"{_qval(total)} known in total")
    if unknown:
        bits.append("count unknown for " + _qval(unknown))
    if isinstance(per, dict) and any((lf.get(m) or {}).get("lost") != n for m, n in per.items()):
        bits.append("per message: " + "; ".join(_qflat(per)))
    elif per is not None and not isinstance(per, dict):
        bits.append(_qval(per))
    return "; ".join(bits) or "none"


#: processing's quality keys -> their row label in report.html (others: "processing: " and the key in words)
_PROCESSING_LABELS = {"timestamps": "processing: timestamps", "wheel_speed_lag": "processing: wheel-speed lag",
                      "wft_ripple": "processing: WFT ripple locked to the wheel angle",
                      "damage": "processing: damaged chunks", "wft_angle_jumps": "processing: WFT angle jumps",
                      "gnss_degraded_spans_s": "processing: GNSS degraded spans"}


def _quality_rows(q: dict) -> list:
    rows = []
    if q.get("kind") == "table":
        rows.append(["rows read", _qval(q.get("rows"))])
        return rows
    rows.append(["duration", fmt(q.get("duration_s"), "time")])
    if q.get("wheel_radius_m") is not None:
        rows.append(["slip radius r (Eq. 6)", fmt(q["wheel_radius_m"], "length_mm")
                     + (f" ({q['wheel_radius_source']})" if q.get("wheel_radius_source") else "")])
    rows.append(["valid share (processing)", f"{num(100 * q['valid_share'], 3)} %" if q.get("valid_share") is not None
                 else "n/a"])
    if q.get("used_in_fit") is not None:
        rows.append(["samples used in the fit", f"{q['used_in_fit']} of {q.get('samples')}"])
    lf = q.get("lost_frames") or {}
    for msg in sorted(lf):
        v = lf[msg]
        if v.get("lost") is None:
            rows.append([f"lost frames {msg}", f"unknown ({v.get('method', '')}); {v.get('received')} received"])
        else:
            rows.append([f"lost frames {msg}", f"{v.get('lost')} of {(v.get('received') or 0) + v.get('lost')} "
                         f"({v.get('method', '')})"])
    if not lf:
        rows.append(["lost frames", "none counted"])
    rej = q.get("rejected_frames")
    rows.append(["rejected frames (import)", _qval(rej) if rej is not None else
                 ("none reported by the import" if q.get("imported") else "n/a (not imported)")])
    dmg = q.get("damaged_chunks") or []
    pdmg = (q.get("processing_quality") or {}).get("damage") or []
    if pdmg:
        lost = sum(int(d.get("frames_lost") or 0) for d in pdmg if isinstance(d, dict))
        rows.append(["damaged chunks", f"{len(pdmg)} skipped, {lost} frames lost"
                     + (": " + " | ".join(dmg) if dmg else "")])
    else:
        rows.append(["damaged chunks", "none" if not dmg else f"{len(dmg)}: " + " | ".join(dmg)])
    rows.append(["recording read to its end (MCAP footer)", {True: "yes", False: "no (truncated or damaged: see "
                                                              "above and the warnings)", None: "n/a"}[q.get("complete")]])
    rx = q.get("kernel_rx_dropped")
    if rx:
        rows.append(["kernel receive drops", ", ".join(f"{b}: {'unknown' if n is None else n}" for b, n in sorted(rx.items()))])
    g = q.get("gnss_fix") or {}
    if g:
        rows.append(["GNSS fix", "; ".join(_qflat(g)) if isinstance(g, dict) else _qval(g)])
    lat = q.get("gnss_latency_s")
    rows.append(["GNSS latency found and removed", "not estimated" if lat is None else
                 f"{fmt(lat, 'latency')} ± {fmt(q.get('gnss_latency_stderr_s'), 'latency', 2)} "
                 f"(reference: {q.get('latency_reference') or 'n/a'})"])
    ine = q.get("inertia") or {}
    if ine:
        rows.append(["inertia compensation", ("applied" if ine.get("applied") else "not applied") + "; "
                     + "; ".join(_qflat({k: v for k, v in ine.items() if k != "applied"}))])
    else:
        rows.append(["inertia compensation", "not reported by processing (not applied)"])
    pq = q.get("processing_quality") or {}
    lost = _lost_frames_text(pq, lf)
    for k, v in sorted(pq.items()):
        if k == "latency":
            rows += _latency_rows(v)
        elif k == "wft_ripple":
            rows.append([_PROCESSING_LABELS[k], _ripple_text(v)])
        elif k in ("lost_frames", "lost_frames_known_total", "lost_frames_unknown"):
            if lost is not None:
                rows.append(["processing: lost frames", lost])
                lost = None
        else:
            name, unit = _key_unit(k)
            rows.append([_PROCESSING_LABELS.get(k, f"processing: {name}"), _qval(v, unit)])
    spans = q.get("excluded_spans") or []
    if spans:
        rows.append(["spans excluded by processing", "; ".join(
            f"{num(e.get('t0_s'))}-{num(e.get('t1_s'))} s: {e.get('reason')}" for e in spans[:20])
            + (f"; ... {len(spans) - 20} more" if len(spans) > 20 else "")])
    for w in q.get("warnings") or []:
        rows.append(["warning", w])
    return rows


def _metrics_section(rep) -> list:
    parts = ["<h2>How well each model predicts (paper Tabs. 2 and 4)</h2>"]
    w = rep["models"]["wong"]
    wz = w.get("log_evidence")
    probs = (rep["diagnosis"].get("probabilities") or {})
    rows = []
    for k, m in rep["models"].items():
        mm = m["metrics"]
        dz = None if (m.get("log_evidence") is None or wz is None) else 2.0 * (m["log_evidence"] - wz)
        rows.append([_e(_title(k)), _e(fmt(mm.get("M0_pct"), "percent", unit=False)),
                     _e(fmt(mm.get("R0_n"), "force", unit=False)), _e(num(mm.get("R2"))),
                     _e(fmt(m.get("cv_R0_n"), "force", unit=False)), _e(num(m.get("cv_score"))),
                     _e("n/a" if dz is None or not np.isfinite(dz) else f"{dz:+.0f}"),
                     _e(num(m.get("probability"), 2) if m.get("probability") is not None else "-"),
                     _e(m["status"]) + _flag_marks(sorted({f.get("kind") for f in m.get("flags") or []} - {None}))])
    parts.append(_table(["model", "M0 [%]", "R0 Dp [N]", "R² Dp [-]", "CV R0 Dp [N]", "CV score [-]",
                         "2 ln(Z/Z_Wong) [-]", "probability [-]", "status, flags"], rows, raw=True))
    extra = {k: v for k, v in probs.items() if _canon(k) not in rep["models"]}
    if extra:
        parts.append("<p>Probabilities of the other hypotheses tried: "
                     + _e(", ".join(f"{_title(k)} {num(v, 2)}" for k, v in extra.items())) + ".</p>")
    # R^2 misleads: say so with the numbers
    r2 = {k: m["metrics"].get("R2") for k, m in rep["models"].items() if m["metrics"].get("R2") is not None}
    r0 = {k: m["metrics"].get("R0_n") for k, m in rep["models"].items() if m["metrics"].get("R0_n") is not None}
    if r2 and r0:
        best_r2, best_r0 = max(r2, key=r2.get), min(r0, key=r0.get)
        txt = []
        if best_r2 != best_r0:
            txt.append(f"R² ranks the models differently from R0 here (highest R²: {_title(best_r2)} "
                       f"{num(r2[best_r2])}; lowest R0: {_title(best_r0)} {fmt(r0[best_r0], 'force')})")
        low = [k for k, v in r2.items() if v < 0.1]
        if low:
            txt.append("R² is below 0.1 for " + ", ".join(f"{_title(k)} ({num(r2[k])}, R0 {fmt(r0.get(k), 'force')})"
                                                           for k in low)
                       + ": the samples' Dp varies little compared with the noise, so R² says little about accuracy")
        if txt:
            parts.append("<p class='warn'>" + _e("; ".join(txt)) + ". Compare models by R0 and CV R0.</p>")
    md = rep["metric_definitions"]
    parts.append("<dl>" + "".join(f"<dt>{_e(t)}</dt><dd>{_e(md[k])}</dd>" for t, k in (
        ("M0", "M0_pct"), ("R0", "R0"), ("R²", "R2"), ("CV R0", "cv_R0"), ("CV score", "cv_score"),
        ("2 ln(Z/Z_Wong)", "evidence"), ("probability", "probability"))) + "</dl>")
    # per channel
    chans = rep["channels"]
    parts.append("<h3>Per channel: in sample and out of sample</h3>")
    hdr = ["model"]
    for c in chans:
        u = _chan_unit(c)
        hdr += [f"R0 {CHANNEL_TITLES.get(c, c)} [{u}]", f"CV R0 {CHANNEL_TITLES.get(c, c)} [{u}]"]
    rows = []
    for k, m in rep["models"].items():
        pc = m.get("per_channel")
        if not pc:
            continue
        row = [_e(_title(k))]
        worse = m.get("worse_than_wong") or {}
        for c in chans:
            wv = worse.get(c) or {}
            row.append(_e(_chan_fmt(_r0(pc, c), c).replace(" " + _chan_unit(c), ""))
                       + (" <span class='flag'>[worse than Wong]</span>" if wv.get("in_sample") else ""))
            row.append(_e(_chan_fmt(_r0(pc, c, True), c).replace(" " + _chan_unit(c), ""))
                       + (" <span class='flag'>[worse than Wong]</span>" if wv.get("out_of_sample") else ""))
        rows.append(row)
    parts.append(_table(hdr, rows, raw=True))
    worse_rows = worse_than_wong_rows(rep)
    if worse_rows:
        parts.append("<p>Where a fitted model is worse than Wong, and why (R0 and CV R0: Wong -> the model):</p>")
        parts.append(_table(["model", "channel", "worse", "R0", "CV R0", "why"],
                            [[_title(r["model"]), CHANNEL_TITLES.get(r["channel"], r["channel"]), r["where"],
                              " -> ".join(r["r0"]), " -> ".join(r["cv_r0"]), r["reason"]] for r in worse_rows]))
    dch = rep["diagnosis"].get("channels") or {}
    if dch:
        parts.append("<h3>Verdict per channel</h3>")
        keys = sorted({k for v in dch.values() if isinstance(v, dict) for k in v})
        first = [k for k in ("effect", "measured", "wong_cv_rmse", "best_cv_rmse", "improves", "worsens") if k in keys]
        keys = first + [k for k in keys if k not in first]
        rows = []
        for c, v in dch.items():
            v = v if isinstance(v, dict) else {"value": v}
            rows.append([CHANNEL_TITLES.get(c, c)] + [
                (_chan_fmt(v.get(k), c) if k.endswith(("rmse", "sigma_cell"))
                 else _title(_canon(v.get(k))) if k in ("model", "compared_model") and v.get(k)
                 else _effect_word(v.get(k)) if k == "effect" and v.get(k)
                 else {True: "yes", False: "no"}[v.get(k)] if isinstance(v.get(k), bool)
                 else num(v.get(k), 2) if isinstance(v.get(k), float)
                 else ("-" if v.get(k) is None else str(v.get(k))))
                for k in keys])
        names = {"effect": "effect", "measured": "measured", "wong_cv_rmse": "Wong CV R0 (channel unit)",
                 "best_cv_rmse": "model CV R0 (channel unit)", "improves": "model improves it out of sample",
                 "worsens": "model worsens it out of sample", "compared_model": "model compared",
                 "model": "model", "gain_noise_var": "held-out gain [noise variances per cell]",
                 "noise_sigma_cell": "cell noise sigma (channel unit)", "p_improve": "p (improves)",
                 "p_worse": "p (worsens)", "structure_p": "p (Wong's structure)"}
        parts.append(_table(["channel"] + [names.get(k, k.replace("_", " ")) for k in keys], rows))
    return parts


def _coefficients_section(rep) -> list:
    parts = ["<h2>Fitted coefficients (paper Tab. 3), ± standard error, with flags</h2>"]
    rows = []
    for k, m in rep["models"].items():
        ps = m.get("parameters")
        if not ps:
            rows.append([_e(_title(k)), "(no free parameters)" if m["status"] == "ok" else _e(m["status"]),
                         _e(", ".join(m.get("terrain_fitted") or []) or "-"),
                         _e(", ".join(m.get("terrain_held_fixed") or []) or "-"), "-"])
            continue
        cells = []
        for p, e in ps.items():
            v, se = e.get("value"), e.get("se")
            vague = v is not None and se is not None and np.isfinite(se) and abs(se) > abs(v) > 0
            cells.append(f"{_e(p)} = {_e(fmt_param(p, v, se))}" + (" <i>(SE &gt; |value|: not told from 0)</i>"
                                                                   if vague else "")
                         + _flag_marks(e.get("flags") or []))
        fitted_t = m.get("terrain_fitted") or []
        fixed = ", ".join(m.get("terrain_held_fixed") or []) or "-"
        cn = m.get("condition_number")
        cn_txt = _e(num(cn)) + (_flag_marks(["ill_conditioned"]) if any(
            f.get("kind") == "ill_conditioned" for f in m.get("flags") or []) else "")
        rows.append([_e(_title(k)), "<br>".join(cells), _e(", ".join(fitted_t) or "-"), _e(fixed), cn_txt])
    parts.append(_table(["model", "parameters (display units)", "terrain fitted", "terrain held at the given values",
                         "condition no. [-]"], rows, raw=True))
    parts.append("<p>Units: c in kPa, phi in degrees, K, H and sinkage in mm, kc in kN/m^(n+1), kphi and "
                 "k_eq = kc/b + kphi in kN/m^(n+2), n, n1, m1, m2 dimensionless. report.json has every value in "
                 "SI (phi in rad, lengths in m, moduli in N).</p>")
    flags = rep.get("flags") or []
    parts.append("<h3>Flags</h3>")
    if flags:
        parts.append(_table(["model", "parameter", "kind", "detail"],
                            [[_title(f.get("model")), f.get("parameter") or "-",
                              str(f.get("kind") or "").replace("_", " "), f.get("detail") or ""]
                             for f in flags]))
    else:
        parts.append("<p>No flags: no parameter at a bound, no |correlation| above "
                     f"{num(CORRELATION_LIMIT)}, no ill-conditioned or physically inconsistent fit.</p>")
    parts.append("<dl><dt>at bound</dt><dd>the parameter ended on a bound of its search box; its standard error "
                 "is not a confidence interval.</dd><dt>correlation</dt><dd>" + _e(METRIC_DEFINITIONS["correlation"])
                 + "</dd><dt>ill conditioned</dt><dd>" + _e(METRIC_DEFINITIONS["condition_number"])
                 + "</dd><dt>inconsistent</dt><dd>the fitted model violates a physical check (its vertical load "
                 "(Eq. 7) against the measured load, sinkage against the limits of Eq. 10).</dd></dl>")
    cons = rep["diagnosis"].get("consistency") or {}
    if cons:
        parts.append("<h3>Physical consistency of the fits</h3>")
        rows = []
        for k, v in sorted(cons.items(), key=lambda kv: _model_order(_canon(kv[0]))):
            v = v if isinstance(v, dict) else {}
            ratios = [r.get("ratio") for r in v.get("load_ratio_by_slip") or [] if isinstance(r, dict)
                      and r.get("ratio") is not None]
            rows.append([_title(_canon(k)), {True: "yes", False: "NO"}.get(v.get("consistent"), "n/a"),
                         f"{num(min(ratios))} to {num(max(ratios))}" if ratios else "n/a",
                         f"{fmt(v.get('sinkage_static_m'), 'length_mm')} (limit {fmt(v.get('sinkage_limit_m'), 'length_mm')})"
                         if v.get("sinkage_limit_m") is not None else "n/a",
                         "; ".join(map(str, v.get("reasons") or [])) or "-"])
        parts.append(_table(["model", "consistent", "model W / measured W over slip bins (Eq. 7) [-]",
                             "static sinkage (limit D/6, Eq. 10)", "reasons"], rows))
    return parts


def _html(rep: dict, figs: list, overviews: list) -> str:
    d = rep["diagnosis"]
    prov = rep.get("provenance") or {}
    parts = ["<!DOCTYPE html>", "<html lang='en'><head><meta charset='utf-8'>",
             "<meta name='viewport' content='width=device-width, initial-scale=1'>",
             f"<title>wheelsoil fit report: {_e(', '.join(Path(str(i)).name for i in rep['input']))}</title>",
             f"<style>{_CSS}</style></head><body>", "<h1>wheelsoil fit report</h1>"]
    parts.append("<p>Input: " + ", ".join(f"<code>{_e(i)}</code>" for i in rep["input"])
                 + f". Terrain: {_e(rep['terrain']['name'])}. Analysed {_e(prov.get('created', 'n/a'))} with wheelsoil "
                 f"{_e(prov.get('version', 'n/a'))} (provenance at the end).</p>")
    sims = [i for i in prov.get("inputs") or [] if (i.get("provenance") or {}).get("kind") == "simulated"]
    if sims:
        parts.append("<div class='sim'><p><b>Simulated recording.</b> "
                     + _e(", ".join(Path(str(i.get("path"))).name for i in sims))
                     + " was made by <code>wheelsoil simulate</code>, not measured on a vehicle: it tests the pipeline. "
                     "The effect hidden in it is not recorded in the file; check the verdict against the simulator's "
                     "truth (<code>wheelsoil simulate ... --truth truth.json</code>).</p></div>")
    damaged = [q for q in rep.get("data_quality") or [] if q.get("damaged_chunks")]
    if damaged:
        parts.append("<div class='warn'><p><b>Damaged input.</b> "
                     + _e(" ".join(w for q in damaged for w in q["damaged_chunks"]))
                     + " The frames of a damaged part are left out, never used altered; the overview shows the "
                     "gap.</p></div>")
    eff = d.get("effect")
    parts.append(
        f"<div class='verdict'><div class='effect'>Effect: {_e(eff)} &nbsp;·&nbsp; "
        f"{'best candidate' if eff == 'unexplained' else 'model'}: "
        f"{_e(_title(_canon(d.get('model'))))} &nbsp;·&nbsp; confidence: {_e(d.get('confidence'))}</div>"
        + _glance(d) + f"<p class='full'><b>In full.</b> {_e(d.get('summary', ''))}</p></div>")
    loud = [x for x in rep.get("notes") or [] if LOUD_NOTE.match(str(x))]
    if loud:  # what puts the verdict in doubt, before the evidence for it
        parts.append("<div class='warn'><p><b>Read first</b> (also in the notes at the end):</p><ul>"
                     + "".join(f"<li>{_e(x)}</li>" for x in loud) + "</ul></div>")
    if rep.get("not_done"):
        parts.append("<h2>What could not be done</h2><div class='warn'><ul>"
                     + "".join(f"<li>{_e(x)}</li>" for x in rep["not_done"]) + "</ul></div>")
    worse_rows = worse_than_wong_rows(rep)
    shown = [x for x in rep["findings"] if x not in {r["text"] for r in worse_rows}]
    if worse_rows:  # each with its numbers and reason in the per-channel section, not twice
        per = {}
        for r in worse_rows:
            per.setdefault(CHANNEL_TITLES.get(r["channel"], r["channel"]), set()).add(r["model"])
        shown.append(f"{len({r['model'] for r in worse_rows})} fitted model(s) are worse than Wong on a channel ("
                     + ", ".join(f"{len(m)} on the {c}" for c, m in per.items())
                     + "): the table under 'Per channel: in sample and out of sample' gives each, with its numbers "
                       "and the reason.")
    parts.append("<h2>What the verdict rests on</h2><ul>" + "".join(f"<li>{_e(x)}</li>" for x in shown) + "</ul>")
    alts = d.get("alternatives") or []
    if alts:
        parts.append("<p>Hypotheses that explain the data equally well: " + _e(", ".join(_title(a) for a in alts))
                     + (f". The measurement that would separate them: {_e(d.get('separating_measurement'))}."
                        if d.get("separating_measurement") else ".") + "</p>")
    g = rep["gain"]
    parts.append(_table(["drawbar pull R0 [N]", "Wong", _title(_canon(d.get("model")) or "wong")],
                        [["in sample", fmt(g.get("R0_n_before"), "force", unit=False), fmt(g.get("R0_n_after"), "force", unit=False)],
                         ["out of sample (CV)", fmt(g.get("cv_R0_n_before"), "force", unit=False),
                          fmt(g.get("cv_R0_n_after"), "force", unit=False)]]))
    parts.extend(_metrics_section(rep))
    parts.extend(_coefficients_section(rep))
    # the run itself
    parts.append("<h2>The run: overview and data quality</h2>")
    dq = {q.get("input"): q for q in rep.get("data_quality") or []}
    for path_fig, inp in overviews:
        parts.append(f"<h3>{_e(inp)}</h3>")
        if path_fig is not None:
            parts.append(_img(Path(path_fig), f"overview of {inp}",
                              "Top to bottom: speed V and r omega, slip (black: samples used in the fit), vertical load "
                              "W, drawbar pull Dp, torque T against time; shading: accelerate / brake / standstill "
                              "phases; bottom strip: the spans excluded from the fit and why."))
        q = dq.get(inp)
        if q:
            parts.append(_table(["data quality", "value"], _quality_rows(q)))
    for q in rep.get("data_quality") or []:
        if q.get("input") not in {i for _, i in overviews}:
            parts.append(f"<h3>{_e(q.get('input'))}</h3>" + _table(["data quality", "value"], _quality_rows(q)))
    # Tab. 1: terrain and wheel
    t = rep["terrain"]
    parts.append("<h2>Terrain and wheel (given)</h2>")
    parts.append(_table(
        ["terrain", "c [kPa]", "phi [deg]", "K [mm]", "n [-]", "kc [kN/m^(n+1)]", "kphi [kN/m^(n+2)]",
         "k_eq = kc/b + kphi [kN/m^(n+2)]"],
        [[t["name"], fmt(t["c_pa"], "pressure", unit=False), num(t["phi_deg"]), fmt(t["k_m"], "length_mm", unit=False),
          num(t["n"]), fmt(t["kc"], "kc", unit=False), fmt(t["kphi"], "kphi", unit=False),
          fmt(t["k_eq"], "kphi", unit=False)]]))
    w = rep["wheel"]
    parts.append(f"<p>Wheel radius {_e(fmt(w['radius_m'], 'length_mm'))}, width {_e(fmt(w['width_m'], 'length_mm'))}. "
                 f"Samples used: {rep['samples_used']} of {rep['samples_read']} ({rep['independent_units']} "
                 f"independent units), slip_min = {_e(num(rep['slip_min']))}. Noise sigma (fit weights): "
                 + _e(", ".join(f"{CHANNEL_TITLES.get(k, k)} {_chan_fmt(v, k, 2)}" for k, v in rep["noise_sigma"].items()))
                 + f". GNSS latency: {_e(fmt(rep['time_sync'].get('gnss_latency_s'), 'latency'))}.</p>")
    if rep["per_run"]:
        parts.append("<h2>Per-run metrics (pooled fit)</h2>")
        shown = [k for k in rep["models"] if rep["models"][k]["params"] is not None]
        hdr = ["run", "samples"] + [f"{_title(k)} R0 Dp [N]" for k in shown]
        rows = [[r["run"], r["samples"]] + [fmt((r["models"].get(k) or {}).get("R0_n"), "force", unit=False) for k in shown]
                for r in rep["per_run"]]
        parts.append(_table(hdr, rows))
    parts.append("<h2>Figures</h2>")
    captions = {
        "dp_vs_slip.png": "Drawbar pull against slip, one panel per model (paper Figs. 4-5: Wong, the three slip-sinkage "
                          f"forms, the chosen model, its alternatives and any other with posterior >= "
                          f"{FIG_MIN_PROBABILITY:.0%}): grey dots measured, "
                          "crosses the model at each sample's measured load, line the model at the median load.",
        "residuals.png": "Wong's error (measured - model) per channel against slip (with binned means of independent "
                         "units and 95 % confidence intervals), load and time.",
        "sinkage_vs_slip.png": "Sinkage against slip: each model's curve at the median load; grey dots measured "
                               "sinkage when measured.",
        "soil_values.png": "The re-fit of all five lab soil values, each in lab standard deviations from the lab "
                           "value: the fitted value and the data's own estimate with its 95 % interval, against the "
                           "lab's stated uncertainty. A value far outside the band says where to re-measure the soil "
                           "(plate-sinkage and shear tests where the wheel ran); causes on no list can move a value "
                           "as far, so the figure shows where the data point, not the cause.",
    }
    for f in figs:
        name = Path(f).name
        cap = captions.get(name, "") + "".join(" " + n + "." for n in rep["figure_notes"].get(name, []))
        parts.append(_img(Path(f), Path(f).stem, _e(cap)))
    th = d.get("thresholds") or {}
    parts.append("<h2>Diagnosis rule</h2><p>Thresholds: " + _e(", ".join(f"{k} = {v}" for k, v in th.items()))
                 + f". Cross-validation: {_e(d.get('cross_validation'))}. See "
                 "<code>wheelsoil.model.diagnosis</code> for the rule.</p>")
    if rep["notes"]:
        parts.append("<h2>Notes</h2><ul>" + "".join(f"<li>{_e(x)}</li>" for x in rep["notes"]) + "</ul>")
    parts.append("<h2>Provenance: how to re-run this report</h2>")
    parts.append("<p>Run the command below in the working directory shown, with the same inputs (check their "
                 "sha256): it gives the same report.json except the analysis time.</p>")
    parts.append(_provenance_html(prov))
    parts.append("</body></html>")
    return "\n".join(parts)


# ============================================================================ entry point


def _fit_rows(data, signals, run: int):
    """(N,) bool: the samples of input ``run`` that the fit used (matched by time), or None when
    the fit data carry no times."""
    t_fit = getattr(data, "t_s", None)
    if t_fit is None or "t_s" not in signals:
        return None
    return np.isin(signals["t_s"].to_numpy(float), np.asarray(t_fit)[np.asarray(data.run) == run])


#: The figures a report writes (a report directory's earlier ones are removed first).
FIGURE_FILES = ("overview.png", "dp_vs_slip.png", "residuals.png", "sinkage_vs_slip.png", "soil_values.png")


def _is_figure(path: Path) -> bool:
    """A figure a report writes: ``FIGURE_FILES`` or ``overview*.png`` (one per run)."""
    return path.name in FIGURE_FILES or (path.name.startswith("overview") and path.suffix == ".png")


def foreign_files(out_dir: Path) -> list[str]:
    """Names of the entries in the existing directory ``out_dir`` that no report writes
    (``report.json``, ``report.html``, its figures): a report is not written into a directory of
    other files.  Raises OSError."""
    return sorted(p.name for p in out_dir.iterdir()
                  if p.name not in ("report.json", "report.html") and not _is_figure(p))


def clear_figures(out_dir: Path) -> None:
    """Create ``out_dir`` and remove the figures an earlier report left there (``FIGURE_FILES``,
    ``overview*.png``), so a report never sits next to another run's plots.  Raises OSError."""
    out_dir.mkdir(parents=True, exist_ok=True)
    for p in out_dir.iterdir():
        if _is_figure(p) and p.is_file():
            p.unlink(missing_ok=True)


def write_report(diag, out_dir, *, terrain, wheel, inputs, time_sync: dict | None = None,
                 extra_notes: list | None = None, progress: bool = False, provenance: dict | None = None,
                 input_details: list | None = None) -> dict:
    """Write ``report.json``, the PNG figures and ``report.html`` into ``out_dir``.

    Parameters: ``diag`` from :func:`wheelsoil.model.diagnosis.diagnose`;
    ``terrain``, ``wheel`` as given by the user; ``inputs`` list of input
    names; ``time_sync`` e.g. ``{"gnss_latency_s": 0.12}`` (None for tables);
    ``extra_notes`` appended to the notes; ``provenance`` the run's provenance
    dict (``version, command, cwd, inputs, vehicle_config, settings, created``);
    ``input_details`` one dict per input: ``path``, ``quality`` (JSON-safe
    data-quality dict) and, for a processed recording, ``signals`` (the
    DataFrame of ``process_recording``), ``wheel_radius_m`` and ``excluded``
    (processing's excluded spans).  Figures that fail are listed under
    ``not_done`` instead of aborting the report.

    Returns the report dict (as written to ``report.json``).
    Raises OSError when ``out_dir`` cannot be created or written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    clear_figures(out)
    figs: list = []
    fig_notes: dict = {}
    notes = list(extra_notes or [])
    failures = getattr(diag, "failures", None)
    if failures is None:
        failures = []
    try:
        figs, fig_notes = _figures(diag, wheel, out, plt)
    except Exception as exc:  # noqa: BLE001 - a figure must never hide the numbers
        failures.append(f"figures could not be drawn: {type(exc).__name__}: {exc}")
    details = list(input_details or [])
    overviews, quality = [], []
    with_signals = [x for x in details if x.get("signals") is not None]
    for i, det in enumerate(details):
        q = dict(det.get("quality") or {})
        q.setdefault("input", str(det.get("path")))
        if det.get("signals") is not None:
            name = "overview.png" if len(with_signals) == 1 else f"overview_{i}.png"
            try:
                stats = overview_figure(det["signals"], float(det.get("wheel_radius_m") or wheel.radius),
                                        diag.data.slip_min, det.get("excluded") or [], out / name,
                                        f"{Path(str(det.get('path'))).name}: the run, what was fitted and what was not",
                                        plt, used=_fit_rows(diag.data, det["signals"], i))
                q["samples"] = stats["samples"]
                q["used_in_fit"] = stats["used"]
                q["excluded_samples"] = stats["excluded"]
                overviews.append((out / name, q["input"]))
                figs.append(out / name)
            except Exception as exc:  # noqa: BLE001
                failures.append(f"overview figure of {q['input']} could not be drawn: {type(exc).__name__}: {exc}")
                overviews.append((None, q["input"]))
        quality.append(q)
    rep = report_dict(diag, terrain=terrain, wheel=wheel, inputs=inputs, time_sync=time_sync,
                      figures=[Path(f).name for f in figs], extra_notes=notes, provenance=provenance,
                      data_quality=quality, figure_notes=fig_notes)
    text = json.dumps(rep, indent=2, allow_nan=False)
    (out / "report.json").write_text(text, encoding="utf-8")
    main_figs = [f for f in figs if not Path(f).name.startswith("overview")]
    (out / "report.html").write_text(_html(rep, main_figs, overviews), encoding="utf-8")
    return rep
