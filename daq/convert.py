"""Import other loggers' files into MCAP, export MCAP to them, recover damaged MCAP.

Formats through python-can's readers/writers: candump ``-L`` ``.log``,
Vector ``.asc`` and ``.blf``, PEAK ``.trc``.

Channel <-> bus names: python-can numbers channels from 0 (ASC/BLF/TRC
channel 1 is python-can channel 0), so channel ``c`` becomes bus ``can<c>``;
a named channel (candump's ``can0``, ``vcan1``) keeps its name. Exporting
writes the bus name as the channel; python-can's ASC/BLF/TRC writers turn
``can<c>`` into file channel ``c+1``. ``channel_map`` overrides both ways.

Data safety (import and export): the output may not be an input, an existing
output is kept unless ``overwrite=True``, and the file is written under a
temporary name in the output's directory and renamed into place only when
complete (:func:`check_output_path`). Import validates every line/frame
(:class:`LogSource`, :func:`~wheelsoil.daq.frames.checked_batch_from_messages`),
rejects and counts invalid ones with their line (BLF: object) numbers, reports
truncated files, refuses an input without a valid frame, and records all of it
in the ``wheelsoil.import`` metadata record next to an ``imported`` provenance.
"""

from __future__ import annotations

import contextlib
import heapq
import itertools
import json
import logging
import os
import re
import secrets
import time
import warnings
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import numpy as np

