"""Measured data prepared for fitting: selection, cells, noise that no effect can inflate.

* :func:`prepare_data` selects the driving samples (``slip_min < s < 1``),
  defines the cross-validation groups (accelerate cycles of a time series;
  interleaved slip-rank folds of a table) and aggregates the samples into
  **cells** (:class:`Cells`): accelerate cycle x slip bin x load bin for a
  time series, one row per cell for a table.  The models are fitted to the
  cell means: 100 Hz samples filtered at 5 Hz are strongly autocorrelated,
  so a cycle x slip-bin mean is the independent unit of information, and the
  fit is ~80x cheaper than on the raw samples.  A cell spans a slip bin, and
  its mean is the forces averaged over that spread (``Cells.slip_sd``), which
  the fit models as such (:func:`wheelsoil.model.crossval.cell_forces`).
* :func:`cell_noise` estimates each channel's noise of one cell mean from
  what no smooth function of slip, load and time explains: the scatter of the
  cell means about a flexible smooth in slip, load and the drift coordinate
  (whatever effect is a smooth function of them, modelled or not, is absorbed
  and cannot inflate the noise), and, as a second, within-cycle view for the
  report, three-point pseudo-residuals along slip inside one cycle.  Never
  from a model's residuals, so an effect cannot inflate its own noise.  The
  cycle-to-cycle (unit-level) scatter stays in it: it is the floor that an
  out-of-sample error can reach.

Sources: Ruppert, Wand & Carroll (2003, Semiparametric Regression, ch. 3) for
the residual variance about a regression spline; Gasser, Sroka &
Jennen-Steinmetz (1986) for the three-point pseudo-residual; Cameron & Miller
(2015) for clustered data.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "FitData",
    "Cells",
    "prepare_data",
    "estimate_noise",
    "cell_noise",
    "make_cells",
    "synthetic_data",
    "CHANNELS",
    "dataclasses_replace",
    "format_lines",
    "TABLE_NEEDS",
]

#: Measured channels a model is fitted against, in order: data column -> WheelForces field.
CHANNELS: dict[str, str] = {
    "drawbar_pull_n": "drawbar_pull_n",
    "torque_nm": "torque_nm",
    "sinkage_m": "sinkage_m",
}

#: Length [s] of a contiguous block, the CV unit of a time series without accelerate cycles: about
#: one accelerate cycle of a slip sweep (6-9 s of sweep in a 10-15 s cycle), so a run gives as many
#: units whatever its procedure.
BLOCK_S = 10.0

#: Most cross-validation folds of a table (interleaved by slip rank): leave-one-out up to this many rows,
#: beyond it folds of ceil(n / MAX_TABLE_FOLDS) rows each, as many as that gives (30 rows: 15 folds of 2).
#: The folds are the units of the diagnosis' paired test (a t over the folds, n - 1 degrees of freedom),
#: so their number is its power; capped as cycles are (``crossval.MAX_FOLDS``, the same 20) to bound the
#: refits.  (It was 10 folds from 21 rows on: a table of 21 rows had half the units of one of 20.)
MAX_TABLE_FOLDS = 20

#: Fitted data [s] per accelerate cycle above which the cycles processing found are not the units:
#: a cycle of a slip sweep holds 3-9 s of data at s > 0.1; a "cycle" with more than two blocks' worth
#: spans several sweeps and several patches of soil (a towed run whose tractor speeds up now and then),
#: so blocks of ``BLOCK_S`` are the independent units instead.
MAX_CYCLE_DATA_S = 2 * BLOCK_S

#: Phases of a processed recording (``phase`` column) that are driving the steady-state model
#: describes outside an accelerate cycle (:func:`wheelsoil.processing.slip.classify_phases`).
DRIVING_PHASES = ("accel", "drive")

#: Slip bins per accelerate cycle (cells).  With slip in (0.1, 0.9) a bin is ~0.067 wide: the
#: error of predicting a cell at its mean slip instead of averaging the model over the bin is
#: 0.5 f'' var(s) ~ 1e-3 of Dp, far below the noise of a cell mean.
N_SLIP_BINS = 12
#: Load bins when the load varies (coefficient of variation above LOAD_CV_BINS): tertiles.
LOAD_CV_BINS = 0.10
#: Cells with fewer samples than this are merged into nothing (dropped from the cell fit):
#: their mean is dominated by the filter's autocorrelation (a 5 Hz low-pass has ~10 correlated
#: samples at 100 Hz).
MIN_CELL_SAMPLES = 3

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
    sigma : data column -> noise std of one sample (:func:`estimate_noise`; for
        reporting and sample-level metrics; the fits use ``cells.sigma``).
    groups : (N,) int cross-validation groups (accelerate cycles, or contiguous blocks).
    units : (N,) int "independent units" for aggregation: table rows, or
        (group, slip-decile) cells of a time series.
    run : (N,) int input index (0 when one input).
    t_s : (N,) time or None (tables).
    kind : "table" or "timeseries".
    notes : list of plain-English notes on excluded rows and choices.
    n_input : rows before filtering; slip_min : threshold used.
    distance_m : (N,) travelled distance (contract C) or None.
    load_static_n : the run's static wheel load [N]: the mean load over every valid row of the
        time series, all slips (over whole accelerate-brake cycles the load transferred by
        accelerating averages out); None for a table, or when the runs' means differ by > 2 %.
    cells : the :class:`Cells` the models are fitted to.
    inertia : data column -> (N,) the wheel's inertial part of the transducer reading the
        column was compensated from (``fx_n - drawbar_pull_n`` = -m_w dV/dt [N],
        ``my_nm - torque_nm`` = I_w domega/dt [N m]; hardware.md), where the input has the
        readings (``fx_n``, ``my_nm``: processed recordings); empty otherwise.  A transducer
        gain error scales the reading, inertia included (``sensor_gain``).
    speed_mps : (N,) the vehicle's forward speed V [m/s] (the input's ``speed_mps`` column:
        processed recordings, or a table that gives it), or None; what the stand-in for a soil whose
        response depends on the speed (``speed_k``) is a function of.
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
    distance_m: np.ndarray | None = None
    cells: "Cells | None" = field(default=None, repr=False)
    load_static_n: float | None = None
    inertia: dict = field(default_factory=dict)
    speed_mps: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Number of samples used."""
        return int(self.slip.size)

    @property
    def x_raw(self) -> np.ndarray | None:
        """(N,) the drift coordinate of each sample: distance_m, else t_s (None for tables)."""
        if self.kind == "table":
            return None
        return self.distance_m if self.distance_m is not None else self.t_s

    @property
    def n_units(self) -> int:
        """Number of independent units: the cells (rows of a table, cycle x slip cells of a time series)."""
        if self.cells is not None:
            return self.cells.n
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
            distance_m=None if self.distance_m is None else self.distance_m[mask],
            cells=None,
            inertia={k: v[mask] for k, v in self.inertia.items()},
            speed_mps=None if self.speed_mps is None else self.speed_mps[mask],
        )


