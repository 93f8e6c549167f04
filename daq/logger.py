"""The field logger: python-can buses -> MCAP recording, for hours, surviving power cuts.

One reader thread per bus does nothing but ``bus.recv()`` and a deque append.
The main loop wakes every ``BATCH_INTERVAL_S`` (0.5 s), turns what arrived into one
:class:`~wheelsoil.daq.frames.FrameBatch` per bus (a few list comprehensions,
no per-frame numpy), updates the counters vectorised (lost WFT frames from
Counter gaps, error frames, unknown ids, DLC mismatches) and hands the batch to
:class:`~wheelsoil.daq.recording.RecordingWriter`, which then closes a chunk and
fsyncs: a power cut loses at most the last ~0.6 s (the batch in progress and its
writing). Half-second batches keep MCAP messages large (hundreds of frames), which
makes reading back fast.
Nothing per frame can raise: a frame python-can delivers is recorded as is;
a bad frame only shows up in the counters.
"""

from __future__ import annotations

import collections
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

from .frames import FrameBatch
from .recording import RecordingWriter, numbered_path
from .stats import StatsAccumulator

#: How often the logger hands received frames to the writer (one MCAP message per bus) [s].
BATCH_INTERVAL_S = 0.5


@dataclass
class LogResult:
    """What a logging run did.

    Attributes:
        files: recordings written (several with rotation).
        frames: bus -> frames recorded.
        status: the last status dict (see :meth:`CanLogger.status`).
        stop_reason: ``duration``, ``max_frames``, ``stopped`` (signal/stop()).
    """

    files: list[Path]
    frames: dict[str, int]
    status: dict
    stop_reason: str


class _Reader(threading.Thread):
    """recv() loop of one bus; frames go into a deque drained by the main loop."""

    def __init__(self, name: str, bus, timeout_s: float = 0.1):
        super().__init__(name=f"wheelsoil-rx-{name}", daemon=True)
        self.bus_name = name
        self.bus = bus
        self.queue: collections.deque = collections.deque()
        self.running = True
        self.timeout_s = timeout_s
        self.bus_errors = 0
        self.last_error = ""

    def run(self) -> None:
        recv = self.bus.recv
        append = self.queue.append
        timeout = self.timeout_s
        while self.running:
            try:
                while self.running:
                    msg = recv(timeout)
                    if msg is not None:
                        append(msg)
            except Exception as exc:  # CanError, OSError (adapter gone), driver bugs: count, go on
                self.bus_errors += 1
                self.last_error = f"{type(exc).__name__}: {exc}"
                time.sleep(0.05)
        # on stop, take what the kernel still queues for us, so nothing received is lost
        try:
            for _ in range(1_000_000):
                msg = recv(0)
                if msg is None:
                    break
                append(msg)
        except Exception as exc:
            self.bus_errors += 1
            self.last_error = f"{type(exc).__name__}: {exc}"


