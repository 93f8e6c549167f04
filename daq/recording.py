"""MCAP recordings of raw CAN frames: writer, fast streaming reader, recovery.

Layout (full description in ``docs/mcap-layout.md``):

- one channel per bus, topic ``/can/<bus>/frames``, schema
  ``wheelsoil_msgs/msg/CanFrameBatch`` (encoding ``ros2msg``), message encoding
  ``cdr``: each MCAP message is a batch of up to 2000 frames of that bus with
  column arrays; ``log_time`` = the first frame's receive time [ns];
- ``/wheelsoil/logger_status`` (JSON): the logger's counters once per second;
- metadata ``wheelsoil.recording`` (start facts) and ``wheelsoil.summary``
  (written on a clean close); attachments ``vehicle.toml`` and the DBC files.

The reader is the non-seeking :class:`mcap.stream_reader.StreamReader`, so a
file cut short by a power loss yields every complete chunk; the writer closes
a chunk and fsyncs on a timer (default every 0.5 s).
"""

from __future__ import annotations

import json
import os
import platform
import socket
import struct
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Iterator, Mapping

import numpy as np

from .provenance import PROVENANCE_RECORD, provenance_to_metadata
from .frames import CLASSIC_WIDTH, FD_WIDTH, FrameBatch

#: ROS 2 message definition of one frame batch (schema encoding ``ros2msg``).
SCHEMA_NAME = "wheelsoil_msgs/msg/CanFrameBatch"
SCHEMA_TEXT = """\
# N raw CAN frames of one bus (wheelsoil, docs/mcap-layout.md). All arrays have N entries
# except data, which has N*data_width bytes (row-major, bytes past the payload are zero).
uint8 data_width        # bytes per frame in data: 8 (classic CAN) or 64 (batch holds CAN FD frames)
uint64[] timestamp_ns   # host (kernel) receive time, ns since the Unix epoch
uint32[] arbitration_id # 11- or 29-bit identifier, no flag bits
uint8[] flags           # bit0 extended id, bit1 remote, bit2 error frame, bit3 FD, bit4 BRS, bit5 ESI, bit6 transmitted
uint8[] dlc             # payload length in bytes (python-can dlc; remote frames: requested length)
uint8[] data            # N*data_width payload bytes
"""
FRAMES_TOPIC = "/can/{bus}/frames"
STATUS_TOPIC = "/wheelsoil/logger_status"
#: Frames per MCAP message at most (a batch is also cut by the logger every 0.5 s).
MAX_FRAMES_PER_MESSAGE = 2000

_CDR_HEADER = b"\x00\x01\x00\x00"  # CDR little-endian, XCDR1 (what ROS 2 writes)
_U32 = struct.Struct("<I")


class RecordingError(ValueError):
    """A recording that cannot be read (names the file and the byte offset)."""


# --------------------------------------------------------------------------- CDR codec
def encode_batch(batch: FrameBatch) -> bytes:
    """Serialise a :class:`FrameBatch` as one ``CanFrameBatch`` CDR message (bytes)."""
    n = len(batch)
    w = batch.data_width
    p1 = (-n) % 4                     # after flags: offset 16 + 13n
    p2 = (-(20 + 14 * n + p1)) % 4    # after dlc
    cnt = _U32.pack(n)
    return b"".join((
        _CDR_HEADER, bytes((w, 0, 0, 0)), cnt,
        batch.timestamp_ns.astype("<u8", copy=False).tobytes(), cnt,
        batch.arbitration_id.astype("<u4", copy=False).tobytes(), cnt,
        batch.flags.tobytes(), b"\0" * p1, cnt,
        batch.dlc.tobytes(), b"\0" * p2, _U32.pack(n * w),
        batch.data.tobytes(),
    ))


