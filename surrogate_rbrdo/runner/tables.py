"""Config tables every kind may use, and the objects they describe.

``[experiment]`` (:class:`ExperimentTable`), ``[spindle]`` (:class:`SpindleTable` →
:func:`build_spindle`), ``[uncertainty]`` (→ :func:`build_inputs`), ``[limit]``,
``[response]`` and ``[deterministic]``; :func:`require_memory` refuses sizes whose arrays would
not fit before any work starts. Each table is a frozen dataclass checked by
:func:`~surrogate_rbrdo.core.schema.parse`; the builders raise ``ValueError`` naming the
dotted path of the field.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.memory import available_memory
from surrogate_rbrdo.core.protocols import LimitState
from surrogate_rbrdo.core.validate import check_int, check_positive
from surrogate_rbrdo.formulations import DeterministicOptions
from surrogate_rbrdo.runner.runfolder import check_name
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.effects import effects_from_data
from surrogate_rbrdo.spindle.geometry import DesignMap, SpindleGeometry, check_balance_grade
from surrogate_rbrdo.spindle.reference import ReferenceSpindle, reference_spindle
from surrogate_rbrdo.study.problem import TABLE4_STD
from surrogate_rbrdo.uncertainty import MultivariateNormal


@dataclass(frozen=True)
class ExperimentTable:
    """``[experiment]``: ``name`` (the results sub-folder), ``kind``, ``seed``,
    ``results_dir`` (the results root, relative to the config file; default ``results`` in
    the working directory), ``description``."""

    name: str
    kind: str
    seed: int = 0
    results_dir: str | None = None
    description: str = ""

    def __post_init__(self) -> None:
        check_name("name", self.name)
        check_int("seed", self.seed, minimum=0)
        if self.results_dir is not None and not self.results_dir.strip():
            raise ValueError(f"results_dir = {self.results_dir!r} is not allowed: give a folder")


@dataclass(frozen=True)
class DesignMapTable:
    """``[spindle.design_map]``: which bearing the preload sets, which sections the span and
    diameter set, and the design box."""

    preload_bearing: str = "front"
    span_tag: str = "span"
    lower: tuple[float, float, float] = (1000.0, 300.0, 50.0)
    upper: tuple[float, float, float] = (3000.0, 750.0, 80.0)


@dataclass(frozen=True)
class SpindleTable:
    """``[spindle]``: ``geometry`` (``"reference"`` or a TOML/JSON file, relative to the
    config), ``balance_grade_mm_s`` (reference geometry only), ``effects`` (replace the
    default physical effects: ``[{name = ..., <params>}]``), ``design_map``, ``baseline``
    (``[F N, L mm, D mm]``), ``theta_bearings`` (the bearings θ scales)."""

    geometry: str = "reference"
    balance_grade_mm_s: float | None = None
    effects: tuple[dict[str, Any], ...] | None = None
    design_map: DesignMapTable | None = None
    baseline: tuple[float, float, float] | None = None
    theta_bearings: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if not self.geometry or self.geometry != self.geometry.strip():
            raise ValueError(f"geometry = {self.geometry!r} is not allowed: give a built-in "
                             "spindle (e.g. 'reference') or a .toml/.json file")
        if self.balance_grade_mm_s is not None:
            check_balance_grade("balance_grade_mm_s", self.balance_grade_mm_s)


def _geometry_file(path: Path) -> SpindleGeometry:
    where = f"spindle.geometry file {str(path)!r}"
    geo = SpindleGeometry.load(path, "spindle.geometry file")
    if not any(u.magnitude_kgm > 0 for u in geo.unbalances):
        raise ValueError(f"{where}: every unbalance is zero (or there is none): the unbalance "
                         "response would be 0 everywhere; give unbalances[].magnitude_kgm > 0")
    return geo


def build_spindle(t: SpindleTable, base_dir: str | Path = ".") -> ReferenceSpindle:
    """The spindle of a ``[spindle]`` table (every field checked, errors name it)."""
    if t.geometry == "reference":
        grade = 2.5 if t.balance_grade_mm_s is None else t.balance_grade_mm_s
        sp = reference_spindle(balance_grade_mm_s=check_positive(
            "spindle.balance_grade_mm_s", grade))
    else:
        if t.balance_grade_mm_s is not None:
            raise ValueError("spindle.balance_grade_mm_s applies only to geometry = 'reference'; "
                             "give the unbalances in the geometry file")
        p = Path(t.geometry)
        geometry = _geometry_file(p if p.is_absolute() else Path(base_dir) / p)
        sp = ReferenceSpindle(geometry, (), DesignMap(), np.array(DesignMap().lower))
        sp = replace(sp, baseline=np.mean(sp.design_map.bounds, axis=1))
    if t.effects is not None:
        sp = replace(sp, effects=effects_from_data(t.effects, "spindle.effects"))
    if t.design_map is not None:
        try:
            sp = replace(sp, design_map=DesignMap(**vars(t.design_map)))
        except ValueError as exc:
            raise ValueError(f"spindle.design_map: {exc}") from None
    if t.baseline is not None:
        try:
            sp = replace(sp, baseline=sp.design_map.check(np.asarray(t.baseline, float)))
        except ValueError as exc:
            raise ValueError(f"spindle.baseline: {exc}") from None
    if t.theta_bearings is not None:
        sp = replace(sp, theta_bearings=tuple(t.theta_bearings))
    try:
        return sp.check()   # design map, effects and θ bearings against the geometry
    except ValueError as exc:
        raise ValueError(f"spindle.{exc}") from None


@dataclass(frozen=True)
class UncertaintyTable:
    """``[uncertainty]``: θ ~ MVN(``mean``, ``std``, ``corr``), one entry per θ bearing
    (defaults: mean 1, the Table 4 CoVs)."""

    mean: tuple[float, ...] | None = None
    std: tuple[float, ...] | None = None
    corr: tuple[tuple[float, ...], ...] | None = None


def build_inputs(t: UncertaintyTable, theta_bearings: tuple[str, ...]) -> MultivariateNormal:
    """θ of a ``[uncertainty]`` table. θ are stiffness factors: every component must stay
    positive (mean > 8 std, so P(θ ≤ 0) < 1e-15)."""
    m = len(theta_bearings)
    mean = np.asarray([1.0] * m if t.mean is None else t.mean, dtype=float)
    std = np.asarray(TABLE4_STD[:m] if t.std is None else t.std, dtype=float)
    for name, v in (("mean", mean), ("std", std)):
        if v.shape != (m,):
            raise ValueError(f"uncertainty.{name} = {v.tolist()} is not allowed: need {m} "
                             f"values, one per θ bearing {list(theta_bearings)}")
    for i in range(m):
        check_positive(f"uncertainty.std[{i}]", float(std[i]))
        if not mean[i] > 8.0 * std[i]:
            raise ValueError(f"uncertainty.mean[{i}] = {mean[i]} is not allowed: θ scales a "
                             f"bearing stiffness and must stay positive: need mean > 8 std = "
                             f"{8.0 * std[i]:g}")
    corr = None if t.corr is None else np.asarray(t.corr, dtype=float)
    try:
        return MultivariateNormal(mean, std=std, corr=corr)
    except ValueError as exc:
        raise ValueError(f"uncertainty.corr: {exc}") from None


@dataclass(frozen=True)
class LimitTable:
    """``[limit]``: failure when ``y > delta_lim_um`` (µm)."""

    delta_lim_um: float = 19.5

    def __post_init__(self) -> None:
        check_positive("delta_lim_um", self.delta_lim_um)

    def limit(self) -> LimitState:
        return LimitState(self.delta_lim_um * 1e-6)


@dataclass(frozen=True)
class DeterministicTable:
    """``[deterministic]``: the g_det constraints (``DeterministicOptions``, speeds in rpm;
    ``omega_max_rpm`` defaults to the spindle's top speed)."""

    stress: bool = True
    yield_strength_pa: float = 930e6
    resonance: str = "paper"
    factor: float = 1.2
    omega_max_rpm: float | None = None
    operating_speeds_rpm: tuple[float, ...] = ()
    margin: float = 0.15

    def options(self, speed_max_rpm: float) -> DeterministicOptions:
        if self.omega_max_rpm is not None:
            check_positive("deterministic.omega_max_rpm", self.omega_max_rpm)
        for i, s in enumerate(self.operating_speeds_rpm):
            check_positive(f"deterministic.operating_speeds_rpm[{i}]", s)
        top = speed_max_rpm if self.omega_max_rpm is None else self.omega_max_rpm
        try:
            return DeterministicOptions(
                stress=self.stress, yield_strength_pa=self.yield_strength_pa,
                resonance=self.resonance, factor=self.factor, omega_max=top * RPM,
                operating_speeds=tuple(float(s) * RPM for s in self.operating_speeds_rpm),
                margin=self.margin)
        except ValueError as exc:
            raise ValueError(f"deterministic.{exc}") from None


def require_memory(field: str, value: Any, nbytes: float, detail: str) -> None:
    """Refuse ``field = value`` if the arrays it sizes (``nbytes``) exceed the memory
    available now."""
    have = available_memory()
    if nbytes > have:
        raise ValueError(f"{field} = {value!r} is not allowed: {detail} need ~{nbytes / 1e9:.3g} "
                         f"GB of memory, more than the {have / 1e9:.3g} GB available")


__all__ = ["DesignMapTable", "DeterministicTable", "ExperimentTable", "LimitTable",
           "SpindleTable", "UncertaintyTable", "available_memory", "build_inputs",
           "build_spindle", "require_memory"]
