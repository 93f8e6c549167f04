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

Lab uncertainties. Each terrain carries standard deviations of the
identifiable subset of its parameters (``Terrain.prior_sd``; the wheel model
only sees k_eq = kc/b + kphi, never kc and kphi apart): defaults in
``DEFAULT_PRIOR_SD`` (reasoned there), overridden per terrain by an optional
sub-table ``[terrains.<slug>.uncertainty]`` (``[uncertainty]`` in a
single-terrain file), in the file's field units:

==========  ======  ================================================
key         unit    standard deviation of
==========  ======  ================================================
k_eq_rel    -       k_eq = kc/b + kphi, as a fraction of k_eq
n           -       the sinkage exponent n
c_kpa       kPa     cohesion c    (or ``c_rel``: fraction of c)
phi_deg     deg     friction angle phi
K_m         m       shear deformation modulus K (or ``K_rel``: fraction of K)
source      -       optional text: where the numbers come from
==========  ======  ================================================

Every value must be a finite number > 0; a fraction is turned into an
absolute SD with that entry's own value when the file is read.
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
    "PRIOR_KEYS",
    "DEFAULT_PRIOR_SD",
    "default_prior_sd",
    "terrain_prior",
    "Wheel",
    "DEFAULT_WHEEL",
    "TERRAINS",
    "load_terrain",
    "load_terrain_file",
    "terrain_from_mapping",
    "check_k_eq",
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


#: Largest plausible value of a terrain file's key, in the file's unit, and the unit mix-up a
#: larger value most likely is.  The built-in library (Wong's tables) reaches c = 69 kPa and
#: K = 0.03 m; the limits are ~7x and ~17x beyond, so a soil is not refused for being firm,
#: while c in Pa (any soil with c >= 0.5 kPa) and K in mm (any K >= 0.5 mm) are.  A friction
#: angle in (0, 1) deg is the angle in radians (the library's smallest is 6 deg).  The library's
#: |kc| reaches 102 and kphi 5880 (kN units); the limits are ~10x and ~7x beyond, so kc in N/m^(n+1)
#: (any |kc| >= 1 kN/m^(n+1)) and kphi in N/m^(n+2) (any kphi >= 40, every library soil's) are refused.
FIELD_UNIT_LIMITS: dict[str, tuple[float, str]] = {
    "c_kpa": (500.0, "cohesion in Pa instead of kPa"),
    "K_m": (0.5, "K in mm instead of m"),
    "kc": (1000.0, "kc in N/m^(n+1) instead of kN/m^(n+1)"),
    "kphi": (40000.0, "kphi in N/m^(n+2) instead of kN/m^(n+2)"),
}
#: Largest plausible k_eq = kc/b + kphi [kN/m^(n+2)] at the wheel's width: the library reaches 7000
#: (lete sand on a 6 cm wheel); 7x beyond is a modulus in N (:func:`check_k_eq`).
K_EQ_LIMIT_KN = 50000.0


#: The soil values of a :class:`Terrain` (SI): what the constructor and ``with_values`` check.
SOIL_VALUES: tuple[str, ...] = ("c", "phi", "K", "n", "kc", "kphi")
#: Names of the identifiable terrain parameters that carry a lab prior (SI units in ``prior_sd``).
PRIOR_KEYS: tuple[str, ...] = ("k_eq", "n", "c", "phi", "K")

#: Units of ``Terrain.prior_sd`` values (k_eq's SD is relative to k_eq).
PRIOR_SD_UNITS: dict[str, str] = {"k_eq": "fraction of k_eq", "n": "-", "c": "Pa", "phi": "rad", "K": "m"}

