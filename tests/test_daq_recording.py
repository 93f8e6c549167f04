"""MCAP recordings: lossless round trip, standard tools read them, truncation and recovery."""

import warnings

import numpy as np
import pytest
from daq_helpers import cli, random_messages

from wheelsoil.daq import (FrameBatch, RecordingError, RecordingWriter, iter_frame_batches, load_vehicle_config,
                           read_frames, read_recording_info)
from wheelsoil.daq.compare import frame_differences


def _write(path, per_bus, *, flush_every=None, config=None):
    with RecordingWriter(path, config=config, metadata={"test": "yes"}) as w:
        for bus, msgs in per_bus.items():
            step = flush_every or len(msgs)
            for lo in range(0, len(msgs), step):
                w.write_frames(bus, msgs[lo:lo + step])
                if flush_every:
                    w.flush()


def test_round_trip_is_lossless(tmp_path):
    msgs = {"can0": random_messages(3000, seed=1), "can1": random_messages(500, seed=2, fd=True)}
    path = tmp_path / "r.mcap"
    _write(path, msgs)
    got = read_frames(path)
    assert set(got) == {"can0", "can1"}
    for bus, ms in msgs.items():
        back = list(got[bus].to_messages())
        assert len(back) == len(ms)
        for a, b in zip(ms, back):
            assert a.equals(b, timestamp_delta=1e-7, check_channel=False), (a, b)
    assert got["can1"].data_width == 64 and got["can0"].data_width == 8
    want = {bus: FrameBatch.from_messages(bus, ms) for bus, ms in msgs.items()}
    assert frame_differences(want, got, flag_mask=0xFF) == []
    np.testing.assert_array_equal(got["can0"].timestamp_ns, want["can0"].timestamp_ns)


def test_timestamps_keep_microseconds_exactly():
    t = np.array([1_700_000_000.000001, 1_700_000_000.999999, 1_712_345_678.123456, 0.5])
    from wheelsoil.daq.frames import ns_to_seconds, seconds_to_ns

    got = seconds_to_ns(t)
    np.testing.assert_array_equal(np.round(got / 1000).astype(np.int64),
                                  [1_700_000_000_000_001, 1_700_000_000_999_999, 1_712_345_678_123_456, 500_000])
    assert all(f"{a:.6f}" == f"{b:.6f}" for a, b in zip(ns_to_seconds(got), t))


def test_standard_ros2_reader_decodes_frames(tmp_path):
    from mcap_ros2.reader import read_ros2_messages

    msgs = random_messages(300, seed=3)
    path = tmp_path / "r.mcap"
    _write(path, {"can0": msgs})
    decoded = list(read_ros2_messages(str(path), topics=["/can/can0/frames"]))
    assert decoded, "no frame channel found by mcap-ros2"
    ids = np.concatenate([np.asarray(m.ros_msg.arbitration_id, np.uint32) for m in decoded])
    ts = np.concatenate([np.asarray(m.ros_msg.timestamp_ns, np.uint64) for m in decoded])
    np.testing.assert_array_equal(ids, [m.arbitration_id for m in msgs])
    np.testing.assert_array_equal(np.round(ts / 1000), np.round(np.array([m.timestamp for m in msgs]) * 1e6))
    assert decoded[0].log_time_ns == int(ts[0])


def test_metadata_and_attachments(tmp_path):
    cfg = load_vehicle_config()
    path = tmp_path / "r.mcap"
    _write(path, {"can0": random_messages(10)}, config=cfg)
    info = read_recording_info(path)
    assert info.complete and not info.warnings
    rec = info.metadata["wheelsoil.recording"]
    assert rec["test"] == "yes" and rec["host"] and rec["version.wheelsoil"]
    assert "wheelsoil.summary" in info.metadata
    assert {"vehicle.toml", "dbc/wft.dbc", "dbc/wheel_speed.dbc", "dbc/gps_rt_speedbox.dbc"} <= set(info.attachments)
    assert info.config_source == "recording attachments"


@pytest.mark.parametrize("cut", [0.35, 0.6, 0.85, 0.999])
def test_truncated_file_keeps_complete_chunks_and_names_offset(tmp_path, cut):
    msgs = random_messages(4000, seed=4, remote=False)
    full = tmp_path / "full.mcap"
    _write(full, {"can0": msgs}, flush_every=400)  # 10 chunks
    data = full.read_bytes()
    bad = tmp_path / "cut.mcap"
    bad.write_bytes(data[: int(len(data) * cut)])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = read_frames(bad)
    msgs_w = [str(w.message) for w in caught]
    assert any(str(bad) in m and "byte" in m for m in msgs_w), msgs_w
    n = len(got.get("can0", []))
    # every chunk that lies fully before the cut is kept (10 chunks of 400 frames)
    assert n % 400 == 0 and n >= 400 * int(cut * 10 - 2), n
    if n:
        ref = FrameBatch.from_messages("can0", msgs[:n])
        assert frame_differences({"can0": ref}, got, flag_mask=0xFF) == []
    with pytest.raises(RecordingError, match="cut.mcap"):
        read_frames(bad, recover=False)
    # recover rewrites a complete, indexed file holding the same frames
    fixed = tmp_path / "fixed.mcap"
    assert cli("recover", bad, "-o", fixed) == 0
    from mcap.reader import make_reader

    with open(fixed, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics.message_count >= n // 2000
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = read_frames(fixed)
    assert len(again.get("can0", [])) == n
    info = read_recording_info(fixed)
    assert info.complete and "wheelsoil.recovered" in info.metadata


def test_not_an_mcap_file_is_a_clear_error(tmp_path, capsys):
    p = tmp_path / "x.mcap"
    p.write_text("hello, not mcap\n")
    with pytest.raises(RecordingError, match="not an MCAP file"):
        read_frames(p)
    assert cli("info", p) == 2
    assert "x.mcap: not an MCAP file" in capsys.readouterr().err
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    with pytest.raises(RecordingError):
        read_frames(empty)


def test_iter_frame_batches_filters_buses(tmp_path):
    path = tmp_path / "r.mcap"
    _write(path, {"can0": random_messages(100, seed=5), "can1": random_messages(50, seed=6)})
    buses = {b.bus for b in iter_frame_batches(path, buses=["can1"])}
    assert buses == {"can1"}
    assert sum(len(b) for b in iter_frame_batches(path, buses="can1")) == 50


def test_damaged_chunk_in_the_middle_is_skipped_and_reading_goes_on(tmp_path):
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader

    msgs = random_messages(2000, seed=9, remote=False)
    path = tmp_path / "r.mcap"
    _write(path, {"can0": msgs}, flush_every=500)  # 4 chunks
    data = bytearray(path.read_bytes())
    # find the second chunk and scramble its compressed payload
    offsets = []

    class Pos:
        def __init__(self, f):
            self.f, self.pos = f, 0

        def read(self, n=-1):
            b = self.f.read(n)
            self.pos += len(b)
            return b

    with open(path, "rb") as fh:
        pos = Pos(fh)
        for rec in StreamReader(pos, emit_chunks=True).records:
            if isinstance(rec, Chunk):
                offsets.append(pos.pos)
    end2 = offsets[1]
    data[end2 - 200:end2 - 100] = bytes(100)
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = read_frames(bad)
    assert any("bad.mcap: chunk at byte" in str(w.message) for w in caught)
    assert len(got["can0"]) == 1500  # chunks 1, 3, 4
    ref = FrameBatch.from_messages("can0", msgs[:500] + msgs[1000:])
    assert frame_differences({"can0": ref}, got, flag_mask=0xFF) == []
