"""Import other loggers' files into MCAP, export MCAP to them, recover damaged MCAP.

Formats through python-can's readers/writers: candump ``-L`` ``.log``,
Vector ``.asc`` and ``.blf``, PEAK ``.trc``.

Channel <-> bus names: python-can numbers channels from 0 (ASC/BLF/TRC
channel 1 is python-can channel 0), so channel ``c`` becomes bus ``can<c>``;
a named channel (candump's ``can0``, ``vcan1``) keeps its name. Exporting
writes the bus name as the channel; python-can's ASC/BLF/TRC writers turn
``can<c>`` into file channel ``c+1``. ``channel_map`` overrides both ways.
"""

from __future__ import annotations

import heapq
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

from .frames import FrameBatch
from .recording import MAX_FRAMES_PER_MESSAGE, RecordingWriter, _iter_records, _Records, iter_frame_batches

#: File suffixes import/export understand (python-can's readers/writers).
FORMATS = (".log", ".asc", ".blf", ".trc")


@dataclass
class ConvertResult:
    """Outcome of an import, export or recovery.

    Attributes:
        output: file written.
        frames: bus -> frames written.
        warnings: counted problems, each naming the file and the place.
        skipped: lines/records that could not be parsed or frames not written
            (each kind also in ``warnings``).
        decoded: frames decoded into JSON messages (``wheelsoil decode``).
    """

    output: Path
    frames: dict[str, int] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    skipped: int = 0
    decoded: int = 0

    @property
    def total(self) -> int:
        """Frames written over all buses."""
        return sum(self.frames.values())


def parse_channel_map(items) -> dict[str, str]:
    """``["0=can1", "vcan0=can0"]`` -> ``{"0": "can1", "vcan0": "can0"}``.

    Raises:
        ValueError: an item without ``=``.
    """
    out = {}
    for it in items or ():
        if "=" not in it:
            raise ValueError(f"--map {it!r}: expected SOURCE=BUS, e.g. --map 0=can1 or --map vcan0=can0")
        k, v = it.split("=", 1)
        out[k.strip()] = v.strip()
    return out


def default_bus_name(channel) -> str:
    """Bus name for a python-can channel: int/digit ``c`` -> ``can<c>``, None -> ``can0``, names kept."""
    if channel is None:
        return "can0"
    if isinstance(channel, int) or (isinstance(channel, str) and channel.isdigit()):
        return f"can{int(channel)}"
    return str(channel)


class _Lines:
    """Line iterator for python-can's text readers that counts file lines and can
    replay the header lines to a fresh reader after a bad line."""

    def __init__(self, f):
        self._f = f
        self.lineno = 0
        self.header: list[str] = []
        self.in_header = True
        self.replay: list[str] = []
        self.last = ""

    def first_message(self) -> None:
        """Called at the first frame: the header is what came before its line."""
        if self.in_header:
            self.in_header = False
            if self.header:
                self.header.pop()

    def __iter__(self):
        return self

    def __next__(self) -> str:
        if self.replay:
            return self.replay.pop(0)
        line = next(self._f)
        self.lineno += 1
        self.last = line
        if self.in_header:
            self.header.append(line)
            if len(self.header) > 5000:
                self.in_header = False
        return line

    def readline(self) -> str:
        try:
            return next(self)
        except StopIteration:
            return ""

    def close(self) -> None:
        pass


def _reader_class(path: Path):
    """python-can's reader class for the suffix (the table behind :func:`can.LogReader`,
    used directly because the text readers get a line iterator, not a file name)."""
    from can.io.player import MESSAGE_READERS

    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(f"{path}: unknown log format {suffix!r}; import reads {', '.join(FORMATS)}")
    return MESSAGE_READERS[suffix]


def iter_log_messages(path, problems: list[str]):
    """Yield python-can messages of a log file; unparsable lines are skipped.

    Text formats: a line python-can cannot parse is reported in ``problems``
    as ``FILE:LINE: ...`` and reading continues with the next line (the file's
    header lines are replayed to a fresh reader). BLF: damage ends the read
    with a problem entry; every frame before it is kept.

    Raises:
        OSError: unreadable file. ValueError: unknown suffix.
    """
    path = Path(path)
    cls = _reader_class(path)
    suffix = path.suffix.lower()
    kwargs = {"relative_timestamp": False} if suffix == ".asc" else {}
    if suffix == ".blf":
        n = 0
        try:
            with cls(str(path)) as reader:
                for msg in reader:
                    n += 1
                    yield msg
        except (OSError, ValueError, EOFError, IndexError, KeyError, TypeError, AttributeError) as exc:
            problems.append(f"{path}: damaged after frame {n}: {type(exc).__name__}: {exc}; "
                            f"kept the {n} frames before it")
        except Exception as exc:  # struct.error, zlib.error, ...
            problems.append(f"{path}: damaged after frame {n}: {type(exc).__name__}: {exc}; "
                            f"kept the {n} frames before it")
        return
    with open(path, "r", encoding="utf-8", errors="replace", newline=None) as f:
        lines = _Lines(f)
        last_fail = -1
        while True:
            reader = cls(lines, **kwargs)
            try:
                for msg in reader:
                    lines.first_message()
                    yield msg
                return
            except Exception as exc:  # python-can raises ValueError/IndexError/... on a bad line
                bad = lines.lineno
                if bad == last_fail:  # no progress: give up rather than loop
                    problems.append(f"{path}:{bad}: cannot continue after this line: {exc}")
                    return
                last_fail = bad
                if lines.in_header and lines.header:
                    lines.header.pop()
                problems.append(f"{path}:{bad}: skipped unparsable line {lines.last.strip()[:60]!r} "
                                f"({type(exc).__name__}: {exc})")
                lines.replay = list(lines.header)