#: Default lab standard deviations (the rules ``default_prior_sd`` applies).
#:
#: These are ASSUMPTIONS, not a measured repeatability of the paper's lab (the
#: paper gives Tab. 1 without uncertainties); their orders of magnitude follow
#: the terramechanics and geotechnical literature:
#:
#: - ``k_eq_rel = 0.30``: Bekker moduli depend strongly on how the soil bed is
#:   prepared and on plate size (Els, Hamersma & Kruger, "Factors affecting
#:   bevameter soil characterization", ISTVS 2022, doi:10.56884/IKRL4697: soil
#:   preparation has "a substantial influence on the pressure-sinkage
#:   relationship"); kc and kphi are notoriously ill-separated by two-plate
#:   fits, their combination k_eq less so. 30 % is our assumption.
#: - ``n = 0.10`` (absolute): assumption, a typical spread of the exponent
#:   between repeated plate tests of one soil.
#: - ``c_rel = 0.30`` with a floor ``c_min_pa = 1000`` Pa: cohesion is the
#:   intercept of a Mohr-Coulomb fit and poorly determined, worst for
#:   near-cohesionless sands (hence the 1 kPa floor); assumption.
#: - ``phi_deg = 2.5`` deg: friction angles from shear-box tests scatter by a
#:   coefficient of variation of ~5-15 % for sands (Phoon & Kulhawy, Can.
#:   Geotech. J. 36, 1999, and the discussion by Cherubini et al.: 5-15 %
#:   sand, 10-50 % clay); 2.5 deg is 10 % of 25 deg.
#: - ``K_rel = 0.30``: K comes from a fit of the Janosi-Hanamoto curve and
#:   varies with normal load and shear-device type (rotational bevameter
#:   rings over-predict drawbar pull by 30-40 %, Els et al. 2022 citing Chang
#:   & Baker 1973 and Shoop 1993); assumption. The built-in entries whose K is
#:   itself assumed (Wong's table has no K) override it with ``K_rel = 0.5``.
DEFAULT_PRIOR_SD: dict[str, float] = {
    "k_eq_rel": 0.30,
    "n": 0.10,
    "c_rel": 0.30,
    "c_min_pa": 1000.0,
    "phi_deg": 2.5,
    "K_rel": 0.30,
}


def default_prior_sd(c: float, K: float) -> dict[str, float]:
    """Default lab SDs (SI, keys ``PRIOR_KEYS``) for a terrain with cohesion c [Pa] and K [m].

    k_eq: 0.30 (relative); n: 0.10; c: max(0.30 c, 1 kPa) [Pa]; phi: 2.5 deg
    [rad]; K: 0.30 K [m]. Source: ``DEFAULT_PRIOR_SD`` (assumptions, reasoned there).
    """
    d = DEFAULT_PRIOR_SD
    return {
        "k_eq": d["k_eq_rel"],
        "n": d["n"],
        "c": max(d["c_rel"] * c, d["c_min_pa"]),
        "phi": math.radians(d["phi_deg"]),
        "K": d["K_rel"] * K,
    }


class _FrozenSD(Mapping):
    """Read-only, hashable mapping name -> SD (explicit per-terrain overrides)."""

    __slots__ = ("_items",)

    def __init__(self, items: Mapping[str, float] | None = None) -> None:
        object.__setattr__(self, "_items", dict(sorted((items or {}).items())))

    def __getitem__(self, key: str) -> float:
        return self._items[key]

    def __iter__(self):
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __hash__(self) -> int:
        return hash(tuple(self._items.items()))

    def __repr__(self) -> str:
        return repr(self._items)

    def __setattr__(self, name, value):  # pragma: no cover - immutability guard
        raise AttributeError("uncertainty overrides are read-only; use Terrain.replace(prior_sd=...)")