def dataclasses_replace(obj, **kw):
    """``dataclasses.replace`` (kept local to avoid shadowing the field name)."""
    import dataclasses

    return dataclasses.replace(obj, **kw)


#: Largest plausible magnitude of a wheel's load, drawbar pull [N] or torque [N m] in a table.
MAX_FORCE = 1e6
#: Most rows of a table (no ``t_s``): one steady-state test point per row, each fitted as a unit (a 2-million-row
#: table took 21 s per hypothesis, 1.6 GB and rising, before cross-validation).
MAX_TABLE_ROWS = 20000
#: Largest plausible median |Dp| / W of the fitted rows: a wheel in soil pulls less than its load (its drawbar pull
#: coefficient stays below about 1), so twice it is a unit error (a load in kN).
MAX_DP_OVER_W = 2.0


#: The columns every table needs (SI units; slip a fraction, Eq. 6).
TABLE_NEEDS: tuple[str, ...] = ("slip", "load_n", "drawbar_pull_n")


def format_lines(lines, limit: int = 10) -> str:
    """File line numbers for a message: ``"line 20"``, ``"lines 20, 21, 35"``, or the first ``limit``
    of them and ``"and N more"``.  ``lines``: ints (1-based line numbers), in the order to show."""
    lines = [int(x) for x in lines]
    more = f" and {len(lines) - limit} more" if len(lines) > limit else ""
    return f"line{'s' if len(lines) > 1 else ''} {', '.join(map(str, lines[:limit]))}{more}"


def _where(df, rows) -> str | None:
    """The file lines of the rows ``rows`` (positions in ``df``) when the table loader gave them
    (columns ``_line`` and ``_file``, :func:`wheelsoil.pipeline.load_inputs`): ``"a.csv lines 4, 9"``
    (``"a.csv lines 4, 9; b.csv line 3"`` over several files); None without them."""
    if "_line" not in df.columns:
        return None
    rows = np.asarray(rows, int)
    lines = df["_line"].to_numpy()[rows]
    files = df["_file"].astype(str).to_numpy()[rows] if "_file" in df.columns else np.full(rows.size, "")
    return "; ".join(f"{f} {format_lines(lines[files == f])}".strip() for f in dict.fromkeys(files))


