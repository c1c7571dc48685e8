"""The plain geometry description of a spindle, loadable from TOML or JSON.

Units follow the field names (``_mm``, ``_kg``, ``_N``...) at input; everything is converted to SI
when the model is assembled. The format is documented in ``docs/geometry-format.md``.

>>> g = SpindleGeometry.from_dict({
...     "sections": [{"length_mm": 100, "outer_diameter_mm": 50, "elements": 4}],
...     "bearings": [{"name": "a", "position_mm": 0, "law": {"type": "constant",
...                   "k_N_per_m": 1e8}},
...                  {"name": "b", "position_mm": 100, "law": {"type": "constant",
...                   "k_N_per_m": 1e8}}],
...     "tool_tip_mm": 0.0})
>>> g.total_length_mm, len(g.bearings)
(100.0, 2)
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from surrogate_rbrdo.core.validate import (
    check_choice,
    check_finite,
    check_int,
    check_keys,
    check_positive,
    check_range,
)


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material (SI)."""

    E_Pa: float = 2.1e11
    nu: float = 0.3
    rho_kg_m3: float = 7850.0
    yield_Pa: float = 930e6

    def __post_init__(self) -> None:
        check_positive("material.E_Pa", self.E_Pa)
        check_range("material.nu", self.nu, -0.99, 0.49)
        check_positive("material.rho_kg_m3", self.rho_kg_m3)
        check_positive("material.yield_Pa", self.yield_Pa)


@dataclass(frozen=True)
class ShaftSection:
    """A cylindrical (optionally hollow) shaft segment, from left to right."""

    length_mm: float
    outer_diameter_mm: float
    inner_diameter_mm: float = 0.0
    material: str = "steel"
    elements: int = 1
    tag: str = ""

    def __post_init__(self) -> None:
        check_positive("sections[].length_mm", self.length_mm)
        check_positive("sections[].outer_diameter_mm", self.outer_diameter_mm)
        check_positive("sections[].inner_diameter_mm", self.inner_diameter_mm, allow_zero=True)
        if self.inner_diameter_mm >= self.outer_diameter_mm:
            raise ValueError(
                f"sections[].inner_diameter_mm = {self.inner_diameter_mm} is not allowed: must "
                f"be smaller than outer_diameter_mm = {self.outer_diameter_mm}"
            )
        check_int("sections[].elements", self.elements, minimum=1)


@dataclass(frozen=True)
class Disk:
    """A rigid disk (tool holder, motor rotor, ...) at an axial position."""

    name: str
    position_mm: float
    mass_kg: float
    polar_inertia_kgm2: float = 0.0
    diametral_inertia_kgm2: float = 0.0

    def __post_init__(self) -> None:
        check_finite("disks[].position_mm", self.position_mm)
        check_positive("disks[].mass_kg", self.mass_kg)
        check_positive("disks[].polar_inertia_kgm2", self.polar_inertia_kgm2, allow_zero=True)
        check_positive(
            "disks[].diametral_inertia_kgm2", self.diametral_inertia_kgm2, allow_zero=True
        )


@dataclass(frozen=True)
class ConstantLaw:
    """Constant bearing coefficients: isotropic ``k_N_per_m`` or a full 2x2 matrix.

    Damping is either a full 2x2 matrix ``c_Ns_per_m`` or ``η K`` (``damping_eta_s``).
    """

    k_N_per_m: float | None = None
    k_matrix_N_per_m: tuple[tuple[float, float], tuple[float, float]] | None = None
    c_matrix_Ns_per_m: tuple[tuple[float, float], tuple[float, float]] | None = None
    damping_eta_s: float = 4e-6

    def __post_init__(self) -> None:
        if (self.k_N_per_m is None) == (self.k_matrix_N_per_m is None):
            raise ValueError(
                "bearing law 'constant' needs exactly one of k_N_per_m or k_matrix_N_per_m"
            )
        if self.k_N_per_m is not None:
            check_positive("law.k_N_per_m", self.k_N_per_m)
        for name in ("k_matrix_N_per_m", "c_matrix_Ns_per_m"):
            val = getattr(self, name)
            if val is not None:
                arr = np.asarray(val, dtype=float)
                if arr.shape != (2, 2) or not np.all(np.isfinite(arr)):
                    raise ValueError(f"law.{name} = {val!r} is not allowed: must be a finite 2x2")
        check_positive("law.damping_eta_s", self.damping_eta_s, allow_zero=True)

    def stiffness_matrix(self) -> np.ndarray:
        if self.k_matrix_N_per_m is not None:
            return np.asarray(self.k_matrix_N_per_m, dtype=float)
        return self.k_N_per_m * np.eye(2)


