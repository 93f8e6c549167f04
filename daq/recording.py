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
import re
import socket
import struct
import time
import warnings
import zlib
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
#: Metadata record the writer keeps up to date with channel id -> bus (outside any chunk).
CHANNELS_RECORD = "wheelsoil.channels"

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

    Files: by default (``atomic=True``) the recording is written to
    ``<path>.tmp-XXXXXXXX`` in the same directory and renamed into place by
    :meth:`close` only; after an exception inside ``with`` (or :meth:`abort`) the
    temporary file is removed and an existing ``path`` is untouched. The field
    logger uses ``atomic=False, overwrite=False``: it writes straight into a
    fresh file that never replaces another (durable every flush).

    Args:
        path: output ``.mcap`` file.
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
        overwrite: an existing ``path`` may be replaced (False: FileExistsError).
        atomic: write a temporary file and rename it on close (see above).
        keep_partial: on failure keep the temporary file as ``<path>.partial``.

    Raises:
        OSError: the file cannot be created; FileExistsError: ``path`` exists and
            ``overwrite`` is False.
    """

    def __init__(self, path, *, config=None, metadata: Mapping | None = None,
                 flush_interval_s: float = 0.5, compression: str = "zstd", fsync: bool = True,
                 write_facts: bool = True, provenance: Mapping | None = None,
                 overwrite: bool = True, atomic: bool = True, keep_partial: bool = False):
        from mcap.writer import CompressionType, Writer

        self.path = Path(path)
        if self.path.exists() and not overwrite:
            raise FileExistsError(f"{self.path}: exists; kept as it is (use --overwrite to replace it)")
        if self.path.is_dir():
            raise IsADirectoryError(f"{self.path}: is a directory")
        self.atomic = bool(atomic)
        self.keep_partial = bool(keep_partial)
        if self.atomic:
            import secrets

            while True:
                tmp = self.path.with_name(f"{self.path.name}.tmp-{secrets.token_hex(4)}")
                try:
                    self._file = open(tmp, "xb")
                    break
                except FileExistsError:
                    continue
            self.tmp_path: Path | None = tmp
        else:
            self._file = open(self.path, "wb" if overwrite else "xb")
            self.tmp_path = None
        try:
            self._start(config, metadata, flush_interval_s, compression, fsync, write_facts, provenance,
                        CompressionType, Writer)
        except BaseException:
            self.abort()
            raise

    def _start(self, config, metadata, flush_interval_s, compression, fsync, write_facts, provenance,
               CompressionType, Writer) -> None:
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
            for name, text in dbc_attachments(config).items():
                self.add_attachment(name, "text/x-dbc", text.encode())
        self.flush()
        if fsync:  # make the new directory entry durable too (a power cut could lose the file)
            _fsync_dir(self.path.parent)

    def add_metadata(self, name: str, data: Mapping) -> None:
        """Add an MCAP metadata record (values converted with ``str``).

        ``wheelsoil.channels`` is the writer's own (channel id -> bus of this file)
        and is not copied from elsewhere."""
        if name == CHANNELS_RECORD:
            return
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
        # the channel record goes into the first chunk; this copy outside any chunk lets a
        # reader go on with the later chunks when that one is damaged
        self._mcap.add_metadata(CHANNELS_RECORD, {str(c): b for b, c in self._channels.items()})
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
        """Write the ``wheelsoil.summary`` metadata and the MCAP summary/footer, fsync, close;
        an atomic writer then renames the temporary file into place (``os.replace``)."""
        if self._closed:
            return
        self._closed = True
        ok = False
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
            ok = True
        finally:
            self._file.close()
            if self.tmp_path is not None:
                if ok:
                    os.replace(self.tmp_path, self.path)
                    if self._fsync:
                        _fsync_dir(self.path.parent)
                else:
                    self._discard_tmp()

    def abort(self) -> None:
        """Give up after a failure: close the file; an atomic writer removes its temporary
        file (or keeps it as ``<path>.partial`` with ``keep_partial``), so an existing
        ``path`` stays as it was. A direct writer (the logger) keeps what it wrote."""
        if getattr(self, "_closed", False):
            return
        self._closed = True
        try:
            if getattr(self, "_mcap", None) is not None and self.tmp_path is None:
                try:  # direct file: make what was written readable to the end
                    self._mcap.finish()
                except Exception:
                    pass
            self._file.close()
        finally:
            if self.tmp_path is not None:
                self._discard_tmp()

    def _discard_tmp(self) -> None:
        try:
            if self.keep_partial:
                os.replace(self.tmp_path, self.path.with_name(self.path.name + ".partial"))
            else:
                os.unlink(self.tmp_path)
        except OSError:
            pass

    def __enter__(self) -> "RecordingWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def dbc_attachments(config) -> dict[str, str]:
    """Attachment name -> DBC text for every DBC file of ``config``.

    A file name used on one bus only (or with the same text on several) is
    stored as ``dbc/<name>``; a file name used on several buses with different
    contents as ``dbc/<bus>/<name>`` for each, so none hides another.
    """
    from .config import read_dbc_text

    cached = getattr(config, "_dbc_texts_by_path", {}) or {}
    per: list[tuple[str, str, str]] = []
    for bus, paths in config.buses.items():
        for p in paths:
            p = Path(p)
            text = cached.get(str(p))
            if text is None:
                try:
                    text = read_dbc_text(p)
                except OSError:
                    text = config.dbc_texts().get(p.name, "")
            per.append((bus, p.name, text))
    texts: dict[str, set] = {}
    for _bus, name, text in per:
        texts.setdefault(name, set()).add(text)
    out: dict[str, str] = {}
    for bus, name, text in per:
        out[f"dbc/{name}" if len(texts[name]) == 1 else f"dbc/{bus}/{name}"] = text
    return out


# --------------------------------------------------------------------------- reader
_MAGIC = b"\x89MCAP0\r\n"
_U64 = struct.Struct("<Q")
_REC_HDR = struct.Struct("<BQ")
_MSG_HDR = struct.Struct("<HIQQ")          # channel id, sequence, log_time, publish_time
_CHUNK_HDR = struct.Struct("<QQQII")       # start, end, uncompressed size, crc, compression length
#: Largest record the reader loads (a chunk, an attachment) [bytes]; a record that claims
#: more is treated as damage (the writer's chunks are ~8 MiB). Bounds memory whatever a file says.
MAX_RECORD_BYTES = 256 * 2**20
#: Largest uncompressed chunk the reader inflates [bytes].
MAX_CHUNK_BYTES = 256 * 2**20
_OP_HEADER = 0x01
_OP_FOOTER, _OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE, _OP_CHUNK, _OP_MSG_INDEX = 0x02, 0x03, 0x04, 0x05, 0x06, 0x07
_OP_ATTACHMENT, _OP_METADATA, _OP_DATA_END = 0x09, 0x0C, 0x0F
_KNOWN_OPS = frozenset(range(0x01, 0x10))
#: What parsing a damaged record can raise (a ValueError subclass covers bad UTF-8).
_PARSE_ERRORS = (ValueError, EOFError, struct.error, IndexError, KeyError, TypeError, OverflowError)
# where a top-level record may start after damage: opcode, then a length < 4 GiB
_RESYNC = re.compile(rb"(?=[\x02\x06\x07\x09\x0c\x0f].{4}\x00\x00\x00\x00)", re.S)
_SCAN_WINDOW = 1 << 20


class _Strict:
    """Read-only stream over bytes: a short read raises EOFError (so a length field that
    claims more than the record holds is an error, never a silent cut or a big allocation)."""

    __slots__ = ("_b", "_o")

    def __init__(self, b):
        self._b = b
        self._o = 0

    def read(self, n: int = -1) -> bytes:
        o = self._o
        if n < 0:
            n = len(self._b) - o
        if o + n > len(self._b):
            raise EOFError(f"field of {n} bytes runs past the record end ({len(self._b) - o} bytes left)")
        self._o = o + n
        return bytes(self._b[o:o + n])


def _parse(cls, body, *args):
    """Parse one mcap record body with the mcap library's own parser, strictly: every
    field within the body, and the fields fill the body exactly.

    Raises:
        EOFError: a field runs past the end. ValueError: bytes left over, bad UTF-8.
    """
    from mcap.data_stream import ReadDataStream

    src = _Strict(body)
    rec = cls.read(ReadDataStream(src), *args)
    if src._o != len(body):
        raise ValueError(f"{cls.__name__} record has {len(body) - src._o} bytes past its fields")
    return rec


def _footer_ok(f, size: int) -> bool:
    """The file ends with a footer record and the magic."""
    tail = 8 + 9 + 20
    if size < 8 + tail:
        return False
    f.seek(size - tail)
    t = f.read(tail)
    return t[-8:] == _MAGIC and t[0] == _OP_FOOTER and _U64.unpack_from(t, 1)[0] == 20


@dataclass
class ReadReport:
    """What a pass over a recording found besides frames (fill one with ``report=``).

    Attributes:
        path: the file read.
        size: its size [bytes].
        footer: the MCAP footer was reached (the writer closed the file).
        complete: footer reached and no damage found: every frame was delivered.
        damage: one dict per damaged place, JSON-ready: ``file``, ``offset`` (byte
            offset of the damaged record), ``kind`` (``crc``: chunk CRC mismatch;
            ``chunk``: chunk does not decompress/parse; ``record``: bad record header
            or size; ``unknown_record``: corrupted record type; ``batch``: a frame
            batch that does not decode; ``channel``: messages of a channel whose
            definition was lost; ``truncated``: the file ends early; ``appended``: a
            second recording joined after the first, not read), ``frames_lost``
            (int, or None = unknown), ``frames_lost_by_bus`` ({bus: int}), ``batches_lost``
            (MCAP messages, None = unknown), ``bytes_skipped``, ``t0_ns``/``t1_ns``
            (log-time span of the lost data where the chunk header gives it, else None)
            and ``message`` (the warning text).
        warnings: the warning texts, each naming the file and the byte offset.
        metadata, attachments, channels, statuses, status_times: records found.
    """

    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    channels: dict[int, dict] = field(default_factory=dict)
    statuses: list[dict] = field(default_factory=list)
    status_times: list[int] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    damage: list[dict] = field(default_factory=list)
    footer: bool = False
    size: int = 0
    path: Path | None = None
    frames: int = 0

    @property
    def complete(self) -> bool:
        """Footer reached and nothing damaged."""
        return self.footer and not self.damage

    @property
    def frames_lost(self) -> int | None:
        """Frames lost to damage over all places (None: at least one place cannot tell)."""
        if any(d["frames_lost"] is None for d in self.damage):
            return None
        return int(sum(d["frames_lost"] for d in self.damage))


_Records = ReadReport  # old private name (convert.py, replay.py)


def _batch_len(data) -> int | None:
    """Frames in a CanFrameBatch message from its header (None if it does not look like one)."""
    try:
        if len(data) < 12 or bytes(data[:2]) != _CDR_HEADER[:2]:
            return None
        w = data[4]
        (n,) = _U32.unpack_from(data, 8)
        if w not in (CLASSIC_WIDTH, FD_WIDTH) or 12 + n * (8 + 4 + 1 + 1 + w) > len(data):
            return None
        return int(n)
    except (struct.error, IndexError, TypeError):
        return None


def _inflate(compression: str, data, usize: int) -> bytes:
    """Decompress a chunk payload into exactly ``usize`` bytes, allocating at most that.

    Raises:
        ValueError: unknown compression, size mismatch or decompression error.
    """
    if usize > MAX_CHUNK_BYTES:
        raise ValueError(f"chunk claims {usize} uncompressed bytes (limit {MAX_CHUNK_BYTES})")
    if compression == "":
        out = bytes(data)
    elif compression == "zstd":
        import zstandard

        try:
            cs = zstandard.get_frame_parameters(data).content_size
        except zstandard.ZstdError as exc:
            raise ValueError(f"zstd: {exc}") from None
        if cs != zstandard.CONTENTSIZE_UNKNOWN and cs != usize:
            raise ValueError(f"zstd frame holds {cs} bytes, the chunk claims {usize}")
        try:
            if cs == usize and usize <= 64 * len(data) + (1 << 20):  # normal: one allocation of the known size
                out = zstandard.ZstdDecompressor().decompress(data)
            else:  # size not in the frame, or a ratio no real chunk has: inflate piecewise, allocating
                # only what really comes out, never more than claimed (+1 to notice)
                import io

                parts, got = [], 0
                with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data)) as r:
                    while got <= usize:
                        piece = r.read(min(1 << 20, usize + 1 - got))
                        if not piece:
                            break
                        parts.append(piece)
                        got += len(piece)
                out = b"".join(parts)
        except zstandard.ZstdError as exc:
            raise ValueError(f"zstd: {exc}") from None
    elif compression == "lz4":
        import lz4.frame

        try:
            info = lz4.frame.get_frame_info(data)
            if info.get("content_size") not in (0, None, usize):
                raise ValueError(f"lz4 frame holds {info['content_size']} bytes, the chunk claims {usize}")
            d = lz4.frame.LZ4FrameDecompressor()
            out = d.decompress(data, max_length=usize + 1)
        except RuntimeError as exc:
            raise ValueError(f"lz4: {exc}") from None
    else:
        raise ValueError(f"unknown chunk compression {compression[:20]!r}")
    if len(out) != usize:
        raise ValueError(f"chunk inflates to {len(out)} bytes, not the {usize} it claims")
    return out


def _parse_chunk(body):
    """Chunk header fields and payload view of a chunk record body.

    Returns (start_ns, end_ns, usize, crc, compression, payload). Raises ValueError.
    """
    if len(body) < _CHUNK_HDR.size:
        raise ValueError("chunk record too short")
    t0, t1, usize, crc, clen = _CHUNK_HDR.unpack_from(body, 0)
    o = _CHUNK_HDR.size
    if clen > 16 or o + clen + 8 > len(body):
        raise ValueError(f"chunk compression name of {clen} bytes")
    comp = bytes(body[o:o + clen]).decode("ascii", "replace")
    o += clen
    (dlen,) = _U64.unpack_from(body, o)
    o += 8
    if dlen > len(body) - o:
        raise ValueError(f"chunk payload claims {dlen} bytes, the record holds {len(body) - o}")
    return t0, t1, usize, crc, comp, memoryview(body)[o:o + dlen]


def _chunk_records(buf) -> list:
    """Records inside an uncompressed chunk: (opcode, record) with messages as
    (channel_id, log_time, data view). Raises ValueError/EOFError on bad framing."""
    from mcap.records import Channel, Schema

    mv = memoryview(buf)
    n = len(buf)
    o = 0
    out = []
    unpack_hdr = _REC_HDR.unpack_from
    unpack_msg = _MSG_HDR.unpack_from
    while o < n:
        if o + 9 > n:
            raise ValueError(f"record header cut at byte {o} of the chunk")
        op, ln = unpack_hdr(buf, o)
        s = o + 9
        e = s + ln
        if e > n:
            raise ValueError(f"record at byte {o} of the chunk claims {ln} bytes, {n - s} left")
        if op == _OP_MESSAGE:
            if ln < 22:
                raise ValueError(f"message record of {ln} bytes")
            cid, _seq, lt, _pt = unpack_msg(buf, s)
            out.append((_OP_MESSAGE, (cid, lt, mv[s + 22:e])))
        elif op == _OP_CHANNEL:
            out.append((op, _parse(Channel, mv[s:e])))
        elif op == _OP_SCHEMA:
            out.append((op, _parse(Schema, mv[s:e])))
        o = e
    return out


def _appended_at(f, start: int, size: int) -> int | None:
    """Byte offset of a second MCAP recording after the one whose data section ends before ``start``
    (files joined end to end, e.g. with ``cat``): the first one's closing magic right before the second's
    opening magic and header record. None if there is none."""
    pat = _MAGIC + _MAGIC + bytes([_OP_HEADER])
    block = 1 << 20
    pos = start
    while pos < size:
        f.seek(pos)
        buf = f.read(block + len(pat) - 1)
        i = buf.find(pat)
        if i >= 0:
            return pos + i + len(_MAGIC)
        pos += block
    return None


def _read_summary_channels(f, size: int) -> tuple[dict, dict]:
    """Schemas and channels repeated in the summary section (if the footer is intact):
    they let the reader go on when the chunk holding a channel's definition is damaged."""
    from mcap.records import Channel, Footer, Schema

    schemas, channels = {}, {}
    tail = 8 + 9 + 20
    if size < 8 + tail:
        return schemas, channels
    try:
        f.seek(size - tail)
        t = f.read(tail)
        if t[-8:] != _MAGIC or t[0] != _OP_FOOTER or _U64.unpack_from(t, 1)[0] != 20:
            return schemas, channels
        foot = _parse(Footer, t[9:29])
        start, end = foot.summary_start, size - tail
        if not 8 < start < end or end - start > MAX_RECORD_BYTES:
            return schemas, channels
        f.seek(start)
        buf = f.read(end - start)
        if foot.summary_crc:
            crc = zlib.crc32(t[:1 + 8 + 16], zlib.crc32(buf))
            if crc != foot.summary_crc:
                return schemas, channels
        o = 0
        while o + 9 <= len(buf):
            op, ln = _REC_HDR.unpack_from(buf, o)
            if o + 9 + ln > len(buf):
                break
            if op == _OP_SCHEMA:
                r = _parse(Schema, buf[o + 9:o + 9 + ln])
                schemas[r.id] = r
            elif op == _OP_CHANNEL:
                r = _parse(Channel, buf[o + 9:o + 9 + ln])
                channels[r.id] = r
            o += 9 + ln
    except (OSError,) + _PARSE_ERRORS:
        pass
    return schemas, channels