from .frames import FrameBatch, checked_batch_from_messages
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
            (each kind also in ``warnings``); for an import the rejected
            lines/objects (invalid frames).
        decoded: frames decoded into JSON messages (``wheelsoil decode``).
        truncated: input files found cut short (import).
        record: the ``wheelsoil.import`` metadata an import wrote (``frames``,
            ``rejected``, ``truncated``, ``files``: per file ``path``,
            ``format``, ``frames``, ``rejected``, ``unit`` (line/object),
            ``first_rejected`` (list of ``{line|object, reason}``),
            ``truncated``, ``notes``).
    """

    output: Path
    frames: dict[str, int] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    skipped: int = 0
    decoded: int = 0
    truncated: list[str] = field(default_factory=list)
    record: dict = field(default_factory=dict)

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


# --------------------------------------------------------------------------- safe output
def _same_file(a: Path, b: Path) -> bool:
    """True when ``a`` and ``b`` name the same file (resolved paths, or hard links)."""
    try:
        if a.resolve() == b.resolve():
            return True
    except (OSError, RuntimeError):
        pass
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_output_path(output, inputs, *, overwrite: bool = False) -> Path:
    """Refuse an output that is one of the inputs, or that exists without ``overwrite``.

    Nothing is touched: call it before reading or writing anything.

    Args:
        output: the file to be written.
        inputs: the files that will be read (paths).
        overwrite: replace an existing ``output`` (on success only).

    Returns:
        ``output`` as a :class:`~pathlib.Path`.

    Raises:
        ValueError: ``output`` is one of ``inputs`` (same path, symlink or hard
            link) or a directory. FileExistsError: ``output`` exists and
            ``overwrite`` is False.
    """
    out = Path(output)
    for p in inputs:
        if _same_file(Path(p), out):
            raise ValueError(f"{out}: the output is the input file {p}; choose another output name "
                             "(nothing was read or written)")
    if out.is_dir():
        raise ValueError(f"{out}: is a directory; give an output file name")
    if (out.exists() or out.is_symlink()) and not overwrite:
        raise FileExistsError(f"{out}: exists and is kept; pass overwrite=True (CLI: --overwrite) to replace it")
    return out


def _temp_path(out: Path) -> Path:
    """A fresh, not yet existing file name next to ``out`` with the same suffix
    (python-can picks its writer from the suffix)."""
    return out.with_name(f".{out.stem}.{os.getpid()}-{secrets.token_hex(4)}.tmp{out.suffix}")


def _fsync_path(path: Path, directory: bool = False) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        if not directory:
            raise
    finally:
        os.close(fd)


def _commit(tmp: Path, out: Path, overwrite: bool) -> None:
    """Make the finished ``tmp`` durable and move it to ``out`` atomically.

    Without ``overwrite`` the move refuses to replace a file that appeared at
    ``out`` meanwhile (hard link + unlink where the file system has links).
    """
    _fsync_path(tmp)
    if overwrite:
        os.replace(tmp, out)
    else:
        try:
            os.link(tmp, out)
        except FileExistsError:
            raise FileExistsError(f"{out}: appeared while writing; kept, the new file was discarded") from None
        except OSError:  # no hard links here (some network/FAT file systems)
            if out.exists():
                raise FileExistsError(f"{out}: appeared while writing; kept") from None
            os.replace(tmp, out)
        else:
            os.unlink(tmp)
    _fsync_path(out.parent, directory=True)


def _discard(tmp: Path) -> None:
    try:
        tmp.unlink()
    except FileNotFoundError:
        pass
    except OSError:
        pass


# --------------------------------------------------------------------------- reading logs
#: Rejected lines/frames listed one by one per file (warnings and metadata); the rest are counted.
MAX_LISTED = 10
#: Name of the MCAP metadata record an import writes (counts, first rejected lines, truncation).
IMPORT_RECORD = "wheelsoil.import"

_BYTE_HEX = re.compile(r"[0-9A-Fa-f]{2}")
_BYTE_DEC = re.compile(r"\d{1,3}")
#: A candump -L line (can-utils lib.c sprint_canframe/parse_canframe): "(sec.usec) channel id#data [R|T]"
#: with a 3-digit 11-bit id (<= 7FF) or an 8-digit 29-bit id (<= 1FFFFFFF; 2xxxxxxx/3xxxxxxx is
#: an error frame, CAN_ERR_FLAG), data as hex pairs, "##<flags><pairs>" for CAN FD, "R[dlc]" for remote.
_CANDUMP_TAIL = (r"#(?:#[0-9A-Fa-f](?:[0-9A-Fa-f]{2})*|[Rr][0-8]?|(?:[0-9A-Fa-f]{2})*)"
                 r"(?P<dir>\s+[RrTt])?\s*")
_CANDUMP_RE = re.compile(r"\s*\(\d+(?:\.\d*)?\)\s+\S+\s+(?:[0-7][0-9A-Fa-f]{2}|[01][0-9A-Fa-f]{7})"
                         + _CANDUMP_TAIL)
_CANDUMP_ERR_RE = re.compile(r"\s*\(\d+(?:\.\d*)?\)\s+\S+\s+[23][0-9A-Fa-f]{7}" + _CANDUMP_TAIL)


def _candump_reason(line: str) -> str:
    """Why ``line`` is not a valid candump -L frame line (slow path, bad lines only)."""
    parts = line.split()
    if len(parts) not in (3, 4):
        return "not a candump -L frame line ('(seconds) channel id#data')"
    ts, _, frame = parts[:3]
    if not re.fullmatch(r"\(\d+(?:\.\d*)?\)", ts):
        return f"timestamp {ts!r} is not a number of seconds"
    if "#" not in frame:
        return f"no '#' between identifier and data in {frame[:40]!r}"
    ident, data = frame.split("#", 1)
    if not re.fullmatch(r"[0-9A-Fa-f]+", ident):
        return f"identifier {ident[:20]!r} is not hexadecimal"
    if len(ident) not in (3, 8):
        return f"identifier {ident[:20]!r} has {len(ident)} hex digits (3 for 11-bit, 8 for 29-bit ids)"
    v = int(ident, 16)
    if len(ident) == 3 and v > 0x7FF:
        return f"11-bit identifier 0x{v:03X} out of range (max 0x7FF)"
    if len(ident) == 8 and v >> 30:
        return f"29-bit identifier 0x{v:08X} out of range (max 0x1FFFFFFF; flag bits set)"
    if data[:1] == "#":
        if not re.fullmatch(r"#[0-9A-Fa-f]", data[:2]):
            return f"CAN FD flags {data[:2]!r} are not one hex digit"
        data = data[2:]
    elif data[:1] in ("R", "r"):
        return f"remote frame {data[:10]!r}: expected R or R0..R8"
    if not re.fullmatch(r"[0-9A-Fa-f]*", data):
        return f"data {data[:40]!r} has characters that are not hex digits"
    if len(data) % 2:
        return f"data {data[:40]!r} has an odd number of hex digits ({len(data)})"
    if len(parts) == 4 and parts[3] not in ("R", "T", "r", "t"):
        return f"direction {parts[3][:10]!r} is not R or T"
    return "not a candump -L frame line"


class _Lines:
    """Line iterator for python-can's text readers: counts file lines, can
    replay the header lines to a fresh reader after a bad line, and remembers
    the lines handed out since the last message for which ``track(line)`` is
    true (frame-like lines), so lines the reader skips silently can be named."""

    def __init__(self, f, *, track=None):
        self._f = f
        self.lineno = 0
        self.header: list[str] = []
        self.in_header = True
        self.replay: list[str] = []
        self.last = ""
        self.track = track
        self.since: list[str] = []

    def first_message(self) -> None:
        """Called at the first frame: the header is what came before its line."""
        if self.in_header:
            self.in_header = False
            if self.header:
                self.header.pop()

    def __iter__(self):
        return self

    def _next_line(self) -> str:
        line = next(self._f)
        self.lineno += 1
        self.last = line
        if self.in_header:
            self.header.append(line)
            if len(self.header) > 5000:
                self.in_header = False
        return line

    def __next__(self) -> str:
        if self.replay:
            return self.replay.pop(0)
        line = self._next_line()
        if self.track is not None:
            self.since.append(line)
        return line

    def readline(self) -> str:
        try:
            return next(self)
        except StopIteration:
            return ""

    def close(self) -> None:
        pass


class _CandumpFilter:
    """The lines of a candump file that match the candump -L grammar, for
    python-can's reader (its own parser takes odd-length hex, '+1' bytes, ids of
    any length, 'nan' times, ...). Works on chunks of lines: a regex per line
    and list operations, no Python call per line; iterating hands the good
    lines to the reader at C speed.

    ``lines`` (a deque) holds the line number of each good line not yet turned
    into a message, in order: python-can makes exactly one message (or raises)
    per non-blank line, so the k-th message comes from the k-th good line.
    Rejected lines go to ``rejected`` as ``(line number, reason)``; line
    numbers of error frames (CAN_ERR_FLAG ids) to ``errors``, with their text.
    """

    def __init__(self, f, rejected: list):
        self._f = f
        self.rejected = rejected
        self.lines: deque[int] = deque()
        self.errors: dict[int, str] = {}
        self._it = itertools.chain.from_iterable(self._chunks())

    def _chunks(self):
        match, err_match = _CANDUMP_RE.fullmatch, _CANDUMP_ERR_RE.fullmatch
        base = 0
        while True:
            chunk = self._f.readlines(1 << 20)
            if not chunk:
                return
            ok = list(map(match, chunk))
            if None in ok:
                for i in [i for i, m in enumerate(ok) if m is None]:
                    line = chunk[i]
                    if not line.strip():
                        continue
                    m = err_match(line)
                    if m is not None:
                        ok[i] = m
                        self.errors[base + i + 1] = line
                    else:
                        self.rejected.append((base + i + 1, _candump_reason(line)))
            last = chunk[-1]
            if not last.endswith("\n") and ok[-1] is not None and ok[-1]["dir"] is None:
                self.rejected.append((base + len(chunk), "cut off: the file ends inside this line "
                                                          "(truncated); not imported"))
                ok[-1] = None
            good = [i for i, m in enumerate(ok, base + 1) if m is not None]
            self.lines.extend(good)
            yield [chunk[i - base - 1] for i in good] if len(good) < len(chunk) else chunk
            base += len(chunk)

    def __iter__(self):
        return self._it

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


def _count_bytes(tokens, pattern) -> int:
    """Leading tokens of ``tokens`` that match ``pattern`` (one data byte each)."""
    if all(map(pattern.fullmatch, tokens)):
        return len(tokens)
    n = 0
    for t in tokens:
        if not pattern.fullmatch(t):
            break
        n += 1
    return n


_PC: dict = {}


def _python_can_tables() -> dict:
    """python-can names the checks use, imported once (python-can loads lazily here)."""
    if not _PC:
        from can.io.trc import TRCFileVersion
        from can.util import dlc2len

        _PC.update(dlc2len=dlc2len, v2=(TRCFileVersion.V2_0, TRCFileVersion.V2_1),
                   first_byte={TRCFileVersion.V1_1: 5, TRCFileVersion.V1_3: 7},
                   id_col={TRCFileVersion.V1_1: 3, TRCFileVersion.V1_3: 4})
    return _PC


_ID_HEX = re.compile(r"[0-9A-Fa-f]{1,8}x?", re.IGNORECASE)
_ID_DEC = re.compile(r"\d{1,10}x?", re.IGNORECASE)
_TIME_MS = re.compile(r"\d+(?:\.\d*)?")


#: An ASC line that looks like a CAN frame: a direction word Rx/Tx anywhere (the time may be garbled: python-can
#: then passes the line over without a word), not a ``//`` comment.
_ASC_FRAMEISH = re.compile(r"(?!\s*//).*\b(?:Rx|Tx)\b", re.IGNORECASE).match


def _asc_frameish(line: str) -> bool:
    """True for an ASC line python-can should turn into a frame (others are events, comments)."""
    return _ASC_FRAMEISH(line) is not None


def _trc_frameish(line: str) -> bool:
    """True for a TRC line that is not blank and not a comment."""
    s = line.lstrip()
    return bool(s) and s[0] != ";"


def _asc_reason(msg, line: str, reader) -> str | None:
    """What is wrong with an ASC frame python-can parsed from ``line`` (None: fine).

    python-can takes the first DLC bytes and ignores the rest, accepts a DLC
    above 8 for classic frames, a CAN FD DLC that does not match the data
    length (only a log message) and ids like ``+12``."""
    if msg.is_error_frame:
        return None
    base = getattr(reader, "_converted_base", 16)
    pat = _BYTE_HEX if base == 16 else _BYTE_DEC
    toks = line.split()
    try:
        if not msg.is_fd:
            if not (_ID_HEX if base == 16 else _ID_DEC).fullmatch(toks[2]):
                return f"identifier {toks[2][:12]!r} is not a number"
            if msg.is_remote_frame:
                return None
            if toks[4] not in ("d", "D"):
                return f"frame type {toks[4][:10]!r} is not 'd' (data) or 'r' (remote)"
            code = int(toks[5], base)
            if code > 8:
                return f"classic CAN frame with DLC {code} (at most 8 data bytes)"
            data = toks[6:6 + code]
            if len(data) == code and all(map(pat.fullmatch, data)) \
                    and (len(toks) == 6 + code or not pat.fullmatch(toks[6 + code])):
                return None
            n = _count_bytes(toks[6:], pat)
            return f"DLC {code} but {n} data bytes" + (" (line cut off?)" if n < code else "")
        if not (_ID_HEX if base == 16 else _ID_DEC).fullmatch(toks[4]):
            return f"identifier {toks[4][:12]!r} is not a number"
        if msg.is_remote_frame:
            return None
        i = 5 if toks[5].isdigit() else 6
        code, dlen = int(toks[i + 2], base), int(toks[i + 3])
        if code > 15 or _python_can_tables()["dlc2len"](code) != dlen:
            return f"CAN FD DLC {code} does not give data length {dlen}"
        n = _count_bytes(toks[i + 4:i + 4 + dlen], pat)
        if n != dlen:
            return f"data length {dlen} but {n} data bytes" + (" (line cut off?)" if n < dlen else "")
    except Exception:  # noqa: BLE001 - any odd line: rejected, never a traceback
        return "not a complete ASC frame line"
    return None


#: TRC 2.x column -> pattern of its text ($COLUMNS letters, PEAK TRC file format 2.1).
_TRC_COLUMN = {"N": r"\d+", "O": r"\d+(?:\.\d*)?", "T": r"[A-Za-z]{2}", "B": r"\d+", "I": r"[0-9A-Fa-f]{1,8}",
               "d": r"[RT]x", "R": r"\S+", "L": r"\d+", "l": r"\d+"}


def _trc_line_re(columns: dict):
    """One regex for a whole TRC 2.x frame line with these columns (data last), or None."""
    order = sorted(columns, key=columns.get)
    if not order or order[-1] != "D" or any(c not in _TRC_COLUMN for c in order[:-1]):
        return None
    body = r"\s+".join(_TRC_COLUMN[c] for c in order[:-1])
    return re.compile(r"\s*" + body + r"(?:\s+(?:[0-9A-Fa-f]{2}(?:\s+|$))*)?\s*").fullmatch


def _trc_reason(msg, line: str, reader) -> str | None:
    """What is wrong with a TRC frame python-can parsed from ``line`` (None: fine).

    python-can's TRC reader takes ``nan``/``1e20`` times, ids like ``+12`` and
    ignores data bytes past the DLC. Also turns the DLC code python-can keeps
    for TRC 2.x into the payload length (``dlc`` means bytes in a :class:`FrameBatch`)."""
    pc = _PC or _python_can_tables()
    v = getattr(reader, "file_version", None)
    try:
        if v in pc["v2"]:
            fast = getattr(reader, "_wheelsoil_line_re", False)
            if fast is False:
                fast = reader._wheelsoil_line_re = _trc_line_re(reader.columns)
            if fast is not None and fast(line) is not None:
                # time, id and data bytes well-formed; the byte count is checked against the DLC later
                if 0 <= msg.dlc <= 15:
                    msg.dlc = pc["dlc2len"](msg.dlc)
                return None
            cols = reader.columns
            parts = line.split(maxsplit=reader._num_columns)
            t_col, id_col = parts[cols["O"]], parts[cols["I"]]
        else:
            parts = line.split()
            k = pc["first_byte"].get(v, 4)  # first data byte: 4 (1.0), 5 (1.1), 7 (1.3)
            t_col, id_col = parts[1], parts[pc["id_col"].get(v, 2)]
        if not _TIME_MS.fullmatch(t_col):
            return f"time offset {t_col[:20]!r} is not a number of milliseconds"
        if not _ID_HEX.fullmatch(id_col) or id_col[-1:] in ("x", "X"):
            return f"identifier {id_col[:12]!r} is not hexadecimal"
        if v in pc["v2"]:
            if 0 <= msg.dlc <= 15:
                msg.dlc = pc["dlc2len"](msg.dlc)
            if msg.is_remote_frame or "D" not in cols:
                return None
            toks = parts[cols["D"]].split() if len(parts) > cols["D"] else []
        else:
            if msg.is_remote_frame:
                return None
            toks = parts[k:]
            if len(toks) != msg.dlc:
                return f"DLC {msg.dlc} but {len(toks)} data bytes"
        n = _count_bytes(toks, _BYTE_HEX)
        if n != len(toks):
            return f"data byte {toks[n][:10]!r} is not two hex digits"
    except Exception:  # noqa: BLE001 - any odd line: rejected, never a traceback
        return "not a complete TRC frame line"
    return None


class _ReadWatch:
    """Binary file wrapper for python-can's BLF reader: notes a short read
    (the file ends inside an object), which the reader itself passes over, and
    never asks for more than the file holds (an object size from a damaged
    header would otherwise make ``read`` allocate up to 4 GiB)."""

    def __init__(self, f, size: int):
        self._f = f
        self.size = size
        self.short_at: int | None = None
        self.offset = 0

    def read(self, n: int = -1) -> bytes:
        if n is None or n < 0 or n > self.size - self.offset:
            want = n
            n = max(self.size - self.offset, 0)
        else:
            want = n
        data = self._f.read(n)
        # a short read, except the reader's end-of-file probe for the next 16-byte object header
        if want is not None and want > 0 and len(data) < want and not (len(data) == 0 and want == 16) \
                and self.short_at is None:
            self.short_at = self.offset + len(data)
        self.offset += len(data)
        return data

    def close(self) -> None:
        pass


def _next_blf_container(raw, start: int, size: int) -> int | None:
    """Byte offset of the next BLF log container (an object header ``LOBJ`` of type 10 whose size fits the
    file) at or after ``start`` in the binary file ``raw``; None if there is none (read in 1 MiB blocks).
    The header layout and the container type are python-can's (``can.io.blf``)."""
    from can.io.blf import LOG_CONTAINER, OBJ_HEADER_BASE_STRUCT as HEADER

    pos, block = start, 1 << 20
    while pos < size:
        raw.seek(pos)
        buf = raw.read(block + HEADER.size - 1)
        i = buf.find(b"LOBJ")
        while i >= 0:
            if i + HEADER.size <= len(buf):
                _sig, hsize, _ver, osize, otype = HEADER.unpack_from(buf, i)
                if otype == LOG_CONTAINER and hsize >= HEADER.size and HEADER.size < osize <= size - (pos + i):
                    return pos + i
            i = buf.find(b"LOBJ", i + 1)
        pos += block
    return None


