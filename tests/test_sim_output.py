"""The simulator's outputs: MCAP as the logger writes it, python-can logs, the CLI, no leaked truth."""

from __future__ import annotations

import json
import subprocess
import sys

import can
import numpy as np
import pytest

from wheelsoil.model import load_terrain
from wheelsoil.simulate import EFFECTS, simulate_run, write_simulation

#: Words that would give a hidden effect (or the fact of a simulation) away.
LEAKS = ("vasilev", "lyasko", "ding", "terrain_mismatch", "terrain mismatch", "effect", "truth", "simulat", "seed",
         "m1", "m2", "n1")


@pytest.fixture(scope="module")
def run():
    return simulate_run(load_terrain("sand"), effect="lyasko", params={"m1": 0.5, "m2": 0.04},
                        added_load_n=5000, seed=3, duration_s=40.0, drop_rate=0.01)


def _mcap_texts(path):
    """Every metadata value, channel/schema text and JSON message of an MCAP file,
    and its attachments (name -> bytes)."""
    from mcap.reader import make_reader

    texts = []
    attachments = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for rec in reader.iter_metadata():
            texts += [rec.name, *rec.metadata.keys(), *rec.metadata.values()]
        for att in reader.iter_attachments():
            attachments[att.name] = att.data
        summary = reader.get_summary()
        for ch in summary.channels.values():
            texts += [ch.topic, json.dumps(ch.metadata)]
        for sc in summary.schemas.values():
            texts += [sc.name, sc.data.decode("utf-8", "replace")]
        for schema, channel, message in reader.iter_messages():
            if channel.message_encoding == "json":
                texts.append(message.data.decode())
    return texts, attachments


def test_mcap_has_frames_of_the_run_and_logger_facts_only(run, tmp_path):
    from wheelsoil.daq import read_frames, read_recording_info

    path = write_simulation(run, tmp_path / "run.mcap")
    frames = read_frames(path)
    for bus, f in run.frames.items():
        b = frames[bus]
        assert np.array_equal(b.timestamp_ns, f["timestamp_ns"])
        assert np.array_equal(b.arbitration_id, f["arbitration_id"])
        assert np.array_equal(b.data[:, :8], f["data"])
    info = read_recording_info(path)
    assert info.complete and not info.warnings
    assert info.stats.lost_frames["WFT_RL_Force"] == run.info["lost_wft_samples"]
    facts = info.metadata["wheelsoil.recording"]
    assert int(facts["start_time_ns"]) <= run.start_ns
    texts, attachments = _mcap_texts(path)
    # attachments: exactly the shipped vehicle configuration and its DBC files
    from wheelsoil.daq import load_vehicle_config

    cfg = load_vehicle_config()
    assert attachments.pop("vehicle.toml").decode() == cfg.text
    assert {k.removeprefix("dbc/"): v.decode() for k, v in attachments.items()} == cfg.dbc_texts()
    for text in texts:
        low = text.lower()
        for word in LEAKS:
            if word in ("m1", "m2", "n1", "ding"):  # short tokens: only as separate words
                assert not any(tok == word for tok in low.replace('"', " ").replace(",", " ").split()), (word, text[:200])
            else:
                assert word not in low, (word, text[:200])


@pytest.mark.parametrize("suffix", [".log", ".blf", ".asc"])
def test_python_can_formats_round_trip(run, tmp_path, suffix):
    path = write_simulation(run, tmp_path / f"run{suffix}")
    msgs = list(can.LogReader(str(path)))
    assert len(msgs) == run.n_frames
    by_ch: dict = {}
    for m in msgs:
        by_ch.setdefault(str(m.channel), []).append(m)
    assert len(by_ch) == 2
    chans = sorted(by_ch)
    wft = by_ch[chans[0]]
    f = run.frames["can0"]
    assert len(wft) == len(f["timestamp_ns"])
    k = len(wft) // 2
    assert wft[k].arbitration_id == f["arbitration_id"][k]
    assert bytes(wft[k].data) == bytes(f["data"][k, : f["dlc"][k]])
    # relative times (ASC stores them relative to its header's start)
    assert abs((wft[k].timestamp - msgs[0].timestamp) - (f["timestamp_ns"][k] - run.start_ns) * 1e-9) < 2e-5
    if suffix == ".log":
        assert chans == ["can0", "can1"]
    text = path.read_bytes()
    for word in LEAKS[:8]:
        assert word.encode() not in text.lower()


def test_cli_simulate_writes_recording_and_truth_only_when_asked(tmp_path):
    out = tmp_path / "run.log"
    cmd = [sys.executable, "-m", "wheelsoil", "simulate", "--terrain", "clay", "--effect", "vasilev",
           "--param", "H=0.05", "--duration", "30", "--seed", "2", "-o", str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert out.exists() and not list(tmp_path.glob("*.json"))
    truth = tmp_path / "truth.json"
    res = subprocess.run(cmd + ["--truth", str(truth)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    doc = json.loads(truth.read_text())
    assert doc["effect"] == "vasilev" and doc["params"] == {"H": 0.05}
    assert doc["gnss_latency_s"] == 0.1 and doc["seed"] == 2
    assert doc["terrain_true"]["phi_deg"] == pytest.approx(14.0)
    bad = subprocess.run(cmd[:-2] + ["--param", "m1=2", "-o", str(tmp_path / "x.log")], capture_output=True, text=True)
    assert bad.returncode == 2 and "m1" in bad.stderr
    bad = subprocess.run(cmd[:-2] + ["-o", str(tmp_path / "x.txt")], capture_output=True, text=True)
    assert bad.returncode == 2 and "format" in bad.stderr


def test_terrain_mismatch_changes_the_true_soil_only():
    lab = load_terrain("clay")
    r = simulate_run(lab, effect="terrain_mismatch", seed=4, duration_s=30.0)
    p = r.info["params"]
    assert set(p) == {"K", "phi_deg"}
    f = p["K"] / lab.K
    assert 0.4 <= f <= 0.7 or 1.5 <= f <= 2.5
    assert 3.0 <= abs(p["phi_deg"] - 14.0) <= 6.0
    assert r.info["terrain_true"]["n"] == r.info["terrain_named"]["n"]
    assert set(EFFECTS) == {"none", "vasilev", "lyasko", "ding", "terrain_mismatch"}
