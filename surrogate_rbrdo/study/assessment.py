"""A surrogate validation's tables (:class:`SurrogateValidationConfig`) and the checked
plan they describe (:func:`build_assessment`): surrogate variants to compare with the full FE
model (``surrogates.assessment``).

The ``[surrogate]`` table is variant ``main``; ``[validation.variants]`` adds named variants
as overrides of it (``raw = {transform = "none"}``, ``res = {structure = "resonance"}``; a
variant of another structure inherits only the keys its structure has). Variant names and
design labels are labels (``core.validate.check_label``: they name files).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.memory import check_memory, memory_needs
from surrogate_rbrdo.core.validate import check_int, check_label, check_positive
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.study.config import LimitTable, UncertaintyTable, build_theta
from surrogate_rbrdo.surrogates.assessment import truth_memory_bytes
from surrogate_rbrdo.surrogates.structured import STRUCTURES, JointDOEOptions, surrogate_options

#: the default designs: resonant, far subcritical and three near the failure boundary
DEFAULT_DESIGNS = {
    "resonant": (2000.0, 650.0, 60.0),
    "subcritical_far": (2000.0, 330.0, 75.0),
    "boundary_a": (1000.0, 425.0, 60.0),
    "boundary_b": (3000.0, 480.0, 70.0),
    "boundary_c": (2000.0, 460.0, 65.0),
}


@dataclass(frozen=True)
class ValidationTable:
    """``[validation]``: test points, the θ sample, designs (label → ``[F N, L mm, D mm]``),
    variants (name → ``[surrogate]`` overrides), tolerance, n_c check size."""

    n_test: int = 120
    n_theta: int = 1000
    designs: dict[str, tuple[float, float, float]] = field(
        default_factory=lambda: dict(DEFAULT_DESIGNS))
    variants: dict[str, dict[str, Any]] = field(default_factory=dict)
    rel_tol: float = 0.05
    n_theta_nc: int = 40

    def __post_init__(self) -> None:
        check_int("n_test", self.n_test, minimum=2)
        check_int("n_theta", self.n_theta, minimum=2)
        check_positive("rel_tol", self.rel_tol)
        if self.rel_tol > 1.0:
            raise ValueError(f"rel_tol = {self.rel_tol!r} is not allowed: must be at most 1 (a "
                             "relative error above 100 % accepts any surrogate)")
        check_int("n_theta_nc", self.n_theta_nc, minimum=2)
        if not self.designs:
            raise ValueError("designs = {} is not allowed: give at least one design")
        for label in self.designs:
            check_label("designs", label)
        for name in self.variants:
            check_label("variants", name)
        if "main" in self.variants:
            raise ValueError("variants.main is not allowed: 'main' is the [surrogate] table")


@dataclass(frozen=True)
class SurrogateValidationConfig:
    """The tables of a ``surrogate_validation`` config."""

    spindle: SpindleTable = field(default_factory=SpindleTable)
    uncertainty: UncertaintyTable = field(default_factory=UncertaintyTable)
    limit: LimitTable = field(default_factory=LimitTable)
    response: ResponseSpec = field(default_factory=ResponseSpec)
    surrogate: dict[str, Any] = field(default_factory=dict)
    validation: ValidationTable = field(default_factory=ValidationTable)


@dataclass(frozen=True, eq=False)
class AssessmentPlan:
    """The spindle, θ, the limit, the response, the variants (name → structure options), the
    joint box of the test points, the designs (label → x) and the ``[validation]`` table."""

    spindle: Any
    inputs: Any
    limit: Any
    response: ResponseSpec
    variants: dict[str, Any]
    test_box: JointDOEOptions
    designs: dict[str, np.ndarray]
    validation: ValidationTable


def _variant(base: Mapping[str, Any], over: Mapping[str, Any], name: str,
             response: ResponseSpec) -> Any:
    """Variant ``name``: ``[surrogate]`` with ``over``; a variant of another structure
    inherits only the keys its structure has."""
    name_s = over.get("structure", base.get("structure", "global"))
    keep = base
    if name_s != base.get("structure", "global") and isinstance(name_s, str) \
            and name_s in set(STRUCTURES):
        fields = STRUCTURES[name_s].options.__dataclass_fields__
        keep = {k: v for k, v in base.items() if k in fields}
    return surrogate_options({**keep, **over}, response, f"validation.variants.{name}")


def build_assessment(c: SurrogateValidationConfig, base_dir: str | Path = "."
                     ) -> AssessmentPlan:
    """The checked plan of a ``surrogate_validation`` config: every variant's options, the
    designs in the design box, the memory of the FE truth and of each structure (errors
    name the dotted path)."""
    spindle = build_spindle(c.spindle, base_dir)
    g = spindle.geometry
    if c.response.kind == "at_speed" and not (g.speed_min_rpm <= c.response.speed_rpm
                                              <= g.speed_max_rpm):
        raise ValueError(f"response.speed_rpm = {c.response.speed_rpm} is not allowed: must "
                         f"lie in the spindle's speed range [{g.speed_min_rpm}, "
                         f"{g.speed_max_rpm}] rpm")
    inputs, response, _ = build_theta(c.uncertainty, spindle, c.response)
    tables = {"surrogate": c.surrogate, **{f"validation.variants.{k}": {**c.surrogate, **v}
                                            for k, v in c.validation.variants.items()}}
    for where, t in tables.items():
        if t.get("structure") == "fe":
            raise ValueError(f"{where}.structure = 'fe' is not allowed here: a surrogate "
                             "validation needs a surrogate (use 'global', 'resonance' or "
                             "'substructure')")
    variants = {"main": surrogate_options(c.surrogate, response, "surrogate")}
    for name, over in c.validation.variants.items():
        variants[name] = _variant(c.surrogate, over, name, response)
    designs = {}
    for label, xv in c.validation.designs.items():
        try:
            designs[label] = spindle.design_map.check(np.asarray(xv, dtype=float))
        except ValueError as exc:
            raise ValueError(f"validation.designs.{label}: {exc}") from None
    main = variants["main"]
    box = main if isinstance(main, JointDOEOptions) else JointDOEOptions(
        n_jobs=main.n_jobs, backend=main.backend)
    v = c.validation
    check_memory({f"validation.{k}": (getattr(v, k), b) for k, b in truth_memory_bytes(
        n_test=v.n_test, n_theta=v.n_theta, n_inputs=inputs.dim, n_designs=len(designs),
        n_variants=len(variants)).items()})
    for name, o in variants.items():        # structures that state their memory
        check_memory(memory_needs(o, "surrogate" if name == "main" else
                                  f"validation.variants.{name}"))
    return AssessmentPlan(spindle, inputs, c.limit.limit(), response, variants, box, designs, v)


__all__ = ["DEFAULT_DESIGNS", "AssessmentPlan", "SurrogateValidationConfig", "ValidationTable",
           "build_assessment"]
