"""Integrity of writing (issue 12, item 2 writer side): atomic writes, existing outputs
kept unless --overwrite, output never an input, the logger starts a numbered file."""

import warnings

import can
import pytest
from daq_helpers import cli, random_messages

from wheelsoil.daq import RecordingWriter, read_frames
from wheelsoil.daq.logger import CanLogger


def _write(path, n=100, seed=0, **kw):
    with RecordingWriter(path, **kw) as w:
        w.write_frames("can0", random_messages(n, seed=seed))


def test_failed_write_leaves_the_old_output_intact_and_no_temporary_file(tmp_path):
    path = tmp_path / "r.mcap"
    _write(path, 100)
    before = path.read_bytes()
    with pytest.raises(RuntimeError):
        with RecordingWriter(path) as w:
            w.write_frames("can0", random_messages(50, seed=2))
            w.flush()
            raise RuntimeError("input broke half way")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.mcap"]
    assert len(read_frames(path)["can0"]) == 100


def test_writer_refuses_an_existing_file_without_overwrite(tmp_path):
    path = tmp_path / "r.mcap"
    _write(path)
    before = path.read_bytes()
    with pytest.raises(FileExistsError, match="r.mcap"):
        RecordingWriter(path, overwrite=False)
    assert path.read_bytes() == before


def test_import_to_its_own_input_is_refused_and_the_input_kept(tmp_path, capsys):
    log = tmp_path / "x.log"
    log.write_text("(1700000000.000000) can0 123#1122334455667788\n" * 10)
    before = log.read_bytes()
    assert cli("import", log, "-o", log) == 2
    assert "x.log" in capsys.readouterr().err
    assert log.read_bytes() == before


@pytest.mark.parametrize("cmd", ["recover", "decode", "export"])
def test_output_equal_to_input_is_refused(tmp_path, capsys, cmd):
    rec = tmp_path / "r.mcap"
    _write(rec)
    before = rec.read_bytes()
    out = rec if cmd != "export" else rec
    assert cli(cmd, rec, "-o", out, "--overwrite") == 2
    assert "input" in capsys.readouterr().err
    assert rec.read_bytes() == before


def test_existing_output_kept_without_overwrite_and_replaced_with_it(tmp_path, capsys):
    rec = tmp_path / "r.mcap"
    _write(rec, 100)
    other = tmp_path / "other.mcap"
    _write(other, 30, seed=5)
    before = other.read_bytes()
    assert cli("recover", rec, "-o", other) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert other.read_bytes() == before
    assert cli("recover", rec, "-o", other, "--overwrite") == 0
    assert len(read_frames(other)["can0"]) == 100
    log = tmp_path / "out.log"
    log.write_text("keep me\n")
    assert cli("export", rec, "-o", log) == 2
    assert log.read_text() == "keep me\n"
    assert cli("export", rec, "-o", log, "--overwrite") == 0
    assert log.read_text().count("can0") == 100
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]


def test_unreadable_import_input_does_not_replace_an_existing_recording(tmp_path):
    good = tmp_path / "good.mcap"
    _write(good)
    before = good.read_bytes()
    missing = tmp_path / "missing.log"
    assert cli("import", missing, "-o", good, "--overwrite") == 2
    assert good.read_bytes() == before


def _log_once(out, **kw):
    bus_tx = can.Bus(interface="virtual", channel="integrity-w")
    bus_rx = can.Bus(interface="virtual", channel="integrity-w")
    try:
        lg = CanLogger({"can0": bus_rx}, out, batch_interval_s=0.05, **kw)
        for m in random_messages(20, seed=3, remote=False):
            bus_tx.send(m)
        return lg.run(duration_s=0.3)
    finally:
        bus_tx.shutdown()
        bus_rx.shutdown()


def test_logger_never_overwrites_an_existing_recording(tmp_path):
    out = tmp_path / "run.mcap"
    _write(out, 7)
    before = out.read_bytes()
    res = _log_once(out)
    assert out.read_bytes() == before
    assert res.files == [tmp_path / "run-001.mcap"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert len(read_frames(res.files[0])["can0"]) == 20
    res2 = _log_once(out)
    assert res2.files == [tmp_path / "run-002.mcap"]
    res3 = _log_once(out, overwrite=True)
    assert res3.files == [out] and out.read_bytes() != before
