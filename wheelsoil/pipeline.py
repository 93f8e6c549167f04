"""``wheelsoil fit``: from recordings or tables to a fitted-model report.

Library entry point :func:`run_fit`; the subcommand is added by :func:`register`.
Each input is either a steady-state table CSV (columns ``slip, load_n,
drawbar_pull_n`` and optional ``torque_nm, sinkage_m``) or a recording
(``.mcap``; ``.log/.blf/.asc/.trc`` if processing reads them) processed by
``wheelsoil.processing.process_recording``.  Several inputs of one terrain are
fitted jointly (a ``run`` column tells them apart; per-run metrics are in the
report).
"""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["run_fit", "load_inputs", "register", "RECORDING_SUFFIXES"]

RECORDING_SUFFIXES = (".mcap", ".log", ".blf", ".asc", ".trc")
TABLE_SUFFIXES = (".csv", ".txt", ".tsv")


def _read_table(path: Path):
    import pandas as pd

    try:
        df = pd.read_csv(path, sep=None, engine="python") if path.suffix == ".tsv" else pd.read_csv(path)
    except pd.errors.EmptyDataError:
        raise ValueError(f"{path}: the table is empty (no header, no rows)") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a readable CSV table: {exc}") from None
    df.columns = [str(c).strip() for c in df.columns]
    return df


def load_inputs(inputs, *, progress: bool = False, wheel_radius_m: float | None = None):
    """Read every input into one DataFrame for fitting.

    Returns ``(df, info)``: ``df`` has the fit columns plus ``run`` (input
    index) and, for recordings, ``t_s``, ``valid`` and ``cycle``; ``info`` is a
    dict with ``kinds`` (per input: ``table``/``recording``), ``time_sync`` (per
    input latency values, None for tables), ``wheel_radius_m``/``wheel_width_m``
    from the first recording's vehicle config (None for tables) and ``notes``.
    ``wheel_radius_m`` [m], when given, is the radius recordings compute slip
    with (Eq. 6; ``process_recording(wheel_radius_m=...)``), so the fit's radius
    is the slip radius; radius conflicts (recordings whose configurations
    disagree, a table's ``wheel_radius_m`` column, or a table's slip of unknown
    radius) are loud notes. ``processing`` lists per recording what processing
    did (``wheel_radius_m``/``_source``, ``inertia``, ``excluded``, ``quality``
    of ``ProcessResult``) for the report.

    Raises ValueError (naming the file) for a missing file, an unknown suffix,
    an unreadable table, or a recording processing cannot read.
    """
    import pandas as pd

    frames, kinds, sync, notes, processing = [], [], [], [], []
    radius = width = None
    for i, raw in enumerate(inputs):
        path = Path(raw)
        if not path.exists():
            raise ValueError(f"{path}: no such file")
        suffix = path.suffix.lower()
        if suffix in RECORDING_SUFFIXES:
            from wheelsoil.processing import process_recording

            res = process_recording(path, progress=progress, wheel_radius_m=wheel_radius_m)
            df = res.signals.copy()
            df["cycle"] = res.cycle
            kinds.append("recording")
            sync.append({
                "input": str(path),
                "gnss_latency_s": res.gnss_latency_s,
                "gnss_latency_stderr_s": res.gnss_latency_stderr_s,
                "gps_time_mapping": res.gps_time_mapping,
            })
            notes.extend(f"{path.name}: {w}" for w in res.warnings)
            processing.append({"input": str(path), "wheel_radius_m": res.wheel_radius_m,
                               "wheel_radius_source": res.wheel_radius_source, "inertia": res.inertia,
                               "excluded": res.excluded, "quality": res.quality})
            if radius is None:  # the first recording's vehicle configuration
                radius, width = res.wheel_radius_m, res.wheel_width_m
            elif abs(res.wheel_radius_m - radius) > 1e-6 * radius:
                notes.append(f"WHEEL RADIUS CONFLICT: {path.name} computed slip with r = {res.wheel_radius_m:g} m "
                             f"(its vehicle configuration), the first recording with {radius:g} m; the fit uses "
                             f"{radius:g} m for all; give --wheel-radius to use one radius for slip and fit")
        elif suffix in TABLE_SUFFIXES:
            df = _read_table(path)
            kinds.append("table")
            tr = (pd.to_numeric(df["wheel_radius_m"], errors="coerce").dropna().unique()
                  if "wheel_radius_m" in df.columns else [])
            if len(tr) > 1 or (len(tr) == 1 and wheel_radius_m is not None
                               and abs(float(tr[0]) - wheel_radius_m) > 1e-6 * wheel_radius_m):
                notes.append(f"WHEEL RADIUS CONFLICT: {path.name} states wheel_radius_m = "
                             f"{', '.join(f'{float(x):g}' for x in tr)} m; the fit uses "
                             f"{wheel_radius_m if wheel_radius_m is not None else float(tr[0]):g} m while the "
                             "table's slip was computed with its own radius (Eq. 6)")
            elif len(tr) == 1 and radius is None:
                radius = float(tr[0])
            elif wheel_radius_m is not None:
                notes.append(f"{path.name}: the table's slip was computed outside wheelsoil with a radius it "
                             f"does not state; the fit uses r = {wheel_radius_m:g} m: it must be the radius "
                             "that slip (Eq. 6) was computed with")
            sync.append({"input": str(path), "gnss_latency_s": None})
        else:
            raise ValueError(
                f"{path}: unknown input type {suffix!r}; give a table (.csv) or a recording "
                f"({', '.join(RECORDING_SUFFIXES)})"
            )
        df["run"] = i
        frames.append(df)
    if not frames:
        raise ValueError("no input given")
    df = pd.concat(frames, ignore_index=True, sort=False)
    if "t_s" in df.columns and df["t_s"].isna().any():  # tables mixed with recordings
        df["t_s"] = df["t_s"].fillna(df.groupby("run").cumcount().astype(float))
    return df, {"kinds": kinds, "time_sync": sync, "wheel_radius_m": radius, "wheel_width_m": width, "notes": notes,
                "processing": processing}


