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
import re
from pathlib import Path

__all__ = ["run_fit", "load_inputs", "build_provenance", "register", "RECORDING_SUFFIXES"]

RECORDING_SUFFIXES = (".mcap", ".log", ".blf", ".asc", ".trc")
TABLE_SUFFIXES = (".csv", ".txt", ".tsv")
#: The columns read from a table (SI units; slip a fraction, Eq. 6): a steady-state table's, the
#: wheel it states, and the time series ``wheelsoil process`` writes (``wheelsoil.processing.COLUMNS``).
TABLE_COLUMNS = ("slip", "load_n", "drawbar_pull_n", "torque_nm", "sinkage_m", "wheel_radius_m", "wheel_width_m",
                 "t_s", "distance_m", "valid", "phase", "cycle", "fx_n", "my_nm", "speed_mps", "omega_radps")


def _read_table(path: Path):
    """Read a table file: ``(df, lines, notes)``.  ``df`` (column names stripped); ``lines``: the file
    line number (1-based) of each of its rows, from the lines the reader skipped (leading ``#`` comment
    lines, noted in ``notes``, and blank lines); ``notes``: what was skipped.  Raises ValueError naming
    the file for an empty or unreadable table, or a line before the header that is not a ``#`` comment
    (a title: the header must be the first line)."""
    import pandas as pd

    from wheelsoil.model.data import TABLE_NEEDS

    try:
        with open(path, encoding="utf-8-sig", errors="replace") as f:
            text = f.read().splitlines()
    except OSError as exc:
        raise ValueError(f"{path}: not readable: {exc}") from None
    n_comment = next((k for k, line in enumerate(text) if not line.lstrip().startswith("#")), len(text))
    head = text[n_comment] if n_comment < len(text) else ""
    sep = next((c for c in ("\t", ";") if c in head and "," not in head), ",")  # a tab or semicolon table
    names = [c.strip().lower() for c in head.split(sep)]
    if not any(c in names for c in TABLE_NEEDS + ("t_s",)):  # a title above the header?
        at = next((k for k, line in enumerate(text[n_comment + 1:n_comment + 20], n_comment + 1)
                   if sum(c in [x.strip().lower() for x in re.split(r"[,;\t]", line)] for c in TABLE_NEEDS) >= 2),
                  None)
        if at is not None:
            raise ValueError(f"{path}: line {at + 1} holds the header ({text[at].strip()[:80]}), line "
                             f"{n_comment + 1} is {head.strip()[:60]!r}: the header must be the first line; "
                             "delete the lines above it or start them with '#'")
    try:
        df = pd.read_csv(path, sep=sep, skiprows=n_comment)
    except pd.errors.EmptyDataError:
        raise ValueError(f"{path}: the table is empty (no header, no rows)") from None
    except (pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a readable CSV table: {exc}") from None
    df.columns = [str(c).strip() for c in df.columns]
    lines = [k + 1 for k in range(n_comment + 1, len(text)) if text[k].strip()]
    if len(lines) != len(df):  # quoted line breaks: the reader's rows are not the file's lines
        lines = list(range(n_comment + 2, n_comment + 2 + len(df)))
    notes = ([f"{path.name}: {n_comment} comment line(s) starting with '#' before the header skipped"]
             if n_comment else [])
    return df, lines, notes


def load_inputs(inputs, *, progress: bool = False, rate_hz: float = 100.0, cutoff_hz: float | None = None,
                wheel_radius_m: float | None = None, inertia: bool = True, wheel_mass_kg: float | None = None,
                wheel_inertia_kgm2: float | None = None, wheel_width_m: float | None = None, vehicle=None):
    """Read every input into one DataFrame for fitting.

    Returns ``(df, info)``: ``df`` has the fit columns plus ``run`` (input
    index) and, for recordings, ``t_s``, ``valid`` and ``cycle``; ``info`` is a
    dict with ``kinds`` (per input: ``table``/``recording``), ``time_sync`` (per
    input latency values, None for tables), ``wheel_radius_m``/``wheel_width_m``
    from the first recording (None for tables), ``notes``, ``results`` (per
    input the :class:`~wheelsoil.processing.ProcessResult`, None for a table:
    the report draws its overview and data quality from it) and ``tables``
    (per input the table's DataFrame, None for a recording).

    ``rate_hz``, ``cutoff_hz``, ``wheel_radius_m`` (slip radius, Eq. 6),
    ``inertia``, ``wheel_mass_kg`` and ``wheel_inertia_kgm2`` (the wheel outboard of the
    transducer, when not the configured one) are passed to ``process_recording`` for recordings.
    ``wheel_radius_m`` [m], when given, is the radius recordings compute slip
    with (Eq. 6; ``process_recording(wheel_radius_m=...)``), so the fit's radius
    is the slip radius; radius conflicts (recordings whose configurations
    disagree, a table's ``wheel_radius_m`` column, or a table's slip of unknown
    radius) are loud notes. ``processing`` lists per recording what processing
    did (``wheel_radius_m``/``_source``, ``inertia``, ``excluded``, ``quality``
    of ``ProcessResult``) for the report.  ``wheel_width_m`` [m]: the width given on the command line
    (a table stating another is a loud note).  Tables that state different wheels (columns or sidecars)
    are an error unless the command line gives the wheel: one fit has one wheel.

    A table's rows keep their file line numbers (column ``_line``, with ``_file``), so every message
    names the line; each table is checked as :func:`_check_table` says (exact copies of rows are
    marked ``_copy`` and not fitted; a constant optional channel is dropped with a loud note).

    Raises ValueError (naming the file) for a missing file, an unknown suffix,
    an unreadable table, a table failing :func:`_check_table`, tables stating different wheels,
    a recording processing cannot read, or one whose decoded signals no wheel can produce (a gross
    entry of ``ProcessResult.quality["implausible"]``: a vehicle configuration or DBC not the recording's).
    """
    import pandas as pd

    frames, kinds, sync, notes, processing, results, tables = [], [], [], [], [], [], []
    radius = width = table_source = None
    stated: dict = {}  # the first table stating a radius / a width: _check_one_wheel
    for i, raw in enumerate(inputs):
        path = Path(raw)
        if not path.exists():
            raise ValueError(f"{path}: no such file")
        if path.is_dir():
            raise ValueError(f"{path}: a directory; give the recordings or tables in it (e.g. {path}/*.mcap)")
        suffix = path.suffix.lower()
        if suffix in RECORDING_SUFFIXES:
            from wheelsoil.processing import process_recording

            res = process_recording(path, config=vehicle, progress=progress, rate_hz=rate_hz, cutoff_hz=cutoff_hz,
                                    wheel_radius_m=wheel_radius_m, inertia=inertia, wheel_mass_kg=wheel_mass_kg,
                                    wheel_inertia_kgm2=wheel_inertia_kgm2)
            gross = [i["text"] for i in (res.quality.get("implausible") or []) if i.get("gross")]
            if gross:
                raise ValueError(f"{path}: the decoded signals are not physical: " + "; ".join(gross)
                                 + ". A fit of them would mean nothing: decode the recording with the vehicle's own "
                                 "configuration and DBC files (--vehicle TOML; 'wheelsoil process' writes the signals "
                                 "to look at)")
            df = res.signals.copy()
            df["cycle"] = res.cycle
            kinds.append("recording")
            results.append(res)
            tables.append(None)
            sync.append({
                "input": str(path),
                "gnss_latency_s": res.gnss_latency_s,
                "gnss_latency_stderr_s": res.gnss_latency_stderr_s,
                "gps_time_mapping": res.gps_time_mapping,
            })
            res.warnings[:] = [_attachment_name(w, path) for w in res.warnings]
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
            df, lines, read_notes = _read_table(path)
            notes.extend(read_notes)
            kinds.append("table")
            results.append(None)
            tables.append(df)
            unused = [c for c in df.columns if c not in TABLE_COLUMNS]
            if unused:
                notes.append(f"{path.name}: column(s) not read: {', '.join(unused)} (a table's columns are "
                             f"{', '.join(TABLE_COLUMNS)}, in SI units; a channel in other units, e.g. "
                             "sinkage in mm, must be converted to be used)")
            from wheelsoil.processing.pipeline import check_wheel_radius, check_wheel_width

            tr, tw, tsrc = _table_wheel(path, df)
            tr = [check_wheel_radius(v, f"{path.name}: wheel_radius_m ({tsrc})") for v in tr]
            tw = [check_wheel_width(v, f"{path.name}: wheel_width_m ({tsrc})") for v in tw]
            side = _sidecar_note(path, tr, tw, tsrc)
            if side:
                notes.append(side)
            _check_one_wheel(path, tr, tw, tsrc, stated, wheel_radius_m, wheel_width_m)
            if len(tr) > 1 or (len(tr) == 1 and wheel_radius_m is not None
                               and abs(float(tr[0]) - wheel_radius_m) > 1e-6 * wheel_radius_m):
                notes.append(f"WHEEL RADIUS CONFLICT: {path.name} states wheel_radius_m = "
                             f"{', '.join(f'{float(x):g}' for x in tr)} m ({tsrc}); the fit uses "
                             f"{wheel_radius_m if wheel_radius_m is not None else float(tr[0]):g} m while the "
                             "table's slip was computed with its own radius (Eq. 6)")
            elif len(tr) == 1 and radius is None:
                radius = float(tr[0])
            elif wheel_radius_m is not None and not tr:
                notes.append(f"{path.name}: the table's slip was computed outside wheelsoil with a radius it "
                             f"does not state; the fit uses r = {wheel_radius_m:g} m: it must be the radius "
                             "that slip (Eq. 6) was computed with")
            if len(tw) > 1 or (len(tw) == 1 and wheel_width_m is not None
                               and abs(float(tw[0]) - wheel_width_m) > 1e-6 * wheel_width_m):
                notes.append(f"WHEEL WIDTH CONFLICT: {path.name} states wheel_width_m = "
                             f"{', '.join(f'{float(x):g}' for x in tw)} m ({tsrc}); the fit uses "
                             f"{wheel_width_m if wheel_width_m is not None else float(tw[0]):g} m")
            if len(tw) and width is None:
                width = float(tw[0])
            if (len(tr) or len(tw)) and table_source is None:
                table_source = f"{path.name}: {tsrc}"
            from wheelsoil.model import DEFAULT_WHEEL

            r_torque = next(float(v) for v in (wheel_radius_m, *tr, DEFAULT_WHEEL.radius) if v is not None)
            df, checked = _check_table(path, df, lines, r_torque)
            notes.extend(checked)
            sync.append({"input": str(path), "gnss_latency_s": None})
        else:
            raise ValueError(
                f"{path}: unknown input type {suffix!r}; give a table (.csv) or a recording "
                f"({', '.join(RECORDING_SUFFIXES)})"
            )
        df = df.copy()
        df["run"] = i
        frames.append(df)
    if not frames:
        raise ValueError("no input given")
    _check_not_the_same_run(inputs, results)
    if len(set(kinds)) > 1:
        raise ValueError(f"{', '.join(map(str, inputs))}: tables and recordings cannot be fitted jointly (a table's "
                         "rows have no accelerate cycles, time base or processing validity); fit them separately, "
                         "or write the recordings as tables with 'wheelsoil process' first")
    df = pd.concat(frames, ignore_index=True, sort=False)
    if "t_s" in df.columns and df["t_s"].isna().any():  # tables mixed with recordings
        df["t_s"] = df["t_s"].fillna(df.groupby("run").cumcount().astype(float))
    return df, {"kinds": kinds, "time_sync": sync, "wheel_radius_m": radius, "wheel_width_m": width,
                "table_wheel_source": table_source, "notes": notes, "processing": processing, "results": results,
                "tables": tables}


def _check_not_the_same_run(inputs, results) -> None:
    """Refuse two recordings whose processed spans (host time, ``ProcessResult.t0_ns`` and ``t_s``) overlap
    by more than half the shorter: the same run in two files (a recovered copy, an import of the same log),
    which would count every cycle twice.  ``results`` (None for tables) in the order of ``inputs``.
    Raises ValueError naming both files and the overlap."""
    spans = []
    for raw, res in zip(inputs, results):
        if res is None or res.signals is None or not len(res.signals):
            continue
        t = res.signals["t_s"]
        spans.append((Path(raw), res.t0_ns * 1e-9 + float(t.min()), res.t0_ns * 1e-9 + float(t.max())))
    for i, (pa, a0, a1) in enumerate(spans):
        for pb, b0, b1 in spans[i + 1:]:
            overlap = min(a1, b1) - max(a0, b0)
            if overlap > 0.5 * min(a1 - a0, b1 - b0) and overlap > 0:
                raise ValueError(f"{pa} and {pb}: they cover the same {overlap:.0f} s of logging time: the same run "
                                 "in two files (a recovered copy, or an import of the same log?) would count every "
                                 "cycle twice; give it once (two runs logged at the same time, by two vehicles: fit "
                                 "them separately)")


def _check_distinct(inputs) -> None:
    """Refuse an input given twice (the same file, or the same bytes under two names): fitting it
    twice doubles its weight and makes the run look like two runs that agree.  Raises ValueError."""
    from collections import Counter

    from wheelsoil.daq.provenance import file_sha256

    paths = [Path(raw) for raw in inputs]
    paths = [p for p in paths if p.is_file()]  # load_inputs names what is wrong with the others
    sizes = Counter(p.stat().st_size for p in paths)
    seen: dict = {}
    for path in paths:
        if sizes[path.stat().st_size] < 2:
            continue  # no other input of its size: nothing to read (a field recording can be gigabytes)
        key = file_sha256(path)
        if key in seen:
            raise ValueError(f"{path}: the same data as {seen[key]} (sha256 {key[:12]}...); give each run once")
        seen[key] = path


def _table_wheel(path: Path, df) -> tuple[list, list, str]:
    """The wheel a table states: its ``wheel_radius_m`` / ``wheel_width_m`` columns, else a sidecar
    ``<table>.json`` next to it with ``{"wheel": {"radius_m": R, "width_m": B}}`` (or the keys
    ``wheel_radius_m`` / ``wheel_width_m`` at its top level), the way measured data sets describe
    their wheel.  Returns ``(radii, widths, source)``: the distinct finite values [m] (empty when
    not stated) and where they came from.  Raises ValueError (naming the file) for a sidecar
    that is not valid JSON or states a non-numeric geometry."""
    import json

    import pandas as pd

    def column(name):
        return [float(v) for v in pd.to_numeric(df[name], errors="coerce").dropna().unique()] if name in df.columns else []

    radii, widths = column("wheel_radius_m"), column("wheel_width_m")
    if radii or widths:
        return radii, widths, "its wheel_radius_m/wheel_width_m columns"
    side = path.with_suffix(".json")
    if not side.is_file():
        return [], [], ""
    try:
        meta = json.loads(side.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise ValueError(f"{side}: the table's sidecar is not readable JSON: {exc}") from None
    wheel = meta.get("wheel") if isinstance(meta, dict) and isinstance(meta.get("wheel"), dict) else {}
    out = []
    for key, top in (("radius_m", "wheel_radius_m"), ("width_m", "wheel_width_m")):
        v = wheel.get(key, meta.get(top) if isinstance(meta, dict) else None)
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0):
            raise ValueError(f"{side}: wheel {key} = {v!r} is not a positive number of metres")
        out.append([float(v)] if v is not None else [])
    return out[0], out[1], f"its sidecar {side.name}"


def _sidecar_note(path: Path, radii: list, widths: list, source: str) -> str | None:
    """A loud note when the table's sidecar ``<table>.json`` exists but does not state the radius or the
    width in the layout read (``{"wheel": {"radius_m": R, "width_m": B}}``), naming the keys it has
    (e.g. ``radius_m`` at its top level, ``wheel.diameter_m``); None when nothing is missing, the
    table's columns state the wheel, or there is no sidecar.  ``radii``/``widths``: what
    :func:`_table_wheel` read (m)."""
    import json

    side = path.with_suffix(".json")
    if (radii and widths) or "columns" in source or not side.is_file():
        return None
    meta = json.loads(side.read_text(encoding="utf-8"))  # _table_wheel read it
    keys = ([f"{k}.{sub}" if isinstance(v, dict) else k for k, v in meta.items()
             for sub in (v if isinstance(v, dict) else [None])] if isinstance(meta, dict) else [])
    missing = [k for k, got in (("wheel.radius_m", radii), ("wheel.width_m", widths)) if not got]
    return (f"{path.name}: WHEEL SIDECAR INCOMPLETE: {side.name} was found but has no {' and no '.join(missing)} "
            f"(its keys: {', '.join(keys[:15]) + (' ...' if len(keys) > 15 else '') or 'none'}); the layout read is "
            '{"wheel": {"radius_m": R, "width_m": B}} in metres (a radius, not a diameter)')


def _check_one_wheel(path: Path, radii: list, widths: list, source: str, stated: dict,
                     radius_given: float | None, width_given: float | None) -> None:
    """Refuse a table whose stated wheel (``radii``/``widths`` [m] from ``source``) differs from the one
    an earlier table of the same fit stated (``stated``: kind -> (file, value, source), updated here),
    unless the command line gives that size (``radius_given``/``width_given``: then each table's
    conflict is a note).  Raises ValueError naming both files and both wheels."""
    for kind, vals, given in (("radius", radii, radius_given), ("width", widths, width_given)):
        if len(vals) != 1 or given is not None:
            continue
        first = stated.setdefault(kind, (path, float(vals[0]), source, radii, widths))
        if abs(first[1] - float(vals[0])) > 1e-6 * first[1]:
            def wheel(r, b):
                return (f"r = {', '.join(f'{float(x):g}' for x in r) or '?'} m, "
                        f"b = {', '.join(f'{float(x):g}' for x in b) or '?'} m")
            raise ValueError(f"{first[0]} and {path}: the tables state different wheels, {wheel(first[3], first[4])} "
                             f"({first[2]}) and {wheel(radii, widths)} ({source}); one fit has one wheel (the "
                             "models' forces and sinkage scale with it): fit them separately, one wheel per fit "
                             "(or give --wheel-radius and --wheel-width if it is one wheel)")


#: Below this fraction of the table's median load (of r times it for the torque), every drawbar pull
#: (torque) of a table is not a wheel's in soil but one in kN (kN m): a 0.3 Dp/W becomes 0.0003.
MIN_CHANNEL_OVER_LOAD = 0.005


def _check_table(path: Path, df, lines: list, radius_m: float):
    """Checks of one table's measured channels before it is fitted; returns ``(df, notes)``.

    ``df``: the table as read (N rows); ``lines``: the file line of each row (N,); ``radius_m`` [m]:
    the wheel's radius (the torque's scale).  The returned ``df`` has the columns ``_line`` (the
    file line), ``_file`` (the file name) and ``_copy`` (True: an exact copy of an earlier row, not
    fitted, said in a note) added; a ``torque_nm`` or ``sinkage_m`` of one value on every line (not
    measured) is dropped with a loud note (``COLUMN DROPPED``).

    Raises ValueError naming the file and the column for a ``drawbar_pull_n`` of one value on every
    line, a ``sinkage_m`` negative on most lines (sinkage is positive below the surface), or a
    ``drawbar_pull_n`` (``torque_nm``) below ``MIN_CHANNEL_OVER_LOAD`` of the median load (times
    ``radius_m``) on every line (kN, kN m given for N, N m).
    """
    import numpy as np
    import pandas as pd

    from wheelsoil.model.data import format_lines

    notes: list[str] = []
    lines = np.asarray(lines, int)
    num = {c: pd.to_numeric(df[c], errors="coerce").to_numpy(float)
           for c in ("load_n", "drawbar_pull_n", "torque_nm", "sinkage_m") if c in df.columns}
    for col in ("drawbar_pull_n", "torque_nm", "sinkage_m"):
        v = num.get(col, np.zeros(0))
        v = v[np.isfinite(v)]
        if v.size >= 3 and np.all(v == v[0]):
            if col == "drawbar_pull_n":
                raise ValueError(f"{path}: drawbar_pull_n is {v[0]:g} on every line: not a measurement; the models "
                                 "are fitted to the drawbar pull, give the measured values")
            notes.append(f"{path.name}: COLUMN DROPPED: {col} is {v[0]:g} on every line: not measured? leave the "
                         "column out; the fit does without it")
            df = df.drop(columns=col)
            del num[col]
    if "sinkage_m" in num:
        z = num["sinkage_m"]
        with np.errstate(invalid="ignore"):
            neg = np.flatnonzero(z < 0)
        if neg.size > np.isfinite(z).sum() / 2:
            raise ValueError(f"{path}: sinkage_m is negative on {neg.size} of {int(np.isfinite(z).sum())} lines "
                             f"({format_lines(lines[neg])}): sinkage is the depth below the undisturbed surface, "
                             "positive downwards; flip the column's sign")
    w = num.get("load_n", np.zeros(0))
    w = w[np.isfinite(w) & (w > 0)]
    for col, scale, unit in (("drawbar_pull_n", 1.0, "kN"), ("torque_nm", radius_m, "kN m")):
        v = np.abs(num.get(col, np.zeros(0)))
        v = v[np.isfinite(v)]
        if w.size and v.size >= 3 and np.all(v < MIN_CHANNEL_OVER_LOAD * scale * np.median(w)):
            bound = (f"{MIN_CHANNEL_OVER_LOAD:.1%} of "
                     + ("" if col == "drawbar_pull_n" else f"r = {radius_m:g} m times "))
            raise ValueError(f"{path}: {col} is below {bound}the median load ({np.median(w):.4g} N) on every line "
                             f"(largest |value| {v.max():.4g}): in {unit}? the column must be in "
                             f"{'N' if unit == 'kN' else 'N m'} (multiply by 1000)")
    copy = df.duplicated().to_numpy()
    if copy.any():
        notes.append(f"{path.name}: {int(copy.sum())} row(s) are exact copies of earlier rows "
                     f"({format_lines(lines[copy])}) and are not used: each test point counts once (a table pasted twice?)")
    df = df.assign(_line=lines, _file=path.name, _copy=copy)
    return df, notes


def _attachment_name(warning: str, path: Path) -> str:
    """A warning about the recording's attached configuration names the attachment, not the
    temporary directory it was unpacked to (which differs on every run: the report must not)."""
    import re

    return re.sub(r"\S*wheelsoil-cfg-[^/\s]+/", f"{path.name}:attached ", warning)


def _time_sync_summary(sync: list) -> dict:
    lat = [s["gnss_latency_s"] for s in sync if s.get("gnss_latency_s") is not None]
    out = {"gnss_latency_s": (sum(lat) / len(lat)) if lat else None}
    if len(sync) == 1:
        out.update({k: v for k, v in sync[0].items() if k != "input"})
    else:
        out["per_input"] = sync
    return out


# ----------------------------------------------------------------------------- provenance

_HIDDEN_KEYS = ("effect", "truth", "hidden_effect", "params", "family", "acceptable")


_HIDDEN_OPTIONS = ("--effect", "--param", "--size")


def _hide_effect(command: list) -> list:
    """A ``wheelsoil simulate`` argument list with the hidden effect's options blanked
    (``--effect X`` -> ``--effect (hidden)``; also ``--param``, ``--size`` and their ``=`` forms)."""
    out, hide = [], False
    for a in map(str, command):
        if hide:
            out.append("(hidden)")
            hide = False
        elif a in _HIDDEN_OPTIONS:
            out.append(a)
            hide = True
        elif a.startswith(tuple(o + "=" for o in _HIDDEN_OPTIONS)):
            out.append(a.split("=", 1)[0] + "=(hidden)")
        else:
            out.append(a)
    return out


def _version() -> str:
    from wheelsoil import __version__

    return __version__


def _environment() -> dict:
    """Versions of the interpreter and the numeric libraries (results depend on them)."""
    import platform
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": platform.python_version()}
    for pkg in ("numpy", "scipy", "pandas", "matplotlib", "mcap", "cantools"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = None
    return out


def _vehicle_config_record(path: Path | None, vehicle=None) -> dict:
    """The vehicle configuration a recording was processed with: its source, wheel geometry and
    mass/inertia, and the sha256 of vehicle.toml and of each DBC (the attached files, else the
    shipped default)."""
    import hashlib

    def sha(b: bytes) -> str:
        return hashlib.sha256(b).hexdigest()

    attached = {}
    if vehicle is not None:  # given (fit --vehicle): what processing used
        from wheelsoil.daq import VehicleConfig, load_vehicle_config

        cfg = vehicle if isinstance(vehicle, VehicleConfig) else load_vehicle_config(vehicle)
        return _wheel_record(_files_record(cfg, f"given: {cfg.source or 'a VehicleConfig object'}"), cfg)
    if path is not None and path.suffix.lower() == ".mcap":
        try:
            from wheelsoil.daq.recording import read_attachments

            attached = read_attachments(path)
        except (OSError, ValueError):
            attached = {}
    cfg = None
    rec: dict = {}
    if "vehicle.toml" in attached:
        try:
            from wheelsoil.daq.info import config_from_attachments

            cfg = config_from_attachments(attached)
        except (ValueError, OSError) as exc:
            rec["warning"] = f"attached configuration unusable ({exc}); processing used the default"
        if cfg is not None:
            rec.update({"source": f"attached to {path.name}", "sha256": sha(attached["vehicle.toml"]),
                        "dbcs": [{"name": n[4:], "sha256": sha(b)} for n, b in sorted(attached.items())
                                 if n.startswith("dbc/")]})
    if cfg is None:
        from wheelsoil.daq import load_vehicle_config

        cfg = load_vehicle_config()
        rec.update(_files_record(cfg, f"shipped default {Path(cfg.source).name if cfg.source else 'vehicle.toml'}"))
    return _wheel_record(rec, cfg)


def _files_record(cfg, source: str) -> dict:
    """``{"source", "sha256", "dbcs"}`` of a configuration read from files: the sha256 of its vehicle.toml (None
    without one) and of each DBC file, by name."""
    from wheelsoil.daq.provenance import file_sha256

    src = Path(cfg.source) if cfg.source else None
    return {"source": source, "sha256": file_sha256(src) if src and src.exists() else None,
            "dbcs": sorted(({"name": p.name, "sha256": file_sha256(p)} for ps in cfg.buses.values() for p in ps),
                           key=lambda d: d["name"])}


def _wheel_record(rec: dict, cfg) -> dict:
    """``rec`` with the configuration's name and wheel (radius, width, mass, inertia)."""
    rec.update({"name": getattr(cfg, "name", ""), "wheel_radius_m": float(cfg.wheel_radius_m),
                "wheel_width_m": float(cfg.wheel_width_m)})
    for k in ("wheel_mass_kg", "wheel_inertia_kgm2"):  # interface B (proc)
        v = getattr(cfg, k, None)
        rec[k] = None if v is None else float(v)
    return rec


def _damaged(warnings) -> list:
    keys = ("damaged", "crc", "corrupt", "truncat", "chunk")
    return [w for w in warnings if any(k in w.lower() for k in keys)]


def _find_key(obj, word: str):
    """First value whose key contains ``word`` in nested dicts (None if absent)."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            if word in str(k).lower() and not isinstance(v, dict):
                return v
        for v in obj.values():
            got = _find_key(v, word)
            if got is not None:
                return got
    return None


def _input_record(path: Path, kind: str, res, table, vehicle=None) -> tuple[dict, dict]:
    """(provenance entry, data-quality dict) of one input."""
    from wheelsoil.daq.provenance import file_sha256

    entry = {"path": str(path), "sha256": file_sha256(path), "size_bytes": path.stat().st_size}
    if kind == "table":
        entry["provenance"] = {"kind": "table"}
        return entry, {"input": str(path), "kind": "table", "rows": int(len(table)) if table is not None else None}
    info = None
    if path.suffix.lower() == ".mcap":
        from wheelsoil.daq.info import read_recording_info

        try:
            info = read_recording_info(path)
        except (OSError, ValueError) as exc:
            entry["provenance"] = {"kind": "unknown", "detail": f"recording info unreadable: {exc}"}
    if info is not None:
        prov = info.provenance
        if prov is None:
            prov = {"kind": "unknown", "detail": "the recording has no wheelsoil.provenance record"}
        elif prov.get("kind") == "simulated":  # the hidden effect stays hidden
            prov = {k: v for k, v in prov.items() if k not in _HIDDEN_KEYS}
            if isinstance(prov.get("command"), list):
                prov["command"] = _hide_effect(prov["command"])
        entry["provenance"] = prov
    elif "provenance" not in entry:
        entry["provenance"] = {"kind": "log file", "format": path.suffix.lower().lstrip("."),
                               "detail": "imported into a temporary recording for processing"}
    entry["vehicle_config"] = _vehicle_config_record(path, vehicle)
    sig = res.signals
    warns = list(res.warnings) + ([w for w in info.warnings if w not in res.warnings] if info else [])
    imp = _import_record(info)
    quality = {
        "input": str(path),
        "kind": "recording",
        "duration_s": float(len(sig) / res.rate_hz) if res.rate_hz else None,
        "rate_hz": res.rate_hz,
        "cutoff_hz": res.cutoff_hz,
        "wheel_radius_m": res.wheel_radius_m,
        "wheel_radius_source": getattr(res, "wheel_radius_source", None),
        "valid_share": float(sig["valid"].mean()) if len(sig) else None,
        "lost_frames": {k: dict(v) for k, v in sorted((res.lost_frames or {}).items())},
        "imported": entry["provenance"].get("kind") in ("imported", "log file") or imp is not None,
        "rejected_frames": next((v for v in (_find_key(imp or {}, "rejected"),
                                             _find_key(entry["provenance"], "rejected")) if v is not None),
                                "; ".join(w for w in warns if "reject" in w.lower()) or None),
        "import_record": imp,
        "damaged_chunks": _damaged(warns),
        "complete": None if info is None else bool(info.complete),
        "kernel_rx_dropped": None if info is None else {
            b: v.get("rx_dropped") for b, v in sorted(((info.status or {}).get("buses") or {}).items())},
        "gnss_fix": _gnss_fix(res),
        "gnss_latency_s": res.gnss_latency_s,
        "gnss_latency_stderr_s": res.gnss_latency_stderr_s,
        "latency_reference": res.latency_reference,
        "inertia": dict(getattr(res, "inertia", {}) or {}),  # interface C (proc)
        "excluded_spans": list(getattr(res, "excluded", []) or []),
        "processing_quality": dict(getattr(res, "quality", {}) or {}),
        "warnings": warns,
    }
    return entry, quality


def _import_record(info) -> dict | None:
    """The ``wheelsoil.import`` metadata record of an imported recording (values JSON-decoded)."""
    import json

    rec = ((info.metadata if info is not None else None) or {}).get("wheelsoil.import")
    if not rec:
        return None
    out = {}
    for k, v in rec.items():
        try:
            out[k] = json.loads(v)
        except (TypeError, ValueError):
            out[k] = v
    return out


def _gnss_fix(res) -> dict:
    """GNSS fix quality as processing reports it (``quality["gnss_fix"]``), else what the GPS time
    mapping tells (fixes used, outliers, residual)."""
    q = getattr(res, "quality", None) or {}
    if isinstance(q.get("gnss_fix"), dict):
        return dict(q["gnss_fix"])
    g = res.gps_time_mapping or {}
    if not g:
        return {"time_fixes": 0, "detail": "no GPS time mapping (see warnings)"}
    return {"time_fixes_used": g.get("n"), "time_fix_outliers": g.get("n_outliers"),
            "time_residual_rms_s": g.get("residual_rms_s")}


def _terrain_setting(terrain, ter, wheel) -> dict:
    from wheelsoil.daq.provenance import file_sha256
    from wheelsoil.model import TERRAINS
    from wheelsoil.model.report import _terrain_dict

    out = {"argument": terrain if isinstance(terrain, str) else None}
    if isinstance(terrain, str) and terrain in TERRAINS:
        out["source"] = "built-in"
    elif isinstance(terrain, str):
        p = Path(terrain.partition("#")[0])
        out["source"] = "file"
        out["sha256"] = file_sha256(p) if p.exists() else None
    else:
        out["source"] = "Terrain object (library call)"
    out["values"] = _terrain_dict(ter, wheel)
    return out


def _equivalent_command(inputs, terrain, out_dir, *, wheel_radius, wheel_width, slip_min, models, fit_terrain,
                        sinkage, rate_hz, cutoff_hz, inertia, wheel_mass=None, wheel_inertia=None,
                        vehicle=None) -> list | None:
    """The ``wheelsoil fit`` argument list that repeats a library call (None: the terrain is an object)."""
    if not isinstance(terrain, str):
        return None
    cmd = ["wheelsoil", "fit", *map(str, inputs), "--terrain", terrain, "-o", str(out_dir),
           "--slip-min", repr(float(slip_min)), "--models", ",".join(models), "--sinkage", sinkage,
           "--rate", repr(float(rate_hz))]
    if cutoff_hz is not None:
        cmd += ["--cutoff", repr(float(cutoff_hz))]
    if wheel_radius is not None:
        cmd += ["--wheel-radius", repr(float(wheel_radius))]
    if wheel_width is not None:
        cmd += ["--wheel-width", repr(float(wheel_width))]
    if wheel_mass is not None:
        cmd += ["--wheel-mass", repr(float(wheel_mass))]
    if wheel_inertia is not None:
        cmd += ["--wheel-inertia", repr(float(wheel_inertia))]
    if fit_terrain:
        cmd.append("--fit-terrain")
    if not inertia:
        cmd.append("--no-inertia")
    if vehicle is not None:
        if not isinstance(vehicle, (str, Path)):
            return None  # a configuration object: no command repeats it
        cmd += ["--vehicle", str(vehicle)]
    return cmd


def build_provenance(inputs, info, *, command, terrain, ter, wheel, wheel_source, settings,
                     vehicle=None) -> tuple[dict, list]:
    """The report's provenance (``version, command, cwd, environment, inputs, vehicle_config,
    settings, created``) and the per-input data-quality dicts.

    ``inputs``: the paths; ``info``: :func:`load_inputs`'s info; ``command``:
    argument list; ``settings``: the fit's settings (this adds the terrain and
    the wheel).  Reads each input once more for its sha256 and, for a recording,
    its own provenance (``read_recording_info``).  Raises OSError for an input
    that cannot be read.
    """
    import os
    import time

    entries, quality = [], []
    for path, kind, res, table in zip(inputs, info["kinds"], info["results"], info["tables"]):
        e, q = _input_record(Path(path), kind, res, table, vehicle)
        entries.append(e)
        quality.append(q)
    first_cfg = next((e["vehicle_config"] for e in entries if "vehicle_config" in e), None)
    vc = dict(first_cfg) if first_cfg else {"source": "none (table input): the wheel as wheel_source says"}
    vc["wheel_radius_used_m"] = wheel.radius
    vc["wheel_width_used_m"] = wheel.width
    vc["wheel_source"] = wheel_source
    st = dict(settings)
    res0 = next((r for r in info["results"] if r is not None), None)
    if res0 is not None:
        st["cutoff_hz_used"] = res0.cutoff_hz
        st["rate_hz_used"] = res0.rate_hz
        ine = getattr(res0, "inertia", None)
        st["inertia_applied"] = bool(ine.get("applied")) if isinstance(ine, dict) and ine else False
    st["terrain"] = _terrain_setting(terrain, ter, wheel)
    prov = {
        "version": _version(),
        "command": list(command) if command is not None else None,
        "cwd": os.getcwd(),
        "environment": _environment(),
        "inputs": entries,
        "vehicle_config": vc,
        "settings": st,
        "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    return prov, quality


def _failure_report(out_dir: Path, inputs, terrain, wheel, slip_min, error: str, provenance=None,
                    effect: str | None = None) -> dict:
    """Write a report.json/report.html that says what could not be done; returns the report dict.
    ``effect``: the verdict the failure itself gives (``unexplained`` when Wong's model on the lab
    terrain buries the wheel the run measured carrying its load), else None."""
    import html
    import json

    from wheelsoil.model.report import ALL_MODELS, SCHEMA, _clean, _terrain_dict, clear_figures

    clear_figures(out_dir)
    rep = _clean({
        "schema": SCHEMA,
        "input": [str(i) for i in inputs],
        "provenance": provenance or {},
        "terrain": _terrain_dict(terrain, wheel),
        "wheel": {"radius_m": wheel.radius, "width_m": wheel.width},
        "samples_used": 0,
        "slip_min": slip_min,
        "time_sync": {"gnss_latency_s": None},
        "models": {m: {"status": f"not fitted: {error}", "params": None, "stderr": None,
                       "metrics": {"M0_pct": None, "R0_n": None, "R2": None}, "cv_R0_n": None, "bic": None}
                   for m in ALL_MODELS},
        "diagnosis": {"effect": effect, "model": None, "confidence": "medium" if effect else None,
                      "why": "wheel_buried" if effect == "unexplained" else None,
                      "summary": (f"Wong's model errs on these data, and the cause is {effect}: {error}." if effect
                                  else f"Nothing could be fitted: {error}")},
        "gain": {"R0_n_before": None, "R0_n_after": None, "cv_R0_n_before": None, "cv_R0_n_after": None},
        "flags": [],
        "not_done": [f"fit and diagnosis: {error}"],
    })
    (out_dir / "report.json").write_text(json.dumps(rep, indent=2, allow_nan=False), encoding="utf-8")
    cmd = " ".join((provenance or {}).get("command") or [])
    (out_dir / "report.html").write_text(
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
        "<meta name='viewport' content='width=device-width, initial-scale=1'><title>wheelsoil fit report</title>"
        f"</head><body><h1>wheelsoil fit report</h1><p><b>"
        + (f"Verdict: {effect}. Wong's model errs on these data; nothing could be fitted from the lab terrain."
           if effect else "Nothing could be fitted.") + f"</b></p><p>{html.escape(error)}</p>"
        f"<p>Inputs: {html.escape(', '.join(map(str, inputs)))}</p>"
        + (f"<p>Command: <code>{html.escape(cmd)}</code></p>" if cmd else "") + "</body></html>",
        encoding="utf-8",
    )
    return rep


DEFAULT_MODELS = ("vasilev", "lyasko", "ding", "terrain_mismatch")


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
    sinkage: str = "auto",
    rate_hz: float = 100.0,
    cutoff_hz: float | None = None,
    inertia: bool = True,
    progress: bool = False,
    command: list | None = None,
    wheel_mass: float | None = None,
    wheel_inertia: float | None = None,
    vehicle=None,
) -> dict:
    """Fit Wong's model and the candidates to the inputs, diagnose, write the report.

    Parameters
    ----------
    inputs : list of paths (table CSVs and/or recordings), fitted jointly.
    terrain : a built-in terrain slug, a TOML path, or a ``Terrain``.
    out_dir : report directory (``report.html``, ``report.json``, ``*.png``).
    wheel_radius, wheel_width : [m]; default: the vehicle config's (0.47/0.32)
        for recordings; for tables what the table states (``wheel_radius_m`` /
        ``wheel_width_m`` columns, else a sidecar ``<table>.json``: :func:`_table_wheel`),
        else the model's ``DEFAULT_WHEEL`` with a "WHEEL GEOMETRY ASSUMED" note.  The
        radius is also the slip radius of Eq. (6) for recordings.
    slip_min : samples with s <= slip_min are not used (paper: 0.2 clay, 0.1 sand).
    models : hypotheses to try (default: every hypothesis of the registry; the legacy list
        ``vasilev, lyasko, ding, terrain_mismatch`` means the same; Wong always).
    fit_terrain : fit the terrain parameters too (k_eq = kc/b + kphi, n, c, phi, K,
        those the data identify).
    sinkage : ``auto`` (default: on data with measured sinkage the static-sinkage law the data choose,
        else Eq. 10; :func:`wheelsoil.model.diagnosis.diagnose`), ``eq10`` or ``balance``.
    rate_hz, cutoff_hz, inertia : processing of recordings (grid rate [Hz],
        low-pass cutoff [Hz], None = processing's default; wheel inertia
        compensation on/off).
    wheel_mass, wheel_inertia : the wheel outboard of the transducer [kg], [kg m^2] for the
        inertia compensation of recordings; default: the vehicle configuration's (80 kg,
        11.5 kg m^2 in hardware.md's).
    vehicle : recordings and CAN logs: the vehicle configuration (a ``vehicle.toml`` path or a
        ``VehicleConfig``: buses, DBC files, signals, wheel) to decode and process them with; default:
        a recording's attached one, else (a CAN log) the shipped one.
    progress : tqdm progress bars on stderr.
    command : the argument list that ran this (the CLI passes it); None: the
        equivalent ``wheelsoil fit`` command is recorded.

    Returns the report dict (``report.json``), with its ``provenance``: the
    version, command, working directory, inputs (sha256 and their own
    provenance), vehicle configuration and DBCs, every setting and the
    analysis time; re-running the command gives the same report.json except
    ``provenance.created``.

    Raises
    ------
    ValueError
        Unreadable input, unknown terrain or a terrain file missing a key, an output that is an
        existing file or a directory of files no report writes (checked first), or data nothing
        can be fitted to (then a report saying so is still written).
    OSError
        The output directory cannot be written.
    """
    from wheelsoil.model import DEFAULT_WHEEL, Terrain, Wheel, load_terrain
    from wheelsoil.model.diagnosis import LabTerrainBuriesWheel, diagnose
    from wheelsoil.model.fit import CANDIDATES, prepare_data
    from wheelsoil.model.report import foreign_files, write_report

    inputs = [str(i) for i in inputs]
    if not inputs:
        raise ValueError("no input given")
    if not 0.0 <= slip_min < 1.0:
        raise ValueError(f"--slip-min must be in [0, 1), got {slip_min}")
    from wheelsoil.processing.pipeline import check_wheel_radius, check_wheel_width

    if wheel_radius is not None:  # the same plausibility check as the slip radius of processing
        wheel_radius = check_wheel_radius(wheel_radius, "--wheel-radius")
    if wheel_width is not None:
        wheel_width = check_wheel_width(wheel_width, "--wheel-width")
    _check_distinct(inputs)
    ter = terrain if isinstance(terrain, Terrain) else load_terrain(terrain)
    models = list(models) if models else list(DEFAULT_MODELS)
    for m in models:
        if m not in CANDIDATES:
            raise ValueError(f"unknown model {m!r} in --models; choose from {', '.join(CANDIDATES)}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():  # before the fit, not after it
        raise ValueError(f"{out}: the report directory (-o) is an existing file; give a directory")
    foreign = foreign_files(out) if out.is_dir() else []
    if foreign:
        raise ValueError(f"{out}: the report directory (-o) holds files no wheelsoil report writes ("
                         + ", ".join(foreign[:5]) + (", ..." if len(foreign) > 5 else "")
                         + "); give a new or empty directory (an earlier report there is replaced)")
    if command is None:
        command = _equivalent_command(inputs, terrain, out_dir, wheel_radius=wheel_radius, wheel_width=wheel_width,
                                      slip_min=slip_min, models=models, fit_terrain=fit_terrain, sinkage=sinkage,
                                      rate_hz=rate_hz, cutoff_hz=cutoff_hz, inertia=inertia,
                                      wheel_mass=wheel_mass, wheel_inertia=wheel_inertia, vehicle=vehicle)
    df, info = load_inputs(inputs, progress=progress, rate_hz=rate_hz, cutoff_hz=cutoff_hz,
                           wheel_radius_m=wheel_radius, inertia=inertia, wheel_mass_kg=wheel_mass,
                           wheel_inertia_kgm2=wheel_inertia, wheel_width_m=wheel_width, vehicle=vehicle)
    recording = "recording" in info["kinds"]
    stated = "vehicle configuration" if recording else info["table_wheel_source"]
    r = next(v for v in (wheel_radius, info["wheel_radius_m"], DEFAULT_WHEEL.radius) if v is not None)
    b = next(v for v in (wheel_width, info["wheel_width_m"], DEFAULT_WHEEL.width) if v is not None)
    wheel = Wheel(float(r), float(b))
    from wheelsoil.model.terrain import check_k_eq

    check_k_eq(ter, wheel.width, terrain if isinstance(terrain, str) else f"terrain {ter.name!r}")
    wheel_source = ("radius: " + ("command line" if wheel_radius is not None else
                                  stated if info["wheel_radius_m"] is not None else "model default")
                    + ", width: " + ("command line" if wheel_width is not None else
                                     stated if info["wheel_width_m"] is not None else "model default"))
    settings = {
        "slip_min": float(slip_min),
        "models": ["wong", *[m for m in models if m != "wong"]],
        "fit_terrain": bool(fit_terrain),
        "sinkage": sinkage,
        "rate_hz": float(rate_hz),
        "cutoff_hz": None if cutoff_hz is None else float(cutoff_hz),
        "inertia": bool(inertia),
        "wheel_mass_kg": None if wheel_mass is None else float(wheel_mass),  # None: the vehicle configuration's
        "wheel_inertia_kgm2": None if wheel_inertia is None else float(wheel_inertia),
        "wheel_radius_m": wheel.radius,
        "wheel_width_m": wheel.width,
    }
    prov, quality = build_provenance(inputs, info, command=command, terrain=terrain, ter=ter, wheel=wheel,
                                     wheel_source=wheel_source, settings=settings, vehicle=vehicle)
    source = inputs[0] if len(inputs) == 1 else f"{len(inputs)} inputs"
    try:
        data = prepare_data(df, slip_min=slip_min, source=source, wheel_radius_m=wheel.radius)
        diag = diagnose(data, ter, wheel, models=[m for m in models if m != "wong"], fit_terrain=fit_terrain,
                        sinkage=sinkage, progress=progress)
    except LabTerrainBuriesWheel as exc:  # a verdict (Wong errs, unexplained), not an error of the input
        return _failure_report(out, inputs, ter, wheel, slip_min, str(exc), provenance=prov, effect="unexplained")
    except ValueError as exc:
        error = str(exc) + _why_no_valid_row(inputs, info["results"])
        _failure_report(out, inputs, ter, wheel, slip_min, error, provenance=prov)
        raise ValueError(f"{error} (a report saying so was written to {out / 'report.html'})") from None
    _cap_for_time_base(diag, info)
    prov["settings"]["sinkage_law"] = dict(diag.sinkage_law)
    prov["settings"]["hypotheses_tried"] = list(getattr(diag, "tried", None) or diag.fits)
    prov["settings"]["diagnosis_thresholds"] = dict(getattr(diag, "thresholds", {}) or {})
    prov["settings"]["cross_validation"] = getattr(data, "group_kind", None)
    notes = list(info["notes"])
    assumed = [w for w, given, stated in (("radius", wheel_radius, info["wheel_radius_m"]),
                                          ("width", wheel_width, info["wheel_width_m"])) if given is None and stated is None]
    from wheelsoil.processing.pipeline import LOG_SUFFIXES

    if assumed and not recording:
        notes.append(f"WHEEL GEOMETRY ASSUMED: no {' or '.join(assumed)} given (command line, the table's "
                     f"wheel_radius_m/wheel_width_m columns or a sidecar {Path(inputs[0]).stem}.json); the fit uses "
                     f"the vehicle's default wheel r = {wheel.radius} m, b = {wheel.width} m (hardware.md). "
                     "Data from another wheel need --wheel-radius and --wheel-width: the model's forces and "
                     "sinkage scale with both, and slip (Eq. 6) was computed with the radius.")
    elif recording and vehicle is None and (wheel_radius is None or wheel_width is None) and any(
            Path(p).suffix.lower() in LOG_SUFFIXES for p in inputs):  # CAN logs: no attached configuration
        logs = [Path(p).name for p in inputs if Path(p).suffix.lower() in LOG_SUFFIXES]
        missing = [w for w, given in (("radius", wheel_radius), ("width", wheel_width)) if given is None]
        notes.append(f"WHEEL GEOMETRY ASSUMED: {', '.join(logs)}: a CAN log carries no vehicle configuration and "
                     f"no {' or '.join(missing)} was given; the fit uses the shipped vehicle configuration's wheel "
                     f"r = {wheel.radius} m, b = {wheel.width} m (dbc/vehicle.toml). Data from another wheel need "
                     "--wheel-radius and --wheel-width, or --vehicle TOML (the vehicle's configuration: its DBC "
                     "files and signals too): the model's forces and sinkage scale with both, and slip (Eq. 6) is "
                     "computed with the radius.")
    elif wheel_radius is None or wheel_width is None:
        notes.append(f"wheel radius {wheel.radius} m, width {wheel.width} m from "
                     + ("the vehicle configuration" if recording else info["table_wheel_source"])
                     + " where not given.")
    if recording and vehicle is None and any(Path(p).suffix.lower() in LOG_SUFFIXES for p in inputs):
        notes.append("CAN logs decoded with the shipped vehicle configuration (dbc/vehicle.toml: its buses, DBC "
                     "files and signals), as a CAN log carries none; give --vehicle TOML for another vehicle's.")
    ts = _time_sync_summary(info["time_sync"]) if recording else {"gnss_latency_s": None}
    details = []
    for path, res, q in zip(inputs, info["results"], quality):
        d = {"path": path, "quality": q}
        if res is not None:
            d.update(signals=res.signals.assign(cycle=res.cycle), wheel_radius_m=res.wheel_radius_m,
                     excluded=list(getattr(res, "excluded", []) or []))  # interface C (proc)
        details.append(d)
    return write_report(diag, out, terrain=ter, wheel=wheel, inputs=inputs, time_sync=ts,
                        extra_notes=notes, progress=progress, provenance=prov, input_details=details)


#: Processing warnings of an input without a valid sample repeated in fit's error.
WHY_INVALID_LISTED = 4
_IMPORTED_NOTE = re.compile(r"^\S.*: imported \d+ frames \(")


def _why_no_valid_row(inputs, results) -> str:
    """What processing said about each recording input none of whose samples is valid (column ``valid``),
    as text to append to the fit's error: ``"; processing NAME said: W1; W2 (and N more: wheelsoil
    process NAME)"``, the first :data:`WHY_INVALID_LISTED` warnings (the "imported N frames" line of a
    log left out); "" when every recording has a valid sample. ``results``: per input the
    :class:`~wheelsoil.processing.ProcessResult`, None for a table."""
    out = []
    for path, res in zip(inputs, results):
        if res is None or "valid" not in res.signals or bool(res.signals["valid"].any()):
            continue
        name = Path(path).name
        ws = [w for w in res.warnings if not _IMPORTED_NOTE.match(w)]
        if not ws:
            continue
        more = len(ws) - WHY_INVALID_LISTED
        out.append(f"; processing {name} said: " + "; ".join(ws[:WHY_INVALID_LISTED])
                   + (f" (and {more} more: wheelsoil process {path})" if more > 0 else ""))
    return "".join(out)


def _cap_for_time_base(diag, info) -> None:
    """Confidence at most "low" when processing could not establish a reliable GNSS latency
    for an input (``ProcessResult.quality["latency"]["reliable"]`` False): slip (Eq. 6) is
    then in doubt by the latency's error, and so is every verdict built on it."""
    from wheelsoil.model.diagnosis import cap_confidence

    for path, res in zip(info["time_sync"], info["results"]):
        lat = ((getattr(res, "quality", None) or {}).get("latency") or {}) if res is not None else {}
        if lat and not lat.get("reliable", True):
            cap_confidence(diag, "low", f"the GNSS latency of {Path(path['input']).name} is unreliable "
                           f"({'; '.join(map(str, lat.get('reasons') or [])) or 'see the data-quality table'}): "
                           "slip is in doubt")


