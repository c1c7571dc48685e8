"""The ``validation`` experiment kind end to end on a small campaign: designs given in the
config or taken from a study run folder, and its resume."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.core.files import json_default
from surrogate_rbrdo.runner.cli import run_experiment
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.runner.experiments import validation as kind
from surrogate_rbrdo.runner.runfolder import read_meta
from surrogate_rbrdo.validation import measure_designs, reference_family

from .test_study import TINY

# five replications of designs ~70x apart: some bootstrap resamples are degenerate (scipy warns
# and the interval is NaN, which the tables show as such)
pytestmark = pytest.mark.filterwarnings("ignore:The BCa confidence interval cannot be")

SMALL = """
[experiment]
name = "val_small"
kind = "validation"
seed = 4

[validation]
n_replications = 5
speeds_rpm = { start = 1000.0, stop = 24000.0, step = 4000.0 }
ramps = 0
n_boot = 500
band_samples = 5
peak = { n_grid = 16, n_refine = 7 }

[designs]
baseline = [2000.0, 500.0, 65.0]
short = [3000.0, 350.0, 75.0]

[model]
n_samples = 20
"""

STUDY_TOML = """
[experiment]
name = "tiny"
kind = "study"
[limit]
delta_lim_um = 19.5
"""


def _write(tmp_path: Path, text: str, name: str = "validation.toml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def test_given_designs_end_to_end(tmp_path):
    cfg = _write(tmp_path, SMALL)
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="r1", progress=False)
    files = {p.name for p in run.path.iterdir()}
    for f in ("table7.csv", "measured.csv", "model_vs_measured.csv", "replications.csv",
              "curves.csv", "phasors_baseline.csv", "phasors_short.csv", "validation.json",
              "validation.md", "fig7_campbell.png", "fig8_response.png", "paired_peak.png",
              "model_vs_measured.png", "summary.json", "designs_source.json"):
        assert f in files, f
    assert read_meta(run.path)["status"] == "complete"
    table7 = list(csv.DictReader((run.path / "table7.csv").open()))
    assert {r["design"] for r in table7} == {"short"}
    # the kind composes the library: the same seed stream gives the same measurements
    plan = prepare(cfg).plan
    direct = measure_designs(reference_family(), plan.designs, options=plan.options,
                             rng=np.random.default_rng(np.random.SeedSequence(4, spawn_key=(0,))))
    rows = list(csv.DictReader((run.path / "replications.csv").open()))
    for d in direct.designs:
        got = [float(r["peak_um"]) for r in rows if r["design"] == d.name]
        np.testing.assert_allclose(got, d.peak * 1e6, rtol=1e-12)
    summary = json.loads((run.path / "summary.json").read_text())
    assert [r.get("design") for r in summary["summary"][:2]] == ["baseline", "short"]


class _Stop(KeyboardInterrupt):
    pass


def test_resume_loads_the_measurement(tmp_path, monkeypatch):
    cfg = _write(tmp_path, SMALL)

    def stop(*args, **kwargs):
        raise _Stop()

    monkeypatch.setattr(kind, "add_model", stop)
    with pytest.raises(KeyboardInterrupt):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="r1", progress=False)
    path = tmp_path / "res" / "val_small" / "r1"
    assert read_meta(path)["status"] == "interrupted"
    assert read_meta(path)["stages"] == {"measure": read_meta(path)["stages"]["measure"]}
    monkeypatch.undo()
    monkeypatch.setattr(kind, "measure_designs", stop)     # must not run again
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="r1", progress=False,
                         resume=True)
    assert read_meta(run.path)["status"] == "complete"
    assert (run.path / "model_vs_measured.csv").is_file()


def _study_folder(tmp_path: Path) -> Path:
    """A finished study run folder as the ``study`` kind writes it (config.json, meta.json,
    verification.csv with its FE columns)."""
    folder = tmp_path / "study_run"
    folder.mkdir()
    resolved = prepare(_write(tmp_path, STUDY_TOML, "study.toml")).resolved()
    (folder / "config.json").write_text(json.dumps(resolved, default=json_default))
    (folder / "meta.json").write_text(json.dumps({"kind": "study", "status": "complete"}))
    head = ["design", "preload_N", "span_mm", "diameter_mm", "mean_um_fe", "std_um_fe",
            "pf_pct_fe", "pf_ci_low_pct_fe", "pf_ci_high_pct_fe", "max_abs_err_um",
            "n_theta_fe", "pf_pct_fe_is"]
    rows = [["baseline", 2000.0, 465.8, 65.0, 21.0, 9.5, 50.0, 40.0, 60.0, 1.0, 100, ""],
            ["rbrdo 10%", 2971.8, 393.96, 72.18, 0.84, 0.05, 0.0, 0.0, 3.6, 0.1, 100, ""],
            ["rdo 5%", 2022.9, 300.4, 76.6, 1.16, 0.07, 0.0, 0.0, 3.6, 0.1, 100, ""]]
    with open(folder / "verification.csv", "w", newline="") as fh:
        csv.writer(fh).writerows([head, *rows])
    return folder


def test_designs_from_a_study_run_folder(tmp_path):
    folder = _study_folder(tmp_path)
    text = SMALL.split("[designs]")[0] + (f'[designs]\nfrom = "{folder}"\n'
                                          'names = ["baseline", "rbrdo 10%"]\n')
    prep = prepare(_write(tmp_path, text))
    assert prep.plan.designs == {"baseline": (2000.0, 465.8, 65.0),
                                 "rbrdo_10pct": (2971.8, 393.96, 72.18)}
    known = prep.plan.model.known
    assert set(known) == {"baseline", "rbrdo_10pct"} and set(known["baseline"]) == {"peak"}
    m = known["baseline"]["peak"]
    assert (m.n, m.pf, m.pf_ci) == (100, 0.5, (0.4, 0.6))
    assert (m.mean, m.std) == pytest.approx((21e-6, 9.5e-6), rel=1e-12)
    assert m.mean_se == pytest.approx(9.5e-6 / 10)
    assert prep.plan.source["study_labels"] == {"baseline": "baseline",
                                                "rbrdo 10%": "rbrdo_10pct"}
    # all its designs by default
    every = prepare(_write(tmp_path, text.replace('names = ["baseline", "rbrdo 10%"]\n', "")))
    assert list(every.plan.designs) == ["baseline", "rbrdo_10pct", "rdo_5pct"]


@pytest.mark.parametrize(("edit", "match"), [
    (lambda t: t.replace('"rbrdo 10%"]', '"rbrdo 5%"]'),
     r"designs.names: 'rbrdo 5%' is not in '.*verification.csv'; its designs: \['baseline'"),
    (lambda t: t.replace("ramps = 0", "ramps = 0\ndelta_lim_um = 30.0"),
     r"validation.delta_lim_um = 30.0 is not allowed: the study '.*' has limit.delta_lim_um "
     r"= 19.5"),
    (lambda t: t.replace("names = [", "names = 3 #"),
     r"designs.names = 3 is not allowed: must be an array of strings"),
])
def test_study_folder_errors(tmp_path, edit, match):
    folder = _study_folder(tmp_path)
    text = SMALL.split("[designs]")[0] + (f'[designs]\nfrom = "{folder}"\n'
                                          'names = ["baseline", "rbrdo 10%"]\n')
    text = edit(text)
    with pytest.raises(ValueError, match=match):
        prepare(_write(tmp_path, text))


def test_unfinished_study_folder_is_refused(tmp_path):
    folder = _study_folder(tmp_path)
    (folder / "meta.json").write_text(json.dumps({"kind": "study", "status": "interrupted"}))
    text = SMALL.split("[designs]")[0] + f'[designs]\nfrom = "{folder}"\n'
    with pytest.raises(ValueError, match=r"not a finished study run folder \(meta.json: kind "
                                         r"'study', status 'interrupted'"):
        prepare(_write(tmp_path, text))


@pytest.mark.slow
def test_validation_of_a_real_study_run(tmp_path):
    """The study kind's own run folder (not a hand-made one) feeds the validation kind."""
    study = run_experiment(_write(tmp_path, TINY, "study.toml"), results_dir=tmp_path / "res",
                           run_id="s1", progress=False)
    text = SMALL.split("[designs]")[0] + (f'[designs]\nfrom = "{study.path}"\n'
                                          'names = ["baseline", "rbrdo 10%"]\n'
                                          "[model]\nn_samples = 20\n")
    run = run_experiment(_write(tmp_path, text), results_dir=tmp_path / "res", run_id="v1",
                         progress=False)
    ver = {r["design"]: r for r in csv.DictReader((study.path / "verification.csv").open())}
    rows = [r for r in csv.DictReader((run.path / "model_vs_measured.csv").open())
            if r["quantity"] == "peak" and r["metric"] == "mean"]
    assert [r["design"] for r in rows] == ["baseline", "rbrdo_10pct"]
    for r, name in zip(rows, ("baseline", "rbrdo 10%"), strict=True):
        assert float(r["model"]) == pytest.approx(float(ver[name]["mean_um_fe"]), rel=1e-12)
