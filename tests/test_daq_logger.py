"""The field logger: replay -> log keeps frames (virtual, udp_multicast), SIGKILL, SIGTERM, rotation."""

import signal
import threading
import time
import warnings

import can
import numpy as np
import pytest
from daq_helpers import cli, random_messages, run_wheelsoil, start_logger, stop_logger

from wheelsoil.daq import FrameBatch, RecordingWriter, load_vehicle_config, read_frames, read_recording_info
from wheelsoil.daq.buses import BusSpec, parse_bus_spec
from wheelsoil.daq.compare import compare_recordings, frame_differences
from wheelsoil.daq.convert import recover_recording
from wheelsoil.daq.logger import CanLogger, format_status
from wheelsoil.daq.replay import map_replay_buses, replay_recording


def _need_udp():
    pytest.importorskip("msgpack", reason="python-can's udp_multicast interface needs msgpack")


def _recording(path, n0=600, n1=300):
    with RecordingWriter(path, config=load_vehicle_config()) as w:
        # ~1500 frames/s together: UDP on a loaded CI machine keeps up with that
        w.write_frames("can0", random_messages(n0, seed=11, spacing_s=1e-3))
        w.write_frames("can1", random_messages(n1, seed=12, spacing_s=2e-3, t0=1_700_000_000.0001))
    return path


def test_bus_specs():
    s = parse_bus_spec("socketcan:can0")
    assert (s.name, s.interface, s.channel, s.named) == ("can0", "socketcan", "can0", False)
    s = parse_bus_spec("can1=udp_multicast:239.0.0.1", 0)
    assert (s.name, s.channel, s.named) == ("can1", "239.0.0.1", True)
    assert parse_bus_spec("udp_multicast:239.0.0.1", 3).name == "can3"
    assert parse_bus_spec("pcan:PCAN_USBBUS1,bitrate=500000").kwargs == {"bitrate": 500000}
    with pytest.raises(ValueError, match="INTERFACE:CHANNEL"):
        parse_bus_spec("can0")
    specs = [BusSpec("x", "virtual", "a"), BusSpec("can1", "virtual", "b", named=True)]
    assert map_replay_buses(["can0", "can1"], specs) == {"can1": specs[1], "can0": specs[0]}
    assert map_replay_buses(["can0", "can1"], specs[:1]) == {"can0": specs[0], "can1": specs[0]}


def test_virtual_replay_into_logger_gives_same_frames(tmp_path):
    rec = _recording(tmp_path / "rec.mcap")
    out = tmp_path / "out.mcap"
    rx = {b: can.Bus(interface="virtual", channel=f"wsv-{b}") for b in ("can0", "can1")}
    logger = CanLogger(rx, out, config=load_vehicle_config())
    statuses = []
    th = threading.Thread(target=lambda: statuses.append(logger.run(on_status=statuses.append)))
    th.start()
    try:
        time.sleep(0.2)
        res = replay_recording(rec, ["can0=virtual:wsv-can0", "can1=virtual:wsv-can1"], speed=0)
        assert res.sent == {"can0": 600, "can1": 300}
        time.sleep(0.4)
    finally:
        logger.stop()
        th.join(10)
        for b in rx.values():
            b.shutdown()
    result = statuses[-1]
    assert result.frames == {"can0": 600, "can1": 300} and result.stop_reason == "stopped"
    assert compare_recordings(rec, out) == []
    info = read_recording_info(out)
    assert info.complete and info.metadata["wheelsoil.summary"]


