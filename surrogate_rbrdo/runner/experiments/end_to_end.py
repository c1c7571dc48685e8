"""Experiment kind ``end_to_end``: the paper's data-driven loop in one run folder
(``docs/validation.md``, "The loop end to end").

Stages, each one library call or another kind's stage function:

``campaign`` (the ``rig`` kind's: ``rig.run_campaign`` on the truth of ``[spindle]`` at its
baseline, with trial-weight runs) → ``identification`` (``identification.run_identification``
on that campaign) → ``uncertainty`` (the study's θ: the identified stiffness block, plus the
``[uncertainty]`` unbalance block) → ``surrogate`` → ``design_model`` → ``optimise`` →
``refine`` → ``verify`` (the ``study`` kind's, on the identified θ) → ``measure`` → ``model``
(the ``validation`` kind's: the chosen designs against the baseline on the rig; the model's
moments are the study's FE verification) → ``discrepancy`` (``discrepancy.experiment.analyse``
on the campaign's phasors when the validation names a disagreement, ``[loop] discrepancy``)
→ ``reoptimise`` (whether the updated spindle can be optimised: effects named, the study's
design constraints defined for it) → ``surrogate_updated`` … ``model_updated`` (the study and
the validation again on the updated spindle, same θ, seeds and rig; ``None`` when not
re-optimised). The report writes each part's files into its subfolder (``rig/``,
``identification/``, ``study[_updated]/``, ``validation[_updated]/``, ``discrepancy/``) and
``report.md`` (:mod:`surrogate_rbrdo.reporting.end_to_end`).

Tables: the ``study`` kind's (``[spindle]`` … ``[refine]``), ``[rig]`` (``RigTable`` without
``design``: the campaign's rotor is ``[spindle]``'s baseline), ``[identification]``
(``IdentificationOptions``; the source is this run's campaign), ``[validation]``, ``[model]``
and ``[loop]``. Each part draws from its own child of the seed (``part_context``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import check_choice
from surrogate_rbrdo.discrepancy.experiment import DiscrepancyTable
from surrogate_rbrdo.discrepancy.report import updated_spindle
from surrogate_rbrdo.identification.experiment import IdentificationOptions, check_source
from surrogate_rbrdo.reporting.end_to_end import write_loop_report
from surrogate_rbrdo.rig.config import RigTable
from surrogate_rbrdo.rig.truth import spindle_truth
from surrogate_rbrdo.runner.experiments import discrepancy as disc_kind
from surrogate_rbrdo.runner.experiments import identification as ident_kind
from surrogate_rbrdo.runner.experiments import rig as rig_kind
from surrogate_rbrdo.runner.experiments import study as study_kind
from surrogate_rbrdo.runner.experiments import validation as validation_kind
from surrogate_rbrdo.runner.experiments.study import StudyConfig, StudyPlan
from surrogate_rbrdo.runner.experiments.validation import (
    ModelTable,
    validation_options,
    validation_plan,
)
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.runfolder import RunFolder
from surrogate_rbrdo.runner.tables import (
    SpindleTable,
    build_theta,
    identified_inputs,
    response_speeds,
)
from surrogate_rbrdo.validation import ModelSpec, Moments, ValidationOptions
from surrogate_rbrdo.validation.campaign import file_label

#: the parts of the loop, in order: each draws from its own child of the experiment's seed
PARTS = ("rig", "identification", "study", "validation", "discrepancy")
DISCREPANCY_WHEN = ("on_disagreement", "always", "never")
#: repeats per speed the discrepancy workflow needs (``discrepancy.observables``)
MIN_REPEATS_DISCREPANCY = 5
#: speeds it needs (``discrepancy.holdout``: some are held out)
MIN_SPEEDS_DISCREPANCY = 8
#: suffix of the second round's stages (the model the discrepancy workflow updated)
UPDATED = "_updated"


@dataclass(frozen=True)
class LoopTable:
    """``[loop]``: which of the study's chosen designs are validated (default: the baseline
    and every RBRDO compromise) and when the discrepancy workflow runs
    (``"on_disagreement"``: when the validation finds model and rig disagreeing beyond
    uncertainty; ``"always"``; ``"never"``) and whether a model it updates (named effects) is
    optimised again and its designs validated on the rig (``reoptimise``)."""

    designs: tuple[str, ...] = ()
    discrepancy: str = "on_disagreement"
    reoptimise: bool = True

    def __post_init__(self) -> None:
        check_choice("discrepancy", self.discrepancy, DISCREPANCY_WHEN)
        if len(set(self.designs)) != len(self.designs):
            raise ValueError(f"designs = {list(self.designs)} is not allowed: a name appears "
                             "twice")


@dataclass(frozen=True)
class EndToEndConfig(StudyConfig):
    """The study's tables plus the rig, identification, validation and the loop's."""

    rig: RigTable = field(default_factory=RigTable)
    identification: IdentificationOptions = field(default_factory=IdentificationOptions)
    validation: ValidationOptions = field(default_factory=ValidationOptions)
    model: ModelTable = field(default_factory=ModelTable)
    discrepancy: DiscrepancyTable = field(default_factory=DiscrepancyTable)
    loop: LoopTable = field(default_factory=LoopTable)


@dataclass(frozen=True, eq=False)
class Plan:
    """The validated objects of every part (the study's with the configured θ, replaced by
    the identified one in stage ``uncertainty``)."""

    config: EndToEndConfig
    rig: Any
    study: StudyPlan
    identification: IdentificationOptions
    validation: Any
    discrepancy: Any
    disk_need: tuple[str, Any, float, str]
    base_dir: Path


@dataclass(frozen=True, eq=False)
class DiscrepancyStage:
    """Whether the discrepancy workflow ran, why, and its result."""

    ran: bool
    reason: str
    result: Any = None


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


def _check_agreement(c: EndToEndConfig, o: Any, spindle: Any) -> None:
    """The validation measures what the study optimised: its δ_lim and speed range."""
    g = spindle.geometry
    if o.delta_lim_um != c.limit.delta_lim_um:
        raise ValueError(f"validation.delta_lim_um = {o.delta_lim_um} is not allowed: the study "
                         f"has limit.delta_lim_um = {c.limit.delta_lim_um}")
    if tuple(o.speed_range_rpm) != (g.speed_min_rpm, g.speed_max_rpm):
        raise ValueError(f"validation.speed_range_rpm = {list(o.speed_range_rpm)} is not allowed:"
                         f" the study's y is the peak over [{g.speed_min_rpm}, "
                         f"{g.speed_max_rpm}] rpm")
    if c.response.kind == "at_speed":
        raise ValueError("response.kind = 'at_speed' is not allowed: the loop validates the "
                         "peak over the range (use 'peak_unbalance' or 'peak')")


def _check_discrepancy_data(loop: LoopTable, o: Any) -> None:
    """The campaign holds what the discrepancy workflow needs (unless it never runs)."""
    if loop.discrepancy == "never":
        return
    why = (f"with loop.discrepancy = {loop.discrepancy!r}: the discrepancy workflow needs >= "
           "{} {} (or set loop.discrepancy = 'never')")
    if o.repeats < MIN_REPEATS_DISCREPANCY:
        raise ValueError(f"rig.campaign.repeats = {o.repeats} is not allowed "
                         + why.format(MIN_REPEATS_DISCREPANCY, "repeats (the noise)"))
    if len(o.speeds_rpm) < MIN_SPEEDS_DISCREPANCY:
        raise ValueError(f"rig.campaign.speeds_rpm has {len(o.speeds_rpm)} speeds: not allowed "
                         + why.format(MIN_SPEEDS_DISCREPANCY, "speeds (some are held out)"))


def build(c: EndToEndConfig, base_dir: Path) -> Plan:
    given = [k for k in ("from_", "mean", "std", "corr") if getattr(c.uncertainty, k) is not None]
    if given:
        v = getattr(c.uncertainty, given[0])
        v = [list(r) if isinstance(r, tuple) else r for r in v] if isinstance(v, tuple) else v
        raise ValueError(f"uncertainty.{given[0].rstrip('_')} = {v!r} is not allowed: the loop's "
                         "stiffness block is this run's identification (uncertainty.from is "
                         "set by stage 'uncertainty'); keep distribution, thermal_max, unbalance")
    study = study_kind.build(c, base_dir)
    spindle = study.problem.spindle
    if c.rig.design is not None:
        raise ValueError(f"rig.design = {list(c.rig.design)} is not allowed: the campaign's "
                         "rotor is [spindle]'s baseline (report.baseline)")
    cfg = c.rig.config()
    truth = spindle_truth(spindle, c.rig.hidden(), c.rig.variability, study.problem.baseline)
    rig = rig_kind.rig_plan(replace(cfg, truth=truth), c.rig.effects)
    if cfg.options.trial_unbalance is None and c.identification.excitation == "trial":
        raise ValueError("rig.campaign.trial_unbalance = None is not allowed: the "
                         "identification uses trial-weight differences; give the trial mass "
                         "[position mm, kg m, phase deg], e.g. [0.0, 5e-5, 0.0]")
    _check_discrepancy_data(c.loop, cfg.options)
    ident = c.identification
    n_coef = 4 if ident.fit_on == "stiffness" else 8      # per bearing pair: k (and c) yy, zz
    if cfg.options.repeats < n_coef + 2:
        raise ValueError(f"rig.campaign.repeats = {cfg.options.repeats} is not allowed: the "
                         f"identification's scatter fit over runs needs >= {n_coef + 2} repeats"
                         f" for identification.fit_on = {ident.fit_on!r} ({n_coef} "
                         "coefficients + 2)")
    o = validation_options(c.rig, c.validation)
    _check_agreement(c, o, spindle)
    disc = c.discrepancy.options()
    return Plan(c, rig, study, ident, o, disc, rig.disk_need, Path(base_dir))


# ---------------------------------------------------------------- rig and identification
def _campaign(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    return rig_kind._campaign(p.rig, done, part_context(ctx, "rig"))


def _model_at_baseline(p: Plan) -> Any:
    """The experimenter's model of the campaign's rotor: ``[spindle]`` at its baseline."""
    return p.study.problem.spindle.model(p.study.problem.baseline)


def identification_plan(p: Plan, ctx: StageContext) -> Any:
    """The ``identification`` kind's plan on this run's campaign (its checks included)."""
    campaign = ctx.run_dir / "campaign"
    try:
        dataset = check_source(campaign, p.identification)
    except ValueError as exc:
        raise ValueError(f"identification.{exc}") from None
    return ident_kind.Plan(_model_at_baseline(p), campaign, dataset, p.identification,
                           {"path": str(campaign), "kind": "end_to_end campaign stage"})


def _demodulate(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    return ident_kind._demodulate(identification_plan(p, ctx), done,
                                  part_context(ctx, "identification"))


def _identify(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    """The identification kind's stage, then its files into ``identification/`` (the
    ``uncertainty.json`` the study's ``[uncertainty] from`` reads)."""
    plan, sub = identification_plan(p, ctx), part_context(ctx, "identification")
    res = ident_kind._identify(plan, done, sub)
    folder = subfolder(ctx.run_dir, "identification")
    ident_kind._report(replace(plan, options=replace(plan.options, figures=False)),
                       {**done, "identify": res}, folder, sub)
    return res


