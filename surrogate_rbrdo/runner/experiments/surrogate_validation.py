"""Experiment kind ``surrogate_validation``: surrogate structures against the full FE model.

The ``[surrogate]`` table is variant ``main``; ``[validation.variants]`` adds named variants
as overrides of it (``raw = {transform = "none"}``, ``res = {structure = "resonance"}``; a
variant of another structure inherits only the keys its structure has). Every variant trains
from the same seed stream, so variants with the same DOE settings get the same DOE, and the
FE cache is shared. Stages: ``truth`` (FE at ``n_test`` fresh LHS points of the joint box,
full-FE MC at the ``designs`` on ``n_theta`` θ, FE resonance quantities if a resonance
variant needs them) → ``variants`` (train, test points, LOO, MC comparison). Tables:
``metrics.csv``, ``loo.csv``, ``mc_comparison.csv``, ``cost.csv`` (training FE calls and the
P_f accuracy; no timings), ``resonance_submodels.csv`` and ``nc_at_designs.csv`` (resonance
variants), parity figures per variant. ``y`` is the peak amplitude.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.counting import CallCounter, CountingResponse
from surrogate_rbrdo.core.protocols import Prediction
from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.doe import lhs
from surrogate_rbrdo.reporting import tables_surrogate as tab
from surrogate_rbrdo.reporting.plots_surrogate import parity_plot
from surrogate_rbrdo.runner.experiments.study import surrogate_options
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.tables import (
    LimitTable,
    SpindleTable,
    UncertaintyTable,
    build_inputs,
    build_spindle,
    require_memory,
)
from surrogate_rbrdo.sampling.fe import fe_cache, sample_designs, sample_positive
from surrogate_rbrdo.spindle.evaluate import PeakAmplitudeResponse, ResponseSpec
from surrogate_rbrdo.surrogates.structured import (
    STRUCTURES,
    JointDOEOptions,
    sample_resonance,
    train_surrogate,
)
from surrogate_rbrdo.surrogates.validation import compare_mc

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
        if "main" in self.variants:
            raise ValueError("variants.main is not allowed: 'main' is the [surrogate] table")


@dataclass(frozen=True)
class SurrogateValidationConfig:
    spindle: SpindleTable = field(default_factory=SpindleTable)
    uncertainty: UncertaintyTable = field(default_factory=UncertaintyTable)
    limit: LimitTable = field(default_factory=LimitTable)
    surrogate: dict[str, Any] = field(default_factory=dict)
    validation: ValidationTable = field(default_factory=ValidationTable)


@dataclass(frozen=True, eq=False)
class Plan:
    spindle: Any
    inputs: Any
    limit: Any
    variants: dict[str, Any]
    test_box: JointDOEOptions
    designs: dict[str, np.ndarray]
    validation: ValidationTable


def _variant(base: Mapping[str, Any], over: Mapping[str, Any], name: str) -> Any:
    name_s = over.get("structure", base.get("structure", "global"))
    keep = base
    if name_s != base.get("structure", "global") and isinstance(name_s, str) \
            and name_s in set(STRUCTURES):
        fields = STRUCTURES[name_s].options.__dataclass_fields__
        keep = {k: v for k, v in base.items() if k in fields}
    return surrogate_options({**keep, **over}, ResponseSpec(), f"validation.variants.{name}")


def build(c: SurrogateValidationConfig, base_dir: Path) -> Plan:
    spindle = build_spindle(c.spindle, base_dir)
    inputs = build_inputs(c.uncertainty, spindle.theta_bearings)
    tables = {"surrogate": c.surrogate, **{f"validation.variants.{k}": {**c.surrogate, **v}
                                            for k, v in c.validation.variants.items()}}
    for where, t in tables.items():
        if t.get("structure") == "fe":
            raise ValueError(f"{where}.structure = 'fe' is not allowed here: a surrogate "
                             "validation needs a surrogate (use 'global', 'resonance' or "
                             "'substructure')")
    variants = {"main": surrogate_options(c.surrogate, ResponseSpec(), "surrogate")}
    for name, over in c.validation.variants.items():
        variants[name] = _variant(c.surrogate, over, name)
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
    require_memory("validation.n_theta", v.n_theta, 4 * 8.0 * len(designs) * v.n_theta *
                   (1 + len(variants)), "designs × n_theta × 4 arrays per variant")
    require_memory("validation.n_test", v.n_test, 8 * 8.0 * v.n_test * len(variants),
                   "the test points")
    return Plan(spindle, inputs, c.limit.limit(), variants, box, designs, v)


@dataclass(frozen=True, eq=False)
class Truth:
    """FE values: test points ``Z``/``y``, the θ sample, FE-MC ``y_fe`` at the designs,
    resonance quantities (``None`` without a resonance variant) and counted FE calls."""

    Z: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    y_fe: np.ndarray
    resonance: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None
    calls: Mapping[str, int]


def _truth(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Truth:
    cache, box = fe_cache(ctx.cache_dir), p.test_box
    c_test, c_mc = CallCounter(), CallCounter()
    Z = lhs(p.validation.n_test, box.bounds(p.spindle, p.inputs), rng=ctx.stream(1))
    Z, y = sample_positive(ResponseSpec().pointwise(p.spindle), Z, n_jobs=box.n_jobs,
                           backend=box.backend, cache=cache, counter=c_test,
                           progress=ctx.progress, desc=f"{ctx.label} FE test points")
    theta = p.inputs.sample(p.validation.n_theta, rng=ctx.stream(2))
    X = np.vstack(list(p.designs.values()))
    y_fe = sample_designs(PeakAmplitudeResponse(p.spindle), X, theta, n_jobs=box.n_jobs,
                          cache=fe_cache(ctx.cache_dir, "fe_mc"), counter=c_mc,
                          progress=ctx.progress, desc=f"{ctx.label} full-FE MC")
    res = None
    if any(v.structure == "resonance" for v in p.variants.values()):
        n_th = min(p.validation.n_theta_nc, p.validation.n_theta)
        Z_t, Q_t = sample_resonance(p.spindle, Z, box, cache=cache, counter=c_test,
                                    progress=ctx.progress, label=ctx.label)
        Z_d = np.column_stack([np.repeat(X, n_th, axis=0), np.tile(theta[:n_th], (len(X), 1))])
        Z_d, Q_d = sample_resonance(p.spindle, Z_d, box, cache=cache, counter=c_test,
                                    progress=ctx.progress, label=ctx.label)
        if Z_d.shape[0] != X.shape[0] * n_th:
            raise ValueError("FE resonance quantities failed at a validation design")
        res = (Z_t, Q_t, Z_d, Q_d)
    return Truth(Z, y, theta, y_fe, res, {"test": c_test.calls, "mc": c_mc.calls})


@dataclass(frozen=True, eq=False)
class VariantResult:
    """One variant's tables, test-point predictions, training info and counted calls."""

    name: str
    y_pred: np.ndarray
    rows: Mapping[str, Any]
    info: Mapping[str, Any]
    calls: Mapping[str, int]


