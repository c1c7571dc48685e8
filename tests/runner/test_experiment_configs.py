"""Every shipped experiment config parses and validates (no work is run)."""

from __future__ import annotations

from pathlib import Path

import pytest

from surrogate_rbrdo.runner.cli import _kinds
from surrogate_rbrdo.runner.config import load_config, spindle_from_config
from surrogate_rbrdo.runner.pipeline import SurrogateConfig
from surrogate_rbrdo.runner.study import parse_study_config

EXPERIMENTS_DIR = Path(__file__).resolve().parents[2] / "experiments"
CONFIGS = sorted(EXPERIMENTS_DIR.glob("*.toml"))


def test_the_experiments_folder_is_found():
    assert {"quick.toml", "paper.toml", "spindle.toml"} <= {p.name for p in CONFIGS}


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_config_validates(path):
    cfg = load_config(path)
    kinds = _kinds()
    assert cfg["experiment"]["kind"] in kinds
    spindle_from_config(cfg.get("spindle", {}), cfg["_base_dir"])
    if cfg["experiment"]["kind"] == "study":
        parse_study_config(cfg)
    if "surrogate" in cfg:
        SurrogateConfig.from_dict(cfg["surrogate"])
