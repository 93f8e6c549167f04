"""wheelsoil predict / wheelsoil terrains."""

from __future__ import annotations

import json
import re

import pytest

from wheelsoil.cli import main
from wheelsoil.model import DEFAULT_WHEEL, get_model, load_terrain

KEYS = {"slip", "load_n", "sinkage_m", "theta1_rad", "drawbar_pull_n", "torque_nm", "load_model_n"}


def test_predict_json_matches_library(capsys):
    argv = ["predict", "--terrain", "clay", "--model", "lyasko", "--param", "m1=0.1", "--param", "m2=0.05",
            "--load", "11000", "--slip", "0.1,0.2,0.5", "--json"]
    assert main(argv) == 0
    rows = json.loads(capsys.readouterr().out)
    assert len(rows) == 3 and all(set(r) == KEYS for r in rows)
    f = get_model("lyasko").predict(load_terrain("clay"), DEFAULT_WHEEL, [11000.0] * 3, [0.1, 0.2, 0.5],
                                    {"m1": 0.1, "m2": 0.05})
    assert [r["slip"] for r in rows] == [0.1, 0.2, 0.5]
    assert [r["drawbar_pull_n"] for r in rows] == pytest.approx(list(f.drawbar_pull_n), rel=1e-12)
    assert [r["torque_nm"] for r in rows] == pytest.approx(list(f.torque_nm), rel=1e-12)


def test_predict_table_and_options(capsys, tmp_path):
    soil = tmp_path / "soil.toml"
    soil.write_text("c_kpa = 5\nphi_deg = 20\nK_m = 0.02\nn = 0.8\nkc = 20\nkphi = 800\n")
    argv = ["predict", "--terrain", str(soil), "--load", "8000,9000", "--slip", "0.2,0.4",
            "--wheel-radius", "0.4", "--wheel-width", "0.3", "--sinkage", "balance"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "Dp [N]" in out and "balance" in out and "r=0.4 m" in out
    assert len([line for line in out.splitlines() if line.strip().startswith("0.")]) == 2


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--slip", "0.1,1.2"], r"slip\[1\] = 1.2"),
        (["--slip", "0.1,x"], "comma-separated numbers"),
        (["--slip", "0.1", "--param", "m1"], "NAME=VALUE"),
        (["--slip", "0.1", "--model", "nope"], "unknown model"),
    ],
)
def test_predict_errors_exit_2(capsys, extra, message):
    assert main(["predict", "--terrain", "clay", "--load", "11000", *extra]) == 2
    assert re.search(message, capsys.readouterr().err)


def test_terrains_lists_library(capsys):
    assert main(["terrains"]) == 0
    out = capsys.readouterr().out
    assert "clay" in out and "dry-sand" in out and "Tab. 1" in out and "kN/m^(n+1)" in out
    assert main(["terrains", "--json"]) == 0
    entries = json.loads(capsys.readouterr().out)
    clay = next(e for e in entries if e["slug"] == "clay")
    assert clay["kc"] == pytest.approx(43.68) and clay["phi_deg"] == pytest.approx(14.0) and clay["source"]
