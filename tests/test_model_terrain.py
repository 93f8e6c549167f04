"""Terrain library, units, TOML loading and validation."""

from __future__ import annotations

import math

import pytest

from wheelsoil.model import DEFAULT_WHEEL, TERRAINS, Terrain, Wheel, load_terrain
from wheelsoil.model.terrain import load_terrain_file

GOOD = """\
name = "Test loam"
c_kpa = 5.0
phi_deg = 20.0
K_m = 0.02
n = 0.8
kc = 20.0
kphi = 800.0
source = "made up for a test"
"""


def test_paper_soils_in_si_units():
    clay, sand = TERRAINS["clay"], TERRAINS["sand"]
    assert clay.c == pytest.approx(7580.0)
    assert clay.phi == pytest.approx(math.radians(14.0))
    assert clay.phi_deg == pytest.approx(14.0)
    assert (clay.K, clay.n) == (0.025, 0.85)
    assert clay.kc == pytest.approx(43680.0)
    assert clay.kphi == pytest.approx(499300.0)
    assert (sand.c, sand.n, sand.kc, sand.kphi) == pytest.approx((1000.0, 1.04, 1000.0, 580000.0))
    assert "Tab. 1" in clay.source and "Tab. 1" in sand.source


def test_library_has_wong_soils_with_sources():
    for slug in ("dry-sand", "lete-sand", "heavy-clay-25", "lean-clay-22", "clayey-soil-38", "snow-us"):
        assert slug in TERRAINS
    dry = TERRAINS["dry-sand"]
    assert (dry.n, dry.kc, dry.kphi, dry.c, dry.phi_deg) == pytest.approx((1.1, 990.0, 1528430.0, 1040.0, 28.0))
    for slug, terrain in TERRAINS.items():
        assert terrain.source.strip(), slug
        assert slug == slug.lower() and " " not in slug
    assert load_terrain("clay") is TERRAINS["clay"]


def test_field_units_round_trip():
    for terrain in TERRAINS.values():
        fu = terrain.field_units()
        back = Terrain.from_field_units(
            fu["name"], source=fu["source"], **{k: fu[k] for k in ("c_kpa", "phi_deg", "K_m", "n", "kc", "kphi")}
        )
        for field in ("c", "phi", "K", "n", "kc", "kphi"):
            assert getattr(back, field) == pytest.approx(getattr(terrain, field), rel=1e-12)
        assert (back.name, back.source) == (terrain.name, terrain.source)


def test_custom_single_terrain_file(tmp_path):
    path = tmp_path / "loam.toml"
    path.write_text(GOOD)
    t = load_terrain(path)
    assert t.name == "Test loam" and t.kc == pytest.approx(20e3) and t.c == pytest.approx(5e3)
    assert load_terrain(str(path)) == t


def test_custom_library_file_and_slug_selection(tmp_path):
    body = GOOD.replace('name = "Test loam"\n', "")
    path = tmp_path / "lib.toml"
    path.write_text("[terrains.a]\n" + body + "\n[terrains.b]\n" + body.replace("n = 0.8", "n = 0.9"))
    assert set(load_terrain_file(path)) == {"a", "b"}
    assert load_terrain(f"{path}#b").n == 0.9
    with pytest.raises(ValueError, match="pick one with"):
        load_terrain(path)
    with pytest.raises(ValueError, match="no terrain 'c'"):
        load_terrain(f"{path}#c")


def test_missing_key_is_named_with_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace("K_m = 0.02\n", ""))
    with pytest.raises(ValueError, match=r"bad\.toml: missing key\(s\) K_m"):
        load_terrain(path)


def test_bad_values_are_named(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace("kc = 20.0", 'kc = "twenty"'))
    with pytest.raises(ValueError, match="bad.toml: key kc must be a number"):
        load_terrain(path)
    path.write_text(GOOD.replace("K_m = 0.02", "K_m = -0.02"))
    with pytest.raises(ValueError, match="bad.toml: .*K must be > 0"):
        load_terrain(path)
    path.write_text(GOOD + "kphii = 3\n")
    with pytest.raises(ValueError, match="unknown key.*kphii"):
        load_terrain(path)
    path.write_text("c_kpa = [")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_terrain(path)
    path.write_bytes(GOOD.encode("utf-16"))  # saved by an editor in UTF-16: named, not a bare codec error
    with pytest.raises(ValueError, match="bad.toml: not UTF-8"):
        load_terrain(path)


