"""Odd CAN logs given to import / info / process / fit: relative ASC times, frames logged twice,
an input given twice, why a fit has no valid row, the assumed wheel of a log, bus names, format hints."""

import json
import re
import warnings

import can
import numpy as np
import pytest
from daq_helpers import cli, random_messages

from wheelsoil.daq import read_frames, read_recording_info
from wheelsoil.daq.convert import import_log


def _import(src, out, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return import_log(src, out, **kw)


# --------------------------------------------------------------------------- 1. ASC "timestamps relative"
def _asc_absolute(path, msgs):
    with can.ASCWriter(str(path)) as w:
        for m in msgs:
            w.on_message_received(m)


def _asc_to_relative(src, dst, event_after: int = 5):
    """Rewrite an absolute ASC file (python-can's ASCWriter) with each event's time since the previous
    event (Vector's 'timestamps relative'), with a status event line inserted after frame ``event_after``."""
    out, prev, n = [], 0.0, 0
    time_re = re.compile(r"^(\s*)(\d+\.\d+)(\s.*)$", re.S)
    for line in open(src):
        if line.startswith("base hex"):
            out.append("base hex  timestamps relative\n")
            continue
        m = time_re.match(line)
        if m is None:
            out.append(line)
            continue
        t = float(m.group(2))
        if n == event_after:  # an event that is no frame, half-way to the next frame, takes part of the delta
            half = round((t - prev) / 2, 6)
            out.append(f"{m.group(1)}{half:.6f} 1 Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%\n")
            prev += half
        out.append(f"{m.group(1)}{t - prev:.6f}{m.group(3)}")
        prev, n = t, n + 1
    dst.write_text("".join(out))


def test_asc_with_relative_timestamps_imports_the_same_frame_times_as_absolute(tmp_path):
    msgs = random_messages(300, seed=3, channel=0, remote=False) \
        + random_messages(200, seed=4, channel=1, remote=False, t0=1_700_000_000.0004)
    msgs.sort(key=lambda m: m.timestamp)
    a, r = tmp_path / "abs.asc", tmp_path / "rel.asc"
    _asc_absolute(a, msgs)
    _asc_to_relative(a, r)
    assert "timestamps relative" in r.read_text()
    ra, rr = _import(a, tmp_path / "a.mcap"), _import(r, tmp_path / "r.mcap")
    assert ra.frames == rr.frames == {"can0": 300, "can1": 200}
    fa, fr = read_frames(tmp_path / "a.mcap"), read_frames(tmp_path / "r.mcap")
    for bus in ("can0", "can1"):
        np.testing.assert_array_equal(fa[bus].arbitration_id, fr[bus].arbitration_id)
        np.testing.assert_array_equal(fa[bus].data, fr[bus].data)
        # the same times to the microsecond (the run spans ~0.5 s, not the last delta's ~1 ms)
        assert np.abs(fa[bus].timestamp_ns - fr[bus].timestamp_ns).max() <= 1000
    span = (fr["can0"].timestamp_ns[-1] - fr["can0"].timestamp_ns[0]) * 1e-9
    assert span > 0.25
    # said, in the warnings and the import record
    assert any("timestamps relative" in w for w in rr.warnings)
    files = json.loads(read_recording_info(tmp_path / "r.mcap").metadata["wheelsoil.import"]["files"])
    assert any("timestamps relative" in n for n in files[0]["notes"])
    assert not any("timestamps relative" in w for w in ra.warnings)


# --------------------------------------------------------------------------- 2. frames logged twice
@pytest.fixture(scope="module")
def sim_log(tmp_path_factory):
    """A small simulated run (processing_sim) exported as a candump log."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from processing_sim import truth_profile, write_recording

    from wheelsoil.daq.convert import export_recording

    d = tmp_path_factory.mktemp("sim")
    info = write_recording(d / "run.mcap", truth_profile(2))
    export_recording(info["path"], d / "run.log")
    return d / "run.log"


def test_frames_logged_twice_are_dropped_counted_and_named(sim_log, tmp_path):
    from wheelsoil.daq.cli import format_info
    from wheelsoil.processing import process_recording

    lines = sim_log.read_text().splitlines(keepends=True)
    doubled = tmp_path / "doubled.log"
    doubled.write_text("".join(x for line in lines for x in (line, line)))
    rec = tmp_path / "doubled.mcap"
    _import(doubled, rec)
    info = read_recording_info(rec)
    assert sum(info.duplicates.values()) == len(lines)
    assert sum(info.stats.frames.values()) == len(lines)  # counted once
    assert info.stats.total("counter_duplicates") == 0
    assert any(f"frames logged twice: {len(lines)} dropped" in w for w in info.warnings)
    assert f"frames logged twice: {len(lines)} dropped" in format_info(info)
    assert info.to_dict()["duplicate_frames"] == info.duplicates

    once, twice = process_recording(sim_log), process_recording(doubled)
    assert any(f"frames logged twice: {len(lines)} dropped" in w for w in twice.warnings)
    assert not any("logged twice" in w for w in once.warnings)
    assert not any("nominal cycle time is wrong" in w for w in twice.warnings)
    assert once.signals.equals(twice.signals)
    assert once.gnss_latency_s is not None and once.gnss_latency_s == twice.gnss_latency_s


def test_duplicate_filter_keeps_frames_that_differ_and_copies_across_batches():
    from wheelsoil.daq.frames import DuplicateFrames, FrameBatch

    ts = np.array([10, 10, 10, 20, 20], np.int64)
    ids = np.array([0x120, 0x121, 0x120, 0x120, 0x120], np.uint32)
    data = np.zeros((5, 8), np.uint8)
    data[4, 0] = 1  # same id and time, other data: a different frame
    flt = DuplicateFrames()
    out = flt(FrameBatch.from_columns("can0", ts, ids, np.zeros(5), np.full(5, 8), data))
    assert out.timestamp_ns.tolist() == [10, 10, 20, 20] and flt.dropped == {"can0": 1}
    # the copy of the last frame at the start of the next batch; another bus is not compared
    nxt = FrameBatch.from_columns("can0", [20, 30], [0x120, 0x120], [0, 0], [8, 8], data[[4, 0]])
    assert flt(nxt).timestamp_ns.tolist() == [30] and flt.dropped == {"can0": 2}
    other = FrameBatch.from_columns("can1", [20], [0x120], [0], [8], data[[4]])
    assert len(flt(other)) == 1 and flt.total == 2


def test_an_input_given_twice_is_refused_naming_it(tmp_path):
    msgs = random_messages(50, seed=1, channel="can0")
    src = tmp_path / "a.log"
    with can.CanutilsLogWriter(str(src)) as w:
        for m in msgs:
            w.on_message_received(m)
    copy = tmp_path / "copy.log"
    copy.write_bytes(src.read_bytes())
    for second, what in ((tmp_path / "." / "a.log", "the same file"), (copy, "the same bytes")):
        with pytest.raises(ValueError, match=r"given twice \(" + what):
            _import([src, second], tmp_path / "x.mcap")
        assert not (tmp_path / "x.mcap").exists()
    assert cli("import", src, src, "-o", tmp_path / "y.mcap") != 0
    assert not (tmp_path / "y.mcap").exists()


# --------------------------------------------------------------------------- 3. why a fit has no valid row
def test_fit_without_a_valid_row_repeats_what_processing_said(tmp_path):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from processing_sim import truth_profile, write_recording

    from wheelsoil.pipeline import run_fit

    rec = write_recording(tmp_path / "no_gnss.mcap", truth_profile(1), no_gnss=True)["path"]
    with pytest.raises(ValueError) as err:
        run_fit([rec], "clay", tmp_path / "rep", models=["lyasko"])
    text = str(err.value)
    assert "every row is marked invalid" in text
    assert "processing no_gnss.mcap said: no GNSS velocity" in text
    report = (tmp_path / "rep" / "report.html").read_text()
    assert "no GNSS velocity" in report


# --------------------------------------------------------------------------- 4. the wheel of a CAN log
def test_fit_of_a_can_log_says_loudly_that_the_wheel_is_assumed(sim_log, tmp_path, capsys):
    assert cli("fit", sim_log, "--terrain", "clay", "-o", tmp_path / "a", "--models", "lyasko", "-q") == 0
    err = capsys.readouterr().err
    assert "WHEEL GEOMETRY ASSUMED" in err and sim_log.name in err
    notes = json.loads((tmp_path / "a" / "report.json").read_text())["notes"]
    assert any(n.startswith("WHEEL GEOMETRY ASSUMED") for n in notes)
    # the wheel given on the command line: nothing assumed
    assert cli("fit", sim_log, "--terrain", "clay", "-o", tmp_path / "b", "--models", "lyasko", "-q",
               "--wheel-radius", "0.47", "--wheel-width", "0.32") == 0
    assert "WHEEL GEOMETRY ASSUMED" not in capsys.readouterr().err


# --------------------------------------------------------------------------- 5. bus names
def test_messages_on_other_bus_names_are_found_and_the_map_given(sim_log, tmp_path):
    from wheelsoil.processing import process_recording

    text = sim_log.read_text()
    vcan = tmp_path / "vcan.log"
    vcan.write_text(text.replace(") can0 ", ") vcan0 ").replace(") can1 ", ") vcan1 "))
    with pytest.raises(ValueError) as err:
        process_recording(vcan)
    msg = str(err.value)
    assert "not on can0 but on vcan0" in msg and "not on can1 but on vcan1" in msg
    assert f"wheelsoil import {vcan} -o NEW.mcap --map vcan0=can0 --map vcan1=can1" in msg
    # swapped: the imported recording names the log it came from
    swapped = tmp_path / "swapped.log"
    swapped.write_text(text.replace(") can0 ", ") canX ").replace(") can1 ", ") can0 ").replace(") canX ", ") can1 "))
    rec = tmp_path / "swapped.mcap"
    _import(swapped, rec)
    with pytest.raises(ValueError, match=r"--map can1=can0 --map can0=can1"):
        process_recording(rec)
    # the map it gives works
    fixed = tmp_path / "fixed.mcap"
    _import(swapped, fixed, channel_map={"can1": "can0", "can0": "can1"})
    assert process_recording(fixed).signals["valid"].any()


def test_import_map_of_a_channel_the_input_does_not_have_is_a_warning(tmp_path):
    src = tmp_path / "a.log"
    with can.CanutilsLogWriter(str(src)) as w:
        for m in random_messages(20, seed=2, channel="can1"):
            w.on_message_received(m)
    with pytest.warns(RuntimeWarning, match=r"--map X=can0: X is no bus or channel of the input \(it has can1\)"):
        res = import_log(src, tmp_path / "a.mcap", channel_map={"X": "can0", "can1": "can1"})
    assert res.frames == {"can1": 20}
    assert not any("can1=can1" in w for w in res.warnings)


def _trc_v11(path, rows):
    """A PCAN-View TRC 1.1 file (no bus column: every frame reads as channel 1) of candump-log ``rows``."""
    t0 = float(rows[0].split()[0][1:-1])
    out = [";$FILEVERSION=1.1", f";$STARTTIME={t0 / 86400 + 25569:.10f}", ";",
           ";---+--   ----+----  --+--  ----+---  +  -+ -- -- -- -- -- -- --"]
    for n, line in enumerate(rows, 1):
        stamp, _, frame = line.split()[:3]
        cid, data = frame.split("#")
        b = bytes.fromhex(data)
        out.append(f"{n:6d}) {1e3 * (float(stamp[1:-1]) - t0):11.1f}  Rx     {cid.upper():>8}  {len(b)}  "
                   + " ".join(f"{x:02X}" for x in b))
    path.write_text("\r\n".join(out) + "\r\n")


def test_logs_of_one_bus_each_are_mapped_per_file_and_the_map_is_named(sim_log, tmp_path):
    from wheelsoil.processing import process_recording

    rows = sim_log.read_text().splitlines()
    a, b = tmp_path / "wft.trc", tmp_path / "wss_gnss.trc"
    _trc_v11(a, [r for r in rows if " can0 " in r])
    _trc_v11(b, [r for r in rows if " can1 " in r])
    n0, n1 = sum(" can0 " in r for r in rows), sum(" can1 " in r for r in rows)
    res = _import([a, b], tmp_path / "one_bus.mcap")  # both read as channel 1: all on can0
    assert res.frames == {"can0": n0 + n1}
    said = [w for w in res.warnings if w.startswith("BUS NAMES MIXED UP")]
    assert len(said) == 1 and "wss_gnss.trc: its frames on can0 are messages configured on can1" in said[0]
    assert "--map wss_gnss.trc:can0=can1" in said[0] and "wft.trc:" not in said[0]
    # the map it names: one file's channel only
    res = _import([a, b], tmp_path / "mapped.mcap", channel_map={"wss_gnss.trc:can0": "can1"})
    assert res.frames == {"can0": n0, "can1": n1}
    assert not any("MIXED UP" in w or "--map" in w for w in res.warnings)
    assert process_recording(tmp_path / "mapped.mcap").signals["valid"].sum() == \
        process_recording(sim_log).signals["valid"].sum()
    # a file key naming no input is said, and maps nothing (so the mix-up is said again)
    with pytest.warns(RuntimeWarning) as said:
        res = import_log([a, b], tmp_path / "x.mcap", channel_map={"other.trc:can0": "can1"})
    said = [str(w.message) for w in said]
    assert any("no input is named other.trc" in w for w in said)
    assert any(w.startswith("BUS NAMES MIXED UP") for w in said)
    assert res.frames == {"can0": n0 + n1}


# --------------------------------------------------------------------------- 6. what a refused file looks like
LINES = [(1700000000.000100 + i * 1e-3, 0x120 + i % 3, "0102030405060708") for i in range(30)]


@pytest.mark.parametrize("name, text, hint", [
    ("ta.log", "".join(f"({t:.6f})  can0  {i:03X}   [8]  {' '.join(d[k:k + 2] for k in range(0, 16, 2))}\n"
                       for t, i, d in LINES), "looks like candump's -ta output"),
    ("plain.log", "".join(f"  can0  {i:03X}   [8]  01 02 03 04 05 06 07 08\n" for _, i, _ in LINES),
     "has no timestamps"),
    ("ms.log", "".join(f"({t * 1e3:.3f}) can0 {i:03X}#{d}\n" for t, i, d in LINES), "look like milliseconds"),
    ("us.log", "".join(f"({round(t * 1e6)}) can0 {i:03X}#{d}\n" for t, i, d in LINES), "look like microseconds"),
    ("cd.asc", "".join(f"({t:.6f}) can0 {i:03X}#{d}\n" for t, i, d in LINES),
     "looks like a candump log: rename it to cd.log"),
])
def test_a_refused_text_log_says_what_it_looks_like(tmp_path, name, text, hint):
    src = tmp_path / name
    src.write_text(text)
    with pytest.raises(ValueError, match="no valid CAN frame") as err:
        _import(src, tmp_path / "x.mcap")
    assert hint in str(err.value)
    assert not (tmp_path / "x.mcap").exists()


def test_an_asc_file_named_log_is_told_to_be_renamed(tmp_path):
    asc = tmp_path / "a.asc"
    _asc_absolute(asc, random_messages(30, seed=5, channel=0, remote=False))
    wrong = tmp_path / "a.log"
    wrong.write_text(asc.read_text())
    with pytest.raises(ValueError, match=r"looks like an ASC file: rename it to a\.asc"):
        _import(wrong, tmp_path / "x.mcap")
    # a good file gets no hint, and a right suffix imports
    assert _import(asc, tmp_path / "y.mcap").total == 30


def test_a_message_sent_at_another_rate_is_not_counted_as_losing_frames():
    """A GNSS receiver set to 10 Hz where the configuration says 20 Hz was reported as '1199 lost in 0 gaps':
    a message hardly ever at its nominal interval runs at its own rate; one losing frames at random does not."""
    from wheelsoil.processing.pipeline import _time_gaps

    rng = np.random.default_rng(3)
    slow = (np.arange(1200) * 0.1e9 + rng.normal(0, 1e5, 1200)).astype(np.int64)
    rep, period = _time_gaps("RT_SB_GPS_Speed", np.sort(slow), 0.05, "DBC")
    assert rep["lost"] == 0 and "sent every 100.0 ms" in rep["method"] and period == pytest.approx(0.1, rel=0.01)
    full = np.arange(2400) * 0.05e9
    lossy = full[rng.random(2400) >= 0.5].astype(np.int64)  # half of the frames lost at random
    rep, period = _time_gaps("RT_SB_GPS_Speed", lossy, 0.05, "DBC")
    assert rep["lost"] == round((lossy[-1] - lossy[0]) / 0.05e9) + 1 - lossy.size  # over its own span
    assert "nominal cycle time 50 ms" in rep["method"] and period == 0.05


# --------------------------------------------------------------------------- 8. a decimated transducer output
def _keep_wft_samples(log_text: str, keep) -> str:
    """The candump log with only the WFT frames (force 0x120, moment 0x121, angle 0x122) whose
    counter ``keep(counter)`` accepts; other frames unchanged."""
    out = []
    for line in log_text.splitlines(keepends=True):
        cid, data = line.split()[2].split("#")
        if cid in ("120", "121", "122"):
            b = bytes.fromhex(data)
            if not keep(b[2] if cid == "122" else b[6]):
                continue
        out.append(line)
    return "".join(out)


def test_a_wft_sending_every_second_sample_is_processed_and_its_losses_counted_at_its_rate(sim_log, tmp_path):
    from wheelsoil.processing import process_recording

    text = sim_log.read_text()
    half = tmp_path / "half.log"
    dec_text = _keep_wft_samples(text, lambda c: c % 2 == 0)
    half.write_text(dec_text)
    full, dec = process_recording(sim_log), process_recording(half)
    assert dec.quality.get("wft_counter_stride") == 2 and "wft_counter_stride" not in full.quality
    assert any("advances by 2 per frame" in w and "250 Hz" in w for w in dec.warnings)
    assert not any("counters unusable" in w for w in dec.warnings)
    for c in ("drawbar_pull_n", "torque_nm", "load_n"):  # the same filtered forces, to a small part of their spread
        d = np.abs(dec.signals[c] - full.signals[c]).to_numpy()
        assert np.nanpercentile(d, 99) < 0.05 * np.nanstd(full.signals[c]), c
    assert all(dec.quality["lost_frames"][m] == 0 for m in ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle"))
    # ten samples of that output lost (counters 100, 102, .. 118 of the second wrap): ten frames of each
    # message, not twenty
    kept, wrap, last, dropped = [], 0, None, 0
    for line in dec_text.splitlines(keepends=True):
        cid, data = line.split()[2].split("#")
        if cid in ("120", "121", "122"):
            c = bytes.fromhex(data)[2 if cid == "122" else 6]
            if cid == "120":
                wrap, last = wrap + (last is not None and c < last), c
            if wrap == 1 and 100 <= c < 120:
                dropped += 1
                continue
        kept.append(line)
    assert dropped == 30
    lossy = tmp_path / "lossy.log"
    lossy.write_text("".join(kept))
    res = process_recording(lossy)
    assert [res.quality["lost_frames"][m] for m in ("WFT_RL_Force", "WFT_RL_Moment", "WFT_RL_Angle")] == [10, 10, 10]
    rec = tmp_path / "half.mcap"
    _import(half, rec)
    info = read_recording_info(rec)
    assert info.stats.counter_stride == {"WFT_RL_Force": 2, "WFT_RL_Moment": 2, "WFT_RL_Angle": 2}
    assert info.stats.total("lost_frames") == 0


def test_counter_stride_tells_a_decimated_output_from_lost_frames():
    from wheelsoil.daq.stats import counter_stride

    rng = np.random.default_rng(5)
    full = np.arange(3000) % 256
    assert counter_stride(full) == 1
    assert counter_stride(np.arange(0, 6000, 2) % 256) == 2
    assert counter_stride(np.arange(1, 12000, 4) % 256) == 4
    # half the frames lost at random: steps of 2 are common, but the counters keep no one residue
    assert counter_stride(full[np.sort(rng.choice(3000, 1500, replace=False))]) == 1
    # a stride of 3 changes residue at every wrap of 256: refused, saying why
    with pytest.raises(ValueError, match="does not divide its wrap"):
        counter_stride(np.arange(0, 9000, 3) % 256)


# --------------------------------------------------------------------------- 9. buses stamped on two clocks
def _shift_bus(log_text: str, bus: str, shift_s: float) -> str:
    """The candump log with every frame of ``bus`` stamped ``shift_s`` later, in time order."""
    rows = []
    for line in log_text.splitlines(keepends=True):
        stamp, rest = line.split(" ", 1)
        t = float(stamp[1:-1]) + (shift_s if rest.startswith(bus + " ") else 0.0)
        rows.append((t, f"({t:.6f}) {rest}"))
    rows.sort(key=lambda r: r[0])
    return "".join(r[1] for r in rows)


@pytest.mark.parametrize("shift_s", [8.0, 1000.0])
def test_a_bus_stamped_on_another_clock_is_moved_back_and_said(sim_log, tmp_path, shift_s):
    from wheelsoil.processing import process_recording

    shifted = tmp_path / "shifted.log"
    shifted.write_text(_shift_bus(sim_log.read_text(), "can1", shift_s))
    same, moved = process_recording(sim_log), process_recording(shifted)
    assert not any("CLOCK" in w for w in same.warnings) and not same.quality["bus_clocks"]["applied"]
    q = moved.quality["bus_clocks"]
    assert q["applied"] and q["bus"] == "can1" and q["reference_bus"] == "can0"
    assert abs(q["estimate_s"] - shift_s) < 0.01
    said = [w for w in moved.warnings if w.startswith("CLOCK OFFSET BETWEEN BUSES")]
    assert len(said) == 1 and str(shifted) in said[0] and "can1" in said[0]
    # the forces are paired with the slip of their own moment again: as on one clock, to the noise
    n = min(len(same.signals), len(moved.signals))
    for c, tol in (("slip", 0.01), ("drawbar_pull_n", 20.0)):
        d = np.abs(same.signals[c].to_numpy()[:n] - moved.signals[c].to_numpy()[:n])
        assert np.nanpercentile(d, 99) < tol, c
    assert moved.signals["valid"].sum() >= 0.95 * same.signals["valid"].sum()


def test_clock_offset_is_found_at_any_shift_and_not_claimed_for_repeated_alike_manoeuvres():
    from wheelsoil.processing.timesync import estimate_clock_offset

    rng = np.random.default_rng(2)
    t = np.arange(0, 120, 0.01)
    v = np.convolve(rng.normal(size=t.size), np.ones(150) / 150, mode="same")  # a speed history of no period
    tb = np.arange(0, 120, 0.01)[::2]
    for shift in (0.0, 3.7, -42.0, 500.0):
        r = estimate_clock_offset(t, v, tb + shift, np.interp(tb, t, v))
        assert r.clear and abs(r.offset_s - shift) <= 0.03, (shift, r)
    # identical sweeps every 10 s: another sweep matches as well, so no shift is claimed
    sweeps = np.abs(np.sin(np.pi * t / 10.0)) ** 3
    r = estimate_clock_offset(t, sweeps, tb + 25.0, np.interp(tb, t, sweeps))
    assert not r.clear and "not distinct" in r.note


def test_a_gnss_later_than_the_latency_search_range_is_found_around_its_coarse_delay(sim_log, tmp_path):
    from wheelsoil.processing import process_recording
    from wheelsoil.processing.pipeline import LATENCY_MAX_S

    rows = []
    for line in sim_log.read_text().splitlines(keepends=True):  # the GNSS frames (29-bit ids) 0.9 s late
        stamp, rest = line.split(" ", 1)
        late = len(rest.split()[1].split("#")[0]) == 8
        t = float(stamp[1:-1]) + (0.9 if late else 0.0)
        rows.append((t, f"({t:.6f}) {rest}"))
    late_log = tmp_path / "late.log"
    late_log.write_text("".join(r for _, r in sorted(rows, key=lambda r: r[0])))
    base, late = process_recording(sim_log), process_recording(late_log)
    assert not base.quality["latency"]["pre_shift"]["applied"]
    assert base.gnss_latency_s + 0.9 > LATENCY_MAX_S  # beyond what the fine search alone reaches
    assert late.quality["latency"]["pre_shift"]["applied"]
    assert abs(late.gnss_latency_s - (base.gnss_latency_s + 0.9)) < 0.01
    said = [w for w in late.warnings if w.startswith("GNSS BEYOND THE LATENCY SEARCH RANGE")]
    assert len(said) == 1 and str(late_log) in said[0]
    n = min(len(base.signals), len(late.signals))  # the late frames lengthen the run at its end
    d = np.abs(late.signals["slip"].to_numpy()[:n] - base.signals["slip"].to_numpy()[:n])
    assert np.nanpercentile(d, 99) < 0.01


# --------------------------------------------------------------------------- 10. a configuration not the recording's
def _config_copy(tmp_path, name, edits):
    """A copy of the shipped dbc/ directory under ``tmp_path/name`` with ``edits`` {file: [(old, new)]} made
    (each ``old`` must be there); returns the copy's vehicle.toml."""
    import shutil
    from pathlib import Path

    src = Path(__file__).resolve().parents[1] / "dbc"
    dst = tmp_path / name
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("__init__.py", "__pycache__"))
    for f, pairs in edits.items():
        text = (dst / f).read_text()
        for old, new in pairs:
            assert old in text, (f, old)
            text = text.replace(old, new)
        (dst / f).write_text(text)
    return dst / "vehicle.toml"


