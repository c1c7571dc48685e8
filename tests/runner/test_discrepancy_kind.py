"""The ``discrepancy`` experiment kind end to end on a small rig campaign: a hidden housing
stage is named, the updated ``[spindle]`` loads with the fitted parameters, ``--resume`` does
not redo finished stages, and the same data read back from the finished run folder, its
dataset or a ``rig`` run give the same findings."""

from __future__ import annotations

import json
import math
import shutil
import tomllib
from pathlib import Path

import pytest

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.reporting import plots_discrepancy
from surrogate_rbrdo.rig.thermal import SoakPlan
from surrogate_rbrdo.runner.cli import run_experiment
from surrogate_rbrdo.runner.execute import RunFailed, prepare
from surrogate_rbrdo.runner.experiments import discrepancy as kind
from surrogate_rbrdo.runner.runfolder import read_meta
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle

ROOT = Path(__file__).resolve().parents[2]

HEAD = """
[experiment]
name = "{name}"
kind = "discrepancy"
seed = 5

[spindle]
geometry = "reference"
baseline = [2000.0, 500.0, 65.0]

[discrepancy]
library = ["housing", "anisotropy", "speed_softening"]
n_draws = 100
max_effects = 1
nuisance = {{ preset = "probe_chain" }}
"""

RIG = """
[rig]
effects = [{{ name = "housing", k_N_per_m = 6.0e8, m_kg = 20.0 }}]
figures = false

[rig.campaign]
speeds_rpm = {{ start = 1000.0, stop = 24000.0, num = 50 }}
repeats = 6
duration_s = 0.4
runup = []
impacts_per_direction = 0
"""


def _write(tmp_path: Path, text: str, name: str = "d.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.fixture(scope="module")
def housing_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("disc")
    cfg = _write(tmp, (HEAD + RIG).format(name="housing"))
    return run_experiment(cfg, results_dir=tmp / "res", run_id="r1", progress=False), tmp


@pytest.mark.known_answer
def test_a_hidden_housing_stage_is_named_and_the_updated_spindle_loads(housing_run):
    run, _ = housing_run
    findings = json.loads((run.path / "findings.json").read_text())
    assert findings["verdict"] == "named"
    assert [e["name"] for e in findings["effects"]] == ["housing"]
    fitted = findings["effects"][0]["parameters"]
    lo, hi = findings["effects"][0]["ci"]["k_N_per_m"]
    assert lo <= 6.0e8 <= hi                       # the hidden truth's stiffness
    assert findings["gap"]["after"]["rmse"] < findings["gap"]["before"]["rmse"]
    table = tomllib.loads((run.path / "spindle_updated.toml").read_text())["spindle"]
    sp = build_spindle(parse(SpindleTable, table, "spindle"))
    housing = [e for e in sp.effects if e.name == "housing"]
    assert len(housing) == 1
    for p in ("k_N_per_m", "m_kg"):
        assert math.isclose(getattr(housing[0], p), fitted[p], rel_tol=1e-12)
    model = [e for e in build_spindle(SpindleTable()).effects if not e.is_off]
    assert [e for e in sp.effects if e.name != "housing"] == model   # the model's own kept
    for f in ("candidates.csv", "curves.csv", "figures/residual_map.png",
              "figures/candidates.png", "figures/gap_unbalance_1x.png"):
        assert (run.path / f).is_file(), f
    summary = json.loads((run.path / "summary.json").read_text())
    assert summary["summary"][0]["verdict"].startswith("named: housing")
    assert read_meta(run.path)["verdict"] == "named"


def test_the_same_data_from_a_folder_gives_the_same_findings(housing_run):
    run, tmp = housing_run
    first = json.loads((run.path / "findings.json").read_text())
    for label, path in (("folder", run.path), ("dataset", run.path / "campaign" / "dataset")):
        cfg = _write(tmp, HEAD.format(name=label) + f"[data]\npath = '{path}'\n", f"{label}.toml")
        again = run_experiment(cfg, results_dir=tmp / "res", run_id="r1", progress=False)
        f = json.loads((again.path / "findings.json").read_text())
        assert f["verdict"] == first["verdict"]
        assert [e["name"] for e in f["effects"]] == [e["name"] for e in first["effects"]]
        assert math.isclose(f["gap"]["before"]["rmse"], first["gap"]["before"]["rmse"],
                            rel_tol=1e-6), label


def test_resume_does_not_redo_finished_stages(tmp_path, monkeypatch, housing_run):
    run0, _ = housing_run
    cfg = _write(tmp_path, HEAD.format(name="resume") + f"[data]\npath = '{run0.path}'\n")

    def broken(*a, **k):
        raise RuntimeError("figures failed")

    monkeypatch.setattr(plots_discrepancy, "plot_all", broken)
    with pytest.raises(RunFailed):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="r", progress=False)
    monkeypatch.undo()

    def never(*a, **k):
        raise AssertionError("a finished stage was redone")

    monkeypatch.setattr(kind, "find_discrepancy", never)
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="r", progress=False,
                         resume=True)
    assert read_meta(run.path)["status"] == "complete"
    assert (run.path / "figures" / "residual_map.png").is_file()


