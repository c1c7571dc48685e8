"""The naming rule: which candidate, if any, the data support — one stage of forward selection.

A candidate passes a stage only if all of these hold (every threshold is an option fixed before
any data are seen):

1. **likelihood ratio**: its ``Δχ²`` over the current model has a family-wise adjusted p-value
   ``≤ α`` (bootstrap min-p over every candidate tried, :mod:`.calibration`);
2. **significant**: the 95 % interval of every strength parameter excludes the off state;
3. **physical**: no strength parameter sits on its physical bound;
4. **held-out speeds improve**: the held-out χ² (parameters and unbalance from training) falls
   in total and worsens on neither the interleaved nor the extrapolated speeds by more than
   ``holdout_tolerance``.

Among the passing candidates, all whose χ² is within ``confound_delta`` of the best are a
confounded set (the data cannot tell them apart); one alone is named. Candidates whose first-
order statistic is far below the threshold are not refitted (their nonlinear ``Δχ²`` equals
the first-order one for small effects; this saves the fits when nothing is missing).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from surrogate_rbrdo.discrepancy.calibration import (
    NullDistribution,
    gp_statistic,
    linear_statistics,
    linearise,
    simulate_null,
)
from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.discrepancy.fit import Fit
from surrogate_rbrdo.discrepancy.holdout import residuals
from surrogate_rbrdo.discrepancy.problem import Problem, _whitened
from surrogate_rbrdo.discrepancy.search import CandidateFit, fit_candidate

#: a candidate is refitted when its first-order statistic exceeds this fraction of its threshold
REFIT_FRACTION = 0.3


@dataclass(frozen=True)
class Assessment:
    """One candidate in one stage: its fit (or first-order statistic) and the rule's checks."""

    name: str
    delta_chi2: float
    p_raw: float
    p_adjusted: float
    fit: CandidateFit | None
    holdout_gain: dict
    checks: dict

    @property
    def passed(self) -> bool:
        return all(self.checks.values())

    def to_dict(self) -> dict:
        d = {"name": self.name, "delta_chi2": self.delta_chi2, "p_raw": self.p_raw,
             "p_adjusted": self.p_adjusted, "holdout_gain": self.holdout_gain,
             "checks": self.checks, "passed": self.passed}
        if self.fit is not None:
            d.update(parameters=self.fit.parameters, ci=self.fit.ci,
                     chi2=self.fit.fit.chi2)
        return d


@dataclass(frozen=True)
class Stage:
    """A stage of forward selection on top of ``base``."""

    base: Fit
    null: NullDistribution
    assessments: tuple[Assessment, ...]
    absorbed: tuple[str, ...]
    gof_p: float
    structure: float
    structure_p: float
    chosen: tuple[str, ...] = field(default=())

    def best(self) -> Assessment | None:
        ok = [a for a in self.assessments if a.passed]
        return min(ok, key=lambda a: a.fit.fit.chi2) if ok else None


@dataclass(frozen=True)
class HoldoutProblems:
    """Problems on the interleaved and extrapolated held-out speeds."""

    interleaved: Problem
    extrapolated: Problem

    def chi2(self, f: Fit) -> tuple[float, float]:
        out = []
        for p in (self.interleaved, self.extrapolated):
            res = residuals(p, f.par, f.x, tuple(u[0] for u in f.evaluation.unbalance))
            out.append(float(sum(np.sum(_whitened(r[None], W) ** 2)
                                 for r, W in zip(res, p.whiten, strict=True))))
        return out[0], out[1]


def run_stage(problem: Problem, base: Fit, candidates: tuple[Candidate, ...],
              holdout: HoldoutProblems, *, alpha: float, n_draws: int,
              holdout_tolerance: float, rng: np.random.Generator, max_nfev: int) -> Stage:
    """Calibrate, fit and check every candidate on top of ``base``."""
    lin = linearise(problem, base, candidates)
    null = simulate_null(problem, lin, n_draws=n_draws, rng=rng)
    r = base.evaluation.residuals[0]
    struct = float(gp_statistic(r, problem.series()))
    tails = null.tails()
    p_crit = null.critical_p(alpha) if lin.candidates else 0.0
    lin_stat = linear_statistics(problem, lin, r) if lin.candidates else np.zeros(0)
    base_ho = holdout.chi2(base)
    out = []
    for k, (c, _) in enumerate(lin.candidates):
        threshold = tails[k].isf(p_crit)
        if lin_stat[k] < REFIT_FRACTION * threshold:
            p = float(tails[k].sf(lin_stat[k]))
            out.append(Assessment(c.name, float(lin_stat[k]), p, null.adjusted(p), None, {},
                                  {"likelihood_ratio": False}))
            continue
        cf = fit_candidate(problem, base, c, max_nfev=max_nfev)
        p = float(tails[k].sf(cf.delta_chi2))
        ho = holdout.chi2(cf.fit)
        gain = {"interleaved": base_ho[0] - ho[0], "extrapolated": base_ho[1] - ho[1]}
        checks = {
            "likelihood_ratio": null.adjusted(p) <= alpha,
            "significant": cf.significant,
            "physical": not cf.at_bound,
            "holdout": (gain["interleaved"] + gain["extrapolated"] > 0
                        and min(gain.values()) >= -holdout_tolerance),
        }
        out.append(Assessment(c.name, cf.delta_chi2, p, null.adjusted(p), cf, gain, checks))
    return Stage(base, null, tuple(out), lin.absorbed, null.p_value("gof", base.chi2), struct,
                 null.p_value("structure", struct))


def confounded_set(stage: Stage, delta: float) -> list[Assessment]:
    """Passing candidates within ``delta`` of the best χ² (the best first)."""
    best = stage.best()
    if best is None:
        return []
    ok = [a for a in stage.assessments if a.passed
          and a.fit.fit.chi2 - best.fit.fit.chi2 <= delta]
    return sorted(ok, key=lambda a: a.fit.fit.chi2)