def _resumed(reader):
    """python-can's BLF ``reader`` started at a container that follows a damaged one: the object split across
    the two is lost, so the first container's data is read from its first whole object (``LOBJ``) on,
    where python-can would stop at the split object's remainder ("Could not find next object")."""
    parse, first = reader._parse_container, [True]

    def parse_from_first_object(data):
        if first[0]:
            first[0] = False
            i = data.find(b"LOBJ")
            data = data[i:] if i >= 0 else b""
        return parse(data)

    reader._parse_container = parse_from_first_object
    return reader


class _Spliced:
    """A binary file read as its first bytes ``head`` (a BLF file header) followed by ``raw`` from byte
    ``start`` on: python-can's BLF reader, which reads the header first, resumes at a later container."""

    def __init__(self, head: bytes, raw, start: int):
        self._head, self._raw, self._at = head, raw, start

    def read(self, n: int = -1) -> bytes:
        k = len(self._head) if n is None or n < 0 else min(n, len(self._head))
        out, self._head = self._head[:k], self._head[k:]
        if n is not None and n >= 0:
            n -= k
            if n == 0:
                return out
        self._raw.seek(self._at)
        data = self._raw.read(n)
        self._at += len(data)
        return out + data

    def close(self) -> None:
        pass


@contextlib.contextmanager
def _quiet_logger(name: str):
    """Raise a python-can logger's level to ERROR for the duration (restored after)."""
    log = logging.getLogger(name)
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        yield
    finally:
        log.setLevel(level)