def test_udp_multicast_replay_and_log_in_other_processes(tmp_path):
    """The acceptance path: `wheelsoil replay` in one process, `wheelsoil log` in another."""
    _need_udp()
    rec = _recording(tmp_path / "rec.mcap")
    out = tmp_path / "out.mcap"
    # one UDP port per bus: Linux delivers every group joined on a port to all its sockets
    buses = ["can0=udp_multicast:239.74.163.11,port=43211", "can1=udp_multicast:239.74.163.12,port=43212"]
    p = start_logger(out, buses)
    try:
        r = run_wheelsoil("replay", rec, *[a for b in buses for a in ("--bus", b)], "--speed", "1")
        assert r.returncode == 0, r.stderr + r.stdout
        assert "sent 900 frames" in r.stdout
        time.sleep(0.5)
    finally:
        rc, log_out = stop_logger(p, signal.SIGINT)
    assert rc == 0, log_out
    assert "recorded 900 frames" in log_out
    assert compare_recordings(rec, out) == []
    got, want = read_frames(out), read_frames(rec)
    # recorded timing kept: the replay is not faster than the recording
    for bus in ("can0", "can1"):
        span_rec = np.ptp(want[bus].timestamp_ns) / 1e9
        span_got = np.ptp(got[bus].timestamp_ns) / 1e9
        assert span_got >= 0.9 * span_rec, (bus, span_got, span_rec)
    assert read_recording_info(out).complete


def _udp_sender(channel, port, stop, sent, rate_hz=1000):
    """Send frames whose data is a running uint32 sequence number; remember send times."""
    bus = can.Bus(interface="udp_multicast", channel=channel, port=port)
    i = 0
    t0 = time.monotonic()
    try:
        while not stop.is_set():
            due = t0 + i / rate_hz
            now = time.monotonic()
            if due > now:
                time.sleep(due - now)
            sent.append((time.time(), i))
            bus.send(can.Message(arbitration_id=0x120, is_extended_id=False,
                                 data=int(i).to_bytes(4, "little") + bytes([0, 0, i % 256, 0])))
            i += 1
    finally:
        bus.shutdown()


def test_sigkill_keeps_everything_older_than_one_second(tmp_path):
    _need_udp()
    out = tmp_path / "killed.mcap"
    ch = "239.74.163.21"
    p = start_logger(out, [f"can0=udp_multicast:{ch},port=43221"])
    stop, sent = threading.Event(), []
    th = threading.Thread(target=_udp_sender, args=(ch, 43221, stop, sent))
    th.start()
    try:
        time.sleep(3.0)
        t_kill = time.time()
        p.send_signal(signal.SIGKILL)
        p.wait(10)
    finally:
        stop.set()
        th.join(5)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = read_frames(out)
    assert any("killed.mcap" in str(w.message) for w in caught), "a killed file should be reported as truncated"
    seq = np.frombuffer(got["can0"].data[:, :4].tobytes(), "<u4")
    old = [i for t, i in sent if t < t_kill - 1.0]
    assert len(old) > 1000
    missing = sorted(set(old) - set(seq.tolist()))
    assert not missing, f"{len(missing)} frames older than 1 s lost, first {missing[:5]}"
    # and `wheelsoil recover` makes it a complete file with the same frames
    fixed = tmp_path / "fixed.mcap"
    assert recover_recording(out, fixed).total == len(seq)
    assert compare_recordings(out, fixed) == []


def test_sigterm_closes_cleanly_and_rotation_splits_files(tmp_path):
    _need_udp()
    out = tmp_path / "rot.mcap"
    ch = "239.74.163.31"
    p = start_logger(out, [f"can0=udp_multicast:{ch},port=43231"], "--split-minutes", "0.02",
                     wait_for=tmp_path / "rot_0001.mcap")
    stop, sent = threading.Event(), []
    th = threading.Thread(target=_udp_sender, args=(ch, 43231, stop, sent, 1000))
    th.start()
    time.sleep(3.0)
    stop.set()
    th.join(5)
    time.sleep(0.4)
    rc, log_out = stop_logger(p, signal.SIGTERM)
    assert rc == 0, log_out
    files = sorted(tmp_path.glob("rot_*.mcap"))
    assert len(files) >= 2, files
    seqs = []
    for f in files:
        info = read_recording_info(f)
        assert info.complete, f
        fr = read_frames(f)
        if "can0" in fr:  # a file opened after the sender stopped has no frames
            seqs.append(np.frombuffer(fr["can0"].data[:, :4].tobytes(), "<u4"))
    assert len(seqs) >= 2
    allseq = np.concatenate(seqs)
    assert allseq.tolist() == [i for _, i in sent]  # nothing lost or doubled across files


