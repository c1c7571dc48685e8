"""Experiment kind ``end_to_end``: the paper's data-driven loop in one run folder
(``docs/validation.md``, "The loop end to end"; the plan and the steps between the parts are
:mod:`surrogate_rbrdo.loop`'s).

Stages, each another kind's stage function or a :mod:`~surrogate_rbrdo.loop.steps` call:

``campaign`` (the ``rig`` kind's, on the truth of ``[spindle]`` at its baseline, with
trial-weight runs) → ``demodulate``, ``identify`` (the ``identification`` kind's on that
campaign) → ``uncertainty`` (``loop.identified_theta``: the identified stiffness block plus
the ``[uncertainty]`` unbalance block) → ``surrogate`` … ``verify`` (the ``study`` kind's, on
the identified θ) → ``measure``, ``model`` (the ``validation`` kind's: the chosen designs
against the baseline on the rig; the model's moments are the study's FE verification) →
``discrepancy`` (the ``discrepancy`` kind's analysis of the campaign when
``loop.discrepancy_reason`` says so) → ``reoptimise`` (``loop.reoptimisation``) →
``surrogate_updated`` … ``model_updated`` (the study and the validation again on the updated
spindle, same θ, seeds and rig; ``None`` when not re-optimised). The report writes each
part's files into its subfolder (``rig/``, ``identification/``, ``study[_updated]/``,
``validation[_updated]/``, ``discrepancy/``) and ``report.md``
(:mod:`surrogate_rbrdo.reporting.end_to_end`). Each part draws from its own child of the
seed (:func:`part_context`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.loop import steps
from surrogate_rbrdo.loop.plan import PARTS, UPDATED, EndToEndConfig, LoopPlan, build_loop
from surrogate_rbrdo.reporting.end_to_end import write_loop_report
from surrogate_rbrdo.reporting.plots_discrepancy import write_discrepancy_run
from surrogate_rbrdo.reporting.plots_identification import write_identification_run
from surrogate_rbrdo.reporting.study import write_study_report
from surrogate_rbrdo.runner.experiments import discrepancy as disc_kind
from surrogate_rbrdo.runner.experiments import identification as ident_kind
from surrogate_rbrdo.runner.experiments import rig as rig_kind
from surrogate_rbrdo.runner.experiments import study as study_kind
from surrogate_rbrdo.runner.experiments import validation as validation_kind
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.runfolder import RunFolder


def part_context(ctx: StageContext, part: str) -> StageContext:
    """The context a part's stages get: the same run folder and cache, and its own child of
    the experiment's seed (so the rig's assemblies, the study's samples and the validation's
    replications never share random numbers).

    >>> ctx = StageContext(seed=1, progress=False, label="x", cache_dir=Path("."),
    ...                    run_dir=Path("."))
    >>> part_context(ctx, "rig").seed != part_context(ctx, "study").seed
    True
    """
    seed = np.random.SeedSequence(ctx.seed, spawn_key=(1000 + PARTS.index(part),))
    return replace(ctx, seed=int(seed.generate_state(1, np.uint64)[0]))


def build(c: EndToEndConfig, base_dir: Path) -> LoopPlan:
    """:func:`~surrogate_rbrdo.loop.plan.build_loop`, and the study report's figures."""
    plan = build_loop(c, base_dir)
    study_kind.check_report(plan.study)
    return plan


def subfolder(run_dir: Path, name: str) -> RunFolder:
    """A part's folder of the run as a :class:`RunFolder` (its kind's report writes there)."""
    (run_dir / name).mkdir(exist_ok=True)
    return RunFolder(path=run_dir / name, experiment=run_dir.parent.name, run_id=run_dir.name)


