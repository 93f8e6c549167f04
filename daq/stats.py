"""Frame statistics of a recording or a live stream, vectorised per batch.

Counts frames per bus and id, error and remote frames, unknown ids (not in the
bus's DBC files), DLC mismatches against the DBC, and lost frames from gaps of
the sample counters named ``wft_counter_*`` in the vehicle configuration.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .frames import FLAG_ERROR, FLAG_REMOTE, FrameBatch

#: A counter that advances by the same step k > 1 in at least this share of its frames, every frame's
#: counter the same modulo k, is a transducer that sends every k-th sample (a decimated output rate):
#: see :func:`counter_stride`.  Random loss leaves no common residue, so it cannot pass for one.
STRIDE_MIN_SHARE = 0.5
STRIDE_MIN_SAME_RESIDUE = 0.99
#: ... judged once, on the first batch of a message with at least this many counter steps (steps
#: before it are counted as steps of one).
STRIDE_MIN_FRAMES = 8


def counter_stride(counter: np.ndarray, *, modulo: int = 256) -> int:
    """The step by which a sample counter advances per frame sent: 1, or ``k`` for a transducer whose
    output is decimated to every ``k``-th sample (a WFT configured to 250 Hz counts 0, 2, 4, ...).

    ``counter`` (N,) counter values ``0..modulo-1`` in frame order.  ``k`` > 1 is returned when the
    most common forward step is ``k`` in at least :data:`STRIDE_MIN_SHARE` of the steps and at least
    :data:`STRIDE_MIN_SAME_RESIDUE` of the counters share one residue modulo ``k`` (frames lost at
    random make steps of 2 common too, but never one residue).  Raises ``ValueError`` when such a
    ``k`` does not divide ``modulo``: the counter then changes residue at every wrap and the sample
    index cannot be unwrapped from it.  Source: the counter's meaning in ``dbc/wft.dbc``; hardware.md
    (500 Hz nominal)."""
    c = np.asarray(counter).astype(np.int64) % modulo
    d = np.diff(c) % modulo
    d = d[d > 0]
    if d.size < 2:
        return 1
    values, counts = np.unique(d, return_counts=True)
    k = int(values[np.argmax(counts)])
    if k <= 1 or counts.max() < STRIDE_MIN_SHARE * d.size:
        return 1
    if modulo % k:
        raise ValueError(f"the counter advances by {k} per frame, which does not divide its wrap at {modulo}: "
                         "the sample index cannot be unwrapped (a transducer output rate that is not the nominal "
                         "rate divided by a power of two?)")
    if np.bincount(c % k, minlength=k).max() < STRIDE_MIN_SAME_RESIDUE * c.size:
        return 1
    return k


@dataclass
class FrameStats:
    """Counts over a stream of frames (see :class:`StatsAccumulator`).

    Attributes:
        frames: bus -> frame count.
        first_ns, last_ns: bus -> first/last receive time [ns].
        id_counts: bus -> {(arbitration id, is_extended): frames}, data frames only.
        error_frames, remote_frames: bus -> count.
        unknown_ids: bus -> {(id, is_extended): frames} of ids not in that bus's DBCs
            (empty when the bus has no DBC configured).
        dlc_mismatch: bus -> {(id, is_extended): frames} whose dlc differs from the DBC length.
        lost_frames: DBC message name -> frames lost according to its sample counter
            (a counter wrap is resolved with the timestamps: a gap of dt is about
            dt / period samples, not dt mod 2**bits).
        lost_frames_estimated: DBC message name -> frames missing by its nominal cycle time
            (DBC ``GenMsgCycleTime``), for messages without a counter: sum over gaps
            dt > 1.5 cycles of round(dt / cycle) - 1 (an estimate: host receive times jitter).
        counter_duplicates: DBC message name -> frames repeating the previous counter value.
        counter_stride: DBC message name -> the step ``k`` > 1 its counter advances by per frame
            (:func:`counter_stride`: a transducer sending one sample in ``k``); ``lost_frames``
            then counts frames of that output, and messages absent here step by 1.
        long_gaps: DBC message name -> intervals between its frames longer than
            :data:`LONG_GAP_NS` (a pause of the logger, or a step of the host clock), which
            ``lost_frames`` and ``lost_frames_estimated`` do not count: no frame a bus dropped
            makes an hour-long hole, and a clock step drops none.
        names: bus -> {(id, is_extended): DBC message name}.
    """

    frames: dict = field(default_factory=dict)
    first_ns: dict = field(default_factory=dict)
    last_ns: dict = field(default_factory=dict)
    id_counts: dict = field(default_factory=dict)
    error_frames: dict = field(default_factory=dict)
    remote_frames: dict = field(default_factory=dict)
    unknown_ids: dict = field(default_factory=dict)
    dlc_mismatch: dict = field(default_factory=dict)
    lost_frames: dict = field(default_factory=dict)
    counter_duplicates: dict = field(default_factory=dict)
    names: dict = field(default_factory=dict)
    lost_frames_estimated: dict = field(default_factory=dict)
    long_gaps: dict = field(default_factory=dict)
    counter_stride: dict = field(default_factory=dict)

    def total(self, what: str) -> int:
        """Sum over buses/messages of one counter (e.g. ``"lost_frames"``, ``"unknown_ids"``)."""
        v = getattr(self, what)
        return int(sum(sum(x.values()) if isinstance(x, dict) else x for x in v.values()))


class StatsAccumulator:
    """Accumulate :class:`FrameStats` batch by batch (no per-frame Python).

    Args:
        config: :class:`~wheelsoil.daq.config.VehicleConfig` for DBC names,
            lengths and counters; None counts frames and ids only.

    Counters are tracked per (bus, id) across batches, so feed each bus's
    batches in receive order.
    """

    def __init__(self, config=None):
        self.stats = FrameStats()
        self._known: dict[str, dict[int, int]] = {}   # bus -> {key: dbc length}
        self._counters: dict[tuple[str, int], tuple[str, int, int, int]] = {}
        self._last_counter: dict[tuple[str, int], tuple[int, int]] = {}   # (counter, t_ns)
        self._period_ns: dict[tuple[str, int], float] = {}
        self._stride: dict[tuple[str, int], int] = {}   # the counter's step per frame, once known
        self._cycles: dict[str, dict[int, tuple[str, float]]] = {}   # bus -> key -> (name, cycle ns)
        self._last_t: dict[tuple[str, int], int] = {}
        if config is not None:
            for bus in config.buses:
                db = config.database(bus)
                self._known[bus] = {_key(m.frame_id, m.is_extended_frame): m.length for m in db.messages}
                self.stats.names[bus] = {(m.frame_id, bool(m.is_extended_frame)): m.name for m in db.messages}
                cyc = {_key(m.frame_id, m.is_extended_frame): (m.name, float(m.cycle_time) * 1e6)
                       for m in db.messages if getattr(m, "cycle_time", None) and m.cycle_time > 0}
                if cyc:
                    self._cycles[bus] = cyc
            for bus, fid, ext, byte, mod, shift in config.counter_specs():
                name = self.stats.names[bus][(fid, ext)]
                self._counters[(bus, _key(fid, ext))] = (name, byte, mod, shift)
                self._cycles.get(bus, {}).pop(_key(fid, ext), None)

    def update(self, b: FrameBatch) -> None:
        """Add one batch."""
        n = len(b)
        if n == 0:
            return
        s = self.stats
        bus = b.bus
        s.frames[bus] = s.frames.get(bus, 0) + n
        s.first_ns.setdefault(bus, int(b.timestamp_ns[0]))
        s.last_ns[bus] = int(b.timestamp_ns[-1])
        err = (b.flags & FLAG_ERROR) != 0
        rem = (b.flags & FLAG_REMOTE) != 0
        s.error_frames[bus] = s.error_frames.get(bus, 0) + int(err.sum())
        s.remote_frames[bus] = s.remote_frames.get(bus, 0) + int(rem.sum())
        good = ~err
        keys = _key(b.arbitration_id[good].astype(np.int64), b.is_extended[good])
        dlc = b.dlc[good]
        uk, inv, cnt = np.unique(keys, return_inverse=True, return_counts=True)
        ids = s.id_counts.setdefault(bus, {})
        known = self._known.get(bus)
        for k, c in zip(uk.tolist(), cnt.tolist()):
            t = _unkey(k)
            ids[t] = ids.get(t, 0) + c
            if known is not None and k not in known:
                d = s.unknown_ids.setdefault(bus, {})
                d[t] = d.get(t, 0) + c
        if known:
            want = np.array([known.get(k, -1) for k in uk.tolist()], np.int64)[inv]
            bad = (want >= 0) & (want != dlc) & ~rem[good]
            if bad.any():
                bk, bc = np.unique(keys[bad], return_counts=True)
                d = s.dlc_mismatch.setdefault(bus, {})
                for k, c in zip(bk.tolist(), bc.tolist()):
                    d[_unkey(k)] = d.get(_unkey(k), 0) + c
        ts = None
        for (cbus, k), (name, byte, mod, shift) in self._counters.items():
            if cbus != bus:
                continue
            sel = (keys == k) & (dlc > byte) & ~rem[good]
            if not sel.any():
                continue
            if ts is None:
                ts = b.timestamp_ns[good]
            data = b.data[good][sel]
            c = (data[:, byte].astype(np.int64) >> shift) % mod
            t = ts[sel]
            prev = self._last_counter.get((bus, k))
            if prev is not None:
                c = np.concatenate(([prev[0]], c))
                t = np.concatenate(([prev[1]], t))
            step = np.diff(c) % mod
            dt = np.diff(t).astype(np.float64)
            g = self._stride.get((bus, k))
            if g is None and step.size >= STRIDE_MIN_FRAMES:  # decided once, on the first frames
                try:
                    g = counter_stride(c, modulo=mod)
                except ValueError:
                    g = 1  # a step that does not divide the wrap: counted as is (processing says why)
                self._stride[(bus, k)] = g
                if g > 1:
                    s.counter_stride[name] = g
            g = g or 1
            # sample period: median receive interval of consecutive samples (one step)
            one = step == g
            per = self._period_ns.get((bus, k))
            if one.sum() >= 8:
                est = float(np.median(dt[one]))
                if est > 0:
                    per = est if per is None else 0.9 * per + 0.1 * est
                    self._period_ns[(bus, k)] = per
            if per is not None and per > 0:
                # a gap longer than the counter's range wraps: the whole number of wraps
                # comes from the elapsed time (dt / period samples), the rest from the counter
                wraps = np.round((dt / per - step / g) / (mod / g))
                k_steps = np.round(step / g) + (mod // g) * np.maximum(wraps, 0)
            else:
                k_steps = np.round(step / g)
            lost = np.where((step == 0) | self._long_gaps(name, dt), 0, np.maximum(k_steps - 1, 0)).astype(np.int64)
            s.lost_frames[name] = s.lost_frames.get(name, 0) + int(lost.sum())
            s.counter_duplicates[name] = s.counter_duplicates.get(name, 0) + int((step == 0).sum())
            s.lost_frames.setdefault(name, 0)
            self._last_counter[(bus, k)] = (int(c[-1]), int(t[-1]))
        cyc = self._cycles.get(bus)
        if cyc:
            if ts is None:
                ts = b.timestamp_ns[good]
            self._cycle_gaps(bus, cyc, keys, uk, ts, rem[good])

    def _long_gaps(self, name: str, dt) -> np.ndarray:
        """Intervals ``dt`` [ns] (K,) of message ``name`` longer than :data:`LONG_GAP_NS`, counted in
        :attr:`FrameStats.long_gaps`; returns their mask (K,), the intervals no lost frame is counted in."""
        long = dt > LONG_GAP_NS
        if long.any():
            self.stats.long_gaps[name] = self.stats.long_gaps.get(name, 0) + int(long.sum())
        return long

    def _cycle_gaps(self, bus, cyc, keys, uk, ts, rem) -> None:
        """Frames missing by nominal cycle time for the ids of ``cyc`` in this batch."""
        s = self.stats
        for k in uk.tolist():
            spec = cyc.get(k)
            if spec is None:
                continue
            name, cycle = spec
            sel = (keys == k) & ~rem
            t = ts[sel]
            if t.size == 0:
                continue
            prev = self._last_t.get((bus, k))
            if prev is not None:
                t = np.concatenate(([prev], t))
            dt = np.diff(t).astype(np.float64)
            big = (dt > 1.5 * cycle) & ~self._long_gaps(name, dt)
            n = int((np.round(dt[big] / cycle) - 1).sum()) if big.any() else 0
            s.lost_frames_estimated[name] = s.lost_frames_estimated.get(name, 0) + n
            self._last_t[(bus, k)] = int(t[-1])


def _key(fid, ext):
    """Pack (id, extended) into one int: id | ext << 31."""
    if isinstance(fid, np.ndarray):
        return fid | (np.asarray(ext, np.int64) << 31)
    return int(fid) | (int(bool(ext)) << 31)


def _unkey(k: int) -> tuple[int, bool]:
    return (k & 0x7FFFFFFF, bool(k >> 31))


def frame_stats(batches, config=None) -> FrameStats:
    """:class:`FrameStats` of an iterable of :class:`FrameBatch` (see :class:`StatsAccumulator`)."""
    acc = StatsAccumulator(config)
    for b in batches:
        acc.update(b)
    return acc.stats


#: An interval between two frames of one message longer than this [ns] is a pause of the logger or a
#: step of the host clock, not frames lost on the bus (:attr:`FrameStats.long_gaps`); the same hour
#: that separates a recording's time clusters (:data:`OUTLIER_GAP_NS`).
LONG_GAP_NS = 3600 * 10**9
#: A frame further than this from the median of its batch is an outlier [ns] (a batch
#: spans <= 0.5 s from the logger, <= 2000 consecutive frames of one bus from an import).
OUTLIER_IN_BATCH_NS = 60 * 10**9
#: Batches whose times are more than this apart belong to separate clusters; the
#: cluster holding most frames is the run, the others are outliers [ns].
OUTLIER_GAP_NS = LONG_GAP_NS
#: ... and when that cluster holds less than this share of all frames.
OUTLIER_SHARE = 0.01


class TimeBaseAccumulator:
    """True first/last receive time of a stream of batches, robust to outliers,
    and backward time steps (logs joined out of order), with bounded memory.

    A frame is an outlier when it is more than :data:`OUTLIER_IN_BATCH_NS` from
    its batch's median (and further than 20 interquartile ranges of the batch),
    or when its whole batch lies in a time cluster separated from the one that
    holds most frames by more than :data:`OUTLIER_GAP_NS` and holding less than
    :data:`OUTLIER_SHARE` of the frames (a frame 6 h or a day off, 0 or huge
    values); bigger far clusters are part of the run (their gaps in ``gaps_s``). Per batch only a few numbers are kept
    (O(batches) memory, one median per batch).

    Source: robust location by medians (Hampel identifier idea; Huber & Ronchetti,
    Robust Statistics, 2009, ch. 1).
    """

    def __init__(self):
        self._batches: list[tuple] = []   # (median, lo, hi, n_inliers, bus, first frame index)
        self._frames: dict[str, int] = {}
        self._last: dict[str, int] = {}
        self.in_batch_outliers: list[tuple[str, int, int]] = []   # (bus, frame index, t_ns)
        self.n_in_batch_outliers = 0
        self.backward: dict[str, int] = {}        # bus -> backward steps
        self.max_backward_ns: dict[str, int] = {}
        self.first_backward: dict[str, tuple[int, int]] = {}    # bus -> (frame index, t_ns)

    def update(self, b: FrameBatch) -> None:
        """Add one batch (batches of one bus in receive order)."""
        n = len(b)
        if n == 0:
            return
        bus = b.bus
        base = self._frames.get(bus, 0)
        self._frames[bus] = base + n
        t = b.timestamp_ns
        med = int(np.median(t))
        d = np.abs(t.astype(np.float64) - med)
        if n >= 4:
            q1, q3 = np.percentile(t, [25, 75])
            tol = max(OUTLIER_IN_BATCH_NS, 20.0 * float(q3 - q1))
        else:
            tol = OUTLIER_IN_BATCH_NS
        bad = d > tol
        if bad.any():
            idx = np.flatnonzero(bad)
            self.n_in_batch_outliers += int(idx.size)
            for i in idx[:5].tolist():
                if len(self.in_batch_outliers) < 10:
                    self.in_batch_outliers.append((bus, base + i, int(t[i])))
            good = np.flatnonzero(~bad)
            t = t[good]
            if t.size == 0:
                return
        else:
            good = None
        steps = np.diff(t)
        back = steps < 0
        prev = self._last.get(bus)
        nb = int(back.sum())
        jump = int(-steps[back].min()) if nb else 0
        first_back = None
        if prev is not None and int(t[0]) < prev:
            nb += 1
            jump = max(jump, prev - int(t[0]))
            first_back = (base + (0 if good is None else int(good[0])), int(t[0]))
        elif nb:
            i = int(np.flatnonzero(back)[0]) + 1
            first_back = (base + (i if good is None else int(good[i])), int(t[i]))
        if nb:
            self.backward[bus] = self.backward.get(bus, 0) + nb
            self.max_backward_ns[bus] = max(self.max_backward_ns.get(bus, 0), jump)
            self.first_backward.setdefault(bus, first_back)
        self._last[bus] = int(t[-1])
        self._batches.append((med, int(t.min()), int(t.max()), int(t.size), bus, base))

    def result(self) -> dict:
        """``{"first_ns", "last_ns", "outliers": {"frames", "examples": [{bus, frame, t_ns}],
        "batches"}, "first_ns_by_bus", "last_ns_by_bus", "backward_steps": {bus: n},
        "max_backward_s": {bus: s}, "first_backward": {bus: {frame, t_ns}}, "gaps_s": [s]}`` (times in ns
        since the Unix epoch; None without frames)."""
        out = {"first_ns": None, "last_ns": None, "first_ns_by_bus": {}, "last_ns_by_bus": {},
               "outliers": {"frames": self.n_in_batch_outliers, "batches": 0,
                            "examples": [{"bus": b, "frame": i, "t_ns": t} for b, i, t in self.in_batch_outliers]},
               "backward_steps": dict(self.backward),
               "max_backward_s": {b: v / 1e9 for b, v in self.max_backward_ns.items()},
               "first_backward": {b: {"frame": i, "t_ns": t} for b, (i, t) in self.first_backward.items()},
               "gaps_s": []}
        if not self._batches:
            return out
        arr = np.array([(m, n) for m, _lo, _hi, n, _b, _i in self._batches], np.float64)
        order = np.argsort(arr[:, 0], kind="stable")
        meds = arr[order, 0]
        cut = np.flatnonzero(np.diff(meds) > OUTLIER_GAP_NS) + 1
        groups = np.split(order, cut)
        weights = np.array([arr[g, 1].sum() for g in groups])
        # outliers: clusters far from the main one holding < 1 % of the frames; a big
        # cluster (two logs of one day joined) is part of the run, its gap is reported
        big = weights >= max(OUTLIER_SHARE * weights.sum(), 1)
        big[int(np.argmax(weights))] = True
        keep = set(np.concatenate([g for g, b_ in zip(groups, big) if b_]).tolist())
        # cut m separates cluster m from cluster m + 1
        out["gaps_s"] = [float((meds[c] - meds[c - 1]) / 1e9) for m, c in enumerate(cut.tolist())
                         if big[m] and big[m + 1]]
        for k, (m, lo, hi, n, bus, base) in enumerate(self._batches):
            if k in keep:
                out["first_ns"] = lo if out["first_ns"] is None else min(out["first_ns"], lo)
                out["last_ns"] = hi if out["last_ns"] is None else max(out["last_ns"], hi)
                out["first_ns_by_bus"][bus] = min(out["first_ns_by_bus"].get(bus, lo), lo)
                out["last_ns_by_bus"][bus] = max(out["last_ns_by_bus"].get(bus, hi), hi)
            else:
                out["outliers"]["frames"] += n
                out["outliers"]["batches"] += 1
                if len(out["outliers"]["examples"]) < 10:
                    out["outliers"]["examples"].append({"bus": bus, "frame": base, "t_ns": m, "batch_frames": n})
        return out
