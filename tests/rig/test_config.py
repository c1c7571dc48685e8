"""The [rig] table: the shipped campaign config parses into a truth and options; bad values
are named (the runner's bad-input corpus, tests/runner/bad_inputs.py, has many more)."""

import tomllib
from pathlib import Path

import pytest

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.rig.campaign import CampaignOptions, SpeedGrid
from surrogate_rbrdo.rig.config import RigTable, RigTruthTable
from surrogate_rbrdo.rig.sensors import ProbeModel, SensorSet

CONFIG = Path(__file__).resolve().parents[2] / "experiments" / "rig_campaign.toml"


def test_shipped_rig_campaign_config_parses():
    cfg = parse(RigTable, tomllib.loads(CONFIG.read_text())["rig"], "rig").config()
    assert [e.name for e in cfg.truth.hidden] == ["anisotropy", "tool_interface"]
    assert len(cfg.options.speeds_rpm) == 50 and cfg.options.repeats == 20
    assert cfg.options.speeds_rpm[0] == 1000.0 and cfg.options.speeds_rpm[-1] == 24000.0
    assert cfg.options.sensors.probe.noise_rms_m == 50e-9


def test_speed_grid_is_linspace():
    o = CampaignOptions(speeds_rpm=SpeedGrid(1000.0, 24000.0, 50))
    assert o.speeds_rpm == CampaignOptions().speeds_rpm
    with pytest.raises(ValueError, match="stop = 1000.0 is not allowed: must be > start"):
        SpeedGrid(2000.0, 1000.0, 5)


def test_the_campaign_sensors_are_the_rig_sensors():
    s = SensorSet(probe=ProbeModel(noise_rms_m=10e-9))
    assert RigTable(sensors=s).config().options.sensors == s
    with pytest.raises(ValueError, match=r"campaign.sensors is not allowed: .*\[rig.sensors\]"):
        RigTable(campaign=CampaignOptions(sensors=s))


def test_unknown_keys_and_effects_are_named():
    with pytest.raises(ValueError, match=r"unknown key rig.campaign.repeat; allowed"):
        parse(RigTable, {"campaign": {"repeat": 3}}, "rig")
    with pytest.raises(ValueError, match=r"rig.effects\[0\]: name = 'nope' is not allowed: "
                       r"unknown effect 'nope'"):
        parse(RigTable, {"effects": [{"name": "nope"}]}, "rig")
    with pytest.raises(ValueError, match=r"unknown key rig.sensors.daq.bit; allowed"):
        parse(RigTable, {"sensors": {"daq": {"bit": 12}}}, "rig")
    with pytest.raises(ValueError, match=r"unknown key rig.campaign; allowed"):
        parse(RigTruthTable, {"campaign": {}}, "rig")
