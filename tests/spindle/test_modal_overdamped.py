"""Regression: over-damped roots of a finely meshed, Rayleigh-damped rotor are no modes at speed.

Rayleigh damping ``C = αM + βK`` (the paper's α = 3.5 s⁻¹, β = 2.1e-6 s) over-damps the FE
mesh's high modes (``ζ = α/2ω + βω/2 > 1`` above ``ω ≈ 2/β``). At rest their roots are real;
at speed the gyroscopic coupling gives them an imaginary part ∝ Ω. Before the fix,
``modal_analysis`` listed them as modes of a few tens of Hz with ζ ≈ 1, ahead of the physical
ones (issue 13: 21, 48, 49, 73 Hz for a shaft whose first mode is ~1 kHz; 73 Hz instead of
355 Hz for the reference spindle meshed at 10 mm).

Known answers used here: the mode count and frequencies at rest (no gyroscopics, so no
spurious roots), the mesh-converged frequencies of the default mesh, and Dunkerley's bound
for the shaft (``1/f² = 1/f_beam² + 1/f_spring²``: Euler–Bernoulli pinned–pinned beam and the
rigid shaft on the two springs; Timoshenko effects make the FE value slightly lower).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from surrogate_rbrdo.spindle.assembly import build_model
from surrogate_rbrdo.spindle.geometry import SpindleGeometry
from surrogate_rbrdo.spindle.modal import campbell, modal_analysis
from surrogate_rbrdo.spindle.reference import reference_spindle

E, RHO, D, L = 2.1e11, 7850.0, 62.5e-3, 0.3


def shaft_model(elements: int = 30):
    """The issue's reproduction: 300 mm x 62.5 mm steel shaft on 3e8 / 2.7e8 N/m, Rayleigh
    damping at the geometry defaults (α = 3.5, β = 2.1e-6)."""
    g = SpindleGeometry.from_dict({
        "sections": [{"length_mm": 300.0, "outer_diameter_mm": 62.5, "elements": elements}],
        "materials": {"steel": {"E_Pa": E, "nu": 0.3, "rho_kg_m3": RHO}},
        "bearings": [
            {"name": "a", "position_mm": 0.0, "law": {"type": "constant", "k_N_per_m": 3e8}},
            {"name": "b", "position_mm": 300.0, "law": {"type": "constant", "k_N_per_m": 2.7e8}},
        ]})
    return build_model(g)


@pytest.mark.known_answer
def test_fine_shaft_at_speed_lists_the_physical_modes_first():
    model = shaft_model()
    rest = modal_analysis(model, 0.0)
    fast = modal_analysis(model, 24000.0)
    # the same oscillatory modes at rest and at speed: no gyroscopically dragged roots
    assert fast.frequency_hz.size == rest.frequency_hz.size
    assert np.all(fast.damping_ratio < 0.99)
    # Dunkerley: pinned-pinned beam and rigid shaft on springs, combined
    area, inertia = np.pi * D**2 / 4, np.pi * D**4 / 64
    f_beam = np.pi / (2 * L**2) * np.sqrt(E * inertia / (RHO * area))
    f_spring = np.sqrt((3e8 + 2.7e8) / (RHO * area * L)) / (2 * np.pi)
    f_dunkerley = 1.0 / np.sqrt(1 / f_beam**2 + 1 / f_spring**2)
    first = fast.frequency_hz[:2]
    assert np.all(first > 0.9 * f_dunkerley) and np.all(first < 1.02 * f_dunkerley)
    # gyroscopic splitting of a slender shaft is small: within 1 % of the frequency at rest
    assert np.allclose(first, rest.frequency_hz[:2], rtol=0.01)
    assert sorted(fast.whirl[:2].tolist()) == ["backward", "forward"]


@pytest.mark.known_answer
def test_reference_spindle_fine_mesh_matches_the_default_mesh_at_speed():
    sp = reference_spindle()
    coarse = sp.model(sp.baseline)
    fine = build_model(replace(sp.geometry_for(sp.baseline), max_element_length_mm=10.0),
                       sp.effects, theta_bearings=sp.theta_bearings)
    assert fine.n_nodes > 3 * coarse.n_nodes
    fc = modal_analysis(coarse, 24000.0, n_modes=4)
    ff = modal_analysis(fine, 24000.0, n_modes=4)
    assert ff.frequency_hz[0] == pytest.approx(355.5, rel=0.01)   # not the 73 Hz of the bug
    assert np.allclose(ff.frequency_hz, fc.frequency_hz, rtol=0.01)
    assert ff.whirl.tolist() == fc.whirl.tolist()
    # the Campbell diagram and the critical speed follow
    speeds = np.array([1000.0, 12000.0, 24000.0])
    cf, cc = campbell(fine, speeds, n_modes=4), campbell(coarse, speeds, n_modes=4)
    assert np.allclose(cf.frequency_hz, cc.frequency_hz, rtol=0.01)
    assert np.allclose(cf.critical_speeds_rpm, cc.critical_speeds_rpm, rtol=0.01)
