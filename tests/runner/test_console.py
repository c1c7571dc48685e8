"""Console and paths (review items 21, 23): no progress bars (ANSI codes) when stderr is not a
terminal, NaN columns left out of the terminal summary, seed-sweep run ids that two sweeps in
one second cannot share, ``[experiment] results_dir`` relative to the config file."""

from __future__ import annotations

import json
import math
import re

from surrogate_rbrdo.runner import cli

from .test_runfolder import SPINDLE


def test_no_progress_codes_when_stderr_is_not_a_terminal(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "exp.toml").write_text(SPINDLE)
    assert cli.main(["run", "exp.toml", "--results", "res"]) == 0     # no --no-progress
    err = capsys.readouterr().err
    assert "\x1b[" not in err and "\r" not in err and err == ""


def test_nan_columns_are_left_out_of_the_summary(tmp_path, capsys):
    rows = [{"design": "baseline", "mean_um_fe": 1.5, "mean_um_surrogate": math.nan}]
    (tmp_path / "summary.json").write_text(json.dumps({"summary": rows}))
    cli._report(tmp_path)
    row = capsys.readouterr().out.splitlines()[1]
    assert row == "  design=baseline, mean_um_fe=1.5"


def test_seed_sweep_run_ids_carry_a_random_part(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "exp.toml").write_text(SPINDLE)
    for _ in range(2):                                   # two sweeps, likely in one second
        assert cli.main(["run", "exp.toml", "--results", "res", "--no-progress",
                         "--seed", "1", "2"]) == 0
    ids = sorted(p.name for p in (tmp_path / "res" / "t").iterdir() if p.name[0] != "_")
    assert len(ids) == 4 and len(set(ids)) == 4
    assert all(re.fullmatch(r"\d{8}T\d{6}Z-[0-9a-f]{6}-seed[12]", i) for i in ids), ids
    capsys.readouterr()


def test_results_dir_is_relative_to_the_config_file(tmp_path, capsys, monkeypatch):
    sub = tmp_path / "configs"
    sub.mkdir()
    (sub / "exp.toml").write_text(SPINDLE.replace('kind = "spindle_report"',
                                                  'kind = "spindle_report"\nresults_dir = "out"'))
    monkeypatch.chdir(tmp_path)
    assert cli.main(["run", "configs/exp.toml", "--no-progress", "--run-id", "x"]) == 0
    assert (sub / "out" / "t" / "x" / "meta.json").is_file()
    assert not (tmp_path / "out").exists() and not (tmp_path / "results").exists()
    capsys.readouterr()
