"""Every imported line/frame is validated; invalid ones rejected with their line (BLF: object)
numbers, good ones all kept; truncated .log/.asc/.blf/.trc reported (issue 12 item 3)."""

import json
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


def _rejected_lines(res, name):
    """Line (or object) numbers named in the warnings as rejected."""
    out = set()
    for w in res.warnings:
        if w.startswith(name) and ": rejected:" in w:
            head = w.split(": rejected:")[0]
            out.add(int(head.rsplit(":", 1)[1].replace("object", "").strip()))
    return out


def _metadata_lines(rec, key="line"):
    files = json.loads(read_recording_info(rec).metadata["wheelsoil.import"]["files"])
    return {r[key] for f in files for r in f["first_rejected"]}, files


CANDUMP = """\
(1700000000.000100) can0 120#0100020003000000
(1700000000.000200) can0 123#0011223
(1700000000.000300) can0 124#00112233445566778899
(1700000000.000400) can0 125##1{fd33}
(1700000000.000500) can0 FFF#00
(1700000000.000550) can0 1FFFFFFFF#0011
(nan) can0 126#00
(inf) can0 127#00
(1e20) can0 128#00
(100000000000000000000.000000) can0 129#00
(1700000000.000600) can0 12A#+1-1
(1700000000.000700) can1 09567C22#0000000000000000
(1700000000.000800) can0 122##1{fd32}
(1700000000.000900) can0 121#R
(1700000000.001000) can0 E0000123#00
(1700000000.001100) can0 130#01
"""
FD33 = "AB" * 33
FD32 = "CD" * 32


def test_candump_invalid_lines_are_rejected_with_line_numbers_and_good_frames_kept(tmp_path, capsys):
    src = tmp_path / "bad.log"
    src.write_text(CANDUMP.format(fd33=FD33, fd32=FD32))
    rec = tmp_path / "a.mcap"
    res = _import(src, rec)
    bad = {2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 15}
    assert _rejected_lines(res, str(src)) == set(sorted(bad)[:10])  # the first ten are named
    assert res.skipped == len(bad)
    assert any("11 invalid lines rejected" in w for w in res.warnings)
    frames = read_frames(rec)
    assert frames["can0"].arbitration_id.tolist() == [0x120, 0x122, 0x121, 0x130]
    assert frames["can1"].arbitration_id.tolist() == [0x9567C22]
    # the kept frames are intact: 8 bytes, 32-byte FD, remote, 1 byte
    assert frames["can0"].dlc.tolist() == [8, 32, 0, 1]
    assert bytes(frames["can0"].data[1, :32]) == bytes.fromhex(FD32)
    assert not (frames["can0"].flags & 0x04).any()  # nothing became an error frame
    # reasons name the problem
    text = "\n".join(res.warnings)
    for phrase in ("odd number of hex digits", "10 data bytes", "33 data bytes", "0xFFF", "9 hex digits",
                   "'(nan)'", "'(inf)'", "'(1e20)'", "1e+20"):
        assert phrase in text, phrase
    # the same first lines are in the recording's metadata
    lines, files = _metadata_lines(rec)
    assert lines == set(sorted(bad)[:10])
    assert files[0]["rejected"] == len(bad) and files[0]["frames"] == 5
    # CLI: exit 0 (good frames imported), the line numbers on stderr
    assert cli("import", src, "-o", tmp_path / "b.mcap") == 0
    err = capsys.readouterr().err
    assert f"{src}:2:" in err and f"{src}:5:" in err and "Traceback" not in err


def test_more_than_ten_bad_lines_are_counted_and_the_first_ten_named(tmp_path):
    # 1 or 3 hex digits of data: all invalid
    lines = [f"(1700000000.{i:06d}) can0 {0x100 + i:03X}#{'0' * (1 + 2 * (i % 2))}" for i in range(40)]
    src = tmp_path / "many.log"
    src.write_text("\n".join(lines[:30]) + "\n(1700000001.000000) can0 200#00\n")
    res = _import(src, tmp_path / "m.mcap")
    assert res.total == 1 and res.skipped == 30
    named = _rejected_lines(res, str(src))
    assert named == set(range(1, 11))
    assert any("30 invalid lines rejected" in w for w in res.warnings)
    md = json.loads(read_recording_info(tmp_path / "m.mcap").metadata["wheelsoil.import"]["rejected"])
    assert md == 30


