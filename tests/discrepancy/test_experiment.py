"""The experiment kind's library side: config tables, a measured-data folder, the analysis."""

from __future__ import annotations

import csv
import json
import tomllib
from dataclasses import fields, replace
from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.discrepancy.experiment import (
    DiscrepancyTable,
    analyse,
    data_from_folder,
    options_from_dict,
)
from surrogate_rbrdo.discrepancy.nuisance import NuisanceOptions
from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions
from surrogate_rbrdo.rig.config import RigTable
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle

from .conftest import campaign_data

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments"


@pytest.mark.parametrize("name", ["discrepancy.toml", "discrepancy_null.toml"])
def test_configs_parse(name):
    cfg = tomllib.loads((EXPERIMENTS / name).read_text())
    assert cfg["experiment"]["kind"] == "discrepancy"
    o = options_from_dict(cfg["discrepancy"])
    assert o.nuisance.gain_sd == 0.02 and "housing" in o.library
    build_spindle(parse(SpindleTable, cfg["spindle"], "spindle"))
    truth = parse(RigTable, cfg["rig"], "rig").config().truth
    assert [e.name for e in truth.hidden] == ([] if "null" in name else ["housing"])


def test_bad_tables_name_the_key():
    with pytest.raises(ValueError, match=r"unknown key discrepancy.alpha_typo; allowed"):
        options_from_dict({"alpha_typo": 0.1})
    with pytest.raises(ValueError, match=r"discrepancy.nuisance.preset = 'nope' is not allowed"):
        options_from_dict({"nuisance": {"preset": "nope"}})
    with pytest.raises(ValueError, match=r"discrepancy.nuisance.mass_sd = 0.9 is not allowed"):
        options_from_dict({"nuisance": {"preset": "probe_chain", "mass_sd": 0.9}})
    with pytest.raises(ValueError, match=r"discrepancy.library\[1\] = 'warp' is not allowed"):
        options_from_dict({"library": ["housing", "warp"]})


def test_a_preset_is_overridden_field_by_field():
    o = options_from_dict({"nuisance": {"preset": "probe_chain", "gain_sd": 0.05}})
    p = NuisanceOptions.probe_chain()
    assert o.nuisance == replace(p, gain_sd=0.05)
    assert options_from_dict({}).nuisance == NuisanceOptions()


def test_a_folder_of_phasors_is_analysed(spindle, tmp_path):
    sp, g = spindle
    data, _ = campaign_data(spindle, seed=3)
    b = data.blocks[0]
    with (tmp_path / "phasors.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["run", "speed_rpm", "channel", "re_m", "im_m"])
        for r in range(b.runs.shape[0]):
            for i, s in enumerate(b.coord):
                for j, c in enumerate(b.channels):
                    w.writerow([r, s, c.name, b.runs[r, i, j].real, b.runs[r, i, j].imag])
    (tmp_path / "channels.json").write_text(json.dumps(
        {c.name: [c.position_mm, c.direction] for c in b.channels}))
    folder = data_from_folder(tmp_path)
    order = [[c.name for c in b.channels].index(c.name) for c in folder.blocks[0].channels]
    assert np.allclose(folder.blocks[0].mean, b.mean[:, order])
    res, paths = analyse(folder, g, sp.effects, spindle_section={"geometry": "reference"},
                         options=options_from_dict({"n_draws": 120}),
                         rng=np.random.default_rng(0), out_dir=tmp_path / "run")
    assert res.verdict == "nothing_missing"
    assert json.loads(paths["findings"].read_text())["verdict"] == "nothing_missing"
    with pytest.raises(ValueError, match="no phasors.csv"):
        data_from_folder(tmp_path / "run")


def test_the_table_has_the_options_fields_and_defaults():
    """[discrepancy] mirrors DiscrepancyOptions (nuisance as a table with a preset)."""
    assert [f.name for f in fields(DiscrepancyTable)] == [
        f.name for f in fields(DiscrepancyOptions)]
    assert DiscrepancyTable().options() == DiscrepancyOptions()
