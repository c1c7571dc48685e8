"""Run folders you can trust: never overwritten, resumable by stage and FE point, marked when
failed or interrupted, never outside the results root, files 0644, reruns byte-identical."""

from __future__ import annotations

import json
import os
import stat

import pytest

from surrogate_rbrdo.runner.cli import main
from surrogate_rbrdo.runner.execute import RunFailed, run_experiment
from surrogate_rbrdo.runner.experiments import study as study_kind
from surrogate_rbrdo.runner.runfolder import AlreadyComplete, RunFolder
from surrogate_rbrdo.spindle.evaluate import PointwisePeak

SPINDLE = """
[experiment]
name = "t"
kind = "spindle_report"
[report]
designs = { a = [3000.0, 300.0, 80.0] }
n_speeds = 20
campbell_speeds = 3
n_modes = 2
"""

STUDY = """
[experiment]
name = "tiny"
kind = "study"
seed = 5
[surrogate]
n_doe = 24
n_jobs = 1
n_start = 1
backend = "sequential"
[design_model]
n_train = 10
n_validate = 2
[deterministic]
resonance = "none"
[optimization]
p_targets = [0.10, 0.01]
n_theta = 40
pop_size = 8
n_gen = 4
n_jobs = 1
[verification]
n_theta = 6
n_jobs = 1
[report]
n_speeds = 20
campbell_speeds = 4
n_modes = 2
"""


