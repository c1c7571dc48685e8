"""The naming rule: which candidate, if any, the data support — one stage of forward selection.

A candidate passes a stage only if all of these hold (every threshold is an option fixed before
any data are seen):

1. **likelihood ratio**: its ``Δχ²`` over the current model has a family-wise adjusted p-value
   ``≤ α`` (bootstrap min-p over every candidate tried, :mod:`.calibration`);
2. **significant**: the 95 % interval of a strength parameter excludes the off state;
3. **physical**: no strength parameter sits on its physical bound with the data wanting it
   beyond (a score test at χ²₁ 99 %, :func:`~.search.bound_score`: a truth at the end of its
   range is inside it), no shape parameter on a bound other than a natural zero;
4. **held-out speeds improve**: the held-out predictive deviance (parameters and unbalance
   from training; residuals against the noise plus the training fit's prediction
   uncertainty, with the log-determinant of that covariance, :func:`~.holdout.predictive_chi2`)
   falls in total and worsens on neither the interleaved nor the extrapolated speeds by more
   than ``holdout_tolerance``.

Candidates passing (1) and (3) whose χ² lies within ``confound_delta`` of the best of them form
a group the data cannot tell apart (:func:`decide`): one alone is named, several are a
confounded set — provided some member beats every generic rival (:mod:`.rivals`, each fitted
candidate's :attr:`Assessment.rival`; the workflow applies it). When the base model's residual
looks like noise, candidates whose first-order statistic is far below the threshold are not
refitted (their nonlinear ``Δχ²`` equals the first-order one for small effects; this saves the
fits when nothing is missing). When it does not, the candidates above that screen are fitted
first; if the best of them leaves a residual that looks like noise (the same three lack-of-fit
tests at its fit), the rest are not refitted either — the data are explained, and a candidate
whose first-order statistic is below half its threshold at the base could join the group only
by a nonlinear gain the rig's fits do not show (:func:`run_stage`); otherwise every candidate
is fitted.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from joblib import Parallel, delayed
from threadpoolctl import threadpool_limits

from surrogate_rbrdo.discrepancy.calibration import (
    Linearisation,
    NullDistribution,
    generic_statistic,
    gp_statistic,
    linear_statistics,
    linearise,
    simulate_null,
)
from surrogate_rbrdo.discrepancy.candidates import Candidate
from surrogate_rbrdo.discrepancy.fit import Fit
from surrogate_rbrdo.discrepancy.holdout import predictive_chi2
from surrogate_rbrdo.discrepancy.holds import interior
from surrogate_rbrdo.discrepancy.impedance import acts_on_rotor
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.rivals import RivalTest, damping_law_columns, rival_test
from surrogate_rbrdo.discrepancy.search import CandidateFit, fit_candidate, warm_base

#: a candidate is refitted when its first-order statistic exceeds this fraction of its threshold
#: — or whenever a lack-of-fit test of the stage's base model has a p-value below QUIET_P and
#: the best fit of those above the fraction does too (:func:`run_stage`)
REFIT_FRACTION = 0.5
QUIET_P = 0.05


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
    #: the encompassing test against the generic local changes (:mod:`.rivals`)
    rival: RivalTest | None = None

    @property
    def passed(self) -> bool:
        return all(self.checks.values())

    @property
    def separable(self) -> bool:
        """Whether the data tell this candidate from every generic local change."""
        return self.rival is None or self.rival.passed

    def to_dict(self) -> dict:
        d = {"name": self.name, "delta_chi2": self.delta_chi2, "p_raw": self.p_raw,
             "p_adjusted": self.p_adjusted, "holdout_gain": self.holdout_gain,
             "checks": self.checks, "passed": self.passed}
        if self.fit is not None:
            d.update(parameters=self.fit.parameters, ci=self.fit.ci,
                     chi2=self.fit.fit.chi2)
        if self.rival is not None:
            d["generic_rival"] = self.rival.to_dict()
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
    generic: float
    generic_p: float
    chosen: tuple[str, ...] = field(default=())
    #: the stage's linearisation without the candidates' columns (the nuisance's and the
    #: generic ones): more draws of the residual statistics (:mod:`.sequential`) need no
    #: second linearisation
    residual_lin: Linearisation | None = field(default=None, repr=False, compare=False)


@dataclass(frozen=True)
class HoldoutProblems:
    """Problems on the interleaved and extrapolated held-out speeds."""

    interleaved: Problem
    extrapolated: Problem

    def chi2(self, f: Fit, train: Problem) -> tuple[float, float]:
        """Predictive deviance of ``f`` (fitted on ``train``) on the interleaved and
        extrapolated points: the residuals against the noise plus the training fit's
        prediction uncertainty, with its log-determinant (:func:`~.holdout.predictive_chi2`)."""
        return predictive_chi2(train, (self.interleaved, self.extrapolated), f, deviance=True)


def run_stage(problem: Problem, base: Fit, candidates: tuple[Candidate, ...],
              holdout: HoldoutProblems, *, alpha: float, n_draws: int,
              holdout_tolerance: float, rng: np.random.Generator, max_nfev: int,
              confound_delta: float, n_jobs: int = 1) -> Stage:
    """Calibrate, fit and check every candidate on top of ``base``; the candidates' fits on
    ``n_jobs`` worker processes (:func:`fit_all`)."""
    lin = linearise(problem, base, candidates)
    null = simulate_null(problem, lin, n_draws=n_draws, rng=rng)
    r = base.evaluation.residuals[0]
    (_, gof_p), (struct, struct_p), (gen, gen_p) = _lack_of_fit(problem, lin, null, base)
    # the first-order screen only where the residual looks like noise: a strong effect can be
    # far from its linearisation at the off state (a housing mode inside the speed range)
    quiet = min(gof_p, struct_p, gen_p) > QUIET_P
    tails = null.tails()
    p_crit = null.critical_p(alpha) if lin.candidates else 0.0
    lin_stat = linear_statistics(problem, lin, r) if lin.candidates else np.zeros(0)
    base_ho = holdout.chi2(base, problem)
    law = damping_law_columns(problem, lin, base.par.names)
    low = [lin_stat[k] < REFIT_FRACTION * tails[k].isf(p_crit)
           for k in range(len(lin.candidates))]
    first = [c for (c, _), lo in zip(lin.candidates, low, strict=True) if not lo]
    rest = [c for (c, _), lo in zip(lin.candidates, low, strict=True) if lo and not quiet]
    # the 1x-only recalibration, once per stage, then the candidates' fits (independent)
    warm = warm_base(problem, base, max_nfev=max_nfev) if first or rest else None
    kw = {"max_nfev": max_nfev, "confound_delta": confound_delta, "n_jobs": n_jobs}
    fitted = dict(zip((c.name for c in first), fit_all(problem, base, first, warm, **kw),
                      strict=True))
    if rest and not (fitted and _explained(problem, lin, null, fitted.values())):
        fitted.update(zip((c.name for c in rest), fit_all(problem, base, rest, warm, **kw),
                          strict=True))
    out = []
    for k, (c, _) in enumerate(lin.candidates):
        if c.name not in fitted:
            p = float(tails[k].sf(lin_stat[k]))
            out.append(Assessment(c.name, float(lin_stat[k]), p, null.adjusted(p), None, {},
                                  {"likelihood_ratio": False}))
            continue
        cf = fitted[c.name]
        p = float(tails[k].sf(cf.delta_chi2))
        ho = holdout.chi2(cf.fit, problem)
        gain = {"interleaved": base_ho[0] - ho[0], "extrapolated": base_ho[1] - ho[1]}
        checks = {
            "likelihood_ratio": null.adjusted(p) <= alpha,
            "significant": cf.significant,
            "physical": not cf.at_bound,
            "holdout": (gain["interleaved"] + gain["extrapolated"] > 0
                        and min(gain.values()) >= -holdout_tolerance),
        }
        # a shape held inside by holds.interior was chosen from the data: it counts as free
        rt = rival_test(problem, lin, base.chi2, r, cf.fit.chi2, cf.fit.evaluation.residuals[0],
                        cf.fit.jac, cf.n_fitted, confound_delta, law,
                        fit_design=problem.unbalance_design(cf.fit.par, cf.fit.x))
        out.append(Assessment(c.name, cf.delta_chi2, p, null.adjusted(p), cf, gain, checks,
                              rt))
    return Stage(base, null, tuple(out), lin.absorbed, gof_p, struct, struct_p, gen, gen_p,
                 residual_lin=replace(lin, candidates=()))


def _explained(problem: Problem, lin: Linearisation, null: NullDistribution, fits) -> bool:
    """Whether the best physical fit of ``fits`` (by χ²; a strength or shape on its bound
    cannot be named, so it explains nothing) leaves a residual that looks like noise: the
    stage's three lack-of-fit statistics at its fit (the generic one with the base's
    linearisation) each with a p-value above :data:`QUIET_P`. The ``gof`` null is the base
    model's: the fit's few extra parameters lower its χ² by about their number (of ≈ 2 500 on
    the rig), so this errs towards "explained" by far less than the test's spread."""
    fits = [cf for cf in fits if not cf.at_bound]
    if not fits:
        return False
    best = min(fits, key=lambda cf: cf.fit.chi2)
    return min(p for _, p in _lack_of_fit(problem, lin, null, best.fit)) > QUIET_P


