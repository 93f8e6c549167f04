"""Vectorised DBC decoding of raw CAN frames with numpy.

cantools parses the DBC files (:func:`cantools.database.load_file`); the
per-frame decoding is done here, one numpy expression per signal over all
frames of one message id in a chunk, instead of one Python call per frame.

Bit layout (DBC convention, as in cantools and Vector's DBC specification):

* Intel (``@1``, ``little_endian``): the start bit is the signal's least
  significant bit, bit ``8*byte + bit_in_byte``. With the first 8 payload bytes
  read as one little-endian ``uint64`` word ``le``: ``raw = (le >> start) & mask``.
* Motorola (``@0``, ``big_endian``): the start bit is the signal's most
  significant bit in the same "sawtooth" numbering. Its network (MSB-first)
  position is ``8*(start//8) + 7 - start%8``; with the payload read as a
  big-endian ``uint64`` word ``be``: ``raw = (be >> (64 - msb_net - length)) & mask``.
* CAN FD payloads longer than 8 bytes are decoded by a byte gather (each of the
  at most 9 bytes covering the signal shifted into place).
* Signed integers: two's complement of ``length`` bits. IEEE float signals
  (``SIG_VALTYPE_`` 1/2): the raw 32/64 bits reinterpreted.
* Physical value ``raw * scale + offset`` (exactly as cantools computes it,
  integer arithmetic when scale and offset are integers).
* Multiplexed messages: a multiplexed signal is NaN in every frame whose
  multiplexer value is not one of its ``multiplexer_ids`` (nested multiplexing
  included). Signals reaching past the frame's data length are NaN
  (cantools would raise or drop them).

Remote and error frames are skipped. 11-bit and 29-bit identifiers are told
apart by the frame's ``is_extended`` flag and cantools' ``is_extended_frame``.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from wheelsoil.daq.frames import FrameBatch

__all__ = [
    "DecodedMessage",
    "Decoder",
    "decode_batches",
    "load_databases",
    "frame_key",
]

_U64_ALL = np.uint64(0xFFFF_FFFF_FFFF_FFFF)
_FLAG_REMOTE = 0x02
_FLAG_ERROR = 0x04


def frame_key(frame_id: int | np.ndarray, is_extended: bool | np.ndarray) -> Any:
    """One integer key per identifier: ``frame_id | is_extended << 31``.

    Separates an 11-bit id from the 29-bit id with the same number. Works on
    scalars and on ``(N,)`` arrays (returns ``uint32``).
    """
    if isinstance(frame_id, np.ndarray):
        return frame_id.astype(np.uint32) | (np.asarray(is_extended, dtype=np.uint32) << np.uint32(31))
    return int(frame_id) | (int(bool(is_extended)) << 31)


@dataclass
class DecodedMessage:
    """All decoded frames of one message on one bus.

    Attributes: ``bus``, ``name``, ``frame_id``, ``is_extended``;
    ``timestamp_ns`` int64 (N,) host receive times; ``signals`` maps each
    decoded signal name to a float64 (N,) array of physical values (NaN where
    the signal is absent: other multiplexer value or too short a frame).
    """

    bus: str
    name: str
    frame_id: int
    is_extended: bool
    timestamp_ns: np.ndarray
    signals: dict[str, np.ndarray] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.timestamp_ns.shape[0])


@dataclass
class _SignalPlan:
    name: str
    byte_order: str
    start: int
    length: int
    signed: bool
    float_bits: int  # 0 for integers, 32 or 64 for IEEE floats
    scale: Any
    offset: Any
    int_scaling: bool  # scale and offset both integers -> exact integer arithmetic
    min_bytes: int  # payload bytes the signal needs
    shift: int  # for the uint64 path
    mask: np.uint64
    gather: list[tuple[int, int]]  # (byte index, left shift (negative = right)) for FD
    mux_signal: str | None
    mux_ids: np.ndarray | None


def _signal_plan(sig: Any, message_length: int) -> _SignalPlan:
    length = int(sig.length)
    start = int(sig.start)
    if not 1 <= length <= 64:
        raise ValueError(f"signal {sig.name}: length {length} outside 1..64 bits")
    mask = _U64_ALL if length == 64 else np.uint64((1 << length) - 1)
    gather: list[tuple[int, int]] = []
    if sig.byte_order == "little_endian":
        lsb, msb = start, start + length - 1
        min_bytes = msb // 8 + 1
        shift = lsb
        for b in range(lsb // 8, msb // 8 + 1):
            gather.append((b, 8 * b - lsb))
    else:
        msb_net = 8 * (start // 8) + 7 - start % 8
        lsb_net = msb_net + length - 1
        min_bytes = lsb_net // 8 + 1
        shift = 64 - msb_net - length
        for b in range(msb_net // 8, lsb_net // 8 + 1):
            gather.append((b, lsb_net - (8 * b + 7)))
    if min_bytes > max(message_length, 8):
        raise ValueError(f"signal {sig.name}: bits reach byte {min_bytes - 1}, past the {message_length}-byte frame")
    conv = sig.conversion
    is_float = bool(conv.is_float)
    if is_float and length not in (32, 64):
        raise ValueError(f"signal {sig.name}: float signals must be 32 or 64 bits, not {length}")
    scale, offset = conv.scale, conv.offset
    int_scaling = isinstance(scale, int) and isinstance(offset, int) and not is_float
    mux_ids = None
    if sig.multiplexer_ids:
        mux_ids = np.array(sorted(sig.multiplexer_ids), dtype=np.float64)
    return _SignalPlan(
        name=sig.name, byte_order=sig.byte_order, start=start, length=length,
        signed=bool(sig.is_signed), float_bits=length if is_float else 0,
        scale=scale, offset=offset, int_scaling=int_scaling, min_bytes=min_bytes,
        shift=shift, mask=mask, gather=gather,
        mux_signal=sig.multiplexer_signal, mux_ids=mux_ids,
    )


class _MessagePlan:
    """Compiled decoding plan of one cantools message (built once)."""

    def __init__(self, message: Any, signal_names: Iterable[str] | None = None):
        self.message = message
        self.name: str = message.name
        self.frame_id: int = int(message.frame_id)
        self.is_extended: bool = bool(message.is_extended_frame)
        self.key = frame_key(self.frame_id, self.is_extended)
        self.length = int(message.length)
        by_name = {s.name: s for s in message.signals}
        wanted = set(by_name) if signal_names is None else set(signal_names)
        unknown = wanted - set(by_name)
        if unknown:
            raise ValueError(f"message {self.name}: no signal(s) {sorted(unknown)} in the DBC")
        # the multiplexers a wanted signal depends on are decoded as well
        todo = list(wanted)
        while todo:
            mux = by_name[todo.pop()].multiplexer_signal
            if mux is not None and mux not in wanted:
                wanted.add(mux)
                todo.append(mux)
        self.wanted = wanted

        def depth(sig: Any) -> int:
            d = 0
            while sig.multiplexer_signal is not None:
                sig = by_name[sig.multiplexer_signal]
                d += 1
            return d

        ordered = sorted((s for s in message.signals if s.name in wanted), key=depth)
        self.signals = [_signal_plan(s, self.length) for s in ordered]
        self.wide = self.length > 8
        self.needs_be = any(p.byte_order == "big_endian" for p in self.signals)

    # -- decoding ---------------------------------------------------------------
    def decode(self, data: np.ndarray | None, nbytes: np.ndarray, words: np.ndarray | None = None
               ) -> dict[str, np.ndarray]:
        """Decode ``n`` frames of this message.

        ``data`` (n, W) uint8 payloads (needed for messages longer than 8
        bytes), ``nbytes`` (n,) payload lengths, ``words`` optional (n,)
        uint64: the first 8 payload bytes read little-endian (computed from
        ``data`` when None). Returns signal name -> float64 (n,) physical
        values, NaN where absent.
        """
        n = nbytes.shape[0]
        le = be = None
        if not self.wide:
            if words is not None:
                le = words
            elif data.shape[1] == 8 and data.flags.c_contiguous:
                le = data.view("<u8").reshape(n)
            else:
                le = np.ascontiguousarray(data[:, :8]).view("<u8").reshape(n)
            if self.needs_be:
                be = le.byteswap()
        full = bool(n == 0 or nbytes.min() >= self.length)
        out: dict[str, np.ndarray] = {}
        for p in self.signals:
            if le is not None:
                word = le if p.byte_order == "little_endian" else be
                raw = word >> np.uint64(p.shift) if p.shift else word
                if p.length < 64:
                    raw = raw & p.mask if raw is word else np.bitwise_and(raw, p.mask, out=raw)
            else:
                raw = self._gather(data, p)
            with np.errstate(all="ignore"):  # NaN/inf payloads of float signals
                value = self._physical(raw, p)
            present = None
            if not full and p.min_bytes > 0:
                present = nbytes >= p.min_bytes
            if p.mux_signal is not None:
                mux_val = out[p.mux_signal]
                sel = np.isin(np.trunc(mux_val), p.mux_ids)
                present = sel if present is None else (present & sel)
            if present is not None and not present.all():
                value = np.where(present, value, np.nan)
            out[p.name] = value
        return out

    @staticmethod
    def _gather(data: np.ndarray, p: _SignalPlan) -> np.ndarray:
        raw = np.zeros(data.shape[0], dtype=np.uint64)
        width = data.shape[1]
        for b, sh in p.gather:
            if b >= width:
                continue
            col = data[:, b].astype(np.uint64)
            raw |= (col << np.uint64(sh)) if sh >= 0 else (col >> np.uint64(-sh))
        if p.length < 64:
            raw &= p.mask
        return raw

    @staticmethod
    def _physical(raw: np.ndarray, p: _SignalPlan) -> np.ndarray:
        if p.float_bits == 32:
            return raw.astype(np.uint32).view(np.float32).astype(np.float64) * p.scale + p.offset
        if p.float_bits == 64:
            return raw.view(np.float64) * p.scale + p.offset
        if p.signed:
            if p.length == 64:
                ival = raw.view(np.int64)
            else:
                sb = np.int64(1 << (p.length - 1))
                ival = (raw.astype(np.int64) ^ sb) - sb
        else:
            ival = raw
        if p.int_scaling:  # cantools computes an exact Python int, then we round once
            if p.scale == 1 and p.offset == 0:
                return ival.astype(np.float64)
            bits = p.length + abs(p.scale).bit_length() + 1
            if bits <= 62 and abs(p.offset) < 2**61:
                return (ival.astype(np.int64) * p.scale + p.offset).astype(np.float64)
            exact = ival.astype(object) * p.scale + p.offset  # rare: > 62-bit products
            return np.array([float(v) for v in exact], dtype=np.float64)
        value = ival.astype(np.float64)
        if p.scale != 1:
            value *= p.scale
        if p.offset != 0:
            value += p.offset
        return value


def load_databases(dbcs: Any) -> dict[str, list[Any]]:
    """Normalise DBC input to ``{bus: [cantools Database, ...]}``.

    ``dbcs`` may be one cantools ``Database`` or DBC path (used for every bus,
    key ``"*"``), or a mapping bus name -> Database / path / sequence of them
    (e.g. ``VehicleConfig.buses``). Raises ``OSError``/``ValueError`` naming
    the DBC file that cannot be read or parsed.
    """
    import cantools

    def load_one(item: Any) -> Any:
        if isinstance(item, (str, PathLike)):
            path = Path(item)
            try:
                return cantools.database.load_file(str(path), strict=False)
            except OSError as exc:
                raise OSError(f"cannot read DBC file {path}: {exc}") from exc
            except Exception as exc:  # cantools raises its own parse errors
                raise ValueError(f"cannot parse DBC file {path}: {exc}") from exc
        return item

    def load_many(items: Any) -> list[Any]:
        if isinstance(items, (str, PathLike)) or hasattr(items, "messages"):
            return [load_one(items)]
        return [load_one(i) for i in items]

    if isinstance(dbcs, Mapping):
        return {str(bus): load_many(v) for bus, v in dbcs.items()}
    return {"*": load_many(dbcs)}


class Decoder:
    """Compiled decoder for the messages of some DBC databases.

    ``Decoder(dbcs, select=None)``: ``dbcs`` as for :func:`load_databases`;
    ``select`` optionally restricts decoding to ``{message name: [signal
    names]}`` (``None`` as the list = all signals of that message); messages
    not named are skipped, which saves time and memory.

    :meth:`decode_batch` decodes one frame batch (duck-typed
    ``wheelsoil.daq.FrameBatch``: ``bus``, ``timestamp_ns`` (N,),
    ``arbitration_id`` (N,), ``is_extended`` (N,), ``flags`` (N,), ``dlc``
    (N,), ``data`` (N, 8|64) uint8) into ``{message name: (timestamp_ns,
    {signal: values})}``. Raises ``ValueError`` for unknown selected names.
    """

    def __init__(self, dbcs: Any, select: Mapping[str, Iterable[str] | None] | None = None):
        self.databases = load_databases(dbcs)
        self._plans: dict[str, dict[int, _MessagePlan]] = {}
        self._sorted: dict[str, tuple[np.ndarray, list[_MessagePlan]]] = {}
        found: set[str] = set()
        for bus, dbs in self.databases.items():
            plans: dict[int, _MessagePlan] = {}
            for db in dbs:
                for msg in db.messages:
                    if select is not None and msg.name not in select:
                        continue
                    plan = _MessagePlan(msg, None if select is None else select[msg.name])
                    plans.setdefault(plan.key, plan)
                    found.add(msg.name)
            self._plans[bus] = plans
        if select is not None:
            missing = set(select) - found
            if missing:
                raise ValueError(f"message(s) {sorted(missing)} not found in any DBC")

    def plans_for(self, bus: str) -> dict[int, _MessagePlan]:
        """The compiled message plans used for ``bus`` (``"*"`` as fallback)."""
        if bus in self._plans:
            return self._plans[bus]
        return self._plans.get("*", {})

    def decode_batch(self, batch: Any) -> dict[str, tuple[np.ndarray, dict[str, np.ndarray]]]:
        """Decode one frame batch; see the class docstring for shapes.

        The frames are grouped by message with one stable sort of small
        integer codes (frame order within a message is kept), so every
        message's payloads, timestamps and lengths are contiguous slices.
        """
        plans = self.plans_for(batch.bus)
        n = len(batch.timestamp_ns)
        if not plans or n == 0:
            return {}
        cached = self._sorted.get(batch.bus)
        if cached is None:
            keys_sorted = np.array(sorted(plans), dtype=np.uint32)
            cached = self._sorted[batch.bus] = (keys_sorted, [plans[int(k)] for k in keys_sorted])
        keys_sorted, plan_list = cached
        keys = frame_key(np.asarray(batch.arbitration_id), np.asarray(batch.is_extended))
        pos = np.searchsorted(keys_sorted, keys)
        np.minimum(pos, keys_sorted.shape[0] - 1, out=pos)
        known = keys_sorted[pos] == keys
        flags = np.asarray(batch.flags)
        if flags.any():  # drop remote and error frames
            known &= (flags & (_FLAG_REMOTE | _FLAG_ERROR)) == 0
        codes = np.where(known, pos, keys_sorted.shape[0]).astype(np.uint8 if len(plan_list) < 255 else np.uint32)
        order = np.argsort(codes, kind="stable")
        bounds = np.concatenate([[0], np.cumsum(np.bincount(codes, minlength=len(plan_list) + 1))])
        data = np.asarray(batch.data)
        ts = np.asarray(batch.timestamp_ns)[order]
        dlc = np.asarray(batch.dlc)[order]  # payload length in bytes (python-can's ``dlc``)
        if data.shape[1] == 8 and data.flags.c_contiguous:
            words = data.view("<u8").reshape(n)[order]
            rows = None
        else:
            rows = data[order]
            words = np.ascontiguousarray(rows[:, :8]).view("<u8").reshape(n)
        result = {}
        for k, plan in enumerate(plan_list):
            a, b = int(bounds[k]), int(bounds[k + 1])
            if a == b:
                continue
            payload = None
            if plan.wide:
                if rows is None:
                    rows = data[order]
                payload = rows[a:b]
            result[plan.name] = (ts[a:b], plan.decode(payload, dlc[a:b], words[a:b]))
        return result


class _Accumulator:
    """Collects decoded chunks of one message; concatenates one array at a time."""

    def __init__(self, bus: str, plan: _MessagePlan):
        self.bus, self.plan = bus, plan
        self.ts: list[np.ndarray] = []
        self.cols: dict[str, list[np.ndarray]] = {p.name: [] for p in plan.signals}

    def add(self, ts: np.ndarray, values: dict[str, np.ndarray]) -> None:
        self.ts.append(ts)
        for name, arr in values.items():
            self.cols[name].append(arr)

    def finish(self) -> DecodedMessage:
        def cat(chunks: list[np.ndarray], dtype: Any) -> np.ndarray:
            if not chunks:
                return np.empty(0, dtype=dtype)
            out = np.concatenate(chunks) if len(chunks) > 1 else chunks[0]
            chunks.clear()  # free the pieces before the next column
            return out

        ts = cat(self.ts, np.int64)
        signals = {name: cat(chunks, np.float64) for name, chunks in self.cols.items()}
        p = self.plan
        return DecodedMessage(self.bus, p.name, p.frame_id, p.is_extended, ts, signals)


#: Frames per bus gathered from small batches before one vectorised decode call.
CHUNK_FRAMES = 1 << 16


class _ChunkBuffer:
    """Preallocated column buffers of one bus, filled batch by batch and reused."""

    def __init__(self, bus: str, capacity: int, width: int):
        self.bus, self.n, self.width = bus, 0, width
        self.ts = np.empty(capacity, np.int64)
        self.ids = np.empty(capacity, np.uint32)
        self.ext = np.empty(capacity, bool)
        self.flags = np.empty(capacity, np.uint8)
        self.dlc = np.empty(capacity, np.uint8)
        self.data = np.zeros((capacity, width), np.uint8)

    def fits(self, k: int, width: int) -> bool:
        return self.n + k <= self.ts.shape[0] and width <= self.width

    def add(self, b: Any) -> None:
        a, k = self.n, len(b.timestamp_ns)
        self.ts[a:a + k] = b.timestamp_ns
        self.ids[a:a + k] = b.arbitration_id
        self.ext[a:a + k] = b.is_extended
        self.flags[a:a + k] = b.flags
        self.dlc[a:a + k] = b.dlc
        d = np.asarray(b.data)
        self.data[a:a + k, : d.shape[1]] = d
        if d.shape[1] < self.width:
            self.data[a:a + k, d.shape[1]:] = 0
        self.n = a + k

    def take(self) -> FrameBatch:
        """The frames gathered so far as views (valid until the next :meth:`add`)."""
        n, self.n = self.n, 0
        return FrameBatch(self.bus, self.ts[:n], self.ids[:n], self.ext[:n], self.flags[:n], self.dlc[:n],
                      self.data[:n])


def iter_chunks(batches: Iterable[Any], chunk_frames: int = CHUNK_FRAMES) -> Iterator[Any]:
    """Regroup a stream of batches into chunks of about ``chunk_frames`` frames per bus.

    Recordings hold batches of up to 2000 frames (the logger cuts them every
    100 ms, often much smaller); decoding is much faster on large chunks.
    Frames are copied into one reused buffer per bus (no allocation per
    batch); a yielded chunk is a view, valid until the next one is requested.
    Frame order per bus is kept; batches of at least ``chunk_frames`` frames
    pass through unchanged.
    """
    bufs: dict[str, _ChunkBuffer] = {}
    for b in batches:
        k = len(b.timestamp_ns)
        if k == 0:
            continue
        width = int(np.shape(b.data)[1])
        buf = bufs.get(b.bus)
        if buf is not None and not buf.fits(k, width):
            if buf.n:
                yield buf.take()
            if not buf.fits(k, width):
                buf = None
        if buf is None:
            if k >= chunk_frames:
                yield b
                continue
            buf = bufs[b.bus] = _ChunkBuffer(b.bus, chunk_frames, max(width, bufs[b.bus].width if b.bus in bufs else 0))
        buf.add(b)
    for buf in bufs.values():
        if buf.n:
            yield buf.take()


def decode_batches(
    batches: Iterable[Any],
    dbcs: Any,
    *,
    select: Mapping[str, Iterable[str] | None] | None = None,
    chunk_frames: int = CHUNK_FRAMES,
) -> dict[str, DecodedMessage]:
    """Decode a stream of frame batches into per-message signal arrays.

    Parameters: ``batches`` an iterable of ``FrameBatch`` (e.g.
    ``wheelsoil.daq.iter_frame_batches(path)``), consumed chunk by chunk
    (regrouped to about ``chunk_frames`` frames per bus) so memory does not
    grow beyond the output arrays plus one chunk per bus; ``dbcs`` one
    DBC/Database for all buses or ``{bus: [DBC paths or Databases]}``
    (``VehicleConfig.buses``), or a :class:`Decoder` built beforehand;
    ``select`` optional ``{message: [signals] | None}`` restriction.

    Returns ``{message name: DecodedMessage}`` (a message name seen on two
    buses is keyed ``"bus/name"`` for the second bus). Each ``DecodedMessage``
    holds ``timestamp_ns`` int64 (N,) and float64 (N,) physical values per
    signal, in the order the frames were stored. Messages never seen are
    absent. Source: DBC bit layout as documented in this module.
    """
    decoder = dbcs if isinstance(dbcs, Decoder) else Decoder(dbcs, select=select)
    acc: dict[tuple[str, str], _Accumulator] = {}
    for chunk in iter_chunks(batches, chunk_frames):
        plans = decoder.plans_for(chunk.bus)
        for name, (ts, values) in decoder.decode_batch(chunk).items():
            key = (chunk.bus, name)
            if key not in acc:
                plan = next(p for p in plans.values() if p.name == name)
                acc[key] = _Accumulator(chunk.bus, plan)
            acc[key].add(ts, values)
    out: dict[str, DecodedMessage] = {}
    for (bus, name), a in acc.items():
        out[name if name not in out else f"{bus}/{name}"] = a.finish()
    return out


def iter_decoded(batches: Iterable[Any], decoder: Decoder) -> Iterator[tuple[str, str, np.ndarray, dict[str, np.ndarray]]]:
    """Yield ``(bus, message, timestamp_ns (n,), {signal: (n,) float64})`` per batch and message."""
    for batch in batches:
        for name, (ts, values) in decoder.decode_batch(batch).items():
            yield batch.bus, name, ts, values