@dataclass(frozen=True)
class PreloadLaw:
    """Hertzian preload law ``k(F) = k_ref (F / F_ref)^exponent`` (isotropic, at Ω = 0).

    For angular-contact ball bearings under a rigid preload the radial stiffness grows as the
    cube root of the axial preload (Hertz point contact, δ ∝ F^{2/3} ⇒ k = dF/dδ ∝ F^{1/3}).
    Speed softening and thermal preload growth are separate, switchable effects.

    >>> law = PreloadLaw(k_ref_N_per_m=3e8, preload_ref_N=2000, preload_N=2000 * 8)
    >>> round(float(law.stiffness(law.preload_N)) / 3e8, 12)
    2.0
    """

    k_ref_N_per_m: float
    preload_ref_N: float
    preload_N: float
    exponent: float = 1.0 / 3.0
    damping_eta_s: float = 4e-6

    def __post_init__(self) -> None:
        check_positive("law.k_ref_N_per_m", self.k_ref_N_per_m)
        check_positive("law.preload_ref_N", self.preload_ref_N)
        check_positive("law.preload_N", self.preload_N)
        check_range("law.exponent", self.exponent, 0.0, 1.0)
        check_positive("law.damping_eta_s", self.damping_eta_s, allow_zero=True)

    def stiffness(self, preload: np.ndarray | float) -> np.ndarray:
        return self.k_ref_N_per_m * (np.asarray(preload) / self.preload_ref_N) ** self.exponent


LAWS = {"constant": ConstantLaw, "preload": PreloadLaw}


@dataclass(frozen=True)
class Bearing:
    """A bearing (spring-damper to ground) at an axial position."""

    name: str
    position_mm: float
    law: ConstantLaw | PreloadLaw

    def __post_init__(self) -> None:
        check_finite("bearings[].position_mm", self.position_mm)
        if not isinstance(self.law, (ConstantLaw, PreloadLaw)):
            raise ValueError(f"bearings[].law = {self.law!r} is not allowed: use {list(LAWS)}")