def _parse_models(text: str):
    return [m.strip() for m in text.split(",") if m.strip()]


def _handler(args) -> int:
    if args.models is not None and not _parse_models(args.models):
        raise ValueError(f"--models is empty ({args.models!r}): give a comma list of hypotheses, or leave the "
                         "option out to try every one")
    rep = run_fit(
        args.inputs,
        args.terrain,
        args.output,
        wheel_radius=args.wheel_radius,
        wheel_width=args.wheel_width,
        slip_min=args.slip_min,
        models=_parse_models(args.models) if args.models is not None else None,
        fit_terrain=args.fit_terrain,
        sinkage=args.sinkage,
        rate_hz=args.rate,
        cutoff_hz=args.cutoff,
        inertia=not args.no_inertia,
        wheel_mass=args.wheel_mass,
        wheel_inertia=args.wheel_inertia,
        vehicle=args.vehicle,
        progress=not args.quiet,
        command=["wheelsoil", *getattr(args, "argv", None)] if getattr(args, "argv", None) is not None else None,
    )
    d, g = rep["diagnosis"], rep["gain"]

    def n(v, unit=" N"):
        return "n/a" if v is None else f"{v:.3g}{unit}"

    import sys

    from wheelsoil.model.report import LOUD_NOTE

    for note in rep.get("notes") or []:  # the loud ones (WHEEL RADIUS CONFLICT: ...) reach the terminal too
        if LOUD_NOTE.match(note):
            print(f"warning: {note}", file=sys.stderr)
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
  wheelsoil fit drive.asc --terrain my_soil.toml --wheel-radius 0.41 --wheel-width 0.26 \\
      --wheel-mass 62 --wheel-inertia 6.4 -o reports/drive
  wheelsoil fit testbed.csv --terrain dry-sand --fit-terrain \\
      --wheel-radius 0.0625 --wheel-width 0.06 -o reports/testbed
  wheelsoil fit table.csv --terrain my_soil.toml --models wong,lyasko -o out/

