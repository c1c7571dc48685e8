"""The ``identification`` experiment kind end to end on a small rig campaign (with trial-weight
runs), the files it writes, that it composes the library, and its resume."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.identification import IdentificationOptions, identify_records
from surrogate_rbrdo.runner.cli import run_experiment
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

    monkeypatch.setattr(kind, "table_rows", stop)        # interrupted in the report
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
