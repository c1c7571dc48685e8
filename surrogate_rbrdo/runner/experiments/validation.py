"""Experiment kind ``validation``: designs built and measured on the virtual rig, compared
with each other (Table 7) and with the model (``docs/validation.md``).

Tables: ``[rig]`` (:class:`~surrogate_rbrdo.rig.config.RigTruthTable`: the truth's hidden
``effects``, ``variability``, ``sensors``), ``[validation]``
(:class:`~surrogate_rbrdo.validation.options.ValidationOptions`; its sensors are
``[rig.sensors]``), ``[designs]`` (``name = [F N, L mm, D mm]`` entries, or ``from = "<study
run folder>"`` with optional ``names = [...]``: the designs of its ``verification.csv`` and,
as the model's known moments, its FE columns), ``[model]`` (:class:`ModelTable`) and, for
given designs, the model's ``[spindle]`` and ``[uncertainty]`` (a study brings its own).
Stages: ``measure`` (``validation.measure_designs``) → ``model``
(``validation.add_model``); both draw from stream 0 of the seed, addressed by key.
"""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.reporting.plots_validation import write_validation_report
from surrogate_rbrdo.reporting.study import verification_fe
from surrogate_rbrdo.rig.config import RigTruthTable
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.truth import Truth
from surrogate_rbrdo.runner.experiments.study import StudyConfig
from surrogate_rbrdo.runner.kinds import Kind, Stage, StageContext, register_kind
from surrogate_rbrdo.runner.runfolder import read_meta
from surrogate_rbrdo.runner.tables import (
    SpindleTable,
    UncertaintyTable,
    build_inputs,
    build_spindle,
    require_memory,
    response_speeds,
)
from surrogate_rbrdo.validation import (
    ModelSpec,
    Moments,
    TruthFamily,
    ValidationOptions,
    add_model,
    measure_designs,
    spindle_model_spec,
)
from surrogate_rbrdo.validation.campaign import check_designs, check_nominal_designs, file_label


@dataclass(frozen=True)
class ModelTable:
    """``[model]``: compare the model's μ, σ, P_f, ±2σ band and Campbell diagram with the
    measurement (``compare``), μ, σ, P_f from ``n_samples`` Monte Carlo θ samples where a
    study's verification does not give them."""

    compare: bool = True
    n_samples: int = 1000

    def __post_init__(self) -> None:
        check_int("n_samples", self.n_samples, minimum=10)


@dataclass(frozen=True)
class ValidationConfig:
    rig: RigTruthTable = field(default_factory=RigTruthTable)
    validation: ValidationOptions = field(default_factory=ValidationOptions)
    designs: dict[str, Any] = field(default_factory=dict)
    model: ModelTable = field(default_factory=ModelTable)
    spindle: SpindleTable | None = None
    uncertainty: UncertaintyTable | None = None


@dataclass(frozen=True, eq=False)
class Plan:
    family: TruthFamily
    designs: dict[str, tuple[float, ...]]
    options: ValidationOptions
    model: Any
    source: dict[str, Any]


def _given(c: ValidationConfig, base_dir: Path) -> tuple[Any, ...]:
    """Designs from the config; the model from ``[spindle]`` and ``[uncertainty]``."""
    if c.spindle is not None and c.spindle.geometry != "reference":
        raise ValueError(f"spindle.geometry = {c.spindle.geometry!r} is not allowed: the rig's "
                         "truth is the reference spindle")
    designs = parse(dict[str, tuple[float, float, float]], c.designs, "designs")
    spindle = build_spindle(c.spindle or SpindleTable(), base_dir)
    inputs = build_inputs(c.uncertainty or UncertaintyTable(), spindle.theta_bearings)
    return designs, spindle, inputs, {}, {"designs": "config"}


def _read_study(c: ValidationConfig) -> tuple[Path, Any, dict[str, dict[str, Any]]]:
    """The finished study run folder of ``designs.from``: folder, config, verification."""
    extra = sorted(set(c.designs) - {"from", "names"})
    if extra:
        raise ValueError(f"unknown key designs.{extra[0]}; allowed with designs.from: "
                         "['from', 'names'] (designs are given by name = [F, L, D] or from a "
                         "study, not both)")
    if c.spindle is not None or c.uncertainty is not None:
        raise ValueError("[spindle] and [uncertainty] are not allowed with designs.from: the "
                         "model is the study's")
    folder = Path(parse(dict[str, str], {"from": c.designs["from"]}, "designs")["from"])
    meta, files = read_meta(folder) or {}, (folder / "config.json", folder / "verification.csv")
    if meta.get("kind") != "study" or meta.get("status") != "complete" or not all(
            f.is_file() for f in files):
        raise ValueError(f"designs.from = {str(folder)!r} is not allowed: not a finished study "
                         f"run folder (meta.json: kind {meta.get('kind')!r}, status "
                         f"{meta.get('status')!r}; needs config.json and verification.csv)")
    cfg = json.loads(files[0].read_text())
    try:
        sc = parse(StudyConfig, {k: v for k, v in cfg.items() if k != "experiment"}, "")
    except ValueError as exc:
        raise ValueError(f"designs.from = {str(folder)!r}: its config.json: {exc}") from None
    with open(files[1], newline="") as fh:
        return folder, sc, verification_fe(csv.DictReader(fh))


