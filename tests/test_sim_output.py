"""The simulator's outputs: MCAP in the logger's layout with the simulated wheel's configuration and an
honest provenance, python-can logs, the CLI, no leaked truth."""

from __future__ import annotations

import json
import subprocess
import sys

import can
import numpy as np
import pytest

from wheelsoil.model import load_terrain
from wheelsoil.simulate import ACCEPTABLE, EFFECTS, IN_FAMILY, OUT_OF_FAMILY, simulate_run, write_simulation

#: Words that would give the hidden effect away (the fact of a simulation and its seed are stated).
LEAKS = ("vasilev", "lyasko", "ding", "terrain_mismatch", "terrain mismatch", "effect", "truth",
         "m1", "m2", "n1")


@pytest.fixture(scope="module")
def run():
    return simulate_run(load_terrain("clay"), effect="lyasko", params={"m1": 0.5, "m2": 0.04}, wheel=(0.55, 0.40),
                        added_load_n=3000, seed=3, duration_s=40.0, drop_rate=0.01)


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
    # honest facts: this machine wrote the file; no logger status, no logger command or host
    import socket

    assert facts["host"] == socket.gethostname() != "wft-logger"
    assert "command" not in facts and "bus_specs" not in facts
    prov = info.provenance
    assert prov["kind"] == "simulated" and prov["seed"] == 3 and "wheelsoil.sim" in prov["simulator"]
    texts, attachments = _mcap_texts(path)
    assert not any("wheelsoil log" in t for t in texts)
    assert "/wheelsoil/logger_status" not in texts
    # attachments: the vehicle configuration of the simulated wheel and the shipped DBC files
    from wheelsoil.daq import load_vehicle_config
    from wheelsoil.daq.info import load_recording_config

    cfg = load_vehicle_config()
    rec_cfg = load_recording_config(path)
    assert (rec_cfg.wheel_radius_m, rec_cfg.wheel_width_m) == (0.55, 0.40)
    toml = attachments.pop("vehicle.toml").decode()
    assert "wheel_mass_kg = 80.0" in toml and "wheel_inertia_kgm2 = 11.5" in toml
    assert toml.count("wheel_radius_m =") == 1
    assert rec_cfg.signals == cfg.signals and list(rec_cfg.buses) == list(cfg.buses)
    assert {k.removeprefix("dbc/"): v.decode() for k, v in attachments.items()} == cfg.dbc_texts()
    # processing computes slip with the simulated wheel's radius
    from wheelsoil.processing import process_recording

    assert process_recording(path).wheel_radius_m == 0.55
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
    for word in LEAKS[:7]:  # the long words (2-letter tokens occur in compressed bytes by chance)
        assert word.encode() not in text.lower()


