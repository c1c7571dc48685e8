"""Experiment kind ``study``: the RBRDO study end to end (:mod:`surrogate_rbrdo.study`).

Stages: ``surrogate`` (the ``[surrogate]`` structure, trained on FE points) → ``design_model``
(g_det) → ``optimise`` (RBRDO at every P_target, then RDO/RBDO/deterministic; one CRN sample)
→ ``refine`` (``[refine]``, off by default) → ``verify`` (the chosen designs with the full FE
model); the report writes the tables and figures. Streams of the seed: 0 surrogate, 1 design
model, 2 the CRN sample, 3 optimisation, 4 verification, 5 refinement.

Tables (every key optional; unknown keys raise): ``[spindle]``, ``[uncertainty]``,
``[limit]``, ``[response]`` (``ResponseSpec``), ``[surrogate]`` (``structure`` selects the
options class: ``GlobalOptions``, ``ResonanceOptions``, ``SubstructureOptions``,
``FEOptions``), ``[design_model]`` (fitted only when g_det needs it), ``[deterministic]``,
``[[constraints]]`` (``name``, ``expression``, ``scale``: ``DesignConstraint``),
``[optimization]`` (``OptimizationOptions``), ``[verification]``, ``[report]``, ``[refine]``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.reporting import study as tables
from surrogate_rbrdo.reporting.spindle import check_overview
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.tables import (
    DeterministicTable,
    LimitTable,
    SpindleTable,
    UncertaintyTable,
    build_spindle,
    build_theta,
)
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.study.constraints import expression_constraints
from surrogate_rbrdo.study.memory import check_study_memory
from surrogate_rbrdo.study.options import OptimizationOptions, VerificationOptions
from surrogate_rbrdo.study.problem import DESIGN_NAMES, Problem
from surrogate_rbrdo.study.stages import optimise, refine, verify
from surrogate_rbrdo.surrogates.design_model import DesignModelOptions, fit_design_model
from surrogate_rbrdo.surrogates.refine import RefineOptions
from surrogate_rbrdo.surrogates.structured import STRUCTURES, train_surrogate


@dataclass(frozen=True)
class StudyReportTable:
    """``[report]``: the baseline design ``[F N, L mm, D mm]`` and the spindle figures."""

    baseline: tuple[float, float, float] | None = None
    n_speeds: int = 300
    campbell_speeds: int = 25
    n_modes: int = 6

    def __post_init__(self) -> None:
        check_int("n_speeds", self.n_speeds, minimum=2)
        check_int("campbell_speeds", self.campbell_speeds, minimum=2)
        check_int("n_modes", self.n_modes, minimum=1)


@dataclass(frozen=True)
class ConstraintTable:
    """``[[constraints]]``: ``g(x) <= 0`` over the design variables (``preload_N``,
    ``span_mm``, ``diameter_mm``), e.g. ``expression = "span_mm / diameter_mm <= 9"``."""

    name: str
    expression: str
    scale: float = 1.0


@dataclass(frozen=True)
class StudyConfig:
    """The tables of a ``study`` config."""

    spindle: SpindleTable = field(default_factory=SpindleTable)
    uncertainty: UncertaintyTable = field(default_factory=UncertaintyTable)
    limit: LimitTable = field(default_factory=LimitTable)
    response: ResponseSpec = field(default_factory=ResponseSpec)
    surrogate: dict[str, Any] = field(default_factory=dict)
    design_model: DesignModelOptions = field(default_factory=DesignModelOptions)
    deterministic: DeterministicTable = field(default_factory=DeterministicTable)
    constraints: tuple[ConstraintTable, ...] = ()
    optimization: OptimizationOptions = field(default_factory=OptimizationOptions)
    verification: VerificationOptions = field(default_factory=VerificationOptions)
    report: StudyReportTable = field(default_factory=StudyReportTable)
    refine: RefineOptions = field(default_factory=RefineOptions)


@dataclass(frozen=True, eq=False)
class StudyPlan:
    """The validated objects of a study config."""

    problem: Problem
    surrogate: Any
    design_model: DesignModelOptions
    optimization: OptimizationOptions
    verification: VerificationOptions
    report: StudyReportTable
    refine: RefineOptions
    theta_source: dict[str, Any] | None = None


def surrogate_options(table: Mapping[str, Any], response: ResponseSpec, where: str) -> Any:
    """The options of the structure a ``[surrogate]`` table selects (``structure``, default
    ``"global"``), checked against ``response``."""
    table = dict(table)
    name = table.pop("structure", "global")
    if not isinstance(name, str) or name not in set(STRUCTURES):
        raise ValueError(f"{where}.structure = {name!r} is not allowed: must be one of "
                         f"{sorted(STRUCTURES)}")
    options = parse(STRUCTURES[name].options, table, where)
    try:
        options.check_response(response)
    except ValueError as exc:
        raise ValueError(f"{where}.{exc}") from None
    return options


def build(c: StudyConfig, base_dir: Path) -> StudyPlan:
    spindle = build_spindle(c.spindle, base_dir)
    inputs, r, theta_source = build_theta(c.uncertainty, spindle, c.response)
    g = spindle.geometry
    if r.kind == "at_speed" and not g.speed_min_rpm <= r.speed_rpm <= g.speed_max_rpm:
        raise ValueError(f"response.speed_rpm = {r.speed_rpm} is not allowed: must lie in the "
                         f"spindle's speed range [{g.speed_min_rpm}, {g.speed_max_rpm}] rpm "
                         "(the bearing laws are fitted there)")
    sur = surrogate_options(c.surrogate, r, "surrogate")
    det = c.deterministic.options(g.speed_max_rpm)
    cons = c.deterministic.constraints(spindle)
    for i, e in enumerate(c.constraints):
        if e.name in {k.name for k in cons}:
            raise ValueError(f"constraints[{i}].name = {e.name!r} is not allowed: taken by "
                             f"{[k.name for k in cons]}")
        try:
            cons += expression_constraints([vars(e)], spindle.design_map.names)
        except ValueError as exc:
            raise ValueError(f"constraints[{i}]: {exc}") from None
    if c.refine.rounds and not STRUCTURES[sur.structure].refinable:
        why = ("there is no surrogate to refine" if sur.structure == "fe" else
               "the refinement loop adds (x, θ) points, and this surrogate is trained on "
               "designs only")
        raise ValueError(f"refine.rounds = {c.refine.rounds} is not allowed with "
                         f"surrogate.structure = {sur.structure!r}: {why} (use rounds = 0)")
    base = c.report.baseline if c.report.baseline is not None else spindle.baseline
    basis = c.deterministic.design_theta(inputs, r)
    try:
        problem = Problem(spindle, inputs, c.limit.limit(), r, det, base, cons, basis)
    except ValueError as exc:
        raise ValueError(f"report.baseline: {exc}") from None
    check_study_memory(problem, sur, c.optimization, c.verification,
                       ("design_model", c.design_model), ("refine", c.refine))
    rep = c.report    # the baseline and one compromise (tables.spotlight)
    check_overview(spindle, {"baseline": base, "compromise": base}, n_speeds=rep.n_speeds,
                   campbell_speeds=rep.campbell_speeds, n_modes=rep.n_modes, where="report")
    return StudyPlan(problem, sur, c.design_model, c.optimization, c.verification, c.report,
                     c.refine, theta_source)


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


def _final(done: Mapping[str, Any]) -> tuple[Any, Any]:
    """The surrogate and the optimisation the verification and the tables use."""
    ref = done["refine"]
    return ref.surrogate or done["surrogate"], ref.optimisation or done["optimise"]


def _verify(p: StudyPlan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    sur, opt = _final(done)
    return verify(p.problem, sur, done["design_model"], opt, p.optimization, p.verification,
                  crn=ctx.seed_sequence(2), rng=ctx.stream(4),
                  cache=fe_cache(ctx.cache_dir, "fe_verification"), progress=ctx.progress,
                  label=ctx.label)


def _report(p: StudyPlan, done: Mapping[str, Any], run: Any, ctx: StageContext
            ) -> dict[str, Any]:
    sur, opt = _final(done)
    ver, w = done["verify"], p.optimization.weights
    run.write_json("surrogate_info.json", {**sur.to_dict(), **dict(sur.model.info)})
    if done["design_model"] is not None:
        run.write_json("design_model_validation.json", done["design_model"].validation)
    if done["refine"].rounds:
        run.write_rows("refine.csv", tables.refine_rows(done["refine"].rounds))
    fronts = tables.front_rows(opt)
    if fronts:
        run.write_rows("pareto_fronts.csv", fronts)
    tables.front_figures(run, opt, w, quantity=p.problem.response.label,
                         model_in_loop=sur.in_loop, baseline=p.problem.baseline)
    g = p.problem.spindle.geometry
    ver_rows = tables.verification_rows(ver, (g.speed_min_rpm, g.speed_max_rpm))
    run.write_rows("verification.csv", ver_rows)
    if ver.fronts is not None:
        run.write_rows("front_verification.csv", ver.fronts.rows(DESIGN_NAMES))
    run.write_rows("strategy_comparison.csv", tables.strategy_rows(opt, ver))
    mbr = tables.mbr_rows(opt, ver, w, sur.in_loop)
    if mbr:
        run.write_rows("mbr.csv", mbr)
    comp = tables.compromise_rows(opt, w)
    run.write_rows("compromises.csv", comp)
    rep = p.report
    tables.spindle_figures(run, p.problem.spindle, tables.spotlight(opt, ver),
                           n_speeds=rep.n_speeds, campbell_speeds=rep.campbell_speeds,
                           n_modes=rep.n_modes, limit_um=p.problem.limit.threshold * 1e6)
    meta = tables.study_meta(p.problem, p.optimization, done["surrogate"], done["design_model"],
                             done["optimise"], done["refine"], done["verify"])
    if p.theta_source is not None:       # [uncertainty] from: the identified model's origin
        meta["uncertainty_from"] = p.theta_source
    run.write_json("study_meta.json", meta)
    keep = ("design", "preload_N", "span_mm", "diameter_mm", "mean_um_fe", "std_um_fe",
            "pf_pct_fe", "mean_um_surrogate", "std_um_surrogate", "pf_pct_surrogate")
    summary = [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()
                if k in keep} for r in ver_rows]
    return {"summary": summary, "mbr": mbr, "compromises": comp, "meta": meta}


register_kind(Kind(
    name="study",
    summary="RBRDO study: surrogate → g_det design model → RBRDO per P_target, RDO, RBDO, "
            "deterministic → refinement → full-FE verification → tables and figures",
    schema=StudyConfig,
    stages=(Stage("surrogate", _surrogate), Stage("design_model", _design_model),
            Stage("optimise", _optimise), Stage("refine", _refine), Stage("verify", _verify)),
    report=_report,
    build=build,
    defaults="with every problem table left out a study is the paper's published problem "
             "(reference spindle, in-phase G 2.5 unbalance, θ = the Table 4 stiffness CoVs, "
             "y = peak over the speed range, δ_lim = 19.5 µm, the f_n1 guard): NOT the "
             "credible reference problem (credible_problem(), experiments/quick.toml, which "
             "states every table)",
))
