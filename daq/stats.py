"""Frame statistics of a recording or a live stream, vectorised per batch.

Counts frames per bus and id, error and remote frames, unknown ids (not in the
bus's DBC files), DLC mismatches against the DBC, and lost frames from gaps of
the sample counters named ``wft_counter_*`` in the vehicle configuration.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .frames import FLAG_ERROR, FLAG_REMOTE, FrameBatch


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
        lost_frames: DBC message name -> frames lost according to its sample counter.
        counter_duplicates: DBC message name -> frames repeating the previous counter value.
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
        self._counters: dict[tuple[str, int], tuple[str, int, int]] = {}
        self._last_counter: dict[tuple[str, int], int] = {}
        if config is not None:
            for bus in config.buses:
                db = config.database(bus)
                self._known[bus] = {_key(m.frame_id, m.is_extended_frame): m.length for m in db.messages}
                self.stats.names[bus] = {(m.frame_id, bool(m.is_extended_frame)): m.name for m in db.messages}
            for bus, fid, ext, byte, mod in config.counter_specs():
                name = self.stats.names[bus][(fid, ext)]
                self._counters[(bus, _key(fid, ext))] = (name, byte, mod)

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
        for (cbus, k), (name, byte, mod) in self._counters.items():
            if cbus != bus:
                continue
            sel = (keys == k) & (dlc > byte) & ~rem[good]
            if not sel.any():
                continue
            data = b.data[good][sel]
            c = (data[:, byte].astype(np.int64)) % mod
            prev = self._last_counter.get((bus, k))
            if prev is not None:
                c = np.concatenate(([prev], c))
            step = np.diff(c) % mod
            s.lost_frames[name] = s.lost_frames.get(name, 0) + int(np.where(step == 0, 0, step - 1).sum())
            s.counter_duplicates[name] = s.counter_duplicates.get(name, 0) + int((step == 0).sum())
            s.lost_frames.setdefault(name, 0)
            self._last_counter[(bus, k)] = int(c[-1])


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