def _time_sync_summary(sync: list) -> dict:
    lat = [s["gnss_latency_s"] for s in sync if s.get("gnss_latency_s") is not None]
    out = {"gnss_latency_s": (sum(lat) / len(lat)) if lat else None}
    if len(sync) == 1:
        out.update({k: v for k, v in sync[0].items() if k != "input"})
    else:
        out["per_input"] = sync
    return out


def _failure_report(out_dir: Path, inputs, terrain, wheel, slip_min, error: str) -> None:
    """Write a report.json/report.html that says what could not be done."""
    import html
    import json

    from wheelsoil.model.report import ALL_MODELS, SCHEMA, _clean, _terrain_dict

    out_dir.mkdir(parents=True, exist_ok=True)
    rep = _clean({
        "schema": SCHEMA,
        "input": [str(i) for i in inputs],
        "terrain": _terrain_dict(terrain, wheel),
        "wheel": {"radius_m": wheel.radius, "width_m": wheel.width},
        "samples_used": 0,
        "slip_min": slip_min,
        "time_sync": {"gnss_latency_s": None},
        "models": {m: {"status": f"not fitted: {error}", "params": None, "stderr": None,
                       "metrics": {"M0_pct": None, "R0_n": None, "R2": None}, "cv_R0_n": None, "bic": None}
                   for m in ALL_MODELS},
        "diagnosis": {"effect": None, "model": None, "confidence": None,
                      "summary": f"Nothing could be fitted: {error}"},
        "gain": {"R0_n_before": None, "R0_n_after": None, "cv_R0_n_before": None, "cv_R0_n_after": None},
        "not_done": [f"fit and diagnosis: {error}"],
    })
    (out_dir / "report.json").write_text(json.dumps(rep, indent=2, allow_nan=False), encoding="utf-8")
    (out_dir / "report.html").write_text(
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>wheelsoil fit report</title></head>"
        f"<body><h1>wheelsoil fit report</h1><p><b>Nothing could be fitted.</b></p><p>{html.escape(error)}</p>"
        f"<p>Inputs: {html.escape(', '.join(map(str, inputs)))}</p></body></html>",
        encoding="utf-8",
    )