class CanLogger:
    """Record python-can buses into MCAP files.

    Args:
        buses: bus name -> open :class:`can.BusABC` (the caller closes them).
        output: ``.mcap`` path. With ``split_minutes`` files are named
            ``<stem>_0001.mcap``, ``<stem>_0002.mcap``, ...
        config: :class:`~wheelsoil.daq.config.VehicleConfig` (attached to the
            file; DBC names, lengths and counters for the statistics).
        split_minutes: start a new file every this many minutes (None: one file).
        metadata: extra recording facts for the ``wheelsoil.recording`` metadata.
        bus_meta: bus name -> channel metadata (interface, channel).
        batch_interval_s: how often received frames are handed to the writer [s].
        flush_interval_s: chunk close + fsync interval of the writer [s].
        status_interval_s: status record/callback interval [s].
        overwrite: replace an existing output file. Default False: a file that
            exists is never touched; the recording goes to the first free
            ``<stem>-001.mcap``, ``-002``... instead (the logger writes straight
            into its file, fsynced every flush, so a power cut keeps what was recorded).
        provenance: the ``recorded`` provenance record
            (:func:`~wheelsoil.daq.provenance.make_provenance`) written to every file
            (None: one made here, adapters from ``bus_meta``).
    """

    def __init__(self, buses: Mapping[str, object], output, *, config=None, split_minutes: float | None = None,
                 metadata: Mapping | None = None, bus_meta: Mapping[str, Mapping] | None = None,
                 batch_interval_s: float = BATCH_INTERVAL_S, flush_interval_s: float = 0.5, status_interval_s: float = 1.0,
                 overwrite: bool = False, provenance: Mapping | None = None):
        if not buses:
            raise ValueError("no bus to log: give at least one --bus INTERFACE:CHANNEL")
        self.buses = dict(buses)
        self.output = Path(output)
        self.config = config
        self.split_s = None if not split_minutes else float(split_minutes) * 60.0
        if self.split_s is not None and self.split_s <= 0:
            raise ValueError("--split-minutes must be > 0")
        self.metadata = dict(metadata or {})
        self.bus_meta = {k: dict(v) for k, v in (bus_meta or {}).items()}
        self.batch_interval_s = batch_interval_s
        self.flush_interval_s = flush_interval_s
        self.status_interval_s = status_interval_s
        self.overwrite = bool(overwrite)
        if provenance is None:  # a library caller: recorded, adapters from the channel metadata
            from .provenance import make_provenance

            adapters = [f"{name}={self.bus_meta[name]['interface']}:{self.bus_meta[name]['channel']}"
                        if {"interface", "channel"} <= set(self.bus_meta.get(name, {})) else name
                        for name in self.buses]
            provenance = make_provenance("recorded", adapters=adapters)
        self.provenance = dict(provenance)
        # a plain flag, not threading.Event: Event.set() from a signal handler can
        # deadlock on the Event's lock when the handler interrupts Event.wait()
        self._stop_requested = False
        self._readers = {name: _Reader(name, bus) for name, bus in self.buses.items()}
        self._stats = StatsAccumulator(config)
        self._writer: RecordingWriter | None = None
        self._files: list[Path] = []
        self._bad_frames = 0
        self._last_error = ""
        self._t0 = 0.0
        self._last_status = {}
        self._prev_counts: dict[str, int] = {}
        self._prev_t = 0.0

    # ------------------------------------------------------------------ control
    def stop(self) -> None:
        """Ask the logger to finish (safe from signal handlers and other threads)."""
        self._stop_requested = True

    def _file_name(self) -> Path:
        if self.split_s is None:
            p = self.output
        else:
            p = self.output.with_name(f"{self.output.stem}_{len(self._files) + 1:04d}{self.output.suffix or '.mcap'}")
        return p if self.overwrite else numbered_path(p)

    def _open_writer(self) -> None:
        meta = dict(self.metadata, file_index=len(self._files) + 1)
        for _attempt in range(100):
            path = self._file_name()
            try:  # written in place (durable every flush), never over a file that exists
                self._writer = RecordingWriter(path, config=self.config, metadata=meta,
                                               flush_interval_s=self.flush_interval_s, atomic=False,
                                               overwrite=self.overwrite, provenance=self.provenance)
                break
            except FileExistsError:  # created meanwhile by someone else: take the next number
                continue
        else:
            raise OSError(f"{self.output}: no free file name to record into")
        for name in self.buses:
            self._writer.add_bus(name, **self.bus_meta.get(name, {}))
        self._files.append(path)

    def _close_writer(self) -> None:
        if self._writer is None:
            return
        st = self.status()
        self._writer.summary.update({
            "lost_frames": self._stats.stats.lost_frames,
            "lost_frames_estimated": self._stats.stats.lost_frames_estimated,
            "rx_dropped": {b: v["rx_dropped"] for b, v in st["buses"].items()},
            "error_frames": self._stats.stats.error_frames,
            "bus_errors": {b: r.bus_errors for b, r in self._readers.items()},
            "bad_frames": self._bad_frames,
            "logger_status": st,
        })
        self._writer.write_status(st)
        self._writer.close()
        self._writer = None

    # ------------------------------------------------------------------ data path
    def _drain(self) -> int:
        """Move what the readers received into the writer; returns frames moved."""
        total = 0
        for name, r in self._readers.items():
            q = r.queue
            n = len(q)
            if not n:
                continue
            pop = q.popleft
            msgs = [pop() for _ in range(n)]
            try:
                batch = FrameBatch.from_messages(name, msgs)
            except Exception:  # one odd object from a driver must not stop the logger
                batch = self._convert_one_by_one(name, msgs)
            self._stats.update(batch)
            self._writer.write_batch(batch)
            total += n
        return total

    def _convert_one_by_one(self, name: str, msgs: list) -> FrameBatch:
        good = []
        for m in msgs:
            try:
                FrameBatch.from_messages(name, [m])
                good.append(m)
            except Exception as exc:
                self._bad_frames += 1
                self._last_error = f"unrecordable frame on {name}: {type(exc).__name__}: {exc}"
        return FrameBatch.from_messages(name, good)

    def status(self) -> dict:
        """Counters since start: per bus frames, fps (since the last status), lost WFT
        frames, error frames, bus errors, kernel rx drops; elapsed time, file, size."""
        now = time.monotonic()
        s = self._stats.stats
        dt = max(now - self._prev_t, 1e-9)
        buses = {}
        lost_by_bus: dict[str, int] = {}
        if self.config is not None:
            names = s.names
            for bus, ids in names.items():
                for name in ids.values():
                    if name in s.lost_frames:
                        lost_by_bus[bus] = lost_by_bus.get(bus, 0) + s.lost_frames[name]
        est_by_bus: dict[str, int] = {}
        for bus, ids in s.names.items():
            for name in ids.values():
                if name in s.lost_frames_estimated:
                    est_by_bus[bus] = est_by_bus.get(bus, 0) + s.lost_frames_estimated[name]
        for name, r in self._readers.items():
            n = s.frames.get(name, 0)
            try:  # None: the interface cannot report drops (udp_multicast, virtual, ...): unknown, not 0
                drops = getattr(r.bus, "rx_dropped", None)
            except Exception:
                drops = None
            buses[name] = {
                "frames": n, "fps": round((n - self._prev_counts.get(name, 0)) / dt, 1),
                "lost_wft_frames": lost_by_bus.get(name, 0),
                "lost_frames_estimated": est_by_bus.get(name, 0),
                "error_frames": s.error_frames.get(name, 0), "bus_errors": r.bus_errors,
                "rx_dropped": None if drops is None else int(drops),
                "unknown_id_frames": sum(s.unknown_ids.get(name, {}).values()),
                "dlc_mismatch_frames": sum(s.dlc_mismatch.get(name, {}).values()),
                "queued": len(r.queue),
            }
            self._prev_counts[name] = n
        self._prev_t = now
        w = self._writer
        errors = [r.last_error for r in self._readers.values() if r.last_error] + \
            ([self._last_error] if self._last_error else [])
        st = {"elapsed_s": round(now - self._t0, 3), "file": str(w.path) if w else "",
              "file_bytes": w.file_size() if w else 0, "files": len(self._files),
              "bad_frames": self._bad_frames, "last_error": errors[-1] if errors else "",
              "buses": buses}
        self._last_status = st
        return st

    def run(self, duration_s: float | None = None, *, max_frames: int | None = None,
            on_status: Callable[[dict], None] | None = None) -> LogResult:
        """Log until ``duration_s`` passed, ``max_frames`` were recorded, or :meth:`stop`.

        Always closes the current file cleanly (summary, footer, fsync) before
        returning, also when interrupted by an exception.

        Raises:
            OSError: the output cannot be written.
        """
        self._t0 = self._prev_t = time.monotonic()
        self._open_writer()
        file_t0 = self._t0
        for r in self._readers.values():
            r.start()
        reason = "stopped"
        next_status = self._t0 + self.status_interval_s
        moved = 0
        try:
            while True:
                time.sleep(self.batch_interval_s)
                now = time.monotonic()
                moved += self._drain()
                self._writer.tick()
                if self._stop_requested:
                    break
                if duration_s is not None and now - self._t0 >= duration_s:
                    reason = "duration"
                    break
                if max_frames is not None and moved >= max_frames:
                    reason = "max_frames"
                    break
                if now >= next_status:
                    next_status = now + self.status_interval_s
                    st = self.status()
                    self._writer.write_status(st)
                    if on_status is not None:
                        on_status(st)
                if self.split_s is not None and now - file_t0 >= self.split_s:
                    self._close_writer()
                    self._open_writer()
                    file_t0 = now
        finally:
            for r in self._readers.values():
                r.running = False
            for r in self._readers.values():
                if r.is_alive():
                    r.join(timeout=2.0)
            if self._writer is not None:
                self._drain()
                final = self.status()
                self._close_writer()
            else:
                final = self._last_status
        return LogResult(files=list(self._files), frames=dict(self._stats.stats.frames), status=final,
                         stop_reason=reason)