def _plausible_record(f, p: int, size: int) -> bool:
    """Does a top-level record that parses exactly start at byte ``p``? (resync after damage)"""
    from mcap.records import Attachment, Metadata

    f.seek(p)
    hdr = f.read(9)
    if len(hdr) < 9:
        return False
    op, ln = _REC_HDR.unpack(hdr)
    if ln > size - p - 9 or ln > MAX_RECORD_BYTES:
        return False
    if op == _OP_DATA_END:
        return ln == 4
    if op == _OP_FOOTER:
        if ln != 20:
            return False
        f.seek(p + 29)
        return f.read(8) == _MAGIC
    if op == _OP_MSG_INDEX:
        if ln < 6:
            return False
        b = f.read(6)
        return len(b) == 6 and _U32.unpack_from(b, 2)[0] == ln - 6 and (ln - 6) % 16 == 0
    body = f.read(ln)
    try:
        if op == _OP_CHUNK:
            t0, t1, usize, crc, comp, payload = _parse_chunk(body)
            return (comp in ("", "zstd", "lz4") and t0 <= t1 and usize <= MAX_CHUNK_BYTES
                    and _CHUNK_HDR.size + len(comp) + 8 + len(payload) == ln)
        if op == _OP_METADATA:
            _parse(Metadata, body)
            return True
        if op == _OP_ATTACHMENT:
            crc = _U32.unpack_from(body, ln - 4)[0]
            _parse(Attachment, body)
            return crc == 0 or crc == zlib.crc32(memoryview(body)[:ln - 4])
    except _PARSE_ERRORS:
        return False
    return False