def test_candump_error_frames_keep_bus_class_and_data(tmp_path):
    """python-can's candump reader drops an error frame's channel, class and data (and reads a
    class without the bus-error bit as a data frame); the import keeps them."""
    src = tmp_path / "err.log"
    src.write_text("(1700000000.000100) can1 20000004#0004000000000000\n"
                   "(1700000000.000200) can1 20000080#0000000000000000\n"
                   "(1700000000.000300) can1 300#01\n")
    frames = read_frames(_import(src, tmp_path / "e.mcap").output)
    assert set(frames) == {"can1"}
    f = frames["can1"]
    assert (f.flags & 0x04).tolist() == [4, 4, 0]
    assert f.arbitration_id.tolist() == [0x4, 0x80, 0x300]
    assert bytes(f.data[0, :8]) == bytes.fromhex("0004000000000000")


ASC = """\
date Tue Nov 14 22:13:20.000 2023
base hex  timestamps absolute
internal events logged
Begin Triggerblock Tue Nov 14 22:13:20.000 2023
 0.000000 Start of measurement
 0.001000 1  120             Rx   d 2 01 02
 0.002000 1  121             Rx   d 8 01 02 03 04 05 06 07 08 09 0A
 0.003000 1  FFF             Rx   d 1 00
 0.004000 CANFD   1 Rx   1234567x                                   1 0 d 33 {fd33}
 0.005000 1  122             Rx   d 4 01 02
 0.006000 2  09567C22x       Rx   d 8 00 00 00 00 00 00 00 00  Length = 228000 BitCount = 117 ID = 156662818x
 0.007000 1  123             Rx   d 1 0G
 0.008000 1  124             Rx   d 1 05
 0.009000 CANFD   1 Rx   1234568x                                   1 0 d 32 {fd32}   0    0     1000        0
 0.010000 1  125             Rx   d 9 01 02 03 04 05 06 07 08
End TriggerBlock
"""


def test_asc_invalid_frames_rejected_with_line_numbers(tmp_path):
    src = tmp_path / "bad.asc"
    src.write_text(ASC.format(fd33=" ".join(["AB"] * 33), fd32=" ".join(["CD"] * 32)))
    rec = tmp_path / "a.mcap"
    res = _import(src, rec)
    assert _rejected_lines(res, str(src)) == {7, 8, 9, 10, 12, 15}
    assert not res.truncated
    frames = read_frames(rec)
    assert frames["can0"].arbitration_id.tolist() == [0x120, 0x124, 0x1234568]
    assert frames["can0"].dlc.tolist() == [2, 1, 32]
    assert frames["can1"].arbitration_id.tolist() == [0x9567C22]
    assert _metadata_lines(rec)[0] == {7, 8, 9, 10, 12, 15}


def test_asc_frame_lines_with_a_garbled_time_are_rejected_not_passed_over(tmp_path):
    """python-can's ASC reader skips a frame line whose time does not parse without a word; such a line
    is a rejected frame with its number (a comment that mentions Rx is not)."""
    head = ASC.split(" 0.001000")[0]
    body = ("// a comment about Rx frames\n"
            " 0.001000 1  120             Rx   d 2 01 02\n"
            " 0.0x2000 1  121             Rx   d 2 01 02\n"
            " O.003000 1  122             Rx   d 2 01 02\n"
            " 0.004000 1  123             Rx   d 2 01 02\n"
            " .005 1  124             Rx   d 2 01 02\n"
            "End TriggerBlock\n")
    src = tmp_path / "garbled.asc"
    src.write_text(head + body)
    first = head.count("\n") + 1
    res = _import(src, tmp_path / "g.mcap")
    assert _rejected_lines(res, str(src)) == {first + 2, first + 3, first + 5}
    assert read_frames(tmp_path / "g.mcap")["can0"].arbitration_id.tolist() == [0x120, 0x123]


