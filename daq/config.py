"""Vehicle configuration: which DBC is on which bus, which signal is which quantity.

The default configuration ships as ``wheelsoil/dbc/vehicle.toml`` (package
``wheelsoil.dbc``); a user with other hardware edits a copy of that one file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

#: Physical quantities every vehicle configuration maps (architecture.md).
REQUIRED_SIGNALS = (
    "wft_fx_w", "wft_fy_w", "wft_fz_w", "wft_my", "wft_angle",
    "wft_counter_force", "wft_counter_moment", "wft_counter_angle",
    "wheel_speed", "gnss_speed", "gnss_forward_velocity", "gnss_time_week", "gnss_time_tow",
)

#: Factor to SI for units a user may write without ``scale_to_si``.
UNIT_TO_SI = {
    "": 1.0, "-": 1.0, "1": 1.0, "N": 1.0, "kN": 1e3, "N.m": 1.0, "Nm": 1.0, "N*m": 1.0,
    "kN.m": 1e3, "rad": 1.0, "deg": math.pi / 180.0, "rad/s": 1.0, "rpm": 2.0 * math.pi / 60.0,
    "deg/s": math.pi / 180.0, "m/s": 1.0, "km/h": 1.0 / 3.6, "kph": 1.0 / 3.6, "mph": 0.44704,
    "s": 1.0, "ms": 1e-3, "m": 1.0, "mm": 1e-3, "week": 1.0,
}


@dataclass(frozen=True)
class SignalRef:
    """Where one physical quantity is on the buses.

    Attributes:
        bus: bus name (key of :attr:`VehicleConfig.buses`).
        message: DBC message name.
        signal: DBC signal name in that message.
        unit: unit of the DBC's physical value.
        scale_to_si: multiply the DBC physical value by this to get SI
            (N, N.m, rad, rad/s, m/s, s); from the TOML or from :data:`UNIT_TO_SI`.
    """

    bus: str
    message: str
    signal: str
    unit: str
    scale_to_si: float = 1.0


@dataclass
class VehicleConfig:
    """A vehicle configuration (see ``dbc/vehicle.toml``).

    Attributes:
        buses: bus name -> DBC files (absolute paths) on that bus.
        signals: quantity key (:data:`REQUIRED_SIGNALS` and any extra) -> :class:`SignalRef`.
        wheel_radius_m: rolling radius r of the instrumented wheel [m].
        wheel_width_m: wheel width b [m].
        name: free text.
        bus_options: bus name -> the other keys of its TOML table (bitrate, description).
        source: the TOML file it was loaded from (None if built in code).
        text: the TOML text (stored in recordings as an attachment).
    """

    buses: dict[str, list[Path]]
    signals: dict[str, SignalRef]
    wheel_radius_m: float = 0.47
    wheel_width_m: float = 0.32
    name: str = ""
    bus_options: dict[str, dict] = field(default_factory=dict)
    source: Path | None = None
    text: str = ""
    _dbs: dict = field(default_factory=dict, repr=False, compare=False)
    _texts: dict = field(default_factory=dict, repr=False, compare=False)

    def database(self, bus: str):
        """The cantools database of all DBC files on ``bus`` (cached).

        Raises:
            KeyError: unknown bus.
            ValueError: a DBC file that cantools cannot parse (names the file).
            OSError: a DBC file that cannot be read.
        """
        if bus not in self._dbs:
            self._dbs[bus] = load_dbc_files(self.buses[bus])
        return self._dbs[bus]

    def message_names(self, bus: str) -> dict[tuple[int, bool], str]:
        """(frame id, is_extended) -> DBC message name for ``bus`` ({} for a bus not configured)."""
        if bus not in self.buses:
            return {}
        return {(m.frame_id, bool(m.is_extended_frame)): m.name for m in self.database(bus).messages}

    def dbc_texts(self) -> dict[str, str]:
        """DBC file name -> its text, for every DBC of every bus (for recordings)."""
        out = {}
        for paths in self.buses.values():
            for p in paths:
                if p.name not in self._texts:
                    self._texts[p.name] = Path(p).read_text(encoding="utf-8", errors="replace")
                out[p.name] = self._texts[p.name]
        return out

    def counter_specs(self) -> list[tuple[str, int, bool, int, int]]:
        """Sample counters to watch for gaps: (bus, frame id, is_extended, byte, modulo).

        From the ``wft_counter_*`` signals: each must be an unsigned little-endian
        signal that starts on a byte boundary and is at most 8 bits long (the
        logger reads one byte per frame and masks it); modulo = 2**length.

        Raises:
            ValueError: a counter signal that is not byte-aligned (names it).
        """
        specs = []
        for key, ref in sorted(self.signals.items()):
            if not key.startswith("wft_counter"):
                continue
            msg = self.database(ref.bus).get_message_by_name(ref.message)
            sig = msg.get_signal_by_name(ref.signal)
            if sig.start % 8 or sig.length > 8 or sig.byte_order != "little_endian" or sig.is_signed:
                raise ValueError(
                    f"{self.source}: [signals.{key}] counter {ref.message}.{ref.signal} must be an "
                    "unsigned little-endian signal of <= 8 bits starting on a byte boundary")
            specs.append((ref.bus, msg.frame_id, bool(msg.is_extended_frame), sig.start // 8,
                          1 << sig.length))
        return specs


def default_vehicle_path() -> Path:
    """Path of the shipped ``vehicle.toml`` (package ``wheelsoil.dbc``)."""
    from importlib.resources import files

    return Path(str(files("wheelsoil.dbc") / "vehicle.toml"))


def load_dbc_files(paths) -> "object":
    """Parse DBC files into one cantools database.

    Raises:
        OSError: a file that cannot be read.
        ValueError: a file cantools cannot parse, naming the file and the parser's message.
    """
    import cantools

    db = cantools.database.Database()
    for p in paths:
        text = Path(p).read_text(encoding="utf-8", errors="replace")
        try:
            db.add_dbc_string(text)
        except Exception as exc:  # cantools raises several parser error types
            raise ValueError(f"{p}: cannot parse DBC file: {exc}") from None
    return db


def load_vehicle_config(path: str | Path | None = None, *, check_dbc: bool = True) -> VehicleConfig:
    """Load a vehicle configuration TOML (None = the shipped ``dbc/vehicle.toml``).

    DBC paths in the file are relative to the file. With ``check_dbc`` every DBC
    is parsed and every signal reference checked against it.

    Raises:
        OSError: the TOML or a DBC cannot be read.
        ValueError: bad TOML, a missing/invalid key, an unknown unit without
            ``scale_to_si``, an unparsable DBC, or a message/signal not in the
            bus's DBCs; the message names the file and the TOML key.
    """
    src = default_vehicle_path() if path is None else Path(path)
    text = src.read_text(encoding="utf-8")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{src}: not valid TOML: {exc}") from None
    return vehicle_config_from_dict(doc, source=src, text=text, check_dbc=check_dbc)


def vehicle_config_from_dict(doc: Mapping, *, source: Path | None = None, text: str = "",
                             check_dbc: bool = True) -> VehicleConfig:
    """Build a :class:`VehicleConfig` from the parsed TOML mapping (see :func:`load_vehicle_config`)."""
    where = str(source) if source else "vehicle config"
    base = source.parent if source else Path.cwd()
    veh = doc.get("vehicle", {})
    try:
        radius = float(veh.get("wheel_radius_m", 0.47))
        width = float(veh.get("wheel_width_m", 0.32))
    except (TypeError, ValueError):
        raise ValueError(f"{where}: [vehicle] wheel_radius_m / wheel_width_m must be numbers") from None
    if not (radius > 0 and width > 0):
        raise ValueError(f"{where}: [vehicle] wheel_radius_m and wheel_width_m must be > 0")

    buses: dict[str, list[Path]] = {}
    bus_options: dict[str, dict] = {}
    raw_buses = doc.get("buses")
    if not isinstance(raw_buses, Mapping) or not raw_buses:
        raise ValueError(f"{where}: needs a [buses.<name>] table with dbc = [...] per bus")
    for name, tab in raw_buses.items():
        dbcs = tab.get("dbc") if isinstance(tab, Mapping) else None
        if isinstance(dbcs, str):
            dbcs = [dbcs]
        if not isinstance(dbcs, list) or not all(isinstance(d, str) for d in dbcs):
            raise ValueError(f"{where}: [buses.{name}] dbc must be a list of file names")
        buses[name] = [(base / d).resolve() for d in dbcs]
        bus_options[name] = {k: v for k, v in tab.items() if k != "dbc"}

    signals: dict[str, SignalRef] = {}
    raw_signals = doc.get("signals", {})
    for key in REQUIRED_SIGNALS:
        if key not in raw_signals:
            raise ValueError(f"{where}: missing [signals.{key}] (needed: {', '.join(REQUIRED_SIGNALS)})")
    for key, tab in raw_signals.items():
        if not isinstance(tab, Mapping):
            raise ValueError(f"{where}: [signals.{key}] must be a table")
        missing = [k for k in ("bus", "message", "signal") if k not in tab]
        if missing:
            raise ValueError(f"{where}: [signals.{key}] lacks {', '.join(missing)}")
        if tab["bus"] not in buses:
            raise ValueError(f"{where}: [signals.{key}] bus {tab['bus']!r} is not in [buses] "
                             f"({', '.join(buses)})")
        unit = str(tab.get("unit", ""))
        if "scale_to_si" in tab:
            try:
                scale = float(tab["scale_to_si"])
            except (TypeError, ValueError):
                raise ValueError(f"{where}: [signals.{key}] scale_to_si must be a number") from None
        elif unit in UNIT_TO_SI:
            scale = UNIT_TO_SI[unit]
        else:
            raise ValueError(f"{where}: [signals.{key}] unit {unit!r} is unknown; give scale_to_si "
                             f"(known units: {', '.join(u for u in UNIT_TO_SI if u)})")
        signals[key] = SignalRef(str(tab["bus"]), str(tab["message"]), str(tab["signal"]), unit, scale)

    cfg = VehicleConfig(buses=buses, signals=signals, wheel_radius_m=radius, wheel_width_m=width,
                        name=str(veh.get("name", "")), bus_options=bus_options, source=source, text=text)
    if check_dbc:
        for key, ref in signals.items():
            db = cfg.database(ref.bus)
            try:
                msg = db.get_message_by_name(ref.message)
            except KeyError:
                raise ValueError(f"{where}: [signals.{key}] message {ref.message!r} is not in the DBC "
                                 f"files of bus {ref.bus} ({', '.join(p.name for p in buses[ref.bus])})") from None
            if ref.signal not in [s.name for s in msg.signals]:
                raise ValueError(f"{where}: [signals.{key}] message {ref.message} has no signal "
                                 f"{ref.signal!r} (it has {', '.join(s.name for s in msg.signals)})")
    return cfg