def run_fit(
    inputs,
    terrain,
    out_dir,
    *,
    wheel_radius: float | None = None,
    wheel_width: float | None = None,
    slip_min: float = 0.1,
    models=None,
    fit_terrain: bool = False,
    sinkage: str = "eq10",
    progress: bool = False,
) -> dict:
    """Fit Wong's model and the candidates to the inputs, diagnose, write the report.

    Parameters
    ----------
    inputs : list of paths (table CSVs and/or recordings), fitted jointly.
    terrain : a built-in terrain slug, a TOML path, or a ``Terrain``.
    out_dir : report directory (``report.html``, ``report.json``, ``*.png``).
    wheel_radius, wheel_width : [m]; default: the vehicle config's (0.47/0.32)
        for recordings, the model's ``DEFAULT_WHEEL`` for tables.
    slip_min : samples with s <= slip_min are not used (paper: 0.2 clay, 0.1 sand).
    models : candidates (default ``vasilev, lyasko, ding, terrain_mismatch``; Wong always).
    fit_terrain : fit the terrain parameters too (k_eq = kc/b + kphi, n, c, phi, K,
        those the data identify).
    sinkage : ``eq10`` or ``balance``.
    progress : tqdm progress bars on stderr.

    Returns the report dict (``report.json``).

    Raises
    ------
    ValueError
        Unreadable input, unknown terrain or a terrain file missing a key, or
        data nothing can be fitted to (then a report saying so is still written).
    OSError
        The output directory cannot be written.
    """
    from wheelsoil.model import DEFAULT_WHEEL, Terrain, Wheel, load_terrain
    from wheelsoil.model.diagnosis import diagnose
    from wheelsoil.model.fit import CANDIDATES, prepare_data
    from wheelsoil.model.report import write_report

    inputs = [str(i) for i in inputs]
    if not inputs:
        raise ValueError("no input given")
    if not 0.0 <= slip_min < 1.0:
        raise ValueError(f"--slip-min must be in [0, 1), got {slip_min}")
    if wheel_radius is not None:  # the same plausibility check as the slip radius of processing
        from wheelsoil.processing.pipeline import check_wheel_radius

        wheel_radius = check_wheel_radius(wheel_radius, "--wheel-radius")
    ter = terrain if isinstance(terrain, Terrain) else load_terrain(terrain)
    models = list(models) if models else ["vasilev", "lyasko", "ding", "terrain_mismatch"]
    for m in models:
        if m not in CANDIDATES:
            raise ValueError(f"unknown model {m!r} in --models; choose from {', '.join(CANDIDATES)}")
    out = Path(out_dir)
    df, info = load_inputs(inputs, progress=progress, wheel_radius_m=wheel_radius)
    recording = "recording" in info["kinds"]
    r = wheel_radius or (info["wheel_radius_m"] if info["wheel_radius_m"] else DEFAULT_WHEEL.radius)
    b = wheel_width or (info["wheel_width_m"] if recording and info["wheel_width_m"] else DEFAULT_WHEEL.width)
    wheel = Wheel(float(r), float(b))
    source = inputs[0] if len(inputs) == 1 else f"{len(inputs)} inputs"
    try:
        data = prepare_data(df, slip_min=slip_min, source=source)
        diag = diagnose(data, ter, wheel, models=[m for m in models if m != "wong"], fit_terrain=fit_terrain,
                        sinkage=sinkage, progress=progress)
    except ValueError as exc:
        _failure_report(out, inputs, ter, wheel, slip_min, str(exc))
        raise ValueError(f"{exc} (a report saying so was written to {out / 'report.html'})") from None
    notes = list(info["notes"])
    if wheel_radius is None or wheel_width is None:
        notes.append(f"wheel radius {wheel.radius} m, width {wheel.width} m "
                     + ("from the vehicle configuration" if recording else "(the model's default wheel)")
                     + " where not given.")
    ts = _time_sync_summary(info["time_sync"]) if recording else {"gnss_latency_s": None}
    return write_report(diag, out, terrain=ter, wheel=wheel, inputs=inputs, time_sync=ts,
                        extra_notes=notes, progress=progress)


