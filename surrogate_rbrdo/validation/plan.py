"""A validation config's tables (:class:`ValidationConfig`) and the checked plan they
describe (:class:`ValidationPlan`, :func:`build_validation`).

Tables: ``[rig]`` (:class:`~surrogate_rbrdo.rig.config.RigTruthTable`: the truth's hidden
``effects``, ``variability``, ``sensors``), ``[validation]``
(:class:`~surrogate_rbrdo.validation.options.ValidationOptions`; its sensors are
``[rig.sensors]``), ``[designs]`` (``name = [F N, L mm, D mm]`` entries, or ``from = "<study
run folder>"`` with optional ``names = [...]``: the designs of its ``verification.csv`` and,
as the model's known moments, its FE columns, :func:`verification_fe`), ``[model]``
(:class:`ModelTable`) and, for given designs, the model's ``[spindle]`` and
``[uncertainty]`` (a study brings its own).
"""

from __future__ import annotations

import csv
import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.core.files import read_meta
from surrogate_rbrdo.core.memory import require_memory
from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import check_int
from surrogate_rbrdo.rig.config import RigTruthTable
from surrogate_rbrdo.rig.sensors import SensorSet
from surrogate_rbrdo.rig.truth import Truth
from surrogate_rbrdo.spindle.config import SpindleTable, build_spindle
from surrogate_rbrdo.study.config import UncertaintyTable, build_inputs, response_speeds
from surrogate_rbrdo.study.plan import StudyConfig
from surrogate_rbrdo.study.problem import DESIGN_NAMES
from surrogate_rbrdo.validation.campaign import check_designs, check_nominal_designs, file_label
from surrogate_rbrdo.validation.model import ModelSpec, Moments, spindle_model_spec
from surrogate_rbrdo.validation.options import ValidationOptions
from surrogate_rbrdo.validation.replicas import TruthFamily


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
    """The tables of a ``validation`` config (the module docstring)."""

    rig: RigTruthTable = field(default_factory=RigTruthTable)
    validation: ValidationOptions = field(default_factory=ValidationOptions)
    designs: dict[str, Any] = field(default_factory=dict)
    model: ModelTable = field(default_factory=ModelTable)
    spindle: SpindleTable | None = None
    uncertainty: UncertaintyTable | None = None


@dataclass(frozen=True, eq=False)
class ValidationPlan:
    """The checked objects of a validation: the truth family, the designs (label → x), the
    options, the model to compare with (``None``: none) and where the designs came from."""

    family: TruthFamily
    designs: dict[str, tuple[float, ...]]
    options: ValidationOptions
    model: Any
    source: dict[str, Any]


def verification_fe(rows: Iterable[Mapping[str, str]]) -> dict[str, dict[str, Any]]:
    """A study's ``verification.csv`` read back (rows as ``csv.DictReader`` gives them): per
    design, ``x`` and the FE model's ``n``, ``mean``, ``std`` (m), ``pf``, ``pf_ci``
    (fractions).

    >>> row = {"design": "baseline", "preload_N": "2000", "span_mm": "465.8",
    ...        "diameter_mm": "65", "mean_um_fe": "21", "std_um_fe": "9.5", "pf_pct_fe": "50",
    ...        "pf_ci_low_pct_fe": "40", "pf_ci_high_pct_fe": "60", "n_theta_fe": "100"}
    >>> verification_fe([row])["baseline"]["pf_ci"]
    (0.4, 0.6)
    """
    out = {}
    for r in rows:
        out[r["design"]] = {
            "x": tuple(float(r[k]) for k in DESIGN_NAMES), "n": int(r["n_theta_fe"]),
            "mean": float(r["mean_um_fe"]) * 1e-6, "std": float(r["std_um_fe"]) * 1e-6,
            "pf": float(r["pf_pct_fe"]) / 100,
            "pf_ci": (float(r["pf_ci_low_pct_fe"]) / 100, float(r["pf_ci_high_pct_fe"]) / 100)}
    return out


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
                    ) -> ValidationPlan:
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
    return ValidationPlan(family, designs, o, model, source)


def build_validation(c: ValidationConfig, base_dir: str | Path = ".") -> ValidationPlan:
    """The checked plan of a ``validation`` config (files relative to ``base_dir``; errors
    name the dotted path)."""
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


__all__ = ["ModelTable", "ValidationConfig", "ValidationPlan", "build_validation",
           "validation_options", "validation_plan", "verification_fe"]
