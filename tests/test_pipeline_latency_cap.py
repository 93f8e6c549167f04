"""An unreliable GNSS latency (slip in doubt) caps the verdict's confidence at "low"."""

from types import SimpleNamespace

import pytest

from wheelsoil.model.diagnosis import diagnose
from wheelsoil.model.fit import prepare_data, synthetic_data
from wheelsoil.model import DEFAULT_WHEEL, load_terrain
from wheelsoil.pipeline import _cap_for_time_base


@pytest.fixture(scope="module")
def diag():
    ter = load_terrain("clay")
    df = synthetic_data(ter, DEFAULT_WHEEL, model="ding", params={"n1": 0.3}, seed=3)
    return lambda: diagnose(prepare_data(df, slip_min=0.1), ter, DEFAULT_WHEEL)


def _info(reliable):
    res = SimpleNamespace(quality={"latency": {"reliable": reliable, "reasons": ["estimators disagree"]}})
    return {"time_sync": [{"input": "/x/run.mcap"}], "results": [res]}


def test_unreliable_latency_caps_confidence_and_says_why(diag):
    d = diag()
    _cap_for_time_base(d, _info(False))
    assert d.confidence == "low"
    assert any("GNSS latency of run.mcap is unreliable" in r for r in d.confidence_reasons)
    assert "unreliable" in d.summary
    assert d.to_dict()["confidence"] == "low"


def test_reliable_latency_leaves_the_verdict_alone(diag):
    d0, d = diag(), diag()
    _cap_for_time_base(d, _info(True))
    assert (d.effect, d.confidence, d.summary) == (d0.effect, d0.confidence, d0.summary)
