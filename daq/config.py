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

#: Dimension of each unit of :data:`UNIT_TO_SI` (to compare a TOML unit with the DBC's).
UNIT_DIMENSION = {
    "": "1", "-": "1", "1": "1", "N": "force", "kN": "force", "N.m": "moment", "Nm": "moment",
    "N*m": "moment", "kN.m": "moment", "rad": "angle", "deg": "angle", "rad/s": "angular speed",
    "rpm": "angular speed", "deg/s": "angular speed", "m/s": "speed", "km/h": "speed", "kph": "speed",
    "mph": "speed", "s": "time", "ms": "time", "m": "length", "mm": "length", "week": "1",
}

#: Other spellings of units found in DBC files (normalised before comparison).
UNIT_ALIASES = {"nm": "N.m", "n.m": "N.m", "n*m": "N.m", "n m": "N.m", "°": "deg", "degree": "deg",
                "degrees": "deg", "1/min": "rpm", "u/min": "rpm", "min-1": "rpm", "km/h": "km/h",
                "kmh": "km/h", "m/sec": "m/s", "sec": "s", "rad/sec": "rad/s", "kn": "kN"}

#: Plausible ranges of the ``[vehicle]`` numbers: key -> (low, high, unit, hint for a value
#: outside). Source: hardware.md (r = 0.47 m, b = 0.32 m, m_w = 80 kg, I_w = 11.5 kg m^2) and
#: the sizes of wheels on single-wheel testbeds (r from 0.05 m) up to large tractor tyres.
VEHICLE_RANGES = {
    "wheel_radius_m": (0.05, 2.0, "m", "radius"),
    "wheel_width_m": (0.02, 1.5, "m", "width"),
    "wheel_mass_kg": (0.0, 2000.0, "kg", "wheel mass (rim + tyre outboard of the WFT)"),
    "wheel_inertia_kgm2": (0.0, 1000.0, "kg m^2", "polar moment of inertia about the axle"),
}

