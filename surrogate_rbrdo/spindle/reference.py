"""The reference spindle: geometry, default effects, design map and θ definition.

Every number and its reason is in ``docs/reference-spindle.md``.

>>> sp = reference_spindle()
>>> sp.design_map.bounds.tolist()
[[1000.0, 3000.0], [300.0, 750.0], [50.0, 80.0]]
>>> m = sp.model(sp.baseline)
>>> m.theta_bearings
('front', 'rear')
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from importlib import resources

import numpy as np

from surrogate_rbrdo.spindle.assembly import RPM, SpindleModel, build_model
from surrogate_rbrdo.spindle.effects import Effect, Gyroscopics, SpeedSoftening, check_effects
from surrogate_rbrdo.spindle.geometry import (
    DesignMap,
    SpindleGeometry,
    Unbalance,
    check_balance_grade,
)

#: speed-softening laws k(n) = k0 (1 - a (n / 24000 rpm)^p) least-squares fitted to the paper's
#: Table 3 (max residual 0.39 % front, 0.21 % rear); k0 goes into the bearings' k_ref.
TABLE3_FIT = {"front": (3.1998e8, 0.19225, 1.2462), "rear": (2.7668e8, 0.18402, 1.5221)}

#: ISO 21940-11 balance quality grade (mm/s) and the speed it refers to
BALANCE_GRADE_MM_S = 2.5
BALANCE_SPEED_RPM = 24000.0
def default_effects() -> tuple[Effect, ...]:
    """Speed softening per Table 3 (front and rear) and gyroscopics on."""
    out: list[Effect] = [
        SpeedSoftening(bearings=(name,), a=a, exponent=p)
        for name, (_, a, p) in TABLE3_FIT.items()
    ]
    out.append(Gyroscopics(g=0.0))
    return tuple(out)


def iso_unbalance_kgm(mass_kg: float, grade_mm_s: float = BALANCE_GRADE_MM_S,
                      speed_rpm: float = BALANCE_SPEED_RPM) -> float:
    """Permissible residual unbalance ``U = m G / Ω`` (kg m) of ISO 21940-11.

    >>> round(iso_unbalance_kgm(10.0) * 1e6, 3)   # g mm
    9.947
    """
    return mass_kg * grade_mm_s * 1e-3 / (speed_rpm * RPM)


@dataclass(frozen=True)
class ReferenceSpindle:
    """A parametric spindle: base geometry + effects + the map of x = [F_f, L, D] onto it."""

    geometry: SpindleGeometry
    effects: tuple[Effect, ...]
    design_map: DesignMap
    baseline: np.ndarray
    theta_bearings: tuple[str, ...] = ("front", "rear")

    def geometry_for(self, x: np.ndarray) -> SpindleGeometry:
        return self.design_map.apply(self.geometry, np.asarray(x, dtype=float))

    def model(self, x: np.ndarray, effects: tuple[Effect, ...] | None = None) -> SpindleModel:
        """The FE model of design ``x`` (with the default effects unless given)."""
        return build_model(self.geometry_for(x), self.effects if effects is None else effects,
                           theta_bearings=self.theta_bearings)

    def check(self) -> ReferenceSpindle:
        """Return ``self`` if its parts fit together, else raise ``ValueError`` naming the
        field: ``design_map`` against the geometry (``DesignMap.check_geometry``), the
        ``effects``' bearings, ``theta_bearings`` (non-empty, existing, distinct),
        ``baseline`` inside the box, and the model of the box's corners.

        >>> from dataclasses import replace
        >>> replace(reference_spindle(), theta_bearings=("front", "nose")).check()
        ... # doctest: +ELLIPSIS
        Traceback (most recent call last):
        ...
        ValueError: theta_bearings = ['front', 'nose'] is not allowed: 'nose' is not a bearing; ...
        """
        names = [b.name for b in self.geometry.bearings]
        try:
            self.design_map.check_geometry(self.geometry)
        except ValueError as exc:
            raise ValueError(f"design_map.{exc}") from None
        check_effects(self.effects, names, "effects")
        tb = list(self.theta_bearings)
        bad = [b for b in tb if b not in names]
        if not tb or bad or len(set(tb)) != len(tb):
            why = ("give the bearings whose stiffness θ scales" if not tb else
                   f"{bad[0]!r} is not a bearing; bearings are {names}" if bad else
                   "a name appears twice")
            raise ValueError(f"theta_bearings = {tb} is not allowed: {why}")
        try:
            self.design_map.check(self.baseline)
        except ValueError as exc:
            raise ValueError(f"baseline = {np.asarray(self.baseline).tolist()}: {exc}") from None
        for side in ("lower", "upper", "baseline"):
            x = getattr(self.design_map, side, self.baseline)
            try:
                self.model(np.asarray(x, dtype=float))
            except ValueError as exc:
                where = side if side == "baseline" else f"design_map.{side}"
                raise ValueError(f"{where} = {np.asarray(x).tolist()}: the model cannot be "
                                 f"built: {exc}") from None
        return self


def _load_geometry(name: str) -> SpindleGeometry:
    text = resources.files("surrogate_rbrdo.data").joinpath(name).read_text()
    return SpindleGeometry.from_dict(tomllib.loads(text))


def _with_iso_unbalance(geom: SpindleGeometry, dmap: DesignMap, baseline: np.ndarray,
                        grade_mm_s: float) -> SpindleGeometry:
    """The fixed in-phase unbalance of the rated-speed problem: ISO 21940-11 ``grade_mm_s`` at
    24 000 rpm for the baseline rotor mass, split equally between the planes."""
    base_model = build_model(dmap.apply(geom, baseline), ())
    U = iso_unbalance_kgm(base_model.rotor_mass_kg, grade_mm_s)
    return replace(geom, unbalances=tuple(
        Unbalance(u.position_mm, U / len(geom.unbalances), u.phase_deg) for u in geom.unbalances
    ))


def reference_spindle(*, balance_grade_mm_s: float = BALANCE_GRADE_MM_S) -> ReferenceSpindle:
    """The project's reference motorized spindle (see ``docs/reference-spindle.md``).

    The residual unbalance is fixed for the spindle family: ISO 21940-11 grade
    ``balance_grade_mm_s`` at 24 000 rpm for the *baseline* rotor mass, split equally between
    the tool-holder and motor-rotor planes, in phase — so every design sees the same excitation.
    (The random-unbalance response, ``spindle.peak_response``, replaces it by each plane's
    ISO tolerance and a random phase.)
    """
    check_balance_grade("balance_grade_mm_s", balance_grade_mm_s)
    geom = _load_geometry("reference_spindle.toml")
    dmap = DesignMap()
    baseline = np.array([2000.0, 500.0, 65.0])
    geom = _with_iso_unbalance(geom, dmap, baseline, balance_grade_mm_s)
    return ReferenceSpindle(geom, default_effects(), dmap, baseline)


#: front preload bounds of the credible variant: the light and the heavy preload class of its
#: front bearing set (``spindle.practice.FRONT_SET``), in N
CREDIBLE_PRELOAD_BOUNDS = (190.0, 1140.0)


def credible_spindle(*, balance_grade_mm_s: float = BALANCE_GRADE_MM_S) -> ReferenceSpindle:
    """The reference spindle with its bearing preloads in the catalogue range of the sets.

    Same rotor, effects and span and diameter bounds; Table 3's stiffness at the medium
    preload class of each bearing set (570 N front, 450 N rear) instead of at 2000 N / 1000 N,
    and the front preload between the light and heavy class, 190–1140 N (the paper's
    1000–3000 N exceeds the heavy class of a 7014 pair, and no rigidly preloaded 7014 pair
    reaches 24 000 rpm there: docs/reference-spindle.md, "Credible variant"). Baseline
    [570 N, 500 mm, 65 mm]: the reference baseline's stiffness.

    >>> sp = credible_spindle()
    >>> sp.design_map.bounds.tolist()
    [[190.0, 1140.0], [300.0, 750.0], [50.0, 80.0]]
    """
    check_balance_grade("balance_grade_mm_s", balance_grade_mm_s)
    geom = _load_geometry("credible_spindle.toml")
    lo, hi = CREDIBLE_PRELOAD_BOUNDS
    dmap = DesignMap(lower=(lo, 300.0, 50.0), upper=(hi, 750.0, 80.0))
    baseline = np.array([570.0, 500.0, 65.0])
    geom = _with_iso_unbalance(geom, dmap, baseline, balance_grade_mm_s)
    return ReferenceSpindle(geom, default_effects(), dmap, baseline)
