"""import / export / info: bit-exact candump round trip, other formats, bad input."""

import json
import warnings

import can
import numpy as np
import pytest
from daq_helpers import cli, random_messages

from wheelsoil.daq import read_frames, read_recording_info
from wheelsoil.daq.compare import frame_differences
from wheelsoil.daq.convert import export_recording, import_log


def _write_candump(path, msgs):
    with can.CanutilsLogWriter(str(path)) as w:
        for m in msgs:
            w.on_message_received(m)


def _candump_lines(path):
    """Frames of a candump -L file as (timestamp string, channel, frame) per line."""
    out = []
    for line in open(path):
        parts = line.split()
        if parts:
            out.append(tuple(parts[:3]))
    return out


def test_candump_import_export_round_trip_is_bit_exact(tmp_path):
    msgs = []
    for bus, seed in (("can0", 1), ("can1", 2), ("vcan3", 3)):
        msgs += random_messages(700, seed=seed, fd=True, channel=bus)
    msgs.sort(key=lambda m: m.timestamp)  # candump files are in time order
    src = tmp_path / "in.log"
    _write_candump(src, msgs)
    rec = tmp_path / "run.mcap"
    assert cli("import", src, "-o", rec) == 0
    frames = read_frames(rec)
    assert {b: len(f) for b, f in frames.items()} == {"can0": 700, "can1": 700, "vcan3": 700}
    out = tmp_path / "out.log"
    assert cli("export", rec, "-o", out) == 0
    a, b = _candump_lines(src), _candump_lines(out)
    assert len(a) == len(b) == 2100
    # same timestamp text (µs), channel, id, flags, data; per-bus order kept
    per_bus = lambda lines, bus: [x for x in lines if x[1] == bus]  # noqa: E731
    for bus in ("can0", "can1", "vcan3"):
        assert per_bus(a, bus) == per_bus(b, bus), bus
    assert sorted(a) == sorted(b)


@pytest.mark.parametrize("suffix", [".asc", ".blf"])
def test_vector_formats_round_trip_frames(tmp_path, suffix):
    msgs = random_messages(400, seed=7, channel=0) + random_messages(300, seed=8, channel=1, t0=1_700_000_000.0002)
    msgs.sort(key=lambda m: m.timestamp)
    rec = tmp_path / "a.mcap"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        src = tmp_path / "in.log"
        _write_candump(src, msgs)
        import_log(src, rec)
        out = tmp_path / f"out{suffix}"
        res = export_recording(rec, out)
        assert res.total == 700
        back = tmp_path / "b.mcap"
        res2 = import_log(out, back)
    assert res2.frames == {"can0": 400, "can1": 300}  # channel numbering survives (file channel 1 = can0)
    a, b = read_frames(rec), read_frames(back)
    for bus in ("can0", "can1"):
        np.testing.assert_array_equal(a[bus].arbitration_id, b[bus].arbitration_id)
        np.testing.assert_array_equal(a[bus].flags & 0x0F, b[bus].flags & 0x0F)
        np.testing.assert_array_equal(a[bus].dlc, b[bus].dlc)
        np.testing.assert_array_equal(a[bus].data, b[bus].data)
        # relative timing to the microsecond
        da = a[bus].timestamp_ns - a["can0"].timestamp_ns[0]
        db = b[bus].timestamp_ns - b["can0"].timestamp_ns[0]
        assert np.abs(da - db).max() <= 1000


def test_channel_map_option(tmp_path):
    src = tmp_path / "in.log"
    _write_candump(src, random_messages(20, seed=9, channel="vcan0") + random_messages(10, seed=9, channel="vcan1"))
    rec = tmp_path / "a.mcap"
    assert cli("import", src, "-o", rec, "--map", "vcan0=can0", "--map", "vcan1=can1") == 0
    assert {b: len(f) for b, f in read_frames(rec).items()} == {"can0": 20, "can1": 10}
    out = tmp_path / "o.log"
    assert cli("export", rec, "-o", out, "--map", "can1=vcan7", "--bus", "can1") == 0
    assert {x[1] for x in _candump_lines(out)} == {"vcan7"}


GOOD = """\
(1700000000.000100) can0 120#0100020003000000
(1700000000.000200) can0 122#10000000
(1700000000.000300) can1 09567C22#0000000000000000
"""


def test_garbage_lines_are_counted_with_file_and_line_and_no_frame_is_lost(tmp_path, capsys):
    lines = GOOD.splitlines()
    text = "\n".join(["this is not candump", lines[0], "(abc) can0 123#11", lines[1],
                      "(1700000000.0004) can0 12G#00", lines[2], "((((", ""])
    src = tmp_path / "bad.log"
    src.write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = import_log(src, tmp_path / "a.mcap")
    assert res.total == 3 and res.skipped == 4
    for lineno in (1, 3, 5, 7):
        assert any(f"bad.log:{lineno}:" in w for w in res.warnings), res.warnings
    assert len([w for w in caught if "bad.log" in str(w.message)]) == 4
    frames = read_frames(tmp_path / "a.mcap")
    assert frames["can0"].arbitration_id.tolist() == [0x120, 0x122]
    assert frames["can1"].arbitration_id.tolist() == [0x9567C22]
    # CLI: a warning line per problem, exit 0, no traceback
    assert cli("import", src, "-o", tmp_path / "b.mcap") == 0
    err = capsys.readouterr().err
    assert "bad.log:3" in err and "Traceback" not in err