TRC = """\
;$FILEVERSION=2.1
;$STARTTIME=45244.92592593
;$COLUMNS=N,O,T,B,I,d,R,L,D
;
      1         1.000 DT  1     0120 Rx -  2    01 02
      2         2.000 DT  1     0121 Rx -  8    01 02
      3         3.000 DT  1     0FFF Rx -  1    00
      4         4.000 DT  1     0122 Rx -  2    0+ 02
      5           nan DT  1     0123 Rx -  1    00
      6         6.000 DT  2 09567C22 Rx -  8    00 00 00 00 00 00 00 00
      7         7.000 DT  1     0124 Rx -  1    05
      8         8.000 DT  1     0125 Rx
"""


def test_trc_invalid_frames_rejected_with_line_numbers(tmp_path):
    src = tmp_path / "bad.trc"
    src.write_text(TRC)
    rec = tmp_path / "a.mcap"
    res = _import(src, rec)
    assert _rejected_lines(res, str(src)) == {6, 7, 8, 9, 12}
    frames = read_frames(rec)
    assert frames["can0"].arbitration_id.tolist() == [0x120, 0x124]
    assert frames["can1"].arbitration_id.tolist() == [0x9567C22]


def test_blf_invalid_frames_rejected_with_object_index(tmp_path):
    msgs = [can.Message(timestamp=1_700_000_000.0 + i * 1e-3, arbitration_id=0x100 + i, is_extended_id=False,
                        data=bytes([i]), channel=0) for i in range(7)]
    msgs[2] = can.Message(timestamp=1_700_000_000.002, arbitration_id=0x800, is_extended_id=False,
                          data=b"\x01", channel=0, check=False)                          # 11-bit id > 0x7FF
    msgs[3] = can.Message(timestamp=1_700_000_000.003, arbitration_id=0x103, is_extended_id=False,
                          dlc=12, data=bytes(8), channel=0, check=False)                  # classic DLC 12
    msgs[5] = can.Message(timestamp=1_700_000_000.005, arbitration_id=0x105, is_extended_id=False,
                          is_fd=True, data=bytes(33), channel=0, check=False)             # FD, 33 bytes
    src = tmp_path / "bad.blf"
    with can.Logger(str(src)) as w:
        for m in msgs:
            w.on_message_received(m)
    rec = tmp_path / "a.mcap"
    res = _import(src, rec)
    assert _rejected_lines(res, str(src)) == {3, 4, 6}
    assert any(f"{src}: object 3: rejected:" in w for w in res.warnings)
    assert read_frames(rec)["can0"].arbitration_id.tolist() == [0x100, 0x101, 0x104, 0x106]
    assert _metadata_lines(rec, "object")[0] == {3, 4, 6}


# ------------------------------------------------------------------ truncated files
def test_truncated_candump_last_line_is_reported_not_stored(tmp_path):
    src = tmp_path / "cut.log"
    src.write_text("(1700000000.000100) can0 120#0100020003000000\n"
                   "(1700000000.000200) can1 09567C22#0000000000000000\n"
                   "(1700000000.000300) can1 09567C22#0000")           # cut: no line end
    rec = tmp_path / "c.mcap"
    res = _import(src, rec)
    assert res.truncated == [str(src)]
    assert any("truncated" in w and "cut.log" in w for w in res.warnings)
    assert _rejected_lines(res, str(src)) == {3}
    frames = read_frames(rec)
    assert len(frames["can1"]) == 1 and frames["can1"].dlc.tolist() == [8]  # no 2-byte frame
    assert json.loads(read_recording_info(rec).metadata["wheelsoil.import"]["truncated"]) is True


@pytest.mark.parametrize("suffix,frac", [(".log", 0.5), (".asc", 0.5), (".asc", 0.731), (".blf", 0.5),
                                         (".blf", 0.9), (".trc", 0.5), (".trc", 0.613)])
