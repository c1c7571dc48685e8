"""The discrepancy figures: drawn on worker processes, the same files as in this one."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from surrogate_rbrdo.discrepancy.summary import BlockCurves
from surrogate_rbrdo.reporting.plots_discrepancy import plot_all


def _block(name: str, n: int, rng: np.random.Generator) -> BlockCurves:
    coord = np.linspace(1000.0, 24000.0, n)
    data = (rng.normal(size=(n, 2)) + 1j * rng.normal(size=(n, 2))) * 1e-6
    return BlockCurves(name, coord, "speed (rpm)", ("front_x", "tool_x"), data,
                       np.full((n, 2), 1e-8), data * 1.1, data * 1.01,
                       rng.normal(size=(n, 2, 2)) * 10, rng.normal(size=(n, 2, 2)),
                       np.arange(n) % 5 == 0)


def test_figures_on_two_workers_are_those_of_one_process(tmp_path):
    """``n_jobs = 2`` draws the residual map and the gap figures on loky workers, largest
    first: every PNG is byte for byte the serial one, and the paths come back in the serial
    order (residual map, candidates, one gap figure per block in the blocks' order)."""
    rng = np.random.default_rng(7)
    curves = (_block("small", 6, rng), _block("large", 30, rng))
    stage = SimpleNamespace(assessments=(
        SimpleNamespace(name="housing", delta_chi2=1e4, passed=True),
        SimpleNamespace(name="anisotropy", delta_chi2=3.0, passed=False)))
    result = SimpleNamespace(verdict="named", curves=curves, stages=(stage,))
    made = {}
    for jobs in (1, 2):
        out = tmp_path / f"j{jobs}"
        out.mkdir()
        made[jobs] = plot_all(result, out, n_jobs=jobs)
    assert list(made[2]) == ["residual_map", "candidates", "gap_small", "gap_large"]
    assert list(made[1]) == list(made[2])
    for key, path in made[1].items():
        assert path.read_bytes() == made[2][key].read_bytes(), key