#: The time at the start of an ASC event line (seconds, as the line writes them).
_ASC_LINE_TIME = re.compile(r"\s*(\d+)(?:\.(\d*))?\s")


def _asc_line_ns(line: str) -> int | None:
    """The leading time of an ASC event line in integer nanoseconds (exact: no float sums), None: no time."""
    m = _ASC_LINE_TIME.match(line)
    if m is None:
        return None
    frac = (m.group(2) or "")[:9]
    return int(m.group(1)) * 10**9 + int(frac.ljust(9, "0") or 0)


class _AscDeltas:
    """Running time of an ASC file whose header says ``base hex  timestamps relative``.

    In Vector's ASC format "relative" means that each event line's time is the
    time since the previous event line (any event: frames on every channel,
    error frames, ``Start of measurement``, status lines), "absolute" (what
    python-can's ASCWriter writes) the time since the start of the measurement.
    python-can 4.6's ASCReader reads the header into ``timestamps_format`` but
    returns each line's delta as the time. The sum runs in integer ns over
    the lines' own text, so 10^5 deltas add no rounding error.
    """

    def __init__(self):
        self.active = False
        self.total_ns = 0

    def add(self, texts: list[str]) -> int:
        """Add the times of the event lines ``texts`` (the lines handed out since the last frame, this
        frame's own line last; lines without a leading time add nothing). Returns the running time [ns]."""
        for line in texts:
            ns = _asc_line_ns(line)
            if ns is not None:
                self.total_ns += ns
        return self.total_ns