inputs: a table CSV with columns slip (a fraction, Eq. 6: 0.3, not 30 %), load_n [N],
drawbar_pull_n [N] and optional torque_nm [N m], sinkage_m [m, not mm] (one row per
steady-state test point; slip in per cent or a sinkage deeper than the wheel's diameter is an
error naming the file), or a recording (.mcap) or CAN log (candump .log, Vector .asc/.blf, PEAK
.trc: read as `wheelsoil import` reads it) that is processed first. Several inputs of one
terrain are fitted jointly. A table's wheel: --wheel-radius/--wheel-width, else its columns
wheel_radius_m/wheel_width_m, else a sidecar TABLE.json next to it ({"wheel": {"radius_m": R,
"width_m": B}}), else the vehicle's 0.47 x 0.32 m wheel with a loud note; a radius that
disagrees with the one the table states is noted as a conflict (slip, Eq. 6, used the table's).

output: DIR/report.html (one self-contained file, opens offline, prints), DIR/report.json
(schema wheelsoil.report/1, SI units), DIR/*.png (overview.png: the run against time with the
excluded spans; dp_vs_slip, residuals, sinkage_vs_slip). Both carry the provenance: version,
command, input sha256s and origins, vehicle configuration and DBCs, every setting; running the
recorded command again gives the same report.json except the analysis time.

verdict (report.json diagnosis.effect): 'none' (Wong's residuals show no relevant
structure), a named cause ('slip_sinkage', 'terrain_mismatch', 'stress_distribution',
'terrain_drift') when it lowers out of sample the error of the drawbar pull (or, when Wong's
drawbar pull has none, of every channel that has one), worsens no measured channel and is
probable enough, or 'unexplained'; wheelsoil.model.diagnosis states the rule.
The report defines every metric where it shows it and flags degenerate or physically
inconsistent fits next to their coefficients.
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
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="table CSV(s), recording(s) (.mcap) or CAN log(s) (.log, .asc, .blf, .trc)")
    p.add_argument("--terrain", required=True,
                   help="built-in terrain slug (see 'wheelsoil terrains') or a terrain TOML file")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="report directory (created; an earlier report there is replaced, a directory of other "
                   "files refused)")
    p.add_argument("--wheel-radius", type=float, default=None, metavar="R",
                   help="wheel radius [m] (default: the vehicle config for recordings, 0.47; for tables what the "
                   "table or its sidecar JSON states, else 0.47)")
    p.add_argument("--wheel-width", type=float, default=None, metavar="B",
                   help="wheel width [m] (default: the vehicle config for recordings, 0.32; for tables what the "
                   "table or its sidecar JSON states, else 0.32)")
    p.add_argument("--slip-min", type=float, default=0.1, metavar="S",
                   help="use samples with slip > S (default 0.1; the paper used 0.2 on clay, 0.1 on sand)")
    from wheelsoil.model.hypotheses import HYPOTHESES

    p.add_argument("--models", default=None,
                   help="comma list of the hypotheses to try (default: every one in the registry: "
                   + ", ".join(n for n in HYPOTHESES if n != "wong") + "; Wong always). Those whose effect is "
                   "'unexplained' stand for causes on no list: leaving them out lets a listed cause be named "
                   "where an off-list one explains the data as well")
    p.add_argument("--fit-terrain", action="store_true",
                   help="also fit terrain parameters (k_eq = kc/b + kphi, n, c, phi, K; those the data "
                   "identify) for soils without lab values")
    p.add_argument("--sinkage", choices=("auto", "eq10", "balance"), default="auto",
                   help="static sinkage from Eq. 10 (the paper's small-angle form), from the vertical force balance "
                        "(Eq. 7 = W), or auto (default): on data with measured sinkage every model is fitted under "
                        "both and the law the data prefer by a Bayes factor over 10 is used, else Eq. 10")
    p.add_argument("--rate", type=float, default=100.0, metavar="HZ",
                   help="recordings: processing grid rate [Hz] (default 100)")
    p.add_argument("--cutoff", type=float, default=None, metavar="HZ",
                   help="recordings: zero-phase low-pass cutoff [Hz] (default: processing's 5 Hz)")
    p.add_argument("--no-inertia", action="store_true",
                   help="recordings: do not compensate the wheel's inertia (Dp = Fx, T = My as measured)")
    p.add_argument("--vehicle", default=None, metavar="TOML",
                   help="recordings and CAN logs: the vehicle configuration (buses, DBC files, signals, wheel) to "
                   "decode them with (default: a recording's attached one; a CAN log's: the shipped one, said)")
    from wheelsoil.processing.cli import wheel_mass_args

    wheel_mass_args(p)
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_handler)
