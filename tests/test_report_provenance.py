"""Every report the README's commands write: provenance, overview, flags, defined metrics; and a
report re-run from its provenance alone gives the same report.json (except the analysis time)."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from test_report_html import check_html

from wheelsoil.daq.provenance import file_sha256
from wheelsoil.model import DEFAULT_WHEEL, load_terrain
from wheelsoil.model.fit import synthetic_data
from wheelsoil.model.report import _canon
from wheelsoil.pipeline import run_fit

ROOT = Path(__file__).resolve().parents[1]
RECORDINGS = sorted((ROOT / "recordings").glob("*.mcap"))


def _shared(rel: str) -> Path:
    """``shared/<rel>`` next to the checkout or a parent of it (worktrees live one level deeper)."""
    for p in ROOT.parents:
        if (p / "shared" / rel).exists():
            return p / "shared" / rel
    return ROOT.parent / "shared" / rel


CMU = _shared("data/cmu-grouser-wheel/cmu_pavlov2023_grouser_beta0.csv")


def _wheelsoil(*args, cwd=ROOT):
    proc = subprocess.run([sys.executable, "-m", "wheelsoil", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc


def _without_created(rep: dict) -> dict:
    rep = json.loads(json.dumps(rep))
    rep["provenance"].pop("created")
    return rep


@pytest.fixture(scope="module")
def readme_reports(tmp_path_factory):
    """The reports of the README's commands: `make report` (each shipped recording, its terrain
    from the file name) and the CMU example."""
    out = {}
    base = tmp_path_factory.mktemp("readme")
    for rec in RECORDINGS:
        name = rec.stem
        _wheelsoil("fit", rec.relative_to(ROOT), "--terrain", name.split("-")[0], "-q", "-o", base / name)
        out[name] = base / name
    if CMU.exists():
        _wheelsoil("fit", CMU, "--terrain", "dry-sand", "--fit-terrain", "--wheel-radius", "0.0625",
                   "--wheel-width", "0.06", "-q", "-o", base / "cmu")
        out["cmu"] = base / "cmu"
    return out


def test_the_readme_commands_are_the_ones_tested():
    readme = (ROOT / "README.md").read_text()
    make = (ROOT / "Makefile").read_text()
    assert "make report" in readme and "wheelsoil fit $$rec --terrain $$terrain -o reports/$$name" in make
    assert "cmu_pavlov2023_grouser_beta0.csv" in readme and "--terrain dry-sand --fit-terrain" in readme
    assert RECORDINGS, "no shipped recordings"


def test_every_readme_report_has_provenance_overview_flags_and_defined_metrics(readme_reports):
    assert len(readme_reports) >= len(RECORDINGS)
    for name, out in readme_reports.items():
        rep = json.loads((out / "report.json").read_text())
        text = (out / "report.html").read_text()
        check_html(text)
        p = rep["provenance"]
        assert p["version"] and p["command"][:2] == ["wheelsoil", "fit"] and p["created"].endswith("Z")
        for inp in p["inputs"]:
            assert inp["sha256"] == file_sha256(Path(p["cwd"]) / inp["path"])
            assert inp["provenance"]["kind"] in {"recorded", "imported", "simulated", "table", "unknown"}
            assert "effect" not in inp["provenance"]
        st = p["settings"]
        for key in ("slip_min", "models", "fit_terrain", "sinkage", "rate_hz", "cutoff_hz", "inertia", "terrain"):
            assert key in st, key
        assert st["terrain"]["values"]["c_pa"] == rep["terrain"]["c_pa"]
        assert "Provenance: how to re-run this report" in text and p["inputs"][0]["sha256"] in text
        if name == "cmu":  # a table: no overview, its provenance says table
            assert p["inputs"][0]["provenance"] == {"kind": "table"}
            assert rep["data_quality"][0]["kind"] == "table"
        else:
            vc = p["vehicle_config"]
            assert vc["dbcs"] and all(len(d["sha256"]) == 64 for d in vc["dbcs"])
            assert vc["wheel_radius_used_m"] == rep["wheel"]["radius_m"]
            assert "overview.png" in rep["figures"] and (out / "overview.png").stat().st_size > 10_000
            q = rep["data_quality"][0]
            assert q["used_in_fit"] == rep["samples_used"]  # the overview marks exactly what was fitted
            assert 0 < q["valid_share"] <= 1 and q["lost_frames"]
            assert "GNSS latency found and removed" in text and "lost frames" in text
        # flags next to the coefficient, and in the JSON
        assert isinstance(rep["flags"], list)
        for fl in rep["flags"]:
            assert fl["kind"] in {"at_bound", "correlation", "ill_conditioned", "inconsistent"}
            if fl.get("parameter") and "," not in fl["parameter"]:
                par = rep["models"][_canon(fl["model"])]["parameters"][fl["parameter"]]
                assert fl["kind"] in par["flags"]
        assert "<h3>Flags</h3>" in text
        for term in ("M0", "R0", "R²", "CV R0", "2 ln(Z/Z_Wong)", "probability"):
            assert f"<dt>{term}</dt>" in text


def test_clay_lyasko_degenerate_fit_is_flagged(readme_reports):
    if "clay-run1" not in readme_reports:
        pytest.skip("no shipped clay recording")
    rep = json.loads((readme_reports["clay-run1"] / "report.json").read_text())
    ly = rep["models"]["lyasko"]
    cond = ly["condition_number"]
    corr = ly["correlation"]["matrix"][0][1]
    kinds = {f["kind"] for f in ly["flags"]}
    # each flag follows from the fit's own numbers
    assert ("ill_conditioned" in kinds) == (cond is not None and cond > 100)
    assert ("correlation" in kinds) == (abs(corr) > 0.95)
    assert ("at_bound" in kinds) == any(p["at_bound"] for p in ly["parameters"].values())
    html_text = (readme_reports["clay-run1"] / "report.html").read_text()
    if kinds:
        assert "class='flag'" in html_text


def test_rerun_from_provenance_alone_gives_the_same_report(readme_reports, tmp_path):
    name = "clay-run1" if "clay-run1" in readme_reports else next(iter(readme_reports))
    out = readme_reports[name]
    first = json.loads((out / "report.json").read_text())
    p = first["provenance"]
    keep = tmp_path / "first"
    shutil.copytree(out, keep)
    shutil.rmtree(out)
    cmd = p["command"]
    assert cmd[0] == "wheelsoil"
    _wheelsoil(*cmd[1:], cwd=p["cwd"])
    again = json.loads((out / "report.json").read_text())
    assert _without_created(again) == _without_created(first)
    shutil.rmtree(out)
    shutil.copytree(keep, out)  # leave the fixture as it was


def test_a_library_call_records_the_equivalent_command_and_reruns(tmp_path):
    df = synthetic_data(load_terrain("sand"), DEFAULT_WHEEL, "ding", {"n1": 0.3}, kind="table", n_rows=40,
                        load_n=13000.0, seed=3)
    csv = tmp_path / "t.csv"
    df.to_csv(csv, index=False)
    rep = run_fit([csv], "sand", tmp_path / "lib", models=["ding", "terrain_mismatch"], slip_min=0.15)
    cmd = rep["provenance"]["command"]
    assert cmd[:2] == ["wheelsoil", "fit"] and "--slip-min" in cmd and "ding,terrain_mismatch" in cmd
    shutil.move(tmp_path / "lib", tmp_path / "lib0")
    _wheelsoil(*cmd[1:], cwd=rep["provenance"]["cwd"])
    again = json.loads((tmp_path / "lib" / "report.json").read_text())
    assert _without_created(again) == _without_created(rep)


def test_a_simulated_recording_is_said_to_be_simulated_without_its_hidden_effect(tmp_path, monkeypatch):
    if not RECORDINGS:
        pytest.skip("no shipped recording")
    from wheelsoil.daq import info as info_mod

    secret = {"kind": "simulated", "seed": 7, "simulator": "wheelsoil.simulate 0.1.0", "wheelsoil_version": "0.1.0",
              "effect": "ding", "params": {"n1": 0.3},
              "command": ["wheelsoil", "simulate", "--terrain", "clay", "--effect", "ding", "--param=n1=0.3",
                          "-o", "x.mcap"]}
    monkeypatch.setattr(info_mod.RecordingInfo, "provenance", property(lambda self: dict(secret)))
    rep = run_fit([RECORDINGS[0]], RECORDINGS[0].stem.split("-")[0], tmp_path / "r", models=["vasilev"])
    prov = rep["provenance"]["inputs"][0]["provenance"]
    assert prov["kind"] == "simulated" and prov["seed"] == 7
    assert "effect" not in prov and "params" not in prov
    assert prov["command"] == ["wheelsoil", "simulate", "--terrain", "clay", "--effect", "(hidden)",
                               "--param=(hidden)", "-o", "x.mcap"]
    text = (tmp_path / "r" / "report.html").read_text()
    assert "Simulated recording." in text and "--truth" in text
    assert '"ding"' not in json.dumps(rep["provenance"])  # the hidden effect; vasilev was asked for
    check_html(text)


def test_cli_options_reach_the_settings(tmp_path):
    df = synthetic_data(load_terrain("sand"), DEFAULT_WHEEL, "wong", {}, kind="table", n_rows=30, load_n=13000.0,
                        seed=4)
    csv = tmp_path / "t.csv"
    df.to_csv(csv, index=False)
    _wheelsoil("fit", csv, "--terrain", "sand", "--models", "vasilev", "--slip-min", "0.2", "--sinkage", "balance",
               "--rate", "50", "--no-inertia", "-q", "-o", tmp_path / "o", cwd=tmp_path)
    rep = json.loads((tmp_path / "o" / "report.json").read_text())
    st = rep["provenance"]["settings"]
    assert st["slip_min"] == 0.2 and st["models"] == ["wong", "vasilev"] and st["sinkage"] == "balance"
    assert st["rate_hz"] == 50.0 and st["inertia"] is False
    assert rep["provenance"]["cwd"] == os.fspath(tmp_path)
    assert rep["provenance"]["command"] == ["wheelsoil", "fit", str(csv), "--terrain", "sand", "--models", "vasilev",
                                            "--slip-min", "0.2", "--sinkage", "balance", "--rate", "50",
                                            "--no-inertia", "-q", "-o", str(tmp_path / "o")]