class LogSource:
    """python-can messages of one log file, checked, with their place in the file.

    Iterating yields :class:`can.Message` objects; after each one ``pos`` is
    its place: the 1-based line number (``.log``, ``.asc``, ``.trc``) or the
    1-based index of the CAN frame object (``.blf``), ``unit`` says which.
    Lines/objects python-can cannot parse, or that fail the checks of the
    format, are not yielded but recorded in ``rejected`` as ``(pos, reason)``;
    ``notes`` collects file-level findings (truncation, damage) and
    ``truncated`` says whether the file was cut short.

    Checks per format (what python-can's readers let through):

    - candump ``.log``: every line must match the candump -L grammar of
      can-utils (hex digits, even data length, 3-digit ids <= 0x7FF, 8-digit
      ids <= 0x1FFFFFFF, numeric time); error frames (CAN_ERR_FLAG ids) are
      rebuilt with their channel, error class and data, which python-can drops;
      a last line without a line end is cut off and rejected.
    - ``.asc``: the data bytes of each frame line are counted against the DLC
      (python-can takes the first DLC bytes and ignores the rest), classic DLC
      <= 8, CAN FD DLC against the data length; no ``End TriggerBlock`` after a
      ``Begin TriggerBlock`` means truncated.
    - ``.trc``: data bytes counted against the DLC; lines python-can skips
      silently (cut off, unsupported record types) are rejected with their number.
    - ``.blf``: file size and object count of the header against what was
      read, and the reader's leftovers: a cut-off file is reported truncated.

    The frame rules common to all formats (identifier range, classic/FD
    lengths, DLC, finite time) are applied per batch by
    :func:`~wheelsoil.daq.frames.checked_batch_from_messages`.

    Raises (when iterated): OSError: unreadable file. ValueError: unknown suffix.
    """

    def __init__(self, path):
        self.path = Path(path)
        self.cls = _reader_class(self.path)
        self.suffix = self.path.suffix.lower()
        self.unit = "object" if self.suffix == ".blf" else "line"
        self.pos = 0
        self.rejected: list[tuple[int, str]] = []
        self.notes: list[str] = []
        self.truncated = False

    def where(self, pos: int) -> str:
        """``FILE:LINE`` or ``FILE: object N``."""
        return f"{self.path}:{pos}" if self.unit == "line" else f"{self.path}: object {pos}"

    def __iter__(self):
        if self.suffix == ".blf":
            return self._iter_blf()
        if self.suffix == ".log":
            return self._iter_candump()
        return self._iter_text()

    # -- text formats
    def _text_tail(self) -> tuple[bool, bool]:
        """(file ends with a line end, ASC trigger block opened but not closed)."""
        with open(self.path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            head = f.read(65536) if self.suffix == ".asc" else b""
            f.seek(max(size - 4096, 0))
            tail = f.read()
        # a file with CR LF line ends that ends in a bare CR was cut between the two
        ends_nl = size == 0 or tail[-1:] == b"\n" or (tail[-1:] == b"\r" and b"\r\n" not in tail)
        open_block = False
        if self.suffix == ".asc" and re.search(rb"(?im)^\s*begin\s+triggerblock", head):
            last = [ln.strip() for ln in tail.splitlines() if ln.strip()]
            open_block = not (last and last[-1].lower().startswith(b"end triggerblock"))
        return ends_nl, open_block

    def _check_end(self) -> None:
        """File-level truncation signs of a text log (see :meth:`_text_tail`) into ``notes``."""
        ends_nl, open_block = self._text_tail()
        if open_block:
            self.truncated = True
            self.notes.append(f"{self.path}: truncated: the trigger block is not closed ('End TriggerBlock' "
                              "missing at the end of the file)")
        if not ends_nl:
            self.truncated = True
            self.notes.append(f"{self.path}: truncated: the file ends inside its last line (no line end)")

    def _iter_text(self):
        path, cls, suffix = self.path, self.cls, self.suffix
        # python-can's relative_timestamp is another thing than the ASC header's "timestamps relative":
        # False adds the trigger block's date to each line's time (see _AscDeltas for the header's mode)
        kwargs = {"relative_timestamp": False} if suffix == ".asc" else {}
        self._check_end()
        check = _asc_reason if suffix == ".asc" else _trc_reason
        deltas = _AscDeltas() if suffix == ".asc" else None
        with open(path, "r", encoding="utf-8", errors="replace", newline=None) as f, \
                _quiet_logger(f"can.io.{suffix[1:]}"):  # its per-line messages are reported here, with numbers
            lines = _Lines(f, track=_trc_frameish if suffix == ".trc" else _asc_frameish)
            last_fail = -1
            while True:
                reader = cls(lines, **kwargs)
                try:
                    for msg in reader:
                        lines.first_message()
                        pos = lines.lineno
                        since = lines.since
                        if len(since) > 1:
                            self._dropped(lines, pos - len(since) + 1, since[:-1])
                        if deltas is not None and reader.timestamps_format == "relative":
                            if not deltas.active:
                                deltas.active = True
                                self.notes.append(
                                    f"{path}: note: the header says 'timestamps relative': each line's time is the "
                                    "time since the previous event (Vector ASC); accumulated into times since the "
                                    "start of the trigger block")
                            msg.timestamp = reader.start_time + deltas.add(since) * 1e-9
                        since.clear()
                        why = check(msg, lines.last, reader)
                        if why is not None:
                            self.rejected.append((pos, why))
                            continue
                        self.pos = pos
                        yield msg
                    since = lines.since
                    self._dropped(lines, lines.lineno - len(since) + 1, since)
                    since.clear()
                    return
                except Exception as exc:  # python-can raises ValueError/IndexError/... on a bad line
                    bad = lines.lineno
                    since = lines.since
                    self._dropped(lines, bad - len(since) + 1, since[:-1])
                    if deltas is not None and deltas.active:
                        deltas.add(since)  # an unreadable event line still takes its time
                    since.clear()
                    if bad == last_fail:  # no progress: give up rather than loop
                        self.notes.append(f"{path}:{bad}: cannot continue after this line: {exc}")
                        self.truncated = True
                        return
                    last_fail = bad
                    if lines.in_header and lines.header:
                        lines.header.pop()
                    self.rejected.append((bad, f"unparsable line {lines.last.strip()[:60]!r} "
                                               f"({type(exc).__name__}: {exc})"))
                    lines.replay = list(lines.header)

    def _iter_candump(self):
        """candump -L: pre-filtered lines (:class:`_CandumpFilter`) through python-can's reader."""
        self._check_end()
        with open(self.path, "r", encoding="utf-8", errors="replace", newline=None) as f:
            lines = _CandumpFilter(f, self.rejected)
            nos, errors = lines.lines, lines.errors
            while True:
                try:
                    for msg in self.cls(lines):
                        pos = nos.popleft()
                        if errors and pos in errors:
                            msg = _candump_error_frame(msg, errors[pos])
                        self.pos = pos
                        yield msg
                    return
                except Exception as exc:  # a line the grammar lets through but python-can refuses
                    if not nos:  # cannot tell the line: stop with what was read
                        self.notes.append(f"{self.path}: reading stopped ({type(exc).__name__}: {exc})")
                        return
                    bad = nos.popleft()
                    self.rejected.append((bad, f"unparsable line ({type(exc).__name__}: {exc})"))

    def _dropped(self, lines: _Lines, first: int, texts: list[str]) -> None:
        """Frame-like lines (``lines.track``) among ``texts`` (lines ``first``, ``first + 1``, ...)
        that python-can passed over without a message or an error: rejected with their number."""
        what = "cut off or unsupported record type" if self.suffix == ".trc" else "malformed frame line"
        for j, text in enumerate(texts):
            if lines.track(text):
                self.rejected.append((first + j, f"not read by python-can's {self.suffix[1:].upper()} reader "
                                                 f"({what}): {text.strip()[:60]!r}"))

    # -- BLF
    def _iter_blf(self):
        path = self.path
        with open(path, "rb") as raw:
            size = os.fstat(raw.fileno()).st_size
            f = _ReadWatch(raw, size)
            try:
                reader = self.cls(f)
            except Exception as exc:  # BLFParseError, struct.error on a short header
                self.notes.append(f"{path}: not a readable BLF file ({type(exc).__name__}: {exc})")
                return
            head_size = int(getattr(reader, "file_size", 0) or 0)
            head_objects = int(getattr(reader, "object_count", 0) or 0)
            head_len = f.offset  # the file header python-can read
            shift = 0  # file offset = f.offset + shift (a resumed reader sees the header, then the file from a container)
            n = damaged = 0
            while True:
                try:
                    for msg in reader:
                        n += 1
                        self.pos = n
                        yield msg
                    break
                except Exception as exc:  # BLFParseError, zlib.error, struct.error, ...
                    bad = f.offset + shift
                    nxt = _next_blf_container(raw, bad, size)
                    if nxt is None:
                        self.truncated = True
                        self.notes.append(f"{path}: damaged after CAN object {n} at byte {bad} of {size} "
                                          f"({type(exc).__name__}: {exc}); kept the {n} objects before it")
                        return
                    damaged += 1
                    self.notes.append(f"{path}: damaged object container before byte {bad} ({type(exc).__name__}: "
                                      f"{exc}), after CAN object {n}: its objects are lost; reading goes on at the "
                                      f"next container, byte {nxt}" + (f" ({nxt - bad} bytes skipped)" if nxt > bad else ""))
                    raw.seek(0)
                    f = _ReadWatch(_Spliced(raw.read(head_len), raw, nxt), size - nxt + head_len)
                    shift = nxt - head_len
                    reader = _resumed(self.cls(f))
            tail = getattr(reader, "_tail", b"")
            cut = []
            if head_size > size:
                cut.append(f"the header says {head_size} bytes, the file has {size}")
            elif head_size < size and head_objects == 0 and n:
                cut.append("the header was never completed (the writer did not close the file)")
            if f.short_at is not None:
                cut.append(f"the file ends inside an object at byte {f.short_at}")
            if tail and tail.strip(b"\0"):
                cut.append(f"{len(tail)} bytes of a cut-off object at the end")
            if cut:
                self.truncated = True
                self.notes.append(f"{path}: truncated: {'; '.join(cut)}; the header lists {head_objects} "
                                  f"objects, {n} CAN frame objects were read")
            elif damaged:
                self.notes.append(f"{path}: the header lists {head_objects} objects; {n} CAN frames were read around "
                                  f"{damaged} damaged container(s)")
            elif head_objects > n:
                self.notes.append(f"{path}: the header lists {head_objects} objects, {n} are CAN frames "
                                  "(python-can skips the other object types)")


def _candump_error_frame(msg, line: str):
    """The error frame of a candump line with CAN_ERR_FLAG (python-can's reader
    drops its channel, error class and data, or reads it as a data frame)."""
    import can

    _, chan, frame = line.split()[:3]
    ident, data = frame.split("#", 1)
    payload = bytes.fromhex(data) if data and data[0] not in "#Rr" else b""
    return can.Message(timestamp=msg.timestamp, arbitration_id=int(ident, 16) & 0x1FFFFFFF,
                       is_extended_id=False, is_error_frame=True, dlc=len(payload), data=payload,
                       channel=int(chan) if chan.isdigit() else chan, is_rx=msg.is_rx, check=False)


def iter_log_messages(path, problems: list[str]):
    """Yield the valid python-can messages of a log file (see :class:`LogSource`).

    Rejected lines/objects and file-level findings are appended to
    ``problems`` as ``FILE:LINE: ...`` / ``FILE: object N: ...`` texts. The
    frame rules of :func:`~wheelsoil.daq.frames.checked_batch_from_messages`
    are not applied here (:func:`import_log` applies them per batch).

    Raises:
        OSError: unreadable file. ValueError: unknown suffix.
    """
    src = LogSource(path)
    yield from src
    problems += [f"{src.where(p)}: rejected: {r}" for p, r in sorted(src.rejected)] + src.notes


# --------------------------------------------------------------------------- what a file looks like
_LOOKS_CANDUMP_L = re.compile(r"\s*\((\d+)(?:\.\d*)?\)\s+\S+\s+[0-9A-Fa-f]{3,8}#")
_LOOKS_CANDUMP_TA = re.compile(r"\s*\(\d+(?:\.\d*)?\)\s+\S+\s+[0-9A-Fa-f]{3,8}\s+\[\d+\]")
_LOOKS_CANDUMP_PLAIN = re.compile(r"\s*[A-Za-z]\w*\s+[0-9A-Fa-f]{3,8}\s+\[\d+\]")
_LOOKS_ASC = re.compile(r"\s*(?:date\s|base\s+(?:hex|dec)\b|begin\s+triggerblock\b|"
                        r"\d+\.\d+\s+\d+\s+[0-9A-Fa-f]+x?\s+(?:Rx|Tx)\b)", re.IGNORECASE)
_LOOKS_TRC = re.compile(r"\s*;\s*\$FILEVERSION\b|\s*\d+\)\s+\d+\.\d+\s+(?:Rx|Tx|DT)\b")
_FORMAT_NAMES = {".log": "a candump log", ".asc": "an ASC file", ".trc": "a TRC file"}


def format_hint(path, *, lines: int = 40) -> str | None:
    """What a text log whose lines were all rejected looks like, and what is expected instead.

    Reads at most the first 64 KiB (``lines`` non-blank lines) of ``path``. Recognises a candump
    ``-L`` log (``(seconds) can0 123#DATA``; times in milliseconds or microseconds named), candump's
    ``-ta`` output (``(seconds)  can0  123   [8]  DE AD ...``) and its default output (no time), an
    ASC and a TRC file. Returns a sentence: a file whose content is another format than its suffix
    says is told to be renamed; None when nothing is recognised or the suffix is ``.blf`` (binary).

    Raises: nothing (an unreadable file gives None).
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".blf":
        return None
    try:
        with open(path, "rb") as f:
            head = f.read(65536).decode("utf-8", errors="replace")
    except OSError:
        return None
    text = [ln for ln in head.splitlines()[:-1] or head.splitlines() if ln.strip()][:lines]
    if not text:
        return None

    def share(pattern) -> float:
        return sum(1 for ln in text if pattern.match(ln)) / len(text)

    def rename(to: str) -> str:
        return f"It looks like {_FORMAT_NAMES[to]}: rename it to {path.stem}{to}"

    expected = "wheelsoil reads candump -L lines '(1700000000.123456) can0 123#DEADBEEF' (candump -l or -L)"
    if share(_LOOKS_CANDUMP_L) >= 0.5:
        secs = [int(m.group(1)) for m in map(_LOOKS_CANDUMP_L.match, text) if m]
        big = sorted(secs)[len(secs) // 2]
        if suffix != ".log":
            return rename(".log")
        for unit, scale in (("microseconds", 1e6), ("milliseconds", 1e3)):
            if big > 1e10 and 1e8 <= big / scale < 1e10:
                return (f"Its timestamps look like {unit} since 1970 ({big} is {big / scale:.0f} s): candump -L "
                        f"writes seconds with a decimal point, '(1700000000.123456)'; convert the times to "
                        "seconds (divide by " + ("1000000" if scale == 1e6 else "1000") + ")")
        return None
    if share(_LOOKS_CANDUMP_TA) >= 0.5:
        return ("It looks like candump's -ta output (data as spaced bytes after '[DLC]'), not a candump -L log; "
                + expected + "; re-log with 'candump -L' or convert each line")
    if share(_LOOKS_CANDUMP_PLAIN) >= 0.5:
        return ("It looks like candump's default screen output, which has no timestamps: it cannot be imported; "
                + expected)
    if share(_LOOKS_ASC) >= 0.3:
        return rename(".asc") if suffix != ".asc" else None
    if share(_LOOKS_TRC) >= 0.3:
        return rename(".trc") if suffix != ".trc" else None
    return None


# --------------------------------------------------------------------------- import
def _pending_flush(w_get, bus, msgs, poss, text, rejected):
    """Check and write one bus's pending messages; rejected ones go to ``rejected`` as (pos, reason)."""
    batch, bad, reasons = checked_batch_from_messages(bus, msgs)
    for i, r in zip(bad.tolist(), reasons):
        rejected.append((poss[i], r))
    if len(batch):
        if text:
            batch.timestamp_ns = (batch.timestamp_ns + 500) // 1000 * 1000
        w_get().write_batch(batch)
    return batch


def _names_file(key: str, p: Path) -> bool:
    """Whether the ``FILE`` of a ``FILE:SRC`` channel-map key names the input ``p`` (its path as given,
    its name, or the same file)."""
    f = key.rsplit(":", 1)[0] if ":" in key else ""
    if not f:
        return False
    if f in (str(p), p.name):
        return True
    try:
        return Path(f).resolve() == p.resolve()
    except (OSError, RuntimeError):
        return False


def _file_map(cmap: Mapping[str, str], p: Path) -> dict[str, str]:
    """The ``FILE:SRC=BUS`` entries of ``cmap`` that name the input ``p``: SRC -> BUS."""
    return {k.rsplit(":", 1)[1]: v for k, v in cmap.items() if _names_file(k, p)}


def _note_ids(ids: dict, batch) -> None:
    """Add the (id, extended) pairs of ``batch``'s frames to ``ids[batch.bus]``."""
    if len(batch):
        key = batch.arbitration_id.astype(np.int64) | (batch.is_extended.astype(np.int64) << 32)
        ids.setdefault(batch.bus, set()).update((int(k) & 0xFFFFFFFF, bool(k >> 32)) for k in np.unique(key))


def _mixed_up_buses(inputs: list, file_ids: list, config) -> str | None:
    """``BUS NAMES MIXED UP`` with the ``--map`` that fixes it, when the frames an input put on a bus are, by
    most of their ids, messages the vehicle configuration has on one other bus (and on no other); None
    otherwise (or without a configuration).
    Several inputs get ``FILE:SRC=BUS`` maps (each may hold one bus: TRC 1.x files have no bus column)."""
    where: dict = {}
    try:
        for bus in config.buses:
            for m in config.database(bus).messages:
                where[(int(m.frame_id), bool(m.is_extended_frame))] = (bus, m.name)
    except Exception:  # noqa: BLE001 - only a hint depends on it
        return None
    moves, parts = [], []
    for p, ids in zip(inputs, file_ids):
        for bus, got in ids.items():
            known = [where[k] for k in got if k in where]
            targets = {b for b, _ in known}
            if len(targets) != 1 or bus in targets or 2 * len(known) < len(got):
                continue  # (a bus of other traffic sharing an id with the configuration's is no mix-up)
            to = targets.pop()
            moves.append((p, bus, to))
            parts.append(f"{p.name}: its frames on {bus} are messages configured on {to} ("
                         + ", ".join(sorted({n for _, n in known})) + ")")
    if not moves:
        return None
    several = len(inputs) > 1
    maps = " ".join(f"--map {p.name + ':' if several else ''}{bus}={to}" for p, bus, to in moves)
    return ("BUS NAMES MIXED UP: " + "; ".join(parts) + ": import with the configuration's bus names: wheelsoil "
            f"import {' '.join(str(p) for p in inputs)} -o NEW.mcap {maps}"
            + (" (FILE:SRC=BUS maps one file's channel)" if several else ""))


def import_log(inputs, output, *, channel_map: Mapping[str, str] | None = None, config=None,
               metadata: Mapping | None = None, overwrite: bool = False) -> ConvertResult:
    """Convert candump ``.log``, ``.asc``, ``.blf`` or ``.trc`` files into one MCAP recording.

    Frames keep their file order per bus. Bus names: see the module docstring;
    ``channel_map`` maps a source channel (python-can's value as text, e.g.
    ``"0"`` or ``"vcan0"``) or a default bus name to the bus name to use; a key
    ``"FILE:SRC"`` does so for the input ``FILE`` only (its path as given or its
    name: logs of one bus each, as PCAN-View writes TRC 1.x files without a bus
    column, all read as channel 1).  Frames that land on a bus whose configured
    messages they are not, while another configured bus has them all, are named
    with the ``--map`` that fixes it (``BUS NAMES MIXED UP`` in the warnings).

    Data safety: the output may not be an input; an existing output is kept
    unless ``overwrite``; the recording is written to a temporary file next to
    the output and renamed into place only when every input was read with at
    least one valid frame, so a failed import leaves nothing behind.

    Validation: every line/object is checked (:class:`LogSource` per format,
    :func:`~wheelsoil.daq.frames.checked_batch_from_messages` for the frame
    rules: hex digits, DLC vs data length, classic <= 8 bytes, CAN FD lengths,
    identifier range, finite timestamps). Invalid ones are rejected and
    counted, the first :data:`MAX_LISTED` per file are named (``FILE:LINE``, BLF:
    ``FILE: object N``) in the warnings and in the ``wheelsoil.import``
    metadata record; every valid frame is kept; a truncated file is reported.

    Provenance: a ``wheelsoil.provenance`` record of kind ``imported`` with
    ``sources`` (path, SHA-256, size of each input); the ``wheelsoil.recording``
    facts give the first frame's time as start time and ``host`` "unknown
    (imported)" (the importing host is ``imported_on_host``).

    Args:
        inputs: one path or a list of paths (appended in that order).
        output: ``.mcap`` path.
        config: :class:`VehicleConfig` to attach (None: the shipped default).
        metadata: extra ``wheelsoil.recording`` facts.
        overwrite: replace an existing ``output``.

    Returns:
        :class:`ConvertResult`: frames per bus, ``skipped`` (rejected lines and
        frames), ``truncated`` (files cut short), ``warnings``, ``record`` (the
        ``wheelsoil.import`` metadata as a dict).

    Raises:
        ValueError: unknown format; output is an input; an input given twice
            (same path or same SHA-256); an input without a single valid frame (empty, garbage, unreadable; names the file and
            the first rejected lines) - nothing is written then.
        FileExistsError: ``output`` exists and ``overwrite`` is False.
        OSError: unreadable input / unwritable output.
    """
    from .config import load_vehicle_config
    from .provenance import file_sha256, make_provenance

    if isinstance(inputs, (str, Path)):
        inputs = [inputs]
    inputs = [Path(p) for p in inputs]
    if not inputs:
        raise ValueError("import: no input file given")
    for p in inputs:
        _reader_class(p)
        if not p.is_file():
            raise OSError(f"{p}: no such file")
    out = check_output_path(output, inputs, overwrite=overwrite)
    cmap = dict(channel_map or {})
    config = load_vehicle_config() if config is None else config
    sources = [{"path": os.path.abspath(p), "sha256": file_sha256(p), "size_bytes": p.stat().st_size} for p in inputs]
    for i, (p, s) in enumerate(zip(inputs, sources)):
        for q, t in zip(inputs[:i], sources[:i]):
            if _same_file(p, q) or s["sha256"] == t["sha256"]:
                how = "the same file" if _same_file(p, q) else f"the same bytes as {q} (sha256 {s['sha256'][:16]}...)"
                raise ValueError(f"{p}: given twice ({how}): its frames would be imported twice; give each log "
                                 f"once (nothing written to {out})")
    prov = make_provenance("imported", sources=sources)
    res = ConvertResult(out)
    names: dict[object, str] = {}
    used: set[str] = set()  # the channel_map keys that named a channel of an input
    tmp = _temp_path(out)
    state: dict = {"w": None, "first_ns": None}

    def writer():
        if state["w"] is None:
            first = state["first_ns"]
            meta = {"source_files": ", ".join(str(p) for p in inputs), "created_by": "wheelsoil import",
                    "start_time_ns": str(first),
                    "start_time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(first // 10**9)),
                    "host": "unknown (imported)", "platform": "unknown (imported)",
                    "imported_on_host": prov["host"], "import_time_utc": prov["created_utc"]}
            meta.update(metadata or {})
            state["w"] = RecordingWriter(tmp, config=config, metadata=meta, fsync=False, provenance=prov)
        return state["w"]

    files_rec = []
    last_ns = None
    channels_seen: set[str] = set()  # the inputs' channels, as python-can gives them and as bus names
    file_ids: list[dict[str, set]] = []  # per input: bus -> its (id, extended) with frames
    try:
        for i_file, p in enumerate(inputs):
            fmap = _file_map(cmap, p)
            ids_here: dict[str, set] = {}
            file_ids.append(ids_here)
            src = LogSource(p)
            trc = src.suffix == ".trc"
            text = src.unit == "line"
            pending: dict[str, tuple[str, list, list]] = {}  # bus -> (bus, messages, places)
            by_channel: dict = {}  # python-can channel -> the pending entry of its bus
            rejected = src.rejected
            good = 0
            need_first = state["first_ns"] is None
            for msg in src:
                if need_first:
                    b, _, _ = checked_batch_from_messages("", [msg])
                    if len(b):
                        t = int(b.timestamp_ns[0])
                        state["first_ns"] = (t + 500) // 1000 * 1000 if text else t
                        need_first = False
                entry = by_channel.get(msg.channel)
                if entry is None:
                    ch = msg.channel
                    bus = names.get((i_file, ch))
                    if bus is None:
                        raw = ch
                        if trc and isinstance(ch, int):
                            raw = ch - 1  # python-can's TRC reader keeps the 1-based number
                        dflt = default_bus_name(raw)
                        key = next((k for k in (str(ch), dflt) if k in fmap), None)
                        if key is not None:
                            bus = fmap[key]
                            used.add(next(k for k in cmap if k.endswith(":" + key) and _names_file(k, p)))
                        else:
                            key = next((k for k in (str(ch), dflt) if k in cmap), None)
                            bus = dflt if key is None else cmap[key]
                            used.add(key)
                        names[(i_file, ch)] = bus
                        channels_seen.update((str(ch), dflt))
                    entry = by_channel[ch] = pending.setdefault(bus, (bus, [], []))
                msgs = entry[1]
                msgs.append(msg)
                entry[2].append(src.pos)
                if len(msgs) >= MAX_FRAMES_PER_MESSAGE:
                    b = _pending_flush(writer, entry[0], msgs, entry[2], text, rejected)
                    _note_ids(ids_here, b)
                    good += len(b)
                    if len(b):
                        t = int(b.timestamp_ns.max())
                        last_ns = t if last_ns is None else max(last_ns, t)
                    msgs.clear()
                    entry[2].clear()
            for bus, msgs, poss in pending.values():
                if msgs:
                    b = _pending_flush(writer, bus, msgs, poss, text, rejected)
                    _note_ids(ids_here, b)
                    good += len(b)
                    if len(b):
                        t = int(b.timestamp_ns.max())
                        last_ns = t if last_ns is None else max(last_ns, t)
            rejected.sort()
            listed = [f"{src.where(pos)}: rejected: {why}" for pos, why in rejected[:MAX_LISTED]]
            if good == 0:
                what = (f"{len(rejected)} {src.unit}(s) rejected, first: " + "; ".join(listed[:3])) if rejected \
                    else "empty"
                hint = format_hint(p)
                raise ValueError(f"{p}: no valid CAN frame in this {src.suffix} file ({what}"
                                 + (f"; {'; '.join(src.notes)}" if src.notes else "")
                                 + f"); nothing written to {out}" + (f". {hint}" if hint else ""))
            probs = listed
            if len(rejected) > MAX_LISTED:
                probs.append(f"{p}: {len(rejected)} invalid {src.unit}s rejected in all (first at "
                             f"{src.unit}s {', '.join(str(x) for x, _ in rejected[:MAX_LISTED])}); "
                             f"{good} frames imported")
            probs += src.notes
            for msg in probs:
                warnings.warn(msg, RuntimeWarning, stacklevel=2)
            res.warnings += probs
            res.skipped += len(rejected)
            if src.truncated:
                res.truncated.append(str(p))
            files_rec.append({"path": str(p), "format": src.suffix, "frames": good, "rejected": len(rejected),
                              "unit": src.unit,
                              "first_rejected": [{src.unit: pos, "reason": why} for pos, why in rejected[:MAX_LISTED]],
                              "truncated": src.truncated, "notes": src.notes})
        unused = [k for k in cmap if k not in used]
        has = ", ".join(sorted({default_bus_name(c) for c in channels_seen}))
        mixed = _mixed_up_buses(inputs, file_ids, config)
        for k in unused:
            msg = (f"--map {k}={cmap[k]}: {k} is no bus or channel of the input (it has {has}); "
                   f"nothing was mapped to {cmap[k]}")
            if ":" in k and not any(_names_file(k, q) for q in inputs):
                msg = (f"--map {k}={cmap[k]}: no input is named {k.rsplit(':', 1)[0]} (FILE:SRC=BUS maps the "
                       f"channel SRC of the input FILE only); nothing was mapped to {cmap[k]}")
            warnings.warn(msg, RuntimeWarning, stacklevel=2)
            res.warnings.append(msg)
        if mixed:
            warnings.warn(mixed, RuntimeWarning, stacklevel=2)
            res.warnings.append(mixed)
        w = writer()
        res.record = {"frames": sum(f["frames"] for f in files_rec), "rejected": res.skipped,
                      "truncated": bool(res.truncated), "files": files_rec}
        w.add_metadata(IMPORT_RECORD, {k: json.dumps(v, sort_keys=True) for k, v in res.record.items()})
        res.frames = dict(w.frame_counts)
        w.summary["import_warnings"] = res.warnings[:100]
        if last_ns is not None:
            w.summary["end_time_ns"] = str(last_ns)
        w.close()
        _commit(tmp, out, overwrite)
    except BaseException:
        w = state["w"]
        if w is not None:
            try:  # a writer that can abort drops its file; else close it, the file is removed below
                (getattr(w, "abort", None) or w.close)()
            except Exception:  # noqa: BLE001 - the original error matters
                pass
        _discard(tmp)
        raise
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


def export_recording(path, output, *, channel_map: Mapping[str, str] | None = None, buses=None,
                     overwrite: bool = False) -> ConvertResult:
    """Write the raw frames of an MCAP recording to ``.log``/``.asc``/``.blf``/``.trc``
    with python-can's writers (:func:`can.Logger`), all buses merged by time.

    Identifiers, flags, DLC and data are bit-exact; timestamps are written as
    the format allows (candump ``.log``: microseconds, absolute). The file is
    written under a temporary name next to ``output`` and renamed into place
    when complete; on any error nothing is left behind and an existing
    ``output`` is untouched.

    Args:
        channel_map: bus name -> channel written (default: the bus name).
        buses: bus names to export (None: all).
        overwrite: replace an existing ``output``.

    Raises:
        ValueError: unknown output suffix; ``output`` is the recording itself.
        FileExistsError: ``output`` exists and ``overwrite`` is False.
        OSError: unreadable/unwritable files. RecordingError: not an MCAP file.
    """
    import can

    out = Path(output)
    if out.suffix.lower() not in FORMATS:
        raise ValueError(f"{out}: unknown output format {out.suffix!r}; export writes {', '.join(FORMATS)}")
    out = check_output_path(out, [path], overwrite=overwrite)
    res = ConvertResult(out)
    counts: dict[str, int] = {}
    rev = {v: k for k, v in (channel_map or {}).items()}
    trc = out.suffix.lower() == ".trc"
    tmp = _temp_path(out)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", RuntimeWarning)
            with can.Logger(str(tmp)) as writer:
                for msg in iter_merged_messages(path, channel_map=channel_map, buses=buses):
                    if trc and (msg.is_remote_frame or msg.is_error_frame or msg.is_fd):
                        res.skipped += 1  # python-can's TRC writer drops these (with a log line each)
                        continue
                    writer.on_message_received(msg)
                    bus = rev.get(msg.channel, msg.channel)
                    counts[bus] = counts.get(bus, 0) + 1
        _commit(tmp, out, overwrite)
    except BaseException:
        _discard(tmp)
        raise
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
        ValueError: output is the input; no frame could be read (nothing is written).
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
        if not any(w.frame_counts.values()):
            raise ValueError(f"{path}: no CAN frame could be read ("
                             + ("; ".join(state.warnings) or "the recording holds none") + "); nothing written")
        for st, t in zip(state.statuses, state.status_times):
            w.write_status(st, time_ns=t)
        if note is not None:
            w.add_metadata(note[0], dict(note[1], source_file=str(path), source_complete=str(state.complete),
                                         damage="; ".join(state.warnings) or "none",
                                         damage_json=json.dumps(getattr(state, "damage", []))))
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
        ValueError: no frame could be read (nothing is written).
    """
    return rewrite_recording(path, output, note=("wheelsoil.recovered", {}))
