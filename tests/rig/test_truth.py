"""The truth's variability model: what is drawn, at which level, with which statistics."""

import numpy as np
import pytest

from surrogate_rbrdo.rig.config import RigTruthTable
from surrogate_rbrdo.rig.truth import Truth, Variability, reference_truth, spindle_truth
from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.effects import CrossCoupling, Gyroscopics, SpeedSoftening
from surrogate_rbrdo.spindle.reference import credible_spindle


def test_levels_are_nested_and_reproducible():
    tr = reference_truth()
    ss = np.random.SeedSequence(11)
    a = tr.state(ss, build=0, tool=0, run=0)
    b = tr.state(ss, build=0, tool=0, run=1)
    c = tr.state(ss, build=1, tool=0, run=0)
    assert a.draws["build"] == b.draws["build"] and a.draws["run"] != b.draws["run"]
    assert a.draws["build"] != c.draws["build"]
    again = tr.state(np.random.SeedSequence(11), build=0, tool=0, run=1)
    assert again.draws == b.draws


def test_draw_statistics_match_the_variability_model():
    v = Variability(bearing_k_cov=0.05, thermal_preload_cov=0.08)
    tr = reference_truth(variability=v)
    ss = np.random.SeedSequence(2)
    k = np.array([tr.draw_build(np.random.SeedSequence(i))["k_factor"] for i in range(3000)])
    assert np.allclose(k.mean(0), 1.0, atol=0.005)
    assert np.allclose(k.std(0), 0.05, rtol=0.08)
    th = np.array([tr.state(ss, build=0, tool=0, run=r).theta[0] for r in range(1500)])
    # per run only the thermal preload varies: k ∝ F^{1/3}, CoV ≈ 0.08 / 3
    assert np.allclose(np.std(np.log(th), axis=0), np.sqrt(np.log1p(0.08**2)) / 3, rtol=0.1)
    U = np.array([tr.draw_build(np.random.SeedSequence(i))["unbalance_kgm"]
                  for i in range(500)])
    per_plane = tr.permissible_unbalance_kgm() / 2
    assert U.max() <= per_plane and U.min() >= 0.25 * per_plane


def test_hidden_effects_reach_the_model():
    tr = reference_truth(hidden=[{"name": "cross_coupling", "kappa": 0.1}])
    st = tr.state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    assert any(isinstance(e, CrossCoupling) and e.kappa == 0.1 for e in st.model().effects)
    assert tr.describe()["hidden"] == [{"name": "cross_coupling", "kappa": 0.1,
                                        "bearings": []}]


def test_bad_variability_names_the_field():
    with pytest.raises(ValueError, match="variability.bearing_k_cov"):
        Variability(bearing_k_cov=-0.1)
    with pytest.raises(ValueError, match="unbalance"):
        Truth(reference_truth().geometry.__class__.from_dict({
            "sections": [{"length_mm": 100, "outer_diameter_mm": 50}],
            "bearings": [{"name": "a", "position_mm": 0,
                          "law": {"type": "constant", "k_N_per_m": 1e8}}]}))


def test_iso_allocation_is_the_permissible_residual_of_the_parts_in_each_plane():
    """ISO 21940-11 §7 allocation: the tool plane keeps the tool holder's own permissible
    residual m_tool G / Ω, the motor plane the rest of the rotor's (hand-computed from the
    geometry's masses, not from the code under test); "disk" magnitudes are uniform over the
    tolerance disk: E[r] = 2/3 and E[r²] = 1/2 of the plane's limit."""
    sp = credible_spindle()
    t = spindle_truth(sp, (), Variability(unbalance_allocation="iso",
                                          unbalance_magnitude="disk"))
    g = t.geometry
    omega = 24_000.0 * 2 * np.pi / 60
    m_tool = next(d.mass_kg for d in g.disks if d.name == "tool_holder")
    m_rotor = build_model(g, ()).rotor_mass_kg
    want = np.array([m_tool, m_rotor - m_tool]) * 2.5e-3 / omega
    r = np.array([t.draw_build(c)["unbalance_kgm"]
                  for c in np.random.SeedSequence(7).spawn(4000)])
    tool_first = g.unbalances[0].position_mm <= g.unbalances[1].position_mm
    np.testing.assert_allclose(r.max(axis=0), want if tool_first else want[::-1], rtol=0.01)
    frac = r / r.max(axis=0)
    np.testing.assert_allclose(frac.mean(axis=0), 2 / 3, atol=0.02)
    np.testing.assert_allclose((frac**2).mean(axis=0), 0.5, atol=0.02)
    equal = spindle_truth(sp, (), Variability()).draw_build(np.random.SeedSequence(1))
    assert len(equal["unbalance_kgm"]) == 2


def test_iso_allocation_needs_two_planes_and_the_tool_disk():
    with pytest.raises(ValueError, match="unbalance_allocation = 'iso' is not allowed"):
        reference_truth(variability=Variability(unbalance_allocation="iso",
                                                tool_disk="no_such_disk"))
    with pytest.raises(ValueError, match="unbalance_magnitude"):
        Variability(unbalance_magnitude="gauss")


def test_a_hidden_switch_replaces_the_models_off_switch():
    """The reference model carries gyroscopics in its off (identity) state (``Gyroscopics(
    g=0)``: the geometry's coupling); a hidden gyroscopics replaces it (one, not two — a
    second raised "at most one 'gyroscopics' effect" from the [rig] table), while a hidden
    effect of a kind the model has on (a bearing softening) is added to the model's own. The
    truth's model scales the gyroscopic matrix as a model built with that switch does."""
    base = reference_truth()
    tr = reference_truth(hidden=[{"name": "gyroscopics", "g": 0.5},
                                 {"name": "speed_softening", "a": 0.1, "exponent": 2.0}])
    gyro = [e for e in tr.all_effects if isinstance(e, Gyroscopics)]
    assert [e.g for e in gyro] == [0.5]
    soft = [e for e in tr.all_effects if isinstance(e, SpeedSoftening)]
    assert len(soft) == 1 + sum(isinstance(e, SpeedSoftening) for e in base.effects)
    st = tr.state(np.random.SeedSequence(0), build=0, tool=0, run=0)
    own = tuple(e for e in base.effects if not isinstance(e, Gyroscopics))
    ref = build_model(st.geometry, own + (Gyroscopics(g=0.5),
                                          SpeedSoftening(a=0.1, exponent=2.0)),
                      theta_bearings=st.theta_bearings)
    off = build_model(st.geometry, own + (Gyroscopics(g=0.0),
                                          SpeedSoftening(a=0.1, exponent=2.0)),
                      theta_bearings=st.theta_bearings)
    assert st.model().gyro_scale == ref.gyro_scale == 1.5 and off.gyro_scale == 1.0
    cfg = RigTruthTable(effects=({"name": "gyroscopics", "g": 0.5},))
    assert [e.g for e in cfg.truth().all_effects if isinstance(e, Gyroscopics)] == [0.5]
