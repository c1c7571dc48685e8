"""FE calls and FE-cache hits per stage, counted where they happen (review items 6 and 7):
the counts in ``meta.json`` equal the FE evaluations an independent wrapper of the FE model
sees, and a rerun in the same results root reports the verification's FE values as cache
hits (not as nothing)."""

from __future__ import annotations

import json

import numpy as np

from surrogate_rbrdo.runner.cli import main
from surrogate_rbrdo.study.problem import Problem

from .test_runfolder import STUDY as BASE

#: the tiny study at its cheapest: one RBRDO run, no design model, two generations
STUDY = (BASE.replace("p_targets = [0.10, 0.01]", "p_targets = [0.10]\nstrategies = []")
         .replace('resonance = "none"', 'resonance = "none"\nstress = false')
         .replace("n_gen = 4", "n_gen = 2"))

#: FE evaluations seen by :class:`WrappedFE` (one entry per (x, θ) point)
SEEN: list[int] = []


class WrappedFE:
    """The FE response, counting the (x, θ) points it evaluates (picklable: the FE cache
    hashes it)."""

    def __init__(self, inner):
        self.inner = inner

    def __call__(self, x, theta):
        y = self.inner(x, theta)
        SEEN.append(int(np.asarray(y).size))
        return y


def test_verification_fe_calls_and_cache_hits_are_counted(tmp_path, monkeypatch, capsys):
    real = Problem.fe_response
    monkeypatch.setattr(Problem, "fe_response",
                        lambda self, method="direct": WrappedFE(real(self, method)))
    cfg = tmp_path / "exp.toml"
    assert STUDY.count("strategies = []") == STUDY.count("stress = false") == 1
    cfg.write_text(STUDY)
    res = tmp_path / "res"
    SEEN.clear()
    assert main(["run", str(cfg), "--results", str(res), "--no-progress", "--run-id", "a"]) == 0
    first = json.loads((res / "tiny" / "a" / "meta.json").read_text())
    rows = (res / "tiny" / "a" / "verification.csv").read_text().splitlines()[1:]
    # known answer: every chosen design on the n_theta = 6 fresh θ, counted by the wrapper
    assert sum(SEEN) == first["fe_calls"]["verification"] == 6 * len(rows) > 0
    assert first["fe_cache_hits"]["verification"] == 0
    SEEN.clear()
    assert main(["run", str(cfg), "--results", str(res), "--no-progress", "--run-id", "b"]) == 0
    second = json.loads((res / "tiny" / "b" / "meta.json").read_text())
    assert sum(SEEN) == 0 == second["fe_calls"]["verification"]
    assert second["fe_cache_hits"]["verification"] == first["fe_calls"]["verification"]
    assert second["fe_cache_hits"]["doe"] == first["fe_calls"]["doe"] == 24
    assert second["fe_cache_hits"]["total"] == sum(
        v for k, v in second["fe_cache_hits"].items() if k != "total")
    capsys.readouterr()
