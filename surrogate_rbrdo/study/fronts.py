"""FE verification of the Pareto fronts themselves, not only of the chosen designs.

Whether a problem has a μ–σ trade-off is a claim about its front: a front of many designs in
the optimiser's archive may collapse to one design once the sampling noise of the common θ
sample is gone. :func:`verify_fronts` takes up to ``n_designs`` designs of each RBRDO/RDO
run's feasible archive front (evenly spaced along it by μ rank, both ends included),
evaluates them with the FE model on one fresh θ sample (the same for every run, so the
designs compare under common random numbers) and marks which stay non-dominated in
``(μ_FE, σ_FE)``. A trade-off is confirmed by many FE-non-dominated, distinct designs; one or
two say there is none to trade.

>>> spread_indices(10, 4).tolist(), spread_indices(3, 5).tolist()
([0, 3, 6, 9], [0, 1, 2])
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.optimization import archive_front
from surrogate_rbrdo.optimization.pareto import nondominated
from surrogate_rbrdo.sampling.fe import sample_designs


def spread_indices(n: int, k: int) -> np.ndarray:
    """``min(n, k)`` indices of ``range(n)`` evenly spread, both ends included."""
    check_int("k", k, minimum=1)
    if n <= k:
        return np.arange(n)
    return np.unique(np.round(np.linspace(0, n - 1, k)).astype(int))


@dataclass(frozen=True, eq=False)
class FrontCheck:
    """Front designs of each run with their CRN and FE moments.

    ``runs[i]`` labels ``X[i]`` (rows), ``front_size`` the archive front's size per run,
    ``crn`` the optimiser's ``(μ, σ, P_f)`` rows, ``fe_mean``/``fe_std``/``fe_pf`` the FE
    values on ``n_theta`` fresh θ, ``fe_nondominated`` whether each row is non-dominated in
    ``(μ_FE, σ_FE)`` among its run's verified designs."""

    runs: tuple[str, ...]
    X: np.ndarray
    front_size: dict[str, int]
    crn: np.ndarray
    fe_mean: np.ndarray
    fe_std: np.ndarray
    fe_pf: np.ndarray
    fe_nondominated: np.ndarray
    n_theta: int
    calls: dict[str, int] = field(default_factory=dict)

    def rows(self, design_names: tuple[str, ...]) -> list[dict[str, Any]]:
        """``front_verification.csv`` rows (µm, percent)."""
        return [{"run": r, **{n: float(v) for n, v in zip(design_names, x, strict=True)},
                 "mean_um_crn": c[0] * 1e6, "std_um_crn": c[1] * 1e6, "pf_pct_crn": c[2] * 100,
                 "mean_um_fe": m * 1e6, "std_um_fe": s * 1e6, "pf_pct_fe": p * 100,
                 "fe_nondominated": bool(nd), "front_size": self.front_size[r],
                 "n_theta_fe": self.n_theta}
                for r, x, c, m, s, p, nd in zip(self.runs, self.X, self.crn, self.fe_mean,
                                                self.fe_std, self.fe_pf, self.fe_nondominated,
                                                strict=True)]


def verify_fronts(problem: Any, optimisation: Any, n_designs: int, theta: np.ndarray, *,
                  n_jobs: int = 1, chunk: int | None = None, cache: Any = None,
                  progress: bool = False, label: str = "") -> FrontCheck:
    """Up to ``n_designs`` front designs of every RBRDO/RDO run of ``optimisation`` checked
    with the FE model on ``theta`` (module docstring)."""
    runs, X, crn, sizes = [], [], [], {}
    for (name, _), lab, res in zip(optimisation.runs, optimisation.labels,
                                   optimisation.results, strict=True):
        if name not in ("rbrdo", "rdo"):
            continue
        front = archive_front(res)
        sizes[lab] = int(front.size)
        pick = front[spread_indices(front.size, n_designs)] if front.size else front
        arch = res.archive
        runs += [lab] * pick.size
        X.append(arch.X[pick])
        crn.append(np.column_stack([arch.F[pick, 0], arch.F[pick, 1], arch.pf[pick]]))
    d = problem.design_bounds.shape[0]
    X = np.vstack(X) if X else np.empty((0, d))
    crn = np.vstack(crn) if crn else np.empty((0, 3))
    counter = CallCounter()
    y = sample_designs(problem.fe_response(), X, theta, n_jobs=n_jobs, chunk=chunk,
                       cache=cache, counter=counter, progress=progress,
                       desc=f"{label} FE: front designs".strip()) if len(X) else \
        np.empty((0, theta.shape[0]))
    mean, std = y.mean(axis=1), y.std(axis=1, ddof=1)
    pf = problem.limit.failed(y).mean(axis=1) if len(X) else np.empty(0)
    nd = np.zeros(len(X), dtype=bool)
    labels = np.array(runs)
    for lab in sizes:
        rows = np.flatnonzero(labels == lab)
        if rows.size:
            nd[rows] = nondominated(np.column_stack([mean[rows], std[rows]]))
    return FrontCheck(tuple(runs), X, sizes, crn, mean, std, pf, nd, int(theta.shape[0]),
                      {"fe": counter.calls, "fe_cached": counter.cached})


__all__ = ["FrontCheck", "spread_indices", "verify_fronts"]