def _resync(f, start: int, size: int) -> int | None:
    """Offset of the next plausible top-level record at or after ``start`` (None: none)."""
    q = start
    while q < size - 9:
        f.seek(q)
        win = f.read(_SCAN_WINDOW)
        if not win:
            break
        for m in _RESYNC.finditer(win):
            p = q + m.start()
            if _plausible_record(f, p, size):
                return p
        q += max(len(win) - 16, 1)
    return None


def _iter_records(path, state: ReadReport, *, recover: bool, with_status: bool = False,
                  frame_buses=None) -> Iterator[FrameBatch]:
    """Yield FrameBatches of a recording in file order, filling ``state`` on the way.

    Every chunk is inflated into at most its claimed size (bounded by
    :data:`MAX_CHUNK_BYTES`) and its CRC (``uncompressed_crc``, 0 = not set) is
    checked before any of its frames is yielded; attachments' CRCs likewise.
    Record sizes are checked against the file size and :data:`MAX_RECORD_BYTES`
    before anything is read. Damage handling: a chunk that fails its CRC, does
    not decompress or parse, a record with a bad header (reading resumes at the
    next record that parses), a corrupted record type, a frame batch that does
    not decode: skipped, with a warning (file, byte offset, frames lost: from the
    batch headers where they are readable, else from the message index / unknown)
    and an entry in ``state.damage``; a file that ends inside a record (power
    cut) ends the read with a warning. With ``recover=False`` damage raises.
    """
    from mcap.records import Attachment, Channel, Header, Metadata, Schema

    path = Path(path)
    state.path = path
    size = 0
    schemas: dict[int, object] = {}
    frame_channels: dict[int, str] = {}
    status_channels: set[int] = set()
    backup_channels: dict[int, str] = {}     # from wheelsoil.channels metadata / the summary section
    backup_schemas: dict[int, object] = {}   # from the summary section
    orphan: dict[int, dict] = {}             # channel id -> damage entry of messages without a channel
    last_chunk_damage: list = [None]

    def damaged(msg: str, kind: str, offset: int, frames_lost=None, by_bus=None, batches=None,
                t0=None, t1=None, skipped=None) -> dict:
        msg = msg + (f"; frames lost: {frames_lost}" if frames_lost is not None else "; frames lost: unknown")
        if not recover:
            raise RecordingError(msg + "; run 'wheelsoil recover' to rewrite it")
        d = {"file": str(path), "offset": int(offset), "kind": kind, "frames_lost": frames_lost,
             "frames_lost_by_bus": dict(by_bus or {}), "batches_lost": batches, "bytes_skipped": skipped,
             "t0_ns": t0, "t1_ns": t1, "message": msg}
        state.damage.append(d)
        state.warnings.append(msg)
        warnings.warn(msg, RuntimeWarning, stacklevel=4)
        return d

    def bus_of(cid: int) -> str | None:
        bus = frame_channels.get(cid)
        if bus is None and cid not in state.channels and cid in backup_channels:
            bus = frame_channels[cid] = backup_channels[cid]
        return bus

    def count_frames(recs) -> tuple[int | None, dict, int]:
        """Frames of the frame batches among (damaged) chunk records, from their headers."""
        total, by_bus, batches = 0, {}, 0
        for op, r in recs:
            if op != _OP_MESSAGE:
                continue
            bus = bus_of(r[0])
            if bus is None:
                continue
            batches += 1
            n = _batch_len(r[2])
            if n is None or total is None:
                total = None
                continue
            total += n
            by_bus[bus] = by_bus.get(bus, 0) + n
        return total, by_bus, batches

    def message(cid: int, log_time: int, data, where: int):
        """FrameBatch for a frame message, else None."""
        bus = bus_of(cid)
        if bus is not None:
            if frame_buses is None or bus in frame_buses:
                try:
                    b = decode_batch(bus, data)
                except ValueError as exc:
                    damaged(f"{path}: frame batch of bus {bus} at log_time {log_time} in the record "
                            f"at byte {where} skipped: {exc}", "batch", where, None, batches=1)
                    return None
                state.frames += len(b)
                return b
            n = _batch_len(data)
            state.frames += n or 0
        elif with_status and cid in status_channels:
            try:
                state.statuses.append(json.loads(bytes(data)))
                state.status_times.append(log_time)
            except ValueError:
                pass
        elif cid not in state.channels:
            if not recover:
                raise RecordingError(f"{path}: messages of channel {cid} at byte {where}: the record defining "
                                     "the channel was in damaged data; run 'wheelsoil recover' to rewrite it")
            n = _batch_len(data)
            d = orphan.setdefault(cid, {"offset": where, "batches": 0, "frames": 0})
            d["batches"] += 1
            d["frames"] = None if (n is None or d["frames"] is None) else d["frames"] + n
        return None

    def report_orphans() -> None:
        for cid, d in orphan.items():
            damaged(f"{path}: {d['batches']} message(s) of channel {cid} from byte {d['offset']} on skipped: "
                    "the record defining the channel was in damaged data", "channel", d["offset"], d["frames"],
                    batches=d["batches"])
        orphan.clear()

    def other(op: int, rec, where: int) -> None:
        if op == _OP_SCHEMA:
            schemas[rec.id] = rec
        elif op == _OP_CHANNEL:
            sch = schemas.get(rec.schema_id) or backup_schemas.get(rec.schema_id)
            name = sch.name if sch else ""
            if sch is None and (rec.id in backup_channels or rec.metadata.get("frames") == SCHEMA_NAME):
                name = SCHEMA_NAME  # its schema record was in damaged data; the channel says what it is
            state.channels[rec.id] = {"topic": rec.topic, "encoding": rec.message_encoding,
                                      "schema": name, "metadata": dict(rec.metadata)}
            if name == SCHEMA_NAME:
                frame_channels[rec.id] = _bus_name(rec.metadata, rec.topic)
            elif rec.topic == STATUS_TOPIC:
                status_channels.add(rec.id)

    def _record(op: int, body, pos: int, ln: int, out: list) -> None:
        """Handle one top-level record whose framing is intact; batches go to ``out``.
        Raises ValueError/EOFError/struct.error when the record itself does not parse."""
        if op == _OP_CHUNK:
            t0, t1, usize, crc, comp, payload = _parse_chunk(body)
            if _CHUNK_HDR.size + len(comp.encode()) + 8 + len(payload) != ln:
                raise ValueError("chunk fields do not add up to the record length")
            last_chunk_damage[0] = None
            try:
                raw = _inflate(comp, payload, usize)
            except (ValueError, MemoryError) as exc:
                last_chunk_damage[0] = damaged(
                    f"{path}: chunk at byte {pos} of {size} damaged and skipped "
                    f"({type(exc).__name__}: {exc})", "chunk", pos, None, t0=t0, t1=t1, skipped=ln + 9)
                return
            try:
                recs, bad = _chunk_records(raw), None
            except _PARSE_ERRORS as exc:
                recs, bad = None, exc
            if crc and zlib.crc32(raw) != crc:
                lost, by_bus, nb = count_frames(recs) if recs is not None else (None, {}, None)
                last_chunk_damage[0] = damaged(
                    f"{path}: chunk at byte {pos} of {size} fails its CRC check (bit rot or a damaged "
                    f"copy) and is skipped", "crc", pos, lost, by_bus, nb, t0, t1, skipped=ln + 9)
            elif recs is None:
                last_chunk_damage[0] = damaged(
                    f"{path}: chunk at byte {pos} of {size} damaged and skipped "
                    f"({type(bad).__name__}: {bad})", "chunk", pos, None, t0=t0, t1=t1, skipped=ln + 9)
            else:
                for op2, r in recs:
                    if op2 == _OP_MESSAGE:
                        b = message(r[0], r[1], r[2], pos)
                        if b is not None:
                            out.append(b)
                    else:
                        other(op2, r, pos)
        elif op == _OP_MSG_INDEX:
            if ln < 6 or _U32.unpack_from(body, 2)[0] != ln - 6 or (ln - 6) % 16:
                raise ValueError("message index fields do not add up to the record length")
            d = last_chunk_damage[0]
            if d is not None:
                (cid,) = struct.unpack_from("<H", body, 0)
                if bus_of(cid) is not None:
                    d["batches_lost"] = (d["batches_lost"] or 0) + (ln - 6) // 16
        elif op == _OP_MESSAGE:
            if ln < 22:
                raise ValueError(f"message record of {ln} bytes")
            cid, _seq, lt, _pt = _MSG_HDR.unpack_from(body, 0)
            b = message(cid, lt, memoryview(body)[22:], pos)
            if b is not None:
                out.append(b)
        elif op == _OP_SCHEMA:
            other(op, _parse(Schema, body), pos)
        elif op == _OP_CHANNEL:
            other(op, _parse(Channel, body), pos)
        elif op == _OP_METADATA:
            md = _parse(Metadata, body)
            state.metadata[md.name] = dict(md.metadata)
            if md.name == CHANNELS_RECORD:
                for k, v in md.metadata.items():
                    if k.isdigit():
                        backup_channels[int(k)] = v
        elif op == _OP_ATTACHMENT:
            att = _parse(Attachment, body)
            crc = _U32.unpack_from(body, ln - 4)[0]
            if crc and crc != zlib.crc32(memoryview(body)[:ln - 4]):
                damaged(f"{path}: attachment {_printable(att.name)!r} at byte {pos} fails its CRC "
                        f"check and is ignored", "attachment", pos, 0)
            else:
                state.attachments[att.name] = att.data
        elif op == _OP_HEADER:
            _parse(Header, body)
        elif op == _OP_DATA_END:
            if ln != 4:
                raise ValueError(f"data end record of {ln} bytes")
        elif op == _OP_FOOTER:
            if ln != 20:
                raise ValueError(f"footer record of {ln} bytes")

    with open(path, "rb") as f:
        size = state.size = os.fstat(f.fileno()).st_size
        head = f.read(8)
        if head != _MAGIC:
            raise RecordingError(f"{path}: not an MCAP file (starts with {head[:8]!r}, "
                                 f"{size} bytes)")
        sch_b, ch_b = _read_summary_channels(f, size)
        backup_schemas.update(sch_b)
        for cid, ch in ch_b.items():
            s = sch_b.get(ch.schema_id)
            if s is not None and s.name == SCHEMA_NAME:
                backup_channels[cid] = _bus_name(ch.metadata, ch.topic)
        pos = 8
        first = True
        data_ops = {_OP_SCHEMA, _OP_CHANNEL, _OP_MESSAGE, _OP_CHUNK, _OP_MSG_INDEX, _OP_ATTACHMENT,
                    _OP_METADATA, _OP_DATA_END, _OP_FOOTER}
        while True:
            f.seek(pos)
            hdr = f.read(9)
            if len(hdr) < 9:
                damaged(f"{path}: ends at byte {size} without the MCAP footer (truncated: the writer did not "
                        f"close it, e.g. power cut or kill); kept the {state.frames} frames before byte {pos}",
                        "truncated", pos, None, skipped=size - pos)
                break
            op, ln = _REC_HDR.unpack(hdr)
            body_at = pos + 9
            fits = ln <= size - body_at and ln <= MAX_RECORD_BYTES
            body = None
            out: list = []
            if not fits:
                problem = (f"record of type 0x{op:02X} at byte {pos} claims {ln} bytes, "
                           + (f"only {size - body_at} are left in the file" if ln > size - body_at
                              else f"more than the {MAX_RECORD_BYTES}-byte limit"))
            elif op not in data_ops and not (first and op == _OP_HEADER):
                problem = f"record of {'unknown' if op not in _KNOWN_OPS else 'unexpected'} type 0x{op:02X} " \
                          f"(corrupted record header) at byte {pos}"
            else:
                body = f.read(ln)
                try:
                    problem = None
                    _record(op, body, pos, ln, out)
                except _PARSE_ERRORS as exc:
                    problem = f"record of type 0x{op:02X} at byte {pos} does not parse ({type(exc).__name__}: {exc})"
            first = False
            if problem is None:
                yield from out
                if op in (_OP_FOOTER, _OP_DATA_END):
                    nxt = _appended_at(f, pos, size)
                    if nxt is not None:
                        damaged(f"{path}: a second MCAP recording starts at byte {nxt} of {size} (recordings "
                                f"joined end to end, e.g. with cat); only the first one (bytes 0-{nxt}, "
                                f"{state.frames} frames) was read; read the second on its own (tail -c "
                                f"+{nxt + 1} {path} > second.mcap)", "appended", nxt, None, skipped=size - nxt)
                    elif op == _OP_FOOTER or _footer_ok(f, size):
                        state.footer = True
                    else:
                        damaged(f"{path}: summary or footer after byte {pos} damaged (every frame was read; "
                                "wheelsoil recover writes a clean copy)", "footer", pos, 0)
                    break
                pos = body_at + ln
                continue
            # a damaged record: find where the next one starts and go on there
            nxt = _resync(f, pos + 1, size)
            lost, by_bus, nb, t0, t1 = None, {}, None, None, None
            if body is None and fits:
                f.seek(body_at)
                body = f.read(ln)
            if body is not None:  # what did it hold, if it was a chunk?
                try:
                    t0, t1, usize, _crc, comp, payload = _parse_chunk(body)
                    lost, by_bus, nb = count_frames(_chunk_records(_inflate(comp, payload, usize)))
                except _PARSE_ERRORS:
                    t0 = t1 = None
            if nxt is None:
                last = op == _OP_CHUNK or ln > size - body_at
                damaged(f"{path}: damaged or truncated at byte {pos} of {size}: {problem}; "
                        f"kept the {state.frames} frames before it", "truncated" if last else "record",
                        pos, lost, by_bus, nb, t0, t1, skipped=size - pos)
                break
            kind = "record" if op in _KNOWN_OPS else "unknown_record"
            last_chunk_damage[0] = damaged(
                f"{path}: damaged record at byte {pos} of {size} skipped ({problem}); {nxt - pos} bytes "
                f"skipped, reading goes on at byte {nxt}", kind, pos, lost, by_bus, nb, t0, t1, skipped=nxt - pos)
            pos = nxt
        report_orphans()