#: hardware.md defaults of the wheel outboard of the WFT (used when the TOML omits them).
DEFAULT_WHEEL_MASS_KG = 80.0
DEFAULT_WHEEL_INERTIA_KGM2 = 11.5


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
        cycle_time_s: nominal period of the message [s] from the TOML's
            ``cycle_time_s`` (None: not given; see :meth:`VehicleConfig.cycle_time_s`).
    """

    bus: str
    message: str
    signal: str
    unit: str
    scale_to_si: float = 1.0
    cycle_time_s: float | None = None


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
        wheel_mass_kg: mass m_w of the wheel assembly outboard of the WFT (rim + tyre) [kg].
        wheel_inertia_kgm2: its polar moment of inertia I_w about the axle [kg m^2]
            (hardware.md: the WFT measures ``Fx = Dp - m_w dV/dt``, ``My = T + I_w domega/dt``).
        notes: sentences about defaults used (e.g. a key the TOML omits); without the
            file name, which the consumer prefixes (a recording's embedded TOML has no path).
    """

    buses: dict[str, list[Path]]
    signals: dict[str, SignalRef]
    wheel_radius_m: float = 0.47
    wheel_width_m: float = 0.32
    name: str = ""
    bus_options: dict[str, dict] = field(default_factory=dict)
    source: Path | None = None
    text: str = ""
    wheel_mass_kg: float = DEFAULT_WHEEL_MASS_KG
    wheel_inertia_kgm2: float = DEFAULT_WHEEL_INERTIA_KGM2
    notes: list = field(default_factory=list)
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
                    self._texts[p.name] = read_dbc_text(p)
                out[p.name] = self._texts[p.name]
        return out

    def cycle_time_s(self, bus: str, message: str) -> tuple[float | None, str]:
        """Nominal period [s] of ``message`` on ``bus`` and where it comes from.

        A ``cycle_time_s`` on any ``[signals.*]`` table of that message wins;
        else the DBC's ``GenMsgCycleTime`` attribute (cantools ``Message.cycle_time``,
        ms); else ``(None, "unknown")``. Returns ``(period_s or None, source text)``.
        """
        for key, ref in sorted(self.signals.items()):
            if ref.bus == bus and ref.message == message and ref.cycle_time_s:
                return float(ref.cycle_time_s), f"vehicle configuration [signals.{key}] cycle_time_s"
        try:
            msg = self.database(bus).get_message_by_name(message)
        except (KeyError, ValueError, OSError):
            return None, "unknown"
        ct = getattr(msg, "cycle_time", None)
        if ct:
            return float(ct) * 1e-3, "DBC GenMsgCycleTime"
        return None, "unknown"

    def counter_specs(self) -> list[tuple[str, int, bool, int, int, int]]:
        """Sample counters to watch for gaps: (bus, frame id, is_extended, byte, modulo, shift).

        From the ``wft_counter_*`` signals: each must be an unsigned signal of at most 8 bits that lies in
        one byte (either byte order: the logger reads that byte per frame, shifts it right by ``shift``
        and masks it); modulo = 2**length.

        Raises:
            ValueError: a counter signal that is signed, longer than 8 bits or spans two bytes (names it
                and the configuration).
        """
        specs = []
        for key, ref in sorted(self.signals.items()):
            if not key.startswith("wft_counter"):
                continue
            msg = self.database(ref.bus).get_message_by_name(ref.message)
            sig = msg.get_signal_by_name(ref.signal)
            # the lowest bit's place in its byte: Intel counts up from the start bit, Motorola's start
            # bit is the most significant one (DBC sawtooth numbering)
            low = sig.start % 8 if sig.byte_order == "little_endian" else sig.start % 8 - (sig.length - 1)
            if sig.is_signed or sig.length > 8 or low < 0 or low + sig.length > 8:
                raise ValueError(
                    f"{self.source or 'the recording attached vehicle configuration'}: [signals.{key}] counter "
                    f"{ref.message}.{ref.signal} must be an unsigned signal of <= 8 bits within one byte (it is "
                    f"{'signed, ' if sig.is_signed else ''}{sig.length} bits from bit {sig.start}, "
                    f"{sig.byte_order.replace('_', '-')})")
            specs.append((ref.bus, msg.frame_id, bool(msg.is_extended_frame), sig.start // 8,
                          1 << sig.length, low))
        return specs


def default_vehicle_path() -> Path:
    """Path of the shipped ``vehicle.toml`` (package ``wheelsoil.dbc``)."""
    from importlib.resources import files

    return Path(str(files("wheelsoil.dbc") / "vehicle.toml"))


def read_dbc_text(path) -> str:
    """A DBC file's text: UTF-8, else Windows-1252 (CANdb++ writes its comments and units, a "°", so).

    Raises:
        OSError: the file cannot be read.
    """
    raw = Path(path).read_bytes()
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")


def _layout(m) -> tuple:
    return (m.length, tuple((g.name, g.start, g.length, g.byte_order, g.is_signed, g.scale, g.offset)
                            for g in m.signals))


def load_dbc_files(paths) -> "object":
    """Parse DBC files into one cantools database.

    Raises:
        OSError: a file that cannot be read.
        ValueError: a file cantools cannot parse, naming the file and the parser's message; a message id
            that two files define differently (which one decodes the bus's frames would depend on the
            order), naming both files.
    """
    import cantools

    messages: list = []
    nodes: dict = {}
    last = None
    where: dict = {}  # (frame id, extended) -> (file, layout)
    for p in paths:
        text = read_dbc_text(p)
        try:
            one = cantools.database.Database()
            one.add_dbc_string(text)
        except Exception as exc:  # cantools raises several parser error types
            raise ValueError(f"{p}: cannot parse DBC file: {exc}") from None
        for m in one.messages:
            key = (m.frame_id, bool(m.is_extended_frame))
            if key in where:
                if where[key][1] != _layout(m):
                    raise ValueError(f"{p}: message {m.name} (id 0x{m.frame_id:X}) is also defined, differently, in "
                                     f"{where[key][0]} on the same bus: which definition decodes its frames would "
                                     "depend on the order of the files; keep one")
                continue  # the same message in two files: one copy decodes it
            where[key] = (p, _layout(m))
            messages.append(m)
        nodes.update({n.name: n for n in one.nodes})
        last = one
    # each file parsed once; the files' messages and nodes in one database, the last file's DBC
    # specifics and buses (as cantools' add_dbc_string merges them)
    return cantools.database.Database(messages=messages, nodes=list(nodes.values()),
                                      buses=last.buses if last else None, version=last.version if last else None,
                                      dbc_specifics=last.dbc if last else None)


