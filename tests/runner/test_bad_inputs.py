"""Every bad input of the corpus (``bad_inputs.py``): exit code 2, one line on stderr that
names the field or file (dotted path), the bad value and what is allowed, and no run folder."""

from __future__ import annotations

import re

import pytest

from surrogate_rbrdo.runner.cli import main

from .bad_inputs import CORPUS


def test_the_corpus_is_large_and_names_are_unique():
    assert len(CORPUS) >= 100
    assert len({c[0] for c in CORPUS}) == len(CORPUS)


@pytest.mark.parametrize(("name", "text", "files", "args", "pattern"), CORPUS,
                         ids=[c[0] for c in CORPUS])
def test_bad_input_gives_one_line_and_no_folder(tmp_path, capsys, monkeypatch, name, text,
                                                files, args, pattern):
    monkeypatch.chdir(tmp_path)
    for fname, content in files.items():
        (tmp_path / fname).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / fname).write_text(content)
    cfg = tmp_path / "exp.toml"
    cfg.write_text(text) if "\x00" not in text else cfg.write_bytes(text.encode())
    code = main(["run", str(cfg), "--results", str(tmp_path / "res"), "--no-progress", *args])
    out = capsys.readouterr()
    err = out.err
    assert code == 2, (out.out, err)
    assert err.startswith("rbrdo: error: ") and err.count("\n") == 1, err
    assert re.search(pattern, err), err
    assert not (tmp_path / "res").exists()
    assert not (tmp_path / "results").exists()