@pytest.mark.parametrize("case, edits, check", [
    ("rpm_as_rad_s", {"vehicle.toml": [('unit = "rpm"\nscale_to_si = 0.10471975511965977   # 2*pi/60 -> rad/s',
                                        'unit = "rad/s"')],
                      "wheel_speed.dbc": [('[0|655.35] "rpm"', '[0|655.35] "rad/s"')]}, "wheel_speed"),
    ("forces_scaled", {"wft.dbc": [('SG_ Fx_w : 0|16@1- (0.5,0)', 'SG_ Fx_w : 0|16@1- (0.05,0)'),
                                   ('SG_ Fz_w : 32|16@1- (1,0)', 'SG_ Fz_w : 32|16@1- (0.1,0)')]}, "traction"),
    ("fx_fz_swapped", {"vehicle.toml": [('signal = "Fx_w"', 'signal = "FZ_TMP"'), ('signal = "Fz_w"', 'signal = "Fx_w"'),
                                        ('signal = "FZ_TMP"', 'signal = "Fz_w"')]}, "load"),
    ("torque_sign", {"wft.dbc": [('SG_ My : 16|16@1- (0.25,0) [-8192|8191.75]', 'SG_ My : 16|16@1- (-0.25,0) [-8191.75|8192]')]},
     "torque_sign"),
])
def test_a_configuration_that_does_not_match_the_recording_is_refused_by_fit_naming_the_signals(
        sim_log, tmp_path, case, edits, check):
    """A DBC factor, unit, sign or a swapped signal of the user's configuration decoded a run into numbers no
    wheel produces (a load of 1.1 kN carrying a torque of 3 r W, slip from rpm read as rad/s, a torque against
    the slip) and the fit named a verdict: processing now says so loudly, naming the signals, and fit refuses."""
    from wheelsoil.pipeline import run_fit
    from wheelsoil.processing import process_recording

    toml = _config_copy(tmp_path, case, edits)
    res = process_recording(sim_log, config=toml)
    found = [i for i in res.quality["implausible"] if i["check"] == check]
    assert found and found[0]["gross"], res.quality["implausible"]
    assert any(w.startswith("SIGNALS IMPLAUSIBLE: ") for w in res.warnings)
    with pytest.raises(ValueError, match="the decoded signals are not physical") as err:
        run_fit([sim_log], "clay", tmp_path / "rep", vehicle=toml)
    assert str(sim_log) in str(err.value) and "--vehicle" in str(err.value)
    assert not process_recording(sim_log).quality["implausible"]  # the recording's own configuration: nothing