def _batch(bus: str, msgs: list, text: bool) -> FrameBatch:
    """Frames of an imported file; text formats carry whole microseconds, so the
    float seconds python-can hands over are rounded back to them."""
    b = FrameBatch.from_messages(bus, msgs)
    if text:
        b.timestamp_ns = (b.timestamp_ns + 500) // 1000 * 1000
    return b


def import_log(inputs, output, *, channel_map: Mapping[str, str] | None = None, config=None,
               metadata: Mapping | None = None) -> ConvertResult:
    """Convert candump ``.log``, ``.asc``, ``.blf`` or ``.trc`` files into one MCAP recording.

    Frames keep their file order per bus. Bus names: see the module docstring;
    ``channel_map`` maps a source channel (python-can's value as text, e.g.
    ``"0"`` or ``"vcan0"``) or a default bus name to the bus name to use.

    Args:
        inputs: one path or a list of paths (appended in that order).
        output: ``.mcap`` path.
        config: :class:`VehicleConfig` to attach (None: the shipped default).

    Returns:
        :class:`ConvertResult` with frames per bus and warnings (bad lines with
        file:line; they are skipped, all good frames are kept).

    Raises:
        OSError: unreadable input/unwritable output. ValueError: unknown format.
    """
    from .config import load_vehicle_config

    if isinstance(inputs, (str, Path)):
        inputs = [inputs]
    inputs = [Path(p) for p in inputs]
    for p in inputs:
        _reader_class(p)
        if not p.is_file():
            raise OSError(f"{p}: no such file")
    cmap = dict(channel_map or {})
    config = load_vehicle_config() if config is None else config
    res = ConvertResult(Path(output))
    meta = {"source_files": ", ".join(str(p) for p in inputs), "created_by": "wheelsoil import"}
    meta.update(metadata or {})
    names: dict[object, str] = {}
    with RecordingWriter(output, config=config, metadata=meta, fsync=False) as w:
        for p in inputs:
            trc = p.suffix.lower() == ".trc"
            text = p.suffix.lower() != ".blf"
            pending: dict[str, list] = {}
            problems: list[str] = []
            for msg in iter_log_messages(p, problems):
                ch = msg.channel
                bus = names.get((trc, ch))
                if bus is None:
                    raw = ch
                    if trc and isinstance(ch, int):
                        raw = ch - 1  # python-can's TRC reader keeps the 1-based number
                    dflt = default_bus_name(raw)
                    bus = cmap.get(str(ch), cmap.get(dflt, dflt))
                    names[(trc, ch)] = bus
                lst = pending.setdefault(bus, [])
                lst.append(msg)
                if len(lst) >= MAX_FRAMES_PER_MESSAGE:
                    w.write_batch(_batch(bus, lst, text))
                    pending[bus] = []
            for bus, lst in pending.items():
                if lst:
                    w.write_batch(_batch(bus, lst, text))
            for msg in problems:
                warnings.warn(msg, RuntimeWarning, stacklevel=2)
            res.warnings += problems
            res.skipped += sum(1 for m in problems if "skipped" in m)
        res.frames = dict(w.frame_counts)
        w.summary["import_warnings"] = res.warnings[:100]
    return res


def iter_merged_messages(path, *, channel_map: Mapping[str, str] | None = None, buses=None):
    """python-can messages of a recording, all buses merged by timestamp (per-bus order kept).

    ``msg.channel`` is the bus name, or ``channel_map[bus]``. Streams: one
    pass over the file per bus.
    """
    state = _Records()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for _ in _iter_records(path, state, recover=True, frame_buses=set()):
            pass
    found = [c["metadata"].get("bus") or c["topic"].split("/")[2] for c in state.channels.values()
             if c["topic"].startswith("/can/") and c["topic"].endswith("/frames")]
    if buses is not None:
        found = [b for b in found if b in set(buses)]
    cmap = dict(channel_map or {})

    def per_bus(bus):
        ch = cmap.get(bus, bus)
        for batch in iter_frame_batches(path, buses=[bus]):
            yield from batch.to_messages(channel=ch)

    return heapq.merge(*[per_bus(b) for b in found], key=lambda m: m.timestamp)


