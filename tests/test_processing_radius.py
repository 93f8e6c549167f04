"""One wheel radius (issue 10 item 1): the radius slip is computed with (Eq. 6) is the one
given on the command line / in the call, reported, and the fit uses the same."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from processing_sim import truth_profile, write_recording  # noqa: E402

from wheelsoil.processing import process_recording  # noqa: E402


@pytest.fixture(scope="module")
def small_wheel(tmp_path_factory):
    """A 0.40 m wheel recorded with the default configuration (0.47 m) attached."""
    truth = truth_profile(1, radius_m=0.40)
    info = write_recording(tmp_path_factory.mktemp("radius") / "r40.mcap", truth, seed=2)
    return truth, info["path"]


def _slip_rms(res, truth):
    s = res.signals
    m = s["valid"].to_numpy() & (s["phase"] == "accel").to_numpy()
    err = s["slip"].to_numpy()[m] - np.interp(s["t_s"].to_numpy()[m], truth.t_s, truth.slip)
    return float(np.sqrt(np.mean(err ** 2)))


def test_given_radius_is_the_slip_radius_and_conflict_is_loud(small_wheel):
    truth, path = small_wheel
    res = process_recording(path, wheel_radius_m=0.40)
    assert res.wheel_radius_m == 0.40 and res.wheel_radius_source == "given"
    assert _slip_rms(res, truth) < 0.01
    conflict = [w for w in res.warnings if "WHEEL RADIUS CONFLICT" in w]
    assert conflict and "0.4 m" in conflict[0] and "0.47 m" in conflict[0]
    assert "wheel radius 0.4 m (given)" in res.summary()


def test_config_radius_without_override(small_wheel):
    truth, path = small_wheel
    res = process_recording(path)
    assert res.wheel_radius_m == 0.47 and "configuration" in res.wheel_radius_source
    assert not any("WHEEL RADIUS CONFLICT" in w for w in res.warnings)
    assert _slip_rms(res, truth) > 0.05  # the wrong radius gives the wrong slip


@pytest.mark.parametrize("bad, match", [(470, "did you give mm"), (float("nan"), "plausible"),
                                        (float("inf"), "plausible"), (-0.4, "plausible"), ("x", "number")])
def test_implausible_radius_is_refused(small_wheel, bad, match):
    _, path = small_wheel
    with pytest.raises(ValueError, match=match):
        process_recording(path, wheel_radius_m=bad)


def test_fit_passes_its_radius_to_processing(small_wheel, tmp_path):
    """pipeline.load_inputs (used by run_fit) computes slip with the fit's radius."""
    import pandas as pd

    from wheelsoil.pipeline import load_inputs

    truth, path = small_wheel
    df, info = load_inputs([path], wheel_radius_m=0.40)
    assert info["wheel_radius_m"] == 0.40
    assert any("WHEEL RADIUS CONFLICT" in n for n in info["notes"])
    m = df["valid"].to_numpy() & (df["phase"] == "accel").to_numpy()
    err = df["slip"].to_numpy()[m] - np.interp(df["t_s"].to_numpy()[m], truth.t_s, truth.slip)
    assert np.sqrt(np.mean(err ** 2)) < 0.01
    # a table that states another radius than the one given: a loud note
    tab = tmp_path / "t.csv"
    pd.DataFrame({"slip": [0.2, 0.3], "load_n": [1e4, 1e4], "drawbar_pull_n": [1e3, 2e3],
                  "wheel_radius_m": [0.47, 0.47]}).to_csv(tab, index=False)
    _, info = load_inputs([tab], wheel_radius_m=0.40)
    assert any("WHEEL RADIUS CONFLICT" in n and "t.csv" in n for n in info["notes"])
    _, info = load_inputs([tab])
    assert info["wheel_radius_m"] == 0.47


def test_fit_refuses_a_radius_in_mm(tmp_path):
    import pandas as pd

    from wheelsoil.pipeline import run_fit

    tab = tmp_path / "t.csv"
    pd.DataFrame({"slip": [0.2, 0.3], "load_n": [1e4, 1e4], "drawbar_pull_n": [1e3, 2e3]}).to_csv(tab, index=False)
    with pytest.raises(ValueError, match=r"--wheel-radius = 470.*did you give mm"):
        run_fit([tab], "clay", tmp_path / "out", wheel_radius=470)