def decode_batch(bus: str, buf: bytes) -> FrameBatch:
    """Parse one ``CanFrameBatch`` CDR message (no per-frame Python; arrays are views).

    Raises:
        ValueError: a message whose lengths do not add up.
    """
    if len(buf) < 12 or buf[:2] != _CDR_HEADER[:2]:
        raise ValueError("not a little-endian CDR CanFrameBatch message")
    w = buf[4]
    (n,) = _U32.unpack_from(buf, 8)
    o = 12
    ts = np.frombuffer(buf, "<u8", n, o).view(np.int64)
    o += 8 * n
    n2, = _U32.unpack_from(buf, o)
    ids = np.frombuffer(buf, "<u4", n, o + 4)
    o += 4 + 4 * n
    n3, = _U32.unpack_from(buf, o)
    flags = np.frombuffer(buf, np.uint8, n, o + 4)
    o += 4 + n
    o += (-(o - 4)) % 4
    n4, = _U32.unpack_from(buf, o)
    dlc = np.frombuffer(buf, np.uint8, n, o + 4)
    o += 4 + n
    o += (-(o - 4)) % 4
    m, = _U32.unpack_from(buf, o)
    if w not in (CLASSIC_WIDTH, FD_WIDTH) or not (n == n2 == n3 == n4) or m != n * w \
            or len(buf) < o + 4 + m:
        raise ValueError(f"malformed CanFrameBatch message ({len(buf)} bytes, n={n}, width={w})")
    data = np.frombuffer(buf, np.uint8, m, o + 4).reshape(n, w)
    return FrameBatch(bus, ts, ids, (flags & 1).astype(bool), flags, dlc, data)


