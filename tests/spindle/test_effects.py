"""Each switchable effect moves the response in its documented direction by the documented
amount, on the rigid rotor of ``conftest`` whose answers are closed-form:

* translational natural frequency ``ω² = 2 k / m`` (two identical bearings, any speed);
* springs in series ``k_eff = k k_h / (k + k_h)`` (housing), and with a housing mass m_h per
  bearing the 2-DOF system ``[m, 0; 0, 2m_h]``, ``[2k, −2k; −2k, 2(k + k_h)]``;
* Hertz contact ``k ∝ F^{1/3}`` (Harris & Kotzalas, *Rolling Bearing Analysis*, 2007, §7);
* the Jeffcott response ``e r² / |1 − r²|`` of an undamped rotor (Genta 2005, §3.4).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from surrogate_rbrdo.spindle.assembly import RPM
from surrogate_rbrdo.spindle.effects import (
    EFFECTS,
    Anisotropy,
    CrossCoupling,
    Gyroscopics,
    HousingFlexibility,
    SpeedSoftening,
    ThermalPreload,
    UnbalanceError,
    effect_from_dict,
)
from surrogate_rbrdo.spindle.harmonic import tool_amplitude, unbalance_response
from surrogate_rbrdo.spindle.modal import critical_speeds, first_natural_frequency, modal_analysis
from surrogate_rbrdo.spindle.reference import reference_spindle

from .conftest import build, rigid_rotor_geometry, rigid_rotor_properties

K_B = 1e7
OMEGA_REF = 24000 * RPM


def wn(k=K_B):
    return np.sqrt(2 * k / rigid_rotor_properties()[0])


# --------------------------------------------------------------------------- speed softening
@pytest.mark.known_answer
def test_speed_softening_coefficients_and_frequency():
    a, p = 0.3, 1.5
    mod = build(rigid_rotor_geometry(K_B), [SpeedSoftening(a=a, exponent=p)])
    om = np.array([[0.0, 0.3, 0.7, 1.0]]) * OMEGA_REF
    K, C = mod.bearing_coefficients(om)
    f = 1 - a * (om[0] / OMEGA_REF) ** p
    for j in range(2):
        assert np.allclose(K[0, :, j], K_B * f[:, None, None] * np.eye(2), rtol=1e-14, atol=0)
    for s in (0.0, 12000.0, 24000.0):
        fs = 1 - a * (s / 24000.0) ** p
        assert first_natural_frequency(mod, s) * 2 * np.pi == pytest.approx(
            wn() * np.sqrt(fs), rel=1e-6)


@pytest.mark.known_answer
def test_speed_softening_lowers_the_critical_speed_by_the_analytic_amount():
    """p = 2: the 1x crossing ω² = ω₀² (1 − a ω²/Ω_ref²) gives ω = ω₀ / sqrt(1 + a ω₀²/Ω_ref²)."""
    a = 0.4
    w0 = wn()
    expected = w0 / np.sqrt(1 + a * w0**2 / OMEGA_REF**2)
    grid = np.linspace(1000.0, 24000.0, 24)
    c0 = critical_speeds(build(rigid_rotor_geometry(K_B)), grid)
    c1 = critical_speeds(build(rigid_rotor_geometry(K_B), [SpeedSoftening(a=a, exponent=2.0)]),
                         grid)
    assert c0.size == 1 and c1.size == 1
    assert c0[0] * RPM == pytest.approx(w0, rel=1e-6)
    assert c1[0] * RPM == pytest.approx(expected, rel=1e-6)
    assert c1[0] < c0[0]


# --------------------------------------------------------------------------- thermal preload
def preload_rotor(effects, *, F0=2000.0, Fref=1000.0, kref=K_B):
    law = {"type": "preload", "k_ref_N_per_m": kref, "preload_ref_N": Fref, "preload_N": F0,
           "damping_eta_s": 0.0}
    bearings = [{"name": "left", "position_mm": 0.0, "law": law},
                {"name": "right", "position_mm": 200.0, "law": law}]
    return build(rigid_rotor_geometry(K_B, bearings=bearings), effects)


@pytest.mark.known_answer
def test_thermal_preload_raises_stiffness_as_cube_root_of_preload():
    b, q, F0, Fref = 0.8, 2.0, 2000.0, 1000.0
    mod = preload_rotor([ThermalPreload(b=b, q=q)], F0=F0, Fref=Fref)
    om = np.array([[0.0, 0.5, 1.0]]) * OMEGA_REF
    K, _ = mod.bearing_coefficients(om)
    F = F0 * (1 + b * (om[0] / OMEGA_REF) ** q)
    k = K_B * (F / Fref) ** (1 / 3)
    assert np.allclose(K[0, :, 0, 0, 0], k, rtol=1e-14, atol=0)
    assert np.all(np.diff(k) > 0)
    f = first_natural_frequency(mod, 24000.0) * 2 * np.pi
    assert f == pytest.approx(wn(k[-1]), rel=1e-6)
    # Hertz: doubling the preload multiplies k by 2^(1/3)
    assert first_natural_frequency(preload_rotor((), F0=2 * F0)) / first_natural_frequency(
        preload_rotor((), F0=F0)) == pytest.approx(2 ** (1 / 6), rel=1e-6)


# --------------------------------------------------------------------------- cross-coupling
@pytest.mark.known_answer
def test_cross_coupling_matrix():
    kappa = 0.25
    mod = build(rigid_rotor_geometry(K_B, c=100.0), [CrossCoupling(kappa=kappa)])
    K, C = mod.bearing_coefficients(np.array([[1000.0]]))
    expected = K_B * np.array([[1.0, kappa], [-kappa, 1.0]])
    assert np.allclose(K[0, 0], expected, rtol=1e-15, atol=0)
    assert np.allclose(C[0, 0], 100.0 * np.eye(2))  # cross-coupling adds no damping
    # κ > 0 destabilises forward whirl: the forward translational mode loses damping
    base = modal_analysis(build(rigid_rotor_geometry(K_B, c=100.0)), 5000.0, n_modes=2)
    cc = modal_analysis(mod, 5000.0, n_modes=4)
    fw = cc.damping_ratio[(cc.whirl == "forward") & (cc.frequency_hz < 200)]
    assert fw.size == 1 and fw[0] < base.damping_ratio.min()


# --------------------------------------------------------------------------- anisotropy
@pytest.mark.known_answer
def test_anisotropy_splits_the_jeffcott_frequencies():
    s = 0.3
    mod = build(rigid_rotor_geometry(K_B), [Anisotropy(s=s)])
    M, _, K = mod.system_matrices(0.0)
    w = np.sqrt(sla.eigh(K, M, eigvals_only=True)[:4])
    m, Jt, _, a = rigid_rotor_properties()
    kxy = K_B * (1 + np.array([-s, s]))  # y and x planes
    expected = np.sort(np.concatenate([wn(kxy), np.sqrt(2 * kxy * a**2 / Jt)]))
    assert np.allclose(w, expected, rtol=1e-6)


# --------------------------------------------------------------------------- housing
@pytest.mark.known_answer
def test_massless_housing_in_series_gives_the_series_stiffness():
    """Undamped rotor: |X| = e r²/|1 − r²| with ω_n² = 2 k k_h/(k + k_h) / m (harmonic solver,
    which condenses the massless housing stage)."""
    kh = 2e7
    keff = K_B * kh / (K_B + kh)
    U = 1e-4
    m = rigid_rotor_properties()[0]
    geo = rigid_rotor_geometry(K_B, unbalance_kgm=U)
    mod = build(geo, [HousingFlexibility(k_N_per_m=kh)])
    sp = np.array([2000.0, 6000.0, 7500.0, 9000.0, 20000.0])
    r = sp * RPM / wn(keff)
    A = tool_amplitude(mod, sp)[0]
    assert np.allclose(A, U / m * r**2 / np.abs(1 - r**2), rtol=1e-5)
    assert np.all(A[:3] > tool_amplitude(build(geo), sp)[0][:3])  # softer: larger below ω_n


@pytest.mark.known_answer
def test_housing_mass_adds_a_mode():
    kh, mh = 4e7, 6.0
    m = rigid_rotor_properties()[0]
    mod = build(rigid_rotor_geometry(K_B), [HousingFlexibility(k_N_per_m=kh, m_kg=mh)])
    w2 = sla.eigh(np.array([[2 * K_B, -2 * K_B], [-2 * K_B, 2 * (K_B + kh)]]),
                  np.diag([m, 2 * mh]), eigvals_only=True)
    res = modal_analysis(mod, 0.0)
    w = res.frequency_hz * 2 * np.pi
    for target in np.sqrt(w2):
        assert np.sum(np.isclose(w, target, rtol=1e-6)) == 2  # x and y
    assert mod.system_matrices(0.0)[0].shape[0] == mod.n_dof + 4


# --------------------------------------------------------------------------- gyroscopics, U
@pytest.mark.known_answer
def test_gyroscopics_off_removes_the_split_on_the_rigid_rotor():
    m, Jt, _, a = rigid_rotor_properties()
    res = modal_analysis(build(rigid_rotor_geometry(K_B), [Gyroscopics(g=-1.0)]), 20000.0,
                         n_modes=4)
    w = res.frequency_hz * 2 * np.pi
    assert np.allclose(w[2:], np.sqrt(2 * K_B * a**2 / Jt), rtol=1e-6)


@pytest.mark.known_answer
def test_unbalance_error_scales_and_rotates_the_response_everywhere():
    eps, delta = 0.35, -40.0
    sp = reference_spindle()
    base = sp.model(sp.baseline)
    err = sp.model(sp.baseline, effects=sp.effects + (UnbalanceError(epsilon=eps,
                                                                      delta_deg=delta),))
    speeds = np.array([1500.0, 9000.0, 21000.0])
    ratio = unbalance_response(err, speeds) / unbalance_response(base, speeds)
    assert np.allclose(ratio, (1 + eps) * np.exp(1j * np.deg2rad(delta)), rtol=1e-10)


# --------------------------------------------------------------------------- off states
@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_off_state_leaves_the_model_unchanged_exactly(name):
    """Adding ``cls.off()`` changes nothing, bit for bit. ``gyroscopics`` is the exception by
    design: its off state (g = −1) *removes* gyroscopics, and its identity is g = 0."""
    cls = EFFECTS[name]
    eff = cls(g=0.0) if cls is Gyroscopics else cls.off()
    if cls is not Gyroscopics:
        assert eff.is_off
    sp = reference_spindle()
    speeds = np.array([2000.0, 15000.0])
    ref_model = sp.model(sp.baseline, effects=(SpeedSoftening(a=0.2),))
    model = sp.model(sp.baseline, effects=(SpeedSoftening(a=0.2), eff))
    assert np.array_equal(unbalance_response(model, speeds), unbalance_response(ref_model, speeds))
    for A, B in zip(model.system_matrices(1000.0), ref_model.system_matrices(1000.0),
                    strict=True):
        assert np.array_equal(A, B)


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_effect_round_trip_and_unknown_keys(name):
    cls = EFFECTS[name]
    eff = cls.off()
    assert effect_from_dict({"name": name, **eff.params()}) == eff
    with pytest.raises(ValueError, match=rf"unknown key effects\.{name}\.nope; allowed: \["):
        effect_from_dict({"name": name, "nope": 1.0})


@pytest.mark.parametrize(
    ("cls", "field", "value"),
    [(SpeedSoftening, "a", 1.5), (ThermalPreload, "b", -0.1), (CrossCoupling, "kappa", 0.9),
     (Anisotropy, "s", 0.7), (HousingFlexibility, "k_N_per_m", 10.0), (Gyroscopics, "g", -2.0),
     (UnbalanceError, "epsilon", -1.0)],
)
def test_effect_parameters_out_of_bounds_raise(cls, field, value):
    with pytest.raises(ValueError, match=rf"^{field} = {value!r} is not allowed: .*\({cls.name}\)"):
        cls(**{field: value})
    with pytest.raises(ValueError, match=rf"^effects\.{cls.name}\.{field} = {value!r} is not"):
        effect_from_dict({"name": cls.name, field: value})


def test_unknown_effect_name_lists_the_known_ones():
    with pytest.raises(ValueError, match="name = 'warp' is not allowed: unknown effect 'warp'; "
                                         "known: anisotropy"):
        effect_from_dict({"name": "warp"})