def _study(c: ValidationConfig, o: ValidationOptions) -> tuple[Any, ...]:
    """Designs, model and known moments (its FE verification) from a study run folder."""
    folder, sc, fe = _read_study(c)
    if sc.spindle.geometry != "reference":
        raise ValueError(f"designs.from = {str(folder)!r} is not allowed: its spindle.geometry "
                         f"= {sc.spindle.geometry!r}, and the rig's truth is the reference "
                         "spindle")
    if sc.limit.delta_lim_um != o.delta_lim_um:
        raise ValueError(f"validation.delta_lim_um = {o.delta_lim_um} is not allowed: the study "
                         f"{str(folder)!r} has limit.delta_lim_um = {sc.limit.delta_lim_um}")
    names = parse(dict[str, tuple[str, ...]], {"names": c.designs.get("names", list(fe))},
                  "designs")["names"]
    for n in names:
        if n not in fe:
            raise ValueError(f"designs.names: {n!r} is not in {str(folder / 'verification.csv')!r}"
                             f"; its designs: {list(fe)}")
    spindle = build_spindle(sc.spindle, folder)
    g, r = spindle.geometry, sc.response
    q = ("peak" if r.kind == "peak" and o.speed_range_rpm == (g.speed_min_rpm, g.speed_max_rpm)
         else "rated" if r.kind == "at_speed" and r.speed_rpm == o.rated_speed_rpm else None)
    labels = {n: file_label(n) for n in names}
    designs = {labels[n]: fe[n].pop("x") for n in names}
    known = {labels[n]: {q: Moments.from_summary(**fe[n], confidence=o.confidence)}
             for n in names} if q else {}
    source = {"designs": str(folder), "study_labels": labels,
              "known_from_study": q or "none: the study's response is not measured"}
    inputs = build_inputs(sc.uncertainty, spindle.theta_bearings,
                          at=response_speeds(sc.response, spindle))
    return designs, spindle, inputs, known, source


def validation_options(rig: RigTruthTable, options: ValidationOptions) -> ValidationOptions:
    """``[validation]`` with the sensors of ``[rig.sensors]`` (its own must stay default)."""
    if options.sensors != SensorSet():
        raise ValueError("validation.sensors is not allowed: the sensors are [rig.sensors]")
    try:
        return replace(options, sensors=rig.sensors)
    except ValueError as exc:
        raise ValueError(f"rig.{exc}") from None


def validation_plan(template: Truth, spindle: Any, designs: dict[str, tuple[float, ...]],
                    o: ValidationOptions, model: ModelSpec | None, source: dict[str, Any]
                    ) -> Plan:
    """The checks before measuring (designs, a truth stable at each, memory) and the plan of
    the stages: ``template`` is the rig's truth, ``spindle`` the design map's owner."""
    try:
        check_designs(designs, o.baseline)
        family = TruthFamily(template, spindle.design_map)
        check_nominal_designs(family, designs, o)
    except ValueError as exc:
        raise ValueError(exc if str(exc).startswith("designs.") else f"designs: {exc}") from None
    except ModelError as exc:
        raise ValueError(f"rig.effects: {exc}") from None
    require_memory("validation.n_replications", o.n_replications, 64.0 * len(designs)
                   * o.n_replications * len(o.speeds_rpm) * len(o.sensors.probe_channels),
                   "the phasors of every replication, speed and probe")
    if model is not None:
        require_memory("model.n_samples", model.n_samples, 64.0 * len(designs)
                       * model.n_samples * max(o.peak.n_grid, len(o.speeds_rpm)),
                       "the model's responses")
    return Plan(family, designs, o, model, source)


def build(c: ValidationConfig, base_dir: Path) -> Plan:
    o = validation_options(c.rig, c.validation)
    designs, spindle, inputs, known, source = (_study(c, o) if "from" in c.designs
                                               else _given(c, base_dir))
    model = spindle_model_spec(spindle, inputs, n_samples=c.model.n_samples, known=known,
                               rated_speed_rpm=o.rated_speed_rpm) if c.model.compare else None
    try:
        template = c.rig.truth()
    except ModelError as exc:
        raise ValueError(f"rig.effects: {exc}") from None
    return validation_plan(template, spindle, designs, o, model, source)


def _measure(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    with ctx.bar("validation: measuring on the rig", "replication") as progress:
        return measure_designs(p.family, p.designs, options=p.options, rng=ctx.stream(0),
                               progress=progress)


def _model(p: Plan, done: Mapping[str, Any], ctx: StageContext) -> Any:
    res = done["measure"]
    if p.model is None:
        return res
    with ctx.bar("validation: the model's moments, band and Campbell", "part") as progress:
        progress(0, 1, f"{len(p.designs)} designs, {p.model.n_samples} θ samples")
        return add_model(res, p.model, rng=ctx.stream(0))


def _report(p: Plan, done: Mapping[str, Any], run: Any, ctx: StageContext) -> dict[str, Any]:
    res = done["model"]
    write_validation_report(res, run.path)
    run.write_json("designs_source.json", p.source)
    rows = [{"design": d.name, "x": list(d.x), "mu_peak_um": round(d.moments["peak"].mean * 1e6, 4),
             "sigma_peak_um": round(d.moments["peak"].std * 1e6, 4),
             "pf_peak": d.moments["peak"].pf} for d in res.designs]
    bad = [f"{v.design} {v.quantity} {v.metric}" for v in res.disagreements]
    return {"meta": {"timings": dict(res.timings), "disagreements": bad,
                     "n_records": sum(d.n_records for d in res.designs)},
            "summary": rows + ([{"model_vs_measured": f"{len(bad)} of {len(res.verdicts)} "
                                 "disagree beyond uncertainty"}] if res.verdicts else [])}


register_kind(Kind(
    name="validation",
    summary="designs built on the virtual rig's truth and measured over paired replications: "
            "Table 7 (paired t, d_z, Wilcoxon, McNemar, bootstrap), model vs measurement, "
            "Fig. 7/8 analogues",
    schema=ValidationConfig,
    stages=(Stage("measure", _measure), Stage("model", _model)),
    report=_report,
    build=build,
))