@dataclass(frozen=True)
class Terrain:
    """Terrain parameters of Bekker's pressure-sinkage law and Janosi-Hanamoto shear.

    Fields (SI): ``c`` cohesion [Pa], ``phi`` internal friction angle [rad],
    ``K`` shear deformation modulus [m], ``n`` sinkage exponent [-],
    ``kc`` cohesive modulus [N/m^(n+1)], ``kphi`` frictional modulus
    [N/m^(n+2)], plus ``name`` and ``source`` (citation text), and
    ``uncertainty``: explicit lab standard deviations overriding the defaults,
    a mapping with keys from ``PRIOR_KEYS`` in SI (k_eq as a fraction of k_eq,
    n absolute, c [Pa], phi [rad], K [m]); missing keys take the defaults.
    ``prior_sd`` gives the full set (defaults + overrides);
    ``replace(prior_sd={...})`` merges new overrides into the old ones;
    ``uncertainty_source`` says where the overrides come from (text).

    The wheel model only uses the combination ``kc/b + kphi`` (Eq. 2) and
    ``kc + b*kphi`` (Eq. 10, which is ``b`` times the same thing), so a fitter
    may fit one modulus, e.g. ``terrain.replace(kc=0.0, kphi=k)``. ``kc`` alone
    may be negative (some published soils have kc < 0) as long as
    ``kc/b + kphi > 0`` for the wheel used; this is checked by the wheel model.

    Raises ``ValueError`` on construction (naming the terrain and the field)
    for: a non-finite value, c < 0, phi outside [0, 90) deg, K <= 0,
    n outside (0, 3) (Eq. 10 needs n < 3), an unknown uncertainty key or an
    uncertainty that is not a finite number > 0.

    Source: paper Eqs. (2), (4); Bekker (1956); Janosi & Hanamoto (1961);
    lab-uncertainty defaults: ``DEFAULT_PRIOR_SD``.
    """

    name: str
    c: float
    phi: float
    K: float
    n: float
    kc: float
    kphi: float
    source: str = ""
    uncertainty: Mapping[str, float] | None = None
    uncertainty_source: str = ""

    def __post_init__(self) -> None:
        self._check_values(SOIL_VALUES)
        where = f"terrain {self.name!r}"
        overrides = self.uncertainty if self.uncertainty is not None else {}
        if not isinstance(overrides, Mapping):
            raise ValueError(f"{where}: uncertainty must be a mapping {{name: sd}} with names "
                             f"{', '.join(PRIOR_KEYS)}, got {type(overrides).__name__}")
        clean: dict[str, float] = {}
        for key, value in overrides.items():
            if key not in PRIOR_KEYS:
                raise ValueError(f"{where}: unknown uncertainty {key!r}; names: {', '.join(PRIOR_KEYS)}")
            try:
                sd = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"{where}: uncertainty {key} must be a number, got {value!r}") from None
            if not (math.isfinite(sd) and sd > 0):
                raise ValueError(f"{where}: uncertainty {key} must be a finite number > 0 "
                                 f"[{PRIOR_SD_UNITS[key]}], got {value!r}")
            clean[key] = sd
        object.__setattr__(self, "uncertainty", _FrozenSD(clean))

    def _check_values(self, fields) -> None:
        """Turn ``fields`` (soil values) into finite floats and check every value's range."""
        where = f"terrain {self.name!r}"
        for field in fields:
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

    def with_values(self, **values: float) -> "Terrain":
        """A copy with soil values changed (``c``, ``phi``, ``K``, ``n``, ``kc``, ``kphi``; SI), checked
        as the constructor checks them: the fitter's hot path (:meth:`replace` re-validates every
        field and the uncertainty mapping, ten times the cost).  Raises ``ValueError`` like the
        constructor, TypeError for another field."""
        bad = set(values) - set(SOIL_VALUES)
        if bad:
            raise TypeError(f"with_values: not a soil value: {', '.join(sorted(bad))}")
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.__dict__.update(values)
        new._check_values(tuple(values))
        return new

    @property
    def phi_deg(self) -> float:
        """Internal friction angle in degrees."""
        return math.degrees(self.phi)

    def replace(self, **changes: Any) -> "Terrain":
        """A copy with some fields changed (``dataclasses.replace``; validated again).

        ``prior_sd={name: sd}`` (SI, see ``prior_sd``) merges into the existing
        uncertainty overrides; ``uncertainty=None`` drops them (back to the
        defaults). Raises ``ValueError`` like the constructor.
        """
        if "prior_sd" in changes:
            extra = changes.pop("prior_sd")
            if not isinstance(extra, Mapping):
                raise ValueError(f"terrain {self.name!r}: prior_sd must be a mapping {{name: sd}}, "
                                 f"got {type(extra).__name__}")
            base = changes.pop("uncertainty", self.uncertainty) or {}
            changes["uncertainty"] = {**base, **extra}
        return dataclasses.replace(self, **changes)

    @property
    def prior_sd(self) -> dict[str, float]:
        """Lab standard deviations of ``PRIOR_KEYS`` in SI: the overrides, else the defaults.

        Units: k_eq as a fraction of k_eq = kc/b + kphi; n [-]; c [Pa];
        phi [rad]; K [m]. Defaults follow the current c and K
        (``default_prior_sd``). Source: ``DEFAULT_PRIOR_SD``.
        """
        sd = default_prior_sd(self.c, self.K)
        sd.update(self.uncertainty or {})
        return sd

    @property
    def prior_sd_origin(self) -> dict[str, str]:
        """For each of ``PRIOR_KEYS``: ``"terrain"`` (an override) or ``"default"`` (an assumption)."""
        return {k: ("terrain" if k in (self.uncertainty or {}) else "default") for k in PRIOR_KEYS}

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
        uncertainty: Mapping[str, float] | None = None,
        uncertainty_source: str = "",
    ) -> "Terrain":
        """Build from field units: c [kPa], phi [deg], K [m], kc [kN/m^(n+1)], kphi [kN/m^(n+2)].

        ``uncertainty`` (optional) is already in SI, keys ``PRIOR_KEYS`` (see ``prior_sd``).
        """
        return cls(
            name=name,
            c=float(c_kpa) * 1e3,
            phi=math.radians(float(phi_deg)),
            K=float(K_m),
            n=float(n),
            kc=float(kc) * 1e3,
            kphi=float(kphi) * 1e3,
            source=source,
            uncertainty=uncertainty,
            uncertainty_source=uncertainty_source,
        )

    def uncertainty_field_units(self) -> dict[str, float]:
        """``prior_sd`` in the terrain file's units: k_eq_rel [-], n [-], c_kpa, phi_deg, K_m."""
        sd = self.prior_sd
        return {"k_eq_rel": sd["k_eq"], "n": sd["n"], "c_kpa": sd["c"] / 1e3,
                "phi_deg": math.degrees(sd["phi"]), "K_m": sd["K"]}

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
    unknown = sorted(set(data) - set(TERRAIN_KEYS) - {"name", "source", "description", "uncertainty"})
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; allowed: "
                         f"{', '.join(TERRAIN_KEYS)}, name, source, description, [uncertainty]")
    values: dict[str, float] = {}
    for key in TERRAIN_KEYS:
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where}: key {key} must be a number [{TERRAIN_KEYS[key]}], got {value!r}")
        values[key] = float(value)
    for key, (limit, mixup) in FIELD_UNIT_LIMITS.items():
        if abs(values[key]) > limit:
            raise ValueError(f"{where}: {key} = {values[key]:g} [{TERRAIN_KEYS[key]}] is far beyond the built-in "
                             f"library's soils (limit {limit:g}): {mixup}? Terrain files are in field units: "
                             + ", ".join(f"{k} [{u}]" for k, u in TERRAIN_KEYS.items()))
    if values["kphi"] < 0 or (values["kphi"] == 0 and values["kc"] <= 0):
        raise ValueError(f"{where}: kphi = {values['kphi']:g}, kc = {values['kc']:g} [kN units]: the pressure-sinkage "
                         "modulus kc/b + kphi (Eq. 2) must be > 0 at the wheel's width b, which needs kphi >= 0 "
                         "(and kc > 0 when kphi = 0); check the signs of kc and kphi")
    if 0.0 < values["phi_deg"] < 1.0:
        raise ValueError(f"{where}: phi_deg = {values['phi_deg']:g} deg is the friction angle in radians? "
                         f"({math.degrees(values['phi_deg']):.1f} deg); terrain files give phi_deg in degrees")
    uncertainty, uncertainty_source = None, ""
    if "uncertainty" in data:
        uncertainty = uncertainty_from_mapping(data["uncertainty"], values, where=f"{where} [uncertainty]")
        uncertainty_source = str(data["uncertainty"].get("source", ""))
    try:
        return Terrain.from_field_units(
            str(data.get("name", name)), source=str(data.get("source", "")), uncertainty=uncertainty,
            uncertainty_source=uncertainty_source, **values
        )
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