def test_logger_never_dies_on_odd_frames(tmp_path):
    """Error frames, remote frames, unknown ids, wrong DLC, FD: recorded and counted."""
    rx = can.Bus(interface="virtual", channel="wsv-odd")
    tx = can.Bus(interface="virtual", channel="wsv-odd")
    msgs = [
        can.Message(arbitration_id=0x120, is_extended_id=False, data=b"\x01\x02"),        # DLC mismatch
        can.Message(arbitration_id=0x7FF, is_extended_id=False, data=b""),                # unknown id
        can.Message(is_error_frame=True, arbitration_id=0x20000080 & 0x1FFFFFFF, data=bytes(8)),
        can.Message(arbitration_id=0x121, is_extended_id=False, is_remote_frame=True, dlc=8),
        can.Message(arbitration_id=0x1ABCDEF, is_fd=True, data=bytes(range(64))),
    ]
    for m in msgs:
        tx.send(m)
    lg = CanLogger({"can0": rx}, tmp_path / "odd.mcap", config=load_vehicle_config())
    res = lg.run(max_frames=len(msgs))
    rx.shutdown()
    tx.shutdown()
    b = res.status["buses"]["can0"]
    assert b["frames"] == 5 and b["error_frames"] == 1 and b["dlc_mismatch_frames"] == 1
    assert b["unknown_id_frames"] == 2
    want = FrameBatch.from_messages("can0", msgs)
    assert frame_differences({"can0": want}, read_frames(tmp_path / "odd.mcap")) == []
    assert "fr/s" in format_status(res.status)


def test_cli_log_errors_are_clear(tmp_path, capsys):
    assert cli("log", "--bus", "nonsense", "-o", tmp_path / "x.mcap", "--duration", "1") == 2
    err = capsys.readouterr().err
    assert "INTERFACE:CHANNEL" in err and "Traceback" not in err
    assert cli("log", "--bus", "nosuchinterface:x", "-o", tmp_path / "x.mcap", "--duration", "1") == 2
    err = capsys.readouterr().err
    assert "cannot open" in err and "nosuchinterface" in err


def test_replay_skips_a_recorded_clock_step_and_stops_within_a_slice():
    """A 1 h gap between two frames (a host clock that stepped) is not slept through: it is counted and
    the replay goes on; a stop request during a wait ends the replay within a sleep slice."""
    import threading
    import time

    import can

    from wheelsoil.daq.replay import MAX_REPLAY_GAP_S, replay_messages

    class Sink:
        def __init__(self):
            self.got = []

        def send(self, msg):
            self.got.append(msg.arbitration_id)

    def msgs(times):
        return [can.Message(timestamp=t, arbitration_id=i, data=b"\x00", channel="can0") for i, t in enumerate(times)]

    sink = Sink()
    t0 = time.monotonic()
    res = replay_messages(msgs([0.0, 0.01, 3600.0, 3600.01]), {"can0": sink})
    assert time.monotonic() - t0 < 2.0 and sink.got == [0, 1, 2, 3]
    assert res.gaps_skipped == 1 and res.gap_skipped_s > 3000 and MAX_REPLAY_GAP_S < 3599
    stop, sink = threading.Event(), Sink()
    threading.Timer(0.3, stop.set).start()
    t0 = time.monotonic()
    replay_messages(msgs([0.0, 5.0]), {"can0": sink}, stop_event=stop)  # a 5 s wait, stopped after 0.3 s
    assert time.monotonic() - t0 < 1.5 and sink.got == [0]
