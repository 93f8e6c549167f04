"""``info`` integrity (issue 12, item 4 info side, item 6 embed side): true first/last time
with outliers set aside, joined logs flagged, provenance shown, escape sequences sanitised,
broken embedded configuration falls back with a warning, same-named DBCs on two buses."""

import dataclasses
import shutil
import warnings

import numpy as np
from daq_helpers import cli

from wheelsoil.daq import FrameBatch, RecordingWriter, load_vehicle_config, read_recording_info
from wheelsoil.daq.cli import format_info
from wheelsoil.daq.provenance import make_provenance

T0 = 1_700_000_000 * 10**9


def _batch(ts_ns, fid=0x120):
    n = len(ts_ns)
    return FrameBatch("can0", np.asarray(ts_ns, np.int64), np.full(n, fid, np.uint32), np.zeros(n, bool),
                      np.zeros(n, np.uint8), np.full(n, 8, np.uint8), np.zeros((n, 8), np.uint8))


def _rec(path, batches, **kw):
    with RecordingWriter(path, **kw) as w:
        for b in batches:
            w.write_batch(b)


def test_info_true_first_last_with_outlier_frames(tmp_path):
    ts = T0 + np.arange(6000, dtype=np.int64) * 10_000_000    # 60 s at 100 Hz
    ts_bad = ts.copy()
    ts_bad[0] = T0 - 6 * 3600 * 10**9          # first frame in file order 6 h early
    ts_bad[3000] = T0 + 6 * 3600 * 10**9       # one 6 h late in the middle
    ts_bad[-1] = np.int64(9_000_000_000_000_000_000)   # huge (NaN-like import)
    p = tmp_path / "o.mcap"
    _rec(p, [_batch(ts_bad[i:i + 500]) for i in range(0, 6000, 500)])
    info = read_recording_info(p)
    assert info.start_ns == ts[1] and info.end_ns == ts[-2]
    assert abs(info.duration_s - (ts[-2] - ts[1]) / 1e9) < 1e-9
    assert info.outlier_frames == 3
    assert any("3 frame(s) with timestamps far outside" in w for w in info.warnings)
    text = format_info(info)
    assert "OUTLIER TIMESTAMPS: 3" in text and "duration 59.970 s" in text


def test_info_whole_batch_a_day_off_is_an_outlier(tmp_path):
    ts = T0 + np.arange(4000, dtype=np.int64) * 10_000_000
    p = tmp_path / "d.mcap"
    _rec(p, [_batch(ts[:2000]), _batch(ts[2000:2010] + 86400 * 10**9), _batch(ts[2010:])])
    info = read_recording_info(p)
    assert info.start_ns == ts[0] and info.end_ns == ts[-1] and info.outlier_frames == 10


def test_info_flags_logs_joined_out_of_order(tmp_path):
    ts = T0 + np.arange(4000, dtype=np.int64) * 10_000_000
    p = tmp_path / "j.mcap"
    _rec(p, [_batch(ts[2000:]), _batch(ts[:2000])])   # second log first
    info = read_recording_info(p)
    assert info.non_monotonic == {"can0": 1}
    assert info.start_ns == ts[0] and info.end_ns == ts[-1]
    assert "NON-MONOTONIC TIME on can0" in format_info(info)


def test_info_shows_provenance_and_never_prints_escape_sequences(tmp_path):
    p = tmp_path / "e.mcap"
    prov = make_provenance("recorded", command=["wheelsoil", "log", "\x1b[2J\x1b[31mevil"],
                           adapters=["can0=socketcan:can0"])
    _rec(p, [_batch(T0 + np.arange(10) * 10**6)], provenance=prov,
         metadata={"host": "bad\x1b]0;title\x07host", "note": "\x9b31m"})
    info = read_recording_info(p)
    text = format_info(info)
    assert "provenance: recorded" in text and "can0=socketcan:can0" in text
    assert "\x1b" not in text and "\x07" not in text and "\x9b" not in text
    assert "\\x1b[2J" in text


def test_info_cli_sanitises_output(tmp_path, capsys):
    p = tmp_path / "e.mcap"
    _rec(p, [_batch(T0 + np.arange(10) * 10**6)],
         provenance=make_provenance("imported", command=None,
                                    sources=[{"path": "a\x1b[31m.log", "sha256": "0" * 64, "size_bytes": 3}]))
    assert cli("info", p) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "provenance: imported" in out and "a\\x1b[31m.log" in out


