"""The tool-holder interface effect (a zero-length joint in the rotor)."""

import numpy as np
import pytest

from surrogate_rbrdo.spindle import modal_analysis, reference_spindle, unbalance_response
from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.effects import EFFECTS, ToolInterface, effect_from_dict
from surrogate_rbrdo.spindle.geometry import SpindleGeometry


def test_off_leaves_the_model_unchanged():
    sp = reference_spindle()
    a = sp.model(sp.baseline)
    b = sp.model(sp.baseline, sp.effects + (ToolInterface.off(),))
    assert np.array_equal(a.K, b.K) and np.array_equal(a.M, b.M) and np.array_equal(a.z, b.z)


def test_registered_and_built_from_dict():
    e = effect_from_dict({"name": "tool_interface", "k_t_N_per_m": 5e8,
                          "k_r_Nm_per_rad": 1e7})
    assert EFFECTS.get("tool_interface") is ToolInterface and e.joint().k_t_N_per_m == 5e8
    with pytest.raises(ValueError, match="both finite"):
        ToolInterface(k_t_N_per_m=5e8)
    with pytest.raises(ValueError, match="k_t_N_per_m"):
        ToolInterface(k_t_N_per_m=10.0, k_r_Nm_per_rad=1e7)


@pytest.mark.known_answer
def test_holder_on_its_interface_has_the_two_spring_mass_frequencies():
    """A 1.8 kg holder disk (J_d 2.6e-3) on the joint at the free end of a very stiff, heavy
    shaft: its translation and rocking decouple into sqrt(k_t/m) and sqrt(k_r/J_d)."""
    geom = SpindleGeometry.from_dict({
        "sections": [{"length_mm": 300, "outer_diameter_mm": 200, "elements": 3,
                      "material": "stiff"}],
        "materials": {"stiff": {"E_Pa": 2.1e15, "nu": 0.3, "rho_kg_m3": 78500.0}},
        "disks": [{"name": "tool_holder", "position_mm": 0.0, "mass_kg": 1.8,
                   "diametral_inertia_kgm2": 2.6e-3}],
        "bearings": [{"name": n, "position_mm": z, "law": {"type": "constant",
                                                          "k_N_per_m": 1e12}}
                     for n, z in (("front", 100.0), ("rear", 300.0))],
        "rayleigh_alpha_per_s": 0.0, "rayleigh_beta_s": 0.0})
    kt, kr = 2e8, 5e5
    m = build_model(geom, (ToolInterface(k_t_N_per_m=kt, k_r_Nm_per_rad=kr),))
    f = modal_analysis(m, 0.0).frequency_hz
    for expect in (np.sqrt(kt / 1.8), np.sqrt(kr / 2.6e-3)):
        fe = expect / (2 * np.pi)
        assert np.min(np.abs(f / fe - 1)) < 2e-3


def test_compliant_interface_raises_the_tool_response_not_the_bearings():
    sp = reference_spindle()
    base = sp.model(sp.baseline)
    soft = sp.model(sp.baseline, sp.effects + (ToolInterface(k_t_N_per_m=2e8,
                                                              k_r_Nm_per_rad=2e6),))
    stiff = sp.model(sp.baseline, sp.effects + (ToolInterface(k_t_N_per_m=1e14,
                                                               k_r_Nm_per_rad=1e13),))
    s = np.array([8000.0])
    q0, q1, q2 = (unbalance_response(m, s)[0, 0] for m in (base, soft, stiff))
    assert abs(q1[soft.tool_node, 0]) > 1.05 * abs(q0[base.tool_node, 0])
    rear = base.bearing_nodes[1]
    assert abs(q1[soft.bearing_nodes[1], 0] / q0[rear, 0] - 1) < 0.05
    np.testing.assert_allclose(q2[stiff.tool_node], q0[base.tool_node], rtol=1e-4)


@pytest.mark.parametrize("pos", [-20.0, 1000.0, 680.0])
def test_joint_must_split_the_shaft_with_mass_on_both_sides(pos):
    """Outside the shaft a joint would silently extend it; at its far end it leaves a massless
    free node."""
    sp = reference_spindle()
    with pytest.raises(ValueError, match=f"position_mm = {pos} is not allowed"):
        sp.model(sp.baseline, sp.effects + (ToolInterface(position_mm=pos, k_t_N_per_m=3e8,
                                                          k_r_Nm_per_rad=5e6),))