def test_info_counts_unknown_ids_dlc_mismatch_and_lost_counters(tmp_path, capsys):
    lines = []
    t = 1_700_000_000.0
    for i in range(300):
        if i in (100, 101, 102):  # three WFT samples lost on the bus
            continue
        c = i % 256
        lines.append(f"({t + i * 0.002:.6f}) can0 120#000000000000{c:02X}00")
        lines.append(f"({t + i * 0.002 + 0.0001:.6f}) can0 122#0000{c:02X}00")
    lines.append(f"({t + 1:.6f}) can0 555#01")           # unknown id
    lines.append(f"({t + 1:.6f}) can0 121#0102")         # DLC 2, DBC says 8
    lines.append(f"({t + 1:.6f}) can1 300#0102030405060708")
    src = tmp_path / "w.log"
    src.write_text("\n".join(lines) + "\n")
    rec = tmp_path / "w.mcap"
    import_log(src, rec)
    info = read_recording_info(rec)
    s = info.stats
    assert s.lost_frames["WFT_RL_Force"] == 3 and s.lost_frames["WFT_RL_Angle"] == 3
    assert s.unknown_ids["can0"] == {(0x555, False): 1}
    assert s.dlc_mismatch["can0"] == {(0x121, False): 1}
    assert s.id_counts["can0"][(0x120, False)] == 297
    assert info.duration_s == pytest.approx(1.0, abs=1e-6)
    assert cli("info", rec, "--json") == 0
    d = json.loads(capsys.readouterr().out)
    assert d["buses"]["can0"]["ids"]["0x120"] == {"frames": 297, "message": "WFT_RL_Force"}
    assert d["lost_frames"]["WFT_RL_Force"] == 3
    assert cli("info", rec) == 0
    text = capsys.readouterr().out
    assert "WFT_RL_Force" in text and "unknown-id frames: 1" in text and "DLC mismatches: 1" in text


def test_bad_inputs_give_clear_errors(tmp_path, capsys):
    assert cli("import", tmp_path / "missing.log", "-o", tmp_path / "x.mcap") == 2
    assert "missing.log" in capsys.readouterr().err
    (tmp_path / "a.xyz").write_text("x")
    assert cli("import", tmp_path / "a.xyz", "-o", tmp_path / "x.mcap") == 2
    assert "unknown log format" in capsys.readouterr().err
    blf = tmp_path / "bad.blf"
    blf.write_bytes(b"LOGG" + b"\x00" * 200)
    rc = cli("import", blf, "-o", tmp_path / "y.mcap")
    err = capsys.readouterr().err
    assert "bad.blf" in err and "Traceback" not in err
    assert rc == 2  # no frame in it: an error, not "imported 0 frames"
    assert not (tmp_path / "y.mcap").exists()


def test_decode_adds_json_channels_with_physical_values(tmp_path, capsys):
    from mcap.reader import make_reader

    src = tmp_path / "w.log"
    # Fx_w = 0x0190 * 0.5 N = 200 N; Fz_w = 0x2328 = 9000 N; counter 7; one short frame (DLC 2)
    src.write_text("(1700000000.000100) can0 120#9001000028230700\n"
                   "(1700000000.000200) can0 120#0102\n"
                   "(1700000000.000300) can1 300#0000000017700000\n")
    rec, dec = tmp_path / "w.mcap", tmp_path / "d.mcap"
    import_log(src, rec)
    assert cli("decode", rec, "-o", dec) == 0
    err = capsys.readouterr().err
    assert "1 WFT_RL_Force frame(s) did not decode" in err
    got = {}
    with open(dec, "rb") as f:
        for _, ch, msg in make_reader(f).iter_messages():
            if ch.topic.startswith("/decoded/"):
                got[ch.topic] = (msg.log_time, json.loads(msg.data))
    t, v = got["/decoded/can0/WFT_RL_Force"]
    assert t == 1_700_000_000_000_100_000
    assert (v["Fx_w"], v["Fz_w"], v["Counter"]) == (200.0, 9000.0, 7.0)
    assert got["/decoded/can1/WSS_WheelSpeeds"][1]["WheelSpeed_RL"] == pytest.approx(0x1770 * 0.01)
    # raw frames are copied unchanged
    assert frame_differences(read_frames(rec), read_frames(dec), flag_mask=0xFF) == []