def _parse_models(text: str):
    return [m.strip() for m in text.split(",") if m.strip()]


def _handler(args) -> int:
    rep = run_fit(
        args.inputs,
        args.terrain,
        args.output,
        wheel_radius=args.wheel_radius,
        wheel_width=args.wheel_width,
        slip_min=args.slip_min,
        models=_parse_models(args.models) if args.models else None,
        fit_terrain=args.fit_terrain,
        sinkage=args.sinkage,
        progress=not args.quiet,
    )
    d, g = rep["diagnosis"], rep["gain"]

    def n(v, unit=" N"):
        return "n/a" if v is None else f"{v:.3g}{unit}"

    print(f"effect: {d['effect']}   model: {d['model']}   confidence: {d['confidence']}")
    print(f"Dp R0 (in sample): {n(g['R0_n_before'])} -> {n(g['R0_n_after'])};  "
          f"out of sample: {n(g['cv_R0_n_before'])} -> {n(g['cv_R0_n_after'])}")
    print(f"samples used: {rep['samples_used']} (slip > {rep['slip_min']})")
    if rep.get("not_done"):
        for x in rep["not_done"]:
            print(f"not done: {x}")
    print(f"report: {Path(args.output) / 'report.html'}")
    return 0


_EPILOG = """\
examples:
  wheelsoil fit run1.mcap run2.mcap --terrain clay --slip-min 0.2 -o reports/clay
  wheelsoil fit testbed.csv --terrain dry-sand --fit-terrain \\
      --wheel-radius 0.0625 --wheel-width 0.06 -o reports/testbed
  wheelsoil fit table.csv --terrain my_soil.toml --models wong,lyasko -o out/

inputs: a table CSV with columns slip, load_n [N], drawbar_pull_n [N] and optional
torque_nm [N m], sinkage_m [m] (one row per steady-state test point), or a recording
(.mcap) that is processed first. Several inputs of one terrain are fitted jointly.

output: DIR/report.html (self-contained, opens offline), DIR/report.json
(schema wheelsoil.report/1), DIR/*.png.

verdict: 'none' (Wong's residuals show no significant structure), 'slip_sinkage',
'terrain_mismatch' (lab K and phi re-fitted explain it), or 'unexplained'. A candidate
must lower the cross-validated error by >= 25 % and the BIC by >= 10; see
wheelsoil.model.diagnosis for the full rule.
"""


def register(subparsers) -> None:
    """Add the ``fit`` subcommand to the ``wheelsoil`` parser."""
    p = subparsers.add_parser(
        "fit",
        help="fit Wong's model and slip-sinkage models, diagnose, write a report",
        description="Fit Wong's model and the slip-sinkage candidates (Vasil'ev, Lyasko, Ding) and a terrain "
        "mismatch to measured data by Gauss-Newton, cross-validate, diagnose what Wong's model gets wrong, "
        "and write an HTML/PNG/JSON report.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="table CSV(s) or recording(s) (.mcap)")
    p.add_argument("--terrain", required=True,
                   help="built-in terrain slug (see 'wheelsoil terrains') or a terrain TOML file")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="report directory (created)")
    p.add_argument("--wheel-radius", type=float, default=None, metavar="R",
                   help="wheel radius [m] (default: vehicle config 0.47 for recordings, 0.47 for tables)")
    p.add_argument("--wheel-width", type=float, default=None, metavar="B",
                   help="wheel width [m] (default: vehicle config 0.32 for recordings, 0.32 for tables)")
    p.add_argument("--slip-min", type=float, default=0.1, metavar="S",
                   help="use samples with slip > S (default 0.1; the paper used 0.2 on clay, 0.1 on sand)")
    p.add_argument("--models", default=None,
                   help="comma list of candidates (default vasilev,lyasko,ding,terrain_mismatch; Wong always)")
    p.add_argument("--fit-terrain", action="store_true",
                   help="also fit terrain parameters (k_eq = kc/b + kphi, n, c, phi, K; those the data "
                   "identify) for soils without lab values")
    p.add_argument("--sinkage", choices=("eq10", "balance"), default="eq10",
                   help="static sinkage from Eq. 10 (default) or from the vertical force balance")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_handler)
