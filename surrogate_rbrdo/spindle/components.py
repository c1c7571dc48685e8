"""The parts a spindle geometry is made of: materials, shaft sections, disks, bearings and
their stiffness laws, unbalances (frozen dataclasses; units in the field names).

Each part checks its own values in ``__post_init__`` (messages name the bare field:
``length_mm = -1.0 is not allowed: ...``); :meth:`SpindleGeometry.from_dict
<surrogate_rbrdo.spindle.geometry.SpindleGeometry.from_dict>` checks types and unknown keys
and prefixes the path (``sections[1].length_mm``).

>>> ShaftSection(length_mm=100.0, outer_diameter_mm=50.0, elements=4).elements
4
>>> ShaftSection(length_mm=100.0, outer_diameter_mm=50.0, inner_diameter_mm=60.0)
Traceback (most recent call last):
...
ValueError: inner_diameter_mm = 60.0 is not allowed: must be smaller than outer_diameter_mm = 50.0
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any

import numpy as np
from pydantic import BeforeValidator

from surrogate_rbrdo.core.schema import parse
from surrogate_rbrdo.core.validate import (
    check_finite,
    check_int,
    check_positive,
    check_range,
    check_text,
)

#: the most finite elements a shaft may have: the dense solvers hold several complex
#: n_dof × n_dof matrices (4 DOFs per node: 1 000 elements are 4 004 DOFs, 256 MB each)
MAX_ELEMENTS = 1000


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material (SI)."""

    E_Pa: float = 2.1e11
    nu: float = 0.3
    rho_kg_m3: float = 7850.0
    yield_Pa: float = 930e6

    def __post_init__(self) -> None:
        check_positive("E_Pa", self.E_Pa)
        check_range("nu", self.nu, -0.99, 0.49)
        check_positive("rho_kg_m3", self.rho_kg_m3)
        check_positive("yield_Pa", self.yield_Pa)


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
        check_positive("length_mm", self.length_mm)
        check_positive("outer_diameter_mm", self.outer_diameter_mm)
        check_positive("inner_diameter_mm", self.inner_diameter_mm, allow_zero=True)
        if self.inner_diameter_mm >= self.outer_diameter_mm:
            raise ValueError(
                f"inner_diameter_mm = {self.inner_diameter_mm} is not allowed: must "
                f"be smaller than outer_diameter_mm = {self.outer_diameter_mm}"
            )
        check_int("elements", self.elements, minimum=1)


@dataclass(frozen=True)
class Disk:
    """A rigid disk (tool holder, motor rotor, ...) at an axial position."""

    name: str
    position_mm: float
    mass_kg: float
    polar_inertia_kgm2: float = 0.0
    diametral_inertia_kgm2: float = 0.0

    def __post_init__(self) -> None:
        check_text("name", self.name)
        check_finite("position_mm", self.position_mm)
        check_positive("mass_kg", self.mass_kg)
        check_positive("polar_inertia_kgm2", self.polar_inertia_kgm2, allow_zero=True)
        check_positive(
            "diametral_inertia_kgm2", self.diametral_inertia_kgm2, allow_zero=True
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
                f"k_N_per_m = {self.k_N_per_m!r} is not allowed: the 'constant' law needs "
                "exactly one of k_N_per_m or k_matrix_N_per_m")
        if self.k_N_per_m is not None:
            check_positive("k_N_per_m", self.k_N_per_m)
        for name in ("k_matrix_N_per_m", "c_matrix_Ns_per_m"):
            val = getattr(self, name)
            if val is not None:
                arr = np.asarray(val, dtype=float)
                if arr.shape != (2, 2) or not np.all(np.isfinite(arr)):
                    raise ValueError(f"{name} = {val!r} is not allowed: must be a finite 2x2")
        check_positive("damping_eta_s", self.damping_eta_s, allow_zero=True)

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
        check_positive("k_ref_N_per_m", self.k_ref_N_per_m)
        check_positive("preload_ref_N", self.preload_ref_N)
        check_positive("preload_N", self.preload_N)
        check_range("exponent", self.exponent, 0.0, 1.0)
        check_positive("damping_eta_s", self.damping_eta_s, allow_zero=True)

    def stiffness(self, preload: np.ndarray | float) -> np.ndarray:
        return self.k_ref_N_per_m * (np.asarray(preload) / self.preload_ref_N) ** self.exponent


