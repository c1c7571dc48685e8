"""The hot path's reuse of θ-free parts and of built effects against the direct computation
(the same numbers, bit for bit)."""

from __future__ import annotations

import numpy as np

from surrogate_rbrdo.discrepancy.candidates import candidate
from surrogate_rbrdo.discrepancy.impedance import bearing_dynamic_stiffness, bearing_parts
from surrogate_rbrdo.spindle.assembly import bearing_coefficients
from surrogate_rbrdo.spindle.effects import CrossCoupling, HousingFlexibility, ThermalPreload

EXTRA = (HousingFlexibility(k_N_per_m=5e8, m_kg=20.0, c_Ns_per_m=2000.0),
         CrossCoupling(kappa=0.1), ThermalPreload(b=0.4, q=1.5))


def test_bearing_parts_give_the_direct_coefficients(spindle):
    """θ applied to the kept θ-free stiffness equals bearing_coefficients at every row."""
    sp, g = spindle
    effects, stiff = sp.effects + EXTRA, sp.effects + EXTRA[1:]
    names = tuple(b.name for b in g.bearings)
    rng = np.random.default_rng(3)
    spin = np.linspace(0.0, 2500.0, 7)
    theta = rng.uniform(0.6, 1.4, (5, len(names)))
    ds = rng.uniform(0.5, 2.0, (5, len(names)))
    K, C = bearing_coefficients(g, stiff, names, np.broadcast_to(spin, (5, 7)), theta)
    w = 1.3 * spin[None, :, None, None, None]
    direct = K + 1j * w * C * ds[:, None, :, None, None]
    parts = bearing_parts(g, effects, spin)
    fast = bearing_dynamic_stiffness(g, effects, names, spin, 1.3 * spin, theta, ds, parts)
    plain = bearing_dynamic_stiffness(g, stiff, names, spin, 1.3 * spin, theta, ds)
    no_stage = bearing_dynamic_stiffness(g, stiff, names, spin, 1.3 * spin, theta, ds,
                                         bearing_parts(g, stiff, spin))
    np.testing.assert_array_equal(plain, no_stage)
    np.testing.assert_array_equal(no_stage, direct)
    # the housing stage condensed in: Z − Z (Z + z_h I)⁻¹ Z on the direct coefficients
    h = EXTRA[0]
    zh = h.k_N_per_m + 1j * 1.3 * spin * h.c_Ns_per_m - (1.3 * spin) ** 2 * h.m_kg
    Zs = direct - direct @ np.linalg.solve(direct + zh[None, :, None, None, None] * np.eye(2),
                                           direct)
    np.testing.assert_allclose(fast, Zs, rtol=1e-12, atol=0)


def test_candidate_effects_are_built_once_and_equal_a_fresh_build():
    c = candidate("housing", ("front", "rear"))
    vals = {"k_N_per_m": 2e-9, "m_kg": 10.0, "c_Ns_per_m": 0.0}
    a = c.effect(("front",), vals)
    assert c.effect(("front",), dict(vals)) is a
    assert a == c._effect(("front",), vals)
    assert c.effect((), vals) == c._effect((), vals) != a
    b = c.effect(("front",), {**vals, "m_kg": 10.0 + 1e-12})
    assert b != a and b.m_kg == 10.0 + 1e-12