def export_recording(path, output, *, channel_map: Mapping[str, str] | None = None, buses=None) -> ConvertResult:
    """Write the raw frames of an MCAP recording to ``.log``/``.asc``/``.blf``/``.trc``
    with python-can's writers (:func:`can.Logger`), all buses merged by time.

    Identifiers, flags, DLC and data are bit-exact; timestamps are written as
    the format allows (candump ``.log``: microseconds, absolute).

    Args:
        channel_map: bus name -> channel written (default: the bus name).
        buses: bus names to export (None: all).

    Raises:
        ValueError: unknown output suffix. OSError: unreadable/unwritable files.
    """
    import can

    out = Path(output)
    if out.suffix.lower() not in FORMATS:
        raise ValueError(f"{out}: unknown output format {out.suffix!r}; export writes {', '.join(FORMATS)}")
    res = ConvertResult(out)
    counts: dict[str, int] = {}
    rev = {v: k for k, v in (channel_map or {}).items()}
    trc = out.suffix.lower() == ".trc"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        with can.Logger(str(out)) as writer:
            for msg in iter_merged_messages(path, channel_map=channel_map, buses=buses):
                if trc and (msg.is_remote_frame or msg.is_error_frame or msg.is_fd):
                    res.skipped += 1  # python-can's TRC writer drops these (with a log line each)
                    continue
                writer.on_message_received(msg)
                bus = rev.get(msg.channel, msg.channel)
                counts[bus] = counts.get(bus, 0) + 1
    res.warnings = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    if res.skipped:
        res.warnings.append(f"{out}: {res.skipped} remote/error/CAN FD frames not written: python-can's "
                            "TRC writer does not support them (use .log, .asc or .blf)")
    res.frames = counts
    return res


def rewrite_recording(path, output, *, on_batch=None, note: tuple[str, dict] | None = None) -> ConvertResult:
    """Copy a recording record by record into a new complete, indexed MCAP file.

    Copies metadata, attachments, frame channels (with their metadata), every
    frame batch of every complete chunk and the logger status records.
    ``on_batch(writer, batch)`` is called after each batch is written (to add
    derived channels); ``note`` = (name, dict) adds a metadata record.

    Raises:
        OSError: unreadable input/unwritable output. RecordingError: not an MCAP file.
        ValueError: output is the input.
    """
    path, output = Path(path), Path(output)
    if output.exists() and path.resolve() == output.resolve():
        raise ValueError(f"{output}: writes a new file; choose another output name than the input")
    state = _Records()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for _ in _iter_records(path, state, recover=True, frame_buses=set(), with_status=True):
            pass
    res = ConvertResult(output, warnings=list(state.warnings))
    w = RecordingWriter(output, config=None, metadata=None, fsync=False, write_facts=False)
    try:
        for name, md in state.metadata.items():
            if name != "wheelsoil.summary":
                w.add_metadata(name, md)
        for name, data in state.attachments.items():
            w.add_attachment(name, "application/toml" if name.endswith(".toml") else "text/x-dbc", data)
        for c in state.channels.values():
            if c["schema"] == "wheelsoil_msgs/msg/CanFrameBatch":
                meta = dict(c["metadata"])
                bus = meta.pop("bus", None) or c["topic"].split("/")[2]
                w.add_bus(bus, **meta)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            for b in iter_frame_batches(path):
                w.write_batch(b)
                if on_batch is not None:
                    on_batch(w, b)
        for st, t in zip(state.statuses, state.status_times):
            w.write_status(st, time_ns=t)
        if note is not None:
            w.add_metadata(note[0], dict(note[1], source_file=str(path), source_complete=str(state.complete),
                                         damage="; ".join(state.warnings) or "none",
                                         damage_json=__import__("json").dumps(getattr(state, "damage", []))))
        if "wheelsoil.summary" in state.metadata:
            w.summary.update(state.metadata["wheelsoil.summary"])
    except BaseException:
        w.abort()  # the temporary file goes; an existing output stays as it was
        raise
    w.close()
    res.frames = dict(w.frame_counts)
    return res


def recover_recording(path, output) -> ConvertResult:
    """Rewrite a damaged/truncated recording into a complete, indexed MCAP file.

    Copies every complete chunk's frames, the status records, metadata and
    attachments (:func:`rewrite_recording`), and adds a ``wheelsoil.recovered``
    metadata record (source, damage found). A file that is not damaged is
    copied the same way.

    Raises:
        OSError: unreadable input/unwritable output. RecordingError: not an MCAP file.
    """
    return rewrite_recording(path, output, note=("wheelsoil.recovered", {}))