def _one(p: Plan, t: Truth, name: str, options: Any, ctx: StageContext) -> VariantResult:
    tr = train_surrogate(p.spindle, p.inputs, p.limit, options, rng=ctx.stream(0),
                         cache=fe_cache(ctx.cache_dir), progress=ctx.progress,
                         label=f"{ctx.label} {name}")
    model = CountingResponse(tr.model.response)
    yp = tr.model.response_points(t.Z)
    X, labels = np.vstack(list(p.designs.values())), list(p.designs)
    cmp = compare_mc(_Grid(model), X, t.theta, p.limit, y_true=t.y_fe,
                     rel_tol=p.validation.rel_tol)
    rows: dict[str, Any] = {
        "metrics": tab.metrics_row(name, t.y, yp, p.limit.threshold),
        "loo": tab.loo_rows(name, tr.model.loo_summary()),
        "mc": tab.mc_rows(name, labels, X, cmp),
        "cost": tab.cost_row(name, getattr(options, "active_learning", False), tr.structure,
                             tr.model.info.get("transform", getattr(options, "transform", "")),
                             tr.model.n_train, tr.model.n_train, cmp)}
    if tr.structure == "resonance":
        n_th = min(p.validation.n_theta_nc, p.validation.n_theta)
        rows["sub"], rows["nc"] = tab.resonance_rows(name, tr.model, *t.resonance, labels, n_th)
    info = {k: v for k, v in tr.to_dict().items() if k != "options"}
    return VariantResult(name, yp, rows, info, {"fe_train": tr.fe_calls,
                                                "surrogate": yp.size + model.counter.calls})


