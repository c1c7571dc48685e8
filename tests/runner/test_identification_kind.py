"""The ``identification`` experiment kind end to end on a small rig campaign (with trial-weight
runs), the files it writes, that it composes the library, and its resume."""

from __future__ import annotations

import csv
import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.identification import (
    IdentificationOptions,
    identify_records,
    stiffness_block_from,
)
from surrogate_rbrdo.reporting import plots_identification
from surrogate_rbrdo.runner.cli import run_experiment
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.runner.experiments import identification as kind
from surrogate_rbrdo.runner.runfolder import read_meta
from surrogate_rbrdo.spindle import reference_spindle

RIG = """
[experiment]
name = "rig_trial"
kind = "rig"
seed = 3

[rig]
figures = false

[rig.campaign]
speeds_rpm = [4000.0, 8000.0, 12000.0, 16000.0, 20000.0, 24000.0]
repeats = 3
duration_s = 0.1
runup = []
impacts_per_direction = 0
trial_unbalance = [0.0, 5e-5, 0.0]
"""

IDENT = """
[experiment]
name = "ident"
kind = "identification"
seed = 5

[identification]
source = "{source}"
n_boot = 40
figures = {figures}
"""

COEFFS = [f"{b}_{q}_{d}" for b in ("front", "rear") for q in ("k", "c") for d in ("yy", "zz")]


class _Stop(KeyboardInterrupt):
    pass


@pytest.fixture(scope="module")
def rig_results(tmp_path_factory):
    root = tmp_path_factory.mktemp("ident_kind")
    cfg = root / "rig.toml"
    cfg.write_text(RIG)
    run_experiment(cfg, results_dir=root / "res", run_id="r1", progress=False)
    return root / "res"


def _config(tmp_path: Path, source: Path | str, figures: bool = True) -> Path:
    p = tmp_path / "ident.toml"
    p.write_text(IDENT.format(source=source, figures=str(figures).lower()))
    return p


def test_identification_run_folder(tmp_path, rig_results):
    cfg = _config(tmp_path, rig_results / "rig_trial" / "latest")
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="i1", progress=False)
    meta = read_meta(run.path)
    assert meta["status"] == "complete" and meta["rig_run"]["run_id"] == "r1"
    with open(run.path / "identified.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert {"speed_rpm", "repeat", *COEFFS} <= set(rows[0])
    # one row per trial pair: every trial record of the dataset, with its speed and repeat
    index = [json.loads(line) for line in (rig_results / "rig_trial" / "r1" / "campaign" /
                                           "dataset" / "index.jsonl").read_text().splitlines()]
    trials = sorted((r["speed_rpm"], r["labels"]["repeat"]) for r in index
                    if r["labels"].get("trial"))
    assert len(trials) == 18
    assert sorted((float(r["speed_rpm"]), int(r["repeat"])) for r in rows) == trials
    k = np.array([[float(r[c]) for c in ("front_k_yy", "rear_k_zz")] for r in rows
                  if r["used"] == "1"])
    assert np.all((k > 1e7) & (k < 1e10))          # N/m (SI), not MN/m
    u = json.loads((run.path / "uncertainty.json").read_text())
    assert u["names"] == ["front", "rear"] and np.shape(u["cov"]) == (2, 2)
    assert set(u["trend"]) == {"front_k_yy", "front_k_zz", "rear_k_yy", "rear_k_zz"}
    assert {"law", "params"} <= set(u["trend"]["front_k_yy"]) and u["tests"]
    for f in ("identification_convergence.png", "identification_trend.png",
              "identification_qq.png", "identification_summary.json"):
        assert (run.path / f).is_file(), f
    # the kind composes the library: the same records and seed stream give the same model
    sp = reference_spindle()
    direct = identify_records(sp.model(sp.baseline), rig_results / "rig_trial" / "r1" / "campaign",
                              IdentificationOptions(n_boot=40, figures=False),
                              rng=np.random.default_rng(np.random.SeedSequence(5, spawn_key=(0,))))
    d = direct.uncertainty.to_dict()
    np.testing.assert_allclose(u["mean"], d["mean"], rtol=1e-12)
    np.testing.assert_allclose(u["cov"], d["cov"], rtol=1e-10)


def test_resume_does_not_redo_the_identification(tmp_path, rig_results, monkeypatch):
    cfg = _config(tmp_path, rig_results / "rig_trial" / "r1", figures=False)

    def stop(*args, **kwargs):
        raise _Stop()

    monkeypatch.setattr(plots_identification, "table_rows", stop)   # interrupted in the report
    with pytest.raises(KeyboardInterrupt):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="i1", progress=False)
    path = tmp_path / "res" / "ident" / "i1"
    assert read_meta(path)["status"] == "interrupted"
    assert {p.name for p in (path / "stages").iterdir()} == {"00-demodulate.pkl",
                                                             "01-identify.pkl"}
    monkeypatch.undo()
    monkeypatch.setattr(kind, "read_responses", stop)
    monkeypatch.setattr(kind, "identify_responses", stop)
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="i1", progress=False,
                         resume=True)
    assert read_meta(run.path)["status"] == "complete"
    assert (run.path / "identified.csv").is_file() and (run.path / "uncertainty.json").is_file()