def _campaign(p: LoopPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    return rig_kind.campaign(p.rig, done, part_context(ctx, "rig"))


def _demodulate(p: LoopPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    return ident_kind.demodulate(steps.identification_plan(p, ctx.run_dir), done,
                                 part_context(ctx, "identification"))


def _identify(p: LoopPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    """The identification kind's stage, then its files into ``identification/`` (the
    ``uncertainty.json`` the study's ``[uncertainty] from`` reads)."""
    plan = steps.identification_plan(p, ctx.run_dir)
    res = ident_kind.identify(plan, done, part_context(ctx, "identification"))
    write_identification_run(subfolder(ctx.run_dir, "identification"),
                             replace(plan, options=replace(plan.options, figures=False)), res)
    return res


def _uncertainty(p: LoopPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    return steps.identified_theta(p, ctx.run_dir / "identification")


def _study_stage(func: Any, updated: bool = False) -> Any:
    def stage(p: LoopPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
        plan = steps.study_plan(p, done, updated)
        if plan is None:
            return None
        return func(plan, steps.round_results(done, updated), part_context(ctx, "study"))
    stage.__name__ = func.__name__.lstrip("_") + (UPDATED if updated else "")
    return stage


def _validation_stage(func: Any, p: LoopPlan, done: Mapping[str, Any], ctx: StageContext,
                      updated: bool = False) -> Any:
    plan = steps.validation_plan_for(p, done, updated)
    return None if plan is None else func(plan, steps.round_results(done, updated),
                                          part_context(ctx, "validation"))


def _discrepancy(p: LoopPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    ran, why = steps.discrepancy_reason(p, done)
    if not ran:
        return steps.DiscrepancyStage(False, why)
    res = disc_kind.analyse(steps.discrepancy_plan(p, ctx.run_dir),
                            {"campaign": ctx.run_dir / "campaign"},
                            part_context(ctx, "discrepancy"))
    return steps.DiscrepancyStage(True, why, res)


def _report(p: LoopPlan, done: Mapping[str, Any], run: Any, ctx: StageContext
            ) -> dict[str, Any]:
    for updated in (False, True):       # the study's tables and figures of each round
        plan = steps.study_plan(p, done, updated)
        if plan is not None and done.get("verify" + (UPDATED if updated else "")) is not None:
            write_study_report(subfolder(run.path, "study" + (UPDATED if updated else "")),
                               plan, steps.round_results(done, updated))
    if done["discrepancy"].ran:
        write_discrepancy_run(subfolder(run.path, "discrepancy").path,
                              steps.discrepancy_plan(p, ctx.run_dir),
                              done["discrepancy"].result, run.path / "campaign")
    pr, c = p.study.problem, p.config
    timings = {k: float(v.get("time_s", 0.0)) for k, v in run.meta.get("stages", {}).items()}
    return write_loop_report(
        run.path, truth=p.rig.rig.truth, campaign=done["campaign"],
        campaign_options=p.rig.rig.options, model=steps.model_at_baseline(p),
        identification=done["identify"], identification_figures=p.identification.figures,
        convergence_speed_rpm=p.identification.convergence_speed_rpm,
        theta=done["uncertainty"], theta_bearings=pr.spindle.theta_bearings,
        verification=done["verify"], limit_um=c.limit.delta_lim_um, validation=done["model"],
        discrepancy=done["discrepancy"], timings=timings, rig_figures=p.rig.rig.figures,
        updated=(done.get("verify" + UPDATED), done.get("model" + UPDATED)),
        reoptimise=done["reoptimise"])


def _round(updated: bool) -> tuple[Stage, ...]:
    """One round's stages: the study's, then the validation's on the rig."""
    sfx = UPDATED if updated else ""
    return (*(Stage(f.__name__.lstrip("_") + sfx, _study_stage(f, updated))
              for f in study_kind.STAGES),
            *(Stage(name + sfx, partial(_validation_stage, f, updated=updated))
              for name, f in (("measure", validation_kind.measure),
                              ("model", validation_kind.model))))


register_kind(Kind(
    name="end_to_end",
    summary="the data-driven loop in one run: rig campaign with trial weights → "
            "identification → the study's θ → RBRDO at every P_target → validation of the "
            "chosen designs on the rig → discrepancy when model and rig disagree → report.md",
    schema=EndToEndConfig,
    stages=(Stage("campaign", _campaign), Stage("demodulate", _demodulate),
            Stage("identify", _identify), Stage("uncertainty", _uncertainty),
            *_round(False), Stage("discrepancy", _discrepancy),
            Stage("reoptimise", lambda p, done, ctx: steps.reoptimisation(p, done)),
            *_round(True)),
    report=_report,
    build=build,
))
