"""The fitted-model report: ``report.html`` (self-contained), ``*.png``, ``report.json``.

:func:`write_report` turns a :class:`wheelsoil.model.diagnosis.Diagnosis` into

* ``report.json`` (schema ``wheelsoil.report/1``, valid JSON: no NaN, ``null``
  instead), with the keys listed in :data:`REQUIRED_KEYS`;
* ``dp_vs_slip.png`` (measured Dp with every model's curve, like the paper's
  Figs. 4–5), ``residuals.png`` (Wong's residuals vs slip with binned means and
  95 % CIs, vs load and time), ``sinkage_vs_slip.png`` (each model's sinkage,
  measured points when present);
* ``report.html``: one file with the figures embedded as base64 ``data:`` URIs,
  inline CSS only, no scripts, fonts or external links, so it opens offline;
  tables like the paper's Tabs. 1–4 and per-run metrics beside the pooled ones.
"""

from __future__ import annotations

import base64
import html
import json
import math
from pathlib import Path

import numpy as np

from .diagnosis import CHANNEL_TITLES, TITLES, Diagnosis

__all__ = ["write_report", "report_dict", "SCHEMA", "ALL_MODELS"]

SCHEMA = "wheelsoil.report/1"
ALL_MODELS = ("wong", "vasilev", "lyasko", "ding", "terrain_mismatch", "vasilev+terrain", "ding+terrain",
              "wong_reece", "drift_linear")
COLORS = {"wong": "#444444", "vasilev": "#1f77b4", "lyasko": "#d62728", "ding": "#2ca02c",
          "terrain_mismatch": "#9467bd", "vasilev+terrain": "#17becf", "ding+terrain": "#bcbd22",
          "wong_reece": "#8c564b", "drift_linear": "#e377c2"}


def _fit_of(diag, name):
    """The fit shown under ``name`` (``terrain_mismatch`` is the ``terrain`` hypothesis)."""
    return diag.fits.get(name) or (diag.fits.get("terrain") if name == "terrain_mismatch" else None)


