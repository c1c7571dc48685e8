"""The reviewer's bad inputs of issue 12 (``review_cases.py``): each gives exit code 2 and one
line ``rbrdo: error: ...`` naming the field or file and the bad value (``PATTERNS``) and
saying what is allowed, and leaves no folder — none in the results root, none beside it (the
label and variant-name escapes of the review wrote ``res/escaped_label.csv``)."""

from __future__ import annotations

import re

import pytest

from surrogate_rbrdo.runner.cli import main

from .review_cases import CASES, PATTERNS

#: what every message has besides the path and the value: what is allowed, or why
ALLOWED = re.compile(r"(is|are) not allowed: \S|; allowed: \[|does not exist"
                     r"|is not valid (TOML|JSON)|is a directory: must be a file"
                     r"|is missing: it is required|missing "
                     r"\[experiment\] table|see rbrdo( run)? --help")

CHECKED = [c for c in CASES if c[0] in PATTERNS]


def test_every_pattern_has_its_case():
    assert len(CHECKED) == len(PATTERNS) >= 150
    assert len({c[0] for c in CHECKED}) == len(CHECKED)


@pytest.mark.parametrize(("name", "text", "files", "args", "pre"), CHECKED,
                         ids=[c[0] for c in CHECKED])
def test_review_case_gives_one_line_and_no_folder(tmp_path, capsys, monkeypatch, name, text,
                                                  files, args, pre):
    d = tmp_path / "case"
    d.mkdir()
    monkeypatch.chdir(d)
    for fname, content in files.items():
        p = d / fname
        p.write_bytes(content) if isinstance(content, bytes) else p.write_text(content)
    (d / "exp.toml").write_text(text)
    if pre is not None:
        pre(d)
    before = sorted(p.name for p in tmp_path.iterdir())
    try:
        code = main(["run", "exp.toml", "--results", "res", "--no-progress", *args])
    except SystemExit as exc:           # argparse errors
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("rbrdo: error: ") and err.count("\n") == 1, err
    assert re.search(PATTERNS[name], err), err
    assert ALLOWED.search(err), err
    assert not (d / "res").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == before
