"""Real measured data (CMU grousered wheel, dry sand, measured sinkage, no torque): no wrong cause."""

from pathlib import Path

import pytest

CMU = Path(__file__).resolve().parents[2] / "shared" / "data" / "cmu-grouser-wheel" / "cmu_pavlov2023_grouser_beta0.csv"
if not CMU.exists():
    CMU = Path("/work/shared/data/cmu-grouser-wheel/cmu_pavlov2023_grouser_beta0.csv")


@pytest.mark.skipif(not CMU.exists(), reason=f"shared CMU data not found at {CMU}")
def test_cmu_grouser_wheel_no_wrong_cause(tmp_path):
    from wheelsoil.pipeline import run_fit

    rep = run_fit([CMU], "dry-sand", tmp_path, wheel_radius=0.0625, wheel_width=0.06, fit_terrain=True)
    d = rep["diagnosis"]
    ch = d["channels"]
    # the measured sinkage grows with slip: the sinkage channel finds slip sinkage
    assert d["sinkage_evidence"]["significant"] and d["sinkage_evidence"]["slope"] > 0
    assert ch["sinkage_m"]["measured"] and ch["sinkage_m"]["effect"] == "slip_sinkage"
    assert ch["torque_nm"]["measured"] is False
    # slip sinkage may be the overall cause only if its model lowers the error of every target
    # channel out of sample and leaves the drawbar pull no worse (rule step 3)
    if d["effect"] == "slip_sinkage":
        assert all(ch[c]["improves"] is True for c in d["target_channels"])
        assert ch["drawbar_pull_n"]["worsens"] is not True
    else:
        assert d["effect"] in ("unexplained", "none", "terrain_mismatch")
    for name, m in d["models"].items():
        if m["effect"] == "slip_sinkage" and m["metrics"]["drawbar_pull_n"]["cv_R0"] is not None:
            wong_cv = d["models"]["wong"]["metrics"]["drawbar_pull_n"]["cv_R0"]
            if m["metrics"]["drawbar_pull_n"]["cv_R0"] > wong_cv:
                assert d["effect"] != "slip_sinkage" or d["model"] != name
    assert d["confidence"] in ("low", "medium")  # 12 rows: never 'high'
    assert abs(sum(d["probabilities"].values()) - 1) < 1e-9
    s = d["summary"]
    assert "grows significantly with slip" in s and "sinkage: slip sinkage" in s and "No torque" in s