def test_unknown_name_and_missing_file():
    with pytest.raises(ValueError, match="unknown terrain 'mud'.*clay"):
        load_terrain("mud")
    with pytest.raises(OSError):
        load_terrain("/nonexistent/soil.toml")


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("K", -0.01, "K must be > 0"),
        ("K", 0.0, "K must be > 0"),
        ("c", -1.0, "c must be >= 0"),
        ("n", 3.0, r"n must be in \(0, 3\)"),
        ("n", 0.0, r"n must be in \(0, 3\)"),
        ("phi", math.radians(90.0), r"phi must be in \[0, 90\)"),
        ("kphi", float("nan"), "kphi must be finite"),
    ],
)
def test_terrain_validation(field, value, message):
    with pytest.raises(ValueError, match=message):
        TERRAINS["clay"].replace(**{field: value})


def test_replace_is_a_copy():
    clay = TERRAINS["clay"]
    other = clay.replace(K=0.01)
    assert other.K == 0.01 and clay.K == 0.025 and other.kc == clay.kc


def test_wheel():
    assert DEFAULT_WHEEL == Wheel(0.47, 0.32)
    with pytest.raises(ValueError, match="radius"):
        Wheel(0.0, 0.3)
    with pytest.raises(ValueError, match="width"):
        Wheel(0.4, float("inf"))


# --- lab uncertainties (prior_sd, [uncertainty] tables, terrain_prior) --------------------------

from wheelsoil.model.terrain import DEFAULT_PRIOR_SD, PRIOR_KEYS, default_prior_sd, terrain_prior  # noqa: E402


def test_default_prior_sd_follows_the_documented_rules():
    clay, sand = TERRAINS["clay"], TERRAINS["sand"]
    assert set(clay.prior_sd) == set(PRIOR_KEYS)
    assert clay.prior_sd == pytest.approx({"k_eq": 0.30, "n": 0.10, "c": 0.30 * 7580.0,
                                           "phi": math.radians(2.5), "K": 0.30 * 0.025})
    # sand's c = 1 kPa: 30 % would be 0.3 kPa, the floor of 1 kPa applies
    assert sand.prior_sd["c"] == pytest.approx(DEFAULT_PRIOR_SD["c_min_pa"])
    assert clay.prior_sd_origin == dict.fromkeys(PRIOR_KEYS, "default")
    # defaults follow the current values
    assert clay.replace(K=0.01).prior_sd["K"] == pytest.approx(0.003)
    assert default_prior_sd(0.0, 0.02) == pytest.approx(
        {"k_eq": 0.3, "n": 0.1, "c": 1000.0, "phi": math.radians(2.5), "K": 0.006})


def test_builtin_assumed_k_carries_a_wider_prior():
    dry = TERRAINS["dry-sand"]
    assert dry.prior_sd["K"] == pytest.approx(0.5 * dry.K)
    assert dry.prior_sd_origin["K"] == "terrain" and dry.prior_sd_origin["n"] == "default"
    assert "assumed" in dry.uncertainty_source
    for slug, terrain in TERRAINS.items():
        if "K assumed" in terrain.source:
            assert terrain.prior_sd["K"] == pytest.approx(0.5 * terrain.K), slug
    assert TERRAINS["clay"].uncertainty == {}


