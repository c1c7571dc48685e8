"""A study config's tables (:class:`StudyConfig`) and the objects they describe
(:class:`StudyPlan`, :func:`build_study`): the problem, the surrogate structure's options,
the design model, the optimisation, the verification, the
refinement.

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

from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.study.config import (
    DeterministicTable,
    LimitTable,
    UncertaintyTable,
    build_theta,
)
from surrogate_rbrdo.study.constraints import expression_constraints
from surrogate_rbrdo.study.memory import check_study_memory
from surrogate_rbrdo.study.options import OptimizationOptions, VerificationOptions
from surrogate_rbrdo.study.problem import Problem
from surrogate_rbrdo.surrogates.design_model import DesignModelOptions
from surrogate_rbrdo.surrogates.refine import RefineOptions
from surrogate_rbrdo.surrogates.structured import STRUCTURES, surrogate_options


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


def build_study(c: StudyConfig, base_dir: str | Path = ".") -> StudyPlan:
    """The validated objects of a study config (files relative to ``base_dir``); raises
    ``ValueError`` naming the dotted path of the field. Before any work: the structure's
    options against the response, the constraints, the refinement against the structure,
    the memory of every stage (the report's spindle figures are checked by
    ``reporting.spindle.check_overview``).

    >>> plan = build_study(StudyConfig(spindle=SpindleTable(geometry="credible")))
    >>> plan.problem.response.kind, plan.surrogate.structure
    ('peak', 'global')
    """
    spindle = build_spindle(c.spindle, base_dir)
    inputs, r, theta_source = build_theta(c.uncertainty, spindle, c.response)
    g = spindle.geometry
    if r.kind == "at_speed" and not g.speed_min_rpm <= r.speed_rpm <= g.speed_max_rpm:
        raise ValueError(f"response.speed_rpm = {r.speed_rpm} is not allowed: must lie in the "
                         f"spindle's speed range [{g.speed_min_rpm}, {g.speed_max_rpm}] rpm "
                         "(the bearing laws are fitted there)")
    sur = surrogate_options(c.surrogate, r, "surrogate")
    det = c.deterministic.options(r.speed_rpm if r.kind == "at_speed" else g.speed_max_rpm)
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
    return StudyPlan(problem, sur, c.design_model, c.optimization, c.verification, c.report,
                     c.refine, theta_source)


def final_models(results: Mapping[str, Any]) -> tuple[Any, Any]:
    """The surrogate and the optimisation the verification and the tables use, from the
    study's stage results by name (``surrogate``, ``optimise``, ``refine``): the refined ones
    where the refinement made them."""
    ref = results["refine"]
    return ref.surrogate or results["surrogate"], ref.optimisation or results["optimise"]


__all__ = ["ConstraintTable", "StudyConfig", "StudyPlan", "StudyReportTable", "build_study",
           "final_models"]
