"""Practice constraints: statics, inertia and run-up by hand; their verdict on the two boxes."""

import numpy as np
import pytest

from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.bearing_rating import basic_rating_life_h, equivalent_dynamic_load
from surrogate_rbrdo.spindle.practice import (
    CHECKS,
    FRONT_SET,
    PracticeConstraints,
    PracticeSpec,
)
from surrogate_rbrdo.spindle.reference import (
    CREDIBLE_PRELOAD_BOUNDS,
    credible_spindle,
    reference_spindle,
)

SP = reference_spindle()
CR = credible_spindle()


@pytest.mark.known_answer
def test_mass_inertia_reactions_and_run_up_by_hand():
    x = np.array([1000.0, 500.0, 65.0])
    q = PracticeConstraints(SP).quantities(x[None])
    m = SP.model(x)
    assert q["rotor_mass_kg"][0] == pytest.approx(m.rotor_mass_kg, rel=1e-12)
    # polar inertia of the hollow sections ρ π L (D⁴ − d⁴)/32 and the disks' J_p
    J = sum(7850 * np.pi * L * (Do**4 - 0.03**4) / 32
            for L, Do in ((0.1, 0.07), (0.5, 0.065), (0.08, 0.05))) + 1.1e-3 + 8.9e-3 + 3e-4
    assert q["polar_inertia_kgm2"][0] == pytest.approx(J, rel=1e-12)
    wb, wm = 6000 * RPM, 24000 * RPM
    assert q["run_up_s"][0] == pytest.approx(J * wb**2 / 25e3 + J * (wm**2 - wb**2) / 50e3)
    # reactions: tool force 300 N at z = 0, supports at 0.1 and 0.6 m, weight at the CM
    W = m.rotor_mass_kg * 9.81
    zc = (sum(7850 * np.pi * (Do**2 - 0.03**2) / 4 * L * zm for L, Do, zm in
              ((0.1, 0.07, 0.05), (0.5, 0.065, 0.35), (0.08, 0.05, 0.64)))
          + 1.8 * 0.0 + 5.0 * 0.35 + 0.6 * 0.68) / m.rotor_mass_kg
    Rf = (300 * 0.6 + W * (0.6 - zc)) / 0.5
    assert q["radial_front_N"][0] == pytest.approx(Rf, rel=1e-9)
    assert q["radial_rear_N"][0] == pytest.approx(abs(300 + W - Rf), rel=1e-9)
    P = equivalent_dynamic_load(FRONT_SET.bearing, Rf / 2, 1000.0)
    assert q["life_front_h"][0] == pytest.approx(
        basic_rating_life_h(FRONT_SET.bearing.dynamic_load_rating_N, P, 24000.0))
    assert q["span_min_mm"][0] == pytest.approx(230 + 30 + 20 + 16)


def test_the_papers_preload_box_cannot_reach_24000_rpm():
    """Claim: no rigidly preloaded 7014 pair reaches 24 000 rpm at 1 000–3 000 N (GMN factors
    on the assumed catalogue data), and the ISO 281 life at 24 000 rpm is below 20 000 h."""
    con = PracticeConstraints(SP)
    F = np.linspace(1000.0, 3000.0, 5)
    X = np.column_stack([F, np.full(5, 450.0), np.full(5, 65.0)])
    g = dict(zip(con.names, con(X).T, strict=True))
    assert np.all(g["speed_front"] > 0) and np.all(g["life_front"] > 0)
    assert np.all(g["speed_rear"] > 0)                 # the rear set at 1 000 N as well


def test_the_credible_box_has_feasible_designs_and_a_speed_limited_preload():
    con = PracticeConstraints(CR)
    lo, hi = CREDIBLE_PRELOAD_BOUNDS
    F = np.linspace(lo, hi, 41)
    X = np.column_stack([F, np.full(41, 450.0), np.full(41, 65.0)])
    g = dict(zip(con.names, con(X).T, strict=True))
    ok = np.all(con(X) <= 0, axis=1)
    assert ok[0] and not ok[-1]
    # the speed check is the first to fail as the preload grows
    first = np.flatnonzero(~ok)[0]
    assert g["speed_front"][first] > 0 and g["life_front"][first] <= 0


def test_spec_validation():
    with pytest.raises(ValueError, match="checks"):
        PracticeSpec(checks=("speed_front", "noise"))
    with pytest.raises(ValueError, match="thermal_preload_factor"):
        PracticeSpec(thermal_preload_factor=0.9)
    assert PracticeConstraints(SP, PracticeSpec(checks=CHECKS)).names[-1] == "thermal_front"