STUDY = """[experiment]
name = "study_from"
kind = "study"
seed = 1
[uncertainty]
from = "{source}"
[response]
{response}
[surrogate]
n_doe = 12
n_jobs = 1
n_start = 1
[deterministic]
resonance = "none"
stress = false
[optimization]
p_targets = [0.10]
n_theta = 20
pop_size = 6
n_gen = 2
n_jobs = 1
strategies = ["rdo"]
[verification]
n_theta = 4
n_jobs = 1
[report]
n_speeds = 10
campbell_speeds = 3
n_modes = 2
"""
AT_24K = 'kind = "at_speed"\nspeed_rpm = 24000.0'


@pytest.fixture(scope="module")
def ident_run(rig_results, tmp_path_factory):
    root = tmp_path_factory.mktemp("ident_run")
    cfg = _config(root, rig_results / "rig_trial" / "r1", figures=False)
    return run_experiment(cfg, results_dir=root / "res", run_id="i1", progress=False).path


def _study(tmp_path: Path, source, response: str = AT_24K) -> Path:
    p = tmp_path / "study.toml"
    p.write_text(STUDY.format(source=source, response=response))
    return p


@pytest.mark.known_answer
def test_study_theta_is_the_identified_model(tmp_path, ident_run):
    """``[uncertainty] from``: at the identification's summary speed (24 000 rpm) the study's θ
    has the mean and covariance written in uncertainty.json; the study runs and its meta.json
    names the file (sha256) and the identification run."""
    u_file = ident_run / "uncertainty.json"
    u = json.loads(u_file.read_text())
    assert u["speed_rpm"] == 24000.0
    cfg = _study(tmp_path, ident_run)
    plan = prepare(cfg).plan
    theta = plan.problem.inputs
    np.testing.assert_allclose(theta.mean, u["mean"], rtol=1e-12)
    np.testing.assert_allclose(theta.cov, u["cov"], rtol=1e-9, atol=1e-15)
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="s1", progress=False)
    meta = read_meta(run.path)
    src = meta["uncertainty_from"]
    assert meta["status"] == "complete"
    assert src["sha256"] == hashlib.sha256(u_file.read_bytes()).hexdigest()
    assert src["run"]["run_id"] == "i1" and src["run"]["kind"] == "identification"
    assert src["speeds_rpm"] == [24000.0]
    # the file is an input: the resume check knows it
    assert meta["inputs"] == {str(u_file.resolve()): src["sha256"]}