LAWS = {"constant": ConstantLaw, "preload": PreloadLaw}


def law_from_data(data: Any) -> ConstantLaw | PreloadLaw:
    """A bearing law from ``{"type": "constant" | "preload", <its fields>}`` (strict types,
    unknown keys refused); a law object is returned as it is.

    >>> law_from_data({"type": "constant", "k_N_per_m": 1e8}).k_N_per_m
    100000000.0
    >>> law_from_data({"type": "preload", "k_ref_N_per_m": "3e8"})
    Traceback (most recent call last):
    ...
    ValueError: law.k_ref_N_per_m = '3e8' is not allowed: must be a number
    """
    if isinstance(data, (ConstantLaw, PreloadLaw)):
        return data
    if not isinstance(data, Mapping):
        raise ValueError(f"law = {data!r} is not allowed: must be a table {{type = "
                         f"{' | '.join(map(repr, LAWS))}, ...}}")
    d = dict(data)
    kind = d.pop("type", None)
    if not isinstance(kind, str) or kind not in LAWS:
        raise ValueError(f"law.type = {kind!r} is not allowed: must be one of {list(LAWS)}")
    return parse(LAWS[kind], d, "law")


@dataclass(frozen=True)
class Bearing:
    """A bearing (spring-damper to ground) at an axial position; in data files its ``law``
    is a table ``{type = "constant" | "preload", ...}`` (:func:`law_from_data`)."""

    name: str
    position_mm: float
    law: Annotated[ConstantLaw | PreloadLaw, BeforeValidator(law_from_data)]

    def __post_init__(self) -> None:
        check_text("name", self.name)
        check_finite("position_mm", self.position_mm)
        if not isinstance(self.law, (ConstantLaw, PreloadLaw)):
            raise ValueError(f"law = {self.law!r} is not allowed: use {list(LAWS)}")


@dataclass(frozen=True)
class Unbalance:
    """A residual unbalance ``U = m e`` (kg m) at an axial position, with a phase."""

    position_mm: float
    magnitude_kgm: float
    phase_deg: float = 0.0

    def __post_init__(self) -> None:
        check_finite("position_mm", self.position_mm)
        check_positive("magnitude_kgm", self.magnitude_kgm, allow_zero=True)
        check_finite("phase_deg", self.phase_deg)


#: the range of ISO 21940-11 balance quality grades, G 0.16 to G 4000 (mm/s)
BALANCE_GRADES_MM_S = (0.16, 4000.0)


def check_balance_grade(name: str, value: object) -> float:
    """``value`` if it is a balance quality grade of ISO 21940-11 (G 0.16 … G 4000, mm/s).

    >>> check_balance_grade("balance_grade_mm_s", 1e300)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: balance_grade_mm_s = 1e+300 is not allowed: must lie in [0.16, 4000.0] (ISO ...
    """
    try:
        return check_range(name, value, *BALANCE_GRADES_MM_S)
    except ValueError as exc:
        raise ValueError(f"{exc} (ISO 21940-11 grades G 0.16 to G 4000, mm/s)") from None


def law_name(law: Any) -> str:
    """The ``type`` of a bearing law object (``"constant"`` or ``"preload"``)."""
    return next(k for k, v in LAWS.items() if isinstance(v, type) and isinstance(law, v))


__all__ = ["BALANCE_GRADES_MM_S", "LAWS", "MAX_ELEMENTS", "Bearing", "ConstantLaw", "Disk",
           "Material", "PreloadLaw", "ShaftSection", "Unbalance", "check_balance_grade",
           "law_from_data", "law_name"]
