"""Replay a recording onto python-can buses with the recorded timing (like ``canplayer``)."""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Mapping

from .convert import iter_merged_messages


#: A recorded gap between two frames longer than this [s] is not waited for (a host clock that stepped, a
#: logger paused): the replay goes on at once and counts it in ``ReplayResult.gaps_skipped``.
MAX_REPLAY_GAP_S = 10.0
#: Longest single sleep [s]: the stop event is checked at least this often.
_SLEEP_SLICE_S = 0.1


@dataclass
class ReplayResult:
    """Frames sent per recorded bus, send errors retried/given up, wall time [s], recorded gaps longer than
    :data:`MAX_REPLAY_GAP_S` not waited for (``gaps_skipped``, ``gap_skipped_s`` their total [s])."""

    sent: dict[str, int] = field(default_factory=dict)
    send_retries: int = 0
    send_failures: int = 0
    wall_s: float = 0.0
    gaps_skipped: int = 0
    gap_skipped_s: float = 0.0


def map_replay_buses(recorded: list[str], specs) -> dict[str, object]:
    """Which target :class:`BusSpec` each recorded bus goes to.

    A spec named ``NAME=...`` takes recorded bus NAME. Unnamed specs take the
    remaining recorded buses in sorted order; a single unnamed spec takes all
    of them (everything onto one bus, e.g. ``vcan0``). Recorded buses left
    without a target are not replayed.

    Raises:
        ValueError: a named spec for a bus the recording does not have.
    """
    out = {}
    rec = sorted(recorded)
    for s in specs:
        if s.named:
            if s.name not in rec:
                raise ValueError(f"--bus {s.name}=...: the recording has no bus {s.name!r} "
                                 f"(it has {', '.join(rec) or 'none'})")
            out[s.name] = s
    rest = [b for b in rec if b not in out]
    unnamed = [s for s in specs if not s.named]
    if len(unnamed) == 1:
        for b in rest:
            out[b] = unnamed[0]
    else:
        for b, s in zip(rest, unnamed):
            out[b] = s
    return out


def replay_messages(messages, targets: Mapping[str, object], *, speed: float = 1.0,
                    stop_event: threading.Event | None = None,
                    on_progress: Callable[[dict], None] | None = None) -> ReplayResult:
    """Send python-can messages (``msg.channel`` = recorded bus name) to ``targets``
    (recorded bus -> open bus), keeping the recorded gaps divided by ``speed``
    (``speed <= 0``: as fast as possible), except gaps longer than :data:`MAX_REPLAY_GAP_S`,
    which are counted and not waited for. The waits are slept in slices that check
    ``stop_event``. A full transmit queue is retried for up to 1 s per frame, then counted
    as a failure.
    """
    import can

    res = ReplayResult()
    t_wall0 = time.monotonic()
    t_rec0 = t_prev = None
    last_progress = t_wall0
    for msg in messages:
        if stop_event is not None and stop_event.is_set():
            break
        bus = targets.get(msg.channel)
        if bus is None:
            continue
        if speed > 0:
            if t_rec0 is None:
                t_rec0 = t_prev = msg.timestamp
            if msg.timestamp - t_prev > MAX_REPLAY_GAP_S:  # not waited for: the replay's clock skips it
                res.gaps_skipped += 1
                res.gap_skipped_s += msg.timestamp - t_prev
                t_rec0 += msg.timestamp - t_prev
            t_prev = max(t_prev, msg.timestamp)
            delay = (msg.timestamp - t_rec0) / speed - (time.monotonic() - t_wall0)
            while delay > 0.0005 and not (stop_event is not None and stop_event.is_set()):
                time.sleep(min(delay, _SLEEP_SLICE_S))
                delay = (msg.timestamp - t_rec0) / speed - (time.monotonic() - t_wall0)
            if stop_event is not None and stop_event.is_set():
                break
        rec_bus = msg.channel
        msg.channel = None  # python-can's socketcan would send to the interface named here
        deadline = None
        while True:
            try:
                bus.send(msg)
                res.sent[rec_bus] = res.sent.get(rec_bus, 0) + 1
                break
            except (can.CanError, OSError):
                now = time.monotonic()
                deadline = deadline or now + 1.0
                if now > deadline:
                    res.send_failures += 1
                    break
                res.send_retries += 1
                time.sleep(0.0005)
        if on_progress is not None and time.monotonic() - last_progress > 1.0:
            last_progress = time.monotonic()
            on_progress(dict(res.sent))
    res.wall_s = time.monotonic() - t_wall0
    return res


def replay_recording(path, specs, *, speed: float = 1.0, buses=None, stop_event=None,
                     on_progress=None) -> ReplayResult:
    """Replay the frames of an MCAP recording onto the buses of ``specs``
    (``BusSpec`` or ``"[NAME=]INTERFACE:CHANNEL"``, mapped by :func:`map_replay_buses`).

    Raises:
        ValueError: bad spec or mapping. OSError: bus cannot be opened, file unreadable.
    """
    from .buses import BusSpec, open_bus, parse_bus_specs
    from .recording import _iter_records, _Records

    specs = [s if isinstance(s, BusSpec) else parse_bus_specs([s])[0] for s in specs]
    state = _Records()
    for _ in _iter_records(path, state, recover=True, frame_buses=set()):
        pass
    recorded = [c["metadata"].get("bus") or c["topic"].split("/")[2] for c in state.channels.values()
                if c["schema"] == "wheelsoil_msgs/msg/CanFrameBatch"]
    if buses is not None:
        recorded = [b for b in recorded if b in set(buses)]
    mapping = map_replay_buses(recorded, specs)
    if not mapping:
        raise ValueError(f"{path}: no bus to replay (recorded: {', '.join(recorded) or 'none'})")
    opened: dict[int, object] = {}
    targets = {}
    try:
        for rec_bus, spec in mapping.items():
            key = id(spec)
            if key not in opened:
                opened[key] = open_bus(spec)
            targets[rec_bus] = opened[key]
        msgs = iter_merged_messages(path, buses=list(mapping))
        return replay_messages(msgs, targets, speed=speed, stop_event=stop_event, on_progress=on_progress)
    finally:
        for b in opened.values():
            try:
                b.shutdown()
            except Exception:
                pass
