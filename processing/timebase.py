"""A robust time base: outlier timestamps, logs joined out of order, loss by cycle time.

Field recordings get copied, joined and converted; a single frame with a
timestamp hours off (a clock step, a converter bug, a NaN stored as the
smallest int64) must not stretch the processing grid over hours, and two logs
joined in the wrong order must not be read as one run. This module works on
the host receive times of one message (int64 ns, in file order, as the MCAP
reader delivers them, ``wheelsoil.daq.iter_frame_batches``):

* :func:`find_time_outliers` sets aside frames whose timestamp is far from
  their neighbours (local median of the ``2 w + 1`` frames around each one in
  file order, so a lone frame off by hours, or a NaN/1e20 converted to int64,
  is found wherever it is), and small clusters of frames far away from the bulk
  of the run (a block of frames off by the same amount);
* :func:`split_joined_parts` finds where time runs backwards in file order
  (two logs joined out of order), checks that the parts do not overlap in time
  (then sorting them is safe) and raises ``ValueError`` naming the parts when
  they do (two recordings of the same time: nothing sensible can be made);
* :func:`find_clock_steps` finds where the host clock stepped (forward or back) during
  logging (NTP or GPS sync after boot, an RTC starting at 1970) from the receiver's GPS time in
  the frames, which runs on: every message's host times jump there by the same amount, and
  nothing was lost in the jump;
* :func:`cycle_loss` counts the frames of a message without a counter against
  its nominal cycle time (DBC ``GenMsgCycleTime`` or ``cycle_time_s`` in
  vehicle.toml): ``lost = round(span / period) + 1 - received`` per part, or
  ``None`` (unknown) without a nominal period. Counting against the span is
  robust to bursty delivery (USB/UDP adapters), where time gaps are not.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["find_time_outliers", "split_joined_parts", "find_clock_steps", "cycle_loss", "robust_period",
           "OUTLIER_MIN_S", "CLUSTER_GAP_S", "CLUSTER_MAX_SHARE", "BACKWARD_MIN_S", "MAX_GRID_ROWS"]

#: A frame is an outlier when it is this far [s] (at least; or 50 typical frame spacings)
#: from the median of its neighbours in file order.
OUTLIER_MIN_S = 1.0
#: Frames separated from the rest of the run by more than this [s] ...
CLUSTER_GAP_S = 60.0
#: ... and holding less than this share of the message's frames are set aside (sorted by
#: time, or at either end of the file) ...
CLUSTER_MAX_SHARE = 0.005
#: ... or less than this share when, in file order, time jumps away and comes back to
#: where it left (a block of frames off by the same amount in the middle of a file).
BLOCK_MAX_SHARE = 0.1
#: A step back in time [s] (at least; or 10 typical spacings) in file order starts a new part.
BACKWARD_MIN_S = 0.5
#: Largest processing grid [rows]: ~14 h at 100 Hz, about 1 GB of columns.
MAX_GRID_ROWS = 5_000_000


def _typical_spacing(x: np.ndarray) -> float:
    """Robust mean spacing [s] of sorted-or-not times ``x`` (n,) in seconds: the 5-95 %
    range over the frames in it (insensitive to outliers and to bursty delivery)."""
    if x.shape[0] < 3:
        return 0.0
    lo, hi = np.percentile(x, [5.0, 95.0])
    return float(max(hi - lo, 0.0) / max(0.9 * x.shape[0], 1.0))


def find_time_outliers(ts_ns: np.ndarray, *, window: int = 8) -> tuple[np.ndarray, list[dict]]:
    """Frames of one message whose timestamps are far outside their neighbours.

    ``ts_ns`` int64 (n,) host receive times in file order. A frame is an
    outlier when it is more than ``max(OUTLIER_MIN_S, 50 x typical spacing)``
    from the median of the ``2 window + 1`` frames around it in file order
    (a mirror at the ends); or when it is in a block of frames that, in file
    order, jumps more than :data:`CLUSTER_GAP_S` away from the frames before it
    and after it while those two agree (time comes back: a block off by the same
    amount), holding less than :data:`BLOCK_MAX_SHARE` of the frames; or when,
    sorted by time, it is in the first or last cluster, separated from the rest
    by more than :data:`CLUSTER_GAP_S`, holding less than
    :data:`CLUSTER_MAX_SHARE` of the frames (and not the largest). Larger blocks are left for
    :func:`split_joined_parts` (logs joined out of order).

    Returns ``(keep, runs)``: ``keep`` bool (n,) False for outliers; ``runs``
    one dict per run of consecutive outliers in file order: ``first`` /
    ``last`` frame index, ``frames`` count, ``claimed_ns`` (min, max) of their
    timestamps, ``before_ns`` / ``after_ns`` the kept neighbours' timestamps
    (None at an end). Source: this project's robust-statistics convention
    (median/percentile based, no distribution assumed).
    """
    ts = np.asarray(ts_ns, dtype=np.int64)
    n = ts.shape[0]
    keep = np.ones(n, dtype=bool)
    if n < 3:
        return keep, []
    ref = int(np.median(ts))
    # seconds relative to the median, in float: int64 differences could overflow for
    # sentinel values (-2**63); float precision (~1e-7 s near 0) is plenty here
    x = (ts.astype(np.float64) - float(ref)) * 1e-9
    spacing = _typical_spacing(x)
    thr = max(OUTLIER_MIN_S, 50.0 * spacing)
    w = int(min(window, (n - 1) // 2))
    if w >= 1:
        from scipy.ndimage import median_filter

        med = median_filter(x, size=2 * w + 1, mode="mirror")
        keep &= np.abs(x - med) <= thr
    # blocks in file order that jump away and come back (time returns to where it left)
    idx = np.flatnonzero(keep)
    if idx.size >= 3:
        xk = x[idx]
        cuts = np.flatnonzero(np.abs(np.diff(xk)) > CLUSTER_GAP_S) + 1
        if cuts.size:
            starts = np.concatenate([[0], cuts])
            ends = np.concatenate([cuts, [xk.size]])
            for a, b in zip(starts, ends):
                small = (b - a) < BLOCK_MAX_SHARE * xk.size
                if 0 < a and b < xk.size and small and abs(xk[b] - xk[a - 1]) <= CLUSTER_GAP_S:
                    keep[idx[a:b]] = False
                elif (a == 0 or b == xk.size) and (b - a) < CLUSTER_MAX_SHARE * xk.size:
                    keep[idx[a:b]] = False
    # clusters far from the bulk in time
    idx = np.flatnonzero(keep)
    if idx.size >= 2:
        order = idx[np.argsort(x[idx], kind="stable")]
        xs = x[order]
        cuts = np.flatnonzero(np.diff(xs) > CLUSTER_GAP_S) + 1
        if cuts.size:
            starts = np.concatenate([[0], cuts])
            ends = np.concatenate([cuts, [xs.size]])
            sizes = ends - starts
            biggest = int(np.argmax(sizes))
            # only at the ends in time: those are what would stretch the grid beyond the run
            # (frames between two parts of the run are not outside their neighbours)
            for k in (0, len(starts) - 1):
                a, b = starts[k], ends[k]
                if k != biggest and (b - a) < CLUSTER_MAX_SHARE * idx.size:
                    keep[order[a:b]] = False
    runs = []
    bad = np.flatnonzero(~keep)
    if bad.size:
        brk = np.flatnonzero(np.diff(bad) > 1) + 1
        kept = np.flatnonzero(keep)
        for grp in np.split(bad, brk):
            a, b = int(grp[0]), int(grp[-1])
            i_before = np.searchsorted(kept, a) - 1
            i_after = np.searchsorted(kept, b, side="right")
            runs.append({
                "first": a, "last": b, "frames": int(grp.size),
                "claimed_ns": (int(ts[grp].min()), int(ts[grp].max())),
                "before_ns": int(ts[kept[i_before]]) if i_before >= 0 else None,
                "after_ns": int(ts[kept[i_after]]) if i_after < kept.size else None,
            })
    return keep, runs


def split_joined_parts(ts_ns: np.ndarray) -> list[tuple[int, int]]:
    """Parts of a message's timestamps that run forward, split where time runs back.

    ``ts_ns`` int64 (n,) in file order (outliers already removed). A step back
    by more than ``max(BACKWARD_MIN_S, 10 x typical spacing)`` starts a new
    part (two logs joined out of order); smaller steps back are reordered
    frames and stay. Returns the parts as ``[(start, stop), ...]`` frame index
    ranges in file order (one part for a normal recording).

    Raises ``ValueError`` when two parts overlap in time (the same span
    recorded twice, or two runs interleaved): the message says which frames and
    times. Parts that do not overlap can be sorted by time safely.
    """
    ts = np.asarray(ts_ns, dtype=np.int64)
    n = ts.shape[0]
    if n < 2:
        return [(0, n)]
    x = (ts.astype(np.float64) - float(ts.min())) * 1e-9  # float: no int64 overflow
    thr = max(BACKWARD_MIN_S, 10.0 * _typical_spacing(x))
    back = np.flatnonzero(np.diff(x) < -thr) + 1
    if back.size == 0:
        return [(0, n)]
    bounds = np.concatenate([[0], back, [n]])
    parts = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
    spans = sorted(((x[a:b].min(), x[a:b].max(), a, b) for a, b in parts))
    lo1, hi1, a1, b1 = spans[0]
    for lo2, hi2, a2, b2 in spans[1:]:
        if lo2 < hi1 - thr:
            raise ValueError(
                f"time runs backwards and the parts overlap: frames {a1}-{b1 - 1} cover "
                f"{lo1:.3f}-{hi1:.3f} s and frames {a2}-{b2 - 1} cover {lo2:.3f}-{hi2:.3f} s "
                "(relative to the earliest frame); two logs of the same time joined (split them and process "
                "each on its own), or the host clock stepped back while logging")
        if hi2 > hi1:
            lo1, hi1, a1, b1 = lo2, hi2, a2, b2
    return parts


#: A host clock step [s] is at least this large (smaller offsets between host and GPS time
#: are latency jitter and bursty delivery) ...
CLOCK_STEP_MIN_S = 1.0
#: ... and the host-minus-GPS offset stays within this [s] of its median on each side of it,
#: over ``CLOCK_STEP_FRAMES`` frames (a step, not one frame with a wrong time).
CLOCK_STEP_SPREAD_S = 0.25
CLOCK_STEP_FRAMES = 5
#: ... while GPS time runs on: between the two frames it advances by at least 0 and at most
#: this [s] (a few lost fixes); logs joined out of order jump in GPS time too.
CLOCK_STEP_GPS_GAP_S = 10.0


def find_clock_steps(host_ns: np.ndarray, gps_s: np.ndarray) -> list[tuple[int, int]]:
    """Steps of the host clock, found against GPS time carried in the frames.

    ``host_ns`` int64 (n,) host receive times of the GPS-time message in file order;
    ``gps_s`` float (n,) the GPS time each frame carries [s] (week * 604800 + time of week).
    The offset host - GPS is constant up to latency jitter; where it changes by at least
    :data:`CLOCK_STEP_MIN_S` between frames ``j`` and ``j + 1`` and stays there (the
    ``CLOCK_STEP_FRAMES`` frames on each side within :data:`CLOCK_STEP_SPREAD_S` of their
    median) while GPS time runs on (it advances by 0 to :data:`CLOCK_STEP_GPS_GAP_S`), the
    host clock stepped, forward or back.  A real pause of the logger moves both clocks and is
    no step; nor are logs joined out of order (GPS time jumps with host time).

    Returns ``[(j, step_ns)]``: ``j`` the last frame before each step (file order),
    ``step_ns`` the step, > 0 forward (the difference of the two medians).  Non-finite GPS
    times are skipped.  Source: this project's robust-statistics convention (medians, no
    distribution assumed).
    """
    host = np.asarray(host_ns, dtype=np.int64)
    gps = np.asarray(gps_s, dtype=np.float64)
    ok = np.flatnonzero(np.isfinite(gps))
    k = CLOCK_STEP_FRAMES
    if ok.size < 2 * k:
        return []
    g = gps[ok] - gps[ok[0]]
    off = (host[ok] - host[ok[0]]) * 1e-9 - g
    dg = np.diff(g)
    steps = []
    for i in np.flatnonzero((np.abs(np.diff(off)) >= CLOCK_STEP_MIN_S) & (dg >= 0) & (dg <= CLOCK_STEP_GPS_GAP_S)):
        before, after = off[max(0, i + 1 - k):i + 1], off[i + 1:i + 1 + k]
        if before.size < k or after.size < k:
            continue
        mb, ma = float(np.median(before)), float(np.median(after))
        if (abs(ma - mb) >= CLOCK_STEP_MIN_S and np.all(np.abs(before - mb) <= CLOCK_STEP_SPREAD_S)
                and np.all(np.abs(after - ma) <= CLOCK_STEP_SPREAD_S)):
            steps.append((int(ok[i]), int(round((ma - mb) * 1e9))))
    return steps


def robust_period(ts_sorted_ns: np.ndarray) -> float:
    """Typical frame period [s] of sorted times ``ts_sorted_ns`` (n,): the median over
    windows of up to 256 frames of (elapsed time / frames), so bursty delivery
    (many frames microseconds apart, then a pause) gives the true mean period; NaN
    for fewer than 3 frames."""
    t = np.asarray(ts_sorted_ns, dtype=np.int64)
    n = t.shape[0]
    if n < 3:
        return float("nan")
    w = int(min(256, n - 1))
    span = (t[w:] - t[:-w]).astype(np.float64) * 1e-9
    return float(np.median(span) / w)


def cycle_loss(ts_sorted_ns: np.ndarray, nominal_s: float | None, *,
               breaks: list[tuple[int, int]] | None = None) -> tuple[int | None, str]:
    """Frames lost from a message without a counter, from its nominal cycle time.

    ``ts_sorted_ns`` int64 (n,) sorted receive times; ``nominal_s`` the
    nominal period [s] (None: unknown); ``breaks`` index ranges of parts whose
    gaps between them are not counted (joined logs). Returns ``(lost, note)``:
    ``lost = sum over parts of round(span / nominal) + 1 - received`` (>= 0),
    or ``None`` with the reason when it cannot be known (no nominal period, or
    more frames than the nominal period allows: the nominal period is wrong).
    """
    t = np.asarray(ts_sorted_ns, dtype=np.int64)
    n = t.shape[0]
    if not nominal_s or not math.isfinite(nominal_s) or nominal_s <= 0:
        return None, "no counter and no nominal cycle time: loss unknown"
    if n < 2:
        return None, "too few frames"
    parts = breaks or [(0, n)]
    expected = sum(int(round((t[b - 1] - t[a]) * 1e-9 / nominal_s)) + 1 for a, b in parts if b > a)
    if n > expected * 1.02 + 2:
        return None, (f"{n} frames where the nominal cycle time {nominal_s * 1e3:g} ms allows {expected}: "
                      "the nominal cycle time is wrong, loss unknown")
    return max(0, expected - n), ""
