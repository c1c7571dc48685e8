"""ISO 21940-11 plane tolerances and the random-unbalance peak response."""

import numpy as np
import pytest

from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.peak_response import PeakUnbalanceResponse, ThetaSpec
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.spindle.unbalance import (
    REFERENCE_TOLERANCES,
    PlaneTolerance,
    UnbalanceTolerances,
    permissible_unbalance,
    plane_masses,
)

SP = reference_spindle()


@pytest.mark.known_answer
def test_permissible_unbalance_is_m_G_over_omega_per_plane():
    m = SP.model(np.array([2000.0, 600.0, 70.0]))
    masses = plane_masses(m, REFERENCE_TOLERANCES)
    assert masses[0] == 1.8 and masses.sum() == pytest.approx(m.rotor_mass_kg)
    U = permissible_unbalance(m, REFERENCE_TOLERANCES)
    np.testing.assert_allclose(U, masses * 2.5e-3 / (24000 * RPM))
    tol = UnbalanceTolerances((PlaneTolerance(1.0, ("tool_holder",)), PlaneTolerance(6.3)),
                              speed_rpm=12000.0)
    np.testing.assert_allclose(permissible_unbalance(m, tol),
                               masses * np.array([1.0, 6.3]) * 1e-3 / (12000 * RPM))


def test_tolerance_errors():
    m = SP.model(SP.baseline)
    with pytest.raises(ValueError, match="not a disk"):
        plane_masses(m, UnbalanceTolerances((PlaneTolerance(2.5, ("spindle",)),
                                             PlaneTolerance())))
    with pytest.raises(ValueError, match="planes"):
        plane_masses(m, UnbalanceTolerances((PlaneTolerance(),)))
    with pytest.raises(ValueError, match="at most one"):
        UnbalanceTolerances((PlaneTolerance(), PlaneTolerance()))


def test_theta_spec_columns_and_split():
    spec = ThetaSpec(thermal_max=0.5, relative_phase=False)
    assert spec.names == ("k_front", "k_rear", "thermal_preload", "u_frac[0]", "u_frac[1]",
                          "phase_deg[0]", "phase_deg[1]")
    k, tau, r, phi = spec.split(np.array([[1.0, 0.9, 0.2, 0.5, 1.0, 90.0, 180.0]]))
    assert tau.tolist() == [0.2] and r.tolist() == [[0.5, 1.0]]
    np.testing.assert_allclose(phi, [[np.pi / 2, np.pi]])
    with pytest.raises(ValueError, match="u_frac"):
        spec.split(np.array([[1.0, 0.9, 0.2, 1.5, 1.0, 90.0, 180.0]]))
    with pytest.raises(ValueError, match="columns"):
        spec.split(np.ones((1, 5)))
    assert ThetaSpec(magnitude="limit").names == ("k_front", "k_rear", "phase_deg[1]")


@pytest.mark.known_answer
def test_coupled_response_equals_the_fe_peak_search():
    resp = PeakUnbalanceResponse(SP)
    rng = np.random.default_rng(4)
    th = np.column_stack([rng.normal(1, 0.02, (3, 2)), rng.random((3, 2)),
                          360 * rng.random(3)])
    X = np.array([[2000.0, 500.0, 65.0], [3000.0, 350.0, 80.0]])
    direct = PeakUnbalanceResponse(SP, method="direct")
    np.testing.assert_allclose(resp(X, th), direct(X, th), rtol=1e-3)


def test_phases_relative_to_the_first_plane_lose_nothing():
    """A common rotation of all phasors leaves the orbit amplitude unchanged."""
    x = np.array([[2500.0, 450.0, 70.0]])
    th_abs = np.array([[1.0, 1.0, 0.6, 0.9, 40.0, 250.0], [1.01, 0.97, 0.3, 0.2, 300.0, 10.0]])
    th_rel = np.column_stack([th_abs[:, :4], (th_abs[:, 5] - th_abs[:, 4]) % 360])
    y_abs = PeakUnbalanceResponse(SP, ThetaSpec(relative_phase=False))(x, th_abs)
    y_rel = PeakUnbalanceResponse(SP)(x, th_rel)
    np.testing.assert_allclose(y_abs, y_rel, rtol=1e-10)


def test_thermal_state_is_a_preload_rise_through_the_hertz_law():
    """τ raises the front preload to F (1 + τ): the same as the design with that preload."""
    spec = ThetaSpec(thermal_max=1.0)
    th = np.array([[1.0, 1.0, 0.5, 0.8, 0.7, 120.0]])
    y = PeakUnbalanceResponse(SP, spec)(np.array([[1500.0, 500.0, 65.0]]), th)
    y_hot = PeakUnbalanceResponse(SP)(np.array([[2250.0, 500.0, 65.0]]),
                                      np.delete(th, 2, axis=1))
    np.testing.assert_allclose(y, y_hot, rtol=1e-10)


def test_response_checks_its_spec():
    with pytest.raises(ValueError, match="n_planes"):
        PeakUnbalanceResponse(SP, ThetaSpec(n_planes=3))
    with pytest.raises(ValueError, match="bearings"):
        PeakUnbalanceResponse(SP, ThetaSpec(bearings=("rear", "front")))
