"""The ``end_to_end`` experiment kind: its tables and build (fast), its resume at the first
unfinished stage (fast: interrupted twice), and a tiny-budget loop to the report (slow)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.loop import steps as loop_steps
from surrogate_rbrdo.runner.cli import run_experiment
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.runner.experiments import end_to_end as kind
from surrogate_rbrdo.runner.experiments import identification as ident_kind
from surrogate_rbrdo.runner.experiments import rig as rig_kind
from surrogate_rbrdo.runner.experiments import study as study_kind
from surrogate_rbrdo.runner.kinds import StageContext
from surrogate_rbrdo.runner.runfolder import read_meta

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.filterwarnings("ignore:The BCa confidence interval cannot be")

TINY = """
[experiment]
name = "e2e_tiny"
kind = "end_to_end"
seed = 1
[spindle]
geometry = "credible"
[uncertainty.unbalance]
magnitude = "disk"
[response]
kind = "peak_unbalance"
[limit]
delta_lim_um = 1.0
[surrogate]
structure = "fe"
[deterministic]
stress = false
resonance = "none"
[optimization]
p_targets = [0.10]
strategies = []
n_theta = 20
pop_size = 8
n_gen = 2
n_jobs = 1
[verification]
n_theta = 10
n_jobs = 1
campbell_speeds = 0
[report]
n_speeds = 20
campbell_speeds = 4
n_modes = 2
[rig]
figures = false
[rig.campaign]
speeds_rpm = { start = 8000.0, stop = 24000.0, num = 8 }
repeats = 6
duration_s = 0.2
trial_unbalance = [0.0, 5e-5, 0.0]
runup = [1000.0, 2000.0, 0.5]
impacts_per_direction = 0
[identification]
n_boot = 20
figures = false
[validation]
n_replications = 4
delta_lim_um = 1.0
speeds_rpm = { start = 1000.0, stop = 24000.0, step = 2000.0 }
ramps = 0
[loop]
discrepancy = "always"
[discrepancy]
n_draws = 100
"""

STUDY = ["surrogate", "design_model", "optimise", "refine", "verify"]
STAGES = ["campaign", "demodulate", "identify", "uncertainty", *STUDY, "measure", "model",
          "discrepancy", "reoptimise", *(f"{s}_updated" for s in STUDY), "measure_updated",
          "model_updated"]


def _write(tmp_path: Path, text: str = TINY) -> Path:
    p = tmp_path / "e2e.toml"
    p.write_text(text)
    return p


def test_the_shipped_config_builds_every_part(tmp_path):
    prep = prepare(ROOT / "experiments" / "end_to_end.toml")
    assert [s.name for s in prep.kind.stages] == STAGES
    p = prep.plan
    # the rig's truth is the study's spindle (the credible one) at its baseline
    assert p.study.problem.spindle.design_map.bounds[0].tolist() == [190.0, 1140.0]
    assert p.rig.rig.truth.geometry == p.study.problem.spindle.geometry_for(
        p.study.problem.baseline)
    assert p.rig.rig.options.trial_unbalance is not None
    assert p.validation.delta_lim_um == p.config.limit.delta_lim_um
    assert p.disk_need[0] == "rig.campaign.repeats"


def test_each_part_draws_from_its_own_seed(tmp_path):
    ctx = StageContext(seed=7, progress=False, label="x", cache_dir=tmp_path, run_dir=tmp_path)
    seeds = {part: kind.part_context(ctx, part).seed for part in kind.PARTS}
    assert len(set(seeds.values())) == len(kind.PARTS)
    again = {part: kind.part_context(ctx, part).seed for part in kind.PARTS}
    assert seeds == again                                   # the same on every resume
    first = {k: kind.part_context(ctx, k).stream(0).random() for k in kind.PARTS}
    assert len(set(first.values())) == len(kind.PARTS)


class _Stop(KeyboardInterrupt):
    pass


def _stop(*args, **kwargs):
    raise _Stop


def test_resume_continues_at_the_first_unfinished_stage(tmp_path, monkeypatch):
    cfg = _write(tmp_path)
    monkeypatch.setattr(loop_steps, "build_theta", _stop)
    with pytest.raises(KeyboardInterrupt):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="r", progress=False)
    path = tmp_path / "res" / "e2e_tiny" / "r"
    assert read_meta(path)["status"] == "interrupted"
    assert sorted(f.name for f in (path / "stages").iterdir()) == [
        "00-campaign.pkl", "01-demodulate.pkl", "02-identify.pkl"]
    written = (path / "identification" / "uncertainty.json").stat().st_mtime_ns
    monkeypatch.undo()
    # finished stages must not run again; stop the second session in the study's optimiser
    monkeypatch.setattr(rig_kind, "run_campaign", _stop)
    monkeypatch.setattr(ident_kind, "read_responses", _stop)
    monkeypatch.setattr(ident_kind, "identify_responses", _stop)
    monkeypatch.setattr(study_kind, "optimise", _stop)
    with pytest.raises(KeyboardInterrupt):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="r", progress=False,
                       resume=True)
    meta = read_meta(path)
    assert meta["status"] == "interrupted" and len(meta["sessions"]) == 2
    assert sorted(meta["stages"]) == sorted(STAGES[:6])
    assert (path / "identification" / "uncertainty.json").stat().st_mtime_ns == written


@pytest.mark.slow
def test_tiny_loop_writes_a_report_whose_sources_exist(tmp_path):
    run = run_experiment(_write(tmp_path), results_dir=tmp_path / "res", run_id="r",
                         progress=False)
    meta = read_meta(run.path)
    assert meta["status"] == "complete" and sorted(meta["stages"]) == sorted(STAGES)
    text = (run.path / "report.md").read_text()
    for head in ("## 1. Rig campaign", "## 2. Identification", "## 3. RBRDO",
                 "## 4. Validation", "## 5. Discrepancy", "## Stage timings"):
        assert head in text
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert figures and all((run.path / f).is_file() for f in figures)
    cited = set(re.findall(r"`([a-z0-9_/]+\.(?:csv|json|toml|md))`", text))
    assert {"study/verification.csv", "validation/table7.csv", "theta.json"} <= cited
    assert all((run.path / c).is_file() for c in cited), [c for c in cited
                                                           if not (run.path / c).is_file()]
    # θ of the study is the identified one: no hidden effect, so near the truth's nominal 1
    theta = json.loads((run.path / "theta.json").read_text())
    assert np.all(np.abs(np.asarray(theta["mean"]) - 1.0) < 0.1)
    assert (run.path / "discrepancy" / "findings.json").is_file()   # loop.discrepancy always


NAMED = (TINY.replace("seed = 1", "seed = 2024")
         .replace("[rig]\nfigures = false", "[rig]\nfigures = false\neffects = [\n"
                  "  { name = \"anisotropy\", s = 0.05 },\n"
                  "  { name = \"tool_interface\", k_t_N_per_m = 3e8, k_r_Nm_per_rad = 5e6 },\n]")
         .replace("speeds_rpm = { start = 8000.0, stop = 24000.0, num = 8 }\nrepeats = 6\n"
                  "duration_s = 0.2", "speeds_rpm = { start = 1000.0, stop = 24000.0, num = 24 }"
                  "\nrepeats = 10")
         .replace("n_draws = 100", "n_draws = 300\nmax_effects = 2\n"
                  "nuisance = { preset = \"probe_chain\" }"))


@pytest.mark.slow
def test_named_effects_are_optimised_again_and_validated_again(tmp_path):
    """The hidden anisotropy and tool interface are named from the campaign; the study has no
    resonance guard here (the separation guard needs a rotationally invariant rotor), so the
    updated spindle is optimised again and its designs measured on the same rig."""
    run = run_experiment(_write(tmp_path, NAMED), results_dir=tmp_path / "res", run_id="r",
                         progress=False)
    findings = json.loads((run.path / "discrepancy" / "findings.json").read_text())
    assert findings["verdict"] == "named"
    named = {e["name"] for e in findings["effects"]}
    assert named <= {"anisotropy", "tool_interface"} and named
    updated = (run.path / "discrepancy" / "spindle_updated.toml").read_text()
    assert all(n in updated for n in named)
    text = (run.path / "report.md").read_text()
    assert "## 6. The updated model" in text
    assert (run.path / "study_updated" / "verification.csv").is_file()
    assert (run.path / "validation_updated" / "table7.csv").is_file()