def _lack_of_fit(problem: Problem, lin: Linearisation, null: NullDistribution, f: Fit
                 ) -> tuple[tuple[float, float], ...]:
    """The three lack-of-fit statistics of fit ``f``'s residual and their p-values under the
    stage's null: ``(gof, p), (structure, p), (generic, p)`` (the generic one with the
    stage's linearisation)."""
    r = f.evaluation.residuals[0]
    stats = {"gof": f.chi2, "structure": float(gp_statistic(r, problem.series())),
             "generic": generic_statistic(problem, lin, r)}
    return tuple((v, null.p_value(k, v)) for k, v in stats.items())


def fit_one(problem: Problem, base: Fit, c: Candidate, warm, *, max_nfev: int,
            confound_delta: float) -> CandidateFit:
    """One candidate's fit on top of ``base`` (:func:`~.search.fit_candidate` from the
    stage's 1x-only recalibration ``warm``), held inside if a shape ends on a bound the data
    may not prefer (:func:`~.holds.interior`); on one BLAS thread, in this process as on a
    worker (whose thread count loky sets), so the digits do not depend on ``n_jobs``."""
    with threadpool_limits(limits=1, user_api="blas"):   # the same digits in any process
        cf = fit_candidate(problem, base, c, max_nfev=max_nfev, warm=warm)
        if cf.at_bound:
            cf = interior(problem, base, cf, confound_delta, max_nfev=max_nfev)
    return cf


