"""Summary of a recording: channels, frame counts per id, duration, losses."""

from __future__ import annotations

import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from .frames import DuplicateFrames, duplicate_frames_warning
from .provenance import PROVENANCE_RECORD, provenance_from_metadata
from .recording import ReadReport, _iter_records
from .stats import FrameStats, StatsAccumulator, TimeBaseAccumulator


@dataclass
class RecordingInfo:
    """What :func:`read_recording_info` found in a recording.

    Attributes:
        path: the file.
        size_bytes: file size.
        complete: the MCAP footer was read (False: truncated, e.g. power cut).
        warnings: damage found while reading (file and byte offset).
        metadata: MCAP metadata records by name (``wheelsoil.recording``,
            ``wheelsoil.summary`` when the logger closed cleanly).
        attachments: attachment names (``vehicle.toml``, ``dbc/<file>``).
        channels: one dict per MCAP channel (topic, encoding, schema, metadata).
        stats: :class:`~wheelsoil.daq.stats.FrameStats` of all frames.
        status: the logger's last per-second status record (or None).
        config_source: where DBC names/lengths/counters came from.
        damage: damaged places skipped by the reader (see
            :class:`~wheelsoil.daq.recording.ReadReport`): file, byte offset, kind,
            frames lost (None = unknown), time span.
        time: the robust time base (:meth:`TimeBaseAccumulator.result
            <wheelsoil.daq.stats.TimeBaseAccumulator.result>`): true first/last
            time, outlier timestamps (count, examples), backward steps per bus.
        footer: the MCAP footer was read (the writer closed the file).
        duplicates: bus -> exact copies of frames (same id, flags, data and timestamp: logged twice)
            dropped before counting (:class:`~wheelsoil.daq.frames.DuplicateFrames`); ``stats`` does
            not count them.
    """

    path: Path
    size_bytes: int
    complete: bool
    warnings: list[str]
    metadata: dict
    attachments: list[str]
    channels: list[dict]
    stats: FrameStats
    status: dict | None = None
    config_source: str = ""
    extra: dict = field(default_factory=dict)
    damage: list = field(default_factory=list)
    time: dict = field(default_factory=dict)
    footer: bool = False
    duplicates: dict = field(default_factory=dict)

    @property
    def buses(self) -> list[str]:
        """Bus names with frames, sorted."""
        return sorted(self.stats.frames)

    @property
    def start_ns(self) -> int | None:
        """True first frame receive time [ns]: the earliest of the run, outlier
        timestamps excluded (not the first frame in file order). None: no frames."""
        if self.time.get("first_ns") is not None:
            return self.time["first_ns"]
        return min(self.stats.first_ns.values()) if self.stats.first_ns else None

    @property
    def end_ns(self) -> int | None:
        """True last frame receive time [ns] (outliers excluded; None: no frames)."""
        if self.time.get("last_ns") is not None:
            return self.time["last_ns"]
        return max(self.stats.last_ns.values()) if self.stats.last_ns else None

    @property
    def duration_s(self) -> float:
        """Time from the true first to the true last frame [s] (outliers excluded)."""
        return 0.0 if self.start_ns is None else (self.end_ns - self.start_ns) / 1e9

    @property
    def outlier_frames(self) -> int:
        """Frames whose timestamps lie far outside the run (excluded from the duration)."""
        return int((self.time.get("outliers") or {}).get("frames", 0))

    @property
    def non_monotonic(self) -> dict[str, int]:
        """Bus -> backward time steps in file order (e.g. two logs joined out of order)."""
        return dict(self.time.get("backward_steps") or {})

    @property
    def frames_lost_to_damage(self) -> int | None:
        """Frames in damaged chunks that were skipped (None: unknown for some place)."""
        if any(d.get("frames_lost") is None for d in self.damage):
            return None
        return int(sum(d["frames_lost"] for d in self.damage))

    @property
    def provenance(self) -> dict | None:
        """The ``wheelsoil.provenance`` record (see :mod:`wheelsoil.daq.provenance`), None if absent."""
        return provenance_from_metadata(self.metadata.get(PROVENANCE_RECORD))

    def rx_dropped(self) -> dict[str, int]:
        """Kernel receive-queue drops per bus as last recorded by the logger ({} if unknown)."""
        buses = (self.status or {}).get("buses", {})
        return {b: int(v.get("rx_dropped") or 0) for b, v in buses.items() if v.get("rx_dropped") is not None}

    def to_dict(self) -> dict:
        """JSON-ready dict (ids as hex strings, names from the DBCs)."""
        s = self.stats

        def ids(d, bus):
            names = s.names.get(bus, {})
            return {_idstr(k): ({"frames": v, "message": names[k]} if k in names else {"frames": v})
                    for k, v in sorted(d.items())}

        return {
            "path": str(self.path), "size_bytes": self.size_bytes, "complete": self.complete,
            "footer": self.footer, "damage": self.damage, "frames_lost_to_damage": self.frames_lost_to_damage,
            "warnings": self.warnings, "start_ns": self.start_ns, "end_ns": self.end_ns,
            "duration_s": self.duration_s, "time": self.time, "outlier_frames": self.outlier_frames,
            "non_monotonic": self.non_monotonic, "channels": self.channels, "attachments": self.attachments,
            "metadata": self.metadata, "config_source": self.config_source, "provenance": self.provenance,
            "buses": {bus: {
                "frames": s.frames[bus],
                "first_ns": self.time.get("first_ns_by_bus", {}).get(bus, s.first_ns[bus]),
                "last_ns": self.time.get("last_ns_by_bus", {}).get(bus, s.last_ns[bus]),
                "error_frames": s.error_frames.get(bus, 0), "remote_frames": s.remote_frames.get(bus, 0),
                "ids": ids(s.id_counts.get(bus, {}), bus),
                "unknown_ids": {_idstr(k): v for k, v in sorted(s.unknown_ids.get(bus, {}).items())},
                "dlc_mismatch": ids(s.dlc_mismatch.get(bus, {}), bus),
                "rx_dropped": self.rx_dropped().get(bus),
            } for bus in self.buses},
            "duplicate_frames": dict(self.duplicates),
            "lost_frames": s.lost_frames, "counter_duplicates": s.counter_duplicates,
            "counter_stride": s.counter_stride,
            "lost_frames_estimated": s.lost_frames_estimated, "long_gaps": s.long_gaps,
            "logger_status": self.status,
        }


