"""The ``[spindle]`` table of an experiment config and the spindle it describes.

:class:`SpindleTable` names a built-in spindle (``"reference"``, ``"credible"``) or a
geometry file, and optionally replaces its effects, design map, baseline and θ bearings;
:func:`build_spindle` turns it into a checked :class:`ReferenceSpindle` (errors name the
dotted path ``spindle.<field>``).

>>> sp = build_spindle(SpindleTable(baseline=(2000.0, 460.0, 65.0)))
>>> sp.baseline.tolist()
[2000.0, 460.0, 65.0]
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import check_positive
from surrogate_rbrdo.spindle.effects import effects_from_data
from surrogate_rbrdo.spindle.geometry import DesignMap, SpindleGeometry, check_balance_grade
from surrogate_rbrdo.spindle.reference import ReferenceSpindle, credible_spindle, reference_spindle

#: the built-in spindles ``[spindle] geometry`` names (else a geometry file)
BUILT_IN = ("credible", "reference")


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
    """``[spindle]``: ``geometry`` (``"credible"``: the reference problem's spindle,
    ``"reference"``: the paper-box spindle of the synthetic benchmarks, or a TOML/JSON file,
    relative to the config), ``balance_grade_mm_s`` (the fixed in-phase unbalance of the
    built-in geometries), ``effects`` (replace the
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
        if self.geometry not in BUILT_IN and Path(self.geometry).suffix not in (".toml",
                                                                                ".json"):
            near = difflib.get_close_matches(self.geometry, BUILT_IN, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise ValueError(f"geometry = {self.geometry!r} is not allowed: give a built-in "
                             f"spindle {list(BUILT_IN)} or a .toml/.json geometry file{hint}")
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
    if t.geometry in BUILT_IN:
        grade = 2.5 if t.balance_grade_mm_s is None else t.balance_grade_mm_s
        factory = reference_spindle if t.geometry == "reference" else credible_spindle
        sp = factory(balance_grade_mm_s=check_positive("spindle.balance_grade_mm_s", grade))
    else:
        if t.balance_grade_mm_s is not None:
            raise ValueError("spindle.balance_grade_mm_s applies only to geometry = 'reference' "
                             "or 'credible'; give the unbalances in the geometry file")
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


__all__ = ["DesignMapTable", "SpindleTable", "build_spindle"]