class _Grid:
    """``compare_mc`` sees the model's response (the median for a log transform)."""

    def __init__(self, model: Any) -> None:
        self.model = model

    def predict_grid(self, x: np.ndarray, theta: np.ndarray) -> Prediction:
        y = self.model(x, theta)
        return Prediction(mean=y, std=np.full_like(y, np.nan))


def _variants(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> tuple[VariantResult, ...]:
    return tuple(_one(p, done["truth"], n, o, ctx) for n, o in p.variants.items())


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    t, vs = done["truth"], done["variants"]
    sub = [r for v in vs for r in v.rows.get("sub", [])]
    nc = [r for v in vs for r in v.rows.get("nc", [])]
    mc = [r for v in vs for r in v.rows["mc"]]
    for name, header, rows in (
            ("metrics.csv", tab.METRICS_HEADER, [v.rows["metrics"] for v in vs]),
            ("loo.csv", tab.LOO_HEADER, [r for v in vs for r in v.rows["loo"]]),
            ("mc_comparison.csv", tab.MC_HEADER, mc),
            ("cost.csv", tab.COST_HEADER, [v.rows["cost"] for v in vs])):
        run.write_csv(name, header, rows)
    if sub:
        run.write_csv("resonance_submodels.csv", tab.SUB_HEADER, sub)
        run.write_csv("nc_at_designs.csv", tab.NC_HEADER, nc)
    n = t.y.size
    for v in vs:
        run.save_figure(f"parity_{v.name}.png", parity_plot(
            t.y * 1e6, v.y_pred * 1e6, title=f"{v.name}: peak amplitude at {n} fresh LHS "
            "points", label="peak amplitude [µm]"))
        run.save_figure(f"parity_log_{v.name}.png", parity_plot(
            np.log10(t.y), np.log10(v.y_pred), title=f"{v.name}: log10 of the peak amplitude "
            f"at {n} fresh LHS points", label="log10(y / 1 m)"))
    run.write_json("surrogate_info.json", {v.name: dict(v.info) for v in vs})
    fe = {"test": t.calls["test"], "mc": t.calls["mc"],
          **{f"train_{v.name}": v.calls["fe_train"] for v in vs}}
    sur = {v.name: v.calls["surrogate"] for v in vs}
    meta = {"fe_calls": {**fe, "total": sum(fe.values())},
            "surrogate_calls": {**sur, "total": sum(sur.values())},
            "n_theta": p.validation.n_theta, "n_test": int(n),
            "note": "fe_calls are computed points (cache misses); cost.csv has the training "
                    "sizes"}
    run.write_json("calls.json", meta)
    keep = ("variant", "design", "mean_rel_err", "std_rel_err", "pf_fe", "pf_sur", "ok_mean",
            "ok_std", "ok_pf")
    return {"variants": [v.name for v in vs], "meta": meta,
            "summary": [{k: x for k, x in zip(tab.MC_HEADER, r, strict=True) if k in keep}
                        for r in mc]}


register_kind(Kind(
    name="surrogate_validation",
    summary="surrogate variants (structures, transforms, active learning) against the full "
            "FE model: test-point metrics, LOO, μ/σ/P_f at designs, cost",
    schema=SurrogateValidationConfig,
    stages=(Stage("truth", _truth), Stage("variants", _variants)),
    report=_report,
    build=build,
))