# --------------------------------------------------------------------------- writer
def _software_versions() -> dict[str, str]:
    from importlib.metadata import PackageNotFoundError, version

    out = {}
    for pkg in ("wheelsoil", "python-can", "mcap", "numpy"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            out[pkg] = "unknown"
    return out


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path if str(path) else ".", os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


class RecordingWriter:
    """Write raw CAN frames to an MCAP recording (context manager).

    ``RecordingWriter(path, config=cfg, metadata={...})`` writes the header,
    the ``wheelsoil.recording`` metadata (start time, host, software versions,
    vehicle config path, wheel geometry, and ``metadata`` as strings) and
    attaches the vehicle TOML and its DBC files. Frames are added with
    :meth:`write_frames` / :meth:`write_batch`; a chunk is closed and the file
    fsynced whenever ``flush_interval_s`` has passed since the last flush
    (checked on every write and by :meth:`tick`), so a power cut loses at most
    that interval plus what the caller still buffers.

    Args:
        path: output ``.mcap`` file (overwritten).
        config: the :class:`~wheelsoil.daq.config.VehicleConfig` in force
            (None: no attachments, bus names taken as given).
        metadata: extra recording facts (values converted with ``str``).
        flush_interval_s: close the chunk in progress and fsync at least this often [s].
        compression: ``"zstd"`` (default), ``"lz4"`` or ``""``.
        fsync: call ``os.fsync`` after each flush (default True).
        write_facts: write the ``wheelsoil.recording`` metadata (False when
            copying another recording's records, as ``recover`` does).
        provenance: where the frames come from, a record made by
            :func:`wheelsoil.daq.provenance.make_provenance` (recorded,
            imported or simulated); written as ``wheelsoil.provenance``.

    Raises:
        OSError: the file cannot be created.
    """

    def __init__(self, path, *, config=None, metadata: Mapping | None = None,
                 flush_interval_s: float = 0.5, compression: str = "zstd", fsync: bool = True,
                 write_facts: bool = True, provenance: Mapping | None = None):
        from mcap.writer import CompressionType, Writer

        self.path = Path(path)
        self._file = open(self.path, "wb")
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "": CompressionType.NONE}
        self._mcap = Writer(self._file, chunk_size=8 * 1024 * 1024, compression=comp[compression])
        self._mcap.start(profile="", library=f"wheelsoil {_software_versions()['wheelsoil']} (mcap-python)")
        self._schema = self._mcap.register_schema(SCHEMA_NAME, "ros2msg", SCHEMA_TEXT.encode())
        self._status_channel = None
        self._channels: dict[str, int] = {}
        self._bus_meta: dict[str, dict] = {}
        self.config = config
        self.frame_counts: dict[str, int] = {}
        self.summary: dict[str, object] = {}
        self.flush_interval_s = float(flush_interval_s)
        self._fsync = fsync
        self._last_flush = time.monotonic()
        self._seq = 0
        self._closed = False
        self.start_time_ns = time.time_ns()
        facts = {
            "start_time_ns": str(self.start_time_ns),
            "start_time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(self.start_time_ns / 1e9)),
            "host": socket.gethostname(),
            "platform": platform.platform(),
            "layout": "wheelsoil-can-mcap/1",
        }
        facts.update({f"version.{k}": v for k, v in _software_versions().items()})
        if config is not None:
            facts.update({
                "vehicle_config": str(config.source or ""), "vehicle_name": config.name,
                "wheel_radius_m": repr(config.wheel_radius_m), "wheel_width_m": repr(config.wheel_width_m),
                "buses": ",".join(config.buses),
            })
        facts.update({str(k): str(v) for k, v in (metadata or {}).items()})
        if write_facts:
            self.add_metadata("wheelsoil.recording", facts)
        if provenance is not None:
            self.add_metadata(PROVENANCE_RECORD, provenance_to_metadata(provenance))
        if config is not None:
            if config.text:
                self.add_attachment("vehicle.toml", "application/toml", config.text.encode())
            for name, text in config.dbc_texts().items():
                self.add_attachment(f"dbc/{name}", "text/x-dbc", text.encode())
        self.flush()
        if fsync:  # make the new directory entry durable too (a power cut could lose the file)
            _fsync_dir(self.path.parent)

    def add_metadata(self, name: str, data: Mapping) -> None:
        """Add an MCAP metadata record (values converted with ``str``)."""
        self._mcap.add_metadata(name, {str(k): str(v) for k, v in data.items()})

    def add_attachment(self, name: str, media_type: str, data: bytes) -> None:
        """Add an MCAP attachment (log/create time = the writer's start time)."""
        self._mcap.add_attachment(self.start_time_ns, self.start_time_ns, name, media_type, bytes(data))

    # -- channels
    def add_bus(self, bus: str, **meta) -> int:
        """Register the channel of ``bus`` (done implicitly on first write); ``meta``
        (e.g. interface, channel, bitrate) goes into the channel metadata. Returns the channel id."""
        if bus in self._channels:
            return self._channels[bus]
        cmeta = {"bus": bus, "frames": "wheelsoil_msgs/msg/CanFrameBatch"}
        if self.config is not None and bus in self.config.buses:
            cmeta["dbc"] = ",".join(p.name for p in self.config.buses[bus])
        cmeta.update({str(k): str(v) for k, v in meta.items()})
        cid = self._mcap.register_channel(FRAMES_TOPIC.format(bus=bus), "cdr", self._schema, cmeta)
        self._channels[bus] = cid
        self.frame_counts.setdefault(bus, 0)
        return cid

    # -- frames
    def write_frames(self, bus: str, msgs: Iterable) -> int:
        """Append python-can :class:`can.Message` objects received on ``bus``; returns their count."""
        batch = FrameBatch.from_messages(bus, msgs)
        self.write_batch(batch)
        return len(batch)

    def write_batch(self, batch: FrameBatch) -> None:
        """Append a :class:`FrameBatch` (split into MCAP messages of <= 2000 frames).

        Frames must be in receive order within the bus; ``log_time`` of each
        message is its first frame's timestamp (negative times are clamped to 0).
        """
        n = len(batch)
        if n == 0:
            return
        cid = self._channels.get(batch.bus) or self.add_bus(batch.bus)
        for lo in range(0, n, MAX_FRAMES_PER_MESSAGE):
            part = batch if n <= MAX_FRAMES_PER_MESSAGE else batch.select(slice(lo, lo + MAX_FRAMES_PER_MESSAGE))
            t0 = max(int(part.timestamp_ns[0]), 0)
            self._mcap.add_message(cid, log_time=t0, data=encode_batch(part), publish_time=t0,
                                   sequence=self._seq)
            self._seq += 1
        self.frame_counts[batch.bus] += n
        self.tick()

    def write_status(self, status: Mapping, time_ns: int | None = None) -> None:
        """Append one JSON status record (logger counters) on ``/wheelsoil/logger_status``."""
        if self._status_channel is None:
            sid = self._mcap.register_schema(
                "wheelsoil.LoggerStatus", "jsonschema",
                json.dumps({"type": "object", "title": "wheelsoil logger counters since start",
                            "properties": {"buses": {"type": "object"}}}).encode())
            self._status_channel = self._mcap.register_channel(STATUS_TOPIC, "json", sid, {})
        t = time.time_ns() if time_ns is None else int(time_ns)
        self._mcap.add_message(self._status_channel, log_time=t, publish_time=t,
                               data=json.dumps(status, sort_keys=True).encode(), sequence=self._seq)
        self._seq += 1

    # -- other channels
    def add_json_channel(self, topic: str, schema: Mapping, metadata: Mapping | None = None) -> int:
        """Register a JSON channel (schema encoding ``jsonschema``); returns its id."""
        title = str(schema.get("title", topic))
        sid = self._mcap.register_schema(title, "jsonschema", json.dumps(schema).encode())
        return self._mcap.register_channel(topic, "json", sid, {str(k): str(v) for k, v in (metadata or {}).items()})

    def write_json(self, channel_id: int, log_time_ns: int, obj) -> None:
        """Append one JSON message to a channel from :meth:`add_json_channel`."""
        t = max(int(log_time_ns), 0)
        self._mcap.add_message(channel_id, log_time=t, publish_time=t, data=json.dumps(obj).encode(),
                               sequence=self._seq)
        self._seq += 1

    # -- durability
    def tick(self) -> None:
        """Flush (close chunk + fsync) if ``flush_interval_s`` has passed since the last flush."""
        if time.monotonic() - self._last_flush >= self.flush_interval_s:
            self.flush()

    def flush(self) -> None:
        """Close the chunk in progress, write it out and fsync the file."""
        self._mcap.flush()
        if self._fsync:
            os.fsync(self._file.fileno())
        self._last_flush = time.monotonic()

    def file_size(self) -> int:
        """Bytes written to the file so far."""
        return self._file.tell()

    def close(self) -> None:
        """Write the ``wheelsoil.summary`` metadata and the MCAP summary/footer, fsync, close."""
        if self._closed:
            return
        self._closed = True
        try:
            summary = {"end_time_ns": str(time.time_ns()),
                       "frames": json.dumps(self.frame_counts, sort_keys=True)}
            summary.update({str(k): v if isinstance(v, str) else json.dumps(v, sort_keys=True)
                            for k, v in self.summary.items()})
            self._mcap.add_metadata("wheelsoil.summary", summary)
            self._mcap.finish()
            self._file.flush()
            if self._fsync:
                os.fsync(self._file.fileno())
        finally:
            self._file.close()

    def __enter__(self) -> "RecordingWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# --------------------------------------------------------------------------- reader
