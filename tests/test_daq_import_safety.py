"""import/export never destroy data: output != input, existing outputs kept, temp file + rename,
empty/garbage input refused; imported provenance (issue 12 items 2 and 7, import side)."""

import hashlib
import json
import os
import socket
import warnings

import can
import numpy as np
import pytest
from daq_helpers import cli, random_messages

from wheelsoil.daq import read_frames, read_recording_info
from wheelsoil.daq.convert import export_recording, import_log


def _candump(path, msgs):
    with can.CanutilsLogWriter(str(path)) as w:
        for m in msgs:
            w.on_message_received(m)
    return path


def _import(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return import_log(*args, **kw)


@pytest.fixture
def good_log(tmp_path):
    return _candump(tmp_path / "good.log", random_messages(300, seed=3, channel="can0"))


def _leftovers(directory, keep):
    return sorted(p.name for p in directory.iterdir() if p.name not in keep)


# ------------------------------------------------------------------ output is an input
def test_import_output_equal_to_input_is_refused_and_input_intact(tmp_path, good_log, capsys):
    before = good_log.read_bytes()
    assert cli("import", good_log, "-o", good_log) != 0
    err = capsys.readouterr().err
    assert "good.log" in err and "input" in err and "Traceback" not in err
    assert good_log.read_bytes() == before
    with pytest.raises(ValueError, match="input"):
        import_log(good_log, good_log, overwrite=True)  # not even with overwrite
    # the same file under another name: a hard link and a symlink
    link, sym = tmp_path / "link.log", tmp_path / "sym.log"
    os.link(good_log, link)
    sym.symlink_to(good_log)
    for other in (link, sym):
        with pytest.raises(ValueError, match="input"):
            import_log(good_log, other, overwrite=True)
        with pytest.raises(ValueError, match="input"):
            import_log([other], good_log, overwrite=True)
    assert good_log.read_bytes() == before
    assert _leftovers(tmp_path, {"good.log", "link.log", "sym.log"}) == []


def test_export_output_equal_to_input_is_refused(tmp_path, good_log):
    rec = tmp_path / "rec.log"  # an MCAP recording that happens to be named .log
    _import(good_log, tmp_path / "r.mcap")
    os.replace(tmp_path / "r.mcap", rec)
    before = rec.read_bytes()
    with pytest.raises(ValueError, match="input"):
        export_recording(rec, rec, overwrite=True)
    assert rec.read_bytes() == before
    assert sum(len(b) for b in read_frames(rec).values()) == 300


# ------------------------------------------------------------------ existing outputs
def test_existing_recording_is_kept_without_overwrite(tmp_path, good_log):
    out = tmp_path / "run.mcap"
    _import(good_log, out)
    before = out.read_bytes()
    other = _candump(tmp_path / "other.log", random_messages(50, seed=4, channel="can1"))
    with pytest.raises(FileExistsError, match="overwrite"):
        _import(other, out)
    assert out.read_bytes() == before
    res = _import(other, out, overwrite=True)
    assert res.frames == {"can1": 50}
    assert {b: len(f) for b, f in read_frames(out).items()} == {"can1": 50}
    assert _leftovers(tmp_path, {"good.log", "other.log", "run.mcap"}) == []


@pytest.mark.parametrize("name,content", [
    ("empty.log", b""),
    ("blank.log", b"\n\n  \n"),
    ("garbage.log", b"this is not a candump file\nnor is this\n\x00\x01\x02\xff\xfe\n"),
    ("binary.log", bytes(np.random.default_rng(0).integers(0, 256, 5000, dtype=np.uint8))),
    ("garbage.asc", b"date Mon Jan 1 00:00:00 2024\nbase hex timestamps absolute\nnothing here\n"),
    ("garbage.trc", b";$FILEVERSION=2.1\n;$STARTTIME=45000\n;$COLUMNS=N,O,T,B,I,d,R,L,D\nxx yy zz\n"),
    ("zeros.blf", b"LOGG" + b"\x00" * 200),
    ("junk.blf", bytes(np.random.default_rng(1).integers(0, 256, 3000, dtype=np.uint8))),
])
def test_unreadable_input_fails_and_keeps_the_existing_recording(tmp_path, good_log, capsys, name, content):
    out = tmp_path / "run.mcap"
    _import(good_log, out)
    before = out.read_bytes()
    bad = tmp_path / name
    bad.write_bytes(content)
    with pytest.raises(ValueError, match=name.replace(".", r"\.")):
        _import(bad, out, overwrite=True)
    assert out.read_bytes() == before  # not replaced by an empty recording
    # CLI: non-zero exit naming the file, no new output, no temp file left behind
    new = tmp_path / "new.mcap"
    assert cli("import", bad, "-o", new) != 0
    err = capsys.readouterr().err
    assert name in err and "Traceback" not in err
    assert not new.exists()
    assert _leftovers(tmp_path, {"good.log", "run.mcap", name}) == []


def test_one_bad_input_among_several_writes_nothing(tmp_path, good_log):
    bad = tmp_path / "bad.log"
    bad.write_text("garbage\n")
    out = tmp_path / "run.mcap"
    with pytest.raises(ValueError, match="bad.log"):
        _import([good_log, bad], out)
    assert not out.exists()
    assert _leftovers(tmp_path, {"good.log", "bad.log"}) == []


def test_import_writes_a_temporary_file_and_renames_it(tmp_path, good_log, monkeypatch):
    """While the import runs, the final name does not exist; the temp file is in the
    output's directory (same file system, so the rename is atomic)."""
    from wheelsoil.daq import convert

    out = tmp_path / "run.mcap"
    seen = []
    real = convert.RecordingWriter

    def spy(path, **kw):
        seen.append((path, out.exists()))
        return real(path, **kw)

    monkeypatch.setattr(convert, "RecordingWriter", spy)
    _import(good_log, out)
    (tmp, existed), = seen
    assert tmp.parent == out.parent and tmp != out and not existed
    assert not tmp.exists() and out.exists()


# ------------------------------------------------------------------ export
def test_export_keeps_existing_output_and_writes_via_a_temporary_file(tmp_path, good_log, monkeypatch):
    from wheelsoil.daq import convert

    rec = tmp_path / "r.mcap"
    _import(good_log, rec)
    out = tmp_path / "out.log"
    out.write_text("precious\n")
    with pytest.raises(FileExistsError, match="overwrite"):
        export_recording(rec, out)
    assert out.read_text() == "precious\n"
    # a failure in the middle of the export leaves the old file and no temp file
    real = convert.iter_merged_messages

    def broken(*a, **kw):
        for i, m in enumerate(real(*a, **kw)):
            if i == 100:
                raise OSError("disk went away")
            yield m

    monkeypatch.setattr(convert, "iter_merged_messages", broken)
    with pytest.raises(OSError, match="disk went away"):
        export_recording(rec, out, overwrite=True)
    assert out.read_text() == "precious\n"
    assert _leftovers(tmp_path, {"good.log", "r.mcap", "out.log"}) == []
    monkeypatch.setattr(convert, "iter_merged_messages", real)
    res = export_recording(rec, out, overwrite=True)
    assert res.total == 300
    assert out.read_text().count("\n") == 300
    assert _leftovers(tmp_path, {"good.log", "r.mcap", "out.log"}) == []
    # a new file needs no overwrite
    assert export_recording(rec, tmp_path / "new.blf").total == 300


# ------------------------------------------------------------------ provenance
def test_imported_recording_says_imported_with_source_hash_and_not_the_import_host(tmp_path, good_log):
    out = tmp_path / "run.mcap"
    t_first = min(m.timestamp for m in random_messages(300, seed=3, channel="can0"))
    _import(good_log, out)
    info = read_recording_info(out)
    prov = info.provenance
    assert prov["kind"] == "imported"
    (src,) = prov["sources"]
    assert src["sha256"] == hashlib.sha256(good_log.read_bytes()).hexdigest()
    assert src["size_bytes"] == good_log.stat().st_size
    assert os.path.samefile(src["path"], good_log)
    assert prov["wheelsoil_version"] and prov["created_utc"]
    facts = info.metadata["wheelsoil.recording"]
    # the recording started when the log's first frame was received, not at import time
    assert int(facts["start_time_ns"]) == pytest.approx(t_first * 1e9, abs=1000)
    assert facts["start_time_utc"].startswith("2023-11-14")
    assert facts["host"] != socket.gethostname() and "imported" in facts["host"]
    assert facts["imported_on_host"] == socket.gethostname()
    summary = info.metadata["wheelsoil.summary"]
    t_last = max(m.timestamp for m in random_messages(300, seed=3, channel="can0"))
    assert int(summary["end_time_ns"]) == pytest.approx(t_last * 1e9, abs=1000)
    rec = info.metadata["wheelsoil.import"]
    assert json.loads(rec["frames"]) == 300 and json.loads(rec["rejected"]) == 0
    assert json.loads(rec["truncated"]) is False


def test_import_says_which_vehicle_configuration_it_attached(tmp_path, good_log, capsys):
    """A log file carries no vehicle: slip (Eq. 6) will use the attached wheel, so ``import`` says which
    one it attached when no --vehicle was given, and says nothing of the kind when one was."""
    from wheelsoil.daq.config import default_vehicle_path, load_vehicle_config

    assert cli("import", good_log, "-o", tmp_path / "a.mcap") == 0
    out = capsys.readouterr().out
    shipped = load_vehicle_config()
    assert "shipped vehicle configuration" in out and f"wheel radius {shipped.wheel_radius_m:g} m" in out
    assert "--vehicle" in out
    assert cli("import", good_log, "-o", tmp_path / "b.mcap", "--vehicle", default_vehicle_path()) == 0
    assert "shipped vehicle configuration" not in capsys.readouterr().out