def format_status(st: dict) -> str:
    """One status line: ``12.0 s | can0 8801 fr/s lost 0 unk 0 errfr 0 buserr 0 drop ? | ... | 3.40 MB run.mcap``

    (lost: frames missing by counter gaps (WFT) plus those missing by nominal
    cycle time (``+N~``, an estimate); unk: frames with ids not in the bus's DBCs;
    errfr: CAN error frames; buserr: driver/adapter errors; drop: kernel
    receive-queue drops, ``?`` when the interface cannot tell (udp_multicast, virtual))."""
    parts = [f"{st['elapsed_s']:7.1f} s"]
    for name, b in st["buses"].items():
        drop = "?" if b["rx_dropped"] is None else str(b["rx_dropped"])
        est = b.get("lost_frames_estimated") or 0
        parts.append(f"{name} {b['fps']:7.0f} fr/s lost {b['lost_wft_frames']}" + (f"+{est}~" if est else "")
                     + f" unk {b.get('unknown_id_frames', 0)} errfr {b['error_frames']}"
                     f" buserr {b['bus_errors']} drop {drop}")
    parts.append(f"{st['file_bytes'] / 1e6:8.2f} MB {Path(st['file']).name}")
    return " | ".join(parts)


def log_buses(specs, output, *, config=None, duration_s: float | None = None,
              split_minutes: float | None = None, max_frames: int | None = None,
              rcvbuf_bytes: int | None = None, on_status: Callable[[dict], None] | None = None,
              handle_signals: bool = False, metadata: Mapping | None = None, overwrite: bool = False,
              command=None) -> LogResult:
    """Open the buses of ``specs`` (``BusSpec`` or ``"[NAME=]INTERFACE:CHANNEL"``) and log them.

    Every file carries the provenance ``recorded`` with ``adapters`` = the bus
    specs and ``command`` (default: ``sys.argv`` of the wheelsoil CLI). Without
    ``overwrite`` an existing output is kept and a numbered file is used (see
    :class:`CanLogger`).

    With ``handle_signals`` SIGINT and SIGTERM stop the logger cleanly (file
    closed with summary and footer); the previous handlers are restored after.

    Raises:
        ValueError: bad spec. OSError: a bus or the output cannot be opened.
    """
    import signal

    from .buses import DEFAULT_RCVBUF_BYTES, BusSpec, open_bus, parse_bus_specs

    specs = [s for s in specs if isinstance(s, BusSpec)] + \
        parse_bus_specs([s for s in specs if not isinstance(s, BusSpec)])
    buses = {}
    try:
        for s in specs:
            buses[s.name] = open_bus(s, rcvbuf_bytes=rcvbuf_bytes or DEFAULT_RCVBUF_BYTES)
        meta = dict(metadata or {})
        adapters = [f"{s.name}={s.interface}:{s.channel}" for s in specs]
        meta["bus_specs"] = " ".join(adapters)
        from .provenance import make_provenance

        prov = make_provenance("recorded", command=command, adapters=adapters)
        logger = CanLogger(buses, output, config=config, split_minutes=split_minutes, metadata=meta,
                           bus_meta={s.name: {"interface": s.interface, "channel": s.channel} for s in specs},
                           overwrite=overwrite, provenance=prov)
        old = {}
        if handle_signals:
            for sig in (signal.SIGINT, signal.SIGTERM):
                old[sig] = signal.signal(sig, lambda *_: logger.stop())
        try:
            return logger.run(duration_s, max_frames=max_frames, on_status=on_status)
        finally:
            for sig, h in old.items():
                signal.signal(sig, h)
    finally:
        for b in buses.values():
            try:
                b.shutdown()
            except Exception:
                pass