class _StrictFile:
    """File wrapper: a short read raises EOFError; counts the offset."""

    def __init__(self, f):
        self._f = f
        self.offset = 0

    def read(self, n: int = -1) -> bytes:
        data = self._f.read(n)
        self.offset += len(data)
        if n > 0 and len(data) < n:
            raise EOFError(f"file ends after {self.offset} bytes, inside a record")
        return data


@dataclass
class _Records:
    """What a pass over a recording found besides frames."""

    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    channels: dict[int, dict] = field(default_factory=dict)
    statuses: list[dict] = field(default_factory=list)
    status_times: list[int] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    complete: bool = False
    size: int = 0


def _iter_records(path, state: _Records, *, recover: bool, with_status: bool = False,
                  frame_buses=None) -> Iterator[FrameBatch]:
    """Yield FrameBatches of a recording in file order, filling ``state`` on the way.

    Damage handling: a chunk that does not decompress/parse, or a frame batch
    that does not decode, is skipped with a warning (file, byte offset) and
    reading goes on with the next record; a file that ends inside a record
    (power cut) ends the read with a warning. With ``recover=False`` both raise.
    """
    from mcap.records import Attachment, Channel, Chunk, Footer, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader, breakup_chunk

    path = Path(path)
    schemas: dict[int, Schema] = {}
    frame_channels: dict[int, str] = {}
    status_channels: set[int] = set()
    n_frames = 0

    def damaged(msg: str) -> None:
        if not recover:
            raise RecordingError(msg + "; run 'wheelsoil recover' to rewrite it")
        state.warnings.append(msg)
        warnings.warn(msg, RuntimeWarning, stacklevel=4)

    def handle(rec, where: int):
        """FrameBatch for a frame message, else None (other records update ``state``)."""
        if isinstance(rec, Message):
            bus = frame_channels.get(rec.channel_id)
            if bus is not None:
                if frame_buses is None or bus in frame_buses:
                    try:
                        return decode_batch(bus, rec.data)
                    except ValueError as exc:
                        damaged(f"{path}: frame batch of bus {bus} at log_time {rec.log_time} in the record "
                                f"at byte {where} skipped: {exc}")
            elif with_status and rec.channel_id in status_channels:
                try:
                    state.statuses.append(json.loads(rec.data))
                    state.status_times.append(rec.log_time)
                except ValueError:
                    pass
        elif isinstance(rec, Schema):
            schemas[rec.id] = rec
        elif isinstance(rec, Channel):
            sch = schemas.get(rec.schema_id)
            state.channels[rec.id] = {"topic": rec.topic, "encoding": rec.message_encoding,
                                      "schema": sch.name if sch else "", "metadata": dict(rec.metadata)}
            if sch is not None and sch.name == SCHEMA_NAME:
                frame_channels[rec.id] = rec.metadata.get("bus") or rec.topic.split("/")[2]
            elif rec.topic == STATUS_TOPIC:
                status_channels.add(rec.id)
        elif isinstance(rec, Metadata):
            state.metadata[rec.name] = dict(rec.metadata)
        elif isinstance(rec, Attachment):
            state.attachments[rec.name] = rec.data
        elif isinstance(rec, Footer):
            state.complete = True
        return None

    with open(path, "rb") as raw:
        state.size = os.fstat(raw.fileno()).st_size
        f = _StrictFile(raw)
        good = 0
        try:
            for rec in StreamReader(f, emit_chunks=True, record_size_limit=1 << 31).records:
                if isinstance(rec, Chunk):
                    try:
                        inner = breakup_chunk(rec)
                    except Exception as exc:  # zstd/lz4 errors, struct.error on a damaged chunk
                        damaged(f"{path}: chunk at byte {good} of {state.size} damaged and skipped "
                                f"({type(exc).__name__}: {exc})")
                        inner = ()
                    for r in inner:
                        batch = handle(r, good)
                        if batch is not None:
                            n_frames += len(batch)
                            yield batch
                else:
                    batch = handle(rec, good)
                    if batch is not None:
                        n_frames += len(batch)
                        yield batch
                good = f.offset
        except (GeneratorExit, KeyboardInterrupt, RecordingError):
            raise
        except Exception as exc:  # the file ends inside a record (EOFError), bad framing, ...
            if good == 0 and f.offset <= 8:
                raise RecordingError(f"{path}: not an MCAP file ({type(exc).__name__}: {exc})") from None
            damaged(f"{path}: damaged or truncated at byte {good} of {state.size} "
                    f"({type(exc).__name__}: {exc or 'incomplete record'}); kept the {n_frames} frames before it")


