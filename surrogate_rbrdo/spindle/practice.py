"""Design constraints a spindle designer imposes, ``g(X) ≤ 0`` for designs ``X = [F, L, D]``.

Each check has its source (module ``bearing_rating`` for the bearing standards):

``speed_front``, ``speed_rear``
    ``1 − n_perm / n_max``: the bearing set's permissible speed at its preload (GMN correction
    factors for rigid pairs, lubrication and ceramic balls, on the single bearing's
    attainable speed) must reach the maximum spindle speed.
``life_front``, ``life_rear``
    ``1 − L10h / L_req``: ISO 281 basic rating life of each bearing of the set at ``n_max``
    under its preload (axial) and its share of the radial reaction to a cutting force at the
    tool plus the rotor weight (statics of the shaft on two supports).
``static_front``, ``static_rear``
    ``1 − s0 / s0_min``: ISO 76 static safety under the preload and a peak tool force.
``span``
    ``1 − L / L_min``: the motor's stator (with end windings) and half of each bearing set,
    plus axial clearances, must fit between the bearing load centres.
``run_up``
    ``t / t_max − 1``: time to accelerate the rotor's polar inertia ``J`` (shaft and disks) to
    ``n_max`` with a motor of constant torque ``P / Ω_b`` up to its base speed and constant
    power ``P`` above: ``t = J Ω_b² / P + J (Ω_max² − Ω_b²) / (2P)``.

The preload-dependent checks use the *hot* preload ``F · thermal_preload_factor`` (1 = the
mounted preload). Every column is dimensionless and 0 on its limit.

>>> import numpy as np
>>> from surrogate_rbrdo.spindle.reference import reference_spindle
>>> con = PracticeConstraints(reference_spindle(), PracticeSpec())
>>> con.names[:3]
('speed_front', 'speed_rear', 'life_front')
>>> con(np.array([[1000.0, 500.0, 65.0]])).shape
(1, 8)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from surrogate_rbrdo.core.validate import check_choice, check_int, check_positive
from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.bearing_rating import (
    CERAMIC_BALL_FACTOR,
    LUBRICATION_FACTOR,
    REFERENCE_HEAT_FLOW_W_MM2,
    RIGID_PAIR_FACTORS,
    AngularContactBearing,
    basic_rating_life_h,
    equivalent_dynamic_load,
    equivalent_static_load,
    friction_torque_Nmm,
    rigid_pair_speed_factor,
)
from surrogate_rbrdo.spindle.geometry import PreloadLaw, SpindleGeometry
from surrogate_rbrdo.spindle.reference import ReferenceSpindle
from surrogate_rbrdo.spindle.unbalance import mass_properties

GRAVITY = 9.81
CHECKS = ("speed_front", "speed_rear", "life_front", "life_rear", "static_front",
          "static_rear", "span", "run_up", "thermal_front")


@dataclass(frozen=True)
class BearingSet:
    """A rigidly preloaded set of ``n_bearings`` equal bearings sharing the radial load.

    ``preload_classes_N``: the catalogue's light / medium / heavy preload of the set;
    ``ndm_single_mm_min``: attainable ``n · d_m`` of one spring-preloaded bearing with steel
    balls and oil-air lubrication (the catalogue's speed value); ``lubrication`` picks the
    GMN lubrication factor; ceramic balls multiply by 1.25.
    """

    bearing: AngularContactBearing
    n_bearings: int = 2
    preload_classes_N: tuple[float, float, float] = (190.0, 570.0, 1140.0)
    ndm_single_mm_min: float = 2.2e6
    lubrication: str = "oil-air"
    arrangement_factors: tuple[float, float, float] = RIGID_PAIR_FACTORS

    def __post_init__(self) -> None:
        check_int("n_bearings", self.n_bearings, minimum=1)
        check_positive("ndm_single_mm_min", self.ndm_single_mm_min)
        check_choice("lubrication", self.lubrication, LUBRICATION_FACTOR)

    def permissible_speed_rpm(self, preload_N: np.ndarray) -> np.ndarray:
        """GMN: ``n_single · f_lub · f_arr(preload) · f_ball`` (rpm)."""
        n_single = self.ndm_single_mm_min / self.bearing.pitch_mm
        f_ball = CERAMIC_BALL_FACTOR if self.bearing.ceramic_balls else 1.0
        return (n_single * LUBRICATION_FACTOR[self.lubrication] * f_ball
                * rigid_pair_speed_factor(preload_N, self.preload_classes_N,
                                          self.arrangement_factors))


@dataclass(frozen=True)
class MotorSpec:
    """Motor of the spindle: power (W), base speed (rpm), stator length incl. end windings."""

    power_W: float = 25e3
    base_speed_rpm: float = 6000.0
    stator_length_mm: float = 230.0

    def __post_init__(self) -> None:
        check_positive("power_W", self.power_W)
        check_positive("base_speed_rpm", self.base_speed_rpm)
        check_positive("stator_length_mm", self.stator_length_mm)


#: front set: two 7014 C hybrid bearings (15°, Table 1) back to back; rear: two 7010 E hybrid
#: (25°, the paper's text). Internal geometry typical of these sizes (assumed: replace by the
#: catalogue's); classes and speed values see docs/reference-spindle.md
FRONT_SET = BearingSet(AngularContactBearing("7014 C/HC", 70.0, 110.0, 20.0, 15.0, 20, 11.112,
                                             ceramic_balls=True))
REAR_SET = BearingSet(AngularContactBearing("7010 E/HC", 50.0, 80.0, 16.0, 25.0, 20, 7.938,
                                            ceramic_balls=True),
                      preload_classes_N=(150.0, 450.0, 900.0), ndm_single_mm_min=2.0e6)


@dataclass(frozen=True)
class PracticeSpec:
    """Requirements and component data of the checks (module docstring); SI where unnamed."""

    front: BearingSet = FRONT_SET
    rear: BearingSet = REAR_SET
    motor: MotorSpec = field(default_factory=MotorSpec)
    front_bearing: str = "front"
    rear_bearing: str = "rear"
    speed_max_rpm: float = 24000.0
    cutting_force_N: float = 300.0
    peak_force_N: float = 3000.0
    life_required_h: float = 20000.0
    static_safety_min: float = 3.0
    run_up_max_s: float = 3.0
    span_clearance_mm: float = 30.0
    thermal_preload_factor: float = 1.0
    viscosity_mm2_s: float = 12.0
    palmgren_f0: float = 1.0
    cooling_factor: float = 1.0
    checks: tuple[str, ...] = CHECKS[:-1]

    def __post_init__(self) -> None:
        for name in ("speed_max_rpm", "cutting_force_N", "peak_force_N", "life_required_h",
                     "static_safety_min", "run_up_max_s", "viscosity_mm2_s", "palmgren_f0",
                     "cooling_factor"):
            check_positive(name, getattr(self, name))
        check_positive("span_clearance_mm", self.span_clearance_mm, allow_zero=True)
        if not self.thermal_preload_factor >= 1.0:
            raise ValueError(f"thermal_preload_factor = {self.thermal_preload_factor} is not "
                             "allowed: must be >= 1 (hot preload / mounted preload)")
        object.__setattr__(self, "checks", tuple(self.checks))
        for c in self.checks:
            check_choice("checks[]", c, CHECKS)


def _layout(g: SpindleGeometry, front: str, rear: str) -> tuple[float, ...]:
    """Tool, front and rear bearing positions (m), rotor mass (kg), centre of mass (m) and
    polar inertia (kg m²) of one geometry (:func:`~.unbalance.mass_properties`)."""
    return (g.tool_tip_mm * 1e-3, g.bearing(front).position_mm * 1e-3,
            g.bearing(rear).position_mm * 1e-3, *mass_properties(g))


@dataclass(frozen=True)
class PracticeConstraints:
    """``g(X) -> (P, k)`` with :attr:`names` (feasible ``≤ 0``), for the spindle's designs."""

    spindle: ReferenceSpindle
    spec: PracticeSpec = field(default_factory=PracticeSpec)

    @property
    def names(self) -> tuple[str, ...]:
        return self.spec.checks

    def quantities(self, X: np.ndarray) -> dict[str, np.ndarray]:
        """The physical quantities behind the checks, per design (SI, rpm, h, s)."""
        s = self.spec
        X = self.spindle.design_map.check_batch(X)
        lay = np.array([_layout(self.spindle.geometry_for(x), s.front_bearing, s.rear_bearing)
                        for x in X])
        zt, zf, zr, mass, zc, J = lay.T
        span = zr - zf
        F_front = X[:, 0] * s.thermal_preload_factor
        rear_law = self.spindle.geometry.bearing(s.rear_bearing).law
        F_rear = np.full(len(X), rear_law.preload_N if isinstance(rear_law, PreloadLaw)
                         else 0.0) * s.thermal_preload_factor
        W = mass * GRAVITY

        def reactions(force):
            # shaft on supports zf < zr; the tool force and the weight on the same side
            Rf = (force * (zr - zt) + W * (zr - zc)) / span
            return np.abs(Rf), np.abs(force + W - Rf)

        Rf, Rr = reactions(s.cutting_force_N)
        Rf0, Rr0 = reactions(s.peak_force_N)
        out = {"span_mm": span * 1e3, "rotor_mass_kg": mass, "polar_inertia_kgm2": J}
        for key, bs, F, R, R0 in (("front", s.front, F_front, Rf, Rf0),
                                  ("rear", s.rear, F_rear, Rr, Rr0)):
            b = bs.bearing
            Fr, Fr0 = R / bs.n_bearings, R0 / bs.n_bearings
            out[f"speed_{key}_rpm"] = bs.permissible_speed_rpm(F)
            P = equivalent_dynamic_load(b, Fr, F)
            out[f"life_{key}_h"] = basic_rating_life_h(b.dynamic_load_rating_N, P,
                                                       s.speed_max_rpm)
            out[f"static_{key}"] = b.static_load_rating_N / equivalent_static_load(b, Fr0, F)
            out[f"radial_{key}_N"] = R
        out["span_min_mm"] = np.full(len(X), s.motor.stator_length_mm + s.span_clearance_mm
                                     + 0.5 * (s.front.n_bearings * s.front.bearing.width_mm
                                              + s.rear.n_bearings * s.rear.bearing.width_mm))
        wb, wm = s.motor.base_speed_rpm * RPM, s.speed_max_rpm * RPM
        P = s.motor.power_W
        out["run_up_s"] = J * wb**2 / P + J * max(wm**2 - wb**2, 0.0) / (2 * P)
        out["friction_front_W"] = self._friction_power(s.front, Rf, F_front)
        return out

    def _friction_power(self, bs: BearingSet, R: np.ndarray, F: np.ndarray) -> np.ndarray:
        s = self.spec
        M = friction_torque_Nmm(bs.bearing, R / bs.n_bearings, F, s.speed_max_rpm,
                                s.viscosity_mm2_s, s.palmgren_f0)
        return bs.n_bearings * M * 1e-3 * s.speed_max_rpm * RPM

    def __call__(self, X: np.ndarray) -> np.ndarray:
        q = self.quantities(X)
        s = self.spec
        n_max = s.speed_max_rpm
        cols = {
            "speed_front": 1.0 - q["speed_front_rpm"] / n_max,
            "speed_rear": 1.0 - q["speed_rear_rpm"] / n_max,
            "life_front": 1.0 - q["life_front_h"] / s.life_required_h,
            "life_rear": 1.0 - q["life_rear_h"] / s.life_required_h,
            "static_front": 1.0 - q["static_front"] / s.static_safety_min,
            "static_rear": 1.0 - q["static_rear"] / s.static_safety_min,
            "span": 1.0 - q["span_mm"] / q["span_min_mm"],
            "run_up": q["run_up_s"] / s.run_up_max_s - 1.0,
            "thermal_front": q["friction_front_W"] / (
                s.cooling_factor * s.front.n_bearings * REFERENCE_HEAT_FLOW_W_MM2
                * s.front.bearing.reference_surface_mm2) - 1.0,
        }
        return np.column_stack([cols[c] for c in self.names])


__all__ = ["CHECKS", "FRONT_SET", "REAR_SET", "BearingSet", "MotorSpec", "PracticeConstraints",
           "PracticeSpec"]