def test_cli_simulate_writes_recording_and_truth_only_when_asked(tmp_path):
    out = tmp_path / "run.log"
    cmd = [sys.executable, "-m", "wheelsoil", "simulate", "--terrain", "clay", "--effect", "vasilev",
           "--wheel-radius", "0.55", "--wheel-width", "0.4",
           "--param", "H=0.05", "--duration", "30", "--seed", "2", "-o", str(out)]
    res = subprocess.run(cmd, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert out.exists() and not list(tmp_path.glob("*.json"))
    # an .mcap from the CLI: the truth only in --truth; the recorded command has the effect's options redacted
    from wheelsoil.daq import read_recording_info

    truth = tmp_path / "t2.json"
    mc = tmp_path / "run.mcap"
    res = subprocess.run(cmd[:-1] + [str(mc), "--truth", str(truth)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    doc = json.loads(truth.read_text())
    assert doc["effect"] == "vasilev" and doc["params"]["H"] == 0.05
    assert doc["family"] == "in" and doc["acceptable"] == ["slip_sinkage"]
    assert doc["gnss_latency_s"] == 0.1 and doc["seed"] == 2
    assert doc["wheel"]["radius_m"] == 0.55 and doc["wheel"]["width_m"] == 0.4
    assert doc["terrain_named"]["phi_deg"] == pytest.approx(14.0)
    prov = read_recording_info(mc).provenance
    assert prov["command"][:2] == ["wheelsoil", "simulate"] and "--wheel-radius" in prov["command"]
    flat = json.dumps(prov)
    for word in ("vasilev", "H=0.05", "t2.json"):
        assert word not in flat, word
    assert prov["command"].count("<hidden>") == 3
    # an existing output is kept unless --overwrite (checked before simulating)
    before = mc.read_bytes()
    again = subprocess.run(cmd[:-1] + [str(mc)], capture_output=True, text=True)
    assert again.returncode == 2 and "exists" in again.stderr and str(mc) in again.stderr
    assert mc.read_bytes() == before
    again = subprocess.run(cmd[:-2] + ["--seed", "3", "-o", str(mc), "--overwrite"], capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert mc.read_bytes() != before
    bad = subprocess.run(cmd[:-2] + ["--param", "m1=2", "-o", str(tmp_path / "x.log")], capture_output=True, text=True)
    assert bad.returncode == 2 and "m1" in bad.stderr
    bad = subprocess.run(cmd[:-2] + ["-o", str(tmp_path / "x.txt")], capture_output=True, text=True)
    assert bad.returncode == 2 and "format" in bad.stderr
    # the paper's clay on the default wheel at 8 + 3 kN cannot be driven: refused, saying why
    bad = subprocess.run(cmd[:6] + ["--duration", "30", "-o", str(tmp_path / "y.mcap")], capture_output=True, text=True)
    assert bad.returncode == 2 and "cannot move" in bad.stderr
    helptext = subprocess.run([sys.executable, "-m", "wheelsoil", "simulate", "--help"], capture_output=True,
                              text=True).stdout
    for eff in EFFECTS:
        assert eff in helptext
    assert "--truth" in helptext and "unexplained" in helptext


def test_truth_lists_acceptable_verdicts_for_every_effect():
    assert set(EFFECTS) == set(IN_FAMILY) | set(OUT_OF_FAMILY) and len(OUT_OF_FAMILY) >= 6
    for eff in OUT_OF_FAMILY:
        assert "unexplained" in ACCEPTABLE[eff]
    for eff in IN_FAMILY:
        assert "unexplained" not in ACCEPTABLE[eff]
    r = simulate_run(load_terrain("sand"), effect="terrain_mismatch", seed=4, duration_s=30.0, added_load_n=5000,
                     params={"changes": {"phi": {"kind": "delta_deg", "value": 3.0}}})
    assert r.info["family"] == "in" and r.info["acceptable"] == ["terrain_mismatch"]
    assert r.info["terrain_true_mid_run"]["phi_deg"] == pytest.approx(r.info["terrain_named"]["phi_deg"] + 3.0)
    assert r.info["terrain_true_mid_run"]["n"] == r.info["terrain_named"]["n"]


def test_vehicle_keys_replaced_or_added_and_loaded_by_the_daq_loader():
    from wheelsoil.daq.config import tomllib
    from wheelsoil.simulate import set_vehicle_keys, vehicle_config_for

    base = '[vehicle]\nname = "x"\nwheel_radius_m = 0.47   # tyre\nwheel_width_m = 0.32\nwheel_mass_kg = 80.0\n\n[buses.can0]\ndbc = []\n'
    out = set_vehicle_keys(base, {"wheel_radius_m": 0.6, "wheel_mass_kg": 95.0, "wheel_inertia_kgm2": 14.0})
    doc = tomllib.loads(out)
    assert doc["vehicle"] == {"name": "x", "wheel_radius_m": 0.6, "wheel_width_m": 0.32, "wheel_mass_kg": 95.0,
                              "wheel_inertia_kgm2": 14.0}
    assert out.count("wheel_mass_kg") == 1 and doc["buses"]["can0"]["dbc"] == []
    with pytest.raises(ValueError, match=r"\[vehicle\]"):
        set_vehicle_keys("[buses.can0]\n", {"wheel_radius_m": 1.0})
    cfg = vehicle_config_for(0.61, 0.43)
    assert (cfg.wheel_radius_m, cfg.wheel_width_m) == (0.61, 0.43)
    vt = tomllib.loads(cfg.text)["vehicle"]
    assert vt["wheel_mass_kg"] == 80.0 and vt["wheel_inertia_kgm2"] == 11.5
    if hasattr(cfg, "wheel_mass_kg"):  # contract B (processing's VehicleConfig fields)
        assert (cfg.wheel_mass_kg, cfg.wheel_inertia_kgm2) == (80.0, 11.5)


def test_simulate_refuses_a_run_length_or_wheel_it_cannot_make():
    """An infinite or NaN duration and a zero wheel are refused naming the option, not run or defaulted."""
    from wheelsoil.model import load_terrain
    from wheelsoil.simulate import simulate_run

    for bad in (float("inf"), float("nan"), 10.0):
        with pytest.raises(ValueError, match="a run is 30 s"):
            simulate_run(load_terrain("sand"), duration_s=bad)
    proc = subprocess.run([sys.executable, "-m", "wheelsoil", "simulate", "--terrain", "sand", "--wheel-width", "0",
                           "-o", "x.mcap"], capture_output=True, text=True)
    assert proc.returncode != 0 and "--wheel-width = 0.0: not a plausible width" in proc.stderr
