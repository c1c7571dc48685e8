"""Structural properties of the assembled matrices (unit/property tests with exact answers)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from surrogate_rbrdo.spindle.effects import HousingFlexibility
from surrogate_rbrdo.spindle.reference import reference_spindle

from .conftest import build, rigid_rotor_geometry, uniform_beam_geometry


@pytest.fixture(scope="module")
def ref_model():
    sp = reference_spindle()
    return sp.model(sp.baseline)


def test_rotor_matrices_symmetry_and_definiteness(ref_model):
    M, K, G = ref_model.M, ref_model.K, ref_model.G
    assert np.array_equal(M, M.T) or np.allclose(M, M.T, rtol=0, atol=1e-14 * np.abs(M).max())
    assert np.allclose(K, K.T, rtol=0, atol=1e-14 * np.abs(K).max())
    assert np.allclose(G, -G.T, rtol=0, atol=0)
    assert np.linalg.eigvalsh(M).min() > 0  # M positive definite
    ev = np.linalg.eigvalsh(K)
    assert ev.min() > -1e-9 * ev.max()  # K positive semi-definite
    # the free rotor's K has exactly the 4 rigid-body null vectors (x, y translation and tilt)
    assert np.sum(np.abs(ev) < 1e-9 * ev.max()) == 4


def test_bearings_make_the_system_stiffness_positive_definite(ref_model):
    M, C, K = ref_model.system_matrices(1000.0)
    assert np.allclose(K, K.T)  # no cross-coupling by default
    assert np.linalg.eigvalsh(0.5 * (K + K.T)).min() > 0
    assert np.allclose(C - C.T, 1000.0 * ref_model.gyro_scale * (ref_model.G - ref_model.G.T))


@pytest.mark.known_answer
def test_free_rotor_has_four_rigid_body_modes():
    """Bearings of 1 N/m: eigh(K_total, M) has 4 eigenvalues ω² < 1 (rigid body: ~2k/m ≈ 0.1),
    then the flexible modes above (2π·100 Hz)²."""
    mod = build(uniform_beam_geometry(500.0, 50.0, 10, 1.0))
    M, _, K = mod.system_matrices(0.0)
    w2 = sla.eigh(K, M, eigvals_only=True)
    assert np.sum(np.abs(w2) < 1.0) == 4
    assert w2[4] > (2 * np.pi * 100) ** 2


@pytest.mark.known_answer
def test_rotor_mass_equals_the_geometry(ref_model):
    geo = ref_model.geometry
    vol = sum(np.pi / 4 * (s.outer_diameter_mm**2 - s.inner_diameter_mm**2) * s.length_mm
              for s in geo.sections) * 1e-9
    m = vol * 7850.0 + sum(d.mass_kg for d in geo.disks)
    assert ref_model.rotor_mass_kg == pytest.approx(m, rel=1e-12)
    ones = np.zeros(ref_model.n_dof)
    ones[0::4] = 1.0
    assert ones @ ref_model.M @ ones == pytest.approx(m, rel=1e-12)  # rigid translation


def test_theta_multiplies_the_bearing_stiffness(ref_model):
    th = np.array([0.8, 1.3])
    _, _, K1 = ref_model.system_matrices(0.0)
    _, _, Kt = ref_model.system_matrices(0.0, th)
    Kb, Cb = ref_model.bearing_coefficients(np.array([[0.0]]))
    for j, node in enumerate(ref_model.bearing_nodes):
        dofs = np.ix_([4 * node, 4 * node + 1], [4 * node, 4 * node + 1])
        assert np.allclose((Kt - K1)[dofs], (th[j] - 1) * Kb[0, 0, j], rtol=1e-12)
        eta = ref_model.geometry.bearings[j].law.damping_eta_s
        assert np.allclose(Cb[0, 0, j], eta * Kb[0, 0, j])  # C = η K_sym
    mask = np.ones_like(K1, dtype=bool)
    for node in ref_model.bearing_nodes:
        mask[np.ix_([4 * node, 4 * node + 1], [4 * node, 4 * node + 1])] = False
    assert np.array_equal(Kt[mask], K1[mask])


def test_housing_adds_two_dofs_per_bearing_in_series():
    kh, mh = 3e7, 2.0
    mod = build(rigid_rotor_geometry(1e7), [HousingFlexibility(k_N_per_m=kh, m_kg=mh)])
    M, _, K = mod.system_matrices(0.0)
    n = mod.n_dof
    assert M.shape == (n + 4, n + 4)
    assert np.allclose(np.diag(M)[n:], mh)
    assert np.allclose(np.diag(K)[n:], 1e7 + kh)
    node = mod.bearing_nodes[0]
    assert K[4 * node, n] == -1e7 and K[n, 4 * node] == -1e7


def test_mesh_has_nodes_at_every_item_and_respects_max_element_length(ref_model):
    z_mm = ref_model.z * 1e3
    geo = ref_model.geometry
    for pos in [b.position_mm for b in geo.bearings] + [d.position_mm for d in geo.disks]:
        assert np.min(np.abs(z_mm - pos)) < 1e-9
    fine = build(uniform_beam_geometry(500.0, 50.0, 2, 1e8, max_element_length_mm=20.0))
    assert np.max(np.diff(fine.z)) <= 0.020 + 1e-12 and fine.n_nodes == 26


def test_block_form_equals_dense(ref_model):
    for name in ("M", "K", "G"):
        A = getattr(ref_model, name)
        diag, up, low = ref_model.blocks[name]
        B = np.zeros_like(A)
        for i in range(ref_model.n_nodes):
            B[4 * i:4 * i + 4, 4 * i:4 * i + 4] = diag[i]
            if i < ref_model.n_nodes - 1:
                B[4 * i:4 * i + 4, 4 * i + 4:4 * i + 8] = up[i]
                B[4 * i + 4:4 * i + 8, 4 * i:4 * i + 4] = low[i]
        assert np.array_equal(A, B)


def test_bad_model_arguments_raise(ref_model):
    geo = ref_model.geometry
    with pytest.raises(ValueError, match="theta_bearings: 'middle' is not a bearing"):
        build(geo, theta_bearings=("middle",))
    name = geo.bearings[0].name
    with pytest.raises(ValueError, match="a name appears twice"):
        build(geo, theta_bearings=(name, name))
    with pytest.raises(ValueError, match="is not an Effect"):
        build(geo, ["speed_softening"])
    with pytest.raises(ValueError, match=r"theta = \[0.0, 1.0\] is not allowed"):
        ref_model.system_matrices(0.0, np.array([0.0, 1.0]))


def test_preload_override_equals_each_designs_own_bearings():
    """Known answer: ``bearing_impedance`` of each design's own geometry (``geometry_for``);
    the override gives all designs in one call, with preload-dependent effects too."""
    from surrogate_rbrdo.spindle.assembly import bearing_impedance
    from surrogate_rbrdo.spindle.effects import SpeedSoftening, ThermalPreload

    sp = reference_spindle()
    effects = (*sp.effects, ThermalPreload(bearings=("front",), b=0.3, q=1.5),
               SpeedSoftening(bearings=("rear",), a=0.1, exponent=1.2))
    X = np.array([[1000.0, 300.0, 50.0], [2417.0, 512.0, 71.3], [3000.0, 750.0, 80.0]])
    omega = np.array([[500.0, 2513.0]])
    theta = np.array([[1.1, 0.9], [0.95, 1.2], [1.0, 1.0]])
    pre = {k: v[:, None] for k, v in sp.design_map.bearing_preloads(X).items()}
    Z = bearing_impedance(sp.geometry, effects, sp.theta_bearings,
                          np.repeat(omega, 3, axis=0), theta, preloads=pre)
    for i, x in enumerate(X):
        own = bearing_impedance(sp.geometry_for(x), effects, sp.theta_bearings, omega,
                                theta[i:i + 1])
        np.testing.assert_array_equal(Z[i], own[0])
    with pytest.raises(ValueError, match=r"'nose' is not a bearing; bearings are \['front', "):
        bearing_impedance(sp.geometry, effects, sp.theta_bearings, omega, theta[:1],
                          preloads={"nose": 2000.0})
    with pytest.raises(ValueError, match=r"preloads\['front'\] = 0.0 is not allowed"):
        bearing_impedance(sp.geometry, effects, sp.theta_bearings, omega, theta[:1],
                          preloads={"front": np.array([2000.0, 0.0])})
    rigid = rigid_rotor_geometry(1e8)             # constant-law bearings: nothing to override
    name = rigid.bearings[0].name
    with pytest.raises(ValueError, match=f"bearing '{name}' has a constant law"):
        bearing_impedance(rigid, (), (name,), omega, theta[:1, :1], preloads={name: 2000.0})