def test_truncated_files_are_reported_and_keep_the_complete_frames(tmp_path, suffix, frac):
    msgs = random_messages(3000, seed=11, channel=0, fd=suffix != ".trc", remote=suffix != ".trc")
    full = tmp_path / f"full{suffix}"
    with can.Logger(str(full)) as w:
        for m in msgs:
            w.on_message_received(m)
    data = full.read_bytes()
    cut = tmp_path / f"cut{suffix}"
    cut.write_bytes(data[:int(len(data) * frac)])
    res = _import(full, tmp_path / "full.mcap")
    assert res.total == 3000 and not res.truncated and res.skipped == 0
    res = _import(cut, tmp_path / "cut.mcap")
    assert res.truncated == [str(cut)]
    assert any("truncated" in w for w in res.warnings)
    a, b = read_frames(tmp_path / "full.mcap")["can0"], read_frames(tmp_path / "cut.mcap")["can0"]
    n = len(b)
    assert 0.8 * frac * 3000 < n < 3000
    # what was kept is exactly the beginning of the file: no altered or partial frame
    np.testing.assert_array_equal(a.arbitration_id[:n], b.arbitration_id)
    np.testing.assert_array_equal(a.dlc[:n], b.dlc)
    np.testing.assert_array_equal(a.flags[:n], b.flags)
    np.testing.assert_array_equal(a.data[:n, :b.data_width], b.data[:, :a.data_width])
    np.testing.assert_array_equal(a.timestamp_ns[:n], b.timestamp_ns)


def test_a_damaged_blf_container_loses_its_frames_only(tmp_path):
    """16 zeroed bytes inside one compressed container of a BLF file: that container's frames are lost
    (and said), every later container is read (before: nothing after the damage was kept)."""
    import re

    msgs = random_messages(40000, seed=12, channel=0, fd=False, remote=False)
    full = tmp_path / "full.blf"
    with can.Logger(str(full)) as w:
        for m in msgs:
            w.on_message_received(m)
    data = bytearray(full.read_bytes())
    starts = [m.start() for m in re.finditer(b"LOBJ", bytes(data))]
    assert len(starts) >= 5  # python-can writes several compressed containers
    k = len(starts) // 3
    at = (starts[k] + starts[k + 1]) // 2
    data[at:at + 16] = bytes(16)
    bad = tmp_path / "bad.blf"
    bad.write_bytes(bytes(data))
    res = _import(bad, tmp_path / "bad.mcap")
    assert any("damaged object container" in w and "reading goes on" in w for w in res.warnings)
    a, b = read_frames(_import(full, tmp_path / "full.mcap").output)["can0"], read_frames(tmp_path / "bad.mcap")["can0"]
    lost = len(a) - len(b)
    assert 0 < lost < len(a) / len(starts) * 1.5  # about one container
    np.testing.assert_array_equal(a.timestamp_ns[-1000:], b.timestamp_ns[-1000:])  # the end is kept


def test_non_finite_timestamps_from_a_reader_are_rejected(tmp_path):
    """The frame rules also hold for what a reader hands over (BLF: a huge time offset)."""
    from wheelsoil.daq.frames import checked_batch_from_messages

    msgs = [can.Message(timestamp=t, arbitration_id=0x10, is_extended_id=False, data=b"\x01")
            for t in (1.7e9, float("nan"), float("inf"), 1e20, -1.0, 1.7e9 + 1)]
    batch, bad, reasons = checked_batch_from_messages("can0", msgs)
    assert bad.tolist() == [1, 2, 3, 4] and len(batch) == 2
    assert all("timestamp" in r for r in reasons)
    np.testing.assert_array_equal(batch.timestamp_ns, [1_700_000_000_000_000_000, 1_700_000_001_000_000_000])


