"""Vehicle configuration: the shipped one, a user's edited copy, clear errors."""

import math
from pathlib import Path

import pytest
from daq_helpers import copy_default_vehicle

from wheelsoil.daq import REQUIRED_SIGNALS, load_vehicle_config


def test_shipped_config_maps_every_quantity():
    cfg = load_vehicle_config()
    assert set(REQUIRED_SIGNALS) <= set(cfg.signals)
    assert [p.name for p in cfg.buses["can0"]] == ["wft.dbc"]
    assert [p.name for p in cfg.buses["can1"]] == ["wheel_speed.dbc", "gps_rt_speedbox.dbc"]
    assert all(p.is_file() for ps in cfg.buses.values() for p in ps)
    assert (cfg.wheel_radius_m, cfg.wheel_width_m) == (0.47, 0.32)
    ws = cfg.signals["wheel_speed"]
    assert (ws.bus, ws.message, ws.signal) == ("can1", "WSS_WheelSpeeds", "WheelSpeed_RL")
    assert ws.scale_to_si == pytest.approx(2 * math.pi / 60)
    assert cfg.signals["wft_angle"].scale_to_si == pytest.approx(math.pi / 180)
    assert cfg.signals["gnss_forward_velocity"].message == "RT_SB_INS_Vel_Body_Axes"
    # counters: byte positions from the DBC (Counter at bit 48 / 48 / 16)
    specs = {fid: byte for _, fid, _, byte, *_ in cfg.counter_specs()}
    assert specs == {0x120: 6, 0x121: 6, 0x122: 2}
    names = cfg.message_names("can1")
    assert names[(0x9588322, True)] == "RT_SB_INS_Vel_Body_Axes"


_copy_default = copy_default_vehicle


def test_user_edits_only_the_toml(tmp_path):
    p = _copy_default(tmp_path)
    text = p.read_text().replace('unit = "rpm"\nscale_to_si = 0.10471975511965977', 'unit = "rpm"')
    text = text.replace("wheel_radius_m = 0.47", "wheel_radius_m = 0.5")
    p.write_text(text)
    cfg = load_vehicle_config(p)
    assert cfg.signals["wheel_speed"].scale_to_si == pytest.approx(2 * math.pi / 60)  # derived from the unit
    assert cfg.wheel_radius_m == 0.5


@pytest.mark.parametrize("edit, match", [
    (lambda t: t.replace("[signals.gnss_time_tow]", "[signals.other]"), r"missing \[signals.gnss_time_tow\]"),
    (lambda t: t.replace('signal = "My"', 'signal = "Mq"'), r"\[signals.wft_my\].*no signal 'Mq'"),
    (lambda t: t.replace('unit = "N.m"', 'unit = "furlong"'), r"\[signals.wft_my\] unit 'furlong'"),
    (lambda t: t.replace('bus = "can1"\nmessage = "WSS_WheelSpeeds"', 'bus = "can9"\nmessage = "WSS_WheelSpeeds"'),
     r"bus 'can9' is not in \[buses\]"),
    (lambda t: t + "\n[[[broken", r"not valid TOML"),
])
def test_bad_toml_errors_name_file_and_key(tmp_path, edit, match):
    p = _copy_default(tmp_path)
    p.write_text(edit(p.read_text()))
    with pytest.raises(ValueError, match=match) as exc:
        load_vehicle_config(p)
    assert str(p) in str(exc.value)


def test_unparsable_dbc_names_the_file(tmp_path):
    p = _copy_default(tmp_path)
    (tmp_path / "wft.dbc").write_text('VERSION "1"\nBO_ 288 WFT_RL_Force: 8 X\n SG_ broken ::: nonsense\n')
    with pytest.raises(ValueError, match="wft.dbc: cannot parse DBC"):
        load_vehicle_config(p)


def test_missing_file_is_oserror(tmp_path):
    with pytest.raises(OSError):
        load_vehicle_config(tmp_path / "nope.toml")
