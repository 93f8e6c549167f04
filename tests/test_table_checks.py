"""Checks of the tables and terrain files a user gives ``wheelsoil fit``: each odd input found by a
probe of the command is an error or a note naming the file and the place (file line, column, key),
never a silent fit (tables are checked at load time: :func:`wheelsoil.pipeline.load_inputs`,
:func:`wheelsoil.model.data.prepare_data`; terrain files: :func:`wheelsoil.model.load_terrain`)."""

from __future__ import annotations

import glob
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from wheelsoil.model.data import prepare_data
from wheelsoil.pipeline import load_inputs

ROOT = Path(__file__).resolve().parents[1]
CMU_TABLES = sorted(glob.glob(str(ROOT / "tests" / "data" / "cmu-3d-terramechanics" / "*.csv")))
TERRAIN = "c_kpa = 7.58\nphi_deg = 14.0\nK_m = 0.025\nn = 0.85\nkc = {kc}\nkphi = {kphi}\n"


def _table(n: int = 20, seed: int = 1) -> pd.DataFrame:
    """A driven wheel's steady-state table in SI units (0.47 m wheel, 10 kN): slip, load, Dp, torque, sinkage."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0.12, 0.8, n)
    w = 1e4 + rng.normal(0, 100, n)
    return pd.DataFrame({"slip": s.round(4), "load_n": w.round(1),
                         "drawbar_pull_n": (3e3 * s + rng.normal(0, 50, n)).round(2),
                         "torque_nm": (2e3 + 2e3 * s).round(2), "sinkage_m": (0.05 + 0.05 * s).round(5)})


def _load(path: Path, **kw):
    df, info = load_inputs([path], wheel_radius_m=0.47, wheel_width_m=0.32, **kw)
    return df, info, prepare_data(df, source=str(path), wheel_radius_m=0.47)


def test_tables_stating_different_wheels_are_not_fitted_jointly(tmp_path):
    """Before: the second table's wheel was replaced by the first's without a word."""
    a, b = tmp_path / "wA.csv", tmp_path / "wB.csv"
    _table().to_csv(a, index=False)
    _table(seed=2).to_csv(b, index=False)
    (tmp_path / "wA.json").write_text(json.dumps({"wheel": {"radius_m": 0.0625, "width_m": 0.06}}))
    (tmp_path / "wB.json").write_text(json.dumps({"wheel": {"radius_m": 0.1, "width_m": 0.1}}))
    with pytest.raises(ValueError, match=r"wA\.csv and .*wB\.csv: the tables state different wheels, r = 0.0625 "
                                         r"m, b = 0.06 m .*and r = 0.1 m, b = 0.1 m.*fit them separately, one wheel "
                                         r"per fit"):
        load_inputs([a, b])
    # the command line gives the wheel: each table's conflict is a note
    _, info = load_inputs([a, b], wheel_radius_m=0.0625, wheel_width_m=0.06)
    assert any(n.startswith("WHEEL RADIUS CONFLICT: wB.csv") for n in info["notes"])
    assert any(n.startswith("WHEEL WIDTH CONFLICT: wB.csv") for n in info["notes"])
    (tmp_path / "wB.json").write_text(json.dumps({"wheel": {"radius_m": 0.0625, "width_m": 0.06}}))
    _, info = load_inputs([a, b])  # one wheel: fitted jointly
    assert (info["wheel_radius_m"], info["wheel_width_m"]) == (0.0625, 0.06)


def test_a_terrain_whose_pressure_sinkage_modulus_is_not_positive_is_refused_naming_the_file(tmp_path, capsys):
    """A negative kphi ran to 'samples used: 0' with nan; a negative kc is allowed while kc/b + kphi > 0."""
    from wheelsoil.model import Wheel, load_terrain
    from wheelsoil.model.terrain import check_k_eq
    from wheelsoil.pipeline import run_fit

    neg = tmp_path / "neg_kphi.toml"
    neg.write_text(TERRAIN.format(kc=43.68, kphi=-499.3))
    with pytest.raises(ValueError, match=r"neg_kphi\.toml: kphi = -499.3, kc = 43.68.*kc/b \+ kphi"):
        load_terrain(neg)
    kc_neg = tmp_path / "kc_neg.toml"
    kc_neg.write_text(TERRAIN.format(kc=-50.0, kphi=500.0))
    ter = load_terrain(kc_neg)
    assert check_k_eq(ter, 0.32, str(kc_neg)) == pytest.approx(-50e3 / 0.32 + 500e3)
    with pytest.raises(ValueError, match=r"kc_neg\.toml: kc/b \+ kphi = -50/0.06 \+ 500 .*b > 0.1 m"):
        check_k_eq(ter, 0.06, str(kc_neg))
    tab = tmp_path / "t.csv"
    _table().to_csv(tab, index=False)
    with pytest.raises(ValueError, match=r"kc_neg\.toml: kc/b \+ kphi"):
        run_fit([tab], str(kc_neg), tmp_path / "out", wheel_radius=0.1, wheel_width=0.06)
    assert Wheel(0.1, 0.06)  # the wheel itself is fine
    from wheelsoil.cli import main  # predict names the file too

    assert main(["predict", "--terrain", str(kc_neg), "--wheel-width", "0.06", "--load", "5000", "--slip", "0.2"]) == 2
    assert "kc_neg.toml: kc/b + kphi" in capsys.readouterr().err


def test_moduli_in_newtons_are_refused_and_every_shipped_terrain_loads(tmp_path):
    from wheelsoil.model import TERRAINS, load_terrain
    from wheelsoil.model.terrain import check_k_eq, load_terrain_file

    for kc, kphi, key in ((43680.0, 499300.0, "kc"), (43.68, 499300.0, "kphi"), (-43680.0, 499.3, "kc")):
        p = tmp_path / "si_k.toml"
        p.write_text(TERRAIN.format(kc=kc, kphi=kphi))
        with pytest.raises(ValueError, match=rf"si_k\.toml: {key} = .*{key} in N/m\^\(n\+\d\) instead of kN"):
            load_terrain(p)
    for slug, ter in TERRAINS.items():
        for b in (0.03, 0.06, 0.32, 1.0):
            check_k_eq(ter, b, slug)
    files = sorted(glob.glob(str(ROOT / "benchmarks" / "**" / "*.toml"), recursive=True))
    assert files
    for f in files:
        for ter in load_terrain_file(f).values():
            check_k_eq(ter, 0.06, f)
            check_k_eq(ter, 0.32, f)


def test_slip_in_per_cent_is_found_with_skid_rows_naming_the_lines(tmp_path):
    """The CMU table in per cent: half its rows are skid rows (negative), so 'most values above 1.5'
    missed it and one slip value was left ('only one slip value')."""
    src = pd.read_csv(CMU_TABLES[0])
    p = tmp_path / "cmu_pct.csv"
    src.assign(slip=100.0 * src["slip"]).to_csv(p, index=False)
    df, _ = load_inputs([p])
    lines = 2 + np.flatnonzero(np.abs(100.0 * src["slip"].to_numpy()) > 1.5)
    with pytest.raises(ValueError, match=rf"cmu_pct\.csv: the slip column looks like per cent.*lines "
                                         rf"{', '.join(map(str, lines[:10]))} and {lines.size - 10} more"
                                         r".*divide it by 100"):
        prepare_data(df, source=str(p))
    # the table as shipped is read as before
    df, info = load_inputs([CMU_TABLES[0]])
    assert prepare_data(df, source=CMU_TABLES[0]).n == 12
    # one typo (a slip of 35 in a table of fractions) is no per-cent column: that row is left out, its line named
    typo = src.copy()
    row = int(np.flatnonzero(src["slip"].to_numpy() > 0.2)[0])
    typo.loc[row, "slip"] = 35.0
    t = tmp_path / "typo.csv"
    typo.to_csv(t, index=False)
    df, _ = load_inputs([t])
    fd = prepare_data(df, source=str(t))
    assert fd.n == 11 and any(f"typo.csv line {row + 2}" in n and "s >= 1" in n for n in fd.notes)


def test_channels_that_cannot_be_measurements(tmp_path):
    """A sinkage of the other sign, a channel of one value (not measured), a Dp or torque in kN (kN m):
    before, each was fitted as measured."""
    base = _table()
    p = tmp_path / "v.csv"
    base.assign(sinkage_m=-base["sinkage_m"]).to_csv(p, index=False)
    with pytest.raises(ValueError, match=r"v\.csv: sinkage_m is negative on 20 of 20 lines \(lines 2, 3, .* and 10 "
                                         r"more\).*flip the column's sign"):
        load_inputs([p])
    for col in ("torque_nm", "sinkage_m"):
        base.assign(**{col: 0.0}).to_csv(p, index=False)
        df, info, data = _load(p)
        assert col not in df.columns and col not in data.channels
        assert any(n.startswith(f"v.csv: COLUMN DROPPED: {col} is 0 on every line: not measured? leave the "
                                "column out") for n in info["notes"])
    base.assign(drawbar_pull_n=0.0).to_csv(p, index=False)
    with pytest.raises(ValueError, match=r"v\.csv: drawbar_pull_n is 0 on every line: not a measurement"):
        load_inputs([p])
    base.assign(drawbar_pull_n=base["drawbar_pull_n"] / 1000).to_csv(p, index=False)
    with pytest.raises(ValueError, match=r"v\.csv: drawbar_pull_n is below 0.5% of the median load.*in kN\?"):
        load_inputs([p])
    base.assign(torque_nm=base["torque_nm"] / 1000).to_csv(p, index=False)
    with pytest.raises(ValueError, match=r"v\.csv: torque_nm is below 0.5% of r = 0.47 m times the median "
                                         r"load.*in kN m\?"):
        load_inputs([p], wheel_radius_m=0.47)


@pytest.mark.parametrize("path", CMU_TABLES, ids=lambda p: Path(p).stem)
def test_the_cmu_tables_load_as_before(path):
    """Skid rows (negative slip, |Dp| ~ 2 W of a locked wheel) are no sign of a unit error."""
    df, info = load_inputs([path])
    data = prepare_data(df, source=path, wheel_radius_m=info["wheel_radius_m"])
    assert info["notes"] == [] and data.n == 12 and sorted(data.channels) == ["drawbar_pull_n", "sinkage_m"]
    assert not df["_copy"].any()
    assert [n.split(" ", 1)[1][:8] for n in data.notes] == ["skid row", "row(s) w"]


def test_a_row_pulling_more_than_twice_its_load_is_excluded_naming_its_line(tmp_path):
    t = _table()
    t.loc[5, "drawbar_pull_n"] = 1e6
    p = tmp_path / "v_outlier.csv"
    t.to_csv(p, index=False)
    _, _, data = _load(p)
    assert data.n == 19
    assert any("1 row(s) with |drawbar_pull_n| above 2 times load_n excluded (v_outlier.csv line 7)" in n
               for n in data.notes)


def test_exact_copies_of_rows_count_once(tmp_path):
    t = _table()
    p = tmp_path / "x3.csv"
    p.write_text(t.to_csv(index=False) + t.to_csv(index=False, header=False) * 2)
    df, info, data = _load(p)
    assert data.n == 20 and len(df) == 60
    assert any(n.startswith("x3.csv: 40 row(s) are exact copies of earlier rows (lines 22, 23, 24, 25, 26, 27, 28, "
                            "29, 30, 31 and 30 more)") for n in info["notes"])


def test_a_sidecar_without_the_wheel_layout_says_what_it_has(tmp_path):
    p = tmp_path / "rig.csv"
    _table().to_csv(p, index=False)
    for meta, has, missing in (({"radius_m": 0.0625, "width_m": 0.06}, "radius_m, width_m",
                                "wheel.radius_m and no wheel.width_m"),
                               ({"wheel": {"diameter_m": 0.125, "width_m": 0.06}}, "wheel.diameter_m, wheel.width_m",
                                "wheel.radius_m")):
        (tmp_path / "rig.json").write_text(json.dumps(meta))
        _, info = load_inputs([p])
        note = next(n for n in info["notes"] if "SIDECAR" in n)
        assert note.startswith(f"rig.csv: WHEEL SIDECAR INCOMPLETE: rig.json was found but has no {missing} "
                               f"(its keys: {has})") and '{"wheel": {"radius_m": R, "width_m": B}}' in note


def test_an_empty_models_list_is_an_error(tmp_path, capsys):
    from wheelsoil.cli import main

    p = tmp_path / "t.csv"
    _table().to_csv(p, index=False)
    assert main(["fit", str(p), "--terrain", "clay", "--models", "", "-o", str(tmp_path / "o"), "-q"]) == 2
    assert "--models is empty" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_rows_are_named_by_their_file_line(tmp_path):
    """A comment line and a blank line before the rows: the messages count the file's lines, not the
    reader's 0-based rows ('row 18' was line 20)."""
    t = _table()
    t.loc[[3, 12], "load_n"] = np.nan
    p = tmp_path / "c.csv"
    body = t.to_csv(index=False).splitlines()
    p.write_text("# rig 2, wheel A\n" + body[0] + "\n\n" + "\n".join(body[1:]) + "\n")
    df, info, data = _load(p)
    assert any(n == "c.csv: 1 comment line(s) starting with '#' before the header skipped" for n in info["notes"])
    # header on line 2, a blank line 3: data row i is on line i + 4
    assert any("2 row(s) with NaN or non-numeric slip/load_n/drawbar_pull_n excluded (c.csv lines 7, 16)" in n
               for n in data.notes)
    t.loc[[4, 9], "sinkage_m"] = [42.0, 55.0]
    t.to_csv(p, index=False)
    df, _ = load_inputs([p])
    with pytest.raises(ValueError, match=r"sinkage_m reaches 55 m \(c\.csv lines 6, 11\)"):
        prepare_data(df, source=str(p), wheel_radius_m=0.47)


