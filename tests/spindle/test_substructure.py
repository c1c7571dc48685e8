"""The condensed rotor: its layout, its static limit, its vector form, its FE call.

(Its coupling with the bearings against the dense solve: ``test_coupling.py``.)
"""

import numpy as np
import pytest

from surrogate_rbrdo.core.errors import ModelError
from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.reference import reference_spindle
from surrogate_rbrdo.spindle.substructure import (
    PointwiseCondensed,
    chain_condensation,
    condensed_from_vector,
    condensed_rotor,
    condensed_rotor_chain,
    condensed_vector,
    retained_layout,
)

from .conftest import uniform_beam_geometry

SP = reference_spindle()
DESIGNS = [[3000.0, 442.5, 65.7], [2000.0, 500.0, 65.0], [1000.0, 750.0, 50.0],
           [3000.0, 300.0, 80.0]]


def test_retained_layout_of_the_reference_spindle():
    m = SP.model(SP.baseline)
    lay = retained_layout(m)
    assert [lay.nodes[lay.tool]] == [m.tool_node]
    assert [lay.nodes[k] for k in lay.bearings] == m.bearing_nodes.tolist()
    assert [lay.nodes[k] for k in lay.unbalance] == m.unbalance_nodes.tolist()


def test_condensed_stiffness_is_static_condensation_at_low_speed():
    """As Ω → 0 the condensation is Guyan's: S = K_RR − K_RI K_II⁻¹ K_IR (independent)."""
    m = SP.model(SP.baseline)
    lay = retained_layout(m)
    R = lay.dofs
    Ii = np.setdiff1d(np.arange(m.n_dof), R)
    K = m.K
    guyan = K[np.ix_(R, R)] - K[np.ix_(R, Ii)] @ np.linalg.solve(K[np.ix_(Ii, Ii)],
                                                                K[np.ix_(Ii, R)])
    S = condensed_rotor(m, np.array([1e-3]), lay)[0]
    np.testing.assert_allclose(S, guyan, rtol=0, atol=1e-9 * np.abs(guyan).max())


def test_vector_round_trip_and_pointwise_call():
    m = SP.model(np.array(DESIGNS[0]))
    lay = retained_layout(m)
    S = condensed_rotor(m, np.array([12000.0, 24000.0]), lay)
    np.testing.assert_array_equal(condensed_from_vector(condensed_vector(S), lay.n_dof), S)
    f = PointwiseCondensed(SP, (12000.0, 24000.0))
    v = f(np.array(DESIGNS[0]))
    assert v.shape == (f.n_outputs(lay.n_dof),)
    np.testing.assert_array_equal(
        condensed_from_vector(v.reshape(2, -1), lay.n_dof), S)


def test_bad_speeds_are_refused():
    m = SP.model(SP.baseline)
    with pytest.raises(ValueError, match="speeds_rpm"):
        condensed_rotor(m, np.array([0.0]))
    with pytest.raises(ValueError, match="speeds_rpm"):
        condensed_rotor(m, np.array([np.nan]))


def test_pointwise_condensed_refuses_another_layout_or_unbalance():
    m = SP.model(SP.baseline)
    lay = retained_layout(m)
    x = np.array(DESIGNS[0])
    with pytest.raises(ModelError, match="retained nodes"):
        PointwiseCondensed(SP, (24000.0,), tuple(n + 1 for n in lay.nodes))(x)
    with pytest.raises(ModelError, match="unbalance"):
        PointwiseCondensed(SP, (24000.0,), lay.nodes, tuple(2 * m.unbalance))(x)
    v = PointwiseCondensed(SP, (24000.0,), lay.nodes, tuple(m.unbalance))(x)
    assert np.all(np.isfinite(v))


@pytest.mark.parametrize("x", DESIGNS)
def test_chain_condensation_equals_the_dense_schur_complement(x):
    """Block elimination along the shaft gives the dense Schur complement (independent)."""
    m = SP.model(np.array(x))
    sp = np.array([1000.0, 9000.0, 21783.0, 24000.0])
    S = condensed_rotor(m, sp)
    np.testing.assert_allclose(condensed_rotor_chain(m, sp), S, rtol=0,
                               atol=1e-11 * np.abs(S).max())


def test_chain_condensation_with_free_ends_on_both_sides():
    """Retained nodes in the middle of the shaft: the free ends are eliminated too."""
    g = uniform_beam_geometry(600.0, 60.0, 12, 1e8, tool_tip_mm=150.0,
                              disks=[{"name": "d", "position_mm": 450.0, "mass_kg": 3.0,
                                      "polar_inertia_kgm2": 0.01,
                                      "diametral_inertia_kgm2": 0.006}],
                              unbalances=[{"position_mm": 450.0, "magnitude_kgm": 1e-5}],
                              rayleigh_alpha_per_s=2.0, rayleigh_beta_s=1e-6)
    g = g.__class__.from_dict({**g.to_dict(), "bearings": [
        {"name": "a", "position_mm": 250.0, "law": {"type": "constant", "k_N_per_m": 1e8}},
        {"name": "b", "position_mm": 500.0, "law": {"type": "constant", "k_N_per_m": 1e8}}]})
    m = build_model(g)
    lay = retained_layout(m)
    assert lay.nodes[0] > 0 and lay.nodes[-1] < m.n_nodes - 1
    sp = np.array([3000.0, 30000.0])
    S = condensed_rotor(m, sp, lay)
    np.testing.assert_allclose(condensed_rotor_chain(m, sp, lay), S, rtol=0,
                               atol=1e-11 * np.abs(S).max())


@pytest.mark.parametrize("nodes", [(), (3, 2), (1, 1), (-1, 4), (0, 10_000), (0.0, 2.0)])
def test_chain_condensation_refuses_bad_nodes(nodes):
    m = SP.model(SP.baseline)
    one = np.ones(1)
    with pytest.raises(ValueError, match="nodes = .* strictly ascending"):
        chain_condensation(m, (one, -one, 0 * one), nodes)
