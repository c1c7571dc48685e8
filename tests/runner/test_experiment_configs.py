"""Every shipped experiment config parses and validates (no work is run)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
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


def test_uncertainty_table_defaults_and_errors():
    from surrogate_rbrdo.runner.config import uncertainty_from_config

    mvn = uncertainty_from_config({}, ("front", "rear"))
    assert np.allclose(mvn.mean, 1.0)
    assert np.allclose(np.sqrt(np.diag(mvn.cov)), [0.0605, 0.0641])
    with pytest.raises(ValueError, match=r"uncertainty.std\[1\] = -0.1"):
        uncertainty_from_config({"std": [0.05, -0.1]}, ("front", "rear"))
    with pytest.raises(ValueError, match=r"shapes \(3,\)/\(2,\)"):
        uncertainty_from_config({"mean": [1, 1, 1]}, ("front", "rear"))
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['sigma'\] in \[uncertainty\]"):
        uncertainty_from_config({"sigma": [0.1, 0.1]}, ("front", "rear"))