def _clean(obj):
    """Recursively convert numpy types to Python and non-finite floats to None (valid JSON)."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_clean(v) for v in obj.tolist()]
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj


def _terrain_dict(t, wheel) -> dict:
    return {
        "name": t.name,
        "c_pa": t.c,
        "phi_deg": t.phi_deg,
        "k_m": t.K,
        "n": t.n,
        "kc": t.kc,
        "kphi": t.kphi,
        "k_eq": t.k_eq(wheel.width),
        "source": getattr(t, "source", ""),
    }


def _per_run(diag: Diagnosis) -> list:
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
        for k, f in diag.fits.items():
            row["models"][k] = _metrics(data.channels["drawbar_pull_n"][m], f.predictions["drawbar_pull_n"][m])
        out.append(row)
    return out


def report_dict(diag: Diagnosis, *, terrain, wheel, inputs, time_sync: dict | None = None,
                figures: list | None = None, extra_notes: list | None = None) -> dict:
    """The ``report.json`` content (schema ``wheelsoil.report/1``) as a JSON-safe dict.

    ``terrain``/``wheel``: the terrain and wheel given by the user; ``inputs``:
    list of input descriptions (paths); ``time_sync``: ``{"gnss_latency_s": ...}``
    (None values for tables).  Every model of :data:`ALL_MODELS` has an entry;
    one that was not fitted has ``"status"`` saying why and null numbers.
    """
    data = diag.data
    models = {}
    for name in ALL_MODELS:
        f = _fit_of(diag, name)
        if f is None:
            why = "not fitted"
            for msg in diag.failures + diag.notes:
                if msg.startswith(TITLES[name]) or msg.startswith(name):
                    why = msg
            models[name] = {"status": why, "params": None, "stderr": None,
                            "metrics": {"M0_pct": None, "R0_n": None, "R2": None},
                            "cv_R0_n": None, "bic": None}
            continue
        models[name] = {
            "status": "ok" if f.success else f"did not converge: {f.message}",
            "params": {k: v for k, v in f.params.items()},
            "stderr": {k: v for k, v in f.stderr.items()},
            "params_fixed_terrain": list(f.fixed_terrain),
            "terrain_used": _terrain_dict(f.terrain, wheel),
            "metrics": dict(f.metrics),
            "channel_metrics": f.channel_metrics,
            "cv_R0_n": f.cv_R0_n,
            "cv_R0": f.cv["cv_R0"] if f.cv else None,
            "cv_score": f.cv["cv_score"] if f.cv else None,
            "cv_folds": f.cv["n_groups"] if f.cv else None,
            "stderr_jackknife": f.cv.get("stderr_jackknife") if f.cv else None,
            "stderr_method": ("max(cluster-robust over cycle x slip cells, jackknife over cycles)"
                              if f.cv and f.cv.get("stderr_jackknife") else
                              "cluster-robust over cycle x slip cells" if data.kind == "timeseries"
                              else "s^2 (J^T J)^-1 (reduced chi-square)"),
            "bic": f.bic,
            "n_eff": f.n_eff,
            "k": f.k,
            "iterations": None if f.result is None else f.result.iterations,
            "correlation": None if f.result is None else {
                "names": list(f.result.names), "matrix": f.result.correlation},
            "condition_number": None if f.result is None else f.result.condition_number,
            "notes": list(f.notes),
        }
    struct = {
        k: {c: {"p": t["p"], "p_poly": t.get("p_poly"), "p_bins": t.get("p_bins"), "effect_sigma": t["effect"],
                "effect_abs": t.get("effect_abs"), "effect_rel": t.get("effect_rel"), "units": t["units"]}
            for c, t in v.items()}
        for k, v in diag.structure.items()
    }
    out = {
        "schema": SCHEMA,
        "input": list(inputs),
        "terrain": _terrain_dict(terrain, wheel),
        "wheel": {"radius_m": wheel.radius, "width_m": wheel.width},
        "samples_used": data.n,
        "samples_read": data.n_input,
        "independent_units": data.n_units,
        "slip_min": data.slip_min,
        "channels": list(data.channels),
        "noise_sigma": dict(data.sigma),
        "time_sync": dict(time_sync) if time_sync else {"gnss_latency_s": None},
        "models": models,
        "diagnosis": {
            **diag.to_dict(),
            "effect": diag.effect,
            "model": diag.model,
            "confidence": diag.confidence,
            "confidence_reasons": list(diag.confidence_reasons),
            "summary": diag.summary,
            "forms_distinguishable": diag.forms_distinguishable,
            "indistinguishable_forms": list(diag.indistinguishable_forms),
            "structure_tests": struct,
            "load_test": diag.load_test,
            "time_test": diag.time_test,
            "sinkage_evidence": diag.sinkage_evidence,
            "thresholds": diag.thresholds,
            "fit_terrain": diag.fit_terrain,
            "identifiability": diag.identifiability,
            "cross_validation": data.group_kind,
        },
        "gain": dict(diag.gain),
        "per_run": _per_run(diag),
        "binned_wong_residuals": diag.binned,
        "notes": list(diag.notes) + list(extra_notes or []),
        "not_done": list(diag.failures),
        "figures": list(figures or []),
    }
    return _clean(out)


# ----------------------------------------------------------------------------- figures


def _model_curves(diag: Diagnosis, wheel, slip_grid, load):
    """name -> WheelForces on a slip grid at one load (models that cannot be evaluated are skipped)."""
    from wheelsoil.model import get_model

    out = {}
    for k, f in diag.fits.items():
        key = "terrain_mismatch" if k == "terrain" else k
        try:
            if hasattr(f, "curve"):
                out[key] = f.curve(np.full(slip_grid.size, load), slip_grid)
                continue
            mp = {p: v for p, v in f.params.items() if p in {q.name for q in get_model(f.model).params}}
            out[key] = get_model(f.model).predict(f.terrain, wheel, np.full(slip_grid.size, load), slip_grid, mp)
        except ValueError:
            continue
    return out


def _figures(diag: Diagnosis, wheel, out_dir: Path) -> list:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = diag.data
    s, dp = data.slip, data.channels["drawbar_pull_n"]
    big = data.n > 500
    pt = dict(s=4 if big else 18, alpha=0.25 if big else 0.8, color="#888888", lw=0)
    load = float(np.median(data.load_n))
    grid = np.linspace(max(data.slip_min, 1e-3), min(float(s.max()) + 0.02, 0.98), 120)
    curves = _model_curves(diag, wheel, grid, load)
    files = []

    # 1. Dp vs slip, one panel per model (paper Figs. 4-5)
    names = [k for k in ALL_MODELS if _fit_of(diag, k) is not None]
    ncol = 3 if len(names) > 2 else len(names)
    nrow = int(math.ceil(len(names) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.3 * nrow), squeeze=False, sharey=True)
    for ax, k in zip(axes.flat, names):
        f = _fit_of(diag, k)
        ax.scatter(s, dp, label="measured", **pt)
        order = np.argsort(s)
        if big:
            ax.plot(s[order], f.predictions["drawbar_pull_n"][order], ".", ms=1, color=COLORS[k], alpha=0.3)
        else:
            ax.plot(s[order], f.predictions["drawbar_pull_n"][order], "o", ms=3, mfc="none", color=COLORS[k],
                    label="model at measured W")
        if k in curves:
            ax.plot(grid, curves[k].drawbar_pull_n, "-", color=COLORS[k], lw=2, label=f"model, W = {load:.4g} N")
        m = f.metrics
        ax.set_title(f"{TITLES[k]}\nM0 {_n(m['M0_pct'], '%')}  R0 {_n(m['R0_n'], 'N')}  R² {_n(m['R2'])}", fontsize=9)
        ax.set_xlabel("slip s")
        ax.grid(alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel("drawbar pull Dp [N]")
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7, loc="best")
    fig.tight_layout()
    files.append(_save(fig, out_dir / "dp_vs_slip.png", plt))

    # 2. Wong's residuals vs slip (binned means, CI), vs load, vs time
    chans = list(data.channels)
    wong = diag.fits["wong"]
    fig, axes = plt.subplots(len(chans), 3, figsize=(13, 3.0 * len(chans)), squeeze=False)
    scale = {"drawbar_pull_n": (1.0, "N"), "torque_nm": (1.0, "N m"), "sinkage_m": (1e3, "mm")}
    t = data.t_s if data.t_s is not None else np.arange(data.n)
    for i, c in enumerate(chans):
        k, unit = scale[c]
        e = (data.channels[c] - wong.predictions[c]) * k
        b = diag.binned[c]
        ax = axes[i, 0]
        ax.scatter(s, e, **pt)
        ax.errorbar(b["slip"], np.array(b["mean"]) * k,
                    yerr=np.abs(np.vstack([np.array(b["mean"]) - np.array(b["lo"]),
                                           np.array(b["hi"]) - np.array(b["mean"])])) * k,
                    fmt="o-", color="#d62728", capsize=3, label="binned mean, 95% CI")
        ax.axhline(0, color="k", lw=0.8)
        p = diag.structure["wong"][c]["p"]
        ax.set_title(f"Wong residual, {CHANNEL_TITLES[c]} (structure p = {_n(p)})", fontsize=9)
        ax.set_xlabel("slip s")
        ax.set_ylabel(f"measured - Wong [{unit}]")
        ax.legend(fontsize=7)
        axes[i, 1].scatter(data.load_n, e, **pt)
        axes[i, 1].axhline(0, color="k", lw=0.8)
        axes[i, 1].set_xlabel("load W [N]")
        axes[i, 1].set_title("vs load", fontsize=9)
        axes[i, 2].scatter(t, e, **pt)
        axes[i, 2].axhline(0, color="k", lw=0.8)
        axes[i, 2].set_xlabel("time [s]" if data.t_s is not None else "row")
        axes[i, 2].set_title("vs time" if data.t_s is not None else "vs row order", fontsize=9)
        for ax in axes[i]:
            ax.grid(alpha=0.3)
    fig.tight_layout()
    files.append(_save(fig, out_dir / "residuals.png", plt))

    # 3. sinkage vs slip per model
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    if "sinkage_m" in data.channels:
        ax.scatter(s, data.channels["sinkage_m"] * 1e3, label="measured", **pt)
    for k in names:
        if k in curves:
            ax.plot(grid, curves[k].sinkage_m * 1e3, "-", color=COLORS[k], lw=2, label=TITLES[k])
    ax.set_xlabel("slip s")
    ax.set_ylabel("sinkage z [mm]")
    ax.set_title(f"sinkage vs slip (model curves at W = {load:.4g} N)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    files.append(_save(fig, out_dir / "sinkage_vs_slip.png", plt))
    return files


def _save(fig, path: Path, plt) -> Path:
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _n(v, unit="", nd=4):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    return f"{v:.{nd}g}{(' ' + unit) if unit else ''}"


# ----------------------------------------------------------------------------- HTML

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1150px;margin:1.5em auto;padding:0 1em;color:#222}
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right}th{background:#f0f0f0}
td:first-child,th:first-child{text-align:left}
.verdict{padding:.8em 1em;border-radius:6px;background:#eef5ff;border:1px solid #9bc}
.effect{font-size:1.3em;font-weight:bold}
.warn{background:#fff4e0;border:1px solid #e0b060;padding:.5em 1em;border-radius:6px}
img{max-width:100%;border:1px solid #ddd;margin:.5em 0}
code{background:#f4f4f4;padding:0 .2em}
"""