def _bus_name(meta, topic: str) -> str:
    """Bus of a frame channel: its ``bus`` metadata, else the ``<bus>`` of ``/can/<bus>/frames``."""
    parts = str(topic).split("/")
    return str(meta.get("bus") or (parts[2] if len(parts) > 2 else topic))


def _printable(s: str) -> str:
    """``s`` without control characters (terminal escape sequences), for messages."""
    return "".join(c if c.isprintable() else f"\\x{ord(c):02x}" if ord(c) < 256 else f"\\u{ord(c):04x}"
                   for c in str(s))


def read_attachments(path) -> dict[str, bytes]:
    """Attachments at the start of a recording (``vehicle.toml``, ``dbc/*``), name -> bytes.

    Reads only up to the first chunk, so it is instant on long files and works
    on truncated ones (the writer puts attachments before any frame). Record
    sizes are checked against the file before reading; an attachment whose CRC
    does not match is left out.

    Raises:
        OSError: unreadable file. RecordingError: not an MCAP file.
    """
    from mcap.records import Attachment

    out: dict[str, bytes] = {}
    with open(path, "rb") as f:
        size = os.fstat(f.fileno()).st_size
        head = f.read(8)
        if head != _MAGIC:
            raise RecordingError(f"{path}: not an MCAP file (starts with {head[:8]!r}, {size} bytes)")
        pos = 8
        while True:
            hdr = f.read(9)
            if len(hdr) < 9:
                break
            op, ln = _REC_HDR.unpack(hdr)
            if op in (_OP_CHUNK, _OP_MESSAGE, _OP_FOOTER, _OP_DATA_END) or op not in _KNOWN_OPS \
                    or ln > size - pos - 9 or ln > MAX_RECORD_BYTES:
                break
            if op == _OP_ATTACHMENT:
                body = f.read(ln)
                try:
                    crc = _U32.unpack_from(body, ln - 4)[0]
                    att = _parse(Attachment, body)
                except (ValueError, EOFError, struct.error):
                    break
                if not crc or crc == zlib.crc32(memoryview(body)[:ln - 4]):
                    out[att.name] = att.data
            else:
                f.seek(ln, 1)
            pos += 9 + ln
    return out