def test_a_title_line_a_missing_terrain_file_and_a_terrain_in_the_wrong_layout(tmp_path):
    from wheelsoil.model import load_terrain

    p = tmp_path / "title.csv"
    p.write_text("Testbed run 2024-03-01\n" + _table().to_csv(index=False))
    with pytest.raises(ValueError, match=r"title\.csv: line 2 holds the header .*the header must be the first line"):
        load_inputs([p])
    with pytest.raises(FileNotFoundError, match=r"--terrain: no such file .*nosuch\.toml \(built-in terrains: clay, "):
        load_terrain(tmp_path / "nosuch.toml")
    w = tmp_path / "wrongtable.toml"
    w.write_text("[clay]\n" + TERRAIN.format(kc=43.68, kphi=499.3))
    with pytest.raises(ValueError, match=r"wrongtable\.toml: no terrain keys at the top level, but the table\(s\) "
                                         r"\[clay\].*\[terrains\.<slug>\].*\(write \[terrains\.clay\]\)"):
        load_terrain(w)


def test_loud_notes_are_shown_under_the_verdict(tmp_path):
    """A wheel assumed or a radius in conflict sat at the bottom of report.html among the notes: each loud note
    is also shown under the verdict, before the evidence."""
    from wheelsoil.model.report import LOUD_NOTE
    from wheelsoil.pipeline import run_fit

    tab = tmp_path / "t.csv"
    _table().to_csv(tab, index=False)
    rep = run_fit([tab], "clay", tmp_path / "out", models=["wong", "vasilev"], progress=False)
    loud = [n for n in rep["notes"] if LOUD_NOTE.match(n)]
    assert any("WHEEL GEOMETRY ASSUMED" in n for n in loud)
    page = (tmp_path / "out" / "report.html").read_text()
    first = page.index("Read first")
    assert first < page.index("What the verdict rests on")
    assert page.count("WHEEL GEOMETRY ASSUMED") >= 2  # under the verdict and among the notes