def fit_all(problem: Problem, base: Fit, candidates: list[Candidate], warm, *,
            max_nfev: int, confound_delta: float, n_jobs: int = 1) -> list[CandidateFit]:
    """:func:`fit_one` of every candidate, in order. The fits are independent and draw no
    random numbers, so with ``n_jobs > 1`` they run on that many joblib (loky) worker
    processes with the same results: the candidate search is most of a stage's CPU, and on
    two idle cores it takes half the wall time (``[discrepancy] n_jobs``)."""
    kw = {"max_nfev": max_nfev, "confound_delta": confound_delta}
    if n_jobs == 1 or len(candidates) < 2:
        return [fit_one(problem, base, c, warm, **kw) for c in candidates]
    # the costliest searches first (longest processing time first: a housing stage's valleys
    # over three bearing scopes would otherwise start last and finish alone)
    order = sorted(range(len(candidates)), key=lambda i: -fit_cost(candidates[i]))
    done = Parallel(n_jobs=min(n_jobs, len(candidates)))(
        delayed(fit_one)(problem, base, candidates[i], warm, **kw) for i in order)
    out: list = [None] * len(candidates)
    for i, cf in zip(order, done, strict=True):
        out[i] = cf
    return out


def search_size(c: Candidate) -> int:
    """A candidate's search size, its parameters times its bearing scopes: the order of
    its fit's residual evaluations (on the shipped run's analysis a housing stage, 3 × 3,
    took 17.5 s of CPU, a speed softening, 2 × 3, 7.1 s, gyroscopics, 1 × 1, 1.0 s).

    >>> from surrogate_rbrdo.discrepancy.candidates import candidate
    >>> [search_size(candidate(n, ("front", "rear"))) for n in ("housing", "gyroscopics")]
    [9, 1]
    """
    return (len(c.strength) + len(c.shape)) * len(c.scopes)


#: how much more a residual evaluation costs when the candidate acts on the rotor (its
#: matrices change with every trial value, so the rotor is condensed again instead of reused
#: and the effect coupled at the bearings' retained DOFs, :mod:`.forward`): the shipped run's
#: fits cost 1–2 s of CPU per unit of :func:`search_size` for the bearing effects, 3.6 s for
#: the tool interface and 1.7 s for gyroscopics (first stage, two workers)
ROTOR_COST = 2


def fit_cost(c: Candidate) -> int:
    """The order of a candidate's fit's cost, for the longest-first schedule of
    :func:`fit_all` (it orders the work, never changes a result): its :func:`search_size`,
    times :data:`ROTOR_COST` for an effect that acts on the rotor.

    >>> from surrogate_rbrdo.discrepancy.candidates import candidate
    >>> [fit_cost(candidate(n, ("front", "rear")))
    ...  for n in ("housing", "tool_interface", "cross_coupling", "gyroscopics")]
    [9, 4, 3, 2]
    """
    return search_size(c) * (ROTOR_COST if acts_on_rotor(c.effect_cls) else 1)


def decide(stage: Stage, delta: float) -> list[Assessment]:
    """The stage's answer: ``[]`` (nothing), one assessment (named) or several (confounded).

    Candidates passing the likelihood-ratio test and inside their physical range, within
    ``delta`` of the best χ² among them, cannot be told apart by the data. If one of them passes
    every check, the group is the answer (a confounded set when it has several members; a
    member that fails significance or the held-out check stays in the set, since the data do
    not separate it from the rest); if none does, nothing is named at this stage.
    """
    lr = [a for a in stage.assessments if a.fit is not None and a.checks["likelihood_ratio"]
          and a.checks["physical"]]
    if not lr:
        return []
    best = min(a.fit.fit.chi2 for a in lr)
    group = sorted((a for a in lr if a.fit.fit.chi2 - best <= delta),
                   key=lambda a: a.fit.fit.chi2)
    if not any(a.passed for a in group):
        return []
    if len(group) == 1:
        return group
    # the model carries the best-fitting member that passes every check
    first = next(a for a in group if a.passed)
    return [first] + [a for a in group if a is not first]
