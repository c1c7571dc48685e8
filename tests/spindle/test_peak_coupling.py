"""The peak over speed for random multi-plane unbalance by exact coupling, against the FE model.

Known answers: the FE model's own peak search (``harmonic.peak_search`` on the direct
block-tridiagonal solve, with a finer grid than its default) and the independent dense solve
of the whole system at fixed speeds (``conftest.dense_response``).
"""

import numpy as np
import pytest
import scipy.linalg as sla

from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.coupling import theta_grid
from surrogate_rbrdo.spindle.effects import Anisotropy, HousingFlexibility, SpeedSoftening
from surrogate_rbrdo.spindle.geometry import SpindleGeometry
from surrogate_rbrdo.spindle.harmonic import PeakOptions, orbit_amplitude, peak_tool_amplitude
from surrogate_rbrdo.spindle.peak_coupling import (
    CoupledPeakOptions,
    coupled_tables,
    forward_basis,
    peak_tool_amplitude_coupled,
    peak_tool_amplitude_unbalance,
)
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.spindle.substructure import retained_layout

from .conftest import dense_response

SP = reference_spindle()
#: resonant in range (baseline), near the top of the range, subcritical, long and thin
DESIGNS = [[2000.0, 500.0, 65.0], [2000.0, 465.8, 65.0], [3000.0, 350.0, 80.0],
           [1000.0, 750.0, 50.0]]
FINE = PeakOptions(n_grid=200, n_candidates=4, n_refine=21, n_zoom=3)


def _sample(n, seed=0, cov=0.04):
    rng = np.random.default_rng(seed)
    th = rng.normal(1.0, cov, size=(n, 2))
    U = 1.0e-5 * np.sqrt(rng.random((n, 2))) * np.exp(2j * np.pi * rng.random((n, 2)))
    return th, U


@pytest.mark.known_answer
@pytest.mark.parametrize("x", DESIGNS)
def test_peak_equals_the_fe_peak_search(x):
    m = SP.model(np.array(x))
    th, U = _sample(40, seed=int(x[1]))
    fast = peak_tool_amplitude_coupled(m, th, U)
    fe = peak_tool_amplitude_unbalance(m, th[:4], U[:4], options=FINE)
    np.testing.assert_allclose(fast.amplitude[:4], fe.amplitude, rtol=1e-3)
    np.testing.assert_allclose(fast.speed_rpm[:4], fe.speed_rpm, rtol=2e-3)


@pytest.mark.known_answer
def test_tables_are_the_dense_solve_at_the_grid_speeds():
    """At a grid speed, N_j / D is the forward tool response to a unit unbalance in plane j."""
    m = SP.model(np.array(DESIGNS[0]))
    nodes = np.array([[1.0, 1.0], [0.9, 1.1]])
    speeds = np.geomspace(1000.0, 24000.0, 8)
    T = coupled_tables(m, speeds, nodes)
    assert T.Nb is None                                     # isotropic: forward block only
    for j in range(2):
        unit = np.zeros(2, dtype=complex)
        unit[j] = 1.0
        m_j = m.__class__(**{**m.__dict__, "unbalance": unit})
        for k, th in enumerate(nodes):
            q = dense_response(m_j, speeds, th)[:, m.tool_node]
            np.testing.assert_allclose(T.Na[k, :, j] / T.D[k], q[:, 0] + 1j * q[:, 1],
                                       rtol=1e-9)


def test_in_phase_unbalance_reproduces_the_fe_peak_of_the_reference_model():
    """The reference model's own (in-phase) unbalance: the FE peak of harmonic."""
    m = SP.model(np.array(DESIGNS[1]))
    th = np.array([[1.0, 1.0], [0.95, 1.04], [1.05, 0.97]])
    fast = peak_tool_amplitude_coupled(m, th, m.unbalance)
    fe = peak_tool_amplitude(m, th, options=FINE)
    np.testing.assert_allclose(fast.amplitude, fe.amplitude, rtol=1e-3)


def test_linear_in_the_unbalance_and_blind_to_a_common_phase():
    m = SP.model(np.array(DESIGNS[2]))
    th, U = _sample(30, seed=3)
    a = peak_tool_amplitude_coupled(m, th, U).amplitude
    b = peak_tool_amplitude_coupled(m, th, 2.5 * np.exp(0.7j) * U).amplitude
    np.testing.assert_allclose(b, 2.5 * a, rtol=1e-9)


@pytest.mark.known_answer
def test_anisotropic_bearings_use_the_whole_system():
    """Anisotropy breaks the forward/backward split: elliptic orbits, both components."""
    m = SP.model(np.array(DESIGNS[0]), effects=SP.effects + (Anisotropy(s=0.1),))
    th, U = _sample(20, seed=5)
    T = coupled_tables(m, np.geomspace(1000.0, 24000.0, 8), theta_grid(th)[0])
    assert T.Nb is not None
    opts = CoupledPeakOptions(n_grid=96, stencil=8)
    fast = peak_tool_amplitude_coupled(m, th[:3], U[:3], options=opts)
    fe = peak_tool_amplitude_unbalance(m, th[:3], U[:3], options=FINE)
    np.testing.assert_allclose(fast.amplitude, fe.amplitude, rtol=1e-3)


@pytest.mark.known_answer
def test_housing_stage_on_a_theta_bearing_falls_back_to_rows():
    """θ is not affine in the bearing impedance with a housing stage: solved row by row."""
    eff = SP.effects + (HousingFlexibility(bearings=("rear",), k_N_per_m=2e8, m_kg=5.0,
                                           c_Ns_per_m=2e3),)
    m = SP.model(np.array(DESIGNS[1]), effects=eff)
    th, U = _sample(3, seed=9)
    fast = peak_tool_amplitude_coupled(m, th, U)
    fe = peak_tool_amplitude_unbalance(m, th, U, options=FINE)
    np.testing.assert_allclose(fast.amplitude, fe.amplitude, rtol=1e-3)