def prepare_data(df, *, slip_min: float = 0.1, source: str = "data", n_blocks: int | None = None,
                 wheel_radius_m: float | None = None) -> FitData:
    """Select and check the samples a driving model is fitted to.

    ``df``: pandas DataFrame with columns ``slip``, ``load_n``, ``drawbar_pull_n``
    and optionally ``torque_nm``, ``sinkage_m``, ``valid`` (bool), ``cycle``
    (accelerate-cycle id, -1 outside), ``run`` (input index), ``t_s`` (time; its
    presence marks a time series).  Kept: rows marked valid, with finite slip,
    load and drawbar pull, ``slip_min < s < 1`` and ``W > 0``.  Skid rows
    (s < 0) and rows with s ~ 0 are excluded from a driving model with a note.

    Cross-validation groups: accelerate cycles (``cycle >= 0``; samples outside a
    cycle join the previous one) unless they hold more than ``MAX_CYCLE_DATA_S`` of
    fitted data each (then blocks, as without cycles), else for a table interleaved folds by slip rank
    (leave-one-out up to ``MAX_TABLE_FOLDS`` rows, else as many folds of equal size as keep their
    number at most that, each spanning the slip range, so
    the held-out error measures interpolation, not extrapolation to unseen slips),
    and for a time series without cycles contiguous blocks of about ``BLOCK_S`` of data each (at
    least 5 per run).
    The samples are then aggregated into :class:`Cells` (:func:`make_cells`).
    ``wheel_radius_m`` [m], when given, bounds the measured sinkage: a wheel cannot sink by
    more than its diameter.  A table's used rows whose |Dp| exceeds ``MAX_DP_OVER_W`` times
    their load are excluded with a note (no soil gives it; when most rows do, the load's unit is
    refused below).  With the columns ``_line``/``_file`` the table loader adds
    (:func:`wheelsoil.pipeline.load_inputs`), messages name the file lines of the rows, else
    their 0-based positions; rows with ``_copy`` True (exact copies) are not used.

    Raises
    ------
    ValueError
        (naming ``source``) for a missing column, an empty table, no rows left
        after the selection, only one distinct slip value (no slip
        dependence can be fitted), slip in per cent (most finite slips above 1.5, in a table, no
        ``t_s``, in size: slip is the fraction of Eq. 6, at most 1) or a sinkage deeper than the wheel's
        diameter (millimetres in the ``sinkage_m`` column), or a table (no ``t_s``) of more than
        ``MAX_TABLE_ROWS`` used rows (each row is a test point the models are fitted to one by one),
        a median |Dp| / W above ``MAX_DP_OVER_W`` (a load in kN), or a table whose torque is negative
        in most driving rows (the other sign convention).
    """
    import pandas as pd

    if not isinstance(df, pd.DataFrame):
        raise ValueError(f"{source}: expected a pandas DataFrame, got {type(df).__name__}")
    missing = [c for c in TABLE_NEEDS if c not in df.columns]
    if missing:
        has = [str(c) for c in df.columns if c != "run" and not str(c).startswith("_")]  # added by the caller
        case = [f"{c!r} for {m!r}" for m in missing for c in has if c.strip().lower() == m]
        raise ValueError(
            f"{source}: missing column(s) {', '.join(missing)}; a table needs slip, load_n, "
            "drawbar_pull_n (optional torque_nm, sinkage_m) in SI units (slip a fraction); it has "
            + (", ".join(has[:20]) + (" ..." if len(has) > 20 else "") or "no columns")
            + (f" (names are case-sensitive: {', '.join(case)}?)" if case else "")
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
        v = df["valid"]
        if not pd.api.types.is_bool_dtype(v) and not pd.api.types.is_numeric_dtype(v):
            # a table's text: "no", "false", "0" are not valid
            v = v.astype(str).str.strip().str.lower().isin(("1", "1.0", "true", "yes", "y", "t"))
        valid = v.fillna(False).astype(bool).to_numpy()
        if (~valid).any():
            notes.append(f"{int((~valid).sum())} of {n_input} samples marked invalid by processing were excluded.")
        keep &= valid
    if "_copy" in df.columns:  # exact copies of earlier rows of a table file, noted by load_inputs
        keep &= ~df["_copy"].fillna(False).astype(bool).to_numpy()
    valid_load = keep & np.isfinite(w) & (w > 0)  # rows the static load is taken over (all slips)
    bad = ~(np.isfinite(s) & np.isfinite(w) & np.isfinite(dp))
    if (bad & keep).any():
        rows = np.flatnonzero(bad & keep)
        notes.append(
            f"{rows.size} row(s) with NaN or non-numeric slip/load_n/drawbar_pull_n excluded "
            f"({_where(df, rows) or f'first at row {int(rows[0])}'})."
        )
    keep &= ~bad
    if not keep.any():
        if "valid" in df.columns and not valid.any():
            raise ValueError(f"{source}: every row is marked invalid (column valid)")
        first = {c: str(df[c].iloc[0]) for c in TABLE_NEEDS}
        shown = ", ".join(f"{c} = {v!r}" for c, v in first.items())
        raise ValueError(f"{source}: no row has finite slip, load_n and drawbar_pull_n ({_where(df, [0]) or 'row 0'}: "
                         f"{shown}); "
                         "give plain numbers with a decimal point, without units or per cent signs")
    # a driven wheel's slip (Eq. 6) is at most 1: a column most of whose values lie beyond 1.5 is in per cent; a
    # table's skid rows count by their size (-100 in per cent), so they do not hide it; a few rows beyond (a typo, a
    # time series' transient) are excluded below with the slips of 1 and more
    pct = np.flatnonzero(keep & ((np.abs(s) if "t_s" not in df.columns else s) > 1.5))
    n_pct = pct.size
    if n_pct > keep.sum() / 2:
        at = _where(df, pct)
        raise ValueError(f"{source}: the slip column looks like per cent ({n_pct} of {int(keep.sum())} values above "
                         f"1.5, median {np.median(s[keep]):.3g}, largest {np.max(s[keep]):.3g}"
                         + (f"; {at}" if at else "") + "); slip is the fraction 1 - V / (omega r) of Eq. 6, "
                         "never above 1: divide it by 100")
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
        at = _where(df, np.flatnonzero(high))
        notes.append(f"{int(high.sum())} row(s) with s >= 1 excluded (slip must be < 1" + (f"; {at}" if at else "") + ").")
    if noload.any():
        notes.append(f"{int(noload.sum())} row(s) with load_n <= 0 excluded.")
    keep &= (s > slip_min) & (s < 1.0) & (w > 0)
    with np.errstate(invalid="ignore"):
        over = keep & (np.abs(dp) > MAX_DP_OVER_W * w)
    if "t_s" not in df.columns and over.any() and over.sum() <= keep.sum() / 2:  # most rows: the load's unit (below)
        at = _where(df, np.flatnonzero(over)) or "rows " + ", ".join(map(str, np.flatnonzero(over)[:10]))
        notes.append(f"{int(over.sum())} row(s) with |drawbar_pull_n| above {MAX_DP_OVER_W:g} times load_n excluded "
                     f"({at}): no soil gives a wheel that drawbar pull (a typo or a value in another unit?).")
        keep &= ~over
    if "cycle" in df.columns and keep.any():
        # a time series with accelerate cycles: the steady-state model is fitted to the accelerate
        # phases processing identified and to steady driving (phase ``drive``: the slip levels of a
        # steady drawbar-pull test, which then join the preceding cycle as their CV unit); other
        # samples outside the cycles (slowing with the torque still on, coasting) are transients
        # the model does not describe
        cyc_all = pd.to_numeric(df["cycle"], errors="coerce").to_numpy(float)
        in_cycle = np.isfinite(cyc_all) & (cyc_all >= 0)
        steady = (df["phase"].astype(str).isin(DRIVING_PHASES).to_numpy() if "phase" in df.columns
                  else np.zeros(n_input, bool))
        if np.unique(cyc_all[keep & in_cycle]).size >= 2:
            if (keep & ~in_cycle & steady).any():
                notes.append(f"{int((keep & ~in_cycle & steady).sum())} sample(s) of steady driving outside the "
                             "accelerate cycles used (each joins the preceding cycle).")
            if (keep & ~in_cycle & ~steady).any():
                notes.append(f"{int((keep & ~in_cycle & ~steady).sum())} driving sample(s) outside the accelerate "
                             "cycles and not driving steadily excluded (transients: the model is a steady-state one).")
            keep &= in_cycle | steady
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
            if col == "sinkage_m" and wheel_radius_m and n_ok and np.nanmax(np.abs(v)) > 2.0 * wheel_radius_m:
                i = int(np.nanargmax(np.abs(v)))
                with np.errstate(invalid="ignore"):
                    deep = np.flatnonzero(keep)[np.abs(v) > 2.0 * wheel_radius_m]
                raise ValueError(f"{source}: sinkage_m reaches {v[i]:.4g} m "
                                 f"({_where(df, deep) or f'row {int(np.flatnonzero(keep)[i])}'}), "
                                 f"more than the wheel's diameter {2.0 * wheel_radius_m:.3g} m: the column must be "
                                 "in metres (millimetres divided by 1000?)")
            if n_ok >= max(3, n // 2):
                channels[col] = v
                if n_ok < n:
                    notes.append(f"{col}: {n - n_ok} of {n} used rows have no value; fitted where present.")
            elif n_ok:
                notes.append(f"{col}: only {n_ok} of {n} used rows have a value; channel not used.")
    for col, v in (("load_n", w[keep]), *channels.items()):
        big = np.abs(v) > MAX_FORCE
        if big.any():  # 1 MN (N m) is a 100 t wheel load: a unit or transcription error, not a measurement
            i = int(np.flatnonzero(big)[0])
            rows = np.flatnonzero(keep)[big]
            at = f"on {_where(df, rows)}" if "_line" in df.columns else f"at row {int(rows[0])}"
            raise ValueError(f"{source}: {col} = {v[i]:.4g} {at} is not a plausible "
                             f"wheel force or torque (|value| > {MAX_FORCE:.0e} in N or N m): a unit, in the table's "
                             "column or, for a recording, in the DBC or vehicle.toml (kN decoded as N?)")
    ratio = float(np.nanmedian(np.abs(channels["drawbar_pull_n"]) / np.abs(w[keep]))) if keep.any() else 0.0
    if ratio > MAX_DP_OVER_W:  # no wheel in soil pulls twice its load
        raise ValueError(f"{source}: the drawbar pull is {ratio:.3g} times the load in the median row: not a wheel in "
                         f"soil (|Dp| / W above {MAX_DP_OVER_W:g}); load_n must be in N (kN given?)")
    if "torque_nm" in channels and "t_s" not in df.columns:
        tq = channels["torque_nm"]
        if np.isfinite(tq).sum() >= 3 and np.nanmedian(tq) < 0:
            raise ValueError(f"{source}: the torque is negative in most rows with slip > {slip_min:g}: a driven wheel's "
                             "torque is positive (paper Eq. 8, slip of Eq. 6 positive when driving); flip the sign "
                             "of torque_nm (and check drawbar_pull_n's)")
    inertia = {}
    for col, reading in (("drawbar_pull_n", "fx_n"), ("torque_nm", "my_nm")):
        if col in channels and reading in df.columns:
            part = pd.to_numeric(df[reading], errors="coerce").to_numpy(float)[keep] - channels[col]
            inertia[col] = np.where(np.isfinite(part), part, 0.0)
    slip = s[keep]
    run_all = pd.to_numeric(df["run"], errors="coerce").fillna(0).to_numpy(int) if "run" in df.columns \
        else np.zeros(n_input, int)
    run = run_all[keep]
    speed = pd.to_numeric(df["speed_mps"], errors="coerce").to_numpy(float)[keep] if "speed_mps" in df.columns else None
    if speed is not None and not np.all(np.isfinite(speed)):
        notes.append(f"speed_mps has {int((~np.isfinite(speed)).sum())} non-numeric value(s): the forward speed is not "
                     "used.")
        speed = None
    t_s = pd.to_numeric(df["t_s"], errors="coerce").to_numpy(float)[keep] if "t_s" in df.columns else None
    if t_s is not None and not np.isfinite(t_s).all():
        notes.append(f"t_s has {int((~np.isfinite(t_s)).sum())} non-numeric value(s): the rows are fitted as a table "
                     "(no time along the run).")
        t_s = None
    dist = pd.to_numeric(df["distance_m"], errors="coerce").to_numpy(float)[keep] if "distance_m" in df.columns else None
    if dist is not None and not np.all(np.isfinite(dist)):
        notes.append("distance_m has NaN values; time is used as the drift coordinate instead.")
        dist = None
    kind = "timeseries" if t_s is not None else "table"
    if kind == "table" and int(keep.sum()) > MAX_TABLE_ROWS:
        raise ValueError(f"{source}: a table of {int(keep.sum())} used rows, more than {MAX_TABLE_ROWS}: each row of "
                         "a table is one test point fitted on its own (a steady-state result); samples of a run "
                         "need their t_s column (then cycle x slip cells are fitted), or average the table's rows "
                         "per test point first")
    groups, group_kind = _cv_groups(df, keep, run, kind, n_blocks)
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
    data = FitData(
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
        distance_m=dist,
        load_static_n=_static_load(w, valid_load, run_all) if kind == "timeseries" else None,
        inertia=inertia,
        speed_mps=speed,
    )
    return dataclasses_replace(data, cells=make_cells(data))


def _static_load(w: np.ndarray, ok: np.ndarray, run: np.ndarray) -> float | None:
    """The static wheel load [N] of a time series: the mean of the loads ``w`` (all rows) over
    the rows ``ok`` (valid, finite positive load), whatever their slip (over accelerate-brake
    cycles the load transferred by accelerating averages out).  None when no row qualifies or the
    runs' (``run``) means differ by more than 2 % (no single static load)."""
    if not ok.any():
        return None
    means = [float(np.mean(w[ok & (run == r)])) for r in np.unique(run[ok])]
    if max(means) > 1.02 * min(means):
        return None
    return float(np.mean(w[ok]))


def _run_seconds(t, idx) -> float:
    """Seconds of data in the kept rows ``idx`` of one run: their count x the run's median positive time
    step of ``t`` (N,) [s]; NaN without ``t`` or without a positive step."""
    dt = np.diff(t[idx]) if t is not None else np.zeros(0)
    dt = dt[np.isfinite(dt) & (dt > 0)]
    return idx.size * float(np.median(dt)) if dt.size else float("nan")


def _cv_groups(df, keep, run, kind, n_blocks):
    """Cross-validation groups for the kept rows: (groups (N,), description)."""
    import pandas as pd

    n = int(keep.sum())
    t = pd.to_numeric(df["t_s"], errors="coerce").to_numpy(float)[keep] if "t_s" in df.columns else None
    runs = [np.flatnonzero(run == r) for r in np.unique(run)]
    note = ""
    if "cycle" in df.columns:
        cyc = pd.to_numeric(df["cycle"], errors="coerce").to_numpy(float)[keep]  # a text cycle: none
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
            per_cycle = sum(_run_seconds(t, idx) for idx in runs) / (g.max() + 1)
            if not per_cycle > MAX_CYCLE_DATA_S:
                return g, "accelerate cycles"
            # fewer, longer "cycles" than sweeps (a towed run whose tractor speeds up now and then, slip
            # swept by the wheel): each holds many sweeps and patches of soil, so blocks are the units
            note = (f" ({g.max() + 1} accelerate cycles found, {per_cycle:.0f} s of fitted data each: "
                    "more than a slip sweep's worth)")
    if kind == "table" and n_blocks is None:
        k = n if n <= MAX_TABLE_FOLDS else math.ceil(n / math.ceil(n / MAX_TABLE_FOLDS))  # sizes differ by <= 1
        rank = np.empty(n, int)
        rank[np.argsort(pd.to_numeric(df["slip"], errors="coerce").to_numpy(float)[keep], kind="stable")] = np.arange(n)
        return rank % k, "leave-one-out" if k == n else f"{k} interleaved slip-rank folds"
    k = n_blocks or (max(2, min(5, n // 3)) if kind == "table" else 5)
    k = max(1, min(k, n))
    t_blocks = t if kind != "table" and n_blocks is None else None
    g = np.zeros(n, int)
    nxt = 0
    for idx in runs:
        kr = k if len(runs) == 1 else max(1, min(k, idx.size // 2))
        secs = _run_seconds(t_blocks, idx)
        if np.isfinite(secs):
            # a recording without accelerate cycles (steady holds, gentle ramps): blocks of about
            # BLOCK_S of data, as many independent units as a sweep test's cycles would give
            kr = max(kr, min(int(round(secs / BLOCK_S)), idx.size // 2))
        g[idx] = nxt + (np.arange(idx.size) * kr) // idx.size
        nxt += kr
    return g, "contiguous blocks" + note



@dataclass(frozen=True)
class Cells:
    """Cell means of the used samples: what the models are fitted to.

    All arrays have shape (C,): ``slip``, ``load_n`` (cell means), ``t_s``
    (mean time, or the row index for tables), ``x`` (drift coordinate: mean
    travelled distance, else time, normalised to [-0.5, 0.5] over the data;
    None for tables), ``group`` (cross-validation fold), ``count`` (samples),
    ``channels`` (column -> (C,) cell means, NaN where not measured),
    ``var`` (column -> (C,) variance of each cell mean: ``sigma^2 *
    max(1, median count / count)``), ``sigma`` (column -> noise std of a cell
    mean, :func:`cell_noise`), ``sigma_within`` (the within-cycle view),
    ``index`` (N,) the cell of each sample, ``x_kind`` ("distance", "time" or None),
    ``bin`` (C,) slip-bin index (time series) or the row's slip rank, ``inertia`` (column ->
    (C,) cell means of :attr:`FitData.inertia`), ``slip_sd`` (C,) the standard deviation of
    the slip within each cell (None for a table: one test point per cell), ``speed_mps`` (C,) cell
    means of :attr:`FitData.speed_mps` (None without it).
    """

    slip: np.ndarray
    load_n: np.ndarray
    t_s: np.ndarray
    x: np.ndarray | None
    group: np.ndarray
    count: np.ndarray
    channels: dict
    var: dict
    sigma: dict
    sigma_within: dict
    index: np.ndarray
    x_kind: str | None
    bin: np.ndarray
    noise_method: str = ""
    x_ref: tuple = (0.0, 1.0)
    inertia: dict = field(default_factory=dict)
    slip_sd: np.ndarray | None = None
    speed_mps: np.ndarray | None = None

    def x_of(self, raw) -> np.ndarray | None:
        """The normalised drift coordinate of raw distance/time values (N,), as for the cells."""
        if self.x is None or raw is None:
            return None
        lo, rng = self.x_ref
        return (np.asarray(raw, float) - lo) / rng - 0.5 if rng > 0 else np.zeros(len(raw))

    @property
    def n(self) -> int:
        """Number of cells."""
        return int(self.slip.size)

    def subset(self, mask: np.ndarray) -> "Cells":
        """The cells where ``mask`` (C,) is True (same noise levels; ``index`` is dropped)."""
        return dataclasses_replace(
            self, slip=self.slip[mask], load_n=self.load_n[mask], t_s=self.t_s[mask],
            x=None if self.x is None else self.x[mask], group=self.group[mask], count=self.count[mask],
            channels={k: v[mask] for k, v in self.channels.items()},
            var={k: v[mask] for k, v in self.var.items()}, index=np.zeros(0, int), bin=self.bin[mask],
            inertia={k: v[mask] for k, v in self.inertia.items()},
            slip_sd=None if self.slip_sd is None else self.slip_sd[mask],
            speed_mps=None if self.speed_mps is None else self.speed_mps[mask])


def make_cells(data: "FitData") -> Cells:
    """Aggregate the samples of ``data`` into cells (see module doc).

    Time series: cell = CV group (accelerate cycle) x slip bin (``N_SLIP_BINS``
    quantile bins over all used samples) x load bin (tertiles when the load's
    coefficient of variation exceeds ``LOAD_CV_BINS``); cells with fewer than
    ``MIN_CELL_SAMPLES`` samples are dropped.  Tables: one cell per row.
    Returns :class:`Cells` with the noise of each channel from :func:`cell_noise`.
    Raises ValueError when fewer than 3 cells remain.
    """
    n = data.n
    if data.kind == "table":
        key = np.arange(n)
        sbin = np.empty(n, int)
        sbin[np.argsort(data.slip, kind="stable")] = np.arange(n)
        lbin = np.zeros(n, int)
    else:
        edges = np.quantile(data.slip, np.linspace(0, 1, N_SLIP_BINS + 1)[1:-1])
        sbin = np.searchsorted(edges, data.slip)
        w = data.load_n
        if np.std(w) > LOAD_CV_BINS * abs(np.mean(w)):
            lbin = np.searchsorted(np.quantile(w, [1 / 3, 2 / 3]), w)
        else:
            lbin = np.zeros(n, int)
        key = (data.groups.astype(np.int64) * 64 + sbin) * 4 + lbin
    uniq, inv, cnt = np.unique(key, return_inverse=True, return_counts=True)
    keep_cell = cnt >= (MIN_CELL_SAMPLES if data.kind != "table" else 1)
    cnt = cnt.astype(float)

    def mean(v):
        ok = np.isfinite(v)
        s = np.bincount(inv, weights=np.where(ok, v, 0.0), minlength=uniq.size)
        c = np.bincount(inv, weights=ok.astype(float), minlength=uniq.size)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(c > 0, s / np.maximum(c, 1), np.nan)

    t = data.t_s if data.t_s is not None else np.arange(n, dtype=float)
    xs, x_kind = None, None
    if data.kind != "table":
        if data.distance_m is not None:
            xs, x_kind = data.distance_m, "distance"
        elif data.t_s is not None:
            xs, x_kind = data.t_s, "time"
    first = np.zeros(uniq.size, int)
    first[inv[::-1]] = np.arange(n)[::-1]
    group = data.groups[first]
    sb = sbin[first]
    chans = {c: mean(v) for c, v in data.channels.items()}
    ch_cnt = {c: np.bincount(inv, weights=np.isfinite(v).astype(float), minlength=uniq.size)
              for c, v in data.channels.items()}
    if keep_cell.sum() < 3:
        raise ValueError(f"only {int(keep_cell.sum())} cells with >= {MIN_CELL_SAMPLES} samples: too little data to "
                         "fit" + ("" if data.kind == "table" else
                                  " (a steady-state table with a t_s or distance_m column is read as a time series "
                                  "of samples: drop those columns to fit one row per test point)"))
    x = None
    x_ref = (0.0, 1.0)
    if xs is not None:
        xm = mean(xs)
        rng = float(np.nanmax(xm[keep_cell]) - np.nanmin(xm[keep_cell]))
        x_ref = (float(np.nanmin(xm[keep_cell])), rng)
        x = (xm - x_ref[0]) / rng - 0.5 if rng > 0 else np.zeros_like(xm)
    sel = keep_cell
    index = np.full(uniq.size, -1)
    index[sel] = np.arange(int(sel.sum()))
    cells_idx = index[inv]
    slip_c, load_c, t_c = mean(data.slip)[sel], mean(data.load_n)[sel], mean(t)[sel]
    slip_sd = None if data.kind == "table" else np.sqrt(np.maximum(mean(data.slip**2)[sel] - slip_c**2, 0.0))
    chans = {c: v[sel] for c, v in chans.items()}
    cntc = {c: v[sel] for c, v in ch_cnt.items()}
    group, sb = group[sel], sb[sel]
    x = None if x is None else x[sel]
    sigma, within, method = cell_noise(chans, slip_c, load_c, t_c, group, sb, data.kind, x)
    var = {}
    for c, v in chans.items():
        ref = float(np.median(cntc[c][cntc[c] > 0])) if np.any(cntc[c] > 0) else 1.0
        var[c] = sigma[c] ** 2 * np.maximum(1.0, ref / np.maximum(cntc[c], 1.0))
    return Cells(slip=slip_c, load_n=load_c, t_s=t_c, x=x, group=group, count=cnt[sel], channels=chans,
                 var=var, sigma=sigma, sigma_within=within, index=cells_idx, x_kind=x_kind, bin=sb,
                 noise_method=method, x_ref=x_ref,
                 inertia={c: np.nan_to_num(mean(v)[sel]) for c, v in data.inertia.items()}, slip_sd=slip_sd,
                 speed_mps=None if data.speed_mps is None else mean(data.speed_mps)[sel])


#: Median of a chi-square variable with one degree of freedom: a robust variance from squares.
_CHI2_1_MEDIAN = 0.454936


def _pseudo_residuals(s, y):
    """Three-point pseudo-residuals along an ordered coordinate s (Gasser et al. 1986):
    ``(e_i - a e_{i-1} - b e_{i+1}) / sqrt(1 + a^2 + b^2)`` with the linear-interpolation
    weights a, b; each has the noise variance when the mean is locally linear."""
    if y.size < 3:
        return np.zeros(0)
    s0, s1, s2 = s[:-2], s[1:-1], s[2:]
    h = s2 - s0
    ok = h > 0
    a = np.where(ok, (s2 - s1) / np.where(ok, h, 1), 0.5)
    b = 1 - a
    r = (y[1:-1] - a * y[:-2] - b * y[2:]) / np.sqrt(1 + a**2 + b**2)
    return r[np.isfinite(r)]


def _robust_sd(r: np.ndarray) -> float:
    """sqrt(median(r^2) / 0.4549): the sd of Gaussian pseudo-residuals, robust to a few large ones."""
    return float(math.sqrt(np.median(r**2) / _CHI2_1_MEDIAN)) if r.size else float("nan")


def _scatter_about(X: np.ndarray, y: np.ndarray) -> float:
    """Residual standard deviation of ``y`` (C,) about its least-squares fit on the design ``X``
    (C, p): sqrt(RSS / (C - rank X)) (Ruppert, Wand & Carroll 2003, ch. 3); NaN when fewer than
    4 degrees of freedom remain.  Units of ``y``."""
    rank = np.linalg.matrix_rank(X)
    if y.size - rank < 4:
        return float("nan")
    e = y - X @ np.linalg.lstsq(X, y, rcond=None)[0]
    return float(math.sqrt(float(e @ e) / (y.size - rank)))


def _smooth_basis(slip, load_n, x, n_cells, interaction: bool = True):
    """Design matrix of a flexible smooth in (slip, load, drift coordinate): a cubic B-spline in
    slip (4..8 functions, interior knots at slip quantiles), the centred load and its product with
    the centred slip (when the load varies at all), and, for a time series, x, x^2 in the drift
    coordinate and the slip spline times x (a slip curve that changes along the run: a soil
    compacting pass by pass stiffens the low-slip branch more than the high-slip one, an effect
    of slip and place together that an additive smooth would count as noise)."""
    from scipy.interpolate import BSpline

    s = np.asarray(slip, float)
    nb = int(np.clip(n_cells // 6, 4, 8))
    inner = np.quantile(s, np.linspace(0, 1, nb - 2)[1:-1]) if nb > 4 else np.zeros(0)
    lo, hi = float(s.min()) - 1e-9, float(s.max()) + 1e-9
    t = np.concatenate([[lo] * 4, inner, [hi] * 4])
    B = BSpline.design_matrix(np.clip(s, lo, hi), t, 3).toarray()
    cols = [B]
    w = np.asarray(load_n, float)
    if np.std(w) > 1e-9 * max(1.0, abs(float(np.mean(w)))):  # however little it varies (see cell_noise)
        wc = (w - w.mean()) / np.std(w)
        sc = (s - s.mean()) / (np.std(s) or 1.0)
        cols.append(np.column_stack([wc, wc * sc]))
    if x is not None and np.std(x) > 0:
        cols.append(np.column_stack([x, x**2 - np.mean(x**2)]))
        if interaction:
            cols.append(B * (x - np.mean(x))[:, None])
    return np.column_stack(cols)


#: No channel is measured better than this fraction of its RMS magnitude: the floor of a cell's noise
#: (a column rounded to a constant, or exact, would otherwise weigh without limit in the fits).
SIGMA_FLOOR_REL = 1e-4


def cell_noise(channels: dict, slip, load_n, t_s, group, sbin, kind: str, x=None):
    """Noise std of one cell mean per channel, model-free (module doc).

    ``channels`` column -> (C,) cell means; ``slip``, ``load_n``, ``t_s``,
    ``group`` (accelerate cycle), ``sbin`` (slip bin), ``x`` drift coordinate or None (C,).
    The cell means are regressed on a flexible smooth of slip, load and the
    drift coordinate (:func:`_smooth_basis`: cubic B-spline in slip, load x
    (1, slip), x and x^2, the slip spline x x while that leaves at least C / 2 degrees of
    freedom); sigma^2 = RSS / (C - p).  Whatever is a smooth
    function of slip, load or time/distance, or a slip curve changing linearly along the run
    (any effect, modelled or not) is absorbed by the smooth, so it cannot inflate the noise.  The load enters
    however little it varies: the torque is about proportional to it, so the
    0.6-1 % that load transfer moves a wheel's load by in a sweep moves the
    torque by 10-20 N m, up to 15x its noise (a smooth without the load counted
    that as noise); what remains is
    measurement noise plus cycle-to-cycle (unit-level) scatter, the floor an
    out-of-sample error can reach.  When C - p < 4 (tiny tables) the
    three-point pseudo-residuals along slip are used instead.  Also returned,
    for the report: the within-cycle view (pseudo-residuals along slip inside
    each accelerate cycle; tables: along slip).
    Returns ``(sigma, sigma_within, method)``: dicts column -> float (> 0) and a description.
    """
    sigma, within = {}, {}
    method = ""
    for c, y in channels.items():
        ok = np.isfinite(y)
        rw = []
        if kind == "table":
            o = np.argsort(slip[ok], kind="stable")
            rw.append(_pseudo_residuals(slip[ok][o], y[ok][o]))
        else:
            for g in np.unique(group[ok]):
                m = ok & (group == g)
                o = np.argsort(slip[m], kind="stable")
                rw.append(_pseudo_residuals(slip[m][o], y[m][o]))
        rw = np.concatenate(rw) if rw else np.zeros(0)
        within[c] = _robust_sd(rw)
        sd = float("nan")
        C = int(ok.sum())
        if C >= 8:
            xo = None if x is None else x[ok]
            X = _smooth_basis(slip[ok], load_n[ok], xo, C)
            if 2 * (C - np.linalg.matrix_rank(X)) < C:  # the interaction only while half the cells stay dof
                X = _smooth_basis(slip[ok], load_n[ok], xo, C, interaction=False)
            sd = _scatter_about(X, y[ok])
            if np.isfinite(sd):
                method = (f"residual scatter of the cell means about a smooth in slip, load"
                          + (" and the drift coordinate" if x is not None else "") + " (cubic B-spline, RSS/(C - p))")
        if not np.isfinite(sd):
            sd = within[c]
            method = "three-point pseudo-residuals along slip"
        yy = y[ok]
        if not (np.isfinite(sd) and sd > 0):
            sd = float(np.std(yy)) if yy.size > 1 and np.std(yy) > 0 else 0.0
        floor = SIGMA_FLOOR_REL * (float(np.sqrt(np.mean(yy**2))) if yy.size else 0.0)
        sigma[c] = float(max(sd, floor, 1e-12))
    return sigma, within, method



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
    columns ``t_s, slip, load_n, drawbar_pull_n, torque_nm, valid, cycle, distance_m``
    (the distance at a constant 1 m/s).
    ``kind="table"``: ``n_rows`` independent rows, slip uniform in [0.05, 0.9],
    white noise; columns ``slip, load_n, drawbar_pull_n, torque_nm``.
    ``noise_z_m`` adds a ``sinkage_m`` column.  The data follow ``model`` with
    ``params`` on ``terrain_truth`` (default ``terrain``).

    Returns a pandas DataFrame.  Raises ValueError for an unknown kind/model.
    """
    import pandas as pd
    from scipy.signal import butter, sosfiltfilt

    from .slip_sinkage import get_model

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
        df["distance_m"] = t * 1.0
    return df