def test_broken_embedded_configuration_falls_back_with_a_warning(tmp_path):
    cfg = load_vehicle_config()
    bad = dataclasses.replace(cfg, text="[vehicle\nwheel_radius_m = = 3\n")
    bad._dbs = cfg._dbs
    p = tmp_path / "c.mcap"
    _rec(p, [_batch(T0 + np.arange(10) * 10**6)], config=bad)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        info = read_recording_info(p)
    assert info.config_source == "default vehicle.toml"
    assert any(str(p) in w and "vehicle.toml" in w and "default" in w for w in info.warnings), info.warnings


def test_dbc_attachment_with_a_path_name_does_not_abort_info(tmp_path):
    cfg = load_vehicle_config()
    p = tmp_path / "c.mcap"
    with RecordingWriter(p, config=cfg) as w:
        w.add_attachment("dbc/", "text/x-dbc", b"junk")
        w.add_attachment("dbc/../../../escape.dbc", "text/x-dbc", b"VERSION \"\"\n")
        w.write_batch(_batch(T0 + np.arange(10) * 10**6))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        info = read_recording_info(p)
    assert info.stats.frames["can0"] == 10
    assert not (tmp_path.parent / "escape.dbc").exists()


def test_same_named_dbcs_on_two_buses_round_trip(tmp_path):
    src = load_vehicle_config()
    base = src.source.parent
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    wft = [p for p in src.buses["can0"]][0]
    shutil.copy(wft, tmp_path / "a" / "sensors.dbc")
    can1 = src.buses["can1"]
    shutil.copy(can1[0], tmp_path / "b" / "sensors.dbc")
    rest = [str(p) for p in can1[1:]]
    text = src.text
    import re

    text = re.sub(r"(\[buses\.can0\][^\[]*?dbc\s*=\s*)\[[^\]]*\]", lambda m: m.group(1) + '["a/sensors.dbc"]', text,
                  flags=re.S)
    text = re.sub(r"(\[buses\.can1\][^\[]*?dbc\s*=\s*)\[[^\]]*\]",
                  lambda m: m.group(1) + repr(["b/sensors.dbc"] + rest).replace("'", '"'), text, flags=re.S)
    toml = tmp_path / "vehicle.toml"
    toml.write_text(text)
    cfg = load_vehicle_config(toml)
    assert [p.name for p in cfg.buses["can0"]] == ["sensors.dbc"] and cfg.buses["can1"][0].name == "sensors.dbc"
    p = tmp_path / "s.mcap"
    _rec(p, [_batch(T0 + np.arange(10) * 10**6)], config=cfg)
    info = read_recording_info(p)
    assert {"dbc/can0/sensors.dbc", "dbc/can1/sensors.dbc"} <= set(info.attachments)
    assert info.config_source == "recording attachments", info.warnings
    names0 = set(info.stats.names["can0"].values())
    names1 = set(info.stats.names["can1"].values())
    assert names0 == {m.name for m in src.database("can0").messages}
    assert names1 == {m.name for m in src.database("can1").messages}
    assert base.exists()


def test_decode_with_a_broken_embedded_configuration_falls_back_with_a_warning(tmp_path):
    from wheelsoil.daq.decode_json import decode_recording

    cfg = load_vehicle_config()
    bad = dataclasses.replace(cfg, text="[buses\n")
    bad._dbs = cfg._dbs
    p = tmp_path / "c.mcap"
    _rec(p, [_batch(T0 + np.arange(10) * 10**6)], config=bad)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = decode_recording(p, tmp_path / "d.mcap")
    assert any(str(p) in w and "default" in w for w in res.warnings)
    assert res.total == 10


def test_two_big_parts_hours_apart_are_both_the_run_not_outliers(tmp_path):
    a = T0 + np.arange(2000, dtype=np.int64) * 10_000_000
    b = a + 4 * 3600 * 10**9
    p = tmp_path / "g.mcap"
    _rec(p, [_batch(a[:1000]), _batch(a[1000:]), _batch(b[:1000]), _batch(b[1000:])])
    info = read_recording_info(p)
    assert info.outlier_frames == 0 and info.start_ns == a[0] and info.end_ns == b[-1]
    assert info.time["gaps_s"] and abs(info.time["gaps_s"][0] - 4 * 3600) < 60
