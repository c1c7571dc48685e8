"""Every shipped experiment config parses and validates (no work is run, no folder made)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.runner.kinds import discover
from surrogate_rbrdo.study.config import UncertaintyTable, build_inputs

EXPERIMENTS_DIR = Path(__file__).resolve().parents[2] / "experiments"
CONFIGS = sorted(EXPERIMENTS_DIR.glob("*.toml"))
#: configs that read another experiment's run: everything validates up to that source (the
#: kind checks it last), which does not exist here
NEEDS_RUN = {"identification.toml": r"identification.source = 'results/rig_campaign_trial/"
                                    r"latest' is not allowed: 'results/rig_campaign_trial' "
                                    r"holds no complete run"}


def test_the_experiments_folder_is_found():
    assert {"quick.toml", "paper.toml", "spindle.toml"} <= {p.name for p in CONFIGS}


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_config_validates(path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)          # a results folder would appear here
    if path.name in NEEDS_RUN:
        with pytest.raises(ValueError, match=NEEDS_RUN[path.name]):
            prepare(path)
        assert not any(tmp_path.iterdir())
        return
    prep = prepare(path)
    assert prep.kind is discover()[prep.experiment.kind]
    assert not any(tmp_path.iterdir())


def test_uncertainty_table_defaults_and_errors():
    mvn = build_inputs(UncertaintyTable(), ("front", "rear"))
    assert np.allclose(mvn.mean, 1.0)
    assert np.allclose(np.sqrt(np.diag(mvn.cov)), [0.0605, 0.0641])
    with pytest.raises(ValueError, match=r"uncertainty.std\[1\] = -0.1"):
        build_inputs(UncertaintyTable(std=(0.05, -0.1)), ("front", "rear"))
    with pytest.raises(ValueError, match=r"uncertainty.mean = \[1.0, 1.0, 1.0\] is not allowed: "
                                         r"need 2 values"):
        build_inputs(UncertaintyTable(mean=(1.0, 1.0, 1.0)), ("front", "rear"))
