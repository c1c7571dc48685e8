"""Experiment kind ``study``: the RBRDO study end to end (:mod:`surrogate_rbrdo.study`).

The tables are :class:`~surrogate_rbrdo.study.plan.StudyConfig`'s (built by
:func:`~surrogate_rbrdo.study.plan.build_study`). Stages: ``surrogate`` (the ``[surrogate]``
structure, trained on FE points) → ``design_model`` (g_det) → ``optimise`` (RBRDO at every
P_target, then RDO/RBDO/deterministic; one CRN sample) → ``refine`` (``[refine]``, off by
default) → ``verify`` (the chosen designs with the full FE model); the report is
:func:`~surrogate_rbrdo.reporting.study.write_study_report`. Streams of the seed: 0
surrogate, 1 design model, 2 the CRN sample, 3 optimisation, 4 verification, 5 refinement.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from surrogate_rbrdo.reporting.spindle import check_overview
from surrogate_rbrdo.reporting.study import write_study_report
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.study.plan import StudyConfig, StudyPlan, build_study, final_models
from surrogate_rbrdo.study.stages import optimise, refine, verify
from surrogate_rbrdo.surrogates.design_model import fit_design_model
from surrogate_rbrdo.surrogates.structured import train_surrogate


def check_report(plan: StudyPlan) -> None:
    """The report's spindle figures (the baseline and one compromise) checked before any
    work (modes, memory)."""
    rep, base = plan.report, plan.problem.baseline
    check_overview(plan.problem.spindle, {"baseline": base, "compromise": base},
                   n_speeds=rep.n_speeds, campbell_speeds=rep.campbell_speeds,
                   n_modes=rep.n_modes, where="report")


def build(c: StudyConfig, base_dir: Path) -> StudyPlan:
    """:func:`build_study`, then :func:`check_report`."""
    plan = build_study(c, base_dir)
    check_report(plan)
    return plan


def _surrogate(p: StudyPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    pr = p.problem
    return train_surrogate(pr.spindle, pr.inputs, pr.limit, p.surrogate, rng=ctx.stream(0),
                           response=pr.response, cache=fe_cache(ctx.cache_dir),
                           progress=ctx.progress, label=ctx.label)


def _design_model(p: StudyPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    if not p.problem.deterministic.names:       # no stress or paper guard: nothing to fit
        return None
    return fit_design_model(p.problem.spindle, p.design_model, rng=ctx.stream(1),
                            progress=ctx.progress, label=ctx.label)


def _optimise(p: StudyPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    return optimise(p.problem, done["surrogate"], done["design_model"], p.optimization,
                    crn=ctx.seed_sequence(2), rng=ctx.stream(3), progress=ctx.progress,
                    label=ctx.label)


def _refine(p: StudyPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    return refine(p.problem, done["surrogate"], done["design_model"], done["optimise"],
                  p.optimization, p.refine, crn=ctx.seed_sequence(2), rng=ctx.stream(5),
                  cache=fe_cache(ctx.cache_dir), progress=ctx.progress, label=ctx.label)


def _verify(p: StudyPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    sur, opt = final_models(done)
    return verify(p.problem, sur, done["design_model"], opt, p.optimization, p.verification,
                  crn=ctx.seed_sequence(2), rng=ctx.stream(4),
                  cache=fe_cache(ctx.cache_dir, "fe_verification"), progress=ctx.progress,
                  label=ctx.label)


def _report(p: StudyPlan, done: Mapping[str, Any], run: Any, ctx: StageContext
            ) -> dict[str, Any]:
    return write_study_report(run, p, done)


#: the study's stage functions, in order (the ``end_to_end`` kind runs them twice)
STAGES = (_surrogate, _design_model, _optimise, _refine, _verify)

register_kind(Kind(
    name="study",
    summary="RBRDO study: surrogate → g_det design model → RBRDO per P_target, RDO, RBDO, "
            "deterministic → refinement → full-FE verification → tables and figures",
    schema=StudyConfig,
    stages=tuple(Stage(f.__name__.lstrip("_"), f) for f in STAGES),
    report=_report,
    build=build,
    defaults="with every problem table left out a study is the paper's published problem "
             "(reference spindle, in-phase G 2.5 unbalance, θ = the Table 4 stiffness CoVs, "
             "y = peak over the speed range, δ_lim = 19.5 µm, the f_n1 guard): NOT the "
             "credible reference problem (credible_problem(), experiments/quick.toml, which "
             "states every table)",
))
