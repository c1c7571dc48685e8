"""Coverage of the reported errors: do the intervals of an estimator cover the exact P_f at the
rate they claim, in repeated runs — and when they do not, does the estimator say so?

:func:`coverage` runs one estimator on one problem with independent generators (seeds
``seed_offset …``) and sorts every run into one of:

* **warned**: it raised an :class:`~._tail.EstimatorWarning` or a
  :class:`~surrogate_rbrdo.core.ModelError`, or reported a bound instead of an estimate
  (``status = "not_reached"``) — the method says its error bar is not to be trusted. Counted
  apart, with the *false alarms* (warned runs whose interval covered anyway);
* **covered**: no warning, and the exact value lies in the method's own interval at the 3σ
  level (two-sided 99.73 %): ``P̂ ± 3·SE`` for the normal-interval methods (IS, ais), the
  log-normal interval ``P̂ exp(s²/2 ± 3s)`` for subset simulation (a product of level
  fractions, skewed), Clopper–Pearson for crude MC;
* **silent miss**: neither — the case that must stay rare (≥ 95 % of the unwarned runs
  covered).

Two further figures check that the errors are not simply inflated: the share of all runs whose
nominal 95 % interval covers (should be close to 0.95), the share covered by the symmetric
``P̂ ± 3·SE`` (the same as the 3σ interval except for subset and MC), and the empirical
against the reported coefficient of variation. A reference's own standard error (a Monte Carlo
reference) is added in quadrature. Used by ``benchmarks/bench_coverage.py`` and the coverage
tests.

>>> from surrogate_rbrdo.estimators.problems import linear_standard
>>> row = coverage(linear_standard(beta=3.0, dim=2), "is", {"n_samples": 200}, n_seeds=5)
>>> row.covered, row.n_runs, row.warned, row.silent_misses
(5, 5, 0, 0)
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import special

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.protocols import Estimate
from surrogate_rbrdo.estimators._common import clopper_pearson, z_of
from surrogate_rbrdo.estimators._tail import EstimatorWarning
from surrogate_rbrdo.estimators.registry import get_estimator

#: two-sided level of the "3σ" interval
LEVEL_3SIGMA = float(special.erf(3.0 / np.sqrt(2.0)))


@dataclass(frozen=True)
class CoverageRow:
    """Outcome of :func:`coverage` for one (problem, estimator) pair (counts of runs)."""

    problem: str
    estimator: str
    options: Mapping[str, Any]
    exact: float
    n_runs: int
    covered: int
    warned: int
    false_alarms: int
    silent_misses: int
    covered_95: int
    covered_3se: int
    mean_calls: float
    mean_pf: float
    cov_empirical: float
    cov_reported: float
    messages: tuple[str, ...] = field(default=())

    @property
    def share_covered(self) -> float:
        """Covered runs among those that did not warn (NaN if every run warned)."""
        unwarned = self.n_runs - self.warned
        return self.covered / unwarned if unwarned else float("nan")

    @property
    def share_covered_or_warned(self) -> float:
        return (self.n_runs - self.silent_misses) / self.n_runs


def interval_at(est: Estimate, level: float, ref_se: float = 0.0) -> tuple[float, float]:
    """The two-sided ``level`` interval of the first design of ``est`` by its own method
    (``diagnostics["ci_method"]``: normal, log-normal or Clopper–Pearson), widened by a
    reference's standard error ``ref_se`` (in quadrature; by ``z·ref_se`` for the exact
    binomial interval)."""
    pf, se = float(est.pf[0]), float(est.pf_se[0])
    method = est.diagnostics.get("ci_method", "normal")
    z = z_of(level)
    if method == "clopper-pearson":
        n = int(est.diagnostics["n_samples"])
        k = np.array([est.diagnostics["n_failures"][0]])
        lo, hi = clopper_pearson(k, n, level)[0]
        return float(lo) - z * ref_se, float(hi) + z * ref_se
    if method == "lognormal" and pf > 0:
        s = np.sqrt(np.log1p((se**2 + ref_se**2) / pf**2))
        return pf * np.exp(0.5 * s * s - z * s), pf * np.exp(0.5 * s * s + z * s)
    half = z * float(np.hypot(se, ref_se))
    return pf - half, pf + half


def coverage(problem: Any, name: str, options: Mapping[str, Any] | None = None, *,
             n_seeds: int = 40, ref_se: float = 0.0, seed_offset: int = 0) -> CoverageRow:
    """Run ``name`` with ``options`` on ``problem`` for ``n_seeds`` generators (first design)."""
    options = dict(options or {})
    est = get_estimator(name, **options)
    exact = float(problem.pf_exact[0])
    n = dict.fromkeys(("covered", "warned", "false", "silent", "c95", "c3se"), 0)
    pfs, covs, calls, msgs = [], [], [], []
    for seed in range(seed_offset, seed_offset + n_seeds):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", EstimatorWarning)
            try:
                r = est.estimate(problem.response, problem.inputs, problem.limit,
                                 problem.x[:1], rng=np.random.default_rng(seed))
            except ModelError as exc:
                n["warned"] += 1
                msgs.append(f"ModelError: {exc}"[:160])
                continue
        said = [str(w.message) for w in caught if issubclass(w.category, EstimatorWarning)]
        status = r.diagnostics.get("status", np.array(["converged"]))[0]
        if status == "not_reached":
            said.append("not reached: a bound, not an estimate")
        pf, se = float(r.pf[0]), float(r.pf_se[0])
        pfs.append(pf)
        covs.append(se / pf if pf > 0 else np.nan)
        calls.append(r.n_calls)
        lo, hi = interval_at(r, LEVEL_3SIGMA, ref_se)
        ok = bool(np.isfinite(se) and lo <= exact <= hi)
        lo95, hi95 = interval_at(r, 0.95, ref_se)
        n["c95"] += bool(np.isfinite(se) and lo95 <= exact <= hi95)
        n["c3se"] += bool(np.isfinite(se) and abs(pf - exact) <= 3 * np.hypot(se, ref_se))
        if said:
            n["warned"] += 1
            n["false"] += ok
            msgs.append(said[0][:160])
        elif ok:
            n["covered"] += 1
        else:
            n["silent"] += 1
    pfs_a = np.asarray(pfs)
    return CoverageRow(
        problem=problem.name, estimator=name, options=options, exact=exact, n_runs=n_seeds,
        covered=n["covered"], warned=n["warned"], false_alarms=n["false"],
        silent_misses=n["silent"], covered_95=n["c95"], covered_3se=n["c3se"],
        mean_calls=float(np.mean(calls)) if calls else np.nan,
        mean_pf=float(pfs_a.mean()) if pfs else np.nan,
        cov_empirical=float(pfs_a.std(ddof=1) / exact) if len(pfs) > 1 else np.nan,
        cov_reported=float(np.nanmean(covs)) if np.isfinite(covs).any() else np.nan,
        messages=tuple(dict.fromkeys(msgs)))


__all__ = ["LEVEL_3SIGMA", "CoverageRow", "coverage", "interval_at"]