def _idstr(k) -> str:
    fid, ext = k
    return f"0x{fid:08X}x" if ext else f"0x{fid:03X}"


def load_recording_config(path):
    """The :class:`VehicleConfig` attached to a recording (None if it has none).

    Reads only the start of the file (works on truncated files).

    Raises:
        OSError: unreadable file. ValueError: not an MCAP file, or invalid attached TOML/DBC.
    """
    from .recording import read_attachments

    atts = read_attachments(path)
    try:
        return config_from_attachments(atts)
    except ValueError as exc:
        raise ValueError(f"{path}: {exc}") from None


def config_from_attachments(attachments: dict[str, bytes]):
    """Rebuild the :class:`VehicleConfig` a recording was made with from its
    ``vehicle.toml`` and ``dbc/*`` attachments (None if they are missing).

    DBC paths in the TOML are replaced by the attached files: ``dbc/<bus>/<name>``
    (same file name on several buses) or ``dbc/<name>`` (older recordings, and
    names used once).

    Raises:
        ValueError: the attached TOML/DBC files are invalid (names the attachment).
    """
    try:
        return _config_from_attachments(attachments)
    except ValueError:
        raise
    except Exception as exc:  # noqa: BLE001 - a malformed attachment must not abort a reader
        raise ValueError(f"attached vehicle configuration: {type(exc).__name__}: {exc}") from None


def _config_from_attachments(attachments: dict[str, bytes]):
    from .config import read_dbc_text, tomllib, vehicle_config_from_dict

    if "vehicle.toml" not in attachments:
        return None
    try:
        text = attachments["vehicle.toml"].decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"attachment vehicle.toml: not UTF-8 text ({exc})") from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"attachment vehicle.toml: invalid TOML ({exc})") from None
    if not isinstance(doc.get("buses"), dict):
        raise ValueError("attachment vehicle.toml: no [buses] table")
    with tempfile.TemporaryDirectory(prefix="wheelsoil-cfg-") as tmp:
        tmpd = Path(tmp)
        for name, data in attachments.items():
            if not name.startswith("dbc/"):
                continue
            parts = [p for p in name[4:].split("/") if p not in ("", ".", "..")]
            if not parts:
                continue
            dest = tmpd.joinpath(*[_safe_name(p) for p in parts])
            dest.parent.mkdir(parents=True, exist_ok=True)
            dest.write_bytes(data)
        for bus, tab in doc["buses"].items():
            if not isinstance(tab, dict):
                raise ValueError(f"attachment vehicle.toml: [buses.{bus}] is not a table")
            d = tab.get("dbc", [])
            names = [Path(str(x)).name for x in ([d] if isinstance(d, str) else d)]
            # dbc/<bus>/<name> (a name used on several buses) before dbc/<name>
            files = [f"{_safe_name(str(bus))}/{_safe_name(n)}" for n in names]
            files = [f if (tmpd / f).is_file() else _safe_name(n) for f, n in zip(files, names)]
            missing = [f for f in files if not (tmpd / f).is_file()]
            if missing:
                raise ValueError(f"attachment vehicle.toml: bus {bus} needs {', '.join(missing)}, "
                                 "not attached to the recording")
            tab["dbc"] = files
        cfg = vehicle_config_from_dict(doc, source=tmpd / "vehicle.toml", text=text)
        by_path = {}
        for bus in cfg.buses:
            try:
                cfg.database(bus)  # parse now, the files vanish with the directory
            except Exception as exc:  # cantools raises many kinds on a broken DBC
                raise ValueError(f"attachment DBC of bus {bus}: {type(exc).__name__}: {exc}") from None
            for p in cfg.buses[bus]:
                by_path[str(p)] = read_dbc_text(p)
        cfg.dbc_texts()
    cfg._dbc_texts_by_path = by_path  # what the writer embeds when this config is written again
    cfg.source = None
    return cfg