def test_forward_basis_is_orthonormal_and_holds_the_unbalance_force():
    lay = retained_layout(SP.model(SP.baseline))
    V = forward_basis(lay)
    np.testing.assert_allclose(V.conj().T @ V, np.eye(V.shape[1]), atol=1e-15)
    f = np.zeros(lay.n_dof, dtype=complex)
    f[4 * lay.unbalance[1]:4 * lay.unbalance[1] + 2] = [1.0, -1.0j]
    np.testing.assert_allclose(V @ (V.conj().T @ f), f, atol=1e-15)


def test_peak_of_a_single_sample_is_the_orbit_amplitude_there():
    """The reported peak is the FE orbit amplitude at the reported speed (interpolation
    error in speed only: < 1e-4)."""
    m = SP.model(np.array(DESIGNS[0]), effects=(SpeedSoftening(a=0.1),))
    th, U = _sample(1, seed=11)
    res = peak_tool_amplitude_coupled(m, th, U)
    q = sum(U[0, j] * dense_response(
        m.__class__(**{**m.__dict__, "unbalance": np.eye(2)[j].astype(complex)}),
        res.speed_rpm, th[0])[0, m.tool_node] for j in range(2))
    assert abs(orbit_amplitude(q[0], q[1]) / res.amplitude[0] - 1) < 1e-4


def test_bad_inputs_are_refused():
    m = SP.model(SP.baseline)
    with pytest.raises(ValueError, match="unbalance has shape"):
        peak_tool_amplitude_coupled(m, np.ones((3, 2)), np.ones((3, 3)))
    with pytest.raises(ValueError, match="speed_range_rpm"):
        peak_tool_amplitude_coupled(m, None, np.ones(2), speed_range_rpm=(5.0, 1.0))
    with pytest.raises(ValueError, match="stencil"):
        CoupledPeakOptions(n_grid=8, stencil=9)
    with pytest.raises(ValueError, match="geometric grid"):
        coupled_tables(m, np.array([1000.0, 2000.0, 2500.0]), np.ones((1, 2)))


@pytest.mark.known_answer
def test_resonance_next_to_a_zero_of_the_numerator():
    """Regression: two planes nearly cancelling at a resonance give two close maxima (found
    in a 3 600-sample validation; Newton from the sub-grid stopped at the lower one)."""
    m = SP.model(np.array([2718.4, 524.0, 57.0]))
    th = np.array([[0.97709421, 1.00226092]])
    U = np.array([[5.17877598e-06 - 8.66284272e-06j, 2.81257216e-06 - 4.37853771e-06j]])
    fast = peak_tool_amplitude_coupled(m, th, U)
    fe = peak_tool_amplitude_unbalance(m, th, U, options=FINE)
    np.testing.assert_allclose(fast.amplitude, fe.amplitude, rtol=1e-3)


def _interior_pole_rotor():
    """A rotor whose condensed stiffness S has a pole inside the speed range: a 5 kg disk in
    the middle of a thin 400 mm segment between two retained nodes (clamped: ~160 Hz)."""
    law = {"type": "constant", "k_N_per_m": 1e8, "damping_eta_s": 4e-6}
    g = SpindleGeometry.from_dict({
        "sections": [{"length_mm": 100, "outer_diameter_mm": 50, "elements": 2},
                     {"length_mm": 400, "outer_diameter_mm": 20, "elements": 8},
                     {"length_mm": 200, "outer_diameter_mm": 50, "elements": 4}],
        "bearings": [{"name": "front", "position_mm": 100, "law": law},
                     {"name": "rear", "position_mm": 700, "law": law}],
        "disks": [{"name": "mid", "position_mm": 300, "mass_kg": 5.0,
                   "polar_inertia_kgm2": 2e-3, "diametral_inertia_kgm2": 1e-3},
                  {"name": "tool_holder", "position_mm": 0, "mass_kg": 1.0}],
        "unbalances": [{"position_mm": 0, "magnitude_kgm": 1e-6},
                       {"position_mm": 500, "magnitude_kgm": 1e-6}],
        "tool_tip_mm": 0.0, "rayleigh_alpha_per_s": 3.5, "rayleigh_beta_s": 2.1e-6})
    return build_model(g)


@pytest.mark.known_answer
def test_a_pole_of_the_condensed_rotor_inside_the_range_does_not_spoil_the_peak():
    """The tables carry det A_II · det(S + P Z Pᵀ), the whole system's determinant, so a
    clamped-interior resonance in the range (a pole of S) cancels."""
    m = _interior_pole_rotor()
    lay = retained_layout(m)
    R = lay.dofs
    Ii = np.setdiff1d(np.arange(m.n_dof), R)
    w = np.sqrt(sla.eigh(m.K[np.ix_(Ii, Ii)], m.M[np.ix_(Ii, Ii)], eigvals_only=True)[0])
    assert 1000 < w * 30 / np.pi < 24000                  # the pole lies in the range
    th, U = _sample(30, seed=13)
    fast = peak_tool_amplitude_coupled(m, th, U * 0.1)
    fe = peak_tool_amplitude_unbalance(m, th[:4], U[:4] * 0.1, options=FINE)
    np.testing.assert_allclose(fast.amplitude[:4], fe.amplitude, rtol=1e-3)