def test_fit_decodes_a_can_log_with_the_vehicle_configuration_given_and_records_it(sim_log, tmp_path):
    """fit had no --vehicle: a CAN log was always decoded with the shipped configuration, silently when the
    wheel was given."""
    import json

    toml = _config_copy(tmp_path, "mine", {})
    assert cli("fit", sim_log, "--terrain", "clay", "-o", tmp_path / "a", "--models", "lyasko", "-q",
               "--vehicle", toml) == 0
    rep = json.loads((tmp_path / "a" / "report.json").read_text())
    assert rep["provenance"]["vehicle_config"]["source"] == f"given: {toml}"
    assert rep["provenance"]["command"][-2:] == ["--vehicle", str(toml)]
    assert not any("WHEEL GEOMETRY ASSUMED" in n or "shipped vehicle configuration" in n for n in rep["notes"])
    assert cli("fit", sim_log, "--terrain", "clay", "-o", tmp_path / "b", "--models", "lyasko", "-q",
               "--wheel-radius", "0.47", "--wheel-width", "0.32") == 0
    notes = json.loads((tmp_path / "b" / "report.json").read_text())["notes"]
    assert any("decoded with the shipped vehicle configuration" in n for n in notes)


def test_a_windows_1252_dbc_is_read_as_such_and_a_message_defined_twice_differently_is_refused(sim_log, tmp_path):
    """A CANdb++ file with "°" in Windows-1252 was read as UTF-8 with replacement characters (its unit "\ufffd"
    then failed the unit check); two DBCs of one bus defining one id differently decoded with whichever came
    first while cantools said the later one overwrote it."""
    from wheelsoil.daq import load_vehicle_config
    from wheelsoil.processing import process_recording

    toml = _config_copy(tmp_path, "cp1252", {"wft.dbc": [('"deg"', '"°"')], "vehicle.toml": [('unit = "deg"', 'unit = "°"')]})
    (toml.parent / "wft.dbc").write_bytes((toml.parent / "wft.dbc").read_text().encode("cp1252"))
    cfg = load_vehicle_config(toml)
    assert any(g.unit == "°" for m in cfg.database("can0").messages for g in m.signals)
    assert process_recording(sim_log, config=toml).signals["valid"].any()
    twice = _config_copy(tmp_path, "twice", {"vehicle.toml": [('dbc = ["wft.dbc"]', 'dbc = ["wft.dbc", "wft_old.dbc"]')]})
    old = (twice.parent / "wft.dbc").read_text().replace("SG_ Fx_w : 0|16@1- (0.5,0)", "SG_ Fx_w : 0|16@1- (0.25,0)")
    (twice.parent / "wft_old.dbc").write_text(old)
    with pytest.raises(ValueError, match=r"wft_old.dbc: message WFT_RL_Force \(id 0x120\) is also defined, differently"):
        load_vehicle_config(twice)
    (twice.parent / "wft_old.dbc").write_text((twice.parent / "wft.dbc").read_text())  # the same: harmless
    db = load_vehicle_config(twice).database("can0")
    assert db.get_message_by_name("WFT_RL_Force")
    assert len(db.messages) == len(cfg.database("can0").messages)  # one copy of each message, not two