def iter_frame_batches(path, *, buses=None, recover: bool = True,
                       report: ReadReport | None = None) -> Iterator[FrameBatch]:
    """Stream the raw frames of an MCAP recording, batch by batch.

    Batches come in file order, which is log-time order per bus (batches of
    different buses interleave). Arrays may be read-only views. Only verified
    data is yielded: every chunk's CRC is checked before its frames are handed
    out, and sizes claimed by records are checked before anything is allocated.

    Args:
        path: ``.mcap`` file written by :class:`RecordingWriter` (or any MCAP
            with ``wheelsoil_msgs/msg/CanFrameBatch`` channels).
        buses: bus names to yield (None: all).
        recover: a truncated/damaged file yields every verified chunk and a
            ``RuntimeWarning`` per damaged place names the file, the byte offset and
            the frames lost. With False damage raises :class:`RecordingError` instead.
        report: a :class:`ReadReport` to fill (``damage``, ``warnings``,
            ``complete``, metadata...): how damage reaches processing without
            parsing warning texts.

    Raises:
        OSError: the file cannot be opened.
        RecordingError (a ValueError): not an MCAP file; damaged and ``recover=False``.
    """
    wanted = None if buses is None else set([buses] if isinstance(buses, str) else buses)
    yield from _iter_records(path, ReadReport() if report is None else report, recover=recover,
                             frame_buses=wanted)