@pytest.mark.parametrize("suffix", [".log", ".asc", ".blf", ".trc"])
def test_mutated_files_never_traceback_nor_store_an_invalid_frame(tmp_path, suffix):
    """Seeded byte flips, truncations and junk lines: the import either keeps only valid frames
    or refuses the file with a ValueError naming it; an existing output is never damaged."""
    import random

    from wheelsoil.daq.frames import FD_LENGTHS

    msgs = random_messages(300, seed=5, channel=0, fd=suffix != ".trc", remote=suffix != ".trc")
    full = tmp_path / f"full{suffix}"
    with can.Logger(str(full)) as w:
        for m in msgs:
            w.on_message_received(m)
    base = full.read_bytes()
    keep = tmp_path / "keep.mcap"
    _import(full, keep)
    before = keep.read_bytes()
    rng = random.Random(suffix)
    for k in range(12):
        d = bytearray(base)
        kind = k % 3
        if kind == 0:
            d = d[:rng.randrange(len(d))]
        elif kind == 1:
            for _ in range(rng.randint(1, 6)):
                d[rng.randrange(len(d))] ^= 1 << rng.randrange(8)
        else:
            i = rng.randrange(len(d))
            d[i:i] = rng.choice([b"\n(nan) can0 123#00\n", b"\nxx yy\n", b"\x00\xff\n", b"\n 0.5 1 FFF Rx d 9 01\n"])
        src = tmp_path / f"m{k}{suffix}"
        src.write_bytes(bytes(d))
        try:
            _import(src, keep, overwrite=True) if k == 11 else _import(src, tmp_path / f"m{k}.mcap")
        except ValueError as exc:
            assert src.name in str(exc)
            continue
        out = keep if k == 11 else tmp_path / f"m{k}.mcap"
        for b in read_frames(out).values():
            ext, rem, err, fd = ((b.flags & bit) != 0 for bit in (1, 2, 4, 8))
            assert (b.arbitration_id[~ext & ~err] <= 0x7FF).all() and (b.arbitration_id <= 0x1FFFFFFF).all()
            assert (b.dlc[~fd & ~rem] <= 8).all() and np.isin(b.dlc[fd], FD_LENGTHS).all()
            assert ((b.timestamp_ns >= 0) & (b.timestamp_ns < 9.2e18)).all()
    if keep.read_bytes() != before:  # replaced only by a successful import of the last file
        assert len(read_frames(keep)) > 0


TRC_V11 = """\
;$FILEVERSION=1.1
;$STARTTIME=45244.92592593
;
     1)      1000.0  Rx         0120  2  01 02
     2)      2000.0  Rx         0121  2  01 02 03
     3)      3000.0  Rx         +122  1  05
     4)       nan    Rx         0123  1  05
     5)      5000.0  Rx     09567C22  8  00 00 00 00 00 00 00 00
     6)      6000.0  Rx         0124  8  01 02
"""
TRC_V13 = """\
;$FILEVERSION=1.3
;$STARTTIME=45244.92592593
;
     1)      1000.0 1  Rx         0120 -  2  01 02
     2)      2000.0 1  Rx         0FFF -  1  01
     3)      3000.0 2  Rx     09567C22 -  8  00 00 00 00 00 00 00 00
"""


@pytest.mark.parametrize("text,bad,ids", [(TRC_V11, {5, 6, 7, 9}, {0x120, 0x9567C22}),
                                          (TRC_V13, {5}, {0x120, 0x9567C22})])
def test_trc_version1_lines_checked(tmp_path, text, bad, ids):
    src = tmp_path / "v1.trc"
    src.write_text(text)
    res = _import(src, tmp_path / "a.mcap")
    assert _rejected_lines(res, str(src)) == bad
    assert {int(i) for b in read_frames(tmp_path / "a.mcap").values() for i in b.arbitration_id} == ids


def test_asc_identifier_and_remote_lines_checked(tmp_path):
    src = tmp_path / "r.asc"
    src.write_text("date Tue Nov 14 22:13:20.000 2023\nbase hex  timestamps absolute\n"
                   "internal events logged\nBegin Triggerblock Tue Nov 14 22:13:20.000 2023\n"
                   " 0.001000 1  +12             Rx   d 1 01\n"
                   " 0.002000 1  130             Rx   r\n"
                   " 0.003000 1  131             Rx   d 1 02\n"
                   "End TriggerBlock\n")
    res = _import(src, tmp_path / "a.mcap")
    assert _rejected_lines(res, str(src)) == {5}
    f = read_frames(tmp_path / "a.mcap")["can0"]
    assert f.arbitration_id.tolist() == [0x130, 0x131] and (f.flags & 2).tolist() == [2, 0]