def test_terrain_prior_in_si_for_the_wheel():
    clay = TERRAINS["clay"]
    prior = terrain_prior(clay, DEFAULT_WHEEL)
    assert list(prior) == list(PRIOR_KEYS)
    k_eq = 43680.0 / 0.32 + 499300.0
    assert prior["k_eq"] == pytest.approx((k_eq, 0.3 * k_eq))
    assert prior["n"] == pytest.approx((0.85, 0.1))
    assert prior["c"] == pytest.approx((7580.0, 2274.0))
    assert prior["phi"] == pytest.approx((math.radians(14.0), math.radians(2.5)))
    assert prior["K"] == pytest.approx((0.025, 0.0075))
    # k_eq depends on the width, its relative SD does not
    wide = terrain_prior(clay, Wheel(0.47, 0.64))["k_eq"]
    assert wide[0] < prior["k_eq"][0] and wide[1] / wide[0] == pytest.approx(0.3)
    with pytest.raises(ValueError, match=r"kc/b \+ kphi"):
        terrain_prior(clay.replace(kc=-1e6, kphi=1.0), DEFAULT_WHEEL)


def test_replace_overrides_merge_and_reset():
    clay = TERRAINS["clay"]
    a = clay.replace(prior_sd={"phi": math.radians(1.0)})
    assert a.prior_sd["phi"] == pytest.approx(math.radians(1.0))
    assert a.prior_sd["n"] == 0.1 and a.prior_sd_origin["phi"] == "terrain"
    b = a.replace(prior_sd={"n": 0.05})
    assert b.uncertainty == {"phi": pytest.approx(math.radians(1.0)), "n": 0.05}
    assert b.replace(uncertainty=None).prior_sd == clay.prior_sd
    assert a != clay and a.replace(prior_sd={}) == a
    assert hash(a) == hash(clay.replace(prior_sd={"phi": math.radians(1.0)}))
    assert clay.replace(K=0.01).uncertainty == {}  # other changes keep the (empty) overrides
    with pytest.raises(ValueError, match="prior_sd must be a mapping"):
        clay.replace(prior_sd=0.1)


@pytest.mark.parametrize(
    "sd, message",
    [
        ({"n": -0.1}, r"uncertainty n must be a finite number > 0 \[-\], got -0.1"),
        ({"phi": float("nan")}, r"uncertainty phi must be a finite number > 0 \[rad\], got nan"),
        ({"K": 0.0}, r"uncertainty K must be a finite number > 0"),
        ({"c": "big"}, r"uncertainty c must be a number"),
        ({"kc": 0.1}, r"unknown uncertainty 'kc'; names: k_eq, n, c, phi, K"),
    ],
)
def test_replace_validates_uncertainty(sd, message):
    with pytest.raises(ValueError, match=message):
        TERRAINS["clay"].replace(prior_sd=sd)


UNC = """
[uncertainty]
k_eq_rel = 0.2
n = 0.05
c_kpa = 0.5
phi_deg = 1.5
K_rel = 0.4
source = "three repeated plate and shear-ring tests"
"""


def test_uncertainty_table_in_field_units(tmp_path):
    path = tmp_path / "loam.toml"
    path.write_text(GOOD + UNC)
    t = load_terrain(path)
    assert t.prior_sd == pytest.approx({"k_eq": 0.2, "n": 0.05, "c": 500.0,
                                        "phi": math.radians(1.5), "K": 0.4 * 0.02})
    assert t.uncertainty_source == "three repeated plate and shear-ring tests"
    assert t.uncertainty_field_units() == pytest.approx(
        {"k_eq_rel": 0.2, "n": 0.05, "c_kpa": 0.5, "phi_deg": 1.5, "K_m": 0.008})
    # partial table: the rest stay defaults; relative c
    path.write_text(GOOD + "\n[uncertainty]\nc_rel = 0.5\n")
    t = load_terrain(path)
    assert t.prior_sd["c"] == pytest.approx(2500.0) and t.prior_sd["n"] == 0.1
    assert t.prior_sd_origin == {"k_eq": "default", "n": "default", "c": "terrain", "phi": "default",
                                 "K": "default"}


def test_uncertainty_table_in_a_library_file(tmp_path):
    body = GOOD.replace('name = "Test loam"\n', "")
    path = tmp_path / "lib.toml"
    path.write_text("[terrains.a]\n" + body + "\n[terrains.a.uncertainty]\nphi_deg = 4.0\n\n[terrains.b]\n" + body)
    lib = load_terrain_file(path)
    assert lib["a"].prior_sd["phi"] == pytest.approx(math.radians(4.0))
    assert lib["b"].prior_sd["phi"] == pytest.approx(math.radians(2.5))


