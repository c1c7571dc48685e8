"""The ``rig`` experiment kind end to end on a small campaign, and its resume."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.rig import store
from surrogate_rbrdo.rig.campaign import run_campaign
from surrogate_rbrdo.rig.config import RigTable
from surrogate_rbrdo.runner.cli import run_experiment
from surrogate_rbrdo.runner.execute import prepare
from surrogate_rbrdo.runner.runfolder import read_meta

SMALL = """
[experiment]
name = "rig_small"
kind = "rig"
seed = 3

[rig]
effects = [{ name = "anisotropy", s = 0.05 }]

[rig.campaign]
speeds_rpm = { start = 6000.0, stop = 18000.0, num = 3 }
repeats = 2
duration_s = 0.2
runup = [1000.0, 24000.0, 2.0]
impacts_per_direction = 1
impact_duration_s = 0.5
"""

STEADY_ONLY = """
[experiment]
name = "rig_steady"
kind = "rig"
seed = 7

[rig]
figures = false

[rig.campaign]
speeds_rpm = [5000.0, 10000.0, 15000.0]
repeats = 3
duration_s = 0.1
runup = []
impacts_per_direction = 0
"""


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "rig.toml"
    p.write_text(text)
    return p


def test_small_campaign_writes_dataset_figures_and_summary(tmp_path):
    cfg = _write(tmp_path, SMALL)
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="r1", progress=False)
    meta = read_meta(run.path)
    assert meta["status"] == "complete" and meta["n_records"] == 3 * 2 + 2 + 2
    ds = store.open_dataset(run.path / "campaign" / "dataset")
    assert len(ds.select(kind="steady")) == 6 and len(ds.select(kind="impact")) == 2
    assert {r["kind"] for r in ds.index} == {"steady", "runup", "rundown", "impact"}
    figs = sorted(p.name for p in (run.path / "figures").iterdir())
    assert figs == ["bode.png", "campbell_runup.png", "frf_tool_x.png", "orbit.png",
                    "polar.png", "waterfall_runup.png"]
    summary = json.loads((run.path / "summary.json").read_text())
    assert summary["summary"][0] == {"quantity": "records", "value": 10}
    rig = json.loads((run.path / "rig_summary.json").read_text())
    assert rig["model_critical_speeds_rpm"] and rig["impact_modes_hz"]


class _Stop(KeyboardInterrupt):
    pass


def test_resume_continues_at_the_first_record_not_written(tmp_path, monkeypatch):
    cfg = _write(tmp_path, STEADY_ONLY.replace("runup = []\n", "runup = [1000.0, 2000.0, 0.3]\n"
                                               "rundown = false\n"))
    real_write = store.DatasetWriter.write
    written: list[str] = []

    def write_then_stop(self, record, labels=None):
        if len(written) == 5:
            raise _Stop()
        real_write(self, record, labels)
        written.append(record.id)

    monkeypatch.setattr(store.DatasetWriter, "write", write_then_stop)
    with pytest.raises(KeyboardInterrupt):
        run_experiment(cfg, results_dir=tmp_path / "res", run_id="r1", progress=False)
    path = tmp_path / "res" / "rig_steady" / "r1"
    assert read_meta(path)["status"] == "interrupted"
    records = path / "campaign" / "dataset" / "records"
    before = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in records.iterdir()}
    assert len(before) == 5

    first = list(written)
    written.clear()
    monkeypatch.setattr(store.DatasetWriter, "write", lambda self, record, labels=None: (
        real_write(self, record, labels), written.append(record.id)))
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="r1", progress=False,
                         resume=True)
    assert read_meta(run.path)["status"] == "complete"
    assert len(written) == 3 * 3 + 1 - 5 and not set(written) & set(first)
    for name, (mtime, data) in before.items():     # finished records are not rewritten
        p = records / name
        assert p.stat().st_mtime_ns == mtime and p.read_bytes() == data
    # and the resumed dataset is the one an uninterrupted run writes
    monkeypatch.setattr(store.DatasetWriter, "write", real_write)
    full = run_experiment(cfg, results_dir=tmp_path / "res", run_id="r2", progress=False)
    assert (full.path / "campaign" / "phasors.csv").read_bytes() == \
        (run.path / "campaign" / "phasors.csv").read_bytes()


def test_no_ramp_no_figures_and_the_kind_composes_the_library(tmp_path):
    cfg = _write(tmp_path, STEADY_ONLY)
    run = run_experiment(cfg, results_dir=tmp_path / "res", run_id="r1", progress=False)
    assert not (run.path / "figures").exists()
    assert read_meta(run.path)["n_records"] == 9
    # the same seed stream through the library gives the same records
    plan = prepare(cfg).plan
    direct = run_campaign(plan.rig.truth, plan.rig.options, tmp_path / "direct",
                          rng=np.random.default_rng(np.random.SeedSequence(7, spawn_key=(0,))))
    assert direct.n_records == 9
    assert (tmp_path / "direct" / "phasors.csv").read_bytes() == \
        (run.path / "campaign" / "phasors.csv").read_bytes()


def test_rig_table_defaults_are_the_papers_campaign():
    cfg = parse(RigTable, {}, "rig").config()
    o = cfg.options
    assert len(o.speeds_rpm) == 50 and o.repeats == 20 and o.duration_s == 1.0
    assert o.speeds_rpm[0] == 1000.0 and o.speeds_rpm[-1] == 24000.0
    assert np.allclose(np.diff(o.speeds_rpm), 23000.0 / 49)
    assert o.runup == (1000.0, 24000.0, 10.0) and o.rundown and o.impacts_per_direction == 5
    assert o.sensors.daq.sample_rate_hz == 10_000.0 and not cfg.truth.hidden