@dataclass(frozen=True, eq=False)
class IdentifiedTheta:
    """The study's θ: the identified stiffness block (``stiffness``), the full random vector
    (``inputs``, with the ``[uncertainty]`` unbalance block for ``peak_unbalance``), the
    response carrying θ's columns, and the provenance (file, SHA-256, speeds)."""

    stiffness: Any
    inputs: Any
    response: Any
    provenance: Mapping[str, Any]


def _uncertainty(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> IdentifiedTheta:
    """``[uncertainty] from = <this run>/identification``: the study's θ as the ``study``
    kind makes it (``runner.tables.build_theta``)."""
    pr = p.study.problem
    t = replace(p.config.uncertainty, from_=str(ctx.run_dir / "identification"))
    inputs, response, prov = build_theta(t, pr.spindle, pr.response)
    block, _ = identified_inputs(t, pr.spindle.theta_bearings,
                                 response_speeds(pr.response, pr.spindle))
    return IdentifiedTheta(block, inputs, response, dict(prov))


# ---------------------------------------------------------------- the study on identified θ
def _round(done: Mapping[str, Any], updated: bool) -> Mapping[str, Any]:
    """The results of one round under the names the study and validation stage functions
    read (``surrogate``, …, ``model``): the second round's are stored as ``<name>_updated``."""
    if not updated:
        return done
    out = dict(done)
    out.update({k[:-len(UPDATED)]: v for k, v in done.items() if k.endswith(UPDATED)})
    return out


def spindle_section(p: Plan) -> dict[str, Any]:
    """``[spindle]`` as given, with the baseline (what the discrepancy workflow updates)."""
    section = {k: v for k, v in dataclasses.asdict(p.config.spindle).items() if v is not None}
    section["baseline"] = [float(v) for v in p.study.problem.baseline]
    return section


def _updated_study(p: Plan, done: Mapping[str, Any]) -> StudyPlan:
    """The study's plan on the spindle the discrepancy workflow updated."""
    table = parse(SpindleTable, updated_spindle(spindle_section(p), p.study.problem.spindle
                                                .effects, done["discrepancy"].result), "spindle")
    return study_kind.build(replace(p.config, spindle=table), p.base_dir)


def study_plan(p: Plan, done: Mapping[str, Any], updated: bool = False) -> StudyPlan | None:
    """The study's plan with the identified θ of stage ``uncertainty``; with ``updated`` on
    the spindle the discrepancy workflow updated (``None`` unless stage ``reoptimise`` found
    it can be optimised)."""
    base = p.study
    if updated:
        r = done.get("reoptimise")
        if r is None or not r.done:
            return None
        base = _updated_study(p, done)
    th = done["uncertainty"]
    return replace(base, problem=replace(base.problem, inputs=th.inputs, response=th.response))


@dataclass(frozen=True)
class Reoptimisation:
    """Whether the updated model is optimised again (``done``) and why (``reason``)."""

    done: bool
    reason: str


def _reoptimise(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Reoptimisation:
    d = done["discrepancy"]
    if not p.config.loop.reoptimise:
        return Reoptimisation(False, "loop.reoptimise = false")
    if not d.ran:
        return Reoptimisation(False, f"the discrepancy workflow did not run ({d.reason})")
    named = [e.name for e in d.result.named_effects]
    if not named:
        return Reoptimisation(False, f"the discrepancy workflow named no effect (verdict "
                                     f"{d.result.verdict!r}): the model is unchanged")
    pr = _updated_study(p, done).problem
    for k in pr.constraints:        # every design constraint must exist for the new spindle
        try:
            k.func(pr.baseline[None, :])
        except (ValueError, ModelError) as exc:
            return Reoptimisation(False, f"the study's design constraint {k.name!r} cannot be "
                                         f"evaluated on the updated spindle (with {named}): "
                                         f"{exc}")
    return Reoptimisation(True, f"the updated spindle adds {named}")


def _study_stage(func: Any, updated: bool = False) -> Any:
    def stage(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
        plan = study_plan(p, done, updated)
        if plan is None:
            return None
        return func(plan, _round(done, updated), part_context(ctx, "study"))
    stage.__name__ = func.__name__ + (UPDATED if updated else "")
    return stage


# ---------------------------------------------------------------- validation on the rig
def validated_designs(p: Plan, done: Mapping[str, Any]) -> dict[str, int]:
    """The study's chosen designs that are validated: name → row of the verification."""
    names = done["verify"].names
    want = p.config.loop.designs or ("baseline",) + tuple(
        n for n in names if n.startswith("rbrdo"))
    for n in want:
        if n not in names:
            raise ValueError(f"loop.designs: {n!r} is not a chosen design of the study; its "
                             f"designs: {list(names)}")
    if want[0] != "baseline":
        want = ("baseline",) + tuple(n for n in want if n != "baseline")
    return {n: names.index(n) for n in want}


def _validation_plan(p: Plan, done: Mapping[str, Any], updated: bool = False) -> Any:
    """The validation of one round's designs on the rig (``None``: no such round). The
    truth is always the rig's (the model's spindle with the hidden effects); the model is
    the round's: its spindle, its FE verification."""
    d = _round(done, updated)
    if updated and done.get("verify" + UPDATED) is None:
        return None
    ver, o, c = d["verify"], p.validation, p.config
    rows = validated_designs(p, d)
    labels = {n: file_label(n) for n in rows}
    designs = {labels[n]: tuple(float(v) for v in ver.X[i]) for n, i in rows.items()}
    model = None
    if c.model.compare:
        known = {labels[n]: {"peak": Moments.from_estimate(ver.fe, i, ver.n_theta,
                                                           o.confidence)}
                 for n, i in rows.items()}
        sur, _ = study_kind._final(d)
        model = ModelSpec({"peak": sur.model.response}, done["uncertainty"].inputs,
                          c.model.n_samples, spindle_model=study_plan(p, done, updated)
                          .problem.spindle.model, known=known,
                          name="updated model" if updated else "model")
    spindle = p.study.problem.spindle
    template = spindle_truth(spindle, c.rig.hidden(), c.rig.variability)
    where = "study_updated" if updated else "study"
    source = {"designs": f"stage verify{UPDATED if updated else ''} ({where}/verification.csv)",
              "study_labels": labels,
              "known_from_study": f"peak: the FE verification of {where} (n_theta fresh θ)"}
    o = replace(o, baseline=labels["baseline"])
    return validation_plan(template, spindle, designs, o, model, source)


def _measure(p: Plan, done: Mapping[str, Any], ctx: StageContext, updated: bool = False
             ) -> Any:
    plan = _validation_plan(p, done, updated)
    return None if plan is None else validation_kind._measure(
        plan, _round(done, updated), part_context(ctx, "validation"))


def _model(p: Plan, done: Mapping[str, Any], ctx: StageContext, updated: bool = False) -> Any:
    plan = _validation_plan(p, done, updated)
    return None if plan is None else validation_kind._model(
        plan, _round(done, updated), part_context(ctx, "validation"))


# ---------------------------------------------------------------- discrepancy
def discrepancy_plan(p: Plan, ctx: StageContext) -> Any:
    """The ``discrepancy`` kind's plan on this run's campaign: the model is ``[spindle]`` at
    the campaign's design (the study's baseline)."""
    pr = p.study.problem
    return disc_kind.Plan(replace(pr.spindle, baseline=pr.baseline), spindle_section(p),
                          p.discrepancy, None, ctx.run_dir / "campaign", None)


def _discrepancy(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> DiscrepancyStage:
    bad = done["model"].disagreements
    when = p.config.loop.discrepancy
    if when == "never" or (when == "on_disagreement" and not bad):
        why = ("loop.discrepancy = 'never'" if when == "never" else
               "the validation found no disagreement beyond uncertainty")
        return DiscrepancyStage(False, why)
    why = ("loop.discrepancy = 'always'" if when == "always" else
           f"{len(bad)} model-vs-rig disagreement(s): "
           + "; ".join(f"{v.design} {v.quantity} {v.metric}" for v in bad))
    res = disc_kind._analyse(discrepancy_plan(p, ctx), {"campaign": ctx.run_dir / "campaign"},
                             part_context(ctx, "discrepancy"))
    return DiscrepancyStage(True, why, res)


# ---------------------------------------------------------------- report
def subfolder(run_dir: Path, name: str) -> RunFolder:
    """A part's folder of the run as a :class:`RunFolder` (its kind's report writes there)."""
    (run_dir / name).mkdir(exist_ok=True)
    return RunFolder(path=run_dir / name, experiment=run_dir.parent.name, run_id=run_dir.name)


def _study_report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext,
                  updated: bool) -> None:
    """The study kind's tables and figures of one round into ``study[_updated]/``."""
    plan = study_plan(p, done, updated)
    if plan is None or done.get("verify" + (UPDATED if updated else "")) is None:
        return
    sub = subfolder(run.path, "study" + (UPDATED if updated else ""))
    study_kind._report(plan, _round(done, updated), sub, part_context(ctx, "study"))


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    for updated in (False, True):
        _study_report(p, done, run, ctx, updated)
    if done["discrepancy"].ran:
        disc_kind._report(discrepancy_plan(p, ctx), {"campaign": run.path / "campaign",
                                                    "analyse": done["discrepancy"].result},
                          subfolder(run.path, "discrepancy"), part_context(ctx, "discrepancy"))
    pr, c = p.study.problem, p.config
    timings = {k: float(v.get("time_s", 0.0)) for k, v in run.meta.get("stages", {}).items()}
    return write_loop_report(
        run.path, truth=p.rig.rig.truth, campaign=done["campaign"],
        campaign_options=p.rig.rig.options, model=_model_at_baseline(p),
        identification=done["identify"], identification_figures=p.identification.figures,
        convergence_speed_rpm=p.identification.convergence_speed_rpm,
        theta=done["uncertainty"], theta_bearings=pr.spindle.theta_bearings,
        verification=done["verify"], limit_um=c.limit.delta_lim_um, validation=done["model"],
        discrepancy=done["discrepancy"], timings=timings, rig_figures=p.rig.rig.figures,
        updated=(done.get("verify" + UPDATED), done.get("model" + UPDATED)),
        reoptimise=done["reoptimise"])


register_kind(Kind(
    name="end_to_end",
    summary="the data-driven loop in one run: rig campaign with trial weights → "
            "identification → the study's θ → RBRDO at every P_target → validation of the "
            "chosen designs on the rig → discrepancy when model and rig disagree → report.md",
    schema=EndToEndConfig,
    stages=(Stage("campaign", _campaign), Stage("demodulate", _demodulate),
            Stage("identify", _identify),
            Stage("uncertainty", _uncertainty),
            Stage("surrogate", _study_stage(study_kind._surrogate)),
            Stage("design_model", _study_stage(study_kind._design_model)),
            Stage("optimise", _study_stage(study_kind._optimise)),
            Stage("refine", _study_stage(study_kind._refine)),
            Stage("verify", _study_stage(study_kind._verify)),
            Stage("measure", _measure), Stage("model", _model),
            Stage("discrepancy", _discrepancy), Stage("reoptimise", _reoptimise),
            *(Stage(f.__name__.lstrip("_") + UPDATED, _study_stage(f, updated=True))
              for f in (study_kind._surrogate, study_kind._design_model, study_kind._optimise,
                        study_kind._refine, study_kind._verify)),
            Stage("measure" + UPDATED, partial(_measure, updated=True)),
            Stage("model" + UPDATED, partial(_model, updated=True))),
    report=_report,
    build=build,
))