def _safe_name(s: str) -> str:
    """A file-name component without path separators or control characters."""
    s = "".join(c if (c.isprintable() and c not in "/\\:") else "_" for c in s)
    return s.strip(". ") or "_"


def _recording_config(path, state):
    from .config import load_vehicle_config

    try:
        cfg = config_from_attachments(state.attachments)
        if cfg is not None:
            return cfg, "recording attachments"
    except Exception as exc:  # noqa: BLE001 - any malformed attachment: fall back, say so
        msg = (f"{path}: the vehicle configuration attached to the recording is unusable "
               f"({exc}); using the default vehicle.toml instead")
        state.warnings.append(msg)
        warnings.warn(msg, RuntimeWarning, stacklevel=3)
    return load_vehicle_config(), "default vehicle.toml"


def read_recording_info(path, *, config=None) -> RecordingInfo:
    """Read a whole recording and summarise it (counts per id with DBC names,
    true duration, outlier timestamps, backward time steps, lost frames from
    counter gaps, unknown ids, DLC mismatches, damaged chunks, provenance).

    Args:
        path: ``.mcap`` recording; damage (a chunk failing its CRC, a truncation)
            is skipped and listed in ``warnings`` and ``damage``.
        config: :class:`~wheelsoil.daq.config.VehicleConfig` for DBC names and
            counters; None: the configuration attached to the recording (an
            unusable one falls back to the shipped default with a warning naming
            the recording), else the shipped default.

    Raises:
        OSError: unreadable file. RecordingError (ValueError): not an MCAP file.
    """
    state = ReadReport()
    source = "given"
    acc = StatsAccumulator(config) if config is not None else None
    tb = TimeBaseAccumulator()
    copies = DuplicateFrames()  # counted as processing counts them: dropped
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for b in _iter_records(path, state, recover=True, with_status=True):
            if acc is None:  # attachments precede the frames in our files
                config, source = _recording_config(path, state)
                acc = StatsAccumulator(config)
            b = copies(b)
            acc.update(b)
            tb.update(b)
        if acc is None:
            config, source = _recording_config(path, state)
            acc = StatsAccumulator(config)
    time_base = tb.result()
    if copies.total:
        state.warnings.append(duplicate_frames_warning(path, copies.dropped)
                              + "; not counted in the frames and losses below")
    n_out = time_base["outliers"]["frames"]
    if n_out:
        ex = ", ".join(f"{e['bus']} frame {e['frame']} at {_fmt_ns(e['t_ns'])}"
                       for e in time_base["outliers"]["examples"][:3])
        state.warnings.append(f"{path}: {n_out} frame(s) with timestamps far outside the run "
                              f"({ex}); excluded from the first/last time and the duration")
    for bus, nb in sorted(time_base["backward_steps"].items()):
        fb = time_base["first_backward"].get(bus) or {}
        state.warnings.append(
            f"{path}: bus {bus}: time goes backwards {nb} time(s) in file order (first at frame "
            f"{fb.get('frame')}, largest step back {time_base['max_backward_s'][bus]:.6g} s): "
            "logs joined out of order?")
    return RecordingInfo(
        path=Path(path), size_bytes=state.size, complete=state.complete, warnings=state.warnings,
        metadata=state.metadata, attachments=sorted(state.attachments),
        channels=[dict(v, id=k) for k, v in sorted(state.channels.items())], stats=acc.stats,
        status=state.statuses[-1] if state.statuses else None, config_source=source,
        damage=list(state.damage), time=time_base, footer=state.footer, duplicates=dict(copies.dropped))


def _fmt_ns(t: int) -> str:
    """UTC time of a ns timestamp, or the raw number when it is out of range."""
    import time as _t

    try:
        if not 0 <= t < 32503680000 * 10**9:
            raise ValueError
        return _t.strftime("%Y-%m-%dT%H:%M:%S", _t.gmtime(t / 1e9)) + f".{(t // 1000) % 10**6:06d}Z"
    except (ValueError, OverflowError, OSError):
        return f"{t} ns"