def read_frames(path, *, buses=None, recover: bool = True,
                report: ReadReport | None = None) -> dict[str, FrameBatch]:
    """All frames of a recording, concatenated per bus: bus name -> :class:`FrameBatch`.

    Same arguments and errors as :func:`iter_frame_batches` (``report`` receives
    the damage found, see :class:`ReadReport`).
    """
    parts: dict[str, list[FrameBatch]] = {}
    for b in iter_frame_batches(path, buses=buses, recover=recover, report=report):
        parts.setdefault(b.bus, []).append(b)
    return {bus: FrameBatch.concat(bs, bus) for bus, bs in parts.items()}


def check_output(output, inputs=(), *, overwrite: bool = False) -> Path:
    """Refuse an output that is one of the inputs, or that exists without ``overwrite``.

    Args:
        output: the file a command will write.
        inputs: the files it reads (compared by resolved path and by inode).
        overwrite: an existing ``output`` may be replaced.

    Returns:
        ``output`` as a Path.

    Raises:
        ValueError: output is an input; output exists and ``overwrite`` is False
            (both name the file).
    """
    out = Path(output)
    for p in ([inputs] if isinstance(inputs, (str, Path)) else inputs):
        p = Path(p)
        same = out.resolve() == p.resolve()
        if not same and out.exists() and p.exists():
            try:
                same = os.path.samefile(out, p)
            except OSError:
                same = False
        if same:
            raise ValueError(f"{out}: the output is the input {p}; choose another output file "
                             "(the input would be destroyed)")
    if out.exists() and not overwrite:
        raise ValueError(f"{out}: exists; kept as it is (use --overwrite to replace it)")
    return out


def numbered_path(path) -> Path:
    """``path`` if it does not exist, else the first free ``<stem>-001<suffix>``, ``-002``, ..."""
    path = Path(path)
    if not path.exists():
        return path
    for i in range(1, 100000):
        p = path.with_name(f"{path.stem}-{i:03d}{path.suffix}")
        if not p.exists():
            return p
    raise OSError(f"{path}: no free numbered file name next to it")