def _cfg(tmp_path, text, name="exp.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _meta(run_path):
    return json.loads((run_path / "meta.json").read_text())


def _run(cfg, res, *extra):
    return main(["run", str(cfg), "--results", str(res), "--no-progress", *extra])


def test_a_finished_run_is_never_overwritten(tmp_path, capsys):
    cfg, res = _cfg(tmp_path, SPINDLE), tmp_path / "res"
    assert _run(cfg, res, "--run-id", "a") == 0
    first = (res / "t" / "a" / "summary.csv").stat().st_mtime_ns
    assert _run(cfg, res, "--run-id", "a") == 2
    err = capsys.readouterr().err
    assert "holds a finished run: pass --overwrite to replace it or choose another --run-id" \
        in err and err.count("\n") == 1
    assert (res / "t" / "a" / "summary.csv").stat().st_mtime_ns == first
    assert _run(cfg, res, "--run-id", "a", "--overwrite") == 0
    assert _meta(res / "t" / "a")["status"] == "complete"
    assert len(_meta(res / "t" / "a")["sessions"]) == 1     # a new run, not a continuation
    # --resume of a finished run: nothing to do, not an error
    assert _run(cfg, res, "--run-id", "a", "--resume") == 0
    assert "already complete: nothing to resume" in capsys.readouterr().out
    with pytest.raises(AlreadyComplete):
        run_experiment(cfg, results_dir=res, run_id="a", resume=True, progress=False)


@pytest.mark.parametrize("rid", ["../x", "a/b", "/abs", "..", ".hidden", "a b", "x" * 129, ""])
def test_run_ids_cannot_leave_the_results_root(tmp_path, capsys, rid):
    cfg = _cfg(tmp_path, SPINDLE)
    assert _run(cfg, tmp_path / "res", "--run-id", rid) == 2
    assert f"--run-id = {rid!r} is not allowed" in capsys.readouterr().err
    assert not (tmp_path / "res").exists() and not (tmp_path / "x").exists()


@pytest.mark.parametrize("name", ["../../x", "a/b", "..", "/tmp/x", "~x"])
def test_experiment_names_cannot_leave_the_results_root(tmp_path, capsys, name):
    cfg = _cfg(tmp_path, SPINDLE.replace('name = "t"', f"name = {name!r}"))
    assert _run(cfg, tmp_path / "res") == 2
    assert f"experiment.name = {name!r} is not allowed" in capsys.readouterr().err
    assert not (tmp_path / "res").exists() and not (tmp_path / "x").exists()


def test_files_are_0644_whatever_the_umask(tmp_path):
    old = os.umask(0o077)
    try:
        run = run_experiment(_cfg(tmp_path, SPINDLE), results_dir=tmp_path / "res",
                             run_id="m", progress=False)
    finally:
        os.umask(old)
    files = [p for p in run.path.rglob("*") if p.is_file()]
    assert len(files) >= 8
    for p in files:
        assert stat.S_IMODE(p.stat().st_mode) == 0o644, p.name


def test_failed_run_is_marked_and_can_be_resumed(tmp_path, monkeypatch, capsys):
    cfg, res = _cfg(tmp_path, STUDY), tmp_path / "res"
    real = study_kind.verify

    def broken(*a, **k):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(study_kind, "verify", broken)
    with pytest.raises(RunFailed, match="RuntimeError: disk on fire") as info:
        run_experiment(cfg, results_dir=res, run_id="f", progress=False)
    assert info.value.stage == "verify" and isinstance(info.value.__cause__, RuntimeError)
    run = res / "tiny" / "f"
    meta = _meta(run)
    assert meta["status"] == "failed" and "RuntimeError: disk on fire" in meta["error"]
    assert meta["failed_in"] == "verify" and "disk on fire" in meta["traceback"]
    assert not (run / "summary.json").exists() and not (run / "verification.csv").exists()
    assert set(meta["stages"]) == {"surrogate", "design_model", "optimise", "refine"}
    # a plain rerun is refused, naming --resume
    assert _run(cfg, res, "--run-id", "f") == 2
    assert "holds an unfinished run (status 'failed'): pass --resume" in capsys.readouterr().err
    # --resume runs only the missing stage: the finished ones are loaded, not recomputed
    monkeypatch.setattr(study_kind, "verify", real)
    for name in ("train_surrogate", "fit_design_model", "optimise", "refine"):
        monkeypatch.setattr(study_kind, name, broken)
    run2 = run_experiment(cfg, results_dir=res, run_id="f", progress=False, resume=True)
    meta = _meta(run2.path)
    assert meta["status"] == "complete" and len(meta["sessions"]) == 2
    # the same tables as an uninterrupted run with the same seed
    monkeypatch.undo()
    ref = run_experiment(cfg, results_dir=res, run_id="ref", progress=False)
    for f in sorted(ref.path.glob("*.csv")):
        assert f.read_bytes() == (run2.path / f.name).read_bytes(), f.name


def test_interrupted_run_resumes_from_cached_fe_points(tmp_path, monkeypatch, capsys):
    """Ctrl-C during the surrogate's FE DOE: the run is marked interrupted, the 10 finished
    FE points are cached, and --resume computes only the other 14."""
    cfg, res = _cfg(tmp_path, STUDY), tmp_path / "res"
    real, calls = PointwisePeak.__call__, []

    def flaky(self, z):
        calls.append(1)
        if len(calls) == 11:
            raise KeyboardInterrupt
        return real(self, z)

    monkeypatch.setattr(PointwisePeak, "__call__", flaky)
    assert _run(cfg, res, "--run-id", "i") == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("rbrdo: interrupted (Ctrl-C)")
    assert "--resume --run-id i" in err
    meta = _meta(res / "tiny" / "i")
    assert meta["status"] == "interrupted" and meta["signal"] == "SIGINT"
    assert "stages" not in meta and not (res / "tiny" / "i" / "summary.json").exists()
    monkeypatch.setattr(PointwisePeak, "__call__", real)
    assert _run(cfg, res, "--run-id", "i", "--resume") == 0
    meta = _meta(res / "tiny" / "i")
    assert meta["status"] == "complete"
    assert meta["fe_calls"]["doe"] == 24 - 10 and meta["fe_cache_hits"]["doe"] == 10


def test_resume_refuses_a_changed_config_and_needs_a_run_id(tmp_path, capsys):
    cfg, res = _cfg(tmp_path, STUDY), tmp_path / "res"
    rf = RunFolder.open(res, "tiny", "c")
    rf.write_json("config.json", {"experiment": {"name": "tiny"}})
    rf.start(kind="study", seeds={"seed": 5})
    rf.stop("interrupted", signal="SIGTERM")
    assert _run(cfg, res, "--run-id", "c", "--resume") == 2
    assert "--resume: the config differs from the one" in capsys.readouterr().err
    assert _run(cfg, res, "--resume") == 2
    assert "--resume is not allowed without --run-id" in capsys.readouterr().err
    assert _run(cfg, res, "--run-id", "nope", "--resume") == 2
    assert "there is no run folder" in capsys.readouterr().err


def test_a_folder_that_is_not_a_run_is_never_touched(tmp_path, capsys):
    cfg, res = _cfg(tmp_path, SPINDLE), tmp_path / "res"
    (res / "t" / "mine").mkdir(parents=True)
    (res / "t" / "mine" / "notes.txt").write_text("keep")
    for extra in ([], ["--overwrite"], ["--resume"]):
        assert _run(cfg, res, "--run-id", "mine", *extra) == 2
        assert "is not a run folder" in capsys.readouterr().err
    assert (res / "t" / "mine" / "notes.txt").read_text() == "keep"


def test_same_seed_gives_byte_identical_tables(tmp_path):
    cfg, res = _cfg(tmp_path, STUDY), tmp_path / "res"
    a = run_experiment(cfg, results_dir=res, run_id="a", progress=False)
    b = run_experiment(cfg, results_dir=res, run_id="b", progress=False)
    tables = sorted(a.path.glob("*.csv"))
    assert {t.name for t in tables} >= {"compromises.csv", "verification.csv",
                                        "pareto_fronts.csv"}
    for t in tables:
        assert t.read_bytes() == (b.path / t.name).read_bytes(), t.name
    assert "wall_time_s" not in (a.path / "compromises.csv").read_text()
    assert _meta(a.path)["optimizer_wall_time_s"]          # the timings went to meta.json