def load_vehicle_config(path: str | Path | None = None, *, check_dbc: bool = True) -> VehicleConfig:
    """Load a vehicle configuration TOML (None = the shipped ``dbc/vehicle.toml``).

    DBC paths in the file are relative to the file. With ``check_dbc`` every DBC
    is parsed and every signal reference checked against it.

    Raises:
        OSError: the TOML or a DBC cannot be read.
        ValueError: bad TOML, a missing/invalid key, a DBC path that is not a file, an unknown unit without
            ``scale_to_si``, an unparsable DBC, or a message/signal not in the
            bus's DBCs; the message names the file and the TOML key.
    """
    src = default_vehicle_path() if path is None else Path(path)
    raw = src.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise ValueError(f"{src}: not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}, "
                         f"line {line}); save the file as UTF-8") from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{src}: not valid TOML: {exc}") from None
    if not isinstance(doc, Mapping):  # pragma: no cover - tomllib always gives a dict
        raise ValueError(f"{src}: not a TOML table")
    return vehicle_config_from_dict(doc, source=src, text=text, check_dbc=check_dbc)


def vehicle_config_from_dict(doc: Mapping, *, source: Path | None = None, text: str = "",
                             check_dbc: bool = True) -> VehicleConfig:
    """Build a :class:`VehicleConfig` from the parsed TOML mapping (see :func:`load_vehicle_config`)."""
    where = str(source) if source else "vehicle config"
    base = source.parent if source else Path.cwd()
    veh = doc.get("vehicle", {})
    if not isinstance(veh, Mapping):
        raise ValueError(f"{where}: [vehicle] must be a table")
    nums = {}
    notes = []
    for key, default in (("wheel_radius_m", 0.47), ("wheel_width_m", 0.32),
                         ("wheel_mass_kg", DEFAULT_WHEEL_MASS_KG),
                         ("wheel_inertia_kgm2", DEFAULT_WHEEL_INERTIA_KGM2)):
        if key not in veh:
            if key in ("wheel_mass_kg", "wheel_inertia_kgm2"):
                notes.append(f"[vehicle] has no {key}; the hardware.md default {default:g} is used "
                             "for the inertia compensation")
            nums[key] = default
            continue
        nums[key] = check_vehicle_number(where, key, veh[key])

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
        missing = [str(p) for p in buses[name] if check_dbc and not p.is_file()]
        if missing:
            raise ValueError(f"{where}: [buses.{name}] dbc names {', '.join(missing)}, which is not a file (DBC paths "
                             "are relative to the vehicle TOML)")
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
            raw = tab["scale_to_si"]
            try:
                if isinstance(raw, bool):
                    raise TypeError
                scale = float(raw)
            except (TypeError, ValueError):
                raise ValueError(f"{where}: [signals.{key}] scale_to_si = {raw!r}: must be a number") from None
            if not (math.isfinite(scale) and scale != 0.0):
                raise ValueError(f"{where}: [signals.{key}] scale_to_si = {raw!r}: must be a finite, "
                                 "non-zero factor to SI")
        elif unit in UNIT_TO_SI:
            scale = UNIT_TO_SI[unit]
        else:
            raise ValueError(f"{where}: [signals.{key}] unit {unit!r} is unknown; give scale_to_si "
                             f"(known units: {', '.join(u for u in UNIT_TO_SI if u)})")
        cycle = None
        if "cycle_time_s" in tab:
            raw = tab["cycle_time_s"]
            try:
                if isinstance(raw, bool):
                    raise TypeError
                cycle = float(raw)
            except (TypeError, ValueError):
                cycle = float("nan")
            if not (math.isfinite(cycle) and 1e-4 <= cycle <= 5.0):
                raise ValueError(f"{where}: [signals.{key}] cycle_time_s = {raw!r}: not a plausible "
                                 "message period in s (1e-4 - 5); did you give ms?")
        signals[key] = SignalRef(str(tab["bus"]), str(tab["message"]), str(tab["signal"]), unit, scale, cycle)

    cfg = VehicleConfig(buses=buses, signals=signals, wheel_radius_m=nums["wheel_radius_m"],
                        wheel_width_m=nums["wheel_width_m"], name=str(veh.get("name", "")),
                        bus_options=bus_options, source=source, text=text,
                        wheel_mass_kg=nums["wheel_mass_kg"], wheel_inertia_kgm2=nums["wheel_inertia_kgm2"],
                        notes=notes)
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
            dbc_unit = msg.get_signal_by_name(ref.signal).unit or ""
            problem = unit_mismatch(ref.unit, dbc_unit)
            if problem:
                files = ", ".join(p.name for p in buses[ref.bus])
                raise ValueError(f"{where}: [signals.{key}] unit = {ref.unit!r} but the DBC ({files}) gives "
                                 f"{ref.message}.{ref.signal} in {dbc_unit!r}: {problem}; write "
                                 f"unit = {dbc_unit!r} (the unit of the DBC's physical value) and, if it is "
                                 "not SI, scale_to_si")
    return cfg


