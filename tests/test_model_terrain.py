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
