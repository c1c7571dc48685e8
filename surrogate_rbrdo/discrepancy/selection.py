"""The forward selection of the discrepancy workflow (:mod:`.workflow`): stage after stage of
candidate fits (:func:`~.naming.run_stage`) on top of the model carried, each stage's group
(:func:`~.naming.decide`) put to the thermal soak when a member drifts with temperature
(:mod:`.soak`) and to the generic rivals (:mod:`.rivals`), until nothing passes, a confounded
set is found, a name is withheld or ``max_effects`` are named; and the last stage's residual
p-values refined (:func:`refined`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from surrogate_rbrdo.discrepancy.fit import Fit
from surrogate_rbrdo.discrepancy.naming import Assessment, Stage, decide, run_stage
from surrogate_rbrdo.discrepancy.problem import Problem
from surrogate_rbrdo.discrepancy.sequential import residual_p_values
from surrogate_rbrdo.discrepancy.soak import SoakBlock, SoakTest, soak_test

if TYPE_CHECKING:
    from surrogate_rbrdo.discrepancy.workflow import DiscrepancyOptions


@dataclass(frozen=True)
class Selection:
    """The forward selection's outcome (:func:`select`): its stages, the names given, a
    confounded set (with the generic changes it holds), the group withheld at the first stage
    (an unnamed residual), the fit the model carries and the thermal soak's verdicts."""

    stages: tuple[Stage, ...]
    named: tuple[Assessment, ...]
    confounded: tuple[Assessment, ...]
    generic: tuple[str, ...]
    withheld: tuple[Assessment, ...]
    current: Fit
    soak: tuple[SoakTest, ...] = ()


def select(train: Problem, base: Fit, cands, ho, options: DiscrepancyOptions,
            rng: np.random.Generator, soaks: tuple[SoakBlock, ...] = ()) -> Selection:
    """Forward selection: a stage of candidate fits on top of the current model until nothing
    passes, a confounded set is found, a name is withheld or ``max_effects`` are named; the
    last stage (no candidates left) holds the residual tests of the model carried. With a
    thermal soak in the data (``soaks``), a stage's group holding an effect that drifts with
    temperature is first put to it (:func:`_soaked`)."""
    current = base
    stages, named = [], []
    confounded: list[Assessment] = []
    generic: tuple[str, ...] = ()          # generic local changes a confounded set holds
    withheld: tuple[Assessment, ...] = ()
    soak: list[SoakTest] = []
    while True:
        left = tuple(c for c in cands if c.name not in {a.name for a in named})
        n_left = len(left) if len(named) < options.max_effects and not confounded else 0
        st = run_stage(train, current, left[:n_left], ho, alpha=options.alpha,
                       n_draws=options.n_draws, holdout_tolerance=options.holdout_tolerance,
                       rng=rng.spawn(1)[0], max_nfev=options.max_nfev,
                       confound_delta=options.confound_delta, n_jobs=options.n_jobs)
        stages.append(st)
        group = decide(st, options.confound_delta) if n_left else []
        drifts: set[str] = set()
        if group and soaks:
            kept, tests = _soaked(train, current, group, soaks, options.alpha)
            soak += tests
            drifts = {t.candidate for t in tests if t.outcome == "drift"}
            if not kept:
                # the soak rejects the drift of every member: the detection stands, the
                # names do not (at the first stage an unnamed residual)
                withheld = () if named else tuple(group)
                break
            group = kept
        if group and not any(a.separable or a.name in drifts for a in group):
            if (not named and options.generic_confound == "confounded"
                    and group[0].rival is not None and group[0].rival.mutual):
                # the library effect and its closest generic change explain the data alike
                # (neither adds to the other): a confounded set with that change, carried at
                # the library member's fit; the residual tests at that fit still judge it
                current, confounded = group[0].fit.fit, group
                generic = tuple(dict.fromkeys(a.rival.rival for a in group
                                              if a.rival is not None and a.rival.mutual))
                continue
            # detected, but a generic local change explains the data better, or as well
            # without the converse: at the first stage nothing can be named (unnamed
            # residual); later, the names stand and the residual tests judge what is left
            # (the stage's rival tests are in the findings)
            withheld = () if named else tuple(group)
            break
        if not group:
            break
        current = group[0].fit.fit
        if len(group) > 1:
            confounded = group
        else:
            named.append(group[0])
    return Selection(tuple(stages), tuple(named), tuple(confounded), generic, withheld,
                     current, tuple(soak))


def _soaked(train: Problem, current: Fit, group: list[Assessment],
            soaks: tuple[SoakBlock, ...], level: float
            ) -> tuple[list[Assessment], tuple[SoakTest, ...]]:
    """A stage's group after the thermal soak (:mod:`.soak`): each member whose effect drifts
    with temperature (:attr:`~surrogate_rbrdo.spindle.effects.Effect.thermal_params`) is
    tested at its own fit against the stage's base (no added drift). If one drifts as
    predicted, the members that cannot drift leave the group (nor can a generic local change:
    a spring or a mass does not drift), and so do drifting members the soak does not confirm;
    if the soak rejects every drifting member's drift, those leave it. Otherwise (no drifting
    member, or a verdict inconclusive) the group is as it was. The carried member is the
    best-fitting one that passes every check; a group left without one is empty, as is a
    group every member of which the soak rejects."""
    drifting = [a for a in group if a.fit is not None and _drifts(a)]
    if not drifting:
        return group, ()
    tests = tuple(soak_test(train, current, a.fit.fit, a.name, soaks, level)
                  for a in drifting)
    out = {t.candidate: t.outcome for t in tests}
    if "drift" in out.values():
        kept = [a for a in group if out.get(a.name) == "drift"]
    elif all(o == "no_drift" for o in out.values()):
        kept = [a for a in group if a.name not in out]
    else:
        return group, tests
    passing = [a for a in kept if a.passed]
    if not passing:
        return [], tests
    return [passing[0]] + [a for a in kept if a is not passing[0]], tests


def _drifts(a: Assessment) -> bool:
    """Whether a candidate's effect has parameters that follow temperature."""
    return bool(a.fit.slot.candidate.effect_cls.thermal_params)


def refined(problem: Problem, st: Stage, level: float, rng: np.random.Generator) -> Stage:
    """The last stage — whose residual tests give the verdict — with their p-values refined by
    sequential Monte Carlo where the bootstrap's first draws leave them near ``level``
    (:func:`~.sequential.residual_p_values`, at the stage's own linearisation; unchanged, and
    no draw taken, where those settle them all)."""
    observed = {"gof": st.base.chi2, "structure": st.structure, "generic": st.generic}
    ps = residual_p_values(problem, st.residual_lin, st.null, observed, level=level,
                           rng=rng.spawn(1)[0])
    return replace(st, gof_p=ps["gof"], structure_p=ps["structure"], generic_p=ps["generic"])
