"""Ratings of angular-contact spindle bearings: load ratings, life, static safety, speed, heat.

Standards and sources, one per quantity (vectorised over loads and preloads):

* basic dynamic load rating ``C = b_m f_c (i cos α)^0.7 Z^(2/3) D_w^1.8`` (ball diameter
  ``D_w ≤ 25.4 mm``), ``b_m = 1.3``, ``f_c`` from ISO 281:2007 Table 2 (single-row radial and
  angular contact groove ball bearings) at ``D_w cos α / D_pw``;
* basic static load rating ``C0 = f0 i Z D_w² cos α`` (4 200 MPa contact stress), ``f0`` from
  ISO 76:2006 Table 2;
* equivalent dynamic load ``P = X F_r + Y F_a`` (ISO 281 Table 3: α = 15° by ``f0 F_a / C0``,
  α = 25° and 40° constant) and the basic rating life ``L10 = (C/P)³`` 10⁶ revolutions
  (ISO 281 §7), in hours ``L10h = 10⁶ (C/P)³ / (60 n)``;
* equivalent static load ``P0 = max(X0 F_r + Y0 F_a, F_r)`` (ISO 76 Table 4) and the static
  safety factor ``s0 = C0 / P0``;
* permissible speed of a rigidly preloaded set (GMN, *Technical information: limiting speed
  for spindle bearings*): ``n = n_single · f_lub · f_arr(preload class) · f_ball`` with
  ``f_lub`` 1.0 oil-air / 0.75 grease, ``f_arr`` 0.8 / 0.7 / 0.5 for a rigid pair at light /
  medium / heavy preload, ``f_ball`` 1.25 for ceramic balls; between the classes ``f_arr``
  is interpolated linearly in the preload, beyond the heavy class extrapolated with the
  medium-to-heavy slope (floored at 0: no speed);
* friction torque (Palmgren, in Harris & Kotzalas, *Essential Concepts of Bearing
  Technology*, 5th ed., 2007, ch. "Friction"): ``M = M0 + M1``, ``M0 = 1e-7 f0 (ν n)^(2/3)
  d_m³`` (ν n ≥ 2000, N mm), ``M1 = f1 P1 d_m``, ``f1 = 0.001 (P0/C0)^0.33``,
  ``P1 = max(0.9 F_a cot α − 0.1 F_r, F_r)`` for angular-contact ball bearings; the heat
  flow a bearing sheds at its reference conditions, ``q_r A_r`` with ``q_r = 16 kW/m²`` and
  ``A_r = π B (D + d)`` (ISO 15312:2018, thermal reference speed).

>>> b = AngularContactBearing("7014 C", 70.0, 110.0, 20.0, 15.0, 20, 11.112)
>>> round(b.dynamic_load_rating_N), round(b.static_load_rating_N)
(40954, 37963)
>>> round(float(basic_rating_life_h(40950.0, 1500.0, 24000.0)))
14129
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate_rbrdo.core.validate import check_int, check_positive, check_range

#: ISO 281:2007 Table 2, f_c of single-row radial and angular contact groove ball bearings
FC_TABLE = np.array([
    [0.01, 29.1], [0.02, 35.8], [0.03, 40.3], [0.04, 43.8], [0.05, 46.7], [0.06, 49.1],
    [0.07, 51.1], [0.08, 52.8], [0.09, 54.3], [0.10, 55.5], [0.12, 57.5], [0.14, 58.8],
    [0.16, 59.6], [0.18, 59.9], [0.20, 59.9], [0.22, 59.6], [0.24, 59.0], [0.26, 58.2],
    [0.28, 57.1], [0.30, 56.0], [0.32, 54.6], [0.34, 53.2], [0.36, 51.7], [0.38, 50.0],
    [0.40, 48.4]])

#: ISO 76:2006 Table 2, f0 of radial and angular contact groove ball bearings
F0_TABLE = np.array([
    [0.00, 14.7], [0.01, 14.9], [0.02, 15.1], [0.03, 15.3], [0.04, 15.5], [0.05, 15.7],
    [0.06, 15.9], [0.07, 16.1], [0.08, 16.3], [0.09, 16.5], [0.10, 16.4], [0.11, 16.1],
    [0.12, 15.9], [0.13, 15.6], [0.14, 15.4], [0.15, 15.2], [0.16, 14.9], [0.17, 14.7],
    [0.18, 14.4], [0.19, 14.2], [0.20, 14.0], [0.21, 13.7], [0.22, 13.5], [0.23, 13.2],
    [0.24, 13.0], [0.25, 12.8], [0.26, 12.5], [0.27, 12.3], [0.28, 12.1], [0.29, 11.8],
    [0.30, 11.6], [0.31, 11.4], [0.32, 11.2], [0.33, 10.9], [0.34, 10.7], [0.35, 10.5],
    [0.36, 10.3], [0.37, 10.0], [0.38, 9.8], [0.39, 9.6], [0.40, 9.4]])

#: ISO 281 Table 3, single-row angular contact ball bearings, α = 15°: columns
#: f0 F_a / C0, e, Y (with X = 0.44 where F_a / F_r > e)
ISO281_15DEG = np.array([
    [0.178, 0.38, 1.47], [0.357, 0.40, 1.40], [0.714, 0.43, 1.30], [1.07, 0.46, 1.23],
    [1.43, 0.47, 1.19], [2.14, 0.50, 1.12], [3.57, 0.55, 1.02], [5.35, 0.56, 1.00],
    [7.14, 0.56, 1.00]])

#: ISO 281 Table 3 (single row) and ISO 76 Table 4: contact angle → (e, X, Y, X0, Y0)
ISO_FACTORS = {15.0: (None, 0.44, None, 0.5, 0.46), 25.0: (0.68, 0.41, 0.87, 0.5, 0.38),
               40.0: (1.14, 0.35, 0.57, 0.5, 0.26)}

#: GMN speed factors: lubrication, rigid pair at preload class L / M / S, ceramic balls
LUBRICATION_FACTOR = {"oil-air": 1.0, "grease": 0.75}
RIGID_PAIR_FACTORS = (0.8, 0.7, 0.5)
CERAMIC_BALL_FACTOR = 1.25

#: ISO 15312 reference heat flow density (W/mm²) for reference surfaces up to 50 000 mm²
REFERENCE_HEAT_FLOW_W_MM2 = 0.016


@dataclass(frozen=True)
class AngularContactBearing:
    """A single-row angular-contact ball bearing: dimensions (mm), contact angle (°), internal
    geometry (``n_balls`` balls of ``ball_mm``), ball material; load ratings computed by the
    standards (module docstring)."""

    designation: str
    bore_mm: float
    outer_mm: float
    width_mm: float
    contact_angle_deg: float
    n_balls: int
    ball_mm: float
    ceramic_balls: bool = False

    def __post_init__(self) -> None:
        for name in ("bore_mm", "outer_mm", "width_mm", "ball_mm"):
            check_positive(name, getattr(self, name))
        if not self.outer_mm > self.bore_mm:
            raise ValueError(f"outer_mm = {self.outer_mm} is not allowed: must exceed bore_mm "
                             f"= {self.bore_mm}")
        if self.contact_angle_deg not in ISO_FACTORS:
            raise ValueError(f"contact_angle_deg = {self.contact_angle_deg} is not allowed: "
                             f"ISO 281 factors are tabulated here for {sorted(ISO_FACTORS)}")
        check_int("n_balls", self.n_balls, minimum=3)
        check_range("ball_mm", self.ball_mm, 1e-3, 25.4)

    @property
    def pitch_mm(self) -> float:
        return 0.5 * (self.bore_mm + self.outer_mm)

    @property
    def _gamma(self) -> float:
        return self.ball_mm * np.cos(np.deg2rad(self.contact_angle_deg)) / self.pitch_mm

    @property
    def dynamic_load_rating_N(self) -> float:
        fc = np.interp(self._gamma, FC_TABLE[:, 0], FC_TABLE[:, 1])
        cos = np.cos(np.deg2rad(self.contact_angle_deg))
        return float(1.3 * fc * cos**0.7 * self.n_balls ** (2 / 3) * self.ball_mm**1.8)

    @property
    def f0(self) -> float:
        return float(np.interp(self._gamma, F0_TABLE[:, 0], F0_TABLE[:, 1]))

    @property
    def static_load_rating_N(self) -> float:
        cos = np.cos(np.deg2rad(self.contact_angle_deg))
        return float(self.f0 * self.n_balls * self.ball_mm**2 * cos)

    @property
    def reference_surface_mm2(self) -> float:
        """ISO 15312 heat-emitting reference surface ``A_r = π B (D + d)`` (radial bearings)."""
        return float(np.pi * self.width_mm * (self.outer_mm + self.bore_mm))


def equivalent_dynamic_load(b: AngularContactBearing, Fr: np.ndarray, Fa: np.ndarray
                            ) -> np.ndarray:
    """``P = X F_r + Y F_a`` (N) of one single-row bearing (ISO 281 Table 3)."""
    Fr, Fa = np.broadcast_arrays(np.asarray(Fr, float), np.asarray(Fa, float))
    e, X, Y, _, _ = ISO_FACTORS[b.contact_angle_deg]
    if e is None:                                        # α = 15°: by the relative axial load
        rel = b.f0 * Fa / b.static_load_rating_N
        e = np.interp(rel, ISO281_15DEG[:, 0], ISO281_15DEG[:, 1])
        Y = np.interp(rel, ISO281_15DEG[:, 0], ISO281_15DEG[:, 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        heavy_axial = Fa > e * Fr
    return np.where(heavy_axial, X * Fr + Y * Fa, Fr)


def equivalent_static_load(b: AngularContactBearing, Fr: np.ndarray, Fa: np.ndarray
                           ) -> np.ndarray:
    """``P0 = max(X0 F_r + Y0 F_a, F_r)`` (N) of one single-row bearing (ISO 76 Table 4)."""
    _, _, _, X0, Y0 = ISO_FACTORS[b.contact_angle_deg]
    Fr = np.asarray(Fr, float)
    return np.maximum(X0 * Fr + Y0 * np.asarray(Fa, float), Fr)


def basic_rating_life_h(C: float, P: np.ndarray, speed_rpm: float) -> np.ndarray:
    """ISO 281 basic rating life of a ball bearing in hours, ``10⁶ (C/P)³ / (60 n)``."""
    return 1e6 * (C / np.asarray(P, float)) ** 3 / (60.0 * check_positive("speed_rpm",
                                                                          speed_rpm))


def rigid_pair_speed_factor(preload_N: np.ndarray, classes_N: tuple[float, float, float],
                            factors: tuple[float, float, float] = RIGID_PAIR_FACTORS
                            ) -> np.ndarray:
    """Arrangement factor of a rigidly preloaded set at ``preload_N``: the catalogue factors
    at the light / medium / heavy class preloads ``classes_N``, linear between them, constant
    below the light class, extrapolated beyond the heavy class and floored at 0.

    >>> rigid_pair_speed_factor(np.array([100.0, 380.0, 1140.0, 1710.0]), (190, 570, 1140))
    array([0.8 , 0.75, 0.5 , 0.3 ])
    """
    F = np.asarray(preload_N, float)
    cl, f = np.asarray(classes_N, float), np.asarray(factors, float)
    if not (np.all(np.diff(cl) > 0) and np.all(np.diff(f) < 0)):
        raise ValueError(f"classes_N = {tuple(classes_N)} must increase and factors = "
                         f"{tuple(factors)} decrease")
    slope = (f[2] - f[1]) / (cl[2] - cl[1])
    out = np.interp(F, cl, f)
    return np.maximum(np.where(F > cl[2], f[2] + slope * (F - cl[2]), out), 0.0)


def friction_torque_Nmm(b: AngularContactBearing, Fr: np.ndarray, Fa: np.ndarray,
                        speed_rpm: float, viscosity_mm2_s: float, f0: float) -> np.ndarray:
    """Palmgren's friction torque ``M0 + M1`` (N mm) of one bearing (module docstring)."""
    vn = viscosity_mm2_s * speed_rpm
    M0 = (1e-7 * f0 * vn ** (2 / 3) if vn >= 2000 else 160e-7 * f0) * b.pitch_mm**3
    Fr, Fa = np.broadcast_arrays(np.asarray(Fr, float), np.asarray(Fa, float))
    f1 = 0.001 * (equivalent_static_load(b, Fr, Fa) / b.static_load_rating_N) ** 0.33
    cot = 1.0 / np.tan(np.deg2rad(b.contact_angle_deg))
    P1 = np.maximum(0.9 * Fa * cot - 0.1 * Fr, Fr)
    return M0 + f1 * P1 * b.pitch_mm


__all__ = [
    "CERAMIC_BALL_FACTOR",
    "LUBRICATION_FACTOR",
    "REFERENCE_HEAT_FLOW_W_MM2",
    "RIGID_PAIR_FACTORS",
    "AngularContactBearing",
    "basic_rating_life_h",
    "equivalent_dynamic_load",
    "equivalent_static_load",
    "friction_torque_Nmm",
    "rigid_pair_speed_factor",
]