def read_attachments(path) -> dict[str, bytes]:
    """Attachments at the start of a recording (``vehicle.toml``, ``dbc/*``), name -> bytes.

    Reads only up to the first chunk, so it is instant on long files and works
    on truncated ones (the writer puts attachments before any frame).

    Raises:
        OSError: unreadable file. RecordingError: not an MCAP file.
    """
    from mcap.records import Attachment, Chunk, Message
    from mcap.stream_reader import StreamReader

    out: dict[str, bytes] = {}
    with open(path, "rb") as raw:
        f = _StrictFile(raw)
        try:
            for rec in StreamReader(f, emit_chunks=True).records:
                if isinstance(rec, Attachment):
                    out[rec.name] = rec.data
                elif isinstance(rec, (Chunk, Message)):
                    break
        except Exception as exc:
            if f.offset <= 8:
                raise RecordingError(f"{path}: not an MCAP file ({type(exc).__name__}: {exc})") from None
    return out


def iter_frame_batches(path, *, buses=None, recover: bool = True) -> Iterator[FrameBatch]:
    """Stream the raw frames of an MCAP recording, batch by batch.

    Batches come in file order, which is log-time order per bus (batches of
    different buses interleave). Arrays may be read-only views.

    Args:
        path: ``.mcap`` file written by :class:`RecordingWriter` (or any MCAP
            with ``wheelsoil_msgs/msg/CanFrameBatch`` channels).
        buses: bus names to yield (None: all).
        recover: a truncated/damaged file yields every complete chunk, then a
            ``RuntimeWarning`` names the file and byte offset. With False that
            raises :class:`RecordingError` instead.

    Raises:
        OSError: the file cannot be opened.
        RecordingError (a ValueError): not an MCAP file; damaged and ``recover=False``.
    """
    wanted = None if buses is None else set([buses] if isinstance(buses, str) else buses)
    yield from _iter_records(path, _Records(), recover=recover, frame_buses=wanted)


def read_frames(path, *, buses=None, recover: bool = True) -> dict[str, FrameBatch]:
    """All frames of a recording, concatenated per bus: bus name -> :class:`FrameBatch`.

    Same arguments and errors as :func:`iter_frame_batches`.
    """
    parts: dict[str, list[FrameBatch]] = {}
    for b in iter_frame_batches(path, buses=buses, recover=recover):
        parts.setdefault(b.bus, []).append(b)
    return {bus: FrameBatch.concat(bs, bus) for bus, bs in parts.items()}