def test_a_table_states_its_wheel_in_columns_or_a_sidecar(tmp_path):
    """A table's wheel comes from its wheel_radius_m/wheel_width_m columns or a sidecar
    <table>.json (the way measured data sets describe their wheel), else the default wheel with a
    loud note; a sidecar that is not JSON is an error naming it."""
    import json

    import pandas as pd

    from wheelsoil.pipeline import _table_wheel, load_inputs

    tab = tmp_path / "rig.csv"
    pd.DataFrame({"slip": [0.2, 0.3], "load_n": [20.0, 20.0], "drawbar_pull_n": [1.0, 2.0]}).to_csv(tab, index=False)
    assert _table_wheel(tab, pd.read_csv(tab)) == ([], [], "")
    (tmp_path / "rig.json").write_text(json.dumps({"wheel": {"radius_m": 0.0575, "width_m": 0.06}}))
    _, info = load_inputs([tab])
    assert (info["wheel_radius_m"], info["wheel_width_m"]) == (0.0575, 0.06)
    assert "rig.json" in info["table_wheel_source"]
    _, info = load_inputs([tab], wheel_radius_m=0.0625)  # the command line against the sidecar: loud
    assert any("WHEEL RADIUS CONFLICT" in n and "rig.json" in n for n in info["notes"])
    df = pd.read_csv(tab).assign(wheel_width_m=0.05)  # columns win over the sidecar
    assert _table_wheel(tab, df) == ([], [0.05], "its wheel_radius_m/wheel_width_m columns")
    (tmp_path / "rig.json").write_text('{"wheel": {"radius_m": "57.5 mm"}}')
    with pytest.raises(ValueError, match=r"rig\.json: wheel radius_m = '57.5 mm'"):
        load_inputs([tab])
    (tmp_path / "rig.json").write_text("{not json")
    with pytest.raises(ValueError, match=r"rig\.json: the table's sidecar is not readable JSON"):
        load_inputs([tab])


def test_a_table_without_its_wheel_gets_a_loud_note(tmp_path):
    import json

    import pandas as pd

    from wheelsoil.model import DEFAULT_WHEEL
    from wheelsoil.pipeline import run_fit

    rng = np.random.default_rng(3)
    s = np.repeat(np.linspace(0.15, 0.8, 8), 3)
    tab = tmp_path / "t.csv"
    pd.DataFrame({"slip": s, "load_n": 1e4, "drawbar_pull_n": 3e3 * s + rng.normal(0, 50, s.size)}).to_csv(
        tab, index=False)
    rep = run_fit([tab], "sand", tmp_path / "out", models=["vasilev"], progress=False)
    assert rep["wheel"] == {"radius_m": DEFAULT_WHEEL.radius, "width_m": DEFAULT_WHEEL.width}
    assert any(n.startswith("WHEEL GEOMETRY ASSUMED: no radius or width") for n in rep["notes"])
    (tmp_path / "t.json").write_text(json.dumps({"wheel_radius_m": 0.5}))  # top-level keys, radius only
    rep = run_fit([tab], "sand", tmp_path / "out2", models=["vasilev"], progress=False)
    assert rep["wheel"]["radius_m"] == 0.5
    assert any(n.startswith("WHEEL GEOMETRY ASSUMED: no width") for n in rep["notes"])
    assert "t.json" in json.loads((tmp_path / "out2" / "report.json").read_text())["provenance"][
        "vehicle_config"]["wheel_source"]


def test_a_table_names_the_columns_it_does_not_read(tmp_path):
    """A channel in other units (sinkage_mm) is not silently dropped: the note names it; a missing
    column's error lists what the table has."""
    import pandas as pd

    from wheelsoil.model.fit import prepare_data
    from wheelsoil.pipeline import load_inputs

    tab = tmp_path / "mm.csv"
    df = pd.DataFrame({"slip": [0.2, 0.4, 0.6], "load_n": 1e4, "drawbar_pull_n": [1e3, 2e3, 2.5e3],
                       "sinkage_mm": [40.0, 50.0, 60.0]})
    df.to_csv(tab, index=False)
    _, info = load_inputs([tab])
    assert any(n.startswith("mm.csv: column(s) not read: sinkage_mm") for n in info["notes"])
    with pytest.raises(ValueError, match=r"missing column\(s\) load_n.*it has slip, load_kn"):
        prepare_data(df.rename(columns={"load_n": "load_kn"}), source="mm.csv")
    # a column named in another case is pointed at; the caller's own "run" column is not listed
    with pytest.raises(ValueError, match=r"missing column\(s\) slip;.*it has Slip, load_n, drawbar_pull_n, "
                                         r"sinkage_mm \(names are case-sensitive: 'Slip' for 'slip'\?\)"):
        prepare_data(df.rename(columns={"slip": "Slip"}).assign(run=0), source="mm.csv")