@pytest.mark.parametrize(
    "table, message",
    [
        ("n = -0.1", r"bad\.toml \[uncertainty\]: key n must be a finite standard deviation > 0 \[-\], got -0.1"),
        ("phi_deg = nan", r"bad\.toml \[uncertainty\]: key phi_deg must be a finite standard deviation > 0"),
        ("K_m = inf", r"bad\.toml \[uncertainty\]: key K_m must be a finite standard deviation > 0"),
        ("c_kpa = 0", r"bad\.toml \[uncertainty\]: key c_kpa must be a finite"),
        ('k_eq_rel = "30 %"', r"bad\.toml \[uncertainty\]: key k_eq_rel must be a number"),
        ("kc = 1.0", r"bad\.toml \[uncertainty\]: unknown key\(s\) kc"),
        ("K_m = 0.01\nK_rel = 0.3", r"bad\.toml \[uncertainty\]: give K_m or K_rel, not both"),
    ],
)
def test_bad_uncertainty_is_named_with_file_and_key(tmp_path, table, message):
    path = tmp_path / "bad.toml"
    path.write_text(GOOD + "\n[uncertainty]\n" + table + "\n")
    with pytest.raises(ValueError, match=message):
        load_terrain(path)


def test_bad_uncertainty_in_library_names_the_entry(tmp_path):
    body = GOOD.replace('name = "Test loam"\n', "")
    path = tmp_path / "lib.toml"
    path.write_text("[terrains.a]\n" + body + "\n[terrains.a.uncertainty]\nn = -1\n")
    with pytest.raises(ValueError, match=r"lib\.toml \[terrains\.a\] \[uncertainty\]: key n"):
        load_terrain_file(path)
    path.write_text("[terrains.a]\n" + body + "\nuncertainty = 0.3\n")
    with pytest.raises(ValueError, match=r"lib\.toml \[terrains\.a\] \[uncertainty\]: must be a table"):
        load_terrain_file(path)


def test_with_values_is_replace_checked_the_same_way():
    """The fitter's fast copy gives the terrain ``replace`` gives and refuses what the constructor refuses."""
    sand = load_terrain("sand").replace(prior_sd={"n": 0.2})
    fast = sand.with_values(n=0.9, kc=0.0, kphi=2.0e6)
    assert fast == sand.replace(n=0.9, kc=0.0, kphi=2.0e6)
    assert fast.prior_sd == sand.prior_sd and sand.n != 0.9  # the original is untouched
    with pytest.raises(ValueError, match="sinkage exponent n"):
        sand.with_values(n=3.5)
    with pytest.raises(ValueError, match="finite"):
        sand.with_values(K=float("nan"))
    with pytest.raises(TypeError, match="not a soil value"):
        sand.with_values(name="other")


@pytest.mark.parametrize("key, value, message", [
    ("c_kpa", 5000.0, r"loam\.toml: c_kpa = 5000 \[kPa\] is far beyond the built-in library's soils .*cohesion in Pa"),
    ("K_m", 20.0, r"loam\.toml: K_m = 20 \[m\] .*K in mm instead of m"),
    ("phi_deg", 0.35, r"loam\.toml: phi_deg = 0\.35 deg is the friction angle in radians\? \(20\.1 deg\)"),
])
def test_a_terrain_file_in_the_wrong_unit_is_refused_naming_the_likely_mixup(tmp_path, key, value, message):
    path = tmp_path / "loam.toml"
    path.write_text(GOOD)
    assert load_terrain(path).c == pytest.approx(5000.0)  # the good file loads
    line = next(ln for ln in GOOD.splitlines() if ln.startswith(key + " "))
    path.write_text(GOOD.replace(line, f"{key} = {value}"))
    with pytest.raises(ValueError, match=message):
        load_terrain(path)
    # every built-in terrain is within the limits (they are loaded from the same TOML path)
    assert len(TERRAINS) > 10