#: Keys of an ``[uncertainty]`` table in a terrain TOML file (field units; see module docstring).
UNCERTAINTY_KEYS: dict[str, str] = {
    "k_eq_rel": "fraction of k_eq",
    "n": "-",
    "c_kpa": "kPa",
    "c_rel": "fraction of c",
    "phi_deg": "deg",
    "K_m": "m",
    "K_rel": "fraction of K",
}


def uncertainty_from_mapping(data: Mapping[str, Any], values: Mapping[str, float], *, where: str) -> dict[str, float]:
    """Lab SDs in SI (keys ``PRIOR_KEYS``) from an ``[uncertainty]`` table in field units.

    ``values`` holds the terrain's own values in field units (``c_kpa``,
    ``K_m``) for the relative keys ``c_rel``/``K_rel``. Raises ``ValueError``
    naming ``where`` and the key for: a non-table, an unknown key, both the
    absolute and relative form of one SD, a non-number, a NaN/inf, or an SD <= 0.
    """
    if not isinstance(data, Mapping):
        raise ValueError(f"{where}: must be a table of standard deviations, got {type(data).__name__}")
    unknown = sorted(set(data) - set(UNCERTAINTY_KEYS) - {"source"})
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)}; allowed: "
                         f"{', '.join(f'{k} [{u}]' for k, u in UNCERTAINTY_KEYS.items())}, source")
    for a, b in (("c_kpa", "c_rel"), ("K_m", "K_rel")):
        if a in data and b in data:
            raise ValueError(f"{where}: give {a} or {b}, not both")
    sd: dict[str, float] = {}
    for key in UNCERTAINTY_KEYS:
        if key not in data:
            continue
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where}: key {key} must be a number [{UNCERTAINTY_KEYS[key]}], got {value!r}")
        value = float(value)
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{where}: key {key} must be a finite standard deviation > 0 "
                             f"[{UNCERTAINTY_KEYS[key]}], got {value!r}")
        if key == "k_eq_rel":
            sd["k_eq"] = value
        elif key == "n":
            sd["n"] = value
        elif key == "c_kpa":
            sd["c"] = value * 1e3
        elif key == "c_rel":
            if values["c_kpa"] <= 0:
                raise ValueError(f"{where}: c_rel needs c > 0 (c_kpa = {values['c_kpa']!r}); give c_kpa instead")
            sd["c"] = value * values["c_kpa"] * 1e3
        elif key == "phi_deg":
            sd["phi"] = math.radians(value)
        elif key == "K_m":
            sd["K"] = value
        elif key == "K_rel":
            sd["K"] = value * values["K_m"]
    return sd


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not UTF-8 text, as TOML must be ({exc.reason} at byte {exc.start}); save it as "
                         "UTF-8") from None


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
    tables = [k for k, v in data.items() if isinstance(v, Mapping) and k != "uncertainty"]
    if tables and not any(k in data for k in TERRAIN_KEYS):
        raise ValueError(f"{path}: no terrain keys at the top level, but the table(s) "
                         f"{', '.join(f'[{t}]' for t in tables)}; a terrain file holds one terrain's keys "
                         f"({', '.join(TERRAIN_KEYS)}) at the top level, or a library of [terrains.<slug>] tables "
                         f"(write [terrains.{tables[0]}])")
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
    file content (naming the file and key), ``OSError`` for an unreadable file
    (``FileNotFoundError`` listing the built-in slugs for a missing one).
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
    if not path.exists():
        raise FileNotFoundError(f"--terrain: no such file {path} (built-in terrains: {', '.join(TERRAINS)})")
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


