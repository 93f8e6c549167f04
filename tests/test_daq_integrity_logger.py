"""Logger loss accounting (issue 12, item 5 logger side, item 7 recorded provenance)."""

import warnings

import can
import numpy as np
from daq_helpers import random_messages

from wheelsoil.daq import FrameBatch, load_vehicle_config, read_recording_info
from wheelsoil.daq.logger import CanLogger, format_status, log_buses
from wheelsoil.daq.stats import StatsAccumulator

T0 = 1_700_000_000 * 10**9


def _wft_force(ts_ns, counters):
    n = len(ts_ns)
    data = np.zeros((n, 8), np.uint8)
    data[:, 6] = np.asarray(counters) % 256
    return FrameBatch("can0", np.asarray(ts_ns, np.int64), np.full(n, 0x120, np.uint32), np.zeros(n, bool),
                      np.zeros(n, np.uint8), np.full(n, 8, np.uint8), data)


def test_counter_wraps_are_resolved_with_the_timestamps():
    cfg = load_vehicle_config()
    idx = np.arange(20000)
    keep = np.ones(idx.size, bool)
    keep[5000:5000 + 2175] = False          # 4.35 s lost: the 8-bit counter wrapped 8 times
    keep[12000:12000 + 100] = False         # a short gap, no wrap
    keep[15000:15000 + 512] = False         # exactly two wraps: the counter alone sees no gap
    rng = np.random.default_rng(0)
    ts = T0 + idx * 2_000_000 + rng.integers(-200_000, 200_000, idx.size)   # 500 Hz, host jitter
    acc = StatsAccumulator(cfg)
    sel = np.flatnonzero(keep)
    for lo in range(0, sel.size, 250):      # half-second batches as the logger hands them over
        s = sel[lo:lo + 250]
        acc.update(_wft_force(ts[s], idx[s]))
    assert acc.stats.lost_frames["WFT_RL_Force"] == 2175 + 100 + 512


def test_messages_without_counter_checked_against_their_cycle_time():
    cfg = load_vehicle_config()
    msg = cfg.database("can1").get_message_by_name("WSS_WheelSpeeds")
    msg.cycle_time = 10                      # what DBC GenMsgCycleTime gives, ms
    try:
        acc = StatsAccumulator(cfg)
        t = T0 + np.arange(1000) * 10_000_000
        keep = np.ones(1000, bool)
        keep[300:330] = False
        keep[700:705] = False
        t = t[keep]
        n = t.size
        b = FrameBatch("can1", t, np.full(n, msg.frame_id, np.uint32), np.zeros(n, bool), np.zeros(n, np.uint8),
                       np.full(n, msg.length, np.uint8), np.zeros((n, 8), np.uint8))
        acc.update(b.select(slice(0, 400)))
        acc.update(b.select(slice(400, n)))
        assert acc.stats.lost_frames_estimated["WSS_WheelSpeeds"] == 35
    finally:
        msg.cycle_time = None


def _virtual_pair(name):
    return can.Bus(interface="virtual", channel=name), can.Bus(interface="virtual", channel=name)


def test_virtual_bus_drops_are_unknown_not_zero_and_status_shows_them(tmp_path):
    tx, rx = _virtual_pair("integrity-l1")
    statuses = []
    try:
        lg = CanLogger({"can0": rx}, tmp_path / "v.mcap", config=load_vehicle_config(), batch_interval_s=0.05,
                       status_interval_s=0.1)
        for m in random_messages(30, seed=1, remote=False):
            tx.send(m)
        res = lg.run(duration_s=0.5, on_status=statuses.append)
    finally:
        tx.shutdown()
        rx.shutdown()
    st = res.status["buses"]["can0"]
    assert st["rx_dropped"] is None
    assert st["unknown_id_frames"] > 0 and "lost_frames_estimated" in st
    line = format_status(res.status)
    assert "drop ?" in line and f"unk {st['unknown_id_frames']}" in line
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        info = read_recording_info(res.files[0])
    assert info.to_dict()["buses"]["can0"]["rx_dropped"] is None
    assert info.rx_dropped() == {}


def test_log_buses_writes_recorded_provenance(tmp_path):
    tx = can.Bus(interface="virtual", channel="integrity-l2")
    try:
        res = log_buses(["can0=virtual:integrity-l2"], tmp_path / "p.mcap", duration_s=0.3,
                        command=["wheelsoil", "log", "--bus", "can0=virtual:integrity-l2"])
    finally:
        tx.shutdown()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        info = read_recording_info(res.files[0])
    prov = info.provenance
    assert prov["kind"] == "recorded" and prov["adapters"] == ["can0=virtual:integrity-l2"]
    assert prov["command"][:2] == ["wheelsoil", "log"]


def test_cli_log_warning_says_unknown_for_drops(tmp_path, capsys):
    from daq_helpers import cli

    out = tmp_path / "c.mcap"
    assert cli("log", "--bus", "can0=virtual:integrity-l3", "-o", out, "--duration", "0.3", "-q") == 0
    err = capsys.readouterr().err
    assert "kernel rx drops 0" not in err and "unknown on can0" in err