def test_fit_refuses_inputs_it_cannot_fit_as_given(tmp_path):
    """The same run twice, tables mixed with recordings, implausible wheel sizes from any source
    are refused naming the file; a semicolon table is read; a 'no' in valid is not valid."""
    import json

    import pandas as pd

    from wheelsoil.model.fit import prepare_data
    from wheelsoil.pipeline import load_inputs, run_fit

    s = np.repeat(np.linspace(0.15, 0.8, 8), 3)
    df = pd.DataFrame({"slip": s, "load_n": 1e4, "drawbar_pull_n": 3e3 * s})
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    df.to_csv(a, index=False)
    df.to_csv(b, index=False)
    with pytest.raises(ValueError, match=r"b\.csv: the same data as .*a\.csv"):
        run_fit([a, b], "sand", tmp_path / "o1")
    with pytest.raises(ValueError, match=r"--wheel-width = 0: not a plausible width"):
        run_fit([a], "sand", tmp_path / "o2", wheel_width=0)
    with pytest.raises(ValueError, match=r"--wheel-width = 320: .*did you give mm"):
        run_fit([a], "sand", tmp_path / "o3", wheel_width=320)
    (tmp_path / "a.json").write_text(json.dumps({"wheel": {"radius_m": 470, "width_m": 320}}))
    with pytest.raises(ValueError, match=r"a\.csv: wheel_radius_m \(its sidecar a\.json\) = 470.*did you give mm"):
        load_inputs([a])
    semi = tmp_path / "semi.csv"
    semi.write_text(df.to_csv(index=False, sep=";"))
    got, _ = load_inputs([semi])
    assert list(got.columns[:3]) == ["slip", "load_n", "drawbar_pull_n"] and len(got) == len(df)
    text = df.assign(valid=["no", "yes", "true"] * 8)
    data = prepare_data(text, source="t.csv")
    assert data.n == 16


def test_fit_refuses_a_table_mixed_with_a_recording(small_wheel, tmp_path):
    import pandas as pd

    from wheelsoil.pipeline import load_inputs

    _, path = small_wheel
    tab = tmp_path / "t.csv"
    pd.DataFrame({"slip": [0.2, 0.3], "load_n": [1e4, 1e4], "drawbar_pull_n": [1e3, 2e3]}).to_csv(tab, index=False)
    with pytest.raises(ValueError, match="tables and recordings cannot be fitted jointly"):
        load_inputs([path, tab])


def test_an_unusable_attached_configuration_is_loud_and_the_recorded_wheel_is_kept(tmp_path):
    """One flipped byte in the attached vehicle.toml (its CRC fails): the shipped default configuration
    is used with a loud 'VEHICLE CONFIGURATION ASSUMED', and the wheel stays the one the recording's
    metadata states (0.55 x 0.40 m), not the default's 0.47 x 0.32 m, so slip and the fit are unchanged."""
    from wheelsoil.model import load_terrain
    from wheelsoil.simulate import simulate_run, write_simulation

    run = simulate_run(load_terrain("clay"), wheel=(0.55, 0.40), added_load_n=3000.0, duration_s=30.0, seed=2,
                       front_wheels="reference")
    good = write_simulation(run, tmp_path / "good.mcap")
    raw = bytearray(good.read_bytes())
    k = raw.find(b"[signals.")
    assert k > 0
    raw[k + 3] ^= 0x20
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(raw))
    ref, res = process_recording(good), process_recording(bad)
    loud = [w for w in res.warnings if w.startswith("VEHICLE CONFIGURATION ASSUMED")]
    assert loud and str(bad) in loud[0] and not any("ASSUMED" in w for w in ref.warnings)
    assert (res.wheel_radius_m, res.wheel_width_m) == (0.55, 0.40) == (ref.wheel_radius_m, ref.wheel_width_m)
    np.testing.assert_allclose(res.signals["slip"], ref.signals["slip"], equal_nan=True)
