"""Terrain and wheel descriptions, the built-in terrain library, TOML loading.

Units: SI inside the code. ``Terrain`` holds c [Pa], phi [rad], K [m], n [-],
kc [N/m^(n+1)], kphi [N/m^(n+2)]. Terrain files (the built-in
``terrains.toml`` and a user's custom TOML) are written in the field's usual
units and converted on loading:

=========  ===============  ===========================================
key        unit in TOML      meaning
=========  ===============  ===========================================
c_kpa      kPa              cohesion c (Mohr-Coulomb)
phi_deg    deg              internal friction angle phi
K_m        m                shear deformation modulus K (Janosi-Hanamoto)
n          -                sinkage exponent n (Bekker)
kc         kN/m^(n+1)       cohesive modulus kc (Bekker)
kphi       kN/m^(n+2)       frictional modulus kphi (Bekker)
name       -                optional display name (custom files)
source     -                optional (custom files), required (built-in)
=========  ===============  ===========================================

A custom file is either one terrain (the keys above at top level) or a
library like the built-in one (``[terrains.<slug>]`` tables); pick one entry
of a library file with ``path.toml#slug``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

try:  # Python >= 3.11
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = [
    "Terrain",
    "Wheel",
    "DEFAULT_WHEEL",
    "TERRAINS",
    "load_terrain",
    "load_terrain_file",
    "terrain_from_mapping",
]

#: Keys of a terrain entry in a TOML file, with their unit (for messages).
TERRAIN_KEYS: dict[str, str] = {
    "c_kpa": "kPa",
    "phi_deg": "deg",
    "K_m": "m",
    "n": "-",
    "kc": "kN/m^(n+1)",
    "kphi": "kN/m^(n+2)",
}


@dataclass(frozen=True)
class Terrain:
    """Terrain parameters of Bekker's pressure-sinkage law and Janosi-Hanamoto shear.

    Fields (SI): ``c`` cohesion [Pa], ``phi`` internal friction angle [rad],
    ``K`` shear deformation modulus [m], ``n`` sinkage exponent [-],
    ``kc`` cohesive modulus [N/m^(n+1)], ``kphi`` frictional modulus
    [N/m^(n+2)], plus ``name`` and ``source`` (citation text).

    The wheel model only uses the combination ``kc/b + kphi`` (Eq. 2) and
    ``kc + b*kphi`` (Eq. 10, which is ``b`` times the same thing), so a fitter
    may fit one modulus, e.g. ``terrain.replace(kc=0.0, kphi=k)``. ``kc`` alone
    may be negative (some published soils have kc < 0) as long as
    ``kc/b + kphi > 0`` for the wheel used; this is checked by the wheel model.

    Raises ``ValueError`` on construction (naming the terrain and the field)
    for: a non-finite value, c < 0, phi outside [0, 90) deg, K <= 0,
    n outside (0, 3) (Eq. 10 needs n < 3).

    Source: paper Eqs. (2), (4); Bekker (1956); Janosi & Hanamoto (1961).
    """

    name: str
    c: float
    phi: float
    K: float
    n: float
    kc: float
    kphi: float
    source: str = ""

    def __post_init__(self) -> None:
        where = f"terrain {self.name!r}"
        for field in ("c", "phi", "K", "n", "kc", "kphi"):
            value = getattr(self, field)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{where}: {field} must be a number, got {value!r}") from None
            if not math.isfinite(value):
                raise ValueError(f"{where}: {field} must be finite, got {value!r}")
            object.__setattr__(self, field, value)
        if self.c < 0:
            raise ValueError(f"{where}: cohesion c must be >= 0 Pa, got {self.c!r}")
        if not 0.0 <= self.phi < math.pi / 2:
            raise ValueError(
                f"{where}: friction angle phi must be in [0, 90) deg, got {math.degrees(self.phi)!r} deg"
            )
        if self.K <= 0:
            raise ValueError(f"{where}: shear deformation modulus K must be > 0 m, got {self.K!r}")
        if not 0.0 < self.n < 3.0:
            raise ValueError(f"{where}: sinkage exponent n must be in (0, 3) (Eq. 10), got {self.n!r}")

    @property
    def phi_deg(self) -> float:
        """Internal friction angle in degrees."""
        return math.degrees(self.phi)

    def replace(self, **changes: Any) -> "Terrain":
        """A copy with some fields changed (``dataclasses.replace``; validated again)."""
        return dataclasses.replace(self, **changes)

    def k_eq(self, width_m: float) -> float:
        """Combined pressure-sinkage modulus ``kc/b + kphi`` [N/m^(n+2)] for width b (Eq. 2)."""
        return self.kc / width_m + self.kphi

    @classmethod
    def from_field_units(
        cls,
        name: str,
        *,
        c_kpa: float,
        phi_deg: float,
        K_m: float,
        n: float,
        kc: float,
        kphi: float,
        source: str = "",
    ) -> "Terrain":
        """Build from field units: c [kPa], phi [deg], K [m], kc [kN/m^(n+1)], kphi [kN/m^(n+2)]."""
        return cls(
            name=name,
            c=float(c_kpa) * 1e3,
            phi=math.radians(float(phi_deg)),
            K=float(K_m),
            n=float(n),
            kc=float(kc) * 1e3,
            kphi=float(kphi) * 1e3,
            source=source,
        )

    def field_units(self) -> dict[str, float | str]:
        """The parameters in field units, keyed like a terrain TOML entry (plus name, source)."""
        return {
            "name": self.name,
            "c_kpa": self.c / 1e3,
            "phi_deg": self.phi_deg,
            "K_m": self.K,
            "n": self.n,
            "kc": self.kc / 1e3,
            "kphi": self.kphi / 1e3,
            "source": self.source,
        }


@dataclass(frozen=True)
class Wheel:
    """A rigid wheel: ``radius`` r [m] and contact width b [m] (> 0, finite).

    Raises ``ValueError`` for a non-positive or non-finite size.
    """

    radius: float
    width: float

    def __post_init__(self) -> None:
        for field in ("radius", "width"):
            value = float(getattr(self, field))
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"wheel {field} must be a finite number > 0 m, got {getattr(self, field)!r}")
            object.__setattr__(self, field, value)


#: Default wheel (hardware.md): a 37x12.5R16.5 tyre, r = 0.47 m, b = 0.32 m.
DEFAULT_WHEEL = Wheel(0.47, 0.32)


def terrain_from_mapping(data: Mapping[str, Any], *, name: str, where: str) -> Terrain:
    """Build a ``Terrain`` from one TOML entry in field units (see module docstring).

    ``where`` names the file/table for error messages. Raises ``ValueError``
    naming ``where`` and the key for a missing key, an unknown key, a
    non-numeric value, or a value that fails ``Terrain`` validation.
    """
    if not isinstance(data, Mapping):
        raise ValueError(f"{where}: a terrain entry must be a table, got {type(data).__name__}")
    missing = [k for k in TERRAIN_KEYS if k not in data]
    if missing:
        raise ValueError(
            f"{where}: missing key(s) {', '.join(missing)} "
            f"(a terrain needs {', '.join(f'{k} [{u}]' for k, u in TERRAIN_KEYS.items())})"
        )
    unknown = sorted(set(data) - set(TERRAIN_KEYS) - {"name", "source", "description"})
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; allowed: "
                         f"{', '.join(TERRAIN_KEYS)}, name, source, description")
    values: dict[str, float] = {}
    for key in TERRAIN_KEYS:
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where}: key {key} must be a number [{TERRAIN_KEYS[key]}], got {value!r}")
        values[key] = float(value)
    try:
        return Terrain.from_field_units(
            str(data.get("name", name)), source=str(data.get("source", "")), **values
        )
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None


def load_terrain_file(path: str | Path) -> dict[str, Terrain]:
    """All terrains in a TOML file, keyed by slug (a single-terrain file: its stem).

    Raises ``OSError`` if the file cannot be read, ``ValueError`` naming the
    file and the table/key for bad content.
    """
    path = Path(path)
    data = _read_toml(path)
    if "terrains" in data:
        table = data["terrains"]
        if not isinstance(table, Mapping) or not table:
            raise ValueError(f"{path}: [terrains] must hold at least one [terrains.<slug>] table")
        return {
            slug: terrain_from_mapping(entry, name=slug, where=f"{path} [terrains.{slug}]")
            for slug, entry in table.items()
        }
    return {path.stem: terrain_from_mapping(data, name=path.stem, where=str(path))}


def _load_builtin() -> dict[str, Terrain]:
    ref = resources.files(__package__).joinpath("terrains.toml")
    with resources.as_file(ref) as path:
        terrains = load_terrain_file(path)
    for slug, terrain in terrains.items():
        if not terrain.source:
            raise ValueError(f"built-in terrain {slug!r} has no source")  # pragma: no cover
    return terrains


#: Built-in terrain library: slug -> Terrain (see ``wheelsoil terrains``).
TERRAINS: dict[str, Terrain] = _load_builtin()


def load_terrain(name_or_path: str | Path) -> Terrain:
    """A built-in terrain by slug (``clay``, ``sand``, ``dry-sand``, ...) or one from a TOML file.

    ``name_or_path``: a slug of ``TERRAINS``; a path to a single-terrain TOML
    file; a library-style file with exactly one entry; or ``path.toml#slug``.
    Raises ``ValueError`` for an unknown slug (listing the known ones) or bad
    file content (naming the file and key), ``OSError`` for an unreadable file.
    """
    if isinstance(name_or_path, Terrain):
        return name_or_path
    text = str(name_or_path)
    if text in TERRAINS:
        return TERRAINS[text]
    path_text, _, slug = text.partition("#")
    path = Path(path_text)
    if path.suffix.lower() != ".toml" and not path.exists():
        raise ValueError(
            f"unknown terrain {text!r}: not a built-in slug ({', '.join(TERRAINS)}) nor a .toml file"
        )
    terrains = load_terrain_file(path)
    if slug:
        if slug not in terrains:
            raise ValueError(f"{path}: no terrain {slug!r}; it has {', '.join(terrains)}")
        return terrains[slug]
    if len(terrains) != 1:
        raise ValueError(
            f"{path}: holds {len(terrains)} terrains ({', '.join(terrains)}); pick one with {path}#<slug>"
        )
    return next(iter(terrains.values()))