def _table(headers, rows) -> str:
    h = "".join(f"<th>{html.escape(str(x))}</th>" for x in headers)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(x))}</td>" for x in r) + "</tr>" for r in rows)
    return f"<table><tr>{h}</tr>{body}</table>"


def _img(path: Path, alt: str) -> str:
    b64 = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{b64}">'


def _html(rep: dict, figs: list) -> str:
    d = rep["diagnosis"]
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>wheelsoil fit report</title>"
             f"<style>{_CSS}</style></head><body>"]
    parts.append("<h1>wheelsoil fit report</h1>")
    parts.append("<p>Input: " + ", ".join(f"<code>{html.escape(str(i))}</code>" for i in rep["input"]) + "</p>")
    parts.append(
        f"<div class='verdict'><div class='effect'>Effect: {html.escape(d['effect'])} &nbsp;·&nbsp; model: "
        f"{html.escape(TITLES.get(d['model'], d['model'] or 'none'))} &nbsp;·&nbsp; confidence: {html.escape(d['confidence'])}</div>"
        f"<p>{html.escape(d['summary'])}</p></div>"
    )
    if rep["not_done"]:
        parts.append("<h2>What could not be done</h2><div class='warn'><ul>"
                     + "".join(f"<li>{html.escape(x)}</li>" for x in rep["not_done"]) + "</ul></div>")
    # Tab. 1: terrain and wheel
    t = rep["terrain"]
    parts.append("<h2>Terrain and wheel (given)</h2>")
    parts.append(_table(
        ["terrain", "c [kPa]", "phi [deg]", "K [m]", "n", "kc [kN/m^(n+1)]", "kphi [kN/m^(n+2)]", "k_eq = kc/b+kphi [kN/m^(n+2)]"],
        [[t["name"], _n(t["c_pa"] / 1e3), _n(t["phi_deg"]), _n(t["k_m"]), _n(t["n"]), _n(t["kc"] / 1e3),
          _n(t["kphi"] / 1e3), _n(t["k_eq"] / 1e3)]]))
    w = rep["wheel"]
    parts.append(f"<p>Wheel radius {w['radius_m']} m, width {w['width_m']} m. Samples used: {rep['samples_used']} of "
                 f"{rep['samples_read']} ({rep['independent_units']} independent units), slip_min = {rep['slip_min']}. "
                 f"Channels: {', '.join(rep['channels'])}. Noise sigma (weights): "
                 + ", ".join(f"{k} {_n(v)}" for k, v in rep["noise_sigma"].items())
                 + f". GNSS latency: {_n(rep['time_sync'].get('gnss_latency_s'), 's')}.</p>")
    # Tab. 2/4: metrics
    parts.append("<h2>Prediction of the drawbar pull (paper Tabs. 2 and 4)</h2>")
    rows = []
    for k, m in rep["models"].items():
        mm = m["metrics"]
        rows.append([TITLES[k], _n(mm["M0_pct"]), _n(mm["R0_n"]), _n(mm["R2"]), _n(m["cv_R0_n"]),
                     _n(m.get("cv_score")), _n(m["bic"], nd=5), m["status"]])
    parts.append(_table(["model", "M0 [%]", "R0 [N]", "R²", "CV R0 [N]", "CV weighted RMS", "BIC (n_eff)", "status"], rows))
    parts.append("<p>M0 = max |error| / |measured| (paper §1.3) grows without bound where the measured Dp "
                 "is near zero; R0 and the out-of-sample CV R0 are the robust comparison. BIC uses the effective "
                 "number of independent observations; lower is better.</p>")
    chan_rows = []
    for k, m in rep["models"].items():
        if m.get("channel_metrics"):
            for c, v in m["channel_metrics"].items():
                if c != "drawbar_pull_n":
                    chan_rows.append([TITLES[k], c, _n(v["R0"]), _n(v["R2"]), _n((m.get("cv_R0") or {}).get(c))])
    if chan_rows:
        parts.append("<p>Other channels:</p>" + _table(["model", "channel", "R0", "R²", "CV R0"], chan_rows))
    # Tab. 3: coefficients
    parts.append("<h2>Fitted coefficients (paper Tab. 3), ± standard error</h2>")
    rows = []
    for k, m in rep["models"].items():
        if m["params"]:
            txt = "; ".join(f"{p} = {_n(v)} ± {_n(m['stderr'].get(p), nd=2)}" for p, v in m["params"].items())
            fixed = ", ".join(m.get("params_fixed_terrain") or []) or "-"
            rows.append([TITLES[k], txt, fixed, _n(m.get("condition_number"), nd=3)])
        else:
            rows.append([TITLES[k], "(no free parameters)" if m["status"] == "ok" else m["status"], "-", "-"])
    parts.append(_table(["model", "parameters (SI; phi in rad)", "terrain held fixed", "condition no."], rows))
    if rep["per_run"]:
        parts.append("<h2>Per-run metrics (pooled fit)</h2>")
        hdr = ["run", "samples"] + [f"{TITLES[k]} R0 [N]" for k in rep["models"] if rep["models"][k]["params"] is not None]
        rows = []
        for r in rep["per_run"]:
            rows.append([r["run"], r["samples"]] + [_n(r["models"][k]["R0_n"]) for k in rep["models"]
                                                     if k in r["models"] and rep["models"][k]["params"] is not None])
        parts.append(_table(hdr, rows))
    parts.append("<h2>Figures</h2>")
    for f in figs:
        parts.append(_img(Path(f), Path(f).stem))
    parts.append("<h2>Diagnosis rule</h2><p>Thresholds: "
                 + ", ".join(f"{k} = {v}" for k, v in d["thresholds"].items())
                 + f". Cross-validation: {html.escape(d['cross_validation'])}. See "
                 "<code>wheelsoil.model.diagnosis</code> for the rule.</p>")
    if rep["notes"]:
        parts.append("<h2>Notes</h2><ul>" + "".join(f"<li>{html.escape(x)}</li>" for x in rep["notes"]) + "</ul>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(diag: Diagnosis, out_dir, *, terrain, wheel, inputs, time_sync: dict | None = None,
                 extra_notes: list | None = None, progress: bool = False) -> dict:
    """Write ``report.json``, the PNG figures and ``report.html`` into ``out_dir``.

    Parameters: ``diag`` from :func:`wheelsoil.model.diagnosis.diagnose`;
    ``terrain``, ``wheel`` as given by the user; ``inputs`` list of input
    names; ``time_sync`` e.g. ``{"gnss_latency_s": 0.12}`` (None for tables);
    ``extra_notes`` appended to the notes.  Figures that fail are listed under
    ``not_done`` instead of aborting the report.

    Returns the report dict (as written to ``report.json``).
    Raises OSError when ``out_dir`` cannot be created or written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    figs: list = []
    notes = list(extra_notes or [])
    try:
        figs = _figures(diag, wheel, out)
    except Exception as exc:  # a figure must never hide the numbers
        diag.failures.append(f"figures could not be drawn: {type(exc).__name__}: {exc}")
    rep = report_dict(diag, terrain=terrain, wheel=wheel, inputs=inputs, time_sync=time_sync,
                      figures=[f.name for f in figs], extra_notes=notes)
    text = json.dumps(rep, indent=2, allow_nan=False)
    (out / "report.json").write_text(text, encoding="utf-8")
    (out / "report.html").write_text(_html(rep, figs), encoding="utf-8")
    return rep
