"""Experiment kind ``surrogate_validation``: surrogate structures against the full FE model.

The ``[surrogate]`` table is variant ``main``; ``[validation.variants]`` adds named variants
as overrides of it (``raw = {transform = "none"}``, ``res = {structure = "resonance"}``; a
variant of another structure inherits only the keys its structure has). Every variant trains
from the same seed stream, so variants with the same DOE settings get the same DOE, and the
FE cache is shared. Stages: ``truth`` (FE at ``n_test`` fresh LHS points of the joint box,
full-FE MC at the ``designs`` on ``n_theta`` θ, FE resonance quantities if a resonance
variant needs them) → ``variants`` (train, test points, LOO, MC comparison). Tables:
``metrics.csv``, ``loo.csv``, ``mc_comparison.csv``, ``cost.csv`` (the FE evaluations each
training used, counted at the sampler: computed now or loaded from the FE cache, so the table
is the same on a rerun; and the P_f accuracy; no timings), ``resonance_submodels.csv`` and
``nc_at_designs.csv`` (resonance variants), parity figures per variant. ``calls.json`` (and
``meta.json``) split the counts into FE calls computed and cache hits, per stage and variant.
Variant names and design labels are labels (``core.validate.check_label``: they name files).
``y`` is the ``[response]`` (default the peak amplitude of the geometry's unbalance;
``kind = "peak_unbalance"``: the credible problem's random-unbalance peak, θ with its
unbalance columns from ``[uncertainty]``, the FE side the FE model's own peak search).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.memory import check_memory, memory_needs
from surrogate_rbrdo.core.validate import check_int, check_label, check_positive
from surrogate_rbrdo.reporting import tables_surrogate as tab
from surrogate_rbrdo.reporting.plots_surrogate import parity_figures
from surrogate_rbrdo.runner.experiments.study import surrogate_options
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.tables import (
    LimitTable,
    SpindleTable,
    UncertaintyTable,
    build_spindle,
    build_theta,
)
from surrogate_rbrdo.sampling.fe import fe_cache
from surrogate_rbrdo.spindle.evaluate import ResponseSpec
from surrogate_rbrdo.surrogates.assessment import (
    Assessment,
    FETruth,
    fe_truth,
    train_and_assess,
    truth_memory_bytes,
)
from surrogate_rbrdo.surrogates.structured import STRUCTURES, JointDOEOptions

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
    spindle: SpindleTable = field(default_factory=SpindleTable)
    uncertainty: UncertaintyTable = field(default_factory=UncertaintyTable)
    limit: LimitTable = field(default_factory=LimitTable)
    response: ResponseSpec = field(default_factory=ResponseSpec)
    surrogate: dict[str, Any] = field(default_factory=dict)
    validation: ValidationTable = field(default_factory=ValidationTable)


@dataclass(frozen=True, eq=False)
class Plan:
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
    name_s = over.get("structure", base.get("structure", "global"))
    keep = base
    if name_s != base.get("structure", "global") and isinstance(name_s, str) \
            and name_s in set(STRUCTURES):
        fields = STRUCTURES[name_s].options.__dataclass_fields__
        keep = {k: v for k, v in base.items() if k in fields}
    return surrogate_options({**keep, **over}, response, f"validation.variants.{name}")


def build(c: SurrogateValidationConfig, base_dir: Path) -> Plan:
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
    return Plan(spindle, inputs, c.limit.limit(), response, variants, box, designs, v)


def _truth(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> FETruth:
    need_res = any(v.structure == "resonance" for v in p.variants.values())
    return fe_truth(p.spindle, p.inputs, np.vstack(list(p.designs.values())), p.test_box,
                    n_test=p.validation.n_test, n_theta=p.validation.n_theta,
                    rng_test=ctx.stream(1), rng_theta=ctx.stream(2),
                    n_theta_nc=p.validation.n_theta_nc if need_res else None,
                    cache=fe_cache(ctx.cache_dir), mc_cache=fe_cache(ctx.cache_dir, "fe_mc"),
                    progress=ctx.progress, label=ctx.label, response=p.response)


def _variants(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> tuple[Assessment, ...]:
    """Every variant trained from the same seed stream (same DOE settings, same DOE)."""
    return tuple(train_and_assess(
        name, p.spindle, p.inputs, p.limit, options, done["truth"], rng=ctx.stream(0),
        cache=fe_cache(ctx.cache_dir), rel_tol=p.validation.rel_tol, progress=ctx.progress,
        label=ctx.label, response=p.response) for name, options in p.variants.items())


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    t, vs = done["truth"], done["variants"]
    tables = tab.validation_tables(list(p.designs), t, vs, p.limit.threshold,
                                   p.validation.n_theta_nc)
    for name, (header, rows) in tables.items():
        run.write_csv(name, header, rows)
    for a in vs:
        for name, fig in parity_figures(a.name, t.y, a.y_pred).items():
            run.save_figure(name, fig)
    run.write_json("surrogate_info.json", {a.name: {k: v for k, v in a.trained.to_dict().items()
                                                    if k != "options"} for a in vs})
    meta = {**tab.validation_calls(t, vs), "n_theta": p.validation.n_theta,
            "n_test": int(t.y.size)}
    run.write_json("calls.json", meta)
    keep = ("variant", "design", "mean_rel_err", "std_rel_err", "pf_fe", "pf_sur", "ok_mean",
            "ok_std", "ok_pf")
    return {"variants": [a.name for a in vs], "meta": meta,
            "summary": [{k: x for k, x in zip(tab.MC_HEADER, r, strict=True) if k in keep}
                        for r in tables["mc_comparison.csv"][1]]}


register_kind(Kind(
    name="surrogate_validation",
    summary="surrogate variants (structures, transforms, active learning) against the full "
            "FE model: test-point metrics, LOO, μ/σ/P_f at designs, cost",
    schema=SurrogateValidationConfig,
    stages=(Stage("truth", _truth), Stage("variants", _variants)),
    report=_report,
    build=build,
))
