"""Summary of a recording: channels, frame counts per id, duration, losses."""

from __future__ import annotations

import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from .provenance import PROVENANCE_RECORD, provenance_from_metadata
from .recording import _iter_records, _Records
from .stats import FrameStats, StatsAccumulator


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

    @property
    def buses(self) -> list[str]:
        """Bus names with frames, sorted."""
        return sorted(self.stats.frames)

    @property
    def start_ns(self) -> int | None:
        """Earliest frame receive time [ns] (None: no frames)."""
        return min(self.stats.first_ns.values()) if self.stats.first_ns else None

    @property
    def end_ns(self) -> int | None:
        """Latest frame receive time [ns] (None: no frames)."""
        return max(self.stats.last_ns.values()) if self.stats.last_ns else None

    @property
    def duration_s(self) -> float:
        """Time from the first to the last frame [s]."""
        return 0.0 if self.start_ns is None else (self.end_ns - self.start_ns) / 1e9

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
            "warnings": self.warnings, "start_ns": self.start_ns, "end_ns": self.end_ns,
            "duration_s": self.duration_s, "channels": self.channels, "attachments": self.attachments,
            "metadata": self.metadata, "config_source": self.config_source, "provenance": self.provenance,
            "buses": {bus: {
                "frames": s.frames[bus], "first_ns": s.first_ns[bus], "last_ns": s.last_ns[bus],
                "error_frames": s.error_frames.get(bus, 0), "remote_frames": s.remote_frames.get(bus, 0),
                "ids": ids(s.id_counts.get(bus, {}), bus),
                "unknown_ids": {_idstr(k): v for k, v in sorted(s.unknown_ids.get(bus, {}).items())},
                "dlc_mismatch": ids(s.dlc_mismatch.get(bus, {}), bus),
                "rx_dropped": self.rx_dropped().get(bus),
            } for bus in self.buses},
            "lost_frames": s.lost_frames, "counter_duplicates": s.counter_duplicates,
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

    return config_from_attachments(read_attachments(path))


def config_from_attachments(attachments: dict[str, bytes]):
    """Rebuild the :class:`VehicleConfig` a recording was made with from its
    ``vehicle.toml`` and ``dbc/*`` attachments (None if they are missing).

    DBC paths in the TOML are replaced by the attached files of the same name.

    Raises:
        ValueError: the attached TOML/DBC files are invalid.
    """
    from .config import tomllib, vehicle_config_from_dict

    if "vehicle.toml" not in attachments:
        return None
    text = attachments["vehicle.toml"].decode("utf-8", "replace")
    doc = tomllib.loads(text)
    with tempfile.TemporaryDirectory(prefix="wheelsoil-cfg-") as tmp:
        for name, data in attachments.items():
            if name.startswith("dbc/"):
                (Path(tmp) / Path(name).name).write_bytes(data)
        for tab in doc.get("buses", {}).values():
            d = tab.get("dbc", [])
            tab["dbc"] = [Path(x).name for x in ([d] if isinstance(d, str) else d)]
        cfg = vehicle_config_from_dict(doc, source=Path(tmp) / "vehicle.toml", text=text)
        for bus in cfg.buses:
            cfg.database(bus)  # parse now, the files vanish with the directory
        cfg.dbc_texts()
    cfg.source = None
    return cfg


def _recording_config(path, state):
    from .config import load_vehicle_config

    try:
        cfg = config_from_attachments(state.attachments)
        if cfg is not None:
            return cfg, "recording attachments"
    except ValueError as exc:
        state.warnings.append(f"{path}: attached vehicle configuration unusable ({exc}); using the default")
    return load_vehicle_config(), "default vehicle.toml"


def read_recording_info(path, *, config=None) -> RecordingInfo:
    """Read a whole recording and summarise it (counts per id with DBC names,
    duration, lost frames from counter gaps, unknown ids, DLC mismatches).

    Args:
        path: ``.mcap`` recording; a truncated one is read up to the damage,
            which is listed in ``warnings``.
        config: :class:`~wheelsoil.daq.config.VehicleConfig` for DBC names and
            counters; None: the configuration attached to the recording, else
            the shipped default.

    Raises:
        OSError: unreadable file. RecordingError (ValueError): not an MCAP file.
    """
    state = _Records()
    source = "given"
    acc = StatsAccumulator(config) if config is not None else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for b in _iter_records(path, state, recover=True, with_status=True):
            if acc is None:  # attachments precede the frames in our files
                config, source = _recording_config(path, state)
                acc = StatsAccumulator(config)
            acc.update(b)
    if acc is None:
        config, source = _recording_config(path, state)
        acc = StatsAccumulator(config)
    return RecordingInfo(
        path=Path(path), size_bytes=state.size, complete=state.complete, warnings=state.warnings,
        metadata=state.metadata, attachments=sorted(state.attachments),
        channels=[dict(v, id=k) for k, v in sorted(state.channels.items())], stats=acc.stats,
        status=state.statuses[-1] if state.statuses else None, config_source=source)