def check_k_eq(terrain: Terrain, width_m: float, where: str) -> float:
    """k_eq = kc/b + kphi [N/m^(n+2)] of ``terrain`` at the wheel width ``width_m`` [m] (Eq. 2), checked.

    ``where`` names the terrain (its file) in messages.  Raises ``ValueError`` naming ``where`` and the
    keys kc and kphi when k_eq <= 0 (a negative kc too large for this narrow a wheel: the smallest
    width it allows is said) or above ``K_EQ_LIMIT_KN`` (moduli in N instead of kN).
    """
    k_eq = terrain.k_eq(width_m)
    kc, kphi = terrain.kc / 1e3, terrain.kphi / 1e3
    if not k_eq > 0:
        b_min = f"; it needs b > {-kc / kphi:.3g} m" if kphi > 0 else ""
        raise ValueError(f"{where}: kc/b + kphi = {kc:g}/{width_m:g} + {kphi:g} = {k_eq / 1e3:.4g} kN/m^(n+2) at the "
                         f"wheel width b = {width_m:g} m must be > 0 (Eq. 2){b_min}: check kc and kphi")
    if k_eq / 1e3 > K_EQ_LIMIT_KN:
        raise ValueError(f"{where}: kc/b + kphi = {k_eq / 1e3:.4g} kN/m^(n+2) at the wheel width b = {width_m:g} m is "
                         f"far beyond the built-in library's soils (limit {K_EQ_LIMIT_KN:g}): kc and kphi in N "
                         "instead of kN? Terrain files give them in kN/m^(n+1), kN/m^(n+2)")
    return k_eq


def terrain_prior(terrain: Terrain, wheel: Wheel) -> dict[str, tuple[float, float]]:
    """Lab prior of the identifiable terrain parameters: name -> (mean, sd), SI units.

    Names ``PRIOR_KEYS``: ``k_eq`` = kc/b + kphi [N/m^(n+2)] for the wheel's
    width b (Eq. 2; its SD is ``prior_sd["k_eq"]`` times k_eq), ``n`` [-],
    ``c`` [Pa], ``phi`` [rad], ``K`` [m]; means are the terrain's (lab)
    values, SDs ``terrain.prior_sd`` (per-terrain overrides, else
    ``DEFAULT_PRIOR_SD``). Raises ``ValueError`` if k_eq <= 0 for this wheel.
    Source: paper Eq. (2), Tab. 1; ``DEFAULT_PRIOR_SD``.
    """
    k_eq = terrain.k_eq(wheel.width)
    if not k_eq > 0:
        raise ValueError(f"terrain {terrain.name!r}: kc/b + kphi = {k_eq!r} must be > 0 "
                         f"for wheel width b = {wheel.width} m (Eq. 2)")
    sd = terrain.prior_sd
    return {
        "k_eq": (k_eq, sd["k_eq"] * k_eq),
        "n": (terrain.n, sd["n"]),
        "c": (terrain.c, sd["c"]),
        "phi": (terrain.phi, sd["phi"]),
        "K": (terrain.K, sd["K"]),
    }
