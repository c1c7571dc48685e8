"""Coverage of the reported standard errors: does ``|P̂_f − P_f| ≤ 3·SE`` hold in repeated runs?

:func:`coverage` runs one estimator on one problem with independent generators (seeds
``0..n_seeds-1``) and counts the runs whose nominal 3-SE interval covers the reference, the runs
that warned (:class:`~._tail.EstimatorWarning`) or raised :class:`~surrogate_rbrdo.core.ModelError`
(a method that says it fails), model calls and the empirical against the reported CoV. The
reference's own standard error (a Monte Carlo reference) is added in quadrature. Used by
``benchmarks/bench_coverage.py`` and the coverage tests.

>>> from surrogate_rbrdo.estimators.problems import linear_standard
>>> row = coverage(linear_standard(beta=3.0, dim=2), "is", {"n_samples": 200}, n_seeds=5)
>>> row.covered, row.n_runs, row.warned
(5, 5, 0)
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators.registry import get_estimator


@dataclass(frozen=True)
class CoverageRow:
    """Outcome of :func:`coverage` for one (problem, estimator) pair.

    ``covered``: runs with ``|pf − ref| ≤ k·√(se² + se_ref²)``; ``warned``: runs that raised an
    ``EstimatorWarning`` or a ``ModelError`` (counted as "said so", not as covered);
    ``silent_misses``: runs neither covered nor warned — the number that must stay small.
    """

    problem: str
    estimator: str
    options: Mapping[str, Any]
    exact: float
    n_runs: int
    covered: int
    warned: int
    silent_misses: int
    mean_calls: float
    mean_pf: float
    cov_empirical: float
    cov_reported: float
    messages: tuple[str, ...] = field(default=())

    @property
    def share_covered(self) -> float:
        return self.covered / self.n_runs

    @property
    def share_covered_or_warned(self) -> float:
        return (self.n_runs - self.silent_misses) / self.n_runs


def coverage(problem: Any, name: str, options: Mapping[str, Any] | None = None, *,
             n_seeds: int = 40, k: float = 3.0, ref_se: float = 0.0,
             seed_offset: int = 0) -> CoverageRow:
    """Run ``name`` with ``options`` on ``problem`` for ``n_seeds`` generators (first design)."""
    options = dict(options or {})
    est = get_estimator(name, **options)
    exact = float(problem.pf_exact[0])
    covered = warned = silent = 0
    pfs, covs, calls, msgs = [], [], [], []
    for seed in range(seed_offset, seed_offset + n_seeds):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", EstimatorWarning)
            try:
                r = est.estimate(problem.response, problem.inputs, problem.limit,
                                 problem.x[:1], rng=np.random.default_rng(seed))
            except ModelError as exc:
                warned += 1
                msgs.append(f"ModelError: {exc}"[:160])
                continue
        said = [w for w in caught if issubclass(w.category, EstimatorWarning)]
        pf, se = float(r.pf[0]), float(r.pf_se[0])
        pfs.append(pf)
        covs.append(se / pf if pf > 0 else np.nan)
        calls.append(r.n_calls)
        ok = bool(np.isfinite(se) and abs(pf - exact) <= k * np.hypot(se, ref_se))
        covered += ok
        if said:
            warned += 1
            msgs.append(str(said[0].message)[:160])
        elif not ok:
            silent += 1
    pfs_a = np.asarray(pfs)
    return CoverageRow(
        problem=problem.name, estimator=name, options=options, exact=exact, n_runs=n_seeds,
        covered=covered, warned=warned, silent_misses=silent,
        mean_calls=float(np.mean(calls)) if calls else np.nan,
        mean_pf=float(pfs_a.mean()) if pfs else np.nan,
        cov_empirical=float(pfs_a.std(ddof=1) / exact) if len(pfs) > 1 else np.nan,
        cov_reported=float(np.nanmean(covs)) if np.isfinite(covs).any() else np.nan,
        messages=tuple(dict.fromkeys(msgs)))


__all__ = ["CoverageRow", "coverage"]