def test_resume_refuses_changed_data(tmp_path, monkeypatch, housing_run):
    """The data files are hashed into the run's inputs: a resumed run whose data changed
    since it started refuses (its finished stages rest on other data)."""
    run0, _ = housing_run
    data = tmp_path / "data"
    shutil.copytree(run0.path / "campaign", data)
    cfg = _write(tmp_path, HEAD.format(name="changed") + f"[data]\npath = '{data}'\n")
    monkeypatch.setattr(kind, "write_discrepancy_run", lambda *a, **k: 1 / 0)
    with pytest.raises(RunFailed):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="r", progress=False)
    monkeypatch.undo()
    assert str(data / "phasors.csv") in read_meta(tmp_path / "res" / "changed" / "r")["inputs"]
    with (data / "phasors.csv").open("a") as fh:
        fh.write("\n")
    with pytest.raises(ValueError, match="phasors.csv.*changed"):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="r", progress=False,
                       resume=True)


@pytest.mark.parametrize("name", ["discrepancy.toml", "discrepancy_null.toml"])
def test_the_shipped_configs_build(name):
    prep = prepare(ROOT / "experiments" / name)
    assert prep.plan.options.nuisance.gain_sd == 0.02
    hidden = [e.name for e in prep.plan.rig.rig.truth.hidden]
    assert hidden == ([] if "null" in name else ["housing"])
    assert prep.plan.rig.rig.options.soak == SoakPlan()      # soak = {}: the defaults


def test_the_impact_config_states_the_test_plan():
    prep = prepare(ROOT / "experiments" / "discrepancy_impacts.toml")
    assert prep.plan.options.use_impacts and prep.plan.options.nuisance.force_gain_sd == 0.01
    camp = prep.plan.rig.rig.options
    assert camp.impact_speeds_rpm == (0.0, 10000.0, 20000.0)
    assert camp.impacts_per_direction == 20
    assert camp.soak == SoakPlan()
    assert [e.name for e in prep.plan.rig.rig.truth.hidden] == ["cross_coupling"]


@pytest.mark.slow
@pytest.mark.known_answer
@pytest.mark.parametrize(("name", "first"), [("discrepancy.toml", "housing"),
                                             ("discrepancy_null.toml", None),
                                             ("discrepancy_impacts.toml", "cross_coupling")])
def test_the_shipped_configs_find_what_is_hidden(tmp_path, name, first):
    """With the impact test plan in every shipped config: the hidden housing stage is named
    with intervals covering its stiffness and mass, the null case says nothing is missing,
    the cross-coupling is named with an interval covering κ = 0.01 (each run 1-3 min)."""
    run = run_experiment(ROOT / "experiments" / name, results_dir=tmp_path, run_id="r",
                         progress=False)
    f = json.loads((run.path / "findings.json").read_text())
    assert f["verdict"] == ("named" if first else "nothing_missing")
    assert [e["name"] for e in f["effects"]][:1] == ([first] if first else [])
    truth = {"housing": {"k_N_per_m": 6.0e8, "m_kg": 20.0},
             "cross_coupling": {"kappa": 0.01}}.get(first, {})
    for p, v in truth.items():
        lo, hi = f["effects"][0]["ci"][p]
        assert lo < v < hi, (p, lo, hi)