def test_info_names_a_bus_without_a_dbc_as_such_not_as_unknown_ids(sim_log, tmp_path):
    """A bus the configuration has no DBC for listed every id as "(unknown id)" above "unknown-id frames: 0"."""
    from wheelsoil.daq.cli import format_info

    rec = tmp_path / "can2.mcap"
    _import(sim_log, rec, channel_map={"can1": "can2"})
    text = format_info(read_recording_info(rec))
    assert "bus can2:" in text and "no DBC configured for it" in text and "(unknown id)" not in text
    assert "(no DBC)" in text and "unknown-id frames: 0" in text


def test_a_counter_of_one_byte_in_either_byte_order_is_read_and_one_in_the_wrong_bits_is_refused(sim_log, tmp_path):
    """A Motorola 8-bit counter in one byte was refused by info (little-endian only) while processing read it;
    a counter configured on the upper nibble of the real one (4 bits) was unwrapped modulo 256 and gave loads of
    -14..+12 kN in valid rows."""
    from wheelsoil.daq import load_vehicle_config
    from wheelsoil.processing import process_recording

    moto = _config_copy(tmp_path, "moto", {"wft.dbc": [("SG_ Counter : 48|8@1+", "SG_ Counter : 55|8@0+")]})
    assert any(spec[3] == 6 and spec[5] == 0 for spec in load_vehicle_config(moto).counter_specs())
    rec = tmp_path / "moto.mcap"
    _import(sim_log, rec, config=load_vehicle_config(moto))
    info = read_recording_info(rec)
    assert info.stats.total("lost_frames") == 0
    assert process_recording(sim_log, config=moto).signals["valid"].sum() == \
        process_recording(sim_log).signals["valid"].sum()
    nibble = _config_copy(tmp_path, "nibble", {"wft.dbc": [("SG_ Counter : 48|8@1+ (1,0) [0|255]",
                                                            "SG_ Counter : 52|4@1+ (1,0) [0|15]")]})
    res = process_recording(sim_log, config=nibble)
    assert any("keeps its value in" in w and "WFT_RL_Force" in w for w in res.warnings)
    assert not res.signals["valid"].any()
