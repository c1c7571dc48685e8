"""The rbrdo command line and run folders: bad input gives one line naming the field."""

from __future__ import annotations

import csv
import json

import pytest

from surrogate_rbrdo.runner.cli import main
from surrogate_rbrdo.runner.runfolder import RunFolder, atomic_write_text


def write(tmp_path, text, name="exp.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


SPINDLE_CFG = """
[experiment]
name = "t"
kind = "spindle_report"
[report]
designs = { a = [3000.0, 300.0, 80.0] }
n_speeds = 20
campbell_speeds = 3
n_modes = 2
"""


def test_spindle_report_runs_and_writes_a_run_folder(tmp_path, capsys):
    cfg = write(tmp_path, SPINDLE_CFG)
    assert main(["run", str(cfg), "--results", str(tmp_path / "res"), "--no-progress"]) == 0
    (run,) = (tmp_path / "res" / "t").iterdir()
    for f in ("summary.csv", "campbell.png", "unbalance_response.png", "meta.json",
              "config.json", "unbalance_response.csv"):
        assert (run / f).is_file(), f
    meta = json.loads((run / "meta.json").read_text())
    assert meta["packages"]["numpy"] and "timings_s" in meta
    rows = list(csv.DictReader((run / "summary.csv").open()))
    assert rows[0]["design"] == "a" and float(rows[0]["preload_N"]) == 3000.0
    # a second run goes into another folder
    assert main(["run", str(cfg), "--results", str(tmp_path / "res"), "--no-progress"]) == 0
    assert len(list((tmp_path / "res" / "t").iterdir())) == 2


HEAD = "[experiment]\nname='t'\nkind='spindle_report'\n"
BAD_CONFIGS = [
    ("[experiment]\nname='t'\nkind='nope'\n",
     r"experiment.kind = 'nope' is not allowed: unknown experiment kind; known: "
     r".*spindle_report"),
    (HEAD + "colour=1\n", r"unknown key experiment.colour; allowed: \['description', 'kind'"),
    (HEAD + "[report]\nn_speeds=1\n", r"report.n_speeds = 1 is not allowed"),
    (HEAD + "[report]\ndesigns={a=[9000.0, 300.0, 60.0]}\n",
     r"preload_N = 9000.0 is not allowed: must lie in \[1000.0, 3000.0\]"),
    (HEAD + "[spindle]\nbalance_grade_mm_s=-1\n", r"spindle.balance_grade_mm_s = -1"),
    (HEAD + "[spindle]\neffects=[{name='warp', a=1}]\n",
     r"unknown effect 'warp'; known: .*speed_softening"),
    (HEAD + "[spindle]\ndesign_map={lower=[1000.0, 300.0, 25.0]}\n",
     r"spindle.design_map.lower\[2\] = 25.0 is not allowed: the span diameter must exceed the "
     r"bore"),
    (HEAD + "[spindle]\ntheta_bearings=['front', 'front']\n",
     r"theta_bearings = \['front', 'front'\] is not allowed.*appears twice"),
    (HEAD + "[spindle]\ntheta_bearings=['nose']\n",
     r"spindle.theta_bearings = \['nose'\] is not allowed: 'nose' is not a bearing"),
    ("[experiment]\nname='t'\n", r"experiment.kind is missing: it is required"),
    ("[experiment\n", r"not valid TOML"),
]


@pytest.mark.parametrize(("text", "pattern"), BAD_CONFIGS)
def test_bad_config_gives_one_line_naming_the_field(tmp_path, capsys, text, pattern):
    cfg = write(tmp_path, text)
    assert main(["run", str(cfg), "--results", str(tmp_path / "res"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rbrdo: error: ") and "\n" not in err
    assert __import__("re").search(pattern, err), err


def test_seed_option_replaces_the_config_seed(tmp_path, capsys):
    cfg = write(tmp_path, SPINDLE_CFG.replace('kind = "spindle_report"',
                                              'kind = "spindle_report"\nseed = 3'))
    res = tmp_path / "res"
    assert main(["run", str(cfg), "--results", str(res), "--run-id", "a", "--no-progress",
                 "--seed", "17"]) == 0
    run = res / "t" / "a"
    assert json.loads((run / "meta.json").read_text())["seeds"] == {"seed": 17}
    assert json.loads((run / "config.json").read_text())["experiment"]["seed"] == 17
    assert "seed = 3" in (run / "config.toml").read_text()       # the file as given
    assert main(["run", str(cfg), "--results", str(res), "--no-progress", "--seed", "-1"]) == 2
    assert "rbrdo: error: --seed = -1 is not allowed" in capsys.readouterr().err
    # a sweep: one run folder per seed
    assert main(["run", str(cfg), "--results", str(res), "--run-id", "sw", "--no-progress",
                 "--seed", "5", "6"]) == 0
    for s in (5, 6):
        meta = json.loads((res / "t" / f"sw-seed{s}" / "meta.json").read_text())
        assert meta["seeds"] == {"seed": s}
    assert main(["run", str(cfg), "--results", str(res), "--no-progress", "--seed", "5",
                 "5"]) == 2
    assert "--seed 5 5 is not allowed: a seed appears twice" in capsys.readouterr().err


def test_missing_config_file(tmp_path, capsys):
    assert main(["run", str(tmp_path / "none.toml")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_help_exits_cleanly(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0
    assert "run" in capsys.readouterr().out


def test_atomic_write_leaves_no_temporary_files(tmp_path):
    atomic_write_text(tmp_path / "a.txt", "x")
    atomic_write_text(tmp_path / "a.txt", "y")
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]
    assert (tmp_path / "a.txt").read_text() == "y"


def test_run_ids_never_collide(tmp_path):
    a = RunFolder.open(tmp_path, "e")
    b = RunFolder.open(tmp_path, "e")
    assert a.path != b.path


def test_version_and_kinds_describe_each_kind(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.startswith("rbrdo 0.")
    assert main(["kinds"]) == 0
    out = capsys.readouterr().out
    for kind in ("study", "surrogate_validation", "spindle_report"):
        block = out.split(f"{kind}\n", 1)[1].split("\n\n")[0]
        assert "tables: [experiment]" in block and "stages:" in block
    assert "stages: surrogate → design_model → optimise → refine → verify → report" in out


def test_a_truncated_terminal_table_says_so(tmp_path, capsys):
    designs = ", ".join(f"d{i} = [2000.0, {300.0 + 20 * i}, 65.0]" for i in range(14))
    cfg = write(tmp_path, SPINDLE_CFG.replace("designs = { a = [3000.0, 300.0, 80.0] }",
                                              f"designs = {{ {designs} }}")
                .replace("campbell_speeds = 3", "campbell_speeds = 3\nn_campbell = 1"))
    assert main(["run", str(cfg), "--results", str(tmp_path / "res"), "--no-progress"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len([line for line in out if line.startswith("  design=")]) == 12
    assert out[-1].startswith("  ... first 12 of 14 rows shown; all in ")
