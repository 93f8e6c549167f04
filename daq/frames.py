"""Raw CAN frames as column arrays: :class:`FrameBatch`.

A batch holds N frames of one bus as numpy columns, the unit in which
recordings are written, read and handed to processing. Conversions to and from
python-can's :class:`can.Message` live here too (import/export/replay use them);
the hot paths (logger, reader) never build per-frame Python objects.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

#: Bits of :attr:`FrameBatch.flags` (see docs/mcap-layout.md).
FLAG_EXTENDED = 0x01
FLAG_REMOTE = 0x02
FLAG_ERROR = 0x04
FLAG_FD = 0x08
FLAG_BRS = 0x10
FLAG_ESI = 0x20
#: Frame was transmitted by the logging host (python-can ``is_rx=False``).
FLAG_TX = 0x40

#: Bytes per frame in ``FrameBatch.data``: classic CAN and CAN FD.
CLASSIC_WIDTH = 8
FD_WIDTH = 64


@dataclass
class FrameBatch:
    """N raw CAN frames of one bus, as column arrays (all of length N).

    Attributes:
        bus: bus name (``can0``, ``can1``, ... as in the vehicle configuration).
        timestamp_ns: int64 (N,), host receive time in ns since the Unix epoch
            (the kernel's SocketCAN receive timestamp in the field).
        arbitration_id: uint32 (N,), 11- or 29-bit identifier (no flag bits).
        is_extended: bool (N,), 29-bit identifier (same as ``flags & 1``).
        flags: uint8 (N,), bit0 extended, bit1 remote, bit2 error, bit3 FD,
            bit4 BRS, bit5 ESI, bit6 transmitted by the host (not received).
        dlc: uint8 (N,), python-can's ``dlc``: payload length in bytes (0..8,
            up to 64 for FD frames); for remote frames the requested length.
        data: uint8 (N, 8) for classic CAN, (N, 64) if any frame is FD; bytes
            past the payload length are zero.
    """

    bus: str
    timestamp_ns: np.ndarray
    arbitration_id: np.ndarray
    is_extended: np.ndarray
    flags: np.ndarray
    dlc: np.ndarray
    data: np.ndarray

    def __len__(self) -> int:
        return int(self.timestamp_ns.shape[0])

    @property
    def data_width(self) -> int:
        """Bytes per frame in :attr:`data` (8 or 64)."""
        return int(self.data.shape[1])

    @classmethod
    def empty(cls, bus: str, width: int = CLASSIC_WIDTH) -> "FrameBatch":
        """A batch with no frames."""
        return cls.from_columns(bus, np.zeros(0, np.int64), np.zeros(0, np.uint32),
                                np.zeros(0, np.uint8), np.zeros(0, np.uint8),
                                np.zeros((0, width), np.uint8))

    @classmethod
    def from_columns(cls, bus: str, timestamp_ns, arbitration_id, flags, dlc, data) -> "FrameBatch":
        """Build a batch from columns; ``is_extended`` is derived from ``flags``.

        Raises:
            ValueError: when the column lengths differ or ``data`` is not (N, 8|64).
        """
        ts = np.ascontiguousarray(timestamp_ns, dtype=np.int64)
        ids = np.ascontiguousarray(arbitration_id, dtype=np.uint32)
        fl = np.ascontiguousarray(flags, dtype=np.uint8)
        dl = np.ascontiguousarray(dlc, dtype=np.uint8)
        d = np.ascontiguousarray(data, dtype=np.uint8)
        n = ts.shape[0]
        if not (ids.shape == fl.shape == dl.shape == (n,)) or d.ndim != 2 or d.shape[0] != n:
            raise ValueError(
                f"FrameBatch {bus!r}: column lengths differ (timestamps {ts.shape}, ids {ids.shape}, "
                f"flags {fl.shape}, dlc {dl.shape}, data {d.shape})")
        if d.shape[1] not in (CLASSIC_WIDTH, FD_WIDTH):
            raise ValueError(f"FrameBatch {bus!r}: data must have 8 or 64 columns, not {d.shape[1]}")
        return cls(bus, ts, ids, (fl & FLAG_EXTENDED).astype(bool), fl, dl, d)

    @classmethod
    def concat(cls, batches: Sequence["FrameBatch"], bus: str | None = None) -> "FrameBatch":
        """Concatenate batches of one bus in the given order (widening data to 64 if needed)."""
        if not batches:
            return cls.empty(bus or "")
        width = max(b.data_width for b in batches)
        data = [b.data if b.data_width == width else _widen(b.data, width) for b in batches]
        return cls.from_columns(
            bus if bus is not None else batches[0].bus,
            np.concatenate([b.timestamp_ns for b in batches]),
            np.concatenate([b.arbitration_id for b in batches]),
            np.concatenate([b.flags for b in batches]),
            np.concatenate([b.dlc for b in batches]),
            np.concatenate(data),
        )

    def select(self, index) -> "FrameBatch":
        """Frames at ``index`` (slice, boolean mask or integer array) as a new batch."""
        return FrameBatch(self.bus, self.timestamp_ns[index], self.arbitration_id[index],
                          self.is_extended[index], self.flags[index], self.dlc[index], self.data[index])

    def payload_lengths(self) -> np.ndarray:
        """int64 (N,): bytes of payload per frame (0 for remote frames, dlc capped at the width)."""
        n = np.minimum(self.dlc.astype(np.int64), self.data_width)
        n[(self.flags & FLAG_REMOTE) != 0] = 0
        return n

    @classmethod
    def from_messages(cls, bus: str, msgs) -> "FrameBatch":
        """Columns from python-can :class:`can.Message` objects (timestamps in s -> ns).

        A few list comprehensions per batch, no per-frame numpy calls. Payload
        bytes beyond 64 are dropped (impossible on a real bus); a payload
        shorter than the row width is zero-padded; ``dlc`` is kept as given
        (clamped to 0..255).
        """
        if not isinstance(msgs, list):
            msgs = list(msgs)
        n = len(msgs)
        if n == 0:
            return cls.empty(bus)
        ts = np.array([m.timestamp or 0.0 for m in msgs], np.float64)
        ids = np.array([m.arbitration_id & 0xFFFFFFFF for m in msgs], np.uint32)
        fl = _flags_of(msgs)
        dlc = np.clip(np.array([m.dlc for m in msgs], np.int64), 0, 255).astype(np.uint8)
        datas = [m.data or b"" for m in msgs]
        lens = [len(d) for d in datas]
        width = FD_WIDTH if max(lens) > CLASSIC_WIDTH else CLASSIC_WIDTH
        if min(lens) == width == max(lens):
            flat = b"".join(datas)
        else:
            flat = b"".join([bytes(d[:width]).ljust(width, b"\0") for d in datas])
        data = np.frombuffer(flat, np.uint8).reshape(n, width)
        return cls.from_columns(bus, seconds_to_ns(ts), ids, fl, dlc, data)

    def to_messages(self, channel=None):
        """Yield python-can :class:`can.Message` objects (timestamp in float seconds).

        ``channel`` defaults to the bus name. Payload length per frame is
        :meth:`payload_lengths`.
        """
        import can

        ch = self.bus if channel is None else channel
        lengths = self.payload_lengths().tolist()
        ts = ns_to_seconds(self.timestamp_ns).tolist()
        for t, i, f, dlc, n, row in zip(ts, self.arbitration_id.tolist(), self.flags.tolist(),
                                        self.dlc.tolist(), lengths, self.data):
            yield can.Message(
                timestamp=t, arbitration_id=i, is_extended_id=bool(f & FLAG_EXTENDED),
                is_remote_frame=bool(f & FLAG_REMOTE), is_error_frame=bool(f & FLAG_ERROR),
                is_fd=bool(f & FLAG_FD), bitrate_switch=bool(f & FLAG_BRS),
                error_state_indicator=bool(f & FLAG_ESI), is_rx=not (f & FLAG_TX),
                dlc=dlc, data=bytes(row[:n]), channel=ch, check=False)


#: Payload lengths a CAN FD frame can have (ISO 11898-1:2015, DLC codes 0-15).
FD_LENGTHS = (0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64)
#: Largest 11-bit (standard) and 29-bit (extended) identifier (ISO 11898-1).
MAX_STANDARD_ID = 0x7FF
MAX_EXTENDED_ID = 0x1FFFFFFF
#: Timestamps accepted from a file [s since the Unix epoch]: 0 <= t < this (int64 ns end in 2262).
MAX_TIMESTAMP_S = 9.2e9

_FD_LENGTH_OK = np.zeros(65, bool)
_FD_LENGTH_OK[list(FD_LENGTHS)] = True


def checked_batch_from_messages(bus: str, msgs) -> tuple["FrameBatch", np.ndarray, list[str]]:
    """Like :meth:`FrameBatch.from_messages`, but frames that cannot be real CAN frames are left out.

    Vectorised over the messages (a few list comprehensions, then numpy). A
    frame is rejected when (first rule that applies):

    1. its timestamp is not finite or outside ``0 <= t <`` :data:`MAX_TIMESTAMP_S` s;
    2. its identifier is out of range: 11-bit > 0x7FF, 29-bit (or error frame) > 0x1FFFFFFF, negative;
    3. it is a remote frame marked CAN FD (CAN FD has no remote frames);
    4. it is a remote frame with data bytes or a requested length (DLC) above 8;
    5. a classic (non-FD) frame with more than 8 data bytes;
    6. a CAN FD frame whose length is not one of :data:`FD_LENGTHS`;
    7. a data frame whose DLC is not its number of data bytes (python-can's
       ``dlc`` is the payload length in bytes).

    Source: ISO 11898-1:2015 (classic and FD frame formats, DLC -> length table).

    Args:
        bus: bus name of the batch.
        msgs: python-can :class:`can.Message` objects (list, length N).

    Returns:
        ``(batch, bad, reasons)``: :class:`FrameBatch` of the valid frames in
        their order; ``bad`` int64 (K,) indices into ``msgs`` of the rejected
        ones (ascending); ``reasons`` K texts, one per rejected frame.
    """
    if not isinstance(msgs, list):
        msgs = list(msgs)
    n = len(msgs)
    if n == 0:
        return FrameBatch.empty(bus), np.zeros(0, np.int64), []
    ts = np.array([m.timestamp for m in msgs], np.float64)  # None -> nan (rejected)
    idl = [m.arbitration_id for m in msgs]
    if max(idl) > 0xFFFFFFFF or min(idl) < 0:
        idl = [-1 if i < 0 else min(i, 0x100000000) for i in idl]
    ids = np.array(idl, np.int64)
    fl = _flags_of(msgs)
    dll = [m.dlc for m in msgs]
    if max(dll) > 0xFFFF or min(dll) < 0:
        dll = [-1 if d < 0 else min(d, 0x10000) for d in dll]
    dlc = np.array(dll, np.int64)
    datas = [m.data or b"" for m in msgs]
    lens = np.fromiter(map(len, datas), np.int64, n)

    ext = (fl & FLAG_EXTENDED) != 0
    remote = (fl & FLAG_REMOTE) != 0
    err = (fl & FLAG_ERROR) != 0
    fd = (fl & FLAG_FD) != 0
    with np.errstate(invalid="ignore"):
        bad_t = ~(np.isfinite(ts) & (ts >= 0) & (ts < MAX_TIMESTAMP_S))
    bad_id = (ids < 0) | (ids > np.where(ext | err, MAX_EXTENDED_ID, MAX_STANDARD_ID))
    rules = (
        bad_t,
        bad_id,
        remote & fd,
        remote & ((lens > 0) | (dlc > 8) | (dlc < 0)),
        ~fd & (lens > CLASSIC_WIDTH),
        (fd & ~remote & ~_FD_LENGTH_OK[np.minimum(lens, 64)]) | (lens > FD_WIDTH),
        ~remote & ~err & (dlc != lens),
    )
    code = np.zeros(n, np.int8)
    for k in range(len(rules), 0, -1):
        code[rules[k - 1]] = k
    bad = np.flatnonzero(code)
    reasons = []
    for i in bad.tolist():
        k = int(code[i])
        if k == 1:
            reasons.append(f"timestamp {float(ts[i])!r} s is not a time (finite, 0 <= t < {MAX_TIMESTAMP_S:.3g} s)")
        elif k == 2:
            wide = bool(ext[i] or err[i])
            reasons.append(f"identifier 0x{int(ids[i]) & 0x1FFFFFFFF:X} out of range for a "
                           f"{'29' if wide else '11'}-bit id (max 0x{MAX_EXTENDED_ID if wide else MAX_STANDARD_ID:X})")
        elif k == 3:
            reasons.append("remote frame marked CAN FD (CAN FD has no remote frames)")
        elif k == 4:
            reasons.append(f"remote frame with {int(lens[i])} data bytes / requested length {int(dlc[i])} (max 8)")
        elif k == 5:
            reasons.append(f"classic CAN frame with {int(lens[i])} data bytes (at most 8)")
        elif k == 6:
            reasons.append(f"CAN FD frame with {int(lens[i])} data bytes (allowed: 0-8, 12, 16, 20, 24, 32, 48, 64)")
        else:
            reasons.append(f"DLC {int(dlc[i])} but {int(lens[i])} data bytes")
    if bad.size:
        keep = code == 0
        ts, ids, fl, dlc, lens = ts[keep], ids[keep], fl[keep], dlc[keep], lens[keep]
        datas = [d for d, k in zip(datas, keep.tolist()) if k]
        if not datas:
            return FrameBatch.empty(bus), bad, reasons
    m = len(datas)
    width = FD_WIDTH if int(lens.max()) > CLASSIC_WIDTH else CLASSIC_WIDTH
    if int(lens.min()) == width:
        flat = b"".join(datas)
    else:
        flat = b"".join([bytes(d).ljust(width, b"\0") for d in datas])
    data = np.frombuffer(flat, np.uint8).reshape(m, width)
    batch = FrameBatch.from_columns(bus, seconds_to_ns(ts), ids.astype(np.uint32), fl,
                                    np.clip(dlc, 0, 255).astype(np.uint8), data)
    return batch, bad, reasons


def message_flags(m) -> int:
    """The :attr:`FrameBatch.flags` byte of one python-can :class:`can.Message`."""
    return ((FLAG_EXTENDED if m.is_extended_id else 0) | (FLAG_REMOTE if m.is_remote_frame else 0)
            | (FLAG_ERROR if m.is_error_frame else 0) | (FLAG_FD if m.is_fd else 0)
            | (FLAG_BRS if m.bitrate_switch else 0) | (FLAG_ESI if m.error_state_indicator else 0)
            | (0 if m.is_rx else FLAG_TX))


def seconds_to_ns(seconds: np.ndarray) -> np.ndarray:
    """float64 seconds (python-can timestamps) -> int64 ns, exact to the ns of the double.

    Splits into whole seconds and fraction so the product keeps sub-microsecond
    resolution at Unix-epoch magnitudes (a plain ``t*1e9`` is only good to 256 ns).
    """
    seconds = np.asarray(seconds, dtype=np.float64)
    whole = np.floor(seconds)
    frac_ns = np.rint((seconds - whole) * 1e9).astype(np.int64)
    return whole.astype(np.int64) * 1_000_000_000 + frac_ns


def ns_to_seconds(ns: np.ndarray) -> np.ndarray:
    """int64 ns -> float64 seconds, correctly rounded (inverse of :func:`seconds_to_ns`)."""
    ns = np.asarray(ns, dtype=np.int64)
    whole = ns // 1_000_000_000
    return whole.astype(np.float64) + (ns - whole * 1_000_000_000).astype(np.float64) * 1e-9


def _widen(data: np.ndarray, width: int) -> np.ndarray:
    out = np.zeros((data.shape[0], width), np.uint8)
    out[:, : data.shape[1]] = data
    return out


def _flags_of(msgs) -> np.ndarray:
    """Flag bits (uint8, shape (N,)) of a list of python-can messages (extended, remote,
    error, FD, BRS, ESI, and TX for frames not received)."""
    fl = np.zeros(len(msgs), np.uint8)
    for bit, attr in ((FLAG_EXTENDED, "is_extended_id"), (FLAG_REMOTE, "is_remote_frame"),
                      (FLAG_ERROR, "is_error_frame"), (FLAG_FD, "is_fd"), (FLAG_BRS, "bitrate_switch"),
                      (FLAG_ESI, "error_state_indicator")):
        col = [getattr(m, attr) for m in msgs]
        if any(col):
            fl[np.array(col, bool)] |= bit
    rx = [m.is_rx for m in msgs]
    if not all(rx):
        fl[~np.array(rx, bool)] |= FLAG_TX
    return fl


class DuplicateFrames:
    """Drops exact copies of frames: the same bus, timestamp, identifier, flags, DLC and data.

    A frame logged twice (a logger reading one interface twice, a bridge that
    echoes, two recordings merged) is one frame on the bus; kept twice it reads
    as frames arriving at half the cycle time and as repeated counter values.
    Call the instance on each batch in file order; it returns the batch without
    the copies of an earlier frame (the first one is kept) and counts them per
    bus in ``dropped``. Copies are found within a batch and against the last
    :attr:`CARRY` frames of the bus's previous batch (copies logged next to
    each other, as a doubled log has them, across a batch boundary too).
    Batches without two frames at the same timestamp cost one sort.
    """

    #: Frames of a bus's previous batch a copy in the next batch is looked for in.
    CARRY = 64

    def __init__(self):
        self.dropped: dict[str, int] = {}
        self._tail: dict[str, FrameBatch] = {}

    @property
    def total(self) -> int:
        """Copies dropped over all buses."""
        return int(sum(self.dropped.values()))

    def __call__(self, b: FrameBatch) -> FrameBatch:
        """``b`` without exact copies of earlier frames (``b`` itself when it has none)."""
        n = len(b)
        if n == 0:
            return b
        tail = self._tail.get(b.bus)
        both = b if tail is None or len(tail) == 0 else FrameBatch.concat([tail, b], b.bus)
        k = len(both) - n
        self._tail[b.bus] = b.select(slice(max(n - self.CARRY, 0), n))
        dup = _duplicate_mask(both)
        if dup is None or not dup[k:].any():
            return b
        dup = dup[k:]
        self.dropped[b.bus] = self.dropped.get(b.bus, 0) + int(dup.sum())
        return b.select(~dup)


def _duplicate_mask(b: FrameBatch) -> np.ndarray | None:
    """bool (N,): frame i is an exact copy of an earlier frame of ``b`` (None: no two frames share a timestamp)."""
    ts = b.timestamp_ns
    order = np.argsort(ts, kind="stable")
    same = ts[order[1:]] == ts[order[:-1]]
    if not same.any():
        return None
    cand = np.zeros(len(b), bool)
    cand[order[1:][same]] = True
    cand[order[:-1][same]] = True
    idx = np.flatnonzero(cand)
    key = np.concatenate([ts[idx].astype("<i8").view(np.uint8).reshape(-1, 8),
                          b.arbitration_id[idx].astype("<u4").view(np.uint8).reshape(-1, 4),
                          b.flags[idx, None], b.dlc[idx, None], b.data[idx]], axis=1)
    key = np.ascontiguousarray(key).view(np.dtype((np.void, key.shape[1]))).ravel()
    _, first = np.unique(key, return_index=True)
    dup = cand
    dup[idx[first]] = False
    return dup


def duplicate_frames_warning(path, dropped: dict) -> str:
    """The warning for the copies :class:`DuplicateFrames` dropped (``dropped``: bus -> count)."""
    n = int(sum(dropped.values()))
    per = ", ".join(f"{bus}: {k}" for bus, k in sorted(dropped.items()) if k)
    return (f"{path}: frames logged twice: {n} dropped ({per}; exact copies of a frame: same bus, id, flags, "
            "data and timestamp), the first of each kept")