def check_vehicle_number(where: str, key: str, raw, name: str | None = None) -> float:
    """One ``[vehicle]`` number (``key`` of :data:`VEHICLE_RANGES`), checked to be finite and within
    its range; returns it as a float [its unit].

    Raises ``ValueError`` naming ``where`` (the file, or a command-line option), the value as
    ``name`` (default ``[vehicle] <key>``) and the range (with a hint when the value looks like
    millimetres or is negative).
    """
    name = name or f"[vehicle] {key}"
    lo, hi, unit, what = VEHICLE_RANGES[key]
    try:
        if isinstance(raw, bool):
            raise TypeError
        val = float(raw)
    except (TypeError, ValueError):
        raise ValueError(f"{where}: {name} = {raw!r}: must be a number in {unit}") from None
    if not (math.isfinite(val) and lo <= val <= hi):
        hint = ""
        if math.isfinite(val) and unit == "m" and lo * 1e3 <= val <= hi * 1e3:
            hint = "; did you give mm?"
        elif math.isfinite(val) and val < 0:
            hint = "; it cannot be negative"
        raise ValueError(f"{where}: {name} = {raw!r}: not a plausible {what} in {unit} "
                         f"({lo:g}-{hi:g}){hint}")
    return val


def _norm_unit(u: str) -> str:
    u = str(u).strip()
    return UNIT_ALIASES.get(u.lower(), u)


def unit_mismatch(toml_unit: str, dbc_unit: str) -> str:
    """Why ``toml_unit`` (vehicle.toml) cannot be the DBC's ``dbc_unit``, or "" if it can.

    Empty DBC units say nothing and match anything. Known units
    (:data:`UNIT_TO_SI`) match when they have the same dimension and factor to SI
    (``N.m`` = ``Nm``); unknown ones when their spelling matches (case aside).
    """
    a, b = _norm_unit(toml_unit), _norm_unit(dbc_unit)
    if not b or a == b:
        return ""
    if a in UNIT_TO_SI and b in UNIT_TO_SI:
        if UNIT_DIMENSION[a] != UNIT_DIMENSION[b]:
            return f"{a!r} is a {UNIT_DIMENSION[a]}, {b!r} a {UNIT_DIMENSION[b]}"
        if not math.isclose(UNIT_TO_SI[a], UNIT_TO_SI[b], rel_tol=1e-9):
            f = UNIT_TO_SI[a] / UNIT_TO_SI[b]
            return (f"values would be scaled {f:g}x " + ("too high" if f > 1 else "too low"))
        return ""
    if a.lower() == b.lower():
        return ""
    return "the units differ"
