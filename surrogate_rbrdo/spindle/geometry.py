"""The plain geometry description of a spindle, loadable from TOML or JSON, and the design map.

Units follow the field names (``_mm``, ``_kg``, ``_N``...) at input; everything is converted to SI
when the model is assembled. The format is documented in ``docs/geometry-format.md``. A file is
parsed by a strict schema (``core.schema``: the dataclasses of ``spindle.components`` are the
schema): wrong types, unknown keys and bad values raise one line naming the path, e.g.
``sections[1].length_mm = '100' is not allowed: must be a number``.

>>> g = SpindleGeometry.from_dict({
...     "sections": [{"length_mm": 100, "outer_diameter_mm": 50, "elements": 4}],
...     "bearings": [{"name": "a", "position_mm": 0, "law": {"type": "constant",
...                   "k_N_per_m": 1e8}},
...                  {"name": "b", "position_mm": 100, "law": {"type": "constant",
...                   "k_N_per_m": 1e8}}],
...     "tool_tip_mm": 0.0})
>>> g.total_length_mm, len(g.bearings)
(100.0, 2)
>>> SpindleGeometry.from_dict({"sections": [{"length_mm": 100, "outer_diameter_mm": "50"}],
...                            "bearings": []})
Traceback (most recent call last):
...
ValueError: sections[0].outer_diameter_mm = '50' is not allowed: must be a number
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.schema import load_data, parse
from surrogate_rbrdo.core.validate import check_positive, check_range, check_text
from surrogate_rbrdo.spindle.components import (
    BALANCE_GRADES_MM_S,
    LAWS,
    MAX_ELEMENTS,
    Bearing,
    ConstantLaw,
    Disk,
    Material,
    PreloadLaw,
    ShaftSection,
    Unbalance,
    check_balance_grade,
    law_name,
)


@dataclass(frozen=True)
class SpindleGeometry:
    """Everything the FE model is built from (positions measured from the left end, z = 0)."""

    sections: tuple[ShaftSection, ...]
    bearings: tuple[Bearing, ...]
    disks: tuple[Disk, ...] = ()
    unbalances: tuple[Unbalance, ...] = ()
    materials: Mapping[str, Material] = field(default_factory=lambda: {"steel": Material()})
    tool_tip_mm: float = 0.0
    rayleigh_alpha_per_s: float = 3.5
    rayleigh_beta_s: float = 2.1e-6
    speed_min_rpm: float = 1000.0
    speed_max_rpm: float = 24000.0
    max_element_length_mm: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "sections", tuple(self.sections))
        object.__setattr__(self, "bearings", tuple(self.bearings))
        object.__setattr__(self, "disks", tuple(self.disks))
        object.__setattr__(self, "unbalances", tuple(self.unbalances))
        if not self.sections:
            raise ValueError("sections = [] is not allowed: the shaft needs at least one section")
        if not self.bearings:
            raise ValueError("bearings = [] is not allowed: the rotor needs at least one bearing")
        for i, s in enumerate(self.sections):
            if s.material not in self.materials:
                raise ValueError(
                    f"sections[{i}].material = {s.material!r} is not allowed: known materials "
                    f"{sorted(self.materials)}"
                )
        total = self.total_length_mm
        for kind, items in (("bearings", self.bearings), ("disks", self.disks),
                            ("unbalances", self.unbalances)):
            for i, it in enumerate(items):
                if not (0.0 <= it.position_mm <= total):
                    raise ValueError(
                        f"{kind}[{i}].position_mm = {it.position_mm} is not allowed: must lie "
                        f"on the shaft, in [0, {total}] mm"
                    )
        names = [b.name for b in self.bearings]
        if len(set(names)) != len(names):
            dup = next(n for n in names if names.count(n) > 1)
            raise ValueError(f"bearings[{names.index(dup, names.index(dup) + 1)}].name = "
                             f"{dup!r} is not allowed: bearing names must be unique")
        check_range("tool_tip_mm", self.tool_tip_mm, 0.0, total)
        check_positive("rayleigh_alpha_per_s", self.rayleigh_alpha_per_s, allow_zero=True)
        check_positive("rayleigh_beta_s", self.rayleigh_beta_s, allow_zero=True)
        check_positive("speed_min_rpm", self.speed_min_rpm)
        if not self.speed_max_rpm > self.speed_min_rpm:
            raise ValueError(
                f"speed_max_rpm = {self.speed_max_rpm} is not allowed: must exceed "
                f"speed_min_rpm = {self.speed_min_rpm}"
            )
        if self.max_element_length_mm is not None:
            check_positive("max_element_length_mm", self.max_element_length_mm)
        self._check_mesh()

    def elements(self) -> list[int]:
        """Finite elements per section (``elements``, more where ``max_element_length_mm``
        asks for them; the mesh adds nodes at bearings, disks and unbalances)."""
        m = self.max_element_length_mm
        return [s.elements if m is None else max(s.elements, math.ceil(s.length_mm / m - 1e-9))
                for s in self.sections]

    def _check_mesh(self) -> None:
        n = self.elements()
        if sum(n) <= MAX_ELEMENTS:
            return
        if self.max_element_length_mm is not None and sum(
                s.elements for s in self.sections) <= MAX_ELEMENTS:
            where, value = "max_element_length_mm", self.max_element_length_mm
        else:
            i = int(np.argmax([s.elements for s in self.sections]))
            where, value = f"sections[{i}].elements", self.sections[i].elements
        raise ValueError(f"{where} = {value!r} is not allowed: the shaft would have {sum(n)} "
                         f"finite elements, more than {MAX_ELEMENTS} (the dense solvers hold "
                         "n_dof² complex matrices)")

    @property
    def total_length_mm(self) -> float:
        return float(sum(s.length_mm for s in self.sections))

    @property
    def min_yield_Pa(self) -> float:
        """The lowest yield strength of the shaft sections' materials (the stress ratio's
        reference)."""
        return min(self.materials[s.material].yield_Pa for s in self.sections)

    def bearing(self, name: str) -> Bearing:
        for b in self.bearings:
            if b.name == name:
                return b
        raise ValueError(f"bearing {name!r} not found; bearings: {[b.name for b in self.bearings]}")

    # ------------------------------------------------------------------ loading
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], where: str = "") -> SpindleGeometry:
        """Build from plain data (as read from TOML/JSON) through the strict schema: types
        checked (no string taken as a number), unknown keys refused, errors one line naming
        the path below ``where`` (``sections[1].length_mm``). ``materials`` adds to (or
        replaces) the default ``steel``."""
        if not isinstance(data, Mapping):
            raise ValueError(f"{where or 'geometry'} = {_short(data)} is not allowed: must be a "
                             "table (sections, bearings, ...)")
        mats = data.get("materials")
        if isinstance(mats, Mapping):
            data = {**data, "materials": {"steel": {}, **mats}}
        return parse(cls, data, where)

    @classmethod
    def load(cls, path: str | Path, what: str = "geometry file") -> SpindleGeometry:
        """Load a ``.toml`` or ``.json`` geometry file (the geometry at the top level or in a
        ``geometry`` table); every error names the file and the path inside it."""
        data = load_data(path, what)
        where = ""
        if isinstance(data, Mapping) and "geometry" in data:
            data, where = data["geometry"], "geometry"
        try:
            return cls.from_dict(data, where)
        except ValueError as exc:
            raise ValueError(f"{what} {str(path)!r}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        """Plain data that :meth:`from_dict` reads back."""
        out = dataclasses.asdict(self)
        out["materials"] = {k: dataclasses.asdict(v) for k, v in self.materials.items()}
        out["bearings"] = [
            {"name": b.name, "position_mm": b.position_mm,
             "law": {"type": law_name(b.law), **_drop_none(dataclasses.asdict(b.law))}}
            for b in self.bearings
        ]
        return _drop_none(out)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _drop_none(d: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in d.items() if v is not None}


# ---------------------------------------------------------------------- design vector
#: a design box lies within this factor of the geometry's own preload, span and diameter
BOX_FACTOR = 10.0


@dataclass(frozen=True)
class DesignMap:
    """Maps the design vector ``x = [F_f (N), L (mm), D (mm)]`` onto a geometry.

    * ``F_f`` sets ``preload_N`` of the bearing ``preload_bearing`` (a :class:`PreloadLaw`);
    * ``L`` scales the sections tagged ``span_tag`` so that their total length is ``L``; axial
      positions inside the span scale with it, positions after it shift by the change;
    * ``D`` sets the outer diameter of the sections tagged ``span_tag``.
    """

    preload_bearing: str = "front"
    span_tag: str = "span"
    names: tuple[str, str, str] = ("preload_N", "span_mm", "diameter_mm")
    lower: tuple[float, float, float] = (1000.0, 300.0, 50.0)
    upper: tuple[float, float, float] = (3000.0, 750.0, 80.0)

    def __post_init__(self) -> None:
        check_text("preload_bearing", self.preload_bearing)
        check_text("span_tag", self.span_tag)
        for i, name in enumerate(self.names):
            lo, hi = self.lower[i], self.upper[i]
            if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
                raise ValueError(
                    f"design bounds for {name} = [{lo}, {hi}] are not allowed: lower must be "
                    "finite, > 0 (a preload, a length, a diameter) and smaller than upper"
                )

    def check_geometry(self, geometry: SpindleGeometry) -> None:
        """Refuse a map that does not fit ``geometry``: ``preload_bearing`` must be one of its
        bearings with a preload law, ``span_tag`` must tag one contiguous run of sections, and
        the box must be a neighbourhood of the geometry: each bound within a factor
        :data:`BOX_FACTOR` of the geometry's own value (the law's reference preload, the span
        length, the span's outer diameter) — beyond, the Hertz law k ∝ F^(1/3) fitted at the
        reference preload and the span's mesh and parts are no longer that spindle — and the
        diameter above the span's bore. Messages name the field (``lower[0]``, ...)."""
        names = [b.name for b in geometry.bearings]
        if self.preload_bearing not in names:
            raise ValueError(f"preload_bearing = {self.preload_bearing!r} is not allowed: "
                             f"bearings are {names}")
        law = geometry.bearing(self.preload_bearing).law
        if not isinstance(law, PreloadLaw):
            raise ValueError(f"preload_bearing = {self.preload_bearing!r} is not allowed: its "
                             f"law is {law_name(law)!r}; the design preload needs a 'preload' "
                             "law")
        idx = self._span(geometry)
        span = [geometry.sections[i] for i in idx]
        nominal = (law.preload_ref_N, sum(s.length_mm for s in span),
                   max(s.outer_diameter_mm for s in span))
        for i, name in enumerate(self.names):
            for side, v in (("lower", self.lower[i]), ("upper", self.upper[i])):
                if not nominal[i] / BOX_FACTOR <= v <= nominal[i] * BOX_FACTOR:
                    raise ValueError(
                        f"{side}[{i}] = {v} is not allowed: {name} must lie within a factor "
                        f"{BOX_FACTOR:g} of the geometry's {nominal[i]:g} (a design box is a "
                        "neighbourhood of the spindle it maps onto)")
        bore = max(s.inner_diameter_mm for s in span)
        if not self.lower[2] > bore:
            raise ValueError(f"lower[2] = {self.lower[2]} is not allowed: the span diameter "
                             f"must exceed the bore {bore} mm of the span sections")
        for side in ("lower", "upper"):
            try:
                self.apply(geometry, np.asarray(getattr(self, side), dtype=float))
            except ValueError as exc:
                raise ValueError(f"{side} = {list(getattr(self, side))}: {exc}") from None

    def _span(self, geometry: SpindleGeometry) -> list[int]:
        """Indices of the sections tagged ``span_tag`` (one contiguous run)."""
        idx = [i for i, s in enumerate(geometry.sections) if s.tag == self.span_tag]
        if not idx or idx != list(range(idx[0], idx[-1] + 1)):
            tags = sorted({s.tag for s in geometry.sections})
            raise ValueError(f"span_tag = {self.span_tag!r} is not allowed: the geometry needs "
                             f"one contiguous run of sections with this tag (tags: {tags})")
        return idx

    @property
    def bounds(self) -> np.ndarray:
        """Array of shape (3, 2): lower and upper bound per design variable."""
        return np.column_stack([self.lower, self.upper])

    def corners(self) -> dict[str, np.ndarray]:
        """The box's 8 corners (``"corner -+-"``: lower, upper, lower) and its ``"centre"``.

        >>> list(DesignMap().corners())[:2], DesignMap().corners()["centre"].tolist()
        (['corner ---', 'corner --+'], [2000.0, 525.0, 65.0])
        """
        b = self.bounds
        out = {"corner " + "".join("-+"[k] for k in c): np.array(
            [b[i, k] for i, k in enumerate(c)]) for c in itertools.product((0, 1), repeat=3)}
        return {**out, "centre": b.mean(axis=1)}

    def check(self, x: np.ndarray) -> np.ndarray:
        """Validate a design vector (shape (3,)) against its bounds."""
        x = np.asarray(x, dtype=float)
        if x.shape != (3,):
            raise ValueError(f"design vector has shape {x.shape}: must be (3,) = {self.names}")
        for i, name in enumerate(self.names):
            if not (math.isfinite(x[i]) and self.lower[i] <= x[i] <= self.upper[i]):
                raise ValueError(
                    f"design {name} = {x[i]} is not allowed: must lie in "
                    f"[{self.lower[i]}, {self.upper[i]}]"
                )
        return x

    def bearing_preloads(self, X: np.ndarray) -> dict[str, np.ndarray]:
        """Bearing preloads (N) that designs ``X`` (P, 3) set: ``{preload_bearing: X[:, 0]}``.

        :meth:`apply` changes no other property of a bearing than this preload and its
        position, so ``assembly.bearing_coefficients(geometry, ..., preloads=...)`` gives
        every design's bearing coefficients in one vectorised call.

        >>> DesignMap().bearing_preloads(np.array([[1500.0, 400.0, 60.0]]))
        {'front': array([1500.])}
        """
        X = self.check_batch(X)
        return {self.preload_bearing: X[:, 0].copy()}

    def check_batch(self, X: np.ndarray) -> np.ndarray:
        """Validate designs ``X`` (P, 3) at once; the first bad row raises :meth:`check`'s
        error."""
        X0 = np.asarray(X, dtype=float)
        X = np.atleast_2d(X0)
        if X.ndim != 2 or X.shape[1] != 3:
            raise ValueError(f"designs have shape {X0.shape}: must be (P, 3) = {self.names}")
        ok = np.all(np.isfinite(X) & (X >= self.lower) & (X <= self.upper), axis=1)
        if not ok.all():
            self.check(X[int(np.argmin(ok))])
        return X

    def apply(self, geometry: SpindleGeometry, x: np.ndarray) -> SpindleGeometry:
        """Return the geometry of design ``x``."""
        preload, span, diam = self.check(x)
        idx = self._span(geometry)
        starts = np.concatenate([[0.0], np.cumsum([s.length_mm for s in geometry.sections])])
        z0, z1 = starts[idx[0]], starts[idx[-1] + 1]
        scale = span / (z1 - z0)

        sections = []
        for i, s in enumerate(geometry.sections):
            if i in idx:
                if s.inner_diameter_mm >= diam:
                    raise ValueError(
                        f"design diameter_mm = {diam} is not allowed: must exceed the bore "
                        f"{s.inner_diameter_mm} mm of the span sections"
                    )
                s = replace(s, length_mm=s.length_mm * scale, outer_diameter_mm=diam)
            sections.append(s)
        new_total = float(sum(s.length_mm for s in sections))  # as total_length_mm sums

        def zmap(z: float) -> float:
            if z <= z0:
                return z
            # clamp: rounding must not push an item at the shaft end off the shaft
            if z <= z1:
                return min(z0 + (z - z0) * scale, new_total)
            return min(z + (z1 - z0) * (scale - 1.0), new_total)

        bearings = []
        for b in geometry.bearings:
            law = b.law
            if b.name == self.preload_bearing:
                if not isinstance(law, PreloadLaw):
                    raise ValueError(
                        f"preload_bearing = {b.name!r} needs a 'preload' law, got "
                        f"{law_name(law)!r}"
                    )
                law = replace(law, preload_N=float(preload))
            bearings.append(replace(b, position_mm=zmap(b.position_mm), law=law))
        if self.preload_bearing not in [b.name for b in bearings]:
            raise ValueError(f"preload_bearing = {self.preload_bearing!r} is not a bearing name")
        return replace(
            geometry,
            sections=tuple(sections),
            bearings=tuple(bearings),
            disks=tuple(replace(d, position_mm=zmap(d.position_mm)) for d in geometry.disks),
            unbalances=tuple(
                replace(u, position_mm=zmap(u.position_mm)) for u in geometry.unbalances
            ),
            tool_tip_mm=zmap(geometry.tool_tip_mm),
        )


__all__ = ["BALANCE_GRADES_MM_S", "BOX_FACTOR", "LAWS", "MAX_ELEMENTS", "Bearing", "ConstantLaw",
           "DesignMap", "Disk", "Material", "PreloadLaw", "ShaftSection", "SpindleGeometry",
           "Unbalance", "check_balance_grade"]
