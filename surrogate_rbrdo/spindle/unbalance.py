"""Permissible residual unbalance per plane (ISO 21940-11), for any design of a spindle.

ISO 21940-11:2016 (formerly ISO 1940-1), §5 and Table 1: a rotor of mass ``m`` balanced to
grade ``G`` (mm/s) at its maximum service speed ``Ω_max`` may keep a residual unbalance up to
``U_per = m e_per = m G / Ω_max``; machine-tool drives are G 2.5 (Table 1). The standard
bounds the *magnitude* only: the angular position of the residual is whatever the last
correction left, so the phase of each plane is random per assembly.

Each unbalance plane of the geometry carries the residual of the parts balanced in it:
:class:`PlaneTolerance` names them by disk (e.g. the tool holder, balanced as a rotor of its
own), or takes "the rest of the rotor" (the shaft and every disk no other plane claims). Plane
tolerances therefore follow the design: a longer or thicker shaft is heavier and may keep
proportionally more unbalance at the same grade.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> m = reference_spindle().model(np.array([2000.0, 500.0, 65.0]))
>>> (permissible_unbalance(m, REFERENCE_TOLERANCES) * 1e6).round(2).tolist()   # g mm
[1.79, 19.0]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_positive
from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel
from surrogate_rbrdo.spindle.geometry import SpindleGeometry


@dataclass(frozen=True)
class PlaneTolerance:
    """Balance grade of one unbalance plane and the parts balanced in it.

    ``disks``: names of the geometry's disks whose mass this plane's residual belongs to;
    ``None``: the rest of the rotor (shaft plus the disks no other plane names).
    """

    grade_mm_s: float = 2.5
    disks: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        check_positive("grade_mm_s", self.grade_mm_s)
        if self.disks is not None:
            object.__setattr__(self, "disks", tuple(self.disks))


@dataclass(frozen=True)
class UnbalanceTolerances:
    """One :class:`PlaneTolerance` per unbalance plane of the geometry (in its order), and the
    service speed the grade refers to (default: the geometry's maximum speed)."""

    planes: tuple[PlaneTolerance, ...]
    speed_rpm: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "planes", tuple(self.planes))
        if not self.planes:
            raise ValueError("planes = () is not allowed: give one PlaneTolerance per plane")
        if sum(p.disks is None for p in self.planes) > 1:
            raise ValueError("planes: at most one plane may take 'the rest of the rotor' "
                             "(disks = None)")
        if self.speed_rpm is not None:
            check_positive("speed_rpm", self.speed_rpm)


#: the reference spindle: the tool holder (with tool) balanced on its own in the tool plane,
#: the rest of the rotor (shaft, motor rotor, rear unit) in the motor plane; G 2.5, the
#: ISO 21940-11 grade of machine-tool drives, at the maximum speed 24 000 rpm
REFERENCE_TOLERANCES = UnbalanceTolerances(
    (PlaneTolerance(2.5, ("tool_holder",)), PlaneTolerance(2.5, None)))


def plane_masses(model: SpindleModel, tolerances: UnbalanceTolerances) -> np.ndarray:
    """Mass (kg) balanced in each plane: its named disks, or the rest of the rotor."""
    return _plane_masses(model.geometry, model.rotor_mass_kg, tolerances)


def _plane_masses(g: SpindleGeometry, rotor_mass_kg: float,
                  tolerances: UnbalanceTolerances) -> np.ndarray:
    if len(tolerances.planes) != len(g.unbalances):
        raise ValueError(f"tolerances give {len(tolerances.planes)} planes, the geometry has "
                         f"{len(g.unbalances)} unbalance planes")
    disks = {d.name: d.mass_kg for d in g.disks}
    claimed = 0.0
    out = np.zeros(len(tolerances.planes))
    for j, p in enumerate(tolerances.planes):
        if p.disks is None:
            continue
        for name in p.disks:
            if name not in disks:
                raise ValueError(f"tolerances.planes[{j}].disks: {name!r} is not a disk; "
                                 f"disks are {sorted(disks)}")
            out[j] += disks[name]
        claimed += out[j]
    for j, p in enumerate(tolerances.planes):
        if p.disks is None:
            out[j] = rotor_mass_kg - claimed
    return out


def mass_properties(g: SpindleGeometry) -> tuple[float, float, float]:
    """Rotor mass (kg), centre of mass (m from the left end) and polar inertia (kg m²) from the
    geometry alone: shaft sections (ρ π (r_o² − r_i²) L, ½ m (r_o² + r_i²)) and disks — what the
    FE model assembles without building its matrices."""
    rho = {k: m.rho_kg_m3 for k, m in g.materials.items()}
    z0, mass, moment, J = 0.0, 0.0, 0.0, 0.0
    for s in g.sections:
        L, ro, ri = s.length_mm * 1e-3, s.outer_diameter_mm * 5e-4, s.inner_diameter_mm * 5e-4
        m = rho[s.material] * np.pi * (ro**2 - ri**2) * L
        mass, moment = mass + m, moment + m * (z0 + L / 2)
        J += 0.5 * m * (ro**2 + ri**2)
        z0 += L
    for d in g.disks:
        mass, moment = mass + d.mass_kg, moment + d.mass_kg * d.position_mm * 1e-3
        J += d.polar_inertia_kgm2
    return mass, moment / mass, J


def geometry_rotor_mass_kg(geometry: SpindleGeometry) -> float:
    """Rotor mass (kg) from the geometry alone (:func:`mass_properties`), the mass the FE
    model assembles (``SpindleModel.rotor_mass_kg``) without building its matrices.

    >>> import numpy as np
    >>> from surrogate_rbrdo.spindle.reference import reference_spindle
    >>> sp = reference_spindle()
    >>> x = np.array([2000.0, 500.0, 65.0])
    >>> bool(np.isclose(geometry_rotor_mass_kg(sp.geometry_for(x)),
    ...                 sp.model(x).rotor_mass_kg, rtol=1e-12))
    True
    """
    return float(mass_properties(geometry)[0])


def permissible_unbalance(model: SpindleModel, tolerances: UnbalanceTolerances) -> np.ndarray:
    """``U_per = m G / Ω_max`` (kg m) of each plane (ISO 21940-11 §5)."""
    return _permissible(model.geometry, plane_masses(model, tolerances), tolerances)


def geometry_permissible_unbalance(geometry: SpindleGeometry,
                                   tolerances: UnbalanceTolerances) -> np.ndarray:
    """:func:`permissible_unbalance` from the geometry alone (:func:`geometry_rotor_mass_kg`:
    no FE matrices), e.g. at a surrogate's prediction designs."""
    masses = _plane_masses(geometry, geometry_rotor_mass_kg(geometry), tolerances)
    return _permissible(geometry, masses, tolerances)


def _permissible(g: SpindleGeometry, masses: np.ndarray,
                 tolerances: UnbalanceTolerances) -> np.ndarray:
    speed = tolerances.speed_rpm or g.speed_max_rpm
    grades = np.array([p.grade_mm_s for p in tolerances.planes]) * 1e-3
    return masses * grades / (speed * RPM)


__all__ = [
    "REFERENCE_TOLERANCES",
    "PlaneTolerance",
    "UnbalanceTolerances",
    "geometry_permissible_unbalance",
    "geometry_rotor_mass_kg",
    "mass_properties",
    "permissible_unbalance",
    "plane_masses",
]