def test_study_from_refuses_what_the_identification_does_not_give(tmp_path, ident_run,
                                                                   monkeypatch):
    monkeypatch.chdir(tmp_path)
    # a speed below the identified range (the campaign was measured from 4 000 rpm up)
    with pytest.raises(ValueError, match=r"uncertainty.from = '.*': speed_rpm = 2000.0 is not "
                                         r"allowed: the model was identified in \[[48]000, "
                                         r"24000\] rpm \(no extrapolation\)"):
        prepare(_study(tmp_path, ident_run, 'kind = "at_speed"\nspeed_rpm = 2000.0'))
    # θ bearings that were not identified
    u = json.loads((ident_run / "uncertainty.json").read_text())
    u["names"] = ["spindle_nose", "rear"]
    (tmp_path / "u.json").write_text(json.dumps(u))
    with pytest.raises(ValueError, match=r"uncertainty.from = 'u.json': theta_bearings = "
                                         r"\['front', 'rear'\] is not allowed: \['front'\] not "
                                         r"identified \(identified: \['spindle_nose', 'rear'\]\)"):
        prepare(_study(tmp_path, "u.json"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["study.toml", "u.json"]


def test_peak_unbalance_theta_over_the_identified_part_of_the_range(tmp_path, ident_run):
    """A peak over 1 000-24 000 rpm: θ's stiffness block is the mixture over 25 speeds
    spanning the identified part of the range (from the lowest speed of a used record in
    identified.csv); the thermal and unbalance columns are those without ``from``."""
    with open(ident_run / "identified.csv", newline="") as fh:
        used = [float(r["speed_rpm"]) for r in csv.DictReader(fh) if r["used"] == "1"]
    plan = prepare(_study(tmp_path, ident_run, 'kind = "peak_unbalance"')).plan
    own, _ = stiffness_block_from(ident_run, ("front", "rear"),
                                  np.linspace(min(used), max(used), 25))
    theta = plan.problem.inputs
    np.testing.assert_allclose(theta.blocks[0].mean, own.mean, rtol=1e-12)
    np.testing.assert_allclose(theta.blocks[0].cov, own.cov, rtol=1e-9, atol=1e-15)
    src = plan.theta_source
    assert src["range_left_out_rpm"] == [[1000.0, min(used)]]
    plain = _study(tmp_path, ident_run, 'kind = "peak_unbalance"').read_text().replace(
        f'from = "{ident_run}"', "")
    (tmp_path / "plain.toml").write_text(plain)
    ref = prepare(tmp_path / "plain.toml").plan.problem.inputs
    assert theta.dim == ref.dim and repr(theta.blocks[1:]) == repr(ref.blocks[1:])


def test_stiffness_block_from_python(ident_run):
    """The library call the runner composes: the MVN of uncertainty.json at its speed."""
    u = json.loads((ident_run / "uncertainty.json").read_text())
    block, prov = stiffness_block_from(ident_run, ("rear", "front"), [24000.0])
    np.testing.assert_allclose(block.mean, u["mean"][::-1], rtol=1e-12)
    np.testing.assert_allclose(block.cov, np.asarray(u["cov"])[::-1, ::-1], rtol=1e-9,
                               atol=1e-15)
    assert prov["run"]["experiment"] == "ident" and prov["distribution"] == "normal"
    logn, _ = stiffness_block_from(ident_run / "uncertainty.json", ("front", "rear"),
                                   [24000.0], distribution="lognormal")
    x = logn.sample(20000, rng=np.random.default_rng(0))
    np.testing.assert_allclose(x.mean(axis=0), u["mean"], rtol=3e-3)


def test_impact_fit_lines_in_the_run_summary():
    """With ``damping = "impact"`` the summary prints each installation's η̂, tool mass, the
    fit's χ²/ν and the lack-of-fit test (the model-error flag; files written before the test
    existed print without it); with ``"response"`` nothing."""
    dmp = {"source": "impact", "installations": {"build=0|tool=0": {
        "eta_s": [4.47603e-06, 4.04102e-06], "chi2_dof": 311.7456,
        "parameters": {"tool_mass": 1.06843, "front_damping": 1.1}}}}
    assert plots_identification.impact_rows(dmp) == [{
        "impacts": "build=0|tool=0", "eta_s": [4.476e-06, 4.041e-06], "tool_mass": 1.0684,
        "chi2_dof": 311.75}]
    rows = plots_identification.impact_rows
    assert rows({"source": "response"}) == [] and rows(None) == []
    inst = dmp["installations"]["build=0|tool=0"]
    inst["lack_of_fit"] = {"chi2_dof": 175.7, "dof": 917, "threshold": 3.0, "flagged": True,
                           "hits": 5}
    assert rows(dmp)[0]["lack_of_fit"] == "MODEL ERROR (chi2/dof 176, threshold 3)"
    inst["lack_of_fit"] = None
    assert rows(dmp)[0]["lack_of_fit"].startswith("not tested")
