"""Vehicle configuration checked for physical sense (issue 12 item 6, config side):
every error names the file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest
from daq_helpers import copy_default_vehicle

from wheelsoil.daq import load_vehicle_config
from wheelsoil.daq.config import unit_mismatch


_copy_default = copy_default_vehicle


@pytest.mark.parametrize("edit, match", [
    (('dbc = ["wft.dbc"]', 'dbc = ["wft_missing.dbc"]'), r"vehicle.toml: \[buses.can0\] dbc names .*wft_missing.dbc"),
    (('dbc = ["wft.dbc"]', 'dbc = ["."]'), r"\[buses.can0\] dbc names .*which is not a file"),
    (("wheel_radius_m = 0.47", "wheel_radius_m = 470"),
     r"\[vehicle\] wheel_radius_m = 470: not a plausible radius in m \(0.05-2\); did you give mm\?"),
    (("wheel_radius_m = 0.47", "wheel_radius_m = inf"), r"\[vehicle\] wheel_radius_m = inf"),
    (("wheel_radius_m = 0.47", "wheel_radius_m = nan"), r"\[vehicle\] wheel_radius_m = nan"),
    (("wheel_radius_m = 0.47", "wheel_radius_m = -0.47"), r"wheel_radius_m = -0.47.*negative"),
    (("wheel_radius_m = 0.47", "wheel_radius_m = true"), r"wheel_radius_m = True: must be a number"),
    (("wheel_width_m = 0.32", "wheel_width_m = 320"), r"wheel_width_m = 320.*did you give mm"),
    (("wheel_mass_kg = 80.0", "wheel_mass_kg = 80000.0"), r"wheel_mass_kg = 80000.0: not a plausible wheel mass"),
    (("wheel_mass_kg = 80.0", "wheel_mass_kg = -1.0"), r"wheel_mass_kg = -1.0"),
    (("wheel_inertia_kgm2 = 11.5", "wheel_inertia_kgm2 = nan"), r"wheel_inertia_kgm2 = nan"),
    (('unit = "deg"\nscale_to_si = 0.017453292519943295', 'unit = "deg"\nscale_to_si = nan'),
     r"\[signals.wft_angle\] scale_to_si = nan: must be a finite"),
    (('unit = "deg"\nscale_to_si = 0.017453292519943295', 'unit = "deg"\nscale_to_si = 0'),
     r"\[signals.wft_angle\] scale_to_si = 0"),
    (('signal = "Fx_w"\nunit = "N"', 'signal = "Fx_w"\nunit = "kN"'),
     r"\[signals.wft_fx_w\] unit = 'kN' but the DBC \(wft.dbc\) gives WFT_RL_Force.Fx_w in 'N': "
     r"values would be scaled 1000x too high"),
    (('signal = "My"\nunit = "N.m"', 'signal = "My"\nunit = "N"'), r"\[signals.wft_my\] unit = 'N'.*moment"),
    (('unit = "rpm"\nscale_to_si = 0.10471975511965977', 'unit = "rad/s"\nscale_to_si = 1.0'),
     r"\[signals.wheel_speed\] unit = 'rad/s' but the DBC"),
    (("cycle_time_s = 0.01", "cycle_time_s = 10"), r"\[signals.wheel_speed\] cycle_time_s = 10.*did you give ms"),
])
def test_implausible_values_name_file_and_key(tmp_path, edit, match):
    p = _copy_default(tmp_path)
    text = p.read_text()
    assert edit[0] in text
    p.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(ValueError, match=match) as exc:
        load_vehicle_config(p)
    assert str(p) in str(exc.value)


def test_plausible_edits_still_load(tmp_path):
    p = _copy_default(tmp_path)
    text = p.read_text().replace("wheel_radius_m = 0.47", "wheel_radius_m = 0.0625")
    text = text.replace('signal = "My"\nunit = "N.m"', 'signal = "My"\nunit = "Nm"')  # same unit, other spelling
    text = text.replace("wheel_mass_kg = 80.0", "wheel_mass_kg = 0.0")
    p.write_text(text)
    cfg = load_vehicle_config(p)
    assert cfg.wheel_radius_m == 0.0625 and cfg.wheel_mass_kg == 0.0
    assert cfg.signals["wheel_speed"].cycle_time_s == 0.01
    assert cfg.cycle_time_s("can1", "WSS_WheelSpeeds") == (0.01, "vehicle configuration [signals.wheel_speed] "
                                                            "cycle_time_s")
    assert cfg.cycle_time_s("can1", "WSS_Status")[0] is None  # neither the DBC nor the TOML say


def test_missing_inertia_keys_fall_back_with_a_note(tmp_path):
    p = _copy_default(tmp_path)
    text = p.read_text()
    text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(("wheel_mass_kg", "wheel_inertia")))
    p.write_text(text)
    cfg = load_vehicle_config(p)
    assert (cfg.wheel_mass_kg, cfg.wheel_inertia_kgm2) == (80.0, 11.5)
    assert any("[vehicle] has no wheel_mass_kg" in n for n in cfg.notes)


def test_utf8_error_names_the_file(tmp_path):
    p = _copy_default(tmp_path)
    p.write_bytes(p.read_bytes().replace(b"instrumented left rear wheel", b"Me\xdfrad hinten links"))
    with pytest.raises(ValueError, match=r"vehicle.toml: not UTF-8 text \(byte 0xdf at offset \d+, line \d+\)"):
        load_vehicle_config(p)


def test_dbc_cycle_time_is_used(tmp_path):
    p = _copy_default(tmp_path)
    dbc = tmp_path / "wheel_speed.dbc"
    dbc.write_text(dbc.read_text() + '\nBA_DEF_ BO_ "GenMsgCycleTime" INT 0 65535;\nBA_DEF_DEF_ "GenMsgCycleTime" 0;\n'
                   'BA_ "GenMsgCycleTime" BO_ 769 100;\n')
    cfg = load_vehicle_config(p)
    assert cfg.cycle_time_s("can1", "WSS_Status") == (0.1, "DBC GenMsgCycleTime")


@pytest.mark.parametrize("a, b, bad", [("N", "N", False), ("Nm", "N.m", False), ("deg", "°", False),
                                       ("week", "", False), ("kN", "N", True), ("N", "N.m", True),
                                       ("km/h", "rpm", True), ("foo", "bar", True), ("foo", "FOO", False)])
def test_unit_mismatch(a, b, bad):
    assert bool(unit_mismatch(a, b)) is bad
