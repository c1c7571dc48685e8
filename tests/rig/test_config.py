"""The [rig] table of the shipped campaign config parses into a truth and options."""

import tomllib
from pathlib import Path

import pytest

from surrogate_rbrdo.rig.config import rig_config_from_dict

CONFIG = Path(__file__).resolve().parents[2] / "experiments" / "pending" / "rig_campaign.toml"


def test_shipped_rig_campaign_config_parses():
    cfg = rig_config_from_dict(tomllib.loads(CONFIG.read_text())["rig"])
    assert [e.name for e in cfg.truth.hidden] == ["anisotropy", "tool_interface"]
    assert len(cfg.options.speeds_rpm) == 50 and cfg.options.repeats == 20
    assert cfg.options.speeds_rpm[0] == 1000.0 and cfg.options.speeds_rpm[-1] == 24000.0
    assert cfg.options.sensors.probe.noise_rms_m == 50e-9


def test_unknown_keys_and_effects_are_named():
    with pytest.raises(ValueError, match="rig.campaign"):
        rig_config_from_dict({"campaign": {"repeat": 3}})
    with pytest.raises(ValueError, match="unknown effect 'nope'"):
        rig_config_from_dict({"effects": [{"name": "nope"}]})
    with pytest.raises(ValueError, match="rig.sensors.daq"):
        rig_config_from_dict({"sensors": {"daq": {"bit": 12}}})
