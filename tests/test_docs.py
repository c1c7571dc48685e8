"""The code in docs/api.md and docs/runner.md runs (each block's own asserts check its
numbers against the full FE model or an invariant), and the errors runner.md quotes are the
ones the runner gives."""

from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

import pytest

from surrogate_rbrdo.runner.cli import main
from surrogate_rbrdo.runner.kinds import KINDS, discover

DOCS = Path(__file__).resolve().parents[1] / "docs"


def _blocks(name: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", (DOCS / name).read_text(), re.S)


@pytest.mark.parametrize("i", range(4), ids=["a_spindle", "b_surrogate", "c_rbrdo",
                                             "d_credible"])
def test_api_scripts_run(i, capsys):
    blocks = _blocks("api.md")
    assert len(blocks) == 4 and all(len(b.strip().splitlines()) <= 22 for b in blocks)
    exec(compile(blocks[i], f"docs/api.md[{i}]", "exec", dont_inherit=True), {})
    assert capsys.readouterr().out.strip()


@pytest.fixture
def registry_snapshot():
    saved = dict(discover()._items)     # the built-in kinds, registered first
    yield
    KINDS._items.clear()
    KINDS._items.update(saved)
    sys.modules.pop("peak_map_doc", None)


def test_the_worked_kind_runs_and_is_checked(tmp_path, monkeypatch, capsys, registry_snapshot):
    monkeypatch.chdir(tmp_path)
    kind_code, run_code = _blocks("runner.md")
    # the kind as a module, as in runner/experiments/ (its results are pickled by name)
    (tmp_path / "peak_map_doc.py").write_text(kind_code)
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.import_module("peak_map_doc")
    assert "peak_map" in set(KINDS)
    exec(compile(run_code, "docs/runner.md[run]", "exec", dont_inherit=True), {})
    rows = (tmp_path / "results" / "peaks" / "r1" / "peaks.csv").read_text().splitlines()
    assert rows[0] == "design,peak_um,speed_rpm" and len(rows) == 3
    assert main(["kinds"]) == 0
    assert "peak_map\n  nominal peak tool-tip amplitude" in capsys.readouterr().out
    text = (DOCS / "runner.md").read_text()
    for bad, msg in (
            ("designs = { a = [2000.0, 500.0] }", "peak_map.designs.a = [2000.0, 500.0] is not "
             "allowed: must be an array of 3 numbers, e.g. [1.0, 2.0, 3.0]"),
            ("design = { a = [2000.0, 500.0, 65.0] }",
             "unknown key peak_map.design; allowed: ['designs']")):
        cfg = tmp_path / "bad.toml"
        cfg.write_text(f"[experiment]\nname = 'p'\nkind = 'peak_map'\n[peak_map]\n{bad}\n")
        assert main(["run", str(cfg), "--results", str(tmp_path / "r"), "--no-progress"]) == 2
        err = capsys.readouterr().err.strip()
        assert err == f"rbrdo: error: {msg}", err
        assert " ".join(msg.split()) in " ".join(text.split())
