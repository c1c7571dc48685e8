"""Bearing ratings against hand computations with the standards' tabulated factors.

Each expected value below is worked by hand from the formula and the table rows it needs
(typed here, not read from the module's tables).
"""

import numpy as np
import pytest

from surrogate_rbrdo.spindle.bearing_rating import (
    AngularContactBearing,
    basic_rating_life_h,
    equivalent_dynamic_load,
    equivalent_static_load,
    friction_torque_Nmm,
    rigid_pair_speed_factor,
)

B7014 = AngularContactBearing("7014 C", 70.0, 110.0, 20.0, 15.0, 20, 11.112)
B7010 = AngularContactBearing("7010 E", 50.0, 80.0, 16.0, 25.0, 20, 7.938)


@pytest.mark.known_answer
def test_load_ratings_by_iso_281_and_iso_76():
    g = 11.112 * np.cos(np.deg2rad(15.0)) / 90.0                 # 0.11926
    fc = 55.5 + (57.5 - 55.5) * (g - 0.10) / 0.02                 # ISO 281 Table 2 rows
    C = 1.3 * fc * np.cos(np.deg2rad(15.0)) ** 0.7 * 20 ** (2 / 3) * 11.112**1.8
    f0 = 16.1 + (15.9 - 16.1) * (g - 0.11) / 0.01                 # ISO 76 Table 2 rows
    C0 = f0 * 20 * 11.112**2 * np.cos(np.deg2rad(15.0))
    assert B7014.dynamic_load_rating_N == pytest.approx(C, rel=1e-12)
    assert B7014.static_load_rating_N == pytest.approx(C0, rel=1e-12)
    assert 38e3 < C < 44e3 and 34e3 < C0 < 40e3     # the catalogue range of 7014 C bearings


@pytest.mark.known_answer
def test_equivalent_loads_and_life():
    # 15°: f0 Fa / C0 = 0.44 lies between the rows 0.357 (e 0.40, Y 1.40) and 0.714 (0.43, 1.30)
    Fa = 0.44 * B7014.static_load_rating_N / B7014.f0
    t = (0.44 - 0.357) / (0.714 - 0.357)
    Y = 1.40 + (1.30 - 1.40) * t
    assert equivalent_dynamic_load(B7014, 200.0, Fa) == pytest.approx(0.44 * 200 + Y * Fa)
    assert equivalent_dynamic_load(B7014, 5000.0, 100.0) == pytest.approx(5000.0)  # Fa/Fr < e
    # 25°: e 0.68, X 0.41, Y 0.87; static X0 0.5, Y0 0.38
    assert equivalent_dynamic_load(B7010, 300.0, 450.0) == pytest.approx(0.41 * 300 + 0.87 * 450)
    assert equivalent_static_load(B7010, 300.0, 450.0) == pytest.approx(0.5 * 300 + 0.38 * 450)
    assert equivalent_static_load(B7010, 900.0, 100.0) == pytest.approx(900.0)   # max(.., Fr)
    assert equivalent_static_load(B7014, 400.0, 1000.0) == pytest.approx(0.5 * 400 + 460.0)
    # L10h = 1e6 (C/P)^3 / (60 n): C/P = 8 at 1500 rpm -> 512e6 rev / 90 000 rev/h
    assert basic_rating_life_h(52e3, 6.5e3, 1500.0) == pytest.approx(512e6 / 90000.0)


@pytest.mark.known_answer
def test_gmn_speed_factor_interpolation_and_extrapolation():
    cl = (200.0, 600.0, 1200.0)
    F = np.array([50.0, 200.0, 400.0, 900.0, 1200.0, 1800.0, 5000.0])
    want = [0.8, 0.8, 0.75, 0.6, 0.5, 0.5 - 0.2 / 600 * 600, 0.0]
    np.testing.assert_allclose(rigid_pair_speed_factor(F, cl), want, atol=1e-12)
    with pytest.raises(ValueError, match="must increase"):
        rigid_pair_speed_factor(F, (600.0, 200.0, 1200.0))


@pytest.mark.known_answer
def test_palmgren_friction_torque():
    # ν n = 12 × 24 000 = 288 000 ≥ 2000: M0 = 1e-7 f0 (ν n)^(2/3) d_m³
    M0 = 1e-7 * 1.0 * 288000 ** (2 / 3) * 90.0**3
    P0 = max(0.5 * 100 + 0.46 * 1000, 100)
    f1 = 0.001 * (P0 / B7014.static_load_rating_N) ** 0.33
    P1 = max(0.9 * 1000 / np.tan(np.deg2rad(15)) - 0.1 * 100, 100)
    M = friction_torque_Nmm(B7014, 100.0, 1000.0, 24000.0, 12.0, 1.0)
    assert M == pytest.approx(M0 + f1 * P1 * 90.0, rel=1e-12)


def test_bad_bearing_data_are_refused():
    with pytest.raises(ValueError, match="contact_angle_deg"):
        AngularContactBearing("x", 70.0, 110.0, 20.0, 20.0, 20, 11.0)
    with pytest.raises(ValueError, match="outer_mm"):
        AngularContactBearing("x", 70.0, 60.0, 20.0, 15.0, 20, 11.0)