@dataclass(frozen=True)
class Unbalance:
    """A residual unbalance ``U = m e`` (kg m) at an axial position, with a phase."""

    position_mm: float
    magnitude_kgm: float
    phase_deg: float = 0.0

    def __post_init__(self) -> None:
        check_finite("unbalances[].position_mm", self.position_mm)
        check_positive("unbalances[].magnitude_kgm", self.magnitude_kgm, allow_zero=True)
        check_finite("unbalances[].phase_deg", self.phase_deg)


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
        for s in self.sections:
            if s.material not in self.materials:
                raise ValueError(
                    f"sections[].material = {s.material!r} is not allowed: known materials "
                    f"{sorted(self.materials)}"
                )
        total = self.total_length_mm
        for kind, items in (("bearings", self.bearings), ("disks", self.disks),
                            ("unbalances", self.unbalances)):
            for it in items:
                if not (0.0 <= it.position_mm <= total):
                    raise ValueError(
                        f"{kind}[].position_mm = {it.position_mm} is not allowed: must lie on "
                        f"the shaft, in [0, {total}] mm"
                    )
        names = [b.name for b in self.bearings]
        if len(set(names)) != len(names):
            raise ValueError(f"bearings[].name = {names} is not allowed: names must be unique")
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
    def from_dict(cls, data: Mapping[str, Any]) -> SpindleGeometry:
        """Build from plain data (as read from TOML/JSON); unknown keys raise."""
        top = {f.name for f in dataclasses.fields(cls)}
        check_keys("geometry", data, top)
        d = dict(data)
        mats = {"steel": Material()}
        for name, m in dict(d.get("materials", {})).items():
            mats[name] = _build(Material, m, f"materials.{name}")
        d["materials"] = mats
        d["sections"] = tuple(_build(ShaftSection, s, "sections[]") for s in d.get("sections", ()))
        d["disks"] = tuple(_build(Disk, s, "disks[]") for s in d.get("disks", ()))
        d["unbalances"] = tuple(
            _build(Unbalance, s, "unbalances[]") for s in d.get("unbalances", ())
        )
        bearings = []
        for b in d.get("bearings", ()):
            check_keys("bearings[]", b, {"name", "position_mm", "law"})
            law = dict(b.get("law", {}))
            kind = check_choice("bearings[].law.type", law.pop("type", None), LAWS)
            lawobj = _build(LAWS[kind], law, f"bearings[].law ({kind})")
            bearings.append(Bearing(name=b["name"], position_mm=b["position_mm"], law=lawobj))
        d["bearings"] = tuple(bearings)
        return cls(**d)

    @classmethod
    def load(cls, path: str | Path) -> SpindleGeometry:
        """Load a ``.toml`` or ``.json`` geometry file."""
        path = Path(path)
        if path.suffix == ".toml":
            data = tomllib.loads(path.read_text())
        elif path.suffix == ".json":
            data = json.loads(path.read_text())
        else:
            raise ValueError(f"geometry file {str(path)!r}: suffix must be .toml or .json")
        return cls.from_dict(data.get("geometry", data))

    def to_dict(self) -> dict[str, Any]:
        """Plain data that :meth:`from_dict` reads back."""
        out = dataclasses.asdict(self)
        out["materials"] = {k: dataclasses.asdict(v) for k, v in self.materials.items()}
        out["bearings"] = [
            {"name": b.name, "position_mm": b.position_mm,
             "law": {"type": _law_name(b.law), **_drop_none(dataclasses.asdict(b.law))}}
            for b in self.bearings
        ]
        return _drop_none(out)


def _law_name(law: Any) -> str:
    return next(k for k, v in LAWS.items() if isinstance(law, v))


def _drop_none(d: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in d.items() if v is not None}


def _build(cls: type, data: Mapping[str, Any], where: str) -> Any:
    check_keys(where, data, {f.name for f in dataclasses.fields(cls)})
    try:
        return cls(**data)
    except TypeError as exc:  # a required field missing
        raise ValueError(f"{where}: {exc}") from None


# ---------------------------------------------------------------------- design vector
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
        for i, name in enumerate(self.names):
            if not (math.isfinite(self.lower[i]) and math.isfinite(self.upper[i])
                    and self.lower[i] < self.upper[i]):
                raise ValueError(
                    f"design bounds for {name} = [{self.lower[i]}, {self.upper[i]}] are not "
                    "allowed: lower must be finite and smaller than upper"
                )

    @property
    def bounds(self) -> np.ndarray:
        """Array of shape (3, 2): lower and upper bound per design variable."""
        return np.column_stack([self.lower, self.upper])

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
        idx = [i for i, s in enumerate(geometry.sections) if s.tag == self.span_tag]
        if not idx or idx != list(range(idx[0], idx[-1] + 1)):
            raise ValueError(
                f"span_tag = {self.span_tag!r}: the geometry needs one contiguous run of "
                "sections with this tag"
            )
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
            if z <= z1:
                return z0 + (z - z0) * scale
            # clamp: rounding must not push an item at the shaft end off the shaft
            return min(z + (z1 - z0) * (scale - 1.0), new_total)

        bearings = []
        for b in geometry.bearings:
            law = b.law
            if b.name == self.preload_bearing:
                if not isinstance(law, PreloadLaw):
                    raise ValueError(
                        f"preload_bearing = {b.name!r} needs a 'preload' law, got "
                        f"{_law_name(law)!r}"
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
